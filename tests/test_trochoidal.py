"""Trochoid generators, the exact front engagement vs the dixel simulation, the CE iteration with
explicit roll-in / roll-out (Jacsó 2021 §3.4, §4)."""
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cnclab.toolpath import trochoidal as tr


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
    assert m["max_engagement_deg"] >= sel.engagement_deg.max() - 1e-9


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
    """Cut <= theta + 5; roll-in rises monotonically from ~0 to theta; roll-out drops; links cut nothing."""
    _, p, df, m = ce_slot
    assert m["max_eng_cut_deg"] <= 65.0 and m["max_eng_roll-out_deg"] <= 65.0
    assert m["max_eng_link_deg"] < 1.0 and m["link_removed_mm2"] < 1e-3
    for k in (2, 3):
        e = df[(df.period == k) & (df.kind == "roll-in")].engagement_deg.to_numpy()
        assert e[0] < 1.0 and e[-1] == pytest.approx(60.0, abs=5.0) and e.max() <= 65.0
        assert np.all(np.maximum.accumulate(e) - e <= 3.0)          # monotone up to the dixel noise
        c = df[(df.period == k) & (df.kind == "cut")].engagement_deg.to_numpy()
        assert np.median(c) == pytest.approx(60.0, abs=2.0)
        o = df[(df.period == k) & (df.kind == "roll-out")].engagement_deg.to_numpy()
        assert o[-1] < 1.0


def test_ce_beats_circular_at_same_engagement_limit(ce_slot):
    _, p, _, m = ce_slot
    s_circ = tr.circle_front_step(60.0, 12.0, 3.0)          # exact front-point step of the circle
    assert p.info["step"] > s_circ
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
