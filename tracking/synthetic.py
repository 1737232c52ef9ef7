"""A flat textured world imaged through a homography: fast frames with exact geometry.

Stand-in for :mod:`visland.render` in the tracking tests and the speed benchmark. The ground
plane z = 0 of the runway frame R carries a seeded grass-like texture (noise at several
scales); the runway (asphalt) and its threshold bars are convex polygons drawn analytically
in the image at exactly :meth:`visland.runway.Runway.corners_runway_m`.

Geometry. A ground point ``p_R = (x, y, 0)`` seen by a camera at ``c_R`` with rotation
``R_camera_from_runway`` lands at ``p_C = x r1 + y r2 - R c_R`` (r1, r2 the first two
columns of R), so the ground texture maps into the image by the homography
``K [r1 r2 -R c_R] M`` (M: texel to metres) and the polygons' corners land exactly where
:meth:`visland.camera.CameraModel.project` puts them (same pixel convention: (0, 0) the
centre of the top-left pixel; texel centres likewise).

Filtering. The ground is sampled from a mip-map (an image pyramid) at the level matching each
pixel's footprint on the texture (the larger axis of the local Jacobian of the
image-to-texture map), blending the two nearest levels, so that the distant ground does not
alias; polygons get an analytic coverage (product over edges of ``clip(0.5 + d, 0, 1)``, d
the signed pixel distance to the edge: exact for one straight edge, close at corners).
Rays that do not hit the ground show a uniform sky. There is no lighting, haze or sensor
model: the drift figures come from :mod:`visland.render` (benchmarks/track_drift.py).
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from visland.camera import CameraModel
from visland.runway import Runway

__all__ = ["PlanarScene", "make_planar_scene", "render_planar"]

_NEAR_PLANE_M = 1.0


@dataclass(frozen=True)
class PlanarScene:
    """The ground texture pyramid and the runway polygons.

    ``pyramid[0]`` is the ground texture: texel (row i, column j) has its centre at runway
    coordinates ``x = x0_m + i * metres_per_texel``, ``y = y0_m + j * metres_per_texel``;
    ``pyramid[l]`` halves the resolution l times (OpenCV ``pyrDown``: its texel i sits on
    level-0 texel ``2^l i``). ``polygons`` is a list of ``(corners_runway_m (k, 3), grey,
    texture_gain)``: convex ground polygons painted in order, grey level plus
    ``texture_gain`` times the ground texture's deviation from its mean.

    Attributes
    ----------
    pyramid : tuple of ndarray
        The ground texture and its ``pyrDown`` levels, grey levels.
    x0_m, y0_m : float
        Runway coordinates of texel (0, 0)'s centre, metres.
    metres_per_texel : float
        Texel size at level 0, metres.
    polygons : tuple
        The painted polygons, as above.
    ground_mean : float
        Mean grey level of the ground texture.
    sky_level : int, default 200
        Grey level of the sky.
    """

    pyramid: tuple
    x0_m: float
    y0_m: float
    metres_per_texel: float
    polygons: tuple
    ground_mean: float
    sky_level: int = 200

    @property
    def M_runway_from_texel(self) -> np.ndarray:
        """Homogeneous map from texel coordinates (column, row, 1) to ground (x, y, 1)."""
        s = self.metres_per_texel
        return np.array([[0.0, s, self.x0_m], [s, 0.0, self.y0_m], [0.0, 0.0, 1.0]])


def _noise(shape, scale_texels: float, rng: np.random.Generator) -> np.ndarray:
    """Zero-mean, unit-RMS smooth noise with correlation length about ``scale_texels``."""
    if scale_texels > 4.0:
        # smooth noise is drawn on a coarse grid and interpolated up (same look, far cheaper)
        factor = scale_texels / 2.0
        coarse = (max(int(shape[0] / factor) + 2, 2), max(int(shape[1] / factor) + 2, 2))
        field = cv2.GaussianBlur(rng.standard_normal(coarse).astype(np.float32), (0, 0), 2.0)
        field = cv2.resize(field, (shape[1], shape[0]), interpolation=cv2.INTER_CUBIC)
    else:
        field = rng.standard_normal(shape).astype(np.float32)
        if scale_texels > 0.5:
            field = cv2.GaussianBlur(field, (0, 0), scale_texels)
    return field / max(float(field.std()), 1e-6)


def _runway_polygons(runway: Runway) -> list:
    half = runway.width_m / 2.0
    polygons = [(runway.corners_runway_m()[[0, 1, 3, 2]], 150.0, 0.35)]
    # threshold bars (piano keys): 30 m long from 6 m past the threshold, 1.8 m wide, 1.8 m apart,
    # leaving the centre 6 m clear (ICAO-like; exact layout is irrelevant here)
    bar, gap = 1.8, 1.8
    y = 3.0
    while y + bar <= half - 1.5:
        for sign in (-1.0, 1.0):
            y0, y1 = sorted((sign * y, sign * (y + bar)))
            polygons.append((np.array([[6.0, y0, 0], [6.0, y1, 0], [36.0, y1, 0], [36.0, y0, 0]]), 225.0, 0.1))
        y += bar + gap
    return polygons


def make_planar_scene(runway: Runway | None = None, seed: int = 0, x_range_m=(-7000.0, 4000.0),
                      y_range_m=(-1500.0, 1500.0), metres_per_texel: float = 1.0) -> PlanarScene:
    """A seeded ground texture and the runway polygons.

    Parameters
    ----------
    runway : the runway (default :class:`visland.runway.Runway`).
    seed : seed of the texture's random generator.
    x_range_m, y_range_m : ground extent (runway frame) covered by the texture (mirrored beyond).
    metres_per_texel : texture resolution.
    """
    runway = runway or Runway()
    if not (isinstance(metres_per_texel, (int, float)) and metres_per_texel > 0):
        raise ValueError(f"metres_per_texel must be positive, got {metres_per_texel!r}")
    (x_min, x_max), (y_min, y_max) = x_range_m, y_range_m
    if not (x_min < x_max and y_min < y_max):
        raise ValueError("x_range_m and y_range_m must be increasing pairs")
    s = float(metres_per_texel)
    rows = int(np.ceil((x_max - x_min) / s))
    cols = int(np.ceil((y_max - y_min) / s))
    if rows * cols > 60_000_000:
        raise ValueError(f"texture of {rows}x{cols} texels is too large; raise metres_per_texel")
    rng = np.random.default_rng(seed)
    ground = 95.0 + 14.0 * _noise((rows, cols), 40.0 / s, rng) + 9.0 * _noise((rows, cols), 6.0 / s, rng) \
        + 6.0 * _noise((rows, cols), 1.0 / s, rng)
    texture = np.clip(ground, 0, 255).astype(np.float32)
    pyramid = [texture]
    while min(pyramid[-1].shape) > 8:
        pyramid.append(cv2.pyrDown(pyramid[-1]))
    return PlanarScene(pyramid=tuple(pyramid), x0_m=x_min + s / 2, y0_m=y_min + s / 2, metres_per_texel=s,
                       polygons=tuple(_runway_polygons(runway)), ground_mean=95.0)


def _ground(scene: PlanarScene, H_texel_from_image: np.ndarray, width: int, height: int,
            sky: np.ndarray) -> np.ndarray:
    """Mip-mapped ground texture sampled at every pixel that is not ``sky``, float32 (height, width)."""
    u = np.arange(width, dtype=np.float64)[None, :]
    v = np.arange(height, dtype=np.float64)[:, None]
    h = H_texel_from_image
    a = h[0, 0] * u + h[0, 1] * v + h[0, 2]
    b = h[1, 0] * u + h[1, 1] * v + h[1, 2]
    w = h[2, 0] * u + h[2, 1] * v + h[2, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        col = a / w
        row = b / w
        # Jacobian columns of (col, row) with respect to u and v
        du = np.hypot(h[0, 0] - col * h[2, 0], h[1, 0] - row * h[2, 0]) / np.abs(w)
        dv = np.hypot(h[0, 1] - col * h[2, 1], h[1, 1] - row * h[2, 1]) / np.abs(w)
        level = np.log2(np.maximum(np.maximum(du, dv), 1.0))
    top = len(scene.pyramid) - 1
    level = np.clip(np.nan_to_num(level, nan=0.0, posinf=0.0), 0.0, top)
    level[sky] = np.nan
    if np.all(sky):
        return np.zeros((height, width), dtype=np.float32)
    out = np.zeros((height, width), dtype=np.float32)
    col32 = np.nan_to_num(col, nan=-1e6).astype(np.float32)
    row32 = np.nan_to_num(row, nan=-1e6).astype(np.float32)
    for lev in range(int(np.floor(np.nanmin(level))), int(np.ceil(np.nanmax(level))) + 1):
        weight = np.nan_to_num(np.clip(1.0 - np.abs(level - lev), 0.0, 1.0), nan=0.0).astype(np.float32)
        rows_used = np.nonzero(weight.max(axis=1) > 0)[0]
        if not rows_used.size:
            continue
        r0, r1 = rows_used[0], rows_used[-1] + 1
        f = np.float32(2.0 ** -lev)
        sample = cv2.remap(scene.pyramid[lev], col32[r0:r1] * f, row32[r0:r1] * f, cv2.INTER_LINEAR,
                           borderMode=cv2.BORDER_REFLECT_101)
        out[r0:r1] += weight[r0:r1] * sample
    return out


def _clip_near(points_C: np.ndarray) -> np.ndarray:
    """Sutherland-Hodgman clip of a polygon (k, 3) in camera coordinates to z >= near plane."""
    out = []
    k = len(points_C)
    for i in range(k):
        a, b = points_C[i], points_C[(i + 1) % k]
        a_in, b_in = a[2] >= _NEAR_PLANE_M, b[2] >= _NEAR_PLANE_M
        if a_in:
            out.append(a)
        if a_in != b_in:
            t = (_NEAR_PLANE_M - a[2]) / (b[2] - a[2])
            out.append(a + t * (b - a))
    return np.array(out).reshape(-1, 3)


def _coverage(uv: np.ndarray, width: int, height: int):
    """Analytic coverage of a convex image polygon: (box (u0, v0, u1, v1), coverage array) or None."""
    u0 = max(int(np.floor(uv[:, 0].min())) - 1, 0)
    v0 = max(int(np.floor(uv[:, 1].min())) - 1, 0)
    u1 = min(int(np.ceil(uv[:, 0].max())) + 2, width)
    v1 = min(int(np.ceil(uv[:, 1].max())) + 2, height)
    if u1 <= u0 or v1 <= v0:
        return None
    uu = np.arange(u0, u1, dtype=np.float64)[None, :]
    vv = np.arange(v0, v1, dtype=np.float64)[:, None]
    # orientation: make the inward normals point inside whatever the winding
    area2 = np.sum(uv[:, 0] * np.roll(uv[:, 1], -1) - np.roll(uv[:, 0], -1) * uv[:, 1])
    sign = 1.0 if area2 > 0 else -1.0
    cover = np.ones((v1 - v0, u1 - u0))
    for i in range(len(uv)):
        a, b = uv[i], uv[(i + 1) % len(uv)]
        edge = b - a
        length = np.hypot(*edge)
        if length < 1e-9:
            continue
        normal = sign * np.array([-edge[1], edge[0]]) / length
        distance = normal[0] * (uu - a[0]) + normal[1] * (vv - a[1])
        cover *= np.clip(0.5 + distance, 0.0, 1.0)
    return (u0, v0, u1, v1), cover.astype(np.float32)


def render_planar(scene: PlanarScene, camera: CameraModel, R_camera_from_runway: np.ndarray,
                  p_camera_runway_m) -> np.ndarray:
    """Grey image of the scene seen by ``camera`` from ``p_camera_runway_m``, through the exact homography.

    Parameters
    ----------
    scene : PlanarScene
        Ground texture and runway polygons.
    camera : visland.camera.CameraModel
        Intrinsics (pinhole).
    R_camera_from_runway : ndarray, shape (3, 3)
        Rotation from the runway frame R to the camera frame.
    p_camera_runway_m : array_like, shape (3,)
        Camera centre in R, metres (z < 0: above the ground).

    Returns
    -------
    ndarray, shape (height, width), uint8
    """
    R = np.asarray(R_camera_from_runway, dtype=float)
    c = np.asarray(p_camera_runway_m, dtype=float)
    if R.shape != (3, 3) or c.shape != (3,):
        raise ValueError("R_camera_from_runway must be 3x3 and p_camera_runway_m of shape (3,)")
    if not c[2] < 0:
        raise ValueError(f"the camera must be above the ground (z < 0 in the runway frame), got z = {c[2]:g}")
    width, height = camera.width, camera.height
    plane_to_camera = np.column_stack([R[:, 0], R[:, 1], -R @ c])
    H_image_from_texel = camera.K @ plane_to_camera @ scene.M_runway_from_texel
    # sky: rays whose runway-frame direction does not point down far enough to meet the ground
    # within 30 km (a flat haze band instead of minified texture at the horizon)
    row = R.T[2] @ np.linalg.inv(camera.K)            # d_z = row . (u, v, 1)
    u = np.arange(width, dtype=np.float32)[None, :]
    v = np.arange(height, dtype=np.float32)[:, None]
    sky = row[0] * u + row[1] * v + row[2] <= -c[2] / 30000.0
    ground = _ground(scene, np.linalg.inv(H_image_from_texel), width, height, sky)
    image = ground.copy()
    for corners_R, grey, gain in scene.polygons:
        p_C = (corners_R - c) @ R.T
        p_C = _clip_near(p_C)
        if len(p_C) < 3:
            continue
        uv = camera.project(p_C)[0]
        result = _coverage(uv, width, height)
        if result is None:
            continue
        (u0, v0, u1, v1), cover = result
        patch = image[v0:v1, u0:u1]
        paint = grey + gain * (ground[v0:v1, u0:u1] - scene.ground_mean)
        image[v0:v1, u0:u1] = patch + cover * (paint - patch)
    image = np.where(sky, np.float32(scene.sky_level), image)
    return np.clip(image + 0.5, 0, 255).astype(np.uint8)
