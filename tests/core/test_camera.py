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


# ---------------------------------------------------------------- lens distortion
WIDE = dict(width=1280, height=720, fx=700.0, fy=700.0, cx=639.5, cy=359.5)
BARREL = (-0.28, 0.09, 0.0007, -0.0004, -0.012)


def test_distortion_matches_opencv_projection():
    # independent truth: OpenCV's own projectPoints with the same coefficients
    cv2 = pytest.importorskip("cv2")
    cam = CameraModel(**WIDE, distortion=BARREL)
    rng = np.random.default_rng(4)
    p_camera_m = np.column_stack([rng.uniform(-0.8, 0.8, 200), rng.uniform(-0.45, 0.45, 200), np.ones(200)])
    uv_cv, _ = cv2.projectPoints(p_camera_m, np.zeros(3), np.zeros(3), cam.K, np.array(BARREL))
    uv_pinhole, _ = cam.project(p_camera_m)
    np.testing.assert_allclose(cam.distort_pixels(uv_pinhole), uv_cv[:, 0, :], atol=1e-9)


def test_undistortion_inverts_distortion_and_agrees_with_opencv():
    cv2 = pytest.importorskip("cv2")
    cam = CameraModel(**WIDE, distortion=BARREL)
    v, u = np.mgrid[0:720:37, 0:1280:53].astype(float)
    uv_distorted = np.stack([u.ravel(), v.ravel()], axis=-1)
    uv_pinhole = cam.undistort_pixels(uv_distorted)
    np.testing.assert_allclose(cam.distort_pixels(uv_pinhole), uv_distorted, atol=1e-7)
    uv_cv = cv2.undistortPoints(uv_distorted[:, None, :], cam.K, np.array(BARREL), P=cam.K,
                                criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-14))
    np.testing.assert_allclose(uv_pinhole, uv_cv[:, 0, :], atol=1e-3)


@pytest.mark.slow
def test_undistortion_maps_straighten_a_distorted_line():
    # A frame through a barrel lens of the half-plane v > 0.05 u + 80 (a straight line in the pinhole
    # image), made by sampling the half-plane at each frame pixel's pinhole position; remapped with
    # the maps, the edge is straight again.
    cv2 = pytest.importorskip("cv2")
    cam = CameraModel(**WIDE, distortion=BARREL)
    v, u = np.mgrid[0:720, 0:1280].astype(float)
    uv_pinhole = cam.undistort_pixels(np.stack([u, v], axis=-1))
    frame = np.where(uv_pinhole[..., 1] > 0.05 * uv_pinhole[..., 0] + 80.0, 200, 40).astype(np.uint8)
    columns = np.arange(100, 1180, 20)
    bent = [np.argmax(frame[:, c] > 120) for c in columns]
    residual = np.array(bent) - np.polyval(np.polyfit(columns, bent, 1), columns)
    assert np.ptp(residual) > 20                                    # the lens bends it by tens of px
    map_u, map_v = cam.undistortion_maps()
    assert map_u.shape == (720, 1280) and map_u.dtype == np.float32
    pinhole = cv2.remap(frame, map_u, map_v, cv2.INTER_LINEAR)
    edge = [np.argmax(pinhole[:, c] > 120) for c in columns]
    np.testing.assert_allclose(edge, np.ceil(0.05 * columns + 80.0), atol=1.0)


def test_pinhole_camera_has_identity_distortion():
    cam = CameraModel(**WIDE)
    uv = np.array([[3.0, 4.0], [1000.0, 700.0]])
    np.testing.assert_array_equal(cam.undistort_pixels(uv), uv)
    assert not cam.has_distortion and cam.without_distortion() == cam


def test_distortion_round_trips_through_camera_json(tmp_path):
    cam = CameraModel.from_fov(1920, 1080, 62.0, mount_rpy_deg=(0.0, -5.0, 0.0), distortion=BARREL)
    assert cam.fx == pytest.approx(960 / math.tan(math.radians(31.0)))
    assert cam.hfov_deg == pytest.approx(62.0)
    cam.save(tmp_path / "camera.json")
    assert CameraModel.load(tmp_path / "camera.json") == cam
    assert "distortion" not in CameraModel.default(64).to_json_dict()


@pytest.mark.parametrize("value, words", [
    ([0.1, 0.2], "list of 5 finite numbers"),
    ("barrel", "list of 5 finite numbers"),
    ([0.1, float("nan"), 0, 0, 0], "list of 5 finite numbers"),
    ([-120.0, 0, 0, 0, 0], "k1 = -120 is outside"),
    ([0, 0, 0.5, 0, 0], "p1 = 0.5 is outside"),
])
def test_malformed_distortion_is_one_sentence_naming_the_field(value, words):
    data = CameraModel.default(64).to_json_dict()
    data["distortion"] = value
    with pytest.raises(ValueError, match="camera.json: field 'distortion'") as error:
        CameraModel.from_json_dict(data)
    assert words in str(error.value)
