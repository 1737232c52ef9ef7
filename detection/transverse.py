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

from visland.detection.horizon import HorizonFrame, cross3, depth_along, meet_h, widths_along
from visland.detection.params import DetectorParams
from visland.detection.pencil import as_slice, finite_median, rectify, row_mean, row_quantile, row_quantiles
from visland.detection.refine import MAD_TO_SIGMA, PixelLine, chroma_of, median_of

__all__ = ["TransverseLine", "SurfaceExtent", "find_transverse_line", "surface_extent", "edge_crossings_s",
           "transverse_grid", "transverse_line_h", "pavement_beyond_edges"]


class SurfaceExtent(tuple):
    """``(d_far, d_near)``: depths where the runway's surface ends; ``.level``: the surface's own
    grey level between its markings (the lower quartile across a dark runway, the upper one
    across a bright one), read where both edges are well supported.

    Parameters
    ----------
    d_far, d_near : float
        Depths below the horizon (pixels) of the surface's far and near ends.
    level : float
        The surface's grey level between its markings.
    near_runs_out : bool
        The surface runs on to the last row read in the image: its near end is where the image
        ends, not a step (the threshold, or the pavement before it, below the image).
    """

    def __new__(cls, d_far: float, d_near: float, level: float, near_runs_out: bool = False):
        extent = super().__new__(cls, (float(d_far), float(d_near)))
        extent.level = float(level)
        extent.near_runs_out = bool(near_runs_out)
        return extent


#: Departures from the ground of the level and of the texture profiles this close (pixels of
#: depth) are one boundary seen twice.
SAME_DEPARTURE_PX = 1.5
#: The level's departure places the boundary instead of the texture's when the texture departs
#: at most this far outside it (pixels of depth: the spread's half-level crossing of the boundary
#: sampled across) and the level's step is at least ``LEVEL_OVER_TEXTURE`` times the texture's
#: (the pavement's own level change, not its stripes'): :func:`find_transverse_line`.
ON_BOUNDARY_PX = 0.75
LEVEL_OVER_TEXTURE = 2.0

#: A chroma step looked for past a narrow runway's marking band (:func:`find_transverse_line`) lies
#: at least this many depth pixels inside the depths read: nearer their end the profile shows only
#: the rising flank of a step beyond them ('concrete, dry grass' at 1024 px, 2.3 km: the flank 2.5
#: px before the end of the depths read, 2.4 px short of the threshold, which lay just past them).
FAR_PICK_CLEARANCE_PX = 3.0


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
    method : str
        ``"ground-exit"`` (the outermost departure from the ground's level, grey levels),
        ``"grey"`` (the strongest step near the surface's end), or ``"chroma"``.
    spans : bool
        Whether the step is found at the same depth in each third of the runway's width (a
        marking or a pavement beside the runway does not span it).
    """

    line_h: np.ndarray
    corner_left_uv: np.ndarray
    corner_right_uv: np.ndarray
    depth_px: float
    step: float
    significance: float
    method: str = "grey"
    spans: bool = True


def surface_extent(image, horizon: HorizonFrame, s0: float, k_left: float, k_right: float,
                   d_support: tuple, d_window: tuple, step_d_px: float = 0.5,
                   marking_fraction: float | None = None, max_rows: int = 800,
                   params: DetectorParams | None = None) -> SurfaceExtent | None:
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

    A runway's surface can change along it: a concrete runway darkened by rubber in its
    touchdown zones is darker than grass there and brighter at its clean ends. Past either end
    of the run of runway rows, across at most a runway width of rows where the surface's level
    crosses the ground's, rows whose quartile lies on the other side of both sides' ground level
    (by ``strip_level_fraction`` of the middle's contrast) carry the runway on to where they
    end, gaps in them (a pavement joining one side) bridged as in the run.

    Parameters
    ----------
    image : ndarray of uint8, shape (H, W), or FloatFrame
        The grey frame, as the camera took it (full resolution), or read through a
        :class:`~visland.detection.pencil.FloatFrame` (several calls on one frame).
    horizon : HorizonFrame
        Its horizon: the rows resampled are lines through V1 on it.
    s0 : float
        The runway's vanishing point V1 on the horizon, pixels from Q.
    k_left, k_right : float
        Slopes ``ds/dd`` of the left and right edges through V1.
    d_support : tuple of 2 float
        ``(d_far, d_near)``: depths (pixels) over which both edges are supported; its middle
        (``strip_core_margin``-style 20 % trimmed each end) is the reference.
    d_window : tuple of 2 float
        ``(d_min, d_max)``: depths searched (pixels below the horizon).
    step_d_px : float, optional
        Row spacing near the horizon, pixels of depth.
    marking_fraction : float, optional
        Reach of a band of blended threshold markings along the runway, in runway widths
        (``params.marking_band_widths`` by default).
    max_rows : int, optional
        Most rows resampled (rows spaced geometrically when the cap is reached).
    params : DetectorParams, optional
        The strip as the trapezoid model reads it: ``strip_inside_band`` (the surface between
        the edges), ``strip_side_band`` (the ground beside each), ``strip_core_margin`` (the
        reference rows) and ``strip_level_fraction`` (a row is the runway's); the
        ``surface_*`` parameters (the rows resampled: ``surface_side_margin``,
        ``surface_rect_columns``, ``surface_width_samples``).

    Returns
    -------
    SurfaceExtent or None
        None when the surface cannot be told from the ground at the reference depths.
    """
    params = params or DetectorParams()
    if marking_fraction is None:
        marking_fraction = params.marking_band_widths
    width = k_right - k_left
    # rows every half pixel near the horizon and at most max_rows of them (geometric beyond)
    n_rows = int(min(max_rows, max(8, (d_window[1] - d_window[0]) / step_d_px + 1)))
    side = params.surface_side_margin
    rect = rectify(image, horizon, s0, (k_left - side * width, k_right + side * width), d_window,
                   max_rows=n_rows, max_columns=params.surface_rect_columns,
                   pixel_step=max(0.5, width * d_window[1] / params.surface_width_samples),
                   geometric_rows=n_rows == max_rows)
    if rect is None:
        return None
    f = (rect.k - k_left) / width
    in_lo, in_hi = params.strip_inside_band
    side_in, side_out = params.strip_side_band
    inside = as_slice((f >= in_lo) & (f <= in_hi))
    beside = (as_slice((f >= -side_out) & (f <= -side_in)), as_slice((f >= 1.0 + side_in) & (f <= 1.0 + side_out)))
    with np.errstate(invalid="ignore"):
        # the ground beside each edge separately: a taxiway joining one side makes that side
        # paved for a while, the other side still tells the runway from its surroundings
        out_levels = [row_quantile(rect.values[:, side], 0.5) for side in beside]
        low, high, median = row_quantiles(rect.values[:, inside], (0.25, 0.75, 0.5))
    core_margin = params.strip_core_margin
    core = (rect.d >= d_support[0] + core_margin * (d_support[1] - d_support[0])) & \
        (rect.d <= d_support[1] - core_margin * (d_support[1] - d_support[0]))
    if core.sum() < 2:
        return None
    out_level = row_mean(np.stack(out_levels, axis=1))          # both sides (a band's reference)
    darker = finite_median(low[core] - out_level[core]) < 0
    surface = low if darker else high
    runway = np.zeros(len(rect.d), dtype=bool)
    flipped_sides = np.zeros(len(rect.d), dtype=int)
    references = []
    for level in out_levels:
        reference_side = finite_median((surface - level)[core])
        if (np.isfinite(reference_side) and abs(reference_side) >= params.surface_min_contrast
                and (reference_side < 0) == darker):
            contrast = np.nan_to_num((surface - level) * np.sign(reference_side))
            runway |= contrast > params.strip_level_fraction * abs(reference_side)
            flipped_sides += contrast < -params.strip_level_fraction * abs(reference_side)
            references.append(reference_side)
    if not references:
        return None
    reference = float(median_of(references))
    # the surface on the other side of both sides' ground level, three quarters of the row at
    # least (the quartile read is the one markings do not move): the same runway, its surface
    # changing along it (a concrete runway darkened by rubber in its touchdown zones is darker
    # than grass there and brighter at its ends; one side's ground alone can be a brighter patch)
    flipped = flipped_sides == len(references)
    # majority over three rows, then the run of runway rows holding the core
    runway, flipped = _majority_of_three(runway), _majority_of_three(flipped)
    centre = int(np.nonzero(core)[0][len(np.nonzero(core)[0]) // 2])
    if not runway[centre]:
        return None
    fx = horizon.camera.fx
    # a pavement crossing the runway (both sides paved for its width) interrupts the run: a
    # gap shorter than a runway width along the runway is bridged when runway rows whose
    # surface has the runway's own level resume after it
    surface_level = finite_median(surface[core])
    same_surface = np.abs(np.nan_to_num(surface - surface_level, nan=np.inf)) < 0.5 * abs(reference)

    def gap_limit(depth):
        return width * depth * depth / fx

    def extend(index, direction):
        while True:
            nxt = index + direction
            while 0 <= nxt < len(runway) and runway[nxt]:
                index, nxt = nxt, nxt + direction
            # a gap: does the runway resume within a runway width?
            limit = gap_limit(rect.d[index])
            j = nxt
            while 0 <= j < len(runway) and not runway[j] and abs(rect.d[j] - rect.d[index]) <= limit:
                j += direction
            resumes = 0 <= j < len(runway) and runway[j] and abs(rect.d[j] - rect.d[index]) <= limit
            if not resumes:
                return index
            # the resumed stretch must be runway surface, and long enough not to be a marking
            k = j
            while 0 <= k + direction < len(runway) and runway[k + direction]:
                k += direction
            if not (same_surface[min(j, k):max(j, k) + 1].mean() > params.surface_resume_fraction
                    and abs(k - j) >= params.surface_resume_rows):
                return index
            index = k

    def extend_flipped(index, direction):
        # past the run's end, across the rows where the surface's level crosses the ground's
        # (a runway width at most), flipped rows, each gap in them (a pavement joining one
        # side) a runway width at most, long enough together not to be a marking
        end, n_flipped = index, 0
        while True:
            limit = gap_limit(rect.d[end])
            j = end + direction
            while 0 <= j < len(runway) and not flipped[j] and abs(rect.d[j] - rect.d[end]) <= limit:
                j += direction
            if not (0 <= j < len(runway) and flipped[j]):
                return end if n_flipped >= params.surface_resume_rows else index
            end = j
            while 0 <= end + direction < len(runway) and flipped[end + direction]:
                end += direction
            n_flipped += abs(end - j) + 1

    def resume_far(index):
        # towards the horizon only, past the run's end: a full-width patch of another shade (a
        # lighter repair up to 80 m long, brighter than the ground, 'variety 29' at 2048 px: the
        # surface ended on it 1.3 km short of the true end, far corners 26 px off over 40 s) or a
        # crossing pavement, then the runway's rows again (differing from the ground beside as
        # the core does, whatever their own level: the pavement past a patch can be a fresher or
        # older one) over several runway widths, too long to be a marking: the runway carries on.
        # Not towards the threshold, where pavement before it (a blast pad, a displaced
        # threshold's) is the markings' business (detector: ground_begins, threshold_marking)
        while True:
            gap = params.surface_far_gap_widths * gap_limit(rect.d[index])
            j = index - 1
            while j >= 0 and not runway[j] and rect.d[index] - rect.d[j] <= gap:
                j -= 1
            if j < 0 or not runway[j] or j == index - 1:
                return index
            k = j
            while k - 1 >= 0 and runway[k - 1]:
                k -= 1
            resumed_widths = widths_along(fx, rect.d[j], max(rect.d[k], 1e-9), width)
            if j - k + 1 < params.surface_resume_rows or resumed_widths < params.surface_far_resume_widths:
                return index
            index = extend_flipped(k, -1)

    lo = resume_far(extend_flipped(extend(centre, -1), -1))
    hi = extend_flipped(extend(centre, +1), +1)
    # then across a band of blended markings (grey level on the other side of the ground's)
    band = np.nan_to_num((median - out_level) * -np.sign(reference)) > 0.5 * abs(reference)

    def reach(depth):
        return marking_fraction * width * depth * depth / fx + 1.0

    start = rect.d[hi]
    while hi < len(runway) - 1 and band[hi + 1] and rect.d[hi + 1] - start <= reach(start):
        hi += 1
    start = rect.d[lo]
    while lo > 0 and band[lo - 1] and start - rect.d[lo - 1] <= reach(start):
        lo -= 1
    # no row nearer than the run's end holds a level: the image ends there
    near_runs_out = not np.isfinite(surface[hi + 1:]).any()
    return SurfaceExtent(rect.d[lo], rect.d[hi], surface_level, near_runs_out)


def _majority_of_three(rows: np.ndarray) -> np.ndarray:
    """Each row of a boolean row mask set when two of it and its two neighbours are."""
    padded = np.concatenate([[rows[0]], rows, [rows[-1]]]).astype(int)
    return (padded[:-2] + padded[1:-1] + padded[2:]) >= 2


def edge_crossings_s(horizon: HorizonFrame, line_left: np.ndarray, line_right: np.ndarray,
                     depth: float) -> tuple[float, float]:
    """``s`` (pixels along the horizon from Q) where the left and right edges cross the line
    parallel to the horizon at ``depth`` below it.

    Parameters
    ----------
    horizon : HorizonFrame
        The frame's horizon.
    line_left, line_right : ndarray, shape (3,)
        The edges as homogeneous pixel lines.
    depth : float
        Depth below the horizon, pixels.

    Returns
    -------
    s_left, s_right : float
    """
    parallel = horizon.parallel_h(depth)
    return horizon.to_sd(meet_h(line_left, parallel))[0], horizon.to_sd(meet_h(line_right, parallel))[0]


def transverse_line_h(horizon: HorizonFrame, s0: float, k_centre: float, depth: float) -> np.ndarray:
    """The transverse line through V2 and the centre line's point at ``depth``.

    Parameters
    ----------
    horizon, s0, k_centre : HorizonFrame, float, float
        The frame's horizon, the runway's vanishing point and its centre line's slope, as for
        :func:`transverse_grid`.
    depth : float
        Depth below the horizon (pixels) where the line crosses the centre line.

    Returns
    -------
    ndarray, shape (3,)
        Homogeneous pixel line ``a u + b v + c = 0`` with ``(a, b)`` a unit vector.
    """
    v2 = horizon.perpendicular_vanishing_point_h(s0)
    centre_point = horizon.pencil_point(s0, k_centre, depth)
    line_h = cross3(np.array([centre_point[0], centre_point[1], 1.0]), v2)
    return line_h / np.linalg.norm(line_h[:2])


def transverse_grid(horizon: HorizonFrame, s0: float, k_centre: float, line_left: np.ndarray,
                    line_right: np.ndarray, depths: np.ndarray, fractions: np.ndarray, image_shape: tuple):
    """Sample points across the runway on its transverse lines (module docstring).

    Each transverse line runs through V2 and the centre line's point ``s = s0 + k_centre d`` at
    one of ``depths``; it is sampled at ``fractions`` of the way from the left edge to the right.

    Parameters
    ----------
    horizon : HorizonFrame
        The frame's horizon.
    s0 : float
        The runway's vanishing point V1 on the horizon, pixels from Q.
    k_centre : float
        Slope ``ds/dd`` of the centre line.
    line_left, line_right : ndarray, shape (3,)
        The edges as homogeneous pixel lines.
    depths : ndarray, shape (m,)
        Depths (pixels below the horizon) where the transverse lines cross the centre line.
    fractions : ndarray, shape (n,)
        Positions across the runway: 0 on the left edge, 1 on the right one.
    image_shape : tuple
        ``(height, width, ...)`` of the frame.

    Returns
    -------
    ends_left, ends_right : ndarray, shape (m, 2)
        Where each transverse line meets the left and right edges (pixels).
    grid : ndarray, shape (m, n, 2)
        The sample points (pixels).
    inside : ndarray of bool, shape (m, n)
        Which samples are finite and inside the frame (between the centres of its first and
        last pixels).
    """
    v2 = horizon.perpendicular_vanishing_point_h(s0)
    centre_points = horizon.pencil_point(s0, k_centre, depths)                        # (m, 2)
    transverse = cross3(np.concatenate([centre_points, np.ones((len(depths), 1))], axis=1), v2)
    ends_left = meet_h(transverse, line_left)
    ends_right = meet_h(transverse, line_right)
    # u and v apart (the same sums and products as on the (m, n, 2) grid; numpy's loops over a
    # last axis of 2 are slow)
    across = ends_right - ends_left
    grid_u = ends_left[:, None, 0] + fractions[None, :] * across[:, None, 0]
    grid_v = ends_left[:, None, 1] + fractions[None, :] * across[:, None, 1]
    grid = np.stack([grid_u, grid_v], axis=-1)
    height, width = image_shape[:2]
    inside = (np.isfinite(grid_u) & np.isfinite(grid_v) & (grid_u >= 0) & (grid_u <= width - 1) & (grid_v >= 0)
              & (grid_v <= height - 1))
    return ends_left, ends_right, grid, inside


def _centre_at(horizon: HorizonFrame, s0: float, line_left: np.ndarray, line_right: np.ndarray, depth: float):
    """Where the edges cross the line parallel to the horizon at ``depth`` (at least 1 px) and the
    centre line's slope through V1 there: ``(s_left, s_right, d_ref, k_centre)``."""
    d_ref = max(float(depth), 1.0)
    s_left, s_right = edge_crossings_s(horizon, line_left, line_right, d_ref)
    return s_left, s_right, d_ref, (0.5 * (s_left + s_right) - s0) / d_ref


def find_transverse_line(image, horizon: HorizonFrame, s0: float, left: PixelLine, right: PixelLine,
                         d_expected: float, d_window: tuple, outward: int, min_step: float,
                         n_columns: int | None = None, step_d_px: float = 0.5,
                         min_significance: float | None = None, marking_fraction: float | None = None,
                         colour=None, min_chroma_step: float | None = None,
                         surface_level: float = math.nan,
                         params: DetectorParams | None = None) -> TransverseLine | None:
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

    In grey levels the boundary is the outermost departure from the ground's level
    (:meth:`_StepProfile.ground_departures`), placed where the profile crosses halfway between
    the ground's line and the first extreme inside.

    Returns None when no step stands out of the profile's noise by ``min_significance`` or
    reaches a quarter of ``min_step`` grey levels per pixel (in grey and in chroma).

    Parameters
    ----------
    image : ndarray of uint8, shape (H, W)
        Grey levels of the whole frame.
    horizon : HorizonFrame
        Horizon of the frame (the transverse lines meet it at V2).
    s0 : float
        The runway's vanishing point V1 on the horizon, pixels from Q.
    left, right : PixelLine
        The refined left and right edges.
    d_expected : float
        Depth (pixels below the horizon) where the surface ends.
    d_window : tuple of 2 float
        ``(d_min, d_max)``: depths searched, pixels.
    outward : int
        +1 for the threshold (outside at larger depth), -1 for the runway end.
    min_step : float
        Smallest grey-level step (grey levels) that counts.
    n_columns : int, optional
        Transverse samples between the edges, at 10 % to 90 % of the width
        (``params.transverse_columns`` by default, over ``params.transverse_column_span``).
    step_d_px : float, optional
        Spacing of the transverse lines, pixels of depth.
    min_significance : float, optional
        A step must stand out of the profile's noise by this factor
        (``params.transverse_min_significance`` by default).
    marking_fraction : float, optional
        Reach of a band of threshold markings along the runway, in runway widths
        (``params.marking_band_widths`` by default).
    colour : ndarray of uint8, shape (H, W, 3), optional
        The RGB frame, for the chroma profile.
    min_chroma_step : float, optional
        Smallest chroma change (levels) for the chroma step to be used
        (``params.transverse_chroma_min_step`` by default).
    surface_level : float, optional
        The runway surface's own grey level (:func:`surface_extent`), NaN if unknown.
    params : DetectorParams, optional
        The defaults above, the profiles' smoothing (``transverse_smooth_sigma_px``,
        ``transverse_light_sigma_px``), the reach searched inside and outside ``d_expected``
        (``transverse_inner_*``, ``transverse_outer_*``) and the faint texture of distant stripes
        (``faint_texture_*``); ``DetectorParams()`` if omitted.

    Returns
    -------
    TransverseLine or None

    References
    ----------
    Gibert, PhD thesis (2016), Fig. 3.5 and Remark 5.3.1: the threshold corners P', P''.
    """
    params = params or DetectorParams()
    n_columns = params.transverse_columns if n_columns is None else n_columns
    min_significance = params.transverse_min_significance if min_significance is None else min_significance
    marking_fraction = params.marking_band_widths if marking_fraction is None else marking_fraction
    min_chroma_step = params.transverse_chroma_min_step if min_chroma_step is None else min_chroma_step
    smoothing = (params.transverse_smooth_sigma_px, params.transverse_light_sigma_px)
    d_min, d_max = (float(x) for x in d_window)
    if not (math.isfinite(d_min) and math.isfinite(d_max)) or d_max - d_min < 6 * step_d_px:
        return None
    line_left, line_right = left.homogeneous(), right.homogeneous()
    # the centre line: through V1, midway between the edges along lines parallel to the horizon
    s_left, s_right, d_ref, k_centre = _centre_at(horizon, s0, line_left, line_right, d_expected)
    depths = np.arange(d_min, d_max + 1e-9, step_d_px)
    fractions = np.linspace(*params.transverse_column_span, n_columns)
    ends_left, ends_right, grid, inside = transverse_grid(horizon, s0, k_centre, line_left, line_right, depths,
                                                          fractions, image.shape)
    height, width = image.shape
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
    inner = max(params.transverse_inner_px, params.transverse_inner_fraction * d_expected)
    width_s = abs(s_right - s_left) * d_expected / d_ref       # runway width along the horizon at d_expected
    outer = max(params.transverse_outer_px, params.transverse_outer_fraction * d_expected,
                marking_fraction * width_s * d_expected / horizon.camera.fx + 1.0)
    profile_of = functools.partial(_depth_profile, maps=maps, inside=inside, rows_ok=rows_ok)
    # the grey levels on the transverse lines, resampled once: the level and texture profiles
    # and each third of the width (:func:`_spans_width`) read them
    values = _transverse_values(image[v0:v1, u0:u1], maps, inside)
    level_profile, texture_profile = _profiles_of(values, rows_ok, texture=True)
    grey = _step_profile(level_profile, depths, step_d_px, d_expected, outward, *smoothing)
    texture = _step_profile(texture_profile, depths, step_d_px, d_expected, outward, *smoothing)
    chosen = grey.pick(min_significance, 0.25 * min_step, inner, outer, outward) if grey else None
    best = (grey, chosen) if chosen is not None else None
    # the outermost departure from the ground that looks like the runway: in texture (the
    # stripes), or in level towards the runway's own surface level (a bare strip, a runway
    # without stripes); a departure away from it without texture is the ground's own (a
    # brighter streak of grass, a field)
    exits = []
    texture_departures = (texture.ground_departures(outward, inner, outer, min_level_change=0.25 * min_step,
                                                    rising_only=True) if texture is not None else [])
    if texture_departures:
        exits.append(texture_departures[0][:3] + ("texture-exit",))
    if grey is not None:
        for depth_i, step_i, significance_i, extreme in grey.ground_departures(outward, inner, outer,
                                                                               min_level_change=0.5 * min_step):
            ground_level = extreme - step_i
            towards_surface = (not math.isfinite(surface_level)
                               or ((extreme - ground_level) * (surface_level - ground_level) > 0
                                   and abs(extreme - ground_level) >= 0.3 * abs(surface_level - ground_level)))
            textured = any(abs(t[0] - depth_i) <= SAME_DEPARTURE_PX for t in texture_departures)
            if towards_surface or textured:
                if (texture_departures and abs(step_i) >= LEVEL_OVER_TEXTURE * abs(texture_departures[0][1])
                        and 0.0 <= (texture_departures[0][0] - depth_i) * outward <= ON_BOUNDARY_PX):
                    # the spread across the lines peaks on the level's boundary, its departure
                    # half a pixel outside the level's, and the pavement's level differs from
                    # the ground's far more than the surface varies across the lines: a
                    # transverse line through the blurred boundary samples ground and pavement
                    # side by side, and the level places the boundary (monochrome snow at 2 km,
                    # 2048 px: the spread 8 inside, 25 on the level's crossing, 3 on the ground;
                    # the level's crossing 0.1 px from the true threshold, the spread's 0.6 px
                    # beyond it). Where the spread departs farther out (unresolved stripes, a
                    # band of the ground's level before a darker pavement: the ray-cast airport
                    # at 3.1-3.4 km, 1024 px, the level's departure 1.2-1.5 px inside) or the
                    # stripes make most of the level's change (the same airport at 600 m), the
                    # spread's is kept
                    exits.pop(0)
                exits.append((depth_i, step_i, significance_i, "ground-exit"))
                break
    # far away the stripes are a band a pixel or two long whose texture rises only a few grey
    # levels above the ground's, but clearly above its spread
    # (only while the stripes, 1/25 to 1/12 of the width each, are too narrow to be resolved:
    # resolved stripes give a strong texture departure, and a faint one is the ground's)
    runway_px = float(np.nanmedian(np.linalg.norm(ends_right - ends_left, axis=1)))
    if texture is not None and not texture_departures and runway_px < params.faint_texture_max_width_px:
        for depth_t, step_t, significance_t, _ in texture.ground_departures(
                outward, inner, outer, min_level_change=params.faint_texture_min_change * min_step,
                k_sigma=params.faint_texture_k_sigma, rising_only=True, lag_px=1.0):
            if significance_t >= params.faint_texture_min_significance:
                exits.append((depth_t, step_t, significance_t, "faint-texture"))
            break
    exit_depth = max(exits, key=lambda e: e[0] * outward) if exits else None
    if colour is not None:
        chroma = _step_profile(profile_of(chroma_of(colour[v0:v1, u0:u1])), depths, step_d_px, d_expected, outward,
                               *smoothing)
        if chroma is not None:
            # the boundary lies at or beyond the grey step (which may be the stripes' inner edge)
            d_from = depths[chosen] if chosen is not None else d_expected
            pick = chroma.pick_rising(min_significance, min_chroma_step, d_from, inner, outer, outward)
            if pick is None:
                # threshold markings are as long in metres on any runway: in runway widths they
                # reach farther on a narrow one (16 stripes on 30 m at 3.3 km, 2048 px: the
                # surface seemed to end 3.1 widths, 4.9 px, inside the threshold, past the reach
                # of a 45 m runway's band, and the grey step placed it 2.4-2.7 px short). Looked
                # for farther, the chroma staying the pavement's up to the step (pavement and
                # paint are grey; a step past a change to the ground's colour is the ground's)
                outer_max = max(outer, params.marking_band_max_widths * width_s * d_expected / horizon.camera.fx + 1.0)
                far_pick = chroma.pick_rising(min_significance, min_chroma_step, d_from, inner, outer_max, outward)
                if (far_pick is not None and chroma.within(far_pick, FAR_PICK_CLEARANCE_PX)
                        and chroma.level_until(d_from, far_pick, 0.5 * min_chroma_step, outward)):
                    pick = far_pick
            if pick is not None:
                best = (chroma, pick)
    if best is not None and best[0] is not grey:
        profile, chosen = best
        depth, method = profile.subpixel(chosen), "chroma"
        step, significance = float(profile.g[chosen]), float(profile.magnitude[chosen] / profile.noise)
    elif exit_depth is not None:
        depth, step, significance, method = exit_depth
    else:
        # no departure from the ground looks like the runway's start: the strongest step in the
        # window would be a guess (a marking, a pavement joining the runway), so there is none
        return None
    spans = _spans_width(values, inside, rows_ok, fractions, depths, outward, depth, level_profile, texture_profile)
    line_h = transverse_line_h(horizon, s0, k_centre, depth)
    return TransverseLine(line_h=line_h, corner_left_uv=meet_h(line_h, line_left),
                          corner_right_uv=meet_h(line_h, line_right), depth_px=depth,
                          step=step, significance=significance, method=method, spans=spans)


def _crop_of(grid, inside, image_shape):
    """The frame's crop around the samples ``grid`` that are ``inside`` it, ``(v0, v1, u0, u1)``,
    and the samples' maps into that crop for :func:`_transverse_values` (outside ones off it)."""
    height, width = image_shape[:2]
    u0 = int(max(0, math.floor(grid[..., 0][inside].min()) - 1))
    v0 = int(max(0, math.floor(grid[..., 1][inside].min()) - 1))
    u1 = int(min(width, math.ceil(grid[..., 0][inside].max()) + 2))
    v1 = int(min(height, math.ceil(grid[..., 1][inside].max()) + 2))
    maps = (np.where(inside, grid[..., 0] - u0, -10.0).astype(np.float32),
            np.where(inside, grid[..., 1] - v0, -10.0).astype(np.float32))
    return (v0, v1, u0, u1), maps


def pavement_beyond_edges(image, horizon: HorizonFrame, s0: float, left: PixelLine, right: PixelLine,
                          depth: float, outward: int, colour=None, surface_level: float = math.nan,
                          params: DetectorParams | None = None) -> tuple[str, ...]:
    """The sides beyond whose edge the transverse step at ``depth`` continues: a pavement crossing
    or joining the runway there, not the runway's own start (issue 11: a transverse edge is the
    threshold only if it is not part of a crossing pavement that continues outside the runway).

    At a threshold the runway's surface meets the ground across the width, and beside the runway
    the ground runs on across the line. Where a taxiway crosses or joins the runway, its edge is
    a transverse line too, and it carries on beyond the runway's edges: beside the runway, the
    line's inner side (towards the runway's surface) is pavement and its outer side is the ground
    that lies before the line between the edges. A side counts when, on the transverse lines
    through V2 (:func:`transverse_grid`) between ``params.crossing_pavement_band`` runway widths
    beyond its edge, the mean level ``params.crossing_pavement_depth_px`` depth pixels outside
    the line differs from that inside it by at least ``params.crossing_pavement_share`` of the
    step between the edges (in grey levels, of the larger of that step and the runway surface's
    own contrast with the ground, ``surface_level``: blended threshold stripes can bring the step
    near the ground's level; and at least half of ``params.min_contrast``), the same way in each half of
    the band, and the outside there has the level of the ground between the edges (within
    ``params.crossing_pavement_ground_tolerance`` of the step beside). Only where a runway width
    along the runway spans ``params.crossing_pavement_min_width_px`` depth pixels or more: farther
    out, a pavement joining a width past the threshold lies within the pixels read, and a crossing
    pavement's width moves the threshold by less than that. A taxiway joining the
    approach side of a true threshold flush with it has pavement on the line's outer side: it
    does not count. Read in the chroma when ``colour`` is given and the chroma steps across the
    line by ``params.transverse_chroma_min_step`` between the edges (pavement is grey, grass and
    fields are not; in grey levels the grass's own shading can step as much), else in grey levels.

    Parameters
    ----------
    image : ndarray of uint8, shape (H, W)
        Grey levels of the whole frame.
    horizon : HorizonFrame
        Horizon of the frame (the transverse lines meet it at V2).
    s0 : float
        The runway's vanishing point V1 on the horizon, pixels from Q.
    left, right : PixelLine
        The refined left and right edges.
    depth : float
        Depth (pixels below the horizon) where the transverse line crosses the centre line.
    outward : int
        +1 for the threshold (outside at larger depth), -1 for the runway end.
    colour : ndarray of uint8, shape (H, W, 3), optional
        The RGB frame, for the chroma.
    surface_level : float, optional
        The runway surface's own grey level (:func:`surface_extent`), NaN if unknown.
    params : DetectorParams, optional
        ``crossing_pavement_*``, ``transverse_column_span``, ``transverse_chroma_min_step``,
        ``min_contrast``.

    Returns
    -------
    tuple of str
        ``"left"``, ``"right"``, both or none.
    """
    params = params or DetectorParams()
    line_left, line_right = left.homogeneous(), right.homogeneous()
    s_left, s_right, d_ref, k_centre = _centre_at(horizon, s0, line_left, line_right, depth)
    if not (math.isfinite(s_left) and math.isfinite(s_right)):
        return ()
    # the depth one runway width spans there (k = W / h, the edges' slope difference)
    width_px = depth - depth_along(horizon.camera.fx, depth, 1.0, abs(s_right - s_left) / d_ref)
    if not width_px >= params.crossing_pavement_min_width_px:
        return ()
    near_px, far_px = params.crossing_pavement_depth_px
    offsets = np.arange(-far_px, far_px + 1e-9, 0.5)
    depths = depth + outward * offsets
    if depths.min() <= 0.5:
        return ()
    inner_band = (offsets <= -near_px)                     # the line's runway side
    outer_band = (offsets >= near_px)
    b0, b1 = params.crossing_pavement_band
    half = 4
    groups = {"inside": np.linspace(*params.transverse_column_span, 2 * half),
              "left": np.linspace(-b1, -b0, 2 * half), "right": 1.0 + np.linspace(b0, b1, 2 * half)}
    fractions = np.concatenate(list(groups.values()))
    _, _, grid, inside = transverse_grid(horizon, s0, k_centre, line_left, line_right, depths, fractions, image.shape)
    if not inside.any():
        return ()
    (v0, v1, u0, u1), maps = _crop_of(grid, inside, image.shape)

    n_inner, n_outer = int(inner_band.sum()), int(outer_band.sum())
    names = list(groups)

    def levels_of(channel):
        """group (or half: "left/a", "left/b") -> (inner side's mean, outer side's mean), where at
        least half the samples of each side are in the frame"""
        values = _transverse_values(channel, maps, inside)
        finite = np.isfinite(values)
        filled = np.where(finite, values, 0.0)
        # sums and counts of each side of the line per half group (columns in blocks of
        # ``half``), then per group (two halves)
        sums = np.stack([filled[inner_band].sum(axis=0), filled[outer_band].sum(axis=0)])
        counts = np.stack([finite[inner_band].sum(axis=0), finite[outer_band].sum(axis=0)])
        sums, counts = sums.reshape(2, -1, half).sum(axis=2), counts.reshape(2, -1, half).sum(axis=2)
        needed = 0.5 * half * np.array([[n_inner], [n_outer]])
        whole_sums, whole_counts = sums.reshape(2, -1, 2).sum(axis=2), counts.reshape(2, -1, 2).sum(axis=2)
        halves_ok = (counts >= needed).all(axis=0)
        whole_ok = (whole_counts >= 2 * needed).all(axis=0)
        halves_mean = sums / np.maximum(counts, 1)
        whole_mean = whole_sums / np.maximum(whole_counts, 1)
        levels = {}
        for g, name in enumerate(names):
            if whole_ok[g]:
                levels[name] = (float(whole_mean[0, g]), float(whole_mean[1, g]))
            for h, suffix in ((2 * g, "/a"), (2 * g + 1, "/b")):
                if halves_ok[h]:
                    levels[name + suffix] = (float(halves_mean[0, h]), float(halves_mean[1, h]))
        return levels

    levels = None
    if colour is not None:
        levels = levels_of(chroma_of(colour[v0:v1, u0:u1]))
        if "inside" not in levels or \
                abs(levels["inside"][1] - levels["inside"][0]) < params.transverse_chroma_min_step:
            levels = None                         # the chroma does not tell the pavement from the ground here
        reference = math.nan
    if levels is None:
        levels = levels_of(image[v0:v1, u0:u1])
        reference = surface_level
    if "inside" not in levels:
        return ()
    surface, ground = levels["inside"]
    step_inside = max(abs(ground - surface), abs(ground - reference) if math.isfinite(reference) else 0.0)
    floor = max(params.crossing_pavement_share * step_inside, 0.5 * params.min_contrast)
    sides = []
    for side in ("left", "right"):
        if not all(key in levels for key in (side, side + "/a", side + "/b")):
            continue
        inner, outer = levels[side]
        step = outer - inner
        halves = [levels[side + p][1] - levels[side + p][0] for p in ("/a", "/b")]
        if (abs(step) >= floor and all(h * step > 0 and abs(h) >= floor for h in halves)
                and abs(outer - ground) <= params.crossing_pavement_ground_tolerance * abs(step)):
            sides.append(side)
    return tuple(sides)


#: Past a step inside the pavement the chroma between the edges stays within this share of the
#: pavement-to-ground chroma step of the pavement's own (:func:`pavement_runs_on`).
PAVEMENT_RUN_ON_SHARE = 0.25


def pavement_runs_on(colour, horizon: HorizonFrame, s0: float, left: PixelLine, right: PixelLine, depth: float,
                     outward: int, band_px: float, params: DetectorParams | None = None) -> bool | None:
    """Does the pavement run on past the transverse line at ``depth``, in the chroma?

    Pavement is grey, grass and fields are not. Past a runway's end (``outward`` -1: farther,
    smaller depths) the surface between the edges becomes the ground; past a step inside the
    pavement (where the touchdown zone's rubber ends, on concrete as light as dry grass) it is
    still pavement. On the transverse lines through V2 (:func:`transverse_grid`) from 1 to
    ``1 + band_px`` depth pixels either side of the line: the chroma between the edges (the
    middle of the width, ``transverse_column_span``) before the line and past it, and the ground's
    a runway width out beside either edge past it. True when the ground on both sides differs from
    the pavement before the line by ``params.transverse_chroma_min_step`` or more and the chroma
    past the line stays within :data:`PAVEMENT_RUN_ON_SHARE` of the smaller of those steps of the
    pavement's; False when it does not; None when the chroma cannot tell (the ground as grey as the
    pavement on a side, or too little of the bands in the frame).

    Parameters
    ----------
    colour : ndarray of uint8, shape (H, W, 3)
        The RGB frame.
    horizon : HorizonFrame
        Horizon of the frame.
    s0 : float
        The runway's vanishing point V1 on the horizon, pixels from Q.
    left, right : PixelLine
        The refined left and right edges.
    depth : float
        Depth (pixels below the horizon) where the transverse line crosses the centre line.
    outward : int
        +1 for the threshold (outside at larger depth), -1 for the runway end.
    band_px : float
        Depth pixels read on each side of the line (past the first).
    params : DetectorParams, optional
        ``transverse_column_span``, ``transverse_chroma_min_step``.

    Returns
    -------
    bool or None
    """
    params = params or DetectorParams()
    line_left, line_right = left.homogeneous(), right.homogeneous()
    s_left, s_right, _, k_centre = _centre_at(horizon, s0, line_left, line_right, depth)
    if not (math.isfinite(s_left) and math.isfinite(s_right)) or not band_px > 0:
        return None
    offsets = np.arange(1.0, 1.0 + band_px + 1e-9, 0.5)
    depths = np.concatenate([depth - outward * offsets, depth + outward * offsets])     # before, then past
    if depths.min() <= 0.5:
        return None
    n = len(offsets)
    groups = {"inside": np.linspace(*params.transverse_column_span, 8), "left": np.linspace(-1.5, -0.5, 8),
              "right": np.linspace(1.5, 2.5, 8)}
    fractions = np.concatenate(list(groups.values()))
    _, _, grid, inside = transverse_grid(horizon, s0, k_centre, line_left, line_right, depths, fractions,
                                         colour.shape)
    if not inside.any():
        return None
    (v0, v1, u0, u1), maps = _crop_of(grid, inside, colour.shape)
    values = _transverse_values(chroma_of(colour[v0:v1, u0:u1]), maps, inside)
    means = {}
    for g, name in enumerate(groups):
        for side, rows in (("before", slice(0, n)), ("past", slice(n, 2 * n))):
            block = values[rows, 8 * g:8 * (g + 1)]
            finite = np.isfinite(block)
            if finite.sum() < 0.5 * block.size:
                return None
            means[name, side] = float(block[finite].mean())
    pavement = means["inside", "before"]
    ground_step = min(abs(means["left", "past"] - pavement), abs(means["right", "past"] - pavement))
    if ground_step < params.transverse_chroma_min_step:
        return None
    return abs(means["inside", "past"] - pavement) <= PAVEMENT_RUN_ON_SHARE * ground_step


def _transition(profile, depths, depth, outward, reach: float = 3.0) -> float:
    """Mean of ``profile`` from 1 to ``reach`` px outside ``depth`` minus that 1 to ``reach`` px inside."""
    u = (depths - depth) * outward
    outside = np.isfinite(profile) & (u >= 1.0) & (u <= reach)
    inside = np.isfinite(profile) & (u <= -1.0) & (u >= -reach)
    if not (outside.any() and inside.any()):
        return math.nan
    return float(profile[outside].mean() - profile[inside].mean())


def _spans_width(values, inside, rows_ok, fractions, depths, outward, depth, level_profile, texture_profile,
                 n_parts: int = 3, min_share: float = 0.3) -> bool:
    """Does the boundary at ``depth`` run across the runway's whole width?

    A threshold (or runway end) spans the runway from edge to edge; a touchdown-zone or aiming
    point marking, a designation number or a pavement joining one side does not. The change of
    level (or of texture) across ``depth`` seen over the whole width must be seen, with the same
    sign and at least ``min_share`` of its size, in each third of the width.

    ``values``: the grey levels on the transverse lines (:func:`_transverse_values`, NaN outside
    ``inside``), columns at ``fractions`` of the width.
    """
    reference = [_transition(level_profile, depths, depth, outward),
                 _transition(texture_profile, depths, depth, outward)]
    for columns in np.array_split(np.arange(len(fractions)), n_parts):
        span = slice(int(columns[0]), int(columns[-1]) + 1)
        sub_rows = rows_ok & (np.count_nonzero(inside[:, span], axis=1) >= 0.5 * len(columns))
        # (the part's columns alone: values are NaN outside ``inside`` already)
        level, spread = _profiles_of(values[:, span], sub_rows, texture=True)
        ok = False
        for whole, part_profile in zip(reference, (level, spread)):
            part = _transition(part_profile, depths, depth, outward)
            if math.isfinite(whole) and math.isfinite(part) and abs(whole) >= 2.0 \
                    and part * math.copysign(1.0, whole) >= min_share * abs(whole):
                ok = True
        if not ok:
            return False
    return True


def _depth_profile(patch, maps, inside, rows_ok, texture: bool = False):
    """Mean of ``patch`` along each transverse line (NaN where too little of it is in the image);
    with ``texture``, also the spread across the line (mean absolute deviation from its median):
    threshold stripes are longitudinal, so across the line they alternate with the surface
    between them and the spread is high where they are, whatever their blended mean level."""
    return _profiles_of(_transverse_values(patch, maps, inside), rows_ok, texture)


def _transverse_values(patch, maps, inside):
    """``patch`` resampled at ``maps`` (bilinear), NaN where not ``inside``: (lines, columns) float32."""
    values = cv2.remap(np.asarray(patch, dtype=np.float32), maps[0], maps[1], cv2.INTER_LINEAR,
                       borderMode=cv2.BORDER_REPLICATE)
    return np.where(inside, values, np.nan)


def _profiles_of(values, rows_ok, texture: bool = False):
    """:func:`_depth_profile` of values already resampled (:func:`_transverse_values`)."""
    profile = np.where(rows_ok, row_mean(values), np.nan)
    if not texture:
        return profile
    median = row_quantile(values, 0.5)
    spread = np.where(rows_ok, row_mean(np.abs(values - median[:, None])), np.nan)
    return profile, spread


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
    light: np.ndarray = None       # the profile smoothed lightly (``transverse_light_sigma_px``)
    raw: np.ndarray = None         # the profile as sampled (gaps filled)

    def ground_departures(self, outward: int, inner: float, outer: float, min_level_change: float,
                          k_sigma: float = 4.0, rising_only: bool = False, trend_px: float = 5.0,
                          lag_px: float = 0.0) -> list:
        """Departures of the profile from the ground, outermost first: ``[(depth, step, significance, extreme)]``.

        The ground is followed from beyond the farthest the boundary can lie (``outer`` past
        ``d_expected``) inwards as a straight line fitted to the ``trend_px`` pixels ending
        ``lag_px`` before each sample (haze and large-scale texture make it drift, not step; with
        a lag, a faint blurred step, a ramp over a pixel or two, is not followed by the line). A departure is a sample
        that leaves that line by more than ``max(k_sigma * spread, min_level_change)`` and does
        not come back within the next sample, or leaves it by twice that (a stripe band a pixel
        wide); ``spread`` is the larger of the line's residual spread and the ground's texture
        over the whole reference stretch (streaked grass must not pass for a boundary). Each is
        located where the profile crosses halfway between the ground's line and the first
        extreme inside (the half-level crossing of a blurred step is the step's position,
        whatever its height), which keeps the boundary where the ground meets the runway even
        when a strong marking (the threshold stripes, 6 m inside) follows within a pixel or two.
        ``extreme`` is the level reached inside. ``rising_only`` counts only departures above the
        ground (the texture profile). Departures further than ``inner`` inside ``d_expected``
        are not returned.
        """
        depths, light = self.depths, self.light
        beyond = (depths - self.d_expected) * outward
        finite = np.isfinite(light)
        if not finite.any():
            return []
        # beyond the farthest the boundary can be, or at least 3 px beyond the expected end
        # where the search window is shorter than that
        start = max(min(outer + 1.0, float(np.max(beyond[finite])) - 3.0), inner + 2.0)
        order = np.argsort(-beyond)                                   # from the outside inwards
        order = order[finite[order] & (beyond[order] >= -inner - 3.0)]
        n_ground = int(np.sum(beyond[order] >= start))
        if n_ground < 6:
            return []
        x, y = beyond[order], light[order]
        reference_slope, reference_offset = np.polyfit(x[:n_ground], y[:n_ground], 1)
        texture = MAD_TO_SIGMA * float(median_of(np.abs(y[:n_ground] - (reference_slope * x[:n_ground] + reference_offset))))
        trend_samples = max(6, int(round(trend_px / self.step_d_px)))
        # the line through the trend_samples before each sample (sliding least squares from
        # cumulative sums): slope, offset and residual RMS for every candidate at once
        sums = [np.concatenate([[0.0], np.cumsum(a)]) for a in (np.ones_like(x), x, y, x * x, x * y, y * y)]
        index = np.arange(n_ground, len(order))
        # the line may end ``lag_px`` before the sample: a blurred step, a ramp over a pixel or
        # two, is then measured against the ground before it, not absorbed into the line
        lag = int(round(lag_px / self.step_d_px))
        hi = np.maximum(index - lag, n_ground // 2 + 1)
        lo = np.maximum(hi - trend_samples, 0)
        n, sx, sy, sxx, sxy, syy = (c[hi] - c[lo] for c in sums)
        denominator = n * sxx - sx * sx
        with np.errstate(invalid="ignore", divide="ignore"):
            slope = np.where(denominator > 1e-12, (n * sxy - sx * sy) / denominator, 0.0)
        offset = (sy - slope * sx) / n
        sse = syy - 2 * slope * sxy - 2 * offset * sy + slope * slope * sxx + 2 * slope * offset * sx + n * offset * offset
        spread = np.maximum(np.sqrt(np.maximum(sse, 0.0) / np.maximum(n - 2, 1)), texture) + 0.25
        limit = np.maximum(k_sigma * spread, min_level_change)
        deviation_here = y[index] - (slope * x[index] + offset)
        nxt = np.minimum(index + 1, len(order) - 1)
        deviation_next = np.where(index + 1 < len(order), y[nxt] - (slope * x[nxt] + offset), 0.0)
        size_here = deviation_here if rising_only else np.abs(deviation_here)
        size_next = deviation_next if rising_only else np.abs(deviation_next)
        confirmed = (size_here > 2.0 * limit) | ((size_here > limit) & (size_next > limit)
                                                  & (np.sign(deviation_here) == np.sign(deviation_next)))
        out = []
        reach = max(2, int(round(3.0 / self.step_d_px)))
        last = -10
        for hit in np.nonzero(confirmed)[0]:
            position = int(index[hit])
            if x[position] < -inner:
                break
            if position <= last + reach:
                continue                       # the same departure seen again
            last = position
            a_line, b_line = float(slope[hit]), float(offset[hit])
            sign = float(np.sign(deviation_here[hit]))
            span = np.arange(position, min(len(order), position + reach))
            values = (y[span] - (a_line * x[span] + b_line)) * sign
            peak = int(np.argmax(values))
            half = 0.5 * values[peak]
            # walk outwards from the extreme to the half-level crossing
            for a, b in zip(range(position + peak, position - 1, -1), range(position + peak - 1, position - 2, -1)):
                excess_a = (y[a] - (a_line * x[a] + b_line)) * sign - half
                excess_b = (y[b] - (a_line * x[b] + b_line)) * sign - half
                if excess_a >= 0 > excess_b:
                    w = excess_a / (excess_a - excess_b)
                    depth = float(depths[order[a]] + w * (depths[order[b]] - depths[order[a]]))
                    out.append((depth, float(sign * values[peak]), float(values[peak] / spread[hit]),
                                float(y[span[peak]])))
                    break
        return out

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
        """The strongest step rising towards the outside from ``d_from - inner`` to ``outer``
        beyond ``d_expected`` or beyond ``d_from`` where that lies outside it (the grey step can
        be the inner edge of a band of blended stripes that reaches ``outer`` past it: 16 stripes
        on a 30 m runway at 3.4 km, 2048 px, the surface seemed to end 0.8 px inside that edge and
        the band's outer edge, the threshold, lay 0.2 px past ``d_expected + outer``), if the
        profile changes by ``min_change`` across it."""
        peaks = self._peaks(min_significance, 0.0)
        peaks = peaks[np.sign(self.g[peaks]) == outward]
        lo = (d_from - self.d_expected) * outward - inner
        hi = max(outer + max(0.0, lo + inner), lo + 2.0 * inner)
        beyond = (self.depths[peaks] - self.d_expected) * outward
        peaks = peaks[(beyond >= lo) & (beyond <= hi)]
        if len(peaks) == 0:
            return None
        chosen = int(peaks[np.argmax(self.magnitude[peaks])])
        reach = max(1, int(round(2.0 / self.step_d_px)))
        before = self.smooth[max(0, chosen - reach)]
        after = self.smooth[min(len(self.smooth) - 1, chosen + reach)]
        return chosen if (after - before) * outward >= min_change else None

    def within(self, chosen: int, clearance_px: float) -> bool:
        """Is the step at index ``chosen`` at least ``clearance_px`` inside both ends of the
        profile (a step cut off by the end of the depths read shows only its flank)?"""
        depth = self.depths[chosen]
        return bool(self.depths[0] + clearance_px <= depth <= self.depths[-1] - clearance_px)

    def level_until(self, d_from: float, chosen: int, tolerance: float, outward: int) -> bool:
        """Does the smoothed profile stay within ``tolerance`` of its value at ``d_from`` from
        there outward to two pixels before the step at index ``chosen``?"""
        u = (self.depths - d_from) * outward
        stop = (self.depths[chosen] - d_from) * outward - 2.0
        stretch = self.smooth[(u >= 0.0) & (u <= stop)]
        return len(stretch) > 0 and bool(np.all(np.abs(stretch - stretch[0]) <= tolerance))

    def subpixel(self, chosen: int) -> float:
        """Centroid of the step's derivative lobe within a pixel of its peak."""
        half = max(1, int(round(1.0 / self.step_d_px)))
        idx = np.arange(max(0, chosen - half), min(len(self.g), chosen + half + 1))
        w = np.maximum(np.sign(self.g[chosen]) * self.g[idx], 0.0)
        return float(np.sum(w * self.depths[idx]) / np.sum(w)) if w.sum() > 0 else float(self.depths[chosen])


def _step_profile(profile, depths, step_d_px, d_expected, outward, smooth_sigma_px: float,
                  light_sigma_px: float) -> _StepProfile | None:
    """Smooth ``profile`` along depth (a Gaussian of ``smooth_sigma_px``), differentiate it (g > 0 where it rises
    with depth) and measure the derivative's noise: the smaller of its spreads over the whole
    window and over the part outside the runway (markings inside, or field boundaries beyond
    the runway's end, are structure, not noise)."""
    valid = np.isfinite(profile)
    if valid.sum() < 12:
        return None
    filled = np.interp(depths, depths[valid], profile[valid])
    kernel = np.exp(-0.5 * (np.arange(-4, 5) * step_d_px / smooth_sigma_px) ** 2)
    kernel /= kernel.sum()
    smooth = np.convolve(filled, kernel, mode="same")
    # np.gradient's central differences (its one-sided ends are zeroed below)
    g = np.empty_like(smooth)
    g[1:-1] = (smooth[2:] - smooth[:-2]) / (2.0 * step_d_px)
    g[:5] = 0.0
    g[-5:] = 0.0
    g = np.where(valid, g, 0.0)
    magnitude = np.abs(g)

    def spread(pool):
        return MAD_TO_SIGMA * float(median_of(np.abs(pool - median_of(pool)))) if pool.size >= 8 else math.inf

    outside = valid & ((depths > d_expected + 2.0) if outward > 0 else (depths < d_expected - 2.0))
    noise = min(spread(magnitude[valid]), spread(magnitude[outside])) + 1e-3
    light_kernel = np.exp(-0.5 * (np.arange(-2, 3) * step_d_px / light_sigma_px) ** 2)
    padded = np.concatenate([filled[:1], filled[:1], filled, filled[-1:], filled[-1:]])     # np.pad's "edge"
    light = np.convolve(padded, light_kernel / light_kernel.sum(), mode="valid")
    light = np.where(valid, light, np.nan)
    return _StepProfile(depths, smooth, g, magnitude, noise, step_d_px, d_expected, light, filled)
