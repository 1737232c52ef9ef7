"""Image measurements of a frame source: detection, tracking, anchored tracking or the labels.

Each function walks the frames in order (detection and tracking carry state from frame to
frame: the region of interest, the templates) while the source decodes ahead in a background
thread, and returns the ``measurements.csv`` columns (SPEC labels schema plus ``source``,
``found``, ``reason``, ``confidence``) and the frames that could not be used.
"""
from __future__ import annotations

import queue
import threading
import time
from dataclasses import dataclass, field

import numpy as np

from visland.contracts import LABEL_COLUMNS, MEASUREMENT_COLUMNS
from visland.folder import as_grey
from visland.progress import progress_bar

__all__ = ["Measurements", "measure", "measure_many", "parse_source", "SOURCES"]

SOURCES = ("detection", "tracking", "anchored", "ideal")


def parse_source(kind: str) -> tuple[str, str | None]:
    """``"tracking"`` or ``"tracking:every_frame"`` (a template update policy of
    :class:`visland.tracking.TrackerParams`) -> (source, policy or None).

    Parameters
    ----------
    kind : str
        ``--source`` value.

    Returns
    -------
    source : str
    policy : str or None
    """
    base, _, policy = str(kind).partition(":")
    if base not in SOURCES:
        raise ValueError(f"--source must be one of {', '.join(SOURCES)} (tracking and anchored may name a template "
                         f"update policy, e.g. tracking:every_frame), got '{kind}'")
    if policy:
        from visland.tracking.params import UPDATE_POLICIES
        if base not in ("tracking", "anchored"):
            raise ValueError(f"--source {kind}: only tracking and anchored take an update policy")
        if policy not in UPDATE_POLICIES:
            raise ValueError(f"--source {kind}: unknown update policy '{policy}' (known: {', '.join(UPDATE_POLICIES)})")
    return base, policy or None
_FEATURE_COLUMNS = [c for c in MEASUREMENT_COLUMNS if c not in ("frame", "t_s", "source", "found", "reason", "confidence")]


@dataclass
class Measurements:
    """Measurement rows of a run, with timing and the frames that could not be used.

    Attributes
    ----------
    source : str
        The measurement source.
    columns : dict
        ``measurements.csv`` columns, one value per frame.
    flagged : list of (int, str)
        ``(frame, reason)`` of unusable frames.
    analysis_s : float
        Seconds in the image analysis proper.
    wall_s : float
        Wall time including decoding, seconds.
    """

    source: str
    columns: dict
    flagged: list = field(default_factory=list)     # (frame, reason) of unusable frames
    analysis_s: float = 0.0                          # time in the image analysis proper
    wall_s: float = 0.0                              # wall time including decoding

    @property
    def n_frames(self) -> int:
        return len(self.columns["frame"])

    @property
    def n_found(self) -> int:
        return int(np.sum(self.columns["found"]))


class _Rows:
    """Accumulates one row per frame in the measurement schema."""

    def __init__(self, source: str):
        self.source = source
        self.rows: list[dict] = []

    def add(self, frame: int, t_s: float, values: dict | None, found: bool, reason: str, confidence: float):
        row = {c: np.nan for c in _FEATURE_COLUMNS}
        if values:
            row.update({k: v for k, v in values.items() if k in row})
        row.update(frame=frame, t_s=t_s, source=self.source, found=int(bool(found)), reason=reason,
                   confidence=confidence)
        self.rows.append(row)

    def columns(self) -> dict:
        return {c: [row[c] for row in self.rows] for c in MEASUREMENT_COLUMNS}


def _measure_ideal(source) -> Measurements:
    if source.labels is None:
        raise ValueError(f"{source.name}: --source ideal needs labels.csv in the input folder")
    labels = source.labels
    rows = _Rows("ideal")
    for i in range(labels.n_rows):
        values = {c: labels[c][i] for c in LABEL_COLUMNS if c in labels and c not in ("frame", "t_s")}
        for corner in ("near_left", "near_right", "far_left", "far_right"):
            if labels[f"{corner}_visible"][i] < 0.5:       # an ideal sensor only sees what is in the image
                values[f"{corner}_u_px"] = values[f"{corner}_v_px"] = np.nan
        rows.add(i, float(source.times_s[i]), values, True, "", 1.0)
    return Measurements("ideal", rows.columns())


def _measure_detection(source, params, quiet, windows=None, publish=None) -> Measurements:
    """``windows``: None (the detector's own search windows) or a
    :class:`visland.datasets.filter_windows.FilterWindows` that places them (its time counts as analysis);
    ``publish``: None or a :class:`_SharedDetections` that receives every frame's result."""
    from visland.detection import DetectionSequence
    sequence = DetectionSequence(source.camera, params)
    rows = _Rows("detection")
    flagged = []
    analysis = 0.0
    start = time.perf_counter()
    with progress_bar(len(source), "detect", enabled=not quiet) as bar:
        for index, image, reason in source.frames(gray=False):        # colour: the chroma places the threshold
            t = float(source.times_s[index])
            if image is None:
                rows.add(index, t, None, False, reason, 0.0)
                flagged.append((index, reason))
            else:
                tic = time.perf_counter()
                predicted = windows.window(index) if windows is not None else None
                result = sequence(image, float(source.inertial.roll_rad[index]),
                                  float(source.inertial.pitch_rad[index]), t, predicted=predicted)
                analysis += time.perf_counter() - tic
                if publish is not None:
                    publish.put(index, result)
                rows.add(index, t, result.to_measurement_row(), result.found, result.reason, result.confidence)
            if windows is not None:
                windows.add(rows.rows[-1])
            bar.update()
    return Measurements("detection", rows.columns(), flagged, analysis, time.perf_counter() - start)


def _measure_tracking(source, kind, init, quiet, detections=None) -> Measurements:
    """``detections``: None, or with anchored tracking a :class:`_SharedDetections` filled by the
    detection source measuring the same frames (the anchor reads them instead of detecting again)."""
    from visland.tracking import TrackerParams, track_source
    base, policy = parse_source(kind)
    params = TrackerParams(update_policy=policy) if policy else None
    start = time.perf_counter()
    with progress_bar(len(source), "track", enabled=not quiet) as bar:
        result = track_source(source, anchor=base == "anchored", init=init, params=params,
                              progress=lambda done, total: bar.update(done - bar.n),
                              anchor_detections=detections.get if detections is not None else None)
    return Measurements(kind, result.columns, result.flagged, result.analysis_s, time.perf_counter() - start)


def measure(source, kind: str = "detection", detector_params=None, init=None, quiet: bool = False,
            windows=None) -> Measurements:
    """Measure every frame of ``source`` with ``kind`` (one of :data:`SOURCES`); ``windows`` (detection
    only): a callable ``windows(source)`` giving what places the search windows (see
    :func:`_measure_detection`), or None.

    Parameters
    ----------
    source : visland.datasets.sources.FrameSource
        The frames, camera and telemetry.
    kind : str, default "detection"
        A measurement source (``tracking:POLICY`` accepted, :func:`parse_source`).
    detector_params : visland.detection.DetectorParams, optional
        For detection and anchored tracking.
    init : str, optional
        Tracking designation (``labels`` or ``"u,v;u,v"``).
    quiet : bool, default False
        No progress bar.
    windows : callable, optional
        As above.

    Returns
    -------
    Measurements
    """
    base, _ = parse_source(kind)
    if base == "ideal":
        return _measure_ideal(source)
    if source.inertial is None:
        raise ValueError(f"{source.name}: telemetry is needed to analyse frames (roll and pitch fix the horizon)")
    if base == "detection":
        return _measure_detection(source, detector_params, quiet, windows(source) if windows else None)
    return _measure_tracking(source, kind, init, quiet)


class _SharedDetections:
    """Each frame's :class:`visland.detection.DetectionResult` from the detection source's thread,
    for the anchored tracker's thread of the same :func:`measure_many` (both run the same
    :class:`visland.detection.DetectionSequence` on the same frames: the anchor reads the
    detection source's results instead of computing them again)."""

    def __init__(self):
        self._results: dict = {}
        self._error: BaseException | None = None
        self._changed = threading.Condition()

    def put(self, index: int, result) -> None:
        with self._changed:
            self._results[index] = result
            self._changed.notify_all()

    def fail(self, error: BaseException) -> None:
        """The detection thread stopped: every later :meth:`get` raises."""
        with self._changed:
            self._error = error
            self._changed.notify_all()

    def get(self, index: int):
        """Frame ``index``'s result, waiting for the detection thread (each is read once)."""
        with self._changed:
            while index not in self._results:
                if self._error is not None:
                    raise RuntimeError(f"frame {index}: the detection source stopped ({self._error})")
                self._changed.wait()
            return self._results.pop(index)


class _TeeSource:
    """One consumer's view of a source whose frames another thread decodes once for all."""

    def __init__(self, source, frames: queue.Queue):
        self._source = source
        self._frames = frames
        for name in ("name", "camera", "times_s", "inertial", "truth", "labels", "runway_json", "telemetry"):
            setattr(self, name, getattr(source, name, None))

    def __len__(self):
        return len(self._source)

    def frames(self, gray: bool = True, prefetch: int = 4):
        while True:
            item = self._frames.get()
            if item is None:
                return
            index, colour, reason, grey = item
            yield (index, grey if grey is not None else as_grey(colour), reason) if gray else (index, colour, reason)


class _Broadcast:
    """Hands each result to several :class:`_SharedDetections`."""

    def __init__(self, targets):
        self._targets = list(targets)

    def put(self, index: int, result) -> None:
        for target in self._targets:
            target.put(index, result)


def measure_many(source, kinds, init=None, quiet: bool = False, windows=None) -> dict:
    """Measure ``source`` with several ``kinds`` while decoding each frame once.

    One thread decodes; each kind consumes the frames in its own thread (OpenCV releases the
    GIL), so a campaign with detection, tracking and anchored tracking pays one decode per
    frame instead of three. Returns ``{kind: Measurements}``.

    Parameters
    ----------
    source : visland.datasets.sources.FrameSource
        The frames.
    kinds : sequence of str
        Measurement sources.
    init : str, optional
        Tracking designation.
    quiet : bool, default False
        No progress bar.
    windows : callable, optional
        As in :func:`measure`.
    """
    kinds = list(dict.fromkeys(kinds))
    if len(kinds) == 1 or all(kind == "ideal" for kind in kinds):
        return {kind: measure(source, kind, init=init, quiet=quiet, windows=windows) for kind in kinds}
    for kind in kinds:
        parse_source(kind)
    imaging = [k for k in kinds if k != "ideal"]
    queues = {k: queue.Queue(maxsize=8) for k in imaging}
    results: dict = {}
    errors: dict = {}

    # detection and anchored tracking run the same detector on the same frames: detect once
    # (not with windows placed by a filter: those differ from the anchor's own)
    anchored = [k for k in imaging if parse_source(k)[0] == "anchored"]
    shared = ({k: _SharedDetections() for k in anchored}
              if "detection" in imaging and windows is None and source.inertial is not None else {})

    def consume(kind):
        try:
            tee = _TeeSource(source, queues[kind])
            if kind == "detection" and shared:
                results[kind] = _measure_detection(tee, None, quiet or kind != imaging[0],
                                                   publish=_Broadcast(shared.values()))
            elif kind in shared:
                results[kind] = _measure_tracking(tee, kind, init, quiet or kind != imaging[0], shared[kind])
            else:
                results[kind] = measure(tee, kind, init=init, quiet=quiet or kind != imaging[0], windows=windows)
        except BaseException as error:          # re-raised in the caller after the decoder stops
            errors[kind] = error
            if kind == "detection":
                for detections in shared.values():
                    detections.fail(error)
            while queues[kind].get() is not None:   # keep draining so the decoder never blocks
                pass

    threads = [threading.Thread(target=consume, args=(k,), daemon=True) for k in imaging]
    for thread in threads:
        thread.start()
    # colour is decoded once; the grey levels the point trackers read are converted once too
    # (detection, anchored tracking included, reads colour)
    want_grey = any(parse_source(k)[0] == "tracking" for k in imaging)
    try:
        for index, image, reason in source.frames(gray=False):
            item = (index, image, reason, as_grey(image) if want_grey else None)
            for k in imaging:
                queues[k].put(item)
    finally:
        for k in imaging:
            queues[k].put(None)
        for thread in threads:
            thread.join()
    if errors:
        raise next(iter(errors.values()))
    if "ideal" in kinds:
        results["ideal"] = measure(source, "ideal")
    return {k: results[k] for k in kinds}
