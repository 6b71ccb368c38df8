"""Dixel vs pixel simulator: cost per tool step vs resolution (fitted exponents) and the speed ratio at
equal engagement accuracy (Jacsó 2021 §2.2: linear vs quadratic growth). Ratios measured in one run.

Run: ``python benchmarks/bench_dixel_vs_pixel.py`` (about a minute).
"""
import math
import time

import numpy as np
from shapely.geometry import Point, box

from cnclab.geometry.engagement import theta_concave
from cnclab.simulation import dixel, pixel

R, RHO, S = 3.0, 8.0, 1.5
RESOLUTIONS = (0.1, 0.05, 0.02, 0.01)


def run(mod, h, sweep_deg=60.0):
    poly = box(-20, -20, 20, 20).difference(Point(0, 0).buffer(RHO, quad_segs=512))
    d = RHO + S - R
    phi = np.linspace(0, math.radians(sweep_deg), int(math.radians(sweep_deg) * d / 0.02))  # same steps
    st = mod.Stock.from_polygon(poly, h)
    P = np.c_[d * np.cos(phi), d * np.sin(phi)]
    st.cut_disk(P[0], R)
    t0 = time.perf_counter()
    for p in P[1:]:
        st.cut_disk(p, R)
    t_cut = (time.perf_counter() - t0) / (len(P) - 1)
    st = mod.Stock.from_polygon(poly, h)
    t0 = time.perf_counter()
    df = mod.simulate(st, P, R, 1, 1000)
    t_sim = (time.perf_counter() - t0) / len(P)
    e = df.engagement_deg.values[len(P) // 2:] - float(theta_concave(S, RHO, R))
    return t_cut, t_sim, float(np.max(np.abs(e)))


def main():
    res = {(m.__name__.split(".")[-1], h): run(m, h) for m in (dixel, pixel) for h in RESOLUTIONS}
    print(f"{'model':6} {'h [mm]':>7} {'cut [ms/step]':>14} {'simulate [ms/step]':>19} {'max eng. err [deg]':>19}")
    for (m, h), (tc, ts, e) in res.items():
        print(f"{m:6} {h:7.3f} {tc * 1e3:14.4f} {ts * 1e3:19.3f} {e:19.3f}")
    hs = np.array(RESOLUTIONS)
    for m in ("dixel", "pixel"):
        kc = -np.polyfit(np.log(hs), np.log([res[m, h][0] for h in hs]), 1)[0]
        ks = -np.polyfit(np.log(hs), np.log([res[m, h][1] for h in hs]), 1)[0]
        print(f"{m}: fitted cost exponent (cost ~ h^-k): cut k = {kc:.2f}, full simulate step k = {ks:.2f}")
    ok = {m: [h for h in RESOLUTIONS if res[m, h][2] <= 0.2] for m in ("dixel", "pixel")}
    if ok["dixel"] and ok["pixel"]:
        hd, hp = max(ok["dixel"]), max(ok["pixel"])
        print(f"coarsest resolution reaching 0.2 deg: dixel {hd} mm, pixel {hp} mm")
        print(f"speed ratio pixel/dixel at equal accuracy: cut {res['pixel', hp][0] / res['dixel', hd][0]:.1f}x, "
              f"simulate step {res['pixel', hp][1] / res['dixel', hd][1]:.1f}x (goal >= 20x)")
    else:
        print("0.2 deg not reached by both models in the resolution range:", ok)


if __name__ == "__main__":
    main()
