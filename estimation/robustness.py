"""``visland study robustness`` (issue 12): the observers on a real installation, one imperfection at a time.

Each row of the sweep flies the scenarios with one imperfection (everything else as in the
thesis's 1 px study, :mod:`visland.estimation.study`) and scores every observer by its dH error
``dH - dH_hat`` at 400, 200 and 100 ft (and dY at 100 ft) per scenario:

===================  ========================================================================
axis                 levels
===================  ========================================================================
noise                corner noise 0, 1, 2, 5 px, the observers told the noise (:func:`noise_params`;
                     5 px: the settings of ``visland study table-5.7``)
frame rate           5, 10, 25, 50 Hz, exact measurements (issue 12: every observer within
                     0.05 m at 100 ft at 5 Hz)
mount pitch / roll   the camera pitched or rolled -1..+1 deg from camera.json, with the
                     mounting's self-calibration applied (``--self-calibration``)
slope                runway longitudinal slope -1, +1 %, self-calibration applied
delay                the frames stamped 20, 50, 100 ms after their exposure: unannounced (the
                     observers take the stamp for the exposure time) and announced (``--time-offset``)
velocity bias        the inertial velocity 5 % low or high (thesis Table 5.12's imperfection)
===================  ========================================================================

How a camera delay ``d`` is scored. The image of a frame stamped ``t`` shows the state at
``t - d``. Unannounced, the observers treat it as the state at ``t`` (the telemetry's ``t``)
and their estimate is for ``t``: it is compared with the truth at ``t``. Announced
(``--time-offset d`` puts the telemetry on the frames' clock), the observers are corrected with the
inertial data of the exposure and propagated from there: the estimate is for the exposure time and
compared with the truth then. Frames whose stamp falls after the telemetry's end are dropped.

The table prints, per observer and row, the largest ``|dH error|`` at 100 ft over the scenarios
(``n/a``: no estimate there on some scenario, e.g. cut off as diverged); ``study.json`` holds every
figure; ``robustness.png`` plots that largest error against each axis.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from visland.contracts import json_ready
from visland.estimation.metrics import run_metrics

__all__ = ["noise_params", "ROBUSTNESS_ROWS", "ROBUSTNESS_OBSERVERS", "ROBUSTNESS_SCENARIOS", "RobustnessRow", "robustness_study",
           "delayed_case"]

ROBUSTNESS_OBSERVERS = ("oj-2p", "ii-2p", "cccs-2p", "ccpi-hg-2p", "ccpi-hosm-2p", "cccj-2p", "kf-2p",
                        "ekf-2l", "cccj-2l")
#: Three of the eight thesis approaches (a straight-in one and two that turn onto the centreline):
#: the sweep is 20 rows, and all eight would take a quarter of an hour on a shared machine.
ROBUSTNESS_SCENARIOS = ("thesis-1", "thesis-4", "thesis-7")


@dataclass(frozen=True)
class RobustnessRow:
    """One row of the sweep: its axis, its label and the imperfection.

    Attributes
    ----------
    axis : str
        The imperfection swept (module docstring's table: ``noise``, ``frame rate``, ...).
    label : str
        The row's name in the table and ``study.json``.
    level : float
        The imperfection's size in the axis's unit (px, Hz, deg, %, s or a fraction), for the plot.
    pixel_noise_px : float, optional
        Gaussian corner noise (px, standard deviation).
    fps : float, optional
        Camera frame rate (Hz).
    mount_error_deg : tuple of float, optional
        (roll, pitch, yaw) error of the camera mounting against camera.json (deg, SPEC ``mount_rpy_deg``).
    slope_pct : float, optional
        Longitudinal slope of the runway (%, positive up along the landing direction).
    delay_s : float, optional
        Time from a frame's exposure to its stamp (s).
    delay_announced : bool, optional
        Whether the observers are told the delay (``--time-offset``).
    velocity_bias_fraction : float, optional
        Relative error of the inertial velocity (0.05: 5 % high).
    self_calibration : str, optional
        The mounting's self-calibration: ``off`` or ``apply`` (as ``--self-calibration``).

    References
    ----------
    Thesis (seed 002) sec. 5.2: noise (5.2.2), frame rate and delay (5.2.3), velocity bias (Table 5.12).
    """

    axis: str
    label: str
    level: float
    pixel_noise_px: float = 1.0
    fps: float = 25.0
    mount_error_deg: tuple = (0.0, 0.0, 0.0)        # roll, pitch, yaw
    slope_pct: float = 0.0
    delay_s: float = 0.0
    delay_announced: bool = False
    velocity_bias_fraction: float = 0.0
    self_calibration: str = "off"


def _rows() -> tuple:
    rows = [RobustnessRow("noise", f"noise {px:g} px", px, pixel_noise_px=px) for px in (0.0, 1.0, 2.0, 5.0)]
    rows += [RobustnessRow("frame rate", f"{fps:g} Hz exact", fps, pixel_noise_px=0.0, fps=fps) for fps in (5, 10, 25, 50)]
    rows += [RobustnessRow("mount pitch", f"pitch {deg:+g} deg", deg, mount_error_deg=(0.0, deg, 0.0),
                           self_calibration="apply") for deg in (-1.0, -0.5, 0.5, 1.0)]
    rows += [RobustnessRow("mount roll", f"roll {deg:+g} deg", deg, mount_error_deg=(deg, 0.0, 0.0),
                           self_calibration="apply") for deg in (-1.0, 1.0)]
    rows += [RobustnessRow("slope", f"slope {pct:+g} %", pct, slope_pct=pct, self_calibration="apply")
             for pct in (-1.0, 1.0)]
    rows += [RobustnessRow("delay", f"delay {1000 * d:g} ms", d, delay_s=d) for d in (0.02, 0.05, 0.1)]
    rows += [RobustnessRow("delay announced", f"delay {1000 * d:g} ms told", d, delay_s=d, delay_announced=True)
             for d in (0.05, 0.1)]
    rows += [RobustnessRow("velocity bias", f"velocity {100 * b:+g} %", b, velocity_bias_fraction=b)
             for b in (-0.05, 0.05)]
    return tuple(rows)


ROBUSTNESS_ROWS = _rows()


def noise_params(pixel_noise_px: float) -> dict:
    """Observer parameters told the corner noise, by observer name (the detector's uncertainty in use).

    Up to 1 px the defaults (the thesis's tuning); from 5 px the studies' 5 px settings
    (``SLOW_5PX_PARAMS``); between, the observers that take the noise as a parameter are told it
    (kf-2p's measurement noise, cccs-2p's bias correction and eta-rate saturation).

    Parameters
    ----------
    pixel_noise_px : float
        Standard deviation of the corner noise (px, at the SPEC camera's fx = 2472 px).

    Returns
    -------
    dict
        Observer name -> parameter overrides (empty up to 1 px).
    """
    from visland.estimation.study import SLOW_5PX_PARAMS
    if pixel_noise_px <= 1.0:
        return {}
    if pixel_noise_px >= 5.0:
        return dict(SLOW_5PX_PARAMS)
    sigma_rad = pixel_noise_px / 2472.0
    return {"kf-2p": {"image_sigma_rad": sigma_rad},
            "cccs-2p": {"noise_sigma_rad": sigma_rad, "max_eta_rate": 0.3}}


def _truth_at(result, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """dH, dX and dY of the flown trajectory at times ``t_s`` (linear between its 50 Hz samples)."""
    traj = result.trajectory
    p = np.stack([np.interp(t_s, traj.t_s, traj.p_runway_m[:, k]) for k in range(3)], axis=1)
    return -p[:, 2], p[:, 0] - result.scenario.runway.aim_distance_m, p[:, 1]


def delayed_case(case, delay_s: float, announced: bool):
    """``case`` (a :class:`visland.estimation.study.Case`) re-prepared with its frames stamped
    ``delay_s`` after their exposure, the delay announced or not (module docstring).

    Parameters
    ----------
    case : visland.estimation.study.Case
        A simulated case with ideal features.
    delay_s : float
        Delay from exposure to stamp, in [0, 1] s.
    announced : bool
        Whether the inertial data are moved onto the frames' clock (``--time-offset``).

    Returns
    -------
    visland.estimation.study.Case
        Frames stamped after the telemetry's end dropped; the truth taken at the time each estimate
        is for (the exposure when announced, the stamp when not).

    Raises
    ------
    ValueError
        ``delay_s`` outside [0, 1] s.
    """
    from visland.estimation.inputs import FeatureSeries, InertialSeries, prepare_inputs
    from visland.estimation.study import Case
    if not (math.isfinite(delay_s) and 0.0 <= delay_s <= 1.0):
        raise ValueError(f"delay_s must lie in [0, 1] s, got {delay_s!r}")
    result = case.result
    features = FeatureSeries.from_ideal(result.features)
    inertial = InertialSeries.from_imu(result.imu)
    stamps = features.t_s + delay_s
    if announced:
        inertial = replace(inertial, t_s=inertial.t_s + delay_s)
    keep = stamps <= inertial.t_s[-1]
    fields = {}
    for name in ("near_uv_px", "lines", "center_line", "dF_px", "points_ok", "lines_ok", "reason", "far_uv_px"):
        value = getattr(features, name)
        fields[name] = value[keep] if value is not None else None
    features = replace(features, t_s=stamps[keep], **fields)
    prepared = prepare_inputs(inertial, features, result.options.camera)
    exposure = np.asarray(result.frames.t_s)[keep]
    # the moment each estimate is for: the exposure when announced, the stamp when not
    dh, dx, dy = _truth_at(result, exposure if announced else exposure + delay_s)
    return Case(case.scenario, result, prepared, dh, dx, dy)


def _case(scenario: str, row: RobustnessRow, seed: int):
    from visland.estimation.study import Condition, simulate_case
    condition = Condition(row.label, pixel_noise_px=row.pixel_noise_px,
                          calibration_error_deg=tuple(row.mount_error_deg), slope_pct=row.slope_pct,
                          velocity_bias_fraction=row.velocity_bias_fraction, self_calibration=row.self_calibration)
    case = simulate_case(scenario, condition, seed=seed, fps=row.fps)
    if row.delay_s:
        case = delayed_case(case, row.delay_s, row.delay_announced)
    return case


def _score(case, name: str, params) -> dict:
    from visland.estimation.study import _run
    try:
        run, metrics = _run(name, case, params)
    except ValueError as error:            # no frame carries its features
        return {"err_400ft_m": math.nan, "err_200ft_m": math.nan, "err_100ft_m": math.nan,
                "dy_err_100ft_m": math.nan, "note": str(error)}
    i = np.nonzero(case.dh_true_m <= 100.0 * 0.3048)[0]
    dy = float(case.dy_true_m[i[0]] - run.dy_m[i[0]]) if i.size else math.nan
    return {"err_400ft_m": metrics["err_400ft_m"], "err_200ft_m": metrics["err_200ft_m"],
            "err_100ft_m": metrics["err_100ft_m"], "dy_err_100ft_m": dy}


def _worst(values) -> float:
    values = [float(v) for v in values]
    if not values or any(not math.isfinite(v) for v in values):
        return math.nan
    return max(abs(v) for v in values)


def robustness_study(out: Path | None, seed: int, echo, scenarios=ROBUSTNESS_SCENARIOS,
                     observers=ROBUSTNESS_OBSERVERS, rows=ROBUSTNESS_ROWS) -> dict:
    """Run the sweep; print the table; write ``robustness.png`` into ``out``; return the figures.

    Parameters
    ----------
    out : pathlib.Path or None
        Existing folder for ``robustness.png``; None: no plot.
    seed : int
        Seed of the noise; scenario k uses ``seed + k``.
    echo : callable
        Takes each printed line (a str).
    scenarios : sequence of str, optional
        Scenario names (:mod:`visland.scenarios`).
    observers : sequence of str, optional
        Observer names (SPEC).
    rows : sequence of RobustnessRow, optional
        The imperfections, one run each.

    Returns
    -------
    dict
        ``rows``: per row label, per observer the largest ``|dH - dH_hat|`` (m) at 400/200/100 ft and
        ``|dY - dY_hat|`` at 100 ft over the scenarios, and the figures per scenario; ``plots``.

    References
    ----------
    Thesis (seed 002) sec. 5.2 and Tables 5.6-5.12 (the imperfections and their metrics).
    """
    echo("study robustness: one imperfection per row, 1 px corner noise and 25 Hz unless the row says otherwise; "
         "mount errors and slope with the self-calibration applied")
    echo(f"scenarios {', '.join(scenarios)}; each cell: the largest |dH - dH_hat| at 100 ft over them (m); "
         "n/a: no estimate at 100 ft on some scenario")
    header = f"{'row':22s}" + "".join(f" | {name:>12s}" for name in observers)
    echo(header)
    echo("-" * len(header))
    figures = {}
    for row in rows:
        per_observer = {name: {} for name in observers}
        for k, scenario in enumerate(scenarios):
            case = _case(scenario, row, seed + k)
            for name in observers:
                per_observer[name][scenario] = _score(case, name, noise_params(row.pixel_noise_px).get(name))
        cells = []
        row_figures = {"axis": row.axis, "level": row.level, "observers": {}}
        for name in observers:
            scores = per_observer[name]
            worst = {key: _worst(s[key] for s in scores.values())
                     for key in ("err_400ft_m", "err_200ft_m", "err_100ft_m", "dy_err_100ft_m")}
            row_figures["observers"][name] = {
                "worst_abs": {k: json_ready(v) for k, v in worst.items()},
                "by_scenario": {s: {k: json_ready(v) for k, v in sc.items()} for s, sc in scores.items()}}
            value = worst["err_100ft_m"]
            cells.append(f"{'n/a':>12s}" if not math.isfinite(value) else f"{value:12.3f}")
        figures[row.label] = row_figures
        echo(f"{row.label:22s}" + "".join(f" | {c}" for c in cells))
    plots = []
    if out is not None:
        path = Path(out) / "robustness.png"
        _plot(figures, observers, path)
        plots.append(str(path))
        echo(f"plot: {path}")
    return {"scenarios": list(scenarios), "observers": list(observers), "rows": figures, "plots": plots}


def _plot(figures: dict, observers, path: Path) -> None:
    """One panel per axis: the largest |dH error| at 100 ft over the scenarios against the level."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    axes_order = []
    for fig_row in figures.values():
        if fig_row["axis"] not in axes_order:
            axes_order.append(fig_row["axis"])
    units = {"noise": "corner noise (px)", "frame rate": "frame rate (Hz), exact measurements",
             "mount pitch": "mount pitch error (deg), self-calibrated", "mount roll": "mount roll error (deg), self-calibrated",
             "slope": "runway slope (%), self-calibrated", "delay": "camera delay (s), not announced",
             "delay announced": "camera delay (s), announced", "velocity bias": "velocity bias (fraction)"}
    n = len(axes_order)
    cols = 4
    rows = math.ceil(n / cols)
    fig, grid = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.4 * rows), squeeze=False)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, axis in enumerate(axes_order):
        ax = grid[k // cols][k % cols]
        items = [r for r in figures.values() if r["axis"] == axis]
        if axis.startswith("delay"):
            # no delay: the 1 px row
            items = [r for r in figures.values() if r["axis"] == "noise" and r["level"] == 1.0] + items
            levels = [0.0] + [r["level"] for r in items[1:]]
        else:
            levels = [r["level"] for r in items]
        for j, name in enumerate(observers):
            values = [r["observers"][name]["worst_abs"]["err_100ft_m"] for r in items]
            values = [np.nan if v is None else max(float(v), 1e-4) for v in values]
            style = "-" if name.endswith("-2p") else "--"
            ax.plot(levels, values, style, marker="o", ms=3, lw=1, color=colours[j % len(colours)], label=name)
            # a missing estimate (diverged, cut off) drawn as an x at the top
            for x, v in zip(levels, values):
                if not np.isfinite(v):
                    ax.plot([x], [300.0], "x", color=colours[j % len(colours)], ms=6)
        ax.set_yscale("log")
        ax.set_ylim(1e-4, 500)
        ax.axhline(0.3, color="grey", lw=0.6, ls=":")
        ax.set_xlabel(units.get(axis, axis), fontsize=8)
        ax.set_ylabel("max |dH err| at 100 ft (m)", fontsize=8)
        ax.grid(True, alpha=0.3)
        ax.tick_params(labelsize=7)
    for k in range(n, rows * cols):
        grid[k // cols][k % cols].axis("off")
    handles, labels = grid[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.955), ncol=len(labels), fontsize=8)
    fig.suptitle("visland study robustness: the largest dH error at 100 ft over the scenarios "
                 "(x at the top: no estimate; dotted: 0.3 m)", fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.92))
    fig.savefig(path, dpi=110)
    plt.close(fig)
