"""``visland process``: frames (a folder or a video) plus telemetry in; measurements, estimates,
metrics and a report out.

The output folder is self-contained, so any stage can be rerun on it (for example
``visland estimate OUT --measurements OUT/measurements.csv --observer all --out ...``)::

    OUT/measurements.csv   image measurements (SPEC labels schema + source, found, reason, confidence)
    OUT/estimates.csv      one row per observer per frame
    OUT/metrics.json       with truth: the seeds' metrics per observer (dH) and dY, dX errors
    OUT/run.json           what was run: input, source, scenario, frames used and flagged, throughput
    OUT/report.html        self-contained report with plots
    OUT/camera.json, OUT/telemetry.csv, OUT/truth.csv   copies of the inputs the estimates used

The folder is built aside and moved into place when complete; an existing OUT is refused
unless ``--force``.
"""
from __future__ import annotations

import json
import math
import shutil
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from visland import __version__
from visland.contracts import MEASUREMENT_COLUMNS, atomic_write_text, json_ready, staged_output_dir, write_csv

__all__ = ["ProcessOptions", "process_input", "process_many", "DEFAULT_OBSERVERS"]

#: Every observer of the seeds (SPEC names).
DEFAULT_OBSERVERS = ("oj-2p", "ii-2p", "cccs-2p", "ccpi-hg-2p", "ccpi-hosm-2p", "cccj-2p", "kf-2p",
                     "oj-2l", "ii-2l", "ccpi-2l", "cccj-2l", "ekf-2l", "ecc-hg", "ecc-hosm")


@dataclass(frozen=True)
class ProcessOptions:
    """What ``visland process`` does (see its --help); validated on construction (``ValueError``
    naming the command-line option).

    Attributes
    ----------
    source : str
        How features are measured: ``detection``, ``tracking``, ``anchored`` (tracking re-anchored
        on detection) or ``ideal`` (the folder's labels.csv); tracking kinds may name a template
        update policy (``tracking:every_frame``).
    observers : tuple of str
        Observer names (SPEC), at least one.
    camera, telemetry, frames_csv : str or None
        A camera.json, telemetry.csv or frames.csv (SPEC contracts) to use instead of the input's own.
    fps : float or None
        Frame rate (Hz) when there is no frames.csv; None: 25 Hz or the video's own.
    initial_height_m : float or None
        Initial guess of the height above the runway (m); required without truth.csv.
    initial_error : float
        With truth.csv and no ``initial_height_m``: start this fraction above the true height
        (0.2, the seeds' 20 %).
    init : str or None
        Tracking designation of the threshold corners: ``labels`` or ``"u,v;u,v"`` in pixels
        (SPEC convention: u right, v down, (0, 0) the centre of the top-left pixel).
    report : bool
        Whether to write the HTML report.
    quiet : bool
        No progress bar.
    params_file : str or None
        Observer parameters (TOML or JSON).
    time_offset_s : float
        Seconds added to the telemetry's times to put them on the frames' clock, within +-60 s
        (:mod:`visland.clocks`).
    estimate_offset : bool
        Estimate that offset from the horizon's roll in the frames.
    self_calibration : bool
        Apply the camera mounting's self-calibration (``estimate --self-calibration``); False: it is
        computed and reported only.
    windows : str
        Who places detection's search windows: ``detector`` or ``dickmanns-4d``
        (:mod:`visland.datasets.filter_windows`).
    """

    source: str = "detection"
    observers: tuple = DEFAULT_OBSERVERS
    camera: str | None = None
    telemetry: str | None = None
    frames_csv: str | None = None
    fps: float | None = None
    initial_height_m: float | None = None
    initial_error: float = 0.2
    init: str | None = None          # tracking designation: "labels" or "u,v;u,v"
    report: bool = True
    quiet: bool = False
    params_file: str | None = None
    time_offset_s: float = 0.0        # added to the telemetry's times (visland.clocks)
    estimate_offset: bool = False
    self_calibration: bool = False    # apply the mounting's self-calibration (estimate --self-calibration)
    windows: str = "detector"         # who places detection's search windows (visland.datasets.filter_windows)

    def __post_init__(self):
        from visland.datasets.measure import parse_source
        parse_source(self.source)
        if not self.observers:
            raise ValueError("--observer: give at least one observer name")
        from visland.limits import FPS_LIMIT
        if self.fps is not None and not (math.isfinite(self.fps) and FPS_LIMIT.low <= self.fps <= FPS_LIMIT.high):
            raise ValueError(f"--fps must be a frame rate in {FPS_LIMIT.low:g}..{FPS_LIMIT.high:g} Hz, got {self.fps!r}")
        from visland.estimation.command import check_initial_guess
        check_initial_guess(self.initial_height_m, self.initial_error)
        from visland.datasets.filter_windows import WINDOW_SOURCES
        if self.windows not in WINDOW_SOURCES:
            raise ValueError(f"--windows must be one of {', '.join(WINDOW_SOURCES)}, got {self.windows!r}")
        if not (math.isfinite(self.time_offset_s) and abs(self.time_offset_s) <= 60.0):
            raise ValueError(f"--time-offset must be a number of seconds within +-60, got {self.time_offset_s!r}")


def _align_clocks(source, options: ProcessOptions, echo) -> None:
    """With ``--estimate-offset``, shift the telemetry (already moved by ``--time-offset`` when
    the source was opened) by the offset estimated from the frames (:mod:`visland.clocks`); an
    estimate the data do not support is said and the telemetry stays as it is."""
    if not options.estimate_offset:
        return
    from visland.clocks import estimate_time_offset
    try:
        found = estimate_time_offset(source)
    except ValueError as error:
        echo(f"clock offset not estimated: {error}; using --time-offset ({options.time_offset_s:+.3f} s)")
        return
    echo(f"clock offset estimated from the horizon's roll against the telemetry's: {found.offset_s:+.3f} s "
         f"+- {found.sigma_s:.3f} s (one sigma; {found.inliers} of {found.frames_used} frames follow the telemetry's "
         f"roll, residual {found.residual_deg:.2f} deg)")
    source.shift_telemetry(found.offset_s)


def _scenario_of(source) -> str | None:
    """Scenario name from a generated dataset's manifest, if any."""
    root = Path(source.name)
    manifest = (root if root.is_dir() else root.parent) / "manifest.json"
    if manifest.exists():
        try:
            data = json.loads(manifest.read_text())
        except json.JSONDecodeError:
            return None
        scenario = data.get("scenario")
        if isinstance(scenario, dict):
            return scenario.get("name")
        if isinstance(scenario, str):
            return scenario
    return None


def _deviation_errors(truth, estimates_path: Path) -> dict:
    """dY and dX errors (truth - estimate) at 400/200/100 ft per observer (``dY_err_400ft_m``, ...)."""
    from visland.contracts import read_estimates
    from visland.estimation.metrics import errors_at_heights
    estimates = read_estimates(estimates_path)
    out = {}
    for observer in dict.fromkeys(estimates["observer"]):
        keep = estimates["observer"] == observer
        entry = {}
        for column, label in (("dy_m", "dY"), ("dx_m", "dX")):
            errors = errors_at_heights(truth["dh_m"], truth[column], estimates[column][keep])
            entry.update({f"{label}_{key}": value for key, value in errors.items()})
        out[observer] = entry
    return out



def process_input(input_path, out_dir, options: ProcessOptions | None = None, force: bool = False,
                  echo=print) -> dict:
    """Run the whole offline pipeline on ``input_path`` into ``out_dir``; return run.json's content.

    Parameters
    ----------
    input_path : str or pathlib.Path or visland.datasets.sources.FrameSource
        A frame folder (SPEC contract), a video, or a frame source already open.
    out_dir : str or pathlib.Path
        The run folder: measurements.csv, estimates.csv, run.json, with truth metrics.json and
        the report.
    options : ProcessOptions, optional
        What to do; None: the defaults.
    force : bool, optional
        Replace an existing output folder (else ``ValueError``).
    echo : callable, optional
        Takes each printed line (a str).

    Returns
    -------
    dict
        The content of run.json (frames, found and flagged frames, observers, files written).
    """
    options = options or ProcessOptions()
    return process_many(input_path, {options.source: out_dir}, options, force=force, echo=echo)[options.source]


def process_many(input_path, out_dirs: dict, options: ProcessOptions | None = None, force: bool = False,
                 echo=print, run_processes: int = 1) -> dict:
    """Process ``input_path`` with several measurement sources (``{source: out_dir}``), decoding
    every frame once; one run folder per source. Returns ``{source: run.json content}``.

    ``input_path`` is a frame folder, a video, or a :class:`visland.datasets.sources.FrameSource`
    already open (the frames streamed from the renderer, :mod:`visland.datasets.stream`).

    Parameters
    ----------
    input_path : str or pathlib.Path or visland.datasets.sources.FrameSource
        A frame folder (SPEC contract), a video, or a frame source already open.
    out_dirs : dict
        Measurement source kind (as :attr:`ProcessOptions.source`) -> its run folder.
    options : ProcessOptions, optional
        What to do (its ``source`` is replaced by each key of ``out_dirs``); None: the defaults.
    force : bool, optional
        Replace existing output folders (else ``ValueError``).
    echo : callable, optional
        Takes each printed line (a str).
    run_processes : int, optional
        With more than 1 and several sources, each source's estimation, metrics and report (what
        follows the last frame) run side by side: all but the last source in spawned processes
        (at most ``run_processes``), the last here (:func:`_write_runs_side_by_side`). Same files;
        the printed lines come out in the sources' order, as one after the other.

    Returns
    -------
    dict
        Source kind -> the content of that run's run.json.

    Raises
    ------
    ValueError
        An output exists without ``force``, the input breaks a SPEC contract (one sentence naming
        the file and row), or there is neither truth.csv nor an initial height.
    """
    from visland.datasets.measure import measure_many
    from visland.datasets.sources import FrameSource, open_source
    from visland.estimation.command import EstimateOptions

    options = options or ProcessOptions()
    started = time.perf_counter()
    for source_kind in out_dirs:
        replace(options, source=source_kind)               # validates the kind
    if isinstance(input_path, FrameSource):
        source, input_path = input_path, input_path.name
        _check_paths(input_path, out_dirs, options, force)
    else:
        _check_paths(input_path, out_dirs, options, force)
        source = open_source(input_path, camera=options.camera, telemetry=options.telemetry,
                             frames_csv=options.frames_csv, fps=options.fps, time_offset_s=options.time_offset_s)
    _align_clocks(source, options, echo)
    if source.truth is None and options.initial_height_m is None:
        raise ValueError(f"{input_path}: no truth.csv, so give the initial height guess with --initial-height M")
    _check_agreement(source, options)
    estimate_options = EstimateOptions(observers=tuple(options.observers), measurements="(set below)",
                                       initial_height_m=options.initial_height_m,
                                       initial_error=options.initial_error, params_file=options.params_file,
                                       self_calibration="apply" if options.self_calibration else "check")
    echo(f"{source.name}: {len(source)} frames of {source.camera.width}x{source.camera.height}, "
         f"{source.times_s[-1] - source.times_s[0]:.1f} s; measuring with {', '.join(out_dirs)}")
    if getattr(source, "timing", "").startswith("variable"):
        echo(f"{source.name}: {source.timing}")
    measured = measure_many(source, list(out_dirs), init=options.init, quiet=options.quiet,
                            windows=_filter_windows(options) if options.windows == "dickmanns-4d" else None)
    if run_processes > 1 and len(out_dirs) > 1:
        return _write_runs_side_by_side(source, measured, out_dirs, options, estimate_options, input_path, force,
                                        started, echo, run_processes)
    runs = {}
    for kind, out_dir in out_dirs.items():
        runs[kind] = _write_run(source, measured[kind], replace(options, source=kind), estimate_options,
                                input_path, out_dir, force, started, echo)
    return runs


def _portable(source):
    """What :func:`_write_run` reads of ``source``, without the frames (picklable: a frame source
    may hold a decoder, a renderer or threads)."""
    from types import SimpleNamespace
    return SimpleNamespace(**{name: getattr(source, name, None)
                              for name in ("name", "camera", "telemetry", "truth", "labels", "runway_json", "timing")})


def _write_run_task(source, measurements, options, estimate_options, input_path, out_dir, force, started):
    """:func:`_write_run` in a spawned process: ``(run, printed lines)``."""
    lines: list = []
    run = _write_run(source, measurements, options, estimate_options, input_path, out_dir, force, started,
                     lines.append)
    return run, lines


def _write_runs_side_by_side(source, measured, out_dirs, options, estimate_options, input_path, force, started,
                             echo, processes: int) -> dict:
    """:func:`_write_run` for every source at once: all but the last in at most ``processes``
    spawned processes, the last in this one. The runs are the serial ones (the same calls on the
    same measurements); the lines each prints are echoed in the sources' order once all are done.

    With two sources on two cores this halves the time after the last frame (each run's
    estimation by every observer and its report's plots are single-threaded Python).
    """
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor
    kinds = list(out_dirs)
    portable = _portable(source)
    runs: dict = {}
    lines: dict = {kind: [] for kind in kinds}
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=min(processes, len(kinds) - 1), mp_context=context) as pool:
        futures = {kind: pool.submit(_write_run_task, portable, measured[kind], replace(options, source=kind),
                                     estimate_options, input_path, out_dirs[kind], force, started)
                   for kind in kinds[:-1]}
        last = kinds[-1]
        runs[last] = _write_run(portable, measured[last], replace(options, source=last), estimate_options,
                                input_path, out_dirs[last], force, started, lines[last].append)
        for kind, future in futures.items():
            runs[kind], lines[kind] = future.result()
    for kind in kinds:
        for line in lines[kind]:
            echo(line)
    return {kind: runs[kind] for kind in kinds}


def _filter_windows(options: ProcessOptions):
    """``windows(source)`` for :func:`visland.datasets.measure.measure`: dickmanns-4d placing the
    detector's search windows, started with the same height guess as the observers."""
    from visland.datasets.filter_windows import FilterWindows

    def make(source):
        def dh0_of_frame(k):
            if options.initial_height_m is not None:
                return options.initial_height_m
            return (1.0 + options.initial_error) * float(source.truth["dh_m"][k])
        return FilterWindows(source, dh0_of_frame, "apply" if options.self_calibration else "off")
    return make


def _check_paths(input_path, out_dirs: dict, options: ProcessOptions, force: bool) -> None:
    """Every path the user gave, checked before any work (issue 19): what it must be, and that
    each output folder can be made."""
    from visland.userfiles import check_input_file, check_output_folder
    path = Path(input_path)
    if not path.exists():
        raise ValueError(f"{path}: input not found (give a frame folder or a video file)")
    for value, option, what in ((options.camera, "--camera", "camera file"),
                                (options.telemetry, "--telemetry", "telemetry file"),
                                (options.frames_csv, "--frames-csv", "frame times file"),
                                (options.params_file, "--params", "observer parameter file")):
        if value is not None:
            check_input_file(value, what, option)
    folder = path if path.is_dir() else path.parent
    if options.camera is None and (folder / "camera.json").exists():
        check_input_file(folder / "camera.json", "camera file")        # a folder named camera.json, say
    for out_dir in out_dirs.values():
        check_output_folder(out_dir, force=force)


def _check_agreement(source, options: ProcessOptions) -> None:
    """What only the inputs together can tell, checked before the first frame is measured
    (issue 20 item 2): the camera's plausibility, frame times against the telemetry rate, truth
    and labels (one row per frame, at the frame times), the labels' pixels in the image."""
    from visland.limits import (check_camera, check_frame_times, check_pixels, check_rows_at_frames,
                                check_telemetry_rate)
    times = np.asarray(source.times_s, dtype=float)
    how = ("frame times (--fps)" if options.fps is not None and options.frames_csv is None else
           f"frame times of {source.name}")
    check_camera(source.camera, options.camera or "camera.json")
    check_frame_times(times, how)
    if source.telemetry is not None:
        check_telemetry_rate(source.telemetry["t_s"], times, str(source.telemetry.path))
    for table, what in ((source.truth, "truth"), (source.labels, "labels")):
        if table is not None:
            check_rows_at_frames(table, times, how, what)
    if source.labels is not None:
        check_pixels(source.labels, source.camera.width, source.camera.height)


def _write_run(source, measurements, options, estimate_options, input_path, out_dir, force, started, echo) -> dict:
    """Estimation, metrics, run.json and report of one source's measurements, into ``out_dir``."""
    from visland.contracts import read_measurements
    from visland.estimation.command import estimate_folder

    with staged_output_dir(out_dir, force=force) as staging:
        write_csv(staging / "measurements.csv", measurements.columns, MEASUREMENT_COLUMNS)
        source.camera.save(staging / "camera.json")
        write_csv(staging / "telemetry.csv", dict(source.telemetry), source.telemetry.column_order)
        if source.truth is not None:
            write_csv(staging / "truth.csv", dict(source.truth), source.truth.column_order)
        if source.runway_json is not None:
            shutil.copyfile(source.runway_json, staging / "runway.json")
        read_measurements(staging / "measurements.csv")       # what we hand on reads back cleanly
        not_started: dict = {}
        diverged: dict = {}
        restarted: dict = {}
        calibration: dict = {}
        metrics = estimate_folder(staging, _with_measurements(estimate_options, staging / "measurements.csv"),
                                  staging / "estimates.csv",
                                  echo=lambda line: echo(line.replace(str(staging), str(out_dir))),
                                  not_started=not_started, diverged=diverged, calibration_out=calibration,
                                  restarted=restarted)
        deviations = _deviation_errors(source.truth, staging / "estimates.csv") if source.truth is not None else {}
        if metrics:
            doc = json.loads((staging / "metrics.json").read_text())
            doc["source"] = options.source
            doc["scenario"] = _scenario_of(source)
            doc["deviations"] = json_ready(deviations)
            atomic_write_text(staging / "metrics.json", json.dumps(doc, indent=2) + "\n")
        wall = time.perf_counter() - started
        n = measurements.n_frames
        run = {
            "software": f"visland {__version__}",
            "input": str(input_path),
            "source": options.source,
            "scenario": _scenario_of(source),
            "observers": list(options.observers),
            "n_frames": n,
            # how the frame times were obtained (frames.csv, --fps, the video's constant or variable rate)
            "frame_timing": getattr(source, "timing", None),
            "n_found": measurements.n_found,
            "n_flagged": len(measurements.flagged),
            "flagged": [{"frame": int(i), "reason": r} for i, r in measurements.flagged],
            # observers that never started (their estimates.csv rows are empty), and why
            "no_estimates": not_started,
            # observers cut off when they diverged (estimates withheld from then on), and when
            "diverged": diverged,
            # observers restarted after a long gap without a measurement, when and from what height
            "restarted": restarted,
            # the camera mounting's error and the runway's slope estimated from the runway
            # (visland.estimation.calibration), applied with --self-calibration, else reported only
            "self_calibration": calibration.get("summary"),
            "throughput": {
                "measure_wall_s": measurements.wall_s,
                "analysis_s": measurements.analysis_s,
                "fps_with_decoding": n / measurements.wall_s if measurements.wall_s > 0 else None,
                "fps_analysis_only": n / measurements.analysis_s if measurements.analysis_s > 0 else None,
                "total_wall_s": wall,
            },
        }
        atomic_write_text(staging / "run.json", json.dumps(json_ready(run), indent=2) + "\n")
        if options.report:
            _write_report(staging, source, measurements, metrics, deviations, run)
    _print_summary(run, metrics, deviations, out_dir, echo, report=options.report)
    return run


def _with_measurements(options, path):
    return replace(options, measurements=str(path))


def _write_report(folder: Path, source, measurements, metrics, deviations, run) -> None:
    from visland.contracts import read_estimates
    from visland.datasets.report import write_report
    estimates = read_estimates(folder / "estimates.csv")
    columns = {k: np.asarray(v) if k in ("source", "reason") else np.asarray(v, dtype=float)
               for k, v in measurements.columns.items()}
    from visland.estimation.metrics import METRIC_DEFINITIONS
    merged = {}
    for observer, values in (metrics or {}).items():
        merged[observer] = {"conv. 5 % to 100 ft (s)": values.get("conv_time_5pct_s"),
                            "conv. 5 % to the end (s)": values.get("conv_time_5pct_to_end_s")}
        merged[observer].update({f"dH @ {h} ft (m)": values.get(f"err_{h}ft_m") for h in (400, 200, 100)})
        merged[observer].update({f"{q} @ 100 ft (m)": deviations.get(observer, {}).get(f"{q}_err_100ft_m")
                                 for q in ("dY", "dX")})
    throughput = run["throughput"]
    summary = [
        ("input", run["input"]), ("scenario", run["scenario"] or "-"), ("measurements", run["source"]),
        ("frames", f"{run['n_frames']} ({run['n_found']} with the runway found, {run['n_flagged']} unusable)"),
        ("throughput", "-" if not throughput["fps_with_decoding"] else
         f"{throughput['fps_with_decoding']:.1f} frames/s with decoding, "
         + (f"{throughput['fps_analysis_only']:.1f} frames/s analysis only" if throughput["fps_analysis_only"]
            else "no frame analysed")),
        ("observers", ", ".join(run["observers"])),
    ]
    calibration = run.get("self_calibration")
    if calibration:
        e, g = calibration["mount_error_deg"], calibration["mount_error_sigma_deg"]
        summary.append(("camera mounting (self-calibration)",
                        f"error roll {e['roll']:+.3f} +- {g['roll']:.3f} deg, pitch {e['pitch']:+.3f} +- "
                        f"{g['pitch']:.3f} deg, yaw {e['yaw']:+.3f} +- {g['yaw']:.3f} deg; runway slope "
                        f"{calibration['slope_pct']:+.2f} +- {calibration['slope_sigma_pct']:.2f} %; "
                        + ("applied to the measurements" if calibration["applied"]
                           else "reported only (--self-calibration applies it)")))
        if calibration.get("problem"):
            summary.append(("CALIBRATION PROBLEM", calibration["problem"]))
    for observer, why in run.get("no_estimates", {}).items():
        summary.append((f"{observer}: no estimates", why))
    for observer, why in run.get("diverged", {}).items():
        summary.append((f"{observer}: DIVERGED", why))
    for observer, sentences in run.get("restarted", {}).items():
        summary.append((f"{observer}: restarted", "; ".join(sentences)))
    write_report(folder / "report.html", title=f"visland run: {run['scenario'] or Path(run['input']).name} "
                                               f"({run['source']})",
                 summary_rows=summary, measurements=columns, estimates=dict(estimates),
                 truth=dict(source.truth) if source.truth is not None else None,
                 labels=dict(source.labels) if source.labels is not None else None, camera=source.camera,
                 metrics=merged or None, flagged=measurements.flagged,
                 metric_notes=[f"conv. 5 % to 100 ft: {METRIC_DEFINITIONS['conv_time_5pct_s']}.",
                               f"conv. 5 % to the end: {METRIC_DEFINITIONS['conv_time_5pct_to_end_s']}.",
                               f"dH @ h ft: {METRIC_DEFINITIONS['err_<h>ft_m']}; dY and dX likewise."])


def _print_summary(run, metrics, deviations, out_dir, echo, report: bool = True) -> None:
    t = run["throughput"]
    echo(f"{run['n_frames']} frames: runway found in {run['n_found']}, {run['n_flagged']} unusable; "
         f"{t['fps_with_decoding'] or 0:.1f} frames/s with decoding, {t['fps_analysis_only'] or 0:.1f} frames/s "
         f"analysis only")
    if run.get("no_estimates"):
        names = list(run["no_estimates"])
        first = run["no_estimates"][names[0]]
        echo(f"no estimates from {', '.join(names)}: {first}" if len(set(run["no_estimates"].values())) == 1 else
             "no estimates from " + "; ".join(f"{name} ({why})" for name, why in run["no_estimates"].items()))
    if metrics:
        echo(f"{'observer':14s} {'conv 5% s':>9s} {'dH@400ft':>9s} {'dH@200ft':>9s} {'dH@100ft':>9s} "
             f"{'dY@100ft':>9s} {'dX@100ft':>9s}")
        for observer, m in metrics.items():
            d = deviations.get(observer, {})

            def f(v):
                return f"{v:9.3f}" if v is not None and math.isfinite(v) else f"{'-':>9s}"
            echo(f"{observer:14s} {f(m.get('conv_time_5pct_s'))} {f(m.get('err_400ft_m'))} {f(m.get('err_200ft_m'))} "
                 f"{f(m.get('err_100ft_m'))} {f(d.get('dY_err_100ft_m'))} {f(d.get('dX_err_100ft_m'))}")
    echo(f"wrote {out_dir}/: measurements.csv estimates.csv run.json"
         + (" metrics.json" if metrics else "") + (" report.html" if report else ""))
