"""Runway geometry in the runway frame R (truth side: the estimators never read it).

R has its origin at the centre of the threshold line, x along the *horizontal projection* of
the centreline in the landing direction, y to the right, z down along gravity: R is level
whatever the runway's slope, so ``dH = -z`` is the vertical height above the threshold and the
glide path stays 3 deg to the horizontal. A runway with a longitudinal slope ``slope_pct``
(positive uphill in the landing direction: the far end higher) has its surface on
``z = -x slope_pct / 100``; with no slope (the default) that is SPEC's ``z = 0``. There is no
transverse slope: the threshold line and every line across the runway are horizontal.

The aiming point E (end of the glide path) is at ``(D, 0, 0)`` with ``D = 320 m`` by default:
55 ft threshold crossing height on a 3 deg slope gives 16.764 m / tan(3 deg) = 320 m (the
thesis's "350 m" in its section 3.3 is a slip, see ../shared/seeds/README.md).

"Left" and "right" are as seen by a pilot looking along the landing direction: the left
edge is at ``y = -width/2``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from visland.userfiles import read_json_object

__all__ = ["Runway", "RUNWAY_SIZES", "GLIDE_SLOPE_RAD", "CORNER_NAMES", "MAX_SLOPE_PCT", "FIELD_UNITS", "JSON_REQUIRED"]

GLIDE_SLOPE_RAD = math.radians(3.0)

#: Corner names in label order: threshold corners (P', P'' of thesis Fig. 3.5), then the
#: runway-end corners.
CORNER_NAMES = ("near_left", "near_right", "far_left", "far_right")

#: Largest longitudinal slope accepted, percent (ICAO Annex 14 allows at most 1 % to 2 % overall
#: depending on the runway's code; the simulator and studies use up to 1.5 %).
MAX_SLOPE_PCT = 2.0

#: Named runway sizes (length_m, width_m): the SPEC default and the range scenes vary over.
RUNWAY_SIZES = {
    "default": (3000.0, 45.0),
    "regional": (1800.0, 30.0),
    "medium": (2500.0, 45.0),
    "long": (4000.0, 60.0),
    "wide": (3200.0, 60.0),
}


#: The fields of ``runway.json`` (and of a scenario's ``[runway]`` table) with their units.
FIELD_UNITS = {"length_m": "metres", "width_m": "metres", "aim_distance_m": "metres", "heading_deg": "degrees",
               "slope_pct": "percent"}
#: The fields SPEC requires in ``runway.json``.
JSON_REQUIRED = ("length_m", "width_m", "aim_distance_m")


@dataclass(frozen=True)
class Runway:
    """A rectangular runway of ``length_m`` x ``width_m`` with aiming point at ``aim_distance_m``.

    Attributes
    ----------
    length_m : float
        Length of the horizontal projection of the centreline, threshold to runway end, metres.
    width_m : float
        Width, metres.
    aim_distance_m : float
        Distance D of the aiming point past the threshold (SPEC: 320 m), metres.
    heading_deg : float
        True heading of the landing direction (from north), used only to place the runway in NED
        for simulation; the estimators must recover what they need from the image.
    slope_pct : float
        Longitudinal slope, percent, positive uphill in the landing direction (the far end
        higher): the surface is ``z = -x slope_pct / 100`` in the level frame R (module
        docstring). In ``[-MAX_SLOPE_PCT, MAX_SLOPE_PCT]``.
    """

    length_m: float = 3000.0
    width_m: float = 45.0
    aim_distance_m: float = 320.0
    heading_deg: float = 40.0
    slope_pct: float = 0.0

    def __post_init__(self):
        checks = (
            ("length_m", self.length_m, 500.0, 6000.0),
            ("width_m", self.width_m, 10.0, 100.0),
            ("aim_distance_m", self.aim_distance_m, 0.0, 1000.0),
            ("heading_deg", self.heading_deg, 0.0, 360.0),
            ("slope_pct", self.slope_pct, -MAX_SLOPE_PCT, MAX_SLOPE_PCT),
        )
        for name, value, low, high in checks:
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError(f"runway {name} must be a finite number, got {value!r}")
            if not low <= value <= high:
                raise ValueError(f"runway {name} must lie in [{low:g}, {high:g}], got {value:g}")
        if self.aim_distance_m >= self.length_m:
            raise ValueError("runway aim_distance_m must be shorter than length_m")

    @classmethod
    def named(cls, name: str, **overrides) -> "Runway":
        """A runway of one of the sizes in :data:`RUNWAY_SIZES`."""
        if name not in RUNWAY_SIZES:
            raise ValueError(f"unknown runway size '{name}'; known: {', '.join(RUNWAY_SIZES)}")
        length, width = RUNWAY_SIZES[name]
        return cls(length_m=length, width_m=width, **overrides)

    @property
    def heading_rad(self) -> float:
        return math.radians(self.heading_deg)

    @property
    def slope_rad(self) -> float:
        """Angle of the centreline above the horizontal, ``atan(slope_pct / 100)`` (uphill positive)."""
        return math.atan(self.slope_pct / 100.0)

    def surface_z_m(self, x_runway_m):
        """z in R (down) of the runway surface (and its extension) at ``x_runway_m``: ``-x slope_pct/100``."""
        return -np.asarray(x_runway_m, dtype=float) * (self.slope_pct / 100.0)

    def direction_runway(self) -> np.ndarray:
        """Unit vector of the centreline in the landing direction, in R, shape (3,): ``(1, 0, -s)/|.|``."""
        s = self.slope_pct / 100.0
        return np.array([1.0, 0.0, -s]) / math.sqrt(1.0 + s * s)

    def normal_runway(self) -> np.ndarray:
        """Unit normal of the runway surface pointing down (into the ground), in R, shape (3,).

        ``(s, 0, 1)/|.|``: orthogonal to :meth:`direction_runway` and to the lateral axis y; the
        runway's own "z" axis (thesis 3.33's ``n`` for a sloped runway).
        """
        s = self.slope_pct / 100.0
        return np.array([s, 0.0, 1.0]) / math.sqrt(1.0 + s * s)

    def corners_runway_m(self) -> np.ndarray:
        """The four corners in R, shape (4, 3), in :data:`CORNER_NAMES` order (on the sloped surface)."""
        half = self.width_m / 2.0
        z_far = float(self.surface_z_m(self.length_m))
        return np.array([
            [0.0, -half, 0.0],
            [0.0, half, 0.0],
            [self.length_m, -half, z_far],
            [self.length_m, half, z_far],
        ])

    def edge_lines_runway_m(self) -> dict:
        """The left edge, right edge and centre line as (point, unit direction) in R.

        The points are on the threshold line; the direction is :meth:`direction_runway` (sloped).
        """
        half = self.width_m / 2.0
        direction = self.direction_runway()
        return {
            "left": (np.array([0.0, -half, 0.0]), direction),
            "right": (np.array([0.0, half, 0.0]), direction),
            "center": (np.array([0.0, 0.0, 0.0]), direction),
        }

    def to_json_dict(self) -> dict:
        """The ``runway.json`` content of SPEC.md (truth side only), with ``slope_pct``."""
        return {"length_m": self.length_m, "width_m": self.width_m,
                "aim_distance_m": self.aim_distance_m, "heading_deg": self.heading_deg,
                "slope_pct": self.slope_pct}

    @classmethod
    def from_json_dict(cls, data: dict, source: str = "runway.json", required=JSON_REQUIRED,
                       field_prefix: str = "") -> "Runway":
        """Build from a ``runway.json`` dictionary (or a scenario's ``[runway]`` table); one sentence
        naming the first missing or bad field.

        Parameters
        ----------
        data : dict
            Field name -> value; fields not in :data:`FIELD_UNITS` are ignored (SPEC: more may follow).
        source : str, optional
            What the sentence starts with (the file's path); empty: the field alone.
        required : tuple of str, optional
            Fields that must be present (the SPEC's three for runway.json; none in a scenario,
            whose runway has defaults).
        field_prefix : str, optional
            Put before a field's name in the sentence (``"runway."`` in a scenario file).

        Returns
        -------
        Runway

        Raises
        ------
        ValueError
            ``"<source>: field 'width_m' must be a finite number of metres, got 'wide'"``, a missing
            field, or a value out of its range.
        """
        start = f"{source}: " if source else ""
        if not isinstance(data, dict):
            raise ValueError(f"{start}the runway must be a JSON object {{...}}, found a {type(data).__name__}")
        for key in required:
            if key not in data:
                raise ValueError(f"{start}missing field '{field_prefix}{key}' (needed: {', '.join(required)})")
        values = {}
        for key, unit in FIELD_UNITS.items():
            if key not in data:
                continue
            value = data[key]
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError(f"{start}field '{field_prefix}{key}' must be a finite number of {unit}, got {value!r}")
            values[key] = float(value)
        try:
            return cls(**values)
        except ValueError as error:        # a range: "runway width_m must lie in [10, 100], got 5"
            message = str(error)
            for key in FIELD_UNITS:
                message = message.replace(f"runway {key} ", f"field '{field_prefix}{key}' ", 1)
            raise ValueError(f"{start}{message}") from None

    @classmethod
    def load(cls, path) -> "Runway":
        """The runway of a ``runway.json`` file (SPEC: ``length_m``, ``width_m``, ``aim_distance_m``;
        optional ``heading_deg``, ``slope_pct``); a ``ValueError`` in one sentence naming the file
        and the field (:meth:`from_json_dict`), or saying the file is missing, unreadable or not a
        JSON object.

        Parameters
        ----------
        path : str or pathlib.Path
            The file.
        """
        path = Path(path)
        return cls.from_json_dict(read_json_object(path, "runway file"), source=str(path))

