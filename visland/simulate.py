"""``visland simulate``: fly a scenario and write its telemetry, truth and ideal labels.

The output folder follows SPEC.md "File contracts": ``telemetry.csv`` (50 Hz IMU),
``truth.csv`` and ``labels.csv`` (one row per camera frame), ``camera.json`` (the nominal
camera the estimators are told about), ``runway.json`` (truth side) and ``manifest.json``
(what was run, for reproducibility). No images: ``visland generate`` renders them.
"""
from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field

import numpy as np

from visland import __version__
from visland.camera import CameraModel
from visland.contracts import (LABEL_COLUMNS, LABEL_EXTRA_COLUMNS, TRUTH_COLUMNS,
                               TRUTH_EXTRA_COLUMNS, atomic_write_text, staged_output_dir, write_csv)
from visland.features import IdealFeatures, ideal_features
from visland.flight import FT_TO_M, FrameStates, Trajectory, simulate_flight
from visland.scenarios import Scenario
from visland.sensors import ImuParams, InertialSeries, camera_with_calibration_error, measure_imu

__all__ = ["SimulationOptions", "SimulationResult", "run_simulation", "write_simulation", "summary_lines",
           "frame_times", "FORMAT_VERSION", "METRIC_HEIGHTS_FT"]

FORMAT_VERSION = 1
METRIC_HEIGHTS_FT = (400.0, 200.0, 100.0)


@dataclass(frozen=True)
class SimulationOptions:
    """What to simulate besides the scenario: camera, frame rate and imperfections.

    Attributes
    ----------
    fps : float, default 25
        Camera frame rate, Hz, in [1, 50] (the dynamics run at 50 Hz).
    camera : visland.camera.CameraModel
        The nominal camera (written to ``camera.json``; default the SPEC 2048 px camera).
    pixel_noise_px : float, default 0
        Standard deviation of the white noise on each corner coordinate, pixels, in [0, 50]
        (thesis 5.2.2.1: 1 or 5 px).
    calibration_error_deg : float or tuple of 3 floats, default 0
        Camera mounting error, degrees: one angle added to roll, pitch and yaw, or
        ``(roll, pitch, yaw)`` (thesis 5.2.2.2).
    imu : visland.sensors.ImuParams
        The inertial unit's imperfections (default: perfect).
    seed : int, default 0
        Seed of the pixel-noise generator.
    """

    fps: float = 25.0
    camera: CameraModel = field(default_factory=CameraModel.default)
    pixel_noise_px: float = 0.0
    calibration_error_deg: float | tuple = 0.0   # one angle for roll, pitch and yaw, or (roll, pitch, yaw)
    imu: ImuParams = field(default_factory=ImuParams)
    seed: int = 0

    def __post_init__(self):
        if not (isinstance(self.fps, (int, float)) and math.isfinite(self.fps) and 1.0 <= self.fps <= 50.0):
            raise ValueError(f"fps must lie in [1, 50] frames per second (the dynamics run at 50 Hz), got {self.fps!r}")
        if not (math.isfinite(self.pixel_noise_px) and 0.0 <= self.pixel_noise_px <= 50.0):
            raise ValueError(f"pixel noise must lie in [0, 50] px, got {self.pixel_noise_px!r}")
        error = self.calibration_error_deg
        values = list(error) if isinstance(error, (tuple, list)) else [error]
        if (len(values) not in (1, 3) or not all(isinstance(v, (int, float)) and math.isfinite(v) and abs(v) <= 10.0
                                                 for v in values)):
            raise ValueError("calibration error must be one angle or three (roll, pitch, yaw), each in [-10, 10] deg, "
                             f"got {error!r}")
        if isinstance(error, list):
            object.__setattr__(self, "calibration_error_deg", tuple(error))
        if not isinstance(self.seed, int) or self.seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got {self.seed!r}")

    def to_json_dict(self) -> dict:
        return {"fps": self.fps, "camera": self.camera.to_json_dict(), "pixel_noise_px": self.pixel_noise_px,
                "calibration_error_deg": (list(self.calibration_error_deg) if isinstance(self.calibration_error_deg, tuple)
                                          else self.calibration_error_deg),
                "imu": asdict(self.imu), "seed": self.seed}


@dataclass
class SimulationResult:
    """A flown scenario with everything the files hold.

    Attributes
    ----------
    scenario : visland.scenarios.Scenario
        What was flown.
    options : SimulationOptions
        How it was simulated.
    trajectory : visland.flight.Trajectory
        The true flight at the dynamics rate.
    imu : visland.sensors.InertialSeries
        What the inertial unit reported (``telemetry.csv``).
    frames : visland.flight.FrameStates
        The true state at the camera frame times (``truth.csv``).
    features : visland.features.IdealFeatures
        Exact (or noisy) image features at the frame times (``labels.csv``).
    camera_true : visland.camera.CameraModel
        The camera as actually mounted (nominal plus calibration error).
    """

    scenario: Scenario
    options: SimulationOptions
    trajectory: Trajectory
    imu: InertialSeries
    frames: FrameStates
    features: IdealFeatures
    camera_true: CameraModel

    def truth_columns(self) -> dict:
        s = self.frames
        p = s.p_runway_m
        aim = self.scenario.runway.aim_distance_m
        dx = p[:, 0] - aim
        dh = -p[:, 2]
        return {
            "t_s": s.t_s, "dx_m": dx, "dy_m": p[:, 1], "dh_m": dh,
            "roll_deg": np.degrees(s.roll_rad), "pitch_deg": np.degrees(s.pitch_rad),
            "dpsi_deg": np.degrees(s.dpsi_rad),
            "frame": np.arange(len(s)), "dgs_m": dh + dx * math.tan(math.radians(3.0)),
            "heading_deg": np.degrees(s.heading_rad) % 360.0,
            "vx_runway_mps": s.v_runway_mps[:, 0], "vy_runway_mps": s.v_runway_mps[:, 1],
            "vz_runway_mps": s.v_runway_mps[:, 2],
            **self._wind_columns(),
        }

    def _wind_columns(self) -> dict:
        """Wind in runway axes at the frame times (truth for the wind-estimating observers)."""
        tr = self.trajectory
        wind = tr.wind_ned_mps @ tr.R_runway_from_ned.T
        t = self.frames.t_s
        return {f"wind_{axis}_runway_mps": np.interp(t, tr.t_s, wind[:, k]) for k, axis in enumerate("xyz")}

    def label_columns(self) -> dict:
        cols = self.features.as_columns()
        cols["frame"] = np.arange(len(self.features))
        return cols


def frame_times(duration_s: float, fps: float) -> np.ndarray:
    """Camera frame times ``k / fps`` inside ``[0, duration_s]``.

    Parameters
    ----------
    duration_s : float
        Length of the flight, seconds.
    fps : float
        Frame rate, Hz.

    Returns
    -------
    ndarray, shape (n,)
        Seconds from 0, the last at most ``duration_s`` (within 1e-9 s).
    """
    n = int(math.floor(duration_s * fps + 1e-9)) + 1
    return np.arange(n) / fps


def run_simulation(scenario: Scenario, options: SimulationOptions | None = None) -> SimulationResult:
    """Fly ``scenario``, measure it with the IMU and compute the ideal image features.

    Parameters
    ----------
    scenario : visland.scenarios.Scenario
        The approach to fly (:func:`visland.flight.simulate_flight`).
    options : SimulationOptions, optional
        Camera, frame rate and imperfections (default: SPEC camera, 25 Hz, none).

    Returns
    -------
    SimulationResult
        Pixels are formed through the true camera, features turned into dpsi and virtual
        coordinates with the nominal camera and the IMU attitude.
    """
    options = options or SimulationOptions()
    trajectory = simulate_flight(scenario)
    imu = measure_imu(trajectory, options.imu)
    times = frame_times(trajectory.duration_s, options.fps)
    frames = trajectory.at(times)
    camera_true = (camera_with_calibration_error(options.camera, options.calibration_error_deg)
                   if np.any(options.calibration_error_deg) else options.camera)
    imu_roll = np.interp(times, imu.t_s, np.unwrap(imu.roll_rad))
    imu_pitch = np.interp(times, imu.t_s, imu.pitch_rad)
    rng = np.random.default_rng(options.seed)
    features = ideal_features(frames, scenario.runway, options.camera, camera_true=camera_true,
                              imu_roll_rad=imu_roll, imu_pitch_rad=imu_pitch,
                              pixel_noise_px=options.pixel_noise_px, rng=rng)
    return SimulationResult(scenario, options, trajectory, imu, frames, features, camera_true)


def write_simulation(result: SimulationResult, out_dir, force: bool = False) -> None:
    """Write the SPEC files of ``result`` into ``out_dir`` (atomically as a whole folder).

    Parameters
    ----------
    result : SimulationResult
        What to write: telemetry.csv, truth.csv, labels.csv, camera.json, runway.json,
        manifest.json.
    out_dir : str or Path
        The folder to create.
    force : bool, default False
        Replace an existing folder (refused otherwise).
    """
    with staged_output_dir(out_dir, force=force) as staging:
        write_simulation_files(result, staging)


def write_simulation_files(result: SimulationResult, folder) -> None:
    """Write the SPEC files of ``result`` into an existing ``folder`` (each file atomically)."""
    from pathlib import Path
    folder = Path(folder)
    write_csv(folder / "telemetry.csv", result.imu.as_columns(), result.imu.columns_written)
    write_csv(folder / "truth.csv", result.truth_columns(), TRUTH_COLUMNS + TRUTH_EXTRA_COLUMNS)
    write_csv(folder / "labels.csv", result.label_columns(), LABEL_COLUMNS + LABEL_EXTRA_COLUMNS)
    atomic_write_text(folder / "camera.json", json.dumps(result.options.camera.to_json_dict(), indent=2) + "\n")
    atomic_write_text(folder / "runway.json", json.dumps(result.scenario.runway.to_json_dict(), indent=2) + "\n")
    atomic_write_text(folder / "manifest.json", json.dumps(simulation_manifest(result), indent=2) + "\n")


def simulation_manifest(result: SimulationResult) -> dict:
    return {
        "format_version": FORMAT_VERSION,
        "kind": "simulation",
        "software": f"visland {__version__}",
        "scenario": result.scenario.to_dict(),
        "options": result.options.to_json_dict(),
        "camera_true_mount_rpy_deg": list(result.camera_true.mount_rpy_deg),
        "n_frames": len(result.frames),
        "duration_s": result.trajectory.duration_s,
        "end_reason": result.trajectory.end_reason,
    }


def summary_lines(result: SimulationResult) -> list[str]:
    """A one-screen summary: duration, deviations at 400/200/100 ft, limits, corner visibility.

    Parameters
    ----------
    result : SimulationResult
        A flown scenario.

    Returns
    -------
    list of str
        The lines ``visland simulate`` prints.
    """
    tr = result.trajectory
    sc = result.scenario
    lines = [
        f"scenario {sc.name}: {sc.description}" if sc.description else f"scenario {sc.name}",
        f"flown {tr.duration_s:.1f} s at {sc.airspeed_kt:g} kt to the {tr.end_reason} "
        f"({len(tr.t_s)} IMU samples at {tr.rate_hz:g} Hz, {len(result.frames)} frames at {result.options.fps:g} Hz)",
        "  height     dX (m)    dY (m)   dGS (m)",
    ]
    for height_ft in METRIC_HEIGHTS_FT:
        i = tr.index_at_height(height_ft * FT_TO_M)
        if i is None:
            lines.append(f"  {height_ft:4.0f} ft   (not reached)")
            continue
        lines.append(f"  {height_ft:4.0f} ft {tr.dx_m[i]:10.1f} {tr.dy_m[i]:9.2f} {tr.dgs_m[i]:9.2f}")
    limits = tr.limits_report()
    parts = []
    for name, rep in limits.items():
        parts.append(f"{name} [{rep['min']:.1f}, {rep['max']:.1f}]{'' if rep['ok'] else ' EXCEEDED'}")
    lines.append("limits (thesis 1.3.2): " + ", ".join(parts))
    visible = result.features.corners_visible.all(axis=1)
    dh = -result.frames.p_runway_m[:, 2]
    above = dh >= 100 * FT_TO_M
    lost = np.nonzero(above & ~visible)[0]
    if lost.size:
        lines.append(f"corners: not all four in the image at {lost.size} frames above 100 ft "
                     f"(first at t = {result.frames.t_s[lost[0]]:.2f} s)")
    else:
        lines.append("corners: all four inside the image in every frame down to 100 ft")
    return lines
