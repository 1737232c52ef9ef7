"""The airport layout's taxiways at an angle (render/scene.py), checked against closed-form
geometry: where each strip meets the runway, its area, and that cutting it out of the ground
leaves no gap, overlap or crack (every piece's vertex on a shared grid line is shared)."""
import math

import numpy as np
import pytest

from visland.render.scene import ObliqueStrip, _cell_owners, _grid_edges, _ground_and_oblique, airport_layout
from visland.runway import Runway


def _area(polygon) -> float:
    x = np.array([v[0] for v in polygon])
    y = np.array([v[1] for v in polygon])
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def test_a_strip_joining_at_45_deg_has_the_closed_form_corners():
    """A 20 m wide strip leaving the right edge (y = 20 m) at x = 150 m at 45 deg, to y = 100 m:
    its mouth on the edge spans 20 / sin 45 = 28.28 m centred on 150 m, its far end is 80 m
    further along x (80 / tan 45), its axis points at 45 deg to the right of +x."""
    strip = ObliqueStrip.joining("s", 150.0, +1, 45.0, 20.0, 100.0, 20.0)
    half = 10.0 / math.sin(math.radians(45.0))
    expected = ((150.0 - half, 20.0), (150.0 + half, 20.0), (230.0 + half, 100.0), (230.0 - half, 100.0))
    np.testing.assert_allclose(np.asarray(strip.corners), np.asarray(expected), atol=1e-12)
    along, across = strip.axis_and_normal()
    np.testing.assert_allclose(along, [math.sqrt(0.5), math.sqrt(0.5)], atol=1e-12)
    assert abs(float(np.dot(along, across))) < 1e-12
    left = ObliqueStrip.joining("s", 150.0, -1, 30.0, 20.0, 100.0, 20.0)
    assert all(y < 0 for _, y in left.corners)
    np.testing.assert_allclose(left.corners[2][0] - left.corners[1][0], 80.0 / math.tan(math.radians(30.0)))


@pytest.mark.parametrize("length, width", [(3000.0, 45.0), (1200.0, 23.0)])
def test_oblique_layout_cuts_the_strips_out_of_the_ground_exactly(length, width):
    """With taxiways="oblique" the ground cells the strips cross are split so that (1) the ground
    pieces, the strips' pieces and the untouched cells cover exactly the ground's area, (2) each
    strip covers width * (its length across) / sin(angle), its closed-form area, (3) each strip
    ends on the runway's edge and on the parallel taxiway's, and (4) every vertex a piece puts on a
    grid line inside the band of a strip is also a vertex of the piece on the other side (no
    T-junction: no crack at any distance)."""
    runway = Runway(length_m=length, width_m=width)
    layout = airport_layout(runway, distractors=True, taxiways="oblique")
    assert len(layout.oblique) == 3
    xs, ys = _grid_edges(layout)
    owner = _cell_owners(layout, xs, ys)
    rows, cols = np.nonzero(owner == -1)
    ground = np.stack([xs[cols], xs[cols + 1], ys[rows], ys[rows + 1]], axis=1)
    kept, ground_pieces, strip_pieces = _ground_and_oblique(ground, layout)
    total = float(np.sum((ground[:, 1] - ground[:, 0]) * (ground[:, 3] - ground[:, 2])))
    kept_area = float(np.sum((kept[:, 1] - kept[:, 0]) * (kept[:, 3] - kept[:, 2])))
    pieces_area = sum(_area(p) for p in ground_pieces) + sum(_area(p) for ps in strip_pieces.values() for p in ps)
    assert kept_area + pieces_area == pytest.approx(total, rel=1e-12)
    for k, strip in enumerate(layout.oblique):
        c = np.asarray(strip.corners)
        assert abs(c[0, 1]) == pytest.approx(width / 2) and abs(c[2, 1]) > 3.0 * width
        mouth = c[1, 0] - c[0, 0]
        span = abs(c[2, 1] - c[0, 1])
        assert sum(_area(p) for p in strip_pieces[k]) == pytest.approx(mouth * span, rel=1e-9)
    # no T-junction: a vertex of one piece lying strictly inside another piece's edge is an error
    pieces = ground_pieces + [p for ps in strip_pieces.values() for p in ps]
    # and the whole cells around the strips: other surfaces' cells and the ground left untouched
    rows, cols = np.nonzero(np.ones_like(owner, dtype=bool))
    every_cell = np.stack([xs[cols], xs[cols + 1], ys[rows], ys[rows + 1]], axis=1)
    was_split = {tuple(cell) for cell in ground} - {tuple(cell) for cell in kept}
    for strip in layout.oblique:
        c = np.asarray(strip.corners)
        near = ((every_cell[:, 0] < c[:, 0].max() + 50) & (every_cell[:, 1] > c[:, 0].min() - 50)
                & (every_cell[:, 2] < c[:, 1].max() + 50) & (every_cell[:, 3] > c[:, 1].min() - 50))
        for x0, x1, y0, y1 in every_cell[near]:
            if (x0, x1, y0, y1) not in was_split:
                pieces.append([(x0, y0), (x1, y0), (x1, y1), (x0, y1)])
    vertices = {v for p in pieces for v in p}
    for piece in pieces:
        for a, b in zip(piece, piece[1:] + piece[:1]):
            for v in vertices:
                if v in (a, b):
                    continue
                cross = (b[0] - a[0]) * (v[1] - a[1]) - (b[1] - a[1]) * (v[0] - a[0])
                if abs(cross) > 1e-9 * max(1.0, math.dist(a, b)):
                    continue
                t = ((v[0] - a[0]) * (b[0] - a[0]) + (v[1] - a[1]) * (b[1] - a[1])) / math.dist(a, b) ** 2
                assert not 1e-9 < t < 1 - 1e-9, f"vertex {v} lies inside the edge {a}-{b} of another piece"
