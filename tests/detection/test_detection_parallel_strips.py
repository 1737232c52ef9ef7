"""A strip beside the runway is never reported as the runway (issue 11): the robustness study
over whole approaches (benchmarks/detection_robustness_approach.py, thesis-3 at 5 Hz, 1024 px,
visland's renderer) found three conditions where the detector acquired the grass between the
runway and its parallel taxiway, or the taxiway itself, and tracked it for the rest of the
approach, reported found (16 stripes, 30 m wide: 210 gross frames; concrete, dry grass: 183;
oblique, 1200x23: 179). The frames below are the study's own (same runway, scene, pose and
frame seed); the errors are against the exact labels (:func:`visland.features.ideal_features`).
"""
import numpy as np
import pytest

from tests.helpers.study_frames import study_errors as _errors, study_frames as _study_frames


@pytest.mark.slow
def test_the_grass_between_the_runway_and_its_parallel_taxiway_is_not_acquired():
    """16 stripes, 30 m wide (2400 x 30 m), 3580 m before the threshold: the grass between the
    runway and the parallel taxiway 122.5 m to the right is bounded by two pavements' edges and
    was the best strip (its inside at the ground's grey level, its outsides darker): found, edges
    about 30 px off, then tracked to the end of the approach. Its inside is the ground, a
    runway's is not: the runway must be found, both edges within 1 px, no corner 5 px off."""
    from visland.detection import detect_runway
    [(rgb, state, labels, _)], camera = _study_frames({"threshold_stripes": 16}, (2400.0, 30.0), [7])
    result = detect_runway(rgb, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    errors = _errors(result, camera, state, labels)
    assert result.found, result.reason
    assert errors["edge_px"] < 1.0, errors
    assert not errors["gross"], errors


@pytest.mark.slow
def test_a_concrete_runway_is_preferred_to_the_narrower_taxiway_beside_it():
    """oblique, 1200x23 (concrete runway, asphalt taxiways of 12 m on both sides), 2974 m before
    the threshold, the aircraft between the runway and the right taxiway: in grey levels the
    taxiways are the best strips, in the chroma a wide low-chroma area around the right taxiway
    was ranked ahead of the runway and the right taxiway was measured (then tracked: 179 gross
    frames). The runway, twice as wide beside it, must be found: edges within 1 px, no corner
    5 px off."""
    from visland.detection import detect_runway
    [(rgb, state, labels, _)], camera = _study_frames({"taxiways": "oblique", "surface": "concrete"},
                                                       (1200.0, 23.0), [50])
    result = detect_runway(rgb, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    errors = _errors(result, camera, state, labels)
    assert result.found, result.reason
    assert errors["edge_px"] < 1.0, errors
    assert not errors["gross"], errors


@pytest.mark.slow
def test_tracking_after_a_miss_does_not_jump_to_the_parallel_taxiway():
    """concrete, dry grass (3000 x 45 m), 2918 m then 2877 m before the threshold (0.6 s apart,
    within the sequence's hold): the runway found on the first frame; on the second, tracking
    from it (after two frames not found in the study) found the darker parallel taxiway 182.5 m
    to the right inside its region of interest (its centre line's lateral offset over height
    from -0.38 to +0.77, half the width) and the study tracked it to the threshold. The second
    frame must be refused (found = 0 with the reason) or be the runway (edges within 1 px): never
    the taxiway reported found."""
    from visland.detection import DetectionSequence, DetectorParams
    frames, camera = _study_frames({"surface": "concrete", "surroundings": "dry"}, (3000.0, 45.0), [54, 57])
    sequence = DetectionSequence(camera, DetectorParams(new_track_frames=1))     # the first frame reported
    (rgb, state, labels, t_s), (rgb2, state2, labels2, t2_s) = frames
    first = sequence(rgb, float(state.roll_rad[0]), float(state.pitch_rad[0]), t_s)
    errors = _errors(first, camera, state, labels)
    assert first.found and errors["edge_px"] < 1.0, (first.reason, errors)
    second = sequence(rgb2, float(state2.roll_rad[0]), float(state2.pitch_rad[0]), t2_s)
    errors = _errors(second, camera, state2, labels2)
    if second.found:
        assert errors["edge_px"] < 1.0 and not errors["gross"], (second.reason, errors)
    else:
        assert "another object" in second.reason, second.reason


@pytest.mark.slow
def test_the_centre_line_seen_in_fog_is_not_paired_with_an_edge():
    """Visibility 2 km, 610 m before the threshold (the study's frame 215): the runway's far half
    fades into the fog and its dashed centre line, paired with the right edge, was the best pair
    (both meet the horizon at one point): found, the 'left edge' on the centre line 20 px from the
    true one, then tracked down to 100 ft (17 gross frames). Across a centre line the pavement is
    the same on both sides, across an edge it is not: the runway's two edges, or nothing."""
    from visland.detection import detect_runway
    [(rgb, state, labels, _)], camera = _study_frames({"visibility_m": 2000.0}, (3000.0, 45.0), [215])
    result = detect_runway(rgb, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    errors = _errors(result, camera, state, labels)
    if result.found:
        assert errors["edge_px"] < 1.0, errors
    else:
        assert "surface does not change alike" in result.reason, result.reason


def _edge_pair_frame():
    """A 200 px grey frame: grass (120) with a vertical pavement strip (80) from u = 60 to 140
    and a bright centre line (200) from u = 98.5 to 101.5, the left edge with a side stripe."""
    image = np.full((200, 200), 120, np.uint8)
    image[:, 60:140] = 80
    image[:, 60:62] = 200                # left side stripe, inside the edge at u = 60
    image[:, 99:101] = 200               # centre line
    return image


def _balance(image, left_u, right_u):
    from types import SimpleNamespace

    from visland.detection.detector import _unbalanced_edges
    from visland.detection.params import DetectorParams
    segment = lambda u: np.array([[u, 10.0], [u, 190.0]])        # noqa: E731 (far, near ends)
    ctx = SimpleNamespace(image=image, colour=None, params=DetectorParams())
    return _unbalanced_edges(ctx, SimpleNamespace(segment_left_uv=segment(left_u), segment_right_uv=segment(right_u)))


def test_edges_with_the_same_surface_change_are_one_pavement():
    """The pavement's two edges (grass outside, pavement inside past the side stripe) change the
    grey level alike: accepted."""
    assert _balance(_edge_pair_frame(), 59.5, 139.5) == ""


def test_a_centre_line_or_a_side_stripe_is_not_a_runway_edge():
    """The centre line's outer side paired with the right edge: pavement on both sides of it
    (step 0 against the edge's +40); the left side stripe's inner side paired with the left edge
    seen from the other side, a 2 px strip: its two sides change the grey level opposite ways.
    Both refused, saying why."""
    image = _edge_pair_frame()
    why = _balance(image, 98.5, 139.5)
    assert "does not change alike" in why and "grey +0.0 / +40.0" in why, why
    assert "does not change alike" in _balance(image, 59.5, 61.5)


@pytest.mark.slow
def test_a_runway_seen_offset_is_preferred_to_the_parallel_taxiway_that_shows_both_ends():
    """variety 1 (2422 x 52 m, 283 m of pavement before the threshold, urban, taxiways near the
    threshold), 3378 m before the threshold, 22 deg of roll, the runway about one height to the
    left: its hypothesis lay a few pixels off to one side and showed no end against the ground,
    so it was no convincing strip, while the parallel taxiway 211 m to its right (23 m wide)
    showed both ends and was measured as the runway (edges 66 px off; then tracked one frame:
    near corners 85 px off). A wider strip of the same kind of surface beside a convincing one
    goes first without an end in view: the runway is found here."""
    from visland.detection import detect_runway
    [(rgb, state, labels, _)], camera = _study_frames({}, (0.0, 0.0), [21], variety=1)
    result = detect_runway(rgb, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    errors = _errors(result, camera, state, labels)
    assert not errors["gross"], (errors, result.reason)
    assert result.found, result.reason
    assert errors["edge_px"] < 2.0, errors          # the largest distance along the edge (1.2 px here)


def _hypothesis(k_left, k_right, score, ends, inside_minus_ground, spread=6.0):
    from visland.detection.trapezoid import RunwayHypothesis
    return RunwayHypothesis(s0=211.8, k_left=k_left, k_right=k_right, d_far=45.0, d_near=61.0, polarity_left=-1,
                            polarity_right=1, score=score, centre_polarity=0, centre_support=0.0,
                            evidence={"contrast": 5.5, "interior": -8.1, "outside_gap": 1.6, "spread": spread,
                                      "ends": ends, "inside_minus_ground": inside_minus_ground})


@pytest.mark.parametrize("inside_minus_ground, spread, runway_first", [
    (-8.2, 6.0, True),          # the same kind of surface as the taxiway (darker than the fields)
    (+8.2, 6.0, False),         # brighter than the fields where the taxiway is darker: not a pavement like it
    (-8.2, 30.0, False),        # not one surface (its inside spread over 1.5 times its step)
])
def test_a_wider_strip_beside_a_convincing_one_goes_first_without_an_end_in_view(inside_minus_ground, spread,
                                                                                 runway_first):
    """The hypotheses of 'variety 1' at 3378 m (evidence as measured there): the parallel taxiway
    (k 0.05 to 0.18, both ends in view, score 0.78) and the runway beside it, 2.2 times as wide
    (k -1.20 to -0.92, no end in view, score 0.35). The runway goes first when its inside is one
    surface on the same side of the ground's level as the taxiway's."""
    from visland.detection.params import DetectorParams
    from visland.detection.trapezoid import _prefer_widest_parallel
    taxiway = _hypothesis(0.048, 0.176, 0.777, 2, -10.8)
    runway = _hypothesis(-1.202, -0.915, 0.352, 0, inside_minus_ground, spread)
    ordered = _prefer_widest_parallel([taxiway, runway], DetectorParams())
    assert (ordered[0] is runway) == runway_first


@pytest.mark.slow
def test_a_faint_concrete_runway_is_preferred_to_the_dark_taxiway_it_is_twice_as_wide_as():
    """concrete, sand, mono at 2048 px (3000 x 45 m concrete runway, asphalt taxiways, sand,
    monochrome), 3651 m before the threshold, the aircraft 200 m off the centre line, in line
    with the parallel taxiway: in grey levels the concrete steps from the sand by 9 levels, the
    asphalt taxiway by 53, and the runway (twice as wide, both ends in view) scored 0.22 of the
    taxiway, which was acquired and tracked for 197 frames (edges about 100 px off). The runway
    must be found: edges within 1 px, no corner 5 px off."""
    from visland.detection import detect_runway
    [(rgb, state, labels, _)], camera = _study_frames(
        {"surface": "concrete", "surroundings": "sand", "monochrome": True}, (3000.0, 45.0), [2], size=2048)
    result = detect_runway(rgb, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    errors = _errors(result, camera, state, labels)
    assert result.found, result.reason
    assert errors["edge_px"] < 1.0, errors
    assert not errors["gross"], errors


@pytest.mark.parametrize("runway_contrast, runway_score, runway_first, runway_length_px", [
    (8.77, 1.29, True, 80.6),   # as measured: 0.22 of the taxiway's score, 0.15 of its contrast
    (52.9, 1.29, False, 80.6),  # as contrasted as the taxiway: the raw scores compare, 0.22 < 0.3
    (8.77, 0.25, False, 80.6),  # per grey level of contrast 0.26 of the taxiway: not convincing enough
    (8.77, 1.29, False, 46.0),  # shorter in the image than the taxiway (55 px): raw scores
])
def test_a_wider_strip_beside_a_convincing_one_is_compared_per_grey_level_of_contrast(
        runway_contrast, runway_score, runway_first, runway_length_px):
    """The two strips of 'concrete, sand, mono' at 3651 m (2048 px): the asphalt taxiway (k -0.16
    to -0.03, contrast 52.9, score 5.87) and the concrete runway beside it (k -1.21 to -0.96,
    contrast 8.77, score 1.29). Divided by its contrast the runway's score is 1.3 times the
    taxiway's and it goes first; a runway as contrasted as the taxiway is compared on raw
    scores, and one that is weak per grey level too stays behind, as does one shorter in the
    image than the taxiway (runway 80.6 px long, taxiway 54.9 px)."""
    from dataclasses import replace
    from visland.detection.params import DetectorParams
    from visland.detection.trapezoid import _prefer_widest_parallel
    taxiway = _hypothesis(-0.156, -0.033, 5.87, 2, -59.6)
    taxiway = replace(taxiway, evidence={**taxiway.evidence, "contrast": 52.9, "interior": -60.3, "spread": 11.9,
                                         "outside_gap": -0.47, "length_px": 54.9})
    runway = _hypothesis(-1.206, -0.961, runway_score, 2, -16.9)
    runway = replace(runway, evidence={**runway.evidence, "contrast": runway_contrast, "interior": -18.1,
                                       "spread": 7.8, "outside_gap": 0.82, "length_px": runway_length_px})
    ordered = _prefer_widest_parallel([taxiway, runway], DetectorParams())
    assert (ordered[0] is runway) == runway_first


@pytest.mark.slow
@pytest.mark.parametrize("distance_m", [3500.0, 1500.0, 600.0])
@pytest.mark.parametrize("stripes", [True, False])
def test_the_threshold_s_own_marking_tells_a_runway(distance_m, stripes):
    """Ray-cast airport (independent of visland's renderer), 1024 px, thesis-1: the threshold's
    stripes, 6 m past it and 30 m long, are seen at the pavement's start (``threshold_marked``)
    from 3.5 km, where they span 0.7 px of depth and blend with the asphalt between them, to
    600 m; the same runway drawn without them (as a taxiway or road has none; its centre line,
    touchdown-zone and aiming-point marks kept) is not marked. This is what lets a sequence
    report a strip followed well beside the approach (DetectionSequence)."""
    from tests.helpers.detection_frames import airport_frame
    from tests.helpers.raycast_airport import PaintedAirport
    from visland.camera import CameraModel
    from visland.detection import detect_runway

    camera = CameraModel.default(1024)
    scene = PaintedAirport(seed=5, threshold_stripes=stripes)
    image, state, labels = airport_frame("thesis-1", distance_m, camera, scene)
    result = detect_runway(image, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    assert result.found, result.reason
    # (unmarked, its threshold is not always found here: 3.5 and 1.5 km; when found it is right)
    assert result.corners_found[:2].all() or not stripes, result.reason
    if result.corners_found[:2].any():
        near = np.linalg.norm(result.corners_uv[:2] - labels.corners_uv[0, :2], axis=1)
        assert np.nanmax(near[result.corners_found[:2]]) < 2.0, (near, result.reason)
    assert result.threshold_marked == stripes, result.reason
