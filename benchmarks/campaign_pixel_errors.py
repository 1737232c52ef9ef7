"""Image-processing errors of a campaign, per source and distance band, and a drift figure.

Reads a ``visland campaign`` folder (its runs' ``measurements.csv`` and the datasets'
``labels.csv``, which --prune-frames keeps) and prints, for every measurement source:

- the share of frames with the runway found;
- the near-corner (threshold) error in pixels, median and 95th percentile, and the largest;
- the edge-line error in pixels (mean distance of the labelled edge's visible points to the
  measured line), median and 95th percentile;
- the heading-deviation error (measured d_F turned into dpsi against the truth), median;

by distance to the threshold (>3 km, 1-3 km, 0.5-1 km, <0.5 km, down to 100 ft), and the
corner error at 5 km, 3 km, 1 km and 100 ft (tracking drift). With --plot it draws the
threshold-corner error against time for every scenario and source.

    python benchmarks/campaign_pixel_errors.py /tmp/campaign/c2048 [--plot docs/campaign_pixel_errors.png]

Ends with one JSON line of the figures.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from visland.camera import CameraModel
from visland.contracts import json_ready, read_labels, read_measurements, read_truth
from visland.datasets.pixel_errors import corner_errors_px, edge_errors_px
from visland.estimation.metrics import FT_TO_M

BANDS = ((3000.0, np.inf, ">3 km"), (1000.0, 3000.0, "1-3 km"), (500.0, 1000.0, "0.5-1 km"), (-np.inf, 500.0, "<0.5 km"))


def run_errors(run_dir: Path, dataset_dir: Path) -> dict:
    measured = read_measurements(run_dir / "measurements.csv")
    labels = read_labels(dataset_dir / "labels.csv")
    truth = read_truth(dataset_dir / "truth.csv")
    camera = CameraModel.load(dataset_dir / "camera.json")
    aim = json.loads((dataset_dir / "runway.json").read_text())["aim_distance_m"]
    distance = -(truth["dx_m"] + aim)                      # to the threshold
    visible = (labels["near_left_visible"] > 0.5) & (labels["near_right_visible"] > 0.5)
    corners = corner_errors_px(measured, labels)
    corner = np.where(visible, np.fmax(corners["near_left"], corners["near_right"]), np.nan)   # the worse of P', P''
    with np.errstate(invalid="ignore"):
        far = np.fmax(corners["far_left"], corners["far_right"])     # the worse runway-end corner (NaN: none)
    edges = np.fmax(*edge_errors_px(measured, labels, camera).values())                      # the worse edge
    dpsi = np.abs(measured["dpsi_deg"] - truth["dpsi_deg"])
    above = truth["dh_m"] >= 100 * FT_TO_M
    return {"t_s": truth["t_s"], "distance_m": distance, "dh_m": truth["dh_m"], "found": measured["found"] > 0.5,
            "corner_px": corner, "far_px": far, "edge_px": edges, "dpsi_deg": dpsi, "above_100ft": above}


def _q(x, k):
    x = x[np.isfinite(x)]
    return float(np.percentile(x, k)) if x.size else None


def summarise(series: list) -> dict:
    cat = {k: np.concatenate([s[k] for s in series]) for k in series[0]}
    keep = cat["above_100ft"]
    out = {"frames": int(keep.sum()), "found_pct": 100.0 * float(cat["found"][keep].mean()), "bands": {}}
    for lo, hi, name in BANDS:
        m = keep & (cat["distance_m"] >= lo) & (cat["distance_m"] < hi)
        if not m.any():
            continue
        out["bands"][name] = {
            "frames": int(m.sum()), "found_pct": 100.0 * float(cat["found"][m].mean()),
            "corner_median_px": _q(cat["corner_px"][m], 50), "corner_p95_px": _q(cat["corner_px"][m], 95),
            "corner_max_px": float(np.nanmax(cat["corner_px"][m])) if np.isfinite(cat["corner_px"][m]).any() else None,
            "edge_median_px": _q(cat["edge_px"][m], 50), "edge_p95_px": _q(cat["edge_px"][m], 95),
            "dpsi_median_deg": _q(cat["dpsi_deg"][m], 50)}
    marks = {}
    for name, test in (("5 km", lambda s: np.argmin(np.abs(s["distance_m"] - 5000.0))),
                       ("3 km", lambda s: np.argmin(np.abs(s["distance_m"] - 3000.0))),
                       ("1 km", lambda s: np.argmin(np.abs(s["distance_m"] - 1000.0))),
                       ("100 ft", lambda s: int(np.argmax(s["dh_m"] <= 100 * FT_TO_M)))):
        values = []
        for s in series:
            i = int(test(s))
            if name == "5 km" and abs(s["distance_m"][i] - 5000.0) > 300:
                continue
            values.append(s["corner_px"][i])
        values = np.array(values, dtype=float)
        marks[name] = {"mean_px": float(np.nanmean(values)) if np.isfinite(values).any() else None,
                       "max_px": float(np.nanmax(values)) if np.isfinite(values).any() else None,
                       "runs": int(values.size), "lost": int(np.sum(~np.isfinite(values)))}
    out["corner_error_at"] = marks
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("campaign", type=Path)
    parser.add_argument("--plot", type=Path, default=None)
    args = parser.parse_args(argv)
    runs = sorted((args.campaign / "runs").iterdir())
    by_source: dict = {}
    for run in runs:
        info = json.loads((run / "run.json").read_text())
        dataset = args.campaign / "datasets" / info["scenario"]
        by_source.setdefault(info["source"], []).append((info["scenario"], run_errors(run, dataset)))
    figures = {}
    for source, items in by_source.items():
        figures[source] = summarise([s for _, s in items])
        f = figures[source]
        print(f"\n{source}: {f['frames']} frames above 100 ft over {len(items)} scenarios, found {f['found_pct']:.1f} %")
        print(f"  {'band':9s} {'found':>6s} {'corner med/p95/max px':>24s} {'edge med/p95 px':>16s} {'dpsi med deg':>12s}")
        for name, b in f["bands"].items():
            fmt = lambda v: "-" if v is None else f"{v:.2f}"
            print(f"  {name:9s} {b['found_pct']:5.1f}% {fmt(b['corner_median_px']):>7s} {fmt(b['corner_p95_px']):>7s} "
                  f"{fmt(b['corner_max_px']):>8s} {fmt(b['edge_median_px']):>7s} {fmt(b['edge_p95_px']):>7s} "
                  f"{fmt(b['dpsi_median_deg']):>12s}")
        print("  corner error at " + ", ".join(
            f"{k}: mean {v['mean_px']:.1f} max {v['max_px']:.1f} px ({v['lost']} lost of {v['runs']})"
            if v["mean_px"] is not None else f"{k}: -" for k, v in f["corner_error_at"].items()))
    if args.plot:
        _plot(by_source, args.plot)
    print(json.dumps(json_ready(figures)))
    return 0


def _plot(by_source: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    scenarios = sorted({name for items in by_source.values() for name, _ in items})
    fig, axes = plt.subplots(2, (len(scenarios) + 1) // 2, figsize=(16, 6.5), sharey=True, squeeze=False)
    for ax, scenario in zip(axes.ravel(), scenarios):
        for k, (source, items) in enumerate(sorted(by_source.items())):
            for name, s in items:
                if name == scenario:
                    ax.semilogy(s["t_s"], np.maximum(s["corner_px"], 1e-2), lw=0.8, color=f"C{k}", label=source)
        ax.set_title(scenario, fontsize=9)
        ax.set_xlabel("t (s)", fontsize=8)
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("threshold-corner error (px)")
    axes[1][0].set_ylabel("threshold-corner error (px)")
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=8)
    fig.suptitle("Threshold corners against the labels, 2048 px frames (campaign)", fontsize=10)
    fig.tight_layout(rect=(0, 0.05, 1, 0.96))
    fig.savefig(path, dpi=72)
    plt.close(fig)


if __name__ == "__main__":
    raise SystemExit(main())
