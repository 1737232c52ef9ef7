"""`visland mask`: the aircraft's structure on a synthetic cockpit sequence with known pixels."""
import cv2
import numpy as np
import pytest

from visland.cli import main
from visland.structure_mask import MaskParams, propose_structure_mask

from tests.helpers.cockpit_frames import HORIZON_V, SIZE, cockpit_frames


@pytest.fixture(scope="module")
def cockpit():
    return cockpit_frames(n_frames=30, seed=2)


def test_mask_covers_the_structure_and_not_the_sky(cockpit):
    frames, truth = cockpit
    result = propose_structure_mask(frames)
    assert result.mask.shape == truth.shape
    assert result.mask[truth].mean() >= 0.95
    assert result.mask[~truth].mean() < 0.02
    # the static sky (as steady as the structure) is not taken, away from the pillars' edges
    sky = np.zeros_like(truth)
    sky[:HORIZON_V - 8] = True
    sky &= cv2.dilate(truth.astype(np.uint8), np.ones((15, 15), np.uint8)) == 0
    assert result.mask[sky].mean() < 0.001


def test_automatic_exposure_and_a_shaking_camera(cockpit):
    """Exposure swinging +-25 % (the wiper's grey would vary 3x the static threshold) and the
    camera shaking by up to two pixels (the seam between wiper and frame flickers): without the
    exposure compensation 92 % of the structure is found, without linking parts across the seam
    the wiper is lost (measured)."""
    frames, truth = cockpit_frames(n_frames=30, seed=2, exposure_swing=0.25, shake_px=2)
    result = propose_structure_mask(frames)
    assert result.mask[truth].mean() >= 0.95
    assert result.mask[~truth].mean() < 0.02
    # the wiper, whose seam with the frame is unsteady, is still attached and masked
    wiper_middle = (300, 480)       # (v, u) on the wiper bar, over the moving ground
    assert result.mask[wiper_middle]


def test_variance_alone_would_take_the_sky(cockpit):
    """The sky is as static as the structure: the dark/static-edge rule is what keeps it out."""
    frames, truth = cockpit
    std = np.std(np.asarray(frames, float), axis=0)
    assert (std[:HORIZON_V - 8] <= MaskParams().max_static_std).mean() > 0.95


def test_footage_that_does_not_move_is_refused(cockpit):
    frames, _ = cockpit
    with pytest.raises(ValueError, match="changes over the 8 frames"):
        propose_structure_mask([frames[0]] * 8, source="still.mp4")


@pytest.mark.slow
def test_mask_command_writes_mask_picture_and_camera_line(cockpit, tmp_path, capsys):
    frames, truth = cockpit
    folder = tmp_path / "clip" / "frames"
    folder.mkdir(parents=True)
    for k, frame in enumerate(frames):
        cv2.imwrite(str(folder / f"{k:04d}.png"), frame)
    out = tmp_path / "cam" / "masks" / "mask.png"
    out.parent.mkdir(parents=True)
    camera = tmp_path / "cam" / "camera.json"
    assert main(["calibrate", "--hfov-deg", "70", "--size", f"{SIZE[0]}x{SIZE[1]}", "--out", str(camera)]) == 0
    assert main(["mask", str(tmp_path / "clip"), "--out", str(out), "--camera", str(camera), "--samples", "20"]) == 0
    printed = capsys.readouterr().out
    assert '"mask": "masks/mask.png"' in printed
    mask = cv2.imread(str(out), cv2.IMREAD_UNCHANGED)
    assert mask.shape == truth.shape and set(np.unique(mask)) <= {0, 255}
    assert (mask[truth] == 255).mean() >= 0.95 and (mask[~truth] == 255).mean() < 0.02
    picture = cv2.imread(str(out.with_name("mask-check.png")))
    assert picture.shape[0] == SIZE[1] and picture.shape[1] > 2 * SIZE[0]
    # a camera of another size is one sentence
    other = tmp_path / "other.json"
    assert main(["calibrate", "--hfov-deg", "70", "--size", "320x240", "--out", str(other)]) == 0
    capsys.readouterr()
    assert main(["mask", str(tmp_path / "clip"), "--out", str(tmp_path / "m2.png"), "--camera", str(other)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "320x240" in err[0] and "640x480" in err[0]


def test_update_camera_writes_the_mask_field_that_camera_json_reads(cockpit, tmp_path, capsys):
    import json

    from visland.camera import CameraModel
    frames, truth = cockpit
    folder = tmp_path / "clip"
    folder.mkdir()
    for k, frame in enumerate(frames[::3]):
        cv2.imwrite(str(folder / f"{k:04d}.png"), frame)
    camera_path = tmp_path / "camera.json"
    assert main(["calibrate", "--hfov-deg", "70", "--size", f"{SIZE[0]}x{SIZE[1]}", "--out", str(camera_path)]) == 0
    # the line was added before the mask existed: the command must still run (it does not read that mask)
    data = json.loads(camera_path.read_text())
    data["mask"] = "mask.png"
    camera_path.write_text(json.dumps(data))
    out = tmp_path / "mask.png"
    assert main(["mask", str(folder), "--out", str(out), "--camera", str(camera_path), "--update-camera"]) == 0
    assert json.loads(camera_path.read_text())["mask"] == "mask.png"
    camera = CameraModel.load(camera_path)
    structure = camera.structure_mask()
    assert structure[truth].mean() >= 0.95 and structure[~truth].mean() < 0.02
