"""The clock offset between a recording's frames and its telemetry (issue 15 item 4).

Real recordings do not share a clock: the telemetry of a video is offset by a fraction of a
second to seconds. Convention: the offset ``S`` is *added to the telemetry's times* to put them
on the frames' clock (``--time-offset S``): a telemetry row stamped ``tau`` describes the moment
the frames stamp ``tau + S``.

:func:`estimate_time_offset` measures ``S`` from the data: the roll angle seen in the frames
(the slope of the visible horizon, :func:`visland.detection.attitude.visible_horizon`, which
does not depend on the runway or the haze) must follow the telemetry's roll. The roll series of
the frames is compared with the telemetry's, shifted by every candidate ``S``; a constant
difference (a camera mounted with a roll error) is allowed. The best ``S`` minimises the RMS
difference; its uncertainty is that of a least-squares fit linearised about it,
``sigma_S = sigma_residual / sqrt(sum(roll_rate^2))``, widened for residuals correlated from
frame to frame (fewer independent samples); without roll motion (straight and level), or with a
horizon too poor to follow the roll, the estimate is refused.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["TimeOffset", "estimate_time_offset", "MAX_OFFSET_S"]

#: Offsets searched, seconds either side of zero, and the search step.
MAX_OFFSET_S = 2.0
STEP_S = 0.002
#: Most frames read for the estimate (spread evenly; the roll seen in a frame costs ~20 ms).
MAX_FRAMES = 400
#: An estimate less certain than this (one sigma, seconds) is not used.
MAX_SIGMA_S = 0.05


@dataclass(frozen=True)
class TimeOffset:
    """The estimated offset of the telemetry's clock against the frames'.

    Attributes
    ----------
    offset_s : float
        Seconds to add to the telemetry's times (``--time-offset``).
    sigma_s : float
        One-sigma uncertainty, seconds (widened by the residuals' frame-to-frame correlation).
    frames_used : int
        Frames whose horizon gave a roll.
    residual_deg : float
        RMS roll difference between the frames and the shifted telemetry, degrees.
    """

    offset_s: float
    sigma_s: float
    frames_used: int
    residual_deg: float


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
    times, rolls = np.asarray(times), np.unwrap(np.asarray(rolls))
    t_tel = np.asarray(telemetry["t_s"], float)
    roll_tel = np.unwrap(np.radians(np.asarray(telemetry["roll_deg"], float)))
    offsets = np.arange(-max_offset_s, max_offset_s + STEP_S / 2, STEP_S)
    costs = np.full(len(offsets), np.inf)
    for k, offset in enumerate(offsets):
        # telemetry on the frames' clock: stamped tau, it happened at tau + offset
        inside = (times >= t_tel[0] + offset) & (times <= t_tel[-1] + offset)
        if inside.sum() < 0.8 * len(times):
            continue
        difference = rolls[inside] - np.interp(times[inside] - offset, t_tel, roll_tel)
        costs[k] = float(np.sqrt(np.mean((difference - difference.mean()) ** 2)))
    if not np.isfinite(costs).any():
        raise ValueError(f"{source.name}: the telemetry does not cover the frames at any offset within "
                         f"+-{max_offset_s:g} s")
    best = int(np.argmin(costs))
    offset = float(offsets[best])
    if 0 < best < len(offsets) - 1 and np.isfinite(costs[best - 1]) and np.isfinite(costs[best + 1]):
        a, b, c = costs[best - 1] ** 2, costs[best] ** 2, costs[best + 1] ** 2
        if a - 2 * b + c > 0:
            offset += 0.5 * (a - c) / (a - 2 * b + c) * STEP_S
    inside = (times >= t_tel[0] + offset) & (times <= t_tel[-1] + offset)
    rate = np.interp(times[inside] - offset, t_tel, np.gradient(roll_tel, t_tel))
    residual = float(costs[best])
    sigma = residual / math.sqrt(max(float(np.sum(rate ** 2)), 1e-30))
    # residuals that follow each other (a horizon biased for seconds by clouds or terrain) carry
    # fewer independent samples than frames: widen sigma by sqrt((1 + rho) / (1 - rho)), rho
    # their lag-one correlation
    r = rolls[inside] - np.interp(times[inside] - offset, t_tel, roll_tel)
    r = r - r.mean()
    rho = float(np.clip(np.dot(r[:-1], r[1:]) / max(float(np.dot(r, r)), 1e-30), 0.0, 0.99)) if len(r) > 2 else 0.0
    sigma *= math.sqrt((1.0 + rho) / (1.0 - rho))
    if not sigma <= MAX_SIGMA_S:
        spread = (f"one sigma {sigma:.2f} s, the horizon's roll {math.degrees(residual):.2f} deg RMS off the "
                  "telemetry's" if sigma < 100 else "no roll motion at all")
        raise ValueError(f"{source.name}: the clock offset cannot be fixed ({spread}): too little roll motion "
                         "(straight and level flight says nothing) or a horizon the frames do not show clearly; "
                         "give --time-offset")
    return TimeOffset(offset_s=offset, sigma_s=sigma, frames_used=len(times), residual_deg=math.degrees(residual))
