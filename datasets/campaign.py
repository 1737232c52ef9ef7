"""``visland campaign``: generate, process and compare a set of scenarios in one command.

Layout of the campaign folder::

    DIR/campaign.json                 what was asked (scenarios, size, fps, sources, observers)
    DIR/datasets/<scenario>/          ``visland generate`` output (resumable)
    DIR/runs/<scenario>-<source>/     ``visland process`` output
    DIR/compare/                      ``visland compare`` of every run (tables, plots)

Scenarios are done one after the other (generate, then process with every source), so that
``--prune-frames`` can delete each scenario's images once its runs are written: a 2048x2048
campaign of eight approaches otherwise needs tens of GB of PNGs.

Resumable: run the same command again after an interruption. A scenario whose runs are all
up to date is skipped; a half-rendered dataset resumes frame by frame; the comparison is
rebuilt. A campaign folder made with other settings is refused unless ``--force``.

With ``--prune-frames`` (frames not kept, as ``visland demo`` by default) a scenario is rendered
and measured in memory (:mod:`visland.datasets.stream`): no PNG is written or decoded, the
dataset folder holds the metadata only, and the runs are identical to the file route's. When
frames are kept, a scenario not yet generated is streamed the same way while a background writer
writes its frames (:class:`visland.datasets.stream.FrameWriter`; the folder ends as a complete
``visland generate`` dataset, and an interrupted one is resumed by ``generate``); a dataset that
already has frames takes the file route: each scenario's runs processed in one decoding pass.

With ``--scheduler`` every scenario that needs runs is submitted at once as one task (render,
measure and estimate in memory, :func:`_cluster_task`), so the cluster runs them side by side;
each task works in a folder of its worker's own and returns the files it made, which this
process writes as the scenario ends: the workers need no file system shared with the client.
Frames kept are generated on the cluster as well, by ``visland generate``'s route (each frame a
task, its PNG streamed back and written here) while the scenarios run. The runs are the serial
campaign's, byte for byte (``tests/datasets/test_campaign_cluster.py``).
"""
from __future__ import annotations

import json
import re
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

from visland.contracts import atomic_write_text

__all__ = ["CampaignOptions", "run_campaign", "parse_scenario_list"]

_RANGE = re.compile(r"^(?P<prefix>.*?)(?P<a>\d+)\.\.(?P=prefix)?(?P<b>\d+)$")


def parse_scenario_list(items) -> list[str]:
    """Expand ``thesis-1..thesis-8`` (or ``thesis-1..8``) and comma-separated names; keep order.

    Parameters
    ----------
    items : iterable of str
        The ``--scenarios`` words: names, ranges, comma-separated lists, .toml scenario files.

    Returns
    -------
    list of str
        Each scenario once, in the order given.

    Raises
    ------
    ValueError
        An unknown scenario, a backward range, or none at all (one sentence naming it).
    """
    from visland.scenarios import BUILTIN_SCENARIOS
    out: list[str] = []
    for item in items:
        for part in filter(None, (p.strip() for p in str(item).split(","))):
            match = _RANGE.match(part)
            if match:
                a, b = int(match["a"]), int(match["b"])
                if b < a:
                    raise ValueError(f"--scenarios: range '{part}' runs backwards")
                names = [f"{match['prefix']}{k}" for k in range(a, b + 1)]
            else:
                names = [part]
            for name in names:
                if name not in BUILTIN_SCENARIOS and not Path(name).is_file():
                    raise ValueError(f"--scenarios: unknown scenario '{name}'; known: {', '.join(BUILTIN_SCENARIOS)} "
                                     "(or a .toml scenario file)")
                if name not in out:
                    out.append(name)
    if not out:
        raise ValueError("--scenarios: give at least one scenario")
    return out


@dataclass(frozen=True)
class CampaignOptions:
    """What a campaign runs (see ``visland campaign --help``).

    Attributes
    ----------
    scenarios : tuple of str
        Scenario names or .toml files (:func:`parse_scenario_list`).
    size : int
        Image width and height (px) of the SPEC default camera scaled to it.
    fps : float
        Camera frame rate (Hz).
    sources : tuple of str
        Measurement sources, one run each (as ``visland process --source``).
    observers : tuple of str
        Observer names (SPEC); empty: ``visland process``'s default set.
    seed : int
        Seed of every random generator.
    workers : int
        Local rendering processes (without ``scheduler``).
    scheduler : str or None
        A Dask scheduler address: every scenario a task on that cluster (module docstring).
    scene : dict
        Scene parameters (:class:`visland.render.params.SceneParams` fields); empty: the defaults.
    prune_frames : bool
        Keep no frames (render and measure in memory).
    png_compression : int
        PNG compression level of kept frames, 0-9.
    """

    scenarios: tuple
    size: int = 2048
    fps: float = 25.0
    sources: tuple = ("detection",)
    observers: tuple = ()
    seed: int = 0
    workers: int = 1
    scheduler: str | None = None
    scene: dict = field(default_factory=dict)
    prune_frames: bool = False
    png_compression: int = 1

    def __post_init__(self):
        from visland.datasets.measure import parse_source
        for source in self.sources:
            parse_source(source)

    def settings(self) -> dict:
        """What must match for a campaign folder to be resumed (not workers nor scheduler)."""
        data = asdict(self)
        data.pop("workers")
        data.pop("scheduler")
        data.pop("prune_frames")
        data["scenarios"] = list(self.scenarios)
        data["sources"] = list(self.sources)
        data["observers"] = list(self.observers)
        return data


def _run_is_current(run_dir: Path, dataset: Path, source: str, observers: tuple) -> bool:
    info = run_dir / "run.json"
    if not info.exists():
        return False
    try:
        data = json.loads(info.read_text())
        manifest = (dataset / "manifest.json").stat().st_mtime
    except (json.JSONDecodeError, OSError):
        return False
    return (data.get("source") == source and list(data.get("observers", [])) == list(observers)
            and info.stat().st_mtime >= manifest)


def _prune_frames(dataset: Path) -> None:
    """Delete a processed dataset's images (they dominate the disk); keep everything else."""
    import shutil
    shutil.rmtree(dataset / "frames", ignore_errors=True)


def _process_task(dataset: str, run_dirs: dict, observers: tuple) -> str:
    """Process one dataset with every source it still needs, decoding each frame once
    (module-level so that Dask can ship it to a worker)."""
    from visland.datasets.process import ProcessOptions, process_many
    lines: list[str] = []
    process_many(dataset, run_dirs, ProcessOptions(observers=observers, quiet=True), force=True, echo=lines.append)
    return "\n".join(lines)


def _stream_task(job, dataset: str, run_dirs: dict, observers: tuple, workers: int, keep_frames: bool = False) -> str:
    """Render one scenario's frames and measure them in memory with every source it still needs,
    the frames written by a background writer when kept (module-level so that Dask can ship it to
    a worker; see :mod:`visland.datasets.stream`)."""
    from visland.datasets.process import ProcessOptions
    from visland.datasets.stream import stream_process
    lines: list[str] = []
    stream_process(job, dataset, run_dirs, ProcessOptions(observers=observers, quiet=True), workers=workers,
                   echo=lines.append, keep_frames=keep_frames)
    return "\n".join(lines)


def _cluster_task(job, dataset: str, run_dirs: dict, observers: tuple) -> dict:
    """One scenario on a Dask worker: render and measure in memory (:func:`_stream_task`) in a
    folder of the worker's own, and return every file made, for the client to write.

    The worker needs no file system shared with the client: the folders are laid out under a
    temporary root as they will be under the campaign's (``datasets/NAME``, ``runs/NAME-SOURCE``),
    and the temporary root is replaced by the campaign's in the files that record paths
    (run.json's ``input``, the report), so that what the client writes is what a run in place
    would have written.

    Returns
    -------
    dict
        ``log`` (the run's printed lines), ``dataset`` and ``runs`` (``{source: {...}}``): each a
        mapping of file paths relative to its folder -> bytes.
    """
    import tempfile
    out = Path(dataset).parent.parent
    with tempfile.TemporaryDirectory(prefix="visland-campaign-") as tmp:
        here = Path(tmp)
        local_dataset = here / Path(dataset).relative_to(out)
        local_runs = {source: str(here / Path(run_dir).relative_to(out)) for source, run_dir in run_dirs.items()}
        log = _stream_task(job, str(local_dataset), local_runs, observers, 1)

        def files(folder: Path) -> dict:
            found = {}
            for path in sorted(p for p in folder.rglob("*") if p.is_file()):
                data = path.read_bytes()
                if path.suffix in (".json", ".html"):
                    data = data.replace(str(here).encode(), str(out).encode())
                found[str(path.relative_to(folder))] = data
            return found
        return {"log": log.replace(str(here), str(out)), "dataset": files(local_dataset),
                "runs": {source: files(Path(run_dir)) for source, run_dir in local_runs.items()}}


def _write_folder(folder: Path, files: dict) -> None:
    """Replace ``folder`` by the files of a cluster task (atomically: built aside, then moved in)."""
    from visland.contracts import atomic_write_bytes, staged_output_dir
    with staged_output_dir(folder, force=True) as staging:
        for name, data in files.items():
            (staging / name).parent.mkdir(parents=True, exist_ok=True)
            atomic_write_bytes(staging / name, data)


def _finish_on_cluster(client, on_cluster: dict, options: CampaignOptions, started: float, echo) -> None:
    """Write the cluster's results as each scenario ends: its runs, and its dataset's metadata
    (frames pruned) or its frames, generated on the cluster too and streamed back to this process
    by :func:`visland.datasets.generate.generate_dataset` (frames kept) while the scenarios run."""
    from distributed import as_completed
    if not options.prune_frames:
        for name, dataset, _, job in on_cluster.values():
            _generate(job, dataset, options, started, echo)
    for future in as_completed(list(on_cluster), loop=client.loop):
        name, dataset, todo, _ = on_cluster[future]
        result = future.result()
        future.release()
        if options.prune_frames:
            _write_folder(dataset, result["dataset"])      # the metadata; frames of an earlier run go
        for source, run_dir in todo.items():
            _write_folder(Path(run_dir), result["runs"][source])
        echo(f"[{time.perf_counter() - started:6.0f} s] {name}: runs of {', '.join(todo)} back from the cluster")
        for line in result["log"].splitlines():
            if "frames: runway found" in line or "in memory in" in line:
                echo("         " + line)


def _generate(job, dataset: Path, options: CampaignOptions, started: float, echo) -> None:
    """``visland generate`` of one scenario's frames into ``dataset`` (resumed if half done), on the
    cluster when there is one (each frame a task, written here); the metadata of an earlier
    streamed run is replaced."""
    import shutil

    from visland.datasets.generate import generate_dataset
    if _is_streamed(dataset):
        shutil.rmtree(dataset)
    echo(f"[{time.perf_counter() - started:6.0f} s] generate {job.scenario.name} ({options.size} px, "
         f"{options.fps:g} Hz)" + (f" on {options.scheduler}, frames written here" if options.scheduler else ""))
    report = generate_dataset(job, dataset, workers=options.workers, scheduler=options.scheduler, force=False)
    echo(f"         {report.n_frames} frames: {report.rendered} rendered, {report.reused} kept, {report.seconds:.0f} s")


def _has_frames(dataset: Path) -> bool:
    """Whether ``dataset`` holds rendered frames (a complete or half-written ``generate``)."""
    return (dataset / "frames").is_dir() and any((dataset / "frames").iterdir())


def _is_streamed(dataset: Path) -> bool:
    """Whether ``dataset`` holds the metadata of a streamed scenario (a simulation manifest, no frames)."""
    try:
        return json.loads((dataset / "manifest.json").read_text()).get("kind") == "simulation"
    except (OSError, json.JSONDecodeError, AttributeError):
        return False


def run_campaign(options: CampaignOptions, out_dir, force: bool = False, echo=print) -> dict:
    """Generate every scenario, process it with every source, compare everything.

    Parameters
    ----------
    options : CampaignOptions
        What to run.
    out_dir : str or pathlib.Path
        The campaign folder (module docstring's layout); resumed if it holds the same campaign.
    force : bool, optional
        Accept a folder holding another campaign or other files.
    echo : callable, optional
        Takes each printed line (a str).

    Returns
    -------
    dict
        :func:`visland.datasets.compare.compare_runs`'s summary of every run.

    Raises
    ------
    ValueError
        The folder holds something else (without ``force``), or the scheduler cannot be reached
        (one sentence, :func:`visland.datasets.cluster.connect_scheduler`).
    """
    from visland.camera import CameraModel
    from visland.cli import simulation_options_from_args
    from visland.datasets.compare import compare_runs
    from visland.datasets.generate import GenerateJob
    from visland.datasets.process import DEFAULT_OBSERVERS
    from visland.render.params import SceneParams
    from visland.scenarios import resolve_scenario

    out = Path(out_dir)
    observers = tuple(options.observers) or DEFAULT_OBSERVERS
    settings = options.settings()
    settings["observers"] = list(observers)
    marker = out / "campaign.json"
    if marker.exists() and not force:
        stored = json.loads(marker.read_text())
        if stored != settings:
            differing = sorted(k for k in settings if stored.get(k) != settings[k])
            raise ValueError(f"{out}: holds a campaign with other settings ({', '.join(differing)}); "
                             "use another --out or --force")
    elif out.exists() and any(out.iterdir()) and not marker.exists() and not force:
        raise ValueError(f"{out}: folder exists and is not a campaign folder; use another --out or --force")
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(marker, json.dumps(settings, indent=2) + "\n")

    started = time.perf_counter()
    scene = SceneParams.from_dict(options.scene) if options.scene else SceneParams()

    class _Args:      # the simulation options a campaign fixes (the same flags as `visland simulate`)
        fps = options.fps
        seed = options.seed
        calibration_error = 0.0
        velocity_bias = 0.0
        imu_noise = 0.0

    runs = []
    client = None
    on_cluster = {}                       # future -> (scenario name, dataset, todo, job)
    if options.scheduler:
        from visland.datasets.cluster import connect_scheduler
        client = connect_scheduler(options.scheduler)
    try:
        for name in options.scenarios:
            scenario = resolve_scenario(name)
            dataset = out / "datasets" / scenario.name
            mine = [(out / "runs" / f"{scenario.name}-{source.replace(':', '-')}", source) for source in options.sources]
            runs.extend(run_dir for run_dir, _ in mine)
            todo = {source: str(run_dir) for run_dir, source in mine
                    if not _run_is_current(run_dir, dataset, source, observers)}
            if not todo:
                echo(f"[{time.perf_counter() - started:6.0f} s] {scenario.name}: every run up to date, kept")
                continue
            sim_options = simulation_options_from_args(_Args, camera=CameraModel.default(options.size))
            job = GenerateJob(scenario=scenario, options=sim_options, scene=scene,
                              png_compression=options.png_compression)
            if client is not None:
                # every scenario one task at once on the cluster; results come back to this process
                echo(f"[{time.perf_counter() - started:6.0f} s] render and measure {scenario.name} in memory "
                     f"({options.size} px, {options.fps:g} Hz) with {', '.join(todo)} on {options.scheduler}")
                future = client.submit(_cluster_task, job, str(dataset), todo, observers, pure=False)
                on_cluster[future] = (scenario.name, dataset, todo, job)
                continue
            keep_streamed = not options.prune_frames and not dataset.exists()
            if (options.prune_frames and not _has_frames(dataset)) or keep_streamed:
                # render and measure in memory, no PNG round trip; frames kept (written by a
                # background writer, the folder then a complete dataset) only when asked
                echo(f"[{time.perf_counter() - started:6.0f} s] render and measure {scenario.name} in memory "
                     f"({options.size} px, {options.fps:g} Hz) with {', '.join(todo)}"
                     + (", frames kept" if keep_streamed else ""))
                text = _stream_task(job, str(dataset), todo, observers, options.workers, keep_streamed)
                for line in text.splitlines():
                    if "frames: runway found" in line or "in memory in" in line or "background writer" in line:
                        echo("         " + line)
                continue
            _generate(job, dataset, options, started, echo)
            echo(f"[{time.perf_counter() - started:6.0f} s] process {scenario.name} with {', '.join(todo)}")
            text = _process_task(str(dataset), todo, observers)
            for line in text.splitlines():
                if "frames: runway found" in line:
                    echo("         " + line)
            if options.prune_frames:
                _prune_frames(dataset)
                echo(f"         {scenario.name}: frames deleted (--prune-frames); labels, telemetry and runs kept")
        if on_cluster:
            _finish_on_cluster(client, on_cluster, options, started, echo)
    finally:
        if client is not None:
            client.close()

    echo(f"[{time.perf_counter() - started:6.0f} s] compare {len(runs)} runs")
    summary = compare_runs(runs, out / "compare", echo=lambda text: None)
    echo((out / "compare" / "compare.md").read_text())
    echo(f"campaign done in {time.perf_counter() - started:.0f} s: {out}/compare/compare.md, "
         f"reports in {out}/runs/*/report.html")
    return summary
