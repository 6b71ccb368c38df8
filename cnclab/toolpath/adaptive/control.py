"""The engagement controller (see the package docstring, "Step control" and "Sliver guard"): the
engagement of a tool circle on the pixel stock at two material levels (:func:`engagement2`), the heading
search for the target (:func:`search_heading`: Newton step from the last slope, Illinois false position
:func:`root_bracket`), the wall-limited heading (:func:`wall_heading`), one clearing pass
(:func:`pass_kernel`) and the replay of a fixed polyline on the stock (:func:`replay`). Units: mm, rad.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .links import bow_runs, mark_free
from .stock import cut_disc, cut_disc_both, material_fraction, inside_mask


#: material level of the sliver guard (see pass_kernel): a bilinear fraction of 0.1 counts crescents
#: down to ~ h/20 thick (the evaluator's dixel rows resolve them along the arc)
GUARD_LEVEL = 0.1


@njit(cache=True)
def arc_inside(fa, fb, da):
    """The part of an arc step of ``da`` rad whose (linearly interpolated) level function f - level
    is >= 0, from its values fa, fb at the two ends."""
    if fa >= 0.0 and fb >= 0.0:
        return da
    if fa >= 0.0:
        return da * fa / (fa - fb)
    if fb >= 0.0:
        return da * fb / (fb - fa)
    return 0.0


@njit(cache=True)
def engagement2(M, x0, y0, h, cx, cy, r, psi, n, level, level2):
    """Engagement (rad) of the front half circle (heading psi) with the material, at two material
    levels from the same arc samples: ``(engagement at level, engagement at level2)``.

    Where the whole arc lies in the grid, the bilinear stencil is read without bounds checks (pixel
    coordinates, the multiplication by 1/h: equal to :func:`material_fraction` up to rounding).

    The material is the region where the bilinear pixel fraction is >= ``level`` (1/2: its boundary
    passes half-way between a material and an empty pixel centre, on the wall for pixel-aligned
    walls; a lower level also counts slivers thinner than a pixel: the conservative guard);
    the arc is sampled at n + 1 angles (rotated by a fixed step) and the crossings between samples
    are interpolated linearly, so a thin rest along a wall counts with its full arc (an averaged
    fraction would under-count an arc running nearly tangent to it)."""
    ny, nx = M.shape
    tot = 0.0
    tot2 = 0.0
    da = math.pi / n
    cd = math.cos(da)
    sd = math.sin(da)
    a = psi - 0.5 * math.pi
    c = math.cos(a)
    s = math.sin(a)
    # pixel coordinates: the bilinear stencil of a point (u, v) is (floor u, floor v) + {0, 1}^2
    ih = 1.0 / h
    u0 = (cx - x0) * ih - 0.5
    v0 = (cy - y0) * ih - 0.5
    R = r * ih
    fast = u0 - R >= 0.0 and u0 + R < nx - 1 and v0 - R >= 0.0 and v0 + R < ny - 1   # whole arc in the grid
    fa = 0.0
    ga = 0.0
    for k in range(n + 1):
        if k > 0:
            c, s = c * cd - s * sd, s * cd + c * sd
        if fast:
            u = u0 + R * c
            v = v0 + R * s
            i = int(u)
            j = int(v)
            tx = u - i
            ty = v - j
            f = ((M[j, i] * (1.0 - tx) + M[j, i + 1] * tx) * (1.0 - ty)
                 + (M[j + 1, i] * (1.0 - tx) + M[j + 1, i + 1] * tx) * ty)
        else:
            f = material_fraction(M, x0, y0, h, cx + r * c, cy + r * s)
        fb = f - level
        gb = f - level2
        if k > 0:
            tot += arc_inside(fa, fb, da)
            tot2 += arc_inside(ga, gb, da)
        fa = fb
        ga = gb
    return tot, tot2


#: heading root finding (root_bracket): stop once the engagement is within this (rad) below its bound
ROOT_TOL = math.radians(1.0)


@njit(cache=True, inline="always")
def probe(Q, m):
    """(engagement at the 1/2 level, at the guard level) rad of the step at heading ``m`` (rad) from
    the probe ``Q`` = (M, x0, y0, h, r, px, py, ds, n_samp, guard_level): the stock, its grid, the tool
    radius, the step's start (mm), length (mm), arc samples and guard level (:func:`engagement2`)."""
    M, x0, y0, h, r, px, py, ds, n_samp, guard_level = Q
    return engagement2(M, x0, y0, h, px + ds * math.cos(m), py + ds * math.sin(m), r, m, n_samp, 0.5, guard_level)


@njit(cache=True)
def root_bracket(Q, a, b, fa, fb, e_a, g_a, bound, which):
    """Heading between ``a`` (engagement <= bound: f(a) = fa <= 0, engagements e_a at the 1/2 level
    and g_a at the guard level) and ``b`` (f(b) = fb > 0) of the step of the probe ``Q`` (:func:`probe`)
    whose engagement -- the 1/2 level (``which`` 0) or the guard level (1) -- is at most ``bound``
    and within ROOT_TOL of it (Illinois false position: a bracketing method, 2-4 evaluations where
    bisection needs 16). Returns (heading, engagement at 1/2, at the guard level, slope df/dheading
    of the final bracket) of the ``a`` end."""
    ta = fa          # the true f(a), f(b) (fa, fb are halved by the Illinois rule)
    tb = fb
    side = 0
    for _ in range(40):
        if ta >= -ROOT_TOL or abs(b - a) < 1e-6:
            break
        m = (a * fb - b * fa) / (fb - fa)
        if not (min(a, b) < m < max(a, b)):
            m = 0.5 * (a + b)
        e, g = probe(Q, m)
        fm = (e if which == 0 else g) - bound
        if fm > 0.0:
            b = m
            fb = fm
            tb = fm
            if side == -1:
                fa *= 0.5
            side = -1
        else:
            a = m
            fa = fm
            ta = fm
            e_a = e
            g_a = g
            if side == 1:
                fb *= 0.5
            side = 1
    return a, e_a, g_a, (tb - ta) / (b - a) if b != a else 0.0


#: a slide along the wall (see pass_kernel) may exceed the target engagement by this much (rad)
SLIDE_MARGIN = math.radians(1.0)


#: first bracketing step (rad) of :func:`search_heading`; doubled until the root is bracketed
BRACKET_STEP = math.radians(2.0)


@njit(cache=True)
def _first_guess(Q, lo, hi, m0, bound, which, slope):
    """The first two evaluations of :func:`search_heading`: at ``m0`` (clipped to [hi, lo]) and at
    the Newton (or bracketing) step from it. Returns (done, status, m0, e0, g0, f0, m1, e1, g1, f1,
    slope): ``done`` True when the search ends there with (status, m1, e1, g1, slope)."""
    m0 = min(max(m0, hi), lo)
    e0, g0 = probe(Q, m0)
    f0 = (e0 if which == 0 else g0) - bound
    if -ROOT_TOL <= f0 <= 0.0:
        return True, 0, m0, e0, g0, f0, m0, e0, g0, f0, slope
    if f0 <= 0.0 and (m0 <= hi or g0 == 0.0):
        m1 = hi                          # holds at the right end, or nothing in front: hard right
    elif f0 > 0.0 and m0 >= lo:
        return True, 1, m0, e0, g0, f0, m0, e0, g0, f0, slope
    else:
        stp = -f0 / slope if slope < 0.0 else (BRACKET_STEP if f0 > 0.0 else -BRACKET_STEP)
        stp = min(max(stp, -4.0 * BRACKET_STEP), 4.0 * BRACKET_STEP)
        m1 = min(max(m0 + stp, hi), lo)
    if m1 == m0:
        m1 = min(max(m0 + (BRACKET_STEP if f0 > 0.0 else -BRACKET_STEP), hi), lo)
        if m1 == m0:                     # a zero-width search interval
            return True, (0 if f0 <= 0.0 else 1), m0, e0, g0, f0, m0, e0, g0, f0, slope
    e1, g1 = probe(Q, m1)
    f1 = (e1 if which == 0 else g1) - bound
    if (f1 - f0) / (m1 - m0) < 0.0:
        slope = (f1 - f0) / (m1 - m0)
    if -ROOT_TOL <= f1 <= 0.0:
        return True, 0, m0, e0, g0, f0, m1, e1, g1, f1, slope
    return False, 0, m0, e0, g0, f0, m1, e1, g1, f1, slope


@njit(cache=True)
def search_heading(Q, lo, hi, m0, bound, which, slope):
    """Heading of the step of the probe ``Q`` (:func:`probe`) whose engagement (1/2 level: ``which`` 0;
    guard level: 1) is at most ``bound`` and within ROOT_TOL of it, searched in [hi, lo] (rad; ``lo``
    the hard left turn, least engagement; ``hi`` the hard right turn or the wall) from the guess
    ``m0``: a Newton step with ``slope`` (d engagement / d heading of the last step, < 0), then
    bracketing steps (doubling) and :func:`root_bracket`. Returns (status, heading, engagement at 1/2, at
    the guard level, slope): status 0 found (or the right end ``hi`` already holds: taken), 1 even
    the hard left exceeds ``bound`` (stuck)."""
    done, status, m0, e0, g0, f0, m1, e1, g1, f1, slope = _first_guess(Q, lo, hi, m0, bound, which, slope)
    if done:
        return status, m1, e1, g1, slope
    if (f0 > 0.0) != (f1 > 0.0):
        if f0 <= 0.0:
            a, fa, ea, ga, b, fb = m0, f0, e0, g0, m1, f1
        else:
            a, fa, ea, ga, b, fb = m1, f1, e1, g1, m0, f0
    elif f1 <= 0.0:
        a, fa, ea, ga = m1, f1, e1, g1   # still below: turn further right until the bound is exceeded
        st = max(abs(m1 - m0), BRACKET_STEP)
        while True:
            if a <= hi:
                return 0, a, ea, ga, slope
            m = max(a - st, hi)
            e, g = probe(Q, m)
            f = (e if which == 0 else g) - bound
            if f > 0.0:
                b, fb = m, f
                break
            a, fa, ea, ga = m, f, e, g
            if f >= -ROOT_TOL:
                return 0, a, ea, ga, slope
            st *= 2.0
    else:
        b, fb = m1, f1                   # still above: turn further left until the bound holds
        st = max(abs(m1 - m0), BRACKET_STEP)
        while True:
            if b >= lo:
                return 1, b, e1, g1, slope
            m = min(b + st, lo)
            e, g = probe(Q, m)
            f = (e if which == 0 else g) - bound
            if f <= 0.0:
                a, fa, ea, ga = m, f, e, g
                break
            b, fb = m, f
            st *= 2.0
    psi, e, g, sl = root_bracket(Q, a, b, fa, fb, ea, ga, bound, which)
    if sl < 0.0:
        slope = sl
    return 0, psi, e, g, slope


@njit(cache=True)
def wall_heading(Amask, x0, y0, h, px, py, ds, lo, b):
    """The rightmost heading between ``lo`` (hard left; must stay in the mask) and ``b`` (leaves it)
    whose step of ``ds`` from (px, py) stays in the tool-centre mask (14 bisections: the pass slides
    along the wall); NaN when even ``lo`` leaves it."""
    if not inside_mask(Amask, x0, y0, h, px + ds * math.cos(lo), py + ds * math.sin(lo)):
        return np.nan
    a = lo
    for _ in range(14):
        m = 0.5 * (a + b)
        if inside_mask(Amask, x0, y0, h, px + ds * math.cos(m), py + ds * math.sin(m)):
            a = m
        else:
            b = m
    return a


@njit(cache=True)
def step_heading(M, Amask, D, K, px, py, phi, dpsi, was_air, slope, slope_g):
    """The heading of a pass's next step from (px, py) mm (the last heading ``phi``, its change
    ``dpsi``, rad; ``was_air``: the last step met no material, the guess is then the hard right
    turn; ``slope``/``slope_g``: the last roots' slopes). ``K``: the pass's settings (x0, y0, h, hc, r,
    ds, n_samp, guard_level, turn, turn_right, target, guard, air_reach) of :func:`pass_kernel`.
    Returns (stop, psi, e, eg, slope, slope_g): ``stop`` -1 a step at psi with engagements e (1/2
    level) and eg (guard level), rad; 0 the step would leave the region, 1 stuck."""
    x0, y0, h, hc, r, ds, n_samp, guard_level, turn, turn_right, target, guard, air_reach = K
    Q = (M, x0, y0, h, r, px, py, ds, n_samp, guard_level)
    lo = phi + turn          # hard left: least engagement
    hi = phi - turn_right    # hard right (curvature limited): most engagement
    # the right end of the search: the hard right turn, or where it would leave the tool-centre
    # region, the rightmost heading that stays inside (the pass slides along the wall)
    if not inside_mask(Amask, x0, y0, h, px + ds * math.cos(hi), py + ds * math.sin(hi)):
        hi = wall_heading(Amask, x0, y0, h, px, py, ds, lo, hi)
        if hi != hi:
            return 0, 0.0, 0.0, 0.0, slope, slope_g
    jc = int(math.floor((py - y0) / hc))
    ic = int(math.floor((px - x0) / hc))
    if 0 <= jc < D.shape[0] and 0 <= ic < D.shape[1] and D[jc, ic] > air_reach:
        psi = hi
        e = 0.0
        eg = 0.0
    else:
        st, psi, e, eg, slope = search_heading(Q, lo, hi, hi if was_air else phi + dpsi, target, np.int64(0), slope)
        if st == 1:
            return 1, psi, e, eg, slope, slope_g
    if eg > guard:
        # the guard: the engagement with every sliver of material counted (level GUARD_LEVEL) stays
        # within ``guard``; where the arc runs nearly tangent to a cut boundary (corner rests,
        # crescents between passes) the 1/2 level can miss a few degrees of thin slivers: turn left
        # until it holds
        st, psi, e, eg, slope_g = search_heading(Q, lo, psi, psi, guard, np.int64(1), slope_g)
        if st == 1:
            return 1, psi, e, eg, slope, slope_g
    if not inside_mask(Amask, x0, y0, h, px + ds * math.cos(psi), py + ds * math.sin(psi)):
        # the headings that stay inside need not be contiguous (a corner of the region between the
        # wall-limited right end and the hard left): slide to the inside boundary between the hard
        # left and psi, where the engagement may exceed the target by at most 1 deg, else stop
        psi = wall_heading(Amask, x0, y0, h, px, py, ds, lo, psi)
        if psi != psi:
            return 0, psi, e, eg, slope, slope_g
        e, eg = probe(Q, psi)
        if e > target + SLIDE_MARGIN:
            return 1, psi, e, eg, slope, slope_g
        if eg > guard:
            st, psi, e, eg, slope_g = search_heading(Q, lo, psi, psi, guard, np.int64(1), slope_g)
            if st == 1 or not inside_mask(Amask, x0, y0, h, px + ds * math.cos(psi), py + ds * math.sin(psi)):
                return 1, psi, e, eg, slope, slope_g
    return -1, psi, e, eg, slope, slope_g


@njit(cache=True)
def pass_kernel(M, Amask, Mr, D, grid, tool, start, control, steps):
    """One engagement-controlled pass; cuts M (all disks flushed at the end) and the rapid stock
    ``Mr`` (the same discs, radius ``r_rapid``) in step with it. ``grid`` (x0, y0, h, hc): the
    stocks' origin and pixel, the coarse cell of ``D`` (mm); ``tool`` (r, r_rapid, r_capsule) mm;
    ``start`` (sx, sy mm, heading rad); ``control`` (target, guard rad, guard_level, n_samp,
    air_eng rad); ``steps`` (ds, lag mm, max_steps, air_stop mm, turn, turn_right rad, max_len mm).

    ``D``: the coarse distance field (cells of ``hc`` mm) of the stock as it was at the start or
    earlier (material only goes: a lower bound of the distance now); where it proves that no
    material lies within reach of any candidate step (r + ds + the cell and pixel margins), the
    step is air without sampling the arc: the hard right turn, engagement 0 (:func:`step_heading`).

    Returns (points (n, 2), removed area mm^2, reason, engagement (n,) rad of each step, free (n,)):
    reason 0 left the region, 1 stuck (cannot lower the engagement), 2 air, 3 step limit; ``free[k]``:
    step k is an air step (engagement < ``air_eng`` rad) whose chord has no pixel of the rapid stock
    within ``r_capsule`` (0: not checked): a G0 through cleared area. The steps of an air run are
    checked when the run ends (dropped runs never): the discs held back since its start are not yet
    cut, so the rapid stock then holds at least the material each of its steps meets."""
    x0, y0, h, hc = grid
    r, r_rapid, r_capsule = tool
    target, guard, guard_level, n_samp, air_eng = control
    ds, lag, max_steps, air_stop, turn, turn_right, max_len = steps
    # no material pixel centre within r + ds + h of any arc sample point: the coarse cell centre may be
    # hc/sqrt(2) from the point, the material pixel hc/sqrt(2) from its cell's centre
    K = (x0, y0, h, hc, r, ds, n_samp, guard_level, turn, turn_right, target, guard, r + ds + h + math.sqrt(2.0) * hc)
    P = np.empty((max_steps + 1, 2))
    E = np.zeros(max_steps + 1)
    F = np.zeros(max_steps + 1, np.bool_)
    P[0, 0] = start[0]
    P[0, 1] = start[1]
    s = np.zeros(max_steps + 1)
    # int64 / np.bool_ from the start: the kernels called with them compile once, not once per literal
    n, k_cut, removed, air, n_air_start, reason = np.int64(1), 0, 0.0, 0.0, np.int64(1), 3
    phi = start[2]
    dpsi = 0.0       # the last heading change: the guess of the next one
    slope = -1.0     # d engagement / d heading (rad/rad) of the last root: the Newton step of the next
    slope_g = -1.0
    was_air = np.bool_(False)  # the last step met no material at all: the next guess is the hard right turn
    span = np.empty((M.shape[0], 4), np.int64)   # the last disc's row spans (see cut_disc_both)
    rows = np.array([1, 0], np.int64)
    for step in range(max_steps):
        if s[n - 1] >= max_len:
            break
        px = P[n - 1, 0]
        py = P[n - 1, 1]
        # during a run through air the disks are held back: the run may be dropped from the pass
        # (air stop), and the stock must hold exactly what the emitted path removes
        k_hold = n_air_start if air > 0.0 else n
        while k_cut < k_hold and s[n - 1] - s[k_cut] > lag:
            removed += cut_disc_both(M, Mr, x0, y0, h, P[k_cut, 0], P[k_cut, 1], r, r_rapid, span, rows)
            k_cut += 1
        stop, psi, e, eg, slope, slope_g = step_heading(M, Amask, D, K, px, py, phi, dpsi, was_air, slope, slope_g)
        if stop >= 0:
            reason = stop
            break
        was_air = eg == 0.0
        if e < 0.3 * target:
            if air == 0.0:
                n_air_start = n
            air += ds
            if air > air_stop:
                reason = 2
                n = n_air_start
                break
        else:
            if air > 0.0 and r_capsule > 0.0:
                mark_free(Mr, x0, y0, h, P, E, F, n_air_start, n, air_eng, r_capsule)
                bow_runs(Mr, Amask, (x0, y0, h), P, E, F, n_air_start, n, air_eng, r_capsule, 2.0 * h, 4)
            air = 0.0
        P[n, 0] = px + ds * math.cos(psi)
        P[n, 1] = py + ds * math.sin(psi)
        E[n] = e
        s[n] = s[n - 1] + ds
        n += 1
        dpsi = psi - phi
        phi = psi
    if air > 0.0 and reason != 2 and r_capsule > 0.0:
        mark_free(Mr, x0, y0, h, P, E, F, n_air_start, n, air_eng, r_capsule)
        bow_runs(Mr, Amask, (x0, y0, h), P, E, F, n_air_start, n, air_eng, r_capsule, 2.0 * h, 4)
    while k_cut < n:
        removed += cut_disc_both(M, Mr, x0, y0, h, P[k_cut, 0], P[k_cut, 1], r, r_rapid, span, rows)
        k_cut += 1
    return P[:n].copy(), removed, reason, E[:n].copy(), F[:n].copy()


@njit(cache=True)
def replay(M, x0, y0, h, r, P, lag, n_samp, level2):
    """Cut the fixed points P (n, 2) into M in order, the disks of the last ``lag`` mm held back as
    in :func:`pass_kernel`; the engagement (rad) measured at each point (heading: the chord from the point
    before; 0 at P[0]) at the 1/2 material level and at ``level2``: two arrays (n,)."""
    n = P.shape[0]
    E = np.zeros(n)
    G = np.zeros(n)
    s = np.zeros(n)
    k_cut = 0
    pcx = np.nan
    pcy = np.nan
    for i in range(1, n):
        dx = P[i, 0] - P[i - 1, 0]
        dy = P[i, 1] - P[i - 1, 1]
        s[i] = s[i - 1] + math.hypot(dx, dy)
        while k_cut < i and s[i] - s[k_cut] > lag + 1e-12:
            cut_disc(M, x0, y0, h, P[k_cut, 0], P[k_cut, 1], r, pcx, pcy)
            pcx = P[k_cut, 0]
            pcy = P[k_cut, 1]
            k_cut += 1
        if dx != 0.0 or dy != 0.0:
            E[i], G[i] = engagement2(M, x0, y0, h, P[i, 0], P[i, 1], r, math.atan2(dy, dx), n_samp, 0.5, level2)
    while k_cut < n:
        cut_disc(M, x0, y0, h, P[k_cut, 0], P[k_cut, 1], r, pcx, pcy)
        pcx = P[k_cut, 0]
        pcy = P[k_cut, 1]
        k_cut += 1
    return E, G
