"""Options shared by several commands are declared once and read alike in each."""
from __future__ import annotations

import argparse

import pytest

from visland.cli import build_parser


def _subparser(name: str) -> argparse.ArgumentParser:
    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return commands.choices[name]


def _options(parser: argparse.ArgumentParser) -> dict:
    return {option: action for action in parser._actions for option in action.option_strings}


FRAME_SOURCE_OPTIONS = ("--camera", "--telemetry", "--frames-csv", "--fps", "--time-offset")


@pytest.mark.parametrize("option", FRAME_SOURCE_OPTIONS)
def test_frame_source_options_are_the_same_in_detect_track_and_process(option):
    found = {command: _options(_subparser(command)).get(option) for command in ("detect", "track", "process")}
    missing = [command for command, action in found.items() if action is None]
    assert not missing, f"{option} missing from {missing}"
    detect, track, process = found.values()
    for action in (track, process):
        assert (action.dest, action.default, action.type, action.metavar) == \
               (detect.dest, detect.default, detect.type, detect.metavar)
        if option != "--telemetry":          # --telemetry adds what the command does without one
            assert action.help == detect.help


def test_parsed_frame_source_options_have_the_same_values():
    argv = ["--camera", "c.json", "--telemetry", "t.csv", "--frames-csv", "f.csv", "--fps", "10", "--time-offset", "0.5"]
    parser = build_parser()
    parsed = [parser.parse_args(["detect", "d", "--out", "m.csv", *argv]),
              parser.parse_args(["track", "d", "--out", "m.csv", *argv]),
              parser.parse_args(["process", "d", "--out", "o", *argv])]
    values = {(a.camera, a.telemetry, a.frames_csv, a.fps, a.time_offset) for a in parsed}
    assert values == {("c.json", "t.csv", "f.csv", 10.0, 0.5)}


@pytest.mark.parametrize("option, default", [("--initial-height", None), ("--initial-error", 0.2)])
def test_initial_guess_options_are_the_same_in_estimate_and_process(option, default):
    estimate, process = (_options(_subparser(command))[option] for command in ("estimate", "process"))
    assert estimate.default == process.default == default
    assert estimate.help == process.help


def test_estimate_takes_the_time_offset_as_process_does():
    estimate, process = (_options(_subparser(command))["--time-offset"] for command in ("estimate", "process"))
    assert (estimate.dest, estimate.default, estimate.type, estimate.metavar, estimate.help) == \
           (process.dest, process.default, process.type, process.metavar, process.help)
    assert "delay" in estimate.help
    from visland.estimation.command import EstimateOptions
    with pytest.raises(ValueError, match="--time-offset"):
        EstimateOptions(observers=("kf-2p",), time_offset_s=float("nan"))
