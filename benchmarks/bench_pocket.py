"""Benchmark: pocket strategies on the designed star (Jacsó 2021 §4) — planning and dixel
simulation time per strategy at two resolutions, ratios measured in one run.

Run: ``.venv/bin/python benchmarks/bench_pocket.py``
"""
import time

import pandas as pd

from cnclab.toolpath import pocket as pk
from cnclab.works.jacso2021.thesis4_star_pocket import star_job


def main(resolutions=(0.2, 0.1)):
    job = star_job()
    plans = {"hybrid": lambda res: pk.hybrid_path(job, res),
             "contour-parallel": lambda res: pk.contour_parallel_path(job),
             "zig-zag": lambda res: pk.zigzag_path(job)}
    rows = []
    for res in resolutions:
        for name, plan in plans.items():
            t0 = time.perf_counter()
            p = plan(res)
            t1 = time.perf_counter()
            _, s = pk.evaluate_strategy(p, job, res)
            t2 = time.perf_counter()
            rows.append({"resolution_mm": res, "strategy": name, "plan_s": t1 - t0, "simulate_s": t2 - t1,
                         "total_s": t2 - t0, "points": len(p.points),
                         "machining_time_s": s["time_s"], "max_eng_deg": s["max_engagement_deg"]})
    df = pd.DataFrame(rows)
    ref = df[(df.strategy == "zig-zag")].set_index("resolution_mm").total_s
    df["total_vs_zigzag"] = df.total_s / df.resolution_mm.map(ref)
    coarse = df[df.resolution_mm == resolutions[0]].set_index("strategy").total_s
    df["total_vs_coarse"] = df.total_s / df.strategy.map(coarse)
    print(df.round(3).to_string(index=False))
    return df


if __name__ == "__main__":
    main()
