"""``visland study NAME``: the seeds' simulated-measurement studies, side by side with the seeds.

Each study flies scenarios (:func:`visland.simulate.run_simulation`), degrades the
measurements as the thesis does (section 5.2.2: 1 px and 5 px Gaussian pixel noise, a 0.5 deg
camera calibration error, a 5 % velocity bias; ECC'15: 1 % relative noise), prepares the
observer inputs exactly as ``visland estimate`` does (:mod:`visland.estimation.inputs`: d_F,
filtered runway heading, virtual frame), runs the observers from a height guess 20 % above
the truth (the seeds' initial error) and scores them with :mod:`visland.estimation.metrics`.

Studies (thesis table numbers; "traj1" = thesis-1, "all8" = thesis-1..8):

==============  ===========================================================================
table-5.3       ideal measurements, two points
table-5.4       ideal measurements, two lines (the line observers of visland.estimation.lines)
table-5.6       1 px pixel noise, two points
table-5.7       5 px pixel noise, two points (slower corrections, as the thesis does)
lines-5px       5 px pixel noise, two lines (issue 12; the thesis has no such table)
table-5.8       standard deviation of the error along trajectory 1, 1 px and 5 px
table-5.10      0.5 deg calibration error on the camera mounting, two points
table-5.12      5 % velocity bias, two points (v_meas = 0.95 v; see VELOCITY_BIAS_FRACTION)
calibration     issue 12: camera mount pitch/roll errors (+-0.5 deg) and runway slope (+-1 %), alone and
                combined, 1 px noise, with the mounting's self-calibration applied
                (visland.estimation.calibration); also its estimate 1 km out against the truth
robustness      issue 12: one imperfection per row (noise 0-5 px, 5-50 Hz, mount pitch/roll +-1 deg,
                slope +-1 %, camera delay 20-100 ms unannounced and announced, velocity bias +-5 %),
                nine observers, three scenarios (visland.estimation.robustness)
ecc             ECC'15: the three landings ecc-1..3 with 1 % measurement noise, ecc-hg and ecc-hosm
academic        seed 001: the single-point observer on its academic example (eq. 14-16)
dickmanns       seed 004: dickmanns-4d (with and without airspeed) beside ekf-2l and ccpi-hg-2p on the 8
                scenarios, 1 px; and on dickmanns-wind against the seed's accuracy
                (:mod:`visland.estimation.dickmanns_study`)
==============  ===========================================================================

Each prints its table with the thesis's figure beside each of ours (``!`` marks a figure more
than twice the thesis's in magnitude, ``~`` less than half of it), writes plots of the error
against dX (as ECC'15 Fig. 4-5) and a ``study.json`` into the output folder, and ends with one
JSON line of figures.
"""
from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from visland.contracts import json_ready

from visland.estimation.inputs import FeatureSeries, InertialSeries, PreparedInputs, prepare_inputs
from visland.estimation.metrics import (FT_TO_M, METRIC_DEFINITIONS, aggregate_at_100ft, error_at_height_of,
                                       run_metrics)
from visland.estimation.registry import make_observer, observer_features
from visland.estimation.runner import ObserverRun, run_observer
from visland.estimation.thesis_tables import THESIS_CONDITIONS, thesis_value

__all__ = ["STUDIES", "StudySpec", "Condition", "run_study", "study_names", "INITIAL_HEIGHT_ERROR",
           "VELOCITY_BIAS_FRACTION", "THESIS_SCENARIOS", "simulate_case"]

THESIS_SCENARIOS = tuple(f"thesis-{k}" for k in range(1, 9))
ECC_SCENARIOS = ("ecc-1", "ecc-2", "ecc-3")
#: The seeds start their observers 20 % away from the true height (thesis Fig. 5.3, ECC'15 IV.B).
INITIAL_HEIGHT_ERROR = 0.20
#: Thesis Table 5.12's errors are positive (dH_hat below dH). A relative velocity bias b scales the
#: whole solution (the virtual-frame points and velocities scale together), so the observers
#: converge to dH_hat = (1 + b) dH; positive errors therefore mean b < 0: v_meas = 0.95 v.
VELOCITY_BIAS_FRACTION = -0.05

POINTS_THESIS = ("cccs-2p", "ii-2p", "ccpi-hg-2p", "kf-2p", "oj-2p")
POINTS_EXTRA = ("ccpi-hosm-2p", "cccj-2p")
LINES_THESIS = ("cccj-2l", "ii-2l", "ccpi-2l", "ekf-2l", "oj-2l")
TABLE_METRICS = (("conv_time_5pct_s", "conv_time_5pct_s_traj1", "conv 5% (s)"),
                 ("err_400ft_m", "err_400ft_m_traj1", "err 400ft"),
                 ("err_200ft_m", "err_200ft_m_traj1", "err 200ft"),
                 ("err_100ft_m", "err_100ft_m_traj1", "err 100ft"),
                 ("mean_err_100ft_m", "mean_err_100ft_m_all8", "mean 100ft/8"),
                 ("std_err_100ft_m", "std_err_100ft_m_all8", "std 100ft/8"))

#: With 5 px of noise the thesis "reduces the correction dynamics" (5.2.2.1); these are ours, and
#: the observers' noise options told the noise (issue 12): cccs-2p's y_a bias correction and eta-rate
#: saturation (its 6 s response: with them, slower was worse), ccpi-hosm-2p a larger Lipschitz
#: bound (L = 0.01 left it stuck 15-25 m off after noise pushed it: the derivative row corrects eta by
#: at most about a2 L / |Phi| per second), ii-2p its default lambda (with its unprojected state,
#: the halved lambda was worse).
#: The line observers (issue 12, ``visland study lines-5px``; module docstring of
#: :mod:`visland.estimation.lines`, "Image noise"): ccpi-2l and cccj-2l slower high-gain dynamics
#: (4.44-4.46: omega 0.7 and 1 rad/s instead of 2.5); oj-2l a slow output injection (h = 0.5/s), a
#: smaller identifier gain and its regressor at the prediction; ii-2l a slow measurement filter
#: without dynamic scaling (4.19, 4.27-4.28), a smaller lambda (4.23) and its eta unprojected;
#: ekf-2l its defaults.
SLOW_5PX_PARAMS = {
    "cccs-2p": {"noise_sigma_rad": 5.0 / 2472.0, "max_eta_rate": 0.3},
    "ccpi-hg-2p": {"response_time_s": 12.0},
    "cccj-2p": {"response_time_s": 12.0},
    "oj-2p": {"k_y": 1.5, "k_eta": 2.5e-4},
    "kf-2p": {"image_sigma_rad": 5.0 / 2472.0},
    "ccpi-hosm-2p": {"lipschitz": 0.1},
    "ccpi-2l": {"omega_rps": 0.7},
    "cccj-2l": {"omega_rps": 1.0},
    "oj-2l": {"k_filter": 0.5, "gain_alpha": 0.05, "regressor_at_measurement": False},
    "ii-2l": {"k_filter": 0.1, "c_scaling": 0.0, "gain_lambda": 0.003, "project_state": False},
}


@dataclass(frozen=True)
class Condition:
    """How the measurements are degraded (thesis 5.2.2; ECC'15 IV.B).

    Attributes
    ----------
    label : str
        The row's name in the tables.
    pixel_noise_px : float
        Corner noise, pixels (thesis 5.2.2.1).
    calibration_error_deg : float
        Camera mounting error, degrees (thesis 5.2.2.2).
    velocity_bias_fraction : float
        Relative IMU velocity bias (thesis 5.2.2.3).
    relative_noise : float
        Relative noise on the measured coordinates (ECC'15 IV.B: 0.01).
    params : dict
        Observer parameters per observer name.
    slope_pct : float
        Runway slope, percent.
    self_calibration : str
        ``"off"``, ``"check"`` or ``"apply"`` (:func:`visland.estimation.inputs.prepare_inputs`).
    """

    label: str
    pixel_noise_px: float = 0.0
    calibration_error_deg: float = 0.0
    velocity_bias_fraction: float = 0.0
    relative_noise: float = 0.0
    params: dict = field(default_factory=dict)
    slope_pct: float = 0.0
    self_calibration: str = "off"


@dataclass(frozen=True)
class StudySpec:
    """One study: which observers, scenarios and degradations, and which thesis table to compare.

    Attributes
    ----------
    name, title : str
        The study's name (``visland study NAME``) and its heading.
    observers : tuple of str
        SPEC observer names.
    conditions : tuple of Condition
        The degradations, one table row group each.
    scenarios : tuple of str
        Built-in scenarios flown.
    thesis_table : str, optional
        The thesis table compared with.
    kind : str
        How the study is run and tabulated (``"table"``, ``"std-along"``, ``"ecc"``,
        ``"calibration"``, ``"robustness"``).
    """

    name: str
    title: str
    observers: tuple
    conditions: tuple
    scenarios: tuple = THESIS_SCENARIOS
    thesis_table: str | None = None
    kind: str = "table"          # "table", "std-along", "ecc"


STUDIES = {
    "table-5.3": StudySpec("table-5.3", "ideal measurements, two points", POINTS_THESIS + POINTS_EXTRA,
                           (Condition("ideal"),), thesis_table="5.3"),
    "table-5.4": StudySpec("table-5.4", "ideal measurements, two lines", LINES_THESIS,
                           (Condition("ideal"),), thesis_table="5.4"),
    "table-5.6": StudySpec("table-5.6", "1 px Gaussian pixel noise, two points", POINTS_THESIS + POINTS_EXTRA,
                           (Condition("1 px", pixel_noise_px=1.0),), thesis_table="5.6"),
    "table-5.7": StudySpec("table-5.7", "5 px Gaussian pixel noise, two points (slower corrections)",
                           POINTS_THESIS + POINTS_EXTRA,
                           (Condition("5 px", pixel_noise_px=5.0, params=SLOW_5PX_PARAMS),), thesis_table="5.7"),
    "lines-5px": StudySpec("lines-5px", "5 px Gaussian pixel noise, two lines (slower corrections; no thesis table)",
                           LINES_THESIS,
                           (Condition("5 px", pixel_noise_px=5.0, params=SLOW_5PX_PARAMS),)),
    "table-5.8": StudySpec("table-5.8", "standard deviation of the error along trajectory 1",
                           POINTS_THESIS + POINTS_EXTRA,
                           (Condition("1px", pixel_noise_px=1.0),
                            Condition("5px", pixel_noise_px=5.0, params=SLOW_5PX_PARAMS)),
                           scenarios=("thesis-1",), thesis_table="5.8", kind="std-along"),
    "table-5.10": StudySpec("table-5.10", "0.5 deg camera calibration error, two points",
                            POINTS_THESIS + POINTS_EXTRA,
                            (Condition("0.5 deg", calibration_error_deg=0.5),), thesis_table="5.10"),
    "table-5.12": StudySpec("table-5.12", "5 % velocity bias (v_meas = 0.95 v), two points",
                            POINTS_THESIS + POINTS_EXTRA,
                            (Condition("5 % bias", velocity_bias_fraction=VELOCITY_BIAS_FRACTION),),
                            thesis_table="5.12"),
    "calibration": StudySpec(
        "calibration", "mount errors and runway slope, 1 px noise, self-calibration applied",
        ("ccpi-hg-2p", "ekf-2l", "kf-2p", "cccj-2l"),
        tuple(Condition(label, pixel_noise_px=1.0, calibration_error_deg=mount, slope_pct=slope,
                        self_calibration="apply")
              for label, mount, slope in (
                  ("pitch +0.5", (0.0, 0.5, 0.0), 0.0), ("pitch -0.5", (0.0, -0.5, 0.0), 0.0),
                  ("roll +0.5", (0.5, 0.0, 0.0), 0.0), ("roll -0.5", (-0.5, 0.0, 0.0), 0.0),
                  ("slope +1 %", (0.0, 0.0, 0.0), 1.0), ("slope -1 %", (0.0, 0.0, 0.0), -1.0),
                  ("p+0.5 r+0.5 s+1", (0.5, 0.5, 0.0), 1.0), ("p+0.5 r-0.5 s-1", (-0.5, 0.5, 0.0), -1.0),
                  ("p-0.5 r+0.5 s+1", (0.5, -0.5, 0.0), 1.0), ("p-0.5 r-0.5 s-1", (-0.5, -0.5, 0.0), -1.0))),
        kind="calibration"),
    "robustness": StudySpec("robustness", "one imperfection at a time: noise, frame rate, mount, slope, delay, "
                            "velocity bias", (), (), kind="robustness"),
    "ecc": StudySpec("ecc", "ECC'15: three landings, 1 % measurement noise", ("ecc-hg", "ecc-hosm"),
                     (Condition("1 % noise", relative_noise=0.01),), scenarios=ECC_SCENARIOS, kind="ecc"),
    "dickmanns": StudySpec("dickmanns", "seed 004: the 4D approach beside the thesis's observers, 1 px noise",
                           ("dickmanns-4d", "ekf-2l", "ccpi-hg-2p"), (Condition("1 px", pixel_noise_px=1.0),),
                           kind="dickmanns"),
    "academic": StudySpec("academic", "seed 001: single-point observer, academic example", (),
                          (Condition("ideal"), Condition("1 % noise", relative_noise=0.01)), scenarios=(),
                          kind="academic"),
}


def study_names() -> list:
    return list(STUDIES)


# --------------------------------------------------------------------------- simulation
@dataclass
class Case:
    """One simulated scenario under one condition, prepared for the observers."""

    scenario: str
    result: object
    prepared: PreparedInputs
    dh_true_m: np.ndarray      # at frames
    dx_true_m: np.ndarray
    dy_true_m: np.ndarray


def simulate_case(scenario_name: str, condition: Condition, seed: int = 0, heading: str = "dF",
                  fps: float = 25.0) -> Case:
    """Fly ``scenario_name`` with the degradations of ``condition`` and prepare the inputs.

    ``heading="dF"`` (default) takes the heading deviation from the measured d_F as ``visland
    estimate`` does; ``heading="truth"`` gives the observers the d_F of the noise-free image (the
    heading deviation known, as in the thesis's simulations), everything else unchanged.

    Parameters
    ----------
    scenario_name : str
        A built-in scenario.
    condition : Condition
        The degradations.
    seed : int, default 0
        Seed of the noise generators.
    heading : str, default "dF"
        ``"dF"`` or ``"truth"``.
    fps : float, default 25
        Camera frame rate, Hz.

    Returns
    -------
    Case
    """
    if heading not in ("dF", "truth"):
        raise ValueError(f"heading must be 'dF' or 'truth', got {heading!r}")
    from visland.scenarios import resolve_scenario
    from visland.sensors import ImuParams
    from visland.simulate import SimulationOptions, run_simulation
    options = SimulationOptions(fps=fps, pixel_noise_px=condition.pixel_noise_px,
                                calibration_error_deg=condition.calibration_error_deg,
                                imu=ImuParams(velocity_bias_fraction=condition.velocity_bias_fraction, seed=seed),
                                seed=seed)
    scenario = resolve_scenario(scenario_name)
    if condition.slope_pct:
        from visland.scenarios import with_runway
        scenario = with_runway(scenario, replace(scenario.runway, slope_pct=condition.slope_pct))
    result = run_simulation(scenario, options)
    features = FeatureSeries.from_ideal(result.features)
    if heading == "truth" and condition.pixel_noise_px:
        clean = run_simulation(scenario, replace(options, pixel_noise_px=0.0))
        features.dF_px = np.asarray(clean.features.dF_px, dtype=float).copy()
    prepared = prepare_inputs(InertialSeries.from_imu(result.imu), features, result.options.camera,
                              self_calibration=condition.self_calibration)
    if condition.relative_noise:
        prepared = _with_relative_noise(prepared, condition.relative_noise, seed)
    p = result.frames.p_runway_m
    aim = result.scenario.runway.aim_distance_m
    return Case(scenario_name, result, prepared, -p[:, 2], p[:, 0] - aim, p[:, 1])


def _with_relative_noise(prepared: PreparedInputs, fraction: float, seed: int) -> PreparedInputs:
    """ECC'15 and seed 001's "1 % random noise": each measured virtual coordinate times (1 + fraction n)."""
    rng = np.random.default_rng(seed + 7919)
    steps = list(prepared.steps)
    for j, inp in enumerate(steps):
        if inp.points_yv is not None:
            noisy = inp.points_yv * (1.0 + fraction * rng.standard_normal((2, 2)))
            steps[j] = replace(inp, points_yv=noisy)
    return replace(prepared, steps=steps)


def _run(name: str, case: Case, params: dict | None) -> tuple[ObserverRun, dict]:
    observer = make_observer(name, params or None)
    start = case.prepared.first_step_with(observer_features(name))
    if start is None:
        raise ValueError(f"{case.scenario}: no frame carries the features of {name}")
    frame = case.prepared.frame_of_step[start]
    dh0 = (1.0 + INITIAL_HEIGHT_ERROR) * case.dh_true_m[frame]
    run = run_observer(observer, case.prepared, dh0)
    metrics = run_metrics(run.t_s, case.dh_true_m, run.dh_m, start_t_s=run.start_t_s)
    return run, metrics


# --------------------------------------------------------------------------- formatting
def _fmt(value, width=10) -> str:
    if value is None:
        return " " * (width - 1) + "-"
    if isinstance(value, float) and not math.isfinite(value):
        return f"{'n/a':>{width}s}"
    magnitude = abs(value)
    if magnitude != 0 and (magnitude < 1e-3 or magnitude >= 1e4):
        return f"{value:>{width}.2e}"
    return f"{value:>{width}.4f}" if magnitude < 10 else f"{value:>{width}.2f}"


def _flag(ours, theirs) -> str:
    """'!' when ours is more than twice the thesis's in magnitude, '~' under half, ' ' otherwise."""
    if theirs is None or ours is None or not math.isfinite(ours):
        return " "
    a, b = abs(ours), abs(theirs)
    if b == 0:
        return " " if a == 0 else "!"
    if a > 2 * b:
        return "!"
    if a < 0.5 * b:
        return "~"
    return " "


# --------------------------------------------------------------------------- studies
def run_study(name: str, out_dir=None, seed: int = 0, heading: str = "dF", echo=print) -> dict:
    """Run study ``name``; print its table(s) with ``echo``; return the figures (the JSON line).

    ``heading``: "dF" (the heading deviation measured from the image, as ``visland estimate``) or
    "truth" (known, as in the thesis's simulations); see :func:`simulate_case`.

    Parameters
    ----------
    name : str
        One of :data:`STUDY_NAMES`.
    out_dir : str or Path, optional
        Folder for plots and study.json (default ``study-NAME``).
    seed : int, default 0
        Seed of the noise generators.
    heading : str, default "dF"
        As above.
    echo : callable, default print
        Where the tables go.

    Returns
    -------
    dict
    """
    if name not in STUDIES:
        raise ValueError(f"unknown study '{name}'; known: {', '.join(STUDIES)}")
    spec = STUDIES[name]
    out = Path(out_dir) if out_dir else None
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    if spec.kind == "academic":
        figures = _academic_study(spec, out, echo)
    elif spec.kind == "dickmanns":
        from visland.estimation.dickmanns_study import dickmanns_study
        figures = dickmanns_study(out, seed, echo)
    elif spec.kind == "ecc":
        figures = _ecc_study(spec, out, seed, echo, heading)
    elif spec.kind == "calibration":
        figures = _calibration_study(spec, seed, echo)
    elif spec.kind == "robustness":
        from visland.estimation.robustness import robustness_study
        figures = robustness_study(out, seed, echo)
    elif spec.kind == "std-along":
        figures = _std_along_study(spec, out, seed, echo, heading)
    else:
        figures = _table_study(spec, out, seed, echo, heading)
    figures = {"study": name, "heading": heading, **figures, "elapsed_s": round(time.perf_counter() - started, 2)}
    if out is not None:
        (out / "study.json").write_text(json.dumps(figures, indent=2, default=_json_default) + "\n")
    return figures


def _json_default(value):
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def _table_study(spec: StudySpec, out: Path | None, seed: int, echo, heading: str = "dF") -> dict:
    condition = spec.conditions[0]
    echo(f"study {spec.name}: {spec.title}")
    if spec.thesis_table:
        echo(f"thesis Table {spec.thesis_table}: {THESIS_CONDITIONS[spec.thesis_table][0]}")
    echo(f"scenarios {', '.join(spec.scenarios)}; observers start {INITIAL_HEIGHT_ERROR:.0%} above the true height; "
         f"heading deviation {'from the measured d_F' if heading == 'dF' else 'known (noise-free d_F)'}")
    per_scenario = {obs: {} for obs in spec.observers}
    runs_traj1 = {}
    timing = {obs: [] for obs in spec.observers}
    diverged: dict = {}            # observer -> {scenario: time it was cut off}
    case1 = None
    for k, scenario in enumerate(spec.scenarios):
        case = simulate_case(scenario, condition, seed=seed + k, heading=heading)
        if k == 0:
            case1 = case
        for obs in spec.observers:
            run, metrics = _run(obs, case, condition.params.get(obs))
            per_scenario[obs][scenario] = metrics
            if run.diverged:
                diverged.setdefault(obs, {})[scenario] = run.diverged_t_s
            timing[obs].append(run.step_time_s / max(run.n_steps, 1))
            if k == 0:
                runs_traj1[obs] = run
    results = {}
    for obs in spec.observers:
        traj1 = per_scenario[obs][spec.scenarios[0]]
        agg = aggregate_at_100ft(m["err_100ft_m"] for m in per_scenario[obs].values())
        results[obs] = {**{k: traj1[k] for k in ("conv_time_5pct_s", "conv_time_5pct_to_end_s", "err_400ft_m",
                                                 "err_200ft_m", "err_100ft_m", "std_err_along_m")},
                        "mean_err_100ft_m": agg["mean_err_100ft_m"], "std_err_100ft_m": agg["std_err_100ft_m"],
                        "err_100ft_m_by_scenario": {s: per_scenario[obs][s]["err_100ft_m"] for s in spec.scenarios},
                        "conv_time_5pct_s_by_scenario": {s: per_scenario[obs][s]["conv_time_5pct_s"]
                                                         for s in spec.scenarios},
                        "conv_time_5pct_to_end_s_by_scenario": {s: per_scenario[obs][s]["conv_time_5pct_to_end_s"]
                                                                for s in spec.scenarios},
                        "step_us": 1e6 * float(np.median(timing[obs]))}
    flags = _print_table(spec, results, echo)
    for obs, where in diverged.items():
        echo(f"{obs} diverged (cut off, its later figures n/a; visland.estimation.runner): "
             + ", ".join(f"{s} at {t:.2f} s" for s, t in where.items()))
    extra = {"diverged": diverged} if diverged else {}
    if spec.thesis_table and case1 is not None:
        extra["convergence_notes"] = _convergence_notes(spec, results, case1, runs_traj1, echo)
    if condition.calibration_error_deg:
        extra["calibration_axes"] = _calibration_axes(condition.calibration_error_deg, echo)
    plots = []
    if out is not None and case1 is not None:
        path = out / f"{spec.name}-error-vs-dx.png"
        _plot_error_vs_dx(case1, runs_traj1, f"{spec.name}: {spec.title} (thesis-1)", path)
        plots.append(str(path))
        echo(f"plot: {path}")
    return {"thesis_table": spec.thesis_table, "condition": condition.label,
            "observers": {o: {k: (json_ready(v) if not isinstance(v, dict) else {s: json_ready(x) for s, x in v.items()})
                              for k, v in r.items()} for o, r in results.items()},
            "thesis": {o: {m: thesis_value(spec.thesis_table, o, key) for m, key, _ in TABLE_METRICS}
                       for o in spec.observers},
            "flags": flags, "plots": plots, **extra}


#: Issue 12's targets for the calibration study: |mean| and std of dH - dH_hat at 100 ft (m) over
#: the eight scenarios, and the mounting error estimated within this of the truth 1 km out (deg).
CALIBRATION_TARGET_M = 0.3
CALIBRATION_TARGET_DEG = 0.05


def _calibration_study(spec: StudySpec, seed: int, echo) -> dict:
    """Each condition on the eight scenarios: dH error at 100 ft per observer (mean, std over the
    scenarios) and the self-calibration's error 1 km out (largest over the scenarios)."""
    echo(f"study {spec.name}: {spec.title}")
    echo(f"scenarios {', '.join(spec.scenarios)}; dH - dH_hat at 100 ft, mean/std over the scenarios (m); "
         f"target |mean| and std <= {CALIBRATION_TARGET_M:g} m; mounting estimate 1 km out within "
         f"{CALIBRATION_TARGET_DEG:g} deg (largest error over the scenarios)")
    header = (f"{'condition':16s}" + "".join(f" | {obs:>13s}" for obs in spec.observers)
              + f" | {'roll err':>8s} | {'pitch err':>9s} | {'slope err':>9s}")
    echo(header)
    echo("-" * len(header))
    figures = {}
    for condition in spec.conditions:
        errors = {obs: [] for obs in spec.observers}
        cal_err = []
        for k, scenario in enumerate(spec.scenarios):
            case = simulate_case(scenario, condition, seed=seed + k)
            for obs in spec.observers:
                _, metrics = _run(obs, case, condition.params.get(obs))
                errors[obs].append(metrics["err_100ft_m"])
            cal = case.prepared.calibration
            i = int(np.argmin(np.abs(case.dx_true_m + 1000.0)))
            truth = np.asarray(condition.calibration_error_deg if isinstance(condition.calibration_error_deg, tuple)
                               else (condition.calibration_error_deg,) * 3, dtype=float)
            cal_err.append([*(np.degrees(cal.mount_error_rad[i, :2]) - truth[:2]),
                            cal.slope_pct[i] - condition.slope_pct])
        cal_err = np.asarray(cal_err)
        row = {}
        cells = []
        for obs in spec.observers:
            agg = aggregate_at_100ft(errors[obs])
            ok = (abs(agg["mean_err_100ft_m"]) <= CALIBRATION_TARGET_M and agg["std_err_100ft_m"] <= CALIBRATION_TARGET_M)
            row[obs] = {"mean_err_100ft_m": agg["mean_err_100ft_m"], "std_err_100ft_m": agg["std_err_100ft_m"],
                        "err_100ft_m_by_scenario": dict(zip(spec.scenarios, map(json_ready, errors[obs]))),
                        "target_met": bool(ok)}
            cells.append(f"{agg['mean_err_100ft_m']:+6.2f}/{agg['std_err_100ft_m']:4.2f}{' ' if ok else '!'}")
        worst = np.abs(cal_err).max(axis=0)
        row["calibration_error_1km"] = {"roll_deg": float(worst[0]), "pitch_deg": float(worst[1]),
                                        "slope_pct": float(worst[2]),
                                        "target_met": bool(worst[:2].max() <= CALIBRATION_TARGET_DEG)}
        figures[condition.label] = row
        echo(f"{condition.label:16s}" + "".join(f" | {c:>13s}" for c in cells)
             + f" | {worst[0]:8.3f} | {worst[1]:9.3f} | {worst[2]:9.3f}")
    echo("(! misses the target)")
    return {"conditions": figures, "target_m": CALIBRATION_TARGET_M, "target_deg": CALIBRATION_TARGET_DEG}


#: Why 5 % convergence times differ from the thesis's by more than 2x, measured (docs/estimation.md,
#: "5 % convergence time on simulated measurements"); printed under a study's table with each run's figures.
#: "faster" for every study; the others by thesis table, for times slower than the thesis's or none.
CONVERGENCE_REASONS = {
    "faster": "faster than the thesis's: tuning. The thesis tuned II, EKF and OJ by iteration and gives no "
              "gains; ours converge while the observability index is high (the turn to the centreline): kf-2p "
              "assuming 10 px of image noise takes 4.4 s on ideal measurements, ii-2p with half our lambda "
              "2.6 s, ekf-2l with sigma_line 1e-2 3.0 s.",
    "5.6": "slower: once aligned the observability index of the corners falls 50-160 fold until about 2 km "
           "out (thesis 5.2.2.1: 20-45 s), and 1 px of noise keeps dH 5-16 % off there. The thesis's Table 5.6 "
           "convergence row is its Table 5.3 (ideal) row digit for digit, and its CCPI error at 400 ft "
           "(-6.17 m, 5.1 %) is outside the band: not a sustained time of its noisy run.",
    "5.7": "slower or none: the weakly observable stretch with 5 px of noise. The thesis's own Table 5.7 "
           "errors lie outside the band after its convergence times (EKF -7.46 m at 400 ft, CCCS 2.91 m at "
           "100 ft).",
    "5.10": "none: the 0.5 deg pitch error of the mounting costs ours metres to tens of metres at 100 ft "
            "(camera misalignment: issue 12).",
    "5.12": "the band's edge: a 5 % velocity bias makes every observer settle on dH_hat = 0.95 dH, so "
            "converged or not is decided by residuals far below a percent.",
}
#: Studies whose reason holds for times faster and slower than the thesis's alike.
CONVERGENCE_REASON_EITHER_WAY = ("5.12",)


def _convergence_notes(spec: StudySpec, results: dict, case: Case, runs: dict, echo) -> dict:
    """For each observer whose convergence time on thesis-1 is more than 2x off the thesis's (or none
    where the thesis has one): if slower, its last frame outside the band before 100 ft and the
    observability index before and after alignment; then the reasons (:data:`CONVERGENCE_REASONS`)."""
    from visland.estimation.metrics import CONVERGENCE_TOLERANCE, CONVERGENCE_WINDOW_END_FT
    notes = {}
    lines = []
    kinds = []
    below = np.nonzero(case.dh_true_m <= CONVERGENCE_WINDOW_END_FT * FT_TO_M)[0]
    end = int(below[0]) + 1 if below.size else len(case.dh_true_m)
    for obs, r in results.items():
        theirs = thesis_value(spec.thesis_table, obs, "conv_time_5pct_s_traj1")
        ours = r["conv_time_5pct_s"]
        if theirs is None or (math.isfinite(ours) and 0.5 * theirs <= ours <= 2.0 * theirs):
            continue
        if math.isfinite(ours) and ours < 0.5 * theirs:
            kinds.append(spec.thesis_table if spec.thesis_table in CONVERGENCE_REASON_EITHER_WAY else "faster")
            notes[obs] = {"kind": "faster"}
            lines.append(f"  {obs}: {ours:.2f} s against the thesis's {theirs:g} s")
            continue
        kinds.append(spec.thesis_table)
        run = runs[obs]
        t_rel = run.t_s - run.start_t_s
        rel = np.abs(case.dh_true_m - run.dh_m) / case.dh_true_m
        outside = np.nonzero(((rel > CONVERGENCE_TOLERANCE) | ~np.isfinite(rel)) & (t_rel >= 0)
                             & (np.arange(len(rel)) < end))[0]
        if not outside.size:
            continue
        k = int(outside[-1])
        first = (t_rel >= 0) & (t_rel < 10.0)
        later = (t_rel >= 15.0) & (t_rel <= t_rel[k])
        o_first = float(np.nanmedian(run.observability[first])) if np.isfinite(run.observability[first]).any() \
            else math.nan
        o_later = float(np.nanmedian(run.observability[later])) if np.isfinite(run.observability[later]).any() \
            else math.nan
        notes[obs] = {"kind": "slower" if math.isfinite(ours) else "none", "last_outside_t_s": float(t_rel[k]),
                      "dx_m": float(case.dx_true_m[k]), "dh_m": float(case.dh_true_m[k]),
                      "error_pct": float(100.0 * rel[k]) if np.isfinite(rel[k]) else None,
                      "observability_first_10s": o_first, "observability_15s_to_last_outside": o_later}
        lines.append(f"  {obs}: last outside 5 % at {t_rel[k]:.2f} s (dX {case.dx_true_m[k]:.0f} m, "
             f"{case.dh_true_m[k]:.1f} m high, "
             + (f"{100.0 * rel[k]:.1f} % off" if np.isfinite(rel[k]) else "no estimate")
             + f"); observability index median {o_first:.3g} in the first 10 s, {o_later:.3g} from 15 s to then")
    reasons = [CONVERGENCE_REASONS[k] for k in dict.fromkeys(kinds) if k in CONVERGENCE_REASONS]
    if notes:
        echo("5 % convergence times more than 2x off the thesis's (or none), on thesis-1:")
        for line in lines + [f"  why: {reason}" for reason in reasons]:
            echo(line)
        echo("")
    return {"observers": {o: {k: json_ready(v) for k, v in n.items()} for o, n in notes.items()},
            "reasons": reasons}


def _calibration_axes(error_deg: float, echo) -> dict:
    """ccpi-hg-2p on thesis-1 with the calibration error on one mounting axis at a time."""
    from visland.features import ideal_features
    from visland.scenarios import resolve_scenario
    from visland.sensors import camera_with_calibration_error
    from visland.simulate import run_simulation
    result = run_simulation(resolve_scenario("thesis-1"))
    dh = -result.frames.p_runway_m[:, 2]
    out = {}
    echo(f"one axis at a time (ccpi-hg-2p, thesis-1, {error_deg:g} deg): dH - dH_hat at 400/200/100 ft")
    for axis, vector in (("roll", (error_deg, 0, 0)), ("pitch", (0, error_deg, 0)), ("yaw", (0, 0, error_deg))):
        camera_true = camera_with_calibration_error(result.options.camera, vector)
        features = ideal_features(result.frames, result.scenario.runway, result.options.camera, camera_true=camera_true)
        prepared = prepare_inputs(InertialSeries.from_imu(result.imu), FeatureSeries.from_ideal(features),
                                  result.options.camera, self_calibration="off")
        run = run_observer(make_observer("ccpi-hg-2p"), prepared, (1.0 + INITIAL_HEIGHT_ERROR) * dh[0])
        m = run_metrics(run.t_s, dh, run.dh_m, start_t_s=run.start_t_s)
        out[axis] = {k: json_ready(m[k]) for k in ("err_400ft_m", "err_200ft_m", "err_100ft_m")}
        echo(f"  {axis:5s} {_fmt(m['err_400ft_m'])} {_fmt(m['err_200ft_m'])} {_fmt(m['err_100ft_m'])}")
    echo("")
    return out


def _print_table(spec: StudySpec, results: dict, echo) -> list:
    header = f"{'observer':13s}" + "".join(f" | {label:>21s}" for _, _, label in TABLE_METRICS)
    echo("")
    echo(f"conv 5%: {METRIC_DEFINITIONS['conv_time_5pct_s']}")
    echo("each cell: ours [thesis]   (! more than 2x the thesis in magnitude, ~ less than half; n/a: none)")
    echo(header)
    echo("-" * len(header))
    flags = []
    for obs, r in results.items():
        cells = []
        for key, thesis_key, label in TABLE_METRICS:
            ours = r[key]
            theirs = thesis_value(spec.thesis_table, obs, thesis_key) if spec.thesis_table else None
            mark = _flag(ours, theirs)
            if mark != " ":
                flags.append({"observer": obs, "metric": key, "ours": json_ready(ours), "thesis": theirs, "mark": mark})
            cells.append(f"{_fmt(ours)}{mark}[{_fmt(theirs, 9).strip():>9s}]")
        echo(f"{obs:13s}" + "".join(f" | {c:>21s}" for c in cells))
    echo("")
    return flags


def _std_along_study(spec: StudySpec, out: Path | None, seed: int, echo, heading: str = "dF") -> dict:
    echo(f"study {spec.name}: {spec.title} (thesis Table {spec.thesis_table})")
    echo("standard deviation of dH - dH_hat over the whole approach, from the observer's start (m)")
    header = f"{'observer':13s}" + "".join(f" | {c.label + ' ours [thesis]':>24s}" for c in spec.conditions)
    echo(header)
    echo("-" * len(header))
    results = {obs: {} for obs in spec.observers}
    flags = []
    plots = []
    for k, condition in enumerate(spec.conditions):
        case = simulate_case(spec.scenarios[0], condition, seed=seed, heading=heading)
        runs = {}
        for obs in spec.observers:
            run, metrics = _run(obs, case, condition.params.get(obs))
            results[obs][condition.label] = metrics["std_err_along_m"]
            runs[obs] = run
        if out is not None:
            path = out / f"{spec.name}-{condition.label}-error-vs-dx.png"
            _plot_error_vs_dx(case, runs, f"{spec.name}: {condition.label} noise (thesis-1)", path)
            plots.append(str(path))
    for obs in spec.observers:
        cells = []
        for condition in spec.conditions:
            ours = results[obs][condition.label]
            theirs = thesis_value(spec.thesis_table, obs, f"std_err_along_traj1_m_{condition.label}")
            mark = _flag(ours, theirs)
            if mark != " ":
                flags.append({"observer": obs, "condition": condition.label, "ours": ours, "thesis": theirs,
                              "mark": mark})
            cells.append(f"{_fmt(ours)}{mark}[{_fmt(theirs, 9).strip():>9s}]")
        echo(f"{obs:13s}" + "".join(f" | {c:>24s}" for c in cells))
    for p in plots:
        echo(f"plot: {p}")
    return {"thesis_table": spec.thesis_table,
            "observers": {o: {c: json_ready(v) for c, v in r.items()} for o, r in results.items()},
            "thesis": {o: {c.label: thesis_value(spec.thesis_table, o, f"std_err_along_traj1_m_{c.label}")
                           for c in spec.conditions} for o in spec.observers},
            "flags": flags, "plots": plots}


def _ecc_study(spec: StudySpec, out: Path | None, seed: int, echo, heading: str = "dF") -> dict:
    condition = spec.conditions[0]
    echo(f"study {spec.name}: {spec.title}")
    echo("ECC'15 gives figures, not tables: our errors at the usual heights (dH - dH_hat, dY - dY_hat, m)")
    header = (f"{'landing':8s} {'observer':9s} | {'conv 5% (s)':>11s} | {'dH 400ft':>9s} | {'dH 200ft':>9s} | "
              f"{'dH 100ft':>9s} | {'dY 400ft':>9s} | {'dY 100ft':>9s} | {'rms dH':>8s}")
    echo(header)
    echo("-" * len(header))
    figures = {}
    cases = []
    all_runs = []
    for k, scenario in enumerate(spec.scenarios):
        case = simulate_case(scenario, condition, seed=seed + k, heading=heading)
        runs = {}
        for obs in spec.observers:
            run, metrics = _run(obs, case, condition.params.get(obs))
            runs[obs] = run
            dy400 = error_at_height_of(case.dh_true_m, case.dy_true_m, run.dy_m, 400 * FT_TO_M)
            dy100 = error_at_height_of(case.dh_true_m, case.dy_true_m, run.dy_m, 100 * FT_TO_M)
            figures.setdefault(scenario, {})[obs] = {
                **{k2: json_ready(v) for k2, v in metrics.items()}, "dy_err_400ft_m": json_ready(dy400),
                "dy_err_100ft_m": json_ready(dy100)}
            echo(f"{scenario:8s} {obs:9s} | {_fmt(metrics['conv_time_5pct_s'], 11)} | {_fmt(metrics['err_400ft_m'], 9)} | "
                 f"{_fmt(metrics['err_200ft_m'], 9)} | {_fmt(metrics['err_100ft_m'], 9)} | {_fmt(dy400, 9)} | "
                 f"{_fmt(dy100, 9)} | {_fmt(metrics['rms_err_m'], 8)}")
        cases.append(case)
        all_runs.append(runs)
    plots = []
    if out is not None:
        for obs in spec.observers:
            path = out / f"ecc-{obs}-error-vs-dx.png"
            _plot_ecc(cases, [r[obs] for r in all_runs], obs, path)
            plots.append(str(path))
            echo(f"plot: {path}")
    return {"condition": condition.label, "landings": figures, "plots": plots}


def _academic_study(spec: StudySpec, out: Path | None, echo) -> dict:
    from visland.estimation.single_point import academic_example
    echo(f"study {spec.name}: {spec.title}")
    echo("x' = A x + B, y = (x1/x3, x2/x3); x(0) = (1, 1.5, 2.5), x_hat(0) = (0.4, 0.6, 1); "
         "xi = 0.99, omega = 7, alpha = 1")
    echo(f"{'condition':10s} | {'|x3 err|/x3 at 0.5 s':>21s} | {'1 s':>9s} | {'2 s':>9s} | {'5 s':>9s}")
    figures = {}
    results = {}
    for condition in spec.conditions:
        result = academic_example(noise_fraction=condition.relative_noise, seed=0)
        results[condition.label] = result
        errs = {f"rel_depth_err_{t:g}s": result.relative_depth_error_at(t) for t in (0.5, 1.0, 2.0, 5.0)}
        figures[condition.label] = errs
        echo(f"{condition.label:10s} | {errs['rel_depth_err_0.5s']:21.5f} | {errs['rel_depth_err_1s']:9.5f} | "
             f"{errs['rel_depth_err_2s']:9.5f} | {errs['rel_depth_err_5s']:9.5f}")
    target = figures["ideal"]["rel_depth_err_2s"]
    echo(f"target: x3 within 1 % of the truth 2 s after the start: {'met' if target < 0.01 else 'NOT met'} "
         f"({100 * target:.3f} %)")
    plots = []
    if out is not None:
        path = out / "academic-depth.png"
        _plot_academic(results, path)
        plots.append(str(path))
        echo(f"plot: {path}")
    return {"conditions": figures, "target_met": bool(target < 0.01), "plots": plots}


# --------------------------------------------------------------------------- plots
def _plot_error_vs_dx(case: Case, runs: dict, title: str, path: Path) -> None:
    """Two panels against dX: the error dH - dH_hat (linear, +-60 m) and its magnitude (log)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax_lin, ax_log) = plt.subplots(2, 1, figsize=(9, 7.5), sharex=True)
    for name, run in runs.items():
        error = case.dh_true_m - run.dh_m
        ax_lin.plot(case.dx_true_m, error, lw=0.8, label=name)
        ax_log.plot(case.dx_true_m, np.abs(error), lw=0.8, label=name)
    ax_lin.set_ylim(-60, 60)
    ax_lin.set_ylabel("dH - dH_hat (m)")
    ax_log.set_yscale("log")
    ax_log.set_ylim(1e-9, 1e3)
    ax_log.set_ylabel("|dH - dH_hat| (m)")
    ax_log.set_xlabel("dX (m)")
    for ax in (ax_lin, ax_log):
        for h in (400, 200, 100):
            i = np.nonzero(case.dh_true_m <= h * FT_TO_M)[0]
            if i.size:
                ax.axvline(case.dx_true_m[i[0]], color="0.6", lw=0.8, ls=":")
                if ax is ax_lin:
                    ax.text(case.dx_true_m[i[0]], 58, f"{h} ft", fontsize=8, va="top", ha="center")
        ax.grid(alpha=0.3)
    ax_log.legend(fontsize=8, ncol=4, loc="lower left")
    ax_lin.set_title(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def _plot_ecc(cases: list, runs: list, observer: str, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax_y, ax_h) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    for case, run in zip(cases, runs):
        ax_y.plot(case.dx_true_m, case.dy_true_m - run.dy_m, lw=1.0, label=case.scenario)
        ax_h.plot(case.dx_true_m, case.dh_true_m - run.dh_m, lw=1.0, label=case.scenario)
    for ax, label in ((ax_y, "dY - dY_hat (m)"), (ax_h, "dH - dH_hat (m)")):
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        ax.set_ylim(-20, 20) if ax is ax_y else ax.set_ylim(-60, 60)
    ax_h.set_xlabel("dX (m)")
    ax_y.set_title(f"{observer}: estimation error against dX, 1 % noise (as ECC'15 Fig. 4-5)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def _plot_academic(results: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 4.5))
    first = next(iter(results.values()))
    ax.plot(first.t_s, first.x[:, 2], "k", lw=1.5, label="x3 (truth)")
    for label, result in results.items():
        ax.plot(result.t_s, result.x_hat[:, 2], lw=1.0, label=f"x3_hat ({label})")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("depth x3")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("seed 001 academic example (eq. 14-16): depth estimate", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)
