"""Dixel vs pixel simulator: cost per tool step vs resolution (fitted exponents) and the speed ratio at
equal engagement accuracy (Jacsó 2021 §2.2: linear vs quadratic growth). Everything measured in one run.

Cases (tool radius r = 3 mm, stepover s = 1.5 mm, tool step 0.02 mm along the path at every resolution):
a concave arc (widening a rho = 8 mm hole), a convex arc (turning a rho = 8 mm disk) and a straight cut
oblique to the rows (25 deg). The accuracy of a model at resolution h is the max |engagement - closed
form| (Thesis I / arccos(1 - s/r)) over the second half of each cut (last step excluded), max over
the three cases. Each stock
is cropped to the region the cut reaches, so the pixel grid stays small (<= ~30 Mpx at 0.0025 mm).

The feed direction is the central difference of the tool-centre samples (``feed_direction="central"``):
the backward chord lags the tangent by half the step's turning angle (0.09 deg here), a path-sampling
artefact common to both models that would otherwise be counted as model error.

Cost is CPU time (``time.process_time``, robust to the other processes on a shared machine), best of
``REPEATS`` runs: ``cut`` = one ``cut_disk`` per step; ``step`` = one step of ``simulate`` (engagement
measurement + cut), both per tool step. Exponents k of cost ~ h^-k are least-squares fits in log-log
over all resolutions and over the fine end (h <= 0.01 mm), where the per-call overhead matters least.

Run: ``python benchmarks/bench_dixel_vs_pixel.py`` (a few minutes; ``--quick`` for a coarse run).
"""
import math
import sys
import time

import numpy as np
from shapely import affinity
from shapely.geometry import Point, box

from cnclab.geometry.engagement import theta_concave, theta_convex, theta_straight
from cnclab.simulation import dixel, pixel

R, RHO, S, STEP = 3.0, 8.0, 1.5, 0.02
TARGET_DEG = 0.2
QUICK = "--quick" in sys.argv
RESOLUTIONS = (0.1, 0.05, 0.02, 0.01) if QUICK else (0.1, 0.05, 0.02, 0.01, 0.005, 0.0025)
REPEATS = 1 if QUICK else 2
SWEEP_DEG = 60.0


def cases():
    """(name, stock polygon, centres (N, 2), analytic engagement deg)."""
    out = []
    phi = np.linspace(0, math.radians(SWEEP_DEG), int(math.radians(SWEEP_DEG) * (RHO + S - R) / STEP) + 1)
    d = RHO + S - R
    hole = Point(0, 0).buffer(RHO, quad_segs=512)
    out.append(("concave", box(-1, -4, RHO + S + 1, RHO + S + 1).difference(hole),
                np.c_[d * np.cos(phi), d * np.sin(phi)], float(theta_concave(S, RHO, R))))
    d = RHO - S + R
    phi = -np.linspace(0, math.radians(SWEEP_DEG), int(math.radians(SWEEP_DEG) * d / STEP) + 1)
    out.append(("convex", hole.intersection(box(-1, -RHO - 1, RHO + 1, 4)),
                np.c_[d * np.cos(phi), d * np.sin(phi)], float(theta_convex(S, RHO, R))))
    ang = 25.0
    u = np.array([math.cos(math.radians(ang)), math.sin(math.radians(ang))])
    nrm = np.array([-u[1], u[0]])
    lam = np.arange(-3.0, 4.0 + 1e-9, STEP)
    poly = affinity.rotate(box(-7, -4, 8, 0), ang, origin=(0, 0))
    out.append(("straight25", poly, lam[:, None] * u + (R - S) * nrm, float(theta_straight(S, R))))
    return out


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
    e = df.engagement_deg.values[len(P) // 2:-1] - th      # the last step has no central difference
    return t_cut, t_step, float(np.max(np.abs(e)))


def fit_exponent(hs, cost):
    return float(-np.polyfit(np.log(hs), np.log(cost), 1)[0])


def log_interp_h(hs, err, target):
    """Resolution (mm) where the max error first falls to ``target`` (log-log interpolation), or None."""
    for i in range(len(hs) - 1):
        if err[i] > target >= err[i + 1]:
            f = (math.log(target) - math.log(err[i])) / (math.log(err[i + 1]) - math.log(err[i]))
            return math.exp(math.log(hs[i]) + f * (math.log(hs[i + 1]) - math.log(hs[i])))
    return hs[0] if err[0] <= target else None


def log_interp_cost(hs, cost, h):
    return math.exp(np.interp(math.log(h), np.log(hs[::-1]), np.log(np.asarray(cost)[::-1])))


def main():
    import pandas  # noqa: F401  (import outside the timed region)

    cs = cases()
    rows = []
    for m in (dixel, pixel):
        name = m.__name__.split(".")[-1]
        for h in RESOLUTIONS:
            res = [measure(m, h, c) for c in cs]
            rows.append((name, h, np.mean([x[0] for x in res]), np.mean([x[1] for x in res]),
                         max(x[2] for x in res), [x[2] for x in res]))
    print(f"{'model':6} {'h [mm]':>7} {'cut [ms/step]':>14} {'step [ms/step]':>15} {'max err [deg]':>14}   "
          + "  ".join(f"{c[0]:>10}" for c in cs))
    for m, h, tc, ts, e, per in rows:
        print(f"{m:6} {h:7.4f} {tc * 1e3:14.4f} {ts * 1e3:15.4f} {e:14.3f}   "
              + "  ".join(f"{x:10.3f}" for x in per))
    hs = np.array(RESOLUTIONS)
    summary = {}
    print()
    for m in ("dixel", "pixel"):
        r = [x for x in rows if x[0] == m]
        tc = np.array([x[2] for x in r])
        ts = np.array([x[3] for x in r])
        err = np.array([x[4] for x in r])
        fine = hs <= 0.01
        print(f"{m}: cost ~ h^-k, fitted k: cut {fit_exponent(hs, tc):.2f} (h <= 0.01: "
              f"{fit_exponent(hs[fine], tc[fine]):.2f}), simulate step {fit_exponent(hs, ts):.2f} "
              f"(h <= 0.01: {fit_exponent(hs[fine], ts[fine]):.2f}); error ~ h^{-fit_exponent(hs, err):.2f}")
        summary[m] = (tc, ts, err)
    print()
    print(f"Equal engagement accuracy ({TARGET_DEG} deg max error over the three cases):")
    hd = [h for h, e in zip(hs, summary["dixel"][2]) if e <= TARGET_DEG]
    hp = [h for h, e in zip(hs, summary["pixel"][2]) if e <= TARGET_DEG]
    print(f"{'':34} {'dixel':>10} {'pixel':>10} {'ratio pixel/dixel':>18}")
    if hd and hp:
        i, j = list(hs).index(max(hd)), list(hs).index(max(hp))
        print(f"{'coarsest grid h reaching it [mm]':34} {hs[i]:10.4f} {hs[j]:10.4f}")
        for k, lab in ((0, "cut [ms/step]"), (1, "simulate step [ms/step]")):
            a, b = summary["dixel"][k][i], summary["pixel"][k][j]
            print(f"{lab:34} {a * 1e3:10.4f} {b * 1e3:10.4f} {b / a:17.1f}x")
    else:
        print("  not reached by both models on the grid:", {"dixel": hd, "pixel": hp})
    hdi = log_interp_h(hs, summary["dixel"][2], TARGET_DEG)
    hpi = log_interp_h(hs, summary["pixel"][2], TARGET_DEG)
    if hdi and hpi:
        print(f"{'interpolated h at 0.2 deg [mm]':34} {hdi:10.4f} {hpi:10.4f}")
        for k, lab in ((0, "cut, interpolated [ms/step]"), (1, "step, interpolated [ms/step]")):
            a = log_interp_cost(hs, summary["dixel"][k], hdi)
            b = log_interp_cost(hs, summary["pixel"][k], hpi)
            print(f"{lab:34} {a * 1e3:10.4f} {b * 1e3:10.4f} {b / a:17.1f}x")
    print("goal: dixel >= 20x faster than pixel at equal accuracy (issue 6)")


if __name__ == "__main__":
    main()
