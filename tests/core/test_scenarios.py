"""Scenarios: the seeds' tables and user TOML files with one clear error per bad field."""
import math

import pytest

from visland.scenarios import BUILTIN_SCENARIOS, get_scenario, load_scenario_file, resolve_scenario


def test_thesis_table_5_2():
    expected = {1: (-5000, 200, -25, 0), 2: (-6000, 200, -25, 0), 3: (-4000, 200, -25, 0), 4: (-5000, 400, -25, 0),
                5: (-5000, 200, -50, 0), 6: (-5000, 200, 50, 0), 7: (-5000, 200, -25, -15), 8: (-5000, 200, -25, 15)}
    for number, (dx, dy, dgs, dpsi) in expected.items():
        s = get_scenario(f"thesis-{number}")
        assert (s.dx_m, s.dy_m, s.dgs_m, s.dpsi_deg, s.gamma_deg, s.roll_deg) == (dx, dy, dgs, dpsi, 0.0, 0.0)
        assert s.airspeed_kt == 140.0


def test_ecc_table_1_with_the_seed_readme_sign_convention():
    # dY signs flipped from the table so that each heading deviation points back to the centreline
    expected = {1: (-5000, -200, -50, 15), 2: (-5000, 200, 50, 0), 3: (-4000, 550, 100, -15)}
    for number, (dx, dy, dgs, dpsi) in expected.items():
        s = get_scenario(f"ecc-{number}")
        assert (s.dx_m, s.dy_m, s.dgs_m, s.dpsi_deg, s.gamma_deg) == (dx, dy, dgs, dpsi, -3.0)
        if dpsi:
            assert math.copysign(1, dpsi) == -math.copysign(1, dy)


def test_initial_height_is_the_glide_path_plus_the_offset():
    s = get_scenario("thesis-1")
    assert s.initial_height_m == pytest.approx(5000 * math.tan(math.radians(3)) - 25)


def test_unknown_name_lists_the_known_ones():
    with pytest.raises(ValueError) as info:
        resolve_scenario("thesis-9")
    message = str(info.value)
    assert "thesis-9" in message and all(name in message for name in BUILTIN_SCENARIOS)


def test_user_scenario_file(tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text('name = "mine"\ndx_m = -4500.0\ndy_m = -120.0\ndgs_m = 10.0\ndpsi_deg = 4.0\n'
                    'gamma_deg = -3.0\n[runway]\nsize = "regional"\nheading_deg = 270.0\n'
                    '[wind]\ncrosswind_mps = 3.0\ngust = true\n')
    s = resolve_scenario(str(path))
    assert (s.name, s.dx_m, s.runway.width_m, s.runway.length_m, s.runway.heading_deg) == ("mine", -4500.0, 30.0, 1800.0, 270.0)
    assert s.wind.crosswind_mps == 3.0 and s.wind.gust


@pytest.mark.parametrize("body, match", [
    ('name = "x"\ndx_m = -5000.0\ndy_m = 0.0\ndgs_m = 0.0\n', "missing field 'dpsi_deg'"),
    ('name = "x"\ndx_m = -50.0\ndy_m = 0.0\ndgs_m = 0.0\ndpsi_deg = 0.0\n', "'dx_m' = -50 is out of range"),
    ('name = "x"\ndx_m = -5000.0\ndy_m = "far"\ndgs_m = 0.0\ndpsi_deg = 0.0\n', "'dy_m' must be a finite number"),
    ('name = "x"\ndx_m = -5000.0\ndy_m = 0.0\ndgs_m = 0.0\ndpsi_deg = 0.0\nspeed = 3\n', "unknown field 'speed'"),
    ('name = "x"\ndx_m = -5000.0\ndy_m = 0.0\ndgs_m = 0.0\ndpsi_deg = 0.0\n[runway]\nwidth_m = 500.0\n',
     "runway.width_m"),
    ('name = "x"\ndx_m = -5000.0\ndy_m = 0.0\ndgs_m = 0.0\ndpsi_deg = 0.0\n[wind]\ncrosswind_mps = 90.0\n',
     "wind.crosswind_mps"),
    ('name = "x"\ndx_m = -5000.0\ndy_m = 0.0\ndgs_m = 0.0\ndpsi_deg = \n', "not valid TOML"),
])
def test_bad_scenario_files_name_the_field(tmp_path, body, match):
    path = tmp_path / "bad.toml"
    path.write_text(body)
    with pytest.raises(ValueError, match=match) as info:
        load_scenario_file(path)
    assert str(path) in str(info.value)
    assert "\n" not in str(info.value).strip()


def test_round_trip_through_a_dictionary():
    from visland.scenarios import scenario_from_dict
    s = get_scenario("dickmanns-wind")
    assert scenario_from_dict(s.to_dict()) == s


def test_runway_slope_in_a_scenario_file_and_runway_json(tmp_path):
    from visland.runway import Runway
    path = tmp_path / "sloped.toml"
    path.write_text('name = "sloped"\ndx_m = -4500.0\ndy_m = 0.0\ndgs_m = 0.0\ndpsi_deg = 0.0\n'
                    '[runway]\nslope_pct = -0.8\n')
    s = resolve_scenario(str(path))
    assert s.runway.slope_pct == -0.8
    (tmp_path / "runway.json").write_text(__import__("json").dumps(s.runway.to_json_dict()))
    assert Runway.load(tmp_path / "runway.json") == s.runway
    path.write_text('name = "sloped"\ndx_m = -4500.0\ndy_m = 0.0\ndgs_m = 0.0\ndpsi_deg = 0.0\n'
                    '[runway]\nslope_pct = 3.0\n')
    with pytest.raises(ValueError, match="runway.slope_pct"):
        resolve_scenario(str(path))
