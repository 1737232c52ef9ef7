"""Runway markings as ICAO Annex 14 (Volume I, 5.2) paints them, as rectangles in the runway frame.

A pure description: :func:`runway_markings` returns white rectangles ``(x0, x1, y0, y1)`` in
metres in the runway frame R (x from the threshold along the landing direction, y to the
right), for both runway ends (the far end carries the reciprocal designator, read by an
aircraft landing the other way). :mod:`visland.render.textures` paints them into textures.

What is drawn (Annex 14 5.2.2 to 5.2.6, precision approach runway, values for the runway's
width and length):

- threshold: longitudinal stripes 30 m long starting 6 m from the threshold, 4/6/8/12/16
  stripes for runways 18/23/30/45/60 m wide, spread to within 3 m of the edges with a double
  space at the centre line;
- designator: the runway number (heading / 10, two digits) 9 m tall, 12 m beyond the
  threshold stripes, in block figures;
- centre line: 30 m stripes with 20 m gaps, 0.9 m wide, between the designators;
- aiming point: two stripes beginning 400 m (150/250/300 m on shorter runways) from the
  threshold, 60 m long, inner edges 0.4 W apart;
- touchdown zone, pattern A: pairs every 150 m of 3, 3, 2, 2, 1, 1 stripes (22.5 m x 1.8 m,
  1.5 m apart), fewer pairs on shorter runways, none within 50 m of the aiming point;
- side stripes: 0.9 m along both edges (0.45 m under 30 m width).

Other marking sets (``style``, :data:`visland.render.params.MARKINGS`): ``faa`` (threshold
stripes 45.7 m long, 1.75 m wide and 1.75 m apart from the centre outwards, so they do not
reach the edges; aiming point 311 m, 45.7 m long), ``none`` (bare pavement), ``displaced``
(ICAO plus a 1.8 m transverse bar at the threshold and white arrows on the pavement before it),
``blast_pad`` (ICAO plus yellow chevrons on the pad before it); ``worn`` is ICAO (the tile
painter wears it). ``threshold_stripes`` overrides the count by width; ``side_stripes`` off
drops them. Arrows and chevrons are polygons (``polygons``), painted at x < 0 only.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from visland.runway import Runway

__all__ = ["MarkingLayout", "runway_markings", "designator_number", "DIGIT_CELLS"]

#: Block figures on a 3 x 5 grid, rows from the top of the figure as read by the pilot.
DIGIT_CELLS = {
    "0": ("111", "101", "101", "101", "111"),
    "1": ("010", "110", "010", "010", "111"),
    "2": ("111", "001", "111", "100", "111"),
    "3": ("111", "001", "011", "001", "111"),
    "4": ("101", "101", "111", "001", "001"),
    "5": ("111", "100", "111", "001", "111"),
    "6": ("111", "100", "111", "101", "111"),
    "7": ("111", "001", "001", "010", "010"),
    "8": ("111", "101", "111", "101", "111"),
    "9": ("111", "101", "111", "001", "111"),
}

THRESHOLD_SETBACK_M = 6.0
THRESHOLD_STRIPE_LENGTH_M = 30.0
DESIGNATOR_GAP_M = 12.0
DIGIT_HEIGHT_M = 9.0
DIGIT_WIDTH_M = 3.0
CENTRELINE_STRIPE_M = 30.0
CENTRELINE_GAP_M = 20.0
TDZ_STRIPE_LENGTH_M = 22.5
TDZ_STRIPE_WIDTH_M = 1.8
TDZ_STRIPE_SPACING_M = 1.5


@dataclass(frozen=True)
class MarkingLayout:
    """White rectangles as ``x0, x1, y0, y1`` in metres (runway frame R) and what they are.

    Attributes
    ----------
    rectangles_m : ndarray, shape (n, 4)
        ``x0, x1, y0, y1`` of each painted rectangle, metres in R.
    kinds : tuple of str
        What each rectangle is (threshold stripe, designator, centre line, ...).
    designators : tuple of str
        ``(near, far)`` runway numbers as painted, e.g. ``("04", "22")``.
    aiming_point_start_m : float
        Where the aiming point marking starts past the threshold, metres.
    touchdown_zone_end_m : float
        Where the touchdown zone markings end, metres.
    polygons : tuple
        Painted polygons ``(colour, (n, 2) array of x, y)``: displaced-threshold arrows (white),
        blast pad chevrons (yellow); all at x < 0, before the threshold.
    pre_threshold_m : float, default 0
        Length of the pavement before the threshold (displaced threshold or blast pad), metres.
    """

    rectangles_m: np.ndarray
    kinds: tuple
    designators: tuple  # (near, far) as painted, e.g. ("04", "22")
    aiming_point_start_m: float
    touchdown_zone_end_m: float
    #: Painted polygons ``(colour, (n, 2) array of x, y)``: displaced-threshold arrows (white),
    #: blast pad chevrons (yellow); all at x < 0, before the threshold.
    polygons: tuple = ()
    #: Length of the pavement before the threshold (displaced threshold or blast pad), metres; 0: none.
    pre_threshold_m: float = 0.0

    def of_kind(self, kind: str) -> np.ndarray:
        mask = np.array([k == kind for k in self.kinds])
        return self.rectangles_m[mask] if mask.any() else np.zeros((0, 4))


def designator_number(heading_deg: float) -> int:
    """Runway number from its heading: heading / 10 rounded, 36 instead of 0.

    Parameters
    ----------
    heading_deg : float
        Landing direction, degrees from north.

    Returns
    -------
    int
        1 to 36.
    """
    number = int(math.floor(heading_deg / 10.0 + 0.5)) % 36
    return 36 if number == 0 else number


def _threshold_stripe_count(width_m: float) -> int:
    for limit, count in ((20.0, 4), (26.0, 6), (37.0, 8), (52.0, 12)):
        if width_m < limit:
            return count
    return 16


def _aiming_point_start(length_m: float) -> float:
    if length_m < 800.0:
        return 150.0
    if length_m < 1200.0:
        return 250.0
    if length_m < 2400.0:
        return 300.0
    return 400.0


def _tdz_pairs(length_m: float) -> int:
    for limit, pairs in ((900.0, 1), (1200.0, 2), (1500.0, 3), (2400.0, 4)):
        if length_m < limit:
            return pairs
    return 6


def _one_end(runway: Runway, number: int, style: str = "icao", n_stripes: int = 0) -> list:
    """Rectangles of one runway end in that end's own frame (x from its threshold, y to its right)."""
    W = runway.width_m
    L = runway.length_m
    out = []
    # threshold stripes
    n = n_stripes or _threshold_stripe_count(W)
    x0 = THRESHOLD_SETBACK_M
    if style == "faa":
        unit = min(1.75, (W - 6.0) / (2 * n))   # FAA: 5.75 ft stripes and spaces, double space at the centre
        x1 = x0 + 45.7
    else:
        span = min(W - 6.0, 54.0)
        unit = span / (2 * n)        # n stripes and n space units (the central space is double)
        x1 = x0 + THRESHOLD_STRIPE_LENGTH_M
    for k in range(n // 2):
        y_in = unit * (1 + 2 * k)    # inner edge of the k-th stripe from the centre
        out.append(("threshold", x0, x1, y_in, y_in + unit))
        out.append(("threshold", x0, x1, -y_in - unit, -y_in))
    # designator, read from the approach: the figure's top is further along x
    text = f"{number:02d}"
    cell_w = DIGIT_WIDTH_M / 3.0
    cell_h = DIGIT_HEIGHT_M / 5.0
    gap = 3.0
    total = len(text) * DIGIT_WIDTH_M + (len(text) - 1) * gap
    x_base = x1 + DESIGNATOR_GAP_M
    for i, char in enumerate(text):
        y_left = -total / 2.0 + i * (DIGIT_WIDTH_M + gap)
        for row, bits in enumerate(DIGIT_CELLS[char]):
            x_top = x_base + DIGIT_HEIGHT_M - row * cell_h
            for col, bit in enumerate(bits):
                if bit == "1":
                    out.append(("designator", x_top - cell_h, x_top, y_left + col * cell_w,
                                y_left + (col + 1) * cell_w))
    designator_end = x_base + DIGIT_HEIGHT_M
    # aiming point
    aim0 = _aiming_point_start(L) if style != "faa" else 311.0
    aim_len = (60.0 if L >= 2400.0 else 45.0) if style != "faa" else 45.7
    aim_w = min(10.0, 0.2 * W)
    aim_in = 0.2 * W
    out.append(("aiming_point", aim0, aim0 + aim_len, aim_in, aim_in + aim_w))
    out.append(("aiming_point", aim0, aim0 + aim_len, -aim_in - aim_w, -aim_in))
    # touchdown zone, pattern A
    counts = (3, 3, 2, 2, 1, 1)[: _tdz_pairs(L)]
    tdz_end = 0.0
    for k, count in enumerate(counts):
        x_start = 150.0 * (k + 1)
        if x_start + TDZ_STRIPE_LENGTH_M > L / 2.0:
            break
        if x_start < aim0 + aim_len + 50.0 and x_start + TDZ_STRIPE_LENGTH_M > aim0 - 50.0:
            continue
        for j in range(count):
            y_in = aim_in + j * (TDZ_STRIPE_WIDTH_M + TDZ_STRIPE_SPACING_M)
            out.append(("touchdown_zone", x_start, x_start + TDZ_STRIPE_LENGTH_M, y_in, y_in + TDZ_STRIPE_WIDTH_M))
            out.append(("touchdown_zone", x_start, x_start + TDZ_STRIPE_LENGTH_M, -y_in - TDZ_STRIPE_WIDTH_M, -y_in))
        tdz_end = x_start + TDZ_STRIPE_LENGTH_M
    return out, designator_end, aim0, tdz_end


def _arrow(x_tip: float, y: float, length: float, shaft_w: float, head_w: float, head_len: float) -> np.ndarray:
    """An arrow pointing +x with its tip at ``(x_tip, y)`` as one polygon (x, y)."""
    xs = x_tip - head_len
    xt = x_tip - length
    return np.array([(x_tip, y), (xs, y + head_w / 2), (xs, y + shaft_w / 2), (xt, y + shaft_w / 2),
                     (xt, y - shaft_w / 2), (xs, y - shaft_w / 2), (xs, y - head_w / 2)])


def _pre_threshold_polygons(style: str, W: float, length: float) -> list:
    """Arrows (displaced threshold) or chevrons (blast pad) on ``[-length, 0] x [-W/2, W/2]``."""
    polys = []
    if style == "displaced":
        # arrows along the centre line every 30 m, and a row of arrow heads across the width 6 m
        # before the threshold bar (Annex 14 figure 5-4, option B)
        x_tip = -10.0
        while x_tip - 20.0 > -length + 5.0:
            polys.append(("paint_white", _arrow(x_tip, 0.0, 20.0, 0.9, 3.0, 6.0)))
            x_tip -= 30.0
        n_heads = max(2, int((W - 6.0) // 9.0))
        for y in np.linspace(-(W / 2 - 4.5), W / 2 - 4.5, n_heads):
            if abs(y) > 3.0:
                polys.append(("paint_white", np.array([(-6.0, y), (-10.5, y + 1.5), (-10.5, y - 1.5)])))
    elif style == "blast_pad":
        # yellow chevrons 0.9 m wide every 30 m, apex on the centre line pointing at the threshold
        half = W / 2.0
        x_apex = -10.0
        while x_apex - half - 1.27 > -length:
            for side in (1.0, -1.0):
                polys.append(("paint_yellow", np.array([
                    (x_apex, 0.0), (x_apex - half, side * half), (x_apex - half - 1.27, side * half),
                    (x_apex - 1.27, 0.0)])))
            x_apex -= 30.0
    return polys


def runway_markings(runway: Runway, style: str = "icao", threshold_stripes: int = 0, side_stripes: bool = True,
                    pre_threshold_m: float = 150.0) -> MarkingLayout:
    """All markings of ``runway`` (both ends, centre line, side stripes) in the runway frame R.

    Parameters
    ----------
    runway : visland.runway.Runway
        Its size (and heading, for the designators).
    style : str, default "icao"
        A marking set (module docstring).
    threshold_stripes : int, default 0
        Number of threshold stripes; 0 takes Annex 14's count for the width.
    side_stripes : bool, default True
        Paint the runway side stripes.
    pre_threshold_m : float, default 150
        Length of the displaced-threshold pavement or of the blast pad, metres (styles
        ``displaced`` and ``blast_pad`` only).

    Returns
    -------
    MarkingLayout
    """
    L, W = runway.length_m, runway.width_m
    near_number = designator_number(runway.heading_deg)
    far_number = designator_number((runway.heading_deg + 180.0) % 360.0)
    if style == "none":
        return MarkingLayout(np.zeros((0, 4)), (), (f"{near_number:02d}", f"{far_number:02d}"),
                             _aiming_point_start(L), 0.0)
    paint_style = "faa" if style == "faa" else "icao"
    near, designator_end, aim0, tdz_end = _one_end(runway, near_number, paint_style, threshold_stripes)
    far, _, _, _ = _one_end(runway, far_number, paint_style, threshold_stripes)
    rects = [(k, x0, x1, y0, y1) for k, x0, x1, y0, y1 in near]
    # the far end's frame is R turned by 180 deg about z: x' = L - x, y' = -y
    rects += [(k, L - x1, L - x0, -y1, -y0) for k, x0, x1, y0, y1 in far]
    # centre line between the designators, stripes centred on the runway's middle
    c0 = designator_end + CENTRELINE_GAP_M
    c1 = L - c0
    period = CENTRELINE_STRIPE_M + CENTRELINE_GAP_M
    n_stripes = int(math.floor((c1 - c0 + CENTRELINE_GAP_M) / period))
    half_w = 0.45 if W >= 30.0 else 0.225
    if n_stripes > 0:
        start = 0.5 * (c0 + c1) - 0.5 * (n_stripes * period - CENTRELINE_GAP_M)
        for k in range(n_stripes):
            x0 = start + k * period
            rects.append(("centre_line", x0, x0 + CENTRELINE_STRIPE_M, -half_w, half_w))
    if side_stripes:
        side_w = 0.9 if W >= 30.0 else 0.45
        rects.append(("side_stripe", 0.0, L, -W / 2.0, -W / 2.0 + side_w))
        rects.append(("side_stripe", 0.0, L, W / 2.0 - side_w, W / 2.0))
    polygons = ()
    pre = 0.0
    if style in ("displaced", "blast_pad"):
        pre = float(pre_threshold_m)
        polygons = tuple(_pre_threshold_polygons(style, W, pre))
        if style == "displaced":
            rects.append(("threshold_bar", 0.0, 1.8, -W / 2.0, W / 2.0))
    kinds = tuple(r[0] for r in rects)
    array = np.array([r[1:] for r in rects], dtype=float)
    return MarkingLayout(array, kinds, (f"{near_number:02d}", f"{far_number:02d}"), aim0, tdz_end, polygons, pre)
