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

__all__ = ["engagement_along", "vector_engagement"]


def _swept(xy: np.ndarray, cutting: np.ndarray, k: int, r: float, quad_segs: int):
    """Union of the tool discs (radius ``r``) swept along the steps between consecutive ``cutting``
    samples of ``xy[:k]`` that come within 2 r of ``xy[k]`` (no other disc reaches its tool circle);
    a cutting sample with no such step: its own disc. None when there is none."""
    c = xy[k]
    a, b = xy[:k - 1], xy[1:k]
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", c - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300), 0.0, 1.0)
    near = np.hypot(*(a + t[:, None] * ab - c).T) <= 2.0 * r + 1e-9
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
                     quad_segs: int = 64, exact_above: float = 0.0) -> np.ndarray:
    """Engagement angle (deg) at each point ``path[1:]`` of a flat end mill of radius ``tool_radius``
    (mm) moving along ``path`` ((n, 2) mm, from where the tool stands) through the vector ``stock``
    (shapely geometry, mm: the material there before the move), which it cuts as it goes: at
    ``path[k]``, 180 deg times the share of the front half of the tool circle (front: the step
    ``path[k] - path[k-1]``) inside the stock less the discs swept along ``path[:k]`` (the disc at
    ``path[0]`` included), material
    thinner than ``min_chip_mm`` (default 2 um) not counted; ``n_arc`` points on the half circle
    (180 / (n_arc - 1) deg apart). Zero-length steps read 0. The local counterpart of
    :func:`vector_engagement` for one run of moves (a planner checking a stretch before it keeps it). ``exact_above``
    (deg): a point whose engagement with no material discounted is at most this keeps that value, an
    upper bound (the thin material is sought only above it: a check against a cap is exact and
    cheaper).

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
        out[k - 1] = 180.0 * float(shapely.contains(near, rim).mean())
        if min_chip_mm > 0 and out[k - 1] > exact_above:
            near = near.buffer(-0.5 * min_chip_mm, quad_segs=quad_segs).buffer(0.5 * min_chip_mm, quad_segs=quad_segs)
            out[k - 1] = 0.0 if near.is_empty else 180.0 * float(shapely.contains(near, rim).mean())
    return out
