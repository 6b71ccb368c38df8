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

The second half (:func:`adversarial_cases`) generates adversarial *pockets* from a seed -- necks
narrower than the tool, wedges of 5-15 deg, islands touching a wall, pockets smaller than the tool,
self-intersecting outlines, duplicated points, huge coordinates, NaN, inch-looking values -- and
plans each with every registered strategy in turn, alternately through the API
(:func:`cnclab.toolpath.planners.plan`) and the CLI. Each case is classified **correct** (a program
that passes :func:`~cnclab.nc.program.check_program`, and whose path, re-simulated by the one
evaluator, has no plunge or rapid into material and no wall gouge beyond
:data:`~cnclab.toolpath.planners.GOUGE_TOL_MM`), **clear error** (``ValueError`` / exit 2 whose
message names the job file or a job key, nothing written) or **wrong** (anything else: must be 0).
The counts by class are printed and asserted to include both correct programs and clear errors.
"""
from __future__ import annotations

import collections
import hashlib
import json
import math

import numpy as np
import pytest

from cnclab.nc import cli_plan
from cnclab.nc.arcfit import DEFAULT_TOL_MM
from cnclab.nc.gcode import read_toolpath
from cnclab.nc.program import check_program, write_program
from cnclab.runtime import pick
from cnclab.toolpath import coverage, planners
from cnclab.toolpath.evaluate import evaluate
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


def _mutation_case(tmp_path, capsys, fam, value, strategy) -> str:
    """One mutated job through the CLI: "error" or "program" (asserting what each must satisfy)."""
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
        assert ("fuzz_job" in err or "p.ngc: not written" in err) and not out.exists(), (fam, value, strategy, err)
        return "error"
    assert rc == 0, (fam, value, strategy, err)
    text = out.read_text()
    assert check_program(text, clearance_z=float(d.get("clearance_z", 5.0)), top_z=0.0).ok, (fam, value, strategy)
    assert "uncut beyond unreachable corners by region" in text
    return "program"


def test_plan_cli_error_or_safe_program(tmp_path, capsys):
    """Every mutated job ends in a clear error or a safe program, and the cases produce both (a suite
    that only ever refuses, or never refuses, tests nothing). One test over all cases: the counts
    need them in one process (xdist)."""
    outcomes = collections.Counter()
    for k, (fam, value, strategy) in enumerate(CASES):
        sub = tmp_path / f"case{k}"
        sub.mkdir()
        outcomes[(fam, _mutation_case(sub, capsys, fam, value, strategy))] += 1
    assert {kind for _, kind in outcomes} == {"error", "program"}, outcomes
    assert sum(outcomes.values()) == len(CASES)


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


# --- adversarial pockets x every strategy x API and CLI (issue 28 item 4) ---------------------------

D_TOOL = 6.0
#: planning resolution of the adversarial cases (mm): D / 20, the coarsest the safety tests use
RES_FUZZ = 0.3
#: evaluation dixel of the re-simulation (mm): r / 20
H_FUZZ = 0.15
#: wall gouge allowed in a *written* program (mm): the planner's GOUGE_TOL_MM plus the arc-fitting
#: tolerance every program header states (cnclab.nc.arcfit.DEFAULT_TOL_MM) and the 4-decimal rounding
WRITTEN_GOUGE_TOL_MM = planners.GOUGE_TOL_MM + DEFAULT_TOL_MM + 1e-4


def _rect(w, h, x0=0.0, y0=0.0):
    return [[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]]


def _neck(rng):
    """Two rooms joined by a neck 0.3-0.95 D wide (narrower than the tool)."""
    a, w = rng.uniform(9, 13), rng.uniform(0.3, 0.95) * D_TOOL
    L = rng.uniform(4, 10)
    y0, y1 = (a - w) / 2, (a + w) / 2
    return {"polygon": [[0, 0], [a, 0], [a, y0], [a + L, y0], [a + L, 0], [2 * a + L, 0], [2 * a + L, a],
                        [a + L, a], [a + L, y1], [a, y1], [a, a], [0, a]]}


def _wedge(rng):
    """A wedge whose apex is 5-15 deg, closed by a room wide enough for the tool."""
    apex = np.radians(rng.uniform(5, 15))
    L = rng.uniform(20, 30)
    h = L * np.tan(apex / 2)
    return {"polygon": [[0, 0], [L, -h], [L, -7], [L + 12, -7], [L + 12, 7], [L, 7], [L, h]]}


def _island_touching(rng):
    """An island that touches (or crosses) the outer wall, or another island."""
    W, H = rng.uniform(22, 30), rng.uniform(16, 22)
    x = rng.uniform(6, W - 12)
    kind = int(rng.integers(3))
    isl = ([[x, 0], [x + 5, 0], [x + 5, 5], [x, 5]] if kind == 0 else                   # on the wall
           [[x, -1], [x + 5, -1], [x + 5, 5], [x, 5]] if kind == 1 else                 # through it
           [[x, 6], [x + 5, 6], [x + 5, 10], [x + 10, 10], [x + 10, 6.0001], [x, 6]])  # a near-degenerate ring
    return {"polygon": _rect(W, H), "islands": [isl]}


def _tiny(rng):
    """A pocket about the tool's size (0.5-1.3 D)."""
    s = rng.uniform(0.5, 1.3) * D_TOOL
    return {"polygon": _rect(s, s * rng.uniform(0.8, 1.2))}


def _self_intersecting(rng):
    """A bow tie, or a rectangle with one vertex pulled across the opposite edge."""
    W, H = rng.uniform(15, 25), rng.uniform(10, 18)
    if rng.random() < 0.5:
        return {"polygon": [[0, 0], [W, H], [W, 0], [0, H]]}
    return {"polygon": [[0, 0], [W, 0], [W, H], [W / 2, -H / 2], [0, H]]}


def _duplicated(rng):
    """Repeated vertices: consecutive duplicates, the closing point, a point repeated later."""
    P = _rect(rng.uniform(16, 24), rng.uniform(12, 16))
    k = int(rng.integers(4))
    P = P[:k + 1] + [P[k]] * int(rng.integers(1, 4)) + P[k + 1:]
    if rng.random() < 0.5:
        P = P + [P[0]]
    if rng.random() < 0.3:
        P = P + [P[1]]                                  # revisits a vertex: a zero-width spike
    return {"polygon": P}


def _huge(rng):
    """A small pocket far from the origin (1e3-1e8 mm: inside and beyond the writer's +-1e4 mm and the
    job format's 1e6 mm): float precision and the program's number format."""
    off = 10.0 ** rng.uniform(3, 8)
    return {"polygon": _rect(rng.uniform(16, 22), rng.uniform(12, 16), off, -off)}


def _nan(rng):
    """NaN or infinity in a coordinate or a cutting value (JSON: the non-standard NaN / Infinity tokens)."""
    d = {"polygon": _rect(20, 14)}
    key = ["polygon", "a_p", "theta_deg", "tool_diameter"][int(rng.integers(4))]
    v = [math.nan, math.inf, -math.inf][int(rng.integers(3))]
    if key == "polygon":
        d["polygon"][int(rng.integers(4))][int(rng.integers(2))] = v
    else:
        d[key] = v
    return d


def _inch(rng):
    """Every length in inches, written where mm are expected (a 0.8 x 0.6 'mm' pocket, a 0.25 'mm' tool),
    or only the tool in inches on a pocket in mm."""
    if rng.random() < 0.5:       # v_c 100 m/min needs 127324 rpm on this tool: refused with the inch hint
        return {"polygon": _rect(20, 14), "tool_diameter": 0.25, "a_p": 0.08}
    d = {"polygon": _rect(0.8, 0.6), "tool_diameter": 0.25, "a_p": 0.04}
    if rng.random() < 0.5:
        d["v_c"] = 15.0          # a cutting speed the spindle reaches on a 0.25 mm tool: plausible numbers
    return d


ADVERSARIAL = (_neck, _wedge, _island_touching, _tiny, _self_intersecting, _duplicated, _huge, _nan, _inch)


def adversarial_cases(seed=2805, n=None):
    """``n`` cases (default 63 = every family x every strategy once, 27 in fast mode) ``(family, job dict, strategy, via)``: families and
    strategies cycle (every family meets every strategy over the slow run), ``via`` alternates
    ``api`` / ``cli``; the geometry of each case is drawn from ``seed``."""
    rng = np.random.default_rng(seed)
    n = n or pick(63, 27)
    strategies = sorted(planners.STRATEGIES)
    out = []
    for k in range(n):
        fam = ADVERSARIAL[k % len(ADVERSARIAL)]
        d = dict(BASE, a_p=1.0, theta_deg=60)
        d.pop("polygon")
        d.update(fam(rng))
        out.append((fam.__name__[1:], d, strategies[(k // len(ADVERSARIAL) + k) % len(strategies)],
                    "api" if k % 2 == 0 else "cli"))
    return out


ADV_CASES = adversarial_cases()


def _names_input(msg: str, source: str) -> bool:
    """A clear error names the job file or a job key ($.key) or the option."""
    return source in msg or "$." in msg or "resolution" in msg


def _safe_path(path, job, tol_mm=planners.GOUGE_TOL_MM) -> list:
    """What is wrong with a path re-simulated by the evaluator (empty: nothing); ``tol_mm``: the wall
    gouge allowed (mm)."""
    ev = evaluate(path, job, min(H_FUZZ, job.tool_radius / 10))
    gouge, at = coverage.wall_gouge(path, job)
    bad = []
    if ev.plunges_into_material:
        bad.append(f"{ev.plunges_into_material} plunge(s) into material")
    if ev.rapids_into_material:
        bad.append(f"{ev.rapids_into_material} rapid(s) into material")
    if gouge > tol_mm:
        bad.append(f"wall gouge {gouge:.4f} mm at {at}")
    return bad


def _adv_api(d, strategy, source):
    try:
        job = Job.from_dict(d, source=source)
        path = planners.plan(job, strategy, min(RES_FUZZ, job.tool_diameter / 10), allow_uncut=True)
        text = write_program(path, job)
    except ValueError as exc:
        return ("clear error", str(exc)) if _names_input(str(exc), source) else ("wrong", f"vague: {exc}")
    except Exception as exc:          # noqa: BLE001 -- the point: any other exception is a wrong outcome
        return "wrong", f"{type(exc).__name__}: {exc}"
    chk = check_program(text, clearance_z=job.clearance_z, top_z=job.top_z)
    bad = ([] if chk.ok else chk.errors[:3]) + _safe_path(path, job)
    return ("wrong", "; ".join(bad)) if bad else ("correct", "")


def _adv_cli(d, strategy, tmp_path, capsys):
    jf = tmp_path / "adv_job.json"
    jf.write_text(json.dumps(d))                       # NaN / Infinity as JSON's non-standard tokens
    before = hashlib.sha256(jf.read_bytes()).hexdigest()
    out = tmp_path / "adv.ngc"
    res = min(RES_FUZZ, d["tool_diameter"] / 10) if math.isfinite(d["tool_diameter"]) else RES_FUZZ
    try:
        rc = cli_plan.main([str(jf), "-o", str(out), "--strategy", strategy, "--allow-uncut",
                            "--resolution", f"{res:g}"])
    except BaseException as exc:      # noqa: BLE001 -- a traceback out of the CLI is a wrong outcome
        return "wrong", f"{type(exc).__name__}: {exc}"
    err = capsys.readouterr().err
    if hashlib.sha256(jf.read_bytes()).hexdigest() != before:
        return "wrong", "the job file was changed"
    if rc == 2:
        ok = err.startswith("error: ") and ("adv_job" in err or "adv.ngc: not written" in err) and not out.exists()
        return ("clear error", err) if ok else ("wrong", f"vague or partial: {err}")
    if rc != 0 or not out.exists():
        return "wrong", f"exit {rc}: {err}"
    text = out.read_text()
    job = Job.from_dict(d, source=str(jf))
    chk = check_program(text, clearance_z=job.clearance_z, top_z=job.top_z)
    bad = ([] if chk.ok else chk.errors[:3]) + _safe_path(read_toolpath(out, tool=job.tool), job, WRITTEN_GOUGE_TOL_MM)
    return ("wrong", "; ".join(bad)) if bad else ("correct", "")


def test_adversarial_pockets_correct_or_clear_error(tmp_path, capsys):
    """Every generated case is a correct program or a clear error, never wrong; the counts by class
    are printed and cover both correct programs and clear errors (a suite that only refuses, or never
    refuses, tests nothing). One test over all cases: the counts need them in one process (xdist)."""
    by_class, by_family, wrong = collections.Counter(), collections.Counter(), []
    for k, (fam, d, strategy, via) in enumerate(ADV_CASES):
        if via == "api":
            kind, why = _adv_api(d, strategy, f"adv_{fam}.json")
        else:
            sub = tmp_path / f"case{k}"
            sub.mkdir()
            kind, why = _adv_cli(d, strategy, sub, capsys)
        by_class[kind] += 1
        by_family[(fam, kind)] += 1
        if kind == "wrong":
            wrong.append((k, fam, strategy, via, why[:400]))
    with capsys.disabled():
        print("\nplan fuzz, adversarial pockets:", len(ADV_CASES), "cases, by class", dict(by_class))
    assert not wrong, wrong
    assert by_class["correct"] >= 1 and by_class["clear error"] >= 1, (by_class, dict(by_family))
