"""Streaming measurement (frames rendered and measured in memory) against the file route.

Independent truth here is the file route itself, ``visland generate`` then ``visland process``:
a PNG is lossless, so measuring the rendered frames in memory must give the very same
measurements and estimates, frame for frame and digit for digit.
"""
import numpy as np
import pytest

from visland.contracts import read_estimates, read_measurements
from visland.datasets import generate as gen
from visland.datasets.process import ProcessOptions, process_many
from visland.datasets.stream import stream_process

from tests.helpers.short_approach import short_job

OBSERVERS = ("ccpi-hg-2p", "ekf-2l")
SOURCES = ("detection", "tracking")


def _job():
    """A short approach (1.5 km, about 20 s) at 512 px and 2 Hz: 35 frames."""
    return short_job(512, 2.0, dy_m=10.0, dgs_m=-3.0, dpsi_deg=1.0)


OPTIONS = ProcessOptions(observers=OBSERVERS, quiet=True, report=False)


@pytest.fixture(scope="module")
def file_route(tmp_path_factory):
    """``visland generate`` then ``visland process`` with both sources (PNG files in between)."""
    files = tmp_path_factory.mktemp("files")
    gen.generate_dataset(_job(), files / "dataset", progress=False)
    process_many(files / "dataset", {s: files / s for s in SOURCES}, OPTIONS, echo=lambda s: None)
    return files


@pytest.mark.slow
@pytest.mark.parametrize("workers", [1, 2])
def test_streamed_runs_equal_the_file_route_frame_for_frame(file_route, tmp_path, workers):
    job, files, options = _job(), file_route, OPTIONS
    streamed = tmp_path / "stream"
    stream_process(job, streamed / "dataset", {s: streamed / s for s in SOURCES}, options, workers=workers,
                   echo=lambda s: None)
    assert not (streamed / "dataset" / "frames").exists()           # nothing written but the metadata
    for kind in SOURCES:
        by_file = read_measurements(files / kind / "measurements.csv")
        in_memory = read_measurements(streamed / kind / "measurements.csv")
        assert by_file.n_rows == in_memory.n_rows == len((files / "dataset" / "frames.csv").read_text().split()) - 1
        assert np.sum(by_file["found"]) >= 0.8 * by_file.n_rows      # the runway is measured: not a vacuous match
        for column in by_file.column_order:
            a, b = by_file[column], in_memory[column]
            if a.dtype.kind == "f":
                np.testing.assert_array_equal(a, b, err_msg=f"{kind}: {column}")
            else:
                assert list(a) == list(b), f"{kind}: {column}"
        assert ((files / kind / "estimates.csv").read_text() == (streamed / kind / "estimates.csv").read_text())
        assert read_estimates(streamed / kind / "estimates.csv").n_rows == len(OBSERVERS) * by_file.n_rows


@pytest.mark.slow
def test_frames_kept_by_the_background_writer_are_the_file_routes_bytes(file_route, tmp_path):
    """Independent truth: ``visland generate``'s PNG files and manifest for the same job."""
    import json
    job, files = _job(), file_route
    streamed = tmp_path / "stream"
    lines = []
    stream_process(job, streamed / "dataset", {"detection": streamed / "detection"}, OPTIONS, echo=lines.append,
                   keep_frames=True, writer_threads=2)
    generated = sorted((files / "dataset" / "frames").iterdir())
    kept = sorted((streamed / "dataset" / "frames").iterdir())
    assert [p.name for p in kept] == [p.name for p in generated] and len(kept) >= 30
    for a, b in zip(generated, kept):
        assert a.read_bytes() == b.read_bytes(), b.name
    manifest_file = json.loads((files / "dataset" / "manifest.json").read_text())
    manifest_stream = json.loads((streamed / "dataset" / "manifest.json").read_text())
    assert manifest_stream == manifest_file
    assert (files / "detection" / "estimates.csv").read_text() == (streamed / "detection" / "estimates.csv").read_text()
    assert any(line.startswith("frames kept by the background writer") for line in lines)


def test_a_writer_error_reaches_the_caller(tmp_path):
    from visland.datasets.stream import FrameWriter
    blocker = tmp_path / "frames"
    blocker.write_text("a file where the frames folder should be")
    with pytest.raises(OSError):
        FrameWriter(blocker)
    writer = FrameWriter(tmp_path / "ok")
    writer.put(0, np.zeros((4, 4, 3), np.uint8))
    writer.put(1, None)                                        # not an image: encoding fails in the thread
    with pytest.raises(TypeError):
        writer.close()
    assert (tmp_path / "ok" / "000000.png").is_file()


def _rendered_source(folder, workers):
    """A :class:`RenderedSource` of a tiny approach (128 px, 1 Hz: a few frames)."""
    from visland.datasets.stream import RenderedSource, write_dataset_files
    from visland.simulate import run_simulation
    job = short_job(128, 1.0)
    result = run_simulation(job.scenario, job.options)
    write_dataset_files(result, folder)
    return RenderedSource(folder, job, result, workers=workers, prefetch=2)


@pytest.fixture
def shared_blocks(monkeypatch):
    """The names of every shared-memory block the streaming pool makes (recorded as made)."""
    from visland.datasets import stream
    names = []

    class Recorded(stream.SharedMemory):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            if kwargs.get("create"):
                names.append(self.name)
    monkeypatch.setattr(stream, "SharedMemory", Recorded)
    return names


def _left_in_dev_shm(names):
    import os
    return [name for name in names if os.path.exists(os.path.join("/dev/shm", name.lstrip("/")))]


@pytest.mark.slow
def test_frames_through_shared_memory_are_the_rendered_pixels_and_leave_nothing_behind(tmp_path, shared_blocks):
    """Independent truth: the same frames rendered in a thread of this process (no hand-off)."""
    in_thread = list(_rendered_source(tmp_path / "a", workers=1)._rendered())
    in_pool = list(_rendered_source(tmp_path / "b", workers=2)._rendered())
    assert len(shared_blocks) == 4                          # workers + prefetch: frames did go through them
    assert [i for i, _ in in_pool] == [i for i, _ in in_thread] == list(range(len(in_thread)))
    assert len(in_thread) > len(shared_blocks)              # every block was used more than once
    for (_, a), (_, b) in zip(in_thread, in_pool):
        assert a.shape == (128, 128, 3) and a.std() > 1.0  # a rendered frame, not a blank
        np.testing.assert_array_equal(a, b)
    assert not _left_in_dev_shm(shared_blocks)


@pytest.mark.slow
def test_an_interrupted_consumer_leaves_no_shared_memory_behind(tmp_path, shared_blocks):
    frames = _rendered_source(tmp_path, workers=2)._rendered()
    index, rgb = next(frames)
    assert index == 0 and rgb.shape == (128, 128, 3)
    assert len(shared_blocks) == 4 and len(_left_in_dev_shm(shared_blocks)) == 4
    frames.close()                                          # the consumer stops early (an error, Ctrl-C)
    assert not _left_in_dev_shm(shared_blocks)


@pytest.mark.slow
def test_a_failing_render_reaches_the_consumer_and_leaves_no_shared_memory_behind(tmp_path, shared_blocks,
                                                                                  monkeypatch):
    real_payload = gen._payload

    def broken(job, result):            # the workers cannot build the runway: every render fails there
        return {**real_payload(job, result), "runway": {"not_a_runway_field": 1.0}}
    monkeypatch.setattr(gen, "_payload", broken)
    with pytest.raises(TypeError, match="not_a_runway_field"):
        list(_rendered_source(tmp_path, workers=2)._rendered())
    assert len(shared_blocks) == 4 and not _left_in_dev_shm(shared_blocks)


@pytest.mark.slow
def test_runs_written_side_by_side_are_the_serial_runs(file_route, tmp_path):
    """Independent truth: the same sources' runs written one after the other (``run_processes=1``)."""
    serial_lines, side_lines = [], []
    serial = process_many(file_route / "dataset", {s: tmp_path / "serial" / s for s in SOURCES}, OPTIONS,
                          echo=serial_lines.append)
    side = process_many(file_route / "dataset", {s: tmp_path / "side" / s for s in SOURCES}, OPTIONS,
                        echo=side_lines.append, run_processes=2)
    assert list(side) == list(serial) == list(SOURCES)
    for kind in SOURCES:
        assert side[kind]["n_found"] == serial[kind]["n_found"] > 0
        for name in ("measurements.csv", "estimates.csv", "metrics.json"):
            assert (tmp_path / "side" / kind / name).read_bytes() == (tmp_path / "serial" / kind / name).read_bytes()
    # the same lines in the same order (the sources' order) but the measured speeds
    def steady(lines, folder):
        import re
        return [re.sub(r"\d+ us/step", "N us/step", line.replace(str(tmp_path / folder), "OUT"))
                for line in lines if "frames/s" not in line]
    assert steady(side_lines, "side") == steady(serial_lines, "serial")
    lines = steady(side_lines, "side")
    about = [k for k, line in enumerate(lines) for kind in SOURCES if f"OUT/{kind}" in line and kind == SOURCES[0]]
    after = [k for k, line in enumerate(lines) if f"OUT/{SOURCES[1]}" in line]
    assert about and after and max(about) < min(after)       # every line of the first source, then the second's


def test_a_shared_block_whose_frame_came_back_whole_is_free_again():
    """A worker that returns its frame whole (another shape: the consumer then says so) leaves its
    block unwritten; the ring must hand it out again, not run dry before the error is reported."""
    import numpy as np
    from visland.datasets.stream import _SharedFrames
    ring = _SharedFrames(2, (4, 5, 3))
    try:
        first, second = ring.take(), ring.take()
        assert len(ring) == 0
        ring.release(first)
        assert ring.take() == first
        np.ndarray((4, 5, 3), np.uint8, buffer=ring.blocks[second].buf)[:] = 7
        assert (ring.read(second) == 7).all() and len(ring) == 1
    finally:
        ring.close()
    assert ring.blocks == {}
