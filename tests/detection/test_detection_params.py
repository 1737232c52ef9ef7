"""DetectorParams: validation naming the field, JSON/TOML round trip, every field documented,
rescaling to the frame size."""
import dataclasses
import json

import pytest

from visland.detection import DetectorParams


def test_defaults_are_valid_and_frozen():
    params = DetectorParams()
    with pytest.raises(dataclasses.FrozenInstanceError):
        params.min_contrast = 3.0


@pytest.mark.parametrize("field, value", [
    ("canny_low_quantile", 0.0),
    ("canny_high_quantile", 1.5),
    ("hough_votes", 2.5),
    ("min_edge_support", -0.1),
    ("max_edge_slope", float("nan")),
    ("refine_iterations", 0),
    ("search_halfwidth_px", True),
])
def test_bad_values_raise_naming_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        DetectorParams(**{field: value})


def test_quantiles_must_be_ordered():
    with pytest.raises(ValueError, match="canny_low_quantile"):
        DetectorParams(canny_low_quantile=0.9, canny_high_quantile=0.8)


@pytest.mark.parametrize("suffix", [".json", ".toml"])
def test_round_trip_through_files(tmp_path, suffix):
    params = DetectorParams(min_contrast=4.5, hough_votes=25, max_width_change=0.3)
    path = tmp_path / f"detector{suffix}"
    params.save(path)
    assert DetectorParams.load(path) == params


def test_partial_file_and_unknown_key(tmp_path):
    path = tmp_path / "p.json"
    path.write_text(json.dumps({"min_contrast": 3.0}))
    assert DetectorParams.load(path).min_contrast == 3.0
    path.write_text(json.dumps({"min_contrats": 3.0}))
    with pytest.raises(ValueError, match="unknown detector parameter 'min_contrats'"):
        DetectorParams.load(path)
    with pytest.raises(ValueError, match="not found"):
        DetectorParams.load(tmp_path / "missing.toml")


def test_every_field_is_documented():
    doc = DetectorParams.__doc__
    for field in dataclasses.fields(DetectorParams):
        assert f"{field.name} :" in doc or f", {field.name} :" in doc or f"{field.name}, " in doc, field.name


def test_scaling_to_the_frame_size():
    params = DetectorParams()
    half = params.scaled_to(1024)
    assert half.reference_side_px == 1024
    assert half.min_edge_length_px == pytest.approx(params.min_edge_length_px / 2)
    assert half.roi_margin_px == pytest.approx(params.roi_margin_px / 2)
    # grey levels, ratios and counts do not scale
    assert (half.min_contrast, half.max_width_change, half.hough_votes) == \
        (params.min_contrast, params.max_width_change, params.hough_votes)
    # idempotent, and back again
    assert half.scaled_to(1024) is half
    assert half.scaled_to(2048).min_edge_length_px == pytest.approx(params.min_edge_length_px)
    with pytest.raises(ValueError, match="image_side_px"):
        params.scaled_to(8)
