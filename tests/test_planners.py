"""plan(job, strategy): every registered 2.5D strategy returns a ToolPath that the one evaluator
scores; machine safety (rapids at clearance, no rapid into material, entries into air or by
helix); levels for a pocket deeper than a_p."""
import numpy as np
import pytest

from cnclab.paths import data_path
from cnclab.toolpath.evaluate import evaluate
from cnclab.toolpath.job import load_job
from cnclab.toolpath.path import APPROACH_MM, ToolPath
from cnclab.toolpath.planners import STRATEGIES, plan

RES = 0.25


@pytest.fixture(scope="module")
def rect():
    return load_job(data_path("jacso2021", "rectangle_pocket.json"))


@pytest.mark.parametrize("name", sorted(STRATEGIES))
def test_every_strategy_plans_a_safe_toolpath(rect, name):
    if name == "constant-engagement":       # breaks its promise on this pocket (2.8 % above theta + 5): refused
        with pytest.raises(ValueError, match="rectangle_pocket.json: the constant-engagement strategy promises"):
            plan(rect, name, resolution_mm=RES)
        return
    p = plan(rect, name, resolution_mm=RES)
    assert isinstance(p, ToolPath) and p.info["strategy"] == name and p.tool == rect.tool
    rapid = p.is_kind("rapid")
    low = rapid & (p.xyz[:, 2] < rect.clearance_z)
    # rapids at clearance, or below it only where the planner marks them inside cleared area (the
    # evaluator below proves that no rapid removes material)
    assert p.cleared[low].all()
    # one rule for lifts and descents (ToolPathBuilder.lift / approach): no feed move above
    # APPROACH_MM over the stock top (every descent from the clearance plane is a G0 down to there,
    # the entry at feed), every move up to the clearance plane a G0 straight up
    feed = np.flatnonzero(~rapid)
    assert np.maximum(p.xyz[feed, 2], p.xyz[feed - 1, 2]).max() <= rect.top_z + APPROACH_MM + 1e-9
    up = np.r_[False, (np.diff(p.xyz[:, 2]) > 1e-9) & (p.xyz[1:, 2] == rect.clearance_z)]
    assert rapid[up].all() and np.allclose(p.xyz[up, :2], p.xyz[np.flatnonzero(up) - 1, :2])
    # the end: a G0 straight up to the clearance plane
    assert p.kinds()[0] == "rapid" and p.kinds()[-1] == "rapid"
    assert p.xyz[-1, 2] == rect.clearance_z and np.allclose(p.xyz[-1, :2], p.xyz[-2, :2])
    assert p.xyz[:, 2].min() == pytest.approx(rect.top_z - rect.a_p)
    ev = evaluate(p, rect, RES)
    assert ev.rapids_into_material == 0
    assert ev.time_total_s == pytest.approx(p.time_s(rect.rapid_mm_min)["total_s"])
    assert ev.uncut_beyond_unreachable_mm2 < 0.02 * rect.polygon.area
    assert ev.plunges_into_material == 0          # entries into air / cleared area, or by helix


def test_kim_yang_paper_plunges_are_counted_and_the_planner_helix_avoids_them():
    """Kim & Yang's program plunges onto each pass start (its spiral's centre, in material): the
    evaluator counts them; the registry's planner enters each pass by a helix instead."""
    from cnclab.toolpath import constant_mrr as cm

    job = load_job(data_path("kim_yang2006", "pocket_120x85.json"))
    passes = cm.kim_yang_passes(job)
    paper = evaluate(cm.passes_path(passes, job), job, 0.5)
    safe = evaluate(cm.passes_path(passes, job, entry="helix"), job, 0.5)
    assert paper.plunges_into_material >= 1 and paper.plunge_swept_area_mm2 > 50
    assert safe.plunges_into_material == 0 and safe.entries_helix == len(passes)


def test_levels_and_unknown_strategy(rect):
    import dataclasses

    deep = dataclasses.replace(rect, depth=5.0)              # a_p = 3: two levels of 2.5 mm
    p = plan(deep, "contour-parallel", resolution_mm=RES)
    assert p.info["levels"] == [-2.5, -5.0]
    cut_z = sorted(set(np.round(p.xyz[p.is_kind("cut"), 2], 9)))
    assert cut_z == [-5.0, -2.5]
    ev = evaluate(p, deep, RES)
    assert ev.uncut_beyond_unreachable_mm2 < 0.02 * 2 * rect.polygon.area and ev.rapids_into_material == 0
    with pytest.raises(ValueError, match="unknown strategy .* must be one of"):
        plan(rect, "spiral-of-doom")
    with pytest.raises(ValueError, match="pocket_120x85.json: the hybrid strategy"):
        plan(load_job(data_path("kim_yang2006", "pocket_120x85.json")), "hybrid")


@pytest.mark.parametrize("name", ["kim-yang-original", "kim-yang-modified"])
def test_kim_yang_strategies_plan_a_polygonal_circle_without_gouging(name):
    """A 100-gon of radius 20 (D6, theta 45): the strategies' arcs are fitted on the points and the
    chords (constant_mrr.fit_arcs(chords=True)); fitted on the points only (the paper's §3.3 rule)
    one arc ran through the vertices of the outer offset and bulged past its sides by their sagitta
    (11.6 um here), so plan() refused the job as a gouge (a 200-gon of radius 42.3 with D5.8 in
    session 21's fuzz campaign: 5.1 um)."""
    from shapely.geometry import Polygon

    from cnclab.toolpath import coverage
    from cnclab.toolpath.job import Job
    from cnclab.toolpath.path import Tool

    a = np.linspace(0, 2 * np.pi, 100, endpoint=False)
    job = Job(Polygon(np.column_stack([20 * np.cos(a), 20 * np.sin(a)])), Tool(6.0), 45.0, 1.0, v_c=100, f_z=0.05)
    p = plan(job, name)
    assert coverage.wall_gouge(p, job)[0] <= 1e-3


def test_hybrid_plans_a_job_whose_cutting_feed_is_above_the_default_v_fmax():
    """f_z 0.1 x 3 teeth x 7958 rpm = 2387 mm/min, above the default v_fmax of 1000 mm/min (the feed
    control's cap): the hybrid scores its wall-share candidates with the cap at the cutting feed
    instead of failing inside the feed control (five of the fuzz campaign's pockets were refused
    with "v_fmax (1000.0) must be >= v_nominal"); its program runs at the job's feed."""
    from shapely.geometry import box

    from cnclab.toolpath.job import Job
    from cnclab.toolpath.path import Tool

    job = Job(box(0, 0, 40, 30), Tool(8.0, flutes=3), 60.0, 2.0, start_hole=(20, 15, 10), v_c=200, f_z=0.1)
    assert job.feed_mm_min > job.v_fmax
    p = plan(job, "hybrid", allow_uncut=True)
    cut = p.is_kind("cut")
    assert cut.any() and np.nanmax(p.feed[cut]) == pytest.approx(job.feed_mm_min)
