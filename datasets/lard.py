"""LARD-compatible corner labels for a generated dataset (for users who train runway detectors).

LARD (Landing Approach Runway Detection, DEEL) v2 keeps one ``;``-separated CSV per dataset
with one row per image. :func:`lard_rows` fills its columns from a visland simulation:

- corners, pixels: ``x_TR, y_TR`` far right, ``x_TL, y_TL`` far left, ``x_BL, y_BL`` threshold
  left, ``x_BR, y_BR`` threshold right (SPEC.md mapping). LARD's pixel coordinates are those of
  the image as stored (column, row); visland's labels use the pixel-centre convention of
  SPEC.md, written unchanged (sub-pixel values);
- pose in LARD's units: ``slant_distance`` and ``along_track_distance`` (camera to the
  threshold centre, and its component along the runway axis) in nautical miles,
  ``height_above_runway`` in feet, ``lateral_path_angle`` and ``vertical_path_angle`` (the
  camera seen from the threshold centre: azimuth from the extended centre line, positive to the
  right, and elevation) in degrees, ``time_to_landing`` in seconds at the current ground speed;
- camera attitude in LARD's (Google Earth Studio) convention, degrees: ``yaw`` in [-180, 180)
  with 0 looking south, ``pitch`` 90 for a horizontal optical axis (larger looks up), ``roll``
  counter-clockwise positive, all of the optical axis of the camera as mounted.

Frames in which a corner is outside the image keep the projected values (they may lie outside
``[0, width)``); a ``runway_in_image`` column (0/1) says whether all four are inside.
"""
from __future__ import annotations

import csv
import io
import math

import numpy as np

from visland.contracts import atomic_write_text
from visland.features import batch_R_camera_from_runway
from visland.flight import FT_TO_M
from visland.frames import R_ned_from_runway

__all__ = ["LARD_COLUMNS", "lard_rows", "write_lard_labels", "NM_M"]

NM_M = 1852.0

LARD_COLUMNS = (
    "image", "height", "width", "type", "original_dataset", "scenario", "airport", "runway", "time_to_landing",
    "weather", "night", "time", "slant_distance", "along_track_distance", "height_above_runway",
    "lateral_path_angle", "vertical_path_angle", "yaw", "pitch", "roll", "watermark_height",
    "x_TR", "y_TR", "x_TL", "y_TL", "x_BL", "y_BL", "x_BR", "y_BR", "runway_in_image",
)

# LARD corner -> visland corner index (CORNER_NAMES order near_left, near_right, far_left, far_right)
_CORNER_OF = {"TR": 3, "TL": 2, "BL": 0, "BR": 1}


def _camera_angles_lard(states, camera, runway_heading_deg):
    """Yaw, pitch, roll (degrees, LARD convention) of the optical axis of ``camera`` for each frame."""
    R_cr = batch_R_camera_from_runway(states.roll_rad, states.pitch_rad, states.dpsi_rad, camera.mount_rpy_rad)
    R_ned_from_camera = R_ned_from_runway(math.radians(runway_heading_deg)) @ np.swapaxes(R_cr, -1, -2)
    axis = R_ned_from_camera[:, :, 2]                     # optical axis in NED
    heading = np.degrees(np.arctan2(axis[:, 1], axis[:, 0]))
    elevation = np.degrees(np.arcsin(np.clip(-axis[:, 2], -1.0, 1.0)))
    # roll about the optical axis: angle of the image x axis below the horizontal plane
    image_x = R_ned_from_camera[:, :, 0]
    roll_right_down = np.degrees(np.arcsin(np.clip(image_x[:, 2], -1.0, 1.0)))
    yaw = (heading - 180.0 + 180.0) % 360.0 - 180.0       # 0 looks south
    return yaw, 90.0 + elevation, -roll_right_down


def lard_rows(result, image_names, designator: str, scenario_name: str) -> list[dict]:
    """One LARD row per frame of a :class:`visland.simulate.SimulationResult`.

    Parameters
    ----------
    result : visland.simulate.SimulationResult
        The flown scenario (true camera, frame states, labels).
    image_names : sequence of str
        The frame files, one per frame.
    designator : str
        The runway's designator as LARD writes it.
    scenario_name : str
        Written in each row.

    Returns
    -------
    list of dict
    """
    s = result.frames
    camera = result.camera_true
    p = s.p_runway_m
    along = -p[:, 0]
    height = -p[:, 2]
    slant = np.linalg.norm(p, axis=1)
    lateral = np.degrees(np.arctan2(p[:, 1], np.maximum(along, 1e-9)))
    vertical = np.degrees(np.arctan2(height, np.hypot(along, p[:, 1])))
    speed_x = s.v_runway_mps[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        time_to_landing = np.where(speed_x > 1.0, along / speed_x, np.nan)
    yaw, pitch, roll = _camera_angles_lard(s, camera, result.scenario.runway.heading_deg)
    uv = result.features.corners_uv
    inside = result.features.corners_visible.all(axis=1)
    rows = []
    for i, name in enumerate(image_names):
        row = {
            "image": name, "height": camera.height, "width": camera.width, "type": "visland",
            "original_dataset": "visland", "scenario": scenario_name, "airport": "VSLD", "runway": designator,
            "time_to_landing": time_to_landing[i], "weather": "clear", "night": 0, "time": f"{s.t_s[i]:.3f}",
            "slant_distance": slant[i] / NM_M, "along_track_distance": along[i] / NM_M,
            "height_above_runway": height[i] / FT_TO_M, "lateral_path_angle": lateral[i],
            "vertical_path_angle": vertical[i], "yaw": yaw[i], "pitch": pitch[i], "roll": roll[i],
            "watermark_height": 0, "runway_in_image": int(inside[i]),
        }
        for corner, k in _CORNER_OF.items():
            row[f"x_{corner}"] = uv[i, k, 0]
            row[f"y_{corner}"] = uv[i, k, 1]
        rows.append(row)
    return rows


def _cell(value) -> str:
    if isinstance(value, str):
        return value
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    value = float(value)
    return "" if not math.isfinite(value) else format(value + 0.0, ".10g")


def write_lard_labels(path, rows) -> None:
    """Write LARD rows as a ``;``-separated CSV, atomically.

    Parameters
    ----------
    path : str or Path
        The CSV to write.
    rows : list of dict
        From :func:`lard_rows`.
    """
    buffer = io.StringIO()
    writer = csv.writer(buffer, delimiter=";", lineterminator="\n")
    writer.writerow(LARD_COLUMNS)
    for row in rows:
        writer.writerow([_cell(row[c]) for c in LARD_COLUMNS])
    atomic_write_text(path, buffer.getvalue())
