"""Search windows placed by dickmanns-4d's prediction against the detector's own (issue 16 item 2).

Seed 004 measures the runway in small windows placed where the filter predicts its borders.
visland's detector tracks from its own last detection (carried by the attitude change only).
This benchmark runs the detector twice over a rendered dataset (frames, telemetry, labels):

1. **own**: :class:`visland.detection.DetectionSequence` as ``visland detect`` runs it;
2. **filter**: the same, but each frame's search window comes from ``dickmanns-4d``'s prediction
   for that frame (:meth:`visland.estimation.dickmanns.Dickmanns4D.predicted_lines`, turned into a
   prior by :func:`visland.detection.predicted.prior_from_prediction`). The filter is stepped up to
   the frame before and predicts the frame from its model and the frame's inertial data; it is
   corrected with pass 1's detections (**open loop**: the filter does not yet see pass 2's own
   measurements; ``visland process`` does not run this loop yet).

Both passes are scored against the exact labels (:func:`visland.detection.accuracy.frame_errors`):
found rate, frames found by tracking (window) rather than a whole-frame search, gross errors,
near-corner error, and the detector's time per frame (median and mean, image reading excluded).

Usage::

    nice .venv/bin/python benchmarks/predicted_windows.py DATASET [--max-frames N] [--skip K]

``--skip K`` drops K-1 frames of every K (a lower frame rate: larger motion between frames, where
the detector's own prediction, which ignores the translation, is weakest; beyond ``hold_s`` it
drops its last detection and searches the whole frame, while the filter still predicts).

Measured (docs/estimation.md, "Search windows placed by the filter"): 512 px dickmanns-wind at 5 Hz with
``--skip 10`` (2 s between frames): the filter's windows track 13 of 23 found frames (own: 0),
detector median 207 vs 419 ms.
"""
from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def _run_pass(folder, camera, frames, labels, predict=None):
    from visland.detection import DetectionSequence
    from visland.detection.accuracy import frame_errors
    sequence = DetectionSequence(camera)
    rows, times, results = [], [], []
    for k in frames:
        image, reason = folder.read_frame(k, gray=False)
        if image is None:
            raise ValueError(f"frame {k}: {reason}")
        t = float(folder.times_s[k])
        roll, pitch = float(folder.inertial.roll_rad[k]), float(folder.inertial.pitch_rad[k])
        prior = predict(k) if predict is not None else None
        tic = time.perf_counter()
        result = sequence(image, roll, pitch, t, predicted=prior)
        times.append(time.perf_counter() - tic)
        results.append(result)
        corners = np.array([[labels[f"{c}_u_px"][k], labels[f"{c}_v_px"][k]]
                            for c in ("near_left", "near_right", "far_left", "far_right")])
        visible = np.array([labels[f"{c}_visible"][k] > 0.5 for c in ("near_left", "near_right", "far_left",
                                                                       "far_right")])
        err = frame_errors(result, camera, corners, visible, math.radians(float(labels["dpsi_deg"][k])))
        err["window"] = prior is not None and prior.found
        rows.append(err)
    return rows, times, results


def _summary(rows, times) -> dict:
    n = len(rows)
    found = [r for r in rows if r["found"]]
    near = np.array([r["near_px"] for r in found], dtype=float)
    near = near[np.isfinite(near)]
    return {"frames": n, "found_pct": round(100.0 * len(found) / max(n, 1), 1),
            "tracking": sum(1 for r in found if r["mode"] == "tracking"),
            "gross": sum(1 for r in found if r["gross"]),
            "near_median_px": round(float(np.median(near)), 2) if near.size else None,
            "near_p95_px": round(float(np.percentile(near, 95)), 2) if near.size else None,
            "time_median_ms": round(1e3 * statistics.median(times), 1),
            "time_mean_ms": round(1e3 * statistics.fmean(times), 1)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dataset", help="a generated dataset (frames/, telemetry.csv, labels.csv, truth.csv)")
    parser.add_argument("--max-frames", type=int, default=None)
    parser.add_argument("--skip", type=int, default=1, help="use every K-th frame (default 1: all)")
    args = parser.parse_args(argv)

    from visland.contracts import MEASUREMENT_COLUMNS, read_labels, read_measurements, read_telemetry, read_truth, \
        write_csv
    from visland.detection.predicted import prior_from_prediction
    from visland.estimation.dickmanns import Dickmanns4D
    from visland.estimation.inputs import FeatureSeries, InertialSeries, prepare_inputs
    from visland.folder import FrameFolder

    root = Path(args.dataset)
    folder = FrameFolder(root)
    camera = folder.camera
    labels = read_labels(root / "labels.csv")
    truth = read_truth(root / "truth.csv")
    n = len(folder) if args.max_frames is None else min(len(folder), args.max_frames)
    frames = list(range(0, n, max(1, args.skip)))
    print(f"{root}: {len(frames)} frames of {camera.width}x{camera.height} (every {args.skip})", flush=True)

    own_rows, own_times, own_results = _run_pass(folder, camera, frames, labels)
    print("own   ", json.dumps(_summary(own_rows, own_times)), flush=True)

    # the filter on pass 1's detections (open loop, module docstring)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "measurements.csv"
        rows = [r.to_measurement_row(frame=k, t_s=float(folder.times_s[k])) for k, r in zip(frames, own_results)]
        write_csv(path, {c: [row[c] for row in rows] for c in MEASUREMENT_COLUMNS}, MEASUREMENT_COLUMNS)
        features = FeatureSeries.from_table(read_measurements(path))
    inertial = InertialSeries.from_table(read_telemetry(root / "telemetry.csv"))
    prepared = prepare_inputs(inertial, features, camera)
    observer = Dickmanns4D()
    start = prepared.first_step_with("lines")
    if start is None:
        raise SystemExit("pass 1 found no lines: nothing to start the filter on")
    k0 = frames[prepared.frame_of_step[start]]
    observer.reset(prepared.steps[start], 1.2 * float(truth["dh_m"][k0]))
    state = {"j": start}
    frame_index = {k: i for i, k in enumerate(frames)}

    def predict(k):
        j_frame = int(prepared.step_of_frame[frame_index[k]])
        if j_frame <= state["j"]:
            return None                        # not started yet: the detector's own window
        while state["j"] < j_frame - 1:        # the filter up to the step before this frame
            state["j"] += 1
            observer.step(prepared.steps[state["j"]])
        inp = prepared.steps[j_frame]
        p = observer.predicted_lines(inp)
        prior = prior_from_prediction(camera, p["near_xy"], p["far_xy"], inp.roll_rad, inp.pitch_rad, p["dpsi_rad"],
                                      lines=p, source="dickmanns-4d")
        state["j"] += 1
        observer.step(inp)
        return prior

    filt_rows, filt_times, _ = _run_pass(folder, camera, frames, labels, predict)
    print("filter", json.dumps(_summary(filt_rows, filt_times)), flush=True)
    print(json.dumps({"bench": "predicted_windows", "dataset": str(root), "skip": args.skip,
                      "own": _summary(own_rows, own_times), "filter": _summary(filt_rows, filt_times),
                      "filter_windows": sum(1 for r in filt_rows if r["window"])}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
