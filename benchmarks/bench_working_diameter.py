"""Benchmark: closed-form working diameter (cnclab.geometry.ball_end) vs a per-point numerical
implementation of the thesis's pseudo-code (§5.2 steps 1–11, Brent's method for the tangent points).

Goals (issue 3): >= 5e6 closed-form evaluations/s in one process; >= 100x over the numerical version.
All rates are measured in this one run (best of ``REPEAT``), with the same random inputs (seed 0).
Run: ``.venv/bin/python benchmarks/bench_working_diameter.py``
"""
from __future__ import annotations

import time

import numpy as np

from cnclab.geometry.ball_end import cut_point_radii, tangent_point_diameters, thesis_steps_numerical

N_VEC = 1_000_000      # points per closed-form call
N_NUM = 300            # points for the numerical reference
REPEAT = 3


def _inputs(n, rng):
    D = rng.choice([6.0, 8.0, 10.0, 12.0], n)
    return (D, rng.uniform(0.05, 1.0, n), rng.uniform(0, 360, n), rng.uniform(-45, 45, n),
            rng.uniform(0, 360, n), rng.uniform(0, 1.0, n))


def _best(fn):
    """Best wall-clock and best CPU time (this process only) over REPEAT runs, seconds."""
    wall = cpu = float("inf")
    for _ in range(REPEAT):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall, cpu = min(wall, time.perf_counter() - t0), min(cpu, time.process_time() - c0)
    return wall, cpu


def main():
    rng = np.random.default_rng(0)
    D, ap, a1, a2, af, ae = _inputs(N_VEC, rng)
    t_tan = _best(lambda: tangent_point_diameters(D, ap, a1, a2, af))
    t_cut = _best(lambda: cut_point_radii(D, ap, ae, a1, a2, af))
    k = slice(0, N_NUM)
    t_num = _best(lambda: [thesis_steps_numerical(D[i], ap[i], ae[i], a1[i], a2[i], af[i]) for i in range(N_NUM)])
    # agreement on the shared points
    c = cut_point_radii(D[k], ap[k], ae[k], a1[k], a2[k], af[k])
    ref = [thesis_steps_numerical(D[i], ap[i], ae[i], a1[i], a2[i], af[i]) for i in range(N_NUM)]
    err = max(abs(float(c.p1[i]) - ref[i]["1"]) + abs(float(c.p2[i]) - ref[i]["2"]) for i in range(N_NUM))
    (w_tan, c_tan), (w_cut, c_cut), (w_num, c_num) = t_tan, t_cut, t_num
    rate_tan, rate_cut, rate_num = N_VEC / w_tan, N_VEC / w_cut, N_NUM / w_num
    rows = [
        ("closed form, tangent points 1,2 (tangent_point_diameters)", rate_tan, N_VEC / c_tan, "goal >= 5e6/s"),
        ("closed form, points 1,1',1'',2,2',2'' (cut_point_radii)", rate_cut, N_VEC / c_cut, ""),
        ("numerical thesis steps 1-11, per point (thesis_steps_numerical)", rate_num, N_NUM / c_num, "reference"),
    ]
    print("evals/s by wall clock and per CPU-second of this process (the machine's cores are shared)")
    print(f"{'method':<66} {'evals/s':>11} {'evals/cpu-s':>12} {'speed-up':>9}  note")
    print("-" * 112)
    for name, rate, cpu_rate, note in rows:
        print(f"{name:<66} {rate:>11.3e} {cpu_rate:>12.3e} {rate / rate_num:>8.0f}x  {note}")
    print(f"\nmax |closed form - numerical| over {N_NUM} points (points 1+2): {err:.2e} mm")
    print(f"goals: closed form >= 5e6/s: wall {'met' if rate_tan >= 5e6 else 'NOT met'}, "
          f"per CPU-second {'met' if N_VEC / c_tan >= 5e6 else 'NOT met'}; "
          f"speed-up >= 100x: {'met' if rate_tan / rate_num >= 100 else 'NOT met'}")


if __name__ == "__main__":
    main()
