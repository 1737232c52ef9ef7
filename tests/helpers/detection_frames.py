"""Test frames for the detection tests: ray-cast (``raycast_airport``) along flown approaches,
with their exact labels from :mod:`visland.features`. Frames are cached per process, small
(512 px) so the whole suite stays fast."""
from __future__ import annotations

import functools
import math

import numpy as np

from tests.helpers.raycast_airport import PaintedAirport, draw_frame
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


@functools.lru_cache(maxsize=None)
def colour_frame(name: str, distance_m: float, size: int = SIZE, seed: int = 1):
    """``(rgb, camera, state, labels)``: a ray-cast frame whose grass is green and whose grey
    levels alone are ambiguous.

    The grass has the grey level (150) of the threshold and side stripes blended with the
    asphalt within a pixel, so in grey levels the runway seems to end at the stripes' inner
    edges. Colour is added with zero luminance (a runway-coverage mask, ray-cast the same way,
    says where): converted to grey, the frame is the grey frame again.
    """
    camera = CameraModel.default(size)
    state = state_at_distance(name, distance_m)
    R = batch_R_camera_from_runway(state.roll_rad, state.pitch_rad, state.dpsi_rad, camera.mount_rpy_rad)[0]
    scene = PaintedAirport(seed=seed, grass_grey=150.0, fields=False)
    grey = draw_frame(scene, camera, state.p_runway_m[0], R, supersample=2, blur_sigma_px=0.4,
                      rng=np.random.default_rng(seed))
    mask_scene = PaintedAirport(seed=seed, grass_grey=0.0, runway_grey=255.0, marking_grey=255.0, fields=False,
                                taxiway_offset_m=None, parallel_road_offset_m=None, crossing_road=False,
                                haze_range_m=1e12)
    runway = draw_frame(mask_scene, camera, state.p_runway_m[0], R, supersample=2, blur_sigma_px=0.4,
                        noise_grey=0.0) / 255.0
    tint = np.array([-18.0, 14.0, (18.0 * 0.299 - 14.0 * 0.587) / 0.114])     # R, G, B; luminance 0
    rgb = np.clip(grey[..., None] + (1.0 - runway[..., None]) * tint, 0, 255).round().astype(np.uint8)
    labels = ideal_features(state, get_scenario(name).runway, camera)
    return rgb, camera, state, labels


@functools.lru_cache(maxsize=None)
def airport_frame(name: str, distance_m: float, camera: CameraModel, scene: PaintedAirport, frame_offset: int = 0,
                  fps: float = 25.0, runway=None, seed: int = 1, noise_grey: float = 2.0):
    """``(image, state, labels)`` of a ray-cast frame of any painted ``scene`` seen by any
    ``camera`` (non-square, distorting lens: labels stay in the pinhole image); ``runway``
    overrides the scenario's (its size must match the scene's); ``noise_grey`` is the sensor's
    pixel noise (grey levels, before its blur)."""
    from dataclasses import replace
    scenario = get_scenario(name)
    if runway is not None:
        scenario = replace(scenario, runway=runway)
    tr = simulate_flight(scenario) if runway is not None else trajectory(name)
    i = int(np.argmin(np.abs(-tr.p_runway_m[:, 0] - distance_m)))
    state = tr.at(np.array([tr.t_s[i] + frame_offset / fps]))
    R = batch_R_camera_from_runway(state.roll_rad, state.pitch_rad, state.dpsi_rad, camera.mount_rpy_rad)
    image = draw_frame(scene, camera, state.p_runway_m[0], R[0], supersample=2, blur_sigma_px=0.5,
                       noise_grey=noise_grey, rng=np.random.default_rng(seed + frame_offset))
    labels = ideal_features(state, scenario.runway, camera.without_distortion())
    return image, state, labels
