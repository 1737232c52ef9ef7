"""Detection over a sequence of frames: the last good detection predicts the next one.

:func:`~visland.detection.detect_runway` takes the previous result as its prior (tracking in
a region of interest). Over a sequence two things go wrong without memory:

- one frame where the runway is not found (a transient) drops the prior, and the next search
  covers the whole frame, where a field boundary or a taxiway can win;
- a re-acquisition after such a loss is not checked against what was just seen.

:class:`DetectionSequence` keeps the last good detection as the prior for
``DetectorParams.hold_s`` after a miss, and refuses a detection that did not come from
tracking when its edges turned, or its vanishing point moved, more than the runway can between
the two frames (``max_edge_turn_*``, ``max_vp_jump_*``: the pair must be consistent over time,
issue item 2). A refused detection is reported not found, with the reason. Threshold corners
that jump since the prior (the touchdown-zone bars taken for the threshold for one frame) are
dropped from an otherwise good detection (``max_threshold_jump_*``). The threshold is also
followed as a track: at a steady ground speed the reciprocal of its width in pixels,
``1 / w = x / (f W)``, falls linearly with time whatever the height, so the widths of the last
``threshold_track_s`` seconds predict the next one (their mean where their scatter has ``1 / w``
rising); a threshold off that prediction (a marking or a pavement joining the runway taken for
it) has its corners withheld, and rejections in a row that agree with each other start the
track afresh once there are at least three of them and as many as the widths the track still
holds in its window (the track's old widths age out of it while the rejections come: a track
that was the wrong object is replaced in about half the window). Flying toward the threshold its
width only grows: where the track holds fewer than three widths, one narrower than the last
threshold accepted in the last ``threshold_shrink_memory_s`` seconds (less the same tolerance) is
withheld (below 100 ft, once the threshold had left the frame below, the touchdown zone's bars
were taken for it; with a track, its prediction does this and more). So does the runway end's:
one narrower than the median of the last ends reported in the track within the same seconds
(less the same tolerance) is withheld (a step in the haze near the horizon taken for it at dusk).
After ``hold_s`` without a good detection the next search starts afresh.

A threshold marking seen inside the pavement (a displaced threshold's bar, the stripes after a
blast pad: :func:`visland.detection.threshold_marking.threshold_marking`) is fixed on the ground:
once two frames within ``marking_memory_s`` saw one at the same place (runway widths inside the
pavement within ``marking_memory_agreement`` of each other), a threshold placed where the
pavement begins is the pavement's start, not the threshold, and its corners are withheld (a
marking fewer than ``marking_memory_min_widths`` in can be the threshold's own, seen behind a
band of ground taken for pavement, and is not remembered). While no threshold is followed yet
(fewer than three widths in its track), one sighting in the last good frame is enough for the
next one. Far out the marking is a
line a fraction of a pixel wide that single frames see only now and then (the robustness
study's displaced threshold from 3.7 to 2.9 km: seen in one frame of three, the others placed
the threshold at the pavement's start, 9-10 px before the true one).

A re-acquisition after a loss longer than ``hold_s`` is checked against where the runway was
(for ``identity_memory_s``): its centre line's lateral offset over height and its width over
height, read off the edges in the horizon frame, must be close to the remembered ones. Every
ground line parallel to the runway shares its vanishing point, so a strip of fields or a taxiway
beside it passes every single-frame test, but not this one.

A strip followed from its acquisition is reported only while it is confirmed as the runway
approached (``unconfirmed_max_lateral_heights``): its threshold carried a threshold marking in
one of its frames (``DetectionResult.threshold_marked``; taxiways and roads carry none), or, in
the frame itself, its centre line lies within one camera height of the aircraft (``k_C = Y /
h``; half a height when its confidence is below ``place_min_confidence``), or the aircraft is
over it. Otherwise it is followed (the next frame's prior) but reported not found, saying why,
and each frame is also searched afresh: a strip found there with a threshold marking replaces
it (one confirmed by its place alone does not: the aircraft can start over a taxiway), and
while the strip followed is doubtful, so does a convincing one (``replacement_min_confidence``)
confirmed by its place. A parallel taxiway beside a runway whose own edges hardly show (the
ray-cast airport's rubber-darkened concrete) was followed and reported from 2.5 km to 100 ft:
within a height at first, at confidence 0.3-0.56, then several heights out. In fog a
parallel taxiway 1.33 heights out was acquired where the runway's own edges gave no segment,
and reported for 1.5 km (the robustness study's overcast frames at 2048 px); the price is the
first frames of an approach that starts more than a height off the runway's centre line, far
enough that its threshold stripes are not seen (an unmarked runway until the aircraft is within
a height: thesis-3's first 4 s).

An approach that starts over a parallel taxiway confirms the taxiway by its place (held-out
draw 14). A strip confirmed by its place alone is therefore checked against a search of the
whole frame now and then (``place_recheck_s``, backing off to ``place_recheck_max_s``): another
strip found there with a threshold marking makes it doubtful (not reported: "which is the runway
approached is not known yet") and, found again by the next search (every frame's while it
contests), replaces it.

A threshold marking read once on a doubtful strip farther than
``single_marking_max_lateral_heights`` (1.5) beside the aircraft confirms it only when read
again within ``weak_marking_window_s``: on held-out draw 4 (a concrete runway lost on sand at
dusk) the sand's blur at a taxiway's start, 2.04 heights out, was read as paint in one frame.

A strip that has lain more than ``diverging_min_lateral_heights`` (1.2) beside the aircraft for
the last ``diverging_window_s`` (4 s) of its track while its offset grew (``diverging_min_growth``,
5 %) is followed but not reported, marked or not: an approach converges on its runway's centre
line, and the aircraft is moving away from that strip (:meth:`DetectionSequence._moving_away`;
draw 4 again: the same taxiway, confirmed from 2.31 km by a band inside it read as a displaced
threshold's marking, its offset growing from 1.31 to 3.0 heights).

A new track (no good detection within ``hold_s``) is followed from its first frame but reported
from its ``new_track_frames``-th (2): a strip found in one frame only can be a road or a taxiway
that the next frame refuses, and then it was a confident wrong answer. On the independent
ray-cast airport through a 62 deg lens (1280x720, 1 Hz), a road 7 m wide, 157 m beside an
aircraft offset toward it and banked 23 deg at 4.4 km, was acquired with confidence 0.74 (the
runway's own edges gave no segment in the haze) and refused in the next frame. A new track that
matches something seen before is reported at once: a re-acquisition where the remembered runway
was (``identity_*``), a strip replacing an unconfirmed one after two frames, a runway found by
tracking from an estimator's prediction. The price is one frame per acquisition.

Without attitude data (``roll_rad`` and ``pitch_rad`` None: footage with no telemetry), the
horizon is read off each frame (:func:`visland.detection.attitude.attitude_from_image`: the
sky-ground step), then moved through the runway's vanishing point once the runway is found (the
edges' crossing, which lies on the true horizon); that correction is carried to the next frames.
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import NamedTuple

import numpy as np

from visland.camera import CameraModel
from visland.detection.attitude import ImageAttitude, attitude_from_image
from visland.detection.detector import beside_the_approach, check_frame, detect_in_scene_frame, detect_runway
from visland.detection.horizon import horizon_frame
from visland.detection.params import DetectorParams
from visland.detection.result import DetectionResult, not_found
from visland.folder import as_grey, ignored_pixels, scene_frame

__all__ = ["DetectionSequence"]

#: One-sigma error of the horizon read off the sky-ground step before the runway's vanishing
#: point places it (degrees; measured 0.00-0.23 deg on the ray-cast airport, hazes 6-20 km).
IMAGE_HORIZON_SIGMA_DEG = 0.15

#: A runway end is compared with the median width of this many of the last ends reported
#: (:meth:`DetectionSequence._follow_end`).
END_TRACK_WIDTHS = 5


class _Sighting(NamedTuple):
    """Another strip found by a search of the whole frame while one is followed
    (:meth:`DetectionSequence._look_for_confirmed`): when, where (``k_centre = Y / h``), and
    whether it showed a threshold marking."""
    t_s: float
    k_centre: float
    marked: bool


def _not_found_as(result: DetectionResult, reason: str) -> DetectionResult:
    """``result`` turned into a row not found, saying ``reason``, with the frame's attitude, mode,
    size and time kept."""
    return not_found(reason, roll_rad=result.roll_rad, pitch_rad=result.pitch_rad, mode=result.mode,
                     image_size=result.image_size, elapsed_s=result.elapsed_s)


def _refused(result: DetectionResult, why: str) -> DetectionResult:
    """``result`` refused by a sequence check: not found, saying ``"refused: " + why``."""
    return _not_found_as(result, f"refused: {why}")


class DetectionSequence:
    """Stateful frame-after-frame detection (see module docstring).

    Parameters
    ----------
    camera : the camera of every frame.
    params : detector parameters (``hold_s`` and the consistency limits are used here).
    """

    def __init__(self, camera: CameraModel, params: DetectorParams | None = None):
        if not isinstance(camera, CameraModel):
            raise ValueError(f"camera must be a CameraModel, got {type(camera).__name__}")
        params = DetectorParams() if params is None else params
        if not isinstance(params, DetectorParams):
            raise ValueError(f"params must be DetectorParams, got {type(params).__name__}")
        self.camera = camera
        self.params = params.scaled_to(camera)
        self.last_good: DetectionResult | None = None
        self.t_good_s: float | None = None
        self.good_geometry: tuple | None = None                   # _ground_geometry(last_good)
        self.threshold_track: list[tuple[float, float]] = []      # (t_s, width_px) accepted
        self.threshold_rejected: list[tuple[float, float]] = []   # rejected in a row
        self.last_threshold: tuple[float, float] | None = None     # (t_s, width_px) last accepted
        self.end_track: list[tuple[float, float]] = []            # (t_s, width_px) runway ends reported
        self.image_attitude: ImageAttitude | None = None          # without telemetry: the last frame's
        self.identity: tuple | None = None                        # (t_s, k_centre, width_ratio) last accepted
        self.identity_history: list[tuple[float, float]] = []    # (t_s, k_centre) accepted, identity_rate_window_s
        self.recent: list[tuple[float, DetectionResult]] = []     # found, within static_window_s
        self.markings_seen: list[tuple[float, float]] = []        # (t_s, widths): markings inside the pavement
        self.confirmed = False                                    # the strip followed is the runway approached
        self.marked = False                                       # ... shown by a marking in its track
        self.replacement: _Sighting | None = None                 # another strip found afresh
        self.track_frames = 0                                     # frames found in the track followed
        self.t_place_check_s: float | None = None                 # last search afresh of a track confirmed by place
        self.place_interval_s: float | None = None                # ... and the time to the next one
        self.marking_reads: list[float] = []                      # t_s: markings read on a doubtful strip far out
        self.place_history: list[tuple[float, float]] = []       # (t_s, heights): the track's place, diverging_window_s

    def reset(self) -> None:
        """Forget the last good detection and the threshold's track (the next frame is searched afresh)."""
        self.last_good = None
        self.t_good_s = None
        self.good_geometry = None
        self.threshold_track = []
        self.threshold_rejected = []
        self.last_threshold = None
        self.end_track = []
        self.image_attitude = None
        self.identity = None
        self.identity_history = []
        self.recent = []
        self.markings_seen = []
        self.confirmed = False
        self.marked = False
        self.replacement = None
        self.track_frames = 0
        self.t_place_check_s = None
        self.place_interval_s = None
        self.marking_reads = []
        self.place_history = []

    def __call__(self, image, roll_rad: float | None, pitch_rad: float | None, t_s: float,
                 predicted: DetectionResult | None = None) -> DetectionResult:
        """Detect the runway in the frame at ``t_s`` (seconds, increasing).

        ``roll_rad``, ``pitch_rad``: the inertial attitude at the frame's time, or both None to
        read the horizon off the frame (module docstring). ``predicted``: where something else
        (an estimator, :func:`visland.detection.predicted.prior_from_prediction`) expects the runway
        in this frame; when it is a found result the search window is placed by it instead of by the
        last good detection. The checks over time still compare with the last good detection.
        """
        prior = self.last_good
        dt = math.inf if self.t_good_s is None else float(t_s) - self.t_good_s
        if prior is not None and not 0.0 < dt <= self.params.hold_s:
            prior = None
        window = predicted if predicted is not None and predicted.found else prior
        inertial = roll_rad is not None and pitch_rad is not None
        if not inertial:
            result = self._detect_without_attitude(image, window)
            roll_rad, pitch_rad = result.roll_rad, result.pitch_rad
        else:
            result = detect_runway(image, self.camera, roll_rad, pitch_rad, params=self.params, previous=window)
        if result.found and prior is not None and result.mode != "tracking":
            why = self._inconsistency(result, prior, dt)
            if why:
                result = not_found(f"refused: {why} since the detection {dt:.2f} s earlier ({result.mode} "
                                   f"picked another object)", roll_rad=float(roll_rad), pitch_rad=float(pitch_rad),
                                   mode=result.mode, image_size=result.image_size, elapsed_s=result.elapsed_s)
        # a new track that matches a strip seen before, not a single frame's: found where the
        # prediction put it (an estimator's, which follows the runway), ...
        seen_before = window is not None and window is predicted and result.found and result.mode == "tracking"
        # a strip confirmed by its place alone (measured: a strip whose place is not is not held
        # back either) is checked against the whole frame now and then
        recheck = (self.confirmed and not self.marked and self.good_geometry is not None
                   and self._recheck_due(float(t_s)))
        if prior is not None and (not self.confirmed or recheck) and inertial:
            result, prior = self._look_for_confirmed(result, prior, image, roll_rad, pitch_rad, dt, float(t_s),
                                                     place_only=self.confirmed)
            seen_before = seen_before or prior is None          # ... replacing the track, found the frame before too
        if result.found:
            result = self._check_moves_with_scene(result, float(t_s), inertial)
        if result.found and prior is None and self.identity is not None:
            result, where_it_was = self._check_identity(result, image, roll_rad, pitch_rad, float(t_s))
            seen_before = seen_before or where_it_was           # ... or where the runway was, remembered
        if result.found and prior is not None and inertial:
            result = self._check_same_object(result, dt)
        if result.found:
            result = self._check_pavement_start(result, float(t_s))
        if result.found and prior is not None:
            result = self._check_threshold(result, prior, dt)
        if result.found:
            result = self._follow_threshold(result, float(t_s))
        if result.found and prior is None:
            self.marked = False                                   # a new track: confirmed by its own frames
            self.t_place_check_s = self.place_interval_s = None
            self.marking_reads = []
            self.place_history = []
        geometry = offset = None
        if result.found:
            geometry = _ground_geometry(result, self.camera)        # (the strip's place, once a frame)
            offset = _offset_of(geometry)
            # a marking seen confirms the track for good (on a doubtful strip far beside the
            # approach, read in two frames); its place alone, only the frame it holds in (a
            # parallel taxiway within a height at 2.4 km is several heights out at 1 km)
            self.marked = self.marked or (result.shows_runway_marking
                                          and self._marking_confirms(result, offset, float(t_s)))
            self.confirmed = self.marked or _confirmed_by_place(result, offset, self.params)
        moving_away = None
        if result.found:
            self.track_frames = 1 if prior is None else self.track_frames + 1
            if seen_before:
                self.track_frames = max(self.track_frames, self.params.new_track_frames)
            self.last_good = result
            self.t_good_s = float(t_s)
            self.good_geometry = geometry
            moving_away = self._moving_away(geometry, float(t_s))
            if moving_away:
                self.confirmed = False                            # (the whole frame searched afresh)
            # only a runway followed from one frame to the next is remembered: a single
            # acquisition can be a road or a taxiway, and remembered it would refuse the runway
            # for identity_memory_s (the 62 deg barrel-lens ray-cast approach: a road 340 m beside
            # the runway acquired once at 3.6 km, the runway refused for the next 8 s)
            if geometry is not None and prior is not None and self.confirmed:
                self.identity = (float(t_s),) + geometry
                window = self.params.identity_rate_window_s
                self.identity_history = [(t, k) for t, k in self.identity_history if float(t_s) - t <= window]
                self.identity_history.append((float(t_s), geometry[0]))
        if result.found and moving_away:
            # well beside the aircraft and moving away from its track: not the runway approached,
            # marked or not (a taxiway or a parallel runway beside it)
            return _not_found_as(result, f"not reported: {moving_away}")
        if result.found and not self.confirmed:
            # followed (the next frame's prior) but not reported: a taxiway beside a runway
            # lost in fog passes every other test
            last_read_s = float(t_s) - self.marking_reads[-1] if self.marking_reads else None
            return _not_found_as(result, "not reported: " + _unconfirmed_reason(result, offset, self.params,
                                                                               last_read_s))
        if result.found and not self.marked and self._contested(float(t_s)):
            # confirmed by its place alone while another strip showed a threshold marking: the
            # aircraft can be over a taxiway beside the runway
            return _not_found_as(result, f"not reported: {self._contested_reason(result, float(t_s))}")
        if result.found and self.track_frames < self.params.new_track_frames:
            # followed but not reported yet: a strip found in one frame can be a road or a taxiway
            # (module docstring)
            return _not_found_as(result, f"not reported: frame {self.track_frames} of a new track, reported from "
                                         f"its frame {self.params.new_track_frames} (a strip found in one frame only "
                                         "can be a road or a taxiway)")
        if result.found:
            result = self._follow_end(result, float(t_s), new_track=prior is None)
        return result

    def _look_for_confirmed(self, result: DetectionResult, prior: DetectionResult, image, roll_rad: float,
                            pitch_rad: float, dt: float, t_s: float,
                            place_only: bool = False) -> tuple[DetectionResult, DetectionResult | None]:
        """While the strip followed is not confirmed as the runway (by a threshold marking or
        :func:`_confirmed_by_place`), the whole frame is searched afresh each frame: another strip found there with a threshold marking
        (:attr:`~visland.detection.result.DetectionResult.shows_runway_marking`) in this frame and
        the one before is the runway, and
        replaces the track (``(found, None)``: the frame starts a new one); the same strip found
        so confirms the track. While the strip followed is doubtful (lost in this frame or its
        confidence below ``place_min_confidence``), an unmarked strip found afresh with
        ``replacement_min_confidence`` and confirmed by its place replaces it too: on the
        ray-cast airport with a rubber-darkened runway (1024 px) the parallel taxiway was
        followed at 0.29-0.56 from 2.5 km, single frames found the runway at 0.93-0.96 from
        1.3 km, no threshold marking among them. On the
        robustness study's overcast frames (2048 px) the parallel taxiway acquired in fog at
        2.4 km was followed, not reported, while single frames found the runway from 1.2 km. A
        strip confirmed by its place alone does not replace the track: on 'concrete, sand, mono'
        the aircraft starts over the parallel taxiway (185 m beside the runway, thesis-3 205 m
        out), which the fresh search found, nearer than a height, and took for the runway.

        ``place_only``: the strip followed is confirmed by its place alone (:meth:`_recheck_due`).
        The search afresh is made whatever this frame's place says, and only a strip found there
        with a threshold marking counts: it contests the one followed (:meth:`_contested`) and,
        found again by the next search (the next frame's: every frame is searched while it
        contests), replaces it. A search that finds nothing marked leaves the contest standing
        until ``hold_s`` has passed since the marked strip was seen (single frames miss a runway's
        worn stripes at 3 km), but the next sighting must be followed by another to replace: on
        held-out draw 19 the runway, confirmed by its place, was contested by a strip 1.6 heights
        out read as marked in two searches 1.0 s apart with four between that did not."""
        offset = _lateral_offset(result, self.camera) if result.found and not place_only else None
        if (not place_only and result.found and (_confirmed_by_place(result, offset, self.params) or
                                                 (result.shows_runway_marking and self._marking_at_once(result, offset)))):
            return result, prior
        previous_check_s, self.t_place_check_s = self.t_place_check_s, (t_s if place_only else None)
        if place_only:      # the next check later, unless this one finds a marked strip elsewhere
            self.place_interval_s = (self.params.place_recheck_s if self.place_interval_s is None else
                                     min(2.0 * self.place_interval_s, self.params.place_recheck_max_s))
        fresh = detect_runway(image, self.camera, roll_rad, pitch_rad, params=self.params)
        geometry = _ground_geometry(fresh, self.camera) if fresh.found else None
        fresh_offset = _offset_of(geometry)
        candidate = self.replacement
        if candidate is not None and t_s - candidate.t_s > self.params.hold_s:
            candidate = None
        if place_only and candidate is not None and candidate.t_s != previous_check_s:
            candidate = None    # found by a search before the last one: not in two searches running
        if not place_only:
            self.replacement = None
        weak = not result.found or result.confidence < self.params.place_min_confidence
        convincing = (not place_only and weak and fresh.found
                      and fresh.confidence >= self.params.replacement_min_confidence
                      and (fresh.shows_runway_marking or _confirmed_by_place(fresh, fresh_offset, self.params)))
        if not (fresh.found and (fresh.shows_runway_marking or convincing)):
            return result, prior
        if self.good_geometry is None or not _identity_mismatch(fresh, self.camera, self.good_geometry[0], math.nan,
                                                                dt, self.params):
            if fresh.shows_runway_marking and self._marking_confirms(fresh, fresh_offset, t_s):
                self.confirmed = self.marked = True            # the strip followed, marked
            return result, prior
        # another strip, marked or convincing: it replaces the one followed when the frame
        # before found it too (one frame's marking can be a texture's end read as paint)
        if (candidate is not None and geometry is not None
                and not _identity_mismatch(fresh, self.camera, candidate.k_centre, math.nan, t_s - candidate.t_s,
                                           self.params)):
            self.reset()
            return fresh, None
        if geometry is not None:
            self.replacement = _Sighting(t_s, geometry[0], fresh.shows_runway_marking)
            if place_only:
                self.place_interval_s = self.params.place_recheck_s
        return result, prior

    def _moving_away(self, geometry: tuple[float, float] | None, t_s: float) -> str | None:
        """Why the strip followed, at ``geometry`` (``k_C``, width / height) in this frame, is not
        the runway approached, if it lies more than
        ``diverging_min_lateral_heights`` camera heights beside the aircraft in every frame of
        the last ``diverging_window_s`` of its track and its offset grew over them by at least
        ``diverging_min_growth`` (a straight line fitted to the offsets, its rise over the window
        relative to their mean); None otherwise. This frame's offset is added to the track's
        ``place_history`` (emptied when the place is not measured). An approach converges on its runway's centre
        line, and the offset of a strip beside it, ``Y / h`` at a lateral distance ``Y``, grows as
        the aircraft descends once the aircraft has stopped closing on it: ``(v_Y - k v_h) / h``
        per second, 3 % of it per second at 2.3 km on a 3 deg descent. Held-out draw 4: a
        taxiway beside a runway lost on sand, confirmed by a band inside it read as a displaced
        threshold's marking, reported from 2.31 km to 850 m while its offset grew from 1.31 to
        3.0 heights. The thesis's approaches whose runway moves away at first (thesis-8: 0.84 to
        1.13 heights from 4.7 to 4.2 km) stay within the bound; thesis-3 and thesis-4 start 1.08
        and 1.69 heights out and close in."""
        p = self.params
        if geometry is None:
            self.place_history = []                      # (no horizon: the place is not measured)
            return None
        self.place_history = [(t, k) for t, k in self.place_history if t_s - t <= p.diverging_window_s + 1e-6]
        self.place_history.append((t_s, abs(geometry[0])))
        times = np.array([t for t, _ in self.place_history])
        heights = np.array([k for _, k in self.place_history])
        if len(times) < 3 or times[-1] - times[0] < p.diverging_window_s - 1e-6 or heights.min() <= p.diverging_min_lateral_heights:
            return None
        slope = np.polyfit(times - times[-1], heights, 1)[0]
        growth = slope * (times[-1] - times[0]) / float(np.mean(heights))
        if growth < p.diverging_min_growth:
            return None
        return (f"the strip followed lies {heights[-1]:.2f} camera heights beside the aircraft, more than "
                f"{p.diverging_min_lateral_heights:g} over the last {times[-1] - times[0]:.1f} s, and its offset grew "
                f"by {100.0 * growth:.0f} % over them (from {heights[0]:.2f}): the aircraft is moving away from it, not "
                "approaching it (a taxiway or runway beside the one approached?)")

    def _marking_confirms(self, result: DetectionResult, offset: tuple[float, float] | None, t_s: float) -> bool:
        """Whether the threshold marking ``result`` shows confirms the strip followed as the
        runway approached: at once (:meth:`_marking_at_once`), or, on a doubtful strip far beside
        the approach, read again in another frame within ``weak_marking_window_s`` (held-out
        draw 4: a taxiway 2.04 heights out at confidence 0.49, read "marked" once at 3.45 km on
        the sand's blur at its start, was reported to 850 m, near corners 136-533 px off). A
        reading that does not confirm at once is kept in ``marking_reads``."""
        if self._marking_at_once(result, offset):
            return True
        window = self.params.weak_marking_window_s
        self.marking_reads = [t for t in self.marking_reads if 0.0 < t_s - t <= window] + [t_s]
        return len(self.marking_reads) >= 2

    def _marking_at_once(self, result: DetectionResult, offset: tuple[float, float] | None) -> bool:
        """Whether one reading of a threshold marking confirms the strip of ``result``, ``offset``
        (:func:`_lateral_offset`) beside the aircraft: it is not doubtful
        (``place_min_confidence``), or lies within ``single_marking_max_lateral_heights`` of the
        aircraft, or its place is not measured."""
        return (result.confidence >= self.params.place_min_confidence or offset is None
                or offset[0] <= self.params.single_marking_max_lateral_heights)

    def _recheck_due(self, t_s: float) -> bool:
        """Whether the strip followed, confirmed by its place alone, is due for a search of the
        whole frame (:meth:`_look_for_confirmed` with ``place_only``): at its first frame so
        confirmed, then after ``place_recheck_s``, doubled after each search that found no other
        strip with a threshold marking up to ``place_recheck_max_s``, and in every frame while such
        a strip contests it (:meth:`_contested`)."""
        if self.t_place_check_s is None or self._contested(t_s):
            return True
        return t_s - self.t_place_check_s >= self.place_interval_s - 1e-9   # both set by the last search

    def _contested(self, t_s: float) -> bool:
        """Whether another strip, found afresh with a threshold marking within ``hold_s``, contests
        the one followed (:meth:`_look_for_confirmed`)."""
        return (self.replacement is not None and self.replacement.marked
                and t_s - self.replacement.t_s <= self.params.hold_s)

    def _contested_reason(self, result: DetectionResult, t_s: float) -> str:
        """Why a strip confirmed by its place alone is not reported while contested (one sentence)."""
        t_seen, k_seen, _ = self.replacement
        heights, _ = _lateral_offset(result, self.camera) or (math.nan, math.nan)
        when = "in this frame" if t_s - t_seen < 1e-6 else f"{t_s - t_seen:.1f} s ago"
        return (f"the strip followed lies {heights:.2f} camera heights beside the aircraft and has shown no threshold "
                f"marking, while a search of the whole frame {when} found another strip with one, "
                f"its centre line at lateral offset / height {k_seen:+.2f}: which is the runway approached is not "
                "known yet (a taxiway under the aircraft?)")

    def _check_moves_with_scene(self, result: DetectionResult, t_s: float, inertial: bool) -> DetectionResult:
        """Refuse a "runway" that stays put in the image while the horizon moves (:class:`DetectorParams`
        ``static_*``): part of the aircraft, not of the scene. A horizon read off the frames
        (``inertial`` False) is uncertain by ``IMAGE_HORIZON_SIGMA_DEG`` in each: its motion
        counts only beyond three standard deviations of the difference of two readings (on the
        ray-cast cockpit footage, 640x360, the runway was refused for 2 px of motion, 0.2 deg,
        noise against the 1.7 px minimum)."""
        p = self.params
        min_motion_px = p.static_min_horizon_motion_px
        if not inertial:
            min_motion_px = max(min_motion_px, 3.0 * math.sqrt(2.0) * self._image_horizon_sigma_px())
        self.recent = [(t, r) for t, r in self.recent if 0.0 < t_s - t <= p.static_window_s]
        if self.recent:
            _, old = self.recent[0]
            # a world point on the horizon stays on it: when the camera turns, the runway's
            # vanishing point moves at least as far as the horizon moved where it was; a crossing
            # of lines fixed to the camera stays put while the horizon moves past it. The
            # horizon's motion is measured at the earlier crossing, as the change of its distance
            # from that point: a measured crossing is not exactly on the horizon (blurred edges
            # put it 10 px below it at 600 m, 'sensor: noise, blur, JPEG' at 2048 px), and its
            # distance from the new horizon alone took that offset for motion while the camera
            # held still, refusing the runway
            vp_then, vp_now = _edges_crossing(old, self.camera), _edges_crossing(result, self.camera)
            horizon_motion = _horizon_motion_at(self.camera, old.horizon, result.horizon, vp_then)
            if vp_now is None or not math.isfinite(horizon_motion):          # (NaN without vp_then)
                horizon_motion, edge_motion = 0.0, math.inf
            else:
                edge_motion = float(np.linalg.norm(vp_now - vp_then))
            if (horizon_motion > min_motion_px
                    and edge_motion < p.static_max_motion_ratio * horizon_motion):
                self.recent.append((t_s, result))
                return _refused(result, f"the edges' crossing stayed within {edge_motion:.1f} px in the image while "
                                        f"the horizon moved {horizon_motion:.0f} px away from it: fixed to the camera "
                                        "(the aircraft's structure? mask it in camera.json, see visland mask), not the "
                                        "runway")
        self.recent.append((t_s, result))
        return result

    def _check_identity(self, result: DetectionResult, image, roll_rad, pitch_rad,
                        t_s: float) -> tuple[DetectionResult, bool]:
        """A re-acquisition after a loss longer than ``hold_s``: is it where the runway was?
        Returns the result (refused if not) and whether it was found where the runway was (False
        when nothing remembered applies).

        Every ground line parallel to the runway meets the horizon at the same vanishing point,
        so a strip of fields or a taxiway beside the runway passes every single-frame test; its
        place relative to the camera does not (:class:`DetectorParams`, ``identity_*``). When it is refused, the last good detection is tried once more as the
        prediction (tracking from it across the gap).
        """
        p = self.params
        t_then, k_then, width_then = self.identity
        dt = t_s - t_then
        if dt > p.identity_memory_s:
            return result, False
        k_then += self._k_rate() * dt
        if _not_approached(k_then, width_then, p):
            return result, False
        why = _identity_mismatch(result, self.camera, k_then, width_then, dt, p)
        if not why:
            return result, True
        if self.last_good is not None and roll_rad is not None and math.isfinite(roll_rad):
            again = detect_runway(image, self.camera, roll_rad, pitch_rad, params=self.params, previous=self.last_good)
            if again.found and not _identity_mismatch(again, self.camera, k_then, width_then, dt, p):
                return again, True
        return _refused(result, f"{why} ({result.mode} picked another object parallel to the runway)"), False

    def _check_same_object(self, result: DetectionResult, dt: float) -> DetectionResult:
        """Refuse a detection, tracked or not, whose centre line's lateral offset over height
        (``k_C``, :func:`_ground_geometry`) jumped since the last good one ``dt`` seconds earlier
        (within ``hold_s``) by more than the ``identity_k_*`` limits: another object parallel to the
        runway. Tracking after a miss searches a region of interest around the prediction, and a
        parallel taxiway inside it was taken for the runway (concrete, dry grass at 2900 m: ``k_C``
        -0.38 to +0.77 in 0.6 s), then tracked to the end of the approach. The width over height
        is not compared here: a single frame's far off by up to 30 % at 3 km (edges of a few
        pixels), and every later frame would be refused against it. Only with the inertial
        attitude: a horizon read off each frame moves ``k_C`` with it (the cockpit footage without
        telemetry lost the runway to this check at close range, then acquired the glareshield)."""
        if self.good_geometry is None:
            return result
        k_then = self.good_geometry[0] + self._k_rate() * dt
        if _not_approached(k_then, self.good_geometry[1], self.params):
            return result
        why = _identity_mismatch(result, self.camera, k_then, math.nan, dt, self.params)
        if not why:
            return result
        return _refused(result, f"{why} ({result.mode} picked another object parallel to the runway)")

    def _k_rate(self) -> float:
        """The rate of the centre line's ``k_C`` (per second) to carry the remembered one forward:
        the slope of a line through the accepted frames' ``k_C`` of ``identity_rate_window_s``,
        shrunk toward zero against a prior of one sigma ``identity_k_rate``, ``r sigma_p^2 /
        (sigma_p^2 + se^2)`` with ``se`` the slope's standard error from the line's own residuals
        (zero with fewer than four frames or less than a second of history)."""
        if len(self.identity_history) < 4:
            return 0.0
        times = np.array([t for t, _ in self.identity_history])
        slopes = np.array([k for _, k in self.identity_history])
        if times[-1] - times[0] < 1.0:
            return 0.0
        spread = float(np.sum((times - times.mean()) ** 2))
        rate, offset = np.polyfit(times - times[-1], slopes, 1)
        residual = slopes - (rate * (times - times[-1]) + offset)
        standard_error_sq = float(np.sum(residual ** 2)) / (len(times) - 2) / spread
        prior_sq = self.params.identity_k_rate ** 2
        return float(rate) * prior_sq / (prior_sq + standard_error_sq)

    def _image_horizon_sigma_px(self) -> float:
        """The uncertainty of a horizon read off a frame (``IMAGE_HORIZON_SIGMA_DEG``), pixels."""
        return self.camera.fy * math.radians(IMAGE_HORIZON_SIGMA_DEG)

    def _detect_without_attitude(self, image, prior: DetectionResult | None) -> DetectionResult:
        """The horizon from the frame, moved through the runway's vanishing point when found.

        The frame is checked and turned into its scene frame once, for the horizon and for
        every detection on it."""
        problem = check_frame(image, self.camera)
        if problem:
            return not_found(problem)
        scene = scene_frame(image, self.camera)
        attitude = attitude_from_image(as_grey(scene), self.camera, ignored_pixels(self.camera), self.image_attitude)
        if isinstance(attitude, str):
            return not_found(f"no attitude data and {attitude}")
        params = self.params
        if attitude.method == "sky":
            # the visible horizon is up to a few tenths of a degree below the true one (haze):
            # until the runway's vanishing point has placed it, edges meet it that loosely
            sigma_px = self._image_horizon_sigma_px()
            params = replace(params, horizon_sigma_px=max(params.horizon_sigma_px, sigma_px),
                             vp_tolerance_px=max(params.vp_tolerance_px, 2.0 * sigma_px))
        result = detect_in_scene_frame(scene, self.camera, attitude.roll_rad, attitude.pitch_rad, params, prior)
        vp = _edges_crossing(result, self.camera)
        if vp is None:
            return result           # the horizon's offset from the last runway is carried on
        corrected = attitude.through_point(self.camera, vp)
        self.image_attitude = corrected
        if abs(corrected.visible_offset_px - attitude.visible_offset_px) > 0.5:
            # the horizon moved: measure again on the right one
            again = detect_in_scene_frame(scene, self.camera, corrected.roll_rad, corrected.pitch_rad, self.params,
                                          prior)
            if again.found:
                result = again
        return result

    def _check_pavement_start(self, result: DetectionResult, t_s: float) -> DetectionResult:
        """Withhold a threshold placed where the pavement begins while two frames of the last
        ``marking_memory_s`` saw a threshold marking the same runway widths inside the pavement,
        or the last good frame did and no threshold is followed yet (module docstring); remember
        this frame's marking."""
        p = self.params
        seen = [(t, w) for t, w in self.markings_seen if t_s - t <= p.marking_memory_s]
        if result.pavement_marking_widths >= p.marking_memory_min_widths:       # NaN: none seen
            seen.append((t_s, float(result.pavement_marking_widths)))
        self.markings_seen = seen
        if not result.corners_found[:2].any() or result.threshold_method.startswith("marking"):
            return result
        if len(self._recent_track(t_s)) < 3 and seen and seen[-1][0] == self.t_good_s:
            # no threshold followed yet (fewer widths than a track needs) to vouch for the
            # pavement's start, and the last good frame saw a marking inside it: that one
            # sighting withholds it (the robustness study's displaced threshold, the first
            # tracked frame at 3666 m: the bar seen 7.8 widths in once, in the acquisition frame
            # before, the threshold then put 8.8 px short). Only in the frame after the sighting:
            # a withheld threshold does not enter the track, and a spurious sighting (a noisy,
            # compressed frame at 2.3 km) then withheld 44 frames for marking_memory_s
            t_late, widths = seen[-1]
            return _without_threshold(result, f"threshold withheld: placed where the pavement begins, but a "
                                              f"threshold marking {widths:.1f} runway widths inside the pavement "
                                              f"was seen {t_s - t_late:.1f} s earlier, and no threshold is "
                                              "followed yet (a displaced threshold?)")
        # the same marking seen twice (with a threshold followed, a single sighting can be the
        # threshold's own stripes behind a band of ground taken for pavement: concrete on dry
        # grass at 650 m)
        for t_late, widths in reversed(seen):
            agreeing = [t for t, w in seen if t != t_late and abs(w - widths) <= p.marking_memory_agreement * widths]
            if agreeing:
                return _without_threshold(result, f"threshold withheld: placed where the pavement begins, but a "
                                                  f"threshold marking {widths:.1f} runway widths inside the pavement "
                                                  f"was seen {t_s - t_late:.1f} and {t_s - max(agreeing):.1f} s "
                                                  "earlier (a displaced threshold?)")
        return result

    def _check_threshold(self, result: DetectionResult, prior: DetectionResult, dt: float) -> DetectionResult:
        """Drop threshold corners that jumped since the prior (the touchdown-zone bars taken for
        the threshold for one frame); the edges and d_F stay."""
        near_now = result.corners_found[:2].all()
        near_then = prior.corners_found[:2].all()
        if not (near_now and near_then):
            return result
        width_px = float(np.hypot(*(prior.corners_uv[1] - prior.corners_uv[0])))
        frames = max(dt * self.params.reference_rate_hz, 1.0)
        limit = (self.params.max_threshold_jump_px + self.params.max_threshold_jump_fraction * width_px) * frames
        jump = float(np.max(np.linalg.norm(result.corners_uv[:2] - prior.corners_uv[:2], axis=1)))
        if jump <= limit:
            return result
        return _without_threshold(result, f"threshold corners dropped: moved {jump:.0f} px since {dt:.2f} s earlier "
                                          f"(> {limit:.0f})")

    def _follow_threshold(self, result: DetectionResult, t_s: float) -> DetectionResult:
        """Check the threshold's width against its track (module docstring); update the track."""
        if not result.corners_found[:2].all():
            return result
        width = float(np.hypot(*(result.corners_uv[1] - result.corners_uv[0])))
        p = self.params
        track = self.threshold_track = self._recent_track(t_s)
        # flying toward it, the threshold's width (f W / depth) only grows: where the track is too
        # short to predict, a threshold narrower than the last one accepted in the last seconds is
        # something farther along the runway (a marking, seen once the threshold has left the
        # frame below)
        if len(track) < 3 and self.last_threshold is not None:
            t_last, last = self.last_threshold
            if t_s - p.threshold_shrink_memory_s <= t_last < t_s and width < last - _width_tolerance(p, last):
                return _without_threshold(result, f"threshold withheld: {width:.1f} px wide, narrower than the "
                                                  f"{last:.1f} px accepted {t_s - t_last:.1f} s earlier (flying "
                                                  "toward the threshold its width only grows)")
        if len(track) >= 3:
            times = np.array([t for t, _ in track])
            inverse = np.array([1.0 / w for _, w in track])
            slope, offset = np.polyfit(times - t_s, inverse, 1)
            if slope > 0.0:
                # flying toward the threshold its width only grows (1 / w falls): a rising 1 / w
                # is the widths' scatter, and extrapolated it predicts a shrinking threshold
                # (thesis-8 at 512 px, 3.5 km: widths 9.6, 9.8, 9.1, 8.8 px predicted 7.7 px
                # half a second on, and the next, 9.7, was withheld); their mean is predicted
                offset = float(np.mean(inverse))
            predicted = 1.0 / offset if offset > 0 else math.inf
            tolerance = _width_tolerance(p, predicted)
            if not abs(width - predicted) <= tolerance:
                rejected = [(t, w) for t, w in self.threshold_rejected if t_s - p.threshold_track_s <= t < t_s]
                rejected.append((t_s, width))
                self.threshold_rejected = rejected
                if len(rejected) >= max(3, len(track)) and _consistent(rejected, p):
                    # the track itself was the wrong object (or the runway was lost and found
                    # again): once the rejections outnumber the widths the track still holds in
                    # its window. Three alone were not enough where a texture's end 17 px beyond
                    # the threshold came three frames running while the track held five widths
                    # a pixel off ('oblique, 1200x23' at 1.3 km, 2048 px: the track restarted on
                    # it and two frames were reported 17.5 px off)
                    self.threshold_track = rejected
                    self.threshold_rejected = []
                    self.last_threshold = (t_s, width)
                    return result
                return _without_threshold(result, f"threshold withheld: {width:.1f} px wide where its track "
                                                  f"predicts {predicted:.1f} px (tolerance {tolerance:.1f})")
        self.threshold_rejected = []
        self.threshold_track = track + [(t_s, width)]
        self.last_threshold = (t_s, width)
        return result

    def _follow_end(self, result: DetectionResult, t_s: float, new_track: bool) -> DetectionResult:
        """Withhold a runway end narrower than the ends reported in the same track in the last
        ``threshold_shrink_memory_s`` seconds (the median of the last ``END_TRACK_WIDTHS`` of them,
        less ``_width_tolerance``): flying toward the end its width (f W / its distance) only
        grows, by about 3 % a second from 3 km. A step farther out taken for it is narrower (the
        haze near the horizon at dusk, 1024 px, 290 m from the threshold: an end 5 px wide, 8.5 px
        above the true one, 16 px wide a second earlier). The median, not the last end: one end
        placed 2-3 px short, 12.9 px wide among true ones of 10 px ('worn, no side stripes' and
        'sand, monochrome' at 1024 px, 3 and 2.4 km), withheld the true ends for 5 s after it. Only
        reported ends are remembered (one on a strip followed but not reported did the same)."""
        if new_track:
            self.end_track = []
        if not result.corners_found[2:].all():
            return result
        width = float(np.hypot(*(result.corners_uv[3] - result.corners_uv[2])))
        p = self.params
        track = [(t, w) for t, w in self.end_track if t_s - p.threshold_shrink_memory_s <= t < t_s]
        if track:
            reference = float(np.median([w for _, w in track[-END_TRACK_WIDTHS:]]))
            if width < reference - _width_tolerance(p, reference):
                self.end_track = track
                return _without_end(result, f"runway end withheld: {width:.1f} px wide, narrower than the "
                                            f"{reference:.1f} px of the ends reported in the last "
                                            f"{t_s - track[0][0]:.1f} s (flying toward it its width only grows)")
        self.end_track = track + [(t_s, width)]
        return result

    def _recent_track(self, t_s: float) -> list:
        """The threshold track's widths of the ``threshold_track_s`` seconds before ``t_s``."""
        return [(t, w) for t, w in self.threshold_track if t_s - self.params.threshold_track_s <= t < t_s]

    def _inconsistency(self, result: DetectionResult, prior: DetectionResult, dt: float) -> str:
        p = self.params
        turn_limit = p.max_edge_turn_rad + p.max_edge_turn_rate_rps * dt
        for name in ("left", "right"):
            theta_now = result.lines[name][1]
            theta_then = prior.lines[name][1]
            if math.isfinite(theta_now) and math.isfinite(theta_then):
                # lines are undirected: compare modulo pi
                turn = abs((theta_now - theta_then + math.pi / 2) % math.pi - math.pi / 2)
                if turn > turn_limit:
                    return f"the {name} edge turned {math.degrees(turn):.1f} deg (> {math.degrees(turn_limit):.1f})"
        if math.isfinite(result.dF_px) and math.isfinite(prior.dF_px):
            jump = abs(result.dF_px - prior.dF_px)
            jump_limit = p.max_vp_jump_px + p.max_vp_jump_rate_pxps * dt
            if jump > jump_limit:
                return f"the vanishing point moved {jump:.0f} px along the horizon (> {jump_limit:.0f})"
        return ""


def _without_threshold(result: DetectionResult, note: str) -> DetectionResult:
    """``result`` with its threshold line and corners withheld, saying ``note``."""
    return _without_line(result, slice(0, 2), "threshold_line", note)


def _without_end(result: DetectionResult, note: str) -> DetectionResult:
    """``result`` with its runway end line and corners withheld, saying ``note``."""
    return _without_line(result, slice(2, 4), "end_line", note)


def _without_line(result: DetectionResult, rows: slice, line: str, note: str) -> DetectionResult:
    """``result`` with the transverse ``line`` field and its corners ``rows`` withheld."""
    corners = result.corners_uv.copy()
    corners[rows] = np.nan
    found = result.corners_found.copy()
    found[rows] = False
    return replace(result, corners_uv=corners, corners_found=found, **{line: (math.nan, math.nan)}).with_note(note)


def _ground_geometry(result: DetectionResult, camera: CameraModel):
    """``(k_centre, width_ratio)``: the runway's centre line slope and its width over the depth
    in the horizon frame (``s = s0 + k d``, :mod:`visland.detection.horizon`). For a ground line
    at lateral distance ``Y`` from the camera at height ``h``, ``k = Y / h`` (up to the heading
    deviation's cosine), so these are the runway's lateral offset and width over the height:
    they change slowly over an approach whatever the attitude. None if not measurable.

    The two edges meet the horizon at one vanishing point, taken as the mean of their own
    crossings ``s0``; the width is read about it where both edges are measured (the middle of
    their common depths): ``|k_r - k_l + (s0_r - s0_l) / d_mid|``. The slopes' difference alone
    extrapolates two short edges to the horizon, where their crossings scatter by pixels: on the
    ray-cast airport at 1280 x 720 (62 deg lens) from 3.8 to 3.0 km, 12-16 px wide, it read
    0.14 to 0.30 for a true 0.18 to 0.22 (this reading: 0.175 to 0.214), and the runway was
    refused as another object for 8 s.
    """
    horizon = horizon_frame(camera, result.roll_rad, result.pitch_rad)
    if horizon is None:
        return None
    pencils = []
    for name in ("left", "right"):
        segment = np.asarray(result.segments_uv.get(name, np.full((2, 2), np.nan)), float)
        if not np.all(np.isfinite(segment)):
            return None
        s0, k = horizon.pencil_from_points(segment[0], segment[1])
        depths = horizon.to_sd(segment)[:, 1]
        if not (math.isfinite(float(s0)) and math.isfinite(float(k))):
            return None
        pencils.append((float(s0), float(k), float(depths.min()), float(depths.max())))
    (s0_left, k_left, far_left, near_left), (s0_right, k_right, far_right, near_right) = pencils
    d_mid = 0.5 * (max(far_left, far_right) + min(near_left, near_right))
    if not d_mid > 1e-9:
        return None
    return 0.5 * (k_left + k_right), abs(k_right - k_left + (s0_right - s0_left) / d_mid)


def _lateral_offset(result: DetectionResult, camera: CameraModel) -> tuple[float, float] | None:
    """``(|Y| / h, |Y| / W)``: how far to the side of the aircraft the strip's centre line lies,
    in camera heights and in the strip's own widths (:func:`_ground_geometry`); None if not
    measurable."""
    return _offset_of(_ground_geometry(result, camera))


def _offset_of(geometry: tuple[float, float] | None) -> tuple[float, float] | None:
    """:func:`_lateral_offset` from a strip's :func:`_ground_geometry` already computed."""
    if geometry is None:
        return None
    heights = abs(geometry[0])
    return heights, (heights / geometry[1] if geometry[1] > 0 else math.inf)


def _confirmed_by_place(result: DetectionResult, offset: tuple[float, float] | None, params: DetectorParams) -> bool:
    """Whether the strip of ``result``, ``offset`` (:func:`_lateral_offset`) beside the aircraft,
    is confirmed as the runway approached by its place in this frame: the aircraft is over it or nearly (``max_lateral_heights_widths``
    of its widths), or it lies within ``unconfirmed_max_lateral_heights`` camera heights of the
    aircraft, within ``weak_max_lateral_heights`` only when its confidence is below
    ``place_min_confidence`` (:class:`DetectorParams`). Every ground line parallel to the runway
    shares its vanishing point, and a taxiway beside it passes every other test: on the
    robustness study's overcast frames (2048 px) the runway's edges were lost in the fog and a
    parallel taxiway 1.33 heights out was acquired at 2.4 km, unmarked; on the ray-cast airport
    with a rubber-darkened runway (1200 x 23 m, grey on grass of nearly its grey, 1024 px) the
    runway's edges held nowhere beyond 1.3 km and a parallel taxiway 0.64 heights out was
    followed from 2.5 km to 100 ft, confidence 0.29-0.56 beyond 1.5 km. A strip whose place
    cannot be measured (no horizon) is not held back."""
    if offset is None or offset[1] <= params.max_lateral_heights_widths:
        return True
    return offset[0] <= _place_limit_heights(result, params)


def _place_limit_heights(result: DetectionResult, params: DetectorParams) -> float:
    """How many camera heights beside the aircraft the strip of ``result`` may lie and be
    confirmed by its place: ``unconfirmed_max_lateral_heights``, ``weak_max_lateral_heights``
    below ``place_min_confidence``."""
    return (params.unconfirmed_max_lateral_heights if result.confidence >= params.place_min_confidence
            else params.weak_max_lateral_heights)


def _unconfirmed_reason(result: DetectionResult, offset: tuple[float, float], params: DetectorParams,
                        last_read_s: float | None = None) -> str:
    """Why the strip of ``result``, ``offset`` (:func:`_lateral_offset`) beside the aircraft, not
    confirmed, is not reported (one sentence); ``last_read_s``:
    how long ago a threshold marking was last read on it without confirming it (a doubtful strip
    far out, read in one frame only), None if none was."""
    heights, widths = offset
    limit = _place_limit_heights(result, params)
    why = (f"more than {limit:g} at a confidence of {result.confidence:.2f}, below {params.place_min_confidence:g}"
           if heights <= params.unconfirmed_max_lateral_heights else
           f"more than {params.unconfirmed_max_lateral_heights:g}")
    shown = ("no threshold marking since it was acquired" if last_read_s is None else
             f"a threshold marking in no two frames within {params.weak_marking_window_s:g} s (the last "
             f"{last_read_s:.1f} s ago; two are asked of a strip at a confidence below {params.place_min_confidence:g} "
             f"more than {params.single_marking_max_lateral_heights:g} camera heights out)")
    return (f"the strip followed lies {heights:.2f} camera heights ({widths:.0f} of its widths) beside the aircraft "
            f"({why}) and has shown {shown}: not confirmed as the runway approached (a taxiway or road beside it?)")


def _not_approached(k_centre: float, width_ratio: float, params: DetectorParams) -> bool:
    """Whether a remembered strip, its centre line ``k_centre = Y / h`` to the side and
    ``width_ratio = W / h`` wide, is no runway being approached, as the detector refuses a pair of
    edges (:func:`~visland.detection.detector.beside_the_approach`): the object remembered was
    then not the runway (tracked until it lay that far out), and does not refuse the one found
    now (``k_centre`` carried forward at its own rate to the frame)."""
    heights = abs(k_centre)
    return beside_the_approach(heights, heights / abs(width_ratio) if width_ratio else math.inf, params)


def _identity_mismatch(result: DetectionResult, camera: CameraModel, k_then: float, width_then: float, dt: float,
                       p: DetectorParams) -> str:
    geometry = _ground_geometry(result, camera)
    if geometry is None:
        return ""
    k_now, width_now = geometry
    k_limit = p.identity_k_tolerance + p.identity_k_rate * dt + 0.1 * abs(k_then)
    if abs(k_now - k_then) > k_limit:
        return (f"its centre line lies at lateral offset / height {k_now:+.2f} where the runway seen {dt:.1f} s "
                f"earlier was at {k_then:+.2f} (tolerance {k_limit:.2f})")
    width_limit = p.identity_width_tolerance + p.identity_width_rate * dt
    if width_then > 0 and abs(width_now / width_then - 1.0) > width_limit:
        return (f"its width / height is {width_now:.3f} where the runway's was {width_then:.3f} {dt:.1f} s earlier "
                f"(more than {100 * width_limit:.0f} % apart)")
    return ""


def _horizon_motion_at(camera: CameraModel, horizon_then, horizon_now, uv) -> float:
    """How far the horizon moved at pixel ``uv`` between two frames: the change of its signed
    distance from ``uv`` (the two lines' normals oriented alike), pixels; NaN when a line or
    ``uv`` is missing."""
    if uv is None or not all(math.isfinite(x) for x in (*horizon_then, *horizon_now)):
        return math.nan
    (r_then, t_then), (r_now, t_now) = (camera.line_to_pixel_hough(*h) for h in (horizon_then, horizon_now))
    d_then = uv[0] * math.cos(t_then) + uv[1] * math.sin(t_then) - r_then
    d_now = uv[0] * math.cos(t_now) + uv[1] * math.sin(t_now) - r_now
    same_side = math.cos(t_now - t_then) >= 0.0
    return float(abs((d_now if same_side else -d_now) - d_then))


def _edges_crossing(result: DetectionResult, camera: CameraModel):
    """Pixel where the two detected edges cross (the runway's vanishing point), or None."""
    if not result.found:
        return None
    from visland.camera import intersect_lines
    (rho_l, theta_l), (rho_r, theta_r) = result.lines["left"], result.lines["right"]
    if not all(math.isfinite(x) for x in (rho_l, theta_l, rho_r, theta_r)):
        return None
    xy = np.asarray(intersect_lines(rho_l, theta_l, rho_r, theta_r), float)
    if not np.all(np.isfinite(xy)):
        return None
    uv = camera.normalized_to_pixels(xy)
    return uv if camera.in_image(uv, margin_px=-max(camera.width, camera.height)) else None


def _width_tolerance(params: DetectorParams, width):
    """How far a threshold's width may be from the one expected (``threshold_width_tolerance_*``)."""
    return params.threshold_width_tolerance_px + params.threshold_width_tolerance_fraction * width


def _consistent(samples: list, params: DetectorParams) -> bool:
    """Do ``(t, width)`` samples follow one line in ``1 / width`` (a track of their own)?"""
    times = np.array([t for t, _ in samples])
    widths = np.array([w for _, w in samples])
    slope, offset = np.polyfit(times - times[-1], 1.0 / widths, 1)
    fitted = 1.0 / (slope * (times - times[-1]) + offset)
    tolerance = _width_tolerance(params, widths)
    return bool(np.all(np.abs(fitted - widths) <= tolerance))
