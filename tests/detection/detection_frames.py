"""Test frames for the detection tests: ray-cast (``raycast_airport``) along flown approaches,
with their exact labels from :mod:`visland.features`. Frames are cached per process, small
(512 px) so the whole suite stays fast."""
from __future__ import annotations

import functools
import math

import numpy as np

from raycast_airport import PaintedAirport, draw_frame
from visland.camera import CameraModel
from visland.features import batch_R_camera_from_runway, ideal_features
from visland.flight import simulate_flight
from visland.scenarios import get_scenario

SIZE = 512


@functools.lru_cache(maxsize=None)
def trajectory(name: str):
    return simulate_flight(get_scenario(name))


def state_at_distance(name: str, distance_m: float, frame_offset: int = 0, fps: float = 25.0):
    """Trajectory state where the camera is ``distance_m`` before the threshold (+ frames)."""
    tr = trajectory(name)
    i = int(np.argmin(np.abs(-tr.p_runway_m[:, 0] - distance_m)))
    return tr.at(np.array([tr.t_s[i] + frame_offset / fps]))


@functools.lru_cache(maxsize=None)
def frame(name: str, distance_m: float, frame_offset: int = 0, size: int = SIZE, concrete: bool = False,
          runway: bool = True, seed: int = 1):
    """``(image, camera, state, labels)`` of one ray-cast frame (cached)."""
    camera = CameraModel.default(size)
    state = state_at_distance(name, distance_m, frame_offset)
    R = batch_R_camera_from_runway(state.roll_rad, state.pitch_rad, state.dpsi_rad, camera.mount_rpy_rad)
    scene = PaintedAirport(seed=seed, runway=runway, runway_grey=150.0 if concrete else 78.0,
                           grass_grey=95.0 if concrete else 105.0)
    image = draw_frame(scene, camera, state.p_runway_m[0], R[0], supersample=2, blur_sigma_px=0.4,
                       rng=np.random.default_rng(seed + frame_offset))
    labels = ideal_features(state, get_scenario(name).runway, camera)
    return image, camera, state, labels


def edge_error_px(camera, labels, result, side: str) -> float:
    """Largest distance from the labelled edge's visible stretch to the detected line (px)."""
    corners = labels.corners_uv[0]
    a = corners[0 if side == "left" else 1]
    b = corners[2 if side == "left" else 3]
    t = np.linspace(0.0, 1.0, 200)[:, None]
    points = a + t * (b - a)
    points = points[camera.in_image(points)]
    rho, theta = result.lines[side]
    if not (math.isfinite(rho) and math.isfinite(theta)):
        return math.inf
    return float(np.abs(camera.line_distance_px(rho, theta, points)).max())
