"""An approach dressed as cockpit footage (issue 18 item 5): what a wide-angle camera behind an
airliner's windshield records, with the aircraft's own structure in view and no telemetry.

No real footage is used (none was available under a licence that allows shipping it): the
scene is the independent ray-cast airport (:mod:`raycast_airport`, written for these tests,
no code or data of anyone else), flown by visland's flight model, seen through a barrel
distorting lens, and dressed in the frame as taken with what is static in a cockpit video:

- the glareshield across the bottom, its top edge a shallow arc (the strongest straight-ish
  edge of the frame, below the horizon: the one a runway detector takes for a runway edge),
- the two windshield pillars, slanted, converging upwards like runway edges do,
- a parked wiper, a dark bar from its pivot on the glareshield, nearly level (like a threshold),
- a reflection on the glass: a soft bright patch over the scene (not structure: it stays),
- sensor noise.

Labels are exact in the pinhole image (SPEC); the structure's polygons (in the frame as taken)
are returned as the truth a mask can be checked against.
"""
from __future__ import annotations

import functools
import math

import cv2
import numpy as np

from tests.helpers.raycast_airport import PaintedAirport, draw_frame
from visland.camera import CameraModel
from visland.features import batch_R_camera_from_runway, ideal_features
from visland.flight import simulate_flight
from visland.scenarios import get_scenario

#: The lens: barrel distortion of a wide-angle camera (OpenCV k1, k2, p1, p2, k3).
COCKPIT_DISTORTION = (-0.18, 0.04, 0.0, 0.0, 0.0)


def cockpit_camera(width: int = 1280, height: int = 720, hfov_deg: float = 60.0) -> CameraModel:
    """The camera behind the windshield (mounted 4 deg nose-down), without a mask."""
    return CameraModel.from_fov(width, height, hfov_deg, (0.0, -4.0, 0.0), COCKPIT_DISTORTION)


def structure_polygons(width: int, height: int) -> tuple:
    """Glareshield, pillars and wiper as polygons of ``(u, v)`` pixels of the frame as taken."""
    w, h = float(width), float(height)
    arc_u = np.linspace(-1.0, w, 17)
    arc_v = h * (0.80 + 0.05 * ((arc_u - 0.45 * w) / w) ** 2 * 4)          # a shallow arc
    glareshield = [(-1.0, h)] + list(zip(arc_u, arc_v)) + [(w, h)]
    left_pillar = [(-1.0, -1.0), (0.09 * w, -1.0), (0.17 * w, 0.82 * h), (-1.0, 0.86 * h)]
    right_pillar = [(0.90 * w, -1.0), (w, -1.0), (w, 0.85 * h), (0.84 * w, 0.81 * h)]
    pivot = np.array([0.80 * w, 0.815 * h])            # parked along the glareshield
    along = np.array([-math.cos(math.radians(12.0)), -math.sin(math.radians(12.0))])
    across = np.array([-along[1], along[0]]) * 0.006 * w
    tip = pivot + 0.30 * h * along
    wiper = [tuple(pivot - across), tuple(tip - across * 0.6), tuple(tip + across * 0.6), tuple(pivot + across)]
    return tuple(tuple((float(u), float(v)) for u, v in polygon)
                 for polygon in (glareshield, left_pillar, right_pillar, wiper))


def dress(grey: np.ndarray, polygons, seed: int = 0) -> np.ndarray:
    """The frame as taken with the cockpit drawn over it (module docstring)."""
    height, width = grey.shape
    rng = np.random.default_rng(seed)
    out = grey.astype(np.float32)
    # a reflection on the glass: a soft bright patch, static in the image
    v, u = np.mgrid[0:height, 0:width].astype(np.float32)
    out += 22.0 * np.exp(-(((u - 0.30 * width) / (0.12 * width)) ** 2 + ((v - 0.55 * height) / (0.10 * height)) ** 2))
    structure = np.zeros((height, width), np.uint8)
    cv2.fillPoly(structure, [np.round(np.asarray(p) * 16).astype(np.int32) for p in polygons], 1, shift=4)
    # dark, slightly shaded structure (lit from above), with its own fine texture
    shade = 28.0 + 18.0 * (1.0 - v / height) + rng.normal(0.0, 2.0, (height, width))
    out = np.where(structure > 0, shade, out)
    out = cv2.GaussianBlur(out, (0, 0), 0.6) + rng.normal(0.0, 1.5, (height, width))
    return np.clip(np.rint(out), 0, 255).astype(np.uint8)


@functools.lru_cache(maxsize=None)
def approach_states(scenario: str = "thesis-3", fps: float = 2.0):
    """The flown approach sampled at ``fps``."""
    trajectory = simulate_flight(get_scenario(scenario))
    t = np.arange(trajectory.t_s[0], trajectory.t_s[-1], 1.0 / fps)
    return trajectory.at(t)


def cockpit_frames(camera: CameraModel, distances_m, scenario: str = "thesis-3", fps: float = 2.0,
                   seed: int = 7, supersample: int = 2, draw: bool = True):
    """Yield ``(t_s, frame, corners_uv, corners_visible, height_m)`` along the approach for each distance window.

    ``distances_m`` = (start, stop): frames whose distance to the threshold lies in between.
    ``draw=False``: the labels only (``frame`` None), for frames drawn earlier.
    """
    states = approach_states(scenario, fps)
    runway = get_scenario(scenario).runway
    scene = PaintedAirport(seed=seed, runway_length_m=runway.length_m, runway_width_m=runway.width_m,
                           haze_range_m=9000.0, joining_taxiways=((350.0, 1, 90.0, 200.0),))
    polygons = structure_polygons(camera.width, camera.height)
    distance = -states.p_runway_m[:, 0]
    R = batch_R_camera_from_runway(states.roll_rad, states.pitch_rad, states.dpsi_rad, camera.mount_rpy_rad)
    labels = ideal_features(states, runway, camera.without_distortion())
    start, stop = distances_m
    for i in np.nonzero((distance <= start) & (distance >= stop))[0]:
        if not draw:
            yield (float(states.t_s[i]), None, labels.corners_uv[i], labels.corners_visible[i],
                   float(-states.p_runway_m[i, 2]))
            continue
        grey = draw_frame(scene, camera, states.p_runway_m[i], R[i], supersample=supersample, blur_sigma_px=0.5,
                          rng=np.random.default_rng(seed + int(i)))
        frame = dress(grey, polygons, seed=seed + int(i))
        yield (float(states.t_s[i]), frame, labels.corners_uv[i], labels.corners_visible[i],
               float(-states.p_runway_m[i, 2]))
