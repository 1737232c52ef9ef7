"""Scene variety (issue 11): seeded draws are reproducible and in range, marking sets are what
they say, and labels stay exact under the new scene options and lens distortion.

The geometric checks are independent of the label code: the camera looks straight down on the
threshold, so the runway's side edges and the threshold are straight image lines whose
positions follow from the pinhole model in closed form (``u = cx + fx y / h``,
``v = cy - fy x / h``); the rendered step is located to sub-pixel precision (peak of the
gradient, parabola through three samples) and compared with them.
"""
import math

import numpy as np
import pytest

from visland.camera import CameraModel
from visland.render.markings import runway_markings
from visland.render.params import MARKINGS, TAXIWAYS, SceneParams
from visland.render.variety import RUNWAY_LENGTH_RANGE_M, RUNWAY_WIDTH_RANGE_M, draw_variety
from visland.runway import Runway

#: Camera frame C from runway frame R for a camera looking straight down, runway forward up in the image.
R_DOWN = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def test_variety_draw_is_reproducible_and_within_the_issue_ranges():
    draws = [draw_variety(seed) for seed in range(60)]
    assert draw_variety(7) == draws[7]
    assert draw_variety(7).scene.to_dict() == draws[7].scene.to_dict()
    assert draws[7] != draws[8]
    lengths = np.array([d.runway_length_m for d in draws])
    widths = np.array([d.runway_width_m for d in draws])
    assert RUNWAY_LENGTH_RANGE_M[0] <= lengths.min() and lengths.max() <= RUNWAY_LENGTH_RANGE_M[1]
    assert RUNWAY_WIDTH_RANGE_M[0] <= widths.min() and widths.max() <= RUNWAY_WIDTH_RANGE_M[1]
    assert {d.scene.markings for d in draws} == set(MARKINGS)
    assert {d.scene.monochrome for d in draws} == {True, False}
    assert {d.scene.taxiways for d in draws} == set(TAXIWAYS)
    vis = np.array([d.scene.visibility_m for d in draws])
    assert 1500.0 <= vis.min() and vis.max() <= 30000.0 and vis.min() < 3000.0 and vis.max() > 15000.0
    assert all(d.scene.seed == seed for seed, d in enumerate(draws))


@pytest.mark.parametrize("field,value", [("markings", "zebra"), ("threshold_stripes", 5), ("threshold_stripes", 18),
                                         ("surroundings", "moon"), ("jpeg_quality", 2), ("vignetting", 0.9),
                                         ("monochrome", 1), ("lighting", "night")])
def test_bad_scene_options_name_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        SceneParams(**{field: value})


@pytest.mark.parametrize("stripes", [4, 8, 16])
@pytest.mark.parametrize("style", ["icao", "faa"])
def test_threshold_stripe_count_and_span(style, stripes):
    runway = Runway(length_m=2000.0, width_m=45.0)
    layout = runway_markings(runway, style, threshold_stripes=stripes)
    near = layout.of_kind("threshold")
    near = near[near[:, 0] < 100.0]
    assert len(near) == stripes
    half_span = np.abs(near[:, 2:]).max()
    if style == "icao":
        assert half_span == pytest.approx((45.0 - 6.0) / 2.0)   # to within 3 m of the edges
    else:
        assert half_span == pytest.approx(min(stripes * 1.75, 19.5))
        assert near[0, 1] - near[0, 0] == pytest.approx(45.7)


def test_marking_sets_none_side_stripes_and_pre_threshold_paint():
    runway = Runway(length_m=2500.0, width_m=30.0)
    assert len(runway_markings(runway, "none").rectangles_m) == 0
    assert len(runway_markings(runway, "icao", side_stripes=False).of_kind("side_stripe")) == 0
    assert len(runway_markings(runway, "icao").of_kind("side_stripe")) == 2
    for style, colour in (("displaced", "paint_white"), ("blast_pad", "paint_yellow")):
        layout = runway_markings(runway, style, pre_threshold_m=200.0)
        assert layout.pre_threshold_m == 200.0 and len(layout.polygons) >= 4
        for name, poly in layout.polygons:
            assert name == colour
            assert poly[:, 0].max() <= 0.0 and poly[:, 0].min() >= -200.0
            assert np.abs(poly[:, 1]).max() <= 15.0 + 1e-9
    assert len(runway_markings(runway, "displaced").of_kind("threshold_bar")) == 1


def _step(profile, expected, window=6):
    """Sub-pixel position of the strongest step of ``profile`` within ``window`` px of ``expected``."""
    grad = np.abs(np.diff(profile.astype(float)))          # grad[k] between samples k and k+1
    lo = max(1, int(round(expected)) - window)
    hi = min(len(grad) - 2, int(round(expected)) + window)
    k = lo + int(np.argmax(grad[lo:hi + 1]))
    a, b, c = grad[k - 1], grad[k], grad[k + 1]
    offset = 0.5 * (a - c) / (a - 2 * b + c) if (a - 2 * b + c) != 0 else 0.0
    return k + 0.5 + offset


def _render_down(params, runway, camera, height_m, x_m):
    from visland.render import FrameRenderer
    with FrameRenderer(params, camera, runway) as renderer:
        return renderer.render(np.array([x_m, 0.0, -height_m]), R_DOWN, frame_seed=1)


@pytest.mark.slow
@pytest.mark.parametrize("options,width", [
    (dict(markings="blast_pad", surroundings="snow", taxiways="near_threshold"), 23.0),
    (dict(markings="displaced", surroundings="sand", monochrome=True, second_runway=True), 60.0),
    (dict(markings="none", surface="concrete", surroundings="snow", lighting="overcast", vignetting=0.3), 40.0),
    (dict(markings="faa", surroundings="urban", lighting="dusk", threshold_stripes=16), 30.0),
])
def test_runway_edges_and_threshold_where_the_geometry_puts_them(options, width):
    camera = CameraModel.from_fov(384, 384, 40.0)
    runway = Runway(length_m=1500.0, width_m=width)
    h = 1.8 * width / math.tan(math.radians(20.0))           # the runway spans ~55 % of the image
    # no side stripes: on snow or sand the stripe's inner edge would be the strongest step
    params = SceneParams(noise_std=0.0, marking_wear=0.0, rubber_deposits=0.0, visibility_m=30000.0, msaa_samples=4,
                         side_stripes=False, **options)
    x_cam = 0.12 * h
    rgb = _render_down(params, runway, camera, h, x_cam)
    grey = rgb.astype(float).mean(axis=-1)
    # side edges, along rows from 52 m past the threshold (beyond the threshold stripes)
    v_threshold = camera.cy + camera.fy * x_cam / h          # x = 0 -> v = cy - fy (0 - x_cam) / h
    u_left = camera.cx - camera.fx * width / 2 / h
    u_right = camera.cx + camera.fx * width / 2 / h
    x_top = min(x_cam + 0.9 * camera.cy * h / camera.fy, 110.0)
    rows = (v_threshold - camera.fy * np.linspace(52.0, x_top, 6) / h).round().astype(int)
    left = [_step(grey[r], u_left) - u_left for r in rows]
    right = [_step(grey[r], u_right) - u_right for r in rows]
    assert np.max(np.abs(left)) < 0.5, left
    assert np.max(np.abs(right)) < 0.5, right
    if options["markings"] in ("blast_pad", "displaced"):
        # the threshold: pavement before it, so the step at x = 0 is pavement to pavement (or paint)
        cols = np.linspace(camera.cx + 0.05 * camera.fx * width / h, camera.cx + 0.12 * camera.fx * width / h,
                           4).round().astype(int)
        steps = [_step(grey[:, c], v_threshold, window=3) - v_threshold for c in cols]
        # measured -0.27 to -0.57 px on the blast pad (a low-contrast step between two textured
        # pavements, the gradient peak pulled by their grain), within 0.3 px on the displaced bar
        assert np.max(np.abs(steps)) < 0.75, steps


@pytest.mark.slow
def test_distorted_frame_is_the_pinhole_render_seen_through_the_lens():
    """Flat scene (white runway on black) through a barrel lens: the runway polygon of the pinhole
    labels, moved by CameraModel.distort_pixels, is white inside and black outside."""
    from visland.render import FrameRenderer
    runway = Runway(length_m=1500.0, width_m=45.0)
    camera = CameraModel.from_fov(320, 240, 60.0, distortion=(-0.2, 0.05, 0.001, -0.001, 0.0))
    h = 60.0
    p = np.array([25.0, 8.0, -h])
    with FrameRenderer(SceneParams.flat(), camera, runway) as renderer:
        rgb = renderer.render(p, R_DOWN)
    # pinhole pixels of a dense grid of runway points, inside and outside by 1.5 px
    step = h / camera.fx                                    # metres per pixel
    xs = np.linspace(-60.0, 120.0, 400)
    ys = np.linspace(-50.0, 50.0, 300)
    X, Y = np.meshgrid(xs, ys)
    inside = (X > 1.5 * step) & (np.abs(Y) < 22.5 - 1.5 * step)
    outside = (X < -1.5 * step) | (np.abs(Y) > 22.5 + 1.5 * step)
    points = np.stack([X, Y, np.zeros_like(X)], axis=-1) - p
    uv_pinhole, _ = camera.project(points @ R_DOWN.T)
    uv = camera.distort_pixels(uv_pinhole)
    ok = camera.in_image(uv, margin_px=1.0) & camera.in_image(uv_pinhole, margin_px=1.0)
    assert (ok & inside).sum() > 1000 and (ok & outside).sum() > 1000
    moved = np.abs(uv - uv_pinhole).max(axis=-1)
    assert moved[ok].max() > 5.0                           # the lens does move the runway
    iu, iv = np.rint(uv[..., 0]).astype(int), np.rint(uv[..., 1]).astype(int)
    values = np.where(ok, rgb[np.clip(iv, 0, 239), np.clip(iu, 0, 319), 0], 0)
    assert values[ok & inside].min() > 200
    assert values[ok & outside].max() < 55


@pytest.mark.slow
def test_sensor_options_monochrome_jpeg_and_same_seed_same_frame():
    from visland.render import FrameRenderer
    camera = CameraModel.from_fov(256, 256, 40.0)
    runway = Runway(length_m=1500.0, width_m=30.0)
    scene = draw_variety(11).scene
    from dataclasses import replace
    scene = replace(scene, monochrome=True, jpeg_quality=60, noise_std=3.0)
    p = np.array([0.0, 0.0, -150.0])
    with FrameRenderer(scene, camera, runway) as renderer:
        a = renderer.render(p, R_DOWN, frame_seed=3)
        b = renderer.render(p, R_DOWN, frame_seed=3)
    assert np.array_equal(a, b)
    assert np.array_equal(a[..., 0], a[..., 1]) and np.array_equal(a[..., 1], a[..., 2])
