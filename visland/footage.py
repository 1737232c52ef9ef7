"""Sampling frames from raw footage: a video file or a folder of images (no SPEC contract).

What ``visland calibrate`` and ``visland mask`` read: footage as it comes from a camera, without
camera.json or telemetry. A folder is its images sorted by name (``.png``, ``.jpg``), taken from
``DIR/frames/`` when there is such a folder (a SPEC frame folder) and from ``DIR`` itself otherwise;
anything else is opened as a video with OpenCV. Frames are sampled evenly across the sequence
(first and last included) so that a long video costs one decoding pass and a bounded memory.

Pixels follow the camera module's convention: ``image[v, u]``, ``(0, 0)`` the centre of the
top-left pixel. Errors are one sentence naming the file or frame.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["FootageFrame", "sample_footage", "evenly_spaced", "FOOTAGE_IMAGE_SUFFIXES"]

FOOTAGE_IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")


@dataclass(frozen=True)
class FootageFrame:
    """One sampled frame.

    Attributes
    ----------
    index : int
        0-based position of the frame in the footage (name order for a folder).
    name : str
        Where it came from, for messages: ``"clip.mp4 frame 120"`` or the image's file name.
    image : ndarray, shape (H, W) or (H, W, 3), uint8
        Grey levels, or RGB when colour was asked for.
    """

    index: int
    name: str
    image: np.ndarray


def evenly_spaced(count: int, wanted: int) -> list[int]:
    """``min(count, wanted)`` indices in ``0..count-1`` spread evenly, first and last included.

    Parameters
    ----------
    count : int
        How many frames there are.
    wanted : int
        How many to pick.

    Returns
    -------
    list of int
        Sorted, without repeats (empty when either number is not positive).
    """
    if count <= 0 or wanted <= 0:
        return []
    if wanted >= count:
        return list(range(count))
    if wanted == 1:
        return [0]
    return sorted({int(round(i * (count - 1) / (wanted - 1))) for i in range(wanted)})


def _image_files(folder: Path) -> list[Path]:
    frames = folder / "frames"
    where = frames if frames.is_dir() else folder
    files = sorted(p for p in where.iterdir() if p.is_file() and p.suffix.lower() in FOOTAGE_IMAGE_SUFFIXES)
    if not files:
        raise ValueError(f"{where}: no images ({', '.join(FOOTAGE_IMAGE_SUFFIXES)}) in this folder")
    return files


def sample_footage(path, wanted: int, colour: bool = False) -> tuple[list[FootageFrame], int]:
    """Up to ``wanted`` frames spread evenly over a video or an image folder.

    Parameters
    ----------
    path : str or Path
        A video file, or a folder of images (``DIR/frames/`` if present, else ``DIR``).
    wanted : int
        How many frames to sample at most.
    colour : bool
        RGB frames (H, W, 3) instead of grey levels (H, W).

    Returns
    -------
    frames : list of FootageFrame
        In footage order; all of one size (a different size is an error naming the frame).
    total : int
        How many frames the footage holds (for a video: as far as it could be decoded).
    """
    import cv2  # heavy import kept local: the core must start fast
    path = Path(path)
    if wanted < 1:
        raise ValueError(f"the number of frames to sample must be at least 1, got {wanted}")
    if not path.exists():
        raise ValueError(f"{path}: not found (give a video file or a folder of images)")
    flag = cv2.IMREAD_COLOR if colour else cv2.IMREAD_GRAYSCALE
    frames: list[FootageFrame] = []
    if path.is_dir():
        files = _image_files(path)
        for index in evenly_spaced(len(files), wanted):
            image = cv2.imread(str(files[index]), flag)
            if image is None:
                raise ValueError(f"{files[index]}: unreadable image")
            if colour:
                image = cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
            frames.append(FootageFrame(index, files[index].name, image))
        total = len(files)
    else:
        capture = cv2.VideoCapture(str(path))
        try:
            if not capture.isOpened():
                raise ValueError(f"{path}: cannot be opened as a video (unknown format or damaged file) "
                                 f"nor is it a folder of images")
            claimed = int(capture.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
            if claimed <= 0:
                # the container gives no count: one counting pass, then reopen
                while capture.grab():
                    claimed += 1
                capture.release()
                capture = cv2.VideoCapture(str(path))
            chosen = set(evenly_spaced(claimed, wanted))
            index = 0
            # one pass: grab every frame (the count may be wrong), decode only the chosen ones
            while chosen and index <= max(chosen) and capture.grab():
                if index in chosen:
                    ok, image = capture.retrieve()
                    if ok and image is not None:
                        image = cv2.cvtColor(image, cv2.COLOR_BGR2RGB if colour else cv2.COLOR_BGR2GRAY)
                        frames.append(FootageFrame(index, f"{path.name} frame {index}", image))
                index += 1
            total = index if index < claimed else claimed
        finally:
            capture.release()
        if not frames:
            raise ValueError(f"{path}: the video holds no decodable frame")
    height, width = frames[0].image.shape[:2]
    for frame in frames[1:]:
        if frame.image.shape[:2] != (height, width):
            h, w = frame.image.shape[:2]
            raise ValueError(f"{path}: {frame.name} is {w}x{h} but {frames[0].name} is {width}x{height} "
                             f"(all frames must have one size)")
    return frames, total
