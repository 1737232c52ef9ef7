"""Property-based tests of the readers (issue 19 item 5): whatever one cell, one line or the
whole text of a file holds, a reader either returns a table whose every number lies inside
the plausibility limits, or refuses with one ValueError sentence naming the file. Never
another exception, never a multi-line message.

Fast by default (a few dozen examples per property); ``pytest --hypothesis-profile=ci`` runs
the longer profile.
"""
import math

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from visland.contracts import read_csv, read_labels, read_telemetry  # noqa: E402
from visland.limits import COLUMN_LIMITS  # noqa: E402
from visland.sensors import TELEMETRY_COLUMNS  # noqa: E402

settings.register_profile("quick", max_examples=40, deadline=None,
                          suppress_health_check=[HealthCheck.function_scoped_fixture])
settings.register_profile("ci", max_examples=1000, deadline=None,
                          suppress_health_check=[HealthCheck.function_scoped_fixture])
settings.load_profile("quick")

N_ROWS = 6
GOOD_ROW = {"roll_deg": 1.0, "pitch_deg": 2.0, "heading_deg": 40.0, "p_dps": 0.1, "q_dps": -0.2, "r_dps": 0.0,
            "vn_mps": 50.0, "ve_mps": 45.0, "vd_mps": 3.5}

cells = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.sampled_from(["", "nan", "inf", "-inf", "1e308", "-1e308", "1e6", "abc", "1,2", '"', "\ufeff1", "0x10",
                     "1e-320", " 7 ", "١٢"]),
    st.text(max_size=8),
)


def _telemetry_text(row: int, column: str, cell: str) -> str:
    lines = [",".join(TELEMETRY_COLUMNS)]
    for i in range(N_ROWS):
        values = {"t_s": f"{0.02 * i:g}", **{k: f"{v:g}" for k, v in GOOD_ROW.items()}}
        if i == row:
            values[column] = cell
        lines.append(",".join(values[c] for c in TELEMETRY_COLUMNS))
    return "\n".join(lines) + "\n"


def _check_outcome(read, path):
    try:
        table = read(path)
    except ValueError as error:
        message = str(error)
        assert str(path) in message and "\n" not in message, message
        return None
    for column in table.column_order:
        limit = COLUMN_LIMITS.get(column)
        if limit is None or table[column].dtype.kind != "f":
            continue
        values = table[column][~(table[column] != table[column])]            # NaN: not measured
        assert all(limit.low <= v <= limit.high for v in values), (column, values)
    return table


@given(row=st.integers(0, N_ROWS - 1), column=st.sampled_from(TELEMETRY_COLUMNS), cell=cells)
def test_one_telemetry_cell_of_anything(tmp_path_factory, row, column, cell):
    path = tmp_path_factory.mktemp("tele") / "telemetry.csv"
    path.write_text(_telemetry_text(row, column, cell), encoding="utf-8", newline="")
    table = _check_outcome(read_telemetry, path)
    if table is not None:
        assert table.n_rows == N_ROWS and all(math.isfinite(v) for c in TELEMETRY_COLUMNS for v in table[c])


@given(data=st.binary(max_size=300))
def test_any_bytes_as_a_csv(tmp_path_factory, data):
    path = tmp_path_factory.mktemp("bytes") / "telemetry.csv"
    path.write_bytes(data)
    _check_outcome(read_telemetry, path)
    _check_outcome(lambda p: read_csv(p, ("t_s",)), path)


@given(line=st.integers(1, N_ROWS), text=st.text(max_size=40))
def test_one_line_replaced_by_any_text(tmp_path_factory, line, text):
    lines = _telemetry_text(0, "roll_deg", "1").splitlines()
    lines[line] = text.replace("\n", " ").replace("\r", " ")
    path = tmp_path_factory.mktemp("line") / "telemetry.csv"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8", newline="")
    _check_outcome(read_telemetry, path)


@given(column=st.sampled_from(["near_left_u_px", "left_theta_rad", "left_rho", "dF_px", "frame", "near_left_visible",
                               "t_s"]), cell=cells)
def test_one_label_cell_of_anything(tmp_path_factory, column, cell):
    from visland.contracts import LABEL_COLUMNS
    rows = []
    for i in range(3):
        values = {c: "0" for c in LABEL_COLUMNS}
        values.update(frame=str(i), t_s=f"{0.04 * i:g}", near_left_visible="1", near_right_visible="1",
                      far_left_visible="1", far_right_visible="1", left_theta_rad="0.5", right_theta_rad="-0.5")
        values.update({c: "100" for c in LABEL_COLUMNS if c.endswith("_px")})
        if i == 1:
            values[column] = cell
        rows.append(",".join(values[c] for c in LABEL_COLUMNS))
    path = tmp_path_factory.mktemp("labels") / "labels.csv"
    path.write_text("\n".join([",".join(LABEL_COLUMNS)] + rows) + "\n", encoding="utf-8", newline="")
    _check_outcome(read_labels, path)
