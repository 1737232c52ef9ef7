"""Self-calibration of the camera mounting (issue 12): checked against the simulator's known mounting
error and runway slope (independent truth: the camera that formed the pixels, runway.slope_pct)."""
from __future__ import annotations

import functools
import json
import math
from dataclasses import replace

import numpy as np
import pytest

from visland.estimation.calibration import (CalibrationParams, batch_R_body_from_camera, estimate_mount_error,
                                            mount_error_jacobian)
from visland.estimation.inputs import FeatureSeries, InertialSeries, _position_ned, prepare_inputs
from visland.estimation.metrics import run_metrics
from visland.estimation.registry import make_observer, observer_features
from visland.estimation.runner import run_observer
from visland.frames import R_body_from_camera
from visland.scenarios import get_scenario, with_runway
from visland.simulate import SimulationOptions, run_simulation


@functools.lru_cache(maxsize=4)
def _sim(scenario="thesis-1", mount_error_deg=(0.0, 0.0, 0.0), slope_pct=0.0, noise_px=0.0, seed=0):
    sc = get_scenario(scenario)
    sc = with_runway(sc, replace(sc.runway, slope_pct=slope_pct))
    return run_simulation(sc, SimulationOptions(pixel_noise_px=noise_px, calibration_error_deg=mount_error_deg,
                                                seed=seed))


def _calibrate(result, params=None):
    features = FeatureSeries.from_ideal(result.features)
    inertial = InertialSeries.from_imu(result.imu)
    at = inertial.at(features.t_s)
    return estimate_mount_error(features.t_s, features.near_uv_px, features.far_uv_px, at.roll_rad, at.pitch_rad,
                                at.heading_rad, _position_ned(inertial, features.t_s), result.options.camera, params)


def test_jacobian_is_the_derivative_of_the_mounting():
    mount = np.radians([1.0, -3.0, 2.0])
    J = mount_error_jacobian(mount)
    h = 1e-6
    for k in range(3):
        d = np.zeros(3)
        d[k] = h
        dR = (R_body_from_camera(mount + d) - R_body_from_camera(mount - d)) / (2 * h) @ R_body_from_camera(mount).T
        omega = np.array([dR[2, 1], dR[0, 2], dR[1, 0]])           # [omega]x = dR R^T
        assert np.allclose(omega, J[:, k], atol=1e-8)
    batch = batch_R_body_from_camera(np.stack([mount, mount * 0]))
    assert np.allclose(batch[0], R_body_from_camera(mount)) and np.allclose(batch[1], R_body_from_camera((0, 0, 0)))


@pytest.mark.slow
@pytest.mark.parametrize("error_deg, slope_pct", [((0.0, 0.5, 0.0), 0.0), ((0.5, -0.5, 0.3), 1.0),
                                                  ((-0.5, 0.0, 0.0), -1.0)])
def test_exact_measurements_recover_mount_error_and_slope(error_deg, slope_pct):
    result = _sim(mount_error_deg=error_deg, slope_pct=slope_pct)
    cal = _calibrate(result)
    dx = result.frames.p_runway_m[:, 0] - result.scenario.runway.aim_distance_m
    i = int(np.argmin(np.abs(dx + 1000.0)))                      # 1 km out
    assert np.degrees(cal.mount_error_rad[i]) == pytest.approx(error_deg, abs=0.01)
    assert cal.slope_pct[i] == pytest.approx(slope_pct, abs=0.01)
    assert cal.problem == "" and cal.applied
    # the uncertainty shrinks along the approach
    assert cal.sigma[i, 1] < cal.sigma[len(cal.t_s) // 4, 1] < math.radians(0.1)


@pytest.mark.slow
def test_one_px_noise_within_five_hundredths_of_a_degree_by_one_km():
    result = _sim(scenario="thesis-2", mount_error_deg=(0.5, -0.5, 0.0), slope_pct=1.0, noise_px=1.0, seed=3)
    cal = _calibrate(result)
    dx = result.frames.p_runway_m[:, 0] - result.scenario.runway.aim_distance_m
    i = int(np.argmin(np.abs(dx + 1000.0)))
    assert np.degrees(cal.mount_error_rad[i, :2]) == pytest.approx([0.5, -0.5], abs=0.05)
    assert cal.slope_pct[i] == pytest.approx(1.0, abs=0.2)


@pytest.mark.slow
def test_gross_misalignment_is_reported_not_absorbed():
    result = _sim(mount_error_deg=(0.0, 5.0, 0.0))
    cal = _calibrate(result)
    assert not cal.applied and "camera.json" in cal.problem and "pitch +5.0" in cal.problem
    assert cal.summary()["mount_error_deg"]["pitch"] == pytest.approx(5.0, abs=0.05)
    prep = prepare_inputs(InertialSeries.from_imu(result.imu), FeatureSeries.from_ideal(result.features),
                          result.options.camera, self_calibration="apply")
    assert not prep.calibration.applied


def _err_100ft(result, observer, mode):
    prep = prepare_inputs(InertialSeries.from_imu(result.imu), FeatureSeries.from_ideal(result.features),
                          result.options.camera, self_calibration=mode)
    dh = -result.frames.p_runway_m[:, 2]
    start = prep.first_step_with(observer_features(observer))
    run = run_observer(make_observer(observer), prep, 1.2 * dh[prep.frame_of_step[start]])
    return run_metrics(run.t_s, dh, run.dh_m, start_t_s=run.start_t_s)["err_100ft_m"], prep


@pytest.mark.slow
def test_applied_calibration_removes_the_height_error_of_a_pitched_camera():
    result = _sim(mount_error_deg=(0.0, 0.5, 0.0))
    err_check, prep_check = _err_100ft(result, "ccpi-hg-2p", "check")
    err_apply, prep_apply = _err_100ft(result, "ccpi-hg-2p", "apply")
    assert abs(err_check) > 10.0                       # thesis Table 5.10: tens of metres
    assert abs(err_apply) < 0.05
    # "check" reports without correcting; "apply" waits for the estimate to settle
    assert not prep_check.calibration.applied and prep_apply.calibration.applied
    first_check = prep_check.first_step_with("points")
    first_apply = prep_apply.first_step_with("points")
    assert first_apply > first_check
    frame = prep_apply.frame_of_step[first_apply] - 1
    assert prep_apply.frame_reason[frame] == "mounting self-calibration not settled yet"


def test_self_calibration_off_is_the_nominal_mounting():
    result = _sim()
    prep = prepare_inputs(InertialSeries.from_imu(result.imu), FeatureSeries.from_ideal(result.features),
                          result.options.camera)
    assert prep.calibration is None
    with pytest.raises(ValueError, match="self_calibration"):
        prepare_inputs(InertialSeries.from_imu(result.imu), FeatureSeries.from_ideal(result.features),
                       result.options.camera, self_calibration="yes")
    with pytest.raises(ValueError, match="pixel_sigma_px"):
        CalibrationParams(pixel_sigma_px=0.0)


@pytest.mark.slow
def test_estimate_command_reports_the_calibration(tmp_path, capsys):
    from visland.cli import main
    from visland.simulate import write_simulation
    folder = tmp_path / "sim"
    write_simulation(_sim(mount_error_deg=(0.0, 0.5, 0.0)), folder)
    out = folder / "estimates.csv"
    assert main(["estimate", str(folder), "--measurements", "ideal", "--observer", "ccpi-hg-2p",
                 "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "self-calibration: mount error" in printed and "reported only" in printed
    doc = json.loads((folder / "metrics.json").read_text())
    assert doc["self_calibration"]["mount_error_deg"]["pitch"] == pytest.approx(0.5, abs=0.01)
    assert doc["self_calibration"]["applied"] is False
    assert abs(doc["observers"]["ccpi-hg-2p"]["err_100ft_m"]) > 10.0
    assert main(["estimate", str(folder), "--measurements", "ideal", "--observer", "ccpi-hg-2p",
                 "--out", str(out), "--self-calibration", "--force"]) == 0
    doc = json.loads((folder / "metrics.json").read_text())
    assert doc["self_calibration"]["applied"] is True
    assert abs(doc["observers"]["ccpi-hg-2p"]["err_100ft_m"]) < 0.05
