"""Frames of the detection robustness studies, rendered by visland's renderer with the seeds the
studies draw them with, and their errors against the exact labels: the approach study's
(benchmarks/detection_robustness_approach.py: thesis-3 at 5 Hz, :func:`study_frames`) and the
single-frame study's (benchmarks/detection_robustness.py: the 25 Hz frame nearest a distance,
:func:`study_frame_at`)."""

import numpy as np

STUDY_FPS = 5.0
#: The single-frame study picks frames of thesis-3 sampled at this rate.
SINGLE_FRAME_FPS = 25.0


def _rendered(runway, scene, size: int, fps: float, pick, seed_of):
    """Thesis-3 flown with ``runway`` and sampled at ``fps``; the frames ``pick(times, trajectory)``
    returns, rendered with ``scene`` at ``size`` px and frame seed ``seed_of(index)``:
    ``[(rgb, state, labels, t_s)], camera``."""
    import os
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    from visland.camera import CameraModel
    from visland.features import batch_R_camera_from_runway, ideal_features
    from visland.flight import simulate_flight
    from visland.render import FrameRenderer
    from visland.scenarios import resolve_scenario, with_runway
    from visland.simulate import frame_times

    trajectory = simulate_flight(with_runway(resolve_scenario("thesis-3"), runway))
    times = frame_times(trajectory.duration_s, fps)
    camera = CameraModel.default(size)
    frames = []
    with FrameRenderer(scene, camera, runway) as renderer:
        for index in pick(times, trajectory):
            state = trajectory.at(times[index:index + 1])
            R = batch_R_camera_from_runway(state.roll_rad, state.pitch_rad, state.dpsi_rad, camera.mount_rpy_rad)
            rgb = renderer.render(state.p_runway_m[0], R[0], frame_seed=seed_of(index))
            frames.append((rgb, state, ideal_features(state, runway, camera), float(times[index])))
    return frames, camera


def study_frames(scene_overrides: dict, runway_m: tuple, indices, size: int = 1024, variety: int | None = None):
    """The approach study's frames ``indices`` (thesis-3 flown with the runway, 5 Hz, rendered by
    visland's renderer with the frame's seed as the study draws it,
    :func:`visland.datasets.generate.frame_seed`): ``[(rgb, state, labels, t_s)], camera``. With
    ``variety`` the runway and the scene are the study's 'variety N'
    (:func:`visland.render.variety.draw_variety`) and the other two are ignored."""
    from visland.datasets.generate import frame_seed
    from visland.render import SceneParams
    from visland.render.variety import draw_variety
    from visland.runway import Runway

    if variety is not None:
        drawn = draw_variety(variety)
        runway, scene = Runway(length_m=drawn.runway_length_m, width_m=drawn.runway_width_m), drawn.scene
    else:
        runway, scene = Runway(length_m=runway_m[0], width_m=runway_m[1]), SceneParams(**scene_overrides)
    return _rendered(runway, scene, size, STUDY_FPS, lambda times, trajectory: indices,
                     lambda index: frame_seed(scene.seed, index))


def study_frame_at(scene_overrides: dict, runway_m: tuple, distance_m: float, size: int):
    """The single-frame study's frame (benchmarks/detection_robustness.py): thesis-3 flown with the
    given runway, the 25 Hz frame nearest ``distance_m`` before the threshold, rendered with that
    frame's index as its seed: ``(rgb, camera, state, labels)``."""
    from visland.render import SceneParams
    from visland.runway import Runway

    def nearest(times, trajectory):
        return [int(np.argmin(np.abs(-trajectory.at(times).p_runway_m[:, 0] - distance_m)))]

    [(rgb, state, labels, _)], camera = _rendered(Runway(length_m=runway_m[0], width_m=runway_m[1]),
                                                  SceneParams(**scene_overrides), size, SINGLE_FRAME_FPS,
                                                  nearest, lambda index: index)
    return rgb, camera, state, labels


def study_errors(result, camera, state, labels):
    """Errors of a detection on a study frame against its exact labels
    (:func:`visland.detection.accuracy.frame_errors`)."""
    from visland.detection.accuracy import frame_errors
    return frame_errors(result, camera, labels.corners_uv[0], labels.corners_visible[0], float(state.dpsi_rad[0]))


def detected_with_errors(rgb, camera, state, labels):
    """``detect_runway`` on one study frame (acquisition, the state's inertial roll and pitch) and
    its errors against the exact labels: ``(result, errors)``."""
    from visland.detection import detect_runway
    result = detect_runway(rgb, camera, float(state.roll_rad[0]), float(state.pitch_rad[0]))
    return result, study_errors(result, camera, state, labels)
