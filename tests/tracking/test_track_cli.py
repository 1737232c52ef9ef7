"""``visland track`` and ``visland bench track`` end to end on a small synthetic frame folder."""
import json
import math

import cv2
import numpy as np
import pytest

from visland.cli import main
from visland.contracts import (LABEL_COLUMNS, MEASUREMENT_COLUMNS, TELEMETRY_COLUMNS, read_frames_csv,
                               read_measurements, write_csv)
from visland.runway import CORNER_NAMES


@pytest.fixture(scope="module")
def folder(approach, tmp_path_factory):
    """A SPEC frame folder: the approach fixture's frames, their labels, full telemetry, camera.json."""
    root = tmp_path_factory.mktemp("trackfolder")
    (root / "frames").mkdir()
    for j, image in enumerate(approach.images):
        cv2.imwrite(str(root / "frames" / f"{j:06d}.png"), image)
    result = approach.result
    times = result.frames.t_s[approach.indices]
    write_csv(root / "frames.csv", {"frame": list(range(len(times))), "t_s": times})
    write_csv(root / "telemetry.csv", result.imu.as_columns(), TELEMETRY_COLUMNS)
    labels = {k: np.asarray(v)[approach.indices] for k, v in result.label_columns().items()}
    labels["frame"] = np.arange(len(times))
    write_csv(root / "labels.csv", labels, LABEL_COLUMNS)
    approach.camera.save(root / "camera.json")
    return root


def run(args, capsys):
    code = main(args)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_track_labels_designation_writes_measurements(folder, approach, tmp_path, capsys):
    out = tmp_path / "m.csv"
    code, stdout, _ = run(["track", str(folder), "--out", str(out)], capsys)
    assert code == 0, stdout
    table = read_measurements(out)
    assert table.column_order[:len(MEASUREMENT_COLUMNS)] == list(MEASUREMENT_COLUMNS)
    assert np.all(table["found"] == 1)
    assert set(table["source"]) == {"tracking"}
    for k, name in enumerate(CORNER_NAMES):
        error = np.hypot(table[f"{name}_u_px"] - approach.corners_uv[:, k, 0],
                         table[f"{name}_v_px"] - approach.corners_uv[:, k, 1])
        assert np.nanmax(error) < 0.5
        assert np.all(table[f"{name}_visible"] == 1)
    assert np.all(np.isnan(table["left_rho"])) and np.all(np.isnan(table["dF_px"]))
    assert np.all(table["confidence"][1:] > 0.8)
    assert "near_left" in stdout and "median px" in stdout


def test_track_command_line_designation_reports_refused_points(folder, approach, tmp_path, capsys):
    out = tmp_path / "m.csv"
    u, v = approach.corners_uv[0, 0]
    code, stdout, _ = run(["track", str(folder), "--out", str(out), "--init", f"{u},{v};900,40"], capsys)
    assert code == 0
    table = read_measurements(out)
    assert np.all(table["found"] == 0)                      # P'' was never tracked
    assert all("near_right refused (designated at (900.0, 40.0), outside the 512x512 image)" in r
               for r in table["reason"])
    assert np.all(np.isnan(table["near_right_u_px"])) and np.all(table["near_right_visible"] == 0)
    assert np.all(np.isfinite(table["near_left_u_px"]))
    assert np.all(np.isnan(table["far_left_visible"]))       # not designated at all


def test_a_frame_of_another_size_is_flagged_in_its_row(folder, approach, tmp_path, capsys):
    bad = tmp_path / "bad"
    import shutil
    shutil.copytree(folder, bad)
    cv2.imwrite(str(bad / "frames" / "000005.png"), approach.images[5][:300, :300])
    out = tmp_path / "m.csv"
    code, _, _ = run(["track", str(bad), "--out", str(out)], capsys)
    assert code == 0
    table = read_measurements(out)
    assert table["found"][5] == 0 and "image is 300x300, camera.json says 512x512" in table["reason"][5]
    assert np.all(np.isnan(table["near_left_u_px"][5]))
    assert np.all(table["found"][6:] == 1)


def test_anchored_tracking_copies_the_anchor_lines(folder, tmp_path, capsys):
    out = tmp_path / "m.csv"
    code, _, _ = run(["track", str(folder), "--out", str(out), "--anchor", "labels", "--anchor-every", "2"], capsys)
    assert code == 0
    table = read_measurements(out)
    anchored = table["source"] == "anchored"
    index = np.arange(len(anchored))
    np.testing.assert_array_equal(anchored, (index % 2 == 0) & (index > 0))   # frame 0 is the designation
    assert np.all(np.isfinite(table["left_rho"][anchored])) and np.all(np.isnan(table["left_rho"][~anchored]))
    assert np.all(np.isfinite(table["dpsi_deg"][anchored]))


def test_bad_arguments_fail_with_one_clear_line(folder, tmp_path, capsys):
    out = tmp_path / "m.csv"
    out.write_text("x\n")
    code, _, err = run(["track", str(folder), "--out", str(out)], capsys)
    assert code == 2 and "output file exists" in err
    code, _, err = run(["track", str(folder), "--out", str(tmp_path / "n.csv"), "--init", "12;4,5"], capsys)
    assert code == 2 and "entry 1 ('12') is not a pixel position 'u,v'" in err
    code, _, err = run(["track", str(tmp_path / "nowhere"), "--out", str(tmp_path / "n.csv")], capsys)
    assert code == 2 and "input folder not found" in err
    code, _, err = run(["track", str(folder), "--out", str(tmp_path / "n.csv"), "--start", "99"], capsys)
    assert code == 2 and "--start must be a frame index" in err


def test_frames_csv_option_replaces_the_folders_frame_times(folder, tmp_path, capsys):
    times = np.asarray(read_frames_csv(folder / "frames.csv")["t_s"])
    short = tmp_path / "short.csv"          # one frame listed for the folder's several: refused, naming this file
    write_csv(short, {"frame": [0], "t_s": times[:1]})
    code, _, err = run(["track", str(folder), "--out", str(tmp_path / "n.csv"), "--frames-csv", str(short)], capsys)
    assert code == 2 and f"{short}: lists 1 frames" in err
    copy = tmp_path / "copy.csv"
    write_csv(copy, {"frame": list(range(len(times))), "t_s": times})
    out = tmp_path / "m.csv"
    code, stdout, _ = run(["track", str(folder), "--out", str(out), "--frames-csv", str(copy)], capsys)
    assert code == 0, stdout
    np.testing.assert_array_equal(read_measurements(out)["t_s"], times)


def test_params_file_and_policy_option(folder, tmp_path, capsys):
    params = tmp_path / "tracker.toml"
    params.write_text('[tracker]\nupdate_policy = "never"\ntemplate_size_px = 15\n')
    out = tmp_path / "m.csv"
    code, stdout, _ = run(["track", str(folder), "--out", str(out), "--params", str(params)], capsys)
    assert code == 0 and "policy never" in stdout
    code, stdout, _ = run(["track", str(folder), "--out", str(out), "--params", str(params), "--policy",
                           "every_n", "--force"], capsys)
    assert code == 0 and "policy every_n" in stdout
    params.write_text('[tracker]\ntemplate_size_px = 14\n')
    code, _, err = run(["track", str(folder), "--out", str(tmp_path / "n.csv"), "--params", str(params)], capsys)
    assert code == 2 and "template_size_px must be odd" in err


@pytest.mark.slow
def test_bench_track_ends_with_a_json_line(capsys):
    code, stdout, _ = run(["bench", "track", "--size", "256", "--frames", "8", "--repeats", "2",
                           "--distance", "900"], capsys)
    assert code == 0
    figures = json.loads(stdout.strip().splitlines()[-1])
    assert figures["bench"] == "track" and figures["size"] == 256 and len(figures["fps_runs"]) == 2
    assert figures["fps_median"] > 0 and math.isfinite(figures["final_error_px_max"])
    assert figures["points_lost_at_end"] == 0


def test_track_source_takes_any_frame_source(folder, approach):
    """A source with frames() (as visland.datasets' sources): unusable frames are flagged, not dropped."""
    from visland.folder import FrameFolder
    from visland.tracking import track_source

    class Source:
        def __init__(self):
            self.inner = FrameFolder(folder)
            self.name, self.camera, self.times_s = "memory", self.inner.camera, self.inner.times_s
            self.inertial, self.labels = self.inner.inertial, self.inner.labels

        def __len__(self):
            return len(self.inner)

        def frames(self, gray=True):
            for j, image in enumerate(approach.images):
                yield (j, None, f"frame {j}: decoder error") if j == 4 else (j, image, None)

    run = track_source(Source(), init=None, anchor=False, start=1)
    assert run.flagged == [(4, "frame 4: decoder error")]
    assert run.columns["found"][0] == 0 and run.columns["reason"][0] == "before the designation"
    assert run.columns["found"][4] == 0 and "decoder error" in run.columns["reason"][4]
    assert all(f == 1 for f in run.columns["found"][5:])
    assert run.analysis_s > 0


def test_edge_points_are_tracked_and_written_as_extra_columns(folder, approach, tmp_path, capsys):
    out = tmp_path / "m.csv"
    code, stdout, _ = run(["track", str(folder), "--out", str(out), "--edge-points", "1"], capsys)
    assert code == 0
    table = read_measurements(out)
    for side, (near, far) in (("left", (0, 2)), ("right", (1, 3))):
        u, v = table[f"{side}_edge_1_u_px"], table[f"{side}_edge_1_v_px"]
        assert np.all(np.isfinite(u))
        # an edge point stays on its edge: distance to the line through the labelled corners
        a, b = approach.corners_uv[:, near], approach.corners_uv[:, far]
        d = b - a
        across = np.abs((u - a[:, 0]) * d[:, 1] - (v - a[:, 1]) * d[:, 0]) / np.hypot(d[:, 0], d[:, 1])
        assert np.max(across) < 0.5
        assert np.all(np.isfinite(table[f"{side}_edge_1_score"][1:]))
    assert "left_edge_1" in stdout


def test_the_command_registration_stays_light():
    """Importing the stage's CLI module (done for every visland command) must not load OpenCV."""
    import subprocess
    import sys
    code = "import sys, visland.tracking.cli; print('cv2' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"
