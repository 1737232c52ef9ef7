"""The thesis result tables the studies compare against (Gibert 2016, chapter 5).

The figures ship as a data file beside this module, ``estimation/thesis_tables.csv`` (a copy of
../shared/seeds/thesis_tables.csv: tables 5.3, 5.4, 5.6, 5.7, 5.8, 5.10, 5.12 of the observers
and 5.14-5.16 of image processing), read when this module is imported, so that ``visland study`` runs
from an installed package. Columns ``table,condition,features,observer,metric,value``; errors
are ``dH - dH_hat`` in metres; "traj1" is scenario thesis-1, "all8" the eight scenarios of
thesis Table 5.2. Observer names are SPEC's (the thesis's EKF_2P is ``kf-2p``).
"""
from __future__ import annotations

import csv
import io
import math
from importlib.resources import files

__all__ = ["THESIS_DATA", "THESIS_TABLES", "THESIS_CONDITIONS", "thesis_value"]

#: the data file, inside the installed package
THESIS_DATA = "thesis_tables.csv"
_COLUMNS = ("table", "condition", "features", "observer", "metric", "value")


def _read() -> tuple[dict, dict]:
    """The data file as ``({(table, observer, metric): value}, {table: (condition, features)})``."""
    text = files("visland.estimation").joinpath(THESIS_DATA).read_text(encoding="utf-8")
    reader = csv.DictReader(io.StringIO(text))
    if tuple(reader.fieldnames or ()) != _COLUMNS:
        raise ValueError(f"{THESIS_DATA}: columns {reader.fieldnames}, expected {list(_COLUMNS)}")
    tables, conditions = {}, {}
    for line, row in enumerate(reader, start=2):
        try:
            value = float(row["value"])
        except (TypeError, ValueError):
            value = math.nan
        if not math.isfinite(value):
            raise ValueError(f"{THESIS_DATA} line {line}: value {row['value']!r} is not a finite number")
        key = (row["table"], row["observer"], row["metric"])
        if key in tables:
            raise ValueError(f"{THESIS_DATA} line {line}: table {key[0]}, {key[1]}, {key[2]} given twice")
        tables[key] = value
        conditions.setdefault(row["table"], (row["condition"], row["features"]))
    return tables, conditions


#: (table, observer, metric) -> value
#: table -> (condition, features), e.g. '5.6': ('1 px Gaussian noise', '2 points')
THESIS_TABLES, THESIS_CONDITIONS = _read()


def thesis_value(table: str, observer: str, metric: str) -> float | None:
    """The thesis figure, or None when the thesis has none for this observer and metric.

    Parameters
    ----------
    table : str
        A thesis table (``"5.6"``, ``"5.7"``...), as in ``thesis_tables.csv``.
    observer : str
        SPEC observer name.
    metric : str
        The ``metric`` of ``thesis_tables.csv`` (``mean_err_100ft_m_all8``, ``conv_time_5pct_s_traj1``...).

    Returns
    -------
    float or None
    """
    return THESIS_TABLES.get((table, observer, metric))
