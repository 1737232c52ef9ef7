"""The OpenCV-to-OpenGL conversion, checked with rendered markers at known positions."""
import math

import numpy as np
import pytest

from visland.camera import CameraModel
from visland.frames import R_camera_from_runway, rot_x, rot_y, rot_z
from visland.render.glview import OffscreenView, check_opengl, gl_camera_pose, gl_projection_matrix, RenderingUnavailable
from visland.render.params import SceneParams
from visland.render.shaders import write_shaders


def _marker_scene(corners_runway_m):
    """A pyrender scene holding one white quad (4 corners, runway frame) on black."""
    import pyrender
    import trimesh
    mesh = trimesh.Trimesh(vertices=np.asarray(corners_runway_m, float), faces=[[0, 1, 2], [0, 2, 3]], process=False)
    material = pyrender.MetallicRoughnessMaterial(name="KIND_FLAT", baseColorFactor=(1.0, 1.0, 1.0, 1.0),
                                                  emissiveFactor=(0.0, 0.0, 3.0), doubleSided=True)
    scene = pyrender.Scene(bg_color=(0.0, 0.0, 0.0, 1.0))
    scene.add(pyrender.Mesh.from_trimesh(mesh, material=material))
    return scene


def _coverage_centroid(rgb):
    w = rgb[..., 0].astype(float) / 255.0
    v, u = np.mgrid[0:w.shape[0], 0:w.shape[1]]
    return np.array([(w * u).sum() / w.sum(), (w * v).sum() / w.sum()]), w.sum()


@pytest.fixture(scope="module")
def shader_dir(tmp_path_factory):
    return str(write_shaders(tmp_path_factory.mktemp("shaders"), SceneParams.flat(), 0.0))


@pytest.mark.parametrize("camera", [
    CameraModel.default(256),
    # non-square pixels and an off-centre principal point catch a swapped or missing half pixel
    CameraModel(320, 240, fx=300.0, fy=270.0, cx=150.25, cy=131.5),
])
def test_marker_centroid_matches_closed_form_projection(camera, shader_dir):
    # a square facing the camera: its image is a square whose centroid is the projected centre
    R_cr = R_camera_from_runway(0.03, -0.02, 0.1, (0.0, math.radians(-3.0), 0.0))
    p_cam = np.array([-900.0, 12.0, -60.0])
    R_rc = R_cr.T
    view = OffscreenView(camera, shader_dir, samples=4, anisotropy=1)
    try:
        for x_c, y_c in ((-0.2, -0.15), (0.1, 0.2), (0.0, 0.0)):
            depth = 80.0
            half = 5.0
            centre_C = np.array([x_c * depth, y_c * depth, depth])
            # turned 30 deg in the image plane: MSAA's 0.25 px coverage steps average out along slanted edges
            square = np.array([[-half, -half, 0], [half, -half, 0], [half, half, 0], [-half, half, 0]])
            corners_C = centre_C + square @ rot_z(math.radians(30.0)).T
            corners_R = (R_rc @ corners_C.T).T + p_cam
            rgb = view.render(_marker_scene(corners_R), p_cam, R_cr, 1.0, 1000.0)
            centroid, area = _coverage_centroid(rgb)
            # closed form: u = fx X/Z + cx, v = fy Y/Z + cy
            expected = np.array([camera.fx * x_c + camera.cx, camera.fy * y_c + camera.cy])
            assert np.abs(centroid - expected).max() < 0.05, (centroid, expected)
            expected_area = (2 * half * camera.fx / depth) * (2 * half * camera.fy / depth)
            assert abs(area - expected_area) / expected_area < 0.01
    finally:
        view.close()


def test_image_rows_are_top_first_and_columns_left_first(shader_dir):
    camera = CameraModel.default(128)
    R_cr = R_camera_from_runway(0.0, 0.0, 0.0, (0.0, 0.0, 0.0))
    p_cam = np.array([0.0, 0.0, -100.0])
    # camera looks along runway +x; image x = runway +y, image y = runway +z (down)
    corners = np.array([[100.0, -30.0, -130.0], [100.0, -20.0, -130.0], [100.0, -20.0, -120.0], [100.0, -30.0, -120.0]])
    view = OffscreenView(camera, shader_dir, samples=0, anisotropy=1)
    try:
        rgb = view.render(_marker_scene(corners), p_cam, R_cr, 1.0, 1000.0)
    finally:
        view.close()
    rows, cols = np.nonzero(rgb[..., 0] > 128)
    assert rows.max() < 64 and cols.max() < 64   # up and to the left: top-left quadrant


def test_closing_one_view_leaves_the_others_rendering(shader_dir):
    """Two views in one process (the EGL display is shared): closing one must not end the other,
    which renders the same bytes after as before and closes cleanly (pyrender's own close
    terminated the display: the other's next render failed with EGL_BAD_DISPLAY)."""
    camera = CameraModel.default(64)
    R_cr = R_camera_from_runway(0.0, 0.0, 0.0, (0.0, 0.0, 0.0))
    p_cam = np.array([0.0, 0.0, -100.0])
    corners = [[100.0, -30.0, -130.0], [100.0, -20.0, -130.0], [100.0, -20.0, -120.0], [100.0, -30.0, -120.0]]
    scene = _marker_scene(corners)                     # a pyrender scene is bound to one context: one each
    kept, closed = OffscreenView(camera, shader_dir, samples=0), OffscreenView(camera, shader_dir, samples=0)
    try:
        before = kept.render(scene, p_cam, R_cr, 1.0, 1000.0)
        assert np.array_equal(closed.render(_marker_scene(corners), p_cam, R_cr, 1.0, 1000.0), before)
        closed.close()
        assert before.max() == 255 and np.array_equal(kept.render(scene, p_cam, R_cr, 1.0, 1000.0), before)
        again = OffscreenView(camera, shader_dir, samples=0)         # a view opened after a close works too
        assert np.array_equal(again.render(_marker_scene(corners), p_cam, R_cr, 1.0, 1000.0), before)
        again.close()
    finally:
        kept.close()


def test_projection_matrix_maps_pixel_centres_to_half_integer_windows():
    camera = CameraModel(200, 100, fx=150.0, fy=160.0, cx=90.3, cy=40.7)
    P = gl_projection_matrix(camera, 0.5, 1000.0)
    p_C = np.array([[0.3, -0.2, 5.0], [-1.0, 0.4, 12.0]])
    uv, _ = camera.project(p_C)
    p_G = p_C * np.array([1.0, -1.0, -1.0])
    clip = (P @ np.c_[p_G, np.ones(2)].T).T
    ndc = clip[:, :2] / clip[:, 3:4]
    window = (ndc + 1.0) / 2.0 * np.array([camera.width, camera.height])
    np.testing.assert_allclose(window, uv + 0.5, atol=1e-9)


def test_camera_pose_is_the_inverse_view():
    R_cr = rot_z(0.3) @ rot_y(-0.1) @ rot_x(0.05)
    p = np.array([-1000.0, 20.0, -50.0])
    T = gl_camera_pose(p, R_cr)
    point_R = np.array([200.0, -10.0, 0.0])
    point_G = np.linalg.inv(T) @ np.r_[point_R, 1.0]
    point_C = R_cr @ (point_R - p)
    np.testing.assert_allclose(point_G[:3], point_C * np.array([1.0, -1.0, -1.0]), atol=1e-9)


def test_bad_pose_and_clip_planes_are_refused():
    with pytest.raises(ValueError, match="R_camera_from_runway"):
        gl_camera_pose([0, 0, -10], np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(ValueError, match="p_runway_m"):
        gl_camera_pose([0, np.nan, -10], np.eye(3))
    with pytest.raises(ValueError, match="znear_m"):
        gl_projection_matrix(CameraModel.default(64), 10.0, 5.0)


def test_missing_egl_library_is_named_with_the_packages_to_install():
    with pytest.raises(RenderingUnavailable) as info:
        check_opengl(libraries=("libEGL-definitely-missing.so.1",))
    message = str(info.value)
    assert "libEGL-definitely-missing.so.1" in message
    assert "libegl1" in message and "libegl-mesa0" in message and "apt-get install" in message
    assert "\n" not in message
