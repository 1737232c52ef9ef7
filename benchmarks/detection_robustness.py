"""Detection robustness over a matrix of scene conditions (issue 11 item 3).

For each condition (a runway size, scene options of :class:`visland.render.SceneParams`, a
lens), the thesis-3 approach is flown and a FEW frames are rendered in memory at the distances
``--distances`` before the threshold (default 4000, 2500, 1500, 900, 600, 300 m; one or two
per band of :data:`visland.detection.accuracy.BANDS`); the detector searches each frame from
scratch (no tracking: the frames are far apart) and is scored against the exact labels with
:func:`visland.detection.accuracy.frame_errors`. Printed: a table per condition (found rate,
gross errors, edge error, near-corner median / p95 / max, |dpsi|), the condition x band table,
and the figures as JSON (last line); ``--figure`` writes the heat map (near-corner error per
condition and band, found rate and gross errors written in the cells).

Usage::

    nice .venv/bin/python benchmarks/detection_robustness.py --size 1024 \
        --out /work/data/NAME/robustness.csv --figure docs/detection_robustness.png

Measured figures are in docs/robustness.md ("Single frames, searched from scratch").
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import sys
import time

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

#: name -> (runway (length, width) m, SceneParams overrides, lens distortion or None)
CONDITIONS = {
    "baseline 3000x45": ((3000.0, 45.0), {}, None),
    "short narrow 1200x23": ((1200.0, 23.0), {}, None),
    "long wide 4000x60": ((4000.0, 60.0), {}, None),
    "no markings": ((3000.0, 45.0), {"markings": "none"}, None),
    "4 threshold stripes": ((3000.0, 45.0), {"threshold_stripes": 4}, None),
    "16 stripes, 30 m wide": ((2400.0, 30.0), {"threshold_stripes": 16}, None),
    "FAA markings": ((3000.0, 45.0), {"markings": "faa"}, None),
    "worn, no side stripes": ((3000.0, 45.0), {"markings": "worn", "side_stripes": False}, None),
    "displaced threshold": ((3000.0, 45.0), {"markings": "displaced", "pre_threshold_m": 300.0}, None),
    "blast pad": ((3000.0, 45.0), {"markings": "blast_pad", "pre_threshold_m": 120.0}, None),
    "patched concrete": ((3000.0, 45.0), {"surface": "patched"}, None),
    "concrete, dry grass": ((3000.0, 45.0), {"surface": "concrete", "surroundings": "dry"}, None),
    "snow, monochrome": ((3000.0, 45.0), {"surroundings": "snow", "monochrome": True}, None),
    "sand, monochrome": ((3000.0, 45.0), {"surroundings": "sand", "monochrome": True}, None),
    "concrete, sand, mono": ((3000.0, 45.0), {"surface": "concrete", "surroundings": "sand", "monochrome": True},
                             None),
    "urban": ((3000.0, 45.0), {"surroundings": "urban"}, None),
    "taxiways near threshold": ((3000.0, 45.0), {"taxiways": "near_threshold", "second_runway": True}, None),
    "oblique taxiways": ((3000.0, 45.0), {"taxiways": "oblique"}, None),
    "oblique, 1200x23": ((1200.0, 23.0), {"taxiways": "oblique", "surface": "concrete"}, None),
    "visibility 2 km": ((3000.0, 45.0), {"visibility_m": 2000.0}, None),
    "overcast, 5 km": ((3000.0, 45.0), {"lighting": "overcast", "visibility_m": 5000.0}, None),
    "dusk, sun ahead 6 deg": ((3000.0, 45.0), {"lighting": "dusk", "sun_elevation_deg": 6.0,
                                               "sun_azimuth_deg": 40.0}, None),
    "sensor: noise, blur, JPEG": ((3000.0, 45.0), {"noise_std": 6.0, "blur_sigma_px": 1.0, "jpeg_quality": 50,
                                                   "vignetting": 0.4}, None),
    "barrel lens k1 -0.15": ((3000.0, 45.0), {}, (-0.15, 0.02, 0.0, 0.0, 0.0)),
    "variety 1": "variety", "variety 2": "variety", "variety 3": "variety",
}


def condition_setup(name: str):
    """``(runway, SceneParams, distortion)`` of condition ``name``."""
    from visland.render import SceneParams
    from visland.render.variety import draw_variety
    from visland.runway import Runway
    spec = CONDITIONS[name]
    if spec == "variety":
        drawn = draw_variety(int(name.split()[-1]))
        return Runway(length_m=drawn.runway_length_m, width_m=drawn.runway_width_m), drawn.scene, None
    (length, width), overrides, distortion = spec
    return Runway(length_m=length, width_m=width), SceneParams(**overrides), distortion


def heat_map(summaries: dict, path: str, title: str) -> None:
    """Condition x band heat map of the near-corner p95 (px), found rate and gross errors in the cells."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm
    from visland.detection.accuracy import BANDS
    bands = [b[2] for b in BANDS]
    names = list(summaries)
    values = np.full((len(names), len(bands)), np.nan)
    text = [["" for _ in bands] for _ in names]
    for i, name in enumerate(names):
        for j, band in enumerate(bands):
            s = summaries[name].get(band)
            if not s:
                continue
            c = s["near_corner_px"]
            # colour: the worst near corner or edge of a frame reported found (a gross edge
            # error with the corners withheld counts); nothing found: top of the scale
            worst = max([v for v in (c["max"], s["edge_px"]["max"]) if v is not None], default=np.nan)
            if c["max"] is None and not s["gross"]:
                worst = np.nan                   # grey: nothing found, or found with the corners withheld
            values[i, j] = max(worst, 0.05) if np.isfinite(worst) else np.nan
            found = f"{100 * s['found_rate']:.0f}% found"
            text[i][j] = (f"{c['median']:.2f} / {c['max']:.2f}" if c["max"] is not None
                          else ("corners withheld" if s["found_rate"] > 0 else "")) + \
                f"\n{found}" + (f"  {s['gross']} gross" if s["gross"] else "")
    fig, ax = plt.subplots(figsize=(9.5, 0.48 * len(names) + 1.6))
    cmap = matplotlib.colormaps["RdYlGn_r"].copy()
    cmap.set_bad("#d0d0d0")
    image = ax.imshow(np.ma.masked_invalid(values), cmap=cmap, norm=LogNorm(vmin=0.1, vmax=50.0), aspect="auto")
    for i in range(len(names)):
        for j in range(len(bands)):
            ax.text(j, i, text[i][j], ha="center", va="center", fontsize=6.5)
    ax.set_xticks(range(len(bands)), bands)
    ax.set_yticks(range(len(names)), names, fontsize=8)
    ax.set_xlabel("distance to the threshold")
    ax.set_title(title, fontsize=9)
    fig.colorbar(image, ax=ax, label="worst near-corner or edge error of a found frame (px); grey: no corner reported")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _report(all_rows, summaries, args) -> None:
    from visland.detection.accuracy import format_table, summarise
    print()
    for line in format_table(summarise(all_rows, key="condition"), title="condition (all bands)"):
        print(line)
    print()
    for line in format_table(summarise(all_rows), title="band (all conditions)"):
        print(line)
    if args.figure:
        heat_map(summaries, args.figure, f"visland detection, {args.scenario} approach, {args.size} px, "
                                         f"{len(args.distances)} frames per condition (acquisition, no tracking):\n"
                                         "near-corner median / max px, found rate, gross errors")
    print(json.dumps({"size": args.size, "distances_m": args.distances, "conditions": summaries}))


def summarise_csv(args) -> int:
    """Tables and heat map from the per-frame CSV of an earlier run."""
    from visland.detection.accuracy import summarise
    rows = []
    with open(args.from_csv, newline="") as handle:
        for raw in csv.DictReader(handle):
            row = dict(raw)
            for key in ("found", "gross", "corners_withheld"):
                row[key] = int(row[key])
            for key in ("distance_m", "confidence", "edge_px", "near_px", "near_along_px", "dpsi_err_deg"):
                row[key] = float(row[key]) if row[key] not in ("", "nan") else math.nan
            rows.append(row)
    order = list(dict.fromkeys(r["condition"] for r in rows))
    summaries = {name: summarise([r for r in rows if r["condition"] == name]) for name in order}
    _report(rows, summaries, args)
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", type=int, default=1024)
    parser.add_argument("--distances", type=float, nargs="+", default=[4000.0, 2500.0, 1500.0, 900.0, 600.0, 300.0])
    parser.add_argument("--conditions", nargs="+", default=list(CONDITIONS), help="names from CONDITIONS")
    parser.add_argument("--scenario", default="thesis-3")
    parser.add_argument("--out", default="/tmp/detection_robustness.csv", help="per-frame CSV")
    parser.add_argument("--figure", help="heat map PNG")
    parser.add_argument("--save-frames", metavar="DIR", help="also write each rendered frame there (PNG)")
    parser.add_argument("--from-csv", metavar="CSV", help="summarise a per-frame CSV of an earlier run (no rendering)")
    args = parser.parse_args(argv)
    if args.from_csv:
        return summarise_csv(args)
    unknown = [c for c in args.conditions if c not in CONDITIONS]
    if unknown:
        parser.error(f"unknown conditions {unknown}; known: {', '.join(CONDITIONS)}")

    from visland.camera import CameraModel
    from visland.detection import DetectorParams, detect_runway
    from visland.detection.accuracy import band_of, frame_errors, summarise
    from visland.features import batch_R_camera_from_runway, ideal_features
    from visland.flight import simulate_flight
    from visland.render import FrameRenderer
    from visland.scenarios import resolve_scenario, with_runway
    from visland.simulate import frame_times

    base_scenario = resolve_scenario(args.scenario)
    params = DetectorParams()
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    fields = ["condition", "distance_m", "band", "found", "confidence", "edge_px", "near_px", "near_along_px",
              "dpsi_err_deg", "gross", "corners_withheld", "reason"]
    all_rows, summaries = [], {}
    t0 = time.perf_counter()
    with open(args.out, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=fields, extrasaction="ignore")
        writer.writeheader()
        for name in args.conditions:
            runway, scene, distortion = condition_setup(name)
            camera = CameraModel.default(args.size)
            if distortion is not None:
                camera = CameraModel.from_json_dict({**camera.to_json_dict(), "distortion": list(distortion)})
            scenario = with_runway(base_scenario, runway)
            trajectory = simulate_flight(scenario)
            times = frame_times(trajectory.duration_s, 25.0)
            states_all = trajectory.at(times)
            distance_all = -states_all.p_runway_m[:, 0]
            chosen = [int(np.argmin(np.abs(distance_all - d))) for d in args.distances]
            states = trajectory.at(times[chosen])
            labels = ideal_features(states, runway, camera)
            R = batch_R_camera_from_runway(states.roll_rad, states.pitch_rad, states.dpsi_rad, camera.mount_rpy_rad)
            rows = []
            with FrameRenderer(scene, camera, runway) as renderer:
                for j, index in enumerate(chosen):
                    rgb = renderer.render(states.p_runway_m[j], R[j], frame_seed=index)
                    if args.save_frames:
                        import cv2
                        os.makedirs(args.save_frames, exist_ok=True)
                        stem = "".join(ch if ch.isalnum() else "_" for ch in name)
                        cv2.imwrite(os.path.join(args.save_frames, f"{stem}_{int(args.distances[j])}.png"),
                                    cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR) if rgb.ndim == 3 else rgb)
                    result = detect_runway(rgb, camera, float(states.roll_rad[j]), float(states.pitch_rad[j]),
                                           params=params, previous=None)
                    errors = frame_errors(result, camera, labels.corners_uv[j], labels.corners_visible[j],
                                          float(states.dpsi_rad[j]))
                    row = {"condition": name, "distance_m": round(float(distance_all[index]), 1),
                           "band": band_of(float(distance_all[index])), **errors}
                    rows.append(row)
                    writer.writerow({k: (round(v, 4) if isinstance(v, float) else v) for k, v in row.items()})
                    handle.flush()
            summaries[name] = summarise(rows)
            all_rows += rows
            s = summaries[name]["all"]
            print(f"{name:28s} found {100 * s['found_rate']:5.1f}%  gross {s['gross']}  near corner med/p95/max "
                  f"{s['near_corner_px']['median']}/{s['near_corner_px']['p95']}/{s['near_corner_px']['max']} px  "
                  f"edge p95 {s['edge_px']['p95']} px  |dpsi| med {s['dpsi_abs_err_deg']['median']} deg  "
                  f"({time.perf_counter() - t0:.0f} s)", flush=True)
    _report(all_rows, summaries, args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
