"""Bad input: the detector says "not found" and why; it never raises and never guesses."""
import math

import numpy as np
import pytest

from tests.helpers.detection_frames import frame
from visland.camera import CameraModel
from visland.detection import DetectionResult, detect_runway

SIZE = 512
CAMERA = CameraModel.default(SIZE)
LEVEL = (0.0, math.radians(2.5))


def assert_not_found(result: DetectionResult, *words):
    assert isinstance(result, DetectionResult)
    assert not result.found
    assert result.confidence == 0.0
    assert np.isnan(result.corners_uv).all() and not result.corners_found.any()
    assert all(math.isnan(v) for line in result.lines.values() for v in line)
    assert math.isnan(result.dF_px) and math.isnan(result.dpsi_rad)
    reason = result.reason.lower()
    assert reason
    for word in words:
        assert word in reason, reason
    row = result.to_measurement_row(frame=3, t_s=0.12)
    assert row["found"] == 0 and row["reason"] == result.reason
    assert all(math.isnan(row[c]) for c in row if c.endswith(("_px", "_rho", "_rad", "_deg")))


@pytest.mark.parametrize("grey", [0, 255])
def test_black_and_white_frames(grey):
    assert_not_found(detect_runway(np.full((SIZE, SIZE), grey, np.uint8), CAMERA, *LEVEL), "contrast")


def test_noise_only_frame():
    rng = np.random.default_rng(7)
    noise = rng.integers(0, 256, (SIZE, SIZE), dtype=np.uint8)
    assert_not_found(detect_runway(noise, CAMERA, *LEVEL))


def test_smooth_noise_frame():
    rng = np.random.default_rng(8)
    import cv2
    noise = cv2.GaussianBlur(rng.normal(128, 40, (SIZE, SIZE)), (0, 0), 3.0)
    noise = np.clip(noise, 0, 255).astype(np.uint8)
    assert_not_found(detect_runway(noise, CAMERA, *LEVEL))


@pytest.mark.slow
def test_airport_without_its_runway():
    image, camera, state, _ = frame("thesis-1", 1200.0, size=SIZE, runway=False)
    assert_not_found(detect_runway(image, camera, float(state.roll_rad[0]), float(state.pitch_rad[0])))


@pytest.mark.parametrize("image, words", [
    (np.zeros((SIZE, SIZE + 8), np.uint8), ("camera",)),
    (np.zeros((SIZE, SIZE), np.float32), ("dtype",)),
    (np.zeros((SIZE, SIZE, 4), np.uint8), ("shape",)),
    (np.zeros((SIZE, SIZE, 3), np.uint8), ("contrast",)),        # a black RGB frame
    ([[0, 1], [2, 3]], ("list",)),
    (None, ("nonetype",)),
])
def test_wrong_frames(image, words):
    assert_not_found(detect_runway(image, CAMERA, *LEVEL), *words)


@pytest.mark.parametrize("roll, pitch, words", [
    (0.0, math.radians(-60.0), ("horizon",)),         # looking down steeply: horizon above the image
    (0.0, math.radians(60.0), ("horizon",)),          # looking up: only sky
    (math.nan, 0.04, ("attitude",)),
    (0.0, math.inf, ("attitude",)),
    ("level", 0.04, ("attitude",)),
])
def test_attitudes_that_do_not_allow_a_search(roll, pitch, words):
    image, camera, _, _ = frame("thesis-1", 1200.0, size=SIZE)
    assert_not_found(detect_runway(image, camera, roll, pitch), *words)


@pytest.mark.slow
def test_a_previous_result_that_was_not_found_means_acquisition():
    image, camera, state, _ = frame("thesis-8", 600.0, size=SIZE, concrete=True)
    lost = detect_runway(np.zeros_like(image), camera, 0.0, 0.04)
    result = detect_runway(image, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]), previous=lost)
    assert result.found and result.mode == "acquisition"


def test_programming_errors_raise_naming_the_argument():
    image = np.zeros((SIZE, SIZE), np.uint8)
    with pytest.raises(ValueError, match="camera"):
        detect_runway(image, "camera.json", 0.0, 0.0)
    with pytest.raises(ValueError, match="params"):
        detect_runway(image, CAMERA, 0.0, 0.0, params={"min_contrast": 3})
    with pytest.raises(ValueError, match="previous"):
        detect_runway(image, CAMERA, 0.0, 0.0, previous="last frame")
