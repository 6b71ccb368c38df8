"""The passes and finishing laps checked on the exact stock where the tool-centre limit turns sharply
(a pocket corner the tool cannot fill): :func:`sharp_points`, :class:`CornerCheck`.

At a convex vertex of the tool-centre region (a pocket corner sharper than the tool) the rim of a
tool that moves into the corner meets the corner's rest over up to the angle the limit turns there
(90 deg in a square corner), however thin that rest is: a chip of 10 um still counts (contact: chips
of 2 um and more). The planning stock (pixels of side h) reads a rest thinner than a pixel as a
fraction of material, so the short passes that took a corner micrometres at a time read within the
target where the exact stock reads theta + 13 deg (corpus jobs rectilinear_1 and comb_1,
``benchmarks/bench_vector_audit.py``). Every pass and lap point within reach of such a corner whose
planning engagement comes near the cap is therefore measured on the exact stock -- the pocket less
the discs of every move the level made at depth (:class:`cnclab.simulation.vector.SweptDiscs`,
:func:`cnclab.simulation.vector.engagement_swept`) -- and a pass ends before the first point above
``theta + corner_exact_cap_deg`` (the planner's ``corner_trim``); a finishing lap goes on past the
corner along the chord across it (``finish._corner_cut``). The rest in the corner stays (the
evaluator counts it as uncut).

Units: mm, deg at the API (the planning engagement ``E`` in rad).
"""
from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.geometry.polygon import orient

from ...simulation.vector import SweptDiscs, engagement_swept

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
            keep = (_window_sum(np.maximum(turn, 0.0), s, float(s[-1] + math.hypot(*(R[0] - R[-1]))),
                                0.5 * window_mm) >= math.radians(min_turn_deg)) & (turn > 0)
            out.extend(R[keep].tolist())
    return np.asarray(out, float).reshape(-1, 2)


def _window_sum(v: np.ndarray, s: np.ndarray, L: float, half: float) -> np.ndarray:
    """(n,) the sum of ``v`` over the vertices within ``half`` (mm of arc length) of each vertex of a
    closed ring of length ``L`` (``s`` (n,) increasing arc lengths from 0): cumulative sums over the
    ring laid out three times, so memory and time grow with n, not n^2.

    >>> _window_sum(np.array([1.0, 2.0, 4.0, 8.0]), np.array([0.0, 1.0, 2.0, 3.0]), 4.0, 1.0).tolist()
    [11.0, 7.0, 14.0, 13.0]
    """
    if 2.0 * half >= L:
        return np.full(len(v), float(v.sum()))          # the window holds the whole ring (each vertex once)
    s3 = np.r_[s - L, s, s + L]
    c = np.r_[0.0, np.cumsum(np.r_[v, v, v])]
    lo = np.searchsorted(s3, s - half - 1e-12, side="left")
    hi = np.searchsorted(s3, s + half + 1e-12, side="right")
    return c[hi] - c[lo]


class CornerCheck:
    """The exact-stock check of one level's passes and finishing laps near the sharp corners of its
    tool-centre region. ``pocket`` (shapely, mm) the level's material outline; ``corners`` (K, 2) mm
    (:func:`sharp_points`); ``r`` tool radius mm; ``cap_deg`` the cap on the exact engagement (deg);
    ``reach_mm`` how far from a corner a point is measured; ``screen_deg`` only points whose planning
    engagement is at least ``cap_deg - screen_deg`` are measured. The level's moves at its height are
    kept as a :class:`cnclab.simulation.vector.SweptDiscs`, synchronised with the builder before each
    check (moves rolled back are dropped)."""

    def __init__(self, pocket, corners, r: float, cap_deg: float, reach_mm: float, screen_deg: float):
        self.pocket, self.corners, self.r = pocket, np.asarray(corners, float).reshape(-1, 2), float(r)
        self.cap_deg, self.reach, self.screen = float(cap_deg), float(reach_mm), math.radians(cap_deg - screen_deg)
        self.measured = 0                              # points measured on the exact stock (stats)
        self.sweep = SweptDiscs(self.r)
        self._wall = pocket.boundary                   # made once (engagement_swept asks it at every point)
        self._seen = np.zeros((0, 3))                  # the level's moves the sweep holds

    def first_over(self, builder, mark0: int, z: float, P: np.ndarray, E: np.ndarray) -> int | None:
        """The index k >= 1 of the first point of the stretch ``P`` ((n, 2) mm, from where the tool
        stands; ``E`` (n,) its planning engagement, rad) whose exact engagement exceeds the cap, the
        level having made the moves of ``builder`` since its mark ``mark0`` (those at height ``z``
        cut); None if none."""
        if not len(self.corners) or len(P) < 2:
            return None
        dd = np.hypot(P[:, None, 0] - self.corners[None, :, 0], P[:, None, 1] - self.corners[None, :, 1])
        ask = (np.min(dd, axis=1) <= self.reach) & (np.asarray(E) >= self.screen)
        ask[0] = False
        if not ask.any():
            return None
        self._sync(builder, mark0, z)
        idx = np.flatnonzero(ask)
        for run in np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1):      # one stretch per corner visit
            a, b = int(run[0]) - 1, int(run[-1]) + 1
            eng = engagement_swept(self.pocket, self.sweep, P[a:b], lead=P[:a + 1], wall=self._wall)  # eng[j] at P[a + 1 + j]
            self.measured += b - a - 1
            over = np.flatnonzero((eng > self.cap_deg) & ask[a + 1:b])
            if over.size:
                return int(a + 1 + over[0])
        return None

    def past_corner(self, P: np.ndarray, k: int) -> int | None:
        """The index of the first point of ``P`` after ``k`` beyond the reach of the corner nearest to
        ``P[k]`` (where a lap can go on past that corner), or None if the stretch ends first."""
        c = self.corners[np.argmin(np.hypot(*(self.corners - P[k]).T))]
        far = np.flatnonzero(np.hypot(*(P[k + 1:] - c).T) > self.reach)
        return None if not far.size else int(k + 1 + far[0])

    def _sync(self, builder, mark0, z):
        """Bring the sweep up to the builder's moves since ``mark0``: the moves added since the last
        check swept in; where moves were rolled back, the sweep cut back to the first changed one."""
        n = len(self._seen)
        if len(builder) - mark0 >= n and n:
            head = builder.tail(mark0 + n - 1)[0]
            if np.array_equal(head[0], self._seen[-1]):
                self._add(np.vstack([self._seen[-1:], head[1:]]), n - 1, z)
                self._seen = np.vstack([self._seen, head[1:]])
                return
        M = builder.tail(mark0)[0]
        m = min(len(M), n)
        diff = np.flatnonzero(np.any(M[:m] != self._seen[:m], axis=1))
        j = int(diff[0]) if diff.size else m          # the first move that changed (or the old end)
        self.sweep.truncate(j)
        self._add(M[max(j - 1, 0):], max(j - 1, 0), z)
        self._seen = M.copy()

    def _add(self, xyz, i0, z):
        """Sweep the moves ``xyz`` (move i0 first; the segment into move i is tagged i) that run at height z."""
        at = np.abs(xyz[:, 2] - z) < 1e-9
        if not at.any():
            return
        idx = np.flatnonzero(at)
        for run in np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1):
            if len(run) == 1:
                if run[0] == 0 and i0 > 0:
                    continue                       # the joint move, swept with the run before
                self.sweep.add(xyz[run, :2], tag=i0 + int(run[0]))
            else:
                self.sweep.add(xyz[run, :2], tag=i0 + run[1:])     # the segment into move i tagged i
