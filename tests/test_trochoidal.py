"""Trochoid generators, the exact front engagement vs the dixel simulation, the CE iteration with
explicit roll-in / roll-out (Jacsó 2021 §3.4, §4)."""
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cnclab.toolpath import trochoidal as tr
from cnclab.toolpath.evaluate import Evaluation
from cnclab.works.jacso2021.studies import compare_patterns

# one xdist group (make test: --dist loadgroup): all of this module runs in one worker, so that
# the module-scoped fixtures (`ce_slot`, `sweep_w12`: ~4 CPU-s) are made once
pytestmark = pytest.mark.xdist_group("test_trochoidal")


@settings(max_examples=30, deadline=None, derandomize=True)
@given(st.floats(0.2, 3.0), st.floats(7.0, 20.0))
def test_generators_stay_in_slot_and_advance_by_step(step, width):
    R = width / 2 - 3
    for gen in (tr.circular_trochoid, tr.cycloid):
        p = gen(step, width, 3.0, 4, ds=0.1)
        per = tr.period_index(p)
        assert np.abs(p.xyz[:, 1]).max() <= R + 1e-9 and np.all(p.xyz[:, 2] == 0)
        x1, x2 = (p.xyz[per == k, 0].mean() for k in (1, 2))    # identical sampling
        assert x2 - x1 == pytest.approx(step, abs=0.05)      # one boundary sample may switch period


def test_circular_period_length_is_circle_plus_step():
    p = tr.circular_trochoid(1.0, 12.0, 3.0, 3, ds=0.01)
    assert tr.length_per_period(p, 1) == pytest.approx(2 * math.pi * 3 + 1, rel=1e-4)
    L = tr.pattern_lengths(p, [1])
    assert L["link"] == pytest.approx(1.0) and L["cut"] == pytest.approx(2 * math.pi * 3, rel=1e-4)


@pytest.mark.parametrize("theta", [30.0, 60.0, 90.0])
def test_front_step_inverse(theta):
    s = tr.circle_front_step(theta, 14.0, 3.0)
    assert tr.max_engagement_circle_front(s, 14.0, 3.0) == pytest.approx(theta, abs=1e-9)


def test_simulated_front_engagement_matches_exact():
    s = 0.9
    p = tr.circular_trochoid(s, 12.0, 3.0, 5, ds=0.05)
    df, m = tr.evaluate_pattern(p, 12.0, 3.0, 0.05)
    k = 3
    sel = df[(df.period == k) & ~df.link & (df.x > k * s + 2.9) & (df.y.abs() < 0.06)]
    assert sel.engagement_deg.mean() == pytest.approx(tr.max_engagement_circle_front(s, 12, 3), abs=1.0)
    # steady state removes W * step per period
    assert m["mrr_avg_sim_mm3_min"] == pytest.approx(m["mrr_avg_mm3_min"], rel=0.01)
    assert m["engagement_max_deg"] >= sel.engagement_deg.max() - 1e-9
    # one metric vocabulary: an Evaluation (p50 <= p95 <= max over the cutting moves; the pattern's own
    # metrics in extra; what the slot evaluation does not measure is NaN / -1)
    assert isinstance(m, Evaluation) and m.engagement_max_deg == m["engagement_max_deg"]
    assert m.engagement_p50_deg <= m.engagement_p95_deg <= m.engagement_max_deg
    assert m["step_mm"] == pytest.approx(s) and m.plunges_into_material == -1 and math.isnan(m.uncut_area_mm2)


@pytest.mark.parametrize("rho,into", [(1.0, True), (2.5, False)])
def test_roll_arc_is_tangent_circle(rho, into):
    E, T = np.array([1.0, 2.0]), np.array([0.6, 0.8])
    P, C = tr.roll_arc(E, T, rho, 90.0, ds=0.01, into=into)
    assert np.allclose(np.hypot(*(P - C).T), rho)
    d = (P[-1] - P[-2]) if into else (P[1] - P[0])
    assert np.allclose(P[-1 if into else 0], E)
    assert np.dot(d / np.hypot(*d), T) == pytest.approx(1.0, abs=1e-3)        # tangent at E
    assert T[0] * (C - E)[1] - T[1] * (C - E)[0] > 0                            # ccw: centre on the left


@pytest.fixture(scope="module")
def ce_slot():
    it = tr.ce_trochoid_iteration(12.0, 3.0, 60.0, n_periods=7, resolution_mm=0.1)
    p = tr.ce_trochoid(12.0, 3.0, 60.0, 5, 0.1, iteration=it)
    df, m = tr.evaluate_pattern(p, 12.0, 3.0, 0.1, link_feed_mm_min=1500.0)
    return it, p, df, m


def test_ce_iteration_converges(ce_slot):
    it = ce_slot[0]
    ch = it.table.shape_change_mm.to_numpy()
    assert ch[-1] < 1.5 * 0.1 and ch[-1] < ch[1]          # converged to ~ one dixel row
    assert 0.5 < it.table.shift_mm.iloc[-1] < 1.5        # < r(1 - cos 60): curved front
    assert np.all(it.table.link_removed_mm2.iloc[1:] < 0.05)   # links run through cleared slot


def test_ce_slot_engagement_by_segment(ce_slot):
    """At its admissible step every cutting move is <= theta (the bisection's limit); the roll-in
    starts in air and rises without a jump (the old roll-in jumped 4 -> 46 deg in one 0.1 mm sample
    at the previous period's corner); the cut holds theta within the dixel noise; roll-out drops."""
    _, p, df, m = ce_slot
    assert m["engagement_max_deg"] <= 60.0
    assert m["engagement_max_link_deg"] < 1.0 and m["link_removed_mm2"] < 1e-3
    for k in (2, 3):
        e = df[(df.period == k) & (df.kind == "roll-in")].engagement_deg.to_numpy()
        assert e[0] < 1.0 and e[-1] == pytest.approx(60.0, abs=8.0) and e.max() <= 60.0
        assert np.diff(e).max() <= 15.0          # no corner jump (samples 0.1 mm apart)
        c = df[(df.period == k) & (df.kind == "cut")].engagement_deg.to_numpy()
        assert np.median(c) == pytest.approx(57.0, abs=4.0)   # theta minus the admissible step's margin
        o = df[(df.period == k) & (df.kind == "roll-out")].engagement_deg.to_numpy()
        assert o[-1] < 1.0


def test_ce_beats_circular_at_same_engagement_limit(ce_slot):
    _, p, _, m = ce_slot
    s_front = tr.circle_front_step(60.0, 12.0, 3.0)         # exact front-point step of the circle
    s_circ = tr.admissible_step("circular", 60.0, 12.0, 3.0, 0.1)
    assert s_circ < s_front              # the circle's maximum lies after the front point
    assert p.info["step"] > s_circ       # both at simulated maximum <= 60 deg
    circ = tr.circular_trochoid(s_circ, 12.0, 3.0, 3, ds=0.1)
    assert m["length_per_mm_slot"] < tr.length_per_period(circ, 1) / s_circ


def test_bad_input():
    with pytest.raises(ValueError, match="width"):
        tr.circular_trochoid(1.0, 6.0, 3.0, 2)
    with pytest.raises(ValueError, match="step"):
        tr.cycloid(-1.0, 12.0, 3.0, 2)
    with pytest.raises(ValueError, match="pattern"):
        tr.admissible_step("spiral", 60, 12, 3)
    with pytest.raises(ValueError, match="radius_mm"):
        tr.roll_arc((0, 0), (1, 0), -1.0, 90.0)


def test_linking_arc_endpoints_and_bulge():
    A, C, ccw = tr.linking_arc((0.0, 3.0), (1.0, -3.0), bulge=0.5, ds=0.05)
    assert np.allclose(A[0], (0, 3)) and np.allclose(A[-1], (1, -3))
    assert A[:, 0].min() < -2.0 and ccw
    assert np.allclose(np.hypot(*(A - C).T), np.hypot(*(A[0] - C)))


# ---------------------------------------------------------------------------------------------
# Thesis IV roll-in (issue 16): filleted entry/exit, equal simulated maximum engagement
# ---------------------------------------------------------------------------------------------
SWEEP_THETAS = (30.0, 45.0, 60.0, 75.0, 90.0)        # theta_max of the notebook's sweep


@pytest.fixture(scope="module")
def sweep_w12():
    """compare_patterns at W/r = 4 (the fast-mode width of the notebook's sweep), 0.1 mm dixels,
    links at 1500 mm/min (Table 4.1 / §4 feeds)."""
    return {th: compare_patterns(12.0, 3.0, th, 0.1, a_p=3.0, feed_mm_min=255.0, link_feed_mm_min=1500.0)
            for th in SWEEP_THETAS}


@pytest.mark.parametrize("theta", SWEEP_THETAS)
def test_ce_never_worse_than_cycloid_at_equal_simulated_max(sweep_w12, theta):
    df = sweep_w12[theta]
    assert (df.theta_limit_deg == theta).all()
    assert (df.engagement_max_deg <= theta).all()                       # every pattern within the limit
    ce = df.loc["constant-engagement"]
    assert ce["engagement_max_roll-in_deg"] <= theta
    # path per mm of slot (same feed) and time per mm of slot (links at 1500 mm/min): CE >= cycloid
    assert ce.mrr_gain_same_feed_vs_cycloid_pct >= 0.0
    assert ce.mrr_gain_vs_cycloid_pct >= 0.0
    assert ce.length_per_mm_slot <= df.loc["cycloid", "length_per_mm_slot"]


@pytest.mark.parametrize("theta", (30.0, 60.0, 90.0))
def test_roll_in_holds_theta_resimulated_at_finer_dixels(theta):
    """Planned and step-bisected on 0.1 mm dixels, re-simulated on 0.05 mm dixels: the engagement
    along every steady roll-in stays <= theta + h/(r sin theta) rad, h = 0.1 mm. Tolerance: the
    planning stock knows the material boundary to one dixel row h; on a front at depth a the
    engagement is acos(1 - a/r), d(theta)/da = 1/(r sin theta), so a boundary off by h moves it by
    h/(r sin theta) (3.8 deg at 30, 2.2 at 60, 1.9 at 90 deg for r = 3 mm)."""
    h, r, W = 0.1, 3.0, 12.0
    it = tr.ce_trochoid_iteration(W, r, theta, 8, h)
    p = tr.ce_trochoid(W, r, theta, 6, h, iteration=it)
    df, m = tr.evaluate_pattern(p, W, r, 0.05)
    tol = math.degrees(h / (r * math.sin(math.radians(theta))))
    steady = df.period.isin([2, 3, 4])
    e = df[steady & (df.kind == "roll-in")].engagement_deg.to_numpy()
    assert e.size > 20 and np.nanmax(e) <= theta + tol
    assert np.nanmax(e) >= theta - 10.0          # the roll-in does reach the cut's engagement


@settings(max_examples=40, deadline=None, derandomize=True)
@given(st.floats(-3, 3), st.floats(-3, 3), st.floats(-math.pi, math.pi), st.floats(0.2, 5.0),
       st.floats(0.05, 0.95))
def test_tangent_arc_is_tangent_circle_through_end(ax, ay, phi, L, frac):
    A = np.array([ax, ay])
    T = np.array([math.cos(phi), math.sin(phi)])
    turn = math.pi * frac                       # B seen from A at this angle left of T
    B = A + L * np.array([math.cos(phi + turn / 2), math.sin(phi + turn / 2)])
    P = tr.tangent_arc(A, T, B, ds=0.01)
    assert np.allclose(P[0], A) and np.allclose(P[-1], B)
    d0 = (P[1] - P[0]) / np.hypot(*(P[1] - P[0]))
    assert d0 @ T == pytest.approx(1.0, abs=5e-3)               # leaves A along T
    # all points on one circle: the chord A->B seen under half the turn => radius L / (2 sin(turn/2))
    rho = L / (2 * math.sin(turn / 2))
    C = A + rho * np.array([-T[1], T[0]])
    assert np.allclose(np.hypot(*(P - C).T), rho, atol=1e-9 * max(1.0, rho))


@settings(max_examples=30, deadline=None, derandomize=True)
@given(st.floats(15.0, 120.0), st.floats(0.5, 4.0))
def test_fillet_entry_is_g1_with_the_given_radius(alpha_deg, rho):
    """Straight wall (+x) and a straight cut leaving it at alpha: the fillet has radius rho (to the
    sampling of the cut, 0.02 mm), is tangent to the wall at its start and to the cut at its end."""
    a = math.radians(alpha_deg)
    ds = 0.02
    roll_in = np.c_[np.linspace(-12.0, 0.0, 601), np.zeros(601)]
    cut = np.c_[np.cos(a), np.sin(a)] * np.linspace(0.0, 12.0, 601)[:, None]
    new_in, new_cut = tr.fillet_entry(roll_in, cut, rho, ds=ds)
    u = rho * math.tan(a / 2)
    assert np.allclose(new_cut[0], u * np.array([math.cos(a), math.sin(a)]), atol=ds)   # joins the cut at u
    assert np.allclose(new_cut[-1], cut[-1])
    fil = new_in[new_in[:, 0] >= -u + 1e-9]                       # after A = (-u, 0): the fillet
    assert np.allclose(new_in[new_in[:, 0] < -u - 1e-9][-5:, 1], 0.0)   # on the wall before A
    C = np.array([-u, rho])                                       # the fillet's centre
    assert np.allclose(np.hypot(*(fil - C).T), rho, atol=2 * ds)
    d_end = new_in[-1] - new_in[-2]
    assert d_end / np.hypot(*d_end) @ np.array([math.cos(a), math.sin(a)]) == pytest.approx(1.0, abs=2e-3)
