"""Does the pavement run on past a runway end found? :func:`visland.detection.transverse.pavement_runs_on`
on synthetic colour frames drawn in the horizon's own coordinates (s along the horizon, d below
it; :mod:`visland.detection.horizon`), so the geometry is exact: a grey runway between two
edges meeting the horizon at V1, on coloured ground.

Past a step inside the pavement (where the touchdown zone's darker rubber ends) the surface
between the edges stays grey; past the runway's end it is the ground's colour. The robustness
study's 'concrete, dry grass' (clean concrete as light as dry grass in grey levels) kept ends
at the rubber's end, 42 px short at 2048 px, until this was read."""
import math

import numpy as np
import pytest

from visland.camera import CameraModel
from visland.detection import DetectorParams
from visland.detection.horizon import horizon_frame
from visland.detection.refine import PixelLine
from visland.detection.transverse import pavement_runs_on

S0, K_LEFT, K_RIGHT = 12.0, -0.25, 0.22      # V1 on the horizon (px from Q), the edges' slopes ds/dd
STEP_D = 90.0                                 # depth of the step the end was placed on


def _frame(ground_rgb, far_end_d: float):
    """A 512 px frame: the ground ``ground_rgb``; the runway (clean grey 150 from depth
    ``far_end_d``, rubber grey 110 from STEP_D on) between the edges; the sky above the horizon."""
    camera = CameraModel.default(512)
    horizon = horizon_frame(camera, 0.0, math.radians(4.0))
    v, u = np.mgrid[0:512, 0:512]
    sd = horizon.to_sd(np.stack([u.ravel(), v.ravel()], axis=1).astype(float))
    s, d = sd[:, 0].reshape(512, 512), sd[:, 1].reshape(512, 512)
    image = np.empty((512, 512, 3), np.uint8)
    image[:] = ground_rgb
    between = (s >= S0 + K_LEFT * d) & (s <= S0 + K_RIGHT * d)
    image[between & (d >= far_end_d)] = (150, 150, 150)
    image[between & (d >= STEP_D)] = (110, 110, 110)
    image[d < 0] = (200, 210, 230)

    def edge(k):
        a, b = horizon.pencil_point(S0, k, 60.0), horizon.pencil_point(S0, k, 200.0)
        return PixelLine(np.asarray(a, float), (b - a) / np.linalg.norm(b - a))
    return image, horizon, edge(K_LEFT), edge(K_RIGHT), DetectorParams().scaled_to(camera)


DRY_GRASS = (176, 150, 96)      # chroma 80; grey level about 153, the clean concrete's


@pytest.mark.parametrize("band_px", [3.0, 6.0])
def test_past_a_step_inside_the_pavement_the_grey_runs_on(band_px):
    image, horizon, left, right, params = _frame(DRY_GRASS, far_end_d=40.0)
    assert pavement_runs_on(image, horizon, S0, left, right, STEP_D, -1, band_px, params) is True


@pytest.mark.parametrize("band_px", [3.0, 6.0])
def test_past_the_runway_end_the_ground_begins(band_px):
    image, horizon, left, right, params = _frame(DRY_GRASS, far_end_d=STEP_D)
    assert pavement_runs_on(image, horizon, S0, left, right, STEP_D, -1, band_px, params) is False


def test_a_few_pixels_of_pavement_before_the_true_end_are_read():
    # the reciprocal runway's aiming-point paint taken for the end: 5.5 px of pavement past it,
    # then the grass ('16 stripes, 30 m wide' and 'variety 1' at 2048 px, 2.8 km): the default
    # band reads the pavement; one of 12.7 px (the edges' run-on stretch there) reads mostly the
    # grass and does not see it
    image, horizon, left, right, params = _frame(DRY_GRASS, far_end_d=STEP_D - 5.5)
    assert pavement_runs_on(image, horizon, S0, left, right, STEP_D, -1, params.end_chroma_band_px, params) is True
    assert pavement_runs_on(image, horizon, S0, left, right, STEP_D, -1, 12.7, params) is False


def test_grey_ground_cannot_tell():
    image, horizon, left, right, params = _frame((140, 140, 140), far_end_d=40.0)
    assert pavement_runs_on(image, horizon, S0, left, right, STEP_D, -1, 4.0, params) is None
