"""Cockpit footage end to end, the way a user with a video and no telemetry would run it.

The frames are the ray-cast approach dressed as a cockpit view (``tests/helpers/cockpit_footage``:
windshield pillars, glareshield, a parked wiper, a reflection, a barrel lens; independent of
visland's renderer). The script writes them as a frame folder with a camera.json (no mask, no
telemetry), runs ``visland mask`` on it, adds the proposed mask to camera.json, runs
``visland detect`` (roll and pitch read off the frames), and compares the measurements with the
exact labels. For comparison the same detection runs with the true structure polygons and
without any mask.

Usage::

    .venv/bin/python benchmarks/cockpit_footage.py --size 1280x720 --fps 2 --work /work/data/cockpit

The last line printed is one JSON object with the figures.
"""
from __future__ import annotations

import argparse
import json
import shutil
import sys
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from tests.helpers.cockpit_footage import cockpit_camera, cockpit_frames, structure_polygons  # noqa: E402


def figures(rows, corners, visible):
    """Found rate, near-corner errors of the frames reported found with both threshold corners."""
    found = rows["found"].astype(bool)
    near = []
    for k in np.nonzero(found)[0]:
        uv = np.array([[rows[f"{c}_u_px"][k], rows[f"{c}_v_px"][k]] for c in ("near_left", "near_right")])
        if np.all(np.isfinite(uv)):
            near.append(float(np.linalg.norm(uv - corners[k][:2], axis=1).max()))
    near = np.array(near)
    in_view = np.array([v[:2].all() for v in visible])
    return {"frames": len(found), "threshold_in_view": int(in_view.sum()),
            "found_pct": round(100.0 * found[in_view].mean(), 1) if in_view.any() else None,
            "with_corners": len(near),
            "near_median_px": round(float(np.median(near)), 2) if len(near) else None,
            "near_p95_px": round(float(np.percentile(near, 95)), 2) if len(near) else None,
            "near_max_px": round(float(near.max()), 2) if len(near) else None,
            "found_over_20px": int(np.sum(near > 20.0))}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", default="1280x720")
    parser.add_argument("--fps", type=float, default=2.0)
    parser.add_argument("--start-m", type=float, default=2500.0)
    parser.add_argument("--stop-m", type=float, default=150.0)
    parser.add_argument("--work", default="/tmp/cockpit_footage")
    parser.add_argument("--reuse", action="store_true", help="reuse the frames already drawn in WORK/frames")
    args = parser.parse_args(argv)
    width, height = (int(a) for a in args.size.split("x"))

    from visland.cli import main as visland
    from visland.contracts import read_measurements

    work = Path(args.work)
    if work.exists() and not args.reuse:
        shutil.rmtree(work)
    (work / "frames").mkdir(parents=True, exist_ok=True)
    for stale in work.glob("mask*.png"):
        stale.unlink()
    camera = cockpit_camera(width, height)
    corners, visible = [], []
    for k, (_, frame, corners_uv, corners_visible, _) in enumerate(
            cockpit_frames(camera, (args.start_m, args.stop_m), fps=args.fps, draw=not args.reuse)):
        if frame is not None:
            cv2.imwrite(str(work / "frames" / f"{k:05d}.png"), frame)
        corners.append(corners_uv)
        visible.append(corners_visible)
    if len(list((work / "frames").glob("*.png"))) != len(corners):
        raise SystemExit(f"{work / 'frames'}: holds a different number of frames than this case; run without --reuse")
    camera.save(work / "camera.json")
    out = {"size": args.size, "fps": args.fps, "frames": len(corners)}
    assert visland(["mask", str(work), "--out", str(work / "mask.png"), "--camera", str(work / "camera.json")]) == 0
    proposed = cv2.imread(str(work / "mask.png"), cv2.IMREAD_GRAYSCALE) > 0
    truth = np.zeros((height, width), np.uint8)
    cv2.fillPoly(truth, [np.round(np.asarray(p) * 16).astype(np.int32) for p in structure_polygons(width, height)],
                 1, shift=4)
    truth = truth > 0
    out["mask_structure_covered_pct"] = round(100.0 * proposed[truth].mean(), 2)
    out["mask_scene_covered_pct"] = round(100.0 * proposed[~truth].mean(), 2)
    cases = {"proposed mask": replace(camera, mask=str((work / "mask.png").resolve())),
             "true polygons": replace(camera, mask=structure_polygons(width, height)),
             "no mask": camera}
    for name, case_camera in cases.items():
        case_camera.save(work / "camera.json")
        csv = work / f"measurements-{name.replace(' ', '-')}.csv"
        assert visland(["detect", str(work), "--out", str(csv), "--fps", str(args.fps), "--quiet", "--force"]) == 0
        out[name] = figures(read_measurements(csv), corners, visible)
        print(name, out[name], flush=True)
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
