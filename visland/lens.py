"""Lens calibration: the intrinsics and distortion of camera.json from chessboard footage.

=========================  ==================================================================
step                       what and where
=========================  ==================================================================
board views                ``cv2.findChessboardCorners`` on frames sampled evenly over the
                           footage, refined by ``cv2.cornerSubPix`` (gradient-orthogonality
                           saddle point, window scaled to the corner spacing)
view selection             at most ``max_views`` of the frames showing the board, spread evenly
                           over the footage (neighbouring video frames add little)
calibration                ``cv2.calibrateCamera``: Zhang's planar method (IEEE TPAMI 22(11),
                           2000, doi:10.1109/34.888718) refined by Levenberg-Marquardt on the
                           reprojection error, with OpenCV's radial-tangential model
                           ``(k1, k2, p1, p2, k3)`` (:meth:`visland.camera.CameraModel.distort_normalized`)
field of view              no calibration at all: ``fx = fy = (W / 2) / tan(hfov / 2)``, principal
                           point at the centre, no distortion (:meth:`CameraModel.from_fov`)
=========================  ==================================================================

Pixels follow :mod:`visland.camera`: ``(0, 0)`` is the centre of the top-left pixel, the
convention of OpenCV's corner finder, so its ``cx, cy`` go to camera.json unchanged.

Limit: distortion is not estimated from straight lines of the scene (horizon, runway edges) on
uncalibrated footage; ``--hfov-deg`` writes a pinhole camera, and a wide-angle lens's barrel
distortion then bends lines by several pixels towards the image border.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from visland.camera import CameraModel
from visland.footage import FootageFrame, evenly_spaced

__all__ = ["BoardView", "ChessboardCalibration", "find_board_views", "calibrate_views", "parse_board",
           "MIN_VIEWS"]

#: Fewest board views accepted. Each view of a plane gives two constraints on the intrinsics
#: (Zhang 2000); four intrinsics and five distortion coefficients from fewer than five distinct
#: poses are at the mercy of noise. OpenCV's guide recommends 10-20 or more.
MIN_VIEWS = 5


@dataclass(frozen=True)
class BoardView:
    """The inner corners of the board found in one frame.

    Attributes
    ----------
    frame : FootageFrame
        Where they were found.
    corners_px : ndarray, shape (N, 2)
        Sub-pixel corner positions, in OpenCV's order (row by row along the first board size).
    """

    frame: FootageFrame
    corners_px: np.ndarray


@dataclass(frozen=True)
class ChessboardCalibration:
    """Result of :func:`calibrate_views`.

    Attributes
    ----------
    camera : CameraModel
        Intrinsics, distortion ``(k1, k2, p1, p2, k3)`` and the mounting given.
    rms_px : float
        Root mean square reprojection error over every corner of every view used, pixels.
    views_used : int
        Board views the calibration used.
    view_rms_px : ndarray, shape (views_used,)
        Reprojection error of each view, pixels.
    view_names : tuple of str
        The frame of each view used.
    """

    camera: CameraModel
    rms_px: float
    views_used: int
    view_rms_px: np.ndarray
    view_names: tuple

    def summary_lines(self) -> list[str]:
        c = self.camera
        worst = int(np.argmax(self.view_rms_px))
        k1, k2, p1, p2, k3 = c.distortion
        return [f"views used: {self.views_used}; RMS reprojection error {self.rms_px:.3f} px "
                f"(worst view {self.view_names[worst]}: {self.view_rms_px[worst]:.3f} px)",
                f"fx {c.fx:.2f} px, fy {c.fy:.2f} px, cx {c.cx:.2f} px, cy {c.cy:.2f} px "
                f"({c.width}x{c.height}, horizontal field of view {c.hfov_deg:.2f} deg)",
                f"distortion k1 {k1:.5f}, k2 {k2:.5f}, p1 {p1:.6f}, p2 {p2:.6f}, k3 {k3:.5f}"]


def parse_board(text: str) -> tuple[int, int]:
    """``"9x6"`` to ``(9, 6)``: the board's inner corners (squares minus one) along each side."""
    parts = text.lower().replace("*", "x").split("x")
    try:
        cols, rows = (int(p) for p in parts)
    except ValueError:
        raise ValueError(f"--board must be the inner corners as COLSxROWS, e.g. 9x6, got {text!r}") from None
    if cols < 3 or rows < 3:
        raise ValueError(f"--board needs at least 3x3 inner corners, got {text!r}")
    if cols == rows:
        # a square grid has no defined first corner: views could be numbered 90 deg apart
        raise ValueError(f"--board {text}: a board with as many inner corners along both sides is ambiguous "
                         f"to OpenCV's corner ordering; use a board such as 9x6")
    return cols, rows


def _subpixel_window(corners_px: np.ndarray, board: tuple[int, int]) -> int:
    """Half-size of cornerSubPix's search window: under half the smallest corner spacing, at most 11."""
    grid = corners_px.reshape(board[1], board[0], 2)
    along = np.linalg.norm(np.diff(grid, axis=1), axis=2).min()
    across = np.linalg.norm(np.diff(grid, axis=0), axis=2).min()
    return int(max(2, min(11, math.floor(0.4 * min(along, across)))))


def find_board_views(frames: list[FootageFrame], board: tuple[int, int]) -> list[BoardView]:
    """The frames in which the whole chessboard is found, with sub-pixel corners.

    Parameters
    ----------
    frames : list of FootageFrame
        Grey frames (colour ones are converted).
    board : (int, int)
        Inner corners ``(columns, rows)``.
    """
    import cv2  # heavy import kept local: the core must start fast
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_FAST_CHECK
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-3)
    views = []
    for frame in frames:
        grey = frame.image if frame.image.ndim == 2 else cv2.cvtColor(frame.image, cv2.COLOR_RGB2GRAY)
        found, corners = cv2.findChessboardCorners(grey, board, flags=flags)
        if not found or corners is None or len(corners) != board[0] * board[1]:
            continue
        corners = corners.astype(np.float32)
        half = _subpixel_window(corners.reshape(-1, 2), board)
        corners = cv2.cornerSubPix(grey, corners, (half, half), (-1, -1), criteria)
        views.append(BoardView(frame, corners.reshape(-1, 2).astype(float)))
    return views


def calibrate_views(views: list[BoardView], board: tuple[int, int], square_m: float, image_size: tuple[int, int],
                    max_views: int = 40, mount_rpy_deg=(0.0, 0.0, 0.0)) -> ChessboardCalibration:
    """OpenCV's chessboard calibration on at most ``max_views`` views spread over the footage.

    Parameters
    ----------
    views : list of BoardView
        From :func:`find_board_views`, in footage order.
    board : (int, int)
        Inner corners ``(columns, rows)``.
    square_m : float
        Side of a square, metres (sets the scale of the board poses only; the intrinsics do not
        depend on it).
    image_size : (int, int)
        ``(width, height)`` of the frames, pixels.
    max_views : int
        Most views used, taken evenly from ``views``.
    mount_rpy_deg : 3 floats
        Mounting written to camera.json (roll, pitch, yaw in degrees; ZYX, SPEC).
    """
    import cv2  # heavy import kept local: the core must start fast
    if not (math.isfinite(square_m) and square_m > 0):
        raise ValueError(f"--square-mm must be a positive size, got {square_m * 1000:g} mm")
    if max_views < MIN_VIEWS:
        raise ValueError(f"--max-views must be at least {MIN_VIEWS}, got {max_views}")
    if len(views) < MIN_VIEWS:
        raise ValueError(f"the board was found in only {len(views)} frame(s); at least {MIN_VIEWS} views at "
                         f"varied angles are needed (15-40 covering the whole image are best)")
    chosen = [views[i] for i in evenly_spaced(len(views), max_views)]
    cols, rows = board
    # board frame: x along the columns, y along the rows, z = 0 on the board (metres)
    p_board_m = np.zeros((rows * cols, 3), np.float32)
    p_board_m[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * square_m
    object_points = [p_board_m] * len(chosen)
    image_points = [v.corners_px.astype(np.float32).reshape(-1, 1, 2) for v in chosen]
    width, height = image_size
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-9)
    rms, K, dist, rvecs, tvecs = cv2.calibrateCamera(object_points, image_points, (width, height), None, None,
                                                     criteria=criteria)
    dist = np.asarray(dist, dtype=float).ravel()
    coefficients = tuple(float(c) for c in (list(dist[:5]) + [0.0] * 5)[:5])
    view_rms = []
    for p_img, rvec, tvec in zip(image_points, rvecs, tvecs):
        projected, _ = cv2.projectPoints(p_board_m, rvec, tvec, K, dist)
        view_rms.append(float(np.sqrt(np.mean(np.sum((projected - p_img) ** 2, axis=2)))))
    try:
        camera = CameraModel(int(width), int(height), float(K[0, 0]), float(K[1, 1]), float(K[0, 2]),
                             float(K[1, 2]), tuple(math.radians(a) for a in mount_rpy_deg), coefficients)
    except ValueError as error:
        raise ValueError(f"the calibration from {len(chosen)} views is not a plausible lens ({error}); the views "
                         f"probably do not constrain it: film the board at varied tilts, reaching the image "
                         f"corners") from None
    return ChessboardCalibration(camera=camera, rms_px=float(rms), views_used=len(chosen),
                                 view_rms_px=np.array(view_rms), view_names=tuple(v.frame.name for v in chosen))
