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


def test_scoring_a_processed_run_finds_the_planted_errors(tmp_path):
    """A run folder written here with known errors: each figure is the planted worst error in its window."""
    import json

    from visland.contracts import MEASUREMENT_COLUMNS, write_csv
    from visland.estimation.dickmanns_study import score_wind_run
    n = 101
    t = np.arange(n) * 0.5                                     # 50 s
    dx = np.linspace(-4320.0, -320.0, n)                       # 4 km to the threshold
    dh = -dx * np.tan(np.radians(3.0)) + 10.0
    wy = np.where(t >= 40.0, 1.0 * np.exp(-(t - 40.0) / 6.0), -1.0)     # gust at 40 s
    zeros = np.zeros(n)
    write_csv(tmp_path / "truth.csv", {"t_s": t, "dx_m": dx, "dy_m": zeros, "dh_m": dh, "roll_deg": zeros,
                                       "pitch_deg": zeros, "dpsi_deg": zeros, "wind_y_runway_mps": wy},
              ["t_s", "dx_m", "dy_m", "dh_m", "roll_deg", "pitch_deg", "dpsi_deg", "wind_y_runway_mps"])
    from_2km = dx > -2320.0
    est_dx = dx - np.where(from_2km, 3.0, 50.0)                 # 3 m inside the window, 50 m outside
    est_dh = dh - np.where(from_2km, 0.4, 9.0)
    est_dy = np.where(from_2km, 0.2, 7.0)
    est_w = 45.0 + np.where(dx > -1320.0, 0.3, 5.0)
    est_wy = wy + np.where(t > 46.0, 0.05, 2.0)
    write_csv(tmp_path / "estimates.csv",
              {"observer": ["dickmanns-4d"] * n, "t_s": t, "dx_m": est_dx, "dy_m": est_dy, "dh_m": est_dh,
               "width_m": est_w, "dpsi_deg": zeros, "observability": zeros + 1.0, "wind_y_mps": est_wy},
              ["observer", "t_s", "dx_m", "dy_m", "dh_m", "width_m", "dpsi_deg", "observability", "wind_y_mps"])
    seen = np.arange(n) % 2 == 0                                # the threshold measured every other frame
    cols = {c: np.full(n, np.nan) for c in MEASUREMENT_COLUMNS}
    cols.update(frame=np.arange(n), t_s=t, found=np.ones(n), source=["detection"] * n, reason=[""] * n,
                confidence=np.ones(n), near_left_u_px=np.where(seen, 10.0, np.nan),
                near_left_v_px=np.where(seen, 10.0, np.nan), near_right_u_px=np.where(seen, 20.0, np.nan),
                near_right_v_px=np.where(seen, 10.0, np.nan))
    write_csv(tmp_path / "measurements.csv", cols, MEASUREMENT_COLUMNS)
    (tmp_path / "runway.json").write_text(json.dumps({"length_m": 3000.0, "width_m": 45.0, "aim_distance_m": 320.0}))
    figures = score_wind_run(tmp_path, echo=lambda line: None)
    assert figures["gust_onset_t_s"] == pytest.approx(40.0)
    row = figures["observers"]["dickmanns-4d"]
    assert row["dx_threshold_visible_m"] == pytest.approx(3.0)
    assert row["dh_from_2km_m"] == pytest.approx(0.4)
    assert row["dy_from_2km_m"] == pytest.approx(0.2)
    assert row["width_by_1km_m"] == pytest.approx(0.3)
    assert row["crosswind_after_gust_mps"] == pytest.approx(0.05)
    assert row["found_pct"] == pytest.approx(100.0)
