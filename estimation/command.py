"""``visland estimate``: run observers on a folder's measurements and telemetry; write estimates.csv.

Reads (SPEC "File contracts"): ``DIR/telemetry.csv``, ``DIR/camera.json``, the measurements
(``--measurements FILE``, a ``measurements.csv``, or ``ideal``: ``DIR/labels.csv``) and, when
present, ``DIR/truth.csv`` (enables ``metrics.json`` and the default height guess).

Writes ``--out FILE`` (``estimates.csv``): the SPEC columns
``observer,t_s,dx_m,dy_m,dh_m,width_m,dpsi_deg,observability`` then ``coasting`` (1 when no
measurement corrected that frame: the observer ran on its model; numeric, so that
:func:`visland.contracts.read_estimates` reads the file unchanged); one row per observer per
frame, empty estimate cells before an observer's first measured frame. With truth,
``metrics.json`` beside it holds the seeds' metrics per observer
(:mod:`visland.estimation.metrics`).
"""
from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from visland.contracts import ESTIMATE_EXTRA_COLUMNS, json_ready
from visland.estimation.deviations import DEFAULT_AIM_DISTANCE_M
from visland.estimation.registry import make_observer, observer_class, observer_features, params_for_camera
from visland.userfiles import read_json_object, read_toml_object

__all__ = ["EstimateOptions", "estimate_folder", "load_observer_params", "ESTIMATE_EXTRA_COLUMNS"]



def check_initial_guess(initial_height_m: float | None, initial_error: float) -> None:
    """``--initial-height`` (None, or a plausible dh_m) and ``--initial-error`` (a fraction in
    (-0.9, 10)), one sentence each; shared by ``estimate`` and ``process``."""
    if initial_height_m is not None and not (math.isfinite(initial_height_m) and 0 < initial_height_m <= 30000):
        raise ValueError(f"--initial-height must be a positive number of metres up to 30000 (the plausible "
                         f"dh_m), got {initial_height_m!r}")
    if not (math.isfinite(initial_error) and -0.9 < initial_error < 10):
        raise ValueError(f"--initial-error must lie in (-0.9, 10), got {initial_error!r}")


@dataclass(frozen=True)
class EstimateOptions:
    """What ``visland estimate`` does with a folder (see the command's --help).

    Attributes
    ----------
    observers : tuple of str
        SPEC observer names.
    measurements : str, default "ideal"
        A ``measurements.csv`` path, or ``"ideal"`` for the folder's ``labels.csv``.
    initial_height_m : float, optional
        Initial height guess, metres (required without ``truth.csv``).
    initial_error : float, default 0.2
        With truth and no guess: start this fraction above the true height.
    aim_distance_m : float, default 320
        Aiming point distance past the threshold, metres.
    params_file : str, optional
        Observer parameters, TOML or JSON (:func:`load_observer_params`).
    self_calibration : str, default "check"
        ``"check"`` reports the mounting's self-calibration, ``"apply"`` corrects with it.
    time_offset_s : float, default 0
        Seconds added to the telemetry's times.
    """

    observers: tuple
    measurements: str = "ideal"
    initial_height_m: float | None = None
    initial_error: float = 0.2
    aim_distance_m: float = DEFAULT_AIM_DISTANCE_M
    params_file: str | None = None
    self_calibration: str = "check"
    time_offset_s: float = 0.0

    def __post_init__(self):
        if not (isinstance(self.time_offset_s, (int, float)) and math.isfinite(self.time_offset_s)
                and abs(self.time_offset_s) <= 60.0):
            raise ValueError(f"--time-offset must be a number of seconds within +-60, got {self.time_offset_s!r}")
        if self.self_calibration not in ("off", "check", "apply"):
            raise ValueError(f"self_calibration must be 'off', 'check' or 'apply', got {self.self_calibration!r}")
        if not self.observers:
            raise ValueError("--observer: give at least one observer name")
        for name in self.observers:
            observer_class(name)          # raises with the list of known names
        check_initial_guess(self.initial_height_m, self.initial_error)
        if not (math.isfinite(self.aim_distance_m) and 0 <= self.aim_distance_m <= 2000):
            raise ValueError(f"--aim-distance must lie in [0, 2000] m, got {self.aim_distance_m!r}")


def load_observer_params(path) -> dict:
    """Observer parameters from a TOML or JSON file: one table per observer name.

    Example (TOML)::

        [ccpi-hg-2p]
        response_time_s = 8.0
        damping = 0.8

    Parameters
    ----------
    path : str or Path
        The TOML or JSON file.

    Returns
    -------
    dict of str to dict
        Observer name -> its parameter fields (validated when the observer is made).
    """
    path = Path(path)
    what = "observer parameter file"
    data = read_toml_object(path, what) if path.suffix == ".toml" else read_json_object(path, what)
    out = {}
    for name, table in data.items():
        cls = observer_class(name)
        out[name] = cls.params_type.from_dict(table, source=f"{path} [{name}]")
    return out


def _read_inputs(folder: Path, measurements: str):
    from visland.camera import CameraModel
    from visland.contracts import read_labels, read_measurements, read_telemetry, read_truth
    from visland.estimation.inputs import FeatureSeries, InertialSeries
    from visland.limits import check_camera, check_pixels, check_telemetry_rate
    from visland.userfiles import check_input_file, check_input_folder
    check_input_folder(folder)
    camera = CameraModel.load(check_input_file(folder / "camera.json", "camera file"))
    check_camera(camera, str(folder / "camera.json"))
    telemetry = read_telemetry(folder / "telemetry.csv")
    if measurements == "ideal":
        path = folder / "labels.csv"
        if not path.exists():
            raise ValueError(f"{path}: --measurements ideal needs the folder's labels.csv (not found)")
        table = read_labels(path)
    else:
        path = Path(measurements)
        table = read_measurements(path)
    check_pixels(table, camera.width, camera.height, rows=(table["found"] > 0.5) if "found" in table else None)
    check_telemetry_rate(telemetry["t_s"], table["t_s"], str(folder / "telemetry.csv"), f"times of {path}")
    features = FeatureSeries.from_table(table)
    truth = None
    truth_path = folder / "truth.csv"
    if truth_path.exists():
        truth = read_truth(truth_path)
        if truth.n_rows != len(features) or not np.allclose(truth["t_s"], features.t_s, atol=1e-6):
            raise ValueError(f"{truth_path}: {truth.n_rows} rows whose times do not match the {len(features)} "
                             f"measurement frames of {path} (truth.csv has one row per frame)")
    return camera, InertialSeries.from_table(telemetry), features, truth, path


def estimate_folder(folder, options: EstimateOptions, out_path, echo=print, not_started: dict | None = None,
                    diverged: dict | None = None, calibration_out: dict | None = None,
                    restarted: dict | None = None) -> dict:
    """Run ``options.observers`` on ``folder``; write ``out_path`` (and metrics.json with truth).

    Returns the metrics per observer (empty without truth). An observer that cannot start
    (no frame carries the features it needs) still has its rows in ``out_path``, every estimate
    cell empty and coasting = 1; why it did not start is echoed and, when ``not_started`` is a
    dict, stored there under its name. An observer that diverged (cut off by
    :func:`visland.estimation.runner.run_observer`) is echoed likewise and, when ``diverged`` is a
    dict, its sentence stored there; an observer restarted after a long gap, its sentences in
    ``restarted`` (a list per name). The mounting's self-calibration (``options.self_calibration``
    "check" or "apply") is echoed and, when ``calibration_out`` is a dict, its summary and sentence
    stored there (``summary``, ``describe``).

    Parameters
    ----------
    folder : str or Path
        A folder with telemetry.csv and camera.json (and truth.csv, labels.csv).
    options : EstimateOptions
        What to run.
    out_path : str or Path
        The ``estimates.csv`` to write.
    echo : callable, default print
        Where the progress lines go.
    not_started, diverged, calibration_out, restarted : dict, optional
        Filled as described above.

    Returns
    -------
    dict
        Metrics per observer name (:func:`visland.estimation.metrics.run_metrics`).
    """
    from visland.contracts import ESTIMATE_COLUMNS, atomic_write_text, write_csv
    from visland.estimation.inputs import prepare_inputs
    from visland.estimation.metrics import METRIC_DEFINITIONS, run_metrics
    from visland.estimation.runner import run_observer

    folder = Path(folder)
    out_path = Path(out_path)
    if out_path.exists() and out_path.is_dir():
        raise ValueError(f"--out {out_path}: is a folder, expected the estimates.csv file to write")
    if not out_path.parent.exists():
        raise ValueError(f"--out {out_path}: folder {out_path.parent} does not exist")
    params = load_observer_params(options.params_file) if options.params_file else {}
    camera, inertial, features, truth, meas_path = _read_inputs(folder, options.measurements)
    if options.time_offset_s:
        # onto the frames' clock (as process --time-offset): a frame stamped t was exposed when the
        # telemetry stamped t - S was true, and the observers are corrected at that moment
        inertial = replace(inertial, t_s=inertial.t_s + float(options.time_offset_s))
    prepared = prepare_inputs(inertial, features, camera, self_calibration=options.self_calibration)
    calibration = prepared.calibration
    if calibration is not None and calibration_out is not None:
        calibration_out["summary"] = json_ready(calibration.summary())
        calibration_out["describe"] = calibration.describe()
    if calibration is not None:
        echo(calibration.describe() + ("" if calibration.applied or calibration.problem
                                        else " (reported only: --self-calibration applies it)"))
    n_points = int(prepared.points_ok.sum())
    n_lines = int(prepared.lines_ok.sum())
    echo(f"{len(features)} frames from {meas_path}: {n_points} with both threshold corners, {n_lines} with both "
         f"edges; {len(prepared)} steps at the inertial rate")
    dh_true = truth["dh_m"] if truth is not None else None
    columns = {c: [] for c in ESTIMATE_COLUMNS + ESTIMATE_EXTRA_COLUMNS}
    metrics = {}
    for name in options.observers:
        start = prepared.first_step_with(observer_features(name))
        if start is None:
            why = _why_not_started(prepared, observer_features(name))
            echo(f"{name}: no estimates: {why}")
            if not_started is not None:
                not_started[name] = why
            _append_empty_rows(columns, name, prepared.frame_t_s)
            continue
        frame = prepared.frame_of_step[start]
        if options.initial_height_m is not None:
            dh0 = options.initial_height_m
        elif dh_true is not None:
            dh0 = (1.0 + options.initial_error) * dh_true[frame]
        else:
            raise ValueError("no truth.csv in the folder: give the initial height guess with --initial-height M")
        # image noise given in pixels means pixels of this camera (registry.params_for_camera)
        chosen = params_for_camera(name, 0.5 * (camera.fx + camera.fy), params.get(name))
        run = run_observer(make_observer(name, chosen), prepared, dh0, options.aim_distance_m)
        for f in range(len(run)):
            columns["observer"].append(name)
            columns["t_s"].append(run.t_s[f])
            columns["dx_m"].append(run.dx_m[f])
            columns["dy_m"].append(run.dy_m[f])
            columns["dh_m"].append(run.dh_m[f])
            columns["width_m"].append(run.width_m[f])
            columns["dpsi_deg"].append(math.degrees(run.dpsi_rad[f]) if np.isfinite(run.dh_m[f]) else math.nan)
            columns["observability"].append(run.observability[f])
            columns["coasting"].append(int(bool(run.coasting[f])))
            for key in ESTIMATE_EXTRA_COLUMNS[1:]:
                columns[key].append(run.extras[key][f] if key in run.extras else math.nan)
        n_coast = int(np.sum(run.coasting & np.isfinite(run.dh_m)))
        reasons = {}
        for f in np.nonzero(run.coasting & np.isfinite(run.dh_m))[0]:
            reasons[run.reason[f]] = reasons.get(run.reason[f], 0) + 1
        started = run.t_s >= run.start_t_s - 1e-9
        n_withheld = int(np.sum(started & ~np.isfinite(run.dh_m)))
        line = (f"{name}: started at t = {run.start_t_s:.2f} s from dH0 = {run.dh0_m:.1f} m; "
                f"{n_coast} frames coasted{' (' + ', '.join(f'{n} {r}' for r, n in reasons.items()) + ')' if reasons else ''}; "
                + (f"{n_withheld} frames withheld (a long gap without measurement, or no height); "
                   if n_withheld else "") +
                f"{1e6 * run.step_time_s / max(run.n_steps, 1):.0f} us/step")
        for note in run.notes:
            echo(f"{name}: {note}")
        if run.restarts and restarted is not None:
            restarted[name] = list(run.restarts)
        if run.diverged:
            echo(f"{name}: {run.diverged}")
            if diverged is not None:
                diverged[name] = run.diverged
        if dh_true is not None:
            m = run_metrics(run.t_s, dh_true, run.dh_m, start_t_s=run.start_t_s)
            m.update({"start_t_s": run.start_t_s, "dh0_m": run.dh0_m, "n_frames": len(run), "n_coasting": n_coast,
                      "n_withheld": n_withheld,
                      "diverged_t_s": run.diverged_t_s if run.diverged else None,
                      "coasting_reasons": reasons, "params": run.params})
            if run.notes:
                m["notes"] = list(run.notes)
            metrics[name] = m
            line += (f"; conv 5% {m['conv_time_5pct_s']:.2f} s (to 100 ft), dH err 400/200/100 ft "
                     f"{m['err_400ft_m']:+.3f}/{m['err_200ft_m']:+.3f}/{m['err_100ft_m']:+.3f} m")
        echo(line)
    write_csv(out_path, columns, ESTIMATE_COLUMNS + ESTIMATE_EXTRA_COLUMNS)
    echo(f"wrote {out_path} ({len(columns['observer'])} rows)")
    if metrics:
        metrics_path = out_path.parent / "metrics.json"
        doc = {"definitions": {"source": "visland.estimation.metrics (thesis 5.2.1): errors are dH - dH_hat in "
                                         "metres; NaN (null) where a metric has no value",
                               **METRIC_DEFINITIONS},
               "measurements": _path_from(meas_path, metrics_path.parent), "observers": json_ready(metrics)}
        if calibration is not None:
            doc["self_calibration"] = json_ready(calibration.summary())
        atomic_write_text(metrics_path, json.dumps(doc, indent=2) + "\n")
        echo(f"wrote {metrics_path}")
    return metrics


def _why_not_started(prepared, features: str) -> str:
    """One sentence: no frame carries ``features``, and the most frequent reasons the frames give."""
    counts: dict = {}
    for reason in prepared.frame_reason:
        # one count per cause, not per frame: the frame's own number and file name are dropped
        reason = re.sub(r"frame \d+( \([^)]*\))?: ", "", str(reason)) or f"no usable {features}"
        reason = reason if len(reason) <= 160 else reason[:157] + "..."
        counts[reason] = counts.get(reason, 0) + 1
    top = sorted(counts.items(), key=lambda item: -item[1])[:3]
    n = len(prepared.frame_reason)
    listed = "; ".join(f"{count} of {n} frames: {reason}" for reason, count in top)
    return f"no frame carries usable {features} ({listed})"


def _append_empty_rows(columns: dict, name: str, frame_t_s) -> None:
    """Rows of an observer that never started: one per frame, no estimate, coasting."""
    for t_s in frame_t_s:
        for key in columns:
            columns[key].append(math.nan)
        columns["observer"][-1] = name
        columns["t_s"][-1] = float(t_s)
        columns["coasting"][-1] = 1


def _path_from(path: Path, folder: Path) -> str:
    """``path`` relative to ``folder`` when it lies inside it (a run folder stays valid when moved
    or renamed), else as given."""
    try:
        return str(path.resolve().relative_to(folder.resolve()))
    except ValueError:
        return str(path)
