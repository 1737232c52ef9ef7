"""``visland process A B C ... --out DIR``: a batch of recordings (issue 15 item 3).

One run folder per input under ``DIR`` (named after the input; a repeated name gets a suffix),
each exactly what ``visland process INPUT --out DIR/NAME`` writes; an input that fails is one
line of the index with its reason and does not stop the others. At the end ``DIR/index.html``
links every run's report with one line of figures, ``DIR/index.json`` holds the same, and the
``compare`` tables across the runs that have truth go to ``DIR/compare``.

Inputs run one after the other in this process (each already decodes ahead in a thread and the
detector uses both cores through OpenCV); parallel runs over processes or Dask are not done.
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


def process_batch(inputs, out_dir, options, force: bool = False, echo=print) -> dict:
    """Process every input into ``out_dir/<name>``; write the index and the comparison.

    Returns the index: ``{"runs": [{"input", "name", "status", "reason" or figures...}], ...}``.
    """
    from visland.datasets.process import process_input

    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise ValueError(f"--out {out_dir}: is a file; a batch writes a folder of runs")
    out_dir.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    rows = []
    for path, name in zip(inputs, _run_names(inputs)):
        echo(f"== {path} -> {out_dir / name}")
        tic = time.perf_counter()
        try:
            run = process_input(path, out_dir / name, options, force=force, echo=echo)
        except ValueError as error:
            echo(f"{path}: failed: {error}")
            rows.append({"input": str(path), "name": name, "status": "failed", "reason": str(error),
                         "wall_s": time.perf_counter() - tic})
            continue
        rows.append({"input": str(path), "name": name, "status": "done", "wall_s": time.perf_counter() - tic,
                     "report": (out_dir / name / "report.html").exists(), **_figures(out_dir / name, run)})
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
