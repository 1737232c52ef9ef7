"""detect_runway: one frame in, a :class:`~visland.detection.result.DetectionResult` out.

Pipeline (issue 4; thesis 5.3.2.2):

1. the horizon from the inertial roll and pitch and the camera mounting;
2. tracking, when ``previous`` found the runway: the previous edges carried into this frame by
   the camera's rotation are refined directly against the gradient; if they do not hold,
   Canny + Hough candidates in the region of interest around them; if that fails too, or
   with no previous runway, acquisition: candidates on the whole ground part of the frame;
3. vanishing-point candidates from the candidate lines, the frame resampled on the lines
   through each, and the trapezoid/symmetry model choosing the left and right edges;
4. where the runway's surface starts and ends, sub-pixel refinement of each edge (past the
   painted side stripes to the runway's boundary), the centre line midway between them;
5. the vanishing point fused from the lines and the horizon, d_F and the heading deviation
   (seed 001 eq. 18-19, through :mod:`visland.features`);
6. the threshold and the runway end through the perpendicular vanishing point, the corners.

Bad input never raises: a frame of the wrong size or type, a black, white or noise-only
frame, a non-finite attitude or one that puts the horizon outside the image give a result
with ``found = False`` and the reason.
"""
from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, replace

import cv2
import numpy as np

from visland.camera import CameraModel
from visland.detection.candidates import banded_hough_segments, candidate_lines, check_lines, hough_segments
from visland.detection.horizon import HorizonFrame, horizon_frame, widths_along
from visland.detection.params import DetectorParams
from visland.detection.pencil import FloatFrame, row_nanmedian
from visland.detection.refine import (LineFit, NoFit, PixelLine, chroma_boundary, chroma_of,
                                     net_step, parabola_peak, refine_line, sample_profiles)
from visland.detection.result import DetectionResult, not_found
from visland.detection.threshold_marking import (ground_begins, marked_at_start, paint_before,
                                                 starts_on_its_stripes, threshold_marking)
from visland.detection.transverse import (TransverseLine, find_transverse_line, pavement_beyond_edges,
                                          pavement_runs_on, surface_extent)
from visland.detection.trapezoid import (Prediction, RunwayHypothesis, is_convincing_strip, runway_hypotheses,
                                         wider_strip_beside)
from visland.features import batch_R_camera_from_runway, dF_from_vanishing_point, dpsi_from_dF
from visland.folder import as_grey, ignored_pixels, scene_frame
from visland.runway import CORNER_NAMES

__all__ = ["detect_runway", "check_frame", "block_grid_ratio", "block_grid_steps"]


def check_frame(image, camera: CameraModel) -> str | None:
    """Why ``image`` cannot be searched (None when it can): type, shape, size, contrast.

    Parameters
    ----------
    image : object
        The frame as given: a uint8 ndarray of shape (H, W) or (H, W, 3) is expected.
    camera : CameraModel
        The camera; the frame's size must be its ``(width, height)``.

    Returns
    -------
    str or None
        One sentence naming what is wrong (type, shape, dtype, size), or None.
    """
    if not isinstance(image, np.ndarray):
        return f"frame is a {type(image).__name__}, not an image array"
    if not (image.ndim == 2 or (image.ndim == 3 and image.shape[2] == 3)):
        return f"frame has shape {image.shape}; a grey-level (H, W) or RGB (H, W, 3) image is expected"
    if image.dtype != np.uint8:
        return f"frame has dtype {image.dtype}; uint8 levels are expected"
    height, width = image.shape[:2]
    if (width, height) != (camera.width, camera.height):
        return f"frame is {width}x{height} but the camera is {camera.width}x{camera.height}"
    return None


def detect_runway(image, camera: CameraModel, roll_rad: float, pitch_rad: float,
                  params: DetectorParams | None = None, previous: DetectionResult | None = None) -> DetectionResult:
    """Find the runway's edges, centre line, corners and d_F in one grey-level frame.

    Parameters
    ----------
    image : ndarray of uint8, shape (H, W) or (H, W, 3)
        The frame as the camera took it, grey levels or RGB; its size must be the camera's.
        With a lens distortion in ``camera`` it is resampled to the pinhole image first, and
        the aircraft's structure (``camera.mask``) is filled from the scene around it
        (:func:`visland.folder.scene_frame`); every feature is in pinhole pixels, and a corner
        that falls on the structure is withheld. Everything runs on grey
        levels; colour adds the chroma profile that places the threshold and the runway end
        where grass meets grey pavement (:mod:`visland.detection.transverse`).
    camera : CameraModel
        Intrinsics and mounting (pixels: (0, 0) at the centre of the top-left pixel).
    roll_rad, pitch_rad : float
        Inertial attitude at the frame's time; with the mounting they fix the horizon.
    params : DetectorParams, optional
        Pixel lengths are for a 2048 px wide frame and rescaled to this one.
    previous : DetectionResult, optional
        The last detection. When it was found, the search runs in a region of interest
        predicted from it (tracking mode); otherwise the whole ground part of the frame is
        searched (acquisition).

    Returns
    -------
    DetectionResult
        ``found``, ``reason``, ``confidence``, corners (4, 2) in
        :data:`visland.runway.CORNER_NAMES` order, lines ``(rho, theta)`` in the SPEC chart,
        ``dF_px`` and ``dpsi_rad``. Never raises on bad image or attitude input.
    """
    start = time.perf_counter()
    if not isinstance(camera, CameraModel):
        raise ValueError(f"camera must be a visland.camera.CameraModel, got {type(camera).__name__}")
    params = params or _default_params()
    if not isinstance(params, DetectorParams):
        raise ValueError(f"params must be a DetectorParams, got {type(params).__name__}")
    params = params.scaled_to(camera)
    if previous is not None and not isinstance(previous, DetectionResult):
        raise ValueError(f"previous must be a DetectionResult or None, got {type(previous).__name__}")

    problem = check_frame(image, camera)
    if problem:
        return not_found(problem, roll_rad=_as_float(roll_rad), pitch_rad=_as_float(pitch_rad),
                         image_size=(camera.width, camera.height), elapsed_s=time.perf_counter() - start)
    # features are measured in the pinhole image (SPEC): a frame through a distorting lens is
    # resampled first; the aircraft's structure never reaches the search
    return detect_in_scene_frame(scene_frame(image, camera), camera, roll_rad, pitch_rad, params, previous, start)


@functools.cache
def _default_params() -> DetectorParams:
    """``DetectorParams()``, made once (frozen; each construction validates every field: 1.2 ms)."""
    return DetectorParams()


def detect_in_scene_frame(image, camera: CameraModel, roll_rad: float, pitch_rad: float, params: DetectorParams,
                          previous: DetectionResult | None = None, start: float | None = None) -> DetectionResult:
    """:func:`detect_runway` on a frame already checked (:func:`check_frame`) and turned into its
    scene frame (:func:`visland.folder.scene_frame`), with ``params`` already scaled to ``camera``:
    for a caller that needs that frame itself (the horizon read off it) and must not prepare it
    twice.

    Parameters
    ----------
    image : ndarray of uint8, shape (H, W) or (H, W, 3)
        The scene frame (pinhole pixels), grey or RGB.
    camera : CameraModel
        The camera.
    roll_rad, pitch_rad : float
        Inertial attitude at the frame's time, radians.
    params : DetectorParams
        Already scaled to ``camera`` (:meth:`DetectorParams.scaled_to`).
    previous : DetectionResult, optional
        The last detection (tracking when found).
    start : float, optional
        ``time.perf_counter()`` when the frame's work began (default now).

    Returns
    -------
    DetectionResult
    """
    start = time.perf_counter() if start is None else start

    def fail(reason: str) -> DetectionResult:
        return not_found(reason, roll_rad=_as_float(roll_rad), pitch_rad=_as_float(pitch_rad),
                         image_size=(camera.width, camera.height), elapsed_s=time.perf_counter() - start)

    roll, pitch = _as_float(roll_rad), _as_float(pitch_rad)
    if not (math.isfinite(roll) and math.isfinite(pitch)):
        return fail(f"attitude is not finite (roll {roll_rad!r}, pitch {pitch_rad!r})")
    horizon = horizon_frame(camera, roll, pitch)
    if horizon is None:
        return fail(f"horizon is parallel to the image columns (roll {math.degrees(roll):.1f} deg)")
    if not horizon.crosses_image(camera.width, camera.height, params.horizon_margin_px):
        return fail(f"horizon from roll {math.degrees(roll):.1f} deg, pitch {math.degrees(pitch):.1f} deg "
                    "lies outside the image")
    ground = horizon.ground_bbox(camera.width, camera.height, margin_px=params.ground_margin_px)
    if ground is None:
        return fail("no ground below the horizon in the image")
    colour = None
    if image.ndim == 3:
        colour, image = image, _grey_below_horizon(image, horizon, params.ground_margin_px + SKY_ROWS_READ_PX)
    u0, v0, u1, v1 = ground
    step = params.contrast_sample_step
    sample = image[v0:v1:step, u0:u1:step]
    spread = _percentile_spread(sample, *params.contrast_percentiles) if sample.size else 0.0
    if spread < params.min_contrast:
        return fail(f"frame has no contrast below the horizon (grey levels within {spread:.0f})")
    across, elsewhere = block_grid_steps(image, ground, params.block_grid_px, params.block_sample_rows)
    coarsely_compressed = elsewhere > 0 and across / elsewhere >= params.block_grid_min_ratio
    if coarsely_compressed:
        # a coarsely compressed frame: its edges are staircases of blocks (edge points off by up
        # to half a block, a straight line's residuals a saw-tooth of 1-2 px RMS), not taken for a
        # bent line; where the grid steps strongly (a noisy sensor's coarse JPEG) it is also
        # smoothed, which averages the staircase out (a faint grid is not: smoothing then costs
        # a small runway its contrast)
        params = params.for_block_grid()
        if params.deblock_sigma_px > 0 and across - elsewhere >= params.deblock_min_grid_step:
            image, colour = _blurred(image, colour, params.deblock_sigma_px)

    context = _Context(image, camera, horizon, params, roll, pitch, start, colour)
    try:
        result, why = _search_frame(context, previous, ground)
        second_looks = params.denoise_sigma_px > 0 or params.low_contrast_factor < 1.0
        noise = pixel_noise(image, ground, params.block_sample_rows) \
            if result is None and not coarsely_compressed and second_looks else math.nan
        if noise >= params.denoise_min_noise and params.denoise_sigma_px > 0:
            # a noisy sensor's frame: the detector's contrast and support thresholds hold for a
            # pixel noise of 1-2 grey levels; smoothed, a noise of 3.5 falls to about that. Only
            # a second look: the smoothing blurs a side stripe into the edge beside it (edges
            # 0.2-0.5 px off where the frame as it came gives 0.05), so what is found without it
            # is measured without it
            smooth_image, smooth_colour = _blurred(image, colour, params.denoise_sigma_px)
            smoothed = f"smoothed against its pixel noise of {noise:.1f} grey levels"
            smooth = _Context(smooth_image, camera, horizon, params, roll, pitch, start, smooth_colour)
            result, why = _look_again(smooth, previous, ground, why, smoothed, f"found on the frame {smoothed}")
        elif noise <= params.low_contrast_max_noise and params.low_contrast_factor < 1.0:
            # a clean frame of low contrast (haze, overcast, dusk): a runway's edges a few grey
            # levels, under min_contrast but many times the noise. Only a second look: on a clear
            # frame the grey-level thresholds keep the ground's texture out
            faint = params.for_low_contrast()
            faintly = "with the contrast thresholds of a low-contrast frame"
            result, why = _look_again(_Context(image, camera, horizon, faint, roll, pitch, start, colour),
                                      previous, ground, why, faintly,
                                      f"found {faintly} (pixel noise {noise:.1f} grey levels, edges of "
                                      f"{faint.min_contrast:g} grey levels accepted)", needs_marking=True)
    except (ArithmeticError, np.linalg.LinAlgError, cv2.error) as error:
        # a degenerate configuration the geometry cannot handle (e.g. lines meeting at
        # infinity) is a frame without a detection, never an exception for the caller
        return fail(f"detector failed on this frame ({type(error).__name__}: {error})")
    if result is None:
        return fail(why)
    return _withhold_hidden_corners(result, camera)


def _look_again(context: "_Context", previous: DetectionResult | None, ground, why: str, how: str, note: str,
                needs_marking: bool = False) -> tuple[DetectionResult | None, str]:
    """A second search of a frame the first did not find the runway in, on ``context`` (the
    frame smoothed, or lower thresholds): ``(result, why)``, the result saying ``note``, or None
    and ``why`` followed by what the second look met (``how``: the way it looked).

    ``needs_marking``: a strip found without its threshold marking is not the runway (in haze a
    parallel taxiway or road is as faint as the runway, and as straight: the ray-cast airport at
    2.5-3 km in a haze of 1.5 km, the taxiway's edges found 72-88 px off, unmarked).
    """
    result, why_again = _search_frame(context, previous, ground)
    if result is not None and needs_marking and not result.shows_runway_marking:
        result, why_again = None, "a strip found without a threshold marking, which a faint runway needs"
    if result is None:
        return None, f"{why} ({how}: {why_again})"
    return result.with_note(note), why


#: How far above the ground's margin (``params.ground_margin_px`` above the horizon) the grey
#: levels of a colour frame are read: no step of the search reaches further up (the sky is
#: never searched), so the rows above are not converted (zeros); a 2048 px frame's conversion
#: costs half as much with the horizon near its middle.
SKY_ROWS_READ_PX = 16.0


def _grey_below_horizon(colour: np.ndarray, horizon: HorizonFrame, margin_px: float) -> np.ndarray:
    """The grey levels of an RGB frame (:func:`visland.folder.as_grey`, the same levels) on the rows
    that hold a part of it less than ``margin_px`` above the horizon; 0 on the rows above."""
    height, width = colour.shape[:2]
    box = horizon.ground_bbox(width, height, margin_px=margin_px)
    top = box[1] if box is not None else height
    if top <= 0:
        return as_grey(colour)
    grey = np.empty((height, width), np.uint8)
    grey[:top] = 0
    if top < height:
        cv2.cvtColor(np.ascontiguousarray(colour[top:]), cv2.COLOR_RGB2GRAY, dst=grey[top:])
    return grey


def _sample_rows(ground, rows: int) -> np.ndarray:
    """``rows`` row indices spread evenly over the ground box, one pixel inside it."""
    u0, v0, u1, v1 = (int(a) for a in ground)
    return np.unique(np.linspace(v0 + 1, v1 - 2, max(1, int(rows))).round().astype(int))


def _blurred(image: np.ndarray, colour: np.ndarray | None, sigma_px: float):
    """``(image, colour)`` each smoothed by a Gaussian of ``sigma_px`` (a missing colour frame stays None)."""
    return (cv2.GaussianBlur(image, (0, 0), sigma_px),
            None if colour is None else cv2.GaussianBlur(colour, (0, 0), sigma_px))


def pixel_noise(image: np.ndarray, ground, rows: int = 32) -> float:
    """The frame's pixel noise (standard deviation, grey levels) on ``rows`` rows of the ground box.

    Immerkaer's estimator (*Fast noise variance estimation*, CVIU 1996) made robust: the mask
    ``[[1, -2, 1], [-2, 4, -2], [1, -2, 1]]`` cancels every grey level that is locally a plane
    or a straight edge's ramp, and turns white noise of deviation ``sigma`` into noise of
    deviation ``6 sigma`` (the root of the sum of its squared taps); the median of its absolute
    response over the ground is ``0.6745 * 6 * sigma`` and hardly sees the texture and edges
    the ground holds. Measured: visland's clean frames and H.264 recordings 0.7-1.2, the ray-cast
    airport of the tests (grey noise 2, blur 0.5 px) 2.0, the robustness study's 'variety 1'
    (colour noise 5.2 per channel) 3.5-3.7 grey levels. NaN when the box is under 3 px wide or
    5 px tall.
    """
    u0, v0, u1, v1 = (int(a) for a in ground)
    if u1 - u0 < 3 or v1 - v0 < 5:
        return math.nan
    centre = _sample_rows((u0, v0 + 1, u1, v1 - 1), rows)
    band = image[np.stack([centre - 1, centre, centre + 1]), u0:u1].astype(np.int32)   # (3, rows, width)
    # the mask is the outer product of [1, -2, 1] with itself: across the three rows, then along them
    across = band[0] - 2 * band[1] + band[2]
    response = np.abs(across[:, :-2] - 2 * across[:, 1:-1] + across[:, 2:])
    return float(np.median(response)) / (0.6745 * 6.0)


def block_grid_ratio(image: np.ndarray, ground, block_px: int = 8, rows: int = 32) -> float:
    """How much a grey frame steps across a compression block grid: the mean absolute step
    between neighbouring columns across the grid's lines (``u + 1`` a multiple of ``block_px``)
    over the mean step elsewhere, on ``rows`` rows of the ground box.

    About 1 for a frame that was not block-compressed (or only lightly); about 3 for a JPEG of
    quality 40-50, whose 8 x 8 blocks each keep a few coefficients: the grid is then visible,
    and straight edges become staircases of blocks (edge points up to half a block off).

    Parameters
    ----------
    image, ground, block_px, rows
        As :func:`block_grid_steps`.

    Returns
    -------
    float
        The ratio; NaN when the box holds fewer than two blocks across or is flat.
    """
    across, inside = block_grid_steps(image, ground, block_px, rows)
    return across / inside if inside > 0 else math.nan


def block_grid_steps(image: np.ndarray, ground, block_px: int = 8, rows: int = 32) -> tuple[float, float]:
    """``(across, elsewhere)``: the mean absolute grey-level step between neighbouring columns
    across the block grid's lines and elsewhere (:func:`block_grid_ratio`'s two terms; NaN when
    the box holds fewer than two blocks across). Their difference is the grid's own step in grey
    levels: 3.0-3.3 on a noisy sensor's JPEG of quality 40 (the ray-cast airport of
    tests/detection/test_detection_noise.py), 2.24-2.43 on the robustness study's JPEG 50 with
    noise and blur, 1.2-2.0 on visland's clean 512 px frames through OpenCV's MJPG writer,
    0.8-1.5 on clean JPEGs of quality 75-40.

    Parameters
    ----------
    image : ndarray (H, W) uint8
        The grey frame.
    ground : tuple of 4 int
        ``(u0, v0, u1, v1)``: the ground's bounding box, end exclusive.
    block_px : int, optional
        The block's side (pixels), the grid aligned with pixel (0, 0).
    rows : int, optional
        Rows read, spread evenly over the box.

    Returns
    -------
    tuple of 2 float
        Grey levels per column step.
    """
    u0, v0, u1, v1 = (int(a) for a in ground)
    if u1 - u0 < 2 * block_px or v1 - v0 < 3:
        return math.nan, math.nan
    levels = image[_sample_rows(ground, rows), u0:u1].astype(np.int16)
    steps = np.abs(np.diff(levels, axis=1))
    # column j is the step from u0 + j to u0 + j + 1: across the grid where u0 + j + 1 is a
    # multiple of block_px; integer sums (exact), then the two means
    across = steps[:, (-u0 - 1) % block_px::block_px]
    total, across_sum = int(steps.sum(dtype=np.int64)), int(across.sum(dtype=np.int64))
    return across_sum / across.size, (total - across_sum) / (steps.size - across.size)


def _percentile_spread(levels: np.ndarray, q_low: float, q_high: float) -> float:
    """``np.percentile(levels, q_high) - np.percentile(levels, q_low)`` of uint8 grey levels, the
    same number (linear interpolation between order statistics) read off their histogram: a
    tenth of the time of sorting the quarter-million levels of a 2048 px frame's ground."""
    if levels.dtype != np.uint8:
        return float(np.percentile(levels, q_high) - np.percentile(levels, q_low))
    # (OpenCV's histogram of the sample: exact counts, as float32 below 2**24; faster than bincount)
    if levels.ndim == 2 and levels.size < 2 ** 24:
        counts = cv2.calcHist([levels], [0], None, [256], [0, 256]).ravel().astype(np.int64)
    else:
        counts = np.bincount(levels.ravel(), minlength=256)
    cumulative = np.cumsum(counts)
    n = int(cumulative[-1])

    def percentile(q):
        index = (n - 1) * (q / 100.0)
        lo = int(math.floor(index))
        t = index - lo
        # the order statistics lo and lo + 1: the first level whose cumulative count exceeds them
        a = float(np.searchsorted(cumulative, lo, side="right"))
        b = float(np.searchsorted(cumulative, min(lo + 1, n - 1), side="right"))
        return b - (b - a) * (1 - t) if t >= 0.5 else a + (b - a) * t     # numpy's lerp

    return percentile(q_high) - percentile(q_low)


def _withhold_hidden_corners(result: DetectionResult, camera: CameraModel) -> DetectionResult:
    """Corners that fall on the aircraft's structure (or outside the lens) are not seen: their
    position would be an extrapolation of edges behind the mask, so they are withheld."""
    ignored = ignored_pixels(camera)
    if ignored is None or not result.found:
        return result
    corners = np.asarray(result.corners_uv, float)
    found = np.asarray(result.corners_found, bool).copy()
    hidden = []
    for k in np.nonzero(found)[0]:
        u, v = (int(round(c)) for c in corners[k])
        if 0 <= v < ignored.shape[0] and 0 <= u < ignored.shape[1] and ignored[v, u]:
            found[k] = False
            hidden.append(CORNER_NAMES[k])
    if not hidden:
        return result
    corners[~found] = np.nan
    reason = "; ".join(r for r in (result.reason, f"{', '.join(hidden)} hidden by the aircraft's structure") if r)
    return replace(result, corners_uv=corners, corners_found=found, reason=reason)


def _search_frame(context: "_Context", previous: DetectionResult | None, ground):
    """Tracking from ``previous`` when it was found, else (or if that fails) acquisition."""
    params = context.params
    tracking_reason = None
    if previous is not None and previous.found:
        prediction, roi = _predict(previous, context, ground)
        if prediction is None:
            tracking_reason = "previous runway not in view after the attitude change"
        else:
            # first the predicted edges refined directly against the gradient (the runway moves
            # a few pixels per frame); then, if they do not hold, Hough candidates in the region
            # of interest; the whole frame only if both fail
            result, why = _measure(context, _hypothesis_of(prediction), "tracking", roi, prediction=prediction)
            if result is not None:
                return result, None
            result, why_roi = _search(context, roi, params.tracking_max_side_px, prediction, "tracking")
            if result is not None:
                return result, None
            tracking_reason = f"{why}; in the region of interest: {why_roi}"
    mode = "acquisition" if tracking_reason is None else "reacquisition"
    result, why = _search(context, ground, params.acquisition_max_side_px, None, mode)
    if result is not None:
        return result, None
    if tracking_reason is not None:
        why = f"{why} (tracking failed first: {tracking_reason})"
    return None, why


class _Context:
    """What every step of one frame's search shares."""

    def __init__(self, image, camera, horizon, params, roll, pitch, start, colour=None):
        self.image = image
        self.colour = colour
        self.camera = camera
        self.horizon = horizon
        self.params = params
        self.roll = roll
        self.pitch = pitch
        self.start = start
        horizon_rho, horizon_theta = horizon.rho, horizon.theta
        self.horizon_line = (horizon_rho, horizon_theta)
        self._chroma = None
        self._float_image = None

    @property
    def float_image(self) -> FloatFrame:
        """The grey frame read as float32 by the region (:class:`~visland.detection.pencil.FloatFrame`),
        for the reads of where the runway's surface ends (the same wedge twice a frame)."""
        if self._float_image is None:
            self._float_image = FloatFrame(self.image)
        return self._float_image

    @property
    def chroma(self):
        """The chroma once :meth:`ground_chroma` has found it usable, else None."""
        return self._chroma if self._chroma is not None and self._chroma is not False else None

    def ground_chroma(self, roi):
        """The colour frame's chroma (:func:`~visland.detection.refine.chroma_of`), or None for a
        grey-level frame or one whose ground in ``roi`` has no chroma to tell surfaces apart
        (a monochrome camera's frame as RGB, snow): its 1st-99th percentile spread is under
        ``params.min_contrast``."""
        if self.colour is None:
            return None
        if self._chroma is None:
            chroma = chroma_of(self.colour)
            u0, v0, u1, v1 = roi
            sample = chroma[v0:v1:4, u0:u1:4]
            spread = _percentile_spread(sample, 1.0, 99.0) if sample.size else 0.0
            self._chroma = chroma if spread >= self.params.min_contrast else False
        return self._chroma if self._chroma is not False else None


def _predict(previous: DetectionResult, ctx: _Context, ground):
    """The previous runway carried into this frame: prediction and region of interest.

    The camera's rotation between the two frames (roll and pitch from the inertial unit; the
    heading change is unknown and taken as zero) moves every image point by the homography
    ``H_now_from_before = K R_cam_from_runway_now R_cam_from_runway_before^T K^-1`` (pixels of
    the previous frame to pixels of this one); the translation over one frame is left to the
    search band.
    """
    camera, horizon, params = ctx.camera, ctx.horizon, ctx.params
    dpsi_rad = previous.dpsi_rad if math.isfinite(previous.dpsi_rad) else 0.0
    if not (math.isfinite(previous.roll_rad) and math.isfinite(previous.pitch_rad)):
        return None, None
    R_cam_from_runway_before = batch_R_camera_from_runway(np.asarray(previous.roll_rad),
                                                          np.asarray(previous.pitch_rad), np.asarray(dpsi_rad),
                                                          camera.mount_rpy_rad)
    R_cam_from_runway_now = batch_R_camera_from_runway(np.asarray(ctx.roll), np.asarray(ctx.pitch),
                                                       np.asarray(dpsi_rad), camera.mount_rpy_rad)
    K = camera.K
    H_now_from_before = K @ R_cam_from_runway_now @ R_cam_from_runway_before.T @ np.linalg.inv(K)

    def carry(uv):
        uv = np.asarray(uv, float).reshape(-1, 2)
        p = np.concatenate([uv, np.ones((len(uv), 1))], axis=1) @ H_now_from_before.T
        return p[:, :2] / p[:, 2:3]

    ends = {}
    for name in ("left", "right"):
        seg = np.asarray(previous.segments_uv.get(name, np.full((2, 2), np.nan)), float)
        if not np.all(np.isfinite(seg)):
            return None, None
        ends[name] = carry(seg)
    s0_left_edge, k_left_edge = horizon.pencil_from_points(ends["left"][0], ends["left"][1])
    s0_right_edge, k_right_edge = horizon.pencil_from_points(ends["right"][0], ends["right"][1])
    if not all(math.isfinite(float(x)) for x in (s0_left_edge, k_left_edge, s0_right_edge, k_right_edge)):
        return None, None
    s0 = 0.5 * (float(s0_left_edge) + float(s0_right_edge))
    ends_sd = horizon.to_sd(np.concatenate([ends["left"], ends["right"]]))
    d_far, d_near = float(ends_sd[:, 1].min()), float(ends_sd[:, 1].max())
    if d_near <= 1.0:
        return None, None
    mid = 0.5 * (d_far + d_near)
    k_left = float(k_left_edge) + (float(s0_left_edge) - s0) / mid
    k_right = float(k_right_edge) + (float(s0_right_edge) - s0) / mid
    points = [ends["left"], ends["right"]]
    corners = np.concatenate([np.asarray(previous.corners_uv, float)[np.asarray(previous.corners_found, bool)],
                              np.asarray(previous.doubtful_corners_uv, float).reshape(-1, 2)])
    if len(corners):
        points.append(carry(corners))
    points = np.concatenate(points)
    lo, hi = points.min(axis=0), points.max(axis=0)
    margin = params.roi_margin_px + params.roi_margin_fraction * float(max(hi - lo))
    roi = (max(ground[0], int(math.floor(lo[0] - margin))), max(ground[1], int(math.floor(lo[1] - margin))),
           min(ground[2], int(math.ceil(hi[0] + margin)) + 1), min(ground[3], int(math.ceil(hi[1] + margin)) + 1))
    if roi[2] - roi[0] < params.roi_min_side_px or roi[3] - roi[1] < params.roi_min_side_px:
        return None, None
    width_near = abs(k_right - k_left) * d_near
    sigma = params.tracking_sigma_px + params.tracking_sigma_width_fraction * width_near
    prediction = Prediction(s0=s0, k_left=k_left, k_right=k_right, d_far=d_far, d_near=d_near, sigma_px=sigma,
                            threshold_marked=bool(previous.threshold_marked))
    return prediction, roi


_WEAK = "runway candidate too weak"
#: Pixels added to a strip's width at its near end before its lateral offset is counted in
#: widths (:func:`_pair_edges`, ``max_lateral_widths``): the width's own uncertainty there.
LATERAL_WIDTH_SLACK_PX = 2.0


def _hypothesis_of(prediction: Prediction) -> RunwayHypothesis:
    return RunwayHypothesis(s0=prediction.s0, k_left=prediction.k_left, k_right=prediction.k_right,
                            d_far=prediction.d_far, d_near=prediction.d_near, polarity_left=0, polarity_right=0,
                            score=1.0, centre_polarity=0, centre_support=0.0, evidence={"predicted": True})


def _search(ctx: _Context, roi, max_side_px: int, prediction, mode: str):
    """Candidates in ``roi``, the trapezoid model, then measurement of the best hypotheses."""
    params, horizon = ctx.params, ctx.horizon
    # acquisition (no prediction) also searches the distant ground's rows on their own where
    # the parameters name bands of them (the low-contrast look's)
    segments = (hough_segments(ctx.image, roi, max_side_px, params) if prediction is not None
                else banded_hough_segments(ctx.image, roi, max_side_px, params))
    lines = check_lines(ctx.image, horizon, candidate_lines(segments, horizon, params), params)
    bottom_depth = _deepest_visible(horizon, ctx.camera.width, ctx.camera.height)
    hypotheses = runway_hypotheses(ctx.image, horizon, lines, params, prediction, bottom_depth_px=bottom_depth)
    # (the chroma is computed only when the grey levels' best is a convincing strip: the one case
    # where a wider strip in the chroma takes its place)
    chroma = (ctx.ground_chroma(roi) if prediction is None and hypotheses and ctx.colour is not None
              and is_convincing_strip(hypotheses[0], params) else None)
    if chroma is not None:
        hypotheses = _wider_strip_in_chroma(hypotheses, chroma, ctx, lines, bottom_depth)
    if not hypotheses:
        return None, (f"no pair of edges meeting on the horizon among {len(lines)} candidate lines "
                      f"({len(segments)} Hough segments)")
    reasons = []
    failed_strips = []
    for hypothesis in hypotheses[:3]:
        if any(wider_strip_beside(hypothesis, strip, params) for strip in failed_strips):
            # of parallel strips the runway is the widest: when it cannot be measured, a narrower
            # strip beside it (a parallel taxiway) is not taken in its place
            continue
        result, why = _measure(ctx, hypothesis, mode, roi)
        if result is not None:
            return result, None
        reasons.append(why)
        if why.startswith(_WEAK):
            # the best-ranked runway that holds together geometrically decides: a weaker-ranked
            # one (a taxiway beside it) is not taken in its place
            break
        if is_convincing_strip(hypothesis, params) and not why.startswith(("left edge", "right edge")):
            # (both its edges were measured: a strip, failing as one runway's pair of sides)
            failed_strips.append(hypothesis)
    return None, reasons[0]


def _wider_strip_in_chroma(hypotheses, chroma, ctx: _Context, lines, bottom_depth: float):
    """The grey-level ranking, with the best strip of the chroma put just ahead of the first
    convincing grey strip it is a wider paved strip beside
    (:func:`~visland.detection.trapezoid.wider_strip_beside`): the grey levels' best, or one
    ranked after hypotheses that are no paved strip along it (a bright building).

    Pavement is grey: a runway whose grey level is the ground's (concrete on dry grass) is still
    a strip of low chroma, when a darker taxiway beside it is the only strip in grey levels. Of
    parallel paved strips the runway is the widest; the narrower ones beside it are then not
    tried in its place (if it cannot be measured, the frame is not found). The chroma strip has
    no centre-line polarity (it is searched both ways in grey levels) and is measured on the
    chroma where the grey levels cannot tell its surface from the ground (``evidence["channel"]``).
    """
    params = ctx.params
    best = hypotheses[0]
    in_chroma = runway_hypotheses(chroma, ctx.horizon, lines, params, None, bottom_depth_px=bottom_depth, inside=-1,
                                  vanishing_points=[best.s0])
    if not in_chroma:
        return hypotheses
    # the first convincing grey strip it is wider beside: the grey levels' best, or one ranked
    # after a strip that is no paved strip along it (a bright building beside the parallel
    # taxiway outscored both at 2500 m; the taxiway was then measured in the runway's place).
    # Every convincing chroma strip scoring at least ``parallel_score_ratio`` of the chroma's
    # best is tried, not only the first, and the one wider beside the best-ranked grey strip
    # goes (the chroma's ranking breaks ties): a wide low-chroma area around the parallel
    # taxiway (oblique, 1200x23 at 3 km) was ranked ahead of the concrete runway and was wider
    # beside the other taxiway only, and the first taxiway was measured
    top, narrower = None, None
    floor = params.parallel_score_ratio * max(h.score for h in in_chroma)
    for candidate in in_chroma:
        if candidate.score < floor or not is_convincing_strip(candidate, params):
            continue
        index = next((i for i, h in enumerate(hypotheses)
                      if is_convincing_strip(h, params) and wider_strip_beside(h, candidate, params)), None)
        if index is not None and (narrower is None or index < narrower):
            top, narrower = candidate, index
    if top is None:
        return hypotheses
    top = replace(top, centre_polarity=0, evidence={**top.evidence, "channel": "chroma"})
    return (hypotheses[:narrower] + [top]
            + [h for h in hypotheses[narrower:] if not wider_strip_beside(h, top, params)])


def _pencil_pixel_line(horizon: HorizonFrame, s0: float, k: float, d_ref: float) -> PixelLine:
    point = horizon.pencil_point(s0, k, d_ref)
    direction = (k * horizon.t_uv + horizon.n_uv) / math.sqrt(1 + k * k)
    return PixelLine(np.asarray(point, float), direction)


def _image_span(line: PixelLine, width: int, height: int, margin: float = 1.0) -> tuple[float, float]:
    """Positions along ``line`` between which it lies inside the image (slab clipping)."""
    lo, hi = -math.inf, math.inf
    for axis, size in ((0, width), (1, height)):
        p, e = line.point[axis], line.direction[axis]
        a, b = margin - 0.5, size - 0.5 - margin
        if abs(e) < 1e-12:
            if not a <= p <= b:
                return math.nan, math.nan
            continue
        t1, t2 = (a - p) / e, (b - p) / e
        lo, hi = max(lo, min(t1, t2)), min(hi, max(t1, t2))
    return (lo, hi) if hi > lo else (math.nan, math.nan)


def _refine_edge(ctx: _Context, s0, k, d_far, d_near, outward_s: int, width_slope: float,
                 halfwidth_px: float, band_fraction: float, iterations: int | None = None) -> LineFit | NoFit:
    """Sub-pixel edge along the pencil line (s0, k) between depths ``d_far`` and ``d_near``.

    ``outward_s`` is the side (in s) of the runway's outside; ``width_slope`` the runway's width
    per pixel of depth (``k_R - k_L``): a painted side stripe up to
    ``params.side_stripe_width_fraction`` of the local width plus the blur
    (``params.edge_blur_px``) is looked past to its outer boundary, which is the runway's edge.
    The band searched is ``band_fraction`` of the local width, between
    ``params.edge_band_min_px`` and ``halfwidth_px``.
    """
    horizon, params = ctx.horizon, ctx.params
    d_ref = 0.5 * (d_far + d_near)
    line = _pencil_pixel_line(horizon, s0, k, d_ref)
    scale = math.sqrt(1 + k * k)
    t_lo, t_hi = (max(1.0, d_far) - d_ref) * scale, (d_near - d_ref) * scale
    img_lo, img_hi = _image_span(line, ctx.camera.width, ctx.camera.height,
                                 params.search_halfwidth_px + params.edge_image_margin_px)
    t_lo, t_hi = max(t_lo, img_lo), min(t_hi, img_hi)
    if not (math.isfinite(t_lo) and math.isfinite(t_hi)) or t_hi - t_lo < params.min_edge_length_px:
        return NoFit(f"its candidate lies in the image over less than {params.min_edge_length_px:.0f} px")
    towards_s = (horizon.t_uv - k * horizon.n_uv) / scale      # unit normal towards +s
    sign = 1 if line.normal @ towards_s > 0 else -1

    def reach(t):
        depth = np.maximum(d_ref + np.asarray(t) / scale, 0.0)
        return params.side_stripe_width_fraction * abs(width_slope) * depth / scale + params.edge_blur_px

    def band(t):
        # never wider than a tenth of the runway's local width (a quarter when tracking a
        # prediction that may have moved), where markings inside it (aiming point, touchdown
        # zone) would become the strongest step
        depth = np.maximum(d_ref + np.asarray(t) / scale, 0.0)
        width = abs(width_slope) * depth / scale
        return np.clip(band_fraction * width, params.edge_band_min_px, halfwidth_px)

    def refine(image):
        return refine_line(image, line, (t_lo, t_hi), "edge", polarity=0, halfwidth_px=band,
                           outward=outward_s * sign, outward_reach_px=reach, params=params, iterations=iterations)

    fit = refine(ctx.image)
    if ctx.colour is None:
        return fit
    # grey pavement against coloured ground: the chroma steps at the edge even where the side
    # stripe, blended with the asphalt, has the grass's grey level (then the grey step is weak
    # or sits on the stripe's inner edge)
    if not fit or fit.extent[1] - fit.extent[0] < params.chroma_retry_extent_fraction * (t_hi - t_lo):
        on_chroma = refine(ctx.colour)
        if on_chroma and (not fit or on_chroma.extent[1] - on_chroma.extent[0] > fit.extent[1] - fit.extent[0]):
            return on_chroma
        if not fit:
            return NoFit(f"{fit.reason} (in chroma: {on_chroma.reason})" if not on_chroma else fit.reason)
    if fit:
        t_fit = np.array(fit.extent) + (fit.line.point - line.point) @ line.direction
        stripe_px = float(np.max(reach(t_fit))) - params.edge_blur_px
        # a side stripe this wide or more is resolved and the grey boundary is already exact
        if stripe_px < params.chroma_resolved_stripe_px:
            on_chroma = chroma_boundary(ctx.colour, fit, outward_s * sign, stripe_px + params.edge_blur_px, params)
            fit = on_chroma if on_chroma else replace(fit, note=f"placed on grey levels ({on_chroma.reason})")
    return fit


def _pencil_of(horizon: HorizonFrame, fit: LineFit) -> tuple[float, float, float]:
    """``(s0, k, sigma_s0)`` of a refined line: horizon crossing, slope and its uncertainty."""
    a = fit.line.point
    b = fit.line.point + 10.0 * fit.line.direction
    s0, k = horizon.pencil_from_points(a, b)
    s0, k = float(s0), float(k)
    crossing = horizon.vanishing_point_uv(s0) if math.isfinite(s0) else fit.line.point
    sigma = fit.sigma_at(crossing) * math.sqrt(1 + k * k) if math.isfinite(k) else math.inf
    return s0, k, sigma


def _segment_in_depth(horizon: HorizonFrame, fit: LineFit) -> np.ndarray:
    """End points (far, near) of a line's supported stretch, pixels (2, 2)."""
    ends = fit.line.point + np.outer(fit.extent, fit.line.direction)
    depth = horizon.to_sd(ends)[:, 1]
    return ends if depth[0] <= depth[1] else ends[::-1]


def _fuse_vanishing_point(horizon: HorizonFrame, fits, sigma_horizon_px: float, min_sigma_px: float) -> np.ndarray:
    """Least-squares vanishing point of the runway lines and the horizon (pixels).

    Minimises ``sum_i (n_i . p - c_i)^2 / sigma_i^2 + (n_h . p - c_h)^2 / sigma_h^2`` where each
    line's sigma is its fitted uncertainty extrapolated to the horizon: the lines fix the
    point along the horizon, the inertial horizon keeps it from sliding along lines that are
    nearly parallel (a far runway). Line sigmas are floored at ``min_sigma_px``.
    """
    A = np.zeros((2, 2))
    b = np.zeros(2)
    for fit in fits:
        h = fit.line.homogeneous()
        n, c = h[:2], -h[2]
        s0, k, _ = _pencil_of(horizon, fit)
        crossing = horizon.vanishing_point_uv(s0) if math.isfinite(s0) else fit.line.point
        w = 1.0 / max(fit.sigma_at(crossing), min_sigma_px) ** 2
        A += w * np.outer(n, n)
        b += w * c * n
    n_h = horizon.n_uv
    w_h = 1.0 / sigma_horizon_px ** 2
    A += w_h * np.outer(n_h, n_h)
    b += w_h * (n_h @ horizon.q_uv) * n_h
    return np.linalg.solve(A, b)


@dataclass(frozen=True)
class _EdgePair:
    """The two refined edges of one runway, in horizon coordinates (s along the horizon from Q,
    d below it, pixels; :mod:`visland.detection.horizon`).

    ``s0_*`` is where an edge meets the horizon, ``k_*`` its slope ``ds/dd`` and
    ``sigma_s0_*_px`` the one-sigma uncertainty of ``s0_*``; ``tolerance_px`` how far apart the
    two crossings may be; ``segment_*_uv`` the (far, near) pixel ends of each edge's supported
    stretch, and ``[d_far, d_near]`` the depths both edges are seen over.
    """

    fits: dict
    s0_left: float
    k_left: float
    sigma_s0_left_px: float
    s0_right: float
    k_right: float
    sigma_s0_right_px: float
    tolerance_px: float
    segment_left_uv: np.ndarray
    segment_right_uv: np.ndarray
    d_far: float
    d_near: float

    @property
    def d_mid(self) -> float:
        return 0.5 * (self.d_far + self.d_near)


@dataclass(frozen=True)
class _TransverseLines:
    """The threshold and runway-end lines of a measurement, their corners and what is missing."""

    corners_uv: np.ndarray
    corners_found: np.ndarray
    threshold_line: tuple
    end_line: tuple
    notes: list
    threshold_method: str = ""
    pavement_marking_widths: float = math.nan
    threshold_marked: bool = False


def _corners_withheld(transverse: _TransverseLines, note: str) -> _TransverseLines:
    """``transverse`` with every corner, the threshold and the runway end withheld, saying ``note``.

    A corner is where an edge meets a transverse line: on edges of low confidence it is off
    by as much as they are, and far more along the edge. In the robustness study at 2048 px
    (monochrome, snow and sand) the white side stripes merge with the ground below 600 m; the
    edges found are the stripes' inner sides, 2-5 px in, at confidence 0.25-0.37, and the near
    corners 5-9 px off. The edges' own confidence decides (:func:`_confidence`), not the
    frame's: a centre line not found far out (not resolved) says nothing about the corners (of
    the frames of the 1024 and 2048 px studies with a near corner and a confidence under 0.4,
    the 47 over 5 px off all have edges under 0.4; of the 142 under 2 px, 49 have edges over
    it, and so do 8 of the 13 of the ray-cast grey approach). The edges and the heading stay
    reported.
    """
    return replace(transverse, corners_uv=np.full((4, 2), np.nan), corners_found=np.zeros(4, bool),
                   threshold_line=(math.nan, math.nan), end_line=(math.nan, math.nan),
                   notes=list(transverse.notes) + [note], threshold_method="")


def _measure(ctx: _Context, hypothesis: RunwayHypothesis, mode: str, roi, prediction: Prediction | None = None):
    """Refine a hypothesis into a measurement, or say why it fails.

    Steps: each edge refined and validated (:func:`_refine_edges`), the two checked as one
    runway's sides (:func:`_pair_edges`), the centre line between them (:func:`_centre_line`),
    the vanishing point and the heading deviation (:func:`_heading`), the threshold and the
    runway end (:func:`_threshold_and_end`) and the confidence (:func:`_confidence`).

    With a ``prediction`` (tracking straight from the previous frame), the edges are searched
    in a band as wide as the prediction's uncertainty and must land within it.

    Returns ``(DetectionResult, None)`` or ``(None, reason)``.
    """
    camera = ctx.camera
    bottom_depth = _deepest_visible(ctx.horizon, camera.width, camera.height)
    fits, why = _refine_edges(ctx, hypothesis, prediction, bottom_depth)
    if fits is None:
        return None, why
    fits = _past_staircase_stripes(ctx, fits)
    pair, why = _pair_edges(ctx, fits, prediction)
    if pair is None:
        return None, why
    # (a tracked pair is the pair acquired, its width held to the prediction's by _pair_edges)
    why = _unbalanced_edges(ctx, pair) if prediction is None else ""
    if why:
        return None, why
    notes = [f"{name} edge {fit.note}" for name, fit in fits.items() if fit.note]
    centre_fit, centre_note = _centre_line(ctx, pair, hypothesis.centre_polarity)
    if centre_note:
        notes.append(centre_note)
    heading, why = _heading(ctx, pair, centre_fit)
    if heading is None:
        return None, why
    vp_uv, dF_px, dpsi_rad = heading
    confidence, edges_confidence, why = _confidence(ctx.params, pair, centre_fit)
    if confidence is None:
        return None, why
    transverse = _threshold_and_end(ctx, pair, vp_uv, bottom_depth, _extent_image(ctx, hypothesis),
                                    marked=prediction is not None and prediction.threshold_marked)
    doubtful = np.zeros((0, 2))
    if edges_confidence < ctx.params.corner_min_confidence and transverse.corners_found.any():
        doubtful = transverse.corners_uv[transverse.corners_found]
        note = (f"corners withheld: the edges they lie on have a confidence of {edges_confidence:.2f} "
                f"(< {ctx.params.corner_min_confidence:g})")
        transverse = _corners_withheld(transverse, note)
    notes.extend(transverse.notes)
    lines = {name: _line_chart(camera, fits[name].line.homogeneous()) for name in ("left", "right")}
    lines["center"] = (_line_chart(camera, centre_fit.line.homogeneous()) if centre_fit is not None
                       else (math.nan, math.nan))
    segments = {"left": pair.segment_left_uv, "right": pair.segment_right_uv,
                "center": (_segment_in_depth(ctx.horizon, centre_fit) if centre_fit is not None
                           else np.full((2, 2), np.nan))}
    fit_of = {"left": fits["left"], "right": fits["right"], "center": centre_fit}
    return DetectionResult(
        found=True, reason="; ".join(notes), confidence=float(confidence), corners_uv=transverse.corners_uv,
        corners_found=transverse.corners_found, lines=lines,
        line_residual_px={n: (f.residual_px if f is not None else math.nan) for n, f in fit_of.items()},
        line_support={n: (f.support if f is not None else 0.0) for n, f in fit_of.items()},
        segments_uv=segments, threshold_line=transverse.threshold_line, end_line=transverse.end_line,
        vanishing_point_uv=vp_uv, horizon=ctx.horizon_line, dF_px=dF_px, dpsi_rad=dpsi_rad, roll_rad=ctx.roll,
        pitch_rad=ctx.pitch, mode=mode, roi=tuple(int(a) for a in roi), image_size=(camera.width, camera.height),
        elapsed_s=time.perf_counter() - ctx.start, notes=tuple(notes), threshold_method=transverse.threshold_method,
        pavement_marking_widths=transverse.pavement_marking_widths, threshold_marked=transverse.threshold_marked,
        doubtful_corners_uv=doubtful), None


def _extent_image(ctx: _Context, hypothesis: RunwayHypothesis):
    """The image in which the strip of ``hypothesis`` ends: the chroma for a strip found in the
    chroma only (its grey level is the ground's, :func:`_wider_strip_in_chroma`), else the grey
    levels."""
    if hypothesis.evidence.get("channel") == "chroma" and ctx.chroma is not None:
        return ctx.chroma
    return ctx.image


def _refine_edges(ctx: _Context, hypothesis: RunwayHypothesis, prediction: Prediction | None,
                  bottom_depth: float) -> tuple[dict | None, str | None]:
    """The left and right edges of ``hypothesis`` refined on the frame, each long, supported and
    straight enough (and, tracking, near its prediction): ``({"left", "right"} -> LineFit, None)``
    or ``(None, reason)``."""
    horizon, params = ctx.horizon, ctx.params
    fits = {}
    width_slope = hypothesis.k_right - hypothesis.k_left
    halfwidth = params.search_halfwidth_px if prediction is None else max(params.search_halfwidth_px,
                                                                          prediction.sigma_px)
    extent_image = _extent_image(ctx, hypothesis)
    # where the strip's surface starts and ends, before fitting its edges there (beyond its
    # ends, texture lined up with an edge would turn the fit)
    extent = surface_extent(ctx.float_image if extent_image is ctx.image else extent_image, horizon, hypothesis.s0,
                            hypothesis.k_left, hypothesis.k_right,
                            (hypothesis.d_far, hypothesis.d_near), (1.0, bottom_depth), marking_fraction=0.0,
                            max_rows=params.edge_surface_rows, params=params)
    d_lo, d_hi = (hypothesis.d_far, hypothesis.d_near) if extent is None else extent
    inset = params.edge_depth_inset_fraction * (d_hi - d_lo)
    for name, k, outward in (("left", hypothesis.k_left, -1), ("right", hypothesis.k_right, 1)):
        fit = _refine_edge(ctx, hypothesis.s0, k, d_lo + inset, d_hi - inset, outward, width_slope, halfwidth,
                           band_fraction=(params.edge_band_fraction if prediction is None
                                          else params.tracking_edge_band_fraction),
                           iterations=None if prediction is None else params.tracking_refine_iterations)
        if not fit:
            return None, f"{name} edge: {fit.reason}"
        length = fit.extent[1] - fit.extent[0]
        if length < params.min_edge_length_px:
            return None, f"{name} edge: supported over {length:.0f} px only (< {params.min_edge_length_px:g})"
        if fit.support < params.min_edge_support:
            return None, f"{name} edge: only {100 * fit.support:.0f} % of its profiles hold the edge"
        if fit.residual_px > params.max_line_residual_px:
            return None, f"{name} edge: not straight (RMS residual {fit.residual_px:.2f} px)"
        if prediction is not None:
            depths = np.array([max(prediction.d_far, 1.0), prediction.d_near])
            s0_fit, k_fit, _ = _pencil_of(horizon, fit)
            k_pred = prediction.k_left if name == "left" else prediction.k_right
            moved = np.abs((s0_fit + k_fit * depths) - (prediction.s0 + k_pred * depths)).max()
            if not moved <= params.prediction_gate_sigmas * prediction.sigma_px:
                return None, f"{name} edge: {moved:.0f} px from its prediction"
        fits[name] = fit
    return fits, None


def _pair_edges(ctx: _Context, fits: dict, prediction: Prediction | None) -> tuple[_EdgePair | None, str | None]:
    """The two refined edges as one runway's sides: they meet on the horizon, are seen over a
    common stretch of depth, do not cross below the horizon and (tracking) are as far apart as
    predicted. ``(_EdgePair, None)`` or ``(None, reason)``."""
    horizon, params = ctx.horizon, ctx.params
    s0_left, k_left, sigma_s0_left_px = _pencil_of(horizon, fits["left"])
    s0_right, k_right, sigma_s0_right_px = _pencil_of(horizon, fits["right"])
    if not all(math.isfinite(x) for x in (s0_left, k_left, s0_right, k_right)):
        return None, "edges parallel to the horizon"
    tolerance = params.vp_tolerance_px + params.edge_crossing_sigmas * math.hypot(sigma_s0_left_px,
                                                                                   sigma_s0_right_px)
    if abs(s0_left - s0_right) > tolerance:
        return None, (f"edges meet the horizon {abs(s0_left - s0_right):.1f} px apart (tolerance {tolerance:.1f} px): "
                      "not the two sides of one runway")
    segment_left_uv, segment_right_uv = _segment_in_depth(horizon, fits["left"]), _segment_in_depth(horizon,
                                                                                                    fits["right"])
    d_far = max(horizon.to_sd(segment_left_uv)[0, 1], horizon.to_sd(segment_right_uv)[0, 1])
    d_near = min(horizon.to_sd(segment_left_uv)[1, 1], horizon.to_sd(segment_right_uv)[1, 1])
    # the two sides of one runway are seen over a common stretch of depth (a quarter of the
    # shorter one at least, params.pair_min_overlap_fraction); two lines supported over disjoint depths are two other objects
    span_left_px, span_right_px = (float(np.ptp(horizon.to_sd(segment)[:, 1]))
                                   for segment in (segment_left_uv, segment_right_uv))
    if d_near - d_far < max(params.min_edge_length_px,
                            params.pair_min_overlap_fraction * min(span_left_px, span_right_px)):
        return None, (f"the two edges overlap over {max(d_near - d_far, 0.0):.0f} px of depth only (their supports "
                      f"span {span_left_px:.0f} and {span_right_px:.0f} px): not the two sides of one runway")
    if not (s0_left + k_left * d_near < s0_right + k_right * d_near):
        return None, "the edges cross below the horizon"
    length_widths = widths_along(horizon.camera.fx, d_near, d_far, k_right - k_left) if d_far > 0 else math.inf
    if length_widths > params.max_length_to_width:
        # (a runway is at most about 130 widths long; the span seen can only be shorter)
        return None, (f"the strip is seen over {length_widths:.0f} of its own widths (more than "
                      f"{params.max_length_to_width:g}): a line (a painted stripe, a road), not a runway")
    # k = Y / h for a ground line Y beside the camera: the strip's centre line lies
    # k_C / (k_R - k_L) = Y / W of its own widths to the side of the aircraft; counted at the
    # near end with the width 2 px wider than measured (edges a pixel or two apart far out
    # measure the width no better: thesis-8's runway at 4.7 km, 512 px, read 0.1-1.1 px wide)
    lateral_widths = (abs(k_left + k_right) / 2.0 * d_near) / max((k_right - k_left) * d_near + LATERAL_WIDTH_SLACK_PX,
                                                                  1e-12)
    if lateral_widths > params.max_lateral_widths:
        return None, (f"the strip lies {lateral_widths:.0f} of its own widths to the side of the aircraft (more than "
                      f"{params.max_lateral_widths:g}): not a runway being approached (a road or taxiway beside it)")
    # k_C = Y / h itself: an approach descends along about 3 deg and keeps the aircraft within a
    # few degrees of the centre line, so the strip lies a few heights to the side at most;
    # unless the aircraft is over it or nearly (a lateral offset over a small height near the
    # ground), a strip farther out is not the runway being approached
    lateral_heights = abs(k_left + k_right) / 2.0
    if beside_the_approach(lateral_heights, lateral_widths, params):
        return None, (f"the strip lies {lateral_heights:.1f} camera heights to the side of the aircraft (more than "
                      f"{params.max_lateral_heights:g}) and {lateral_widths:.0f} of its own widths: not a runway being "
                      "approached (a taxiway, road or runway beside it)")
    if prediction is not None:
        # the runway's width over the camera height (k_R - k_L = W / h) changes by a few per
        # cent a second; a parallel taxiway or road is half as wide or less
        d_mid_check = 0.5 * (d_far + d_near)
        width_now = ((s0_right + k_right * d_mid_check) - (s0_left + k_left * d_mid_check)) / d_mid_check
        width_before = prediction.k_right - prediction.k_left
        if not abs(width_now / width_before - 1.0) <= params.max_width_change:
            return None, (f"the edges are {width_now / width_before:.2f} times as far apart as predicted: "
                          "not the runway tracked so far")
    return _EdgePair(fits=fits, s0_left=s0_left, k_left=k_left, sigma_s0_left_px=sigma_s0_left_px,
                     s0_right=s0_right, k_right=k_right, sigma_s0_right_px=sigma_s0_right_px, tolerance_px=tolerance,
                     segment_left_uv=segment_left_uv, segment_right_uv=segment_right_uv, d_far=d_far,
                     d_near=d_near), None


def beside_the_approach(lateral_heights: float, lateral_widths: float, params: DetectorParams) -> bool:
    """Whether a strip whose centre line lies ``lateral_heights`` camera heights (``|k_C| = |Y| / h``)
    and ``lateral_widths`` of its own widths (``|Y| / W``) to the side of the aircraft is no runway
    being approached: more than ``params.max_lateral_heights`` heights out while the aircraft is
    not over it or nearly (more than ``params.max_lateral_heights_widths`` widths)."""
    return lateral_heights > params.max_lateral_heights and lateral_widths > params.max_lateral_heights_widths


#: Profiles sampled across each edge by :func:`_unbalanced_edges`, and the stretch of the edge
#: they cover (fractions of its supported length: its ends are left out).
BALANCE_PROFILES = 24
BALANCE_SPAN = (0.1, 0.9)


def _across_edge(segment_uv: np.ndarray, other_uv: np.ndarray):
    """Where to sample across the edge ``segment_uv`` (far and near end points, pixels) of a
    runway whose other edge is ``other_uv``: ``(points, direction, outward, width)``, the
    :data:`BALANCE_PROFILES` points spread over :data:`BALANCE_SPAN` of the edge (n, 2), its unit
    direction, its unit normal pointing away from the other edge (out of the runway) and the
    runway's width at each point (the distance to the other edge's line, pixels). None when either
    segment is shorter than a pixel."""
    segment, other = np.asarray(segment_uv, float), np.asarray(other_uv, float)
    direction = segment[1] - segment[0]
    length = float(np.hypot(*direction))
    other_direction = other[1] - other[0]
    if length < 1.0 or float(np.hypot(*other_direction)) < 1.0:
        return None
    direction /= length
    other_normal = np.array([-other_direction[1], other_direction[0]]) / float(np.hypot(*other_direction))
    outward = np.array([-direction[1], direction[0]])
    if (other.mean(axis=0) - segment.mean(axis=0)) @ outward > 0:
        outward = -outward
    points = segment[0] + np.outer(np.linspace(*BALANCE_SPAN, BALANCE_PROFILES) * length, direction)
    width = np.abs((points - other[0]) @ other_normal)
    return points, direction, outward, width


def _staircase_ratios(image, segment_uv: np.ndarray, other_uv: np.ndarray, params: DetectorParams):
    """Where a second grey-level step of the edge's own sign lies beyond the edge ``segment_uv``,
    as a fraction of the runway's local width, at each of :data:`BALANCE_PROFILES` points:
    ``(ratios, width_px, points, outward, with_shoulders)``, NaN where a profile has none, the
    runway's width at
    each point, the points (n, 2) and the edge's outward unit normal (:func:`_across_edge`).
    None when the segments are too short to sample or the runway too narrow for the widest
    stripe looked for to be ``staircase_min_px`` wide.

    Each profile runs outwards from the edge (offset 0). The edge's own step is the strongest
    slope within ``edge_blur_px`` of it; the second step is the strongest local maximum of the
    slope of the same sign from 2 px out to ``side_stripe_width_fraction`` of the local width plus
    ``edge_blur_px``, at least ``staircase_step_ratio`` of the first, its place refined to a
    fraction of a sample by a parabola through its peak.
    """
    across = _across_edge(segment_uv, other_uv)
    if across is None:
        return None
    points, direction, outward, width = across
    if params.side_stripe_width_fraction * width.max() < params.staircase_min_px:
        return None                     # no stripe looked for could be wide enough to count
    reach = params.side_stripe_width_fraction * width + params.edge_blur_px
    step = 0.5
    profiles, offsets = sample_profiles(image, points, outward, direction, float(reach.max()) + 3.0, step_px=step)
    slope = np.zeros(profiles.shape)
    slope[:, 1:-1] = np.nan_to_num((profiles[:, 2:] - profiles[:, :-2]) / (2.0 * step))
    rows = np.arange(len(points))
    at_edge = np.abs(offsets) <= params.edge_blur_px
    edge_slopes = slope[:, at_edge]
    strongest = np.argmax(np.abs(edge_slopes), axis=1)
    sign = np.sign(edge_slopes[rows, strongest])
    edge_slope = np.abs(edge_slopes[rows, strongest])
    same = sign[:, None] * slope
    peak = np.zeros(same.shape, dtype=bool)
    peak[:, 1:-1] = (same[:, 1:-1] >= same[:, :-2]) & (same[:, 1:-1] > same[:, 2:])
    beyond = (offsets[None, :] >= 2.0) & (offsets[None, :] <= reach[:, None])
    candidate = np.where(peak & beyond & (same >= params.staircase_step_ratio * edge_slope[:, None])
                         & (edge_slope[:, None] > 0.0), same, -np.inf)
    j = np.argmax(candidate, axis=1)
    found = np.isfinite(candidate[rows, j])
    ratios = np.where(found, (offsets[j] + parabola_peak(same, j) * step) / width, np.nan)
    # (and the ratios with the shoulders read where the slope makes no peak)
    shoulder = _stripe_shoulder(sign[:, None] * profiles, same, offsets, np.flatnonzero(at_edge)[strongest],
                                edge_slope, reach, params)
    with_shoulders = np.where(~found & (shoulder >= 2.0) & (shoulder <= reach), shoulder / width, ratios)
    return ratios, width, points, outward, with_shoulders


def _stripe_shoulder(rising: np.ndarray, slope: np.ndarray, offsets: np.ndarray, edge_column: np.ndarray,
                     edge_slope: np.ndarray, reach: np.ndarray, params: DetectorParams) -> np.ndarray:
    """Where a side stripe blurred into the step onto it ends, in each profile (offset, pixels;
    NaN where the profile shows no such stripe): the second step of a staircase
    (:func:`_staircase_ratios`) that makes no peak of the slope of its own but a shoulder.

    ``rising`` are the profiles signed so that they rise outwards (the edge's own sign),
    sampled at ``offsets`` (0.5 px apart, 0 on the edge), ``slope`` their central difference
    per pixel (0 at the ends and where a profile leaves the frame); ``edge_column`` the column of each
    edge's strongest slope, ``edge_slope`` that slope; ``reach`` the widest stripe looked for
    plus the blur (pixels). The edge's own lobe ends where its slope falls below half its peak:
    a plain step has risen there to within 0.002-0.11 of the whole step of its outside level
    (area-sampled and blurred by 0.3 to 1.2 px, at four sub-pixel phases; were it counted, its
    midway crossing would lie 1-2 px out under blurs up to 0.9 px, where
    :func:`_staircase_ratios` counts no stripe, 2-2.3 px under 1.2 px), a stripe a little darker
    than the ground beyond it stops short on the paint's level. When that level is short of the
    ground's (read just past ``reach``) by ``params.staircase_shoulder_fraction`` of the whole
    step from the pavement (read 1.5 to 3 px inside) or more, the stripe ends where the profile
    then crosses midway between the two. On the ray-cast snow airport at 357 m (1024 px; ground
    232, paint 196, asphalt 72) the profiles where the stripe is 2.5 px wide or more stop short
    by 0.14 to 0.29 of the step, those where it is narrower by 0.03 to 0.11; their slopes make
    a second peak in 4 of 24.
    """
    n, m = rising.shape
    step = float(offsets[1] - offsets[0]) if m > 1 else 1.0
    rows = np.arange(n)
    columns = np.arange(m)[None, :]
    past_lobe = (slope < 0.5 * edge_slope[:, None]) & (columns > edge_column[:, None])
    lobe_end = np.argmax(past_lobe, axis=1)
    paint = rising[rows, lobe_end]
    beyond = (offsets[None, :] > reach[:, None] + 0.5) & (offsets[None, :] <= reach[:, None] + 2.5)
    inside = (offsets >= -3.0) & (offsets <= -1.5)
    ground = row_nanmedian(np.where(beyond, rising, np.nan))
    pavement = row_nanmedian(rising[:, inside]) if inside.any() else np.full(n, np.nan)
    whole = ground - pavement
    with np.errstate(invalid="ignore"):
        shoulder = (past_lobe.any(axis=1) & (whole > 0.0)
                    & (ground - paint >= params.staircase_shoulder_fraction * whole))
    midway = 0.5 * (paint + ground)
    crossed = (rising >= midway[:, None]) & (columns > lobe_end[:, None])
    at = np.argmax(crossed, axis=1)
    shoulder &= crossed[rows, at]
    before, after = rising[rows, at - 1], rising[rows, at]
    with np.errstate(invalid="ignore", divide="ignore"):
        fraction = np.clip((midway - before) / (after - before), 0.0, 1.0)
    return np.where(shoulder, offsets[np.clip(at - 1, 0, m - 1)] + step * fraction, np.nan)


def _seen_near_only(ratios: np.ndarray, width: np.ndarray, median: float, params: DetectorParams) -> bool:
    """Whether the second steps beyond an edge (:func:`_staircase_ratios`) are seen the way a side
    stripe resolved on the edge's near part only shows.

    Of the profiles where a stripe ``median`` of the local width wide is at least
    ``staircase_min_px`` wide, taken from far to near, the nearer half must see the step
    regularly (``staircase_near_min_profiles`` and ``staircase_near_fraction`` of them within
    ``staircase_near_scatter`` of ``median``) and the farther half hardly at all (at most
    ``staircase_far_max_fraction``): farther out the stripe merges with the step onto it into one
    lobe. On the ray-cast snow airport from 360 to 280 m (1024 px) the nearest 4-6 of 11-14 such
    profiles see it within 10 % and the farther ones none; texture beyond an edge (sand in
    'concrete, sand, mono' at 2048 px) shows steps all along it, half or more of the farther
    profiles.

    Parameters
    ----------
    ratios : ndarray
        The second step's distance beyond the edge at each profile, fraction of the runway's
        local width, NaN where none is seen.
    width : ndarray
        The runway's local width at each profile (pixels).
    median : float
        The median of the finite ``ratios``.
    params : DetectorParams
        The detector's parameters.

    Returns
    -------
    bool
    """
    resolved = np.flatnonzero(width * median >= params.staircase_min_px)
    far_to_near = resolved[np.argsort(width[resolved], kind="stable")]
    far, near = far_to_near[:len(far_to_near) // 2], far_to_near[len(far_to_near) // 2:]
    held = np.isfinite(ratios)
    regular = held & (np.abs(np.where(held, ratios, 0.0) - median) <= params.staircase_near_scatter * median)
    return bool(regular[near].sum() >= max(params.staircase_near_min_profiles, params.staircase_near_fraction * len(near))
                and held[far].sum() <= params.staircase_far_max_fraction * len(far))


def _past_staircase_stripes(ctx: _Context, fits: dict) -> dict:
    """The two edges moved out past their side stripes where both are seen as staircases.

    A side stripe a little darker than the ground beyond it (snow, light sand in a grey frame) is
    no bright band but a staircase: the pavement's strong step onto the paint, then a weaker step
    of the same sign onto the ground, the runway's true edge. :func:`refine.boundary_offsets`
    takes the outer step only where it reaches ``boundary_same_step_ratio`` of the inner one's
    slope; weaker, each edge is placed on the stripe's inner flank, a stripe's width inside
    (the robustness study's 'variety 3', snow beyond a worn stripe, below 200 m at 2048 px: both
    edges 14-24 px inside, reported with confidence 0.4-0.8).

    A painted side stripe is a ground constant: its width is the same fraction of the runway's
    width all along both edges (the perspective scales both alike), where texture beyond the
    edge (sand's brighter patches) lies anywhere. So the edges move only where on both edges
    ``staircase_min_fraction`` of the profiles (:func:`_staircase_ratios`) see the second step,
    at fractions of the local width whose robust scatter is within ``staircase_max_scatter`` of
    their median on each edge, whose medians agree within ``staircase_agreement`` and are at most
    ``side_stripe_width_fraction`` (the fraction of profiles counted where a stripe that wide is
    at least ``staircase_min_px`` wide, three profiles at least), or where an edge's profiles
    see it the way a stripe resolved on its near part only shows (:func:`_seen_near_only`: the
    nearer half regularly, the farther half hardly at all). Both edges are looked across over
    the depths either is supported over.

    Each edge is then refitted through the point where it meets the horizon (a stripe's width,
    and its shift, are nothing there, so the edges meet the horizon where they did) and the
    steps onto the ground where its profiles see them, elsewhere the two medians' mean times the
    local width out: where the edge found was held on part of its stretch only, turned, the steps
    turn it back (the ray-cast snow airport at 150 m, 768 px: edges 4.3 and 5.5 px in, 0.1 and
    0.3 px after). The fits' supports and contrasts are kept; their residuals become the RMS
    distance of the steps seen from the moved line where that is smaller (the edges found lay
    on the paint's flanks, crooked where the stripe is partly resolved: in 'variety 3' at 2048
    px from 540 to 230 m their residuals of 0.9-1.1 px withheld corners 0.3-1.4 px off).
    Returns ``fits``, the two edges replaced when they moved.

    A stripe narrower than ``staircase_min_px`` merges with the step onto it and is not seen:
    there the edges stay a stripe's width in (the ray-cast snow airport at 250 m, 768 px: 4.3 px
    in at the near corner, reported; 'variety 3' from 560 to 480 m at 2048 px: 2-3 px).
    """
    params = ctx.params
    # both edges looked across over the depths either is supported over (where one edge's
    # near part was not held, the other's may see the stripe widest)
    supported = [_segment_in_depth(ctx.horizon, fits[name]) for name in ("left", "right")]
    depths = ctx.horizon.to_sd(np.concatenate(supported))[:, 1]
    d_far, d_near = float(depths.min()), float(depths.max())
    segments = {}
    for name in ("left", "right"):
        line = fits[name].line.homogeneous()
        ends = [np.cross(line, ctx.horizon.parallel_h(d)) for d in (d_far, d_near)]
        if any(abs(end[2]) < 1e-12 for end in ends):
            return fits
        segments[name] = np.array([end[:2] / end[2] for end in ends])
    # the second steps' peaks first; their shoulders too only where the peaks alone do not make
    # a staircase (shoulders read on levels are looser: on 'snow, monochrome' at 133 m, 2048 px,
    # adding them to peaks that made one spread the ratios past the scatter allowed)
    read = {}
    for name, other in (("left", "right"), ("right", "left")):
        read[name] = _staircase_ratios(ctx.image, segments[name], segments[other], params)
        if read[name] is None:
            return fits
    staircase = _staircase_seen(read, params, shoulders=False) or _staircase_seen(read, params, shoulders=True)
    if staircase is None:
        return fits
    seen_on, ratio, where = staircase
    moved = {}
    for name, other in (("left", "right"), ("right", "left")):
        fit = fits[name]
        ratios, width, sampled, outward = seen_on[name]
        # the edge through where it meets the horizon (a stripe's width is nothing there: the
        # edges still meet it where they did) and the steps onto the ground where seen,
        # elsewhere a stripe's width out: the steps turn it where the fit found was held on
        # part of the edge only
        crossing = np.cross(fit.line.homogeneous(), ctx.horizon.parallel_h(0.0))
        if abs(crossing[2]) < 1e-12:
            return fits
        crossing = crossing[:2] / crossing[2]
        outer = sampled + (np.where(np.isfinite(ratios), ratios, ratio) * width)[:, None] * outward
        direction = np.linalg.svd(outer - crossing)[2][0]
        if direction @ fit.line.direction < 0.0:
            direction = -direction
        point = crossing + ((outer.mean(axis=0) - crossing) @ direction) * direction
        line = PixelLine(point=point, direction=direction)
        other_line = fits[other].line
        points = fit.points + (ratio * np.abs(other_line.distance(fit.points)))[:, None] * outward
        along = (points - point) @ direction
        note = (f"moved out past its side stripe ({100 * ratio:.1f} % of the runway's width: a staircase "
                f"beyond {where}both edges)")
        # straight as the edge found or as the steps onto the ground about the moved line, the
        # straighter (the edge found lay on the paint's flanks, crooked where the stripe is
        # partly resolved; the steps onto the ground are weaker and noisier where it is not)
        seen = np.isfinite(ratios)
        residual = min(fit.residual_px, float(np.sqrt(np.mean(line.distance(outer[seen]) ** 2))))
        moved[name] = replace(fit, line=line, points=points, residual_px=residual,
                              extent=(float(along.min()), float(along.max())),
                              note="; ".join(filter(None, [fit.note, note])))
    return moved


def _staircase_seen(read: dict, params: DetectorParams, shoulders: bool):
    """The staircase rule's verdict (:func:`_past_staircase_stripes`) on the two edges' second
    steps ``read`` (:func:`_staircase_ratios` of "left" and "right"): ``(seen_on, ratio, where)``,
    each edge's ``(ratios, width, points, outward)``, the stripe's width as a fraction of the
    runway's (the two edges' medians' mean) and the note's "the near parts of " when an edge
    counted by :func:`_seen_near_only`; None when the steps do not make a side stripe.
    ``shoulders``: the second steps read as shoulders too (:func:`_stripe_shoulder`), not only
    as peaks."""
    medians, seen_on, where = [], {}, ""
    for name in ("left", "right"):
        peaks, width, points, outward, with_shoulders = read[name]
        ratios = with_shoulders if shoulders else peaks
        seen_on[name] = (ratios, width, points, outward)
        held = np.isfinite(ratios)
        if held.sum() < 3:
            return None
        median = float(np.median(ratios[held]))
        scatter = float(np.median(np.abs(ratios[held] - median)))
        # counted where a stripe that wide is resolved (its width grows along the edge: far
        # out it merges with the step onto it)
        resolved = width * median >= params.staircase_min_px
        if not (0.0 < median <= params.side_stripe_width_fraction and scatter <= params.staircase_max_scatter * median
                and resolved.sum() >= 3):
            return None
        if (held & resolved).sum() < params.staircase_min_fraction * resolved.sum():
            if not _seen_near_only(ratios, width, median, params):
                return None
            where = "the near parts of "
        medians.append(median)
    if abs(medians[0] - medians[1]) > params.staircase_agreement * max(medians):
        return None
    return seen_on, 0.5 * (medians[0] + medians[1]), where


def _stripe_reach_and_band(width: np.ndarray, params: DetectorParams) -> tuple[np.ndarray, np.ndarray]:
    """Across an edge where the runway is ``width`` pixels wide: how far a side stripe reaches
    inside it (``side_stripe_width_fraction`` of the width plus ``edge_blur_px``, as
    :func:`_refine_edge` looks past it) and the band read past that, 15 % of the width, 1.5 to
    8 px."""
    return params.side_stripe_width_fraction * width + params.edge_blur_px, np.clip(0.15 * width, 1.5, 8.0)


def _edge_step(image, segment_uv: np.ndarray, other_uv: np.ndarray, params: DetectorParams) -> float:
    """Median level just outside the edge ``segment_uv`` minus inside it past a side stripe.

    ``other_uv`` is the runway's other edge (the inside lies towards it). Across each of
    :data:`BALANCE_PROFILES` points of the edge: the mean of the surface between 1 px and a band
    beyond the edge, minus the mean of the pavement between the side stripe's reach (as in
    :func:`_refine_edge`: ``side_stripe_width_fraction`` of the local width plus
    ``edge_blur_px``) and a band past it (:func:`visland.detection.refine.net_step`, as the edge
    refinement measures each profile's net step); the band is 15 % of the local width, 1.5 to 8 px.
    ``image`` is grey levels or RGB (its chroma is sampled). NaN when nothing is sampled.
    """
    across = _across_edge(segment_uv, other_uv)
    if across is None:
        return math.nan
    points, direction, outward, width = across
    reach, band = _stripe_reach_and_band(width, params)
    profiles, offsets = sample_profiles(image, points, outward, direction, float((reach + band).max()) + 3.0)
    # the profiles are centred on the edge and run outwards: the boundary at offset 0
    net = net_step(profiles, offsets, np.zeros(len(points)), 1, reach, (1.0, 1.0 + band[:, None]),
                    (0.5, 0.5 + band[:, None]))
    sampled = np.isfinite(net)
    return float(np.median(net[sampled])) if sampled.any() else math.nan


def _edges_run_on(image, end: TransverseLine, vp_uv: np.ndarray, stretch_px: float,
                  params: DetectorParams) -> float | None:
    """How far the edges run on past the runway end ``end``: for each edge, the contrast across
    it (:func:`_edge_contrast`) over ``stretch_px`` of depth beyond the end line, less the
    ground's own a runway width farther out, over the edge's contrast just before the end; the
    smaller of the two ratios. None when the stretch is too short to read (under 2 px) or the
    contrast before the end too weak (under ``min_contrast``). Past a runway's end both edges
    cross the ground (ratios near 0); past a step inside the pavement (rubber ending on the
    paler asphalt beyond the touchdown zone, or on concrete as light as the grass) the pavement
    and its side stripes still part from the ground there. Reading stops at the first edge whose
    ratio is below ``end_run_on_ratio`` (the ground's contrast, which only lowers it, is then
    not read): the answer is the same, at a third of the cost on the usual true end."""
    depth = end.depth_px
    if not (math.isfinite(depth) and depth > stretch_px + 1.0 and stretch_px >= 2.0):
        return None
    vp = np.asarray(vp_uv, float)

    def stretch(corner, d_from, d_to):
        # along the edge through ``corner`` and the vanishing point, depth scaling with the
        # distance to the vanishing point
        corner = np.asarray(corner, float)
        return np.array([vp + (corner - vp) * (d_from / depth), vp + (corner - vp) * (d_to / depth)])

    smallest = math.inf
    for corner, other in ((end.corner_left_uv, end.corner_right_uv), (end.corner_right_uv, end.corner_left_uv)):
        before = _edge_contrast(image, stretch(corner, depth + 1.0, depth + 1.0 + stretch_px),
                                stretch(other, depth + 1.0, depth + 1.0 + stretch_px), params)
        edge_beyond = stretch(corner, depth - 1.0 - stretch_px, depth - 1.0)
        other_beyond = stretch(other, depth - 1.0 - stretch_px, depth - 1.0)
        beyond = _edge_contrast(image, edge_beyond, other_beyond, params)
        if not (math.isfinite(before) and math.isfinite(beyond)) or before < params.min_contrast:
            return None
        if beyond / before < params.end_run_on_ratio:
            return beyond / before
        # the same rows a runway width farther out: the ground's own contrast there (a road
        # crossing past the end, fields in bands near the horizon, read across a slanted edge)
        ground = _edge_contrast(image, edge_beyond, other_beyond, params, offset_widths=1.0)
        if not math.isfinite(ground):
            return None
        smallest = min(smallest, (beyond - ground) / before)
    return smallest


def _edge_contrast(image, segment_uv: np.ndarray, other_uv: np.ndarray, params: DetectorParams,
                   offset_widths: float = 0.0) -> float:
    """Range of grey levels of the median profile across the edge ``segment_uv`` (``other_uv``:
    the runway's other edge), over the side stripe's reach and a band either side of the edge
    (as :func:`_edge_step` reads it): the step onto the pavement, the stripe's ridge, the
    pavement's own shades; a few levels where the edge line crosses plain ground. With
    ``offset_widths``, the same profiles that many local runway widths farther out. NaN when
    nothing is sampled."""
    across = _across_edge(segment_uv, other_uv)
    if across is None:
        return math.nan
    points, direction, outward, width = across
    points = points + offset_widths * width[:, None] * outward
    reach, band = _stripe_reach_and_band(width, params)
    profiles, _ = sample_profiles(image, points, outward, direction, float((reach + band).max()) + 1.0, step_px=0.5)
    if np.isfinite(profiles).all():
        profile = np.median(profiles, axis=0)               # (nanmedian's cost, without a NaN)
    else:
        profile = np.nanmedian(profiles, axis=0) if profiles.size else np.array([math.nan])
    return float(np.nanmax(profile) - np.nanmin(profile)) if np.isfinite(profile).any() else math.nan


def _unbalanced_edges(ctx: _Context, pair: _EdgePair) -> str:
    """Why the two edges cannot be one runway's sides (``""`` when they can): across both, the
    surface must change the same way (outside minus inside of one sign) and by comparable
    amounts (``params.edge_balance_*``). A painted line inside a pavement (the centre line seen
    in fog taken for the left edge) has pavement on both sides; a side stripe taken for a narrow
    strip has the runway's pavement outside one of its sides and grass outside the other. Grey
    levels and, in a colour frame, chroma are each asked; a channel whose stronger step is
    under ``edge_balance_min_levels`` does not decide."""
    params = ctx.params
    channels = [("grey", ctx.image)] + ([("chroma", ctx.colour)] if ctx.colour is not None else [])
    verdicts = []
    for name, image in channels:
        left = _edge_step(image, pair.segment_left_uv, pair.segment_right_uv, params)
        right = _edge_step(image, pair.segment_right_uv, pair.segment_left_uv, params)
        if not (math.isfinite(left) and math.isfinite(right)):
            continue
        strong, weak = max(abs(left), abs(right)), min(abs(left), abs(right))
        if strong < params.edge_balance_min_levels:
            continue
        if left * right > 0 and weak >= params.edge_balance_min_ratio * strong:
            return ""                   # one deciding channel finds them balanced: enough
        verdicts.append((name, left, right))
    if not verdicts:
        return ""
    steps = "; ".join(f"{name} {left:+.1f} / {right:+.1f}" for name, left, right in verdicts)
    return (f"the surface does not change alike across the two edges (steps outside minus inside, left / right: "
            f"{steps}): not one pavement's two sides")


def _centre_line(ctx: _Context, pair: _EdgePair, polarity_hint: int) -> tuple[LineFit | None, str]:
    """The centre line midway between the edges in horizon coordinates (the harmonic conjugate of
    the horizon with respect to the edges, :mod:`visland.detection.horizon`), kept when it meets
    the horizon where the edges do: ``(LineFit or None, note)`` (the note empty when found)."""
    horizon, params = ctx.horizon, ctx.params
    weights = np.array([1.0 / max(pair.sigma_s0_left_px, 1e-3) ** 2, 1.0 / max(pair.sigma_s0_right_px, 1e-3) ** 2])
    s0 = float((weights @ np.array([pair.s0_left, pair.s0_right])) / weights.sum())
    d_mid = pair.d_mid
    k_centre = 0.5 * ((pair.s0_left + pair.k_left * d_mid - s0) + (pair.s0_right + pair.k_right * d_mid - s0)) / d_mid
    centre_fit = _refine_centre(ctx, s0, k_centre, pair.k_left, pair.k_right, pair.d_far, pair.d_near, polarity_hint)
    if not centre_fit:
        return None, f"centre line not found ({centre_fit.reason})"
    s0_centre, _, sigma_s0_centre_px = _pencil_of(horizon, centre_fit)
    sigma_edges_px = min(pair.sigma_s0_left_px, pair.sigma_s0_right_px)
    if abs(s0_centre - s0) > params.vp_tolerance_px + params.edge_crossing_sigmas * math.hypot(sigma_s0_centre_px,
                                                                                                sigma_edges_px):
        return None, "centre line rejected (does not meet the edges on the horizon)"
    return centre_fit, ""


def _heading(ctx: _Context, pair: _EdgePair, centre_fit: LineFit | None):
    """The vanishing point fused from the lines and the horizon, d_F and the heading deviation
    (seed 001 eq. 18-19): ``((vp_uv, dF_px, dpsi_rad), None)``, or ``(None, reason)`` when the
    runway's direction is too far off the aircraft's heading to be the runway approached."""
    horizon, params, camera = ctx.horizon, ctx.params, ctx.camera
    all_fits = [pair.fits["left"], pair.fits["right"]] + ([centre_fit] if centre_fit is not None else [])
    vp_uv = _fuse_vanishing_point(horizon, all_fits, params.horizon_sigma_px, params.vp_line_min_sigma_px)
    vp_xy = camera.pixels_to_normalized(vp_uv)
    dF_px = float(dF_from_vanishing_point(vp_xy[None, :], np.array([horizon.rho]), np.array([horizon.theta]),
                                          camera)[0])
    dpsi_rad = float(dpsi_from_dF(np.array([dF_px]), np.array([ctx.roll]), np.array([ctx.pitch]), camera)[0])
    if not abs(dpsi_rad) <= math.radians(params.max_heading_deviation_deg):
        # a runway being approached lies ahead: its direction within tens of degrees of the
        # aircraft's heading (a crossing taxiway or road meets the horizon far to the side)
        return None, (f"the edges meet the horizon {math.degrees(dpsi_rad):+.0f} deg off the aircraft's heading "
                      f"(> {params.max_heading_deviation_deg:g}): not a runway being approached")
    return (vp_uv, dF_px, dpsi_rad), None


def _threshold_and_end(ctx: _Context, pair: _EdgePair, vp_uv: np.ndarray, bottom_depth: float,
                       extent_image=None, marked: bool = False) -> _TransverseLines:
    """The threshold and the runway end: where the runway's surface ends along it, the transverse
    steps there through V2 (:mod:`visland.detection.transverse`), the threshold moved to where
    the pavement ends or to a threshold marking (:mod:`visland.detection.threshold_marking`),
    the runway end withheld when nearer than a runway's length; their corners where in the image.
    ``marked``: the strip, followed from the previous frame, was seen with its threshold marking
    there (a threshold found now carries it without reading it again, a millisecond per frame)."""
    horizon, params, camera = ctx.horizon, ctx.params, ctx.camera
    fits, d_far, d_near, d_mid = pair.fits, pair.d_far, pair.d_near, pair.d_mid
    s0_vp = float(horizon.to_sd(vp_uv)[0])
    notes = []
    corners = np.full((4, 2), np.nan)
    corners_found = np.zeros(4, dtype=bool)
    threshold_line = end_line = (math.nan, math.nan)
    depth_span = d_near - d_far
    width, height = camera.width, camera.height
    edges_reach_border = d_near >= bottom_depth - params.border_clearance_px
    min_step = params.min_contrast
    width_slope = abs(pair.k_right - pair.k_left)
    # where the runway's surface ends (more reliable than where its edges fade)
    # the edges' slopes as lines through the fused vanishing point, at mid depth
    k_left_through_vp = (pair.s0_left + pair.k_left * d_mid - s0_vp) / d_mid
    k_right_through_vp = (pair.s0_right + pair.k_right * d_mid - s0_vp) / d_mid
    in_chroma = extent_image is not None and extent_image is not ctx.image
    extent = surface_extent(extent_image if in_chroma else ctx.float_image, horizon, s0_vp, k_left_through_vp,
                            k_right_through_vp, (d_far, d_near), (1.0, bottom_depth), params=params)
    d_near_expected, d_far_expected = d_near, d_far
    surface_level = math.nan
    if extent is not None:
        d_far_expected, d_near_expected = extent
        surface_level = extent.level if not in_chroma else math.nan      # a grey level, unknown here

    def transverse(d_expected, d_window, outward):
        # the transverse step nearest d_expected within d_window, across this pair of edges
        return find_transverse_line(ctx.image, horizon, s0_vp, fits["left"].line, fits["right"].line, d_expected,
                                    d_window, outward=outward, min_step=min_step, colour=ctx.colour,
                                    surface_level=surface_level, params=params)

    def window(depth):
        half = max(params.threshold_window_min_px, 0.5 * params.threshold_search_fraction * depth_span,
                   params.threshold_window_depth_fraction * depth)
        return max(0.5, depth - half), min(bottom_depth, depth + half)

    # the runway's surface running out of the bottom of the image hides the threshold: a step
    # found there would be a marking (the last second before the threshold)
    d_exit = _depth_leaving_image(horizon, s0_vp, 0.5 * (k_left_through_vp + k_right_through_vp), d_mid, bottom_depth,
                                  width, height)
    near_window = window(d_near_expected)
    # (the surface read to the last row the image holds: its near end is the image's, a few
    # pixels short of where the runway's centre line leaves it)
    surface_out = d_near_expected >= d_exit - params.threshold_exit_margin_px or (
        extent is not None and extent.near_runs_out)
    if surface_out:
        near = None
        edges_reach_border = True
    else:
        near = transverse(d_near_expected, near_window, 1)
    if ((near is None or not near.spans) and not edges_reach_border and extent is not None
            and window(d_near)[1] > near_window[1] + 1.0 and d_near < d_exit - params.threshold_exit_margin_px):
        # the surface seemed to end well before the edges do (a concrete runway's middle
        # darkened by tyre rubber, its clean part nearer the threshold as light as the ground:
        # 'oblique, 1200x23'; the touchdown zone's paint of 16 stripes on 30 m at 3.6 km, 2048
        # px: the surface 15 px short, the edges 4.5 px, the threshold past the first window):
        # the threshold is looked for where the edges' support ends
        again = transverse(d_near, window(d_near), 1)
        if again is not None:
            near = again
    if near is not None and not near.spans:
        notes.append("threshold withheld: the transverse step found does not span the runway's width")
        near = None
    elif near is None:
        notes.append("threshold below the image" if edges_reach_border else "threshold not found")
        if surface_out and extent is not None:
            # the pavement runs out of the image: a displaced threshold's bar or stripes can still
            # be ahead on it (300 m of pavement before the threshold, 2048 px: its start leaves the
            # image at 380 m, 37 m high, and the threshold was lost for the last 5 s above 100
            # ft). The first threshold marking from the image's edge inwards, past the stripes'
            # own reach (a true threshold just below the image leaves at most the far ends of its
            # stripes in view; the touchdown zone's and aiming point's marks leave the middle free
            # and are no threshold marking), where the first widths are resolved. Not where the
            # surface merely seemed to end without a step: on concrete as light as dry grass that
            # end is anywhere, and a band past it was reported 97-522 px off at 2048 px
            d_from = min(d_near_expected, d_exit - params.threshold_exit_margin_px)
            ahead = threshold_marking(ctx.image, horizon, s0_vp, fits["left"].line, fits["right"].line, d_from,
                                      1.0, min_step, surface_level=surface_level, resolved_only=True, params=params)
            if ahead is not None and ahead.line is not None:
                notes[-1] = (f"threshold on the {ahead.kind} marking {ahead.pavement_widths:.1f} runway widths inside "
                             "the image, the pavement running out of it")
                near = ahead.line
    far = transverse(d_far_expected, window(d_far_expected), -1)
    far_withheld = False
    if far is not None and far.spans and far.depth_px - d_far > params.end_past_edges_fraction * depth_span:
        # both edges run on well past the step found (rubber ending on the paler pavement beyond
        # the touchdown zone: the ray-cast airport's 1200 x 23 m asphalt runway, its end placed
        # 12 px short from 1.5 km to 400 m): the end is looked for where they end, nearer than
        # that step, or withheld
        lo, hi = window(d_far)
        hi = min(hi, far.depth_px - 0.5 * params.end_past_edges_fraction * depth_span)
        again = transverse(d_far, (lo, hi), -1) if hi > lo else None
        if again is None or not again.spans:
            notes.append(f"runway end withheld: both edges run on {far.depth_px - d_far:.1f} px past the step found")
            far_withheld = True
        far = again if again is not None and again.spans else None
    if far is not None and far.spans:
        # the edges' support can end with the step too (tracking, the edges refined over the
        # surface's extent, which ends where the rubber does): their own step, read on past it
        ratio = _edges_run_on(ctx.image, far, vp_uv, max(2.0, params.end_past_edges_fraction * depth_span), params)
        if ratio is not None and ratio >= params.end_run_on_ratio:
            notes.append(f"runway end withheld: both edges run on past the step found (the contrast across them "
                         f"there {ratio:.2f} of theirs before it or more)")
            far, far_withheld = None, True
    if far is not None and far.spans and ctx.colour is not None and pavement_runs_on(
            ctx.colour, horizon, s0_vp, fits["left"].line, fits["right"].line, far.depth_px, -1,
            params.end_chroma_band_px, params):
        # the grey pavement runs on past the step, where the ground beside is coloured (concrete
        # as light as dry grass, its rubber ending: the edges' contrast past it read beside
        # joining taxiways, or over 2 px only at 1024 px, did not withhold it; far corners
        # 42 px short at 2048 px, 19-23 px at 1024). Read over a few pixels past it: the
        # reciprocal runway's touchdown-zone paint taken for the end leaves only 5-6 px of
        # pavement before the true end at 2.8 km, 2048 px (far corners 5.4-6.9 px off)
        notes.append("runway end withheld: the pavement's grey runs on past the step found, between coloured ground")
        far, far_withheld = None, True
    marking_widths = math.nan
    if near is not None and not near.method.startswith("marking"):
        # (a threshold already on a marking, ahead on pavement running out of the image, has no
        # pavement's start to check)
        #
        # a step inside the pavement (a patch's edge, the stripes' inner edge) is not where the
        # runway begins: the ground must begin at the threshold, or the step is searched again
        # where it does; then, if the pavement precedes a threshold marking (displaced
        # threshold, blast pad), the threshold is that marking
        d_pavement, pavement_step, moved = near.depth_px, near.step, None
        reach = params.pavement_search_fraction * depth_span + params.pavement_search_px
        ground = ground_begins(ctx.image, horizon, s0_vp, fits["left"].line, fits["right"].line, near.depth_px,
                               min(d_exit, near.depth_px + reach), surface_level, min_step, colour=ctx.colour,
                               params=params)
        if ground is not None and math.isinf(ground[0]):
            # pavement all the way searched: a step inside the runway (the near edge of its
            # touchdown zone's rubber when the edges' support ends there, concrete on dry grass
            # at 1.5 km: 16 px short); the ground is looked for as far again
            ground = ground_begins(ctx.image, horizon, s0_vp, fits["left"].line, fits["right"].line, near.depth_px,
                                   min(d_exit, near.depth_px + params.pavement_search_extend * reach), surface_level,
                                   min_step, colour=ctx.colour, params=params)
        runs_on = ground is not None and math.isinf(ground[0])
        if runs_on:
            notes.append("threshold withheld: the pavement continues past the step found as far as searched")
            near = None
        elif ground is not None and ground[0] > near.depth_px + params.pavement_min_move_px:
            d_ground, ground_step = ground
            d_pavement = d_ground
            if math.isfinite(ground_step):              # (NaN: only the chroma told the ground)
                pavement_step = ground_step
            again = transverse(d_ground, (d_ground - params.pavement_window_px,
                                          min(bottom_depth, d_ground + params.pavement_window_px)), 1)
            moved = (again if again is not None and again.spans
                     and abs(again.depth_px - d_ground) <= params.pavement_agreement_px else False)
            if moved:
                d_pavement, pavement_step = moved.depth_px, moved.step
        marking = None if runs_on else threshold_marking(ctx.image, horizon, s0_vp, fits["left"].line,
                                                         fits["right"].line, d_pavement, 1.0, min_step,
                                                         surface_level=surface_level, pavement_step=pavement_step,
                                                         params=params)
        if marking is not None:
            marking_widths = marking.pavement_widths
        if marking is not None and marking.line is None:
            notes.append(f"threshold withheld: plain pavement, then a marking {marking.pavement_widths:.1f} runway "
                         "widths in, too far to be placed (a displaced threshold?)")
            near = None
        elif marking is not None:
            notes.append(f"threshold on the {marking.kind} marking {marking.pavement_widths:.1f} runway widths "
                         "inside the pavement")
            near = marking.line
        elif moved:
            notes.append(f"threshold moved {moved.depth_px - near.depth_px:.1f} px to where the pavement ends")
            near = moved
        elif moved is False:
            notes.append("threshold withheld: pavement continues before the step found")
            near = None
    if near is not None:
        # a transverse edge that carries on beyond the runway's edges is a pavement's crossing or
        # joining it there (the runway continues past it, or begins elsewhere), not the threshold
        beyond = pavement_beyond_edges(ctx.image, horizon, s0_vp, fits["left"].line, fits["right"].line,
                                       near.depth_px, 1, colour=ctx.colour, surface_level=surface_level,
                                       params=params)
        if beyond:
            notes.append(f"threshold withheld: its step continues beyond the runway's {' and '.join(beyond)} "
                         f"edge{'s' if len(beyond) > 1 else ''} (a pavement crossing or joining the runway there)")
            near = None
    if near is not None and not near.method.startswith("marking"):
        # runway paint nearer than the threshold: the runway begins before it (a touchdown zone's
        # rubber ending on concrete as light as the ground, the step at the rubber's start). Not
        # asked of a threshold on a marking: paint before it is the pavement's (a displaced
        # threshold's arrows)
        painted = paint_before(ctx.image, horizon, s0_vp, fits["left"].line, fits["right"].line, near.depth_px,
                               d_exit - params.threshold_exit_margin_px, min_step, params=params)
        if painted is not None:
            notes.append(f"threshold withheld: runway paint {painted:.1f} runway widths nearer than the threshold found "
                         "(the runway begins before it)")
            near = None
    if (near is not None and not near.method.startswith("marking")
            and starts_on_its_stripes(ctx.image, horizon, s0_vp, fits["left"].line, fits["right"].line,
                                      near.depth_px, min_step, params=params)):
        notes.append("threshold withheld: placed where its stripes start, the pavement before them as light as "
                     "the ground (where the runway begins is not seen)")
        near = None
    threshold_marked = near is not None and (marked or near.method.startswith("marking") or marked_at_start(
        ctx.image, horizon, s0_vp, fits["left"].line, fits["right"].line, near.depth_px, min_step,
        pavement_step=near.step if math.isfinite(near.step) else 0.0, params=params))
    if near is not None and far is not None and far.spans:
        # a runway is a long strip (params.min_length_to_width widths at least): an "end" found
        # nearer than that past the threshold is a marking (the far side of the threshold stripes
        # when the surface seemed to end there), not the runway's end
        length_widths = widths_along(camera.fx, near.depth_px, far.depth_px, max(width_slope, 1e-9))
        if length_widths < params.min_length_to_width:
            notes.append(f"runway end withheld: {length_widths:.1f} runway widths past the threshold only "
                         f"(< {params.min_length_to_width:g})")
            far = None
            far_withheld = True
    if near is not None:
        threshold_line = _line_chart(camera, near.line_h)
        for index, uv in ((0, near.corner_left_uv), (1, near.corner_right_uv)):
            if camera.in_image(uv, margin_px=0.0):
                corners[index] = uv
                corners_found[index] = True
        if not corners_found[:2].all():
            notes.append("a threshold corner lies outside the image")
    if far is not None and not far.spans:
        notes.append("runway end withheld: the transverse step found does not span the runway's width")
    elif far is None and not far_withheld:
        notes.append("runway end not found")
    if far is not None and far.spans:
        end_line = _line_chart(camera, far.line_h)
        for index, uv in ((2, far.corner_left_uv), (3, far.corner_right_uv)):
            if camera.in_image(uv, margin_px=0.0):
                corners[index] = uv
                corners_found[index] = True
    return _TransverseLines(corners, corners_found, threshold_line, end_line, notes,
                            near.method if near is not None else "", marking_widths, threshold_marked)


def _confidence(params: DetectorParams, pair: _EdgePair,
                centre_fit: LineFit | None) -> tuple[float | None, float | None, str | None]:
    """A heuristic 0..1 confidence from the edges' support, straightness, agreement on the
    horizon and contrast, and whether the centre line was found: ``(confidence, edges, None)``
    with ``edges`` the two edges' own part (without the centre line's factor: what a corner on
    them is worth, :func:`_corners_withheld`), or ``(None, None, reason)`` below
    ``params.min_confidence``."""
    fits = pair.fits
    q_support = math.sqrt(fits["left"].support * fits["right"].support)
    q_residual = math.exp(-0.5 * (max(fits["left"].residual_px, fits["right"].residual_px)
                                  / params.confidence_residual_px) ** 2)
    # the crossings' separation in sigmas (the tolerance is edge_crossing_sigmas of them)
    chi = abs(pair.s0_left - pair.s0_right) / max(pair.tolerance_px / params.edge_crossing_sigmas, 1e-6)
    q_vp = math.exp(-0.5 * (chi / params.confidence_vp_sigmas) ** 2)
    q_contrast = min(1.0, min(fits["left"].contrast, fits["right"].contrast)
                     / (params.confidence_contrast_factor * params.min_contrast))
    edges = q_support * q_residual * q_vp * math.sqrt(q_contrast)
    confidence = edges * (1.0 if centre_fit is not None else params.confidence_without_centre)
    if confidence < params.min_confidence:
        return None, None, (f"{_WEAK} (confidence {confidence:.2f} < {params.min_confidence:g}: "
                            f"support {q_support:.2f}, residual {q_residual:.2f}, horizon agreement {q_vp:.2f}, "
                            f"contrast {q_contrast:.2f})")
    return confidence, edges, None


def _refine_centre(ctx: _Context, s0, k_centre, k_left, k_right, d_far, d_near, polarity_hint: int) -> LineFit | NoFit:
    """The centre line (a painted stripe, often dashed) midway between the edges, or why it was
    not found (for each stripe polarity tried)."""
    horizon, params = ctx.horizon, ctx.params
    line = _pencil_pixel_line(horizon, s0, k_centre, 0.5 * (d_far + d_near))
    scale = math.sqrt(1 + k_centre * k_centre)
    d_ref = 0.5 * (d_far + d_near)
    t_lo, t_hi = (d_far - d_ref) * scale, (d_near - d_ref) * scale
    img_lo, img_hi = _image_span(line, ctx.camera.width, ctx.camera.height, params.centre_image_margin_px)
    t_lo, t_hi = max(t_lo, img_lo), min(t_hi, img_hi)
    if not (math.isfinite(t_lo) and math.isfinite(t_hi)) or t_hi - t_lo < params.min_edge_length_px:
        return NoFit(f"it lies in the image over less than {params.min_edge_length_px:.0f} px")
    width_near = abs(k_right - k_left) * d_near / scale
    halfwidth = float(np.clip(params.centre_band_fraction * width_near, params.centre_band_min_px,
                              params.search_halfwidth_px * params.centre_band_max_factor))

    def stripe_width(t):
        depth = d_ref + np.asarray(t) / scale
        return np.maximum(params.centre_width_fraction * np.abs(k_right - k_left) * depth / scale,
                          params.centre_min_width_px)

    best = None
    reasons = []
    for polarity in ((polarity_hint,) if polarity_hint else (1, -1)):
        fit = refine_line(ctx.image, line, (t_lo, t_hi), "stripe", polarity=polarity, halfwidth_px=halfwidth,
                          stripe_width_px=stripe_width, params=params,
                          iterations=max(1, params.refine_iterations - 1))
        stripe = "bright stripe" if polarity > 0 else "dark stripe"
        if not fit:
            reasons.append(f"{stripe}: {fit.reason}")
            continue
        if fit.residual_px > params.max_line_residual_px:
            reasons.append(f"{stripe}: not straight (RMS residual {fit.residual_px:.2f} px)")
            continue
        length = fit.extent[1] - fit.extent[0]
        if length < params.min_edge_length_px or fit.support < params.centre_min_support:
            reasons.append(f"{stripe}: supported over {length:.0f} px by {100 * fit.support:.0f} % of its profiles "
                           f"(< {params.min_edge_length_px:g} px or {100 * params.centre_min_support:.0f} %)")
            continue
        if best is None or fit.n_inliers > best.n_inliers:
            best = fit
        if best is not None and best.support >= params.centre_bright_support:
            break            # a painted line is white: the dark try only if the bright one fails
    return best if best is not None else NoFit(" / ".join(reasons))


def _depth_leaving_image(horizon: HorizonFrame, s0: float, k: float, d_from: float, d_to: float,
                         width: int, height: int) -> float:
    """Depth at which the pencil line ``s = s0 + k d`` leaves the image (searched in ``[d_from, d_to]``)."""
    depths = np.linspace(d_from, max(d_to, d_from + 1.0), 400)
    uv = horizon.pencil_point(s0, k, depths)
    inside = (uv[:, 0] >= -0.5) & (uv[:, 0] <= width - 0.5) & (uv[:, 1] >= -0.5) & (uv[:, 1] <= height - 0.5)
    if not inside.any():
        return float(d_from)
    return float(depths[np.nonzero(inside)[0][-1]])


def _deepest_visible(horizon: HorizonFrame, width: int, height: int) -> float:
    corners = np.array([[-0.5, -0.5], [width - 0.5, -0.5], [-0.5, height - 0.5], [width - 0.5, height - 0.5]])
    return float(horizon.to_sd(corners)[:, 1].max())


def _line_chart(camera: CameraModel, line_h) -> tuple[float, float]:
    """SPEC ``(rho, theta)`` of a homogeneous pixel line ``a u + b v + c = 0``."""
    a, b, c = (float(x) for x in line_h)
    norm = math.hypot(a, b)
    theta_px = math.atan2(b / norm, a / norm)
    rho_px = -c / norm
    rho, theta = camera.line_from_pixel_hough(rho_px, theta_px)
    return float(rho), float(theta)


def _as_float(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan
