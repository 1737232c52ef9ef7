"""Where the threshold stripes start, 6 m past the threshold, on synthetic grey frames drawn in
metres on the ground and sampled like a rendered frame (each pixel the mean of 4 x 4 samples,
then a blur of half a pixel); the SPEC camera at 2048 px, 12 stripes 1.8 m wide and 30 m long.

- A displaced threshold's bar blended with the stripes after it
  (:func:`visland.detection.threshold_marking.threshold_marking`). The robustness study's
  displaced threshold at 2048 px, 1 km out: the bar (1.8 m) and the gap after it (4.2 m) span a
  pixel of depth, so the band test sees one band, its first lines striped. Taken for the
  stripes' start, the threshold was placed 6 m before it, 6 m short of the bar (1.0-1.5 px, in
  one frame out of three from 1.7 km to 650 m, by the phase of the bar against the lines read).
  The stripes begin where the paint varies across the width, which a bar across does not change.
  A 45 m runway seen from 67 m above the ground (3 deg from 1 km), the threshold 1000-1003 m
  ahead (every phase of the lines read), 300 m of pavement before it.
- The stripes' start taken for the threshold where the pavement is as light as the ground
  (:func:`visland.detection.threshold_marking.starts_on_its_stripes`): 'concrete, sand, mono' at
  2048 px kept thresholds 2.4-3.0 px beyond the true one from 680 to 510 m, where the 0.1 widths
  read before the stripes span 1.3-1.7 px and under 2 px were not read.
"""
import math

import cv2
import numpy as np
import pytest

from visland.camera import CameraModel
from visland.detection import DetectorParams
from visland.detection.horizon import horizon_frame
from visland.detection.refine import PixelLine
from visland.detection.threshold_marking import starts_on_its_stripes, threshold_marking

WIDTH_M, HEIGHT_M = 45.0, 67.0
DISPLACED_M = 300.0
GRASS, PAVEMENT, PAINT = 110.0, 70.0, 190.0
SUPERSAMPLE = 4
S0 = 0.0                                       # V1 on the horizon, px from Q


def _paint(x_m, y_m, bar, stripes=True, bar_m=1.8):
    """Paint share at ``x_m`` metres past the threshold, ``y_m`` from the centre line."""
    stripes = stripes & (x_m >= 6.0) & (x_m < 36.0) & (np.abs(y_m) <= 0.5 * WIDTH_M - 1.8) & \
        (np.floor((y_m + 0.5 * WIDTH_M - 1.8) / 1.8) % 2 == 0)
    painted = stripes | ((x_m >= 0.0) & (x_m < bar_m)) if bar else stripes
    return painted.astype(float)


def _blotches(x_m, y_m, amplitude):
    """A concrete surface's lighter and darker blotches, ``amplitude`` grey levels at most: a sum
    of waves 2-10 m long along the runway and 1-4 m across (seeded)."""
    if not amplitude:
        return 0.0
    rng = np.random.default_rng(7)
    total = 0.0
    for _ in range(8):
        kx, ky = 2.0 * np.pi / rng.uniform(2.0, 10.0), 2.0 * np.pi / rng.uniform(1.0, 4.0)
        total = total + np.cos(kx * x_m + rng.uniform(-1.0, 1.0) * ky * y_m + rng.uniform(0.0, 2.0 * np.pi))
    return amplitude * np.clip(total / 3.0, -1.0, 1.0)


def _frame(threshold_m, bar, height_m=HEIGHT_M, before_m=DISPLACED_M, grass=GRASS, pavement=PAVEMENT, paint=PAINT,
           stripes=True, bar_m=1.8, blotches=0.0):
    """Grey 2048 px frame and its horizon, edges and params, and the threshold's depth below the
    horizon, for a threshold ``threshold_m`` ahead seen from ``height_m`` above the ground, with
    ``before_m`` of pavement before it, the ground at grey level ``grass``, the pavement at
    ``pavement`` and the paint at ``paint`` (a band ``bar_m`` long across the width where ``bar``,
    the stripes after it where ``stripes``), the surface's blotches ``blotches`` levels at most."""
    camera = CameraModel.default(2048)
    horizon = horizon_frame(camera, 0.0, math.radians(2.0))
    f = camera.fx

    def ground(v0, v1, scale):
        v, u = np.mgrid[v0 * scale:v1 * scale, 0:camera.width * scale]
        sd = horizon.to_sd((np.stack([u.ravel(), v.ravel()], axis=1) + 0.5) / scale - 0.5)
        s, d = sd[:, 0].reshape(u.shape), sd[:, 1].reshape(u.shape)
        with np.errstate(divide="ignore", invalid="ignore"):
            x_m = f * height_m / d - threshold_m             # metres past the threshold
            y_m = (s - S0) * height_m / d                    # metres right of the centre line
            on_runway = (d > 0) & (np.abs(y_m) <= 0.5 * WIDTH_M) & (x_m >= -before_m)
            surface = pavement + np.where(on_runway, _blotches(x_m, y_m, blotches), 0.0)
        return on_runway, np.where(on_runway, _paint(x_m, y_m, bar, stripes, bar_m), 0.0), d, surface

    on_runway, _, d, surface = ground(0, camera.height, 1)
    grey = np.where(on_runway, surface, grass)
    grey[d < 0] = 220.0
    # the marking's rows, supersampled: the paint averaged over each pixel
    d_thr = f * height_m / threshold_m
    rows = np.flatnonzero((d[:, camera.width // 2] < d_thr + 3) & (d[:, camera.width // 2] > d_thr * 0.9))
    v0, v1 = int(rows.min()), int(rows.max()) + 1
    inside, share, _, surface = ground(v0, v1, SUPERSAMPLE)
    fine = np.where(inside, surface + share * (paint - surface), grass)
    grey[v0:v1] = fine.reshape(v1 - v0, SUPERSAMPLE, camera.width, SUPERSAMPLE).mean(axis=(1, 3))
    grey = cv2.GaussianBlur(grey.astype(np.float32), (0, 0), 0.5).round().astype(np.uint8)

    def edge(k):
        a, b = horizon.pencil_point(S0, k, 100.0), horizon.pencil_point(S0, k, 300.0)
        return PixelLine(np.asarray(a, float), (b - a) / np.linalg.norm(b - a))
    k_half = 0.5 * WIDTH_M / height_m                 # the edges' slopes ds/dd: s = S0 -+ k_half d
    return grey, horizon, edge(-k_half), edge(k_half), DetectorParams().scaled_to(camera), d_thr


@pytest.mark.parametrize("bar", [True, False], ids=["bar and stripes", "stripes only"])
def test_threshold_placed_at_the_bar_or_6_m_before_the_stripes(bar):
    errors = []
    for threshold_m in np.linspace(1000.0, 1003.0, 7):      # 0.5 px of depth: every phase of the lines
        grey, horizon, left, right, params, d_thr = _frame(threshold_m, bar)
        d_pavement = horizon.camera.fx * HEIGHT_M / (threshold_m - DISPLACED_M)
        found = threshold_marking(grey, horizon, S0, left, right, d_pavement, 20.0, params.min_contrast,
                                  surface_level=PAVEMENT, pavement_step=PAVEMENT - GRASS, params=params)
        assert found is not None and found.line is not None, threshold_m
        errors.append(found.line.depth_px - d_thr)
    # 6 m here is 1.0 px of depth: a bar taken for the stripes' start is 1 px off (0.82 px at
    # 1000 m with the threshold placed from the mean level's rise; stripes only: 0.28 px)
    assert np.max(np.abs(errors)) <= 0.25, np.round(errors, 2)


@pytest.mark.parametrize("ground", [208.0, 128.0], ids=["snow, brighter", "darker ground"])
def test_dim_paint_beside_a_brighter_ground_is_still_the_threshold_marking(ground):
    """Held-out scene draw 15 of the robustness study (2048 px, a displaced threshold on concrete
    beside snow, haze): the bar and stripes stood 20-29 grey levels over the concrete, the snow
    36-42 over it. Markings had to outshine the pavement by the ground's step, so the threshold
    stayed where the pavement begins, 195-688 px short, reported found, from 540 to 350 m. White
    paint cannot outshine snow: beside a brighter ground half its step is asked. Beside a darker
    ground by as much, paint this dim is no marking (a lighter patch of surface), as before."""
    pavement, paint = 168.0, 190.0
    errors = []
    for threshold_m in np.linspace(1000.0, 1003.0, 4):
        grey, horizon, left, right, params, d_thr = _frame(threshold_m, True, grass=ground, pavement=pavement,
                                                           paint=paint)
        d_pavement = horizon.camera.fx * HEIGHT_M / (threshold_m - DISPLACED_M)
        found = threshold_marking(grey, horizon, S0, left, right, d_pavement, 20.0, params.min_contrast,
                                  surface_level=pavement, pavement_step=pavement - ground, params=params)
        if ground < pavement:
            assert found is None or found.line is None, threshold_m
            continue
        assert found is not None and found.line is not None, threshold_m
        errors.append(found.line.depth_px - d_thr)
    if errors:
        assert np.max(np.abs(errors)) <= 0.25, np.round(errors, 2)


@pytest.mark.parametrize("paint", [190.0, 250.0], ids=["dimmer than the snow's step", "brighter"])
def test_a_band_without_stripes_beside_a_brighter_ground_must_outshine_it(paint):
    """A band across the width without stripes (15 m long, 1.8 px of depth at 1 km), dimmer over
    the pavement than the brighter ground's step, is no threshold marking: a lighter patch of a
    patched surface is such a band (held-out draw 10, concrete on snow: a patch 11 widths in,
    100 grey levels over the concrete with the snow 107-112 over it, would have moved the
    threshold 18.7 px). The same band outshining the pavement by the ground's step is taken
    for a bar, as before."""
    pavement, ground, threshold_m = 168.0, 208.0, 1000.0
    grey, horizon, left, right, params, d_thr = _frame(threshold_m, True, grass=ground, pavement=pavement,
                                                       paint=paint, stripes=False, bar_m=15.0)
    d_pavement = horizon.camera.fx * HEIGHT_M / (threshold_m - DISPLACED_M)
    found = threshold_marking(grey, horizon, S0, left, right, d_pavement, 20.0, params.min_contrast,
                              surface_level=pavement, pavement_step=pavement - ground, params=params)
    if paint - pavement >= ground - pavement:
        assert found is not None and found.line is not None and found.kind == "bar", found
        assert abs(found.line.depth_px - d_thr) <= 0.5, (found.line.depth_px, d_thr)
    else:
        assert found is None or found.line is None, found


def test_dim_stripes_on_a_blotched_concrete_beside_snow_are_placed():
    """Stripes 22 levels over a concrete whose blotches reach 6 levels, beside snow 40 over it:
    they cross more marks than the blotches do on the pavement before them, and are placed (the
    blotches alone, held-out draw 13: tests/detection/test_detection_doubtful_corners.py)."""
    pavement, ground, threshold_m = 168.0, 208.0, 1000.0
    grey, horizon, left, right, params, d_thr = _frame(threshold_m, True, grass=ground, pavement=pavement,
                                                       paint=190.0, blotches=6.0)
    d_pavement = horizon.camera.fx * HEIGHT_M / (threshold_m - DISPLACED_M)
    found = threshold_marking(grey, horizon, S0, left, right, d_pavement, 20.0, params.min_contrast,
                              surface_level=pavement, pavement_step=pavement - ground, params=params)
    assert found is not None and found.line is not None
    assert abs(found.line.depth_px - d_thr) <= 0.5, (found.line.depth_px, d_thr)


def test_a_threshold_on_the_stripes_start_is_told_where_the_setback_spans_a_pixel():
    """700 m out, 52 m above the ground, the pavement 9 grey levels darker than the ground (the
    step 'concrete, sand, mono' gives): the 0.1 widths read before the stripes span 1.2 px, the
    6 m to them 1.6 px. A threshold placed where the stripes start is told (the old code read
    only 2 px or more); one placed on the true threshold, plain pavement just inside it, is not."""
    threshold_m, height_m = 700.0, 52.0
    grey, horizon, left, right, params, d_thr = _frame(threshold_m, False, height_m, before_m=0.0,
                                                       grass=PAVEMENT + 9.0)
    d_stripes = horizon.camera.fx * height_m / (threshold_m + 6.0)     # 1.6 px nearer the horizon
    assert starts_on_its_stripes(grey, horizon, S0, left, right, d_stripes, params.min_contrast, params=params)
    assert not starts_on_its_stripes(grey, horizon, S0, left, right, d_thr, params.min_contrast, params=params)
