"""Command-line registration of the visland.detection stage (light: no heavy imports here).

- ``visland detect DIR --out FILE``: the detector over a frame folder, ``measurements.csv``.
- ``visland bench detect``: acquisition and tracking speed on full-size frames.
"""
from __future__ import annotations


def _load_params(path):
    from visland.detection.params import DetectorParams
    return DetectorParams.load(path) if path else DetectorParams()


def _cmd_detect(args) -> int:
    from pathlib import Path

    from visland.detection.run import detect_folder, write_measurements
    from visland.folder import FrameFolder
    from visland.userfiles import check_output_file
    if args.max_frames is not None and args.max_frames < 1:
        raise ValueError(f"--max-frames must be a positive number of frames, got {args.max_frames}")
    out = check_output_file(args.out, force=args.force)
    if out.exists() and not args.force:
        raise ValueError(f"{out}: output file exists; choose another --out or pass --force to replace it")
    if out.is_dir():
        raise ValueError(f"{out}: is a folder; --out names the measurements CSV file to write")
    params = _load_params(args.params)
    folder = FrameFolder(args.dir, camera=args.camera, telemetry=args.telemetry, frames_csv=args.frames_csv,
                         fps=args.fps, require_telemetry=False, time_offset_s=args.time_offset)
    from visland.limits import check_frame_folder
    check_frame_folder(folder, args.camera or str(Path(args.dir) / "camera.json"), args.dir)
    if folder.inertial is None:
        print(f"no telemetry ({args.telemetry or Path(args.dir) / 'telemetry.csv'} not found): roll and pitch are "
              "read off each frame (its horizon, then the runway's vanishing point)")
    result = detect_folder(folder, params, progress=not args.quiet, max_frames=args.max_frames)
    write_measurements(result, out)
    print(result.summary())
    print(f"wrote {out}")
    return 0


def _cmd_bench(args) -> int:
    from visland.detection.bench import frames_from_folder, print_report, render_frames, run_bench
    if args.repeat < 1:
        raise ValueError(f"--repeat must be at least 1, got {args.repeat}")
    if args.threads is not None and args.threads < 1:
        raise ValueError(f"--threads must be at least 1, got {args.threads}")
    if args.length < 2:
        raise ValueError(f"--length must be at least 2 frames (tracking needs a previous frame), got {args.length}")
    if args.dir:
        frames = frames_from_folder(args.dir, args.sequences, args.length)
    else:
        distances = [float(x) for x in args.distances.split(",") if x.strip()]
        if not distances or any(d <= 0 for d in distances):
            raise ValueError(f"--distances must be positive metres separated by commas, got {args.distances!r}")
        frames = render_frames(args.scenario, args.size, distances, args.length)
    figures = run_bench(frames, _load_params(args.params), repeat=args.repeat, threads=args.threads)
    print_report(frames, figures)
    return 0


def register(subparsers):
    """Add this stage's commands to the visland parser.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        ``visland``'s commands (:func:`visland.cli.build_parser`), to which ``detect`` is added.
    """
    from visland.cli import add_frame_source_arguments
    p = subparsers.add_parser(
        "detect", help="detect the runway in a frame folder; write measurements.csv",
        description="Detect the runway (edges, centre line, threshold and far corners, d_F and the heading "
                    "deviation) in every frame of a folder in the SPEC contract (frames/, frames.csv or --fps, "
                    "telemetry.csv for the horizon (without it the horizon is read off the frames), camera.json). Each frame is tracked from the previous "
                    "detection in a region of interest; the whole frame is searched to acquire or re-acquire. "
                    "Writes measurements.csv in the labels schema with source=detection, found, reason and "
                    "confidence; unusable frames are rows with found=0 and the reason.")
    p.add_argument("dir", metavar="DIR", help="frame folder (frames/, telemetry.csv, camera.json, ...)")
    p.add_argument("--out", required=True, metavar="FILE", help="measurements CSV to write (refused if it exists)")
    p.add_argument("--params", metavar="FILE", help="detector parameters, JSON or TOML (visland.detection.DetectorParams)")
    add_frame_source_arguments(p, telemetry_note="without one, roll and pitch are read off each frame")
    p.add_argument("--max-frames", type=int, default=None, metavar="N", help="only the first N frames")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    p.add_argument("--force", action="store_true", help="replace an existing output file")
    p.set_defaults(func=_cmd_detect)


def register_bench(bench_subparsers):
    """Add ``visland bench detect``.

    Parameters
    ----------
    bench_subparsers : argparse._SubParsersAction
        Gains ``detect`` (acquisition and tracking speed).
    """
    p = bench_subparsers.add_parser(
        "detect", help="detection speed: whole-frame acquisition and region-of-interest tracking",
        description="Time the detector on full-size frames: acquisition (no previous detection) on every "
                    "frame, and tracking along runs of consecutive frames. Frames come from --dir or are "
                    "rendered in memory along --scenario. Medians of wall time; ends with one JSON line.")
    p.add_argument("--dir", metavar="DIR", help="frame folder to read frames from instead of rendering")
    p.add_argument("--scenario", default="thesis-1", help="scenario to render (default thesis-1)")
    p.add_argument("--size", type=int, default=2048, metavar="PX", help="rendered image size (default 2048)")
    p.add_argument("--distances", default="4500,2000,700,300", metavar="M,M,...",
                   help="distances from the threshold of the rendered runs (default 4500,2000,700,300)")
    p.add_argument("--length", type=int, default=5, metavar="N", help="consecutive frames per run (default 5)")
    p.add_argument("--sequences", type=int, default=4, metavar="N", help="runs taken from --dir (default 4)")
    p.add_argument("--repeat", type=int, default=3, metavar="N", help="timing passes (default 3)")
    p.add_argument("--params", metavar="FILE", help="detector parameters, JSON or TOML")
    p.add_argument("--threads", type=int, default=None, metavar="N",
                   help="OpenCV threads while timing (default OpenCV's own); with 1, the CPU-time figures "
                        "are the least disturbed by other load on a shared machine")
    p.set_defaults(func=_cmd_bench)
