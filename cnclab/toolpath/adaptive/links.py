"""Links at depth and the proofs that let them be rapids (see the package docstring, "Links"):
the Dijkstra search over the coarse free cells (:func:`dijkstra`), the chord shortcut through
the free set (:func:`shortcut`, :func:`chord_free`), the rapid proofs on the rapid stock
(:func:`mark_free`, :func:`chain_clear`, :func:`bow_runs`: an air run is a G0 only where no
material pixel lies within r + h/sqrt(2) of its chord) and the feed legs off a wall
(:func:`rapid_legs`). Units: mm.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .stock import capsule_free, capsule_row, capsule_window, segment_inside


@njit(cache=True)
def mark_free(Mr, x0, y0, h, P, E, F, k0, k1, air_eng, r_capsule):
    """F[k] = the chord P[k-1] -> P[k] has no pixel of ``Mr`` within ``r_capsule``, for the air steps
    (E[k] < air_eng) k0 <= k < k1."""
    for k in range(max(k0, 1), k1):
        if E[k] < air_eng:
            F[k] = capsule_free(Mr, x0, y0, h, P[k - 1, 0], P[k - 1, 1], P[k, 0], P[k, 1], r_capsule)


@njit(cache=True)
def chain_clear(Mr, Amask, x0, y0, h, Q, r_capsule):
    """Every chord of the polyline Q (m, 2) has no pixel of ``Mr`` within ``r_capsule`` and every
    point of it, sampled every h/2, lies in the tool-centre mask (:func:`segment_inside`)."""
    for k in range(1, Q.shape[0]):
        ax = Q[k - 1, 0]
        ay = Q[k - 1, 1]
        bx = Q[k, 0]
        by = Q[k, 1]
        if not segment_inside(Amask, x0, y0, h, ax, ay, bx, by, 0.0):
            return False
        if not capsule_free(Mr, x0, y0, h, ax, ay, bx, by, r_capsule):
            return False
    return True


@njit(cache=True)
def bow_runs(Mr, Amask, geo, P, E, F, k0, k1, air_eng, r_capsule, delta, min_steps):
    """For the air steps k0 <= k < k1 (engagement < ``air_eng``) not proven free one by one: a run of
    at least ``min_steps`` of them (steps a..b, from P[a-1] to P[b]) that slides along the last
    cut boundary (a wall-following pass left its skin there: the rapid stock keeps a band of it
    within r + h/sqrt(2) of the same line, so no chord on that line is ever proven) is moved
    ``delta`` mm to its left, away from the material on the pass's right: P[a..b-1] shifted. When
    every chord of the shifted points and the end points is proven as in :func:`mark_free` and
    inside the mask, its inner steps become G0 (``F``) and the first and last steps stay feed links
    (the legs of ``delta`` off the line and back). Called before the run's discs are cut: the rapid
    stock holds what each step meets; the shifted discs remove nothing (proven), the discs at the
    shifted points that the pass cuts later remove nothing either. ``geo``: (x0, y0, h) the pixel
    grid's origin and pixel size (mm)."""
    x0, y0, h = geo
    k = max(k0, 1)
    while k < k1:
        if not (E[k] < air_eng) or F[k]:
            k += 1
            continue
        a = k
        while k < k1 and E[k] < air_eng and not F[k]:
            k += 1
        b = k - 1
        if b - a + 1 < min_steps:
            continue
        m = b - a                      # points P[a..b-1] shifted
        Q = np.empty((m + 2, 2))
        Q[0, 0] = P[a - 1, 0]
        Q[0, 1] = P[a - 1, 1]
        Q[m + 1, 0] = P[b, 0]
        Q[m + 1, 1] = P[b, 1]
        for q in range(m):
            i = a + q
            tx = P[i + 1, 0] - P[i - 1, 0]
            ty = P[i + 1, 1] - P[i - 1, 1]
            L = math.hypot(tx, ty)
            if L == 0.0:
                return
            Q[q + 1, 0] = P[i, 0] - delta * ty / L
            Q[q + 1, 1] = P[i, 1] + delta * tx / L
        if chain_clear(Mr, Amask, x0, y0, h, Q[1:m + 1], r_capsule):
            for q in range(m):
                P[a + q, 0] = Q[q + 1, 0]
                P[a + q, 1] = Q[q + 1, 1]
            for q in range(a + 1, b):
                F[q] = True


@njit(cache=True)
def _start_cell(D, Ac, r_free, goal, start, geo, reach, A):
    """The coarse cell a search from ``start`` (x, y) mm begins at: its own when free (Ac and D >=
    r_free, or ``goal``), else the nearest free cell (first in row order among equals) within
    ``reach`` mm whose centre a straight chord inside the fine tool-centre mask ``A`` reaches;
    (j, i), or (-1, -1) when none. ``geo``: (x0, y0, hc, h) grid origin, cell and pixel size (mm)."""
    ny, nx = D.shape
    x0, y0, hc, h = geo
    cx, cy = start
    gj, gi = goal
    j0 = min(max(int((cy - y0) // hc), 0), ny - 1)
    i0 = min(max(int((cx - x0) // hc), 0), nx - 1)
    if (Ac[j0, i0] and D[j0, i0] >= r_free) or (j0 == gj and i0 == gi):
        return j0, i0
    jlo = max(int(math.floor((cy - reach - y0) / hc)) - 1, 0)
    jhi = min(int(math.ceil((cy + reach - y0) / hc)) + 1, ny - 1)
    size = max(jhi - jlo + 1, 0) * nx
    cand = np.empty(size)
    cj = np.empty(size, np.int64)
    ci = np.empty(size, np.int64)
    m = 0
    for j in range(jlo, jhi + 1):
        ycc = y0 + (j + 0.5) * hc
        for i in range(nx):
            if (Ac[j, i] and D[j, i] >= r_free) or (j == gj and i == gi):
                xcc = x0 + (i + 0.5) * hc
                d2 = (xcc - cx) ** 2 + (ycc - cy) ** 2
                if d2 <= reach * reach:
                    cand[m] = d2
                    cj[m] = j
                    ci[m] = i
                    m += 1
    cand = cand[:m]
    for q in np.argsort(cand, kind="mergesort"):
        if segment_inside(A, x0, y0, h, cx, cy, x0 + (ci[q] + 0.5) * hc, y0 + (cj[q] + 0.5) * hc, 2.0 * h):
            return cj[q], ci[q]
    return -1, -1


@njit(cache=True)
def _heap_pop(hk, hv, n):
    """Pop the least key of the binary heap hk/hv of ``n`` entries: (key, value); the heap then holds n - 1."""
    d = hk[0]
    v = hv[0]
    n -= 1
    hk[0] = hk[n]
    hv[0] = hv[n]
    p = 0
    while True:
        c = 2 * p + 1
        if c >= n:
            break
        if c + 1 < n and hk[c + 1] < hk[c]:
            c += 1
        if hk[c] < hk[p]:
            hk[c], hk[p] = hk[p], hk[c]
            hv[c], hv[p] = hv[p], hv[c]
            p = c
        else:
            break
    return d, v


@njit(cache=True)
def _heap_push(hk, hv, n, key, val):
    """Push (key, val) onto the binary heap hk/hv of ``n`` entries (it then holds n + 1)."""
    hk[n] = key
    hv[n] = val
    c = n
    while c > 0:
        p = (c - 1) // 2
        if hk[c] < hk[p]:
            hk[c], hk[p] = hk[p], hk[c]
            hv[c], hv[p] = hv[p], hv[c]
            c = p
        else:
            break


@njit(cache=True)
def _route_to(prev, found, nx):
    """The cells (n, 2) from the search's start to ``found`` (flat index) along ``prev``."""
    m = 0
    v = found
    while v >= 0:
        m += 1
        v = prev[v]
    out = np.empty((m, 2), np.int64)
    v = found
    for k in range(m - 1, -1, -1):
        out[k, 0] = v // nx
        out[k, 1] = v % nx
        v = prev[v]
    return out


@njit(cache=True, inline="always")
def _octile(j, i, gj, gi):
    """The 8-neighbour route length (cells; diagonal steps 1.4142) from (j, i) to (gj, gi) with no obstacle."""
    a = abs(j - gj)
    b = abs(i - gi)
    return max(a, b) - min(a, b) + 1.4142 * min(a, b)


@njit(cache=True)
def dijkstra(D, Ac, banned, r_free, band_hi, goal, start, geo, reach, buf, A):
    """8-neighbour Dijkstra (binary heap, lazy deletion) over the free cells (Ac and D >= r_free, or
    the cell ``goal`` (j, i)) from the cell of ``start`` (x, y) mm (off the free set: from the nearest
    free cell centre within ``reach`` mm that a straight chord from it inside the fine tool-centre mask
    ``A`` reaches, :func:`_start_cell`; none: [[-1, -1]]) to the nearest goal cell (free, and D <
    band_hi and not banned, or ``goal``); the route as (n, 2) cell indices (empty when none).
    ``geo``: (x0, y0, hc, h) grid origin, coarse cell and pixel size (mm); ``buf``: (dist, prev, hk,
    hv, touched) work arrays, ``dist``/``prev`` all inf/-1 on entry and left so (the cells touched
    are reset). With no goal band (``band_hi`` -inf) the one goal is ``goal`` and the search is A*
    (the octile distance to it, exact for these edge weights, orders the heap): a shortest route,
    found without spreading over the whole free set."""
    ny, nx = D.shape
    dist, prev, hk, hv, touched = buf
    gj, gi = goal
    nb = banned.shape[0] > 1
    astar = band_hi == -np.inf and gj >= 0
    j0, i0 = _start_cell(D, Ac, r_free, goal, start, geo, reach, A)
    if j0 < 0:
        return np.full((1, 2), -1, np.int64)     # no free cell reachable by a straight chord
    s0 = j0 * nx + i0
    dist[s0] = 0.0
    touched[0] = s0
    nt = 1
    hk[0] = 0.0
    hv[0] = s0
    n = np.int64(1)        # int64 from the start: _heap_pop compiles once
    dj = (-1, -1, -1, 0, 0, 1, 1, 1)
    di = (-1, 0, 1, -1, 1, -1, 0, 1)
    ww = (1.4142, 1.0, 1.4142, 1.0, 1.0, 1.4142, 1.0, 1.4142)
    found = -1
    while n > 0:
        key, v = _heap_pop(hk, hv, n)
        n -= 1
        j = v // nx
        i = v % nx
        d = dist[v]
        if key > d + (_octile(j, i, gj, gi) if astar else 0.0) + 1e-9:
            continue            # a stale entry (lazy deletion)
        if (j == gj and i == gi) or (D[j, i] < band_hi and not (nb and banned[j, i])):
            found = v
            break
        for q in range(8):
            jj = j + dj[q]
            ii = i + di[q]
            if 0 <= jj < ny and 0 <= ii < nx and ((Ac[jj, ii] and D[jj, ii] >= r_free) or (jj == gj and ii == gi)):
                u = jj * nx + ii
                nd = d + ww[q]
                if nd < dist[u]:
                    if dist[u] == np.inf:
                        touched[nt] = u
                        nt += 1
                    dist[u] = nd
                    prev[u] = v
                    _heap_push(hk, hv, n, nd + (_octile(jj, ii, gj, gi) if astar else 0.0), u)
                    n += 1
    out = np.empty((0, 2), np.int64) if found < 0 else _route_to(prev, found, nx)
    for t in range(nt):
        dist[touched[t]] = np.inf
        prev[touched[t]] = -1
    return out


@njit(cache=True)
def boundary_gradient(D, j, i):
    """(gx, gy): central differences of the distance field ``D`` at the cell (j, i) (one-sided at the
    grid's edges), pointing away from the material; the climb heading along the material boundary,
    material on the right, is this turned clockwise."""
    ny, nx = D.shape
    gy = D[min(j + 1, ny - 1), i] - D[max(j - 1, 0), i]
    gx = D[j, min(i + 1, nx - 1)] - D[j, max(i - 1, 0)]
    return gx, gy


@njit(cache=True)
def upstream_end(D, Ac, banned, r_free, band_hi, j, i, max_cells):
    """The upstream end of the band of pass starts through the cell (j, i): walking the goal cells
    (in ``Ac``, r_free <= D < band_hi, not banned) against the climb direction (the heading along the
    material boundary with material on the right, from D's gradient) -- 8-neighbour steps, each the
    best aligned (cosine >= 0.5) with the smoothed walking direction, no cell twice -- until no
    neighbour continues the run, or ``max_cells`` steps. A pass started there runs the whole
    boundary downstream instead of hooking off it where it began (a start beside a wall)."""
    ny, nx = D.shape
    nb = banned.shape[0] > 1
    gx, gy = boundary_gradient(D, j, i)
    g = math.hypot(gx, gy)
    if not (g > 0.0 and math.isfinite(g)):
        return j, i
    # the climb heading is the gradient turned clockwise: (gy, -gx) / g; upstream is its opposite
    ux = -gy / g
    uy = gx / g
    seen_j = np.empty(max_cells + 1, np.int64)
    seen_i = np.empty(max_cells + 1, np.int64)
    seen_j[0] = j
    seen_i[0] = i
    ns = 1
    for _ in range(max_cells):
        best = 0.5
        bj = -1
        bi = -1
        for dj in range(-1, 2):
            for di in range(-1, 2):
                if dj == 0 and di == 0:
                    continue
                jj = j + dj
                ii = i + di
                if jj < 0 or ii < 0 or jj >= ny or ii >= nx:
                    continue
                if not (Ac[jj, ii] and D[jj, ii] >= r_free and D[jj, ii] < band_hi) or (nb and banned[jj, ii]):
                    continue
                dup = False
                for q in range(ns):
                    if seen_j[q] == jj and seen_i[q] == ii:
                        dup = True
                        break
                if dup:
                    continue
                L = math.hypot(di, dj)
                c = (di * ux + dj * uy) / L
                if c > best:
                    best = c
                    bj = jj
                    bi = ii
        if bj < 0:
            break
        L = math.hypot(bi - i, bj - j)
        ux = 0.7 * ux + 0.3 * (bi - i) / L
        uy = 0.7 * uy + 0.3 * (bj - j) / L
        n = math.hypot(ux, uy)
        ux /= n
        uy /= n
        j = bj
        i = bi
        seen_j[ns] = j
        seen_i[ns] = i
        ns += 1
    return j, i


@njit(cache=True)
def chord_free(D, Ac, r_free, gj, gi, x0, y0, hc, ax, ay, bx, by):
    """True when the chord a-b stays in free coarse cells (Ac and D >= r_free, or (gj, gi)): sampled
    every hc/2, its interior samples in free cells and no sample off the grid."""
    ny, nx = D.shape
    n = max(2, int(math.ceil(math.hypot(bx - ax, by - ay) / (0.5 * hc))) + 1)
    dt = 1.0 / (n - 1)
    for k in range(n):
        t = 1.0 if k == n - 1 else k * dt
        j = int(math.floor((ay + t * (by - ay) - y0) / hc))
        i = int(math.floor((ax + t * (bx - ax) - x0) / hc))
        if j < 0 or i < 0 or j >= ny or i >= nx:
            return False
        if 0 < k < n - 1 and not ((Ac[j, i] and D[j, i] >= r_free) or (j == gj and i == gi)):
            return False
    return True


@njit(cache=True)
def shortcut(pts, D, Ac, r_free, gj, gi, x0, y0, hc, A, h):
    """Indices of the points of ``pts`` (m, 2) kept by greedy straight chords that stay free
    (:func:`chord_free`) and inside the fine tool-centre mask ``A`` (pixel ``h``; sampled every h/2,
    :func:`segment_inside`: the coarse samples every hc/2 can cut a corner of the region between
    them, a link clipping a wall by a few hundredths of a mm): from each kept point the farthest
    reachable one (a binary search while the gap is over 8 points). The first chord may start on the
    true wall (a finishing lap ends there), outside the mask for its first 2 h."""
    m = pts.shape[0]
    out = np.empty(m, np.int64)
    out[0] = 0
    n = 1
    i = 0
    while i < m - 1:
        j = m - 1
        while j > i + 1 and not (chord_free(D, Ac, r_free, gj, gi, x0, y0, hc, pts[i, 0], pts[i, 1], pts[j, 0], pts[j, 1])
                                 and segment_inside(A, x0, y0, h, pts[i, 0], pts[i, 1], pts[j, 0], pts[j, 1],
                                                    2.0 * h if i == 0 else 0.0)):
            j = max(i + 1, (i + j) // 2) if j - i > 8 else j - 1
        out[n] = j
        n += 1
        i = j
    return out[:n]


@njit(cache=True)
def solid_within(M, x0, y0, h, cx, cy, rr):
    """(area mm^2, centroid x, y mm) of the material pixels of ``M`` within ``rr`` mm of (cx, cy) whose
    four neighbours are material too (the stock eroded by one pixel: the one- and two-pixel-wide
    skins and seams a pass's 1/2-contour engagement does not see count for nothing); the centroid is
    (cx, cy) when there are none."""
    ny, nx = M.shape
    i0 = max(int(math.floor((cx - rr - x0) / h)), 1)
    i1 = min(int(math.ceil((cx + rr - x0) / h)), nx - 2)
    j0 = max(int(math.floor((cy - rr - y0) / h)), 1)
    j1 = min(int(math.ceil((cy + rr - y0) / h)), ny - 2)
    n = 0
    sx = 0.0
    sy = 0.0
    for j in range(j0, j1 + 1):
        py = y0 + (j + 0.5) * h - cy
        for i in range(i0, i1 + 1):
            if M[j, i] and M[j - 1, i] and M[j + 1, i] and M[j, i - 1] and M[j, i + 1]:
                px = x0 + (i + 0.5) * h - cx
                if px * px + py * py <= rr * rr:
                    n += 1
                    sx += px
                    sy += py
    if n == 0:
        return 0.0, cx, cy
    return n * h * h, cx + sx / n, cy + sy / n


@njit(cache=True)
def blocked_spans(M, x0, y0, h, ax, ay, bx, by, rr):
    """(k, 2): for each material pixel centre of ``M`` within ``rr`` (mm) of the chord a -> b, the
    open interval of the chord parameter t in [0, 1] whose points lie within ``rr`` of it (unmerged,
    unsorted): the chord's sub-segment [t0, t1] is :func:`capsule_free` iff it meets none of them."""
    i0, i1, j0, j1 = capsule_window(M, x0, y0, h, ax, ay, bx, by, rr)
    dx = bx - ax
    dy = by - ay
    A = dx * dx + dy * dy
    out = np.empty((max(0, (j1 - j0 + 1) * (i1 - i0 + 1)), 2))
    n = 0
    if A == 0.0:
        return out[:0]
    for j in range(j0, j1 + 1):
        py = y0 + (j + 0.5) * h
        lo, hi = capsule_row(x0, h, ax, ay, dx, dy, rr, py, i0, i1)
        for i in range(lo, hi + 1):
            if M[j, i]:
                px = x0 + (i + 0.5) * h
                B = 2.0 * (dx * (ax - px) + dy * (ay - py))
                C = (ax - px) ** 2 + (ay - py) ** 2 - rr * rr
                disc = B * B - 4.0 * A * C
                if disc <= 0.0:
                    continue
                sq = math.sqrt(disc)
                t0 = (-B - sq) / (2.0 * A)
                t1 = (-B + sq) / (2.0 * A)
                if t1 <= 0.0 or t0 >= 1.0:
                    continue
                out[n, 0] = max(t0, 0.0)
                out[n, 1] = min(t1, 1.0)
                n += 1
    return out[:n]


def rapid_pieces(g, p, q, min_len):
    """The chord p -> q at depth that :func:`rapid_legs` cannot prove as one G0, split where the rapid
    stock allows: every stretch of at least ``min_len`` mm with no material pixel within r + h/sqrt(2)
    (:func:`blocked_spans`; each piece checked again by :func:`capsule_free`) is a G0, the rest feed.
    Returns ``[(end point, is_rapid), ...]`` from p to q, or None when no G0 piece is proven."""
    L = math.hypot(q[0] - p[0], q[1] - p[1])
    if L < min_len:
        return None
    S = blocked_spans(g.Mr, g.x0, g.y0, g.h, p[0], p[1], q[0], q[1], g.r_capsule)
    S = S[np.argsort(S[:, 0])]
    free, t = [], 0.0                       # the complement of the union of the open intervals
    for t0, t1 in S:
        if t0 > t:
            free.append((t, t0))
        t = max(t, t1)
    if t < 1.0:
        free.append((t, 1.0))
    at = lambda u: (p[0] + u * (q[0] - p[0]), p[1] + u * (q[1] - p[1]))       # noqa: E731
    eps = 1e-9
    pieces, t = [], 0.0
    for f0, f1 in free:
        a, b = (f0 + eps if f0 > 0.0 else 0.0), (f1 - eps if f1 < 1.0 else 1.0)
        if (b - a) * L < min_len or not capsule_free(g.Mr, g.x0, g.y0, g.h, *at(a), *at(b), g.r_capsule):
            continue
        if a > t:
            pieces.append((at(a), False))
        pieces.append((at(b), True))
        t = b
    if not pieces:
        return None
    if t < 1.0:
        pieces.append(((q[0], q[1]), False))
    return pieces


def rapid_legs(g, p, q):
    """A G0 for the chord p -> q at depth: ``(None, q)`` when the chord is proven clear on the rapid
    stock (:func:`capsule_free`); else ``(p', q')`` with feed legs p -> p' and q' -> q of 2 h or 4 h
    along the chord at either end or both (``p'`` None: no leg at the start) when the shortened chord
    is proven; None when no G0 is proven."""
    h = g.h
    if capsule_free(g.Mr, g.x0, g.y0, h, p[0], p[1], q[0], q[1], g.r_capsule):
        return None, q
    L = math.hypot(q[0] - p[0], q[1] - p[1])
    ux, uy = (q[0] - p[0]) / L, (q[1] - p[1]) / L
    # every shortened chord tried below holds the one shortened by the longest leg tried at both ends:
    # material within reach of that one blocks them all (one test instead of up to six)
    inner = 4.0 * h if L >= 16.0 * h else 2.0 * h
    if L >= 8.0 * h and not capsule_free(g.Mr, g.x0, g.y0, h, p[0] + inner * ux, p[1] + inner * uy,
                                         q[0] - inner * ux, q[1] - inner * uy, g.r_capsule):
        return None
    for leg in (2.0 * h, 4.0 * h):
        if L < 4.0 * leg:
            break
        a = (p[0] + leg * ux, p[1] + leg * uy)
        b = (q[0] - leg * ux, q[1] - leg * uy)
        for s, e in ((a, q), (p, b), (a, b)):
            if capsule_free(g.Mr, g.x0, g.y0, h, s[0], s[1], e[0], e[1], g.r_capsule):
                return (None if s is p else s), e
    return None
