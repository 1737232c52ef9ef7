"""Roll and pitch from the frame itself, for footage without attitude data (issue 18 item 3).

The detector needs the horizon: every runway line meets it (:mod:`visland.detection.horizon`).
With telemetry the horizon comes from the inertial roll and pitch; without it, from the image,
in two steps:

1. **The visible horizon** (:func:`visible_horizon`): where the sky meets the ground, the
   straight line across the frame (pixels of the aircraft's structure left out) along which
   the grey levels step most. Its slope gives the roll.
2. **The true horizon** lies a little above the visible one: haze fades the distant ground into
   the sky, so the sky-ground step is seen where the ground still shows (measured on the
   ray-cast airport with 6-20 km of haze, 1024 and 1280x720 frames: pitch 0.00 to 0.20 deg too
   high, roll within 0.06 deg). Once the runway is found, its own vanishing point is on the
   true horizon: :meth:`ImageAttitude.through_point` moves the horizon through it, and the
   offset is carried to the next frames. (The crossings of pairs of ground lines, which also
   lie on the true horizon, were tried and placed it no better on those frames.)

:func:`attitude_from_horizon` turns a horizon line into the roll and pitch that
:func:`visland.detection.horizon.horizon_frame` would turn back into the same line (the camera's
mounting is taken as known). Yaw does not move the horizon.

Pixel conventions (SPEC.md): ``(u, v)`` with (0, 0) at the centre of the top-left pixel, v down;
the frame here is the pinhole image (:func:`visland.folder.scene_frame`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from visland.camera import CameraModel

__all__ = ["ImageAttitude", "attitude_from_horizon", "attitude_from_image", "visible_horizon"]

#: Working resolution of the horizon search (longer side, pixels).
WORKING_SIDE_PX = 512
#: Largest roll of the horizon in the image searched (degrees) and the angular step of the search.
MAX_ROLL_DEG = 30.0
ANGLE_STEP_DEG = 0.5
#: Smallest sky-ground step (grey levels, mean over the bands either side) taken for a horizon.
MIN_STEP_GREY = 4.0


@dataclass(frozen=True)
class ImageAttitude:
    """Roll and pitch read off one frame.

    Attributes
    ----------
    roll_rad, pitch_rad : float
        Body attitude (ZYX Euler, the telemetry's convention) whose horizon, with the camera's
        mounting, is the horizon found in the image.
    point_uv, direction_uv : ndarray, shape (2,)
        A point of that horizon and its unit direction in pixels (``u`` increasing).
    visible_offset_px : float
        How far the true horizon was placed above the visible sky-ground step (pixels, along
        the image's up normal of the horizon).
    method : str
        ``"sky"`` (the visible horizon) or ``"runway"`` (moved through the runway's vanishing
        point, in this frame or an earlier one).
    """

    roll_rad: float
    pitch_rad: float
    point_uv: np.ndarray
    direction_uv: np.ndarray
    visible_offset_px: float
    method: str

    def through_point(self, camera: CameraModel, uv, method: str = "runway") -> "ImageAttitude":
        """The same horizon direction moved parallel to pass through ``uv`` (a vanishing point)."""
        uv = np.asarray(uv, float)
        up = _up_normal(self.direction_uv)
        shift = float((uv - self.point_uv) @ up)
        roll, pitch = attitude_from_horizon(camera, uv, self.direction_uv)
        return ImageAttitude(roll, pitch, uv, self.direction_uv, self.visible_offset_px + shift, method)


def _up_normal(direction_uv) -> np.ndarray:
    """Unit normal of a horizon direction pointing up in the image (towards the sky)."""
    t = np.asarray(direction_uv, float) / np.linalg.norm(direction_uv)
    n = np.array([t[1], -t[0]])
    return n if n[1] < 0 else -n


def attitude_from_horizon(camera: CameraModel, point_uv, direction_uv) -> tuple[float, float]:
    """Roll and pitch (radians) whose horizon is the pixel line through ``point_uv`` along
    ``direction_uv``, the ground lying below it in the image.

    The horizon is the image of the directions orthogonal to the local vertical: the plane
    through the camera centre and the line has normal ``n_C`` (the cross product of the rays of
    two of its points), which is the down axis in the camera frame up to sign (thesis eq. 3.33's
    ``n``); the sign puts the image's lower side on the ground. In the body frame
    ``n_B = R_BC n_C = (-sin(theta), sin(phi) cos(theta), cos(phi) cos(theta))``, so
    ``theta = asin(-n_Bx)`` and ``phi = atan2(n_By, n_Bz)``.

    Parameters
    ----------
    camera : CameraModel
        Intrinsics ``K`` and mounting ``R_body_from_camera`` (the mounting is taken as known).
    point_uv : array_like, shape (2,)
        A pixel of the horizon line (SPEC convention, pinhole image).
    direction_uv : array_like, shape (2,)
        Direction of the horizon line in pixels (any length; normalised here).

    Returns
    -------
    roll_rad, pitch_rad : float
        Body roll and pitch (ZYX Euler, radians) whose horizon, through the camera's mounting,
        is that line.

    References
    ----------
    Gibert, PhD thesis (2016), eq. 3.33 (the ground plane's normal ``n`` in the camera frame).
    """
    p = np.asarray(point_uv, float)
    t = np.asarray(direction_uv, float) / np.linalg.norm(direction_uv)
    K_inv = np.linalg.inv(camera.K)
    ray_a = K_inv @ np.array([p[0], p[1], 1.0])
    ray_b = K_inv @ np.array([p[0] + 100.0 * t[0], p[1] + 100.0 * t[1], 1.0])
    down_C = np.cross(ray_a, ray_b)
    down_C /= np.linalg.norm(down_C)
    below = p - 100.0 * _up_normal(t)                 # a pixel on the ground side
    if (K_inv @ np.array([below[0], below[1], 1.0])) @ down_C < 0:
        down_C = -down_C
    down_B = camera.R_body_from_camera @ down_C
    pitch = math.asin(float(np.clip(-down_B[0], -1.0, 1.0)))
    roll = math.atan2(float(down_B[1]), float(down_B[2]))
    return roll, pitch


def visible_horizon(grey: np.ndarray, ignored: np.ndarray | None = None):
    """The sky-ground step as a pixel line: ``(point_uv, direction_uv, step_grey)`` or None.

    ``grey`` is the pinhole frame in grey levels; ``ignored`` the pixels showing no scene
    (:func:`visland.folder.ignored_pixels`). The frame is turned through a fan of angles
    (+-:data:`MAX_ROLL_DEG`); at each, the rows are averaged across the whole width (scene
    pixels only), and the horizon is the angle and row where that profile steps most between a
    band above and a band below (a Radon transform of the step: a straight edge across the
    whole frame wins over field boundaries and roads, which are shorter or lie at other angles).

    Parameters
    ----------
    grey : ndarray of uint8, shape (H, W)
        Pinhole frame, grey levels.
    ignored : ndarray of bool, shape (H, W), optional
        True where a pixel shows no scene (the aircraft's structure, outside the lens).

    Returns
    -------
    tuple or None
        ``(point_uv, direction_uv, step_grey)``: a pixel of the horizon (shape (2,), SPEC pixels),
        its unit direction (shape (2,), ``u`` increasing) and the grey-level step across it; None
        when no step of :data:`MIN_STEP_GREY` grey levels crosses the frame.
    """
    height, width = grey.shape
    scale = WORKING_SIDE_PX / float(max(height, width))
    size = (max(16, int(round(width * scale))), max(16, int(round(height * scale))))
    small = cv2.resize(grey, size, interpolation=cv2.INTER_AREA).astype(np.float32)
    valid = np.ones(small.shape, np.float32)
    if ignored is not None:
        valid = (cv2.resize(ignored.astype(np.float32), size, interpolation=cv2.INTER_AREA) < 0.01).astype(np.float32)
    w, h = size
    centre = ((w - 1) / 2.0, (h - 1) / 2.0)
    # coarse: wide bands (a hazy horizon is a ramp tens of rows tall), every angle; then fine:
    # narrow bands around the coarse line, a finer fan of angles
    coarse = _strongest_step(small, valid, centre, np.arange(-MAX_ROLL_DEG, MAX_ROLL_DEG + 1e-9, ANGLE_STEP_DEG),
                             max(3, h // 36), (0, h))
    if coarse[1] is None or coarse[0] < MIN_STEP_GREY:
        return None
    fine_half = max(2, h // 120)
    margin = 2 * max(3, h // 36)
    best = _strongest_step(small, valid, centre, coarse[1] + np.arange(-1.0, 1.0 + 1e-9, 0.1), fine_half,
                           (int(coarse[2]) - margin, int(coarse[2]) + margin))
    if best[1] is None:
        best = coarse
    score, angle, row = best
    # the row in the turned image, back to the working image, then to full-resolution pixels
    M = cv2.getRotationMatrix2D(centre, float(angle), 1.0)
    M_back = cv2.invertAffineTransform(M)
    point = M_back @ np.array([centre[0], row, 1.0])
    direction = M_back[:, :2] @ np.array([1.0, 0.0])
    kx, ky = width / float(w), height / float(h)
    point_full = np.array([(point[0] + 0.5) * kx - 0.5, (point[1] + 0.5) * ky - 0.5])
    direction_full = np.array([direction[0] * kx, direction[1] * ky])
    direction_full /= np.linalg.norm(direction_full)
    if direction_full[0] < 0:
        direction_full = -direction_full
    return point_full, direction_full, score


def _strongest_step(small, valid, centre, angles, half: int, row_range):
    """``(step_grey, angle_deg, row)`` of the strongest step of the width-averaged profile over
    ``angles`` (the image turned about ``centre``), bands of ``half`` rows, split rows within
    ``row_range``; the angle and row refined to a fraction of their steps by parabolas."""
    h, w = small.shape
    best, steps = (0.0, None, None), []
    lo, hi = max(half, row_range[0]), min(h - half, row_range[1])
    if hi <= lo:
        return best
    for angle in angles:
        M = cv2.getRotationMatrix2D(centre, float(angle), 1.0)
        turned = cv2.warpAffine(small * valid, M, (w, h), flags=cv2.INTER_LINEAR, borderValue=0)
        weight = cv2.warpAffine(valid, M, (w, h), flags=cv2.INTER_LINEAR, borderValue=0)
        count = weight.sum(axis=1)
        profile = np.where(count > 0.3 * w, turned.sum(axis=1) / np.maximum(count, 1e-6), np.nan)
        c = np.concatenate([[0.0], np.cumsum(np.nan_to_num(profile))])
        cf = np.concatenate([[0], np.cumsum(np.isfinite(profile))])
        rows = np.arange(lo, hi)
        complete = (cf[rows + half] - cf[rows - half]) == 2 * half
        step = np.where(complete, np.abs((c[rows] - c[rows - half]) - (c[rows + half] - c[rows])) / half, 0.0)
        k = int(np.argmax(step))
        steps.append(step[k])
        if step[k] > best[0]:
            offset = 0.0
            if 0 < k < len(step) - 1 and step[k - 1] > 0 and step[k + 1] > 0:
                denom = step[k - 1] - 2 * step[k] + step[k + 1]
                offset = 0.5 * (step[k - 1] - step[k + 1]) / denom if denom < 0 else 0.0
            # the split between rows[k] - 1 and rows[k] lies at rows[k] - 0.5
            best = (float(step[k]), float(angle), float(rows[k] - 0.5 + offset))
    score, angle, row = best
    if angle is None:
        return best
    j = int(np.argmin(np.abs(np.asarray(angles) - angle)))
    if 0 < j < len(angles) - 1:
        a_, b_, c_ = steps[j - 1], steps[j], steps[j + 1]
        denom = a_ - 2 * b_ + c_
        if denom < 0:
            angle += 0.5 * (a_ - c_) / denom * float(angles[1] - angles[0])
    return score, angle, row


def attitude_from_image(grey: np.ndarray, camera: CameraModel, ignored: np.ndarray | None = None,
                        previous: ImageAttitude | None = None) -> ImageAttitude | str:
    """Roll and pitch from the frame (module docstring), or the reason they cannot be read.

    ``previous``: the last frame's result; its offset between the visible and the true horizon
    (set by the runway's vanishing point, :meth:`ImageAttitude.through_point`) is carried over.

    Parameters
    ----------
    grey : ndarray of uint8, shape (H, W)
        Pinhole frame, grey levels.
    camera : CameraModel
        The camera (intrinsics and mounting).
    ignored : ndarray of bool, shape (H, W), optional
        True where a pixel shows no scene (:func:`visland.folder.ignored_pixels`).
    previous : ImageAttitude, optional
        The previous frame's result.

    Returns
    -------
    ImageAttitude or str
        The attitude, or one sentence saying why the frame gives none.
    """
    found = visible_horizon(grey, ignored)
    if found is None:
        return "no horizon in the frame (no straight sky-ground step across it)"
    point, direction, _ = found
    # the runway's vanishing point, once seen, says how far the true horizon is above the
    # visible step; the offset changes slowly (height and visibility), so it is carried over
    offset = previous.visible_offset_px if previous is not None else 0.0
    method = "sky" if previous is None else previous.method
    true_point = point + offset * _up_normal(direction)
    roll, pitch = attitude_from_horizon(camera, true_point, direction)
    return ImageAttitude(roll, pitch, true_point, direction, float(offset), method)
