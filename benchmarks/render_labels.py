"""Labels agree with pixels: corner errors (px) of the flat-colour runway at 5 km, 1 km and 100 ft.

Prints the per-corner errors between labels.csv and the runway polygon extracted from a
flat-colour render (the extraction of tests/render/test_labels_agree_with_pixels.py), for MSAA 4
and 0, on thesis-7 (15 deg heading error) with a 0.5 deg camera calibration error, and ends with
one JSON line.

    .venv/bin/python benchmarks/render_labels.py
"""
import importlib.util
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("labels_test", ROOT / "tests/render/test_labels_agree_with_pixels.py")
labels_test = importlib.util.module_from_spec(spec)
spec.loader.exec_module(labels_test)


def main():
    import tempfile
    from visland.camera import CameraModel
    from visland.contracts import read_labels
    from visland.features import batch_R_camera_from_runway
    from visland.flight import FT_TO_M
    from visland.render import FrameRenderer, SceneParams
    from visland.scenarios import get_scenario
    from visland.simulate import SimulationOptions, run_simulation, write_simulation_files

    scenario = sys.argv[1] if len(sys.argv) > 1 else "thesis-7"
    result = run_simulation(get_scenario(scenario), SimulationOptions(fps=5.0, camera=CameraModel.default(2048),
                                                                      calibration_error_deg=0.5))
    with tempfile.TemporaryDirectory() as folder:
        write_simulation_files(result, folder)
        labels = read_labels(Path(folder) / "labels.csv")
    s = result.frames
    camera = result.camera_true
    R_cr = batch_R_camera_from_runway(s.roll_rad, s.pitch_rad, s.dpsi_rad, camera.mount_rpy_rad)
    frames = {"5 km": labels_test._frame_at_distance(result, 5000.0),
              "1 km": labels_test._frame_at_distance(result, 1000.0),
              "100 ft": labels_test._frame_at_height(result, 100.0 * FT_TO_M)}
    corners = ("near_left", "near_right", "far_left", "far_right")
    figures = {}
    for msaa in (4, 0):
        with FrameRenderer(SceneParams.flat(msaa_samples=msaa), camera, result.scenario.runway) as renderer:
            for name, i in frames.items():
                label_uv = np.array([[labels[f"{c}_u_px"][i], labels[f"{c}_v_px"][i]] for c in corners])
                measured = labels_test.extract_runway_corners(renderer.render(s.p_runway_m[i], R_cr[i]), label_uv)
                error = np.linalg.norm(measured - label_uv, axis=1)
                figures[f"msaa{msaa} {name}"] = {c: round(float(e), 4) for c, e in zip(corners, error)}
                print(f"MSAA {msaa}, {name:6s}: corner errors (px) " +
                      ", ".join(f"{c} {e:.3f}" for c, e in zip(corners, error)))
    worst = max(max(v.values()) for v in figures.values())
    print(json.dumps({"bench": "render_labels", "scenario": scenario, "max_error_px": worst, "errors_px": figures}))


if __name__ == "__main__":
    main()
