"""Command-line registration of the visland.estimation stage (light: no heavy imports here).

Commands: ``visland estimate`` (observers on a folder), ``visland study`` (the seeds' studies)
and the bench target ``visland bench estimate``.
"""
from __future__ import annotations

import json

OBSERVER_HELP = ("two points: oj-2p ii-2p cccs-2p ccpi-hg-2p ccpi-hosm-2p cccj-2p kf-2p; two lines: oj-2l ii-2l "
                 "ccpi-2l cccj-2l ekf-2l; ECC'15: ecc-hg ecc-hosm; seed 004 (4D approach): dickmanns-4d; "
                 "or the groups 'points', 'lines', 'ecc', 'dickmanns', 'all'")
STUDY_NAMES = ("table-5.3", "table-5.4", "table-5.6", "table-5.7", "lines-5px", "table-5.8", "table-5.10", "table-5.12",
               "calibration", "robustness", "ecc", "academic", "dickmanns")


def _expand_observers(names):
    from visland.estimation.registry import (DICKMANNS_OBSERVERS, ECC_OBSERVERS, LINE_OBSERVERS, OBSERVER_NAMES,
                                             POINT_OBSERVERS)
    groups = {"points": POINT_OBSERVERS, "lines": LINE_OBSERVERS, "ecc": ECC_OBSERVERS,
              "dickmanns": DICKMANNS_OBSERVERS, "all": OBSERVER_NAMES}
    out = []
    for name in names:
        for item in groups.get(name, (name,)):
            if item not in out:
                out.append(item)
    return tuple(out)


def _cmd_estimate(args) -> int:
    from pathlib import Path

    from visland.estimation.command import EstimateOptions, estimate_folder
    from visland.userfiles import check_output_file
    # one rule with process, detect and track: nothing is replaced without --force, and that
    # includes the metrics.json written beside the estimates when the folder has truth
    out = check_output_file(args.out, force=args.force)
    metrics = out.parent / "metrics.json"
    if metrics.exists() and not args.force and (Path(args.dir) / "truth.csv").exists():
        raise ValueError(f"{metrics}: exists and would be replaced by the metrics of {out.name}; choose another "
                         "--out folder or pass --force to replace it")
    options = EstimateOptions(observers=_expand_observers(args.observer), measurements=args.measurements,
                              initial_height_m=args.initial_height, initial_error=args.initial_error,
                              aim_distance_m=args.aim_distance, params_file=args.params,
                              self_calibration="apply" if args.self_calibration else "check",
                              time_offset_s=args.time_offset)
    estimate_folder(args.dir, options, args.out)
    return 0


def _cmd_study(args) -> int:
    from visland.estimation.study import run_study
    out = args.out or f"study-{args.name}"
    figures = run_study(args.name, out_dir=out, seed=args.seed, heading=args.heading)
    print(json.dumps(figures, default=str))
    return 0


def _cmd_bench_estimate(args) -> int:
    from visland.estimation.bench import bench_estimate
    observers = _expand_observers(args.observer) if args.observer else None
    figures = bench_estimate(observers, repeat=args.repeat, seed=args.seed)
    print(json.dumps(figures))
    return 0


def add_initial_guess_arguments(parser) -> None:
    """The observers' initial guess, declared once for ``estimate`` and ``process``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The subcommand's parser: gains ``--initial-height`` (attribute ``initial_height``, metres
        above the runway, None by default) and ``--initial-error`` (``initial_error``, a
        fraction, 0.2 by default), checked by the command with
        :func:`visland.estimation.command.check_initial_guess`.
    """
    parser.add_argument("--initial-height", type=float, default=None, metavar="M",
                        help="initial guess of the height above the runway (required without truth.csv)")
    parser.add_argument("--initial-error", type=float, default=0.2, metavar="FRACTION",
                        help="with truth.csv and no --initial-height: start this fraction above the true height "
                             "(default 0.2, the seeds' 20 %%)")


def register(subparsers):
    """Add this stage's commands to the visland parser.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        Gains ``estimate`` and ``study``; each command's ``func(args)`` returns the exit status.
    """
    p = subparsers.add_parser(
        "estimate", help="run observers on a folder's measurements and telemetry; write estimates.csv",
        description="Estimate the aircraft's position relative to the runway from image measurements and "
                    "telemetry with the thesis's observers. Writes estimates.csv (one row per observer per "
                    "frame; coasting=1 where no measurement corrected the frame) and, when DIR/truth.csv "
                    "exists, metrics.json beside it. Neither is replaced without --force.")
    p.add_argument("dir", metavar="DIR", help="folder with telemetry.csv, camera.json (and truth.csv, labels.csv)")
    p.add_argument("--measurements", required=True, metavar="FILE|ideal",
                   help="a measurements.csv, or 'ideal' for the folder's exact labels.csv")
    p.add_argument("--observer", required=True, nargs="+", metavar="NAME", help=OBSERVER_HELP)
    p.add_argument("--out", required=True, metavar="FILE", help="estimates.csv to write")
    add_initial_guess_arguments(p)
    p.add_argument("--aim-distance", type=float, default=320.0, metavar="M",
                   help="aiming point distance past the threshold, for dX (default 320 m)")
    p.add_argument("--params", default=None, metavar="FILE",
                   help="observer parameters, TOML or JSON, one table per observer name")
    p.add_argument("--force", action="store_true", help="replace an existing FILE (and metrics.json beside it)")
    from visland.cli import TIME_OFFSET_HELP
    p.add_argument("--time-offset", type=float, default=0.0, metavar="S", help=TIME_OFFSET_HELP)
    p.add_argument("--self-calibration", action="store_true",
                   help="correct the camera's mounting (pitch, roll, yaw) with its estimate from the runway itself "
                        "(vanishing point and threshold on the inertial horizon, epipolar constraint of the "
                        "threshold corners); the observers start once it has settled. Without it the estimate "
                        "is only reported (run log, metrics.json), and a calibration problem (mounting degrees off) "
                        "is always reported")
    p.set_defaults(func=_cmd_estimate)

    p = subparsers.add_parser(
        "study", help="rerun a seed study (thesis tables, ECC'15, seed 001) beside the seeds' numbers",
        description="Rerun one of the seeds' simulated-measurement studies and print it beside the thesis's "
                    "figures; writes plots and study.json into --out; ends with one JSON line.")
    p.add_argument("name", choices=STUDY_NAMES, metavar="NAME", help=", ".join(STUDY_NAMES))
    p.add_argument("--out", default=None, metavar="DIR", help="folder for plots and study.json (default study-NAME)")
    p.add_argument("--seed", type=int, default=0, help="seed of the noise generators (default 0)")
    p.add_argument("--heading", choices=("dF", "truth"), default="dF",
                   help="heading deviation from the measured d_F (default, as 'visland estimate') or known "
                        "(noise-free d_F, as in the thesis's simulations)")
    p.set_defaults(func=_cmd_study)


def register_bench(bench_subparsers):
    """Add ``visland bench estimate``.

    Parameters
    ----------
    bench_subparsers : argparse._SubParsersAction
        ``visland bench``'s targets; ``estimate`` times every observer.
    """
    p = bench_subparsers.add_parser("estimate", help="time every observer on a 100 s, 50 Hz approach",
                                    description="Time each observer's steps over a 100 s, 50 Hz approach (target "
                                                "0.5 s); ends with one JSON line of per-observer timings.")
    p.add_argument("--observer", nargs="+", default=None, metavar="NAME", help=OBSERVER_HELP + " (default all)")
    p.add_argument("--repeat", type=int, default=5, help="runs per observer; the median is reported (default 5)")
    p.add_argument("--seed", type=int, default=0, help="noise seed (default 0)")
    p.set_defaults(func=_cmd_bench_estimate)
