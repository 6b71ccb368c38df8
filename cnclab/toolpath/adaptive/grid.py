"""The planner's state at one level (:class:`Grid`): the planning stock, the rapid stock, the
tool-centre mask and the coarse free-distance field kept up to date incrementally (see the
package docstring). Units: mm.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .control import GUARD_LEVEL, pass_kernel, replay
from .links import dijkstra
from .params import AdaptiveParams
from .stock import capsule_free, coarse_any, cut_disc, cut_path, dist_window, max_filter, raster


def _union(a, b):
    """The bounding box (x0, y0, x1, y1) of two boxes (None: empty)."""
    if a is None:
        return b
    return (min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), max(a[3], b[3]))


def stock_frame(pocket, h):
    """(x0, y0, nx, ny): the pixel frame of a level's stocks, the pocket's box grown by 2 h (origin mm,
    pixel counts; pixel centre ``x0 + (i + 0.5) h``)."""
    x0, y0, x1, y1 = pocket.bounds
    m = 2 * h
    return x0 - m, y0 - m, int(math.ceil((x1 - x0 + 2 * m) / h)), int(math.ceil((y1 - y0 + 2 * m) / h))


def rapid_radii(r, h):
    """(r_rapid, r_capsule) mm of the rapid stock (see :class:`Grid`): its discs are cut with radius
    r - h/sqrt(2), and a chord with no material pixel of it within r + h/sqrt(2) is a proven G0."""
    return r - h / math.sqrt(2.0), r + h / math.sqrt(2.0) * (1 + 1e-9)


class PassStep(NamedTuple):
    """How a pass steps (:func:`pass_kernel`'s settings that stay fixed for a plan): ``ds`` step (mm),
    ``lag`` the look-back of the engagement sampling (mm), ``n_samp`` samples on the arc, ``turn``
    the largest heading change a step (rad)."""

    ds: float
    lag: float
    n_samp: int
    turn: float


class Grid:
    """The planning stock ``M`` (pixels of ``h`` mm), the tool-centre mask ``A`` and, on a coarse grid
    (cells of ``hc = k h``), the distance from each cell centre to the nearest material, kept up to date
    incrementally: every change of ``M`` goes through a method that marks the changed box, and
    :meth:`free_field` recomputes the coarse field only in the window the change can affect. The field
    is capped at ``cap`` (mm): the planner only compares it with thresholds below ``cap``."""

    def __init__(self, pocket, allowed, r, h, hole, cell_mm=AdaptiveParams.coarse_cell_mm,
                 cell_max_r=AdaptiveParams.coarse_cell_max_r):
        """``cell_mm``, ``cell_max_r``: the coarse cell is about ``min(cell_mm, cell_max_r r)`` mm, a whole
        number of pixels (AdaptiveParams.coarse_cell_mm / coarse_cell_max_r, their defaults)."""
        self.r, self.h = r, h
        self.x0, self.y0, self.nx, self.ny = stock_frame(pocket, h)
        self.M = raster(pocket, self.x0, self.y0, h, self.nx, self.ny)
        # tool-centre region shrunk by h/sqrt(2): every point of a pixel whose centre it holds (what
        # inside_mask accepts) is inside the true region (a further 1e-6: centres exactly on the shrunk
        # boundary, e.g. of axis-parallel walls, are outside)
        self.A = raster(allowed.buffer(-h / math.sqrt(2.0) * (1 + 1e-6)), self.x0, self.y0, h, self.nx, self.ny)
        # the rapid stock: the same discs cut with radius r - h/sqrt(2). A pixel centre it shows as
        # clear is within r - h/sqrt(2) of a disc centre, so every point within h/sqrt(2) of it (its
        # pixel) is truly swept: a chord with no material pixel of it within r + h/sqrt(2) is
        # clear in the exact geometry too, sub-pixel cusps between passes included
        self.r_rapid, self.r_capsule = rapid_radii(r, h)
        self.Mr = self.M.copy()
        if hole is not None:
            cut_disc(self.M, self.x0, self.y0, h, hole[0], hole[1], 0.5 * hole[2], np.nan, np.nan)
            cut_disc(self.Mr, self.x0, self.y0, h, hole[0], hole[1], 0.5 * hole[2] - h / math.sqrt(2.0), np.nan, np.nan)
        # coarse grid for the free-space search
        self.k = max(1, int(round(min(cell_mm, cell_max_r * r) / h)))
        self.hc = self.k * h
        self.Ac = self.coarse(self.A).min(axis=(1, 3)) > 0
        # each cell's distance to the region's boundary (mm: to the nearest cell outside it)
        nJ, nI = self.Ac.shape
        self.dA = np.empty(self.Ac.shape)
        dist_window(~self.Ac, 0, nJ, 0, nI, 0, nJ, 0, nI, self.hc, np.inf, self.dA)
        # half-width of the tool-centre region around each cell: the largest dA within r
        c = int(math.ceil(r / self.hc))
        self.half_width = max_filter(self.dA, c)
        self.cap = r + 4.0 * self.hc + r / 30.0   # > the air test of pass_kernel at the default step r/30
        self.mat = np.zeros(self.Ac.shape, bool)
        self.D = np.empty(self.Ac.shape)
        self._dirty = (-np.inf, -np.inf, np.inf, np.inf)
        self._since, self._shadow = None, None      # see checkpoint()
        n = self.Ac.size            # Dijkstra buffers, reset after each search
        self._dist = np.full(n, np.inf)
        self._prev = -np.ones(n, np.int64)
        self._hk = np.empty(8 * n + 8)
        self._hv = np.empty(8 * n + 8, np.int64)
        self._touched = np.empty(n, np.int64)

    def coarse(self, a):
        k = self.k
        ny, nx = (a.shape[0] // k) * k, (a.shape[1] // k) * k
        return a[:ny, :nx].reshape(ny // k, k, nx // k, k)

    # -- every change of M goes through these -------------------------------------------------
    def touch(self, P, rad):
        """Mark the box of the points P (n, 2) grown by ``rad`` mm as changed."""
        P = np.asarray(P, float).reshape(-1, 2)
        lo = P.min(axis=0) - rad
        hi = P.max(axis=0) + rad
        self._dirty = _union(self._dirty, (lo[0], lo[1], hi[0], hi[1]))
        self._since = _union(self._since, (lo[0], lo[1], hi[0], hi[1]))

    def _cut_rapid(self, P):
        cut_path(self.Mr, self.x0, self.y0, self.h, np.ascontiguousarray(P, float), self.r_rapid)

    def snapshot(self):
        """Copies of the stocks, for :meth:`restore`."""
        return self.M.copy(), self.Mr.copy()

    def run_pass(self, start, heading, target, step: PassStep, max_steps, air_stop, turn_right, max_len,
                 guard, air_eng=0.0, check_rapids=False):
        """:func:`pass_kernel` on these stocks from ``start`` (x, y) mm (every argument given: numba's
        fast dispatch); ``step``: the plan's :class:`PassStep`; ``check_rapids``: mark the air steps
        whose chord is clear on the rapid stock."""
        ds, lag, n_samp, turn = step
        P, removed, reason, E, F = pass_kernel(
            self.M, self.A, self.Mr, self.free_field()[0],
            (float(self.x0), float(self.y0), float(self.h), float(self.hc)),
            (float(self.r), float(self.r_rapid), float(self.r_capsule) if check_rapids else 0.0),
            (float(start[0]), float(start[1]), float(heading)),
            (float(target), float(guard), float(GUARD_LEVEL), int(n_samp), float(air_eng)),
            (float(ds), float(lag), int(max_steps), float(air_stop), float(turn), float(turn_right), float(max_len)))
        self.touch(P, self.r + self.h)
        return P, removed, reason, E, F

    def cut_path(self, P, P_rapid=None):
        """Cut discs at the points ``P`` (n, 2) mm into the planning stock and at ``P_rapid`` (default
        ``P``: points the tool truly passes) into the rapid stock."""
        cut_path(self.M, self.x0, self.y0, self.h, P, self.r)
        self._cut_rapid(P if P_rapid is None else P_rapid)
        self.touch(P, self.r + self.h)

    def replay(self, P, lag, n_samp):
        E = replay(self.M, self.x0, self.y0, self.h, self.r, P, float(lag), int(n_samp), GUARD_LEVEL)[0]
        self._cut_rapid(P)
        self.touch(P, self.r + self.h)
        return E

    def restore(self, snap):
        """Set the stocks back to a :meth:`snapshot`."""
        self.M[:] = snap[0]
        self.Mr[:] = snap[1]
        self._dirty = self._since = (-np.inf, -np.inf, np.inf, np.inf)

    def window(self, box):
        """Pixel slices (rows, columns) of the box (x0, y0, x1, y1) mm, one pixel grown, clipped."""
        if box is None:
            return slice(0, 0), slice(0, 0)
        h = self.h
        i0 = 0 if not np.isfinite(box[0]) else max(int(math.floor((box[0] - self.x0) / h)) - 1, 0)
        j0 = 0 if not np.isfinite(box[1]) else max(int(math.floor((box[1] - self.y0) / h)) - 1, 0)
        i1 = self.nx if not np.isfinite(box[2]) else min(int(math.ceil((box[2] - self.x0) / h)) + 2, self.nx)
        j1 = self.ny if not np.isfinite(box[3]) else min(int(math.ceil((box[3] - self.y0) / h)) + 2, self.ny)
        return slice(j0, max(j1, j0)), slice(i0, max(i1, i0))

    def checkpoint(self):
        """Remember the stocks as they are now, for :meth:`rollback`. Cheap: a shadow copy of both
        stocks is kept, and only the window changed since the last checkpoint (every change goes
        through :meth:`touch`) is copied into it."""
        if self._shadow is None:
            self._shadow = (self.M.copy(), self.Mr.copy())
        else:
            w = self.window(self._since)
            self._shadow[0][w] = self.M[w]
            self._shadow[1][w] = self.Mr[w]
        self._since = None

    def rapid_free_at_checkpoint(self, a, b) -> bool:
        """Whether the chord a -> b (x, y) mm was a proven G0 on the rapid stock as it was at the last
        :meth:`checkpoint` (no pixel within ``r_capsule`` of it: :func:`capsule_free`)."""
        Mr = self.Mr if self._shadow is None else self._shadow[1]
        return bool(capsule_free(Mr, self.x0, self.y0, self.h, float(a[0]), float(a[1]), float(b[0]), float(b[1]),
                                 self.r_capsule))

    def taken_since_checkpoint(self) -> np.ndarray:
        """(m, 2) centres (mm) of the planning-stock pixels removed since the last :meth:`checkpoint`."""
        w = self.window(self._since)
        J, I = np.nonzero((self._shadow[0][w] != 0) & (self.M[w] == 0))
        return np.c_[self.x0 + (I + w[1].start + 0.5) * self.h, self.y0 + (J + w[0].start + 0.5) * self.h]

    def rollback(self):
        """Set the stocks back to the last :meth:`checkpoint` (only the window changed since)."""
        box = self._since
        w = self.window(box)
        self.M[w] = self._shadow[0][w]
        self.Mr[w] = self._shadow[1][w]
        if box is not None:
            self._dirty = _union(self._dirty, box)
        self._since = None

    def free_field(self):
        """(distance from each coarse cell centre to the nearest material, mm, capped at ``cap``;
        coarse tool-centre mask). Read-only views: copy before changing them."""
        d = self._dirty
        if d is not None:
            hc, cap = self.hc, self.cap
            nJ, nI = self.mat.shape
            c = int(math.ceil(cap / hc)) + 1
            J0 = max(int(math.floor((d[1] - self.y0) / hc)) - 1, 0) if np.isfinite(d[1]) else 0
            I0 = max(int(math.floor((d[0] - self.x0) / hc)) - 1, 0) if np.isfinite(d[0]) else 0
            J1 = min(int(math.ceil((d[3] - self.y0) / hc)) + 1, nJ) if np.isfinite(d[3]) else nJ
            I1 = min(int(math.ceil((d[2] - self.x0) / hc)) + 1, nI) if np.isfinite(d[2]) else nI
            if J0 < J1 and I0 < I1:
                coarse_any(self.M, self.k, self.mat, J0, J1, I0, I1)
                # the cells within cap of the change, from the material within cap of those cells
                wj0, wj1, wi0, wi1 = max(J0 - c, 0), min(J1 + c, nJ), max(I0 - c, 0), min(I1 + c, nI)
                ej0, ej1, ei0, ei1 = max(wj0 - c, 0), min(wj1 + c, nJ), max(wi0 - c, 0), min(wi1 + c, nI)
                dist_window(self.mat, ej0, ej1, ei0, ei1, wj0, wj1, wi0, wi1, hc, cap, self.D)
            self._dirty = None
        return self.D, self.Ac

    def cell(self, x, y):
        return (int((y - self.y0) // self.hc), int((x - self.x0) // self.hc))

    def centre(self, j, i):
        return (self.x0 + (i + 0.5) * self.hc, self.y0 + (j + 0.5) * self.hc)

    def route(self, cur, r_free, band_hi=-np.inf, banned=None, cell=(-1, -1)):
        """Shortest 8-neighbour route (cells) from the cell of ``cur`` through free cells (in the
        tool-centre region, D >= r_free; ``cell`` counts as free) to the nearest goal cell (free with
        D < band_hi and not banned, or ``cell``); starting off the free set, first to the nearest free
        cell within 2 r. None when no goal is reachable."""
        D, Ac = self.free_field()
        if banned is None:
            banned = np.zeros((1, 1), bool)
        route = dijkstra(D, Ac, banned, float(r_free), float(band_hi), (int(cell[0]), int(cell[1])),
                         (float(cur[0]), float(cur[1])), (float(self.x0), float(self.y0), float(self.hc), float(self.h)),
                         2.0 * self.r, (self._dist, self._prev, self._hk, self._hv, self._touched), self.A)
        if len(route) == 1 and route[0, 0] < 0:
            return "off"        # no free cell within 2 r that a straight chord inside the region reaches
        return None if len(route) == 0 else route
