"""Theses II and III: arcs vs Thesis I, convergence orders, rotation sense, simulated engagement."""
import math

import numpy as np
import pytest
from shapely.geometry import Point, Polygon, box

from cnclab.geometry.contours import Arc, Blob, Ellipse, Line, Reversed, RoundedPolygon, SplineContour
from cnclab.runtime import pick
from cnclab.toolpath import constant_engagement as ce

R, TH = 3.0, 60.0


def _arc_errors(method, kind, dts):
    arc = Arc((0, 0), 8.0, 0, 200 if kind == "concave" else -200)
    P0, d = ce.arc_start_point(arc, R, TH, kind)
    return np.array([np.max(np.abs(np.hypot(*ce.thesis3_path(arc, R, TH, dt, method, P0=P0).P.T) - d))
                     for dt in dts])


@pytest.mark.parametrize("kind", ["concave", "convex"])
def test_convergence_orders_on_arcs(kind):
    dts = np.array([0.4, 0.2, 0.1, 0.05])
    for method, order in (("euler", 1), ("midpoint", 2)):
        err = _arc_errors(method, kind, dts)
        slope = np.polyfit(np.log(dts), np.log(err), 1)[0]
        assert abs(slope - order) < 0.15, (method, slope)


def test_convergence_against_ivp_on_ellipse():
    ell = Ellipse((0, 0), 12, 8)
    ref = ce.thesis2_ivp(ell, R, TH, t_end=3.0)
    dts = np.array([0.04, 0.02, 0.01])
    for method, order in (("euler", 1), ("midpoint", 2)):
        err = []
        for dt in dts:
            p = ce.thesis3_path(ell, R, TH, dt, method, t_end=3.0)
            err.append(np.max(np.hypot(*(p.P - ref.sol.sol(p.t).T).T)))
        slope = np.polyfit(np.log(dts), np.log(err), 1)[0]
        assert abs(slope - order) < 0.2, (method, slope)


def test_thesis2_and_thesis3_directions_agree():
    rng = np.random.default_rng(0)
    for _ in range(20):
        C = rng.normal(size=2)
        a = rng.uniform(0, 2 * np.pi)
        P = C + R * np.array([np.cos(a), np.sin(a)])
        assert np.allclose(ce.thesis3_feed_direction(P, C, TH), ce.thesis2_feed_direction(P, C, TH))


def test_straight_contour_offset_exact_and_constraint():
    res = ce.thesis3_path(Line((0, 0), (20, 0)), R, TH, 0.3)
    assert np.allclose(res.P[:, 1], R * math.cos(math.radians(TH)))
    assert np.allclose(np.hypot(*(res.P - res.C).T), R)          # |P_i C_i| = r at every step


def test_adaptive_step_meets_tolerance_with_fewer_steps():
    blob = Blob((0, 0), 10.0)
    ref = ce.thesis2_ivp(blob, R, TH)
    fixed = ce.thesis3_path(blob, R, TH, 0.01, "midpoint")
    ada = ce.thesis3_path(blob, R, TH, 0.05, "midpoint", adaptive=True, tol_mm=1e-5)
    err = np.max(np.hypot(*(ada.P - ref.sol.sol(ada.t).T).T))
    assert err < 1e-3 and len(ada.t) < len(fixed.t)


@pytest.mark.parametrize("name", ["blob", "rounded_polygon", "spline"])
def test_generated_paths_hold_engagement_in_simulation(name):
    h = pick(0.01, 0.03)
    if name == "blob":
        c = Blob((0, 0), 10.0)
    elif name == "rounded_polygon":
        c = RoundedPolygon([(-10, -8), (10, -8), (10, 8), (-10, 8)], 4.0)
    else:
        t = np.linspace(0, 2 * np.pi, 9)[:-1]
        c = SplineContour(np.c_[10 * np.cos(t), 8 * np.sin(t) + np.sin(2 * t)], closed=True)
    res = ce.thesis3_path(c, R, TH, 0.05, "midpoint")
    P = ce.resample_path(res.P, h)
    stock = box(-25, -25, 25, 25).difference(Polygon(c.sample(4000)))
    df = ce.engagement_along_path(stock, P, R, h)
    stats = ce.deviation_stats(df.engagement_deg, TH, skip_mm=3.0, s_mm=df.s, end_skip_mm=12.0)
    assert stats["max_dev_deg"] <= pick(1.0, 1.5), stats


def test_reversed_contour_and_bad_input():
    a = Arc((0, 0), 5, 0, 90)
    rv = Reversed(a)
    assert np.allclose(rv.point(0.0), a.point(a.t_max))
    with pytest.raises(ValueError, match="theta_deg"):
        ce.thesis3_path(a, R, 0.0, 0.1)
    with pytest.raises(ValueError, match="tool_radius"):
        ce.thesis3_path(a, -1, 60, 0.1)
    with pytest.raises(ValueError, match="dt"):
        ce.thesis3_path(a, R, 60, 0.0)
    with pytest.raises(ValueError, match="method"):
        ce.thesis3_path(a, R, 60, 0.1, method="rk4")


def test_multi_pass_grows_pocket_within_final_contour():
    from cnclab.simulation import dixel

    h = 0.05
    domain = box(-20, -20, 20, 20)
    final = Point(0, 0).buffer(14.0, quad_segs=128)
    stock = dixel.Stock.from_polygon(domain.difference(Point(0, 0).buffer(6.0, quad_segs=128)), h)
    laps = ce.multi_pass(stock, domain, final, (0, 0), R, TH, n_passes=2, dt=0.1)
    assert len(laps) == 2 and all(lap["removed_mm2"] > 0 for lap in laps)
    for lap in laps:
        assert np.all(np.hypot(*lap["path"].T) <= 14.0 - R + 1e-6)


def _spline_contour():
    t = np.linspace(0, 2 * np.pi, 9)[:-1]
    return SplineContour(np.c_[10 * np.cos(t), 8 * np.sin(t) + np.sin(2 * t)], closed=True)


def test_convergence_orders_on_spline_contour():
    # Thesis III vs the Thesis II IVP on a closed cubic-spline contour: observed orders 1 and 2
    table, orders = ce.convergence_study(_spline_contour(), R, TH, [0.08, 0.04, 0.02, 0.01], t_end=20.0)
    assert abs(orders["euler"] - 1.0) < 0.1 and abs(orders["midpoint"] - 2.0) < 0.1, orders
    for m, g in table.groupby("method"):
        assert np.all(np.diff(g.max_err_mm.values) < 0), (m, g)       # error falls at every halving


def test_simulated_engagement_deviation_shrinks_with_dt():
    # the dixel simulator measures the engagement along Euler paths of decreasing step: the deviation
    # from theta after the entry transient must shrink with dt (first order: about halving)
    c = _spline_contour()
    stock = box(-25, -25, 25, 25).difference(Polygon(c.sample(4000)))
    df = ce.simulated_deviation_vs_dt(c, stock, R, TH, [0.4, 0.2, 0.1], method="euler",
                                      resolution_mm=0.05, t_end=25.0)
    dev = df.max_dev_deg.values
    assert np.all(dev[1:] < 0.7 * dev[:-1]), df
    assert np.all(np.diff(df.mean_abs_dev_deg.values) < 0), df
    # the midpoint path at the coarsest of these steps already holds theta within 0.2 deg
    mid = ce.simulated_deviation_vs_dt(c, stock, R, TH, [0.4], method="midpoint", resolution_mm=0.05,
                                       t_end=25.0)
    assert mid.max_dev_deg.iloc[0] <= 0.2, mid


def test_convergence_study_bad_input():
    with pytest.raises(ValueError, match="dts"):
        ce.convergence_study(Line((0, 0), (10, 0)), R, TH, [0.1])


def test_thin_ring_closes_a_ring_whose_last_point_nearly_repeats_the_first():
    """issue 29: on the 60 x 40 mm deep pocket a cleared-region ring thinned to 0.3 mm ended 1.3e-4 mm
    from its first point (at y = 39.75 mm): np.allclose calls them equal, so SplineContour did not close
    the ring, and scipy's periodic spline refused the unequal ends (the constant-engagement strategy
    failed on the job). thin_ring drops that point; the ring's spline is then periodic."""
    from cnclab.geometry.contours import SplineContour

    phi = np.linspace(0.0, 2 * np.pi, 1201)[:-1]
    ring = np.c_[20 + 20 * np.cos(phi), 19.75 + 20 * np.sin(phi)]
    ring = np.vstack([ring, ring[0] + [1.3e-4, 0.0]])
    raw = ring[::12]                                     # what thinning kept before: the near-duplicate last
    assert np.allclose(raw[0], raw[-1]) and not np.array_equal(raw[0], raw[-1])
    with pytest.raises(ValueError, match="periodic"):
        SplineContour(raw, closed=True)
    pts = ce.thin_ring(ring, 1.0)
    gaps = np.hypot(*np.diff(np.vstack([pts, pts[:1]]), axis=0).T)
    assert gaps.min() >= 0.5 and gaps.max() < 1.2           # thinned to ~1 mm, the closing gap included
    c = SplineContour(pts, closed=True)
    assert np.allclose(c.point(0.0), c.point(c.t_max))     # closed: one full turn back to the start
