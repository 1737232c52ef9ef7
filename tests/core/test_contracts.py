"""File contracts: validated readers (one sentence naming file, line, column) and atomic writers."""
import math

import numpy as np
import pytest

from visland.contracts import (read_csv, read_measurements, read_telemetry, staged_output_dir, write_csv)
from visland.sensors import TELEMETRY_COLUMNS


def _telemetry_text(rows):
    return ",".join(TELEMETRY_COLUMNS) + "\n" + "".join(",".join(str(v) for v in row) + "\n" for row in rows)


def test_round_trip_keeps_numbers_and_empties(tmp_path):
    path = tmp_path / "t.csv"
    write_csv(path, {"t_s": [0.0, 0.04], "x": [1.0 / 3.0, math.nan], "name": ["a", "b"]})
    table = read_csv(path, ["t_s", "x"], text_columns=["name"], optional_empty=["x"])
    np.testing.assert_allclose(table["x"][0], 1.0 / 3.0, rtol=1e-12)
    assert math.isnan(table["x"][1]) and list(table["name"]) == ["a", "b"]


@pytest.mark.parametrize("rows, match", [
    ([[0, 0, 0, 0, 0, 0, 0, 70, 0, 0], [0, 0, 0, 0, 0, 0, 0, 70, 0, 0]], r"line 3: t_s does not increase"),
    ([[0, 0, 0, 0, 0, 0, 0, 70, 0, 0], [0.02, "abc", 0, 0, 0, 0, 0, 70, 0, 0]], r"line 3: column 'roll_deg' is not a number"),
    ([[0, 0, 0, 0, 0, 0, 0, 70, 0, "nan"]], r"line 2: column 'vd_mps' is nan"),
    ([[0, 0, 0, 0, 0, 0, 0, 70, 0, ""]], r"line 2: column 'vd_mps' is empty"),
    ([[0, 0, 0, 0, 0, 0, 0, 70, 0]], r"line 2: 9 cells, the header has 10"),
])
def test_bad_telemetry_is_named(tmp_path, rows, match):
    path = tmp_path / "telemetry.csv"
    path.write_text(_telemetry_text(rows))
    with pytest.raises(ValueError, match=match) as info:
        read_telemetry(path)
    assert str(path) in str(info.value)


@pytest.mark.parametrize("value, match", [("0", "line 3: column 'tas_mps' is 0"),
                                          ("", "line 3: column 'tas_mps' is nan"),
                                          ("-3", "line 3: column 'tas_mps' is -3")])
def test_optional_airspeed_must_be_positive_on_every_line(tmp_path, value, match):
    path = tmp_path / "telemetry.csv"
    rows = [[0, 0, 0, 0, 0, 0, 0, 70, 0, 0, 72.0], [0.02, 0, 0, 0, 0, 0, 0, 70, 0, 0, value]]
    path.write_text(",".join(TELEMETRY_COLUMNS) + ",tas_mps\n" + "".join(",".join(str(v) for v in r) + "\n" for r in rows))
    with pytest.raises(ValueError, match=match):
        read_telemetry(path)
    rows[1][-1] = 72.5
    path.write_text(",".join(TELEMETRY_COLUMNS) + ",tas_mps\n" + "".join(",".join(str(v) for v in r) + "\n" for r in rows))
    np.testing.assert_allclose(read_telemetry(path)["tas_mps"], [72.0, 72.5])


def test_missing_column_is_named(tmp_path):
    path = tmp_path / "telemetry.csv"
    path.write_text("t_s,roll_deg\n0,0\n")
    with pytest.raises(ValueError, match="missing column 'pitch_deg'"):
        read_telemetry(path)


def test_missing_and_empty_files(tmp_path):
    with pytest.raises(ValueError, match="file not found"):
        read_telemetry(tmp_path / "nope.csv")
    (tmp_path / "empty.csv").write_text("")
    with pytest.raises(ValueError, match="file is empty"):
        read_telemetry(tmp_path / "empty.csv")


def test_measurements_found_must_be_binary(tmp_path):
    from visland.contracts import MEASUREMENT_COLUMNS
    row = {c: "" for c in MEASUREMENT_COLUMNS}
    row.update(frame="0", t_s="0", found="2", source="detection", reason="")
    path = tmp_path / "m.csv"
    path.write_text(",".join(MEASUREMENT_COLUMNS) + "\n" + ",".join(row[c] for c in MEASUREMENT_COLUMNS) + "\n")
    with pytest.raises(ValueError, match="line 2: column 'found' must be 0 or 1"):
        read_measurements(path)


def test_staged_output_dir_leaves_nothing_on_failure(tmp_path):
    out = tmp_path / "run"
    with pytest.raises(RuntimeError):
        with staged_output_dir(out) as staging:
            (staging / "half.csv").write_text("x")
            raise RuntimeError("boom")
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_staged_output_dir_refuses_an_existing_folder_unless_forced(tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    (out / "old.txt").write_text("old")
    with pytest.raises(ValueError, match="exists"):
        with staged_output_dir(out):
            pass
    with staged_output_dir(out, force=True) as staging:
        (staging / "new.txt").write_text("new")
    assert sorted(p.name for p in out.iterdir()) == ["new.txt"]
    assert [p.name for p in tmp_path.iterdir()] == ["run"]
