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

Units: min. ``benchmarks/time_breakdown.py [--corpus] NAME ...`` prints one row per job (ours, FreeCAD).
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from cnclab.toolpath import planners  # noqa: E402
from cnclab.toolpath.evaluate import evaluate  # noqa: E402
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
    out["lifts"] = ev.retracts
    return out


def run(name, corpus):
    jb = cc.job(name) if corpus else fx.job(name)
    h = cc.resolution_mm(jb, False) if corpus else (0.1 if "120x85" in name else 0.05)
    t0 = time.perf_counter()
    tp = planners.plan(jb, "adaptive", h, allow_uncut=True)
    t_plan = time.perf_counter() - t0
    rows = {"ours": breakdown(evaluate(tp, jb, h), jb) | {"plan_s": t_plan, "info": {k: tp.info.get(k) for k in (
        "passes", "entries", "links", "remnant_sweeps", "clean_rounds")}}}
    try:
        fp = fx.freecad_path(name, jb.tool, cc.FIXTURES if corpus else fx.FIXTURES)
        rows["FC"] = breakdown(evaluate(fp, jb, h), jb)
    except Exception as exc:   # noqa: BLE001
        print(name, "FreeCAD:", exc)
    return rows


if __name__ == "__main__":
    corpus = "--corpus" in sys.argv
    names = [a for a in sys.argv[1:] if not a.startswith("--")]
    cc.warm()
    for n in names:
        R = run(n, corpus)
        df = pd.DataFrame({k: {c: v for c, v in r.items() if c != "info"} for k, r in R.items()}).T
        print(f"== {n} {R['ours']['info']}")
        print(df.round(3).to_string(), flush=True)
