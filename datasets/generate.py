"""``visland generate``: fly a scenario, render every camera frame, write a SPEC dataset.

Output folder (SPEC.md "File contracts")::

    frames/000000.png ...   one PNG per camera frame (RGB), zero-padded 0-based index
    frames.csv              frame,t_s
    telemetry.csv truth.csv labels.csv camera.json runway.json     as `visland simulate`
    manifest.json           format version, scenario, seeds, scene parameters, software
                            version, and the SHA-256 of every frame
    lard/labels.csv         with --lard: LARD v2 corner labels (``;``-separated)

Frames are rendered with the camera *as mounted* (``SimulationResult.camera_true``, which
differs from ``camera.json`` when a calibration error is asked for).

Resumable and safe:

- each frame is written to a temporary file and renamed into place, so a frame file that
  exists is complete; the job's identity (everything that determines the bytes) is written to
  ``.visland-generate.json`` before the first frame and compared on every run;
- run the same command again after a kill, a full disk or a crash: finished frames are kept,
  the missing ones rendered, and the result is byte-identical to an uninterrupted run
  (rendering, noise and PNG encoding are deterministic for a given seed);
- a folder holding another job (other scenario, options, scene, size or visland version) or
  anything that is not a visland dataset is refused, never overwritten (unless ``force``);
- ``manifest.json`` is written last: its presence means the dataset is complete.

Rendering runs in local worker processes (spawn start method, one GL context each) or, given
a scheduler address, on an existing Dask distributed cluster whose workers can import visland;
the workers return PNG bytes and this process writes them, so the output folder need only be
visible here.
"""
from __future__ import annotations

import errno
import hashlib
import json
import os
import shutil
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from visland import __version__
from visland.contracts import FRAMES_COLUMNS, atomic_write_bytes, atomic_write_text, write_csv
from visland.features import batch_R_camera_from_runway
from visland.progress import progress_bar
from visland.render.params import SceneParams
from visland.scenarios import Scenario
from visland.simulate import FORMAT_VERSION, SimulationOptions, SimulationResult, run_simulation, write_simulation_files

__all__ = ["GenerateJob", "GenerateReport", "generate_dataset", "frame_name", "JOB_FILE", "MIN_SIZE", "MAX_SIZE",
           "MAX_WORKERS", "DATASET_FORMAT_VERSION"]

DATASET_FORMAT_VERSION = 1
JOB_FILE = ".visland-generate.json"
MIN_SIZE = 64
MAX_SIZE = 4096
MAX_WORKERS = 64


def frame_name(index: int) -> str:
    """File name of frame ``index`` inside ``frames/``.

    Parameters
    ----------
    index : int
        0-based frame index.

    Returns
    -------
    str
        Six digits and ``.png``.
    """
    return f"{index:06d}.png"


@dataclass(frozen=True)
class GenerateJob:
    """Everything that determines a dataset's bytes.

    Parameters
    ----------
    scenario : Scenario
    options : SimulationOptions
        Simulation options; ``options.camera`` sets the image size and ``options.fps`` the rate.
    scene : SceneParams
        How frames look (its seed seeds the textures and the sensor noise).
    png_compression : int
        zlib level of the PNG files, 0-9 (1 by default: fastest, about 10 % larger than 6).
    lard : bool
        Also write ``lard/labels.csv``.
    """

    scenario: Scenario
    options: SimulationOptions
    scene: SceneParams = field(default_factory=SceneParams)
    png_compression: int = 1
    lard: bool = False

    def __post_init__(self):
        size = self.options.camera.width
        if not MIN_SIZE <= size <= MAX_SIZE or self.options.camera.height != size:
            raise ValueError(f"--size must be a square image of {MIN_SIZE} to {MAX_SIZE} px, got "
                             f"{self.options.camera.width}x{self.options.camera.height}")
        if isinstance(self.png_compression, bool) or self.png_compression not in range(10):
            raise ValueError(f"png_compression must be an integer from 0 to 9, got {self.png_compression!r}")

    def identity(self) -> dict:
        """What a folder must match to be resumed (JSON-ready; no times, no paths)."""
        return {
            "format_version": DATASET_FORMAT_VERSION,
            "simulation_format_version": FORMAT_VERSION,
            "kind": "dataset",
            "software": f"visland {__version__}",
            "scenario": self.scenario.to_dict(),
            "options": self.options.to_json_dict(),
            "seeds": {"simulation": self.options.seed, "imu": self.options.imu.seed, "scene": self.scene.seed},
            "scene": self.scene.to_dict(),
            "png_compression": self.png_compression,
            "lard": self.lard,
        }


@dataclass
class GenerateReport:
    """What a run did.

    Attributes
    ----------
    out_dir : Path
        The dataset folder.
    n_frames : int
        Frames in the dataset.
    rendered, reused : int
        Frames rendered by this run, and kept from an interrupted one.
    seconds : float
        Wall time, seconds.
    already_complete : bool
        The folder was complete: nothing was done.
    """

    out_dir: Path
    n_frames: int
    rendered: int
    reused: int
    seconds: float
    already_complete: bool = False


# --------------------------------------------------------------------------- rendering workers
_WORKER = {}
_WORKER_LOCK = threading.Lock()


def _payload(job: GenerateJob, result: SimulationResult) -> dict:
    """What a worker needs to render any frame of the job (small, picklable)."""
    camera = result.camera_true
    return {"scene": job.scene.to_dict(), "camera": camera.to_json_dict(),
            "runway": result.scenario.runway.to_json_dict(), "png_compression": job.png_compression}


def _renderer_for(payload: dict):
    """The process's renderer for ``payload`` (built once per process and payload)."""
    from visland.camera import CameraModel
    from visland.render import FrameRenderer
    from visland.runway import Runway
    key = json.dumps(payload, sort_keys=True)
    if _WORKER.get("key") != key:
        if _WORKER.get("renderer") is not None:
            _WORKER["renderer"].close()
        runway = Runway(**payload["runway"])
        camera = CameraModel.from_json_dict(payload["camera"], source="worker camera")
        _WORKER["renderer"] = FrameRenderer(SceneParams.from_dict(payload["scene"]), camera, runway)
        _WORKER["key"] = key
    return _WORKER["renderer"]


def frame_seed(scene_seed: int, index: int) -> int:
    """Seed of frame ``index``'s sensor noise."""
    return (int(scene_seed) * 1_000_003 + int(index)) % (2 ** 63)


def encode_frame_png(rgb, png_compression: int, index: int = -1) -> bytes:
    """The PNG bytes of a rendered RGB frame, as every dataset stores them (OpenCV, BGR order)."""
    import cv2
    ok, encoded = cv2.imencode(".png", np.ascontiguousarray(rgb[..., ::-1]),
                               [cv2.IMWRITE_PNG_COMPRESSION, int(png_compression)])
    if not ok:
        raise RuntimeError(f"frame {index}: PNG encoding failed")
    return encoded.tobytes()


def render_frame_png(payload: dict, index: int, p_runway_m, R_camera_from_runway) -> tuple[int, bytes]:
    """Render and PNG-encode one frame; ``(index, png_bytes)``. Safe to call from several threads."""
    with _WORKER_LOCK:
        renderer = _renderer_for(payload)
        rgb = renderer.render(np.asarray(p_runway_m, float), np.asarray(R_camera_from_runway, float),
                              frame_seed=frame_seed(payload["scene"]["seed"], index))
    return index, encode_frame_png(rgb, payload["png_compression"], index)


def _pool_task(task):
    # no Pool initializer: an error there (no EGL, say) makes Pool restart workers forever;
    # raised here, it reaches the parent through imap
    payload, index, p, R = task
    return render_frame_png(payload, index, p, R)


# --------------------------------------------------------------------------- folder state
def _read_json(path: Path):
    try:
        return json.loads(path.read_text())
    except (OSError, json.JSONDecodeError):
        return None


def _same_job(stored: dict | None, identity: dict) -> bool:
    if not isinstance(stored, dict):
        return False
    return {k: stored.get(k) for k in identity} == json.loads(json.dumps(identity))


def _describe_difference(stored: dict, identity: dict) -> str:
    wanted = json.loads(json.dumps(identity))
    for key in ("software", "format_version", "scenario", "options", "scene", "seeds", "png_compression", "lard"):
        if stored.get(key) != wanted.get(key):
            if key == "scenario":
                return f"scenario {stored.get('scenario', {}).get('name', '?')!r} differs from {wanted['scenario']['name']!r}"
            if key == "software":
                return f"it was made by {stored.get('software')!r}, this is {wanted['software']!r}"
            return f"its {key.replace('_', ' ')} differ{'s' if not key.endswith('s') else ''}"
    return "it was made by another job"


def _prepare_folder(out: Path, identity: dict, force: bool) -> str:
    """Check ``out`` and return its state: 'new', 'resume' or 'complete'. Refuses foreign folders."""
    if out.exists() and not out.is_dir():
        raise ValueError(f"{out}: exists and is not a folder; choose another --out")
    if out.is_dir():
        manifest = _read_json(out / "manifest.json")
        job = _read_json(out / JOB_FILE)
        entries = [p for p in out.iterdir()]
        if force and entries:
            shutil.rmtree(out)
            return "new"
        if manifest is not None and manifest.get("kind") == "dataset":
            if _same_job(manifest, identity) and job is None:
                return "complete"
            raise ValueError(f"{out}: holds a dataset from another job ({_describe_difference(manifest, identity)}); "
                             "it is not overwritten: choose another --out, or pass --force to replace it")
        if job is not None:
            if _same_job(job, identity):
                return "resume"
            raise ValueError(f"{out}: holds an unfinished dataset from another job "
                             f"({_describe_difference(job, identity)}); it is not overwritten: choose another --out, "
                             "or pass --force to replace it")
        if entries:
            raise ValueError(f"{out}: exists and is not a visland dataset; it is not overwritten: choose another "
                             "--out, or pass --force to replace it")
        return "new"
    return "new"


def _disk_error(out: Path, what: str, error: OSError) -> ValueError:
    reason = os.strerror(error.errno) if error.errno else str(error)
    hint = ""
    if error.errno in (errno.ENOSPC, errno.EDQUOT):
        hint = "; free some space"
    elif error.errno in (errno.EROFS, errno.EACCES, errno.EPERM):
        hint = "; choose a writable --out"
    return ValueError(f"{out}: cannot write {what} ({reason}){hint}; the frames already written are complete and "
                      "running the same command again resumes from them")


# --------------------------------------------------------------------------- the job
def generate_dataset(job: GenerateJob, out_dir, workers: int = 1, scheduler: str | None = None,
                     force: bool = False, progress: bool = True, result: SimulationResult | None = None
                     ) -> GenerateReport:
    """Simulate, render and write the dataset of ``job`` into ``out_dir`` (resuming if possible).

    Parameters
    ----------
    job : GenerateJob
    out_dir : output folder (created; refused if it holds something else, see module docstring).
    workers : local worker processes, 1-64 (1 renders in this process); ignored with ``scheduler``.
    scheduler : address of a Dask distributed scheduler (e.g. ``tcp://127.0.0.1:8786``).
    force : replace whatever ``out_dir`` holds.
    progress : draw a progress bar on stderr (on a terminal only, see :mod:`visland.progress`).
    result : a simulation already run for ``job`` (saves running it again).
    """
    if isinstance(workers, bool) or not isinstance(workers, int) or not 1 <= workers <= MAX_WORKERS:
        raise ValueError(f"--workers must be an integer from 1 to {MAX_WORKERS}, got {workers!r}")
    t0 = time.perf_counter()
    out = Path(out_dir)
    identity = job.identity()
    state = _prepare_folder(out, identity, force)
    result = result or run_simulation(job.scenario, job.options)
    n = len(result.frames)
    names = [frame_name(i) for i in range(n)]
    if state == "complete":
        missing = [name for name in names if not (out / "frames" / name).is_file()]
        if not missing:
            return GenerateReport(out, n, 0, n, time.perf_counter() - t0, already_complete=True)
        # a complete dataset that lost frames: resume it (the manifest is rewritten at the end)
        state = "resume"
    frames_dir = out / "frames"
    try:
        frames_dir.mkdir(parents=True, exist_ok=True)
        if (out / "manifest.json").exists():
            (out / "manifest.json").unlink()
        atomic_write_text(out / JOB_FILE, json.dumps(identity, indent=2) + "\n")
        write_simulation_files(result, out)
        # the simulation manifest is replaced by the dataset manifest at the end
        (out / "manifest.json").unlink()
        write_csv(out / "frames.csv", {"frame": np.arange(n), "t_s": result.frames.t_s}, FRAMES_COLUMNS)
        if job.lard:
            from .lard import lard_rows, write_lard_labels
            from visland.render.markings import designator_number
            (out / "lard").mkdir(exist_ok=True)
            rows = lard_rows(result, [f"frames/{name}" for name in names],
                             f"{designator_number(job.scenario.runway.heading_deg):02d}", job.scenario.name)
            write_lard_labels(out / "lard" / "labels.csv", rows)
        for stale in frames_dir.glob(".*.tmp"):
            stale.unlink()
    except OSError as error:
        raise _disk_error(out, "the dataset files", error) from None

    digests = {}
    pending = [i for i, name in enumerate(names) if not (frames_dir / name).is_file()]
    reused = n - len(pending)
    s = result.frames
    camera = result.camera_true
    R_cr = batch_R_camera_from_runway(s.roll_rad, s.pitch_rad, s.dpsi_rad, camera.mount_rpy_rad)
    tasks = [(i, s.p_runway_m[i], R_cr[i]) for i in pending]
    payload = _payload(job, result)
    if tasks and not scheduler:
        from visland.render.glview import check_opengl
        check_opengl()          # one clear sentence here rather than in every worker
    bar = progress_bar(n, "render", initial=reused, enabled=progress)

    def write(index: int, data: bytes) -> None:
        try:
            atomic_write_bytes(frames_dir / names[index], data)
        except OSError as error:
            raise _disk_error(out, f"frame {index}", error) from None
        digests[index] = hashlib.sha256(data).hexdigest()
        bar.update()

    try:
        if tasks:
            if scheduler:
                _run_dask(scheduler, payload, tasks, write)
            elif workers == 1:
                for index, p, R in tasks:
                    write(*render_frame_png(payload, index, p, R))
            else:
                _run_pool(workers, payload, tasks, write)
    finally:
        bar.close()

    for i, name in enumerate(names):
        if i not in digests:
            digests[i] = hashlib.sha256((frames_dir / name).read_bytes()).hexdigest()
    manifest = dataset_manifest(job, result, digests)
    try:
        atomic_write_text(out / "manifest.json", json.dumps(manifest, indent=1) + "\n")
        (out / JOB_FILE).unlink()
    except OSError as error:
        raise _disk_error(out, "manifest.json", error) from None
    return GenerateReport(out, n, len(tasks), reused, time.perf_counter() - t0)


def dataset_manifest(job: GenerateJob, result: SimulationResult, digests: dict) -> dict:
    """``manifest.json`` of a complete dataset of ``job`` (``digests``: frame index -> SHA-256)."""
    s, camera = result.frames, result.camera_true
    manifest = dict(job.identity())
    manifest.update({
        "n_frames": len(s), "image_size": [camera.width, camera.height], "fps": job.options.fps,
        "duration_s": result.trajectory.duration_s, "end_reason": result.trajectory.end_reason,
        "camera_true_mount_rpy_deg": list(camera.mount_rpy_deg),
        "files": {"frames": "frames/", "frames_csv": "frames.csv", "telemetry": "telemetry.csv", "truth": "truth.csv",
                  "labels": "labels.csv", "camera": "camera.json", "runway": "runway.json",
                  **({"lard": "lard/labels.csv"} if job.lard else {})},
        "frames": [{"frame": i, "file": f"frames/{frame_name(i)}", "t_s": round(float(s.t_s[i]), 9),
                    "sha256": digests[i]} for i in range(len(s))],
    })
    return manifest


def _run_pool(workers: int, payload: dict, tasks: list, write) -> None:
    import multiprocessing
    context = multiprocessing.get_context("spawn")   # one fresh GL context per process
    with context.Pool(min(workers, len(tasks))) as pool:
        try:
            for index, data in pool.imap_unordered(_pool_task, [(payload, *task) for task in tasks], chunksize=1):
                write(index, data)
        except BaseException:
            pool.terminate()
            raise


def _run_dask(address: str, payload: dict, tasks: list, write) -> None:
    from visland.datasets.cluster import connect_scheduler
    client = connect_scheduler(address)
    from distributed import as_completed
    try:
        n_workers = max(1, len(client.scheduler_info().get("workers", {})))
        window = 2 * n_workers + 2                       # bounded: PNGs are megabytes each
        queue = list(tasks)
        first = []
        for _ in range(min(window, len(queue))):
            index, p, R = queue.pop(0)
            first.append(client.submit(render_frame_png, payload, index, p, R, pure=False))
        running = as_completed(first, loop=client.loop)
        for future in running:
            index, data = future.result()
            future.release()
            write(index, data)
            if queue:
                index, p, R = queue.pop(0)
                running.add(client.submit(render_frame_png, payload, index, p, R, pure=False))
    finally:
        client.close()
