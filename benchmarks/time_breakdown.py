"""Where the adaptive planner's program time goes against FreeCAD Adaptive's (issue 29 / 24 analysis).

Per job: both programs through the one evaluator; the time of every evaluation sample (its 3D length
over its feed, rapids at the job's rapid rate) is put into one class:

* ``cut_theta``: a feed sample with engagement >= theta - 10 deg (cutting at about theta);
* ``cut_low``: a feed sample with air_deg < engagement < theta - 10 deg (low-engagement cutting);
* ``air_feed``: a feed move in the xy plane meeting no material (engagement <= 0.5 deg: links at feed,
  air tails of passes, approach moves);
* ``entry``: helix/ramp/plunge samples (z going down at feed);
* ``rapid``: G0 (at depth and at clearance, retracts included).

Beside the classes' ``total`` (length / feed), ``machine`` is the same path on the small-VMC machine
model (``Evaluation.time_machine_s``: acceleration, corners; :mod:`cnclab.toolpath.motion`).

Both programs are timed as written: our path goes through :func:`cnclab.nc.program.write_program` and
is read back by the reader of FreeCAD's programs (as the corpus benchmark scores it). Per program also
``rapid_mm`` (G0 length, mm), ``removed_mm2`` (the area the tool can reach, the pocket's opening by r, less the
evaluator's uncut area beyond the unreachable corners) and ``cut_min_per_cm2`` (cutting time,
``cut_theta + cut_low``, per cm^2 removed): at equal engagement the two programs' values would be
equal; the ratio says how much of a program-time difference is the work done rather than the way.

Units: min. ``benchmarks/time_breakdown.py [--corpus] NAME ...`` prints one row per job (ours, FreeCAD);
``--corpus --all --csv PATH`` runs every corpus job FreeCAD planned and writes one row per job (the
columns of both programs, suffixes ``_ours`` / ``_FC``) and prints the corpus sums and the median
ratio of ``cut_min_per_cm2`` (the closing note of 2026-11-26 quotes that run).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from cnclab.nc.program import program_path  # noqa: E402
from cnclab.toolpath import planners  # noqa: E402
from cnclab.toolpath.evaluate import evaluate, unreachable_region  # noqa: E402
from cnclab.works.jacso2021 import corpus_comparison as cc  # noqa: E402
from cnclab.works.jacso2021 import freecad_comparison as fx  # noqa: E402

CLASSES = ["cut_theta", "cut_low", "air_feed", "entry", "rapid"]


def breakdown(ev, job) -> dict:
    """Program time (min) per class of an evaluation's samples (module docstring)."""
    tr = ev.trace
    P = np.c_[tr["x"], tr["y"], tr["z"]]
    L = np.r_[0.0, np.linalg.norm(np.diff(P, axis=0), axis=1)]
    kind = np.asarray(tr["kind"], object)
    feed = np.asarray(tr["feed_mm_min"], float)
    rapid = kind == "rapid"
    rate = np.where(rapid, job.rapid_mm_min, feed)
    t = np.where((L > 0) & np.isfinite(rate) & (rate > 0), L / np.where(rate > 0, rate, 1.0), 0.0)
    eng = np.nan_to_num(np.asarray(tr["engagement_deg"], float))
    dz = np.r_[0.0, np.diff(P[:, 2])]
    entry = ~rapid & (dz < -1e-9)
    cls = np.where(rapid, "rapid", np.where(entry, "entry", np.where(eng <= 0.5, "air_feed", np.where(
        eng < job.theta_deg - 10.0, "cut_low", "cut_theta"))))
    out = {c: float(t[cls == c].sum()) for c in CLASSES}
    out["total"] = float(t.sum())
    out["machine"] = float(ev.time_machine_s) / 60.0
    out["air_feed_mm"] = float(L[cls == "air_feed"].sum())
    out["rapid_mm"] = float(L[rapid].sum())
    out["lifts"] = fx.lifts(ev, job.top_z)     # rises from below the stock top (G0 or G1), as the corpus counts
    reach = job.polygon.area - unreachable_region(job.polygon, job.tool_radius).area   # the evaluator's opening
    out["removed_mm2"] = float(reach - ev.uncut_beyond_unreachable_mm2)
    out["cut_min_per_cm2"] = (out["cut_theta"] + out["cut_low"]) / (out["removed_mm2"] / 100.0)
    return out


def run(name, corpus):
    jb = cc.job(name) if corpus else fx.job(name)
    h = cc.resolution_mm(jb, False) if corpus else (0.1 if "120x85" in name else 0.05)
    t0 = time.perf_counter()
    tp = planners.plan(jb, "adaptive", h, allow_uncut=True, written=program_path)
    t_plan = time.perf_counter() - t0
    rows = {"ours": breakdown(evaluate(fx.as_written(tp, jb), jb, h), jb) | {"plan_s": t_plan, "info": {k: tp.info.get(k) for k in (
        "passes", "entries", "links", "remnant_sweeps", "clean_rounds")}}}
    try:
        fp = fx.freecad_path(name, jb.tool, cc.FIXTURES if corpus else fx.FIXTURES)
        rows["FC"] = breakdown(evaluate(fp, jb, h), jb)
    except Exception as exc:   # noqa: BLE001
        print(name, "FreeCAD:", exc)
    return rows


def corpus_table(path) -> pd.DataFrame:
    """Every corpus job with a FreeCAD program: one row (both programs' columns); written to ``path``."""
    from cnclab.fileio import atomic_write

    rows = []
    for n in cc.job_names():
        R = run(n, True)
        if "FC" not in R:
            continue
        rows.append({"job": n} | {f"{c}_{k}": v for k, r in R.items() for c, v in r.items() if c != "info"})
    df = pd.DataFrame(rows).set_index("job")
    atomic_write(Path(path), df.to_csv())
    return df


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("jobs", nargs="*", help="pocket names (the comparison's, or the corpus's with --corpus)")
    ap.add_argument("--corpus", action="store_true", help="the names are corpus jobs")
    ap.add_argument("--all", action="store_true", help="every corpus job FreeCAD planned (with --corpus and --csv)")
    ap.add_argument("--csv", help="with --all: the table's path")
    a = ap.parse_args(argv)
    if a.all and not (a.corpus and a.csv):
        raise SystemExit("--all needs --corpus and --csv PATH")
    cc.warm()
    if a.all:
        df = corpus_table(a.csv)
        sums = {c: (round(float(df[c + "_ours"].sum()), 2), round(float(df[c + "_FC"].sum()), 2)) for c in CLASSES + ["total"]}
        print("corpus sums (ours, FreeCAD), min:", sums)
        print("median cut_min_per_cm2 ours / FreeCAD:", round(float((df["cut_min_per_cm2_ours"] / df["cut_min_per_cm2_FC"]).median()), 3))
        return
    for n in a.jobs:
        R = run(n, a.corpus)
        df = pd.DataFrame({k: {c: v for c, v in r.items() if c != "info"} for k, r in R.items()}).T
        print(f"== {n} {R['ours']['info']}")
        print(df.round(3).to_string(), flush=True)


if __name__ == "__main__":
    main()
