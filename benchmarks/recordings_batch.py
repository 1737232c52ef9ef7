"""A batch of recorded approaches with an unknown clock offset, processed in one command.

For each scenario: ``visland generate`` renders the approach (small frames, low rate), the frames
are encoded as one MPEG-4 video, and the video is put in a folder of its own with camera.json,
truth.csv and a telemetry.csv whose times run ``--offset`` seconds behind the frames' (as a
recorder with its own clock would write them). Then ``visland process`` runs on all the videos
in one call, once with ``--estimate-offset`` and once with the exact ``--time-offset``, and the
estimated offsets and the dH errors at 100 ft of the two batches are compared.

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
        if not video.exists():
            first = cv2.imread(str(frames[0]))
            writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"mp4v"), args.fps,
                                     (first.shape[1], first.shape[0]))
            for path in frames:
                writer.write(cv2.imread(str(path)))
            writer.release()
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
    prepared_s = time.perf_counter() - started
    figures = {"scenarios": args.scenarios, "size": args.size, "fps": args.fps, "offset_s": args.offset,
               "prepare_s": round(prepared_s, 1)}
    for label, extra in (("estimated", ["--estimate-offset"]), ("exact", ["--time-offset", args.offset])):
        out = work / f"batch-{label}"
        tic = time.perf_counter()
        log = work / f"batch-{label}.log"
        run(["process", *videos, "--out", out, "--observer", *args.observers, "--no-report", "--quiet", "--force",
             *extra], log=log)
        index = json.loads((out / "index.json").read_text())
        figures[label] = {"wall_s": round(time.perf_counter() - tic, 1), "done": index["done"],
                          "failed": index["failed"]}
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
    print(json.dumps(figures))
    return 0


if __name__ == "__main__":
    sys.exit(main())
