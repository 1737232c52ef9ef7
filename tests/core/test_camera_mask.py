"""The aircraft's own structure in camera.json (issue 18 item 1): polygons or a mask image,
checked when read, filled from the scene before detection and tracking see the frame."""
import json

import cv2
import numpy as np
import pytest

from visland.camera import CameraModel
from visland.folder import ignored_pixels, scene_frame

SQUARE = ((10.0, 50.0), (40.0, 50.0), (40.0, 63.0), (10.0, 63.0))


def _camera_json(tmp_path, **extra):
    data = CameraModel.from_fov(80, 64, 50.0).to_json_dict() | extra
    path = tmp_path / "camera.json"
    path.write_text(json.dumps(data))
    return path


def test_mask_polygons_round_trip_through_camera_json(tmp_path):
    camera = CameraModel.load(_camera_json(tmp_path, mask=[[list(v) for v in SQUARE]]))
    assert camera.mask == (SQUARE,)
    mask = camera.structure_mask()
    # fillPoly with pixel centres on the integer grid: columns 10..40, rows 50..63 inclusive
    assert mask[50:64, 10:41].all() and mask.sum() == 31 * 14
    assert CameraModel.from_json_dict(camera.to_json_dict()).mask == camera.mask


def test_mask_image_beside_camera_json(tmp_path):
    image = np.zeros((64, 80), np.uint8)
    image[:8] = 255
    cv2.imwrite(str(tmp_path / "mask.png"), image)
    camera = CameraModel.load(_camera_json(tmp_path, mask="mask.png"))
    assert camera.mask == str((tmp_path / "mask.png").resolve())
    assert np.array_equal(camera.structure_mask(), image > 0)


@pytest.mark.parametrize("mask, message", [
    ("missing.png", "not found"),
    ("wrong_size.png", "is 40x32 px, the camera's frames are 80x64"),
    ("everything.png", "nothing would be left to see"),
    ([[[0, 0], [1, 1]]], "polygon 0 must be a list of at least 3"),
    ([[[0, 0], [1, "a"], [2, 2]]], "not two finite pixel coordinates"),
    (12, "must be a list of polygons"),
])
def test_bad_masks_are_one_sentence_naming_the_file(tmp_path, mask, message):
    cv2.imwrite(str(tmp_path / "wrong_size.png"), np.zeros((32, 40), np.uint8))
    cv2.imwrite(str(tmp_path / "everything.png"), np.full((64, 80), 255, np.uint8))
    path = _camera_json(tmp_path, mask=mask)
    with pytest.raises(ValueError) as error:
        CameraModel.load(path)
    text = str(error.value)
    assert str(path) in text and message in text and "\n" not in text


def test_scene_frame_fills_the_structure_without_an_edge():
    """A ramp scene with a dark bar across it: the bar is filled with the ramp, and nothing
    outside the grown mask changes."""
    camera = CameraModel.from_fov(128, 96, 50.0, mask=(((30.0, 40.0), (100.0, 40.0), (100.0, 52.0), (30.0, 52.0)),))
    u = np.arange(128, dtype=float)
    scene = np.tile(60.0 + u, (96, 1)).astype(np.uint8)
    frame = scene.copy()
    frame[40:53, 30:101] = 5
    filled = scene_frame(frame, camera)
    ignored = ignored_pixels(camera)
    assert np.array_equal(filled[~ignored], frame[~ignored])
    # the fill continues the ramp: within a few grey levels of the scene, no step at the outline
    assert np.abs(filled[ignored].astype(float) - scene[ignored]).max() < 10.0     # measured 7
    rows = filled[30:64, 60].astype(float)
    assert np.abs(np.diff(rows)).max() < 3.0


def test_outside_the_lens_is_ignored_and_filled():
    """Pincushion distortion: the pinhole image's corners see past the frame; they are ignored."""
    camera = CameraModel.from_fov(160, 120, 70.0, distortion=(0.3, 0.05, 0.0, 0.0, 0.0))
    ignored = ignored_pixels(camera)
    assert ignored[0, 0] and ignored[-1, -1] and not ignored[60, 80]
    frame = np.full((120, 160), 120, np.uint8)
    filled = scene_frame(frame, camera)
    assert np.abs(filled.astype(int) - 120).max() <= 1      # no black corners (no false edges)
