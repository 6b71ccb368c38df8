"""The issue-16 comparison recipe (cnclab.works.jacso2021.freecad_comparison) and its benchmark script
(benchmarks/bench_vs_freecad.py): fixture coverage, §4 feed control on a hand-computed path, the wall
gouge, the table and ratios. FreeCAD is not needed (the committed programs are scored)."""
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from shapely.geometry import box

from cnclab.nc import gcode
from cnclab.toolpath.evaluate import evaluate
from cnclab.toolpath.job import Job
from cnclab.toolpath.path import Tool, ToolPath
from cnclab.works.jacso2021 import freecad_comparison as fx

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("name", list(fx.POCKETS))
def test_every_pocket_has_a_freecad_fixture_made_from_its_job(name):
    prov = json.loads((fx.FIXTURES / f"{name}.json").read_text(encoding="utf-8"))
    assert prov["job"] == fx.POCKETS[name]
    job = fx.job(name)
    assert prov["settings"]["tool_diameter"] == job.tool_diameter
    # FreeCAD's StepOver is a_e / D with a_e = r (1 - cos theta)
    assert prov["settings"]["stepover_pct"] == pytest.approx(100 * job.a_e / job.tool_diameter, rel=1e-9)
    assert prov["plan_time_s"] > 0
    try:
        p = fx.freecad_path(name, job.tool)
    except ValueError as exc:          # FreeCAD planned nothing: say so, never a silent empty row
        assert "no cutting motion" in str(exc)
        return
    # the program cuts at the job's feed and runs its helix and descents at the job's entry feed (as
    # ours do: FreeCAD's vertFeed, prov["settings"]), and its time is the G-code reader's canonical total
    d = np.diff(p.xyz, axis=0)
    cut = p.is_kind("cut") & np.r_[False, np.linalg.norm(d, axis=1) > 1e-9]   # zero-length repeats take no time
    down = np.r_[False, d[:, 2] < -1e-9]
    assert np.allclose(p.feed[cut & ~down], job.feed_mm_min, rtol=1e-3)
    assert np.allclose(p.feed[cut & down], job.entry_feed, rtol=1e-3)
    assert prov["settings"]["entry_feed_mm_min"] == job.entry_feed
    moves = gcode.load_gcode(fx.FIXTURES / f"{name}.ngc")
    assert p.time_s(job.rapid_mm_min)["total_s"] == pytest.approx(
        gcode.program_time(moves, job.rapid_mm_min)["total_s"], rel=1e-9)


def _slot_job():
    return Job(box(0, 0, 40, 20), Tool(6.0), 180.0, 2.0, feed_mm_min=300.0, spindle_rpm=5000.0, v_fmax=1000.0)


def test_feed_control_hand_computed_air_then_slot():
    """From x = -20 to 45 at y = 10, z = -2 through a 40 x 20 pocket: the disc (r = 3) meets material
    at x = -3 and is full (engagement 180 deg = theta, w = a_e = 6 mm) from x = 3 until its front reaches the wall (x = 37); air before
    x = -3 and after x = 43. By the §4 rule: nominal feed (300) in the full slot, v_fmax (1000) in air,
    the MRR-holding feed min(1000, 300 a_e / w) >= 300 where the disc enters or leaves. Time bounds:
    the MRR never exceeds nominal (w <= a_e), so the cutting time is at least a_p A / MRR_nom =
    A / (a_e v) with A = 40 x 6 mm^2, and the air at least 17 mm at 1000 mm/min; at most the nominal time."""
    jb = _slot_job()
    p = ToolPath.build([[-20, 10, -2], [45, 10, -2]], kind=["rapid", "cut"], feed=300.0)
    ev = evaluate(p, jb, 0.05)
    q = fx.feed_controlled(p, jb, ev)
    assert np.allclose(q.xyz[-1], p.xyz[-1]) and len(q) == len(p.resample(0.05))
    x, f = q.xyz[:, 0], q.feed
    assert np.all(f[(x > 4) & (x < 36.5)] == 300.0)                 # full slot: blocks at theta, nominal
    assert np.all(f[(x < -3.6) & q.is_kind("cut")] == 1000.0)       # air before the disc meets material
    assert np.all(f[x > 43.6] == 1000.0)                            # air after it leaves
    assert np.all((f[q.is_kind("cut")] >= 300.0) & (f[q.is_kind("cut")] <= 1000.0))
    t = q.time_s(jb.rapid_mm_min)["total_s"]
    assert 60 * (240 / (6 * 300) + 17 / 1000) <= t < p.time_s(jb.rapid_mm_min)["total_s"]


def test_feed_control_keeps_links_and_refuses_a_foreign_evaluation():
    jb = _slot_job()
    p = ToolPath.build([[5, 10, 5], [5, 10, -2], [30, 10, -2], [30, 10, 5]],
                       kind=["rapid", "plunge", "link", "retract"], feed=[math.nan, 100.0, 1500.0, 100.0])
    ev = evaluate(p, jb, 0.1)
    q = fx.feed_controlled(p, jb, ev)
    r = p.resample(0.1)
    assert np.array_equal(np.isnan(q.feed), np.isnan(r.feed))
    assert np.allclose(q.feed[~np.isnan(r.feed)], r.feed[~np.isnan(r.feed)])     # no cut move: nothing changes
    with pytest.raises(ValueError, match="not the evaluation"):
        fx.feed_controlled(p, jb, evaluate(ToolPath.build([[5, 10, -2], [20, 10, -2]], feed=300.0), jb, 0.1))


def test_wall_gouge_zero_inside_and_counts_outside():
    jb = _slot_job()
    inside = ToolPath.build([[3, 10, 5], [3, 10, -2], [37, 10, -2], [37, 3, -2], [37, 3, 5]],
                            kind=["rapid", "plunge", "cut", "cut", "retract"], feed=300.0)
    assert fx.wall_gouge_mm(evaluate(inside, jb, 0.1), jb) == pytest.approx(0.0, abs=1e-9)
    out = ToolPath.build([[3, 10, 5], [3, 10, -2], [41, 10, -2]], kind=["rapid", "plunge", "cut"], feed=300.0)
    assert fx.wall_gouge_mm(evaluate(out, jb, 0.1), jb) == pytest.approx(4.0, abs=1e-6)   # centre 1 mm past x = 40
    above = ToolPath.build([[-10, 10, 5], [50, 10, 5]], kind=["rapid", "rapid"])
    assert fx.wall_gouge_mm(evaluate(above, jb, 0.1), jb) == 0.0


def test_comparison_table_rectangle_fast():
    keep = {}
    T = fx.comparison("rectangle", {"adaptive_clearing": "adaptive"}, fast=True, keep=keep)
    lab, lab_fc = "adaptive_clearing", "adaptive_clearing" + fx.FEED_CONTROL_SUFFIX
    assert list(T.index) == [lab, lab_fc, fx.FREECAD]
    # the planner's row is its program as written (arcs fitted within 5 um: G2/G3 moves read back), the
    # feed-control row the planned path: the same moves counted, the engagement within the fit's shift
    assert np.any(keep[lab][0].arc != 0)
    same = ["lifts", "retracts", "plunges_into_material", "rapids_into_material", "plan_time_s"]
    assert np.allclose(T.loc[lab, same].to_numpy(float), T.loc[lab_fc, same].to_numpy(float), equal_nan=True)
    for c, tol in (("engagement_p95_deg", 0.5), ("engagement_max_deg", 3.0), ("uncut_beyond_mm2", 0.1)):
        assert abs(T.loc[lab, c] - T.loc[lab_fc, c]) <= tol, c
    assert T.loc[lab_fc, "program_time_min"] < T.loc[lab, "program_time_min"]
    for r in (lab, lab_fc, fx.FREECAD):
        assert T.loc[r, "machine_time_min"] > 0
    assert T.loc[lab, "machine_time_min"] == pytest.approx(keep[lab][1].time_machine_s / 60)
    assert T.loc[fx.FREECAD, "plan_time_s"] == fx.freecad_plan_time_s("rectangle")
    assert T.loc[lab, "program_time_min"] == pytest.approx(keep[lab][1].time_total_s / 60)
    R = fx.ratios(T)
    assert fx.FREECAD not in R.index
    fc = T.loc[fx.FREECAD, fx.COLUMNS].astype(float)
    for c in fx.COLUMNS:
        expect = T.loc[lab, c] / fc[c] if fc[c] != 0 else math.nan
        assert R.loc[lab, c] == pytest.approx(expect, nan_ok=True)


def test_comparison_pocket_freecad_left_unmachined_gets_a_nan_row_with_reason():
    T = fx.comparison("slot", {"adaptive_clearing": "adaptive"}, fast=True, feed_control=False)
    assert np.isnan(T.loc[fx.FREECAD, "engagement_p95_deg"]) and "no cutting motion" in T.loc[fx.FREECAD, "note"]
    assert np.isfinite(T.loc["adaptive_clearing", "engagement_p95_deg"])


def test_unknown_pocket_is_refused():
    with pytest.raises(ValueError, match="pocket must be one of"):
        fx.job("hexagon")


@pytest.mark.slow      # the bench script end to end on one pocket: make test-slow (CI)
def test_bench_script_uses_the_package_and_prints_ratios(capsys, monkeypatch):
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import bench_vs_freecad as bench

    monkeypatch.setattr(bench.fx, "PLANNER_ROWS", {"adaptive_clearing": "adaptive"})
    tables = bench.main(["slot", "--fixtures", "--fast"])
    out = capsys.readouterr().out
    assert "committed programs" in out and "ratio to FreeCAD Adaptive" in out and "== slot" in out
    assert set(tables) == {"slot"}
    assert not (ROOT / "benchmarks" / "score_paths.py").exists() and not (ROOT / "benchmarks" / "pocket_jobs.py").exists()
    with pytest.raises(SystemExit, match="unknown pocket"):
        bench.main(["hexagon", "--fixtures"])


def test_as_written_is_the_program_read_back():
    """``as_written`` scores the program a machine runs: a helix and a straight cut, written and read
    back, start at the clearance plane (the writer's approach), keep every planned point within the
    0.005 mm fit and the 4-decimal rounding (+ the 0.01 mm sampling), carry the helix as G2/G3 arcs,
    and take the same time at feed within 0.1 % (arcs for chords; the approach and retract are rapids)."""
    jb = Job(box(0, 0, 40, 20), Tool(6.0), 60.0, 2.0, feed_mm_min=300, spindle_rpm=5000)
    a = np.linspace(0, 4 * np.pi, 400)
    helix = np.column_stack([10 + 2 * np.cos(a), 10 + 2 * np.sin(a), -a / (4 * np.pi)])
    line = np.column_stack([np.linspace(12, 30, 50), np.full(50, 10.0), np.full(50, -1.0)])
    P = np.vstack([[12.0, 10.0, jb.clearance_z], helix, line])    # from the clearance plane, as planners start
    tp = ToolPath.build(P, kind=["rapid", "plunge"] + ["helix"] * 399 + ["cut"] * 50, feed=300.0, spindle=5000.0)
    w = fx.as_written(tp, jb)
    assert w.xyz[0, 2] == pytest.approx(jb.clearance_z)
    assert np.any(w.arc != 0)
    d = np.linalg.norm(w.resample(0.01).xyz[:, None, :] - P[None, ::7, :], axis=2).min(axis=0)
    assert d.max() <= 0.005 + 1e-4 + 0.01
    tw, tt = w.time_s(jb.rapid_mm_min), tp.time_s(jb.rapid_mm_min)
    assert tw["total_s"] - tw["rapid_s"] == pytest.approx(tt["total_s"] - tt["rapid_s"], rel=1e-3)
