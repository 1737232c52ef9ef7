"""Sub-pixel refinement of an image line against the grey-level gradient.

A line is refined the way ViSP's moving edges or Dickmanns' gradient windows do it: profiles
are sampled across the predicted line (bilinear interpolation of the full-resolution frame,
three taps along the line averaged), each profile is differentiated with the smoothed
central difference ``[-1, -2, 0, 2, 1] / 8``, the edge in each profile is the extremum of
the derivative with the expected sign, located to a fraction of a pixel by a parabola
through the three samples around it, and a line is fitted to those edge points by weighted
total least squares with Tukey biweight re-weighting (outliers: markings, texture, gaps).
Stripes (the centre line) are located as the midpoint between their rising and falling edge.

Pixels: (0, 0) is the centre of the top-left pixel (SPEC), the same convention as
``cv2.remap``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import cv2
import numpy as np

from visland.detection.params import DetectorParams

__all__ = ["PixelLine", "LineFit", "NoFit", "SLOPE_PER_STEP", "median_of", "percentile_of", "sample_profiles",
           "edge_offsets", "boundary_offsets", "BoundaryPoints", "HiddenStripe", "past_hidden_stripe", "transition_offsets",
           "stripe_offsets", "fit_line", "refine_line", "chroma_boundary", "chroma_of",
           "remap_inside", "net_step", "parabola_peak"]

_DERIVATIVE = np.array([-1.0, -2.0, 0.0, 2.0, 1.0]) / 8.0
#: Peak slope of the 5-tap derivative across a step blurred by about a pixel, per unit of step
#: height (a blurred step of height h peaks near h / (sqrt(2 pi) sigma)): slope / 0.3 estimates h.
SLOPE_PER_STEP = 0.3
#: The same for the central difference across an area-sampled step (a one-pixel ramp): h / 2.
RAMP_SLOPE_PER_STEP = 0.5
#: Sampling step (px) of the profiles across a region's boundary (sub-pixel flank positions).
BOUNDARY_STEP_PX = 0.5
#: Room (px) added beyond the search band so the derivative kernels see whole steps.
KERNEL_ROOM_PX = 3.0
#: Median absolute deviation to standard deviation (Gaussian noise).
MAD_TO_SIGMA = 1.4826
#: Tukey biweight cut-off, in robust sigmas (95 % efficiency under Gaussian noise).
TUKEY_C = 4.685
#: Fewest profiles seeing both flanks of a border stripe before its width is trusted
#: (:func:`past_hidden_stripe`).
HIDDEN_STRIPE_MIN_PROFILES = 6


@dataclass(frozen=True)
class PixelLine:
    """A line in pixels: a point on it and a unit direction; the normal is the direction turned
    by +90 deg in the image (``(-e_v, e_u)``).

    Attributes
    ----------
    point : ndarray, shape (2,)
        A pixel on the line (SPEC convention: (0, 0) at the centre of the top-left pixel).
    direction : ndarray, shape (2,)
        Unit direction of the line in pixels.
    """

    point: np.ndarray
    direction: np.ndarray

    @property
    def normal(self) -> np.ndarray:
        return np.array([-self.direction[1], self.direction[0]])

    def distance(self, uv) -> np.ndarray:
        """Signed distance (pixels) of points ``(..., 2)`` along the normal."""
        return (np.asarray(uv, float) - self.point) @ self.normal

    def homogeneous(self) -> np.ndarray:
        """``(a, b, c)`` with ``a u + b v + c = 0`` and ``(a, b)`` the unit normal."""
        n = self.normal
        return np.array([n[0], n[1], -n @ self.point])


@dataclass(frozen=True)
class LineFit:
    """A refined line and how well the image supports it.

    Attributes
    ----------
    line : PixelLine
        Fitted line (point at the inliers' centroid).
    residual_px : float
        RMS distance of the inliers to the line.
    support : float
        Inliers / profiles sampled.
    contrast : float
        Median absolute grey-level step (edges) or stripe height (stripes) of the inliers.
    polarity : int
        Sign of the grey-level change along the line normal (stripes: +1 bright, -1 dark).
    extent : tuple of float
        ``(t_min, t_max)``, positions along ``line.direction`` (from ``line.point``) of the
        inliers' span.
    sigma_offset_px, sigma_angle_rad : float
        One-sigma uncertainty of the line's offset at the centroid and of its angle.
    n_inliers : int
    points : ndarray, shape (n, 2)
        Inlying edge points (pixels).
    note : str
        How the line was placed when it matters (e.g. on grey levels because the chroma did not
        tell, and why); empty otherwise.
    """

    line: PixelLine
    residual_px: float
    support: float
    contrast: float
    polarity: int
    extent: tuple
    sigma_offset_px: float
    sigma_angle_rad: float
    n_inliers: int
    points: np.ndarray
    note: str = ""

    def sigma_at(self, uv) -> float:
        """One-sigma normal uncertainty (pixels) of the line at a point, extrapolated."""
        t = float((np.asarray(uv, float) - self.line.point) @ self.line.direction)
        return math.hypot(self.sigma_offset_px, t * self.sigma_angle_rad)


@dataclass(frozen=True)
class NoFit:
    """Why a line could not be refined: false in a boolean test, so ``if not fit`` reads as
    "no line", and the reason travels to the measurement row.

    Attributes
    ----------
    reason : str
        One sentence saying why (carried into the detection's reason and notes).
    """

    reason: str

    def __bool__(self) -> bool:
        return False


def median_of(values):
    """``np.median(values)`` of all the values, the same number and type (NaN if any is NaN), in
    a quarter of the time on the short arrays the detector takes medians of (numpy's median
    spends most of its time on generality: axes, masked arrays, ``out``).

    Parameters
    ----------
    values : array_like
        Any shape; all values count.

    Returns
    -------
    numpy scalar
        The median, of the type ``np.median`` returns.
    """
    a = np.asarray(values)
    n = a.size
    if n == 0 or a.dtype.kind != "f":
        return np.median(a)
    a = a.ravel()
    half = n // 2
    # the last position is partitioned too: it holds the largest value, NaN if there is one
    if n % 2:
        part = np.partition(a, (half, n - 1)) if n > 1 else a
        out = part[half]
    else:
        part = np.partition(a, (half - 1, half, n - 1))
        out = (part[half - 1] + part[half]) / 2
    if np.isnan(part[n - 1]):
        return part.dtype.type(np.nan)
    return out


def percentile_of(values, q: float):
    """``np.percentile(values, q)`` (its default linear interpolation) of all the values, for a
    Python number ``q``: the same number and type (NaN if any is NaN), without numpy's
    generality (axes, methods, weights), which costs tens of microseconds on short arrays.

    Parameters
    ----------
    values : array_like
        Any shape; all values count.
    q : float
        The percentile, 0 to 100 (a Python int or float).

    Returns
    -------
    numpy scalar
        The percentile, of the type ``np.percentile`` returns.
    """
    a = np.asarray(values)
    n = a.size
    if n == 0 or a.dtype.kind != "f" or type(q) not in (int, float) or not 0 <= q <= 100:
        return np.percentile(a, q)
    # numpy's steps: the virtual index (n - 1) q / 100, the order statistics either side of it
    # (the last one when it is the last index), the weight between them as a Python float
    virtual = (n - 1) * (q / 100)
    lo = hi = n - 1 if virtual >= n - 1 else math.floor(virtual)
    if virtual < n - 1:
        hi = lo + 1
    gamma = virtual - (-1 if virtual >= n - 1 else lo)
    part = np.partition(a.ravel(), sorted({lo, hi, n - 1}))
    if np.isnan(part[n - 1]):
        return part.dtype.type(np.nan)
    below, above = part[lo], part[hi]
    difference = above - below
    # numpy's _lerp: from below, or from above when the weight is at least a half
    return above - difference * (1 - gamma) if gamma >= 0.5 else below + difference * gamma


def chroma_of(rgb: np.ndarray) -> np.ndarray:
    """Chroma of a uint8 RGB image: largest minus smallest channel, (H, W) uint8 (0 for greys).

    Parameters
    ----------
    rgb : ndarray of uint8, shape (H, W, 3)
        Colour frame.

    Returns
    -------
    ndarray of uint8, shape (H, W)
    """
    r, g, b = cv2.split(np.ascontiguousarray(rgb))
    return cv2.subtract(cv2.max(cv2.max(r, g), b), cv2.min(cv2.min(r, g), b))


def remap_inside(image, map_u, map_v, inside, border_mode: int = cv2.BORDER_CONSTANT,
                 border_value: float = 0.0) -> np.ndarray:
    """``cv2.remap(image as float32, map_u, map_v)`` (bilinear) at the samples ``inside``, read
    from a float32 crop of the frame around them instead of the whole frame converted.

    The crop holds every pixel a sample inside interpolates from (a pixel of margin each side,
    more where the frame ends), and the maps move by the crop's whole-pixel origin, an exact
    float32 subtraction that keeps ``cv2.remap``'s fixed-point sub-pixel position: the values
    inside are the whole frame's to the bit. Samples outside read ``border_value`` (constant
    border) or a pixel of the crop's edge (replicated border): the caller sets them.

    Parameters
    ----------
    image : ndarray, shape (H, W)
        Grey frame (uint8 or float32).
    map_u, map_v : ndarray of float32
        Sample positions, pixels of the frame (SPEC convention, as ``cv2.remap``).
    inside : ndarray of bool, same shape
        The samples that must be exact (finite positions within the frame).
    border_mode : int, optional
        ``cv2.remap``'s border mode for taps outside the crop.
    border_value : float, optional
        Its value with ``cv2.BORDER_CONSTANT``.

    Returns
    -------
    ndarray of float32, shape of ``map_u``
    """
    if not inside.any():
        return np.full(map_u.shape, np.float32(border_value), np.float32)
    height, width = image.shape[:2]
    u0 = max(0, int(math.floor(float(map_u.min(where=inside, initial=np.inf)))) - 1)
    v0 = max(0, int(math.floor(float(map_v.min(where=inside, initial=np.inf)))) - 1)
    u1 = min(width, int(math.ceil(float(map_u.max(where=inside, initial=-np.inf)))) + 2)
    v1 = min(height, int(math.ceil(float(map_v.max(where=inside, initial=-np.inf)))) + 2)
    crop = np.asarray(image[v0:v1, u0:u1], dtype=np.float32)
    crop_u = np.where(inside, map_u - np.float32(u0), np.float32(-1.0))
    crop_v = np.where(inside, map_v - np.float32(v0), np.float32(-1.0))
    return cv2.remap(crop, crop_u, crop_v, cv2.INTER_LINEAR, borderMode=border_mode, borderValue=border_value)


def sample_profiles(image, centres_uv, normal_uv, direction_uv, halfwidth_px: float,
                    step_px: float = 1.0, taps_px: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Grey-level (or chroma) profiles across a line.

    Parameters
    ----------
    image : ndarray (H, W), uint8 or float32; or (H, W, 3) RGB uint8, whose chroma (largest
        minus smallest channel) is sampled
    centres_uv : ndarray (n, 2)
        Profile centres (pixels).
    normal_uv, direction_uv : ndarray (2,) or (n, 2)
        Unit normal (profile axis) and unit direction along the line.
    halfwidth_px : float
        Profiles span ``[-halfwidth, halfwidth]`` along the normal.
    step_px, taps_px : float
        Spacing of the profile samples; three taps at ``-taps, 0, +taps`` along the line are
        averaged (smoothing along the line, where the edge does not change).

    Returns
    -------
    profiles : ndarray (n, m)
    offsets : ndarray (m,)
        Position of each profile sample along the normal (pixels).
    """
    centres = np.asarray(centres_uv, np.float32)
    m = int(math.floor(halfwidth_px / step_px))
    offsets = np.arange(-m, m + 1) * step_px
    normal = np.broadcast_to(np.asarray(normal_uv, np.float32), centres.shape)
    direction = np.broadcast_to(np.asarray(direction_uv, np.float32), centres.shape)
    taps = np.array([-taps_px, 0.0, taps_px], np.float32)
    off32 = offsets.astype(np.float32)
    n = len(centres)

    def coordinate(axis):
        # centre + offset * normal + tap * direction, (n, 3 taps, m samples) as (3 n, m)
        return (centres[:, axis, None, None] + off32[None, None, :] * normal[:, axis, None, None]
                + taps[None, :, None] * direction[:, axis, None, None]).reshape(n * 3, -1)

    map_u, map_v = coordinate(0), coordinate(1)
    height, width = image.shape[:2]
    outside = ((map_u < -0.5) | (map_v < -0.5) | (map_u > width - 0.5) | (map_v > height - 0.5)
               | ~np.isfinite(map_u) | ~np.isfinite(map_v))
    inside = ~outside
    if not inside.any():
        return np.full((n, len(offsets)), np.nan, np.float32), offsets
    # interpolate on a float32 crop of the frame around the samples (exact grey levels; the
    # extremes over the samples inside, reductions with a mask: no copies)
    u0 = max(0, int(math.floor(map_u.min(where=inside, initial=np.inf))) - 1)
    v0 = max(0, int(math.floor(map_v.min(where=inside, initial=np.inf))) - 1)
    u1 = min(width, int(math.ceil(map_u.max(where=inside, initial=-np.inf))) + 2)
    v1 = min(height, int(math.ceil(map_v.max(where=inside, initial=-np.inf))) + 2)
    crop = image[v0:v1, u0:u1]
    crop = np.asarray(chroma_of(crop) if crop.ndim == 3 else crop, dtype=np.float32)
    map_u = np.where(outside, -10.0, map_u - u0).astype(np.float32)
    map_v = np.where(outside, -10.0, map_v - v0).astype(np.float32)
    values = cv2.remap(crop, map_u, map_v, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    values = values.reshape(n, 3, -1)
    values[outside.reshape(n, 3, -1)] = np.nan
    # the three taps' mean (the sum in tap order, then the division: ``mean(axis=1)``'s bits)
    return (values[:, 0] + values[:, 1] + values[:, 2]) / 3, offsets


def _derivative(profiles: np.ndarray, step_px: float) -> np.ndarray:
    """Smoothed central difference along each profile, grey levels per pixel (edges: NaN)."""
    out = np.full(profiles.shape, np.nan, np.float32)
    if profiles.shape[1] >= 5:
        k = _DERIVATIVE
        out[:, 2:-2] = (k[0] * profiles[:, :-4] + k[1] * profiles[:, 1:-3] + k[3] * profiles[:, 3:-1]
                        + k[4] * profiles[:, 4:]) / step_px
    return out


def parabola_peak(values: np.ndarray, index: np.ndarray) -> np.ndarray:
    """Sub-sample offset of the peak of a parabola through ``values[index-1 .. index+1]``, per row.

    Parameters
    ----------
    values : ndarray, shape (n, m)
        Samples, one row per profile.
    index : ndarray of int, shape (n,)
        The peak's sample in each row.

    Returns
    -------
    ndarray, shape (n,)
        Offset from ``index`` in samples, within +-0.5 (0 where the three are collinear).
    """
    rows = np.arange(len(index))
    left = values[rows, np.clip(index - 1, 0, values.shape[1] - 1)]
    centre = values[rows, index]
    right = values[rows, np.clip(index + 1, 0, values.shape[1] - 1)]
    denominator = left - 2.0 * centre + right
    with np.errstate(divide="ignore", invalid="ignore"):
        delta = np.where(np.abs(denominator) > 1e-9, 0.5 * (left - right) / denominator, 0.0)
    return np.clip(np.nan_to_num(delta), -0.5, 0.5)


def edge_offsets(profiles: np.ndarray, offsets: np.ndarray, polarity: int,
                 window: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Sub-pixel position of the strongest step edge in each profile.

    Parameters
    ----------
    profiles : ndarray, shape (n, m)
        Grey levels across the line (:func:`sample_profiles`), NaN outside the frame.
    offsets : ndarray, shape (m,)
        Position of each sample along the line's normal, pixels (evenly spaced).
    polarity : int
        +1 (grey rises along the normal), -1 (falls) or 0 (strongest of either).
    window : ndarray of bool, shape (n, m), optional
        Where each profile may hold its edge.

    Returns
    -------
    position : ndarray, shape (n,)
        Offset of the edge, pixels (NaN where the profile has none).
    strength : ndarray, shape (n,)
        Absolute grey-level slope at the edge (grey levels per pixel).

    References
    ----------
    Dickmanns and Schell, autonomous landing by dynamic machine vision (seed 004): runway borders
    located by gradient templates in windows around their prediction.
    """
    step = float(offsets[1] - offsets[0]) if len(offsets) > 1 else 1.0
    g = _derivative(profiles, step)
    signed = g * polarity if polarity else np.abs(g)
    signed = np.where(np.isfinite(signed), signed, -np.inf)
    if window is not None:
        signed = np.where(window, signed, -np.inf)
    index = np.argmax(signed, axis=1)
    best = signed[np.arange(len(index)), index]
    delta = parabola_peak(np.where(np.isfinite(signed), signed, 0.0), index)
    position = offsets[index] + delta * step
    valid = np.isfinite(best) & (best > 0) & (index > 1) & (index < signed.shape[1] - 2)
    return np.where(valid, position, np.nan), np.where(valid, best, 0.0)


def transition_offsets(profiles: np.ndarray, offsets: np.ndarray, window: np.ndarray, halfspan_px: float = 2.0,
                       side_px: tuple = (2.5, 5.0)) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centre of the strongest grey-level transition in each profile, and its net step.

    The centre is the centroid of the gradient magnitude within ``halfspan_px`` of the
    strongest gradient: stable from profile to profile whether the transition is a plain step
    or a step lined with a thin painted stripe (two flanks), which is what a candidate line
    needs before it is known which side is the runway. The net step is the mean grey level
    ``side_px`` beyond the centre minus the mean as far before it, so a bright border stripe
    does not flip it.

    Parameters
    ----------
    profiles : ndarray, shape (n, m)
        Grey levels across the line, NaN outside the frame.
    offsets : ndarray, shape (m,)
        Position of each sample along the normal, pixels (evenly spaced).
    window : ndarray of bool, shape (n, m)
        Where each profile may hold its transition.
    halfspan_px : float, optional
        Half width of the centroid window around the strongest gradient, pixels.
    side_px : tuple of 2 float, optional
        ``(near, far)``: the grey levels for the net step are averaged between these distances
        beyond and before the centre, pixels.

    Returns
    -------
    position, strength, net_step : ndarray, shape (n,)
        Centre offset (pixels; NaN where none), the strongest gradient (grey levels per pixel)
        and the net step (grey levels, along the normal; NaN where none).
    """
    step = float(offsets[1] - offsets[0]) if len(offsets) > 1 else 1.0
    n, m = profiles.shape
    g = _derivative(profiles, step)
    finite = np.isfinite(g)
    a = np.where(finite & window, np.abs(g), -np.inf)
    rows = np.arange(n)
    peak = np.argmax(a, axis=1)
    best = a[rows, peak]
    span = max(1, int(round(halfspan_px / step)))
    idx = np.clip(peak[:, None] + np.arange(-span, span + 1)[None, :], 0, m - 1)
    mag = np.where(finite[rows[:, None], idx], np.abs(np.nan_to_num(g[rows[:, None], idx])), 0.0)
    w = np.where(mag >= 0.2 * best[:, None], mag, 0.0)
    total = w.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        position = (w * offsets[idx]).sum(axis=1) / total
    lo, hi = side_px
    rel = offsets[None, :] - np.nan_to_num(position)[:, None]
    after = (rel >= lo) & (rel <= hi)
    before = (rel <= -lo) & (rel >= -hi)
    with np.errstate(invalid="ignore"):
        net = (np.nansum(np.where(after, profiles, 0.0), axis=1) / np.maximum(after.sum(axis=1), 1)
               - np.nansum(np.where(before, profiles, 0.0), axis=1) / np.maximum(before.sum(axis=1), 1))
    valid = np.isfinite(best) & (best > 0) & (total > 0) & (after.sum(axis=1) > 0) & (before.sum(axis=1) > 0)
    return (np.where(valid, position, np.nan), np.where(valid, best, 0.0), np.where(valid, net, np.nan))


def boundary_offsets(profiles: np.ndarray, offsets: np.ndarray, outward: int, window: np.ndarray,
                     stripe_reach_px, flank_ratio: float | None = None, centroid_halfwidth_px: float = 0.5,
                     stripe_shift=None, outer_flank: bool = True, flank_bias_px: float | None = None,
                     params: DetectorParams | None = None) -> "BoundaryPoints":
    """Sub-pixel position of a region's boundary in each profile, painted border stripe or not.

    Walking outwards (``outward`` = +1: along +offsets), a plain boundary is one step; a
    boundary lined with a painted stripe (a runway's side stripe, brighter or darker than
    both sides) is two steps of opposite signs, and the boundary is the outer one. So: take
    the strongest step in the window; if within ``stripe_reach_px`` outwards of it there is a
    step of the opposite sign reaching ``flank_ratio`` of its strength, the strongest step was
    the stripe's inner flank and the boundary is that outer flank.

    A flank is located at the centroid of its derivative lobe (within 1 px of its peak). A
    rendered frame is area-sampled: a step becomes a one-pixel ramp whose derivative lobe is
    centred on the step; a stripe narrower than two pixels has its outer flank's lobe pushed
    outwards, by an amount read from the separation of its two flanks (see the code).

    Profiles should be sampled finely (0.5 px); the derivative is the central difference.

    Parameters
    ----------
    profiles : ndarray, shape (n, m)
        Grey levels across the boundary, NaN outside the frame.
    offsets : ndarray, shape (m,)
        Position of each sample along the normal, pixels (evenly spaced, 0.5 px apart).
    outward : int
        +1/-1: the direction (along +/- offsets) of the region's outside.
    window : ndarray of bool, shape (n, m)
        Where each profile may hold its strongest step.
    stripe_reach_px : float or ndarray, shape (n,)
        Widest border stripe looked past, pixels (one per profile or for all).
    flank_ratio : float, optional
        An opposite step outwards of the strongest is the stripe's outer flank when it reaches
        this fraction of the strongest step's slope (``params.boundary_flank_ratio`` by default).
    centroid_halfwidth_px : float, optional
        Half width of the window of a flank's centroid, pixels.
    stripe_shift : tuple of 3 float, optional
        ``(amplitude_px, start_px, scale_px)`` of the correction for an unresolved stripe's outer
        flank: ``amplitude * exp(-(max(separation - start, 0) / scale) ** 1.5)`` pixels inwards,
        ``separation`` the distance between the stripe's two flanks (calibration in the code);
        by default ``params.boundary_stripe_shift_px``, ``boundary_stripe_resolved_px`` and
        ``boundary_stripe_shift_scale_px``.
    outer_flank : bool, optional
        Place the boundary by extrapolating the outer flank of the chosen lobe (its 60 % and
        20 % crossings) instead of at the lobe's centroid.
    flank_bias_px : float, optional
        Offset (pixels, outwards) of that extrapolation for an area-sampled step, removed
        (``params.boundary_flank_bias_px`` by default).
    params : DetectorParams, optional
        The defaults above and ``boundary_same_step_ratio`` (a step of the chosen one's sign just
        outside it is the region's sharper edge when it reaches this fraction of its slope);
        ``DetectorParams()`` if omitted.

    Returns
    -------
    BoundaryPoints
        ``position`` (offset of the boundary, pixels, NaN where none), ``strength`` (the chosen
        flank's grey-level slope, grey levels per pixel) and ``stripe_inner`` (where the boundary
        was placed on a border stripe's outer flank, the offset of its inner flank located the
        same way, as if it were the boundary; NaN elsewhere): :func:`past_hidden_stripe` uses it
        where the stripe's outer flank is not seen.
    """
    params = params or DetectorParams()
    flank_ratio = params.boundary_flank_ratio if flank_ratio is None else flank_ratio
    flank_bias_px = params.boundary_flank_bias_px if flank_bias_px is None else flank_bias_px
    if stripe_shift is None:
        stripe_shift = (params.boundary_stripe_shift_px, params.boundary_stripe_resolved_px,
                        params.boundary_stripe_shift_scale_px)
    step = float(offsets[1] - offsets[0]) if len(offsets) > 1 else 1.0
    n, m = profiles.shape
    g = np.full(profiles.shape, np.nan, np.float32)
    g[:, 1:-1] = (profiles[:, 2:] - profiles[:, :-2]) / (2.0 * step)
    finite = np.isfinite(g)
    g0 = np.where(finite, g, 0.0)
    a = np.where(finite & window, np.abs(g0), -np.inf)
    rows = np.arange(n)
    p1 = np.argmax(a, axis=1)
    best = a[rows, p1]
    sign1 = np.sign(g0[rows, p1])
    columns = np.arange(m)[None, :]
    out_dir = 1 if outward >= 0 else -1
    reach = np.broadcast_to(np.asarray(stripe_reach_px, float) / step, (n,))[:, None]
    beyond = (columns - p1[:, None]) * out_dir
    zone = (beyond >= 2) & (beyond <= reach + 1) & finite
    opposite = np.where(zone, -sign1[:, None] * g0, -np.inf)          # > 0 where the sign is opposite
    local = np.zeros(zone.shape, dtype=bool)
    local[:, 1:-1] = (opposite[:, 1:-1] >= opposite[:, :-2]) & (opposite[:, 1:-1] >= opposite[:, 2:])
    opposite = np.where(local, opposite, -np.inf)
    p2 = np.argmax(opposite, axis=1)
    has_outer = opposite[rows, p2] >= flank_ratio * best
    chosen = np.where(has_outer, p2, p1)
    lobe_sign = np.where(has_outer, -sign1, sign1)
    strength = np.where(has_outer, opposite[rows, p2], best)
    # a second step of the same sign just outside the chosen one is the sharper geometric edge
    # of the region, the chosen one a blur of its texture inside it (a rendered runway's side
    # stripe, filtered at a grazing angle, spreads inwards from the polygon's edge)
    beyond2 = (columns - chosen[:, None]) * out_dir
    zone2 = (beyond2 >= 2) & (beyond2 <= reach + 1) & finite
    same = np.where(zone2, lobe_sign[:, None] * g0, -np.inf)
    local2 = np.zeros(zone2.shape, dtype=bool)
    local2[:, 1:-1] = (same[:, 1:-1] >= same[:, :-2]) & (same[:, 1:-1] >= same[:, 2:])
    same = np.where(local2 & (same >= params.boundary_same_step_ratio * strength[:, None]), same, -np.inf)
    outermost = np.where(np.isfinite(same), columns * out_dir, -np.inf).argmax(axis=1)
    has_same = np.isfinite(same[rows, outermost])
    chosen = np.where(has_same, outermost, chosen)
    strength = np.where(has_same, same[rows, outermost], strength)
    # centroid of a lobe within half a pixel of its peak (narrow: a rendered runway's texture is
    # blurred inside its sharp polygon edge, a ramp that must not pull the boundary inwards)
    half = max(1, int(round(centroid_halfwidth_px / step)))

    def centroid(peak, sign):
        idx = np.clip(peak[:, None] + np.arange(-half, half + 1)[None, :], 0, m - 1)
        w = np.maximum(sign[:, None] * g0[rows[:, None], idx], 0.0)
        total = w.sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            return (w * offsets[idx]).sum(axis=1) / total, total

    position, total = centroid(chosen, lobe_sign)
    inner, _ = centroid(p1, sign1)
    striped = has_outer & ~has_same
    stripe_inner = np.where(striped, inner, np.nan)
    def flank_edge(signed, peak):
        # a lobe's outer flank, extrapolated: where it falls to 60 % and 20 % of the peak, the
        # edge lies at 2 x60 - x20 (for the lobe of an area-sampled step seen through bilinear
        # interpolation and a central difference this lands 0.11 px outside, ``flank_bias_px``);
        # a blurred ramp of texture inside the edge widens the lobe inwards only and does not
        # move this
        x60, x20 = _outer_crossings(signed, peak, out_dir, offsets, (0.6, 0.2))
        return 2.0 * x60 - x20 - flank_bias_px * out_dir

    if outer_flank:
        extrapolated = flank_edge(g0 * lobe_sign[:, None], chosen)
        position = np.where(np.isfinite(extrapolated), extrapolated, position)
        if striped.any():
            # the stripe's inner flank placed the way a lone step is (its own lobe's outer flank)
            rows_s = np.nonzero(striped)[0]
            stripe_inner[rows_s] = flank_edge(g0[rows_s] * sign1[rows_s, None], p1[rows_s])
    # a stripe narrower than about two pixels is not resolved: area sampling spreads each of its
    # flanks over a pixel, which puts the outer flank's centroid about half a pixel outside the
    # boundary; the flanks' separation tells (under 1.6 px for stripes up to 1.5 px wide, 2 px
    # and more once resolved). ``stripe_shift = (amplitude, start, scale)`` was calibrated on
    # area-sampled profiles of stripes 0 to 3 px wide at every sub-pixel phase: mean residual
    # within 0.12 px (the unit tests check 0.5, 2 and 4 px stripes on a slanted edge)
    separation = np.abs(position - inner)
    amplitude, start, scale = stripe_shift
    shift = amplitude * np.exp(-(np.maximum(separation - start, 0.0) / scale) ** 1.5)
    position = position - np.where(has_outer, shift * out_dir, 0.0)
    valid = np.isfinite(best) & (best > 0) & (total > 0) & (chosen >= half) & (chosen < m - half)
    return BoundaryPoints(np.where(valid, position, np.nan), np.where(valid, strength, 0.0),
                          np.where(valid, stripe_inner, np.nan))


class BoundaryPoints(NamedTuple):
    """A region's boundary located in each profile (:func:`boundary_offsets`).

    Parameters
    ----------
    position : ndarray, shape (n,)
        Offset of the boundary along the profiles' normal, pixels (NaN where none).
    strength : ndarray, shape (n,)
        The chosen flank's grey-level slope, grey levels per pixel.
    stripe_inner : ndarray, shape (n,)
        Where the boundary lies on a border stripe's outer flank, the offset of the stripe's
        inner flank, located as a lone step would be (NaN elsewhere).
    """

    position: np.ndarray
    strength: np.ndarray
    stripe_inner: np.ndarray


class HiddenStripe(NamedTuple):
    """A border stripe along a line, as :func:`past_hidden_stripe` found it.

    Parameters
    ----------
    inner0, inner1 : float
        Its inner flank's offset along the line's normal, ``inner0 + inner1 t`` pixels at the
        position t along the line.
    width0, width1 : float
        Its width, ``width0 + width1 t`` pixels.
    t_lo, t_hi : float
        The stretch of the line where it was seen, pixels along the line.
    """

    inner0: float
    inner1: float
    width0: float
    width1: float
    t_lo: float
    t_hi: float

    def restated(self, old: "PixelLine", new: "PixelLine") -> "HiddenStripe":
        """The same stripe in the coordinates of line ``new`` (it was in those of ``old``)."""
        t = np.array([self.t_lo, self.t_hi])
        if not t[1] > t[0]:
            return self
        inner = old.point + t[:, None] * old.direction + (self.inner0 + self.inner1 * t)[:, None] * old.normal
        t_new = (inner - new.point) @ new.direction
        off_new = (inner - new.point) @ new.normal
        width = self.width0 + self.width1 * t
        slope_i = (off_new[1] - off_new[0]) / (t_new[1] - t_new[0])
        slope_w = (width[1] - width[0]) / (t_new[1] - t_new[0])
        return HiddenStripe(float(off_new[0] - slope_i * t_new[0]), float(slope_i),
                            float(width[0] - slope_w * t_new[0]), float(slope_w), float(t_new[0]), float(t_new[1]))


def past_hidden_stripe(position: np.ndarray, stripe_inner: np.ndarray, use: np.ndarray, t: np.ndarray,
                       outward: int, growth: float, params: DetectorParams,
                       prior: HiddenStripe | None = None) -> tuple[np.ndarray, int, HiddenStripe | None]:
    """Boundary offsets moved past a border stripe where only its inner flank is seen.

    A runway's side stripe is a painted line along the whole edge; outside it lies the ground.
    Where the ground is as bright as the paint (sand, snow, light concrete in a grey frame) the
    stripe's outer flank, the runway's edge, has no contrast, and the profile's only step is the
    stripe's inner flank, a stripe's width inside the edge. A line fitted through a mix of both
    (sand, monochrome, 392 m: 1.3 to 5 px inside wherever the sand was bright) leans inwards
    toward the aircraft and the edge is refused as not straight or placed wrong.

    Where enough profiles see both flanks (``params.hidden_stripe_min_fraction`` of those used),
    their inner flanks and the stripe's width (the flanks' separation) are each a straight
    function of the position along the line (a ground stripe's image width grows linearly with the
    depth below the horizon, so along the edge). A profile whose only step lies on that inner line
    (within ``params.hidden_stripe_tolerance`` of the width) is the stripe's inner flank: its
    boundary is that step plus the stripe's width there. Nothing moves when the width is not
    resolved (fewer than that many profiles see it ``params.hidden_stripe_min_px`` wide or more:
    an unresolved stripe's flanks lie about 1.6 px apart whatever its width, and the correction
    of :func:`boundary_offsets` applies), when the seen stripes do not agree on a straight width
    or it does not widen the way the perspective does (texture beyond the edge, not a painted
    stripe), and nowhere beyond half the length of the stretch where the stripe was seen from it.

    Parameters
    ----------
    position, stripe_inner : ndarray, shape (n,)
        :class:`BoundaryPoints` of the profiles, pixels.
    use : ndarray of bool, shape (n,)
        Profiles that hold the boundary.
    t : ndarray, shape (n,)
        Each profile's position along the line, pixels.
    outward : int
        +1/-1: the direction (along +/- offsets) of the region's outside.
    growth : float
        How the widest stripe expected changes along the line (the sign of its slope in t: the
        near end is where it is wider); 0 when it does not.
    params : DetectorParams
        ``hidden_stripe_min_fraction``, ``hidden_stripe_min_px``, ``hidden_stripe_tolerance``,
        ``hidden_stripe_max_scatter``.
    prior : HiddenStripe, optional
        The stripe an earlier pass of the same refinement found, in this pass's coordinates
        (:meth:`HiddenStripe.restated`): used when this pass's profiles do not make one (the
        narrower band sees fewer outer flanks), so one refinement does not decide twice.

    Returns
    -------
    position : ndarray, shape (n,)
        The offsets, moved past the stripe where its inner flank was the only step.
    moved : int
        How many were moved.
    stripe : HiddenStripe or None
        The stripe used.
    """
    out_dir = 1 if outward >= 0 else -1
    stripe = _stripe_seen(position, stripe_inner, use, t, out_dir, growth, params) or prior
    if stripe is None:
        return position, 0, None
    width_t = stripe.width0 + stripe.width1 * t
    lone = use & ~np.isfinite(stripe_inner) & np.isfinite(position)
    # near where the stripe was seen: its width is extrapolated by half that stretch at most
    span = stripe.t_hi - stripe.t_lo
    within = (t >= stripe.t_lo - 0.5 * span) & (t <= stripe.t_hi + 0.5 * span)
    on_inner = (lone & within & (width_t >= params.hidden_stripe_min_px)
                & (np.abs(position - (stripe.inner0 + stripe.inner1 * t)) <= params.hidden_stripe_tolerance * width_t))
    return np.where(on_inner, position + out_dir * width_t, position), int(on_inner.sum()), stripe


def _stripe_seen(position, stripe_inner, use, t, out_dir: int, growth: float,
                 params: DetectorParams) -> HiddenStripe | None:
    """The border stripe the profiles see both flanks of, or None when they do not make one
    (:func:`past_hidden_stripe`)."""
    seen = use & np.isfinite(stripe_inner) & np.isfinite(position)
    width = np.where(seen, (position - stripe_inner) * out_dir, np.nan)
    resolved = seen & (width >= params.hidden_stripe_min_px)
    if resolved.sum() < max(HIDDEN_STRIPE_MIN_PROFILES, params.hidden_stripe_min_fraction * use.sum()):
        return None
    width_fit = _robust_linear(t[seen], width[seen])
    inner_fit = _robust_linear(t[seen], stripe_inner[seen])
    if width_fit is None or inner_fit is None:
        return None
    (w0, w1, w_sigma), (i0, i1, _) = width_fit, inner_fit
    # the stripes seen must agree on one straight width (texture beyond the edge does not), and
    # it must widen toward the near end as the stripe reach does (perspective)
    if w_sigma > params.hidden_stripe_max_scatter * float(median_of(width[seen])):
        return None
    if growth and w1 * growth <= 0:
        return None
    return HiddenStripe(i0, i1, w0, w1, float(t[seen].min()), float(t[seen].max()))


def _robust_linear(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float] | None:
    """``(a, b, sigma)`` of ``y ~ a + b x`` by least squares, refitted once without the points more
    than 3 robust sigmas off; ``sigma`` is the robust scatter (MAD) of the first fit's residuals."""
    if x.size < 3 or np.ptp(x) <= 0:
        return None
    design = np.stack([np.ones_like(x), x], axis=1)
    coef = np.linalg.lstsq(design, y, rcond=None)[0]
    residual = y - design @ coef
    sigma = MAD_TO_SIGMA * float(median_of(np.abs(residual - median_of(residual))))
    keep = np.abs(residual) <= 3.0 * max(sigma, 0.05)
    if keep.sum() >= 3 and np.ptp(x[keep]) > 0:
        coef = np.linalg.lstsq(design[keep], y[keep], rcond=None)[0]
    return float(coef[0]), float(coef[1]), sigma


def _outer_crossings(signed: np.ndarray, peak: np.ndarray, out_dir: int, offsets: np.ndarray, fractions):
    """Offsets where each row's lobe (``signed`` > 0 around column ``peak``) falls, walking
    outwards, below each fraction of its peak value (linear interpolation; NaN if it does not
    within the row)."""
    n, m = signed.shape
    rows = np.arange(n)
    top = signed[rows, peak]
    steps = np.arange(m)[None, :]
    order = np.clip(peak[:, None] + out_dir * steps, -1, m)            # columns walking outwards
    inside = (order >= 0) & (order < m)
    walk = np.where(inside, signed[rows[:, None], np.clip(order, 0, m - 1)], -np.inf)
    out = []
    for fraction in fractions:
        level = fraction * top[:, None]
        below = walk < level
        first = np.where(below.any(axis=1), below.argmax(axis=1), -1)
        ok = first >= 1
        j1 = np.clip(first, 1, m - 1)
        v0 = walk[rows, j1 - 1]
        v1 = walk[rows, j1]
        with np.errstate(invalid="ignore", divide="ignore"):
            frac = np.clip((v0 - level[:, 0]) / (v0 - v1), 0.0, 1.0)
        step = float(offsets[1] - offsets[0]) if len(offsets) > 1 else 1.0
        offset = offsets[np.clip(peak, 0, m - 1)] + out_dir * step * (j1 - 1 + frac)
        out.append(np.where(ok & np.isfinite(v1), offset, np.nan))
    return out


def stripe_offsets(profiles: np.ndarray, offsets: np.ndarray, polarity: int,
                   max_width_px: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """Sub-pixel centre of a bright (polarity +1) or dark (-1) stripe in each profile.

    The stripe's centre is the midpoint of its rising and falling edges: this works the same
    for a stripe narrower than a pixel (the two derivative peaks sit symmetrically about it)
    and for one many pixels wide. The edges are searched within ``max_width_px`` (scalar or
    one per profile) of the profile's extreme grey level.

    Parameters
    ----------
    profiles, offsets : ndarray, shapes (n, m) and (m,)
        Profiles across the line and the positions of their samples along its normal, as
        :func:`sample_profiles` returns them (pixels, evenly spaced; NaN outside the frame).
    polarity : int
        +1 for a bright stripe, -1 for a dark one.
    max_width_px : float or ndarray, shape (n,)
        Widest stripe expected, pixels (at least 2 samples are searched).

    Returns
    -------
    position : ndarray, shape (n,)
        Offset of the stripe centre, pixels (NaN where none).
    height : ndarray, shape (n,)
        Grey-level height of the stripe above its surroundings.
    """
    step = float(offsets[1] - offsets[0]) if len(offsets) > 1 else 1.0
    n, m = profiles.shape
    sign = 1.0 if polarity >= 0 else -1.0
    p = np.where(np.isfinite(profiles), profiles * sign, -np.inf)
    g = _derivative(np.where(np.isfinite(profiles), profiles, 0.0) * sign, step)
    g[~np.isfinite(g)] = 0.0
    centre = np.argmax(p, axis=1)
    columns = np.arange(m)[None, :]
    reach = np.broadcast_to(np.maximum(np.asarray(max_width_px, float) / step, 2.0), (n,))[:, None]
    left_zone = (columns <= centre[:, None]) & (columns >= centre[:, None] - reach) & (columns >= 2)
    right_zone = (columns >= centre[:, None]) & (columns <= centre[:, None] + reach) & (columns <= m - 3)
    rise = np.where(left_zone, g, -np.inf)
    fall = np.where(right_zone, -g, -np.inf)
    i_rise = np.argmax(rise, axis=1)
    i_fall = np.argmax(fall, axis=1)
    rows = np.arange(n)
    ok = np.isfinite(rise[rows, i_rise]) & np.isfinite(fall[rows, i_fall]) \
        & (rise[rows, i_rise] > 0) & (fall[rows, i_fall] > 0)
    d_rise = parabola_peak(g, i_rise)
    d_fall = parabola_peak(-g, i_fall)
    position = offsets[0] + step * (0.5 * (i_rise + d_rise + i_fall + d_fall))
    # height: the peak above the mean of the profile's two ends beyond the stripe edges
    outer_left = np.clip(i_rise - 3, 0, m - 1)
    outer_right = np.clip(i_fall + 3, 0, m - 1)
    base = 0.5 * (p[rows, outer_left] + p[rows, outer_right])
    height = p[rows, centre] - base
    ok &= np.isfinite(height) & (height > 0)
    return np.where(ok, position, np.nan), np.where(ok, height, 0.0)


def fit_line(points: np.ndarray, weights: np.ndarray, min_sigma_px: float = 0.05,
             iterations: int = 4) -> tuple[PixelLine, np.ndarray, float] | None:
    """Weighted total-least-squares line with Tukey biweight re-weighting.

    The scale is the median absolute deviation of the residuals (about their median) times
    1.4826, floored at ``min_sigma_px``; weights are Tukey's biweight with the cut-off 4.685 scales
    (95 % efficiency under Gaussian noise).

    Parameters
    ----------
    points : ndarray, shape (n, 2)
        Edge points, pixels (rows with NaN are not used).
    weights : ndarray, shape (n,)
        Non-negative prior weights (edge strengths); points of weight 0 are not used.
    min_sigma_px : float, optional
        Floor of the robust scale, pixels.
    iterations : int, optional
        Re-weighting passes.

    Returns
    -------
    tuple or None
        ``(line, inliers, sigma_px)``: the :class:`PixelLine` (point at the weighted centroid),
        the inlier mask over ``points`` (shape (n,)) and the robust scale (pixels); None with fewer
        than 3 usable points.
    """
    pts = np.asarray(points, float)
    w0 = np.asarray(weights, float)
    usable = np.isfinite(pts).all(axis=1) & (w0 > 0)
    if usable.sum() < 3:
        return None
    pts, w0 = pts[usable], w0[usable]
    w = w0
    line, sigma = None, math.inf
    for _ in range(iterations):
        total = w.sum()
        if total <= 0:
            return None
        centroid = (w @ pts) / total
        rel = pts - centroid
        sxx = (w * rel[:, 0] ** 2).sum() / total
        syy = (w * rel[:, 1] ** 2).sum() / total
        sxy = (w * rel[:, 0] * rel[:, 1]).sum() / total
        # principal axis of the 2x2 scatter matrix (closed form)
        angle = 0.5 * math.atan2(2.0 * sxy, sxx - syy)
        line = PixelLine(centroid, np.array([math.cos(angle), math.sin(angle)]))
        r = rel @ line.normal
        active = r[w > 0]
        centre = float(median_of(active)) if active.size else 0.0
        mad = float(median_of(np.abs(active - centre))) if active.size else 0.0
        sigma = max(MAD_TO_SIGMA * mad, min_sigma_px)
        # residuals about their median: a first fit pulled by outliers still keeps its inliers
        u = (r - centre) / (TUKEY_C * sigma)
        w = w0 * np.where(np.abs(u) < 1.0, (1 - u ** 2) ** 2, 0.0)
    inliers_usable = w > 0
    mask = np.zeros(len(usable), dtype=bool)
    mask[np.nonzero(usable)[0][inliers_usable]] = True
    return line, mask, sigma


def refine_line(image, line: PixelLine, t_range: tuple, kind: str = "edge", polarity: int = 0,
                halfwidth_px: float = 6.0, outward: int = 0, outward_reach_px=0.0,
                stripe_width_px=None, net_polarity: int = 0, params: DetectorParams | None = None,
                iterations: int | None = None) -> LineFit | NoFit:
    """Refine ``line`` on ``image`` between positions ``t_range`` along it.

    Parameters
    ----------
    image : ndarray (H, W)
        Full-resolution grey frame (uint8 or float32).
    line : PixelLine
        Predicted line (pixels).
    t_range : tuple of 2 float
        ``(t0, t1)``: the span sampled, pixels along ``line.direction`` from ``line.point``.
    kind : {"edge", "stripe"}
        A step edge (or a region's boundary, with ``outward``) or a painted stripe.
    polarity : int
        +1/-1: sign of the grey change along ``line.normal`` (edges), bright/dark (stripes);
        0 to take the stronger of either (edges only).
    halfwidth_px : float or callable
        First search band (or a function of the position t along the line giving it); each
        later pass halves it (not below ``params.refine_min_band_px``).
    outward : int
        0, or +1/-1: the side of the line (along +/- ``line.normal``) where the runway's
        outside lies. The edge is then the region's boundary (:func:`boundary_offsets`): past
        a painted border stripe up to ``outward_reach_px`` wide.
    outward_reach_px : float or callable
        Widest border stripe looked past, pixels (or a function of the position t along the
        line giving it).
    stripe_width_px : callable t -> width or None
        Widest stripe expected at each position (stripes only).
    net_polarity : int
        With ``outward``: the sign of the grey-level change from inside to outside the region
        (0: the majority of the profiles says). Profiles whose located boundary does not change
        the grey level that way (``params.refine_net_fraction``) are not used.
    params : DetectorParams, optional
        ``refine_samples`` profiles along the line (at most one per pixel), ``min_contrast``
        (weaker edges, in grey levels, are not used), ``refine_weak_fraction``,
        ``refine_run_gap_px`` / ``refine_run_gap_fraction`` (the visible stretch) and
        ``refine_min_band_px``.
    iterations : int, optional
        Passes (default ``params.refine_iterations``).

    Returns
    -------
    LineFit, or NoFit with the reason (fewer than 3 profiles hold an edge, no continuous run).
    """
    params = params or DetectorParams()
    iterations = params.refine_iterations if iterations is None else int(iterations)
    min_contrast = params.min_contrast
    t0, t1 = float(min(t_range)), float(max(t_range))
    length = t1 - t0
    if not (math.isfinite(length) and length >= 2.0):
        return NoFit(f"a span of {length:.1f} px is too short to refine")
    n = int(max(3, min(params.refine_samples, math.floor(length) + 1)))
    t = np.linspace(t0, t1, n)
    scale_band = 1.0
    # once a border stripe hid its outer flank (past_hidden_stripe), later passes keep its inner
    # flank within the band: the narrowed band around the boundary would lose it
    inner_room = False
    stripe = None
    current = line
    result = None
    for _ in range(iterations):
        centres = current.point + t[:, None] * current.direction
        band = np.broadcast_to(np.asarray(halfwidth_px(t) if callable(halfwidth_px) else halfwidth_px, float),
                               t.shape)
        halfwidth = np.maximum(band * scale_band, np.minimum(band, params.refine_min_band_px))
        stripe_reach = np.broadcast_to(np.asarray(
            outward_reach_px(t) if callable(outward_reach_px) else outward_reach_px, float), t.shape)
        profiles, offsets = sample_profiles(image, centres, current.normal, current.direction,
                                            float(halfwidth.max()) + (float(stripe_reach.max()) if outward else 0.0)
                                            + KERNEL_ROOM_PX,
                                            step_px=BOUNDARY_STEP_PX if (kind == "edge" and outward) else 1.0)
        inward = stripe_reach if inner_room else 0.0
        if outward:
            offsets_out = offsets[None, :] * outward
            window = (offsets_out >= -(halfwidth + inward)[:, None]) & (offsets_out <= halfwidth[:, None])
        else:
            window = np.abs(offsets)[None, :] <= halfwidth[:, None]
        if kind == "edge" and outward:
            position, strength, stripe_inner = boundary_offsets(profiles, offsets, outward, window, stripe_reach,
                                                                params=params)
            contrast = strength / RAMP_SLOPE_PER_STEP
        elif kind == "edge":
            position, strength = edge_offsets(profiles, offsets, polarity, window=window)
            contrast = strength / SLOPE_PER_STEP
        elif kind == "stripe":
            width = stripe_width_px(t) if stripe_width_px is not None else halfwidth
            position, contrast = stripe_offsets(profiles, offsets, polarity, width)
            strength = contrast
        else:
            raise ValueError(f"kind must be 'edge' or 'stripe', got {kind!r}")
        position_out = position * (outward if outward else 1)
        reach_out = stripe_reach if outward else 0.0
        located = (np.isfinite(position) & (position_out >= -(halfwidth + inward))
                   & (position_out <= halfwidth + reach_out))
        keep = located & (contrast >= min_contrast)
        why = (f"{int(located.sum())} of {n} profiles hold a {kind} within the band, "
               f"{int(keep.sum())} of at least {min_contrast:g} grey levels")
        if kind == "edge" and outward and keep.sum() >= 3:
            # the region's boundary separates its inside (past a border stripe) from its outside:
            # a marking's edge inside the region (its grey level against the surface) or a texture
            # edge outside it does not change the grey level the way the boundary does
            net = np.nan_to_num(net_step(profiles, offsets, position, outward, stripe_reach,
                                          params.net_step_outside_px, params.net_step_inside_px))
            sign = net_polarity or int(np.sign(median_of(net[keep])) or 1)
            keep &= net * sign >= params.refine_net_fraction * median_of(np.abs(net[keep]))
            why += f", {int(keep.sum())} changing the grey level the boundary's way"
        if keep.sum() >= 3:
            # texture beside the line (grass) is weaker than the line's own edge: drop points
            # much weaker than the line's typical strength
            keep &= contrast >= params.refine_weak_fraction * median_of(contrast[keep])
        if keep.sum() < 3:
            return NoFit(f"no consistent step along the line ({why})")
        if kind == "edge" and outward:
            growth = float(np.sign(stripe_reach[-1] - stripe_reach[0]) * np.sign(t[-1] - t[0]))
            position, moved, stripe = past_hidden_stripe(position, stripe_inner, keep, t, outward, growth, params,
                                                         prior=stripe)
            inner_room = inner_room or moved > 0
        points = centres + position[:, None] * current.normal
        weights = np.where(keep, np.minimum(strength, percentile_of(strength[keep], params.fit_weight_cap_percentile)),
                           0.0)
        fitted = fit_line(points, weights)
        if fitted is None:
            return NoFit(f"no line through the edge points ({why})")
        new_line, inliers, sigma = fitted
        # the line's visible stretch: the largest run of inliers without a long gap (stray
        # texture edges lined up beyond the runway's end are left out), then refit on it
        t_all = (points - new_line.point) @ new_line.direction
        run = _largest_run(t_all, inliers, max(params.refine_run_gap_px, params.refine_run_gap_fraction * length))
        if run.sum() < 3:
            return NoFit(f"the edge points form no continuous run ({int(inliers.sum())} inliers scattered)")
        if run.sum() < inliers.sum():
            fitted = fit_line(np.where(run[:, None], points, np.nan), np.where(run, weights, 0.0))
            if fitted is None:
                return NoFit("no line through the edge points of the longest run")
            new_line, inliers, sigma = fitted
        # keep the direction of travel of the prediction
        if new_line.direction @ current.direction < 0:
            new_line = PixelLine(new_line.point, -new_line.direction)
        n_in = int(inliers.sum())
        if n_in < 3:
            return NoFit(f"only {n_in} edge points agree on a line")
        rms, extent, sigma_offset, sigma_angle = _fit_statistics(new_line, points[inliers])
        t_profiles = (centres - new_line.point) @ new_line.direction
        in_span = np.count_nonzero((t_profiles >= extent[0] - 0.5) & (t_profiles <= extent[1] + 0.5))
        found_polarity = int(polarity) if polarity else int(np.sign(median_of(
            _signed_step(profiles[inliers], offsets))) or 1)
        result = LineFit(
            line=new_line, residual_px=rms, support=n_in / max(in_span, 1),
            contrast=float(median_of(contrast[inliers])), polarity=found_polarity, extent=extent,
            sigma_offset_px=sigma_offset, sigma_angle_rad=sigma_angle, n_inliers=n_in, points=points[inliers])
        # the next pass samples the same span around the fitted line, in a narrower band
        t = t_profiles
        if stripe is not None:
            stripe = stripe.restated(current, new_line)
        current = new_line
        scale_band /= 2.0
    return result


def chroma_boundary(colour, fit: LineFit, outward: int, reach_px: float,
                    params: DetectorParams | None = None) -> LineFit | NoFit:
    """Move a region's refined boundary (``fit``, from grey levels) onto its chroma boundary.

    A runway is grey pavement, white paint and rubber; grass and fields beside it are not grey.
    Where a painted side stripe, blended within a pixel with the asphalt, matches the grass's
    grey level, the grey step is the stripe's inner edge, up to a stripe width inside the
    runway; the chroma (largest minus smallest of R, G, B) still steps at the edge. Chroma
    profiles across ``fit.line`` (0.5 px apart): in each, the steepest chroma rise towards the
    outside (``outward`` along ``fit.line.normal``) between ``reach_px + 1`` inside the line
    and 1.5 px outside it, at the centroid of its derivative lobe, kept when the chroma rises
    by ``params.chroma_min_change`` levels across it (``params.chroma_samples`` profiles). A
    line fitted to those points replaces the grey one when they cover ``params.chroma_min_span``
    of the grey line's span; otherwise NoFit with the reason (the chroma does not tell: grey
    ground, haze, a grey-level camera).

    Parameters
    ----------
    colour : ndarray of uint8, shape (H, W, 3)
        The RGB frame.
    fit : LineFit
        The boundary refined on grey levels.
    outward : int
        +1/-1: the side of ``fit.line`` (along +/- its normal) where the region's outside lies.
    reach_px : float
        How far inside the grey line the chroma boundary is searched, pixels (a border stripe's
        width).
    params : DetectorParams, optional
        ``chroma_min_change``, ``chroma_min_span``, ``chroma_samples``.

    Returns
    -------
    LineFit or NoFit
        The boundary on the chroma (support and contrast those of ``fit``), or why not.
    """
    params = params or DetectorParams()
    min_change, min_span = params.chroma_min_change, params.chroma_min_span
    line = fit.line
    t0, t1 = fit.extent
    if not (math.isfinite(t0) and math.isfinite(t1)) or t1 - t0 < params.chroma_min_length_px:
        return NoFit(f"the grey boundary is shorter than {params.chroma_min_length_px:g} px")
    n = int(max(3, min(params.chroma_samples, math.floor(t1 - t0) + 1)))
    t = np.linspace(t0, t1, n)
    centres = line.point + t[:, None] * line.direction
    profiles, offsets = sample_profiles(colour, centres, line.normal, line.direction, reach_px + 5.0,
                                        step_px=BOUNDARY_STEP_PX)
    out_dir = 1.0 if outward >= 0 else -1.0
    rel = offsets * out_dir                                   # > 0 towards the outside
    g = np.full(profiles.shape, np.nan, np.float32)
    g[:, 1:-1] = (profiles[:, 2:] - profiles[:, :-2]) * out_dir          # rise towards the outside, per pixel
    window = (rel >= -reach_px - params.chroma_inside_margin_px) & (rel <= params.chroma_outside_reach_px)
    rising = np.where(np.isfinite(g) & window[None, :], g, -np.inf)
    peak = np.argmax(rising, axis=1)
    rows = np.arange(n)
    idx = np.clip(peak[:, None] + np.arange(-2, 3)[None, :], 0, len(offsets) - 1)
    w = np.maximum(np.nan_to_num(g[rows[:, None], idx]), 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        position = (w * offsets[idx]).sum(axis=1) / w.sum(axis=1)
    # the chroma just outside minus just inside the located boundary
    here = position[:, None] * out_dir
    finite = np.isfinite(profiles)
    values = np.where(finite, profiles, 0.0)

    def mean(mask):
        mask = mask & finite
        with np.errstate(invalid="ignore", divide="ignore"):
            return (values * mask).sum(axis=1) / mask.sum(axis=1)

    near, far = params.chroma_step_band_px
    change = mean((rel[None, :] >= here + near) & (rel[None, :] <= here + far)) \
        - mean((rel[None, :] <= here - near) & (rel[None, :] >= here - far))
    keep = np.isfinite(rising[rows, peak]) & np.isfinite(position) & (change >= min_change)
    covered = float(np.ptp(t[keep]) / (t1 - t0)) if keep.sum() >= 2 else 0.0
    if keep.sum() < 3 or covered < min_span:
        return NoFit(f"the chroma rises by {min_change:g} levels over {100 * covered:.0f} % of the boundary "
                     f"(< {100 * min_span:.0f} %)")
    points = centres + position[:, None] * line.normal
    fitted = fit_line(np.where(keep[:, None], points, np.nan), np.where(keep, change, 0.0))
    if fitted is None or fitted[1].sum() < 3:
        return NoFit("the chroma boundary points are not on a line")
    new_line, inliers, _ = fitted
    if new_line.direction @ line.direction < 0:
        new_line = PixelLine(new_line.point, -new_line.direction)
    rms, extent, sigma_offset, sigma_angle = _fit_statistics(new_line, points[inliers])
    if extent[1] - extent[0] < min_span * (t1 - t0):
        return NoFit(f"the collinear chroma boundary points cover {100 * (extent[1] - extent[0]) / (t1 - t0):.0f} % "
                     f"of the boundary (< {100 * min_span:.0f} %)")
    return LineFit(line=new_line, residual_px=max(rms, 0.05), support=fit.support, contrast=fit.contrast,
                   polarity=fit.polarity, extent=extent, sigma_offset_px=sigma_offset, sigma_angle_rad=sigma_angle,
                   n_inliers=int(inliers.sum()), points=points[inliers])


def _fit_statistics(line: PixelLine, points: np.ndarray, min_sigma_px: float = 0.05):
    """``(rms, extent, sigma_offset_px, sigma_angle_rad)`` of a line fitted to its inlying
    ``points``: RMS distance, span ``(t_min, t_max)`` along the line from ``line.point``, and the
    one-sigma offset and angle uncertainties from the RMS (floored at ``min_sigma_px``)."""
    rms = float(np.sqrt(np.mean(line.distance(points) ** 2)))
    t_in = (points - line.point) @ line.direction
    spread = float(np.sum((t_in - t_in.mean()) ** 2))
    sigma = max(rms, min_sigma_px)
    return (rms, (float(t_in.min()), float(t_in.max())), sigma / math.sqrt(len(points)),
            sigma / math.sqrt(spread) if spread > 0 else math.inf)


def net_step(profiles: np.ndarray, offsets: np.ndarray, position: np.ndarray, outward: int,
             stripe_reach, outside_px: tuple, inside_px: tuple) -> np.ndarray:
    """Grey level just outside a located boundary (between ``outside_px`` beyond it) minus inside
    it past a border stripe (between ``inside_px`` beyond the stripe's reach), per profile.

    Parameters
    ----------
    profiles : ndarray (n, m)
        Profiles across the boundary (:func:`sample_profiles`), NaN where not sampled.
    offsets : ndarray (m,)
        Position of each sample along the profile (pixels).
    position : ndarray (n,)
        The boundary's offset on each profile (NaN: none located).
    outward : int
        The sign of the offsets on the outside (+1 or -1).
    stripe_reach : float or ndarray (n,)
        How far inside the boundary a border stripe may reach (pixels).
    outside_px, inside_px : tuple of 2
        The bands read, pixels beyond the boundary and beyond the stripe's reach; each limit a
        number or an array of shape (n, 1) (one band per profile).

    Returns
    -------
    ndarray (n,)
        The net step, grey levels; NaN where a profile holds no sample on one side or no
        boundary.
    """
    out_dir = 1.0 if outward >= 0 else -1.0
    pos = np.nan_to_num(position)[:, None] * out_dir
    reach = np.broadcast_to(np.asarray(stripe_reach, float), (len(profiles),))[:, None]
    rel = offsets[None, :] * out_dir - pos
    outside = (rel >= outside_px[0]) & (rel <= outside_px[1])
    inside = (rel <= -reach - inside_px[0]) & (rel >= -reach - inside_px[1])
    finite = np.isfinite(profiles)

    def mean(mask):
        m = mask & finite
        return np.where(m, profiles, 0.0).sum(axis=1) / np.maximum(m.sum(axis=1), 1)

    net = mean(outside) - mean(inside)
    ok = ((outside & finite).sum(axis=1) > 0) & ((inside & finite).sum(axis=1) > 0) & np.isfinite(position)
    return np.where(ok, net, np.nan)


def _largest_run(t: np.ndarray, mask: np.ndarray, max_gap: float) -> np.ndarray:
    """Mask of the masked positions forming the most populated run with gaps <= max_gap."""
    chosen = np.zeros(len(t), dtype=bool)
    idx = np.nonzero(mask)[0]
    if len(idx) == 0:
        return chosen
    order = idx[np.argsort(t[idx])]
    breaks = np.nonzero(np.diff(t[order]) > max_gap)[0]
    starts = np.concatenate([[0], breaks + 1])
    ends = np.concatenate([breaks + 1, [len(order)]])
    best = int(np.argmax(ends - starts))
    chosen[order[starts[best]:ends[best]]] = True
    return chosen


def _signed_step(profiles: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Mean grey level on the +normal half minus the -normal half of each profile."""
    half = len(offsets) // 2
    def mean(block):
        finite = np.isfinite(block)
        return np.where(finite, block, 0.0).sum(axis=1) / np.maximum(finite.sum(axis=1), 1)
    return mean(profiles[:, half + 1:]) - mean(profiles[:, :half])
