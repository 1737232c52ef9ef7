"""DetectorParams: validation naming the field, JSON/TOML round trip, every field documented,
rescaling to the frame size."""
import dataclasses
import json

import pytest

from visland.camera import CameraModel
from visland.detection import DetectorParams
from visland.detection.params import NOT_SCALED_PX, SCALES_WITH_FOCAL, SCALES_WITH_SIZE


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
    # idempotent, made once per frame size, and back again
    assert half.scaled_to(1024) is half
    assert params.scaled_to(1024) is half and params.scaled_to(768) is not half
    assert half == dataclasses.replace(params, **{f.name: getattr(half, f.name) for f in dataclasses.fields(half)})
    assert half.scaled_to(2048).min_edge_length_px == pytest.approx(params.min_edge_length_px)
    with pytest.raises(ValueError, match="at least 16 px"):
        params.scaled_to(8)
    with pytest.raises(ValueError, match="CameraModel"):
        params.scaled_to("1024")


def test_every_pixel_length_scales_or_says_why_not():
    names = {f.name for f in dataclasses.fields(DetectorParams)}
    classified = set(SCALES_WITH_SIZE) | set(SCALES_WITH_FOCAL) | set(NOT_SCALED_PX)
    assert classified <= names
    assert not set(SCALES_WITH_SIZE) & set(SCALES_WITH_FOCAL)
    pixel_fields = {n for n in names if n.endswith(("_px", "_pxps")) or "_px_" in n}
    assert pixel_fields - classified == set()


def test_a_non_square_camera_scales_lengths_by_its_side_and_angles_by_its_focal_length():
    """1920x1080 behind a 62 deg lens: resolution lengths follow the 1920 px side (x0.94),
    angular ones the focal length (1598 px: x0.65), every one of them."""
    camera = CameraModel.from_fov(1920, 1080, 62.0)
    params = DetectorParams()
    scaled = params.scaled_to(camera)
    k_size, k_focal = 1920 / 2048, camera.fx / params.reference_focal_px
    assert k_focal == pytest.approx(0.6464, abs=1e-3)
    for name, floor in SCALES_WITH_SIZE.items():
        if floor is not None:
            assert getattr(scaled, name) == pytest.approx(max(floor, getattr(params, name) * k_size)), name
    for name, floor in SCALES_WITH_FOCAL.items():
        assert getattr(scaled, name) == pytest.approx(max(floor, getattr(params, name) * k_focal)), name
    assert scaled.acquisition_max_side_px == round(1024 * k_size)
    for name in NOT_SCALED_PX:
        if name not in ("reference_side_px", "reference_focal_px"):
            assert getattr(scaled, name) == getattr(params, name), name
    assert (scaled.reference_side_px, scaled.reference_focal_px) == (1920, pytest.approx(camera.fx))
    assert scaled.scaled_to(camera) is scaled
    # back to the reference camera: the unfloored lengths come back
    again = scaled.scaled_to(CameraModel.default(2048))
    assert again.roi_margin_px == pytest.approx(params.roi_margin_px)
    assert again.min_edge_length_px == pytest.approx(params.min_edge_length_px)


@pytest.mark.parametrize("field, value", [("pair_outside_band", (0.4, 0.12)), ("strip_side_band", (0.1,)),
                                          ("centre_stripe_sides", "wide"), ("hough_depth_bands", (0.3, 0.1)),
                                          ("low_contrast_hough_bands", (0.1, 1.5))])
def test_band_tuples_are_checked(field, value):
    with pytest.raises(ValueError, match=field):
        DetectorParams(**{field: value})


def test_the_low_contrast_look_scales_the_grey_level_thresholds_and_adds_bands():
    params = DetectorParams(min_contrast=8.0, surface_min_contrast=2.0, low_contrast_factor=0.25)
    faint = params.for_low_contrast()
    assert (faint.min_contrast, faint.surface_min_contrast) == (2.0, 0.5)
    assert faint.hough_depth_bands == params.low_contrast_hough_bands != params.hough_depth_bands
    assert faint.refine_samples == params.refine_samples
    # the confidence weighs a faint edge against the usual contrast scale
    assert faint.confidence_contrast_factor * faint.min_contrast == params.confidence_contrast_factor * params.min_contrast
    assert params.for_low_contrast() is faint                     # made once
    never = DetectorParams(low_contrast_factor=1.0)
    assert never.for_low_contrast() is never                      # 1: no second look
