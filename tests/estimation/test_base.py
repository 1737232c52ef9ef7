"""The observer interface's bad-input policy (estimation/base.py), on a real observer and a broken one."""
import math
from dataclasses import replace

import numpy as np
import pytest

from tests.helpers.estimation_sims import prepared
from visland.estimation.base import Estimate, Observer, observer_measurement
from visland.estimation.points import CCPIHG2P, PointsParams


def _first_two():
    prep = prepared()
    start = prep.first_step_with("points")
    return prep.steps[start], prep.steps[start + 1], prep.steps[start + 2]


def test_reset_refuses_a_non_positive_or_non_finite_height_guess():
    first, _, _ = _first_two()
    for bad in (0.0, -10.0, math.nan, math.inf):
        with pytest.raises(ValueError, match="dh0_m"):
            CCPIHG2P().reset(first, bad)


def test_reset_needs_a_measured_first_input():
    first, second, _ = _first_two()
    assert second.points_yv is None          # 50 Hz steps, 25 Hz frames: every other step is unmeasured
    with pytest.raises(ValueError, match="first input"):
        CCPIHG2P().reset(second, 250.0)


def test_step_before_reset_and_non_increasing_time_are_errors():
    first, second, _ = _first_two()
    with pytest.raises(ValueError, match="reset"):
        CCPIHG2P().step(second)
    observer = CCPIHG2P()
    observer.reset(first, 250.0)
    with pytest.raises(ValueError, match="time must increase"):
        observer.step(first)
    observer.step(second)
    with pytest.raises(ValueError, match="time must increase"):
        observer.step(replace(second, t_s=second.t_s - 0.01))


def test_wrong_shapes_and_non_finite_inertial_data_are_errors():
    first, second, third = _first_two()
    observer = CCPIHG2P()
    observer.reset(first, 250.0)
    with pytest.raises(ValueError, match="points_yv"):
        observer.step(replace(third, points_yv=np.zeros(3)))
    with pytest.raises(ValueError, match="v_runway_mps"):
        observer.step(replace(second, v_runway_mps=np.array([70.0, math.nan, 0.0])))
    with pytest.raises(ValueError, match="R_runway_from_camera"):
        observer.step(replace(second, R_runway_from_camera=np.eye(2)))
    with pytest.raises(ValueError, match="t_s"):
        observer.step(replace(second, t_s=math.inf))


def test_a_missing_or_non_finite_measurement_coasts_with_a_reason():
    first, second, third = _first_two()
    observer = CCPIHG2P()
    observer.reset(first, 250.0)
    est = observer.step(second)
    assert est.coasting and est.reason == "no measurement" and math.isfinite(est.dh_m)
    bad = third.points_yv.copy()
    bad[1, 0] = math.nan
    est = observer.step(replace(third, points_yv=bad))
    assert est.coasting and est.reason == "non-finite measurement"
    assert np.isfinite(est.state).all()


class _Exploding(Observer):
    """An observer whose maths breaks after two steps (to exercise the roll-back)."""

    name = "exploding"
    features = "points"
    params_type = PointsParams

    def _reset(self, first, dh0_m, measurement):
        self._x = np.array([1.0 / dh0_m])
        self._n = 0

    def _step(self, inp, dt_s, measurement):
        self._n += 1
        if self._n > 2:
            self._x = self._x * math.nan
        return Estimate(inp.t_s, 1.0 / float(self._x[0]), 1.0, measurement is None, self._x.copy())

    def _get_state(self):
        return self._x.copy()

    def _set_state(self, state):
        self._x = state.copy()


def test_a_state_turning_nan_is_rolled_back_and_flagged():
    prep = prepared()
    start = prep.first_step_with("points")
    observer = _Exploding()
    observer.reset(prep.steps[start], 200.0)
    estimates = [observer.step(prep.steps[start + k]) for k in range(1, 6)]
    assert [e.reason for e in estimates[2:]] == ["rejected: state diverged"] * 3
    assert all(e.dh_m == pytest.approx(200.0) and e.coasting for e in estimates[2:])
    assert all(np.isfinite(e.state).all() for e in estimates)


def test_params_round_trip_through_json_and_toml_and_name_unknown_keys(tmp_path):
    from visland.estimation.points import CCPIHGParams
    params = CCPIHGParams(response_time_s=8.0, damping=0.7)
    for suffix in (".json", ".toml"):
        path = tmp_path / f"p{suffix}"
        params.save(path)
        assert CCPIHGParams.load(path) == params
    with pytest.raises(ValueError, match="unknown observer parameter 'gain'"):
        CCPIHGParams.from_dict({"gain": 1.0})
    with pytest.raises(ValueError, match="damping"):
        CCPIHGParams(damping=1.5)
    with pytest.raises(ValueError, match="response_time_s"):
        CCPIHGParams(response_time_s=-1.0)


def test_observer_measurement_selects_the_feature_set():
    first, _, _ = _first_two()
    points, reason = observer_measurement(first, "points")
    assert points.shape == (2, 2) and reason == ""
    lines, _ = observer_measurement(first, "lines")
    assert lines.shape == (2, 2)
    empty = replace(first, lines=None)
    assert observer_measurement(empty, "lines") == (None, "no measurement")
