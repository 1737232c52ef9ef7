"""PointTracker on synthetic approach frames whose corners are known exactly (conftest)."""
import math

import numpy as np
import pytest

from visland.camera import CameraModel
from visland.runway import CORNER_NAMES
from visland.tracking import AnchorObservation, PointTracker, TrackerParams
from visland.tracking.anchoring import labels_anchor_provider


def designate(approach, names=CORNER_NAMES, j=0, offset=(0.0, 0.0)):
    return {n: approach.corners_uv[j, CORNER_NAMES.index(n)] + np.asarray(offset) for n in names}


def errors(step, approach, j, names):
    return np.array([np.hypot(*(step.point(n).uv - approach.corners_uv[j, CORNER_NAMES.index(n)])) for n in names])


@pytest.mark.parametrize("policy", ["every_frame", "never", "scale_change"])
def test_threshold_corners_are_tracked_to_a_fraction_of_a_pixel(approach, policy):
    tracker = PointTracker(approach.camera, TrackerParams(update_policy=policy))
    names = ("near_left", "near_right")
    first = tracker.start(approach.images[0], designate(approach, names), approach.attitude(0))
    assert [p.status for p in first.points] == ["designated", "designated"]
    worst = 0.0
    for j in range(1, len(approach.images)):
        step = tracker.step(approach.images[j], approach.attitude(j))
        assert all(p.status == "tracked" for p in step.points), step.reason()
        worst = max(worst, errors(step, approach, j, names).max())
    assert worst < 0.5
    # the corners moved several pixels meanwhile: this is tracking, not standing still
    assert np.hypot(*(approach.corners_uv[-1, 0] - approach.corners_uv[0, 0])) > 3.0


def test_tracking_without_inertial_data_still_follows_the_corners(approach):
    tracker = PointTracker(approach.camera, TrackerParams())
    names = ("near_left", "near_right")
    tracker.start(approach.images[0], designate(approach, names))
    for j in range(1, len(approach.images)):
        step = tracker.step(approach.images[j])
    assert step.motion is None and not step.consistency_checked
    assert errors(step, approach, len(approach.images) - 1, names).max() < 0.5


def test_bad_designations_are_refused_point_by_point(approach):
    tracker = PointTracker(approach.camera, TrackerParams())
    step = tracker.start(approach.images[0], {"near_left": approach.corners_uv[0, 0], "near_right": (900.0, 40.0),
                                              "sky": (256.0, 60.0), "far_left": (math.nan, 3.0)},
                         approach.attitude(0))
    status = {p.name: (p.status, p.reason) for p in step.points}
    assert status["near_left"][0] == "designated"
    assert status["near_right"][0] == "refused" and "outside the 512x512 image" in status["near_right"][1]
    assert status["sky"][0] == "refused" and "featureless" in status["sky"][1]
    assert status["far_left"][0] == "refused" and "not finite" in status["far_left"][1]
    nxt = tracker.step(approach.images[1], approach.attitude(1))
    assert nxt.point("near_right").status == "refused" and "near_right refused" in nxt.reason()
    assert np.all(np.isnan(nxt.point("near_right").uv))
    with pytest.raises(ValueError, match="no designated point can be tracked"):
        PointTracker(approach.camera).start(approach.images[0], {"sky": (256.0, 60.0)})


def test_frame_of_another_size_is_skipped_and_tracking_resumes(approach):
    tracker = PointTracker(approach.camera, TrackerParams())
    names = ("near_left", "near_right")
    tracker.start(approach.images[0], designate(approach, names), approach.attitude(0))
    tracker.step(approach.images[1], approach.attitude(1))
    small = approach.images[2][:256, :256].copy()
    skipped = tracker.step(small, approach.attitude(2))
    assert "256x256" in skipped.reason() and all(p.status == "skipped" for p in skipped.points)
    assert all(np.all(np.isnan(p.uv)) for p in skipped.points)
    after = tracker.step(approach.images[3], approach.attitude(3))
    assert after.frame_index == 3
    assert all(p.status == "tracked" for p in after.points)
    assert errors(after, approach, 3, names).max() < 0.5


def test_an_occluded_point_coasts_then_is_lost_never_jumps(approach):
    params = TrackerParams(max_coast_frames=2)
    tracker = PointTracker(approach.camera, params)
    names = ("near_left", "near_right")
    tracker.start(approach.images[0], designate(approach, names), approach.attitude(0))
    statuses = []
    for j in range(1, 8):
        image = approach.images[j].copy()
        u, v = np.round(approach.corners_uv[j, 1]).astype(int)
        if j >= 2:
            image[v - 40:v + 40, u - 40:u + 40] = 97          # a flat cloud over P''
        step = tracker.step(image, approach.attitude(j))
        statuses.append(step.point("near_right").status)
        if step.point("near_right").status != "tracked":
            assert np.all(np.isnan(step.point("near_right").uv))      # nothing measured, nothing invented
        assert step.point("near_left").status == "tracked"
    assert statuses[:3] == ["tracked", "coasting", "coasting"]
    assert statuses[3:] == ["lost"] * 4
    assert "no match for 3 frames" in step.point("near_right").reason


def test_a_sudden_jump_of_the_scene_is_not_followed(approach):
    tracker = PointTracker(approach.camera, TrackerParams(max_coast_frames=1))
    tracker.start(approach.images[0], designate(approach, ("near_left", "near_right")), approach.attitude(0))
    shifted = np.roll(approach.images[1], 60, axis=1)               # content 60 px to the right
    step = tracker.step(shifted, approach.attitude(1))
    for p in step.points:
        assert p.status == "coasting" and np.all(np.isnan(p.uv))


def test_lost_point_is_reacquired_only_where_the_others_put_it(approach):
    tracker = PointTracker(approach.camera, TrackerParams(max_coast_frames=0))
    tracker.start(approach.images[0], designate(approach), approach.attitude(0))
    for j in range(1, len(approach.images)):
        image = approach.images[j].copy()
        if j in (2, 3):
            u, v = np.round(approach.corners_uv[j, 1]).astype(int)
            image[v - 30:v + 30, u - 30:u + 30] = 97
        step = tracker.step(image, approach.attitude(j))
        if j in (2, 3):
            assert step.point("near_right").status == "lost"
    assert step.point("near_right").status == "tracked"
    assert errors(step, approach, len(approach.images) - 1, ["near_right"])[0] < 0.5


def test_a_point_dragged_off_the_runway_is_flagged_and_reprojected(approach):
    """Make P'' follow a decoy: its surroundings are moved 7.8 px for one frame.

    (At this range the far corners are 8 px apart: the others place P'' only to about 1.2 px,
    so the check needs a slide beyond 3.3 + 3 x 1.2 px to be sure.)
    """
    for action in ("flag", "reproject"):
        tracker = PointTracker(approach.camera, TrackerParams(on_inconsistent=action))
        tracker.start(approach.images[0], designate(approach), approach.attitude(0))
        tracker.step(approach.images[1], approach.attitude(1))
        image = approach.images[2].copy()
        u, v = np.round(approach.corners_uv[2, 1]).astype(int)
        image[v - 25:v + 25, u - 25:u + 25] = approach.images[2][v - 25 - 6:v + 25 - 6, u - 25 - 5:u + 25 - 5]
        step = tracker.step(image, approach.attitude(2))
        report = step.point("near_right")
        assert step.consistency_checked
        assert report.residual_px > 7.0
        if action == "flag":
            assert report.status == "inconsistent" and "rigid motion" in report.reason
            assert errors(step, approach, 2, ["near_right"])[0] > 7.0
        else:
            assert report.status == "reprojected"
            assert errors(step, approach, 2, ["near_right"])[0] < 1.0
        for other in ("near_left", "far_left", "far_right"):
            assert step.point(other).status == "tracked"


def test_anchoring_corrects_a_bad_designation(approach):
    """A designation 3 px off stays 3 px off when tracking; anchoring pulls it onto the corner."""
    names = ("near_left", "near_right")
    provider = labels_anchor_provider({**_label_columns(approach)})
    plain = PointTracker(approach.camera, TrackerParams())
    onto = PointTracker(approach.camera, TrackerParams(anchor_weight=1.0))
    halfway = PointTracker(approach.camera, TrackerParams(anchor_weight=0.5))
    for tracker in (plain, onto, halfway):
        tracker.start(approach.images[0], designate(approach, names, offset=(2.0, 2.2)), approach.attitude(0))
    a = plain.step(approach.images[1], approach.attitude(1))
    b = onto.step(approach.images[1], approach.attitude(1), anchor=provider(1, approach.images[1]))
    c = halfway.step(approach.images[1], approach.attitude(1), anchor=provider(1, approach.images[1]))
    assert errors(a, approach, 1, names).min() > 2.5
    assert errors(b, approach, 1, names).max() < 1e-9
    assert b.anchored and "anchored: detected 3.0 px from the track, weight 1" in b.point("near_left").reason
    np.testing.assert_allclose(errors(c, approach, 1, names), 0.5 * errors(a, approach, 1, names), atol=0.1)
    for j in range(2, 8):
        c = halfway.step(approach.images[j], approach.attitude(j), anchor=provider(j, approach.images[j]))
    assert errors(c, approach, 7, names).max() < 0.1


def test_a_detection_away_from_a_consistent_track_is_refused_whole(approach):
    params = TrackerParams(anchor_gate_px=5.0, anchor_confirm_frames=3)
    tracker = PointTracker(approach.camera, params)
    tracker.start(approach.images[0], designate(approach), approach.attitude(0))
    decoy = np.array([30.0, -12.0])                 # the detector sees near_left 32 px away (a taxiway)
    for j in range(1, 6):
        corners = approach.corners_uv[j].copy()
        corners[0] += decoy
        observation = AnchorObservation(True, "", 0.9, corners, np.array([True, False, False, False]))
        step = tracker.step(approach.images[j], approach.attitude(j), anchor=observation)
        report = step.point("near_left")
        assert report.status == "tracked"
        assert "anchor: refused (detected corners away from consistent tracks: near_left 32 px" in step.reason()
        assert errors(step, approach, j, ["near_left"])[0] < 0.5
    low = AnchorObservation(True, "", 0.2, approach.corners_uv[6], np.ones(4, dtype=bool))
    step = tracker.step(approach.images[6], approach.attitude(6), anchor=low)
    assert "not used (confidence 0.20 < 0.50)" in step.reason()


def test_a_lost_point_follows_a_far_detection_once_confirmed(approach):
    params = TrackerParams(anchor_gate_px=5.0, anchor_confirm_frames=3, max_coast_frames=0)
    tracker = PointTracker(approach.camera, params)
    tracker.start(approach.images[0], designate(approach, ("near_left", "near_right")), approach.attitude(0))
    statuses, reasons = [], []
    for j in range(1, 7):
        image = approach.images[j].copy()
        u, v = np.round(approach.corners_uv[j, 0]).astype(int)
        if j <= 2:
            image[v - 40:v + 40, u - 40:u + 40] = 97        # near_left hidden: lost at frame 1
        corners = approach.corners_uv[j]
        observation = AnchorObservation(True, "", 0.9, corners, np.array([True, False, False, False]))
        step = tracker.step(image, approach.attitude(j), anchor=observation if j >= 2 else None)
        statuses.append(step.point("near_left").status)
        reasons.append(step.point("near_left").reason)
        if j in (2, 3):
            assert f"not followed yet ({j - 1}/3)" in step.point("near_left").reason
    assert statuses[:3] == ["lost", "lost", "lost"]
    assert statuses[3] == "anchored" and "re-anchored while lost after 3 agreeing detections" in reasons[3]
    assert errors(step, approach, 6, ["near_left"])[0] < 0.5


def test_tracker_rejects_malformed_input(approach):
    tracker = PointTracker(approach.camera)
    with pytest.raises(ValueError, match="call start"):
        tracker.step(approach.images[0])
    with pytest.raises(ValueError, match="uint8"):
        tracker.start(approach.images[0].astype(float), {"near_left": (10, 10)})
    with pytest.raises(ValueError, match="2-D grey image"):
        tracker.start(np.dstack([approach.images[0]] * 3), {"near_left": (10, 10)})
    with pytest.raises(ValueError, match="is 256x256"):
        tracker.start(approach.images[0][:256, :256].copy(), {"near_left": (10, 10)})
    with pytest.raises(ValueError, match="camera must be a CameraModel"):
        PointTracker("camera.json")


def test_policy_never_without_warp_loses_a_rotating_view_every_frame_follows_it():
    """The update policy decides what survives an appearance change (here an image rotating 2 deg/frame)."""
    import cv2
    rng = np.random.default_rng(2)
    base = cv2.GaussianBlur(rng.normal(100, 40, (200, 200)).astype(np.float32), (0, 0), 2.0)
    base = np.clip(base, 0, 255).astype(np.uint8)
    camera = CameraModel.default(200)
    point = np.array([130.0, 90.0])
    centre = (99.5, 99.5)
    results = {}
    for policy in ("never", "every_frame"):
        tracker = PointTracker(camera, TrackerParams(update_policy=policy, scale_adaptation=False,
                                                     max_coast_frames=0, min_score=0.8, template_size_px=21))
        tracker.start(base, {"p": point})
        for k in range(1, 16):
            M = cv2.getRotationMatrix2D(centre, 2.0 * k, 1.0)
            frame = cv2.warpAffine(base, M, (200, 200), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
            step = tracker.step(frame)
        truth = M[:, :2] @ point + M[:, 2]
        results[policy] = (step.point("p").status, step.point("p").uv, truth)
    assert results["never"][0] == "lost"
    status, uv, truth = results["every_frame"]
    assert status == "tracked" and np.hypot(*(uv - truth)) < 1.0


def _label_columns(approach):
    cols = {}
    for k, name in enumerate(CORNER_NAMES):
        cols[f"{name}_u_px"] = np.full(len(approach.images), np.nan)
        cols[f"{name}_v_px"] = np.full(len(approach.images), np.nan)
        cols[f"{name}_visible"] = np.zeros(len(approach.images))
        cols[f"{name}_u_px"][:] = approach.corners_uv[:, k, 0]
        cols[f"{name}_v_px"][:] = approach.corners_uv[:, k, 1]
        cols[f"{name}_visible"][:] = 1
    for name in ("left", "right", "center"):
        cols[f"{name}_rho"] = np.zeros(len(approach.images))
        cols[f"{name}_theta_rad"] = np.zeros(len(approach.images))
    cols["dF_px"] = np.zeros(len(approach.images))
    cols["dpsi_deg"] = np.zeros(len(approach.images))
    return cols


def test_a_lost_point_does_not_follow_a_detector_locked_on_something_else(approach):
    """near_left is lost; the detector reports all corners 40 px off (a taxiway): nothing follows it."""
    params = TrackerParams(anchor_gate_px=5.0, anchor_confirm_frames=2, max_coast_frames=0)
    tracker = PointTracker(approach.camera, params)
    tracker.start(approach.images[0], designate(approach), approach.attitude(0))
    for j in range(1, 6):
        image = approach.images[j].copy()
        u, v = np.round(approach.corners_uv[j, 0]).astype(int)
        image[v - 40:v + 40, u - 40:u + 40] = 97
        observation = AnchorObservation(True, "", 0.9, approach.corners_uv[j] + [40.0, 0.0], np.ones(4, dtype=bool))
        step = tracker.step(image, approach.attitude(j), anchor=observation)
        assert step.point("near_left").status == "lost"
        assert "anchor: refused" in step.reason()
        assert not step.anchored
