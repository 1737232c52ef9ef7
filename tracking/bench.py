"""``visland bench track``: how many frames per second the tracker handles (ends with a JSON line).

Frames are produced before timing and held in memory (grey uint8): the synthetic planar scene
of :mod:`visland.tracking.synthetic` along the thesis-1 approach from ``--distance`` metres
before the threshold, or frames rendered by :mod:`visland.render`. Only
:meth:`visland.tracking.PointTracker.step` is timed (prediction, matching, sub-pixel
refinement, rigid check, template update), not reading or decoding images. Each repeat
starts a new tracker on the first frame; the figure is the median over repeats of
``frames / total step time``, with the load average of the machine at the end (timings are
noisy on a shared machine).
"""
from __future__ import annotations

import json
import math
import os
import time

import numpy as np

from visland.camera import CameraModel
from visland.features import batch_R_camera_from_runway
from visland.folder import as_grey
from visland.runway import CORNER_NAMES
from visland.scenarios import get_scenario
from visland.simulate import SimulationOptions, run_simulation
from visland.tracking.motion import Attitude
from visland.tracking.params import TrackerParams
from visland.tracking.tracker import PointTracker

__all__ = ["run_track_benchmark", "TARGET_FPS"]

#: Issue target: two points at 2048x2048.
TARGET_FPS = 200.0


def _frames(source: str, camera, scenario, states, indices):
    R = batch_R_camera_from_runway(states.roll_rad, states.pitch_rad, states.dpsi_rad, camera.mount_rpy_rad)
    images = []
    if source == "synthetic":
        from visland.tracking.synthetic import make_planar_scene, render_planar
        scene = make_planar_scene(scenario.runway, seed=0, x_range_m=(-3000.0, 3500.0), y_range_m=(-800.0, 800.0))
        for k in indices:
            images.append(render_planar(scene, camera, R[k], states.p_runway_m[k]))
        return images
    from visland.render import FrameRenderer, SceneParams
    with FrameRenderer(SceneParams(), camera, scenario.runway) as renderer:
        for k in indices:
            images.append(as_grey(renderer.render(states.p_runway_m[k], R[k])))
    return images


def run_track_benchmark(args) -> int:
    """Run ``visland bench track``: the tracker's speed on synthetic or rendered frames.

    Parameters
    ----------
    args : argparse.Namespace
        ``--size``, ``--points``, ``--frames``, ``--repeats``, ``--policy``, ``--distance``,
        ``--source`` (see ``visland bench track --help``).

    Returns
    -------
    int
        Exit status 0; the last line printed is one JSON object of the figures.
    """
    for name, low, high in (("size", 64, 8192), ("frames", 5, 5000), ("repeats", 1, 100)):
        value = getattr(args, name)
        if not low <= value <= high:
            raise ValueError(f"--{name} must lie in [{low}, {high}], got {value}")
    if args.points not in (1, 2, 3, 4):
        raise ValueError(f"--points must be 1 to 4 (runway corners), got {args.points}")
    if not (math.isfinite(args.distance) and args.distance > 200.0):
        raise ValueError(f"--distance must be more than 200 m, got {args.distance}")
    camera = CameraModel.default(args.size)
    scenario = get_scenario("thesis-1")
    result = run_simulation(scenario, SimulationOptions(camera=camera))
    states, labels = result.frames, result.features
    distance_to_threshold = -states.p_runway_m[:, 0]
    first = int(np.argmin(np.abs(distance_to_threshold - args.distance)))
    last = first + args.frames
    if last >= len(states):
        raise ValueError(f"--frames {args.frames} from {args.distance:g} m runs past the threshold "
                         f"({len(states) - first - 1} frames left)")
    indices = list(range(first, last + 1))
    print(f"bench track: {args.source} frames {args.size}x{args.size}, thesis-1 frames {first}..{last} "
          f"({distance_to_threshold[first]:.0f} m to {distance_to_threshold[last]:.0f} m from the threshold)",
          flush=True)
    started = time.perf_counter()
    images = _frames(args.source, camera, scenario, states, indices)
    print(f"  frames ready in {time.perf_counter() - started:.1f} s", flush=True)
    names = CORNER_NAMES[:args.points]
    params = TrackerParams(update_policy=args.policy)

    def attitude(k):
        return Attitude(float(states.roll_rad[k]), float(states.pitch_rad[k]), float(states.heading_rad[k]))

    fps_runs, step_ms, max_error, lost = [], [], 0.0, 0
    for repeat in range(args.repeats):
        tracker = PointTracker(camera, params)
        tracker.start(images[0], {n: labels.corners_uv[first, CORNER_NAMES.index(n)] for n in names},
                      attitude(first), frame_index=first)
        total = 0.0
        for image, k in zip(images[1:], indices[1:]):
            attitude_k = attitude(k)
            t0 = time.perf_counter()
            step = tracker.step(image, attitude_k, frame_index=k)
            dt = time.perf_counter() - t0
            total += dt
            step_ms.append(1000.0 * dt)
        fps_runs.append(args.frames / total)
        for n in names:
            report = step.point(n)
            if report.measured:
                max_error = max(max_error, float(np.hypot(*(report.uv - labels.corners_uv[k, CORNER_NAMES.index(n)]))))
            else:
                lost += 1
        print(f"  run {repeat + 1}: {fps_runs[-1]:.0f} frames/s ({1000 * total / args.frames:.2f} ms per frame)",
              flush=True)
    fps = float(np.median(fps_runs))
    figures = {
        "bench": "track", "source": args.source, "size": args.size, "points": args.points, "frames": args.frames,
        "repeats": args.repeats, "policy": args.policy, "fps_median": round(fps, 1),
        "fps_runs": [round(f, 1) for f in fps_runs],
        "ms_per_frame_median": round(float(np.median(step_ms)), 3),
        "ms_per_frame_p95": round(float(np.percentile(step_ms, 95)), 3),
        "target_fps": TARGET_FPS, "meets_target": bool(fps >= TARGET_FPS),
        "final_error_px_max": round(max_error, 3), "points_lost_at_end": lost,
        "load_average_1min": round(os.getloadavg()[0], 2), "cpu_count": os.cpu_count(),
    }
    print(f"median {fps:.0f} frames/s for {args.points} points at {args.size}x{args.size} "
          f"(target {TARGET_FPS:.0f}: {'met' if fps >= TARGET_FPS else 'NOT met'}); load average "
          f"{figures['load_average_1min']} on {os.cpu_count()} cores")
    print(json.dumps(figures))
    return 0
