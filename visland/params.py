"""One way for every stage's parameter set to travel through files.

Each stage keeps its parameters in one frozen dataclass, validated in ``__post_init__``
(STYLE.md). :class:`ParamsFile` gives such a dataclass its dictionary, JSON and TOML round
trip, with unknown keys named and every error one sentence naming the file::

    @dataclass(frozen=True)
    class TrackerParams(ParamsFile):
        params_kind: ClassVar[str] = "tracker"      # errors say "unknown tracker parameter 'x'"
        toml_table: ClassVar[str | None] = "tracker"  # a TOML file may hold the keys under [tracker]
        template_size_px: int = 32
        ...

    params.save("tracker.toml"); TrackerParams.load("tracker.toml") == params

Lists read from JSON or TOML become tuples where the field's default is a tuple, so a
round trip gives back an equal (hashable) object.
"""
from __future__ import annotations

import json
from dataclasses import MISSING, asdict, fields
from pathlib import Path
from typing import ClassVar
from visland.userfiles import read_json_object, read_toml_object

__all__ = ["ParamsFile", "toml_value"]


def toml_value(value) -> str:
    """A scalar or a list as a TOML value.

    Parameters
    ----------
    value : bool, int, float, str, or list or tuple of them
        What to write (strings quoted as JSON strings, which TOML reads alike).

    Returns
    -------
    str

    Raises
    ------
    ValueError
        Any other type.
    """
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    raise ValueError(f"cannot write {value!r} to TOML")


class ParamsFile:
    """Mixin of a frozen parameter dataclass: ``to_dict``/``from_dict``, ``save``/``load``."""

    #: How errors name these parameters ("scene", "detector", "tracker", "observer").
    params_kind: ClassVar[str] = "stage"
    #: A TOML table the keys may sit under (``[scene]``), besides the top level.
    toml_table: ClassVar[str | None] = None

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict, source: str | None = None):
        """Build from a dictionary (a JSON object or a TOML table), naming any unknown key."""
        source = source or f"{cls.params_kind} parameters"
        if not isinstance(data, dict):
            raise ValueError(f"{source}: expected a table of {cls.params_kind} parameters, got {type(data).__name__}")
        known = {f.name: f for f in fields(cls)}
        for key in data:
            if key not in known:
                raise ValueError(f"{source}: unknown {cls.params_kind} parameter '{key}' "
                                 f"(known: {', '.join(sorted(known))})")
        values = {}
        for key, value in data.items():
            default = known[key].default
            if isinstance(value, list) and default is not MISSING and isinstance(default, tuple):
                value = tuple(value)
            values[key] = value
        try:
            return cls(**values)
        except (TypeError, ValueError) as error:
            raise ValueError(f"{source}: {error}") from None

    def save(self, path) -> None:
        """Write ``.json`` or ``.toml`` (flat ``key = value`` lines)."""
        path = Path(path)
        suffix = path.suffix.lower()
        data = self.to_dict()
        if suffix == ".json":
            text = json.dumps(data, indent=2) + "\n"
        elif suffix == ".toml":
            text = f"# visland {self.params_kind} parameters ({type(self).__name__})\n"
            text += "".join(f"{key} = {toml_value(value)}\n" for key, value in data.items())
        else:
            raise ValueError(f"{path}: {self.params_kind} parameter files are .json or .toml")
        path.write_text(text)

    @classmethod
    def load(cls, path):
        """Read a ``.json`` or ``.toml`` file (any subset of the fields; the rest keep their defaults)."""
        path = Path(path)
        suffix = path.suffix.lower()
        if suffix not in (".json", ".toml"):
            raise ValueError(f"{path}: {cls.params_kind} parameter files are .json or .toml")
        what = f"{cls.params_kind} parameter file"
        data = read_toml_object(path, what) if suffix == ".toml" else read_json_object(path, what)
        if suffix == ".toml" and cls.toml_table and set(data) == {cls.toml_table}:
            data = data[cls.toml_table]
        return cls.from_dict(data, source=str(path))
