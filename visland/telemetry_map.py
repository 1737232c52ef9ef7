"""Telemetry as people have it (issue 15 item 5): a CSV with other column names and units turned
into the SPEC ``telemetry.csv`` by a small TOML column map, without editing the file.

The map names, for each SPEC column, the file's column and its unit (and a sign, for an axis
that points the other way, such as an up velocity for ``vd_mps``)::

    # map.toml: a flight-test logger writing radians, knots and ENU velocities
    [columns]
    t_s         = { column = "time_ms", unit = "ms" }
    roll_deg    = { column = "phi", unit = "rad" }
    pitch_deg   = { column = "theta", unit = "rad" }
    heading_deg = { column = "psi", unit = "rad" }
    p_dps       = { column = "p", unit = "rad/s" }
    q_dps       = { column = "q", unit = "rad/s" }
    r_dps       = { column = "r", unit = "rad/s" }
    vn_mps      = { column = "v_north", unit = "kt" }
    ve_mps      = { column = "v_east", unit = "kt" }
    vd_mps      = { column = "v_up", unit = "ft/min", sign = -1 }
    tas_mps     = { column = "tas", unit = "kt" }          # optional

A column given as a plain string (``roll_deg = "phi"``) is taken in the SPEC unit. The result is
read back with :func:`visland.contracts.read_telemetry`, so every SPEC check applies.
"""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from visland.contracts import read_telemetry, write_csv
from visland.sensors import TELEMETRY_COLUMNS, TELEMETRY_OPTIONAL_COLUMNS
from visland.userfiles import check_input_file, read_toml_object

__all__ = ["UNITS", "convert_telemetry"]

#: Units a map may name, per kind, as the factor to the SPEC unit.
UNITS = {
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "min": 60.0},
    "angle": {"deg": 1.0, "rad": 180.0 / np.pi},
    "rate": {"deg/s": 1.0, "rad/s": 180.0 / np.pi},
    "speed": {"m/s": 1.0, "kt": 1852.0 / 3600.0, "km/h": 1.0 / 3.6, "ft/s": 0.3048, "ft/min": 0.3048 / 60.0},
}
_KIND = {"t_s": "time", "roll_deg": "angle", "pitch_deg": "angle", "heading_deg": "angle", "p_dps": "rate",
         "q_dps": "rate", "r_dps": "rate", "vn_mps": "speed", "ve_mps": "speed", "vd_mps": "speed", "tas_mps": "speed"}


def _entries(map_path: Path) -> dict:
    """``{spec column: (file column, factor)}`` from the map, checked (one sentence per fault)."""
    data = read_toml_object(map_path, "telemetry column map")
    columns = data.get("columns")
    if not isinstance(columns, dict):
        raise ValueError(f"{map_path}: needs a [columns] table naming, for each of {', '.join(TELEMETRY_COLUMNS)}, "
                         "the file's column")
    unknown = sorted(set(columns) - set(TELEMETRY_COLUMNS) - set(TELEMETRY_OPTIONAL_COLUMNS))
    if unknown:
        raise ValueError(f"{map_path}: [columns] names '{unknown[0]}', which is not a telemetry column (known: "
                         f"{', '.join(TELEMETRY_COLUMNS + TELEMETRY_OPTIONAL_COLUMNS)})")
    entries = {}
    for spec in TELEMETRY_COLUMNS + TELEMETRY_OPTIONAL_COLUMNS:
        if spec not in columns:
            if spec in TELEMETRY_COLUMNS:
                raise ValueError(f"{map_path}: [columns] does not say which column holds '{spec}'")
            continue
        entry = columns[spec]
        if isinstance(entry, str):
            entry = {"column": entry}
        if not isinstance(entry, dict) or not isinstance(entry.get("column"), str) or not entry["column"]:
            raise ValueError(f"{map_path}: [columns] {spec} must be a column name or {{ column = \"...\", unit = "
                             f"\"...\" }}, got {entry!r}")
        kind = _KIND[spec]
        spec_unit = {"time": "s", "angle": "deg", "rate": "deg/s", "speed": "m/s"}[kind]
        unit = entry.get("unit", spec_unit)
        if unit not in UNITS[kind]:
            raise ValueError(f"{map_path}: [columns] {spec}: unit {unit!r} is not one of "
                             f"{', '.join(UNITS[kind])}")
        sign = entry.get("sign", 1)
        if sign not in (1, -1) or isinstance(sign, bool):
            raise ValueError(f"{map_path}: [columns] {spec}: sign must be 1 or -1, got {sign!r}")
        extra = sorted(set(entry) - {"column", "unit", "sign"})
        if extra:
            raise ValueError(f"{map_path}: [columns] {spec}: unknown key '{extra[0]}' (column, unit, sign)")
        entries[spec] = (entry["column"], sign * UNITS[kind][unit])
    return entries


def convert_telemetry(csv_path, map_path, out_path) -> int:
    """Write ``out_path`` (SPEC telemetry.csv) from ``csv_path`` through the column map.

    A column the map names that the file lacks, or a cell that is not a number, is one
    sentence naming the column, line and file.

    Parameters
    ----------
    csv_path : str or Path
        The telemetry as recorded (other column names and units).
    map_path : str or Path
        The TOML column map: ``[columns] spec = { column, unit, sign }`` (README, "Telemetry as
        people have it").
    out_path : str or Path
        The SPEC ``telemetry.csv`` to write (atomically).

    Returns
    -------
    int
        The number of rows written.
    """
    csv_path = check_input_file(csv_path, "telemetry file")
    entries = _entries(Path(check_input_file(map_path, "telemetry column map")))
    with csv_path.open(newline="", encoding="utf-8-sig") as handle:
        reader = csv.reader(handle)
        try:
            header = [h.strip() for h in next(reader)]
        except StopIteration:
            raise ValueError(f"{csv_path}: file is empty (expected a header row)") from None
        rows = [row for row in reader if row and any(cell.strip() for cell in row)]
    position = {}
    for spec, (column, _) in entries.items():
        if column not in header:
            raise ValueError(f"{csv_path}: has no column '{column}' (the map's {spec}); header has: "
                             f"{', '.join(header)}")
        position[spec] = header.index(column)
    values = {spec: np.empty(len(rows)) for spec in entries}
    for line, row in enumerate(rows, start=2):
        for spec, (column, factor) in entries.items():
            try:
                values[spec][line - 2] = float(row[position[spec]]) * factor
            except (ValueError, IndexError):
                cell = row[position[spec]] if position[spec] < len(row) else ""
                raise ValueError(f"{csv_path} line {line}: column '{column}' holds {cell!r}, not a number") from None
    order = list(TELEMETRY_COLUMNS) + [c for c in TELEMETRY_OPTIONAL_COLUMNS if c in entries]
    write_csv(Path(out_path), values, order)
    read_telemetry(out_path)          # every SPEC check on what was written
    return len(rows)
