"""Dixel and pixel simulators: closed forms for engagement, swept-area volume, invariants, bad input."""
import math

import numpy as np
import pytest
from shapely import affinity
from shapely.geometry import LineString, Point, box

from cnclab.geometry.engagement import stepover_thesis1, theta_concave, theta_convex, theta_straight
from cnclab.runtime import pick
from cnclab.simulation import dixel, pixel
from cnclab.simulation.common import chip_thickness

R = 3.0
H = pick(0.01, 0.02)            # 0.01 mm is the accuracy target; fast mode checks at 0.02 mm
TOL = pick(0.2, 0.3)            # deg (the 0.2 deg target at 0.01 mm; fast-mode tolerance at 0.02 mm)
MODELS = [dixel, pixel]


def _arc_case(mod, kind, s, rho=8.0, h=H, sweep_deg=120.0):
    if kind == "concave":
        poly = box(-20, -20, 20, 20).difference(Point(0, 0).buffer(rho, quad_segs=512))
        d, sign, th = rho + s - R, 1.0, float(theta_concave(s, rho, R))
    else:
        poly = Point(0, 0).buffer(rho, quad_segs=512)
        d, sign, th = rho - s + R, -1.0, float(theta_convex(s, rho, R))
    n = int(math.radians(sweep_deg) * d / h)
    phi = sign * np.linspace(0, math.radians(sweep_deg), n)
    df = mod.simulate(mod.Stock.from_polygon(poly, h), np.c_[d * np.cos(phi), d * np.sin(phi)], R, 1, 1000)
    return df.engagement_deg.values[n // 3:], th


@pytest.mark.parametrize("mod", MODELS, ids=["dixel", "pixel"])
@pytest.mark.parametrize("kind", ["concave", "convex"])
def test_arc_engagement_matches_closed_form(mod, kind):
    e, th = _arc_case(mod, kind, 1.5)
    assert np.max(np.abs(e - th)) < TOL + (0.1 if mod is pixel else 0.0)


@pytest.mark.parametrize("s", [1.0, 3.0, 4.5])
def test_oblique_straight_cut_dixel(s):
    ang = 25.0
    poly = affinity.rotate(box(-30, -30, 30, 0), ang, origin=(0, 0))
    u = np.array([math.cos(math.radians(ang)), math.sin(math.radians(ang))])
    nrm = np.array([-u[1], u[0]])
    lam = np.arange(-6.0, 6.0, H)
    df = dixel.simulate(dixel.Stock.from_polygon(poly, H), lam[:, None] * u + (R - s) * nrm, R, 3, 255, f_z=0.04)
    e = df.engagement_deg.values[len(lam) // 2:]
    assert np.max(np.abs(e - float(theta_straight(s, R)))) < TOL
    mrr = df.mrr_mm3_min.values[len(lam) // 2:]
    assert np.median(mrr) == pytest.approx(3 * s * 255, rel=0.01)        # a_p * a_e * v_f


@pytest.mark.parametrize("mod", MODELS, ids=["dixel", "pixel"])
def test_closed_path_removed_area_equals_swept_geometry(mod):
    stock_poly = box(-15, -15, 15, 15)
    t = np.linspace(0, 2 * np.pi, pick(3000, 1500))
    path = np.c_[6 * np.cos(t) + 1.5 * np.cos(3 * t), 5 * np.sin(t)]
    h = pick(0.02, 0.05)
    st = mod.Stock.from_polygon(stock_poly, h)
    a0 = st.area()
    df = mod.simulate(st, path, R, 1, 1000)
    swept = stock_poly.intersection(LineString(path).buffer(R, quad_segs=256)).area
    removed = a0 - st.area()
    assert removed == pytest.approx(df.removed_mm2.sum(), rel=1e-12)
    assert removed == pytest.approx(swept, rel=1e-3 if mod is dixel else 3e-3)


def test_dixel_disk_area_exact_and_polygon_area():
    st = dixel.Stock.from_polygon(box(0, 0, 10, 10).difference(Point(5, 5).buffer(2, quad_segs=256)), 0.25)
    ref = 100 - Point(5, 5).buffer(2, quad_segs=256).area
    assert st.area() == pytest.approx(ref, rel=2e-3)
    full = dixel.Stock.from_polygon(box(-10, -10, 10, 10), 0.37)
    assert full.cut_disk((0.123, -0.456), 2.5) == pytest.approx(math.pi * 2.5 ** 2, rel=1e-12)


@pytest.mark.parametrize("mod", MODELS, ids=["dixel", "pixel"])
def test_copy_is_independent_and_cut_is_idempotent(mod):
    st = mod.Stock.from_polygon(box(0, 0, 10, 10), 0.05)
    c = st.copy()
    first = st.cut_disk((5, 5), 2)
    assert first > 0 and st.cut_disk((5, 5), 2) == 0.0
    assert c.area() == pytest.approx(100.0)
    assert st.area() == pytest.approx(100.0 - first)


@pytest.mark.parametrize("mod", MODELS, ids=["dixel", "pixel"])
def test_engagement_slot_and_air(mod):
    st = mod.Stock.from_polygon(box(0, 0, 20, 20), 0.02)
    assert st.engagement_angle((10, 10), 3, (1, 0)) == pytest.approx(180.0, abs=1e-9)
    assert st.engagement_angle((40, 40), 3, (1, 0)) == 0.0


def test_chip_thickness_straight_formulas():
    theta = math.radians(60)
    hmax, havg = chip_thickness(np.array([[-math.pi / 2, -math.pi / 2 + theta]]), 0.04)
    assert hmax == pytest.approx(0.04 * math.sin(theta))
    assert havg == pytest.approx(0.04 * 1.5 / (3 * theta))    # f_z a_e / (r theta)


@pytest.mark.parametrize("mod", MODELS, ids=["dixel", "pixel"])
def test_bad_input(mod):
    with pytest.raises(ValueError, match="resolution_mm"):
        mod.Stock.from_polygon(box(0, 0, 1, 1), 0)
    with pytest.raises(ValueError, match="polygon"):
        mod.Stock.from_polygon(LineString([(0, 0), (1, 1)]), 0.1)
    st = mod.Stock.from_polygon(box(0, 0, 1, 1), 0.1)
    with pytest.raises(ValueError, match="tool_radius"):
        st.cut_disk((0, 0), -1)
    with pytest.raises(ValueError, match="centres"):
        mod.simulate(st, np.zeros((1, 2)), 1, 1, 100)
    with pytest.raises(ValueError, match="a_p"):
        mod.simulate(st, np.zeros((3, 2)) + [[0, 0], [1, 0], [2, 0]], 1, 0, 100)


@pytest.mark.parametrize("center, feed, expected", [
    ((5.0, 12.0), (1.0, 0.0), math.degrees(math.acos(1 - 1 / 3))),   # tool overhangs the grid's top edge
    ((5.0, -2.0), (1.0, 0.0), math.degrees(math.acos(1 - 1 / 3))),   # ... and its bottom edge
    ((1.0, 5.0), (0.0, 1.0), math.degrees(math.acos(-1 / 3))),       # centre 1 mm inside the left edge
])
def test_engagement_when_the_tool_reaches_beyond_the_stock_grid(center, feed, expected):
    from shapely.geometry import box

    from cnclab.simulation import dixel, pixel

    for mod in (dixel, pixel):
        st = mod.Stock.from_polygon(box(0, 0, 20, 10), 0.02)
        assert st.engagement(center, 3.0, feed).angle_deg == pytest.approx(expected, abs=0.2), mod.__name__


def test_dixel_many_intervals_per_row_match_1d_reference_and_round_trip():
    # random small disks split rows into many intervals (the per-row capacity must grow); every
    # row must equal the 1-D reference [0, 20] minus the union of the disks' mean chords
    from shapely.geometry import MultiLineString
    from shapely.ops import unary_union

    rng = np.random.default_rng(7)
    st = dixel.Stock.from_polygon(box(0, 0, 20, 2), 0.1)
    centres = np.c_[rng.uniform(0, 20, 60), rng.uniform(0, 2, 60)]
    total = sum(st.cut_disk(c, 0.25) for c in centres)
    assert st.area() == pytest.approx(40.0 - total, rel=1e-12)
    rows, a, b = st.intervals()
    assert np.all(np.diff(rows) >= 0) and np.all(b > a)
    same_row = rows[1:] == rows[:-1]
    assert np.all(a[1:][same_row] >= b[:-1][same_row])             # sorted, disjoint
    assert np.bincount(rows).max() >= 4                             # several intervals in a row
    for j in range(st.n_rows):
        chords = []
        for c in centres:
            jj, w = st.disk_halfwidths(c[1], 0.25)
            if j in jj:
                ww = w[list(jj).index(j)]
                chords.append([(c[0] - ww, 0), (c[0] + ww, 0)])
        ref = LineString([(0, 0), (20, 0)]).difference(unary_union(MultiLineString(chords))) if chords \
            else LineString([(0, 0), (20, 0)])
        assert np.sum(b[rows == j] - a[rows == j]) == pytest.approx(ref.length, abs=1e-9), j
    # the flat (rows, a, b) view rebuilds an identical stock (constructor used by subclasses)
    st2 = dixel.Stock(st.y0, st.resolution_mm, st.n_rows, rows, a, b, st.x_min, st.x_max)
    assert st2.area() == pytest.approx(st.area(), rel=1e-12)
    assert st2.engagement((10, 1), 0.8, (1, 0)).angle_deg == pytest.approx(
        st.engagement((10, 1), 0.8, (1, 0)).angle_deg, abs=1e-12)


@pytest.mark.parametrize("kind", ["concave", "convex"])
def test_dixel_engagement_second_order_with_central_feed_direction(kind):
    # with the tangent (central difference) as feed direction, the dixel engagement on arcs is
    # second-order accurate in the row height (polyline boundary between rows)
    errs = []
    for h in (0.1, 0.05):
        if kind == "concave":
            poly = box(-1, -4, 10.5, 10.5).difference(Point(0, 0).buffer(8.0, quad_segs=512))
            d, sign, th = 6.5, 1.0, float(theta_concave(1.5, 8.0, R))
        else:
            poly = Point(0, 0).buffer(8.0, quad_segs=512).intersection(box(-1, -9, 9, 4))
            d, sign, th = 9.5, -1.0, float(theta_convex(1.5, 8.0, R))
        phi = sign * np.linspace(0, math.radians(60), int(math.radians(60) * d / 0.02) + 1)
        df = dixel.simulate(dixel.Stock.from_polygon(poly, h), np.c_[d * np.cos(phi), d * np.sin(phi)], R,
                            1, 1000, feed_direction="central")
        errs.append(np.max(np.abs(df.engagement_deg.values[len(phi) // 2:-1] - th)))
    assert errs[1] < 0.06 and errs[1] < 0.4 * errs[0], errs


def test_material_removal_rate_formula():
    from cnclab.simulation.common import material_removal_rate

    out = material_removal_rate([0.075, 0.0], [0.05, 0.0], a_p=3.0, feed_mm_min=255.0)
    assert out[0] == pytest.approx(3 * 1.5 * 255) and np.isnan(out[1])
    with pytest.raises(ValueError, match="feed_direction"):
        dixel.simulate(dixel.Stock.from_polygon(box(0, 0, 1, 1), 0.1), [[0, 0], [1, 0]], 1, 1, 100,
                       feed_direction="forward")


def test_dixel_engagement_bad_options():
    st = dixel.Stock.from_polygon(box(0, 0, 10, 10), 0.1)
    with pytest.raises(ValueError, match="boundary"):
        st.engagement((5, 12), 3, (1, 0), boundary="spline")
    with pytest.raises(ValueError, match="method"):
        st.engagement((5, 12), 3, (1, 0), method="exact")
    # both boundary models agree on a straight edge parallel to the rows (exact: acos(1 - 1/3))
    for b in ("polyline", "linear"):
        assert st.engagement((5, 12), 3, (1, 0), boundary=b).angle_deg == pytest.approx(
            math.degrees(math.acos(1 - 1 / 3)), abs=0.05)


def test_simulate_runs_equals_simulating_each_run_on_one_stock():
    """simulate_runs = simulate per run between rapids, in order, on the same stock; bad flags refused."""
    import pytest as _pytest
    from shapely.geometry import box as _box

    from cnclab.simulation import dixel as _dixel

    xs = np.arange(0.0, 12.0, 0.1)
    P = np.r_[np.c_[xs, np.full_like(xs, 1.0)], np.c_[xs[::-1], np.full_like(xs, 2.5)], [[5.0, 2.5]]]
    rapid = np.zeros(len(P), bool)
    rapid[len(xs)] = True                       # lift between the two passes
    rapid[-1] = True                            # a lone last point: a run of 1, skipped
    T = _dixel.simulate_runs(_dixel.Stock.from_polygon(_box(0, 0, 12, 6), 0.05), P, rapid, 1.5, 2, 300)
    st = _dixel.Stock.from_polygon(_box(0, 0, 12, 6), 0.05)
    a = _dixel.simulate(st, P[:len(xs)], 1.5, 2, 300)
    b = _dixel.simulate(st, P[len(xs):-1], 1.5, 2, 300)
    assert len(T) == len(P) - 1
    assert np.array_equal(T.point.to_numpy(), np.arange(len(P) - 1))
    assert np.flatnonzero(T.plunge.to_numpy()).tolist() == [0, len(xs)]
    np.testing.assert_allclose(T.removed_mm2.to_numpy(), np.r_[a.removed_mm2, b.removed_mm2])
    np.testing.assert_allclose(T.engagement_deg.to_numpy(), np.r_[a.engagement_deg, b.engagement_deg])
    with _pytest.raises(ValueError, match="rapid"):
        _dixel.simulate_runs(st, P, rapid[:-1], 1.5, 2, 300)
