"""Kim & Yang (2006) §3.2-3.3: pixel Linear_Motion, path insertion, arcs, spiral entry."""
import math

import numpy as np
import pytest
from shapely.geometry import LineString, Point, box

from cnclab.simulation import pixel
from cnclab.toolpath import constant_mrr as cm
from cnclab.toolpath.job import Job
from cnclab.toolpath.path import APPROACH_MM, Tool
from cnclab.nc import gcode
from cnclab.nc.program import write_moves


def test_eq4_reference_hand_computed():
    fz = cm.feed_per_tooth(500, 2000, 2)
    assert fz == pytest.approx(0.125)
    assert cm.reference_pixel_count(fz, 3.0, 0.3) == pytest.approx((0.125 / 0.3) * 10)
    with pytest.raises(ValueError, match="teeth"):
        cm.feed_per_tooth(500, 2000, 0)
    with pytest.raises(ValueError, match="pixel_mm"):
        cm.reference_pixel_count(0.1, 3, 0)


def test_linear_motion_counts_the_stadium_and_cut_is_idempotent():
    st = pixel.Stock.from_polygon(box(0, 0, 60, 40), 0.1)
    p0, p1, r = (10, 20), (40, 20), 5
    n = cm.linear_motion(st, p0, p1, r)
    assert n * 0.01 == pytest.approx(2 * r * 30 + math.pi * r * r, rel=0.01)
    assert cm.cut_linear(st, p0, p1, r) == n
    assert cm.linear_motion(st, p0, p1, r) == 0


def _wall_setup(res=0.3):
    """Stock cleared along y=16 (the left side of a +x pass); a pass at y=13 takes b = 3 mm on its right."""
    st = pixel.Stock.from_polygon(box(0, 0, 80, 40), res)
    cm.cut_linear(st, (-10, 16), (90, 16), 5)
    return st


def test_constant_radial_depth_needs_no_insertion():
    st = _wall_setup()
    ref = cm.reference_pixel_count(0.125, 3.0, 0.3) / 0.125
    res = cm.modify_path([np.array([[0.0, 13.0], [70.0, 13.0]])], st, 5, ref, box(-5, -5, 90, 45), step_mm=1.0)
    assert res.n_excessive == 0 and res.n_insertions == 0
    assert len(res.passes[0]) == 71


def test_excess_triggers_insertion_and_lowers_overload():
    ref = cm.reference_pixel_count(0.125, 3.0, 0.3) / 0.125
    path = np.array([[0.0, 13.0], [70.0, 13.0]])
    allowed = box(-5, -5, 90, 45)
    # cleared on the left (y=19): the pass at y=13 takes 6 mm, twice the reference width
    st = pixel.Stock.from_polygon(box(0, 0, 80, 40), 0.3)
    cm.cut_linear(st, (-10, 19), (90, 19), 5)
    seg = cm.resample_polyline(path, 1.0)
    assert all(cm.linear_motion(st, a, b, 5) > 1.15 * ref for a, b in zip(seg[:-1], seg[1:]))
    res = cm.modify_path([path], st, 5, ref, allowed, step_mm=1.0)
    assert res.n_excessive > 0 and res.n_insertions > 0
    assert res.inserted[0].any()
    # every inserted point stays in the allowed region; the path still ends at the original end
    assert all(allowed.contains(Point(q)) for q in res.passes[0])
    assert np.allclose(res.passes[0][-1], path[-1])
    # replay the modified path on a fresh stock: the overloaded share of segments drops
    st2 = pixel.Stock.from_polygon(box(0, 0, 80, 40), 0.3)
    cm.cut_linear(st2, (-10, 19), (90, 19), 5)
    p = res.passes[0]
    over = []
    for a, b in zip(p[:-1], p[1:]):
        L = np.hypot(*(b - a))
        over.append(cm.cut_linear(st2, a, b, 5) > 1.15 * ref * L if L > 0 else False)
    assert np.mean(over) < 0.2          # was 1.0 before the modification


def test_fit_arcs_recovers_a_circle_and_keeps_lines():
    t = np.linspace(0, math.pi, 40)
    arc = np.column_stack([5 + 3 * np.cos(t), 2 + 3 * np.sin(t)])
    items = cm.fit_arcs(arc, tol_mm=1e-6, short_mm=1.0)
    assert len(items) == 1 and items[0][0] == "arc" and items[0][3] is True      # CCW
    assert np.allclose(items[0][2], (5, 2))
    line = np.column_stack([np.linspace(0, 10, 11), np.zeros(11)])
    assert all(it[0] == "line" for it in cm.fit_arcs(line))


def test_program_round_trip_and_arc_geometry():
    t = np.linspace(0, -math.pi / 2, 20)                      # clockwise quarter
    p = np.vstack([[[-5.0, 10.0]], np.column_stack([10 * np.cos(t), 10 * np.sin(t)])[::-1][::-1]])
    job = Job(box(-20, -20, 20, 20), Tool(10.0), 66.42, 0.5, feed_mm_min=500, spindle_rpm=2000)
    path = cm.passes_path([p], job, tol_mm=1e-6, short_mm=2.0)
    # G0 to the clearance plane, G0 down to APPROACH_MM above the stock top, the plunge at feed, and a
    # G0 straight up at the end (as every planner comes down and lifts)
    assert path.kinds()[[0, 1, 2, -1]].tolist() == ["rapid", "rapid", "plunge", "rapid"]
    assert path.xyz[[0, 1, 2, -1], 2].tolist() == [job.clearance_z, job.top_z + APPROACH_MM, -0.5, job.clearance_z]
    assert np.allclose(path.xyz[-1, :2], path.xyz[-2, :2]) and path.cleared[1] and path.feed[2] == 500
    moves = path.to_moves()
    assert any(m.motion == "G2" for m in moves)
    text = write_moves(moves)
    again = gcode.parse_gcode(text)
    assert write_moves(again) == text
    pts, _ = gcode.to_polyline(again, max_segment=0.1)
    cut = pts[np.isclose(pts[:, 2], -0.5)]
    on_arc = cut[cut[:, 0] >= 0]
    assert np.allclose(np.hypot(on_arc[:, 0], on_arc[:, 1]), 10, atol=1e-3)


def test_spiral_entry_grows_and_stays_inside():
    region = box(0, 0, 20, 20)
    sp = cm.spiral_entry(region, (10, 18), pitch_mm=3)
    rad = np.hypot(sp[:-1, 0] - 10, sp[:-1, 1] - 10)
    assert np.all(np.diff(rad) >= -1e-9) and rad.max() <= 10 + 1e-6
    assert region.buffer(1e-9).contains(LineString(sp))
    assert np.allclose(sp[-1], (10, 18))


def test_spindle_current_is_linear_with_assumed_constants():
    i = cm.spindle_current([0, 750, 1500])
    assert i[0] == cm.ASSUMED_CURRENT_MODEL["p1_A"]
    assert i[2] - i[1] == pytest.approx(i[1] - i[0])
