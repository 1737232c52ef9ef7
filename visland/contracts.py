"""File contracts of SPEC.md: the CSV and JSON files users exchange, read and written here.

Every reader validates what it reads and fails with one ``ValueError`` sentence naming the
file, the line and the column (missing column, text where a number belongs, NaN, time that
does not increase). Every writer writes atomically (a temporary file renamed into place), so
a reader never sees half a file.

Schemas (columns in this order; "more columns may follow" where SPEC says so):

- ``telemetry.csv``: :data:`TELEMETRY_COLUMNS`, inertial data at >= the frame rate, then the
  optional :data:`TELEMETRY_OPTIONAL_COLUMNS` (true airspeed ``tas_mps``).
- ``truth.csv``: :data:`TRUTH_COLUMNS` then :data:`TRUTH_EXTRA_COLUMNS`, one row per frame.
- ``labels.csv``: :data:`LABEL_COLUMNS` then :data:`LABEL_EXTRA_COLUMNS`, one row per frame.
- ``measurements.csv``: :data:`MEASUREMENT_COLUMNS` (labels schema + source, found, reason,
  confidence); empty cells where a feature was not measured.
- ``estimates.csv``: :data:`ESTIMATE_COLUMNS` then :data:`ESTIMATE_EXTRA_COLUMNS`, one row per
  observer per frame.
- ``frames.csv``: ``frame,t_s``.
"""
from __future__ import annotations

import csv
import io
import math
import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from visland.limits import check_columns, check_frame_times
from visland.runway import CORNER_NAMES
from visland.sensors import TELEMETRY_COLUMNS, TELEMETRY_OPTIONAL_COLUMNS

__all__ = [
    "TELEMETRY_COLUMNS", "TELEMETRY_OPTIONAL_COLUMNS", "TRUTH_COLUMNS", "TRUTH_EXTRA_COLUMNS", "LABEL_COLUMNS", "LABEL_EXTRA_COLUMNS",
    "MEASUREMENT_COLUMNS", "ESTIMATE_COLUMNS", "ESTIMATE_EXTRA_COLUMNS", "FRAMES_COLUMNS", "Table", "read_csv", "write_csv",
    "read_telemetry", "read_truth", "read_labels", "read_measurements", "read_frames_csv", "read_estimates",
    "atomic_write_text", "atomic_write_bytes", "staged_output_dir", "check_time_column", "json_ready",
]

TRUTH_COLUMNS = ("t_s", "dx_m", "dy_m", "dh_m", "roll_deg", "pitch_deg", "dpsi_deg")
TRUTH_EXTRA_COLUMNS = ("frame", "dgs_m", "heading_deg", "vx_runway_mps", "vy_runway_mps", "vz_runway_mps",
                       "wind_x_runway_mps", "wind_y_runway_mps", "wind_z_runway_mps")

LABEL_COLUMNS = (
    ("frame", "t_s")
    + tuple(f"{c}_{a}_px" for c in CORNER_NAMES for a in ("u", "v"))
    + ("left_rho", "left_theta_rad", "right_rho", "right_theta_rad", "center_rho", "center_theta_rad",
       "dF_px", "dpsi_deg")
    + tuple(f"{c}_visible" for c in CORNER_NAMES)
)
#: Virtual-frame threshold corners (thesis 3.23) and observability indices (thesis 3.30, 3.40).
LABEL_EXTRA_COLUMNS = ("yv1_near_left", "yv2_near_left", "yv1_near_right", "yv2_near_right",
                       "obs_points", "obs_lines")
MEASUREMENT_COLUMNS = LABEL_COLUMNS + ("source", "found", "reason", "confidence")
ESTIMATE_COLUMNS = ("observer", "t_s", "dx_m", "dy_m", "dh_m", "width_m", "dpsi_deg", "observability")
#: ``coasting``: 1 where no measurement corrected the frame (the observer ran on its model, or its
#: estimate was withheld after a long gap: then the estimate cells are empty); ``wind_x_mps``,
#: ``wind_y_mps``: the horizontal wind in runway axes, empty for observers that do not estimate it.
ESTIMATE_EXTRA_COLUMNS = ("coasting", "wind_x_mps", "wind_y_mps")
FRAMES_COLUMNS = ("frame", "t_s")

#: Label/measurement columns that may be empty (not visible, not measured).
_FEATURE_COLUMNS = frozenset(LABEL_COLUMNS[2:] + LABEL_EXTRA_COLUMNS)


def _read_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


_UMASK = _read_umask()


class Table(dict):
    """Columns of a CSV file as numpy arrays (text columns as arrays of str), with its path.

    Parameters
    ----------
    columns : dict of str to ndarray
        Column name -> values, one per data row (numbers as float, NaN for an allowed empty cell).
    path : Path
        The file read (named in errors).
    column_order : list of str
        The columns in file order (kept as ``column_order`` for writing back).
    """

    def __init__(self, columns: dict, path: Path, column_order: list):
        super().__init__(columns)
        self.path = path
        self.column_order = list(column_order)

    @property
    def n_rows(self) -> int:
        return len(next(iter(self.values()))) if self else 0


# --------------------------------------------------------------------------- writing
def json_ready(value):
    """``value`` with numpy scalars turned into Python numbers and NaN/inf into None (JSON null).

    Parameters
    ----------
    value : object
        A number, or dicts, lists and tuples of them (walked recursively); anything else is
        returned as is.

    Returns
    -------
    object
        The same structure, ready for :func:`json.dumps` (tuples become lists).
    """
    if isinstance(value, dict):
        return {k: json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    return value


def _format_cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, (str, np.str_)):
        return str(value)
    if isinstance(value, (bool, np.bool_)):
        return "1" if value else "0"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    value = float(value)
    if not math.isfinite(value):
        return ""
    return format(value, ".12g")


def write_csv(path, columns: dict, order=None) -> None:
    """Write columns (equal-length sequences) as CSV, atomically; NaN and None become empty cells.

    Parameters
    ----------
    path : str or Path
        The file to write (replaced if it exists).
    columns : dict of str to sequence
        Column name -> values (numbers written with 12 significant digits, booleans as 1/0).
    order : sequence of str, optional
        The columns to write, in order (default: every column, in dict order).

    Raises
    ------
    ValueError
        A column of ``order`` missing from ``columns``, or columns of different lengths.
    """
    order = list(order) if order is not None else list(columns)
    missing = [c for c in order if c not in columns]
    if missing:
        raise ValueError(f"{path}: no data for column '{missing[0]}'")
    lengths = {len(columns[c]) for c in order}
    if len(lengths) > 1:
        raise ValueError(f"{path}: columns have different lengths {sorted(lengths)}")
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(order)
    cols = [columns[c] for c in order]
    n = lengths.pop() if lengths else 0
    for i in range(n):
        writer.writerow([_format_cell(col[i]) for col in cols])
    atomic_write_text(path, buffer.getvalue())


def atomic_write_bytes(path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file in the same folder and a rename.

    Parameters
    ----------
    path : str or Path
        The file to write; a reader sees the old file or the new one, never half of one.
    data : bytes
        The content (the file gets the usual permissions, 0666 less the umask).
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.chmod(tmp, 0o666 & ~_UMASK)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise


def atomic_write_text(path, text: str) -> None:
    """:func:`atomic_write_bytes` for text.

    Parameters
    ----------
    path : str or Path
        The file to write.
    text : str
        Written as UTF-8.
    """
    atomic_write_bytes(path, text.encode("utf-8"))


@contextmanager
def staged_output_dir(out_dir, force: bool = False):
    """Build an output folder in a hidden sibling and move it into place only on success.

    An existing ``out_dir`` is refused unless ``force``; on failure nothing is left behind
    (and a forced run keeps the old folder).

    Parameters
    ----------
    out_dir : str or Path
        The folder the command writes.
    force : bool, default False
        Replace an existing ``out_dir`` (only once the new one is complete).

    Yields
    ------
    Path
        The staging folder to write into; a ``ValueError`` raised inside names ``out_dir``
        instead of it.
    """
    out_dir = Path(out_dir)
    if out_dir.exists() and not force:
        raise ValueError(f"{out_dir}: output folder exists; choose another --out or pass --force to replace it")
    parent = out_dir.parent if str(out_dir.parent) else Path(".")
    parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.partial-", dir=parent))
    os.chmod(staging, 0o777 & ~_UMASK)
    try:
        yield staging
    except ValueError as error:
        shutil.rmtree(staging, ignore_errors=True)
        # the staging folder is gone and means nothing to the user: name the output instead
        raise ValueError(str(error).replace(str(staging), str(out_dir))) from None
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    if out_dir.exists():
        old = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.old-", dir=parent))
        os.replace(out_dir, old / "dir")
        os.replace(staging, out_dir)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(staging, out_dir)


# --------------------------------------------------------------------------- reading
def read_csv(path, required, text_columns=(), optional_empty=(), name=None) -> Table:
    """Read a CSV file with a header row into a :class:`Table`.

    Parameters
    ----------
    path : file to read.
    required : columns that must be present (others are kept too).
    text_columns : columns kept as text.
    optional_empty : numeric columns whose cells may be empty (read as NaN); any other empty,
        NaN or infinite cell in a numeric column is an error.
    name : how the file is named in errors (default: the path).
    """
    path = Path(path)
    label = name or str(path)
    try:
        handle = path.open(newline="", encoding="utf-8-sig")     # a spreadsheet's byte-order mark is not a column name
    except FileNotFoundError:
        raise ValueError(f"{label}: file not found") from None
    except IsADirectoryError:
        raise ValueError(f"{label}: is a folder, expected a CSV file") from None
    with handle:
        reader = csv.reader(handle)
        try:
            header = next(reader)
        except StopIteration:
            raise ValueError(f"{label}: file is empty (expected a header row)") from None
        except csv.Error as error:
            raise ValueError(f"{label}: not a readable CSV file ({error})") from None
        except UnicodeDecodeError as error:
            raise ValueError(f"{label}: not UTF-8 text (byte {error.start} is 0x{error.object[error.start]:02x}), "
                             "not a CSV file") from None
        header = [h.strip() for h in header]
        duplicates = {h for h in header if header.count(h) > 1}
        if duplicates:
            raise ValueError(f"{label}: column '{sorted(duplicates)[0]}' appears twice in the header")
        for column in required:
            if column not in header:
                raise ValueError(f"{label}: missing column '{column}' (header has: {', '.join(header)})")
        text = set(text_columns)
        allowed_empty = set(optional_empty)
        raw = {h: [] for h in header}
        try:
            for line_number, row in enumerate(reader, start=2):
                if not row or all(not cell.strip() for cell in row):
                    continue
                if len(row) != len(header):
                    raise ValueError(f"{label} line {line_number}: {len(row)} cells, the header has {len(header)}")
                for column, cell in zip(header, row):
                    cell = cell.strip()
                    if column in text:
                        raw[column].append(cell)
                        continue
                    if cell == "":
                        if column in allowed_empty or column not in required:
                            raw[column].append(math.nan)
                            continue
                        raise ValueError(f"{label} line {line_number}: column '{column}' is empty")
                    try:
                        value = float(cell)
                    except ValueError:
                        raise ValueError(f"{label} line {line_number}: column '{column}' is not a number "
                                         f"({cell!r})") from None
                    if not math.isfinite(value) and column not in allowed_empty:
                        raise ValueError(f"{label} line {line_number}: column '{column}' is {cell} "
                                         "(a finite number is required)")
                    raw[column].append(value)
        except csv.Error as error:
            raise ValueError(f"{label}: not a readable CSV file ({error})") from None
        except UnicodeDecodeError:
            raise ValueError(f"{label}: not UTF-8 text, not a CSV file") from None
    columns = {h: (np.array(v, dtype=object).astype(str) if h in text else np.array(v, dtype=float))
               for h, v in raw.items()}
    if not columns[header[0]].size:
        raise ValueError(f"{label}: no data rows after the header")
    return Table(columns, path, header)


def check_time_column(table: Table, column: str = "t_s", strictly: bool = True) -> None:
    """Raise if the time column does not increase (naming the first offending line).

    Parameters
    ----------
    table : Table
        A table read by :func:`read_csv`.
    column : str, default "t_s"
        The time column, seconds.
    strictly : bool, default True
        Refuse equal successive times too.
    """
    t = table[column]
    steps = np.diff(t)
    bad = np.nonzero(steps <= 0 if strictly else steps < 0)[0]
    if bad.size:
        i = int(bad[0]) + 1
        raise ValueError(f"{table.path} line {i + 2}: {column} does not increase ({t[i]:g} after {t[i - 1]:g})")


def read_telemetry(path) -> Table:
    """``telemetry.csv``: all SPEC columns, finite, strictly increasing time; the optional
    ``tas_mps`` (true airspeed), when present, positive and finite on every line.

    Parameters
    ----------
    path : str or Path
        The telemetry file (degrees, deg/s, m/s as the column names say).

    Returns
    -------
    Table
        The SPEC columns (and ``tas_mps`` when present), time strictly increasing.
    """
    table = read_csv(path, TELEMETRY_COLUMNS)
    check_time_column(table)
    check_columns(table)
    for column in TELEMETRY_OPTIONAL_COLUMNS:
        if column in table:
            bad = np.nonzero(~(np.isfinite(table[column]) & (table[column] > 0)))[0]
            if bad.size:
                i = int(bad[0])
                raise ValueError(f"{table.path} line {i + 2}: column '{column}' is {table[column][i]:g} "
                                 "(a positive airspeed in m/s is required on every line, or no column)")
    return table


def read_truth(path) -> Table:
    """``truth.csv``: the SPEC columns (extras optional), strictly increasing time.

    Parameters
    ----------
    path : str or Path
        One row per frame: deviations in metres, attitude in degrees.

    Returns
    -------
    Table
        The SPEC columns and any extras, one row per frame.
    """
    table = read_csv(path, TRUTH_COLUMNS)
    check_time_column(table)
    check_columns(table)
    check_frame_times(table["t_s"], str(table.path))
    return table


def read_labels(path) -> Table:
    """``labels.csv``: the SPEC labels schema; feature cells may be empty (not visible).

    Parameters
    ----------
    path : str or Path
        Exact features of a generated dataset, one row per frame (pixels, radians).

    Returns
    -------
    Table
        Empty feature cells as NaN; ``*_visible`` 0 or 1.
    """
    table = read_csv(path, LABEL_COLUMNS, optional_empty=_FEATURE_COLUMNS)
    check_time_column(table)
    _check_frames_and_flags(table)
    check_columns(table)
    check_frame_times(table["t_s"], str(table.path))
    return table


#: The corner and line columns of a measurement file (at least one pair must be there).
_GEOMETRY_COLUMNS = tuple(c for c in LABEL_COLUMNS if c.endswith(("_px", "_rho", "_theta_rad")) and c != "dF_px")


def read_measurements(path) -> Table:
    """``measurements.csv``: labels schema plus source, found, reason, confidence.

    A file from another tool needs only ``t_s`` and the features it has (corners and/or lines,
    SPEC columns); what it lacks defaults: ``frame`` the row index, ``source`` "external",
    ``found`` 1 where the row holds a corner or a line, ``reason`` empty, ``confidence`` empty,
    ``*_visible`` 1 where the corner's two coordinates are given, other features empty.

    Parameters
    ----------
    path : str or Path
        A detector's, tracker's or another tool's features, one row per frame.

    Returns
    -------
    Table
        Every :data:`MEASUREMENT_COLUMNS` column, the missing ones filled as described.
    """
    table = read_csv(path, ("t_s",), text_columns=("source", "reason"),
                     optional_empty=_FEATURE_COLUMNS | {"confidence"})
    present = [c for c in _GEOMETRY_COLUMNS if c in table]
    if not present:
        raise ValueError(f"{table.path}: no corner or line columns (e.g. near_left_u_px, near_left_v_px, "
                         "left_rho, left_theta_rad); nothing to estimate from")
    n = table.n_rows
    order = list(table.column_order)
    def add(column, values):
        table[column] = values
        order.append(column)
    for column in LABEL_COLUMNS:
        if column not in table and column not in ("frame", "t_s") and not column.endswith("_visible"):
            add(column, np.full(n, np.nan))
    for corner in CORNER_NAMES:
        if f"{corner}_visible" not in table:
            add(f"{corner}_visible", (np.isfinite(table[f"{corner}_u_px"])
                                      & np.isfinite(table[f"{corner}_v_px"])).astype(float))
    if "frame" not in table:
        add("frame", np.arange(n, dtype=float))
    if "source" not in table:
        add("source", np.full(n, "external"))
    if "found" not in table:
        add("found", np.any([np.isfinite(table[c]) for c in present], axis=0).astype(float))
    if "reason" not in table:
        add("reason", np.full(n, ""))
    if "confidence" not in table:
        add("confidence", np.full(n, np.nan))
    table.column_order = order
    check_time_column(table)
    bad = np.nonzero(~np.isin(table["found"], (0.0, 1.0)))[0]
    if bad.size:
        raise ValueError(f"{table.path} line {int(bad[0]) + 2}: column 'found' must be 0 or 1")
    _check_frames_and_flags(table)
    check_columns(table, rows=table["found"] > 0.5)
    check_frame_times(table["t_s"], str(table.path))
    return table


def _check_frames_and_flags(table: Table) -> None:
    """``frame`` holds the integers 0, 1, 2... in order (when the column is there, it may be
    missing from a measurement file from elsewhere) and each ``*_visible`` flag is 0 or 1."""
    if "frame" in table and table["frame"].dtype.kind == "f":
        frames = table["frame"]
        bad = np.nonzero((frames != np.round(frames)) | (frames < 0))[0]
        if bad.size:
            i = int(bad[0])
            raise ValueError(f"{table.path} line {i + 2}: column 'frame' is {frames[i]:g} (a frame index 0, 1, 2... "
                             "is required)")
        bad = np.nonzero(np.diff(frames) <= 0)[0]
        if bad.size:
            i = int(bad[0]) + 1
            raise ValueError(f"{table.path} line {i + 2}: frame {frames[i]:g} after frame {frames[i - 1]:g} (one row "
                             "per frame, in order)")
    found = table["found"] > 0.5 if "found" in table else np.ones(table.n_rows, dtype=bool)
    for corner in CORNER_NAMES:
        column = f"{corner}_visible"
        if column in table:
            values = table[column]
            bad = np.nonzero(np.isfinite(values) & ~np.isin(values, (0.0, 1.0)))[0]
            if bad.size:
                i = int(bad[0])
                raise ValueError(f"{table.path} line {i + 2}: column '{column}' is {values[i]:g} (0 or 1 is required)")
            for axis in ("u", "v"):
                cells = table.get(f"{corner}_{axis}_px")
                if cells is None:
                    continue
                bad = np.nonzero((values == 1.0) & found & ~np.isfinite(cells))[0]
                if bad.size:
                    i = int(bad[0])
                    raise ValueError(f"{table.path} line {i + 2}: column '{corner}_{axis}_px' is empty but "
                                     f"'{column}' is 1 (a visible corner has its pixel)")


def read_frames_csv(path) -> Table:
    """``frames.csv``: ``frame,t_s`` with increasing time.

    Parameters
    ----------
    path : str or Path
        Frame index or file name, and time in seconds, one row per image.

    Returns
    -------
    Table
        ``frame`` as text (an index or a file name), ``t_s`` increasing.
    """
    table = read_csv(path, FRAMES_COLUMNS, text_columns=("frame",))
    check_time_column(table)
    check_columns(table, columns=("t_s",))
    check_frame_times(table["t_s"], str(table.path))
    return table


def read_estimates(path) -> Table:
    """``estimates.csv``: one row per observer per frame; estimate cells may be empty (coasting).

    Parameters
    ----------
    path : str or Path
        As written by ``visland estimate`` or ``visland process``.

    Returns
    -------
    Table
        ``observer`` as text; coasting estimates as NaN.
    """
    return read_csv(path, ESTIMATE_COLUMNS, text_columns=("observer",),
                    optional_empty={"dx_m", "dy_m", "dh_m", "width_m", "dpsi_deg", "observability"})
