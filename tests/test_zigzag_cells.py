"""The zig-zag's cell order and its links along the wall (zigzag.cell_order, zigzag.raster_link):
properties on random inputs."""
import numpy as np
import shapely
from hypothesis import given, settings, strategies as st
from shapely.geometry import Point, box

from cnclab.toolpath.zigzag import cell_order, raster_lines, raster_link


@settings(max_examples=60, deadline=None)
@given(st.integers(5, 40), st.floats(0.0, 1.0), st.floats(0.0, 1.0))
def test_the_link_along_a_ring_is_its_shorter_way(n, u, v):
    """Two points on the outer ring of an annulus (n-gons of radius 10 and 9), at arc lengths u L and
    v L (through the ring's start or not): where the chord leaves the annulus, the link starts at one,
    ends at the other, stays on the ring and is as long as the shorter way round it."""
    A = Point(0, 0).buffer(10.0, n).difference(Point(0, 0).buffer(9.0, n))
    ring = shapely.get_exterior_ring(A)
    L = ring.length
    a, b = ring.interpolate(u * L), ring.interpolate(v * L)
    fwd = (v - u) % 1.0 * L
    P = raster_link((a.x, a.y), (b.x, b.y), A, L)
    assert P is not None and np.allclose(P[0], [a.x, a.y]) and np.allclose(P[-1], [b.x, b.y])
    if len(P) == 2 and shapely.LineString(P).within(A.buffer(1e-6)):
        return                                   # the chord stays inside: no need to go round
    assert np.all(shapely.distance(ring, shapely.points(P)) < 1e-6)
    assert abs(np.hypot(*np.diff(P, axis=0).T).sum() - min(fwd, L - fwd)) < 1e-6
    assert raster_link((a.x, a.y), (b.x, b.y), A, 0.5 * min(fwd, L - fwd)) is None     # too long: a jump


@settings(max_examples=40, deadline=None)
@given(st.floats(20, 60), st.floats(15, 40), st.floats(0.3, 0.7), st.floats(0.2, 0.6), st.floats(0.8, 3.0))
def test_cell_order_cuts_every_piece_once(w, h, fx, fy, step):
    """A box with a box island at a random place: every raster piece is cut exactly once (as drawn
    or reversed), and the first stays first."""
    R = box(0, 0, w, h).difference(box(fx * w - 4, fy * h - 3, fx * w + 4, fy * h + 3))
    pieces = raster_lines(R, step)
    out, links = cell_order(pieces, R, 3 * step)
    assert len(out) == len(pieces) and np.array_equal(out[0], pieces[0])
    # each link runs from the end of the piece before to the start of its piece (None: the first, a jump)
    assert len(links) == len(out) and links[0] is None
    assert all(np.allclose(L[0], a[-1]) and np.allclose(L[-1], b[0]) for a, b, L in zip(out, out[1:], links[1:])
               if L is not None)
    key = lambda q: tuple(np.round(np.sort(q, axis=0).ravel(), 9))     # noqa: E731
    assert sorted(map(key, out)) == sorted(map(key, pieces))
