"""Frame sources for offline processing: a SPEC frame folder or a video file.

Both give frames in order with their times, the telemetry interpolated at those times, the
camera, and (when present) truth and labels. Frames are decoded ahead of the analysis in a
background thread (OpenCV releases the GIL while decoding), so decoding and analysis overlap.

A frame that cannot be used (unreadable, wrong size) comes out as ``(index, None, reason)``:
the caller flags it and carries on.
"""
from __future__ import annotations

import concurrent.futures
import math
from collections import deque
from pathlib import Path

import numpy as np

from visland.camera import CameraModel
from visland.contracts import read_frames_csv, read_labels, read_telemetry, read_truth
from visland.folder import FrameFolder, interpolate_telemetry

__all__ = ["FrameSource", "FolderSource", "VideoSource", "LabelsSource", "open_source", "VIDEO_SUFFIXES"]

VIDEO_SUFFIXES = (".mp4", ".avi", ".mkv", ".mov", ".m4v", ".webm")


class FrameSource:
    """Common interface: ``len``, ``times_s``, ``camera``, ``inertial``, ``truth``, ``labels``, ``frames()``."""

    name: str
    camera: CameraModel
    times_s: np.ndarray
    inertial = None
    truth = None
    labels = None
    runway_json: Path | None = None

    def __len__(self) -> int:
        return len(self.times_s)

    def frames(self, gray: bool = True, prefetch: int = 4):
        """Yield ``(index, image or None, reason or None)`` in order."""
        raise NotImplementedError

    def shift_telemetry(self, offset_s: float) -> None:
        """Put the telemetry on the frames' clock: ``offset_s`` seconds added to its times
        (:mod:`visland.clocks`), and interpolated again at the frame times."""
        table = self.telemetry
        table["t_s"] = np.asarray(table["t_s"], float) + float(offset_s)
        self.inertial = interpolate_telemetry(table, self.times_s,
                                              source=f"{table.path} (times shifted by {offset_s:+.3f} s)")
        if hasattr(self, "folder"):
            self.folder.inertial = self.inertial


class FolderSource(FrameSource):
    """A SPEC frame folder (see :class:`visland.folder.FrameFolder`).

    Parameters
    ----------
    root : str or Path
        The folder.
    camera, telemetry, frames_csv, fps, time_offset_s
        As in :func:`open_source`, passed to :class:`visland.folder.FrameFolder`.
    """

    def __init__(self, root, camera=None, telemetry=None, frames_csv=None, fps=None, time_offset_s=0.0):
        self.folder = FrameFolder(root, camera=camera, telemetry=telemetry, frames_csv=frames_csv, fps=fps,
                                  time_offset_s=time_offset_s)
        self.name = str(self.folder.root)
        self.camera = self.folder.camera
        self.times_s = self.folder.times_s
        self.telemetry = self.folder.telemetry
        self.inertial = self.folder.inertial
        self.truth = self.folder.truth
        self.labels = self.folder.labels
        runway = self.folder.root / "runway.json"
        self.runway_json = runway if runway.exists() else None

    def frames(self, gray: bool = True, prefetch: int = 4):
        n = len(self.folder)
        with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
            pending = deque()
            next_index = 0
            while next_index < n and len(pending) < prefetch:
                pending.append(pool.submit(self.folder.read_frame, next_index, gray))
                next_index += 1
            index = 0
            while pending:
                image, reason = pending.popleft().result()
                if next_index < n:
                    pending.append(pool.submit(self.folder.read_frame, next_index, gray))
                    next_index += 1
                yield index, image, reason
                index += 1


class VideoSource(FrameSource):
    """A video file; telemetry, camera and optional truth/frames.csv sit beside it or are given.

    Frame times come from ``frames_csv`` (``frame,t_s``) if given or present beside the video,
    else from ``fps`` if given, else from the container's timestamps: a video of constant frame
    rate gives ``k / fps`` exactly, one of variable frame rate (a recorder that drops or delays
    frames) each frame's own presentation time. ``timing`` says which, in one sentence.

    Parameters
    ----------
    path : str or Path
        The video file.
    camera, telemetry, frames_csv, fps, time_offset_s
        As in :func:`open_source`; files not given are looked for beside the video.
    """

    def __init__(self, path, camera=None, telemetry=None, frames_csv=None, fps=None, time_offset_s=0.0):
        import cv2
        self.path = Path(path)
        self.name = str(self.path)
        here = self.path.parent
        capture = cv2.VideoCapture(str(self.path))
        if not capture.isOpened():
            raise ValueError(f"{self.path}: the video cannot be opened (unknown format or damaged file)")
        self._count, stamps_s = _scan_frames(capture)
        video_fps = capture.get(cv2.CAP_PROP_FPS)
        capture.release()
        if self._count == 0:
            raise ValueError(f"{self.path}: the video holds no decodable frame")
        frames_csv = Path(frames_csv) if frames_csv else here / "frames.csv"
        if frames_csv.exists():
            table = read_frames_csv(frames_csv)
            if table.n_rows != self._count:
                raise ValueError(f"{frames_csv}: lists {table.n_rows} frames but {self.path} holds {self._count}")
            self.times_s = table["t_s"]
            self.timing = f"frame times from {frames_csv}"
        elif fps is not None:
            self.times_s = np.arange(self._count) / float(fps)
            self.timing = f"frame times from --fps {fps:g}"
        else:
            self.times_s, self.timing = _container_times(stamps_s, video_fps, self.path)
        self.camera = CameraModel.for_input(camera, here)
        telemetry_path = Path(telemetry) if telemetry else here / "telemetry.csv"
        if not telemetry_path.exists():
            raise ValueError(f"{telemetry_path}: telemetry file not found; estimation needs inertial data (give "
                             "--telemetry FILE), and `visland detect` finds the runway in frames alone")
        self.telemetry = read_telemetry(telemetry_path)
        self.telemetry["t_s"] = self.telemetry["t_s"] + float(time_offset_s)      # onto the frames' clock
        self.inertial = interpolate_telemetry(self.telemetry, self.times_s, source=str(telemetry_path))
        truth = here / "truth.csv"
        self.truth = read_truth(truth) if truth.exists() else None
        if self.truth is not None and self.truth.n_rows != self._count:
            raise ValueError(f"{truth}: {self.truth.n_rows} rows but {self.path} holds {self._count} frames")
        labels = here / "labels.csv"
        self.labels = read_labels(labels) if labels.exists() else None
        runway = here / "runway.json"
        self.runway_json = runway if runway.exists() else None

    def frames(self, gray: bool = True, prefetch: int = 4):
        import cv2
        capture = cv2.VideoCapture(str(self.path))
        queue: deque = deque()
        with concurrent.futures.ThreadPoolExecutor(max_workers=1) as pool:

            def decode():
                ok, image = capture.read()
                return image if ok else None

            for _ in range(min(prefetch, self._count)):
                queue.append(pool.submit(decode))
            for index in range(self._count):
                image = queue.popleft().result()
                if index + prefetch < self._count:
                    queue.append(pool.submit(decode))
                if image is None:
                    yield index, None, f"frame {index}: could not be decoded from {self.path.name}"
                    continue
                height, width = image.shape[:2]
                if (width, height) != (self.camera.width, self.camera.height):
                    yield index, None, (f"frame {index}: video frames are {width}x{height}, "
                                        f"the camera file says {self.camera.width}x{self.camera.height}")
                    continue
                image = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY if gray else cv2.COLOR_BGR2RGB)
                yield index, image, None
        capture.release()


class LabelsSource(FrameSource):
    """A simulated folder without images (``visland simulate``): frame times and exact features
    from ``labels.csv``; only ``--source ideal`` can measure it.

    Parameters
    ----------
    root : str or Path
        The folder ``visland simulate`` wrote.
    camera, telemetry : optional
        Instead of its ``camera.json`` and ``telemetry.csv``.
    """

    def __init__(self, root, camera=None, telemetry=None):
        root = Path(root)
        self.name = str(root)
        labels_path = root / "labels.csv"
        self.labels = read_labels(labels_path)
        self.times_s = self.labels["t_s"]
        self.camera = CameraModel.for_input(camera, root)
        telemetry_path = Path(telemetry) if telemetry else root / "telemetry.csv"
        self.telemetry = read_telemetry(telemetry_path)
        self.inertial = interpolate_telemetry(self.telemetry, self.times_s, source=str(telemetry_path))
        truth = root / "truth.csv"
        self.truth = read_truth(truth) if truth.exists() else None
        if self.truth is not None and self.truth.n_rows != len(self.times_s):
            raise ValueError(f"{truth}: {self.truth.n_rows} rows but labels.csv has {len(self.times_s)} frames")
        runway = root / "runway.json"
        self.runway_json = runway if runway.exists() else None

    def frames(self, gray: bool = True, prefetch: int = 4):
        raise ValueError(f"{self.name}: no frames/ folder; only --source ideal can process a simulated folder")


def _scan_frames(capture) -> tuple[int, np.ndarray]:
    """Frames a video really holds (the container's count is often wrong: grab them all) and
    each one's presentation time from the container (s; NaN where the container gives none)."""
    import cv2
    stamps = []
    while capture.grab():
        stamps.append(capture.get(cv2.CAP_PROP_POS_MSEC) / 1000.0)
    return len(stamps), np.asarray(stamps, dtype=float)


#: Container timestamps within this of ``k / fps`` (s) are a constant frame rate: ``k / fps`` is
#: used (the container rounds its times to its time base, often 1 ms).
CONSTANT_RATE_TOLERANCE_S = 1.5e-3


def _container_times(stamps_s: np.ndarray, video_fps: float, path: Path) -> tuple[np.ndarray, str]:
    """Frame times of a video without frames.csv or --fps: ``k / fps`` for a constant frame rate,
    else the container's presentation times (variable frame rate), with one sentence saying which."""
    n = len(stamps_s)
    rate_ok = bool(video_fps) and math.isfinite(video_fps) and video_fps > 0
    stamps_ok = n >= 2 and np.isfinite(stamps_s).all() and (np.diff(stamps_s) > 0).all()
    if rate_ok:
        uniform = np.arange(n) / float(video_fps)
        if not stamps_ok or np.max(np.abs(stamps_s - stamps_s[0] - uniform)) <= CONSTANT_RATE_TOLERANCE_S:
            return uniform, f"frame times from the video's constant frame rate ({video_fps:g} frames/s)"
    if not stamps_ok:
        raise ValueError(f"{path}: the video gives no frame rate and no increasing frame timestamps; pass --fps or "
                         "--frames-csv")
    times = stamps_s - stamps_s[0]
    steps = np.diff(times)
    return times, (f"variable frame rate: frame times from the container's timestamps (intervals "
                   f"{steps.min():.3f} to {steps.max():.3f} s, median {np.median(steps):.3f} s)")


def open_source(path, camera=None, telemetry=None, frames_csv=None, fps=None, time_offset_s=0.0) -> FrameSource:
    """A frame folder or a video file, by what ``path`` is.

    A folder without ``frames/`` but with ``labels.csv`` (``visland simulate``) opens as a
    :class:`LabelsSource`; ``frames_csv``, ``fps`` and ``time_offset_s`` do not apply to it.

    Parameters
    ----------
    path : str or Path
        A SPEC frame folder, or a video (:data:`VIDEO_SUFFIXES`).
    camera : str, Path or CameraModel, optional
        Instead of the input's ``camera.json``.
    telemetry : str or Path, optional
        Instead of the input's ``telemetry.csv``.
    frames_csv : str or Path, optional
        Frame times ``frame,t_s`` instead of the input's ``frames.csv``.
    fps : float, optional
        Frame rate in Hz when there is no frames.csv (default 25, or the video's timestamps).
    time_offset_s : float, default 0
        Seconds added to the telemetry's times to put them on the frames' clock.

    Returns
    -------
    FrameSource
        ``len()``, ``times_s``, ``camera``, ``inertial``, ``truth``, ``labels`` and ``frames()``.
    """
    path = Path(path)
    if path.is_dir():
        if not (path / "frames").exists() and (path / "labels.csv").exists():
            return LabelsSource(path, camera=camera, telemetry=telemetry)
        return FolderSource(path, camera=camera, telemetry=telemetry, frames_csv=frames_csv, fps=fps,
                            time_offset_s=time_offset_s)
    if path.is_file() and path.suffix.lower() in VIDEO_SUFFIXES:
        return VideoSource(path, camera=camera, telemetry=telemetry, frames_csv=frames_csv, fps=fps,
                           time_offset_s=time_offset_s)
    if not path.exists():
        raise ValueError(f"{path}: input not found (give a frame folder or a video file)")
    raise ValueError(f"{path}: not a frame folder nor a video ({', '.join(VIDEO_SUFFIXES)})")
