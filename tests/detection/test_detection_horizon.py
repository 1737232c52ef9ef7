"""Horizon frame: checked against exact projections of far points and the SPEC closed form of d_F."""
import math

import numpy as np
import pytest

from visland.camera import CameraModel
from visland.detection.horizon import horizon_frame
from visland.features import batch_R_camera_from_runway, project_runway_corners
from visland.frames import R_camera_from_runway
from visland.runway import Runway

ATTITUDES = [(0.0, 0.03, 0.0), (math.radians(-20), math.radians(5), math.radians(-6)),
             (math.radians(10), math.radians(-2), math.radians(15)), (math.radians(3), 0.0, math.radians(-12))]


def far_point_pixel(camera, roll, pitch, dpsi, direction_runway, distance=1e7):
    """Pixel of a ground point ``distance`` metres away along ``direction_runway`` (a finite
    point, projected exactly)."""
    R = R_camera_from_runway(roll, pitch, dpsi, camera.mount_rpy_rad)
    p_camera = R @ (distance * np.asarray(direction_runway, float) - np.array([0.0, 0.0, -200.0]))
    uv, in_front = camera.project(p_camera)
    assert in_front
    return uv


@pytest.mark.parametrize("roll, pitch, dpsi", ATTITUDES)
def test_far_ground_points_lie_on_the_horizon(roll, pitch, dpsi):
    camera = CameraModel.default(1024)
    horizon = horizon_frame(camera, roll, pitch)
    for azimuth in np.radians([-15, 0, 10]):
        direction = [math.cos(dpsi + azimuth), math.sin(dpsi + azimuth), 0.0]
        uv = far_point_pixel(camera, roll, pitch, 0.0, direction)
        assert abs(horizon.to_sd(uv)[1]) < 0.05


@pytest.mark.parametrize("roll, pitch, dpsi", ATTITUDES)
def test_ground_side_and_coordinates_round_trip(roll, pitch, dpsi):
    camera = CameraModel.default(1024)
    horizon = horizon_frame(camera, roll, pitch)
    ahead = far_point_pixel(camera, roll, pitch, dpsi, [1.0, 0.0, 0.0], distance=2000.0)
    assert horizon.to_sd(ahead)[1] > 0            # a ground point ahead is below the horizon
    sd = np.array([[12.5, 30.0], [-400.0, 5.0]])
    assert np.allclose(horizon.to_sd(horizon.to_uv(sd)), sd)


def test_vanishing_point_position_is_the_spec_closed_form_d_F():
    """With no mounting rotation, SPEC: d_F = fx (tan(phi) tan(theta) - tan(dpsi) / cos(theta))."""
    camera = CameraModel.default(2048, mount_rpy_deg=(0.0, 0.0, 0.0))
    for roll, pitch, dpsi in ATTITUDES:
        horizon = horizon_frame(camera, roll, pitch)
        vp = far_point_pixel(camera, roll, pitch, dpsi, [1.0, 0.0, 0.0])
        expected = camera.fx * (math.tan(roll) * math.tan(pitch) - math.tan(dpsi) / math.cos(pitch))
        assert horizon.to_sd(vp)[0] == pytest.approx(expected, abs=0.05)


@pytest.mark.parametrize("roll, pitch, dpsi", ATTITUDES)
def test_perpendicular_vanishing_point(roll, pitch, dpsi):
    camera = CameraModel.default(1024)
    horizon = horizon_frame(camera, roll, pitch)
    vp = far_point_pixel(camera, roll, pitch, dpsi, [1.0, 0.0, 0.0])
    v2 = horizon.perpendicular_vanishing_point_h(horizon.to_sd(vp)[0])
    # the image of the runway's y axis: two ground points along y, projected
    R = R_camera_from_runway(roll, pitch, dpsi, camera.mount_rpy_rad)
    a, _ = camera.project(R @ np.array([800.0, -100.0, 200.0]))
    b, _ = camera.project(R @ np.array([800.0, 100.0, 200.0]))
    line = np.cross(np.append(a, 1.0), np.append(b, 1.0))
    line = line / np.linalg.norm(line[:2])
    if abs(v2[2]) > 1e-9:      # finite V2: it lies on the threshold's image (within 0.01 px)
        assert abs(line @ (v2 / v2[2])) < 0.01
    else:                      # at infinity: the threshold's image runs along its direction
        assert abs(line[:2] @ v2[:2]) < 1e-6


@pytest.mark.parametrize("roll, pitch, dpsi, y_m", [(0.0, 0.04, 0.0, 0.0), (math.radians(-20), 0.08, -0.1, 195.0),
                                                    (math.radians(8), 0.02, 0.25, -400.0)])
def test_centre_line_slope_is_the_mean_of_the_edge_slopes(roll, pitch, dpsi, y_m):
    """The trapezoid symmetry the model relies on: k_C = (k_L + k_R) / 2 in horizon coordinates."""
    camera = CameraModel.default(2048)
    runway = Runway(length_m=3000.0, width_m=45.0)
    p = np.array([[-1500.0, y_m, -90.0]])
    R = batch_R_camera_from_runway(np.array([roll]), np.array([pitch]), np.array([dpsi]), camera.mount_rpy_rad)
    uv, _, _ = project_runway_corners(R, p, runway, camera)
    uv = uv[0]
    horizon = horizon_frame(camera, roll, pitch)
    _, k_left = horizon.pencil_from_points(uv[0], uv[2])
    _, k_right = horizon.pencil_from_points(uv[1], uv[3])
    centre_near, centre_far = 0.5 * (uv[0] + uv[1]), 0.5 * (uv[2] + uv[3])
    # the centre line's image: the projections of two points on the centre line
    a, _ = camera.project(R[0] @ (np.array([0.0, 0.0, 0.0]) - p[0]))
    b, _ = camera.project(R[0] @ (np.array([3000.0, 0.0, 0.0]) - p[0]))
    _, k_centre = horizon.pencil_from_points(a, b)
    assert k_centre == pytest.approx(0.5 * (k_left + k_right), abs=1e-9)
    # while the midpoint of the corners is not on it in general (perspective): only when the
    # threshold is parallel to the image plane (no roll, no heading offset) is it exactly on it
    along = (b - a) / np.hypot(*(b - a))
    off_px = [abs(along[0] * (c[1] - a[1]) - along[1] * (c[0] - a[0])) for c in (centre_near, centre_far)]
    if roll == 0.0 and dpsi == 0.0:
        assert max(off_px) < 1e-6
    else:
        assert off_px[0] > 0.01    # measured 0.019 and 0.027 px at the threshold, 0.002-0.003 px at the far end


def test_horizon_outside_the_image():
    camera = CameraModel.default(512)
    assert horizon_frame(camera, 0.0, 0.0).crosses_image(512, 512)
    looking_down = horizon_frame(camera, 0.0, math.radians(-60))
    looking_up = horizon_frame(camera, 0.0, math.radians(60))
    assert not looking_down.crosses_image(512, 512) and not looking_up.crosses_image(512, 512)
    assert looking_down.ground_bbox(512, 512) == (0, 0, 512, 512)
    assert looking_up.ground_bbox(512, 512) is None


def test_cross3_is_numpys_cross_to_the_bit():
    from visland.detection.horizon import cross3
    rng = np.random.default_rng(11)
    for shape_a, shape_b in [((3,), (3,)), ((9, 3), (3,)), ((3,), (5, 3)), ((4, 3), (4, 3)), ((2, 6, 3), (6, 3))]:
        for _ in range(20):
            a = rng.normal(size=shape_a) * 10.0 ** rng.uniform(-3, 4)
            b = rng.normal(size=shape_b) * 10.0 ** rng.uniform(-3, 4)
            expected = np.cross(a, b)
            got = cross3(a, b)
            assert got.shape == expected.shape and got.dtype == expected.dtype
            assert np.array_equal(got, expected)
    # a homogeneous line through two points holds both (a check independent of np.cross)
    line = cross3(np.array([2.0, 3.0, 1.0]), np.array([-1.0, 7.0, 1.0]))
    assert line @ np.array([2.0, 3.0, 1.0]) == 0.0 and line @ np.array([-1.0, 7.0, 1.0]) == 0.0
