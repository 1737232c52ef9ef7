"""visland generate: dataset files, resumption, refusal of foreign folders, disk errors, workers, Dask, LARD."""
import argparse
import errno
import hashlib
import json
import shutil

import numpy as np
import pytest

from visland.camera import CameraModel
from visland.contracts import read_labels
from visland.datasets import generate as gen
from visland.datasets import generate_cli
from visland.folder import FrameFolder
from visland.render.params import SceneParams
from visland.scenarios import Scenario
from visland.simulate import SimulationOptions

SIZE = 96


def _scenario(name="short", dy_m=30.0):
    return Scenario(name, dx_m=-1500.0, dy_m=dy_m, dgs_m=0.0, dpsi_deg=0.0)


def _job(name="short", fps=2.0, lard=False, **scene):
    options = SimulationOptions(fps=fps, camera=CameraModel.default(SIZE), seed=3)
    return gen.GenerateJob(_scenario(name), options, SceneParams(seed=3, **scene), png_compression=1, lard=lard)


def _tree_digest(folder):
    """SHA-256 of every file (relative path -> digest), to compare whole datasets byte for byte."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("ref") / "ds"
    report = gen.generate_dataset(_job(lard=True), out, progress=False)
    return out, report


@pytest.mark.slow
def test_dataset_holds_the_spec_files_and_checksums(reference):
    out, report = reference
    assert report.rendered == report.n_frames > 10
    for name in ("frames.csv", "telemetry.csv", "truth.csv", "labels.csv", "camera.json", "runway.json",
                 "manifest.json", "lard/labels.csv"):
        assert (out / name).is_file(), name
    assert not (out / gen.JOB_FILE).exists()
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["n_frames"] == report.n_frames == len(manifest["frames"])
    assert manifest["seeds"] == {"simulation": 3, "imu": 0, "scene": 3}
    assert manifest["scene"]["seed"] == 3 and manifest["software"].startswith("visland ")
    for entry in manifest["frames"]:
        assert hashlib.sha256((out / entry["file"]).read_bytes()).hexdigest() == entry["sha256"]
    # the folder is a valid SPEC frame folder, one label row per frame, frames of the camera's size
    folder = FrameFolder(out)
    assert len(folder) == report.n_frames
    image, reason = folder.read_frame(len(folder) - 1, gray=False)
    assert reason is None and image.shape == (SIZE, SIZE, 3)
    assert read_labels(out / "labels.csv").n_rows == report.n_frames
    names = sorted(p.name for p in (out / "frames").iterdir())
    assert names[0] == "000000.png" and names[-1] == f"{report.n_frames - 1:06d}.png"


@pytest.mark.slow
def test_rerun_of_a_complete_dataset_does_nothing(reference):
    out, _ = reference
    before = _tree_digest(out)
    report = gen.generate_dataset(_job(lard=True), out, progress=False)
    assert report.already_complete and report.rendered == 0
    assert _tree_digest(out) == before


@pytest.mark.slow
def test_interrupted_run_resumes_to_identical_bytes(reference, tmp_path):
    ref, report = reference
    out = tmp_path / "ds"
    shutil.copytree(ref, out)
    # the state a killed job leaves: no manifest, its job file, some frames missing, a half-written temp file
    (out / "manifest.json").unlink()
    (out / gen.JOB_FILE).write_text(json.dumps(_job(lard=True).identity()))
    missing = [0, 5, report.n_frames - 1]
    for i in missing:
        (out / "frames" / gen.frame_name(i)).unlink()
    (out / "frames" / ".000005.png.abcd.tmp").write_bytes(b"half a frame")
    resumed = gen.generate_dataset(_job(lard=True), out, progress=False)
    assert resumed.rendered == len(missing) and resumed.reused == report.n_frames - len(missing)
    assert _tree_digest(out) == _tree_digest(ref)


@pytest.mark.slow
def test_full_disk_stops_with_a_clear_message_and_resumes(reference, tmp_path, monkeypatch):
    ref, report = reference
    out = tmp_path / "ds"
    real_write = gen.atomic_write_bytes
    calls = {"n": 0}

    def write_until_full(path, data):
        calls["n"] += 1
        if calls["n"] > 4:
            raise OSError(errno.ENOSPC, "No space left on device")
        real_write(path, data)

    monkeypatch.setattr(gen, "atomic_write_bytes", write_until_full)
    with pytest.raises(ValueError) as info:
        gen.generate_dataset(_job(lard=True), out, progress=False)
    message = str(info.value)
    assert "No space left on device" in message and "frame" in message and "resumes" in message
    assert "\n" not in message
    written = sorted((out / "frames").glob("*.png"))
    assert len(written) == 4 and not (out / "manifest.json").exists()
    for path in written:   # what was written is valid: the same bytes as the uninterrupted run
        assert path.read_bytes() == (ref / "frames" / path.name).read_bytes()
    monkeypatch.setattr(gen, "atomic_write_bytes", real_write)
    gen.generate_dataset(_job(lard=True), out, progress=False)
    assert _tree_digest(out) == _tree_digest(ref)


def test_read_only_output_names_the_cause(tmp_path, monkeypatch):
    def read_only(path, data):
        raise OSError(errno.EROFS, "Read-only file system")

    monkeypatch.setattr(gen, "atomic_write_bytes", read_only)
    monkeypatch.setattr(gen, "atomic_write_text", lambda path, text: read_only(path, text))
    with pytest.raises(ValueError, match="Read-only file system.*writable --out"):
        gen.generate_dataset(_job(), tmp_path / "ds", progress=False)


@pytest.mark.slow
def test_folder_of_another_job_or_foreign_content_is_refused(reference, tmp_path):
    out, _ = reference
    before = _tree_digest(out)
    with pytest.raises(ValueError, match="another job.*scenario 'short' differs from 'other'"):
        gen.generate_dataset(_job(name="other", lard=True), out, progress=False)
    with pytest.raises(ValueError, match="another job.*scene differs"):
        gen.generate_dataset(_job(lard=True, surface="concrete"), out, progress=False)
    assert _tree_digest(out) == before
    foreign = tmp_path / "photos"
    foreign.mkdir()
    (foreign / "holiday.jpg").write_bytes(b"not ours")
    with pytest.raises(ValueError, match="not a visland dataset"):
        gen.generate_dataset(_job(), foreign, progress=False)
    assert (foreign / "holiday.jpg").read_bytes() == b"not ours"


@pytest.mark.slow
def test_another_software_version_is_refused(reference, tmp_path):
    ref, _ = reference
    out = tmp_path / "ds"
    shutil.copytree(ref, out)
    manifest = json.loads((out / "manifest.json").read_text())
    manifest["software"] = "visland 0.0.1"
    (out / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(ValueError, match="made by 'visland 0.0.1'"):
        gen.generate_dataset(_job(lard=True), out, progress=False)


@pytest.mark.slow
def test_two_worker_processes_give_the_same_bytes(reference, tmp_path):
    ref, _ = reference
    out = tmp_path / "ds"
    gen.generate_dataset(_job(lard=True), out, workers=2, progress=False)
    assert _tree_digest(out) == _tree_digest(ref)


@pytest.mark.slow
def test_dask_local_cluster_gives_the_same_bytes(reference, tmp_path):
    from distributed import LocalCluster
    ref, _ = reference
    out = tmp_path / "ds"
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        gen.generate_dataset(_job(lard=True), out, scheduler=cluster.scheduler_address, progress=False)
    assert _tree_digest(out) == _tree_digest(ref)


@pytest.mark.slow
def test_unreachable_scheduler_is_one_sentence(tmp_path):
    with pytest.raises(ValueError, match="cannot reach the Dask scheduler at tcp://127.0.0.1:9"):
        gen.generate_dataset(_job(), tmp_path / "ds", scheduler="tcp://127.0.0.1:9", progress=False)


@pytest.mark.slow
def test_lard_labels_map_the_corners_and_use_lard_units(reference):
    out, _ = reference
    labels = read_labels(out / "labels.csv")
    truth = np.genfromtxt(out / "truth.csv", delimiter=",", names=True)
    lard = np.genfromtxt(out / "lard" / "labels.csv", delimiter=";", names=True, dtype=None, encoding="utf-8")
    for lard_corner, ours in (("TR", "far_right"), ("TL", "far_left"), ("BL", "near_left"), ("BR", "near_right")):
        np.testing.assert_allclose(lard[f"x_{lard_corner}"], labels[f"{ours}_u_px"], atol=1e-6)
        np.testing.assert_allclose(lard[f"y_{lard_corner}"], labels[f"{ours}_v_px"], atol=1e-6)
    np.testing.assert_allclose(lard["height_above_runway"], truth["dh_m"] / 0.3048, rtol=1e-8)
    along_nm = -(truth["dx_m"] + 320.0) / 1852.0
    np.testing.assert_allclose(lard["along_track_distance"], along_nm, rtol=1e-8)
    import csv
    with open(out / "lard" / "labels.csv", newline="") as handle:
        first = next(csv.DictReader(handle, delimiter=";"))
    assert first["image"] == "frames/000000.png" and first["runway"] == "04"
    # a horizontal optical axis would read 90; the camera looks a few degrees down on approach
    assert np.all((lard["pitch"] > 80.0) & (lard["pitch"] < 95.0))


def _cli(argv):
    parser = argparse.ArgumentParser(prog="visland")
    generate_cli.register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(argv)
    return args.func(args)


@pytest.mark.parametrize("argv, message", [
    (["--size", "32"], r"--size must lie in \[64, 4096\] px, got 32"),
    (["--size", "9000"], r"--size must lie in \[64, 4096\] px, got 9000"),
    (["--fps", "60"], r"--fps must lie in \[1, 50\] frames per second"),
    (["--workers", "0"], r"--workers must lie in \[1, 64\], got 0"),
    (["--workers", "65"], r"--workers must lie in \[1, 64\], got 65"),
    (["--png-compression", "12"], r"--png-compression must lie in \[0, 9\], got 12"),
])
def test_out_of_range_arguments_are_one_sentence(argv, message, tmp_path):
    with pytest.raises(ValueError, match=message):
        _cli(["generate", "--scenario", "thesis-1", "--out", str(tmp_path / "ds")] + argv)
    assert not (tmp_path / "ds").exists()


@pytest.mark.slow
def test_cli_generates_a_small_dataset(tmp_path, capsys):
    out = tmp_path / "ds"
    code = _cli(["generate", "--scenario", "thesis-1", "--out", str(out), "--size", "64", "--fps", "1",
                 "--no-progress", "--flat", "--runway", "regional"])
    assert code == 0
    assert "frames" in capsys.readouterr().out
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["scene"]["style"] == "flat" and manifest["scenario"]["runway"]["width_m"] == 30.0
    assert manifest["image_size"] == [64, 64]



@pytest.mark.slow
def test_variety_and_runway_size_reach_runway_json_labels_and_manifest(tmp_path):
    """--variety draws the runway and the scene; --runway-width and --markings override the draw;
    runway.json and labels.csv follow the varied runway: the threshold's image span scales with
    the width (same approach over a 45 m runway of the same length: ratio 27.5 / 45)."""
    from visland.render.variety import draw_variety
    spans = {}
    for width in ("27.5", "45"):
        out = tmp_path / f"ds{width}"
        code = _cli(["generate", "--scenario", "thesis-3", "--out", str(out), "--size", "64", "--fps", "1",
                     "--no-progress", "--variety", "5", "--runway-width", width, "--markings", "blast_pad"])
        assert code == 0
        labels = read_labels(out / "labels.csv")
        spans[width] = np.asarray(labels["near_right_u_px"], float) - np.asarray(labels["near_left_u_px"], float)
    drawn = draw_variety(5)
    runway = json.loads((tmp_path / "ds27.5" / "runway.json").read_text())
    assert runway["length_m"] == drawn.runway_length_m and runway["width_m"] == 27.5
    manifest = json.loads((tmp_path / "ds27.5" / "manifest.json").read_text())
    assert manifest["scene"] == json.loads(json.dumps(dict(drawn.scene.to_dict(), markings="blast_pad")))
    ratio = spans["27.5"][:10] / spans["45"][:10]
    assert np.allclose(ratio, 27.5 / 45.0, rtol=0.01), ratio


def test_distortion_option_is_checked_in_one_sentence(tmp_path):
    with pytest.raises(ValueError, match=r"--distortion must be five numbers k1,k2,p1,p2,k3, got '0.1,x'"):
        _cli(["generate", "--scenario", "thesis-1", "--out", str(tmp_path / "ds"), "--distortion", "0.1,x"])
    assert not (tmp_path / "ds").exists()



@pytest.mark.slow
def test_distortion_option_reaches_camera_json_and_the_frames(tmp_path):
    """--distortion: camera.json carries the lens, labels stay pinhole (identical to the run
    without it), and the frames are not the pinhole ones."""
    import cv2
    for name, extra in (("lens", ["--distortion=-0.2,0.03,0,0,0"]), ("pinhole", [])):
        assert _cli(["generate", "--scenario", "thesis-3", "--out", str(tmp_path / name), "--size", "64", "--fps",
                     "1", "--no-progress", "--flat"] + extra) == 0
    camera = json.loads((tmp_path / "lens" / "camera.json").read_text())
    assert camera["distortion"] == [-0.2, 0.03, 0.0, 0.0, 0.0]
    assert (tmp_path / "lens" / "labels.csv").read_text() == (tmp_path / "pinhole" / "labels.csv").read_text()
    last = sorted((tmp_path / "lens" / "frames").glob("*.png"))[-1].name
    lens = cv2.imread(str(tmp_path / "lens" / "frames" / last))
    pinhole = cv2.imread(str(tmp_path / "pinhole" / "frames" / last))
    assert np.abs(lens.astype(int) - pinhole.astype(int)).max() > 100
