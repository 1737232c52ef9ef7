"""The shared parameter-file mixin: dictionary, JSON and TOML round trips, named errors."""
from dataclasses import dataclass
from typing import ClassVar

import pytest

from visland.params import ParamsFile


@dataclass(frozen=True)
class _Demo(ParamsFile):
    params_kind: ClassVar[str] = "demo"
    toml_table: ClassVar[str | None] = "demo"
    gain: float = 1.5
    steps: int = 3
    name: str = "a b"
    enabled: bool = True
    window: tuple = (4, 8)

    def __post_init__(self):
        if self.gain <= 0:
            raise ValueError(f"demo gain must be positive, got {self.gain}")


@pytest.mark.parametrize("suffix", [".json", ".toml"])
def test_round_trip(tmp_path, suffix):
    params = _Demo(gain=0.25, steps=7, name='quote " inside', enabled=False, window=(1, 2, 3))
    path = tmp_path / f"p{suffix}"
    params.save(path)
    again = _Demo.load(path)
    assert again == params and isinstance(again.window, tuple)


def test_partial_files_keep_defaults_and_tables_are_accepted(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text("[demo]\ngain = 2.0\n")
    assert _Demo.load(path) == _Demo(gain=2.0)


@pytest.mark.parametrize("name, text, match", [
    ("p.json", '{"gian": 1}', "unknown demo parameter 'gian'"),
    ("p.json", '{"gain": -1}', "demo gain must be positive"),
    ("p.json", '{"gain": 1', "not valid JSON"),
    ("p.toml", "gain = = 1", "not valid TOML"),
    ("p.yaml", "gain: 1", "demo parameter files are .json or .toml"),
])
def test_errors_name_the_file_and_the_problem(tmp_path, name, text, match):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(ValueError, match=match) as info:
        _Demo.load(path)
    assert str(path) in str(info.value)


def test_missing_file():
    with pytest.raises(ValueError, match="demo parameter file not found"):
        _Demo.load("/nonexistent/p.json")
