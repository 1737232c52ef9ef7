"""Image-processing errors against the labels (visland.datasets.pixel_errors), on hand-made rows
whose answers are known: a corner moved (3, 4) px is 5 px off, an edge line moved 3 px is 3 px off."""
import math

import numpy as np
import pytest

from visland.camera import CameraModel
from visland.datasets.pixel_errors import corner_errors_px, edge_errors_px
from visland.runway import CORNER_NAMES

CAMERA = CameraModel.default()        # 2048 px, fx = fy = 2472, cx = cy = 1023.5
CORNERS_UV = {"near_left": (500.0, 1500.0), "near_right": (1500.0, 1500.0),
              "far_left": (500.0, 1000.0), "far_right": (1500.0, 1000.0)}


def labels_and_measurements():
    """Two frames of a rectangle-shaped runway image with vertical edges at u = 500 and u = 1500;
    in frame 1 the far-left corner lies outside the image."""
    labels, measured = {}, {}
    for name in CORNER_NAMES:
        u, v = CORNERS_UV[name]
        labels[f"{name}_u_px"] = np.array([u, u])
        labels[f"{name}_v_px"] = np.array([v, v if name != "far_left" else -500.0])
        labels[f"{name}_visible"] = np.array([1.0, 0.0 if name == "far_left" else 1.0])
        measured[f"{name}_u_px"] = np.array([u + 3.0, math.nan])
        measured[f"{name}_v_px"] = np.array([v + 4.0, math.nan])
    # vertical lines u = const: theta = 0 and rho = x = (u - cx) / fx, 3 px right of the labelled edges
    for edge, u in (("left", 500.0), ("right", 1500.0)):
        measured[f"{edge}_theta_rad"] = np.array([0.0, 0.0])
        measured[f"{edge}_rho"] = np.array([(u + 3.0 - CAMERA.cx) / CAMERA.fx, (u + 3.0 - CAMERA.cx) / CAMERA.fx])
    return measured, labels


def test_corner_errors_are_distances_and_nan_where_unmeasured_or_outside():
    measured, labels = labels_and_measurements()
    errors = corner_errors_px(measured, labels)
    assert set(errors) == set(CORNER_NAMES)
    for name in CORNER_NAMES:
        assert errors[name][0] == pytest.approx(5.0)
        assert math.isnan(errors[name][1])


def test_edge_errors_average_the_labelled_edge_points_inside_the_image():
    measured, labels = labels_and_measurements()
    errors = edge_errors_px(measured, labels, CAMERA)
    assert errors["left"][0] == pytest.approx(3.0, abs=1e-9) and errors["right"][0] == pytest.approx(3.0, abs=1e-9)
    # frame 1: the left edge runs out of the image (v < 0) but its points inside are still 3 px off
    assert errors["left"][1] == pytest.approx(3.0, abs=1e-9)
    measured["right_rho"][1] = math.nan
    assert math.isnan(edge_errors_px(measured, labels, CAMERA)["right"][1])
