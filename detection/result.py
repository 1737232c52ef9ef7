"""DetectionResult: what one frame's detection found, what it did not, and why.

Conventions (SPEC.md, :mod:`visland.camera`): pixels ``(u, v)`` with (0, 0) at the centre of
the top-left pixel; lines ``x cos(theta) + y sin(theta) = rho`` in normalised coordinates
``x = (u - cx)/fx``, ``y = (v - cy)/fy``, theta in [-pi/2, pi/2). Corners are in
:data:`visland.runway.CORNER_NAMES` order (threshold corners P', P'' of thesis Fig. 3.5, then
the runway-end corners); "left" and "right" are as seen by a pilot landing.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from visland.contracts import MEASUREMENT_COLUMNS
from visland.runway import CORNER_NAMES

__all__ = ["DetectionResult", "LINE_NAMES", "not_found"]

#: The three runway lines, in measurement-column order.
LINE_NAMES = ("left", "right", "center")

_NAN_LINE = (math.nan, math.nan)


@dataclass(frozen=True)
class DetectionResult:
    """The runway found in one frame (or why not).

    Attributes
    ----------
    found : bool
        True when both runway edges were found and the trapezoid passed every check.
    reason : str
        Why the runway was not found; when found, what is missing (empty if nothing).
    confidence : float
        0..1 (0 when not found): edge support, fit residuals, symmetry and horizon agreement.
    corners_uv : ndarray, shape (4, 2)
        Corner pixels in ``CORNER_NAMES`` order, NaN where not found.
    corners_found : ndarray of bool, shape (4,)
        Which corners were measured (intersection of an edge with the threshold or runway end
        line, inside the image).
    lines : dict
        ``{"left", "right", "center"}`` -> ``(rho, theta)`` SPEC chart, NaN where not found.
    line_residual_px : dict
        RMS distance (pixels) of each line's inlying edge points to the refined line.
    line_support : dict
        Fraction of each line's sampled profiles that held an inlying edge (or stripe).
    segments_uv : dict
        ``{"left", "right", "center"}`` -> (2, 2) pixel end points (far, near) of the stretch of
        each line the image supports; NaN where not found. Used to predict the next frame.
    threshold_line, end_line : tuple
        ``(rho, theta)`` of the threshold and of the runway end, NaN where not found.
    vanishing_point_uv : ndarray, shape (2,)
        Vanishing point of the runway direction (pixels), on the horizon.
    horizon : tuple
        ``(rho, theta)`` of the horizon from the inertial roll and pitch.
    dF_px : float
        Signed distance along the horizon from Q (the horizon at u = cx) to the vanishing
        point, positive to the right (seed 001 eq. 18-19, SPEC d_F).
    dpsi_rad : float
        Heading deviation recovered from d_F, the roll, pitch and camera mounting.
    roll_rad, pitch_rad : float
        The inertial attitude the frame was detected with (kept for the next prediction).
    mode : str
        ``"acquisition"`` (full frame) or ``"tracking"`` (region of interest from ``previous``).
    roi : tuple
        ``(u0, v0, u1, v1)`` region searched, pixels (end exclusive).
    image_size : tuple
        ``(width, height)`` of the frame.
    elapsed_s : float
        Wall time spent in :func:`detect_runway`.
    notes : tuple of str
        Details of what was not found (also summarised in ``reason``).
    threshold_method : str
        How the threshold line was placed (:class:`visland.detection.transverse.TransverseLine`
        ``method``: ``"chroma"``, ``"grey"``, ``"ground-exit"``, ... at the step where the
        pavement begins; ``"marking-bar"``, ``"marking-stripes"`` on a threshold marking inside
        the pavement); empty when there is no threshold line.
    pavement_marking_widths : float
        Runway widths from the pavement's start to a threshold marking seen inside it (a
        displaced threshold's bar, stripes after a blast pad), placed or not; NaN when none was
        seen.
    threshold_marked : bool
        The threshold carries a threshold marking: stripes or a bar across the width at the
        pavement's start (:func:`visland.detection.threshold_marking.marked_at_start`), or the
        marking inside the pavement it was placed on. A runway's mark, which a taxiway or road
        does not carry. Tracking the strip of a previous detection that saw it, it is carried,
        not read again (whenever a threshold is found).
    doubtful_corners_uv : ndarray, shape (k, 2)
        Corners measured but withheld from ``corners_uv`` because the edges they lie on are of
        low confidence (``DetectorParams.corner_min_confidence``): never a measurement, only what
        the next frame's search window covers (tracking, :func:`visland.detection.detect_runway`).
    """

    found: bool
    reason: str
    confidence: float = 0.0
    corners_uv: np.ndarray = field(default_factory=lambda: np.full((4, 2), np.nan))
    corners_found: np.ndarray = field(default_factory=lambda: np.zeros(4, dtype=bool))
    lines: dict = field(default_factory=lambda: {name: _NAN_LINE for name in LINE_NAMES})
    line_residual_px: dict = field(default_factory=lambda: {name: math.nan for name in LINE_NAMES})
    line_support: dict = field(default_factory=lambda: {name: 0.0 for name in LINE_NAMES})
    segments_uv: dict = field(default_factory=lambda: {name: np.full((2, 2), np.nan) for name in LINE_NAMES})
    threshold_line: tuple = _NAN_LINE
    end_line: tuple = _NAN_LINE
    vanishing_point_uv: np.ndarray = field(default_factory=lambda: np.full(2, np.nan))
    horizon: tuple = _NAN_LINE
    dF_px: float = math.nan
    dpsi_rad: float = math.nan
    roll_rad: float = math.nan
    pitch_rad: float = math.nan
    mode: str = "acquisition"
    roi: tuple = (0, 0, 0, 0)
    image_size: tuple = (0, 0)
    elapsed_s: float = 0.0
    notes: tuple = ()
    threshold_method: str = ""
    pavement_marking_widths: float = math.nan
    threshold_marked: bool = False
    doubtful_corners_uv: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))

    @property
    def lines_found(self) -> dict:
        """Which of the three lines were measured."""
        return {name: bool(np.all(np.isfinite(self.lines[name]))) for name in LINE_NAMES}

    @property
    def shows_runway_marking(self) -> bool:
        """Whether this saw a runway's own marking: the threshold's (``threshold_marked``, which
        includes a threshold placed on a marking inside the pavement), or a threshold marking
        inside the pavement it could not place (a displaced threshold's bar far out). Not a
        centre line: taxiways carry one too (the robustness study's overcast taxiway, its centre
        line found from 1.0 km)."""
        return self.threshold_marked or math.isfinite(self.pavement_marking_widths)

    def with_note(self, note: str) -> "DetectionResult":
        """This result saying ``note`` too, after its ``reason`` and ``notes``."""
        return replace(self, reason="; ".join(filter(None, [self.reason, note])), notes=tuple(self.notes) + (note,))

    def to_measurement_row(self, frame: int | None = None, t_s: float | None = None) -> dict:
        """One row of ``measurements.csv`` (:data:`visland.contracts.MEASUREMENT_COLUMNS`).

        Not measured features are NaN (empty cells); ``source`` is ``"detection"``. A result
        that is not found carries no feature values at all, so nothing unconfirmed reaches
        an estimator.
        """
        row = {"frame": frame, "t_s": t_s}
        corners = self.corners_uv if self.found else np.full((4, 2), np.nan)
        found_corners = self.corners_found if self.found else np.zeros(4, dtype=bool)
        for k, name in enumerate(CORNER_NAMES):
            ok = bool(found_corners[k])
            row[f"{name}_u_px"] = float(corners[k, 0]) if ok else math.nan
            row[f"{name}_v_px"] = float(corners[k, 1]) if ok else math.nan
        for name in LINE_NAMES:
            rho, theta = self.lines[name] if self.found else _NAN_LINE
            row[f"{name}_rho"] = float(rho)
            row[f"{name}_theta_rad"] = float(theta)
        row["dF_px"] = float(self.dF_px) if self.found else math.nan
        row["dpsi_deg"] = math.degrees(self.dpsi_rad) if self.found else math.nan
        for k, name in enumerate(CORNER_NAMES):
            row[f"{name}_visible"] = int(bool(found_corners[k]))
        row["source"] = "detection"
        row["found"] = int(bool(self.found))
        row["reason"] = self.reason
        row["confidence"] = float(self.confidence)
        missing = [c for c in MEASUREMENT_COLUMNS if c not in row]
        if missing:  # keeps this method in step with the contract if a column is added there
            raise RuntimeError(f"measurement row lacks column {missing[0]}")
        return row


def not_found(reason: str, **fields_) -> DetectionResult:
    """A result that found nothing, with its reason (every feature NaN, confidence 0).

    Parameters
    ----------
    reason : str
        One sentence saying why.
    **fields_
        Other :class:`DetectionResult` fields (attitude, image size, mode, elapsed time).

    Returns
    -------
    DetectionResult
    """
    return DetectionResult(found=False, reason=reason, confidence=0.0, **fields_)
