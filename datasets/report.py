"""Self-contained HTML report of a processed run (plots embedded as PNG, no external files).

Sections: summary (input, source, frames used and flagged, metrics per observer), image
features over time (measured against labels where the folder has them), estimates against
truth (dH, dY, dX and their errors), observability indices, and the pixel errors of the
detection or tracking against the labels.
"""
from __future__ import annotations

import base64
import html
import io
import math

import numpy as np

from visland.contracts import atomic_write_text
from visland.runway import CORNER_NAMES

__all__ = ["write_report", "figure_to_data_uri"]

_CSS = """
body { font-family: -apple-system, 'Segoe UI', Helvetica, Arial, sans-serif; margin: 24px auto; max-width: 1180px;
       color: #1d2327; line-height: 1.45; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; } h2 { border-bottom: 1px solid #ccd; padding-bottom: 4px; margin-top: 1.6em; }
.meta { color: #555; } table { border-collapse: collapse; margin: 8px 0 16px; font-size: 0.92em; }
th, td { border: 1px solid #d0d4d8; padding: 4px 8px; text-align: right; } th { background: #f1f3f5; }
td:first-child, th:first-child { text-align: left; } img { max-width: 100%; border: 1px solid #e3e5e8; }
.warn { background: #fff4e5; border-left: 4px solid #f0a020; padding: 6px 10px; }
.ok { background: #eef8ee; border-left: 4px solid #3a3; padding: 6px 10px; }
"""


def figure_to_data_uri(figure) -> str:
    """A matplotlib figure as a PNG ``data:`` URI (90 dpi), for a self-contained HTML report; the figure is closed.

    Parameters
    ----------
    figure : matplotlib.figure.Figure

    Returns
    -------
    str
    """
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=90, bbox_inches="tight")
    import matplotlib.pyplot as plt
    plt.close(figure)
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")


def _fmt(value, digits=3) -> str:
    if value is None:
        return "-"
    if isinstance(value, str):
        return html.escape(value)
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    value = float(value)
    if not math.isfinite(value):
        return "-"
    if value != 0 and (abs(value) < 1e-3 or abs(value) >= 1e5):
        return f"{value:.{digits}e}"
    return f"{value:.{digits}f}"


def _table(header: list[str], rows: list[list]) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{_fmt(c)}</td>" for c in row) + "</tr>" for row in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def _plots_features(measurements, labels, camera):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    t = measurements["t_s"]
    fig, axes = plt.subplots(2, 2, figsize=(12, 6.5), sharex=True)
    for ax, coord in zip(axes[0], ("u", "v")):
        for name, color in zip(CORNER_NAMES[:2], ("tab:blue", "tab:red")):
            column = f"{name}_{coord}_px"
            if labels is not None:
                visible = labels[f"{name}_visible"] > 0.5
                ax.plot(labels["t_s"], np.where(visible, labels[column], np.nan), color=color, lw=2.5, alpha=0.35,
                        label=f"{name} (labels)")
            ax.plot(t, measurements[column], ".", ms=2, color=color, label=f"{name} (measured)")
        if camera is not None:
            ax.set_ylim(-0.5, (camera.width if coord == "u" else camera.height) - 0.5)
        ax.set_ylabel(f"{coord} (px)")
        ax.set_title(f"threshold corners P', P'': {coord}")
        ax.legend(fontsize=7, loc="best")
    for ax, quantity, unit in zip(axes[1], ("theta_rad", "rho"), ("(rad)", "(normalised)")):
        for name, color in zip(("left", "right"), ("tab:green", "tab:purple")):
            column = f"{name}_{quantity}"
            if labels is not None:
                ax.plot(labels["t_s"], labels[column], color=color, lw=2.5, alpha=0.35, label=f"{name} edge (labels)")
            ax.plot(t, measurements[column], ".", ms=2, color=color, label=f"{name} edge (measured)")
        ax.set_ylabel(f"{quantity.split('_')[0]} {unit}")
        ax.set_xlabel("t (s)")
        ax.set_title(f"edge lines: {quantity.split('_')[0]}")
        ax.legend(fontsize=7, loc="best")
    return figure_to_data_uri(fig)


def _plot_heading(measurements, truth):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(12, 2.8))
    ax.plot(measurements["t_s"], measurements["dpsi_deg"], ".", ms=2, label="from d_F (measured)")
    if truth is not None:
        ax.plot(truth["t_s"], truth["dpsi_deg"], lw=1.5, color="k", alpha=0.6, label="truth")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("dpsi (deg)")
    ax.set_title("heading deviation")
    ax.legend(fontsize=8)
    return figure_to_data_uri(fig)


def _observer_series(estimates, observer):
    keep = estimates["observer"] == observer
    return {k: v[keep] for k, v in estimates.items()}


_GROUPS = (("two points", "-2p"), ("two lines", "-2l"), ("ECC'15 system", "ecc-"))


def _group_of(observer: str) -> str:
    for label, key in _GROUPS:
        if key in observer:
            return label
    return "other"


def _plots_estimates(estimates, truth, observers):
    """dH against truth, then the errors of dH, dY and dX, one column per feature set."""
    import matplotlib.pyplot as plt
    groups = [label for label, _ in _GROUPS if any(_group_of(o) == label for o in observers)]
    groups += ["other"] if any(_group_of(o) == "other" for o in observers) else []
    quantities = [("dh_m", "dH"), ("dy_m", "dY"), ("dx_m", "dX")]
    rows = len(quantities) + 1
    fig, axes = plt.subplots(rows, len(groups), figsize=(4.2 * len(groups) + 1, 2.5 * rows), sharex=True,
                             squeeze=False)
    for col, group in enumerate(groups):
        members = [o for o in observers if _group_of(o) == group]
        ax = axes[0][col]
        if truth is not None:
            ax.plot(truth["t_s"], truth["dh_m"], color="k", lw=2.5, alpha=0.5, label="truth")
        for k, observer in enumerate(members):
            series = _observer_series(estimates, observer)
            ax.plot(series["t_s"], series["dh_m"], color=f"C{k}", lw=1, label=observer)
        ax.set_yscale("log")
        ax.set_title(group)
        ax.legend(fontsize=7)
        if col == 0:
            ax.set_ylabel("dH (m)")
        for row, (column, label) in enumerate(quantities, start=1):
            ax = axes[row][col]
            if truth is None:
                ax.set_visible(False)
                continue
            plotted = 0
            for k, observer in enumerate(members):
                series = _observer_series(estimates, observer)
                if not np.isfinite(series[column]).any():
                    continue
                truth_at = np.interp(series["t_s"], truth["t_s"], truth[column])
                ax.plot(series["t_s"], truth_at - series[column], color=f"C{k}", lw=0.8)
                plotted += 1
            if not plotted:
                ax.text(0.5, 0.5, f"{label} is not estimated from {group}", ha="center", va="center",
                        transform=ax.transAxes, fontsize=8, color="0.4")
            # linear within a metre: noise around zero stays a wiggle, transients show in decades
            ax.set_yscale("symlog", linthresh=1.0)
            ax.axhline(0, color="k", lw=0.5)
            if col == 0:
                ax.set_ylabel(f"{label} error (m)")
            if row == rows - 1:
                ax.set_xlabel("t (s)")
    fig.suptitle("estimates (top) and truth - estimate (symmetric log scale, linear within 1 m)", y=1.0)
    fig.tight_layout()
    return figure_to_data_uri(fig)


def _plot_observability(estimates, observers):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(12, 3))
    for observer in observers:
        series = _observer_series(estimates, observer)
        ax.semilogy(series["t_s"], np.maximum(series["observability"], 1e-12), lw=1, label=observer)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("observability index")
    ax.set_title("observability (thesis 3.30 for points, 3.40 for lines)")
    ax.legend(fontsize=7, ncol=4)
    return figure_to_data_uri(fig)


def _pixel_errors(measurements, labels, camera):
    """Per-frame corner errors (px) and edge-line distances (px), as :mod:`visland.datasets.pixel_errors`
    defines them (edges only with the camera)."""
    from visland.datasets.pixel_errors import corner_errors_px, edge_errors_px
    errors = corner_errors_px(measurements, labels)
    if camera is not None:
        errors.update({f"{edge} edge": e for edge, e in edge_errors_px(measurements, labels, camera).items()})
    return errors


def _plot_pixel_errors(t, errors):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(12, 3.2))
    plotted = 0
    for name, series in errors.items():
        if np.isfinite(series).any():
            ax.semilogy(t, np.maximum(series, 1e-3), ".", ms=2, label=name)
            plotted += 1
    ax.set_xlabel("t (s)")
    ax.set_ylabel("error (px)")
    ax.set_title("image-processing error against the labels")
    if plotted:
        ax.legend(fontsize=7, ncol=3)
    else:
        # a run without a measured frame: say so rather than draw empty axes
        ax.text(0.5, 0.5, "no frame was measured: nothing to compare with the labels", transform=ax.transAxes,
                ha="center", va="center")
        if len(t) > 1:
            ax.set_xlim(float(np.min(t)), float(np.max(t)))
    return figure_to_data_uri(fig)


def write_report(path, *, title: str, summary_rows: list[tuple[str, str]], measurements, estimates,
                 truth=None, labels=None, camera=None, metrics: dict | None = None,
                 flagged: list[tuple[int, str]] | None = None, metric_notes: list[str] | None = None) -> None:
    """Write the HTML report.

    Parameters
    ----------
    path : output file.
    title : page title.
    summary_rows : (label, value) lines of the summary table.
    measurements : table in the measurements schema (dict of arrays).
    estimates : table in the estimates schema.
    truth, labels : optional tables (enable errors).
    camera : :class:`visland.camera.CameraModel`, used for line errors in pixels.
    metrics : ``{observer: {metric: value}}``.
    flagged : ``[(frame, reason)]`` of frames that could not be used.
    metric_notes : sentences defining the metrics, listed under their table.
    """
    import matplotlib
    matplotlib.use("Agg")
    observers = list(dict.fromkeys(estimates["observer"]))
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
             f"<style>{_CSS}</style></head><body>", f"<h1>{html.escape(title)}</h1>"]
    parts.append(_table(["item", "value"], [[k, v] for k, v in summary_rows]))
    flagged = flagged or []
    if flagged:
        shown = "".join(f"<li>frame {i}: {html.escape(r)}</li>" for i, r in flagged[:20])
        more = f"<li>... and {len(flagged) - 20} more (see measurements.csv)</li>" if len(flagged) > 20 else ""
        parts.append(f"<div class='warn'><b>{len(flagged)} frame(s) not used</b><ul>{shown}{more}</ul></div>")
    else:
        parts.append("<div class='ok'>Every frame was used.</div>")
    if metrics:
        names = list(dict.fromkeys(m for values in metrics.values() for m in values))
        parts.append("<h2>Metrics (truth - estimate)</h2>")
        parts.append(_table(["observer"] + names, [[obs] + [metrics[obs].get(m) for m in names] for obs in metrics]))
        if metric_notes:
            parts.append("<ul class='meta'>" + "".join(f"<li>{html.escape(n)}</li>" for n in metric_notes) + "</ul>")
    parts.append("<h2>Estimates against truth</h2>")
    parts.append(f"<img src='{_plots_estimates(estimates, truth, observers)}' alt='estimates'>")
    parts.append("<h2>Observability</h2>")
    parts.append(f"<img src='{_plot_observability(estimates, observers)}' alt='observability'>")
    parts.append("<h2>Image features</h2>")
    parts.append(f"<img src='{_plots_features(measurements, labels, camera)}' alt='features'>")
    parts.append(f"<img src='{_plot_heading(measurements, truth)}' alt='heading'>")
    if labels is not None:
        errors = _pixel_errors(measurements, labels, camera)
        parts.append("<h2>Image-processing errors against the labels</h2>")
        rows = []
        for name, series in errors.items():
            finite = series[np.isfinite(series)]
            rows.append([name, finite.size, np.median(finite) if finite.size else None,
                         np.percentile(finite, 95) if finite.size else None, finite.max() if finite.size else None])
        parts.append(_table(["feature", "frames", "median px", "p95 px", "max px"], rows))
        parts.append(f"<img src='{_plot_pixel_errors(measurements['t_s'], errors)}' alt='pixel errors'>")
    parts.append("<p class='meta'>visland report: conventions and file contracts in the README; "
                 "errors are truth minus estimate.</p></body></html>")
    atomic_write_text(path, "\n".join(parts))
