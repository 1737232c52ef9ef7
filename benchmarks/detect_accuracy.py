"""Detection accuracy on rendered approaches of the eight thesis scenarios (issue 4 figures).

For each scenario the approach is flown (``visland.flight``), frames are rendered in memory
at 2048x2048 with :class:`visland.render.FrameRenderer` (no PNG written) every ``--every``-th
camera frame from ``--start-m`` metres before the threshold down to 100 ft, and the detector
runs on them in order, each frame tracked from the previous detection as ``visland detect``
does. Every frame is compared with its exact labels (:func:`visland.features.ideal_features`)
and the truth:

- found rate;
- edge line error: the largest distance (px) from the labelled left/right edge, over its
  stretch visible in the image, to the detected line;
- near corners (threshold corners P', P''): distance (px) from the label, where both are in
  the image;
- heading deviation: detected dpsi minus the true dpsi (deg); d_F error (px).

Figures are given per band of distance to the threshold and overall; per-frame rows go to
``--out`` (CSV, written as frames come, so a long run can be read while it runs); the last
line printed is one JSON object with the figures.

Usage::

    PYOPENGL_PLATFORM=egl .venv/bin/python benchmarks/detect_accuracy.py --every 25 --out /tmp/detection/acc.csv
    .venv/bin/python benchmarks/detect_accuracy.py --scenarios thesis-1 --every 5
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import sys
import time

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

BANDS = ((3000.0, math.inf, ">3 km"), (1000.0, 3000.0, "1-3 km"), (500.0, 1000.0, "0.5-1 km"),
         (0.0, 500.0, "<0.5 km (to 100 ft)"))
FT = 0.3048


def edge_error_px(camera, corners_uv, rho_theta, side: str) -> float:
    """Largest distance from the labelled edge's visible stretch to the detected line (px)."""
    a = corners_uv[0 if side == "left" else 1]
    b = corners_uv[2 if side == "left" else 3]
    t = np.linspace(0.0, 1.0, 400)[:, None]
    points = a + t * (b - a)
    points = points[camera.in_image(points)]
    rho, theta = rho_theta
    if len(points) == 0 or not (math.isfinite(rho) and math.isfinite(theta)):
        return math.nan
    return float(np.abs(camera.line_distance_px(rho, theta, points)).max())


def band_of(distance_m: float) -> str:
    for low, high, name in BANDS:
        if low <= distance_m < high:
            return name
    return BANDS[-1][2]


def summarise(rows: list[dict]) -> dict:
    def stats(values):
        values = np.asarray([v for v in values if math.isfinite(v)], float)
        if values.size == 0:
            return {"median": None, "p95": None, "n": 0}
        return {"median": round(float(np.median(values)), 3), "p95": round(float(np.percentile(values, 95)), 3),
                "n": int(values.size)}

    out = {}
    for name in [b[2] for b in BANDS] + ["all"]:
        chosen = [r for r in rows if name == "all" or r["band"] == name]
        if not chosen:
            continue
        found = [r for r in chosen if r["found"]]
        out[name] = {
            "frames": len(chosen),
            "found_rate": round(len(found) / len(chosen), 4),
            "wrong_rate": round(sum(1 for r in found if not (r["edge_px"] <= 3.0)) / len(chosen), 4),
            "edge_px": stats([r["edge_px"] for r in found]),
            "near_corner_px": stats([e for r in found for e in (r["near_left_px"], r["near_right_px"])]),
            "far_corner_px": stats([e for r in found for e in (r["far_left_px"], r["far_right_px"])]),
            "dpsi_abs_err_deg": stats([abs(r["dpsi_err_deg"]) for r in found]),
            "dF_abs_err_px": stats([abs(r["dF_err_px"]) for r in found]),
            "tracking_rate": round(sum(1 for r in found if r["mode"] == "tracking") / max(len(found), 1), 3),
            "detect_ms": stats([r["detect_ms"] for r in chosen]),
        }
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenarios", nargs="+", default=[f"thesis-{i}" for i in range(1, 9)])
    parser.add_argument("--every", type=int, default=25, help="render every N-th camera frame (default 25: 1 Hz)")
    parser.add_argument("--size", type=int, default=2048)
    parser.add_argument("--fps", type=float, default=25.0)
    parser.add_argument("--start-m", type=float, default=5000.0, help="first frame this far before the threshold")
    parser.add_argument("--stop-ft", type=float, default=100.0, help="last frame at this height (default 100 ft)")
    parser.add_argument("--acquire", action="store_true", help="search every frame from scratch (no tracking)")
    parser.add_argument("--colour", action="store_true", help="give the detector the colour frames (as `visland "
                                                              "detect` does) instead of grey levels")
    parser.add_argument("--out", default="/tmp/detection/detect_accuracy.csv", help="per-frame CSV")
    parser.add_argument("--cache", metavar="DIR", help="keep rendered frames as PNG in DIR and reuse them "
                                                        "(re-running the detector without rendering again)")
    args = parser.parse_args(argv)
    if args.every < 1:
        parser.error("--every must be at least 1")

    import cv2
    from visland.camera import CameraModel
    from visland.detection import DetectorParams, detect_runway
    from visland.features import batch_R_camera_from_runway, ideal_features
    from visland.flight import simulate_flight
    from visland.render import FrameRenderer, SceneParams
    from visland.scenarios import resolve_scenario
    from visland.simulate import frame_times

    camera = CameraModel.default(args.size)
    params = DetectorParams()
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    fields = ["scenario", "frame", "t_s", "distance_m", "height_m", "band", "found", "mode", "confidence", "edge_px",
              "near_left_px", "near_right_px", "far_left_px", "far_right_px", "dpsi_err_deg", "dF_err_px", "detect_ms",
              "reason"]
    rows = []
    start = time.perf_counter()
    with open(args.out, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=fields)
        writer.writeheader()
        for name in args.scenarios:
            scenario = resolve_scenario(name)
            trajectory = simulate_flight(scenario)
            times = frame_times(trajectory.duration_s, args.fps)
            states = trajectory.at(times)
            distance = -states.p_runway_m[:, 0]
            height = -states.p_runway_m[:, 2]
            chosen = np.nonzero((distance <= args.start_m) & (height >= args.stop_ft * FT))[0][::args.every]
            states = trajectory.at(times[chosen])
            labels = ideal_features(states, scenario.runway, camera)
            R = batch_R_camera_from_runway(states.roll_rad, states.pitch_rad, states.dpsi_rad, camera.mount_rpy_rad)
            previous = None
            renderer = None
            try:
                for j, index in enumerate(chosen):
                    cached = os.path.join(args.cache, f"{scenario.name}_{args.size}_{index:05d}.png") \
                        if args.cache else None
                    if cached and args.colour:
                        cached = cached.replace(".png", "_rgb.png")
                    grey = cv2.imread(cached, cv2.IMREAD_UNCHANGED) if cached and os.path.exists(cached) else None
                    if grey is not None and grey.ndim == 3:
                        grey = cv2.cvtColor(grey, cv2.COLOR_BGR2RGB)
                    if grey is None:
                        if renderer is None:
                            renderer = FrameRenderer(SceneParams(), camera, scenario.runway)
                        rgb = renderer.render(states.p_runway_m[j], R[j])
                        grey = rgb if args.colour else cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
                        if cached:
                            os.makedirs(args.cache, exist_ok=True)
                            cv2.imwrite(cached, cv2.cvtColor(grey, cv2.COLOR_RGB2BGR) if grey.ndim == 3 else grey)
                    tic = time.perf_counter()
                    result = detect_runway(grey, camera, float(states.roll_rad[j]), float(states.pitch_rad[j]),
                                           params=params, previous=None if args.acquire else previous)
                    detect_ms = 1e3 * (time.perf_counter() - tic)
                    previous = result if result.found else None
                    corners = labels.corners_uv[j]
                    visible = labels.corners_visible[j]
                    corner_err = np.linalg.norm(result.corners_uv - corners, axis=1)
                    corner_err = np.where(visible, corner_err, np.nan)
                    edge = max(edge_error_px(camera, corners, result.lines["left"], "left"),
                               edge_error_px(camera, corners, result.lines["right"], "right")) \
                        if result.found else math.nan
                    row = {"scenario": scenario.name, "frame": int(index), "t_s": round(float(states.t_s[j]), 3),
                           "distance_m": round(float(distance[index]), 1), "height_m": round(float(height[index]), 1),
                           "band": band_of(float(distance[index])), "found": int(result.found), "mode": result.mode,
                           "confidence": round(result.confidence, 3), "edge_px": edge,
                           "near_left_px": corner_err[0], "near_right_px": corner_err[1],
                           "far_left_px": corner_err[2], "far_right_px": corner_err[3],
                           "dpsi_err_deg": math.degrees(result.dpsi_rad - float(states.dpsi_rad[j]))
                           if result.found else math.nan,
                           "dF_err_px": result.dF_px - float(labels.dF_px[j]) if result.found else math.nan,
                           "detect_ms": round(detect_ms, 2), "reason": result.reason}
                    rows.append(row)
                    writer.writerow({k: (round(v, 4) if isinstance(v, float) and math.isfinite(v) else v)
                                     for k, v in row.items()})
                    handle.flush()
                    print(f"{scenario.name} frame {index:5d} {row['distance_m']:7.0f} m found={row['found']} "
                          f"edge={edge:6.2f} near={corner_err[0]:5.2f},{corner_err[1]:5.2f} "
                          f"dpsi_err={row['dpsi_err_deg']:7.3f} deg {detect_ms:6.0f} ms {result.mode[:5]} "
                          f"{result.reason[:60]}", file=sys.stderr, flush=True)
            finally:
                if renderer is not None:
                    renderer.close()
    summary = summarise(rows)
    elapsed = time.perf_counter() - start
    print(f"{len(rows)} frames of {len(args.scenarios)} scenarios (every {args.every}-th frame at {args.fps:g} Hz, "
          f"{args.size}x{args.size}) in {elapsed / 60:.1f} min; per-frame rows in {args.out}")
    print(f"{'band':22s} {'frames':>6s} {'found':>6s} {'wrong':>6s} {'edge med/p95 px':>16s} "
          f"{'near corner med/p95 px':>23s} {'|dpsi err| med/p95 deg':>23s}")
    for name, s in summary.items():
        print(f"{name:22s} {s['frames']:6d} {100 * s['found_rate']:5.1f}% {100 * s['wrong_rate']:5.1f}% "
              f"{s['edge_px']['median']!s:>7s}/{s['edge_px']['p95']!s:<8s} "
              f"{s['near_corner_px']['median']!s:>10s}/{s['near_corner_px']['p95']!s:<12s} "
              f"{s['dpsi_abs_err_deg']['median']!s:>10s}/{s['dpsi_abs_err_deg']['p95']!s:<12s}")
    print(json.dumps({"benchmark": "detect_accuracy", "scenarios": args.scenarios, "every": args.every,
                      "frames": len(rows), "minutes": round(elapsed / 60, 2), "bands": summary}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
