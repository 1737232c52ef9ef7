"""visland fly (closed loop on the estimates) in its fast mode: exact features plus 1 px noise.

Independent truth: the flare law's closed form at its two ends, the certification window for
automatic landing (CS-AWO: main gear on the runway between 60 m and 823 m past the threshold),
and the same approach flown on the truth.
"""
import json
import math

import pytest

from visland.cli import main
from visland.datasets.fly import FlyOptions, fly
from visland.flight import FlareParams
from visland.scenarios import Scenario


def _short():
    """1.5 km out, 20 m right of the centreline, on the glide path: about 25 s of flight."""
    return Scenario("short", dx_m=-1500.0, dy_m=20.0, dgs_m=0.0, dpsi_deg=0.0, gamma_deg=-3.0)


def test_flare_law_starts_at_the_glide_sink_rate_and_ends_at_the_touchdown_sink_rate():
    flare = FlareParams(flare_height_m=15.0, touchdown_sink_mps=0.6)
    tan_gs = math.tan(math.radians(3.0))
    assert flare.hdot_order_mps(15.0, 72.0, tan_gs) == pytest.approx(-72.0 * tan_gs)
    assert flare.hdot_order_mps(0.0, 72.0, tan_gs) == pytest.approx(-0.6)


@pytest.fixture(scope="module")
def landings():
    return {truth: fly(_short(), FlyOptions(truth_guided=truth, seed=3)) for truth in (False, True)}


def test_vision_guided_landing_touches_down_in_the_window_near_the_truth_guided_one(landings):
    vision, truth = landings[False], landings[True]
    for run in (vision, truth):
        assert not run["go_around"], run["go_around_reason"]
        assert 60.0 <= run["touchdown_x_m"] <= 823.0
        assert abs(run["touchdown_y_m"]) <= 3.0
        assert 0.2 <= run["sink_rate_mps"] <= 1.5            # flared: the glide path's sink is 3.8 m/s
        assert [d["continue"] for d in run["decisions"]] == [True, True]
    assert abs(vision["touchdown_x_m"] - truth["touchdown_x_m"]) <= 60.0
    assert abs(vision["dh_err_100ft_m"]) < 1.0 and truth["dh_err_100ft_m"] == 0.0


def test_losing_the_runway_below_150_ft_is_a_go_around_at_100_ft():
    run = fly(_short(), FlyOptions(seed=3, detection_lost_below_ft=150.0))
    assert run["go_around"] and run["touchdown_x_m"] is None
    assert run["go_around_reason"].startswith("100 ft: runway found in 0%")


def test_fly_command_ends_with_one_json_line_and_refuses_a_line_observer(capsys, tmp_path):
    scenario = tmp_path / "short.toml"
    scenario.write_text('name = "short"\ndx_m = -1500.0\ndy_m = 20.0\ndgs_m = 0.0\ndpsi_deg = 0.0\ngamma_deg = -3.0\n')
    assert main(["fly", "--scenario", str(scenario), "--truth-guided"]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert {"touchdown_x_m", "touchdown_y_m", "sink_rate_mps", "go_around", "go_around_reason",
            "dh_err_100ft_m", "wall_s"} <= set(result)
    assert main(["fly", "--scenario", str(scenario), "--observer", "ekf-2l"]) == 2
    assert "two-point observer" in capsys.readouterr().err
