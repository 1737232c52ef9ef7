"""Input preparation (issue item 1): telemetry plus image measurements -> one ObserverInput per step.

What the observers need and how it is obtained (SPEC frames, see :mod:`visland.frames`):

- Heading deviation ``dpsi`` from the vanishing-point feature d_F (seed 001 eq. 18-19, for any
  camera mounting: :func:`visland.features.dpsi_from_dF`) with the inertial roll and pitch. A
  frame without d_F but with all four corners (a point tracker's output) gets d_F from the
  vanishing point of the two edges through its corners.
- The runway heading ``psi_rwy = heading - dpsi`` is a constant: each frame gives one sample
  and the estimate is their causal running mean (circular, each frame weighted by the squared
  pixel span of the threshold: the vanishing point sharpens as the runway grows in the image),
  so the heading deviation used at a step is ``dpsi = heading - psi_rwy_hat``, available at the
  inertial rate and far less noisy than one frame's d_F. The mean is used once its standard
  error (weighted spread of the samples over the effective number of frames) is under
  ``HEADING_SETTLED_RAD`` (1 deg): far away, a few pixels of noise on a runway 20 px wide can
  put one frame's vanishing point 20 deg off, and an observer started on that heading turns
  20 % of the speed into a false lateral velocity. Exact or detected d_F settles on the first
  frame; until then the frames are "no heading deviation yet" and no observer starts.
- Velocities in the runway axes R (= the virtual-frame axes V): ``v_R = Rz(-psi_rwy_hat) v_NED``;
  in camera axes ``v_C = R_camera_from_runway v_R``.
- Camera angular velocity ``w_C = R_body_from_camera^T (p, q, r)``.
- ``R_runway_from_camera = Rz(dpsi) Ry(pitch) Rx(roll) R_body_from_camera`` and the runway down
  axis in C, ``n_C = R_camera_from_runway [0 0 1]`` (thesis 3.33).
- Threshold corners P' (near left) and P'' (near right) in the virtual frame (thesis 3.23:
  ``y_v = (X_v/Z_v, Y_v/Z_v)`` of the ray ``R_runway_from_camera (x, y, 1)``), from their pixels.
- The left and right edge lines ``(rho, theta)`` (SPEC chart) and the centre line, as measured.

Steps are the telemetry samples from the first to the last frame, plus the frame times that
are not on the telemetry grid (inertial data interpolated there, angles unwrapped). A frame
whose measurement is missing (found = 0, empty cells, a corner outside the image) leaves its
step without that feature: the observers coast across it and say so.

References
----------
V. Gibert, L. Burlion, A. Chriette, J. Boada, F. Plestan, "A new observer for range
identification in perspective vision systems", Advances in Aerospace Guidance, Navigation
and Control (seeds 001 and 003).
    Appendix, eq. 18-19: d_F and the heading deviation.
V. Gibert, "Analyse d'observabilite et synthese d'observateurs robustes pour l'atterrissage
base vision d'avions de ligne sur des pistes inconnues", PhD thesis, 2016 (seed 002).
    Eq. 3.19-3.24: the virtual frame and eta = 1/dH.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from visland.camera import CameraModel, intersect_lines, line_through_points
from visland.contracts import Table
from visland.features import (batch_R_camera_from_runway, dF_from_vanishing_point, dpsi_from_dF, horizon_line,
                              virtual_from_pixels)
from visland.frames import wrap_pi
from visland.sensors import TIME_MATCH_S, InertialSeries

from visland.estimation.base import ObserverInput

__all__ = ["InertialSeries", "FeatureSeries", "PreparedInputs", "prepare_inputs", "TIME_MATCH_S"]

#: Frame times within this of a telemetry sample share its step.
#: The runway-heading estimate is used once its standard error is under this (radians).
HEADING_SETTLED_RAD = math.radians(1.0)
#: ... and once single frames' heading samples scatter by less than this (their local robust
#: standard deviation, :func:`_robust_heading_weights`): far out they are biased by about their scatter.
HEADING_SAMPLE_SETTLED_RAD = math.radians(0.5)
#: The mounting's self-calibration corrects the steps once its roll and pitch standard deviations
#: are under this (radians).
CALIBRATION_SETTLED_RAD = math.radians(0.05)
#: ... and is not applied at all when it has not settled this long after the first measured frame.
CALIBRATION_MAX_WAIT_S = 30.0

_NEAR_CORNERS = ("near_left", "near_right")
_FAR_CORNERS = ("far_left", "far_right")


@dataclass
class FeatureSeries:
    """Image measurements, one row per camera frame (NaN where not measured).

    Attributes
    ----------
    t_s : (m,) frame times.
    near_uv_px : (m, 2, 2) pixels of P' (near left) and P'' (near right).
    lines : (m, 2, 2) ``[[rho_l, theta_l], [rho_r, theta_r]]`` left and right edges, SPEC chart.
    center_line : (m, 2) ``[rho, theta]`` of the centre line.
    dF_px : (m,) vanishing-point feature d_F (SPEC), pixels.
    far_uv_px : (m, 2, 2) pixels of the runway-end corners (far left, far right), NaN where not
        measured; with the near corners they give the vanishing point when d_F is not measured
        (a point tracker measures corners only).
    points_ok, lines_ok : (m,) bool, whether the frame measured both near corners / both edges.
    reason : (m,) str, why a frame measured nothing ("" when it did).
    """

    t_s: np.ndarray
    near_uv_px: np.ndarray
    lines: np.ndarray
    center_line: np.ndarray
    dF_px: np.ndarray
    points_ok: np.ndarray
    lines_ok: np.ndarray
    reason: np.ndarray = field(default=None)
    far_uv_px: np.ndarray = field(default=None)

    def __post_init__(self):
        m = len(self.t_s)
        if self.reason is None:
            self.reason = np.full(m, "", dtype=object)
        if self.far_uv_px is None:
            self.far_uv_px = np.full((m, 2, 2), np.nan)
        if m < 1:
            raise ValueError("measurements: no frames")
        if np.any(np.diff(self.t_s) <= 0):
            raise ValueError("measurements: frame time must increase strictly")

    def __len__(self):
        return len(self.t_s)

    @classmethod
    def from_table(cls, table: Table) -> "FeatureSeries":
        """From ``labels.csv`` or ``measurements.csv`` (SPEC labels schema).

        A corner is used when its two cells are filled and, if the table has them, its
        ``*_visible`` flag is 1; with a ``found`` column, rows with found = 0 measure nothing.
        """
        m = table.n_rows
        uv = np.stack([np.stack([table[f"{c}_u_px"], table[f"{c}_v_px"]], axis=-1) for c in _NEAR_CORNERS], axis=1)
        visible = np.ones((m, 2), dtype=bool)
        for k, c in enumerate(_NEAR_CORNERS):
            if f"{c}_visible" in table:
                flags = table[f"{c}_visible"]
                visible[:, k] = np.nan_to_num(flags, nan=0.0) > 0.5
        found = np.ones(m, dtype=bool)
        if "found" in table:
            found = table["found"] > 0.5
        lines = np.stack([np.stack([table["left_rho"], table["left_theta_rad"]], axis=-1),
                          np.stack([table["right_rho"], table["right_theta_rad"]], axis=-1)], axis=1)
        center = np.stack([table["center_rho"], table["center_theta_rad"]], axis=-1)
        points_ok = found & np.isfinite(uv).all(axis=(1, 2)) & visible.all(axis=1)
        lines_ok = found & np.isfinite(lines).all(axis=(1, 2))
        reason = np.full(m, "", dtype=object)
        source_reason = table["reason"] if "reason" in table else np.full(m, "", dtype=object)
        for i in range(m):
            if not found[i]:
                reason[i] = f"not found ({source_reason[i]})" if source_reason[i] else "not found"
            elif not points_ok[i] and not lines_ok[i]:
                reason[i] = "no usable corners or lines"
            elif not points_ok[i]:
                reason[i] = "near corners not measured" if visible.all(axis=1)[i] else "near corner outside the image"
        dF = np.where(found, table["dF_px"], np.nan)
        far = np.stack([np.stack([table[f"{c}_u_px"], table[f"{c}_v_px"]], axis=-1) for c in _FAR_CORNERS], axis=1)
        for k, c in enumerate(_FAR_CORNERS):
            if f"{c}_visible" in table:
                far[:, k] = np.where((np.nan_to_num(table[f"{c}_visible"], nan=0.0) > 0.5)[:, None], far[:, k], np.nan)
        far = np.where(found[:, None, None], far, np.nan)
        return cls(t_s=np.asarray(table["t_s"], dtype=float), near_uv_px=np.where(points_ok[:, None, None], uv, np.nan),
                   lines=np.where(lines_ok[:, None, None], lines, np.nan), center_line=np.where(found[:, None], center, np.nan),
                   dF_px=dF, points_ok=points_ok, lines_ok=lines_ok, reason=reason, far_uv_px=far)

    @classmethod
    def from_ideal(cls, features) -> "FeatureSeries":
        """From :class:`visland.features.IdealFeatures` (a simulation, no files)."""
        uv = features.corners_uv[:, :2, :]
        visible = features.corners_visible[:, :2].all(axis=1)
        points_ok = visible & np.isfinite(uv).all(axis=(1, 2))
        lines = np.stack([np.stack(features.lines["left"], axis=-1), np.stack(features.lines["right"], axis=-1)], axis=1)
        lines_ok = np.isfinite(lines).all(axis=(1, 2))
        reason = np.array(["" if p else "near corner outside the image" for p in points_ok], dtype=object)
        far = np.where(features.corners_visible[:, 2:, None], features.corners_uv[:, 2:, :], np.nan)
        return cls(far_uv_px=far, t_s=np.asarray(features.t_s, dtype=float), near_uv_px=np.where(points_ok[:, None, None], uv, np.nan),
                   lines=np.where(lines_ok[:, None, None], lines, np.nan),
                   center_line=np.stack(features.lines["center"], axis=-1), dF_px=np.asarray(features.dF_px, dtype=float),
                   points_ok=points_ok, lines_ok=lines_ok, reason=reason)


@dataclass
class PreparedInputs:
    """Everything the observers consume, step by step.

    Attributes
    ----------
    steps : list of :class:`ObserverInput`, one per step (inertial rate plus off-grid frames).
    t_s : (N,) step times.
    frame_of_step : (N,) int, the frame measured at each step, -1 for none.
    step_of_frame : (m,) int, the step of each frame.
    frame_t_s : (m,) frame times.
    psi_runway_rad : (N,) running estimate of the runway heading (NaN before the first d_F).
    dpsi_rad : (N,) heading deviation used at each step.
    dpsi_frame_rad : (m,) heading deviation from each frame's own d_F (NaN without d_F).
    frame_reason : (m,) why a frame gave no usable measurement ("" when it did).
    points_ok, lines_ok : (m,) which frames carry usable points / lines for the observers.
    calibration : :class:`visland.estimation.calibration.MountCalibration` (the self-calibration
        of the camera mounting whose causal estimate corrected every step), or None when off.
    """

    steps: list
    t_s: np.ndarray
    frame_of_step: np.ndarray
    step_of_frame: np.ndarray
    frame_t_s: np.ndarray
    psi_runway_rad: np.ndarray
    dpsi_rad: np.ndarray
    dpsi_frame_rad: np.ndarray
    frame_reason: np.ndarray
    points_ok: np.ndarray
    lines_ok: np.ndarray
    calibration: object = None

    def __len__(self):
        return len(self.steps)

    def first_step_with(self, features: str) -> int | None:
        """Index of the first step carrying a measurement of ``features`` ("points" or "lines")."""
        ok = self.points_ok if features == "points" else self.lines_ok
        frames = np.nonzero(ok)[0]
        return int(self.step_of_frame[frames[0]]) if frames.size else None


def _circular_running_mean(angles_rad: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Causal weighted running mean of angles (NaN entries skipped; NaN until the first valid one)."""
    valid = np.isfinite(angles_rad)
    w = np.ones_like(angles_rad) if weights is None else np.where(np.isfinite(weights), weights, 0.0)
    w = np.where(valid, w, 0.0)
    c = np.cumsum(w * np.cos(np.nan_to_num(angles_rad)))
    s = np.cumsum(w * np.sin(np.nan_to_num(angles_rad)))
    total = np.cumsum(w)
    return np.where(total > 0, np.arctan2(s, c), np.nan)


def _running_standard_error(angles_rad: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Causal standard error of the weighted running mean of ``angles_rad``:
    sqrt(weighted variance / effective number of samples), NaN entries skipped; infinite
    until two samples. Angles are taken relative to the first valid one (no wrap: the samples
    are one constant heading plus noise far below pi)."""
    valid = np.isfinite(angles_rad)
    if not valid.any():
        return np.full(len(angles_rad), np.inf)
    w = np.where(valid & np.isfinite(weights), weights, 0.0)
    x = np.where(valid, wrap_pi(angles_rad - angles_rad[np.argmax(valid)]), 0.0)
    sw, swx, swxx, sww = np.cumsum(w), np.cumsum(w * x), np.cumsum(w * x * x), np.cumsum(w * w)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = swx / sw
        variance = np.maximum(swxx / sw - mean ** 2, 0.0)
        n_eff = sw ** 2 / sww
        se = np.sqrt(variance / n_eff)
    return np.where((np.cumsum(valid) >= 2) & np.isfinite(se), se, np.inf)


def _heading_weights(near_uv_px: np.ndarray) -> np.ndarray:
    """Relative weight of each frame's d_F: the squared pixel span of the threshold (P'P'').

    The vanishing point comes from the edges; for a given pixel noise its angular error shrinks
    as the runway grows in the image (roughly as 1 / its size), so an inverse-variance mean
    weighs each frame by the squared size. Frames without both corners reuse the last weight.
    (The streaming estimator of ``visland fly`` still uses these; the offline one uses
    :func:`_robust_heading_weights`.)
    """
    span = np.hypot(near_uv_px[:, 1, 0] - near_uv_px[:, 0, 0], near_uv_px[:, 1, 1] - near_uv_px[:, 0, 1])
    weights = span ** 2
    last = 1.0
    for i in range(len(weights)):
        if np.isfinite(weights[i]) and weights[i] > 0:
            last = weights[i]
        else:
            weights[i] = last
    return weights


#: Frames (valid samples) in the causal window that measures the local spread of the heading samples.
HEADING_WINDOW_FRAMES = 25
#: Valid samples the window needs before their spread is trusted (a MAD of 2-4 samples can be
#: near zero by chance); until then a sample has no weight, unless the samples agree exactly.
HEADING_MIN_SAMPLES = 10
#: A heading sample further than this many local robust standard deviations from the window's
#: median is an outlier and gets no weight.
HEADING_GATE_SIGMAS = 4.0
#: Floor of the local standard deviation (radians): exact samples agree to rounding, and the
#: weights only need to stay finite.
HEADING_SIGMA_FLOOR_RAD = 1e-5


def _robust_heading_weights(angles_rad: np.ndarray, window: int = HEADING_WINDOW_FRAMES,
                            gate_sigmas: float = HEADING_GATE_SIGMAS) -> tuple[np.ndarray, np.ndarray]:
    """Inverse-variance weights of the runway-heading samples from their own local spread, with a gate.

    Far out the vanishing point of a runway a few pixels wide is not only noisier than
    :func:`_heading_weights`' squared span predicts, it is heavy-tailed and biased: on thesis-4
    with 5 px of corner noise the per-frame heading errors have a robust spread of 2.5 deg and a
    median of +2.7 deg in the first 5 s (single frames 50-100 deg off), 0.2 deg and +0.02 deg
    from 20 s on. Weighted by the squared span, those first seconds kept the running mean 2.6 deg
    off at 16 s and 1 deg off at 32 s; kf-2p then ended 60 m high at 100 ft.

    Each sample's standard deviation is estimated from the samples themselves, causally: ``s_i =
    1.4826 MAD`` of the last ``window`` valid samples up to and including ``i``, floored at
    :data:`HEADING_SIGMA_FLOOR_RAD` (infinite, weight 0, while the window holds fewer than
    :data:`HEADING_MIN_SAMPLES` that do not agree to the floor); its weight is ``1 / s_i^2``
    (inverse variance: the seconds with a tenth of the spread count a hundred times more), and 0
    when it lies more than ``gate_sigmas`` ``s_i`` from the window's median (a gate on the
    normalised residual, as a Mahalanobis gate in one dimension) or when it is the first valid
    sample (no spread known yet). Exact samples all agree, so any weights give the same mean:
    the estimate on ideal measurements is unchanged.

    Returns ``(weights, sigma_rad)`` of shape (m,): the weights (0 where the sample is NaN) and
    the local standard deviation ``s_i`` (infinite until two valid samples, NaN where the sample is).
    """
    angles_rad = np.asarray(angles_rad, dtype=float)
    weights = np.zeros(len(angles_rad))
    sigma_out = np.full(len(angles_rad), np.nan)
    valid = np.nonzero(np.isfinite(angles_rad))[0]
    sigma_out[valid] = np.inf
    if valid.size < 2:
        return weights, sigma_out
    x = wrap_pi(angles_rad[valid] - angles_rad[valid[0]])
    n = len(x)
    padded = np.concatenate([np.full(window - 1, np.nan), x])
    windows = np.lib.stride_tricks.sliding_window_view(padded, window)       # (n, window), causal
    count = np.minimum(np.arange(1, n + 1), window)
    median = np.nanmedian(windows, axis=1)
    mad_sigma = 1.4826 * np.nanmedian(np.abs(windows - median[:, None]), axis=1)
    spread = np.nanmax(windows, axis=1) - np.nanmin(windows, axis=1)
    # fewer than HEADING_MIN_SAMPLES: no spread known yet (weight 0), unless they agree exactly
    sigma = np.where(count >= HEADING_MIN_SAMPLES, np.maximum(mad_sigma, HEADING_SIGMA_FLOOR_RAD),
                     np.where(spread <= HEADING_SIGMA_FLOOR_RAD, HEADING_SIGMA_FLOOR_RAD, np.inf))
    w = 1.0 / sigma ** 2
    w[np.abs(x - median) > gate_sigmas * sigma] = 0.0
    w[0] = 0.0
    sigma[0] = np.inf
    weights[valid] = w
    sigma_out[valid] = sigma
    return weights, sigma_out


def _dF_with_corner_fallback(features: FeatureSeries, ins_f: InertialSeries, camera: CameraModel) -> np.ndarray:
    """d_F per frame: as measured, else from the vanishing point of the two edges through the
    near and far corners (seed 001 appendix: the vanishing point of the runway sides), measured
    along the inertial horizon. NaN where neither is available."""
    dF = np.asarray(features.dF_px, dtype=float).copy()
    corners = np.concatenate([features.near_uv_px, features.far_uv_px], axis=1)   # NL, NR, FL, FR
    fill = ~np.isfinite(dF) & np.isfinite(corners).all(axis=(1, 2))
    if fill.any():
        xy = camera.pixels_to_normalized(corners[fill])
        left = line_through_points(xy[:, 0], xy[:, 2])
        right = line_through_points(xy[:, 1], xy[:, 3])
        vp = intersect_lines(*left, *right)
        R_cr_level = batch_R_camera_from_runway(ins_f.roll_rad[fill], ins_f.pitch_rad[fill],
                                                np.zeros(int(fill.sum())), camera.mount_rpy_rad)
        dF[fill] = dF_from_vanishing_point(vp, *horizon_line(R_cr_level), camera)
    return dF


def _dF_on_horizon(features: FeatureSeries, ins_f: InertialSeries, camera: CameraModel) -> np.ndarray:
    """d_F per frame from where each runway edge crosses the inertial horizon (mean of the two).

    The runway direction is horizontal, so its vanishing point lies on the horizon that the
    inertial roll and pitch predict (:func:`visland.features.horizon_line`); each edge (the
    measured line, else the line through its near and far corners) crosses that horizon at the
    vanishing point, and the mean of the two crossings is measured along the horizon as d_F.
    Intersecting the two edges with each other instead (the unconstrained vanishing point) divides
    by their small angle: 5 km out with 5 px of corner noise that ratio is heavy-tailed and biased
    (per-frame heading errors 50-100 deg, a +2.7 deg median on thesis-4); crossing a known line is
    linear in the noise. On exact measurements both give the same point. NaN where neither edge
    pair is measured.
    """
    m = len(features)
    left = np.full((m, 2), np.nan)
    right = np.full((m, 2), np.nan)
    ok = features.lines_ok
    left[ok] = features.lines[ok, 0]
    right[ok] = features.lines[ok, 1]
    corners = np.concatenate([features.near_uv_px, features.far_uv_px], axis=1)   # NL, NR, FL, FR
    fill = ~ok & np.isfinite(corners).all(axis=(1, 2))
    if fill.any():
        xy = camera.pixels_to_normalized(corners[fill])
        left[fill] = np.stack(line_through_points(xy[:, 0], xy[:, 2]), axis=1)
        right[fill] = np.stack(line_through_points(xy[:, 1], xy[:, 3]), axis=1)
    dF = np.full(m, np.nan)
    use = np.isfinite(left).all(axis=1) & np.isfinite(right).all(axis=1)
    if use.any():
        R_cr_level = batch_R_camera_from_runway(ins_f.roll_rad[use], ins_f.pitch_rad[use],
                                                np.zeros(int(use.sum())), camera.mount_rpy_rad)
        h_rho, h_theta = horizon_line(R_cr_level)
        vp = 0.5 * (intersect_lines(left[use, 0], left[use, 1], h_rho, h_theta)
                    + intersect_lines(right[use, 0], right[use, 1], h_rho, h_theta))
        dF[use] = dF_from_vanishing_point(vp, h_rho, h_theta, camera)
    return dF


def _position_ned(inertial: InertialSeries, times_s: np.ndarray) -> np.ndarray:
    """The inertial ground velocity integrated (trapezoids at the unit's rate) to ``times_s``, origin at
    the first sample: the camera's displacements between frames (the epipolar constraint's T)."""
    v = inertial.v_ned_mps
    steps = 0.5 * (v[1:] + v[:-1]) * np.diff(inertial.t_s)[:, None]
    p = np.concatenate([np.zeros((1, 3)), np.cumsum(steps, axis=0)])
    return np.stack([np.interp(times_s, inertial.t_s, p[:, k]) for k in range(3)], axis=1)


def _dpsi_from_vanishing_point(features: FeatureSeries, ins_f: InertialSeries, R_body_from_camera_frame: np.ndarray,
                               camera: CameraModel) -> np.ndarray:
    """Heading deviation per frame from the edges' vanishing point (the edge lines, else the four
    corners), back-projected through each frame's (corrected) mounting into the level heading frame
    (as :func:`visland.features.dpsi_from_dF`); NaN where neither is measured."""
    from visland.features import batch_R_runway_from_body
    m = len(features)
    vp = np.full((m, 2), np.nan)
    ok = features.lines_ok
    if ok.any():
        vp[ok] = intersect_lines(features.lines[ok, 0, 0], features.lines[ok, 0, 1],
                                 features.lines[ok, 1, 0], features.lines[ok, 1, 1])
    corners = np.concatenate([features.near_uv_px, features.far_uv_px], axis=1)
    fill = ~np.isfinite(vp).all(axis=1) & np.isfinite(corners).all(axis=(1, 2))
    if fill.any():
        xy = camera.pixels_to_normalized(corners[fill])
        vp[fill] = intersect_lines(*line_through_points(xy[:, 0], xy[:, 2]), *line_through_points(xy[:, 1], xy[:, 3]))
    ray_C = np.concatenate([vp, np.ones((m, 1))], axis=1)
    R_LC = batch_R_runway_from_body(ins_f.roll_rad, ins_f.pitch_rad, np.zeros(m)) @ R_body_from_camera_frame
    ray_L = np.einsum("nij,nj->ni", R_LC, ray_C)
    return np.arctan2(-ray_L[:, 1], ray_L[:, 0])


def prepare_inputs(inertial: InertialSeries, features: FeatureSeries, camera: CameraModel,
                   self_calibration: str = "off", calibration_params=None) -> PreparedInputs:
    """Build the per-step observer inputs (see the module docstring for each quantity).

    Parameters
    ----------
    inertial : telemetry at its own rate (>= the frame rate), covering every frame time.
    features : image measurements per frame.
    camera : the nominal camera (``camera.json``): intrinsics and mounting.
    self_calibration : "off" (``camera.json``'s mounting as it is), "check" (estimate the
        mounting's error from the runway, :mod:`visland.estimation.calibration`, and report it in
        ``PreparedInputs.calibration`` without correcting anything) or "apply" (also correct every
        step with the causal estimate once it has settled; no observer starts before).
    calibration_params : :class:`visland.estimation.calibration.CalibrationParams` (default tuning).
    """
    frame_t = features.t_s
    if frame_t[0] < inertial.t_s[0] - TIME_MATCH_S or frame_t[-1] > inertial.t_s[-1] + TIME_MATCH_S:
        raise ValueError(f"telemetry covers {inertial.t_s[0]:g}..{inertial.t_s[-1]:g} s but the frames span "
                         f"{frame_t[0]:g}..{frame_t[-1]:g} s")
    # ---- step times: telemetry samples within the frame span, plus off-grid frame times
    inside = (inertial.t_s >= frame_t[0] - TIME_MATCH_S) & (inertial.t_s <= frame_t[-1] + TIME_MATCH_S)
    grid = inertial.t_s[inside]
    nearest = np.clip(np.searchsorted(grid, frame_t), 0, max(len(grid) - 1, 0))
    on_grid = np.zeros(len(frame_t), dtype=bool)
    if grid.size:
        for k in (nearest, np.clip(nearest - 1, 0, len(grid) - 1)):
            on_grid |= np.abs(grid[k] - frame_t) <= TIME_MATCH_S
    times = np.union1d(grid, frame_t[~on_grid])
    step_of_frame = np.clip(np.searchsorted(times, frame_t - TIME_MATCH_S), 0, len(times) - 1)
    frame_of_step = np.full(len(times), -1, dtype=int)
    frame_of_step[step_of_frame] = np.arange(len(frame_t))
    ins = inertial.at(times)

    # ---- self-calibration of the mounting: its causal estimate at each frame and each step
    ins_f = inertial.at(frame_t)
    last_frame = np.searchsorted(frame_t, times + TIME_MATCH_S, side="right") - 1
    calibration = None
    mount_error_frame = np.zeros((len(frame_t), 3))
    calibration_wait = np.zeros(len(frame_t), dtype=bool)
    slope_frame = np.zeros(len(frame_t))
    if self_calibration not in ("off", "check", "apply"):
        raise ValueError(f"self_calibration must be 'off', 'check' or 'apply', got {self_calibration!r}")
    if self_calibration != "off":
        from visland.estimation.calibration import estimate_mount_error
        calibration = estimate_mount_error(frame_t, features.near_uv_px, features.far_uv_px, ins_f.roll_rad,
                                           ins_f.pitch_rad, ins_f.heading_rad, _position_ned(inertial, frame_t),
                                           camera, calibration_params)
        if self_calibration == "check":
            calibration.applied = False
        elif calibration.applied:
            # applied once settled (roll and pitch known to CALIBRATION_SETTLED_RAD), and no
            # observer starts before: the first frames' estimate swings by tenths of a degree,
            # and a correction switched on under a running observer is a jump of its
            # measurements (ccpi-hg-2p diverges on a 0.5 deg jump 4 km out). A calibration not
            # settled CALIBRATION_MAX_WAIT_S after the first measured frame is not applied.
            settled = np.maximum.accumulate(calibration.sigma[:, :2].max(axis=1) <= CALIBRATION_SETTLED_RAD)
            measured = np.nonzero(features.points_ok | features.lines_ok)[0]
            first_t = frame_t[measured[0]] if measured.size else frame_t[0]
            if settled.any() and frame_t[np.argmax(settled)] <= first_t + CALIBRATION_MAX_WAIT_S:
                mount_error_frame = np.where(settled[:, None], calibration.mount_error_rad, 0.0)
                slope_frame = np.where(settled, calibration.slope_pct / 100.0, 0.0)
                calibration_wait = ~settled
            else:
                calibration.applied = False
                calibration.problem = calibration.problem or (
                    f"the mounting's self-calibration did not settle within {CALIBRATION_MAX_WAIT_S:g} s of the first "
                    "measured frame (roll and pitch need the four corners and the threshold corners over a few "
                    "seconds): camera.json's mounting used as it is")
    mount_error_step = np.where((last_frame >= 0)[:, None], mount_error_frame[np.clip(last_frame, 0, None)], 0.0)
    corrected = bool(np.any(mount_error_frame))

    # ---- heading: dpsi per frame from d_F, runway heading as a filtered constant
    dpsi_frame = np.full(len(frame_t), np.nan)
    dF_px = _dF_on_horizon(features, ins_f, camera)
    dF_px = np.where(np.isfinite(dF_px), dF_px, _dF_with_corner_fallback(features, ins_f, camera))
    has_dF = np.isfinite(dF_px)
    if has_dF.any():
        dpsi_frame[has_dF] = dpsi_from_dF(dF_px[has_dF], ins_f.roll_rad[has_dF], ins_f.pitch_rad[has_dF], camera)
    if corrected:
        # with a corrected mounting, read the heading from the vanishing point itself (d_F is
        # measured along the nominal horizon)
        from visland.estimation.calibration import batch_R_body_from_camera
        vp_dpsi = _dpsi_from_vanishing_point(features, ins_f, batch_R_body_from_camera(
            np.asarray(camera.mount_rpy_rad)[None, :] + mount_error_frame), camera)
        dpsi_frame = np.where(np.isfinite(vp_dpsi), vp_dpsi, dpsi_frame)
    psi_samples = ins_f.heading_rad - dpsi_frame
    weights, sample_sigma = _robust_heading_weights(psi_samples)
    psi_rwy_frame = _circular_running_mean(psi_samples, weights)
    # settled: the mean known to HEADING_SETTLED_RAD and single frames no longer scattering by more
    # (frames that scatter by degrees are also biased by about as much: _robust_heading_weights)
    settled = np.maximum.accumulate((_running_standard_error(psi_samples, weights) <= HEADING_SETTLED_RAD)
                                    & (np.nan_to_num(sample_sigma, nan=np.inf) <= HEADING_SAMPLE_SETTLED_RAD))
    psi_rwy_frame = np.where(settled, psi_rwy_frame, np.nan)
    # value at each step: the estimate from the frames up to that time (hold the last one)
    psi_rwy = np.where(last_frame >= 0, psi_rwy_frame[np.clip(last_frame, 0, None)], np.nan)
    dpsi = wrap_pi(ins.heading_rad - psi_rwy)

    # ---- rotations and velocities at every step
    if corrected:
        from visland.estimation.calibration import batch_R_body_from_camera
        from visland.features import batch_R_runway_from_body
        R_bc = batch_R_body_from_camera(np.asarray(camera.mount_rpy_rad)[None, :] + mount_error_step)
        R_rc = batch_R_runway_from_body(ins.roll_rad, ins.pitch_rad, dpsi) @ R_bc
        R_cr = np.swapaxes(R_rc, -1, -2)
        omega_camera = np.einsum("nji,nj->ni", R_bc, ins.omega_body_rps)     # R_bc^T w_B per step
    else:
        R_cr = batch_R_camera_from_runway(ins.roll_rad, ins.pitch_rad, dpsi, camera.mount_rpy_rad)
        R_rc = np.swapaxes(R_cr, -1, -2)
        omega_camera = ins.omega_body_rps @ camera.R_body_from_camera       # = (R_bc^T w_B) row-wise
    c, s = np.cos(psi_rwy), np.sin(psi_rwy)
    vn, ve = ins.v_ned_mps[:, 0], ins.v_ned_mps[:, 1]
    v_runway = np.stack([c * vn + s * ve, -s * vn + c * ve, ins.v_ned_mps[:, 2]], axis=1)
    v_camera = np.einsum("nij,nj->ni", R_cr, v_runway)
    n_camera = R_cr[:, :, 2]
    if corrected and calibration is not None:
        # the runway plane's normal (thesis 3.33's n; Runway.normal_runway) with the estimated
        # slope: the line observers then measure the distance to the sloped plane (runner converts)
        slope = np.where(last_frame >= 0, slope_frame[np.clip(last_frame, 0, None)], 0.0)
        n_runway = np.stack([slope, np.zeros_like(slope), np.ones_like(slope)], axis=1) / np.sqrt(1.0 + slope ** 2)[:, None]
        n_camera = np.einsum("nij,nj->ni", R_cr, n_runway)
    else:
        slope = np.zeros(len(times))

    # ---- measurements at their steps
    frame_steps = step_of_frame
    yv = np.full((len(frame_t), 2, 2), np.nan)
    pts = features.points_ok & np.isfinite(psi_rwy[frame_steps])
    if pts.any():
        yv[pts] = virtual_from_pixels(features.near_uv_px[pts], R_rc[frame_steps[pts]], camera)
    lines_ok = features.lines_ok & np.isfinite(psi_rwy[frame_steps])
    reason = features.reason.copy()
    for i in np.nonzero((features.points_ok | features.lines_ok) & ~np.isfinite(psi_rwy[frame_steps]))[0]:
        reason[i] = "no heading deviation yet (neither d_F nor the four corners measured)"
    if calibration_wait.any():
        for i in np.nonzero((pts | lines_ok) & calibration_wait)[0]:
            reason[i] = "mounting self-calibration not settled yet"
        pts = pts & ~calibration_wait
        lines_ok = lines_ok & ~calibration_wait

    steps = []
    usable = np.isfinite(psi_rwy)
    for j in range(len(times)):
        f = frame_of_step[j]
        points_j = lines_j = center_j = None
        if f >= 0:
            if pts[f]:
                points_j = yv[f].copy()
            if lines_ok[f]:
                lines_j = features.lines[f].copy()
                if np.isfinite(features.center_line[f]).all():
                    center_j = features.center_line[f].copy()
        steps.append(ObserverInput(
            t_s=float(times[j]),
            # before the first d_F there is no runway heading: no observer starts there (NaN marks it)
            v_runway_mps=v_runway[j],
            v_camera_mps=v_camera[j],
            omega_camera_rps=omega_camera[j],
            n_camera=n_camera[j],
            R_runway_from_camera=R_rc[j],
            points_yv=points_j, lines=lines_j, center_line=center_j,
            dpsi_rad=float(dpsi[j]) if usable[j] else math.nan,
            roll_rad=float(ins.roll_rad[j]), pitch_rad=float(ins.pitch_rad[j]),
            tas_mps=math.nan if ins.tas_mps is None else float(ins.tas_mps[j]),
            slope=float(slope[j])))
    return PreparedInputs(steps=steps, t_s=times, frame_of_step=frame_of_step, step_of_frame=step_of_frame,
                          frame_t_s=frame_t, psi_runway_rad=psi_rwy, dpsi_rad=dpsi, dpsi_frame_rad=dpsi_frame,
                          frame_reason=reason, points_ok=pts, lines_ok=lines_ok, calibration=calibration)
