"""The threshold marking when pavement continues before the threshold (issue 11).

The threshold is the line where the runway begins (SPEC), which on most runways is where the
pavement begins: :func:`visland.detection.transverse.find_transverse_line` finds it there. A
displaced threshold or a blast pad puts paved surface before it (tens to hundreds of metres,
with arrows or chevrons on it); the threshold is then marked on the pavement: a transverse bar
across the whole width (displaced threshold), or the threshold stripes, which begin 6 m past the
threshold (ICAO Annex 14, 5.2.4; FAA AC 150/5340-1, 20 ft).

From the pavement's start the runway is read inwards along transverse lines (through V2, the
vanishing point of the ground direction across the runway): per line, which samples between
the edges are markings (white paint: brighter than the pavement by more than the pavement
differs from a darker ground; beside a brighter ground, snow, which paint cannot outshine, by a
quarter of that difference, and then only as clear stripes standing out from the surface's own
blotches). A line belongs to the threshold marking when it holds markings in every quarter of the
width, either as one bar covering most of it or as several separate stripes. Other markings
do not: the centre line, arrows and the designation are central, touchdown-zone and aiming-point
marks leave the middle free, and a chevron's two arms cross a line at two places only.

Marks shorter along the runway than the threshold's stripes (30 m at least, ICAO Annex 14
5.2.4; FAA 150 ft), a displaced threshold's row of arrow heads, are skipped where that length is
resolved; a bar one line wide just before the stripes is the threshold's bar.

Only when such a band starts clearly inside the pavement (``min_pavement_widths`` runway widths
along it at least; ICAO stripes begin 6 m in, 0.1 to 0.26 widths; blast pads and displaced
thresholds are 30 m to several hundred metres long) is the pavement before it
taken as paved ground before the threshold, and the threshold placed at the band: at its near
edge for a bar, 6 m before it for stripes. Otherwise nothing changes.

Depths and along-runway lengths: with ``k = W / h`` the runway's width over the camera's height
(the pencil slopes' difference) and ``d = f h / x`` (x the distance ahead), a point ``n`` runway
widths farther along than depth ``d`` is at depth ``f / (f / d + n k)``.

Pixels: (0, 0) is the centre of the top-left pixel (SPEC).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from visland.detection.horizon import HorizonFrame, depth_along, meet_h, widths_along
from visland.detection.params import DetectorParams
from visland.detection.pencil import row_mean
from visland.detection.refine import PixelLine, chroma_of, percentile_of, remap_inside
from visland.detection.transverse import TransverseLine, edge_crossings_s, transverse_grid, transverse_line_h

__all__ = ["ThresholdMarking", "threshold_marking", "marked_at_start", "ground_begins", "paint_before", "STRIPES_FROM_THRESHOLD_WIDTHS"]

#: Threshold stripes begin 6 m past the threshold (ICAO Annex 14 5.2.4.5; FAA: 20 ft), in runway
#: widths for a 45 m runway (the width is not known in metres: 0.1 to 0.26 of 23-60 m widths).
STRIPES_FROM_THRESHOLD_WIDTHS = 6.0 / 45.0

#: How far past the threshold :func:`marked_at_start` reads the plain pavement, in runway widths
#: (the touchdown zone's and aiming point's marks, 150-400 m in, brighten part of it).
PLAIN_REACH_WIDTHS = 6.0

#: Most lines :func:`paint_before` reads (half a pixel apart, farther apart over a deeper span).
MAX_PAINT_LINES = 160

#: Depth pixels under which a marking's blur along the runway shows on a single line of the
#: band test (its lines are half a pixel apart), and the blur allowed around a bar one line wide.
ONE_LINE_PX = 1.0


@dataclass(frozen=True)
class ThresholdMarking:
    """The threshold marking found inside the pavement: the threshold line and how it was placed.

    Attributes
    ----------
    line : TransverseLine or None
        The threshold line placed from the marking, with its corners; None for ``"unresolved"``.
    kind : str
        ``"bar"`` (a transverse bar: the threshold at its near edge), ``"stripes"`` (the
        threshold 6 m before them, :data:`STRIPES_FROM_THRESHOLD_WIDTHS`), or ``"unresolved"``
        (plain pavement, then a brighter line the frame cannot place: the threshold is doubtful
        and is withheld).
    pavement_widths : float
        The paved length before the marking, in runway widths.
    """

    line: TransverseLine | None
    kind: str
    pavement_widths: float


def _across_at(horizon: HorizonFrame, s0: float, left: PixelLine, right: PixelLine, depth: float):
    """The runway across at ``depth`` px below the horizon: ``(line_left, line_right, width_k,
    k_centre)``, its edges as homogeneous lines, its width over the camera height (the pencil
    slopes' difference) and its centre line's slope; None when the edges do not span a width
    there."""
    if not depth > 1.0:
        return None
    line_left, line_right = left.homogeneous(), right.homogeneous()
    s_left, s_right = edge_crossings_s(horizon, line_left, line_right, depth)
    width_k = float(s_right - s_left) / depth
    if not (math.isfinite(width_k) and width_k > 0):
        return None
    return line_left, line_right, width_k, (0.5 * (s_left + s_right) - s0) / depth


def threshold_marking(image, horizon: HorizonFrame, s0: float, left: PixelLine, right: PixelLine,
                      d_pavement: float, d_far: float, min_step: float, surface_level: float = math.nan,
                      pavement_step: float = 0.0, min_pavement_widths: float | None = None,
                      max_pavement_widths: float | None = None, n_columns: int | None = None, step_d_px: float = 0.5,
                      min_resolved_px: float | None = None, min_unresolved_span_px: float | None = None,
                      start_fraction: float | None = None, unresolved_coverage: float | None = None,
                      unresolved_plain_px: float | None = None, resolved_only: bool = False,
                      params: DetectorParams | None = None) -> ThresholdMarking | None:
    """The threshold marking when the pavement before it starts at ``d_pavement`` (module docstring).

    Parameters
    ----------
    image : ndarray (H, W) uint8
        Grey levels.
    horizon : HorizonFrame
    s0 : float
        The runway's vanishing point on the horizon.
    left, right : PixelLine
        The runway's edges.
    d_pavement : float
        Depth (px below the horizon) where the pavement begins (the threshold found so far).
    d_far : float
        Depth of the far end of the edges' support: the search stays nearer than it.
    min_step : float
        Grey levels: markings must be brighter than the pavement by twice this at least.
    surface_level : float, optional
        The pavement's own grey level between markings (else the median of the rows read).
    pavement_step : float, optional
        Grey-level step from the ground to the pavement where it begins: markings must be
        brighter than the pavement by at least as much. Negative (a ground brighter than the
        pavement, resolved): the first lines that only decay from the ground's level are its
        blur, not a marking (:func:`_ground_blur_lines`), and past them the first line brighter
        than the pavement by ``min_step``, beyond where a threshold at the pavement's start shows
        its stripes, makes the threshold doubtful (kind ``"unresolved"``): a blast pad's asphalt
        beside snow, held-out draw 12 at 2048 px, read its start as a bar and kept the threshold
        there, 8-9 px short.
    min_pavement_widths, max_pavement_widths : float
        The marking must begin between these many runway widths inside the pavement
        (``params.marking_min_pavement_widths``, ``marking_max_pavement_widths`` by default).
    n_columns : int, optional
        Samples along each transverse line between the edges, over ``params.marking_column_span``
        of the width (``params.marking_columns`` by default).
    step_d_px : float, optional
        Spacing of the transverse lines read, pixels of depth.
    min_resolved_px : float, optional
        (``params.marking_min_resolved_px`` by default) Depth pixels the first ``min_pavement_widths`` of pavement must span for the marking to
        be looked for: below it the stripes a threshold at the pavement's start carries (6 m in,
        30 m long: about 0.83 of that span) cover less than the band test's two lines, their
        absence cannot be seen, and a marking further in (an aiming-point or touchdown-zone mark,
        blurred across the width) would be taken for them. Measured on visland's thesis-1 at
        4.5 km (2048 px camera, 1.0 px for 0.8 widths): the aiming-point marks 9.2 widths in moved
        the threshold 14 px; the ray-cast blast pad at 900 m (768 px camera, 1.9 px) needs the search.
        Below it (*unresolved*) those stripes are still seen blended: a line within the first
        ``min_pavement_widths`` (plus 1 px of blur) brighter than the pavement's median line by
        ``start_fraction`` of the markings' contrast keeps the pavement's start (None, as
        before). Otherwise a band across the width covering ``unresolved_coverage`` of it, on
        lines crossing the runway over ``min_unresolved_span_px`` at least (stripes are not told
        from a bar there), is the marking, unless a line nearer the pavement's start is brighter
        than its median line by ``min_step`` (the first marking inside it: within the first
        ``min_pavement_widths`` the pavement's start stands, past them the threshold is
        doubtful); and when there is none the frame can place, but the first
        ``unresolved_plain_px`` of pavement are plain (their lines within half ``min_step``), or
        its first ``min_pavement_widths`` (plus 1 px) are plain at the surface's own level, and a
        line further in is brighter by ``min_step`` and half ``pavement_step`` at least, a
        marking lies inside the pavement that the frame cannot place: the threshold is doubtful
        (kind ``"unresolved"``). Measured on the robustness study's displaced threshold (1024 px):
        at 2500 m the bar 7 widths in is placed (0.32 px; 10.2 px off at the pavement's start);
        at 3680 m it is a 0.3 px line dimmer than the pavement's step, withheld (was 9.1 px off);
        its blast pad (120 m) at 3.4-2.75 km, 3.5 px of pavement before stripes blurred over 1.5
        px, withheld (was 3.3-4.2 px off).
    min_unresolved_span_px : float, optional
        Unresolved: pixels a transverse line must cross the runway over to be read
        (``params.marking_unresolved_min_span_px`` by default).
    start_fraction : float, optional
        Unresolved: the first lines' excess over the pavement's median line, as a fraction of the
        markings' contrast, that shows the threshold's blended stripes at the pavement's start
        (``params.marking_start_fraction`` by default).
    unresolved_coverage : float, optional
        Unresolved: fraction of the width a band must cover to be the marking
        (``params.marking_unresolved_coverage`` by default).
    unresolved_plain_px : float, optional
        Unresolved: depth pixels of plain pavement at its start before a brighter line makes the
        threshold doubtful (``params.marking_unresolved_plain_px`` by default).
    resolved_only : bool, optional
        None when the first ``min_pavement_widths`` are not resolved (the caller has no step
        where the pavement begins, and far out a band found is too uncertain to place it).
    params : DetectorParams, optional
        The defaults above, ``marking_column_span`` and the band test (``marking_bright_percentile``,
        ``marking_quarter_min_share``, ``marking_bar_coverage``, ``marking_min_stripes``);
        ``DetectorParams()`` if omitted.

    Returns
    -------
    ThresholdMarking or None
        None when no threshold marking begins inside the pavement (the usual runway, or one
        without threshold markings: the pavement's start stands); ``line`` None when one does
        but cannot be placed (the caller withholds the threshold).
    """
    params = params or DetectorParams()
    if min_pavement_widths is None:
        min_pavement_widths = params.marking_min_pavement_widths
    if max_pavement_widths is None:
        max_pavement_widths = params.marking_max_pavement_widths
    n_columns = params.marking_columns if n_columns is None else n_columns
    min_resolved_px = params.marking_min_resolved_px if min_resolved_px is None else min_resolved_px
    if min_unresolved_span_px is None:
        min_unresolved_span_px = params.marking_unresolved_min_span_px
    start_fraction = params.marking_start_fraction if start_fraction is None else start_fraction
    unresolved_coverage = params.marking_unresolved_coverage if unresolved_coverage is None else unresolved_coverage
    unresolved_plain_px = params.marking_unresolved_plain_px if unresolved_plain_px is None else unresolved_plain_px
    across = _across_at(horizon, s0, left, right, d_pavement)
    if across is None:
        return None
    line_left, line_right, width_k, k_centre = across
    fx = horizon.camera.fx

    def depth_at(widths):                      # depth of the point `widths` runway widths farther along
        return depth_along(fx, d_pavement, widths, width_k)

    # too far to resolve the threshold's own stripes at the pavement's start: they are still seen
    # blended, a brighter first pixel of pavement (checked below, before a band further in counts)
    d_min_pavement = depth_at(min_pavement_widths)
    unresolved = d_pavement - d_min_pavement < min_resolved_px
    # where a threshold at the pavement's start would show its stripes: its first widths and a
    # pixel of blur
    d_start_reach = d_min_pavement - 1.0
    if unresolved and resolved_only:
        return None
    d_lo = max(depth_at(max_pavement_widths), d_far + 2.0, 1.0)
    d_hi = d_pavement - 0.5
    if d_hi - d_lo < 4.0:
        return None
    depths = np.arange(d_hi, d_lo, -step_d_px)                      # from the pavement's start inwards
    # clear of the side stripes (a few per cent of the width) and of the edges' blur
    fractions = np.linspace(*params.marking_column_span, n_columns)
    ends_left, ends_right, grid, inside = transverse_grid(horizon, s0, k_centre, line_left, line_right, depths,
                                                          fractions, image.shape)
    rows_ok = inside.all(axis=1)
    if rows_ok.sum() < 8:
        return None
    # a line must cross the runway over several pixels to tell stripes apart
    span_px = np.linalg.norm(ends_right - ends_left, axis=1)
    # (unresolved: only a band's presence across the width is asked, not its stripes)
    rows_ok &= span_px >= (min_unresolved_span_px if unresolved else 2.0 * n_columns / 8.0)
    if rows_ok.sum() < 8:
        return None
    maps = (np.where(inside, grid[..., 0], -1).astype(np.float32), np.where(inside, grid[..., 1], -1).astype(np.float32))
    values = remap_inside(image, maps[0], maps[1], inside, cv2.BORDER_CONSTANT, np.nan)
    values = np.where(inside & rows_ok[:, None], values, np.nan)
    level = row_mean(values)                    # across the width, per line (values: NaN outside)
    # a ground brighter than the pavement blurs into its first lines: those that only decay from
    # it are no marking (a band of them was taken for a bar at the pavement's start)
    skip = _ground_blur_lines(level, min_step) if pavement_step < 0.0 and not unresolved else 0
    if skip:
        rows_ok[:skip] = False
        values[:skip] = np.nan
        level[:skip] = np.nan
        if rows_ok.sum() < 8:
            return None
    ok = values[rows_ok]
    if math.isfinite(surface_level):
        surface = surface_level
    else:
        surface = float(np.nanmedian(ok))
    # threshold markings are white paint: brighter than asphalt and concrete alike, and by more
    # than the pavement differs from the ground (a brighter patch of surface, a seam, rubber
    # deposits, chevrons in yellow are not), which the haze dims in the same proportion
    sign = 1.0
    sampled = ok[~np.isnan(ok)]
    bright = float(percentile_of(sampled, params.marking_bright_percentile)) if sampled.size else math.nan
    contrast = bright - surface
    doubtful = None
    d_first_rise = -math.inf                    # unresolved or past a brighter ground's blur: the first marking's depth
    if unresolved:
        # the stripes of a threshold at the pavement's start lie within its first 0.8 widths (plus
        # the blur): a brighter line there, and the threshold is where the pavement begins
        start = (depths >= d_start_reach) & rows_ok
        plain = float(np.nanmedian(level[rows_ok]))
        if not start.any() or float(np.nanmax(level[start])) - plain > start_fraction * max(contrast, 0.0):
            return None
        # the first line brighter than the pavement by the frame's least step, past the ground's
        # blur, is the first marking inside it: a band the test below finds farther in is not the
        # threshold's (a blast pad's stripes, blended below the band test at 3.3 km, 1024 px,
        # and the aiming-point marks 10 px in taken for them)
        d_first_rise = _first_rise(level, rows_ok, depths, d_pavement - ONE_LINE_PX, plain, min_step)
        # plain pavement first (no marking for several pixels: paved ground before the threshold)
        # then a brighter line further in: a marking the frame cannot place, so the threshold is
        # doubtful (at 3680 m on 1024 px a displaced threshold's bar 6.7 widths in is a 0.3 px
        # line, dimmed below the pavement's own step). Or plain over a shorter stretch, where a
        # threshold's own stripes would show (the start lines above), at the surface's own level
        # (no paint blended into it): a blast pad of 120 m at 3.3 km, 1024 px, is 3.5 px of
        # pavement, the stripes blurred over its last 1.5 (placed at the pad's start, 3.5 px
        # short, in 46 frames from 3.4 to 2.75 km); the ray-cast airport's 1280 x 720 barrel
        # lens at 2.5 km has its first 1.3 px flat but 4-6 levels over the surface (the
        # stripes' ends)
        for d_plain, at_surface in ((d_hi - unresolved_plain_px, False), (d_start_reach, True)):
            first_px = rows_ok & (depths >= d_plain)
            later = rows_ok & (depths < d_plain)
            if not (first_px.sum() >= 3 and later.any() and np.ptp(level[first_px]) <= 0.5 * min_step):
                continue
            plain_level = float(np.median(level[first_px]))
            if at_surface and abs(plain_level - surface) > 0.5 * min_step:
                continue
            if float(np.nanmax(level[later])) - plain_level >= max(min_step, 0.5 * abs(pavement_step)):
                j = int(np.nonzero(later)[0][np.nanargmax(level[later])])
                doubtful = ThresholdMarking(line=None, kind="unresolved",
                                            pavement_widths=float(widths_along(fx, d_pavement, depths[j], width_k)))
                break
    if skip:
        # past the blur, the first line brighter than the pavement by the frame's least step is the
        # first marking inside it, as when unresolved (above): a band farther in is another mark
        d_first_rise = _first_rise(level, rows_ok, depths, depths[skip] - ONE_LINE_PX,
                                   float(np.nanmedian(level[rows_ok])), min_step)
        if -math.inf < d_first_rise < d_start_reach:
            # past where a threshold at the pavement's start shows its stripes: paved ground
            # before a marking (a blast pad's 127 m of asphalt beside snow, 2048 px at 2.3 km:
            # the threshold placed where it begins, 8-9 px short, from 2.6 to 1.3 km)
            doubtful = doubtful or ThresholdMarking(line=None, kind="unresolved", pavement_widths=float(
                widths_along(fx, d_pavement, d_first_rise, width_k)))
    # beside a brighter ground (snow) the paint cannot be asked to outshine the pavement by the
    # ground's step: white paint on concrete is dimmer than snow (held-out draw 15, a displaced
    # threshold beside snow in haze: bar and stripes 20-29 levels over the concrete, the snow's
    # step 36-42; the threshold stayed where the pavement begins, 195-688 px short, from 540 to
    # 350 m). Paint that passes only so must show stripes (below): a lighter patch across the
    # width is a bar as well (held-out draw 10, patched concrete on snow, a patch 11 widths in)
    ground_scale = pavement_step if pavement_step >= 0.0 else -params.marking_brighter_ground_fraction * pavement_step
    if not contrast >= max(2.0 * min_step, ground_scale):
        return doubtful
    dim_paint = not contrast >= abs(pavement_step)
    marked = np.nan_to_num((values - surface) * sign, nan=-1.0) > 0.5 * contrast
    coverage = marked.mean(axis=1)
    spans_all, runs = _marks_across(marked, params)
    spans_all &= rows_ok
    is_bar = spans_all & (coverage >= params.marking_bar_coverage)
    is_stripes = spans_all & (runs >= params.marking_min_stripes)
    band = is_bar | is_stripes
    if unresolved:
        # stripes are not told from a bar: a band across the width is the marking
        band = spans_all & (coverage >= unresolved_coverage)
    # the first band nearest the pavement's start that is a bar or stripes long enough to be
    # the threshold's (a bar seen on one line just before the stripes is taken for them)
    # one line is a band only resolved and far enough in not to be the threshold's own stripes
    # behind a band of ground taken for pavement (marking_memory_min_widths)
    single_lines_from = -math.inf if unresolved else depth_at(params.marking_memory_min_widths)
    found = _first_threshold_band(band, is_bar, depths, fx, width_k, params, single_lines_from)
    if found is None:
        return doubtful
    first, kind, marks_end = found
    d_band = float(depths[first])
    widths_in = widths_along(fx, d_pavement, d_band, width_k)
    if not (min_pavement_widths <= widths_in <= max_pavement_widths):
        return doubtful
    if dim_paint and not _clear_stripes(runs, is_stripes & ~is_bar, rows_ok, depths, first, fx, width_k, params):
        # dimmer than the brighter ground's step, and no clear stripes: a lighter patch, the
        # concrete's own blotches (held-out draws 10 and 13, concrete beside snow)
        return doubtful
    if d_band < d_first_rise - ONE_LINE_PX:
        # a brighter line nearer the pavement's start than the band: the band is a mark farther
        # along. Within the threshold's own stripes' reach that line is them (the pavement's start
        # stands); past it, a marking the frame cannot place
        if d_first_rise >= d_start_reach:
            return None
        return doubtful or ThresholdMarking(line=None, kind="unresolved", pavement_widths=float(
            widths_along(fx, d_pavement, d_first_rise, width_k)))
    # the band's near edge to a fraction of a pixel: the mean level across the width crossing
    # midway between the plain pavement before it and the band, both read on their own lines only
    # (not on the short marks skipped before the band, a displaced threshold's arrow heads, nor on
    # the gap after a bar one line wide)
    j_plain = slice(max(0, first - 6, marks_end), max(0, first - 1))
    j_band = [j for j in range(first, min(len(depths), first + 3)) if band[j]]
    band_level = float(np.nanmean(level[j_band]))
    plain_level = float(np.nanmean(level[j_plain])) if first - 1 > max(0, marks_end) else surface
    j_from, j_to = max(0, first - 4, marks_end), min(len(depths) - 1, first + 2)
    # stripes begin where the paint begins to vary across the width: a displaced threshold's bar
    # 6 m before them (1.8 m wide, 4.2 m of pavement after it) blends with their first line where
    # those 6 m span a pixel or two, and moves the mean level's rise towards the camera, but it
    # adds to every column alike. The mean level's rise where that cannot be read, and for a bar
    start = None
    if kind == "stripes":
        start = _stripes_start(values, band, depths, first, marks_end, j_from, j_to, min_step)
    if start is None:
        start = _rising_through(level * sign, depths, j_from, j_to, 0.5 * (band_level + plain_level) * sign)
    edge = d_band if start is None else start
    if kind == "stripes":
        # the threshold 6 m before the stripes
        edge = depth_along(fx, edge, -STRIPES_FROM_THRESHOLD_WIDTHS, width_k)
    line_h = transverse_line_h(horizon, s0, k_centre, edge)
    line = TransverseLine(line_h=line_h, corner_left_uv=meet_h(line_h, line_left),
                          corner_right_uv=meet_h(line_h, line_right), depth_px=edge,
                          step=(band_level - plain_level), significance=math.nan, method=f"marking-{kind}", spans=True)
    return ThresholdMarking(line=line, kind=kind, pavement_widths=float(widths_in))


def marked_at_start(image, horizon: HorizonFrame, s0: float, left: PixelLine, right: PixelLine, d_threshold: float,
                    min_step: float, pavement_step: float = 0.0, params: DetectorParams | None = None) -> bool:
    """Whether the threshold found where the pavement begins, at depth ``d_threshold``, carries the
    threshold's own marking: white paint across the whole width within its first
    ``params.marked_start_widths`` runway widths, a runway's mark that a taxiway or a road does
    not carry.

    Read on transverse lines from ``params.marked_start_skip_px`` inside the pavement's start to
    the reach, against the pavement's level from there to :data:`PLAIN_REACH_WIDTHS` widths in
    (its darkest line: touchdown-zone and aiming-point marks brighten many lines far out): in
    every quarter of the width the mean over one line at least must exceed that level by
    ``max(min_step, |pavement_step| / 2, |ground_step| / 2)``, the last read here, from the ground
    1-2 px before the threshold to the plain pavement (the step the threshold was placed on can be
    another: a texture's end). A brighter ground blurred into the pavement adds less than half its
    step there (half a pixel in, under a blur of 1 px sigma, 31 %), so it cannot pass for paint;
    on 'concrete, sand, mono' (2048 px, 3.4 km) a taxiway's threshold placed on a texture's end
    0.6 px before its 70-level step from the sand was read as marked against half the 9-level
    step given. Far out the stripes are unresolved and blend with the asphalt between them,
    still a band brighter than the plain pavement past them: on the robustness study's frames at
    3.7 km (2048 px: stripes 0.8 px of depth; 1024 px: 0.4 px) they lie 10-30 grey levels over
    the pavement half a pixel to a pixel in, while an unmarked runway and the overcast taxiway's
    start are at the pavement's level there.

    Parameters
    ----------
    image : ndarray (H, W) uint8
        Grey levels.
    horizon : HorizonFrame
    s0 : float
        The runway's vanishing point on the horizon.
    left, right : PixelLine
        The runway's edges.
    d_threshold : float
        Depth (px below the horizon) of the threshold found at the pavement's start.
    min_step, pavement_step : float
        Grey levels: the frame's least step, and the step from the ground to the pavement.
    params : DetectorParams, optional
        ``marked_start_widths``, ``marked_start_skip_px`` and ``marking_column_span``.
    """
    params = params or DetectorParams()
    across = _across_at(horizon, s0, left, right, d_threshold)
    if across is None:
        return False
    line_left, line_right, width_k, k_centre = across
    fx = horizon.camera.fx
    d_reach = depth_along(fx, d_threshold, params.marked_start_widths, width_k)
    d_plain_far = max(depth_along(fx, d_threshold, PLAIN_REACH_WIDTHS, width_k), 1.0)
    start = d_threshold - params.marked_start_skip_px
    # the marking's lines (one at least), then the plain pavement's, a pixel of blur past the reach,
    # and the ground's before the threshold, past the blur
    mark_depths = np.arange(start, min(d_reach, start) - 0.25, -0.5)
    plain_depths = np.arange(min(d_reach, start) - 1.0, d_plain_far, -0.5)
    if len(plain_depths) < 3:
        return False
    ground_depths = d_threshold + np.array([1.0, 1.5, 2.0])
    depths = np.concatenate([mark_depths, plain_depths, ground_depths])
    group = np.repeat([0, 1, 2], [len(mark_depths), len(plain_depths), len(ground_depths)])
    fractions = np.linspace(*params.marking_column_span, 16)
    ends_left, ends_right, grid, inside = transverse_grid(horizon, s0, k_centre, line_left, line_right, depths,
                                                          fractions, image.shape)
    rows_ok = inside.all(axis=1) & (np.linalg.norm(ends_right - ends_left, axis=1) >= 4.0)
    if not (rows_ok & (group == 0)).any() or (rows_ok & (group == 1)).sum() < 3:
        return False
    values = remap_inside(image, grid[..., 0].astype(np.float32), grid[..., 1].astype(np.float32), inside,
                          cv2.BORDER_CONSTANT, np.nan)
    line_levels = row_mean(values)
    # (its darkest line: touchdown-zone and aiming-point marks brighten many of them far out)
    plain = float(np.nanmin(line_levels[rows_ok & (group == 1)]))
    ground_ok = rows_ok & (group == 2)
    ground_step = float(np.nanmedian(line_levels[ground_ok])) - plain if ground_ok.any() else 0.0
    quarters = np.stack([row_mean(q) for q in np.array_split(values[rows_ok & (group == 0)], 4, axis=1)],
                        axis=1)                                              # (lines, 4)
    # (the step where the threshold was placed can be another than the ground's: a texture's end)
    excess = max(min_step, 0.5 * abs(pavement_step), 0.5 * abs(ground_step))
    return bool(np.any(np.all(quarters - plain >= excess, axis=1)))


#: The shortest setback of threshold stripes from the threshold, runway widths: ICAO Annex 14 and
#: the FAA both start them 6 m in, 0.1 widths of the widest runway (60 m).
STRIPE_SETBACK_WIDTHS = 0.1

#: Depth pixels the setback must span for :func:`starts_on_its_stripes` to read it (a line at
#: least, half a pixel inside the threshold found). At 2 px, 'concrete, sand, mono' at 2048 px
#: kept thresholds on the stripes' start 2.4-3.0 px beyond the true one from 680 to 510 m, where
#: the setback is 1.3-1.7 px.
STRIPE_SETBACK_MIN_PX = 1.0

#: Runway widths past a threshold line where its stripes lie whatever the runway: they start 6 m
#: in (0.26 widths of a 23 m runway) and run 30 m (ICAO; 45 m FAA), 0.5 widths of a 60 m one.
STRIPES_INSIDE_WIDTHS = (0.3, 0.5)
#: Correlation across the runway's columns between the band before the stripes and the stripes
#: at least this high: the band holds the same stripes.
STRIPES_ALIKE = 0.7


def _first_rise(level: np.ndarray, rows_ok: np.ndarray, depths: np.ndarray, d_from: float, plain: float,
                min_step: float) -> float:
    """Depth of the first line read (``rows_ok``), at ``d_from`` or farther in, whose mean
    ``level`` stands ``min_step`` over the pavement's ``plain`` level: the first marking inside
    the pavement; -inf when there is none."""
    rising = rows_ok & (depths <= d_from) & (level - plain >= min_step)
    return float(depths[np.argmax(rising)]) if rising.any() else -math.inf


def _ground_blur_lines(level: np.ndarray, min_step: float) -> int:
    """How many of the first lines inside a pavement, read from its start inwards (``level``:
    their means, NaN where not read), only decay from a brighter ground's level: each over the
    median line by ``min_step`` at least and under the line before by ``min_step`` / 2 or a
    fifth of its excess at least; none unless two lines do (under a blur of about 0.7 px the
    ground leaves one line, not told from stripes blended at the start). Paint holds its level
    from one line to the next."""
    plain = float(np.nanmedian(level))
    excess = level - plain
    count = 0
    while count < len(excess) and excess[count] >= min_step and (
            count == 0 or excess[count] <= excess[count - 1] - max(0.5 * min_step, 0.2 * excess[count - 1])):
        count += 1
    return count if count >= 2 else 0


def _marks_across(marked: np.ndarray, params: DetectorParams) -> tuple[np.ndarray, np.ndarray]:
    """Per line across the runway (rows of ``marked``, columns from the left edge to the right):
    whether it holds markings in every quarter of the width (``marking_quarter_min_share`` of
    each quarter's columns at least), and how many separate runs of marked columns it holds."""
    quarters = np.array_split(np.arange(marked.shape[1]), 4)
    share = np.stack([marked[:, q].mean(axis=1) for q in quarters], axis=1)        # (lines, 4)
    runs = (np.diff(marked.astype(np.int8), axis=1) == 1).sum(axis=1) + marked[:, 0]
    return (share >= params.marking_quarter_min_share).all(axis=1), runs


def paint_before(image, horizon: HorizonFrame, s0: float, left: PixelLine, right: PixelLine, d_step: float,
                 d_limit: float, min_step: float, params: DetectorParams | None = None) -> float | None:
    """How many runway widths nearer than a threshold at ``d_step`` runway paint lies, between
    the edges carried on toward the camera: None when there is none there.

    Before a runway's threshold lies ground (or a blast pad's or displaced threshold's pavement,
    whose step is found first): no white paint across the width. Threshold stripes there mean
    the step found is inside the runway:
    a rubber-darkened touchdown zone ending on concrete as light as the ground beside it (the
    ray-cast 1200 x 23 m runway, grey 112 on grass 105: the threshold placed at the rubber's
    start 150 m in, 12-33 px off, with confidence 0.8), or a marking's edge taken for the step
    when the pavement does not differ from the ground. Lines across the runway are read from
    ``paint_before_from_widths`` runway widths nearer than the step (a pixel at least) to
    ``paint_before_widths`` runway widths nearer or ``d_limit``,
    whichever is first, at most :data:`MAX_PAINT_LINES` lines, over
    ``marking_column_span`` of the width; a line is painted as :func:`threshold_marking` reads
    threshold stripes (markings in every quarter of the width, ``marking_min_stripes`` separate
    stripes at least; not a bar, which a bright field across the approach also makes) with paint
    brighter than the ground beside the runway on that line and than the line's lower quartile,
    by twice ``min_step`` and ``paint_before_noise_sigmas`` times the ground's texture (a robust
    sigma of its spread beside the runway) at least. Two consecutive painted lines marked in the
    same columns (``paint_before_agreement`` of them, intersection over union: stripes run along
    the runway, grass texture does not), over ``paint_before_min_px`` of depth at least, are
    paint, not a texture's chance.

    Parameters
    ----------
    image : ndarray (H, W) uint8
        Grey levels.
    horizon : HorizonFrame
    s0 : float
        The runway's vanishing point on the horizon.
    left, right : PixelLine
        The runway's edges.
    d_step : float
        Depth (px below the horizon) of the step taken for the threshold.
    d_limit : float
        Deepest depth read (the runway leaves the image there).
    min_step : float
        Grey levels (the frame's minimum contrast).
    params : DetectorParams, optional
        ``paint_before_*``, ``marking_columns``,
        ``marking_column_span``, ``marking_quarter_min_share`` and ``marking_min_stripes``.

    Returns
    -------
    float or None
        The runway widths from the step to the nearest painted line, or None.
    """
    params = params or DetectorParams()
    across = _across_at(horizon, s0, left, right, d_step)
    if across is None:
        return None
    line_left, line_right, width_k, k_centre = across
    fx = horizon.camera.fx
    d_hi = min(d_limit, float(depth_along(fx, d_step, -params.paint_before_widths, width_k)))
    # from paint_before_from_widths nearer (the step's own blur, and the paint bleeding across it,
    # 0.1-0.3 widths on 16 stripes at 1024 px, are not paint before it), lines half a pixel apart,
    # at most MAX_PAINT_LINES of them (paint near the camera is deep)
    d_lo = max(d_step + 1.0, float(depth_along(fx, d_step, -params.paint_before_from_widths, width_k)))
    step = max(0.5, (d_hi - d_lo) / MAX_PAINT_LINES)
    depths = np.arange(d_lo, d_hi, step)
    if len(depths) < 2:
        return None
    n_columns = params.marking_columns
    fractions = np.linspace(*params.marking_column_span, n_columns)
    lo, hi = params.strip_side_band
    beside = np.concatenate([np.linspace(-hi, -lo, 6), np.linspace(1.0 + lo, 1.0 + hi, 6)])
    ends_left, ends_right, grid, inside = transverse_grid(horizon, s0, k_centre, line_left, line_right, depths,
                                                          np.concatenate([fractions, beside]), image.shape)
    # stripes told apart: a line crosses the runway over two pixels per stripe gap at least
    rows_ok = inside.all(axis=1) & (np.linalg.norm(ends_right - ends_left, axis=1) >= 2.0 * n_columns / 8.0)
    if rows_ok.sum() < 2:
        return None
    values = remap_inside(image, grid[..., 0].astype(np.float32), grid[..., 1].astype(np.float32), inside,
                          cv2.BORDER_CONSTANT, np.nan)[rows_ok]
    # each line's base: the ground beside the runway there, or the line's own lower quartile if
    # brighter (a light field across the approach); paint stands out of the ground's texture
    # (its spread beside the runway, a robust sigma) by paint_before_noise_sigmas
    across_runway, ground = values[:, :n_columns], values[:, n_columns:]
    ground_level = np.median(ground, axis=1)
    texture = 1.4826 * float(np.median(np.abs(ground - ground_level[:, None])))
    base = np.maximum(ground_level, np.percentile(across_runway, 25.0, axis=1))
    rise = max(2.0 * min_step, params.paint_before_noise_sigmas * texture)
    marked = across_runway - base[:, None] >= rise
    spans_all, runs = _marks_across(marked, params)
    painted = spans_all & (runs >= params.marking_min_stripes)
    # stripes run along the runway: the next line is painted in the same columns (grass texture
    # bright in separate places on one line is not, on the next)
    same = (marked[:-1] & marked[1:]).sum(axis=1) / np.maximum((marked[:-1] | marked[1:]).sum(axis=1), 1)
    held = painted[:-1] & painted[1:] & (same >= params.paint_before_agreement)
    if not held.any() or step * (held.sum() + 1) < params.paint_before_min_px:
        return None
    return float(widths_along(fx, depths[rows_ok][np.argmax(held)], d_step, width_k))


def starts_on_its_stripes(image, horizon: HorizonFrame, s0: float, left: PixelLine, right: PixelLine,
                          d_threshold: float, min_step: float, params: DetectorParams | None = None) -> bool:
    """Whether a threshold placed at depth ``d_threshold`` lies where its stripes start, the
    pavement before them unseen (as light as the ground: concrete on sand in a grey frame).

    Threshold stripes start 6 m past the threshold (:data:`STRIPE_SETBACK_WIDTHS` of the widest
    runway), so the band just inside a true threshold is plain pavement. Where that band would
    be :data:`STRIPE_SETBACK_MIN_PX` deep or more, it is read across the runway (48 columns over
    ``marking_column_span``): a threshold placed on the stripes' start has paint and pavement side
    by side there (the 80th and 20th percentiles of the columns' levels at least ``min_step``
    apart), bright in the same columns as the stripes :data:`STRIPES_INSIDE_WIDTHS` past the line
    (a correlation of :data:`STRIPES_ALIKE` at least), and the pavement between the stripes at the
    ground's level just before the line (within 30 % of the paint's rise over the ground): the
    step found is the paint's, the runway begins before it.
    """
    params = params or DetectorParams()
    across = _across_at(horizon, s0, left, right, d_threshold)
    if across is None:
        return False
    line_left, line_right, width_k, k_centre = across
    d_setback = float(depth_along(horizon.camera.fx, d_threshold, STRIPE_SETBACK_WIDTHS, width_k))
    if not d_threshold - d_setback >= STRIPE_SETBACK_MIN_PX:
        return False
    band = np.arange(d_threshold - 0.5, d_setback + 0.25, -0.5)
    ground = d_threshold + np.array([1.0, 1.5, 2.0])
    d_in, d_deep = (float(depth_along(horizon.camera.fx, d_threshold, w, width_k)) for w in STRIPES_INSIDE_WIDTHS)
    stripes = np.arange(d_in, d_deep - 0.25, -0.5)
    fractions = np.linspace(*params.marking_column_span, 48)
    _, _, grid, inside = transverse_grid(horizon, s0, k_centre, line_left, line_right,
                                         np.concatenate([band, ground, stripes]), fractions, image.shape)
    if len(stripes) < 2 or not inside.all():
        return False
    values = remap_inside(image, grid[..., 0].astype(np.float32), grid[..., 1].astype(np.float32), inside,
                          cv2.BORDER_CONSTANT, np.nan)
    # (every sample lies inside the frame: no NaN)
    columns = values[:len(band)].mean(axis=0)
    ground_level = float(np.median(values[len(band):len(band) + len(ground)]))
    deeper = values[len(band) + len(ground):].mean(axis=0)
    between, paint = np.percentile(columns, [20.0, 80.0])
    if not (paint - between >= min_step and paint > ground_level):
        return False
    # the band's bright columns are the stripes' (the same columns as deeper in), not the
    # pavement's own texture (concrete on dry grass at 160 m, 2048 px: a true threshold);
    # the band varies (paint over pavement), the stripes deeper in may not (a bar across)
    if not (np.std(deeper) > 0 and float(np.corrcoef(columns, deeper)[0, 1]) >= STRIPES_ALIKE):
        return False
    return bool(abs(between - ground_level) <= 0.3 * (paint - ground_level))


def _rising_through(profile: np.ndarray, depths: np.ndarray, j_from: int, j_to: int, mid: float) -> float | None:
    """Depth where ``profile`` (a value per line read) first rises through ``mid`` from line
    ``j_from`` on (the crossing's last line before ``j_to``), interpolated between the two lines;
    None when it does not."""
    for j in range(j_from, j_to):
        a, b = profile[j] - mid, profile[j + 1] - mid
        if math.isfinite(a) and math.isfinite(b) and a < 0 <= b:
            return float(depths[j] + (depths[j + 1] - depths[j]) * a / (a - b))
    return None


def _stripes_start(values: np.ndarray, band: np.ndarray, depths: np.ndarray, first: int, marks_end: int,
                   j_from: int, j_to: int, min_step: float) -> float | None:
    """Depth where the stripes of the band beginning on line ``first`` begin: where the paint's
    variation across the width rises halfway from the lines before the band (``marks_end`` on)
    to the band's own, searched from line ``j_from`` to ``j_to``.

    The columns (``values``: a line per row) brighter than midway between the 20th and 80th
    percentiles of the band's own lines past its start's blur are the stripes, the others the
    gaps between them; a line's variation is the mean of its stripe columns less the mean of its
    gap columns. A bar across adds to both alike, even tilted against the lines by a fraction of
    a pixel (a line's 80th percentile less its 20th rises on such a bar): a displaced threshold's
    bar blended with the stripes' first line (1.8 m wide and 4.2 m before them: a pixel or two
    of depth for the 6 m from 650 m to 1.7 km out at 2048 px) leaves this rise where the stripes
    begin, while the mean level rises on the bar (the threshold placed 6 m short: 1.0-1.5 px, a
    frame out of three, in the robustness study). None when the band's stripes do not vary
    across the width by twice ``min_step`` more than the lines before it, or the band has under
    four lines or no line before it.
    """
    stop = first + int(np.argmin(band[first:])) if not band[first:].all() else len(band)
    j0 = max(0, first - 6, marks_end)
    if stop - (first + 2) < 2 or first - 1 - j0 < 1:
        return None
    read = values[j0:stop]
    if not np.isfinite(read).all():
        return None
    columns = read[first + 2 - j0:].mean(axis=0)          # the band's own lines, past its start's blur
    low, high = np.percentile(columns, [20.0, 80.0])
    on_stripes = columns > 0.5 * (low + high)
    if on_stripes.all() or not on_stripes.any():
        return None
    spread = np.full(len(depths), np.nan)
    spread[j0:stop] = read[:, on_stripes].mean(axis=1) - read[:, ~on_stripes].mean(axis=1)
    body = float(np.median(spread[first + 2:stop]))
    plain = float(np.median(spread[j0:first - 1]))
    if not body - plain >= 2.0 * min_step:
        return None
    return _rising_through(spread, depths, max(j_from, j0), min(j_to, stop - 1), 0.5 * (body + plain))


def _clear_stripes(runs: np.ndarray, is_stripes: np.ndarray, rows_ok: np.ndarray, depths: np.ndarray, first: int,
                   fx: float, width_k: float, params: DetectorParams) -> bool:
    """Whether the band found at line ``first`` shows stripes clearly: from its first striped
    line on, over ``params.marking_dim_stripes_widths`` runway widths along the runway (two lines
    at least), ``params.marking_dim_stripes_share`` of the lines read cross
    ``params.marking_dim_min_stripes`` separate marks or more. Threshold stripes are 30 m long at
    least and 4 to 16 across the width, so every line over their length crosses them all; a
    lighter patch crosses a few marks on a line or two (held-out draw 10 at 1.34 km: 3, 3; draw
    15's stripes at 540 m: 9 to 11 on ten lines running; draw 12's worn stripes at 2.3 km: 6,
    8). Their lines must also cross ``params.marking_dim_texture_ratio`` times as many marks as
    the pavement's lines before them (medians): the blotches of a concrete surface beside snow
    cross 3 to 8 on every line (held-out draws 13 and 16 from 1 km to 50 m: medians 1.0 to 1.75
    times the pavement's before them; draw 15's stripes 9 to 10 times, draw 12's over plain
    asphalt, no mark before them)."""
    striped = np.flatnonzero(is_stripes[first:])
    if not len(striped):
        return False
    j0 = first + int(striped[0])
    d_end = depth_along(fx, depths[j0], params.marking_dim_stripes_widths, width_k)
    lines = np.flatnonzero(rows_ok[j0:] & (depths[j0:] >= d_end)) + j0
    if len(lines) < 2:
        lines = np.flatnonzero(rows_ok[j0:])[:2] + j0
    if len(lines) < 2:
        return False
    clear = np.count_nonzero(runs[lines] >= params.marking_dim_min_stripes)
    if not (clear >= 2 and clear >= params.marking_dim_stripes_share * len(lines)):
        return False
    # and more marks than the surface's own texture crosses on the pavement before them
    before = np.flatnonzero(rows_ok[:first])
    return (len(before) < 2
            or float(np.median(runs[lines])) >= params.marking_dim_texture_ratio * float(np.median(runs[before])))


def _first_threshold_band(band: np.ndarray, is_bar: np.ndarray, depths: np.ndarray, fx: float, width_k: float,
                          params: DetectorParams, single_lines_from: float = math.inf) -> tuple[int, str, int] | None:
    """The first band of ``band`` that can be the threshold marking: ``(index of its first line,
    "bar" or "stripes", index after the last short marks skipped before it (0: none))``, or None.

    A band is two lines at least (1 px: one line alone can be noise): a bar, or stripes that run
    along the runway over ``params.marking_stripes_min_widths`` runway widths at least wherever
    that length spans ``params.marking_stripes_resolved_px`` of depth (shorter marks across the
    width, a displaced threshold's arrow heads, are skipped). Where that length spans under a
    pixel of depth, stripes on one line are a band at depths up to ``single_lines_from`` (pixels
    below the horizon): the lines are half a pixel apart, and stripes blurred over them pass the
    test on their brightest line only (the robustness study's blast pad at 2.8 km, 2048 px).
    The caller gives ``-inf`` where the stripes are not resolved across the runway (one line
    across the width can then be any marking: the touchdown zone's 400 m in at 3.45 km) and
    otherwise the depth of ``marking_memory_min_widths`` runway widths in (nearer, one line was
    the threshold's own stripes seen behind a band of ground taken for pavement: 'short narrow'
    at 1024 px, 950 m, 2.8 px off). A bar on a single line within the 6 m before the stripes (plus a
    pixel of blur) is the threshold's bar: the threshold is its near edge, not 6 m before the
    stripes' blurred start. ``depths`` decrease from the pavement's start; a point ``n`` widths
    farther along than depth ``d`` is at depth ``f / (f / d + n k)``."""
    edges = np.flatnonzero(np.diff(np.concatenate(([0], band.astype(np.int8), [0]))))
    marks_end = 0
    for first, stop in zip(edges[::2].tolist(), edges[1::2].tolist()):      # runs of band lines
        d_long = depth_along(fx, depths[first], params.marking_stripes_min_widths, width_k)
        if stop - first == 1 and (depths[first] > single_lines_from or is_bar[first]
                                  or depths[first] - d_long >= ONE_LINE_PX):
            continue                                                # one line: noise, or a bar too thin to tell
        if is_bar[first:min(stop, first + 3)].any():
            return first, "bar", marks_end
        resolved = depths[first] - d_long >= params.marking_stripes_resolved_px
        if stop < len(band) and resolved and depths[stop - 1] > d_long:
            marks_end = stop                                        # short marks: not the threshold's stripes
            continue
        d_threshold = depth_along(fx, depths[first], -STRIPES_FROM_THRESHOLD_WIDTHS, width_k) + ONE_LINE_PX
        bars = np.flatnonzero(is_bar[:first] & (depths[:first] <= d_threshold))
        return (int(bars[0]), "bar", marks_end) if len(bars) else (first, "stripes", marks_end)
    return None


def ground_begins(image, horizon: HorizonFrame, s0: float, left: PixelLine, right: PixelLine, d_from: float,
                  d_to: float, surface_level: float, min_step: float, step_d_px: float = 0.5,
                  min_ground_px: float | None = None, colour=None,
                  params: DetectorParams | None = None) -> tuple[float, float] | None:
    """Depth where the ground begins before a threshold found at ``d_from``, searching towards the
    camera up to ``d_to``.

    Row by row along transverse lines (through V2), the surface between the edges (median of the
    middle 70 %, ``ground_begin_middle_span``) is compared with the ground beside each edge (15 to
    40 % of the width outside, ``ground_begin_side_band``):
    a row is pavement while it differs from both sides the way the runway's own surface
    ``surface_level`` does (by half that difference at least; a taxiway joining one side makes
    that side paved, and the row counts as ground, so nothing moves). With ``colour``, a row is
    also pavement while its chroma differs from both sides' the way the runway's does (read on
    the rows just inside ``d_from``; only where the ground's chroma differs from it by
    ``params.transverse_chroma_min_step`` levels): a patch of darker concrete has the grass's grey
    level but not its colour (the robustness study's patched concrete at 1.25 to 1.07 km: the
    threshold was kept on a patch's step 9 px inside the runway, the ground "beginning" in grey
    levels 1.7 px past it). Returns the depth of the
    first ``min_ground_px`` of ground rows (``d_from`` itself when the ground begins at once) and
    the grey-level step from the ground to the runway's surface (the pavement's level less the
    ground's, negative beside a brighter ground, as
    :func:`visland.detection.transverse.find_transverse_line`'s step; the
    smaller of the two sides; NaN when only the chroma tells them apart); ``(inf, step)`` when no ground has begun by
    ``d_to`` (the rows all in the frame); None when the frame cannot tell (no clear difference between the
    runway and the ground beside it, rows outside the image).

    Parameters
    ----------
    image : ndarray of uint8, shape (H, W)
        Grey levels.
    horizon : HorizonFrame
        The frame's horizon.
    s0 : float
        The runway's vanishing point V1 on the horizon, pixels from Q.
    left, right : PixelLine
        The runway's edges.
    d_from : float
        Depth (pixels below the horizon) of the threshold found so far.
    d_to : float
        Deepest row searched, pixels (towards the camera).
    surface_level : float
        The runway surface's own grey level (:func:`visland.detection.transverse.surface_extent`).
    min_step : float
        The surface must differ from the ground beside each edge by this many grey levels.
    step_d_px : float, optional
        Spacing of the transverse lines read, pixels of depth.
    min_ground_px : float, optional
        Depth (pixels) of consecutive ground rows that counts as the ground beginning
        (``params.ground_begin_min_px`` by default).
    colour : ndarray of uint8, shape (H, W, 3), optional
        The colour frame: its chroma (:func:`visland.detection.refine.chroma_of`) also tells
        pavement from ground.
    params : DetectorParams, optional
        That default and the samples read (``ground_begin_middle_span``,
        ``ground_begin_side_band``, ``ground_begin_middle_samples``, ``ground_begin_side_samples``,
        ``ground_begin_chroma_rows_px``), ``transverse_chroma_min_step``;
        ``DetectorParams()`` if omitted.

    Returns
    -------
    tuple of 2 float or None
        ``(depth_px, step)`` as above (``depth_px`` inf: pavement as far as searched), or None.
    """
    params = params or DetectorParams()
    min_ground_px = params.ground_begin_min_px if min_ground_px is None else min_ground_px
    line_left, line_right = left.homogeneous(), right.homogeneous()
    s_left, s_right = edge_crossings_s(horizon, line_left, line_right, d_from)
    k_centre = (0.5 * (s_left + s_right) - s0) / d_from
    if not (math.isfinite(k_centre) and math.isfinite(surface_level) and d_to - d_from >= 3.0 * step_d_px):
        return None
    depths = np.arange(d_from + step_d_px, d_to, step_d_px)
    side_in, side_out = params.ground_begin_side_band
    n_side = params.ground_begin_side_samples
    parts = (np.linspace(*params.ground_begin_middle_span, params.ground_begin_middle_samples),
             np.linspace(-side_out, -side_in, n_side), np.linspace(1.0 + side_in, 1.0 + side_out, n_side))
    fractions = np.concatenate(parts)
    _, _, grid, inside = transverse_grid(horizon, s0, k_centre, line_left, line_right, depths, fractions,
                                         image.shape)
    rows_ok = inside.all(axis=1)
    if rows_ok.sum() < 3:
        return None
    # (the rows with a sample outside the frame are not used: rows_ok)
    maps = (grid[..., 0].astype(np.float32), grid[..., 1].astype(np.float32))
    values = remap_inside(image, maps[0], maps[1], inside)
    n0, n1 = len(parts[0]), len(parts[0]) + len(parts[1])
    middle = np.median(values[:, :n0], axis=1)
    beside = (np.median(values[:, n0:n1], axis=1), np.median(values[:, n1:], axis=1))
    pavement = rows_ok.copy()
    contrasts = []
    for side in beside:
        contrast = surface_level - float(np.median(side[rows_ok]))
        if not abs(contrast) >= min_step:
            pavement, contrasts = None, []         # grey levels cannot tell (the chroma may)
            break
        pavement &= (middle - side) * math.copysign(1.0, contrast) > 0.5 * abs(contrast)
        contrasts.append(contrast)
    in_chroma = (_chroma_pavement(colour, horizon, s0, k_centre, line_left, line_right, d_from, step_d_px, depths,
                                  grid, inside, rows_ok, (n0, n1), params) if colour is not None else None)
    if in_chroma is not None:
        pavement = in_chroma if pavement is None else pavement | in_chroma
    if pavement is None:
        return None
    ground = rows_ok & ~pavement
    need = max(1, int(round(min_ground_px / step_d_px)))
    run = 0
    for i, g in enumerate(ground):
        run = run + 1 if g else 0
        if run >= need:
            first = i - need + 1
            depth = float(d_from) if first == 0 else float(depths[first] - 0.5 * step_d_px)
            return depth, min(contrasts, key=abs) if contrasts else math.nan
        if not rows_ok[i]:
            return None
    return math.inf, min(contrasts, key=abs) if contrasts else math.nan


def _chroma_pavement(colour, horizon: HorizonFrame, s0: float, k_centre: float, line_left, line_right,
                     d_from: float, step_d_px: float, depths, grid, inside, rows_ok, split: tuple,
                     params: DetectorParams):
    """:func:`ground_begins`'s rows (``grid``, the middle's samples then each side's, ``split``)
    that are pavement in the chroma: the middle's chroma differs from each side's as the
    runway's does just inside ``d_from`` (the middle's median over ``ground_begin_chroma_rows_px``
    of depth there), by half that difference at least. None when a side's ground does not differ
    from the runway by ``transverse_chroma_min_step`` chroma levels (sand, snow, dry grass, a
    grey camera) or the rows inside are not in the frame."""
    n0, n1 = split
    height, width = colour.shape[:2]
    inner_depths = np.arange(d_from - step_d_px, max(d_from - params.ground_begin_chroma_rows_px, 0.5) - 1e-9,
                             -step_d_px)
    if len(inner_depths) < 2:
        return None
    _, _, inner_grid, inner_inside = transverse_grid(horizon, s0, k_centre, line_left, line_right, inner_depths,
                                                     np.linspace(*params.ground_begin_middle_span, n0),
                                                     colour.shape)
    if not inner_inside.all():
        return None
    points = np.concatenate([grid[inside], inner_grid.reshape(-1, 2)])
    u0, v0 = (max(0, int(math.floor(points[:, k].min())) - 1) for k in (0, 1))
    u1, v1 = int(min(width, math.ceil(points[:, 0].max()) + 2)), int(min(height, math.ceil(points[:, 1].max()) + 2))
    chroma = chroma_of(colour[v0:v1, u0:u1])

    def read(samples, ok):
        shifted = samples - np.array([u0, v0], float)
        return remap_inside(chroma, shifted[..., 0].astype(np.float32), shifted[..., 1].astype(np.float32), ok)

    surface = float(np.median(read(inner_grid, inner_inside)))
    values = read(grid, inside)
    middle = np.median(values[:, :n0], axis=1)
    pavement = rows_ok.copy()
    for side in (np.median(values[:, n0:n1], axis=1), np.median(values[:, n1:], axis=1)):
        contrast = float(np.median(side[rows_ok])) - surface
        if not abs(contrast) >= params.transverse_chroma_min_step:
            return None
        pavement &= (side - middle) * math.copysign(1.0, contrast) > 0.5 * abs(contrast)
    return pavement

