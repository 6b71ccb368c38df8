"""The adaptive planner on letter-shaped pockets it was never developed on: channels with corners,
junctions and ends (T, H, U, E, O, plus), drawn at random from a seed -- the engagement, safety and
uncut checks of issue 29 on shapes outside the corpus (``data/pockets/corpus`` has no channel that
turns a sharp corner or meets another).

Each job: a letter of bars ``w`` mm wide and ``L`` mm long, a tool of D in {3, 4, 5, 6, 8, 10, 12}
mm, ``w`` drawn in [w_lo, w_hi] x D (default 1.2-3.5; the narrow-channel run: 1.1-1.8), theta in
[20, 120] deg, one level of 1 mm; the planning and evaluation dixel r/30 clipped to [0.05, 0.2] mm
(as the corpus). Scored by the package's one evaluator (:func:`cnclab.toolpath.evaluate.evaluate`):
plunges and rapids into material, wall gouge, engagement p95 / max / share above theta + 5 deg
(contact: material thicker than the evaluator's air tolerance, half a pixel's area per sample),
uncut area beyond what no tool disc reaches.

Seeds: 7 and 11 were the development set of the narrow-region period check and the even-legged
ramp (session of 2026-11-26); other seeds are validation. Deterministic in the seed.

    .venv/bin/python benchmarks/bench_letters.py [--seed 21] [--n 14] [--w-lo 1.1 --w-hi 1.8] [--out DIR]

Writes ``DIR/letters_<seed>_<w_lo>-<w_hi>.csv`` (one row per job) and prints it with the count of
jobs within the targets.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from cnclab.fileio import atomic_write  # noqa: E402
from cnclab.sweep import sweep  # noqa: E402
from cnclab.works.jacso2021.letter_pockets import draw, score  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=21)
    ap.add_argument("--n", type=int, default=14)
    ap.add_argument("--w-lo", type=float, default=1.2)
    ap.add_argument("--w-hi", type=float, default=3.5)
    ap.add_argument("--out", default="benchmarks/results")
    a = ap.parse_args(argv)
    rows = sweep(score, draw(a.seed, a.n, a.w_lo, a.w_hi))
    df = pd.DataFrame(rows)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write(out / f"letters_{a.seed}_{a.w_lo:g}-{a.w_hi:g}.csv", df.to_csv(index=False))
    with pd.option_context("display.width", 250, "display.max_columns", 30, "display.precision", 2,
                           "display.max_colwidth", 70):
        print(df.to_string())
    planned = df["ok_safe"].notna().sum() if "ok_safe" in df else 0
    print(f"\nseed {a.seed}, w {a.w_lo:g}-{a.w_hi:g} D: {planned} of {len(df)} planned, "
          f"safe {int(df.get('ok_safe', pd.Series(dtype=bool)).fillna(False).sum())}, within the engagement "
          f"targets {int(df.get('ok_engagement', pd.Series(dtype=bool)).fillna(False).sum())}")
    return df


if __name__ == "__main__":
    main()
