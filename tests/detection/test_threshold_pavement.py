"""Issue 11 item 4: a transverse line inside the pavement is not the threshold.

Two causes of gross threshold errors in the robustness study over whole approaches:

- a patch of darker concrete has the grass's grey level (patched concrete, 1.25-1.07 km: the
  threshold kept on a patch's far edge 9 px inside the runway, the ground "beginning" in grey
  levels right there): the chroma tells the grey patch from the green grass
  (:func:`visland.detection.threshold_marking.ground_begins` with ``colour``);
- a displaced threshold's bar far out is a line a fraction of a pixel wide that single frames see
  now and then: once seen, a threshold placed where the pavement begins is withheld over the
  sequence (:class:`visland.detection.DetectionSequence`, ``marking_memory_s``).

The frames are ray cast (:mod:`tests.helpers.raycast_airport`, not visland's renderer) and the
truth is the closed-form projection of runway-frame points.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import numpy as np
import pytest

from tests.helpers.detection_frames import airport_frame
from tests.helpers.raycast_airport import PaintedAirport
from visland.camera import CameraModel
from visland.detection import DetectionResult, DetectionSequence, DetectorParams
from visland.detection.horizon import horizon_frame
from visland.detection.refine import PixelLine
from visland.detection.threshold_marking import ground_begins
from visland.features import batch_R_camera_from_runway

GRASS_GREY = 105.0


@dataclass(frozen=True)
class _PatchedAirport(PaintedAirport):
    """The painted airport with a patch across the runway from ``patch_m[0]`` to ``patch_m[1]``
    metres past the threshold, of grey level ``patch_grey``."""

    patch_m: tuple = (40.0, 150.0)
    patch_grey: float = GRASS_GREY

    def rectangles(self):
        rects, marks = super().rectangles()
        x0, x1 = self.patch_m
        marks.append((0.5 * (x0 + x1), 0.0, 0.5 * (x1 - x0), self.runway_width_m / 2.0, 0.0, self.patch_grey))
        return rects, marks


@functools.lru_cache(maxsize=2)
def _patched_frames(distance_m: float):
    """``(grey, colour, state, labels, camera)``: the patched airport's frame in grey levels (the
    patch at the grass's level) and in colour (the grass green: its green channel 40 levels above
    the red and blue ones; the runway, its patch and its markings grey)."""
    camera = CameraModel.default(384)
    scene = _PatchedAirport(seed=4, grass_grey=GRASS_GREY, taxiway_offset_m=None, parallel_road_offset_m=None,
                            crossing_road=False)
    grey, state, labels = airport_frame("thesis-3", distance_m, camera, scene)
    green, _, _ = airport_frame("thesis-3", distance_m, camera, replace(scene, grass_grey=GRASS_GREY + 40.0))
    colour = np.stack([grey, green, grey], axis=-1)
    return grey, colour, state, labels, camera


def _depth_of(horizon, camera, state, x_m: float) -> float:
    """Depth below the horizon (px) of the centre line's point ``x_m`` metres past the threshold."""
    R = batch_R_camera_from_runway(state.roll_rad, state.pitch_rad, state.dpsi_rad, camera.mount_rpy_rad)[0]
    uv, _ = camera.project(R @ (np.array([x_m, 0.0, 0.0]) - state.p_runway_m[0]))
    return float(horizon.to_sd(uv)[1])


def test_a_patch_at_the_grass_grey_level_is_not_where_the_ground_begins():
    grey, colour, state, labels, camera = _patched_frames(500.0)
    horizon = horizon_frame(camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    corners = labels.corners_uv[0]
    left = PixelLine(corners[0], (corners[2] - corners[0]) / np.linalg.norm(corners[2] - corners[0]))
    right = PixelLine(corners[1], (corners[3] - corners[1]) / np.linalg.norm(corners[3] - corners[1]))
    far, near = horizon.to_sd(corners[2]), horizon.to_sd(corners[0])         # the left edge meets the horizon at V1
    s0 = float(far[0] - (near[0] - far[0]) * far[1] / (near[1] - far[1]))
    d_threshold = _depth_of(horizon, camera, state, 0.0)
    d_patch_end = _depth_of(horizon, camera, state, 150.0)        # the patch's far edge: the step taken
    assert d_threshold - d_patch_end > 6.0, (d_threshold, d_patch_end)
    search_to = d_threshold + 20.0
    # grey levels: the patch looks like grass, the ground "begins" at the patch's edge
    in_grey = ground_begins(grey, horizon, s0, left, right, d_patch_end, search_to, surface_level=78.0, min_step=8.0)
    assert in_grey is not None and in_grey[0] < d_patch_end + 3.0, (in_grey, d_patch_end, d_threshold)
    # the step is signed as the transverse line's, the pavement's level less the ground's: the
    # asphalt's 78 against the brighter grass's 105 (it was unsigned, and a threshold moved to
    # where the ground begins beside snow was searched for markings as beside a darker ground)
    assert -40.0 < in_grey[1] < -10.0, in_grey
    # with the colour, the pavement runs on to the threshold
    found = ground_begins(grey, horizon, s0, left, right, d_patch_end, search_to, surface_level=78.0, min_step=8.0,
                          colour=colour)
    assert found is not None
    assert abs(found[0] - d_threshold) < 1.0, (found, d_threshold, d_patch_end)
    # searched short of the threshold, the pavement runs on: said so (the caller searches again
    # farther, then withholds), not "cannot tell" (concrete on dry grass at 1.5 km: the step at
    # the touchdown zone's rubber was kept, 16 px short, the ground beginning 0.3 px too late)
    short = ground_begins(grey, horizon, s0, left, right, d_patch_end, d_threshold - 2.0, surface_level=78.0,
                          min_step=8.0, colour=colour)
    assert short is not None and math.isinf(short[0]), short


def test_a_patch_inside_the_runway_does_not_move_the_detected_threshold():
    """The whole detector on the colour frame: the near corners on the threshold (were 9.3 px off,
    on the patch's far edge)."""
    from visland.detection import detect_runway
    grey, colour, state, labels, camera = _patched_frames(500.0)
    result = detect_runway(colour, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    assert result.found and result.corners_found[:2].all(), result.reason
    near = np.linalg.norm(result.corners_uv[:2] - labels.corners_uv[0, :2], axis=1)
    assert near.max() < 1.5, (near, result.reason)


def _found(width_px: float, method: str, marking_widths: float = math.nan) -> DetectionResult:
    """A found result whose threshold is ``width_px`` wide, placed by ``method`` (no threshold
    corners for ``method`` "")."""
    corners = np.array([[500.0 - width_px / 2, 600.0], [500.0 + width_px / 2, 600.0], [495.0, 400.0], [505.0, 400.0]])
    found = np.array([bool(method)] * 2 + [True] * 2)
    return DetectionResult(found=True, reason="", confidence=0.9, corners_uv=np.where(found[:, None], corners, np.nan),
                           corners_found=found, threshold_line=(0.1, 1.5) if method else (math.nan, math.nan),
                           mode="tracking", threshold_method=method, pavement_marking_widths=marking_widths)


def test_the_pavement_start_is_withheld_once_a_marking_was_seen_twice_inside_the_pavement(monkeypatch):
    """Far out a displaced threshold's bar is seen in one frame of three; the others place the
    threshold where the pavement begins (9-10 px before it at 1024 px). Once two frames within
    ``marking_memory_s`` saw the marking the same number of widths in, those are withheld; a
    frame that places the threshold on the marking keeps it; a single sighting (the threshold's
    own stripes behind ground taken for pavement) or none leaves the pavement's start, once a
    threshold is followed (three frames placed it before)."""
    import visland.detection.sequence as seq_module
    frames = iter([_found(20.0, "chroma"), _found(20.0, "chroma"), _found(20.0, "chroma"),   # a track
                   _found(20.0, "chroma"),                            # nothing seen: kept
                   _found(20.0, "", marking_widths=7.2),              # a marking seen, not placed (withheld)
                   _found(20.2, "chroma"),                            # seen once: kept
                   _found(20.4, "", marking_widths=6.9),              # seen again, the same place
                   _found(20.6, "chroma"),                            # the pavement's start: withheld
                   _found(18.5, "marking-bar", marking_widths=7.0),   # placed on the bar: kept
                   _found(21.0, "ground-exit"),                       # the pavement's start: withheld
                   _found(19.0, "", marking_widths=1.1),              # another marking, elsewhere
                   _found(21.5, "chroma")])                           # the sightings are old: kept
    monkeypatch.setattr(seq_module, "detect_runway", lambda *a, **k: next(frames))
    camera = CameraModel.default(1024)
    params = replace(DetectorParams(), marking_memory_s=1.0, new_track_frames=1)     # the first frame reported
    sequence = DetectionSequence(camera, params)
    times = [-0.6, -0.4, -0.2, 0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.2, 2.5, 2.7]
    kept = [bool(sequence(np.zeros((8, 8), np.uint8), 0.0, 0.0, t).corners_found[:2].all()) for t in times]
    assert kept == [True, True, True, True, False, True, False, False, True, False, False, True]


def test_a_single_sighting_withholds_the_pavement_start_while_no_threshold_is_followed(monkeypatch):
    """The robustness study's displaced threshold (1024 px, 3.7 km): the acquisition frame saw
    the bar 7.8 runway widths inside the pavement and withheld its threshold; the next frame did
    not see the bar and placed the threshold where the pavement begins, 8.8 px before the true
    one. With no threshold followed yet, that one sighting withholds it in the next frame only (a
    withheld threshold does not enter the track: a spurious sighting in a noisy frame would
    otherwise withhold every frame for marking_memory_s)."""
    import visland.detection.sequence as seq_module
    frames = iter([_found(20.0, "", marking_widths=7.8),              # acquisition: the bar seen once
                   _found(20.0, "chroma"),                            # the pavement's start: withheld
                   _found(20.0, "chroma"),                            # the sighting 2 frames old: kept
                   _found(20.0, "marking-bar", marking_widths=7.5),   # on the bar: kept
                   _found(20.1, "marking-bar", marking_widths=7.4),
                   _found(20.2, "marking-bar", marking_widths=7.6),
                   _found(20.3, "chroma")])                           # sightings agree: withheld
    monkeypatch.setattr(seq_module, "detect_runway", lambda *a, **k: next(frames))
    sequence = DetectionSequence(CameraModel.default(1024), DetectorParams(new_track_frames=1))
    results = [sequence(np.zeros((8, 8), np.uint8), 0.0, 0.0, t) for t in (0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.2)]
    kept = [bool(r.corners_found[:2].all()) for r in results]
    assert kept == [False, False, True, True, True, True, False]
    assert all(r.found for r in results)
    assert "no threshold is followed yet" in results[1].reason


def test_with_a_threshold_followed_one_sighting_leaves_the_pavement_start(monkeypatch):
    """Three thresholds placed (a track), then one sighting of a marking inside the pavement
    (the threshold's own stripes behind a band of ground taken for pavement): the pavement's
    start placed next is kept."""
    import visland.detection.sequence as seq_module
    frames = iter([_found(20.0, "chroma"), _found(20.1, "chroma"), _found(20.2, "chroma"),
                   _found(20.3, "", marking_widths=2.5),
                   _found(20.4, "chroma")])
    monkeypatch.setattr(seq_module, "detect_runway", lambda *a, **k: next(frames))
    sequence = DetectionSequence(CameraModel.default(1024), DetectorParams(new_track_frames=1))
    results = [sequence(np.zeros((8, 8), np.uint8), 0.0, 0.0, t) for t in (0.0, 0.2, 0.4, 0.6, 0.8)]
    assert [bool(r.corners_found[:2].all()) for r in results] == [True, True, True, False, True]


@pytest.mark.slow
def test_a_threshold_on_its_stripes_start_is_withheld_where_the_pavement_before_them_is_unseen(monkeypatch):
    """'concrete, sand, mono' of the robustness study (visland's renderer, 1024 px, frames 244-253,
    190 to 62 m): the concrete between the threshold and its stripes is as light as the sand, and
    the threshold was placed where the stripes start, 16-54 px beyond the true one, reported found
    (frames 249 and 251-253). :func:`threshold_marking.starts_on_its_stripes` sees the band before
    the stripes hold the stripes themselves, their gaps at the sand's level: no near corner is now
    reported more than 5 px off, and with the check off one is."""
    import visland.detection.detector as detector
    from tests.helpers.study_frames import study_frames
    frames, camera = study_frames({"surface": "concrete", "surroundings": "sand", "monochrome": True},
                                  (3000.0, 45.0), list(range(244, 254)), size=1024)

    def worst_near():
        sequence = DetectionSequence(camera)
        worst = 0.0
        for rgb, state, labels, t_s in frames:
            result = sequence(rgb, float(state.roll_rad[0]), float(state.pitch_rad[0]), t_s)
            if result.found and result.corners_found[:2].all():
                worst = max(worst, float(np.linalg.norm(result.corners_uv[:2] - labels.corners_uv[0, :2],
                                                        axis=1).max()))
        return worst

    assert worst_near() < 5.0
    monkeypatch.setattr(detector, "starts_on_its_stripes", lambda *args, **kwargs: False)
    assert worst_near() > 10.0
