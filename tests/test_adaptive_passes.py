"""The adaptive planner's pass loop on two corpus jobs where it used to lift and enter again
(issues 29 / 24: program time against FreeCAD Path Adaptive).

* ``rectilinear_0`` (an L whose arm leaves a tool-centre band 1.8 mm wide, D 10 mm, theta 79.5 deg):
  a pass that removed nothing banned every coarse cell within r of its start, the whole face of the
  arm, and the arm's end was then taken by a lift and a second helix entry (0.665 min against
  FreeCAD's 0.427); now a start that leaves the region at its first step bans r/2
  (``pass_ban_frac``) and, before any lift, the bans are lifted once (the second chance, failed
  starts then banning r/2, sliver passes undone): one entry, no lift (0.51 min).
* ``tapered_channel_2`` (a channel narrowing to 10.5 mm, D 8 mm): its narrow end is cut by the
  trochoid (narrow.py); the mouth test (the first periods' swing across the axis meets no material
  within r + h) always met the wall pixels within h of the tool-centre boundary that no pass clears,
  so the region was entered by a lift and a helix at its closed end; with the capsule radius r
  + h/2 (``mouth_capsule_margin_h``) it is entered from cleared area.

Both plans are scored by the package's one evaluator at the corpus resolution (r/30): 0 plunges or
rapids into material, no wall gouge beyond 1 um (the evaluator's tolerance for a sampled
polyline), engagement p95 <= theta + 2 deg and max <= theta + 10 deg (the issue-29 targets).
"""
import numpy as np
import pytest
import shapely

from cnclab.toolpath import planners
from cnclab.toolpath.adaptive import AdaptiveParams
from cnclab.toolpath.evaluate import evaluate
from cnclab.works.jacso2021 import corpus_comparison as cc
from cnclab.works.jacso2021.freecad_comparison import lifts


def _plan(name, **params):
    jb = cc.job(name)
    h = cc.resolution_mm(jb, False)
    return jb, h, planners.plan(jb, "adaptive", h, params=AdaptiveParams(**params), allow_uncut=True)


def _safe_and_within_targets(tp, jb, h):
    ev = evaluate(tp, jb, h)
    assert ev.plunges_into_material == 0 and ev.rapids_into_material == 0
    assert ev.wall_gouge_max_mm <= 1e-3
    assert ev.engagement_p95_deg <= jb.theta_deg + 2.0
    assert ev.engagement_max_deg <= jb.theta_deg + 10.0
    return ev


def test_a_failed_pass_start_does_not_ban_a_narrow_arm():
    # with the nearest pass starts (upstream_start_frac 0: where this was measured, and plan's re-plans)
    jb, h, tp = _plan("rectilinear_0", upstream_start_frac=0.0)
    assert tp.info["entries"] == 1
    ev = _safe_and_within_targets(tp, jb, h)
    assert lifts(ev, jb.top_z) == 1                  # the final retract only
    # the former ban radius (r) is what made the second entry (the failed-start rescue of the links,
    # which also saves that entry, off: rescue_max_fails=0)
    assert _plan("rectilinear_0", pass_ban_frac=1.0, rescue_max_fails=0, upstream_start_frac=0.0)[2].info["entries"] == 2
    # the default upstream starts take the arm's end by a second helix (2 lifts: FreeCAD's 2, committed
    # fixture; issue 29 target lifts <= FreeCAD's), safe and within the engagement targets
    jb, h, tp = _plan("rectilinear_0")
    assert lifts(_safe_and_within_targets(tp, jb, h), jb.top_z) <= 2


@pytest.mark.slow      # two plans with their re-plans (8 s): make test-slow (CI)
@pytest.mark.parametrize("name", ["tapered_channel_2"])
def test_narrow_region_mouth_is_entered_from_cleared_area(name):
    jb, h, tp = _plan(name)
    assert len(tp.info["narrow_regions"]) == 1, tp.info
    assert "from cleared area" in tp.info["narrow_regions"][0]
    assert tp.info["entries"] == 1
    _safe_and_within_targets(tp, jb, h)
    assert "from a helix" in _plan(name, mouth_capsule_margin_h=1.0)[2].info["narrow_regions"][0]


def test_grid_checkpoint_rollback_restores_both_stocks_and_the_free_field():
    # a 20 x 10 mm box, r 2 mm, h r/30: one cut, a checkpoint, a second cut elsewhere, a rollback ->
    # both stocks and the coarse distance field equal those after the first cut (bit for bit; the
    # rollback copies back only the window changed since the checkpoint)
    from shapely.geometry import box

    from cnclab.toolpath.adaptive.grid import Grid
    pocket = box(0, 0, 20, 10)
    r, h = 2.0, 2.0 / 30
    g = Grid(pocket, pocket.buffer(-r), r, h, None)
    g.cut_path(np.array([[3.0, 5.0], [6.0, 5.0]]))
    M1, Mr1, D1 = g.M.copy(), g.Mr.copy(), g.free_field()[0].copy()
    g.checkpoint()
    g.cut_path(np.array([[12.0, 4.0], [16.0, 6.0]]))
    assert (g.M != M1).any() and (g.free_field()[0] != D1).any()
    g.rollback()
    assert np.array_equal(g.M, M1) and np.array_equal(g.Mr, Mr1)
    assert np.array_equal(g.free_field()[0], D1)
    # a second round from that state: the checkpoint copies only what changed
    g.cut_path(np.array([[10.0, 5.0], [11.0, 5.0]]))
    M2 = g.M.copy()
    g.checkpoint()
    g.cut_path(np.array([[15.0, 5.0], [17.0, 5.0]]))
    g.rollback()
    assert np.array_equal(g.M, M2)


def test_sliver_passes_are_undone():
    # star_3 (D 12 mm, theta 109 deg): with sliver_pass_min_yield 0.2 (default off, see params.py)
    # passes removing less than 0.2 a_e per mm (outside bands narrower than the tool) are undone with
    # their links: fewer passes and a shorter program than with the rule off (0.809 against 0.847
    # min), safe, within the engagement targets, and no more
    # uncut than FreeCAD's + 0.5 mm^2 (9.0 mm^2, committed fixture)
    jb, h, tp = _plan("star_3", sliver_pass_min_yield=0.2)
    _, _, tp0 = _plan("star_3")
    assert tp.info["passes"] < tp0.info["passes"]
    assert tp.time_s(jb.rapid_mm_min)["total_s"] < tp0.time_s(jb.rapid_mm_min)["total_s"]
    ev = _safe_and_within_targets(tp, jb, h)
    assert ev.uncut_beyond_unreachable_mm2 <= 8.99 + 0.5


def test_grid_taken_since_checkpoint_is_the_removed_pixels():
    # a 20 x 10 mm box, r 2 mm, h r/30: after a checkpoint one straight cut of 4 mm (tool discs every
    # 0.05 mm) removes the capsule of radius r about it; the pixels listed are exactly those that changed (bit for bit),
    # their area that of the capsule within the pixel discretisation (4 x 2r + pi r^2 = 28.57 mm^2,
    # within 2 % at h = 0.067 mm: the boundary pixels), every centre within r + h/sqrt(2) of the cut
    from shapely.geometry import box

    from cnclab.toolpath.adaptive.grid import Grid
    pocket = box(0, 0, 20, 10)
    r, h = 2.0, 2.0 / 30
    g = Grid(pocket, pocket.buffer(-r), r, h, None)
    g.checkpoint()
    assert len(g.taken_since_checkpoint()) == 0
    before = g.M.copy()
    g.cut_path(np.c_[np.linspace(6.0, 10.0, 81), np.full(81, 5.0)])
    T = g.taken_since_checkpoint()
    J, I = np.nonzero((before != 0) & (g.M == 0))
    assert len(T) == len(J) > 0
    want = np.c_[g.x0 + (I + 0.5) * h, g.y0 + (J + 0.5) * h]
    assert np.allclose(np.sort(T, axis=0), np.sort(want, axis=0))
    assert len(T) * h * h == pytest.approx(4 * 2 * r + np.pi * r * r, rel=0.02)
    d = np.hypot(np.clip(T[:, 0], 6.0, 10.0) - T[:, 0], T[:, 1] - 5.0)
    assert d.max() <= r + h / np.sqrt(2)


@pytest.mark.slow      # two whole plans and evaluations: make test-slow (CI)
def test_wall_sliver_passes_are_left_to_the_finish_lap():
    # the spline bench pocket (D 6 mm, theta 60 deg, dixel 0.05 mm): between the hooks that clear the
    # crescents along its wall, passes that would cut only a cusp at the wall (less than 0.25 r a_e,
    # all of it within reach of the finishing lap still to come) are undone with their links; the lap
    # takes the cusps in its one run. Against the rule off: fewer links and a shorter written program
    # on the small-VMC machine model (every link at depth costs an acceleration and a stop), safe, within
    # the engagement targets, and no more uncut area (+0.05 mm^2: one dixel row along 1 mm)
    from cnclab.nc.gcode import read_gcode
    from cnclab.nc.machine import SMALL_VMC, machine_time
    from cnclab.nc.program import write_program
    from cnclab.works.jacso2021 import freecad_comparison as fx
    # (with the nearest pass starts, upstream_start_frac 0, where the hooks along the wall leave such
    # cusps; from the upstream ends the passes run along the wall and the rule changes the bench
    # pockets' machine time by at most 0.3 %)
    jb, h = fx.job("spline"), 0.05
    on = planners.plan(jb, "adaptive", h, allow_uncut=True, params=AdaptiveParams(upstream_start_frac=0.0))
    off = planners.plan(jb, "adaptive", h, allow_uncut=True,
                        params=AdaptiveParams(wall_sliver_max_area_rae=0.0, upstream_start_frac=0.0))
    assert on.info["wall_slivers"] > 0 and off.info["wall_slivers"] == 0
    assert on.info["links"] < off.info["links"]
    t_on, t_off = (machine_time(read_gcode(write_program(p, jb)).moves, SMALL_VMC)["time_machine_s"] for p in (on, off))
    assert t_on < t_off
    ev_on, ev_off = _safe_and_within_targets(on, jb, h), evaluate(off, jb, h)
    assert ev_on.uncut_beyond_unreachable_mm2 <= ev_off.uncut_beyond_unreachable_mm2 + 0.05


@pytest.mark.slow      # two whole plans and evaluations: make test-slow (CI)
def test_upstream_starts_run_the_boundary_instead_of_hooking():
    # Jacsó's rectangle pocket (D 6 mm, theta 60 deg, dixel 0.05 mm): a pass started at the upstream
    # end of the band of starts (links.upstream_end) runs the material boundary from wall to wall, as
    # FreeCAD Adaptive's arcs do; started at the nearest point (upstream_start_frac 0) it hooked off the
    # wall beside which it began. Measured: 71 passes against 132, 181.1 s against 183.2 s on the small
    # VMC, uncut 1.72 against 1.45 mm^2 (FreeCAD's 1.898, committed fixture). Asserted: at most 0.6 x the
    # passes and fewer links, a shorter written program on the machine model, safe and within the
    # engagement targets, uncut within the issue-29 slack (0.5 mm^2) of the nearest starts' and below
    # FreeCAD's
    from cnclab.nc.gcode import read_gcode
    from cnclab.nc.machine import SMALL_VMC, machine_time
    from cnclab.nc.program import write_program
    from cnclab.works.jacso2021 import freecad_comparison as fx
    jb, h = fx.job("rectangle"), 0.05
    up = planners.plan(jb, "adaptive", h, allow_uncut=True)
    near = planners.plan(jb, "adaptive", h, allow_uncut=True, params=AdaptiveParams(upstream_start_frac=0.0))
    assert up.info["passes"] <= 0.6 * near.info["passes"] and up.info["links"] < near.info["links"]
    t_up, t_near = (machine_time(read_gcode(write_program(p, jb)).moves, SMALL_VMC)["time_machine_s"] for p in (up, near))
    assert t_up < t_near
    ev_up, ev_near = _safe_and_within_targets(up, jb, h), evaluate(near, jb, h)
    assert ev_up.uncut_beyond_unreachable_mm2 <= min(ev_near.uncut_beyond_unreachable_mm2 + 0.5, 1.898)


@pytest.mark.slow      # a plan with its re-plans, and an evaluation: make test-slow (CI)
def test_a_level_beyond_the_bounds_is_planned_again_with_the_nearest_starts():
    # tapered_channel_2 (D 8 mm, theta 81.1 deg): with the upstream starts 0.71 % of the cutting length
    # lies above theta + 5 deg (the bound: 0.5 %); plan's check re-plans (planners._retries) and keeps
    # the first plan within max, p95 and share -- the scored path meets all three
    jb = cc.job("tapered_channel_2")
    h = cc.resolution_mm(jb, False)
    tp = planners.plan(jb, "adaptive", h, allow_uncut=True)
    chk = tp.info["engagement_check"]
    assert chk.get("retried") and chk["share_above_5_pct"] <= 0.5
    ev = _safe_and_within_targets(tp, jb, h)
    assert ev.share_above_5_pct <= 0.5


def test_a_finishing_lap_that_stops_short_is_resumed_past_where_it_stopped():
    # star_4 (D 8 mm, theta 113.5 deg): the first lap along the outer ring stops at a corner where the
    # control finds no way on at the finish target; it used to be the ring's only lap (the rest of
    # the ring held skins thinner than finish_rest_min_mm, too thin for a further lap), and 7.0 mm^2
    # stayed uncut (FreeCAD 6.08, committed fixture). Resumed at the first free ring point r past the
    # stop (finish_resume_laps): 1.95 mm^2. Asserted: less than half the uncut area of the lap not
    # resumed, no more lifts, safe and within the engagement targets
    jb, h, tp = _plan("star_4")
    _, _, tp0 = _plan("star_4", finish_resume_laps=0)
    ev, ev0 = _safe_and_within_targets(tp, jb, h), evaluate(tp0, jb, h)
    assert ev.uncut_beyond_unreachable_mm2 < 0.5 * ev0.uncut_beyond_unreachable_mm2
    assert lifts(ev, jb.top_z) <= lifts(ev0, jb.top_z)


def _finish_cover(tp, jb, tol_mm=2e-3):
    """Share of the tool-centre limit (sampled every 0.25 mm) within ``tol_mm`` of a finishing move."""
    fin = np.flatnonzero(tp.tag == "finish")
    moves = shapely.multilinestrings([np.array([tp.xyz[i - 1, :2], tp.xyz[i, :2]]) for i in fin])
    edge = jb.allowed().boundary
    pts = shapely.line_interpolate_point(edge, np.arange(0.0, edge.length, 0.25))
    return float(np.mean(shapely.distance(moves, pts) < tol_mm))


@pytest.mark.slow      # two plans and evaluations: make test-slow (CI)
def test_corner_rests_the_full_laps_leave_are_peeled_by_local_laps():
    # rectilinear_0 (D 10 mm, theta 79.5 deg): the finishing lap rounds the sharp corners at the end
    # of the arm's 1.8 mm tool-centre band (the control at the finish target keeps out of the corner
    # wedge) and leaves crescents: 8.63 mm^2 beyond what no tool disc reaches (FreeCAD 7.64, committed
    # fixture). A local lap over each run of the ring with material deeper than 1.5 h in reach
    # (finish_peel_rounds) takes them: 3.96 mm^2. Asserted: at least 3 mm^2 less than without the
    # peels, more of the tool-centre limit run by a finishing move, no more entries, safe and within
    # the engagement targets
    jb, h, tp = _plan("rectilinear_0")
    _, _, tp0 = _plan("rectilinear_0", finish_peel_rounds=0)
    ev, ev0 = _safe_and_within_targets(tp, jb, h), evaluate(tp0, jb, h)
    assert tp.info.get("peels", 0) >= 1 and tp0.info.get("peels", 0) == 0
    assert ev.uncut_beyond_unreachable_mm2 <= ev0.uncut_beyond_unreachable_mm2 - 3.0
    assert _finish_cover(tp, jb) > _finish_cover(tp0, jb)
    assert tp.info["entries"] <= tp0.info["entries"]


@pytest.mark.slow      # two whole plans and evaluations: make test-slow (CI)
def test_the_first_finishing_lap_runs_the_whole_ring():
    # islands_5 (D 5 mm, theta 53.8 deg): the passes run along the outer wall h/sqrt(2) inside the
    # tool-centre limit, and the planning stock shows no material in reach there, so the first lap
    # used to end 2 r past the last ring point with material: 42 mm of the top wall were never run on
    # the limit, a sub-pixel skin the evaluator counts (3.91 mm^2 uncut, FreeCAD 2.90). The whole ring
    # (finish_full_first_lap): 1.81 mm^2. Asserted: at least 97 % of the tool-centre limit within
    # 2 um of a finishing move (84 % without), 1.5 mm^2 less uncut, safe and within the targets
    jb, h, tp = _plan("islands_5")
    _, _, tp0 = _plan("islands_5", finish_full_first_lap=False)
    ev, ev0 = _safe_and_within_targets(tp, jb, h), evaluate(tp0, jb, h)
    assert _finish_cover(tp, jb) >= 0.97 > 0.9 > _finish_cover(tp0, jb)
    assert ev.uncut_beyond_unreachable_mm2 <= ev0.uncut_beyond_unreachable_mm2 - 1.5


@pytest.mark.slow      # two plans and evaluations: make test-slow (CI)
def test_laps_after_the_first_cover_only_the_arc_of_the_rests():
    # dwg_polylines (D 8 mm, theta 38.8 deg): after the full first lap the rests deeper than
    # max(0.3 mm, a_e/4) lie in one corner just behind the tool; the further laps started at the free
    # ring point nearest to the tool and ran 226 and 240 mm of the 241 mm ring to reach them. Started
    # upstream of the shortest arc holding the rests (finish_arc_laps), they run about 58 mm each.
    # Asserted: at least 250 mm less finishing, less program time, the uncut area within the 0.5 mm^2
    # per job of issue 29's uncut target (the long laps shaved micrometres off wall skins), safe and
    # within the engagement targets
    jb, h, tp = _plan("dwg_polylines")
    _, _, tp0 = _plan("dwg_polylines", finish_arc_laps=False)
    ev, ev0 = _safe_and_within_targets(tp, jb, h), evaluate(tp0, jb, h)
    fin = lambda p: float(p.segment_lengths()[p.tag == "finish"].sum())     # noqa: E731
    assert fin(tp) <= fin(tp0) - 250.0
    assert ev.time_total_s < ev0.time_total_s
    assert ev.uncut_beyond_unreachable_mm2 <= ev0.uncut_beyond_unreachable_mm2 + 0.5
