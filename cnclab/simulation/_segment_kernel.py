"""Compiled (numba) kernel of the pixel stock's sweep along a straight move
(:meth:`.pixel.Stock.segment_pixels`, Kim & Yang's ``Linear_Motion`` count); the numpy reference is
that method's ``backend="numpy"`` branch (``tests/test_simulation_kernels.py`` checks both give the
same count and stock)."""
from __future__ import annotations

import math

from numba import njit


@njit(cache=True)
def segment_pixels(grid, x0, y0, h, ax, ay, bx, by, r, L2, cut):
    """Port of :meth:`.pixel.Stock.segment_pixels`: the material pixels whose centres lie within ``r``
    of the segment (ax, ay)--(bx, by) (mm; ``L2`` its squared length, computed by the caller);
    ``cut`` removes them. Returns their count. Same operations in the same order as the numpy
    reference (no fused multiply-add), so the same pixels."""
    ny, nx = grid.shape
    i0 = max(int(math.floor((min(ax, bx) - r - x0) / h)), 0)
    i1 = min(int(math.ceil((max(ax, bx) + r - x0) / h)), nx)
    j0 = max(int(math.floor((min(ay, by) - r - y0) / h)), 0)
    j1 = min(int(math.ceil((max(ay, by) + r - y0) / h)), ny)
    d0 = bx - ax
    d1 = by - ay
    rr = r * r
    n = 0
    for j in range(j0, j1):
        Y = (y0 + (j + 0.5) * h) - ay
        for i in range(i0, i1):
            if not grid[j, i]:
                continue
            X = (x0 + (i + 0.5) * h) - ax
            t = 0.0
            if L2 != 0:
                t = min(max((X * d0 + Y * d1) / L2, 0.0), 1.0)
            u = X - t * d0
            v = Y - t * d1
            if u * u + v * v <= rr:
                n += 1
                if cut:
                    grid[j, i] = False
    return n
