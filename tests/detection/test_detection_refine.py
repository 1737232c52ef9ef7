"""Sub-pixel refinement against known truth: area-sampled synthetic edges and stripes at known
sub-pixel positions (each pixel the average of 16 x 16 samples of the ideal picture)."""
import math

import numpy as np
import pytest

from visland.detection import DetectorParams
from visland.detection.refine import NoFit, PixelLine, fit_line, refine_line


def area_sampled(size, grey_of, supersample=16, noise=0.0, seed=0):
    """Image whose pixel (u, v) (centred at integer u, v) averages grey_of(u', v') over its area."""
    offsets = (np.arange(supersample) + 0.5) / supersample - 0.5
    u = np.arange(size)[None, :, None, None] + offsets[None, None, None, :]
    v = np.arange(size)[:, None, None, None] + offsets[None, None, :, None]
    image = grey_of(np.broadcast_to(u, (size, size, supersample, supersample)),
                    np.broadcast_to(v, (size, size, supersample, supersample))).mean(axis=(2, 3))
    if noise:
        image = image + np.random.default_rng(seed).normal(0.0, noise, image.shape)
    return np.clip(image, 0, 255).astype(np.float32)


def signed_distance(u, v, point, angle):
    """Distance along the normal (-sin, cos) of the line through ``point`` at ``angle``."""
    return -(u - point[0]) * math.sin(angle) + (v - point[1]) * math.cos(angle)


TRUE_POINT = np.array([40.3, 31.7])
TRUE_ANGLE = math.radians(63.0)          # a slanted line: every sub-pixel phase occurs along it


def true_line():
    return PixelLine(TRUE_POINT, np.array([math.cos(TRUE_ANGLE), math.sin(TRUE_ANGLE)]))


def line_error_px(fit_line_, span=(-25, 25)):
    """Largest distance from the true line's points over ``span`` to the fitted line."""
    t = np.linspace(*span, 50)
    points = TRUE_POINT + t[:, None] * true_line().direction
    return float(np.abs(fit_line_.distance(points)).max())


def start_line(offset_px=2.0, turn_deg=1.5):
    """A wrong initial guess: shifted and turned."""
    angle = TRUE_ANGLE + math.radians(turn_deg)
    direction = np.array([math.cos(angle), math.sin(angle)])
    normal = np.array([-direction[1], direction[0]])
    return PixelLine(TRUE_POINT + offset_px * normal, direction)


def test_plain_step_is_located_to_a_few_hundredths_of_a_pixel():
    image = area_sampled(80, lambda u, v: np.where(signed_distance(u, v, TRUE_POINT, TRUE_ANGLE) > 0, 150.0, 80.0),
                         noise=1.5, seed=1)
    fit = refine_line(image, start_line(), (-25, 25), "edge", halfwidth_px=6, outward=1, outward_reach_px=1.5)
    assert fit, fit.reason
    assert fit.support > 0.9
    assert line_error_px(fit.line) < 0.05
    assert fit.residual_px < 0.2


@pytest.mark.parametrize("stripe_px, tolerance", [(4.0, 0.1), (2.0, 0.15), (0.5, 0.4)])
def test_boundary_past_a_painted_side_stripe(stripe_px, tolerance):
    """Grass (outside, +normal side) | white stripe | asphalt: the boundary is grass/stripe."""
    def grey(u, v):
        d = signed_distance(u, v, TRUE_POINT, TRUE_ANGLE)         # > 0 outside the runway
        return np.where(d > 0, 115.0, np.where(d > -stripe_px, 235.0, 84.0))

    image = area_sampled(80, grey, noise=1.5, seed=2)
    fit = refine_line(image, start_line(offset_px=-1.0), (-25, 25), "edge", halfwidth_px=6, outward=1,
                      outward_reach_px=max(1.5, 1.5 * stripe_px))
    assert fit, fit.reason
    assert line_error_px(fit.line) < tolerance


@pytest.mark.parametrize("width_px", [0.7, 3.0, 8.0])
def test_stripe_centre(width_px):
    def grey(u, v):
        return np.where(np.abs(signed_distance(u, v, TRUE_POINT, TRUE_ANGLE)) < width_px / 2, 220.0, 90.0)

    image = area_sampled(80, grey, noise=1.0, seed=3)
    fit = refine_line(image, start_line(offset_px=1.5), (-25, 25), "stripe", polarity=1, halfwidth_px=6 + width_px,
                      stripe_width_px=lambda t: np.full(np.shape(t), width_px + 3.0))
    assert fit, fit.reason
    assert line_error_px(fit.line) < 0.1


def test_line_fit_ignores_outliers():
    rng = np.random.default_rng(4)
    t = np.linspace(-30, 30, 120)
    points = TRUE_POINT + t[:, None] * true_line().direction + rng.normal(0, 0.1, (120, 1)) * true_line().normal
    points[::7] += 6.0 * true_line().normal                # markings beside the edge
    line, inliers, sigma = fit_line(points, np.ones(len(points)))
    assert line_error_px(line) < 0.05
    assert not inliers[::7].any() and inliers.sum() > 90
    assert sigma == pytest.approx(0.1, rel=0.3)


def test_no_edge_gives_no_fit_with_the_reason():
    flat = np.full((80, 80), 100.0, np.float32) + np.random.default_rng(5).normal(0, 1.0, (80, 80)).astype(np.float32)
    fit = refine_line(flat, start_line(), (-25, 25), "edge", halfwidth_px=6, outward=1, outward_reach_px=1.5,
                      params=DetectorParams(min_contrast=6.0))
    assert isinstance(fit, NoFit) and not fit
    assert "of at least 6 grey levels" in fit.reason, fit.reason
    # a span too short to sample says so
    short = refine_line(flat, start_line(), (0, 1), "edge", halfwidth_px=6)
    assert not short and "too short" in short.reason


@pytest.mark.parametrize("border", ["constant", "replicate"])
def test_remap_inside_reads_the_whole_frames_values(border):
    """Resampling a crop around the samples gives, at every sample inside the frame, the very
    float32 value ``cv2.remap`` reads off the whole frame converted to float32 (sub-pixel
    positions, samples on the frame's last row and column, a sample outside left to the caller)."""
    import cv2

    from visland.detection.refine import remap_inside
    rng = np.random.default_rng(3)
    image = rng.integers(0, 256, (60, 80), dtype=np.uint8)
    map_u = np.concatenate([rng.uniform(20.0, 45.0, 200), [79.0, 0.0, 33.5, -4.0]]).astype(np.float32)
    map_v = np.concatenate([rng.uniform(10.0, 30.0, 200), [12.25, 59.0, 59.0, 5.0]]).astype(np.float32)
    map_u, map_v = map_u.reshape(6, 34), map_v.reshape(6, 34)
    inside = (map_u >= 0) & (map_u <= 79) & (map_v >= 0) & (map_v <= 59)
    mode = cv2.BORDER_CONSTANT if border == "constant" else cv2.BORDER_REPLICATE
    whole = cv2.remap(image.astype(np.float32), map_u, map_v, cv2.INTER_LINEAR, borderMode=mode, borderValue=np.nan)
    cropped = remap_inside(image, map_u, map_v, inside, mode, np.nan)
    assert not inside.all() and inside.sum() == 6 * 34 - 1
    np.testing.assert_array_equal(cropped[inside], whole[inside])      # NaN (constant border) included
    assert cropped.dtype == np.float32 and cropped.shape == map_u.shape


NUMPY_2_4 = tuple(int(part) for part in np.__version__.split(".")[:2]) >= (2, 4)


def test_percentile_of_is_numpys_percentile_to_the_bit():
    """Float32 and float64 arrays, ties, a NaN, an infinity, the ends and arbitrary percentiles:
    the same number and type as np.percentile's linear interpolation (numpy 2.4's, to the bit;
    float32 arrays under an older numpy, whose weight is rounded to float32, within a few ulps)."""
    from visland.detection.refine import percentile_of
    rng = np.random.default_rng(5)
    for trial in range(600):
        values = (rng.standard_normal(int(rng.integers(1, 50))) * 10.0 ** rng.integers(-2, 3))
        values = values.astype(np.float32 if trial % 2 else np.float64)
        if trial % 5 == 0:
            values = np.round(values)
        if trial % 37 == 0:
            values[0] = np.nan
        if trial % 41 == 0:
            values[-1] = np.inf
        q = (90.0, 0.0, 100.0, 50, 99.0, float(rng.uniform(0.0, 100.0)))[trial % 6]
        with np.errstate(invalid="ignore"):
            expected, got = np.percentile(values, q), percentile_of(values, q)
        assert type(got) is type(expected)
        if values.dtype == np.float32 and not NUMPY_2_4:
            # numpy before 2.4 weights a float32 array's two order statistics by a float32 weight
            # (q / 100 rounded), up to tens of ulps from the float64 weight of numpy 2.4 and of
            # percentile_of: checked against the float64 percentile within a few float32 ulps
            with np.errstate(invalid="ignore"):
                expected = np.percentile(values.astype(np.float64), q)
            finite = np.abs(values[np.isfinite(values)])
            tolerance = 4.0 * float(np.spacing(np.float32(finite.max()))) if finite.size else 0.0
            assert (math.isnan(got) and math.isnan(expected)) or got == expected or \
                abs(float(got) - float(expected)) <= tolerance, (values, q)
            continue
        assert got == expected or (math.isnan(got) and math.isnan(expected)), (values, q)


def test_boundary_past_a_side_stripe_hidden_by_ground_as_bright_as_the_paint():
    """Sand as bright as the paint hides the side stripe's outer flank (the runway's edge) over
    most of the edge; where the sand is darker both flanks show. The stripe widens toward the
    near end (perspective, 2.4 to 5 px here). Mixed, the edge points lie on the boundary in one
    stretch and a stripe's width inside it in the next: the line must still be the boundary, not
    tilted between the two (as it is with the rule turned off: the test can fail)."""
    point, angle = np.array([60.3, 59.7]), math.radians(63.0)
    direction = np.array([math.cos(angle), math.sin(angle)])

    def stripe_px(t):
        return 3.7 + t / 30.0

    def grey(u, v):
        d = signed_distance(u, v, point, angle)               # > 0 outside the runway
        t = (u - point[0]) * direction[0] + (v - point[1]) * direction[1]
        hidden = np.floor((t + 100.0) / 9.0) % 5 < 3             # 60 % of the edge: sand = paint
        outside = np.where(hidden, 235.0, 150.0)
        return np.where(d > 0, outside, np.where(d > -stripe_px(t), 235.0, 84.0))

    image = area_sampled(120, grey, noise=1.5, seed=6)
    guess = PixelLine(point - 1.0 * np.array([-direction[1], direction[0]]), direction)

    def refined(params):
        return refine_line(image, guess, (-40, 40), "edge", halfwidth_px=6, outward=1,
                           outward_reach_px=lambda t: 1.5 + 1.3 * stripe_px(np.asarray(t)), params=params)

    t = np.linspace(-40, 40, 50)
    truth = point + t[:, None] * direction
    fit = refined(DetectorParams())
    assert fit, fit.reason
    assert np.abs(fit.line.distance(truth)).max() < 0.2
    assert fit.residual_px < 0.3
    without = refined(DetectorParams(hidden_stripe_min_fraction=1.0, hidden_stripe_min_px=100.0))
    assert not without or np.abs(without.line.distance(truth)).max() > 0.8
