"""Candidate lines: Canny edges and the probabilistic Hough transform (OpenCV) in a region of
interest, at a working resolution, then each segment checked and re-fitted on the frame.

The region is cropped from the frame and downsampled (area averaging) so that its larger
side is at most ``max_side_px``: Canny and the Hough transform cost in proportion to the
pixels they see (a full 2048x2048 Canny plus Hough takes about 70 ms), and the candidates
only need to be right to a pixel or two, because every chosen line is refined afterwards
against the full-resolution gradient (:mod:`visland.detection.refine`).

Canny's thresholds follow the frame's contrast: quantiles of the gradient magnitude of the
working image (a dim, hazy far runway and a sharp near one both give edges), with a floor so
that a flat or noise-only frame gives none.

Segments are then written in horizon coordinates (:mod:`visland.detection.horizon`) as lines
``s = s0 + k d`` over a span of depths, steep enough to be runway lines (not the horizon, a
road across the view or a threshold bar), merged when they are pieces of one edge, and
checked on the full-resolution frame (:func:`check_lines`).

Pixels: (0, 0) is the centre of the top-left pixel of the full frame (SPEC).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from visland.detection.horizon import HorizonFrame
from visland.detection.params import DetectorParams
from visland.detection.refine import (MAD_TO_SIGMA, SLOPE_PER_STEP, TUKEY_C, median_of, sample_profiles,
                                      transition_offsets)

#: sqrt(pi / 2): Gaussian residuals' mean absolute value times this is their standard deviation
#: (applied to the median absolute residual, its robust stand-in).
MEDIAN_ABS_TO_SIGMA = 1.2533
__all__ = ["Segments", "hough_segments", "banded_hough_segments", "CandidateLines", "candidate_lines", "check_lines",
           "pencil_normal_uv"]


@dataclass(frozen=True)
class Segments:
    """Hough segments in full-frame pixels.

    Attributes
    ----------
    uv_a, uv_b : ndarray (n, 2)
        End points, full-resolution pixels.
    scale : float
        Working-image pixels per full-resolution pixel (1 = full resolution).
    roi : tuple
        ``(u0, v0, u1, v1)`` searched (end exclusive).
    edge_fraction : float
        Fraction of the working image marked as edges (a noise-only frame has many short ones).
    """

    uv_a: np.ndarray
    uv_b: np.ndarray
    scale: float
    roi: tuple
    edge_fraction: float

    def __len__(self) -> int:
        return len(self.uv_a)

    @property
    def lengths(self) -> np.ndarray:
        return np.linalg.norm(self.uv_b - self.uv_a, axis=1)


def hough_segments(image: np.ndarray, roi: tuple, max_side_px: int, params: DetectorParams,
                   min_length_px: float | None = None) -> Segments:
    """Canny + probabilistic Hough segments inside ``roi`` of a grey uint8 frame.

    Parameters
    ----------
    image : ndarray (H, W) uint8
    roi : (u0, v0, u1, v1)
        Integer pixel bounds, end exclusive.
    max_side_px : int
        Working resolution: the crop is downsampled so its larger side is at most this.
    params : DetectorParams
    min_length_px : float, optional
        Shortest segment in working-image pixels (default ``params.hough_min_length_px``).
    """
    u0, v0, u1, v1 = (int(a) for a in roi)
    crop = image[v0:v1, u0:u1]
    scale = min(1.0, max_side_px / float(max(crop.shape)))
    if scale < 1.0:
        size = (max(8, int(round(crop.shape[1] * scale))), max(8, int(round(crop.shape[0] * scale))))
        work = cv2.resize(crop, size, interpolation=cv2.INTER_AREA)
        scale_u = size[0] / crop.shape[1]
        scale_v = size[1] / crop.shape[0]
    else:
        work = crop
        scale_u = scale_v = 1.0
    if params.blur_sigma_px > 0:
        work = cv2.GaussianBlur(work, (0, 0), params.blur_sigma_px)
    step = params.canny_quantile_step
    gx = cv2.Sobel(work[::step, ::step], cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(work[::step, ::step], cv2.CV_32F, 0, 1, ksize=3)
    magnitude = np.abs(gx) + np.abs(gy)                      # Canny's L1 gradient, on every step-th pixel
    low, high = np.quantile(magnitude, [params.canny_low_quantile, params.canny_high_quantile])
    high = max(float(high), params.canny_min_high)
    low = min(max(float(low), params.canny_min_low_ratio * high), high)
    edges = cv2.Canny(work, low, high, L2gradient=False)
    edge_fraction = float(np.count_nonzero(edges)) / edges.size
    min_length = params.hough_min_length_px if min_length_px is None else min_length_px
    lines = cv2.HoughLinesP(edges, 1.0, math.radians(params.hough_angle_step_deg), params.hough_votes,
                            minLineLength=min_length, maxLineGap=params.hough_max_gap_px)
    if lines is None:
        empty = np.zeros((0, 2))
        return Segments(empty, empty, scale, (u0, v0, u1, v1), edge_fraction)
    xy = lines.reshape(-1, 4).astype(float)
    # working pixel i is centred at full-resolution (i + 0.5) / scale - 0.5
    a = np.stack([(xy[:, 0] + 0.5) / scale_u - 0.5 + u0, (xy[:, 1] + 0.5) / scale_v - 0.5 + v0], axis=1)
    b = np.stack([(xy[:, 2] + 0.5) / scale_u - 0.5 + u0, (xy[:, 3] + 0.5) / scale_v - 0.5 + v0], axis=1)
    return Segments(a, b, min(scale_u, scale_v), (u0, v0, u1, v1), edge_fraction)


def banded_hough_segments(image: np.ndarray, roi: tuple, max_side_px: int, params: DetectorParams) -> Segments:
    """:func:`hough_segments` in ``roi``, and again in bands of its rows next to the horizon
    (``params.hough_depth_bands``, fractions of its height from its top), each band with its own
    Canny thresholds.

    The thresholds are quantiles of the gradient over the crop searched, which the near ground's
    texture dominates; haze (contrast falling as ``exp(-3 x / visibility)`` with distance x),
    overcast and dusk take a distant runway's edges below them, a few grey levels where the near
    fields step by tens. Among the distant ground's rows alone, the runway's edges are among the
    strongest. On the robustness study's 'overcast, 5 km' frame at 1.97 km (2048 px) the whole
    frame's candidates held no line of the runway; the first band's held both its edges.

    Parameters
    ----------
    image : ndarray (H, W) uint8
    roi : (u0, v0, u1, v1)
        Integer pixel bounds, end exclusive; its top rows are the ones nearest the horizon.
    max_side_px : int
        Working resolution of each search (:func:`hough_segments`).
    params : DetectorParams
        ``hough_depth_bands`` (a band of zero height, or under 8 rows, is not searched) and the
        Canny and Hough parameters.

    Returns
    -------
    Segments
        All the searches' segments; ``scale`` the coarsest of theirs (the end points'
        uncertainty), ``roi`` and ``edge_fraction`` those of the whole crop. The whole crop's
        own :class:`Segments` when no band is searched.
    """
    segments = hough_segments(image, roi, max_side_px, params)
    u0, v0, u1, v1 = (int(a) for a in roi)
    height = v1 - v0
    uv_a, uv_b = [segments.uv_a], [segments.uv_b]
    scale = segments.scale
    top = v0
    for fraction in params.hough_depth_bands:
        bottom = v0 + int(round(fraction * height))
        if bottom - top >= 8:
            band = hough_segments(image, (u0, top, u1, bottom), max_side_px, params)
            uv_a.append(band.uv_a)
            uv_b.append(band.uv_b)
            scale = min(scale, band.scale)
        top = max(top, bottom)
    if len(uv_a) == 1:
        return segments
    return Segments(np.concatenate(uv_a), np.concatenate(uv_b), scale, segments.roi, segments.edge_fraction)


@dataclass(frozen=True)
class CandidateLines:
    """Candidate lines in horizon coordinates ``s = s0 + k d`` over depths ``[d_a, d_b]``.

    ``sigma_s0`` is the one-sigma uncertainty of each line's horizon crossing (its
    segment's end points known to ``1 / scale`` pixels, extrapolated to the horizon).
    ``polarity`` is the sign of the grey-level change across the line towards +s, ``contrast``
    the median step (grey levels) and ``support`` the fraction of profiles holding that step.

    Attributes
    ----------
    s0 : ndarray, shape (n,)
        Horizon crossing of each line, pixels along the horizon from Q (the line's d_F).
    k : ndarray, shape (n,)
        Slope ``ds/dd`` of each line in horizon coordinates (dimensionless).
    d_a, d_b : ndarray, shape (n,)
        Depths below the horizon (pixels) of the far and near ends of the span each line was seen
        over (``d_a < d_b``).
    sigma_s0 : ndarray, shape (n,)
        One-sigma uncertainty of ``s0``, pixels.
    polarity : ndarray of int, shape (n,)
        +1 (grey rises towards +s) or -1; empty before :func:`check_lines`.
    contrast : ndarray, shape (n,)
        Median grey-level step across each line; empty before :func:`check_lines`.
    support : ndarray, shape (n,)
        Fraction of each line's profiles holding the step, 0..1; empty before :func:`check_lines`.
    """

    s0: np.ndarray
    k: np.ndarray
    d_a: np.ndarray
    d_b: np.ndarray
    sigma_s0: np.ndarray
    polarity: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    contrast: np.ndarray = field(default_factory=lambda: np.zeros(0))
    support: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __len__(self) -> int:
        return len(self.s0)


def pencil_normal_uv(horizon: HorizonFrame, k) -> tuple[np.ndarray, np.ndarray]:
    """Unit direction (towards larger d) and unit normal (towards larger s) of pencil lines, pixels.

    Parameters
    ----------
    horizon : HorizonFrame
        The frame's horizon (unit direction ``t_uv`` and ground-side normal ``n_uv``).
    k : float or array_like, shape (...)
        Slopes ``ds/dd`` of the lines ``s = s0 + k d``.

    Returns
    -------
    direction, normal : ndarray, shape (..., 2)
        Unit pixel vectors along each line (towards larger d, the ground) and across it (towards
        larger s).
    """
    k = np.asarray(k, float)[..., None]
    norm = np.sqrt(1.0 + k ** 2)
    direction = (k * horizon.t_uv + horizon.n_uv) / norm
    normal = (horizon.t_uv - k * horizon.n_uv) / norm
    return direction, normal


def candidate_lines(segments: Segments, horizon: HorizonFrame, params: DetectorParams,
                 min_depth_px: float = 1.0) -> CandidateLines:
    """Candidate segments that could be runway lines, merged and in horizon coordinates.

    Segments are written as ``s = s0 + k d`` (horizon coordinates), kept when steep enough to be a
    runway line (``|k| <= params.max_edge_slope``), entirely below ``min_depth_px`` and at least
    ``params.candidate_min_length_fraction * params.min_edge_length_px`` long; the longest
    ``params.max_candidates`` are merged greedily (longest first) when they lie within
    ``params.segment_merge_working_px`` working pixels plus ``params.segment_merge_px`` of each
    other, and each group is re-fitted by length-weighted least squares.

    Parameters
    ----------
    segments : Segments
        Hough segments, full-resolution pixels (:func:`hough_segments`).
    horizon : HorizonFrame
        The frame's horizon, which sets the (s, d) coordinates.
    params : DetectorParams
        Thresholds named above, scaled to the frame.
    min_depth_px : float, optional
        Segments reaching closer than this to the horizon (pixels of depth) are dropped.

    Returns
    -------
    CandidateLines
        Without polarity, contrast or support (set by :func:`check_lines`).

    References
    ----------
    Gibert, PhD thesis (2016), 5.3.2.2: runway lines found by the Hough transform, the runway a
    trapezoid in the image.
    """
    if len(segments) == 0:
        return CandidateLines(*(np.zeros(0) for _ in range(5)))
    a = horizon.to_sd(segments.uv_a)
    b = horizon.to_sd(segments.uv_b)
    swap = a[:, 1] > b[:, 1]
    a, b = np.where(swap[:, None], b, a), np.where(swap[:, None], a, b)     # a: far end (smaller d)
    dd = b[:, 1] - a[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        k = (b[:, 0] - a[:, 0]) / dd
    keep = (dd > 1.0) & (np.abs(k) <= params.max_edge_slope) & (a[:, 1] > min_depth_px)
    length = np.hypot(b[:, 0] - a[:, 0], dd)
    keep &= length >= params.min_edge_length_px * params.candidate_min_length_fraction
    if not np.any(keep):
        return CandidateLines(*(np.zeros(0) for _ in range(5)))
    a, b, k, dd, length = a[keep], b[keep], k[keep], dd[keep], length[keep]
    order = np.argsort(-length)[:params.max_candidates]
    a, b, k, dd, length = a[order], b[order], k[order], dd[order], length[order]
    s0 = a[:, 0] - k * a[:, 1]
    # merge segments lying on one line (Canny double edges, broken edges): greedy, longest first
    end_error = 1.0 / max(segments.scale, 1e-3)
    merged = []
    used = np.zeros(len(k), dtype=bool)
    for i in range(len(k)):
        if used[i]:
            continue
        group = [i]
        used[i] = True
        for j in range(i + 1, len(k)):
            if used[j]:
                continue
            # distance between the two lines at both ends of segment j and of segment i
            dj = np.array([a[j, 1], b[j, 1], a[i, 1], b[i, 1]])
            gap = np.abs((s0[i] + k[i] * dj) - (s0[j] + k[j] * dj)) / np.sqrt(1 + k[i] ** 2)
            if gap.max() <= params.segment_merge_working_px * end_error + params.segment_merge_px:
                group.append(j)
                used[j] = True
        points = np.concatenate([a[group], b[group]])
        weights = np.concatenate([length[group], length[group]])
        # least squares s = s0 + k d over the end points, weighted by segment length
        A = np.stack([np.ones(len(points)), points[:, 1]], axis=1)
        W = weights / weights.sum()
        try:
            coef = np.linalg.solve(A.T @ (W[:, None] * A) + 1e-9 * np.eye(2), A.T @ (W * points[:, 0]))
        except np.linalg.LinAlgError:
            coef = np.array([s0[i], k[i]])
        d_a, d_b = float(points[:, 1].min()), float(points[:, 1].max())
        span = max(d_b - d_a, 1.0)
        d_mid = 0.5 * (d_a + d_b)
        sigma_k = math.sqrt(2.0) * end_error / span
        merged.append((coef[0], coef[1], d_a, d_b, math.hypot(end_error, sigma_k * d_mid)))
    m = np.array(merged, dtype=float)
    return CandidateLines(m[:, 0], m[:, 1], m[:, 2], m[:, 3], m[:, 4])


def check_lines(image, horizon: HorizonFrame, lines: CandidateLines, params: DetectorParams) -> CandidateLines:
    """Check each candidate line on the full-resolution frame and re-fit it.

    Hough segments found at the working resolution are often short, slightly turned pieces
    of an edge. Two passes: profiles across the line are sampled over its Hough span (band
    ``params.check_first_band_px``), the transition in each profile is located and the line
    ``s = s0 + k d`` re-fitted to them with a robust weight; then profiles are sampled around the
    re-fitted line (band ``params.check_second_band_px``) over its span extended by
    ``params.check_extend_far`` times its length towards the horizon and
    ``params.check_extend_near`` times towards the image bottom, the line is re-fitted again and
    its span becomes the run of consistent points that holds the first span.
    Returns the lines with polarity (sign of the grey-level step towards +s), contrast
    (median step, grey levels) and support (fraction of the span's profiles holding the
    edge); duplicates (two Hough pieces of one edge) are merged.

    Parameters
    ----------
    image : ndarray of uint8, shape (H, W)
        Full-resolution grey frame.
    horizon : HorizonFrame
        The frame's horizon.
    lines : CandidateLines
        From :func:`candidate_lines`.
    params : DetectorParams
        ``check_*`` thresholds, ``min_contrast``, ``pencil_fit_min_sigma_px``,
        ``crossing_min_sigma_px``, ``duplicate_gap_px``; scaled to the frame.

    Returns
    -------
    CandidateLines
        The lines that hold on the frame, re-fitted, with polarity, contrast and support.
    """
    if len(lines) == 0:
        return lines
    n_samples = params.check_samples
    extend = params.check_first_extend
    span = np.maximum(lines.d_b - lines.d_a, params.check_min_span_px)
    first = _evidence_pass(image, horizon, lines.s0, lines.k, np.maximum(lines.d_a - extend * span, 1.0),
                           lines.d_b + extend * span, params.check_first_band_px, n_samples // 2, params)
    if len(first) == 0:
        return CandidateLines(*(np.zeros(0) for _ in range(5)))
    span = np.maximum(first[:, 3] - first[:, 2], params.check_min_span_px)
    second = _evidence_pass(image, horizon, first[:, 0], first[:, 1],
                            np.maximum(first[:, 2] - params.check_extend_far * span, 1.0),
                            first[:, 3] + params.check_extend_near * span, params.check_second_band_px, n_samples,
                            params, keep=(first[:, 2], first[:, 3]))
    if len(second) == 0:
        return CandidateLines(*(np.zeros(0) for _ in range(5)))
    arr = _merge_duplicates(second, params.duplicate_gap_px)
    return CandidateLines(arr[:, 0], arr[:, 1], arr[:, 2], arr[:, 3], arr[:, 4], arr[:, 5].astype(int), arr[:, 6],
                       arr[:, 7])


def _evidence_pass(image, horizon: HorizonFrame, s0_lines, k_lines, d_lo, d_hi, halfwidth_px: float,
                   n_samples: int, params: DetectorParams, keep=None) -> np.ndarray:
    """One pass of :func:`line_evidence`: rows ``(s0, k, d_a, d_b, sigma_s0, polarity, contrast, support)``."""
    n = len(s0_lines)
    frac = (np.arange(n_samples) + 0.5) / n_samples
    d = d_lo[:, None] + frac[None, :] * (d_hi - d_lo)[:, None]                     # (n, m)
    centres = horizon.pencil_point(s0_lines[:, None], k_lines[:, None], d).reshape(-1, 2)
    direction, normal = pencil_normal_uv(horizon, np.repeat(k_lines, n_samples))
    side_px = params.check_transition_side_px
    # room beyond the band for the grey levels read either side of a transition (and the kernel)
    profiles, offsets = sample_profiles(image, centres, normal, direction, halfwidth_px + (side_px[1] + 1.0))
    window = np.broadcast_to(np.abs(offsets)[None, :] <= halfwidth_px, profiles.shape)
    position, strength, net = transition_offsets(profiles, offsets, window, params.check_transition_halfspan_px,
                                                 side_px)
    contrast_all = (strength / SLOPE_PER_STEP).reshape(n, n_samples)
    step = net.reshape(n, n_samples)
    edge_s = (s0_lines[:, None] + k_lines[:, None] * d) \
        + position.reshape(n, n_samples) * np.sqrt(1 + k_lines[:, None] ** 2)
    out = []
    for i in range(n):
        ok = np.isfinite(edge_s[i]) & (contrast_all[i] >= params.min_contrast) & np.isfinite(step[i])
        if ok.sum() < params.check_min_points:
            continue
        polarity = int(np.sign(median_of(step[i][ok])))
        ok &= np.sign(step[i]) == polarity
        if ok.sum() < params.check_min_points or polarity == 0:
            continue
        fit = _robust_pencil_fit(d[i][ok], edge_s[i][ok], contrast_all[i][ok], params.pencil_fit_min_sigma_px,
                                 params.check_fit_iterations, params.check_fit_min_inliers,
                                 params.fit_weight_cap_percentile)
        if fit is None:
            continue
        s0, k, inlier = fit
        depth_ok = d[i][ok][inlier]
        # longest run of inliers without a gap of more than a fifth of the sampled span
        order = np.sort(depth_ok)
        gap = params.check_max_gap_fraction * (d_hi[i] - d_lo[i])
        breaks = np.nonzero(np.diff(order) > gap)[0]
        starts = np.concatenate([[0], breaks + 1])
        ends = np.concatenate([breaks + 1, [len(order)]])
        if keep is None:
            best = int(np.argmax(ends - starts))
        else:   # the run overlapping most the span found before
            overlap = [np.count_nonzero((order[a:b] >= keep[0][i]) & (order[a:b] <= keep[1][i]))
                       for a, b in zip(starts, ends)]
            best = int(np.argmax(overlap))
        run = order[starts[best]:ends[best]]
        if len(run) < params.check_min_run_points:
            continue
        d_a, d_b = float(run[0]), float(run[-1])
        in_span = np.count_nonzero((d[i] >= d_a) & (d[i] <= d_b))
        support = len(run) / max(in_span, 1)
        contrast = float(median_of(contrast_all[i][ok][inlier]))
        length = (d_b - d_a) * math.sqrt(1 + k * k)
        if length < params.candidate_min_length_fraction * params.min_edge_length_px:
            continue
        residual = np.abs(edge_s[i][ok][inlier] - (s0 + k * depth_ok)) / math.sqrt(1 + k * k)
        sigma_px = max(MEDIAN_ABS_TO_SIGMA * float(median_of(residual)), params.check_line_min_sigma_px)
        spread = max(float(np.std(run)), 1.0)
        # horizon crossing uncertainty: offset and slope errors extrapolated from the run's middle
        sigma_s0 = sigma_px * math.sqrt(1 + k * k) * math.hypot(1.0, 0.5 * (d_a + d_b) / spread) / math.sqrt(len(run))
        out.append((s0, k, d_a, d_b, max(sigma_s0, params.crossing_min_sigma_px), polarity, contrast, support))
    return np.array(out, dtype=float).reshape(-1, 8)


def _robust_pencil_fit(d, s, weights, min_sigma: float, iterations: int, min_inliers: int, weight_cap_percentile: float):
    """Fit ``s = s0 + k d`` with Tukey re-weighting (robust scale floored at ``min_sigma``, weights
    capped at their ``weight_cap_percentile``); returns (s0, k, inlier mask), or None with fewer
    than ``min_inliers`` inliers."""
    w0 = np.minimum(weights, np.percentile(weights, weight_cap_percentile))
    w = w0.copy()
    A = np.stack([np.ones_like(d), d], axis=1)
    coef = None
    for _ in range(iterations):
        if np.count_nonzero(w > 0) < 3:
            return None
        AtW = A.T * w
        try:
            coef = np.linalg.solve(AtW @ A + 1e-9 * np.eye(2), AtW @ s)
        except np.linalg.LinAlgError:
            return None
        r = s - A @ coef
        scale = max(MAD_TO_SIGMA * float(median_of(np.abs(r[w > 0]))), min_sigma)
        u = r / (TUKEY_C * scale)
        w = w0 * np.where(np.abs(u) < 1, (1 - u * u) ** 2, 0.0)
    inlier = w > 0
    if inlier.sum() < min_inliers:
        return None
    return float(coef[0]), float(coef[1]), inlier


def _merge_duplicates(arr: np.ndarray, max_gap_px: float) -> np.ndarray:
    """Keep one of several candidates describing one edge (same crossing, slope and polarity:
    within ``max_gap_px`` of each other over their common span)."""
    order = np.argsort(-(arr[:, 3] - arr[:, 2]) * arr[:, 7])
    kept = []
    for i in order:
        s0, k, d_a, d_b, sigma, polarity = arr[i, :6]
        duplicate = False
        for j in kept:
            if arr[j, 5] != polarity:
                continue
            depths = np.array([max(d_a, arr[j, 2]), min(d_b, arr[j, 3])])
            if depths[1] < depths[0]:
                depths = np.array([d_a, d_b])
            gap = np.abs((s0 + k * depths) - (arr[j, 0] + arr[j, 1] * depths)) / math.sqrt(1 + k * k)
            if gap.max() < max_gap_px:
                duplicate = True
                break
        if not duplicate:
            kept.append(i)
    return arr[kept]
