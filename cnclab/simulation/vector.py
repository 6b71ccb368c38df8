"""Engagement measured on an exact (vector) stock at chosen samples of a planar path: the independent
check of the dixel evaluator's peaks.

The dixel models (:mod:`cnclab.simulation.dixel`, :mod:`cnclab.simulation.pixel`) see material in
dixels of side h: a wall skin or crescent thinner than a dixel row reads as contact over up to
acos(1 - h / r) on each side of the tool circle, so a peak of the evaluator's engagement can be a
sub-dixel sliver. Here the stock is polygon geometry (shapely): the pocket less the discs swept along
the path before the sample, material thinner than ``min_chip_mm`` removed (a morphological opening by
half of it), and the engagement is 180 deg times the share of the front half of the tool circle (with
respect to the step direction) that lies in that stock -- the quantity the evaluator scores. Exact up
to the circle's sampling (``n_arc`` points: 180 / (n_arc - 1) deg) and the discs' polygonisation
(``quad_segs`` segments per quarter circle: a chord sagitta of r (1 - cos(pi / (4 quad_segs)))).

Units: mm, deg.

>>> import numpy as np
>>> from shapely.geometry import box
>>> xy = np.c_[np.linspace(-10, 40, 101), np.full(101, 20 + 3 - 1.5)]   # r 3, a_e 1.5 into y < 20
>>> round(float(vector_engagement(box(0, 0, 30, 20), xy, [50], 3.0)[0]), 1)   # acos(1 - 1.5 / 3)
60.0
"""
from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import LineString, Point, box

__all__ = ["SweptDiscs", "engagement_along", "engagement_swept", "vector_engagement", "point_segment_distances"]


def _swept(xy: np.ndarray, cutting: np.ndarray, k: int, r: float, quad_segs: int):
    """Union of the tool discs (radius ``r``) swept along the steps between consecutive ``cutting``
    samples of ``xy[:k]`` that come within 2 r of ``xy[k]`` (no other disc reaches its tool circle);
    a cutting sample with no such step: its own disc. None when there is none."""
    c = xy[k]
    a, b = xy[:k - 1], xy[1:k]
    near = point_segment_distances(np.broadcast_to(c, a.shape), a, b) <= 2.0 * r + 1e-9
    step = near & cutting[:k - 1] & cutting[1:k]              # step i: xy[i] -> xy[i + 1]
    parts = []
    idx = np.flatnonzero(step)
    if idx.size:
        for run in np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1):
            parts.append(LineString(xy[run[0]:run[-1] + 2]).buffer(r, quad_segs=quad_segs))
    lone = cutting[:k] & (np.hypot(*(xy[:k] - c).T) <= 2.0 * r)
    lone[np.r_[idx, idx + 1].astype(int)] = False
    parts += [Point(xy[i]).buffer(r, quad_segs=quad_segs) for i in np.flatnonzero(lone)]
    return shapely.union_all(parts) if parts else None


def vector_engagement(polygon, xy, at, tool_radius: float, cutting=None, min_chip_mm: float = 0.002,
                      n_arc: int = 3601, quad_segs: int = 64) -> np.ndarray:
    """Engagement angle (deg) at the samples ``at`` of the tool-centre path ``xy`` ((N, 2), mm) of a
    flat end mill of radius ``tool_radius`` (mm) cutting the stock ``polygon`` (shapely, mm; holes are
    islands): 180 deg times the share of the front half of the tool circle at ``xy[k]`` (front: the
    step ``xy[k] - xy[k-1]``) inside the stock the discs along ``xy[:k]`` left, material thinner than
    ``min_chip_mm`` (default 2 um) not counted. ``cutting`` ((N,) bool, default all): the samples
    whose discs cut (e.g. those at the level's depth); the discs are swept along runs of consecutive
    cutting samples, so a jump between runs (a lift) cuts nothing.

    >>> from shapely.geometry import box
    >>> xy = np.c_[np.linspace(-5, 25, 61), np.full(61, 5.0)]          # a full-width slot, r 2
    >>> vector_engagement(box(0, 0, 20, 10), xy, [30], 2.0).round(1).tolist()
    [180.0]
    """
    xy = np.asarray(xy, float)
    if xy.ndim != 2 or xy.shape[1] != 2 or len(xy) < 2:
        raise ValueError(f"xy must be an (N, 2) array of tool-centre points (mm), N >= 2; got shape {xy.shape}")
    r = float(tool_radius)
    if not (np.isfinite(r) and r > 0):
        raise ValueError(f"tool_radius must be a finite number > 0 mm, got {tool_radius!r}")
    if not (min_chip_mm >= 0 and n_arc >= 3):
        raise ValueError(f"min_chip_mm must be >= 0 mm and n_arc >= 3, got {min_chip_mm!r}, {n_arc!r}")
    cut = np.ones(len(xy), bool) if cutting is None else np.asarray(cutting, bool)
    if cut.shape != (len(xy),):
        raise ValueError(f"cutting must have one flag per point ({len(xy)}), got shape {cut.shape}")
    out = []
    for k in np.atleast_1d(np.asarray(at, int)):
        if not 1 <= k < len(xy):
            raise ValueError(f"sample {k} has no step before it (1 <= k < {len(xy)})")
        d = xy[k] - xy[k - 1]
        if not np.hypot(*d) > 0:
            raise ValueError(f"sample {k}: no step direction (xy[{k}] == xy[{k - 1}])")
        swept = _swept(xy, cut, k, r, quad_segs)
        near = polygon.intersection(box(*(xy[k] - 2.0 * r), *(xy[k] + 2.0 * r)))     # the rest is r and more away
        stock = near if swept is None else near.difference(swept)
        if min_chip_mm > 0 and not stock.is_empty:
            stock = stock.buffer(-0.5 * min_chip_mm, quad_segs=quad_segs).buffer(0.5 * min_chip_mm, quad_segs=quad_segs)
        phi = np.arctan2(d[1], d[0]) + np.linspace(-0.5 * np.pi, 0.5 * np.pi, n_arc)
        rim = shapely.points(xy[k, 0] + r * np.cos(phi), xy[k, 1] + r * np.sin(phi))
        inside = np.zeros(n_arc, bool) if stock.is_empty else shapely.contains(stock, rim)
        out.append(180.0 * float(inside.mean()))
    return np.asarray(out)


def engagement_along(stock, path, tool_radius: float, min_chip_mm: float = 0.002, n_arc: int = 361,
                     quad_segs: int = 64) -> np.ndarray:
    """Engagement angle (deg) at each point ``path[1:]`` of a flat end mill of radius ``tool_radius``
    (mm) moving along ``path`` ((n, 2) mm, from where the tool stands) through the vector ``stock``
    (shapely geometry, mm: the material there before the move), which it cuts as it goes: at
    ``path[k]``, 180 deg times the share of the front half of the tool circle (front: the step
    ``path[k] - path[k-1]``) inside the stock less the discs swept along ``path[:k]`` (the disc at
    ``path[0]`` included), material
    thinner than ``min_chip_mm`` (default 2 um) not counted; ``n_arc`` points on the half circle
    (180 / (n_arc - 1) deg apart). Zero-length steps read 0. The polygon counterpart of
    :func:`engagement_swept` for one run of moves (its reference in the tests).

    >>> from shapely.geometry import box
    >>> xy = np.c_[np.linspace(-5, 25, 61), np.full(61, 5.0)]           # a full-width slot, r 2
    >>> float(engagement_along(box(0, 0, 20, 10), xy, 2.0)[30])
    180.0
    """
    P = np.asarray(path, float)
    if P.ndim != 2 or P.shape[1] != 2:
        raise ValueError(f"path must be an (n, 2) array of tool-centre points (mm); got shape {P.shape}")
    r = float(tool_radius)
    if not (np.isfinite(r) and r > 0):
        raise ValueError(f"tool_radius must be a finite number > 0 mm, got {tool_radius!r}")
    out = np.zeros(max(len(P) - 1, 0))
    half = np.linspace(-0.5 * np.pi, 0.5 * np.pi, n_arc)
    if len(P):
        stock = stock.difference(Point(P[0]).buffer(r, quad_segs=quad_segs))      # where the tool stands
    for k in range(1, len(P)):
        d = P[k] - P[k - 1]
        if k > 1:
            stock = stock.difference(LineString(P[k - 2:k]).buffer(r, quad_segs=quad_segs))
        if not np.hypot(*d) > 0 or stock.is_empty:
            continue
        near = stock.intersection(box(*(P[k] - r - 0.01), *(P[k] + r + 0.01)))
        if near.is_empty:
            continue
        phi = np.arctan2(d[1], d[0]) + half
        rim = shapely.points(P[k, 0] + r * np.cos(phi), P[k, 1] + r * np.sin(phi))
        if min_chip_mm > 0:
            near = near.buffer(-0.5 * min_chip_mm, quad_segs=quad_segs).buffer(0.5 * min_chip_mm, quad_segs=quad_segs)
        out[k - 1] = 0.0 if near.is_empty else 180.0 * float(shapely.contains(near, rim).mean())
    return out


class SweptDiscs:
    """The region a disc of radius ``r`` (mm) swept along polylines, asked point by point: the distance
    (mm) from points to the nearest swept segment (a point lies in the swept region when it is at
    most r). Segments are split into pieces of at most ``piece_mm``; the pieces are indexed in a k-d
    tree of their midpoints (rebuilt once ``tail`` newer pieces have gathered, which are searched
    directly: :meth:`_index`), so a query costs about two nearest-neighbour searches. Each piece keeps the tag it was
    added with (e.g. a move index), and :meth:`truncate` drops the pieces from a tag on (a planner's
    rollback).

    >>> s = SweptDiscs(2.0)
    >>> s.add([[0.0, 0.0], [10.0, 0.0]], tag=0)
    >>> s.distance(np.array([[5.0, 3.0], [-3.0, 4.0], [5.0, 0.0]])).round(6).tolist()
    [3.0, 5.0, 0.0]
    """

    def __init__(self, r: float, piece_mm: float = 0.1, tail: int = 256):
        self.r, self.piece, self.tail_max = float(r), float(piece_mm), int(tail)
        self._A, self._B, self._tag = np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0, np.int64)
        self._new = []                     # pieces added since the arrays were last joined
        self._tree, self._n_tree = None, 0          # the large tree: pieces [0, _n_tree)
        self._small, self._n_small = None, 0        # the small one: [_n_tree, _n_small); then the tail

    def _join(self):
        if self._new:
            self._A = np.vstack([self._A, *[q[0] for q in self._new]])
            self._B = np.vstack([self._B, *[q[1] for q in self._new]])
            self._tag = np.concatenate([self._tag, *[q[2] for q in self._new]])
            self._new = []

    @property
    def A(self) -> np.ndarray:
        """(m, 2) mm: the pieces' start points."""
        self._join()
        return self._A

    @property
    def B(self) -> np.ndarray:
        """(m, 2) mm: the pieces' end points."""
        self._join()
        return self._B

    @property
    def tag(self) -> np.ndarray:
        """(m,) the pieces' tags."""
        self._join()
        return self._tag

    def __len__(self) -> int:
        return len(self.A)

    def add(self, xy, tag=0) -> None:
        """The segments of the polyline ``xy`` ((n, 2) mm; one point: a disc there), tagged ``tag``
        (one tag, or one per segment, increasing)."""
        P = np.asarray(xy, float).reshape(-1, 2)
        if len(P) == 1:
            P = np.vstack([P, P])
        a, b = P[:-1], P[1:]
        tags = np.broadcast_to(np.asarray(tag, np.int64), (len(a),))
        m = np.maximum(np.ceil(np.hypot(*(b - a).T) / self.piece).astype(int), 1)
        k = np.repeat(np.arange(len(a)), m)
        t0 = (np.arange(len(k)) - np.repeat(np.cumsum(m) - m, m)) / np.repeat(m, m)
        t1 = t0 + 1.0 / np.repeat(m, m)
        d = (b - a)[k]
        self._new.append((a[k] + t0[:, None] * d, a[k] + t1[:, None] * d, tags[k]))

    def truncate(self, tag: int) -> None:
        """Drop the pieces tagged ``tag`` or later (tags are added in increasing order)."""
        keep = int(np.searchsorted(self.tag, tag, side="left"))
        self._A, self._B, self._tag = self._A[:keep], self._B[:keep], self._tag[:keep]
        if keep < self._n_tree:
            self._tree, self._n_tree = None, 0
        if keep < self._n_small:
            self._small, self._n_small = None, self._n_tree

    def _index(self) -> None:
        """Index the pieces: a large k-d tree, a small one over the pieces added since it was built
        (rebuilt every ``tail`` pieces; the large one once the small holds 16 ``tail``), the newest
        pieces (fewer than ``tail``) searched directly."""
        from scipy.spatial import cKDTree

        n = len(self.A)
        if n - self._n_small <= self.tail_max:
            return
        if n - self._n_tree > 16 * self.tail_max:
            self._tree, self._n_tree = cKDTree(0.5 * (self.A + self.B)), n
            self._small, self._n_small = None, n
        else:
            k = self._n_tree
            self._small, self._n_small = cKDTree(0.5 * (self.A[k:] + self.B[k:])), n

    def distance(self, pts: np.ndarray, cap: float = np.inf, loose_below: float = -np.inf) -> np.ndarray:
        """(n,) mm: the distance from each point of ``pts`` ((n, 2) mm) to the nearest piece, or ``cap``
        where that is farther (inf: no cap; inf where there is no piece). A distance at most
        ``loose_below`` may be returned as an upper bound that is itself at most ``loose_below`` (a
        caller asking only "within r?" passes r: fewer exact searches)."""
        pts = np.asarray(pts, float).reshape(-1, 2)
        self._index()
        A, B = self.A[self._n_small:], self.B[self._n_small:]
        if np.isfinite(cap) and len(A) and len(pts):
            lo, hi = pts.min(axis=0) - cap, pts.max(axis=0) + cap
            near = np.all((np.minimum(A, B) <= hi) & (np.maximum(A, B) >= lo), axis=1)
            A, B = A[near], B[near]
        out = np.minimum(_seg_dist_min(pts, A, B), cap)
        for tree, off in ((self._tree, 0), (self._small, self._n_tree)):
            if tree is not None:
                out = self._tree_min(tree, off, pts, out, cap, loose_below)
        return out

    def _tree_min(self, tree, off, pts, out, cap, loose_below):
        """``out`` lowered to the distances to the pieces of ``tree`` (its pieces from ``off`` on)."""
        dm, _ = tree.query(pts, k=1, distance_upper_bound=cap + 0.5 * self.piece)
        # the nearest piece's midpoint lies within (its distance + half a piece) of the point
        rad = np.minimum(dm, out) + 0.5 * self.piece + 1e-9
        out = np.minimum(out, dm)
        ask = np.isfinite(rad) & (out > loose_below)
        if ask.any():
            lists = tree.query_ball_point(pts[ask], rad[ask])
            lens = np.fromiter((len(q) for q in lists), int, len(lists))
            if lens.sum():
                who = np.flatnonzero(ask)[np.repeat(np.arange(len(lists)), lens)]
                seg = off + np.concatenate([np.asarray(q, int) for q in lists if len(q)])
                np.minimum.at(out, who, point_segment_distances(pts[who], self.A[seg], self.B[seg]))
        return out


def point_segment_distances(p, a, b):
    """Distances (n,) from the points p to the segments a -> b (row by row; p may be one point), mm.

    >>> point_segment_distances(np.array([1.0, 1.0]), np.array([[0.0, 0], [2, 0]]), np.array([[2.0, 0], [2, 0]])).tolist()
    [1.0, 1.4142135623730951]
    """
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300), 0.0, 1.0)
    return np.hypot(*(a + t[:, None] * ab - p).T)


def _seg_dist_min(pts, A, B, chunk: int = 2_000_000):
    """(n,) the distance from each point to the nearest of the segments A -> B (brute force; inf if none)."""
    out = np.full(len(pts), np.inf)
    if not len(A) or not len(pts):
        return out
    step = max(1, chunk // len(A))
    ab = B - A
    L2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    for i in range(0, len(pts), step):
        p = pts[i:i + step, None, :]
        t = np.clip(np.einsum("nmj,mj->nm", p - A[None], ab) / L2, 0.0, 1.0)
        out[i:i + step] = np.min(np.hypot(*(A[None] + t[..., None] * ab[None] - p).transpose(2, 0, 1)), axis=1)
    return out


def engagement_swept(pocket, swept: SweptDiscs, path, min_chip_mm: float = 0.002, n_arc: int = 361,
                     lead=None, wall=None) -> np.ndarray:
    """Engagement angle (deg) at each point ``path[1:]`` of a flat end mill (radius ``swept.r`` mm)
    moving along ``path`` ((n, 2) mm, from where the tool stands) through the material of ``pocket``
    (shapely, mm) less the region ``swept`` (:class:`SweptDiscs`, the moves before) and less its own
    discs along ``path[:k]``: 180 deg times the share of the front half of the tool circle in that
    stock, material thinner than ``min_chip_mm`` not counted (a rim point counts when some point
    within ``min_chip_mm`` / 2 of it carries a disc of that radius inside the stock: the opening of
    :func:`vector_engagement`, tested on 8 directions). The point-wise counterpart of
    :func:`engagement_along` (no polygon booleans: for long levels; the planner's corner check).
    ``lead`` ((m, 2) mm): moves before ``path`` not in ``swept`` (swept too). ``wall``:
    ``pocket.boundary``, when the caller has it.

    >>> from shapely.geometry import box
    >>> xy = np.c_[np.linspace(-10, 40, 101), np.full(101, 20 + 3 - 1.5)]   # r 3, a_e 1.5
    >>> s = SweptDiscs(3.0)
    >>> round(float(engagement_swept(box(0, 0, 30, 20), s, xy)[50]), 1)   # acos(1 - 1.5 / 3) = 60 on 361 points
    59.8
    """
    P = np.asarray(path, float).reshape(-1, 2)
    r, dl = swept.r, 0.5 * float(min_chip_mm)
    own = SweptDiscs(r, swept.piece)
    if lead is not None and len(lead):
        own.add(lead)
    if len(P):
        own.add(P[:1])
    half = np.linspace(-0.5 * np.pi, 0.5 * np.pi, n_arc)
    wall = pocket.boundary if wall is None else wall
    shapely.prepare(pocket)
    shapely.prepare(wall)
    out = np.zeros(max(len(P) - 1, 0))
    for k in range(1, len(P)):
        if k > 1:
            own.add(P[k - 2:k])
        d = P[k] - P[k - 1]
        if not np.hypot(*d) > 0:
            continue
        phi = np.arctan2(d[1], d[0]) + half
        rim = P[k] + r * np.c_[np.cos(phi), np.sin(phi)]
        ok = _in_stock(pocket, wall, swept, own, rim, r, dl)
        out[k - 1] = 180.0 * float(ok.mean())
    return out


def _in_stock(pocket, wall, swept, own, pts, r, dl):
    """(n,) bool: the points ``pts`` inside the stock (the pocket less both sweeps) opened by ``dl``."""
    inside = shapely.contains_xy(pocket, pts[:, 0], pts[:, 1])
    cap = r + 4.0 * dl + 1e-6        # nearer or farther than r + 2 dl is all the test asks
    ds = np.minimum(swept.distance(pts, cap, r), own.distance(pts, cap, r)) - r
    ok = inside & (ds > 0)
    if dl <= 0 or not ok.any():
        return ok
    thin = np.zeros(len(pts), bool)
    thin[np.flatnonzero(ok)] = (ds[ok] < dl) | shapely.dwithin(wall, shapely.points(pts[ok]), dl)
    for i in np.flatnonzero(thin):
        q = pts[i] + dl * _OPENING_STEPS
        dq = np.minimum(swept.distance(q, cap, r), own.distance(q, cap, r)) - r
        wq = shapely.distance(wall, shapely.points(q))
        iq = shapely.contains_xy(pocket, q[:, 0], q[:, 1])
        ok[i] = bool(np.any(iq & (dq >= dl) & (wq >= dl)))
    return ok


#: the offsets (9, 2) of the opening test of :func:`engagement_swept`: the point itself and 8 directions
_OPENING_STEPS = np.vstack([[0.0, 0.0], np.c_[np.cos(np.arange(8) * np.pi / 4), np.sin(np.arange(8) * np.pi / 4)]])
