"""Benchmark: Kim & Yang Linear_Motion (one swept stadium) vs per-disk pixel cuts; G-code write/parse.

Ratios are measured in one run and printed as a table (no absolute-time assertions anywhere).
Run: ``.venv/bin/python benchmarks/bench_toolpath_io_and_pixels.py``
"""
from __future__ import annotations

import time

import numpy as np
from shapely.geometry import box

from cnclab.simulation import pixel
from cnclab.toolpath import constant_mrr as cm
from cnclab.nc import gcode
from cnclab.nc.program import write_moves


def _time(fn, repeat=3):
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main():
    rows = []
    base = pixel.Stock.from_polygon(box(0, 0, 120, 85), 0.3)
    p0, p1, r = np.array([10.0, 40.0]), np.array([110.0, 40.0]), 5.0

    def stadium():
        st = base.copy()
        cm.cut_linear(st, p0, p1, r)

    def disks(step=0.3):
        st = base.copy()
        for t in np.linspace(0, 1, int(100 / step) + 1):
            st.cut_disk_pixels(tuple(p0 + t * (p1 - p0)), r)

    t_st, t_dk = _time(stadium), _time(disks)
    rows.append(("100 mm cut, 0.3 mm pixels: swept stadium vs disks every 0.3 mm", t_st, t_dk))

    pts = np.column_stack([np.linspace(0, 100, 20001), np.sin(np.linspace(0, 60, 20001))])
    moves = gcode.linear_moves(pts, feed=500, spindle=2000, z=-0.5)
    text = write_moves(moves)
    t_w = _time(lambda: write_moves(moves))
    t_p = _time(lambda: gcode.parse_gcode(text))
    rows.append(("20k G1 moves: write vs parse", t_w, t_p))

    print(f"{'case':70s} {'A [s]':>9s} {'B [s]':>9s} {'B/A':>7s}")
    for name, a, b in rows:
        print(f"{name:70s} {a:9.4f} {b:9.4f} {b / a:7.1f}")


if __name__ == "__main__":
    main()
