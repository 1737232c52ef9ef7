"""Search windows placed by an estimator's prediction (issue 16 item 2, seed 004).

Independent truth: ray-cast frames with their exact labels (``tests.helpers.detection_frames``);
the prediction is built from the labelled corners, so a perfect estimator's window is tested.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from tests.helpers.detection_frames import frame
from visland.camera import CameraModel
from visland.detection import DetectionSequence, DetectorParams
from visland.detection.predicted import prior_from_prediction


def _prediction_from_labels(camera, labels, shift_px=0.0):
    uv = labels.corners_uv[0].copy()                 # near left, near right, far left, far right
    uv[:, 0] += shift_px
    xy = (uv - [camera.cx, camera.cy]) / [camera.fx, camera.fy]
    return xy[:2], xy[2:]


def test_prior_places_the_edges_at_the_predicted_pixels():
    camera = CameraModel.default(512)
    near = np.array([[-0.05, 0.20], [0.05, 0.20]])
    far = np.array([[-0.004, 0.01], [0.004, 0.01]])
    prior = prior_from_prediction(camera, near, far, 0.01, -0.02, 0.003)
    assert prior.found and prior.mode == "predicted"
    np.testing.assert_allclose(prior.segments_uv["left"], [[-0.004 * 618 + 255.5, 0.01 * 618 + 255.5],
                                                           [-0.05 * 618 + 255.5, 0.20 * 618 + 255.5]])
    np.testing.assert_allclose(prior.corners_uv[:2], near * 618 + 255.5)
    assert prior.corners_found.tolist() == [True, True, False, False]
    assert (prior.roll_rad, prior.pitch_rad, prior.dpsi_rad) == (0.01, -0.02, 0.003)
    low = prior_from_prediction(camera, np.array([[-0.3, 0.5], [0.3, 0.5]]), far, 0.0, 0.0, 0.0)
    assert low.found and not low.corners_found[:2].any()          # threshold below the frame
    behind = prior_from_prediction(camera, np.full((2, 2), np.nan), far, 0.0, 0.0, 0.0)
    assert not behind.found and "not in front" in behind.reason
    with pytest.raises(ValueError, match="near_xy"):
        prior_from_prediction(camera, np.zeros(2), far, 0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="roll_rad"):
        prior_from_prediction(camera, near, far, math.nan, 0.0, 0.0)


@pytest.mark.parametrize("distance_m", [2500.0, 900.0])
def test_a_predicted_window_tracks_the_first_frame(distance_m):
    image, camera, state, labels = frame("thesis-3", distance_m)
    roll, pitch = float(state.roll_rad[0]), float(state.pitch_rad[0])
    near, far = _prediction_from_labels(camera, labels)
    prior = prior_from_prediction(camera, near, far, roll, pitch, float(state.dpsi_rad[0]))
    # alone, the first frame of a track is followed, reported from the second (new_track_frames);
    # found where the prediction put it, at once
    assert not DetectionSequence(camera)(image, roll, pitch, 0.0).found
    alone = DetectionSequence(camera, DetectorParams(new_track_frames=1))(image, roll, pitch, 0.0)
    guided = DetectionSequence(camera)(image, roll, pitch, 0.0, predicted=prior)
    assert alone.found and alone.mode == "acquisition"
    assert guided.found and guided.mode == "tracking"          # searched in the predicted window
    true_near = labels.corners_uv[0, :2]
    for result in (alone, guided):
        assert np.abs(result.corners_uv[:2] - true_near).max() < 2.0


def test_a_wrong_prediction_costs_the_window_not_the_runway():
    image, camera, state, labels = frame("thesis-3", 900.0)
    roll, pitch = float(state.roll_rad[0]), float(state.pitch_rad[0])
    near, far = _prediction_from_labels(camera, labels, shift_px=-160.0)   # a third of the frame off
    prior = prior_from_prediction(camera, near, far, roll, pitch, float(state.dpsi_rad[0]))
    # (found by the search that follows, the first frame of a new track: reported at once here)
    result = DetectionSequence(camera, DetectorParams(new_track_frames=1))(image, roll, pitch, 0.0, predicted=prior)
    assert result.found and result.mode != "tracking"
    assert np.abs(result.corners_uv[:2] - labels.corners_uv[0, :2]).max() < 2.0
