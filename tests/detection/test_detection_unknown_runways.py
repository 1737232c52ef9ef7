"""Detection on runways, scenes and cameras it was not tuned on (issue 11), on the independent
ray-cast airport (``raycast_airport``): grey levels with haze, taxiways joining the runway's side
near the threshold, a non-square camera with a distorting lens. Labels are exact (pinhole image).

A confident wrong answer is the failure that matters: a frame reported found must have its
corners within a few pixels, or withhold them."""
import math

from dataclasses import replace

import numpy as np
import pytest

from tests.helpers.detection_frames import airport_frame, edge_error_px
from tests.helpers.raycast_airport import PaintedAirport
from visland.camera import CameraModel
from visland.detection import DetectionSequence, DetectorParams, detect_runway
from visland.runway import Runway

BARREL = (-0.22, 0.06, 0.0005, -0.0003, -0.008)


def _errors(result, camera, labels):
    near = np.linalg.norm(result.corners_uv[:2] - labels.corners_uv[0, :2], axis=1)
    return near, max(edge_error_px(camera, labels, result, side) for side in ("left", "right"))


@pytest.mark.slow
def test_a_distorting_non_square_camera_reports_pinhole_features():
    # the runway 18 deg left of the optical axis, where the lens bends lines by pixels
    camera = CameraModel.from_fov(800, 450, 62.0, mount_rpy_deg=(0.0, -6.0, 18.0), distortion=BARREL)
    scene = PaintedAirport(seed=2)
    image, state, labels = airport_frame("thesis-1", 900.0, camera, scene)
    result = detect_runway(image, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    assert result.found, result.reason
    near, edge = _errors(result, camera.without_distortion(), labels)
    assert edge < 1.0
    assert result.corners_found[:2].all() and near.max() < 1.5, (near, result.reason)
    # the same frame read as if the lens were a pinhole is wrong by the distortion (tens of px
    # at the image border), so the test would see a detector that ignored it
    undistorted_view = detect_runway(image, camera.without_distortion(), float(state.roll_rad[0]),
                                     float(state.pitch_rad[0]))
    if undistorted_view.found and undistorted_view.corners_found[:2].all():
        assert np.linalg.norm(undistorted_view.corners_uv[:2] - labels.corners_uv[0, :2], axis=1).max() > 1.5


@pytest.mark.slow
@pytest.mark.parametrize("distance", [1500.0, 700.0])
def test_grey_level_threshold_with_haze(distance):
    """No colour: the threshold placed on grey levels (the ground's end, not the stripes' edge)."""
    camera = CameraModel.default(1024)
    scene = PaintedAirport(seed=5, haze_range_m=5000.0)
    image, state, labels = airport_frame("thesis-3", distance, camera, scene)
    result = detect_runway(image, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    assert result.found, result.reason
    near, edge = _errors(result, camera, labels)
    assert edge < 1.0
    assert result.corners_found[:2].all(), result.reason
    assert near.max() < 1.2, near


def _attitude(state):
    return float(state.roll_rad[0]), float(state.pitch_rad[0])


@pytest.mark.slow
def test_a_runway_in_thick_haze_is_found_on_a_second_look():
    """Haze of 1.5 km at 1.8 km out, a clean sensor: the runway's edges a few grey levels, under
    ``min_contrast`` and under the Canny thresholds the near ground sets; the low-contrast second
    look (halved thresholds, Hough bands near the horizon) finds it, exact against ray-cast truth."""
    camera = CameraModel.default(1024)
    image, state, labels = airport_frame("thesis-3", 1800.0, camera, PaintedAirport(seed=5, haze_range_m=1500.0),
                                         noise_grey=0.8)
    first_look_only = detect_runway(image, camera, *_attitude(state), params=DetectorParams(low_contrast_factor=1.0))
    assert not first_look_only.found, "the frame no longer needs the second look: make the haze thicker"
    result = detect_runway(image, camera, *_attitude(state))
    assert result.found and "low-contrast frame" in result.reason, result.reason
    near, edge = _errors(result, camera, labels)
    assert edge < 1.0
    # faint edges weigh little in the confidence (0.38 here): the corners, 0.34 px right, withheld
    assert "corners withheld" in result.reason and not result.corners_found[:2].any(), result.reason
    corners_anyway = detect_runway(image, camera, *_attitude(state), params=DetectorParams(corner_min_confidence=0.0))
    assert corners_anyway.corners_found[:2].all()
    assert _errors(corners_anyway, camera, labels)[0].max() < 0.6


@pytest.mark.slow
@pytest.mark.parametrize("distance", [3000.0, 2500.0])
def test_a_faint_strip_without_threshold_marking_is_not_reported(distance):
    """The same haze further out: with the halved thresholds the parallel taxiway (185 m beside
    the runway) holds together as a strip, edges 72-88 px from the runway's; unmarked, it is not
    reported. Whatever is reported lies on the runway."""
    camera = CameraModel.default(1024)
    image, state, labels = airport_frame("thesis-3", distance, camera, PaintedAirport(seed=5, haze_range_m=1500.0),
                                         noise_grey=0.8)
    result = detect_runway(image, camera, *_attitude(state))
    if result.found:
        near, edge = _errors(result, camera, labels)
        assert edge < 1.5, (edge, result.reason)
    else:
        assert "low-contrast frame" in result.reason, result.reason


@pytest.mark.slow
def test_a_taxiway_joining_near_the_threshold_never_becomes_the_threshold():
    """Taxiways join both sides 150-350 m past the threshold, one of them oblique, paved like the
    runway: over an approach from 1.6 km to 400 m at 5 Hz, no frame reports a corner more than
    5 px off (withholding is allowed, a wrong corner is not)."""
    camera = CameraModel.default(768)
    runway = Runway(length_m=2600.0, width_m=40.0)
    scene = PaintedAirport(seed=7, runway_length_m=2600.0, runway_width_m=40.0, taxiway_grey=84.0,
                           joining_taxiways=((150.0, 1, 90.0, 250.0), (350.0, -1, 35.0, 250.0)),
                           haze_range_m=8000.0)
    sequence = DetectionSequence(camera)
    found = withheld = 0
    distances = np.arange(1600.0, 399.0, -70.0)
    for k, distance in enumerate(distances):
        image, state, labels = airport_frame("thesis-1", float(distance), camera, scene, runway=runway)
        result = sequence(image, float(state.roll_rad[0]), float(state.pitch_rad[0]), 0.2 * k)
        if not result.found:
            continue
        found += 1
        near, edge = _errors(result, camera, labels)
        assert edge < 2.0, (distance, edge)
        if result.corners_found[:2].all():
            assert near.max() < 5.0, (distance, near, result.reason)
        else:
            withheld += 1
    assert found >= len(distances) - 1
    assert withheld <= len(distances) // 4


@pytest.mark.slow
@pytest.mark.parametrize("distance", [150.0, 80.0])
def test_side_stripes_a_little_darker_than_the_snow_beyond_them(distance):
    """Worn side stripes (grey 196) between the asphalt (72) and snow (232 +- 12): each edge is a
    staircase, a strong step onto the paint and a weaker one onto the snow, the runway's edge.
    Taken at the strong step, both edges lie a stripe's width inside (4-7 px here, near corners
    5-7 px off, reported found); moved past both stripes they are within a pixel."""
    camera = CameraModel.default(512)
    scene = PaintedAirport(seed=3, grass_grey=232.0, marking_grey=196.0, runway_grey=72.0)
    image, state, labels = airport_frame("thesis-3", distance, camera, scene)
    roll, pitch = float(state.roll_rad[0]), float(state.pitch_rad[0])
    result = detect_runway(image, camera, roll, pitch)
    assert result.found, result.reason
    assert "moved out past its side stripe" in result.reason
    near, edge = _errors(result, camera, labels)
    assert edge < 1.0
    assert result.corners_found[:2].all() and near.max() < 1.0, (near, result.reason)
    # the rule off (no stripe counts as resolved): the edges stay on the paint's inner flank
    inner = detect_runway(image, camera, roll, pitch, params=DetectorParams(staircase_min_px=1000.0))
    assert _errors(inner, camera, labels)[1] > 3.0


@pytest.mark.slow
def test_side_stripes_resolved_on_the_edges_near_parts_only():
    """The snow airport of the ray-cast approach (2600 x 40 m) at 1024 px, 310 m out: the side
    stripes (0.9 m) are 3-4 px wide near the bottom of the frame and merge with the step onto
    them farther up, so only the nearest profiles see the step onto the snow (too few for the
    whole-edge rule) and the edge found, mixed, is turned: 5.3 px in, the near corners 5.3-6.0 px
    off with confidence 0.65. Seen as a stripe resolved on the near parts only
    (:func:`detector._seen_near_only`), both edges move past it: within a pixel. Without that
    rule, the step onto the snow, a shoulder of the step onto the paint rather than a peak of its
    own (:func:`detector._stripe_shoulder`), is seen wherever the stripe is resolved, and both
    edges move past it by the whole-edge rule: within a pixel too."""
    camera = CameraModel.default(1024)
    runway = Runway(length_m=2600.0, width_m=40.0)
    scene = PaintedAirport(seed=3, runway_length_m=2600.0, runway_width_m=40.0, grass_grey=232.0,
                           marking_grey=196.0, runway_grey=72.0)
    image, state, labels = airport_frame("thesis-1", 310.0, camera, scene, runway=runway)
    roll, pitch = float(state.roll_rad[0]), float(state.pitch_rad[0])
    result = detect_runway(image, camera, roll, pitch)
    assert result.found and "beyond the near parts of both edges" in result.reason, result.reason
    near, edge = _errors(result, camera, labels)
    assert edge < 1.0
    assert result.corners_found[:2].all() and near.max() < 1.0, (near, result.reason)
    whole_edge = DetectorParams(staircase_near_min_profiles=1000)
    shoulders = detect_runway(image, camera, roll, pitch, params=whole_edge)
    assert shoulders.found and "a staircase beyond both edges" in shoulders.reason, shoulders.reason
    near, edge = _errors(shoulders, camera, labels)
    assert edge < 1.0
    assert shoulders.corners_found[:2].all() and near.max() < 1.0, (near, shoulders.reason)
    turned = detect_runway(image, camera, roll, pitch, params=replace(whole_edge, staircase_shoulder_fraction=1.0))
    assert _errors(turned, camera, labels)[1] > 4.0


@pytest.mark.slow
@pytest.mark.parametrize("distance_m", [400.0, 700.0])
def test_a_threshold_is_not_placed_where_the_rubber_of_the_touchdown_zone_begins(distance_m):
    """A concrete runway as light as the grass beside it (1200 x 23 m, grey 112 on 105), its
    touchdown zone darkened by rubber from 150 to 700 m (80 % of the width, grey 70): the dark
    band is the strip that differs from the ground, and its near end, 150 m past the threshold,
    was taken for the threshold (12-33 px off, confidence 0.7-0.9). The threshold stripes lie
    nearer than that step (:func:`threshold_marking.paint_before`): the threshold is withheld,
    the edges kept.

    At 400 m the rubber's start is also a step down from a brighter side with a brighter line
    past it (the aiming point's marks 7 widths in), and since c541c09 that reading
    (:func:`threshold_marking._ground_blur_lines`: a blast pad beside snow) withholds the
    threshold first, with or without ``paint_before``: the outcome is the same, and the ray-cast
    approach of this runway (``benchmarks/raycast_approach.py --runway 1200,23 --runway-grey 112
    --rubber 150,700,0.8,70 --fps 5 --start-m 2500``) is identical frame by frame. At 700 m only
    ``paint_before`` withholds it."""
    camera = CameraModel.default(1024)
    runway = Runway(length_m=1200.0, width_m=23.0)
    scene = PaintedAirport(seed=3, runway_length_m=1200.0, runway_width_m=23.0, runway_grey=112.0,
                           rubber=((150.0, 700.0, 0.8, 70.0),))
    image, state, labels = airport_frame("thesis-1", distance_m, camera, scene, runway=runway)
    roll, pitch = float(state.roll_rad[0]), float(state.pitch_rad[0])
    result = detect_runway(image, camera, roll, pitch)
    near, edge = _errors(result, camera, labels)
    assert result.found and edge < 1.0, result.reason
    assert not result.corners_found[:2].any(), (near, result.reason)
    blind = detect_runway(image, camera, roll, pitch, params=DetectorParams(paint_before_widths=0.0))
    if distance_m > 500.0:
        assert "runway paint" in result.reason, result.reason
        # the rule off: the rubber's start is reported as the threshold, pixels off
        assert blind.corners_found[:2].all() and _errors(blind, camera, labels)[0].min() > 5.0
    else:
        assert "plain pavement, then a marking" in result.reason, result.reason
        assert not blind.corners_found[:2].any(), blind.reason


def _rubber_airport(runway_grey: float, rubber_grey: float):
    """The rubber scene of ``benchmarks/raycast_approach.py --runway 1200,23 --rubber ...`` (its
    seed 3, here 0: other fields and buildings): a 1200 x 23 m runway of ``runway_grey`` on grass 105, rubber of ``rubber_grey`` from 150 to
    700 m over 80 % of its width, the parallel taxiway 94.5 m to its left, taxiways joining it
    at 300 m (right) and 450 m (left, oblique), haze 6 km; the 1024 px camera, the runway."""
    camera = CameraModel.default(1024)
    runway = Runway(length_m=1200.0, width_m=23.0)
    scene = PaintedAirport(seed=0, runway_length_m=1200.0, runway_width_m=23.0, runway_grey=runway_grey,
                           taxiway_offset_m=-94.5, taxiway_grey=84.0, haze_range_m=6000.0,
                           joining_taxiways=((300.0, 1, 90.0, 260.0), (450.0, -1, 35.0, 260.0)),
                           rubber=((150.0, 700.0, 0.8, rubber_grey),))
    return camera, runway, scene


@pytest.mark.slow
def test_the_runway_end_is_not_placed_where_the_rubber_of_the_touchdown_zone_ends():
    """An asphalt runway (1200 x 23 m, grey 78 on grass 105), its touchdown zone darkened by
    rubber from 150 to 700 m (80 % of the width, grey 50), 700 m out at 1024 px: the surface's
    grey level ends where the rubber does, 500 m short of the runway's end, and the runway end
    was placed on that step (far corners 12.6 px off, confidence 0.94) while both edges ran on
    past it. Searched again where the edges end (``end_past_edges_fraction``), the end is within
    a pixel."""
    camera, runway, scene = _rubber_airport(78.0, 50.0)
    image, state, labels = airport_frame("thesis-1", 700.0, camera, scene, runway=runway)
    roll, pitch = float(state.roll_rad[0]), float(state.pitch_rad[0])

    def far_errors(result):
        assert result.found and result.corners_found[2:].all(), result.reason
        return np.linalg.norm(result.corners_uv[2:] - labels.corners_uv[0][2:], axis=1)

    assert far_errors(detect_runway(image, camera, roll, pitch)).max() < 1.0
    blind = detect_runway(image, camera, roll, pitch, params=DetectorParams(end_past_edges_fraction=10.0))
    assert far_errors(blind).min() > 5.0


@pytest.mark.slow
def test_a_tracked_runway_end_is_withheld_where_both_edges_run_on():
    """The rubber-darkened concrete runway as light as the grass (1200 x 23 m, grey 112 on 105,
    rubber grey 70 from 150 to 700 m), followed from 560 m at 5 Hz: tracking refines the edges
    over the surface's extent, which ends where the rubber does, and the runway end was placed
    there in every frame (far corners 13.4-13.8 px off, confidence 0.9). The contrast across both
    edges runs on past that step (``end_run_on_ratio``): the end is withheld, never wrong."""
    from visland.detection.sequence import DetectionSequence
    camera, runway, scene = _rubber_airport(112.0, 70.0)
    frames = [airport_frame("thesis-1", d, camera, scene, runway=runway) for d in (560.0, 546.0, 532.0, 518.0)]

    def far_errors(params):
        sequence = DetectionSequence(camera, params)
        errors = []
        for k, (image, state, labels) in enumerate(frames):
            result = sequence(image, float(state.roll_rad[0]), float(state.pitch_rad[0]), 0.2 * k)
            if result.found:
                found = result.corners_found[2:]
                errors.append(np.linalg.norm(result.corners_uv[2:][found] - labels.corners_uv[0][2:][found], axis=1))
        assert len(errors) == len(frames) - 1                   # reported from the track's second frame
        return np.concatenate(errors)

    assert far_errors(DetectorParams()).size == 0
    assert far_errors(DetectorParams(end_run_on_ratio=1e6)).min() > 5.0


@pytest.mark.slow
def test_a_tracked_runway_end_is_not_kept_at_the_rubbers_end_on_concrete_as_light_as_dry_grass():
    """The robustness study's 'concrete, dry grass' approach (3000 x 45 m, visland's renderer,
    1024 px, its frames 92-96 at 5 Hz, 2.38-2.32 km out): tracking placed the runway end where
    the touchdown zone's rubber ends, far corners 19 px off at confidence 0.9, on every other
    frame. In grey levels the clean concrete past it is the dry grass's level, and the edges'
    contrast read past it was beside joining taxiways or over 2 px only; in the chroma the
    pavement runs on between the coloured grass. Every far corner reported must be within 5 px
    (withheld, or the true end)."""
    from tests.helpers.study_frames import study_frames
    frames, camera = study_frames({"surface": "concrete", "surroundings": "dry"}, (3000.0, 45.0), range(92, 97))
    sequence = DetectionSequence(camera)
    reported = 0
    for rgb, state, labels, t_s in frames:
        result = sequence(rgb, float(state.roll_rad[0]), float(state.pitch_rad[0]), t_s)
        if not result.found:
            continue
        reported += 1
        found = result.corners_found[2:] & np.asarray(labels.corners_visible[0][2:], bool)
        far = np.linalg.norm(result.corners_uv[2:][found] - labels.corners_uv[0][2:][found], axis=1)
        assert (far < 5.0).all(), (t_s, far, result.reason)
    assert reported >= len(frames) - 1
