"""A batch of recorded approaches with an unknown clock offset, processed in one command.

For each scenario: ``visland generate`` renders the approach (small frames, low rate), the frames
are encoded as one H.264 video (ffmpeg's libx264 from imageio-ffmpeg; ``--codec mp4v`` uses
OpenCV's MPEG-4 instead), and the video is put in a folder of its own with camera.json,
truth.csv and a telemetry.csv whose times run ``--offset`` seconds behind the frames' (as a
recorder with its own clock would write them). A ninth input is the first video cut in the
middle of its file (a recording that was not closed). Then ``visland process`` runs on all the
videos in one call: with ``--estimate-offset`` (on ``--workers 2`` and on a local Dask cluster
of two single-threaded workers), with the exact ``--time-offset`` (one after the other, on
``--workers 2`` and on the Dask cluster), and the estimated offsets, the dH errors at 100 ft and
the wall times are compared.

Usage::

    .venv/bin/python benchmarks/recordings_batch.py --work /work/data/recordings --size 512 --fps 5

The last line printed is one JSON object with the figures.
"""
from __future__ import annotations

import argparse
import json
import math
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import cv2

HERE = Path(__file__).resolve().parent
VISLAND = [sys.executable, "-m", "visland.cli"]


def run(args, log=None) -> str:
    result = subprocess.run(VISLAND + [str(a) for a in args], capture_output=True, text=True)
    if log is not None:
        log.write_text(result.stdout + result.stderr)
    if result.returncode not in (0,):
        raise SystemExit(f"visland {' '.join(map(str, args))} failed:\n{result.stderr}")
    return result.stdout


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenarios", nargs="+", default=[f"thesis-{i}" for i in range(1, 9)])
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--fps", type=float, default=5.0)
    parser.add_argument("--offset", type=float, default=0.3, help="telemetry clock behind the frames' (s)")
    parser.add_argument("--observers", nargs="+", default=["ccpi-hg-2p", "ekf-2l"])
    parser.add_argument("--work", default="/tmp/recordings_batch")
    parser.add_argument("--codec", choices=("h264", "mp4v"), default="h264")
    parser.add_argument("--force-encode", action="store_true", help="encode the videos again even if present")
    parser.add_argument("--no-dask", action="store_true", help="skip the batch on a local Dask cluster")
    args = parser.parse_args(argv)
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    videos = []
    started = time.perf_counter()
    for name in args.scenarios:
        dataset = work / "datasets" / name
        if not (dataset / "manifest.json").exists():
            run(["generate", "--scenario", name, "--out", dataset, "--size", args.size, "--fps", args.fps,
                 "--workers", "1", "--no-progress", "--force"])
        folder = work / "videos" / name
        folder.mkdir(parents=True, exist_ok=True)
        video = folder / f"{name}.mp4"
        # the recorder's telemetry runs longer than the video: the video starts and stops a few
        # frames inside it, so the telemetry covers every frame whatever the offset
        trim = int(math.ceil(abs(args.offset) * args.fps)) + 1
        frames = sorted((dataset / "frames").glob("*.png"))[trim:-trim]
        if not video.exists() or args.force_encode:
            encode(frames, video, args.fps, args.codec)
        shutil.copy(dataset / "camera.json", folder / "camera.json")
        for file in ("truth.csv", "frames.csv"):
            lines = (dataset / file).read_text().splitlines()
            kept = lines[1 + trim:len(lines) - trim]
            column = lines[0].split(",").index("frame")        # frame indices of the video, from 0
            kept = [",".join(str(k) if c == column else cell for c, cell in enumerate(line.split(",")))
                    for k, line in enumerate(kept)]
            (folder / file).write_text("\n".join([lines[0]] + kept) + "\n")
        lines = (dataset / "telemetry.csv").read_text().splitlines()
        shifted = [lines[0]] + [re.sub(r"^[^,]+", lambda m: f"{float(m.group(0)) - args.offset:.6f}", line)
                                for line in lines[1:]]
        (folder / "telemetry.csv").write_text("\n".join(shifted) + "\n")
        videos.append(video)
    # a recording that was not closed: the first video cut in the middle of its file
    broken = work / "videos" / "truncated"
    broken.mkdir(parents=True, exist_ok=True)
    data = videos[0].read_bytes()
    (broken / "truncated.mp4").write_bytes(data[:len(data) // 2])
    for file in ("camera.json", "truth.csv", "telemetry.csv"):
        shutil.copy(videos[0].parent / file, broken / file)
    videos.append(broken / "truncated.mp4")
    prepared_s = time.perf_counter() - started
    figures = {"scenarios": args.scenarios, "size": args.size, "fps": args.fps, "offset_s": args.offset,
               "prepare_s": round(prepared_s, 1)}
    batches = [("estimated", ["--estimate-offset", "--workers", "2"]),
               ("exact", ["--time-offset", args.offset]),
               ("exact-2-workers", ["--time-offset", args.offset, "--workers", "2"])]
    cluster = None
    if not args.no_dask:
        from distributed import LocalCluster
        cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                               dashboard_address=None)
        batches.append(("exact-dask", ["--time-offset", args.offset, "--scheduler", cluster.scheduler_address]))
        batches.append(("estimated-dask", ["--estimate-offset", "--scheduler", cluster.scheduler_address]))
    for label, extra in batches:
        out = work / f"batch-{label}"
        tic = time.perf_counter()
        log = work / f"batch-{label}.log"
        run(["process", *videos, "--out", out, "--observer", *args.observers, "--no-report", "--quiet", "--force",
             *extra], log=log)
        index = json.loads((out / "index.json").read_text())
        figures[label] = {"wall_s": round(time.perf_counter() - tic, 1), "done": index["done"],
                          "failed": index["failed"],
                          "failures": {r["name"]: r["reason"] for r in index["runs"] if r["status"] != "done"}}
        offsets = [float(m.group(1)) for m in re.finditer(r"clock offset estimated .*?: ([+-][0-9.]+) s",
                                                           log.read_text())]
        if offsets:
            figures[label]["offsets_s"] = offsets
        errors = {}
        for row in index["runs"]:
            if row["status"] != "done":
                continue
            metrics = json.loads((out / row["name"] / "metrics.json").read_text())["observers"]
            errors[row["name"]] = {o: metrics[o].get("err_100ft_m") for o in args.observers if o in metrics}
        figures[label]["dh_err_100ft_m"] = errors
        print(label, json.dumps(figures[label]), flush=True)
    if cluster is not None:
        cluster.close()
    if "estimated" in figures and "exact" in figures:
        gaps = {}
        for name, errors in figures["estimated"]["dh_err_100ft_m"].items():
            exact = figures["exact"]["dh_err_100ft_m"].get(name, {})
            gaps[name] = {o: (None if e is None or exact.get(o) is None else round(e - exact[o], 4))
                          for o, e in errors.items()}
        figures["estimated_minus_exact_100ft_m"] = gaps
    print(json.dumps(figures))
    return 0


def encode(frames, video: Path, fps: float, codec: str) -> None:
    """The PNG ``frames`` as one video at ``fps``: H.264 through ffmpeg, or OpenCV's MPEG-4."""
    if codec == "h264":
        import imageio_ffmpeg
        listing = video.with_suffix(".txt")
        listing.write_text("".join(f"file '{path}'\nduration {1.0 / fps:.6f}\n" for path in frames))
        subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-y", "-loglevel", "error", "-f", "concat", "-safe", "0",
                        "-i", str(listing), "-fps_mode", "cfr", "-r", f"{fps:g}", "-c:v", "libx264", "-crf", "20",
                        "-pix_fmt", "yuv420p", str(video)], check=True)
        listing.unlink()
        return
    first = cv2.imread(str(frames[0]))
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"mp4v"), fps, (first.shape[1], first.shape[0]))
    for path in frames:
        writer.write(cv2.imread(str(path)))
    writer.release()


if __name__ == "__main__":
    sys.exit(main())
