"""``visland study dickmanns``: the 4D approach (seed 004) beside the thesis's observers and the seed.

Two parts, both on simulated measurements with 1 px of Gaussian pixel noise (thesis 5.2.2),
the inputs prepared as ``visland estimate`` does (heading deviation from the measured d_F) and
every observer started 20 % above the true height (:func:`visland.estimation.study.simulate_case`):

1. **The eight thesis scenarios** (thesis Table 5.2, no wind): ``dickmanns-4d`` with the airspeed
   (telemetry ``tas_mps``, wind states estimated) and without it (the column removed: no wind
   states, the observer says so), beside ``ekf-2l`` (the thesis's line EKF) and ``ccpi-hg-2p``
   (its two-point reference). Per observer: dH, dY and dX errors (``truth - estimate``, metres) at
   400/200/100 ft on thesis-1; at 100 ft the mean and standard deviation over the eight
   scenarios; the 5 % convergence time on thesis-1 (the thesis's metric,
   :mod:`visland.estimation.metrics`). The thesis's Table 5.6 (1 px, two points) figure is printed
   beside ``ccpi-hg-2p``'s; the thesis has no noisy-lines table, so ``ekf-2l`` has none.
2. **The seed's wind case** (``dickmanns-wind``: thesis-1 through a -1 m/s crosswind from 800 m
   before the threshold and a 2 m/s cross / 1 m/s vertical gust at 650 m decaying in 6 s), with and
   without the airspeed, against seed 004's published accuracy (sec. 7, HIL and flight): distance
   within 5 m while the threshold is visible, height and lateral within 1 m (from 2 km in here),
   runway width within 1 m (by 1 km out), the crosswind within 0.5 m/s once the gust has decayed
   (one time constant after its onset), and at 100 ft at least as good as ``ekf-2l``.

Writes ``dickmanns-wind.png`` (errors and the crosswind against dX) and ``thesis-1-dickmanns.png``
into the output folder.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from visland.contracts import json_ready
from visland.estimation.metrics import FT_TO_M, aggregate_at_100ft, error_at_height_of, run_metrics
from visland.estimation.registry import make_observer, observer_features
from visland.estimation.runner import run_observer
from visland.estimation.thesis_tables import thesis_value

__all__ = ["DICKMANNS_VARIANTS", "SEED_004_TARGETS", "dickmanns_study", "score_wind_run", "without_airspeed",
           "wind_case_figures"]

#: Rows of the study: (label, observer, airspeed given to it).
DICKMANNS_VARIANTS = (("dickmanns-4d", "dickmanns-4d", True),
                      ("dickmanns-4d no tas", "dickmanns-4d", False),
                      ("ekf-2l", "ekf-2l", True),
                      ("ccpi-hg-2p", "ccpi-hg-2p", True))

#: Line style of each row in the plots (the two dickmanns-4d rows overlap: the second dashed).
_STYLE = {"dickmanns-4d": {"color": "C0"}, "dickmanns-4d no tas": {"color": "C1", "ls": "--"},
          "ekf-2l": {"color": "C2"}, "ccpi-hg-2p": {"color": "C3"}}

#: Seed 004's published accuracy (sec. 7), metres and m/s, as checked on ``dickmanns-wind``.
SEED_004_TARGETS = {"dx_threshold_visible_m": 5.0, "dh_from_2km_m": 1.0, "dy_from_2km_m": 1.0,
                    "width_by_1km_m": 1.0, "crosswind_after_gust_mps": 0.5}

_HEIGHTS_FT = (400.0, 200.0, 100.0)
_PIXEL_NOISE_PX = 1.0


def without_airspeed(prepared):
    """The same prepared inputs with the airspeed removed (as telemetry without ``tas_mps``).

    Parameters
    ----------
    prepared : visland.estimation.inputs.PreparedInputs
        Inputs prepared as ``visland estimate`` does; not modified.

    Returns
    -------
    visland.estimation.inputs.PreparedInputs
        A copy whose every step has ``tas_mps = nan``.
    """
    return replace(prepared, steps=[replace(step, tas_mps=math.nan) for step in prepared.steps])


def _run(observer_name: str, case, airspeed: bool):
    from visland.estimation.study import INITIAL_HEIGHT_ERROR
    prepared = case.prepared if airspeed else without_airspeed(case.prepared)
    start = prepared.first_step_with(observer_features(observer_name))
    if start is None:
        raise ValueError(f"{case.scenario}: no frame carries the features of {observer_name}")
    dh0 = (1.0 + INITIAL_HEIGHT_ERROR) * case.dh_true_m[prepared.frame_of_step[start]]
    return run_observer(make_observer(observer_name), prepared, dh0)


def _scores(case, run) -> dict:
    """dH/dY/dX errors at 400/200/100 ft and the 5 % convergence time of one run."""
    metrics = run_metrics(run.t_s, case.dh_true_m, run.dh_m, start_t_s=run.start_t_s)
    out = {"conv_time_5pct_s": metrics["conv_time_5pct_s"]}
    for q, truth, est in (("dh", case.dh_true_m, run.dh_m), ("dy", case.dy_true_m, run.dy_m),
                          ("dx", case.dx_true_m, run.dx_m)):
        for h in _HEIGHTS_FT:
            out[f"{q}_err_{h:.0f}ft_m"] = error_at_height_of(case.dh_true_m, truth, est, h * FT_TO_M)
    return out


def _fmt(value, width: int = 8) -> str:
    if value is None:
        return f"{'-':>{width}s}"
    if not math.isfinite(value):
        return f"{'n/a':>{width}s}"
    return f"{value:>{width}.3f}" if abs(value) < 100 else f"{value:>{width}.1f}"


def dickmanns_study(out: Path | None, seed: int, echo) -> dict:
    """Run both parts (module docstring); print the tables; return the figures (the JSON line).

    Parameters
    ----------
    out : pathlib.Path or None
        Existing folder for ``dickmanns-wind.png`` and ``thesis-1-dickmanns.png``; None: no plots.
    seed : int
        Seed of the pixel noise; scenario k of the thesis's eight uses ``seed + k``.
    echo : callable
        Takes each printed line (a str).

    Returns
    -------
    dict
        ``observers`` (per row of :data:`DICKMANNS_VARIANTS`: errors in metres at 400/200/100 ft,
        means and standard deviations over the eight scenarios, 5 % convergence times in seconds,
        the thesis's Table 5.6 figures), ``wind`` (:func:`wind_case_figures`), ``plots``.

    References
    ----------
    E. D. Dickmanns, F.-R. Schell, "Autonomous landing of airplanes by dynamic machine vision"
    (seed 004), sec. 7 (accuracy reached); thesis (seed 002) Table 5.2 (scenarios), Table 5.6 (1 px).
    """
    from visland.estimation.study import THESIS_SCENARIOS, Condition, simulate_case
    condition = Condition("1 px", pixel_noise_px=_PIXEL_NOISE_PX)
    echo("study dickmanns: seed 004's 4D approach (dickmanns-4d) beside ekf-2l and ccpi-hg-2p, 1 px pixel noise")
    echo(f"part 1: scenarios {', '.join(THESIS_SCENARIOS)} (no wind); observers start 20 % above the true height; "
         "errors truth - estimate (m)")
    per = {label: {} for label, _, _ in DICKMANNS_VARIANTS}
    runs1 = {}
    case1 = None
    for k, scenario in enumerate(THESIS_SCENARIOS):
        case = simulate_case(scenario, condition, seed=seed + k)
        if k == 0:
            case1 = case
        for label, name, airspeed in DICKMANNS_VARIANTS:
            run = _run(name, case, airspeed)
            per[label][scenario] = _scores(case, run)
            if k == 0:
                runs1[label] = run
    table = {}
    for label, name, _ in DICKMANNS_VARIANTS:
        traj1 = per[label][THESIS_SCENARIOS[0]]
        row = dict(traj1)
        for q in ("dh", "dy", "dx"):
            agg = aggregate_at_100ft(per[label][s][f"{q}_err_100ft_m"] for s in THESIS_SCENARIOS)
            row[f"{q}_mean_100ft_m"] = agg["mean_err_100ft_m"]
            row[f"{q}_std_100ft_m"] = agg["std_err_100ft_m"]
        row["dh_err_100ft_m_by_scenario"] = {s: per[label][s]["dh_err_100ft_m"] for s in THESIS_SCENARIOS}
        row["conv_time_5pct_s_by_scenario"] = {s: per[label][s]["conv_time_5pct_s"] for s in THESIS_SCENARIOS}
        row["thesis_5.6"] = {"conv_time_5pct_s": thesis_value("5.6", name, "conv_time_5pct_s_traj1"),
                             "dh_err_100ft_m": thesis_value("5.6", name, "err_100ft_m_traj1"),
                             "dh_mean_100ft_m": thesis_value("5.6", name, "mean_err_100ft_m_all8"),
                             "dh_std_100ft_m": thesis_value("5.6", name, "std_err_100ft_m_all8")}
        table[label] = row
    _print_thesis_table(table, echo)
    echo("")
    wind = wind_case_figures(seed, echo, out)
    plots = list(wind.pop("plots"))
    if out is not None and case1 is not None:
        path = out / "thesis-1-dickmanns.png"
        _plot_thesis1(case1, runs1, path)
        plots.append(str(path))
        echo(f"plot: {path}")
    return {"pixel_noise_px": _PIXEL_NOISE_PX, "scenarios": list(THESIS_SCENARIOS),
            "observers": {label: {k: (json_ready(v) if not isinstance(v, dict) else
                                      {s: json_ready(x) for s, x in v.items()}) for k, v in row.items()}
                          for label, row in table.items()},
            "wind": wind, "seed_004_targets": SEED_004_TARGETS, "plots": plots}


def _print_thesis_table(table: dict, echo) -> None:
    head = (f"{'observer':20s} {'q':2s} " + " ".join(f"{f'{h:.0f} ft':>8s}" for h in _HEIGHTS_FT)
            + f" {'mean/8':>8s} {'std/8':>8s}  {'conv5%':>7s}")
    echo("thesis-1 errors at 400/200/100 ft; at 100 ft mean and std over the 8 scenarios; 5 % convergence "
         "time (s) on thesis-1; [thesis Table 5.6, 1 px, 2 points] where it has the figure")
    echo(head)
    for label, row in table.items():
        for q in ("dh", "dy", "dx"):
            cells = " ".join(_fmt(row[f"{q}_err_{h:.0f}ft_m"]) for h in _HEIGHTS_FT)
            line = (f"{label if q == 'dh' else '':20s} {q[1].upper():2s} {cells} {_fmt(row[f'{q}_mean_100ft_m'])} "
                    f"{_fmt(row[f'{q}_std_100ft_m'])}")
            if q == "dh":
                line += f"  {_fmt(row['conv_time_5pct_s'], 7)}"
                thesis = row["thesis_5.6"]
                if thesis["dh_err_100ft_m"] is not None:
                    line += (f"  [thesis 100 ft {thesis['dh_err_100ft_m']:.3f}, mean/std "
                             f"{thesis['dh_mean_100ft_m']:.3f}/{thesis['dh_std_100ft_m']:.3f}, "
                             f"conv {thesis['conv_time_5pct_s']:.2f} s]")
            echo(line)


# --------------------------------------------------------------------------- the seed's wind case
def wind_case_figures(seed: int, echo, out: Path | None = None) -> dict:
    """Part 2 (module docstring): ``dickmanns-wind`` with and without airspeed against seed 004.

    Parameters
    ----------
    seed : int
        Seed of the pixel noise (1 px).
    echo : callable
        Takes each printed line (a str).
    out : pathlib.Path or None, optional
        Existing folder for ``dickmanns-wind.png``; None: no plot.

    Returns
    -------
    dict
        Per observer the largest errors (m, m/s) over the windows of :data:`SEED_004_TARGETS`,
        ``dickmanns_4d_meets`` (each target met or not) and ``plots`` (paths written).

    References
    ----------
    E. D. Dickmanns, F.-R. Schell, "Autonomous landing of airplanes by dynamic machine vision"
    (seed 004), sec. 7.1-7.2 (HIL and flight-test accuracy).
    """
    from visland.estimation.study import Condition, simulate_case
    case = simulate_case("dickmanns-wind", Condition("1 px", pixel_noise_px=_PIXEL_NOISE_PX), seed=seed)
    result = case.result
    tr = result.trajectory
    wind_runway = tr.wind_ned_mps @ tr.R_runway_from_ned.T
    t_frames = np.asarray(result.frames.t_s, dtype=float)
    wy_true = np.interp(t_frames, tr.t_s, wind_runway[:, 1])
    wx_true = np.interp(t_frames, tr.t_s, wind_runway[:, 0])
    gust = result.scenario.wind
    steady = gust.crosswind_mps
    onset = np.nonzero(wind_runway[:, 1] - steady > 0.5 * gust.gust_crosswind_mps)[0]
    gust_t0 = float(tr.t_s[onset[0]]) if onset.size else math.nan
    prepared = case.prepared
    threshold_seen = np.array([prepared.steps[j].points_yv is not None for j in prepared.step_of_frame])
    width_true = result.scenario.runway.width_m
    runs = {"dickmanns-4d": _run("dickmanns-4d", case, True),
            "dickmanns-4d no tas": _run("dickmanns-4d", case, False),
            "ekf-2l": _run("ekf-2l", case, True)}
    from_2km = case.dx_true_m > -2000.0 - result.scenario.runway.aim_distance_m
    by_1km = case.dx_true_m > -1000.0 - result.scenario.runway.aim_distance_m
    after_gust = t_frames > gust_t0 + gust.gust_time_constant_s
    figures = {"scenario": "dickmanns-wind", "gust_onset_t_s": gust_t0, "observers": {}}

    def worst(error, mask):
        values = np.abs(error[mask & np.isfinite(error)])
        return float(values.max()) if values.size else math.nan

    echo("part 2: dickmanns-wind (thesis-1 through -1 m/s crosswind from 800 m before the threshold and a 2 m/s "
         f"gust at 650 m, decaying in {gust.gust_time_constant_s:g} s), 1 px noise; largest |truth - estimate|: "
         "dX while the threshold is visible from 2 km in (and from 1 km), dH and dY from 2 km in, width from 1 km "
         f"in, crosswind from one time constant after the gust's onset (t > {gust_t0:.1f} + "
         f"{gust.gust_time_constant_s:g} s)")
    echo(f"{'observer':20s} {'dX thr.vis':>10s} {'dX <1km':>8s} {'dH <2km':>8s} {'dY <2km':>8s} {'W <1km':>8s} "
         f"{'wind y':>8s} {'dH 100ft':>9s} {'dY 100ft':>9s}")
    echo(f"{'seed 004':20s} {SEED_004_TARGETS['dx_threshold_visible_m']:>10.1f} {'-':>8s} "
         f"{SEED_004_TARGETS['dh_from_2km_m']:>8.1f} {SEED_004_TARGETS['dy_from_2km_m']:>8.1f} "
         f"{SEED_004_TARGETS['width_by_1km_m']:>8.1f} {SEED_004_TARGETS['crosswind_after_gust_mps']:>8.1f} "
         f"{'<= ekf-2l':>9s} {'-':>9s}")
    for label, run in runs.items():
        row = {"dx_threshold_visible_m": worst(case.dx_true_m - run.dx_m, threshold_seen & from_2km),
               "dx_threshold_visible_from_1km_m": worst(case.dx_true_m - run.dx_m, threshold_seen & by_1km),
               "dh_from_2km_m": worst(case.dh_true_m - run.dh_m, from_2km),
               "dy_from_2km_m": worst(case.dy_true_m - run.dy_m, from_2km),
               "width_by_1km_m": worst(width_true - run.width_m, by_1km),
               "crosswind_after_gust_mps": (worst(wy_true - run.extras["wind_y_mps"], after_gust)
                                            if "wind_y_mps" in run.extras else math.nan),
               "dh_err_100ft_m": error_at_height_of(case.dh_true_m, case.dh_true_m, run.dh_m, 100 * FT_TO_M),
               "dy_err_100ft_m": error_at_height_of(case.dh_true_m, case.dy_true_m, run.dy_m, 100 * FT_TO_M),
               "notes": list(run.notes)}
        figures["observers"][label] = {k: (json_ready(v) if not isinstance(v, list) else v) for k, v in row.items()}
        echo(f"{label:20s} {_fmt(row['dx_threshold_visible_m'], 10)} {_fmt(row['dx_threshold_visible_from_1km_m'])} "
             f"{_fmt(row['dh_from_2km_m'])} "
             f"{_fmt(row['dy_from_2km_m'])} {_fmt(row['width_by_1km_m'])} {_fmt(row['crosswind_after_gust_mps'])} "
             f"{_fmt(row['dh_err_100ft_m'], 9)} {_fmt(row['dy_err_100ft_m'], 9)}")
    ours = figures["observers"]["dickmanns-4d"]
    ekf = figures["observers"]["ekf-2l"]
    checks = {key: bool(ours[key] is not None and ours[key] <= target) for key, target in SEED_004_TARGETS.items()}
    checks["dh_100ft_at_least_ekf_2l"] = bool(ours["dh_err_100ft_m"] is not None and ekf["dh_err_100ft_m"] is not None
                                             and abs(ours["dh_err_100ft_m"]) <= abs(ekf["dh_err_100ft_m"]))
    figures["dickmanns_4d_meets"] = checks
    echo("dickmanns-4d against seed 004: " + ", ".join(f"{k} {'ok' if v else 'NOT MET'}" for k, v in checks.items()))
    for label, run in runs.items():
        for note in run.notes:
            echo(f"{label}: {note}")
    plots = []
    if out is not None:
        path = out / "dickmanns-wind.png"
        _plot_wind(case, runs, wy_true, wx_true, threshold_seen, width_true, gust_t0, path)
        plots.append(str(path))
        echo(f"plot: {path}")
    figures["plots"] = plots
    return figures


# --------------------------------------------------------------------------- plots
def _plot_wind(case, runs, wy_true, wx_true, threshold_seen, width_true, gust_t0, path: Path) -> None:
    """Five panels against dX: dX (threshold visible), dH, dY, width errors and the crosswind."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    dx = case.dx_true_m
    fig, axes = plt.subplots(5, 1, figsize=(9, 12), sharex=True)
    panels = (("dX error (m), threshold visible", lambda r: np.where(threshold_seen, dx - r.dx_m, np.nan), 5.0),
              ("dH error (m)", lambda r: case.dh_true_m - r.dh_m, 1.0),
              ("dY error (m)", lambda r: case.dy_true_m - r.dy_m, 1.0),
              ("width error (m)", lambda r: width_true - r.width_m, 1.0))
    for ax, (title, error, target) in zip(axes, panels):
        for label, run in runs.items():
            ax.plot(dx, error(run), lw=0.8, label=label, **_STYLE[label])
        ax.axhspan(-target, target, color="0.85", zorder=0, label=f"seed 004: +-{target:g}")
        ax.set_ylim(-4 * target, 4 * target)
        ax.set_ylabel(title, fontsize=8)
        ax.grid(alpha=0.3)
    ax = axes[4]
    ax.plot(dx, wy_true, color="k", lw=1.2, label="crosswind truth (runway y)")
    ax.plot(dx, wx_true, color="0.5", lw=1.0, ls="--", label="along-runway wind truth")
    for label, run in runs.items():
        if "wind_y_mps" in run.extras and np.isfinite(run.extras["wind_y_mps"]).any():
            ax.plot(dx, run.extras["wind_y_mps"], lw=0.8, color=_STYLE[label]["color"], label=f"{label} crosswind")
            ax.plot(dx, run.extras["wind_x_mps"], lw=0.8, color=_STYLE[label]["color"], ls=":",
                    label=f"{label} along")
    if math.isfinite(gust_t0):
        i = int(np.searchsorted(case.result.frames.t_s, gust_t0))
        if i < len(dx):
            for a in axes:
                a.axvline(dx[i], color="r", lw=0.8, ls=":")
            ax.text(dx[i], 2.5, " gust", color="r", fontsize=8, va="top")
    ax.set_ylim(-3, 3)
    ax.set_ylabel("wind (m/s)", fontsize=8)
    ax.set_xlabel("dX (m)")
    ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, ncol=4, loc="upper left")
    ax.legend(fontsize=7, ncol=3, loc="lower left")
    axes[0].set_title("dickmanns-wind, 1 px noise: dickmanns-4d with / without airspeed, ekf-2l", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def _plot_thesis1(case, runs: dict, path: Path) -> None:
    """dH, dY, dX errors against dX on thesis-1 for every row of the study."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    dx = case.dx_true_m
    for ax, (q, truth, limit) in zip(axes, (("dH", case.dh_true_m, 20.0), ("dY", case.dy_true_m, 20.0),
                                           ("dX", case.dx_true_m, 200.0))):
        for label, run in runs.items():
            est = {"dH": run.dh_m, "dY": run.dy_m, "dX": run.dx_m}[q]
            ax.plot(dx, truth - est, lw=0.8, label=label, **_STYLE[label])
        ax.set_ylim(-limit, limit)
        ax.set_ylabel(f"{q} error (m)")
        ax.grid(alpha=0.3)
        for h in _HEIGHTS_FT:
            i = np.nonzero(case.dh_true_m <= h * FT_TO_M)[0]
            if i.size:
                ax.axvline(dx[i[0]], color="0.6", lw=0.8, ls=":")
    axes[0].legend(fontsize=8, ncol=4)
    axes[0].set_title("thesis-1, 1 px noise: errors (truth - estimate) against dX; dotted: 400/200/100 ft",
                      fontsize=10)
    axes[2].set_xlabel("dX (m)")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


# --------------------------------------------------------------------------- a processed run
def score_wind_run(run_dir, echo=print) -> dict:
    """Seed 004's figures (:data:`SEED_004_TARGETS`) for each observer of a ``visland process`` run of
    ``dickmanns-wind`` (or any approach with truth): reads ``estimates.csv``, ``truth.csv`` (with its
    wind columns), ``measurements.csv`` (the threshold counts as visible where both near corners were
    measured) and, for scoring only, ``runway.json``'s width and aiming distance and ``manifest.json``'s
    gust time constant. The gust's onset is the frame where the true crosswind jumps up most (at least
    0.5 m/s between two frames). Prints one row per observer; returns the figures.

    Parameters
    ----------
    run_dir : str or pathlib.Path
        Output folder of ``visland process`` on a dataset with truth (the files above).
    echo : callable, optional
        Takes each printed line (a str).

    Returns
    -------
    dict
        Per observer name, the largest ``|truth - estimate|`` (m; crosswind m/s) in each window of
        :data:`SEED_004_TARGETS` (NaN where the window holds no estimate).

    References
    ----------
    E. D. Dickmanns, F.-R. Schell, "Autonomous landing of airplanes by dynamic machine vision"
    (seed 004), sec. 7.
    """
    import json

    from visland.contracts import read_estimates, read_measurements, read_truth
    from visland.runway import Runway
    run_dir = Path(run_dir)
    truth = read_truth(run_dir / "truth.csv")
    estimates = read_estimates(run_dir / "estimates.csv")
    measured = read_measurements(run_dir / "measurements.csv")
    runway = Runway.load(run_dir / "runway.json")
    tau = 6.0
    manifest = run_dir / "manifest.json"
    if manifest.exists():
        tau = float(json.loads(manifest.read_text()).get("scenario", {}).get("wind", {}).get("gust_time_constant_s",
                                                                                               tau))
    t = np.asarray(truth["t_s"], dtype=float)
    dx_true, dy_true, dh_true = (np.asarray(truth[c], dtype=float) for c in ("dx_m", "dy_m", "dh_m"))
    wy_true = np.asarray(truth["wind_y_runway_mps"], dtype=float) if "wind_y_runway_mps" in truth else None
    gust_t0 = math.nan
    if wy_true is not None and len(wy_true) > 1:
        jump = np.diff(wy_true)
        if jump.max() > 0.5:
            gust_t0 = float(t[int(np.argmax(jump)) + 1])
    seen = np.isfinite(np.asarray(measured["near_left_u_px"], dtype=float)) & \
        np.isfinite(np.asarray(measured["near_right_u_px"], dtype=float)) & (np.asarray(measured["found"]) > 0.5)
    aim = runway.aim_distance_m
    from_2km = dx_true > -2000.0 - aim
    by_1km = dx_true > -1000.0 - aim
    after_gust = t > gust_t0 + tau

    def worst(error, mask):
        values = np.abs(error[mask & np.isfinite(error)])
        return float(values.max()) if values.size else math.nan

    names = list(dict.fromkeys(str(o) for o in estimates["observer"]))
    figures = {"run": str(run_dir), "gust_onset_t_s": gust_t0, "observers": {}}
    echo(f"{run_dir}: largest |truth - estimate| (seed 004: dX {SEED_004_TARGETS['dx_threshold_visible_m']:g} m "
         f"while the threshold is visible, dH and dY 1 m, width 1 m, crosswind 0.5 m/s)")
    echo(f"{'observer':14s} {'dX thr.vis':>10s} {'dX <1km':>8s} {'dH <2km':>8s} {'dY <2km':>8s} {'W <1km':>8s} "
         f"{'wind y':>8s} {'dH 100ft':>9s} {'found %':>8s}")
    for name in names:
        rows = np.asarray(estimates["observer"]) == name
        est = {c: np.asarray(estimates[c], dtype=float)[rows] for c in ("dx_m", "dy_m", "dh_m", "width_m")}
        if len(est["dh_m"]) != len(t):
            raise ValueError(f"{run_dir}/estimates.csv: {name} has {len(est['dh_m'])} rows for {len(t)} frames")
        wind_y = np.asarray(estimates["wind_y_mps"], dtype=float)[rows] if "wind_y_mps" in estimates else None
        row = {"dx_threshold_visible_m": worst(dx_true - est["dx_m"], seen & from_2km),
               "dx_threshold_visible_from_1km_m": worst(dx_true - est["dx_m"], seen & by_1km),
               "dh_from_2km_m": worst(dh_true - est["dh_m"], from_2km),
               "dy_from_2km_m": worst(dy_true - est["dy_m"], from_2km),
               "width_by_1km_m": worst(runway.width_m - est["width_m"], by_1km),
               "crosswind_after_gust_mps": (worst(wy_true - wind_y, after_gust)
                                            if wind_y is not None and wy_true is not None else math.nan),
               "dh_err_100ft_m": error_at_height_of(dh_true, dh_true, est["dh_m"], 100 * FT_TO_M),
               "found_pct": 100.0 * float(np.mean(np.asarray(measured["found"]) > 0.5))}
        figures["observers"][name] = json_ready(row)
        echo(f"{name:14s} {_fmt(row['dx_threshold_visible_m'], 10)} {_fmt(row['dx_threshold_visible_from_1km_m'])} "
             f"{_fmt(row['dh_from_2km_m'])} {_fmt(row['dy_from_2km_m'])} {_fmt(row['width_by_1km_m'])} "
             f"{_fmt(row['crosswind_after_gust_mps'])} {_fmt(row['dh_err_100ft_m'], 9)} {row['found_pct']:8.1f}")
    return figures
