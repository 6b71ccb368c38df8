"""Planar zig-zag (raster) tool paths — Hoang (2024) Table 1, and a general covering raster.

Passes run along +X / −X (``length`` [mm]) and step along +Y by the stepover ``S_z`` [mm] until the
``width`` [mm] is covered. Points are cutter-contact (CC) points in the XY plane; the programs built by
:func:`zigzag_path` put them at a cutting height ``z_cut`` [mm] with a plunge from and a retract to
``z_clear`` [mm], ending with a rapid back to the start above the part.

* :func:`hoang_table1_points` transcribes Table 1 literally (MATLAB ``for i = 1:n/2`` with
  ``n = Width/S_z + S_z/2``: ``floor(n/2)`` iterations of pass, stepover, pass, stepover).
* :func:`zigzag_points` covers the width: the last pass lies at ``y ≥ y0 + width`` (the paper's
  Fig. 9 "N107 X100 Y50.744" end-of-field fix), optionally with CC points every ``forward_step`` mm.

>>> p = zigzag_points((0, 0), width=2.0, length=10.0, stepover=1.0)
>>> p.tolist()
[[0.0, 0.0], [10.0, 0.0], [10.0, 1.0], [0.0, 1.0], [0.0, 2.0], [10.0, 2.0]]
"""
from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.geometry import LineString
from shapely.ops import substring

from .path import ToolPath, ToolPathBuilder

__all__ = ["hoang_table1_points", "zigzag_points", "zigzag_path", "n_passes_covering", "raster_lines", "cell_order",
           "raster_passes"]


def _positive(name, v):
    if not (isinstance(v, (int, float, np.floating, np.integer)) and math.isfinite(v) and v > 0):
        raise ValueError(f"{name} must be a finite number > 0 (mm), got {v!r}")
    return float(v)


def hoang_table1_points(x: float, y: float, width: float, length: float, stepover: float,
                        forward_step: float) -> np.ndarray:
    """Table 1 of Hoang (2024) executed as printed; returns the (k, 2) XY points [mm] of ``temp``.

    ``n = Width/S_z + S_z/2``, ``m = Long/F_r``; ``for i = 1:n/2`` runs ``floor(n/2)`` times (MATLAB
    colon semantics), each iteration appending a +X pass of ``F_r·m`` (= Long), a stepover, a −X pass
    and a stepover (so the path ends with a stepover after the last pass).
    """
    width, length = _positive("width", width), _positive("length", length)
    sz, fr = _positive("stepover", stepover), _positive("forward_step", forward_step)
    n = width / sz + sz / 2.0          # line 7, as printed
    m = length / fr                    # line 8
    temp = [(x, y)]
    for _ in range(int(math.floor(n / 2.0))):   # MATLAB 1:n/2 -> 1..floor(n/2)
        x = x + fr * m
        temp.append((x, y))
        y = y + sz
        temp.append((x, y))
        x = x - fr * m
        temp.append((x, y))
        y = y + sz
        temp.append((x, y))
    return np.array(temp, dtype=float)


def n_passes_covering(width: float, stepover: float) -> int:
    """Number of passes so that the last one lies at or beyond ``width`` mm: ``ceil(width/S_z) + 1``.

    >>> n_passes_covering(50.0, 0.994987)
    52
    """
    width, sz = _positive("width", width), _positive("stepover", stepover)
    return int(math.ceil(width / sz - 1e-12)) + 1


def zigzag_points(start, width: float, length: float, stepover: float, forward_step: float | None = None,
                  n_passes: int | None = None) -> np.ndarray:
    """Zig-zag CC points [mm], (k, 2): passes along X of ``length``, stepping ``stepover`` along +Y.

    ``n_passes`` defaults to :func:`n_passes_covering`; with ``forward_step`` [mm] each pass carries
    CC points every ``forward_step`` (the last interval may be shorter), else only its two ends.
    The passes are those of :func:`raster_passes` on the rectangle ``length`` x ``(n_passes - 1)
    stepover`` (last pass on its far edge), concatenated (the stepovers are the straight links).
    """
    x0, y0 = (float(v) for v in start)
    width, length = _positive("width", width), _positive("length", length)
    sz = _positive("stepover", stepover)
    if n_passes is None:
        n_passes = n_passes_covering(width, sz)
    if int(n_passes) != n_passes or n_passes < 1:
        raise ValueError(f"n_passes must be an int >= 1, got {n_passes!r}")
    rect = (x0, x0 + length, y0, y0 + (int(n_passes) - 1) * sz)
    step = None if forward_step is None else _positive("forward_step", forward_step)
    return np.vstack(raster_passes(rect, sz, last="edge", step=step, sampling="fixed"))


def zigzag_path(points, z_cut: float, z_clear: float, feed: float, spindle: float | None = None,
                plunge_feed: float | None = None, return_home: bool = True, tool=None) -> ToolPath:
    """The tool path of XY ``points`` [mm]: rapid above the first point at ``z_clear``, plunge to
    ``z_cut`` (at ``plunge_feed``, default ``feed`` [mm/min]), cuts through the points, retract to
    ``z_clear`` at ``feed``, and (``return_home``) a rapid back above the first point.

    >>> zigzag_path([[0, 0], [10, 0]], z_cut=0, z_clear=10, feed=500).kinds().tolist()
    ['rapid', 'plunge', 'cut', 'retract', 'rapid']
    """
    p = np.asarray(points, float)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 2:
        raise ValueError(f"points must have shape (k >= 2, 2), got {p.shape}")
    if not z_clear > z_cut:
        raise ValueError(f"z_clear must be above z_cut (mm), got z_clear={z_clear}, z_cut={z_cut}")
    b = ToolPathBuilder(tool=tool, spindle=spindle, info={"name": "zig-zag"})
    z_clear, z_cut = float(z_clear) + 0.0, float(z_cut) + 0.0               # no -0.0 in the program
    b.rapid(p[:1], z=z_clear)
    b.plunge(p[0], z_cut, feed if plunge_feed is None else plunge_feed)
    b.cut(p, feed, z=z_cut)
    b.retract(z_clear, feed)
    if return_home:
        b.rapid(p[:1], z=z_clear)
    return b.build(drop_repeats=True)                       # the plunge lands on points[0]


def raster_lines(region, stepover: float, min_length: float = 1e-6) -> list[np.ndarray]:
    """Zig-zag raster over a shapely (Multi)Polygon ``region`` (mm): lines along x every ``stepover``
    mm in y from the bottom (+1e-6 mm), clipped to the region (pieces shorter than ``min_length`` mm
    dropped), alternate lines reversed; list of (2, 2) arrays (:func:`raster_passes` at 0 deg).

    >>> from shapely.geometry import box
    >>> [q.round(6).tolist() for q in raster_lines(box(0, 0, 10, 2), 1.0)]
    [[[0.0, 1e-06], [10.0, 1e-06]], [[10.0, 1.000001], [0.0, 1.000001]]]
    """
    return raster_passes(region, stepover, start_offset_mm=1e-6, min_length=min_length)


def _rect_clip(p0, u, rect, tol=1e-9):
    """Parameter range (tmin, tmax) of the line ``p0 + t u`` inside the rectangle (x0, x1, y0, y1)."""
    x0, x1, y0, y1 = rect
    tmin, tmax = -np.inf, np.inf
    for ax, lo, hi in ((0, x0, x1), (1, y0, y1)):
        if abs(u[ax]) < 1e-12:
            if not (lo - tol <= p0[ax] <= hi + tol):
                return 1.0, 0.0
            continue
        ta, tb = (lo - p0[ax]) / u[ax], (hi - p0[ax]) / u[ax]
        tmin, tmax = max(tmin, min(ta, tb)), min(tmax, max(ta, tb))
    return tmin, tmax


def _sample(a, b, step, sampling):
    """Parameters from a to b: ends only (step None), ``ceil((b-a)/step)`` even intervals
    (``"even"``) or every ``step`` from a with a shorter last interval (``"fixed"``)."""
    if step is None:
        return np.array([a, b])
    if sampling == "even":
        return np.linspace(a, b, int(np.ceil((b - a) / step)) + 1)
    t = np.append(a + np.arange(0.0, b - a, step), b)
    return t[np.r_[True, np.diff(t) > 1e-12]]


def raster_passes(region, stepover: float, angle_deg: float = 0.0, *, start_offset_mm: float = 0.0,
                  last: str = "inside", step: float | None = None, sampling: str = "even",
                  min_length: float = 0.0, links: bool = False) -> list[np.ndarray]:
    """The zig-zag raster of the collection: passes (list of (M, 2) arrays, mm) covering ``region``.

    Passes run along u = (cos A, sin A) (``angle_deg`` A from +x), on lines spaced ``stepover`` mm
    along v = (-sin A, cos A) from the region's lowest v plus ``start_offset_mm``; consecutive
    non-empty lines alternate direction (the first runs along +u).

    Parameters
    ----------
    region : shapely (Multi)Polygon (lines clipped to it; a line crossing it several times gives one
        pass per piece, ordered along +u, each reversed on reversed lines), or a rectangle
        ``(x0, x1, y0, y1)`` (mm, clipped analytically, points clamped into it).
    stepover : line spacing a_e (mm).
    last : ``"inside"``: lines strictly below the highest v; ``"edge"``: lines up to the highest v
        inclusive, plus one on it when the spacing misses it by more than 1e-9 mm.
    step : sampling step (mm) of passes and links; None: pass ends only.
    sampling : ``"even"`` (``ceil(L/step)`` equal intervals) or ``"fixed"`` (every ``step`` from the
        pass start, shorter last interval).
    min_length : pieces not longer than this (mm) are dropped.
    links : append to each pass the interior points (every ``step``) of the straight link to the
        next pass (for a convex region it stays inside), so the concatenated passes are the path.

    >>> [q.tolist() for q in raster_passes((0, 4, 0, 2), 1.0, last="edge")]
    [[[0.0, 0.0], [4.0, 0.0]], [[4.0, 1.0], [0.0, 1.0]], [[0.0, 2.0], [4.0, 2.0]]]
    """
    sz = _positive("stepover", stepover)
    if step is not None:
        step = _positive("step", step)
    if last not in ("inside", "edge"):
        raise ValueError(f"last must be 'inside' or 'edge', got {last!r}")
    if sampling not in ("even", "fixed"):
        raise ValueError(f"sampling must be 'even' or 'fixed', got {sampling!r}")
    A = np.radians(angle_deg)
    u = np.array([np.cos(A), np.sin(A)])
    v = np.array([-np.sin(A), np.cos(A)])
    rect = None
    if isinstance(region, (tuple, list, np.ndarray)):
        rect = tuple(map(float, region))
        if len(rect) != 4 or not (rect[0] <= rect[1] and rect[2] <= rect[3]):
            raise ValueError(f"region rectangle must be (x0, x1, y0, y1) with x0 <= x1, y0 <= y1 (mm), got {region!r}")
        x0, x1, y0, y1 = rect
        coords = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    else:
        coords = shapely.get_coordinates(region)
        if region.is_empty:
            return []
    cv, cu = coords @ v, coords @ u
    if last == "edge":
        offs = np.arange(cv.min() + start_offset_mm, cv.max() + 1e-9, sz)
        if offs.size == 0 or cv.max() - offs[-1] > 1e-9:
            offs = np.append(offs, cv.max())
    else:
        offs = np.arange(cv.min() + start_offset_mm, cv.max(), sz)
    passes, n_lines = [], 0
    for o in offs:
        p0 = o * v
        if rect is not None:
            tmin, tmax = _rect_clip(p0, u, rect)
            spans = [(tmin, tmax)] if tmax - tmin >= 1e-9 and tmax - tmin > min_length else []
            pieces = [p0 + _sample(a, b, step, sampling)[:, None] * u for a, b in spans]
        else:
            g = region.intersection(LineString([p0 + (cu.min() - 1) * u, p0 + (cu.max() + 1) * u]))
            pieces = []
            for q in sorted((np.asarray(p.coords) for p in shapely.get_parts(g) if p.length > min_length),
                            key=lambda q: (q @ u).min()):
                q = q[np.argsort(q @ u)]
                if step is not None:
                    t = q @ u
                    q = p0 + _sample(t[0], t[-1], step, sampling)[:, None] * u
                pieces.append(q)
        if not pieces:
            continue
        passes += pieces if n_lines % 2 == 0 else [q[::-1] for q in pieces]
        n_lines += 1
    if links:
        for k in range(len(passes) - 1):
            a, b = passes[k][-1], passes[k + 1][0]
            d = float(np.linalg.norm(b - a))
            if step is None or d <= 0:
                continue
            m = int(np.ceil(d / step))
            f = np.linspace(0, 1, m + 1)[1:-1] if sampling == "even" else np.arange(step, d - 1e-12, step) / d
            if f.size:
                passes[k] = np.vstack([passes[k], a + f[:, None] * (b - a)])
    if rect is not None:
        passes = [np.clip(q, [rect[0], rect[2]], [rect[1], rect[3]]) for q in passes]
    return passes


def raster_link(a, b, region, max_along_mm: float = 0.0, guard=None):
    """The feed link (K, 2) from ``a`` to ``b`` (mm) inside ``region`` (1e-6 mm tolerance): the straight
    chord if it stays inside, else, where both lie on one ring of the region's boundary, the shorter
    way along that ring if it is at most ``max_along_mm`` long (round a convex corner of the wall,
    where the chord between two rows leaves the tool-centre region); else None (a jump).

    >>> from shapely.geometry import box
    >>> R = box(0, 0, 10, 10).difference(box(4, 4, 6, 6))          # round the island's corner (6, 4)
    >>> raster_link((5, 4), (6, 5), R) is None, raster_link((5, 4), (6, 5), R, 3.0).tolist()
    (True, [[5.0, 4.0], [6.0, 4.0], [6.0, 5.0]])
    """
    a, b = np.asarray(a, float), np.asarray(b, float)
    guard = region.buffer(1e-6) if guard is None else guard
    if guard.contains(LineString([a, b])):
        return np.vstack([a, b])
    if max_along_mm <= 0:
        return None
    for part in shapely.get_parts(region):
        for ring in [part.exterior, *part.interiors]:
            if ring.distance(shapely.Point(a)) > 1e-6 or ring.distance(shapely.Point(b)) > 1e-6:
                continue
            L, sa, sb = ring.length, ring.project(shapely.Point(a)), ring.project(shapely.Point(b))
            fwd = (sb - sa) % L
            if min(fwd, L - fwd) > max_along_mm:
                return None
            P = _along(ring, sa, sb, L, fwd <= L - fwd)
            P[0], P[-1] = a, b
            return P
    return None


def _along(ring, sa: float, sb: float, L: float, forward: bool) -> np.ndarray:
    """The points of ``ring`` (its vertices kept) from arc length ``sa`` to ``sb`` (mm), forward (the
    ring's direction, through its start if need be) or backward."""
    def piece(u, v):
        return shapely.get_coordinates(substring(ring, u, v))

    if forward:
        return piece(sa, sb) if sb >= sa else np.vstack([piece(sa, L), piece(0.0, sb)[1:]])
    return piece(sa, sb) if sb <= sa else np.vstack([piece(sa, 0.0), piece(L, sb)[1:]])


def cell_order(pieces, region, max_along_mm: float = 0.0) -> tuple[list[np.ndarray], list]:
    """The raster ``pieces`` (from :func:`raster_lines`: horizontal (M, 2) arrays, mm, row by row) in
    boustrophedon-cell order, with the feed link into each: ``(pieces, links)``, ``links[k]`` the
    :func:`raster_link` (K, 2) from the end of piece k - 1 to the start of piece k, or None (the first
    piece, and a jump). From the end of a piece the next is a piece of the row above that a link inside
    ``region`` (a shapely (Multi)Polygon, 1e-6 mm tolerance; along the wall up to ``max_along_mm`` where
    the chord leaves the region) reaches, the nearest such end first (the piece reversed if its far end
    is the nearer); where none is, the tool jumps to the nearest piece that has no unvisited piece below
    it overlapping it in x (the bottom of a part the raster has not covered yet). An island or a narrow
    neck splits the rows into cells, and each cell is cut in one go instead of one jump per row (the
    raster order crosses from cell to cell on every row). The first piece stays first (the entry slot
    goes to it).

    >>> from shapely.geometry import box
    >>> U = box(0, 0, 10, 6).difference(box(4, 2, 6, 7))         # a U: two columns above a base
    >>> P, links = cell_order(raster_lines(U, 1.0), U)
    >>> [(round(float(q[0, 0]), 1), round(float(q[0, 1]))) for q in P]
    [(0.0, 0), (10.0, 1), (0.0, 2), (4.0, 3), (0.0, 4), (4.0, 5), (6.0, 2), (10.0, 3), (6.0, 4), (10.0, 5)]
    >>> [k for k, link in enumerate(links) if link is None]               # the first piece, one jump
    [0, 6]
    """
    pieces = [np.asarray(q, float) for q in pieces]
    if len(pieces) < 2:
        return pieces, [None] * len(pieces)
    guard = region.buffer(1e-6)
    shapely.prepare(guard)
    ys = np.array([q[0, 1] for q in pieces])
    levels = np.unique(np.round(ys, 6))
    row = np.searchsorted(levels, np.round(ys, 6))
    lo = np.array([q[:, 0].min() for q in pieces])
    hi = np.array([q[:, 0].max() for q in pieces])
    by_row: dict[int, set] = {}
    for i, k in enumerate(row):
        by_row.setdefault(int(k), set()).add(i)

    def oriented(i, cur):
        q = pieces[i]
        return q if np.hypot(*(q[0] - cur)) <= np.hypot(*(q[-1] - cur)) else q[::-1]

    def bottom(i):
        below = by_row.get(int(row[i]) - 1, ())
        return not any(lo[j] < hi[i] and lo[i] < hi[j] for j in below)

    out, links, last = [pieces[0]], [None], 0
    by_row[int(row[0])].discard(0)
    for _ in range(len(pieces) - 1):
        cur = out[-1][-1]
        best = None
        for j in by_row.get(int(row[last]) + 1, ()):
            q = oriented(j, cur)
            d = float(np.hypot(*(q[0] - cur)))
            if best is None or d < best[0]:
                link = raster_link(cur, q[0], region, max_along_mm, guard)
                if link is not None:
                    best = (d, j, q, link)
        if best is None:          # a jump: the nearest bottom of what is left (linked if a link reaches it)
            left = [j for r in by_row.values() for j in r]
            base = [j for j in left if bottom(j)] or left
            j = min(base, key=lambda j: (min(np.hypot(*(pieces[j][0] - cur)), np.hypot(*(pieces[j][-1] - cur))), j))
            q = oriented(j, cur)
            best = (0.0, j, q, raster_link(cur, q[0], region, max_along_mm, guard))
        _, last, q, link = best
        by_row[int(row[last])].discard(last)
        out.append(q)
        links.append(link)
    return out, links
