"""Deviations from dH and the features (against the flown truth) and the seeds' metrics (closed forms)."""
import math

import numpy as np
import pytest

from tests.helpers.estimation_sims import prepared, simulation, true_height, true_virtual_points
from visland.estimation.deviations import deviations_from_lines, deviations_from_points
from visland.estimation.metrics import aggregate_at_100ft, convergence_time_s, error_at_height, run_metrics


def test_deviations_from_the_threshold_corners_match_the_flight():
    result = simulation()
    yv = true_virtual_points(result)
    dh = true_height(result)
    p = result.frames.p_runway_m
    for k in (0, 700, 1500):
        dev = deviations_from_points(yv[k], dh[k])
        assert dev.dx_m == pytest.approx(p[k, 0] - 320.0, abs=1e-6)
        assert dev.dy_m == pytest.approx(p[k, 1], abs=1e-6)
        assert dev.width_m == pytest.approx(result.scenario.runway.width_m, abs=1e-6)


def test_deviations_from_the_edge_lines_match_the_flight():
    result = simulation()
    prep = prepared()
    dh = true_height(result)
    p = result.frames.p_runway_m
    for k in (10, 800, 1500):
        step = prep.steps[prep.step_of_frame[k]]
        dev = deviations_from_lines(step.lines, step.R_runway_from_camera, dh[k])
        assert math.isnan(dev.dx_m)
        assert dev.dy_m == pytest.approx(p[k, 1], abs=1e-4)
        assert dev.width_m == pytest.approx(result.scenario.runway.width_m, abs=1e-4)


def test_deviation_inputs_are_validated():
    with pytest.raises(ValueError, match="points_yv"):
        deviations_from_points(np.zeros(4), 100.0)
    with pytest.raises(ValueError, match="dh_m"):
        deviations_from_points(np.zeros((2, 2)), 0.0)


def test_convergence_time_is_the_start_of_the_last_stay_in_the_band():
    t = np.arange(0.0, 10.0, 0.5)
    truth = np.full_like(t, 100.0)
    est = 100.0 + 30.0 * np.exp(-t)         # inside 5 % once 30 e^-t <= 5, t >= ln 6 = 1.79 s
    assert convergence_time_s(t, truth, est) == pytest.approx(2.0)
    est[12] = 120.0                          # one excursion at t = 6 s
    assert convergence_time_s(t, truth, est) == pytest.approx(6.5)
    est[-1] = 120.0                          # out of the band at the end: never converged
    assert math.isnan(convergence_time_s(t, truth, est))
    assert convergence_time_s(t, truth, np.full_like(t, 101.0)) == 0.0


def test_error_at_height_interpolates_at_the_crossing():
    truth = np.array([150.0, 130.0, 110.0, 90.0])
    est = truth - np.array([1.0, 2.0, 3.0, 5.0])
    # 121.92 m lies 8.08/20 of the way from 130 to 110
    assert error_at_height(truth, est, 121.92) == pytest.approx(2.0 + 8.08 / 20.0)
    assert math.isnan(error_at_height(truth, est, 50.0))


def test_metrics_of_a_run_and_the_eight_run_aggregate():
    t = np.arange(0.0, 60.0, 0.04)
    truth = 250.0 - 4.0 * t
    est = truth * (1.0 - 0.001)
    m = run_metrics(t, truth, est)
    assert m["err_100ft_m"] == pytest.approx(0.001 * 30.48, rel=1e-6)
    assert m["conv_time_5pct_s"] == 0.0
    agg = aggregate_at_100ft([0.1, 0.3, math.nan])
    assert agg == {"mean_err_100ft_m": pytest.approx(0.2), "std_err_100ft_m": pytest.approx(0.1), "n_runs": 2,
                   "n_missing": 1}
    with pytest.raises(ValueError, match="increase"):
        run_metrics(t[::-1], truth, est)
