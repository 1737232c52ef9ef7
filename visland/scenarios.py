"""Approach scenarios: the seeds' initial conditions and user scenarios from TOML.

A scenario fixes where the vision-based approach starts, relative to the aiming point E
(SPEC deviations): ``dx_m`` (negative on approach), ``dy_m`` (right of the centreline
positive), ``dgs_m`` (height above the 3 deg glide path), ``dpsi_deg`` (heading minus
runway heading), with wings level at 140 kt.

Built-in sets:

- ``thesis-1`` .. ``thesis-8``: thesis Table 5.2, level flight (flight path 0 deg). The
  table's "Delta_H" column is the offset from the glide path.
- ``ecc-1`` .. ``ecc-3``: ECC'15 Table I, on a -3 deg flight path. With SPEC signs the
  table's dY signs are flipped so that each heading deviation points back towards the
  centreline (../shared/seeds/README.md).
- ``dickmanns-wind``: ``thesis-1`` flown through the crosswind and gust of the Dickmanns
  and Schell seed (section on simulation results).

User scenario files are TOML; see :func:`load_scenario_file` and the README.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from pathlib import Path

from visland.runway import FIELD_UNITS, Runway
from visland.userfiles import read_toml_object

__all__ = ["Scenario", "Wind", "BUILTIN_SCENARIOS", "get_scenario", "load_scenario_file",
           "resolve_scenario", "scenario_names", "KNOTS_TO_MPS"]

KNOTS_TO_MPS = 1852.0 / 3600.0


@dataclass(frozen=True)
class Wind:
    """Wind in the runway frame: a steady part and an optional Dickmanns-style gust.

    Parameters
    ----------
    crosswind_mps : float
        Steady wind component along runway +y (blowing towards the right of the centreline).
    headwind_mps : float
        Steady wind component against the landing direction (blowing along runway -x).
    crosswind_onset_m : float or None
        Distance before the threshold at which the steady wind starts; ``None``: from the start.
    gust : bool
        Add the gust: starts ``gust_onset_m`` before the threshold and decays as
        ``exp(-t / gust_time_constant_s)``.
    gust_onset_m : float
        Distance before the threshold at which the gust starts, metres.
    gust_crosswind_mps, gust_updraft_mps : float
        Initial gust components along runway +y and upwards.
    gust_time_constant_s : float
        Decay time constant of the gust, seconds.

    Raises
    ------
    ValueError
        A field out of its range, naming it (``wind.NAME``).
    """

    crosswind_mps: float = 0.0
    headwind_mps: float = 0.0
    crosswind_onset_m: float | None = None
    gust: bool = False
    gust_onset_m: float = 650.0
    gust_crosswind_mps: float = 2.0
    gust_updraft_mps: float = 1.0
    gust_time_constant_s: float = 6.0

    def __post_init__(self):
        for name in ("crosswind_mps", "headwind_mps", "gust_crosswind_mps", "gust_updraft_mps"):
            _check_range(f"wind.{name}", getattr(self, name), -25.0, 25.0)
        if self.crosswind_onset_m is not None:
            _check_range("wind.crosswind_onset_m", self.crosswind_onset_m, 0.0, 20000.0)
        _check_range("wind.gust_onset_m", self.gust_onset_m, 0.0, 20000.0)
        _check_range("wind.gust_time_constant_s", self.gust_time_constant_s, 0.1, 120.0)
        if not isinstance(self.gust, bool):
            raise ValueError(f"wind.gust must be true or false, got {self.gust!r}")


@dataclass(frozen=True)
class Scenario:
    """Initial conditions of an approach and its environment (see module docstring).

    Parameters
    ----------
    name : str
        Non-empty name (the built-in ones: :data:`BUILTIN_SCENARIOS`).
    dx_m : float
        Start along the runway axis relative to the aiming point E, metres (negative on
        approach, -12000 .. -1500).
    dy_m : float
        Start across the runway axis, metres, right of the centreline positive (runway frame).
    dgs_m : float
        Start height above the 3 deg glide path, metres.
    dpsi_deg : float
        Heading minus runway heading, degrees.
    gamma_deg : float, default 0
        Flight-path angle, degrees (negative descending; 0: level flight).
    roll_deg : float, default 0
        Initial roll, degrees.
    airspeed_kt : float, default 140
        Airspeed, knots.
    runway : visland.runway.Runway
        The runway (size, aiming distance, heading, slope).
    wind : Wind
        Steady wind and gust (default: calm).
    description : str
        One line for ``visland scenarios``.

    Raises
    ------
    ValueError
        A field out of its range (naming it), or a start below 60 m above the runway.
    """

    name: str
    dx_m: float
    dy_m: float
    dgs_m: float
    dpsi_deg: float
    gamma_deg: float = 0.0
    roll_deg: float = 0.0
    airspeed_kt: float = 140.0
    runway: Runway = field(default_factory=Runway)
    wind: Wind = field(default_factory=Wind)
    description: str = ""

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.strip():
            raise ValueError("scenario name must be a non-empty string")
        if not isinstance(self.description, str):
            raise ValueError(f"scenario {self.name}: description must be text, got {self.description!r}")
        _check_range("dx_m", self.dx_m, -12000.0, -1500.0)
        _check_range("dy_m", self.dy_m, -1000.0, 1000.0)
        _check_range("dgs_m", self.dgs_m, -150.0, 150.0)
        _check_range("dpsi_deg", self.dpsi_deg, -30.0, 30.0)
        _check_range("gamma_deg", self.gamma_deg, -6.0, 5.0)
        _check_range("roll_deg", self.roll_deg, -30.0, 30.0)
        _check_range("airspeed_kt", self.airspeed_kt, 100.0, 200.0)
        if self.initial_height_m < 60.0:
            raise ValueError(f"scenario {self.name}: starts {self.initial_height_m:.0f} m above the runway; "
                             "dgs_m puts it below 60 m")

    @property
    def airspeed_mps(self) -> float:
        return self.airspeed_kt * KNOTS_TO_MPS

    @property
    def initial_height_m(self) -> float:
        """dH at the start: the glide path height at dx plus the offset dgs."""
        return -self.dx_m * math.tan(math.radians(3.0)) + self.dgs_m

    def to_dict(self) -> dict:
        """A TOML-ready dictionary (round-trips through :func:`scenario_from_dict`)."""
        out = {f.name: getattr(self, f.name) for f in fields(self) if f.name not in ("runway", "wind")}
        out["runway"] = {k: getattr(self.runway, k) for k in ("length_m", "width_m", "aim_distance_m", "heading_deg",
                                                             "slope_pct")}
        wind = {f.name: getattr(self.wind, f.name) for f in fields(Wind)}
        if wind["crosswind_onset_m"] is None:
            del wind["crosswind_onset_m"]
        out["wind"] = wind
        return out


def _check_range(name, value, low, high):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"field '{name}' must be a finite number, got {value!r}")
    if not low <= value <= high:
        raise ValueError(f"field '{name}' = {value:g} is out of range [{low:g}, {high:g}]")


def _thesis(number, dx, dy, dgs, dpsi):
    return Scenario(f"thesis-{number}", dx, dy, dgs, dpsi, gamma_deg=0.0,
                    description=f"thesis Table 5.2 trajectory No.{number}: dX {dx:g} m, dY {dy:g} m, "
                                f"{dgs:+g} m from the glide path, dpsi {dpsi:+g} deg, level flight")


def _ecc(number, dx, dy, dgs, dpsi, difficulty):
    return Scenario(f"ecc-{number}", dx, dy, dgs, dpsi, gamma_deg=-3.0,
                    description=f"ECC'15 Table I landing {number} ({difficulty}): dX {dx:g} m, dY {dy:g} m, "
                                f"{dgs:+g} m from the glide path, dpsi {dpsi:+g} deg, -3 deg flight path")


BUILTIN_SCENARIOS: dict[str, Scenario] = {s.name: s for s in [
    _thesis(1, -5000.0, 200.0, -25.0, 0.0),
    _thesis(2, -6000.0, 200.0, -25.0, 0.0),
    _thesis(3, -4000.0, 200.0, -25.0, 0.0),
    _thesis(4, -5000.0, 400.0, -25.0, 0.0),
    _thesis(5, -5000.0, 200.0, -50.0, 0.0),
    _thesis(6, -5000.0, 200.0, 50.0, 0.0),
    _thesis(7, -5000.0, 200.0, -25.0, -15.0),
    _thesis(8, -5000.0, 200.0, -25.0, 15.0),
    _ecc(1, -5000.0, -200.0, -50.0, 15.0, "easy"),
    _ecc(2, -5000.0, 200.0, 50.0, 0.0, "medium"),
    _ecc(3, -4000.0, 550.0, 100.0, -15.0, "difficult"),
    Scenario("dickmanns-wind", -5000.0, 200.0, -25.0, 0.0,
             wind=Wind(crosswind_mps=-1.0, crosswind_onset_m=800.0, gust=True),
             description="thesis-1 through the Dickmanns-Schell wind: -1 m/s crosswind from 800 m "
                         "before the threshold, a 2 m/s cross / 1 m/s vertical gust at 650 m decaying in 6 s"),
]}


def scenario_names() -> list[str]:
    """The built-in scenarios' names, in listing order."""
    return list(BUILTIN_SCENARIOS)


def get_scenario(name: str) -> Scenario:
    """A built-in scenario by name; the error lists the known ones.

    Parameters
    ----------
    name : str
        A key of :data:`BUILTIN_SCENARIOS` (``thesis-1``, ``ecc-2``, ...).

    Returns
    -------
    Scenario
        The built-in scenario (frozen: shared by every caller).

    Raises
    ------
    ValueError
        An unknown name, listing the known ones.
    """
    try:
        return BUILTIN_SCENARIOS[name]
    except KeyError:
        raise ValueError(f"unknown scenario '{name}'; known scenarios: {', '.join(BUILTIN_SCENARIOS)} "
                         "(or give a path to a .toml scenario file)") from None


_SCENARIO_KEYS = {f.name for f in fields(Scenario)}
_REQUIRED_KEYS = ("name", "dx_m", "dy_m", "dgs_m", "dpsi_deg")


def scenario_from_dict(data: dict, source: str = "scenario") -> Scenario:
    """Build a scenario from a dictionary (as read from TOML), naming any bad field."""
    unknown = set(data) - _SCENARIO_KEYS
    if unknown:
        raise ValueError(f"{source}: unknown field '{sorted(unknown)[0]}' "
                         f"(known: {', '.join(sorted(_SCENARIO_KEYS))})")
    for key in _REQUIRED_KEYS:
        if key not in data:
            raise ValueError(f"{source}: missing field '{key}' (required: {', '.join(_REQUIRED_KEYS)})")
    kwargs = dict(data)
    try:
        runway_data = kwargs.pop("runway", {})
        wind_data = kwargs.pop("wind", {})
        if not isinstance(runway_data, dict):
            raise ValueError("field 'runway' must be a table")
        if not isinstance(wind_data, dict):
            raise ValueError("field 'wind' must be a table")
        runway_keys = {*FIELD_UNITS, "size"}
        for key in runway_data:
            if key not in runway_keys:
                raise ValueError(f"unknown field 'runway.{key}' (known: {', '.join(sorted(runway_keys))})")
        runway_data = dict(runway_data)
        size = runway_data.pop("size", None)
        if size is not None:                # a named size, its fields overridden by those given
            named = Runway.named(size)
            runway_data = {"length_m": named.length_m, "width_m": named.width_m, **runway_data}
        runway = Runway.from_json_dict(runway_data, source="", required=(), field_prefix="runway.")
        wind_keys = {f.name for f in fields(Wind)}
        for key in wind_data:
            if key not in wind_keys:
                raise ValueError(f"unknown field 'wind.{key}' (known: {', '.join(sorted(wind_keys))})")
        wind = Wind(**wind_data)
        return Scenario(runway=runway, wind=wind, **kwargs)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{source}: {error}") from None


def load_scenario_file(path) -> Scenario:
    """Load a user scenario from a TOML file.

    Example::

        name = "gusty-offset"
        dx_m = -5000.0
        dy_m = -150.0
        dgs_m = 20.0
        dpsi_deg = 8.0
        gamma_deg = -3.0          # optional, default 0 (level)
        airspeed_kt = 140.0       # optional
        [runway]                  # optional
        length_m = 2500.0
        width_m = 30.0
        heading_deg = 123.0
        slope_pct = 0.8           # optional, longitudinal slope, uphill positive (default 0)
        [wind]                    # optional
        crosswind_mps = 3.0
        gust = true

    Parameters
    ----------
    path : str or Path
        The TOML file.

    Returns
    -------
    Scenario

    Raises
    ------
    ValueError
        One sentence naming the file and the key that is missing, unknown or out of range.
    """
    path = Path(path)
    data = read_toml_object(path, "scenario file")
    return scenario_from_dict(data, source=str(path))


def resolve_scenario(name_or_path: str) -> Scenario:
    """A built-in scenario name, or a path to a TOML scenario file.

    Parameters
    ----------
    name_or_path : str
        A built-in name (:func:`get_scenario`), or a ``.toml`` file or any existing file
        (:func:`load_scenario_file`).

    Returns
    -------
    Scenario
    """
    if name_or_path in BUILTIN_SCENARIOS:
        return BUILTIN_SCENARIOS[name_or_path]
    if name_or_path.endswith(".toml") or Path(name_or_path).is_file():
        return load_scenario_file(name_or_path)
    return get_scenario(name_or_path)


def with_runway(scenario: Scenario, runway: Runway) -> Scenario:
    """The same scenario over another runway.

    Parameters
    ----------
    scenario : Scenario
        The approach.
    runway : visland.runway.Runway
        The runway to fly it to (validated again with the scenario).

    Returns
    -------
    Scenario
    """
    return replace(scenario, runway=runway)
