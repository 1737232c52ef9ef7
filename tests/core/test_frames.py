"""Rotations named by frames, checked against hand-computed cases."""
import math

import numpy as np
import pytest

from visland.frames import (R_body_from_camera, R_camera_from_runway, R_ned_from_body, R_ned_from_runway,
                            euler_zyx_from_R_ned_from_body, wrap_pi)


def test_heading_90_turns_body_forward_to_east():
    R = R_ned_from_body(0.0, 0.0, math.radians(90.0))
    np.testing.assert_allclose(R @ [1, 0, 0], [0, 1, 0], atol=1e-15)
    # heading east, the right wing points south: NED (-1, 0, 0)
    np.testing.assert_allclose(R @ [0, 1, 0], [-1, 0, 0], atol=1e-15)


def test_positive_pitch_raises_the_nose():
    R = R_ned_from_body(0.0, math.radians(10.0), 0.0)
    forward_ned = R @ [1, 0, 0]
    assert forward_ned[2] == pytest.approx(-math.sin(math.radians(10.0)))   # z down: negative is up


def test_positive_roll_lowers_the_right_wing():
    R = R_ned_from_body(math.radians(20.0), 0.0, 0.0)
    right_wing_ned = R @ [0, 1, 0]
    assert right_wing_ned[2] == pytest.approx(math.sin(math.radians(20.0)))


def test_euler_round_trip():
    rng = np.random.default_rng(1)
    for _ in range(200):
        roll, heading = rng.uniform(-math.pi, math.pi, 2)
        pitch = rng.uniform(-1.5, 1.5)
        got = euler_zyx_from_R_ned_from_body(R_ned_from_body(roll, pitch, heading))
        np.testing.assert_allclose(got, [roll, pitch, heading], atol=1e-12)


def test_zero_mount_camera_axes():
    R = R_body_from_camera([0.0, 0.0, 0.0])
    np.testing.assert_allclose(R @ [0, 0, 1], [1, 0, 0])   # optical axis along body x
    np.testing.assert_allclose(R @ [1, 0, 0], [0, 1, 0])   # image x along body y
    np.testing.assert_allclose(R @ [0, 1, 0], [0, 0, 1])   # image y along body z


def test_negative_mount_pitch_looks_down():
    R = R_body_from_camera([0.0, math.radians(-3.0), 0.0])
    axis_body = R @ [0, 0, 1]
    assert axis_body[2] == pytest.approx(math.sin(math.radians(3.0)))


def test_camera_from_runway_is_consistent_with_ned_chain():
    # R_camera_from_runway must equal (R_ned_from_body(heading) R_body_from_camera)^T R_ned_from_runway
    roll, pitch, heading, psi_rwy = 0.1, -0.05, 1.2, 0.9
    mount = [0.01, -0.06, 0.02]
    direct = R_camera_from_runway(roll, pitch, heading - psi_rwy, mount)
    chain = (R_ned_from_body(roll, pitch, heading) @ R_body_from_camera(mount)).T @ R_ned_from_runway(psi_rwy)
    np.testing.assert_allclose(direct, chain, atol=1e-14)


def test_wrap_pi():
    np.testing.assert_allclose(wrap_pi([3 * math.pi / 2, -3 * math.pi / 2, 0.5]), [-math.pi / 2, math.pi / 2, 0.5])
