"""Tool-path reordering as a search (Mgherony 2024, Sec. 9.2, Thesis 5). Lengths mm, angles deg.

1. Densify the CL points so that no step exceeds d_lim (eqs 9-1 ... 9-3; d_lim = a_e suggested).
2. Assign each point the normal of its STL facet (nearest centroid, as Sec. 7.2.3).
3. Neighbour sets (``neighbours=``): "knn" (default, the thesis reading): the k nearest points
   (k = 4 or 8) of every point, visited or not -- the thesis grows a radius R until at least k points
   are inside, which (without ties) is the k-nearest set, a KD-tree query; visited points are then
   removed from the set as tabu. "radius": the same growth taken literally, R = m * radius_step
   (m = 1, 2, ...) until >= k points are inside, all points within that R (ties and overshoot kept).
   "unvisited": the k nearest *unvisited* points at every step (never empty, so it only jumps when
   ``adjacent_mm`` is given) -- a contrast reading, not the text's.
4. From the start point, repeatedly move to the unvisited (non-tabu) neighbour with the smallest
   |D_eff(neighbour, A_f = direction of the move) - D_eff(current)| (``direction="move"``, Sec. 9.2:
   "the milling direction ... based on the slopes between the tool position and its neighbor
   points"), or of the point's D_eff at the constant Table 9-1 feed direction (``"constant"``);
   ties within ``tie_tol`` (flat areas) go to the neighbour closest to the current feed direction.
   When every neighbour is visited, *jump* to the nearest unvisited point (counted). With
   ``adjacent_mm`` a move to a chosen neighbour farther than that is flagged as a jump too.

Complexity: the working diameters of all (point, neighbour) pairs are computed in one vectorised
call; the walk itself is O(N k) plus the jump searches (KD-tree of the unvisited points, rebuilt
when half of it has been visited).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.spatial import cKDTree

from ..cutting.spindle_model import working_diameters
from ..cutting.speeds import spindle_speed
from .path import Tool, ToolPath, ToolPathBuilder, resample_polyline

__all__ = ["densify", "neighbour_sets", "ReorderOptions", "ReorderResult", "reorder_path", "reordered_path", "path_metrics"]

NEIGHBOUR_RULES = ("knn", "radius", "unvisited")


def densify(points, d_lim: float) -> tuple[np.ndarray, np.ndarray]:
    """Insert points so that consecutive points are at most ``d_lim`` apart (eqs 9-1 ... 9-3).

    Returns ``(dense, source)`` where ``source[j]`` is the index of the original segment start.

    >>> d, s = densify([[0, 0, 0], [1, 0, 0]], 0.4)
    >>> d[:, 0].round(4).tolist(), s.tolist()
    ([0.0, 0.3333, 0.6667, 1.0], [0, 0, 0, 1])
    """
    P = np.asarray(points, float)
    if P.ndim != 2 or P.shape[1] != 3 or len(P) == 0:
        raise ValueError(f"points must have shape (N, 3), got {P.shape}")
    if not (np.isfinite(d_lim) and d_lim > 0):
        raise ValueError(f"d_lim must be > 0 mm, got {d_lim}")
    # eqs 9-1 ... 9-3: every segment in ceil(d / d_lim) equal pieces (the one resampler)
    dense, end = resample_polyline(P, d_lim, return_index=True)
    vertex = np.r_[True, end[1:] != np.r_[end[2:], -1]]               # the pieces ending on a vertex
    return dense, np.where(vertex, end, end - 1)

def neighbour_sets(points, k: int, rule: str = "knn", radius_step: float | None = None, tree=None):
    """Static neighbour sets (self excluded) as CSR arrays ``(indptr, indices)``.

    ``rule="knn"``: the k nearest points; ``"radius"``: every point within R = m * radius_step (mm),
    m the smallest integer for which at least k points are inside (Sec. 9.2 read literally: on a
    regular grid the set can exceed k). Distances are 3D (eq 9-1).

    >>> P = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]])
    >>> ip, ix = neighbour_sets(P, 2)
    >>> ip.tolist(), sorted(ix[:2].tolist())
    ([0, 2, 4, 6, 8], [1, 2])
    >>> neighbour_sets(P, 2, "radius", 1.0)[0].tolist()      # R = 1 holds 2 points: no overshoot
    [0, 2, 4, 6, 8]
    >>> neighbour_sets(P, 3, "radius", 1.0)[0].tolist()      # R = 2 holds all 3 others
    [0, 3, 6, 9, 12]
    """
    P = np.asarray(points, float)
    N = len(P)
    if rule not in ("knn", "radius"):
        raise ValueError(f"rule must be 'knn' or 'radius' for static sets, got {rule!r}")
    k = int(min(k, N - 1))
    tree = cKDTree(P) if tree is None else tree
    dist, nb = tree.query(P, k=k + 1)
    if rule == "knn":
        # drop the point itself (normally column 0; with duplicate points it may sit elsewhere)
        own = nb == np.arange(N)[:, None]
        own[~own.any(axis=1), -1] = True
        own[np.cumsum(own, axis=1) > 1] = False
        keep = nb[~own].reshape(N, k)
        return np.arange(0, N * k + 1, k), keep.ravel()
    if not (radius_step is not None and np.isfinite(radius_step) and radius_step > 0):
        raise ValueError(f"radius_step must be > 0 mm for rule 'radius', got {radius_step}")
    R = np.maximum(1, np.ceil(dist[:, -1] / radius_step - 1e-9)) * radius_step
    lists = tree.query_ball_point(P, R * (1 + 1e-12) + 1e-12, return_sorted=True)
    rows = [[q for q in L if q != i] for i, L in enumerate(lists)]
    counts = np.fromiter((len(r) for r in rows), np.int64, N)
    indptr = np.concatenate([[0], np.cumsum(counts)])
    return indptr, np.fromiter((q for r in rows for q in r), np.int64, int(indptr[-1]))


@dataclasses.dataclass
class ReorderResult:
    """``order`` (N,) visiting order; ``jump`` (N,) bool, True where the move into the point is a jump;
    ``d_eff`` (N,) working diameter (mm) at each visited point (with its arrival direction)."""

    order: np.ndarray
    jump: np.ndarray
    d_eff: np.ndarray

    @property
    def n_jumps(self) -> int:
        return int(self.jump.sum())


@dataclasses.dataclass(frozen=True, kw_only=True)
class ReorderOptions:
    """Settings of the Sec. 9.2 search of :func:`reorder_path`, keyword-only.

    ``tool_diameter``, ``a_p`` (mm); ``k`` neighbours (4 or 8 in the thesis); ``start`` index;
    ``feed_direction_deg`` initial/tie-break direction (deg); ``point`` tangent-point rule (see
    spindle_control); ``tie_tol`` D_eff tie tolerance (mm); ``direction`` "move" (default, Sec. 9.2:
    D_eff of a neighbour evaluated with A_f = direction of the move to it) or "constant" (D_eff of
    every point at the constant feed_direction_deg of Table 9-1); ``neighbours`` "knn" (default) /
    "radius" (needs ``radius_step``, mm) / "unvisited" (module docstring); ``adjacent_mm``: also flag
    moves longer than this (mm) as jumps (None: only empty-set jumps).

    >>> ReorderOptions(tool_diameter=10, a_p=0.3, k=8).neighbours
    'knn'
    """

    tool_diameter: float
    a_p: float
    k: int = 4
    start: int = 0
    feed_direction_deg: float = 0.0
    point: str = "max"
    tie_tol: float = 1e-6
    direction: str = "move"
    neighbours: str = "knn"
    radius_step: float | None = None
    adjacent_mm: float | None = None


def reorder_path(points, normals, options: ReorderOptions | None = None, **fields) -> ReorderResult:
    """Reorder CL ``points`` (N, 3, mm) with facet ``normals`` (N, 3) by the Sec. 9.2 search.

    The settings are a :class:`ReorderOptions` or its fields as keywords (``fields`` replace those of
    ``options``): tool_diameter, a_p (mm), k, start, feed_direction_deg (deg), point, tie_tol (mm),
    direction, neighbours, radius_step (mm), adjacent_mm (mm).

    >>> x, y = np.meshgrid(np.arange(3.0), np.arange(2.0))
    >>> P = np.column_stack([x.ravel(), y.ravel(), np.zeros(6)])
    >>> r = reorder_path(P, np.tile([0, 0, 1.0], (6, 1)), tool_diameter=10, a_p=0.3, k=4)
    >>> r.order.tolist(), r.n_jumps                   # flat: along the feed direction, then back
    ([0, 1, 2, 5, 4, 3], 0)
    """
    o = ReorderOptions(**fields) if options is None else dataclasses.replace(options, **fields)
    tool_diameter, a_p, k, start, point, tie_tol = o.tool_diameter, o.a_p, o.k, o.start, o.point, o.tie_tol
    feed_direction_deg, direction, neighbours = o.feed_direction_deg, o.direction, o.neighbours
    radius_step, adjacent_mm = o.radius_step, o.adjacent_mm
    if direction not in ("move", "constant"):
        raise ValueError(f"direction must be 'move' or 'constant', got {direction!r}")
    if neighbours not in NEIGHBOUR_RULES:
        raise ValueError(f"neighbours must be one of {NEIGHBOUR_RULES}, got {neighbours!r}")
    if adjacent_mm is not None and not adjacent_mm > 0:
        raise ValueError(f"adjacent_mm must be > 0 mm or None, got {adjacent_mm}")
    P = np.asarray(points, float)
    N = len(P)
    if N < 2:
        raise ValueError("points: need at least 2 points")
    if not (0 <= start < N):
        raise ValueError(f"start must be in [0, {N}), got {start}")
    if int(k) != k or k < 1:
        raise ValueError(f"k must be a positive integer, got {k}")
    k = int(min(k, N - 1))
    nrm = np.asarray(normals, float)
    tree = cKDTree(P)

    def deff(idx, ang_deg):
        return working_diameters(nrm[idx], ang_deg, tool_diameter, a_p, point, feed_direction_deg)[0]

    d_pt = deff(np.arange(N), np.full(N, float(feed_direction_deg))) if direction == "constant" else None
    # static candidate lists (for "unvisited": a 4k-nearest cache, extended on demand)
    if neighbours == "unvisited":
        indptr, flat = neighbour_sets(P, min(4 * k, N - 1), "knn", tree=tree)
    else:
        indptr, flat = neighbour_sets(P, k, neighbours, radius_step, tree=tree)
    src = np.repeat(np.arange(N), np.diff(indptr))
    ang = np.arctan2(P[flat, 1] - P[src, 1], P[flat, 0] - P[src, 0])
    # working diameter of every (point, neighbour) pair for the move direction point -> neighbour
    d_flat = d_pt[flat] if d_pt is not None else deff(flat, np.degrees(ang))
    fl, dl, al = flat.tolist(), d_flat.tolist(), ang.tolist()
    bounds = list(zip(indptr[:-1].tolist(), indptr[1:].tolist()))

    def candidates(cur):
        """(index, D_eff, move angle rad) of the candidate neighbours of ``cur`` (tabu included)."""
        a, b = bounds[cur]
        if neighbours != "unvisited":
            return zip(fl[a:b], dl[a:b], al[a:b])
        free = [j for j in range(a, b) if not visited[fl[j]]][:k]
        if len(free) == k or b - a == N - 1:
            return ((fl[j], dl[j], al[j]) for j in free)
        q = nearest_unvisited(cur, k)                  # beyond the cache: query and evaluate now
        aq = np.arctan2(P[q, 1] - P[cur, 1], P[q, 0] - P[cur, 0])
        dq = d_pt[q] if d_pt is not None else deff(q, np.degrees(aq))
        return zip(q.tolist(), dq.tolist(), aq.tolist())

    pool = {"idx": np.arange(N), "tree": tree, "used": 0}

    def nearest_unvisited(cur, m):
        """The m nearest unvisited points to ``cur`` (KD-tree of the unvisited pool, rebuilt when half used)."""
        if pool["used"] * 2 > len(pool["idx"]):
            pool["idx"] = np.nonzero(~visited)[0]
            pool["tree"] = cKDTree(P[pool["idx"]])
            pool["used"] = 0
        idx, kk = pool["idx"], 2 * m + 6
        while True:
            kq = min(kk, len(idx))
            _, c = pool["tree"].query(P[cur], k=kq)
            c = idx[np.atleast_1d(c)]
            free = c[~visited[c]]
            if free.size >= m or kq == len(idx):
                return free[:m]
            kk *= 4

    visited = np.zeros(N, bool)
    order = np.empty(N, np.int64)
    jump = np.zeros(N, bool)
    d_eff = np.empty(N)
    cur_d = float(d_pt[start] if d_pt is not None else deff(np.array([start]), np.array([feed_direction_deg]))[0])
    cur, cur_dir = start, math.radians(feed_direction_deg)
    visited[cur] = True
    order[0], d_eff[0] = cur, cur_d
    adj2 = None if adjacent_mm is None else adjacent_mm ** 2
    for step in range(1, N):
        best, best_key = -1, None
        for q, dq, aq in candidates(cur):
            if visited[q]:
                continue
            diff = abs(dq - cur_d)
            turn = abs(math.remainder(aq - cur_dir, 2 * math.pi))
            key = (round(diff / tie_tol) if tie_tol > 0 else diff, turn)
            if best_key is None or key < best_key:
                best, best_key, best_d, best_a = q, key, dq, aq
        if best < 0:  # stuck: jump to the nearest unvisited point
            best = int(nearest_unvisited(cur, 1)[0])
            v = P[best] - P[cur]
            best_a = math.atan2(v[1], v[0]) if abs(v[0]) + abs(v[1]) > 1e-12 else cur_dir
            best_d = float(d_pt[best] if d_pt is not None else deff(np.array([best]),
                                                                      np.array([math.degrees(best_a)]))[0])
            jump[step] = True
        elif adj2 is not None and float(np.sum((P[best] - P[cur]) ** 2)) > adj2:
            jump[step] = True
        visited[best] = True
        pool["used"] += 1
        order[step], d_eff[step] = best, best_d
        cur, cur_d, cur_dir = best, best_d, best_a
    return ReorderResult(order, jump, d_eff)


def path_metrics(points, d_eff, v_c: float = 63.0, jump=None) -> dict:
    """Travelling distance (mm), and the ranges of |Delta D_eff| (mm) and |Delta n| (rpm) between
    consecutive points of a path (points in visiting order, d_eff per point); moves flagged in ``jump``
    (bool per point: the move into it) are excluded from the Delta ranges (the tool lifts)."""
    P = np.asarray(points, float)
    d = np.asarray(d_eff, float)
    n = spindle_speed(v_c, np.maximum(d, 1e-6))
    keep = np.ones(len(d) - 1, bool) if jump is None else ~np.asarray(jump, bool)[1:]
    dd = np.abs(np.diff(d))[keep]
    dn = np.abs(np.diff(n))[keep]
    return {"distance_mm": float(np.linalg.norm(np.diff(P, axis=0), axis=1).sum()),
            "dD_min": float(dd.min()), "dD_max": float(dd.max()), "dD_mean": float(dd.mean()),
            "dn_min": float(dn.min()), "dn_max": float(dn.max()), "dn_mean": float(dn.mean()),
            "dD_p99": float(np.percentile(dd, 99)), "dn_p99": float(np.percentile(dn, 99)),
            "jumps": 0 if jump is None else int(np.sum(jump))}


def reordered_path(points, result: ReorderResult, *, feed_mm_min: float, clearance_z: float,
                   spindle_rpm: float | None = None, tool: Tool | None = None) -> ToolPath:
    """The :class:`ToolPath` visiting ``points`` (N, 3, mm) in ``result.order``: a rapid above the
    first point at ``clearance_z``, a plunge onto it, feed moves between neighbours, and at every
    jump a retract to ``clearance_z``, a rapid above the next point and a plunge onto it; a final
    retract. (:class:`ReorderResult` stays the search's record: order, jumps, working diameters.)

    >>> P = np.array([[0, 0, 0], [1, 0, 0], [5, 5, 0.0]])
    >>> r = ReorderResult(np.array([0, 1, 2]), np.array([False, False, True]), np.ones(3))
    >>> reordered_path(P, r, feed_mm_min=500, clearance_z=30).kinds().tolist()
    ['rapid', 'plunge', 'cut', 'retract', 'rapid', 'plunge', 'retract']
    """
    P = np.asarray(points, float)
    order = np.asarray(result.order)
    if P.ndim != 2 or P.shape[1] != 3 or len(order) != len(P):
        raise ValueError(f"points must be (N, 3) with N = len(result.order), got {P.shape}, {len(order)}")
    cuts = np.flatnonzero(np.asarray(result.jump, bool))
    b = ToolPathBuilder(tool=tool, spindle=spindle_rpm, info={"name": "reordered", "n_jumps": result.n_jumps})
    for seg in np.split(P[order], cuts[cuts > 0]):
        b.rapid(seg[:1, :2], z=clearance_z)
        b.plunge(seg[0, :2], seg[0, 2], feed_mm_min)
        b.cut(seg[1:], feed_mm_min)
        b.retract(clearance_z, feed_mm_min)
    return b.build()
