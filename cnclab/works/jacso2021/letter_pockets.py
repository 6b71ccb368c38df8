"""Letter-shaped pockets (T, H, U, E, O, plus) drawn from a seed: channels with sharp corners,
junctions and ends, shapes outside the pocket corpus (``data/pockets/corpus`` has no channel that
turns a sharp corner or meets another), and their score by the package's one evaluator -- the
issue-29 engagement, safety and uncut checks on pockets the adaptive planner was not developed on
(``benchmarks/bench_letters.py``; seeds 7 and 11 were the development set of the narrow-region
period check, the others are validation). Units: mm, deg.

>>> round(letter("T", 10.0, 30.0).area, 1)       # 30 x 10 bar + 10 x 20 stem
500.0
>>> [spec[0] for spec in draw(21, 3, 1.1, 1.8)] == [spec[0] for spec in draw(21, 3, 1.1, 1.8)]
True
"""
from __future__ import annotations

import time

import numpy as np
import shapely
from shapely.geometry import box

from ...nc.program import program_path
from ...toolpath import planners
from ...toolpath.adaptive import unproven_rapids
from ...toolpath.evaluate import evaluate
from ...toolpath.job import Job
from ...toolpath.path import Tool
from .freecad_comparison import as_written, meets_bounds

__all__ = ["LETTERS", "letter", "draw", "score"]

LETTERS = ("T", "H", "U", "E", "O", "plus")


def letter(kind: str, w: float, L: float):
    """The letter ``kind`` of bars ``w`` mm wide in an ``L`` x ``L`` mm square (mm)."""
    if kind == "T":
        return shapely.union(box(0, 0, L, w), box(L / 2 - w / 2, 0, L / 2 + w / 2, L))
    if kind == "H":
        return shapely.union_all([box(0, 0, w, L), box(L - w, 0, L, L), box(0, L / 2 - w / 2, L, L / 2 + w / 2)])
    if kind == "U":
        return shapely.union_all([box(0, 0, w, L), box(L - w, 0, L, L), box(0, 0, L, w)])
    if kind == "E":
        return shapely.union_all([box(0, 0, w, L), box(0, 0, L, w), box(0, L / 2 - w / 2, L, L / 2 + w / 2),
                                  box(0, L - w, L, L)])
    if kind == "O":
        return box(0, 0, L, L).difference(box(w, w, L - w, L - w))
    if kind == "plus":
        return shapely.union(box(L / 2 - w / 2, 0, L / 2 + w / 2, L), box(0, L / 2 - w / 2, L, L / 2 + w / 2))
    raise ValueError(f"unknown letter {kind!r}: one of {LETTERS}")


def draw(seed: int, n: int, w_lo: float, w_hi: float) -> list:
    """``n`` job specs (kind, D mm, w mm, L mm, theta deg) drawn from ``seed``."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        kind = str(rng.choice(LETTERS))
        D = float(rng.choice([3, 4, 5, 6, 8, 10, 12]))
        w = float(np.round(D * rng.uniform(w_lo, w_hi), 1))
        L = float(np.round(max(3 * w, D * rng.uniform(5, 10)), 1))
        th = float(np.round(rng.uniform(20, 120), 1))
        out.append((kind, D, w, L, th))
    return out


def score(kind: str, D: float, w: float, L: float, theta: float) -> dict:
    """One row: the adaptive plan of the letter job, scored as written (:func:`.freecad_comparison.as_written`)
    by the evaluator (a refusal: the note)."""
    jb = Job(letter(kind, w, L), Tool(D), theta, 1.0, v_c=100, f_z=0.05, source=f"{kind} w{w} L{L}")
    h = float(np.clip(D / 2 / 30, 0.05, 0.2))
    row = {"letter": kind, "D_mm": D, "w_mm": w, "L_mm": L, "theta_deg": theta}
    t0 = time.perf_counter()
    try:
        tp = planners.plan(jb, "adaptive", h, allow_uncut=True, allow_engagement_breach=True, written=program_path)
    except Exception as exc:       # noqa: BLE001 -- a refusal is a result of this benchmark
        return row | {"note": f"{type(exc).__name__}: {str(exc)[:160]}"}
    row["plan_s"] = round(time.perf_counter() - t0, 2)
    ev = evaluate(as_written(tp, jb), jb, h)
    row |= {"max_minus_theta": ev.engagement_max_deg - theta, "p95_minus_theta": ev.engagement_p95_deg - theta,
            "share_above_5_pct": ev.share_above_5_pct, "plunges": ev.plunges_into_material,
            "rapids_into_material": ev.rapids_into_material, "gouge_mm": ev.wall_gouge_max_mm,
            "uncut_beyond_mm2": ev.uncut_beyond_unreachable_mm2, "narrow_regions": len(tp.info.get("narrow_regions", [])),
            "note": (tp.info.get("engagement_check") or {}).get("where", ""),
            # the G0s at depth the written path does not prove clear (adaptive.audit; a sound plan: none)
            "g0_unproven": len(unproven_rapids(tp, jb))}
    row["ok_safe"] = bool(row["plunges"] == 0 and row["rapids_into_material"] == 0 and row["gouge_mm"] <= 1e-3
                          and row["g0_unproven"] == 0)
    row["ok_engagement"] = meets_bounds(ev.engagement_p95_deg, ev.engagement_max_deg, ev.share_above_5_pct, theta)
    return row
