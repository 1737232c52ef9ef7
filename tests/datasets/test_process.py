"""visland process / compare / campaign on small inputs: simulated folders, generated frames, a video.

Independent truth here is the simulation (truth.csv, labels.csv); the figures checked are what
the pipeline must get right whatever the observer: files in the SPEC schemas, every frame
accounted for, flagged frames named, the estimate close to the truth on exact measurements.
"""
import json
import re
import shutil

import cv2
import numpy as np
import pytest

from visland.camera import CameraModel
from visland.cli import main
from visland.contracts import (ESTIMATE_COLUMNS, MEASUREMENT_COLUMNS, read_estimates, read_labels, read_measurements,
                               read_truth)
from visland.datasets.pixel_errors import corner_errors_px, edge_errors_px
from visland.datasets.process import ProcessOptions, process_input

from tests.helpers.short_approach import generate_short

SIZE = 512
OBSERVERS = ("ccpi-hg-2p", "cccj-2l", "ecc-hg")


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    out = tmp_path_factory.mktemp("sim") / "thesis-3"
    assert main(["simulate", "--scenario", "thesis-3", "--out", str(out)]) == 0
    return out


@pytest.fixture(scope="module")
def generated(tmp_path_factory):
    """A short approach (1.8 km, about 25 s) rendered at SIZE px and 5 Hz."""
    return generate_short(tmp_path_factory.mktemp("gen") / "short", SIZE, 5.0, dx_m=-1800.0)


def _quiet(**kwargs):
    return ProcessOptions(observers=OBSERVERS, quiet=True, **kwargs)


@pytest.mark.slow
def test_ideal_measurements_of_a_simulated_folder(simulated, tmp_path):
    out = tmp_path / "run"
    run = process_input(simulated, out, _quiet(source="ideal"), echo=lambda s: None)
    truth = read_truth(simulated / "truth.csv")
    assert run["n_frames"] == truth.n_rows == run["n_found"] and run["n_flagged"] == 0
    measurements = read_measurements(out / "measurements.csv")
    assert list(measurements.column_order) == list(MEASUREMENT_COLUMNS)
    estimates = read_estimates(out / "estimates.csv")
    assert list(estimates.column_order)[:len(ESTIMATE_COLUMNS)] == list(ESTIMATE_COLUMNS)
    assert len(estimates["observer"]) == len(OBSERVERS) * truth.n_rows
    metrics = json.loads((out / "metrics.json").read_text())
    for name in OBSERVERS:
        assert abs(metrics["observers"][name]["err_100ft_m"]) < 0.01         # exact measurements
        assert abs(metrics["deviations"][name]["dY_err_100ft_m"]) < 0.05
    # the run folder is self-contained: rerunning the estimation on it needs nothing else
    assert {p.name for p in out.iterdir()} >= {"camera.json", "telemetry.csv", "truth.csv", "run.json",
                                                "report.html", "metrics.json"}
    html = (out / "report.html").read_text()
    assert html.count("<img src='data:image/png;base64,") >= 4
    assert not re.search(r"""(src|href)=['"]https?:""", html)          # no external resources


def _near_corner_error_px(measurements, labels):
    """Per frame, the worse of the two threshold corners' errors (NaN unless both are visible and measured)."""
    errors = corner_errors_px(measurements, labels)
    return np.maximum(errors["near_left"], errors["near_right"])


@pytest.mark.slow
def test_rendered_approach_measured_and_estimated_against_labels_and_truth(generated, tmp_path):
    """End to end on rendered frames: detection, tracking and anchored tracking against labels.csv,
    their estimates against truth.csv.

    The tolerances sit a little above what was measured when the test was written (in the
    comments: 104 frames of 512x512 at 5 Hz from 1480 m before the threshold to the threshold),
    so a regression of the README's figures' kind (pixel errors per band, dH at 100 ft) fails here.
    """
    from visland.datasets.process import process_many
    out = {source: tmp_path / source for source in ("detection", "tracking", "anchored")}
    runs = process_many(generated, out, _quiet(report=False), echo=lambda s: None)
    labels = read_labels(generated / "labels.csv")
    camera = CameraModel.default(SIZE)
    n = labels.n_rows
    near_visible = (labels["near_left_visible"] == 1) & (labels["near_right_visible"] == 1)
    far_visible = (labels["far_left_visible"] == 1) & (labels["far_right_visible"] == 1)
    assert n == 104 and near_visible.sum() == 100 and far_visible.all()
    before_500m = np.arange(n) < 69            # the first two thirds: 1480 to 500 m before the threshold
    measured = {}
    for source, run in runs.items():
        m = measured[source] = read_measurements(out[source] / "measurements.csv")
        assert run["n_frames"] == m.n_rows == n == len(list((generated / "frames").iterdir()))
        # an anchored run's row says "tracking" where no detection anchored it
        assert set(m["source"]) == ({"anchored", "tracking"} if source == "anchored" else {source})
        assert run["throughput"]["fps_analysis_only"] > 0

    # detection: found in every frame but the first (a new track is reported from its second
    # frame, new_track_frames); corners, edges and heading against the labels
    m = measured["detection"]
    assert m["found"][1:].all() and not m["found"][0] and "frame 1 of a new track" in m["reason"][0]
    near = _near_corner_error_px(m, labels)
    assert np.isfinite(near).sum() >= 70                        # measured 79 of 100 (others withheld)
    assert np.nanmedian(near) < 0.25                             # measured 0.19 px
    assert np.nanpercentile(near, 95) < 1.2                      # measured 0.92 px
    assert np.nanmax(near[before_500m]) < 3.0                    # measured 2.59 px
    # measured: one gross error, frame 99 (near corners at the image's border, found 20 px short)
    assert np.sum(near > 3.0) <= 1
    errors = corner_errors_px(m, labels)
    far = np.maximum(errors["far_left"], errors["far_right"])
    assert np.nanmedian(far) < 0.6 and np.nanmax(far) < 2.5     # measured 0.46 / 2.17 px
    for side, edge in edge_errors_px(m, labels, camera).items():
        assert np.isfinite(edge).sum() >= 102                    # measured 102 of 104 (not the first)
        # measured p95 0.155 / 0.237, max 0.263 / 0.531 px (left / right)
        assert np.nanpercentile(edge, 95) < 0.3 and np.nanmax(edge) < 0.7
    dpsi = np.abs(m["dpsi_deg"] - labels["dpsi_deg"])[1:]
    assert np.median(dpsi) < 0.01 and dpsi.max() < 0.12          # measured 0.006 / 0.097 deg

    # tracking (built for 25 Hz, here 5 Hz): drifts, holds the corners to 500 m; every frame without
    # them says which point and why
    m = measured["tracking"]
    assert m["found"][:10].all() and m["found"].sum() >= 93       # measured 95 of 104
    near = _near_corner_error_px(m, labels)
    assert np.nanmax(near[:34]) < 1.6 and np.nanmax(near[before_500m]) < 3.2   # measured 1.29 / 2.52 px
    lost = m["found"] == 0
    assert all(any(p in r for p in ("near_left", "near_right")) for r in m["reason"][lost])

    # anchored tracking: detection keeps the tracker on the corners
    m = measured["anchored"]
    assert m["found"].sum() >= 98                                 # measured 100 of 104
    near = _near_corner_error_px(m, labels)
    assert np.nanmedian(near) < 0.4                  # measured 0.30 px
    assert np.nanmax(near[before_500m]) < 1.7                      # measured 1.34 px

    # estimates against the truth (observers start 20 % above the true height, 90 m at the start);
    # measured at 100 ft since 3b161bf (point observers correct at every 5 Hz frame): dH ccpi-hg-2p
    # -0.95 (detection) / -1.21 (anchored), cccj-2l 0.90 / 0.81, ecc-hg -1.53 / -1.42 m; dY ccpi-hg-2p
    # 0.043 / 0.085 m (before it, with every gain halved at 5 Hz: ccpi-hg-2p -0.13 / -0.90 m)
    limits_dh_m = {"ccpi-hg-2p": (1.2, 1.5), "cccj-2l": (1.2, 1.1), "ecc-hg": (2.0, 1.9)}
    for k, source in enumerate(("detection", "anchored")):
        metrics = json.loads((out[source] / "metrics.json").read_text())
        for name, limits in limits_dh_m.items():
            assert abs(metrics["observers"][name]["err_100ft_m"]) < limits[k], (source, name)
        assert abs(metrics["deviations"]["ccpi-hg-2p"]["dY_err_100ft_m"]) < (0.06, 0.12)[k]


@pytest.mark.slow
def test_unusable_frames_are_flagged_and_the_run_goes_on(generated, tmp_path):
    folder = tmp_path / "damaged"
    shutil.copytree(generated, folder)
    frames = sorted((folder / "frames").iterdir())
    frames[3].write_bytes(b"not a png")                                       # unreadable
    cv2.imwrite(str(frames[5]), np.zeros((SIZE // 2, SIZE, 3), np.uint8))     # another size
    run = process_input(folder, tmp_path / "run", _quiet(source="detection"), echo=lambda s: None)
    flagged = {item["frame"]: item["reason"] for item in run["flagged"]}
    assert set(flagged) == {3, 5}
    assert "unreadable" in flagged[3] and f"{SIZE}x{SIZE // 2}" in flagged[5]
    measurements = read_measurements(tmp_path / "run" / "measurements.csv")
    assert measurements["found"][3] == 0 and measurements["found"][5] == 0
    assert "frame 3" in (tmp_path / "run" / "report.html").read_text()


@pytest.mark.slow
def test_a_video_with_telemetry_beside_it(generated, tmp_path):
    video = tmp_path / "approach.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 5.0, (SIZE, SIZE))
    for path in sorted((generated / "frames").iterdir()):
        writer.write(cv2.imread(str(path)))
    writer.release()
    for name in ("telemetry.csv", "camera.json", "truth.csv"):
        shutil.copy(generated / name, tmp_path / name)
    run = process_input(video, tmp_path / "run", _quiet(source="detection"), echo=lambda s: None)
    truth = read_truth(generated / "truth.csv")
    assert run["n_frames"] == truth.n_rows
    measurements = read_measurements(tmp_path / "run" / "measurements.csv")
    np.testing.assert_allclose(measurements["t_s"], truth["t_s"], atol=1e-9)     # times from the video's 5 Hz
    assert run["n_found"] >= 0.8 * run["n_frames"]


@pytest.mark.slow
@pytest.mark.parametrize("damage, message", [
    (lambda d: (d / "camera.json").write_text('{"width": 256}'), "camera.json: missing field 'height'"),
    (lambda d: (d / "telemetry.csv").write_text((d / "telemetry.csv").read_text().replace("vd_mps", "vz")),
     "telemetry.csv: missing column 'vd_mps'"),
    (lambda d: (d / "telemetry.csv").write_text("\n".join((d / "telemetry.csv").read_text().splitlines()[:40]) + "\n"),
     "telemetry covers"),
    (lambda d: (d / "frames.csv").write_text("frame,t_s\n0,0.0\n1,0.0\n"), "frames.csv line 3: t_s does not increase"),
])
def test_bad_inputs_are_one_sentence_naming_the_file(generated, tmp_path, capsys, damage, message):
    folder = tmp_path / "bad"
    shutil.copytree(generated, folder)
    damage(folder)
    assert main(["process", str(folder), "--out", str(tmp_path / "run"), "--quiet", "--observer", "ccpi-hg-2p"]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and err.count("\n") == 0
    assert not (tmp_path / "run").exists()


def test_a_video_that_cannot_be_opened(tmp_path, capsys):
    video = tmp_path / "broken.mp4"
    video.write_bytes(b"\x00" * 1000)
    assert main(["process", str(video), "--out", str(tmp_path / "run"), "--quiet"]) == 2
    assert "broken.mp4: the video cannot be opened" in capsys.readouterr().err


@pytest.mark.slow
def test_compare_builds_the_thesis_tables(simulated, tmp_path, capsys):
    runs = []
    for k, scenario in enumerate(("thesis-1", "thesis-3")):
        folder = tmp_path / scenario
        assert main(["simulate", "--scenario", scenario, "--out", str(folder)]) == 0
        (folder / "manifest.json").write_text(json.dumps({"scenario": {"name": scenario}}))
        runs.append(tmp_path / f"run{k}")
        process_input(folder, runs[-1], _quiet(source="ideal", report=False), echo=lambda s: None)
    capsys.readouterr()
    assert main(["compare", *map(str, runs), "--out", str(tmp_path / "cmp")]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    headline = json.loads(lines[-1])
    assert headline["ideal"]["best_observer"] in OBSERVERS
    table = (tmp_path / "cmp" / "compare.md").read_text()
    assert "5 % convergence time (s), thesis-1" in table and "standard deviation at 100 ft (m), 2 runs" in table
    figures = json.loads((tmp_path / "cmp" / "compare.json").read_text())
    for quantity in ("dH", "dY", "dX"):
        assert "ccpi-hg-2p" in figures["ideal"][quantity]
    assert (tmp_path / "cmp" / "errors_vs_dx_ideal.png").exists()


@pytest.mark.slow
def test_campaign_resumes_without_redoing_work(tmp_path, capsys):
    scenario = tmp_path / "short.toml"
    scenario.write_text('name = "short"\ndx_m = -1600.0\ndy_m = 20.0\ndgs_m = 0.0\ndpsi_deg = 0.0\ngamma_deg = -3.0\n')
    args = ["campaign", "--scenarios", str(scenario), "--size", "128", "--fps", "2", "--sources", "detection",
            "--observer", "ccpi-hg-2p", "--workers", "1", "--out", str(tmp_path / "camp")]
    assert main(args) == 0
    first = capsys.readouterr().out
    assert "render and measure short in memory (128 px, 2 Hz) with detection, frames kept" in first
    assert "frames kept by the background writer" in first
    manifest = json.loads((tmp_path / "camp" / "datasets" / "short" / "manifest.json").read_text())
    assert manifest["kind"] == "dataset" and len(manifest["frames"]) == len(
        list((tmp_path / "camp" / "datasets" / "short" / "frames").iterdir()))
    assert main(args) == 0
    second = capsys.readouterr().out
    assert "every run up to date, kept" in second and "generate short" not in second
    assert main(args + ["--seed", "9"]) == 2
    assert "holds a campaign with other settings (seed)" in capsys.readouterr().err


@pytest.mark.slow
def test_several_sources_in_one_decoding_pass_match_separate_runs(generated, tmp_path):
    from visland.datasets.process import process_many
    options = _quiet(report=False)
    together = process_many(generated, {"detection": tmp_path / "d", "tracking": tmp_path / "t"}, options,
                            echo=lambda s: None)
    alone = process_input(generated, tmp_path / "d1", _quiet(source="detection", report=False), echo=lambda s: None)
    assert together["detection"]["n_found"] == alone["n_found"]
    a = read_measurements(tmp_path / "d" / "measurements.csv")
    b = read_measurements(tmp_path / "d1" / "measurements.csv")
    np.testing.assert_array_equal(np.nan_to_num(a["near_left_u_px"], nan=-1), np.nan_to_num(b["near_left_u_px"], nan=-1))
    assert set(read_measurements(tmp_path / "t" / "measurements.csv")["source"]) == {"tracking"}


@pytest.mark.slow
def test_a_tracker_policy_is_a_source_of_its_own(generated, tmp_path):
    from visland.datasets.measure import parse_source
    assert parse_source("tracking:every_frame") == ("tracking", "every_frame")
    with pytest.raises(ValueError, match="only tracking and anchored take an update policy"):
        parse_source("detection:never")
    run = process_input(generated, tmp_path / "memo", _quiet(source="tracking:every_frame", report=False),
                        echo=lambda s: None)
    assert run["source"] == "tracking:every_frame" and run["n_frames"] > 0


@pytest.mark.slow
def test_a_batch_of_recordings_with_one_bad_input(simulated, tmp_path):
    """Three inputs, one without telemetry: two runs, one failed line in the index, a comparison."""
    import shutil

    from visland.datasets.batch import process_batch
    inputs = []
    for name in ("approach-a", "approach-b", "broken"):
        shutil.copytree(simulated, tmp_path / "in" / name)
        inputs.append(tmp_path / "in" / name)
    (tmp_path / "in" / "broken" / "telemetry.csv").unlink()
    index = process_batch(inputs, tmp_path / "batch", _quiet(source="ideal", report=False), echo=lambda s: None)
    assert (index["done"], index["failed"]) == (2, 1)
    failed = [r for r in index["runs"] if r["status"] == "failed"]
    assert failed[0]["name"] == "broken" and "telemetry" in failed[0]["reason"]
    for run in index["runs"][:2]:
        assert (tmp_path / "batch" / run["name"] / "estimates.csv").exists()
        assert abs(run["dh_err_100ft_m"]) < 0.01                # exact measurements
    page = (tmp_path / "batch" / "index.html").read_text()
    assert "approach-a" in page and "failed:" in page
    assert index["comparison"] == "compare" and any((tmp_path / "batch" / "compare").iterdir())
    assert json.loads((tmp_path / "batch" / "index.json").read_text())["done"] == 2


@pytest.mark.slow
def test_a_batch_in_worker_processes_and_on_dask_matches_one_after_the_other(simulated, tmp_path):
    """The same three inputs (one broken) on 2 worker processes and on a local Dask cluster: the same
    rows, in the inputs' order, and the same estimates as one after the other."""
    import shutil

    from distributed import LocalCluster

    from visland.datasets.batch import process_batch
    inputs = []
    for name in ("approach-a", "broken", "approach-b"):
        shutil.copytree(simulated, tmp_path / "in" / name)
        inputs.append(tmp_path / "in" / name)
    (tmp_path / "in" / "broken" / "telemetry.csv").unlink()
    options = _quiet(source="ideal", report=False)
    serial = process_batch(inputs, tmp_path / "serial", options, echo=lambda s: None)
    lines: list = []
    pooled = process_batch(inputs, tmp_path / "pooled", options, echo=lines.append, workers=2)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        dask = process_batch(inputs, tmp_path / "dask", options, echo=lambda s: None,
                             scheduler=cluster.scheduler_address)
    for index in (pooled, dask):
        assert [(r["name"], r["status"]) for r in index["runs"]] == [(r["name"], r["status"]) for r in serial["runs"]]
        assert [r.get("dh_err_100ft_m") for r in index["runs"]] == [r.get("dh_err_100ft_m") for r in serial["runs"]]
    assert "batch: 3 inputs, 2 at a time in worker processes" in lines
    assert any(line.startswith("== ") and "(failed, " in line for line in lines)
    for name in ("approach-a", "approach-b"):
        assert (tmp_path / "pooled" / name / "estimates.csv").read_bytes() == \
            (tmp_path / "serial" / name / "estimates.csv").read_bytes()
    with pytest.raises(ValueError, match="cannot reach the Dask scheduler at tcp://127.0.0.1:9"):
        process_batch(inputs, tmp_path / "nowhere", options, echo=lambda s: None, scheduler="tcp://127.0.0.1:9")


@pytest.mark.slow
def test_process_applies_the_self_calibration_on_request_and_reports_it(tmp_path):
    """A camera pitched 0.5 deg more than camera.json says (simulate --calibration-error): process
    estimates the mounting's error from the runway and shows it in run.json and the report;
    --self-calibration applies it, and the 100 ft error of ccpi-hg-2p falls from metres to decimetres
    (the calibration study's figures: -15..-20 m uncorrected, within 0.3 m corrected)."""
    folder = tmp_path / "thesis-3-pitched"
    assert main(["simulate", "--scenario", "thesis-3", "--out", str(folder), "--calibration-error", "0,0.5,0",
                 "--pixel-noise", "1", "--seed", "2"]) == 0
    errors = {}
    for apply in (False, True):
        out = tmp_path / f"run-{apply}"
        run = process_input(folder, out, ProcessOptions(observers=("ccpi-hg-2p",), quiet=True, source="ideal",
                                                        self_calibration=apply), echo=lambda s: None)
        calibration = run["self_calibration"]
        assert calibration["applied"] is apply
        assert calibration["mount_error_deg"]["pitch"] == pytest.approx(0.5, abs=0.05)
        html = (out / "report.html").read_text()
        assert "camera mounting (self-calibration)" in html
        assert ("applied to the measurements" in html) is apply
        errors[apply] = json.loads((out / "metrics.json").read_text())["observers"]["ccpi-hg-2p"]["err_100ft_m"]
    assert abs(errors[False]) > 3.0
    assert abs(errors[True]) < 0.3


def test_dask_tasks_share_their_hosts_cores_among_the_workers_task_slots():
    """Two single-threaded workers on a 2-core host get one OpenCV thread each; a lone 1-thread
    worker on a 4-core host gets 4; a 2-thread worker sharing an 8-core host with a 1-thread one
    gets 8 // 3 = 2 per task; a worker whose core count is unknown gets 1."""
    from visland.datasets.batch import opencv_threads_per_worker
    workers = {"tcp://a:1": {"host": "a", "nthreads": 1}, "tcp://a:2": {"host": "a", "nthreads": 1},
               "tcp://b:1": {"host": "b", "nthreads": 1},
               "tcp://c:1": {"host": "c", "nthreads": 2}, "tcp://c:2": {"host": "c", "nthreads": 1},
               "tcp://d:1": {"host": "d", "nthreads": 1}}
    cpus = {"tcp://a:1": 2, "tcp://a:2": 2, "tcp://b:1": 4, "tcp://c:1": 8, "tcp://c:2": 8, "tcp://d:1": None}
    assert opencv_threads_per_worker(workers, cpus) == {"tcp://a:1": 1, "tcp://a:2": 1, "tcp://b:1": 4,
                                                        "tcp://c:1": 2, "tcp://c:2": 2, "tcp://d:1": 1}


@pytest.mark.slow
def test_anchored_tracking_reads_the_detection_sources_results_exactly(generated):
    """measure_many with detection and anchored tracking detects each frame once (the anchor reads
    the detection source's results); its anchored rows equal those of anchored tracking measured
    alone, which runs its own detector on the same frames."""
    from visland.datasets.measure import measure, measure_many
    from visland.datasets.sources import open_source
    together = measure_many(open_source(generated), ["detection", "anchored"], quiet=True)
    alone = measure(open_source(generated), "anchored", quiet=True)
    assert together["anchored"].columns.keys() == alone.columns.keys()
    for column, values in alone.columns.items():
        assert np.array_equal(np.asarray(together["anchored"].columns[column]), np.asarray(values),
                              equal_nan=np.asarray(values).dtype.kind == "f"), column
    assert list(together["anchored"].columns["source"]).count("anchored") > 50


def test_shared_detections_hand_over_in_any_order_and_report_a_stopped_detector():
    import threading
    from visland.datasets.measure import _SharedDetections
    shared = _SharedDetections()
    got = []
    reader = threading.Thread(target=lambda: got.extend(shared.get(i) for i in range(3)))
    reader.start()
    for i in range(3):
        shared.put(i, f"result {i}")
    reader.join(timeout=5)
    assert got == ["result 0", "result 1", "result 2"]
    shared.fail(ValueError("broken frame"))
    with pytest.raises(RuntimeError, match="frame 3: the detection source stopped"):
        shared.get(3)
