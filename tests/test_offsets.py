"""Contour-parallel offsets and linking (cnclab.toolpath.offsets)."""
import numpy as np
import pytest
from shapely.geometry import LinearRing, LineString, Point, Polygon, box

from cnclab.toolpath import offsets


def test_rectangle_levels_are_stepover_apart():
    lv = offsets.offset_levels(box(0, 0, 40, 30), tool_radius=5, stepover=3)
    assert [len(x) for x in lv] == [1, 1, 1, 1]            # offsets 5, 8, 11, 14; 17 collapses
    for a, b in zip(lv[:-1], lv[1:]):
        assert LinearRing(a[0]).distance(LinearRing(b[0])) == pytest.approx(3, abs=1e-9)
    first = Polygon(lv[0][0])
    assert first.bounds == pytest.approx((5, 5, 35, 25))


def test_island_orientation_and_clearance():
    pocket = Polygon([(0, 0), (60, 0), (60, 40), (0, 40)], [[(25, 15), (35, 15), (35, 25), (25, 25)]])
    lv = offsets.offset_levels(pocket, 4, 3)
    outer, island = lv[0]
    assert LinearRing(outer).is_ccw and not LinearRing(island).is_ccw   # climb, material on the right
    assert LinearRing(island).distance(pocket.interiors[0]) == pytest.approx(4, abs=1e-3)


def test_offsets_split_in_a_narrow_neck():
    dumbbell = box(0, 0, 30, 30).union(box(30, 12, 50, 18)).union(box(50, 0, 80, 30))
    lv = offsets.offset_levels(dumbbell, 2, 2)
    counts = [len(x) for x in lv]
    assert counts[0] == 1 and max(counts) == 2              # one loop, then two after the neck closes


def test_link_inside_out_and_inside_allowed_region():
    pocket = Polygon([(0, 0), (60, 0), (60, 40), (0, 40)], [[(25, 15), (35, 15), (35, 25), (25, 25)]])
    r = 4
    lv = offsets.offset_levels(pocket, r, 3)
    allowed = offsets.allowed_region(pocket, r)
    passes = offsets.link_loops(lv, allowed)
    innermost = np.vstack(lv[-1])
    assert np.min(np.hypot(*(innermost - passes[0][0]).T)) < 1e-9     # starts on the innermost level
    guard = allowed.buffer(1e-6)
    for p in passes:
        assert guard.contains(LineString(p))
    n_loops = sum(len(x) for x in lv)
    assert sum(len(p) for p in passes) >= sum(len(lp) for x in lv for lp in x)
    assert 1 <= len(passes) <= n_loops


def test_link_never_crosses_an_island():
    pocket = Polygon([(0, 0), (60, 0), (60, 20), (0, 20)], [[(28, 2), (32, 2), (32, 18), (28, 18)]])
    passes = offsets.link_loops(offsets.offset_levels(pocket, 1, 1), offsets.allowed_region(pocket, 1))
    island = Polygon(pocket.interiors[0]).buffer(1 - 1e-6)
    for p in passes:
        assert not LineString(p).intersects(island)


@pytest.mark.parametrize("kw, name", [({"tool_radius": 0, "stepover": 1}, "tool_radius"),
                                       ({"tool_radius": 2, "stepover": 5}, "stepover"),
                                       ({"tool_radius": 2, "stepover": -1}, "stepover")])
def test_bad_input(kw, name):
    with pytest.raises(ValueError, match=name):
        offsets.offset_levels(box(0, 0, 10, 10), **kw)
    with pytest.raises(ValueError, match="pocket"):
        offsets.offset_levels(Point(0, 0).buffer(0), 1, 1)
