"""Camera attitude from the inertial unit, and the image motions it predicts.

The tracker never knows the runway heading. It works in the *level frame* L of the
designation: the runway-frame axes of :mod:`visland.frames` (z down) turned so that x is the
horizontal direction the aircraft was heading at the designation frame, i.e. the runway
frame R rotated by the unknown ``dpsi_0`` about the vertical. ``R_camera_from_level`` is
:func:`visland.frames.R_camera_from_runway` with ``dpsi = heading - heading_0`` (inertial
heading change), so it is known from telemetry alone.

Two image maps follow (K the intrinsic matrix):

- rotation between frames a and b (thesis pinhole, section 2.1): a direction ``d_Ca`` is seen
  at ``d_Cb = R_Cb_from_Ca d_Ca`` with ``R_Cb_from_Ca = R_Cb_from_L R_Ca_from_L^T``; points
  far away (or a pure rotation) move by the homography ``K R_Cb_from_Ca K^-1``;
- ground plane (thesis virtual frame, eq. 3.23): a ground point P seen from camera centre c at
  height dH has level-frame coordinates ``p_L = dH (y_v1, y_v2, 1)``, so its pixel is
  ``K R_C_from_L [y_v1, y_v2, 1]^T``: the homography ``G = K R_C_from_L`` maps virtual
  coordinates to pixels (:func:`virtual_to_pixel_homography`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from visland.camera import CameraModel
from visland.frames import R_camera_from_runway

__all__ = ["Attitude", "R_camera_from_level", "rotation_homography", "virtual_to_pixel_homography"]


@dataclass(frozen=True)
class Attitude:
    """Inertial attitude of the body at one frame (ZYX Euler angles from NED, radians).

    Attributes
    ----------
    roll_rad, pitch_rad : float
        Roll and pitch of the body frame relative to NED, radians.
    heading_rad : float
        True heading, radians (from north, clockwise seen from above).

    Raises
    ------
    ValueError
        When an angle is not a finite number.
    """

    roll_rad: float
    pitch_rad: float
    heading_rad: float

    def __post_init__(self):
        for name in ("roll_rad", "pitch_rad", "heading_rad"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)) or not np.isfinite(value):
                raise ValueError(f"attitude {name} must be a finite number of radians, got {value!r}")


def R_camera_from_level(attitude: Attitude, heading_reference_rad: float, camera: CameraModel) -> np.ndarray:
    """Rotation from the level frame L (x along ``heading_reference_rad``, z down) to the camera frame.

    Parameters
    ----------
    attitude : Attitude
        The body's roll, pitch and true heading relative to NED, radians.
    heading_reference_rad : float
        Heading of L's x axis, radians (the heading at the designation frame).
    camera : visland.camera.CameraModel
        Its mounting (body to camera, ``mount_rpy_rad``).

    Returns
    -------
    ndarray, shape (3, 3)
        ``R_C_from_L``: L coordinates to OpenCV camera coordinates (x right, y down, z forward).
    """
    return R_camera_from_runway(attitude.roll_rad, attitude.pitch_rad,
                                attitude.heading_rad - heading_reference_rad, camera.mount_rpy_rad)


def rotation_homography(R_cb_from_ca: np.ndarray, camera: CameraModel) -> np.ndarray:
    """Pixel homography ``K R K^-1`` of a pure camera rotation from frame a to frame b.

    Parameters
    ----------
    R_cb_from_ca : ndarray, shape (3, 3)
        Rotation from camera frame a (before) to camera frame b (after).
    camera : visland.camera.CameraModel
        Its intrinsic matrix ``K`` (pixels).

    Returns
    -------
    ndarray, shape (3, 3)
        Maps homogeneous pixels ``(u, v, 1)`` of frame a to those of frame b (SPEC pixel
        convention: (0, 0) at the centre of the top-left pixel, u right, v down).
    """
    K = camera.K
    return K @ R_cb_from_ca @ np.linalg.inv(K)


def virtual_to_pixel_homography(R_cam_from_level: np.ndarray, camera: CameraModel) -> np.ndarray:
    """``G = K R_C_from_L``: virtual ground coordinates ``(y_v1, y_v2)`` (thesis 3.23) to pixels.

    Parameters
    ----------
    R_cam_from_level : ndarray, shape (3, 3)
        Rotation from the level frame L to the camera frame (:func:`R_camera_from_level`).
    camera : visland.camera.CameraModel
        Its intrinsic matrix ``K`` (pixels).

    Returns
    -------
    ndarray, shape (3, 3)
        Maps homogeneous virtual coordinates ``(y_v1, y_v2, 1)`` to homogeneous pixels.
    """
    return camera.K @ R_cam_from_level
