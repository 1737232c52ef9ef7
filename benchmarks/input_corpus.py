"""Mutation corpus of hostile and absurd inputs (issues 19 and 20): count tracebacks, hangs,
silent acceptances and wrong-named errors of every reader and command.

Usage::

    .venv/bin/python benchmarks/input_corpus.py --work /work/data/NAME/corpus [--base DIR] [--only TEXT]
        [--timeout S] [--list]

``--base`` is an 8-frame SPEC folder (frames/, frames.csv, telemetry.csv, camera.json,
truth.csv, labels.csv); without it one is rendered (384 px, 2 Hz, 1.5 km approach, frames 8-15)
into ``--work``. Each case copies the base, damages one thing, and runs one command in this
process (``visland.cli.main``) under a time limit. Outcomes:

- ``traceback``: an exception other than the one-sentence ``ValueError`` escaped;
- ``hang``: the command ran over ``--timeout`` seconds (default 10);
- ``silent``: nonsense accepted without a word (exit 0 where an error or a flagged frame was due);
- ``wrong-name``: an error that does not name the culprit (file, option), or names a staging
  folder (``.partial-``), or leaks a Python internal;
- ``ok``: the expected one-sentence error, flagged frame or acceptance.

Ends with one JSON line of the counts (and the cases of each bad outcome).
"""
from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import os
import re
import shutil
import signal
import sys
import time
from pathlib import Path

INTERNALS = ("math domain error", "must not contain infs or NaNs", "unhashable type", "object has no attribute",
             "codec can't decode", "index out of", "list index", "NoneType", "Errno", "is not subscriptable",
             "could not convert", "invalid literal", "Traceback", "OpenCV(")


class Hang(Exception):
    pass


def _alarm(signum, frame):
    raise Hang()


# --------------------------------------------------------------------------- base folder
def make_base(work: Path) -> Path:
    from visland.camera import CameraModel
    from visland.datasets import generate as gen
    from visland.render.params import SceneParams
    from visland.scenarios import Scenario
    from visland.simulate import SimulationOptions
    full = work / "rendered"
    if not (full / "manifest.json").exists():
        scenario = Scenario("short", dx_m=-1500.0, dy_m=25.0, dgs_m=-5.0, dpsi_deg=2.0, gamma_deg=-3.0)
        options = SimulationOptions(fps=2.0, camera=CameraModel.default(384), seed=1)
        gen.generate_dataset(gen.GenerateJob(scenario, options, SceneParams(seed=1)), full, progress=False)
    base = work / "base"
    shutil.rmtree(base, ignore_errors=True)
    (base / "frames").mkdir(parents=True)
    start, n = 8, 8
    for k, f in enumerate(sorted((full / "frames").iterdir())[start:start + n]):
        shutil.copy(f, base / "frames" / f"{k:06d}.png")
    for name in ("frames.csv", "truth.csv", "labels.csv"):
        lines = (full / name).read_text().splitlines()
        body = lines[1 + start:1 + start + n]
        if lines[0].split(",")[0] == "frame":
            body = [",".join([str(k)] + line.split(",")[1:]) for k, line in enumerate(body)]
        (base / name).write_text("\n".join([lines[0]] + body) + "\n")
    for name in ("telemetry.csv", "camera.json", "runway.json"):
        shutil.copy(full / name, base / name)
    return base


# --------------------------------------------------------------------------- damage helpers
def _rows(path: Path):
    lines = path.read_text().splitlines()
    return lines[0].split(","), [line.split(",") for line in lines[1:]]


def _write_rows(path: Path, header, rows) -> None:
    path.write_text("\n".join([",".join(header)] + [",".join(r) for r in rows]) + "\n")


def set_cell(name, column, value, row=2):
    def damage(d: Path):
        header, rows = _rows(d / name)
        rows[row][header.index(column)] = value
        _write_rows(d / name, header, rows)
    return damage


def map_column(name, column, fn):
    def damage(d: Path):
        header, rows = _rows(d / name)
        k = header.index(column)
        for r in rows:
            r[k] = repr(fn(float(r[k])))
        _write_rows(d / name, header, rows)
    return damage


def drop_column(name, column):
    def damage(d: Path):
        header, rows = _rows(d / name)
        k = header.index(column)
        _write_rows(d / name, header[:k] + header[k + 1:], [r[:k] + r[k + 1:] for r in rows])
    return damage


def keep_rows(name, fn):
    def damage(d: Path):
        header, rows = _rows(d / name)
        _write_rows(d / name, header, [r for i, r in enumerate(rows) if fn(i)])
    return damage


def write_text(name, text, encoding="utf-8"):
    def damage(d: Path):
        (d / name).write_bytes(text.encode(encoding) if isinstance(text, str) else text)
    return damage


def transform_text(name, fn):
    def damage(d: Path):
        (d / name).write_text(fn((d / name).read_text()))
    return damage


def as_directory(name):
    def damage(d: Path):
        (d / name).unlink()
        (d / name).mkdir()
    return damage


def remove(name):
    def damage(d: Path):
        (d / name).unlink()
    return damage


def camera_field(field, value):
    def damage(d: Path):
        data = json.loads((d / "camera.json").read_text())
        if value is KeyError:
            data.pop(field)
        else:
            data[field] = value
        (d / "camera.json").write_text(json.dumps(data))
    return damage


def frame(k, fn):
    def damage(d: Path):
        fn(sorted((d / "frames").iterdir())[k])
    return damage


def _huge_png(path: Path):
    import struct
    import zlib
    ihdr = struct.pack(">IIBBBBB", 100000, 100000, 8, 0, 0, 0, 0)
    chunk = b"IHDR" + ihdr
    data = b"\x89PNG\r\n\x1a\n" + struct.pack(">I", len(ihdr)) + chunk + struct.pack(">I", zlib.crc32(chunk))
    path.write_bytes(data + b"\x00" * 64)


def _frame_dir(path: Path):
    path.unlink()
    path.mkdir()


def _dangling(path: Path):
    path.unlink()
    path.symlink_to(path.parent / "does-not-exist.png")


def _loop(path: Path):
    path.unlink()
    path.symlink_to(path)


def _black(path: Path):
    import cv2
    import numpy as np
    cv2.imwrite(str(path), np.zeros((384, 384, 3), np.uint8))


def _small(path: Path):
    import cv2
    import numpy as np
    cv2.imwrite(str(path), np.zeros((100, 384, 3), np.uint8))


# --------------------------------------------------------------------------- the cases
def cases():
    """(name, damage(folder), command(folder, out) -> argv, expect, token).

    ``expect``: "error" (a one-sentence error naming ``token``), "flag" (the run completes with a
    flagged frame or a reason) or "accept"."""
    out = []
    P = ["--observer", "ccpi-hg-2p", "ekf-2l", "--quiet", "--no-report"]

    def process(source="ideal", extra=()):
        return lambda d, o: ["process", str(d), "--out", str(o / "run"), "--source", source, *P, *extra]

    def detect(extra=()):
        return lambda d, o: ["detect", str(d), "--out", str(o / "m.csv"), "--quiet", *extra]

    def track(extra=()):
        return lambda d, o: ["track", str(d), "--out", str(o / "m.csv"), *extra]

    def estimate(extra=()):
        return lambda d, o: ["estimate", str(d), "--measurements", "ideal", "--observer", "ccpi-hg-2p", "ekf-2l",
                             "--out", str(o / "e.csv"), *extra]

    detect_without_telemetry = detect()       # detection reads roll and pitch off the frames without telemetry, and says so
    readers = {"telemetry.csv": [process(), estimate(), detect_without_telemetry], "truth.csv": [process(), estimate()],
               "labels.csv": [process(), estimate(), track()], "frames.csv": [process(), detect(), track()]}
    tele_cols = ("t_s", "roll_deg", "pitch_deg", "heading_deg", "p_dps", "q_dps", "r_dps", "vn_mps", "ve_mps",
                 "vd_mps")
    # ---- generic CSV damage, every reader and its commands
    for name, commands in readers.items():
        generic = [
            ("missing", remove(name), "error" if name != "frames.csv" and name != "truth.csv" else "accept"),
            ("empty", write_text(name, ""), "error"),
            ("header only", transform_text(name, lambda t: t.splitlines()[0] + "\n"), "error"),
            ("bom", transform_text(name, lambda t: "\ufeff" + t), "accept"),
            ("a folder", as_directory(name), "error"),
            ("binary", write_text(name, bytes(range(256)) * 4), "error"),
            ("short row", transform_text(name, lambda t: t.replace("\n", "\n1,2\n", 2).replace("\n1,2\n", "\n", 1)),
             "error"),
            ("time repeated", set_cell(name, "t_s", _rows_first_time(name)), "error"),
            ("text in time", set_cell(name, "t_s", "abc"), "error"),
            ("nan time", set_cell(name, "t_s", "nan"), "error"),
            ("inf time", set_cell(name, "t_s", "inf"), "error"),
            ("huge time", set_cell(name, "t_s", "1e308", row=-1), "error"),
            ("time in ms", map_column(name, "t_s", lambda t: t * 1000.0), "error"),
            ("negative times", map_column(name, "t_s", lambda t: t - 1e6), "error"),
            ("extra column", transform_text(name, lambda t: "\n".join(
                line + (",extra" if i == 0 else ",1") for i, line in enumerate(t.splitlines())) + "\n"), "accept"),
            ("duplicate column", transform_text(name, lambda t: "\n".join(
                line + (",t_s" if i == 0 else ",1") for i, line in enumerate(t.splitlines())) + "\n"), "error"),
        ]
        if name == "truth.csv":
            generic[0] = ("missing", remove(name), "accept-truthless")
        for label, damage, expect in generic:
            if name == "frames.csv" and label == "missing":
                continue
            # a time shift of frames.csv or labels.csv shows as frames the telemetry does not cover:
            # the error names the frame and its time (and the telemetry), which is the culprit
            token = "frame" if label in ("negative times",) and name in ("frames.csv", "labels.csv") else \
                name.split(".")[0]
            for command in commands:
                accepted = command is detect_without_telemetry and label == "missing"
                out.append((f"{name}: {label}", damage, command, "accept" if accepted else expect, token))
    # ---- telemetry values
    for column in tele_cols[1:]:
        for label, value in (("nan", "nan"), ("inf", "inf"), ("1e308", "1e308"), ("-1e308", "-1e308"),
                             ("text", "x"), ("empty", "")):
            expect = "error"
            out.append((f"telemetry.csv: {column} {label}", set_cell("telemetry.csv", column, value), process(),
                        expect, "telemetry.csv"))
    for column, value in (("roll_deg", "1e6"), ("pitch_deg", "400"), ("roll_deg", "-200"), ("heading_deg", "1e9"),
                          ("p_dps", "1e5"), ("q_dps", "-1e5"), ("r_dps", "5e4"), ("vn_mps", "5000"),
                          ("vd_mps", "-3000"), ("ve_mps", "1e7"), ("tas_mps", "-5"), ("tas_mps", "0"),
                          ("tas_mps", "1e6")):
        out.append((f"telemetry.csv: {column} = {value}", set_cell("telemetry.csv", column, value), process(),
                    "error", "telemetry.csv"))
        out.append((f"telemetry.csv: {column} = {value} (detect)", set_cell("telemetry.csv", column, value),
                    detect(), "error", "telemetry.csv"))
    out.append(("telemetry.csv: sparser than the frames", keep_rows("telemetry.csv", lambda i: i % 50 == 0),
                process(), "error", "telemetry.csv"))
    out.append(("telemetry.csv: every 3rd row", keep_rows("telemetry.csv", lambda i: i % 3 == 0), process(),
                "accept", ""))
    out.append(("telemetry.csv: not covering the frames", keep_rows("telemetry.csv", lambda i: i < 20), process(),
                "error", "telemetry.csv"))
    # ---- truth values
    for column in ("dx_m", "dy_m", "dh_m", "roll_deg", "pitch_deg", "dpsi_deg"):
        for value in ("1e308", "nan", "-1e6"):
            out.append((f"truth.csv: {column} = {value}", set_cell("truth.csv", column, value), process(), "error",
                        "truth.csv"))
    out.append(("truth.csv: one row fewer", keep_rows("truth.csv", lambda i: i < 7), process(), "error", "truth.csv"))
    out.append(("truth.csv: times shifted", map_column("truth.csv", "t_s", lambda t: t + 0.25), process(), "error",
                "truth.csv"))
    out.append(("truth.csv: times shifted (estimate)", map_column("truth.csv", "t_s", lambda t: t + 0.25),
                estimate(), "error", "truth.csv"))
    # ---- labels (the ideal source's measurements)
    for column, value in (("near_left_u_px", "-5000"), ("near_left_v_px", "1e9"), ("left_theta_rad", "100"),
                          ("left_rho", "1e6"), ("dF_px", "1e12"), ("near_left_visible", "7"), ("frame", "2.5"),
                          ("near_right_u_px", "nan"), ("center_theta_rad", "-50")):
        out.append((f"labels.csv: {column} = {value}", set_cell("labels.csv", column, value), process(), "error",
                    "labels.csv"))
    out.append(("labels.csv: frame numbers repeated", set_cell("labels.csv", "frame", "1", row=2), process(), "error",
                "labels.csv"))
    # ---- frames.csv
    for label, damage in (("frame 2.5", set_cell("frames.csv", "frame", "2.5")),
                          ("frame -1", set_cell("frames.csv", "frame", "-1")),
                          ("frame name missing", set_cell("frames.csv", "frame", "nope.png")),
                          ("one row fewer", keep_rows("frames.csv", lambda i: i < 7))):
        out.append((f"frames.csv: {label}", damage, process(), "error", "frames.csv"))
    # ---- camera.json
    for field in ("width", "height", "fx", "fy", "cx", "cy", "mount_rpy_deg"):
        out.append((f"camera.json: no {field}", camera_field(field, KeyError), process("detection"), "error",
                    "camera.json"))
        for value in ("abc", None, [1, 2], {"a": 1}, -1, 0, float("nan") if False else "nan"):
            if field == "mount_rpy_deg" and isinstance(value, list):
                value = [1, 2]
            out.append((f"camera.json: {field} = {value!r}", camera_field(field, value), process("detection"),
                        "error", "camera.json"))
    # a camera.json whose size is not the frames': every frame flagged, the run completes and says
    # why (issue 20 item 3)
    for field, value in (("width", 400), ("height", 200)):
        out.append((f"camera.json: {field} = {value!r}", camera_field(field, value), process("detection"), "flag",
                    "camera.json"))
    for field, value in (("fx", 10.0), ("fx", 1e9), ("fy", 1e-3), ("cx", 5000.0),
                         ("cy", -900.0), ("mount_rpy_deg", [0, 180, 0]), ("mount_rpy_deg", [0, -89.9, 0]),
                         ("width", 10 ** 9), ("distortion", [0.1, 0.2]), ("distortion", "abc"),
                         ("distortion", [1e9, 0, 0, 0, 0])):
        out.append((f"camera.json: {field} = {value!r}", camera_field(field, value), process("detection"), "error",
                    "camera.json"))
    for label, damage in (("a folder", as_directory("camera.json")), ("a list", write_text("camera.json", "[1, 2]")),
                          ("invalid", write_text("camera.json", "{")), ("empty", write_text("camera.json", "")),
                          ("binary", write_text("camera.json", b"\xff\xfe\x00")),
                          ("bom", transform_text("camera.json", lambda t: "\ufeff" + t))):
        expect = "accept" if label == "bom" else "error"
        for command in (process("detection"), detect(), track(), estimate()):
            out.append((f"camera.json: {label}", damage, command, expect, "camera.json"))
    # a focal length 3x too long is a plausible lens: no single file can tell (accepted)
    out.append(("camera.json: fx = 3x", camera_field("fx", 463.5 * 3), process("detection"), "accept", ""))
    # ---- frames
    for label, fn, expect in (("unreadable", lambda p: p.write_bytes(b"not an image"), "flag"),
                              ("empty file", lambda p: p.write_bytes(b""), "flag"),
                              ("other size", _small, "flag"),
                              ("huge PNG header", _huge_png, "flag"),
                              ("a folder", _frame_dir, "flag"), ("dangling link", _dangling, "flag"),
                              ("link loop", _loop, "flag"), ("all black", _black, "flag")):
        for command in (process("detection"), process("anchored"), detect(), track()):
            out.append((f"frames: frame 3 {label}", frame(3, fn), command, expect, "frame 3"))
        out.append((f"frames (no frames.csv): frame 3 {label}",
                    lambda d, fn=fn: (frame(3, fn)(d), (d / "frames.csv").unlink(), (d / "truth.csv").unlink(),
                                      (d / "labels.csv").unlink()),
                    process("detection", ("--initial-height", "80", "--fps", "2")), expect, "frame 3"))
    # ---- command-line paths and numbers
    def nothing(d):
        pass

    for label, command, token in (
            ("process --out /proc/x", lambda d, o: ["process", str(d), "--out", "/proc/visland-x", *P], "--out"),
            ("process --out below a file", lambda d, o: ["process", str(d), "--out", str(d / "camera.json" / "x"), *P],
             "--out"),
            ("detect --out /proc/x", lambda d, o: ["detect", str(d), "--out", "/proc/visland-x.csv", "--quiet"], "--out"),
            ("detect --out below a file", lambda d, o: ["detect", str(d), "--out", str(d / "camera.json" / "m.csv")],
             "--out"),
            ("track --out /proc/x", lambda d, o: ["track", str(d), "--out", "/proc/visland-x.csv"], "--out"),
            ("track --out below a file", lambda d, o: ["track", str(d), "--out", str(d / "camera.json" / "m.csv")],
             "--out"),
            ("estimate --out /proc/x", lambda d, o: estimate()(d, o)[:-1] + ["/proc/visland-x.csv"], "--out"),
            ("estimate --out below a file", lambda d, o: estimate()(d, o)[:-1] + [str(d / "camera.json" / "e.csv")],
             "--out"),
            ("compare --out /proc/x", lambda d, o: ["compare", str(d), "--out", "/proc/visland-x"], "--out"),
            ("process --camera a folder", lambda d, o: process("detection", ("--camera", str(d / "frames")))(d, o),
             "--camera"),
            ("process --telemetry a folder", lambda d, o: process("ideal", ("--telemetry", str(d / "frames")))(d, o),
             "--telemetry"),
            ("process --telemetry missing", lambda d, o: process("ideal", ("--telemetry", str(d / "nope.csv")))(d, o),
             "nope.csv"),
            ("process --frames-csv a folder", lambda d, o: process("ideal", ("--frames-csv", str(d / "frames")))(d, o),
             "--frames-csv"),
            ("process --params a folder", lambda d, o: process("ideal", ("--params", str(d / "frames")))(d, o),
             "--params"),
            ("process input missing", lambda d, o: ["process", str(d / "nope"), "--out", str(o / "run"), *P], "nope"),
            ("process input a file", lambda d, o: ["process", str(d / "camera.json"), "--out", str(o / "run"), *P],
             "camera.json"),
            ("detect --max-frames 0", lambda d, o: detect(("--max-frames", "0"))(d, o), "--max-frames"),
            ("detect --max-frames -1", lambda d, o: detect(("--max-frames", "-1"))(d, o), "--max-frames"),
            ("process --fps 0", lambda d, o: process("ideal", ("--fps", "0"))(d, o), "--fps"),
            ("process --fps nan", lambda d, o: process("ideal", ("--fps", "nan"))(d, o), "--fps"),
            ("process --fps 1e308", lambda d, o: process("ideal", ("--fps", "1e308"))(d, o), "--fps"),
            ("process --initial-height -5", lambda d, o: process("ideal", ("--initial-height", "-5"))(d, o),
             "--initial-height"),
            ("process --initial-height nan", lambda d, o: process("ideal", ("--initial-height", "nan"))(d, o),
             "--initial-height"),
            ("process --initial-height 1e308", lambda d, o: process("ideal", ("--initial-height", "1e308"))(d, o),
             "--initial-height"),
            ("process --initial-error -2", lambda d, o: process("ideal", ("--initial-error", "-2"))(d, o),
             "--initial-error"),
            ("estimate --aim-distance nan", lambda d, o: estimate(("--aim-distance", "nan"))(d, o), "--aim-distance"),
            ("track --init two corners", lambda d, o: process("tracking", ("--init", "100,200;150,200"))(d, o), ""),
            ("track --init garbage", lambda d, o: track(("--init", "a,b"))(d, o), "--init"),
    ):
        expect = "flag" if label == "track --init two corners" else "error"
        out.append((label, nothing, command, expect, token))
    # the fps that makes frame times disagree with truth (no frames.csv)
    out.append(("process --fps 3 without frames.csv", lambda d: (d / "frames.csv").unlink(),
                process("ideal", ("--fps", "3")), "error", "truth.csv"))
    # ---- compare on damaged run folders
    for label, damage, token in (
            ("run.json a list", write_text("run/run.json", "[1, 2]"), "run.json"),
            ("run.json a folder", as_directory("run/run.json"), "run.json"),
            ("run.json invalid", write_text("run/run.json", "{"), "run.json"),
            ("run.json source null", transform_text("run/run.json", lambda t: re.sub(r'"source": "[^"]*"',
                                                                                      '"source": null', t)), "run.json"),
            ("run.json binary", write_text("run/run.json", b"\xff\xfe"), "run.json"),
            ("estimates.csv missing", remove("run/estimates.csv"), "estimates.csv"),
            ("truth.csv dh 1e308", set_cell("run/truth.csv", "dh_m", "1e308"), "truth.csv"),
    ):
        out.append((f"compare: {label}", ("compare", damage),
                    lambda d, o: ["compare", str(d / "run"), "--out", str(o / "cmp")], "error", token))
    # ---- estimate on damaged measurements
    for column, value in (("near_left_u_px", "-1e6"), ("left_theta_rad", "100"), ("left_rho", "1e9"),
                          ("found", "2"), ("confidence", "7"), ("dF_px", "1e300"), ("t_s", "1e308"),
                          ("frame", "0.5")):
        out.append((f"measurements.csv: {column} = {value}", ("measurements", set_cell("m.csv", column, value)),
                    lambda d, o: ["estimate", str(d), "--measurements", str(d / "m.csv"), "--observer", "ccpi-hg-2p",
                                  "ekf-2l", "--out", str(o / "e.csv")], "error", "m.csv"))
    # ---- scenario files (generate/simulate)
    good = 'name = "s"\ndx_m = -1600.0\ndy_m = 20.0\ndgs_m = 0.0\ndpsi_deg = 1.0\n'
    for label, text, token in (("a folder", None, "s.toml"), ("invalid", "name = ", "s.toml"),
                               ("description a list", good + "description = [1]\n", "description"),
                               ("dx 1e308", good.replace("-1600.0", "-1e308"), "dx_m"),
                               ("dx nan", good.replace("-1600.0", "nan"), "dx_m"),
                               ("name a number", good.replace('"s"', "5"), "name"),
                               ("airspeed 1e6", good + "airspeed_kt = 1e6\n", "airspeed_kt"),
                               ("roll 400", good + "roll_deg = 400.0\n", "roll_deg"),
                               ("bom", "\ufeff" + good, "")):
        expect = "accept" if label == "bom" else "error"
        out.append((f"scenario: {label}", ("scenario", text),
                    lambda d, o: ["simulate", "--scenario", str(d / "s.toml"), "--out", str(o / "sim")], expect, token))
    return out


def _rows_first_time(name):
    return "0.5" if name == "frames.csv" else "0"


# --------------------------------------------------------------------------- running
def prepare(base: Path, case_dir: Path, damage) -> None:
    shutil.copytree(base, case_dir, symlinks=True)
    if isinstance(damage, tuple):
        kind, what = damage
        if kind == "compare":
            from visland.cli import main
            with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
                main(["process", str(case_dir), "--out", str(case_dir / "run"), "--source", "ideal", "--observer",
                      "ccpi-hg-2p", "--quiet", "--no-report"])
            what(case_dir)
        elif kind == "measurements":
            lines = (case_dir / "labels.csv").read_text().splitlines()
            (case_dir / "m.csv").write_text("\n".join([lines[0] + ",source,found,reason,confidence"]
                                                      + [line + ",external,1,,1" for line in lines[1:]]) + "\n")
            what(case_dir)
        elif kind == "scenario":
            if what is None:
                (case_dir / "s.toml").mkdir()
            else:
                (case_dir / "s.toml").write_text(what)
        return
    damage(case_dir)


def run_case(base: Path, work: Path, index: int, case, timeout: float) -> dict:
    from visland.cli import main
    name, damage, command, expect, token = case
    case_dir = work / f"case{index:03d}"
    shutil.rmtree(case_dir, ignore_errors=True)
    prepare(base, case_dir, damage)
    out = case_dir.parent / f"out{index:03d}"
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir()
    argv = command(case_dir, out)
    stdout, stderr = io.StringIO(), io.StringIO()
    signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    tic = time.perf_counter()
    outcome, rc, message = None, None, ""
    try:
        with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
            rc = main(argv)
    except Hang:
        outcome = "hang"
    except SystemExit as error:                       # argparse: a usage error is a clean refusal
        rc = error.code
    except BaseException as error:                    # noqa: BLE001 - what the corpus counts
        outcome, message = "traceback", f"{type(error).__name__}: {error}"
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
    wall = time.perf_counter() - tic
    err = stderr.getvalue().strip()
    if outcome is None:
        if rc not in (0, None):
            message = err.splitlines()[-1] if err else ""
            named = (token in message) if token else True
            leaked = any(s in message for s in INTERNALS) or ".partial-" in message
            if expect == "error" or expect == "flag" and rc == 2:
                outcome = "ok" if named and not leaked and err.count("\n") == 0 else "wrong-name"
                if expect == "flag":
                    outcome = "ok" if named and not leaked else "wrong-name"
            else:
                outcome = "ok" if not leaked and (expect != "accept" or False) else "wrong-refusal"
        else:
            flagged = _flagged(out, stdout.getvalue())
            if expect == "error":
                outcome = "silent"
            elif expect == "flag":
                outcome = "ok" if flagged else "silent"
            else:
                outcome = "ok"
    return {"case": name, "argv": " ".join(argv[:2]), "expect": expect, "outcome": outcome, "rc": rc,
            "wall_s": round(wall, 2), "message": message[:300]}


def _flagged(out: Path, text: str) -> bool:
    run = out / "run" / "run.json"
    if run.exists():
        data = json.loads(run.read_text())
        if data.get("n_flagged") or data.get("no_estimates"):
            return True
    for csv in (out / "run" / "measurements.csv", out / "m.csv"):
        if csv.exists():
            from visland.contracts import read_csv
            table = read_csv(csv, (), text_columns=("source", "reason"))
            if "found" in table and (table["found"] == 0).any():
                return True
    csv = out / "m.csv"
    if csv.exists():
        content = csv.read_text()
        return ",0," in content or "unreadable" in content or "skipped" in content
    return False


def use_tree(root: Path) -> None:
    """Import visland from another checkout ``root`` (same layout as pyproject's package-dir),
    to count a former version with the same corpus."""
    import importlib.abc
    import importlib.util
    stages = {"visland": root / "visland", **{f"visland.{s}": root / s for s in
                                               ("render", "detection", "tracking", "estimation", "datasets")}}

    class Finder(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path=None, target=None):
            if name in stages:
                return importlib.util.spec_from_file_location(name, stages[name] / "__init__.py",
                                                              submodule_search_locations=[str(stages[name])])
            return None

    sys.meta_path.insert(0, Finder())


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tree", type=Path, default=None, help="import visland from this checkout instead")
    parser.add_argument("--work", required=True, type=Path, help="scratch folder (cases are written there)")
    parser.add_argument("--base", type=Path, default=None, help="8-frame SPEC folder (default: rendered into --work)")
    parser.add_argument("--only", default=None, help="run only the cases whose name contains this text")
    parser.add_argument("--timeout", type=float, default=10.0, help="seconds before a case counts as a hang")
    parser.add_argument("--list", action="store_true", help="list the cases and stop")
    parser.add_argument("--keep", action="store_true", help="keep each case's folder")
    args = parser.parse_args(argv)
    if args.tree:
        use_tree(args.tree.resolve())
    all_cases = cases()
    if args.list:
        for k, case in enumerate(all_cases):
            print(k, case[0], case[3])
        print(len(all_cases), "cases")
        return 0
    args.work.mkdir(parents=True, exist_ok=True)
    base = args.base or make_base(args.work)
    results = []
    for k, case in enumerate(all_cases):
        if args.only and args.only not in case[0]:
            continue
        result = run_case(base, args.work, k, case, args.timeout)
        results.append(result)
        if result["outcome"] != "ok":
            print(f"{k:3d} {result['outcome']:11s} {result['wall_s']:6.1f}s {case[0]} [{result['argv']}] "
                  f"{result['message'][:200]}", flush=True)
        if not args.keep:
            shutil.rmtree(args.work / f"case{k:03d}", ignore_errors=True)
            shutil.rmtree(args.work / f"out{k:03d}", ignore_errors=True)
    counts = {}
    for r in results:
        counts[r["outcome"]] = counts.get(r["outcome"], 0) + 1
    slow = sum(1 for r in results if r["wall_s"] > 10.0)
    (args.work / "results.json").write_text(json.dumps(results, indent=1))
    print(json.dumps({"cases": len(results), "counts": counts, "over_10_s": slow,
                      "max_wall_s": max((r["wall_s"] for r in results), default=math.nan)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
