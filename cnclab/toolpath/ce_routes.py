"""Routes of the constant-engagement clearing (:mod:`cnclab.toolpath.ce_clearing`): straight links
that miss the material, shortest links through the cleared region on a grid (scipy Dijkstra), the
seeds' geodesic cells, the labelling of a simulated stretch into cutting runs and links, and the
roll-in arcs onto a run (Jacsó §4).

Units: mm, mm², deg, mm/min; ``r`` is the tool *radius*.

>>> from shapely.geometry import box
>>> cells = geodesic_cells(box(0, 0, 20, 10), [(5, 5), (15, 5)])     # one cell per seed, tiling the box
>>> len(cells), round(sum(c.area for c in cells), 6)
(2, 200.0)
"""
from __future__ import annotations

import math

import numpy as np
import shapely
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra
from shapely.geometry import LineString, Point, Polygon
from shapely.geometry.polygon import orient

from ..simulation.common import simulate

__all__ = ["chord_clear", "dilate", "round_corners", "grid_graph", "geodesic", "geodesic_cells", "split_runs",
           "roll_in", "ROLL_IN_OFFSETS",
           "ROLL_IN_RADII", "ROLL_IN_SWEEPS_DEG"]


def chord_clear(a, b, material, guard, r, margin_mm):
    """Is the straight move a -> b inside ``guard`` and its swept disk (radius r - margin) free of
    ``material`` (shapely geometry)?"""
    line = LineString([a, b])
    if line.length < 1e-9:
        return True
    if not guard.contains(line):
        return False
    return material.is_empty or not line.buffer(r - margin_mm, quad_segs=16).intersects(material)


#: segments per quarter circle of :func:`dilate`'s round joins (its distance is raised by the chord error)
DILATE_QUAD_SEGS = 8


def dilate(material, distance_mm: float, tol_mm: float):
    """A polygon containing every point within ``distance_mm`` (mm) of ``material`` (a shapely
    geometry), and at most about ``tol_mm`` + 0.5 % of ``distance_mm`` more: ``material`` simplified
    within ``tol_mm`` (the dixel stock's staircase of rows collapses to its outline), grown by
    ``distance_mm + tol_mm``, with the round joins' chords pushed out to contain the arcs; any
    material the simplification left farther than ``tol_mm`` outside (GEOS's topology-preserving
    simplifier does not bound that: up to 0.02 mm^2 seen on the spline pocket) is grown by
    ``distance_mm`` and added. ~100x faster than growing the staircase itself (2 s -> 0.02 s a call
    on data/pockets/spline_pocket.json at 0.1 mm rows), which dominated the constant-engagement planner.

    >>> from shapely.geometry import box
    >>> m = box(0, 0, 1, 1)
    >>> bool(dilate(m, 2.0, 0.1).contains(m.buffer(2.0, quad_segs=64)))
    True
    """
    if material.is_empty:
        return material
    q = DILATE_QUAD_SEGS
    sec = 1.0 / math.cos(math.pi / (4 * q))              # a join's chords lie inside its arc by (sec - 1) x radius
    ms = material.simplify(tol_mm)
    out = ms.buffer((distance_mm + tol_mm) * sec, quad_segs=q)
    extra = material.difference(ms.buffer(tol_mm, quad_segs=q))
    if not extra.is_empty:
        out = out.union(extra.buffer(distance_mm * sec, quad_segs=q))
    return out


def round_corners(region, radius_mm: float, min_turn_deg: float = 20.0):
    """``region`` (mm) with each convex vertex of its rings that turns by more than ``min_turn_deg``
    (deg) rounded by a tangent arc of radius ``radius_mm`` (mm): the morphological opening of
    ``region`` by that radius, kept only near those vertices (thin parts elsewhere stay whole).

    >>> from shapely.geometry import box
    >>> round(box(0, 0, 10, 10).area - round_corners(box(0, 0, 10, 10), 1.0).area, 3)   # 4 (1 - pi/4)
    0.859
    """
    if not radius_mm > 0:
        return region
    opened = region.buffer(-radius_mm, quad_segs=64).buffer(radius_mm, quad_segs=64)
    discs = []
    for p in shapely.get_parts(region):
        if not isinstance(p, Polygon) or p.is_empty:
            continue
        for ring in [orient(p, 1.0).exterior] + list(orient(p, 1.0).interiors):
            V = np.asarray(ring.coords)[:-1]
            if len(V) < 3:
                continue
            a, b = V - np.roll(V, 1, axis=0), np.roll(V, -1, axis=0) - V
            turn = np.degrees(np.arctan2(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0], (a * b).sum(axis=1)))
            # exterior counter-clockwise, holes clockwise: a left turn (> 0) is convex for the region
            for v, t in zip(V, turn):
                if t > min_turn_deg:
                    reach = radius_mm * (1.0 + 1.0 / math.tan(math.radians(180.0 - t) / 2.0))
                    discs.append(Point(v).buffer(reach, quad_segs=16))
    if not discs:
        return region
    return region.difference(region.difference(opened).intersection(shapely.union_all(discs)))


def grid_graph(free, grid_mm):
    """8-connected grid graph of the points of ``free`` (spacing ``grid_mm``): (csr, points (n, 2))."""
    x0, y0, x1, y1 = free.bounds
    X, Y = np.meshgrid(np.arange(x0, x1 + grid_mm, grid_mm), np.arange(y0, y1 + grid_mm, grid_mm))
    ok = shapely.contains_xy(free, X, Y)
    idx = np.full((ok.shape[0] + 2, ok.shape[1] + 2), -1)
    idx[1:-1, 1:-1][ok] = np.arange(ok.sum())
    A = idx[1:-1, 1:-1]
    rows, cols, w = [], [], []
    for dj, di in ((0, 1), (1, 0), (1, 1), (1, -1)):
        B = idx[1 + dj:idx.shape[0] - 1 + dj, 1 + di:idx.shape[1] - 1 + di]
        m = (A >= 0) & (B >= 0)
        rows.append(A[m])
        cols.append(B[m])
        w.append(np.full(int(m.sum()), grid_mm * math.hypot(di, dj)))
    n = int(ok.sum())
    G = coo_matrix((np.concatenate(w), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)).tocsr()
    return G, np.c_[X[ok], Y[ok]]


def geodesic(a, b, free, grid_mm, guard, material=None, r=0.0, margin_mm=0.0):
    """Shortest 8-connected grid path (spacing ``grid_mm``) from a to b inside the polygon ``free``
    (scipy Dijkstra), simplified; (n, 2) points a ... b inside ``guard`` (and, when ``material`` is
    given, whose swept disk of radius ``r - margin_mm`` misses it), or None."""
    free = free() if callable(free) else free
    if free.is_empty:
        return None
    G, pts = grid_graph(free, grid_mm)
    if len(pts) == 0:
        return None
    ia = int(np.argmin(np.hypot(*(pts - a).T)))
    ib = int(np.argmin(np.hypot(*(pts - b).T)))
    dist, pred = dijkstra(G, directed=False, indices=ia, return_predecessors=True)
    if not np.isfinite(dist[ib]):
        return None
    chain = [ib]
    while chain[-1] != ia:
        chain.append(pred[chain[-1]])
    route = np.vstack([a, pts[chain[::-1]], b])
    simp = LineString(route).simplify(0.5 * grid_mm, preserve_topology=False)

    def ok(line):
        if not guard.contains(line):
            return False
        return material is None or material.is_empty or not line.buffer(r - margin_mm, quad_segs=8).intersects(material)

    if free.buffer(0.5 * grid_mm).contains(simp) and ok(simp):
        return np.asarray(simp.coords)
    return route if ok(LineString(route)) else None


def geodesic_cells(allowed, seeds, grid_mm: float = 1.0):
    """Split ``allowed`` (mm) into one cell per seed: the points geodesically nearest (inside
    ``allowed``, 8-connected grid of ``grid_mm``) to that seed; the cells tile ``allowed`` (their
    interfaces are straightened to within ``grid_mm``). Returns a list of polygons."""
    G, pts = grid_graph(allowed, grid_mm)
    src = [int(np.argmin(np.hypot(*(pts - np.asarray(s)).T))) for s in seeds]
    D = np.atleast_2d(dijkstra(G, directed=False, indices=src))
    lab = np.argmin(D, axis=0)
    if len(seeds) == 1:
        return [allowed]
    cells, taken = [], Polygon()
    for k in range(len(seeds)):
        q = pts[lab == k]
        sq = shapely.union_all(shapely.box(q[:, 0] - grid_mm / 2, q[:, 1] - grid_mm / 2,
                                           q[:, 0] + grid_mm / 2, q[:, 1] + grid_mm / 2))
        # grow by one grid step to cover the boundary strip, simplify the staircase, no overlaps
        cell = sq.buffer(2 * grid_mm).simplify(0.5 * grid_mm).intersection(allowed).difference(taken)
        if k == len(seeds) - 1:
            cell = allowed.difference(taken)
        cells.append(cell)
        taken = taken.union(cell)
    return cells


def split_runs(P, removed, material, guard, r, air_tol_mm2, kind, min_run, margin_mm, free=None,
                grid_mm=1.0):
    """Label the points of a simulated stretch ``P`` (``removed[i]``: area cut at point i, mm²).
    Cutting points keep ``kind``; an air run between cutting points becomes one straight link when
    the tool swept along the chord stays in ``guard`` and misses the material left at that time
    (``material`` before the stretch minus the stretch swept so far), otherwise it stays as an air
    link along ``P``. Trailing air is dropped. Returns ``(points, kinds)`` or None."""
    cutting = removed > air_tol_mm2
    if not cutting.any():
        return None
    last = int(np.flatnonzero(cutting)[-1])
    out_p, out_k = [P[0]], [kind if cutting[0] else "link"]
    i = 1
    while i <= last:
        if cutting[i]:
            out_p.append(P[i])
            out_k.append(kind)
            i += 1
            continue
        j = i
        while not cutting[j]:
            j += 1                                        # P[i:j] air, P[j] cuts (j <= last)
        ok = False
        if j - i >= min_run and np.hypot(*(P[j - 1] - out_p[-1])) < 0.9 * np.sum(np.hypot(*np.diff(P[i - 1:j], axis=0).T)):
            swept = LineString(P[:i]).buffer(r, quad_segs=16) if i > 1 else Point(P[0]).buffer(r, quad_segs=16)
            ok = chord_clear(out_p[-1], P[j - 1], material.difference(swept), guard, r, margin_mm)
        route = None
        if not ok and free is not None and j - i >= min_run:
            swept = LineString(P[:j]).buffer(r, quad_segs=16)
            route = geodesic(out_p[-1], P[j - 1], free, grid_mm, guard, material.difference(swept), r, margin_mm)
            if route is not None and LineString(route).length >= 0.9 * LineString(P[i - 1:j]).length:
                route = None
        if ok:
            out_p.append(P[j - 1])                        # straight link to the last air point
            out_k.append("link")
        elif route is not None:                           # shortest link through the cleared region
            out_p.extend(route[1:])
            out_k.extend(["link"] * (len(route) - 1))
        else:
            out_p.extend(P[i:j])
            out_k.extend(["link"] * (j - i))
        i = j
    return np.asarray(out_p), np.asarray(out_k, dtype=object)


#: roll-in candidates (:func:`roll_in`): where along the run (x r), arc radii (x r), swept angles (deg)
ROLL_IN_OFFSETS, ROLL_IN_RADII, ROLL_IN_SWEEPS_DEG = (0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0), (1.0, 2.0, 3.0, 4.0), \
    (90.0, 45.0, 30.0)


def roll_in(stock, P, r, limits_deg, guard, free, a_p, feed_mm_min, step, at, allowed):
    """A roll-in arc (Jacsó §4) onto the run ``P`` (mm): a circular arc of radius rho >= r
    (:data:`ROLL_IN_RADII` x r) tangent to ``P`` at ``P[j]``, :data:`ROLL_IN_OFFSETS` x r along the run
    (a run resuming from the wall leaves it at an angle, and no tangent arc inside the final contour
    reaches its first point), swept back :data:`ROLL_IN_SWEEPS_DEG`, whose start lies in ``free`` (the
    tool there misses the material), inside ``guard`` (the allowed region). Each candidate is cut, with
    the first tool radius of ``P[j:]``, through a copy of ``stock`` (``a_p``, ``feed_mm_min``); the first
    offset with a candidate at or below ``limits_deg[0]`` (deg) gives the arc of lowest maximum
    engagement, else the lowest over all offsets if at or below ``limits_deg[1]``:
    the engagement ramps up from air instead of the tool entering the run head-on (what ``P[:j]``
    leaves is cut by later laps or the final pass). Only a run resuming from the final contour (``P[0]``
    within ``step`` of the boundary of ``allowed``, away from the tool position ``at``) is entered so.
    Returns ``(arc (n, 2) from its start to P[j], j)``, or ``(None, 0)``.

    Measured at r/20 (strategy constant-engagement, which uses it): share of the cutting length above
    theta + 5 on Jacsó's rectangle 4.81 -> 2.76 %, two_regions 2.37 -> 1.56 %, L 6.48 -> 2.23 %, star
    6.83 -> 6.45 %, long_slot 36.2 % unchanged; the maximum is not lowered (127.7 deg on the rectangle:
    a lap stretch and the runs no arc reaches). Not the default: on the island pocket of
    tests/test_ce_clearing.py it leaves 13.4 mm² uncut (0.75 without) and reaches 180 deg."""
    P = np.asarray(P, float)
    if np.hypot(*(P[0] - np.asarray(at))) < 1e-9 or allowed.boundary.distance(Point(P[0])) > step:
        return None, 0
    s_run = np.r_[0.0, np.cumsum(np.hypot(*np.diff(P, axis=0).T))]
    fr, best = None, (math.inf, None, 0)
    for off in ROLL_IN_OFFSETS:
        j = int(np.searchsorted(s_run, off * r))
        if j >= len(P) - 2:
            break
        jt = min(len(P) - 1, max(j + 1, int(np.searchsorted(s_run, s_run[j] + 0.5 * step))))
        u = P[jt] - P[j]
        if np.hypot(*u) < 1e-9:
            continue
        u = u / np.hypot(*u)
        n = np.array([-u[1], u[0]])
        head = P[j + 1:max(j + 2, int(np.searchsorted(s_run, s_run[j] + r)) + 1)]
        for k_r in ROLL_IN_RADII:
            rho = k_r * r
            for sw in ROLL_IN_SWEEPS_DEG:
                for side in (1.0, -1.0):
                    C = P[j] + side * rho * n
                    m = max(int(math.ceil(rho * math.radians(sw) / step)), 4)
                    phi = -side * np.linspace(math.radians(sw), 0.0, m + 1)   # start -> P[j]
                    v = P[j] - C
                    A = C + np.c_[np.cos(phi) * v[0] - np.sin(phi) * v[1], np.sin(phi) * v[0] + np.cos(phi) * v[1]]
                    if not guard.contains(LineString(A)):
                        continue
                    fr = free() if fr is None else fr
                    if not fr.contains(Point(A[0])):
                        continue
                    eng = simulate(stock, np.vstack([A, head]), r, a_p, feed_mm_min, copy=True).engagement_deg.to_numpy()
                    e = float(np.nanmax(np.r_[eng, 0.0]))
                    if e < best[0]:
                        best = (e, A, j)
        if best[0] <= limits_deg[0]:
            break
    if best[0] <= limits_deg[1]:
        return best[1], best[2]
    return None, 0
