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
from dataclasses import dataclass

import numpy as np

from visland.camera import CameraModel
from visland.flight import Trajectory

__all__ = ["ImuParams", "ImuSamples", "measure_imu", "camera_with_calibration_error", "TELEMETRY_COLUMNS",
           "TELEMETRY_OPTIONAL_COLUMNS"]

TELEMETRY_COLUMNS = ("t_s", "roll_deg", "pitch_deg", "heading_deg", "p_dps", "q_dps", "r_dps",
                     "vn_mps", "ve_mps", "vd_mps")
#: Columns a telemetry file may add after the SPEC ones: the true airspeed (m/s).
TELEMETRY_OPTIONAL_COLUMNS = ("tas_mps",)


@dataclass(frozen=True)
class ImuParams:
    """Inertial unit imperfections (defaults: a perfect unit, as thesis hypothesis 2 assumes)."""

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
class ImuSamples:
    """Inertial data at the simulation rate, SI units (the ``telemetry.csv`` content); ``tas_mps``
    the true airspeed, None without air data."""

    t_s: np.ndarray
    roll_rad: np.ndarray
    pitch_rad: np.ndarray
    heading_rad: np.ndarray
    omega_body_rps: np.ndarray
    v_ned_mps: np.ndarray
    tas_mps: np.ndarray | None = None

    @property
    def columns_written(self) -> tuple:
        """The telemetry columns these samples fill, in file order."""
        return TELEMETRY_COLUMNS + (TELEMETRY_OPTIONAL_COLUMNS if self.tas_mps is not None else ())

    def as_columns(self) -> dict:
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


def measure_imu(trajectory: Trajectory, params: ImuParams | None = None) -> ImuSamples:
    """What the inertial unit reports along ``trajectory`` (see module docstring)."""
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
    return ImuSamples(
        t_s=trajectory.t_s.copy(),
        roll_rad=trajectory.roll_rad + att_noise[:, 0],
        pitch_rad=trajectory.pitch_rad + att_noise[:, 1],
        heading_rad=trajectory.heading_rad + att_noise[:, 2],
        omega_body_rps=trajectory.omega_body_rps + rate_noise,
        v_ned_mps=(1.0 + params.velocity_bias_fraction) * trajectory.v_ned_mps + vel_noise,
        tas_mps=tas,
    )


def camera_with_calibration_error(camera: CameraModel, error_deg) -> CameraModel:
    """The camera as actually mounted: nominal mounting plus ``error_deg``.

    ``error_deg`` is one number (added to roll, pitch and yaw) or three ``(roll, pitch, yaw)``.
    """
    errors = np.broadcast_to(np.asarray(error_deg, dtype=float), (3,))
    if not np.all(np.isfinite(errors)) or np.any(np.abs(errors) > 10.0):
        raise ValueError(f"calibration error must be finite and within 10 deg, got {error_deg!r}")
    return camera.with_mount(tuple(m + math.radians(e) for m, e in zip(camera.mount_rpy_rad, errors)))
