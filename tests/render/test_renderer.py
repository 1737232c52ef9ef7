"""FrameRenderer: input checks, no z-fighting between runway and ground, determinism, the bench command."""
import json
import math

import numpy as np
import pytest

from visland.camera import CameraModel
from visland.features import batch_R_camera_from_runway, project_runway_corners
from visland.render import FrameRenderer, SceneParams
from visland.runway import Runway


def _pose(distance_m, height_m, camera):
    p = np.array([-distance_m, 0.0, -height_m])
    pitch = -math.atan2(height_m, distance_m + 1500.0) - camera.mount_rpy_rad[1]
    R = batch_R_camera_from_runway(np.array([0.0]), np.array([pitch]), np.array([0.0]), camera.mount_rpy_rad)[0]
    return p, R


def test_runway_seen_from_6_km_has_no_ground_pixel_inside():
    # the classic failure: a runway a few centimetres above the ground z-fights from far away
    camera = CameraModel.default(1024)
    runway = Runway()
    p, R = _pose(6000.0, 320.0, camera)
    with FrameRenderer(SceneParams.flat(msaa_samples=0), camera, runway) as renderer:
        rgb = renderer.render(p, R)
    uv, _, visible = project_runway_corners(R[None], p[None], runway, camera)
    assert visible.all()
    import cv2
    polygon = uv[0][[0, 1, 3, 2]]
    mask = np.zeros(rgb.shape[:2], np.uint8)
    cv2.fillConvexPoly(mask, np.round(polygon * 16).astype(np.int32), 1, lineType=cv2.LINE_8, shift=4)
    inner = cv2.erode(mask, np.ones((3, 3), np.uint8))          # away from the edges
    assert inner.sum() > 100
    assert np.all(rgb[inner.astype(bool)] == 255)
    assert np.all(rgb[cv2.dilate(mask, np.ones((5, 5), np.uint8)) == 0] == 0)


@pytest.mark.slow
def test_same_frame_twice_is_identical_and_noise_follows_the_frame_seed():
    camera = CameraModel.default(128)
    p, R = _pose(3000.0, 160.0, camera)
    with FrameRenderer(SceneParams(distractors=False), camera, Runway()) as renderer:
        a = renderer.render(p, R, frame_seed=5)
        b = renderer.render(p, R, frame_seed=5)
        c = renderer.render(p, R, frame_seed=6)
    assert a.shape == (128, 128, 3) and a.dtype == np.uint8
    assert np.array_equal(a, b) and not np.array_equal(a, c)


def test_bad_input_is_refused():
    camera = CameraModel.default(64)
    with pytest.raises(ValueError, match="params must be a SceneParams"):
        FrameRenderer({"seed": 0}, camera, Runway())
    renderer = FrameRenderer(SceneParams.flat(), camera, Runway())
    p, R = _pose(3000.0, 160.0, camera)
    with pytest.raises(ValueError, match="above the ground"):
        renderer.render([-3000.0, 0.0, 5.0], R)
    with pytest.raises(ValueError, match="rotation matrix"):
        renderer.render(p, 2.0 * R)
    renderer.close()
    renderer.close()
    with pytest.raises(ValueError, match="closed"):
        renderer.render(p, R)


@pytest.mark.slow
def test_bench_render_prints_its_figures_as_the_last_json_line(capsys):
    from visland.render.bench import run_render_bench
    figures = run_render_bench(size=64, n_frames=3, variants=False, png_levels=(1,))
    last = capsys.readouterr().out.strip().splitlines()[-1]
    data = json.loads(last)
    assert data["bench"] == "render" and data["size_px"] == 64
    assert data["render"]["median_s"] == figures["render"]["median_s"] > 0
    assert "1" in data["png_levels"]


@pytest.mark.slow
def test_uniforms_held_by_a_program_are_not_sent_again_and_the_frames_are_the_same_bytes(monkeypatch):
    """glview._cache_uniforms skips a uniform value the program already holds: the frames of a
    short sequence (two poses, each drawn twice, interleaved) are byte-identical to pyrender's
    own every-uniform-every-primitive path, and fewer uniforms reach the driver."""
    import visland.render.glview as glview
    camera = CameraModel.default(96)
    poses = [_pose(3000.0, 160.0, camera), _pose(800.0, 45.0, camera)] * 2

    def frames():
        sent = []
        with FrameRenderer(SceneParams(distractors=False), camera, Runway()) as renderer:
            images = []
            for k, (p, R) in enumerate(poses):
                images.append(renderer.render(p, R, frame_seed=k))
            for program in renderer._view._offscreen._renderer._program_cache._program_cache.values():
                sent.append(getattr(program, "_visland_sent", 0))
        return images, sum(sent)

    import pyrender.shader_program as shader_program
    original = shader_program.ShaderProgram.set_uniform

    def counting(self, name, value, unsigned=False):
        self._visland_sent = getattr(self, "_visland_sent", 0) + 1
        return original(self, name, value, unsigned)

    monkeypatch.setattr(shader_program.ShaderProgram, "set_uniform", counting)
    cached, sent_cached = frames()
    monkeypatch.setattr(glview, "_cache_uniforms", lambda program: setattr(program, "_visland_uniforms", {}))
    every, sent_every = frames()
    assert all(np.array_equal(a, b) for a, b in zip(cached, every))
    assert not np.array_equal(cached[0], cached[1])                 # two different poses
    assert 0 < sent_cached < sent_every / 2
