"""A threshold marking too far out to be placed (:func:`visland.detection.threshold_marking.threshold_marking`,
the *unresolved* case), on synthetic grey frames drawn in the horizon's own coordinates (s along
the horizon, d below it; :mod:`visland.detection.horizon`), supersampled so that a band a pixel
or two deep blends into its neighbours as in a rendered frame.

The robustness study's blast pad (120 m of pavement before the threshold) at 3.3 km, 1024 px:
the pad is 3.5 px of depth, the threshold's stripes blurred over 1.5 px at its end, the
aiming-point marks 10 px farther in. The unresolved test asked 3 px of plain pavement before a
brighter line, which the pad never shows, so the threshold stayed where the pad begins (near
corners 3.3-4.2 px off in 46 frames); once the rule was relaxed, a band test that skipped the
blended stripes took the aiming-point marks for the threshold marking (10 px off). The geometry
below is that frame's: the pad begins 73.4 px below the horizon, the runway 19 px wide there.
"""
import math

import numpy as np
import pytest

from visland.camera import CameraModel
from visland.detection import DetectorParams
from visland.detection.horizon import horizon_frame
from visland.detection.refine import PixelLine
from visland.detection.threshold_marking import threshold_marking

S0, K_LEFT, K_RIGHT = 3.0, -0.13, 0.13       # V1 on the horizon (px from Q), the edges' slopes ds/dd
# where the pavement begins (the pad's start): between two rows of pixel centres (at depths
# 66.93 + n), where the half-level crossing of the outline sampled at the centres lies, as the
# grey step that found it places it
D_START = 73.43
GRASS, PAVEMENT, PAINT = 147.0, 127.0, 175.0  # grey levels
SUPERSAMPLE = 4
#: Image row of the horizon at the centre column (roll 0: depth d is row - ROW_OF_HORIZON; the
#: pixel centres lie at depths 66.93 + n)
ROW_OF_HORIZON = 533.07


def _frame(bands):
    """A 1024 px grey frame: grass; between the edges, pavement from the horizon to ``D_START``
    with ``bands`` of paint across the whole width, ``(d_inner, d_outer, fraction)`` (the paint's
    share of the band's area: stripes blended with the asphalt between them). As in a rendered
    frame, the pavement's outline is sampled at the pixel centres and the paint, part of its
    texture, is averaged over each pixel (supersampled)."""
    camera = CameraModel.default(1024)
    horizon = horizon_frame(camera, 0.0, math.radians(4.0))

    def s_d(scale, v0=0, v1=1024):
        v, u = np.mgrid[v0 * scale:v1 * scale, 0:1024 * scale]
        sd = horizon.to_sd((np.stack([u.ravel(), v.ravel()], axis=1) + 0.5) / scale - 0.5)
        return sd[:, 0].reshape(u.shape), sd[:, 1].reshape(u.shape)
    # the paint only where it is: the rows of the bands (supersampling the whole frame took 3 s)
    paint = np.zeros((1024, 1024))
    for d_inner, d_outer, fraction in bands:
        v0 = int(np.floor(ROW_OF_HORIZON + d_inner)) - 1
        v1 = int(np.ceil(ROW_OF_HORIZON + d_outer)) + 2
        s, d = s_d(SUPERSAMPLE, v0, v1)
        fine = np.where((d >= d_inner) & (d < d_outer), fraction, 0.0)
        paint[v0:v1] = np.maximum(paint[v0:v1], fine.reshape(v1 - v0, SUPERSAMPLE, 1024, SUPERSAMPLE).mean(axis=(1, 3)))
    s, d = s_d(1)
    grey = np.full(s.shape, GRASS)
    runway = (s >= S0 + K_LEFT * d) & (s <= S0 + K_RIGHT * d) & (d > 0) & (d < D_START)
    grey[runway] = PAVEMENT + paint[runway] * (PAINT - PAVEMENT)
    grey[d < 0] = 220.0
    grey = grey.round().astype(np.uint8)

    def edge(k):
        a, b = horizon.pencil_point(S0, k, 30.0), horizon.pencil_point(S0, k, 120.0)
        return PixelLine(np.asarray(a, float), (b - a) / np.linalg.norm(b - a))
    return grey, horizon, edge(K_LEFT), edge(K_RIGHT), DetectorParams().scaled_to(camera)


def _marking(bands):
    grey, horizon, left, right, params = _frame(bands)
    return threshold_marking(grey, horizon, S0, left, right, D_START, 10.0, params.min_contrast,
                             surface_level=PAVEMENT, pavement_step=GRASS - PAVEMENT, params=params)


STRIPES_AT_START = (D_START - 1.2, D_START - 0.2, 0.25)     # a threshold where the pavement begins
STRIPES_PAST_PAD = (D_START - 4.2, D_START - 2.7, 0.25)     # the threshold 2.7 px in: a pad before it
AIMING_MARKS = (D_START - 11.0, D_START - 10.0, 0.8)       # marks farther in, nearly across the width


def test_a_threshold_whose_stripes_begin_the_pavement_stands():
    assert _marking([STRIPES_AT_START, AIMING_MARKS]) is None


@pytest.mark.parametrize("bands", [[STRIPES_PAST_PAD], [STRIPES_PAST_PAD, AIMING_MARKS]])
def test_stripes_a_few_pixels_past_the_pavements_start_make_the_threshold_doubtful(bands):
    found = _marking(bands)
    assert found is not None and found.line is None and found.kind == "unresolved", found


def test_marks_farther_in_alone_are_not_taken_for_a_threshold_past_a_pad():
    # no stripes at all at the start: the first marking inside the pavement is the farther one;
    # it may be placed only where it is (a bar across the width), never nearer the start
    found = _marking([AIMING_MARKS])
    if found is not None and found.line is not None:
        assert abs(found.line.depth_px - AIMING_MARKS[1]) < 1.0, found
