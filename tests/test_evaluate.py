"""The one evaluator: hand-computed cases (full slot, plunge, rapid through stock, air cut, levels)
and invariants (time = sum of parts = the program's length / feed)."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import box

from cnclab.toolpath.evaluate import Evaluation, evaluate, evaluate_engagement, weighted_percentile
from cnclab.toolpath.job import Job
from cnclab.toolpath.path import Tool, ToolPath

H = 0.05
F = 300.0


def _job(depth=None, a_p=2.0, theta=90.0):
    return Job(box(0, 0, 40, 20), Tool(6.0, flutes=2), theta, a_p, depth=depth, v_c=100, feed_mm_min=F)


def _slot(z=-2.0, y=10.0, entry="plunge", x0=-5.0, x1=45.0):
    return ToolPath.build([[x0, y, 5], [x0, y, z], [x1, y, z], [x1, y, 5]],
                          kind=["rapid", entry, "cut", "retract"], feed=F)


def test_full_slot_hand_computed():
    """Straight slot through a 40 x 20 pocket, D = 6, a_p = 2, v_f = 300: engagement 180 deg, MRR =
    a_p D v_f, so MRR / nominal = D / a_e = 6 / 3 at theta = 90 deg (tolerance 2 %: one dixel row
    of 0.05 mm on a 6 mm chord per window); uncut = 40 x 14 (+- h x wall length)."""
    job = _job()
    ev = evaluate(_slot(), job, H)
    assert ev.engagement_p50_deg == pytest.approx(180, abs=0.5)
    assert ev.mrr_max_over_nominal == pytest.approx(2.0, rel=0.02)
    assert ev.cut_length_mm == pytest.approx(50.0) and ev.entry_length_mm == pytest.approx(7.0)
    assert ev.time_cut_s == pytest.approx(60 * 50 / F) and ev.time_entry_s == pytest.approx(60 * 7 / F)
    assert ev.time_retract_s == pytest.approx(60 * 7 / F)
    assert (ev.entries_plunge, ev.plunges_into_material, ev.rapids_into_material, ev.retracts) == (1, 0, 0, 1)
    assert ev.uncut_area_mm2 == pytest.approx(40 * 14, abs=H * 80)
    corners = 4 * 9 * (1 - math.pi / 4)
    assert ev.uncut_beyond_unreachable_mm2 == pytest.approx(40 * 14 - corners, abs=H * 80)
    # air: centre x < -3 (disc not yet in the stock) and x > 40 (the front crescent has left it); the
    # crescent near x = 40 shrinks below the air tolerance 0.5 h^2 a few steps early: +- 0.5 mm
    assert ev.air_cut_length_mm == pytest.approx(2.0 + 5.0, abs=0.5)
    mid = (ev.trace["x"] > 5) & (ev.trace["x"] < 35) & ev.trace["cutting"]
    assert np.nanmedian(ev.trace["mrr_mm3_min"][mid]) == pytest.approx(2.0 * 6.0 * F, rel=0.02)


def test_plunge_into_stock_is_counted_and_ramp_is_not():
    job = _job()
    ev = evaluate(_slot(x0=20.0), job, H)                        # plunge at (20, 10) inside the stock
    assert ev.plunges_into_material == 1
    assert ev.plunge_swept_area_mm2 == pytest.approx(math.pi * 9, rel=0.02)
    ramp = ToolPath.build([[10, 10, 5], [10, 10, 0], [20, 10, -2], [35, 10, -2], [35, 10, 5]],
                          kind=["rapid", "plunge", "ramp", "cut", "retract"], feed=F)
    ev2 = evaluate(ramp, job, H)
    assert ev2.plunges_into_material == 0 and ev2.entries_ramp == 1 and ev2.entries_plunge == 1
    assert ev2.entry_engagement_max_deg > 90                       # the ramp cuts a slot on its way down


def test_rapid_through_stock_is_counted():
    job = Job(box(0, 0, 40, 20), Tool(6.0), 90.0, 2.0, start_hole=(5.0, 10.0, 8.0), v_c=100, feed_mm_min=F)
    p = ToolPath.build([[5, 10, 5], [5, 10, -1], [35, 10, -1], [35, 10, 5]],
                       kind=["rapid", "plunge", "rapid", "retract"], feed=F)
    ev = evaluate(p, job, H)
    assert (ev.rapids_into_material, ev.plunges_into_material) == (1, 0)     # plunge into the drilled hole
    p2 = ToolPath.build([[-5, 10, 5], [45, 10, 5]], kind=["rapid", "rapid"])
    assert evaluate(p2, job, H).rapids_into_material == 0           # at clearance: air


def test_second_pass_is_air_cut_and_levels():
    job = _job()
    twice = ToolPath.concat([_slot(), _slot()])
    ev = evaluate(twice, job, H)
    assert ev.air_cut_length_mm == pytest.approx(7.0 + 50.0, abs=0.5)
    deep = _job(depth=4.0)                                        # two levels of 2 mm
    one = evaluate(_slot(), deep, H)
    assert one.uncut_area_mm2 == pytest.approx(40 * 14 + 40 * 20, abs=H * 160)
    both = evaluate(ToolPath.concat([_slot(), _slot(z=-4.0)]), deep, H)
    assert both.uncut_area_mm2 == pytest.approx(2 * 40 * 14, abs=H * 160)
    full = evaluate(_slot(z=-4.0), deep, H)                       # full depth in one go: twice the volume
    assert full.mrr_max_over_nominal == pytest.approx(4.0, rel=0.02)


@pytest.mark.parametrize("below_um, cuts_slab_2", [(0.0, False), (0.05, False), (0.5, False), (10.0, True)])
def test_a_pass_at_a_level_as_written_does_not_cut_the_slab_below(below_um, cuts_slab_2):
    """Levels of 7.475 / 3 = 2.491667 mm: a program writes the first floor as Z-2.4917 (0.033 um
    lower, 4 decimals) or Z-2.492 (0.33 um, 3 decimals). A second pass along a slot cut at the first
    level, written that way, runs in the slot (air); read 33 nm into the slab below it was cut at full
    width there (180 deg, the fuzz campaign's adaptive floor circles). 10 um below is a cut."""
    job = Job(box(0, 0, 40, 20), Tool(6.0, flutes=2), 90.0, 2.99, depth=7.475, v_c=100, feed_mm_min=F)
    z1 = job.levels()[0]
    assert z1 == pytest.approx(-7.475 / 3)
    ev = evaluate(ToolPath.concat([_slot(z=z1), _slot(z=z1 - below_um * 1e-3)]), job, H)
    second = ev.trace["move"] >= 4
    cut = second & ev.trace["cutting"]
    assert cut.any() == cuts_slab_2
    if cuts_slab_2:                           # a real cut below the level: the full slot, at 180 deg
        assert np.nanmax(ev.trace["engagement_deg"][cut]) == pytest.approx(180, abs=0.5)
    else:
        assert ev.engagement_max_deg == pytest.approx(180, abs=0.5)      # the first pass's slot only
        assert ev.air_cut_length_mm == pytest.approx(7.0 + 50.0, abs=0.5)


def test_summary_table_and_schema():
    ev = evaluate(_slot(), _job(), 0.1)
    d = ev.to_dict()
    assert "trace" not in d and d["theta_deg"] == 90.0
    tab = ev.summary_table()
    assert list(tab.columns) == ["metric", "value", "unit"] and len(tab) == len(d)
    assert dict(zip(tab.metric, tab.unit))["time_total_s"] == "s"
    with pytest.raises(ValueError, match="resolution_mm"):
        evaluate(_slot(), _job(), 0.0)
    with pytest.raises(TypeError):
        evaluate([[0, 0]], _job())


def test_weighted_percentile():
    assert weighted_percentile([5, 1, 3], [1, 1, 1], 50) == 3
    assert weighted_percentile([1, 100], [99, 1], 95) == 1
    assert math.isnan(weighted_percentile([], [], 50))


@settings(max_examples=15, deadline=None)
@given(st.lists(st.tuples(st.floats(-5, 45), st.floats(-5, 25), st.sampled_from(["rapid", "cut", "link"])),
                min_size=2, max_size=6))
def test_time_is_sum_of_parts(moves):
    """time_total = cut + link + rapid + entry + retract, and equals length / feed per move."""
    pts = [[-5, -5, 5], [-5, -5, -2]] + [[x, y, -2] for x, y, _ in moves] + [[moves[-1][0], moves[-1][1], 5]]
    kinds = ["rapid", "plunge"] + [k for _, _, k in moves] + ["retract"]
    p = ToolPath.build(pts, kind=kinds, feed=F)
    ev = evaluate(p, _job(), 0.2)
    parts = ev.time_cut_s + ev.time_link_s + ev.time_rapid_s + ev.time_entry_s + ev.time_retract_s
    assert ev.time_total_s == pytest.approx(parts, rel=1e-12)
    L = p.segment_lengths()
    rate = np.where(p.is_kind("rapid"), _job().rapid_mm_min, F)
    assert ev.time_total_s == pytest.approx(float(np.sum(60 * L / rate)), rel=1e-12)
    assert isinstance(ev, Evaluation)


def test_engagement_only_evaluation_skips_gouge_and_uncut_and_nothing_else():
    # evaluate_engagement (the adaptive planner's check of its promise): the same engagement, counts
    # and times; gouge and uncut beyond the corners not measured (NaN, gouges -1), rapids outside the
    # allowed region still counted. The slot runs in through the pocket's x = 0 and out through its x = 40 wall
    job = _job()
    p = _slot(x0=-5.0, y=10.0)
    full, part = evaluate(p, job, H), evaluate_engagement(p, job, H)
    for f in ("engagement_p50_deg", "engagement_p95_deg", "engagement_max_deg", "share_above_5_pct",
              "plunges_into_material", "rapids_into_material", "time_total_s", "uncut_area_mm2"):
        assert getattr(part, f) == getattr(full, f), f
    assert np.array_equal(part.trace["engagement_deg"], full.trace["engagement_deg"], equal_nan=True)
    assert full.uncut_beyond_unreachable_mm2 > 0 and math.isnan(part.uncut_beyond_unreachable_mm2)
    assert full.wall_gouge_max_mm > 1.0 and full.gouges >= 1
    assert math.isnan(part.wall_gouge_max_mm) and part.gouges == -1
    out = ToolPath.build([[5, 10, 5], [5, 10, -1], [5, -5, -1], [5, -5, 5]],
                         kind=["rapid", "plunge", "rapid", "retract"], feed=F)     # a G0 through the wall
    assert evaluate_engagement(out, job, H).rapids_into_material == 1


@pytest.mark.parametrize("h", [0.05, 0.25, 0.5])
def test_an_arc_round_an_island_corner_reads_no_gouge_at_any_resolution(h):
    """A G2 of radius exactly r about the corner of a square island (the tool goes round it touching
    it) gouges nothing. Sampled by arc length (the analyzer's sampling) on chords as long as the
    step, it read up to step^2 / (8 r): 0.8 um at h = 0.25 and 1.6 um at 0.5 on r = 5 (session 21's
    fuzz campaign: a written zig-zag program read as a 1.5 um gouge). Tolerance 0.2 um: the
    samples' 0.1 um (evaluate.ARC_SAGITTA_MM) and the float noise."""
    r = 5.0
    island = box(40, 40, 50, 50)
    job = Job(box(0, 0, 100, 100).difference(island), Tool(2 * r), 60.0, 1.0, v_c=100, f_z=0.05)
    c = (50.0, 50.0)                                    # the island's top-right corner
    p = ToolPath.build([[45, 55, 5], [45, 55, -1], [50, 55, -1], [55, 50, -1], [55, 45, -1]],
                       kind=["rapid", "plunge", "cut", "cut", "cut"], feed=300,
                       arc=[0, 0, 0, 2, 0], arc_center=[[np.nan] * 2] * 3 + [list(c), [np.nan] * 2])
    ev = evaluate(p, job, h, sampling="arc_length")
    assert ev.wall_gouge_max_mm < 2e-4 and ev.gouges == 0
