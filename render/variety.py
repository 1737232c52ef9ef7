"""Seeded random scenes for campaigns: one integer draws a runway size and a whole SceneParams.

:func:`draw_variety` is the one place where the ranges live (issue 11): runway 1200-4000 m by
23-60 m; marking sets (ICAO with 4-16 threshold stripes, FAA, worn, none, displaced threshold,
blast pad), side stripes or not; asphalt, concrete or patched pavement; green, dry, sand, snow
or urban surroundings; taxiways (standard, near the threshold, at an angle, none), a second runway; sun
from 5 deg to overhead, overcast or dusk; visibility 1.5-30 km (log-uniform); colour or
monochrome sensor, noise, blur, vignetting and JPEG compression. The same seed gives the same
draw on every machine (``numpy.random.default_rng([seed, 0x5CE7E])``, values rounded).
"""
from __future__ import annotations

import math

import numpy as np

from .params import LIGHTING, MARKINGS, SURROUNDINGS, SceneParams

__all__ = ["Variety", "draw_variety", "RUNWAY_LENGTH_RANGE_M", "RUNWAY_WIDTH_RANGE_M"]

RUNWAY_LENGTH_RANGE_M = (1200.0, 4000.0)
RUNWAY_WIDTH_RANGE_M = (23.0, 60.0)


class Variety(tuple):
    """``(scene, runway_length_m, runway_width_m)`` of one draw.

    Parameters
    ----------
    scene : SceneParams
        The drawn scene.
    runway_length_m, runway_width_m : float
        The drawn runway size, metres.
    """

    __slots__ = ()

    def __new__(cls, scene: SceneParams, runway_length_m: float, runway_width_m: float):
        return super().__new__(cls, (scene, runway_length_m, runway_width_m))

    scene = property(lambda self: self[0])
    runway_length_m = property(lambda self: self[1])
    runway_width_m = property(lambda self: self[2])


def draw_variety(seed: int, base: SceneParams | None = None) -> Variety:
    """Draw a runway size and a scene from ``seed``.

    Parameters
    ----------
    seed : int
        Non-negative; also the scene's own texture seed.
    base : SceneParams, optional
        Supplies what is not drawn (texel size, anisotropy, msaa).

    Returns
    -------
    Variety
    """
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"variety seed must be a non-negative integer, got {seed!r}")
    rng = np.random.default_rng([int(seed), 0x5CE7E])
    base = base or SceneParams()
    length = round(float(rng.uniform(*RUNWAY_LENGTH_RANGE_M)), 1)
    width = round(float(rng.uniform(*RUNWAY_WIDTH_RANGE_M)), 2)
    markings = str(rng.choice(MARKINGS, p=[0.3, 0.15, 0.15, 0.1, 0.15, 0.15]))
    stripes = int(rng.choice([0, 4, 6, 8, 10, 12, 14, 16], p=[0.3] + [0.1] * 7))
    lighting = str(rng.choice(LIGHTING, p=[0.6, 0.25, 0.15]))
    sun_elevation = round(float(rng.uniform(5.0, 90.0)), 2)
    if lighting == "dusk":
        sun_elevation = round(float(rng.uniform(5.0, 10.0)), 2)
    values = dict(
        seed=int(seed),
        surface=str(rng.choice(("asphalt", "concrete", "patched"))),
        markings=markings,
        threshold_stripes=stripes,
        side_stripes=bool(rng.random() < 0.75),
        marking_wear=round(float(rng.uniform(0.0, 0.6)), 3),
        rubber_deposits=round(float(rng.uniform(0.0, 1.0)), 3),
        pre_threshold_m=round(float(rng.uniform(60.0, 400.0)), 1),
        surroundings=str(rng.choice(SURROUNDINGS)),
        taxiways=str(rng.choice(("standard", "near_threshold", "none"), p=[0.4, 0.45, 0.15])),
        second_runway=bool(rng.random() < 0.3),
        lighting=lighting,
        sun_azimuth_deg=round(float(rng.uniform(0.0, 360.0)) % 360.0, 2),
        sun_elevation_deg=sun_elevation,
        visibility_m=round(float(math.exp(rng.uniform(math.log(1500.0), math.log(30000.0)))), 1),
        cloud_cover=round(float(rng.uniform(0.0, 0.8)), 3),
        monochrome=bool(rng.random() < 0.4),
        noise_std=round(float(rng.uniform(0.0, 6.0)), 2),
        blur_sigma_px=round(float(rng.choice([0.0, rng.uniform(0.3, 1.5)])), 3),
        vignetting=round(float(rng.choice([0.0, rng.uniform(0.1, 0.5)])), 3),
        jpeg_quality=int(rng.choice([0, 0, int(rng.integers(40, 96))])),
    )
    # drawn last, so that every draw above stays what it was before taxiways at an angle existed
    if values["taxiways"] in ("standard", "near_threshold") and rng.random() < 0.4:
        values["taxiways"] = "oblique"
    data = base.to_dict()
    data.update(values)
    return Variety(SceneParams.from_dict(data, source=f"variety {seed}"), length, width)
