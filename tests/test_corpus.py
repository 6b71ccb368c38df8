"""The issue-29 pocket corpus (data/pockets/corpus) is what its generator says, frozen and traceable:
the committed jobs equal a fresh run of the seeded generator, every job loads, the families and the
cases named in the issue are there, every drawing job names its public source (repository, path,
commit, licence) and the committed copy of the drawing is byte-identical to it (git blob hash), and
FreeCAD's committed program and provenance exist for every job."""
import importlib.util
import json
import re
from pathlib import Path

import pytest

from cnclab.paths import REPO_ROOT
from cnclab.works.jacso2021 import corpus_comparison as cc

# one xdist group (make test: --dist loadgroup): all of this module runs in one worker, so that
# the module-scoped `jobs` are loaded once
pytestmark = pytest.mark.xdist_group("test_corpus")

CORPUS = REPO_ROOT / "data" / "pockets" / "corpus"


def _load(path):
    """The module of the script ``path`` (the corpus generator, a benchmark), imported by its file."""
    spec = importlib.util.spec_from_file_location(path.stem, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _generator():
    return _load(CORPUS / "make_corpus.py")


def test_corpus_is_the_frozen_generator_output():
    jobs = _generator().build()
    assert sorted(jobs) == cc.job_names() and len(jobs) >= 60
    for name, (d, _) in jobs.items():
        assert (CORPUS / f"{name}.json").read_text(encoding="utf-8") == json.dumps(d, indent=1) + "\n", name


@pytest.fixture(scope="module")
def jobs():
    """Every corpus job, loaded once for the tests below (cc.job reads and validates a file a call)."""
    return {n: cc.job(n) for n in cc.job_names()}


def test_families_named_cases_and_tools(jobs):
    fams = {n: cc.family(n) for n in cc.job_names()}
    assert {"star", "rectilinear", "islands", "neck", "slot_bulbs", "tapered_channel", "gear", "spiral", "comb",
            "channel_15d", "regions", "drawing"} == set(fams.values())
    assert sum(f == "drawing" for f in fams.values()) >= 10
    ch, g = jobs["tapered_channel_30_10"], jobs["gear10_island"]
    assert (ch.tool_diameter, ch.theta_deg, g.tool_diameter, g.theta_deg) == (8.0, 30.7, 6.0, 45.6)
    assert len(g.polygon.interiors) == 1                                  # the round island
    tools = {jobs[n].tool_diameter for n in cc.job_names()}
    thetas = [jobs[n].theta_deg for n in cc.job_names()]
    assert min(tools) == 3 and max(tools) == 12 and min(thetas) >= 20 and max(thetas) <= 120


@pytest.mark.parametrize("name", [n for n in cc.job_names() if n.startswith("dwg_")])
def test_drawing_provenance_and_fixture(name):
    prov = json.loads((CORPUS / "provenance" / f"{name}.json").read_text())
    assert {"repo", "path", "commit", "licence", "blob_sha1", "copy", "scale"} <= set(prov)
    gen = _generator()
    assert gen._blob_sha(REPO_ROOT / prov["copy"]) == prov["blob_sha1"]
    assert len(prov["commit"]) == 40 and prov["licence"]


def test_freecad_fixture_for_every_job(jobs):
    for name in cc.job_names():
        prov = json.loads((cc.FIXTURES / f"{name}.json").read_text())
        assert prov["job"] == f"data/pockets/corpus/{name}.json" and "plan_time_s" in prov
        assert Path(cc.FIXTURES / f"{name}.ngc").exists()
        assert prov["settings"]["tool_diameter"] == jobs[name].tool_diameter


def test_bounded_freecad_fixtures_are_what_their_search_says(jobs):
    """FreeCAD held to the engagement bounds (benchmarks/freecad_bounded.py): for every job a
    provenance whose kept scale is the one its recorded search found (every coarse scale above it
    failed the bounds, the kept one met them) and whose settings are the job's stepover times that
    scale; or the reason there is none (FreeCAD writes nothing at the job's stepover, or no scale down
    to the search's minimum meets the bounds: every scale tried failed)."""
    kept = 0
    for name in cc.job_names():
        prov = json.loads((cc.FIXTURES_BOUNDED / f"{name}.json").read_text())
        tried = {t["scale"]: t for t in prov["tried"]}
        if "error" in prov:
            assert not any(t.get("ok") for t in prov["tried"]), name
            continue
        s = prov["stepover_scale"]
        assert tried[s]["ok"] and 0.5 <= s <= 1.0, name
        assert cc.meets_bounds(jobs[name].theta_deg + tried[s]["p95_minus_theta_deg"],
                               jobs[name].theta_deg + tried[s]["max_minus_theta_deg"],
                               tried[s]["share_above_5_pct"], jobs[name].theta_deg), name
        assert all(not t.get("ok") for k, t in tried.items() if k > s), name
        nominal = 100.0 * jobs[name].a_e / jobs[name].tool_diameter
        assert prov["settings"]["stepover_pct"] == pytest.approx(nominal * s, rel=1e-9), name
        assert (cc.FIXTURES_BOUNDED / f"{name}.ngc").exists()
        kept += 1
    assert kept > 0


def test_a_bounded_freecad_program_meets_the_bounds_when_measured_again(jobs):
    """The committed program of a small job, measured now by the evaluator at the corpus resolution,
    meets the bounds its provenance says it meets (a stale or hand-made fixture would not)."""
    from cnclab.toolpath.evaluate import evaluate_engagement
    from cnclab.works.jacso2021 import freecad_comparison as fx

    name = "gear_0"
    jb = jobs[name]
    ev = evaluate_engagement(fx.freecad_path(name, jb.tool, cc.FIXTURES_BOUNDED), jb, cc.resolution_mm(jb, False))
    prov = json.loads((cc.FIXTURES_BOUNDED / f"{name}.json").read_text())
    t = {x["scale"]: x for x in prov["tried"]}[prov["stepover_scale"]]
    assert cc.meets_bounds(ev.engagement_p95_deg, ev.engagement_max_deg, ev.share_above_5_pct, jb.theta_deg)
    # the same numbers as recorded (the evaluator is deterministic; 1e-3 deg: the rounding in the file)
    assert ev.engagement_max_deg - jb.theta_deg == pytest.approx(t["max_minus_theta_deg"], abs=1e-3)


def test_freecad_job_spec_scales_only_the_stepover(jobs):
    fa = _load(REPO_ROOT / "benchmarks" / "freecad_adaptive.py")
    jb = jobs["star_2"]
    full, held = fa.job_spec(jb), fa.job_spec(jb, 0.8)
    assert full["stepover_pct"] == pytest.approx(100.0 * jb.a_e / jb.tool_diameter, rel=1e-12)
    assert held["stepover_pct"] == pytest.approx(0.8 * full["stepover_pct"], rel=1e-12)
    assert {k: v for k, v in held.items() if not k.startswith("stepover")} == \
        {k: v for k, v in full.items() if not k.startswith("stepover")}
    for bad in (0.0, 1.2, -0.5):
        with pytest.raises(ValueError, match="stepover_scale"):
            fa.job_spec(jb, bad)


def test_bounded_targets_count_by_hand():
    """Three jobs, hand-counted: two programs faster than bounded FreeCAD's (ratio 0.5 and 1.0), one
    slower (1.1); one job without a bounded program is left out; lifts and uncut compared per job."""
    import math

    import pandas as pd

    df = pd.DataFrame({
        "theta_deg": [60.0, 60.0, 60.0, 60.0], "engagement_max_deg": [65.0, 65.0, 65.0, 65.0],
        "program_time_min": [1.0, 2.0, 1.1, 1.0], "program_time_min_fcb": [2.0, 2.0, 1.0, math.nan],
        "lifts": [1, 3, 1, 1], "lifts_fcb": [1, 2, 1, math.nan],
        "uncut_beyond_mm2": [1.0, 1.0, 2.0, 0.0], "uncut_beyond_mm2_fcb": [1.0, 0.6, 1.0, math.nan],
        "engagement_p95_deg_fcb": [61.0, 62.0, 61.0, math.nan], "engagement_max_deg_fcb": [69.0, 70.0, 62.0, math.nan],
        "share_above_5_pct_fcb": [0.1, 0.5, 0.0, math.nan]}, index=["a", "b", "c", "d"])
    T = cc.bounded_targets(df)
    assert T.loc["bounded FreeCAD meets the bounds (checked again here)", "measured"] == "3/3"
    prog = T.loc["program time <= bounded FreeCAD's on >= 95 %"]
    assert prog["measured"].startswith("66.7 % of 3 jobs") and "median ratio 1.000" in prog["measured"] and not prog["met"]
    assert T.loc["program time <= 1.05 x bounded FreeCAD's on all", "measured"] == "worst 1.100 (c)"
    assert T.loc["lifts <= bounded FreeCAD's on >= 95 %", "measured"].startswith("66.7 %")
    # b: 1.0 <= 0.6 + 0.5; c: 2.0 > 1.0 + 0.5
    assert T.loc["uncut <= bounded FreeCAD's + 0.5 mm^2 on >= 95 %", "measured"].startswith("66.7 %")
    assert cc.bounded_targets(df.drop(columns="program_time_min_fcb")).empty


@pytest.mark.parametrize("argv, says", [(["--min-scale", "2"], "--min-scale must be in (0, 1]"),
                                        (["--min-scale", "0"], "--min-scale must be in (0, 1]"),
                                        (["no_such_job"], "unknown job(s) ['no_such_job']")])
def test_freecad_bounded_refuses_bad_arguments_before_running_anything(argv, says):
    # a scale above 1 would write "no scale meets the bounds" over every fixture: refused up front
    fb = _load(REPO_ROOT / "benchmarks" / "freecad_bounded.py")
    before = {p.name: p.stat().st_mtime_ns for p in cc.FIXTURES_BOUNDED.iterdir()}
    with pytest.raises(SystemExit, match=re.escape(says)):
        fb.main(argv)
    assert {p.name: p.stat().st_mtime_ns for p in cc.FIXTURES_BOUNDED.iterdir()} == before


def test_time_breakdown_counts_by_hand():
    # a 40 x 20 pocket: a plunge from the clearance plane to -2 at x=5, a 4 mm cut, a G0 lift, a G0 of
    # 11 mm at clearance, a G0 down to 0.5 (air), a plunge to -2, a G1 retract. Two lifts from below the
    # stock top, one by G0 and one by G1 (the column counted only G1 retracts before)
    from shapely.geometry import box

    from cnclab.toolpath.evaluate import evaluate
    from cnclab.toolpath.job import Job
    from cnclab.toolpath.path import Tool, ToolPath

    tb = _load(REPO_ROOT / "benchmarks" / "time_breakdown.py")
    jb = Job(box(0, 0, 40, 20), Tool(6.0), 60.0, 2.0, feed_mm_min=300, spindle_rpm=5000, rapid_mm_min=6000)
    p = ToolPath.build([[5, 10, 5], [5, 10, -2], [9, 10, -2], [9, 10, 5], [20, 10, 5], [20, 10, 0.5], [20, 10, -2],
                        [20, 10, 5]], kind=["rapid", "plunge", "cut", "rapid", "rapid", "rapid", "plunge", "retract"],
                       feed=300)
    out = tb.breakdown(evaluate(p, jb, 0.25), jb)
    assert out["lifts"] == 2
    # rapids: 7 + 11 + 4.5 mm at 6000 mm/min (the first positioning is move 0: no length); entries: 7 + 2.5 mm at 300
    assert out["rapid"] == pytest.approx((7 + 11 + 4.5) / 6000, rel=1e-9)
    assert out["entry"] == pytest.approx((7 + 2.5) / 300, rel=1e-9)
    # the 4 mm cut and the 7 mm retract at feed 300: a cut into full material (slotting) is cut_theta,
    # the retract (z going up, no material) air at feed
    assert out["cut_theta"] + out["cut_low"] == pytest.approx(4 / 300, rel=1e-9)
    assert out["air_feed"] == pytest.approx(7 / 300, rel=1e-9)
    assert out["total"] == pytest.approx(sum(out[c] for c in tb.CLASSES), rel=1e-12)


@pytest.mark.parametrize("argv, says", [(["--radii", "0,1.5"], "every radius must be > 0 mm"),
                                        (["--radii", "1;2"], "comma-separated radii in mm"),
                                        (["--param", "no_such_field=1"], "NAME an AdaptiveParams field"),
                                        (["--param", "coarse_cell_max_r"], "NAME an AdaptiveParams field"),
                                        (["--param", "coarse_cell_max_r=x"], "is not a value of coarse_cell_max_r"),
                                        (["--param", "finish_resume_laps=2.5"], "is not a value of finish_resume_laps"),
                                        (["--param", "finish=yes"], "is not a value of finish (bool)"),
                                        (["--param", "rescue_turns_deg=30"], "is not set from the command line"),
                                        (["--param", "narrow_check_margin_deg=4"], "is not set from the command line")])
def test_random_pocket_bench_refuses_bad_arguments(argv, says):
    rp = _load(REPO_ROOT / "benchmarks" / "bench_random_pockets.py")
    with pytest.raises(SystemExit, match=re.escape(says)):
        rp.main(argv + ["--n", "0"])
    assert rp._params(["coarse_cell_max_r=1e-9", "finish_resume_laps=3"]).coarse_cell_max_r == 1e-9
    assert rp._params(["finish_resume_laps=3"]).finish_resume_laps == 3
    assert rp._params(["finish=False"]).finish is False and rp._params([]) == rp.AdaptiveParams()
