"""``python -m cnclab analyze`` and ``plan``: argument handling, reading, outputs, errors.

INTEGRATOR NOTE: cnclab.toolpath.job / evaluate / planners (toolpath-core, issue 12) are not on this
branch. These tests put tiny stand-ins for ``load_job``, ``evaluate`` and ``plan`` into the CLI
modules with monkeypatch (only here) to test the CLI's own work: reading real programs, refusing
bad ones with file/line/word, atomic outputs, never overwriting inputs. After the merge, the tests
marked ``needs_toolpath_core`` run against the real functions.
"""
import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from shapely.geometry import box

from cnclab.nc import cli_analyze, cli_plan
from cnclab.nc.gcode import read_gcode
from cnclab.nc.program import check_program
from cnclab.toolpath.path import Tool, ToolPath

FREECAD = Path(__file__).parent / "fixtures" / "freecad"
HAVE_CORE = cli_analyze.evaluate is not None and cli_plan.plan is not None


@dataclasses.dataclass
class _Job:                      # stand-in for cnclab.toolpath.job.Job (the fields the CLIs use)
    polygon: object
    tool: Tool
    clearance_z: float = 5.0
    top_z: float = 0.0
    spindle_rpm: float = 6366.0
    rapid_mm_min: float = 10000.0


class _Eval:                     # stand-in for cnclab.toolpath.evaluate.Evaluation (schema subset)
    def __init__(self, path):
        P, _ = path.polyline(0.5)
        s = np.r_[0, np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))]
        self.trace = {"s_mm": s, "x": P[:, 0], "y": P[:, 1], "engagement_deg": np.full(len(P), 60.0),
                      "mrr_mm3_min": np.zeros(len(P)), "feed_mm_min": np.full(len(P), 254.6),
                      "kind": np.array(["cut"] * len(P))}
        self.cut_length_mm = path.lengths()["feed_mm"]

    def summary_table(self):
        return pd.DataFrame({"metric": ["cut_length"], "value": [self.cut_length_mm], "unit": ["mm"]})


@pytest.fixture
def standins(monkeypatch):
    if HAVE_CORE:
        pytest.skip("the real toolpath-core functions are present: see test_*_real")
    job = _Job(box(0, 0, 40, 24), Tool(6.0))
    monkeypatch.setattr(cli_analyze, "load_job", lambda p: job)
    monkeypatch.setattr(cli_analyze, "evaluate", lambda path, j, res: _Eval(path))
    monkeypatch.setattr(cli_plan, "load_job", lambda p: job)

    def plan(j, strategy="constant-engagement"):
        if strategy not in ("constant-engagement", "zigzag"):
            raise KeyError(f"unknown strategy {strategy!r}")
        pts = [[20, 12, 1], [22, 12, -3], [30, 12, -3], [30, 12, 2]]
        return ToolPath.build(pts, kind=["rapid", "ramp", "cut", "retract"], feed=254.6, tool=j.tool,
                              info={"strategy": strategy})
    monkeypatch.setattr(cli_plan, "plan", plan)
    return job


def test_analyze_writes_every_output(tmp_path, standins, capsys):
    job = tmp_path / "job.json"
    job.write_text("{}")
    rc = cli_analyze.main([str(FREECAD / "rectangle_pocket_adaptive_linuxcnc.ngc"), "--job", str(job),
                           "--resolution", "0.1", "-o", str(tmp_path / "out")])
    assert rc == 0
    out = capsys.readouterr().out
    assert "cut_length" in out
    names = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert names == ["engagement_map.png", "summary.csv", "trace.csv", "trace.pdf", "trace.png"]
    tr = pd.read_csv(tmp_path / "out" / "trace.csv")
    assert list(tr.columns[:3]) == ["s_mm", "x", "y"] and tr["s_mm"].is_monotonic_increasing
    assert (tmp_path / "out" / "trace.pdf").read_bytes()[:4] == b"%PDF"


def test_analyze_bad_program_names_file_line_word(tmp_path, standins, capsys):
    bad = tmp_path / "bad.ngc"
    bad.write_text("G21\nG0 X0 Y0 Z5\nG81 X1 Y1 Z-1 R1 F100\n")
    job = tmp_path / "job.json"
    job.write_text("{}")
    assert cli_analyze.main([str(bad), "--job", str(job), "-o", str(tmp_path / "out")]) == 2
    assert "bad.ngc:3: word G81" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()          # nothing written


def test_analyze_argument_errors(tmp_path, standins, capsys):
    job = tmp_path / "job.json"
    job.write_text("{}")
    prog = FREECAD / "star_pocket_adaptive_grbl.nc"
    assert cli_analyze.main([str(prog), "--job", str(job), "--resolution", "-1"]) == 2
    assert "--resolution" in capsys.readouterr().err
    assert cli_analyze.main([str(tmp_path / "none.ngc"), "--job", str(job)]) == 2
    assert "no such program file" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        cli_analyze.main([str(prog)])                # --job is required


def test_plan_writes_a_safe_program_and_never_overwrites_the_job(tmp_path, standins, capsys):
    job = tmp_path / "job.json"
    job.write_text("{}")
    out = tmp_path / "p.ngc"
    assert cli_plan.main([str(job), "-o", str(out)]) == 0
    text = out.read_text()
    assert check_program(text, clearance_z=5.0).ok
    assert read_gcode(text).tool_number == 1
    assert cli_plan.main([str(job), "-o", str(job)]) == 2
    assert "refusing to overwrite the input file" in capsys.readouterr().err
    assert job.read_text() == "{}"
    assert cli_plan.main([str(job), "-o", str(out), "--strategy", "nope"]) == 2
    assert "unknown strategy" in capsys.readouterr().err


def test_cli_is_registered():
    from cnclab.__main__ import COMMANDS

    assert COMMANDS["analyze"][0] == "cnclab.nc.cli_analyze"
    assert COMMANDS["plan"][0] == "cnclab.nc.cli_plan"
    assert COMMANDS["programs"][0] == "cnclab.works.programs"


@pytest.mark.skipif(not HAVE_CORE, reason="needs_toolpath_core: cnclab.toolpath.job/evaluate/planners not merged")
def test_analyze_real_freecad_program_reports_engagement(tmp_path):
    res = cli_analyze.analyze(FREECAD / "star_pocket_adaptive_linuxcnc.ngc", "data/jacso2021/star_pocket.json",
                              resolution_mm=0.1, outdir=tmp_path, quiet=True)
    ev = res["evaluation"]
    assert 0 < ev.engagement_p50_deg <= 180 and ev.cut_length_mm > 0


@pytest.mark.skipif(not HAVE_CORE, reason="needs_toolpath_core: cnclab.toolpath.job/planners not merged")
@pytest.mark.parametrize("job", sorted(str(p) for p in Path("data").rglob("*.json")
                                       if '"tool_diameter"' in p.read_text() and '"polygon"' in p.read_text()
                                       or '"star"' in p.read_text()))
def test_plan_real_every_job_file(tmp_path, job):
    out = cli_plan.plan_program(job, tmp_path / "p.ngc", quiet=True)
    assert check_program(out.read_text(), clearance_z=5.0).rapids_below_clearance == 0
