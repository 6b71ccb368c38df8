"""Constant-engagement pocket clearing (cnclab.toolpath.ce_clearing): engagement, region, uncut, G-code."""
import functools
import math

import numpy as np
import pytest
import shapely
from scipy.spatial import cKDTree
from shapely.geometry import box

from cnclab.nc import gcode
from cnclab.nc.program import write_moves
from cnclab.toolpath import ce_clearing as cc
from cnclab.toolpath.evaluate import evaluate
from cnclab.toolpath.job import Job
from cnclab.toolpath.path import APPROACH_MM, Tool, ToolPath

# one xdist group (make test: --dist loadgroup): all of this module runs in one worker, so that
# the cached clearing paths (`_run`) are planned once
pytestmark = pytest.mark.xdist_group("test_ce_clearing")

R, THETA, H = 5.0, math.degrees(math.acos(1 - 3 / 5)), 0.25
POCKETS = {"plain": box(0, 0, 40, 30), "island": box(0, 0, 60, 40).difference(box(25, 15, 35, 25))}


def _job(pocket):
    return Job(pocket, Tool(2 * R), THETA, 1.0, v_c=60.0, feed_mm_min=1000.0)


@functools.cache
def _run(name, wall="gate"):
    pk = POCKETS[name]
    job = _job(pk)
    path = cc.ce_clearing(job, resolution_mm=H, wall=wall)
    return job, path, evaluate(path, job, H)


def _laps(ev):
    """Cutting samples of the laps (tag 'seed k'), their engagement and step lengths."""
    t = ev.trace
    m = t["cutting"] & (t["kind"] == "cut") & np.array([str(x).startswith("seed") for x in t["tag"]])
    return t["engagement_deg"][m], t["ds_mm"][m]


def _share(e, ds, lim):
    return float(ds[e > lim].sum() / ds.sum())


@pytest.mark.parametrize("name", ["plain", "island"])
def test_laps_hold_the_engagement(name):
    _, path, ev = _run(name)
    e, ds = _laps(ev)
    assert abs(np.nanmedian(e) - THETA) < 2.0
    # the constant-engagement laps: almost all of their length within theta + 5 deg
    assert _share(e, ds, THETA + 5) < 0.05
    # the wall limit acts inside the lap (the previous behaviour, centres clamped after the lap,
    # reaches 145 deg here and 180 deg on the Kim & Yang pocket)
    assert np.nanmax(e) < 140
    # the entry helices bore a slot: reported on their own, not in the path's statistics
    assert ev.entry_engagement_max_deg > 150 and ev.entries_helix >= 1
    assert ev.engagement_max_deg < ev.entry_engagement_max_deg


def test_clamped_laps_cut_wedges_that_the_gate_avoids():
    e_c, ds_c = _laps(_run("island", "clamp")[2])
    e_g, ds_g = _laps(_run("island")[2])
    assert np.nanmax(e_c) > np.nanmax(e_g)
    assert _share(e_c, ds_c, THETA + 5) > 0.1 > 0.05 > _share(e_g, ds_g, THETA + 5)


def test_roll_in_arcs_lower_the_share_above_theta_plus_5_and_stay_safe():
    """wall="roll-in" (the runs resuming from the wall entered by roll-in arcs tangent to them, Jacsó
    §4) on the plain pocket: less cutting length above theta + 5 deg than "gate" (the head-on links
    into those runs go), the arcs inside the allowed region, no plunge or rapid into material, and
    the pocket still cleared (what an arc skips is cut by later laps or the final pass)."""
    job, _, ev_g = _run("plain")
    _, path, ev = _run("plain", "roll-in")
    assert ev.share_above_5_pct < ev_g.share_above_5_pct
    xy = path.xyz[:, :2]
    assert shapely.contains_xy(job.allowed().buffer(1e-6), xy[:, 0], xy[:, 1]).all()
    assert ev.uncut_beyond_unreachable_mm2 < 1.0
    assert ev.plunges_into_material == 0 and ev.rapids_into_material == 0


@pytest.mark.parametrize("name", ["plain", "island"])
def test_path_stays_in_the_allowed_region_clears_the_pocket_and_is_machine_safe(name):
    """Tool centres inside the allowed region; uncut only the unreachable corners; no plunge and no
    rapid into material (re-entries plunge into the cleared region and link at depth)."""
    job, path, ev = _run(name)
    allowed = job.allowed()
    xy = path.xyz[:, :2]
    assert shapely.contains_xy(allowed.buffer(1e-6), xy[:, 0], xy[:, 1]).all()
    assert ev.uncut_beyond_unreachable_mm2 < 1.0
    assert ev.plunges_into_material == 0 and ev.rapids_into_material == 0
    z_rapid = path.xyz[path.is_kind("rapid"), 2]          # at the clearance plane or down to 0.5 mm above the top
    assert np.all((z_rapid == job.clearance_z) | (z_rapid == job.top_z + APPROACH_MM))
    assert ev.time_total_s == pytest.approx(path.time_s(job.rapid_mm_min)["total_s"])


def test_two_parts_get_two_seeds_and_cells():
    neck = box(0, 0, 30, 20).union(box(30, 8, 40, 12)).union(box(40, 0, 70, 20))
    seeds = cc.default_seeds(neck)
    assert len(seeds) == 2 and seeds[0][0] < 30 < 40 < seeds[1][0]
    cells = cc.geodesic_cells(neck, seeds)
    assert sum(c.area for c in cells) == pytest.approx(neck.area, rel=1e-6)
    assert all(c.buffer(1e-9).contains(shapely.Point(s)) for c, s in zip(cells, seeds))


def test_straight_cut_evaluates_to_nominal():
    """A straight cut at a_e = 3 mm along the top edge: engagement arccos(1 - 3/5), MRR = nominal."""
    pk = box(0, 0, 60, 30)
    y = 30 + R - 3.0
    path = ToolPath.from_segments([(np.array([[-10.0, y], [70.0, y]]), "cut", "")], z_cut=-1.0, feed=1000.0)
    ev = evaluate(path, _job(pk), 0.1)
    assert ev.engagement_p50_deg == pytest.approx(THETA, abs=0.5)
    assert ev.mrr_max_over_nominal == pytest.approx(1.0, abs=0.05)


def test_gcode_round_trip():
    _, path, _ = _run("island")
    moves = path.to_moves()
    text = write_moves(moves, header="ce test", decimals=4)
    back = gcode.parse_gcode(text)
    P = np.array([m.xyz for m in back])
    d, _ = cKDTree(path.xyz).query(P)
    assert d.max() < 1e-4                                    # every written point is on the path
    d2, _ = cKDTree(P).query(path.xyz)
    assert d2.max() < 1e-4                                   # every path point is written
    feeds = {m.feed for m in back if m.motion == "G1" and abs(m.z + 1.0) < 1e-9}
    assert feeds == {1000.0, cc.LINK_FEED_MM_MIN}            # links at the linking feed
    helix = path.is_kind("helix")
    assert helix.any() and np.all(np.diff(path.xyz[helix, 2])[:10] < 0)   # the helices go down


def test_clamp_to_region_respects_islands():
    from cnclab.toolpath.constant_engagement import clamp_to_region

    ring = box(0, 0, 10, 10).difference(box(4, 4, 6, 6))
    P = clamp_to_region([[5.0, 4.5], [12.0, 5.0], [1.0, 1.0]], ring)
    assert P.tolist() == [[5.0, 4.0], [10.0, 5.0], [1.0, 1.0]]


def test_bad_input_names_the_parameter():
    pk = box(0, 0, 40, 30)

    def job(poly=pk, r=R, theta=THETA):
        return Job(poly, Tool(2 * r), theta, 1.0, v_c=60.0, feed_mm_min=1000.0)

    with pytest.raises(ValueError, match="theta_deg"):
        cc.ce_clearing(job(theta=0.0))
    with pytest.raises(ValueError, match="tool_radius"):
        cc.ce_clearing(job(r=20.0))                      # the tool does not fit
    with pytest.raises(ValueError, match="resolution_mm"):
        cc.ce_clearing(job(), resolution_mm=0)
    with pytest.raises(ValueError, match="seeds"):
        cc.ce_clearing(job(), seeds=[(1.0, 1.0)])
    with pytest.raises(ValueError, match="pocket"):
        cc.ce_clearing(job(poly="not a polygon"))
    with pytest.raises(ValueError, match="Job"):
        cc.ce_clearing(pk)
    with pytest.raises(ValueError, match="entry_radius_mm"):
        cc.helical_entry((0, 0), 4.0, R)
    with pytest.raises(ValueError, match="wall"):
        cc.ce_clearing(job(), wall="slide")
    with pytest.raises(ValueError, match="seed_clearance_ratio"):
        cc.default_seeds(pk, 1.5)
    with pytest.raises(TypeError, match="'wal'"):                  # not a ClearingSettings field
        cc.ce_clearing(job(), wal="gate")
    with pytest.raises(TypeError, match="'a_p'"):                  # cutting data come from the job only
        cc.ce_clearing(job(), a_p=2.0)
    with pytest.raises(ValueError, match="resolution_mm"):          # the same check through the dataclass
        cc.ce_clearing(job(), cc.ClearingSettings(resolution_mm=-1.0))


def test_keyword_options_and_settings_objects_plan_the_same_path():
    """The keyword options are the fields of ClearingSettings: both spellings give one path; the cutting
    level, feeds and planes are the job's."""
    job = Job(box(0, 0, 24, 18), Tool(6.0), 60.0, 2.0, top_z=1.0, clearance_z=6.0, v_c=60.0, feed_mm_min=800.0)
    a = cc.ce_clearing(job, resolution_mm=0.25, max_laps=3)
    b = cc.ce_clearing(job, cc.ClearingSettings(resolution_mm=0.25, max_laps=3))
    assert np.array_equal(a.xyz, b.xyz) and a.kinds().tolist() == b.kinds().tolist()
    assert a.xyz[:, 2].min() == pytest.approx(-1.0)                 # top_z - a_p
    assert a.xyz[:, 2].max() == pytest.approx(6.0)                  # the job's clearance plane
    assert np.nanmax(a.feed[a.is_kind("cut")]) == pytest.approx(800.0)


def _shares(path, job):
    """Share (%) of the cutting length above theta + 5 deg, whole path and per part, at r / 20."""
    ev = evaluate(path, job, job.tool_radius / 20)
    t = ev.trace
    e = np.nan_to_num(np.asarray(t["engagement_deg"], float), nan=-1.0)
    cut, ds = np.asarray(t["cutting"], bool), np.asarray(t["ds_mm"], float)
    tag = np.asarray(t["tag"], object)
    over = cut & (e > job.theta_deg + 5)
    part = {"cleanup": np.array(["cleanup" in g for g in tag]), "linkcut": np.array(["linkcut" in g for g in tag])}
    L = ds[cut].sum()
    return ev, {k: 100 * ds[over & m].sum() / L for k, m in part.items()}


def test_link_limit_and_offset_rings_lower_the_engagement_above_theta():
    """issue 28 (constant-engagement strategy): on a 28 x 18 mm rectangle (D6, theta 60 deg) the runs
    resuming from the wall that no roll-in arc reaches were linked straight into the material, and the
    one final contour pass cut the corners' wedges. With ``link_limit_deg`` (such runs start where a
    link reaches them within theta + 10) and ``cleanup_step_mm`` (contour-parallel passes 0.375 mm
    apart over what the laps leave) the cutting length above theta + 5 deg drops -- measured: links
    2.15 -> 0.61 %, cleanup 1.06 -> 0.72 %, whole path 3.61 -> 1.44 % -- still with nothing plunged
    or rapid into material and only the corner cusps uncut."""
    job = Job(box(0, 0, 28, 18), Tool(6.0), 60.0, 1.0, v_c=100, f_z=0.05)
    before = cc.ce_clearing(job, resolution_mm=0.1, wall="roll-in")
    after = cc.ce_clearing(job, resolution_mm=0.1, wall="roll-in", link_limit_deg=10.0,
                             cleanup_step_mm=0.25 * 3.0 * (1 - math.cos(math.radians(60.0))))
    ev0, p0 = _shares(before, job)
    ev1, p1 = _shares(after, job)
    assert ev1.share_above_5_pct < 0.6 * ev0.share_above_5_pct
    assert p1["linkcut"] < 0.5 * p0["linkcut"] and p1["cleanup"] < p0["cleanup"]
    assert ev1.plunges_into_material == 0 and ev1.rapids_into_material == 0
    assert ev1.uncut_beyond_unreachable_mm2 < 1.0


@pytest.mark.parametrize("name", ["plain", "island"])
def test_reentry_plunges_are_tagged_cleared_and_the_program_counts_none(name):
    """Every vertical plunge below the stock top follows a jump into the cleared region: the planner
    flags it ``cleared`` (written ``(cnclab:cleared/1)``), the static checker counts no plunge into material,
    and the dixel evaluator (independently) finds none either."""
    from cnclab.nc.program import check_program, write_program

    job, path, ev = _run(name)
    down = np.r_[False, np.diff(path.xyz[:, 2]) < 0]
    pl = path.is_kind("plunge") & down & (path.xyz[:, 2] < job.top_z - 1e-9)
    assert pl.sum() >= 1 and path.cleared[pl].all()
    text = write_program(path, job)
    chk = check_program(text, clearance_z=job.clearance_z, top_z=job.top_z)
    assert chk.plunges_into_material == 0 and chk.entries["plunge"] >= pl.sum()
    assert text.count("(cnclab:cleared/1)") >= pl.sum()
    assert ev.plunges_into_material == 0


def test_untagged_plunge_is_counted_by_the_checker():
    """The flag is what the writer reads: the same path with the flags removed (tags kept) counts each
    plunge."""
    from cnclab.nc.program import check_program, write_program

    job, path, _ = _run("island")
    bare = ToolPath.build(path.xyz, kind=path.kinds(), tag=path.tag, feed=path.feed, spindle=path.spindle,
                          tool=path.tool, cleared=path.cleared & path.is_kind("rapid"))   # the plunges' flags removed
    down = np.r_[False, np.diff(path.xyz[:, 2]) < 0]
    n = int((path.is_kind("plunge") & down & (path.xyz[:, 2] < job.top_z - 1e-9)).sum())
    chk = check_program(write_program(bare, job), clearance_z=job.clearance_z, top_z=job.top_z)
    assert chk.plunges_into_material == n >= 1
