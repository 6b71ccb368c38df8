"""Tool-path reordering as a search (Mgherony 2024, Sec. 9.2, Thesis 5). Lengths mm, angles deg.

1. Densify the CL points so that no step exceeds d_lim (eqs 9-1 ... 9-3; d_lim = a_e suggested).
2. Assign each point the normal of its STL facet (nearest centroid, as Sec. 7.2.3).
3. Neighbour sets: the k nearest points (k = 4 or 8); the thesis grows a radius R until at least k
   points are inside, which (without ties) is the k-nearest set -- a KD-tree query.
4. From the start point, repeatedly move to the unvisited (non-tabu) neighbour with the smallest
   |D_eff(neighbour, A_f = direction of the move) - D_eff(current)|; ties within ``tie_tol`` (flat
   areas) go to the neighbour closest to the current feed direction. When every neighbour is
   visited, *jump* to the nearest unvisited point (counted).

Complexity: the working diameters of all (point, neighbour) pairs are computed in one vectorised
call; the walk itself is O(N k) plus the jump searches (KD-tree of the unvisited points, rebuilt
when half of it has been visited).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["densify", "ReorderResult", "reorder_path", "path_metrics", "reordered_program"]


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
    d = np.linalg.norm(np.diff(P, axis=0), axis=1)                  # eq 9-1
    I = np.maximum(1, np.ceil(d / d_lim - 1e-12)).astype(np.int64)  # eq 9-2
    seg = np.repeat(np.arange(len(d)), I)
    j = np.arange(seg.size) - np.repeat(np.cumsum(I) - I, I)
    frac = j / I[seg]
    dense = P[seg] + frac[:, None] * (P[seg + 1] - P[seg])          # eq 9-3
    return np.vstack([dense, P[-1:]]), np.append(seg, len(P) - 1)


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


def reorder_path(points, normals, *, tool_diameter: float, a_p: float, k: int = 4, start: int = 0,
                 feed_direction_deg: float = 0.0, point: str = "max", tie_tol: float = 1e-6,
                 direction: str = "move") -> ReorderResult:
    """Reorder CL ``points`` (N, 3) with facet ``normals`` (N, 3) by the Sec. 9.2 search.

    Parameters: tool_diameter, a_p (mm); k neighbours (4 or 8 in the thesis); start index;
    feed_direction_deg initial/tie-break direction; point tangent-point rule (see spindle_control);
    direction "move" (D_eff of a neighbour evaluated with A_f = direction of the move to it, as Sec. 9.2
    describes) or "constant" (D_eff of every point at the constant feed_direction_deg of Table 9-1).
    """
    if direction not in ("move", "constant"):
        raise ValueError(f"direction must be 'move' or 'constant', got {direction!r}")
    from ..cutting.spindle_control import working_diameters

    P = np.asarray(points, float)
    N = len(P)
    if N < 2:
        raise ValueError("points: need at least 2 points")
    if not (0 <= start < N):
        raise ValueError(f"start must be in [0, {N}), got {start}")
    if int(k) != k or k < 1:
        raise ValueError(f"k must be a positive integer, got {k}")
    k = int(min(k, N - 1))
    tree = cKDTree(P)
    _, nb = tree.query(P, k=k + 1)
    nb = nb[:, 1:]
    # working diameter of every neighbour for the move direction current -> neighbour
    dx = P[nb, 0] - P[:, None, 0]
    dy = P[nb, 1] - P[:, None, 1]
    ang = np.degrees(np.arctan2(dy, dx))
    nrm = np.asarray(normals, float)
    d_nb, _, _ = working_diameters(nrm[nb.ravel()], ang.ravel(), tool_diameter, a_p, point, feed_direction_deg)
    d_nb = d_nb.reshape(nb.shape)
    if direction == "constant":
        d_pt = working_diameters(nrm, np.full(N, float(feed_direction_deg)), tool_diameter, a_p, point,
                                 feed_direction_deg)[0]
        d_nb = d_pt[nb]
    d_start, _, _ = working_diameters(nrm[[start]], np.array([feed_direction_deg]), tool_diameter, a_p, point,
                                      feed_direction_deg)
    visited = np.zeros(N, bool)
    order = np.empty(N, np.int64)
    jump = np.zeros(N, bool)
    deff = np.empty(N)
    cur, cur_d, cur_dir = start, float(d_start[0]), math.radians(feed_direction_deg)
    visited[cur] = True
    order[0], deff[0] = cur, cur_d
    # jump search: KD-tree over the unvisited points, rebuilt when half of it is visited
    pool = np.arange(N)
    pool_tree = tree
    pool_visited = 1
    nb_l = nb.tolist()
    dnb_l = d_nb.tolist()
    ang_l = np.radians(ang).tolist()
    for step in range(1, N):
        best, best_key = -1, None
        row, drow, arow = nb_l[cur], dnb_l[cur], ang_l[cur]
        for q, dq, aq in zip(row, drow, arow):
            if visited[q]:
                continue
            diff = abs(dq - cur_d)
            turn = abs(math.remainder(aq - cur_dir, 2 * math.pi))
            key = (round(diff / tie_tol) if tie_tol > 0 else diff, turn)
            if best_key is None or key < best_key:
                best, best_key, best_d, best_a = q, key, dq, aq
        if best < 0:  # stuck: jump to the nearest unvisited point
            if pool_visited * 2 > len(pool):
                pool = np.nonzero(~visited)[0]
                pool_tree = cKDTree(P[pool])
                pool_visited = 0
            kk = 8
            while True:
                kq = min(kk, len(pool))
                _, cand = pool_tree.query(P[cur], k=kq)
                cand = pool[np.atleast_1d(cand)]
                free = cand[~visited[cand]]
                if free.size or kq == len(pool):
                    break
                kk *= 4
            best = int(free[0])
            v = P[best] - P[cur]
            best_a = math.atan2(v[1], v[0]) if abs(v[0]) + abs(v[1]) > 1e-12 else cur_dir
            a_deg = math.degrees(best_a) if direction == "move" else feed_direction_deg
            best_d = float(working_diameters(nrm[[best]], np.array([a_deg]), tool_diameter, a_p,
                                             point, feed_direction_deg)[0][0])
            jump[step] = True
        visited[best] = True
        pool_visited += 1
        order[step], deff[step] = best, best_d
        cur, cur_d, cur_dir = best, best_d, best_a
    return ReorderResult(order, jump, deff)


def path_metrics(points, d_eff, v_c: float = 63.0, jump=None) -> dict:
    """Travelling distance (mm), and the ranges of |Delta D_eff| (mm) and |Delta n| (rpm) between
    consecutive points of a path (points in visiting order, d_eff per point); moves flagged in ``jump``
    (bool per point: the move into it) are excluded from the Delta ranges (the tool lifts)."""
    from ..cutting.speeds import spindle_speed

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


def reordered_program(points, result: ReorderResult, *, feed_mm_min: float, spindle_rpm: float,
                      tool_diameter: float, clearance_z: float, partno: str = "CNCLAB_REORDERED",
                      decimals: int = 3):
    """An APT program visiting ``points`` (N, 3, mm) in ``result.order``: feed moves between
    neighbours, and at every jump a retract to ``clearance_z`` (mm), a rapid over the next point and a
    rapid plunge onto it (the tool lifts; no material is cut on a jump).

    >>> P = np.array([[0, 0, 0], [1, 0, 0], [5, 5, 0.0]])
    >>> r = ReorderResult(np.array([0, 1, 2]), np.array([False, False, True]), np.ones(3))
    >>> prog = reordered_program(P, r, feed_mm_min=500, spindle_rpm=2000, tool_diameter=10, clearance_z=30)
    >>> cl = prog.cl_points(); cl.rapid.tolist()
    [True, True, False, True, True, True, True]
    """
    from .apt import cl_program

    P = np.asarray(points, float)
    order = np.asarray(result.order)
    if P.ndim != 2 or P.shape[1] != 3 or len(order) != len(P):
        raise ValueError(f"points must be (N, 3) with N = len(result.order), got {P.shape}, {len(order)}")
    cuts = np.flatnonzero(np.asarray(result.jump, bool))
    segs = np.split(P[order], cuts[cuts > 0])
    return cl_program(segs, feed_mm_min, spindle_rpm, tool_diameter, clearance_z, partno=partno,
                      decimals=decimals, link="rapid")
