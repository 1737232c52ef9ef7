"""The seeds' accuracy metrics (thesis 5.2.1), reusable by ``estimate``, ``study``, ``process`` and ``compare``.

Definitions (thesis section 5.2.1, the bullet list under Figure 5.3; errors are ``dH - dH_hat``
in metres, as in its tables). :data:`METRIC_DEFINITIONS` holds the same sentences for the
files and pages people read (metrics.json, the HTML report, compare.md, the studies):

- **5 % convergence time** (``conv_time_5pct_s``): the thesis's "temps de convergence à 5% : cela
  correspond au temps que met l'observateur pour converger vers la valeur réelle avec une erreur
  d'estimation inférieure à 5% de manière prolongée le long de la trajectoire d'atterrissage
  No. 1" (section 5.2.1, under Figure 5.3, defining the first row of Tables 5.3-5.16). Its
  evaluation ends at 100 ft (the lowest height its tables read: the ILS decision heights of the
  section's footnote 3), so the window runs from the observer's start to the first sample at or
  below 100 ft true height (the whole run if it never gets that low). The time is the start of
  the last stay inside the band ``|dH - dH_hat| <= 0.05 dH`` that lasts to the end of the window
  ("de manière prolongée": sustained, not a passing crossing), measured from the observer's start.
  Samples without an estimate count as outside. NaN if the estimate is outside at the end of
  the window (not converged by 100 ft).
- **5 % convergence time to the end of the run** (``conv_time_5pct_to_end_s``): the same with
  the window running to the last sample. Stricter: below 100 ft 5 % of the height is a few
  decimetres, and a single late excursion (the threshold leaving the image) makes it NaN.
- **Error at 400, 200 and 100 ft**: ``dH - dH_hat`` when the true height first falls to the
  given height, linearly interpolated between the two samples around the crossing (the
  estimate is interpolated the same way). NaN if the approach never gets that low or has no
  estimate there. :func:`error_at_height_of` does the same for dY and dX.
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

__all__ = ["FT_TO_M", "METRIC_HEIGHTS_FT", "CONVERGENCE_TOLERANCE", "CONVERGENCE_WINDOW_END_FT",
           "METRIC_DEFINITIONS", "convergence_time_s", "error_at_height", "error_at_height_of", "errors_at_heights",
           "run_metrics",
           "aggregate_at_100ft", "std_along_trajectory"]

FT_TO_M = 0.3048
METRIC_HEIGHTS_FT = (400.0, 200.0, 100.0)
#: The band of the convergence time: |dH - dH_hat| <= 5 % of dH (thesis 5.2.1).
CONVERGENCE_TOLERANCE = 0.05
#: Where the thesis's evaluation ends (its lowest table height), hence its convergence window.
CONVERGENCE_WINDOW_END_FT = 100.0

#: One sentence per metric, for metrics.json, the HTML report, compare.md and the studies.
METRIC_DEFINITIONS = {
    "conv_time_5pct_s": (
        "seconds from the observer's start to the start of its last stay within |dH - dH_hat| <= 0.05 dH "
        "that lasts until the true height first falls to 100 ft (thesis 5.2.1: error under 5 % 'de manière "
        "prolongée', its evaluation ending at 100 ft); none if outside the band at 100 ft"),
    "conv_time_5pct_to_end_s": (
        "the same, the stay lasting to the last sample (stricter than the thesis: below 100 ft 5 % of dH is "
        "a few decimetres, and one late excursion leaves it undefined)"),
    "err_<h>ft_m": "dH - dH_hat (m) where the true height first falls to h ft, interpolated between samples",
    "std_err_along_m": "standard deviation of dH - dH_hat over the samples with an estimate (thesis Table 5.8)",
    "rms_err_m": "root mean square of dH - dH_hat over the samples with an estimate",
}


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


def convergence_time_s(t_s, dh_true_m, dh_est_m, tolerance: float = CONVERGENCE_TOLERANCE,
                       start_t_s: float | None = None,
                       until_height_m: float | None = CONVERGENCE_WINDOW_END_FT * FT_TO_M) -> float:
    """5 % convergence time (see the module docstring): the thesis's, over its window.

    Parameters
    ----------
    t_s, dh_true_m, dh_est_m : (n,) arrays
        Sample times (strictly increasing), true height and estimated height (NaN: no estimate).
    tolerance : float
        Half-width of the band, relative to the true height (0.05: the thesis's 5 %).
    start_t_s : float, optional
        The observer's start; defaults to the first estimate. The time is measured from it.
    until_height_m : float or None
        The window ends at the first sample whose true height is at or below this (default
        100 ft, the thesis's); None: the window runs to the last sample (the strict variant,
        ``conv_time_5pct_to_end_s``).

    Returns
    -------
    float
        Seconds from ``start_t_s`` to the first sample of the last stay in the band that lasts to
        the end of the window; 0.0 if inside throughout; NaN if outside at the end of the window
        or without any estimate.
    """
    t, truth, est = _validated(t_s, dh_true_m, dh_est_m)
    if not 0 < tolerance < 1:
        raise ValueError(f"tolerance must lie in (0, 1), got {tolerance!r}")
    if until_height_m is not None and not (math.isfinite(until_height_m) and until_height_m >= 0):
        raise ValueError(f"until_height_m must be a finite height >= 0 or None, got {until_height_m!r}")
    has = np.isfinite(est)
    if not has.any():
        return math.nan
    if start_t_s is None:
        start_t_s = float(t[np.argmax(has)])
    end = len(t)                                     # window: samples [.., end)
    if until_height_m is not None:
        below = np.nonzero(truth <= until_height_m)[0]
        if below.size:
            end = int(below[0]) + 1                  # the first sample at or below the height is in
    inside = has & (np.abs(truth - np.where(has, est, 0.0)) <= tolerance * np.abs(truth))
    window = (t >= start_t_s - 1e-9) & (np.arange(len(t)) < end)
    if not window.any():
        return math.nan
    outside = np.nonzero(window & ~inside)[0]
    if outside.size == 0:
        return 0.0
    last_out = int(outside[-1])
    if last_out == int(np.nonzero(window)[0][-1]):
        return math.nan
    return float(t[last_out + 1] - start_t_s)


def error_at_height_of(dh_true_m, q_true, q_est, height_m: float) -> float:
    """``q_true - q_est`` where the true height first falls to ``height_m`` (interpolated).

    The error of any deviation (dH, dY, dX) at the thesis's heights: linear interpolation between
    the two samples around the first crossing; the first sample's error if the run starts below;
    NaN if the height is never reached (or an estimate around the crossing is NaN).

    Parameters
    ----------
    dh_true_m : array_like, shape (n,)
        True height above the runway, metres (where the height is crossed).
    q_true, q_est : array_like, shape (n,)
        True and estimated deviation (dH, dY or dX), metres.
    height_m : float
        The height of the metric, metres.

    Returns
    -------
    float
    """
    dh = np.asarray(dh_true_m, dtype=float)
    error = np.asarray(q_true, dtype=float) - np.asarray(q_est, dtype=float)
    if dh.ndim != 1 or error.shape != dh.shape:
        raise ValueError(f"dh_true_m, q_true and q_est must be 1-D arrays of one length, got shapes "
                         f"{dh.shape}, {np.shape(q_true)}, {np.shape(q_est)}")
    below = np.nonzero(dh <= height_m)[0]
    if below.size == 0:
        return math.nan
    i = int(below[0])
    if i == 0:
        return float(error[0])
    h0, h1 = dh[i - 1], dh[i]
    w = (h0 - height_m) / (h0 - h1) if h0 != h1 else 1.0
    return float((1.0 - w) * error[i - 1] + w * error[i])


def error_at_height(dh_true_m, dh_est_m, height_m: float) -> float:
    """``dH - dH_hat`` where the true height first falls to ``height_m`` (interpolated).

    Parameters
    ----------
    dh_true_m, dh_est_m : array_like, shape (n,)
        True and estimated heights above the runway, metres.
    height_m : float
        The height of the metric, metres.

    Returns
    -------
    float
        Metres (NaN when the height is never reached).
    """
    return error_at_height_of(dh_true_m, dh_true_m, dh_est_m, height_m)


def errors_at_heights(dh_true_m, q_true, q_est, heights_ft: Sequence[float] = METRIC_HEIGHTS_FT) -> dict:
    """``{"err_<h>ft_m": q_true - q_est at h ft}`` for each of ``heights_ft`` (see :func:`error_at_height_of`).

    Parameters
    ----------
    dh_true_m : array_like, shape (n,)
        True height above the runway, metres.
    q_true, q_est : array_like, shape (n,)
        True and estimated deviation, metres.
    heights_ft : sequence of float, default (400, 200, 100)
        The thesis's heights, feet.

    Returns
    -------
    dict of str to float
    """
    return {f"err_{h:.0f}ft_m": error_at_height_of(dh_true_m, q_true, q_est, h * FT_TO_M) for h in heights_ft}


def std_along_trajectory(dh_true_m, dh_est_m) -> float:
    """Standard deviation of ``dH - dH_hat`` over the samples with an estimate (thesis Table 5.8).

    Parameters
    ----------
    dh_true_m, dh_est_m : array_like, shape (n,)
        True and estimated heights, metres (NaN: no estimate).

    Returns
    -------
    float
        Metres.
    """
    error = np.asarray(dh_true_m, dtype=float) - np.asarray(dh_est_m, dtype=float)
    error = error[np.isfinite(error)]
    return float(np.std(error)) if error.size else math.nan


def run_metrics(t_s, dh_true_m, dh_est_m, heights_ft: Sequence[float] = METRIC_HEIGHTS_FT,
                start_t_s: float | None = None) -> dict:
    """All single-run metrics: ``conv_time_5pct_s`` (the thesis's, to 100 ft), ``conv_time_5pct_to_end_s``,
    ``err_<h>ft_m`` per height, ``std_err_along_m``, ``rms_err_m`` (of the samples with an estimate),
    ``n_estimates``.

    Parameters
    ----------
    t_s : array_like, shape (n,)
        Frame times, seconds.
    dh_true_m, dh_est_m : array_like, shape (n,)
        True and estimated heights above the runway, metres (NaN: no estimate).
    heights_ft : sequence of float, default (400, 200, 100)
        Heights of the ``err_<h>ft_m`` metrics, feet.
    start_t_s : float, optional
        Time the observer started (convergence times count from it; default the first estimate).

    Returns
    -------
    dict of str to float
    """
    t, truth, est = _validated(t_s, dh_true_m, dh_est_m)
    out = {"conv_time_5pct_s": convergence_time_s(t, truth, est, start_t_s=start_t_s),
           "conv_time_5pct_to_end_s": convergence_time_s(t, truth, est, start_t_s=start_t_s, until_height_m=None)}
    out.update(errors_at_heights(truth, truth, est, heights_ft))
    error = truth - est
    finite = np.isfinite(error)
    out["std_err_along_m"] = std_along_trajectory(truth, est)
    out["rms_err_m"] = float(np.sqrt(np.mean(error[finite] ** 2))) if finite.any() else math.nan
    out["n_estimates"] = int(finite.sum())
    return out


def aggregate_at_100ft(errors_m: Iterable[float]) -> dict:
    """Mean and population standard deviation of per-run 100 ft errors (thesis tables' last rows).

    Runs whose error is NaN (did not reach 100 ft, no estimate there) are excluded and counted.

    Parameters
    ----------
    errors_m : iterable of float
        One 100 ft error per run, metres.

    Returns
    -------
    dict
        ``mean_err_100ft_m``, ``std_err_100ft_m`` (metres), ``n_runs`` used and ``n_missing``.
    """
    values = np.asarray(list(errors_m), dtype=float)
    finite = values[np.isfinite(values)]
    return {"mean_err_100ft_m": float(np.mean(finite)) if finite.size else math.nan,
            "std_err_100ft_m": float(np.std(finite)) if finite.size else math.nan,
            "n_runs": int(finite.size), "n_missing": int(values.size - finite.size)}
