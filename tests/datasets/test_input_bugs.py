"""Issue 20: specific input bugs found by the mutation corpus, one test each.

The independent truth is the input itself: a byte-order mark is not part of a column name, a
frame count of 0 measures nothing, a skipped report is not written, an existing file is not
replaced without --force, a folder entry that is not an image file is named.
"""
import json
import shutil

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
