"""Issue 20: specific input bugs found by the mutation corpus, one test each.

The independent truth is the input itself: a byte-order mark is not part of a column name, a
frame count of 0 measures nothing, a skipped report is not written, an existing file is not
replaced without --force, a folder entry that is not an image file is named.
"""
import json
import shutil

import numpy as np
import pytest

from visland.cli import main
from visland.contracts import read_telemetry

BOM = "\ufeff"


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """A simulated approach (no images): labels, telemetry, truth, camera."""
    out = tmp_path_factory.mktemp("sim") / "thesis-3"
    assert main(["simulate", "--scenario", "thesis-3", "--out", str(out)]) == 0
    return out


# ---------------------------------------------------------------- item 5: byte-order mark
def test_a_csv_starting_with_a_byte_order_mark_is_read(simulated, tmp_path):
    text = (simulated / "telemetry.csv").read_text()
    path = tmp_path / "telemetry.csv"
    path.write_text(BOM + text, encoding="utf-8")
    table = read_telemetry(path)
    assert table.column_order[0] == "t_s"
    assert table.n_rows == len(text.strip().splitlines()) - 1


def test_a_json_or_toml_starting_with_a_byte_order_mark_is_read(simulated, tmp_path):
    from visland.runway import Runway
    from visland.scenarios import load_scenario_file
    path = tmp_path / "runway.json"
    path.write_text(BOM + (simulated / "runway.json").read_text(), encoding="utf-8")
    assert Runway.load(path) == Runway.load(simulated / "runway.json")
    scenario = tmp_path / "s.toml"
    scenario.write_text(BOM + 'name = "s"\ndx_m = -1600.0\ndy_m = 20.0\ndgs_m = 0.0\ndpsi_deg = 1.0\n', encoding="utf-8")
    assert load_scenario_file(scenario).dx_m == -1600.0


# ---------------------------------------------------------------- item 7: process --no-report
@pytest.mark.slow
def test_process_without_report_does_not_list_it(simulated, tmp_path):
    from visland.datasets.process import ProcessOptions, process_input
    lines = []
    out = tmp_path / "run"
    process_input(simulated, out, ProcessOptions(source="ideal", observers=("ccpi-hg-2p",), report=False,
                                                 quiet=True), echo=lines.append)
    assert not (out / "report.html").exists()
    wrote = lines[-1]                                          # the run's closing line lists its files
    assert wrote.startswith(f"wrote {out}/") and "estimates.csv" in wrote and "report.html" not in wrote


# ---------------------------------------------------------------- item 4: estimate --out and --force
def test_estimate_refuses_to_replace_its_outputs_without_force(simulated, tmp_path, capsys):
    folder = tmp_path / "sim"
    shutil.copytree(simulated, folder)
    out = folder / "estimates.csv"
    args = ["estimate", str(folder), "--measurements", "ideal", "--observer", "ccpi-hg-2p", "--out", str(out)]
    assert main(args) == 0
    assert (folder / "metrics.json").exists()
    before = out.read_bytes(), (folder / "metrics.json").read_bytes()
    capsys.readouterr()
    assert main(args) == 2                                       # the estimates exist
    assert "output file exists; choose another --out or pass --force" in capsys.readouterr().err
    other = folder / "other.csv"                                 # a new file, but metrics.json exists beside it
    assert main(args[:-1] + [str(other)]) == 2
    assert "metrics.json" in capsys.readouterr().err and not other.exists()
    assert (out.read_bytes(), (folder / "metrics.json").read_bytes()) == before
    assert main(args + ["--force"]) == 0
    json.loads((folder / "metrics.json").read_text())


# ---------------------------------------------------------------- rendered frames (items 1, 2, 3, 9)
SIZE = 384


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    """A short approach (1.5 km, 16 s) rendered at 384 px and 2 Hz: 33 frames."""
    from tests.helpers.short_approach import generate_short
    return generate_short(tmp_path_factory.mktemp("gen") / "short", SIZE, 2.0)


def _process(folder, out, source, observers, **kwargs):
    from visland.datasets.process import ProcessOptions, process_input
    return process_input(folder, out, ProcessOptions(source=source, observers=observers, quiet=True, report=False,
                                                     **kwargs), echo=lambda line: None)


def _estimates_by_observer(path):
    from visland.contracts import read_estimates
    table = read_estimates(path)
    return {name: {k: table[k][table["observer"] == name] for k in ("t_s", "dh_m", "coasting")}
            for name in dict.fromkeys(table["observer"])}


# ---------------------------------------------------------------- item 1: a flagged frame leaves everything coasting
ITEM1_OBSERVERS = ("ekf-2l", "cccj-2l", "ccpi-hg-2p", "ecc-hg")


@pytest.mark.slow
@pytest.mark.parametrize("source", ["anchored", "tracking", "detection"])
def test_an_unreadable_frame_leaves_every_source_and_observer_coasting(rendered, tmp_path, source):
    from visland.contracts import read_measurements
    bad = 10
    folder = tmp_path / "damaged"
    shutil.copytree(rendered, folder)
    sorted((folder / "frames").iterdir())[bad].write_bytes(b"not an image")
    run = _process(folder, tmp_path / "bad", source, ITEM1_OBSERVERS)
    assert [item["frame"] for item in run["flagged"]] == [bad] and "unreadable" in run["flagged"][0]["reason"]
    measurements = read_measurements(tmp_path / "bad" / "measurements.csv")
    assert measurements["found"][bad] == 0 and measurements["source"][bad] == source
    assert f"frame {bad}" in measurements["reason"][bad]
    features = [c for c in measurements if c.endswith(("_px", "_rho", "_rad")) or c == "dF_px"]
    assert all(np.isnan(measurements[c][bad]) for c in features)
    damaged = _estimates_by_observer(tmp_path / "bad" / "estimates.csv")
    assert set(damaged) == set(ITEM1_OBSERVERS)
    for name, series in damaged.items():
        assert series["coasting"][bad] == 1, name
    if source != "anchored":
        return
    # the frames after the bad one: as good as without it (the clean run within a few metres at the end)
    _process(rendered, tmp_path / "clean", source, ITEM1_OBSERVERS)
    clean = _estimates_by_observer(tmp_path / "clean" / "estimates.csv")
    for name in ITEM1_OBSERVERS:
        after = slice(bad + 1, None)
        assert np.all(np.abs(damaged[name]["dh_m"][after]) < 1000.0), name
        assert abs(damaged[name]["dh_m"][-1] - clean[name]["dh_m"][-1]) < 3.0, name


# ---------------------------------------------------------------- item 3: a run where no observer can start
@pytest.mark.slow
def test_a_run_without_any_usable_frame_completes_and_says_why(rendered, tmp_path):
    from visland.contracts import read_measurements
    from visland.datasets.process import ProcessOptions, process_input
    folder = tmp_path / "wrong-camera"
    shutil.copytree(rendered, folder)
    camera = json.loads((folder / "camera.json").read_text())
    camera["width"] = SIZE + 16                                   # every frame is 384 px wide
    (folder / "camera.json").write_text(json.dumps(camera))
    lines = []
    out = tmp_path / "run"
    run = process_input(folder, out, ProcessOptions(source="detection", observers=("ccpi-hg-2p", "ekf-2l"), quiet=True),
                        echo=lines.append)
    n = len(list((folder / "frames").iterdir()))
    assert run["n_frames"] == n and run["n_found"] == 0 and run["n_flagged"] == n
    measurements = read_measurements(out / "measurements.csv")
    assert measurements.n_rows == n and not measurements["found"].any()
    assert all(f"camera.json says {SIZE + 16}x{SIZE}" in reason for reason in measurements["reason"])
    estimates = _estimates_by_observer(out / "estimates.csv")
    assert set(estimates) == {"ccpi-hg-2p", "ekf-2l"}
    for series in estimates.values():
        assert len(series["dh_m"]) == n and np.isnan(series["dh_m"]).all() and (series["coasting"] == 1).all()
    assert set(run["no_estimates"]) == {"ccpi-hg-2p", "ekf-2l"}
    assert all(f"{n} of {n} frames" in why and f"camera.json says {SIZE + 16}x{SIZE}" in why
               for why in run["no_estimates"].values())
    assert json.loads((out / "run.json").read_text())["no_estimates"] == run["no_estimates"]
    assert any(line.startswith("no estimates from ccpi-hg-2p") and "ekf-2l" in line for line in lines)
    assert "no estimates" in (out / "report.html").read_text()


def test_a_json_camera_file_starting_with_a_byte_order_mark_is_read(simulated, tmp_path):
    from visland.camera import CameraModel
    path = tmp_path / "camera.json"
    path.write_text(BOM + (simulated / "camera.json").read_text(), encoding="utf-8")
    assert CameraModel.load(path) == CameraModel.load(simulated / "camera.json")


# ---------------------------------------------------------------- item 6: detect --max-frames
@pytest.mark.parametrize("count", ["0", "-1"])
def test_detect_refuses_a_frame_count_below_one(simulated, tmp_path, capsys, count):
    out = tmp_path / "m.csv"
    assert main(["detect", str(simulated), "--out", str(out), "--max-frames", count, "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"--max-frames must be a positive number of frames, got {count}" in err
    assert not out.exists()


# ---------------------------------------------------------------- item 9: entries of frames/ that are not images
@pytest.mark.slow
def test_frame_entries_that_are_not_files_are_flagged_and_keep_the_times(rendered, tmp_path):
    import cv2
    from visland.contracts import read_measurements
    folder = tmp_path / "odd"
    shutil.copytree(rendered, folder)
    for name in ("frames.csv", "truth.csv", "labels.csv"):          # times from --fps: index / fps
        (folder / name).unlink()
    frames = sorted((folder / "frames").iterdir())
    n = len(frames)
    frames[3].unlink()
    frames[3].mkdir()                                              # a folder named as a frame
    frames[5].unlink()
    frames[5].symlink_to(folder / "frames" / "gone.png")           # a dangling link
    frames[7].unlink()
    frames[7].symlink_to(frames[7])                                # a link loop
    header = b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + (100000).to_bytes(4, "big") * 2 + b"\x08\x00\x00\x00\x00"
    frames[9].write_bytes(header + b"\x00" * 64)                   # a header declaring 1e10 pixels
    run = _process(folder, tmp_path / "run", "detection", ("ccpi-hg-2p",), fps=2.0, initial_height_m=80.0)
    flagged = {item["frame"]: item["reason"] for item in run["flagged"]}
    assert set(flagged) == {3, 5, 7, 9}
    assert "a folder" in flagged[3] and "a dangling link" in flagged[5] and "a link loop" in flagged[7]
    assert "unreadable image" in flagged[9]
    measurements = read_measurements(tmp_path / "run" / "measurements.csv")
    assert measurements.n_rows == n
    np.testing.assert_allclose(measurements["t_s"], np.arange(n) / 2.0)
    assert cv2.imread(str(frames[10])) is not None and measurements["found"][10] in (0, 1)
