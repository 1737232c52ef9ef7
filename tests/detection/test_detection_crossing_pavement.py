"""A transverse edge is the threshold only if it is not part of a pavement crossing or joining the
runway there (issue 11 item 4): :func:`visland.detection.transverse.pavement_beyond_edges`.

Frames from the independent ray caster (tests/helpers/raycast_airport.py), 512 px, thesis-3:
a 23 m taxiway crossing the runway's extended centre line just before the threshold
(``x`` from -23 to 0 m, paved across the runway's width and 150 m beyond each edge), the
threshold stripes 6 m past the threshold. Its near edge at ``x = -23`` m is a transverse step
across the whole width that continues beyond both edges: before the check it was reported as
the threshold (found, near corners up to 9 px off). Exact geometry from the labels
(:mod:`visland.features`) and the camera's projection.
"""
import numpy as np
import pytest

from tests.helpers.detection_frames import airport_frame
from tests.helpers.raycast_airport import PaintedAirport
from visland.camera import CameraModel
from visland.detection import DetectorParams, detect_runway
from visland.detection.horizon import horizon_frame, meet_h
from visland.detection.refine import PixelLine
from visland.detection.transverse import pavement_beyond_edges
from visland.features import batch_R_camera_from_runway

SIZE = 512
CROSSING = ((-11.5, -1, 90.0, 150.0), (-11.5, 1, 90.0, 150.0))


def _crossing_scene(taxiway_grey: float) -> PaintedAirport:
    """The crossing taxiway: the runway's width of it paved at the runway's grey (pre-threshold
    pavement, no markings), beyond the edges at ``taxiway_grey``."""
    return PaintedAirport(seed=4, pre_threshold_m=23.0, joining_taxiways=CROSSING, taxiway_grey=taxiway_grey)


def _geometry(camera, state, labels):
    """The labelled edges as pixel lines, the horizon, V1's ``s0`` and a function giving the depth
    below the horizon of a runway-frame point on the centre line (closed-form projection)."""
    horizon = horizon_frame(camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    corners = labels.corners_uv[0]
    left = PixelLine(corners[0], (corners[2] - corners[0]) / np.linalg.norm(corners[2] - corners[0]))
    right = PixelLine(corners[1], (corners[3] - corners[1]) / np.linalg.norm(corners[3] - corners[1]))
    s0 = float(horizon.to_sd(meet_h(left.homogeneous(), right.homogeneous()))[0])
    R = batch_R_camera_from_runway(state.roll_rad, state.pitch_rad, state.dpsi_rad, camera.mount_rpy_rad)[0]

    def depth_of(x_m):
        uv, _ = camera.project(R @ (np.array([x_m, 0.0, 0.0]) - state.p_runway_m[0]))
        return float(horizon.to_sd(uv)[1])
    return horizon, left, right, s0, depth_of


@pytest.mark.slow
@pytest.mark.parametrize("taxiway_grey", [84.0, 122.0])
def test_the_edge_of_a_pavement_crossing_before_the_threshold_continues_beyond_both_edges(taxiway_grey):
    """At 600 m: the crossing's near edge (x = -23 m) continues beyond both runway edges, whether
    the taxiway is asphalt like the runway (84 against 78, darker than the grass's 105) or
    brighter than the grass (122); the true threshold of the same runway without the crossing
    does not; nor does a threshold with a taxiway joining flush on its approach side (x from -23
    to 0 m, one side: the pavement beside it lies on the line's outer side)."""
    camera = CameraModel.default(SIZE)
    params = DetectorParams().scaled_to(camera)
    image, state, labels = airport_frame("thesis-3", 600.0, camera, _crossing_scene(taxiway_grey))
    horizon, left, right, s0, depth_of = _geometry(camera, state, labels)
    assert pavement_beyond_edges(image, horizon, s0, left, right, depth_of(-23.0), 1,
                                 params=params) == ("left", "right")
    plain, state, labels = airport_frame("thesis-3", 600.0, camera, PaintedAirport(seed=4))
    horizon, left, right, s0, depth_of = _geometry(camera, state, labels)
    assert pavement_beyond_edges(plain, horizon, s0, left, right, depth_of(0.0), 1, params=params) == ()
    flush = PaintedAirport(seed=4, joining_taxiways=((-11.5, 1, 90.0, 150.0),), taxiway_grey=taxiway_grey)
    image, state, labels = airport_frame("thesis-3", 600.0, camera, flush)
    horizon, left, right, s0, depth_of = _geometry(camera, state, labels)
    assert pavement_beyond_edges(image, horizon, s0, left, right, depth_of(0.0), 1, params=params) == ()


@pytest.mark.slow
@pytest.mark.parametrize("distance", [400.0, 300.0])
def test_a_pavement_crossing_before_the_threshold_is_not_reported_as_the_threshold(distance):
    """The whole detector on the crossing frames (taxiway brighter than the grass): the
    crossing's near edge was reported as the threshold (4.3 and 6.8 px off, found). The
    threshold must now be withheld, saying why; the edges are still measured. On the same
    runway without the crossing at 300 m the threshold is found within 1 px (the check does not
    withhold a clean threshold; at 400 m that frame is not found at all, for other reasons)."""
    camera = CameraModel.default(SIZE)
    image, state, labels = airport_frame("thesis-3", distance, camera, _crossing_scene(122.0))
    result = detect_runway(image, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    assert result.found, result.reason
    assert not result.corners_found[:2].any(), (result.corners_uv[:2], labels.corners_uv[0, :2])
    assert "continues beyond the runway's" in result.reason, result.reason
    plain, state, labels = airport_frame("thesis-3", 300.0, camera, PaintedAirport(seed=4))
    result = detect_runway(plain, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    assert result.found and result.corners_found[:2].all(), result.reason
    assert np.linalg.norm(result.corners_uv[:2] - labels.corners_uv[0, :2], axis=1).max() < 1.0


@pytest.mark.slow
def test_a_parallel_taxiway_is_not_measured_in_place_of_a_runway_that_fails():
    """Ray-cast airport, 768 px, 1500 m, a taxiway joining the runway's right side just before
    the threshold: the runway (the best strip) fails its measurement (its refined edges meet the
    horizon 4.1 px apart, tolerance 4.0), and the parallel taxiway 185 m to its left, a narrower
    strip beside it, was measured in its place (found, edges 58 px off). Of parallel strips the
    runway is the widest: the frame must not be found on the taxiway (found with both edges
    within 2 px of the exact labels, or not found)."""
    from tests.helpers.detection_frames import edge_error_px
    camera = CameraModel.default(768)
    scene = PaintedAirport(seed=4, joining_taxiways=((-11.5, 1, 90.0, 150.0),), taxiway_grey=84.0)
    image, state, labels = airport_frame("thesis-3", 1500.0, camera, scene)
    result = detect_runway(image, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    if result.found:
        assert max(edge_error_px(camera, labels, result, side) for side in ("left", "right")) < 2.0, result.reason
