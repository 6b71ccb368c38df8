"""The finishing laps checked on the exact stock where the tool-centre limit turns sharply (a pocket
corner the tool cannot fill): :func:`sharp_points`, :class:`CornerCheck`.

At a convex vertex of the tool-centre region (a pocket corner sharper than the tool) the rim of a
tool that moves into the corner meets the corner's rest over up to the angle the limit turns there
(90 deg in a square corner), however thin that rest is: a chip of 10 um still counts (contact: chips
of 2 um and more). The planning stock (pixels of side h) reads a rest thinner than a pixel as a
fraction of material, so the peel laps that take a corner micrometres at a time read within the
finish target where the exact stock reads theta + 13 deg (corpus jobs rectilinear_1 and comb_1,
``benchmarks/bench_vector_audit.py``). Every lap point within reach of such a corner whose planning
engagement comes near the cap is therefore measured on the exact stock -- the pocket less the discs
of every move the level made at depth (:func:`cnclab.simulation.vector.engagement_along`) -- and the
lap ends before the first point above ``theta + corner_exact_cap_deg``: the rest in the corner stays
(the evaluator counts it as uncut).

Units: mm, deg at the API (the planning engagement ``E`` in rad).
"""
from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.geometry import LineString, box
from shapely.geometry.polygon import orient

from ...simulation.vector import engagement_along

__all__ = ["CornerCheck", "sharp_points"]


def _ring_turns(R: np.ndarray) -> tuple:
    """(turn (n,) rad, arc length (n,) mm) at the vertices of the closed ring ``R`` ((n, 2), not
    repeated at the end): the signed turn of the boundary there (left, around a region on the left:
    > 0)."""
    e = np.roll(R, -1, axis=0) - R                        # edge i: R[i] -> R[i + 1]
    a = np.arctan2(e[:, 1], e[:, 0])
    turn = (a - np.roll(a, 1) + np.pi) % (2 * np.pi) - np.pi     # at R[i]: from edge i - 1 to edge i
    s = np.r_[0.0, np.cumsum(np.hypot(*e.T))[:-1]]
    return turn, s


def sharp_points(allowed, min_turn_deg: float, window_mm: float) -> np.ndarray:
    """The vertices (K, 2) mm of the boundary of the tool-centre region ``allowed`` (shapely
    (Multi)Polygon) where it turns convexly (around the region) by at least ``min_turn_deg`` within
    ``window_mm`` of its length: the tool-centre places of the pocket corners sharper than the tool
    (a sharp vertex, or a fillet a little wider than the tool drawn as many small turns).

    >>> from shapely.geometry import Polygon
    >>> sharp_points(Polygon([(0, 0), (10, 0), (10, 10), (0, 10)]), 20.0, 1.0).tolist()
    [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]]
    """
    out = []
    for poly in shapely.get_parts(allowed):
        poly = orient(poly, 1.0)                       # the region on the left of every ring
        for ring in [poly.exterior, *poly.interiors]:
            R = np.asarray(ring.coords)[:-1]
            if len(R) < 3:
                continue
            turn, s = _ring_turns(R)
            L = float(s[-1] + math.hypot(*(R[0] - R[-1])))
            gap = np.abs(s[:, None] - s[None, :])
            near = np.minimum(gap, L - gap) <= 0.5 * window_mm + 1e-12
            conv = near @ np.maximum(turn, 0.0)            # the convex turning within the window
            keep = (conv >= math.radians(min_turn_deg)) & (turn > 0)
            out.extend(R[keep].tolist())
    return np.asarray(out, float).reshape(-1, 2)


class CornerCheck:
    """The exact-stock check of one level's finishing laps near the sharp corners of its tool-centre
    region. ``pocket`` (shapely, mm) the level's material outline; ``corners`` (K, 2) mm
    (:func:`sharp_points`); ``r`` tool radius mm; ``cap_deg`` the cap on the exact engagement (deg);
    ``reach_mm`` how far from a corner a lap point is measured; ``screen_deg`` only points whose
    planning engagement is at least ``cap_deg - screen_deg`` are measured."""

    def __init__(self, pocket, corners, r: float, cap_deg: float, reach_mm: float, screen_deg: float):
        self.pocket, self.corners, self.r = pocket, np.asarray(corners, float).reshape(-1, 2), float(r)
        self.cap_deg, self.reach, self.screen = float(cap_deg), float(reach_mm), math.radians(cap_deg - screen_deg)
        self.measured = 0                              # lap points measured on the exact stock (stats)
        self._swept = {}      # corner index -> ([(moves included, the last one, their discs near it)], union)

    def first_over(self, moves, z: float, P: np.ndarray, E: np.ndarray) -> int | None:
        """The index k >= 1 of the first point of the lap ``P`` ((n, 2) mm, from where the tool stands;
        ``E`` (n,) its planning engagement, rad) whose exact engagement exceeds the cap, the level
        having made the moves ``moves()`` ((m, 3) mm, asked only when a point is measured; those at
        height ``z`` cut); None if none."""
        self._moves = None
        if not len(self.corners) or len(P) < 2:
            return None
        dd = np.hypot(P[:, None, 0] - self.corners[None, :, 0], P[:, None, 1] - self.corners[None, :, 1])
        c_of, d = np.argmin(dd, axis=1), np.min(dd, axis=1)
        ask = (d <= self.reach) & (np.asarray(E) >= self.screen)
        ask[0] = False
        if not ask.any():
            return None
        idx = np.flatnonzero(ask)
        # one stretch per visit of one corner (consecutive asked points nearest to the same corner)
        for run in np.split(idx, np.flatnonzero((np.diff(idx) > 1) | (np.diff(c_of[idx]) != 0)) + 1):
            k = self._over_in(moves, z, P, int(run[0]) - 1, int(run[-1]) + 1, ask, int(c_of[run[0]]))
            if k is not None:
                return k
        return None

    def _over_in(self, moves, z, P, a, b, ask, c):
        """The first asked point of ``P[a + 1:b]`` (each within reach of corner ``c``) over the cap,
        measured from ``P[a]``; None if none."""
        if self._moves is None:
            self._moves = np.asarray(moves(), float).reshape(-1, 3)
        m = self.corners[c]
        stock = self.pocket.intersection(box(*(m - self.reach - self.r - 0.05), *(m + self.reach + self.r + 0.05)))
        for swept in (self._level_swept(c, z), _swept_at(P[:a + 1], None, m, self.reach + 2.0 * self.r + 0.05, self.r)):
            if swept is not None:
                stock = stock.difference(swept)
        eng = engagement_along(stock, P[a:b], self.r, exact_above=self.cap_deg)      # eng[j] at P[a + 1 + j]
        self.measured += int(b - a - 1)
        over = np.flatnonzero((eng > self.cap_deg) & ask[a + 1:b])
        return None if not over.size else int(a + 1 + over[0])

    def _level_swept(self, c, z):
        """The discs of the level's moves at height ``z`` near corner ``c``, cached per corner as chunks
        of moves (a chunk whose moves were rolled back is dropped; the moves added since are swept into a
        new one)."""
        M = self._moves
        chunks, union = self._swept.get(c, ([], None))
        ok = 0
        while ok < len(chunks) and chunks[ok][0] <= len(M) and tuple(M[chunks[ok][0] - 1]) == chunks[ok][1]:
            ok += 1
        if ok < len(chunks):
            chunks = chunks[:ok]
            geoms = [q[2] for q in chunks if q[2] is not None]
            union = shapely.union_all(geoms) if geoms else None
        n = chunks[-1][0] if chunks else 0
        if n < len(M):
            new = _swept_at(M[max(n - 1, 0):], z, self.corners[c], self.reach + 2.0 * self.r + 0.05, self.r)
            chunks = chunks + [(len(M), tuple(M[-1]), new)]
            union = new if union is None else (union if new is None else union.union(new))
        self._swept[c] = (chunks, union)
        return union


def _swept_at(xyz: np.ndarray, z, centre, half: float, r: float):
    """The union of the tool discs (radius ``r`` mm) along the moves ``xyz`` ((n, 3) mm, those at height
    ``z`` only; or (n, 2) with ``z`` None: all) whose points lie within ``half`` mm of ``centre`` (and the steps into and out of it); None if none."""
    xyz = np.asarray(xyz, float)
    at = np.ones(len(xyz), bool) if z is None else np.abs(xyz[:, 2] - z) < 1e-9
    xy = xyz[:, :2]
    inb = at & (np.hypot(*(xy - np.asarray(centre)).T) <= half)
    if not inb.any():
        return None
    # the points in the square and one either side of each stretch of them, at the height only
    keep = (inb | np.r_[inb[1:], False] | np.r_[False, inb[:-1]]) & at
    idx = np.flatnonzero(keep)
    parts = []
    for q in np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1):
        g = shapely.points(xy[q[0]]) if len(q) == 1 else LineString(xy[q])
        parts.append(g.buffer(r, quad_segs=64))
    return shapely.union_all(parts)
