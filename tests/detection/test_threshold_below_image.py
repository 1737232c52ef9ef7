"""The threshold when the pavement runs out of the bottom of the image (issue 11).

A displaced threshold puts paved ground before the threshold (300 m in the robustness study);
from 380 m out at 2048 px (37 m high) that pavement's start is below the image, and the
threshold, a bar across the width with stripes past it, was lost ("threshold not found") for the
last 5 s above 100 ft. It is now looked for as a threshold marking from the image's edge inwards
(:func:`visland.detection.detector._threshold_and_end`, :func:`visland.detection.threshold_marking.threshold_marking`).
The other side of that search: on a runway whose threshold is below the image the marks still in
view (touchdown zone, aiming point, designation, centre line) are no threshold marking, and no
threshold may be reported. Frames of visland's renderer, with the study's seeds, checked against
the exact labels.
"""
from dataclasses import replace

import numpy as np
import pytest

from tests.helpers.study_frames import detected_with_errors, study_frame_at

DISPLACED = {"markings": "displaced", "pre_threshold_m": 300.0}


@pytest.mark.slow
@pytest.mark.parametrize("distance", [330.0, 250.0])
def test_a_displaced_threshold_is_found_on_its_bar_when_the_pavement_runs_out_of_the_image(distance):
    rgb, camera, state, labels = study_frame_at(DISPLACED, (3000.0, 45.0), distance, 2048)
    result, errors = detected_with_errors(rgb, camera, state, labels)
    assert result.found and result.corners_found[:2].all(), result.reason
    assert result.threshold_method == "marking-bar", result.reason
    assert errors["near_px"] < 1.0, (errors, result.reason)


@pytest.mark.slow
@pytest.mark.parametrize("rows_below_threshold", [-20, -100])
def test_no_threshold_is_reported_when_a_runways_threshold_is_below_the_image(rows_below_threshold):
    """The baseline runway at 300 m, 2048 px, its frame cut above the threshold (the rows kept end
    20 or 100 px above it: the far part of its stripes, or none, in view; the touchdown zone's marks
    below 900 m all in view). The threshold is not in the frame: its corners must not be reported
    (none of the marks in view is a threshold marking), and the edges must still be found."""
    from visland.detection import detect_runway
    from visland.features import ideal_features
    from visland.runway import Runway

    rgb, camera, state, labels = study_frame_at({}, (3000.0, 45.0), 300.0, 2048)
    near_row = float(np.min(labels.corners_uv[0, :2, 1]))
    height = int(near_row) + rows_below_threshold
    assert camera.cy < height - 1 < camera.height
    cropped = replace(camera, height=height)
    result = detect_runway(np.ascontiguousarray(rgb[:height]), cropped, float(state.roll_rad[0]),
                           float(state.pitch_rad[0]))
    assert not ideal_features(state, Runway(length_m=3000.0, width_m=45.0), cropped).corners_visible[0, :2].any()
    assert result.found, result.reason
    assert not result.corners_found[:2].any(), (result.reason, result.corners_uv[:2])
    assert "threshold below the image" in result.reason

