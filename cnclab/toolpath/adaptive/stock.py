"""The planning stock's compiled kernels (pixels of ``h`` mm: ``M[j, i] = 1`` material, pixel centre
``x0 + (i + 0.5) h, y0 + (j + 0.5) h``): disc cuts (:func:`cut_disc`, :func:`cut_disc_both` into the planning
and the rapid stock at once, :func:`cut_path`), the bilinear material fraction (:func:`material_fraction`),
capsule and segment tests (:func:`capsule_free`, :func:`segment_inside`), rasterisation of the
pocket and of the tool-centre region (:func:`raster`), the coarse distance field to the material
(:func:`coarse_any`, :func:`dist_window`), 8-connected labels of remnants (:func:`label8`,
:func:`component_discs`) and polyline resampling. Units: mm.
"""
from __future__ import annotations

import math

import numpy as np
import shapely
from numba import njit


# ------------------------------------------------------------------------------------------------
# compiled kernels (pixel stock: M[j, i] = 1 material, pixel centre x0 + (i + 0.5) h, y0 + (j + 0.5) h)
# ------------------------------------------------------------------------------------------------
@njit(cache=True)
def cut_disc(M, x0, y0, h, cx, cy, r, pcx, pcy):
    """Clear the pixels whose centre lies within ``r`` of (cx, cy); the area removed (mm^2).

    (pcx, pcy): the centre of the disc cut just before on the same path (NaN: none; always given: an
    omitted NaN default never matches numba's cache index, NaN != NaN). Its pixels are
    already clear, so each row only scans the part of its span outside that disc's span (the same
    span arithmetic: exactly the pixels a full scan would clear)."""
    ny, nx = M.shape
    j0 = max(int(math.floor((cy - r - y0) / h - 0.5)), 0)
    j1 = min(int(math.ceil((cy + r - y0) / h - 0.5)), ny - 1)
    has_prev = pcx == pcx
    rem = 0
    for j in range(j0, j1 + 1):
        yc = y0 + (j + 0.5) * h
        yy = yc - cy
        w2 = r * r - yy * yy
        if w2 < 0:
            continue
        w = math.sqrt(w2)
        i0 = max(int(math.ceil((cx - w - x0) / h - 0.5)), 0)
        i1 = min(int(math.floor((cx + w - x0) / h - 0.5)), nx - 1)
        p0 = 1
        p1 = 0
        if has_prev:
            vy = yc - pcy
            v2 = r * r - vy * vy
            if v2 >= 0:
                v = math.sqrt(v2)
                p0 = max(int(math.ceil((pcx - v - x0) / h - 0.5)), 0)
                p1 = min(int(math.floor((pcx + v - x0) / h - 0.5)), nx - 1)
        if p0 > p1:
            a0, a1, b0, b1 = i0, i1, 1, 0
        else:
            a0, a1, b0, b1 = i0, min(i1, p0 - 1), max(i0, p1 + 1), i1
        for i in range(a0, a1 + 1):
            if M[j, i]:
                M[j, i] = 0
                rem += 1
        for i in range(b0, b1 + 1):
            if M[j, i]:
                M[j, i] = 0
                rem += 1
    return rem * h * h


@njit(cache=True)
def cut_disc_both(M, Mr, x0, y0, h, cx, cy, r, rr, span, rows):
    """:func:`cut_disc` of the disc (cx, cy, r) into M and of (cx, cy, rr) into Mr (rr <= r) in one pass over
    the rows, each row scanning only what lies outside the previous disc's span there. ``span`` (ny, 4)
    int64 holds each row's spans of the previous disc (M then Mr; empty: 1, 0) and ``rows`` (2,) its
    row range (empty: 1, 0); both are updated to this disc. The area removed from M (mm^2)."""
    ny, nx = M.shape
    j0 = max(int(math.floor((cy - r - y0) / h - 0.5)), 0)
    j1 = min(int(math.ceil((cy + r - y0) / h - 0.5)), ny - 1)
    p0 = rows[0]
    p1 = rows[1]
    rem = 0
    for j in range(j0, j1 + 1):
        yy = y0 + (j + 0.5) * h - cy
        w2 = r * r - yy * yy
        if w2 < 0:
            a0, a1, b0, b1 = 1, 0, 1, 0
        else:
            w = math.sqrt(w2)
            a0 = max(int(math.ceil((cx - w - x0) / h - 0.5)), 0)
            a1 = min(int(math.floor((cx + w - x0) / h - 0.5)), nx - 1)
            v2 = rr * rr - yy * yy
            if v2 < 0:
                b0, b1 = 1, 0
            else:
                v = math.sqrt(v2)
                b0 = max(int(math.ceil((cx - v - x0) / h - 0.5)), 0)
                b1 = min(int(math.floor((cx + v - x0) / h - 0.5)), nx - 1)
        if p0 <= j <= p1:
            q0, q1, s0, s1 = span[j, 0], span[j, 1], span[j, 2], span[j, 3]
        else:
            q0, q1, s0, s1 = 1, 0, 1, 0
        # M: the span minus the previous span
        for i in range(a0, min(a1, q0 - 1) + 1 if q0 <= q1 else a1 + 1):
            if M[j, i]:
                M[j, i] = 0
                rem += 1
        if q0 <= q1:
            for i in range(max(a0, q1 + 1), a1 + 1):
                if M[j, i]:
                    M[j, i] = 0
                    rem += 1
        for i in range(b0, min(b1, s0 - 1) + 1 if s0 <= s1 else b1 + 1):
            Mr[j, i] = 0
        if s0 <= s1:
            for i in range(max(b0, s1 + 1), b1 + 1):
                Mr[j, i] = 0
        span[j, 0] = a0
        span[j, 1] = a1
        span[j, 2] = b0
        span[j, 3] = b1
    # rows of the previous disc outside this one's range keep stale spans: mark the range
    rows[0] = j0
    rows[1] = j1
    return rem * h * h


@njit(cache=True)
def material_fraction(M, x0, y0, h, x, y):
    """Bilinear material fraction at (x, y) (outside the grid: no material)."""
    ny, nx = M.shape
    fx = (x - x0) / h - 0.5
    fy = (y - y0) / h - 0.5
    i = int(math.floor(fx))
    j = int(math.floor(fy))
    tx = fx - i
    ty = fy - j
    s = 0.0
    for dj in range(2):
        for di in range(2):
            jj = j + dj
            ii = i + di
            if 0 <= jj < ny and 0 <= ii < nx and M[jj, ii]:
                s += (tx if di else 1 - tx) * (ty if dj else 1 - ty)
    return s


@njit(cache=True, inline="always")
def capsule_window(M, x0, y0, h, ax, ay, bx, by, rr):
    """(i0, i1, j0, j1): the pixel columns i0..i1 and rows j0..j1 (inclusive, clipped to ``M``) of the
    box of the segment (a, b) grown by ``rr`` mm."""
    ny, nx = M.shape
    i0 = max(int(math.floor((min(ax, bx) - rr - x0) / h)), 0)
    i1 = min(int(math.ceil((max(ax, bx) + rr - x0) / h)), nx - 1)
    j0 = max(int(math.floor((min(ay, by) - rr - y0) / h)), 0)
    j1 = min(int(math.ceil((max(ay, by) + rr - y0) / h)), ny - 1)
    return i0, i1, j0, j1


@njit(cache=True, inline="always")
def capsule_row(x0, h, ax, ay, dx, dy, rr, py, i0, i1):
    """(i_lo, i_hi): the pixel columns of row centre ``py`` (mm) whose centres may lie within ``rr``
    of the segment a -> a + (dx, dy), within i0..i1 (i_lo > i_hi: none). A superset: only the
    segment's points with |y - py| < rr can be that near, and their x range grown by rr bounds the
    row's pixels (one column of slack each side)."""
    if dy == 0.0:
        if abs(ay - py) >= rr:
            return 1, 0
        t_lo, t_hi = 0.0, 1.0
    else:
        ta = (py - rr - ay) / dy
        tb = (py + rr - ay) / dy
        t_lo = max(min(ta, tb), 0.0)
        t_hi = min(max(ta, tb), 1.0)
        if t_lo > t_hi:
            return 1, 0
    xa = ax + t_lo * dx
    xb = ax + t_hi * dx
    lo = max(int(math.floor((min(xa, xb) - rr - x0) / h - 0.5)) - 1, i0)
    hi = min(int(math.ceil((max(xa, xb) + rr - x0) / h - 0.5)) + 1, i1)
    return lo, hi


#: a label image for :func:`capsule_free_of` when no component is set aside (never indexed: ``skip`` 0)
_NO_LABELS = np.zeros((1, 1), np.int32)


@njit(cache=True)
def capsule_free_of(M, labels, skip, x0, y0, h, ax, ay, bx, by, rr):
    """True when no material pixel centre lies within ``rr`` of the segment (a, b), the pixels of
    component ``skip`` of the label image ``labels`` (same shape as ``M``; :func:`label8`) set aside
    (``skip`` 0: none, ``labels`` not read). Each row is scanned only over the capsule's span in it
    (:func:`capsule_row`), not over the segment's whole box."""
    i0, i1, j0, j1 = capsule_window(M, x0, y0, h, ax, ay, bx, by, rr)
    dx = bx - ax
    dy = by - ay
    L2 = dx * dx + dy * dy
    for j in range(j0, j1 + 1):
        py = y0 + (j + 0.5) * h
        lo, hi = capsule_row(x0, h, ax, ay, dx, dy, rr, py, i0, i1)
        for i in range(lo, hi + 1):
            if M[j, i] and (skip == 0 or labels[j, i] != skip):
                px = x0 + (i + 0.5) * h
                t = 0.0 if L2 == 0.0 else ((px - ax) * dx + (py - ay) * dy) / L2
                t = min(max(t, 0.0), 1.0)
                ex = ax + t * dx - px
                ey = ay + t * dy - py
                if ex * ex + ey * ey < rr * rr:
                    return False
    return True


@njit(cache=True)
def capsule_free(M, x0, y0, h, ax, ay, bx, by, rr):
    """True when no material pixel centre lies within ``rr`` of the segment (a, b): the tool disc
    (radius < rr - h/sqrt(2)) swept along it removes nothing (:func:`capsule_free_of`, no component
    set aside)."""
    return capsule_free_of(M, _NO_LABELS, 0, x0, y0, h, ax, ay, bx, by, rr)


@njit(cache=True)
def material_within(M, x0, y0, h, P, r):
    """Area (mm^2) of the material pixels of ``M`` whose centre lies within ``r`` (strictly) of any
    of the points P (n, 2) mm: each point's disc scanned row by row over its chord (one pixel of
    slack each side, then the exact test), each pixel counted once. The same pixels as the pairwise
    test of every material pixel against every point, without its (pixels x points) array."""
    ny, nx = M.shape
    if P.shape[0] == 0:
        return 0.0
    j0 = max(int(math.floor((P[:, 1].min() - r - y0) / h)) - 1, 0)
    j1 = min(int(math.ceil((P[:, 1].max() + r - y0) / h)) + 1, ny - 1)
    i0 = max(int(math.floor((P[:, 0].min() - r - x0) / h)) - 1, 0)
    i1 = min(int(math.ceil((P[:, 0].max() + r - x0) / h)) + 1, nx - 1)
    if j1 < j0 or i1 < i0:
        return 0.0
    seen = np.zeros((j1 - j0 + 1, i1 - i0 + 1), np.bool_)
    rr = r * r
    n = 0
    for k in range(P.shape[0]):
        px = P[k, 0]
        py = P[k, 1]
        ja = max(int(math.floor((py - r - y0) / h - 0.5)) - 1, j0)
        jb = min(int(math.ceil((py + r - y0) / h - 0.5)) + 1, j1)
        for j in range(ja, jb + 1):
            dy = y0 + (j + 0.5) * h - py
            w2 = rr - dy * dy
            if w2 < 0.0:
                continue
            w = math.sqrt(w2)
            ia = max(int(math.floor((px - w - x0) / h - 0.5)) - 1, i0)
            ib = min(int(math.ceil((px + w - x0) / h - 0.5)) + 1, i1)
            for i in range(ia, ib + 1):
                if M[j, i] and not seen[j - j0, i - i0]:
                    dx = x0 + (i + 0.5) * h - px
                    if dx * dx + dy * dy < rr:
                        seen[j - j0, i - i0] = True
                        n += 1
    return n * h * h


@njit(cache=True)
def cut_path(M, x0, y0, h, P, r):
    rem = 0.0
    pcx = np.nan
    pcy = np.nan
    for k in range(P.shape[0]):
        rem += cut_disc(M, x0, y0, h, P[k, 0], P[k, 1], r, pcx, pcy)
        pcx = P[k, 0]
        pcy = P[k, 1]
    return rem


@njit(cache=True)
def raster_edges(E, x0, y0, h, nx, ny):
    """Pixel mask (ny, nx) uint8 of the polygon with edges E (m, 4: x1, y1, x2, y2, every ring of
    every part): pixel centres x0 + (i + 1/2) h, y0 + (j + 1/2) h inside by the even-odd rule (a
    scanline fill: the same pixels as a point-in-polygon test of the centres, up to centres exactly
    on an edge)."""
    out = np.zeros((ny, nx), np.uint8)
    xs = np.empty(E.shape[0])
    for j in range(ny):
        y = y0 + (j + 0.5) * h
        m = 0
        for k in range(E.shape[0]):
            ya = E[k, 1]
            yb = E[k, 3]
            if (ya <= y < yb) or (yb <= y < ya):
                xs[m] = E[k, 0] + (y - ya) * (E[k, 2] - E[k, 0]) / (yb - ya)
                m += 1
        if m < 2:
            continue
        xx = np.sort(xs[:m])
        for q in range(0, m - 1, 2):
            i0 = max(int(math.ceil((xx[q] - x0) / h - 0.5)), 0)
            i1 = min(int(math.ceil((xx[q + 1] - x0) / h - 0.5)), nx)
            for i in range(i0, i1):
                out[j, i] = 1
    return out


def raster(poly, x0, y0, h, nx, ny):
    """:func:`raster_edges` of a shapely Polygon/MultiPolygon."""
    rings = []
    for part in shapely.get_parts(poly):
        rings += [part.exterior, *part.interiors]
    E = np.concatenate([np.c_[c[:-1], c[1:]] for c in (np.asarray(r.coords)[:, :2] for r in rings)]) if rings \
        else np.zeros((0, 4))
    return raster_edges(np.ascontiguousarray(E, float), float(x0), float(y0), float(h), int(nx), int(ny))


@njit(cache=True)
def coarse_any(M, k, mat, J0, J1, I0, I1):
    """mat[J, I] = any material pixel in coarse cell (J, I) (k x k pixels), for J0 <= J < J1, I0 <= I < I1."""
    for J in range(J0, J1):
        for I in range(I0, I1):
            v = False
            for j in range(J * k, J * k + k):
                for i in range(I * k, I * k + k):
                    if M[j, i]:
                        v = True
                        break
                if v:
                    break
            mat[J, I] = v


@njit(cache=True)
def dist_window(mat, ej0, ej1, ei0, ei1, wj0, wj1, wi0, wi1, hc, cap, D):
    """D[j, i] = min(cap, hc x the Euclidean distance (cells) from cell (j, i) to the nearest True
    cell of ``mat`` inside the window rows ej0:ej1, columns ei0:ei1), for the cells of the window
    wj0:wj1, wi0:wi1 (inside the first). Exact: a column scan, then the lower envelope of parabolas
    along each row (Felzenszwalb & Huttenlocher 2012, "Distance transforms of sampled functions")."""
    BIG = 1e30
    nr = wj1 - wj0
    nc = ei1 - ei0
    g = np.full((nr, nc), BIG)          # squared vertical distance to material in the column
    for c in range(nc):
        i = ei0 + c
        last = -1
        for j in range(ej0, ej1):        # downward: nearest material above
            if mat[j, i]:
                last = j
            if wj0 <= j < wj1 and last >= 0:
                g[j - wj0, c] = float((j - last) * (j - last))
        last = -1
        for j in range(ej1 - 1, ej0 - 1, -1):   # upward: nearest material below
            if mat[j, i]:
                last = j
            if wj0 <= j < wj1 and last >= 0:
                d = float((last - j) * (last - j))
                if d < g[j - wj0, c]:
                    g[j - wj0, c] = d
    v = np.empty(nc, np.int64)
    z = np.empty(nc + 1)
    for rr in range(nr):
        f = g[rr]
        k = -1
        for q in range(nc):
            if f[q] >= BIG:
                continue
            if k < 0:
                k = 0
                v[0] = q
                z[0] = -BIG
                z[1] = BIG
                continue
            while True:
                p = v[k]
                sx = ((f[q] + q * q) - (f[p] + p * p)) / (2.0 * (q - p))
                if sx <= z[k]:
                    k -= 1
                    if k < 0:
                        break
                else:
                    break
            k += 1
            v[k] = q
            z[k] = -BIG if k == 0 else sx
            z[k + 1] = BIG
        j = wj0 + rr
        if k < 0:
            for i in range(wi0, wi1):
                D[j, i] = cap
            continue
        kk = 0
        for i in range(wi0, wi1):
            p = i - ei0
            while z[kk + 1] < p:
                kk += 1
            q = v[kk]
            d = math.sqrt((p - q) * (p - q) + f[q]) * hc
            D[j, i] = d if d < cap else cap


@njit(cache=True)
def label8(M):
    """Connected components of the nonzero pixels of M (8-neighbourhood): (labels (ny, nx) int32, 0 for
    empty pixels and 1..n for the components in row order of their first pixel, n)."""
    ny, nx = M.shape
    lab = np.zeros((ny, nx), np.int32)
    stack = np.empty(ny * nx, np.int64)
    n = 0
    for j0 in range(ny):
        for i0 in range(nx):
            if M[j0, i0] == 0 or lab[j0, i0] != 0:
                continue
            n += 1
            lab[j0, i0] = n
            top = 0
            stack[0] = j0 * nx + i0
            top = 1
            while top > 0:
                top -= 1
                v = stack[top]
                j = v // nx
                i = v % nx
                for dj in range(-1, 2):
                    for di in range(-1, 2):
                        jj = j + dj
                        ii = i + di
                        if 0 <= jj < ny and 0 <= ii < nx and M[jj, ii] != 0 and lab[jj, ii] == 0:
                            lab[jj, ii] = n
                            stack[top] = jj * nx + ii
                            top += 1
    return lab, n


@njit(cache=True)
def component_discs(lab, n, x0, y0, h):
    """For components 1..n of a label image (pixels of h mm, origin x0, y0): the centroid of their pixel
    centres and the largest distance of a pixel centre from it (mm); arrays (n + 1,), index 0 unused
    (radius inf)."""
    ny, nx = lab.shape
    sx = np.zeros(n + 1)
    sy = np.zeros(n + 1)
    cnt = np.zeros(n + 1)
    for j in range(ny):
        for i in range(nx):
            k = lab[j, i]
            if k:
                sx[k] += x0 + (i + 0.5) * h
                sy[k] += y0 + (j + 0.5) * h
                cnt[k] += 1.0
    cx = sx / np.maximum(cnt, 1.0)
    cy = sy / np.maximum(cnt, 1.0)
    rad = np.zeros(n + 1)
    rad[0] = np.inf
    for j in range(ny):
        for i in range(nx):
            k = lab[j, i]
            if k:
                d = math.hypot(x0 + (i + 0.5) * h - cx[k], y0 + (j + 0.5) * h - cy[k])
                if d > rad[k]:
                    rad[k] = d
    return cx, cy, rad


def max_filter(a, c):
    """The largest value of ``a`` (2-D) within c cells along each axis (a (2c+1)^2 window clipped at the
    edges; scipy.ndimage.maximum_filter's result, without importing scipy)."""
    from numpy.lib.stride_tricks import sliding_window_view

    w = 2 * c + 1
    a = np.pad(a, ((c, c), (0, 0)), mode="edge")
    a = sliding_window_view(a, w, axis=0).max(axis=-1)
    a = np.pad(a, ((0, 0), (c, c)), mode="edge")
    return sliding_window_view(a, w, axis=1).max(axis=-1)


@njit(cache=True)
def inside_mask(Amask, x0, y0, h, x, y):
    ny, nx = Amask.shape
    i = int(math.floor((x - x0) / h))
    j = int(math.floor((y - y0) / h))
    if i < 0 or j < 0 or i >= nx or j >= ny:
        return False
    return Amask[j, i] != 0


@njit(cache=True)
def segment_inside(A, x0, y0, h, ax, ay, bx, by, skip):
    """True when every point of the segment a-b sampled every h/2 lies in a pixel of the mask ``A``,
    but for the first ``skip`` mm (2 h where the start may lie on the true wall -- a finishing lap ends
    there -- outside the mask, which is the region shrunk by h/sqrt(2))."""
    L = math.hypot(bx - ax, by - ay)
    n = max(2, int(math.ceil(L / (0.5 * h))) + 1)
    for k in range(n):
        t = k / (n - 1)
        if t * L < skip:
            continue
        if not inside_mask(A, x0, y0, h, ax + t * (bx - ax), ay + t * (by - ay)):
            return False
    return True
