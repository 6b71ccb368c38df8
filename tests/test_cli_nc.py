"""``python -m cnclab analyze`` and ``plan``: argument handling, reading, outputs, errors, on the
real job loader, evaluator and planners (a small job file for the CLI's own work; every job file of
``data/`` for ``plan``)."""
import json
from pathlib import Path

import pandas as pd
import pytest

from cnclab.nc import cli_analyze, cli_plan
from cnclab.nc.gcode import read_gcode
from cnclab.nc.program import check_program

FREECAD = Path(__file__).parent / "fixtures" / "freecad"
RECT = "data/jacso2021/rectangle_pocket.json"


@pytest.fixture
def small_job(tmp_path):
    """A 24 x 16 mm pocket, 6 mm tool, no start hole (the planner makes its own entry)."""
    job = tmp_path / "job.json"
    job.write_text(json.dumps({"polygon": [[0, 0], [24, 0], [24, 16], [0, 16]], "tool_diameter": 6.0,
                               "teeth": 2, "v_c": 120.0, "f_z": 0.04, "feed_mm_min": 500.0, "a_p": 1.0,
                               "theta_deg": 60.0}))
    return job


def test_analyze_writes_every_output(tmp_path, capsys):
    rc = cli_analyze.main([str(FREECAD / "rectangle_pocket_adaptive_linuxcnc.ngc"), "--job", RECT,
                           "--resolution", "0.2", "-o", str(tmp_path / "out")])
    assert rc == 0
    out = capsys.readouterr().out
    assert "cut_length" in out and "engagement_p95" in out
    names = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert names == ["engagement_map.png", "events.csv", "summary.csv", "trace.csv", "trace.pdf", "trace.png"]
    tr = pd.read_csv(tmp_path / "out" / "trace.csv")
    assert list(tr.columns[:3]) == ["s_mm", "x", "y"] and tr["s_mm"].is_monotonic_increasing
    pdf = (tmp_path / "out" / "trace.pdf").read_bytes()
    assert pdf[:4] == b"%PDF"
    assert b"/CreationDate" not in pdf          # the same program and job give the same bytes on every run


def test_analyze_bad_program_names_file_line_word(tmp_path, small_job, capsys):
    bad = tmp_path / "bad.ngc"
    bad.write_text("G21\nG0 X0 Y0 Z5\nG81 X1 Y1 Z-1 R1 F100\n")
    assert cli_analyze.main([str(bad), "--job", str(small_job), "-o", str(tmp_path / "out")]) == 2
    assert "bad.ngc:3: word G81" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()          # nothing written


def test_analyze_argument_errors(tmp_path, small_job, capsys):
    job = small_job
    prog = FREECAD / "star_pocket_adaptive_grbl.nc"
    assert cli_analyze.main([str(prog), "--job", str(job), "--resolution", "-1"]) == 2
    assert "--resolution" in capsys.readouterr().err
    assert cli_analyze.main([str(tmp_path / "none.ngc"), "--job", str(job)]) == 2
    assert "no such program file" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        cli_analyze.main([str(prog)])                # --job is required


def test_plan_writes_a_safe_program_and_never_overwrites_the_job(tmp_path, small_job, capsys):
    job = small_job
    before = job.read_bytes()
    out = tmp_path / "p.ngc"
    assert cli_plan.main([str(job), "-o", str(out)]) == 0
    text = out.read_text()
    assert check_program(text, clearance_z=5.0).ok
    assert read_gcode(text).tool_number == 1
    assert cli_plan.main([str(job), "-o", str(job)]) == 2
    assert "refusing to overwrite the input file" in capsys.readouterr().err
    assert job.read_bytes() == before
    assert cli_plan.main([str(job), "-o", str(out), "--strategy", "nope"]) == 2
    assert "unknown strategy" in capsys.readouterr().err


def test_cli_is_registered():
    from cnclab.__main__ import COMMANDS

    assert COMMANDS["analyze"][0] == "cnclab.nc.cli_analyze"
    assert COMMANDS["plan"][0] == "cnclab.nc.cli_plan"
    assert COMMANDS["programs"][0] == "cnclab.works.programs"


def test_analyze_real_freecad_program_reports_engagement(tmp_path):
    res = cli_analyze.analyze(FREECAD / "star_pocket_adaptive_linuxcnc.ngc", "data/jacso2021/star_pocket.json",
                              resolution_mm=0.1, outdir=tmp_path, quiet=True)
    ev = res["evaluation"]
    assert 0 < ev.engagement_p50_deg <= 180 and ev.cut_length_mm > 0


# the issue-29 corpus (data/pockets/corpus, 71 jobs) is scored by benchmarks/bench_corpus.py, not here
@pytest.mark.parametrize("job", sorted(str(p) for p in Path("data").rglob("*.json")
                                       if "corpus" not in p.parts and (
                                           '"tool_diameter"' in p.read_text() and '"polygon"' in p.read_text()
                                           or '"star"' in p.read_text())))
def test_plan_real_every_job_file(tmp_path, job):
    out = cli_plan.plan_program(job, tmp_path / "p.ngc", quiet=True)
    chk = check_program(out.read_text(), clearance_z=5.0)
    assert chk.ok, chk.errors[:3]           # rapids above clearance or in cleared area, no plunge into stock
