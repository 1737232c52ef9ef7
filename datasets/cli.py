"""Command-line registration of the visland.datasets stage: ``process``, ``compare``,
``campaign`` and ``demo`` (light: every heavy import happens inside the command)."""
from __future__ import annotations

from visland.estimation.cli import OBSERVER_HELP as _NAMES     # light: no heavy imports there

OBSERVER_HELP = f"observer names ({_NAMES}; default all)"


def _observers(names):
    from visland.estimation.cli import _expand_observers
    return _expand_observers(names or ["all"])


def _cmd_process(args) -> int:
    from visland.datasets.process import ProcessOptions, process_input
    options = ProcessOptions(source=args.source, observers=_observers(args.observer), camera=args.camera,
                             telemetry=args.telemetry, frames_csv=args.frames_csv, fps=args.fps,
                             initial_height_m=args.initial_height, initial_error=args.initial_error,
                             init=args.init, report=not args.no_report, quiet=args.quiet, params_file=args.params,
                             time_offset_s=args.time_offset, estimate_offset=args.estimate_offset,
                             self_calibration=args.self_calibration,
                             windows=args.windows)
    if len(args.input) > 1:
        for flag, value in (("--telemetry", args.telemetry), ("--camera", args.camera), ("--frames-csv", args.frames_csv)):
            if value:
                raise ValueError(f"{flag} names one file, but a batch of {len(args.input)} inputs takes each input's own")
    if len(args.input) == 1:
        if args.workers != 1 or args.scheduler:
            raise ValueError("--workers and --scheduler spread a batch of several inputs; one input runs here")
        process_input(args.input[0], args.out, options, force=args.force)
        return 0
    from visland.datasets.batch import process_batch
    index = process_batch(args.input, args.out, options, force=args.force, workers=args.workers,
                          scheduler=args.scheduler)
    return 0 if index["done"] else 2


def _cmd_compare(args) -> int:
    import json
    from visland.datasets.compare import compare_runs
    summary = compare_runs(args.runs, args.out)
    print(json.dumps(_headline(summary)))
    return 0


def _headline(summary: dict) -> dict:
    """Best observer per source by |mean| + std of the dH error at 100 ft."""
    import math
    out = {}
    for source, quantities in summary.items():
        best, score = None, math.inf
        for observer, values in quantities.get("dH", {}).items():
            mean, std = values.get("mean_err_100ft_m"), values.get("std_err_100ft_m")
            if mean is None or std is None or not (math.isfinite(mean) and math.isfinite(std)):
                continue
            if abs(mean) + std < score:
                best, score = observer, abs(mean) + std
        if best is not None:
            entry = {"best_observer": best}
            for quantity in ("dH", "dY", "dX"):
                values = quantities.get(quantity, {}).get(best, {})
                entry[f"{quantity}_mean_100ft_m"] = values.get("mean_err_100ft_m")
                entry[f"{quantity}_std_100ft_m"] = values.get("std_err_100ft_m")
            out[source] = entry
    from visland.contracts import json_ready
    return json_ready(out)                 # NaN (dX from lines) as null: valid JSON


def _cmd_campaign(args) -> int:
    import json
    from visland.datasets.campaign import CampaignOptions, parse_scenario_list, run_campaign
    options = CampaignOptions(scenarios=tuple(parse_scenario_list(args.scenarios)), size=args.size, fps=args.fps,
                              sources=tuple(dict.fromkeys(args.sources)), observers=_observers(args.observer),
                              seed=args.seed, workers=args.workers, scheduler=args.scheduler,
                              prune_frames=args.prune_frames, png_compression=args.png_compression)
    summary = run_campaign(options, args.out, force=args.force)
    print(json.dumps(_headline(summary)))
    return 0


def _cmd_demo(args) -> int:
    """The README's main job: a short campaign on one approach, then where to look."""
    import json
    from visland.datasets.campaign import CampaignOptions, run_campaign
    options = CampaignOptions(scenarios=(args.scenario,), size=args.size, fps=args.fps,
                              sources=("detection", "tracking"), observers=_observers(["all"]),
                              seed=0, workers=args.workers, prune_frames=not args.keep_frames,
                              png_compression=0)
    print(f"visland demo: {args.scenario} rendered at {args.size}x{args.size}, {args.fps:g} Hz; runway detection and "
          f"point tracking; every observer. Output: {args.out}/"
          + ("" if args.keep_frames else " (frames deleted once processed; --keep-frames keeps them)"))
    summary = run_campaign(options, args.out, force=args.force)
    print(json.dumps(_headline(summary)))
    return 0


def _cmd_fly(args) -> int:
    import json
    from visland.contracts import json_ready
    from visland.datasets.fly import FlyOptions, fly, monte_carlo
    from visland.scenarios import resolve_scenario
    options = FlyOptions(observer=args.observer, measure=args.measure, pixel_noise_px=args.pixel_noise, size=args.size,
                         truth_guided=args.truth_guided, flare_height_source=args.flare_height_source,
                         initial_height_m=args.initial_height, seed=args.seed,
                         calibration_error_deg=(0.0, args.pitch_mount_error, 0.0),
                         detection_lost_below_ft=args.lose_runway_below, frozen_frames_at_ft=args.freeze_at,
                         fps=args.fps)
    if args.monte_carlo:
        sources = args.sources.split(",") if args.sources else None
        summary = monte_carlo(args.monte_carlo, options, args.out, echo=print, sources=sources,
                              scheduler=args.scheduler)
        print(json.dumps(json_ready(summary)))
        return 0
    result = fly(resolve_scenario(args.scenario), options)
    result.pop("trace")          # per-frame detail, kept in --monte-carlo's runs/*.json only
    if result["envelope"]["report"]:
        print(result["envelope"]["report"])
    print(json.dumps(json_ready(result)))
    return 0


def register(subparsers):
    """Add this stage's commands to the visland parser.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        Gains ``process``, ``compare``, ``campaign``, ``demo`` and ``fly``.
    """
    from visland.cli import add_frame_source_arguments
    from visland.estimation.cli import add_initial_guess_arguments
    p = subparsers.add_parser(
        "fly", help="closed loop: the autopilot flies on the vision estimates, flares and lands (one JSON line)",
        description="Fly a scenario with the ILS laws fed by an observer's estimates (dY, dGS, dpsi) instead of the "
                    "truth: each frame is measured from the true state (simulated features with pixel noise, or a "
                    "rendered frame and runway detection), the observer steps at 50 Hz, a flare law and main-gear "
                    "touchdown end the run, and a monitor decides at 200 and 100 ft to continue or go around. "
                    "Ends with one JSON line (touchdown_x_m, touchdown_y_m, sink_rate_mps, go_around, "
                    "go_around_reason, dh_err_100ft_m, wall_s, ...).")
    p.add_argument("--scenario", default="thesis-3", metavar="NAME|FILE", help="scenario (default thesis-3)")
    p.add_argument("--observer", default="kf-2p", help="two-point observer that guides (default kf-2p)")
    p.add_argument("--measure", default="simulated", choices=("simulated", "detection"),
                   help="simulated: exact features plus --pixel-noise (fast); detection: rendered frames")
    p.add_argument("--pixel-noise", type=float, default=1.0, metavar="PX", help="corner noise in simulated mode (1)")
    p.add_argument("--size", type=int, default=2048, metavar="PX", help="image size (default 2048)")
    p.add_argument("--truth-guided", action="store_true", help="fly the same case on the truth (the baseline)")
    p.add_argument("--flare-height-source", default="vision", choices=("vision", "radio"),
                   help="height the flare law reads: the vision estimate, or a radio altimeter below 50 ft")
    p.add_argument("--initial-height", type=float, default=None, metavar="M",
                   help="the observers' initial height guess (default: the true height + 20 %%)")
    p.add_argument("--seed", type=int, default=0, help="seed of the pixel noise and the scene")
    p.add_argument("--pitch-mount-error", type=float, default=0.0, metavar="DEG",
                   help="fault: camera pitch mounting error the estimator does not know")
    p.add_argument("--lose-runway-below", type=float, default=None, metavar="FT",
                   help="fault: the runway is not found below this height (fog bank)")
    p.add_argument("--freeze-at", type=float, default=None, metavar="FT",
                   help="fault: the frame stream repeats one frame for 1 s from this height")
    p.add_argument("--monte-carlo", type=int, default=0, metavar="N",
                   help="fly N cases (thesis-1..8 and ecc-1..3 in turn, crosswind 0-15 kt, gusts, noise seeds), "
                        "each on the estimates and on the truth; writes --out DIR/landings.csv and a plot")
    p.add_argument("--sources", default=None, metavar="LIST",
                   help="--monte-carlo: what each case is flown on, comma-separated among detection, simulated, "
                        "truth (default: --measure, simulated when that is not it, and truth)")
    p.add_argument("--scheduler", default=None, metavar="ADDR",
                   help="--monte-carlo: a Dask scheduler address (tcp://host:port); each flight not yet flown is one "
                        "task on that cluster")
    p.add_argument("--fps", type=float, default=25.0, metavar="HZ",
                   help="camera frame rate, a divisor of the 50 Hz flight rate (25, 12.5, 10...; default 25)")
    p.add_argument("--out", default="visland-fly", metavar="DIR", help="output folder of --monte-carlo")
    p.set_defaults(func=_cmd_fly)

    p = subparsers.add_parser(
        "process", help="frames (folder or video) + telemetry -> measurements, estimates, metrics, report",
        description="Process a frame folder (SPEC contract) or a video: measure the runway in every frame "
                    "(detection, tracking, anchored tracking, or the folder's exact labels), run the observers, "
                    "score them against truth.csv when present, and write a self-contained HTML report.")
    p.add_argument("input", metavar="INPUT", nargs="+",
                   help="frame folder (frames/, telemetry.csv, camera.json, ...) or video file; several make a batch: "
                        "one run per input under --out, index.html linking them, and the compare tables")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (refused if it exists, unless --force)")
    add_frame_source_arguments(p)
    p.add_argument("--source", default="detection", metavar="SOURCE",
                   help="how features are measured: detection (default), tracking, anchored (tracking re-anchored on "
                        "detection) or ideal (the folder's exact labels); tracking and anchored may name a template "
                        "update policy, e.g. tracking:every_frame (the thesis's drifting tracker)")
    p.add_argument("--observer", nargs="+", metavar="NAME", help=OBSERVER_HELP)
    p.add_argument("--init", metavar="labels|'u,v;u,v'", default=None,
                   help="tracking designation of the threshold corners (default: labels when present)")
    add_initial_guess_arguments(p)
    p.add_argument("--windows", choices=("detector", "dickmanns-4d"), default="detector",
                   help="detection's search windows: placed by the detector's last detection (default) or by "
                        "dickmanns-4d's prediction of each frame (seed 004; the filter runs beside the detector)")
    p.add_argument("--params", default=None, metavar="FILE", help="observer parameters (TOML or JSON)")
    p.add_argument("--estimate-offset", action="store_true",
                   help="estimate the telemetry-to-frames clock offset from the horizon's roll in the frames")
    p.add_argument("--self-calibration", action="store_true",
                   help="apply the camera mounting's self-calibration from the runway (as 'estimate "
                        "--self-calibration'); without it the estimate is computed and reported only")
    p.add_argument("--no-report", action="store_true", help="skip the HTML report")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--force", action="store_true", help="replace an existing output folder")
    p.add_argument("--workers", type=int, default=1, metavar="N",
                   help="a batch: inputs processed at once in worker processes (default 1: one after the other)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="a batch: run each input as a task on this Dask scheduler, e.g. tcp://127.0.0.1:8786")
    p.set_defaults(func=_cmd_process)

    p = subparsers.add_parser(
        "compare", help="thesis-style tables (Tables 5.14-5.17) across processed runs",
        description="Compare observers and measurement sources across 'visland process' runs: 5 % convergence "
                    "time (the thesis's, sustained until 100 ft, and the strict one to the last frame; "
                    "definitions in compare.md) and errors at 400/200/100 ft on scenario 1, mean and standard deviation at 100 ft over "
                    "all runs, for dH, dY and dX; writes compare.md, compare.json, compare.csv and plots; ends "
                    "with one JSON line.")
    p.add_argument("runs", nargs="+", metavar="RUN", help="output folders of 'visland process'")
    p.add_argument("--out", required=True, metavar="DIR", help="folder for the tables and plots")
    p.set_defaults(func=_cmd_compare)

    p = subparsers.add_parser(
        "campaign", help="generate, process and compare several scenarios in one command (resumable)",
        description="Generate the datasets of several scenarios, process each with the chosen measurement "
                    "sources and every observer, and compare them (thesis Tables 5.14-5.17 form). Resumable: "
                    "run the same command again after an interruption. With --scheduler, frames render and "
                    "runs process on a Dask cluster.")
    p.add_argument("--scenarios", nargs="+", default=["thesis-1..thesis-8"], metavar="NAMES",
                   help="scenario names, ranges such as thesis-1..thesis-8, or TOML files (default thesis-1..thesis-8)")
    p.add_argument("--out", required=True, metavar="DIR", help="campaign folder (resumed if it holds the same campaign)")
    p.add_argument("--size", type=int, default=2048, metavar="PX", help="image size (default 2048)")
    p.add_argument("--fps", type=float, default=25.0, help="frame rate (default 25)")
    p.add_argument("--sources", nargs="+", metavar="SOURCE", default=["detection", "tracking", "anchored"],
                   help="measurement sources (default detection tracking anchored; also ideal, and tracker policies "
                        "such as tracking:every_frame), processed in one decoding pass per scenario")
    p.add_argument("--observer", nargs="+", metavar="NAME", help=OBSERVER_HELP)
    p.add_argument("--seed", type=int, default=0, help="seed of every random generator (default 0)")
    p.add_argument("--workers", type=int, default=2, metavar="N", help="local rendering processes (default 2)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler address, e.g. tcp://127.0.0.1:8786")
    p.add_argument("--prune-frames", action="store_true",
                   help="delete each scenario's images once its runs are written (a 2048 px campaign of eight "
                        "approaches otherwise needs tens of GB)")
    p.add_argument("--png-compression", type=int, default=1, metavar="LEVEL",
                   help="PNG zlib level of the frames, 0-9 (default 1; 0 writes twice as fast, twice as large)")
    p.add_argument("--force", action="store_true", help="reuse a folder holding another campaign")
    p.set_defaults(func=_cmd_campaign)

    p = subparsers.add_parser(
        "demo", help="the README's main job: one approach rendered, measured, estimated and compared",
        description="Run a short campaign on one approach (render, detect, track, every observer, compare) and "
                    "print where the tables and the HTML reports are. Resumable like 'campaign'.")
    p.add_argument("--out", default="visland-demo", metavar="DIR", help="output folder (default ./visland-demo)")
    p.add_argument("--scenario", default="thesis-3", metavar="NAME",
                   help="scenario (default thesis-3: thesis Table 5.2 No.3, 4 km out, 51 s)")
    p.add_argument("--size", type=int, default=2048, metavar="PX", help="image size (default 2048)")
    p.add_argument("--keep-frames", action="store_true",
                   help="keep the rendered frames (16 GB at 2048 px) instead of deleting them once processed")
    p.add_argument("--fps", type=float, default=25.0, help="frame rate (default 25)")
    p.add_argument("--workers", type=int, default=2, metavar="N", help="local rendering processes (default 2)")
    p.add_argument("--force", action="store_true", help="reuse a folder holding another campaign")
    p.set_defaults(func=_cmd_demo)
