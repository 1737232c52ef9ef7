"""The threshold and the runway end: transverse lines through V2, and the corners.

The threshold and the runway end are ground lines perpendicular to the runway, so they meet
the horizon at V2, the vanishing point of the perpendicular ground direction (fixed by V1,
the horizon and the calibration: :meth:`HorizonFrame.perpendicular_vanishing_point_h`).
Each is then a one-parameter family: the line through V2 and a point of the centre line.
Along the runway, transverse lines are sampled between the two edges (columns at fractions of
the width, clear of the side stripes) and averaged into one profile; the threshold is the
outermost grey-level step of that profile near the point where the edges' support ends (the
grass, or whatever precedes the runway, against the runway's surface and threshold marks),
located to a fraction of a pixel. Colour frames add a second profile, the chroma (largest minus
smallest of R, G, B): paved runways are grey and grass or fields are not, and from 1 km out the
threshold stripes, blended within a pixel with the asphalt, can match the grass's grey level
exactly, so the grey step shows only the stripes' inner edge (1 to 2 px short of the threshold)
while the chroma step stays at the threshold. The chroma step is used when it is clear; the
grey one otherwise (a paved area beyond the threshold, snow, a grey-level camera). The corners
P', P'' (thesis Fig. 3.5, Remark 5.3.1) are
the intersections of the edges with the threshold line, the far corners those with the
runway-end line.

Pixels: (0, 0) is the centre of the top-left pixel (SPEC).
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import cv2
import numpy as np

from visland.detection.horizon import HorizonFrame
from visland.detection.pencil import finite_median, rectify, row_mean, row_quantile
from visland.detection.refine import PixelLine, chroma_of

__all__ = ["TransverseLine", "find_transverse_line", "surface_extent"]


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


def surface_extent(image, horizon: HorizonFrame, s0: float, k_left: float, k_right: float,
                   d_support: tuple, d_window: tuple, step_d_px: float = 0.5,
                   marking_fraction: float = 1.2, max_rows: int = 800) -> tuple[float, float] | None:
    """Depths ``(d_far, d_near)`` where the runway's surface ends, from rows of the frame
    resampled on lines through the vanishing point.

    A row belongs to the runway while the surface between the edges differs from the ground
    beside them as it does in the middle of the edges' support (``d_support``). Markings are
    bright on a dark runway (dark on a bright one): the surface is read as the lower quartile
    of the row between the edges when the runway is darker than its surroundings, the upper
    quartile otherwise, so threshold stripes and numbers do not end it early. Far away the
    threshold stripes blend into a band brighter (darker) than the ground across the whole
    width; such rows still belong to the runway up to ``marking_fraction`` runway widths
    along it (ICAO threshold stripes and the strip before them: 36 m on a 45 m runway), in
    depth ``marking_fraction * width_px * d / fx``.
    """
    width = k_right - k_left
    # rows every half pixel near the horizon and at most max_rows of them (geometric beyond)
    n_rows = int(min(max_rows, max(8, (d_window[1] - d_window[0]) / step_d_px + 1)))
    rect = rectify(image, horizon, s0, (k_left - 0.4 * width, k_right + 0.4 * width), d_window,
                   max_rows=n_rows, max_columns=96, pixel_step=max(0.5, width * d_window[1] / 50.0),
                   geometric_rows=n_rows == max_rows)
    if rect is None:
        return None
    f = (rect.k - k_left) / width
    inside = (f >= 0.1) & (f <= 0.9)
    outside = ((f >= -0.38) & (f <= -0.12)) | ((f >= 1.12) & (f <= 1.38))
    with np.errstate(invalid="ignore"):
        out_level = row_quantile(rect.values[:, outside], 0.5)
        low = row_quantile(rect.values[:, inside], 0.25)
        high = row_quantile(rect.values[:, inside], 0.75)
    core = (rect.d >= d_support[0] + 0.2 * (d_support[1] - d_support[0])) & \
        (rect.d <= d_support[1] - 0.2 * (d_support[1] - d_support[0]))
    if core.sum() < 2:
        return None
    darker = finite_median(low[core] - out_level[core]) < 0
    contrast = (low - out_level) if darker else (high - out_level)
    reference = finite_median(contrast[core])
    if not np.isfinite(reference) or abs(reference) < 2.0:
        return None
    runway = np.nan_to_num(contrast * np.sign(reference)) > 0.5 * abs(reference)
    # majority over three rows, then the run of runway rows holding the core
    padded = np.concatenate([[runway[0]], runway, [runway[-1]]]).astype(int)
    runway = (padded[:-2] + padded[1:-1] + padded[2:]) >= 2
    centre = int(np.nonzero(core)[0][len(np.nonzero(core)[0]) // 2])
    if not runway[centre]:
        return None
    lo = centre
    while lo > 0 and runway[lo - 1]:
        lo -= 1
    hi = centre
    while hi < len(runway) - 1 and runway[hi + 1]:
        hi += 1
    # then across a band of blended markings (grey level on the other side of the ground's)
    median = row_quantile(rect.values[:, inside], 0.5)
    band = np.nan_to_num((median - out_level) * -np.sign(reference)) > 0.5 * abs(reference)
    fx = horizon.camera.fx

    def reach(depth):
        return marking_fraction * width * depth * depth / fx + 1.0

    start = rect.d[hi]
    while hi < len(runway) - 1 and band[hi + 1] and rect.d[hi + 1] - start <= reach(start):
        hi += 1
    start = rect.d[lo]
    while lo > 0 and band[lo - 1] and start - rect.d[lo - 1] <= reach(start):
        lo -= 1
    return float(rect.d[lo]), float(rect.d[hi])


def _meet(line_a: np.ndarray, line_b: np.ndarray) -> np.ndarray:
    p = np.cross(line_a, line_b)
    with np.errstate(divide="ignore", invalid="ignore"):
        return p[..., :2] / p[..., 2:3]


def find_transverse_line(image, horizon: HorizonFrame, s0: float, left: PixelLine, right: PixelLine,
                         d_expected: float, d_window: tuple, outward: int, min_step: float,
                         n_columns: int = 48, step_d_px: float = 0.5,
                         min_significance: float = 2.5, marking_fraction: float = 1.2,
                         colour=None, min_chroma_step: float = 8.0) -> TransverseLine | None:
    """Locate the threshold (``outward = +1``: outside is at larger depth) or the runway end
    (``outward = -1``) near depth ``d_expected`` within ``d_window = (d_min, d_max)``.

    ``d_expected`` is where the runway's surface ends (:func:`surface_extent`): the boundary is
    the outermost clear step from a pixel inside it to as far beyond it as a band of threshold
    markings can reach (``marking_fraction`` runway widths along the runway, as in
    :func:`surface_extent`: between 1 and 3 km the blended stripes can look like the ground, so
    the surface seems to end at their inner edge, 3 to 7 px short of the threshold), else the
    step nearest to it, weighted by its strength.

    ``colour`` (the frame as (H, W, 3) uint8, optional) adds the chroma profile (module
    docstring): its step, rising towards the outside, replaces the grey one when the chroma
    differs by at least ``min_chroma_step`` levels across it and it lies between the grey step
    (or, without one, ``d_expected``) and the outer end of a marking band.

    Returns None when no step stands out of the profile's noise by ``min_significance`` or
    reaches a quarter of ``min_step`` grey levels per pixel (in grey and in chroma).
    """
    d_min, d_max = (float(x) for x in d_window)
    if not (math.isfinite(d_min) and math.isfinite(d_max)) or d_max - d_min < 6 * step_d_px:
        return None
    v2 = horizon.perpendicular_vanishing_point_h(s0)
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
    maps = ((u - u0).astype(np.float32), (v - v0).astype(np.float32))
    inner = max(1.5, 0.01 * d_expected)
    width_s = abs(sd_right[0] - sd_left[0]) * d_expected / d_ref       # runway width along the horizon at d_expected
    outer = max(2.5, 0.02 * d_expected, marking_fraction * width_s * d_expected / horizon.camera.fx + 1.0)
    profile_of = functools.partial(_depth_profile, maps=maps, inside=inside, rows_ok=rows_ok)
    grey = _step_profile(profile_of(image[v0:v1, u0:u1]), depths, step_d_px, d_expected, outward)
    chosen = grey.pick(min_significance, 0.25 * min_step, inner, outer, outward) if grey else None
    best = (grey, chosen) if chosen is not None else None
    if colour is not None:
        chroma = _step_profile(profile_of(chroma_of(colour[v0:v1, u0:u1])), depths, step_d_px, d_expected, outward)
        if chroma is not None:
            # the boundary lies at or beyond the grey step (which may be the stripes' inner edge)
            d_from = depths[chosen] if chosen is not None else d_expected
            pick = chroma.pick_rising(min_significance, min_chroma_step, d_from, inner, outer, outward)
            if pick is not None:
                best = (chroma, pick)
    if best is None:
        return None
    profile, chosen = best
    depth = profile.subpixel(chosen)
    centre_point = horizon.pencil_point(s0, k_centre, depth)
    line_h = np.cross(np.array([centre_point[0], centre_point[1], 1.0]), v2)
    line_h = line_h / np.linalg.norm(line_h[:2])
    return TransverseLine(line_h=line_h, corner_left_uv=_meet(line_h, line_left),
                          corner_right_uv=_meet(line_h, line_right), depth_px=depth,
                          step=float(profile.g[chosen]), significance=float(profile.magnitude[chosen] / profile.noise))


def _depth_profile(patch, maps, inside, rows_ok) -> np.ndarray:
    """Mean of ``patch`` along each transverse line (NaN where too little of it is in the image)."""
    values = cv2.remap(np.asarray(patch, dtype=np.float32), maps[0], maps[1], cv2.INTER_LINEAR,
                       borderMode=cv2.BORDER_REPLICATE)
    profile = row_mean(np.where(inside, values, np.nan))
    return np.where(rows_ok, profile, np.nan)


@dataclass
class _StepProfile:
    """A profile along depth, smoothed, its derivative ``g`` and the derivative's noise level."""

    depths: np.ndarray
    smooth: np.ndarray
    g: np.ndarray
    magnitude: np.ndarray
    noise: float
    step_d_px: float
    d_expected: float

    def _peaks(self, min_significance: float, min_slope: float) -> np.ndarray:
        m = self.magnitude
        return np.nonzero((m[1:-1] >= m[:-2]) & (m[1:-1] > m[2:]) & (m[1:-1] >= min_significance * self.noise)
                          & (m[1:-1] >= min_slope))[0] + 1

    def pick(self, min_significance, min_slope, inner, outer, outward) -> int | None:
        """The runway's surface ends at ``d_expected`` (last row of runway, markings included):
        its boundary is the outermost clear step from just inside that row to a little beyond
        it; failing one there, the step nearest to it weighted by its strength."""
        peaks = self._peaks(min_significance, min_slope)
        if len(peaks) == 0:
            return None
        beyond = (self.depths[peaks] - self.d_expected) * outward
        near = peaks[(beyond >= -inner) & (beyond <= outer) & (self.magnitude[peaks] >= 0.25 * self.magnitude[peaks].max())]
        if len(near):
            return int(near.max() if outward > 0 else near.min())
        score = self.magnitude[peaks] * np.exp(-0.5 * ((self.depths[peaks] - self.d_expected) / (2.0 * inner)) ** 2)
        return int(peaks[np.argmax(score)])

    def pick_rising(self, min_significance, min_change, d_from, inner, outer, outward) -> int | None:
        """The strongest step rising towards the outside from ``d_from - inner`` to
        ``d_expected + outer``, if the profile changes by ``min_change`` across it."""
        peaks = self._peaks(min_significance, 0.0)
        peaks = peaks[np.sign(self.g[peaks]) == outward]
        lo = (d_from - self.d_expected) * outward - inner
        hi = max(outer, lo + 2.0 * inner)
        beyond = (self.depths[peaks] - self.d_expected) * outward
        peaks = peaks[(beyond >= lo) & (beyond <= hi)]
        if len(peaks) == 0:
            return None
        chosen = int(peaks[np.argmax(self.magnitude[peaks])])
        reach = max(1, int(round(2.0 / self.step_d_px)))
        before = self.smooth[max(0, chosen - reach)]
        after = self.smooth[min(len(self.smooth) - 1, chosen + reach)]
        return chosen if (after - before) * outward >= min_change else None

    def subpixel(self, chosen: int) -> float:
        """Centroid of the step's derivative lobe within a pixel of its peak."""
        half = max(1, int(round(1.0 / self.step_d_px)))
        idx = np.arange(max(0, chosen - half), min(len(self.g), chosen + half + 1))
        w = np.maximum(np.sign(self.g[chosen]) * self.g[idx], 0.0)
        return float(np.sum(w * self.depths[idx]) / np.sum(w)) if w.sum() > 0 else float(self.depths[chosen])


def _step_profile(profile, depths, step_d_px, d_expected, outward) -> _StepProfile | None:
    """Smooth ``profile`` along depth (about one pixel), differentiate it (g > 0 where it rises
    with depth) and measure the derivative's noise: the smaller of its spreads over the whole
    window and over the part outside the runway (markings inside, or field boundaries beyond
    the runway's end, are structure, not noise)."""
    valid = np.isfinite(profile)
    if valid.sum() < 12:
        return None
    filled = np.interp(depths, depths[valid], profile[valid])
    kernel = np.exp(-0.5 * (np.arange(-4, 5) * step_d_px / 0.8) ** 2)
    kernel /= kernel.sum()
    smooth = np.convolve(filled, kernel, mode="same")
    g = np.gradient(smooth, step_d_px)
    g[:5] = 0.0
    g[-5:] = 0.0
    g = np.where(valid, g, 0.0)
    magnitude = np.abs(g)

    def spread(pool):
        return 1.4826 * float(np.median(np.abs(pool - np.median(pool)))) if pool.size >= 8 else math.inf

    outside = valid & ((depths > d_expected + 2.0) if outward > 0 else (depths < d_expected - 2.0))
    noise = min(spread(magnitude[valid]), spread(magnitude[outside])) + 1e-3
    return _StepProfile(depths, smooth, g, magnitude, noise, step_d_px, d_expected)


def _horizon_parallel(horizon: HorizonFrame, depth: float) -> np.ndarray:
    """Homogeneous pixel line parallel to the horizon at ``depth`` below it."""
    n = horizon.n_uv
    return np.array([n[0], n[1], -(n @ horizon.q_uv) - depth])
