"""A second, independent way of drawing runway frames: ray casting a painted airport.

This is deliberately not the project's renderer (no meshes, no OpenGL, no texture maps): each
pixel is split into ``supersample x supersample`` rays, each ray is intersected with the
ground plane z = 0 of the runway frame R, and the ground's grey level there is evaluated from
a painted plan of an airport (oriented rectangles drawn in order: fields, grass, roads, a
parallel taxiway with a centre line, connectors, an apron, the runway with side stripes,
threshold piano keys, designation blocks, touchdown-zone and aiming-point markings, centre
line dashes, tyre marks). Rays above the horizon see a sky gradient; distance adds haze.
The frame is then blurred (lens) and given seeded sensor noise.

So the detector is checked on frames whose look it was not tuned on, against exact labels
from :mod:`visland.features` (the same camera model).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from visland.camera import CameraModel

__all__ = ["PaintedAirport", "draw_frame", "hash_noise"]


def hash_noise(x, y, cell_m: float, seed: int) -> np.ndarray:
    """Smooth value noise in [0, 1): hashed grid values bilinearly interpolated (cell size in metres)."""
    gx, gy = x / cell_m, y / cell_m
    ix, iy = np.floor(gx), np.floor(gy)
    fx, fy = gx - ix, gy - iy
    fx = fx * fx * (3 - 2 * fx)
    fy = fy * fy * (3 - 2 * fy)

    def h(i, j):
        v = np.sin(i * 12.9898 + j * 78.233 + seed * 37.719) * 43758.5453
        return v - np.floor(v)

    a, b = h(ix, iy), h(ix + 1, iy)
    c, d = h(ix, iy + 1), h(ix + 1, iy + 1)
    return (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy


@dataclass(frozen=True)
class PaintedAirport:
    """The painted plan (grey levels 0..255; lengths in metres, runway frame R).

    ``runway_grey`` below ``grass_grey`` makes a dark runway on lighter grass (the usual look);
    above it, a bright concrete runway.
    """

    runway_length_m: float = 3000.0
    runway_width_m: float = 45.0
    runway_grey: float = 78.0
    grass_grey: float = 105.0
    marking_grey: float = 225.0
    side_stripes: bool = True
    taxiway_offset_m: float | None = -185.0   # centre of a parallel taxiway (None: no taxiway)
    parallel_road_offset_m: float | None = 340.0
    crossing_road: bool = True
    fields: bool = True
    haze_range_m: float = 14000.0
    runway: bool = True                        # False: the same airport without its runway
    seed: int = 0
    #: taxiways joining the runway's side: ``(x_m, side, angle_deg, length_m)``: where the
    #: taxiway's centre line meets the runway edge (x from the threshold), on which side (-1 left,
    #: +1 right), its angle to the runway (90: perpendicular, 30: a high-speed exit pointing
    #: along the landing direction) and how far it runs out; 23 m wide, the taxiway grey
    joining_taxiways: tuple = ()
    taxiway_grey: float = 122.0
    #: paved length before the threshold (a blast pad or a displaced threshold's pavement), the
    #: runway's width and grey, no markings on it; the threshold (x = 0) stays where the labels
    #: say, marked by the stripes 6 m past it and, with ``threshold_bar``, a 1.8 m white bar at it
    pre_threshold_m: float = 0.0
    threshold_bar: bool = False
    #: with a paved length before the threshold, a row of white arrow heads across its width
    #: just before the threshold (a displaced threshold's, ICAO Annex 14 figure 5-4): 4 m long,
    #: 3 m wide, 9 m apart, short marks across the width that are no threshold stripes
    threshold_heads: bool = False
    #: False: no threshold stripes (piano keys) at either end, the rest of the markings kept
    threshold_stripes: bool = True
    #: grey level of the distance haze (and of rays that reach no ground)
    haze_grey: float = 165.0
    #: rubber deposits on the runway (its touchdown zones): ``(x_start_m, x_end_m,
    #: width_fraction, grey)``, a band centred on the centre line, under the markings (out of
    #: the repr: frames cached under the repr of a scene without them stay valid)
    rubber: tuple = field(default=(), repr=False)

    def rectangles(self):
        """Oriented rectangles ``(x_c, y_c, half_length, half_width, angle_rad, grey)`` in paint order:
        the ground plan, then the runway markings (which lie on the runway)."""
        L, W = self.runway_length_m, self.runway_width_m
        half = W / 2.0
        rects, marks = [], []
        rng = np.random.default_rng(self.seed)
        if self.crossing_road:
            rects.append((-900.0, 0.0, 6000.0, 4.0, math.radians(68.0), 58.0))
            rects.append((L + 1500.0, 0.0, 6000.0, 3.5, math.radians(-52.0), 64.0))
        if self.parallel_road_offset_m is not None:
            rects.append((L / 2, self.parallel_road_offset_m, L / 2 + 2500.0, 3.5, 0.0, 66.0))
        if self.taxiway_offset_m is not None:
            y_t = self.taxiway_offset_m
            side = math.copysign(1.0, y_t)
            rects.append((L / 2, y_t, L / 2 + 80.0, 11.5, 0.0, 122.0))
            rects.append((L / 2, y_t, L / 2 + 80.0, 0.08, 0.0, 160.0))
            for x_c in (430.0, 1530.0, L - 60.0):                 # perpendicular connectors
                rects.append((x_c, y_t / 2, 11.5, abs(y_t) / 2, math.pi / 2, 122.0))
            # a high-speed exit at 30 deg
            rects.append((1900.0, y_t / 2, abs(y_t) / math.sin(math.radians(30)) / 2, 11.5,
                          -side * math.radians(30.0), 122.0))
            # apron and buildings beyond the taxiway
            rects.append((1300.0, y_t + side * 180.0, 450.0, 160.0, 0.0, 138.0))
            for k in range(6):
                rects.append((900.0 + 160.0 * k, y_t + side * (360.0 + 25.0 * (k % 2)), 40.0, 18.0, 0.0,
                              float(rng.uniform(40, 200))))
        for x_j, side, angle_deg, length in self.joining_taxiways:
            angle = math.radians(angle_deg)
            # centre of the strip: from the edge, half its length out along its direction
            dx, dy = -math.cos(angle), side * math.sin(angle)
            edge_y = side * self.runway_width_m / 2.0
            rects.append((x_j + dx * length / 2, edge_y + dy * length / 2, length / 2 + 6.0, 11.5,
                          math.atan2(dy, dx), self.taxiway_grey))
        # runway surface, then its markings (drawn only on the runway)
        if not self.runway:
            return rects, marks
        rects.append((L / 2, 0.0, L / 2, half, 0.0, self.runway_grey))
        for x_start, x_end, width_fraction, grey in self.rubber:
            rects.append(((x_start + x_end) / 2, 0.0, (x_end - x_start) / 2, width_fraction * half, 0.0, grey))
        if self.pre_threshold_m > 0:
            rects.append((-self.pre_threshold_m / 2, 0.0, self.pre_threshold_m / 2, half, 0.0, self.runway_grey))
            if self.threshold_heads:
                for y_c in np.arange(-half + 6.0, half - 4.0, 9.0):
                    rects.append((-9.0, float(y_c), 2.0, 1.5, 0.0, self.marking_grey))
        if self.threshold_bar:
            marks.append((0.9, 0.0, 0.9, half - 0.9, 0.0, self.marking_grey))
        if self.side_stripes:
            for sign in (-1.0, 1.0):
                marks.append((L / 2, sign * (half - 0.45), L / 2, 0.45, 0.0, self.marking_grey))
        for x0 in (6.0, L - 36.0) if self.threshold_stripes else ():  # threshold piano keys
            for i in range(6):
                for sign in (-1.0, 1.0):
                    y_c = sign * (1.8 + 3.6 * i + 0.9)
                    if abs(y_c) + 0.9 < half - 1.5:
                        marks.append((x0 + 15.0, y_c, 15.0, 0.9, 0.0, self.marking_grey))
        for x_c in (52.0, L - 52.0):                                 # designation blocks
            for y_c in (-3.5, 3.5):
                marks.append((x_c, y_c, 4.5, 1.5, 0.0, self.marking_grey))
        for x_c in (160.0, 460.0, 610.0, 760.0, 910.0, L - 160.0):   # touchdown zone
            for sign in (-1.0, 1.0):
                for j in range(3 if x_c < 400 else 2):
                    marks.append((x_c, sign * (10.0 + 3.6 * j), 11.25, 0.9, 0.0, self.marking_grey))
        for x_c in (330.0, L - 330.0):                               # aiming point
            for sign in (-1.0, 1.0):
                marks.append((x_c, sign * 13.5, 30.0, 4.5, 0.0, self.marking_grey))
        x = 66.0
        while x + 30.0 < L - 66.0:                                   # centre line dashes
            marks.append((x + 15.0, 0.0, 15.0, 0.45, 0.0, self.marking_grey))
            x += 50.0
        for k in range(10):                                          # tyre marks
            marks.append((float(rng.uniform(250, 700)), float(rng.uniform(-4, 4)), float(rng.uniform(10, 40)),
                          0.3, 0.0, self.runway_grey - 18.0))
        return rects, marks

    def grey_at(self, x, y) -> np.ndarray:
        """Grey level of the ground at runway-frame points ``x, y`` (arrays of equal shape)."""
        grey = self.grass_grey + 16.0 * (hash_noise(x, y, 60.0, self.seed) - 0.5) \
            + 8.0 * (hash_noise(x, y, 5.0, self.seed + 1) - 0.5)
        if self.fields:
            angle = math.radians(23.0)
            c, s = math.cos(angle), math.sin(angle)
            xr, yr = c * x + s * y, -s * x + c * y
            i, j = np.floor(xr / 380.0), np.floor(yr / 260.0)
            v = np.sin(i * 7.13 + j * 3.77 + self.seed) * 9731.3
            offset = (v - np.floor(v) - 0.5) * 50.0
            airport = (np.abs(y) < 600.0) & (x > -600.0) & (x < self.runway_length_m + 600.0)
            grey = np.where(airport, grey, grey + offset)
        rects, marks = self.rectangles()
        grey = _paint(grey, x, y, rects)
        on_runway = (np.abs(y) <= self.runway_width_m / 2) & (x >= 0) & (x <= self.runway_length_m)
        if self.runway and np.any(on_runway):
            grey[on_runway] = _paint(grey[on_runway], x[on_runway], y[on_runway], marks)
        return grey


def _paint(grey, x, y, rectangles):
    grey = np.array(grey, dtype=float, copy=True)
    for x_c, y_c, hl, hw, ang, value in rectangles:
        c, s = math.cos(ang), math.sin(ang)
        dx, dy = x - x_c, y - y_c
        inside = (np.abs(c * dx + s * dy) <= hl) & (np.abs(-s * dx + c * dy) <= hw)
        grey[inside] = value
    return grey


def draw_frame(scene: PaintedAirport, camera: CameraModel, p_runway_m, R_camera_from_runway,
               supersample: int = 3, blur_sigma_px: float = 0.6, noise_grey: float = 2.0,
               rng: np.random.Generator | None = None) -> np.ndarray:
    """Ray-cast a grey uint8 frame (H, W) of ``scene`` seen by ``camera`` at ``p_runway_m``.

    Sub-pixel rays are spread symmetrically around each pixel centre (pixel (0, 0) is centred
    at u = v = 0, SPEC), so the frame's geometry matches :meth:`CameraModel.project` exactly.
    With a lens distortion in ``camera``, each ray leaves through the pinhole direction of its
    (distorted) pixel, :meth:`CameraModel.undistort_normalized`: the frame is what that lens
    sees, while labels stay in the pinhole image (SPEC).
    """
    p = np.asarray(p_runway_m, dtype=float)
    R_runway_from_camera = np.asarray(R_camera_from_runway, dtype=float).T
    n = supersample
    offsets = (np.arange(n) + 0.5) / n - 0.5
    height, width = camera.height, camera.width
    accumulator = np.zeros((height, width))
    u = np.arange(width, dtype=float)
    sky_top, sky_horizon, haze = 200.0, 178.0, scene.haze_grey
    chunk = max(1, 250000 // width)
    for v0 in range(0, height, chunk):
        v = np.arange(v0, min(height, v0 + chunk), dtype=float)
        for du in offsets:
            for dv in offsets:
                uu, vv = np.meshgrid(u + du, v + dv)
                xy = np.stack([(uu - camera.cx) / camera.fx, (vv - camera.cy) / camera.fy], axis=-1)
                if camera.has_distortion:
                    xy = camera.undistort_normalized(xy)
                ray_C = np.concatenate([xy, np.ones_like(uu)[..., None]], axis=-1)
                ray_R = ray_C @ R_runway_from_camera.T
                ray_R /= np.linalg.norm(ray_R, axis=-1, keepdims=True)
                down = ray_R[..., 2]
                ground = down > 1e-6
                with np.errstate(divide="ignore", invalid="ignore"):
                    t = np.where(ground, -p[2] / down, np.inf)
                far = ground & (t < 60000.0)
                x = np.where(far, p[0] + t * ray_R[..., 0], 0.0)
                y = np.where(far, p[1] + t * ray_R[..., 1], 0.0)
                grey_ground = scene.grey_at(x, y)
                fog = np.exp(-np.where(far, t, 1e9) / scene.haze_range_m)
                grey_ground = fog * grey_ground + (1 - fog) * haze
                elevation = np.clip(-down, 0.0, 1.0)
                sky = sky_horizon + (sky_top - sky_horizon) * np.sqrt(elevation)
                accumulator[v0:v0 + len(v)] += np.where(far, grey_ground, np.where(ground, haze, sky))
    image = accumulator / (n * n)
    if blur_sigma_px > 0:
        image = cv2.GaussianBlur(image, (0, 0), blur_sigma_px)
    if noise_grey > 0:
        rng = rng if rng is not None else np.random.default_rng(0)
        image = image + rng.normal(0.0, noise_grey, image.shape)
    return np.clip(np.rint(image), 0, 255).astype(np.uint8)
