"""Drift of the template tracker on rendered approaches, pure and anchored (tracking issue, figures).

For each scenario (default: the eight of thesis Table 5.2): fly it, render every frame at
25 Hz in memory with :class:`visland.render.FrameRenderer` (grey), designate the four runway
corners once with the labelled corners of the first frame (a perfect pilot), and run several
trackers side by side on the same frames down to 100 ft:

- ``pure``: the tracker's default (template re-cut when the ground around the point has
  grown by 25 %, warped in between), drift only flagged by the rigid check;
- ``every_frame``: re-cut every frame (thesis 5.3.2.1 "Memo": the most similar patch each
  frame), and ``every_n``, ``score_drop``, ``never``: the other update policies;
- ``consensus``: ``pure`` plus re-projection of the points the rigid check singles out
  (the several-points remedy);
- ``anchored``: ``pure`` plus re-anchoring on :func:`visland.detection.detect_runway` run on
  every frame (the detection remedy); only when the detector runs on full frames;
- ``anchored_labels``: ``pure`` re-anchored once a second on the exact labelled corners (a
  perfect detector at 1 Hz: the tracker's own drift between anchors).

Each tracked corner is compared with its label (the exact projection). Figures: the pixel
error at 5, 3 and 1 km before the aiming point (along-track dX = -5000, -3000, -1000 m;
"n/a" when the scenario starts inside that distance, as thesis-1 does at exactly 5 km: the
designation) and at 100 ft, per corner, and the worst over the approach; a plot of the
threshold corners' error against time; a JSON line at the end.

``--crop`` renders only a window of the same 2048 camera around the path of the corners
(the same pixels, several times faster: its principal point is kept, so it is the same
pinhole); the detector is not run on crops (it searches the whole frame).

``benchmarks/track_height.py`` then feeds the tracked corners to the observers (the height
error at 400/200/100 ft, thesis Table 5.14).

Usage::

    python benchmarks/track_drift.py                                  # eight scenarios, full frames
    python benchmarks/track_drift.py --scenarios thesis-1 --crop      # quick
    python benchmarks/track_drift.py --plot /tmp/tracking_drift.png

Results are kept per scenario in ``--out`` (an ``.npz`` each): a rerun skips the scenarios
already done unless ``--force``.
"""
from __future__ import annotations

import argparse
import json
import math
import multiprocessing
import os
import sys
import time
from pathlib import Path

import numpy as np

FT_TO_M = 0.3048
TRACKERS = ("pure", "every_frame", "every_n", "score_drop", "never", "consensus", "anchored", "anchored_labels")
STATUS_CODES = {"designated": 0, "tracked": 1, "anchored": 2, "reprojected": 3, "inconsistent": 4,
                "coasting": 5, "lost": 6, "refused": 7, "skipped": 8}
MARKS = (("5 km", "dx", -5000.0), ("3 km", "dx", -3000.0), ("1 km", "dx", -1000.0), ("100 ft", "dh", 100 * FT_TO_M))


def tracker_setup(name: str):
    """(TrackerParams, anchor kind) of a named tracker."""
    from visland.tracking import TrackerParams
    if name == "pure":
        return TrackerParams(), None                       # the default policy (scale_change)
    if name == "every_n":
        return TrackerParams(update_policy="every_n", update_every_n=10), None
    if name in ("every_frame", "score_drop", "never"):
        return TrackerParams(update_policy=name), None
    if name == "consensus":
        return TrackerParams(on_inconsistent="reproject"), None
    if name == "anchored":
        return TrackerParams(), "detector"
    if name == "anchored_labels":
        return TrackerParams(), "labels"
    raise ValueError(f"unknown tracker '{name}' (known: {', '.join(TRACKERS)})")


def crop_camera(camera, corners_uv, margin_px: int):
    """The window of ``camera`` holding all corners (plus margin) and its principal point."""
    from visland.camera import CameraModel
    u = corners_uv[..., 0]
    v = corners_uv[..., 1]
    u0 = int(max(0, min(np.floor(np.nanmin(u)) - margin_px, math.floor(camera.cx))))
    v0 = int(max(0, min(np.floor(np.nanmin(v)) - margin_px, math.floor(camera.cy))))
    u1 = int(min(camera.width, max(np.ceil(np.nanmax(u)) + margin_px + 1, math.ceil(camera.cx) + 1)))
    v1 = int(min(camera.height, max(np.ceil(np.nanmax(v)) + margin_px + 1, math.ceil(camera.cy) + 1)))
    cropped = CameraModel(u1 - u0, v1 - v0, camera.fx, camera.fy, camera.cx - u0, camera.cy - v0,
                          camera.mount_rpy_rad)
    return cropped, (u0, v0)


def run_scenario(task: dict) -> dict:
    """Render and track one scenario; save its arrays; return its summary (runs in a worker)."""
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    import cv2

    from visland.camera import CameraModel
    from visland.features import batch_R_camera_from_runway
    from visland.render import FrameRenderer, SceneParams
    from visland.runway import CORNER_NAMES
    from visland.scenarios import get_scenario
    from visland.simulate import SimulationOptions, run_simulation
    from visland.tracking import AnchorObservation, Attitude, PointTracker
    from visland.tracking.anchoring import anchor_from_detection

    name, size, crop, names = task["scenario"], task["size"], task["crop"], task["trackers"]
    scenario = get_scenario(name)
    camera_full = CameraModel.default(size)
    result = run_simulation(scenario, SimulationOptions(camera=camera_full))
    states, labels = result.frames, result.features
    dh = -states.p_runway_m[:, 2]
    dx = states.p_runway_m[:, 0] - scenario.runway.aim_distance_m
    last = int(np.nonzero(dh <= 100 * FT_TO_M)[0][0])        # down to 100 ft
    n = last + 1
    corners_full = labels.corners_uv[:n]
    if crop:
        camera, (u0, v0) = crop_camera(camera_full, corners_full, task["margin"])
        names = [t for t in names if t != "anchored"]
    else:
        camera, (u0, v0) = camera_full, (0, 0)
    corners = corners_full - np.array([u0, v0])
    R = batch_R_camera_from_runway(states.roll_rad, states.pitch_rad, states.dpsi_rad, camera.mount_rpy_rad)
    trackers = {t: (PointTracker(camera, tracker_setup(t)[0]), tracker_setup(t)[1]) for t in names}
    errors = {t: np.full((n, 4), np.nan) for t in names}
    positions = {t: np.full((n, 4, 2), np.nan) for t in names}      # full-frame pixels
    status = {t: np.full((n, 4), -1, dtype=np.int8) for t in names}
    step_s = {t: 0.0 for t in names}
    detector_s, detector_found, detector_error = 0.0, 0, []
    detector_corner_error = np.full((n, 4), np.nan)
    detector_confidence = np.full(n, np.nan)
    detect = None
    if "anchored" in names:
        from visland.detection import detect_runway
        detect = detect_runway
    previous = None
    render_s = 0.0
    started = time.perf_counter()
    with FrameRenderer(SceneParams(seed=task["seed"]), camera, scenario.runway) as renderer:
        for k in range(n):
            tic = time.perf_counter()
            gray = cv2.cvtColor(renderer.render(states.p_runway_m[k], R[k], frame_seed=k), cv2.COLOR_RGB2GRAY)
            render_s += time.perf_counter() - tic
            attitude = Attitude(float(states.roll_rad[k]), float(states.pitch_rad[k]), float(states.heading_rad[k]))
            detection = None
            if detect is not None and k > 0:
                tic = time.perf_counter()
                found = detect(gray, camera, attitude.roll_rad, attitude.pitch_rad, previous=previous)
                detector_s += time.perf_counter() - tic
                previous = found if found.found else None
                detection = anchor_from_detection(found)
                detector_confidence[k] = found.confidence
                if found.found:
                    detector_found += 1
                    ok = np.asarray(found.corners_found, dtype=bool)
                    detector_corner_error[k] = np.where(ok, np.hypot(*(found.corners_uv - corners[k]).T), np.nan)
                    detector_error.append(float(np.nanmax(np.where(ok, np.hypot(*(found.corners_uv - corners[k]).T),
                                                                   np.nan))) if ok.any() else np.nan)
            for t, (tracker, anchor) in trackers.items():
                tic = time.perf_counter()
                if k == 0:
                    step = tracker.start(gray, {c: corners[0, i] for i, c in enumerate(CORNER_NAMES)}, attitude)
                else:
                    observation = None
                    if anchor == "detector":
                        observation = detection
                    elif anchor == "labels" and k % 25 == 0:
                        observation = AnchorObservation(True, "", 1.0, corners[k], labels.corners_visible[k])
                    step = tracker.step(gray, attitude, observation)
                step_s[t] += time.perf_counter() - tic
                for i, c in enumerate(CORNER_NAMES):
                    report = step.point(c)
                    status[t][k, i] = STATUS_CODES[report.status]
                    if report.measured:
                        errors[t][k, i] = float(np.hypot(*(report.uv - corners[k, i])))
                        positions[t][k, i] = report.uv + (u0, v0)
            if task["verbose"] and k % 100 == 0:
                line = "  ".join(f"{t} {np.nanmax(errors[t][k, :2]):.2f}" for t in names)
                print(f"  {name} frame {k}/{n - 1} (render {render_s / (k + 1):.2f} s/frame): {line}", flush=True)
    out = Path(task["out"])
    extra = {}
    if detect is not None:
        extra["error_detector"] = detector_corner_error
        extra["confidence_detector"] = detector_confidence
        extra["status_detector"] = np.where(np.isfinite(detector_corner_error), STATUS_CODES["tracked"],
                                            STATUS_CODES["lost"]).astype(np.int8)
    np.savez_compressed(out / f"{name}.npz", t_s=states.t_s[:n], dx_m=dx[:n], dh_m=dh[:n], trackers=np.array(names),
                        **{f"error_{t}": errors[t] for t in names}, **{f"status_{t}": status[t] for t in names},
                        **{f"uv_{t}": positions[t] for t in names}, **extra)
    summary = {"scenario": name, "frames": n, "crop": [u0, v0, camera.width, camera.height] if crop else None,
               "render_s_per_frame": render_s / n, "wall_s": time.perf_counter() - started,
               "tracker_ms_per_frame": {t: 1000 * step_s[t] / n for t in names}}
    if detect is not None:
        finite = np.array([e for e in detector_error if np.isfinite(e)])
        summary["detector"] = {"found_fraction": detector_found / max(n - 1, 1),
                               "ms_per_frame": 1000 * detector_s / max(n - 1, 1),
                               "corner_error_px_median": float(np.median(finite)) if finite.size else None,
                               "corner_error_px_max": float(finite.max()) if finite.size else None}
    (out / f"{name}.json").write_text(json.dumps(summary, indent=1))
    return summary


def marks(data) -> dict:
    """Frame index of each figure mark (None when the approach does not reach or starts past it)."""
    out = {}
    for label, kind, value in MARKS:
        series = data["dx_m"] if kind == "dx" else data["dh_m"]
        if kind == "dx":
            reached = np.nonzero(series >= value)[0]
            out[label] = int(reached[0]) if reached.size and series[0] < value - 50.0 else None
        else:
            reached = np.nonzero(series <= value)[0]
            out[label] = int(reached[0]) if reached.size else None
    return out


def figures(out: Path, scenarios, names) -> dict:
    table = {}
    for name in scenarios:
        data = np.load(out / f"{name}.npz")
        index = marks(data)
        table[name] = {}
        for t in names:
            if f"error_{t}" not in data:
                continue
            err = data[f"error_{t}"]
            lost = data[f"status_{t}"] >= STATUS_CODES["coasting"]
            entry = {}
            for label, k in index.items():
                entry[label] = None if k is None else [None if not np.isfinite(e) else round(float(e), 2)
                                                       for e in err[k]]
            near = err[:, :2]
            entry["max_threshold_corners_px"] = round(float(np.nanmax(near)), 2) if np.isfinite(near).any() else None
            entry["measured_fraction"] = round(float(np.mean(~lost[1:, :2])), 3)
            table[name][t] = entry
    return table


def summarise(table, names) -> dict:
    """Per tracker and mark: mean and worst over the scenarios of the larger threshold-corner error."""
    out = {}
    for t in names:
        row = {}
        for label, _, _ in MARKS:
            values = []
            for scenario in table.values():
                entry = scenario.get(t, {}).get(label)
                if entry is None or entry[0] is None or entry[1] is None:
                    continue
                values.append(max(entry[0], entry[1]))
            row[label] = {"mean": round(float(np.mean(values)), 2) if values else None,
                          "worst": round(float(np.max(values)), 2) if values else None, "n": len(values)}
        out[t] = row
    return out


def print_table(table, names) -> None:
    print("\npixel error of the tracked corners against the labels (near_left/near_right/far_left/far_right) at "
          "5, 3 and 1 km before the aiming point (along-track) and at 100 ft; n/a: the approach starts inside "
          "that distance; -: not measured (lost)")
    for t in names:
        print(f"\n{t}")
        print(f"  {'scenario':10s} {'5 km':>23s} {'3 km':>23s} {'1 km':>23s} {'100 ft':>23s} {'max near':>9s} "
              f"{'measured':>9s}")
        for scenario, row in table.items():
            if t not in row:
                continue
            e = row[t]

            def cell(label):
                values = e[label]
                if values is None:
                    return f"{'n/a':>23s}"
                text = "/".join("-" if x is None else f"{x:.1f}" for x in values)
                return f"{text:>23s}"
            worst = e["max_threshold_corners_px"]
            print(f"  {scenario:10s} {cell('5 km')} {cell('3 km')} {cell('1 km')} {cell('100 ft')} "
                  f"{'-' if worst is None else f'{worst:.1f}':>9s} {e['measured_fraction']:9.3f}")


def plot(out: Path, scenarios, names, path: Path, shown=("every_frame", "pure", "anchored", "anchored_labels"),
         dpi: int = 110):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    colours = {"pure": "tab:red", "anchored": "tab:green", "anchored_labels": "tab:blue", "every_frame": "tab:orange",
               "never": "tab:purple", "consensus": "tab:brown", "every_n": "tab:pink", "score_drop": "tab:gray"}
    columns = 4 if len(scenarios) > 2 else len(scenarios)
    rows = int(math.ceil(len(scenarios) / columns))
    fig, axes = plt.subplots(rows, columns, figsize=(max(3.6 * columns, 6.0), 2.8 * rows + 0.6), squeeze=False,
                             sharey=True)
    for ax, name in zip(axes.ravel(), scenarios):
        data = np.load(out / f"{name}.npz")
        t = data["t_s"]
        for tracker in shown:
            if tracker not in names or f"error_{tracker}" not in data:
                continue
            err = data[f"error_{tracker}"]
            for i, style in ((0, "-"), (1, "--")):
                ax.plot(t, err[:, i], style, color=colours.get(tracker, "black"), lw=0.9,
                        label=f"{tracker} {'P' + chr(39) if i == 0 else 'P' + chr(39) * 2}")
        for m, (label, k) in enumerate(marks(data).items()):
            if k is not None:
                ax.axvline(t[k], color="0.6", lw=0.6)
                ax.text(t[k], 0.98 - 0.07 * (m % 2), label, transform=ax.get_xaxis_transform(), fontsize=6,
                        ha="center", va="top")
        ax.set_yscale("log")
        ax.set_ylim(0.03, 300.0)
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("time (s)", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
    for ax in axes[:, 0]:
        ax.set_ylabel("corner error (px, log)", fontsize=8)
    for ax in axes.ravel()[len(scenarios):]:
        ax.axis("off")
    handles, text = axes.ravel()[0].get_legend_handles_labels()
    fig.legend(handles, text, loc="lower center", ncol=min(len(text), 4), fontsize=7)
    fig.suptitle("Threshold corners P' (solid) and P'' (dashed): distance from the label, pixels (2048 px camera)",
                 fontsize=10)
    fig.tight_layout(rect=(0, 0.1, 1, 0.95))
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenarios", default=",".join(f"thesis-{i}" for i in range(1, 9)))
    parser.add_argument("--trackers", default=",".join(TRACKERS), help=f"subset of {', '.join(TRACKERS)}")
    parser.add_argument("--size", type=int, default=2048)
    parser.add_argument("--crop", action="store_true", help="render only the window the corners cross (no detector)")
    parser.add_argument("--margin", type=int, default=90, help="crop margin around the corners, px")
    parser.add_argument("--seed", type=int, default=0, help="scene seed")
    parser.add_argument("--workers", type=int, default=1, help="scenarios rendered in parallel (spawned processes)")
    parser.add_argument("--out", default="/tmp/tracking/drift", help="folder of the per-scenario results")
    parser.add_argument("--plot", default=None, help="also write the plot here (default: OUT/tracking_drift.png)")
    parser.add_argument("--plot-dpi", type=int, default=110, help="plot resolution (default 110)")
    parser.add_argument("--force", action="store_true", help="recompute scenarios already done")
    parser.add_argument("--quiet", action="store_true")
    args = parser.parse_args(argv)
    scenarios = [s.strip() for s in args.scenarios.split(",") if s.strip()]
    names = [t.strip() for t in args.trackers.split(",") if t.strip()]
    for t in names:
        tracker_setup(t)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    todo = [s for s in scenarios if args.force or not (out / f"{s}.npz").exists()]
    tasks = [{"scenario": s, "size": args.size, "crop": args.crop, "margin": args.margin, "trackers": names,
              "seed": args.seed, "out": str(out), "verbose": not args.quiet} for s in todo]
    print(f"track_drift: {len(scenarios)} scenarios ({len(todo)} to run), {args.size}x{args.size}"
          f"{' cropped' if args.crop else ''}, trackers {', '.join(names)}", flush=True)
    if args.workers > 1 and len(tasks) > 1:
        with multiprocessing.get_context("spawn").Pool(args.workers) as pool:
            for summary in pool.imap_unordered(run_scenario, tasks):
                print(f"  done {summary['scenario']}: {summary['frames']} frames, "
                      f"{summary['render_s_per_frame']:.2f} s/frame rendering", flush=True)
    else:
        for task in tasks:
            summary = run_scenario(task)
            print(f"  done {summary['scenario']}: {summary['frames']} frames, "
                  f"{summary['render_s_per_frame']:.2f} s/frame rendering", flush=True)
    shown = names + (["detector"] if "anchored" in names and not args.crop else [])
    table = figures(out, scenarios, shown)
    print_table(table, shown)
    summaries = {s: json.loads((out / f"{s}.json").read_text()) for s in scenarios}
    for s, summary in summaries.items():
        if "detector" in summary:
            d = summary["detector"]
            print(f"detector on {s}: found in {100 * d['found_fraction']:.0f} % of frames, corner error median "
                  f"{d['corner_error_px_median']} px, max {d['corner_error_px_max']} px, {d['ms_per_frame']:.0f} ms/frame")
    summary = summarise(table, shown)
    print("\nthreshold corners over the scenarios (mean / worst of max(P', P''), px; lost counts as missing):")
    for t, row in summary.items():
        print(f"  {t:16s} " + "  ".join(f"{label} {v['mean']}/{v['worst']} ({v['n']} sc.)" for label, v in row.items()))
    plot_path = Path(args.plot) if args.plot else out / "tracking_drift.png"
    plot(out, scenarios, shown, plot_path, dpi=args.plot_dpi)
    print(f"plot: {plot_path}")
    print(json.dumps({"benchmark": "track_drift", "size": args.size, "crop": args.crop, "scenarios": scenarios,
                      "trackers": shown, "summary_px": summary, "error_px": table,
                      "tracker_ms_per_frame": {s: summaries[s]["tracker_ms_per_frame"] for s in scenarios},
                      "detector": {s: summaries[s].get("detector") for s in scenarios}}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
