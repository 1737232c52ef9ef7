"""Runway markings against the numbers of ICAO Annex 14 (Volume I, 5.2)."""
import numpy as np
import pytest

from visland.render.markings import designator_number, runway_markings
from visland.runway import Runway


def _near_end(layout, kind, x_max=1500.0):
    rects = layout.of_kind(kind)
    return rects[rects[:, 1] <= x_max]


def test_threshold_stripes_of_a_45_m_runway():
    layout = runway_markings(Runway(3000.0, 45.0))
    stripes = _near_end(layout, "threshold")
    assert len(stripes) == 12                                   # 45 m wide: 12 stripes
    np.testing.assert_allclose(stripes[:, 0], 6.0)              # 6 m from the threshold
    np.testing.assert_allclose(stripes[:, 1] - stripes[:, 0], 30.0)
    assert stripes[:, 2].min() == pytest.approx(-22.5 + 3.0) and stripes[:, 3].max() == pytest.approx(22.5 - 3.0)
    widths = stripes[:, 3] - stripes[:, 2]
    assert np.all((widths > 1.4) & (widths < 1.9))              # about 1.8 m
    inner = np.sort(np.abs(stripes[:, 2:4]).min(axis=1))
    assert inner[0] == pytest.approx(widths[0])                  # double space at the centre line


@pytest.mark.parametrize("width, count", [(18.0, 4), (23.0, 6), (30.0, 8), (45.0, 12), (60.0, 16)])
def test_threshold_stripe_count_follows_the_width(width, count):
    layout = runway_markings(Runway(2500.0, width))
    assert len(_near_end(layout, "threshold")) == count


def test_designators_of_both_ends():
    assert runway_markings(Runway(heading_deg=40.0)).designators == ("04", "22")
    assert designator_number(359.0) == 36 and designator_number(4.0) == 36 and designator_number(185.0) == 19


def test_aiming_point_and_touchdown_zone_of_a_3000_m_runway():
    layout = runway_markings(Runway(3000.0, 45.0))
    aim = _near_end(layout, "aiming_point")
    assert len(aim) == 2
    np.testing.assert_allclose(aim[:, 0], 400.0)                # LDA >= 2400 m: begins 400 m in
    tdz_starts = sorted(set(_near_end(layout, "touchdown_zone")[:, 0]))
    # pairs every 150 m, the one within 50 m of the aiming point (450 m) left out
    assert tdz_starts == [150.0, 300.0, 600.0, 750.0, 900.0]
    counts = [int((_near_end(layout, "touchdown_zone")[:, 0] == x).sum()) // 2 for x in tdz_starts]
    assert counts == [3, 3, 2, 1, 1]


def test_shorter_runway_moves_the_aiming_point_and_has_fewer_pairs():
    layout = runway_markings(Runway(1800.0, 30.0))
    assert layout.aiming_point_start_m == 300.0
    starts = sorted(set(_near_end(layout, "touchdown_zone", 900.0)[:, 0]))
    assert starts == [150.0, 450.0, 600.0]                      # 4 pairs, 300 m dropped next to the aiming point


def test_centre_line_side_stripes_and_everything_on_the_runway():
    runway = Runway(3000.0, 45.0)
    layout = runway_markings(runway)
    centre = layout.of_kind("centre_line")
    np.testing.assert_allclose(centre[:, 1] - centre[:, 0], 30.0)
    np.testing.assert_allclose(np.diff(centre[:, 0]), 50.0)     # 30 m stripes, 20 m gaps
    np.testing.assert_allclose(centre[:, 3] - centre[:, 2], 0.9)
    # both ends symmetric: the pattern is centred on the runway's middle
    assert centre[0, 0] == pytest.approx(runway.length_m - centre[-1, 1])
    side = layout.of_kind("side_stripe")
    assert len(side) == 2 and np.allclose(side[:, 0], 0.0) and np.allclose(side[:, 1], 3000.0)
    r = layout.rectangles_m
    assert r[:, 0].min() >= 0.0 and r[:, 1].max() <= 3000.0 and r[:, 2].min() >= -22.5 and r[:, 3].max() <= 22.5
