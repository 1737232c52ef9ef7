"""`visland calibrate`: OpenCV's chessboard calibration against a known synthetic lens, and the
field-of-view camera.json; one-sentence errors."""
import json
import math

import cv2
import numpy as np
import pytest

from visland.camera import CameraModel
from visland.cli import main

from tests.helpers.chessboard_views import TRUE_DISTORTION, TRUE_K, TRUE_SIZE, render_views


@pytest.fixture(scope="module")
def board_folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("board")
    for i, image in enumerate(render_views(seed=3)):
        cv2.imwrite(str(folder / f"view_{i:02d}.png"), image)
    return folder


def test_calibration_recovers_the_known_lens(board_folder, tmp_path, capsys):
    out = tmp_path / "camera.json"
    assert main(["calibrate", str(board_folder), "--board", "9x6", "--square-mm", "25", "--out", str(out),
                 "--mount-deg", "0,-3,0"]) == 0
    printed = capsys.readouterr().out
    assert "board found in 12" in printed and "views used: 12" in printed
    rms = float(printed.split("RMS reprojection error ")[1].split(" px")[0])
    assert rms < 0.2
    data = json.loads(out.read_text())
    assert (data["width"], data["height"]) == TRUE_SIZE
    for key in ("fx", "fy", "cx", "cy"):
        assert data[key] == pytest.approx(TRUE_K[key], rel=0.01), key
    k1, k2, p1, p2, k3 = data["distortion"]
    assert k1 == pytest.approx(TRUE_DISTORTION[0], abs=0.02)
    assert abs(p1 - TRUE_DISTORTION[2]) < 1e-3 and abs(p2 - TRUE_DISTORTION[3]) < 1e-3
    assert data["mount_rpy_deg"] == pytest.approx([0.0, -3.0, 0.0])
    # the whole lens, not just k1: a point near the image corner moves where the true lens puts it
    camera = CameraModel.load(out)
    truth = CameraModel(*TRUE_SIZE, TRUE_K["fx"], TRUE_K["fy"], TRUE_K["cx"], TRUE_K["cy"], (0, 0, 0), TRUE_DISTORTION)
    corner_xy = np.array([[-0.5, -0.4], [0.5, 0.35], [0.3, -0.3]])
    assert np.abs(camera.normalized_to_pixels(camera.distort_normalized(corner_xy))
                  - truth.normalized_to_pixels(truth.distort_normalized(corner_xy))).max() < 1.5


def test_max_views_subsamples(board_folder, tmp_path, capsys):
    assert main(["calibrate", str(board_folder), "--square-mm", "25", "--out", str(tmp_path / "c.json"),
                 "--max-views", "6", "--examine", "12"]) == 0
    assert "views used: 6" in capsys.readouterr().out


def test_field_of_view_camera(tmp_path, capsys):
    out = tmp_path / "camera.json"
    assert main(["calibrate", "--hfov-deg", "90", "--size", "1280x720", "--out", str(out)]) == 0
    data = json.loads(out.read_text())
    # 90 deg across 1280 px: tan(45 deg) = 1, so f = 640 px
    assert data["fx"] == pytest.approx(640.0) and data["fy"] == pytest.approx(640.0)
    assert (data["width"], data["height"], data["cx"], data["cy"]) == (1280, 720, 639.5, 359.5)
    assert "distortion" not in data and data["mount_rpy_deg"] == [0.0, 0.0, 0.0]


def test_field_of_view_takes_the_size_from_footage(board_folder, tmp_path):
    out = tmp_path / "camera.json"
    assert main(["calibrate", str(board_folder), "--hfov-deg", "60", "--out", str(out)]) == 0
    data = json.loads(out.read_text())
    assert (data["width"], data["height"]) == TRUE_SIZE
    assert data["fx"] == pytest.approx(320.0 / math.tan(math.radians(30.0)))


def _error(capsys, argv):
    assert main(argv) == 2
    lines = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(lines) == 1
    return lines[0]


def test_no_board_is_one_sentence(tmp_path, capsys):
    folder = tmp_path / "blank"
    folder.mkdir()
    rng = np.random.default_rng(1)
    for i in range(3):
        cv2.imwrite(str(folder / f"{i}.png"), rng.integers(0, 255, (120, 160), dtype=np.uint8))
    message = _error(capsys, ["calibrate", str(folder), "--square-mm", "25", "--out", str(tmp_path / "c.json")])
    assert "no 9x6 chessboard found in any of the 3 frames" in message
    assert not (tmp_path / "c.json").exists()


def test_too_few_views_is_one_sentence(board_folder, tmp_path, capsys):
    folder = tmp_path / "few"
    folder.mkdir()
    for name in sorted(p.name for p in board_folder.iterdir())[:3]:
        (folder / name).write_bytes((board_folder / name).read_bytes())
    message = _error(capsys, ["calibrate", str(folder), "--square-mm", "25", "--out", str(tmp_path / "c.json")])
    assert "found in only 3 frame(s)" in message and "at least 5" in message


def test_unreadable_video_is_one_sentence(tmp_path, capsys):
    video = tmp_path / "clip.mp4"
    video.write_text("not a video")
    message = _error(capsys, ["calibrate", str(video), "--square-mm", "25", "--out", str(tmp_path / "c.json")])
    assert "clip.mp4: cannot be opened as a video" in message


def test_bad_board_and_missing_square(board_folder, tmp_path, capsys):
    out = str(tmp_path / "c.json")
    assert "COLSxROWS" in _error(capsys, ["calibrate", str(board_folder), "--board", "nine", "--square-mm", "25",
                                          "--out", out])
    assert "--square-mm" in _error(capsys, ["calibrate", str(board_folder), "--out", out])
    assert "--hfov-deg needs the frame size" in _error(capsys, ["calibrate", "--hfov-deg", "60", "--out", out])


def test_calibration_from_a_video(tmp_path, capsys):
    views = render_views(seed=5)
    video = tmp_path / "board.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 25.0, TRUE_SIZE, isColor=True)
    assert writer.isOpened()
    for image in views:
        for _ in range(3):                      # each pose held for 3 frames: 36 frames
            writer.write(cv2.cvtColor(image, cv2.COLOR_GRAY2BGR))
    writer.release()
    out = tmp_path / "camera.json"
    assert main(["calibrate", str(video), "--square-mm", "25", "--out", str(out), "--examine", "12"]) == 0
    printed = capsys.readouterr().out
    assert "36 frames, 12 examined, board found in 12" in printed
    data = json.loads(out.read_text())
    for key in ("fx", "fy", "cx", "cy"):
        assert data[key] == pytest.approx(TRUE_K[key], rel=0.01), key
    assert data["distortion"][0] == pytest.approx(TRUE_DISTORTION[0], abs=0.02)


# ----------------------------------------------------------------------------- straight lines
LINE_K = dict(fx=448.0, fy=448.0, cx=319.5, cy=239.5)     # 640x480, 71 deg across: from_fov's centre
LINE_VIEWS = [(10, 40), (25, 30), (40, 50), (70, 35)]      # (yaw, tilt) of the camera over the fields


def _field_folder(folder, k1):
    from tests.helpers.line_scene import render_fields
    folder.mkdir()
    for n, (yaw, tilt) in enumerate(LINE_VIEWS):
        cv2.imwrite(str(folder / f"{n}.png"), render_fields(LINE_K, (k1, 0.0, 0.0, 0.0, 0.0), yaw, tilt, seed=n))
    return folder


@pytest.mark.slow
def test_k1_from_straight_lines(tmp_path, capsys):
    folder = _field_folder(tmp_path / "fields", -0.12)
    hfov = math.degrees(2 * math.atan(320.0 / LINE_K["fx"]))
    out = tmp_path / "camera.json"
    assert main(["calibrate", str(folder), "--hfov-deg", f"{hfov:.6f}", "--lines", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "edge pieces" in printed
    data = json.loads(out.read_text())
    assert data["fx"] == pytest.approx(LINE_K["fx"], rel=1e-6)
    k1, k2, p1, p2, k3 = data["distortion"]
    assert k1 == pytest.approx(-0.12, abs=0.012) and (k2, p1, p2, k3) == (0.0, 0.0, 0.0, 0.0)


@pytest.mark.slow
def test_straight_lines_of_a_pinhole_lens_give_k1_near_zero(tmp_path):
    from visland.lens import estimate_k1_from_lines
    folder = _field_folder(tmp_path / "fields", 0.0)
    frames = [cv2.imread(str(p), cv2.IMREAD_GRAYSCALE) for p in sorted(folder.iterdir())]
    result = estimate_k1_from_lines(frames, **LINE_K)
    assert abs(result.k1) < 0.012 and result.pieces >= 50
    assert result.straightness_after_px < 0.2


def test_no_straight_edges_is_one_sentence(tmp_path, capsys):
    folder = tmp_path / "noise"
    folder.mkdir()
    rng = np.random.default_rng(4)
    for i in range(3):
        cv2.imwrite(str(folder / f"{i}.png"), np.full((240, 320), 128, np.uint8) + rng.integers(0, 3, (240, 320), dtype=np.uint8))
    message = _error(capsys, ["calibrate", str(folder), "--hfov-deg", "60", "--lines", "--out", str(tmp_path / "c.json")])
    assert "long straight edge pieces found in 3 frames" in message
