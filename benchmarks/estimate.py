"""Time every observer on a 100 s, 50 Hz approach (the same as ``visland bench estimate``).

Usage::

    .venv/bin/python benchmarks/estimate.py [--repeat N] [--observer NAME ...]

Prints a table and ends with one JSON line of per-observer timings (median of N runs). The
target is 0.5 s of ``Observer.step`` time per 100 s of flight (about 100 us per step).
"""
import argparse
import json
import sys

from visland.estimation.bench import bench_estimate


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--observer", nargs="+", default=None)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    figures = bench_estimate(args.observer, repeat=args.repeat, seed=args.seed)
    print(json.dumps(figures))
    return 0 if figures["all_ok"] else 1


if __name__ == "__main__":
    sys.exit(main())
