"""Shared fixtures of the tracking tests: a short synthetic approach with exact corners.

The frames come from :mod:`visland.tracking.synthetic` (a textured ground plane and the
runway polygons imaged through the exact homography), so the labelled corners are the
independent truth: they are projected by :meth:`visland.camera.CameraModel.project`, not
measured by the tracker.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from visland.camera import CameraModel
from visland.features import batch_R_camera_from_runway
from visland.scenarios import get_scenario
from visland.simulate import SimulationOptions, run_simulation
from visland.tracking.motion import Attitude
from visland.tracking.synthetic import make_planar_scene, render_planar

SIZE = 512


@dataclass
class Approach:
    camera: CameraModel
    result: object          # visland.simulate.SimulationResult of the whole approach
    indices: list           # frame indices of the short sequence
    images: list            # grey frames at those indices
    corners_uv: np.ndarray  # (n, 4, 2) labelled corners at those indices

    def attitude(self, j: int) -> Attitude:
        s = self.result.frames
        k = self.indices[j]
        return Attitude(float(s.roll_rad[k]), float(s.pitch_rad[k]), float(s.heading_rad[k]))


def render_approach(distance_m: float, n_frames: int, size: int = SIZE, seed: int = 3) -> Approach:
    camera = CameraModel.default(size)
    scenario = get_scenario("thesis-1")
    result = run_simulation(scenario, SimulationOptions(camera=camera))
    states = result.frames
    first = int(np.argmin(np.abs(-states.p_runway_m[:, 0] - distance_m)))
    indices = list(range(first, first + n_frames))
    R = batch_R_camera_from_runway(states.roll_rad, states.pitch_rad, states.dpsi_rad, camera.mount_rpy_rad)
    scene = make_planar_scene(scenario.runway, seed=seed, x_range_m=(-1800.0, 3200.0), y_range_m=(-500.0, 500.0))
    images = [render_planar(scene, camera, R[k], states.p_runway_m[k]) for k in indices]
    return Approach(camera, result, indices, images, result.features.corners_uv[indices])


@pytest.fixture(scope="session")
def approach() -> Approach:
    """24 frames of thesis-1 from 450 m before the threshold, 512x512."""
    return render_approach(450.0, 24)
