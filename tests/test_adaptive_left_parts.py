"""Parts of the tool-centre region the adaptive planner cannot open are left and stated (issue 28
item 1), not a failure of the whole job.

A 40 x 30 mm pocket (D = 6 mm, theta = 60 deg; a pocket of this test) with a 6.1 mm square bay
joined to it by a 4 mm neck: the neck is narrower than the tool, so the bay's part of the
tool-centre region is a separate sliver 0.1 mm wide (inscribed radius 0.05 mm), too small for the
smallest helix (``helix_min_frac`` r = 0.3 mm) and with no way in at depth. Before, the finish
raised PlanningError for the whole job (dwg_box_w_holes, dwg_example009, dwg_many_holes_inner of
the corpus); now the bay is left, named in ``info["left_parts"]`` and the program header, and
``plan`` measures it as uncut: above the limit (:func:`cnclab.toolpath.coverage.uncut_limit_mm2`,
1 mm^2 + 1 % of the reachable area) an :class:`UncutError` unless ``allow_uncut``. The rest of the
pocket is planned safely (0 plunges or rapids into material, scored by the evaluator at r / 30)."""
import dataclasses

import pytest
from shapely.geometry import box

from cnclab.nc.program import check_program, write_program
from cnclab.toolpath import adaptive, planners
from cnclab.toolpath.evaluate import evaluate
from cnclab.toolpath.job import Job
from cnclab.toolpath.path import Tool

R = 3.0
H = R / 30.0


def _job():
    # bay 40.8..46.9 x 11.95..18.05 (tool-centre part about 43.0..43.9 x 14.95..15.05), neck 4 mm wide (< D)
    poly = box(0.0, 0.0, 40.0, 30.0).union(box(39.0, 13.0, 41.0, 17.0)).union(box(40.8, 11.95, 46.9, 18.05))
    return Job(poly, Tool(2 * R), 60.0, 3.0, feed_mm_min=764.0, spindle_rpm=5968.0, rapid_mm_min=10000.0,
               link_feed_mm_min=1500.0, v_fmax=1146.0, source="bay behind a neck")


def test_a_part_no_entry_can_open_is_refused_as_uncut_by_default():
    with pytest.raises(planners.UncutError, match="leaves material uncut"):
        planners.plan(_job(), "adaptive", H)


def test_a_part_no_entry_can_open_is_left_and_stated_with_allow_uncut():
    job = _job()
    tp = planners.plan(job, "adaptive", H, allow_uncut=True)
    left = tp.info["left_parts"]
    assert len(left) == 1 and "too narrow to be entered" in left[0] and ", 15.00)" in left[0]
    assert tp.info["uncut"]["over"] == [0] and tp.info["warnings"]
    prog = write_program(tp, job)
    assert "left uncut" in prog
    assert check_program(prog, clearance_z=job.clearance_z, top_z=job.top_z).errors == []
    ev = evaluate(tp, job, H)
    assert ev.plunges_into_material == 0 and ev.rapids_into_material == 0
    # the bay (6.1 x 6.1 mm, its corners beyond r unreachable by any tool) is what is left; the
    # main rectangle is cleared as without the bay (measured 3.6 mm^2 uncut beyond the corners)
    assert 25.0 < tp.info["uncut"]["uncut_mm2"][0] < 45.0


def _slot_job():
    # a 30 x 20 pocket with a slot 6.6 mm wide (1.1 D) and 14 mm long off its right side: the slot's
    # part of the tool-centre region is 0.6 mm wide (half-width 0.1 r < 0.2 r), no step enters it
    # under the engagement bound
    poly = box(0.0, 0.0, 30.0, 20.0).union(box(29.0, 6.7, 44.0, 13.3))
    return Job(poly, Tool(2 * R), 60.0, 2.0, feed_mm_min=764.0, spindle_rpm=5968.0, rapid_mm_min=10000.0,
               link_feed_mm_min=1500.0, v_fmax=1146.0, source="slot 1.1 D")


def test_a_strip_too_narrow_for_the_bound_is_refused_with_its_place_and_the_remedies():
    """The refusal says why and what to do: the strip (where, its size, the material left in its
    reach), and the two ways (slot_narrow / --slot-narrow, a smaller tool); with slot_narrow the plan
    leaves no more than its limit (the planner's own plan slots the strip, stating its engagement)."""
    from cnclab.toolpath.adaptive import AdaptiveParams

    with pytest.raises(planners.UncutError) as err:
        planners.plan(_slot_job(), "adaptive", H)
    msg = str(err.value)
    assert msg.startswith("slot 1.1 D: ") and "too narrow to be cleared by this plan's passes" in msg and "mm^2 of material within the tool's reach" in msg
    assert "--slot-narrow" in msg and "smaller tool" in msg
    x, y = (float(v) for v in msg.split("region near (")[1].split(")")[0].split(", "))
    assert 27.0 < x < 41.0 and abs(y - 10.0) < 0.5     # on the slot's axis (tool centres x 27..41: mouth to end)
    slotted = adaptive.plan_job(_slot_job(), resolution_mm=R / 60, params=AdaptiveParams(slot_narrow=True))
    assert any("cut by slotting at up to" in n for n in slotted.info["notes"]) and not slotted.info["left_parts"]
    # plan() checks the promise and re-plans (its first re-plan, the tighter guard, clears the strip by passes)
    tp = planners.plan(_slot_job(), "adaptive", H, params=AdaptiveParams(slot_narrow=True))
    assert tp.info["uncut"]["over"] == []
    ev = evaluate(tp, _slot_job(), H)
    assert ev.plunges_into_material == 0 and ev.rapids_into_material == 0


def test_a_slot_narrower_than_the_tool_centre_lap_gets_its_walls_finished():
    """data/pockets/long_slot.json (7.2 mm wide, D6: a tool-centre strip 1.2 mm wide, narrower than
    the tool, so no place on its ring is free of material): the passes left a skin of 30-150 um on
    both walls (9.3 mm^2 at r / 30 by the evaluator) and the finish skipped the strip's lap. The
    tool stands in the strip after its passes: it now steps onto the ring at the cutting feed (the
    step's engagement within the finish target) and laps it. What is left is under 1.5 mm^2 by
    ``plan``'s count and the evaluator's, the engagement bound and safety kept."""
    from cnclab.paths import data_path
    from cnclab.toolpath.job import load_job

    job = load_job(data_path("pockets", "long_slot.json"))
    p = planners.plan(job, "adaptive", 0.1)                       # no UncutError: within the limit
    assert p.info["uncut"]["uncut_mm2"][0] < 1.5
    assert any(t == "finish: onto a skin" for t in p.tag)
    ev = evaluate(p, job, job.tool_radius / 30)
    assert ev.uncut_beyond_unreachable_mm2 < 1.5
    assert ev.engagement_max_deg <= job.theta_deg + 10 and ev.plunges_into_material == 0
    assert ev.rapids_into_material == 0 and ev.wall_gouge_max_mm <= planners.GOUGE_TOL_MM


def test_a_level_with_skin_laps_is_planned_again_without_them_first():
    """A level beyond the bounds that lapped sliver parts from a skin step is planned again first
    without those laps, then with every retry of that plan (dwg_many_holes_inner: with them a link
    later in the level read theta + 43.5 deg; the plan without them, retried, theta + 8.0); a level
    without skin laps keeps its retries."""
    prm = adaptive.AdaptiveParams()
    plain = planners._retries(prm)
    assert all(p.finish_skin_step for p in plain)
    again = planners._retries(prm, skin_steps=2)
    assert again[0] == adaptive.AdaptiveParams(finish_skin_step=False)
    assert again[1:] == planners._retries(again[0]) and not any(p.finish_skin_step for p in again)
    assert [dataclasses.replace(p, finish_skin_step=True) for p in again[1:]] == plain
