"""Labels agree with pixels: the runway polygon extracted from a flat-colour render matches labels.csv.

The extraction is independent of the label code: white runway on black, each row's left and
right edge located to sub-pixel precision from the anti-aliased coverage (the uncovered area
left of the runway in a row equals the edge's abscissa + 0.5), each column's far and near edge
likewise, straight lines fitted through them and intersected.
"""
import math

import numpy as np
import pytest

from visland.camera import CameraModel
from visland.contracts import read_labels
from visland.features import batch_R_camera_from_runway
from visland.flight import FT_TO_M
from visland.render import FrameRenderer, SceneParams
from visland.scenarios import get_scenario
from visland.simulate import SimulationOptions, run_simulation, write_simulation_files

SIZE = 2048


def _edges_along(coverage_lines, index, margin):
    """Sub-pixel start and end of the covered run in each line (rows or columns) of ``coverage_lines``."""
    starts, ends, where = [], [], []
    for k in index:
        line = coverage_lines[k]
        full = np.nonzero(line >= 0.999)[0]
        if len(full) < 2 * margin + 1:
            continue
        m = full[len(full) // 2]
        start = -0.5 + np.sum(1.0 - line[: m + 1])
        end = m + 0.5 + np.sum(line[m + 1:])
        starts.append(start)
        ends.append(end)
        where.append(k)
    return np.array(where, float), np.array(starts), np.array(ends)


def _fit(t, s):
    """Least-squares line s = a t + b."""
    a, b = np.polyfit(t, s, 1)
    return a, b


def _intersect(vertical, horizontal):
    """Intersect u = a1 v + b1 with v = a2 u + b2."""
    a1, b1 = vertical
    a2, b2 = horizontal
    v = (a2 * b1 + b2) / (1.0 - a1 * a2)
    return np.array([a1 * v + b1, v])


def extract_runway_corners(rgb, corners_hint_uv, margin=3):
    """Corners (near_left, near_right, far_left, far_right) of the white quadrilateral, (4, 2) pixels.

    ``corners_hint_uv`` only chooses which rows and columns are away from the corners.
    """
    coverage = rgb[..., 0].astype(float) / 255.0
    nl, nr, fl, fr = corners_hint_uv
    v_lo = int(math.ceil(max(fl[1], fr[1]))) + margin
    v_hi = int(math.floor(min(nl[1], nr[1]))) - margin
    rows, lefts, rights = _edges_along(coverage, range(max(v_lo, 0), min(v_hi, SIZE - 1) + 1), 1)
    left = _fit(rows, lefts)
    right = _fit(rows, rights)
    cols_far = range(int(math.ceil(fl[0])) + margin, int(math.floor(fr[0])) - margin + 1)
    cols_near = range(int(math.ceil(max(nl[0], 0))) + margin, int(math.floor(min(nr[0], SIZE - 1))) - margin + 1)
    c_far, tops, _ = _edges_along(coverage.T, cols_far, 1)
    c_near, _, bottoms = _edges_along(coverage.T, cols_near, 1)
    far = _fit(c_far, tops)
    near = _fit(c_near, bottoms)
    return np.array([_intersect(left, near), _intersect(right, near), _intersect(left, far), _intersect(right, far)])


@pytest.fixture(scope="module")
def flown(tmp_path_factory):
    camera = CameraModel.default(SIZE)
    result = run_simulation(get_scenario("thesis-7"), SimulationOptions(fps=5.0, camera=camera,
                                                                        calibration_error_deg=0.5))
    folder = tmp_path_factory.mktemp("labels")
    write_simulation_files(result, folder)
    return result, read_labels(folder / "labels.csv")


def _frame_at_distance(result, distance_m):
    # distance from the camera to the threshold centre, along the ground
    d = np.hypot(result.frames.p_runway_m[:, 0], result.frames.p_runway_m[:, 1])
    return int(np.argmin(np.abs(d - distance_m)))


def _frame_at_height(result, height_m):
    dh = -result.frames.p_runway_m[:, 2]
    return int(np.nonzero(dh <= height_m)[0][0])


@pytest.mark.slow
@pytest.mark.parametrize("msaa", [4, 0])
def test_rendered_runway_corners_match_labels_within_half_a_pixel(flown, msaa):
    result, labels = flown
    frames = {"5 km": _frame_at_distance(result, 5000.0), "1 km": _frame_at_distance(result, 1000.0),
              "100 ft": _frame_at_height(result, 100.0 * FT_TO_M)}
    # the image is formed by the camera as mounted (with its calibration error), as in a dataset
    camera = result.camera_true
    s = result.frames
    R_cr = batch_R_camera_from_runway(s.roll_rad, s.pitch_rad, s.dpsi_rad, camera.mount_rpy_rad)
    errors = {}
    with FrameRenderer(SceneParams.flat(msaa_samples=msaa), camera, result.scenario.runway) as renderer:
        for name, i in frames.items():
            label_uv = np.array([[labels[f"{c}_u_px"][i], labels[f"{c}_v_px"][i]]
                                 for c in ("near_left", "near_right", "far_left", "far_right")])
            visible = [labels[f"{c}_visible"][i] for c in ("near_left", "near_right", "far_left", "far_right")]
            assert all(v == 1 for v in visible), f"{name}: all four corners must be in the image"
            rgb = renderer.render(s.p_runway_m[i], R_cr[i])
            measured = extract_runway_corners(rgb, label_uv)
            errors[name] = np.abs(measured - label_uv).max()
    assert max(errors.values()) < 0.5, errors
    if msaa:
        # anti-aliased edges and long edges at 1 km and 100 ft: expect far better
        assert errors["1 km"] < 0.2 and errors["100 ft"] < 0.2, errors
