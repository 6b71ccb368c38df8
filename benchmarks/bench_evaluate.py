"""Benchmark: the one evaluator (cnclab.toolpath.evaluate.evaluate, every move, level by level)
against the feed-control simulation of the cutting level (evaluate(..., feed_control=False, level_only=True)) on the same
ToolPaths — seconds per call and their ratio, measured in one run, printed as one table.

Run: ``.venv/bin/python benchmarks/bench_evaluate.py [--res 0.1]``.
"""
import argparse
import time

import pandas as pd

from cnclab.paths import data_path
from cnclab.toolpath import pocket as pk
from cnclab.toolpath.evaluate import evaluate
from cnclab.toolpath.job import load_job
from cnclab.toolpath.planners import plan


def main(res=0.1):
    job = load_job(data_path("jacso2021", "rectangle_pocket.json"))
    evaluate(plan(job, "zig-zag", res), job, res)                   # compile the kernels once
    rows = []
    for name in ("hybrid", "contour-parallel", "zig-zag", "constant-engagement"):
        p = plan(job, name, res)
        t0 = time.perf_counter()
        ev = evaluate(p, job, res)
        t1 = time.perf_counter()
        evaluate(p, job, res, feed_control=False, level_only=True)
        t2 = time.perf_counter()
        rows.append({"strategy": name, "moves": len(p), "evaluate_s": t1 - t0, "cutting_level_s": t2 - t1,
                     "ratio": (t1 - t0) / (t2 - t1), "time_total_s": ev.time_total_s,
                     "plunges_into_material": ev.plunges_into_material})
    df = pd.DataFrame(rows)
    with pd.option_context("display.width", 200):
        print(df.round(3).to_string(index=False))
    return df


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=float, default=0.1, help="dixel row height and sampling step (mm)")
    main(ap.parse_args().res)
