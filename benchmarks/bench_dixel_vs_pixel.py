"""Dixel vs pixel simulator: cost per tool step vs resolution (fitted exponents) and the speed ratio at
equal engagement accuracy (Jacsó 2021 §2.2: linear vs quadratic growth). Everything measured in one run.

Cases (:func:`cnclab.works.jacso2021.theses_1_3.accuracy_cases`; r = 3 mm, stepover 1.5 mm, tool step
0.02 mm at every resolution): a concave arc (widening a rho = 8 mm hole), a convex arc (turning a
rho = 8 mm disk) and a straight cut oblique to the rows (25 deg). The accuracy of a model at resolution h
is the max |engagement - closed form| over the second half of each cut (last step excluded), max over the
three cases. Stocks are cropped to the region the cut reaches (pixel grid <= ~30 Mpx at 0.0025 mm).
The feed direction is the central difference of the samples (``feed_direction="central"``): the
backward chord lags the tangent by half the step's turning angle (0.09 deg here), a path-sampling
artefact common to both models that would otherwise be counted as model error.

Cost is CPU time (``time.process_time``: robust to the other processes on a shared machine), best of
``REPEATS`` runs, per tool step: ``cut`` = one ``cut_disk``; ``step`` = one step of ``simulate``
(engagement measurement + cut). Exponents k of cost ~ h^-k are least-squares log-log fits over all
resolutions and over the fine end (h <= 0.01 mm); since a fixed per-step cost (numpy call overhead)
dominates at coarse h, cost = a + b h^-k is fitted as well, whose k is the growth rate §2.2 speaks of.
The equal-accuracy table interpolates error(h) and cost(h) log-linearly between measured resolutions
(targets outside the measured range are reported as not reached).

Run: ``python benchmarks/bench_dixel_vs_pixel.py`` (a few minutes; ``--quick``: h >= 0.01 mm only).
"""
import math
import sys
import time

import numpy as np

from cnclab.simulation import dixel, pixel
from cnclab.works.jacso2021.theses_1_3 import R_TOOL as R
from cnclab.works.jacso2021.theses_1_3 import accuracy_cases

QUICK = "--quick" in sys.argv
RESOLUTIONS = (0.1, 0.05, 0.02, 0.01) if QUICK else (0.1, 0.05, 0.02, 0.01, 0.005, 0.0025)
REPEATS = 1 if QUICK else 2
TARGETS_DEG = (0.2, 0.1, 0.05, 0.02)


def measure(mod, h, case):
    _, poly, P, th = case
    t_cut = t_step = math.inf
    for _ in range(REPEATS):
        st = mod.Stock.from_polygon(poly, h)
        t0 = time.process_time()
        for p in P:
            st.cut_disk(p, R)
        t_cut = min(t_cut, (time.process_time() - t0) / len(P))
        st = mod.Stock.from_polygon(poly, h)
        t0 = time.process_time()
        df = mod.simulate(st, P, R, 1, 1000, feed_direction="central")
        t_step = min(t_step, (time.process_time() - t0) / len(P))
    e = df.engagement_deg.values[len(P) // 2:-1] - th
    return t_cut, t_step, float(np.max(np.abs(e)))


def fit_exponent(hs, cost):
    hs, cost = np.asarray(hs), np.asarray(cost)
    return float(-np.polyfit(np.log(hs), np.log(cost), 1)[0]) if hs.size >= 2 else math.nan


def fit_overhead_power(hs, cost):
    """Fit cost = a + b h^-k (log-space least squares); returns (a, k, std(k)): overhead and exponent."""
    from scipy.optimize import curve_fit

    def f(lh, a, b, k):
        return np.log(a + b * np.exp(-k * lh))

    p, cov = curve_fit(f, np.log(hs), np.log(cost), p0=[float(np.min(cost)) / 2, 1e-3, 1.5],
                       bounds=([0, 0, 0], [10, 10, 4]))
    return float(p[0]), float(p[2]), float(np.sqrt(cov[2, 2]))


def h_at_error(hs, err, target):
    """Coarsest resolution (mm) at which the error reaches ``target`` (log-log interpolation), or None."""
    if err[0] <= target:
        return float(hs[0])
    for i in range(len(hs) - 1):
        if err[i] > target >= err[i + 1]:
            f = math.log(target / err[i]) / math.log(err[i + 1] / err[i])
            return math.exp(math.log(hs[i]) + f * math.log(hs[i + 1] / hs[i]))
    return None


def cost_at(hs, cost, h):
    return math.exp(np.interp(math.log(h), np.log(hs[::-1]), np.log(np.asarray(cost)[::-1])))


def main():
    import pandas  # noqa: F401  (import outside the timed region)

    cs = accuracy_cases()
    rows = {}
    for m in (dixel, pixel):
        name = m.__name__.split(".")[-1]
        for h in RESOLUTIONS:
            res = [measure(m, h, c) for c in cs]
            rows[name, h] = (np.mean([x[0] for x in res]), np.mean([x[1] for x in res]),
                             max(x[2] for x in res), [x[2] for x in res])
    print(f"{'model':6} {'h [mm]':>7} {'cut [ms/step]':>14} {'step [ms/step]':>15} {'max err [deg]':>14}   "
          + "  ".join(f"{c[0]:>10}" for c in cs))
    for (m, h), (tc, ts, e, per) in rows.items():
        print(f"{m:6} {h:7.4f} {tc * 1e3:14.4f} {ts * 1e3:15.4f} {e:14.4f}   "
              + "  ".join(f"{x:10.4f}" for x in per))
    hs = np.array(RESOLUTIONS)
    fine = hs <= 0.01
    S = {}
    print()
    for m in ("dixel", "pixel"):
        tc, ts, err = (np.array([rows[m, h][k] for h in hs]) for k in range(3))
        S[m] = (tc, ts, err)
        print(f"{m}: cost ~ h^-k: cut k = {fit_exponent(hs, tc):.2f} (h <= 0.01 mm: "
              f"{fit_exponent(hs[fine], tc[fine]):.2f}), simulate step k = {fit_exponent(hs, ts):.2f} "
              f"(h <= 0.01 mm: {fit_exponent(hs[fine], ts[fine]):.2f});  max error ~ h^{-fit_exponent(hs, err):.2f}")
        if hs.size >= 4:
            for lab, c in (("cut", tc), ("simulate step", ts)):
                a, k, sk = fit_overhead_power(hs, c)
                print(f"       {lab}: cost = a + b h^-k fit: fixed a = {a * 1e3:.3f} ms, k = {k:.2f} +- {sk:.2f}")
    print()
    print("Speed ratio at equal engagement accuracy (max error over the three cases):")
    print(f"{'target [deg]':>12} {'h dixel':>9} {'h pixel':>9} {'dixel step':>11} {'pixel step':>11} "
          f"{'ratio step':>11} {'ratio cut':>10}")
    for tgt in TARGETS_DEG:
        hd, hp = h_at_error(hs, S["dixel"][2], tgt), h_at_error(hs, S["pixel"][2], tgt)
        if hd is None or hp is None:
            print(f"{tgt:12.3f} {'-' if hd is None else f'{hd:.4f}':>9} {'-' if hp is None else f'{hp:.4f}':>9}"
                  "   not reached by both models in the measured range")
            continue
        sd, sp = cost_at(hs, S["dixel"][1], hd), cost_at(hs, S["pixel"][1], hp)
        cd, cp = cost_at(hs, S["dixel"][0], hd), cost_at(hs, S["pixel"][0], hp)
        print(f"{tgt:12.3f} {hd:9.4f} {hp:9.4f} {sd * 1e3:9.4f}ms {sp * 1e3:9.4f}ms {sp / sd:10.1f}x {cp / cd:9.1f}x")
    print("(h in mm: coarsest resolution reaching the target; step/cut costs interpolated at those h)")
    print("goal (issue 6): dixel >= 20x faster than pixel at the resolution where both reach 0.2 deg")


if __name__ == "__main__":
    main()
