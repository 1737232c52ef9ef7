"""The template point tracker: N designated points followed frame to frame (thesis 5.3.2.1).

A pilot designates points once (the runway corners, or any ground points with texture);
:class:`PointTracker` then finds each one again in every new frame:

1. *Prediction*: the last position turned by the camera rotation between the two frames
   (inertial attitude, :func:`visland.tracking.motion.rotation_homography`) plus the last
   frame's remaining image motion.
2. *Matching*: normalised cross-correlation of the point's template in a window of
   ``search_radius_px`` around the prediction, sub-pixel refinement
   (:func:`visland.tracking.template.match_in_window`). The template is the reference cut at
   the last update, warped by the predicted ground-plane motion when ``scale_adaptation`` is
   on (a straight-line fit through the last rigid fits: :data:`MOTION_HISTORY`).
3. *Loss*: a refused match (low score, two similar peaks, peak on the window border) leaves
   the point *coasting*, not measured; after ``max_coast_frames`` it is *lost*. A point is
   never taken from a match outside its search window.
4. *Consistency*: the measured points must follow one ground-plane motion
   (:mod:`visland.tracking.rigid`); those that do not are flagged, re-projected or dropped
   (``on_inconsistent``). Coasting points are put where that motion places them, and lost
   points are looked for there (within the consistency threshold only), when it places them
   precisely.
5. *Anchoring* (optional): a confident detected corner close to the tracked point pulls it
   towards the detection (:mod:`visland.tracking.anchoring`); a far one is followed only by
   an untrusted point, after several agreeing detections.
6. *Template update*: by ``update_policy`` (:mod:`visland.tracking.params`: this is what
   makes the drift).

Every frame returns a :class:`TrackStep` with each point's status, position, score and the
reason for anything unusual. Pixels follow :mod:`visland.camera` (``(0, 0)`` the centre of the
top-left pixel, u right, v down).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from visland.camera import CameraModel
from visland.folder import scene_frame
from visland.runway import CORNER_NAMES
from visland.tracking.anchoring import AnchorObservation
from visland.tracking.motion import (Attitude, R_camera_from_level, rotation_homography,
                                     virtual_to_pixel_homography)
from visland.tracking.params import TrackerParams
from visland.tracking.rigid import PlaneMotion, check_consistency, prediction_std_px
from visland.tracking.template import (ReferencePatch, Texture, apply_homography, cut_reference, homography_jacobian,
                                       match_in_window, patch_texture, template_from_reference)

__all__ = ["PointTracker", "PointReport", "TrackStep", "MEASURED_STATUSES", "POINT_STATUSES"]

#: Rigid-motion fits kept to predict the ground-plane motion (a straight-line fit over about
#: 0.4 s at 25 Hz smooths the frame-to-frame scatter of the fits; a two-point extrapolation
#: amplifies it and, through the template warp, feeds it back into the matches).
MOTION_HISTORY = 10

#: Per-point statuses of a frame. Measured ones carry a position in the outputs.
POINT_STATUSES = ("designated", "tracked", "anchored", "reprojected", "inconsistent",
                  "coasting", "lost", "refused", "skipped")
MEASURED_STATUSES = frozenset({"designated", "tracked", "anchored", "reprojected", "inconsistent"})


@dataclass(frozen=True)
class PointReport:
    """One point in one frame.

    Attributes
    ----------
    name : str
        The point's name (a corner of :data:`visland.runway.CORNER_NAMES`, or an edge point).
    status : str
        One of :data:`POINT_STATUSES`; those of :data:`MEASURED_STATUSES` carry a position.
    uv : ndarray, shape (2,)
        Measured pixel position ``(u, v)`` (SPEC convention: (0, 0) at the centre of the
        top-left pixel, u right, v down); NaN unless ``measured``.
    score : float
        Normalised cross-correlation of the accepted or refused match, NaN if none.
    residual_px : float
        Distance in pixels to the rigid ground-plane motion of the points, NaN if not checked.
    reason : str
        What was unusual (empty when tracked normally).
    """

    name: str
    status: str
    uv: np.ndarray
    score: float
    residual_px: float
    reason: str

    @property
    def measured(self) -> bool:
        return self.status in MEASURED_STATUSES


@dataclass(frozen=True)
class TrackStep:
    """Everything the tracker says about one frame.

    Attributes
    ----------
    frame_index : int
        0-based index of the frame in the sequence given to the tracker.
    points : tuple of PointReport
        One report per tracked point, in the tracker's point order.
    motion : visland.tracking.rigid.PlaneMotion or None
        The ground-plane motion fitted to the points since the designation (None when it
        could not be fitted).
    consistency_checked : bool
        Whether the points were checked against one rigid runway motion this frame.
    anchor : AnchorObservation or None
        The anchor provider's observation used this frame (None when not anchored).
    note : str
        What happened to the frame as a whole (a skipped frame's reason), empty otherwise.
    """

    frame_index: int
    points: tuple
    motion: PlaneMotion | None = None
    consistency_checked: bool = False
    anchor: AnchorObservation | None = None
    note: str = ""

    def point(self, name: str) -> PointReport:
        for report in self.points:
            if report.name == name:
                return report
        raise ValueError(f"no tracked point named '{name}' (points: {', '.join(p.name for p in self.points)})")

    @property
    def anchored(self) -> bool:
        return any(p.status == "anchored" for p in self.points)

    def reason(self) -> str:
        """One line: the frame note, then each point that is not simply tracked, with why."""
        parts = [self.note] if self.note else []
        for p in self.points:
            if p.status in ("tracked", "designated") and not p.reason:
                continue
            parts.append(f"{p.name} {p.status}" + (f" ({p.reason})" if p.reason else ""))
        return "; ".join(parts)


@dataclass
class _Point:
    """Mutable state of one tracked point."""

    name: str
    corner: str | None
    status: str
    uv: np.ndarray
    reason: str = ""
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(2))
    reference: ReferencePatch | None = None
    texture: Texture | None = None
    cut_frame: int = 0
    cut_R_camera_from_level: np.ndarray | None = None
    cut_motion: PlaneMotion | None = None
    cut_configuration: dict = field(default_factory=dict)
    q_designation: np.ndarray | None = None    # designation coordinates (tracking.rigid), once known
    score: float = math.nan
    residual_px: float = math.nan
    coast_count: int = 0
    pending_anchor: list = field(default_factory=list)

    @property
    def active(self) -> bool:
        return self.status not in ("lost", "refused")

    @property
    def edge_normal(self):
        return self.texture.normal if (self.texture is not None and self.texture.kind == "edge") else None


class PointTracker:
    """Tracks designated image points through a sequence of grey frames (see the module docstring).

    Parameters
    ----------
    camera : :class:`visland.camera.CameraModel`
        Image size, intrinsics and mounting (for the inertial prediction and the rigid check).
    params : :class:`visland.tracking.TrackerParams`

    Use :meth:`start` on the designation frame, then :meth:`step` on each next frame (or
    :meth:`skip` for a frame that cannot be used). The inertial attitude is optional but
    enables the rotation-compensated prediction, the template warp and the rigid check; give
    it on every frame or on none.
    """

    def __init__(self, camera: CameraModel, params: TrackerParams | None = None):
        if not isinstance(camera, CameraModel):
            raise ValueError(f"camera must be a CameraModel, got {type(camera).__name__}")
        params = params or TrackerParams()
        if not isinstance(params, TrackerParams):
            raise ValueError(f"params must be TrackerParams, got {type(params).__name__}")
        self.camera = camera
        self.params = params
        self._points: list[_Point] = []
        self._frame = -1
        self._started = False
        self._heading_reference = None
        self._R_cam_from_level_before = None
        self._motions: list[tuple[int, PlaneMotion]] = []
        self._configuration: dict = {}
        self._reference_half = int(math.ceil(1.5 * params.half_template_px)) + 1

    # ----------------------------------------------------------------- public
    @property
    def point_names(self) -> tuple:
        return tuple(p.name for p in self._points)

    @property
    def frame_index(self) -> int:
        """Index of the last frame processed (-1 before :meth:`start`)."""
        return self._frame

    def start(self, image, designations, attitude: Attitude | None = None, frame_index: int = 0) -> TrackStep:
        """Designate the points on the first frame.

        Parameters
        ----------
        image : ndarray, shape (height, width), uint8 grey.
        designations : mapping name -> (u, v), or sequence of (name, (u, v)). Names in
            :data:`visland.runway.CORNER_NAMES` mark runway corners (which a detector can
            re-anchor); other names are free.
        attitude : inertial attitude at this frame (sets the level frame of the rigid check).
        frame_index : index of this frame in the sequence.

        Each point is refused, with its reason, if it lies outside the image, too close to the
        border for its template, or on a featureless patch. Raises ValueError if no point is
        usable or the arguments are malformed.
        """
        image = self._check_image(image, strict=True)
        items = list(designations.items()) if isinstance(designations, dict) else list(designations)
        if not items:
            raise ValueError("designations is empty: give at least one point to track")
        names = [str(name) for name, _ in items]
        if len(set(names)) != len(names):
            raise ValueError(f"designations name a point twice: {', '.join(names)}")
        if isinstance(frame_index, bool) or not isinstance(frame_index, (int, np.integer)) or frame_index < 0:
            raise ValueError(f"frame_index must be a non-negative integer, got {frame_index!r}")
        self._frame = int(frame_index)
        self._points = []
        self._motions = []
        R_cam_from_level = None
        if attitude is not None:
            self._heading_reference = float(attitude.heading_rad)
            R_cam_from_level = R_camera_from_level(attitude, self._heading_reference, self.camera)
        else:
            self._heading_reference = None
        self._R_cam_from_level_before = R_cam_from_level
        G_virtual_to_pixels = (virtual_to_pixel_homography(R_cam_from_level, self.camera)
                               if R_cam_from_level is not None else None)
        for name, uv in items:
            point = self._designate(image, str(name), uv)
            self._points.append(point)
        usable = [p for p in self._points if p.status == "designated"]
        if not usable:
            raise ValueError("no designated point can be tracked: "
                             + "; ".join(f"{p.name}: {p.reason}" for p in self._points))
        if G_virtual_to_pixels is not None:
            G_pixels_to_virtual = np.linalg.inv(G_virtual_to_pixels)
            for p in usable:
                p.q_designation = apply_homography(G_pixels_to_virtual, p.uv)
            self._motions.append((self._frame, PlaneMotion(1.0, np.zeros(2))))
        self._configuration = {p.name: p.uv.copy() for p in usable}
        for p in usable:
            p.cut_R_camera_from_level = R_cam_from_level
            p.cut_motion = self._motions[-1][1] if self._motions else None
            p.cut_configuration = dict(self._configuration)
        self._started = True
        return self._report(None, False, None, "designation")

    def skip(self, reason: str, frame_index: int | None = None) -> TrackStep:
        """Record a frame that cannot be used (unreadable, wrong size...): nothing is measured.

        The points keep their state; the next :meth:`step` predicts over the gap.
        """
        self._require_started()
        self._frame = self._next_index(frame_index)
        reports = tuple(PointReport(p.name, "skipped" if p.active else p.status, np.full(2, np.nan), math.nan,
                                    math.nan, p.reason if not p.active else "") for p in self._points)
        return TrackStep(self._frame, reports, note=f"frame skipped: {reason}")

    def step(self, image, attitude: Attitude | None = None, anchor: AnchorObservation | None = None,
             frame_index: int | None = None) -> TrackStep:
        """Track the points into a new frame.

        Parameters
        ----------
        image : ndarray, shape (height, width), uint8 grey, the size of the designation frame.
            A frame of another size is not used: the step reports it (as :meth:`skip`).
        attitude : inertial attitude at this frame (if it was given at :meth:`start`).
        anchor : corners found in this frame by a detector (optional re-anchoring).
        frame_index : index of this frame (default: the previous one plus one); a gap means
            frames were missed, and the prediction spans it.
        """
        self._require_started()
        image, problem = self._check_image(image, strict=False)
        if problem:
            return self.skip(problem, frame_index)
        index = self._next_index(frame_index)
        gap = index - self._frame
        self._frame = index
        params = self.params
        R_cam_from_level = None
        if attitude is not None and self._heading_reference is not None:
            R_cam_from_level = R_camera_from_level(attitude, self._heading_reference, self.camera)
        G_virtual_to_pixels = (virtual_to_pixel_homography(R_cam_from_level, self.camera)
                               if R_cam_from_level is not None else None)
        H_now_from_before = None
        if (R_cam_from_level is not None and self._R_cam_from_level_before is not None
                and params.use_inertial_prediction):
            H_now_from_before = rotation_homography(R_cam_from_level @ self._R_cam_from_level_before.T, self.camera)
        motion_guess = self._smoothed_motion(index) if G_virtual_to_pixels is not None else None

        bases = {}
        for p in self._points:
            p.residual_px = math.nan
            if not p.active:
                continue
            base = apply_homography(H_now_from_before, p.uv) if H_now_from_before is not None else p.uv.copy()
            bases[p.name] = base
            self._match(p, image, base + gap * p.velocity, motion_guess, G_virtual_to_pixels, R_cam_from_level)

        notes = []
        motion, checked, fit = None, False, None
        if G_virtual_to_pixels is not None:
            motion, checked, consistency_note, fit = self._check_rigid(G_virtual_to_pixels)
            notes.append(consistency_note)
        if anchor is not None:
            notes.append(self._apply_anchor(anchor, index, motion, G_virtual_to_pixels))
        note = "; ".join(x for x in notes if x)
        if motion is not None and (fit.decided or not fit.checked):
            self._motions = (self._motions + [(index, motion)])[-MOTION_HISTORY:]
            for p in self._points:
                if p.q_designation is None and p.status in MEASURED_STATUSES:
                    p.q_designation = motion.designation(apply_homography(np.linalg.inv(G_virtual_to_pixels), p.uv))
            self._follow_rigid_motion(image, motion, fit, G_virtual_to_pixels, R_cam_from_level)

        configuration = {p.name: p.uv.copy() for p in self._points if p.status in MEASURED_STATUSES}
        for p in self._points:
            if p.status in ("tracked", "inconsistent") and p.name in bases:
                p.velocity = (p.uv - bases[p.name]) / gap
        smoothed = self._smoothed_motion(index) if motion is not None else None
        for p in self._points:
            if p.status in MEASURED_STATUSES:
                self._maybe_update_template(p, image, index, R_cam_from_level, smoothed, configuration,
                                            G_virtual_to_pixels)
        self._configuration = configuration
        self._R_cam_from_level_before = R_cam_from_level
        return self._report(motion, checked, anchor, note)

    # ----------------------------------------------------------------- designation
    def _designate(self, image, name: str, uv) -> _Point:
        corner = name if name in CORNER_NAMES else None
        try:
            uv = np.asarray(uv, dtype=float).reshape(2)
        except (TypeError, ValueError):
            return _Point(name, corner, "refused", np.full(2, np.nan), reason=f"not a pixel position: {uv!r}")
        if not np.all(np.isfinite(uv)):
            return _Point(name, corner, "refused", np.full(2, np.nan), reason="designated position is not finite")
        where = f"({uv[0]:.1f}, {uv[1]:.1f})"
        if not self.camera.in_image(uv):
            return _Point(name, corner, "refused", uv,
                          reason=f"designated at {where}, outside the {self.camera.width}x{self.camera.height} image")
        reference = cut_reference(image, uv, self._reference_half)
        if reference is None:
            return _Point(name, corner, "refused", uv,
                          reason=f"designated at {where}, within {self._reference_half} px of the image border "
                                 f"(no room for its template)")
        texture = self._texture(reference)
        if texture.kind == "featureless":
            return _Point(name, corner, "refused", uv,
                          reason=f"featureless patch at {where} (gradient {texture.strong:.1f} < "
                                 f"{self.params.min_contrast:g} grey levels/px)")
        point = _Point(name, corner, "designated", uv, reference=reference, texture=texture, cut_frame=self._frame)
        if texture.kind == "edge":
            point.reason = (f"edge point (texture {texture.weak:.1f} < {self.params.min_texture:g}): "
                            "may slide along the edge")
        return point

    def _texture(self, reference: ReferencePatch) -> Texture:
        big, half = reference.half_px, self.params.half_template_px
        central = reference.pixels[big - half:big + half + 1, big - half:big + half + 1]
        return patch_texture(central, self.params.min_texture, self.params.min_contrast)

    # ----------------------------------------------------------------- matching
    def _warp_reference_from_image(self, p: _Point, predicted, motion_guess, G_virtual_to_pixels, R_cam_from_level,
                                   configuration=None):
        """2x2 map of displacements now -> in the reference image, or None if unknown.

        With the inertial attitude: the local derivative of the ground-plane homography from
        now to the cut (module :mod:`visland.tracking.rigid`), or of the rotation alone when
        no rigid motion is known. Without it: the similarity (scale and rotation) of the
        point configuration between the cut and now (``configuration``, default the last
        frame's), when at least two points are common to both.
        """
        if R_cam_from_level is None or p.cut_R_camera_from_level is None:
            similarity = _similarity(p.cut_configuration,
                                     self._configuration if configuration is None else configuration)
            if similarity is None:
                return None
            rotation = np.array([[similarity.real, similarity.imag], [-similarity.imag, similarity.real]])
            return rotation / abs(similarity) ** 2
        G_cut = virtual_to_pixel_homography(p.cut_R_camera_from_level, self.camera)
        if motion_guess is not None and p.cut_motion is not None:
            # pixels now -> designation coordinates -> pixels at the cut (module rigid)
            S_cut = np.array([[p.cut_motion.scale, 0, p.cut_motion.shift[0]],
                              [0, p.cut_motion.scale, p.cut_motion.shift[1]], [0, 0, 1.0]])
            S_now_inv = np.array([[1.0, 0, -motion_guess.shift[0]], [0, 1.0, -motion_guess.shift[1]],
                                  [0, 0, motion_guess.scale]]) / motion_guess.scale
            H_cut_from_now = G_cut @ S_cut @ S_now_inv @ np.linalg.inv(G_virtual_to_pixels)
        else:
            H_cut_from_now = rotation_homography(p.cut_R_camera_from_level @ R_cam_from_level.T, self.camera)
        A = homography_jacobian(H_cut_from_now, predicted)
        if not np.all(np.isfinite(A)) or abs(np.linalg.det(A)) < 1e-6:
            return None
        return A

    def _match(self, p: _Point, image, predicted, motion_guess, G_virtual_to_pixels, R_cam_from_level) -> None:
        params = self.params
        half = params.half_template_px
        margin = half - params.border_margin_px
        width, height = self.camera.width, self.camera.height
        if not (np.all(np.isfinite(predicted)) and margin - 0.5 <= predicted[0] <= width - 0.5 - margin
                and margin - 0.5 <= predicted[1] <= height - 0.5 - margin):
            self._lose(p, f"left the image (predicted at ({predicted[0]:.0f}, {predicted[1]:.0f}))")
            return
        if p.reference is None:
            self._lose(p, "no template (the last cut was featureless or at the border)")
            return
        A = self._warp_reference_from_image(p, predicted, motion_guess, G_virtual_to_pixels, R_cam_from_level)
        template, offset = template_from_reference(p.reference, params.template_size_px,
                                                   A if params.scale_adaptation else None)
        match = match_in_window(image, template, offset, predicted, params.search_radius_px, params.min_score,
                                params.ambiguity_margin, params.ambiguity_distance_px, params.subpixel)
        p.score = match.score
        if match.found:
            p.uv = match.uv
            p.status = "tracked"
            p.reason = ""
            p.coast_count = 0
            return
        p.coast_count += 1
        p.uv = np.asarray(predicted, dtype=float)
        if p.coast_count > params.max_coast_frames:
            self._lose(p, f"{match.reason}; no match for {p.coast_count} frames")
        else:
            p.status = "coasting"
            p.reason = f"{match.reason}; coasting {p.coast_count}/{params.max_coast_frames}"

    def _lose(self, p: _Point, reason: str) -> None:
        p.status = "lost"
        p.reason = reason
        p.velocity = np.zeros(2)

    def _reliable_limit_px(self) -> float:
        """Largest standard deviation of a rigid prediction that the tracker acts on."""
        return self.params.consistency_threshold_px / 2.0

    def _follow_rigid_motion(self, image, motion, fit, G_virtual_to_pixels, R_cam_from_level) -> None:
        """Put coasting points where the rigid motion puts them, and look for lost ones there.

        Only where the motion places the point precisely (standard deviation under half the
        consistency threshold): a loose prediction would send the search, and the point,
        somewhere else.
        """
        if fit is None or fit.information is None or not fit.decided:
            return
        params = self.params
        for p in self._points:
            if p.q_designation is None or p.status not in ("coasting", "lost"):
                continue
            std = float(prediction_std_px(motion, fit.information, p.q_designation, G_virtual_to_pixels,
                                          params.consistency_sigma_px)[0])
            if not std <= self._reliable_limit_px():
                continue
            predicted = motion.pixels(p.q_designation, G_virtual_to_pixels)
            if p.status == "coasting":
                p.uv = predicted
                continue
            if p.reference is None:
                continue
            half = params.half_template_px
            if not (np.all(np.isfinite(predicted)) and half <= predicted[0] <= self.camera.width - 1 - half
                    and half <= predicted[1] <= self.camera.height - 1 - half):
                continue
            radius = params.consistency_threshold_px + 3.0 * std
            A = self._warp_reference_from_image(p, predicted, motion, G_virtual_to_pixels, R_cam_from_level)
            template, offset = template_from_reference(p.reference, params.template_size_px,
                                                       A if params.scale_adaptation else None)
            match = match_in_window(image, template, offset, predicted, int(math.ceil(radius)) + 1,
                                    params.min_score, params.ambiguity_margin, params.ambiguity_distance_px,
                                    params.subpixel)
            distance = float(np.hypot(*(match.uv - predicted))) if match.found else math.inf
            if distance <= radius:
                p.uv = match.uv
                p.score = match.score
                p.status = "tracked"
                p.coast_count = 0
                p.velocity = np.zeros(2)
                p.reason = f"re-acquired {distance:.1f} px from where the other points put it"

    # ----------------------------------------------------------------- anchoring
    def _apply_anchor(self, anchor: AnchorObservation, index: int, motion, G_virtual_to_pixels) -> str:
        """Re-anchor corners on confident detections (after the rigid check of this frame).

        The detection is refused as a whole when a corner of a point tracked consistently
        (status tracked after the rigid check) lies beyond ``anchor_gate_px`` of its track: a
        detector can lock onto a taxiway or a road, and then every corner it gives is wrong.
        Otherwise a detection within the gate pulls the point towards it by ``anchor_weight``,
        and a farther one is followed only by an untrusted point (coasting, lost, refused, or
        inconsistent with the others), after ``anchor_confirm_frames`` consecutive detections
        agree.
        """
        params = self.params
        if not anchor.found:
            for p in self._points:
                p.pending_anchor = []
            return f"anchor: none ({anchor.reason})" if anchor.reason else "anchor: none"
        if anchor.confidence < params.anchor_min_confidence:
            for p in self._points:
                p.pending_anchor = []
            return f"anchor: not used (confidence {anchor.confidence:.2f} < {params.anchor_min_confidence:.2f})"
        G_pixels_to_virtual = np.linalg.inv(G_virtual_to_pixels) if G_virtual_to_pixels is not None else None
        # the detection as a whole must agree with the points tracked consistently: a detector
        # locked onto another object (a taxiway, a road) is refused for every point
        disagreeing = []
        for p in self._points:
            detected = anchor.corner(p.corner) if p.corner is not None else None
            if detected is not None and p.status == "tracked":
                distance = float(np.hypot(*(detected - p.uv)))
                if distance > params.anchor_gate_px:
                    disagreeing.append(f"{p.name} {distance:.0f} px")
        if disagreeing:
            for p in self._points:
                p.pending_anchor = []
            return (f"anchor: refused (detected corners away from consistent tracks: {', '.join(disagreeing)}; "
                    f"gate {params.anchor_gate_px:g} px)")
        for p in self._points:
            if p.corner is None:
                continue
            detected = anchor.corner(p.corner)
            if detected is None:
                p.pending_anchor = []
                continue
            has_position = p.status in MEASURED_STATUSES or p.status == "coasting"
            distance = float(np.hypot(*(detected - p.uv))) if has_position else math.inf
            if distance <= params.anchor_gate_px:
                w = params.anchor_weight
                self._anchor_point(p, p.uv + w * (detected - p.uv),
                                   f"anchored: detected {distance:.1f} px from the track, weight {w:g}")
            else:
                # a chain of detections on consecutive frames, each within the gate of the one before
                pending = list(p.pending_anchor)
                if pending and (pending[-1][0] != index - 1
                                or np.hypot(*(detected - pending[-1][1])) > params.anchor_gate_px):
                    pending = []
                pending.append((index, detected))
                p.pending_anchor = pending[-params.anchor_confirm_frames:]
                if len(p.pending_anchor) < params.anchor_confirm_frames:
                    gap = f"{distance:.0f} px away" if has_position else f"found while {p.status}"
                    note = (f"detected corner {gap} (gate {params.anchor_gate_px:g} px): not followed yet "
                            f"({len(p.pending_anchor)}/{params.anchor_confirm_frames})")
                    p.reason = f"{p.reason}; {note}" if p.reason else note
                    continue
                where = f"{distance:.0f} px from the track" if has_position else f"while {p.status}"
                self._anchor_point(p, detected, f"re-anchored {where} after {len(p.pending_anchor)} "
                                               "agreeing detections")
            if motion is not None and G_pixels_to_virtual is not None:
                # the detector is trusted over the designation: re-base the point's plane position
                p.q_designation = motion.designation(apply_homography(G_pixels_to_virtual, p.uv))
        return ""

    def _anchor_point(self, p: _Point, detected, reason: str) -> None:
        p.uv = np.asarray(detected, dtype=float).copy()
        p.status = "anchored"
        p.reason = reason
        p.coast_count = 0
        p.pending_anchor = []
        p.score = math.nan

    # ----------------------------------------------------------------- rigid check
    def _check_rigid(self, G_virtual_to_pixels):
        """Rigid check of the measured points: (motion, checked, note, ConsistencyResult or None)."""
        params = self.params
        members = [p for p in self._points if p.status in MEASURED_STATUSES and p.q_designation is not None]
        if len(members) < 2:
            return None, False, "", None
        uv = np.array([p.uv for p in members])
        q = np.array([p.q_designation for p in members])
        normals = [p.edge_normal for p in members]
        threshold = params.consistency_threshold_px + params.consistency_threshold_fraction * \
            self._configuration_size(uv)
        result = check_consistency(q, uv, G_virtual_to_pixels, threshold, normals, params.consistency_sigma_px)
        if result.motion is None:
            return None, False, "", None
        for k, p in enumerate(members):
            p.residual_px = float(result.residual_px[k])
        if not result.checked:
            return result.motion, False, "", result
        if not result.decided:
            worst = float(np.nanmax(result.residual_px))
            names = ", ".join(p.name for p in members)
            return result.motion, True, (f"points {names} disagree with one rigid runway motion by up to "
                                         f"{2 * worst:.1f} px (> {threshold:.1f}); too few points to tell which "
                                         "drifts"), result
        for k, p in enumerate(members):
            if result.consistent[k]:
                continue
            residual = float(result.residual_px[k])
            std = float(result.prediction_std_px[k])
            text = f"{residual:.1f} px off the rigid motion of the others (> {threshold:.1f} + 3 x {std:.1f})"
            action = params.on_inconsistent
            if action == "reproject" and not std <= self._reliable_limit_px():
                action = "flag"
                text += f"; not moved (the others place it only to +-{std:.1f} px)"
            if action == "flag":
                p.status = "inconsistent"
                p.reason = text
            elif action == "reproject":
                p.uv = result.motion.pixels(p.q_designation, G_virtual_to_pixels)
                p.status = "reprojected"
                p.reason = text + "; moved onto it"
            else:
                self._lose(p, text + "; dropped")
        return result.motion, True, "", result

    def _smoothed_motion(self, index: int) -> PlaneMotion | None:
        """Ground-plane motion at frame ``index`` from the recent rigid fits.

        A straight line through the last fits (log-scale and shift against the frame index,
        least squares) evaluated at ``index``: constant-rate motion, which over
        :data:`MOTION_HISTORY` frames is what an approach does; fewer than three fits give
        the last one. None when the last fit is more than a second (25 frames) old.
        """
        if not self._motions:
            return None
        frames = np.array([k for k, _ in self._motions], dtype=float)
        if index - frames[-1] > 25:
            return None
        if len(self._motions) < 3:
            return self._motions[-1][1]
        log_scale = np.log([m.scale for _, m in self._motions])
        shift = np.array([m.shift for _, m in self._motions])
        t = frames - frames[-1]
        design = np.column_stack([np.ones_like(t), t])
        coefficients, *_ = np.linalg.lstsq(design, np.column_stack([log_scale, shift]), rcond=None)
        at = np.array([1.0, index - frames[-1]]) @ coefficients
        if not np.all(np.isfinite(at)):
            return self._motions[-1][1]
        return PlaneMotion(float(np.exp(at[0])), at[1:].copy())

    # ----------------------------------------------------------------- template update
    def _magnification(self, p: _Point, R_cam_from_level, motion, G_virtual_to_pixels, configuration) -> float:
        """How much the ground around the point has grown in the image since its reference was cut."""
        A = self._warp_reference_from_image(p, p.uv, motion, G_virtual_to_pixels, R_cam_from_level, configuration)
        if A is None:
            return 1.0
        return 1.0 / math.sqrt(abs(float(np.linalg.det(A))))

    def _maybe_update_template(self, p: _Point, image, index, R_cam_from_level, motion, configuration,
                               G_virtual_to_pixels) -> None:
        params = self.params
        policy = params.update_policy
        if p.status in ("anchored", "reprojected"):
            cut = True          # the point moved: its old template is centred elsewhere
        elif policy == "every_frame":
            cut = True
        elif policy == "every_n":
            cut = index - p.cut_frame >= params.update_every_n
        elif policy == "score_drop":
            cut = math.isfinite(p.score) and p.score < params.update_score_below
        elif policy == "scale_change":
            magnification = self._magnification(p, R_cam_from_level, motion, G_virtual_to_pixels, configuration)
            cut = max(magnification, 1.0 / magnification) >= params.update_scale_ratio
        else:
            cut = False
        if not cut:
            return
        reference = cut_reference(image, p.uv, self._reference_half)
        if reference is None:
            return          # too close to the border to cut: keep the previous reference
        texture = self._texture(reference)
        if texture.kind == "featureless":
            p.reference = None
            p.reason = (f"{p.reason}; " if p.reason else "") + "template cut here is featureless"
            return
        p.reference = reference
        p.texture = texture
        p.cut_frame = index
        p.cut_R_camera_from_level = R_cam_from_level
        p.cut_motion = motion
        p.cut_configuration = dict(configuration)

    # ----------------------------------------------------------------- helpers
    def _report(self, motion, checked, anchor, note) -> TrackStep:
        reports = []
        for p in self._points:
            measured = p.status in MEASURED_STATUSES
            reports.append(PointReport(p.name, p.status, p.uv.copy() if measured else np.full(2, np.nan),
                                       float(p.score), float(p.residual_px), p.reason))
        return TrackStep(self._frame, tuple(reports), motion, checked, anchor, note)

    @staticmethod
    def _configuration_size(uv_list) -> float:
        """RMS distance of the points to their centroid, in pixels (NaN under two points)."""
        uv = np.asarray([u for u in uv_list if np.all(np.isfinite(u))], dtype=float).reshape(-1, 2)
        if len(uv) < 2:
            return math.nan
        return float(np.sqrt(np.mean(np.sum((uv - uv.mean(axis=0)) ** 2, axis=1))))

    def _check_image(self, image, strict: bool):
        """Validate a grey frame (as the camera took it) and return its pinhole image. strict: raise on
        any problem; else return (image, problem) for size problems."""
        if not isinstance(image, np.ndarray):
            raise ValueError(f"image must be a numpy array, got {type(image).__name__}")
        if image.ndim != 2:
            raise ValueError(f"image must be a 2-D grey image (height, width), got shape {image.shape}")
        if image.dtype != np.uint8:
            raise ValueError(f"image must be uint8 grey levels, got {image.dtype}")
        expected = (self.camera.height, self.camera.width)
        if image.shape != expected:
            problem = (f"image is {image.shape[1]}x{image.shape[0]}, the tracker's camera is "
                       f"{self.camera.width}x{self.camera.height}")
            if strict:
                raise ValueError(problem)
            return image, problem
        # points are tracked and reported in the pinhole image (SPEC): a frame through a
        # distorting lens is resampled first, the aircraft's structure filled with the scene
        image = scene_frame(image, self.camera)
        return image if strict else (image, "")

    def _require_started(self):
        if not self._started:
            raise ValueError("the tracker has no points yet: call start(image, designations) first")

    def _next_index(self, frame_index):
        if frame_index is None:
            return self._frame + 1
        if isinstance(frame_index, bool) or not isinstance(frame_index, (int, np.integer)) or frame_index <= self._frame:
            raise ValueError(f"frame_index must be an integer after the last frame {self._frame}, got {frame_index!r}")
        return int(frame_index)


def _similarity(before: dict, after: dict) -> complex | None:
    """Scale-and-rotation ``a`` (complex) best mapping the common points: ``after ~ a before`` (centred).

    Least squares in complex form: ``a = sum conj(z_before) z_after / sum |z_before|^2`` over
    the points both configurations hold (at least two, spread over more than a pixel).
    """
    names = [n for n in before if n in after]
    if len(names) < 2:
        return None
    z0 = np.array([complex(*before[n]) for n in names])
    z1 = np.array([complex(*after[n]) for n in names])
    z0 = z0 - z0.mean()
    z1 = z1 - z1.mean()
    energy = float(np.sum(np.abs(z0) ** 2))
    if energy < 1.0:
        return None
    a = complex(np.sum(np.conj(z0) * z1) / energy)
    return a if np.isfinite(a) and abs(a) > 1e-3 else None
