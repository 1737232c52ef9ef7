"""``visland compare``: tables in the thesis's form across processed runs (thesis Tables 5.14-5.17).

Input: run folders written by ``visland process`` (``run.json``, ``estimates.csv``,
``truth.csv``). For each measurement source (detection, tracking, anchored, ideal) and each
observer:

- on scenario 1 (the run whose scenario is ``thesis-1``; else the first run): the 5 %
  convergence times of dH (the thesis's, sustained until 100 ft, and the stricter one to the end
  of the run) and the errors ``truth - estimate`` of dH, dY and dX when the true height first
  falls to 400, 200 and 100 ft;
- over all runs: the mean and (population) standard deviation of those errors at 100 ft.

Every figure comes from :mod:`visland.estimation.metrics` (the one home of the definitions,
written under the tables), measured from each observer's start as recorded in the run's
``metrics.json``, so ``compare`` and ``metrics.json`` agree (to the rounding of estimates.csv).

Writes ``compare.md`` (the tables), ``compare.json`` (every figure), ``compare.csv`` (tidy:
source, observer, run, quantity, metric, value) and plots into ``--out``, prints the tables,
and ends with one JSON line of the headline figures.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from visland.contracts import atomic_write_text, json_ready, read_estimates, read_truth, write_csv
from visland.userfiles import read_json_object

__all__ = ["RunResult", "load_run", "run_figures", "compare_runs", "QUANTITIES"]

#: (estimate column, truth column, label)
QUANTITIES = (("dh_m", "dh_m", "dH"), ("dy_m", "dy_m", "dY"), ("dx_m", "dx_m", "dX"))


@dataclass
class RunResult:
    """One processed run: its identity and per-observer estimate series at the frames.

    Attributes
    ----------
    path : Path
        The run folder.
    source : str
        Its measurement source (detection, tracking, anchored, ideal).
    scenario : str
        The scenario or input it processed.
    truth : dict of str to ndarray
        ``truth.csv``'s columns (metres, degrees).
    series : dict
        Observer -> arrays ``t_s``, ``dh_m``, ``dy_m``, ``dx_m`` at the frames.
    start_t_s : dict of str to float
        Observer -> its start (metrics.json); absent: the first estimate.
    diverged : dict of str to str
        Observer -> why it was cut off (run.json ``diverged``).
    """

    path: Path
    source: str
    scenario: str
    truth: dict
    series: dict           # observer -> dict of arrays (t_s, dh_m, dy_m, dx_m)
    start_t_s: dict = field(default_factory=dict)   # observer -> its start (metrics.json); absent: first estimate
    diverged: dict = field(default_factory=dict)    # observer -> why it was cut off (run.json "diverged")


def load_run(path) -> RunResult:
    """Read a ``visland process`` output folder (errors name the file).

    Parameters
    ----------
    path : str or Path
        A run folder (run.json, estimates.csv, truth.csv).

    Returns
    -------
    RunResult
    """
    path = Path(path)
    if not path.is_dir():
        raise ValueError(f"{path}: run folder not found")
    info_path = path / "run.json"
    if not info_path.exists():
        raise ValueError(f"{info_path}: not found (is {path} a 'visland process' output folder?)")
    info = read_json_object(info_path, "run description")
    truth_path = path / "truth.csv"
    if not truth_path.exists():
        raise ValueError(f"{truth_path}: not found; comparison needs the run's truth")
    truth = read_truth(truth_path)
    estimates = read_estimates(path / "estimates.csv")
    series = {}
    for observer in dict.fromkeys(estimates["observer"]):
        keep = estimates["observer"] == observer
        data = {k: estimates[k][keep] for k in ("t_s", "dh_m", "dy_m", "dx_m")}
        if len(data["t_s"]) != truth.n_rows or not np.allclose(data["t_s"], truth["t_s"], atol=1e-6):
            raise ValueError(f"{path / 'estimates.csv'}: observer {observer} has {len(data['t_s'])} rows whose times "
                             f"do not match the {truth.n_rows} frames of truth.csv")
        series[observer] = data
    source, scenario = info.get("source"), info.get("scenario")
    if not isinstance(source, str) or not source:
        raise ValueError(f"{info_path}: field 'source' is {json.dumps(source)} (the measurement source that made the "
                         "run, e.g. \"detection\", is required)")
    if scenario is not None and not isinstance(scenario, str):
        raise ValueError(f"{info_path}: field 'scenario' is {json.dumps(scenario)} (a name or null is required)")
    diverged = info.get("diverged") or {}
    if not isinstance(diverged, dict):
        raise ValueError(f"{info_path}: field 'diverged' is {json.dumps(diverged)} (an object mapping observers to "
                         "a sentence is required)")
    return RunResult(path, source, scenario or path.name, dict(truth), series, _observer_starts(path / "metrics.json"),
                     {str(k): str(v) for k, v in diverged.items()})


def _observer_starts(metrics_path: Path) -> dict:
    """``{observer: start_t_s}`` from a run's metrics.json (empty if the file or the entries are absent)."""
    if not metrics_path.exists():
        return {}
    try:
        doc = json.loads(metrics_path.read_text())
    except json.JSONDecodeError as error:
        raise ValueError(f"{metrics_path}: not valid JSON ({error.msg})") from None
    observers = doc.get("observers", {}) if isinstance(doc, dict) else None
    if not isinstance(observers, dict):
        raise ValueError(f"{metrics_path}: 'observers' must map each observer to its metrics "
                         f"(is it a metrics.json written by 'visland estimate'?)")
    starts = {}
    for observer, values in observers.items():
        start = values.get("start_t_s") if isinstance(values, dict) else None
        if start is not None:
            if not isinstance(start, (int, float)) or not math.isfinite(start):
                raise ValueError(f"{metrics_path}: observer {observer}: start_t_s is {start!r} (a finite number of "
                                 f"seconds is required)")
            starts[observer] = float(start)
    return starts


def run_figures(run: RunResult) -> dict:
    """``{observer: {"dH": {conv_time_5pct_s, conv_time_5pct_to_end_s, err_400ft_m, ...}, "dY": {...},
    "dX": {...}}}``, by :mod:`visland.estimation.metrics`.

    Parameters
    ----------
    run : RunResult
        A loaded run.

    Returns
    -------
    dict
    """
    from visland.estimation.metrics import convergence_time_s, errors_at_heights
    out = {}
    t_s, dh_true = run.truth["t_s"], run.truth["dh_m"]
    for observer, data in run.series.items():
        start = run.start_t_s.get(observer)
        figures = {}
        for est_col, truth_col, label in QUANTITIES:
            values = {}
            if label == "dH":
                values["conv_time_5pct_s"] = convergence_time_s(t_s, dh_true, data["dh_m"], start_t_s=start)
                values["conv_time_5pct_to_end_s"] = convergence_time_s(t_s, dh_true, data["dh_m"], start_t_s=start,
                                                                       until_height_m=None)
            values.update(errors_at_heights(dh_true, run.truth[truth_col], data[est_col]))
            figures[label] = values
        out[observer] = figures
    return out


#: The convergence rows of the dH table: (metric key, row label). The thesis's first (its tables' name).
CONVERGENCE_ROWS = (("conv_time_5pct_s", "5 % convergence time (s)"),
                    ("conv_time_5pct_to_end_s", "5 % convergence time to the end of the run (s)"))


def _fmt(value, digits=3):
    return "-" if value is None or not math.isfinite(value) else f"{value:.{digits}f}"


def compare_runs(run_paths, out_dir, echo=print) -> dict:
    """Build the comparison of ``run_paths`` into ``out_dir``; return its figures.

    Parameters
    ----------
    run_paths : sequence of str or Path
        The ``visland process`` run folders.
    out_dir : str or Path
        Where compare.md, compare.json, compare.csv and the plots go.
    echo : callable, default print
        Where the tables go.

    Returns
    -------
    dict
    """
    from visland.estimation.metrics import FT_TO_M, METRIC_DEFINITIONS, METRIC_HEIGHTS_FT, aggregate_at_100ft
    from visland.userfiles import check_output_folder
    out_dir = check_output_folder(out_dir, force=True)         # compare adds its files to a folder
    runs = [load_run(p) for p in run_paths]
    if not runs:
        raise ValueError("give at least one run folder")
    out_dir.mkdir(parents=True, exist_ok=True)
    per_run = [(run, run_figures(run)) for run in runs]
    sources = list(dict.fromkeys(run.source for run in runs))
    tidy = {k: [] for k in ("source", "observer", "run", "scenario", "quantity", "metric", "value")}
    for run, figures in per_run:
        for observer, by_quantity in figures.items():
            for quantity, values in by_quantity.items():
                for metric, value in values.items():
                    for k, v in zip(tidy, (run.source, observer, str(run.path), run.scenario, quantity, metric, value)):
                        tidy[k].append(v)
    write_csv(out_dir / "compare.csv", tidy)

    summary = {}
    md = ["# visland comparison", "", f"{len(runs)} runs: " + ", ".join(f"{r.scenario} ({r.source})" for r in runs), ""]
    for source in sources:
        mine = [(r, f) for r, f in per_run if r.source == source]
        reference = next(((r, f) for r, f in mine if r.scenario == "thesis-1"), mine[0])
        observers = list(dict.fromkeys(o for _, f in mine for o in f))
        summary[source] = {}
        for quantity in ("dH", "dY", "dX"):
            header = ["metric"] + observers
            rows = []
            if quantity == "dH":
                for key, label in CONVERGENCE_ROWS:
                    rows.append([f"{label}, {reference[0].scenario}"]
                                + [reference[1].get(o, {}).get("dH", {}).get(key) for o in observers])
            for h in METRIC_HEIGHTS_FT:
                rows.append([f"error at {h:.0f} ft (m), {reference[0].scenario}"]
                            + [reference[1].get(o, {}).get(quantity, {}).get(f"err_{h:.0f}ft_m") for o in observers])
            means, stds, counts = [], [], []
            for o in observers:
                agg = aggregate_at_100ft(f[o][quantity]["err_100ft_m"] for _, f in mine if o in f)
                means.append(agg["mean_err_100ft_m"])
                stds.append(agg["std_err_100ft_m"])
                counts.append(agg["n_runs"])
            rows.append([f"mean error at 100 ft (m), {len(mine)} runs"] + means)
            rows.append([f"standard deviation at 100 ft (m), {len(mine)} runs"] + stds)
            md.append(f"## {quantity}: {source}")
            md.append("")
            md.append("| " + " | ".join(header) + " |")
            md.append("|" + "---|" * len(header))
            for row in rows:
                md.append("| " + " | ".join([row[0]] + [_fmt(v) for v in row[1:]]) + " |")
            md.append("")
            summary[source][quantity] = {o: {"mean_err_100ft_m": m, "std_err_100ft_m": s, "n_runs": c,
                                             **reference[1].get(o, {}).get(quantity, {})}
                                         for o, m, s, c in zip(observers, means, stds, counts)}
    md.append("Definitions (visland.estimation.metrics; errors are truth - estimate; '-': none):")
    md.append("")
    for key, label in CONVERGENCE_ROWS:
        md.append(f"- {label}: {METRIC_DEFINITIONS[key]}.")
    md.append("- error at h ft: " + METRIC_DEFINITIONS["err_<h>ft_m"].replace("dH - dH_hat", "truth - estimate")
              + "; mean and standard deviation (population) of the 100 ft errors over the runs that have one.")
    notes = _never_low_enough(runs, METRIC_HEIGHTS_FT) + [
        f"Note: in run {run.path} ({run.scenario}, {run.source}) {observer} {why} (its later errors are -)."
        for run in runs for observer, why in run.diverged.items()]
    if notes:
        md[3:3] = notes + [""]
    text = "\n".join(md) + "\n"
    atomic_write_text(out_dir / "compare.md", text)
    atomic_write_text(out_dir / "compare.json", json.dumps(json_ready(summary), indent=2) + "\n")
    _plot(per_run, sources, out_dir)
    echo(text)
    return summary


def _never_low_enough(runs, heights_ft) -> list:
    """One line per run whose truth never descends to a height of the tables (issue 20 item 8):
    its errors there are "-" and this says why."""
    from visland.estimation.metrics import FT_TO_M
    notes = []
    for run in runs:
        lowest = float(np.min(run.truth["dh_m"]))
        missing = [h for h in heights_ft if lowest > h * FT_TO_M]
        if missing:
            notes.append(f"Note: run {run.path} ({run.scenario}) never descends below {lowest / FT_TO_M:.0f} ft "
                         f"({lowest:.1f} m), so it has no errors at {', '.join(f'{h:.0f}' for h in missing)} ft "
                         "(shown as -).")
    return notes


def _plot(per_run, sources, out_dir: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    for source in sources:
        runs = [r for r, _ in per_run if r.source == source]
        observers = list(dict.fromkeys(o for r in runs for o in r.series))
        fig, axes = plt.subplots(len(QUANTITIES), 1, figsize=(10, 2.8 * len(QUANTITIES)), sharex=True)
        for ax, (est_col, truth_col, label) in zip(axes, QUANTITIES):
            for k, observer in enumerate(observers):
                for j, run in enumerate(runs):
                    if observer not in run.series:
                        continue
                    error = run.truth[truth_col] - run.series[observer][est_col]
                    ax.plot(run.truth["dx_m"], error, color=f"C{k % 10}", lw=0.8, alpha=0.7,
                            label=observer if j == 0 else None)
            ax.set_ylabel(f"{label} error (m)")
            ax.set_yscale("symlog", linthresh=1.0)
            ax.axhline(0, color="k", lw=0.5)
        axes[0].set_title(f"truth - estimate against dX, {source} ({len(runs)} runs)")
        axes[0].legend(fontsize=7, ncol=4)
        axes[-1].set_xlabel("dX (m)")
        fig.savefig(out_dir / f"errors_vs_dx_{source}.png", dpi=90, bbox_inches="tight")
        plt.close(fig)
