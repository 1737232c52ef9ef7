"""The clock offset between a recording's frames and its telemetry (issue 15 item 4).

Real recordings do not share a clock: the telemetry of a video is offset by a fraction of a
second to seconds. Convention: the offset ``S`` is *added to the telemetry's times* to put them
on the frames' clock (``--time-offset S``): a telemetry row stamped ``tau`` describes the moment
the frames stamp ``tau + S``.

:func:`estimate_time_offset` measures ``S`` from the data: the roll angle seen in the frames
(the slope of the visible horizon, :func:`visland.detection.attitude.visible_horizon`, which
does not depend on the runway or the haze) must follow the telemetry's roll. The roll series of
the frames is compared with the telemetry's, shifted by every candidate ``S``; a difference
that is constant (a camera mounted with a roll error) or drifts linearly over the record is
allowed: the visible horizon is the edge of hazed terrain a few to tens of kilometres away, not
the horizon at infinity, and its tilt changes slowly with the aircraft's height and heading
(measured on visland's 512 px thesis approaches against the true roll: residuals of 0.05-0.11
deg correlated over seconds, a straight-line trend in time removing a third of their variance
on thesis-6). A slow bias left in the comparison is confused with a shift of the telemetry
wherever the roll rate keeps one sign for a while; fitting the drift took the eight H.264
thesis approaches' offset errors from an RMS of 18 ms (worst 27 ms) to 12 ms (worst 28 ms, 7 of
8 within 20 ms), and the cut at three robust sigmas (below) to 6 ms (worst 11 ms, all eight). A faster drift (a quadratic in time) is not modelled: it takes the roll
manoeuvres' own signal (thesis-8: 47 ms off).

The comparison is robust: a frame's horizon is sometimes another line (a cloud bank, the
terrain's far edge; seen on visland's own 512 px approaches, episodes of seconds 3 to 13 deg
off, while the rest agree within 0.05-0.15 deg), so each frame's difference, centred on the
drift fitted to the frames that follow, costs its square up to a limit and no more (a truncated
quadratic), and ``S`` minimises the sum. The limit is first :data:`INLIER_DEG`, then
:data:`K_SIGMA` robust sigmas of the differences that follow (1.4826 times their median absolute
deviation, at least :data:`MIN_LIMIT_DEG`), and ``S`` is searched again within
:data:`REFINE_S` of the previous one, :data:`PASSES` times at most: a horizon that goes wrong
slowly (before it jumps to a cloud bank it is often 0.3-0.6 deg off for seconds, 5-8 of its own
sigmas) stays inside a fixed 0.5 deg limit and pulls ``S`` wherever the roll rate is high
(thesis-1 at 512 px: the first 3 s, 0.3-0.6 deg off while the roll rate is 4-12 deg/s, took
the offset 28 ms early). A cut at three sigmas is the usual one for Gaussian noise (0.3 % of
the frames that do follow are cut). Its uncertainty is the larger of the least-squares one over the
inlier frames, ``sigma_residual / sqrt(sum(roll_rate^2))`` widened for residuals correlated
from frame to frame, and a block jackknife (the estimate repeated without each
:data:`BLOCK_S`-second stretch of frames), which also sees errors that follow the flight.
Without roll motion (straight and level), or with a horizon too poor to follow the roll, the
estimate is refused.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["TimeOffset", "estimate_time_offset", "offset_from_rolls", "MAX_OFFSET_S"]

#: Offsets searched, seconds either side of zero, and the search step.
MAX_OFFSET_S = 2.0
STEP_S = 0.002
#: Most frames read for the estimate, spread evenly: the roll seen in a frame costs about 0.35 s
#: of CPU (the horizon's fan of 142 turned 512 px images, one OpenCV thread), and on the 512 px
#: thesis approaches reading every second frame gives the same offsets within 2 ms as every frame.
MAX_FRAMES = 150
#: An estimate less certain than this (one sigma, seconds) is not used.
MAX_SIGMA_S = 0.1
#: A frame whose roll differs from the telemetry's (less the fitted constant and drift) by more
#: than this is not following it: its cost stops growing there (deg).
INLIER_DEG = 0.5
#: After the first search, the cut is this many robust sigmas of the differences that follow...
K_SIGMA = 3.0
#: ...but never below this (deg): a horizon measured better than this is not expected, and the
#: cut must not close on noise-free series.
MIN_LIMIT_DEG = 0.02
#: Searches with a cut from the previous one's residuals, each within this of the previous
#: offset (s); they stop when the cut no longer changes (within 1 %).
PASSES = 3
REFINE_S = 0.2
#: Length of the stretches of frames left out in turn by the jackknife (s): longer than the
#: horizon's own correlated errors (seconds). On the eight thesis approaches' cached horizons
#: (H.264, 512 and 1024 px, telemetry 0.3 s behind) the worst error was 4.3 sigmas with 2 s
#: stretches (thesis-8 at 1024 px: 30 ms off, sigma 7 ms), 2.2 with 3 s and 1.7 with 4 s (sigma
#: 17 ms); the worst over the sixteen, 2.6 sigmas (thesis-3 at 1024 px: 10 ms off, sigma 4 ms).
#: The offsets do not change.
BLOCK_S = 4.0


@dataclass(frozen=True)
class TimeOffset:
    """The estimated offset of the telemetry's clock against the frames'.

    Attributes
    ----------
    offset_s : float
        Seconds to add to the telemetry's times (``--time-offset``).
    sigma_s : float
        One-sigma uncertainty, seconds: the larger of the least-squares one over the inlier
        frames (widened by their residuals' frame-to-frame correlation) and the block jackknife's.
    frames_used : int
        Frames whose horizon gave a roll.
    residual_deg : float
        RMS roll difference between the inlier frames and the shifted telemetry, degrees.
    inliers : int
        Frames whose roll follows the shifted telemetry's within the final cut (module docstring).
    """

    offset_s: float
    sigma_s: float
    frames_used: int
    residual_deg: float
    inliers: int = 0


def estimate_time_offset(source, max_offset_s: float = MAX_OFFSET_S) -> TimeOffset:
    """Estimate the telemetry-to-frames clock offset of a :class:`visland.datasets.sources.FrameSource`.

    Parameters
    ----------
    source : visland.datasets.sources.FrameSource
        Frames with their times, camera and telemetry (its ``roll_deg`` is compared with the
        roll of the horizon seen in up to :data:`MAX_FRAMES` frames).
    max_offset_s : float, default MAX_OFFSET_S
        Largest offset searched, seconds, either way.

    Returns
    -------
    TimeOffset

    Raises
    ------
    ValueError
        One sentence when the frames show too little roll motion, or too few horizons, for the
        offset to be known within :data:`MAX_SIGMA_S`.
    """
    from visland.detection.attitude import attitude_from_horizon, visible_horizon
    from visland.folder import ignored_pixels, scene_frame

    camera = source.camera
    telemetry = source.telemetry
    n = len(source.times_s)
    step = max(1, int(math.ceil(n / MAX_FRAMES)))
    ignored = ignored_pixels(camera)
    times, rolls = [], []
    for index, image, _ in source.frames(gray=True):
        if index % step or image is None:
            continue
        found = visible_horizon(scene_frame(image, camera), ignored)
        if found is None:
            continue
        roll, _ = attitude_from_horizon(camera, found[0], found[1])
        times.append(float(source.times_s[index]))
        rolls.append(roll)
    if len(times) < 10:
        raise ValueError(f"{source.name}: a horizon was seen in {len(times)} of the frames examined; the clock "
                         "offset cannot be estimated (give --time-offset)")
    t_tel = np.asarray(telemetry["t_s"], float)
    roll_tel = np.unwrap(np.radians(np.asarray(telemetry["roll_deg"], float)))
    return offset_from_rolls(source.name, np.asarray(times), np.unwrap(np.asarray(rolls)), t_tel, roll_tel, max_offset_s)


def offset_from_rolls(name: str, times, rolls, t_tel, roll_tel, max_offset_s: float = MAX_OFFSET_S) -> TimeOffset:
    """The clock offset from the roll seen in the frames and the telemetry's roll (module docstring).

    Parameters
    ----------
    name : str
        The recording, for the messages.
    times : ndarray, shape (n,)
        Frame times on the frames' clock, s.
    rolls : ndarray, shape (n,)
        Roll of the visible horizon in those frames, rad (unwrapped).
    t_tel, roll_tel : ndarray, shape (m,)
        The telemetry's times on its own clock (s, increasing) and roll (rad, unwrapped).
    max_offset_s : float, default MAX_OFFSET_S
        Largest offset searched, seconds, either way.

    Returns
    -------
    TimeOffset

    Raises
    ------
    ValueError
        As :func:`estimate_time_offset`.
    """
    offsets = np.arange(-max_offset_s, max_offset_s + STEP_S / 2, STEP_S)
    limit = math.radians(INLIER_DEG)
    offset = _best_offset(times, rolls, t_tel, roll_tel, offsets, limit)
    if offset is None:
        raise ValueError(f"{name}: the telemetry does not cover the frames at any offset within "
                         f"+-{max_offset_s:g} s")
    for _ in range(PASSES):
        cut = _sigma_cut(_without_drift(times, rolls - np.interp(times - offset, t_tel, roll_tel), limit), limit)
        if abs(cut - limit) <= 0.01 * limit:
            break
        limit = cut
        near = offset + np.arange(-REFINE_S, REFINE_S + STEP_S / 2, STEP_S)
        found = _best_offset(times, rolls, t_tel, roll_tel, near[np.abs(near) <= max_offset_s], limit)
        offset = offset if found is None else found
    difference = _without_drift(times, rolls - np.interp(times - offset, t_tel, roll_tel), limit)
    inliers = np.abs(difference) < limit
    rate = np.interp(times - offset, t_tel, np.gradient(roll_tel, t_tel))[inliers]
    # what the drift's two terms cannot absorb of the sensitivity to the offset
    basis = _drift_basis(times[inliers])
    rate = rate - basis @ np.linalg.lstsq(basis, rate, rcond=None)[0]
    r = difference[inliers]
    residual = float(np.sqrt(np.mean(r ** 2))) if r.size else math.inf
    sigma = residual / math.sqrt(max(float(np.sum(rate ** 2)), 1e-30))
    # residuals that follow each other (a horizon biased for seconds by clouds or terrain) carry
    # fewer independent samples than frames: widen sigma by sqrt((1 + rho) / (1 - rho)), rho
    # their lag-one correlation
    rho = float(np.clip(np.dot(r[:-1], r[1:]) / max(float(np.dot(r, r)), 1e-30), 0.0, 0.99)) if len(r) > 2 else 0.0
    sigma *= math.sqrt((1.0 + rho) / (1.0 - rho))
    moving = float(np.sqrt(np.mean(rate ** 2))) if rate.size else 0.0
    if int(inliers.sum()) >= 10 and sigma <= MAX_SIGMA_S:
        sigma = max(sigma, _jackknife_sigma(times, rolls, t_tel, roll_tel, offset, limit))
    if not sigma <= MAX_SIGMA_S or int(inliers.sum()) < 10:
        spread = (f"one sigma {sigma:.2f} s, {int(inliers.sum())} of {len(times)} horizons following the telemetry's "
                  f"roll within {math.degrees(limit):.2g} deg" if moving > math.radians(0.05) else "no roll motion at all")
        raise ValueError(f"{name}: the clock offset cannot be fixed ({spread}): too little roll motion "
                         "(straight and level flight says nothing) or a horizon the frames do not show clearly; "
                         "give --time-offset")
    return TimeOffset(offset_s=float(offset), sigma_s=float(sigma), frames_used=len(times), residual_deg=math.degrees(residual),
                      inliers=int(inliers.sum()))


def _best_offset(times, rolls, t_tel, roll_tel, offsets, limit: float) -> float | None:
    """The offset among ``offsets`` minimising the quadratic cost truncated at ``limit`` (rad;
    module docstring), refined by a parabola through its neighbours; None when the telemetry
    never covers 80 % of the frames."""
    c2 = limit ** 2
    costs = np.full(len(offsets), np.inf)
    for k, offset in enumerate(offsets):
        # telemetry on the frames' clock: stamped tau, it happened at tau + offset
        inside = (times >= t_tel[0] + offset) & (times <= t_tel[-1] + offset)
        if inside.sum() < 0.8 * len(times):
            continue
        difference = _without_drift(times[inside], rolls[inside] - np.interp(times[inside] - offset, t_tel, roll_tel),
                                    limit)
        # frames outside the telemetry cost as much as an outlier, so that coverage does not pay
        costs[k] = float(np.sum(np.minimum(difference ** 2, c2)) + c2 * (len(times) - inside.sum()))
    if not np.isfinite(costs).any():
        return None
    best = int(np.argmin(costs))
    offset = float(offsets[best])
    if 0 < best < len(offsets) - 1 and np.isfinite(costs[best - 1]) and np.isfinite(costs[best + 1]):
        a, b, c = costs[best - 1], costs[best], costs[best + 1]
        if a - 2 * b + c > 0:
            step = offsets[1] - offsets[0]
            offset += float(np.clip(0.5 * (a - c) / (a - 2 * b + c), -0.5, 0.5)) * step
    return offset


def _drift_basis(times) -> np.ndarray:
    """Columns 1 and the time scaled to [-0.5, 0.5] over ``times``: a constant and a linear drift."""
    span = float(np.ptp(times)) if len(times) else 0.0
    u = (times - float(np.mean(times))) / span if span > 0 else np.zeros_like(times)
    return np.column_stack([np.ones_like(times), u])


def _without_drift(times, difference, limit: float) -> np.ndarray:
    """``difference`` (rad, frames' roll minus the shifted telemetry's) less its constant and
    linear drift, fitted to the frames that follow it: centred on the median first, then three
    least-squares fits to the frames within ``limit`` (rad) of the previous fit."""
    residual = difference - np.median(difference)
    basis = _drift_basis(times)
    for _ in range(3):
        follow = np.abs(residual) < limit
        if int(follow.sum()) < 3:
            break
        coefficients = np.linalg.lstsq(basis[follow], difference[follow], rcond=None)[0]
        residual = difference - basis @ coefficients
    return residual


def _sigma_cut(residual, limit: float) -> float:
    """The next cut (rad): :data:`K_SIGMA` robust sigmas (1.4826 median absolute deviations) of
    the residuals within ``limit``, at least :data:`MIN_LIMIT_DEG` and at most ``limit``."""
    follow = residual[np.abs(residual) < limit]
    if follow.size < 10:
        return limit
    sigma = 1.4826 * float(np.median(np.abs(follow - np.median(follow))))
    return float(np.clip(K_SIGMA * sigma, math.radians(MIN_LIMIT_DEG), limit))


def _jackknife_sigma(times, rolls, t_tel, roll_tel, offset: float, limit: float) -> float:
    """Block jackknife standard error of the offset: re-estimated without each :data:`BLOCK_S`
    stretch of frames (searched within 0.2 s of ``offset``, the cost truncated at ``limit``)."""
    blocks = np.floor((times - times[0]) / BLOCK_S).astype(int)
    labels = np.unique(blocks)
    if len(labels) < 3:
        return 0.0
    near = offset + np.arange(-0.2, 0.2 + STEP_S / 2, STEP_S)
    estimates = []
    for label in labels:
        keep = blocks != label
        found = _best_offset(times[keep], rolls[keep], t_tel, roll_tel, near, limit)
        if found is not None:
            estimates.append(found)
    n = len(estimates)
    if n < 3:
        return 0.0
    estimates = np.asarray(estimates)
    return float(math.sqrt((n - 1) / n * np.sum((estimates - estimates.mean()) ** 2)))
