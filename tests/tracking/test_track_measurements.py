"""Designation parsing and the measurement rows built from tracker steps."""
import math

import numpy as np
import pytest

from visland.contracts import MEASUREMENT_COLUMNS
from visland.runway import CORNER_NAMES
from visland.tracking import AnchorObservation
from visland.tracking.measurements import (designation_from_labels, measurement_columns, parse_designation,
                                           steps_to_columns)
from visland.tracking.tracker import PointReport, TrackStep


def test_designation_text_names_points_in_corner_order():
    points = parse_designation("10,20; 30.5,40 ;;7,8;1,2")
    assert points == [("near_left", (10.0, 20.0)), ("near_right", (30.5, 40.0)), ("far_right", (7.0, 8.0)),
                      ("point_5", (1.0, 2.0))]
    assert parse_designation("near_right=3,4;edge=5,6") == [("near_right", (3.0, 4.0)), ("edge", (5.0, 6.0))]


@pytest.mark.parametrize("text, message", [
    ("", "give 'labels' or pixel positions"),
    ("1,2,3", r"entry 1 \('1,2,3'\) is not a pixel position"),
    ("a,b", "is not a pixel position"),
    ("nan,3", "not a finite pixel position"),
    ("1,2;near_left=3,4", "designated twice"),
    ("Bad Name=1,2", "must be lower-case"),
    (";;", "no pixel position given"),
])
def test_bad_designation_text_is_named(text, message):
    with pytest.raises(ValueError, match=message):
        parse_designation(text)


def labels(n=3):
    cols = {"t_s": np.arange(n) / 25.0}
    for k, name in enumerate(CORNER_NAMES):
        cols[f"{name}_u_px"] = np.full(n, 100.0 + 10 * k)
        cols[f"{name}_v_px"] = np.full(n, 200.0 - 50 * (k // 2))
        cols[f"{name}_visible"] = np.ones(n)
    return cols


def test_labels_designation_with_edge_points_on_the_segments():
    cols = labels()
    cols["far_right_visible"][1] = 0
    points = dict(designation_from_labels(cols, 0, edge_points=1))
    assert set(points) == set(CORNER_NAMES) | {"left_edge_1", "right_edge_1"}
    np.testing.assert_allclose(points["left_edge_1"], (110.0, 175.0))     # midway near_left (100,200) - far_left (120,150)
    assert "far_right" not in dict(designation_from_labels(cols, 1))
    with pytest.raises(ValueError, match="right edge's corners are not both visible"):
        designation_from_labels(cols, 1, edge_points=2)
    with pytest.raises(ValueError, match="no row for frame 5"):
        designation_from_labels(cols, 5)


def report(name, status, uv=(1.0, 2.0), score=0.9, reason=""):
    measured = status in ("designated", "tracked", "anchored", "reprojected", "inconsistent")
    return PointReport(name, status, np.array(uv) if measured else np.full(2, np.nan), score, math.nan, reason)


def test_rows_say_what_was_measured_and_why_not():
    names = ["near_left", "near_right", "left_edge_1"]
    anchor = AnchorObservation(True, "", 0.8, np.zeros((4, 2)), np.ones(4, dtype=bool),
                               {"left": (0.1, 0.02)}, 12.0, math.radians(2.0))
    steps = [
        None,
        TrackStep(1, (report("near_left", "designated", score=math.nan), report("near_right", "designated",
                                                                               score=math.nan),
                      report("left_edge_1", "designated", score=math.nan)), note="designation"),
        TrackStep(2, (report("near_left", "tracked", score=0.93), report("near_right", "coasting", score=0.41,
                                                                        reason="score 0.41 < 0.60"),
                      report("left_edge_1", "tracked", (5.0, 6.0), 0.7))),
        TrackStep(3, (report("near_left", "anchored", score=math.nan), report("near_right", "tracked", score=0.95),
                      report("left_edge_1", "tracked", score=0.8)), anchor=anchor),
    ]
    cols = steps_to_columns(steps, [0.0, 0.04, 0.08, 0.12], names)
    assert list(cols) == measurement_columns(names)
    assert list(cols)[:len(MEASUREMENT_COLUMNS)] == list(MEASUREMENT_COLUMNS)
    assert cols["found"] == [0, 1, 0, 1]
    assert cols["reason"][0] == "before the designation"
    assert cols["reason"][2] == "near_right coasting (score 0.41 < 0.60)"
    assert math.isnan(cols["near_right_u_px"][2]) and cols["near_right_visible"][2] == 0
    assert cols["left_edge_1_u_px"][2] == 5.0 and cols["left_edge_1_score"][2] == 0.7
    assert math.isnan(cols["far_left_visible"][2])                  # not designated
    assert cols["source"] == ["tracking", "tracking", "tracking", "anchored"]
    assert cols["confidence"][3] == pytest.approx(0.8)              # min(anchor 0.8, score 0.95)
    assert cols["left_rho"][3] == 0.1 and cols["dF_px"][3] == 12.0 and cols["dpsi_deg"][3] == pytest.approx(2.0)
    assert math.isnan(cols["right_rho"][3]) and math.isnan(cols["left_rho"][2])
