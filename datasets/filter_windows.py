"""``visland process --windows dickmanns-4d``: the detector searches where the 4D filter expects the runway.

Seed 004 places its measurement windows by the filter's prediction. :class:`FilterWindows` runs
``dickmanns-4d`` alongside the detector, frame after frame: before frame k is detected, the
observer inputs are prepared from the telemetry and the measurements of frames 0..k-1 (frame k
itself not yet measured: :func:`visland.estimation.inputs.prepare_inputs`, whose heading, virtual
frame and mounting estimates are all causal, so the inputs up to frame k are those a whole run
would use), the filter is stepped to the step before frame k and predicts the runway at frame k
(:meth:`visland.estimation.dickmanns.Dickmanns4D.predicted_lines`); the prediction becomes the
detector's search window (:func:`visland.detection.predicted.prior_from_prediction`). Until the
filter has started (the first frame with both edges) and whenever it predicts nothing, the
detector uses its own window.

Cost: preparing the inputs again at every frame grows with the length of the run (about 0.1 s
per frame late in a 100 s approach on the reference machine); the filter itself is stepped once.
The estimates written by ``visland process`` are computed afterwards from the measurements, as
for every source.
"""
from __future__ import annotations

import math

import numpy as np

from visland.contracts import MEASUREMENT_COLUMNS, Table

__all__ = ["FilterWindows", "WINDOW_SOURCES"]

#: ``visland process --windows``: the detector's own prediction, or dickmanns-4d's.
WINDOW_SOURCES = ("detector", "dickmanns-4d")

_TEXT_COLUMNS = ("source", "reason")


class FilterWindows:
    """``dickmanns-4d`` run beside a detection sequence to place its search windows (module docstring).

    Parameters
    ----------
    source : FrameSource
        The frames' source (camera, ``times_s``, ``telemetry`` table).
    dh0_of_frame : callable
        ``dh0_of_frame(k)``: the initial height guess (m) when the filter starts at frame ``k``.
    self_calibration : str
        "off" or "apply": the mounting's self-calibration in the inputs (as ``prepare_inputs``).
    """

    def __init__(self, source, dh0_of_frame, self_calibration: str = "off"):
        from visland.estimation.dickmanns import Dickmanns4D
        from visland.estimation.inputs import InertialSeries
        from visland.estimation.registry import params_for_camera
        if source.telemetry is None:
            raise ValueError(f"{source.name}: --windows dickmanns-4d needs telemetry")
        self.camera = source.camera
        self.times_s = np.asarray(source.times_s, dtype=float)
        self.inertial = InertialSeries.from_table(source.telemetry)
        self.dh0_of_frame = dh0_of_frame
        self.self_calibration = self_calibration
        self.observer = Dickmanns4D(params_for_camera("dickmanns-4d", 0.5 * (self.camera.fx + self.camera.fy)))
        self.started = False
        self.rows: list[dict] = []
        self.n_predicted = 0

    def add(self, row: dict) -> None:
        """The measurement row of the frame just detected (``visland.contracts.MEASUREMENT_COLUMNS``)."""
        self.rows.append(row)

    def window(self, index: int):
        """The predicted runway at frame ``index`` (the next frame after those added), or None."""
        from visland.detection.predicted import prior_from_prediction
        from visland.estimation.inputs import FeatureSeries, prepare_inputs
        if index != len(self.rows):
            raise ValueError(f"FilterWindows: frame {index} asked after {len(self.rows)} frames were added")
        if not self.rows:
            return None
        pending = {c: math.nan for c in MEASUREMENT_COLUMNS}
        pending.update(frame=index, t_s=float(self.times_s[index]), source="detection", found=0,
                       reason="not measured yet", confidence=0.0)
        rows = self.rows + [pending]
        columns = {c: (np.array([str(r[c]) for r in rows], dtype=object) if c in _TEXT_COLUMNS
                       else np.array([r[c] for r in rows], dtype=float)) for c in MEASUREMENT_COLUMNS}
        features = FeatureSeries.from_table(Table(columns, None, list(MEASUREMENT_COLUMNS)))
        prepared = prepare_inputs(self.inertial, features, self.camera, self_calibration=self.self_calibration)
        steps = prepared.steps
        j_frame = int(prepared.step_of_frame[-1])
        if not self.started:
            start = prepared.first_step_with("lines")
            if start is None or start >= j_frame:
                return None
            self.observer.reset(steps[start], float(self.dh0_of_frame(int(prepared.frame_of_step[start]))))
            self.started = True
        t_now = self.observer.t_s
        for j in range(j_frame):
            if steps[j].t_s > t_now + 1e-9:
                self.observer.step(steps[j])
        inp = steps[j_frame]
        predicted = self.observer.predicted_lines(inp)
        prior = prior_from_prediction(self.camera, predicted["near_xy"], predicted["far_xy"], inp.roll_rad,
                                      inp.pitch_rad, predicted["dpsi_rad"], lines=predicted, source="dickmanns-4d")
        if prior.found:
            self.n_predicted += 1
        return prior
