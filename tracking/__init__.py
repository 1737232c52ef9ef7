"""visland.tracking: a template point tracker (thesis 5.3.2.1, "Memo"), its drift, and its remedies.

A pilot designates points once (the runway corners); the tracker finds them again in every
frame by normalised cross-correlation around a predicted position. Re-cutting the template
from the new frame (the update policy) is what makes the thesis's drift; two remedies the
thesis names are built in: several points that must move as one rigid runway (a drifting one
shows), and re-anchoring on a detector's corners.

Public API::

    from visland.tracking import PointTracker, TrackerParams, Attitude
    tracker = PointTracker(camera, TrackerParams(update_policy="every_frame"))
    step = tracker.start(gray0, {"near_left": (u, v), "near_right": (u, v)}, attitude0)
    step = tracker.step(gray1, attitude1, anchor=None)      # TrackStep: per-point status, uv, score, reason

    run = track_source(FrameFolder(dir), init="labels", anchor=None)   # a whole folder -> run.columns

Modules (each one idea):

- :mod:`~visland.tracking.params`: :class:`TrackerParams` (the update policies are documented here).
- :mod:`~visland.tracking.template`: cut, texture, warp and match a template (pure functions).
- :mod:`~visland.tracking.motion`: inertial attitude, rotation prediction, virtual-to-pixel homography.
- :mod:`~visland.tracking.rigid`: do the points move as one rigid runway would? (drift detection)
- :mod:`~visland.tracking.anchoring`: anchor observations and providers (labels, detector).
- :mod:`~visland.tracking.tracker`: :class:`PointTracker`, the stateful tracker.
- :mod:`~visland.tracking.measurements`: tracker steps as ``measurements.csv`` rows; designations.
- :mod:`~visland.tracking.run`: track a frame folder or video source (``visland track``, ``visland process``).
- :mod:`~visland.tracking.synthetic`: flat textured world through a homography (tests, speed bench).
- :mod:`~visland.tracking.bench`: ``visland bench track``.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from visland.exports import lazy_exports

# Exports load on first use (visland.exports, PEP 562): ``visland.tracking.cli``, imported by the ``visland``
# command for every subcommand, must not pull in OpenCV and SciPy (0.3-0.4 s against 0.23 s
# for a whole ``visland scenarios``; see visland.detection). The imports below are the same
# names for readers and editors ("go to definition"); they are not executed.
if TYPE_CHECKING:
    from visland.tracking.anchoring import AnchorObservation
    from visland.tracking.motion import Attitude
    from visland.tracking.params import INCONSISTENT_ACTIONS, UPDATE_POLICIES, TrackerParams
    from visland.tracking.run import TrackRun, track_source
    from visland.tracking.tracker import MEASURED_STATUSES, POINT_STATUSES, PointReport, PointTracker, TrackStep

_EXPORTS = {
    "PointTracker": "visland.tracking.tracker", "TrackStep": "visland.tracking.tracker",
    "PointReport": "visland.tracking.tracker", "MEASURED_STATUSES": "visland.tracking.tracker",
    "POINT_STATUSES": "visland.tracking.tracker",
    "TrackerParams": "visland.tracking.params", "UPDATE_POLICIES": "visland.tracking.params",
    "INCONSISTENT_ACTIONS": "visland.tracking.params",
    "Attitude": "visland.tracking.motion",
    "AnchorObservation": "visland.tracking.anchoring",
    "track_source": "visland.tracking.run", "TrackRun": "visland.tracking.run",
}

__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
