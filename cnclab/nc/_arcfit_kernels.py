"""Compiled kernels of :mod:`cnclab.nc.arcfit`: the line and arc tests of one piece of a polyline and
the greedy cover of a run by the longest pieces (:func:`fit_run`). Units: mm. The arithmetic is the
fit's (module docstring of :mod:`cnclab.nc.arcfit`), on floats: an arc block's written centre is
rounded to the program's grid, every point and chord of the piece lies within its chord's tolerance.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def line_ok(P, i, j, tol):
    """The line P[i] -> P[j] fits P[i..j]: every point within its tolerance (a point gets the smaller
    of its two chords' ``tol``; the line's distance to a chord is largest at the chord's ends) and
    advancing along the line."""
    ax, ay, az = P[i, 0], P[i, 1], P[i, 2]
    dx, dy, dz = P[j, 0] - ax, P[j, 1] - ay, P[j, 2] - az
    dd = dx * dx + dy * dy + dz * dz
    if dd <= 1e-18:
        return False
    t_prev = 0.0
    for m in range(j - i + 1):
        qx, qy, qz = P[i + m, 0] - ax, P[i + m, 1] - ay, P[i + m, 2] - az
        t = (qx * dx + qy * dy + qz * dz) / dd
        if m > 0 and t - t_prev < -1e-12:
            return False
        t_prev = t
        px, py, pz = qx - t * dx, qy - t * dy, qz - t * dz
        if m == 0:
            c = tol[i]
        elif m == j - i:
            c = tol[j - 1]
        else:
            c = min(tol[i + m - 1], tol[i + m])
        if px * px + py * py + pz * pz > c * c:
            return False
    return True


@njit(cache=True)
def _snap(x, scale):
    return np.rint(x * scale) / scale


@njit(cache=True)
def arc_fit(P, i, j, tol, grid, scale, max_radius, max_step, max_sweep):
    """``(code, cx, cy)`` of the arc (code 2 clockwise, 3 counter-clockwise) through P[i] and P[j]
    that fits P[i..j] (``tol`` per chord), its centre on the written grid; code 0 when none does."""
    L = j - i
    Awx, Awy = _snap(P[i, 0], scale), _snap(P[i, 1], scale)
    Bwx, Bwy = _snap(P[j, 0], scale), _snap(P[j, 1], scale)
    chx, chy = Bwx - Awx, Bwy - Awy
    d = math.hypot(chx, chy)
    if d < 10 * grid:
        return 0, math.nan, math.nan
    nx, ny = -chy / d, chx / d
    hx, hy = 0.5 * chx, 0.5 * chy
    ab = 0.0
    bb = 0.0
    for m in range(L + 1):
        px, py = P[i + m, 0] - Awx, P[i + m, 1] - Awy
        a = (px * px + py * py) - 2 * (px * hx + py * hy)
        b = 2 * (px * nx + py * ny)
        ab += a * b
        bb += b * b
    if bb <= 1e-18:
        return 0, math.nan, math.nan                  # collinear: a line, if anything
    t = ab / bb
    if math.hypot(0.5 * d, t) > max_radius:
        return 0, math.nan, math.nan
    cx, cy = _snap(Awx + hx + t * nx, scale), _snap(Awy + hy + t * ny, scale)
    r0, r1 = math.hypot(Awx - cx, Awy - cy), math.hypot(Bwx - cx, Bwy - cy)
    if abs(r0 - r1) > 1.5 * grid:
        return 0, math.nan, math.nan
    r = 0.5 * (r0 + r1)
    dth = np.empty(L)
    sweep = 0.0
    ang0 = math.atan2(P[i, 1] - cy, P[i, 0] - cx)
    for m in range(L):
        ang1 = math.atan2(P[i + m + 1, 1] - cy, P[i + m + 1, 0] - cx)
        dth[m] = (ang1 - ang0 + math.pi) % (2 * math.pi) - math.pi
        sweep += dth[m]
        ang0 = ang1
    s = 1.0 if sweep > 0 else -1.0
    if not (1e-9 < abs(sweep) <= max_sweep):
        return 0, math.nan, math.nan
    for m in range(L):
        if dth[m] * s < -1e-12 or abs(dth[m]) > max_step:
            return 0, math.nan, math.nan
    az, bz = P[i, 2], P[j, 2]
    cum0 = 0.0
    acc = 0.0
    for m in range(L):
        acc += dth[m]
        cum1 = acc / sweep
        v0x, v0y = P[i + m, 0] - cx, P[i + m, 1] - cy
        v1x, v1y = P[i + m + 1, 0] - cx, P[i + m + 1, 1] - cy
        dr0, dr1 = math.hypot(v0x, v0y) - r, math.hypot(v1x, v1y) - r
        # outward deviation is largest at an end point (|p - c| is convex along a chord), inward
        # deviation is r minus the chord's distance to the centre; z at the chord's middle too
        ex, ey = v1x - v0x, v1y - v0y
        ee = ex * ex + ey * ey
        u = -(v0x * ex + v0y * ey) / (ee if ee > 0 else 1.0)
        u = min(max(u, 0.0), 1.0)
        inward = r - math.hypot(v0x + u * ex, v0y + u * ey)
        rad = max(max(abs(dr0), abs(dr1)), inward)
        dz0 = P[i + m, 2] - (az + (bz - az) * cum0)
        dz1 = P[i + m + 1, 2] - (az + (bz - az) * cum1)
        zmid = 0.5 * (P[i + m, 2] + P[i + m + 1, 2]) - (az + (bz - az) * 0.5 * (cum0 + cum1))
        zdev = max(max(abs(dz0), abs(dz1)), abs(zmid))
        if rad * rad + zdev * zdev > tol[i + m] * tol[i + m]:
            return 0, math.nan, math.nan
        cum0 = cum1
    return (3 if s > 0 else 2), cx, cy


@njit(cache=True)
def _piece(P, i, j, tol, arc, grid, scale, max_radius, max_step, max_sweep):
    if arc:
        code, cx, cy = arc_fit(P, i, j, tol, grid, scale, max_radius, max_step, max_sweep)
        return code != 0, code, cx, cy
    return line_ok(P, i, j, tol), 0, math.nan, math.nan


@njit(cache=True)
def _longest(P, i, first, tol, arc, grid, scale, max_radius, max_step, max_sweep, max_span):
    """A large ``j`` in [first, min(n, first + max_span)] whose piece P[i..j] fits: every doubling
    ``first - 1 + 2**k`` is probed (a short piece may fail where a longer one fits: an arc centre is
    ill-determined over a short, noisy run), then bisection between the longest one that fits and the
    next probe. Returns ``(j, fits, code, cx, cy)``; ``(first - 1, False, ...)`` when no probe fits."""
    n = P.shape[0] - 1
    last = min(n, first - 1 + max_span)
    probes = np.empty(64, np.int64)
    k = 0
    step = 1
    while first - 1 + step <= last:
        probes[k] = first - 1 + step
        k += 1
        step *= 2
    if k == 0 or probes[k - 1] != last:
        probes[k] = last
        k += 1
    best, found, code, cx, cy, hi = first - 1, False, 0, math.nan, math.nan, last + 1
    for q in range(k - 1, -1, -1):
        ok, c, x, y = _piece(P, i, probes[q], tol, arc, grid, scale, max_radius, max_step, max_sweep)
        if ok:
            best, found, code, cx, cy = probes[q], True, c, x, y
            hi = probes[q + 1] if q + 1 < k else last + 1
            break
    lo = best
    while best >= first and hi - lo > 1:
        mid = (lo + hi) // 2
        ok, c, x, y = _piece(P, i, mid, tol, arc, grid, scale, max_radius, max_step, max_sweep)
        if ok:
            lo, best, found, code, cx, cy = mid, mid, True, c, x, y
        else:
            hi = mid
    return best, found, code, cx, cy


@njit(cache=True)
def fit_run(P, tol, grid, scale, max_radius, max_step, max_sweep, arcs, max_span):
    """The pieces covering the polyline ``P`` (n + 1, 3), greedily the longest from each start: arrays
    of the end index in P, the arc code (0 line, 2/3 arc) and the centre (NaN for lines); an arc is
    taken only when it reaches further than the longest line. ``tol`` [mm] per chord of ``P``."""
    n = P.shape[0] - 1
    ends = np.empty(n, np.int64)
    codes = np.empty(n, np.int64)
    cxs = np.empty(n)
    cys = np.empty(n)
    k = 0
    i = np.int64(0)        # int64 and np.bool_ arguments: one compiled _longest, not one per literal
    while i < n:
        jl, _, _, _, _ = _longest(P, i, i + 1, tol, np.bool_(False), grid, scale, max_radius, max_step, max_sweep, max_span)
        jl = max(jl, i + 1)
        ja, found = i, False
        code, cx, cy = 0, math.nan, math.nan
        if arcs and n - i >= 2:
            ja, found, code, cx, cy = _longest(P, i, i + 2, tol, np.bool_(True), grid, scale, max_radius, max_step,
                                               max_sweep, max_span)
        if found and ja > jl:
            ends[k], codes[k], cxs[k], cys[k] = ja, code, cx, cy
            i = ja
        else:
            ends[k], codes[k], cxs[k], cys[k] = jl, 0, math.nan, math.nan
            i = jl
        k += 1
    return ends[:k], codes[:k], cxs[:k], cys[:k]
