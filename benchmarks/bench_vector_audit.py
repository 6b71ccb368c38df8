"""The corpus engagement audited on an exact vector stock (issue 29): for each corpus job, our written
program and FreeCAD's committed one, both evaluated at the corpus dixel (r / 30), then measured
again on polygons (:func:`cnclab.toolpath.vector_check.vector_audit`: the evaluator's 5 highest
peaks and 300 random cutting samples, seed 0; contact: chips of 2 um and more).

What it answers: does the maximum the dixel reports stand on an exact stock (``vector_peak_max``),
and does the dixel read *lower* than the exact stock anywhere (``random_diff_max``: vector - dixel
over the random samples)? One row per job and program; a summary per program.

    .venv/bin/python benchmarks/bench_vector_audit.py [JOB ...] [--out benchmarks/results/vector_audit_corpus.csv]

Through :func:`cnclab.sweep.sweep` (joblib processes, or a Dask cluster with ``$CNCLAB_DASK_SCHEDULER``).
"""
from __future__ import annotations

import argparse
import functools
import sys
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from cnclab.fileio import atomic_write  # noqa: E402
from cnclab.nc.program import program_path  # noqa: E402
from cnclab.sweep import sweep  # noqa: E402
from cnclab.toolpath import planners  # noqa: E402
from cnclab.toolpath.evaluate import evaluate  # noqa: E402
from cnclab.toolpath.vector_check import vector_audit  # noqa: E402
from cnclab.works.jacso2021 import corpus_comparison as cc  # noqa: E402
from cnclab.works.jacso2021 import freecad_comparison as fx  # noqa: E402

COLS = ["dixel_max", "vector_peak_max", "random_vector_max", "random_diff_max", "random_diff_min", "random_absdiff_p95", "n_random"]


def audit_job(name: str, ours_only: bool = False) -> list:
    """Rows (ours, FreeCAD's where it wrote a program, unless ``ours_only``) of job ``name``: the
    audit's values over theta."""
    jb = cc.job(name)
    h = cc.resolution_mm(jb, False)
    tp = planners.plan(jb, "adaptive", h, allow_uncut=True, allow_engagement_breach=True, written=program_path)
    progs = [("ours", fx.as_written(tp, jb))]
    try:
        if not ours_only:
            progs.append(("FreeCAD", fx.freecad_path(name, jb.tool, cc.FIXTURES)))
    except (ValueError, FileNotFoundError):
        pass
    rows = []
    for who, path in progs:
        a = vector_audit(evaluate(path, jb, h), jb)
        row = {"job": name, "family": cc.family(name), "program": who, "theta_deg": jb.theta_deg, "resolution_mm": h}
        for c in COLS:
            row[c] = a[c] - (jb.theta_deg if c.endswith("_max") and "diff" not in c else 0.0)
        rows.append(row)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("jobs", nargs="*")
    ap.add_argument("--out", default="benchmarks/results/vector_audit_corpus.csv")
    ap.add_argument("--ours-only", action="store_true", help="audit our programs only (FreeCAD's fixtures do not change)")
    a = ap.parse_args(argv)
    names = a.jobs or cc.job_names()
    df = pd.DataFrame([r for rows in sweep(functools.partial(audit_job, ours_only=a.ours_only), names) for r in rows])
    df = df.rename(columns={c: c + "_minus_theta" for c in ("dixel_max", "vector_peak_max", "random_vector_max")})
    if a.ours_only and Path(a.out).exists():
        # FreeCAD's rows (its committed programs) kept from the earlier run of the file, in job order
        old = pd.read_csv(a.out)
        df = pd.concat([df, old[old["program"] != "ours"]]).sort_values(["job", "program"], key=lambda c: c.map(
            {n: i for i, n in enumerate(cc.job_names())}) if c.name == "job" else c.map({"ours": 0}).fillna(1),
            kind="stable").reset_index(drop=True)
    atomic_write(Path(a.out), df.to_csv(index=False))
    with pd.option_context("display.width", 200, "display.max_rows", 500, "display.precision", 2):
        print(df.to_string())
        print(df.groupby("program")[["dixel_max_minus_theta", "vector_peak_max_minus_theta",
                                     "random_vector_max_minus_theta", "random_diff_max",
                                     "random_diff_min", "random_absdiff_p95"]].agg(["max", "median"]).T)
    return df


if __name__ == "__main__":
    main()
