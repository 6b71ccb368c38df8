"""Issue 16: the clearing planners of cnclab against FreeCAD Path Adaptive on every pocket of
:data:`cnclab.works.jacso2021.freecad_comparison.POCKETS` (Jacsó's star, rectangle and L, the Kim & Yang
120 x 85 pocket, data/pockets/*.json), all scored by the package's one evaluator
(:func:`cnclab.toolpath.evaluate.evaluate`, dixel 0.05 mm; 0.1 mm for the 120 x 85 pocket) on the job
read by the one loader (:func:`cnclab.toolpath.job.load_job`); FreeCAD's programs are read back by the
one G-code reader (:func:`cnclab.nc.gcode.read_toolpath`).

Rows: ``adaptive_clearing`` (planners.STRATEGIES["adaptive"]), the same path with Jacsó §4
engagement-based feed control (``freecad_comparison.feed_controlled``), the old ``ce_clearing``
(STRATEGIES["constant-engagement"]), ``hybrid_path`` on the pockets with a start hole, FreeCAD Adaptive.
Columns: p95, max, share above theta+5 / +15 deg, entry max, retracts, plunges and rapids into
material, uncut beyond the unreachable corners, program time (as written), plan time, wall gouge;
then every row divided by FreeCAD's, measured in one run. Last, the written programs: motion blocks
of adaptive_clearing's program as the one writer writes it (arcs fitted within 0.005 mm) against
FreeCAD's program, and both programs' time as length / feed and on the two machine models of
:mod:`cnclab.nc.machine` (small VMC, GRBL router: acceleration, junction deviation, block rate)
(issue 24 targets: blocks and machine time ours <= FreeCAD's on every pocket).

FreeCAD is run live through its own Python (benchmarks/freecad_adaptive.py) when ``/usr/bin/python3``
can import it (Debian: ``apt-get install -y --no-install-recommends freecad``); otherwise (or with
``--fixtures``) the committed programs tests/fixtures/freecad/<pocket>.ngc are scored and FreeCAD's
plan time is the one in <pocket>.json (then the plan-time ratio is NOT from one run: marked).
``--update-fixtures`` rewrites those programs and their provenance JSON (needs FreeCAD).
Times are wall clock on a shared CPU: noisy.

    .venv/bin/python benchmarks/bench_vs_freecad.py [pocket ...] [--fixtures] [--update-fixtures] [--fast]
                                                    [--adaptive-only]

``--adaptive-only`` leaves out the old ce_clearing and hybrid_path rows (tens of minutes in all).
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from freecad_adaptive import freecad_available, run_freecad  # noqa: E402

from cnclab.fileio import atomic_write  # noqa: E402
from cnclab.nc.arcfit import DEFAULT_TOL_MM  # noqa: E402
from cnclab.nc.gcode import program_time, read_gcode, read_toolpath  # noqa: E402
from cnclab.nc.machine import MACHINES, machine_time  # noqa: E402
from cnclab.works.jacso2021 import freecad_comparison as fx  # noqa: E402


def planner_rows(job, adaptive_only=False) -> dict:
    rows = dict(fx.PLANNER_ROWS)
    if adaptive_only:
        return {k: v for k, v in rows.items() if v == "adaptive"}
    if job.start_hole is not None:
        rows["hybrid_path"] = "hybrid"
    return rows


def freecad_live(name, job, update):
    """Run FreeCAD on the job: ``(ToolPath or None, plan s, note)``; with ``update`` the fixture and its
    provenance JSON are rewritten (atomically)."""
    out = fx.FIXTURES / f"{name}.ngc" if update else Path("/tmp") / f"cnclab_fc_{name}.ngc"
    res = run_freecad(job, out)
    if update:
        prov = {"job": fx.POCKETS[name], "freecad_version": res["freecad_version"], "settings": res["settings"],
                "command": res["command"], "plan_time_s": res["plan_time_s"],
                "note": "libarea Adaptive2d + PathScripts.PathAdaptive.GenerateGCode + linuxcnc_post, "
                        "run headless by benchmarks/freecad_adaptive.py"}
        atomic_write(fx.FIXTURES / f"{name}.json", json.dumps(prov, indent=1) + "\n")
    p = read_toolpath(out, tool=job.tool)
    if len(p) < 2 or not (p.xyz[:, 2] < job.top_z).any():
        return None, res["plan_time_s"], "FreeCAD wrote no cutting motion (run live)"
    return p, res["plan_time_s"], "run live in this run"


def main(argv):
    update = "--update-fixtures" in argv
    live = "--fixtures" not in argv and freecad_available()
    fast = "--fast" in argv
    adaptive_only = "--adaptive-only" in argv
    names = [a for a in argv if not a.startswith("--")] or list(fx.POCKETS)
    unknown = [n for n in names if n not in fx.POCKETS]
    if unknown:
        raise SystemExit(f"unknown pocket(s) {unknown}; choose from {list(fx.POCKETS)}")
    if update and not live:
        raise SystemExit("--update-fixtures needs FreeCAD (apt-get install -y --no-install-recommends freecad)")
    print(f"FreeCAD: {'run live' if live else 'committed programs (tests/fixtures/freecad)'}; "
          f"{'fast' if fast else 'full'} resolution; CPU shared, times noisy")
    # the planners' compiled kernels are loaded (or compiled) once before any timing, as FreeCAD's
    # plan time excludes its own start-up
    fx.warm_planners(sorted({s for n in names for s in planner_rows(fx.job(n), adaptive_only).values()}))
    tables, written = {}, {}
    for name in names:
        job = fx.job(name)
        freecad = freecad_live(name, job, update) if live else None
        keep = {}
        T = fx.comparison(name, planner_rows(job, adaptive_only), fast=fast, freecad=freecad, keep=keep)
        fc_file = fx.FIXTURES / f"{name}.ngc" if (update or not live) else Path("/tmp") / f"cnclab_fc_{name}.ngc"
        written[name] = written_programs(job, keep, fc_file)
        tables[name] = T
        R = fx.ratios(T)
        print(f"\n== {name} ({fx.POCKETS[name]}; theta = {job.theta_deg:.2f} deg, dixel {T.attrs['resolution_mm']} mm"
              f"{'' if live else '; FreeCAD plan time from the fixture JSON, not this run'})")
        with pd.option_context("display.width", 250, "display.max_columns", 20, "display.precision", 3):
            print(T[fx.COLUMNS])
            print("ratio to FreeCAD Adaptive:")
            print(R)
        for who, note in T["note"].items():
            if note:
                print(f"  {who}: {note}")
    print("\n== summary: adaptive_clearing / FreeCAD Adaptive, measured in this run")
    with pd.option_context("display.width", 250, "display.max_columns", 20, "display.precision", 3):
        print(fx.summary(tables))
        print("\n== written programs: motion blocks (G0/G1/G2/G3 read back by cnclab's reader), "
              f"ours with arcs fitted within {DEFAULT_TOL_MM} mm; FreeCAD's committed/live program; time as "
              "length / feed (rapids at the job's rate) and on the machine models of cnclab.nc.machine")
        print(pd.DataFrame(written).T.to_string(float_format=lambda v: f"{v:.3f}"))
    return tables


def written_programs(job, keep, fc_file) -> dict:
    """Motion blocks of the programs as written: the first planner row's program (the one writer's,
    :func:`cnclab.nc.program.write_program`, default arc fitting, kept by
    :func:`cnclab.works.jacso2021.freecad_comparison.as_written`) and FreeCAD's program."""
    label = next(k for k in keep if k != fx.FREECAD) if any(k != fx.FREECAD for k in keep) else None
    out = {}
    if label is not None:
        moves = read_gcode(keep[label][0].info["program"]).moves
        out["blocks ours"] = len(moves)
        out["arc blocks ours"] = sum(m.motion in ("G2", "G3") for m in moves)
        out["feed time ours min"] = program_time(moves, job.rapid_mm_min)["total_s"] / 60
        for key, m in MACHINES.items():
            out[f"machine {key} ours min"] = machine_time(moves, m)["time_machine_s"] / 60
    if fc_file.is_file():
        fc = read_gcode(fc_file.read_text(encoding="utf-8"), source=str(fc_file)).moves
        out["blocks FreeCAD"] = len(fc)
        if fc:
            out["feed time FreeCAD min"] = program_time(fc, job.rapid_mm_min)["total_s"] / 60
            for key, m in MACHINES.items():
                out[f"machine {key} FreeCAD min"] = machine_time(fc, m)["time_machine_s"] / 60
    if "blocks ours" in out and out.get("blocks FreeCAD"):
        out["blocks ratio"] = out["blocks ours"] / out["blocks FreeCAD"]
        for key in MACHINES:
            out[f"machine {key} ratio"] = out[f"machine {key} ours min"] / out[f"machine {key} FreeCAD min"]
    return out


if __name__ == "__main__":
    main(sys.argv[1:])
