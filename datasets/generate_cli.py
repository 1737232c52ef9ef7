"""``visland generate`` command registration (light: OpenGL, OpenCV and Dask load inside the command)."""
from __future__ import annotations

import argparse

from visland.render.params import LIGHTING, MARKINGS, SURROUNDINGS, TAXIWAYS


def _positive_int(text):
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None


def register(subparsers) -> None:
    """Add ``generate`` to the visland parser.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The parser's commands; ``generate`` is added with the simulation options of
        :func:`visland.cli.add_simulation_arguments` and the scene options.
    """
    from visland.cli import add_simulation_arguments
    p = subparsers.add_parser(
        "generate", help="simulate, render every frame and write a dataset (frames + labels + telemetry)",
        description="Fly a scenario, render what the nose camera sees at each frame and write a SPEC dataset: "
                    "frames/, frames.csv, labels.csv, telemetry.csv, truth.csv, camera.json, runway.json, "
                    "manifest.json (per-frame SHA-256). Resumable: run the same command again after an "
                    "interruption; a folder from another job is refused.")
    add_simulation_arguments(p)
    p.add_argument("--size", type=_positive_int, default=2048, metavar="PX",
                   help="square image size in pixels, 64-4096 (default 2048; the SPEC camera scaled)")
    p.add_argument("--workers", type=_positive_int, default=1, metavar="N",
                   help="local rendering processes, 1-64 (default 1)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="render on an existing Dask distributed cluster, e.g. tcp://127.0.0.1:8786")
    p.add_argument("--lard", action="store_true", help="also write lard/labels.csv (LARD v2 corner labels)")
    p.add_argument("--runway", metavar="NAME", help="runway size: default, regional, medium, long, wide")
    p.add_argument("--png-compression", type=_positive_int, default=1, metavar="LEVEL",
                   help="PNG zlib level 0-9 (default 1: fastest; 6 saves about 10 %% of disk at 3x the time)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    scene = p.add_argument_group("scene (see visland.render.SceneParams)")
    scene.add_argument("--scene", metavar="FILE", help="scene parameters, JSON or TOML (options below override it)")
    scene.add_argument("--scene-seed", type=_positive_int, metavar="N", help="texture and noise seed (default --seed)")
    scene.add_argument("--surface", choices=("asphalt", "concrete", "patched"))
    scene.add_argument("--marking-wear", type=float, metavar="0..1")
    scene.add_argument("--sun-azimuth", type=float, metavar="DEG", dest="sun_azimuth_deg")
    scene.add_argument("--sun-elevation", type=float, metavar="DEG", dest="sun_elevation_deg")
    scene.add_argument("--visibility", type=float, metavar="M", dest="visibility_m")
    scene.add_argument("--clouds", type=float, metavar="0..1", dest="cloud_cover")
    scene.add_argument("--noise", type=float, metavar="DN", dest="noise_std", help="sensor noise std, 8-bit levels")
    scene.add_argument("--blur", type=float, metavar="PX", dest="blur_sigma_px", help="Gaussian blur sigma")
    scene.add_argument("--msaa", type=int, choices=(0, 2, 4), dest="msaa_samples")
    scene.add_argument("--flat", action="store_true", help="flat colours (white runway on black) for label checks")
    scene.add_argument("--variety", type=_positive_int, metavar="SEED",
                       help="draw the runway size and the whole scene at random from SEED (visland.render.variety); "
                            "the options here still override the draw")
    scene.add_argument("--runway-length", type=float, metavar="M", help="runway length, metres (e.g. 1200-4000)")
    scene.add_argument("--runway-width", type=float, metavar="M", help="runway width, metres (e.g. 23-60)")
    scene.add_argument("--markings", choices=MARKINGS, help="marking set")
    scene.add_argument("--threshold-stripes", type=int, metavar="N", help="threshold stripes, even 4-16 (0: by width)")
    scene.add_argument("--no-side-stripes", action="store_false", dest="side_stripes", default=None,
                       help="no runway side stripes")
    scene.add_argument("--pre-threshold", type=float, metavar="M", dest="pre_threshold_m",
                       help="length of the displaced-threshold pavement or blast pad, metres")
    scene.add_argument("--surroundings", choices=SURROUNDINGS)
    scene.add_argument("--taxiways", choices=TAXIWAYS)
    scene.add_argument("--second-runway", action="store_true", default=None, help="a second, parallel runway")
    scene.add_argument("--lighting", choices=LIGHTING)
    scene.add_argument("--monochrome", action="store_true", default=None, help="grey-level sensor")
    scene.add_argument("--vignetting", type=float, metavar="0..0.6", help="corner light fall-off")
    scene.add_argument("--jpeg", type=int, metavar="QUALITY", dest="jpeg_quality",
                       help="JPEG compression quality 5-100 applied to every frame (0: none)")
    scene.add_argument("--distortion", metavar="K1,K2,P1,P2,K3",
                       help="lens distortion of the camera (OpenCV coefficients, written to camera.json); frames "
                            "are the pinhole render seen through it, labels stay pinhole; write --distortion=-0.1,0,0,0,0 when k1 < 0")
    p.set_defaults(func=cmd_generate)


def scene_from_args(args):
    """SceneParams from ``--scene`` and the individual scene options.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed ``visland generate`` arguments: ``--scene``, ``--flat``, ``--scene-seed`` (else
        ``--seed``), ``--variety`` and each scene option given (None = the file's or default value).

    Returns
    -------
    visland.render.SceneParams
        Validated; a bad value raises ``ValueError`` naming the option.
    """
    from visland.render.params import SceneParams
    base = SceneParams.load(args.scene).to_dict() if args.scene else SceneParams().to_dict()
    if args.flat:
        base.update(SceneParams.flat().to_dict())
    base["seed"] = args.scene_seed if args.scene_seed is not None else (args.seed if not args.scene else base["seed"])
    if getattr(args, "variety", None) is not None:
        from visland.render.variety import draw_variety
        base = draw_variety(args.variety, SceneParams.from_dict(base, source="scene options")).scene.to_dict()
        if args.scene_seed is not None:
            base["seed"] = args.scene_seed
    for name in ("surface", "marking_wear", "sun_azimuth_deg", "sun_elevation_deg", "visibility_m", "cloud_cover",
                 "noise_std", "blur_sigma_px", "msaa_samples", "markings", "threshold_stripes", "side_stripes",
                 "pre_threshold_m", "surroundings", "taxiways", "second_runway", "lighting", "monochrome",
                 "vignetting", "jpeg_quality"):
        value = getattr(args, name, None)
        if value is not None:
            base[name] = value
    return SceneParams.from_dict(base, source="scene options")


def runway_size_from_args(args, runway):
    """Runway length and width: ``--runway-length/--runway-width``, else the ``--variety`` draw, else ``runway``'s.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed ``visland generate`` arguments.
    runway : visland.runway.Runway
        The scenario's runway (the fallback).

    Returns
    -------
    length_m, width_m : float
        Runway length and width in metres.
    """
    length, width = runway.length_m, runway.width_m
    if getattr(args, "variety", None) is not None:
        from visland.render.variety import draw_variety
        drawn = draw_variety(args.variety)
        length, width = drawn.runway_length_m, drawn.runway_width_m
    if getattr(args, "runway_length", None) is not None:
        length = args.runway_length
    if getattr(args, "runway_width", None) is not None:
        width = args.runway_width
    return float(length), float(width)


def cmd_generate(args) -> int:
    """Run ``visland generate``: simulate the scenario, render every frame, write the dataset folder.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed ``visland generate`` arguments (see ``visland generate --help``).

    Returns
    -------
    int
        Exit status, 0 on success (bad input raises ``ValueError``: one line, status 2).
    """
    from visland.camera import CameraModel
    from visland.cli import scenario_from_args, simulation_options_from_args
    from visland.runway import Runway
    from visland.scenarios import with_runway
    from .generate import MAX_SIZE, MAX_WORKERS, MIN_SIZE, GenerateJob, generate_dataset

    if not MIN_SIZE <= args.size <= MAX_SIZE:
        raise ValueError(f"--size must lie in [{MIN_SIZE}, {MAX_SIZE}] px, got {args.size}")
    if not 1.0 <= args.fps <= 50.0:
        raise ValueError(f"--fps must lie in [1, 50] frames per second (the dynamics run at 50 Hz), got {args.fps:g}")
    if not 1 <= args.workers <= MAX_WORKERS:
        raise ValueError(f"--workers must lie in [1, {MAX_WORKERS}], got {args.workers}")
    if not 0 <= args.png_compression <= 9:
        raise ValueError(f"--png-compression must lie in [0, 9], got {args.png_compression}")
    scenario = scenario_from_args(args)
    if args.runway:
        scenario = with_runway(scenario, Runway.named(args.runway, heading_deg=scenario.runway.heading_deg,
                                                      aim_distance_m=scenario.runway.aim_distance_m,
                                                      slope_pct=scenario.runway.slope_pct))
    length, width = runway_size_from_args(args, scenario.runway)
    if (length, width) != (scenario.runway.length_m, scenario.runway.width_m):
        scenario = with_runway(scenario, Runway(length_m=length, width_m=width, heading_deg=scenario.runway.heading_deg,
                                                aim_distance_m=scenario.runway.aim_distance_m,
                                                slope_pct=scenario.runway.slope_pct))
    camera = CameraModel.default(args.size)
    if getattr(args, "distortion", None):
        from dataclasses import replace
        try:
            coefficients = tuple(float(c) for c in args.distortion.split(","))
        except ValueError:
            raise ValueError(f"--distortion must be five numbers k1,k2,p1,p2,k3, got {args.distortion!r}") from None
        if len(coefficients) != 5:
            raise ValueError(f"--distortion must be five numbers k1,k2,p1,p2,k3, got {args.distortion!r}")
        camera = replace(camera, distortion=coefficients)
    options = simulation_options_from_args(args, camera=camera)
    job = GenerateJob(scenario, options, scene_from_args(args), png_compression=args.png_compression, lard=args.lard)
    report = generate_dataset(job, args.out, workers=args.workers, scheduler=args.scheduler, force=args.force,
                              progress=not args.no_progress)
    if report.already_complete:
        print(f"{report.out_dir}: already complete ({report.n_frames} frames); nothing to do")
    else:
        rate = report.rendered / report.seconds if report.seconds > 0 else 0.0
        print(f"wrote {report.out_dir}/: {report.n_frames} frames ({report.rendered} rendered, {report.reused} kept "
              f"from an earlier run) in {report.seconds:.1f} s ({rate:.2f} frames/s), frames.csv labels.csv "
              f"telemetry.csv truth.csv camera.json runway.json manifest.json{' lard/labels.csv' if args.lard else ''}")
    return 0
