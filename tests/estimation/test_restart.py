"""An observer is restarted after a long gap without measurements, from the dead-reckoned height.

Coasted open loop through a long gap, an observer whose height had not converged drifts, and the
first correction after it can throw it into the wrong basin (the robustness study's dusk
approach: 22.5 m off at 100 ft). The runner restarts it instead, at the first measurement more
than RESTART_AFTER_S after the last correction, from the last corrected height carried on with
the inertial vertical speed. Truth here is the flown height of thesis-1 (ideal measurements).
"""
import math
import re
from dataclasses import replace

import numpy as np
import pytest

from tests.helpers.estimation_sims import prepared, simulation, true_height
from visland.estimation.registry import make_observer, observer_features
from visland.estimation.runner import RESTART_AFTER_S, run_observer


def _with_gap(prep, t_from: float, t_to: float):
    """``prep`` without any image measurement at the steps in ``[t_from, t_to)``."""
    steps = [replace(s, points_yv=None, lines=None, center_line=None) if t_from <= s.t_s < t_to else s
             for s in prep.steps]
    return replace(prep, steps=steps)


def _run(observer: str, prep, restart_after_s: float = RESTART_AFTER_S):
    dh = true_height(simulation())
    start = prep.first_step_with(observer_features(observer))
    return run_observer(make_observer(observer), prep, 1.2 * dh[prep.frame_of_step[start]],
                        restart_after_s=restart_after_s)


def _first_measured_after(prep, t_s: float) -> float:
    return next(float(s.t_s) for s in prep.steps if s.t_s >= t_s and s.points_yv is not None)


@pytest.mark.parametrize("observer", ["ccpi-hg-2p", "ekf-2l"])
def test_a_long_gap_restarts_the_observer_at_the_dead_reckoned_height(observer):
    prep = prepared()
    dh = true_height(simulation())
    t0 = float(prep.frame_t_s[0])
    gap_from, gap_to = t0 + 25.0, t0 + 25.0 + RESTART_AFTER_S + 5.0
    gapped = _with_gap(prep, gap_from, gap_to)
    run = _run(observer, gapped)
    restart_t = _first_measured_after(gapped, gap_to)
    restarts = [n for n in run.notes if n.startswith("restarted")]
    assert len(restarts) == 1
    assert f"t = {restart_t:.2f} s" in restarts[0]
    # converged before the gap, so the height carried through it with the inertial vertical
    # speed is within a metre of the truth (the coasted frames are withheld meanwhile)
    frame = int(np.argmin(np.abs(run.t_s - restart_t)))
    carried = float(re.search(r"\(([\d.]+) m\)", restarts[0]).group(1))
    assert run.dh_m[frame] == pytest.approx(carried, abs=0.05)
    assert abs(carried - dh[frame]) < 1.0
    gap = (run.t_s > gap_from + 2.5) & (run.t_s < gap_to)
    assert gap.any() and np.isnan(run.dh_m[gap]).all()
    # and it converges again: within half a metre over the last second of the run
    last = run.t_s > run.t_s[-1] - 1.0
    assert np.nanmax(np.abs(run.dh_m[last] - dh[last])) < 0.5


def test_a_gap_shorter_than_the_restart_time_is_coasted_through_unchanged():
    prep = prepared()
    t0 = float(prep.frame_t_s[0])
    gapped = _with_gap(prep, t0 + 20.0, t0 + 20.0 + 0.5 * RESTART_AFTER_S)
    run = _run("ccpi-hg-2p", gapped)
    never = _run("ccpi-hg-2p", gapped, restart_after_s=math.inf)
    assert not [n for n in run.notes if n.startswith("restarted")]
    assert np.array_equal(run.dh_m, never.dh_m, equal_nan=True)


def test_an_unconverged_observer_coasted_through_a_long_gap_comes_back_when_restarted():
    # thesis-3 with 1 px of image noise, started 20 % high, two seconds of corners, then none
    # until 14 s before the end (the dusk approach's timeline): coasted through, the first
    # corrections after the gap leave it metres off at the end; restarted, it ends within
    # half a metre of the truth
    prep = prepared("thesis-3", 1.0)
    dh = true_height(simulation("thesis-3", 1.0))
    t0, t_end = float(prep.frame_t_s[0]), float(prep.frame_t_s[-1])
    gapped = _with_gap(prep, t0 + 2.0, t_end - 14.0)
    start = gapped.first_step_with("points")
    errors = {}
    for restart_after_s in (RESTART_AFTER_S, math.inf):
        run = run_observer(make_observer("ccpi-hg-2p"), gapped, 1.2 * dh[gapped.frame_of_step[start]],
                           restart_after_s=restart_after_s)
        last = run.t_s > t_end - 1.0
        errors[restart_after_s] = float(np.nanmax(np.abs(run.dh_m[last] - dh[last])))
        assert any(n.startswith("restarted") for n in run.notes) == math.isfinite(restart_after_s)
    assert errors[RESTART_AFTER_S] < 0.5
    assert errors[math.inf] > 1.0          # the failure the restart is for


def test_the_restart_time_must_be_positive():
    with pytest.raises(ValueError, match="restart_after_s"):
        _run("ccpi-hg-2p", prepared(), restart_after_s=0.0)
