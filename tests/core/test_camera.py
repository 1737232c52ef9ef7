"""Camera model and line conventions, against hand computation."""
import json
import math

import numpy as np
import pytest

from visland.camera import CameraModel, intersect_lines, line_through_points, wrap_line_chart


def test_default_camera_matches_spec():
    cam = CameraModel.default()
    assert (cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy) == (2048, 2048, 2472.0, 2472.0, 1023.5, 1023.5)
    # 45 deg field of view: the image edge is at tan(22.5 deg) in normalised coordinates (to 0.1 %)
    assert (2048 / 2) / cam.fx == pytest.approx(math.tan(math.radians(22.5)), rel=1e-3)


def test_projection_of_a_point_on_the_axis_is_the_principal_point():
    cam = CameraModel.default(512)
    uv, in_front = cam.project([0.0, 0.0, 10.0])
    np.testing.assert_allclose(uv, [255.5, 255.5])
    assert in_front


def test_points_behind_the_camera_are_not_projected():
    uv, in_front = CameraModel.default().project([[1.0, 2.0, -5.0]])
    assert not in_front[0] and np.isnan(uv).all()


def test_pixel_normalised_round_trip():
    cam = CameraModel(640, 480, 500.0, 510.0, 320.2, 239.7)
    uv = np.array([[0.0, 0.0], [639.0, 479.0], [100.25, 400.5]])
    np.testing.assert_allclose(cam.normalized_to_pixels(cam.pixels_to_normalized(uv)), uv, atol=1e-12)


def test_line_chart_wrap():
    rho, theta = wrap_line_chart([0.3, 0.3, -0.2], [math.pi - 0.1, -math.pi / 2 - 0.1, 0.4])
    np.testing.assert_allclose(theta, [-0.1, math.pi / 2 - 0.1, 0.4])
    np.testing.assert_allclose(rho, [-0.3, -0.3, -0.2])
    assert np.all((theta >= -math.pi / 2) & (theta < math.pi / 2))


def test_line_through_points_contains_both_points():
    a, b = np.array([0.1, -0.2]), np.array([-0.05, 0.3])
    rho, theta = line_through_points(a, b)
    for p in (a, b):
        assert p[0] * math.cos(theta) + p[1] * math.sin(theta) == pytest.approx(rho, abs=1e-15)


def test_intersection_of_two_lines():
    p = np.array([0.02, -0.07])
    l1 = line_through_points(p, [0.5, 0.4])
    l2 = line_through_points(p, [-0.3, 0.9])
    np.testing.assert_allclose(intersect_lines(*l1, *l2), p, atol=1e-14)


def test_pixel_hough_conversion_keeps_points_on_the_line():
    cam = CameraModel(800, 600, 700.0, 650.0, 401.3, 298.8)
    # pixel line u cos t + v sin t = r through two known pixels
    p1, p2 = np.array([120.0, 30.0]), np.array([500.0, 580.0])
    d = p2 - p1
    t = math.atan2(d[0], -d[1])
    r = p1[0] * math.cos(t) + p1[1] * math.sin(t)
    rho, theta = cam.line_from_pixel_hough(r, t)
    for p in (p1, p2):
        x, y = cam.pixels_to_normalized(p)
        assert x * math.cos(theta) + y * math.sin(theta) == pytest.approx(float(rho), abs=1e-12)
    # and back to pixel space: same line, distance of both pixels zero
    np.testing.assert_allclose(cam.line_distance_px(rho, theta, np.stack([p1, p2])), 0.0, atol=1e-9)


def test_json_round_trip_and_bad_fields(tmp_path):
    cam = CameraModel.default(1024, mount_rpy_deg=(0.5, -4.0, 1.0))
    path = tmp_path / "camera.json"
    cam.save(path)
    again = CameraModel.load(path)
    assert again.width == cam.width and again.fx == cam.fx and again.cx == cam.cx
    np.testing.assert_allclose(again.mount_rpy_rad, cam.mount_rpy_rad, atol=1e-15)
    data = json.loads(path.read_text())
    del data["fy"]
    path.write_text(json.dumps(data))
    with pytest.raises(ValueError, match="missing field 'fy'"):
        CameraModel.load(path)
    data["fy"] = "wide"
    path.write_text(json.dumps(data))
    with pytest.raises(ValueError, match="'fy' must be a finite number"):
        CameraModel.load(path)


@pytest.mark.parametrize("kwargs, match", [
    (dict(width=0), "width"), (dict(fx=-1.0), "fx"), (dict(cx=5000.0), "cx"),
    (dict(mount_rpy_rad=(0.0, 0.0)), "mount_rpy_rad"),
])
def test_invalid_camera_is_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        CameraModel(**kwargs)
