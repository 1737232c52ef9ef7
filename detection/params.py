"""DetectorParams: the one frozen parameter set of the detection stage (JSON/TOML round trip).

Every threshold and tuning number the detector uses lives here, named with its unit and
documented; the detector's modules hold only mathematical constants (a median absolute
deviation's 1.4826, Tukey's 4.685) and sampling guards.

Pixel lengths are given for the reference camera of SPEC.md (a frame 2048 pixels on its longer
side, focal length 2472 px) and rescaled to the frame the detector is given
(:meth:`DetectorParams.scaled_to`), in one of two ways, so that one parameter file serves every
image size and lens:

- **with the frame size** (:data:`SCALES_WITH_SIZE`): lengths that are about image resolution
  and evidence: working resolutions, search bands around a candidate found at the working
  resolution, shortest edge, widths below which a strip is not resolved;
- **with the focal length** (:data:`SCALES_WITH_FOCAL`): lengths that are angles seen through
  the lens: motion between frames, attitude uncertainty (the horizon's position), tolerances on
  where lines meet on the horizon.

For the SPEC camera at another size (a square frame, 45 deg field of view) both factors are
equal. Lengths in :data:`NOT_SCALED_PX` are sub-pixel sampling steps and floors, or lengths in
the downsampled working image the Hough transform sees: they do not change with the frame.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from functools import cached_property
from typing import ClassVar

import numpy as np

from visland.params import ParamsFile

__all__ = ["DetectorParams", "SCALES_WITH_SIZE", "SCALES_WITH_FOCAL", "NOT_SCALED_PX", "REFERENCE_FOCAL_PX"]

#: Focal length (px) of the reference camera the focal-scaled lengths are given for (SPEC).
REFERENCE_FOCAL_PX = 2472.0

#: Fields scaled with the frame's longer side, and the floor each is kept above.
SCALES_WITH_SIZE = {
    "acquisition_max_side_px": None,        # special: at least min(512, side), integer
    "tracking_max_side_px": None,           # special: at least min(256, side), integer
    "min_edge_length_px": 4.0,
    "search_halfwidth_px": 2.5,
    "check_first_band_px": 4.0,
    "check_second_band_px": 3.0,
    "vp_line_weight_max_px": 20.0,
    "tracking_min_depth_span_px": 4.0,
    "acquisition_min_depth_px": 1.0,
    "acquisition_max_depth_px": 256.0,
    "pencil_band_min_px": 3.0,
    "pair_min_width_px": 1.5,
    "pair_length_scale_px": 4.0,
    "strip_end_clearance_px": 1.0,
    "refine_run_gap_px": 3.0,
    "threshold_width_tolerance_px": 0.5,
}

#: Fields scaled with the focal length, and the floor each is kept above.
SCALES_WITH_FOCAL = {
    "roi_margin_px": 0.0,
    "vp_tolerance_px": 0.5,
    "horizon_sigma_px": 0.05,
    "tracking_sigma_px": 1.0,
    "horizon_margin_px": 0.0,
    "max_vp_jump_px": 0.0,
    "max_vp_jump_rate_pxps": 0.0,
    "max_threshold_jump_px": 0.0,
    "static_min_horizon_motion_px": 0.5,
}

#: Pixel lengths that deliberately do not scale (sub-pixel sampling and noise floors, working-image
#: pixels, and the reference itself).
NOT_SCALED_PX = (
    "blur_sigma_px", "hough_min_length_px", "hough_max_gap_px", "segment_merge_working_px", "segment_merge_px",
    "crossing_min_sigma_px", "pencil_fit_min_sigma_px", "duplicate_gap_px", "pencil_step_halfspan_px",
    "pencil_join_tolerance_px", "refine_min_band_px", "max_line_residual_px", "reference_side_px",
    "reference_focal_px",
    # profile lengths across a line's boundary, sub-pixel by nature (refine)
    "chroma_min_length_px", "chroma_inside_margin_px", "chroma_outside_reach_px", "chroma_step_band_px",
    "net_step_outside_px", "net_step_inside_px",
    # depth profiles' smoothing across a threshold or runway end, sub-pixel (transverse)
    "transverse_smooth_sigma_px", "transverse_light_sigma_px", "transverse_inner_px", "transverse_outer_px",
    "faint_texture_max_width_px", "crossing_pavement_depth_px", "crossing_pavement_min_width_px",
    # calibrated sub-pixel corrections of an area-sampled boundary (refine)
    "boundary_flank_bias_px", "boundary_stripe_shift_px", "boundary_stripe_resolved_px",
    "boundary_stripe_shift_scale_px", "hidden_stripe_min_px", "staircase_min_px",
    # candidate lines' sub-pixel profile lengths and floors (candidates)
    "check_min_span_px", "check_transition_halfspan_px", "check_transition_side_px", "check_line_min_sigma_px",
    # the blur of the ground's step into the pavement, read past (threshold_marking.marked_at_start)
    "marked_start_skip_px",
    # paint's least depth before a threshold: two lines half a pixel apart (threshold_marking.paint_before)
    "paint_before_min_px",
    # the measurement's sub-pixel floors, blur and resolution limits (detector)
    "edge_band_min_px", "edge_image_margin_px", "edge_blur_px", "chroma_resolved_stripe_px", "vp_line_min_sigma_px",
    "centre_band_min_px", "centre_min_width_px", "confidence_residual_px",
    # a compressed frame's block grid and its smoothing: pixels of the codec, whatever the frame
    "block_grid_px", "deblock_sigma_px",
    # pixel noise and its smoothing: pixels of the sensor
    "denoise_sigma_px",
    # depth margins of the measurement (detector) kept at their 2048 px values at every size:
    # scaled with the frame they did worse at 1024 px (benchmarks/detection_robustness.py --size
    # 1024: 69.3 % found, 7 gross against 70.0 %, 6 gross; raycast_approach.py --size 1024 --fps 1
    # unchanged, 95.2 %, 0 gross); ground_margin_px also moves the acquisition's Hough crop
    "ground_margin_px", "roi_min_side_px", "centre_image_margin_px", "threshold_window_min_px",
    "border_clearance_px", "threshold_exit_margin_px", "pavement_search_px", "pavement_min_move_px",
    "pavement_window_px", "pavement_agreement_px",
    # the chroma read past a runway end: 3 px at every size, as the 1024 px study read it before
    # (the least band it had, max(3, a tenth of the edges' depth span)), short enough at 2048 px
    # for the 5-6 px of pavement a false end on paint leaves
    "end_chroma_band_px",
    # where the ground begins and the threshold marking: depth pixels of resolution and sampling
    # (threshold_marking), kept at their 2048 px values
    "ground_begin_min_px", "ground_begin_chroma_rows_px", "marking_min_resolved_px", "marking_unresolved_min_span_px",
    "marking_unresolved_plain_px", "marking_stripes_resolved_px",
)


@dataclass(frozen=True)
class DetectorParams(ParamsFile):
    """Parameters of :func:`visland.detection.detect_runway`.

    Pixel lengths are for the reference camera (``reference_side_px``, ``reference_focal_px``)
    and rescaled to the frame (module docstring). Fractions "of the width" are of the runway's
    local width in the image, between its two edges.

    Parameters
    ----------
    acquisition_max_side_px : int
        Acquisition (no previous detection) runs Canny and the Hough transform on the ground part
        of the frame downsampled so that its larger side is at most this many pixels (the
        sub-pixel refinement always works on the full-resolution image).
    tracking_max_side_px : int
        Same for the region of interest in tracking mode.
    blur_sigma_px : float
        Gaussian blur applied before Canny, in pixels of the working (downsampled) image.
    canny_low_quantile, canny_high_quantile : float
        Canny hysteresis thresholds as quantiles of the gradient magnitude of the working
        image's ground part (adapts to the frame's contrast; 0 < low < high < 1).
    canny_min_high : float
        Floor of the high Canny threshold (Sobel magnitude units), so a flat frame gives no edges.
    canny_min_low_ratio : float
        The low Canny threshold is at least this fraction of the high one.
    hough_votes : int
        Accumulator threshold of the probabilistic Hough transform (edge pixels on a segment).
    hough_min_length_px : float
        Shortest Hough segment kept, in working-image pixels.
    hough_max_gap_px : float
        Largest gap bridged inside a Hough segment, in working-image pixels.
    hough_angle_step_deg : float
        Angular resolution of the Hough transform.
    max_candidates : int
        At most this many segments (the longest) enter the trapezoid model.
    candidate_min_length_fraction : float
        A Hough segment, or a checked candidate line, shorter than this fraction of
        ``min_edge_length_px`` is dropped.
    segment_merge_working_px, segment_merge_px : float
        Two Hough segments are one line when they lie within ``segment_merge_working_px``
        working-image pixels plus ``segment_merge_px`` full-resolution pixels of each other.
    check_samples : int
        Profiles sampled across a candidate line when it is checked on the full frame.
    check_first_band_px, check_second_band_px : float
        Half width of the band searched across a candidate line in the first check (around the
        Hough segment) and the second (around the re-fitted line).
    check_first_extend : float
        The first check samples the Hough span extended by this fraction of its length each side.
    check_extend_far, check_extend_near : float
        The second check samples the re-fitted line over its span extended by these multiples of
        its length towards the horizon and towards the image bottom.
    check_min_points : int
        Fewest profiles holding a step of one sign for a candidate line to be re-fitted.
    check_min_run_points : int
        Fewest consistent points in a candidate line's supported run.
    check_max_gap_fraction : float
        A candidate line's supported run has no gap longer than this fraction of the span sampled.
    crossing_min_sigma_px : float
        Floor of a candidate line's horizon-crossing uncertainty.
    canny_quantile_step : int
        The Canny thresholds' gradient quantiles are read on every this-many-th pixel of the
        working image, each way (their cost).
    check_min_span_px : float
        A candidate line's span is taken as at least this (pixels of depth) when it is extended.
    hough_depth_bands : tuple of 2 float
        Acquisition also looks for Hough segments in two bands of the ground's rows next to the
        horizon, ``[0, b1]`` and ``[b1, b2]`` fractions of its height, each with its own Canny
        thresholds (:func:`~visland.detection.candidates.banded_hough_segments`); a band of zero
        height is not searched. None by default: on clear frames the bands' extra candidates
        made a parallel taxiway the runway ('concrete, sand, mono': 198 gross frames out of 240);
        the low-contrast second look (:meth:`for_low_contrast`) searches
        ``low_contrast_hough_bands``.
    check_transition_halfspan_px, check_transition_side_px : float, tuple of 2 float
        A transition across a candidate line is centred on its gradient within the first of the
        strongest, its net step read between the second's distances either side
        (:func:`refine.transition_offsets`).
    check_fit_iterations, check_fit_min_inliers : int
        Re-weighting passes of a candidate line's robust re-fit, and the fewest inliers it keeps.
    check_line_min_sigma_px : float
        Floor of a candidate line's robust residual scale.
    fit_weight_cap_percentile : float
        Edge strengths weighting a line fit are capped at this percentile of theirs (a few very
        strong points do not decide alone; candidate lines and refinement).
    pencil_fit_min_sigma_px : float
        Floor of the robust scale when a candidate line ``s = s0 + k d`` is re-fitted.
    duplicate_gap_px : float
        Candidate lines of one polarity within this distance of each other over their common
        span are one edge.
    max_edge_slope : float
        Largest ``|ds/dd|`` of a runway line in horizon coordinates (s along the horizon, d
        below it): 4 is 76 deg from the horizon's normal. Flatter lines (the horizon, roads
        across the view, the threshold bar) are not edge candidates.
    vp_tolerance_px : float
        Two edges belong to one runway when their crossings of the horizon agree to this many
        pixels plus their extrapolation uncertainty.
    vp_min_line_support : float
        Candidate lines with less support (fraction of profiles) do not propose vanishing points.
    vp_line_weight_max_px : float
        A candidate line's vote for a vanishing point grows with its length up to this length.
    vp_sigma_factor : float
        Lines agree on a vanishing point within ``vp_tolerance_px`` plus this many of their
        crossing sigmas.
    vp_points_acquisition, vp_points_tracking : int
        Vanishing-point candidates examined in acquisition and in tracking (the prediction first).
    max_hypotheses : int
        Runway hypotheses kept from the trapezoid model (the best few are measured).
    tracking_slope_margin : float
        In tracking, slopes ``k`` searched beyond the predicted edges' (horizon coordinates).
    tracking_depth_margin_far, tracking_depth_margin_near : float
        In tracking, depths searched beyond the predicted runway, as fractions of its depth span,
        towards the horizon and towards the image bottom.
    tracking_min_depth_span_px : float
        Smallest depth span used for those margins.
    acquisition_min_depth_px, acquisition_max_depth_px : float
        Depths below the horizon rectified in acquisition.
    acquisition_rect_rows, acquisition_rect_columns : int
        Size of the acquisition's rectified image (rows spaced in proportion to depth): caps on
        its cost, not lengths (a smaller frame is rectified as finely or more).
    pencil_band_ratio : float
        Depth bands of the rectified image grow geometrically by this ratio.
    pencil_band_min_px : float
        Shallowest depth band.
    pencil_step_halfspan_px : float
        Steps along a band's column profile are differences over this many pixels each side.
    pencil_join_tolerance_px : float
        Steps of neighbouring bands within this distance (pixels at the band's depth) are one edge.
    pencil_min_step_fraction : float
        Smallest step in a band profile, as a fraction of ``min_contrast``.
    pencil_column_coverage : float
        A band's column is used when at least this fraction of its rows lies in the frame.
    pencil_max_edges : int
        Most edges kept per rectified image.
    min_length_to_width : float
        Smallest length-to-width ratio of a runway (a long strip; ICAO runways are 20 to 80
        times longer than wide): pairs of lines bounding a shorter strip are not runways.
    max_length_to_width : float
        Longest length-to-width ratio a strip may show and be a runway (the longest and
        narrowest runways are about 130 times longer than wide; a 0.9 m side stripe along a
        2 km runway is 2200, a 7 m road thousands): the length is the span seen, so a longer
        one is a line, not a runway.
    pair_min_width_px : float
        Narrowest runway, pixels at the near end of the two edges' common span.
    pair_length_scale_px : float
        Length (px) at which a pair's length term reaches 63 % (``1 - exp(-length / scale)``).
    pair_max_examined : int
        Pairs, best by the quick score, examined in full per rectified image.
    pair_min_interior : float
        A pair whose inside differs from its outside by less than this fraction of its edges'
        step (the sign the edges say) is not a strip.
    pair_min_off_ground, pair_ground_test_max_width : float
        A pair narrower than ``pair_ground_test_max_width`` (``k_R - k_L``, width over height)
        whose inside lies within ``pair_min_off_ground`` of its inside-outside step from the
        ground's grey level (the median of the whole pencil's rows) is ground between two
        pavements (the grass between a runway and its parallel taxiway), not a strip: a runway's
        inside is pavement and its outsides are ground (the ratio is about 1), here the other way
        round (0.03 at 3.6 km on "16 stripes, 30 m wide"). Wider pairs fill the pencil's rows
        (close to the ground) and are not tested.
    pair_interior_margin : float
        The inside of a pair is read from this fraction of the width in from each edge.
    pair_quick_centre_gap, pair_centre_gap : float
        ... to this fraction of the width short of the midline (quick score and full evidence).
    pair_outside_band : tuple of 2 float
        The ground beside an edge is read between these fractions of the width outside it.
    score_symmetry_floor, score_outside_floor, score_centre_floor : float
        Floors added to the symmetry, same-ground-both-sides and centre-line terms of a pair's
        score (a pair weak in one is not zeroed by it).
    score_uniform_floor, score_spread_scale : float
        The term rewarding an inside that is mostly one surface falls from 1 to this floor as the
        inside's interquartile spread grows to ``score_spread_scale`` times the edges' step.
    score_ends_base, score_ends_per_end : float
        The score's term for the strip's ends in view: base plus this much per end (a runway is
        a finite strip; a road runs on).
    score_dark_centre_weight : float
        A dark centre stripe counts this fraction of a bright one (painted lines are white).
    score_width_exponent : float
        A pair's score (quick and full) grows as its width to this power: among parallel paved
        strips the runway is the widest, but a wide pair of unrelated lines must not win by width.
    ground_rows_column_step : int
        The ground's grey level row by row (the median across the pencil) is read on every
        this-many-th column of the rectified image (its cost).
    centre_stripe_halfwidth, centre_stripe_sides : float, tuple of 2 float
        The centre stripe is read within this fraction of the width of the midline, against the
        mean between these fractions on either side.
    centre_stripe_min_step, centre_stripe_fraction : float
        A row holds the centre stripe when it stands out by at least the larger of this many grey
        levels and this fraction of the inside-outside difference.
    strip_inside_band : tuple of 2 float
        Fractions of the width read as the strip's surface when following it along its length.
    strip_side_band : tuple of 2 float
        Fractions of the width outside each edge read as the ground beside it.
    strip_core_margin : float
        The strip's reference rows skip this fraction of the edges' common span at each end.
    strip_level_fraction, ground_level_fraction : float
        A row belongs to the strip when it differs from the ground by at least the first fraction
        of the reference difference, to the ground when by at most the second.
    strip_end_rows : int
        Rows beyond a strip's end that must look like the ground for the end to count.
    surface_min_contrast : float
        Where the runway's surface ends (:func:`transverse.surface_extent`): the ground beside an
        edge is used when the surface differs from it by at least this many grey levels.
    surface_resume_fraction, surface_resume_rows : float, int
        A gap in the surface (a pavement crossing the runway) is bridged when the rows after it
        hold the surface's own level in at least this fraction and are at least this many; rows
        of the surface on the other side of the ground's level past the run's end (a surface that
        changes along the runway) carry it on when at least this many.
    surface_far_gap_widths, surface_far_resume_widths : float
        Past the far end of the surface's run, a gap of at most the first many runway widths
        along it (a full-width patch of another shade, a crossing pavement) is bridged when rows
        differing from the ground as the runway does follow it over at least the second many
        runway widths (whatever their own level: the pavement past a repair can be older or
        fresher).
    surface_side_margin : float
        :func:`transverse.surface_extent` resamples the runway and this fraction of its width
        beyond each edge.
    surface_rect_columns : int
        ... in at most this many columns ...
    surface_width_samples : float
        ... spaced (at the nearest depth searched) at most a runway width over this many, and
        never closer than half a pixel.
    marking_band_widths : float
        Reach of a band of threshold markings along the runway, in runway widths (ICAO threshold
        stripes and the strip before them: 36 m on a 45 m runway): the runway's surface carries
        on across such a band of blended markings, and the threshold is searched that far beyond
        where the surface seems to end (:func:`transverse.find_transverse_line`).
    marking_band_max_widths : float
        Where the chroma tells the pavement from the ground, the threshold (runway end) is also
        searched this many runway widths past where the surface seemed to end, if the chroma
        stays the pavement's up to the step (:func:`transverse.find_transverse_line`): markings
        are as long in metres on any runway, so they reach more widths on a narrow one (16
        stripes and the designation on a 30 m runway at 3.3 km, 2048 px: the surface seemed to
        end 3.1 widths inside the threshold).
    transverse_columns, transverse_column_span : int, tuple of 2 float
        The threshold and the runway's end are searched on transverse lines sampled at this many
        points between these fractions of the width ...
    transverse_min_significance : float
        ... where a step must stand out of the depth profile's noise by this factor ...
    transverse_chroma_min_step : float
        ... and the chroma profile's step is used when the chroma changes across it by at least
        this many levels.
    transverse_inner_px, transverse_inner_fraction : float
        The boundary is searched from the larger of this many depth pixels and this fraction of
        its expected depth inside where the surface ends ...
    transverse_outer_px, transverse_outer_fraction : float
        ... to the largest of this many pixels, this fraction of the depth and
        ``marking_band_widths`` outside it.
    faint_texture_max_width_px, faint_texture_min_change, faint_texture_k_sigma, faint_texture_min_significance : float
        While the runway spans fewer than the first pixels across (stripes unresolved), a rise of
        texture by the second fraction of the smallest step, above the ground's spread by the
        third factor, standing out of the profile's noise by the fourth, is a band of distant
        stripes.
    crossing_pavement_band, crossing_pavement_depth_px : tuple of 2 float
        A threshold's step is checked beside the runway (:func:`transverse.pavement_beyond_edges`)
        between these runway widths beyond each edge, comparing the mean levels this many depth
        pixels on either side of the line ...
    crossing_pavement_share, crossing_pavement_ground_tolerance : float
        ... where a step of at least this fraction of the step between the edges, in each half
        of the band, whose outer side has the level of the ground between the edges (within this
        fraction of the step beside), is a pavement crossing or joining the runway there: the
        threshold is withheld ...
    crossing_pavement_min_width_px : float
        ... where a runway width along the runway spans at least this many depth pixels.
    transverse_smooth_sigma_px, transverse_light_sigma_px : float
        Sigmas (pixels of depth) of the Gaussians smoothing those depth profiles before they are
        differentiated, and lightly for the fit of the boundary.
    strip_end_clearance_px : float
        An end must lie this far from the horizon and the image bottom to count.
    parallel_score_ratio, parallel_min_width_ratio : float
        Of strips side by side, a wider one (by this ratio) scoring at least this fraction of the
        other's score (per grey level of edge contrast when its contrast is the lower and it is
        at least as long in the image) is put first (a runway is wider than its parallel
        taxiway, and no shorter).
    parallel_min_gap : float
        ... and only if its edges step the same way and ground at least this fraction of the
        narrower strip's width lies between them (the ground between a runway and its taxiway,
        bounded by their facing edges, is not a wider strip to prefer). Two hypotheses sharing an
        edge (within this fraction of the narrower width) with reversed steps are a strip and
        the ground beside it.
    ground_between_margin : float
        Of those two, the one whose inside is nearer the ground's grey level by this much more
        (in units of the larger edge step) is the ground and goes after the other.
    strip_min_interior, strip_max_outside_gap, strip_max_spread : float
        A convincing strip: inside-outside difference at least ``strip_min_interior`` of its
        edges' step, the two outsides within ``strip_max_outside_gap`` of that difference, the
        inside's spread within ``strip_max_spread`` times it.
    enclosing_centre_tolerance, enclosing_max_width_ratio, enclosing_score_ratio : float
        A hypothesis enclosing the best one (same midline within the tolerance, fraction of the
        width; at most this much wider; at least this fraction of its score) is the runway's
        outer boundary and goes first (the best was the inner edges of the side stripes).
    min_edge_length_px : float
        Shortest runway edge accepted (full-resolution pixels along the line).
    search_halfwidth_px : float
        Half width of the band searched across a predicted line during refinement.
    refine_samples : int
        Most profiles sampled along one line during refinement.
    refine_iterations : int
        Re-sampling passes of the refinement (each narrows the band).
    refine_min_band_px : float
        The refinement's band never narrows below this half width.
    refine_net_fraction : float
        A region boundary's profile is used when its grey level changes the boundary's way by at
        least this fraction of the median change.
    refine_weak_fraction : float
        Profiles whose step is weaker than this fraction of the median step are not used
        (texture beside the line).
    refine_run_gap_px, refine_run_gap_fraction : float
        A refined line's visible stretch is the largest run of inliers without a gap longer than
        the larger of this length and this fraction of the span.
    chroma_min_change : float
        A chroma boundary is used where the chroma rises by at least this many levels across it.
    chroma_min_span : float
        ... and its points cover at least this fraction of the grey line's span.
    chroma_samples : int
        Chroma profiles sampled along a boundary.
    chroma_min_length_px : float
        A grey boundary shorter than this is not moved onto the chroma.
    chroma_inside_margin_px, chroma_outside_reach_px : float
        The chroma boundary is searched from the border stripe's reach plus the first inside
        the grey line to the second outside it (pixels).
    chroma_step_band_px : tuple of 2 float
        The chroma's rise across a located boundary: mean between these distances outside minus
        the same inside (pixels).
    boundary_flank_ratio : float
        Walking outwards from a region boundary's strongest step, an opposite step reaching this
        fraction of its slope is a border stripe's outer flank, the boundary
        (:func:`refine.boundary_offsets`).
    boundary_same_step_ratio : float
        A step of the chosen flank's sign just outside it, reaching this fraction of its slope,
        is the region's sharper geometric edge and is taken instead (a blurred texture inside).
    boundary_flank_bias_px : float
        The boundary is extrapolated from the outer flank of its derivative lobe (its 60 % and
        20 % crossings); for an area-sampled step seen through bilinear interpolation and a
        central difference this lands this far outside, removed (calibrated).
    boundary_stripe_shift_px, boundary_stripe_resolved_px, boundary_stripe_shift_scale_px : float
        An unresolved border stripe's outer flank lies outside the boundary by
        ``shift * exp(-(max(separation - resolved, 0) / scale) ** 1.5)`` pixels, ``separation``
        between the stripe's two flanks (calibrated on area-sampled stripes 0 to 3 px wide at
        every sub-pixel phase: mean residual within 0.12 px); removed.
    hidden_stripe_min_fraction : float
        A border stripe's width is trusted along a boundary where this fraction of the profiles
        used see both its flanks; a profile whose only step is on the stripe's inner line is then
        moved out by that width (:func:`refine.past_hidden_stripe`: the ground as bright as the
        paint hides the stripe's outer flank).
    hidden_stripe_min_px : float
        ... where the stripe is at least this wide (pixels of the frame: below, it is not resolved).
    hidden_stripe_tolerance : float
        ... and the lone step lies within this fraction of the width from the inner line.
    hidden_stripe_max_scatter : float
        ... and the stripes seen agree on a straight width within this fraction of it (robust
        scatter): texture beyond the edge does not.
    staircase_min_fraction : float
        A side stripe a little darker than the ground beyond it (snow, light sand) is a staircase:
        the pavement's step onto the paint, then a weaker one of the same sign onto the ground, the
        runway's edge. Where on both edges this fraction of the profiles sampled across them
        (:func:`detector._past_staircase_stripes`) see such a second step beyond the edge found...
    staircase_step_ratio : float
        ... of at least this fraction of the edge's own slope (or a shoulder: the edge's own step
        stopping short of the ground's level by ``staircase_shoulder_fraction`` of the whole step
        or more), ...
    staircase_shoulder_fraction : float
        ... a second step that makes no peak of the slope of its own counts where the edge's step
        stops short of the ground's level by this fraction of the whole step from the pavement
        (:func:`detector._stripe_shoulder`; a plain step stops within 0.002-0.11 of it) ...
    staircase_max_scatter : float
        ... at a fraction of the runway's local width that is the same along each edge within this
        fraction of it (robust scatter: texture beyond the edge has none) ...
    staircase_agreement : float
        ... and the same on both edges within this fraction (the two side stripes are painted
        alike), ...
    staircase_min_px : float
        ... the profiles counted where the stripe is at least this wide (pixels of the frame:
        narrower, it merges with the step onto it), both edges are moved out past their stripes.
    staircase_near_min_profiles, staircase_near_fraction, staircase_near_scatter, staircase_far_max_fraction : int, float, float, float
        Or seen the way a stripe resolved on the edges' near part only is: of the nearer half
        of those profiles, at least ``staircase_near_min_profiles`` and ``staircase_near_fraction``
        see the second step within ``staircase_near_scatter`` of the median fraction (as regular
        as paint), of the farther half at most ``staircase_far_max_fraction`` see one at all
        (there the stripe merges with the step onto it; texture beyond an edge shows steps all
        along it).
    net_step_outside_px, net_step_inside_px : tuple of 2 float
        A boundary's net grey-level change: mean between the first's distances outside it minus
        the mean between the second's distances inside the border stripe's reach (pixels).
    min_edge_support : float
        Smallest fraction of a line's profiles that must hold an inlying edge.
    max_line_residual_px : float
        Largest RMS distance of the inlying edge points to a refined line.
    min_contrast : float
        Smallest grey-level step accepted as an edge or stripe.
    block_sample_rows : int
        The frame's compression block grid is looked for on this many rows of its ground.
    block_grid_px : int
        Side of a compression block (JPEG, MPEG: 8 px, aligned with the frame's top-left pixel).
    block_grid_min_ratio : float
        A frame whose mean absolute grey-level step across the block grid's columns is at
        least this many times the mean step elsewhere (on those rows) was compressed coarsely
        (:func:`visland.detection.detector.block_grid_ratio`): a JPEG of quality 40-50 reads
        2.9-3.3, the raw frame and a JPEG of quality 95 about 1, the key frames of the
        recordings' H.264 videos (512 px) 1.5-1.7 and their other frames 0.9-1.3. Each block
        keeps a few coefficients, so a straight edge becomes a staircase of blocks: its points
        are off by up to half a block, evenly spread, a standard deviation of ``block_grid_px /
        sqrt(12)`` (2.3 px for 8 px blocks). On such a frame ``confidence_residual_px`` and
        ``max_line_residual_px`` are at least that (:meth:`for_block_grid`): a straight edge's
        staircase is not taken for a bent line.
    deblock_sigma_px, deblock_min_grid_step : float
        Such a frame whose grid steps by at least ``deblock_min_grid_step`` grey levels more than
        the frame elsewhere (:func:`visland.detection.detector.block_grid_steps`) is also
        smoothed by a Gaussian of this sigma (pixels) before the search, which averages the
        staircase out along the edges (0: not smoothed). Measured grid steps: the robustness
        study's 'sensor: noise, blur, JPEG' frames (JPEG 50, noise 6, blur 1 px, 1024 px)
        2.24-2.43 levels, a noisy JPEG of quality 40 on the ray-cast airport 3.0-3.3; visland's
        clean 512 px frames through OpenCV's MJPG writer 1.2-2.0 (ratio 2.3-3.1; smoothed, 43 of
        their 104 frames were found: tests/datasets/test_process.py's video), clean JPEGs of
        quality 75-40 0.8-1.5. The limit lies between the two groups, with little room on
        either side (0.1-0.15 levels).
    denoise_min_noise, denoise_sigma_px : float
        A frame in which the runway was not found, that was not deblocked and whose pixel noise
        (:func:`visland.detection.detector.pixel_noise`) is at least ``denoise_min_noise`` grey
        levels is searched again smoothed by a Gaussian of ``denoise_sigma_px`` (pixels; 0:
        never). The detector's contrast and support thresholds hold for a noise of 1-2 grey levels
        (visland's clean frames 0.7-1.2, the ray-cast airport 2.0); white noise of deviation
        ``s`` comes out of a Gaussian of sigma 1 px at about ``s / 3.5``. Only a second look:
        smoothed, a side stripe blurs into the edge beside it (edges 0.2-0.5 px off).
    low_contrast_max_noise, low_contrast_factor : float
        A frame in which the runway was not found and whose pixel noise is at most
        ``low_contrast_max_noise`` grey levels is searched again with its grey-level thresholds
        (``min_contrast``, ``surface_min_contrast``) times ``low_contrast_factor`` (1: never):
        haze, overcast and dusk take a runway's edges to a few grey levels, still many times
        such a frame's noise. Only a second look: on a clear frame the thresholds keep the
        ground's texture out.
    low_contrast_hough_bands : tuple of 2 float
        The ``hough_depth_bands`` of that second look: haze and dusk take a distant runway's
        contrast below the near ground's texture, whose gradients set the whole frame's Canny
        thresholds ('overcast, 5 km' at 1.97 km, 2048 px: no candidate line on the runway).
    roi_margin_px : float
        Margin added around the predicted runway in tracking mode.
    roi_margin_fraction : float
        Extra margin as a fraction of the predicted runway's size.
    threshold_search_fraction : float
        The threshold is searched along the runway over this fraction of the edges' visible
        length on each side of the near end of the edge support.
    horizon_sigma_px : float
        One-sigma uncertainty of the horizon from the inertial attitude, pixels: weighs the
        horizon against the three lines when the vanishing point is fused.
    max_lateral_widths : float
        The two edges are not the runway being approached when their centre line lies farther to
        the side of the aircraft than this many of their own widths: in the horizon frame the
        pencil slopes give ``k_C / (k_R - k_L) = Y / W`` exactly, whatever the height, attitude
        and heading (a ground line at lateral distance ``Y`` from the camera has ``k = Y / h``).
        An approach keeps the aircraft within about two localizer dots (5 deg) of the centre line:
        from 7 km a 23 m runway (the narrowest the robustness study draws) is then 27 of its widths
        to the side. A road 7 m wide parallel to the runway 340 m beside it is 49 widths out (the
        ray-cast airport through a 62 deg barrel lens: taken for the runway from 4.4 to 1.3 km,
        edges 55-70 px off, confidence 0.7).
    max_lateral_heights, max_lateral_heights_widths : float
        The two edges are not the runway being approached when their centre line lies farther to
        the side of the aircraft than ``max_lateral_heights`` camera heights (``|k_C| = |Y| / h``,
        exact in the horizon frame, no runway size assumed) while the aircraft is not over the
        strip or nearly (more than ``max_lateral_heights_widths`` of its widths to the side: near
        the ground a lateral offset of a few metres is many heights). An approach descends along
        about 3 deg (h / d = 0.052) within a few degrees of the centre line: 3 heights is 9 deg off
        it seen from the threshold; the thesis's approaches start at most 1.69 heights out
        (thesis-4: 400 m at 5 km, 237 m high). A parallel taxiway 185 m beside the runway on the
        robustness study's overcast frames at 2048 px was acquired at 2.4 km, 1.33 heights out
        (no geometry refuses it there), and tracked as its ``k_C`` grew with the descent (3 heights
        at about 1 km, 5.8 at 250 m), edges 90-130 px off; with this check it is dropped at 3.
    unconfirmed_max_lateral_heights : float
        Over a sequence (:class:`~visland.detection.sequence.DetectionSequence`), a strip followed
        since its acquisition is reported only once it is confirmed as the runway approached: it
        showed a threshold marking (``marked_start_widths``; not a centre line: taxiways carry
        one) in one of its frames, or
        its centre line lay within this many camera heights of the aircraft (or the aircraft
        over it, ``max_lateral_heights_widths``). Until then it is followed but reported not
        found, saying why. One height is 3 deg off the centre line seen from the threshold on a
        3 deg descent, about a stabilised approach's limit; the overcast taxiway above was
        acquired 1.33 heights out, its runway's own edges lost in the fog, and never came
        nearer. A runway approached from farther out (thesis-4 starts 1.69 heights out) is
        reported from its first threshold marking seen or once the aircraft is within this many
        heights; while a strip is not confirmed the whole frame is searched afresh too, and
        another strip found there with a threshold marking in two frames running replaces it.
        Confirmation by place holds only in the frames it holds in (a marking seen confirms a
        track for good).
    weak_max_lateral_heights, place_min_confidence : float
        A strip unmarked so far whose confidence is below ``place_min_confidence`` is confirmed
        by its place only within ``weak_max_lateral_heights`` (instead of
        ``unconfirmed_max_lateral_heights``): a doubtful strip beside the approach is a taxiway as
        often as the runway. On the ray-cast airport with a rubber-darkened 1200 x 23 m runway on
        grass of nearly its grey (1024 px, 5 Hz) the runway's edges held nowhere beyond 1.3 km
        and the parallel taxiway, 0.64 heights beside the aircraft at 2.5 km, was followed to
        100 ft at confidences 0.29-0.56 while within a height, 144 frames reported 50-450 px
        off. The price, the runway's own doubtful frames beside the approach: 1 frame of 6480 on
        the robustness study at 2048 px, 4 at 1024 px; 4 of 62 on the ray-cast approach at 1 Hz
        (4.1-4.6 km, the runway 0.53-0.84 heights out at confidence 0.25-0.59).
    replacement_min_confidence : float
        While the strip followed is not confirmed and doubtful (below ``place_min_confidence``, or
        lost in the frame), an unmarked strip found afresh with at least this confidence, itself
        confirmed by its place, in this frame and the one before, replaces it
        (:meth:`~visland.detection.sequence.DetectionSequence._look_for_confirmed`).
    place_recheck_s, place_recheck_max_s : float
        A strip confirmed by its place alone (within ``unconfirmed_max_lateral_heights``, no
        threshold marking seen in its track) is checked against a search of the whole frame
        afresh: at its first frame so confirmed, then ``place_recheck_s`` later, the interval
        doubled after each search that found no other marked strip, up to
        ``place_recheck_max_s``. Another strip found there with a threshold marking makes the one
        followed doubtful (not reported) for ``hold_s``, is looked for in every frame while it
        does, and, seen again in the next frame, replaces the one followed. An approach that starts over a
        parallel taxiway finds the taxiway under the aircraft confirmed by its place (held-out
        draw 14: from 3.6 to 2.7 km, edges 104-127 px off, while single frames searched afresh
        found the runway beside it, its stripes read). Not every frame: a search of the whole
        frame costs about eight tracked frames, and a runway without markings is confirmed by its
        place alone all the way down.
    single_marking_max_lateral_heights, weak_marking_window_s : float
        A threshold marking read on a doubtful strip (below ``place_min_confidence``) lying
        farther than ``single_marking_max_lateral_heights`` camera heights beside the aircraft
        confirms it only when read again, in another frame, within ``weak_marking_window_s``:
        one frame's reading there can be the ground's blur at the strip's start (held-out draw 4,
        a concrete runway lost on sand at dusk: a taxiway 2.04 heights out at confidence 0.49
        read "marked" once at 3.45 km, the sand's blur at its start, then reported to 940 m,
        120-490 px off). 1.5 heights is 4.5 deg off the centre line seen from the threshold on a
        3 deg descent, beyond a localizer's full-scale deflection (1.5-3 deg either side); the
        thesis's approaches start within 1.69 heights (thesis-4), and a doubtful runway seen
        from there is confirmed by its second reading. Within that bound (held-out draw 8: its
        runway 1.09 heights out at 3.5 km, confidence 0.3-0.6) one reading confirms.
    diverging_min_lateral_heights, diverging_window_s, diverging_min_growth : float
        Over a sequence, a strip followed that lies more than ``diverging_min_lateral_heights``
        camera heights beside the aircraft in every frame of the last ``diverging_window_s``
        seconds of its track, its offset grown over them by ``diverging_min_growth`` (a line
        fitted to the offsets, its rise relative to their mean), is not reported, marked or
        not: the aircraft is moving away from it, and an approach converges on its runway's
        centre line (:meth:`~visland.detection.sequence.DetectionSequence._moving_away`). A
        strip's offset ``Y / h`` grows by ``-v_h / h`` per second once the aircraft stops
        closing on it (3 % per second at 2.3 km on a 3 deg descent, 7 % at 1 km); measured
        offsets scatter by about 1 % frame to frame (held-out draw 4's taxiway at 3.6 km: 2.06
        to 2.10). 1.2 heights is beyond the thesis's approaches while their runway moves away
        (thesis-8: 0.84 to 1.13 heights from 4.7 to 4.2 km, its initial heading off); thesis-3
        and thesis-4 start 1.08 and 1.69 heights out and close in. Held-out draw 4: a taxiway
        beside a runway lost on sand, confirmed by a band inside it read as a displaced
        threshold's marking, was reported from 2.31 km to 850 m, its offset growing from 1.31
        to 3.0 heights.
    max_width_change : float
        In tracking, the runway's apparent width (its width over the camera height) may differ
        from the previous frame's by this fraction at most (a parallel taxiway is half as wide).
    tracking_sigma_px : float
        How far (one sigma, pixels) the runway may move from its prediction between frames
        before a candidate loses the preference the prediction gives it.
    min_confidence : float
        Detections below this confidence are reported as not found.
    corner_min_confidence : float
        Where the two edges' own confidence (support, straightness, agreement on the horizon,
        contrast: the confidence without the centre line's part) is below this, the corners, the
        threshold and the runway end are withheld (the edges and the heading are reported):
        corners lie on the edges and are as doubtful.
    horizon_margin_px : float
        The horizon from roll and pitch must cross the image enlarged by this margin.
    max_heading_deviation_deg : float
        A runway being approached lies ahead: a pair of edges whose vanishing point says the
        runway's direction is more than this far from the aircraft's heading (a crossing
        taxiway or road) is not taken (the thesis's approaches start within 15 deg).
    ground_margin_px : float
        The ground searched is the part of the frame more than this below the horizon.
    contrast_sample_step : int
        The frame's contrast check reads every this-many-th pixel of the ground, each way.
    contrast_percentiles : tuple of 2 float
        The contrast is the spread between these percentiles of those grey levels (compared
        with ``min_contrast``).
    roi_min_side_px : float
        A tracking region of interest narrower or shorter than this is not searched (the
        previous runway is taken as out of view).
    tracking_sigma_width_fraction : float
        The prediction's one-sigma motion grows by this fraction of the runway's near width (px
        per px), on top of ``tracking_sigma_px``.
    edge_depth_inset_fraction : float
        Each edge is refined between the surface's ends moved inwards by this fraction of their
        depth span.
    edge_surface_rows : int
        Most rows read to find where a hypothesis's surface ends before its edges are refined.
    edge_band_fraction, tracking_edge_band_fraction : float
        The band searched across an edge is at most this fraction of the runway's local width
        (acquisition, tracking a prediction that may have moved), so markings inside the
        runway do not become the strongest step.
    edge_band_min_px : float
        ... and at least this half width.
    tracking_refine_iterations : int
        Refinement passes of a predicted edge (tracking).
    edge_image_margin_px : float
        An edge is sampled where it lies this far (plus ``search_halfwidth_px``) inside the image.
    side_stripe_width_fraction : float
        Widest painted side stripe looked past to the runway's boundary, fraction of the runway's
        local width (ICAO: 0.9 m on runways 30 m and wider, 1.5 to 3 %).
    edge_blur_px : float
        Blur added to that stripe width, pixels.
    chroma_retry_extent_fraction : float
        In colour, an edge whose grey-level fit covers less than this fraction of its span is
        refined again on the chroma.
    chroma_resolved_stripe_px : float
        A side stripe at least this wide (pixels) is resolved and the grey boundary kept;
        narrower, the boundary is moved onto the chroma step (:func:`refine.chroma_boundary`).
    prediction_gate_sigmas : float
        Tracking: a refined edge more than this many prediction sigmas from its prediction is
        not the runway tracked.
    edge_crossing_sigmas : float
        The edges (and the centre line) meet the horizon within ``vp_tolerance_px`` plus this
        many of their crossings' combined sigma.
    pair_min_overlap_fraction : float
        The two edges must be seen over a common stretch of depth of at least this fraction of
        the shorter one's (and ``min_edge_length_px``).
    edge_balance_min_ratio, edge_balance_min_levels : float
        Both sides of one runway separate its pavement from what lies beside it: the grey-level
        (or chroma) step across the weaker edge, between the surface just outside it and the
        pavement inside past a side stripe, must be at least ``edge_balance_min_ratio`` of the
        step across the stronger one. A painted line inside a pavement (the centre line taken
        for an edge, seen in fog) has the same surface on both sides. A channel decides only
        where the stronger step reaches ``edge_balance_min_levels`` levels; the pair is refused
        when a deciding channel finds the steps unbalanced and no deciding channel finds them
        balanced.
    vp_line_min_sigma_px : float
        Floor of a line's uncertainty at the horizon when the vanishing point is fused.
    centre_band_fraction, centre_band_min_px, centre_band_max_factor : float
        Half width of the band searched for the centre line: this fraction of the runway's near
        width, between this many pixels and this many times ``search_halfwidth_px``.
    centre_width_fraction, centre_min_width_px : float
        Widest centre stripe expected: this fraction of the runway's local width, at least this
        many pixels.
    centre_image_margin_px : float
        The centre line is sampled where it lies this far inside the image.
    centre_min_support : float
        A centre stripe held by a smaller fraction of its profiles is not the centre line.
    centre_bright_support : float
        A bright centre stripe this well supported ends the search (the dark one is tried only
        when the bright one fails: painted lines are white).
    threshold_window_min_px, threshold_window_depth_fraction : float
        The threshold (runway end) is searched within the largest of this many pixels, half the
        ``threshold_search_fraction`` of the edges' depth span, and this fraction of its
        expected depth, of where the surface ends.
    end_past_edges_fraction : float
        A runway end found where both edges run on farther than this fraction of their depth
        span is a step inside the pavement (rubber ending on the paler pavement beyond the
        touchdown zone): the end is searched again where the edges end, nearer than that step,
        and withheld if not found there.
    end_run_on_ratio : float
        A runway end is withheld when the contrast across both edges (the range of grey levels
        across each: pavement against ground, the side stripe), read over
        ``end_past_edges_fraction`` of their depth span past it (2 px at least), less the
        contrast of the same rows a runway width farther out (the ground's own: a road crossing
        past the end, bands of fields near the horizon), is at least this fraction of theirs
        just before it: the edges run on, the step is inside the pavement (tracking, where the
        edges are refined over the surface's extent and end with it). On the ray-cast 1200 x
        23 m runway at 1024 px, 5 Hz: past the rubber's end 0.27-1.3 (asphalt, and concrete as
        light as the grass), past the true end within 0.1 of 0 (no rubber), once -0.37; on
        visland's 'oblique, 1200x23' frame at 450 m, a road crossing just past the end, 0.63
        and 0.60 without the ground's subtracted, 0.21 and -0.36 with it.
    end_chroma_band_px : float
        In a colour frame, a runway end is withheld when the chroma between the edges from 1 to
        1 + this many depth pixels past it stays the pavement's while the ground beside both
        edges differs (:func:`visland.detection.transverse.pavement_runs_on`). Short, so that
        it reads the pavement left between a false end and the true one: the reciprocal
        runway's touchdown-zone or aiming-point paint taken for the end, 400-450 m short, leaves
        5-6 px of pavement before the grass at 2.8 km and 2048 px ('16 stripes, 30 m wide',
        'variety 1'); a band of 13 px read mostly the grass beyond and did not withhold it.
    border_clearance_px : float
        Edges supported to within this depth of the image bottom reach its border (a threshold
        not found is then below the image).
    threshold_exit_margin_px : float
        A surface ending within this depth of where the runway leaves the image hides the
        threshold: none is searched.
    pavement_search_fraction, pavement_search_px : float
        Where the ground begins before a threshold found is searched this fraction of the edges'
        depth span plus this many pixels towards the camera.
    pavement_search_extend : float
        When the pavement runs on over all of that, it is searched again this many times as far;
        still pavement there, the step found is inside the runway and the threshold is withheld.
    pavement_min_move_px : float
        The threshold moves to where the ground begins when that is more than this depth past
        the step found.
    pavement_window_px, pavement_agreement_px : float
        The step is then searched again within this depth of where the ground begins and must
        lie within the second of it.
    ground_begin_min_px : float
        Where the ground begins (:func:`threshold_marking.ground_begins`): the first this many
        pixels of depth of consecutive ground rows ...
    ground_begin_middle_span, ground_begin_middle_samples : tuple of 2 float, int
        ... a row being ground when the median of this many samples between these fractions of
        the width ...
    ground_begin_side_band, ground_begin_side_samples : tuple of 2 float, int
        ... differs from the runway's surface level as the median of this many samples between
        these fractions of the width outside each edge does.
    ground_begin_chroma_rows_px : float
        With a colour frame the chroma also tells pavement from ground there, the runway's own
        chroma read over this many pixels of depth just inside the step found.
    marking_min_pavement_widths, marking_max_pavement_widths : float
        A threshold marking (:func:`threshold_marking.threshold_marking`) must begin between these
        many runway widths inside the pavement.
    paint_before_from_widths, paint_before_widths, paint_before_min_px : float
        :func:`threshold_marking.paint_before`: runway paint (a threshold band's lines) read from
        the first to the second many runway widths nearer than the threshold step found, over
        this many pixels of depth at least, means the step lies inside the runway: the threshold
        is withheld.
    paint_before_noise_sigmas, paint_before_agreement : float
        Paint there stands out of the ground's texture by this many robust sigmas, and two
        consecutive lines hold it in the same columns (this intersection over union at least).
    marking_columns, marking_column_span : int, tuple of 2 float
        It is read on transverse lines sampled at this many points between these fractions of the
        width (clear of the side stripes and of the edges' blur).
    marking_min_resolved_px : float
        Depth pixels the first ``marking_min_pavement_widths`` of pavement must span for the
        threshold's own stripes to be resolved; below it they are *unresolved* (seen blended)
        and only a band's presence across the width is asked.
    marking_unresolved_min_span_px : float
        Unresolved: pixels a transverse line must cross the runway over to be read.
    marking_start_fraction : float
        Unresolved: the first lines' excess over the pavement's median line, as a fraction of the
        markings' contrast, that shows the threshold's blended stripes at the pavement's start.
    marking_unresolved_coverage : float
        Unresolved: fraction of the width a band must cover to be the marking.
    marking_unresolved_plain_px : float
        Unresolved: depth pixels of plain pavement at its start before a brighter line makes the
        threshold doubtful.
    marking_brighter_ground_fraction : float
        Markings must outshine the pavement by the ground's step where the ground is darker; where
        it is brighter (snow), by this fraction of that step: white paint cannot outshine snow.
        Paint that passes only so must show clear stripes (the next three).
    marking_dim_stripes_widths, marking_dim_stripes_share, marking_dim_min_stripes : float, float, int
        Clear stripes: over this many runway widths from their first line (0.5: 30 m, the
        shortest threshold stripes, on a 60 m runway), this share of the lines read crosses this
        many separate marks at least (4: the fewest threshold stripes).
    marking_dim_texture_ratio : float
        And those lines cross this many times as many marks as the pavement's lines before them
        (medians): not the surface's own blotches.
    marking_bright_percentile : float
        The markings' grey level is this percentile of the pavement's samples (white paint); a
        sample is marked when brighter than the pavement by half their difference.
    marking_quarter_min_share, marking_bar_coverage, marking_min_stripes : float, float, int
        A line is a band of markings when each quarter of the width has at least the first
        fraction marked, and then a bar when the second fraction of the width is marked, stripes
        when at least this many separate marked runs cross it.
    marking_stripes_min_widths, marking_stripes_resolved_px : float
        Stripes are the threshold's only when they run along the runway over this many runway widths at
        least (ICAO Annex 14 5.2.4: 30 m at least, 0.5 of a 60 m width; FAA 150 ft), checked where
        that length spans the given pixels of depth or more: a row of arrow heads before a
        displaced threshold's bar (4.5 m long) crosses the width as stripes do (the robustness
        study at 2048 px, 600 to 390 m before it: taken for the stripes, the threshold put 6-12 px
        before the bar).
    marked_start_widths, marked_start_skip_px : float
        The threshold's own marking at the pavement's start (the stripes, 6 m in and 30 m long
        at least, ICAO Annex 14 5.2.4; FAA 20 ft and 150 ft; or a bar) is looked for over this
        many runway widths from the threshold found there (1.6: a 23 m runway's first 36 m), from
        this many pixels of depth inside it (where a brighter ground's blur adds less than half
        its step)
        (:func:`visland.detection.threshold_marking.marked_at_start`). Seen, it tells a runway
        from a taxiway or road (none carries one), whatever the distance:
        :class:`~visland.detection.sequence.DetectionSequence` then reports a strip
        followed well beside the approach (``unconfirmed_max_lateral_heights``).
    confidence_residual_px : float
        The confidence's straightness term is ``exp(-(r / this)^2 / 2)``, r the larger edge RMS
        residual (pixels).
    confidence_vp_sigmas : float
        Its horizon-agreement term falls as the edges' crossings separate by this many sigmas.
    confidence_contrast_factor : float
        Its contrast term is full at this many times ``min_contrast``.
    confidence_without_centre : float
        Factor on the confidence when the centre line is not found.
    hold_s : float
        Over a sequence (:class:`visland.detection.DetectionSequence`): how long the last good
        detection keeps predicting the runway after frames where it was not found, before the
        next search starts from nothing (a lost runway is then acquired on the whole frame).
    new_track_frames : int
        Over a sequence: a new track (an acquisition with no good detection within ``hold_s``
        and no remembered runway to check it against, ``identity_memory_s``) is followed from its
        first frame but reported from its ``new_track_frames``-th consecutive one (1: at once). One
        frame's strip can be a road: on the independent ray-cast airport through a 62 deg lens
        (1280x720, 1 Hz) a road 7 m wide, 157 m beside the aircraft at 4.4 km, was acquired once
        with confidence 0.74 and refused in the next frame, which found the runway.
    max_edge_turn_rad, max_edge_turn_rate_rps : float
        Over a sequence: a detection that did not come from tracking (a re-acquisition) is
        refused when an edge's direction in the image differs from the last good detection's by
        more than ``max_edge_turn_rad + max_edge_turn_rate_rps * dt`` (a field boundary or a
        taxiway picked after a short loss).
    max_vp_jump_px, max_vp_jump_rate_pxps : float
        Over a sequence: the same for the vanishing point's move along the horizon (d_F), in
        pixels of the reference image side.
    static_window_s, static_min_horizon_motion_px, static_max_motion_ratio : float
        Over a sequence: a runway moves in the image with the scene. When, between a detection
        and one up to ``static_window_s`` earlier, the horizon moved away from the earlier
        vanishing point by more than ``static_min_horizon_motion_px`` (the camera turned) while
        the edges' crossing moved by less than ``static_max_motion_ratio`` of that (a world
        vanishing point stays on the horizon, so it moves at least as far), the "runway" is fixed to the camera (the
        windshield frame, the glareshield): refused.
    identity_memory_s : float
        Over a sequence: how long the runway's place on the ground relative to the camera (its
        centre line's lateral offset over height, its width over height: the pencil slopes
        ``k_C`` and ``k_R - k_L`` in the horizon frame, independent of attitude) is remembered
        to check a re-acquisition after a loss longer than ``hold_s``. Only frames that follow a
        good one within ``hold_s`` are remembered: a single acquisition can be a road or a
        taxiway, and would refuse the runway for this long.
    identity_k_tolerance, identity_k_rate : float
        A re-acquired runway whose centre line's ``k_C`` (lateral offset / height) differs from
        the remembered one by more than ``identity_k_tolerance + identity_k_rate * dt`` plus 10 %
        of it is another object parallel to the runway (a strip of fields, a taxiway): refused.
    identity_rate_window_s : float
        The remembered ``k_C`` is carried forward at its own rate: a straight line fitted to the
        accepted frames' ``k_C`` of this many seconds before the last one, its slope shrunk toward
        zero by its standard error against a prior of one sigma ``identity_k_rate`` (a noisy or
        short history moves nothing). ``k_C`` changes at ``(v_Y - k_C v_h) / h``: 0.1 per second
        while an approach aligns with the runway at 22 m/s from 220 m (thesis-8 at 4 km), twice
        the fixed rate, and the runway itself was refused for 11 s after a short loss.
    identity_width_tolerance, identity_width_rate : float
        The same for the width over height ``k_R - k_L``, relative: more than
        ``identity_width_tolerance + identity_width_rate * dt`` away (the height falls by about
        2 % per second on the glide path at 800 ft, 7 % at 50 ft).
    max_threshold_jump_px, max_threshold_jump_fraction : float
        Over a sequence: threshold corners farther than ``max_threshold_jump_px +
        max_threshold_jump_fraction * threshold width`` per frame (at ``reference_rate_hz``)
        from the last good detection's are dropped (the edges and d_F are kept).
    threshold_track_s : float
        Over a sequence: the threshold's width in pixels ``w`` is followed over this many
        seconds of accepted frames; at a steady ground speed ``1 / w = x / (f W)`` falls
        linearly with time whatever the height (``x``: distance to the threshold, ``W``: the
        runway's width), so three or more accepted widths predict the next one.
    threshold_width_tolerance_px, threshold_width_tolerance_fraction : float
        A threshold whose width differs from the track's prediction by more than
        ``threshold_width_tolerance_px + threshold_width_tolerance_fraction * predicted width``
        is not the threshold followed so far (a marking, a joining pavement): its corners are
        withheld. (A tolerance widened by three standard errors of the track's own scatter was
        tried, a614eae, and removed: it kept correct thresholds at 512 px, 3-6 % off the
        prediction, and let through 5 gross ones in the robustness study's 'snow, monochrome',
        6-7 % off, 5-8 px wrong; the width cannot tell the two apart.)
    threshold_shrink_memory_s : float
        Over a sequence, where the track holds fewer than three widths: a threshold narrower
        than the last one accepted in the last this many seconds, by more than the tolerance
        above, is withheld: flying toward the threshold its width ``f W / depth`` only grows.
        (Against the widest of the memory instead, the noisy frames of the robustness study's
        'sensor' condition lost 44 correct thresholds to one high width.)
    marking_memory_s, marking_memory_agreement : float
        Over a sequence: while two frames of the last ``marking_memory_s`` seconds saw a
        threshold marking inside the pavement (a displaced threshold, a blast pad) the same
        number of runway widths in (within this fraction), a threshold placed where the
        pavement begins is withheld (:class:`visland.detection.DetectionSequence`); while no
        threshold is followed yet (``threshold_track_s``), one such frame is enough for the
        frame after it.
    marking_memory_min_widths : float
        ... a marking at least this many runway widths in: nearer, it can be the threshold's own
        marking (stripes from 6 to 36 m in, the designation to about 60 m: 1.3 widths of a 45 m
        runway) seen behind a band of ground taken for pavement. On visland's 512 px thesis-3
        approach a dark band of grass before the threshold did that from 700 to 450 m: sightings
        1.0-1.3 widths in, and 10 thresholds within 0.1-1.2 px of the truth withheld.
    reference_rate_hz : float
        Frame rate the per-frame limits above are given for.
    reference_side_px : int
        Longer side of the frame the size-scaled lengths above are given for.
    reference_focal_px : float
        Focal length (px) of the camera the focal-scaled lengths above are given for.
    """

    params_kind: ClassVar[str] = "detector"
    toml_table: ClassVar[str | None] = "detector"

    # --- working resolution, Canny and Hough (candidates.hough_segments)
    acquisition_max_side_px: int = 1024
    tracking_max_side_px: int = 640
    blur_sigma_px: float = 1.0
    canny_low_quantile: float = 0.70
    canny_high_quantile: float = 0.85
    canny_min_high: float = 10.0
    canny_min_low_ratio: float = 0.4
    hough_votes: int = 18
    hough_min_length_px: float = 14.0
    hough_max_gap_px: float = 3.0
    hough_angle_step_deg: float = 1.0
    max_candidates: int = 150
    # --- candidate lines checked on the frame (candidates.candidate_lines, check_lines)
    candidate_min_length_fraction: float = 0.5
    segment_merge_working_px: float = 1.5
    segment_merge_px: float = 0.5
    check_samples: int = 48
    check_first_band_px: float = 6.0
    check_second_band_px: float = 3.0
    check_first_extend: float = 0.1
    check_extend_far: float = 1.0
    check_extend_near: float = 1.5
    check_min_points: int = 6
    check_min_run_points: int = 4
    check_max_gap_fraction: float = 0.2
    crossing_min_sigma_px: float = 0.3
    pencil_fit_min_sigma_px: float = 0.3
    duplicate_gap_px: float = 1.0
    canny_quantile_step: int = 2
    check_min_span_px: float = 4.0
    hough_depth_bands: tuple = (0.0, 0.0)
    check_transition_halfspan_px: float = 2.0
    check_transition_side_px: tuple = (2.5, 5.0)
    check_fit_iterations: int = 5
    check_fit_min_inliers: int = 4
    check_line_min_sigma_px: float = 0.2
    fit_weight_cap_percentile: float = 90.0
    # --- vanishing points and the trapezoid model (trapezoid, pencil)
    max_edge_slope: float = 4.0
    vp_tolerance_px: float = 8.0
    vp_min_line_support: float = 0.3
    vp_line_weight_max_px: float = 200.0
    vp_sigma_factor: float = 2.0
    vp_points_acquisition: int = 4
    vp_points_tracking: int = 2
    max_hypotheses: int = 6
    tracking_slope_margin: float = 0.3
    tracking_depth_margin_far: float = 0.3
    tracking_depth_margin_near: float = 0.5
    tracking_min_depth_span_px: float = 8.0
    acquisition_min_depth_px: float = 2.0
    acquisition_max_depth_px: float = 4096.0
    acquisition_rect_rows: int = 160
    acquisition_rect_columns: int = 3072
    pencil_band_ratio: float = 1.35
    pencil_band_min_px: float = 6.0
    pencil_step_halfspan_px: float = 0.75
    pencil_join_tolerance_px: float = 1.0
    pencil_min_step_fraction: float = 0.5
    pencil_column_coverage: float = 0.5
    pencil_max_edges: int = 120
    min_length_to_width: float = 8.0
    max_length_to_width: float = 300.0
    pair_min_width_px: float = 3.0
    pair_length_scale_px: float = 30.0
    pair_max_examined: int = 24
    pair_min_interior: float = 0.1
    pair_min_off_ground: float = 0.3
    pair_ground_test_max_width: float = 2.0
    pair_interior_margin: float = 0.12
    pair_quick_centre_gap: float = 0.05
    pair_centre_gap: float = 0.08
    pair_outside_band: tuple = (0.12, 0.4)
    score_symmetry_floor: float = 0.5
    score_outside_floor: float = 0.3
    score_centre_floor: float = 0.5
    score_uniform_floor: float = 0.1
    score_spread_scale: float = 2.0
    score_ends_base: float = 0.4
    score_ends_per_end: float = 0.3
    score_dark_centre_weight: float = 0.5
    score_width_exponent: float = 0.5
    ground_rows_column_step: int = 4
    centre_stripe_halfwidth: float = 0.015
    centre_stripe_sides: tuple = (0.04, 0.08)
    centre_stripe_min_step: float = 2.0
    centre_stripe_fraction: float = 0.2
    strip_inside_band: tuple = (0.1, 0.9)
    strip_side_band: tuple = (0.12, 0.38)
    strip_core_margin: float = 0.2
    strip_level_fraction: float = 0.5
    ground_level_fraction: float = 0.25
    strip_end_rows: int = 3
    surface_min_contrast: float = 2.0
    surface_resume_fraction: float = 0.6
    surface_resume_rows: int = 3
    surface_far_gap_widths: float = 2.0
    surface_far_resume_widths: float = 3.0
    surface_side_margin: float = 0.4
    surface_rect_columns: int = 96
    surface_width_samples: float = 50.0
    marking_band_widths: float = 1.2
    marking_band_max_widths: float = 4.0
    transverse_columns: int = 48
    transverse_column_span: tuple = (0.1, 0.9)
    transverse_min_significance: float = 2.5
    transverse_chroma_min_step: float = 8.0
    transverse_inner_px: float = 1.5
    transverse_inner_fraction: float = 0.01
    transverse_outer_px: float = 2.5
    transverse_outer_fraction: float = 0.02
    faint_texture_max_width_px: float = 64.0
    faint_texture_min_change: float = 0.1
    faint_texture_k_sigma: float = 3.0
    faint_texture_min_significance: float = 5.0
    crossing_pavement_band: tuple = (0.25, 1.0)
    crossing_pavement_depth_px: tuple = (1.0, 3.0)
    crossing_pavement_share: float = 0.5
    crossing_pavement_ground_tolerance: float = 0.5
    crossing_pavement_min_width_px: float = 2.0
    transverse_smooth_sigma_px: float = 0.8
    transverse_light_sigma_px: float = 0.3
    strip_end_clearance_px: float = 3.0
    parallel_score_ratio: float = 0.3
    parallel_min_width_ratio: float = 1.3
    parallel_min_gap: float = 0.25
    ground_between_margin: float = 0.5
    strip_min_interior: float = 0.5
    strip_max_outside_gap: float = 0.5
    strip_max_spread: float = 1.5
    enclosing_centre_tolerance: float = 0.15
    enclosing_max_width_ratio: float = 1.4
    enclosing_score_ratio: float = 0.25
    # --- sub-pixel refinement (refine)
    min_edge_length_px: float = 24.0
    search_halfwidth_px: float = 6.0
    refine_samples: int = 96
    refine_iterations: int = 3
    refine_min_band_px: float = 2.5
    refine_net_fraction: float = 0.3
    refine_weak_fraction: float = 0.35
    refine_run_gap_px: float = 8.0
    refine_run_gap_fraction: float = 0.15
    chroma_min_change: float = 8.0
    chroma_min_span: float = 0.6
    chroma_samples: int = 64
    chroma_min_length_px: float = 4.0
    chroma_inside_margin_px: float = 1.0
    chroma_outside_reach_px: float = 1.5
    chroma_step_band_px: tuple = (1.0, 3.0)
    boundary_flank_ratio: float = 0.3
    boundary_same_step_ratio: float = 0.6
    boundary_flank_bias_px: float = 0.11
    boundary_stripe_shift_px: float = 0.2
    boundary_stripe_resolved_px: float = 1.6
    boundary_stripe_shift_scale_px: float = 0.2
    hidden_stripe_min_fraction: float = 0.08
    hidden_stripe_min_px: float = 2.0
    hidden_stripe_tolerance: float = 0.35
    hidden_stripe_max_scatter: float = 0.25
    staircase_min_fraction: float = 0.6
    staircase_step_ratio: float = 0.12
    staircase_shoulder_fraction: float = 0.12
    staircase_max_scatter: float = 0.2
    staircase_agreement: float = 0.3
    staircase_min_px: float = 2.5
    staircase_near_min_profiles: int = 4
    staircase_near_fraction: float = 0.5
    staircase_near_scatter: float = 0.1
    staircase_far_max_fraction: float = 0.25
    net_step_outside_px: tuple = (1.0, 3.0)
    net_step_inside_px: tuple = (0.5, 3.0)
    min_edge_support: float = 0.45
    max_line_residual_px: float = 1.5
    min_contrast: float = 6.0
    block_sample_rows: int = 32
    block_grid_px: int = 8
    block_grid_min_ratio: float = 2.0
    deblock_sigma_px: float = 1.5
    deblock_min_grid_step: float = 2.15
    denoise_min_noise: float = 2.5
    denoise_sigma_px: float = 1.0
    low_contrast_max_noise: float = 1.5
    low_contrast_factor: float = 0.5
    low_contrast_hough_bands: tuple = (0.125, 0.33)
    # --- tracking, the measurement and its confidence (detector)
    roi_margin_px: float = 40.0
    roi_margin_fraction: float = 0.15
    threshold_search_fraction: float = 0.35
    horizon_sigma_px: float = 4.0
    tracking_sigma_px: float = 12.0
    max_lateral_widths: float = 30.0
    max_lateral_heights: float = 3.0
    max_lateral_heights_widths: float = 1.5
    unconfirmed_max_lateral_heights: float = 1.0
    weak_max_lateral_heights: float = 0.5
    place_min_confidence: float = 0.6
    replacement_min_confidence: float = 0.8
    place_recheck_s: float = 0.5
    place_recheck_max_s: float = 4.0
    single_marking_max_lateral_heights: float = 1.5
    weak_marking_window_s: float = 2.0
    diverging_min_lateral_heights: float = 1.2
    diverging_window_s: float = 4.0
    diverging_min_growth: float = 0.05
    max_width_change: float = 0.25
    min_confidence: float = 0.25
    corner_min_confidence: float = 0.4
    horizon_margin_px: float = 0.0
    max_heading_deviation_deg: float = 40.0
    # --- the measurement of a hypothesis (detector._measure and its steps)
    ground_margin_px: float = 2.0
    contrast_sample_step: int = 4
    contrast_percentiles: tuple = (1.0, 99.0)
    roi_min_side_px: float = 8.0
    tracking_sigma_width_fraction: float = 0.05
    edge_depth_inset_fraction: float = 0.03
    edge_surface_rows: int = 300
    edge_band_fraction: float = 0.05
    tracking_edge_band_fraction: float = 0.15
    edge_band_min_px: float = 2.0
    tracking_refine_iterations: int = 1
    edge_image_margin_px: float = 4.0
    side_stripe_width_fraction: float = 0.04
    edge_blur_px: float = 1.5
    chroma_retry_extent_fraction: float = 0.5
    chroma_resolved_stripe_px: float = 3.0
    prediction_gate_sigmas: float = 2.5
    edge_crossing_sigmas: float = 3.0
    pair_min_overlap_fraction: float = 0.25
    edge_balance_min_ratio: float = 0.25
    edge_balance_min_levels: float = 6.0
    vp_line_min_sigma_px: float = 0.02
    centre_band_fraction: float = 0.08
    centre_band_min_px: float = 3.0
    centre_band_max_factor: float = 3.0
    centre_width_fraction: float = 0.06
    centre_min_width_px: float = 2.0
    centre_image_margin_px: float = 8.0
    centre_min_support: float = 0.25
    centre_bright_support: float = 0.5
    threshold_window_min_px: float = 8.0
    threshold_window_depth_fraction: float = 0.1
    end_past_edges_fraction: float = 0.1
    end_run_on_ratio: float = 0.3
    end_chroma_band_px: float = 3.0
    border_clearance_px: float = 3.0
    threshold_exit_margin_px: float = 2.0
    pavement_search_fraction: float = 0.5
    pavement_search_px: float = 8.0
    pavement_search_extend: float = 3.0
    pavement_min_move_px: float = 3.0
    pavement_window_px: float = 3.0
    pavement_agreement_px: float = 2.0
    ground_begin_min_px: float = 1.5
    ground_begin_middle_span: tuple = (0.15, 0.85)
    ground_begin_middle_samples: int = 15
    ground_begin_side_band: tuple = (0.15, 0.4)
    ground_begin_side_samples: int = 6
    ground_begin_chroma_rows_px: float = 3.0
    marking_min_pavement_widths: float = 0.8
    marking_max_pavement_widths: float = 12.0
    marking_columns: int = 64
    paint_before_from_widths: float = 0.5
    paint_before_widths: float = 8.0
    paint_before_min_px: float = 1.0
    paint_before_noise_sigmas: float = 5.0
    paint_before_agreement: float = 0.5
    marking_column_span: tuple = (0.06, 0.94)
    marking_min_resolved_px: float = 1.5
    marking_unresolved_min_span_px: float = 6.0
    marking_start_fraction: float = 0.25
    marking_unresolved_coverage: float = 0.6
    marking_unresolved_plain_px: float = 3.0
    marking_brighter_ground_fraction: float = 0.25
    marking_dim_stripes_widths: float = 0.5
    marking_dim_stripes_share: float = 0.75
    marking_dim_min_stripes: int = 4
    marking_dim_texture_ratio: float = 3.0
    marking_bright_percentile: float = 99.0
    marking_quarter_min_share: float = 0.15
    marked_start_widths: float = 1.6
    marked_start_skip_px: float = 0.5
    marking_bar_coverage: float = 0.8
    marking_min_stripes: int = 3
    marking_stripes_min_widths: float = 0.3
    marking_stripes_resolved_px: float = 3.0
    confidence_residual_px: float = 0.8
    confidence_vp_sigmas: float = 3.0
    confidence_contrast_factor: float = 4.0
    confidence_without_centre: float = 0.85
    # --- over a sequence (sequence)
    hold_s: float = 1.0
    new_track_frames: int = 2
    max_edge_turn_rad: float = 0.05
    max_edge_turn_rate_rps: float = 0.3
    max_vp_jump_px: float = 60.0
    max_vp_jump_rate_pxps: float = 250.0
    static_window_s: float = 3.0
    static_min_horizon_motion_px: float = 8.0
    static_max_motion_ratio: float = 0.2
    identity_memory_s: float = 10.0
    identity_k_tolerance: float = 0.1
    identity_k_rate: float = 0.05
    identity_rate_window_s: float = 3.0
    identity_width_tolerance: float = 0.25
    identity_width_rate: float = 0.05
    max_threshold_jump_px: float = 6.0
    max_threshold_jump_fraction: float = 0.12
    threshold_track_s: float = 2.0
    threshold_width_tolerance_px: float = 2.0
    threshold_width_tolerance_fraction: float = 0.04
    threshold_shrink_memory_s: float = 5.0
    marking_memory_s: float = 10.0
    marking_memory_agreement: float = 0.25
    marking_memory_min_widths: float = 2.0
    reference_rate_hz: float = 25.0
    # --- the reference camera of the pixel lengths
    reference_side_px: int = 2048
    reference_focal_px: float = REFERENCE_FOCAL_PX

    #: Valid range of every field: ``(low, high)``; ``int`` marks integers, ``open`` an excluded
    #: low end; tuples are checked element by element.
    _RANGES: ClassVar[dict] = {
        "acquisition_max_side_px": (128, 8192, "int"), "tracking_max_side_px": (64, 8192, "int"),
        "blur_sigma_px": (0.0, 5.0), "canny_low_quantile": (0.0, 1.0, "open"),
        "canny_high_quantile": (0.0, 1.0, "open"), "canny_min_high": (0.0, 2000.0),
        "canny_min_low_ratio": (0.0, 1.0), "hough_votes": (2, 10000, "int"),
        "hough_min_length_px": (2.0, 10000.0), "hough_max_gap_px": (0.0, 100.0),
        "hough_angle_step_deg": (0.01, 5.0), "max_candidates": (4, 10000, "int"),
        "candidate_min_length_fraction": (0.0, 1.0), "segment_merge_working_px": (0.0, 50.0),
        "segment_merge_px": (0.0, 50.0), "check_samples": (8, 10000, "int"),
        "check_first_band_px": (0.5, 500.0), "check_second_band_px": (0.5, 500.0),
        "check_first_extend": (0.0, 10.0), "check_extend_far": (0.0, 10.0), "check_extend_near": (0.0, 10.0),
        "check_min_points": (3, 1000, "int"), "check_min_run_points": (2, 1000, "int"),
        "check_max_gap_fraction": (0.0, 1.0, "open"), "crossing_min_sigma_px": (0.0, 100.0),
        "pencil_fit_min_sigma_px": (0.01, 100.0), "duplicate_gap_px": (0.0, 100.0),
        "canny_quantile_step": (1, 16, "int"), "check_min_span_px": (0.5, 1000.0),
        "hough_depth_bands": (0.0, 1.0),
        "check_transition_halfspan_px": (0.5, 100.0), "check_transition_side_px": (0.5, 100.0),
        "check_fit_iterations": (1, 50, "int"), "check_fit_min_inliers": (3, 1000, "int"),
        "check_line_min_sigma_px": (0.01, 100.0), "fit_weight_cap_percentile": (1.0, 100.0),
        "max_edge_slope": (0.1, 100.0), "vp_tolerance_px": (0.1, 1000.0), "vp_min_line_support": (0.0, 1.0),
        "vp_line_weight_max_px": (1.0, 100000.0), "vp_sigma_factor": (0.0, 100.0),
        "vp_points_acquisition": (1, 100, "int"), "vp_points_tracking": (1, 100, "int"),
        "max_hypotheses": (1, 1000, "int"), "tracking_slope_margin": (0.0, 100.0),
        "tracking_depth_margin_far": (0.0, 10.0), "tracking_depth_margin_near": (0.0, 10.0),
        "tracking_min_depth_span_px": (1.0, 10000.0), "acquisition_min_depth_px": (0.5, 10000.0),
        "acquisition_max_depth_px": (16.0, 100000.0), "acquisition_rect_rows": (16, 10000, "int"),
        "acquisition_rect_columns": (64, 100000, "int"), "pencil_band_ratio": (1.01, 10.0),
        "pencil_band_min_px": (1.0, 1000.0), "pencil_step_halfspan_px": (0.1, 100.0),
        "pencil_join_tolerance_px": (0.1, 100.0), "pencil_min_step_fraction": (0.0, 10.0),
        "pencil_column_coverage": (0.0, 1.0, "open"), "pencil_max_edges": (2, 10000, "int"),
        "min_length_to_width": (0.0, 1000.0), "max_length_to_width": (1.0, 1e9), "pair_min_width_px": (0.0, 1000.0),
        "pair_length_scale_px": (0.1, 10000.0), "pair_max_examined": (1, 10000, "int"),
        "pair_min_interior": (0.0, 1.0), "pair_min_off_ground": (0.0, 10.0), "pair_ground_test_max_width": (0.0, 100.0), "pair_interior_margin": (0.0, 0.5), "pair_quick_centre_gap": (0.0, 0.5),
        "pair_centre_gap": (0.0, 0.5), "pair_outside_band": (0.0, 5.0), "score_symmetry_floor": (0.0, 100.0),
        "score_outside_floor": (0.0, 100.0), "score_centre_floor": (0.0, 100.0), "score_uniform_floor": (0.0, 1.0),
        "score_spread_scale": (0.01, 100.0),
        "score_ends_base": (0.0, 100.0), "score_ends_per_end": (0.0, 100.0), "score_dark_centre_weight": (0.0, 1.0),
        "score_width_exponent": (0.0, 4.0), "ground_rows_column_step": (1, 64, "int"),
        "centre_stripe_halfwidth": (0.0, 0.5, "open"), "centre_stripe_sides": (0.0, 0.5),
        "centre_stripe_min_step": (0.0, 255.0), "centre_stripe_fraction": (0.0, 10.0),
        "strip_inside_band": (0.0, 1.0), "strip_side_band": (0.0, 5.0), "strip_core_margin": (0.0, 0.49),
        "strip_level_fraction": (0.0, 10.0), "ground_level_fraction": (0.0, 10.0),
        "strip_end_rows": (1, 1000, "int"), "surface_min_contrast": (0.0, 255.0),
        "surface_resume_fraction": (0.0, 1.0), "surface_resume_rows": (1, 1000, "int"),
        "surface_far_gap_widths": (0.0, 100.0), "surface_far_resume_widths": (0.0, 1000.0),
        "surface_side_margin": (0.0, 10.0), "surface_rect_columns": (8, 10000, "int"),
        "surface_width_samples": (1.0, 10000.0), "marking_band_widths": (0.0, 100.0),
        "marking_band_max_widths": (0.0, 100.0),
        "transverse_columns": (8, 10000, "int"), "transverse_column_span": (0.0, 1.0), "transverse_min_significance": (0.0, 100.0),
        "transverse_chroma_min_step": (0.0, 255.0), "transverse_inner_px": (0.0, 1000.0), "transverse_inner_fraction": (0.0, 1.0),
        "transverse_outer_px": (0.0, 1000.0), "transverse_outer_fraction": (0.0, 1.0),
        "faint_texture_max_width_px": (0.0, 100000.0), "faint_texture_min_change": (0.0, 10.0),
        "faint_texture_k_sigma": (0.0, 100.0), "faint_texture_min_significance": (0.0, 100.0),
        "crossing_pavement_band": (0.0, 10.0), "crossing_pavement_depth_px": (0.0, 100.0),
        "crossing_pavement_share": (0.0, 10.0), "crossing_pavement_ground_tolerance": (0.0, 10.0),
        "crossing_pavement_min_width_px": (0.0, 10000.0),
        "transverse_smooth_sigma_px": (0.05, 100.0, "open"),
        "transverse_light_sigma_px": (0.05, 100.0, "open"), "strip_end_clearance_px": (0.0, 1000.0),
        "parallel_score_ratio": (0.0, 10.0), "parallel_min_width_ratio": (1.0, 100.0),
        "parallel_min_gap": (0.0, 100.0), "ground_between_margin": (0.0, 100.0),
        "strip_min_interior": (0.0, 10.0), "strip_max_outside_gap": (0.0, 100.0), "strip_max_spread": (0.0, 100.0),
        "enclosing_centre_tolerance": (0.0, 10.0), "enclosing_max_width_ratio": (1.0, 100.0),
        "enclosing_score_ratio": (0.0, 10.0),
        "min_edge_length_px": (4.0, 10000.0), "search_halfwidth_px": (1.5, 200.0),
        "refine_samples": (8, 100000, "int"), "refine_iterations": (1, 20, "int"),
        "refine_min_band_px": (0.5, 100.0), "refine_net_fraction": (0.0, 10.0), "refine_weak_fraction": (0.0, 1.0),
        "refine_run_gap_px": (0.0, 10000.0), "refine_run_gap_fraction": (0.0, 1.0),
        "chroma_min_change": (0.0, 255.0), "chroma_min_span": (0.0, 1.0), "chroma_samples": (3, 100000, "int"),
        "chroma_min_length_px": (1.0, 1000.0), "chroma_inside_margin_px": (0.0, 100.0),
        "chroma_outside_reach_px": (0.0, 100.0), "chroma_step_band_px": (0.0, 100.0),
        "boundary_flank_ratio": (0.0, 10.0),
        "boundary_same_step_ratio": (0.0, 10.0), "boundary_flank_bias_px": (-10.0, 10.0),
        "boundary_stripe_shift_px": (0.0, 10.0), "boundary_stripe_resolved_px": (0.0, 100.0),
        "boundary_stripe_shift_scale_px": (0.01, 100.0), "hidden_stripe_min_fraction": (0.0, 1.0),
        "hidden_stripe_min_px": (0.0, 100.0), "hidden_stripe_tolerance": (0.0, 1.0),
        "hidden_stripe_max_scatter": (0.0, 10.0), "staircase_min_fraction": (0.0, 1.0), "staircase_step_ratio": (0.0, 10.0),
        "staircase_shoulder_fraction": (0.0, 1.0),
        "staircase_near_min_profiles": (3, 1000, "int"), "staircase_near_fraction": (0.0, 1.0),
        "staircase_near_scatter": (0.0, 10.0), "staircase_far_max_fraction": (0.0, 1.0),
        "staircase_max_scatter": (0.0, 10.0), "staircase_agreement": (0.0, 10.0), "staircase_min_px": (0.0, 1000.0), "net_step_outside_px": (0.0, 100.0), "net_step_inside_px": (0.0, 100.0),
        "min_edge_support": (0.0, 1.0, "open"), "max_line_residual_px": (0.01, 100.0), "min_contrast": (0.0, 255.0),
        "block_sample_rows": (1, 4096, "int"), "block_grid_px": (2, 64, "int"),
        "block_grid_min_ratio": (1.0, 100.0), "deblock_min_grid_step": (0.0, 255.0), "deblock_sigma_px": (0.0, 10.0),
        "denoise_min_noise": (0.0, 255.0), "denoise_sigma_px": (0.0, 10.0),
        "low_contrast_max_noise": (0.0, 255.0), "low_contrast_factor": (0.0, 1.0, "open"),
        "low_contrast_hough_bands": (0.0, 1.0),
        "roi_margin_px": (0.0, 4096.0), "roi_margin_fraction": (0.0, 10.0),
        "threshold_search_fraction": (0.01, 1.0), "horizon_sigma_px": (0.01, 10000.0),
        "tracking_sigma_px": (0.1, 10000.0), "max_width_change": (0.01, 10.0), "max_lateral_widths": (0.0, 1e6), "max_lateral_heights": (0.0, 1e6), "max_lateral_heights_widths": (0.0, 1e6), "unconfirmed_max_lateral_heights": (0.0, 1e6), "weak_max_lateral_heights": (0.0, 1e6), "place_min_confidence": (0.0, 1.0), "replacement_min_confidence": (0.0, 1.0), "place_recheck_s": (0.0, 1e6), "place_recheck_max_s": (0.0, 1e6), "single_marking_max_lateral_heights": (0.0, 1e6), "weak_marking_window_s": (0.0, 1e6), "diverging_min_lateral_heights": (0.0, 1e6), "diverging_window_s": (0.0, 600.0), "diverging_min_growth": (0.0, 1e6), "min_confidence": (0.0, 1.0), "corner_min_confidence": (0.0, 1.0),
        "ground_margin_px": (0.0, 1000.0), "contrast_sample_step": (1, 64, "int"),
        "contrast_percentiles": (0.0, 100.0), "roi_min_side_px": (1.0, 10000.0),
        "tracking_sigma_width_fraction": (0.0, 10.0), "edge_depth_inset_fraction": (0.0, 0.49),
        "edge_surface_rows": (8, 100000, "int"), "edge_band_fraction": (0.0, 10.0, "open"),
        "tracking_edge_band_fraction": (0.0, 10.0, "open"), "edge_band_min_px": (0.5, 1000.0),
        "tracking_refine_iterations": (1, 20, "int"), "edge_image_margin_px": (0.0, 1000.0),
        "side_stripe_width_fraction": (0.0, 1.0), "edge_blur_px": (0.0, 100.0),
        "chroma_retry_extent_fraction": (0.0, 1.0), "chroma_resolved_stripe_px": (0.0, 1000.0),
        "prediction_gate_sigmas": (0.1, 100.0), "edge_crossing_sigmas": (0.1, 100.0),
        "pair_min_overlap_fraction": (0.0, 1.0), "vp_line_min_sigma_px": (0.001, 100.0),
        "edge_balance_min_ratio": (0.0, 1.0), "edge_balance_min_levels": (0.0, 255.0),
        "centre_band_fraction": (0.0, 1.0), "centre_band_min_px": (0.5, 1000.0),
        "centre_band_max_factor": (1.0, 100.0), "centre_width_fraction": (0.0, 1.0),
        "centre_min_width_px": (0.5, 1000.0), "centre_image_margin_px": (0.0, 1000.0),
        "centre_min_support": (0.0, 1.0), "centre_bright_support": (0.0, 1.0),
        "threshold_window_min_px": (0.0, 10000.0), "threshold_window_depth_fraction": (0.0, 10.0), "end_past_edges_fraction": (0.0, 10.0), "end_run_on_ratio": (0.0, 1e6),
        "end_chroma_band_px": (0.5, 1000.0),
        "border_clearance_px": (0.0, 1000.0), "threshold_exit_margin_px": (0.0, 1000.0),
        "pavement_search_fraction": (0.0, 10.0), "pavement_search_px": (0.0, 10000.0), "pavement_search_extend": (1.0, 100.0),
        "pavement_min_move_px": (0.0, 1000.0), "pavement_window_px": (0.5, 1000.0),
        "pavement_agreement_px": (0.0, 1000.0),
        "ground_begin_min_px": (0.0, 1000.0), "ground_begin_middle_span": (0.0, 1.0),
        "ground_begin_middle_samples": (3, 1000, "int"), "ground_begin_side_band": (0.0, 10.0),
        "ground_begin_side_samples": (1, 1000, "int"), "ground_begin_chroma_rows_px": (0.5, 1000.0), "marking_min_pavement_widths": (0.0, 1000.0),
        "marking_max_pavement_widths": (0.0, 1000.0), "marking_columns": (8, 10000, "int"),
        "paint_before_from_widths": (0.0, 1000.0), "paint_before_widths": (0.0, 1000.0),
        "paint_before_min_px": (0.0, 1000.0),
        "paint_before_noise_sigmas": (0.0, 1000.0), "paint_before_agreement": (0.0, 1.0),
        "marking_column_span": (0.0, 1.0), "marking_min_resolved_px": (0.0, 1000.0),
        "marking_unresolved_min_span_px": (0.0, 10000.0), "marking_start_fraction": (0.0, 10.0),
        "marking_unresolved_coverage": (0.0, 1.0), "marking_unresolved_plain_px": (0.0, 1000.0),
        "marking_brighter_ground_fraction": (0.0, 10.0), "marking_dim_stripes_widths": (0.0, 100.0),
        "marking_dim_stripes_share": (0.0, 1.0), "marking_dim_min_stripes": (1, 1000, "int"),
        "marking_dim_texture_ratio": (0.0, 100.0),
        "marking_bright_percentile": (50.0, 100.0), "marking_quarter_min_share": (0.0, 1.0), "marked_start_widths": (0.0, 100.0), "marked_start_skip_px": (0.0, 100.0),
        "marking_bar_coverage": (0.0, 1.0), "marking_min_stripes": (1, 1000, "int"), "marking_stripes_min_widths": (0.0, 100.0), "marking_stripes_resolved_px": (0.0, 1000.0), "confidence_residual_px": (0.01, 100.0),
        "confidence_vp_sigmas": (0.1, 100.0), "confidence_contrast_factor": (0.1, 1000.0),
        "confidence_without_centre": (0.0, 1.0),
        "horizon_margin_px": (0.0, 100000.0), "hold_s": (0.0, 60.0), "new_track_frames": (1, 1000, "int"), "max_heading_deviation_deg": (1.0, 90.0), "max_edge_turn_rad": (0.0, 3.2),
        "max_edge_turn_rate_rps": (0.0, 100.0), "max_vp_jump_px": (0.0, 100000.0),
        "max_vp_jump_rate_pxps": (0.0, 1e6), "max_threshold_jump_px": (0.0, 100000.0),
        "max_threshold_jump_fraction": (0.0, 100.0), "threshold_track_s": (0.1, 60.0),
        "static_window_s": (0.1, 60.0), "static_min_horizon_motion_px": (0.0, 100000.0),
        "static_max_motion_ratio": (0.0, 1.0), "identity_memory_s": (0.0, 600.0), "identity_k_tolerance": (0.0, 100.0), "identity_k_rate": (0.0, 100.0),
        "identity_rate_window_s": (0.0, 600.0),
        "identity_width_tolerance": (0.0, 100.0), "identity_width_rate": (0.0, 100.0),
        "threshold_width_tolerance_px": (0.0, 1000.0), "threshold_width_tolerance_fraction": (0.0, 10.0),
        "threshold_shrink_memory_s": (0.0, 600.0),
        "marking_memory_s": (0.0, 3600.0), "marking_memory_agreement": (0.0, 10.0),
        "marking_memory_min_widths": (0.0, 1000.0), "reference_rate_hz": (0.1, 10000.0),
        "reference_side_px": (16, 100000, "int"), "reference_focal_px": (1.0, 1e6),
    }

    def __post_init__(self):
        for f in fields(self):
            if f.name not in self._RANGES:
                raise RuntimeError(f"DetectorParams.{f.name} has no valid range")    # keeps the table complete
            low, high, *flags = self._RANGES[f.name]
            value = getattr(self, f.name)
            if isinstance(f.default, tuple):
                if not isinstance(value, (tuple, list)) or len(value) != len(f.default):
                    raise ValueError(f"DetectorParams.{f.name} must be {len(f.default)} numbers, got {value!r}")
                items = tuple(self._number(f.name, v, low, high, flags) for v in value)
                if list(items) != sorted(items):
                    raise ValueError(f"DetectorParams.{f.name} must be increasing, got {value!r}")
                object.__setattr__(self, f.name, items)
            else:
                object.__setattr__(self, f.name, self._number(f.name, value, low, high, flags))
        if self.canny_low_quantile >= self.canny_high_quantile:
            raise ValueError("DetectorParams.canny_low_quantile must be smaller than canny_high_quantile")

    @staticmethod
    def _number(name, value, low, high, flags):
        integer, open_low = "int" in flags, "open" in flags
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise ValueError(f"DetectorParams.{name} must be a number, got {value!r}")
        if integer and int(value) != value:
            raise ValueError(f"DetectorParams.{name} must be an integer, got {value!r}")
        if not math.isfinite(value) or value < low or value > high or (open_low and value == low):
            bracket = "(" if open_low else "["
            raise ValueError(f"DetectorParams.{name} must lie in {bracket}{low:g}, {high:g}], got {value!r}")
        return int(value) if integer else float(value)

    # ----------------------------------------------------------------- variants
    def for_block_grid(self) -> "DetectorParams":
        """The same detector for a coarsely compressed frame (:attr:`block_grid_min_ratio`): the
        residuals a straight edge is allowed, ``confidence_residual_px`` and
        ``max_line_residual_px``, at least the scatter of its points over a block's staircase,
        ``block_grid_px / sqrt(12)``.

        Returns
        -------
        DetectorParams
            ``self`` when both already allow it, else a copy, made once per parameter set (a
            copy validates every field again: 0.65 ms, on every frame of a compressed video).
        """
        return self._block_grid_params

    @cached_property
    def _block_grid_params(self) -> "DetectorParams":
        staircase_px = self.block_grid_px / math.sqrt(12.0)
        if self.confidence_residual_px >= staircase_px and self.max_line_residual_px >= staircase_px:
            return self
        return replace(self, confidence_residual_px=max(self.confidence_residual_px, staircase_px),
                       max_line_residual_px=max(self.max_line_residual_px, staircase_px))

    def for_low_contrast(self) -> "DetectorParams":
        """The same detector with its grey-level thresholds (``min_contrast``,
        ``surface_min_contrast``) times ``low_contrast_factor`` and the Hough bands
        ``low_contrast_hough_bands``, for a frame of low contrast and low noise
        (:attr:`low_contrast_max_noise`); the confidence's contrast scale
        (``confidence_contrast_factor`` times ``min_contrast``) unchanged. Made once per
        parameter set."""
        return self._low_contrast_params

    @cached_property
    def _low_contrast_params(self) -> "DetectorParams":
        if self.low_contrast_factor == 1.0:
            return self
        # (the confidence still weighs an edge's contrast against the usual threshold: a faint
        # edge found is a doubtful one, its corners withheld sooner)
        return replace(self, min_contrast=self.min_contrast * self.low_contrast_factor,
                       surface_min_contrast=self.surface_min_contrast * self.low_contrast_factor,
                       confidence_contrast_factor=self.confidence_contrast_factor / self.low_contrast_factor,
                       hough_depth_bands=self.low_contrast_hough_bands)

    def scaled_to(self, frame) -> "DetectorParams":
        """The same detector for another frame: lengths in pixels scale (module docstring), counts,
        ratios and grey levels do not.

        Parameters
        ----------
        frame : CameraModel or int
            The camera of the frames (its longer side and focal length ``fx``), or the side of a
            square frame of the SPEC field of view (45 deg: the focal length scales with it).

        Returns
        -------
        DetectorParams
            With ``reference_side_px`` and ``reference_focal_px`` those of ``frame``; idempotent
            (``self`` when they already are). The copy for another frame is made once and kept.
        """
        if isinstance(frame, (int, np.integer)) and not isinstance(frame, bool):
            if frame < 16:
                raise ValueError(f"frame must be a CameraModel or an image side of at least 16 px, got {frame!r}")
            side, focal = int(frame), REFERENCE_FOCAL_PX * int(frame) / 2048.0
        elif hasattr(frame, "width") and hasattr(frame, "height") and hasattr(frame, "fx"):
            side, focal = int(max(frame.width, frame.height)), float(frame.fx)
        else:
            raise ValueError(f"frame must be a CameraModel or an image side in pixels, got {frame!r}")
        if side == self.reference_side_px and math.isclose(focal, self.reference_focal_px, rel_tol=1e-12):
            return self
        # made once per frame size: a copy validates every field again (1.2 ms, on every frame
        # of a camera other than the reference one)
        scaled = self.__dict__.setdefault("_scaled_copies", {})
        if (side, focal) not in scaled:
            scaled[(side, focal)] = self._scaled_copy(side, focal)
        return scaled[(side, focal)]

    def _scaled_copy(self, side: int, focal: float) -> "DetectorParams":
        k_size = side / float(self.reference_side_px)
        k_focal = focal / self.reference_focal_px
        changes = {"reference_side_px": side, "reference_focal_px": focal}
        for name, floor in SCALES_WITH_SIZE.items():
            if floor is not None:
                changes[name] = max(floor, getattr(self, name) * k_size)
        changes["acquisition_max_side_px"] = int(max(min(512, side), round(self.acquisition_max_side_px * k_size)))
        changes["tracking_max_side_px"] = int(max(min(256, side), round(self.tracking_max_side_px * k_size)))
        for name, floor in SCALES_WITH_FOCAL.items():
            changes[name] = max(floor, getattr(self, name) * k_focal)
        return replace(self, **changes)
