"""The inertial unit and the camera mounting error (thesis hypotheses 2-3, section 5.2.2).

The IMU gives, at the simulation rate (50 Hz): roll, pitch and true heading, body rates
(p, q, r) and the NED ground velocity. Imperfections (all off by default, all seeded):

- a constant relative velocity bias ``b``: ``v_meas = (1 + b) v_true`` on every component
  (thesis 5.2.2.3 studies 1 % and 5 %; the bias is constant in time, as the thesis assumes);
- white Gaussian noise on attitude, rates and velocity;
- a camera mounting calibration error (thesis 5.2.2.2: 0.3, 0.5, 1 deg): the camera is
  mounted at ``nominal + error`` on each of roll, pitch and yaw, while ``camera.json`` keeps
  the nominal mounting, so the estimators work with a wrong camera attitude.

Air data (issue 16): the true airspeed ``|v_ground - wind|`` with white noise of
``airspeed_noise_mps`` (0.5 m/s by default, about 1 kt: an air-data computer's accuracy), written
as the optional telemetry column ``tas_mps`` (:data:`TELEMETRY_OPTIONAL_COLUMNS`). With it the
wind is observable (``dickmanns-4d``); ``airspeed=False`` leaves the column out.
"""
from __future__ import annotations

import math
from dataclasses import InitVar, dataclass
from typing import TYPE_CHECKING

import numpy as np

from visland.camera import CameraModel
from visland.flight import Trajectory

if TYPE_CHECKING:                       # visland.contracts imports this module's column names
    from visland.contracts import Table

__all__ = ["ImuParams", "InertialSeries", "measure_imu", "camera_with_calibration_error", "TELEMETRY_COLUMNS",
           "TELEMETRY_OPTIONAL_COLUMNS", "TIME_MATCH_S"]

TELEMETRY_COLUMNS = ("t_s", "roll_deg", "pitch_deg", "heading_deg", "p_dps", "q_dps", "r_dps",
                     "vn_mps", "ve_mps", "vd_mps")
#: Columns a telemetry file may add after the SPEC ones: the true airspeed (m/s).
TELEMETRY_OPTIONAL_COLUMNS = ("tas_mps",)
#: Two times closer than this (s) are the same instant (inertial samples against frame times).
TIME_MATCH_S = 1e-6


@dataclass(frozen=True)
class ImuParams:
    """Inertial unit imperfections (defaults: a perfect unit, as thesis hypothesis 2 assumes).

    Attributes
    ----------
    velocity_bias_fraction : float
        Constant relative velocity bias ``b``: ``v_meas = (1 + b) v_true`` on every NED
        component (thesis 5.2.2.3: 0.01, 0.05), within [-0.5, 0.5].
    velocity_noise_mps : float
        Standard deviation of the white noise on each NED velocity component, m/s.
    attitude_noise_deg : float
        Standard deviation of the white noise on roll, pitch and heading, degrees.
    rate_noise_dps : float
        Standard deviation of the white noise on the body rates (p, q, r), deg/s.
    seed : int
        Seed of the noise generator (non-negative).
    airspeed : bool
        Whether the unit reports the true airspeed (telemetry column ``tas_mps``).
    airspeed_noise_mps : float
        Standard deviation of the white noise on the true airspeed, m/s (0.5: about 1 kt).

    Raises
    ------
    ValueError
        A value out of its range, naming the field.
    """

    velocity_bias_fraction: float = 0.0
    velocity_noise_mps: float = 0.0
    attitude_noise_deg: float = 0.0
    rate_noise_dps: float = 0.0
    seed: int = 0
    airspeed: bool = True
    airspeed_noise_mps: float = 0.5

    def __post_init__(self):
        if not (math.isfinite(self.velocity_bias_fraction) and abs(self.velocity_bias_fraction) <= 0.5):
            raise ValueError(f"velocity_bias_fraction must lie in [-0.5, 0.5], got {self.velocity_bias_fraction!r}")
        if not isinstance(self.airspeed, bool):
            raise ValueError(f"airspeed must be true or false, got {self.airspeed!r}")
        for name in ("velocity_noise_mps", "attitude_noise_deg", "rate_noise_dps", "airspeed_noise_mps"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.0 <= value <= 100.0):
                raise ValueError(f"{name} must be a non-negative number, got {value!r}")
        if not isinstance(self.seed, int) or self.seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got {self.seed!r}")


@dataclass
class InertialSeries:
    """Inertial data at the unit's rate, SI units (radians, rad/s, m/s): the one record of
    inertial samples, whether simulated (:func:`measure_imu`), read from ``telemetry.csv``
    (:meth:`from_table`) or interpolated at frame times (:meth:`at`,
    :func:`visland.folder.interpolate_telemetry`).

    Parameters
    ----------
    t_s : ndarray, shape (n,)
        Sample times in seconds, strictly increasing.
    roll_rad, pitch_rad, heading_rad : ndarray, shape (n,)
        Body attitude relative to NED in radians (roll and true heading unwrapped).
    omega_body_rps : ndarray, shape (n, 3)
        Body rates (p, q, r) in rad/s, body frame.
    v_ned_mps : ndarray, shape (n, 3)
        Ground velocity in m/s, NED frame.
    tas_mps : ndarray, shape (n,), optional
        True airspeed in m/s (None when the telemetry has no ``tas_mps`` column).
    min_samples : int, default 2
        Fewest samples accepted: 2 for a series to interpolate from (telemetry, IMU), 1 for
        values at the frames of a one-frame recording. Not stored.

    Raises
    ------
    ValueError
        A shape that is not (n,) or (n, 3), a NaN or infinite value, a non-positive airspeed,
        or times that do not increase strictly over ``min_samples`` samples.
    """

    t_s: np.ndarray
    roll_rad: np.ndarray
    pitch_rad: np.ndarray
    heading_rad: np.ndarray
    omega_body_rps: np.ndarray
    v_ned_mps: np.ndarray
    tas_mps: np.ndarray | None = None
    min_samples: InitVar[int] = 2

    def __post_init__(self, min_samples: int = 2):
        n = len(self.t_s)
        if self.tas_mps is not None:
            tas = np.asarray(self.tas_mps, dtype=float)
            if tas.shape != (n,):
                raise ValueError(f"InertialSeries.tas_mps must have shape ({n},)")
            bad = np.nonzero(~(np.isfinite(tas) & (tas > 0)))[0]
            if bad.size:
                raise ValueError(f"telemetry: tas_mps at t = {float(self.t_s[bad[0]]):g} s is {tas[bad[0]]!r} "
                                 "(a positive airspeed in m/s is required)")
            self.tas_mps = tas
        for name in ("roll_rad", "pitch_rad", "heading_rad"):
            if np.shape(getattr(self, name)) != (n,):
                raise ValueError(f"InertialSeries.{name} must have shape ({n},)")
        for name in ("omega_body_rps", "v_ned_mps"):
            if np.shape(getattr(self, name)) != (n, 3):
                raise ValueError(f"InertialSeries.{name} must have shape ({n}, 3)")
        for name in ("t_s", "roll_rad", "pitch_rad", "heading_rad", "omega_body_rps", "v_ned_mps"):
            values = np.asarray(getattr(self, name), dtype=float)
            if not np.isfinite(values).all():
                raise ValueError(f"telemetry: {name} holds a NaN or infinite value")
            setattr(self, name, values)
        if n < min_samples or np.any(np.diff(self.t_s) <= 0):
            raise ValueError("telemetry: time must increase strictly over at least two samples" if min_samples == 2
                             else f"telemetry: time must increase strictly over at least {min_samples} sample(s)")

    @classmethod
    def from_table(cls, table: "Table", min_samples: int = 2) -> "InertialSeries":
        """From a ``telemetry.csv`` table, degrees to radians, roll and heading unwrapped.

        Parameters
        ----------
        table : visland.contracts.Table
            As read by :func:`visland.contracts.read_telemetry` (SPEC columns and units).
        min_samples : int, default 2
            Fewest rows accepted (see the class).

        Returns
        -------
        InertialSeries
        """
        return cls(t_s=table["t_s"], roll_rad=np.unwrap(np.radians(table["roll_deg"])),
                   pitch_rad=np.radians(table["pitch_deg"]),
                   heading_rad=np.unwrap(np.radians(table["heading_deg"])),
                   omega_body_rps=np.radians(np.stack([table["p_dps"], table["q_dps"], table["r_dps"]], axis=1)),
                   v_ned_mps=np.stack([table["vn_mps"], table["ve_mps"], table["vd_mps"]], axis=1),
                   tas_mps=table["tas_mps"] if "tas_mps" in table else None, min_samples=min_samples)

    @classmethod
    def from_imu(cls, imu: "InertialSeries") -> "InertialSeries":
        """The simulated samples of :func:`measure_imu` with roll and heading unwrapped."""
        return cls(t_s=imu.t_s, roll_rad=np.unwrap(imu.roll_rad), pitch_rad=imu.pitch_rad,
                   heading_rad=np.unwrap(imu.heading_rad), omega_body_rps=imu.omega_body_rps,
                   v_ned_mps=imu.v_ned_mps, tas_mps=imu.tas_mps)

    def at(self, times_s, min_samples: int = 2) -> "InertialSeries":
        """Linear interpolation at ``times_s`` (inside the covered span).

        Parameters
        ----------
        times_s : array_like, shape (m,)
            Times in seconds, strictly increasing, within ``t_s[0] .. t_s[-1]`` (to
            :data:`TIME_MATCH_S`).
        min_samples : int, default 2
            Fewest times accepted (1 for the frames of a one-frame recording).

        Returns
        -------
        InertialSeries
            The samples at ``times_s`` (angles interpolated unwrapped).
        """
        times = np.asarray(times_s, dtype=float)
        if times.size and (times.min() < self.t_s[0] - TIME_MATCH_S or times.max() > self.t_s[-1] + TIME_MATCH_S):
            raise ValueError(f"telemetry covers {self.t_s[0]:g}..{self.t_s[-1]:g} s but the measurements span "
                             f"{times.min():g}..{times.max():g} s")

        def interp(series):
            if series.ndim == 1:
                return np.interp(times, self.t_s, series)
            return np.stack([np.interp(times, self.t_s, series[:, k]) for k in range(series.shape[1])], axis=1)

        return InertialSeries(times, interp(self.roll_rad), interp(self.pitch_rad), interp(self.heading_rad),
                              interp(self.omega_body_rps), interp(self.v_ned_mps),
                              None if self.tas_mps is None else interp(self.tas_mps), min_samples=min_samples)

    @property
    def columns_written(self) -> tuple:
        """The telemetry columns these samples fill, in file order."""
        return TELEMETRY_COLUMNS + (TELEMETRY_OPTIONAL_COLUMNS if self.tas_mps is not None else ())

    def as_columns(self) -> dict:
        """The ``telemetry.csv`` columns in SPEC units (degrees, deg/s, m/s; heading in [0, 360))."""
        columns = {
            "t_s": self.t_s,
            "roll_deg": np.degrees(self.roll_rad),
            "pitch_deg": np.degrees(self.pitch_rad),
            "heading_deg": np.degrees(self.heading_rad) % 360.0,
            "p_dps": np.degrees(self.omega_body_rps[:, 0]),
            "q_dps": np.degrees(self.omega_body_rps[:, 1]),
            "r_dps": np.degrees(self.omega_body_rps[:, 2]),
            "vn_mps": self.v_ned_mps[:, 0],
            "ve_mps": self.v_ned_mps[:, 1],
            "vd_mps": self.v_ned_mps[:, 2],
        }
        if self.tas_mps is not None:
            columns["tas_mps"] = self.tas_mps
        return columns


def measure_imu(trajectory: Trajectory, params: ImuParams | None = None) -> InertialSeries:
    """What the inertial unit reports along ``trajectory`` (see module docstring).

    Parameters
    ----------
    trajectory : visland.flight.Trajectory
        The true flight, sampled at the simulation rate.
    params : ImuParams, optional
        The unit's imperfections (default: a perfect unit).

    Returns
    -------
    InertialSeries
        At the trajectory's times: attitude (rad) and body rates (rad/s) relative to NED,
        ground velocity in NED (m/s), true airspeed ``|v_ned - wind_ned|`` (m/s) when
        ``params.airspeed``. Every noise stream is drawn even when its sigma is zero, so that
        switching one on leaves the others' realisations unchanged.
    """
    params = params or ImuParams()
    rng = np.random.default_rng(params.seed)
    n = len(trajectory.t_s)
    att_sigma = math.radians(params.attitude_noise_deg)
    rate_sigma = math.radians(params.rate_noise_dps)
    # draw every stream even when its sigma is zero, so that switching one noise on does not
    # change the others' realisations
    att_noise = rng.normal(0.0, 1.0, size=(n, 3)) * att_sigma
    rate_noise = rng.normal(0.0, 1.0, size=(n, 3)) * rate_sigma
    vel_noise = rng.normal(0.0, 1.0, size=(n, 3)) * params.velocity_noise_mps
    tas_noise = rng.normal(0.0, 1.0, size=n) * params.airspeed_noise_mps      # drawn last: the others unchanged
    tas = None
    if params.airspeed:
        tas = np.linalg.norm(trajectory.v_ned_mps - trajectory.wind_ned_mps, axis=1) + tas_noise
    return InertialSeries(
        t_s=trajectory.t_s.copy(),
        roll_rad=trajectory.roll_rad + att_noise[:, 0],
        pitch_rad=trajectory.pitch_rad + att_noise[:, 1],
        heading_rad=trajectory.heading_rad + att_noise[:, 2],
        omega_body_rps=trajectory.omega_body_rps + rate_noise,
        v_ned_mps=(1.0 + params.velocity_bias_fraction) * trajectory.v_ned_mps + vel_noise,
        tas_mps=tas,
    )


def camera_with_calibration_error(camera: CameraModel, error_deg) -> CameraModel:
    """The camera as actually mounted: nominal mounting plus ``error_deg`` (thesis 5.2.2.2).

    Parameters
    ----------
    camera : visland.camera.CameraModel
        The nominal camera (what ``camera.json`` says).
    error_deg : float or sequence of 3 floats
        Mounting error in degrees: one number added to roll, pitch and yaw of the mounting
        (body to camera), or three ``(roll, pitch, yaw)``; each within 10 deg.

    Returns
    -------
    visland.camera.CameraModel
        The same intrinsics, mounting ``mount_rpy_rad + radians(error_deg)``.

    Raises
    ------
    ValueError
        A non-finite error or one over 10 deg.
    """
    errors = np.broadcast_to(np.asarray(error_deg, dtype=float), (3,))
    if not np.all(np.isfinite(errors)) or np.any(np.abs(errors) > 10.0):
        raise ValueError(f"calibration error must be finite and within 10 deg, got {error_deg!r}")
    return camera.with_mount(tuple(m + math.radians(e) for m, e in zip(camera.mount_rpy_rad, errors)))
