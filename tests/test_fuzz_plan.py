"""Plan fuzz (issue 28 item 7): hostile and careless job files through ``python -m cnclab plan``
(every registered strategy in turn) and the public ``plan`` API. A seeded generator mutates a valid
small job (one key at a time, values from the families below); every case must end in one of two
outcomes:

* **error**: exit code 2, a message on stderr that names the job file (or, when the planned program
  fails the static safety check, the program it refused to write), and no output file; or
* **a program**: exit 0, the program passes the static safety check
  (:func:`cnclab.nc.program.check_program`) and its header states the uncut area by region.

The job file is never changed (hash before/after). Outcome counts by family are asserted to cover
both outcomes (a suite that only ever refuses, or never refuses, tests nothing).
"""
from __future__ import annotations

import collections
import hashlib
import json
import math

import numpy as np
import pytest

from cnclab.nc import cli_plan
from cnclab.nc.program import check_program
from cnclab.runtime import pick
from cnclab.toolpath import planners
from cnclab.toolpath.job import Job

BASE = {"polygon": [[0, 0], [24, 0], [24, 16], [0, 16]], "tool_diameter": 6, "teeth": 2, "theta_deg": 60,
        "a_p": 2, "v_c": 100, "f_z": 0.05}
#: family -> values for one key (JSON cannot carry NaN: the loader's own NaN guard is fuzzed elsewhere)
FAMILIES = {
    "a_p": [1e-6, 1e-4, 0.0009, 0.001, 2.0, 1e4],
    "depth": [3000.0, 2002.0, 1e9, 0.5, 4.0],          # 2002 / 2: 1001 levels, one over the limit
    "theta_deg": [1e-3, 0.5, 5.0, 120.0, 179.9],
    "tool_diameter": [0.01, 5.99, 15.9, 16.0, 1e4],
    "polygon": [[[0, 0], [24, 0], [48, 0]], [[0, 0], [24, 16], [24, 0], [0, 16]], [[0, 0], [1e-4, 0], [0, 1e-4]],
                [[0, 0], [24, 0], [24, 6.5], [0, 6.5]], [[0, 0], [60, 0], [60, 7], [0, 7]]],
    "islands": [[[[30, 30], [31, 30], [31, 31]]], [[[10, 7], [14, 7], [14, 9], [10, 9]]],
                [[[1, 1], [23, 1], [23, 15], [1, 15]]], [[[11.5, 7.5], [12.5, 7.5], [12.5, 8.5]]]],
    "clearance_z": [-1.0, 0.0, 1e5],
    "start_hole": [{"center": [12, 8], "diameter": 5}, {"center": [12, 8], "diameter": 7},
                   {"center": [2, 2], "diameter": 7}],
}


def cases(seed=28, n=None):
    rng = np.random.default_rng(seed)
    n = n or pick(40, 16)
    names = sorted(FAMILIES)
    strategies = sorted(planners.STRATEGIES)
    out = []
    for k in range(n):
        fam = names[k % len(names)]
        vals = FAMILIES[fam]
        out.append((fam, vals[int(rng.integers(len(vals)))], strategies[int(rng.integers(len(strategies)))]))
    return out


CASES = cases()
OUTCOMES = collections.Counter()


@pytest.mark.parametrize("fam,value,strategy", CASES, ids=[f"{f}-{i}" for i, (f, _, _) in enumerate(CASES)])
def test_plan_cli_error_or_safe_program(tmp_path, capsys, fam, value, strategy):
    d = dict(BASE)
    d[fam] = value
    job = tmp_path / "fuzz_job.json"
    job.write_text(json.dumps(d))
    before = hashlib.sha256(job.read_bytes()).hexdigest()
    out = tmp_path / "p.ngc"
    rc = cli_plan.main([str(job), "-o", str(out), "--strategy", strategy])
    err = capsys.readouterr().err
    assert hashlib.sha256(job.read_bytes()).hexdigest() == before
    if rc == 2:
        assert ("fuzz_job" in err or "p.ngc: not written" in err) and not out.exists(), err
        OUTCOMES[(fam, "error")] += 1
    else:
        assert rc == 0
        text = out.read_text()
        assert check_program(text, clearance_z=float(d.get("clearance_z", 5.0)), top_z=0.0).ok
        assert "uncut beyond unreachable corners by region" in text
        OUTCOMES[(fam, "program")] += 1


@pytest.mark.parametrize("res", [0.0, -0.1, math.nan, math.inf, "0.1"])
def test_plan_api_resolution_refused(res):
    job = Job.from_dict(BASE, source="res.json")
    with pytest.raises(ValueError, match=r"resolution_mm must be a finite number > 0 mm"):
        planners.plan(job, "zig-zag", res)


@pytest.mark.parametrize("res,why", [(0.61, "above D/10"), (3.0, "above D/10"), (100.0, "above D/10"),
                                     (0.004, "below 0.005 mm")])
def test_plan_resolution_bounded(res, why):
    """``resolution_mm`` outside [0.005, D/10] (D 6 mm: 0.6 mm) is refused before planning, naming the
    option, its bound, the job and why; the same through the CLI's ``--resolution``."""
    job = Job.from_dict(BASE, source="res.json")
    for strategy in sorted(planners.STRATEGIES):
        with pytest.raises(ValueError, match=rf"^resolution_mm {res:g} mm is outside \[0.005, 0.6\] mm for res.json "
                                             rf"\(tool D 6 mm\): {why}"):
            planners.plan(job, strategy, res)
    planners.check_resolution(0.6, job)                 # the bounds themselves are accepted
    planners.check_resolution(0.005, job)


def test_plan_cli_resolution_bounded(tmp_path, capsys):
    job = tmp_path / "res.json"
    job.write_text(json.dumps(BASE))
    out = tmp_path / "p.ngc"
    assert cli_plan.main([str(job), "-o", str(out), "--resolution", "0.7"]) == 2
    err = capsys.readouterr().err
    assert "error: --resolution 0.7 mm is outside [0.005, 0.6] mm for" in err and "res.json" in err, err
    assert not out.exists()
    assert cli_plan.main([str(job), "-o", str(out), "--resolution", "0.3", "--strategy", "zig-zag"]) == 0
    assert check_program(out.read_text(), clearance_z=5.0, top_z=0.0).ok


def test_outcomes_cover_both_kinds():
    """The fuzz above produced both refusals and programs (run after it: file order)."""
    kinds = {k for _, k in OUTCOMES}
    assert kinds == {"error", "program"}, OUTCOMES
    assert sum(OUTCOMES.values()) == len(CASES)
