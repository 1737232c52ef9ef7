"""Any frame rate (issue 12 item 2): the inertial data drive the prediction at 50 Hz, the frames
correct at their own times; exact measurements at 5 Hz must give the exact height at 100 ft."""
from __future__ import annotations

import functools

import pytest

from visland.estimation.inputs import FeatureSeries, InertialSeries, prepare_inputs
from visland.estimation.metrics import run_metrics
from visland.estimation.registry import make_observer, observer_features
from visland.estimation.runner import run_observer
from visland.scenarios import get_scenario
from visland.simulate import SimulationOptions, run_simulation


@functools.lru_cache(maxsize=2)
def _prepared(scenario: str, fps: float):
    result = run_simulation(get_scenario(scenario), SimulationOptions(fps=fps))
    prep = prepare_inputs(InertialSeries.from_imu(result.imu), FeatureSeries.from_ideal(result.features),
                          result.options.camera)
    return result, prep


@pytest.mark.slow
@pytest.mark.parametrize("observer", ["oj-2p", "ii-2p", "cccs-2p", "ccpi-hg-2p", "ccpi-hosm-2p", "kf-2p", "ecc-hg",
                                      "ecc-hosm", "ekf-2l", "cccj-2l"])
def test_five_hertz_exact_measurements_converge(observer):
    result, prep = _prepared("thesis-6", 5.0)
    dh = -result.frames.p_runway_m[:, 2]
    start = prep.first_step_with(observer_features(observer))
    run = run_observer(make_observer(observer), prep, 1.2 * dh[prep.frame_of_step[start]])
    assert abs(run_metrics(run.t_s, dh, run.dh_m, start_t_s=run.start_t_s)["err_100ft_m"]) < 0.05
