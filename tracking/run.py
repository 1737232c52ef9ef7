"""Track a frame folder (SPEC.md folder contract) from a designation to the last frame.

This is what ``visland track DIR --out FILE`` runs: read the folder with
:class:`visland.folder.FrameFolder`, designate the points on the start frame (labelled
corners or pixel positions), step a :class:`~visland.tracking.PointTracker` through the frames
with the inertial attitude, optionally re-anchoring on a detector, and turn the steps into
``measurements.csv`` columns (:mod:`visland.tracking.measurements`). A frame that cannot be
read, or has another size than ``camera.json``, is recorded as skipped with its reason.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from visland.runway import CORNER_NAMES
from visland.tracking.anchoring import detector_anchor_provider, labels_anchor_provider
from visland.tracking.measurements import designation_from_labels, parse_designation, steps_to_columns
from visland.tracking.motion import Attitude
from visland.tracking.params import TrackerParams
from visland.tracking.tracker import PointTracker

__all__ = ["TrackRun", "track_folder", "ANCHOR_SOURCES", "error_against_labels"]

ANCHOR_SOURCES = ("detector", "labels")


@dataclass
class TrackRun:
    """The outcome of :func:`track_folder`.

    ``steps`` has one entry per frame of the folder (None before the start frame);
    ``columns`` the ``measurements.csv`` columns; ``column_order`` their order.
    """

    steps: list
    point_names: tuple
    columns: dict
    column_order: list
    start_frame: int
    params: TrackerParams
    anchor: str | None


def _attitude(folder, index):
    inertial = folder.inertial
    if inertial is None:
        return None
    return Attitude(float(inertial.roll_rad[index]), float(inertial.pitch_rad[index]),
                    float(inertial.heading_rad[index]))


def track_folder(folder, init: str = "labels", params: TrackerParams | None = None, anchor: str | None = None,
                 anchor_every: int = 1, start: int = 0, edge_points: int = 0, use_inertial: bool = True,
                 progress=None) -> TrackRun:
    """Track the points of ``folder`` (a :class:`visland.folder.FrameFolder`).

    Parameters
    ----------
    init : ``"labels"`` (the visible labelled corners of the start frame) or pixel positions
        ``"u,v;u,v"`` (see :func:`visland.tracking.measurements.parse_designation`).
    params : tracker parameters.
    anchor : None, ``"detector"`` (re-anchor on :func:`visland.detection.detect_runway`) or
        ``"labels"`` (re-anchor on the exact labelled corners: a perfect detector, for studies).
    anchor_every : run the anchor provider every this many frames.
    start : index of the designation frame.
    edge_points : with ``init="labels"``, points added on each side edge.
    use_inertial : use the telemetry attitude (prediction, template warp, rigid check).
    progress : optional callable ``progress(frame_index, n_frames)``.
    """
    params = params or TrackerParams()
    n = len(folder)
    if isinstance(start, bool) or not isinstance(start, int) or not 0 <= start < n:
        raise ValueError(f"--start must be a frame index in [0, {n - 1}], got {start!r}")
    if isinstance(anchor_every, bool) or not isinstance(anchor_every, int) or anchor_every < 1:
        raise ValueError(f"--anchor-every must be a positive integer, got {anchor_every!r}")
    camera = folder.camera
    if init == "labels":
        if folder.labels is None:
            raise ValueError(f"{folder.root / 'labels.csv'}: not found, so --init labels cannot designate the "
                             "corners (give pixel positions: --init 'u,v;u,v')")
        designation = designation_from_labels(folder.labels, start, edge_points=edge_points)
    else:
        if edge_points:
            raise ValueError("--edge-points needs --init labels (it places points between labelled corners)")
        designation = parse_designation(init, camera.width, camera.height)
    if anchor is None:
        provider = None
    elif anchor == "labels":
        if folder.labels is None:
            raise ValueError(f"{folder.root / 'labels.csv'}: not found, so --anchor labels has nothing to anchor on")
        provider = labels_anchor_provider(folder.labels, every_n=anchor_every)
    elif anchor == "detector":
        if folder.inertial is None:
            raise ValueError("--anchor detector needs telemetry (the detector uses the inertial roll and pitch)")
        detect = detector_anchor_provider(camera, folder.inertial)

        def provider(index, image):
            if (index - start) % anchor_every:
                from visland.tracking.anchoring import AnchorObservation
                return AnchorObservation.nothing(f"detector run every {anchor_every} frames")
            return detect(index, image)
    else:
        raise ValueError(f"--anchor must be one of {', '.join(ANCHOR_SOURCES)}, got {anchor!r}")
    if anchor is not None and not any(name in CORNER_NAMES for name, _ in designation):
        raise ValueError("anchoring re-anchors runway corners: designate at least one corner by name "
                         f"({', '.join(CORNER_NAMES)})")

    tracker = PointTracker(camera, params)
    steps = [None] * n
    image, problem = folder.read_frame(start)
    if image is None:
        raise ValueError(f"cannot designate on {problem}")
    attitude = _attitude(folder, start) if use_inertial else None
    steps[start] = tracker.start(image, designation, attitude, frame_index=start)
    for index in range(start + 1, n):
        image, problem = folder.read_frame(index)
        if image is None:
            steps[index] = tracker.skip(problem, frame_index=index)
        else:
            observation = provider(index, image) if provider is not None else None
            attitude = _attitude(folder, index) if use_inertial else None
            steps[index] = tracker.step(image, attitude, observation, frame_index=index)
        if progress is not None:
            progress(index, n)
    names = tracker.point_names
    columns = steps_to_columns(steps, folder.times_s, names, params.anchor_min_confidence)
    from visland.tracking.measurements import measurement_columns
    return TrackRun(steps, names, columns, measurement_columns(names), start, params, anchor)


def error_against_labels(run: TrackRun, labels) -> dict:
    """Pixel distance between each measured corner and its label: ``{corner: (n_frames,) array}``.

    NaN where the corner was not measured or not labelled visible.
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
