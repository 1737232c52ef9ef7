"""``visland process --windows dickmanns-4d`` (issue 16 item 2): the filter's window for each frame.

Independent truth: a simulated folder's exact labels (``visland simulate``). The filter is fed the
labels of frames 0..k-1 as measurements; its window for frame k must hold frame k's labelled
threshold corners, which it has not seen.
"""
from __future__ import annotations

import types

import numpy as np
import pytest

from visland.camera import CameraModel
from visland.cli import main
from visland.contracts import MEASUREMENT_COLUMNS, read_labels, read_telemetry, read_truth
from visland.datasets.filter_windows import FilterWindows
from visland.datasets.process import ProcessOptions


def test_unknown_window_source_is_refused():
    with pytest.raises(ValueError, match="--windows must be one of detector, dickmanns-4d"):
        ProcessOptions(windows="kalman")


@pytest.mark.slow
def test_the_window_of_the_next_frame_holds_its_threshold(tmp_path):
    out = tmp_path / "thesis-3"
    assert main(["simulate", "--scenario", "thesis-3", "--out", str(out), "--fps", "5"]) == 0
    labels = read_labels(out / "labels.csv")
    truth = read_truth(out / "truth.csv")
    source = types.SimpleNamespace(name="thesis-3", camera=CameraModel.load(out / "camera.json"),
                                   times_s=labels["t_s"], telemetry=read_telemetry(out / "telemetry.csv"))
    windows = FilterWindows(source, lambda k: 1.2 * float(truth["dh_m"][k]))
    n = min(labels.n_rows, 120)
    errors = []
    for k in range(n):
        prior = windows.window(k)
        if k == 0:
            assert prior is None                       # nothing measured yet: the detector's own window
        elif k > 60:                                   # 12 s after the start
            assert prior is not None and prior.found and prior.mode == "predicted"
            truth_uv = np.array([[labels["near_left_u_px"][k], labels["near_left_v_px"][k]],
                                 [labels["near_right_u_px"][k], labels["near_right_v_px"][k]]])
            errors.append(np.abs(prior.corners_uv[:2] - truth_uv).max())
        row = {c: (labels[c][k] if c in labels else np.nan) for c in MEASUREMENT_COLUMNS}
        row.update(frame=k, source="ideal", found=1, reason="", confidence=1.0)
        windows.add(row)
    assert windows.n_predicted > 60
    assert max(errors) < 2.0                            # pixels at 2048 px: the window is on the runway
    with pytest.raises(ValueError, match="asked after"):
        windows.window(n + 3)


@pytest.mark.slow
def test_process_with_the_filter_windows_on_rendered_frames(tmp_path):
    """End to end: a short approach rendered at 512 px, 2.5 Hz (0.4 s between frames), processed with
    the detector's windows and with dickmanns-4d's; both against the exact labels."""
    from visland.datasets import generate as gen
    from visland.datasets.process import process_input
    from visland.render.params import SceneParams
    from visland.scenarios import Scenario
    from visland.simulate import SimulationOptions

    scenario = Scenario("short", dx_m=-1600.0, dy_m=20.0, dgs_m=-5.0, dpsi_deg=2.0, gamma_deg=-3.0)
    options = SimulationOptions(fps=2.5, camera=CameraModel.default(512), seed=2)
    data = tmp_path / "short"
    gen.generate_dataset(gen.GenerateJob(scenario, options, SceneParams(seed=2)), data, progress=False)
    labels = read_labels(data / "labels.csv")
    found = {}
    for windows in ("detector", "dickmanns-4d"):
        out = tmp_path / windows
        process_input(data, out, ProcessOptions(observers=("dickmanns-4d",), quiet=True, report=False,
                                                windows=windows), echo=lambda s: None)
        from visland.contracts import read_measurements
        m = read_measurements(out / "measurements.csv")
        found[windows] = int(m["found"].sum())
        both = (m["found"] > 0.5) & np.isfinite(m["near_left_u_px"]) & (labels["near_left_visible"] > 0.5)
        error = np.hypot(m["near_left_u_px"] - labels["near_left_u_px"], m["near_left_v_px"] - labels["near_left_v_px"])
        assert both.sum() >= 0.8 * labels.n_rows
        assert np.median(error[both]) < 0.5                     # pixels, 512 px frames
    assert found["dickmanns-4d"] >= found["detector"] - 1
