"""Anchors: runway corners found by some other means, to re-anchor drifting tracked points.

Thesis 5.3.2.1: "another solution is to use a detection algorithm to recompute the point to
track". An *anchor provider* is any callable ``provider(frame_index, image) ->
AnchorObservation``; the tracker takes the detected corners that are confident, close to
the tracked points (or confirmed over several frames) and re-cuts the templates there
(:meth:`visland.tracking.PointTracker.step`).

Providers here:

- :func:`labels_anchor_provider`: the exact corners of a ``labels.csv`` (a perfect
  detector, for tests and to separate tracking errors from detection errors);
- :func:`detector_anchor_provider`: :func:`visland.detection.detect_runway` on each frame,
  with the inertial roll and pitch of the frame.

Pixels follow :mod:`visland.camera` (``(0, 0)`` the centre of the top-left pixel); lines are
SPEC ``(rho, theta)`` in normalised coordinates, theta in [-pi/2, pi/2).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from visland.runway import CORNER_NAMES

__all__ = ["AnchorObservation", "labels_anchor_provider", "detector_anchor_provider", "LINE_NAMES"]

LINE_NAMES = ("left", "right", "center")


@dataclass(frozen=True)
class AnchorObservation:
    """Corners found in one frame by an anchor provider.

    Attributes
    ----------
    found : bool
        Whether the provider found the runway at all.
    reason : str
        Why not (or a note), one short sentence.
    confidence : float
        In [0, 1]; the tracker ignores observations under ``anchor_min_confidence``.
    corners_uv : ndarray, shape (4, 2)
        Pixels of the corners in :data:`visland.runway.CORNER_NAMES` order (NaN if not found).
    corners_found : ndarray of bool, shape (4,)
    lines : dict
        ``{"left"|"right"|"center": (rho, theta_rad)}`` SPEC lines the provider measured
        (copied into the measurements of anchored frames); empty if none.
    dF_px, dpsi_rad : float
        Vanishing-point heading measurement (seed 001 eq. 18-19), NaN if none.
    """

    found: bool
    reason: str
    confidence: float
    corners_uv: np.ndarray
    corners_found: np.ndarray
    lines: dict = field(default_factory=dict)
    dF_px: float = math.nan
    dpsi_rad: float = math.nan

    def __post_init__(self):
        corners = np.asarray(self.corners_uv, dtype=float)
        if corners.shape != (4, 2):
            raise ValueError(f"corners_uv must have shape (4, 2), got {corners.shape}")
        found = np.asarray(self.corners_found, dtype=bool)
        if found.shape != (4,):
            raise ValueError(f"corners_found must have shape (4,), got {found.shape}")
        if not (math.isfinite(self.confidence) and 0.0 <= self.confidence <= 1.0):
            raise ValueError(f"confidence must lie in [0, 1], got {self.confidence!r}")
        object.__setattr__(self, "corners_uv", corners)
        object.__setattr__(self, "corners_found", found & np.all(np.isfinite(corners), axis=1))

    def corner(self, name: str) -> np.ndarray | None:
        """Pixel of a found corner, or None."""
        k = CORNER_NAMES.index(name)
        return self.corners_uv[k].copy() if self.corners_found[k] else None

    @classmethod
    def nothing(cls, reason: str) -> "AnchorObservation":
        return cls(False, reason, 0.0, np.full((4, 2), np.nan), np.zeros(4, dtype=bool))


def labels_anchor_provider(labels, every_n: int = 1):
    """A perfect detector reading the exact corners of a labels table.

    Parameters
    ----------
    labels : :class:`visland.contracts.Table` from :func:`visland.contracts.read_labels`
        (or any mapping with the labels columns), one row per frame.
    every_n : anchor on every ``every_n``-th frame only (a slow detector); other frames
        report nothing.
    """
    if isinstance(every_n, bool) or not isinstance(every_n, int) or every_n < 1:
        raise ValueError(f"every_n must be a positive integer, got {every_n!r}")
    corners = np.stack([np.stack([np.asarray(labels[f"{c}_u_px"], dtype=float),
                                  np.asarray(labels[f"{c}_v_px"], dtype=float)], axis=-1)
                        for c in CORNER_NAMES], axis=1)                                  # (n, 4, 2)
    visible = np.stack([np.asarray(labels[f"{c}_visible"], dtype=float) == 1 for c in CORNER_NAMES], axis=1)
    lines = {name: (np.asarray(labels[f"{name}_rho"], dtype=float), np.asarray(labels[f"{name}_theta_rad"], dtype=float))
             for name in LINE_NAMES}
    dF = np.asarray(labels["dF_px"], dtype=float)
    dpsi = np.radians(np.asarray(labels["dpsi_deg"], dtype=float))
    n = len(corners)

    def provider(frame_index: int, image=None) -> AnchorObservation:
        if not 0 <= frame_index < n:
            return AnchorObservation.nothing(f"no label row for frame {frame_index}")
        if frame_index % every_n:
            return AnchorObservation.nothing(f"labels used every {every_n} frames")
        found = visible[frame_index]
        frame_lines = {name: (float(r[frame_index]), float(t[frame_index])) for name, (r, t) in lines.items()
                       if math.isfinite(r[frame_index]) and math.isfinite(t[frame_index])}
        return AnchorObservation(bool(found.any()), "" if found.any() else "no corner visible", 1.0,
                                 corners[frame_index], found, frame_lines, float(dF[frame_index]),
                                 float(dpsi[frame_index]))

    return provider


def detector_anchor_provider(camera, inertial, params=None, track_previous: bool = True, detections=None):
    """Anchors from :func:`visland.detection.detect_runway` (imported here: a heavy stage).

    Parameters
    ----------
    camera : :class:`visland.camera.CameraModel`
    inertial : :class:`visland.sensors.InertialSeries` (roll and pitch at each frame).
    params : ``visland.detection.DetectorParams`` or None for the defaults.
    track_previous : pass the previous frame's detection to the detector as its prior.
    detections : optional callable ``(frame_index) -> DetectionResult``: the results of a
        :class:`visland.detection.DetectionSequence` with these ``params`` already run on the same
        frames (with ``track_previous``, called on every frame in order), used instead of detecting
        again.

    Raises ValueError if the detection stage is not available.
    """
    try:
        from visland.detection import DetectionSequence, DetectorParams, detect_runway
    except ImportError as error:
        raise ValueError(f"--anchor needs the detection stage (visland.detection.detect_runway), "
                         f"which does not import here: {error}") from None
    params = params or DetectorParams()
    # frame after frame, the detector keeps its last good detection as the prior through short
    # losses and checks re-acquisitions against it (visland.detection.sequence)
    sequence = DetectionSequence(camera, params) if track_previous else None

    def provider(frame_index: int, image) -> AnchorObservation:
        if image is None:
            return AnchorObservation.nothing("no image")
        if detections is not None:
            return anchor_from_detection(detections(frame_index))
        roll, pitch = float(inertial.roll_rad[frame_index]), float(inertial.pitch_rad[frame_index])
        if sequence is not None:
            result = sequence(image, roll, pitch, float(inertial.t_s[frame_index]))
        else:
            result = detect_runway(image, camera, roll, pitch, params=params)
        return anchor_from_detection(result)

    return provider


def anchor_from_detection(result) -> AnchorObservation:
    """Convert a ``visland.detection.DetectionResult`` (see its docstring) to an anchor."""
    if not result.found:
        return AnchorObservation.nothing(str(result.reason) or "runway not detected")
    corners = np.asarray(result.corners_uv, dtype=float).reshape(4, 2)
    found = np.asarray(result.corners_found, dtype=bool).reshape(4)
    confidence = float(result.confidence)
    confidence = min(max(confidence, 0.0), 1.0) if math.isfinite(confidence) else 0.0
    lines = {}
    raw_lines = getattr(result, "lines", None) or {}
    if isinstance(raw_lines, dict):
        for name in LINE_NAMES:
            line = raw_lines.get(name)
            if line is not None and len(line) == 2 and all(math.isfinite(float(x)) for x in line):
                lines[name] = (float(line[0]), float(line[1]))
    dF = float(getattr(result, "dF_px", math.nan))
    dpsi = float(getattr(result, "dpsi_rad", math.nan))
    return AnchorObservation(True, str(result.reason or ""), confidence, corners, found, lines, dF, dpsi)
