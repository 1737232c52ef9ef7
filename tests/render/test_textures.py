"""Procedural textures: exact paint coverage, seamless tiling, determinism."""
import numpy as np

from visland.render import textures


def test_coverage_integrates_to_the_rectangle_area():
    x_edges = np.linspace(0.0, 10.0, 126)
    y_edges = np.linspace(-3.0, 3.0, 77)
    rect = np.array([[1.03, 7.71, -1.37, 0.94]])
    coverage = textures.coverage_of_rectangles(rect, x_edges, y_edges)
    texel_area = np.outer(np.diff(y_edges), np.diff(x_edges))
    assert abs(np.sum(coverage * texel_area) - (7.71 - 1.03) * (0.94 + 1.37)) < 1e-9
    assert coverage.max() == 1.0 and coverage.min() == 0.0


def test_tileable_noise_has_no_seam():
    field = textures.tileable_noise((256, 256), np.random.default_rng(1), beta=2.0)
    inside = np.abs(np.diff(field, axis=1)).mean()
    seam = np.abs(field[:, 0] - field[:, -1]).mean()
    assert seam < 1.5 * inside
    assert abs(field.mean()) < 1e-6 and abs(field.std() - 1.0) < 1e-3


def test_same_seed_same_texture_other_seed_other_texture():
    a = textures.grass_detail(np.random.default_rng([4, 2]), 128)
    b = textures.grass_detail(np.random.default_rng([4, 2]), 128)
    c = textures.grass_detail(np.random.default_rng([5, 2]), 128)
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    assert abs(a.mean() - 128) < 6   # detail textures are neutral grey on average
