"""``visland process A B C ... --out DIR``: a batch of recordings (issue 15 item 3).

One run folder per input under ``DIR`` (named after the input; a repeated name gets a suffix),
each exactly what ``visland process INPUT --out DIR/NAME`` writes; an input that fails is one
line of the index with its reason and does not stop the others. At the end ``DIR/index.html``
links every run's report with one line of figures, ``DIR/index.json`` holds the same, and the
``compare`` tables across the runs that have truth go to ``DIR/compare``.

By default the inputs run one after the other in this process (each decodes ahead in a thread
and the detector uses every core through OpenCV). ``workers > 1`` runs that many inputs at once
in worker processes (spawned: each has its own OpenCV state, limited to its share of the cores),
``scheduler`` ships each input to a Dask cluster as one task; either way each run's log is
printed when it ends, and the index and comparison are the same as one after the other.
"""
from __future__ import annotations

import html
import json
import math
import time
from pathlib import Path

from visland.contracts import atomic_write_text, json_ready

__all__ = ["process_batch"]


def _run_names(inputs) -> list[str]:
    names, used = [], set()
    for path in inputs:
        base = Path(path).stem if Path(path).suffix else Path(path).name
        base = base or "run"
        name, k = base, 2
        while name in used:
            name, k = f"{base}-{k}", k + 1
        used.add(name)
        names.append(name)
    return names


def process_one(path: str, run_dir: str, options, force: bool, echo=None, cv_threads: int | dict = 0) -> dict:
    """One input of a batch: its index row, and its log when ``echo`` is None (module level, so
    that a process pool or Dask can ship it). A ``ValueError`` is the row's reason, not raised.
    ``cv_threads``: OpenCV's thread count here (0: leave it), or on Dask a table worker address ->
    count (:func:`opencv_threads_per_worker`)."""
    from visland.datasets.process import process_input
    if isinstance(cv_threads, dict):                      # on Dask: this worker's share of its host
        from dask.distributed import get_worker
        cv_threads = cv_threads.get(get_worker().address, 0)
    if cv_threads:
        import cv2
        cv2.setNumThreads(cv_threads)
    lines: list[str] = []
    tic = time.perf_counter()
    row = {"input": str(path), "name": Path(run_dir).name}
    try:
        run = process_input(path, run_dir, options, force=force, echo=echo or lines.append)
    except ValueError as error:
        (echo or lines.append)(f"{path}: failed: {error}")
        row.update(status="failed", reason=str(error), wall_s=time.perf_counter() - tic)
    else:
        row.update(status="done", wall_s=time.perf_counter() - tic, report=(Path(run_dir) / "report.html").exists(),
                   **_figures(Path(run_dir), run))
    if echo is None:
        row["log"] = lines
    return row


def process_batch(inputs, out_dir, options, force: bool = False, echo=print, workers: int = 1,
                  scheduler: str | None = None) -> dict:
    """Process every input into ``out_dir/<name>``; write the index and the comparison.

    ``workers``: inputs processed at once in worker processes (1: one after the other, here);
    ``scheduler``: a Dask scheduler address, each input one task on the cluster. Returns the
    index: ``{"runs": [{"input", "name", "status", "reason" or figures...}], ...}``.

    Parameters
    ----------
    inputs : sequence of str or Path
        Frame folders or videos.
    out_dir : str or Path
        The batch folder (one run per input, index.html, the comparison).
    options : visland.datasets.process.ProcessOptions
        What each run does.
    force : bool, default False
        Replace an existing ``out_dir``.
    echo : callable, default print
        Where progress lines go.
    workers : int, default 1
        Local worker processes.
    scheduler : str, optional
        A Dask scheduler address.
    """
    from dataclasses import replace
    if isinstance(workers, bool) or not isinstance(workers, int) or not 1 <= workers <= 64:
        raise ValueError(f"--workers must be a whole number from 1 to 64, got {workers!r}")
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise ValueError(f"--out {out_dir}: is a file; a batch writes a folder of runs")
    out_dir.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    jobs = [(str(path), str(out_dir / name)) for path, name in zip(inputs, _run_names(inputs))]
    if scheduler is None and workers == 1:
        rows = []
        for path, run_dir in jobs:
            echo(f"== {path} -> {run_dir}")
            rows.append(process_one(path, run_dir, options, force, echo=echo))
    else:
        quiet = replace(options, quiet=True)              # no progress bars from several runs at once
        rows = _run_parallel(jobs, quiet, force, echo, workers, scheduler)
    done = [out_dir / r["name"] for r in rows if r["status"] == "done"]
    comparison = None
    with_truth = [d for d in done if (d / "metrics.json").exists()]
    if len(with_truth) >= 1:
        from visland.datasets.compare import compare_runs
        compare_runs([str(d) for d in with_truth], str(out_dir / "compare"), echo=echo)
        comparison = "compare"
    index = {"inputs": len(rows), "done": len(done), "failed": len(rows) - len(done), "runs": rows,
             "comparison": comparison, "wall_s": time.perf_counter() - started}
    atomic_write_text(out_dir / "index.json", json.dumps(json_ready(index), indent=2) + "\n")
    atomic_write_text(out_dir / "index.html", _index_html(index))
    echo(f"batch: {len(done)} of {len(rows)} inputs processed in {index['wall_s']:.0f} s; "
         f"index {out_dir / 'index.html'}" + (f", comparison {out_dir / 'compare'}" if comparison else ""))
    return index


def _run_parallel(jobs, options, force: bool, echo, workers: int, scheduler: str | None) -> list:
    """The batch's inputs at once: ``workers`` spawned processes, or tasks on the Dask cluster at
    ``scheduler``; each run's log printed as it ends, the rows in the inputs' order."""
    import concurrent.futures
    import multiprocessing
    import os
    rows: list = [None] * len(jobs)

    def finished(k, row):
        echo(f"== {jobs[k][0]} -> {jobs[k][1]} ({row['status']}, {row['wall_s']:.0f} s)")
        for line in row.pop("log", []):
            echo(line)
        rows[k] = row

    if scheduler is not None:
        from visland.datasets.cluster import connect_scheduler
        client = connect_scheduler(scheduler)
        from distributed import as_completed
        with client:
            shares = opencv_threads_per_worker(client.scheduler_info()["workers"], client.run(os.cpu_count))
            echo(f"batch: {len(jobs)} inputs on the Dask cluster at {scheduler} "
                 f"(OpenCV threads per task: {', '.join(str(n) for n in sorted(set(shares.values())))})")
            futures = {client.submit(process_one, path, run_dir, options, force, None, shares, pure=False): k
                       for k, (path, run_dir) in enumerate(jobs)}
            for future in as_completed(list(futures), loop=client.loop):
                finished(futures[future], future.result())
        return rows
    cv_threads = max(1, (os.cpu_count() or 1) // workers)
    echo(f"batch: {len(jobs)} inputs, {workers} at a time in worker processes")
    with concurrent.futures.ProcessPoolExecutor(max_workers=workers,
                                                mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = {pool.submit(process_one, path, run_dir, options, force, None, cv_threads): k
                   for k, (path, run_dir) in enumerate(jobs)}
        for future in concurrent.futures.as_completed(futures):
            finished(futures[future], future.result())
    return rows


def opencv_threads_per_worker(workers: dict, cpu_counts: dict) -> dict:
    """OpenCV's thread count for a task on each Dask worker: its host's cores shared among the
    task slots (threads) of every worker on that host, at least 1.

    Without it each task's OpenCV would start one thread per core of the host, and two workers of
    one host would each use all the cores at once (measured: 88 s against 54 s for the same batch
    in two worker processes that share the cores).

    Parameters
    ----------
    workers : dict
        ``Client.scheduler_info()["workers"]``: worker address -> its info with ``"host"`` and
        ``"nthreads"``.
    cpu_counts : dict
        Worker address -> ``os.cpu_count()`` on that worker (``Client.run(os.cpu_count)``).

    Returns
    -------
    dict
        Worker address -> OpenCV threads for a task running there.
    """
    slots_on_host: dict = {}
    for info in workers.values():
        slots_on_host[info["host"]] = slots_on_host.get(info["host"], 0) + max(1, int(info["nthreads"]))
    return {address: max(1, int(cpu_counts.get(address) or 1) // slots_on_host[info["host"]])
            for address, info in workers.items()}


def _figures(run_dir: Path, run: dict) -> dict:
    """One line of figures of a run: frames, found, and the best observer's dH at 100 ft."""
    figures = {"n_frames": run.get("n_frames"), "n_found": run.get("n_found"), "n_flagged": run.get("n_flagged")}
    metrics_path = run_dir / "metrics.json"
    if metrics_path.exists():
        metrics = json.loads(metrics_path.read_text()).get("observers", {})
        best, value = None, None
        for observer, m in metrics.items():
            err = m.get("err_100ft_m") if isinstance(m, dict) else None
            if err is not None and math.isfinite(err) and (value is None or abs(err) < abs(value)):
                best, value = observer, err
        figures.update(best_observer=best, dh_err_100ft_m=value)
    return figures


def _index_html(index: dict) -> str:
    lines = ["<!doctype html><meta charset='utf-8'><title>visland batch</title>",
             "<style>body{font-family:sans-serif;margin:2em}td,th{padding:2px 10px;text-align:left}"
             ".failed{color:#a00}</style>",
             f"<h1>visland batch: {index['done']} of {index['inputs']} inputs processed</h1>", "<table>",
             "<tr><th>run</th><th>input</th><th>frames</th><th>runway found</th><th>best observer</th>"
             "<th>dH error at 100 ft (m)</th><th>wall (s)</th></tr>"]
    for row in index["runs"]:
        name = html.escape(row["name"])
        if row["status"] != "done":
            lines.append(f"<tr class='failed'><td>{name}</td><td>{html.escape(row['input'])}</td>"
                         f"<td colspan='5'>failed: {html.escape(row['reason'])}</td></tr>")
            continue
        report = f"<a href='{name}/report.html'>{name}</a>" if row.get("report") else name
        dh = row.get("dh_err_100ft_m")
        lines.append(f"<tr><td>{report}</td><td>{html.escape(row['input'])}</td><td>{row.get('n_frames')}</td>"
                     f"<td>{row.get('n_found')}</td><td>{html.escape(str(row.get('best_observer') or '-'))}</td>"
                     f"<td>{'-' if dh is None else f'{dh:+.3f}'}</td><td>{row['wall_s']:.0f}</td></tr>")
    lines.append("</table>")
    if index.get("comparison"):
        lines.append(f"<p>Comparison across the runs with truth: <a href='{index['comparison']}/'>"
                     f"{index['comparison']}/</a></p>")
    return "\n".join(lines) + "\n"
