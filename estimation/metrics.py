"""The seeds' accuracy metrics (thesis 5.2.1), reusable by ``estimate``, ``study``, ``process`` and ``compare``.

Definitions (thesis section 5.2.1, the bullet list under Figure 5.3; errors are ``dH - dH_hat``
in metres, as in its tables):

- **5 % convergence time**: the time the observer takes to converge to the true value with
  an estimation error below 5 % *for the rest of the approach*: the first time ``t`` after
  which ``|dH - dH_hat| <= 0.05 dH`` at every later sample, measured from the observer's start.
  Samples without an estimate count as outside the band. NaN if it never stays inside.
- **Error at 400, 200 and 100 ft**: ``dH - dH_hat`` when the true height first falls to the
  given height, linearly interpolated between the two samples around the crossing (the
  estimate is interpolated the same way). NaN if the approach never gets that low or has no
  estimate there.
- **Mean and standard deviation at 100 ft**: over a set of runs (the thesis: the eight
  scenarios of Table 5.2), of the 100 ft errors; population standard deviation (ddof = 0).
- **Standard deviation along the trajectory** (thesis Table 5.8): of ``dH - dH_hat`` over all
  samples with an estimate, from the observer's start to the end of the run.

Functions take plain arrays, so any run (simulated or a processed folder with truth.csv)
can be scored the same way.
"""
from __future__ import annotations

import math
from typing import Iterable, Sequence

import numpy as np

__all__ = ["FT_TO_M", "METRIC_HEIGHTS_FT", "convergence_time_s", "error_at_height", "run_metrics",
           "aggregate_at_100ft", "std_along_trajectory"]

FT_TO_M = 0.3048
METRIC_HEIGHTS_FT = (400.0, 200.0, 100.0)


def _validated(t_s, dh_true_m, dh_est_m):
    t = np.asarray(t_s, dtype=float)
    truth = np.asarray(dh_true_m, dtype=float)
    est = np.asarray(dh_est_m, dtype=float)
    if t.ndim != 1 or truth.shape != t.shape or est.shape != t.shape:
        raise ValueError(f"t_s, dh_true_m and dh_est_m must be 1-D arrays of one length, got shapes "
                         f"{t.shape}, {truth.shape}, {est.shape}")
    if t.size and np.any(np.diff(t) <= 0):
        raise ValueError("t_s must increase strictly")
    if not np.isfinite(truth).all():
        raise ValueError("dh_true_m holds a NaN or infinite value")
    return t, truth, est


def convergence_time_s(t_s, dh_true_m, dh_est_m, tolerance: float = 0.05, start_t_s: float | None = None) -> float:
    """5 % convergence time (see module docstring); ``start_t_s`` defaults to the first estimate."""
    t, truth, est = _validated(t_s, dh_true_m, dh_est_m)
    if not 0 < tolerance < 1:
        raise ValueError(f"tolerance must lie in (0, 1), got {tolerance!r}")
    has = np.isfinite(est)
    if not has.any():
        return math.nan
    if start_t_s is None:
        start_t_s = float(t[np.argmax(has)])
    inside = has & (np.abs(truth - np.where(has, est, 0.0)) <= tolerance * np.abs(truth))
    after = t >= start_t_s - 1e-9
    outside = np.nonzero(after & ~inside)[0]
    if outside.size == 0:
        return 0.0
    last_out = int(outside[-1])
    if last_out == len(t) - 1:
        return math.nan
    return float(t[last_out + 1] - start_t_s)


def error_at_height(dh_true_m, dh_est_m, height_m: float) -> float:
    """``dH - dH_hat`` where the true height first falls to ``height_m`` (interpolated)."""
    truth = np.asarray(dh_true_m, dtype=float)
    est = np.asarray(dh_est_m, dtype=float)
    below = np.nonzero(truth <= height_m)[0]
    if below.size == 0:
        return math.nan
    i = int(below[0])
    error = truth - est
    if i == 0:
        return float(error[0])
    h0, h1 = truth[i - 1], truth[i]
    w = (h0 - height_m) / (h0 - h1) if h0 != h1 else 1.0
    return float((1.0 - w) * error[i - 1] + w * error[i])


def std_along_trajectory(dh_true_m, dh_est_m) -> float:
    """Standard deviation of ``dH - dH_hat`` over the samples with an estimate (thesis Table 5.8)."""
    error = np.asarray(dh_true_m, dtype=float) - np.asarray(dh_est_m, dtype=float)
    error = error[np.isfinite(error)]
    return float(np.std(error)) if error.size else math.nan


def run_metrics(t_s, dh_true_m, dh_est_m, heights_ft: Sequence[float] = METRIC_HEIGHTS_FT,
                start_t_s: float | None = None) -> dict:
    """All single-run metrics: ``conv_time_5pct_s``, ``err_<h>ft_m`` per height, ``std_err_along_m``,
    ``rms_err_m`` (of the samples with an estimate), ``n_estimates``."""
    t, truth, est = _validated(t_s, dh_true_m, dh_est_m)
    out = {"conv_time_5pct_s": convergence_time_s(t, truth, est, start_t_s=start_t_s)}
    for h in heights_ft:
        out[f"err_{h:.0f}ft_m"] = error_at_height(truth, est, h * FT_TO_M)
    error = truth - est
    finite = np.isfinite(error)
    out["std_err_along_m"] = std_along_trajectory(truth, est)
    out["rms_err_m"] = float(np.sqrt(np.mean(error[finite] ** 2))) if finite.any() else math.nan
    out["n_estimates"] = int(finite.sum())
    return out


def aggregate_at_100ft(errors_m: Iterable[float]) -> dict:
    """Mean and population standard deviation of per-run 100 ft errors (thesis tables' last rows).

    Runs whose error is NaN (did not reach 100 ft, no estimate there) are excluded and counted.
    """
    values = np.asarray(list(errors_m), dtype=float)
    finite = values[np.isfinite(values)]
    return {"mean_err_100ft_m": float(np.mean(finite)) if finite.size else math.nan,
            "std_err_100ft_m": float(np.std(finite)) if finite.size else math.nan,
            "n_runs": int(finite.size), "n_missing": int(values.size - finite.size)}
