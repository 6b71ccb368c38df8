"""Deep pockets (issue 29 item 2): every registered strategy plans a pocket deeper than a_p, with or
without a start hole, with or without an island, as a program that passes the static safety check
(no plunge or rapid into material unless the planner proved the area cleared), the dixel simulator
(0 plunges, 0 rapids into material) and, when LinuxCNC is installed, ``rs274``.

The matrix: strategy x depth in {a_p, 2 a_p, 2.5 a_p} x start hole yes/no x island yes/no (the two
slowest planners' 2 a_p cells marked slow: ``make test-slow``, see :data:`SLOW`), on a small rectangular pocket (so that
it runs in the test budget; the 60 x 40 mm, D8 case of the issue is checked by ``python -m cnclab
plan`` in ``test_issue_pocket_through_the_cli``)."""
import dataclasses
import json

import numpy as np
import pytest
from shapely.geometry import box

from cnclab.nc.program import check_program, write_program
from cnclab.nc.rs274 import parse_canonical, rs274_available, run_rs274
from cnclab.toolpath.adaptive import unproven_rapids
from cnclab.toolpath.evaluate import evaluate
from cnclab.toolpath.job import Job
from cnclab.toolpath.levels import CLEARED_ABOVE, LevelError, swept_region
from cnclab.toolpath.path import Tool, ToolPath
from cnclab.toolpath.planners import STRATEGIES, plan

AP = 1.0        # mm: small levels keep the helices short
D = 6.0         # mm tool
RES = 0.1       # mm: the evaluator's dixel and the planners' resolution


def _job(mult, hole, island):
    poly = box(0, 0, 30, 22)
    if island:
        poly = poly.difference(box(14, 9, 18, 13))      # 2 D and more from every wall
    sh = (6.0, 11.0, 7.0) if hole else None
    return Job(poly, Tool(D, flutes=2), 60.0, AP, depth=AP * mult, start_hole=sh, v_c=120, f_z=0.04)


#: the planners that take seconds a level on this pocket (laps on a fine dixel stock): their 2 a_p
#: cells are marked slow (``make test-slow``, which CI runs; 2.5 a_p already joins three levels, one
#: of them partial, in ``make test``); every cell of the matrix runs in CI
SLOW = ("constant-engagement", "kim-yang-modified")
#: the strategies that accept every job of the matrix (the others may refuse islands or a missing hole)
ALWAYS = ("adaptive", "contour-parallel", "zig-zag")
CASES = [(n, m, h, i) for n in sorted(STRATEGIES) for m in (1, 2, 2.5) for h in (False, True) for i in (False, True)]


def _marks(n, m):
    group = pytest.mark.xdist_group(f"deep-{n}")
    return [group, pytest.mark.slow] if (n in SLOW and m == 2) else [group]


# the a_p job of a cell is field for field the first level plan() makes of its 2 a_p job: with the
# memo_levels fixture (tests/conftest.py) that level is planned once per strategy, and one xdist group
# per strategy (make test: --dist loadgroup) keeps a strategy's cells in one worker
@pytest.mark.parametrize("name, mult, hole, island",
                         [pytest.param(*c, marks=_marks(c[0], c[1])) for c in CASES],
                         ids=[f"{n}-{m}-{'hole' if h else 'no-hole'}-{'island' if i else 'plain'}" for n, m, h, i in CASES])
def test_every_strategy_plans_every_depth_safely(name, mult, hole, island, tmp_path, memo_levels):
    job = _job(mult, hole, island)
    try:
        p = plan(job, name, resolution_mm=RES)
    except LevelError:
        raise
    except ValueError as exc:
        # a strategy that cannot honour the job at all (islands for the paper strategies, no start hole
        # for the hybrid) refuses it at any depth with the same message: never because the pocket is deep
        assert name not in ALWAYS and "strategy" in str(exc), exc
        if mult != 1:
            with pytest.raises(ValueError) as one:
                plan(_job(1, hole, island), name, resolution_mm=RES)
            assert str(one.value) == str(exc)
        return
    levels = job.levels()
    assert p.info["levels"] == levels and len(levels) == int(np.ceil(mult - 1e-9))
    assert p.xyz[:, 2].min() == pytest.approx(levels[-1])
    text = write_program(p, job)
    chk = check_program(text, job.clearance_z, job.top_z)
    assert chk.errors == [] and chk.plunges_into_material == 0 and chk.rapids_below_clearance == 0
    ev = evaluate(p, job, RES)
    assert ev.plunges_into_material == 0 and ev.rapids_into_material == 0
    # every G0 at depth (only the adaptive planner writes them) proven from the path before it, on a
    # rapid stock rebuilt level by level from the written moves (adaptive.audit)
    assert unproven_rapids(p, job, p.info.get("resolution_mm", RES)) == []
    # every level below the first cuts only under area the levels above cleared (same plan in x, y)
    assert max(p.info["levels_extra_mm2"]) < 0.5
    if rs274_available():
        f = tmp_path / "deep.ngc"
        f.write_text(text)
        canon = parse_canonical(run_rs274(f), source=str(f))
        assert canon.feed_mm > 0 and canon.spindle_on_before_feed


def test_a_move_through_uncleared_levels_is_reentered_by_a_helix():
    """A level whose entry lies where the level above left material: its descent (tagged cleared by
    its one-level planner) is replaced by a plunge to the stock top and a helix from there."""
    from cnclab.toolpath.levels import join_levels

    job = Job(box(0, 0, 40, 20), Tool(6.0), 60.0, 1.0, depth=2.0, v_c=100, f_z=0.05, start_hole=(5, 10, 7))
    c = (30.0, 10.0)
    # level 1 cuts only a slot at x < 15 from the start hole; level 2 descends beside (30, 10) as if
    # the floor there were clear
    lv1 = ToolPath.build([[5, 10, 5], [5, 10, -1], [14, 10, -1], [14, 10, 5]],
                         kind=["rapid", "plunge", "cut", "rapid"], feed=300, tag=["", "start hole", "", ""],
                         cleared=[False, True, False, False])
    lv2 = ToolPath.build([[c[0] + 1, c[1], 5], [c[0] + 1, c[1], -0.5], [c[0] + 1, c[1], -1],
                          [c[0] + 1, c[1], -2], [c[0] + 1, c[1], 5]],
                         kind=["rapid", "rapid", "plunge", "helix", "rapid"], feed=300,
                         tag=["", "above the level", "air", "entry", ""], cleared=[False, True, False, False, False],
                         arc=[0, 0, 0, 3, 0], arc_center=[[np.nan] * 2] * 3 + [list(c), [np.nan] * 2])
    out = join_levels([lv1, lv2], [0.0, -1.0], job)
    k2 = len(lv1)
    K = out.kinds()[k2:]
    assert K[:2].tolist() == ["rapid", "plunge"] and K[-1] == "rapid"
    assert set(K[2:-1]) == {"helix"} and len(K) - 4 >= 16     # one turn of at least 16 chords (one helix generator)
    assert out.arc[-2] == 3 and out.xyz[-2, 2] == -2.0      # then the level's own helix, as planned
    assert out.xyz[k2 + 1, 2] == 0.0                        # the plunge ends on the stock top (air)
    hx = out.xyz[k2 + 2:-2]
    assert hx[-1, 2] == pytest.approx(-1.0) and np.all(np.diff(np.r_[0.0, hx[:, 2]]) < 0)
    assert np.allclose(np.hypot(hx[:, 0] - c[0], hx[:, 1] - c[1]), 1.0)      # about the level's helix centre
    assert np.allclose(hx[-1, :2], [c[0] + 1, c[1]])        # back where the level's own helix starts
    assert not out.cleared[k2:].any()
    text = write_program(out, job)
    assert check_program(text, job.clearance_z, job.top_z).errors == []


def test_reentry_follows_a_helix_of_line_moves():
    """The same re-entry when the level's own helix is the package's one helix generator's line moves
    (ToolPathBuilder.helix on a helix_ring, as the adaptive planner writes it): centre (the
    circumcentre of its first points), sense and pitch read from the line moves."""
    from cnclab.toolpath.helix import helix_ring, helix_segments
    from cnclab.toolpath.levels import join_levels
    from cnclab.toolpath.path import ToolPathBuilder

    job = Job(box(0, 0, 40, 20), Tool(6.0), 60.0, 1.0, depth=2.0, v_c=100, f_z=0.05, start_hole=(5, 10, 7))
    c = (30.0, 10.0)
    lv1 = ToolPath.build([[5, 10, 5], [5, 10, -1], [14, 10, -1], [14, 10, 5]],
                         kind=["rapid", "plunge", "cut", "rapid"], feed=300, cleared=[False, True, False, False])
    b = ToolPathBuilder(tool=job.tool)
    b.rapid([[c[0] + 1, c[1]]], z=5)
    b.rapid([[c[0] + 1, c[1]]], z=-0.5, tag="above the level", cleared=True)
    b.plunge([c[0] + 1, c[1]], -1.0, 300, tag="air")
    b.helix(helix_ring(c, 1.0, 24, turns=1.5), -1.0, -2.0, 300, equal_steps=True)   # 1.5 turns: 1 mm a turn / 1.5
    b.retract(5, 300)
    out = join_levels([lv1, b.build()], [0.0, -1.0], job)
    k2 = len(lv1)
    K = out.kinds()[k2:]
    assert K[:2].tolist() == ["rapid", "plunge"] and out.xyz[k2 + 1, 2] == 0.0
    n_new = int(np.flatnonzero(out.xyz[k2 + 2:, 2] == -1.0)[0]) + 1     # re-entry moves down to the level top
    assert set(K[2:2 + n_new]) == {"helix"}
    hx = out.xyz[k2 + 2:k2 + 2 + n_new]
    assert np.allclose(np.hypot(hx[:, 0] - c[0], hx[:, 1] - c[1]), 1.0)      # about the level's helix centre
    assert np.allclose(hx[-1, :2], [c[0] + 1, c[1]]) and np.all(np.diff(np.r_[0.0, hx[:, 2]]) < 0)
    # whole turns of helix_segments(1 mm) chords (0.01 mm sagitta), pitch <= the level's 1/1.5 mm a
    # turn: 1 mm in ceil(1.5) = 2 turns
    assert n_new == 2 * helix_segments(1.0)
    assert np.all(np.diff(np.unwrap(np.arctan2(hx[:, 1] - c[1], hx[:, 0] - c[0]))) > 0)   # counter-clockwise, as planned
    assert not out.cleared[k2:].any()
    assert check_program(write_program(out, job), job.clearance_z, job.top_z).errors == []


def test_a_move_proven_by_the_level_above_is_tagged_cleared():
    job = Job(box(0, 0, 40, 20), Tool(6.0), 60.0, 1.0, depth=2.0, v_c=100, f_z=0.05)
    from cnclab.toolpath.levels import join_levels

    lv1 = ToolPath.build([[5, 10, 5], [5, 10, 0], [5, 10, -1], [30, 10, -1], [30, 10, 5]],
                         kind=["rapid", "plunge", "cut", "cut", "rapid"], feed=300)
    lv2 = ToolPath.build([[10, 10, 5], [10, 10, -1], [10, 10, -2], [12, 10, -2], [12, 10, 5]],
                         kind=["rapid", "plunge", "plunge", "cut", "rapid"], feed=300)
    out = join_levels([lv1, lv2], [0.0, -1.0], job)
    k2 = len(lv1)
    assert out.cleared[k2 + 1] and CLEARED_ABOVE in out.tag[k2 + 1]   # down to the floor of level 1: proven
    assert not out.cleared[k2 + 2]                          # into level 2's own material: its own claim
    # swept area of a stroke: 2 r x length + pi r^2 (the buffer polygon within its chord error)
    assert swept_region(lv1, 0.0, 3.0).area == pytest.approx(6 * 25 + np.pi * 9, rel=1e-3)


def test_issue_pocket_through_the_cli(tmp_path):
    """The issue's case: 60 x 40 mm, D8, a_p 3, depth 7.5, no start hole -> ``python -m cnclab plan``
    writes a program that passes its own check (it refused it before)."""
    from cnclab.nc.cli_plan import main

    jf = tmp_path / "deep.json"
    jf.write_text(json.dumps({"polygon": [[0, 0], [60, 0], [60, 40], [0, 40]], "tool_diameter": 8, "teeth": 2,
                              "theta_deg": 60, "a_p": 3, "depth": 7.5, "v_c": 120, "f_z": 0.04}))
    out = tmp_path / "deep.ngc"
    assert main([str(jf), "-o", str(out), "--strategy", "contour-parallel"]) == 0
    text = out.read_text()
    assert check_program(text, 5.0, 0.0).errors == []
    assert "Z-7.5000" in text


def test_plan_passes_resolution_through():
    job = _job(1, False, False)
    a = plan(job, "adaptive", resolution_mm=0.04)        # finer than r/60 = 0.05 mm: as given
    assert a.info["resolution_mm"] == pytest.approx(0.04)
    b = plan(job, "adaptive")
    assert b.info["resolution_mm"] == pytest.approx(job.tool_radius / 60)
    c = plan(job, "adaptive", resolution_mm=0.5)        # coarser than r/60: planned at r/60
    assert c.info["resolution_mm"] == pytest.approx(job.tool_radius / 60)
    with pytest.raises(ValueError, match="resolution_mm"):
        plan(job, "zig-zag", resolution_mm=0.0)
    assert dataclasses.is_dataclass(job)


@pytest.mark.parametrize("name", sorted(STRATEGIES))
def test_a_level_as_deep_as_the_first_is_its_plan_lowered(name):
    """plan() plans a level as deep as the first once and lowers it (planners.lowered_level): for
    every strategy that plan is what the strategy plans for the deeper level itself -- the same moves,
    kinds, tags, feeds and info, z within 1e-9 mm (the helix's z steps rounded differently) -- on a
    job with the parts that state z in their info (left parts: a 0.1 mm bay behind a 4 mm neck)."""
    from cnclab.toolpath import planners

    hole, island = (False, True) if name in ALWAYS else (True, False)
    job = _job(3, hole, island)
    if name in ALWAYS:
        poly = job.polygon.union(box(29.0, 9.0, 31.0, 13.0)).union(box(30.8, 7.95, 36.9, 14.05))
        job = dataclasses.replace(job, polygon=poly)
    f = STRATEGIES[name][0]
    levels = job.levels()
    one = [dataclasses.replace(job, top_z=t, a_p=t - z, depth=t - z) for t, z in zip([job.top_z] + levels[:-1], levels)]
    try:
        first = planners._run_strategy(f, name, one[0], RES, {})
    except ValueError as exc:
        assert name not in ALWAYS, exc
        return
    for lv, z in zip(one[1:], levels[1:]):
        own = planners._run_strategy(f, name, lv, RES, {})
        low = planners.lowered_level(first, levels[0], z, job.clearance_z)
        assert len(low) == len(own) and np.abs(low.xyz - own.xyz).max() < 1e-9
        for col in ("kind", "tag", "feed", "arc", "arc_center", "cleared"):
            assert np.array_equal(getattr(low, col), getattr(own, col), equal_nan=col in ("feed", "arc_center")), col
        assert _untimed(low.info) == _untimed(own.info)
    if name == "adaptive":
        assert any(f"level z {levels[2]:g}:" in q for q in low.info["left_parts"])


#: info keys that are wall times (s): the only info two plans of one level may differ in
TIMES = ("plan_time_s", "plan_s", "evaluate_s")


def _untimed(v):
    """``v`` (an info value) without its wall times (:data:`TIMES`), at any depth."""
    if isinstance(v, dict):
        return {k: _untimed(q) for k, q in v.items() if k not in TIMES}
    if isinstance(v, list):
        return [_untimed(q) for q in v]
    return v


@pytest.mark.parametrize("t_um, proven", [(1.0, True), (10.0, False)])
def test_a_move_along_the_rest_of_a_level_above_is_proven_only_when_thinner_than_the_polygons_chords(t_um, proven):
    """Level 1 cuts a slot (y 7..13 mm, r 3); level 2 comes down and runs 20 mm through slab 1 at
    y = 10 + t: its disc reaches t past the slot's side, a strip 20 mm x t of the material level 1
    left. 1 um (0.02 mm^2, over PROOF_TOL_MM2 by area) is thinner than twice the tool-disc buffers'
    chord error (levels.sliver_mm(3) = 0.9 um): the polygons' chords, not material (the zig-zag
    refused 7 of 30 deep fuzz pockets for 1.19 um scallops along a round wall); 10 um is material and
    the move is refused by name."""
    from cnclab.toolpath.levels import PROOF_TOL_MM2, join_levels, sliver_mm

    job = Job(box(0, 0, 40, 20), Tool(6.0), 60.0, 1.0, depth=2.0, v_c=100, f_z=0.05, start_hole=(5, 10, 7))
    t = t_um * 1e-3
    lv1 = ToolPath.build([[5, 10, 5], [5, 10, -1], [35, 10, -1], [35, 10, 5]],
                         kind=["rapid", "plunge", "cut", "rapid"], feed=300, cleared=[False, True, False, False])
    lv2 = ToolPath.build([[10, 10 + t, 5], [10, 10 + t, -0.5], [30, 10 + t, -0.5], [30, 10 + t, -2],
                          [32, 10 + t, -2], [32, 10 + t, 5]],
                         kind=["rapid", "rapid", "rapid", "plunge", "cut", "rapid"], feed=300,
                         cleared=[False, True, True, True, False, False])
    assert 20 * t > PROOF_TOL_MM2 and (t < 2 * sliver_mm(3.0)) == proven
    if proven:
        out = join_levels([lv1, lv2], [0.0, -1.0], job)
        assert out.cleared[len(lv1) + 2] and "cleared: levels above" in out.tag[len(lv1) + 2]
    else:
        with pytest.raises(LevelError, match=r"level 2 .* move 1 at x 10.000 y 10.010 mm runs through material"):
            join_levels([lv1, lv2], [0.0, -1.0], job)
