"""Sensor noise and blur."""
import numpy as np
import pytest

from visland.render.sensor import NoiseBank, apply_blur


def test_noise_has_the_requested_spread_and_is_seeded_per_frame():
    bank = NoiseBank(64, 80, 4.0, seed=2)
    grey = np.full((64, 80, 3), 128, np.uint8)
    a = bank.apply(grey, frame_seed=1).astype(float) - 128
    b = bank.apply(grey, frame_seed=1).astype(float) - 128
    c = bank.apply(grey, frame_seed=2).astype(float) - 128
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    assert abs(a.std() - 4.0) < 0.3 and abs(a.mean()) < 0.3
    assert abs(np.corrcoef(a.ravel(), c.ravel())[0, 1]) < 0.1


def test_noise_saturates_instead_of_wrapping():
    bank = NoiseBank(32, 32, 10.0, seed=0)
    white = np.full((32, 32, 3), 255, np.uint8)
    out = bank.apply(white, 0)
    assert out.min() > 180 and out.max() == 255


def test_wrong_image_size_is_refused():
    with pytest.raises(ValueError, match="rgb must be"):
        NoiseBank(32, 32, 1.0, seed=0).apply(np.zeros((16, 32, 3), np.uint8), 0)


def test_blur_spreads_an_edge_and_keeps_the_mean():
    image = np.zeros((40, 40, 3), np.uint8)
    image[:, 20:] = 200
    blurred = apply_blur(image, 1.5)
    assert abs(blurred.astype(float).mean() - image.astype(float).mean()) < 0.5
    assert 0 < blurred[10, 19, 0] < 200 and 0 < blurred[10, 20, 0] < 200
    assert apply_blur(image, 0.0) is image
