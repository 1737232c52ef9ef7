"""The threshold and the runway end: transverse lines through V2, and the corners.

The threshold and the runway end are ground lines perpendicular to the runway, so they meet
the horizon at V2, the vanishing point of the perpendicular ground direction (fixed by V1,
the horizon and the calibration: :meth:`HorizonFrame.perpendicular_vanishing_point_h`).
Each is then a one-parameter family: the line through V2 and a point of the centre line.
Along the runway, transverse lines are sampled between the two edges (columns at fractions of
the width, clear of the side stripes) and averaged into one profile; the threshold is the
outermost grey-level step of that profile near the point where the edges' support ends (the
grass, or whatever precedes the runway, against the runway's surface and threshold marks),
located to a fraction of a pixel. The corners P', P'' (thesis Fig. 3.5, Remark 5.3.1) are
the intersections of the edges with the threshold line, the far corners those with the
runway-end line.

Pixels: (0, 0) is the centre of the top-left pixel (SPEC).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from visland.detection.horizon import HorizonFrame
from visland.detection.refine import PixelLine

__all__ = ["TransverseLine", "find_transverse_line"]


@dataclass(frozen=True)
class TransverseLine:
    """A threshold or runway-end line.

    Attributes
    ----------
    line_h : ndarray (3,)
        Homogeneous pixel line ``a u + b v + c = 0``.
    corner_left_uv, corner_right_uv : ndarray (2,)
        Its intersections with the left and right edges.
    depth_px : float
        Depth below the horizon where it crosses the centre line.
    step : float
        Grey-level step across it (runway side minus outside).
    significance : float
        The step's slope over the profile's noise level.
    """

    line_h: np.ndarray
    corner_left_uv: np.ndarray
    corner_right_uv: np.ndarray
    depth_px: float
    step: float
    significance: float


def _meet(line_a: np.ndarray, line_b: np.ndarray) -> np.ndarray:
    p = np.cross(line_a, line_b)
    with np.errstate(divide="ignore", invalid="ignore"):
        return p[..., :2] / p[..., 2:3]


def find_transverse_line(image, horizon: HorizonFrame, s0: float, left: PixelLine, right: PixelLine,
                         d_expected: float, d_window: tuple, outward: int, min_step: float,
                         n_columns: int = 48, step_d_px: float = 0.5, min_significance: float = 6.0
                         ) -> TransverseLine | None:
    """Locate the threshold (``outward = +1``: outside is at larger depth) or the runway end
    (``outward = -1``) near depth ``d_expected`` within ``d_window = (d_min, d_max)``.

    Returns None when no step stands out of the profile's noise by ``min_significance`` or
    reaches ``min_step`` grey levels.
    """
    d_min, d_max = (float(x) for x in d_window)
    if not (math.isfinite(d_min) and math.isfinite(d_max)) or d_max - d_min < 6 * step_d_px:
        return None
    v2 = horizon.perpendicular_vanishing_point_h(s0)
    vp = horizon.vanishing_point_uv(s0)
    line_left, line_right = left.homogeneous(), right.homogeneous()
    # the centre line: through V1, midway between the edges along lines parallel to the horizon
    d_ref = max(d_expected, 1.0)
    sd_left = horizon.to_sd(_meet(line_left, _horizon_parallel(horizon, d_ref)))
    sd_right = horizon.to_sd(_meet(line_right, _horizon_parallel(horizon, d_ref)))
    k_centre = (0.5 * (sd_left[0] + sd_right[0]) - s0) / d_ref
    depths = np.arange(d_min, d_max + 1e-9, step_d_px)
    centre_points = horizon.pencil_point(s0, k_centre, depths)                        # (m, 2)
    transverse = np.cross(np.concatenate([centre_points, np.ones((len(depths), 1))], axis=1), v2)
    ends_left = _meet(transverse, line_left)
    ends_right = _meet(transverse, line_right)
    fractions = np.linspace(0.1, 0.9, n_columns)
    grid = ends_left[:, None, :] + fractions[None, :, None] * (ends_right - ends_left)[:, None, :]
    height, width = image.shape
    finite = np.isfinite(grid).all(axis=-1)
    inside = finite & (grid[..., 0] >= 0) & (grid[..., 0] <= width - 1) & (grid[..., 1] >= 0) \
        & (grid[..., 1] <= height - 1)
    rows_ok = inside.mean(axis=1) >= 0.5
    if rows_ok.sum() < 12:
        return None
    u = np.where(inside, grid[..., 0], -10.0)
    v = np.where(inside, grid[..., 1], -10.0)
    u0 = int(max(0, math.floor(u[inside].min()) - 1))
    v0 = int(max(0, math.floor(v[inside].min()) - 1))
    u1 = int(min(width, math.ceil(u[inside].max()) + 2))
    v1 = int(min(height, math.ceil(v[inside].max()) + 2))
    crop = np.asarray(image[v0:v1, u0:u1], dtype=np.float32)
    values = cv2.remap(crop, (u - u0).astype(np.float32), (v - v0).astype(np.float32), cv2.INTER_LINEAR,
                       borderMode=cv2.BORDER_REPLICATE)
    values = np.where(inside, values, np.nan)
    with np.errstate(invalid="ignore"):
        profile = np.nanmean(values, axis=1)
    profile = np.where(rows_ok, profile, np.nan)
    # smooth along depth (about one pixel) and differentiate: g > 0 where grey rises with depth
    valid = np.isfinite(profile)
    filled = np.interp(depths, depths[valid], profile[valid])
    kernel = np.exp(-0.5 * (np.arange(-4, 5) * step_d_px / 0.8) ** 2)
    kernel /= kernel.sum()
    smooth = np.convolve(filled, kernel, mode="same")
    g = np.gradient(smooth, step_d_px)
    g[:5] = 0.0
    g[-5:] = 0.0
    g = np.where(valid, g, 0.0)
    magnitude = np.abs(g)
    noise = 1.4826 * np.median(np.abs(magnitude - np.median(magnitude))) + 1e-3
    peaks = np.nonzero((magnitude[1:-1] >= magnitude[:-2]) & (magnitude[1:-1] > magnitude[2:]))[0] + 1
    # a step's height: difference of the means over a few pixels on each side
    span = max(2, int(round(2.0 / step_d_px)))

    def step_height(i):
        outside = smooth[i + span:i + 2 * span + 1] if outward > 0 else smooth[max(0, i - 2 * span):i - span + 1]
        runway = smooth[max(0, i - 2 * span):i - span + 1] if outward > 0 else smooth[i + span:i + 2 * span + 1]
        if len(outside) == 0 or len(runway) == 0:
            return 0.0
        return float(np.mean(runway) - np.mean(outside))

    good = [i for i in peaks if magnitude[i] / noise >= min_significance and abs(step_height(i)) >= min_step]
    if not good:
        return None
    # the outermost step that is not much weaker than the strongest near the expected depth
    strongest = max(magnitude[i] for i in good)
    good = [i for i in good if magnitude[i] >= 0.2 * strongest]
    chosen = max(good) if outward > 0 else min(good)
    delta = 0.0
    left_m, centre_m, right_m = magnitude[chosen - 1], magnitude[chosen], magnitude[chosen + 1]
    denominator = left_m - 2 * centre_m + right_m
    if abs(denominator) > 1e-9:
        delta = float(np.clip(0.5 * (left_m - right_m) / denominator, -0.5, 0.5))
    depth = float(depths[chosen] + delta * step_d_px)
    centre_point = horizon.pencil_point(s0, k_centre, depth)
    line_h = np.cross(np.array([centre_point[0], centre_point[1], 1.0]), v2)
    line_h = line_h / np.linalg.norm(line_h[:2])
    return TransverseLine(line_h=line_h, corner_left_uv=_meet(line_h, line_left),
                          corner_right_uv=_meet(line_h, line_right), depth_px=depth,
                          step=step_height(chosen), significance=float(magnitude[chosen] / noise))


def _horizon_parallel(horizon: HorizonFrame, depth: float) -> np.ndarray:
    """Homogeneous pixel line parallel to the horizon at ``depth`` below it."""
    n = horizon.n_uv
    return np.array([n[0], n[1], -(n @ horizon.q_uv) - depth])
