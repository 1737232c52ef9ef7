"""Telemetry as people have it (issue 15 item 5): other names and units through a column map."""
import numpy as np
import pytest

from visland.cli import main
from visland.contracts import read_telemetry

MAP = """
[columns]
t_s         = { column = "time_ms", unit = "ms" }
roll_deg    = { column = "phi", unit = "rad" }
pitch_deg   = { column = "theta", unit = "rad" }
heading_deg = "hdg"
p_dps       = { column = "p", unit = "rad/s" }
q_dps       = { column = "q", unit = "rad/s" }
r_dps       = { column = "r", unit = "rad/s" }
vn_mps      = { column = "v_north", unit = "kt" }
ve_mps      = { column = "v_east", unit = "kt" }
vd_mps      = { column = "v_up", unit = "ft/min", sign = -1 }
"""


def _recorded(tmp_path, header="time_ms,phi,theta,hdg,p,q,r,v_east,v_north,v_up"):
    path = tmp_path / "log.csv"
    path.write_text(header + "\n0,0.0174533,0.0523599,40,0,0.01,0,10,140,-600\n"
                             "40,0.0349066,0.0523599,40.2,0.01,0,0,10,140,-600\n")
    (tmp_path / "map.toml").write_text(MAP)
    return path


def test_a_logger_s_csv_becomes_the_spec_telemetry(tmp_path):
    log = _recorded(tmp_path)
    out = tmp_path / "telemetry.csv"
    assert main(["telemetry", str(log), "--map", str(tmp_path / "map.toml"), "--out", str(out)]) == 0
    table = read_telemetry(out)
    np.testing.assert_allclose(table["t_s"], [0.0, 0.04])
    np.testing.assert_allclose(table["roll_deg"], [1.0, 2.0], atol=1e-4)
    np.testing.assert_allclose(table["q_dps"], [np.degrees(0.01), 0.0], atol=1e-9)
    np.testing.assert_allclose(table["vn_mps"], 140 * 1852 / 3600)            # knots
    np.testing.assert_allclose(table["ve_mps"], 10 * 1852 / 3600)
    np.testing.assert_allclose(table["vd_mps"], 600 * 0.3048 / 60)            # 600 ft/min down


@pytest.mark.parametrize("header, map_edit, message", [
    ("time_ms,phi,theta,hdg,p,q,r,v_east,v_north,vz", None, "has no column 'v_up' (the map's vd_mps)"),
    (None, ('unit = "kt" }\nve_mps', 'unit = "mph" }\nve_mps'), "unit 'mph' is not one of"),
    (None, ('heading_deg = "hdg"\n', ''), "does not say which column holds 'heading_deg'"),
])
def test_map_faults_are_one_sentence(tmp_path, capsys, header, map_edit, message):
    log = _recorded(tmp_path, header) if header else _recorded(tmp_path)
    if map_edit:
        (tmp_path / "map.toml").write_text(MAP.replace(*map_edit))
    assert main(["telemetry", str(log), "--map", str(tmp_path / "map.toml"), "--out", str(tmp_path / "t.csv")]) == 2
    error = capsys.readouterr().err
    assert message in error and error.count("\n") == 1
