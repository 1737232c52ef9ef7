"""Command-line registration of the visland.tracking stage (light: no heavy imports here).

``visland track DIR --out FILE [--init labels|"u,v;u,v"] [--anchor [detector|labels]] ...``
tracks designated points through a frame folder and writes ``measurements.csv``;
``visland bench track`` times the tracker (ends with one JSON line).
"""
from __future__ import annotations

import argparse


def register(subparsers):
    """Add this stage's commands to the visland parser.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        Where ``track`` goes (the commands of :func:`visland.cli.build_parser`).
    """
    from visland.cli import add_frame_source_arguments
    p = subparsers.add_parser(
        "track", help="track designated points (runway corners) through a frame folder into measurements.csv",
        description="Template tracking of designated points (thesis 5.3.2.1) through the frames of DIR "
                    "(SPEC folder: frames/, camera.json, telemetry.csv, optional labels.csv). Writes FILE "
                    "in the measurements schema: tracked corners in the corner columns, per-point loss in "
                    "'reason' and empty cells. The template update policy makes the drift (see --policy).",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("folder", metavar="DIR", help="frame folder")
    p.add_argument("--out", required=True, metavar="FILE", help="measurements CSV to write")
    p.add_argument("--init", default="labels", metavar='labels|"u,v;u,v"',
                   help="designation on the start frame: 'labels' (the visible labelled corners) or pixel "
                        "positions 'u,v;u,v' taken as near_left, near_right, far_left, far_right in order "
                        "(or named: 'near_left=u,v;near_right=u,v'); default labels")
    p.add_argument("--anchor", nargs="?", const="detector", default=None, choices=("detector", "labels"),
                   help="re-anchor the corners on detection: 'detector' (default when the flag is given: "
                        "visland.detection) or 'labels' (the exact labelled corners, a perfect detector "
                        "for studies)")
    p.add_argument("--anchor-every", type=int, default=1, metavar="N",
                   help="run the anchor every N frames (default 1)")
    p.add_argument("--policy", default=None,
                   choices=("every_frame", "every_n", "score_drop", "scale_change", "never"),
                   help="template update policy (overrides --params; default scale_change; every_frame is "
                        "the thesis's behaviour, which drifts fastest)")
    p.add_argument("--params", metavar="FILE", help="tracker parameters (.json or .toml, see "
                                                    "visland.tracking.TrackerParams)")
    p.add_argument("--start", type=int, default=0, metavar="FRAME", help="designation frame (default 0)")
    p.add_argument("--edge-points", type=int, default=0, metavar="K",
                   help="with --init labels: also track K points on each side edge (for the rigid check)")
    p.add_argument("--no-inertial", action="store_true",
                   help="ignore the telemetry attitude (no rotation prediction, template warp or rigid check)")
    add_frame_source_arguments(p, telemetry_note="required unless --no-inertial")
    p.add_argument("--force", action="store_true", help="replace an existing output file")
    p.set_defaults(func=_cmd_track)


def register_bench(bench_subparsers):
    """Add ``visland bench track``.

    Parameters
    ----------
    bench_subparsers : argparse._SubParsersAction
        Where ``visland bench track`` is registered.
    """
    p = bench_subparsers.add_parser(
        "track", help="tracker speed: frames per second for N points (ends with a JSON line)",
        description="Times PointTracker.step on frames held in memory (synthetic planar scene along the "
                    "thesis-1 approach, or rendered with visland.render). Reports the median over repeats.")
    p.add_argument("--size", type=int, default=2048, help="image size in pixels (default 2048)")
    p.add_argument("--points", type=int, default=2, help="tracked points: 2 (threshold corners) or 4 (default 2)")
    p.add_argument("--frames", type=int, default=100, help="frames per run (default 100)")
    p.add_argument("--repeats", type=int, default=5, help="runs; the median is reported (default 5)")
    p.add_argument("--policy", default="scale_change",
                   choices=("every_frame", "every_n", "score_drop", "scale_change", "never"),
                   help="template update policy (default scale_change, the tracker's default)")
    p.add_argument("--distance", type=float, default=2000.0, metavar="M",
                   help="start the timed frames this far from the threshold (default 2000 m)")
    p.add_argument("--source", default="synthetic", choices=("synthetic", "render"),
                   help="frames: 'synthetic' (tracking.synthetic, fast) or 'render' (visland.render)")
    p.set_defaults(func=_cmd_bench_track)


def _cmd_track(args) -> int:
    from pathlib import Path

    from visland.contracts import write_csv
    from visland.folder import FrameFolder
    from visland.tracking.params import TrackerParams
    from visland.tracking.run import track_source

    from visland.userfiles import check_output_file
    out = check_output_file(args.out, force=args.force)
    if out.exists() and not args.force:
        raise ValueError(f"{out}: output file exists; choose another --out or pass --force to replace it")
    if out.exists() and out.is_dir():
        raise ValueError(f"{out}: is a folder; --out names the measurements CSV file to write")
    if not out.parent.exists():
        raise ValueError(f"{out.parent}: folder of --out does not exist")
    params = TrackerParams.load(args.params) if args.params else TrackerParams()
    if args.policy:
        params = TrackerParams.from_dict({**params.to_dict(), "update_policy": args.policy}, source="--policy")
    folder = FrameFolder(args.folder, camera=args.camera, telemetry=args.telemetry, frames_csv=args.frames_csv,
                         fps=args.fps, require_telemetry=not args.no_inertial, time_offset_s=args.time_offset)
    from visland.limits import check_frame_folder
    check_frame_folder(folder, args.camera or str(Path(args.folder) / "camera.json"), args.folder)
    run = track_source(folder, init=args.init, params=params, anchor=args.anchor, anchor_every=args.anchor_every,
                       start=args.start, edge_points=args.edge_points, use_inertial=not args.no_inertial)
    write_csv(out, run.columns, run.column_order)
    for line in summary_lines(run, folder.labels):
        print(line)
    print(f"wrote {out} ({len(folder)} frames, source {'anchored' if args.anchor else 'tracking'}, "
          f"policy {params.update_policy})")
    return 0


def summary_lines(run, labels=None) -> list:
    """Per point: frames measured, losses, anchoring; pixel error against labels when present.

    Parameters
    ----------
    run : visland.tracking.TrackRun
        The outcome of :func:`visland.tracking.track_source`.
    labels : visland.contracts.Table, optional
        The folder's ``labels.csv`` (exact corners, pixels), for the error columns.

    Returns
    -------
    list of str
        The lines to print, one per tracked point.
    """
    import numpy as np

    from visland.tracking.run import error_against_labels

    errors = error_against_labels(run, labels) if labels is not None else {}
    tracked = [s for s in run.steps if s is not None]
    lines = [f"tracked {len(run.point_names)} points over {len(tracked)} frames from frame {run.start_frame}"]
    header = f"  {'point':14s} {'measured':>9s} {'coasting':>9s} {'lost':>6s} {'anchored':>9s}"
    if errors:
        header += f" {'median px':>10s} {'max px':>8s} {'last px':>8s}"
    lines.append(header)
    for name in run.point_names:
        statuses = [s.point(name).status for s in tracked]
        measured = sum(s in ("designated", "tracked", "anchored", "reprojected", "inconsistent") for s in statuses)
        line = (f"  {name:14s} {measured:9d} {statuses.count('coasting'):9d} {statuses.count('lost'):6d} "
                f"{statuses.count('anchored'):9d}")
        if name in errors:
            e = errors[name]
            finite = e[np.isfinite(e)]
            if finite.size:
                line += f" {np.median(finite):10.2f} {finite.max():8.2f} {finite[-1]:8.2f}"
            else:
                line += f" {'-':>10s} {'-':>8s} {'-':>8s}"
        first_loss = next((s.frame_index for s in tracked if s.point(name).status in ("lost", "refused")), None)
        if first_loss is not None:
            reason = next(s.point(name).reason for s in tracked if s.frame_index == first_loss)
            line += f"   first lost at frame {first_loss}: {reason}"
        lines.append(line)
    return lines


def _cmd_bench_track(args) -> int:
    from visland.tracking.bench import run_track_benchmark
    return run_track_benchmark(args)
