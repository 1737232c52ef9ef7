"""How far past where the surface seemed to end the threshold is looked for in the chroma
(:func:`visland.detection.transverse.find_transverse_line`, ``marking_band_max_widths``), on
synthetic colour frames drawn in the horizon's own coordinates (s along the horizon, d below it;
:mod:`visland.detection.horizon`), so the geometry is exact.

Threshold markings are as long in metres on any runway, so on a narrow one they reach more runway
widths. The robustness study's '16 stripes, 30 m wide' at 3.3 km, 2048 px: the surface seemed to
end 4.9 px (3.1 widths) inside the threshold, beyond the reach of a 45 m runway's marking band,
and the grey step put the threshold 2.4-2.7 px short in one frame of three. The geometry below is
that frame's: the threshold 136 px below the horizon, the runway 23 px wide there (a 30 m
runway 180 m below the camera, 3.3 km out)."""
import math
from dataclasses import replace

import numpy as np
import pytest

from visland.camera import CameraModel
from visland.detection import DetectorParams
from visland.detection.horizon import horizon_frame
from visland.detection.refine import PixelLine
from visland.detection.transverse import find_transverse_line

S0, K_LEFT, K_RIGHT = 5.0, -0.085, 0.085     # V1 on the horizon (px from Q), the edges' slopes ds/dd
D_THRESHOLD = 136.0                           # depth of the threshold (the pavement's start)
D_EXPECTED = D_THRESHOLD - 4.9                # where the surface seemed to end
PAVEMENT, NEAR_PAVEMENT = (120, 120, 120), (131, 131, 131)
GRASS = (110, 150, 90)                        # chroma 60, grey level 131


def _frame(ground_before=None):
    """A 2048 px frame (rows 1000-1399 drawn, the horizon crossing them): grass; the runway
    between the edges, darker pavement to D_EXPECTED and then, to D_THRESHOLD, pavement and
    blended stripes as light as the grass (so the grey levels see the surface end at
    D_EXPECTED); ``ground_before`` (RGB) between D_EXPECTED + 1 and D_THRESHOLD instead of
    pavement when given (the pavement ending there)."""
    camera = CameraModel.default(2048)
    horizon = horizon_frame(camera, 0.0, math.radians(4.0))
    rows = slice(1000, 1400)
    v, u = np.mgrid[rows, 0:2048]
    sd = horizon.to_sd(np.stack([u.ravel(), v.ravel()], axis=1).astype(float))
    s, d = sd[:, 0].reshape(u.shape), sd[:, 1].reshape(u.shape)
    colour = np.empty((2048, 2048, 3), np.uint8)
    colour[:] = GRASS
    band = colour[rows]
    between = (s >= S0 + K_LEFT * d) & (s <= S0 + K_RIGHT * d) & (d > 0)
    band[between & (d < D_EXPECTED)] = PAVEMENT
    band[between & (d >= D_EXPECTED) & (d < D_THRESHOLD)] = NEAR_PAVEMENT
    if ground_before is not None:
        band[between & (d >= D_EXPECTED + 1.0) & (d < D_THRESHOLD)] = ground_before
    band[d < 0] = (200, 210, 230)
    grey = (0.299 * colour[..., 0] + 0.587 * colour[..., 1] + 0.114 * colour[..., 2]).round().astype(np.uint8)

    def edge(k):
        a, b = horizon.pencil_point(S0, k, 60.0), horizon.pencil_point(S0, k, 200.0)
        return PixelLine(np.asarray(a, float), (b - a) / np.linalg.norm(b - a))
    return colour, grey, horizon, edge(K_LEFT), edge(K_RIGHT), DetectorParams().scaled_to(camera)


def _threshold(colour, grey, horizon, left, right, params):
    return find_transverse_line(grey, horizon, S0, left, right, D_EXPECTED, (D_EXPECTED - 12.0, D_EXPECTED + 12.0),
                                outward=1, min_step=params.min_contrast, colour=colour, params=params)


def test_the_threshold_is_found_in_the_chroma_past_a_narrow_runways_marking_band():
    colour, grey, horizon, left, right, params = _frame()
    found = _threshold(colour, grey, horizon, left, right, params)
    assert found is not None and found.method == "chroma"
    assert abs(found.depth_px - D_THRESHOLD) < 0.3, found


def test_within_a_wide_runways_band_only_the_chroma_step_is_out_of_reach():
    colour, grey, horizon, left, right, params = _frame()
    found = _threshold(colour, grey, horizon, left, right, replace(params, marking_band_max_widths=0.0))
    assert found is None or abs(found.depth_px - D_THRESHOLD) > 1.0, found


@pytest.mark.parametrize("ground_before", [(134, 131, 128), (128, 134, 128)])
def test_a_step_past_ground_of_another_colour_is_the_grounds_not_the_threshold(ground_before):
    # the pavement ends just past where the surface seemed to end, on ground whose colour differs
    # from the pavement's by less than a chroma step (6 levels: a bare field), and a green field
    # begins farther: the chroma is not the pavement's up to that step, so it is not taken (it
    # is, without that condition)
    colour, grey, horizon, left, right, params = _frame(ground_before)
    found = _threshold(colour, grey, horizon, left, right, params)
    assert found is None or abs(found.depth_px - D_THRESHOLD) > 1.0, found
