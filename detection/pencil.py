"""Edges through one vanishing point: the image resampled in pencil coordinates.

Given a candidate vanishing point V1 on the horizon (``s = s0``, see
:mod:`visland.detection.horizon`), every line through it is ``s = s0 + k d``. Sampling the
frame on a grid of depths ``d`` (rows) and slopes ``k`` (columns) gives a *rectified* image
in which all those lines are columns: the runway's edges, its centre line, taxiways and
roads parallel to it, field boundaries along it. Averaging columns over a band of depths
turns faint, short edges into clean steps (a far runway's edges are a few grey levels on
textured grass), and locates them to a fraction of a pixel in ``k`` whatever the Hough
transform made of them.

Depths are processed in bands of geometric widths (a runway spans depths from its far end to
its threshold; a band much longer would dilute it with grass): each band's mean column
profile is differentiated over about one and a half pixels, its steps are found, and steps
found at the same slope in neighbouring bands are joined into one edge with a depth span.

Pixels: (0, 0) is the centre of the top-left pixel (SPEC).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from visland.detection.horizon import HorizonFrame

__all__ = ["PencilImage", "PencilEdges", "rectify", "pencil_edges"]


@dataclass(frozen=True)
class PencilImage:
    """The frame resampled on lines through ``(s0, 0)``.

    Attributes
    ----------
    s0 : float
    k : ndarray (m,)
        Column slopes.
    d : ndarray (r,)
        Row depths (pixels below the horizon).
    values : ndarray (r, m)
        Grey levels (NaN outside the frame).
    """

    s0: float
    k: np.ndarray
    d: np.ndarray
    values: np.ndarray

    @property
    def k_step(self) -> float:
        return float(self.k[1] - self.k[0]) if len(self.k) > 1 else 1.0

    def column_of(self, k) -> np.ndarray:
        return np.clip(np.rint((np.asarray(k, float) - self.k[0]) / self.k_step).astype(int), 0, len(self.k) - 1)

    def rows_between(self, d_lo: float, d_hi: float) -> np.ndarray:
        return (self.d >= d_lo) & (self.d <= d_hi)


@dataclass(frozen=True)
class PencilEdges:
    """Steps found in a :class:`PencilImage`: one row per edge.

    ``k`` slope, ``polarity`` sign of the grey-level change towards larger k (towards +s),
    ``contrast`` mean step (grey levels) over the edge's depth span ``[d_a, d_b]``,
    ``support`` the fraction of that span's bands holding it.
    """

    s0: float
    k: np.ndarray
    polarity: np.ndarray
    contrast: np.ndarray
    d_a: np.ndarray
    d_b: np.ndarray
    support: np.ndarray

    def __len__(self) -> int:
        return len(self.k)


def rectify(image, horizon: HorizonFrame, s0: float, k_range: tuple, d_range: tuple,
            max_rows: int = 160, max_columns: int = 4096, pixel_step: float = 0.5) -> PencilImage | None:
    """Resample ``image`` on lines through the horizon point ``s0``.

    Columns are spaced so that neighbouring columns are ``pixel_step`` pixels apart at the
    deepest row; rows are one pixel apart (at most ``max_rows``).
    """
    d_lo, d_hi = max(float(d_range[0]), 1.0), float(d_range[1])
    k_lo, k_hi = float(k_range[0]), float(k_range[1])
    if not (d_hi > d_lo + 2 and k_hi > k_lo):
        return None
    n_rows = int(min(max_rows, max(8, math.ceil(d_hi - d_lo) + 1)))
    d = np.linspace(d_lo, d_hi, n_rows)
    k_step = pixel_step / d_hi
    n_cols = int(math.ceil((k_hi - k_lo) / k_step)) + 1
    if n_cols > max_columns:
        n_cols = max_columns
        k_step = (k_hi - k_lo) / (n_cols - 1)
    k = k_lo + k_step * np.arange(n_cols)
    uv = horizon.pencil_point(s0, k[None, :], d[:, None])                  # (r, m, 2)
    height, width = image.shape
    inside = (uv[..., 0] >= 0) & (uv[..., 0] <= width - 1) & (uv[..., 1] >= 0) & (uv[..., 1] <= height - 1)
    if not inside.any():
        return None
    u0 = int(max(0, math.floor(uv[..., 0][inside].min()) - 1))
    v0 = int(max(0, math.floor(uv[..., 1][inside].min()) - 1))
    u1 = int(min(width, math.ceil(uv[..., 0][inside].max()) + 2))
    v1 = int(min(height, math.ceil(uv[..., 1][inside].max()) + 2))
    crop = np.asarray(image[v0:v1, u0:u1], dtype=np.float32)
    map_u = np.where(inside, uv[..., 0] - u0, -10.0).astype(np.float32)
    map_v = np.where(inside, uv[..., 1] - v0, -10.0).astype(np.float32)
    values = cv2.remap(crop, map_u, map_v, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    values = np.where(inside, values, np.nan).astype(np.float32)
    return PencilImage(float(s0), k, d, values)


def _band_edges(profile: np.ndarray, half: int, min_step: float):
    """Steps of one mean column profile: (columns, signed step heights)."""
    m = len(profile)
    if m < 2 * half + 3:
        return np.zeros(0, int), np.zeros(0)
    step = np.full(m, np.nan)
    step[half:m - half] = profile[2 * half:] - profile[:m - 2 * half]
    a = np.abs(np.nan_to_num(step))
    peaks = np.nonzero((a[1:-1] >= a[:-2]) & (a[1:-1] > a[2:]) & (a[1:-1] >= min_step))[0] + 1
    return peaks, step[peaks]


def pencil_edges(rect: PencilImage, min_step: float, band_ratio: float = 1.35,
                 max_edges: int = 40) -> PencilEdges:
    """Steps along columns of a rectified image, joined across depth bands."""
    d = rect.d
    # depth bands of geometric widths, at least 6 rows each
    edges_of_bands = []
    lo = d[0]
    bands = []
    while lo < d[-1] - 1e-9:
        hi = min(d[-1], max(lo * band_ratio, lo + 6.0))
        if d[-1] - hi < 0.5 * (hi - lo):
            hi = d[-1]
        bands.append((lo, hi))
        lo = hi
    values = rect.values
    for b_lo, b_hi in bands:
        rows = (d >= b_lo) & (d <= b_hi)
        if rows.sum() < 2:
            edges_of_bands.append((np.zeros(0, int), np.zeros(0)))
            continue
        with np.errstate(invalid="ignore"):
            counts = np.isfinite(values[rows]).sum(axis=0)
            profile = np.where(counts >= 0.5 * rows.sum(), np.nanmean(values[rows], axis=0), np.nan)
        # difference over about +-0.75 px at the band's middle depth
        half = max(1, int(round(0.75 / (rect.k_step * 0.5 * (b_lo + b_hi)))))
        edges_of_bands.append(_band_edges(profile, half, min_step))
    # join: every band's step proposes an edge; its span is the run of bands holding a step
    # of the same sign within a pixel of the same column
    proposals = []
    for b, (cols, steps) in enumerate(edges_of_bands):
        for c, s in zip(cols, steps):
            proposals.append((abs(s), b, int(c), float(np.sign(s))))
    proposals.sort(reverse=True)
    taken = [np.zeros(len(c), bool) for c, _ in edges_of_bands]
    out = []
    for strength, b, c, sign in proposals:
        if taken[b][np.searchsorted(edges_of_bands[b][0], c)]:
            continue
        members = [(b, c, strength)]
        for direction in (-1, 1):
            bb, cc = b + direction, c
            while 0 <= bb < len(bands):
                cols, steps = edges_of_bands[bb]
                tol = max(1, int(round(1.0 / (rect.k_step * 0.5 * sum(bands[bb])))))
                near = np.nonzero((np.abs(cols - cc) <= tol) & (np.sign(steps) == sign) & ~taken[bb])[0]
                if len(near) == 0:
                    break
                j = near[np.argmin(np.abs(cols[near] - cc))]
                members.append((bb, int(cols[j]), abs(float(steps[j]))))
                cc = int(cols[j])
                bb += direction
        for bb, cc, _ in members:
            index = np.searchsorted(edges_of_bands[bb][0], cc)
            if index < len(taken[bb]) and edges_of_bands[bb][0][index] == cc:
                taken[bb][index] = True
        band_ids = [m[0] for m in members]
        weights = np.array([m[2] for m in members])
        column = float(np.average([m[1] for m in members], weights=weights))
        out.append((rect.k[0] + column * rect.k_step, sign, float(weights.mean()),
                    bands[min(band_ids)][0], bands[max(band_ids)][1], len(members) / (max(band_ids) - min(band_ids) + 1)))
        if len(out) >= max_edges:
            break
    if not out:
        z = np.zeros(0)
        return PencilEdges(rect.s0, z, z.astype(int), z, z, z, z)
    a = np.array(out)
    return PencilEdges(rect.s0, a[:, 0], a[:, 1].astype(int), a[:, 2], a[:, 3], a[:, 4], a[:, 5])
