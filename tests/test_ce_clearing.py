"""Constant-engagement pocket clearing (cnclab.toolpath.ce_clearing): engagement, region, uncut, G-code."""
import functools
import math

import numpy as np
import pytest
import shapely
from scipy.spatial import cKDTree
from shapely.geometry import box

from cnclab.toolpath import ce_clearing as cc
from cnclab.nc import gcode

R, THETA, H = 5.0, math.degrees(math.acos(1 - 3 / 5)), 0.25
POCKETS = {"plain": box(0, 0, 40, 30), "island": box(0, 0, 60, 40).difference(box(25, 15, 35, 25))}


@functools.cache
def _run(name, wall="gate"):
    pk = POCKETS[name]
    path = cc.ce_clearing(pk, R, THETA, resolution_mm=H, wall=wall)
    table, summary = cc.evaluate_path(path, pk, R, THETA, resolution_mm=H)
    return pk, path, table, summary


@pytest.mark.parametrize("name", ["plain", "island"])
def test_laps_hold_the_engagement(name):
    _, path, table, s = _run(name)
    lap = table[table.cutting & (table.kind == "cut")]
    assert abs(np.nanmedian(lap.engagement_deg) - THETA) < 2.0
    # the constant-engagement laps: almost all of their length within theta + 5 deg
    assert s["share_above_cut"] < 0.05
    # the wall limit acts inside the lap (measured 110 / 138 deg; the previous behaviour, centres
    # clamped after the lap, reaches 145 deg here and 180 deg on the Kim & Yang pocket)
    assert s["max_engagement_cut_deg"] < 140
    # the entry slots (a helix bore simulated at full depth): reported on their own, not hidden ...
    assert s["max_engagement_entry_deg"] > 150
    # ... and left out of the path's engagement statistics
    others = [s[f"max_engagement_{k}_deg"] for k in ("cut", "cleanup", "linkcut")]
    assert s["max_engagement_deg"] == pytest.approx(np.nanmax(others))


def test_clamped_laps_cut_wedges_that_the_gate_avoids():
    s_clamp = _run("island", "clamp")[3]
    s_gate = _run("island")[3]
    assert s_clamp["max_engagement_cut_deg"] > s_gate["max_engagement_cut_deg"]
    assert s_clamp["share_above_cut"] > 0.1 > 0.05 > s_gate["share_above_cut"]      # measured 0.14 / 0.04


@pytest.mark.parametrize("name", ["plain", "island"])
def test_path_stays_in_the_allowed_region_and_clears_the_pocket(name):
    pk, path, _, s = _run(name)
    allowed = pk.buffer(-R, quad_segs=64)
    feed = path.kinds != "rapid"
    assert shapely.contains_xy(allowed.buffer(1e-6), path.points[feed, 0], path.points[feed, 1]).all()
    assert s["uncut_area_mm2"] - s["unreachable_area_mm2"] < 1.0
    assert s["uncut_area_mm2"] >= s["unreachable_area_mm2"] - 0.1


def test_two_parts_get_two_seeds_and_cells():
    neck = box(0, 0, 30, 20).union(box(30, 8, 40, 12)).union(box(40, 0, 70, 20))
    seeds = cc.default_seeds(neck)
    assert len(seeds) == 2 and seeds[0][0] < 30 < 40 < seeds[1][0]
    cells = cc.geodesic_cells(neck, seeds)
    assert sum(c.area for c in cells) == pytest.approx(neck.area, rel=1e-6)
    assert all(c.buffer(1e-9).contains(shapely.Point(s)) for c, s in zip(cells, seeds))


def test_straight_cut_evaluates_to_nominal():
    pk = box(0, 0, 60, 30)
    y = 30 + R - 3.0                       # a_e = 3 mm along the top edge
    P = np.c_[np.linspace(-10, 70, 401), np.full(401, y)]
    path = cc.ClearingPath(P, np.array(["entry"] + ["cut"] * 400, dtype=object), np.zeros(401, int))
    with pytest.raises(ValueError, match="pocket"):
        cc.evaluate_path(path, box(0, 0, 0, 0), R, THETA)
    T, s = cc.evaluate_path(path, pk, R, THETA, resolution_mm=0.1)
    mid = T[(T.x > 10) & (T.x < 50)]
    assert np.median(mid.engagement_deg) == pytest.approx(THETA, abs=0.5)
    assert s["max_mrr_over_nominal"] == pytest.approx(1.0, abs=0.05)


def test_times_use_cutting_link_and_rapid_feeds():
    pk = box(0, 0, 60, 30)
    y = 30 + R - 3.0
    go = np.c_[np.linspace(0, 40, 161), np.full(161, y)]                  # cut 40 mm at a_e = 3 ...
    P = np.vstack([go, go[::-1][1:], [[20.0, y]], [[50.0, y]]])           # ... back in air, then a rapid jump
    K = np.array(["cut"] * 161 + ["link"] * 160 + ["rapid", "rapid"], dtype=object)
    path = cc.ClearingPath(P, K, np.zeros(len(P), int))
    _, s = cc.evaluate_path(path, pk, R, THETA, resolution_mm=0.25, feed_mm_min=500.0, retract_mm=5.5)
    assert s["cutting_length_mm"] == pytest.approx(40.0, abs=0.3)
    assert s["linking_length_mm"] == pytest.approx(40.0, abs=0.3)
    assert s["cutting_time_min"] == pytest.approx(s["cutting_length_mm"] / 500.0)
    assert s["linking_time_min"] == pytest.approx(s["linking_length_mm"] / cc.LINK_FEED_MM_MIN)
    assert s["n_rapids"] == 1 and s["rapid_length_mm"] == pytest.approx(30.0 + 20.0)
    assert s["rapid_time_min"] == pytest.approx((50.0 + 5.5) / cc.RAPID_MM_MIN)
    assert s["time_one_feed_min"] == pytest.approx((s["cutting_length_mm"] + s["linking_length_mm"]) / 500.0, rel=1e-3)
    _, s2 = cc.evaluate_path(path, pk, R, THETA, resolution_mm=0.25, feed_mm_min=500.0, link_feed_mm_min=3000.0)
    assert s2["linking_time_min"] == pytest.approx(s["linking_time_min"] / 2)
    with pytest.raises(ValueError, match="link_feed_mm_min"):
        cc.evaluate_path(path, pk, R, THETA, link_feed_mm_min=0.0)


def test_gcode_round_trip():
    _, path, _, _ = _run("island")
    moves = cc.to_moves(path, z_cut=-0.5, z_clear=5.0, feed=500.0, spindle=2000.0, link_feed=1500.0)
    text = gcode.write_gcode(moves, header="ce test", decimals=4)
    back = gcode.parse_gcode(text)
    cut = np.array([[m.x, m.y] for m in back if abs(m.z + 0.5) < 1e-9])
    d, _ = cKDTree(path.points).query(cut)
    assert d.max() < 1e-4                                    # every written point is on the path
    d2, _ = cKDTree(cut).query(path.points[1:])
    assert d2.max() < 1e-4                                   # every path point is written
    feeds = {m.feed for m in back if m.motion == "G1" and abs(m.z + 0.5) < 1e-9}
    assert feeds == {500.0, 1500.0}                          # links at the linking feed
    ramp = [m.z for m in back if m.z < 0 and m.z > -0.5]
    assert ramp and np.all(np.diff(ramp[: len(ramp) // 2]) <= 1e-12)   # helical ramp goes down


def test_clamp_to_region_respects_islands():
    from cnclab.toolpath.constant_engagement import clamp_to_region

    ring = box(0, 0, 10, 10).difference(box(4, 4, 6, 6))
    P = clamp_to_region([[5.0, 4.5], [12.0, 5.0], [1.0, 1.0]], ring)
    assert P.tolist() == [[5.0, 4.0], [10.0, 5.0], [1.0, 1.0]]


def test_bad_input_names_the_parameter():
    pk = box(0, 0, 40, 30)
    with pytest.raises(ValueError, match="theta_deg"):
        cc.ce_clearing(pk, R, 0.0)
    with pytest.raises(ValueError, match="tool_radius"):
        cc.ce_clearing(pk, -1.0, THETA)
    with pytest.raises(ValueError, match="tool_radius"):
        cc.ce_clearing(pk, 20.0, THETA)                      # the tool does not fit
    with pytest.raises(ValueError, match="resolution_mm"):
        cc.ce_clearing(pk, R, THETA, resolution_mm=0)
    with pytest.raises(ValueError, match="seeds"):
        cc.ce_clearing(pk, R, THETA, seeds=[(1.0, 1.0)])
    with pytest.raises(ValueError, match="pocket"):
        cc.ce_clearing("not a polygon", R, THETA)
    with pytest.raises(ValueError, match="entry_radius_mm"):
        cc.helical_entry((0, 0), 4.0, R)
    with pytest.raises(ValueError, match="wall"):
        cc.ce_clearing(pk, R, THETA, wall="slide")
    with pytest.raises(ValueError, match="seed_clearance_ratio"):
        cc.default_seeds(pk, 1.5)
    _, path, _, _ = _run("plain")
    with pytest.raises(ValueError, match="z_cut"):
        cc.to_moves(path, z_cut=1.0, z_clear=5.0, feed=500, spindle=2000)
