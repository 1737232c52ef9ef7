"""Detection over a sequence of frames: the last good detection predicts the next one.

:func:`~visland.detection.detect_runway` takes the previous result as its prior (tracking in
a region of interest). Over a sequence two things go wrong without memory:

- one frame where the runway is not found (a transient) drops the prior, and the next search
  covers the whole frame, where a field boundary or a taxiway can win;
- a re-acquisition after such a loss is not checked against what was just seen.

:class:`DetectionSequence` keeps the last good detection as the prior for
``DetectorParams.hold_s`` after a miss, and refuses a detection that did not come from
tracking when its edges turned, or its vanishing point moved, more than the runway can between
the two frames (``max_edge_turn_*``, ``max_vp_jump_*``: the pair must be consistent over time,
issue item 2). A refused detection is reported not found, with the reason. Threshold corners
that jump since the prior (the touchdown-zone bars taken for the threshold for one frame) are
dropped from an otherwise good detection (``max_threshold_jump_*``). After ``hold_s`` without a
good detection the next search starts afresh.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from visland.camera import CameraModel
from visland.detection.detector import detect_runway
from visland.detection.params import DetectorParams
from visland.detection.result import DetectionResult, not_found

__all__ = ["DetectionSequence"]


class DetectionSequence:
    """Stateful frame-after-frame detection (see module docstring).

    Parameters
    ----------
    camera : the camera of every frame.
    params : detector parameters (``hold_s`` and the consistency limits are used here).
    """

    def __init__(self, camera: CameraModel, params: DetectorParams | None = None):
        if not isinstance(camera, CameraModel):
            raise ValueError(f"camera must be a CameraModel, got {type(camera).__name__}")
        params = DetectorParams() if params is None else params
        if not isinstance(params, DetectorParams):
            raise ValueError(f"params must be DetectorParams, got {type(params).__name__}")
        self.camera = camera
        self.params = params.scaled_to(camera.width)
        self.last_good: DetectionResult | None = None
        self.t_good_s: float | None = None

    def reset(self) -> None:
        """Forget the last good detection (the next frame is searched afresh)."""
        self.last_good = None
        self.t_good_s = None

    def __call__(self, image, roll_rad: float, pitch_rad: float, t_s: float) -> DetectionResult:
        """Detect the runway in the frame at ``t_s`` (seconds, increasing)."""
        prior = self.last_good
        dt = math.inf if self.t_good_s is None else float(t_s) - self.t_good_s
        if prior is not None and not 0.0 < dt <= self.params.hold_s:
            prior = None
        result = detect_runway(image, self.camera, roll_rad, pitch_rad, params=self.params, previous=prior)
        if result.found and prior is not None and result.mode != "tracking":
            why = self._inconsistency(result, prior, dt)
            if why:
                result = not_found(f"refused: {why} since the detection {dt:.2f} s earlier ({result.mode} "
                                   f"picked another object)", roll_rad=float(roll_rad), pitch_rad=float(pitch_rad),
                                   mode=result.mode, image_size=result.image_size, elapsed_s=result.elapsed_s)
        if result.found and prior is not None:
            result = self._check_threshold(result, prior, dt)
        if result.found:
            self.last_good = result
            self.t_good_s = float(t_s)
        return result

    def _check_threshold(self, result: DetectionResult, prior: DetectionResult, dt: float) -> DetectionResult:
        """Drop threshold corners that jumped since the prior (the touchdown-zone bars taken for
        the threshold for one frame); the edges and d_F stay."""
        near_now = result.corners_found[:2].all()
        near_then = prior.corners_found[:2].all()
        if not (near_now and near_then):
            return result
        width_px = float(np.hypot(*(prior.corners_uv[1] - prior.corners_uv[0])))
        frames = max(dt * self.params.reference_rate_hz, 1.0)
        limit = (self.params.max_threshold_jump_px + self.params.max_threshold_jump_fraction * width_px) * frames
        jump = float(np.max(np.linalg.norm(result.corners_uv[:2] - prior.corners_uv[:2], axis=1)))
        if jump <= limit:
            return result
        corners = result.corners_uv.copy()
        corners[:2] = np.nan
        found = result.corners_found.copy()
        found[:2] = False
        note = f"threshold corners dropped: moved {jump:.0f} px since {dt:.2f} s earlier (> {limit:.0f})"
        return replace(result, corners_uv=corners, corners_found=found, threshold_line=(math.nan, math.nan),
                       reason="; ".join(filter(None, [result.reason, note])), notes=result.notes + (note,))

    def _inconsistency(self, result: DetectionResult, prior: DetectionResult, dt: float) -> str:
        p = self.params
        turn_limit = p.max_edge_turn_rad + p.max_edge_turn_rate_rps * dt
        for name in ("left", "right"):
            theta_now = result.lines[name][1]
            theta_then = prior.lines[name][1]
            if math.isfinite(theta_now) and math.isfinite(theta_then):
                # lines are undirected: compare modulo pi
                turn = abs((theta_now - theta_then + math.pi / 2) % math.pi - math.pi / 2)
                if turn > turn_limit:
                    return f"the {name} edge turned {math.degrees(turn):.1f} deg (> {math.degrees(turn_limit):.1f})"
        if math.isfinite(result.dF_px) and math.isfinite(prior.dF_px):
            jump = abs(result.dF_px - prior.dF_px)
            jump_limit = p.max_vp_jump_px + p.max_vp_jump_rate_pxps * dt
            if jump > jump_limit:
                return f"the vanishing point moved {jump:.0f} px along the horizon (> {jump_limit:.0f})"
        return ""
