"""Tracked points as ``measurements.csv`` rows (the labels schema of SPEC.md), and designations.

Measurement rows (:data:`visland.contracts.MEASUREMENT_COLUMNS`, then extra columns):

- ``<corner>_u_px, <corner>_v_px``: the tracked corner when it was measured in this frame
  (statuses tracked, anchored, reprojected, inconsistent, designated); empty otherwise;
- ``<corner>_visible``: 1 measured, 0 designated but not measured in this frame (coasting,
  lost, refused, skipped frame), empty for a corner that was not designated;
- lines, ``dF_px``, ``dpsi_deg``: only on frames where an anchor (the detector) was used and
  supplied them; empty otherwise (a template tracker measures points, not lines);
- ``source``: ``"anchored"`` when a point of the row was re-anchored on the detector in this
  frame, else ``"tracking"``;
- ``found``: 1 when every designated threshold corner (near_left, near_right) was measured,
  or, if none was designated, every designated point; 0 otherwise;
- ``reason``: every point not simply tracked, with its status and why, e.g.
  ``"near_right coasting (score 0.41 < 0.60; coasting 1/5)"``; the frame note first
  (skipped frame, anchor not used, points disagreeing);
- ``confidence``: the smallest match score (normalised cross-correlation, clipped to [0, 1])
  over the points ``found`` requires; an anchored point counts with the anchor's confidence;
- extra columns: ``<point>_score`` for every tracked point, and ``<point>_u_px``,
  ``<point>_v_px`` for designated points that are not runway corners (edge points).
"""
from __future__ import annotations

import math
import re

import numpy as np

from visland.contracts import MEASUREMENT_COLUMNS
from visland.runway import CORNER_NAMES
from visland.tracking.anchoring import LINE_NAMES

__all__ = ["measurement_columns", "steps_to_columns", "parse_designation", "designation_from_labels",
           "THRESHOLD_CORNERS"]

THRESHOLD_CORNERS = ("near_left", "near_right")
_NAME = re.compile(r"^[a-z][a-z0-9_]*$")


def measurement_columns(point_names) -> list:
    """Column order: the SPEC measurement columns, then the per-point extras.

    Parameters
    ----------
    point_names : sequence of str
        The tracked points (corners of :data:`visland.runway.CORNER_NAMES` and extra points).

    Returns
    -------
    list of str
    """
    extra = []
    for name in point_names:
        if name not in CORNER_NAMES:
            extra += [f"{name}_u_px", f"{name}_v_px"]
    extra += [f"{name}_score" for name in point_names]
    return list(MEASUREMENT_COLUMNS) + extra


def _required(point_names) -> list:
    near = [n for n in THRESHOLD_CORNERS if n in point_names]
    return near if near else list(point_names)


def steps_to_columns(steps, times_s, point_names, anchor_min_confidence: float = 0.5,
                     run_source: str = "tracking") -> dict:
    """Columns (dict of lists) of ``measurements.csv`` for a sequence of :class:`TrackStep`.

    ``steps`` holds one entry per frame, None for a frame before the designation (written as
    not found, reason "before the designation"); ``times_s`` the frame times. A measured row's
    ``source`` says how it was measured (``anchored`` when a detection re-anchored a point,
    else ``tracking``); a row that measured nothing (before the designation, a skipped frame)
    carries ``run_source``, the run's own source.

    Parameters
    ----------
    steps : sequence of TrackStep or None
        One entry per frame.
    times_s : sequence of float
        The frame times, seconds.
    point_names : sequence of str
        The tracked points, in column order.
    anchor_min_confidence : float, default 0.5
        An anchor observation under this confidence does not make a row ``anchored``.
    run_source : str, default "tracking"
        ``source`` of the rows that measured nothing.

    Returns
    -------
    dict of str to list
        :func:`measurement_columns` -> one value per frame.
    """
    point_names = list(point_names)
    columns = {c: [] for c in measurement_columns(point_names)}
    required = _required(point_names)
    for frame, (step, t_s) in enumerate(zip(steps, times_s)):
        row = {c: math.nan for c in columns}
        row["frame"] = frame
        row["t_s"] = float(t_s)
        if step is None:
            row.update(source=run_source, found=0, reason="before the designation")
            for name in CORNER_NAMES:
                row[f"{name}_visible"] = 0 if name in point_names else math.nan
            for c in columns:
                columns[c].append(row[c])
            continue
        anchor = step.anchor
        anchor_used = anchor is not None and anchor.found and anchor.confidence >= anchor_min_confidence
        scores = []
        for report in step.points:
            measured = report.measured
            if report.name in CORNER_NAMES:
                row[f"{report.name}_visible"] = 1 if measured else 0
            if measured:
                row[f"{report.name}_u_px"] = float(report.uv[0])
                row[f"{report.name}_v_px"] = float(report.uv[1])
            row[f"{report.name}_score"] = report.score
            if report.name in required:
                if not measured:
                    scores.append(math.nan)
                elif report.status == "anchored" and anchor_used:
                    scores.append(anchor.confidence)
                else:
                    scores.append(report.score)
        found = all(step.point(n).measured for n in required)
        if anchor_used:
            for name in LINE_NAMES:
                if name in anchor.lines:
                    row[f"{name}_rho"], row[f"{name}_theta_rad"] = anchor.lines[name]
            row["dF_px"] = anchor.dF_px
            row["dpsi_deg"] = math.degrees(anchor.dpsi_rad) if math.isfinite(anchor.dpsi_rad) else math.nan
        finite_scores = [s for s in scores if math.isfinite(s)]
        measured_any = any(report.measured for report in step.points)
        row["source"] = ("anchored" if step.anchored else "tracking") if measured_any else run_source
        row["found"] = 1 if found else 0
        row["reason"] = step.reason()
        row["confidence"] = (float(np.clip(min(finite_scores), 0.0, 1.0)) if (found and finite_scores)
                             else math.nan)
        for c in columns:
            columns[c].append(row[c])
    return columns


def parse_designation(text: str) -> list:
    """Points from a command-line designation ``"u,v;u,v"`` or ``"near_left=u,v;near_right=u,v"``.

    Unnamed points take the corner names in order (near_left, near_right, far_left,
    far_right), then ``point_5``, ``point_6``...; an empty entry skips a corner name
    (``";;u,v"`` designates far_left only). Returns ``[(name, (u, v)), ...]``. Positions
    outside the image are kept (the tracker refuses them with a reason); text that is not a
    pair of numbers raises ValueError naming the entry.

    Parameters
    ----------
    text : str
        The ``--init`` value.

    Returns
    -------
    list of (str, (float, float))
        Name and pixel position ``(u, v)`` of each designated point.
    """
    if not isinstance(text, str) or not text.strip():
        raise ValueError("--init: give 'labels' or pixel positions 'u,v;u,v'")
    points = []
    for position, entry in enumerate(text.split(";")):
        entry = entry.strip()
        if not entry:
            continue
        if "=" in entry:
            name, _, value = entry.partition("=")
            name = name.strip()
            if not _NAME.match(name):
                raise ValueError(f"--init: point name '{name}' must be lower-case letters, digits and _")
        else:
            name = CORNER_NAMES[position] if position < len(CORNER_NAMES) else f"point_{position + 1}"
            value = entry
        parts = value.split(",")
        try:
            u, v = (float(x) for x in parts)
        except ValueError:
            raise ValueError(f"--init: entry {position + 1} ({entry!r}) is not a pixel position 'u,v'") from None
        if not (math.isfinite(u) and math.isfinite(v)):
            raise ValueError(f"--init: entry {position + 1} ({entry!r}) is not a finite pixel position")
        points.append((name, (u, v)))
    names = [n for n, _ in points]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise ValueError(f"--init: point '{duplicates[0]}' is designated twice")
    if not points:
        raise ValueError("--init: no pixel position given")
    return points


def designation_from_labels(labels, frame: int, corners=CORNER_NAMES, edge_points: int = 0) -> list:
    """The labelled corners of one frame (those visible), plus points along the runway edges.

    ``edge_points`` points are put on each side edge between its threshold and end corners, at
    equal steps of the image segment (the image of a straight edge is the segment between its
    corners' images), named ``left_edge_1``... and ``right_edge_1``...; they are edge points
    for the tracker (matched across the edge only).

    Parameters
    ----------
    labels : visland.contracts.Table
        ``labels.csv`` (exact corners and visibility flags).
    frame : int
        The designation frame (a row of ``labels``).
    corners : sequence of str, default CORNER_NAMES
        The corners to designate when visible.
    edge_points : int, default 0
        Points per side edge, 0 to 20.

    Returns
    -------
    list of (str, (float, float))
    """
    if isinstance(edge_points, bool) or not isinstance(edge_points, int) or not 0 <= edge_points <= 20:
        raise ValueError(f"edge_points must be an integer in [0, 20], got {edge_points!r}")
    n = len(labels["t_s"])
    if not 0 <= frame < n:
        raise ValueError(f"labels.csv has no row for frame {frame} ({n} rows)")
    points = []
    uv = {}
    for name in CORNER_NAMES:
        u = float(labels[f"{name}_u_px"][frame])
        v = float(labels[f"{name}_v_px"][frame])
        visible = float(labels[f"{name}_visible"][frame]) == 1 and math.isfinite(u) and math.isfinite(v)
        if visible:
            uv[name] = np.array([u, v])
            if name in corners:
                points.append((name, (u, v)))
    for side in ("left", "right"):
        near, far = uv.get(f"near_{side}"), uv.get(f"far_{side}")
        if edge_points and (near is None or far is None):
            raise ValueError(f"labels.csv frame {frame}: the {side} edge's corners are not both visible, "
                             "so no edge points can be put on it")
        for k in range(1, edge_points + 1):
            f = k / (edge_points + 1)
            p = near + f * (far - near)
            points.append((f"{side}_edge_{k}", (float(p[0]), float(p[1]))))
    if not points:
        raise ValueError(f"labels.csv frame {frame}: no runway corner is visible to designate")
    return points
