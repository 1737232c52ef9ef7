"""Height error of the observers fed by tracked corners (thesis Table 5.14, with visland's tracker).

Thesis 5.3.3 feeds the threshold corners P', P'' from its tracker ("Memo") to the two-point
observers and finds the estimated height off by about 15 m at 100 ft (Table 5.14), because
the tracked points drift. This script does the same with the corners tracked by
``benchmarks/track_drift.py`` (its per-scenario ``.npz`` holds the tracked positions):

1. write the simulation files of the same scenario (telemetry, truth, labels, camera:
   :func:`visland.simulate.run_simulation`, the same flight the frames were rendered along);
2. write one ``measurements.csv`` per tracker from the tracked threshold corners (SPEC
   measurement schema; frames where a corner was not measured, and frames after 100 ft where
   tracking stopped, are rows with ``found`` 0 and empty cells: the observers coast);
3. run ``visland estimate DIR --measurements FILE --observer points`` and read
   ``metrics.json``: dH - estimate at 400, 200 and 100 ft, per observer;
4. print the table (and the labels, i.e. perfect corners, for reference) and a JSON line.

Usage::

    python benchmarks/track_drift.py --out /tmp/tracking/drift_full        # first
    python benchmarks/track_height.py --drift /tmp/tracking/drift_full --trackers pure,anchored
"""
from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
from pathlib import Path

import numpy as np

OBSERVERS = ("oj-2p", "ii-2p", "cccs-2p", "ccpi-hg-2p", "ccpi-hosm-2p", "cccj-2p", "kf-2p")
METRICS = ("err_400ft_m", "err_200ft_m", "err_100ft_m")


def write_measurements(path: Path, times_s, uv: np.ndarray, source: str) -> None:
    """``measurements.csv`` from tracked corners ``uv (m, 4, 2)`` (m <= len(times_s)), CORNER_NAMES order.

    A frame is found when both threshold corners were measured; the runway-end corners, when
    tracked, let the estimator place the vanishing point (heading) without d_F.
    """
    from visland.runway import CORNER_NAMES
    from visland.contracts import MEASUREMENT_COLUMNS, write_csv
    n = len(times_s)
    columns = {c: [np.nan] * n for c in MEASUREMENT_COLUMNS}
    columns["frame"] = list(range(n))
    columns["t_s"] = list(times_s)
    columns["source"] = [source] * n
    columns["found"] = [0] * n
    columns["reason"] = ["not tracked (below 100 ft)"] * n
    for k in range(len(uv)):
        ok = np.all(np.isfinite(uv[k]), axis=1)
        for i, name in enumerate(CORNER_NAMES):
            if ok[i]:
                columns[f"{name}_u_px"][k], columns[f"{name}_v_px"][k] = uv[k, i]
            columns[f"{name}_visible"][k] = int(ok[i])
        columns["found"][k] = int(ok[:2].all())
        columns["reason"][k] = "" if ok[:2].all() else "threshold corner not measured"
        columns["confidence"][k] = 1.0 if ok[:2].all() else np.nan
    write_csv(path, columns, MEASUREMENT_COLUMNS)


def estimate(folder: Path, measurements: str, out: Path, quiet: bool) -> dict:
    from visland.cli import main
    out.parent.mkdir(parents=True, exist_ok=True)
    args = ["estimate", str(folder), "--measurements", measurements, "--observer", *OBSERVERS, "--out", str(out)]
    sink = io.StringIO()
    with contextlib.redirect_stdout(sink) if quiet else contextlib.nullcontext():
        code = main(args)
    if code:
        raise RuntimeError(f"visland estimate failed with status {code}: {' '.join(args)}")
    return json.loads((out.parent / "metrics.json").read_text())["observers"]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--drift", default="/tmp/tracking/drift_full", help="track_drift.py output folder")
    parser.add_argument("--scenarios", default=None, help="default: every scenario done in --drift")
    parser.add_argument("--trackers", default="pure,every_frame,anchored,anchored_labels")
    parser.add_argument("--out", default="/tmp/tracking/height")
    parser.add_argument("--verbose", action="store_true")
    args = parser.parse_args(argv)
    from visland.scenarios import get_scenario
    from visland.simulate import SimulationOptions, run_simulation, write_simulation_files
    from visland.camera import CameraModel
    drift = Path(args.drift)
    scenarios = ([s.strip() for s in args.scenarios.split(",")] if args.scenarios
                 else sorted(p.stem for p in drift.glob("thesis-*.npz")))
    trackers = [t.strip() for t in args.trackers.split(",") if t.strip()]
    out = Path(args.out)
    table = {}
    for name in scenarios:
        data = np.load(drift / f"{name}.npz")
        folder = out / name
        folder.mkdir(parents=True, exist_ok=True)
        result = run_simulation(get_scenario(name), SimulationOptions(camera=CameraModel.default(2048)))
        write_simulation_files(result, folder)
        times = result.frames.t_s
        table[name] = {"labels": {o: [m[k] for k in METRICS]
                                  for o, m in estimate(folder, "ideal", folder / "labels" / "estimates.csv",
                                                       not args.verbose).items()}}
        for tracker in trackers:
            if f"uv_{tracker}" not in data:
                continue
            (folder / tracker).mkdir(exist_ok=True)
            path = folder / tracker / "measurements.csv"
            write_measurements(path, times, data[f"uv_{tracker}"], tracker)
            metrics = estimate(folder, str(path), folder / tracker / "estimates.csv", not args.verbose)
            table[name][tracker] = {o: [m[k] for k in METRICS] for o, m in metrics.items()}
    print("dH - estimated dH (m) at 400 / 200 / 100 ft, two-point observers fed by the tracked threshold corners")
    for name, rows in table.items():
        print(f"\n{name}")
        print(f"  {'measurements':16s} " + " ".join(f"{o:>20s}" for o in OBSERVERS))
        for source, by_observer in rows.items():
            cells = []
            for o in OBSERVERS:
                values = by_observer.get(o)
                cells.append(f"{'/'.join('-' if v is None else f'{v:.1f}' for v in values):>20s}" if values
                             else f"{'':>20s}")
            print(f"  {source:16s} " + " ".join(cells))
    print(json.dumps({"benchmark": "track_height", "metric": "dH - estimate (m) at 400/200/100 ft",
                      "observers": OBSERVERS, "table": table}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
