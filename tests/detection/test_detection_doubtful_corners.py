"""Corners on doubtful edges are withheld, not reported wrong (issue 11: "a confidence that drops
when it is doubtful, and the corners withheld rather than wrong")."""
import math

import numpy as np
import pytest

from tests.helpers.profiles import area_sampled_steps
from tests.helpers.study_frames import study_errors, study_frames


def _transverse():
    from visland.detection.detector import _TransverseLines
    corners = np.array([[940.0, 1200.0], [1100.0, 1200.0], [1010.0, 1030.0], [1035.0, 1030.0]])
    return _TransverseLines(corners, np.ones(4, bool), (0.1, 0.2), (0.3, 0.4), ["runway end not found"],
                            threshold_method="grey", pavement_marking_widths=7.5)


def test_withheld_corners_leave_nothing_of_the_threshold_or_the_end():
    from visland.detection.detector import _corners_withheld
    note = "corners withheld: the edges they lie on have a confidence of 0.31 (< 0.4)"
    withheld = _corners_withheld(_transverse(), note)
    assert not withheld.corners_found.any() and np.isnan(withheld.corners_uv).all()
    assert all(math.isnan(x) for x in withheld.threshold_line + withheld.end_line)
    assert withheld.threshold_method == ""
    assert withheld.notes == ["runway end not found", note]
    # a marking seen inside the pavement is still reported (the sequence remembers where it was)
    assert withheld.pavement_marking_widths == 7.5


@pytest.mark.slow
def test_corners_on_the_inner_sides_of_side_stripes_lost_in_snow_are_withheld():
    """'variety 3' of the robustness study at 2048 px (snow, monochrome), 479 m before the
    threshold: the white side stripes merge with the snow, the edges found are their inner sides
    (2-5 px in), at confidence 0.30, and the near corners were reported 5.1 px off (tracked; 4.6 px
    for the edges acquired on this frame alone). The runway is found and no corner is reported.

    The stripes here are darker than the snow, steps of the edges' own sign 3 px out, so the
    staircase rule (``staircase_*``) moves both edges past them; this frame's withholding is
    checked with that rule off. With it on the moved edges are as straight as the steps onto the
    snow (confidence 0.64) and the near corners are reported, 0.6 and 0.85 px off."""
    from visland.detection import DetectorParams, detect_runway
    [(rgb, state, labels, _)], camera = study_frames({}, (0.0, 0.0), [224], size=2048, variety=3)
    roll, pitch = float(state.roll_rad[0]), float(state.pitch_rad[0])
    result = detect_runway(rgb, camera, roll, pitch, params=DetectorParams(staircase_min_px=1000.0))
    errors = study_errors(result, camera, state, labels)
    assert result.found, result.reason
    assert "corners withheld: the edges they lie on have a confidence of" in result.reason, result.reason
    assert not result.corners_found.any()
    assert not errors["gross"], errors
    moved = detect_runway(rgb, camera, roll, pitch)
    assert moved.found and "moved out past its side stripe" in moved.reason, moved.reason
    errors = study_errors(moved, camera, state, labels)
    assert moved.corners_found[:2].all() and errors["near_px"] < 1.2, errors
    assert errors["edge_px"] < 2.5, errors


def test_the_next_search_window_covers_the_doubtful_corners():
    """Withheld corners are not measurements, but the runway is still there: the next frame's
    region of interest covers them as it covers reported corners (without them tracking the
    noisy 'variety 1' at 1024 px lost 15 % of its frames far out)."""
    from types import SimpleNamespace
    from visland.camera import CameraModel
    from visland.detection.detector import _predict
    from visland.detection.horizon import horizon_frame
    from visland.detection.params import DetectorParams
    from visland.detection.result import DetectionResult
    camera = CameraModel.default(1024)
    params = DetectorParams().scaled_to(camera)
    horizon = horizon_frame(camera, 0.0, 0.0)
    context = SimpleNamespace(camera=camera, horizon=horizon, params=params, roll=0.0, pitch=0.0)
    segments = {"left": np.array([[500.0, 600.0], [470.0, 660.0]]), "right": np.array([[530.0, 600.0], [560.0, 660.0]])}
    corners = np.array([[440.0, 760.0], [590.0, 760.0]])
    common = dict(found=True, reason="", segments_uv=segments, roll_rad=0.0, pitch_rad=0.0, dpsi_rad=0.0)
    ground = (0, 0, camera.width, camera.height)
    _, roi_edges = _predict(DetectionResult(**common), context, ground)
    _, roi_doubtful = _predict(DetectionResult(**common, doubtful_corners_uv=corners), context, ground)
    corners_found = np.zeros(4, bool)
    corners_found[:2] = True
    reported = DetectionResult(**common, corners_uv=np.concatenate([corners, np.full((2, 2), np.nan)]),
                               corners_found=corners_found)
    _, roi_reported = _predict(reported, context, ground)
    assert roi_edges[3] < 760 <= roi_doubtful[3]
    assert roi_doubtful == roi_reported


@pytest.mark.parametrize("sigma_px", [0.8, 1.0, 1.2])
def test_a_brighter_grounds_blur_is_told_from_the_stripes_at_the_pavements_start(sigma_px):
    """:func:`threshold_marking._ground_blur_lines` on profiles of an independent model
    (:func:`tests.helpers.profiles.area_sampled_steps`), read every half pixel from 0.5 px in:
    snow 60 levels over the asphalt, blurred 0.8-1.2 px, then 30 px of plain pavement with a
    band of stripes 9 px in (a blast pad): its first lines only decay, two or more are skipped
    and none of the band. The same ground with a threshold's stripes (35 levels over the
    asphalt, from 0.3 to 2.3 px in) at the start: paint holds, nothing skipped. (Under a sharper
    blur the ground leaves one line over ``min_step``; one line is not skipped, and is read as
    before.)"""
    from visland.detection.threshold_marking import _ground_blur_lines
    lines = 0.5 + 0.5 * np.arange(60)
    pad = area_sampled_steps(lines, (60.0, 0.0, 14.0, 0.0), (0.0, 9.0, 11.0), sigma_px)
    skipped = _ground_blur_lines(pad, 6.0)
    assert 2 <= skipped and lines[skipped] < 9.0 - 2.0 * sigma_px, (skipped, np.round(pad[:8], 1))
    runway = area_sampled_steps(lines, (60.0, 0.0, 35.0, 0.0, 14.0, 0.0), (0.0, 0.3, 2.3, 9.0, 11.0), sigma_px)
    assert _ground_blur_lines(runway, 6.0) == 0, np.round(runway[:8], 1)


@pytest.mark.slow
def test_a_blast_pads_start_beside_snow_is_not_taken_for_the_threshold(monkeypatch):
    """Held-out scene draw 12 of the robustness study at 2048 px (a 127 m blast pad of asphalt
    before a 42 m wide runway, snow, monochrome, worn paint), a sequence started 2.32 km out:
    where the pad begins is the strongest transverse step, the snow's blur into it was read as a
    bar at the pavement's start, and the threshold was reported there, 8.8-9.1 px short (110
    frames of the study from 3.6 to 1.3 km). No corner is 5 px off: the threshold is withheld, or
    placed on the worn stripes 127 m in (within a pixel: their 28-30 levels over the asphalt pass
    the markings' gate beside the brighter snow since it asks a quarter of the snow's step, in
    one frame of the four); with the blur read as before, a near corner more than 5 px off is
    reported."""
    import visland.detection.threshold_marking as marking
    from visland.detection import DetectionSequence

    frames, camera = study_frames({}, (0.0, 0.0), [96, 97, 98, 99], size=2048, variety=12)

    def run():
        sequence = DetectionSequence(camera)
        results = [sequence(rgb, float(state.roll_rad[0]), float(state.pitch_rad[0]), t_s)
                   for rgb, state, _, t_s in frames]
        errors = [study_errors(r, camera, state, labels) for r, (_, state, labels, _) in zip(results, frames)]
        return results, errors

    results, errors = run()
    assert all(r.found for r in results[1:]), [r.reason for r in results]
    assert not any(e["gross"] for e in errors), errors
    placed = [e["near_px"] for r, e in zip(results[1:], errors[1:]) if r.corners_found[:2].any()]
    assert all(near <= 1.0 for near in placed), (placed, [r.reason for r in results])
    monkeypatch.setattr(marking, "_ground_blur_lines", lambda level, min_step: 0)
    _, errors = run()
    assert any(e["gross"] for e in errors), errors


@pytest.mark.slow
def test_a_concrete_surfaces_blotches_beside_snow_are_not_taken_for_stripes():
    """Held-out scene draw 13 of the robustness study at 2048 px (an unmarked concrete runway
    beside snow), a sequence started 1.04 km out. Markings dimmer than the snow's step over the
    concrete are read beside it when they show clear stripes; the concrete's blotches cross 4 to
    7 marks on every line, and with that the only test, they were read as stripes 2.3 widths in
    at 970 m (near corners 10.6 px off; 28 frames of the study from 1.0 km to 220 m, up to 106
    px). Stripes must cross 3 times as many marks as the pavement before them: no corner 5 px
    off; without that, one is."""
    import dataclasses

    from visland.detection import DetectionSequence, DetectorParams

    frames, camera = study_frames({}, (0.0, 0.0), [185, 186, 187, 188, 189, 190], size=2048, variety=13)

    def errors_with(params):
        sequence = DetectionSequence(camera, params)
        results = [sequence(rgb, float(state.roll_rad[0]), float(state.pitch_rad[0]), t_s)
                   for rgb, state, _, t_s in frames]
        return [study_errors(r, camera, state, labels) for r, (_, state, labels, _) in zip(results, frames)]

    errors = errors_with(DetectorParams())
    assert not any(e["gross"] for e in errors), errors
    errors = errors_with(dataclasses.replace(DetectorParams(), marking_dim_texture_ratio=0.0))
    assert any(e["gross"] for e in errors), errors
