"""Files people have (issue 15 items 1 and 2): frames.csv naming the images, and measurement
files from another tool with only the columns that matter."""
import numpy as np
import pytest

from visland.camera import CameraModel
from visland.contracts import read_measurements
from visland.folder import FrameFolder


def _folder(tmp_path, names):
    frames = tmp_path / "frames"
    frames.mkdir()
    for name in names:
        (frames / name).write_bytes(b"")
    CameraModel.from_fov(64, 48, 50.0).save(tmp_path / "camera.json")
    return tmp_path


def test_frames_csv_may_name_the_image_files(tmp_path):
    folder = _folder(tmp_path, ["a_010.png", "a_002.png", "a_100.png"])
    # the file's order (times increasing), not the names' order
    (folder / "frames.csv").write_text("frame,t_s\na_002.png,4.92\nframes/a_010.png,5.00\na_100.png,5.12\n")
    frames = FrameFolder(folder, require_telemetry=False)
    assert [f.name for f in frames.frame_files] == ["a_002.png", "a_010.png", "a_100.png"]
    assert np.allclose(frames.times_s, [4.92, 5.00, 5.12])


def test_frames_csv_indices_still_work(tmp_path):
    folder = _folder(tmp_path, ["b.png", "a.png"])
    (folder / "frames.csv").write_text("frame,t_s\n0,0.0\n1,0.04\n")
    assert [f.name for f in FrameFolder(folder, require_telemetry=False).frame_files] == ["a.png", "b.png"]


@pytest.mark.parametrize("rows, message", [
    ("a.png,0\nc.png,0.1\n", "line 3: frame 'c.png' is not an image of"),
    ("a.png,0\na.png,0.1\n", "line 3: frame 'a.png' is listed twice"),
    ("a.png,0\n", "names 1 of the 2 images"),
    ("0,0\n2,0.1\n", "lists 2 frames 0..1 but"),
])
def test_frames_csv_names_that_do_not_match_are_one_sentence(tmp_path, rows, message):
    folder = _folder(tmp_path, ["a.png", "b.png"])
    (folder / "frames.csv").write_text("frame,t_s\n" + rows)
    with pytest.raises(ValueError) as error:
        FrameFolder(folder, require_telemetry=False)
    assert message in str(error.value) and "frames.csv" in str(error.value)


def test_a_measurement_file_from_elsewhere_needs_only_time_and_features(tmp_path):
    path = tmp_path / "corners.csv"
    path.write_text("t_s,near_left_u_px,near_left_v_px,near_right_u_px,near_right_v_px\n"
                    "0.0,10.5,40.0,20.5,40.2\n0.04,,,,\n0.08,10.7,40.4,20.9,40.6\n")
    table = read_measurements(path)
    assert list(table["frame"]) == [0, 1, 2]
    assert list(table["found"]) == [1, 0, 1]
    assert set(table["source"]) == {"external"}
    assert list(table["near_left_visible"]) == [1, 0, 1] and list(table["far_left_visible"]) == [0, 0, 0]
    assert np.isnan(table["left_rho"]).all() and np.isnan(table["confidence"]).all()


def test_a_measurement_file_without_any_feature_is_refused(tmp_path):
    path = tmp_path / "m.csv"
    path.write_text("t_s,dF_px\n0.0,1.0\n")
    with pytest.raises(ValueError, match="no corner or line columns"):
        read_measurements(path)


class _RecordedApproach:
    """A recording whose telemetry clock runs ``lag_s`` behind the frames': ray-cast frames
    (320x180) of thesis-1's first 30 s, where the aircraft banks to line up."""

    def __init__(self, lag_s: float, level: bool = False):
        from dataclasses import replace

        from tests.helpers.raycast_airport import PaintedAirport, draw_frame
        from visland.contracts import Table
        from visland.features import batch_R_camera_from_runway
        from visland.scenarios import get_scenario
        from visland.simulate import SimulationOptions, run_simulation
        scenario = get_scenario("thesis-1")
        if level:
            scenario = replace(scenario, dy_m=0.0)
        self.camera = CameraModel.from_fov(320, 180, 60.0, (0.0, -4.0, 0.0))
        sim = run_simulation(scenario, SimulationOptions(fps=5.0, camera=self.camera))
        keep = sim.frames.t_s <= 30.0
        self.times_s = sim.frames.t_s[keep]
        R = batch_R_camera_from_runway(sim.frames.roll_rad, sim.frames.pitch_rad, sim.frames.dpsi_rad,
                                       self.camera.mount_rpy_rad)
        scene = PaintedAirport(seed=3, haze_range_m=9000.0)
        self._images = [draw_frame(scene, self.camera, sim.frames.p_runway_m[i], R[i], supersample=1,
                                   rng=np.random.default_rng(i)) for i in np.nonzero(keep)[0]]
        imu = sim.imu
        self.telemetry = Table({"t_s": imu.t_s - lag_s, "roll_deg": np.degrees(imu.roll_rad)}, None,
                               ["t_s", "roll_deg"])
        self.name = "recorded approach"

    def frames(self, gray=True, prefetch=4):
        for index, image in enumerate(self._images):
            yield index, image, None


@pytest.mark.slow
def test_the_clock_offset_is_read_from_the_horizon_s_roll():
    """Telemetry stamped 0.3 s early: the offset found is +0.3 s within 0.02 s (measured
    +0.3003 s, sigma 0.0006 s, 151 frames); a straight, level record says it cannot tell."""
    from visland.clocks import estimate_time_offset
    found = estimate_time_offset(_RecordedApproach(lag_s=0.3))
    assert found.offset_s == pytest.approx(0.3, abs=0.02), found
    assert found.sigma_s < 0.02
    with pytest.raises(ValueError, match="too little roll motion"):
        estimate_time_offset(_RecordedApproach(lag_s=0.3, level=True))


def test_time_offset_moves_the_telemetry_onto_the_frames_clock(tmp_path):
    """A roll step stamped at 1.0 s in the telemetry, shifted by +0.5 s: the frames see it at 1.5 s."""
    from visland.datasets.sources import open_source
    folder = _folder(tmp_path, [f"{k:03d}.png" for k in range(31)])
    (folder / "frames.csv").write_text("frame,t_s\n" + "".join(f"{k},{0.1 * k:.1f}\n" for k in range(31)))
    rows = ["t_s,roll_deg,pitch_deg,heading_deg,p_dps,q_dps,r_dps,vn_mps,ve_mps,vd_mps"]
    for k in range(61):
        t = -1.0 + 0.1 * k
        rows.append(f"{t:.1f},{10.0 if t >= 1.0 else 0.0},0,0,0,0,0,70,0,3")
    (folder / "telemetry.csv").write_text("\n".join(rows) + "\n")
    source = open_source(folder)
    assert np.degrees(source.inertial.roll_rad[10]) == pytest.approx(10.0)
    source.shift_telemetry(0.5)
    roll = np.degrees(source.inertial.roll_rad)
    assert roll[14] == pytest.approx(0.0) and roll[15] == pytest.approx(10.0)
    # the same given when the recording is opened (--time-offset), before interpolating
    roll = np.degrees(open_source(folder, time_offset_s=0.5).inertial.roll_rad)
    assert roll[14] == pytest.approx(0.0) and roll[15] == pytest.approx(10.0)


# ---------------------------------------------------------------- issue 15 item 4: variable frame rate
def _encode_h264(folder, images, times_s, name="flight.mp4"):
    """An H.264 MP4 whose frames carry ``times_s`` (multiples of 0.04 s: a 25 Hz camera that drops
    frames), by ffmpeg's concat demuxer with per-image durations."""
    import subprocess

    import cv2
    import imageio_ffmpeg
    lines = []
    for k, image in enumerate(images):
        cv2.imwrite(str(folder / f"img{k:03d}.png"), image)
        duration = times_s[k + 1] - times_s[k] if k + 1 < len(times_s) else 0.04
        lines += [f"file 'img{k:03d}.png'", f"duration {duration:.6f}"]
    (folder / "list.txt").write_text("\n".join(lines) + "\n")
    subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-y", "-loglevel", "error", "-f", "concat", "-safe", "0",
                    "-i", str(folder / "list.txt"), "-fps_mode", "vfr", "-c:v", "libx264", "-pix_fmt", "yuv420p",
                    str(folder / name)], check=True)
    return folder / name


def _level_telemetry(path, duration_s=3.0):
    from visland.contracts import TELEMETRY_COLUMNS, write_csv
    t = np.arange(0.0, duration_s, 0.02)
    zeros = np.zeros_like(t)
    values = {"t_s": t, "roll_deg": zeros, "pitch_deg": zeros + 2.0, "heading_deg": 90.0 + 10.0 * t, "p_dps": zeros,
              "q_dps": zeros, "r_dps": zeros + 10.0, "vn_mps": zeros, "ve_mps": zeros + 70.0, "vd_mps": zeros + 3.5}
    write_csv(path, values, TELEMETRY_COLUMNS)


def test_a_video_of_variable_frame_rate_takes_its_frame_times_from_the_container(tmp_path):
    from visland.datasets.sources import VideoSource
    times = [0.0, 0.04, 0.12, 0.16, 0.36, 0.40, 0.44, 0.60, 0.64, 1.00]       # dropped frames, a 0.36 s gap
    images = [np.full((48, 64, 3), 20 * k, np.uint8) for k in range(len(times))]
    video = _encode_h264(tmp_path, images, times)
    CameraModel.from_fov(64, 48, 50.0).save(tmp_path / "camera.json")
    _level_telemetry(tmp_path / "telemetry.csv")
    source = VideoSource(video)
    assert len(source) == len(times)
    assert np.allclose(source.times_s, times, atol=1e-3)
    assert source.timing.startswith("variable frame rate: frame times from the container's timestamps")
    # the inertial data are interpolated at those times, not at k / fps (heading 90 + 10 t deg)
    assert np.allclose(np.degrees(source.inertial.heading_rad), 90.0 + 10.0 * np.asarray(times), atol=0.02)
    decoded = [int(round(float(image.mean()))) for _, image, _ in source.frames(gray=True)]
    assert decoded == pytest.approx([20 * k for k in range(len(times))], abs=3)
    # --fps overrides the container (the user knows better), and says so
    forced = VideoSource(video, fps=25.0)
    assert np.allclose(forced.times_s, np.arange(len(times)) / 25.0) and forced.timing == "frame times from --fps 25"


def test_a_video_of_constant_frame_rate_keeps_exact_times(tmp_path):
    import cv2

    from visland.datasets.sources import VideoSource
    writer = cv2.VideoWriter(str(tmp_path / "cfr.avi"), cv2.VideoWriter_fourcc(*"MJPG"), 5.0, (64, 48))
    for k in range(12):
        writer.write(np.full((48, 64, 3), 10 * k, np.uint8))
    writer.release()
    CameraModel.from_fov(64, 48, 50.0).save(tmp_path / "camera.json")
    _level_telemetry(tmp_path / "telemetry.csv")
    source = VideoSource(tmp_path / "cfr.avi")
    assert np.array_equal(source.times_s, np.arange(12) / 5.0)
    assert source.timing == "frame times from the video's constant frame rate (5 frames/s)"
