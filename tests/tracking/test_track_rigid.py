"""The rigid ground-plane motion check against closed-form projections of known ground points."""
import math

import numpy as np

from visland.camera import CameraModel
from visland.frames import R_camera_from_runway
from visland.tracking.motion import Attitude, R_camera_from_level, virtual_to_pixel_homography
from visland.tracking.rigid import check_consistency, fit_plane_motion

CAMERA = CameraModel.default(1024)
POINTS_R = np.array([[0.0, -22.5, 0.0], [0.0, 22.5, 0.0], [3000.0, -22.5, 0.0], [3000.0, 22.5, 0.0],
                     [1500.0, -22.5, 0.0], [1500.0, 22.5, 0.0]])


def view(c_runway_m, roll_deg, pitch_deg, dpsi_deg):
    """Exact pixels of POINTS_R from camera centre c with the attitude relative to the runway."""
    R = R_camera_from_runway(math.radians(roll_deg), math.radians(pitch_deg), math.radians(dpsi_deg),
                             CAMERA.mount_rpy_rad)
    uv, in_front = CAMERA.project((POINTS_R - np.asarray(c_runway_m)) @ R.T)
    assert in_front.all()
    return uv


def level_homography(roll_deg, pitch_deg, heading_deg, heading_reference_deg):
    attitude = Attitude(math.radians(roll_deg), math.radians(pitch_deg), math.radians(heading_deg))
    R = R_camera_from_level(attitude, math.radians(heading_reference_deg), CAMERA)
    return virtual_to_pixel_homography(R, CAMERA)


def designated(uv0, G0):
    """Level-frame coordinates of the pixels ``uv0`` designated in a frame with homography ``G0``."""
    q = np.linalg.solve(G0, np.column_stack([uv0, np.ones(len(uv0))]).T).T
    return q[:, :2] / q[:, 2:3]


def two_views(ck=(-1200.0, 20.0, -70.0)):
    """The common scene: all points designated 3 km out, seen again from ``ck``: ``(q, uvk, Gk)``."""
    c0 = np.array([-3000.0, 100.0, -160.0])
    uv0, uvk = view(c0, 0.0, 1.0, 3.0), view(np.asarray(ck), 1.0, 2.0, 1.0)
    G0, Gk = level_homography(0.0, 1.0, 3.0, 3.0), level_homography(1.0, 2.0, 1.0, 3.0)
    return designated(uv0, G0), uvk, Gk


def test_ground_points_follow_the_closed_form_motion():
    runway_heading = 40.0
    c0, ck = np.array([-4000.0, 150.0, -220.0]), np.array([-1500.0, 40.0, -95.0])
    uv0 = view(c0, 2.0, 1.0, 5.0)
    uvk = view(ck, -3.0, 2.5, -2.0)
    # level frame of the designation = runway axes turned by the heading at frame 0 (dpsi_0 = 5 deg)
    G0 = level_homography(2.0, 1.0, runway_heading + 5.0, runway_heading + 5.0)
    Gk = level_homography(-3.0, 2.5, runway_heading - 2.0, runway_heading + 5.0)
    q = designated(uv0, G0)
    result = check_consistency(q, uvk, Gk, threshold_px=0.5)
    assert result.checked and result.decided and result.consistent.all()
    assert np.max(result.residual_px) < 1e-6
    # closed form: s = dH0 / dHk, b = (c0 - ck)_xy / dHk in the level axes of frame 0
    assert math.isclose(result.motion.scale, 220.0 / 95.0, rel_tol=1e-9)
    a = math.radians(5.0)
    R_level_from_runway = np.array([[math.cos(a), math.sin(a)], [-math.sin(a), math.cos(a)]])
    np.testing.assert_allclose(result.motion.shift, R_level_from_runway @ (c0 - ck)[:2] / 95.0, atol=1e-9)


def test_one_drifting_point_is_singled_out():
    q, uvk, Gk = two_views()
    drifted = uvk.copy()
    drifted[1] += [4.0, -3.0]                   # P'' slid 5 px
    result = check_consistency(q, drifted, Gk, threshold_px=2.0)
    assert result.decided
    np.testing.assert_array_equal(result.consistent, [True, False, True, True, True, True])
    assert math.isclose(result.residual_px[1], 5.0, rel_tol=0.05)
    # the others still give the motion, so the drifted point's rigid prediction is its true place
    np.testing.assert_allclose(result.motion.pixels(q[1], Gk), uvk[1], atol=1e-6)


def test_two_points_that_disagree_cannot_be_told_apart():
    q, uvk, Gk = two_views()
    q, uvk = q[:2], uvk[:2]
    ok = check_consistency(q, uvk, Gk, threshold_px=1.0)
    assert ok.checked and ok.decided and ok.consistent.all()
    drifted = uvk.copy()
    drifted[1, 1] += 6.0                      # across the threshold line: the segment turns
    bad = check_consistency(q, drifted, Gk, threshold_px=1.0)
    assert bad.checked and not bad.decided and not bad.consistent.any()


def test_edge_points_may_slide_along_their_edge():
    q, uvk, Gk = two_views()
    # points 4 and 5 are edge points: their normals are across the edge lines through the corners
    normals = [None] * 4
    for near, far in ((0, 2), (1, 3)):
        d = uvk[far] - uvk[near]
        normals.append(np.array([-d[1], d[0]]) / np.hypot(*d))
    slid = uvk.copy()
    for k, (near, far) in zip((4, 5), ((0, 2), (1, 3))):
        d = (uvk[far] - uvk[near]) / np.hypot(*(uvk[far] - uvk[near]))
        slid[k] += 7.0 * d                       # along the edge: the aperture problem, not an error
    result = check_consistency(q, slid, Gk, threshold_px=0.5, normals=normals)
    assert result.decided and result.consistent.all()
    across = slid.copy()
    across[4] += 3.0 * normals[4]
    flagged = check_consistency(q, across, Gk, threshold_px=0.5, normals=normals)
    assert not flagged.consistent[4] and flagged.consistent[[0, 1, 2, 3, 5]].all()


def test_too_few_equations_are_not_checked():
    G = level_homography(0.0, 1.0, 0.0, 0.0)
    assert fit_plane_motion([[0.1, 0.2]], [[500.0, 600.0]], G) is None
    result = check_consistency([[0.1, 0.2]], [[500.0, 600.0]], G, threshold_px=1.0)
    assert result.motion is None and not result.checked


def test_prediction_spread_matches_monte_carlo():
    """sigma^2 (A^T A)^-1 carried to the image equals the scatter of refits on noisy points."""
    from visland.tracking.rigid import _fit, prediction_std_px
    q, uvk, Gk = two_views(ck=(-450.0, 20.0, -30.0))
    q, uvk = q[:4], uvk[:4]
    keep = np.array([True, False, True, True])
    motion, information = _fit(q, uvk, Gk, [None] * 4, keep)
    predicted_std = prediction_std_px(motion, information, q[1:2], Gk, 0.2)[0]
    rng = np.random.default_rng(0)
    samples = np.array([fit_plane_motion(q, uvk + rng.normal(0.0, 0.2, uvk.shape), Gk, keep=keep).pixels(q[1], Gk)
                        for _ in range(2000)])
    monte_carlo = math.sqrt(np.linalg.eigvalsh(np.cov(samples.T))[-1])
    assert abs(predicted_std - monte_carlo) < 0.05 * monte_carlo


def test_closed_form_leave_one_out_equals_refitting_without_the_point():
    """(I - H_i)^-1 e_i, the residual of point i against the others' fit, checked by refitting."""
    from visland.tracking.rigid import _blocks, _solve
    q, uvk, Gk = two_views()
    noisy = uvk + np.random.default_rng(4).normal(0.0, 0.7, uvk.shape)
    normals = [None] * 4 + [np.array([0.6, 0.8]), None]
    blocks = _blocks(q, noisy, Gk, normals)
    keep = np.ones(len(q), dtype=bool)
    theta, information = _solve(blocks, keep)
    inverse = np.linalg.inv(information)
    for i in range(len(q)):
        A, r = blocks[i]
        closed = np.linalg.solve(np.eye(len(r)) - A @ inverse @ A.T, r - A @ theta)
        others = keep.copy()
        others[i] = False
        theta_out, _ = _solve(blocks, others)
        np.testing.assert_allclose(closed, r - A @ theta_out, rtol=1e-9, atol=1e-9)
