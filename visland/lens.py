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
straight lines             with the field of view, ``k1`` alone from edges that are straight in the
                           world (field boundaries, roads, the horizon), bent by the lens: the
                           plumb-line method (Brown, Photogrammetric Engineering 37(8), 1971;
                           Devernay and Faugeras, Machine Vision and Applications 13, 2001,
                           doi:10.1007/PL00013269): Canny edges split at corners
                           (Douglas-Peucker), ``k1`` chosen so that the undistorted pieces are
                           straightest (golden-section search on the squared distances, in frame
                           pixels, of the points to their piece's total-least-squares line); pieces
                           whose own optimum lies at an end of the range, or that stay bent by
                           more than a fraction of a pixel, are dropped and the search repeated
=========================  ==================================================================

Pixels follow :mod:`visland.camera`: ``(0, 0)`` is the centre of the top-left pixel, the
convention of OpenCV's corner finder, so its ``cx, cy`` go to camera.json unchanged.

Limits of the straight-line path: one radial coefficient (``k2 = p1 = p2 = k3 = 0``), the
principal point at the centre and ``fx`` from the field of view guessed; edges curved in the
world (a curved glare shield, bends of roads) pull ``k1`` unless masked (``--mask``) or dropped
as the least straight; footage with few long edges far from the centre does not constrain it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from visland.camera import CameraModel
from visland.footage import FootageFrame, evenly_spaced

__all__ = ["BoardView", "ChessboardCalibration", "find_board_views", "calibrate_views", "parse_board",
           "MIN_VIEWS", "LineDistortion", "edge_pieces", "estimate_k1_from_lines", "undistort_radial_k1"]

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
    """``"9x6"`` to ``(9, 6)``: the board's inner corners (squares minus one) along each side.

    Parameters
    ----------
    text : str
        ``COLSxROWS`` (``*`` accepted for ``x``), at least 3 each, not square.

    Returns
    -------
    cols, rows : int

    Raises
    ------
    ValueError
        Naming ``--board`` and what is wrong.
    """
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


# ----------------------------------------------------------------------------- straight lines
@dataclass(frozen=True)
class LineDistortion:
    """Result of :func:`estimate_k1_from_lines`.

    Attributes
    ----------
    k1 : float
        Radial coefficient (OpenCV's model with ``k2 = p1 = p2 = k3 = 0``).
    pieces : int
        Straight edge pieces the final fit used.
    straightness_before_px, straightness_after_px : float
        RMS distance of the pieces' points to their own lines with ``k1 = 0`` and with ``k1``,
        pixels of the frame.
    frames : int
        Frames the pieces came from.
    """

    k1: float
    pieces: int
    straightness_before_px: float
    straightness_after_px: float
    frames: int


def _split_douglas_peucker(points: np.ndarray, tolerance_px: float) -> list[tuple[int, int]]:
    """Index ranges ``[i, j]`` of the pieces of a polyline within ``tolerance_px`` of their chord."""
    ranges, stack = [], [(0, len(points) - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            ranges.append((i, j))
            continue
        a, b = points[i], points[j]
        chord = b - a
        length = float(np.hypot(*chord))
        inner = points[i + 1:j] - a
        if length < 1e-9:
            distance = np.hypot(inner[:, 0], inner[:, 1])
        else:
            distance = np.abs(chord[0] * inner[:, 1] - chord[1] * inner[:, 0]) / length
        k = int(np.argmax(distance))
        if distance[k] > tolerance_px:
            stack.append((i, i + 1 + k))
            stack.append((i + 1 + k, j))
        else:
            ranges.append((i, j))
    return ranges


def edge_pieces(grey: np.ndarray, min_length_px: float, tolerance_px: float, ignore=None) -> list[np.ndarray]:
    """Nearly straight edge pieces of a grey frame: Canny edges, split at corners.

    Parameters
    ----------
    grey : ndarray, shape (H, W), uint8
    min_length_px : float
        Shortest piece kept (chord length, pixels).
    tolerance_px : float
        Douglas-Peucker tolerance: a piece bends at most this far from its chord (it must allow
        the lens's bending of a straight line).
    ignore : ndarray of bool, shape (H, W), optional
        Pixels whose edges are not used (the aircraft's structure).

    Returns
    -------
    list of ndarray, shape (N, 2)
        Pixel coordinates ``(u, v)`` of each piece's edge points (distorted frame).
    """
    import cv2  # heavy import kept local: the core must start fast
    blurred = cv2.GaussianBlur(grey, (0, 0), 1.0)
    median = float(np.median(blurred))
    edges = cv2.Canny(blurred, max(10.0, 0.33 * median), max(30.0, 0.66 * median))
    if ignore is not None:
        edges[cv2.dilate(ignore.astype(np.uint8), np.ones((7, 7), np.uint8)) > 0] = 0
    height, width = grey.shape
    edges[:2] = edges[-2:] = 0
    edges[:, :2] = edges[:, -2:] = 0
    contours, _ = cv2.findContours(edges, cv2.RETR_LIST, cv2.CHAIN_APPROX_NONE)
    # sub-pixel edge positions: the gradient magnitude's peak across the edge (parabola through 3 samples)
    g = blurred.astype(np.float32)
    gu = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3)
    gv = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3)
    magnitude = np.hypot(gu, gv)
    pieces = []
    for contour in contours:
        points = contour.reshape(-1, 2)
        if len(points) < min_length_px:
            continue
        u, v = points[:, 0], points[:, 1]
        nu, nv = gu[v, u], gv[v, u]
        norm = np.maximum(np.hypot(nu, nv), 1e-6)
        nu, nv = nu / norm, nv / norm
        centre = magnitude[v, u]
        ahead = cv2.remap(magnitude, (u + nu).astype(np.float32)[None], (v + nv).astype(np.float32)[None],
                          cv2.INTER_LINEAR)[0]
        behind = cv2.remap(magnitude, (u - nu).astype(np.float32)[None], (v - nv).astype(np.float32)[None],
                           cv2.INTER_LINEAR)[0]
        curvature = ahead - 2.0 * centre + behind
        offset = np.where(curvature < 0, 0.5 * (behind - ahead) / np.where(curvature < 0, curvature, -1.0), 0.0)
        offset = np.clip(offset, -0.5, 0.5)
        refined = np.stack([u + offset * nu, v + offset * nv], axis=1)
        coarse = points.astype(float)
        for i, j in _split_douglas_peucker(coarse, tolerance_px):
            if np.hypot(*(coarse[j] - coarse[i])) >= min_length_px:
                trim = max(2, (j - i) // 20)        # ends round off into corners and junctions
                if j - i > 2 * trim + 3:
                    pieces.append(refined[i + trim:j + 1 - trim])
    return pieces


def undistort_radial_k1(xy_distorted: np.ndarray, k1: float) -> np.ndarray:
    """Inverse of ``x_d = x (1 + k1 r^2)`` on normalised coordinates (Newton on r, 20 steps).

    Parameters
    ----------
    xy_distorted : array_like, shape (..., 2)
        Distorted normalised coordinates ``((u - cx)/fx, (v - cy)/fy)``.
    k1 : float
        First radial coefficient (negative: barrel).

    Returns
    -------
    ndarray, shape (..., 2)
        Undistorted normalised coordinates; NaN where there is no inverse (beyond the fold of a
        strong barrel lens).
    """
    xy_distorted = np.asarray(xy_distorted, dtype=float)
    r_d = np.hypot(xy_distorted[..., 0], xy_distorted[..., 1])
    r = r_d.copy()
    for _ in range(20):
        f = r * (1.0 + k1 * r * r) - r_d
        df = 1.0 + 3.0 * k1 * r * r
        r = r - f / np.where(np.abs(df) < 1e-9, 1e-9, df)
    ok = (np.abs(r * (1.0 + k1 * r * r) - r_d) < 1e-9) & (1.0 + 3.0 * k1 * r * r > 0) & (r >= 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(r_d > 1e-12, r / r_d, 1.0)
    return np.where(ok[..., None], xy_distorted * scale[..., None], np.nan)


class _Pieces:
    """Edge pieces in normalised coordinates, stacked for vectorised per-piece line fits."""

    def __init__(self, pieces_xy: list[np.ndarray]):
        self.xy = np.concatenate(pieces_xy)
        self.index = np.repeat(np.arange(len(pieces_xy)), [len(p) for p in pieces_xy])
        self.count = np.bincount(self.index).astype(float)
        self.n = len(pieces_xy)


def _straightness(pieces: _Pieces, k1: float) -> np.ndarray:
    """Per piece: mean squared distance of its points to its line, measured in the frame.

    The line is fitted (total least squares) to the undistorted points; each point's distance
    to it is brought back to the frame by the undistortion's magnification across the line
    (radially ``dr_u/dr_d``, tangentially ``r_u/r_d``). Measured in the undistorted image
    instead, a barrel correction, which stretches the border, would be rewarded or penalised
    for the stretching itself. Normalised units (times ``fx^2`` for pixels^2).
    """
    p = undistort_radial_k1(pieces.xy, k1)
    idx, n = pieces.index, pieces.n
    sums = [np.bincount(idx, w, n) for w in (p[:, 0], p[:, 1], p[:, 0] ** 2, p[:, 1] ** 2, p[:, 0] * p[:, 1])]
    mx, my, sxx, syy, sxy = (s_ / pieces.count for s_ in sums)
    a, b, c = sxx - mx * mx, syy - my * my, sxy - mx * my
    smallest = (a + b) / 2.0 - np.sqrt(((a - b) / 2.0) ** 2 + c * c)
    # normal of each piece's line: eigenvector of the smallest eigenvalue
    n1 = np.stack([c, smallest - a], axis=1)
    n2 = np.stack([smallest - b, c], axis=1)
    normal = np.where((np.hypot(*n1.T) >= np.hypot(*n2.T))[:, None], n1, n2)
    normal /= np.maximum(np.hypot(*normal.T), 1e-300)[:, None]
    distance = (p[:, 0] - mx[idx]) * normal[idx, 0] + (p[:, 1] - my[idx]) * normal[idx, 1]
    r_u = np.hypot(p[:, 0], p[:, 1])
    r_d = np.hypot(pieces.xy[:, 0], pieces.xy[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        tangential = np.where(r_d > 1e-12, r_u / r_d, 1.0)
        radial = 1.0 / (1.0 + 3.0 * k1 * r_u * r_u)
        cos_phi = np.where(r_u > 1e-12, (p[:, 0] * normal[idx, 0] + p[:, 1] * normal[idx, 1]) / r_u, 0.0)
    magnification = np.sqrt((radial * cos_phi) ** 2 + (tangential ** 2) * (1.0 - cos_phi ** 2))
    cost = np.bincount(idx, (distance / magnification) ** 2, n) / pieces.count
    return np.where(np.isfinite(cost), cost, np.inf)


def _golden_minimum(f, low: float, high: float, iterations: int = 40) -> float:
    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = low, high
    c, d = b - ratio * (b - a), a + ratio * (b - a)
    fc, fd = f(c), f(d)
    for _ in range(iterations):
        if fc < fd:
            b, d, fd = d, c, fc
            c = b - ratio * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, d, fd
            d = a + ratio * (b - a)
            fd = f(d)
    return (a + b) / 2.0


def estimate_k1_from_lines(frames: list[np.ndarray], fx: float, fy: float, cx: float, cy: float, ignore=None,
                           k1_range=(-0.5, 0.3)) -> LineDistortion:
    """``k1`` that makes the straight edges of the frames straightest (plumb-line method).

    Parameters
    ----------
    frames : list of ndarray, shape (H, W), uint8
        Grey frames (spread over the footage: more, and more varied, straight edges).
    fx, fy, cx, cy : float
        Intrinsics assumed (pixels; e.g. from the field of view).
    ignore : ndarray of bool, shape (H, W), optional
        The aircraft's structure (its edges are not used).
    k1_range : (float, float)
        Interval searched.
    """
    if not frames:
        raise ValueError("no frames to find straight edges in")
    height, width = frames[0].shape[:2]
    min_length = 0.12 * min(width, height)
    tolerance = 0.005 * max(width, height)
    pieces_px = []
    for grey in frames:
        pieces_px.extend(edge_pieces(grey, min_length, tolerance, ignore))
    # pieces near the centre say nothing about the radial term; keep those reaching a third out
    radius = np.hypot(width / 2.0, height / 2.0)
    pieces_px = [p for p in pieces_px if np.hypot(p[:, 0] - cx, p[:, 1] - cy).max() > radius / 3.0]
    if len(pieces_px) < 10:
        raise ValueError(f"only {len(pieces_px)} long straight edge pieces found in {len(frames)} frames (at least 10 "
                         f"needed, away from the image centre): the lens cannot be estimated from lines here")
    pieces_xy = [np.stack([(p[:, 0] - cx) / fx, (p[:, 1] - cy) / fy], axis=1) for p in pieces_px]
    every = _Pieces(pieces_xy)
    # a straight line in the world is straightest at some k1 inside the range: a piece whose own
    # optimum sits at an end (a shallow corner, two edges merged, a curve) is not one
    grid = np.linspace(k1_range[0], k1_range[1], 15)
    own = grid[np.argmin(np.stack([_straightness(every, k) for k in grid]), axis=0)]
    keep = (own > grid[0]) & (own < grid[-1])
    k1 = 0.0
    for _ in range(3):
        if keep.sum() < 10:
            break
        chosen = _Pieces([p for p, k in zip(pieces_xy, keep) if k])
        k1 = _golden_minimum(lambda k: float(np.sum(_straightness(chosen, k) * chosen.count)), *k1_range)
        # pieces not straight to a fraction of a pixel at k1 (curved in the world, two edges merged) go
        distance_px = fx * np.sqrt(_straightness(every, k1))
        keep &= distance_px <= max(0.35, 2.5 * float(np.median(distance_px[keep])))
    if keep.sum() < 10:
        raise ValueError(f"only {int(keep.sum())} of the {len(pieces_xy)} edge pieces found in {len(frames)} frames "
                         f"are straight at a plausible k1 (at least 10 needed): the lens cannot be estimated from "
                         f"lines here")
    if abs(k1 - k1_range[0]) < 1e-3 or abs(k1 - k1_range[1]) < 1e-3:
        raise ValueError(f"the straightest edges call for k1 at the end of the searched range ({k1:.3f}): edges "
                         f"curved in the world dominate, or the field of view is far off")

    def rms_px(k):
        squared = _straightness(every, k) * every.count
        return fx * math.sqrt(float(np.sum(squared[keep]) / np.sum(every.count[keep])))

    return LineDistortion(k1=float(k1), pieces=int(keep.sum()), straightness_before_px=rms_px(0.0),
                          straightness_after_px=rms_px(k1), frames=len(frames))
