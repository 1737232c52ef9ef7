"""detect_runway on frames drawn by an independent method (ray casting a painted airport,
``raycast_airport``), against exact labels from the camera model and the flown trajectory."""
import math

import cv2
import numpy as np
import pytest

from tests.helpers.detection_frames import colour_frame, edge_error_px, frame
from tests.helpers.profiles import area_sampled_steps
from visland.contracts import MEASUREMENT_COLUMNS, read_measurements, write_csv
from visland.detection import DetectorParams, detect_runway

SIZE = 768
CASES = [
    # scenario, metres before the threshold, bright concrete runway (else dark asphalt)
    ("thesis-1", 1500.0, False),
    ("thesis-1", 350.0, False),
    ("thesis-7", 1200.0, False),     # heading 15 deg off the runway, turning back
    ("thesis-4", 1500.0, True),      # 400 m beside the centre line at the start
    ("thesis-8", 600.0, True),
]


@pytest.mark.slow
@pytest.mark.parametrize("name, distance, concrete", CASES)
def test_edges_corners_and_heading_match_the_labels(name, distance, concrete):
    image, camera, state, labels = frame(name, distance, size=SIZE, concrete=concrete)
    result = detect_runway(image, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    assert result.found, result.reason
    assert result.mode == "acquisition"
    for side in ("left", "right"):
        assert edge_error_px(camera, labels, result, side) < 1.0
    near = np.linalg.norm(result.corners_uv[:2] - labels.corners_uv[0, :2], axis=1)
    assert result.corners_found[:2].all() and near.max() < 2.5
    assert abs(math.degrees(result.dpsi_rad - state.dpsi_rad[0])) < 0.1
    assert abs(result.dF_px - labels.dF_px[0]) < 2.0
    assert 0.0 < result.confidence <= 1.0


@pytest.mark.slow
def test_tracking_from_the_previous_frame():
    image0, camera, state0, _ = frame("thesis-1", 800.0, size=SIZE)
    image1, _, state1, labels1 = frame("thesis-1", 800.0, frame_offset=1, size=SIZE)
    first = detect_runway(image0, camera, float(state0.roll_rad[0]), float(state0.pitch_rad[0]))
    second = detect_runway(image1, camera, float(state1.roll_rad[0]), float(state1.pitch_rad[0]), previous=first)
    assert second.found and second.mode == "tracking"
    assert second.roi != (0, 0, camera.width, camera.height)
    for side in ("left", "right"):
        assert edge_error_px(camera, labels1, second, side) < 1.0


@pytest.mark.slow
def test_the_same_detector_serves_every_image_size():
    """Parameters are given for 2048 px frames and rescaled: a 512 px frame works with defaults."""
    image, camera, state, labels = frame("thesis-8", 600.0, size=512, concrete=True)
    result = detect_runway(image, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]),
                           params=DetectorParams())
    assert result.found, result.reason
    for side in ("left", "right"):
        assert edge_error_px(camera, labels, result, side) < 1.0


@pytest.mark.slow
def test_centre_line_lies_midway():
    image, camera, state, labels = frame("thesis-1", 350.0, size=SIZE)
    result = detect_runway(image, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    assert result.found and result.lines_found["center"]
    rho, theta = result.lines["center"]
    true_rho, true_theta = labels.lines["center"][0][0], labels.lines["center"][1][0]
    assert abs(theta - true_theta) < math.radians(0.5)
    # the labelled centre line's points (midpoints of the corner pairs) lie on the detected one
    for a, b in ((0, 1), (2, 3)):
        midpoint = 0.5 * (labels.corners_uv[0, a] + labels.corners_uv[0, b])
        if camera.in_image(midpoint):
            assert abs(camera.line_distance_px(rho, theta, midpoint)) < 1.5
    assert abs(rho - true_rho) * camera.fx < 0.5    # in pixels at the image centre; measured 0.02 px


@pytest.mark.slow
def test_measurement_row_round_trips_through_the_contract(tmp_path):
    image, camera, state, _ = frame("thesis-8", 600.0, size=SIZE, concrete=True)
    found = detect_runway(image, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    missing = detect_runway(np.zeros_like(image), camera, 0.0, 0.04)
    rows = [found.to_measurement_row(frame=0, t_s=0.0), missing.to_measurement_row(frame=1, t_s=0.04)]
    assert list(rows[0]) == list(MEASUREMENT_COLUMNS)
    path = tmp_path / "measurements.csv"
    write_csv(path, {c: [r[c] for r in rows] for c in MEASUREMENT_COLUMNS}, MEASUREMENT_COLUMNS)
    table = read_measurements(path)
    assert list(table["found"]) == [1.0, 0.0]
    assert table["source"][0] == "detection"
    assert table["near_left_u_px"][0] == pytest.approx(found.corners_uv[0, 0], abs=1e-6)
    assert math.isnan(table["near_left_u_px"][1]) and table["reason"][1] == missing.reason


@pytest.mark.slow
@pytest.mark.parametrize("name, distance", [("thesis-1", 1500.0), ("thesis-1", 800.0), ("thesis-7", 1200.0)])
def test_colour_places_the_threshold_and_edges_where_grey_levels_cannot(name, distance):
    """Grass with the grey level of the blended stripes: the chroma finds the runway's outline."""
    rgb, camera, state, labels = colour_frame(name, distance, size=SIZE)
    roll, pitch = float(state.roll_rad[0]), float(state.pitch_rad[0])
    errors = {}
    for kind, image in (("colour", rgb), ("grey", cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY))):
        result = detect_runway(image, camera, roll, pitch)
        assert result.found, (kind, result.reason)
        assert result.corners_found[:2].all(), (kind, result.reason)
        errors[kind] = float(np.linalg.norm(result.corners_uv[:2] - labels.corners_uv[0, :2], axis=1).max())
        if kind == "colour":
            for side in ("left", "right"):
                assert edge_error_px(camera, labels, result, side) < 0.3
            assert abs(math.degrees(result.dpsi_rad - state.dpsi_rad[0])) < 0.05
    assert errors["colour"] < 0.4
    # in grey levels the blended stripes have the grass's level, so only their texture (longitudinal
    # stripes alternating with the surface across the runway) tells where the runway starts
    assert errors["grey"] < 1.5


def test_a_centre_line_too_thin_to_see_says_why_it_is_missing():
    # thesis-1 at 4 km on a 512 px frame: the 0.9 m centre stripe (ICAO, 45 m runway) spans
    # fx * 0.9 / 4000 = 0.14 px, a few grey levels at most after blur: the edges are found, the
    # centre line is not, and the measurement row says why (not only that it is missing)
    image, camera, state, _ = frame("thesis-1", 4000.0)
    assert camera.fx * 0.9 / 4000.0 < 0.2
    result = detect_runway(image, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    assert result.found, result.reason
    assert math.isnan(result.lines["center"][0])
    row = result.to_measurement_row(frame=0, t_s=0.0)
    assert "centre line not found (bright stripe: no consistent step along the line" in row["reason"], row["reason"]


def _same_detection(a, b) -> bool:
    """Two results equal in every field but the time taken (NaN equal to NaN)."""
    import dataclasses
    for field in dataclasses.fields(a):
        if field.name == "elapsed_s":
            continue
        x, y = getattr(a, field.name), getattr(b, field.name)
        pairs = [(x[k], y[k]) for k in x] if isinstance(x, dict) else [(x, y)]
        for p, q in pairs:
            try:
                p_values, q_values = np.asarray(p, float), np.asarray(q, float)
            except (TypeError, ValueError):           # text: reasons, notes, the mode
                if p != q:
                    return False
                continue
            if not np.array_equal(p_values, q_values, equal_nan=True):
                return False
    return True


@pytest.mark.parametrize("distance", [2500.0])
def test_the_sky_above_the_horizon_is_never_read(distance, monkeypatch):
    """The grey levels of a colour frame are converted only from SKY_ROWS_READ_PX above the
    ground's margin down (detector._grey_below_horizon): acquisition and then tracking (the
    frame again, from its acquisition) give the same results to the bit as with the whole frame
    converted, and as with the rows above that replaced by noise."""
    from visland.detection import detector
    from visland.detection.horizon import horizon_frame
    from visland.folder import as_grey
    rgb, camera, state, _ = colour_frame("thesis-1", distance, size=SIZE)
    roll, pitch = float(state.roll_rad[0]), float(state.pitch_rad[0])
    horizon = horizon_frame(camera, roll, pitch)
    margin = DetectorParams().scaled_to(camera).ground_margin_px + detector.SKY_ROWS_READ_PX
    top = horizon.ground_bbox(camera.width, camera.height, margin_px=margin)[1]
    assert 20 < top < camera.height // 2
    np.testing.assert_array_equal(detector._grey_below_horizon(rgb, horizon, margin)[top:],
                                  cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)[top:])
    noisy = rgb.copy()
    noisy[:top] = np.random.default_rng(4).integers(0, 256, noisy[:top].shape, dtype=np.uint8)

    def acquired_then_tracked(image):
        first = detect_runway(image, camera, roll, pitch)
        return first, detect_runway(image, camera, roll, pitch, previous=first)

    results = [acquired_then_tracked(rgb), acquired_then_tracked(noisy)]
    monkeypatch.setattr(detector, "_grey_below_horizon", lambda colour, horizon, margin_px: as_grey(colour))
    results.append(acquired_then_tracked(rgb))
    (first, second), others = results[0], results[1:]
    assert first.found and second.found and second.mode == "tracking"
    for other_first, other_second in others:
        assert _same_detection(first, other_first) and _same_detection(second, other_second)


def test_frame_checks_read_the_numbers_numpy_defines():
    """The contrast spread (a histogram of the sampled levels) and the block grid's steps (integer
    sums) are np.percentile's and the masked means' numbers."""
    from visland.detection.detector import _percentile_spread, _sample_rows, block_grid_steps
    rng = np.random.default_rng(9)
    for _ in range(50):
        image = (rng.integers(0, 256, (120, 200)) // int(rng.integers(1, 40))).astype(np.uint8)
        u0, v0 = (int(x) for x in rng.integers(0, 40, 2))
        ground = (u0, v0, int(min(200, u0 + rng.integers(17, 170))), int(min(120, v0 + rng.integers(3, 90))))
        sample = image[ground[1]:ground[3]:4, ground[0]:ground[2]:4]
        assert _percentile_spread(sample, 1.0, 99.0) == float(np.percentile(sample, 99.0) - np.percentile(sample, 1.0))
        levels = image[_sample_rows(ground, 32), ground[0]:ground[2]].astype(np.int16)
        steps = np.abs(np.diff(levels, axis=1))
        across = (np.arange(ground[0], ground[2] - 1) + 1) % 8 == 0
        assert block_grid_steps(image, ground) == (float(steps[:, across].mean()), float(steps[:, ~across].mean()))


def test_a_stripe_seen_on_the_near_part_of_an_edge_only():
    """:func:`detector._seen_near_only`: the step beyond an edge seen regularly by the nearer
    half of the profiles that could resolve it and by hardly any of the farther half is a side
    stripe resolved near the camera only; the same number of steps spread along the edge (texture
    beyond it), or too few, is not."""
    from visland.detection.detector import _seen_near_only
    params = DetectorParams()
    width = np.linspace(40.0, 140.0, 24)              # far to near, px
    median = 0.037                                     # resolved (>= 2.5 px) where width >= 68 px
    resolved = np.flatnonzero(width * median >= params.staircase_min_px)
    assert len(resolved) == 17
    rng = np.random.default_rng(5)

    def ratios_at(indices):
        ratios = np.full(24, np.nan)
        ratios[indices] = median * (1.0 + rng.uniform(-0.05, 0.05, len(indices)))
        return ratios

    assert _seen_near_only(ratios_at(resolved[-6:]), width, median, params)
    assert _seen_near_only(ratios_at(np.r_[resolved[2], resolved[-5:]]), width, median, params)
    assert not _seen_near_only(ratios_at(resolved[::3]), width, median, params)          # all along
    assert not _seen_near_only(ratios_at(resolved[-3:]), width, median, params)          # too few
    spread = ratios_at(resolved[-6:])
    spread[resolved[-6:]] = median * np.array([0.7, 1.3, 0.8, 1.25, 0.75, 1.2])          # not paint-regular
    assert not _seen_near_only(spread, width, median, params)


@pytest.mark.parametrize("stripe_px", [2.5, 3.0, 4.0, 5.0])
def test_a_stripe_blurred_into_the_step_onto_it_is_seen_as_a_shoulder(stripe_px):
    """:func:`detector._stripe_shoulder`: asphalt (72), a side stripe ``stripe_px`` wide (196),
    snow (232), area-sampled and blurred (0.4 to 0.9 px): the stripe's end, the runway's edge, is
    found within 0.35 px; a plain step of the same height, blurred by 0.3 to 1.2 px at four
    sub-pixel phases, shows none."""
    from visland.detection.detector import _stripe_shoulder
    params = DetectorParams()
    offsets = np.arange(-8.0, 9.0, 0.5)
    reach = np.array([0.04 * 140.0 + params.edge_blur_px])

    def shoulder(profile):
        slope = np.gradient(profile, 0.5)
        column = np.array([int(np.argmax(np.where(np.abs(offsets) <= params.edge_blur_px, slope, -np.inf)))])
        central = np.zeros((1, len(profile)))                 # as the detector reads it: 0 at the ends
        central[0, 1:-1] = (profile[2:] - profile[:-2]) / 1.0
        return _stripe_shoulder(profile[None, :], central, offsets, column, np.array([slope[column[0]]]), reach,
                                params)[0]

    for blur in (0.4, 0.6, 0.9):
        found = shoulder(area_sampled_steps(offsets, (72.0, 196.0, 232.0), (0.0, stripe_px), blur))
        assert abs(found - stripe_px) < 0.35, (blur, found)
    for blur in (0.3, 0.6, 0.9, 1.2):
        for phase in (0.0, 0.125, 0.25, 0.375):
            assert np.isnan(shoulder(area_sampled_steps(offsets, (72.0, 232.0), (phase,), blur))), (blur, phase)


def test_row_nanmedian_is_numpys_to_the_last_bit():
    """:func:`pencil.row_nanmedian` gives ``np.nanmedian(values, axis=1)`` exactly, rows all NaN
    included (NaN), on random rows of every length with ties and gaps."""
    import warnings
    from visland.detection.pencil import row_nanmedian
    rng = np.random.default_rng(11)
    for _ in range(500):
        values = rng.normal(100.0, 20.0, (int(rng.integers(1, 30)), int(rng.integers(1, 40)))).round(int(rng.integers(0, 3)))
        values[rng.random(values.shape) < rng.random()] = np.nan
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            expected = np.nanmedian(values, axis=1)
        assert np.array_equal(row_nanmedian(values), expected, equal_nan=True)
