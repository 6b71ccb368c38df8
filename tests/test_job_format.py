"""docs/job-format.md is the text generated from JOB_SCHEMA (so it cannot drift from the loader), it
documents every schema key, and every example in it loads."""
import json
import re
from pathlib import Path

from cnclab.toolpath.job import JOB_SCHEMA, Job
from cnclab.toolpath.job_format import job_format_markdown, main

DOC = Path(__file__).resolve().parents[1] / "docs" / "job-format.md"


def test_docs_job_format_is_generated_from_the_schema():
    assert DOC.read_text(encoding="utf-8") == job_format_markdown(), (
        "docs/job-format.md is out of date: run `python -m cnclab job --schema > docs/job-format.md`")


def test_every_key_is_documented_with_its_limits():
    text = job_format_markdown()
    for key, s in JOB_SCHEMA["properties"].items():
        row = re.search(rf"^\| `{key}` \|(.*)$", text, re.M)
        assert row, key
        for lim in ("minimum", "exclusiveMinimum", "maximum", "exclusiveMaximum"):
            if lim in s:
                assert f"{s[lim]:g}" in row.group(1), (key, lim)
    # a default the loader really uses: a job without 'teeth' gets the documented value
    teeth = re.search(r"^\| `teeth` \|.*?\| `(\d+)` \|", text, re.M).group(1)
    job = Job.from_dict({"polygon": [[0, 0], [40, 0], [40, 30], [0, 30]], "tool_diameter": 6, "theta_deg": 60,
                         "a_p": 3, "v_c": 120, "f_z": 0.04})
    assert job.teeth == int(teeth)


def test_every_example_in_the_doc_loads():
    blocks = re.findall(r"^```json\n(.*?)^```", DOC.read_text(encoding="utf-8"), re.S | re.M)
    assert len(blocks) >= 6
    for b in blocks:
        Job.from_dict(json.loads(b))


def test_job_cli_prints_the_reference_and_checks_a_file(capsys, tmp_path):
    assert main(["--schema"]) == 0
    assert capsys.readouterr().out == job_format_markdown()
    bad = tmp_path / "bad.json"
    bad.write_text('{"polygon": [[0, 0], [40, 0], [40, 30], [0, 30]], "tool_diameter": -6, "theta_deg": 60, "a_p": 3}')
    assert main(["--check", str(bad)]) == 2
    assert "$.tool_diameter" in capsys.readouterr().err
