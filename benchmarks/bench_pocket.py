"""Benchmark: pocket strategies on the designed star and the user pockets (rectangle, L-shape) of
Jacsó (2021) §4 — planning and dixel simulation time per shape and strategy, ratios measured in
one run, printed as one table.

The hybrid path runs with the default ``max_wall_share="auto"`` (every candidate planned and
simulated): ``chosen_plan_s`` is the planning time of the chosen candidate alone, so
``auto_cost = plan_s / chosen_plan_s`` is what the automatic choice costs.

Run: ``.venv/bin/python benchmarks/bench_pocket.py`` (resolutions 0.2 and 0.1 mm) or
``--quick`` (0.1 mm only: the fast-mode resolution of the notebook and the tests).

The cells (shape x resolution x strategy) go through :func:`cnclab.sweep.sweep`: serial by default
(the times compare like with like), ``CNCLAB_SWEEP_JOBS=N`` on N processes or
``CNCLAB_DASK_SCHEDULER=tcp://host:port`` on a Dask cluster (then each cell's times are the
worker's, measured inside the cell).
"""
import argparse
import time

import pandas as pd

from cnclab.paths import data_path
from cnclab.sweep import sweep
from cnclab.toolpath import pocket as pk
from cnclab.toolpath.evaluate import evaluate
from cnclab.toolpath.job import load_job
from cnclab.works.jacso2021.thesis4_star_pocket import star_job

SHAPES = {"star": star_job,
          "rectangle": lambda: load_job(data_path("jacso2021", "rectangle_pocket.json")),
          "L-shape": lambda: load_job(data_path("jacso2021", "l_pocket.json"))}


STRATEGIES = {"hybrid": lambda job, res: pk.hybrid_path(job, res),
              "contour-parallel": lambda job, res: pk.contour_parallel_path(job),
              "zig-zag": lambda job, res: pk.zigzag_path(job)}


def bench_cell(shape: str, res: float, name: str) -> dict:
    """Plan and simulate one (shape, resolution mm, strategy) cell; its times measured inside."""
    job = SHAPES[shape]()
    t0 = time.perf_counter()
    p = STRATEGIES[name](job, res)
    t1 = time.perf_counter()
    s = evaluate(p, job, res, feed_control=name == "hybrid", level_only=True).trace["level_summary"]
    t2 = time.perf_counter()
    row = {"shape": shape, "resolution_mm": res, "strategy": name, "plan_s": t1 - t0,
           "simulate_s": t2 - t1, "total_s": t2 - t0, "points": len(p),
           "machining_time_s": s["time_s"], "engagement_max_deg": s["engagement_max_deg"],
           "uncut_beyond_unreachable_mm2": s["uncut_area_mm2"] - s["unreachable_area_mm2"]}
    if name == "hybrid":
        c = p.info["wall_share_candidates"]
        chosen = next(m for m in c if m["max_wall_share"] == p.info["max_wall_share"])
        row.update(max_wall_share=p.info["max_wall_share"], chosen_plan_s=chosen["plan_s"],
                   auto_cost=(t1 - t0) / chosen["plan_s"])
    return row


def main(resolutions=(0.2, 0.1)):
    rows = sweep(bench_cell, [(shape, res, name) for shape in SHAPES for res in resolutions for name in STRATEGIES])
    df = pd.DataFrame(rows)
    ref = df[df.strategy == "zig-zag"].set_index(["shape", "resolution_mm"]).total_s
    df["total_vs_zigzag"] = df.total_s / pd.Series(list(zip(df["shape"], df.resolution_mm))).map(ref).to_numpy()
    if len(resolutions) > 1:
        coarse = df[df.resolution_mm == resolutions[0]].set_index(["shape", "strategy"]).total_s
        df["total_vs_coarse"] = df.total_s / pd.Series(list(zip(df["shape"], df.strategy))).map(coarse).to_numpy()
    with pd.option_context("display.width", 200):
        print(df.round(3).to_string(index=False))
    return df


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="0.1 mm only (the fast-mode resolution)")
    main((0.1,) if ap.parse_args().quick else (0.2, 0.1))
