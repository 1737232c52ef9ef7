"""``visland detect DIR --out FILE``: the detector over a frame folder (SPEC contract).

Reads the folder with :class:`visland.folder.FrameFolder` (frames in name order, their times,
telemetry interpolated at those times, the camera), detects the runway frame by frame (each
frame tracked from the last good detection, :class:`~visland.detection.sequence.DetectionSequence`;
the whole frame searched again after a loss longer than ``hold_s``) and writes ``measurements.csv`` in the labels schema plus ``source``, ``found``,
``reason`` and ``confidence`` (:data:`visland.contracts.MEASUREMENT_COLUMNS`). A frame that
cannot be used (unreadable, wrong size) is a row with ``found = 0`` and the reason; nothing
raises on a bad frame.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

from visland.contracts import MEASUREMENT_COLUMNS, write_csv
from visland.detection.params import DetectorParams
from visland.detection.result import not_found
from visland.detection.sequence import DetectionSequence
from visland.progress import progress_bar

__all__ = ["FolderDetection", "detect_folder", "write_measurements"]


@dataclass
class FolderDetection:
    """Rows of ``measurements.csv`` and a summary of a folder run.

    Attributes
    ----------
    rows : list of dict
        One :meth:`DetectionResult.to_measurement_row` per frame, in frame order.
    n_found : int
        Frames where the runway was found.
    n_unusable : int
        Frames that could not be read.
    n_tracking : int
        Found frames tracked from the previous frame.
    analysis_s : float
        Seconds spent detecting (reading frames excluded).
    wall_s : float
        Seconds for the whole run.
    """

    rows: list = field(default_factory=list)
    n_found: int = 0
    n_unusable: int = 0
    n_tracking: int = 0
    analysis_s: float = 0.0
    wall_s: float = 0.0

    def columns(self) -> dict:
        return {c: [row[c] for row in self.rows] for c in MEASUREMENT_COLUMNS}

    def summary(self) -> str:
        n = len(self.rows)
        rate = n / self.analysis_s if self.analysis_s > 0 else float("nan")
        return (f"{n} frames: runway found in {self.n_found} ({100.0 * self.n_found / max(n, 1):.1f} %), "
                f"{self.n_tracking} of them tracked from the previous frame; {self.n_unusable} unusable frames; "
                f"{rate:.1f} frames/s of detection ({self.wall_s:.1f} s in all)")


def detect_folder(folder, params: DetectorParams | None = None, progress: bool = True,
                  max_frames: int | None = None) -> FolderDetection:
    """Detect the runway in every frame of a :class:`visland.folder.FrameFolder`.

    Parameters
    ----------
    folder : FrameFolder
        The frames, their times, the telemetry (or none: the horizon is then read off each frame)
        and the camera.
    params : DetectorParams, optional
        Detector parameters (defaults: :class:`DetectorParams`), rescaled to the camera.
    progress : bool, optional
        Show a progress bar.
    max_frames : int, optional
        Detect only the first frames.

    Returns
    -------
    FolderDetection
    """
    params = params or DetectorParams()
    out = FolderDetection()
    sequence = DetectionSequence(folder.camera, params)
    start = time.perf_counter()
    n = len(folder) if max_frames is None else min(len(folder), max_frames)
    with progress_bar(n, "detect", enabled=progress) as bar:
        for index in range(n):
            _detect_one(folder, index, sequence, out)
            bar.update()
    out.wall_s = time.perf_counter() - start
    return out


def _detect_one(folder, index: int, sequence: DetectionSequence, out: FolderDetection) -> None:
    """One frame of :func:`detect_folder`: its row in ``out``."""
    t_s = float(folder.times_s[index])
    image, reason = folder.read_frame(index, gray=False)      # colour: the chroma places the threshold
    if image is None:
        result = not_found(reason)
        out.n_unusable += 1
    else:
        tic = time.perf_counter()
        if folder.inertial is None:      # no telemetry: the horizon is read off the frame
            roll, pitch = None, None
        else:
            roll, pitch = float(folder.inertial.roll_rad[index]), float(folder.inertial.pitch_rad[index])
        result = sequence(image, roll, pitch, t_s)
        out.analysis_s += time.perf_counter() - tic
    if result.found:
        out.n_found += 1
        out.n_tracking += result.mode == "tracking"
    out.rows.append(result.to_measurement_row(frame=index, t_s=t_s))


def write_measurements(result: FolderDetection, path) -> None:
    """Write ``measurements.csv`` atomically.

    Parameters
    ----------
    result : FolderDetection
        The rows to write.
    path : str or Path
        The CSV to write (its folder is created).
    """
    path = Path(path)
    if path.parent and not path.parent.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
    write_csv(path, result.columns(), MEASUREMENT_COLUMNS)
