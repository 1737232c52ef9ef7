"""The symmetry/trapezoid model: which lines are the runway's left edge, right edge and centre
line (thesis 5.3.2.2).

A runway of unknown size is a trapezoid in the image whose sides meet on the horizon. In
horizon coordinates (:mod:`visland.detection.horizon`: s along the horizon, d below it) its
three lines are ``s = s0 + k d`` with one ``s0`` (the vanishing point V1 on the horizon) and
``k_C = (k_L + k_R) / 2`` (the centre line is the harmonic conjugate of the horizon with
respect to the edges: midway between them along any line parallel to the horizon).

The model works in two steps:

1. Vanishing point candidates: every checked candidate line proposes the point where it
   meets the horizon; proposals that agree are pooled and ranked by the evidence of their
   lines (the runway's edges, its centre line and markings, and whatever runs along it:
   taxiways, roads, field boundaries, all meet there).
2. For each candidate point, the frame is resampled on the lines through it
   (:mod:`visland.detection.pencil`), where every line through the point is a column, and
   the steps along columns are found. A runway is a pair of steps of opposite signs (the
   same two materials on mirrored sides) that overlap in depth, whose inside differs from
   its outside the way the steps say (between a runway edge and a taxiway edge lies mostly
   grass, like outside), with a stripe midway (the centre line). Pairs are ranked by the
   strength, continuity and symmetry of both edges, the centre stripe, the width (of
   parallel paved strips the runway is the widest: a taxiway is half as wide) and agreement
   with the previous frame's runway when there is one.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from visland.detection.candidates import CandidateLines
from visland.detection.horizon import HorizonFrame, widths_along
from visland.detection.params import DetectorParams
from visland.detection.refine import median_of
from visland.detection.pencil import (PencilEdges, PencilImage, as_slice, finite_median, pencil_edges, rectify, row_mean,
                                      row_quantile, row_quantiles)

__all__ = ["Prediction", "RunwayHypothesis", "vanishing_point_candidates", "runway_hypotheses", "is_convincing_strip",
           "wider_strip_beside"]


@dataclass(frozen=True)
class Prediction:
    """The runway expected in this frame (from the previous detection), horizon coordinates.

    Attributes
    ----------
    s0 : float
        Vanishing point V1 on the horizon, pixels from Q along it.
    k_left, k_right : float
        Slopes ``ds/dd`` of the left and right edges (horizon coordinates).
    d_far, d_near : float
        Depths (pixels below the horizon) of the far and near ends of the edges' support.
    sigma_px : float
        One-sigma motion (pixels) of the runway from the prediction, widening the search band.
    threshold_marked : bool
        The previous detection's threshold carried its marking
        (:attr:`~visland.detection.result.DetectionResult.threshold_marked`): the strip followed
        keeps it, and it is not read again.
    """

    s0: float
    k_left: float
    k_right: float
    d_far: float
    d_near: float
    sigma_px: float
    threshold_marked: bool = False


@dataclass(frozen=True)
class RunwayHypothesis:
    """A left/right edge pair through one horizon point, with its evidence.

    Attributes
    ----------
    s0 : float
        Vanishing point V1 on the horizon, pixels from Q along it.
    k_left, k_right : float
        Slopes ``ds/dd`` of the left and right edges; the centre line is at
        ``k_centre = (k_left + k_right) / 2``.
    d_far, d_near : float
        Depths (pixels below the horizon) over which both edges are seen.
    polarity_left, polarity_right : int
        Sign of each edge's grey-level step towards +s (0: unknown, a prediction).
    score : float
        The trapezoid model's ranking score (larger is better; comparable within one frame).
    centre_polarity : int
        +1 bright / -1 dark centre stripe found midway, 0 none.
    centre_support : float
        Fraction of the depth bands holding the centre stripe, 0..1.
    evidence : dict
        The terms of the score (symmetry, contrast, interior, spread, ends, prior, ...) for
        diagnostics; ``{"predicted": True}`` for a hypothesis made from a prediction.
    """

    s0: float
    k_left: float
    k_right: float
    d_far: float
    d_near: float
    polarity_left: int
    polarity_right: int
    score: float
    centre_polarity: int
    centre_support: float
    evidence: dict

    @property
    def k_centre(self) -> float:
        return 0.5 * (self.k_left + self.k_right)


def vanishing_point_candidates(lines: CandidateLines, params: DetectorParams, max_points: int = 4,
                               prediction: Prediction | None = None) -> list[tuple[float, float, tuple, tuple]]:
    """Points of the horizon where several checked lines meet, best first.

    Returns ``(s0, weight, (k_min, k_max), (d_min, d_max))`` per point: the lines' slopes and
    depths, to bound the search around it. A prediction is always a candidate.

    Parameters
    ----------
    lines : CandidateLines
        Checked candidate lines (:func:`visland.detection.candidates.check_lines`).
    params : DetectorParams
        ``vp_min_line_support``, ``min_contrast``, ``vp_line_weight_max_px``, ``vp_tolerance_px``,
        ``vp_sigma_factor``.
    max_points : int, optional
        Most points returned (besides the prediction).
    prediction : Prediction, optional
        The runway expected from the previous frame: its point comes first.

    Returns
    -------
    list of tuple
        ``(s0, weight, (k_min, k_max), (d_min, d_max))`` per point (pixels from Q; summed line
        weight, ``inf`` for the prediction; slopes and depths of its lines).

    References
    ----------
    Gibert, PhD thesis (2016), 5.3.2.2: the runway's lines meet on the horizon.
    """
    out = []
    usable = ((lines.support >= params.vp_min_line_support) & (lines.contrast >= params.min_contrast)
              if len(lines) else np.zeros(0, bool))
    index = np.nonzero(usable)[0]
    if len(index):
        s0 = lines.s0[index]
        weight = lines.contrast[index] * lines.support[index] * np.minimum(
            (lines.d_b[index] - lines.d_a[index]) * np.sqrt(1 + lines.k[index] ** 2), params.vp_line_weight_max_px)
        tolerance = params.vp_tolerance_px + params.vp_sigma_factor * lines.sigma_s0[index]
        # each line's vote, spread over its tolerance; a point's score sums the lines it holds
        held = np.abs(s0[:, None] - s0[None, :]) <= np.maximum(tolerance[:, None], tolerance[None, :])
        score = held.astype(float) @ weight
        taken = np.zeros(len(index), bool)
        for i in np.argsort(-score):
            if taken[i]:
                continue
            members = held[i] & ~taken
            taken |= held[i]
            w = weight[members]
            centre = float(np.average(s0[members], weights=w))
            j = index[members]
            out.append((centre, float(score[i]), (float(lines.k[j].min()), float(lines.k[j].max())),
                        (float(lines.d_a[j].min()), float(lines.d_b[j].max()))))
            if len(out) >= max_points:
                break
    if prediction is not None:
        out = [p for p in out if abs(p[0] - prediction.s0) > params.vp_tolerance_px]
        out.insert(0, (prediction.s0, math.inf, (prediction.k_left, prediction.k_right),
                       (prediction.d_far, prediction.d_near)))
    return out


def runway_hypotheses(image, horizon: HorizonFrame, lines: CandidateLines, params: DetectorParams,
                      prediction: Prediction | None = None,
                      bottom_depth_px: float = math.inf, inside: int = 0,
                      vanishing_points: list[float] | None = None) -> list[RunwayHypothesis]:
    """Rank left/right edge pairs by the trapezoid model and the image evidence (best first;
    at most ``params.max_hypotheses``).

    Parameters
    ----------
    image : ndarray of uint8, shape (H, W)
        Full-resolution grey frame, or any one-channel image in which a runway is a strip (its
        chroma: :func:`visland.detection.refine.chroma_of`).
    horizon : HorizonFrame
        The frame's horizon, which sets the (s, d) coordinates.
    lines : CandidateLines
        Checked candidate lines.
    params : DetectorParams
        The ``vp_*``, ``pencil_*``, ``pair_*``, ``score_*``, ``strip_*`` parameters, scaled.
    prediction : Prediction, optional
        The runway expected from the previous frame (tracking): the search is bounded around it
        and hypotheses agreeing with it are preferred.
    bottom_depth_px : float, optional
        Deepest depth visible in the frame (pixels below the horizon).
    inside : int, optional
        -1 keeps only strips lower inside than beside them (+1 higher, 0 both): paved surfaces
        are grey, so in chroma a runway is a strip of low chroma, and a strip of high chroma is a
        field between paved areas.
    vanishing_points : list of float, optional
        Acquisition only: search through these horizon points ``s0`` instead of those of ``lines``.

    Returns
    -------
    list of RunwayHypothesis

    References
    ----------
    Gibert, PhD thesis (2016), 5.3.2.2 and Fig. 5.13: the runway, whose two edges are parallel,
    is a trapezoid in the image; its symmetry is what the detector looks for.
    """
    hypotheses = []
    tracking = prediction is not None
    if vanishing_points is not None and not tracking:
        points = [(float(s0), math.inf, (math.nan, math.nan), (math.nan, math.nan)) for s0 in vanishing_points]
    else:
        points = vanishing_point_candidates(lines, params, prediction=prediction,
                                            max_points=params.vp_points_tracking if tracking
                                            else params.vp_points_acquisition)
    for s0, _, (k_min, k_max), (d_min, d_max) in points:
        # the lines that found the point need not be the runway's (a taxiway, a field boundary
        # along it): search every slope, unless tracking a predicted runway
        if tracking:
            margin = params.tracking_slope_margin
            k_range = (max(-params.max_edge_slope, k_min - margin), min(params.max_edge_slope, k_max + margin))
            span = max(d_max - d_min, params.tracking_min_depth_span_px)
            d_range = (max(1.0, d_min - params.tracking_depth_margin_far * span),
                       min(bottom_depth_px, d_max + params.tracking_depth_margin_near * span))
            rect = rectify(image, horizon, s0, k_range, d_range)
        else:   # every slope, the whole ground below the point, rows in proportion to depth
            k_range = (-params.max_edge_slope, params.max_edge_slope)
            d_range = (params.acquisition_min_depth_px, min(bottom_depth_px, params.acquisition_max_depth_px))
            rect = rectify(image, horizon, s0, k_range, d_range, max_rows=params.acquisition_rect_rows,
                           max_columns=params.acquisition_rect_columns, geometric_rows=True)
        if rect is None:
            continue
        edges = pencil_edges(rect, params)
        pairs = _pairs(rect, edges, params, prediction, horizon.camera.fx, bottom_depth_px)
        # the left edge steps down into a strip lower than its surroundings
        hypotheses.extend(h for h in pairs if not inside or h.polarity_left == inside)
    hypotheses.sort(key=lambda h: -h.score)
    hypotheses = _prefer_enclosing(hypotheses, params)
    hypotheses = _prefer_widest_parallel(hypotheses, params)
    hypotheses = _ground_between_strips_last(hypotheses, params)
    return hypotheses[:params.max_hypotheses]


def _pairs(rect: PencilImage, edges: PencilEdges, params: DetectorParams,
           prediction: Prediction | None, rect_focal_px: float,
           bottom_depth_px: float = math.inf) -> list[RunwayHypothesis]:
    """Left/right pairs among the steps of one rectified image, scored."""
    n = len(edges)
    if n < 2:
        return []
    L, R = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    ok = (edges.k[L] < edges.k[R]) & (edges.polarity[L] == -edges.polarity[R])
    d_far = np.maximum(edges.d_a[L], edges.d_a[R])
    d_near = np.minimum(edges.d_b[L], edges.d_b[R])
    ok &= d_near > d_far
    ok &= (edges.k[R] - edges.k[L]) * d_near >= params.pair_min_width_px
    # a runway is a long strip: with d = f h / x (x the distance ahead, h the height) and
    # W / h = k_R - k_L, the strip seen from depth d_far to d_near is
    # L / W = f (d_near - d_far) / ((k_R - k_L) d_near d_far) long (truncated spans only
    # shorten it); but not a line: a strip seen longer than any runway is a painted stripe
    # (a side stripe's two flanks) or a road
    with np.errstate(divide="ignore", invalid="ignore"):
        length_to_width = widths_along(rect_focal_px, d_near, d_far, edges.k[R] - edges.k[L])
    ok &= (length_to_width >= params.min_length_to_width) & (length_to_width <= params.max_length_to_width)
    li, ri = L[ok], R[ok]
    if len(li) == 0:
        return []
    far, near = d_far[ok], d_near[ok]
    c_l, c_r = edges.contrast[li], edges.contrast[ri]
    symmetry = np.minimum(c_l, c_r) / np.maximum(c_l, c_r)
    width = edges.k[ri] - edges.k[li]
    k_c = 0.5 * (edges.k[li] + edges.k[ri])
    length = (near - far) * np.sqrt(1 + k_c ** 2)
    length_term = 1.0 - np.exp(-length / params.pair_length_scale_px)
    prior = np.ones(len(li))
    if prediction is not None:
        depths = np.array([max(prediction.d_far, 1.0), max(prediction.d_near, 1.0)])
        s_pred_l = prediction.s0 + prediction.k_left * depths
        s_pred_r = prediction.s0 + prediction.k_right * depths
        gap_l = np.abs(rect.s0 + edges.k[li][:, None] * depths - s_pred_l).max(axis=1)
        gap_r = np.abs(rect.s0 + edges.k[ri][:, None] * depths - s_pred_r).max(axis=1)
        prior = np.exp(-0.5 * (np.maximum(gap_l, gap_r) / prediction.sigma_px) ** 2)
        # and about as wide as before (a parallel taxiway is half as wide)
        width_ratio = (edges.k[ri] - edges.k[li]) / max(prediction.k_right - prediction.k_left, 1e-9)
        prior = np.where(np.abs(width_ratio - 1.0) <= params.max_width_change, prior, 0.0)
    # inside against both outsides from the band profiles, for every pair at once: a runway's
    # inside differs from the ground beside it, the same on both sides
    overlap = np.clip(np.minimum(near[:, None], edges.bands[None, :, 1])
                      - np.maximum(far[:, None], edges.bands[None, :, 0]), 0.0, None)
    band_w = overlap / np.maximum(edges.bands[None, :, 1] - edges.bands[None, :, 0], 1e-9)
    k_l, k_r = edges.k[li], edges.k[ri]
    margin, gap = params.pair_interior_margin, params.pair_quick_centre_gap
    out_in, out_out = params.pair_outside_band
    inside = 0.5 * (edges.band_means(band_w, rect.k, k_l + margin * width, k_c - gap * width)
                    + edges.band_means(band_w, rect.k, k_c + gap * width, k_r - margin * width))
    out_l = edges.band_means(band_w, rect.k, k_l - out_out * width, k_l - out_in * width)
    out_r = edges.band_means(band_w, rect.k, k_r + out_in * width, k_r + out_out * width)
    expected = np.where(edges.polarity[li] < 0, -1.0, 1.0)
    contrast_min = np.maximum(np.minimum(c_l, c_r), 1.0)
    quick_interior = np.nan_to_num(np.clip(expected * (inside - 0.5 * (out_l + out_r)) / contrast_min, 0.0, 1.0))
    quick_outside = np.nan_to_num(np.clip(1.0 - np.abs(out_l - out_r) / contrast_min, 0.0, 1.0))
    pre_score = (length_term * np.minimum(c_l, c_r) * (params.score_symmetry_floor + symmetry) * prior
                 * quick_interior * (params.score_outside_floor + quick_outside) * width ** params.score_width_exponent)
    hypotheses = []
    # the ground's grey level row by row: the median over the whole width of the pencil (every
    # slope the search allows, a few hundred metres either side), where fields and grass are the
    # majority and a paved strip is a minority
    ground_rows = row_quantile(rect.values[:, ::params.ground_rows_column_step], 0.5)
    for p in np.argsort(-pre_score)[:params.pair_max_examined]:
        if pre_score[p] <= 0:
            continue
        inside = _inside_evidence(rect, edges.k[li[p]], edges.k[ri[p]], far[p], near[p], params, ground_rows)
        contrast = max(float(min(c_l[p], c_r[p])), 1.0)
        # inside darker than outside when the left edge darkens towards +s, and vice versa;
        # a runway's inside differs from its outside by about its edges' step
        expected = -1.0 if edges.polarity[li[p]] < 0 else 1.0
        interior_term = float(np.clip(expected * inside["interior"] / contrast, 0.0, 1.0))
        if interior_term <= params.pair_min_interior:
            continue
        # the ground between two pavements (a runway and its parallel taxiway): its inside has the
        # ground's grey level and its outsides do not, where a runway is the other way round
        off_ground = abs(inside["inside_minus_ground"])
        if (float(width[p]) < params.pair_ground_test_max_width and math.isfinite(off_ground)
                and off_ground < params.pair_min_off_ground * abs(inside["interior"])):
            continue
        step = max(abs(inside["interior"]), contrast)
        outside_term = float(np.clip(1.0 - abs(inside["outside_gap"]) / step, 0.0, 1.0))
        uniform_term = float(np.clip(1.0 - inside["spread"] / (params.score_spread_scale * step),
                                     params.score_uniform_floor, 1.0))
        # a painted centre line (white; a dark stripe counts less)
        centre_term = inside["centre_rows"] * (1.0 if inside["centre_polarity"] > 0 else params.score_dark_centre_weight)
        # width: among parallel paved strips the runway is the widest (a taxiway is about half
        # as wide, a road a fifth), but a wide pair of unrelated lines must not win by width
        width_term = float(width[p]) ** params.score_width_exponent
        # a runway is a finite strip: it ends (threshold, runway end) inside the image, where a
        # road or a field boundary runs on to the horizon and out of the frame
        ends = _strip_ends(rect, edges.k[li[p]], edges.k[ri[p]], far[p], near[p], bottom_depth_px, params)
        ends_term = params.score_ends_base + params.score_ends_per_end * ends
        score = float(pre_score[p] * interior_term * (params.score_outside_floor + outside_term) * uniform_term
                      * (params.score_centre_floor + centre_term) * width_term * ends_term)
        centre_polarity = inside["centre_polarity"]
        hypotheses.append(RunwayHypothesis(
            s0=rect.s0, k_left=float(edges.k[li[p]]), k_right=float(edges.k[ri[p]]), d_far=float(far[p]),
            d_near=float(near[p]), polarity_left=int(edges.polarity[li[p]]),
            polarity_right=int(edges.polarity[ri[p]]), score=score, centre_polarity=int(centre_polarity),
            centre_support=centre_term,
            evidence={"symmetry": float(symmetry[p]), "contrast": contrast, "interior": inside["interior"],
                      "outside_gap": inside["outside_gap"], "spread": inside["spread"],
                      "centre_rows": inside["centre_rows"], "ends": ends, "prior": float(prior[p]),
                      "inside_minus_ground": inside["inside_minus_ground"],
                      "length_px": float(length[p]),
                      "width_k": float(width[p])}))
    return hypotheses


def _inside_evidence(rect: PencilImage, k_left: float, k_right: float, d_far: float, d_near: float,
                     params: DetectorParams, ground_rows: np.ndarray | None = None) -> dict:
    """What lies between and beside a pair of edges, from the rectified image.

    Returns a dict: ``interior`` (median grey inside minus outside), ``outside_gap`` (median
    grey outside the left edge minus outside the right edge), ``spread`` (interquartile range
    inside), ``centre_polarity`` and ``centre_rows`` (fraction of rows holding a stripe on
    the midline), ``inside_minus_ground`` (median grey inside minus the median of
    ``ground_rows``, the ground's level per row of ``rect``, over the same rows; NaN without
    them). A runway's inside is one surface (markings in the minority) with the same
    ground on both sides; its centre line is a stripe in most rows (dashes included), where
    texture would make one in a few.
    """
    empty = {"interior": 0.0, "outside_gap": math.inf, "spread": math.inf, "centre_polarity": 0, "centre_rows": 0.0,
             "inside_minus_ground": math.nan}
    rows = rect.rows_between(d_far, d_near)
    if rows.sum() < 2:
        return empty
    block = rect.values[as_slice(rows)]
    width = k_right - k_left

    def columns(f_lo, f_hi):
        c = rect.column_of([k_left + f_lo * width, k_left + f_hi * width])
        return slice(int(min(c)), int(max(c)) + 1)

    def values(*parts):
        v = np.concatenate([block[:, part].ravel() for part in parts])
        return v[np.isfinite(v)]

    margin, gap = params.pair_interior_margin, params.pair_centre_gap
    out_in, out_out = params.pair_outside_band
    inside = values(columns(margin, 0.5 - gap), columns(0.5 + gap, 1.0 - margin))
    out_left, out_right = values(columns(-out_out, -out_in)), values(columns(1.0 + out_in, 1.0 + out_out))
    if inside.size < 4 or out_left.size < 4 or out_right.size < 4:
        return empty
    q25, q50, q75 = np.percentile(inside, [25, 50, 75])
    m_left, m_right = float(median_of(out_left)), float(median_of(out_right))
    ground = finite_median(ground_rows[rows]) if ground_rows is not None else math.nan
    result = {"interior": float(q50 - 0.5 * (m_left + m_right)), "outside_gap": m_left - m_right,
              "spread": float(q75 - q25), "centre_polarity": 0, "centre_rows": 0.0,
              "inside_minus_ground": float(q50 - ground)}
    # centre stripe: per row, the mean near the midline against the mean a little farther out on
    # either side
    centre = int(rect.column_of(0.5 * (k_left + k_right)))
    side_in, side_out = params.centre_stripe_sides
    half = max(1, int(round(params.centre_stripe_halfwidth * width / rect.k_step)))
    inner = max(half + 1, int(round(side_in * width / rect.k_step)))
    outer = max(inner + 1, int(round(side_out * width / rect.k_step)))
    if centre - outer < 0 or centre + outer >= block.shape[1]:
        return result
    mid = row_mean(block[:, centre - half:centre + half + 1])
    sides = 0.5 * (row_mean(block[:, centre - outer:centre - inner + 1])
                   + row_mean(block[:, centre + inner:centre + outer + 1]))
    ridge = mid - sides
    ridge = ridge[np.isfinite(ridge)]
    if ridge.size < 2:
        return result
    threshold = max(params.centre_stripe_min_step, params.centre_stripe_fraction * abs(result["interior"]))
    bright, dark = float(np.mean(ridge > threshold)), float(np.mean(ridge < -threshold))
    result["centre_polarity"], result["centre_rows"] = (1, bright) if bright >= dark else (-1, dark)
    return result


def _strip_ends(rect: PencilImage, k_left: float, k_right: float, d_far: float, d_near: float,
                bottom_depth_px: float, params: DetectorParams) -> int:
    """How many ends (0, 1, 2) the strip between two edges shows inside the rectified rows.

    Row by row, the strip's surface (the lower quartile between the edges when it is darker
    than beside it, the upper quartile otherwise) is compared with the ground beside it;
    the run of rows that look like the strip's middle is followed outwards, and an end is
    counted where it stops with rows beyond it that look like the ground, before the
    horizon and the image bottom.
    """
    width = k_right - k_left
    f = (rect.k - k_left) / width
    in_lo, in_hi = params.strip_inside_band
    side_in, side_out = params.strip_side_band
    inside = (f >= in_lo) & (f <= in_hi)
    outside = ((f >= -side_out) & (f <= -side_in)) | ((f >= 1.0 + side_in) & (f <= 1.0 + side_out))
    if inside.sum() < 2 or outside.sum() < 2:
        return 0
    with np.errstate(invalid="ignore"):
        out_level = row_quantile(rect.values[:, outside], 0.5)
        between = rect.values[:, as_slice(inside)]
        low, high = row_quantiles(between, (0.25, 0.75))
    core_margin = params.strip_core_margin * (d_near - d_far)
    core = rect.rows_between(d_far + core_margin, d_near - core_margin)
    if core.sum() < 1:
        core = rect.rows_between(d_far, d_near)
    if core.sum() < 1:
        return 0
    darker = finite_median(low[core] - out_level[core]) < 0
    contrast = (low - out_level) if darker else (high - out_level)
    reference = finite_median(contrast[core])
    if not math.isfinite(reference) or reference == 0.0:
        return 0
    strip = np.nan_to_num(contrast * np.sign(reference), nan=-1.0) > params.strip_level_fraction * abs(reference)
    ground = np.nan_to_num(contrast * np.sign(reference), nan=1e9) < params.ground_level_fraction * abs(reference)
    rows = np.nonzero(core)[0]
    ends = 0
    for start, step in ((rows[0], -1), (rows[-1], 1)):
        i = start
        while 0 <= i + step < len(strip) and strip[i + step]:
            i += step
        beyond = np.arange(i + step, i + step * (params.strip_end_rows + 1), step)
        beyond = beyond[(beyond >= 0) & (beyond < len(strip))]
        clearance = params.strip_end_clearance_px
        limit_ok = rect.d[i] > clearance if step < 0 else rect.d[i] < bottom_depth_px - clearance
        if limit_ok and len(beyond) >= min(2, params.strip_end_rows) and ground[beyond].mean() >= 0.5:
            ends += 1
    return ends


def is_convincing_strip(h: RunwayHypothesis, params: DetectorParams) -> bool:
    """Whether ``h`` is a convincing paved strip (:func:`_prefer_widest_parallel`): an inside that
    differs from the outside as much as the edges say (``strip_min_interior``) and is mostly one
    surface (``strip_max_spread``: a runway's markings spread it), the same ground on both sides
    (``strip_max_outside_gap``), and an end in view.

    Parameters
    ----------
    h : RunwayHypothesis
        A hypothesis with its ``evidence`` (from :func:`runway_hypotheses`).
    params : DetectorParams
        The ``strip_*`` parameters.

    Returns
    -------
    bool
    """
    return _is_one_surface_strip(h, params) and h.evidence.get("ends", 0) >= 1


def _is_one_surface_strip(h: RunwayHypothesis, params: DetectorParams) -> bool:
    """:func:`is_convincing_strip` without its end in view."""
    e = h.evidence
    contrast = max(e.get("contrast", 0.0), 1e-6)
    interior = abs(e.get("interior", 0.0))
    return (interior >= params.strip_min_interior * contrast
            and abs(e.get("outside_gap", math.inf)) <= params.strip_max_outside_gap * max(interior, contrast)
            and e.get("spread", math.inf) <= params.strip_max_spread * interior)    # mostly one surface


def _paved_like(h: RunwayHypothesis, r: RunwayHypothesis, params: DetectorParams) -> bool:
    """Whether ``r`` is a strip of the same kind of surface as the convincing strip ``h``: a
    convincing strip itself, or one that passes every test of :func:`is_convincing_strip` but its
    end in view, whose inside lies on the same side of the ground's grey level as ``h``'s
    (``inside_minus_ground``, both pavements darker or both brighter than the fields).

    The end is not asked of the wider strip beside a convincing one: a runway seen with a
    lateral offset of a few widths far out (the robustness study's 'variety 1' at 3.4 km, 22 deg
    of roll) had its hypothesis a few pixels off to one side, so that no end of it stood out
    against the ground beside (283 m of pavement before its threshold), while the parallel
    taxiway 211 m to its right, 23 m wide, showed both ends; the taxiway was measured as the
    runway (edges 66 px off) for two frames.
    """
    if not _is_one_surface_strip(r, params):
        return False
    if r.evidence.get("ends", 0) >= 1:
        return True
    mine, theirs = h.evidence.get("inside_minus_ground", math.nan), r.evidence.get("inside_minus_ground", math.nan)
    return bool(math.isfinite(mine) and math.isfinite(theirs) and mine * theirs > 0)


def wider_strip_beside(h: RunwayHypothesis, r: RunwayHypothesis, params: DetectorParams) -> bool:
    """Whether ``r`` is a paved strip beside ``h`` (the same vanishing point, ground at least
    ``params.parallel_min_gap`` of ``h``'s width between them) and wider by
    ``params.parallel_min_width_ratio``: of the two, ``r`` is the runway. Unlike
    :func:`_side_by_side` the steps are not compared: ``r`` may come from another channel (the
    chroma, where pavement is always the lower side).

    Parameters
    ----------
    h, r : RunwayHypothesis
        Two hypotheses in horizon coordinates (``s = s0 + k d``; ``k`` is lateral offset over height).
    params : DetectorParams
        ``parallel_min_gap`` and ``parallel_min_width_ratio``.

    Returns
    -------
    bool
    """
    width = h.k_right - h.k_left
    gap = params.parallel_min_gap * width
    apart = r.k_left - h.k_right >= gap or h.k_left - r.k_right >= gap
    return abs(r.s0 - h.s0) < 1e-6 and apart and (r.k_right - r.k_left) > params.parallel_min_width_ratio * width


def _prefer_widest_parallel(hypotheses: list[RunwayHypothesis], params: DetectorParams) -> list[RunwayHypothesis]:
    """Of strips running side by side (one vanishing point, disjoint), put the widest first.

    A runway and its parallel taxiway (half as wide), or a road along it, all look like long
    paved strips; the runway is the widest. Wherever a strip stands in the ranking, a wider
    strip beside it (``params.parallel_min_width_ratio``) is moved just ahead of it. Only
    convincing strips count: a score at least ``params.parallel_score_ratio`` of the other's (per
    grey level of edge contrast when the wider one's is the lower and it is at least as long,
    :func:`_scores_as_parallel_strip`), an
    inside that differs from the outside as much as the edges say and is mostly one surface
    (``strip_min_interior``, ``strip_max_spread``: a runway's markings spread it), the same ground
    on both sides (``strip_max_outside_gap``), and an end in view; the wider one may lack the end
    when its inside lies on the same side of the ground's level as the narrower one's
    (:func:`_paved_like`).
    """
    def is_strip(h):
        return is_convincing_strip(h, params)

    ordered = []
    remaining = list(hypotheses)
    while remaining:
        h = remaining.pop(0)
        if is_strip(h):
            width = h.k_right - h.k_left
            rivals = [r for r in remaining
                      if abs(r.s0 - h.s0) < 1e-6 and _scores_as_parallel_strip(r, h, params)
                      and _paved_like(h, r, params)
                      and _side_by_side(h, r, params.parallel_min_gap * width)
                      and (r.k_right - r.k_left) > params.parallel_min_width_ratio * width]
            if rivals:
                widest = max(rivals, key=lambda r: r.k_right - r.k_left)
                remaining.remove(widest)
                remaining.insert(0, h)
                h = widest
        ordered.append(h)
    return ordered


def _scores_as_parallel_strip(r: RunwayHypothesis, h: RunwayHypothesis, params: DetectorParams) -> bool:
    """Whether the strip ``r`` scores at least ``params.parallel_score_ratio`` of the strip ``h``
    beside it, the scores taken per grey level of edge contrast when ``r``'s contrast is the
    lower and ``r`` is at least as long in the image.

    A hypothesis's score grows with its edges' contrast (the smaller step of the two), which says
    how far the two materials differ in grey, not which strip is the runway: in monochrome a
    concrete runway on sand steps by 9 grey levels where the asphalt taxiway beside it steps by
    53, and the runway (twice as wide, longer, both ends in view) scored 0.22 of the taxiway
    (robustness study at 2048 px, 'concrete, sand, mono', 3.65 km; the taxiway was acquired and
    tracked for 197 frames). Divided by their contrasts the two scores compare the strips' shape:
    symmetry, length, a uniform inside that differs from both outsides as the edges say, ends.
    Only for a strip at least as long in the image as ``h``: a parallel taxiway serves its
    runway's length, so the runway is no shorter. A wide faint strip shorter than the taxiway
    (a second runway or a field 1.7 heights out on 'taxiways near threshold', in the chroma at
    3.7 km: 46 px long against the taxiway's 55 and the runway's 81) is compared on raw scores.
    """
    floor = params.parallel_score_ratio * h.score
    contrast_h, contrast_r = h.evidence.get("contrast", math.nan), r.evidence.get("contrast", math.nan)
    as_long = r.evidence.get("length_px", 0.0) >= h.evidence.get("length_px", math.inf)
    if contrast_r < contrast_h and as_long:     # NaN contrast: raw scores only
        floor *= contrast_r / contrast_h
    return r.score >= floor


def _ground_between_strips_last(hypotheses: list[RunwayHypothesis],
                                params: DetectorParams) -> list[RunwayHypothesis]:
    """Put the ground between two paved strips after the strip it touches.

    Between a runway and a parallel taxiway lies a band of grass bounded by their facing edges:
    a pair of edges of opposite steps meeting on the same horizon point, as long as the runway,
    uniform inside, wider than the runway, and one of its edges is the runway's. Two such
    hypotheses that share an edge with their steps reversed are a strip and the ground beside
    it; the one whose inside has the ground's grey level (``inside_minus_ground``: the median of
    the whole pencil's rows, where fields and grass are the majority) is the ground. It is
    moved just after the other, which is moved ahead wherever it was ranked among the hypotheses of
    its vanishing point (if it scores at least ``params.parallel_score_ratio`` of it), but not
    ahead of a hypothesis of another vanishing point that outscores it: the ground's score is not
    the strip's (at 2000 m on the bench frames a field's bright strip, 0.6 of the runway's score,
    was moved over the runway beside the field's grass, and the frame was not found). Without
    that evidence nothing moves.
    """
    out = list(hypotheses)
    i = 0
    budget = len(out) ** 2 + 1                  # each step moves the ground after a strip; bound it anyway
    while i < len(out) and budget > 0:
        budget -= 1
        h = out[i]
        width_h = h.k_right - h.k_left
        for j in range(i + 1, len(out)):
            r = out[j]
            width_r = r.k_right - r.k_left
            tolerance = params.parallel_min_gap * min(width_h, width_r)
            touching = abs(r.k_left - h.k_right) <= tolerance or abs(r.k_right - h.k_left) <= tolerance
            if not (abs(r.s0 - h.s0) < 1e-6 and touching and r.score >= params.parallel_score_ratio * h.score
                    and (r.polarity_left, r.polarity_right) == (-h.polarity_left, -h.polarity_right)):
                continue
            scale = max(h.evidence.get("contrast", 1.0), r.evidence.get("contrast", 1.0), 1.0)
            h_ground = abs(h.evidence.get("inside_minus_ground", math.nan)) / scale
            r_ground = abs(r.evidence.get("inside_minus_ground", math.nan)) / scale
            if h_ground + params.ground_between_margin < r_ground:     # NaN: no decision
                r = out.pop(j)
                between = out[i + 1:j]
                ahead = [x for x in between if abs(x.s0 - r.s0) >= 1e-6 and x.score > r.score]
                rest = [x for x in between if not any(x is a for a in ahead)]
                out[i:j] = ahead + [r, h] + rest
                if ahead:
                    i -= 1                      # out[i] is now one of those: examine it too
                break
        i += 1
    return out


def _side_by_side(h: RunwayHypothesis, r: RunwayHypothesis, min_gap_k: float) -> bool:
    """Whether ``r`` is another paved strip beside ``h``: the same two materials (its edges step
    the same way, so its inside is brighter or darker than the ground like ``h``'s), with ground
    between them at least ``min_gap_k`` wide (in ``k``, width over height).

    The ground between a runway and its parallel taxiway is itself bounded by two edges of
    opposite steps and looks like a strip, wider than either, that shares one edge with each:
    its steps are the runway's reversed (grass brighter than the asphalt beside it), and it
    touches the runway. Neither holds for a parallel taxiway, whose edge lies a strip of
    ground away (ICAO Annex 14: at least about 1.4 runway widths even for the smallest
    runways), with the runway's polarities.
    """
    if (r.polarity_left, r.polarity_right) != (h.polarity_left, h.polarity_right):
        return False
    if r.k_left >= h.k_right:
        return r.k_left - h.k_right >= min_gap_k
    if r.k_right <= h.k_left:
        return h.k_left - r.k_right >= min_gap_k
    return False


def _prefer_enclosing(hypotheses: list[RunwayHypothesis], params: DetectorParams) -> list[RunwayHypothesis]:
    """Move ahead of a hypothesis any that encloses it with the same midline and a comparable
    score: the runway's outer boundary rather than the inner edges of its side stripes."""
    if len(hypotheses) < 2:
        return hypotheses
    best = hypotheses[0]
    width = best.k_right - best.k_left
    for other in hypotheses[1:]:
        other_width = other.k_right - other.k_left
        if (abs(other.s0 - best.s0) < 1e-6 and other.k_left < best.k_left and other.k_right > best.k_right
                and abs(other.k_centre - best.k_centre) < params.enclosing_centre_tolerance * width
                and other_width < params.enclosing_max_width_ratio * width
                and other.score >= params.enclosing_score_ratio * best.score):
            return [other] + [h for h in hypotheses if h is not other]
    return hypotheses
