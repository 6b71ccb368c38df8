"""Compiled (numba) per-step kernels of the dixel and pixel simulators.

Line-by-line ports of the numpy reference implementations in :mod:`.dixel`, :mod:`.pixel` and
:mod:`.common` (which stay the readable reference, ``backend="numpy"``); the tests
(``tests/test_simulation_kernels.py``) check that both give the same removed areas, stocks and
engagement angles. Both models get the same treatment -- plain loops over the rows (dixel: the
intervals of a row; pixel: the pixels of a row's chord), and a whole :func:`~.common.simulate` path
runs in one compiled call -- so a speed ratio between them reflects the data structures (linear vs
quadratic in 1/resolution), not interpreter or numpy call overhead.

Storage conventions (as in the numpy reference): dixel ``A``, ``B`` are ``(K, n_rows)`` float arrays
with row j's intervals ``[A[k, j], B[k, j])`` in increasing k, padded with +inf; pixel ``grid`` is
a ``(ny, nx)`` boolean array. Angles in radians inside the kernels. Compiled with ``cache=True``
(the first call in a fresh environment compiles, later processes load the cache).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

_NO_MATERIAL = 1e9
_PI = math.pi
_TWO_PI = 2.0 * math.pi


@njit(cache=True, inline="always")
def _npmod(a, b):
    """numpy's float ``np.mod`` (floor modulo with the sign of the divisor; Python's float ``%``
    computes it the same way: fmod, then + b when the signs differ)."""
    return a % b


@njit(cache=True, inline="always")
def _angle_range(f0, f1, front_only):
    """Feed direction angle psi0 (rad) and the measured range (lo, hi) of angles from it (rad):
    the front half-circle (-pi/2, pi/2) or the whole circle (-pi, pi)."""
    if front_only:
        return math.atan2(f1, f0), -_PI / 2, _PI / 2
    return math.atan2(f1, f0), -_PI, _PI


# ---------------------------------------------------------------------------------------------
# dixel
# ---------------------------------------------------------------------------------------------
@njit(cache=True)
def dixel_cut(A, B, y0, h, cx, cy, r):
    """Remove the disk (cx, cy, r) from the dixel stock in place; removed area (mm^2).

    Returns -1.0 without modifying anything when a row would need more than K intervals (the
    caller grows the capacity and calls again).
    """
    K, n_rows = A.shape
    j_lo = max(int(math.floor((cy - r - y0) / h)), 0)
    j_hi = min(int(math.ceil((cy + r - y0) / h)) - 1, n_rows - 1)
    if j_hi < j_lo:
        return 0.0
    m = j_hi - j_lo + 1
    w = np.empty(m)
    gprev = 0.0
    for q in range(m + 1):
        u = y0 + (j_lo + q) * h - cy
        u = min(max(u, -r), r)
        g = u * math.sqrt(max(r * r - u * u, 0.0)) + r * r * math.asin(u / r)
        if q > 0:
            w[q - 1] = (g - gprev) * (0.5 / h)
        gprev = g
    # capacity check (a cut splits at most one interval per row)
    for q in range(m):
        j = j_lo + q
        if math.isinf(A[K - 1, j]):
            continue
        xs = cx - w[q]
        xe = cx + w[q]
        for k in range(K):
            if A[k, j] < xs and B[k, j] > xe and min(B[k, j], xs) > A[k, j]:
                return -1.0
    removed = 0.0
    na = np.empty(K + 1)
    nb = np.empty(K + 1)
    for q in range(m):
        j = j_lo + q
        xs = cx - w[q]
        xe = cx + w[q]
        hit = False
        for k in range(K):
            a = A[k, j]
            if math.isinf(a):
                break
            ov = min(B[k, j], xe) - max(a, xs)
            if ov > 0:
                removed += ov
                hit = True
        if not hit:
            continue
        n = 0
        for k in range(K):
            a = A[k, j]
            if math.isinf(a):
                break
            b = B[k, j]
            lb = min(b, xs)
            if lb > a:
                na[n] = a
                nb[n] = lb
                n += 1
            ra = max(a, xe)
            if b > ra:
                na[n] = ra
                nb[n] = b
                n += 1
        for k in range(K):
            if k < n:
                A[k, j] = na[k]
                B[k, j] = nb[k]
            else:
                A[k, j] = np.inf
                B[k, j] = np.inf
    return removed * h


@njit(cache=True, inline="always")
def _dixel_row_contains(A, B, j, x):
    K = A.shape[0]
    for k in range(K):
        a = A[k, j]
        if math.isinf(a):
            return False
        if a <= x and x < B[k, j]:
            return True
    return False


@njit(cache=True)
def _dixel_contains(A, B, y0, h, x, y):
    j = int(math.floor((y - y0) / h))
    if j < 0 or j >= A.shape[1]:
        return False
    return _dixel_row_contains(A, B, j, x)


@njit(cache=True)
def _dixel_contains_interp(A, B, y0, h, x, y):
    """Port of ``Stock._contains_interp`` for one point."""
    K, n = A.shape
    t = (y - y0) / h - 0.5
    j = int(math.floor(t))
    f = t - j
    j1 = j + 1
    ok0 = j >= 0 and j < n
    ok1 = j1 >= 0 and j1 < n
    c0 = 0
    c1 = 0
    if ok0:
        while c0 < K and not math.isinf(A[c0, j]):
            c0 += 1
    if ok1:
        while c1 < K and not math.isinf(A[c1, j1]):
            c1 += 1
    if c0 == c1:
        for k in range(c0):
            ai = A[k, j] + f * (A[k, j1] - A[k, j])
            bi = B[k, j] + f * (B[k, j1] - B[k, j])
            if ai <= x and x < bi:
                return True
        return False
    if f < 0.5:
        return ok0 and _dixel_row_contains(A, B, j, x)
    return ok1 and _dixel_row_contains(A, B, j1, x)


@njit(cache=True)
def _contains_any(kind, A, B, grid, x0, y0, h, x, y):
    """Membership test selected by ``kind``: 0 dixel rows, 1 dixel interpolated, 2 pixel."""
    if kind == 0:
        return _dixel_contains(A, B, y0, h, x, y)
    if kind == 1:
        return _dixel_contains_interp(A, B, y0, h, x, y)
    i = int(math.floor((x - x0) / h))
    j = int(math.floor((y - y0) / h))
    if i < 0 or j < 0 or j >= grid.shape[0] or i >= grid.shape[1]:
        return False
    return grid[j, i]


@njit(cache=True)
def _refine(kind, A, B, grid, geo, circ, brackets, nq, bisections, out, n_out):
    """Port of :func:`.common.refine_transitions` (n_sub = 256); appends the transitions to ``out``.
    ``geo`` (x0, y0, h) mm; ``circ`` (cx, cy, r) mm, psi0 rad; ``brackets`` (a, b, inside at a), nq used."""
    (x0, y0, h), (cx, cy, r, psi0), (a_in, b_in, ma_in) = geo, circ, brackets
    n_sub = 256
    rounds = int(math.ceil(bisections / math.log2(n_sub))) - 1
    # first round: every transition in every bracket
    ta = np.empty(16)
    tb = np.empty(16)
    tm = np.empty(16, np.bool_)
    nt = 0
    for q in range(nq):
        a = a_in[q]
        span = b_in[q] - a
        prev = ma_in[q]
        gprev = a + span * 0.0
        for i in range(1, n_sub + 1):
            g = a + span * (i / n_sub)
            if i < n_sub:
                ang = psi0 + g
                cur = _contains_any(kind, A, B, grid, x0, y0, h, cx + r * math.cos(ang), cy + r * math.sin(ang))
            else:
                cur = not ma_in[q]
            if cur != prev:
                if nt == ta.size:
                    ta2 = np.empty(2 * nt)
                    tb2 = np.empty(2 * nt)
                    tm2 = np.empty(2 * nt, np.bool_)
                    ta2[:nt] = ta
                    tb2[:nt] = tb
                    tm2[:nt] = tm
                    ta, tb, tm = ta2, tb2, tm2
                ta[nt] = gprev
                tb[nt] = g
                tm[nt] = prev
                nt += 1
            prev = cur
            gprev = g
    for _ in range(rounds):
        for q in range(nt):
            a = ta[q]
            span = tb[q] - a
            first = n_sub
            for i in range(1, n_sub):
                g = a + span * (i / n_sub)
                ang = psi0 + g
                cur = _contains_any(kind, A, B, grid, x0, y0, h, cx + r * math.cos(ang), cy + r * math.sin(ang))
                if cur != tm[q]:
                    first = i
                    break
            ta[q] = a + span * ((first - 1) / n_sub)
            tb[q] = a + span * (first / n_sub)
    for q in range(nt):
        out[n_out] = 0.5 * (ta[q] + tb[q])
        n_out += 1
    return n_out


@njit(cache=True)
def _dixel_signed_xdist(A, B, x, j):
    """(signed distance, nearest end point) of point x in row j; see ``Stock._signed_xdist``."""
    K, n_rows = A.shape
    if j < 0 or j >= n_rows:
        return -_NO_MATERIAL, np.nan
    best = np.inf
    kk = 0
    for k in range(K):
        a = A[k, j]
        if math.isinf(a):
            break
        m = max(a - x, x - B[k, j])
        if m < best:
            best = m
            kk = k
    if math.isinf(best):
        return -_NO_MATERIAL, np.nan
    a = A[kk, j]
    b = B[kk, j]
    e = a if abs(x - a) <= abs(b - x) else b
    return -min(best, _NO_MATERIAL), e


@njit(cache=True)
def _band(A, B, y0, h, circ, p0, p1, j0, j1, out, n_out):
    """Port of ``Stock._band_transitions`` for one bracket: (ok, n_out) with the angles appended."""
    cx, cy, r, psi0 = circ
    K, n_rows = A.shape
    if j0 == j1:
        ym = cy + r * math.sin(psi0 + 0.5 * (p0 + p1))
        jb = j0 if ym > y0 + (j0 + 0.5) * h else j0 - 1
    else:
        jb = min(j0, j1)
    if not (abs(j1 - j0) <= 1 and jb >= 0 and jb + 1 < n_rows):
        return False, n_out
    for k in range(K):
        if math.isinf(A[k, jb]) != math.isinf(A[k, jb + 1]):
            return False, n_out
    Y0 = y0 + (jb + 0.5) * h - cy
    cnt = 0
    start = n_out
    for side in range(2):
        for k in range(K):
            if math.isinf(A[k, jb]):
                break
            if side == 0:
                X0 = A[k, jb] - cx
                dX = A[k, jb + 1] - cx - X0
            else:
                X0 = B[k, jb] - cx
                dX = B[k, jb + 1] - cx - X0
            qa = dX * dX + h * h
            qb = X0 * dX + Y0 * h
            qc = X0 * X0 + Y0 * Y0 - r * r
            disc = qb * qb - qa * qc
            if not disc >= 0.0:
                continue
            sq = math.sqrt(disc)
            for sgn in (-1.0, 1.0):
                t = (-qb + sgn * sq) / qa
                a = math.atan2(Y0 + t * h, X0 + t * dX) - psi0
                a = p0 + _npmod(a - p0, _TWO_PI)
                if t >= 0 and t <= 1 and a > p0 and a < p1:
                    out[n_out] = a
                    n_out += 1
                    cnt += 1
    if cnt % 2 == 1:
        return True, n_out
    return False, start


@njit(cache=True, inline="always")
def _crossing(o, m, j_lo, y0, h, cy, r):
    """Crossing o of the circle with the row centre lines, in the reference's order (right side
    bottom->top, then left side top->bottom): (dy, x-offset, row)."""
    if o < m:
        q = o
    else:
        q = 2 * m - 1 - o
    dy = y0 + (j_lo + q + 0.5) * h - cy
    cxq = math.sqrt(max(r * r - dy * dy, 0.0))
    return dy, (cxq if o < m else -cxq), j_lo + q


@njit(cache=True, inline="always")
def _crossing_psi(o, m, j_lo, y0, h, cy, r, psi0):
    dy, x, _ = _crossing(o, m, j_lo, y0, h, cy, r)
    return _npmod(math.atan2(dy, x) - psi0 + _PI, _TWO_PI) - _PI


@njit(cache=True)
def _dixel_engagement_front(A, B, y0, h, cx, cy, r, psi0, m, j_lo, polyline, bisections):
    """Front half-circle engagement computing the polar angle (atan2) only where it is used.

    Same result as the all-crossings port below: a crossing is in the range (-pi/2, pi/2) when its
    component along the feed direction is > 0, decided on the exact angle when that component is
    within 1e-9 r of 0; the polar angles are evaluated only at the brackets with a material/air
    transition and at the two ends (with the reference's 2 pi unwrapping). Returns (ok, intervals);
    ok False (degenerate: no crossing or every crossing in range) -> the caller uses the full port.
    """
    n = 2 * m
    lo, hi = -_PI / 2, _PI / 2
    cu, su = math.cos(psi0), math.sin(psi0)
    tol = 1e-9 * r
    # (hot loops are kept free of branches that raise -- float %, atan2 -- which slow them ~20x)
    inr = np.empty(n, np.bool_)
    n_amb = 0
    for o in range(n):
        dy, x, _ = _crossing(o, m, j_lo, y0, h, cy, r)
        u = x * cu + dy * su
        inr[o] = u > tol
        n_amb += abs(u) <= tol
    if n_amb:
        for o in range(n):
            dy, x, _ = _crossing(o, m, j_lo, y0, h, cy, r)
            if abs(x * cu + dy * su) <= tol:
                p = _crossing_psi(o, m, j_lo, y0, h, cy, r, psi0)
                inr[o] = p > lo and p < hi
    n_r = np.int64(0)      # typed int64 from the start: no second compile of the callees for a literal 0
    for o in range(n):
        n_r += inr[o]
    if n_r == 0 or n_r == n:
        return False, np.empty((0, 2))
    o_s = -1
    prev = inr[n - 1]
    for o in range(n):
        if inr[o] and not prev:
            o_s = o
            break
        prev = inr[o]
    # the range must be one cyclic block of n_r crossings (else: the general port decides)
    o = o_s
    for q in range(n_r):
        if not inr[o]:
            return False, np.empty((0, 2))
        o += 1
        if o == n:
            o = 0
    o_e = o - 1 if o > 0 else n - 1
    ne = n_r + 2
    je = np.empty(ne, np.int64)
    dist = np.empty(ne)
    ex = np.empty(ne)
    o = o_s - 1 if o_s > 0 else n - 1
    for q in range(ne):
        dy, x, jq = _crossing(o, m, j_lo, y0, h, cy, r)
        je[q] = jq
        dist[q], ex[q] = _dixel_signed_xdist(A, B, cx + x, jq)
        o += 1
        if o == n:
            o = 0
    # polar angles only at the ends and around the transitions
    need = np.zeros(ne, np.bool_)
    need[0] = True
    need[ne - 1] = True
    for q in range(ne - 1):
        t = (dist[q] > 0) != (dist[q + 1] > 0)
        need[q] |= t
        need[q + 1] |= t
    pe = np.full(ne, np.nan)
    ps = _crossing_psi(o_s, m, j_lo, y0, h, cy, r, psi0)
    pl = _crossing_psi(o_e, m, j_lo, y0, h, cy, r, psi0)
    for q in range(ne):
        if need[q]:
            o = o_s - 1 + q
            if o < 0:
                o += n
            elif o >= n:
                o -= n
            p = _crossing_psi(o, m, j_lo, y0, h, cy, r, psi0)
            if q == 0 and p > ps:
                p -= _TWO_PI
            elif q == ne - 1 and p < pl:
                p += _TWO_PI
            pe[q] = p
    return True, _finish(A, B, y0, h, (cx, cy, r, psi0), (pe, je, dist, ex), ne, lo, hi, polyline, bisections)


@njit(cache=True)
def dixel_engagement(A, B, y0, h, cx, cy, r, f0, f1, front_only, polyline, bisections):
    """Port of ``dixel.Stock.engagement`` (method="rows"): (k, 2) engaged intervals (rad, from feed)."""
    psi0, lo, hi = _angle_range(f0, f1, front_only)
    empty = np.empty((0, 2))
    j_lo = int(math.ceil((cy - r - y0) / h - 0.5))
    j_hi = int(math.floor((cy + r - y0) / h - 0.5))
    if j_hi < j_lo:
        return empty
    m = j_hi - j_lo + 1
    if front_only:
        ok, iv = _dixel_engagement_front(A, B, y0, h, cx, cy, r, psi0, m, j_lo, polyline, bisections)
        if ok:
            return iv
    n = 2 * m
    psi = np.empty(n)
    cxx = np.empty(n)
    jj = np.empty(n, np.int64)
    for q in range(m):
        jq = j_lo + q
        dy = y0 + (jq + 0.5) * h - cy
        cxq = math.sqrt(max(r * r - dy * dy, 0.0))
        # right side bottom->top at q, left side top->bottom at n-1-q
        cxx[q] = cxq
        jj[q] = jq
        psi[q] = _npmod(math.atan2(dy, cxq) - psi0 + _PI, _TWO_PI) - _PI
        cxx[n - 1 - q] = -cxq
        jj[n - 1 - q] = jq
        psi[n - 1 - q] = _npmod(math.atan2(dy, -cxq) - psi0 + _PI, _TWO_PI) - _PI
    w = 0
    for q in range(1, n):
        if psi[q] < psi[w]:
            w = q
    # rotated index t -> original (t + w) % n
    i0 = -1
    i1 = -1
    for t in range(n):
        p = psi[(t + w) % n]
        if p > lo and p < hi:
            if i0 < 0:
                i0 = t
            i1 = t + 1
    if i0 < 0:
        i0 = 0
        while i0 < n and psi[(i0 + w) % n] < lo:
            i0 += 1
        i1 = i0
    ne = i1 - i0 + 2
    pe = np.empty(ne)
    xe = np.empty(ne)
    je = np.empty(ne, np.int64)
    dist = np.empty(ne)
    ex = np.empty(ne)
    for q in range(ne):
        idx = i0 - 1 + q
        t = idx % n
        o = (t + w) % n
        pe[q] = psi[o] + _TWO_PI * (idx // n)
        xe[q] = cx + cxx[o]
        je[q] = jj[o]
        dist[q], ex[q] = _dixel_signed_xdist(A, B, xe[q], je[q])
    return _finish(A, B, y0, h, (cx, cy, r, psi0), (pe, je, dist, ex), ne, lo, hi, polyline, bisections)


@njit(cache=True)
def _finish(A, B, y0, h, circ, crossings, ne, lo, hi, polyline, bisections):
    """Engaged intervals from ``crossings`` (pe, je, dist, ex): angles ``pe`` (needed only at the ends and
    at brackets with a transition), rows, signed x-distances, nearest end points; ``circ`` (cx, cy, r, psi0)."""
    (cx, cy, r, psi0), (pe, je, dist, ex) = circ, crossings
    n_rows = A.shape[1]
    empty = np.empty((0, 2))
    n_in = 0
    for q in range(ne):
        if dist[q] > 0:
            n_in += 1
    if n_in == 0:
        return empty
    if n_in == ne:
        out = np.empty((1, 2))
        out[0, 0] = lo
        out[0, 1] = hi
        return out
    trans = np.empty(ne, np.int64)        # brackets with a transition (a tight loop first)
    n_t = 0
    for k in range(ne - 1):
        trans[n_t] = k
        n_t += (dist[k] > 0) != (dist[k + 1] > 0)
    edges = np.empty(64)
    n_e = np.int64(0)
    wk = np.empty(ne, np.int64)           # wide brackets, to resolve afterwards
    n_w = 0
    for kt in range(n_t):
        k = trans[kt]
        d0 = dist[k]
        d1 = dist[k + 1]
        p0 = pe[k]
        p1 = pe[k + 1]
        lin = p0 + min(max(d0 / (d0 - d1), 0.0), 1.0) * (p1 - p0)
        emp = min(d0, d1) <= -_NO_MATERIAL / 2
        wide = ((p1 - p0) > 4.0 * h / r) or emp
        if wide:
            wk[n_w] = k
            n_w += 1
            continue
        e = lin
        if polyline and abs(je[k + 1] - je[k]) == 1:
            xa = ex[k] - cx
            ya = y0 + (je[k] + 0.5) * h - cy
            dx = ex[k + 1] - cx - xa
            dyv = y0 + (je[k + 1] + 0.5) * h - cy - ya
            qa = dx * dx + dyv * dyv
            qb = xa * dx + ya * dyv
            qc = xa * xa + ya * ya - r * r
            disc = qb * qb - qa * qc
            best = np.nan
            if disc >= 0.0:
                sq = math.sqrt(disc)
                for sgn in (-1.0, 1.0):
                    t = (-qb + sgn * sq) / qa
                    ang = math.atan2(ya + t * dyv, xa + t * dx) - psi0
                    ang = lin + (_npmod(ang - lin + _PI, _TWO_PI) - _PI)
                    okt = t >= 0 and t <= 1 and ang >= p0 and ang <= p1
                    if okt and not (abs(best - lin) <= abs(ang - lin)):
                        best = ang
            if math.isfinite(best):
                e = best
        if n_e + 1 > edges.size:
            e2 = np.empty(2 * edges.size)
            e2[:n_e] = edges[:n_e]
            edges = e2
        edges[n_e] = e
        n_e += 1
    if n_w:
        # wide brackets: band transitions (polyline), else the membership test
        ra = np.empty(n_w)
        rb = np.empty(n_w)
        rm = np.empty(n_w, np.bool_)
        n_r = np.int64(0)      # typed int64 from the start: no second compile of the callees for a literal 0
        for q in range(n_w):
            k = wk[q]
            if n_e + 4 * A.shape[0] + 2 > edges.size:
                e2 = np.empty(2 * edges.size + 4 * A.shape[0] + 2)
                e2[:n_e] = edges[:n_e]
                edges = e2
            ok = False
            if polyline:
                ok, n_e = _band(A, B, y0, h, circ, pe[k], pe[k + 1], je[k], je[k + 1], edges, n_e)
            if not ok:
                ra[n_r] = pe[k]
                rb[n_r] = pe[k + 1]
                rm[n_r] = dist[k] > 0
                n_r += 1
        if n_r:
            buf = np.empty(256 * n_r)
            n_b = _refine(1 if polyline else 0, A, B, np.zeros((1, 1), np.bool_), (0.0, y0, h), circ,
                          (ra, rb, rm), n_r, bisections, buf, 0)
            e2 = np.empty(n_e + n_b)
            e2[:n_e] = edges[:n_e]
            e2[n_e:] = buf[:n_b]
            edges = e2
            n_e = n_e + n_b
        edges = np.sort(edges[:n_e])
    return _bounds_to_intervals(pe[0], pe[ne - 1], dist[0] > 0, dist[ne - 1] > 0, edges, n_e, lo, hi, np.bool_(True))


@njit(cache=True)
def _bounds_to_intervals(first, last, in_first, in_last, edges, n_e, lo, hi, clip):
    nb = n_e + int(in_first) + int(in_last)
    bounds = np.empty(nb)
    q = 0
    if in_first:
        bounds[0] = first
        q = 1
    bounds[q:q + n_e] = edges[:n_e]
    if in_last:
        bounds[nb - 1] = last
    niv = nb // 2
    out = np.empty((niv, 2))
    n = 0
    for i in range(niv):
        a = bounds[2 * i]
        b = bounds[2 * i + 1]
        if clip:
            a = min(max(a, lo), hi)
            b = min(max(b, lo), hi)
            if not b > a:
                continue
        out[n, 0] = a
        out[n, 1] = b
        n += 1
    return out[:n]


# ---------------------------------------------------------------------------------------------
# pixel
# ---------------------------------------------------------------------------------------------
@njit(cache=True)
def pixel_cut(grid, x0, y0, h, cx, cy, r):
    """Clear the pixels whose centres lie in the disk; returns how many were material.

    Per row the chord's column range comes from a square root and its two ends are then fixed on
    the reference test (x^2 + y^2 <= r^2 on the pixel centre), so the set equals the reference's.
    """
    ny, nx = grid.shape
    i0 = max(int(math.floor((cx - r - x0) / h)), 0)
    i1 = min(int(math.ceil((cx + r - x0) / h)), nx)
    j0 = max(int(math.floor((cy - r - y0) / h)), 0)
    j1 = min(int(math.ceil((cy + r - y0) / h)), ny)
    if i1 <= i0 or j1 <= j0:
        return 0
    rr = r * r
    n = 0
    for j in range(j0, j1):
        yc = y0 + (j + 0.5) * h - cy
        y2 = yc * yc
        if y2 > rr:
            continue
        half = math.sqrt(rr - y2)
        a = max(int(math.ceil((cx - half - x0) / h - 0.5)), i0)
        b = min(int(math.floor((cx + half - x0) / h - 0.5)), i1 - 1)
        # fix the ends on the exact test
        while a > i0:
            xc = x0 + (a - 1 + 0.5) * h - cx
            if y2 + xc * xc <= rr:
                a -= 1
            else:
                break
        while a <= b:
            xc = x0 + (a + 0.5) * h - cx
            if y2 + xc * xc <= rr:
                break
            a += 1
        while b < i1 - 1:
            xc = x0 + (b + 1 + 0.5) * h - cx
            if y2 + xc * xc <= rr:
                b += 1
            else:
                break
        while b >= a:
            xc = x0 + (b + 0.5) * h - cx
            if y2 + xc * xc <= rr:
                break
            b -= 1
        row = grid[j]
        for i in range(a, b + 1):
            n += row[i]
            row[i] = False
    return n


@njit(cache=True)
def pixel_engagement(grid, x0, y0, h, cx, cy, r, f0, f1, front_only, n_samples, bisections):
    """Port of ``StockBase.engagement`` on the pixel grid: (k, 2) engaged intervals (rad)."""
    psi0, lo, hi = _angle_range(f0, f1, front_only)
    empty = np.empty((0, 2))
    if n_samples <= 0:
        n_samples = max(181, int(math.ceil((hi - lo) * r / (0.5 * h))) + 1)
    step = (hi - lo) / (n_samples - 1)
    A = np.empty((1, 1))
    n_in = 0
    m = np.empty(n_samples, np.bool_)
    for i in range(n_samples):
        p = i * step + lo if i < n_samples - 1 else hi
        ang = psi0 + p
        m[i] = _contains_any(np.int64(2), A, A, grid, x0, y0, h, cx + r * math.cos(ang), cy + r * math.sin(ang))
        n_in += m[i]
    if n_in == 0:
        return empty
    if n_in == n_samples:
        out = np.empty((1, 2))
        out[0, 0] = lo
        out[0, 1] = hi
        return out
    nq = np.int64(0)
    for i in range(n_samples - 1):
        if m[i] != m[i + 1]:
            nq += 1
    ra = np.empty(nq)
    rb = np.empty(nq)
    rm = np.empty(nq, np.bool_)
    q = 0
    for i in range(n_samples - 1):
        if m[i] != m[i + 1]:
            ra[q] = i * step + lo
            rb[q] = (i + 1) * step + lo if i + 1 < n_samples - 1 else hi
            rm[q] = m[i]
            q += 1
    buf = np.empty(256 * nq)
    n_b = _refine(np.int64(2), A, A, grid, (x0, y0, h), (cx, cy, r, psi0), (ra, rb, rm), nq, bisections, buf, 0)
    edges = np.sort(buf[:n_b])
    return _bounds_to_intervals(lo, hi, m[0], m[n_samples - 1], edges, n_b, lo, hi, np.bool_(False))


# ---------------------------------------------------------------------------------------------
# whole path
# ---------------------------------------------------------------------------------------------
@njit(cache=True)
def _chip(iv, f_z):
    """Port of :func:`.common.chip_thickness` -> (h_max, h_avg) (mm)."""
    theta = 0.0
    s = 0.0
    cmax = -np.inf
    c0 = False
    any_ = False
    for i in range(iv.shape[0]):
        lo = min(max(iv[i, 0], -_PI / 2), _PI / 2)
        hi = min(max(iv[i, 1], -_PI / 2), _PI / 2)
        if not hi > lo:
            continue
        any_ = True
        theta += hi - lo
        s += math.sin(hi) - math.sin(lo)
        if lo <= 0 and hi >= 0:
            c0 = True
        cmax = max(cmax, math.cos(lo), math.cos(hi))
    if not any_ or theta <= 0:
        return 0.0, 0.0
    if c0:
        cmax = 1.0
    return f_z * cmax, f_z * s / theta


@njit(cache=True, inline="always")
def _cut_one(model, A, B, grid, x0, y0, h, cx, cy, r):
    """Cut one disk (model 0 dixel, 1 pixel): removed area (mm^2), or -1 when a dixel row ran out
    of interval capacity (nothing changed: grow and retry)."""
    if model == 0:
        return dixel_cut(A, B, y0, h, cx, cy, r)
    return pixel_cut(grid, x0, y0, h, cx, cy, r) * (h * h)


@njit(cache=True)
def reaches_front(qx, qy, px, py, g0, g1, r, margin):
    """True when the tool disc at (qx, qy) (radius r, mm) covers part of the front half-circle of the
    tool at (px, py) with feed direction (g0, g1) deeper than ``margin`` (mm): the distance from the
    disc centre to that arc is below ``r - margin`` (a disc ahead of the tool, centre closer than
    2 r, always does). A disc behind the tool on a path whose curvature radius exceeds r never does:
    it only touches the arc's ends, where the margin keeps the row-discretisation artefact out."""
    vx = qx - px
    vy = qy - py
    rho = math.hypot(vx, vy)
    if rho < 1e-12:
        return False
    gn = math.hypot(g0, g1)
    fx = g0 / gn
    fy = g1 / gn
    if vx * fx + vy * fy > 0.0:
        return rho < 2.0 * r         # a disc ahead of the tool always covers part of its front arc
    else:
        nx = -fy * r
        ny = fx * r
        dist = min(math.hypot(vx - nx, vy - ny), math.hypot(vx + nx, vy + ny))
    return dist < r - margin


@njit(cache=True)
def simulate_path(A, B, grid, P, d, ds, s, cfg, state, out):
    """Port of the loop of :func:`.common.simulate`, settings ``cfg`` (:class:`.common.PathSettings`): fills
    ``out`` (eng, ent, ext, rem, hmax, havg) from ``state`` (step i, cut k, feed fd0, fd1) on. Returns the
    state: i = k = N when done; else a dixel row ran out of interval capacity at cut k (grow, call again).
    """
    model, x0, y0, h, r, lag, central, front_only, polyline, bisections, n_samples, f_z, hold_front = cfg
    (i_start, k_start, fd0, fd1), (eng, ent, ext, rem, hmax, havg) = state, out
    n = P.shape[0]
    k = k_start
    for i in range(i_start, n):
        if i > 0 and ds[i] > 0:
            fd0 = d[i - 1, 0]
            fd1 = d[i - 1, 1]
        g0 = fd0
        g1 = fd1
        if central and 0 < i < n - 1:
            v0 = P[i + 1, 0] - P[i - 1, 0]
            v1 = P[i + 1, 1] - P[i - 1, 1]
            if v0 != 0 or v1 != 0:
                g0 = v0
                g1 = v1
        m = k
        if hold_front and (g0 != 0 or g1 != 0):
            for q in range(i - 1, k - 1, -1):
                if reaches_front(P[q, 0], P[q, 1], P[i, 0], P[i, 1], g0, g1, r, 1e-9):
                    m = q + 1
                    break
        while k < i and (s[i] - s[k] > lag or k < m):
            v = _cut_one(model, A, B, grid, x0, y0, h, P[k, 0], P[k, 1], r)
            if v < 0:
                return i, k, fd0, fd1
            rem[k] = v
            k += 1
        if g0 != 0 or g1 != 0:
            if model == 0:
                iv = dixel_engagement(A, B, y0, h, P[i, 0], P[i, 1], r, g0, g1, front_only, polyline, bisections)
            else:
                iv = pixel_engagement(grid, x0, y0, h, P[i, 0], P[i, 1], r, g0, g1, front_only, n_samples,
                                      bisections)
            if iv.shape[0] == 0:
                eng[i] = 0.0
                ent[i] = np.nan
                ext[i] = np.nan
            else:
                tot = 0.0
                for q in range(iv.shape[0]):
                    tot += iv[q, 1] - iv[q, 0]
                eng[i] = math.degrees(tot)
                ent[i] = math.degrees(iv[0, 0])
                ext[i] = math.degrees(iv[iv.shape[0] - 1, 1])
            if not math.isnan(f_z):
                hmax[i], havg[i] = _chip(iv, f_z)
        else:
            eng[i] = np.nan
            ent[i] = np.nan
            ext[i] = np.nan
    i = n
    while k < n:
        v = _cut_one(model, A, B, grid, x0, y0, h, P[k, 0], P[k, 1], r)
        if v < 0:
            return i, k, fd0, fd1
        rem[k] = v
        k += 1
    return i, k, fd0, fd1


@njit(cache=True)
def cut_path(model, A, B, grid, x0, y0, h, P, r, k_start, rem):
    """Cut the disks at ``P[k_start:]`` in order (model 0 dixel, 1 pixel); removed areas in ``rem``.

    Returns the index of the first disk not cut (``len(P)`` when done; a dixel row ran out of
    interval capacity otherwise: grow and call again from there). Used by the benchmark to time
    the cut alone without per-call overhead.
    """
    for k in range(k_start, P.shape[0]):
        v = _cut_one(model, A, B, grid, x0, y0, h, P[k, 0], P[k, 1], r)
        if v < 0:
            return k
        rem[k] = v
    return P.shape[0]
