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

from ..path import KINDS, ToolPath, resample_polyline
from .grid import rapid_radii, stock_frame
from .stock import capsule_free, cut_disc, cut_path, raster

__all__ = ["unproven_rapids"]

_RAPID = KINDS.index("rapid")


def unproven_rapids(tp: ToolPath, job, resolution_mm: float | None = None) -> list:
    """Indices of the G0 moves at depth of ``tp`` that the path before them does not prove clear.

    ``job``: the :class:`cnclab.toolpath.job.Job` it machines (its ``polygon``, tool radius and
    ``start_hole``); ``tp.info["levels"]``: the cutting z of each level (mm; set by ``plan`` and by
    :func:`.adaptive_clearing`); ``resolution_mm``: the pixel (mm; None: ``tp.info["resolution_mm"]``,
    the planner's). A G0 at depth is a rapid whose start and end lie on one level's z.

    Two passes 1 mm apart (tool radius 1 mm), a feed link to the middle, then a G0 between them --
    or one 0.3 mm past the second pass:

    >>> from shapely.geometry import box
    >>> from cnclab.toolpath.job import Job
    >>> from cnclab.toolpath.path import Tool, ToolPath
    >>> job = Job(box(0, 0, 10, 10), Tool(2.0), 60.0, 1.0, v_c=100, f_z=0.05)
    >>> cut = [[2, 2, 0], [2, 2, -1], [8, 2, -1], [8, 3, -1], [2, 3, -1]]
    >>> kind = ["rapid", "plunge", "cut", "cut", "cut", "link", "rapid"]
    >>> tp = ToolPath.build(cut + [[3, 2.5, -1], [7, 2.5, -1]], kind=kind, feed=100, info={"levels": [-1.0]})
    >>> unproven_rapids(tp, job, 0.05)
    []
    >>> tp = ToolPath.build(cut + [[3, 3.3, -1], [7, 3.3, -1]], kind=kind, feed=100, info={"levels": [-1.0]})
    >>> unproven_rapids(tp, job, 0.05)
    [6]

    A G0 back along the very line of a cut is not proven (its disc meets the pixels along the rim the
    cut swept only in part): the planner leaves a cut boundary by a short feed leg.
    """
    for key in ("levels",) + (("resolution_mm",) if resolution_mm is None else ()):
        if key not in tp.info:
            raise ValueError(f"unproven_rapids: the path's info has no {key!r} (plan() and adaptive_clearing "
                             "set it; give resolution_mm for other paths)")
    h = float(tp.info["resolution_mm"] if resolution_mm is None else resolution_mm)
    r_rapid, r_capsule = rapid_radii(job.tool_radius, h)
    x0, y0, nx, ny = stock_frame(job.polygon, h)
    hole = job.start_hole
    P, K = tp.xyz, tp.kind
    bad = []
    for z in tp.info["levels"]:
        M = raster(job.polygon, x0, y0, h, nx, ny)
        if hole is not None:
            cut_disc(M, x0, y0, h, hole[0], hole[1], 0.5 * hole[2] - h / math.sqrt(2.0), np.nan, np.nan)
        on = np.abs(P[:, 2] - z) < 1e-9
        for k in np.flatnonzero(on[1:]) + 1:
            a, b = P[k - 1], P[k]
            if not on[k - 1] or tp.arc[k] != 0:
                # arriving on the level (a helix, a plunge) or an arc: only the end is sure to be swept
                cut_disc(M, x0, y0, h, b[0], b[1], r_rapid, np.nan, np.nan)
                continue
            if K[k] == _RAPID and not capsule_free(M, x0, y0, h, a[0], a[1], b[0], b[1], r_capsule):
                bad.append(int(k))
            # discs every h/2 along the move, both ends included
            cut_path(M, x0, y0, h, np.ascontiguousarray(resample_polyline(np.array([a[:2], b[:2]]), 0.5 * h)), r_rapid)
    return bad
