"""The interface every visland observer shares: prepared inputs, the estimate, the observer.

NOTE for the lines engineer (B): the names and fields of the interface brief are all here and
will not be renamed without a note at this spot. Added beyond the brief (all optional to use):
``ObserverInput.dpsi_rad/roll_rad/pitch_rad``, ``Estimate.reason``, ``ObserverParams`` (base of
every observer's frozen parameter dataclass: validation helpers, JSON/TOML round trip),
``Observer.params_type``, the template methods ``_reset/_step/_get_state/_set_state`` that
``reset``/``step`` wrap with the bad-input policy, and the helpers ``observer_measurement``,
``clip_eta``, ``ETA_MIN``/``ETA_MAX``.

Frames and conventions (SPEC.md, :mod:`visland.frames`, :mod:`visland.camera`): runway frame R
(x along the centreline, y right, z down, origin at the threshold centre); virtual frame V (the
runway axes carried to the camera centre, thesis 3.2.2); camera frame C (OpenCV); lines
``x cos(theta) + y sin(theta) = rho`` in normalised coordinates, theta in [-pi/2, pi/2).
Every observer estimates ``eta = 1/dH`` (dH the height above the runway plane, metres).

Timing: observers step at the inertial rate (50 Hz); a camera frame (25 Hz) brings a
measurement on every other step. ``step`` integrates the observer's model from the previous
time to ``inp.t_s`` and corrects with the measurement when there is one; otherwise it coasts on
its model and says so (``Estimate.coasting``).

Bad input (SPEC "Bad input"): a programming error raises one ``ValueError`` naming the field
(wrong shape, non-increasing time, a non-finite inertial input, a non-positive height guess);
a missing or non-finite *measurement* is a coasting step with a reason; a state that turns
non-finite or absurdly large (beyond :data:`STATE_LIMIT`), or a step whose arithmetic
overflows, is rolled back and the step is flagged, so no NaN ever reaches the output.
"""
from __future__ import annotations

import abc
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from visland.params import ParamsFile

__all__ = [
    "ObserverInput",
    "Estimate",
    "ObserverParams",
    "Observer",
    "observer_measurement",
    "clip_eta",
    "ETA_MIN",
    "ETA_MAX",
    "FEATURE_SETS",
]

#: Feature sets an observer may consume.
FEATURE_SETS = ("points", "lines")

#: Physical domain of ``eta = 1/dH`` (dH between 0.5 m and 20 km). Observers project their
#: estimate of eta onto it: a standard projection that keeps 1/eta finite and positive while
#: the correction is still large (the thesis's observers assume dH > 0, hypothesis 1.3.1).
ETA_MIN = 1.0 / 20000.0
ETA_MAX = 1.0 / 0.5

#: A state component beyond this magnitude is a diverged state (image coordinates, lines and
#: eta are all of order 1 to 1e3): the step is rolled back like a non-finite one.
STATE_LIMIT = 1e9


def clip_eta(eta: float) -> float:
    """Project an estimate of ``eta = 1/dH`` onto ``[ETA_MIN, ETA_MAX]`` (scalar, fast).

    Parameters
    ----------
    eta : float
        Inverse height, 1/m.

    Returns
    -------
    float
    """
    if eta < ETA_MIN:
        return ETA_MIN
    if eta > ETA_MAX:
        return ETA_MAX
    return eta


@dataclass(frozen=True)
class ObserverInput:
    """One step of prepared inputs (built by :mod:`visland.estimation.inputs`).

    Attributes
    ----------
    t_s : float
        Time of the step, seconds.
    v_runway_mps : (3,) ndarray
        Camera ground velocity in runway axes R, which are also the virtual-frame axes V
        (z down); thesis ``v`` of 3.24.
    v_camera_mps : (3,) ndarray
        The same velocity in camera axes C (thesis 3.37 ``v``).
    omega_camera_rps : (3,) ndarray
        Camera angular velocity in C: the IMU body rates through the mounting (thesis ``w``).
    n_camera : (3,) ndarray
        Runway down axis in C (thesis 3.33 ``n = cR0 [0 0 1]``), from roll, pitch and dpsi.
    R_runway_from_camera : (3, 3) ndarray
        Rotation of the camera axes into the runway axes (roll, pitch, dpsi and the mounting).
    points_yv : (2, 2) ndarray or None
        Virtual coordinates (thesis 3.23) ``[X_v/Z_v, Y_v/Z_v]`` of P' (row 0, near left) and
        P'' (row 1, near right); None when not measured at this step.
    lines : (2, 2) ndarray or None
        ``[[rho_left, theta_left], [rho_right, theta_right]]`` in the SPEC chart; None when not
        measured.
    center_line : (2,) ndarray or None
        ``[rho, theta]`` of the centre line, or None.
    dpsi_rad, roll_rad, pitch_rad : float
        The heading deviation used (from d_F, filtered) and the inertial roll and pitch, for
        observers and reports that need the attitude relative to the runway.
    tas_mps : float
        True airspeed (telemetry column ``tas_mps``), NaN when the telemetry has none; used by
        observers that estimate the wind (``dickmanns-4d``).
    slope : float
        The runway's longitudinal slope (``slope_pct / 100``, uphill positive) that ``n_camera``
        carries: 0 unless the mounting's self-calibration estimated it
        (:mod:`visland.estimation.calibration`). ``n_camera`` is then the sloped plane's normal
        and a line observer's ``1/eta`` the distance to that plane.
    """

    t_s: float
    v_runway_mps: np.ndarray
    v_camera_mps: np.ndarray
    omega_camera_rps: np.ndarray
    n_camera: np.ndarray
    R_runway_from_camera: np.ndarray
    points_yv: np.ndarray | None
    lines: np.ndarray | None
    center_line: np.ndarray | None = None
    dpsi_rad: float = 0.0
    roll_rad: float = 0.0
    pitch_rad: float = 0.0
    tas_mps: float = math.nan
    slope: float = 0.0


@dataclass
class Estimate:
    """What an observer reports after one step.

    Attributes
    ----------
    t_s : float
        Time of the estimate.
    dh_m : float
        Estimated height above the runway plane, metres (never NaN, always positive).
    observability : float
        Observability index of the observer's feature set on the estimated features and the
        measured velocities: thesis 3.30 for points, 3.40 for lines ((m/s)^2 and (1/s)^2 m^2).
    coasting : bool
        True when no measurement corrected this step.
    state : ndarray
        The observer's full state (documented per observer class).
    reason : str
        Why the step coasted ("" when it was corrected): "no measurement", "non-finite
        measurement", "rejected: state diverged", ...
    """

    t_s: float
    dh_m: float
    observability: float
    coasting: bool
    state: np.ndarray
    reason: str = ""


# --------------------------------------------------------------------------- parameters
class ObserverParams(ParamsFile):
    """Base of every observer's frozen parameter dataclass.

    Subclasses are ``@dataclass(frozen=True)`` with float fields and a ``__post_init__`` that
    calls the checks below; they round-trip through JSON and TOML (``to_dict``/``from_dict``,
    ``save``/``load``).
    """

    params_kind: ClassVar[str] = "observer"


    def _check_positive(self, *names: str) -> None:
        for name in names:
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
                raise ValueError(f"{type(self).__name__}.{name} must be a positive finite number, got {value!r}")

    def _check_range(self, name: str, low: float, high: float) -> None:
        value = getattr(self, name)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ValueError(f"{type(self).__name__}.{name} must be a finite number, got {value!r}")
        if not low <= value <= high:
            raise ValueError(f"{type(self).__name__}.{name} = {value!r} is out of range [{low:g}, {high:g}]")


# --------------------------------------------------------------------------- measurements
_MEASUREMENT_SHAPES = {"points": (2, 2), "lines": (2, 2)}


def observer_measurement(inp: ObserverInput, features: str) -> tuple[np.ndarray | None, str]:
    """The measurement an observer of ``features`` uses at this step, and why it is missing.

    Returns ``(array, "")`` with a (2, 2) float array, or ``(None, reason)`` when there is no
    usable measurement (absent or non-finite: a coasting step). A measurement of the wrong
    shape is a programming error: ``ValueError``.

    Parameters
    ----------
    inp : ObserverInput
        This step's input.
    features : str
        ``"points"`` (the virtual-frame threshold corners, thesis 3.23) or ``"lines"`` (the two
        edges' ``(rho, theta)``).
    """
    value = inp.points_yv if features == "points" else inp.lines
    if value is None:
        return None, "no measurement"
    shape = _MEASUREMENT_SHAPES[features]
    field_name = "points_yv" if features == "points" else "lines"
    if not isinstance(value, np.ndarray) or value.shape != shape:
        got = value.shape if isinstance(value, np.ndarray) else type(value).__name__
        raise ValueError(f"ObserverInput.{field_name} at t = {inp.t_s:g} s must be an array of shape {shape}, "
                         f"got {got}")
    if not math.isfinite(value[0, 0] + value[0, 1] + value[1, 0] + value[1, 1]):
        return None, "non-finite measurement"
    return value, ""


_INERTIAL_FIELDS = (("v_runway_mps", (3,)), ("v_camera_mps", (3,)), ("omega_camera_rps", (3,)),
                    ("n_camera", (3,)), ("R_runway_from_camera", (3, 3)))


def _check_inertial(inp: ObserverInput) -> None:
    """Shapes and finiteness of the inertial part of an input (programming errors).

    An input that passed is marked, so the same prepared input stepped through by several
    observers is checked once (a ``dataclasses.replace`` copy is checked again).
    """
    if not isinstance(inp, ObserverInput):
        raise ValueError(f"step() expects an ObserverInput, got {type(inp).__name__}")
    if inp.__dict__.get("_inertial_checked", False):
        return
    t = inp.t_s
    if isinstance(t, bool) or not isinstance(t, (int, float, np.floating)) or not math.isfinite(t):
        raise ValueError(f"ObserverInput.t_s must be a finite number of seconds, got {t!r}")
    for name, shape in _INERTIAL_FIELDS:
        value = getattr(inp, name)
        if not isinstance(value, np.ndarray) or value.shape != shape:
            raise ValueError(f"ObserverInput.{name} at t = {t:g} s must be an array of shape {shape}, "
                             f"got {getattr(value, 'shape', type(value).__name__)}")
        if not math.isfinite(float(value.sum())):
            raise ValueError(f"ObserverInput.{name} at t = {t:g} s holds a NaN or infinite value "
                             "(inertial data must be complete; fix the telemetry)")
    object.__setattr__(inp, "_inertial_checked", True)


def _state_within_limit(state: np.ndarray) -> bool:
    """Every component of ``state`` finite and of magnitude below :data:`STATE_LIMIT`.

    The sum of squares below ``STATE_LIMIT^2`` implies it (and is NaN or infinite otherwise); one
    dot product is a third of the cost of ``abs`` and ``max`` at every step, which are only needed
    when the sum is that large.
    """
    flat = state.ravel()
    if flat.dtype.kind == "f" and float(flat.dot(flat)) < STATE_LIMIT * STATE_LIMIT:
        return True
    return bool(np.isfinite(flat).all() and np.abs(flat).max() < STATE_LIMIT)


# --------------------------------------------------------------------------- observer
class Observer(abc.ABC):
    """Base class: the bad-input policy around an observer's maths.

    Subclasses set ``name``, ``features``, ``params_type`` and implement:

    - ``_reset(first, dh0_m, measurement)``: set the state from the first input (whose
      measurement is given, already validated) and the height guess;
    - ``_step(inp, dt_s, measurement) -> Estimate``: integrate from the previous time over
      ``dt_s > 0`` and correct with ``measurement`` (a (2, 2) array) or coast when it is None;
    - ``_get_state() -> ndarray`` (a copy) and ``_set_state(x)``: used to roll back a step
      whose state turned non-finite.

    ``reset`` and ``step`` validate the inputs (see module docstring) and keep the time.

    Parameters
    ----------
    params : ObserverParams or dict, optional
        The subclass's ``params_type`` instance, a dict of its fields (validated), or None for
        its defaults.
    """

    name: ClassVar[str] = ""
    features: ClassVar[str] = "points"
    params_type: ClassVar[type] = ObserverParams

    def __init__(self, params=None):
        if params is None:
            params = self.params_type()
        elif isinstance(params, dict):
            params = self.params_type.from_dict(params, source=f"{self.name} parameters")
        elif not isinstance(params, self.params_type):
            raise ValueError(f"params of {self.name} must be a {self.params_type.__name__} or a dict, "
                             f"got {type(params).__name__}")
        self.params = params
        self._t_s: float | None = None
        self._last: Estimate | None = None

    # public --------------------------------------------------------------------------
    def reset(self, first: ObserverInput, dh0_m: float) -> None:
        """Initialise the state: measured part from ``first``, ``eta = 1/dh0_m``.

        ``first`` must carry a measurement of the observer's features (the run starts at the
        first measured frame); ``dh0_m`` is the initial height guess (the seeds start 20 % off).
        """
        _check_inertial(first)
        if isinstance(dh0_m, bool) or not isinstance(dh0_m, (int, float, np.floating)) \
                or not math.isfinite(dh0_m) or dh0_m <= 0:
            raise ValueError(f"dh0_m (initial height guess) must be a positive finite number of metres, got {dh0_m!r}")
        if not ETA_MIN <= 1.0 / dh0_m <= ETA_MAX:
            raise ValueError(f"dh0_m = {dh0_m:g} m is outside the observers' domain "
                             f"[{1 / ETA_MAX:g}, {1 / ETA_MIN:g}] m")
        measurement, reason = observer_measurement(first, self.features)
        if measurement is None:
            raise ValueError(f"{self.name}: the first input (t = {first.t_s:g} s) must carry a measurement of the "
                             f"{self.features} ({reason}); start the run at the first measured frame")
        self._reset(first, float(dh0_m), measurement)
        self._t_s = float(first.t_s)
        self._last = None

    def step(self, inp: ObserverInput) -> Estimate:
        """Advance to ``inp.t_s``; correct with the measurement if any, else coast (flagged)."""
        if self._t_s is None:
            raise ValueError(f"{self.name}: call reset() before step()")
        _check_inertial(inp)
        dt = float(inp.t_s) - self._t_s
        if not dt > 0.0:
            raise ValueError(f"{self.name}: time must increase: t = {inp.t_s:g} s after t = {self._t_s:g} s")
        measurement, reason = observer_measurement(inp, self.features)
        backup = self._get_state()
        try:
            estimate = self._step(inp, dt, measurement)
        except (OverflowError, ZeroDivisionError, FloatingPointError):
            estimate = None              # arithmetic blew up on a bad measurement: same as diverging
        if estimate is not None and measurement is None:
            estimate.coasting = True
            estimate.reason = estimate.reason or reason
        if estimate is None or not (math.isfinite(estimate.dh_m) and estimate.dh_m > 0
                                    and math.isfinite(estimate.observability)
                                    and _state_within_limit(estimate.state)):
            self._set_state(backup)
            estimate = self._rolled_back(inp, backup)
        self._t_s = float(inp.t_s)
        self._last = estimate
        return estimate

    @property
    def t_s(self) -> float | None:
        """Time of the last reset or step (None before reset)."""
        return self._t_s

    @property
    def last_estimate(self) -> Estimate | None:
        return self._last

    # for subclasses ------------------------------------------------------------------
    @abc.abstractmethod
    def _reset(self, first: ObserverInput, dh0_m: float, measurement: np.ndarray) -> None:
        """Set the state from the first input and the height guess."""

    @abc.abstractmethod
    def _step(self, inp: ObserverInput, dt_s: float, measurement: np.ndarray | None) -> Estimate:
        """Integrate over ``dt_s`` and correct (or coast when ``measurement`` is None)."""

    @abc.abstractmethod
    def _get_state(self) -> np.ndarray:
        """A copy of the full state."""

    @abc.abstractmethod
    def _set_state(self, state: np.ndarray) -> None:
        """Restore a state returned by ``_get_state``."""

    def _dh_from_state(self, state: np.ndarray) -> float:
        """Height of a state (override when eta is not the last state component)."""
        return 1.0 / clip_eta(float(state[-1]))

    def _rolled_back(self, inp: ObserverInput, state: np.ndarray) -> Estimate:
        previous = self._last
        return Estimate(t_s=float(inp.t_s), dh_m=self._dh_from_state(state),
                        observability=previous.observability if previous is not None else 0.0,
                        coasting=True, state=state.copy(), reason="rejected: state diverged")

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.params!r})"
