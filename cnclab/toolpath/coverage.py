"""What a plan leaves: the area of each pocket region that no tool disc at a level's depth swept,
beyond the corners no tool disc can reach (:func:`uncut_report`), and the limit above which
:func:`cnclab.toolpath.planners.plan` refuses a plan (:data:`UNCUT_ABS_MM2`, :data:`UNCUT_REL`).

At each level z (:meth:`Job.levels`) the part of every region a tool disc can reach (its
morphological opening by the disc of radius r, shapely) is rasterised (pixel stock of
:mod:`cnclab.simulation.pixel`, pixel h = r / 25, pixel centres inside) and the tool disc is stamped
every r / 10 along every move whose two ends are at that z (arcs sampled with chords of at most
r / 10): the stamped discs' edge is within (r/10)^2 / (8 r) = r / 800 (a thirtieth of a pixel) of the
swept band's. A pixel left counts when its centre is farther than r + :data:`CONTACT_MM` (2 um)
from every move at z, measured exactly (:class:`cnclab.simulation.vector.SweptDiscs`): the stamps'
scallops and a pass that follows a wall a micrometre off leave nothing, a rest of any thickness
above that counts (until 2026-11-28 the pixels were opened by a 3 x 3 square instead, which also
dropped real rests up to about 2 h = r / 12 thick: the 0.18 mm crescents a finishing lap leaves
when it takes a square corner by its chord, 0.8 mm^2 a corner on a 64 x 46 L, D8, reported as 0.0
where ``cnclab analyze`` read 11.9 mm^2). Uncut areas are summed over the levels (as
:func:`cnclab.toolpath.evaluate.evaluate` sums them). Units: mm, mm^2.

>>> from shapely.geometry import box
>>> from cnclab.toolpath.path import Tool, ToolPath
>>> job = Job(box(0, 0, 20, 10), Tool(6.0), 60.0, 2.0, v_c=100, f_z=0.05)
>>> p = ToolPath.build([[3, 5, 5], [3, 5, -2], [17, 5, -2], [17, 5, 5]], kind=["rapid", "plunge", "cut", "retract"],
...                    feed=300)
>>> rep = uncut_report(p, job)     # one pass along the middle: 2 x (20 x 2) minus the rounded ends = 80.0 mm^2
>>> abs(rep["uncut_mm2"][0] - 80.0) < 1.0, rep["over"]
(True, [0])
"""
from __future__ import annotations

import math

import numpy as np
import shapely
from ..simulation.pixel import Stock
from ..simulation.vector import SweptDiscs

from .evaluate import POSITION_TOL_MM
from .job import Job
from .path import ToolPath

__all__ = ["UNCUT_ABS_MM2", "UNCUT_REL", "uncut_report", "uncut_limit_mm2", "wall_gouge"]

#: uncut area a plan may leave in a region (mm^2): UNCUT_ABS_MM2 + UNCUT_REL x the region's reachable
#: area -- 1 mm^2 of cusps and chord errors plus 1 % (a pass boundary's cusps: an a_e / 2-high ridge
#: left along a pass is far below this; a skipped neck, finger or annulus is far above it)
UNCUT_ABS_MM2 = 1.0
UNCUT_REL = 0.01
#: mm: a pixel whose centre is within r + this of a swept segment is cut (a rest thinner than the chip
#: the engagement counts as contact, :func:`cnclab.simulation.vector.vector_engagement`'s 2 um)
CONTACT_MM = 2e-3


def uncut_limit_mm2(reach_area_mm2: float) -> float:
    """The uncut area (mm^2) :func:`cnclab.toolpath.planners.plan` accepts in a region whose reachable
    area is ``reach_area_mm2``."""
    return UNCUT_ABS_MM2 + UNCUT_REL * float(reach_area_mm2)


def _runs(P: np.ndarray, z: float, at_or_below: bool = False) -> list:
    """The (m, 2) polylines (mm) of the runs of ``P`` ((n, 3) mm, the path's polyline) whose two ends
    are at ``z`` (``at_or_below``: at or below it), and single such points as (1, 2) arrays."""
    # at or below: up to POSITION_TOL_MM above z too, a level's z as a program writes it (-4.9833 for
    # -4.983333 is 33 nm above; at 1e-6 the last level's whole floor read uncut: 1193 mm^2 of a 40 x 30)
    at = (P[:, 2] <= z + POSITION_TOL_MM) if at_or_below else (np.abs(P[:, 2] - z) <= 1e-6)
    seg = at[1:] & at[:-1]
    edges = np.flatnonzero(np.diff(np.r_[0, seg.astype(int), 0]))
    runs = [P[i0:i1 + 1, :2] for i0, i1 in zip(edges[0::2], edges[1::2])]      # segments i0..i1-1
    lone = at & ~np.r_[seg, False] & ~np.r_[False, seg]
    return runs + [p[None, :] for p in P[lone, :2]]


def _centres(runs: list, step: float) -> np.ndarray:
    """Tool centres (x, y) every ``step`` mm of arc length along each run (and its last point)."""
    pts = [np.zeros((0, 2))]
    for Q in runs:
        sc = np.r_[0.0, np.cumsum(np.hypot(*np.diff(Q, axis=0).T))]
        t = np.r_[np.arange(0.0, sc[-1], step), sc[-1]]
        pts.append(np.c_[np.interp(t, sc, Q[:, 0]), np.interp(t, sc, Q[:, 1])])
    return np.vstack(pts)


def _left_mm2(region, centres, r: float, swept: SweptDiscs) -> float:
    """Area (mm^2) of ``region`` no disc of radius ``r`` along ``swept`` reaches: the pixels the discs
    at ``centres`` leave, each kept only when its centre is farther than r + :data:`CONTACT_MM` from
    every swept segment (exact: the stamps' scallops and a rest thinner than a chip are not uncut)."""
    if region.is_empty:
        return 0.0
    h = r / 25.0
    x0, y0, x1, y1 = region.bounds
    h = max(h, math.sqrt((x1 - x0) * (y1 - y0) / 2e7))          # at most ~2e7 pixels
    st = Stock.from_polygon(region, h)
    far = st.copy()
    st.cut_disks_pixels(centres, r)
    # a pixel beyond r + 2 h of every stamp is beyond r + 2 h - r / 20 > r + CONTACT_MM of the moves
    # (stamps every r / 10 along them, h >= r / 25): uncut without asking; only the ring between asked
    far.cut_disks_pixels(centres, r + 2.0 * h)
    j, i = np.nonzero(st.grid & ~far.grid)
    n = float(np.count_nonzero(far.grid))
    if len(j) and len(swept):
        xy = np.c_[st.x0 + (i + 0.5) * h, st.y0 + (j + 0.5) * h]
        n += float(np.count_nonzero(swept.distance(xy) > r + CONTACT_MM))
    else:
        n += len(j)
    return n * h * h


def uncut_report(path: ToolPath, job: Job, at_or_below: bool = False) -> dict:
    """Uncut area beyond the unreachable corners, by region of ``job.polygon`` (largest first as
    shapely lists them), summed over the levels (the limit too: :func:`uncut_limit_mm2` per level):
    ``{"uncut_mm2": [..], "reach_mm2": [..],
    "limit_mm2": [..], "over": [region indices above their limit], "levels": [z ..]}``.
    A level's floor counts as cut where the moves at its depth swept it (a planner's own levels);
    ``at_or_below``: the moves at or below its depth, within the programs' reading tolerance
    :data:`~cnclab.toolpath.evaluate.POSITION_TOL_MM` (any program: a deeper move clears the floor
    above it too, a floor written 33 nm above the level by rounding is the level's, and a floor cut
    0.1 mm above it is not)."""
    r = job.tool_radius
    regions = list(shapely.get_parts(job.polygon))
    reach = [g.buffer(-r, quad_segs=64).buffer(r, quad_segs=64) for g in regions]
    levels = job.levels()
    uncut = np.zeros(len(regions))
    P, _ = path.polyline(max(r / 10.0, 1e-3))          # arcs by chords of at most r / 10
    for z in levels:
        runs = _runs(P, z, at_or_below)
        c = _centres(runs, r / 10.0)
        swept = SweptDiscs(r)
        for Q in runs:
            swept.add(Q)
        for k, R in enumerate(reach):
            x0, y0, x1, y1 = R.bounds if not R.is_empty else (0, 0, 0, 0)
            near = c[(c[:, 0] > x0 - r) & (c[:, 0] < x1 + r) & (c[:, 1] > y0 - r) & (c[:, 1] < y1 + r)]
            uncut[k] += _left_mm2(R, near, r, swept)
    # the limit holds per level: the sum over n levels may reach n times it (a deep pocket repeats
    # the one-level plan; the sum of three levels of a plan accepted at one level is no worse)
    lim = [uncut_limit_mm2(R.area) * len(levels) for R in reach]
    return {"uncut_mm2": uncut.round(3).tolist(), "reach_mm2": [round(R.area, 3) for R in reach],
            "limit_mm2": [round(v, 3) for v in lim], "over": [k for k in range(len(regions)) if uncut[k] > lim[k]],
            "levels": levels}


#: mm: the segments :func:`_deep_inside` may skip are at most this many r long
_DEEP_SEG_FRAC = 0.05


def _deep_inside(polygon, P, seg, r: float) -> np.ndarray:
    """For the segments ``P[seg] -> P[seg + 1]`` (mm): True where the segment lies inside the pocket
    shrunk by ``r (1 + 2e-4) + 2e-6`` mm, proven without building it: it is at most
    ``_DEEP_SEG_FRAC r`` long and both its ends are inside the pocket shrunk by that much more (every
    point of it is within half its length of an end). Such a segment is inside the shrunk pocket
    :func:`wall_gouge` drops segments in (its offset ``r (1 + 1e-4) + 1e-6`` plus the 64-segment
    arcs' sagitta < 7.6e-5 r), so skipping it changes nothing; only the cost of building it.
    """
    L = np.hypot(*(P[seg + 1, :2] - P[seg, :2]).T)
    short = L <= _DEEP_SEG_FRAC * r
    if not short.any():
        return short
    deep = polygon.buffer(-(r * (1.0 + 2e-4) + 2e-6 + 0.5 * _DEEP_SEG_FRAC * r), quad_segs=64)
    if deep.is_empty:
        return np.zeros(len(seg), bool)
    shapely.prepare(deep)
    ends = np.unique(np.r_[seg[short], seg[short] + 1])
    ok = np.zeros(len(P), bool)
    ok[ends] = shapely.contains_xy(deep, P[ends, 0], P[ends, 1])
    return short & ok[seg] & ok[seg + 1]


def wall_gouge(path: ToolPath, job: Job) -> tuple:
    """How far (mm) the tool disc reaches past a wall or island below the stock top, and where:
    ``(depth_mm, (x, y))`` -- max over every move below ``job.top_z`` of r - d, d the exact distance
    (mm) of the move's segment to the pocket boundary (a segment with an end outside the pocket:
    r + that end's distance). Arcs are taken by chords of at most r / 50 (sagitta <= r / 400 on an arc
    of radius r / 10, the smallest helix). ``(0.0, None)`` when the disc never leaves the pocket.

    >>> from shapely.geometry import box
    >>> from cnclab.toolpath.path import Tool, ToolPath
    >>> job = Job(box(0, 0, 40, 20), Tool(6.0), 60.0, 2.0, v_c=100, f_z=0.05)
    >>> p = ToolPath.build([[5, 10, 5], [5, 10, -2], [38, 10, -2]], kind=["rapid", "plunge", "cut"], feed=300)
    >>> g, at = wall_gouge(p, job)          # centre 2 mm from the x = 40 wall, r = 3
    >>> round(g, 6), at
    (1.0, (38.0, 10.0))
    """
    r = job.tool_radius
    P, _ = path.polyline(max(r / 50.0, 1e-3))
    low = P[:, 2] < job.top_z - 1e-9
    if not low.any():
        return 0.0, None
    B = job.polygon.boundary
    inside = shapely.contains_xy(job.polygon, P[:, 0], P[:, 1])
    # points and segments inside the pocket shrunk by r + delta are farther than r from every wall
    # (no gouge): only the others are measured exactly (delta = 1e-4 r + 1e-6 mm exceeds the sagitta
    # r (1 - cos(pi/256)) < 7.6e-5 r of the shrunk pocket's 64-segment arcs). Same result, faster
    inner = job.polygon.buffer(-(r * (1.0 + 1e-4) + 1e-6), quad_segs=64)
    shapely.prepare(inner)
    near = low & ~shapely.contains_xy(inner, P[:, 0], P[:, 1])
    worst, at = -math.inf, None
    if near.any():
        pts = P[near, :2]
        d_pt = shapely.distance(B, shapely.points(pts))
        d_pt = np.where(inside[near], d_pt, -d_pt)
        worst, at = r - float(d_pt.min()), tuple(float(v) for v in pts[int(np.argmin(d_pt))])
    seg = np.flatnonzero(low[1:] & low[:-1] & inside[1:] & inside[:-1])
    seg = seg[np.any(P[seg, :2] != P[seg + 1, :2], axis=1)]
    seg = seg[~_deep_inside(job.polygon, P, seg, r)]
    if len(seg):
        lines = shapely.linestrings(np.stack([P[seg, :2], P[seg + 1, :2]], axis=1))
        lines = lines[~shapely.contains(inner, lines)]
    if len(seg) and len(lines):
        d = shapely.distance(B, lines)
        k = int(np.argmin(d))
        if r - float(d[k]) > worst:
            worst = r - float(d[k])
            q = shapely.get_coordinates(shapely.shortest_line(lines[k], B))[0]
            at = (float(q[0]), float(q[1]))
    return (worst, at) if worst > 0 else (0.0, None)
