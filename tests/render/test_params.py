"""SceneParams: validation naming the field, JSON and TOML round trips."""
import pytest

from visland.render.params import SceneParams


def test_defaults_are_a_clear_day():
    params = SceneParams()
    assert params.style == "realistic" and params.visibility_m >= 20000 and params.cloud_cover < 0.5
    assert SceneParams.flat().style == "flat" and SceneParams.flat().noise_std == 0.0


@pytest.mark.parametrize("field, value", [
    ("visibility_m", 100.0), ("sun_elevation_deg", 95.0), ("noise_std", -1.0), ("marking_wear", 1.5),
    ("blur_sigma_px", float("nan")), ("anisotropy", 0.5), ("texel_m", 1.0), ("msaa_samples", 8),
    ("surface", "grass"), ("style", "cartoon"), ("seed", -1), ("distractors", "yes"),
])
def test_out_of_range_values_name_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        SceneParams(**{field: value})


@pytest.mark.parametrize("suffix", [".json", ".toml"])
def test_round_trip_through_files(tmp_path, suffix):
    params = SceneParams(seed=7, surface="concrete", marking_wear=0.6, sun_azimuth_deg=95.0, visibility_m=4000.0,
                         noise_std=3.0, blur_sigma_px=0.8, msaa_samples=4, distractors=False)
    path = tmp_path / f"scene{suffix}"
    params.save(path)
    assert SceneParams.load(path) == params


def test_unknown_key_and_bad_file_are_one_sentence(tmp_path):
    path = tmp_path / "scene.json"
    path.write_text('{"visibility": 5000}')
    with pytest.raises(ValueError, match="unknown scene parameter 'visibility'"):
        SceneParams.load(path)
    path.write_text("{not json")
    with pytest.raises(ValueError, match="not valid JSON"):
        SceneParams.load(path)
    toml = tmp_path / "scene.toml"
    toml.write_text("[scene]\nvisibility_m = 2000.0\n")
    assert SceneParams.load(toml).visibility_m == 2000.0
