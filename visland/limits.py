"""Plausibility limits of every physical input (SPEC "Bad input"), in one table.

A value outside its limit is refused by the reader with one sentence naming the file, the
line, the column, the value and the limit (``telemetry.csv line 5: column 'vn_mps' is 1e+308,
outside the plausible -1000..1000 m/s (ground velocity: Mach 3 at most)``). The limits are
wide on purpose: they let every real approach through (an airliner, a helicopter, a fast jet,
a UNIX time stamp) and stop what no instrument reports (1e308 m/s, a roll of 1e6 deg, a time
in milliseconds, a line angle of 100 rad), which would otherwise make the observers run on
nonsense or for hours. The README's table ("Plausibility limits") is :func:`markdown_table`.

Checks that need more than one file (pixels against the image size, the telemetry rate
against the frame rate, camera against frames) are functions here too, called by the
commands once every input is read.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Limit", "COLUMN_LIMITS", "FRAME_INTERVAL_S", "PIXEL_MARGIN", "FOCAL_PER_SIDE", "MAX_IMAGE_SIDE_PX",
           "MOUNT_LIMITS_DEG", "PRINCIPAL_POINT_SPREAD", "FPS_LIMIT", "check_rows_at_frames", "check_columns", "check_frame_times", "check_telemetry_rate", "check_pixels",
           "check_camera", "markdown_table"]


@dataclass(frozen=True)
class Limit:
    """A closed interval ``[low, high]`` in ``unit``, and why.

    Attributes
    ----------
    low, high : float
        The interval's ends, in ``unit``.
    unit : str
        The unit as written in messages (``"deg"``, ``"m/s"``, ``"px"``...).
    why : str
        What makes a value outside implausible, quoted in the error.
    """

    low: float
    high: float
    unit: str
    why: str

    def describe(self) -> str:
        return f"{self.low:g}..{self.high:g} {self.unit}".rstrip() + f" ({self.why})"


_ANGLE_ROLL = Limit(-180.0, 180.0, "deg", "an Euler roll angle")
_ANGLE_PITCH = Limit(-90.0, 90.0, "deg", "an Euler pitch angle")
_TIME = Limit(-1e10, 1e10, "s", "seconds, UNIX time stamps included; milliseconds are refused by the rate checks")
_RATE = Limit(-400.0, 400.0, "deg/s", "body rate: an aerobatic roll is under 400 deg/s")
_VELOCITY = Limit(-1000.0, 1000.0, "m/s", "velocity: Mach 3 at most")
_PIXEL = Limit(-1e6, 1e6, "px", "a pixel coordinate; the image size bounds it further")
_THETA = Limit(-math.pi / 2 - 1e-6, math.pi / 2 + 1e-6, "rad", "the SPEC line chart, theta in [-pi/2, pi/2)")
_RHO = Limit(-100.0, 100.0, "", "normalised distance of a line from the principal point; 100 is 100 focal lengths")

#: Per column: its limit (the same in every file that has the column).
COLUMN_LIMITS = {
    "t_s": _TIME,
    "roll_deg": _ANGLE_ROLL,
    "pitch_deg": _ANGLE_PITCH,
    "heading_deg": Limit(-3600.0, 3600.0, "deg", "a heading, unwrapped over at most ten turns"),
    "p_dps": _RATE, "q_dps": _RATE, "r_dps": _RATE,
    "vn_mps": _VELOCITY, "ve_mps": _VELOCITY, "vd_mps": _VELOCITY,
    "tas_mps": Limit(1e-3, 1000.0, "m/s", "true airspeed: positive, Mach 3 at most"),
    "dx_m": Limit(-1e5, 1e5, "m", "along-track distance: a visual approach starts within 100 km"),
    "dy_m": Limit(-1e5, 1e5, "m", "cross-track distance: 100 km"),
    "dh_m": Limit(-1000.0, 30000.0, "m", "height above the runway: 1 km below to 30 km above"),
    "dpsi_deg": Limit(-180.0, 180.0, "deg", "a heading deviation"),
    **{f"{corner}_{axis}_px": _PIXEL for corner in ("near_left", "near_right", "far_left", "far_right")
       for axis in ("u", "v")},
    **{f"{line}_theta_rad": _THETA for line in ("left", "right", "center")},
    **{f"{line}_rho": _RHO for line in ("left", "right", "center")},
    "dF_px": Limit(-1e7, 1e7, "px", "the vanishing-point feature: fx tan(dpsi) for |dpsi| < 89.99 deg"),
    "confidence": Limit(0.0, 1.0, "", "a confidence"),
}
#: Time between two frames (frames.csv, --fps): 0.1 ms to 10 s.
FRAME_INTERVAL_S = Limit(1e-4, 10.0, "s", "frames at 0.1 Hz to 10 kHz; a time in milliseconds looks 1000x too slow")
#: Pixels (corners) must lie within this many image sizes outside the frame.
PIXEL_MARGIN = 1.0
#: Focal length against the larger image side: a 0.5 deg to 170 deg field of view.
FOCAL_PER_SIDE = Limit(0.04, 100.0, "x side", "fx and fy over the image side: fields of view of 170 deg to 0.6 deg")
MAX_IMAGE_SIDE_PX = 16384
#: The principal point lies within this fraction of the side from the image centre.
PRINCIPAL_POINT_SPREAD = 0.25
#: --fps: frames at 0.1 Hz to 10 kHz (the inverse of :data:`FRAME_INTERVAL_S`).
FPS_LIMIT = Limit(0.1, 1e4, "Hz", "a camera frame rate")
#: Camera mounting (roll, pitch, yaw) relative to the body: a forward-looking camera.
MOUNT_LIMITS_DEG = (Limit(-180.0, 180.0, "deg", "mount roll"), Limit(-60.0, 60.0, "deg", "mount pitch: forward-looking"),
                    Limit(-60.0, 60.0, "deg", "mount yaw: forward-looking"))


def _line_of(table, index: int) -> int:
    return index + 2                                   # the header is line 1


def check_columns(table, name: str | None = None, columns=None, rows=None) -> None:
    """Raise on the first cell of ``table`` outside its :data:`COLUMN_LIMITS` limit (NaN cells,
    which mean "not measured", pass).

    Parameters
    ----------
    table : visland.contracts.Table
        A table as read.
    name : str, optional
        How the file is named in the error (default its path).
    columns : iterable of str, optional
        The columns to check (default every column of the file).
    rows : ndarray of bool, shape (n_rows,), optional
        The rows to check (default all).
    """
    label = name or str(table.path)
    for column in (columns or table.column_order):
        limit = COLUMN_LIMITS.get(column)
        if limit is None or column not in table or table[column].dtype.kind != "f":
            continue
        values = table[column]
        i = _first_outside(values, limit.low, limit.high, rows)
        if i is not None:
            raise ValueError(f"{label} line {_line_of(table, i)}: column '{column}' is {values[i]:g}, outside the "
                             f"plausible {limit.describe()}")


def _first_outside(values, low: float, high: float, rows=None):
    """Index of the first of ``values`` outside ``[low, high]`` among ``rows`` (NaN is inside:
    "not measured"), or None."""
    with np.errstate(invalid="ignore"):
        bad = (values < low) | (values > high)
    if rows is not None:
        bad &= rows
    index = np.nonzero(bad)[0]
    return int(index[0]) if index.size else None


def check_frame_times(times_s, name: str) -> None:
    """Frame times: increasing by :data:`FRAME_INTERVAL_S` at most and at least.

    Parameters
    ----------
    times_s : array_like, shape (n,)
        Frame times, seconds (fewer than two pass).
    name : str
        What the times are called in the error (a file, or "frame times of DIR").
    """
    times = np.asarray(times_s, dtype=float)
    if times.size < 2:
        return
    steps = np.diff(times)
    limit = FRAME_INTERVAL_S
    bad = np.nonzero((steps < limit.low) | (steps > limit.high))[0]
    if bad.size:
        i = int(bad[0]) + 1
        raise ValueError(f"{name}: frame {i} comes {steps[i - 1]:g} s after frame {i - 1}, outside the plausible "
                         f"{limit.describe()}")


def check_telemetry_rate(telemetry_t_s, frame_t_s, name: str, frames_name: str = "") -> None:
    """SPEC: telemetry at a rate >= the frame rate, over the frames' span (median intervals).

    Parameters
    ----------
    telemetry_t_s : array_like, shape (m,)
        Telemetry times, seconds, on the frames' clock.
    frame_t_s : array_like, shape (n,)
        Frame times, seconds; each must lie inside the telemetry's span.
    name : str
        The telemetry file, as named in the error.
    frames_name : str, optional
        Where the frame times come from, added to the coverage error.
    """
    telemetry = np.asarray(telemetry_t_s, dtype=float)
    frames = np.asarray(frame_t_s, dtype=float)
    if telemetry.size and frames.size:
        outside = np.nonzero((frames < telemetry[0] - 1e-6) | (frames > telemetry[-1] + 1e-6))[0]
        if outside.size:
            i = int(outside[0])
            raise ValueError(f"{name}: telemetry covers {telemetry[0]:g}..{telemetry[-1]:g} s but frame {i} is at "
                             f"t = {frames[i]:g} s{' (' + frames_name + ')' if frames_name else ''}")
    if telemetry.size < 2 or frames.size < 2:
        return
    inside = telemetry[(telemetry >= frames[0]) & (telemetry <= frames[-1])]
    span = frames[-1] - frames[0]
    frame_step = float(np.median(np.diff(frames)))
    telemetry_step = float(np.median(np.diff(telemetry)))
    if telemetry_step > frame_step * (1.0 + 1e-6) or inside.size < frames.size * (1.0 - 1e-6) - 1:
        raise ValueError(f"{name}: one sample every {telemetry_step:g} s ({inside.size} over the frames' {span:g} s), "
                         f"sparser than the frames (every {frame_step:g} s); the telemetry must come at a rate >= "
                         "the frame rate, times in seconds")


def check_rows_at_frames(table, times_s, how: str, what: str) -> None:
    """``table`` (truth, labels) has one row per frame, at the frame times ``times_s``.

    Parameters
    ----------
    table : visland.contracts.Table
        The truth or labels table (its ``t_s`` column).
    times_s : array_like, shape (n,)
        The frame times, seconds (matched to 1e-6 s).
    how : str
        Where the frame times come from, quoted in the error.
    what : str
        The table's name in the error (``"labels"``, ``"truth"``).
    """
    times = np.asarray(times_s, dtype=float)
    if table.n_rows != len(times):
        raise ValueError(f"{table.path}: {table.n_rows} rows but there are {len(times)} frames (one row per frame)")
    off = np.nonzero(np.abs(table["t_s"] - times) > 1e-6)[0]
    if off.size:
        i = int(off[0])
        raise ValueError(f"{table.path} line {i + 2}: t_s is {table['t_s'][i]:g} s but frame {i} is at {times[i]:g} s "
                         f"({how}); the {what} must have one row per frame at the frame times")


def check_pixels(table, width: int, height: int, name: str | None = None, rows=None) -> None:
    """Corner pixels within :data:`PIXEL_MARGIN` image sizes of a ``width`` x ``height`` frame
    (only the rows of ``rows`` and the corners flagged visible, when the table says).

    Parameters
    ----------
    table : visland.contracts.Table
        Labels or measurements (``*_u_px``, ``*_v_px`` columns, SPEC pixel convention).
    width, height : int
        The frame's size, pixels.
    name : str, optional
        How the file is named in the error (default its path).
    rows : ndarray of bool, shape (n_rows,), optional
        The rows to check (default all).
    """
    label = name or str(table.path)
    for corner in ("near_left", "near_right", "far_left", "far_right"):
        for axis, side in (("u", width), ("v", height)):
            column = f"{corner}_{axis}_px"
            if column not in table:
                continue
            values = table[column]
            low, high = -PIXEL_MARGIN * side, (1.0 + PIXEL_MARGIN) * side
            checked = rows
            if f"{corner}_visible" in table:            # a corner said not visible may lie anywhere
                visible = np.nan_to_num(table[f"{corner}_visible"], nan=0.0) > 0.5
                checked = visible if rows is None else visible & rows
            i = _first_outside(values, low, high, checked)
            if i is not None:
                raise ValueError(f"{label} line {_line_of(table, i)}: column '{column}' is {values[i]:g} px, outside "
                                 f"the plausible {low:g}..{high:g} px (the {width}x{height} image and "
                                 f"{PIXEL_MARGIN:g} image size around it)")


def check_camera(camera, name: str) -> None:
    """Focal lengths against the image size, principal point inside the image, mounting.

    Parameters
    ----------
    camera : visland.camera.CameraModel
        The camera to check (image size, ``fx``, ``fy``, ``cx``, ``cy`` in pixels, mounting).
    name : str
        Its file, as named in the error.
    """
    side = max(camera.width, camera.height)
    if side > MAX_IMAGE_SIDE_PX:
        raise ValueError(f"{name}: an image of {camera.width}x{camera.height} px, larger than the plausible "
                         f"{MAX_IMAGE_SIDE_PX} px side")
    limit = FOCAL_PER_SIDE
    for key in ("fx", "fy"):
        value = getattr(camera, key)
        if not limit.low * side <= value <= limit.high * side:
            raise ValueError(f"{name}: field '{key}' is {value:g} px, outside the plausible {limit.low * side:g}.."
                             f"{limit.high * side:g} px for a {camera.width}x{camera.height} image ({limit.why})")
    for key, size in (("cx", camera.width), ("cy", camera.height)):
        value = getattr(camera, key)
        low, high = (size - 1) / 2 - PRINCIPAL_POINT_SPREAD * size, (size - 1) / 2 + PRINCIPAL_POINT_SPREAD * size
        if not low <= value <= high:
            raise ValueError(f"{name}: field '{key}' is {value:g} px, outside the plausible {low:g}..{high:g} px "
                             f"(the middle half of the {size} px side: a lens centred on its sensor)")
    for k, (angle, limit) in enumerate(zip(camera.mount_rpy_rad, MOUNT_LIMITS_DEG)):
        degrees = math.degrees(angle)
        if not limit.low <= degrees <= limit.high:
            raise ValueError(f"{name}: field 'mount_rpy_deg'[{k}] is {degrees:g} deg, outside the plausible "
                             f"{limit.describe()}")


def markdown_table() -> str:
    """The README table of every limit."""
    rows = ["| input | plausible range | why |", "|---|---|---|"]
    groups: dict = {}
    for column, limit in COLUMN_LIMITS.items():
        groups.setdefault(limit, []).append(column)
    for limit, columns in groups.items():
        names = ", ".join(f"`{c}`" for c in columns)
        rows.append(f"| {names} | {limit.low:g} .. {limit.high:g} {limit.unit} | {limit.why} |")
    rows.append(f"| frame interval (frames.csv, --fps) | {FRAME_INTERVAL_S.low:g} .. {FRAME_INTERVAL_S.high:g} s | "
                f"{FRAME_INTERVAL_S.why} |")
    rows.append("| telemetry rate | >= the frame rate (median intervals) | SPEC; a time in milliseconds fails it |")
    rows.append(f"| corner pixels (`*_u_px`, `*_v_px`) against camera.json | -{PIXEL_MARGIN:g} .. "
                f"{1 + PIXEL_MARGIN:g} image sizes | a visible or found corner lies near the frame |")
    rows.append(f"| `fx`, `fy` | {FOCAL_PER_SIDE.low:g} .. {FOCAL_PER_SIDE.high:g} x the larger image side | "
                f"{FOCAL_PER_SIDE.why} |")
    rows.append(f"| `cx`, `cy` | (size - 1) / 2 +- {PRINCIPAL_POINT_SPREAD:g} x size px | a lens centred on its "
                "sensor |")
    rows.append(f"| `--fps` | {FPS_LIMIT.low:g} .. {FPS_LIMIT.high:g} Hz | {FPS_LIMIT.why} |")
    rows.append(f"| `width`, `height` | 1 .. {MAX_IMAGE_SIDE_PX} px, equal to the frames' | every frame of another "
                "size is flagged; a run where none fits says so |")
    rows.append("| `mount_rpy_deg` | " + ", ".join(f"{m.low:g} .. {m.high:g}" for m in MOUNT_LIMITS_DEG)
                + " deg | a forward-looking camera |")
    rows.append("| `frame` (frames.csv, labels, measurements) | integers 0, 1, 2... in order | one row per frame |")
    rows.append("| `found`, `*_visible` | 0 or 1 | flags |")
    return "\n".join(rows)


def check_frame_folder(folder, camera_source: str, where: str) -> None:
    """What every command reading a :class:`visland.folder.FrameFolder` checks before its first
    frame: the camera, the frame times, the telemetry's rate against them and the labels' rows."""
    check_camera(folder.camera, camera_source)
    check_frame_times(folder.times_s, f"frame times of {where}")
    if folder.telemetry is not None:
        check_telemetry_rate(folder.telemetry["t_s"], folder.times_s, str(folder.telemetry.path))
    if folder.labels is not None:
        check_rows_at_frames(folder.labels, folder.times_s, f"frame times of {where}", "labels")
