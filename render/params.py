"""Scene parameters of the renderer: one frozen dataclass, validated, JSON/TOML round trip.

Everything that changes how a frame looks lives here; the runway's size comes from the
:class:`visland.runway.Runway` of the scenario, the camera from :class:`visland.camera.CameraModel`.
The default is a clear day: sun high in the south-west, 30 km visibility, light sensor noise,
no multisampling (see ``msaa_samples``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from visland.params import ParamsFile

__all__ = ["SceneParams", "SURFACES", "STYLES", "MARKINGS", "SURROUNDINGS", "LIGHTING", "TAXIWAYS"]

SURFACES = ("asphalt", "concrete", "patched")
#: Marking sets (see :mod:`visland.render.markings`): ``icao`` (Annex 14), ``faa`` (FAA AC
#: 150/5340-1 proportions: longer, narrower threshold stripes), ``worn`` (ICAO, paint mostly
#: gone), ``none`` (bare pavement), ``displaced`` (ICAO with a displaced threshold: pavement
#: with white arrows before a transverse bar at the threshold), ``blast_pad`` (ICAO with a
#: paved blast pad carrying yellow chevrons before the threshold).
MARKINGS = ("icao", "faa", "worn", "none", "displaced", "blast_pad")
#: What lies around the airport: fields and grass of these colours, or a town.
SURROUNDINGS = ("green", "dry", "sand", "snow", "urban")
#: ``day``: sun and sky as given; ``overcast``: diffuse light, grey sky; ``dusk``: dim, warm.
LIGHTING = ("day", "overcast", "dusk")
#: Taxiway layouts: ``standard`` (parallel taxiway on the right, connectors far from the
#: threshold), ``near_threshold`` (also connectors within 300 m of the threshold on both sides
#: and a parallel taxiway on the left), ``oblique`` (parallel taxiways on both sides joined by
#: taxiways at 30-45 deg, two of them within 200 m of the threshold), ``none`` (no taxiways,
#: apron or buildings).
TAXIWAYS = ("standard", "near_threshold", "none", "oblique")
#: ``realistic``: textured scene; ``flat``: flat colours for label checks (white runway,
#: black ground and sky, no markings, no haze, no noise).
STYLES = ("realistic", "flat")


@dataclass(frozen=True)
class SceneParams(ParamsFile):
    """How the airport scene looks and how the sensor degrades it.

    Parameters
    ----------
    seed : int
        Seed of every procedural texture and of the sensor noise (frame noise is seeded by
        ``seed`` and the frame index).
    style : str
        ``"realistic"`` or ``"flat"`` (see :data:`STYLES`).
    surface : str
        Runway pavement, ``"asphalt"`` or ``"concrete"``.
    marking_wear : float
        0 (fresh paint) to 1 (paint mostly gone in the touchdown zones).
    rubber_deposits : float
        0 to 1: darkness of the tyre marks in the touchdown zones.
    sun_azimuth_deg : float
        Direction of the sun from true north, degrees, in [0, 360).
    sun_elevation_deg : float
        Sun elevation above the horizon, degrees, in [5, 90].
    visibility_m : float
        Meteorological optical range (5 % contrast, Koschmieder), metres, in [300, 80000].
    cloud_cover : float
        0 (clear sky) to 1 (overcast look of the sky dome).
    noise_std : float
        Sensor noise, standard deviation in digital numbers of the 8-bit image, in [0, 30].
    blur_sigma_px : float
        Gaussian optical blur, pixels, in [0, 5] (0: none).
    msaa_samples : int
        Multisample anti-aliasing samples: 0 (default), 2 or 4. llvmpipe's MSAA doubles the cost
        of a frame (about +0.15 s of CPU at 2048x2048), so it is off by default; the flat preset
        turns it on for sub-pixel label checks.
    anisotropy : float
        Taps of the anisotropic filter of the pavement textures (runway markings seen at grazing
        angles stay sharp), 1 (off) to 16; done in the shader on the pavements only.
    texel_m : float
        Runway marking texture resolution, metres per texel, in [0.03, 0.5].
    distractors : bool
        Draw taxiways, apron, buildings and roads.
    markings : str
        Marking set, one of :data:`MARKINGS`.
    threshold_stripes : int
        Number of threshold stripes, an even number from 4 to 16, or 0 for Annex 14's count
        for the runway's width.
    side_stripes : bool
        Paint the runway side stripes.
    pre_threshold_m : float
        Length of the displaced-threshold pavement or the blast pad before the threshold
        (markings ``displaced`` / ``blast_pad``), metres, in [30, 600].
    surroundings : str
        One of :data:`SURROUNDINGS`.
    taxiways : str
        Taxiway layout, one of :data:`TAXIWAYS` (with ``distractors``).
    second_runway : bool
        A second, parallel runway 400 m to the left, staggered (with ``distractors``).
    lighting : str
        One of :data:`LIGHTING`.
    monochrome : bool
        Grey-level sensor (the three channels of the frame are equal).
    vignetting : float
        Light fall-off at the image corners, 0 (none) to 0.6 (corners 60 % darker).
    jpeg_quality : int
        0 (no compression) or a JPEG quality from 5 to 100: each frame goes through JPEG
        encoding and decoding (blocking and ringing) before it is stored.
    """

    params_kind: ClassVar[str] = "scene"
    toml_table: ClassVar[str | None] = "scene"


    seed: int = 0
    style: str = "realistic"
    surface: str = "asphalt"
    marking_wear: float = 0.25
    rubber_deposits: float = 0.5
    sun_azimuth_deg: float = 210.0
    sun_elevation_deg: float = 45.0
    visibility_m: float = 30000.0
    cloud_cover: float = 0.3
    noise_std: float = 1.5
    blur_sigma_px: float = 0.0
    msaa_samples: int = 0
    anisotropy: float = 8.0
    texel_m: float = 0.08
    distractors: bool = True
    markings: str = "icao"
    threshold_stripes: int = 0
    side_stripes: bool = True
    pre_threshold_m: float = 150.0
    surroundings: str = "green"
    taxiways: str = "standard"
    second_runway: bool = False
    lighting: str = "day"
    monochrome: bool = False
    vignetting: float = 0.0
    jpeg_quality: int = 0

    def __post_init__(self):
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ValueError(f"scene seed must be a non-negative integer, got {self.seed!r}")
        if self.style not in STYLES:
            raise ValueError(f"scene style must be one of {', '.join(STYLES)}, got {self.style!r}")
        if self.surface not in SURFACES:
            raise ValueError(f"scene surface must be one of {', '.join(SURFACES)}, got {self.surface!r}")
        ranges = (
            ("marking_wear", 0.0, 1.0), ("rubber_deposits", 0.0, 1.0),
            ("sun_azimuth_deg", 0.0, 360.0), ("sun_elevation_deg", 5.0, 90.0),
            ("visibility_m", 300.0, 80000.0), ("cloud_cover", 0.0, 1.0),
            ("noise_std", 0.0, 30.0), ("blur_sigma_px", 0.0, 5.0),
            ("anisotropy", 1.0, 16.0), ("texel_m", 0.03, 0.5),
            ("pre_threshold_m", 30.0, 600.0), ("vignetting", 0.0, 0.6),
        )
        for name, low, high in ranges:
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError(f"scene {name} must be a finite number, got {value!r}")
            if not low <= value <= high:
                raise ValueError(f"scene {name} must lie in [{low:g}, {high:g}], got {value:g}")
            object.__setattr__(self, name, float(value))
        if self.msaa_samples not in (0, 2, 4) or isinstance(self.msaa_samples, bool):
            raise ValueError(f"scene msaa_samples must be 0, 2 or 4, got {self.msaa_samples!r}")
        for name in ("distractors", "side_stripes", "second_runway", "monochrome"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"scene {name} must be true or false, got {getattr(self, name)!r}")
        for name, choices in (("markings", MARKINGS), ("surroundings", SURROUNDINGS), ("lighting", LIGHTING),
                              ("taxiways", TAXIWAYS)):
            if getattr(self, name) not in choices:
                raise ValueError(f"scene {name} must be one of {', '.join(choices)}, got {getattr(self, name)!r}")
        n = self.threshold_stripes
        if isinstance(n, bool) or not isinstance(n, int) or not (n == 0 or (4 <= n <= 16 and n % 2 == 0)):
            raise ValueError(f"scene threshold_stripes must be 0 (by the runway's width) or an even number from "
                             f"4 to 16, got {n!r}")
        q = self.jpeg_quality
        if isinstance(q, bool) or not isinstance(q, int) or not (q == 0 or 5 <= q <= 100):
            raise ValueError(f"scene jpeg_quality must be 0 (none) or an integer from 5 to 100, got {q!r}")

    # ----------------------------------------------------------------- presets
    @classmethod
    def flat(cls, **overrides) -> "SceneParams":
        """Flat colours for label checks: white runway on black, no markings, haze or noise."""
        base = dict(style="flat", noise_std=0.0, blur_sigma_px=0.0, distractors=False, cloud_cover=0.0, msaa_samples=4)
        base.update(overrides)
        return cls(**base)

    # ----------------------------------------------------------------- files