"""Issue 16: the engagement-controlled clearing planner (cnclab.toolpath.adaptive_clearing) against
FreeCAD Path Adaptive on every pocket of ``pocket_jobs.POCKETS``, scored by the same dixel rules
(benchmarks/score_paths.py; resolution 0.05 mm, 0.1 mm for the 120 x 85 pocket).

FreeCAD is run through its own Python (benchmarks/freecad_adaptive.py) when ``/usr/bin/python3`` can
import it (``apt-get install -y --no-install-recommends freecad``); otherwise the committed programs
tests/fixtures/freecad/<pocket>.ngc are scored (their plan times from the provenance JSON, measured
when they were made: a ratio to them is not from one run, and is marked so).
``--update-fixtures`` rewrites those programs and their provenance files.

Prints one table per pocket: planner x (p95, max, share above theta+5 / +15 deg, retracts, plunges
into material, rapids into material, uncut beyond the unreachable corners, program time, plan time)
and the ratios planner / FreeCAD. Times are wall-clock on a shared CPU: noisy.

    .venv/bin/python benchmarks/bench_vs_freecad.py [pocket ...] [--update-fixtures]
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from freecad_adaptive import freecad_available, read_program, run_freecad  # noqa: E402
from pocket_jobs import POCKETS, ROOT, load_job  # noqa: E402
from score_paths import score  # noqa: E402

from cnclab.fileio import atomic_write  # noqa: E402
from cnclab.toolpath.adaptive_clearing import plan_job  # noqa: E402

FIXTURES = ROOT / "tests" / "fixtures" / "freecad"
COLS = ["p95", "max", "share>5%", "share>15%", "entry_max", "retracts", "plunges", "rapids_in_mat",
        "uncut_beyond_mm2", "time_min", "plan_s"]


def freecad_program(name, job, live, update):
    ngc = FIXTURES / f"{name}.ngc"
    if live:
        out = ngc if update else Path("/tmp") / f"cnclab_fc_{name}.ngc"
        res = run_freecad(job, out)
        text = out.read_text(encoding="utf-8")
        if update:
            prov = {"job": job.source, "freecad_version": res["freecad_version"], "settings": res["settings"],
                    "command": res["command"], "plan_time_s": res["plan_time_s"],
                    "note": "libarea Adaptive2d + PathScripts.PathAdaptive.GenerateGCode + linuxcnc_post, "
                            "run headless by benchmarks/freecad_adaptive.py"}
            atomic_write(FIXTURES / f"{name}.json", json.dumps(prov, indent=1) + "\n")
        return text, res["plan_time_s"], True
    prov = json.loads((FIXTURES / f"{name}.json").read_text(encoding="utf-8"))
    return ngc.read_text(encoding="utf-8"), prov["plan_time_s"], False


def main(argv):
    update = "--update-fixtures" in argv
    names = [a for a in argv if not a.startswith("--")] or list(POCKETS)
    live = freecad_available()
    if update and not live:
        raise SystemExit("--update-fixtures needs FreeCAD (apt-get install -y --no-install-recommends freecad)")
    FIXTURES.mkdir(parents=True, exist_ok=True)
    print(f"FreeCAD: {'run live' if live else 'committed programs'}; CPU shared, times noisy")
    tables = {}
    for name in names:
        job = load_job(POCKETS[name])
        rows = {}
        text, t_fc, same_run = freecad_program(name, job, live, update)
        try:
            fc = score(read_program(text, job.tool), job)
            fc.pop("_trace")
        except ValueError as exc:    # FreeCAD wrote no motion (the pocket was not machined)
            fc = {c: float("nan") for c in COLS} | {"note": f"no program ({exc})"}
        fc["plan_s"] = t_fc
        t0 = time.perf_counter()
        try:
            tp = plan_job(job)
            t_pl = time.perf_counter() - t0
            pl = score(tp, job)
            pl.pop("_trace")
        except ValueError as exc:
            t_pl = time.perf_counter() - t0
            pl = {c: float("nan") for c in COLS} | {"note": f"refused: {exc}"}
        pl["plan_s"] = t_pl
        rows["FreeCAD Adaptive"] = fc
        rows["adaptive_clearing"] = pl
        T = pd.DataFrame(rows).T.reindex(columns=COLS)
        ratio = (T.loc["adaptive_clearing"].astype(float) / T.loc["FreeCAD Adaptive"].astype(float))
        T.loc["ratio planner/FreeCAD"] = ratio
        tables[name] = T
        print(f"\n== {name} ({job.source}; theta = {job.theta_deg:.2f} deg, resolution {job.resolution_mm} mm"
              f"{'' if same_run else '; FreeCAD plan time from the fixture, not this run'})")
        with pd.option_context("display.width", 200, "display.max_columns", 20, "display.precision", 3):
            print(T)
        for who, row in rows.items():
            if "note" in row:
                print(f"  {who}: {row['note']}")
    return tables


if __name__ == "__main__":
    main(sys.argv[1:])
