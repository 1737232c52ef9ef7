"""Parameters of the template point tracker: one frozen dataclass, validated, JSON/TOML round trip.

The template update policy (:attr:`TrackerParams.update_policy`) is the parameter that makes
or prevents drift (thesis 5.3.2.1: "the algorithm matches the two most similar pixels, which
are never exactly identical; this correlation repeated over many cycles makes the tracked
point drift"):

``"every_frame"``
    Re-cut the template around the new estimate after every match (the thesis's "Memo"
    behaviour). Follows any change of appearance, but each frame's matching error becomes
    the next frame's reference: the errors add up as a random walk plus any bias (drift).
    On rendered 2048 px approaches it drifts by tenths of a pixel per frame on the small,
    noisy corners seen from 5 km and loses them within seconds.
``"every_n"``
    Re-cut every :attr:`update_every_n` frames: the error accumulates N times more slowly,
    while the appearance change between updates must stay small enough to match.
``"score_drop"``
    Keep the reference until its match score falls below :attr:`update_score_below`, then
    re-cut: as few updates as the appearance change allows.
``"scale_change"`` (default)
    Re-cut when the image of the ground around the point has been magnified (or shrunk) by
    more than :attr:`update_scale_ratio` since the reference was cut (about 15 re-cuts from
    5 km to the threshold at 1.25); in between, the reference is warped by the predicted
    ground-plane motion. Few re-cuts, so little accumulated error, and a reference that
    still looks like the runway: the default because it drifted least on the rendered
    thesis approaches (benchmarks/track_drift.py).
``"never"``
    Keep the designation template for the whole approach: no accumulation at all, but the
    runway grows about thirty times in the image; without scale adaptation the point is lost
    (and reported lost) once the reference no longer matches.

:attr:`scale_adaptation` warps the kept reference by the predicted ground-plane motion
(scale, rotation and perspective, from the inertial attitude and the tracked point
configuration, see :mod:`visland.tracking.rigid`) before matching, so a kept reference still
matches as the runway grows; it matters for every policy but ``"every_frame"``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from visland.params import ParamsFile

__all__ = ["TrackerParams", "UPDATE_POLICIES", "INCONSISTENT_ACTIONS"]

UPDATE_POLICIES = ("every_frame", "every_n", "score_drop", "scale_change", "never")
#: What the tracker does with a point that does not move with the others (rigid check).
INCONSISTENT_ACTIONS = ("flag", "reproject", "drop")


@dataclass(frozen=True)
class TrackerParams(ParamsFile):
    """Template tracker parameters (all pixel sizes for the image being tracked).

    Parameters
    ----------
    template_size_px : int
        Side of the square template (odd), centred on the tracked point.
    search_radius_px : int
        Half-side of the search window around the predicted position: the largest
        prediction error the tracker can absorb in one frame. A match is never accepted
        outside it, so a point can never jump further than this between frames.
    update_policy : str
        One of :data:`UPDATE_POLICIES` (see the module docstring: this makes the drift).
    update_every_n : int
        Frames between template updates for ``"every_n"``.
    update_score_below : float
        Match score under which ``"score_drop"`` re-cuts the template.
    update_scale_ratio : float
        Magnification (> 1) since the last cut at which ``"scale_change"`` re-cuts.
    scale_adaptation : bool
        Warp the reference template by the predicted ground-plane motion before matching.
    use_inertial_prediction : bool
        Centre the search window on the last position turned by the camera rotation between
        the frames (from the inertial attitude) plus the last image motion; else on the last
        position plus the last image motion only.
    subpixel : str
        Sub-pixel refinement of the correlation peak: ``"gradient"`` (Gauss-Newton on the
        normalised difference, about 0.05 px on rendered runway corners) or ``"parabola"``
        (three-point parabola through the correlation scores: cheaper, biased towards whole
        pixels by up to a few tenths of a pixel on sharp peaks, so it drifts faster when the
        template is re-cut every frame).
    min_score : float
        Normalised cross-correlation (OpenCV ``TM_CCOEFF_NORMED``, in [-1, 1]) under which a
        match is refused (the point coasts, then is lost).
    ambiguity_margin : float
        A second peak, at least :attr:`ambiguity_distance_px` from the best one, scoring within
        this margin of it makes the match ambiguous (refused: the point coasts).
    ambiguity_distance_px : float
        Distance beyond which a second peak counts as another match.
    max_coast_frames : int
        Consecutive frames without an accepted match after which a point is declared lost.
    min_texture : float
        Smallest RMS image gradient (grey levels per pixel) along the weakest direction of a
        template (square root of the structure tensor's small eigenvalue) for a corner-like
        point. Under it, the point is an edge point (matched across the edge only) if the
        strong direction reaches :attr:`min_contrast`, else a featureless patch (refused).
    min_contrast : float
        Smallest RMS gradient along the strongest direction of a usable template.
    border_margin_px : int
        A point whose template would cross the image border by more than this is lost
        ("left the image").
    consistency_threshold_px : float
        Largest pixel distance between a point and where the rigid runway motion fitted on
        the other points puts it (:mod:`visland.tracking.rigid`); beyond it the point is
        "inconsistent".
    consistency_threshold_fraction : float
        Added to the threshold as a fraction of the point configuration's size in pixels
        (model errors grow with the image of the runway).
    consistency_sigma_px : float
        Matching noise of one coordinate assumed by the rigid check (0.2 px: the frame-to-frame
        scatter of matches on rendered runway corners): a point is inconsistent only beyond the
        threshold plus three standard deviations of where the others place it, and it is
        re-projected, or searched for when lost, there only when that standard deviation is
        under half of ``consistency_threshold_px``.
    on_inconsistent : str
        ``"flag"`` (report it, keep tracking), ``"reproject"`` (move the point to where the
        rigid motion puts it and re-cut its template there: the several-points remedy of
        thesis 5.3.2.1) or ``"drop"`` (declare the point lost).
    anchor_min_confidence : float
        Smallest detector confidence at which a detected corner re-anchors a tracked one.
    anchor_weight : float
        In (0, 1]: a confident detected corner within the gate moves the tracked point this
        fraction of the way to it (1: onto it). Under 1 the detector's frame-to-frame noise
        is averaged while the tracker's drift stays bounded (a complementary filter: the
        track follows the detections with a lag of about ``1 / anchor_weight`` frames).
    anchor_gate_px : float
        A detected corner further than this from the tracked point does not re-anchor it; if
        that point is tracked consistently, the whole detection is refused (the detector has
        locked onto something else: no jump to a far-away match) ...
    anchor_confirm_frames : int
        ... and a point that is coasting, lost, refused or inconsistent with the others jumps
        to the detection only after this many consecutive confident detections agree on it
        (within the gate of one another); the jump is reported.
    """

    params_kind: ClassVar[str] = "tracker"
    toml_table: ClassVar[str | None] = "tracker"


    template_size_px: int = 31
    search_radius_px: int = 16
    update_policy: str = "scale_change"
    update_every_n: int = 10
    update_score_below: float = 0.9
    update_scale_ratio: float = 1.25
    scale_adaptation: bool = True
    use_inertial_prediction: bool = True
    subpixel: str = "gradient"
    min_score: float = 0.6
    ambiguity_margin: float = 0.02
    ambiguity_distance_px: float = 4.0
    max_coast_frames: int = 5
    min_texture: float = 0.5
    min_contrast: float = 1.0
    border_margin_px: int = 0
    consistency_threshold_px: float = 3.0
    consistency_threshold_fraction: float = 0.01
    consistency_sigma_px: float = 0.2
    on_inconsistent: str = "flag"
    anchor_min_confidence: float = 0.5
    anchor_weight: float = 0.5
    anchor_gate_px: float = 12.0
    anchor_confirm_frames: int = 3

    def __post_init__(self):
        def integer(name, low, high):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
                raise ValueError(f"tracker {name} must be an integer in [{low}, {high}], got {value!r}")

        def number(name, low, high):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                    or not low <= value <= high:
                raise ValueError(f"tracker {name} must be a number in [{low:g}, {high:g}], got {value!r}")

        integer("template_size_px", 5, 201)
        if self.template_size_px % 2 == 0:
            raise ValueError(f"tracker template_size_px must be odd (the point is its centre pixel), "
                             f"got {self.template_size_px}")
        integer("search_radius_px", 2, 500)
        if self.update_policy not in UPDATE_POLICIES:
            raise ValueError(f"tracker update_policy must be one of {', '.join(UPDATE_POLICIES)}, "
                             f"got {self.update_policy!r}")
        integer("update_every_n", 1, 100000)
        number("update_score_below", -1.0, 1.0)
        number("update_scale_ratio", 1.01, 10.0)
        for name in ("scale_adaptation", "use_inertial_prediction"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"tracker {name} must be true or false, got {getattr(self, name)!r}")
        if self.subpixel not in ("gradient", "parabola"):
            raise ValueError(f"tracker subpixel must be 'gradient' or 'parabola', got {self.subpixel!r}")
        number("min_score", -1.0, 1.0)
        number("ambiguity_margin", 0.0, 2.0)
        number("ambiguity_distance_px", 1.0, 1000.0)
        integer("max_coast_frames", 0, 100000)
        number("min_texture", 0.0, 255.0)
        number("min_contrast", 0.0, 255.0)
        integer("border_margin_px", 0, 1000)
        number("consistency_threshold_px", 0.0, 10000.0)
        number("consistency_threshold_fraction", 0.0, 1.0)
        number("consistency_sigma_px", 0.001, 100.0)
        if self.on_inconsistent not in INCONSISTENT_ACTIONS:
            raise ValueError(f"tracker on_inconsistent must be one of {', '.join(INCONSISTENT_ACTIONS)}, "
                             f"got {self.on_inconsistent!r}")
        number("anchor_min_confidence", 0.0, 1.0)
        number("anchor_weight", 0.01, 1.0)
        number("anchor_gate_px", 0.0, 10000.0)
        integer("anchor_confirm_frames", 1, 1000)

    @property
    def half_template_px(self) -> int:
        return self.template_size_px // 2

    # ----------------------------------------------------------------- files