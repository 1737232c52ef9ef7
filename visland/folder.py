"""Reading a frame folder in the SPEC.md contract (what ``detect``, ``track`` and ``process`` read).

::

    DIR/frames/        images sorted by name (png or jpg)
    DIR/frames.csv     frame,t_s   (optional; else t = index / fps)
    DIR/telemetry.csv  inertial data at >= the frame rate, interpolated to frame times
    DIR/camera.json    intrinsics and mounting
    DIR/truth.csv      optional, one row per frame (enables metrics)
    DIR/labels.csv     optional, exact features (generated datasets)

``frame`` in ``frames.csv`` is the 0-based index of the image in name order. Validation
errors are one sentence naming the file, line or frame.
"""
from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np

from visland.camera import CameraModel
from visland.contracts import Table, read_frames_csv, read_labels, read_telemetry, read_truth
from visland.sensors import InertialSeries

__all__ = ["FrameFolder", "IMAGE_SUFFIXES", "as_grey", "pinhole_frame", "scene_frame", "ignored_pixels", "interpolate_telemetry",
           "list_frame_files"]

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg")


def interpolate_telemetry(telemetry: Table, times_s, source: str = "telemetry.csv") -> InertialSeries:
    """The telemetry at the frame times: :meth:`InertialSeries.at` with the frames named.

    Parameters
    ----------
    telemetry : visland.contracts.Table
        As read by :func:`visland.contracts.read_telemetry` (one row is enough when every frame
        is at its time).
    times_s : array_like, shape (n,)
        Frame times in seconds on the telemetry's clock, strictly increasing.
    source : str
        What the telemetry is called in an error (its path).

    Returns
    -------
    visland.sensors.InertialSeries
        Attitude (radians; roll and heading unwrapped before interpolating), body rates (rad/s),
        NED ground velocity (m/s) and the true airspeed when recorded, one sample per frame.

    Raises
    ------
    ValueError
        When the telemetry does not cover every frame time, naming the first uncovered frame.
    """
    times = np.asarray(times_s, dtype=float)
    t = telemetry["t_s"]
    outside = np.nonzero((times < t[0] - 1e-9) | (times > t[-1] + 1e-9))[0]
    if outside.size:
        i = int(outside[0])
        raise ValueError(f"{source}: telemetry covers {t[0]:g}..{t[-1]:g} s but frame {i} is at t = {times[i]:g} s")
    return InertialSeries.from_table(telemetry, min_samples=1).at(times, min_samples=1)


def list_frame_files(frames_dir: Path) -> list[Path]:
    """Entries of a frames folder named as images (.png, .jpg), sorted by name.

    An entry named as an image that is not one (a folder, a dangling link, a link loop) stays
    in the list: it is a frame that cannot be used, flagged by :meth:`FrameFolder.read_frame`,
    and every later frame keeps its index and time.

    Parameters
    ----------
    frames_dir : Path
        The ``frames/`` folder.

    Returns
    -------
    list of Path
        Sorted by name; never empty (no image raises ``ValueError``).
    """
    if not frames_dir.is_dir():
        raise ValueError(f"{frames_dir}: frames folder not found")
    files = sorted(p for p in frames_dir.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
    if not files:
        raise ValueError(f"{frames_dir}: no .png or .jpg images in the frames folder")
    return files


def _frames_in_csv_order(table, frames_csv: Path, files: list[Path], frames_dir: Path) -> list[Path]:
    """The frame files in the order of ``frames.csv``, whose ``frame`` column holds either the
    0-based index of each image in name order or its file name (relative to ``frames/``).

    Every image of ``frames/`` must be listed once (nothing is skipped silently); a name that
    is not there, or an index out of order, is one sentence naming the row.
    """
    values = [str(f).strip() for f in table["frame"]]
    n = len(files)
    if all(v.lstrip("-").isdigit() for v in values):
        index = np.array([int(v) for v in values])
        if len(index) != n or not np.array_equal(index, np.arange(n)):
            raise ValueError(f"{frames_csv}: lists {len(index)} frames 0..{len(index) - 1} but {frames_dir} holds "
                             f"{n} images (column 'frame' holds 0-based indices in name order, or file names)")
        return files
    by_name = {f.name: f for f in files}
    ordered, seen = [], set()
    for row, name in enumerate(values, start=2):
        path = by_name.get(Path(name).name) if Path(name).parent in (Path("."), Path("frames")) else None
        if path is None:
            raise ValueError(f"{frames_csv}: line {row}: frame {name!r} is not an image of {frames_dir}")
        if path.name in seen:
            raise ValueError(f"{frames_csv}: line {row}: frame {name!r} is listed twice")
        seen.add(path.name)
        ordered.append(path)
    if len(ordered) != n:
        missing = sorted(set(by_name) - seen)
        raise ValueError(f"{frames_csv}: names {len(ordered)} of the {n} images of {frames_dir}; not listed: "
                         f"{', '.join(missing[:3])}{' ...' if len(missing) > 3 else ''}")
    return ordered


class FrameFolder:
    """A validated frame folder: frame files, their times, telemetry at those times, camera.

    Parameters
    ----------
    root : str or Path
        The folder (SPEC layout, see the module docstring).
    camera : CameraModel or str or Path, optional
        The camera, or a path overriding ``root/camera.json``.
    telemetry : str or Path, optional
        Path overriding ``root/telemetry.csv``.
    frames_csv : str or Path, optional
        Path overriding ``root/frames.csv``.
    fps : float, optional
        Frame rate in Hz used when there is no frames.csv (default 25 Hz).
    require_telemetry : bool, default True
        Raise if there is no telemetry (without it detection reads the horizon off each frame;
        estimation needs it).
    time_offset_s : float, default 0
        Seconds added to the telemetry's times (its clock against the frames',
        :mod:`visland.clocks`).

    Attributes
    ----------
    frame_files : list of Path
        The frames, in frame order.
    times_s : ndarray, shape (n,)
        Frame times in seconds.
    inertial : visland.sensors.InertialSeries or None
        The telemetry interpolated at ``times_s`` (None without telemetry).
    telemetry, truth, labels : visland.contracts.Table or None
        The files as read (None when absent).

    Raises
    ------
    ValueError
        One sentence naming the file, line or frame that is wrong.
    """

    def __init__(self, root, camera: CameraModel | str | Path | None = None, telemetry=None, frames_csv=None,
                 fps: float | None = None, require_telemetry: bool = True, time_offset_s: float = 0.0):
        self.root = Path(root)
        if not self.root.is_dir():
            raise ValueError(f"{self.root}: input folder not found")
        self.frame_files = list_frame_files(self.root / "frames")
        n = len(self.frame_files)
        frames_csv = Path(frames_csv) if frames_csv else self.root / "frames.csv"
        if frames_csv.exists():
            table = read_frames_csv(frames_csv)
            self.frame_files = _frames_in_csv_order(table, frames_csv, self.frame_files, self.root / "frames")
            self.times_s = table["t_s"]
        else:
            fps = 25.0 if fps is None else float(fps)
            if not (math.isfinite(fps) and fps > 0):
                raise ValueError(f"fps must be a positive number, got {fps!r}")
            self.times_s = np.arange(n) / fps
        self.camera = CameraModel.for_input(camera, self.root)
        telemetry_path = Path(telemetry) if telemetry else self.root / "telemetry.csv"
        if telemetry_path.exists():
            self.telemetry = read_telemetry(telemetry_path)
            self.telemetry["t_s"] = self.telemetry["t_s"] + float(time_offset_s)    # onto the frames' clock
            self.inertial = interpolate_telemetry(self.telemetry, self.times_s, source=str(telemetry_path))
        elif require_telemetry:
            raise ValueError(f"{telemetry_path}: telemetry file not found; estimation needs inertial data (give "
                             "--telemetry FILE), and `visland detect` finds the runway in frames alone")
        else:
            self.telemetry = None
            self.inertial = None
        truth_path = self.root / "truth.csv"
        self.truth = read_truth(truth_path) if truth_path.exists() else None
        if self.truth is not None and self.truth.n_rows != n:
            raise ValueError(f"{truth_path}: {self.truth.n_rows} rows but there are {n} frames (one row per frame)")
        labels_path = self.root / "labels.csv"
        self.labels = read_labels(labels_path) if labels_path.exists() else None
        if self.labels is not None and self.labels.n_rows != n:
            raise ValueError(f"{labels_path}: {self.labels.n_rows} rows but there are {n} frames (one row per frame)")

    def __len__(self) -> int:
        return len(self.frame_files)

    def read_frame(self, index: int, gray: bool = True):
        """Read frame ``index``: ``(image, None)`` or ``(None, reason)`` when it cannot be used.

        The image is uint8, (H, W) when ``gray`` else (H, W, 3) RGB. A frame of another size
        than the camera's is refused with the reason.
        """
        import cv2  # heavy import kept local: the core must start fast
        path = self.frame_files[index]
        problem = _not_a_file(path)
        if problem:
            return None, f"frame {index} ({path.name}): {problem}, not an image"
        try:
            image = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE if gray else cv2.IMREAD_COLOR)
        except cv2.error:                   # e.g. a header declaring more pixels than OpenCV allows
            return None, f"frame {index} ({path.name}): unreadable image (OpenCV refuses its header)"
        if image is None:
            return None, f"frame {index} ({path.name}): unreadable image"
        height, width = image.shape[:2]
        if (width, height) != (self.camera.width, self.camera.height):
            return None, (f"frame {index} ({path.name}): image is {width}x{height}, "
                          f"camera.json says {self.camera.width}x{self.camera.height}")
        if not gray:
            image = cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
        return image, None


def _not_a_file(path: Path) -> str:
    """Why ``path`` is not a regular file ("" when it is one)."""
    if path.is_symlink():
        try:
            path.resolve(strict=True)
        except FileNotFoundError:
            return "a dangling link"
        except (RuntimeError, OSError):
            return "a link loop"
    if path.is_dir():
        return "a folder"
    if not path.is_file():
        return "not a regular file"
    return ""


def as_grey(image):
    """``image`` as grey levels: unchanged when it is (H, W), converted from RGB when (H, W, 3).

    Parameters
    ----------
    image : ndarray, shape (H, W) or (H, W, 3), uint8, or None
        A frame (RGB channel order when in colour).

    Returns
    -------
    ndarray, shape (H, W), uint8, or None
        None stays None.
    """
    if image is None or image.ndim == 2:
        return image
    import cv2  # heavy import kept local: the core must start fast
    return cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)


@functools.lru_cache(maxsize=4)
def _undistortion_maps(camera: CameraModel):
    import cv2  # heavy import kept local: the core must start fast
    map_u, map_v = camera.undistortion_maps()
    return cv2.convertMaps(map_u, map_v, cv2.CV_16SC2)


def pinhole_frame(image, camera: CameraModel):
    """The frame as the pinhole camera of the same intrinsics would see it (SPEC: features are
    always in the undistorted image).

    Parameters
    ----------
    image : ndarray, shape (H, W) or (H, W, 3), uint8, or None
        A frame as ``camera`` took it (None stays None).
    camera : visland.camera.CameraModel
        Its intrinsics and lens distortion.

    Returns
    -------
    ndarray, same shape and dtype as ``image``
        Unchanged when the camera has no lens distortion, else resampled through
        :meth:`CameraModel.undistortion_maps` (bilinear; pixels whose lens position falls
        outside the frame come back 0). The maps are computed once per camera.
    """
    if image is None or not camera.has_distortion:
        return image
    import cv2  # heavy import kept local: the core must start fast
    map_a, map_b = _undistortion_maps(camera)
    return cv2.remap(image, map_a, map_b, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)


#: Pixels of the structure mask's edge are grown by this many pixels (blur and the lens's
#: resampling spread the structure's outline beyond the drawn mask).
MASK_GROWTH_PX = 3


@functools.lru_cache(maxsize=4)
def ignored_pixels(camera: CameraModel) -> np.ndarray | None:
    """Pixels of the pinhole image that show no scene, as a read-only boolean image, or None.

    Parameters
    ----------
    camera : visland.camera.CameraModel
        Its structure mask and lens.

    Returns
    -------
    ndarray of bool, shape (height, width), or None
        The aircraft's structure (:meth:`CameraModel.structure_mask`, carried through the lens
        like the frame) grown by :data:`MASK_GROWTH_PX`, and with a distorting lens the pinhole
        pixels whose lens position falls outside the frame. None when every pixel shows the
        scene.
    """
    import cv2  # heavy import kept local: the core must start fast
    ignored = np.zeros((camera.height, camera.width), bool)
    structure = camera.structure_mask()
    if structure is not None:
        ignored |= pinhole_frame(structure.astype(np.uint8) * 255, camera) > 0
    if camera.has_distortion:
        map_u, map_v = camera.undistortion_maps()
        ignored |= ((map_u < -0.5) | (map_u > camera.width - 0.5) | (map_v < -0.5) | (map_v > camera.height - 0.5))
    if not ignored.any():
        return None
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * MASK_GROWTH_PX + 1,) * 2)
    ignored = cv2.dilate(ignored.astype(np.uint8), kernel) > 0
    ignored.setflags(write=False)
    return ignored


def scene_frame(image, camera: CameraModel):
    """The pinhole frame (:func:`pinhole_frame`) with the pixels that show no scene
    (:func:`ignored_pixels`: the aircraft's structure, outside the lens) filled smoothly from
    the scene around them, so that no edge, line or texture of theirs reaches the detector or
    the tracker.

    The fill is a normalised convolution (the blurred scene divided by the blurred weight of
    the scene pixels) on a coarse image, widened until every hole is reached: it continues the
    surrounding grey levels without a step at the mask's outline, and carries no structure.

    Parameters
    ----------
    image : ndarray, shape (H, W) or (H, W, 3), uint8, or None
        A frame as ``camera`` took it (None stays None).
    camera : visland.camera.CameraModel
        Its intrinsics, lens and structure mask.

    Returns
    -------
    ndarray, same shape and dtype as ``image``
        The pinhole frame with the ignored pixels filled.
    """
    image = pinhole_frame(image, camera)
    ignored = ignored_pixels(camera) if image is not None else None
    if ignored is None:
        return image
    import cv2  # heavy import kept local: the core must start fast
    height, width = ignored.shape
    step = max(1, int(max(height, width) // 256))
    small = cv2.resize(image, (width // step, height // step), interpolation=cv2.INTER_AREA).astype(np.float32)
    weight = cv2.resize((~ignored).astype(np.float32), (width // step, height // step), interpolation=cv2.INTER_AREA)
    weight = np.where(weight > 0.99, 1.0, 0.0).astype(np.float32)    # coarse pixels wholly in the scene
    weighted = small * (weight[..., None] if small.ndim == 3 else weight)
    fill = np.zeros_like(small)
    done = np.zeros(weight.shape, bool)
    sigma = 2.0
    while not done.all() and sigma < 4 * max(weight.shape):
        blur_w = cv2.GaussianBlur(weight, (0, 0), sigma)
        blur_s = cv2.GaussianBlur(weighted, (0, 0), sigma)
        reached = (blur_w > 1e-3) & ~done
        denom = blur_w[..., None] if small.ndim == 3 else blur_w
        fill[reached] = (blur_s / np.maximum(denom, 1e-6))[reached]
        done |= reached
        sigma *= 2.0
    fill = cv2.resize(fill, (width, height), interpolation=cv2.INTER_LINEAR)
    out = image.copy()
    out[ignored] = np.clip(fill[ignored], 0, 255).astype(image.dtype)
    return out
