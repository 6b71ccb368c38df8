"""The vector-stock engagement (cnclab.simulation.vector) against hand-derived cases: a slot (180 deg),
a straight side cut (acos(1 - a_e / r)), a concave and a convex arc in steady state (Jacsó's Thesis I
formulas, cnclab.geometry.engagement), a skin thinner than the chip threshold (no contact), and the
dixel evaluator converging to it as its dixel shrinks.

Tolerances: the rim is sampled at 3601 points (0.05 deg apart) and the discs are polygons of 64
segments a quarter (sagitta r (1 - cos(pi / 256)) = 0.04 um at r 5 mm): 0.1 deg on a clean arc; the
opening that drops material thinner than 2 um moves the rim of a boundary by nothing on straight
edges and arcs wider than 1 um."""
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from shapely.geometry import Point, box

from cnclab.geometry.engagement import theta_concave, theta_convex, theta_straight
from cnclab.simulation.vector import vector_engagement


def test_a_slot_is_engaged_over_the_whole_front_half():
    xy = np.c_[np.linspace(-5, 25, 61), np.full(61, 5.0)]
    assert vector_engagement(box(0, 0, 20, 10), xy, [20, 30, 40], 2.0) == pytest.approx([180.0] * 3)


@settings(max_examples=15, deadline=None)
@given(r=st.floats(1.0, 6.0), frac=st.floats(0.05, 1.9))
def test_a_straight_side_cut_reads_acos_of_its_radial_depth(r, frac):
    a_e = frac * r
    xy = np.c_[np.linspace(-2 * r, 20, 80), np.full(80, 20.0 + r - a_e)]       # material below y = 20
    got = vector_engagement(box(-5 * r, 0, 30, 20), xy, [60], r)[0]
    assert got == pytest.approx(float(theta_straight(a_e, r)), abs=0.1)


@pytest.mark.parametrize("kind", ["concave", "convex"])
def test_an_arc_in_steady_state_reads_the_thesis_i_angle(kind):
    """The cleared region's boundary a circle of radius rho (concave: cleared inside, the tool moves on
    the circle of radius rho + s - r; convex: a boss of radius rho, the tool on rho - s + r)."""
    r, s, rho = 3.0, 1.2, 10.0
    if kind == "concave":
        stock, R = box(-40, -40, 40, 40).difference(Point(0, 0).buffer(rho, quad_segs=512)), rho + s - r
        expect = theta_concave(s, rho, r)
    else:
        stock, R = Point(0, 0).buffer(rho, quad_segs=512), rho - s + r
        expect = theta_convex(s, rho, r)
    # counter-clockwise, 0.9 of the turn swept before the sample; the front is the chord to the sample,
    # the tangent turned back by half a step (0.024 deg at 4000 samples)
    a = np.linspace(0.0, 1.2 * math.pi, 4000)
    xy = np.c_[R * np.cos(a), R * np.sin(a)]
    assert vector_engagement(stock, xy, [3600], r)[0] == pytest.approx(float(expect), abs=0.1)


def test_a_skin_thinner_than_the_chip_threshold_is_no_contact():
    """A 1 um wall skin the tool runs along (its rim tangent to the wall): no chip of 2 um (the
    default threshold); with every material counted, the arc of the rim inside the skin,
    acos(1 - t / r) = 1.48 deg (r 3 mm, t 1 um) -- where a dixel of h reads up to acos(1 - h / r)."""
    skin = box(0, 19.999, 30, 20.0)
    xy = np.c_[np.linspace(-5, 25, 61), np.full(61, 20.0 - 3.0)]
    assert vector_engagement(skin, xy, [40], 3.0)[0] == 0.0
    assert vector_engagement(skin, xy, [40], 3.0, min_chip_mm=0.0)[0] == pytest.approx(math.degrees(math.acos(1 - 0.001 / 3)), abs=0.1)


def test_cutting_flags_keep_a_jump_from_cutting():
    """Two runs: a slot along y = 5, then (after a jump through air) a sample beside it; without the
    flags the jump itself would sweep the stock."""
    first = np.c_[np.linspace(-5, 25, 31), np.full(31, 5.0)]
    xy = np.r_[first, [[10.0, 25.0], [10.0, 24.0], [10.0, 23.0]]]     # a jump to y = 25, then down
    flags = np.r_[np.ones(31, bool), False, True, True]
    with_flags = vector_engagement(box(0, 0, 20, 30), xy, [33], 2.0, cutting=flags)[0]
    without = vector_engagement(box(0, 0, 20, 30), xy, [33], 2.0)[0]
    assert with_flags == pytest.approx(180.0) and without < 170.0


@pytest.mark.parametrize("bad, match", [({"xy": np.zeros((1, 2))}, "N >= 2"), ({"tool_radius": 0.0}, "tool_radius"),
                                        ({"at": [0]}, "no step before"), ({"cutting": np.ones(3, bool)}, "one flag")])
def test_bad_arguments_are_named(bad, match):
    kw = {"polygon": box(0, 0, 10, 10), "xy": np.c_[np.arange(5.0), np.zeros(5)], "at": [2], "tool_radius": 1.0} | bad
    with pytest.raises(ValueError, match=match):
        vector_engagement(**kw)


def test_the_dixel_evaluator_agrees_on_a_side_cut():
    """A pass 1 mm beside an earlier one along the wall: the evaluator at r / 10, r / 20, r / 40 and
    the vector stock read the same sample within 0.5 deg (two independent models of one cut)."""
    from cnclab.toolpath.evaluate import evaluate
    from cnclab.toolpath.job import Job
    from cnclab.toolpath.path import Tool, ToolPath

    r = 2.0
    job = Job(box(0, 0, 30, 12), Tool(2 * r), 60.0, 1.0, feed_mm_min=300.0, spindle_rpm=8000.0)
    y1, y2 = 12 - r, 12 - r - 1.0                        # a pass along the wall, then one 1 mm lower
    pts = [[-5, y1, 5], [-5, y1, -1], [35, y1, -1], [35, y2, -1], [-5, y2, -1], [-5, y2, 5]]
    path = ToolPath.build(pts, kind=["rapid", "plunge", "cut", "cut", "cut", "retract"], feed=300.0)
    errs = []
    for h in (r / 10, r / 20, r / 40):
        t = evaluate(path, job, h).trace
        k = int(np.argmin(np.abs(t["x"] - 15.0) + np.abs(t["y"] - y2) + 100 * (t["z"] > -0.5)))
        xy = np.c_[t["x"], t["y"]]
        exact = vector_engagement(job.polygon, xy, [k], r, cutting=t["z"] < -0.5)[0]
        errs.append(abs(float(t["engagement_deg"][k]) - exact))
    assert exact == pytest.approx(float(theta_straight(1.0, r)), abs=0.1)
    assert max(errs) < 0.5


def test_the_audit_finds_a_peak_the_dixel_reports_and_the_random_draw_is_seeded():
    """cnclab.toolpath.vector_check.vector_audit on a two-pass program (a pass along the wall, then one
    1 mm beside it, then a slot across both): the peak is the slot's 180 deg on both stocks; the
    random samples agree within 1 deg on these plain cuts (the pass starts: the evaluator's lag); the
    same seed draws the same samples, another seed others."""
    from cnclab.toolpath.evaluate import evaluate
    from cnclab.toolpath.job import Job
    from cnclab.toolpath.path import Tool, ToolPath
    from cnclab.toolpath.vector_check import vector_audit

    job = Job(box(0, 0, 30, 30), Tool(4.0), 60.0, 1.0, feed_mm_min=300.0, spindle_rpm=8000.0)
    pts = [[-5, 28, 5], [-5, 28, -1], [35, 28, -1], [35, 27, -1], [-5, 27, -1], [-5, 10, -1], [35, 10, -1], [35, 10, 5]]
    p = ToolPath.build(pts, kind=["rapid", "plunge", "cut", "cut", "cut", "link", "cut", "retract"], feed=300.0)
    ev = evaluate(p, job, 0.1)
    a = vector_audit(ev, job, n_peaks=2, n_random=60, seed=3)
    assert a["dixel_max"] == pytest.approx(180.0, abs=1.0) and a["vector_peak_max"] == pytest.approx(180.0, abs=0.1)
    assert len(a["peaks_vector"]) == 2 and a["n_random"] == 60
    assert a["random_diff_max"] < 1.0 and a["random_diff_min"] > -1.0
    b, c = (vector_audit(ev, job, n_peaks=0, n_random=60, seed=s) for s in (3, 4))
    assert b["random_diff_max"] == a["random_diff_max"] and (c["random_diff_max"], c["random_diff_min"]) != \
        (a["random_diff_max"], a["random_diff_min"])
