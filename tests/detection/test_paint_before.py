"""Runway paint nearer than the threshold (:func:`visland.detection.threshold_marking.paint_before`)
must be paint, not the ground's texture: on visland's own frames the blotchy grass before a true
threshold passed for threshold stripes when the rule asked only for marks in every quarter of
the width, and true thresholds were withheld (the first 2048 px study run with it: 23 frames of
the baseline approach, 824-364 m). The rubber-darkened runway that the rule is for is tested on
the independent ray-cast airport (``test_detection_unknown_runways``)."""
import pytest

from tests.helpers.study_frames import study_errors, study_frames
from visland.detection import DetectorParams, detect_runway


@pytest.mark.slow
def test_grass_before_a_true_threshold_is_not_taken_for_paint():
    """The robustness study's baseline approach (3000 x 45 m, 1024 px), frames 225 and 230 (464
    and 392 m): the threshold is reported within a pixel. Without the texture's sigmas and the
    agreement from one line to the next, the grass passes for stripes and both are withheld."""
    frames, camera = study_frames({}, (3000.0, 45.0), [225, 230], size=1024)
    loose = DetectorParams(paint_before_noise_sigmas=0.0, paint_before_agreement=0.0)
    for rgb, state, labels, _ in frames:
        roll, pitch = float(state.roll_rad[0]), float(state.pitch_rad[0])
        result = detect_runway(rgb, camera, roll, pitch)
        errors = study_errors(result, camera, state, labels)
        assert result.corners_found[:2].all(), result.reason
        assert max(errors["near_left_px"], errors["near_right_px"]) < 1.0, errors
        blind = detect_runway(rgb, camera, roll, pitch, params=loose)
        assert not blind.corners_found[:2].any() and "runway paint" in blind.reason, blind.reason
