"""Synthetic chessboard photographs through a known lens, for the calibration tests.

Independent of the code under test: each square is drawn as a polygon whose sides are sampled
finely on the board plane, moved to the camera by a known pose and projected with OpenCV's
radial-tangential model written out here (Brown-Conrady, as documented by OpenCV), at 4x the
resolution and averaged down (anti-aliasing). Pixel convention of visland.camera: (0, 0) is the
centre of the top-left pixel.
"""
import math

import cv2
import numpy as np

#: the camera behind the synthetic views: 640x480, about 63 deg across, marked barrel distortion
TRUE_SIZE = (640, 480)
TRUE_K = dict(fx=520.0, fy=512.0, cx=324.5, cy=236.0)
TRUE_DISTORTION = (-0.28, 0.09, 0.0008, -0.0006, 0.0)
BOARD = (9, 6)          # inner corners
SQUARE_M = 0.025
SUPERSAMPLE = 4


def _rotation(rx, ry, rz):
    cx_, sx = math.cos(rx), math.sin(rx)
    cy_, sy = math.cos(ry), math.sin(ry)
    cz, sz = math.cos(rz), math.sin(rz)
    Rx = np.array([[1, 0, 0], [0, cx_, -sx], [0, sx, cx_]])
    Ry = np.array([[cy_, 0, sy], [0, 1, 0], [-sy, 0, cy_]])
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def project(p_board_m, R_cam_from_board, t_cam_m, K=TRUE_K, distortion=TRUE_DISTORTION):
    """Board-plane points (N, 3) to distorted pixels (N, 2), OpenCV's model written out."""
    p = p_board_m @ R_cam_from_board.T + t_cam_m
    x, y = p[:, 0] / p[:, 2], p[:, 1] / p[:, 2]
    k1, k2, p1, p2, k3 = distortion
    r2 = x * x + y * y
    g = 1 + k1 * r2 + k2 * r2 ** 2 + k3 * r2 ** 3
    xd = x * g + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * g + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return np.stack([K["fx"] * xd + K["cx"], K["fy"] * yd + K["cy"]], axis=1)


def _outline(x0, y0, x1, y1, samples=16):
    """Closed outline of the board-plane rectangle [x0, x1] x [y0, y1] (square units), finely sampled."""
    s = np.linspace(0, 1, samples, endpoint=False)
    sides = [np.stack([x0 + (x1 - x0) * s, np.full_like(s, y0)], 1),
             np.stack([np.full_like(s, x1), y0 + (y1 - y0) * s], 1),
             np.stack([x1 - (x1 - x0) * s, np.full_like(s, y1)], 1),
             np.stack([np.full_like(s, x0), y1 - (y1 - y0) * s], 1)]
    xy = np.concatenate(sides) * SQUARE_M
    return np.concatenate([xy, np.zeros((len(xy), 1))], axis=1)


def render_view(rx_deg, ry_deg, rz_deg, centre_cam_m, rng, size=TRUE_SIZE):
    """One grey photograph of the board; the board centre at ``centre_cam_m`` in the camera frame."""
    cols, rows = BOARD
    R = _rotation(*np.radians([rx_deg, ry_deg, rz_deg]))
    centre_board = np.array([(cols - 1) / 2, (rows - 1) / 2, 0.0]) * SQUARE_M
    t = np.asarray(centre_cam_m, float) - R @ centre_board
    width, height = size
    S = SUPERSAMPLE
    image = np.full((height * S, width * S), 110, np.uint8)

    def fill(outline_m, value):
        uv = project(outline_m, R, t)
        hi = ((uv + 0.5) * S - 0.5) * 16.0          # 1/16 px fixed point at 4x resolution
        cv2.fillPoly(image, [np.round(hi).astype(np.int32)], int(value), lineType=cv2.LINE_8, shift=4)
        return uv

    margin = fill(_outline(-2, -2, cols + 1, rows + 1), 235)
    inside = (margin[:, 0] > 2) & (margin[:, 0] < width - 3) & (margin[:, 1] > 2) & (margin[:, 1] < height - 3)
    assert inside.all(), "test pose puts the board outside the image"
    for i in range(cols + 1):          # squares [i-1, i] x [j-1, j]
        for j in range(rows + 1):
            if (i + j) % 2 == 0:
                fill(_outline(i - 1, j - 1, i, j), 25)
    small = cv2.resize(image, (width, height), interpolation=cv2.INTER_AREA).astype(float)
    small += rng.normal(0.0, 2.0, small.shape)
    return np.clip(np.round(small), 0, 255).astype(np.uint8)


#: (rx, ry, rz) degrees and the board centre in the camera frame (m): tilted views reaching the
#: image corners and borders, where the distortion shows
POSES = [
    ((0, 0, 0), (0.0, 0.0, 0.45)),
    ((25, 0, 5), (-0.08, -0.06, 0.42)),
    ((-25, 5, -5), (0.08, 0.06, 0.42)),
    ((0, 30, 10), (-0.09, 0.03, 0.42)),
    ((5, -30, -10), (0.09, -0.05, 0.42)),
    ((20, 20, 0), (-0.10, 0.08, 0.45)),
    ((-20, -20, 15), (0.10, -0.06, 0.45)),
    ((15, -25, 30), (0.10, 0.08, 0.45)),
    ((-15, 25, -30), (-0.10, -0.03, 0.45)),
    ((30, 10, 90), (0.0, 0.0, 0.40)),
    ((-10, -35, 0), (0.0, 0.0, 0.38)),
    ((35, 0, -15), (0.0, 0.03, 0.40)),
]


def render_views(seed=0):
    rng = np.random.default_rng(seed)
    return [render_view(*rotation, centre, rng) for rotation, centre in POSES]
