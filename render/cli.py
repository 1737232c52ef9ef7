"""Command-line registration of the visland.render stage (light: no heavy imports here).

``visland bench render`` times the renderer (see :mod:`visland.render.bench`). Datasets are
made by ``visland generate`` (:mod:`visland.datasets.generate_cli`).
"""


def register(subparsers):
    """The render stage adds no top-level command (``generate`` lives in visland.datasets).

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        Left as it is: frames are rendered by ``visland generate`` (:mod:`visland.datasets`).
    """


def register_bench(bench_subparsers):
    """Add ``visland bench render``.

    Parameters
    ----------
    bench_subparsers : argparse._SubParsersAction
        The targets of ``visland bench``, to which ``render`` is added.
    """
    p = bench_subparsers.add_parser(
        "render", help="time the renderer: seconds per frame with readback, with PNG writing, per quality option")
    p.add_argument("--size", type=int, default=2048, help="square image size in pixels (default 2048)")
    p.add_argument("--frames", type=int, default=9, help="frames per configuration (default 9)")
    p.add_argument("--png-compression", type=int, default=1, help="PNG zlib level of the write timing (default 1)")
    p.add_argument("--no-options", action="store_true", help="time the default only (skip the quality options)")
    p.set_defaults(func=_cmd_bench_render)


def _cmd_bench_render(args) -> int:
    from .bench import run_render_bench
    if not 64 <= args.size <= 4096:
        raise ValueError(f"--size must lie in [64, 4096] px, got {args.size}")
    if not 3 <= args.frames <= 200:
        raise ValueError(f"--frames must lie in [3, 200], got {args.frames}")
    if not 0 <= args.png_compression <= 9:
        raise ValueError(f"--png-compression must lie in [0, 9], got {args.png_compression}")
    run_render_bench(args.size, args.frames, args.png_compression, variants=not args.no_options)
    return 0
