"""Evaluation speed of the working-diameter models (Mgherony 2024 ch. 6): closed form vs r1 vs networks.

Honest context for chapter 6: the closed-form geometric model (cnclab.geometry.ball_end) is itself
cheap, so a learned surrogate only pays off if it is faster *and* accurate. All models are evaluated
on the same random batch of N points (D, a_p, A_N2, A_f); throughput in points per second, best of
R repeats, measured in this one run (ratios are relative to the closed form).

Run: ``.venv/bin/python benchmarks/bench_surrogates.py``. Network weights come from a short training
(speed does not depend on accuracy); the accurate networks are trained in the ch6 notebook.
"""
from __future__ import annotations

import time

import numpy as np
import pandas as pd

from cnclab.analysis.mlp import train_mlp
from cnclab.works.mgherony2024 import ch6

N, REPEATS = 200_000, 5


def _best_rate(fn) -> float:
    best = np.inf
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return N / best


def main() -> pd.DataFrame:
    rng = np.random.default_rng(0)
    pts = pd.DataFrame({"D": rng.uniform(6, 12, N), "a_p": rng.uniform(0.15, 0.45, N),
                        "A_N2": rng.uniform(-40, 40, N), "A_f": rng.uniform(-89, 89, N)})
    df = ch6.dataset()
    X, Y = df[list(ch6.INPUTS)].to_numpy(), df[list(ch6.OUTPUTS)].to_numpy()
    a2 = train_mlp(X, Y, hidden=(10, 5), seed=0, max_epochs=5)
    Xs = ch6.surrogate_features(df)
    sur = train_mlp(Xs, Y / df[["D"]].to_numpy(), hidden=(20, 20), activation="tansig", seed=0, max_epochs=3)
    r1 = ch6.r1_fit()
    cols = [pts[c].to_numpy() for c in ch6.INPUTS]
    Xp = pts[list(ch6.INPUTS)].to_numpy()
    cases = {
        "closed form (ball_end.tangent_point_diameters, both points)": lambda: ch6.working_diameters(*cols),
        "r1 regression (eq 6-4, one output)": lambda: r1.predict(pts),
        "a2 network 4-10-5-2 (torch, both outputs)": lambda: a2.predict(Xp),
        "surrogate 5-20-20-2 (torch, both outputs)": lambda: ch6.surrogate_predict(sur, pts),
    }
    rates = {name: _best_rate(fn) for name, fn in cases.items()}
    base = rates[next(iter(rates))]
    table = pd.DataFrame({"points_per_s": rates, "relative_to_closed_form": {k: v / base for k, v in rates.items()}})
    return table


if __name__ == "__main__":
    t = main()
    with pd.option_context("display.width", 160, "display.float_format", "{:,.3g}".format):
        print(f"N = {N:,} points, best of {REPEATS}")
        print(t.to_string())
