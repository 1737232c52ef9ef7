"""Track a frame source (a SPEC.md frame folder, or a video source) from a designation to the end.

This is what ``visland track DIR --out FILE`` (and ``visland process --source tracking``)
runs: read the frames in order, designate the points on the start frame (labelled
corners or pixel positions), step a :class:`~visland.tracking.PointTracker` through the frames
with the inertial attitude, optionally re-anchoring on a detector, and turn the steps into
``measurements.csv`` columns (:mod:`visland.tracking.measurements`). A frame that cannot be
read, or has another size than ``camera.json``, is recorded as skipped with its reason.
"""
from __future__ import annotations

import collections
import concurrent.futures
import math
import time
from dataclasses import dataclass

import numpy as np

from visland.folder import as_grey
from visland.runway import CORNER_NAMES
from visland.tracking.anchoring import AnchorObservation, detector_anchor_provider, labels_anchor_provider
from visland.tracking.measurements import (designation_from_labels, measurement_columns, parse_designation,
                                           steps_to_columns)
from visland.tracking.motion import Attitude
from visland.tracking.params import TrackerParams
from visland.tracking.tracker import PointTracker

__all__ = ["TrackRun", "track_source", "ANCHOR_SOURCES", "error_against_labels"]

ANCHOR_SOURCES = ("detector", "labels")


@dataclass
class TrackRun:
    """The outcome of :func:`track_source`.

    Attributes
    ----------
    steps : list of TrackStep or None
        One entry per frame of the source (None before the start frame).
    point_names : tuple of str
        The tracked points, in column order.
    columns : dict of str to ndarray
        The ``measurements.csv`` columns (SPEC units: pixels, radians, degrees).
    column_order : list of str
        The order of ``columns`` in the file.
    start_frame : int
        Index of the designation frame.
    params : TrackerParams
        The parameters the tracker ran with.
    anchor : str or None
        The anchor provider (``"detector"``, ``"labels"``) or None.
    flagged : list of (int, str)
        ``(frame, reason)`` of the frames that could not be used.
    analysis_s : float
        Seconds spent in the tracker and the anchor provider (not in decoding images).
    """

    steps: list
    point_names: tuple
    columns: dict
    column_order: list
    start_frame: int
    params: TrackerParams
    anchor: str | None
    flagged: list
    analysis_s: float


def _attitude(inertial, index):
    if inertial is None:
        return None
    return Attitude(float(inertial.roll_rad[index]), float(inertial.pitch_rad[index]),
                    float(inertial.heading_rad[index]))


def _frames(source, gray: bool = True):
    """``(index, image or None, reason)`` in order (grey, or RGB when not ``gray``), from a source
    with ``frames()`` or ``read_frame()``."""
    if callable(getattr(source, "frames", None)):
        yield from source.frames(gray=gray)
        return
    # decode a few frames ahead in threads (OpenCV releases the GIL while decoding)
    n = len(source)
    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
        pending = collections.deque(pool.submit(source.read_frame, i, gray) for i in range(min(4, n)))
        for index in range(n):
            image, reason = pending.popleft().result()
            if index + len(pending) + 1 < n:
                pending.append(pool.submit(source.read_frame, index + len(pending) + 1, gray))
            yield index, image, reason


def _anchor_provider(source, anchor, anchor_every, start, detections=None):
    if anchor is None:
        return None
    if anchor == "labels":
        if source.labels is None:
            raise ValueError(f"{_name(source)}: no labels.csv, so --anchor labels has nothing to anchor on")
        return labels_anchor_provider(source.labels, every_n=anchor_every)
    if anchor == "detector":
        if source.inertial is None:
            raise ValueError("--anchor detector needs telemetry (the detector uses the inertial roll and pitch)")
        detect = detector_anchor_provider(source.camera, source.inertial, detections=detections)

        def provider(index, image):
            if (index - start) % anchor_every:
                return AnchorObservation.nothing(f"detector run every {anchor_every} frames")
            return detect(index, image)
        return provider
    raise ValueError(f"--anchor must be one of {', '.join(ANCHOR_SOURCES)}, got {anchor!r}")


def _name(source) -> str:
    return str(getattr(source, "name", None) or getattr(source, "root", "input"))


def track_source(source, init: str | None = "labels", params: TrackerParams | None = None, anchor=None,
                 anchor_every: int = 1, start: int = 0, edge_points: int = 0, use_inertial: bool = True,
                 progress=None, anchor_detections=None) -> TrackRun:
    """Track the designated points through the frames of ``source``.

    Parameters
    ----------
    source : a :class:`visland.folder.FrameFolder`, or any frame source with ``len()``,
        ``times_s``, ``camera``, ``inertial`` (or None), ``labels`` (or None) and either
        ``frames(gray=True)`` yielding ``(index, image or None, reason)`` in order or
        ``read_frame(index)`` returning ``(image or None, reason)``.
    init : ``"labels"`` (the visible labelled corners of the start frame; also when None) or
        pixel positions ``"u,v;u,v"`` (see :func:`visland.tracking.measurements.parse_designation`).
    params : tracker parameters.
    anchor : None/False, ``"detector"``/True (re-anchor on
        :func:`visland.detection.detect_runway`) or ``"labels"`` (re-anchor on the exact
        labelled corners: a perfect detector, for studies).
    anchor_every : run the anchor provider every this many frames.
    start : index of the designation frame.
    edge_points : with ``init="labels"``, points added on each side edge.
    use_inertial : use the telemetry attitude (prediction, template warp, rigid check).
    progress : optional callable ``progress(frames_done, n_frames)``.
    anchor_detections : optional callable ``(frame_index) -> DetectionResult`` with ``anchor="detector"``:
        the detections of a :class:`visland.detection.DetectionSequence` run on the same frames
        (every frame, from ``start``), used instead of running the detector again (a campaign
        measuring detection and anchored tracking detects each frame once).
    """
    params = params or TrackerParams()
    anchor = {True: "detector", False: None}.get(anchor, anchor) if isinstance(anchor, bool) else anchor
    init = "labels" if init is None else init
    n = len(source)
    if isinstance(start, bool) or not isinstance(start, int) or not 0 <= start < n:
        raise ValueError(f"--start must be a frame index in [0, {n - 1}], got {start!r}")
    if isinstance(anchor_every, bool) or not isinstance(anchor_every, int) or anchor_every < 1:
        raise ValueError(f"--anchor-every must be a positive integer, got {anchor_every!r}")
    camera = source.camera
    if init == "labels":
        if source.labels is None:
            raise ValueError(f"{_name(source)}: no labels.csv, so --init labels cannot designate the corners "
                             "(give pixel positions: --init 'u,v;u,v')")
        designation = designation_from_labels(source.labels, start, edge_points=edge_points)
    else:
        if edge_points:
            raise ValueError("--edge-points needs --init labels (it places points between labelled corners)")
        designation = parse_designation(init)
    provider = _anchor_provider(source, anchor, anchor_every, start, anchor_detections)
    if provider is not None and not any(name in CORNER_NAMES for name, _ in designation):
        raise ValueError("anchoring re-anchors runway corners: designate at least one corner by name "
                         f"({', '.join(CORNER_NAMES)})")
    inertial = source.inertial if use_inertial else None

    tracker = PointTracker(camera, params)
    steps = [None] * n
    flagged = []
    analysis = 0.0
    # the detector takes colour frames (its chroma profile places the threshold); the tracker grey
    colour = anchor == "detector"
    for index, frame, reason in _frames(source, gray=not colour):
        if index < start:
            continue
        tic = time.perf_counter()
        image = as_grey(frame)
        if index == start:
            if image is None:
                raise ValueError(f"cannot designate on {reason}")
            steps[index] = tracker.start(image, designation, _attitude(inertial, index), frame_index=index)
            if provider is not None:
                # the designation frame is the detector's first frame too (its sequence then holds
                # the prior the detection source's holds: both see the same frames)
                provider(index, frame)
        elif image is None:
            steps[index] = tracker.skip(reason, frame_index=index)
            flagged.append((index, reason))
        else:
            observation = provider(index, frame) if provider is not None else None
            steps[index] = tracker.step(image, _attitude(inertial, index), observation, frame_index=index)
        analysis += time.perf_counter() - tic
        if progress is not None:
            progress(index + 1, n)
    names = tracker.point_names
    columns = steps_to_columns(steps, source.times_s, names, params.anchor_min_confidence,
                               run_source="anchored" if anchor else "tracking")
    return TrackRun(steps, names, columns, measurement_columns(names), start, params, anchor, flagged, analysis)


def error_against_labels(run: TrackRun, labels) -> dict:
    """Pixel distance between each measured corner and its label.

    Parameters
    ----------
    run : TrackRun
        The outcome of :func:`track_source`.
    labels : visland.contracts.Table
        The folder's ``labels.csv`` (exact corners, pixels, one row per frame).

    Returns
    -------
    dict of str to ndarray, shape (n_frames,)
        ``{corner: distance in pixels}`` for the tracked corners; NaN where the corner was not
        measured or not labelled visible.
    """
    out = {}
    for name in run.point_names:
        if name not in CORNER_NAMES:
            continue
        u = np.asarray(run.columns[f"{name}_u_px"], dtype=float)
        v = np.asarray(run.columns[f"{name}_v_px"], dtype=float)
        lu = np.asarray(labels[f"{name}_u_px"], dtype=float)
        lv = np.asarray(labels[f"{name}_v_px"], dtype=float)
        visible = np.asarray(labels[f"{name}_visible"], dtype=float) == 1
        error = np.hypot(u - lu, v - lv)
        error[~visible] = math.nan
        out[name] = error
    return out
