"""Inputs from a point tracker (corners only, no d_F) and long measurement gaps."""
import numpy as np

from tests.helpers.estimation_sims import simulation
from visland.estimation.inputs import FeatureSeries, InertialSeries, prepare_inputs
from visland.estimation.registry import make_observer
from visland.estimation.runner import run_observer


def _corners_only(features):
    """What a tracker gives: the four corners, no lines and no d_F."""
    return FeatureSeries(t_s=features.t_s, near_uv_px=features.near_uv_px,
                         lines=np.full_like(features.lines, np.nan), center_line=np.full_like(features.center_line, np.nan),
                         dF_px=np.full_like(features.dF_px, np.nan), points_ok=features.points_ok,
                         lines_ok=np.zeros_like(features.lines_ok), far_uv_px=features.far_uv_px)


def test_heading_from_the_vanishing_point_of_tracked_corners():
    result = simulation()
    inertial = InertialSeries.from_imu(result.imu)
    features = FeatureSeries.from_ideal(result.features)
    with_dF = prepare_inputs(inertial, features, result.options.camera)
    corners = prepare_inputs(inertial, _corners_only(features), result.options.camera)
    # the edges through exact corners meet at the exact vanishing point: same heading
    assert np.nanmax(np.abs(corners.dpsi_frame_rad - with_dF.dpsi_frame_rad)) < 1e-9
    assert corners.points_ok.sum() == with_dF.points_ok.sum() > 0
    assert not corners.lines_ok.any()


def test_without_heading_nothing_is_measured_and_the_reason_says_why():
    result = simulation()
    features = _corners_only(FeatureSeries.from_ideal(result.features))
    features.far_uv_px[:] = np.nan
    prep = prepare_inputs(InertialSeries.from_imu(result.imu), features, result.options.camera)
    assert not prep.points_ok.any()
    assert "neither d_F nor the four corners" in prep.frame_reason[0]


def test_estimates_are_withheld_after_a_long_gap_and_resume():
    result = simulation()
    features = FeatureSeries.from_ideal(result.features)
    gap = (features.t_s > 20.0) & (features.t_s < 25.0)
    features.points_ok = features.points_ok & ~gap
    features.near_uv_px[gap] = np.nan
    prep = prepare_inputs(InertialSeries.from_imu(result.imu), features, result.options.camera)
    run = run_observer(make_observer("ccpi-hg-2p"), prep, 1.2 * 280.0, max_coast_s=2.0)
    t = run.t_s
    coasted = (t > 20.0) & (t <= 22.0)
    withheld = (t > 22.05) & (t < 25.0)
    assert np.isfinite(run.dh_m[coasted]).all() and run.coasting[coasted].all()
    assert np.isnan(run.dh_m[withheld]).all()
    assert all("estimate withheld" in r for r in run.reason[withheld])
    after = t > 26.0
    assert np.isfinite(run.dh_m[after]).all()
