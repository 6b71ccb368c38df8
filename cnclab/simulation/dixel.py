"""Dixel (row-interval) material-removal simulator for 2.5D milling (Jacsó 2021, §2.2).

The stock in the X-Y plane is cut into rows of height ``resolution_mm``; each row holds a sorted set
of float intervals [a, b) of material (the dixels). The tool is a disk whose chord in each row is
the *exact* mean chord of the row strip (strip area / row height), so the modelled disk area is
exactly pi r^2 -- the property the booklet points out for the dixel model. Cost per tool step grows
linearly with 1/resolution (rows touched), against quadratically for pixels (:mod:`.pixel`).

Common interface (identical in :mod:`cnclab.simulation.pixel`)
--------------------------------------------------------------
``Stock.from_polygon(polygon, resolution_mm)``  shapely (Multi)Polygon in mm, holes allowed
``stock.copy()``                                 independent copy
``stock.area()``                                 material area (mm^2)
``stock.cut_disk(center_xy, tool_radius)``       remove the disk; returns the removed area (mm^2)
``stock.engagement_angle(center_xy, tool_radius, feed_direction_xy)``  degrees (front half-circle)
``stock.engagement(...)``                        angle + entry/exit angles (deg) + intervals
``stock.contains(x, y)``                         material membership of points
``simulate(stock, centres, tool_radius, a_p, feed_mm_min, f_z=None, teeth=None)``
                                                 per-step DataFrame (engagement_deg, removed_mm2,
                                                 mrr_mm3_min, h_max_mm, h_avg_mm, ...)

Units: mm, mm^2, mm/min, mm^3/min; angles in degrees at the API. Row j covers
``y0 + j*h <= y < y0 + (j+1)*h`` and is represented by its centre line ``y0 + (j+0.5)*h``.

>>> from shapely.geometry import box
>>> st = Stock.from_polygon(box(0, 0, 10, 10), 0.01)
>>> round(st.area(), 6)
100.0
>>> round(st.cut_disk((5, 5), 2.0) / (math.pi * 4), 12)      # exact disk area
1.0
"""
from __future__ import annotations

import math

import numpy as np

from .common import (Engagement, PathSettings, StockBase, check_radius, check_xy, refine_transitions, resolve_backend,
                     simulate, simulate_runs)

__all__ = ["Stock", "simulate", "simulate_runs", "Engagement", "scanline_intervals"]


def rings(polygon):
    """Coordinate arrays (mm) of every exterior and interior ring of a shapely polygon or multipolygon."""
    from shapely.geometry import MultiPolygon, Polygon

    if isinstance(polygon, Polygon):
        polys = [polygon]
    elif isinstance(polygon, MultiPolygon):
        polys = list(polygon.geoms)
    else:
        raise ValueError(f"polygon must be a shapely Polygon or MultiPolygon, got {type(polygon).__name__}")
    if polygon.is_empty or not polygon.is_valid:
        raise ValueError("polygon must be a valid, non-empty shapely polygon")
    out = []
    for p in polys:
        out.append(np.asarray(p.exterior.coords, float))
        out += [np.asarray(i.coords, float) for i in p.interiors]
    return out


def scanline_intervals(polygon, y0: float, h: float, n_rows: int):
    """Material intervals of ``polygon`` on the row centre lines ``y0 + (j + 0.5) h``.

    Even-odd rule on all rings (holes allowed), vectorised over edges and rows. Returns
    (rows, a, b) arrays sorted by (row, a).
    """
    rows_l, xs_l = [], []
    for ring in rings(polygon):
        p, q = ring[:-1], ring[1:]
        ylo = np.minimum(p[:, 1], q[:, 1])
        yhi = np.maximum(p[:, 1], q[:, 1])
        # rows with ylo <= y_j < yhi (half-open: vertices counted once, horizontal edges never)
        j0 = np.ceil((ylo - y0) / h - 0.5).astype(np.int64)
        j1 = np.ceil((yhi - y0) / h - 0.5).astype(np.int64)      # exclusive
        j0 = np.clip(j0, 0, n_rows)
        j1 = np.clip(j1, 0, n_rows)
        cnt = np.maximum(j1 - j0, 0)
        if cnt.sum() == 0:
            continue
        e = np.repeat(np.arange(len(p)), cnt)
        off = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        j = j0[e] + off
        y = y0 + (j + 0.5) * h
        t = (y - p[e, 1]) / (q[e, 1] - p[e, 1])
        rows_l.append(j)
        xs_l.append(p[e, 0] + t * (q[e, 0] - p[e, 0]))
    if not rows_l:
        return np.empty(0, np.int64), np.empty(0), np.empty(0)
    rows = np.concatenate(rows_l)
    xs = np.concatenate(xs_l)
    o = np.lexsort((xs, rows))
    rows, xs = rows[o], xs[o]
    a, b, rr = xs[0::2], xs[1::2], rows[0::2]
    keep = b > a
    return rr[keep], a[keep], b[keep]


#: signed x-distance (mm) reported for a row without material (a large negative number)
_NO_MATERIAL = 1e9

_INF = math.inf


class Stock(StockBase):
    """Dixel stock: per row a sorted set of material intervals (mm). See the module docstring.

    Storage: two ``(K, n_rows)`` float arrays ``A``, ``B`` holding row j's intervals ``[A[k, j],
    B[k, j])`` in increasing k order, padded with ``+inf`` (empty slots); the capacity K doubles when
    a cut splits a row into more intervals than it holds. A disk cut and an engagement measurement
    therefore touch only the ~2r/h rows the tool covers, with a fixed number of numpy operations
    per call (no per-row Python loop, no copy of the whole stock). The flat view ``(rows, a, b)``
    of :meth:`intervals` (and the ``_row``/``_a``/``_b`` attributes) is built on demand.
    """

    def __init__(self, y0: float, resolution_mm: float, n_rows: int, rows, a, b, x_min: float,
                 x_max: float):
        self.y0 = float(y0)
        self.resolution_mm = float(resolution_mm)
        self.n_rows = int(n_rows)
        self.x_min, self.x_max = float(x_min), float(x_max)
        self._span = (self.x_max - self.x_min) + 2.0
        rows = np.asarray(rows, np.int64)
        a = np.asarray(a, float)
        b = np.asarray(b, float)
        if not (rows.shape == a.shape == b.shape and rows.ndim == 1):
            raise ValueError("rows, a, b must be 1-D arrays of the same length")
        if rows.size and (rows.min() < 0 or rows.max() >= self.n_rows):
            raise ValueError(f"rows must lie in [0, n_rows={self.n_rows})")
        o = np.lexsort((a, rows))
        rows, a, b = rows[o], a[o], b[o]
        cnt = np.bincount(rows, minlength=self.n_rows)
        k = max(int(cnt.max()) if cnt.size else 0, 1) + 1
        self._A = np.full((k, self.n_rows), _INF)
        self._B = np.full((k, self.n_rows), _INF)
        col = np.arange(rows.size) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        self._A[col, rows] = a
        self._B[col, rows] = b

    # -- flat view (sorted by row, then a) --------------------------------------------------------
    def intervals(self):
        """(rows, a, b) arrays of the material intervals, sorted by row then a (copies)."""
        j, k = np.nonzero(np.isfinite(self._A.T))
        return j.astype(np.int64), self._A[k, j], self._B[k, j]

    @property
    def _row(self):
        return self.intervals()[0]

    @property
    def _a(self):
        return self.intervals()[1]

    @property
    def _b(self):
        return self.intervals()[2]

    @classmethod
    def from_polygon(cls, polygon, resolution_mm: float, margin_mm: float = 0.0) -> "Stock":
        """Dixel stock of a shapely (Multi)Polygon (mm, holes allowed) at row height ``resolution_mm``.

        ``margin_mm`` widens the row range beyond the polygon's bounds (air rows).
        """
        h = float(resolution_mm)
        if not (math.isfinite(h) and h > 0):
            raise ValueError(f"resolution_mm must be a positive length in mm, got {resolution_mm!r}")
        rings(polygon)
        minx, miny, maxx, maxy = polygon.bounds
        y0 = miny - float(margin_mm)
        n_rows = int(math.ceil((maxy + float(margin_mm) - y0) / h))
        if n_rows > 5_000_000:
            raise ValueError(f"resolution_mm={h} gives {n_rows} rows: too fine for this polygon")
        rows, a, b = scanline_intervals(polygon, y0, h, n_rows)
        return cls(y0, h, n_rows, rows, a, b, minx - 1.0, maxx + 1.0)

    def copy(self) -> "Stock":
        """An independent copy (same class)."""
        new = object.__new__(type(self))
        new.__dict__.update(self.__dict__)
        new._A = self._A.copy()
        new._B = self._B.copy()
        return new

    def area(self) -> float:
        """Material area (mm^2) = sum of interval lengths x row height."""
        fin = np.isfinite(self._A)
        return float(np.sum(self._B[fin] - self._A[fin]) * self.resolution_mm)

    @property
    def n_intervals(self) -> int:
        """Number of stored material intervals (the model's data size)."""
        return int(np.count_nonzero(np.isfinite(self._A)))

    def row_y(self, rows=None) -> np.ndarray:
        """Centre-line y (mm) of rows (all rows by default)."""
        j = np.arange(self.n_rows) if rows is None else np.asarray(rows)
        return self.y0 + (j + 0.5) * self.resolution_mm

    def _contains(self, x, y):
        j = np.floor((y - self.y0) / self.resolution_mm).astype(np.int64)
        ok = (j >= 0) & (j < self.n_rows)
        jc = np.where(ok, j, 0)
        return ok & np.any((self._A[:, jc] <= x) & (x < self._B[:, jc]), axis=0)

    def _contains_interp(self, x, y):
        """Membership with the boundary interpolated linearly between row centre lines.

        Between the centre lines of rows j and j+1 holding the same number of intervals, the
        interval end points are interpolated linearly in y (the polygon through the dixel end
        points: second-order accurate for smooth boundaries); otherwise the nearer row decides.
        """
        t = (y - self.y0) / self.resolution_mm - 0.5
        j = np.floor(t).astype(np.int64)
        f = t - j
        n = self.n_rows
        j1 = j + 1
        ok0 = (j >= 0) & (j < n)
        ok1 = (j1 >= 0) & (j1 < n)
        A0, B0 = self._A[:, np.where(ok0, j, 0)], self._B[:, np.where(ok0, j, 0)]
        A1, B1 = self._A[:, np.where(ok1, j1, 0)], self._B[:, np.where(ok1, j1, 0)]
        fin0 = np.isfinite(A0) & ok0
        fin1 = np.isfinite(A1) & ok1
        same = np.all(fin0 == fin1, axis=0)
        with np.errstate(invalid="ignore"):
            Ai = A0 + f * (A1 - A0)
            Bi = B0 + f * (B1 - B0)
            smooth = np.any(fin0 & (Ai <= x) & (x < Bi), axis=0)
        near0 = f < 0.5
        stair = np.where(near0, ok0 & np.any((A0 <= x) & (x < B0), axis=0),
                         ok1 & np.any((A1 <= x) & (x < B1), axis=0))
        return np.where(same, smooth, stair)

    def _band_transitions(self, c, r, psi0, p0, p1, j0, j1):
        """Exact transitions of the circle with the polyline boundary inside angle brackets.

        Bracket i runs between consecutive row-centre crossings p0[i] < p1[i] (rad, relative to the
        feed direction psi0) in rows j0[i], j1[i]; its arc lies in one band between the centre lines
        of rows jb and jb + 1. When both rows hold the same number of intervals, the boundary in the
        band is the set of segments joining corresponding end points (see :meth:`_contains_interp`),
        and the transitions are the circle-segment intersections. Returns ``(ok, angles)``: ok[i]
        False where this does not apply (rows differ, beyond the grid, even number of crossings);
        angles (rad) of all transitions of the ok brackets.
        """
        h = self.resolution_mm
        same = j0 == j1
        ym = c[1] + r * np.sin(psi0 + 0.5 * (p0 + p1))
        jb = np.where(same, np.where(ym > self.y0 + (j0 + 0.5) * h, j0, j0 - 1), np.minimum(j0, j1))
        ok = (np.abs(j1 - j0) <= 1) & (jb >= 0) & (jb + 1 < self.n_rows)
        jc = np.where(ok, jb, 0)
        A0, A1 = self._A[:, jc], self._A[:, jc + 1]
        fin = np.isfinite(A0)
        ok &= np.all(fin == np.isfinite(A1), axis=0)
        Y0 = self.y0 + (jc + 0.5) * h - c[1]
        fin2 = np.concatenate([fin, fin])
        with np.errstate(invalid="ignore"):
            X0 = np.concatenate([A0, self._B[:, jc]]) - c[0]             # (2K, q) segment starts
            dX = np.concatenate([A1, self._B[:, jc + 1]]) - c[0] - X0
            qa = dX * dX + h * h
            qb = X0 * dX + Y0 * h
            qc = X0 * X0 + Y0 * Y0 - r * r
            sq = np.sqrt(qb * qb - qa * qc)
            angs, valid = [], []
            for t in ((-qb - sq) / qa, (-qb + sq) / qa):
                a = np.arctan2(Y0 + t * h, X0 + t * dX) - psi0
                a = p0 + np.mod(a - p0, 2 * np.pi)
                angs.append(a)
                valid.append(fin2 & (t >= 0) & (t <= 1) & (a > p0) & (a < p1))
        ang = np.concatenate(angs)
        val = np.concatenate(valid)
        ok &= (val.sum(axis=0) % 2) == 1
        return ok, ang[val & ok]

    def _signed_xdist(self, x, j, endpoint: bool = False):
        """Signed x-distance (mm) of points (x, row j) to the material boundary of row j (+ inside).

        ``-_NO_MATERIAL`` for rows without material and rows beyond the grid (air). With
        ``endpoint=True`` also returns the x (mm) of the nearest interval end point (NaN when none).
        """
        ok = (j >= 0) & (j < self.n_rows)
        jc = np.where(ok, j, 0)
        A = self._A[:, jc]
        B = self._B[:, jc]
        # per interval max(a - x, x - b): -(distance inside) if x in [a, b), else the gap to it
        m = np.maximum(A - x, x - B)
        if not endpoint:
            return np.where(ok, -np.minimum(m.min(axis=0), _NO_MATERIAL), -_NO_MATERIAL)
        kk = m.argmin(axis=0)
        cols = np.arange(x.size)
        d = m[kk, cols]
        a, b = A[kk, cols], B[kk, cols]
        with np.errstate(invalid="ignore"):
            e = np.where(np.abs(x - a) <= np.abs(b - x), a, b)
        good = ok & np.isfinite(d)
        return np.where(good, -np.minimum(d, _NO_MATERIAL), -_NO_MATERIAL), np.where(good, e, np.nan)

    def _plain(self) -> bool:
        cls = type(self)
        return cls.cut_disk is Stock.cut_disk and cls.engagement is Stock.engagement

    def _simulate_compiled(self, P, d, ds, s, r, lag, central, front_only, f_z, out, hold_front=False):
        from . import _kernels as K

        n = len(P)
        i, k, f0, f1 = 0, 0, float(d[0, 0]), float(d[0, 1])
        dummy = np.zeros((1, 1), np.bool_)
        while True:
            cfg = PathSettings(0, 0.0, self.y0, self.resolution_mm, r, lag, central, front_only, True, 16, 0, f_z,
                                 hold_front)
            i, k, f0, f1 = K.simulate_path(self._A, self._B, dummy, P, d, ds, s, cfg, (i, k, f0, f1), tuple(out))
            if i == n and k == n:
                return True
            self._grow(2 * self._A.shape[0])          # a row ran out of interval slots: grow, resume

    def engagement(self, center_xy, tool_radius, feed_direction_xy, front_only: bool = True,
                   method: str = "rows", backend: str | None = None, **kw) -> Engagement:
        """Engagement of the tool circumference with material (see :meth:`StockBase.engagement`).

        ``method="rows"`` (default) uses the dixel structure: the circle crosses every row centre
        line at two points (O(1/resolution) work). Where consecutive crossings (adjacent rows) are
        on opposite sides of the material boundary, the boundary between the two rows is taken as
        the segment joining their nearest interval end points and intersected with the circle
        (``boundary="polyline"``, default; ``boundary="linear"`` interpolates the signed
        x-distance linearly along the circle instead). Brackets near the top/bottom of the circle
        (sparse rows) or next to an empty row are resolved on the membership test.
        ``method="sample"`` uses the generic sampling + refinement of :class:`StockBase`.
        ``backend``: "numba" (compiled port, :func:`._kernels.dixel_engagement`), "numpy" (this
        code, the reference) or None (default of :func:`.common.set_backend`).
        """
        be = resolve_backend(backend)
        if method == "sample":
            return super().engagement(center_xy, tool_radius, feed_direction_xy, front_only, **kw)
        if method != "rows":
            raise ValueError(f"method must be 'rows' or 'sample', got {method!r}")
        if kw.get("boundary", "polyline") not in ("polyline", "linear"):
            raise ValueError(f"boundary must be 'polyline' or 'linear', got {kw['boundary']!r}")
        c = check_xy(center_xy, "center_xy")
        r = check_radius(tool_radius)
        f = check_xy(feed_direction_xy, "feed_direction_xy")
        if math.hypot(*f) == 0:
            raise ValueError("feed_direction_xy must be a non-zero vector")
        if be == "numba":
            from . import _kernels as K

            iv = K.dixel_engagement(self._A, self._B, self.y0, self.resolution_mm, float(c[0]), float(c[1]), r,
                                    float(f[0]), float(f[1]), bool(front_only),
                                    kw.get("boundary", "polyline") == "polyline", int(kw.get("bisections", 16)))
            return self._engagement_from_intervals(iv)
        psi0 = math.atan2(f[1], f[0])
        h = self.resolution_mm
        lo, hi = (-np.pi / 2, np.pi / 2) if front_only else (-np.pi, np.pi)
        rays = self._row_crossings(c, r, psi0, lo, hi)
        if rays is None:
            return Engagement(0.0, math.nan, math.nan, np.empty((0, 2)))
        pe, xe, je = rays
        dist, ex = self._signed_xdist(xe, je, endpoint=True)
        ins = dist > 0
        if not ins.any():
            return Engagement(0.0, math.nan, math.nan, np.empty((0, 2)))
        if ins.all():
            return Engagement(math.degrees(hi - lo), math.degrees(lo), math.degrees(hi),
                              np.array([[lo, hi]]))
        k = np.flatnonzero(ins[1:] != ins[:-1])
        d0, d1 = dist[k], dist[k + 1]
        p0, p1 = pe[k], pe[k + 1]
        # first estimate: linear interpolation of the signed x-distance along the circle
        edges = p0 + np.minimum(np.maximum(d0 / (d0 - d1), 0.0), 1.0) * (p1 - p0)
        empty = np.minimum(d0, d1) <= -_NO_MATERIAL / 2      # an empty row: no position information
        wide = ((p1 - p0) > 4.0 * h / r) | empty
        if kw.get("boundary", "polyline") == "polyline":
            # the material boundary between two adjacent rows is the segment joining the row end
            # points nearest to the crossings; intersect it with the tool circle (second order in h
            # for smooth boundaries, where the x-distance interpolation is first order)
            adj = ~wide & (np.abs(je[k + 1] - je[k]) == 1)
            if adj.any():
                edges[adj] = self._segment_edges(c, r, psi0, k[adj], ex, je, edges[adj], p0[adj], p1[adj])
        # wide brackets (near the top/bottom rows, where rows are sparse in angle) and brackets
        # next to an empty row: all transitions located on the membership test
        if wide.any():
            kw_ = np.flatnonzero(wide)
            parts = [edges[~wide]]
            if kw.get("boundary", "polyline") == "polyline":
                ok, found = self._band_transitions(c, r, psi0, p0[kw_], p1[kw_], je[k[kw_]], je[k[kw_] + 1])
                parts.append(found)
                kw_ = kw_[~ok]
                test = self._contains_interp
            else:
                test = self._contains
            if kw_.size:
                parts.append(refine_transitions(test, c, r, psi0, p0[kw_], p1[kw_], ins[k[kw_]],
                                                 kw.get("bisections", 16)))
            edges = np.sort(np.concatenate(parts))
        bounds = np.concatenate([pe[:1] if ins[0] else [], edges, pe[-1:] if ins[-1] else []])
        iv = np.minimum(np.maximum(bounds.reshape(-1, 2), lo), hi)
        return self._engagement_from_intervals(iv[iv[:, 1] > iv[:, 0]])

    def _row_crossings(self, c, r: float, psi0: float, lo: float, hi: float):
        """The tool circle's crossings of the row centre lines used by :meth:`engagement`: ``(pe, xe,
        je)`` polar angle from the feed (rad, unwrapped, increasing), x (mm) and row index of the
        crossings inside (lo, hi) plus one neighbour on each side; None when no row is crossed."""
        h = self.resolution_mm
        # every row the circle crosses, also those beyond the grid (they hold no material: air)
        j_lo = int(math.ceil((c[1] - r - self.y0) / h - 0.5))
        j_hi = int(math.floor((c[1] + r - self.y0) / h - 0.5))
        if j_hi < j_lo:
            return None
        j = np.arange(j_lo, j_hi + 1)
        dy = self.y0 + (j + 0.5) * h - c[1]
        cx = np.sqrt(np.maximum(r * r - dy * dy, 0.0))
        # crossings in increasing polar angle: right side bottom->top, then left side top->bottom
        dyy = np.concatenate([dy, dy[::-1]])
        cxx = np.concatenate([cx, -cx[::-1]])
        jj = np.concatenate([j, j[::-1]])
        psi = np.arctan2(dyy, cxx) - psi0                 # increasing (up to the -pi/pi wrap)
        psi = np.mod(psi + np.pi, 2 * np.pi) - np.pi     # relative to feed, (-pi, pi]
        w = int(np.argmin(psi))                          # rotate so that psi increases
        if w:
            psi = np.concatenate([psi[w:], psi[:w]])
            cxx = np.concatenate([cxx[w:], cxx[:w]])
            jj = np.concatenate([jj[w:], jj[:w]])
        # only the crossings inside (lo, hi) (contiguous) and one neighbour on each side
        inr = np.flatnonzero((psi > lo) & (psi < hi))
        n = psi.size
        if inr.size:
            i0, i1 = int(inr[0]), int(inr[-1]) + 1
        else:                                            # no row centre line inside the range
            i0 = i1 = int(np.searchsorted(psi, lo))
        idx = np.arange(i0 - 1, i1 + 1)
        pe = psi[idx % n] + 2 * np.pi * np.floor_divide(idx, n)       # unwrapped, increasing
        return pe, c[0] + cxx[idx % n], jj[idx % n]

    def _segment_edges(self, c, r: float, psi0: float, ka, ex, je, lin, p0, p1):
        """``boundary="polyline"`` edges of :meth:`engagement` (rad from the feed): for the brackets
        ``ka`` between adjacent rows, the material boundary is the segment joining the row end points
        ``ex`` nearest to the crossings; its intersection with the tool circle within (p0, p1), the
        one closest to the linear estimate ``lin`` (kept where there is none). Second order in h for
        smooth boundaries, where the x-distance interpolation is first order."""
        h = self.resolution_mm
        xa = ex[ka] - c[0]
        ya = self.y0 + (je[ka] + 0.5) * h - c[1]
        dx = ex[ka + 1] - c[0] - xa
        dyv = self.y0 + (je[ka + 1] + 0.5) * h - c[1] - ya
        qa = dx * dx + dyv * dyv
        qb = xa * dx + ya * dyv
        qc = xa * xa + ya * ya - r * r
        disc = qb * qb - qa * qc
        with np.errstate(invalid="ignore", divide="ignore"):
            sq = np.sqrt(disc)
            best = np.full(ka.size, np.nan)
            for t in ((-qb - sq) / qa, (-qb + sq) / qa):
                ang = np.arctan2(ya + t * dyv, xa + t * dx) - psi0
                ang = lin + (np.mod(ang - lin + np.pi, 2 * np.pi) - np.pi)
                okt = (t >= 0) & (t <= 1) & (ang >= p0) & (ang <= p1)
                closer = okt & ~(np.abs(best - lin) <= np.abs(ang - lin))
                best = np.where(closer, ang, best)
        return np.where(np.isfinite(best), best, lin)

    def _rows_of_disk(self, cy: float, r: float):
        h = self.resolution_mm
        j_lo = max(int(math.floor((cy - r - self.y0) / h)), 0)
        j_hi = min(int(math.ceil((cy + r - self.y0) / h)) - 1, self.n_rows - 1)
        if j_hi < j_lo:
            return j_lo, j_lo, np.empty(0)
        # exact mean half-chord of each row strip: (G(top) - G(bottom)) / h, G the half-area primitive
        u = np.clip(self.y0 + np.arange(j_lo, j_hi + 2) * h - cy, -r, r)
        g = u * np.sqrt(np.maximum(r * r - u * u, 0.0)) + r * r * np.arcsin(u / r)
        return j_lo, j_hi + 1, np.diff(g) * (0.5 / h)

    def disk_halfwidths(self, cy: float, tool_radius: float):
        """Rows touched by a disk centred at height ``cy`` and their exact mean half-chords (mm).

        The half-chord of row j is strip area / (2 h), so sum(2 w h) = pi r^2 exactly.

        >>> from shapely.geometry import box
        >>> st = Stock.from_polygon(box(0, 0, 10, 10), 0.5)
        >>> j, w = st.disk_halfwidths(5.0, 1.0)
        >>> j.tolist(), round(float(np.sum(2 * w * 0.5)) / math.pi, 12)
        ([8, 9, 10, 11], 1.0)
        """
        r = check_radius(tool_radius)
        j0, j1, w = self._rows_of_disk(float(cy), r)
        return np.arange(j0, j1, dtype=np.int64), w

    def cut_disk(self, center_xy, tool_radius, backend: str | None = None) -> float:
        """Remove the tool disk at ``center_xy`` (mm); returns the removed area (mm^2).

        Interval arithmetic on the rows the disk covers: every interval [a, b) of a row with
        half-chord w becomes [a, min(b, x-w)) and [max(a, x+w), b) (empty pieces dropped).
        ``backend="numpy"``: vectorised over the rows (the reference); "numba": the compiled loop
        :func:`._kernels.dixel_cut`; None: the default of :func:`.common.set_backend`.
        """
        cx, cy = check_xy(center_xy, "center_xy")
        r = check_radius(tool_radius)
        if resolve_backend(backend) == "numba":
            from . import _kernels as K

            while True:
                v = K.dixel_cut(self._A, self._B, self.y0, self.resolution_mm, float(cx), float(cy), r)
                if v >= 0:
                    return v
                self._grow(2 * self._A.shape[0])
        j0, j1, w = self._rows_of_disk(float(cy), r)
        if j1 <= j0:
            return 0.0
        A = self._A[:, j0:j1]
        B = self._B[:, j0:j1]
        xs = cx - w
        xe = cx + w
        ov = np.minimum(B, xe) - np.maximum(A, xs)
        hit = ov > 0
        rows_hit = np.flatnonzero(hit.any(axis=0))
        if rows_hit.size == 0:
            return 0.0
        removed = float(np.sum(ov[hit])) * self.resolution_mm
        k0, k1 = int(rows_hit[0]), int(rows_hit[-1]) + 1
        A, B, xs, xe = A[:, k0:k1], B[:, k0:k1], xs[k0:k1], xe[k0:k1]
        lb = np.minimum(B, xs)
        ra = np.maximum(A, xe)
        # left and right pieces; the valid ones are disjoint, so sorting a and b separately keeps
        # the pairs (empty slots are +inf and sort last)
        lv = lb > A
        rv = B > ra
        na = np.concatenate([np.where(lv, A, _INF), np.where(rv, ra, _INF)], axis=0)
        nb = np.concatenate([np.where(lv, lb, _INF), np.where(rv, B, _INF)], axis=0)
        na.sort(axis=0)
        nb.sort(axis=0)
        K = self._A.shape[0]
        if np.isfinite(na[K]).any():                  # a row now holds more than K intervals
            self._grow(2 * K)
            K = 2 * K
        self._A[:, j0 + k0:j0 + k1] = na[:K]
        self._B[:, j0 + k0:j0 + k1] = nb[:K]
        return removed

    def _grow(self, k: int) -> None:
        A = np.full((k, self.n_rows), _INF)
        B = np.full((k, self.n_rows), _INF)
        k0 = self._A.shape[0]
        A[:k0] = self._A
        B[:k0] = self._B
        self._A, self._B = A, B

    def to_polygon(self):
        """Material as a shapely geometry (union of row rectangles, mm)."""
        import shapely

        h = self.resolution_mm
        rows, a, b = self.intervals()
        y = self.y0 + rows * h
        y1 = self.y0 + (rows + 1) * h               # same formula as the next row's bottom edge
        boxes = shapely.box(a, y, b, y1)
        return shapely.union_all(boxes)

    def boundary_points(self):
        """(k, 2) material boundary samples: interval end points on the row centre lines (mm)."""
        rows, a, b = self.intervals()
        y = self.row_y(rows)
        return np.concatenate([np.c_[a, y], np.c_[b, y]])
