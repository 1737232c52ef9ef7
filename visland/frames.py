"""Reference frames and rotations, each named by the frames it maps between.

Frames (SPEC.md "Conventions"; thesis section 1.1.1 and 3.2.2):

- ``R`` runway (thesis F_o): origin at the centre of the threshold line, x along the
  centreline in the landing direction, y to the right of x, z down. Runway surface z = 0.
- ``N`` North-East-Down. The runway frame is N turned by the runway heading ``psi_rwy``
  about the down axis; both share the origin (the threshold centre).
- ``B`` body: x forward, y right wing, z down. Attitude from N by ZYX Euler angles
  heading ``psi``, pitch ``theta``, roll ``phi``.
- ``C`` camera (OpenCV): x right in the image, y down in the image, z along the optical axis.
- ``V`` virtual (thesis 3.2.2): the runway axes carried to the camera centre; a point's
  coordinates in V are ``R_runway_from_camera @ p_C``.

Naming: ``R_a_from_b`` maps a vector expressed in frame b to frame a
(``v_a = R_a_from_b @ v_b``); ``p_runway_m`` is a position in R, in metres.
All angles are radians inside the code.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = [
    "rot_x",
    "rot_y",
    "rot_z",
    "R_ned_from_body",
    "euler_zyx_from_R_ned_from_body",
    "R_ned_from_runway",
    "R_body_from_camera",
    "R_camera_from_runway",
    "body_rates_from_euler_rates",
    "wrap_pi",
]

# Camera axes in body axes for a zero mounting rotation: image x along body y (right wing),
# image y along body z (down), optical axis along body x (forward). Columns are the camera
# axes expressed in the body frame.
_R_BODY_FROM_CAMERA_ZERO_MOUNT = np.array(
    [[0.0, 0.0, 1.0],
     [1.0, 0.0, 0.0],
     [0.0, 1.0, 0.0]]
)


def rot_x(angle_rad: float) -> np.ndarray:
    """Rotation matrix of a frame turned by ``angle_rad`` about x: ``R_parent_from_child``.

    Parameters
    ----------
    angle_rad : float
        Radians, positive turning y towards z (a roll to the right, for the body).

    Returns
    -------
    ndarray, shape (3, 3)
        Maps child-frame coordinates to parent-frame coordinates.
    """
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(angle_rad: float) -> np.ndarray:
    """Rotation matrix of a frame turned by ``angle_rad`` about y: ``R_parent_from_child``.

    Parameters
    ----------
    angle_rad : float
        Radians, positive turning z towards x (a pitch up, for the body).
    """
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(angle_rad: float) -> np.ndarray:
    """``R_parent_from_child`` of a frame turned by ``angle_rad`` about z (the heading's axis).

    Parameters
    ----------
    angle_rad : float
        Radians, positive turning x towards y (to the right, for NED and the body).

    Returns
    -------
    ndarray, shape (3, 3)
    """
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def R_ned_from_body(roll_rad: float, pitch_rad: float, heading_rad: float) -> np.ndarray:
    """Body-to-NED rotation from ZYX Euler angles (heading, then pitch, then roll).

    ``R_ned_from_body = Rz(heading) Ry(pitch) Rx(roll)``; the transpose is the thesis
    matrix 0R_c of eq. 3.17 (written there from the inertial frame to the body frame).
    The same function gives ``R_runway_from_body`` when called with the heading deviation
    ``dpsi = psi - psi_rwy`` instead of the true heading.

    Parameters
    ----------
    roll_rad, pitch_rad, heading_rad : float
        ZYX Euler angles of the body relative to NED, radians.

    Returns
    -------
    ndarray, shape (3, 3)
        ``R_ned_from_body``: body coordinates (x forward, y right wing, z down) to NED.
    """
    return rot_z(heading_rad) @ rot_y(pitch_rad) @ rot_x(roll_rad)


def euler_zyx_from_R_ned_from_body(R_ned_from_body_: np.ndarray) -> tuple[float, float, float]:
    """Inverse of :func:`R_ned_from_body`: ``(roll_rad, pitch_rad, heading_rad)``.

    Parameters
    ----------
    R_ned_from_body_ : array_like, shape (3, 3)
        A body-to-NED rotation.

    Returns
    -------
    roll_rad, pitch_rad, heading_rad : float
        Pitch in [-pi/2, pi/2]; roll and heading in (-pi, pi].

    Raises
    ------
    ValueError
        When the matrix is not 3x3.
    """
    R = np.asarray(R_ned_from_body_, dtype=float)
    if R.shape != (3, 3):
        raise ValueError(f"R_ned_from_body_ must be 3x3, got shape {R.shape}")
    pitch = -math.asin(max(-1.0, min(1.0, R[2, 0])))
    roll = math.atan2(R[2, 1], R[2, 2])
    heading = math.atan2(R[1, 0], R[0, 0])
    return roll, pitch, heading


def R_ned_from_runway(runway_heading_rad: float) -> np.ndarray:
    """Runway-to-NED rotation: the runway axes are NED turned by the runway heading.

    Parameters
    ----------
    runway_heading_rad : float
        True heading of the runway's x axis (landing direction), radians from north.

    Returns
    -------
    ndarray, shape (3, 3)
        ``R_ned_from_runway``.
    """
    return rot_z(runway_heading_rad)


def R_body_from_camera(mount_rpy_rad) -> np.ndarray:
    """Camera-to-body rotation for a camera mounted with attitude ``mount_rpy_rad``.

    ``mount_rpy_rad = [roll, pitch, yaw]`` is the camera's attitude relative to the body
    (ZYX: yaw, then pitch, then roll), as in SPEC.md ``camera.json``. ``[0, 0, 0]`` puts the
    optical axis along body x, image x along body y and image y along body z; a negative
    pitch looks down.

    Parameters
    ----------
    mount_rpy_rad : sequence of 3 floats
        The camera's roll, pitch and yaw relative to the body, radians.

    Returns
    -------
    ndarray, shape (3, 3)
        ``R_body_from_camera``: OpenCV camera coordinates (x right, y down, z forward) to body.
    """
    roll, pitch, yaw = (float(a) for a in mount_rpy_rad)
    R_body_from_mount = rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)
    return R_body_from_mount @ _R_BODY_FROM_CAMERA_ZERO_MOUNT


def R_camera_from_runway(roll_rad: float, pitch_rad: float, dpsi_rad: float,
                         mount_rpy_rad) -> np.ndarray:
    """Runway-to-camera rotation from the attitude relative to the runway and the mounting.

    ``R_camera_from_runway = R_body_from_camera^T R_runway_from_body^T`` with
    ``R_runway_from_body = Rz(dpsi) Ry(pitch) Rx(roll)``.

    Parameters
    ----------
    roll_rad, pitch_rad : float
        Body roll and pitch, radians.
    dpsi_rad : float
        Heading deviation ``psi - psi_rwy`` of the body from the runway axis, radians.
    mount_rpy_rad : sequence of 3 floats
        The camera's roll, pitch and yaw relative to the body, radians.

    Returns
    -------
    ndarray, shape (3, 3)
        ``R_camera_from_runway``: runway coordinates to OpenCV camera coordinates.
    """
    R_runway_from_body = R_ned_from_body(roll_rad, pitch_rad, dpsi_rad)
    return (R_runway_from_body @ R_body_from_camera(mount_rpy_rad)).T


def body_rates_from_euler_rates(roll_rad, pitch_rad, roll_rate, pitch_rate, heading_rate):
    """Body angular rates (p, q, r) from ZYX Euler angle rates.

    p = phi' - psi' sin(theta); q = theta' cos(phi) + psi' cos(theta) sin(phi);
    r = -theta' sin(phi) + psi' cos(theta) cos(phi). Works on scalars or arrays.

    Parameters
    ----------
    roll_rad, pitch_rad : float or ndarray
        Roll ``phi`` and pitch ``theta``, radians.
    roll_rate, pitch_rate, heading_rate : float or ndarray
        Euler angle rates ``phi'``, ``theta'``, ``psi'``, rad/s.

    Returns
    -------
    p, q, r : float or ndarray
        Body rates about body x, y, z, rad/s (the shape of the inputs).
    """
    sphi, cphi = np.sin(roll_rad), np.cos(roll_rad)
    sth, cth = np.sin(pitch_rad), np.cos(pitch_rad)
    p = roll_rate - heading_rate * sth
    q = pitch_rate * cphi + heading_rate * cth * sphi
    r = -pitch_rate * sphi + heading_rate * cth * cphi
    return p, q, r


def wrap_pi(angle_rad):
    """Wrap an angle (scalar or array) to [-pi, pi).

    Parameters
    ----------
    angle_rad : float or array_like
        Angle(s) in radians.

    Returns
    -------
    ndarray
        The same angle(s) in [-pi, pi) (a 0-d array for a scalar).
    """
    return (np.asarray(angle_rad) + np.pi) % (2.0 * np.pi) - np.pi
