"""Streaming measurement: render a scenario's frames and measure them in memory, no PNG round trip.

``visland campaign --prune-frames`` and ``visland demo`` (frames not kept) used to render every
frame to a PNG file, decode it again to measure it, then delete it: at 2048 px the PNG writing
(0.25-0.33 s per frame) cost four times the rendering (0.05-0.07 s) and ten times the detection.
Here the frames go straight from the renderer to the measurement, through the very code that
``visland process`` runs on a folder (:func:`visland.datasets.process.process_many`, which
decodes each frame once for every source):

- the dataset folder gets every file of ``visland generate`` but the images (``frames.csv``,
  ``telemetry.csv``, ``truth.csv``, ``labels.csv``, ``camera.json``, ``runway.json`` and the
  simulation's ``manifest.json``), written first and read back by :class:`RenderedSource`
  exactly as :class:`visland.datasets.sources.FolderSource` reads them;
- :class:`RenderedSource` yields the rendered RGB frames in order. A PNG is lossless and a
  folder's frames are decoded to RGB, so every source sees the same pixels, the same times and
  the same inertial data as on the file route: measurements and estimates are identical
  (``tests/datasets/test_stream.py`` checks it frame for frame);
- frames render ahead of the measurement: in a background thread (one process), in a pool of
  worker processes (``workers`` > 1, each with its GL context), and the whole scenario is one
  task on a Dask worker with ``--scheduler`` (see :mod:`visland.datasets.campaign`);
- frames are kept only when asked (``keep_frames``): a :class:`FrameWriter` encodes and writes
  them in background threads (OpenCV's PNG encoder and hashlib release the GIL) while the
  measurement goes on, and the folder ends as a complete dataset, byte-identical to
  ``visland generate``'s (same PNG encoding, same manifest with every frame's SHA-256).
"""
from __future__ import annotations

import os
import queue
import threading
import time
from multiprocessing.shared_memory import SharedMemory
from pathlib import Path

import numpy as np

from visland.camera import CameraModel
from visland.contracts import FRAMES_COLUMNS, read_frames_csv, read_labels, read_telemetry, read_truth, write_csv
from visland.datasets.sources import FrameSource
from visland.folder import as_grey, interpolate_telemetry

__all__ = ["RenderedSource", "FrameWriter", "write_dataset_files", "stream_process"]


def write_dataset_files(result, folder) -> None:
    """Every file ``visland generate`` writes into ``folder`` but ``frames/`` (and the simulation's
    manifest instead of the dataset's, so the folder is not taken for a complete dataset).

    Parameters
    ----------
    result : visland.simulate.SimulationResult
        The simulated approach.
    folder : str or pathlib.Path
        The dataset folder, created if missing.
    """
    from visland.simulate import write_simulation_files
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    write_simulation_files(result, folder)
    write_csv(folder / "frames.csv", {"frame": np.arange(len(result.frames)), "t_s": result.frames.t_s},
              FRAMES_COLUMNS)


class FrameWriter:
    """Write rendered frames as ``frames/NNNNNN.png`` in background threads.

    ``put(index, rgb)`` hands a frame over and returns at once unless ``queue_size`` frames are
    already waiting (then it blocks: memory stays bounded at ``queue_size`` frames, 12.6 MB each
    at 2048 px). ``close()`` waits for the last frame and raises the first error a writer met.
    Each frame is encoded as :func:`visland.datasets.generate.encode_frame_png` and written
    atomically (a frame file that exists is complete); ``digests`` maps index -> SHA-256.

    Parameters
    ----------
    frames_dir : str or pathlib.Path
        Folder of the PNG files, created if missing.
    png_compression : int, optional
        OpenCV's PNG compression level, 0-9 (as ``visland generate --png-compression``).
    threads : int, optional
        Writer threads (at least 1).
    queue_size : int, optional
        Frames that may wait to be written before ``put`` blocks (at least 1).

    Attributes
    ----------
    encode_s : float
        Seconds the writer threads spent encoding, hashing and writing (summed over threads).
    blocked_s : float
        Seconds ``put`` waited on a full queue: the time the producer lost to the writer.
    """

    def __init__(self, frames_dir, png_compression: int = 1, threads: int = 1, queue_size: int = 8):
        self.frames_dir = Path(frames_dir)
        self.frames_dir.mkdir(parents=True, exist_ok=True)
        self.png_compression = int(png_compression)
        self.digests: dict = {}
        self.encode_s = 0.0
        self.blocked_s = 0.0
        self._queue: queue.Queue = queue.Queue(maxsize=max(1, int(queue_size)))
        self._error = None
        self._lock = threading.Lock()
        self._threads = [threading.Thread(target=self._run, daemon=True) for _ in range(max(1, int(threads)))]
        for thread in self._threads:
            thread.start()

    def _run(self):
        import hashlib
        from visland.contracts import atomic_write_bytes
        from visland.datasets.generate import encode_frame_png, frame_name
        while True:
            item = self._queue.get()
            if item is None:
                return
            if self._error is not None:
                continue                      # drain: the first error is what close() reports
            index, rgb = item
            tic = time.perf_counter()
            try:
                data = encode_frame_png(rgb, self.png_compression, index)
                atomic_write_bytes(self.frames_dir / frame_name(index), data)
                digest = hashlib.sha256(data).hexdigest()
            except BaseException as error:    # handed to close()
                with self._lock:
                    self._error = self._error or error
                continue
            with self._lock:
                self.digests[index] = digest
                self.encode_s += time.perf_counter() - tic

    def put(self, index: int, rgb) -> None:
        """Queue frame ``index`` (an RGB array the caller no longer modifies)."""
        if self._error is not None:
            raise self._error
        tic = time.perf_counter()
        self._queue.put((int(index), rgb))
        self.blocked_s += time.perf_counter() - tic

    def close(self) -> None:
        """Wait for every queued frame to be written; raise the first writing error."""
        for _ in self._threads:
            self._queue.put(None)
        for thread in self._threads:
            thread.join()
        if self._error is not None:
            raise self._error


def _render_task(task):
    """Render one frame in a pool worker: ``(index, rgb)`` (module level: spawn pickles it)."""
    from visland.datasets.generate import _WORKER_LOCK, _renderer_for, frame_seed
    payload, index, p_runway_m, R_camera_from_runway = task
    with _WORKER_LOCK:
        renderer = _renderer_for(payload)
        rgb = renderer.render(np.asarray(p_runway_m, float), np.asarray(R_camera_from_runway, float),
                              frame_seed=frame_seed(payload["scene"]["seed"], index))
    return index, rgb


#: shared-memory blocks this worker process has attached, by name (a pool's workers end with it)
_ATTACHED: dict = {}


def _render_task_shared(task, block: str, shape: tuple):
    """Render one frame in a pool worker into the shared-memory block ``block`` (``shape`` uint8):
    ``(index, None)``; a frame of another shape or type comes back whole, ``(index, rgb)``, for the
    parent to report it."""
    index, rgb = _render_task(task)
    if rgb.shape != tuple(shape) or rgb.dtype != np.uint8:
        return index, rgb
    memory = _ATTACHED.get(block)
    if memory is None:
        # attached, never unlinked here: the parent made the block and unlinks it (the spawned
        # workers share the parent's resource tracker, so this registration is the parent's own)
        memory = _ATTACHED[block] = SharedMemory(name=block)
    np.copyto(np.ndarray(shape, np.uint8, buffer=memory.buf), rgb)
    return index, None


def _shared_memory_room(nbytes: int) -> bool:
    """Whether ``/dev/shm`` has ``nbytes`` free (a block written past the room of its tmpfs kills
    the writer with SIGBUS: below that, frames come back through the pipe)."""
    try:
        stat = os.statvfs("/dev/shm")
    except (OSError, AttributeError):
        return False
    return stat.f_bavail * stat.f_frsize >= 2 * nbytes


class _SharedFrames:
    """A ring of shared-memory blocks, one frame each, that pool workers render into.

    ``take()`` gives a free block's name, ``read(name)`` copies the frame out of it (a fresh
    array the consumer owns: the block is free again at once), ``close()`` releases and unlinks
    every block (also after an error or an interrupted consumer: nothing stays in ``/dev/shm``).
    """

    def __init__(self, count: int, shape: tuple):
        self.shape = tuple(shape)
        nbytes = int(np.prod(self.shape))
        self.blocks: dict = {}
        try:
            for _ in range(count):
                memory = SharedMemory(create=True, size=nbytes)
                self.blocks[memory.name] = memory
        except BaseException:
            self.close()
            raise
        self._free = list(self.blocks)

    def take(self) -> str:
        return self._free.pop()

    def read(self, name: str):
        view = np.ndarray(self.shape, np.uint8, buffer=self.blocks[name].buf)
        rgb = view.copy()
        del view                              # no export left: the block can be closed
        self.release(name)
        return rgb

    def release(self, name: str) -> None:
        """Block ``name`` is free again (read, or not written: its frame came back whole)."""
        self._free.append(name)

    def __len__(self):
        return len(self._free)

    def close(self) -> None:
        for memory in self.blocks.values():
            memory.close()
            try:
                memory.unlink()
            except FileNotFoundError:
                pass
        self.blocks = {}
        self._free = []


class RenderedSource(FrameSource):
    """The frames of a generate job rendered on demand, with the metadata of its folder.

    Parameters
    ----------
    root : a folder written by :func:`write_dataset_files` for ``result``.
    job : visland.datasets.generate.GenerateJob
        What the frames look like (scene, camera size); the same job renders the same pixels as
        ``visland generate``.
    result : visland.simulate.SimulationResult
        The job's simulation (poses of the camera as mounted).
    workers : int
        1 renders in a background thread of this process; more renders in that many spawned
        processes (frames come back in order).
    prefetch : int
        Frames rendered ahead of the consumer (each is ``H x W x 3`` bytes: 12.6 MB at 2048 px).
    writer : FrameWriter or None
        Also hand every rendered frame to this writer (frames kept as PNG files).
    """

    def __init__(self, root, job, result, workers: int = 1, prefetch: int = 4, writer: FrameWriter | None = None):
        self.root = Path(root)
        self.name = str(self.root)
        self._job = job
        self._result = result
        self._workers = int(workers)
        self._prefetch = max(1, int(prefetch))
        self._writer = writer
        # read back exactly as FrameFolder reads a folder (same files, same parsing)
        times = read_frames_csv(self.root / "frames.csv")
        self.times_s = times["t_s"]
        if len(self.times_s) != len(result.frames):
            raise ValueError(f"{self.root / 'frames.csv'}: {len(self.times_s)} frames but the job renders "
                             f"{len(result.frames)}")
        self.camera = CameraModel.for_input(None, self.root)
        self.telemetry = read_telemetry(self.root / "telemetry.csv")
        self.inertial = interpolate_telemetry(self.telemetry, self.times_s, source=str(self.root / "telemetry.csv"))
        self.truth = read_truth(self.root / "truth.csv")
        self.labels = read_labels(self.root / "labels.csv")
        runway = self.root / "runway.json"
        self.runway_json = runway if runway.exists() else None
        #: seconds spent rendering (summed over the rendering threads or processes' results)
        self.render_wall_s = 0.0

    def _tasks(self):
        from visland.datasets.generate import _payload
        from visland.features import batch_R_camera_from_runway
        s = self._result.frames
        camera = self._result.camera_true
        R_camera_from_runway = batch_R_camera_from_runway(s.roll_rad, s.pitch_rad, s.dpsi_rad, camera.mount_rpy_rad)
        payload = _payload(self._job, self._result)
        return [(payload, i, s.p_runway_m[i], R_camera_from_runway[i]) for i in range(len(s))]

    def _rendered(self):
        """``(index, rgb)`` in order, rendered ahead in a thread or a process pool."""
        tasks = self._tasks()
        if self._workers > 1:
            yield from self._rendered_in_processes(tasks)
            return
        frames: queue.Queue = queue.Queue(maxsize=self._prefetch)
        stop = threading.Event()

        def render_all():
            # the renderer is made, used and closed in this one thread (its GL context is current here)
            from visland.datasets.generate import frame_seed
            from visland.render import FrameRenderer
            renderer = None
            try:
                payload = tasks[0][0]
                renderer = FrameRenderer(self._job.scene, self._result.camera_true, self._result.scenario.runway)
                for _, index, p_runway_m, R_camera_from_runway in tasks:
                    if stop.is_set():
                        return
                    rgb = renderer.render(p_runway_m, R_camera_from_runway,
                                          frame_seed=frame_seed(payload["scene"]["seed"], index))
                    frames.put((index, rgb))
                frames.put(None)
            except BaseException as error:          # handed to the consumer
                frames.put(error)
            finally:
                if renderer is not None:
                    renderer.close()

        thread = threading.Thread(target=render_all, daemon=True)
        thread.start()
        try:
            while True:
                item = frames.get()
                if item is None:
                    return
                if isinstance(item, BaseException):
                    raise item
                yield item
        finally:
            stop.set()
            while thread.is_alive():              # unblock a renderer waiting on a full queue
                try:
                    frames.get(timeout=0.1)
                except queue.Empty:
                    pass
            thread.join()

    def _rendered_in_processes(self, tasks):
        """``(index, rgb)`` in order, rendered ahead by a pool of spawned processes.

        Each frame comes back through a block of shared memory (:class:`_SharedFrames`): the
        worker copies it in, this process copies it out, and only the block's name goes through
        the pool's pipe. Pickling 12.6 MB frames through the pipe instead cost a pickle, two
        kernel copies and an unpickle per frame, and kept both sides busy in the pipe. At most
        ``workers + prefetch`` frames are rendered ahead (one block each).
        """
        import multiprocessing
        from collections import deque
        import cv2  # noqa: F401 -- imported before the spawn: a spawned child takes sys.path as it is
        #             then, and OpenCV's loader puts its own folder there while another thread imports it
        shape = (self.camera.height, self.camera.width, 3)
        workers = min(self._workers, len(tasks))
        ring = None
        if _shared_memory_room(int(np.prod(shape)) * (workers + self._prefetch)):
            ring = _SharedFrames(min(len(tasks), workers + self._prefetch), shape)
        context = multiprocessing.get_context("spawn")              # one fresh GL context per process
        try:
            with context.Pool(workers) as pool:
                try:
                    if ring is None:
                        yield from pool.imap(_render_task, tasks, chunksize=1)
                        return
                    pending: deque = deque()                        # (block, AsyncResult) in frame order
                    todo = iter(tasks)
                    for task in todo:
                        block = ring.take()
                        pending.append((block, pool.apply_async(_render_task_shared, (task, block, shape))))
                        if not len(ring):
                            break
                    while pending:
                        block, result = pending.popleft()
                        index, rgb = result.get()
                        if rgb is None:
                            rgb = ring.read(block)
                        else:                               # came back whole: its block was not used
                            ring.release(block)
                        task = next(todo, None)
                        if task is not None:
                            block = ring.take()
                            pending.append((block, pool.apply_async(_render_task_shared, (task, block, shape))))
                        yield index, rgb
                finally:
                    pool.terminate()
        finally:
            if ring is not None:
                ring.close()

    def frames(self, gray: bool = True, prefetch: int = 4):
        """Yield ``(index, image, None)`` in order: RGB (H, W, 3) uint8, or grey levels when ``gray``."""
        expected = (self.camera.height, self.camera.width)
        for index, rgb in self._rendered():
            if rgb.shape[:2] != expected:          # the job's camera and camera.json disagree: a bug, say so
                raise ValueError(f"frame {index}: rendered {rgb.shape[1]}x{rgb.shape[0]}, camera.json says "
                                 f"{self.camera.width}x{self.camera.height}")
            if self._writer is not None:
                self._writer.put(index, rgb)
            yield index, (as_grey(rgb) if gray else rgb), None


def stream_process(job, dataset_dir, run_dirs: dict, options, workers: int = 1, echo=print,
                   keep_frames: bool = False, writer_threads: int = 1) -> dict:
    """Simulate ``job``, write its dataset files (no frames), render and measure every frame in
    memory with every source of ``run_dirs`` (``{source: run folder}``), estimate and write the
    runs as ``visland process`` does with ``options`` (:class:`visland.datasets.process.ProcessOptions`).
    With ``keep_frames`` a :class:`FrameWriter` also writes the frames, and the dataset's manifest
    is written last (the folder is then a complete ``visland generate`` dataset).
    Returns ``{source: run.json content}``.

    Parameters
    ----------
    job : visland.datasets.generate.GenerateJob
        Scenario, simulation options (camera, frame rate, seed) and scene.
    dataset_dir : str or pathlib.Path
        The dataset folder (metadata files; the frames too with ``keep_frames``).
    run_dirs : dict
        Measurement source kind -> its run folder (replaced if present).
    options : visland.datasets.process.ProcessOptions
        What the runs do.
    workers : int, optional
        Render processes (1: a background thread of this process).
    echo : callable, optional
        Takes each printed line (a str).
    keep_frames : bool, optional
        Also write the frames as PNG files, byte-identical to ``visland generate``'s.
    writer_threads : int, optional
        Threads of the :class:`FrameWriter` with ``keep_frames``.

    Returns
    -------
    dict
        Source kind -> the content of that run's run.json.
    """
    import json
    from visland.contracts import atomic_write_text
    from visland.datasets.generate import dataset_manifest
    from visland.datasets.process import process_many
    from visland.simulate import run_simulation
    from visland.datasets.generate import JOB_FILE
    started = time.perf_counter()
    started_epoch = time.time()
    result = run_simulation(job.scenario, job.options)
    if keep_frames:
        # as visland generate: the job's identity first, so that an interrupted run is resumed by
        # generate_dataset (frames are written atomically: a frame file that exists is complete)
        Path(dataset_dir).mkdir(parents=True, exist_ok=True)
        atomic_write_text(Path(dataset_dir) / JOB_FILE, json.dumps(job.identity(), indent=2) + "\n")
    write_dataset_files(result, dataset_dir)
    writer = FrameWriter(Path(dataset_dir) / "frames", job.png_compression, threads=writer_threads) \
        if keep_frames else None
    source = RenderedSource(dataset_dir, job, result, workers=workers, writer=writer)
    try:
        runs = process_many(source, run_dirs, options, force=True, echo=echo, run_processes=workers)
    finally:
        if writer is not None:
            tic = time.perf_counter()
            writer.close()
            writer.tail_s = time.perf_counter() - tic
    echo(f"{len(source)} frames rendered and measured in memory in {time.perf_counter() - started:.0f} s")
    if writer is not None:
        if len(writer.digests) != len(source):
            raise RuntimeError(f"{dataset_dir}: {len(writer.digests)} of {len(source)} frames written")
        if job.lard:                              # as visland generate writes them
            from visland.datasets.generate import frame_name
            from visland.datasets.lard import lard_rows, write_lard_labels
            from visland.render.markings import designator_number
            (Path(dataset_dir) / "lard").mkdir(exist_ok=True)
            rows = lard_rows(result, [f"frames/{frame_name(i)}" for i in range(len(source))],
                             f"{designator_number(job.scenario.runway.heading_deg):02d}", job.scenario.name)
            write_lard_labels(Path(dataset_dir) / "lard" / "labels.csv", rows)
        atomic_write_text(Path(dataset_dir) / "manifest.json",
                          json.dumps(dataset_manifest(job, result, writer.digests), indent=1) + "\n")
        # dated when the dataset's content was fixed (before the runs), as a campaign compares them
        os.utime(Path(dataset_dir) / "manifest.json", (started_epoch, started_epoch))
        (Path(dataset_dir) / JOB_FILE).unlink()
        echo(f"frames kept by the background writer: {writer.encode_s:.1f} s of PNG encoding and writing, "
             f"rendering and measuring waited {writer.blocked_s:.1f} s on it, {writer.tail_s:.1f} s after the "
             f"last frame")
    return runs
