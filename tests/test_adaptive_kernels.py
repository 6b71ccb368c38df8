"""Exactness tests of the compiled pieces behind the planner's speed (cnclab.toolpath.adaptive):
each fast kernel against the plain computation it replaces, on random inputs.

Tolerances: distances are exact up to floating-point rounding of one square root (1e-12 mm); masks and
stocks must be equal pixel for pixel (the raster may differ from a point-in-polygon test only for pixel
centres within 1e-9 mm of an edge, where "inside" is a matter of rounding)."""
import math
import types

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy import ndimage
from shapely.geometry import Point, Polygon, box

from cnclab.toolpath.adaptive.control import engagement2
from cnclab.toolpath.adaptive.grid import Grid
from cnclab.toolpath.adaptive.links import blocked_spans, bow_runs, chord_free, rapid_legs, rapid_pieces, shortcut
from cnclab.toolpath.adaptive.stock import (capsule_free, capsule_free_of, cut_disc, cut_disc_both, cut_path, dist_window,
                                            material_fraction, label8, max_filter, raster)

_SET = dict(max_examples=60, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))


@settings(**_SET)
@given(st.integers(1, 40), st.integers(1, 40), st.sampled_from([0.0, 0.01, 0.1, 0.5]),
       st.sampled_from([0.5, 3.0, 1e6]), st.integers(0, 2 ** 31 - 1))
def test_distance_window_equals_scipy_edt(ny, nx, p, cap, seed):
    rng = np.random.default_rng(seed)
    mat = rng.random((ny, nx)) < p
    hc = 0.2
    D = np.full((ny, nx), -1.0)
    dist_window(mat, 0, ny, 0, nx, 0, ny, 0, nx, hc, cap, D)
    ref = np.minimum(ndimage.distance_transform_edt(~mat) * hc, cap) if mat.any() else np.full((ny, nx), cap)
    np.testing.assert_allclose(D, ref, rtol=0, atol=1e-12)
    # a sub-window is filled with the same values and nothing else is touched
    j0, i0 = int(rng.integers(0, ny)), int(rng.integers(0, nx))
    j1, i1 = int(rng.integers(j0 + 1, ny + 1)), int(rng.integers(i0 + 1, nx + 1))
    D2 = np.full((ny, nx), -1.0)
    dist_window(mat, 0, ny, 0, nx, j0, j1, i0, i1, hc, cap, D2)
    np.testing.assert_allclose(D2[j0:j1, i0:i1], ref[j0:j1, i0:i1], rtol=0, atol=1e-12)
    D2[j0:j1, i0:i1] = -1.0
    assert (D2 == -1.0).all()


@st.composite
def polygons(draw):
    n = draw(st.integers(3, 9))
    ang = np.sort(draw(st.lists(st.floats(0, 2 * math.pi), min_size=n, max_size=n, unique=True)))
    rad = draw(st.lists(st.floats(1.0, 6.0), min_size=n, max_size=n))
    poly = Polygon(np.c_[np.cos(ang) * rad, np.sin(ang) * rad]).buffer(0)
    if draw(st.booleans()) and poly.area > 4:
        hole = poly.buffer(-0.8)
        if not hole.is_empty:
            poly = poly.difference(shapely.get_parts(hole)[0].buffer(-0.3))
    return poly


@settings(**_SET)
@given(polygons(), st.sampled_from([0.05, 0.0833, 0.2]))
def test_raster_equals_point_in_polygon(poly, h):
    if poly.is_empty:
        return
    x0, y0, x1, y1 = poly.bounds
    x0, y0 = x0 - 2 * h, y0 - 2 * h
    nx, ny = int(math.ceil((x1 - x0) / h)) + 2, int(math.ceil((y1 - y0) / h)) + 2
    X, Y = np.meshgrid(x0 + (np.arange(nx) + 0.5) * h, y0 + (np.arange(ny) + 0.5) * h)
    ref = shapely.contains_xy(poly, X, Y)
    got = raster(poly, x0, y0, h, nx, ny).astype(bool)
    diff = got != ref
    if diff.any():
        d = shapely.distance(poly.boundary, shapely.points(X[diff], Y[diff]))
        assert d.max() < 1e-9, d.max()


@settings(**_SET)
@given(st.integers(0, 2 ** 31 - 1), st.sampled_from([1.5, 3.0, 5.0]), st.sampled_from([0.05, 0.1, 1.0]))
def test_cut_skipping_the_previous_disc_is_exact(seed, r, step):
    """Cutting a path disc by disc, each scan skipping the previous disc's span, clears exactly the
    pixels (and reports exactly the area) that full scans clear."""
    rng = np.random.default_rng(seed)
    h = 0.05
    M1 = (rng.random((300, 300)) < 0.9).astype(np.uint8)
    M2 = M1.copy()
    P = np.cumsum(rng.normal(0, step, (40, 2)), axis=0) + 7.5
    a1 = sum(cut_disc(M1, 0.0, 0.0, h, x, y, r, np.nan, np.nan) for x, y in P)
    a2 = cut_path(M2, 0.0, 0.0, h, P, r)
    assert np.array_equal(M1, M2) and a1 == a2


@settings(**dict(_SET, max_examples=25))
@given(st.integers(0, 2 ** 31 - 1))
def test_rapid_stock_chords_are_truly_swept(seed):
    """A chord the rapid stock accepts (no material pixel within r + h/sqrt(2) of it, the discs cut with
    r - h/sqrt(2)) has its whole tool disc inside the exact union of the cut discs (or outside the
    pocket): a G0 along it removes nothing, whatever the pixel alignment. Exact geometry by shapely
    with 256 segments per circle (chord error r (1 - cos(pi/256)) = 7.5e-5 r, allowed as area)."""
    rng = np.random.default_rng(seed)
    r, h = 3.0, 0.05
    pocket = box(0, 0, 20, 20)
    g = Grid(pocket, pocket.buffer(-r), r, h, None)
    # a random zig-zag of passes leaving cusps between them
    P = np.vstack([np.c_[np.linspace(3, 17, 60), np.full(60, y) + rng.normal(0, 0.05, 60)]
                   for y in np.arange(3, 17.5, rng.uniform(2.0, 3.5))])
    g.cut_path(np.ascontiguousarray(P))
    swept = shapely.union_all(shapely.buffer(shapely.points(P), r, quad_segs=64))
    tol = 2 * math.pi * r * r * (1 - math.cos(math.pi / 256)) * 4
    checked = 0
    for _ in range(40):
        a, b = rng.uniform(3, 17, 2), rng.uniform(3, 17, 2)
        if capsule_free(g.Mr, g.x0, g.y0, h, a[0], a[1], b[0], b[1], g.r_capsule):
            cap = shapely.LineString([a, b]).buffer(r, quad_segs=64).intersection(pocket)
            assert cap.difference(swept).area <= tol, cap.difference(swept).area
            checked += 1
    # not vacuous: a chord along a middle pass, well inside the swept band (passes closer than 2 r), passes
    ys = np.unique(np.round(P[::60, 1]))
    y = float(np.median(P[:, 1]))
    assert capsule_free(g.Mr, g.x0, g.y0, h, 6.0, y, 14.0, y, g.r_capsule) or len(ys) < 3


@settings(**_SET)
@given(st.floats(0.0, 0.02), st.floats(0.0, 0.3), st.sampled_from([0.03, 0.05]))
def test_air_run_along_a_wall_moved_off_it_is_truly_swept(gap, wobble, h):
    """An air run along the line of the wall-following pass that left the wall skin is never proven
    there (the skin is tangent to its discs); :func:`bow_runs` moves it 2 h to its left and marks its
    inner steps G0 only when that is proven, and :func:`rapid_legs` proves a link leaving the wall
    after a feed leg. Every accepted G0 has its tool disc inside the exact swept area or outside the
    pocket (shapely, 256 segments a circle; tolerance as in the test above)."""
    r = 3.0
    pocket = box(0, 0, 20, 20)
    g = Grid(pocket, pocket.buffer(-r), r, h, None)
    y0 = r + h / math.sqrt(2.0) + 1e-3 + gap          # the wall-following pass, just inside the mask
    xs = np.arange(3.5, 16.5, 0.1)
    passes = [np.c_[xs, np.full(len(xs), y0)], np.c_[xs, np.full(len(xs), y0 + 1.5 + wobble)],
              np.c_[xs, np.full(len(xs), y0 + 3.0)]]
    for P in passes:
        g.cut_path(np.ascontiguousarray(P))
    swept = shapely.union_all(shapely.buffer(shapely.points(np.vstack(passes)), r, quad_segs=64))
    tol = 2 * math.pi * r * r * (1 - math.cos(math.pi / 256)) * 4

    def truly_swept(a, b):
        cap = shapely.LineString([a, b]).buffer(r, quad_segs=64).intersection(pocket)
        return cap.difference(swept).area <= tol

    run = np.ascontiguousarray(np.c_[np.arange(6.0, 12.0, 0.1), np.full(60, y0)])
    assert not capsule_free(g.Mr, g.x0, g.y0, h, 6.0, y0, 11.9, y0, g.r_capsule)   # on the line: never
    E, F = np.zeros(len(run)), np.zeros(len(run), np.bool_)
    P = run.copy()
    bow_runs(g.Mr, g.A, (g.x0, g.y0, h), P, E, F, 1, len(P), 1e-3, g.r_capsule, 2 * h, 4)
    assert F[2:-1].all() and not F[1] and not F[-1]          # not vacuous: the inner steps are G0
    np.testing.assert_array_equal(P[[0, -1]], run[[0, -1]])
    np.testing.assert_allclose(P[1:-1, 1], y0 + 2 * h)       # moved left of the heading (+x): +y
    for k in np.flatnonzero(F):
        assert truly_swept(P[k - 1], P[k])
    legs = rapid_legs(g, (9.0, y0), (9.0, y0 + 2.5))         # a link leaving the wall
    assert legs is not None and legs[0] is not None
    assert truly_swept(legs[0], legs[1])


def test_incremental_free_field_equals_full_recompute():
    """After any sequence of cuts and a restore, the windowed update of the coarse distance field equals
    the distance transform of the whole coarse stock (capped)."""
    rng = np.random.default_rng(3)
    r, h = 3.0, 0.05
    pocket = box(0, 0, 30, 20).difference(Point(15, 10).buffer(2))
    g = Grid(pocket, pocket.buffer(-r), r, h, None)
    g.free_field()
    snap = g.snapshot()
    for k in range(12):
        P = np.cumsum(rng.normal(0, 0.1, (50, 2)), axis=0) + rng.uniform([4, 4], [26, 16])
        g.cut_path(np.ascontiguousarray(P))
        if k == 6:
            g.restore(snap)
        D, _ = g.free_field()
        mat = g.coarse(g.M).max(axis=(1, 3)) > 0
        ref = np.minimum(ndimage.distance_transform_edt(~mat) * g.hc, g.cap)
        np.testing.assert_allclose(D, ref, rtol=0, atol=1e-12)


def test_shortcut_keeps_only_free_chords():
    """Hand case: an L-shaped free corridor of coarse cells; the shortcut of the cell route keeps the
    corner (the straight chord from start to end would cross blocked cells) and every kept chord is
    free."""
    D = np.zeros((20, 20))
    Ac = np.zeros((20, 20), bool)
    Ac[2:5, 2:18] = True      # along x
    Ac[2:18, 15:18] = True    # then up
    D[Ac] = 10.0
    hc = 1.0
    route = [(3, i) for i in range(3, 17)] + [(j, 16) for j in range(4, 17)]
    pts = np.array([(i + 0.5, j + 0.5) for j, i in route])
    A = np.ones((80, 80), np.uint8)         # the fine mask (h = 0.25 mm): all inside
    keep = shortcut(pts, D, Ac, 5.0, -1, -1, 0.0, 0.0, hc, A, 0.25)
    assert keep[0] == 0 and keep[-1] == len(pts) - 1 and len(keep) == 3
    for a, b in zip(keep[:-1], keep[1:]):
        assert chord_free(D, Ac, 5.0, -1, -1, 0.0, 0.0, hc, *pts[a], *pts[b])
    assert not chord_free(D, Ac, 5.0, -1, -1, 0.0, 0.0, hc, *pts[0], *pts[-1])
    # the fine mask is honoured too: a wall pixel on the first leg's chord (x 8 mm, y 3.5 mm) splits it;
    # every chord the shortcut chose (over more than one route step) stays inside the mask
    A[14, 32] = 0
    keep2 = shortcut(pts, D, Ac, 5.0, -1, -1, 0.0, 0.0, hc, A, 0.25)
    assert len(keep2) > len(keep)
    from cnclab.toolpath.adaptive.stock import segment_inside
    for a, b in zip(keep2[:-1], keep2[1:]):
        assert b == a + 1 or segment_inside(A, 0.0, 0.0, 0.25, *pts[a], *pts[b], 0.0)


def _eng2_reference(M, x0, y0, h, cx, cy, r, psi, n, level, level2):
    """Plain twin of engagement2: every sample through the bounds-checked material_fraction."""
    tot = tot2 = 0.0
    da = math.pi / n
    fa = ga = 0.0
    for k in range(n + 1):
        a = psi - 0.5 * math.pi + k * da
        f = material_fraction(M, x0, y0, h, cx + r * math.cos(a), cy + r * math.sin(a))
        fb, gb = f - level, f - level2
        if k > 0:
            for (p, q), acc in (((fa, fb), 0), ((ga, gb), 1)):
                add = da if (p >= 0 and q >= 0) else da * p / (p - q) if p >= 0 else da * q / (q - p) if q >= 0 else 0.0
                if acc == 0:
                    tot += add
                else:
                    tot2 += add
        fa, ga = fb, gb
    return tot, tot2


@settings(**_SET)
@given(st.integers(0, 2 ** 31 - 1), st.floats(-0.5, 12.5), st.floats(-0.5, 8.5), st.floats(-4, 4))
def test_engagement_fast_stencil_equals_checked_lookup(seed, cx, cy, psi):
    """The engagement read with the unchecked bilinear stencil (arc inside the grid) equals the one read
    sample by sample through the bounds-checked lookup, to 1e-9 rad (the two differ only in dividing by
    h or multiplying by 1/h: rounding); arcs leaving the grid take the checked path."""
    rng = np.random.default_rng(seed)
    M = (rng.random((170, 250)) < 0.5).astype(np.uint8)
    got = engagement2(M, 0.0, 0.0, 0.05, cx, cy, 1.5, psi, 90, 0.5, 0.1)
    ref = _eng2_reference(M, 0.0, 0.0, 0.05, cx, cy, 1.5, psi, 90, 0.5, 0.1)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9)


@settings(**_SET)
@given(st.integers(1, 30), st.integers(1, 30), st.integers(0, 6), st.integers(0, 2 ** 31 - 1))
def test_max_filter_equals_scipy(ny, nx, c, seed):
    a = np.random.default_rng(seed).random((ny, nx))
    np.testing.assert_array_equal(max_filter(a, c), ndimage.maximum_filter(a, size=2 * c + 1))


@settings(**_SET)
@given(st.integers(0, 2 ** 31 - 1), st.sampled_from([1.5, 3.0, 5.0]), st.sampled_from([0.05, 0.3, 2.0]))
def test_cut_both_equals_two_full_cuts(seed, r, step):
    """Cutting a path into the planning and the rapid stock together, each row skipping the previous
    disc's spans, clears exactly what full scans of each disc clear, and reports the same area."""
    rng = np.random.default_rng(seed)
    h, rr = 0.05, r - 0.05 / math.sqrt(2.0)
    M1 = (rng.random((300, 300)) < 0.9).astype(np.uint8)
    R1 = M1.copy()
    M2, R2 = M1.copy(), M1.copy()
    P = np.cumsum(rng.normal(0, step, (40, 2)), axis=0) + 7.5
    a1 = sum(cut_disc(M1, 0.0, 0.0, h, x, y, r, np.nan, np.nan) for x, y in P)
    for x, y in P:
        cut_disc(R1, 0.0, 0.0, h, x, y, rr, np.nan, np.nan)
    span, rows = np.empty((300, 4), np.int64), np.array([1, 0], np.int64)
    a2 = sum(cut_disc_both(M2, R2, 0.0, 0.0, h, x, y, r, rr, span, rows) for x, y in P)
    assert np.array_equal(M1, M2) and np.array_equal(R1, R2) and a1 == a2


@settings(**_SET)
@given(st.integers(1, 40), st.integers(1, 40), st.sampled_from([0.2, 0.4, 0.6]), st.integers(0, 2 ** 31 - 1))
def test_label8_equals_scipy(ny, nx, p, seed):
    M = (np.random.default_rng(seed).random((ny, nx)) < p).astype(np.uint8)
    got, n = label8(M)
    ref, m = ndimage.label(M, structure=np.ones((3, 3)))
    assert n == m and np.array_equal(got, ref)     # both number components in row order of their first pixel


@settings(**_SET)
@given(st.integers(0, 2 ** 31 - 1), st.sampled_from([0.0, 0.002, 0.02]), st.sampled_from([0.5, 2.0]))
def test_rapid_pieces_split_a_chord_into_proven_g0s_and_feed(seed, p, min_len):
    """A link chord split by :func:`rapid_pieces`: the pieces run end to end from p to q along the
    chord; every G0 piece is at least ``min_len`` long and :func:`capsule_free` on the rapid stock;
    every stretch of at least ``min_len`` + 2 h between the material's blocked spans has a G0 in it
    (nothing provable is left at feed); no pieces when no stretch is long enough. ``blocked_spans``
    agrees with :func:`capsule_free` on random sub-chords."""
    rng = np.random.default_rng(seed)
    g = types.SimpleNamespace(Mr=rng.random((80, 120)) < p, x0=0.0, y0=0.0, h=0.1, r_capsule=1.07)
    P, Q = rng.uniform([1, 1], [11, 7], 2), rng.uniform([1, 1], [11, 7], 2)
    L = math.hypot(*(Q - P))
    at = lambda u: P + u * (Q - P)        # noqa: E731
    S = blocked_spans(g.Mr, 0.0, 0.0, 0.1, *P, *Q, g.r_capsule)
    for _ in range(20):
        a, b = np.sort(rng.uniform(0, 1, 2))
        hit = bool(((S[:, 0] < b) & (S[:, 1] > a)).any())       # open spans meet the closed [a, b]
        assert capsule_free(g.Mr, 0.0, 0.0, 0.1, *at(a), *at(b), g.r_capsule) == (not hit)
    pieces = rapid_pieces(g, tuple(P), tuple(Q), min_len)
    free = []                             # the complement of the blocked spans
    t = 0.0
    for t0, t1 in S[np.argsort(S[:, 0])]:
        if t0 > t:
            free.append((t, t0))
        t = max(t, t1)
    if t < 1.0:
        free.append((t, 1.0))
    long_free = [(a, b) for a, b in free if (b - a) * L >= min_len + 2 * g.h]
    if pieces is None:
        assert not long_free
        return
    prev = P
    for e, fast in pieces:
        e = np.asarray(e)
        assert abs((Q - P)[0] * (e - P)[1] - (Q - P)[1] * (e - P)[0]) <= 1e-9 * max(L, 1.0) ** 2   # on the chord
        assert np.dot(e - prev, Q - P) >= -1e-12                           # in order
        if fast:
            assert math.hypot(*(e - prev)) >= min_len - 1e-6
            assert capsule_free(g.Mr, 0.0, 0.0, 0.1, *prev, *e, g.r_capsule)
        prev = e
    assert np.allclose(prev, Q)
    for a, b in long_free:                # some G0 runs inside every long free stretch
        m = at(0.5 * (a + b))
        starts = [P] + [np.asarray(e) for e, _ in pieces[:-1]]
        assert any(fast and np.dot(m - s, Q - P) >= 0 and np.dot(np.asarray(e) - m, Q - P) >= 0
                   for s, (e, fast) in zip(starts, pieces))


@pytest.mark.parametrize("r, h, k", [(1.5, 0.05, 3), (1.5, 0.025, 6), (2.0, 2.0 / 30, 3), (6.0, 0.1, 2), (6.0, 0.2, 1),
                                     (0.5, 0.05, 1), (1.0, 0.03, 3)])
def test_coarse_cell_is_a_tenth_of_r_or_0_2_mm(r, h, k):
    # the free-space search's cell: about min(0.2 mm, r/10), a whole number of pixels, at least one
    # (AdaptiveParams.coarse_cell_mm / coarse_cell_max_r); 0.5 mm tool radius at h 0.05: one pixel
    pocket = box(0, 0, 12, 10)
    g = Grid(pocket, pocket.buffer(-r), r, h, None)
    assert g.k == k and g.hc == pytest.approx(k * h)
    assert g.D.shape == g.Ac.shape == (g.ny // k, g.nx // k)


def _near_segment(M, x0, y0, h, a, b, rr):
    """Brute force: the material pixel centres of ``M`` within ``rr`` of the segment a -> b (bool mask)."""
    J, I = np.mgrid[0:M.shape[0], 0:M.shape[1]]
    px, py = x0 + (I + 0.5) * h, y0 + (J + 0.5) * h
    d = np.subtract(b, a)
    L2 = float(d @ d)
    t = np.zeros_like(px) if L2 == 0 else np.clip(((px - a[0]) * d[0] + (py - a[1]) * d[1]) / L2, 0, 1)
    return M.astype(bool) & ((a[0] + t * d[0] - px) ** 2 + (a[1] + t * d[1] - py) ** 2 < rr * rr)


@settings(**_SET)
@given(st.integers(0, 2 ** 31 - 1), st.sampled_from([0.0005, 0.003, 0.02]),
       st.sampled_from(["any", "horizontal", "vertical", "point", "steep"]))
def test_capsule_scans_only_the_capsule_rows_and_misses_no_pixel(seed, p, kind):
    """:func:`capsule_free` and :func:`blocked_spans` scan each row only over the capsule's span in it
    (``capsule_row``): they agree with a brute-force test of every pixel of the stock, for chords of
    every direction, points and chords running off the stock (sparse material: most chords free)."""
    rng = np.random.default_rng(seed)
    M = (rng.random((90, 130)) < p).astype(np.uint8)
    x0, y0, h = -0.3, 0.2, 0.1
    for _ in range(25):
        a = rng.uniform([-1.0, -1.0], [14.0, 10.0])
        b = {"any": rng.uniform([-1.0, -1.0], [14.0, 10.0]), "horizontal": a + [rng.uniform(-9, 9), 0.0],
             "vertical": a + [0.0, rng.uniform(-9, 9)], "point": a.copy(),
             "steep": a + [rng.uniform(-0.05, 0.05), rng.uniform(-9, 9)]}[kind]
        rr = float(rng.uniform(0.05, 2.5))
        near = _near_segment(M, x0, y0, h, a, b, rr)
        assert capsule_free(M, x0, y0, h, *a, *b, rr) == (not near.any())
        if kind != "point":
            assert len(blocked_spans(M, x0, y0, h, *a, *b, rr)) == int(near.sum())


@settings(**_SET)
@given(st.integers(0, 2 ** 31 - 1), st.sampled_from([0.01, 0.05, 0.2]))
def test_capsule_free_of_sets_one_component_aside(seed, p):
    """:func:`capsule_free_of` with component k of :func:`label8` set aside answers as
    :func:`capsule_free` on the stock with that component removed (the remnant sweep's test), and
    with none set aside (``skip`` 0) as :func:`capsule_free` itself; checked against brute force."""
    rng = np.random.default_rng(seed)
    M = (rng.random((60, 80)) < p).astype(np.uint8)
    lbl, n = label8(M)
    x0, y0, h = 0.1, -0.2, 0.1
    for _ in range(20):
        a, b = rng.uniform([-0.5, -0.5], [8.5, 6.0]), rng.uniform([-0.5, -0.5], [8.5, 6.0])
        rr, k = float(rng.uniform(0.05, 1.5)), int(rng.integers(0, n + 1))
        others = np.where(lbl == k, 0, M).astype(np.uint8) if k else M
        want = not _near_segment(others, x0, y0, h, a, b, rr).any()
        assert capsule_free_of(M, lbl, k, x0, y0, h, *a, *b, rr) == want
        assert capsule_free(others, x0, y0, h, *a, *b, rr) == want


@settings(**_SET)
@given(st.integers(0, 2 ** 31 - 1), st.sampled_from([0.05, 0.3, 0.9]), st.integers(0, 40),
       st.sampled_from([0.05, 0.7, 2.5]))
def test_material_within_counts_the_pixels_the_pairwise_test_counts(seed, p, n_pts, r):
    """:func:`material_within` (the finishing laps' rest within reach of a run of ring points) counts
    exactly the material pixels whose centre lies within r of some point: the pairwise statement it
    replaced (every material pixel against every point), points off the stock and on pixel centres
    included."""
    from cnclab.toolpath.adaptive.stock import material_within

    rng = np.random.default_rng(seed)
    M = (rng.random((70, 90)) < p).astype(np.uint8)
    x0, y0, h = -1.3, 0.4, 0.1
    P = rng.uniform([-3.0, -2.0], [10.0, 9.0], (n_pts, 2))
    P[: n_pts // 3] = np.round(P[: n_pts // 3] / h) * h + [x0 % h, y0 % h] + 0.5 * h   # on pixel centres
    jj, ii = np.nonzero(M)
    C = np.c_[x0 + (ii + 0.5) * h, y0 + (jj + 0.5) * h]
    ref = 0.0 if n_pts == 0 or len(C) == 0 else \
        float(np.count_nonzero(((C[:, None, :] - P[None, :, :]) ** 2).sum(axis=2).min(axis=1) < r * r)) * h * h
    assert material_within(M, x0, y0, h, P, r) == ref
