"""Pinhole camera model and the image conventions every visland stage uses.

Conventions (stated once here; SPEC.md "Conventions"):

- Camera frame C (OpenCV): x right, y down, z along the optical axis.
- Pixels ``(u, v)``: u to the right, v down; ``(0, 0)`` is the *centre* of the top-left
  pixel (OpenCV). The image covers ``-0.5 <= u <= width - 0.5``.
- Intrinsics ``fx, fy, cx, cy``; default 2048x2048, fx = fy = 2472 px (45 deg field of
  view), cx = cy = 1023.5 (scaled with the image size for other sizes).
- Normalised coordinates ``x = (u - cx) / fx``, ``y = (v - cy) / fy`` (thesis focal f = 1).
- Lines ``(rho, theta)``: ``x cos(theta) + y sin(theta) = rho`` in normalised coordinates
  (thesis eq. 3.34). Chart: ``theta`` in ``[-pi/2, pi/2)``, ``rho`` signed. A line whose
  normal would leave the chart is written ``(-rho, theta -+ pi)``; runway edges and centre
  line are near-vertical in the image, so their ``theta`` stays near 0, far from the wrap.
  Pixel-space Hough lines ``u cos(t) + v sin(t) = r`` are converted at the boundary with
  :meth:`CameraModel.line_from_pixel_hough` / :meth:`CameraModel.line_to_pixel_hough`.
- Lens distortion (optional, ``camera.json`` ``"distortion": [k1, k2, p1, p2, k3]``): OpenCV's
  radial-tangential model. Every feature visland reads or writes (labels, measurements, lines,
  d_F) is in the *undistorted* pinhole image of the same ``fx, fy, cx, cy``: a distorted pixel
  ``(u_d, v_d)`` of a frame corresponds to the pinhole pixel :meth:`CameraModel.undistort_pixels`
  gives, and a frame is turned into its pinhole image with :meth:`CameraModel.undistortion_maps`
  (for ``cv2.remap``). Without distortion the two images are the same.
- The aircraft's own structure (optional, ``camera.json`` ``"mask"``): the pixels of the frame
  *as taken* that show the windshield frame, a wiper, the nose or a reflection and must never
  be read as scene. Either polygons ``[[[u, v], ...], ...]`` in pixels, or the name of an image
  file beside ``camera.json`` (same size as the frames; non-zero = structure), such as the one
  ``visland mask`` proposes. :meth:`CameraModel.structure_mask` gives it as a boolean image.
"""
from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from visland.frames import R_body_from_camera

__all__ = [
    "CameraModel",
    "DEFAULT_IMAGE_SIZE",
    "DEFAULT_FOCAL_PX",
    "DEFAULT_MOUNT_RPY_DEG",
    "wrap_line_chart",
    "line_through_points",
    "intersect_lines",
    "DISTORTION_NAMES",
]

#: OpenCV's order of the radial-tangential distortion coefficients in ``camera.json``.
DISTORTION_NAMES = ("k1", "k2", "p1", "p2", "k3")

DEFAULT_IMAGE_SIZE = 2048
DEFAULT_FOCAL_PX = 2472.0
# Optical axis along body x, pitched down 3 deg: keeps the runway, from 6 km out in level
# flight to 50 ft on the glide path, inside the 45 deg field of view.
DEFAULT_MOUNT_RPY_DEG = (0.0, -3.0, 0.0)


@dataclass(frozen=True)
class CameraModel:
    """Pinhole camera: image size, intrinsics and mounting on the body.

    Parameters
    ----------
    width, height : int
        Image size in pixels.
    fx, fy : float
        Focal lengths in pixels.
    cx, cy : float
        Principal point in pixels (pixel-centre convention, see module docstring).
    mount_rpy_rad : tuple of 3 float
        Camera attitude relative to the body, ``(roll, pitch, yaw)`` applied ZYX;
        ``(0, 0, 0)`` looks along body x, negative pitch looks down.
    distortion : tuple of 5 float or None
        OpenCV radial-tangential coefficients ``(k1, k2, p1, p2, k3)`` of the lens, or None for
        a pinhole lens. Features are always expressed in the undistorted pinhole image (module
        docstring).
    mask : tuple of polygons, str or None
        The aircraft's own structure in the frame as taken (module docstring): polygons, each a
        tuple of at least 3 ``(u, v)`` pixel vertices, or the absolute path of a mask image
        (non-zero = structure). None: nothing masked.
    """

    width: int = DEFAULT_IMAGE_SIZE
    height: int = DEFAULT_IMAGE_SIZE
    fx: float = DEFAULT_FOCAL_PX
    fy: float = DEFAULT_FOCAL_PX
    cx: float = (DEFAULT_IMAGE_SIZE - 1) / 2.0
    cy: float = (DEFAULT_IMAGE_SIZE - 1) / 2.0
    mount_rpy_rad: tuple = field(
        default=tuple(math.radians(a) for a in DEFAULT_MOUNT_RPY_DEG))
    distortion: tuple | None = None
    mask: tuple | str | None = None

    def __post_init__(self):
        for name in ("width", "height"):
            value = getattr(self, name)
            if not isinstance(value, (int, np.integer)) or isinstance(value, bool) or value < 16:
                raise ValueError(f"camera {name} must be an integer of at least 16 px, got {value!r}")
        for name in ("fx", "fy"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float, np.floating)) and math.isfinite(value) and value > 0):
                raise ValueError(f"camera {name} must be a positive finite number of pixels, got {value!r}")
        if not (math.isfinite(self.cx) and -0.5 <= self.cx <= self.width - 0.5):
            raise ValueError(f"camera cx must lie inside the image width, got {self.cx!r}")
        if not (math.isfinite(self.cy) and -0.5 <= self.cy <= self.height - 0.5):
            raise ValueError(f"camera cy must lie inside the image height, got {self.cy!r}")
        mount = tuple(float(a) for a in self.mount_rpy_rad)
        if len(mount) != 3 or not all(math.isfinite(a) and abs(a) <= math.pi for a in mount):
            raise ValueError(f"camera mount_rpy_rad must be 3 finite angles within +-pi, got {self.mount_rpy_rad!r}")
        object.__setattr__(self, "mount_rpy_rad", mount)
        object.__setattr__(self, "distortion", _checked_distortion(self.distortion, "camera distortion"))
        object.__setattr__(self, "mask", _checked_mask(self.mask, "camera mask"))
        object.__setattr__(self, "width", int(self.width))
        object.__setattr__(self, "height", int(self.height))
        object.__setattr__(self, "fx", float(self.fx))
        object.__setattr__(self, "fy", float(self.fy))
        object.__setattr__(self, "cx", float(self.cx))
        object.__setattr__(self, "cy", float(self.cy))

    # ----------------------------------------------------------------- construction
    @classmethod
    def default(cls, size: int = DEFAULT_IMAGE_SIZE, mount_rpy_deg=DEFAULT_MOUNT_RPY_DEG) -> "CameraModel":
        """The SPEC camera (45 deg field of view) at a square image ``size``."""
        if not isinstance(size, (int, np.integer)) or size < 16:
            raise ValueError(f"size must be an integer of at least 16 px, got {size!r}")
        focal = DEFAULT_FOCAL_PX * size / DEFAULT_IMAGE_SIZE
        centre = (size - 1) / 2.0
        return cls(int(size), int(size), focal, focal, centre, centre,
                   tuple(math.radians(a) for a in mount_rpy_deg))

    @classmethod
    def from_fov(cls, width: int, height: int, hfov_deg: float,
                 mount_rpy_deg=DEFAULT_MOUNT_RPY_DEG, distortion=None, mask=None) -> "CameraModel":
        """Square-pixel camera of a horizontal field of view ``hfov_deg`` (any frame shape).

        ``fx = fy = (width / 2) / tan(hfov / 2)``, principal point at the image centre.
        """
        if not (isinstance(hfov_deg, (int, float)) and math.isfinite(hfov_deg) and 1.0 <= hfov_deg <= 170.0):
            raise ValueError(f"hfov_deg must be a field of view between 1 and 170 deg, got {hfov_deg!r}")
        for name, value in (("width", width), ("height", height)):
            if not isinstance(value, (int, np.integer)) or isinstance(value, bool) or value < 16:
                raise ValueError(f"{name} must be an integer of at least 16 px, got {value!r}")
        focal = (width / 2.0) / math.tan(math.radians(hfov_deg) / 2.0)
        return cls(int(width), int(height), focal, focal, (width - 1) / 2.0, (height - 1) / 2.0,
                   tuple(math.radians(a) for a in mount_rpy_deg), distortion, mask)

    def with_mount(self, mount_rpy_rad) -> "CameraModel":
        """Same intrinsics and lens, another mounting (e.g. to apply a calibration error)."""
        return replace(self, mount_rpy_rad=tuple(mount_rpy_rad))

    def without_distortion(self) -> "CameraModel":
        """The pinhole camera of the same intrinsics: the image features are expressed in."""
        return replace(self, distortion=None)

    @property
    def has_distortion(self) -> bool:
        return self.distortion is not None and any(c != 0.0 for c in self.distortion)

    @property
    def hfov_deg(self) -> float:
        """Horizontal field of view of the pinhole image, degrees."""
        return math.degrees(math.atan((self.cx + 0.5) / self.fx) + math.atan((self.width - 0.5 - self.cx) / self.fx))

    @property
    def mount_rpy_deg(self) -> tuple:
        return tuple(math.degrees(a) for a in self.mount_rpy_rad)

    @property
    def K(self) -> np.ndarray:
        """3x3 intrinsic matrix."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def R_body_from_camera(self) -> np.ndarray:
        return R_body_from_camera(self.mount_rpy_rad)

    # ----------------------------------------------------------------- JSON
    def to_json_dict(self) -> dict:
        """The ``camera.json`` content of SPEC.md (angles in degrees; ``distortion`` if any)."""
        data = {"width": self.width, "height": self.height, "fx": self.fx, "fy": self.fy,
                "cx": self.cx, "cy": self.cy, "mount_rpy_deg": list(self.mount_rpy_deg)}
        if self.distortion is not None:
            data["distortion"] = list(self.distortion)
        if isinstance(self.mask, str):
            data["mask"] = self.mask
        elif self.mask is not None:
            data["mask"] = [[list(vertex) for vertex in polygon] for polygon in self.mask]
        return data

    @classmethod
    def from_json_dict(cls, data: dict, source: str = "camera.json", base_dir=None) -> "CameraModel":
        """Build from a ``camera.json`` dictionary; one clear error per missing/bad field.

        A mask image named in ``data["mask"]`` is looked for relative to ``base_dir`` (the
        folder of the ``camera.json``; default the working directory) and checked now: it
        must be readable, of the camera's size, and leave part of the image unmasked.
        """
        if not isinstance(data, dict):
            raise ValueError(f"{source}: expected a JSON object, got {type(data).__name__}")
        required = ("width", "height", "fx", "fy", "cx", "cy", "mount_rpy_deg")
        for key in required:
            if key not in data:
                raise ValueError(f"{source}: missing field '{key}' (needed: {', '.join(required)})")
        for key in ("width", "height"):
            value = data[key]
            if isinstance(value, bool) or not isinstance(value, (int, float)) or int(value) != value:
                raise ValueError(f"{source}: field '{key}' must be an integer, got {value!r}")
        for key in ("fx", "fy", "cx", "cy"):
            value = data[key]
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError(f"{source}: field '{key}' must be a finite number, got {value!r}")
        mount = data["mount_rpy_deg"]
        if (not isinstance(mount, (list, tuple)) or len(mount) != 3
                or not all(isinstance(a, (int, float)) and not isinstance(a, bool) and math.isfinite(a)
                           for a in mount)):
            raise ValueError(f"{source}: field 'mount_rpy_deg' must be a list of 3 numbers [roll, pitch, yaw], got {mount!r}")
        distortion = data.get("distortion")
        if distortion is not None:
            distortion = _checked_distortion(distortion, f"{source}: field 'distortion'")
        mask = data.get("mask")
        if isinstance(mask, str):
            mask_path = Path(mask) if Path(mask).is_absolute() else Path(base_dir or ".") / mask
            mask = str(mask_path.resolve())
        elif mask is not None:
            mask = _checked_mask(mask, f"{source}: field 'mask'")
        try:
            camera = cls(int(data["width"]), int(data["height"]), float(data["fx"]), float(data["fy"]),
                         float(data["cx"]), float(data["cy"]), tuple(math.radians(a) for a in mount),
                         distortion, mask)
        except ValueError as error:
            raise ValueError(f"{source}: {error}") from None
        if camera.mask is not None:
            try:
                camera.structure_mask()
            except ValueError as error:
                raise ValueError(f"{source}: field 'mask': {error}") from None
        return camera

    def save(self, path) -> None:
        Path(path).write_text(json.dumps(self.to_json_dict(), indent=2) + "\n")

    @classmethod
    def load(cls, path) -> "CameraModel":
        """The camera of a ``camera.json`` file (SPEC contract); a ``ValueError`` in one sentence
        naming the file and the field (:meth:`from_json_dict`), or saying the file is missing,
        unreadable or not a JSON object.

        Parameters
        ----------
        path : str or pathlib.Path
            The file; a mask image it names is looked for beside it.
        """
        from visland.userfiles import read_json_object    # a byte-order mark, a folder, a list: one sentence
        path = Path(path)
        return cls.from_json_dict(read_json_object(path, "camera file"), source=str(path), base_dir=path.parent)

    @classmethod
    def for_input(cls, camera, folder) -> "CameraModel":
        """The camera of a frame folder or video: the one every reader of an input uses.

        Parameters
        ----------
        camera : CameraModel or str or pathlib.Path or None
            A camera already built (returned as it is), the camera.json a command was given
            (``--camera``), or None for the input's own.
        folder : str or pathlib.Path
            Where the input's own ``camera.json`` lies (the frame folder, or a video's folder).

        Returns
        -------
        CameraModel

        Raises
        ------
        ValueError
            ``"<path>: camera file not found (give --camera FILE)"``, or :meth:`load`'s sentence.
        """
        if isinstance(camera, cls):
            return camera
        path = Path(camera) if camera else Path(folder) / "camera.json"
        if not path.exists():
            raise ValueError(f"{path}: camera file not found (give --camera FILE)")
        return cls.load(path)

    # ----------------------------------------------------------------- points
    def normalized_to_pixels(self, xy) -> np.ndarray:
        """Normalised coordinates ``(..., 2)`` to pixels ``(..., 2)``."""
        xy = np.asarray(xy, dtype=float)
        return np.stack([self.fx * xy[..., 0] + self.cx, self.fy * xy[..., 1] + self.cy], axis=-1)

    def pixels_to_normalized(self, uv) -> np.ndarray:
        """Pixels ``(..., 2)`` to normalised coordinates ``(..., 2)``."""
        uv = np.asarray(uv, dtype=float)
        return np.stack([(uv[..., 0] - self.cx) / self.fx, (uv[..., 1] - self.cy) / self.fy], axis=-1)

    def project(self, p_camera_m) -> tuple[np.ndarray, np.ndarray]:
        """Project camera-frame points ``(..., 3)`` to pixels.

        Returns
        -------
        uv : ndarray, shape (..., 2)
            Pixel coordinates (NaN for points at or behind the camera centre).
        in_front : ndarray of bool, shape (...)
            True where the point lies in front of the camera (z > 0).
        """
        p = np.asarray(p_camera_m, dtype=float)
        z = p[..., 2]
        in_front = z > 1e-9
        with np.errstate(divide="ignore", invalid="ignore"):
            xy = np.stack([p[..., 0] / z, p[..., 1] / z], axis=-1)
        xy = np.where(in_front[..., None], xy, np.nan)
        return self.normalized_to_pixels(xy), in_front

    # ----------------------------------------------------------------- lens distortion
    def distort_normalized(self, xy) -> np.ndarray:
        """Pinhole normalised coordinates ``(..., 2)`` to distorted normalised coordinates.

        OpenCV's model: with ``r2 = x^2 + y^2`` and ``g = 1 + k1 r2 + k2 r2^2 + k3 r2^3``,
        ``x_d = x g + 2 p1 x y + p2 (r2 + 2 x^2)``, ``y_d = y g + p1 (r2 + 2 y^2) + 2 p2 x y``.
        """
        xy = np.asarray(xy, dtype=float)
        if not self.has_distortion:
            return xy.copy()
        k1, k2, p1, p2, k3 = self.distortion
        x, y = xy[..., 0], xy[..., 1]
        r2 = x * x + y * y
        radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
        x_d = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
        y_d = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y
        return np.stack([x_d, y_d], axis=-1)

    def undistort_normalized(self, xy_distorted, iterations: int = 30) -> np.ndarray:
        """Inverse of :meth:`distort_normalized` (Newton iterations with a numerical Jacobian).

        Converges to 1e-12 inside the lens's monotonic zone; points where the model folds over
        (far outside the field of view of a strongly distorted lens) come back NaN.
        """
        target = np.asarray(xy_distorted, dtype=float)
        if not self.has_distortion:
            return target.copy()
        xy = target.copy()
        step = 1e-7
        for _ in range(iterations):
            residual = self.distort_normalized(xy) - target
            if np.nanmax(np.abs(residual), initial=0.0) < 1e-13:
                break
            jx = (self.distort_normalized(xy + [step, 0.0]) - self.distort_normalized(xy - [step, 0.0])) / (2 * step)
            jy = (self.distort_normalized(xy + [0.0, step]) - self.distort_normalized(xy - [0.0, step])) / (2 * step)
            det = jx[..., 0] * jy[..., 1] - jy[..., 0] * jx[..., 1]
            with np.errstate(divide="ignore", invalid="ignore"):
                dx = (jy[..., 1] * residual[..., 0] - jy[..., 0] * residual[..., 1]) / det
                dy = (jx[..., 0] * residual[..., 1] - jx[..., 1] * residual[..., 0]) / det
            xy = xy - np.stack([dx, dy], axis=-1)
        residual = np.abs(self.distort_normalized(xy) - target).max(axis=-1)
        return np.where((residual < 1e-9)[..., None], xy, np.nan)

    def distort_pixels(self, uv) -> np.ndarray:
        """Pinhole (undistorted) pixels ``(..., 2)`` to the pixels of the real, distorted frame."""
        return self.normalized_to_pixels(self.distort_normalized(self.pixels_to_normalized(uv)))

    def undistort_pixels(self, uv_distorted) -> np.ndarray:
        """Pixels of the real, distorted frame ``(..., 2)`` to pinhole (undistorted) pixels."""
        return self.normalized_to_pixels(self.undistort_normalized(self.pixels_to_normalized(uv_distorted)))

    def undistortion_maps(self) -> tuple[np.ndarray, np.ndarray]:
        """``cv2.remap`` maps (float32, shape (height, width)) from the frame to its pinhole image.

        ``pinhole[v, u] = frame[map_v[v, u], map_u[v, u]]``: each pinhole pixel is looked up at
        its distorted position. Same size and intrinsics as the frame.
        """
        v, u = np.mgrid[0:self.height, 0:self.width].astype(float)
        uv_distorted = self.distort_pixels(np.stack([u, v], axis=-1))
        return uv_distorted[..., 0].astype(np.float32), uv_distorted[..., 1].astype(np.float32)

    def structure_mask(self) -> np.ndarray | None:
        """The aircraft's own structure as a boolean image ``(height, width)`` of the frame as
        taken (True = never read as scene), or None without a mask.

        Raises ``ValueError`` (one sentence naming the mask file) when the mask image cannot be
        read, is not of the camera's size, or covers the whole image.
        """
        if self.mask is None:
            return None
        return _structure_mask(self.mask, self.width, self.height)

    def in_image(self, uv, margin_px: float = 0.0) -> np.ndarray:
        """True where pixel coordinates lie inside the image (``margin_px`` inside the border)."""
        uv = np.asarray(uv, dtype=float)
        u, v = uv[..., 0], uv[..., 1]
        with np.errstate(invalid="ignore"):
            return ((u >= -0.5 + margin_px) & (u <= self.width - 0.5 - margin_px)
                    & (v >= -0.5 + margin_px) & (v <= self.height - 0.5 - margin_px))

    # ----------------------------------------------------------------- lines
    def line_from_pixel_hough(self, rho_px, theta_px_rad) -> tuple[np.ndarray, np.ndarray]:
        """Pixel-space line ``u cos(t) + v sin(t) = r`` (OpenCV HoughLines) to SPEC ``(rho, theta)``.

        Substituting ``u = fx x + cx``, ``v = fy y + cy`` gives
        ``x fx cos(t) + y fy sin(t) = r - cx cos(t) - cy sin(t)``, normalised to a unit normal.
        """
        t = np.asarray(theta_px_rad, dtype=float)
        r = np.asarray(rho_px, dtype=float)
        a = self.fx * np.cos(t)
        b = self.fy * np.sin(t)
        norm = np.hypot(a, b)
        rho = (r - self.cx * np.cos(t) - self.cy * np.sin(t)) / norm
        theta = np.arctan2(b, a)
        return wrap_line_chart(rho, theta)

    def line_to_pixel_hough(self, rho, theta_rad) -> tuple[np.ndarray, np.ndarray]:
        """SPEC ``(rho, theta)`` to a pixel-space line ``u cos(t) + v sin(t) = r`` with t in [-pi/2, pi/2)."""
        theta = np.asarray(theta_rad, dtype=float)
        rho = np.asarray(rho, dtype=float)
        # x cos + y sin = rho, x = (u - cx)/fx, y = (v - cy)/fy
        a = np.cos(theta) / self.fx
        b = np.sin(theta) / self.fy
        c = rho + self.cx * a + self.cy * b
        norm = np.hypot(a, b)
        return wrap_line_chart(c / norm, np.arctan2(b, a))

    def line_distance_px(self, rho, theta_rad, uv) -> np.ndarray:
        """Signed distance in pixels from pixel points ``uv (..., 2)`` to a SPEC line."""
        r_px, t_px = self.line_to_pixel_hough(rho, theta_rad)
        uv = np.asarray(uv, dtype=float)
        return uv[..., 0] * np.cos(t_px) + uv[..., 1] * np.sin(t_px) - r_px


def _checked_distortion(value, what: str):
    """``None`` or a tuple of the 5 OpenCV coefficients; one sentence naming ``what`` otherwise."""
    if value is None:
        return None
    if (not isinstance(value, (list, tuple, np.ndarray)) or len(value) != len(DISTORTION_NAMES)
            or not all(isinstance(c, (int, float, np.floating)) and not isinstance(c, bool) and math.isfinite(c)
                       for c in value)):
        raise ValueError(f"{what} must be a list of 5 finite numbers [k1, k2, p1, p2, k3] (OpenCV order), got {value!r}")
    coefficients = tuple(float(c) for c in value)
    limits = (("k1", 2.0), ("k2", 5.0), ("p1", 0.1), ("p2", 0.1), ("k3", 10.0))
    for c, (name, limit) in zip(coefficients, limits):
        if abs(c) > limit:
            raise ValueError(f"{what}: {name} = {c:g} is outside +-{limit:g} (not a lens distortion in "
                             f"OpenCV's normalised units; were pixel units or another model used?)")
    return coefficients


def _checked_mask(value, what: str):
    """Polygons as a tuple of tuples of ``(u, v)`` floats, a path as a non-empty string, or None."""
    if value is None or (isinstance(value, str) and value):
        return value
    if isinstance(value, (str, bytes)) or not isinstance(value, (list, tuple)) or not value:
        raise ValueError(f"{what} must be a list of polygons [[[u, v], ...], ...] or the name of a mask "
                         f"image, got {value!r}"[:300])
    polygons = []
    for k, polygon in enumerate(value):
        if not isinstance(polygon, (list, tuple)) or len(polygon) < 3:
            raise ValueError(f"{what}: polygon {k} must be a list of at least 3 [u, v] vertices, got {polygon!r}"[:300])
        vertices = []
        for vertex in polygon:
            if (not isinstance(vertex, (list, tuple)) or len(vertex) != 2
                    or not all(isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c)
                               for c in vertex)):
                raise ValueError(f"{what}: polygon {k} has a vertex that is not two finite pixel coordinates: "
                                 f"{vertex!r}"[:300])
            vertices.append((float(vertex[0]), float(vertex[1])))
        polygons.append(tuple(vertices))
    return tuple(polygons)


#: A mask leaving less than this fraction of the image is refused (nothing left to see).
MASK_MAX_COVER = 0.98


@functools.lru_cache(maxsize=8)
def _structure_mask(mask, width: int, height: int) -> np.ndarray:
    import cv2  # heavy import kept local: the core must start fast
    if isinstance(mask, str):
        path = Path(mask)
        if not path.is_file():
            raise ValueError(f"mask image {path} not found")
        image = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
        if image is None:
            raise ValueError(f"mask image {path} cannot be read as an image")
        if image.shape != (height, width):
            raise ValueError(f"mask image {path} is {image.shape[1]}x{image.shape[0]} px, the camera's frames "
                             f"are {width}x{height}")
        structure = image > 0
        name = f"mask image {path}"
    else:
        canvas = np.zeros((height, width), np.uint8)
        # vertices in pixels with (0, 0) at the centre of the top-left pixel: fillPoly's integer
        # grid is the same, with 4 fractional bits
        polygons = [np.round(np.asarray(p, float) * 16).astype(np.int32) for p in mask]
        cv2.fillPoly(canvas, polygons, 1, lineType=cv2.LINE_8, shift=4)
        structure = canvas > 0
        name = "mask polygons"
    if structure.mean() > MASK_MAX_COVER:
        raise ValueError(f"{name} cover {100 * structure.mean():.1f} % of the image: nothing would be left to "
                         "see (non-zero pixels are the aircraft's structure)")
    structure.setflags(write=False)
    return structure


def wrap_line_chart(rho, theta_rad) -> tuple[np.ndarray, np.ndarray]:
    """Map any ``(rho, theta)`` to the SPEC chart ``theta in [-pi/2, pi/2)``.

    A shift of theta by pi flips the sign of rho: ``(rho, theta) ~ (-rho, theta + pi)``,
    so ``theta - k pi`` goes with ``(-1)^k rho``.

    Parameters
    ----------
    rho : float or array_like
        Signed distance of the line from the principal point, normalised coordinates
        (``x cos(theta) + y sin(theta) = rho``, ``x = (u - cx)/fx``, ``y = (v - cy)/fy``).
    theta_rad : float or array_like
        Angle of the line's normal, radians (any value).

    Returns
    -------
    rho, theta_rad : ndarray
        The same line(s) with theta in [-pi/2, pi/2).
    """
    theta = np.asarray(theta_rad, dtype=float)
    rho = np.asarray(rho, dtype=float)
    k = np.floor((theta + np.pi / 2) / np.pi)
    sign = np.where(np.mod(k, 2) == 0, 1.0, -1.0)
    return sign * rho, theta - k * np.pi


def line_through_points(xy_a, xy_b) -> tuple[np.ndarray, np.ndarray]:
    """SPEC ``(rho, theta)`` of the line through two normalised points.

    Parameters
    ----------
    xy_a, xy_b : array_like, shape (..., 2)
        Two distinct points in normalised coordinates ``x = (u - cx)/fx``, ``y = (v - cy)/fy``.

    Returns
    -------
    rho, theta_rad : ndarray, shape (...)
        ``x cos(theta) + y sin(theta) = rho`` with theta in [-pi/2, pi/2).
    """
    a = np.asarray(xy_a, dtype=float)
    b = np.asarray(xy_b, dtype=float)
    d = b - a
    # normal (cos t, sin t) is perpendicular to the direction d
    theta = np.arctan2(d[..., 0], -d[..., 1])
    rho = a[..., 0] * np.cos(theta) + a[..., 1] * np.sin(theta)
    return wrap_line_chart(rho, theta)


def intersect_lines(rho_a, theta_a, rho_b, theta_b) -> np.ndarray:
    """Intersection of two SPEC lines ``x cos(theta) + y sin(theta) = rho`` (normalised coordinates).

    Parameters
    ----------
    rho_a, theta_a : float or array_like
        First line: distance (normalised) and normal angle (radians).
    rho_b, theta_b : float or array_like
        Second line, broadcast against the first.

    Returns
    -------
    ndarray, shape (..., 2)
        ``(x, y)`` normalised coordinates of the intersection, NaN where the lines are parallel.
    """
    ca, sa = np.cos(theta_a), np.sin(theta_a)
    cb, sb = np.cos(theta_b), np.sin(theta_b)
    det = ca * sb - sa * cb
    with np.errstate(divide="ignore", invalid="ignore"):
        x = (np.asarray(rho_a) * sb - np.asarray(rho_b) * sa) / det
        y = (ca * np.asarray(rho_b) - cb * np.asarray(rho_a)) / det
    bad = np.abs(det) < 1e-12
    return np.stack([np.where(bad, np.nan, x), np.where(bad, np.nan, y)], axis=-1)
