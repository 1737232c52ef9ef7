"""`visland mask` on an approach drawn by the independent ray caster, dressed as a cockpit view.

Frames: ``tests/helpers/raycast_airport.py`` (a painted airport ray-cast pixel by pixel, not
visland's renderer) along a scenario flown by visland's flight model, with a wide-angle camera;
over each frame a cockpit is painted at fixed pixels: a dark glare shield with a curved edge and
a faint lighter reflection stripe on it, two slanted windshield pillars, a parked wiper bar. The
structure's pixels are known exactly, so the proposed mask is scored: the fraction of the
structure it covers and the fraction of the rest (ground and sky) it takes.

Usage::

    .venv/bin/python benchmarks/structure_mask_raycast.py --size 640x360 --frames 30 --workers 1 \\
        --picture docs/structure_mask_check.png

The last line printed is one JSON object with the figures.
"""
from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the repository root, for tests.helpers.raycast_airport


def cockpit_overlay(width: int, height: int):
    """Grey levels (float, NaN where the view is open) of the painted cockpit, and its truth mask."""
    import cv2
    grey = np.full((height, width), np.nan)
    u = np.arange(width)
    # glare shield: a curved upper edge, darker towards the bottom
    edge_v = 0.80 * height - 0.05 * height * np.cos(np.pi * (u - width / 2) / width)
    v = np.arange(height)[:, None]
    shield = v >= edge_v[None, :]
    grey[shield] = (38.0 - 14.0 * (v - edge_v[None, :]) / height * np.ones((1, width)))[shield]
    stripe = (v >= edge_v[None, :] + 0.03 * height) & (v < edge_v[None, :] + 0.03 * height + 5)
    grey[stripe & (u[None, :] > 0.2 * width) & (u[None, :] < 0.7 * width)] = 88.0      # static reflection
    pillars = np.zeros((height, width), np.uint8)
    cv2.fillPoly(pillars, [np.array([[0, 0], [int(0.06 * width), 0], [int(0.13 * width), height - 1],
                                     [0, height - 1]], np.int32)], 1)
    cv2.fillPoly(pillars, [np.array([[int(0.95 * width), 0], [width - 1, 0], [width - 1, height - 1],
                                     [int(0.89 * width), height - 1]], np.int32)], 1)
    grey[pillars > 0] = 30.0
    wiper = np.zeros((height, width), np.uint8)
    cv2.line(wiper, (int(0.62 * width), height - 1), (int(0.34 * width), int(0.62 * height)), 1,
             thickness=max(4, int(0.012 * width)))
    grey[(wiper > 0) & ~shield] = 52.0
    grey[(wiper > 0) & shield] = 46.0
    return grey, ~np.isnan(grey)


def _draw(job):
    from tests.helpers.raycast_airport import draw_frame
    scene, camera, p, R, seed = job
    return draw_frame(scene, camera, p, R, supersample=2, blur_sigma_px=0.5, rng=np.random.default_rng(seed))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", default="thesis-3")
    parser.add_argument("--size", default="640x360", help="WxH (default 640x360)")
    parser.add_argument("--hfov", type=float, default=70.0, help="horizontal field of view, deg (default 70)")
    parser.add_argument("--frames", type=int, default=30, help="frames spread over the approach (default 30)")
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--k1", type=float, default=0.0, help="radial distortion of the lens (default 0)")
    parser.add_argument("--lines", action="store_true",
                        help="also estimate k1 from straight edges (visland calibrate --lines), with and without "
                             "the proposed mask")
    parser.add_argument("--picture", metavar="PNG", help="write the frame | mask check picture here")
    parser.add_argument("--frames-dir", metavar="DIR", help="also write the cockpit frames here (DIR/frames/)")
    args = parser.parse_args(argv)

    import cv2
    from tests.helpers.raycast_airport import PaintedAirport

    from visland.camera import CameraModel
    from visland.features import batch_R_camera_from_runway
    from visland.footage import evenly_spaced
    from visland.scenarios import resolve_scenario
    from visland.simulate import SimulationOptions, run_simulation
    from visland.structure_mask import mask_picture, propose_structure_mask

    width, height = (int(a) for a in args.size.lower().split("x"))
    camera = CameraModel.from_fov(width, height, args.hfov, (0.0, -4.0, 0.0),
                                  (args.k1, 0.0, 0.0, 0.0, 0.0) if args.k1 else None)
    sim = run_simulation(resolve_scenario(args.scenario), SimulationOptions(fps=5.0, camera=camera))
    states = sim.frames
    chosen = evenly_spaced(len(states.t_s), args.frames)
    R = batch_R_camera_from_runway(states.roll_rad, states.pitch_rad, states.dpsi_rad, camera.mount_rpy_rad)
    scene = PaintedAirport(seed=args.seed)
    jobs = [(scene, camera, states.p_runway_m[i], R[i], args.seed * 1000 + i) for i in chosen]
    start = time.perf_counter()
    with mp.get_context("spawn").Pool(max(1, args.workers)) as pool:
        views = pool.map(_draw, jobs, chunksize=1)
    draw_s = time.perf_counter() - start
    overlay, truth = cockpit_overlay(width, height)
    rng = np.random.default_rng(args.seed)
    frames = []
    for view in views:
        image = view.astype(float)
        image[truth] = overlay[truth] + rng.normal(0.0, 2.0, int(truth.sum()))
        frames.append(np.clip(np.rint(image), 0, 255).astype(np.uint8))
    if args.frames_dir:
        out = Path(args.frames_dir) / "frames"
        out.mkdir(parents=True, exist_ok=True)
        for k, image in enumerate(frames):
            cv2.imwrite(str(out / f"{k:05d}.png"), image)
        cv2.imwrite(str(Path(args.frames_dir) / "structure_truth.png"), truth.astype(np.uint8) * 255)
    start = time.perf_counter()
    result = propose_structure_mask(frames, source=args.scenario)
    mask_s = time.perf_counter() - start
    covered = float(result.mask[truth].mean())
    taken = float(result.mask[~truth].mean())
    print(result.summary())
    print(f"structure covered {100 * covered:.2f} %, rest taken {100 * taken:.2f} % "
          f"({len(frames)} frames {width}x{height} drawn in {draw_s:.0f} s; mask in {mask_s:.2f} s)")
    if args.picture:
        picture = mask_picture(frames[len(frames) // 2], result.mask)
        cv2.imwrite(args.picture, cv2.cvtColor(picture, cv2.COLOR_RGB2BGR))
        print(f"wrote {args.picture}")
    figures = {"benchmark": "structure_mask_raycast", "scenario": args.scenario, "size": [width, height],
               "hfov_deg": args.hfov, "k1": args.k1, "frames": len(frames), "structure_covered": round(covered, 4),
               "rest_taken": round(taken, 4), "coverage": round(result.coverage, 4), "mask_s": round(mask_s, 2)}
    if args.lines:
        from visland.lens import estimate_k1_from_lines
        for name, ignore in (("k1_from_lines", None), ("k1_from_lines_masked", result.mask)):
            try:
                estimate = estimate_k1_from_lines(frames, camera.fx, camera.fy, camera.cx, camera.cy, ignore=ignore)
                figures[name] = round(estimate.k1, 4)
                print(f"{name}: {estimate.k1:.4f} (truth {args.k1}) from {estimate.pieces} pieces")
            except ValueError as error:
                figures[name] = None
                print(f"{name}: {error}")
    print(json.dumps(figures))
    return 0


if __name__ == "__main__":
    sys.exit(main())
