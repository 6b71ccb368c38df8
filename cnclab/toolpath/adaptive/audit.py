"""An independent re-proof of the planner's G0 moves at depth, from the written path alone.

The level planner marks a rapid below the stock top ``cleared`` only where its rapid stock proves it
(see :class:`.grid.Grid`: discs of ``r - h/sqrt(2)`` cut where the tool went, no material pixel
within ``r + h/sqrt(2)`` of the chord). That proof is made on the planner's state at the time; a
bookkeeping slip -- a proof made for one chord and another written, a stock cut where the tool never
went -- would write a G0 that meets material, which no later check of the planner would see.
:func:`unproven_rapids` therefore rebuilds the rapid stock from the moves of the path itself, level
by level, in the order they run (discs of ``r - h/sqrt(2)`` every ``h/2`` along each feed move at the
level, at the end of each move arriving on it), and proves every G0 at depth again before it runs.
Every disc it cuts the real tool swept, so its stock never holds less material than the true one,
and a chord it proves is clear in the exact geometry; the planner's own proofs rest on a stock with
no more cuts than this one, so on a sound plan it finds nothing. Units: mm.
"""
from __future__ import annotations

import math

import numpy as np

from ..path import KINDS, ToolPath
from .stock import capsule_free, cut_disc, raster

__all__ = ["unproven_rapids"]

_RAPID = KINDS.index("rapid")


def unproven_rapids(tp: ToolPath, pocket, tool_radius: float, resolution_mm: float, levels, start_hole=None) -> list:
    """Indices of the G0 moves at depth of ``tp`` that the path before them does not prove clear.

    ``pocket``: the shapely (Multi)Polygon; ``tool_radius`` (mm); ``resolution_mm``: the pixel (the
    planner's, ``tp.info["resolution_mm"]``); ``levels``: the cutting z of each level (mm,
    ``tp.info["levels"]``); ``start_hole``: None or (x, y, diameter) mm. A G0 at depth is a rapid
    whose start and end lie on one level's z.

    Two passes 1 mm apart (tool radius 1 mm), a feed link to the middle, then a G0 between them --
    or one 0.3 mm past the second pass:

    >>> from shapely.geometry import box
    >>> from cnclab.toolpath.path import ToolPath
    >>> cut = [[2, 2, 0], [2, 2, -1], [8, 2, -1], [8, 3, -1], [2, 3, -1]]
    >>> kind = ["rapid", "plunge", "cut", "cut", "cut", "link", "rapid"]
    >>> tp = ToolPath.build(cut + [[3, 2.5, -1], [7, 2.5, -1]], kind=kind, feed=100)
    >>> unproven_rapids(tp, box(0, 0, 10, 10), 1.0, 0.05, [-1.0])
    []
    >>> tp = ToolPath.build(cut + [[3, 3.3, -1], [7, 3.3, -1]], kind=kind, feed=100)
    >>> unproven_rapids(tp, box(0, 0, 10, 10), 1.0, 0.05, [-1.0])
    [6]

    A G0 back along the very line of a cut is not proven (its disc meets the pixels along the rim the
    cut swept only in part): the planner leaves a cut boundary by a short feed leg.
    """
    h = float(resolution_mm)
    r_rapid = tool_radius - h / math.sqrt(2.0)
    r_capsule = tool_radius + h / math.sqrt(2.0) * (1 + 1e-9)
    x0, y0, x1, y1 = pocket.bounds
    m = 2 * h
    x0, y0 = x0 - m, y0 - m
    nx, ny = int(math.ceil((x1 - x0 + m) / h)), int(math.ceil((y1 - y0 + m) / h))
    P, K = tp.xyz, tp.kind
    bad = []
    for z in levels:
        M = raster(pocket, x0, y0, h, nx, ny)
        if start_hole is not None:
            cut_disc(M, x0, y0, h, start_hole[0], start_hole[1], 0.5 * start_hole[2] - h / math.sqrt(2.0), np.nan, np.nan)
        on = np.abs(P[:, 2] - z) < 1e-9
        for k in np.flatnonzero(on[1:]) + 1:
            a, b = P[k - 1], P[k]
            if not on[k - 1] or tp.arc[k] != 0:
                # arriving on the level (a helix, a plunge) or an arc: only the end is sure to be swept
                cut_disc(M, x0, y0, h, b[0], b[1], r_rapid, np.nan, np.nan)
                continue
            if K[k] == _RAPID and not capsule_free(M, x0, y0, h, a[0], a[1], b[0], b[1], r_capsule):
                bad.append(int(k))
            _cut_segment(M, x0, y0, h, a, b, r_rapid)
    return bad


def _cut_segment(M, x0, y0, h, a, b, rr):
    """Discs of radius ``rr`` every h/2 along a -> b (both ends included)."""
    L = math.hypot(b[0] - a[0], b[1] - a[1])
    n = max(1, int(math.ceil(L / (0.5 * h))))
    pcx = pcy = np.nan
    for t in np.linspace(0.0, 1.0, n + 1):
        cx, cy = a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])
        cut_disc(M, x0, y0, h, cx, cy, rr, pcx, pcy)
        pcx, pcy = cx, cy
