"""DetectorParams: the one frozen parameter set of the detection stage (JSON/TOML round trip).

Every number the detector uses lives here, with its unit in its name. Lengths in pixels are
for a frame ``reference_side_px`` wide (2048 by default, the SPEC camera); the detector
rescales them to the frame it is given (:meth:`DetectorParams.scaled_to`), so one parameter
file serves every image size. Lengths marked "working-image pixels" are in the downsampled
image the Hough transform sees and do not scale.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from visland.params import ParamsFile

__all__ = ["DetectorParams"]


@dataclass(frozen=True)
class DetectorParams(ParamsFile):
    """Parameters of :func:`visland.detection.detect_runway`.

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
    max_edge_slope : float
        Largest ``|ds/dd|`` of a runway line in horizon coordinates (s along the horizon, d
        below it): 4 is 76 deg from the horizon's normal. Flatter lines (the horizon, roads
        across the view, the threshold bar) are not edge candidates.
    vp_tolerance_px : float
        Two edges belong to one runway when their crossings of the horizon agree to this many
        pixels plus their extrapolation uncertainty.
    min_length_to_width : float
        Smallest length-to-width ratio of a runway (a long strip; ICAO runways are 20 to 80
        times longer than wide): pairs of lines bounding a shorter strip are not runways.
    min_edge_length_px : float
        Shortest runway edge accepted (full-resolution pixels along the line).
    search_halfwidth_px : float
        Half width of the band searched across a predicted line during refinement.
    refine_samples : int
        Most profiles sampled along one line during refinement.
    refine_iterations : int
        Re-sampling passes of the refinement (each narrows the band).
    min_edge_support : float
        Smallest fraction of a line's profiles that must hold an inlying edge.
    max_line_residual_px : float
        Largest RMS distance of the inlying edge points to a refined line.
    min_contrast : float
        Smallest grey-level step accepted as an edge or stripe.
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
    max_width_change : float
        In tracking, the runway's apparent width (its width over the camera height) may differ
        from the previous frame's by this fraction at most (a parallel taxiway is half as wide).
    tracking_sigma_px : float
        How far (one sigma, pixels) the runway may move from its prediction between frames
        before a candidate loses the preference the prediction gives it.
    min_confidence : float
        Detections below this confidence are reported as not found.
    horizon_margin_px : float
        The horizon from roll and pitch must cross the image enlarged by this margin.
    hold_s : float
        Over a sequence (:class:`visland.detection.DetectionSequence`): how long the last good
        detection keeps predicting the runway after frames where it was not found, before the
        next search starts from nothing (a lost runway is then acquired on the whole frame).
    max_edge_turn_rad, max_edge_turn_rate_rps : float
        Over a sequence: a detection that did not come from tracking (a re-acquisition) is
        refused when an edge's direction in the image differs from the last good detection's by
        more than ``max_edge_turn_rad + max_edge_turn_rate_rps * dt`` (a field boundary or a
        taxiway picked after a short loss).
    max_vp_jump_px, max_vp_jump_rate_pxps : float
        Over a sequence: the same for the vanishing point's move along the horizon (d_F), in
        pixels of the reference image side.
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
        withheld.
    reference_rate_hz : float
        Frame rate the per-frame limits above are given for.
    reference_side_px : int
        Image width the pixel lengths above are given for.
    """

    params_kind: ClassVar[str] = "detector"
    toml_table: ClassVar[str | None] = "detector"


    acquisition_max_side_px: int = 1024
    tracking_max_side_px: int = 640
    blur_sigma_px: float = 1.0
    canny_low_quantile: float = 0.70
    canny_high_quantile: float = 0.85
    canny_min_high: float = 10.0
    hough_votes: int = 18
    hough_min_length_px: float = 14.0
    hough_max_gap_px: float = 3.0
    hough_angle_step_deg: float = 1.0
    max_candidates: int = 150
    max_edge_slope: float = 4.0
    vp_tolerance_px: float = 8.0
    min_length_to_width: float = 8.0
    min_edge_length_px: float = 24.0
    search_halfwidth_px: float = 6.0
    refine_samples: int = 96
    refine_iterations: int = 3
    min_edge_support: float = 0.45
    max_line_residual_px: float = 1.5
    min_contrast: float = 6.0
    roi_margin_px: float = 40.0
    roi_margin_fraction: float = 0.15
    threshold_search_fraction: float = 0.35
    horizon_sigma_px: float = 4.0
    tracking_sigma_px: float = 12.0
    max_width_change: float = 0.25
    min_confidence: float = 0.25
    horizon_margin_px: float = 0.0
    hold_s: float = 1.0
    max_edge_turn_rad: float = 0.05
    max_edge_turn_rate_rps: float = 0.3
    max_vp_jump_px: float = 60.0
    max_vp_jump_rate_pxps: float = 250.0
    max_threshold_jump_px: float = 6.0
    max_threshold_jump_fraction: float = 0.12
    threshold_track_s: float = 2.0
    threshold_width_tolerance_px: float = 2.0
    threshold_width_tolerance_fraction: float = 0.04
    reference_rate_hz: float = 25.0
    reference_side_px: int = 2048

    def __post_init__(self):
        def number(name, low, high, integer=False, open_low=False):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ValueError(f"DetectorParams.{name} must be a number, got {value!r}")
            if integer and int(value) != value:
                raise ValueError(f"DetectorParams.{name} must be an integer, got {value!r}")
            if not math.isfinite(value) or value < low or value > high or (open_low and value == low):
                bracket = "(" if open_low else "["
                raise ValueError(f"DetectorParams.{name} must lie in {bracket}{low:g}, {high:g}], got {value!r}")
            if integer:
                object.__setattr__(self, name, int(value))

        number("acquisition_max_side_px", 128, 8192, integer=True)
        number("tracking_max_side_px", 64, 8192, integer=True)
        number("blur_sigma_px", 0.0, 5.0)
        number("canny_low_quantile", 0.0, 1.0, open_low=True)
        number("canny_high_quantile", 0.0, 1.0, open_low=True)
        if self.canny_low_quantile >= self.canny_high_quantile:
            raise ValueError("DetectorParams.canny_low_quantile must be smaller than canny_high_quantile")
        number("canny_min_high", 0.0, 2000.0)
        number("hough_votes", 2, 10000, integer=True)
        number("hough_min_length_px", 2.0, 10000.0)
        number("hough_max_gap_px", 0.0, 100.0)
        number("hough_angle_step_deg", 0.01, 5.0)
        number("max_candidates", 4, 10000, integer=True)
        number("max_edge_slope", 0.1, 100.0)
        number("vp_tolerance_px", 0.1, 1000.0)
        number("min_length_to_width", 0.0, 1000.0)
        number("min_edge_length_px", 4.0, 10000.0)
        number("search_halfwidth_px", 1.5, 200.0)
        number("refine_samples", 8, 100000, integer=True)
        number("refine_iterations", 1, 20, integer=True)
        number("min_edge_support", 0.0, 1.0, open_low=True)
        number("max_line_residual_px", 0.01, 100.0)
        number("min_contrast", 0.0, 255.0)
        number("roi_margin_px", 0.0, 4096.0)
        number("roi_margin_fraction", 0.0, 10.0)
        number("threshold_search_fraction", 0.01, 1.0)
        number("horizon_sigma_px", 0.01, 10000.0)
        number("tracking_sigma_px", 0.1, 10000.0)
        number("max_width_change", 0.01, 10.0)
        number("hold_s", 0.0, 60.0)
        number("max_edge_turn_rad", 0.0, 3.2)
        number("max_edge_turn_rate_rps", 0.0, 100.0)
        number("max_vp_jump_px", 0.0, 100000.0)
        number("max_vp_jump_rate_pxps", 0.0, 1e6)
        number("max_threshold_jump_px", 0.0, 100000.0)
        number("max_threshold_jump_fraction", 0.0, 100.0)
        number("threshold_track_s", 0.1, 60.0)
        number("threshold_width_tolerance_px", 0.0, 1000.0)
        number("threshold_width_tolerance_fraction", 0.0, 10.0)
        number("reference_rate_hz", 0.1, 10000.0)
        number("min_confidence", 0.0, 1.0)
        number("horizon_margin_px", 0.0, 100000.0)
        number("reference_side_px", 16, 100000, integer=True)

    # ----------------------------------------------------------------- variants
    def scaled_to(self, image_side_px: int) -> "DetectorParams":
        """The same detector for frames ``image_side_px`` wide: lengths in pixels scale, counts,
        ratios and grey levels do not. Idempotent (the result's reference is that width)."""
        if isinstance(image_side_px, bool) or not isinstance(image_side_px, (int, np.integer)) or image_side_px < 16:
            raise ValueError(f"image_side_px must be an integer of at least 16, got {image_side_px!r}")
        image_side_px = int(image_side_px)
        if image_side_px == self.reference_side_px:
            return self
        k = image_side_px / float(self.reference_side_px)
        return replace(
            self,
            reference_side_px=image_side_px,
            acquisition_max_side_px=int(max(min(512, image_side_px), round(self.acquisition_max_side_px * k))),
            tracking_max_side_px=int(max(min(256, image_side_px), round(self.tracking_max_side_px * k))),
            min_edge_length_px=max(4.0, self.min_edge_length_px * k),
            search_halfwidth_px=max(2.5, self.search_halfwidth_px * k),
            roi_margin_px=self.roi_margin_px * k,
            vp_tolerance_px=max(0.5, self.vp_tolerance_px * k),
            horizon_sigma_px=max(0.05, self.horizon_sigma_px * k),
            tracking_sigma_px=max(1.0, self.tracking_sigma_px * k),
            horizon_margin_px=self.horizon_margin_px * k,
            max_vp_jump_px=self.max_vp_jump_px * k,
            max_vp_jump_rate_pxps=self.max_vp_jump_rate_pxps * k,
            max_threshold_jump_px=self.max_threshold_jump_px * k,
            threshold_width_tolerance_px=self.threshold_width_tolerance_px * k)

    # ----------------------------------------------------------------- files