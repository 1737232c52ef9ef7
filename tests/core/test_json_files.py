"""camera.json and runway.json: one loader each (CameraModel.load, Runway.load), one sentence per bad field.

Independent truth: the file written by the test, damaged in one field; the sentence must name the
file and that field (SPEC "Bad input"), and the file undamaged must load to the object saved.
"""
import json
import math

import pytest

from visland.camera import CameraModel
from visland.runway import Runway
from visland.scenarios import load_scenario_file


def _one_sentence(error, *parts):
    message = str(error.value)
    assert "\n" not in message.strip(), message
    for part in parts:
        assert part in message, message


def _refused_with(path, field, value, load, words):
    """``path`` (a JSON object that loads) with ``field`` set to ``value``: ``load`` refuses it in
    one sentence naming the file and holding ``words``."""
    data = json.loads(path.read_text())
    data[field] = value
    path.write_text(json.dumps(data))
    with pytest.raises(ValueError) as error:
        load(path)
    _one_sentence(error, str(path), words)


# ---------------------------------------------------------------- camera.json
@pytest.mark.parametrize("field, value, words", [
    ("width", "wide", "field 'width' must be an integer, got 'wide'"),
    ("height", 512.5, "field 'height' must be an integer, got 512.5"),
    ("fx", math.nan, "field 'fx' must be a finite number, got nan"),
    ("cy", True, "field 'cy' must be a finite number, got True"),
    ("mount_rpy_deg", [0.0, -5.0], "field 'mount_rpy_deg' must be a list of 3 numbers"),
    ("distortion", [0.1, "k2"], "field 'distortion'"),
])
def test_a_malformed_camera_field_is_one_sentence_naming_it(tmp_path, field, value, words):
    path = tmp_path / "camera.json"
    CameraModel.default(512).save(path)
    assert CameraModel.load(path).to_json_dict() == CameraModel.default(512).to_json_dict()
    _refused_with(path, field, value, CameraModel.load, words)


def test_the_input_camera_is_the_given_file_or_the_folders_own(tmp_path):
    (tmp_path / "given").mkdir()
    CameraModel.default(256).save(tmp_path / "camera.json")
    CameraModel.default(128).save(tmp_path / "given" / "camera.json")
    assert CameraModel.for_input(None, tmp_path).width == 256
    assert CameraModel.for_input(tmp_path / "given" / "camera.json", tmp_path).width == 128
    built = CameraModel.default(64)
    assert CameraModel.for_input(built, tmp_path) is built
    with pytest.raises(ValueError) as error:
        CameraModel.for_input(None, tmp_path / "given" / "nowhere")
    _one_sentence(error, f"{tmp_path / 'given' / 'nowhere' / 'camera.json'}: camera file not found (give --camera FILE)")


# ---------------------------------------------------------------- runway.json
@pytest.mark.parametrize("field, value, words", [
    ("width_m", "wide", "field 'width_m' must be a finite number of metres, got 'wide'"),
    ("length_m", None, "field 'length_m' must be a finite number of metres, got None"),
    ("aim_distance_m", True, "field 'aim_distance_m' must be a finite number of metres, got True"),
    ("heading_deg", math.inf, "field 'heading_deg' must be a finite number of degrees, got inf"),
    ("slope_pct", 5.0, "field 'slope_pct' must lie in [-2, 2], got 5"),
    ("width_m", 5.0, "field 'width_m' must lie in [10, 100], got 5"),
    ("aim_distance_m", 1200.0, "field 'aim_distance_m' must lie in [0, 1000], got 1200"),
])
def test_a_malformed_runway_field_is_one_sentence_naming_it(tmp_path, field, value, words):
    path = tmp_path / "runway.json"
    runway = Runway(length_m=2500.0, width_m=30.0, aim_distance_m=320.0, heading_deg=123.0, slope_pct=0.5)
    path.write_text(json.dumps(runway.to_json_dict()))
    assert Runway.load(path) == runway
    _refused_with(path, field, value, Runway.load, words)


def test_runway_json_needs_the_spec_fields_and_ignores_more(tmp_path):
    path = tmp_path / "runway.json"
    path.write_text(json.dumps({"length_m": 3000, "width_m": 45, "surface": "asphalt"}))
    with pytest.raises(ValueError) as error:
        Runway.load(path)
    _one_sentence(error, str(path), "missing field 'aim_distance_m' (needed: length_m, width_m, aim_distance_m)")
    path.write_text(json.dumps({"length_m": 3000, "width_m": 45, "aim_distance_m": 300, "surface": "asphalt"}))
    assert Runway.load(path) == Runway(3000.0, 45.0, 300.0)


def test_a_scenario_runway_table_is_read_by_the_same_loader(tmp_path):
    """The scenario's [runway] names the field with its table, as runway.json names it alone."""
    path = tmp_path / "s.toml"
    head = 'name = "s"\ndx_m = -5000.0\ndy_m = 0.0\ndgs_m = 0.0\ndpsi_deg = 0.0\n[runway]\n'
    path.write_text(head + 'width_m = "wide"\n')
    with pytest.raises(ValueError) as error:
        load_scenario_file(path)
    _one_sentence(error, str(path), "field 'runway.width_m' must be a finite number of metres, got 'wide'")
    path.write_text(head + 'size = "regional"\nwidth_m = 40.0\n')          # a named size, one field overridden
    assert load_scenario_file(path).runway == Runway(length_m=1800.0, width_m=40.0)
