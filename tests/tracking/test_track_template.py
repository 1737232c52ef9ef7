"""Template operations against known answers: planted patches, analytic sub-pixel shifts."""
import numpy as np
import pytest

from visland.tracking.template import (apply_homography, cut_reference, homography_jacobian, match_in_window,
                                       patch_texture, refine_translation, template_from_reference)


def smooth_scene(shape, shift_uv=(0.0, 0.0), seed=0):
    """Grey image of a sum of random Gaussian blobs evaluated at pixel centres minus a shift.

    Evaluating the continuous function at ``(u - du, v - dv)`` moves the content by exactly
    ``(du, dv)``: an independent sub-pixel truth.
    """
    rng = np.random.default_rng(seed)
    height, width = shape
    v, u = np.mgrid[0:height, 0:width].astype(float)
    u = u - shift_uv[0]
    v = v - shift_uv[1]
    image = np.full(shape, 90.0)
    for _ in range(int(width * height / 60)):
        cu, cv_ = rng.uniform(-10, width + 10), rng.uniform(-10, height + 10)
        sigma = rng.uniform(1.5, 4.0)
        image += rng.uniform(-60, 60) * np.exp(-((u - cu) ** 2 + (v - cv_) ** 2) / (2 * sigma ** 2))
    return np.clip(image, 0, 255).astype(np.uint8)


def test_cut_reference_is_the_pixels_around_the_point_with_its_offset():
    image = np.arange(50 * 60, dtype=np.uint8).reshape(50, 60)
    ref = cut_reference(image, (20.3, 10.6), 3)
    np.testing.assert_array_equal(ref.centre_px, [20, 11])
    np.testing.assert_allclose(ref.offset_px, [0.3, -0.4])
    np.testing.assert_array_equal(ref.pixels, image[8:15, 17:24])
    assert cut_reference(image, (2.0, 10.0), 3) is None        # template would cross the border


def test_planted_template_peaks_where_planted():
    rng = np.random.default_rng(1)
    image = rng.integers(60, 120, size=(120, 140)).astype(np.uint8)
    patch = rng.integers(0, 255, size=(15, 15)).astype(np.uint8)
    image[40:55, 70:85] = patch                          # centre pixel (77, 47)
    match = match_in_window(image, patch.astype(np.float32), (0.0, 0.0), (72.0, 51.0), 10, 0.5, 0.05, 3.0,
                            subpixel="parabola")
    assert match.found and match.score > 0.99
    np.testing.assert_allclose(match.uv, [77.0, 47.0], atol=0.02)


@pytest.mark.parametrize("method, tolerance", [("gradient", 0.03), ("parabola", 0.25)])
def test_known_subpixel_shift_is_measured(method, tolerance):
    before = smooth_scene((90, 90))
    shift = np.array([0.37, -0.71])
    after = smooth_scene((90, 90), shift_uv=shift)
    point = np.array([45.2, 44.6])
    ref = cut_reference(before, point, 10)
    template, offset = template_from_reference(ref, 21)
    match = match_in_window(after, template, offset, point + 1.0, 6, 0.5, 0.02, 3.0, subpixel=method)
    assert match.found
    assert np.hypot(*(match.uv - (point + shift))) < tolerance


def test_low_score_is_refused_with_its_reason():
    before = smooth_scene((80, 80), seed=2)
    other = np.random.default_rng(7).integers(0, 255, size=(80, 80)).astype(np.uint8)   # unrelated content
    ref = cut_reference(before, (40, 40), 8)
    template, offset = template_from_reference(ref, 17)
    match = match_in_window(other, template, offset, (40, 40), 8, 0.8, 0.02, 3.0)
    assert not match.found and "score" in match.reason
    assert np.all(np.isnan(match.uv))


def test_repeated_pattern_is_ambiguous_not_a_guess():
    u = np.arange(120)
    stripes = np.tile((128 + 80 * np.sin(2 * np.pi * u / 8.0)).astype(np.uint8), (60, 1))
    ref = cut_reference(stripes, (60, 30), 7)
    template, offset = template_from_reference(ref, 15)
    match = match_in_window(stripes, template, offset, (61, 30), 10, 0.5, 0.02, 3.0)
    assert not match.found and "ambiguous" in match.reason


def test_peak_beyond_the_search_window_is_refused_not_clamped():
    before = smooth_scene((100, 100), seed=4)
    after = smooth_scene((100, 100), shift_uv=(9.0, 0.0), seed=4)
    ref = cut_reference(before, (50, 50), 8)
    template, offset = template_from_reference(ref, 17)
    # true position 59; a window of +-5 around 50 cannot contain it
    match = match_in_window(after, template, offset, (50, 50), 5, 0.3, 0.0, 3.0)
    assert not match.found
    assert "border" in match.reason or "score" in match.reason


def test_texture_kinds():
    flat = np.full((21, 21), 100.0)
    assert patch_texture(flat, 1.5, 3.0).kind == "featureless"
    v, u = np.mgrid[0:21, 0:21]
    edge = np.where(u >= 10, 200.0, 60.0)
    texture = patch_texture(edge, 1.5, 3.0)
    assert texture.kind == "edge"
    np.testing.assert_allclose(np.abs(texture.normal), [1.0, 0.0], atol=1e-9)   # across the edge: along u
    corner = np.where((u >= 10) & (v >= 10), 200.0, 60.0)
    assert patch_texture(corner, 1.5, 3.0).kind == "corner"


def test_homography_jacobian_matches_finite_differences():
    H = np.array([[1.1, 0.2, 5.0], [-0.1, 0.9, -3.0], [1e-3, -2e-3, 1.0]])
    point = np.array([40.0, 25.0])
    J = homography_jacobian(H, point)
    h = 1e-5
    numeric = np.column_stack([(apply_homography(H, point + [h, 0]) - apply_homography(H, point - [h, 0])) / (2 * h),
                               (apply_homography(H, point + [0, h]) - apply_homography(H, point - [0, h])) / (2 * h)])
    np.testing.assert_allclose(J, numeric, rtol=1e-6, atol=1e-9)


def test_warped_template_predicts_a_zoomed_view():
    """Zoom by s about p: I2(x) = I1(p + (x - p) / s); the reference warped with A = I / s is I2 around p."""
    rng = np.random.default_rng(5)
    height = width = 120
    blobs = [(rng.uniform(0, width), rng.uniform(0, height), rng.uniform(3, 6), rng.uniform(-60, 60))
             for _ in range(250)]

    def scene(u, v):
        u, v = np.broadcast_arrays(u, v)
        out = np.full(u.shape, 100.0)
        for cu, cv_, sigma, amplitude in blobs:
            out += amplitude * np.exp(-((u - cu) ** 2 + (v - cv_) ** 2) / (2 * sigma ** 2))
        return out

    v, u = np.mgrid[0:height, 0:width].astype(float)
    p = np.array([60.3, 59.6])
    s = 1.2
    before = scene(u, v).astype(np.float32)
    expected = scene(p[0] + (u - p[0]) / s, p[1] + (v - p[1]) / s)
    ref = cut_reference(before, p, 17)
    template, offset = template_from_reference(ref, 21, np.eye(2) / s)
    np.testing.assert_allclose(offset, 0.0)
    grid = np.arange(21) - 10
    exact = scene(p[0] + grid[None, :] / s, p[1] + grid[:, None] / s)
    # the template is the zoomed view centred exactly on p (bilinear resampling error only)
    assert np.max(np.abs(template - exact)) < 0.03 * np.ptp(exact)
    match = match_in_window(expected.astype(np.float32), template, offset, p + 1.5, 5, 0.5, 0.02, 3.0)
    assert match.found and np.hypot(*(match.uv - p)) < 0.05


def test_refinement_leaves_an_edge_alone_along_it():
    v, u = np.mgrid[0:60, 0:60].astype(float)
    edge = (100 + 80 / (1 + np.exp(-(u - 30.25) / 1.2))).astype(np.float32)   # edge at u = 30.25, along v
    template = edge[20:41, 20:41]              # centred on (30, 30)
    start = np.array([30.2, 31.0])
    refined = refine_translation(edge, template, start)
    assert refined is not None
    assert abs(refined[0] - 30.0) < 0.02       # across the edge: found
    assert abs(refined[1] - 31.0) < 1e-6       # along the edge: unconstrained, unchanged
