"""Issue 16 on pockets that are not in the repository: the default planner
(:func:`cnclab.toolpath.adaptive.adaptive_clearing`) on random pockets, scored by the
package's one evaluator (dixel 0.05 mm; 0.1 mm above 2500 mm^2; at most r/30, the corpus's relative
resolution, since session 11: at 0.05 mm = r/20 the maximum of an r = 1 mm tool's path moved by up to
12 deg between the planned path and the written program of pocket 76:5, 6.4 and 5.8 deg at r/60),
one row per pocket and a summary.

The pockets (seeded, reproducible): a random star (5-11 vertices, radii 12-30 mm), the largest part
of a union of three random boxes (15-35 mm) or a smooth blob (radius 20 mm with harmonics 2-5 of
up to 3 mm); with probability 0.6 one or two islands (discs of radius 2-5 mm or 6 x 4 mm boxes)
near an interior point. Tool radius r in {2, 3, 5} mm, theta in {40, 60, 75} deg, a_p 1 mm, feed
300 mm/min. Columns: engagement p95 / max over theta, share above theta + 5 deg (%), entries, plunges
and rapids into material, uncut area beyond the unreachable corners (mm^2), wall gouge (how far the
tool disc reaches past a wall or island, exact geometry along every move at depth, mm), program
time (s, as written at 10 m/min rapids) and plan time (s). A pocket the planner refuses is listed
with its reason (a refusal is a clear error, never an unsafe program).

    .venv/bin/python benchmarks/bench_random_pockets.py [--seed S] [--n N] [--via-plan] [--radii 2,3,5]
        [--param NAME=VALUE ...]

``--radii``: the tool radii drawn from (mm; the same pockets and thetas for any list of three, the
draw consumes the generator alike). ``--param``: an :class:`AdaptiveParams` field for every plan, for
an ablation (``--radii 1,1.5,1.5 --param coarse_cell_max_r=1e-9`` is the one-pixel coarse cell of
small tools before session 10).

``--via-plan``: each pocket through :func:`cnclab.toolpath.planners.plan` (strategy ``adaptive``, what
``python -m cnclab plan`` runs) instead of ``adaptive_clearing`` alone: its promise check re-plans a
level beyond the engagement bounds with a tighter guard and refuses it, naming the place, when that
fails too (counted as refused, with the reason); material left is allowed (``allow_uncut``).

Targets of issue 16 checked per pocket (``ok``): the comparison notebook's
(:func:`cnclab.works.jacso2021.freecad_comparison.engagement_targets`): p95 <= theta + 2, max <=
theta + 10, share above theta + 5 <= 0.5 % and above theta + 15 <= 0.05 %, zero plunges and rapids
into material, no wall gouge (<= 1e-3 mm, the finishing snap's tolerance). Since 2026-11-26 (session
11) every pocket is scored as written (:func:`cnclab.works.jacso2021.freecad_comparison.as_written`:
the program the writer writes, read back), as the corpus is; earlier seeds were scored on the path.
Times are wall clock on a shared CPU: noisy.
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
from shapely.geometry import Point, Polygon, box
from shapely.ops import unary_union

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from cnclab.nc.program import program_path  # noqa: E402
from cnclab.toolpath import planners  # noqa: E402
from cnclab.toolpath.adaptive import AdaptiveParams, PlanningError, adaptive_clearing, unproven_rapids  # noqa: E402
from cnclab.toolpath.evaluate import evaluate  # noqa: E402
from cnclab.toolpath.job import Job  # noqa: E402
from cnclab.toolpath.path import Tool  # noqa: E402
from cnclab.works.jacso2021.freecad_comparison import as_written, engagement_targets  # noqa: E402


def random_pocket(rng):
    """One random pocket (shapely Polygon, mm), see the module docstring."""
    k = rng.integers(0, 3)
    if k == 0:
        n = rng.integers(5, 12)
        ang = np.sort(rng.uniform(0, 2 * np.pi, n))
        rad = rng.uniform(12, 30, n)
        P = Polygon(np.c_[np.cos(ang) * rad, np.sin(ang) * rad]).buffer(0)
    elif k == 1:
        bs = [box(x, y, x + w, y + hh) for x, y, w, hh in zip(rng.integers(0, 25, 3), rng.integers(0, 25, 3),
                                                               rng.integers(15, 35, 3), rng.integers(15, 35, 3))]
        u = unary_union(bs)
        P = max(getattr(u, "geoms", [u]), key=lambda g: g.area)
    else:
        t = np.linspace(0, 2 * np.pi, 120, endpoint=False)
        rr = 20 + sum(rng.uniform(-3, 3) * np.cos(m * t + rng.uniform(0, 6)) for m in range(2, 6))
        P = Polygon(np.c_[np.cos(t) * rr, np.sin(t) * rr])
    if rng.random() < 0.6:
        for _ in range(rng.integers(1, 3)):
            inner = P.buffer(-10)
            if inner.is_empty:
                break
            c = inner.representative_point()
            c = Point(c.x + rng.uniform(-5, 5), c.y + rng.uniform(-5, 5))
            isl = c.buffer(rng.uniform(2, 5), quad_segs=4) if rng.random() < 0.5 else box(c.x - 3, c.y - 2, c.x + 3, c.y + 2)
            if P.buffer(-1).contains(isl):
                P = P.difference(isl)
    return P


def _params(items):
    """AdaptiveParams with the ``NAME=VALUE`` fields of ``items`` (SystemExit naming a bad one): a
    number field takes a number (an int field a whole one), a bool field True or False; a field
    whose default is None or a tuple is not set from here."""
    defaults = AdaptiveParams()
    kw = {}
    for it in items:
        name, eq, val = it.partition("=")
        if not eq or not hasattr(defaults, name) or name.startswith("_"):
            raise SystemExit(f"--param {it!r}: NAME=VALUE with NAME an AdaptiveParams field")
        kind = type(getattr(defaults, name))
        if kind not in (bool, int, float):
            raise SystemExit(f"--param {it!r}: {name} (default {getattr(defaults, name)!r}) is not set from the "
                             "command line")
        try:
            if kind is bool:
                if val not in ("True", "False"):
                    raise ValueError(val)
                kw[name] = val == "True"
            elif kind is int:
                kw[name] = int(val)
            else:
                kw[name] = float(val)
        except ValueError:
            raise SystemExit(f"--param {it!r}: {val!r} is not a value of {name} ({kind.__name__})") from None
    return AdaptiveParams(**kw)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--via-plan", action="store_true", help="plan through planners.plan (the CLI's path)")
    ap.add_argument("--radii", default="2,3,5", help="tool radii to draw from, mm (comma-separated; default 2,3,5)")
    ap.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                    help="an AdaptiveParams field for every plan (an ablation: the old rule against the new)")
    a = ap.parse_args(argv)
    try:
        radii = [float(v) for v in a.radii.split(",")]
    except ValueError:
        raise SystemExit(f"--radii: comma-separated radii in mm, got {a.radii!r}") from None
    if not radii or min(radii) <= 0:
        raise SystemExit(f"--radii: every radius must be > 0 mm, got {a.radii!r}")
    prm = _params(a.param)
    rng = np.random.default_rng(a.seed)
    rows = []
    for it in range(a.n):
        P = random_pocket(rng)
        r = float(rng.choice(radii))
        th = float(rng.choice([40.0, 60.0, 75.0]))
        if not P.is_valid or P.buffer(-r).is_empty:
            continue
        row = {"pocket": f"{a.seed}:{it}", "r_mm": r, "theta_deg": th, "area_mm2": round(P.area)}
        job = Job(P, Tool(2 * r), th, 1.0, feed_mm_min=300.0, spindle_rpm=6000.0, rapid_mm_min=10000.0,
                  source=f"random {a.seed}:{it}")
        t0 = time.perf_counter()
        try:
            tp = planners.plan(job, "adaptive", None, allow_uncut=True, params=prm, written=program_path) if a.via_plan \
                else adaptive_clearing(job, prm)
        except (PlanningError, ValueError) as e:
            row["refused"] = str(e)
            rows.append(row)
            print(row["pocket"], "refused:", e, flush=True)
            continue
        row["plan_s"] = time.perf_counter() - t0
        ev = evaluate(as_written(tp, job), job, min(0.05 if P.area < 2500 else 0.1, r / 30))    # as written
        row.update({"p95-theta": ev.engagement_p95_deg - th, "max-theta": ev.engagement_max_deg - th,
                    "share_above_5_pct": ev.share_above_5_pct, "entries": tp.info["entries"],
                    "plunges": ev.plunges_into_material, "rapids_into": ev.rapids_into_material,
                    "uncut_mm2": ev.uncut_beyond_unreachable_mm2, "gouge_mm": ev.wall_gouge_max_mm,
                    "program_s": tp.time_s(10000.0)["total_s"],
                    "g0_unproven": len(unproven_rapids(tp, job))})
        row["ok"] = all(engagement_targets(ev.engagement_p95_deg, ev.engagement_max_deg, ev.share_above_5_pct,
                                           ev.share_above_15_pct, ev.plunges_into_material, ev.rapids_into_material,
                                           ev.wall_gouge_max_mm, th, gouge_tol_mm=1e-3).values()) and row["g0_unproven"] == 0
        rows.append(row)
        print(" ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}" for k, v in row.items()), flush=True)
    df = pd.DataFrame(rows).set_index("pocket")
    planned = df[df.get("refused").isna()] if "refused" in df else df
    print()
    print(df.drop(columns=[c for c in ("refused",) if c in df]).round(3).to_string())
    print(f"\n== summary (seed {a.seed}{', through plan()' if a.via_plan else ''}): {len(planned)} planned, {len(df) - len(planned)} refused; "
          f"targets met on {int(planned['ok'].sum())}/{len(planned)}; max over theta {planned['max-theta'].max():.1f} deg, "
          f"max share above theta+5 {planned['share_above_5_pct'].max():.2f} %, plunges {int(planned['plunges'].sum())}, "
          f"rapids into material {int(planned['rapids_into'].sum())}, unproven G0s at depth "
          f"{int(planned['g0_unproven'].sum())}, max gouge {planned['gouge_mm'].max():.4f} mm, "
          f"max plan {planned['plan_s'].max():.2f} s")


if __name__ == "__main__":
    main()
