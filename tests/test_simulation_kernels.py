"""Compiled (numba) simulator kernels agree with the numpy reference on random stocks and paths."""
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from shapely.geometry import Point, box

from cnclab.runtime import pick
from cnclab.simulation import common, dixel, pixel

TOL = 1e-9
N_EXAMPLES = pick(25, 10)


def _random_stock_polygon(rng):
    """A box with up to two round holes and a rectangular notch (several intervals per row)."""
    poly = box(-6, -6, 6, 6)
    for _ in range(rng.integers(0, 3)):
        poly = poly.difference(Point(rng.uniform(-4, 4, 2)).buffer(rng.uniform(0.5, 2.0), quad_segs=32))
    if rng.random() < 0.5:
        x, y = rng.uniform(-5, 3, 2)
        poly = poly.difference(box(x, y, x + rng.uniform(0.3, 2), y + rng.uniform(0.3, 2)))
    return poly


def _random_path(rng, n_seg=3, step=0.05):
    """Lines and arcs joined end to end (mm), sampled every ~``step``; sometimes repeated points."""
    p = rng.uniform(-5, 5, 2)
    heading = rng.uniform(-math.pi, math.pi)
    pts = [p]
    for _ in range(n_seg):
        L = rng.uniform(1.0, 5.0)
        m = max(int(L / step), 2)
        if rng.random() < 0.5:                              # line
            t = np.arange(1, m + 1) * (L / m)
            seg = p + t[:, None] * [math.cos(heading), math.sin(heading)]
        else:                                               # arc of radius rho, either sense
            rho = rng.uniform(1.0, 6.0) * rng.choice([-1.0, 1.0])
            dphi = np.arange(1, m + 1) * (L / m) / rho
            ctr = p + rho * np.array([-math.sin(heading), math.cos(heading)])
            ang = heading - math.pi / 2 + dphi
            seg = ctr + abs(rho) * np.c_[np.cos(ang), np.sin(ang)] * np.sign(rho)
            heading += dphi[-1]
        pts.append(seg)
        p = seg[-1]
    P = np.vstack([np.atleast_2d(q) for q in pts])
    if rng.random() < 0.3:                                 # a standstill (ds = 0) inside the path
        i = rng.integers(1, len(P) - 1)
        P = np.insert(P, i, P[i], axis=0)
    return P


def _compare_runs(mod, seed, h, **kw):
    rng = np.random.default_rng(seed)
    poly = _random_stock_polygon(rng)
    P = _random_path(rng)
    r = float(rng.uniform(0.5, 3.0))
    out = {}
    for be in ("numpy", "numba"):
        s = mod.Stock.from_polygon(poly, h)
        out[be] = (mod.simulate(s, P, r, 2.0, 500.0, f_z=0.03, backend=be, **kw), s)
    (a, sa), (b, sb) = out["numpy"], out["numba"]
    for c in a.columns:
        x, y = a[c].to_numpy(), b[c].to_numpy()
        assert np.array_equal(np.isnan(x), np.isnan(y)), c
        ok = ~np.isnan(x)
        assert np.max(np.abs(x[ok] - y[ok]), initial=0.0) <= TOL * max(1.0, np.max(np.abs(x[ok]), initial=0)), c
    assert sa.area() == pytest.approx(sb.area(), rel=1e-12, abs=1e-9)
    return sa, sb, a


@settings(max_examples=N_EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), h=st.sampled_from([0.05, 0.08, 0.13]),
       central=st.booleans(), front_only=st.booleans(), lag=st.sampled_from([None, 0.0, 0.7]),
       lag_rule=st.sampled_from(["path", "front"]))
def test_dixel_simulate_compiled_equals_reference(seed, h, central, front_only, lag, lag_rule):
    sa, sb, df = _compare_runs(dixel, seed, h, feed_direction="central" if central else "backward",
                               front_only=front_only, lag_mm=lag, lag_rule=lag_rule)
    ra, aa, ba = sa.intervals()
    rb, ab, bb = sb.intervals()
    assert np.array_equal(ra, rb)                            # same intervals in every row
    assert np.max(np.abs(aa - ab), initial=0) <= TOL and np.max(np.abs(ba - bb), initial=0) <= TOL


@settings(max_examples=N_EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), h=st.sampled_from([0.05, 0.08]), front_only=st.booleans(),
       lag_rule=st.sampled_from(["path", "front"]))
def test_pixel_simulate_compiled_equals_reference(seed, h, front_only, lag_rule):
    sa, sb, _ = _compare_runs(pixel, seed, h, front_only=front_only, lag_rule=lag_rule)
    assert np.array_equal(sa.grid, sb.grid)                 # the same pixels removed


@settings(max_examples=N_EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1))
def test_single_calls_agree_including_options(seed):
    # engagement with the non-default options (full circle, linear boundary, sample counts) and
    # single cuts on a stock already cut by many small disks (several intervals per row)
    rng = np.random.default_rng(seed)
    poly = _random_stock_polygon(rng)
    for mod in (dixel, pixel):
        s = mod.Stock.from_polygon(poly, 0.07)
        for c in rng.uniform(-6, 6, (15, 2)):
            assert s.copy().cut_disk(c, 0.4, backend="numba") == pytest.approx(
                s.cut_disk(c, 0.4, backend="numpy"), rel=1e-12, abs=1e-12)
        for _ in range(10):
            c, f, r = rng.uniform(-7, 7, 2), rng.normal(size=2), rng.uniform(0.3, 3)
            opts = [{}, {"front_only": False}]
            opts += [{"boundary": "linear"}, {"bisections": 24}] if mod is dixel else [{"n_samples": 400}]
            for o in opts:
                e1 = s.engagement(c, r, f, backend="numpy", **o)
                e2 = s.engagement(c, r, f, backend="numba", **o)
                assert e2.angle_deg == pytest.approx(e1.angle_deg, abs=TOL), o
                assert e1.intervals.shape == e2.intervals.shape, o
                assert np.allclose(e1.intervals, e2.intervals, rtol=0, atol=TOL), o


def test_dixel_capacity_grows_inside_the_compiled_loop():
    # many small disks split the rows into more intervals than the initial capacity holds: the
    # compiled loop stops, the capacity doubles, and the path resumes -- same result as numpy
    rng = np.random.default_rng(3)
    P = np.c_[np.linspace(0, 20, 400), 1 + 0.8 * np.sin(np.linspace(0, 60, 400))]
    P = P[rng.permutation(len(P))[:120]]
    res = []
    for be in ("numpy", "numba"):
        s = dixel.Stock.from_polygon(box(0, 0, 20, 2), 0.1)
        k0 = s._A.shape[0]
        df = dixel.simulate(s, P, 0.2, 1, 100, backend=be, lag_mm=0.0)
        res.append((df, s))
    assert res[1][1]._A.shape[0] > k0                        # it did grow
    assert np.allclose(res[0][0].removed_mm2, res[1][0].removed_mm2, rtol=0, atol=1e-12)
    assert np.allclose(res[0][0].engagement_deg, res[1][0].engagement_deg, rtol=0, atol=TOL, equal_nan=True)
    for x, y in zip(res[0][1].intervals(), res[1][1].intervals()):
        assert np.array_equal(x, y) if x.dtype.kind == "i" else np.allclose(x, y, rtol=0, atol=1e-12)


def test_pixel_cut_kernel_equals_window_test_on_boundary_cases():
    # disks centred on pixel corners/centres and reaching beyond the grid: the per-row chord range
    # with its end fix-up selects exactly the pixels whose centres satisfy x^2 + y^2 <= r^2
    for c, r in [((0.0, 0.0), 1.0), ((0.05, 0.05), 0.5), ((1.0, 1.0), 0.3), ((-0.2, 2.0), 0.7),
                 ((1.025, 0.975), 0.45)]:
        a = pixel.Stock.from_polygon(box(0, 0, 2, 2), 0.05)
        b = a.copy()
        assert a.cut_disk_pixels(c, r, backend="numpy") == b.cut_disk_pixels(c, r, backend="numba")
        assert np.array_equal(a.grid, b.grid)


def test_backend_switch_and_subclass_override():
    with pytest.raises(ValueError, match="backend"):
        common.set_backend("cuda")
    with pytest.raises(ValueError, match="backend"):
        dixel.Stock.from_polygon(box(0, 0, 1, 1), 0.1).cut_disk((0, 0), 1, backend="fortran")
    old = common.set_backend("numpy")
    try:
        assert common.get_backend() == "numpy"
    finally:
        common.set_backend(old)
    calls = []

    class Counting(dixel.Stock):                  # an override must be honoured by simulate
        def cut_disk(self, center_xy, tool_radius):
            calls.append(1)
            return super().cut_disk(center_xy, tool_radius)

    s = Counting.from_polygon(box(0, 0, 10, 10), 0.1)
    dixel.simulate(s, np.c_[np.linspace(1, 9, 20), np.full(20, 5.0)], 1.0, 1, 100, backend="numba")
    assert len(calls) == 20


def test_dixel_engagement_few_rows_under_the_tool():
    # tool radius comparable to the row height: only a few crossings, the front range may start at
    # the first crossing behind the tool (2 pi unwrapping) or hold all/none of them (general port)
    rng = np.random.default_rng(11)
    s = dixel.Stock.from_polygon(box(0, 0, 4, 4).difference(Point(2, 2).buffer(0.8, quad_segs=16)), 0.13)
    for _ in range(pick(3000, 1500)):
        c, f, r = rng.uniform(0.5, 3.5, 2), rng.normal(size=2), rng.uniform(0.05, 0.5)
        fo = bool(rng.random() < 0.8)
        e1 = s.engagement(c, r, f, front_only=fo, backend="numpy")
        e2 = s.engagement(c, r, f, front_only=fo, backend="numba")
        assert e1.intervals.shape == e2.intervals.shape and np.allclose(e1.intervals, e2.intervals, rtol=0, atol=TOL)


@pytest.mark.parametrize("mod", [dixel, pixel])
def test_lag_rule_front_no_phantom_engagement_on_a_u_turn(mod):
    # a slot along y = 5 to x = 20, then straight back along the same line: on the way back the tool
    # is in its own slot, the true engagement is 0. The path lag (1.2 mm here) still holds the last
    # disks of the way out when the tool turns: it sees them as material ahead (phantom engagement);
    # lag_rule="front" cuts those disks first (they cover the front half-circle): 0 deg.
    h, r = 0.05, 3.0
    xs = np.arange(0.0, 20.0 + 1e-9, h)
    P = np.r_[np.c_[xs, np.full_like(xs, 5.0)], np.c_[xs[::-1][1:], np.full(len(xs) - 1, 5.0)]]
    back = np.arange(len(xs), len(P))
    res = {}
    for rule in ("path", "front"):
        st_ = mod.Stock.from_polygon(box(0, 0, 30, 10), h)
        res[rule] = mod.simulate(st_, P, r, 1.0, 100.0, lag_rule=rule).engagement_deg.to_numpy()
    assert np.nanmax(res["path"][back]) > 15.0              # the phantom the old rule reports (21.7 deg)
    # the front rule: 0 deg from the third sample of the way back on; at the turning point itself the
    # two samples keep the row artefact the lag exists for (disc edges at +-90 deg, <= 2 sqrt(2h/r) rad)
    assert np.all(res["front"][back][2:] <= 1e-4)       # 1e-4 deg: the transition bisection (24 halvings of ~pi)
    assert np.nanmax(res["front"][back]) <= math.degrees(2 * math.sqrt(2 * h / r))
    assert np.count_nonzero(res["path"][back] > 0) > 10     # the old rule: a phantom over ~0.6 mm
    out = np.arange(int(3.0 / h), len(xs) - 1)               # the way out (past the first tool length) unchanged
    np.testing.assert_allclose(res["front"][out], res["path"][out], atol=1e-9)


def test_lag_rule_rejects_unknown():
    with pytest.raises(ValueError, match="lag_rule"):
        dixel.simulate(dixel.Stock.from_polygon(box(0, 0, 5, 5), 0.1), [[1, 1], [2, 1]], 1.0, 1.0, 1.0, lag_rule="x")


def test_cut_disks_pixels_equals_one_disk_at_a_time():
    # the batch kernel (coverage's uncut measure) removes the same pixels as the reference numpy
    # window test applied centre by centre, and counts the same material, on random centres inside,
    # on and beyond the grid
    rng = np.random.default_rng(5)
    C = rng.uniform(-1.0, 11.0, (200, 2))
    for r in (0.3, 1.0, 2.55):
        a = pixel.Stock.from_polygon(box(0, 0, 10, 7), 0.05)
        b = a.copy()
        n = sum(a.cut_disk_pixels(c, r, backend="numpy") for c in C)
        assert b.cut_disks_pixels(C, r) == n and np.array_equal(a.grid, b.grid)
    with pytest.raises(ValueError, match="centers_xy"):
        b.cut_disks_pixels([[np.nan, 0.0]], 1.0)


@settings(max_examples=N_EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 10_000), h=st.sampled_from([0.05, 0.1, 0.3]))
def test_segment_pixels_compiled_equals_reference(seed, h):
    """``Stock.segment_pixels`` (Kim & Yang's Linear_Motion count and cut): the numba kernel counts and
    removes the same pixels as the numpy window test, segment after segment on one stock (zero-length
    segments, segments leaving the stock and pixel-centre ties on a grid-aligned radius included)."""
    rng = np.random.default_rng(seed)
    a = pixel.Stock.from_polygon(_random_stock_polygon(rng), h)
    b = a.copy()
    start, counts = int(a.grid.sum()), []
    for k in range(12):
        p0 = rng.uniform(-8, 8, 2)
        p1 = p0 if k % 5 == 0 else (np.round(rng.uniform(-8, 8, 2) / h) * h if k % 3 == 0 else rng.uniform(-8, 8, 2))
        r = float(rng.uniform(0.3, 3.0)) if k % 4 else 4 * h        # 4 h: centres exactly at r along an axis
        cut = bool(k % 2)
        counts.append(a.segment_pixels(p0, p1, r, cut=cut, backend="numpy"))
        assert counts[-1] == b.segment_pixels(p0, p1, r, cut=cut, backend="numba")
        assert np.array_equal(a.grid, b.grid)
    assert max(counts) > 0 and int(a.grid.sum()) < start    # not vacuous: material met and removed


def test_segment_pixels_is_the_union_of_the_discs_along_it():
    """A hand-checkable case: the pixels within r of a segment are those some disc centred on it covers
    (dense discs every h/20 along it: the same set up to centres within h/20 of the capsule's rim)."""
    st_ = pixel.Stock.from_polygon(box(0, 0, 20, 10), 0.1)
    full = int(st_.grid.sum())
    n = st_.segment_pixels((3.0, 4.0), (15.0, 6.5), 2.0)
    discs = st_.copy()
    t = np.linspace(0, 1, int(np.hypot(12.0, 2.5) / 0.005) + 1)
    removed = discs.cut_disks_pixels(np.c_[3 + 12 * t, 4 + 2.5 * t], 2.0)
    assert int(st_.grid.sum()) == full              # read only without cut
    assert abs(n - removed) <= 0.002 * n, (n, removed)


@settings(max_examples=N_EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 10_000), h=st.sampled_from([0.1, 0.3]), model=st.sampled_from(["pixel", "dixel"]))
def test_removal_equals_the_simulation_s_removal_columns(seed, h, model):
    """``common.removal`` (no engagement measured: the pixel stock's compiled disc loop, the dixel
    stock's fallback through ``simulate``) gives exactly ``simulate``'s s, ds, removed_mm2 and
    mrr_mm3_min, and leaves the same stock, on random stocks and paths (a standstill included)."""
    rng = np.random.default_rng(seed)
    mod = {"pixel": pixel, "dixel": dixel}[model]
    a = mod.Stock.from_polygon(_random_stock_polygon(rng), h)
    b = a.copy()
    P = _random_path(rng, step=0.2)
    r = float(rng.uniform(0.5, 3.0))
    ref = common.simulate(a, P, r, 2.0, 300.0)
    got = common.removal(b, P, r, 2.0, 300.0)
    for col in ("s", "ds", "removed_mm2", "mrr_mm3_min"):
        np.testing.assert_array_equal(got[col].to_numpy(), ref[col].to_numpy(), err_msg=col)
    assert np.array_equal(getattr(a, "grid", None), getattr(b, "grid", None)) if model == "pixel" \
        else a.area() == b.area()
