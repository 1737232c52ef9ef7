"""``visland study dickmanns`` (issue 16): its plumbing against independent truth.

- removing the airspeed changes nothing but ``tas_mps`` and makes ``dickmanns-4d`` say it runs
  without wind;
- the seed's wind case: the gust's onset found in the wind series is where the flown trajectory
  crosses 650 m before the threshold (the scenario's definition, read off the positions), the
  crosswind the study scores is the one the scenario defines (steady -1 m/s once decayed), and the
  plot is written.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from tests.helpers.estimation_sims import prepared, simulation
from visland.estimation.dickmanns import NO_AIRSPEED_NOTE
from visland.estimation.dickmanns_study import wind_case_figures, without_airspeed
from visland.estimation.registry import make_observer
from visland.estimation.runner import run_observer


def test_without_airspeed_removes_only_the_airspeed():
    prep = prepared("thesis-1")
    assert np.isfinite([s.tas_mps for s in prep.steps]).all()
    stripped = without_airspeed(prep)
    assert len(stripped.steps) == len(prep.steps)
    assert np.isnan([s.tas_mps for s in stripped.steps]).all()
    for a, b in zip(prep.steps[::500], stripped.steps[::500]):
        assert a.t_s == b.t_s
        np.testing.assert_array_equal(a.v_runway_mps, b.v_runway_mps)
        np.testing.assert_array_equal(a.R_runway_from_camera, b.R_runway_from_camera)
    result = simulation("thesis-1")
    start = stripped.first_step_with("lines")
    dh0 = 1.2 * -result.frames.p_runway_m[stripped.frame_of_step[start], 2]
    run = run_observer(make_observer("dickmanns-4d"), stripped, dh0)
    assert run.notes == [NO_AIRSPEED_NOTE]
    assert np.isnan(run.extras["wind_y_mps"]).all()


def test_the_command_line_offers_every_study():
    # the CLI lists the names statically (no import of the studies at start-up)
    from visland.estimation.cli import STUDY_NAMES
    from visland.estimation.study import STUDIES
    assert set(STUDY_NAMES) == set(STUDIES)
    assert "dickmanns" in STUDY_NAMES


@pytest.mark.slow
def test_wind_case_gust_onset_and_crosswind(tmp_path):
    lines = []
    figures = wind_case_figures(0, lines.append, tmp_path)
    from visland.estimation.study import Condition, simulate_case
    case = simulate_case("dickmanns-wind", Condition("1 px", pixel_noise_px=1.0), seed=0)
    tr = case.result.trajectory
    x = tr.p_runway_m[:, 0]
    crossing = float(np.interp(-650.0, x, tr.t_s))          # x increases along the approach
    assert figures["gust_onset_t_s"] == pytest.approx(crossing, abs=0.05)
    ours = figures["observers"]["dickmanns-4d"]
    assert ours["crosswind_after_gust_mps"] < 0.5
    assert figures["observers"]["dickmanns-4d no tas"]["crosswind_after_gust_mps"] is None
    assert figures["observers"]["dickmanns-4d no tas"]["notes"] == [NO_AIRSPEED_NOTE]
    assert math.isfinite(ours["dh_err_100ft_m"]) and abs(ours["dh_err_100ft_m"]) < 0.3
    assert figures["plots"] == [str(tmp_path / "dickmanns-wind.png")]
    assert (tmp_path / "dickmanns-wind.png").stat().st_size > 10_000
