"""``visland bench render``: time the renderer on frames of a flown approach.

Figures (seconds per frame, median over the frames, with the 10th and 90th percentiles):

- ``render``: :meth:`FrameRenderer.render` at the requested size: draw, MSAA resolve, RGB
  readback, blur and noise (what a dataset frame costs before it is written);
- ``render+png``: the same plus PNG encoding (zlib level ``--png-compression``) and an atomic
  write to a temporary folder;
- ``options``: the cost of each quality option, as the change of the median ``render`` time
  when that option alone is changed from the default (one renderer per variant);
- CPU seconds per frame (all threads of the process, llvmpipe's included), which depend far
  less than wall time on what else runs on the machine.

The machine is often shared: the load average before and after is printed with the figures.
The last line is one JSON object holding them.
"""
from __future__ import annotations

import json
import os
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

__all__ = ["run_render_bench", "approach_poses", "VARIANTS"]

#: Quality options timed against the default, (label, SceneParams overrides).
VARIANTS = (
    ("msaa 4", {"msaa_samples": 4}),
    ("msaa 2", {"msaa_samples": 2}),
    ("anisotropic taps 1 (off)", {"anisotropy": 1.0}),
    ("anisotropic taps 16", {"anisotropy": 16.0}),
    ("noise off", {"noise_std": 0.0}),
    ("blur sigma 1 px", {"blur_sigma_px": 1.0}),
    ("no distractors", {"distractors": False}),
    ("no clouds", {"cloud_cover": 0.0}),
    ("flat colours", {"style": "flat", "noise_std": 0.0, "distractors": False}),
)


def approach_poses(size: int, n_frames: int, scenario_name: str = "thesis-1"):
    """``n_frames`` camera poses spread from the start of the approach to 100 ft, and the camera and runway.

    Parameters
    ----------
    size : int
        Frame side, pixels (the SPEC camera scaled).
    n_frames : int
        Number of poses.
    scenario_name : str, default "thesis-1"
        The built-in scenario flown.

    Returns
    -------
    poses : list of (ndarray, ndarray)
        ``(p_runway_m (3,), R_camera_from_runway (3, 3))`` per frame.
    camera : visland.camera.CameraModel
    runway : visland.runway.Runway
    """
    from visland.camera import CameraModel
    from visland.features import batch_R_camera_from_runway
    from visland.flight import FT_TO_M
    from visland.scenarios import resolve_scenario
    from visland.simulate import SimulationOptions, run_simulation
    camera = CameraModel.default(size)
    result = run_simulation(resolve_scenario(scenario_name), SimulationOptions(fps=5.0, camera=camera))
    s = result.frames
    last = int(np.nonzero(-s.p_runway_m[:, 2] <= 100.0 * FT_TO_M)[0][0])
    index = np.unique(np.linspace(0, last, n_frames).round().astype(int))
    R_cr = batch_R_camera_from_runway(s.roll_rad, s.pitch_rad, s.dpsi_rad, camera.mount_rpy_rad)
    return [(s.p_runway_m[i], R_cr[i]) for i in index], camera, result.scenario.runway


def _percentiles(times):
    t = np.asarray(times)
    return {"median_s": float(np.median(t)), "p10_s": float(np.percentile(t, 10)), "p90_s": float(np.percentile(t, 90)),
            "n": int(t.size)}


def _time_renders(params, camera, runway, poses, warmup=1, png_level=None, folder=None):
    import cv2
    from visland.contracts import atomic_write_bytes
    from visland.render import FrameRenderer
    t0 = time.perf_counter()
    with FrameRenderer(params, camera, runway) as renderer:
        setup = time.perf_counter() - t0
        for p, R in poses[:warmup]:
            renderer.render(p, R, frame_seed=0)
        render_times, write_times, sizes, cpu_times = [], [], [], []
        for k, (p, R) in enumerate(poses):
            t = time.perf_counter()
            c = time.process_time()
            rgb = renderer.render(p, R, frame_seed=k)
            t_render = time.perf_counter() - t
            render_times.append(t_render)
            cpu_times.append(time.process_time() - c)
            if png_level is not None:
                ok, data = cv2.imencode(".png", np.ascontiguousarray(rgb[..., ::-1]),
                                        [cv2.IMWRITE_PNG_COMPRESSION, png_level])
                atomic_write_bytes(Path(folder) / f"{k:06d}.png", data.tobytes())
                write_times.append(time.perf_counter() - t)
                sizes.append(len(data))
    return setup, render_times, write_times, sizes, cpu_times


def run_render_bench(size: int = 2048, n_frames: int = 9, png_compression: int = 1, variants: bool = True,
                     png_levels=(0, 1, 3, 6), out=print) -> dict:
    """Run the benchmark, print a table with ``out`` and return the figures (also printed as JSON last).

    Parameters
    ----------
    size : int, default 2048
        Square frame side, pixels.
    n_frames : int, default 9
        Frames rendered along the approach.
    png_compression : int, default 1
        PNG compression level of the frames written.
    variants : bool, default True
        Also time the scene options (msaa, variety...).
    png_levels : sequence of int
        PNG levels whose encoding time is measured.
    out : callable, default print
        Where the table's lines go.

    Returns
    -------
    dict
        The figures (seconds per frame and per step).
    """
    from visland.render.params import SceneParams
    load_before = os.getloadavg()
    poses, camera, runway = approach_poses(size, n_frames)
    default = SceneParams()
    out(f"visland bench render: {size}x{size}, {len(poses)} frames of thesis-1 from the start to 100 ft, "
        f"load average {load_before[0]:.2f} (1 min) before")
    with tempfile.TemporaryDirectory(prefix="visland-bench-") as folder:
        setup, render_times, write_times, sizes, cpu_times = _time_renders(default, camera, runway, poses,
                                                                           png_level=png_compression, folder=folder)
        figures = {
            "size_px": size, "frames": len(poses), "setup_s": setup,
            "render": _percentiles(render_times),
            "render_cpu_median_s": float(np.median(cpu_times)),
            "render_png": _percentiles(write_times),
            "png_compression": png_compression, "png_mean_bytes": float(np.mean(sizes)),
        }
        out(f"  scene setup (textures, GL context): {setup:.2f} s")
        out(f"  render (draw + readback + noise): median {figures['render']['median_s']:.3f} s/frame "
            f"[p10 {figures['render']['p10_s']:.3f}, p90 {figures['render']['p90_s']:.3f}], "
            f"CPU (all threads) {figures['render_cpu_median_s']:.3f} s/frame")
        out(f"  render + PNG level {png_compression} + write: median {figures['render_png']['median_s']:.3f} s/frame "
            f"[p10 {figures['render_png']['p10_s']:.3f}, p90 {figures['render_png']['p90_s']:.3f}], "
            f"{figures['png_mean_bytes'] / 1e6:.2f} MB/frame")
        png = {}
        if png_levels:
            import cv2
            from visland.render import FrameRenderer
            with FrameRenderer(default, camera, runway) as renderer:
                images = [renderer.render(p, R, frame_seed=k)[..., ::-1].copy() for k, (p, R) in enumerate(poses[:3])]
            for level in png_levels:
                times, nbytes = [], []
                for image in images:
                    t = time.perf_counter()
                    ok, data = cv2.imencode(".png", image, [cv2.IMWRITE_PNG_COMPRESSION, level])
                    times.append(time.perf_counter() - t)
                    nbytes.append(len(data))
                png[str(level)] = {"encode_median_s": float(np.median(times)), "mean_bytes": float(np.mean(nbytes))}
                out(f"  PNG level {level}: encode {png[str(level)]['encode_median_s']:.3f} s, "
                    f"{png[str(level)]['mean_bytes'] / 1e6:.2f} MB")
        figures["png_levels"] = png
    options = {}
    if variants:
        base = figures["render"]["median_s"]
        out("  quality options (median render time, change from the default):")
        for label, overrides in VARIANTS:
            params = replace(default, **overrides)
            _, times, _, _, cpus = _time_renders(params, camera, runway, poses)
            median = float(np.median(times))
            cpu = float(np.median(cpus))
            options[label] = {"median_s": median, "delta_s": median - base, "cpu_median_s": cpu,
                              "cpu_delta_s": cpu - figures["render_cpu_median_s"]}
            out(f"    {label:28s} {median:.3f} s  ({median - base:+.3f} s)   CPU {cpu:.3f} s "
                f"({cpu - figures['render_cpu_median_s']:+.3f} s)")
    figures["options"] = options
    figures["load_average_before"] = load_before[0]
    figures["load_average_after"] = os.getloadavg()[0]
    figures["target_s"] = 0.15
    figures["meets_target"] = figures["render"]["median_s"] <= 0.15
    out(f"  load average after: {figures['load_average_after']:.2f}; target 0.15 s/frame: "
        f"{'met' if figures['meets_target'] else 'NOT met'}")
    out(json.dumps({"bench": "render", **figures}))
    return figures
