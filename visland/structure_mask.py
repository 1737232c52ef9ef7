"""Proposing a mask of the aircraft's own structure from footage (windshield frame, wiper, nose).

The aircraft's structure is fixed to the camera, so it does not move with the scene: over frames
sampled across an approach, its pixels keep their grey level while the ground slides past.
Low temporal variance alone is not enough, though: a uniform sky is just as steady, and so is
the horizon in steady flight. The rule, pixel by pixel, on frames divided by their exposure
gain (:func:`exposure_gains`) and smoothed by a Gaussian of ``blur_sigma_px``:

=====================  ==========================================================================
test                   definition
=====================  ==========================================================================
static                 temporal standard deviation of the grey level ``<= max_static_std``
moving scene           temporal standard deviation ``> 2 max_static_std`` (its median grey level
                       ``g_scene`` sets what "dark" means)
dark                   temporal mean ``< dark_fraction * g_scene``: the cabin, exposed for the
                       outside, is in shadow
static edge            gradient of the temporal mean ``>= edge_min_grad`` and at least
                       ``edge_static_ratio`` times the mean of the frames' own gradients: an
                       edge that stays put keeps its full contrast in the mean image, a moving
                       one is averaged away (ratio about ``1 / sqrt(frames)``)
structure candidate    static and (dark, or within ``edge_reach_px`` of a static edge)
=====================  ==========================================================================

So a bright static area counts only along static edges: the interior of a uniform sky is never
taken. The candidates are then cleaned up: an opening by a disc of radius ``open_fraction`` of
the short side removes thin bands (the horizon of a steady flight, static cloud edges, which
qualify along their edge only); only connected parts that touch the image border (structure
enters the view from outside it; parts within ``2 link_px`` of each other count as connected,
since the seam between two static parts is itself unsteady when the camera vibrates) and cover
at least ``min_area_fraction`` of the image are kept;
holes up to ``max_hole_fraction`` of the image are filled (reflections, instruments), larger
ones are the view through the windshield and stay open; finally the mask is dilated by
``dilate_px`` (a margin against vibration and the structure's own edge).

Limits: a uniformly bright piece of structure (a white nose in sunlight) is outlined only, not
filled; a dark, uniform, barely moving stretch of ground touching the border (a dark forest near
the horizon) over a short stretch of footage can be taken for structure. The user checks the
picture and edits the PNG or gives polygons in camera.json.

Pixels follow :mod:`visland.camera` (``image[v, u]``); the mask has the frames' size.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields

import numpy as np

__all__ = ["MaskParams", "StructureMask", "propose_structure_mask", "temporal_statistics", "exposure_gains",
           "mask_picture"]


@dataclass(frozen=True)
class MaskParams:
    """Thresholds of :func:`propose_structure_mask` (module docstring for their role).

    Parameters
    ----------
    blur_sigma_px : float
        Gaussian smoothing of each frame before the statistics, pixels.
    max_static_std : float
        Largest temporal standard deviation of a static pixel, grey levels (0-255).
    dark_fraction : float
        A pixel is dark below this fraction of the moving scene's median grey level.
    edge_min_grad : float
        Smallest gradient of the mean image at a static edge, grey levels per pixel.
    edge_static_ratio : float
        Smallest ratio of the mean image's gradient to the mean of the frames' gradients.
    edge_reach_px : int
        How far from a static edge a bright static pixel may be, pixels.
    link_px : int
        Parts closer than twice this are one part when deciding which touch the image border.
    open_fraction : float
        Radius of the opening disc as a fraction of the short side (at least 2 px).
    min_area_fraction : float
        Smallest part kept, fraction of the image.
    max_hole_fraction : float
        Largest hole filled, fraction of the image.
    dilate_px : int or None
        Final dilation radius, pixels; None: 0.3 % of the short side, at least 1 px.
    min_moving_fraction : float
        Fewer moving pixels than this fraction of the image: the footage is refused (nothing
        to tell the structure from).
    max_coverage : float
        A proposed mask above this fraction of the image is refused.
    compensate_exposure : bool
        Divide each frame by its exposure gain (:func:`exposure_gains`) first: a camera's
        automatic exposure otherwise makes the structure's grey levels vary with the scene's
        brightness.
    """

    blur_sigma_px: float = 1.0
    max_static_std: float = 6.0
    dark_fraction: float = 0.5
    edge_min_grad: float = 6.0
    edge_static_ratio: float = 0.6
    edge_reach_px: int = 3
    link_px: int = 3
    open_fraction: float = 0.008
    min_area_fraction: float = 0.002
    max_hole_fraction: float = 0.01
    dilate_px: int | None = None
    min_moving_fraction: float = 0.03
    max_coverage: float = 0.9
    compensate_exposure: bool = True

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            if (f.name == "dilate_px" and value is None) or f.name == "compensate_exposure":
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
                raise ValueError(f"mask parameter {f.name} must be a non-negative number, got {value!r}")
        for name in ("dark_fraction", "edge_static_ratio", "open_fraction", "min_area_fraction", "max_hole_fraction",
                     "min_moving_fraction", "max_coverage"):
            if getattr(self, name) > 1:
                raise ValueError(f"mask parameter {name} is a fraction (0-1), got {getattr(self, name)!r}")

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class StructureMask:
    """A proposed mask and the figures behind it.

    Attributes
    ----------
    mask : ndarray of bool, shape (H, W)
        True on the aircraft's structure (to be ignored by detection and tracking).
    coverage : float
        Fraction of the image masked.
    static_fraction, moving_fraction : float
        Fractions of the image found static and moving.
    scene_grey : float
        Median grey level of the moving scene.
    dark_level : float
        Grey level under which a static pixel counts as dark.
    frames : int
        Frames the statistics used.
    """

    mask: np.ndarray
    coverage: float
    static_fraction: float
    moving_fraction: float
    scene_grey: float
    dark_level: float
    frames: int

    def summary(self) -> str:
        return (f"{self.frames} frames: {100 * self.moving_fraction:.1f} % of the image moves with the scene, "
                f"{100 * self.static_fraction:.1f} % is static; dark below grey {self.dark_level:.0f} "
                f"(scene median {self.scene_grey:.0f}); proposed mask: {100 * self.coverage:.1f} % of the image")


def exposure_gains(frames) -> np.ndarray:
    """Each frame's exposure relative to the sequence: median over pixels of frame / temporal median.

    Computed on frames reduced 4x (area averaging) and on pixels brighter than 20 grey levels of
    the median image (the ratio of near-black pixels is noise). The moving scene's ratios scatter
    around 1, the static parts' ratios are the gain itself: the median follows the camera's
    automatic exposure as long as the scene does not change its overall brightness.

    Parameters
    ----------
    frames : sequence of ndarray, shape (H, W)
        Grey frames of one camera, any numeric dtype.

    Returns
    -------
    ndarray, shape (n_frames,)
        Gains, 1 for a frame exposed like the median (all ones when too few pixels are lit).
    """
    import cv2  # heavy import kept local: the core must start fast
    small = np.stack([cv2.resize(np.asarray(f, np.float32), None, fx=0.25, fy=0.25, interpolation=cv2.INTER_AREA)
                      for f in frames])
    reference = np.median(small, axis=0)
    lit = reference > 20.0
    if lit.sum() < 16:
        return np.ones(len(frames))
    return np.array([float(np.median(s[lit] / reference[lit])) for s in small])


def temporal_statistics(frames, blur_sigma_px: float = 1.0):
    """Per-pixel mean and standard deviation over frames, and the mean of the frames' gradients.

    Parameters
    ----------
    frames : iterable of ndarray, shape (H, W), uint8 or float
        Grey frames of one size.
    blur_sigma_px : float
        Gaussian smoothing of each frame first (0: none).

    Returns
    -------
    mean, std : ndarray, shape (H, W)
        Grey levels (float64).
    mean_gradient : ndarray, shape (H, W)
        Mean over frames of the gradient magnitude (grey levels per pixel; Sobel / 8).
    count : int
        Frames used.
    """
    import cv2  # heavy import kept local: the core must start fast
    total = total_sq = total_grad = None
    count = 0
    for frame in frames:
        grey = np.asarray(frame, dtype=np.float32)
        if blur_sigma_px > 0:
            grey = cv2.GaussianBlur(grey, (0, 0), blur_sigma_px)
        if total is None:
            total = np.zeros(grey.shape, np.float64)
            total_sq = np.zeros(grey.shape, np.float64)
            total_grad = np.zeros(grey.shape, np.float64)
        total += grey
        total_sq += grey.astype(np.float64) ** 2
        total_grad += _gradient_magnitude(grey)
        count += 1
    if count == 0:
        raise ValueError("no frames to compute the statistics from")
    mean = total / count
    std = np.sqrt(np.maximum(total_sq / count - mean ** 2, 0.0))
    return mean, std, total_grad / count, count


def _gradient_magnitude(grey) -> np.ndarray:
    import cv2  # heavy import kept local: the core must start fast
    gu = cv2.Sobel(grey, cv2.CV_32F, 1, 0, ksize=3) / 8.0
    gv = cv2.Sobel(grey, cv2.CV_32F, 0, 1, ksize=3) / 8.0
    return np.hypot(gu, gv).astype(np.float64)


def _disc(radius: int):
    import cv2  # heavy import kept local: the core must start fast
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1, 2 * radius + 1))


def propose_structure_mask(frames, params: MaskParams | None = None, source: str = "footage") -> StructureMask:
    """Propose the mask of the aircraft's structure from frames sampled across a sequence.

    Parameters
    ----------
    frames : list of ndarray, shape (H, W), uint8
        Grey frames spread over the footage (the farther apart, the more the scene moves).
    params : MaskParams
        Thresholds (module docstring).
    source : str
        Name of the footage for messages.
    """
    import cv2  # heavy import kept local: the core must start fast
    params = params or MaskParams()
    if len(frames) < 5:
        raise ValueError(f"{source}: {len(frames)} frame(s) sampled; at least 5 spread over the footage are needed")
    gains = exposure_gains(frames) if params.compensate_exposure else np.ones(len(frames))
    mean, std, mean_gradient, count = temporal_statistics(
        (np.asarray(f, np.float32) / g for f, g in zip(frames, gains)), params.blur_sigma_px)
    height, width = mean.shape
    n_pixels = height * width
    short_side = min(height, width)

    static = std <= params.max_static_std
    moving = std > 2.0 * params.max_static_std
    moving_fraction = float(moving.mean())
    if moving_fraction < params.min_moving_fraction:
        raise ValueError(f"{source}: only {100 * moving_fraction:.1f} % of the image changes over the {count} frames "
                         f"sampled (at least {100 * params.min_moving_fraction:.0f} % needed to tell the structure "
                         f"from the scene); give footage in which the aircraft moves")
    scene_grey = float(np.median(mean[moving]))
    dark_level = params.dark_fraction * scene_grey
    dark = mean < dark_level

    mean_grad = _gradient_magnitude(mean.astype(np.float32))
    static_edge = (mean_grad >= params.edge_min_grad) & (mean_grad >= params.edge_static_ratio * mean_gradient)
    reach = int(round(params.edge_reach_px))
    near_edge = cv2.dilate(static_edge.astype(np.uint8), _disc(reach)) > 0 if reach > 0 else static_edge
    candidate = (static & (dark | near_edge)).astype(np.uint8)

    # thin bands go: the horizon of a steady flight, static cloud edges
    radius = max(2, int(round(params.open_fraction * short_side)))
    candidate = cv2.morphologyEx(candidate, cv2.MORPH_OPEN, _disc(radius))

    # keep the parts attached to the image border (the airframe enters from outside the view);
    # parts within 2 link_px of each other count as attached: where two static parts of
    # different grey meet (wiper over frame), vibration makes the seam itself unsteady
    link = int(round(params.link_px))
    linked = cv2.dilate(candidate, _disc(link)) if link > 0 else candidate
    n, labels, stats, _ = cv2.connectedComponentsWithStats(linked, connectivity=8)
    keep = np.zeros(n, bool)
    for k in range(1, n):
        x, y, w, h, _ = stats[k]
        touches = x == 0 or y == 0 or x + w == width or y + h == height
        keep[k] = touches and np.count_nonzero(candidate[labels == k]) >= params.min_area_fraction * n_pixels
    mask = keep[labels] & (candidate > 0)

    # fill small holes (reflections, instruments); the view through the windshield stays open
    n, labels, stats, _ = cv2.connectedComponentsWithStats((~mask).astype(np.uint8), connectivity=4)
    for k in range(1, n):
        x, y, w, h, area = stats[k]
        inside = x > 0 and y > 0 and x + w < width and y + h < height
        if inside and area <= params.max_hole_fraction * n_pixels:
            mask |= labels == k

    dilate = params.dilate_px if params.dilate_px is not None else max(1, int(round(0.003 * short_side)))
    if dilate > 0:
        mask = cv2.dilate(mask.astype(np.uint8), _disc(int(dilate))) > 0
    coverage = float(mask.mean())
    if coverage > params.max_coverage:
        raise ValueError(f"{source}: the proposed mask covers {100 * coverage:.0f} % of the image (the scene hardly "
                         f"moves over the frames sampled, or is very dark); draw the mask by hand")
    return StructureMask(mask=mask, coverage=coverage, static_fraction=float(static.mean()),
                         moving_fraction=moving_fraction, scene_grey=scene_grey, dark_level=dark_level, frames=count)


def mask_picture(frame, mask: np.ndarray) -> np.ndarray:
    """Side-by-side check picture: the frame | the frame with the mask tinted red and outlined.

    Parameters
    ----------
    frame : ndarray, shape (H, W) or (H, W, 3), uint8
        A frame of the footage (grey or RGB).
    mask : ndarray of bool, shape (H, W)

    Returns
    -------
    ndarray, shape (H, 2 W + gap, 3), uint8, RGB
    """
    import cv2  # heavy import kept local: the core must start fast
    rgb = frame if frame.ndim == 3 else cv2.cvtColor(frame, cv2.COLOR_GRAY2RGB)
    tinted = rgb.astype(np.float32)
    red = np.array([255.0, 0.0, 0.0], np.float32)
    tinted[mask] = 0.45 * tinted[mask] + 0.55 * red
    tinted = np.clip(tinted, 0, 255).astype(np.uint8)
    contours, _ = cv2.findContours(mask.astype(np.uint8), cv2.RETR_LIST, cv2.CHAIN_APPROX_NONE)
    cv2.drawContours(tinted, contours, -1, (255, 255, 0), 1)
    gap = np.full((rgb.shape[0], 8, 3), 255, np.uint8)
    return np.concatenate([rgb, gap, tinted], axis=1)
