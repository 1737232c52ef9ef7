"""Frames of the detection robustness study (benchmarks/detection_robustness_approach.py):
thesis-3 flown at 5 Hz over a condition's runway and scene, rendered by visland's renderer with
each frame's seed as the study draws it, and their errors against the exact labels."""

STUDY_FPS = 5.0


def study_frames(scene_overrides: dict, runway_m: tuple, indices, size: int = 1024, variety: int | None = None):
    """The study's frames ``indices`` (thesis-3 flown with the runway, 5 Hz, rendered by visland's
    renderer with the frame's seed as the study draws it, :func:`visland.datasets.generate.frame_seed`):
    ``[(rgb, state, labels, t_s)], camera``. With ``variety`` the runway and the scene are the
    study's 'variety N' (:func:`visland.render.variety.draw_variety`) and the other two are ignored."""
    import os
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    from visland.camera import CameraModel
    from visland.datasets.generate import frame_seed
    from visland.features import batch_R_camera_from_runway, ideal_features
    from visland.flight import simulate_flight
    from visland.render import FrameRenderer, SceneParams
    from visland.render.variety import draw_variety
    from visland.runway import Runway
    from visland.scenarios import resolve_scenario, with_runway
    from visland.simulate import frame_times

    if variety is not None:
        drawn = draw_variety(variety)
        runway, scene = Runway(length_m=drawn.runway_length_m, width_m=drawn.runway_width_m), drawn.scene
    else:
        runway, scene = Runway(length_m=runway_m[0], width_m=runway_m[1]), SceneParams(**scene_overrides)
    trajectory = simulate_flight(with_runway(resolve_scenario("thesis-3"), runway))
    times = frame_times(trajectory.duration_s, STUDY_FPS)
    camera = CameraModel.default(size)
    frames = []
    with FrameRenderer(scene, camera, runway) as renderer:
        for index in indices:
            state = trajectory.at(times[index:index + 1])
            R = batch_R_camera_from_runway(state.roll_rad, state.pitch_rad, state.dpsi_rad, camera.mount_rpy_rad)
            rgb = renderer.render(state.p_runway_m[0], R[0], frame_seed=frame_seed(scene.seed, index))
            frames.append((rgb, state, ideal_features(state, runway, camera), float(times[index])))
    return frames, camera


def study_errors(result, camera, state, labels):
    from visland.detection.accuracy import frame_errors
    return frame_errors(result, camera, labels.corners_uv[0], labels.corners_visible[0], float(state.dpsi_rad[0]))
