"""The ``visland`` command line: one entry point, a subcommand per job.

Core commands (``scenarios``, ``simulate``) live here. Each stage registers its own commands
from a light module ``visland.<stage>.cli`` exposing ``register(subparsers)`` and, for
benchmarks, ``register_bench(bench_subparsers)``; those modules import their heavy
dependencies (OpenGL, OpenCV, Dask) only inside the command functions, so ``visland simulate``
starts fast. A command function takes the parsed arguments and returns an exit code; a
``ValueError`` becomes one clear line on stderr and exit status 2.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from visland import __version__

#: Stage CLI modules, in the order their commands are listed.
STAGE_CLI_MODULES = (
    "visland.render.cli",
    "visland.detection.cli",
    "visland.tracking.cli",
    "visland.estimation.cli",
    "visland.datasets.generate_cli",
    "visland.datasets.cli",
    "visland.footage_cli",
)


def _cmd_scenarios(args) -> int:
    from visland.scenarios import BUILTIN_SCENARIOS
    print(f"{'name':15s} {'dX m':>7s} {'dY m':>6s} {'dGS m':>6s} {'dpsi':>5s} {'gamma':>5s}  description")
    for scenario in BUILTIN_SCENARIOS.values():
        print(f"{scenario.name:15s} {scenario.dx_m:7.0f} {scenario.dy_m:6.0f} {scenario.dgs_m:6.0f} "
              f"{scenario.dpsi_deg:5.0f} {scenario.gamma_deg:5.0f}  {scenario.description}")
    print("\nAlso: any TOML scenario file (README, Commands, 'Scenarios and simulation': the fields).")
    return 0


def _angles(text: str):
    """One number, or three comma-separated numbers."""
    parts = [p for p in text.split(",") if p.strip()]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number or three comma-separated numbers, got {text!r}") from None
    if len(values) == 1:
        return values[0]
    if len(values) == 3:
        return tuple(values)
    raise argparse.ArgumentTypeError(f"expected one or three numbers, got {len(values)}")


def add_simulation_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments shared by ``simulate`` and the commands that simulate before rendering.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The subcommand's parser: gains ``--scenario``, ``--out``, ``--fps``, ``--seed``,
        ``--calibration-error``, ``--slope``, ``--velocity-bias``, ``--imu-noise``,
        ``--airspeed-noise``, ``--no-airspeed`` and ``--force``.
    """
    parser.add_argument("--scenario", required=True, metavar="NAME|FILE",
                        help="built-in scenario name (see 'visland scenarios') or a TOML scenario file")
    parser.add_argument("--out", required=True, metavar="DIR", help="output folder (must not exist unless --force)")
    parser.add_argument("--fps", type=float, default=25.0, help="camera frame rate in Hz (default 25)")
    parser.add_argument("--seed", type=int, default=0, help="seed of every random generator (default 0)")
    parser.add_argument("--calibration-error", type=_angles, default=0.0, metavar="DEG|R,P,Y",
                        help="camera mounting error in degrees: one value added to roll, pitch and yaw (thesis "
                             "5.2.2.2: 0.3, 0.5, 1), or three 'roll,pitch,yaw'")
    parser.add_argument("--slope", type=float, default=None, metavar="PCT",
                        help="runway longitudinal slope in percent, uphill positive (overrides the scenario's "
                             "[runway] slope_pct; at most +-2)")
    parser.add_argument("--velocity-bias", type=float, default=0.0, metavar="FRACTION",
                        help="constant relative IMU velocity bias, e.g. 0.05 for 5 %% (thesis 5.2.2.3)")
    parser.add_argument("--imu-noise", type=float, default=0.0, metavar="SCALE",
                        help="IMU white noise: SCALE x (0.05 deg attitude, 0.1 deg/s rates, 0.1 m/s velocity)")
    parser.add_argument("--airspeed-noise", type=float, default=0.5, metavar="MPS",
                        help="white noise of the true airspeed written as telemetry column tas_mps (default 0.5 m/s)")
    parser.add_argument("--no-airspeed", action="store_true",
                        help="leave the true airspeed (tas_mps) out of the telemetry: no wind estimation")
    parser.add_argument("--force", action="store_true", help="replace an existing output folder")


#: ``--time-offset``'s help, shared by detect, track, process and estimate.
TIME_OFFSET_HELP = ("seconds added to the telemetry's times to put them on the frames' clock; a camera whose frames "
                    "are stamped S seconds after their exposure (a camera-to-IMU delay) is --time-offset S (default 0)")


def add_frame_source_arguments(parser: argparse.ArgumentParser, telemetry_note: str = "") -> None:
    """Where a recording's files are when not in its folder: the options of ``detect``, ``track``
    and ``process``, declared once here so that they read and behave alike.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The subcommand's parser: gains ``--camera``, ``--telemetry``, ``--frames-csv``, ``--fps``
        and ``--time-offset`` (attributes ``camera``, ``telemetry``, ``frames_csv``, ``fps``,
        ``time_offset``), passed on to :class:`visland.folder.FrameFolder` or
        :func:`visland.datasets.sources.open_source`.
    telemetry_note : str, optional
        What the command does without telemetry, appended to ``--telemetry``'s help.
    """
    parser.add_argument("--camera", metavar="FILE",
                        help="camera.json to use instead of the input's own (in its folder, or beside a video)")
    parser.add_argument("--telemetry", metavar="FILE",
                        help="telemetry.csv to use instead of the input's own (in its folder, or beside a video)"
                             + (f"; {telemetry_note}" if telemetry_note else ""))
    parser.add_argument("--frames-csv", metavar="FILE",
                        help="frame,t_s times to use instead of the folder's frames.csv (without either: --fps)")
    parser.add_argument("--fps", type=float, default=None,
                        help="frame rate in Hz when there is no frames.csv (default 25, or the video's own)")
    parser.add_argument("--time-offset", type=float, default=0.0, metavar="S", help=TIME_OFFSET_HELP)


def scenario_from_args(args):
    """The scenario of ``--scenario`` with the runway options (``--slope``) applied.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments of a command with :func:`add_simulation_arguments`.

    Returns
    -------
    visland.scenarios.Scenario

    Raises
    ------
    ValueError
        An unknown scenario or a slope outside +-2 % (naming ``--slope``).
    """
    from dataclasses import replace
    from visland.scenarios import resolve_scenario, with_runway
    scenario = resolve_scenario(args.scenario)
    if getattr(args, "slope", None) is not None:
        try:
            runway = replace(scenario.runway, slope_pct=args.slope)
        except ValueError as error:
            raise ValueError(f"--slope: {error}") from None
        scenario = with_runway(scenario, runway)
    return scenario


def simulation_options_from_args(args, camera=None):
    """Build :class:`visland.simulate.SimulationOptions` from parsed arguments.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments of a command with :func:`add_simulation_arguments` (``--pixel-noise``
        too when the command has it).
    camera : visland.camera.CameraModel, optional
        The camera to simulate (default: :meth:`CameraModel.default`, the SPEC 2048 px camera).

    Returns
    -------
    visland.simulate.SimulationOptions

    Raises
    ------
    ValueError
        A negative ``--imu-noise``, or an IMU parameter out of range (naming it).
    """
    from visland.camera import CameraModel
    from visland.sensors import ImuParams
    from visland.simulate import SimulationOptions
    if args.imu_noise < 0:
        raise ValueError(f"--imu-noise must be non-negative, got {args.imu_noise}")
    imu = ImuParams(velocity_bias_fraction=args.velocity_bias, velocity_noise_mps=0.1 * args.imu_noise,
                    attitude_noise_deg=0.05 * args.imu_noise, rate_noise_dps=0.1 * args.imu_noise,
                    seed=args.seed, airspeed=not getattr(args, "no_airspeed", False),
                    airspeed_noise_mps=getattr(args, "airspeed_noise", 0.5))
    return SimulationOptions(fps=args.fps, camera=camera or CameraModel.default(),
                             pixel_noise_px=getattr(args, "pixel_noise", 0.0),
                             calibration_error_deg=args.calibration_error, imu=imu, seed=args.seed)


def _cmd_telemetry(args) -> int:
    from pathlib import Path
    from visland.telemetry_map import convert_telemetry
    out = Path(args.out)
    if out.exists() and not args.force:
        raise ValueError(f"{out}: output file exists; choose another --out or pass --force to replace it")
    n = convert_telemetry(args.csv, args.map, out)
    print(f"wrote {out}: {n} rows in the SPEC columns")
    return 0


def _cmd_simulate(args) -> int:
    from visland.simulate import run_simulation, summary_lines, write_simulation
    scenario = scenario_from_args(args)
    options = simulation_options_from_args(args)
    result = run_simulation(scenario, options)
    write_simulation(result, args.out, force=args.force)
    for line in summary_lines(result):
        print(line)
    print(f"wrote {args.out}/: telemetry.csv truth.csv labels.csv camera.json runway.json manifest.json")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The ``visland`` parser: the core commands, then each stage's (:data:`STAGE_CLI_MODULES`).

    Returns
    -------
    argparse.ArgumentParser
        Every subcommand sets ``func(args) -> int``. Building it imports only the light stage
        ``cli`` modules (no NumPy, OpenCV or OpenGL: ``tests/core/test_exports.py``).
    """
    parser = argparse.ArgumentParser(
        prog="visland",
        description="Vision-based landing on unknown runways: simulate, render, detect, track, estimate.")
    parser.add_argument("--version", action="version", version=f"visland {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    p = sub.add_parser("scenarios", help="list the built-in scenarios")
    p.set_defaults(func=_cmd_scenarios)

    p = sub.add_parser("simulate", help="fly a scenario; write telemetry, truth and ideal labels (no images)")
    add_simulation_arguments(p)
    p.add_argument("--pixel-noise", type=float, default=0.0, metavar="PX",
                   help="white Gaussian noise on the corner pixels (thesis 5.2.2.1: 1 or 5 px)")
    p.set_defaults(func=_cmd_simulate)

    p = sub.add_parser("telemetry", help="convert a telemetry CSV with other column names and units to the SPEC one",
                       description="Write the SPEC telemetry.csv from a CSV with other column names and units "
                                   "(radians, knots, feet per minute, milliseconds, an up velocity...) through a "
                                   "small TOML column map (see README, 'Telemetry as people have it').")
    p.add_argument("csv", metavar="CSV", help="the telemetry file as recorded")
    p.add_argument("--map", required=True, metavar="TOML", help="column map: [columns] spec = { column, unit, sign }")
    p.add_argument("--out", required=True, metavar="FILE", help="telemetry.csv to write (refused if it exists)")
    p.add_argument("--force", action="store_true", help="replace an existing output file")
    p.set_defaults(func=_cmd_telemetry)

    bench = sub.add_parser("bench", help="time a stage: render, detect, track or estimate")
    bench_sub = bench.add_subparsers(dest="target", metavar="TARGET")
    bench_sub.required = True

    for module_name in STAGE_CLI_MODULES:
        module = importlib.import_module(module_name)
        module.register(sub)
        if hasattr(module, "register_bench"):
            module.register_bench(bench_sub)
    return parser


def main(argv=None) -> int:
    """Run the ``visland`` command (the console script).

    Parameters
    ----------
    argv : list of str, optional
        The arguments after the program name (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status: the command's (0 on success), 2 for a ``ValueError`` (printed as one line
        on stderr naming the command), 130 when interrupted.
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except ValueError as error:
        print(f"visland {args.command}: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"visland {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
