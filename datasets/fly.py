"""``visland fly``: the autopilot flies on the vision estimates (closed loop), flares and lands.

At every step of the flight model (50 Hz; a camera frame every other step at 25 Hz):

1. the camera sees the runway from the *true* state: either a rendered frame measured by
   runway detection (``--measure detection``), or, fast, the exact image features
   (:func:`visland.features.ideal_features`) with white pixel noise on the corners
   (``--measure simulated``, the thesis's "analyse d'images simulée", 5.1.2);
2. the inputs are prepared as :func:`visland.estimation.inputs.prepare_inputs` prepares them,
   causally, one step at a time (:class:`StepInputs`: d_F -> dpsi, the runway heading as the
   weighted running mean of ``heading - dpsi``, velocities in runway axes, virtual coordinates);
3. the chosen observer (a two-point observer: the glide path needs dX) steps, and its
   dX, dY, dH and the heading deviation give the perceived position and ground velocity that the
   ILS laws of :mod:`visland.flight` (the same laws as ``visland simulate``) turn into orders;
   ``--truth-guided`` gives the laws the true state instead (the baseline: it lands whatever
   the monitor says of the estimates; a go-around decision is recorded as
   ``monitor_would_go_around``, not flown);
4. below the flare height (main gear, :class:`visland.flight.FlareParams`) the flare law takes
   over, its height from the vision estimate or from a simulated radio altimeter (true height
   plus white noise, valid below 50 ft) (``--flare-height-source``);
5. a monitor decides at 400, 200 and 100 ft (true height: the radio altimeter's call-outs)
   whether to continue: the detection's success and confidence over the last second, the
   observer's coasting, its observability index (thesis 3.30), and the disagreement between the point observer and a line observer
   (``ekf-2l``) on dH and dY. A go-around is flown (wings level, climb) and counted.

The run ends at main-gear touchdown (or a few seconds into a go-around) with one JSON line.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from visland.flight import FT_TO_M, FlareParams, FlightModel

__all__ = ["FlyOptions", "fly", "MonitorParams", "StepInputs"]

MEASURE_MODES = ("simulated", "detection")
HEIGHT_SOURCES = ("vision", "radio")
RADIO_ALTIMETER_MAX_M = 50 * FT_TO_M


@dataclass(frozen=True)
class MonitorParams:
    """Continue-or-go-around rule at the decision heights (see the module docstring).

    At each decision height (true height, the radio altimeter's call-out), in this order: the
    detection over the last ``window_s`` (found fraction, median confidence), the guidance
    observer's time since its last correction, its observability, then, below ``agreement_below_ft`` (at 200 and 100 ft: the
    line observer is not converged at 400 ft on the thesis approaches, 30-50 % off on thesis-1
    with a crosswind), its agreement with the line observer on dH and dY.

    Observability. The instantaneous index (thesis 3.30, ``O = |Phi|^2``, (m/s)^2) is small on a
    stabilised glide path by nature (the corners sit near the focus of expansion: 3-230 at 400 ft
    on a glide-path start, thesis-1 and thesis-3, against about 5000 in level flight), so a
    threshold on it would send nominal approaches around. What the height rests on is what the
    observer has *accumulated*: since ``y_v' = Phi eta`` (thesis 3.29), a relative height error
    ``d`` moves the predicted corners by ``d`` times their image motion due to the translation.
    That motion, in pixels of the real camera (the virtual-frame rate ``Phi eta`` of each measured
    corner carried through the camera's projection, summed over the two corners and the corrected
    steps), is the "depth flow" ``F``: a 1 px measurement resolves the height to about ``1 / F``.
    The decision asks ``F >= min_depth_flow_px`` (20 px: about 5 %); the window's median ``O``
    is reported too.

    Agreement. Two observers on the same frames that are each right differ by no more than
    their errors allow: with ``e_p`` and ``e_l`` the expected (RMS) relative dH errors of the
    point and the line observer at that height, their difference has a standard deviation of
    ``dH sqrt(e_p^2 + e_l^2)`` (independent errors: different features, different models), and
    the rule asks ``|dH_p - dH_l| <= agreement_sigmas dH sqrt(e_p^2 + e_l^2)``, dH the smaller of
    the two (a wrong high estimate must not widen its own tolerance). ``expected_dh_error``
    gives ``(height ft, e_p, e_l)``, the entry nearest the decision height applying. The defaults
    are what kf-2p and ekf-2l reached on rendered 512 px frames with detection (thesis-1/2/3 of
    the Monte Carlo, 3-4 flights, truth - estimate over dH): kf-2p 1.3 % RMS at 200 ft (largest
    1.9 %), 1.0 % at 100 ft (1.7 %); ekf-2l 2.6 % at 200 ft (4.3 %), 1.2 % at 100 ft (1.6 %),
    rounded up to 1.5/3 % and 1/1.5 %: 3 sigma is 10 % of dH at 200 ft (6.1 m) and 5.4 % at
    100 ft (1.6 m). The filters' own covariances are not used: on those flights they were
    2.5-10 times too small (ekf-2l's dH 2.6 m off at 200 ft with sigma 0.25 m). The former
    limit, 3 m or 5 % of dH at both heights, was 1.5 sigma of the expected gap at 200 ft (one
    nominal approach in seven sent around by it) and 5.5 sigma at 100 ft (a 3 m height error let
    through where the flare is 15 m away).

    Start. The measurements reach the heading estimate and the observers only once the detection
    passes the same test as at a decision height over a full window (found in ``min_found_fraction``
    of the last ``window_s``, median confidence ``min_confidence``), on a found frame; until then
    the aircraft flies wings level at the vertical speed it started with, for at most
    ``max_acquisition_s`` (then it goes around, the runway not acquired: without that bound a start
    15 deg off the runway heading, thesis-8-mc40 at 512 px, flew level past the runway for 400 s
    without the measurements ever being trusted). Far out a runway a few pixels wide is found
    in one frame of two or fewer, and those first detections are the least reliable: on
    thesis-2-mc1 at 512 px (5.7 km, runway 5 px wide) the first acquisition took a parallel
    object 21 px to the side, and kf-2p, started on it, was sent to dH 1900-2500 m and rejected
    every later measurement; from the first full second with the runway found in 80 % of the
    frames (8 s later, 5.4 km) every found corner was within 1.3 px of the exact one.

    Attributes
    ----------
    decision_heights_ft : tuple of float
        True heights (ft) at which the decision is taken.
    window_s : float
        How far back (s) the detection and the observability are judged.
    min_found_fraction : float
        Fraction of the window's frames in which the runway must be found.
    min_confidence : float
        Median detection confidence of the window's found frames, 0-1.
    agreement_sigmas : float
        ``|dH points - dH lines|`` must lie within this many of its expected standard deviation.
    expected_dh_error : tuple of tuple
        ``(height ft, points, lines)``: the RMS relative dH error of the point and the line
        observer expected at that height (the entry nearest the decision height applies).
    max_dy_disagreement_m : float
        Largest ``|dY points - dY lines|`` (m).
    max_coast_s : float
        Longest time (s) since the guidance observer's last correction.
    min_depth_flow_px : float
        Smallest accumulated corner motion due to the translation (px of the camera, "depth flow").
    agreement_below_ft : float
        The agreement is judged below this true height (ft) only.
    max_acquisition_s : float
        Longest time (s) from the start of the approach to the measurements being trusted
        ("Start"); beyond it the approach is abandoned (go-around) whatever the height.

    References
    ----------
    Thesis (seed 002) eq. 3.29-3.30 (the observability index ``O`` and ``y_v' = Phi eta``).
    """

    decision_heights_ft: tuple = (400.0, 200.0, 100.0)
    window_s: float = 1.0                 # how far back detection and observability are judged
    min_found_fraction: float = 0.8       # of the frames in the window
    min_confidence: float = 0.5           # median confidence of the found frames in the window
    agreement_sigmas: float = 3.0         # |dH points - dH lines| within this many of its expected standard deviation
    expected_dh_error: tuple = ((200.0, 0.015, 0.030), (100.0, 0.010, 0.015))   # (ft, points, lines): RMS dH error / dH
    max_dy_disagreement_m: float = 3.0    # |dY points - dY lines|
    max_coast_s: float = 0.5              # the guidance observer's time since its last correction
    min_depth_flow_px: float = 20.0       # accumulated corner motion due to the translation (see above)
    agreement_below_ft: float = 300.0     # the line observer converges later: agreement judged below this height only
    max_acquisition_s: float = 30.0       # the measurements trusted within this time of the start, or a go-around


@dataclass(frozen=True)
class StabilisedGate:
    """Where an approach must be stabilised for the flight-envelope report: at ``height_ft``
    (true height) within ``max_dgs_m`` of the glide path and ``max_dy_m`` of the centreline."""

    height_ft: float = 400.0
    max_dgs_m: float = 5.0
    max_dy_m: float = 10.0


@dataclass(frozen=True)
class FlyOptions:
    """What ``visland fly`` flies (see its --help); validated on construction (``ValueError``
    naming the option).

    Attributes
    ----------
    observer : str
        The two-point observer whose estimates guide (SPEC name; lines do not observe dX).
    monitor_observer : str
        The line observer the monitor compares it with.
    measure : str
        ``simulated`` (exact features plus ``pixel_noise_px``) or ``detection`` (rendered frames).
    pixel_noise_px : float
        Corner noise (px, standard deviation) in simulated mode.
    size : int
        Image width and height (px) of the SPEC default camera scaled to it.
    truth_guided : bool
        Fly on the true state (the baseline); the monitor's decision is recorded, not flown.
    flare_height_source : str
        ``vision`` (the estimate) or ``radio`` (a simulated radio altimeter below 50 ft).
    radio_noise_m : float
        The radio altimeter's white noise (m, standard deviation).
    initial_height_m : float or None
        The observers' initial height guess (m); None: ``initial_error`` above the true height.
    initial_error : float
        Relative error of the default initial guess (0.2: the seeds' 20 %).
    seed : int
        Seed of the pixel noise and the scene.
    fps : float
        Camera frame rate (Hz), a divisor of the 50 Hz flight rate.
    calibration_error_deg : tuple of float
        (roll, pitch, yaw) error (deg) of the camera mounting the estimator does not know.
    detection_lost_below_ft : float or None
        Fault: the runway is not found below this true height (ft).
    frozen_frames_at_ft : float or None
        Fault: the frame stream repeats one frame for 1 s from this true height (ft).
    monitor : MonitorParams
        The continue-or-go-around rule.
    gate : StabilisedGate
        Where the approach must be stabilised (the flight-envelope report).
    flare : visland.flight.FlareParams
        The flare law and the main gear.
    """

    observer: str = "kf-2p"
    monitor_observer: str = "ekf-2l"
    measure: str = "simulated"
    pixel_noise_px: float = 1.0
    size: int = 2048
    truth_guided: bool = False
    flare_height_source: str = "vision"
    radio_noise_m: float = 0.1
    initial_height_m: float | None = None
    initial_error: float = 0.2
    seed: int = 0
    fps: float = 25.0
    calibration_error_deg: tuple = (0.0, 0.0, 0.0)
    detection_lost_below_ft: float | None = None     # fault: the detector loses the runway below this height
    frozen_frames_at_ft: float | None = None         # fault: the frame stream freezes for 1 s at this height
    monitor: MonitorParams = field(default_factory=MonitorParams)
    gate: StabilisedGate = field(default_factory=StabilisedGate)
    flare: FlareParams = field(default_factory=FlareParams)

    def __post_init__(self):
        from visland.estimation.registry import observer_features
        if observer_features(self.observer) != "points":
            raise ValueError(f"--observer {self.observer}: fly needs dX for the glide path, which lines do not "
                             "observe; choose a two-point observer (e.g. kf-2p, ccpi-hg-2p)")
        if observer_features(self.monitor_observer) != "lines":
            raise ValueError(f"--monitor-observer {self.monitor_observer}: the monitor compares the point observer "
                             "with a line observer (e.g. ekf-2l)")
        if self.measure not in MEASURE_MODES:
            raise ValueError(f"--measure must be one of {', '.join(MEASURE_MODES)}, got {self.measure!r}")
        if self.flare_height_source not in HEIGHT_SOURCES:
            raise ValueError(f"--flare-height-source must be one of {', '.join(HEIGHT_SOURCES)}, "
                             f"got {self.flare_height_source!r}")
        if not (math.isfinite(self.pixel_noise_px) and self.pixel_noise_px >= 0):
            raise ValueError(f"--pixel-noise must be a non-negative number, got {self.pixel_noise_px!r}")
        if not (math.isfinite(self.fps) and 1.0 <= self.fps <= 50.0 and abs(50.0 / self.fps - round(50.0 / self.fps)) < 1e-9):
            raise ValueError(f"--fps must divide the 50 Hz flight rate (50, 25, 12.5, 10, ...), got {self.fps!r}")
        if self.initial_height_m is not None and not (math.isfinite(self.initial_height_m) and self.initial_height_m > 0):
            raise ValueError(f"--initial-height must be a positive number of metres, got {self.initial_height_m!r}")


class _Row(dict):
    """A one-row measurement table for :meth:`FeatureSeries.from_table`."""

    @property
    def n_rows(self):
        return 1


class StepInputs:
    """Causal, step-by-step version of :func:`visland.estimation.inputs.prepare_inputs` (without
    the mounting's self-calibration): the same quantities from the same helpers.

    Parameters
    ----------
    camera : visland.camera.CameraModel
        The camera the estimator is told about (its mounting turns d_F into dpsi).

    References
    ----------
    Gibert et al., range identification in perspective systems (seeds 001/003), appendix eq.
    18-19 (dpsi from d_F).
    """

    def __init__(self, camera):
        self.camera = camera
        self._sums = np.zeros(7)
        self._first = None
        self._settled = False
        self.psi_runway_rad = math.nan
        self._window: list = []

    def frame(self, row: dict, roll_rad: float, pitch_rad: float, heading_rad: float):
        """Take one frame's measurement row (labels schema + found); return its FeatureSeries."""
        from visland.estimation.inputs import (HEADING_SAMPLE_SETTLED_RAD, HEADING_SETTLED_RAD,
                                               HEADING_WINDOW_FRAMES, FeatureSeries, _dF_on_horizon,
                                               _dF_with_corner_fallback, _robust_heading_weights)
        from visland.features import dpsi_from_dF
        table = _Row({k: np.array([v]) for k, v in row.items()})
        features = FeatureSeries.from_table(table)

        class _Ins:
            pass
        ins = _Ins()
        ins.roll_rad, ins.pitch_rad = np.array([roll_rad]), np.array([pitch_rad])
        # d_F where the edges cross the inertial horizon, else as measured (prepare_inputs' order)
        dF = _dF_on_horizon(features, ins, self.camera)[0]
        if not np.isfinite(dF):
            dF = _dF_with_corner_fallback(features, ins, self.camera)[0]
        dpsi = float(dpsi_from_dF(np.array([dF]), ins.roll_rad, ins.pitch_rad, self.camera)[0]) if np.isfinite(dF) \
            else math.nan
        # the runway heading: the weighted circular running mean of heading - dpsi and its standard
        # error, as estimation.inputs._circular_running_mean / _running_standard_error, kept as sums;
        # each sample weighted by _robust_heading_weights over the last HEADING_WINDOW_FRAMES samples
        # (its value for the window's last sample is the offline one for that frame)
        sample = heading_rad - dpsi
        sample_sigma = math.inf
        if math.isfinite(sample):
            self._window.append(sample)
            del self._window[:-HEADING_WINDOW_FRAMES]
            w = 0.0                  # the first sample: no spread known yet
            if len(self._window) > 1:
                weights, sigmas = _robust_heading_weights(np.array(self._window))
                w, sample_sigma = float(weights[-1]), float(sigmas[-1])
            if self._first is None:
                self._first = sample
            x = (sample - self._first + math.pi) % (2 * math.pi) - math.pi
            self._sums += np.array([w * math.cos(sample), w * math.sin(sample), w, w * x, w * x * x, w * w, 1.0])
        c, s_, sw, swx, swxx, sww, n = self._sums
        if n >= 2 and sw > 0 and sww > 0:
            mean = swx / sw
            se = math.sqrt(max(swxx / sw - mean * mean, 0.0) / (sw * sw / sww))
            if se <= HEADING_SETTLED_RAD and sample_sigma <= HEADING_SAMPLE_SETTLED_RAD:
                self._settled = True
        if self._settled:
            self.psi_runway_rad = math.atan2(s_, c)
        return features

    def step(self, t_s, roll_rad, pitch_rad, heading_rad, omega_body_rps, v_ned_mps, features=None):
        """One :class:`ObserverInput` (None before the runway heading is known)."""
        from visland.estimation.base import ObserverInput
        from visland.features import batch_R_camera_from_runway, virtual_from_pixels
        from visland.frames import wrap_pi
        psi = self.psi_runway_rad
        if not math.isfinite(psi):
            return None
        dpsi = float(wrap_pi(heading_rad - psi))
        R_cr = batch_R_camera_from_runway(np.array([roll_rad]), np.array([pitch_rad]), np.array([dpsi]),
                                          self.camera.mount_rpy_rad)[0]
        R_rc = R_cr.T
        c, s = math.cos(psi), math.sin(psi)
        vn, ve, vd = v_ned_mps
        v_runway = np.array([c * vn + s * ve, -s * vn + c * ve, vd])
        points = lines = center = None
        if features is not None:
            if features.points_ok[0]:
                points = virtual_from_pixels(features.near_uv_px[:1], R_rc[None], self.camera)[0]
            if features.lines_ok[0]:
                lines = features.lines[0].copy()
                if np.isfinite(features.center_line[0]).all():
                    center = features.center_line[0].copy()
        return ObserverInput(t_s=float(t_s), v_runway_mps=v_runway, v_camera_mps=R_cr @ v_runway,
                             omega_camera_rps=np.asarray(omega_body_rps) @ self.camera.R_body_from_camera,
                             n_camera=R_cr[:, 2], R_runway_from_camera=R_rc, points_yv=points, lines=lines,
                             center_line=center, dpsi_rad=dpsi, roll_rad=float(roll_rad), pitch_rad=float(pitch_rad))


def _depth_flow_px(inp, dh_m, fx_px, dt_s) -> float:
    """Pixels the measured corners of ``inp`` move in ``dt_s`` through the translation alone:
    ``y_v' = Phi eta`` (thesis 3.29, :func:`visland.features.point_virtual_dynamics`) carried
    through the projection (virtual ray ``(y1, y2, 1)`` -> camera ray -> ``fx x / z``)."""
    from visland.features import point_virtual_dynamics
    y_v = np.asarray(inp.points_yv, float)
    y_dot, _ = point_virtual_dynamics(y_v, 1.0 / dh_m, np.asarray(inp.v_runway_mps, float))
    R_cr = np.asarray(inp.R_runway_from_camera, float).T
    total = 0.0
    for y, yd in zip(y_v, y_dot):
        a = R_cr @ np.array([y[0], y[1], 1.0])
        b = R_cr @ np.array([y[0] + yd[0] * dt_s, y[1] + yd[1] * dt_s, 1.0])
        if a[2] * b[2] <= 0:
            continue                       # behind the camera: no image motion to speak of
        total += fx_px * math.hypot(b[0] / b[2] - a[0] / a[2], b[1] / b[2] - a[1] / a[2])
    return total if math.isfinite(total) else 0.0


class _Tracked:
    """An observer run step by step, with its latest deviations."""

    def __init__(self, name, aim_m, fx_px):
        from visland.estimation.registry import make_observer, params_for_camera
        self.observer = make_observer(name, params_for_camera(name, fx_px))
        self.aim_m = aim_m
        self.started = False
        self.restarts = None               # visland.estimation.runner.Restarts, from the start
        self.last_correction_s = math.nan
        self.dx_m = self.dy_m = self.dh_m = math.nan
        self.observability = math.nan
        self.coast_reason = ""
        self.observability_log = []        # (t, O) on corrected steps
        self.fx_px = fx_px
        self.depth_flow_px = 0.0           # fx * integral of sqrt(O) / dH over corrected steps (MonitorParams)
        self._last_yv = None
        self._offset_m = None              # (dX, dY) of the last measured corners minus the observer's own

    def dh_sigma_m(self) -> float:
        """The observer's own standard deviation of dH (metres) from its covariance, NaN for an
        observer without one: kf-2p's ``P[Z, Z]``; ekf-2l's ``P[eta, eta]`` carried to
        ``dH = 1 / eta`` (``sigma_dH = sigma_eta / eta^2``, first order)."""
        obs = self.observer
        if not self.started:
            return math.nan
        if hasattr(obs, "_kf"):
            return math.sqrt(max(float(obs._kf.P[3, 3]), 0.0))
        if hasattr(obs, "_ekf"):
            eta = float(obs._ekf.x[4, 0]) if obs._ekf.x.ndim == 2 else float(obs._ekf.x[4])
            return math.sqrt(max(float(obs._ekf.P[4, 4]), 0.0)) / (eta * eta) if eta > 0 else math.nan
        return math.nan

    def step(self, inp, dh0_m):
        from visland.estimation.deviations import deviations_from_lines, deviations_from_points
        from visland.estimation.runner import Restarts, on_domain_bound
        obs = self.observer
        has = inp.points_yv is not None if obs.features == "points" else inp.lines is not None
        if not self.started:
            if not has:
                return
            obs.reset(inp, dh0_m)
            self.restarts = Restarts(obs, inp, dh0_m)
            self.started = True
            self.dh_m = dh0_m
            self.last_correction_s = inp.t_s
        elif (restarted := self.restarts.before_step(inp)) is not None:
            # after a long gap, from the height dead-reckoned since the last correction
            # (visland.estimation.runner.Restarts); its observability counts from here
            self.dh_m = restarted.dh_m
            self.observability = float(restarted.observability)
            self.last_correction_s = inp.t_s
            self.depth_flow_px = 0.0
            self.observability_log = []
        else:
            estimate = obs.step(inp)
            self.restarts.after_step(inp, estimate, on_domain_bound(estimate.dh_m))
            self.dh_m = estimate.dh_m
            self.observability = float(estimate.observability)
            if not estimate.coasting:
                if inp.points_yv is not None and self.dh_m > 0:
                    self.depth_flow_px += _depth_flow_px(inp, self.dh_m, self.fx_px,
                                                         min(inp.t_s - self.last_correction_s, 0.2))
                self.last_correction_s = inp.t_s
                if math.isfinite(self.observability):
                    self.observability_log.append((float(inp.t_s), self.observability))
                    if len(self.observability_log) > 400:
                        del self.observability_log[:200]
            else:
                self.coast_reason = estimate.reason or ""
        if obs.features == "points":
            # as visland.estimation.runner: the observer's own corners, unless it says they lag the
            # measured ones (kf-2p); then the measured corners on a frame that has them and, between
            # frames and while coasting, the last measured position moved as the observer predicts:
            # its own deviations plus the metres by which the last measured corners differed from
            # its own at that frame. (Read on the last measured corners as they were, the position
            # froze while the corners were out of the image: on thesis-4-mc3 the guidance turned on
            # a frozen dY for 30 s and crossed the centreline, 365 m left of it at 400 ft.)
            own_yv = obs.predicted_points_yv() if hasattr(obs, "predicted_points_yv") else None
            if own_yv is not None and not (np.isfinite(own_yv).all() and np.abs(own_yv).max() < 1e4):
                own_yv = None
            own_dev = deviations_from_points(own_yv, self.dh_m, self.aim_m) if own_yv is not None else None
            if own_dev is not None and getattr(obs, "deviations_from_own_points", True):
                d = own_dev
            elif inp.points_yv is not None:
                self._last_yv = inp.points_yv
                d = deviations_from_points(inp.points_yv, self.dh_m, self.aim_m)
                self._offset_m = ((d.dx_m - own_dev.dx_m, d.dy_m - own_dev.dy_m) if own_dev is not None
                                  and math.isfinite(own_dev.dx_m + own_dev.dy_m) else None)
            elif own_dev is not None and self._offset_m is not None:
                d = None
                self.dx_m, self.dy_m = own_dev.dx_m + self._offset_m[0], own_dev.dy_m + self._offset_m[1]
            else:
                d = deviations_from_points(self._last_yv, self.dh_m, self.aim_m) if self._last_yv is not None else None
            if d is not None:
                self.dx_m, self.dy_m = d.dx_m, d.dy_m
        elif inp.lines is not None:
            d = deviations_from_lines(inp.lines, inp.R_runway_from_camera, self.dh_m)
            self.dy_m = d.dy_m


def _measure_simulated(state, runway, camera, camera_true, noise_px, rng):
    from visland.features import ideal_features
    features = ideal_features(state.frame_states(), runway, camera, camera_true=camera_true,
                              pixel_noise_px=noise_px, rng=rng)
    cols = features.as_columns()
    row = {k: float(np.asarray(v)[0]) for k, v in cols.items()}
    row.update(found=1.0, confidence=1.0)
    return row


def _measurement_row_from_detection(result, t_s):
    from visland.contracts import LABEL_COLUMNS
    values = result.to_measurement_row() if result.found else {}
    row = {c: math.nan for c in LABEL_COLUMNS if c not in ("frame",)}
    row.update({k: v for k, v in values.items() if k in row})
    row.update(t_s=t_s, found=1.0 if result.found else 0.0, confidence=float(result.confidence))
    return row


def _empty_row(t_s, why=""):
    from visland.contracts import LABEL_COLUMNS
    row = {c: math.nan for c in LABEL_COLUMNS if c not in ("frame",)}
    row.update(t_s=t_s, found=0.0, confidence=0.0)
    return row


def fly(scenario, options: FlyOptions, echo=None) -> dict:
    """Fly ``scenario`` closed loop (module docstring); return the figures of the JSON line.

    Parameters
    ----------
    scenario : visland.scenarios.Scenario
        The approach's start, runway and wind.
    options : FlyOptions
        What to fly and how.
    echo : callable, optional
        Takes each printed line (a str); None: nothing printed.

    Returns
    -------
    dict
        ``touchdown_x_m``, ``touchdown_y_m`` (main gear in the runway frame, m; None after a
        go-around), ``sink_rate_mps``, ``go_around`` and its reason, ``dh_err_100ft_m`` (truth -
        estimate), the decisions at each decision height, ``wall_s`` and the other figures of the
        JSON line.

    References
    ----------
    Thesis (seed 002) ch. 4 (the observers) and 3.30 (their observability index).
    """
    from visland.camera import CameraModel
    from visland.sensors import camera_with_calibration_error
    from visland.features import batch_R_camera_from_runway
    wall0 = time.perf_counter()
    rng = np.random.default_rng(options.seed)
    model = FlightModel(scenario, flare=options.flare)
    runway = scenario.runway
    aim = runway.aim_distance_m
    camera = CameraModel.default(options.size)
    camera_true = (camera_with_calibration_error(camera, options.calibration_error_deg)
                   if np.any(options.calibration_error_deg) else camera)
    steps_per_frame = int(round(50.0 / options.fps))
    prep = StepInputs(camera)
    guide_obs = _Tracked(options.observer, aim, camera.fx)
    monitor_obs = _Tracked(options.monitor_observer, aim, camera.fx)
    dh0 = options.initial_height_m or (1.0 + options.initial_error) * scenario.initial_height_m
    renderer = detector = None
    if options.measure == "detection":
        from visland.detection import DetectionSequence
        from visland.render import FrameRenderer
        from visland.render.params import SceneParams
        renderer = FrameRenderer(SceneParams(seed=options.seed), camera_true, runway)
        detector = DetectionSequence(camera, None)
    frames_log = []           # (t, found, confidence)
    trace = []                # per frame: t, true height, found, confidence, guidance dH and dY (before this frame)
    decisions = []
    go_around = False
    go_around_reason = ""
    go_around_t = None
    monitor_would_go_around = ""
    flaring = False
    dh_err_100 = math.nan
    deviations_at = {}
    # a decision height the approach starts below is not called out (no detection history to judge yet)
    h_start = -model.current().p_runway_m[2]
    heights_pending = sorted((h for h in options.monitor.decision_heights_ft if h * FT_TO_M < h_start), reverse=True)
    log_heights = [400.0, 200.0, 100.0, 50.0]
    envelope = _EnvelopeLog(options.gate, h_start)
    measure_s = estimate_s = 0.0
    frozen_image = None
    frozen_until = None
    trusted_from = None       # where the measurements were first trusted (MonitorParams, "Start")
    hdot_start_mps = -float(model.current().v_ned_mps[2])
    t_start_s = float(model.current().t_s)
    k = 0
    max_steps = int(400 * 50)
    while k < max_steps:
        state = model.current()
        h_true = -state.p_runway_m[2]
        t = state.t_s
        features = None
        # once a go-around is decided nothing reads the camera any more: its 10 s are flown on the
        # go-around orders alone, without rendering or measuring (100-250 frames per go-around)
        if k % steps_per_frame == 0 and not go_around:
            tic = time.perf_counter()
            lost = (options.detection_lost_below_ft is not None and h_true < options.detection_lost_below_ft * FT_TO_M)
            if options.frozen_frames_at_ft is not None and frozen_until is None \
                    and h_true < options.frozen_frames_at_ft * FT_TO_M:
                frozen_until = t + 1.0
            frozen = frozen_until is not None and t < frozen_until
            if lost:
                row = _empty_row(t)
            elif options.measure == "simulated":
                if frozen and frozen_image is not None:
                    row = dict(frozen_image, t_s=t)
                else:
                    row = _measure_simulated(state, runway, camera, camera_true, options.pixel_noise_px, rng)
                    frozen_image = row
            else:
                if frozen and frozen_image is not None:
                    image = frozen_image
                else:
                    R_cr = batch_R_camera_from_runway(np.array([state.roll_rad]), np.array([state.pitch_rad]),
                                                      np.array([state.dpsi_rad]), camera_true.mount_rpy_rad)[0]
                    image = renderer.render(state.p_runway_m, R_cr, frame_seed=k)
                    frozen_image = image
                result = detector(image, state.roll_rad, state.pitch_rad, t)
                row = _measurement_row_from_detection(result, t)
            measure_s += time.perf_counter() - tic
            frames_log.append((t, row["found"] > 0.5, row["confidence"]))
            trace.append((round(t, 2), round(h_true, 2), int(row["found"] > 0.5), _r(row["confidence"]),
                          _r(guide_obs.dh_m), _r(guide_obs.dy_m)))
            if trusted_from is None and _measurements_trusted(options.monitor, frames_log, t):
                trusted_from = {"t_s": round(t, 3), "dx_m": round(float(state.p_runway_m[0]) - aim, 1),
                                "dh_m": round(h_true, 1)}
            # nothing reaches the heading estimate or the observers before the detection is
            # trusted (MonitorParams, "Start")
            features = prep.frame(row if trusted_from is not None else _empty_row(t), state.roll_rad,
                                  state.pitch_rad, state.heading_rad)
        tic = time.perf_counter()
        inp = prep.step(t, state.roll_rad, state.pitch_rad, state.heading_rad, state.omega_body_rps,
                        state.v_ned_mps, features)
        if inp is not None:
            guide_obs.step(inp, dh0)
            monitor_obs.step(inp, dh0)
        estimate_s += time.perf_counter() - tic

        # ---- what the guidance believes
        if options.truth_guided:
            p_seen, v_seen = state.p_runway_m, state.v_runway_mps
            dh_seen = h_true
        elif inp is not None and guide_obs.started and math.isfinite(guide_obs.dx_m):
            dh_seen = guide_obs.dh_m
            p_seen = np.array([guide_obs.dx_m + aim, guide_obs.dy_m, -dh_seen])
            v_seen = inp.v_runway_mps
        else:
            p_seen = v_seen = None
            dh_seen = math.nan
        for h_ft in list(log_heights):
            if h_true <= h_ft * FT_TO_M:
                log_heights.remove(h_ft)
                deviations_at[f"{h_ft:g}ft"] = {
                    "dy_m": float(state.p_runway_m[1]),
                    "dgs_m": float(h_true + (state.p_runway_m[0] - aim) * model.guide.tan_gs),
                    "dh_err_m": float(h_true - dh_seen) if math.isfinite(dh_seen) else None}
                if h_ft == 100.0 and math.isfinite(dh_seen):
                    dh_err_100 = float(h_true - dh_seen)

        # ---- the runway not acquired in time (MonitorParams, "Start")
        if trusted_from is None and not go_around and not monitor_would_go_around \
                and t - t_start_s > options.monitor.max_acquisition_s:
            _, why = _detection_test(options.monitor, frames_log, t)
            why = (f"runway not acquired: measurements not trusted within {options.monitor.max_acquisition_s:g} s "
                   f"of the start ({why or 'the last second passed the detection test only now'})")
            if options.truth_guided:
                monitor_would_go_around = why
            else:
                go_around, go_around_reason, go_around_t = True, why, t

        # ---- monitor at the decision heights
        if not go_around and heights_pending and h_true <= heights_pending[0] * FT_TO_M:
            h_ft = heights_pending.pop(0)
            ok, why = _monitor(options, frames_log, t, guide_obs, monitor_obs, h_true, h_ft)
            decisions.append({"height_ft": h_ft, "t_s": round(t, 3), "continue": ok, "reason": why,
                              "observability": _r(_recent_observability(guide_obs, t, options.monitor.window_s)),
                              "depth_flow_px": _r(guide_obs.depth_flow_px),
                              "coast_s": _r(t - guide_obs.last_correction_s),
                              "dh_true_m": round(h_true, 3), "dy_true_m": round(float(state.p_runway_m[1]), 3),
                              "dh_points_m": _r(guide_obs.dh_m), "dy_points_m": _r(guide_obs.dy_m),
                              "dh_lines_m": _r(monitor_obs.dh_m), "dy_lines_m": _r(monitor_obs.dy_m),
                              "dh_sigma_points_m": _r(guide_obs.dh_sigma_m()),
                              "dh_sigma_lines_m": _r(monitor_obs.dh_sigma_m())})
            if not ok and options.truth_guided:
                # the baseline lands whatever the estimators say: the decision is recorded, not flown
                monitor_would_go_around = monitor_would_go_around or f"{h_ft:g} ft: {why}"
            elif not ok:
                go_around, go_around_reason, go_around_t = True, f"{h_ft:g} ft: {why}", t

        # ---- orders
        gear_h = model.gear_height_m()
        if go_around:
            orders = model.go_around_orders()
        elif p_seen is None:
            # no estimate yet: wings level, the vertical speed the approach started with held
            orders = (0.0, model._vertical_orders(hdot_start_mps))
        else:
            bank, nz = model.guidance_orders(p_seen, v_seen)
            flare_h = _flare_height(options, dh_seen, gear_h, h_true, model, rng)
            if flaring or flare_h <= options.flare.flare_height_m:
                flaring = True
                bank, nz = model.flare_orders(bank, flare_h, math.hypot(*v_seen[:2]), -float(state.v_ned_mps[2]))
            else:
                envelope.orders(model.guide.saturated, t, h_true, model.dt)
            orders = (bank, nz)
        envelope.state(state, h_true, aim, model.guide.tan_gs)
        model.step(*orders)
        k += 1
        if model.touchdown is not None:
            break
        if go_around and t - go_around_t > 10.0:
            break
        if h_true < 0.5:
            break
    wall = time.perf_counter() - wall0
    envelope_report = envelope.report(scenario.name)
    td = model.touchdown
    gear = td["gear_runway_m"] if td else None
    out = {
        "scenario": scenario.name, "observer": options.observer, "measure": options.measure,
        "truth_guided": options.truth_guided, "flare_height_source": options.flare_height_source,
        "touchdown_x_m": float(gear[0]) if gear is not None else None,
        "touchdown_y_m": float(gear[1]) if gear is not None else None,
        "sink_rate_mps": float(td["sink_rate_mps"]) if td else None,
        "touchdown_t_s": float(td["t_s"]) if td else None,
        "go_around": go_around, "go_around_reason": go_around_reason,
        "monitor_would_go_around": monitor_would_go_around,
        "dh_err_100ft_m": dh_err_100 if math.isfinite(dh_err_100) else None,
        "decisions": decisions, "deviations": deviations_at,
        "in_window": bool(gear is not None and 60.0 <= gear[0] <= 823.0 and abs(gear[1]) <= runway.width_m / 2),
        "measurements_trusted_from": trusted_from,
        "observer_restarts": [f"{o.observer.name}: {note}" for o in (guide_obs, monitor_obs) if o.started
                              for note in o.restarts.notes],
        "frames": len(frames_log), "measure_s": round(measure_s, 3), "estimate_s": round(estimate_s, 3),
        "envelope": envelope_report,
        "trace": {"columns": ["t_s", "dh_true_m", "found", "confidence", "dh_m", "dy_m"], "rows": trace},
        "wall_s": round(wall, 3),
    }
    if renderer is not None:
        renderer.close()
    return out


class _EnvelopeLog:
    """What the flight-envelope report needs: how long each autopilot limit bound the guidance
    orders (:attr:`visland.flight._Guidance.saturated`), the deviations at the stabilisation
    gate, and the extremes of thesis 1.3.2's limits (:data:`visland.flight.FLIGHT_LIMITS`)."""

    def __init__(self, gate: StabilisedGate, h_start_m: float):
        self.gate = gate
        self.gate_m = gate.height_ft * FT_TO_M
        self.gate_applies = h_start_m > self.gate_m
        self.at_gate = None                  # (dgs_m, dy_m)
        self.bound = {}                      # limit -> [seconds above the gate, seconds in all, first t, lowest h]
        self.extremes = {}
        self._last_roll = None

    def orders(self, saturated, t, h_m, dt):
        for name in saturated:
            b = self.bound.setdefault(name, [0.0, 0.0, t, h_m])
            b[0] += dt if h_m > self.gate_m else 0.0
            b[1] += dt
            b[3] = min(b[3], h_m)

    def state(self, state, h_m, aim_m, tan_gs):
        if self.gate_applies and self.at_gate is None and h_m <= self.gate_m:
            self.at_gate = (float(h_m + (state.p_runway_m[0] - aim_m) * tan_gs), float(state.p_runway_m[1]))
        values = {"gamma_deg": math.degrees(state.gamma_rad), "nz_g": state.nz_g, "roll_deg": math.degrees(state.roll_rad)}
        if self._last_roll is not None:
            values["roll_rate_dps"] = math.degrees(state.roll_rad - self._last_roll[1]) / max(state.t_s - self._last_roll[0], 1e-9)
        self._last_roll = (state.t_s, state.roll_rad)
        for name, v in values.items():
            lo, hi = self.extremes.get(name, (v, v))
            self.extremes[name] = (min(lo, v), max(hi, v))

    def report(self, scenario_name: str) -> dict:
        """``flyable`` (stabilised at the gate and inside thesis 1.3.2's limits), the limits that
        bound, and one sentence naming the scenario and the violated limit when not flyable."""
        from visland.flight import FLIGHT_LIMITS
        g = self.gate
        exceeded = [f"{name} reached {lo if lo < FLIGHT_LIMITS[name][0] else hi:.1f} (limit {FLIGHT_LIMITS[name][0]:g} .. "
                    f"{FLIGHT_LIMITS[name][1]:g})" for name, (lo, hi) in self.extremes.items()
                    if lo < FLIGHT_LIMITS[name][0] - 1e-9 or hi > FLIGHT_LIMITS[name][1] + 1e-9]
        unstable = []
        if self.at_gate is not None:
            dgs, dy = self.at_gate
            if abs(dgs) > g.max_dgs_m:
                unstable.append(f"{abs(dgs):.1f} m {'above' if dgs > 0 else 'below'} the glide path")
            if abs(dy) > g.max_dy_m:
                unstable.append(f"{abs(dy):.1f} m {'right' if dy > 0 else 'left'} of the centreline")
        before_gate = sorted(((b[0], name) for name, b in self.bound.items() if b[0] > 0), reverse=True)
        out = {"flyable": not (exceeded or unstable),
               "gate_ft": g.height_ft if self.gate_applies else None,
               "dgs_at_gate_m": _r(self.at_gate[0]) if self.at_gate else None,
               "dy_at_gate_m": _r(self.at_gate[1]) if self.at_gate else None,
               "limits_bound": {name: {"s_above_gate": round(b[0], 2), "s": round(b[1], 2), "first_t_s": round(b[2], 2),
                                       "lowest_ft": round(b[3] / FT_TO_M)} for name, b in self.bound.items()},
               "flight_limits_exceeded": exceeded, "report": ""}
        if out["flyable"]:
            return out
        parts = []
        if unstable:
            parts.append(f"not stabilised at the {g.height_ft:g} ft gate ({' and '.join(unstable)}; the gate allows "
                         f"{g.max_dgs_m:g} m and {g.max_dy_m:g} m)")
        if before_gate:
            seconds, name = before_gate[0]
            parts.append(f"the limit that bound: the {name} for {seconds:.1f} s before the gate")
        elif unstable:
            parts.append("no autopilot limit bound the orders (the guidance had not converged)")
        if exceeded:
            parts.append("thesis 1.3.2 limit exceeded: " + "; ".join(exceeded))
        out["report"] = f"{scenario_name} cannot be flown within the flight envelope: " + ", ".join(parts) + \
            "; flown anyway."
        return out


def _r(value):
    return round(float(value), 3) if value is not None and math.isfinite(value) else None


def _flare_height(options, dh_seen, gear_h_true, h_true, model, rng):
    """Main-gear height the flare law reads: the vision estimate (CG height minus the gear's
    offset, true attitude), or the radio altimeter below 50 ft (true gear height plus noise)."""
    offset = h_true - gear_h_true
    if options.truth_guided:
        return gear_h_true
    if options.flare_height_source == "radio" and h_true <= RADIO_ALTIMETER_MAX_M:
        return gear_h_true + float(rng.normal(0.0, options.radio_noise_m))
    return dh_seen - offset


def _recent_observability(tracked, t, window_s):
    """Median observability index of ``tracked``'s corrected steps in the last ``window_s`` (NaN if none)."""
    values = [o for (to, o) in tracked.observability_log if t - to <= window_s + 1e-9]
    return float(np.median(values)) if values else math.nan


def _detection_test(m, frames_log, t):
    """(passed?, reason): the runway found in at least ``m.min_found_fraction`` of the frames of
    the last ``m.window_s`` with a median confidence of at least ``m.min_confidence`` (passed when
    no frame is in the window)."""
    recent = [(found, conf) for (tf, found, conf) in frames_log if t - tf <= m.window_s + 1e-9]
    if recent:
        found_fraction = sum(f for f, _ in recent) / len(recent)
        if found_fraction < m.min_found_fraction:
            return False, f"runway found in {found_fraction:.0%} of the frames of the last {m.window_s:g} s"
        confidences = [c for f, c in recent if f]
        if confidences and float(np.median(confidences)) < m.min_confidence:
            return False, f"detection confidence {float(np.median(confidences)):.2f} < {m.min_confidence:g}"
    return True, ""


def _measurements_trusted(m, frames_log, t) -> bool:
    """Whether the observers may start on the detections (:class:`MonitorParams`, "Start"): a
    full window of frames behind ``t`` that passes :func:`_detection_test`, and the frame at
    ``t`` found."""
    if not frames_log or not frames_log[-1][1] or t - frames_log[0][0] < m.window_s - 1e-9:
        return False
    return _detection_test(m, frames_log, t)[0]


def _dh_agreement_limit_m(m, h_ft, dh_points_m, dh_lines_m) -> float:
    """The largest |dH points - dH lines| that passes at decision height ``h_ft``
    (:class:`MonitorParams`, "Agreement")."""
    _, e_points, e_lines = min(m.expected_dh_error, key=lambda entry: abs(entry[0] - h_ft))
    return m.agreement_sigmas * min(dh_points_m, dh_lines_m) * math.hypot(e_points, e_lines)


def _monitor(options, frames_log, t, guide_obs, monitor_obs, h_true, h_ft=200.0):
    """(continue?, reason): the rule of :class:`MonitorParams`."""
    m = options.monitor
    ok, why = _detection_test(m, frames_log, t)
    if not ok:
        return False, why
    if not guide_obs.started or not math.isfinite(guide_obs.dx_m):
        return False, f"no estimate from {guide_obs.observer.name}"
    if t - guide_obs.last_correction_s > m.max_coast_s:
        return False, f"{guide_obs.observer.name} coasting for {t - guide_obs.last_correction_s:.1f} s"
    if not guide_obs.depth_flow_px >= m.min_depth_flow_px:
        return False, (f"{guide_obs.observer.name}'s height is weakly observable: its corners moved "
                       f"{guide_obs.depth_flow_px:.1f} px through the translation since its start "
                       f"(< {m.min_depth_flow_px:g} px, a height resolved to worse than "
                       f"{100.0 / max(m.min_depth_flow_px, 1e-9):.0f} %)")
    if h_ft < m.agreement_below_ft and monitor_obs.started and math.isfinite(monitor_obs.dh_m):
        limit = _dh_agreement_limit_m(m, h_ft, guide_obs.dh_m, monitor_obs.dh_m)
        gap = abs(guide_obs.dh_m - monitor_obs.dh_m)
        if gap > limit:
            return False, (f"dH of {guide_obs.observer.name} and {monitor_obs.observer.name} differ by {gap:.1f} m "
                           f"(> {limit:.1f} m)")
        if math.isfinite(monitor_obs.dy_m) and abs(guide_obs.dy_m - monitor_obs.dy_m) > m.max_dy_disagreement_m:
            return False, (f"dY of {guide_obs.observer.name} and {monitor_obs.observer.name} differ by "
                           f"{abs(guide_obs.dy_m - monitor_obs.dy_m):.1f} m")
    return True, "estimates consistent"


#: The Monte Carlo's scenarios, flown in turn: the thesis's eight and ECC'15's three.
MONTE_CARLO_SCENARIOS = tuple(f"thesis-{k}" for k in range(1, 9)) + ("ecc-1", "ecc-2", "ecc-3")
KT_TO_MPS = 0.514444


def monte_carlo_cases(n: int, seed: int = 0):
    """``n`` (scenario, seed) cases: the scenarios in turn, a crosswind drawn in 0-15 kt (either
    side), a Dickmanns gust on every other case, the pixel-noise seed = the case number."""
    from dataclasses import replace
    from visland.scenarios import resolve_scenario
    rng = np.random.default_rng(seed)
    cases = []
    for i in range(n):
        base = resolve_scenario(MONTE_CARLO_SCENARIOS[i % len(MONTE_CARLO_SCENARIOS)])
        crosswind = float(rng.uniform(0.0, 15.0) * KT_TO_MPS * rng.choice([-1.0, 1.0]))
        wind = replace(base.wind, crosswind_mps=crosswind, gust=bool(i % 2))
        cases.append((replace(base, name=f"{base.name}-mc{i}", wind=wind), seed + i))
    return cases


GUIDANCE_SOURCES = ("detection", "simulated", "truth")


def guidance_sources(options: FlyOptions, sources=None) -> tuple:
    """What each Monte Carlo case is flown on: by default ``options.measure`` (the estimates on
    detected or simulated features), the ideal-measurement loop (exact features + pixel noise)
    when that is not already the first, and the truth (the baseline); or ``sources``, a subset
    of :data:`GUIDANCE_SOURCES` (e.g. ``("detection", "truth")``: the ideal-feature loop is a
    third of a rendered-frame campaign's time and none of its must-show figures)."""
    if sources is None:
        return (options.measure,) + (("simulated",) if options.measure != "simulated" else ()) + ("truth",)
    sources = tuple(dict.fromkeys(sources))
    unknown = [s for s in sources if s not in GUIDANCE_SOURCES]
    if unknown or not sources:
        raise ValueError(f"--sources must name one or more of {', '.join(GUIDANCE_SOURCES)}, got "
                         f"{','.join(sources) or 'nothing'}")
    return sources


def _options_for(options: FlyOptions, source: str, seed: int) -> FlyOptions:
    from dataclasses import replace
    if source == "truth":
        return replace(options, truth_guided=True, measure="simulated", seed=seed)
    return replace(options, truth_guided=False, measure=source, seed=seed)


def fly_and_keep(scenario, options: FlyOptions, path, cv_threads: dict | None = None) -> dict:
    """Fly one Monte Carlo flight and write its JSON to ``path`` atomically (None: not written; a
    Dask task returns it and the client writes it); return it. Module level, so that a Dask
    worker can run it. ``cv_threads``: on Dask, worker address -> OpenCV threads
    (:func:`visland.datasets.batch.opencv_threads_per_worker`)."""
    import json
    from visland.contracts import atomic_write_text, json_ready
    if cv_threads:
        import cv2
        from dask.distributed import get_worker
        cv2.setNumThreads(cv_threads.get(get_worker().address, 0))
    r = json_ready(fly(scenario, options))
    if path is not None:
        atomic_write_text(path, json.dumps(r) + "\n")
    return r


def _fly_on_cluster(pending, scheduler: str, echo) -> None:
    """Fly ``pending`` ``(scenario, options, path)`` flights as one Dask task each on the cluster
    at ``scheduler``; each flight's JSON comes back and is written here (the workers need no file
    system shared with this process)."""
    import json
    import os

    from dask.distributed import as_completed

    from visland.contracts import atomic_write_text
    from visland.datasets.batch import opencv_threads_per_worker
    from visland.datasets.cluster import connect_scheduler
    client = connect_scheduler(scheduler)
    with client:
        shares = opencv_threads_per_worker(client.scheduler_info()["workers"], client.run(os.cpu_count))
        echo(f"monte carlo: {len(pending)} flights on the Dask cluster at {scheduler}")
        futures = {client.submit(fly_and_keep, scenario, options, None, shares, pure=False): path
                   for scenario, options, path in pending}
        for future in as_completed(list(futures), loop=client.loop):
            r = future.result()
            atomic_write_text(futures[future], json.dumps(r) + "\n")
            echo(f"{futures[future].name}: flown on the cluster ({r['wall_s']:.0f} s)")


def monte_carlo(n: int, options: FlyOptions, out_dir, echo=print, sources=None, scheduler: str | None = None) -> dict:
    """Fly ``n`` cases on each of :func:`guidance_sources` (``sources``: see there); write
    ``landings.csv`` and ``touchdowns.png`` into ``out_dir``; return the summary (the JSON line).

    Each flight's JSON is kept in ``out_dir/runs/`` (written atomically) and not flown again when
    the command is re-run: a campaign stopped part-way resumes where it stopped. ``scheduler``:
    a Dask scheduler address; the flights not yet flown are one task each on that cluster. The
    summary's ``flown`` and ``campaign_wall_s`` are the flights flown by this call and its wall
    time (the throughput)."""
    import json
    from pathlib import Path
    from visland.contracts import write_csv
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ValueError(f"--monte-carlo must be a positive number of cases, got {n!r}")
    wall0 = time.perf_counter()
    out = Path(out_dir)
    (out / "runs").mkdir(parents=True, exist_ok=True)
    rows = []
    flown_on = guidance_sources(options, sources)
    rate = "" if options.fps == 25.0 else f"-{options.fps:g}hz"      # the camera rate, when not the default
    flights = []
    for scenario, seed in monte_carlo_cases(n, options.seed):
        for source in flown_on:
            tag = (f"{source}-{options.size}px" if source == "detection" else source) + (rate if source != "truth" else "")
            flights.append((scenario, source, _options_for(options, source, seed),
                            out / "runs" / f"{scenario.name}-{tag}.json"))
    flown = [path for _, _, _, path in flights if not path.exists()]
    if scheduler is not None and flown:
        _fly_on_cluster([(scenario, o, path) for scenario, _, o, path in flights if not path.exists()], scheduler, echo)
    for scenario, source, flight_options, path in flights:
        if path.exists():
            r = json.loads(path.read_text())
        else:
            r = fly_and_keep(scenario, flight_options, path)
        rows.append(_landing_row(scenario, source, r))
        echo(f"{scenario.name} {source}: " + (
            f"go-around ({r['go_around_reason']})" if r["go_around"] else
            f"touchdown x {r['touchdown_x_m']:.0f} m, y {r['touchdown_y_m']:+.2f} m, sink {r['sink_rate_mps']:.2f} m/s"
            if r["touchdown_x_m"] is not None else "no touchdown") + f" ({r['wall_s']:.0f} s)")
        columns = {k: [row[k] if row[k] is not None else math.nan for row in rows] for k in rows[0]}
        write_csv(out / "landings.csv", columns, list(rows[0]))
    summary = _monte_carlo_summary(rows)
    summary["flown"] = len(flown)
    summary["campaign_wall_s"] = round(time.perf_counter() - wall0, 1)
    _plot_touchdowns(rows, out / "touchdowns.png")
    summary["landings_csv"] = str(out / "landings.csv")
    summary["plot"] = str(out / "touchdowns.png")
    return summary


def _landing_row(scenario, source, r) -> dict:
    dev = r["deviations"]
    decisions = {f"{d['height_ft']:g}": d for d in r["decisions"]}
    return {"case": scenario.name, "guidance": source, "truth_guided": int(source == "truth"),
            "crosswind_mps": scenario.wind.crosswind_mps, "gust": int(scenario.wind.gust),
            "touchdown_x_m": r["touchdown_x_m"], "touchdown_y_m": r["touchdown_y_m"],
            "sink_rate_mps": r["sink_rate_mps"], "go_around": int(r["go_around"]),
            "go_around_reason": r["go_around_reason"], "monitor_would_go_around": r.get("monitor_would_go_around", ""),
            "dh_err_100ft_m": r["dh_err_100ft_m"],
            **{f"{q}_{h}_m": (dev.get(h) or {}).get(q) for h in ("200ft", "100ft", "50ft") for q in ("dy", "dgs")},
            "observability_400ft": (decisions.get("400") or {}).get("observability"),
            "depth_flow_400ft_px": (decisions.get("400") or {}).get("depth_flow_px"),
            "frames": r["frames"], "measure_s": r["measure_s"], "estimate_s": r["estimate_s"], "wall_s": r["wall_s"]}


def _monte_carlo_summary(rows) -> dict:
    """Per guidance source: landings, go-arounds and why, touchdown mean and standard deviation
    along and across the runway; for the estimates, the touchdown along the runway against the
    truth-guided run of the same case."""
    truth = {r["case"]: r for r in rows if r["guidance"] == "truth"}
    summary = {"n_cases": len({r["case"] for r in rows})}
    for source in dict.fromkeys(r["guidance"] for r in rows):
        runs = [r for r in rows if r["guidance"] == source]
        landed = [r for r in runs if not r["go_around"] and r["touchdown_x_m"] is not None]
        x = np.array([r["touchdown_x_m"] for r in landed])
        y = np.array([r["touchdown_y_m"] for r in landed])
        along = [r["touchdown_x_m"] - truth[r["case"]]["touchdown_x_m"] for r in landed
                 if r["case"] in truth and truth[r["case"]]["touchdown_x_m"] is not None
                 and not truth[r["case"]]["go_around"]] if source != "truth" else []
        dh100 = [abs(r["dh_err_100ft_m"]) for r in landed if r["dh_err_100ft_m"] is not None]
        frames = sum(r["frames"] for r in runs)
        summary[source] = {
            "flights": len(runs), "landed": len(landed),
            "in_window": int(np.sum((x >= 60.0) & (x <= 823.0))) if len(x) else 0,
            "go_arounds": sum(r["go_around"] for r in runs),
            "go_around_reasons": [f"{r['case']}: {r['go_around_reason']}" for r in runs if r["go_around"]],
            "monitor_would_go_around": [f"{r['case']}: {r['monitor_would_go_around']}" for r in runs
                                        if r.get("monitor_would_go_around")],
            "touchdown_x_mean_m": float(x.mean()) if len(x) else None,
            "touchdown_x_std_m": float(x.std(ddof=1)) if len(x) > 1 else None,
            "touchdown_y_mean_m": float(y.mean()) if len(y) else None,
            "touchdown_y_std_m": float(y.std(ddof=1)) if len(y) > 1 else None,
            "touchdown_dy_p95_m": float(np.percentile(np.abs(y), 95)) if len(y) else None,
            "touchdown_dx_vs_truth_max_abs_m": float(np.max(np.abs(along))) if along else None,
            "sink_rate_max_mps": float(max(r["sink_rate_mps"] for r in landed)) if landed else None,
            "dh_err_100ft_max_abs_m": float(max(dh100)) if dh100 else None,
            "wall_s_per_flight": float(np.mean([r["wall_s"] for r in runs])),
            "measure_ms_per_frame": 1000.0 * sum(r["measure_s"] for r in runs) / frames if frames else None}
    return summary


def _plot_touchdowns(rows, path) -> None:
    """Touchdown points on the runway outline (default 3000 x 45 m) and the CS-AWO window."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(9, 3.2))
    ax.add_patch(plt.Rectangle((0, -22.5), 1000, 45, fill=False, color="0.3"))
    ax.axvspan(60, 823, color="tab:green", alpha=0.08, label="CS-AWO window 60-823 m")
    styles = {"truth": ("0.5", "x", "truth-guided"), "simulated": ("tab:orange", "+", "ideal features + noise"),
              "detection": ("tab:blue", "o", "rendered frames, detection")}
    for source in dict.fromkeys(r["guidance"] for r in rows):
        colour, marker, label = styles.get(source, ("tab:red", "s", source))
        pts = [(r["touchdown_x_m"], r["touchdown_y_m"]) for r in rows
               if r["guidance"] == source and r["touchdown_x_m"] is not None and not r["go_around"]]
        if pts:
            x, y = zip(*pts)
            ax.scatter(x, y, s=14, color=colour, label=f"{label} ({len(pts)})", marker=marker)
    ax.set_xlim(0, 1000)
    ax.set_ylim(-25, 25)
    ax.set_xlabel("x from the threshold (m)")
    ax.set_ylabel("y, right of the centreline (m)")
    ax.set_title("visland fly --monte-carlo: main-gear touchdown points (first 1000 m of the runway)")
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
