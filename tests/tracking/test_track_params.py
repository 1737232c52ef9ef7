"""TrackerParams: validation naming the argument, file round trips, every field documented."""
import dataclasses

import pytest

from visland.tracking import TrackerParams


def test_defaults_are_valid_and_round_trip_through_json_and_toml(tmp_path):
    params = TrackerParams(update_policy="score_drop", template_size_px=15, scale_adaptation=False)
    for suffix in (".json", ".toml"):
        path = tmp_path / f"p{suffix}"
        params.save(path)
        assert TrackerParams.load(path) == params


@pytest.mark.parametrize("field, value, message", [
    ("template_size_px", 20, "must be odd"),
    ("template_size_px", 3, "template_size_px must be an integer"),
    ("update_policy", "sometimes", "update_policy must be one of"),
    ("min_score", 1.5, "min_score must be a number"),
    ("on_inconsistent", "ignore", "on_inconsistent must be one of"),
    ("scale_adaptation", 1, "scale_adaptation must be true or false"),
    ("subpixel", "spline", "subpixel must be"),
    ("search_radius_px", 2.5, "search_radius_px must be an integer"),
])
def test_bad_values_are_refused_naming_the_parameter(field, value, message):
    with pytest.raises(ValueError, match=message):
        TrackerParams(**{field: value})


def test_unknown_key_in_a_file_is_named(tmp_path):
    path = tmp_path / "p.json"
    path.write_text('{"template_size": 21}')
    with pytest.raises(ValueError, match="unknown tracker parameter 'template_size'"):
        TrackerParams.load(path)
    path = tmp_path / "p.yaml"
    path.write_text("")
    with pytest.raises(ValueError, match=".json or .toml"):
        TrackerParams.load(path)


def test_every_parameter_is_documented():
    doc = TrackerParams.__doc__
    for field in dataclasses.fields(TrackerParams):
        assert f"{field.name} :" in doc, field.name
