"""Issue 29 on the pocket corpus (``data/pockets/corpus``, 71 jobs the planner was not developed on):
the default planner against FreeCAD Path Adaptive (same tool, stepover, feed), one row per job, the
per-family distribution table and the issue-29 targets, all computed by
:mod:`cnclab.works.jacso2021.corpus_comparison` and run through :func:`cnclab.sweep.sweep` (serial,
``CNCLAB_SWEEP_JOBS=N`` local processes, or a Dask cluster with ``CNCLAB_DASK_SCHEDULER=tcp://host:port``).

FreeCAD's programs are the committed fixtures ``tests/fixtures/freecad/corpus/<job>.ngc`` (their plan
time in ``<job>.json``); ``--update-fixtures`` regenerates them live with FreeCAD's own Python
(``benchmarks/freecad_adaptive.py``; needs ``apt-get install freecad``) before scoring, so the
plan-time ratio is then measured on the same machine in the same session.

    .venv/bin/python benchmarks/bench_corpus.py [JOB ...] [--fast] [--update-fixtures] [--live-freecad-time]
                                                [--out DIR]

FreeCAD Adaptive is not deterministic (two runs of a job write different programs), so the committed
programs stay the comparison's; ``--live-freecad-time`` runs FreeCAD on each job just before our
planner plans it, in the same worker (programs to a temporary folder, not scored), and takes its plan
time from that run, so that the plan-time ratio is measured back to back with ours (the machine's
speed drifts: up to 1.8 x within one 13-minute run, when FreeCAD's times were all taken first) while
every other column still scores the committed programs (``corpus_run.json`` says which).

Writes ``DIR/corpus_rows.csv`` (one row per job), ``DIR/corpus_families.csv`` (per family) and
``DIR/corpus_targets.csv`` (the targets, met or not), ``DIR/corpus_bounded.csv`` (the program-time,
lifts and uncut targets again against FreeCAD held to the same engagement bounds: the fixtures of
``benchmarks/freecad_bounded.py``, FreeCAD at the largest stepover whose program meets them) and ``DIR/corpus_run.json`` (commit, date,
mode) -- DIR defaults to ``benchmarks/results`` (the committed run the notebook
``notebooks/jacso2021/adaptive_vs_freecad.ipynb`` draws) -- and prints them. Times are wall clock on a shared CPU: noisy.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from freecad_adaptive import freecad_available, run_freecad  # noqa: E402

from cnclab.fileio import atomic_write  # noqa: E402
from cnclab.sweep import sweep  # noqa: E402
from cnclab.works.jacso2021 import corpus_comparison as cc  # noqa: E402


def update_fixtures(names) -> None:
    """Run FreeCAD Adaptive on every job and write ``<job>.ngc`` + provenance ``<job>.json``."""
    cc.FIXTURES.mkdir(parents=True, exist_ok=True)
    for name in names:
        job = cc.job(name)
        out = cc.FIXTURES / f"{name}.ngc"
        t0 = time.perf_counter()
        try:
            res = run_freecad(job, out)
        except Exception as exc:       # noqa: BLE001 -- FreeCAD's failure is recorded, not fatal
            prov = {"job": f"data/pockets/corpus/{name}.json", "error": str(exc)[-500:]}
            atomic_write(cc.FIXTURES / f"{name}.json", json.dumps(prov, indent=1) + "\n")
            print(f"{name}: FreeCAD failed: {str(exc)[-200:]}", flush=True)
            continue
        prov = {"job": f"data/pockets/corpus/{name}.json", "freecad_version": res["freecad_version"],
                "settings": res["settings"], "command": res["command"], "plan_time_s": res["plan_time_s"],
                "note": "libarea Adaptive2d + PathScripts.PathAdaptive.GenerateGCode + linuxcnc_post, "
                        "run headless by benchmarks/freecad_adaptive.py (bench_corpus.py --update-fixtures)"}
        atomic_write(cc.FIXTURES / f"{name}.json", json.dumps(prov, indent=1) + "\n")
        print(f"{name}: FreeCAD {res['plan_time_s']:.2f} s plan, {time.perf_counter() - t0:.1f} s wall", flush=True)


def live_freecad_time(name: str) -> float:
    """FreeCAD Adaptive's plan time (s, in its process, as the fixtures record it) of job ``name``, run
    now into a temporary folder (the program is not kept); NaN where FreeCAD fails."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        try:
            return float(run_freecad(cc.job(name), Path(tmp) / f"{name}.ngc")["plan_time_s"])
        except Exception as exc:       # noqa: BLE001 -- as update_fixtures: recorded, not fatal
            print(f"{name}: FreeCAD failed: {str(exc)[-200:]}", flush=True)
            return float("nan")


def score_with_live_freecad(name: str, fast: bool) -> dict:
    """:func:`cc.score_job` with FreeCAD's plan time of the job measured just before ours, in the same
    worker (``plan_time_s_fc_live``): the two planners of a job run back to back, so a drift of the
    machine's speed during the run (this one's: up to 1.8 x within 13 minutes) hits both alike."""
    t_fc = live_freecad_time(name)
    return cc.score_job(name, fast) | {"plan_time_s_fc_live": t_fc}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("jobs", nargs="*", help="job names (default: the whole corpus)")
    ap.add_argument("--fast", action="store_true", help="evaluation and planning dixel doubled")
    ap.add_argument("--update-fixtures", action="store_true", help="regenerate FreeCAD's programs first")
    ap.add_argument("--fixtures-only", action="store_true", help="only regenerate FreeCAD's programs")
    ap.add_argument("--live-freecad-time", action="store_true",
                    help="FreeCAD's plan time from a run in this session (its programs not kept; the committed ones scored)")
    ap.add_argument("--out", default="benchmarks/results", help="output folder of the CSV tables")
    a = ap.parse_args(argv)
    names = a.jobs or cc.job_names()
    unknown = sorted(set(names) - set(cc.job_names()))
    if unknown:
        raise SystemExit(f"unknown job(s) {unknown}")
    if a.update_fixtures or a.fixtures_only:
        if not freecad_available():
            raise SystemExit("--update-fixtures needs FreeCAD (apt-get install -y --no-install-recommends freecad)")
        update_fixtures(names)
        if a.fixtures_only:
            return None
    t_start = time.perf_counter()
    commit = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    live = a.live_freecad_time
    if live and not freecad_available():
        raise SystemExit("--live-freecad-time needs FreeCAD (apt-get install -y --no-install-recommends freecad)")
    cc.warm()
    rows = sweep(score_with_live_freecad if live else cc.score_job, [(n, a.fast) for n in names])
    df = pd.DataFrame(rows).set_index("job")
    if live:
        # only where the committed program is scored (FreeCAD planned the job): a live time of a job whose
        # fixture records a failure or no cutting motion is not a plan time of a compared program
        live_s = df.pop("plan_time_s_fc_live")
        df["plan_time_s_fc"] = df["plan_time_s_fc"].where(df["plan_time_s_fc"].isna(), live_s)
    fam, tg, tb = cc.family_table(df), cc.targets(df), cc.bounded_targets(df)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    for fname, T in (("corpus_rows.csv", df), ("corpus_families.csv", fam), ("corpus_targets.csv", tg),
                     ("corpus_bounded.csv", tb)):
        atomic_write(out / fname, T.to_csv())
    run = {"commit": commit, "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()), "fast": bool(a.fast),
           "jobs": len(names), "freecad": "live-regenerated fixtures" if a.update_fixtures else "committed fixtures",
           "freecad_plan_time": ("live, each job's just before ours (programs not kept)" if live
                                 else "from the fixtures' provenance"),
           "wall_s": round(time.perf_counter() - t_start, 1)}
    atomic_write(out / "corpus_run.json", json.dumps(run, indent=1) + "\n")
    with pd.option_context("display.width", 250, "display.max_columns", 40, "display.precision", 3):
        print(df[cc.ROW_COLUMNS].to_string())
        print("\n== per family (worst over the family's jobs; ratios adaptive / FreeCAD)")
        print(fam.to_string())
        print("\n== issue-29 targets")
        print(tg.to_string())
        print("\n== against FreeCAD held to the same engagement bounds (benchmarks/freecad_bounded.py)")
        print(tb.to_string())
    return df


if __name__ == "__main__":
    main()
