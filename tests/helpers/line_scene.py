"""A patchwork of fields seen obliquely through a known lens: long straight boundaries, bent by
the lens's distortion, for the straight-line (plumb-line) distortion tests.

Independent of the code under test: each field (a square of the ground grid with its own grey
level) is drawn as a polygon whose sides are sampled finely on the ground, projected with the
radial model written out in :func:`tests.helpers.chessboard_views.project`, at 4x resolution and
averaged down.
"""
import math

import cv2
import numpy as np

from tests.helpers.chessboard_views import _rotation, project

SIZE = (640, 480)


def _cell_outline(i, j, cell_m, samples=24):
    s = np.linspace(0.0, 1.0, samples, endpoint=False)
    x0, y0 = i * cell_m, j * cell_m
    sides = [np.stack([x0 + cell_m * s, np.full_like(s, y0)], 1),
             np.stack([np.full_like(s, x0 + cell_m), y0 + cell_m * s], 1),
             np.stack([x0 + cell_m * (1 - s), np.full_like(s, y0 + cell_m)], 1),
             np.stack([np.full_like(s, x0), y0 + cell_m * (1 - s)], 1)]
    xy = np.concatenate(sides)
    return np.concatenate([xy, np.zeros((len(xy), 1))], axis=1)


def render_fields(K, distortion, yaw_deg, tilt_deg, seed, size=SIZE, cell_m=10.0, height_m=40.0):
    """One grey frame of a field patchwork on the ground, camera ``height_m`` above it, looking
    ``tilt_deg`` down from the horizontal and turned by ``yaw_deg`` against the grid."""
    rng = np.random.default_rng(seed)
    width, height = size
    S = 4
    image = np.full((height * S, width * S), 128, np.uint8)
    # ground frame: x, y on the ground, z up; camera frame: x right, y down, z forward
    tilt, yaw = math.radians(tilt_deg), math.radians(yaw_deg)
    R_tilted_from_level_cam = np.array([[1, 0, 0], [0, math.cos(tilt), -math.sin(tilt)],
                                        [0, math.sin(tilt), math.cos(tilt)]])
    R_level_cam_from_ground = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]])
    R_cam_from_level = R_tilted_from_level_cam @ R_level_cam_from_ground
    R_cam_from_ground = R_cam_from_level @ _rotation(0.0, 0.0, yaw)
    t_cam_m = -R_cam_from_ground @ np.array([0.0, 0.0, height_m])
    n = 30
    greys = rng.integers(40, 220, (2 * n, 2 * n))
    for i in range(-n, n):
        for j in range(-n, n):
            outline = _cell_outline(i, j, cell_m)
            p_cam = outline @ R_cam_from_ground.T + t_cam_m
            if p_cam[:, 2].min() < 5.0:
                continue
            r2 = (p_cam[:, 0] ** 2 + p_cam[:, 1] ** 2) / p_cam[:, 2] ** 2
            if distortion[0] < 0 and r2.max() > 0.8 / (3.0 * -distortion[0]):
                continue            # beyond where the radial polynomial folds back: not in view
            uv = project(outline, R_cam_from_ground, t_cam_m, K, distortion)
            if (uv[:, 0].max() < -50 or uv[:, 0].min() > width + 50 or uv[:, 1].max() < -50
                    or uv[:, 1].min() > height + 50):
                continue
            hi = ((uv + 0.5) * S - 0.5) * 16.0
            cv2.fillPoly(image, [np.round(hi).astype(np.int32)], int(greys[i + n, j + n]), shift=4)
    small = cv2.resize(image, (width, height), interpolation=cv2.INTER_AREA).astype(float)
    small += rng.normal(0.0, 2.0, small.shape)
    return np.clip(np.round(small), 0, 255).astype(np.uint8)
