"""`visland simulate` and `visland scenarios` through the command line."""
import csv
import json
import subprocess
import sys

import numpy as np
import pytest

from visland.cli import main
from visland.contracts import (LABEL_COLUMNS, TELEMETRY_COLUMNS, TRUTH_COLUMNS, read_labels, read_telemetry,
                               read_truth)


def _header(path):
    with open(path, newline="") as handle:
        return next(csv.reader(handle))


def test_simulate_writes_the_spec_files(tmp_path, capsys):
    out = tmp_path / "sim"
    assert main(["simulate", "--scenario", "thesis-1", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "400 ft" in printed and "100 ft" in printed and "threshold" in printed
    names = sorted(p.name for p in out.iterdir())
    assert names == ["camera.json", "labels.csv", "manifest.json", "runway.json", "telemetry.csv", "truth.csv"]
    assert _header(out / "telemetry.csv") == list(TELEMETRY_COLUMNS) + ["tas_mps"]
    assert _header(out / "truth.csv")[:len(TRUTH_COLUMNS)] == list(TRUTH_COLUMNS)
    assert _header(out / "labels.csv")[:len(LABEL_COLUMNS)] == list(LABEL_COLUMNS)
    telemetry, truth, labels = read_telemetry(out / "telemetry.csv"), read_truth(out / "truth.csv"), read_labels(out / "labels.csv")
    assert np.allclose(np.diff(telemetry["t_s"]), 0.02)
    assert np.allclose(np.diff(labels["t_s"]), 0.04) and labels.n_rows == truth.n_rows
    camera = json.loads((out / "camera.json").read_text())
    assert camera["width"] == 2048 and camera["fx"] == 2472.0 and len(camera["mount_rpy_deg"]) == 3
    runway = json.loads((out / "runway.json").read_text())
    assert {"length_m", "width_m", "aim_distance_m"} <= set(runway)
    # truth and labels agree at the first frame: dX of the scenario, corners visible
    assert truth["dx_m"][0] == pytest.approx(-5000.0)
    assert labels["near_left_visible"][0] == 1


@pytest.mark.slow
def test_airspeed_column_and_wind_truth(tmp_path):
    out = tmp_path / "wind"
    assert main(["simulate", "--scenario", "dickmanns-wind", "--out", str(out), "--airspeed-noise", "0"]) == 0
    telemetry, truth = read_telemetry(out / "telemetry.csv"), read_truth(out / "truth.csv")
    np.testing.assert_allclose(telemetry["tas_mps"], 140 * 1852 / 3600, rtol=1e-6)
    # -1 m/s of crosswind from 800 m before the threshold, then the gust's +2 m/s (seed 004, 7.1)
    assert truth["wind_y_runway_mps"][0] == 0.0 and truth["wind_y_runway_mps"].min() == pytest.approx(-1.0)
    assert truth["wind_y_runway_mps"].max() == pytest.approx(1.0, abs=0.05)
    quiet = tmp_path / "no-airspeed"
    assert main(["simulate", "--scenario", "thesis-1", "--out", str(quiet), "--no-airspeed"]) == 0
    assert _header(quiet / "telemetry.csv") == list(TELEMETRY_COLUMNS)


def test_existing_output_is_refused_unless_forced(tmp_path, capsys):
    out = tmp_path / "sim"
    out.mkdir()
    assert main(["simulate", "--scenario", "thesis-3", "--out", str(out)]) == 2
    assert "exists" in capsys.readouterr().err
    assert main(["simulate", "--scenario", "thesis-3", "--out", str(out), "--force"]) == 0
    assert (out / "labels.csv").exists()


def test_unknown_scenario_lists_the_known_ones(tmp_path, capsys):
    assert main(["simulate", "--scenario", "nope", "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert "unknown scenario 'nope'" in err and "thesis-1" in err and "ecc-3" in err
    assert not (tmp_path / "x").exists()


def test_bad_scenario_file_names_the_field_and_writes_nothing(tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_text('name = "s"\ndx_m = -5000.0\ndy_m = 0.0\ndgs_m = 500.0\ndpsi_deg = 0.0\n')
    assert main(["simulate", "--scenario", str(path), "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert "'dgs_m' = 500 is out of range" in err and err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]


def test_pixel_noise_and_seed_are_reproducible(tmp_path):
    for name in ("a", "b"):
        assert main(["simulate", "--scenario", "thesis-3", "--out", str(tmp_path / name), "--pixel-noise", "1",
                     "--seed", "5"]) == 0
    assert (tmp_path / "a" / "labels.csv").read_bytes() == (tmp_path / "b" / "labels.csv").read_bytes()


def test_scenarios_command_lists_all(capsys):
    assert main(["scenarios"]) == 0
    out = capsys.readouterr().out
    assert all(f"thesis-{k}" in out for k in range(1, 9)) and "ecc-3" in out


def test_simulate_starts_fast_without_heavy_imports():
    code = ("import sys, visland.cli; visland.cli.build_parser(); "
            "heavy = [m for m in ('cv2', 'pyrender', 'OpenGL', 'dask', 'filterpy', 'scipy', 'trimesh') if m in sys.modules]; "
            "print(','.join(heavy))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == ""


@pytest.mark.slow
def test_slope_option_reaches_runway_json_and_the_labels(tmp_path, capsys):
    flat, sloped = tmp_path / "flat", tmp_path / "sloped"
    assert main(["simulate", "--scenario", "thesis-2", "--out", str(flat)]) == 0
    assert main(["simulate", "--scenario", "thesis-2", "--out", str(sloped), "--slope", "1.0"]) == 0
    assert json.loads((sloped / "runway.json").read_text())["slope_pct"] == 1.0
    a, b = read_labels(flat / "labels.csv"), read_labels(sloped / "labels.csv")
    np.testing.assert_allclose(a["near_left_v_px"], b["near_left_v_px"])     # the threshold does not move
    assert np.all(b["far_left_v_px"] < a["far_left_v_px"] - 1.0)              # the far end is 30 m higher
    assert main(["simulate", "--scenario", "thesis-2", "--out", str(tmp_path / "x"), "--slope", "5"]) == 2
    assert "--slope" in capsys.readouterr().err
