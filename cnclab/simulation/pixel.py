"""Pixel-grid material-removal simulator (baseline; Kim & Yang 2006, §3.2 used 0.3 mm pixels).

The stock is a boolean grid of square pixels of side ``resolution_mm``; a pixel is material when its
centre is inside the polygon, and is removed when its centre is inside the tool disk (so the
modelled disk area is only approximately pi r^2). Cost per tool step grows with (1/resolution)^2.

Same interface as :mod:`cnclab.simulation.dixel` (see there):
``Stock.from_polygon(polygon, resolution_mm)``, ``copy()``, ``area()`` (mm^2),
``cut_disk(center_xy, tool_radius)`` -> removed area (mm^2), ``engagement_angle(...)`` (deg),
``engagement(...)``, ``contains(x, y)``, and the shared ``simulate(...)``.
Extra: ``cut_disk_pixels`` returns the number of removed pixels (Kim & Yang's count, eq. 4).

>>> from shapely.geometry import box
>>> st = Stock.from_polygon(box(0, 0, 10, 10), 0.05)
>>> round(st.area(), 6)
100.0
>>> abs(st.cut_disk((5, 5), 2.0) / (math.pi * 4) - 1) < 0.01
True
"""
from __future__ import annotations

import math

import numpy as np

from .common import Engagement, PathSettings, StockBase, check_radius, check_xy, removal, resolve_backend, simulate
from .dixel import rings, scanline_intervals

__all__ = ["Stock", "simulate", "removal", "Engagement"]


class Stock(StockBase):
    """Pixel stock: boolean grid ``grid[j, i]`` (row j along y, column i along x), mm units."""

    def __init__(self, x0: float, y0: float, resolution_mm: float, grid: np.ndarray):
        self.x0, self.y0 = float(x0), float(y0)
        self.resolution_mm = float(resolution_mm)
        self.grid = np.asarray(grid, bool)

    @classmethod
    def from_polygon(cls, polygon, resolution_mm: float, margin_mm: float = 0.0) -> "Stock":
        """Pixel stock of a shapely (Multi)Polygon (mm, holes allowed): pixel centres inside."""
        h = float(resolution_mm)
        if not (math.isfinite(h) and h > 0):
            raise ValueError(f"resolution_mm must be a positive length in mm, got {resolution_mm!r}")
        rings(polygon)
        minx, miny, maxx, maxy = polygon.bounds
        m = float(margin_mm)
        x0, y0 = minx - m, miny - m
        nx = int(math.ceil((maxx + m - x0) / h))
        ny = int(math.ceil((maxy + m - y0) / h))
        if nx * ny > 400_000_000:
            raise ValueError(f"resolution_mm={h} gives {nx}x{ny} pixels: too fine for this polygon")
        rows, a, b = scanline_intervals(polygon, y0, h, ny)
        # pixel i is material when its centre x0 + (i+0.5) h lies in [a, b)
        ia = np.clip(np.ceil((a - x0) / h - 0.5).astype(np.int64), 0, nx)
        ib = np.clip(np.ceil((b - x0) / h - 0.5).astype(np.int64), 0, nx)
        diff = np.zeros((ny, nx + 1), np.int32)
        np.add.at(diff, (rows, ia), 1)
        np.add.at(diff, (rows, ib), -1)
        grid = np.cumsum(diff, axis=1)[:, :nx] > 0
        return cls(x0, y0, h, grid)

    def copy(self) -> "Stock":
        """An independent copy."""
        return Stock(self.x0, self.y0, self.resolution_mm, self.grid.copy())

    def area(self) -> float:
        """Material area (mm^2) = number of material pixels x pixel area."""
        return float(np.count_nonzero(self.grid)) * self.resolution_mm ** 2

    def _contains(self, x, y):
        h = self.resolution_mm
        i = np.floor((x - self.x0) / h).astype(np.int64)
        j = np.floor((y - self.y0) / h).astype(np.int64)
        ny, nx = self.grid.shape
        ok = (i >= 0) & (i < nx) & (j >= 0) & (j < ny)
        out = np.zeros(x.shape, bool)
        out[ok] = self.grid[j[ok], i[ok]]
        return out

    def _plain(self) -> bool:
        cls = type(self)
        return (cls.cut_disk is Stock.cut_disk and cls.cut_disk_pixels is Stock.cut_disk_pixels
                and cls.engagement is Stock.engagement)

    def _simulate_compiled(self, P, d, ds, s, r, lag, central, front_only, f_z, out, hold_front=False):
        from . import _kernels as K

        dummy = np.empty((1, 1))
        cfg = PathSettings(1, self.x0, self.y0, self.resolution_mm, r, lag, central, front_only, True, 24, 0, f_z,
                             hold_front)
        K.simulate_path(dummy, dummy, self.grid, P, d, ds, s, cfg, (0, 0, float(d[0, 0]), float(d[0, 1])), tuple(out))
        return True

    def _removed_compiled(self, P, r, rem) -> bool:
        """The discs at ``P`` cut in order by :func:`._kernels.cut_path` (the numba
        :meth:`cut_disk_pixels` per centre): their removed areas (mm^2) in ``rem``."""
        from . import _kernels as K

        dummy = np.empty((1, 1))
        K.cut_path(1, dummy, dummy, self.grid, self.x0, self.y0, self.resolution_mm, np.ascontiguousarray(P), r, 0, rem)
        return True

    def engagement(self, center_xy, tool_radius, feed_direction_xy, front_only: bool = True,
                   n_samples: int | None = None, bisections: int = 24,
                   backend: str | None = None) -> Engagement:
        """Engagement of the tool circumference with the material (see :meth:`StockBase.engagement`).

        ``backend``: "numpy" (the sampling reference of :class:`StockBase`), "numba" (its compiled
        port :func:`._kernels.pixel_engagement`) or None (default of :func:`.common.set_backend`).
        """
        if resolve_backend(backend) == "numpy":
            return super().engagement(center_xy, tool_radius, feed_direction_xy, front_only, n_samples,
                                      bisections)
        from . import _kernels as K

        c = check_xy(center_xy, "center_xy")
        r = check_radius(tool_radius)
        f = check_xy(feed_direction_xy, "feed_direction_xy")
        if math.hypot(*f) == 0:
            raise ValueError("feed_direction_xy must be a non-zero vector")
        iv = K.pixel_engagement(self.grid, self.x0, self.y0, self.resolution_mm, float(c[0]), float(c[1]), r,
                                float(f[0]), float(f[1]), bool(front_only),
                                0 if n_samples is None else int(n_samples), int(bisections))
        return self._engagement_from_intervals(iv)

    def cut_disk_pixels(self, center_xy, tool_radius, backend: str | None = None) -> int:
        """Remove the pixels whose centres lie in the disk; returns how many were material.

        ``backend``: "numpy" (vectorised over the bounding window, the reference), "numba" (the
        compiled per-row loop :func:`._kernels.pixel_cut`) or None (default of :func:`.common.set_backend`).
        """
        cx, cy = check_xy(center_xy, "center_xy")
        r = check_radius(tool_radius)
        if resolve_backend(backend) == "numba":
            from . import _kernels as K

            return int(K.pixel_cut(self.grid, self.x0, self.y0, self.resolution_mm, float(cx), float(cy), r))
        h = self.resolution_mm
        ny, nx = self.grid.shape
        i0 = max(int(math.floor((cx - r - self.x0) / h)), 0)
        i1 = min(int(math.ceil((cx + r - self.x0) / h)), nx)
        j0 = max(int(math.floor((cy - r - self.y0) / h)), 0)
        j1 = min(int(math.ceil((cy + r - self.y0) / h)), ny)
        if i1 <= i0 or j1 <= j0:
            return 0
        xc = self.x0 + (np.arange(i0, i1) + 0.5) * h - cx
        yc = self.y0 + (np.arange(j0, j1) + 0.5) * h - cy
        disk = (yc[:, None] ** 2 + xc[None, :] ** 2) <= r * r
        win = self.grid[j0:j1, i0:i1]
        hit = win & disk
        n = int(np.count_nonzero(hit))
        win ^= hit                                   # clear the material pixels under the disk
        return n

    def segment_pixels(self, p0, p1, tool_radius, cut: bool = False, backend: str | None = None) -> int:
        """The material pixels whose centres lie within ``tool_radius`` (mm) of the segment ``p0``--``p1``
        (mm): the tool's sweep along a straight move (Kim & Yang's ``Linear_Motion`` count); ``cut``
        removes them. Returns how many were material.

        ``backend``: "numpy" (vectorised over the segment's bounding window, the reference), "numba"
        (:func:`._segment_kernel.segment_pixels`, the same arithmetic per pixel: the same count and stock)
        or None (default of :func:`.common.set_backend`).

        >>> from shapely.geometry import box
        >>> st = Stock.from_polygon(box(0, 0, 10, 4), 0.5)
        >>> st.segment_pixels((2.0, 2.0), (8.0, 2.0), 1.0, cut=True), int(st.grid.sum())
        (60, 100)

        (of 160 pixels: the 12 columns of centres x = 2.25 ... 7.75 mm have 4 centres within 1 mm of
        y = 2 (48); at each end the column 0.25 mm beyond it 4 (|y - 2| <= 0.968) and the next, 0.75
        mm, 2 (|y - 2| <= 0.661): 48 + 2 * 6)
        """
        a = np.asarray(check_xy(p0, "p0"), float)
        b = np.asarray(check_xy(p1, "p1"), float)
        r = check_radius(tool_radius)
        d = b - a
        L2 = float(d @ d)                   # computed once, here, for both backends (the same bits)
        if resolve_backend(backend) == "numba":
            from . import _segment_kernel as KS

            return int(KS.segment_pixels(self.grid, self.x0, self.y0, self.resolution_mm, float(a[0]), float(a[1]),
                                           float(b[0]), float(b[1]), r, L2, bool(cut)))
        h = self.resolution_mm
        ny, nx = self.grid.shape
        lo = np.minimum(a, b) - r
        hi = np.maximum(a, b) + r
        i0 = max(int(math.floor((lo[0] - self.x0) / h)), 0)
        i1 = min(int(math.ceil((hi[0] - self.x0) / h)), nx)
        j0 = max(int(math.floor((lo[1] - self.y0) / h)), 0)
        j1 = min(int(math.ceil((hi[1] - self.y0) / h)), ny)
        if i1 <= i0 or j1 <= j0:
            return 0
        X = (self.x0 + (np.arange(i0, i1) + 0.5) * h)[None, :] - a[0]
        Y = (self.y0 + (np.arange(j0, j1) + 0.5) * h)[:, None] - a[1]
        t = np.zeros_like(X + Y) if L2 == 0 else np.clip((X * d[0] + Y * d[1]) / L2, 0.0, 1.0)
        mask = (X - t * d[0]) ** 2 + (Y - t * d[1]) ** 2 <= r * r
        win = self.grid[j0:j1, i0:i1]
        hit = win & mask
        if cut:
            win ^= hit
        return int(np.count_nonzero(hit))

    def cut_disks_pixels(self, centers_xy, tool_radius) -> int:
        """Remove the disks of radius ``tool_radius`` (mm) at every centre of ``centers_xy`` (n, 2) mm,
        in one compiled loop (:func:`._kernels.cut_path`: the numba :meth:`cut_disk_pixels` per
        centre, without its per-call overhead); returns how many pixels were material.

        >>> from shapely.geometry import box
        >>> st = Stock.from_polygon(box(0, 0, 10, 4), 0.5)
        >>> st.cut_disks_pixels([[0.0, 2.0], [10.0, 2.0]], 1.0), int(st.grid.sum())
        (12, 148)

        (160 pixels; at each end the column of centres 0.25 mm from the edge has 4 within the disk,
        |y - 2| <= sqrt(1 - 0.25^2) = 0.968, the next column, 0.75 mm, 2: |y - 2| <= 0.661)
        """
        C = np.ascontiguousarray(np.asarray(centers_xy, float).reshape(-1, 2))
        if not np.isfinite(C).all():
            raise ValueError("centers_xy must be finite (mm)")
        h = self.resolution_mm
        rem = np.empty(len(C))
        self._removed_compiled(C, check_radius(tool_radius), rem)
        return int(round(float(rem.sum()) / (h * h)))

    def cut_disk(self, center_xy, tool_radius, backend: str | None = None) -> float:
        """Remove the tool disk at ``center_xy`` (mm); returns the removed area (mm^2)."""
        return self.cut_disk_pixels(center_xy, tool_radius, backend) * self.resolution_mm ** 2
