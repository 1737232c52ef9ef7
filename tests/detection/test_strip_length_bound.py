"""A strip seen longer than any runway is a line, not a runway (issue 11: a confident wrong
answer is the failure that matters).

On a runway nearly as grey as its grass, the strongest strip in view is a side stripe: its two
flanks are a pair of edges of opposite steps meeting on the horizon, 0.9 m apart. The runway's
own pair (the stripes' inner flanks) encloses a surface that differs from the grass by a few
grey levels against the paint's step of 130, and is no hypothesis. The stripe was reported as
the runway at confidence 0.9. A runway is at most about 130 times longer than wide; the span
seen of a strip can only be shorter than the strip, so one seen over more than
``max_length_to_width`` (300) of its widths is refused.
"""
import math

import numpy as np
import pytest

from tests.helpers.detection_frames import airport_frame, edge_error_px
from tests.helpers.raycast_airport import PaintedAirport
from visland.camera import CameraModel
from visland.detection import DetectorParams, detect_runway
from visland.detection.horizon import widths_along
from visland.runway import Runway


@pytest.mark.parametrize("length_m, width_m, height_m, x_near_m", [
    (3000.0, 45.0, 60.0, 1100.0), (1200.0, 23.0, 210.0, 4000.0), (2000.0, 0.9, 30.0, 400.0)])
def test_the_ratio_is_the_ground_strips_length_over_width(length_m, width_m, height_m, x_near_m):
    """Closed-form projection: a level pinhole camera ``height_m`` above flat ground sees the
    ground ``x`` metres ahead ``f h / x`` pixels below the horizon, and a strip ``W`` wide
    spreads over ``(W / h) d`` pixels at depth ``d``: the ratio read from the image is L / W."""
    fx = 2472.0
    d_near, d_far = fx * height_m / x_near_m, fx * height_m / (x_near_m + length_m)
    ratio = widths_along(fx, d_near, d_far, width_m / height_m)
    assert math.isclose(ratio, length_m / width_m, rel_tol=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("distance_m", [400.0, 600.0])
def test_a_side_stripe_is_not_reported_as_the_runway(distance_m):
    """visland's independent ray-cast airport, a 2000 x 45 m runway of grey 100 on grass of 105
    (+- 12), 2048 px, frames searched from scratch: at 400 and 600 m a side stripe was reported
    as the runway (its near corners 182-273 px off, confidence 0.91). Refused now: the frame is
    not found, or found within 2 px; the bound lifted, the stripe again."""
    camera = CameraModel.default(2048)
    runway = Runway(length_m=2000.0, width_m=45.0)
    scene = PaintedAirport(runway_length_m=2000.0, runway_grey=100.0)
    image, state, labels = airport_frame("thesis-1", distance_m, camera, scene, runway=runway)
    roll, pitch = float(state.roll_rad[0]), float(state.pitch_rad[0])

    def near_errors(result):
        found = result.corners_found[:2]
        return np.linalg.norm(result.corners_uv[:2][found] - labels.corners_uv[0][:2][found], axis=1)

    result = detect_runway(image, camera, roll, pitch)
    assert not result.found or (near_errors(result) < 2.0).all(), (near_errors(result), result.reason)
    lifted = detect_runway(image, camera, roll, pitch, params=DetectorParams(max_length_to_width=1e9))
    assert lifted.found and near_errors(lifted).max() > 100.0, lifted.reason


@pytest.mark.slow
def test_a_road_beside_the_approach_is_not_reported_as_the_runway():
    """The ray-cast approach's airport (``benchmarks/raycast_approach.py --runway-grey 100``: a
    2600 x 40 m runway of grey 100 on grass of 105, the parallel taxiway, the joining taxiways,
    haze 6 km) at 4.4 km, 2048 px, searched from scratch: the runway barely stands out, and the
    road 340 m to its right, 7 m wide and unmarked, was reported in its place (edges 153-171 px
    off, confidence 0.68; on the approach, 7 frames from 4.6 to 4.1 km at 0.78-0.85). It is seen
    over 489 of its widths: refused."""
    camera = CameraModel.default(2048)
    runway = Runway(length_m=2600.0, width_m=40.0)
    scene = PaintedAirport(runway_length_m=2600.0, runway_width_m=40.0, runway_grey=100.0, haze_range_m=6000.0,
                           joining_taxiways=((300.0, 1, 90.0, 260.0), (450.0, -1, 35.0, 260.0)),
                           taxiway_grey=84.0, taxiway_offset_m=-162.5)
    image, state, labels = airport_frame("thesis-1", 4400.0, camera, scene, runway=runway)
    roll, pitch = float(state.roll_rad[0]), float(state.pitch_rad[0])
    result = detect_runway(image, camera, roll, pitch)
    assert not result.found and "of its own widths" in result.reason, result.reason
    lifted = detect_runway(image, camera, roll, pitch, params=DetectorParams(max_length_to_width=1e9))
    assert lifted.found and min(edge_error_px(camera, labels, lifted, side) for side in ("left", "right")) > 100.0
