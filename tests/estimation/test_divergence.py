"""A diverged observer is cut off and said to be (issue 19 item 3), never printed as a height.

Every observer projects eta = 1/dH onto [ETA_MIN, ETA_MAX]; a height pinned on that bound is the
projection hiding a correction outside the physical domain. The scripted observer below puts its
height where the test wants it, so the runner's bookkeeping is checked against a known timeline.
"""
import math

import numpy as np
import pytest

from tests.helpers.estimation_sims import prepared
from visland.estimation.base import ETA_MAX, ETA_MIN, Estimate, Observer
from visland.estimation.points import PointsParams
from visland.estimation.runner import DIVERGED_AFTER_S, on_domain_bound, run_observer


class _Scripted(Observer):
    """Height 200 m, except on the bound (20 km) during the ``pinned`` time intervals."""

    name = "scripted"
    features = "points"
    params_type = PointsParams
    pinned: tuple = ()

    def _reset(self, first, dh0_m, measurement):
        self._x = np.array([1.0 / dh0_m])
        self.calls = 0

    def _step(self, inp, dt_s, measurement):
        self.calls += 1
        on_bound = any(a <= inp.t_s < b for a, b in self.pinned)
        self._x = np.array([ETA_MIN if on_bound else 1.0 / 200.0])
        return Estimate(inp.t_s, 1.0 / float(self._x[0]), 1.0, measurement is None, self._x.copy())

    def _get_state(self):
        return self._x.copy()

    def _set_state(self, state):
        self._x = state.copy()


def test_the_bound_is_the_observers_projection_domain():
    assert on_domain_bound(1.0 / ETA_MIN) and on_domain_bound(1.0 / ETA_MAX)
    assert not on_domain_bound(19000.0) and not on_domain_bound(0.6) and not on_domain_bound(250.0)


def test_a_short_excursion_is_withheld_and_a_long_one_cuts_the_observer_off():
    prep = prepared()                                # thesis-1: about 65 s of frames
    t0 = float(prep.steps[prep.first_step_with("points")].t_s)
    short_end, long_start = t0 + 2.0 + 0.5 * DIVERGED_AFTER_S, t0 + 4.0 + 0.5 * DIVERGED_AFTER_S
    assert long_start + DIVERGED_AFTER_S < prep.frame_t_s[-1] - 5.0
    observer = _Scripted()
    observer.pinned = ((t0 + 2.0, short_end), (long_start, math.inf))
    run = run_observer(observer, prep, 200.0)
    t = run.t_s
    short = (t >= t0 + 2.0) & (t < short_end)
    assert short.any() and np.isnan(run.dh_m[short]).all() and run.coasting[short].all()
    assert all(str(r).startswith("height on the observer's domain bound") for r in run.reason[short])
    between = (t > short_end + 0.1) & (t < long_start)
    assert between.any() and np.allclose(run.dh_m[between], 200.0)      # it came back: estimates again
    # pinned for good: cut off, everything from the first pinned frame withheld
    first_pinned = float(t[t >= long_start][0])
    assert run.diverged_t_s == pytest.approx(first_pinned, abs=0.05)
    later = t >= run.diverged_t_s
    assert np.isnan(run.dh_m[later]).all() and np.isnan(run.width_m[later]).all()
    assert all(r == run.diverged for r in run.reason[later])
    assert "diverged" in run.diverged and "20000" in run.diverged
    assert not (run.dh_m >= 0.999 / ETA_MIN).any()                  # never printed as a height
    # cut off means no more steps: DIVERGED_AFTER_S past the first pinned step, not to the end
    steps_t = np.array([s.t_s for s in prep.steps])
    assert run.n_steps == observer.calls
    assert steps_t[prep.first_step_with("points") + run.n_steps] == pytest.approx(
        first_pinned + DIVERGED_AFTER_S, abs=0.05)


def test_an_observer_still_on_the_bound_at_the_end_is_reported_as_diverged():
    prep = prepared()
    end = float(prep.frame_t_s[-1])
    observer = _Scripted()
    observer.pinned = ((end - 0.5 * DIVERGED_AFTER_S, math.inf),)
    run = run_observer(observer, prep, 200.0)
    assert "to the end of the run" in run.diverged
    assert run.diverged_t_s == pytest.approx(end - 0.5 * DIVERGED_AFTER_S, abs=0.05)
    assert np.isnan(run.dh_m[run.t_s >= run.diverged_t_s]).all()
    assert np.isfinite(run.dh_m[(run.t_s >= run.start_t_s) & (run.t_s < run.diverged_t_s)]).all()


def test_an_observer_that_never_touches_the_bound_is_not_cut_off():
    run = run_observer(_Scripted(), prepared(), 200.0)
    assert run.diverged == "" and math.isnan(run.diverged_t_s)
    started = run.t_s >= run.start_t_s
    assert np.isfinite(run.dh_m[started]).all()
