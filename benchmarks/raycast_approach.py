"""Detection (and the estimates it feeds) on an approach drawn by the independent ray caster.

The frames come from ``tests/helpers/raycast_airport.py``: no meshes, no OpenGL, no texture
maps, a painted plan ray-cast pixel by pixel, so nothing of visland's renderer (and nothing
the detector was tuned on) is in them. The approach is flown by visland's flight model
(``visland.simulate``); labels are exact (:func:`visland.features.ideal_features`).

Default case (the situation reported in issue 11): grey-level camera, haze, a 2600 x 40 m
runway, a parallel taxiway, a taxiway joining the runway's right side 300 m past the threshold
and an oblique one on the left at 450 m; 5 frames per second.

Per frame the detector runs as ``visland detect`` does (:class:`DetectionSequence`); the
figures per distance band are those of :mod:`visland.detection.accuracy` (gross error: found
with a corner or edge more than 5 px off). With ``--estimate`` the measurements are written
with the simulation's telemetry and truth into ``--work`` and ``visland estimate`` runs
ccpi-hg-2p and ekf-2l (dH at 100 ft).

Usage::

    .venv/bin/python benchmarks/raycast_approach.py --size 1024 --workers 2
    .venv/bin/python benchmarks/raycast_approach.py --size 1920x1080 --hfov 62 --distortion -0.2,0.05,0,0,0
    .venv/bin/python benchmarks/raycast_approach.py --colour --estimate --work /work/data/raycast

The last line printed is one JSON object with the figures.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import multiprocessing as mp
import os
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the repository root, for tests.helpers.raycast_airport

FT = 0.3048


def parse_size(text: str) -> tuple[int, int]:
    if "x" in text:
        w, h = text.lower().split("x")
        return int(w), int(h)
    return int(text), int(text)


def scene_of(args):
    from tests.helpers.raycast_airport import PaintedAirport
    joining = []
    for spec in args.joining:
        x, side, angle = (float(a) for a in spec.split(","))
        joining.append((x, int(side), angle, 260.0))
    return PaintedAirport(runway_length_m=args.runway[0], runway_width_m=args.runway[1], seed=args.seed,
                          joining_taxiways=tuple(joining), haze_range_m=args.haze_m, taxiway_grey=args.taxiway_grey,
                          taxiway_offset_m=(-(4 * args.runway[1] + 2.5) if args.taxiway_offset is None
                                            else args.taxiway_offset), grass_grey=args.ground_grey,
                          runway_grey=args.runway_grey, marking_grey=args.marking_grey,
                          rubber=args.rubber)


def _draw(job):
    """One frame (worker process): grey (H, W) or RGB (H, W, 3) uint8, from the cache if there."""
    cached = job[-1]
    if cached is not None and os.path.exists(cached):
        import cv2
        image = cv2.imread(cached, cv2.IMREAD_UNCHANGED)
        return image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
    image = _draw_new(job[:-1])
    if cached is not None:
        import cv2
        cv2.imwrite(cached + ".tmp.png", image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
        os.replace(cached + ".tmp.png", cached)
    return image


def _draw_new(job):
    scene, camera, p, R, colour, seed, supersample = job
    from tests.helpers.raycast_airport import draw_frame, PaintedAirport
    grey = draw_frame(scene, camera, p, R, supersample=supersample, blur_sigma_px=0.5,
                      rng=np.random.default_rng(seed))
    if not colour:
        return grey
    # grass tinted green, paved areas left grey: the mask of paved ground ray-cast the same way
    paved = PaintedAirport(**{**scene.__dict__, "grass_grey": 0.0, "runway_grey": 255.0, "marking_grey": 255.0,
                              "taxiway_grey": 255.0, "fields": False, "haze_range_m": 1e12,
                              "rubber": tuple((*zone[:3], 255.0) for zone in scene.rubber)})
    mask = draw_frame(paved, camera, p, R, supersample=supersample, blur_sigma_px=0.5, noise_grey=0.0) / 255.0
    tint = np.array([-14.0, 12.0, (14.0 * 0.299 - 12.0 * 0.587) / 0.114])
    return np.clip(grey[..., None] + (1.0 - mask[..., None]) * tint, 0, 255).round().astype(np.uint8)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", default="thesis-1")
    parser.add_argument("--runway", default="2600,40", help="runway length,width in metres (default 2600,40)")
    parser.add_argument("--joining", nargs="*", default=["300,1,90", "450,-1,35"],
                        help="taxiways joining the runway: x_m,side(-1 left/+1 right),angle_deg (default: "
                             "300 m right at 90 deg and 450 m left at 35 deg)")
    parser.add_argument("--taxiway-grey", type=float, default=84.0,
                        help="grey level of the joining taxiways (default 84: asphalt like the runway's 78)")
    parser.add_argument("--taxiway-offset", type=float, default=None, metavar="Y_M",
                        help="centre of the parallel taxiway, metres right of the runway's centre line (default: "
                             "4 runway widths + 2.5 m to the left; thesis-3 starts 205 m right)")
    parser.add_argument("--haze-m", type=float, default=6000.0, help="haze range of the ray caster (m)")
    parser.add_argument("--ground-grey", type=float, default=105.0,
                        help="grey level of the ground around the runway (default 105, grass; 232: snow)")
    parser.add_argument("--runway-grey", type=float, default=78.0, help="grey level of the runway (default 78)")
    parser.add_argument("--marking-grey", type=float, default=225.0,
                        help="grey level of the markings (default 225; 196: worn paint, darker than snow)")
    parser.add_argument("--rubber", nargs="*", default=[],
                        help="rubber deposits on the runway: x_start_m,x_end_m,width_fraction,grey (e.g. "
                             "150,700,0.8,70: a touchdown zone darker than the runway)")
    parser.add_argument("--size", default="2048", help="N or WxH (default 2048)")
    parser.add_argument("--hfov", type=float, default=None, help="horizontal field of view, deg (default: SPEC 45 deg)")
    parser.add_argument("--distortion", default=None, help="k1,k2,p1,p2,k3 (OpenCV)")
    parser.add_argument("--mount-pitch", type=float, default=-3.0, help="camera mount pitch, deg (default -3)")
    parser.add_argument("--fps", type=float, default=5.0)
    parser.add_argument("--start-m", type=float, default=math.inf, help="first frame this far before the threshold")
    parser.add_argument("--colour", action="store_true", help="colour frames (green grass) instead of grey levels")
    parser.add_argument("--supersample", type=int, default=2)
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--workers", type=int, default=2, help="processes drawing frames")
    parser.add_argument("--estimate", action="store_true", help="run ccpi-hg-2p and ekf-2l on the measurements")
    parser.add_argument("--work", default="/tmp/raycast_approach", help="folder for the per-frame CSV and estimates")
    parser.add_argument("--cache", metavar="DIR", help="keep the drawn frames as PNG in DIR and reuse them (a "
                                                        "folder per case: re-running the detector only)")
    parser.add_argument("--quiet", action="store_true", help="no per-frame lines")
    args = parser.parse_args(argv)
    args.runway = tuple(float(a) for a in args.runway.split(","))
    for name in ("ground_grey", "runway_grey", "marking_grey", "taxiway_grey"):
        value = getattr(args, name)
        if not 0.0 <= value <= 255.0:
            parser.error(f"--{name.replace('_', '-')} must be a grey level from 0 to 255, got {value:g}")
    zones = []
    for spec in args.rubber:
        try:
            x_start, x_end, fraction, grey = (float(a) for a in spec.split(","))
        except ValueError:
            parser.error(f"--rubber {spec!r}: expected x_start_m,x_end_m,width_fraction,grey (four numbers)")
        if not (x_start < x_end and 0.0 < fraction <= 1.0 and 0.0 <= grey <= 255.0):
            parser.error(f"--rubber {spec!r}: needs x_start_m < x_end_m, a width fraction in (0, 1] and a grey "
                         "level from 0 to 255")
        zones.append((x_start, x_end, fraction, grey))
    args.rubber = tuple(zones)

    from visland.camera import CameraModel
    from visland.contracts import MEASUREMENT_COLUMNS, write_csv
    from visland.detection import DetectionSequence, DetectorParams
    from visland.detection.accuracy import band_of, format_table, frame_errors, summarise
    from visland.features import batch_R_camera_from_runway
    from visland.runway import Runway
    from visland.scenarios import resolve_scenario
    from visland.simulate import SimulationOptions, run_simulation, write_simulation_files
    from dataclasses import replace

    width, height = parse_size(args.size)
    distortion = tuple(float(a) for a in args.distortion.split(",")) if args.distortion else None
    mount = (0.0, args.mount_pitch, 0.0)
    if args.hfov is None and width == height:
        camera = replace(CameraModel.default(width, mount), distortion=distortion)
    else:
        camera = CameraModel.from_fov(width, height, args.hfov or 45.0, mount, distortion)
    scenario = resolve_scenario(args.scenario)
    scenario = replace(scenario, runway=Runway(length_m=args.runway[0], width_m=args.runway[1],
                                               aim_distance_m=scenario.runway.aim_distance_m,
                                               heading_deg=scenario.runway.heading_deg))
    sim = run_simulation(scenario, SimulationOptions(fps=args.fps, camera=camera))
    states, labels = sim.frames, sim.features
    # the detector gets the inertial attitude, as `visland detect` does from telemetry.csv
    roll_imu = np.interp(states.t_s, sim.imu.t_s, np.unwrap(sim.imu.roll_rad))
    pitch_imu = np.interp(states.t_s, sim.imu.t_s, sim.imu.pitch_rad)
    distance = -states.p_runway_m[:, 0]
    chosen = np.nonzero(distance <= args.start_m)[0]
    R = batch_R_camera_from_runway(states.roll_rad, states.pitch_rad, states.dpsi_rad, camera.mount_rpy_rad)
    scene = scene_of(args)
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    cache = None
    if args.cache:
        import hashlib
        key = hashlib.sha1(repr((scene, camera, args.scenario, args.fps, args.colour, args.seed,
                                 args.supersample) + ((scene.rubber,) if scene.rubber else ())).encode()).hexdigest()[:12]
        cache = Path(args.cache) / key
        cache.mkdir(parents=True, exist_ok=True)
    jobs = [(scene, camera, states.p_runway_m[i], R[i], args.colour, args.seed * 100003 + int(i), args.supersample,
             str(cache / f"{int(i):05d}.png") if cache else None)
            for i in chosen]
    sequence = DetectionSequence(camera, DetectorParams())
    rows, measurement_rows = [], {c: [] for c in MEASUREMENT_COLUMNS}
    start = time.perf_counter()
    detect_s = []
    context = mp.get_context("spawn")
    with context.Pool(max(1, args.workers)) as pool:
        for j, image in enumerate(pool.imap(_draw, jobs, chunksize=1)):
            i = int(chosen[j])
            tic = time.perf_counter()
            result = sequence(image, float(roll_imu[i]), float(pitch_imu[i]), float(states.t_s[i]))
            detect_s.append(time.perf_counter() - tic)
            errors = frame_errors(result, camera, labels.corners_uv[i], labels.corners_visible[i],
                                  float(states.dpsi_rad[i]), float(labels.dF_px[i]))
            height_m = float(-states.p_runway_m[i, 2])
            row = {"frame": i, "t_s": round(float(states.t_s[i]), 3), "distance_m": round(float(distance[i]), 1),
                   "height_m": round(height_m, 1), "band": band_of(float(distance[i])), **errors}
            if height_m >= 100 * FT:
                rows.append(row)
            for key, value in result.to_measurement_row(i, float(states.t_s[i])).items():
                measurement_rows[key].append(value)
            if not args.quiet:
                print(f"frame {i:4d} {row['distance_m']:7.0f} m found={row['found']} near={row['near_px']:7.2f} px "
                      f"edge={row['edge_px']:6.2f} px gross={row['gross']} conf={row['confidence']:.2f} "
                      f"{result.mode[:5]} {result.reason[:70]}", file=sys.stderr, flush=True)
    elapsed = time.perf_counter() - start
    with open(work / "frames.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    summary = summarise(rows)
    figures = {"benchmark": "raycast_approach", "camera": camera.to_json_dict(), "colour": args.colour,
               "runway": list(args.runway), "joining": args.joining, "rubber": [list(zone) for zone in args.rubber], "fps": args.fps, "frames": len(rows),
               "detect_ms_median": round(1e3 * float(np.median(detect_s)), 1), "minutes": round(elapsed / 60, 2),
               "bands": summary}
    print(f"{len(rows)} frames above 100 ft ({width}x{height}, {'colour' if args.colour else 'grey'}) in "
          f"{elapsed / 60:.1f} min; detection {figures['detect_ms_median']} ms/frame median; rows in {work}/frames.csv")
    for line in format_table(summary):
        print(line)
    if args.estimate:
        from visland.estimation.command import EstimateOptions, estimate_folder
        folder = work / "run"
        folder.mkdir(exist_ok=True)
        write_simulation_files(sim, folder)
        # frames not drawn (before --start-m) carry no measurement
        n = len(states.t_s)
        full = {c: [] for c in MEASUREMENT_COLUMNS}
        drawn = {int(f): k for k, f in enumerate(measurement_rows["frame"])}
        for i in range(n):
            for c in MEASUREMENT_COLUMNS:
                if i in drawn:
                    full[c].append(measurement_rows[c][drawn[i]])
                else:
                    full[c].append({"frame": i, "t_s": float(states.t_s[i]), "source": "detection", "found": 0,
                                    "reason": "not drawn", "confidence": 0.0}.get(c, math.nan))
        write_csv(folder / "measurements.csv", full, MEASUREMENT_COLUMNS)
        metrics = estimate_folder(folder, EstimateOptions(observers=("ccpi-hg-2p", "ekf-2l", "oj-2p", "kf-2p"),
                                                          measurements=str(folder / "measurements.csv")),
                                  folder / "estimates.csv", echo=lambda *a: None)
        figures["dh_err_100ft_m"] = {name: m.get("err_100ft_m") for name, m in metrics.items()}
        print("dH error at 100 ft (truth - estimate): " + ", ".join(
            f"{name} {value:+.3f} m" for name, value in figures["dh_err_100ft_m"].items() if value is not None))
    print(json.dumps(figures, default=lambda o: None))
    return 0


if __name__ == "__main__":
    sys.exit(main())
