"""Run one observer over prepared inputs and collect its estimates at the camera frames.

The run starts at the first step carrying a measurement of the observer's features (its
measured part initialises the state, ``eta = 1/dh0``), steps through every later step (inertial
rate) and records one row per camera frame: dH, the deviations of
:mod:`visland.estimation.deviations`, the observability index, and whether the frame's step
coasted (and why). Frames before the start have no estimate (NaN) and say so.

A diverged observer is cut off (issue 19): every observer projects ``eta = 1/dH`` onto its
domain (:data:`visland.estimation.base.ETA_MIN`, ``ETA_MAX``: dH from 0.5 m to 20 km), so a
correction that left the physical domain shows as a height pinned on the domain's bound, which
is not a height. Such frames are withheld. Pinned for :data:`DIVERGED_AFTER_S` while
measurements keep correcting it, the observer has diverged: the run stops stepping it, every
later frame is withheld with the reason, and :attr:`ObserverRun.diverged_t_s` says when. One
that ends the run pinned is reported as diverged as well.

An observer is restarted after a long gap: the first measurement more than
:data:`RESTART_AFTER_S` after the last one resets it (:meth:`Observer.reset`) from that
measurement and the height dead-reckoned since the last correction with the inertial vertical
speed (``dH' = -v_z``, R axes z down), instead of correcting the state coasted through the gap.
Coasted open loop, an observer whose height had not converged drifts away (the robustness
study's dusk approach at 2048 px: ccpi-hg-2p started at 5.8 s 20 % high, corrected twice, then
20 s without corners; its height rose from 218 to 269 m while the aircraft descended to 83 m),
and the first correction after the gap threw it into the wrong basin: 31 m for 83 m, then
down to the domain's bound, 22.5 m off at 100 ft. :attr:`ObserverRun.notes` lists the restarts.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from visland.estimation.base import ETA_MAX, ETA_MIN, Observer, observer_measurement
from visland.estimation.deviations import DEFAULT_AIM_DISTANCE_M, deviations_from_lines, deviations_from_points
from visland.estimation.inputs import PreparedInputs

__all__ = ["ObserverRun", "run_observer", "MAX_COAST_S", "DIVERGED_AFTER_S", "DIVERGED_CORRECTIONS", "on_domain_bound"]


@dataclass
class ObserverRun:
    """One observer's estimates at the camera frames (arrays of shape (m,), NaN = no estimate).

    ``step_time_s`` is the wall time spent in ``Observer.step`` over the whole run (the cost
    the speed target is about); ``n_steps`` the number of steps taken. ``extras`` holds the
    per-frame outputs an observer reports beyond the SPEC columns (``extra_outputs()``, e.g. the
    wind of ``dickmanns-4d``); ``notes`` what the observer said once about the run (e.g. that it
    cannot estimate the wind without airspeed). ``diverged_t_s`` is the time from which the
    observer's height sat on its domain bound until it was cut off (NaN: it did not diverge),
    ``diverged`` one sentence saying so (empty if not).

    Attributes
    ----------
    observer, features : str
        The SPEC observer name and ``"points"`` or ``"lines"``.
    t_s : ndarray, shape (m,)
        Frame times, seconds.
    dh_m, dx_m, dy_m, width_m : ndarray, shape (m,)
        Estimated height above the runway, along- and cross-track deviations, runway width, metres.
    observability : ndarray, shape (m,)
        The observer's observability index (thesis 3.30 or 3.40).
    dpsi_rad : ndarray, shape (m,)
        Heading deviation used, radians.
    coasting : ndarray of bool, shape (m,)
        No measurement corrected the frame.
    reason : ndarray of str, shape (m,)
        Why a frame has no estimate (empty otherwise).
    start_t_s : float
        Time of the first measured step, seconds.
    dh0_m : float
        The initial height guess, metres.
    step_time_s : float
        Wall time in ``Observer.step``, seconds.
    n_steps : int
        Steps taken.
    params : dict
        The observer's parameters as run.
    extras : dict of str to ndarray
        Outputs beyond the SPEC columns.
    notes : list of str
        What the observer said once about the run.
    diverged_t_s : float
        When the height started sitting on its bound (NaN: never).
    diverged : str
        One sentence when it diverged, empty otherwise.
    restarts : list of str
        One sentence per restart after a long gap (:class:`Restarts`; also in ``notes``).
    """

    observer: str
    features: str
    t_s: np.ndarray
    dh_m: np.ndarray
    dx_m: np.ndarray
    dy_m: np.ndarray
    width_m: np.ndarray
    observability: np.ndarray
    dpsi_rad: np.ndarray
    coasting: np.ndarray
    reason: np.ndarray
    start_t_s: float
    dh0_m: float
    step_time_s: float
    n_steps: int
    params: dict = field(default_factory=dict)
    extras: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)
    diverged_t_s: float = math.nan
    diverged: str = ""
    restarts: list = field(default_factory=list)

    def __len__(self):
        return len(self.t_s)


#: Longest run of frames without a correcting measurement over which an estimate is still
#: reported: the model is exact dead reckoning only while the state was good, and beyond a few
#: seconds a coasted estimate is a guess, so it is withheld (NaN) and flagged instead.
MAX_COAST_S = 2.0
#: Virtual coordinates |X_v/Z_v| beyond this (a point 10^4 heights away) are not a runway corner.
_MAX_ABS_YV = 1e4
#: A height pinned on the observers' domain bound for this long (s), through at least
#: :data:`DIVERGED_CORRECTIONS` measurements that did not bring it back, is a diverged observer:
#: cut off. Shorter excursions are withheld frame by frame and the run goes on: on the thesis
#: scenarios an observer knocked onto the bound by a 0.5 deg mounting error or 5 px of noise came
#: back within 7.5 s when it came back at all (and then converged as without the excursion);
#: those that stayed longer stayed to the end of the run. One still on the bound at the end of
#: the run is reported as diverged too.
DIVERGED_AFTER_S = 10.0
DIVERGED_CORRECTIONS = 3
#: Seconds without a measurement after which the next one restarts the observer from the
#: height dead-reckoned since its last correction (module docstring). Shorter gaps are
#: coasted through: a Kalman filter's own prediction is the better dead reckoning, and its
#: covariance would be lost to a restart.
RESTART_AFTER_S = 10.0


def on_domain_bound(dh_m: float) -> bool:
    """True when ``dh_m`` sits on the observers' projection bound (0.5 m or 20 km, within 0.1 %):
    the projection hiding a correction outside the physical domain, not a height.

    Parameters
    ----------
    dh_m : float
        An estimated height above the runway, metres.

    Returns
    -------
    bool
    """
    return dh_m >= 0.999 / ETA_MIN or dh_m <= 1.001 / ETA_MAX


def run_observer(observer: Observer, prepared: PreparedInputs, dh0_m: float,
                 aim_distance_m: float = DEFAULT_AIM_DISTANCE_M, max_coast_s: float = MAX_COAST_S,
                 restart_after_s: float = RESTART_AFTER_S) -> ObserverRun:
    """Reset ``observer`` at its first measured step with the height guess ``dh0_m`` and run it.

    Frames more than ``max_coast_s`` after the last correction get no estimate (NaN) and the
    reason "no measurement for ... s"; frames whose height sits on the observer's domain bound
    get none either, and after :data:`DIVERGED_AFTER_S` there the observer is cut off; the first
    measurement more than ``restart_after_s`` after the last one restarts it from the
    dead-reckoned height (module docstring). Raises ``ValueError`` when no frame carries the
    observer's features.

    Parameters
    ----------
    observer : visland.estimation.base.Observer
        A fresh observer (:func:`visland.estimation.registry.make_observer`).
    prepared : visland.estimation.inputs.PreparedInputs
        The inputs of every step (:func:`visland.estimation.inputs.prepare_inputs`).
    dh0_m : float
        Initial guess of the height above the runway, metres.
    aim_distance_m : float, default 320
        Aiming point distance past the threshold, metres (for dX).
    max_coast_s : float, default 2
        Longest time without a correction that still gives an estimate, seconds.
    restart_after_s : float, default 10
        Gap without a measurement after which the next measurement restarts the observer,
        seconds (``math.inf``: never).

    Returns
    -------
    ObserverRun
    """
    if not (math.isfinite(max_coast_s) and max_coast_s > 0):
        raise ValueError(f"max_coast_s must be a positive number of seconds, got {max_coast_s!r}")
    if not restart_after_s > 0:
        raise ValueError(f"restart_after_s must be a positive number of seconds, got {restart_after_s!r}")
    start = prepared.first_step_with(observer.features)
    if start is None:
        raise ValueError(f"{observer.name}: no frame carries usable {observer.features} "
                         f"(every frame's measurement is missing)")
    m = len(prepared.frame_t_s)
    out = {k: np.full(m, np.nan) for k in ("dh_m", "dx_m", "dy_m", "width_m", "observability")}
    coasting = np.ones(m, dtype=bool)
    reason = np.full(m, "not started (no measurement yet)", dtype=object)
    steps = prepared.steps
    frame_of_step = prepared.frame_of_step
    has_points = hasattr(observer, "predicted_points_yv")
    # observers whose state holds the deviations themselves (dickmanns-4d) report them directly
    own_deviations = hasattr(observer, "deviations")
    extras = {}

    last_correction = [float(steps[start].t_s)]
    last_y1 = [math.nan]

    def record(j, estimate, pinned):
        f = frame_of_step[j]
        if f < 0:
            return
        inp = steps[j]
        if pinned:
            coasting[f] = True
            reason[f] = (f"height on the observer's domain bound (dH = {estimate.dh_m:g} m): not a height, "
                         f"estimate withheld")
            return
        if not estimate.coasting:
            last_correction[0] = float(inp.t_s)
        elif inp.t_s - last_correction[0] > max_coast_s:
            coasting[f] = True
            reason[f] = (f"no measurement for {inp.t_s - last_correction[0]:.1f} s (> {max_coast_s:g} s): "
                         f"estimate withheld ({estimate.reason})")
            return
        dh = estimate.dh_m
        if observer.features == "lines" and inp.slope != 0.0:
            dh = _level_height(dh, inp, last_y1)
        out["dh_m"][f] = dh
        out["observability"][f] = estimate.observability
        coasting[f] = estimate.coasting
        reason[f] = estimate.reason if estimate.coasting else ""
        if hasattr(observer, "extra_outputs"):
            for key, value in observer.extra_outputs().items():
                column = extras.get(key)
                if column is None:           # (not setdefault: its default would be built at every frame)
                    column = extras[key] = np.full(m, np.nan)
                column[f] = value
        if own_deviations:
            dev = observer.deviations(aim_distance_m)
            out["dx_m"][f], out["dy_m"][f], out["width_m"][f] = dev.dx_m, dev.dy_m, dev.width_m
        elif observer.features == "points":
            # the observer's own (filtered) corners, unless it says they lag the measured ones
            own = has_points and not (inp.points_yv is not None and not observer.deviations_from_own_points)
            yv = observer.predicted_points_yv() if own else inp.points_yv
            if yv is not None and not (np.isfinite(yv).all() and np.abs(yv).max() < _MAX_ABS_YV):
                yv = inp.points_yv       # a diverged prediction: fall back on the measured points
            if yv is not None:
                dev = deviations_from_points(yv, estimate.dh_m, aim_distance_m)
                out["dx_m"][f], out["dy_m"][f], out["width_m"][f] = dev.dx_m, dev.dy_m, dev.width_m
        elif inp.lines is not None:
            dev = deviations_from_lines(inp.lines, inp.R_runway_from_camera, dh)
            out["dy_m"][f], out["width_m"][f] = dev.dy_m, dev.width_m

    observer.reset(steps[start], dh0_m)
    first = _initial_estimate(observer, steps[start], dh0_m)
    record(start, first, on_domain_bound(first.dh_m))
    step = observer.step
    elapsed = 0.0
    bound_since = math.nan           # time from which the height sits on the domain bound
    corrected_on_bound = 0           # measurements that have not moved it off since
    diverged_t_s, diverged = math.nan, ""
    n_steps = 0
    restart = Restarts(observer, steps[start], dh0_m, restart_after_s)
    for j in range(start + 1, len(steps)):
        inp = steps[j]
        estimate = restart.before_step(inp)
        if estimate is not None:
            bound_since, corrected_on_bound = math.nan, 0
            if frame_of_step[j] >= 0:
                record(j, estimate, False)
            continue
        t0 = time.perf_counter()
        estimate = step(inp)
        elapsed += time.perf_counter() - t0
        n_steps += 1
        pinned = on_domain_bound(estimate.dh_m)
        restart.after_step(inp, estimate, pinned)
        if frame_of_step[j] >= 0:
            record(j, estimate, pinned)
        if not pinned:
            bound_since, corrected_on_bound = math.nan, 0
            continue
        t_s = float(steps[j].t_s)
        if not math.isfinite(bound_since):
            bound_since, corrected_on_bound = t_s, 0
        corrected_on_bound += not estimate.coasting
        if t_s - bound_since >= DIVERGED_AFTER_S - 1e-9 and corrected_on_bound >= DIVERGED_CORRECTIONS:
            diverged_t_s = bound_since
            diverged = (f"diverged: its height sat on its domain bound (dH = {estimate.dh_m:g} m) from "
                        f"t = {bound_since:.2f} s through {corrected_on_bound} measurements; cut off, no "
                        f"estimate from then on")
            later = prepared.frame_t_s >= bound_since - 1e-9
            for key in out:
                out[key][later] = np.nan
            coasting[later] = True
            reason[later] = diverged
            break
    if not diverged and math.isfinite(bound_since):
        diverged = (f"diverged: its height sat on its domain bound from t = {bound_since:.2f} s to the end of the "
                    f"run; no estimate from then on")
        diverged_t_s = bound_since
    params = observer.params.to_dict() if hasattr(observer.params, "to_dict") else {}
    dpsi = prepared.dpsi_rad[prepared.step_of_frame]
    if "dpsi_rad" in extras:             # an observer that corrects the heading deviation reports its own
        dpsi = np.where(np.isfinite(extras["dpsi_rad"]), extras["dpsi_rad"], dpsi)
    return ObserverRun(observer=observer.name, features=observer.features, t_s=prepared.frame_t_s.copy(),
                       coasting=coasting, reason=reason, dpsi_rad=dpsi,
                       start_t_s=float(steps[start].t_s), dh0_m=float(dh0_m), step_time_s=elapsed,
                       n_steps=n_steps, params=params, extras=extras,
                       notes=list(getattr(observer, "notes", ())) + restart.notes, diverged_t_s=diverged_t_s,
                       diverged=diverged, restarts=list(restart.notes),
                       **out)


class Restarts:
    """The restart of an observer after a long gap (module docstring), for a loop that steps it.

    Before each step, :meth:`before_step` carries the height dead-reckoned since the last
    correction to the input's time (``dH' = -v_z``, the previous input's inertial vertical
    speed, R axes z down) and, when the input carries a measurement more than
    ``restart_after_s`` after the last one, resets the observer there from that height and
    returns its initial estimate (the caller then does not step it); after each step,
    :meth:`after_step` takes the correction in. :attr:`notes` says when it restarted.

    Parameters
    ----------
    observer : visland.estimation.base.Observer
        The observer, already reset at ``first``.
    first : ObserverInput
        The input it was reset at.
    dh0_m : float
        The height it was reset with, metres.
    restart_after_s : float
        Gap without a measurement after which the next one restarts it, seconds.
    """

    def __init__(self, observer: Observer, first, dh0_m: float, restart_after_s: float = RESTART_AFTER_S):
        self.observer = observer
        self.restart_after_s = float(restart_after_s)
        self.dead_reckoned_m = float(dh0_m)
        self.last_measured_t_s = float(first.t_s)        # (a height pinned on the bound is measured too)
        self._previous = first
        self.notes = []

    def before_step(self, inp):
        """The initial estimate of a restart at ``inp``, or None: step the observer as usual."""
        previous, self._previous = self._previous, inp
        self.dead_reckoned_m -= float(previous.v_runway_mps[2]) * (float(inp.t_s) - float(previous.t_s))
        gap_s = float(inp.t_s) - self.last_measured_t_s
        height = self.dead_reckoned_m
        if not (gap_s > self.restart_after_s and height > 0 and ETA_MIN <= 1.0 / height <= ETA_MAX
                and observer_measurement(inp, self.observer.features)[0] is not None):
            return None
        self.observer.reset(inp, height)
        self.last_measured_t_s = float(inp.t_s)
        self.notes.append(f"restarted at t = {float(inp.t_s):.2f} s, {gap_s:.1f} s after its last measurement, "
                          f"from the height dead-reckoned since its last correction ({height:.1f} m)")
        return _initial_estimate(self.observer, inp, height)

    def after_step(self, inp, estimate, pinned: bool) -> None:
        """Take in the estimate of the step at ``inp`` (``pinned``: its height on the domain's bound)."""
        if not estimate.coasting:
            self.last_measured_t_s = float(inp.t_s)
            if not pinned:
                self.dead_reckoned_m = float(estimate.dh_m)


def _level_height(distance_m: float, inp, last_y1: list) -> float:
    """Height above the threshold's level from a line observer's distance to a sloped runway plane.

    The plane ``s x + z = 0`` (R, z down; ``s = inp.slope``) through the threshold is at the
    distance ``d = (h - s x) / sqrt(1 + s^2)`` from the camera at ``(x, ., -h)``; the threshold
    corners' virtual coordinate ``y_v1 = -x / h`` (thesis 3.23) gives ``x``, so
    ``h = d sqrt(1 + s^2) / (1 + s y_v1)``. Without the corners at this step the last ones seen are
    used; never seen: ``h = d`` (off by ``s x``).
    """
    if inp.points_yv is not None and np.isfinite(inp.points_yv[:, 0]).all():
        last_y1[0] = float(np.mean(inp.points_yv[:, 0]))
    s = inp.slope
    y1 = last_y1[0]
    if not math.isfinite(y1) or 1.0 + s * y1 <= 0.1:
        return distance_m
    return distance_m * math.sqrt(1.0 + s * s) / (1.0 + s * y1)


def _initial_estimate(observer, inp, dh0_m):
    from visland.estimation.base import Estimate
    state = observer._get_state()
    observability = math.nan
    if observer.features == "points" and inp.points_yv is not None:
        from visland.features import observability_points
        observability = float(observability_points(inp.points_yv, inp.v_runway_mps))
    elif inp.lines is not None:
        from visland.features import observability_lines
        observability = float(observability_lines([inp.lines[0], inp.lines[1]], inp.v_camera_mps,
                                                  inp.omega_camera_rps, inp.n_camera))
    return Estimate(t_s=float(inp.t_s), dh_m=float(dh0_m), observability=observability, coasting=False,
                    state=state)
