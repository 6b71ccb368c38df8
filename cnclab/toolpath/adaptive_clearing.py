"""Engagement-controlled clearing of any 2.5D pocket (islands, necks, several regions): the tool
follows the boundary of the cleared region, each step steered so that its engagement angle equals
the target, and links at depth through the cleared region (issue 16).

Units: lengths mm, angles deg at the API (rad inside the kernels), feeds mm/min; ``tool_radius`` is
the radius of the flat end mill. The pocket is a shapely Polygon/MultiPolygon whose holes are islands.

Design (the ideas and where they come from; the code is cnclab's own)
--------------------------------------------------------------------
* **The cleared region is the state** (Jacsó 2021, Thesis III: the constant-engagement path is the
  offset of the *cleared boundary*, not of the pocket contour). It is kept as a pixel stock
  (``h = r/60``, the tool-radius resolution of the evaluator) that the planner cuts as it goes.
* **Step control by the engagement angle** (Thesis III's constant engagement, Adaptive2d's per-step
  direction search): from the current point the next point is ``ds`` (default r/30) away; its
  heading is searched between a hard left turn (away from the material, material on the right:
  climb milling with an M3 spindle) and a hard right turn (or, where that would leave the
  tool-centre region, the rightmost heading that stays in it: the pass slides along the wall) so
  that the engagement measured
  on the stock -- the material fraction of the front half of the tool circle, the quantity the
  evaluator scores, on the 1/2 contour of the bilinear pixel stock with the crossings between the
  arc samples interpolated -- equals ``theta``. Libarea's ``Adaptive2d`` does the same with the *area cut
  per unit length* (its ``stepOverFactor``); at a constant step the two are equivalent to first
  order, and the angle is what is promised, so the angle is controlled directly. The search starts
  from the last step's turn rate, takes a Newton step with the last step's slope d(engagement)/
  d(heading) and closes the bracket by false position (Illinois), stopping within ROOT_TOL (1 deg)
  below the target: 2-3 arc evaluations a step. Air steps turn hard right at once. Disks are cut
  into the planning stock with the evaluator's lag (the last ``2 sqrt(2 r h) + 2 h`` mm not yet
  cut) so the planner measures what the evaluator will measure.
* **Sliver guard**: where the tool circle runs nearly tangent to a cut boundary -- re-entering a
  corner another pass left, a pass start beside a crescent -- the engagement angle jumps although
  the chip is thin, and the 1/2 contour can miss a sub-pixel crescent. Every step is therefore also
  measured with any material counted (bilinear fraction >= ``GUARD_LEVEL``); where that exceeds
  ``theta + guard_deg`` (5 deg) the heading turns left until it holds, or the pass ends.
  Consequence: the tool centre stops short of a concave corner of the tool-centre region (reaching
  it means touching the unreachable corner over ~180 deg minus the corner angle): a wedge about as
  large as the unreachable corner itself stays (less than FreeCAD Adaptive leaves, see
  ``benchmarks/bench_vs_freecad.py``).
* **A pass ends** when the next point would leave the tool-centre region (pocket shrunk by r), when
  even the hardest left turn cannot bring the engagement down to the target, or when the tool has
  run ``1.5 r`` through air (that air tail is dropped; a pass that met no material at all in a band
  narrower than the tool is tried once more with ``3.5 r``, kept if it removes 0.2 a_e per mm: the
  way to the face of a neck is a loop mostly through air). Kim & Yang's insertion idea -- insert a path only where the regular
  pass would leave material -- becomes the start rule: every pass starts at the cleared-region
  point *nearest through cleared area* to where the tool is whose disk just touches material
  (distance to the nearest material = r), heading along the material boundary; the controller
  then turns into the material and settles at ``theta`` (no perpendicular approach: no slotting).
  Where the tool-centre region is narrower than the turning circle and a pass runs straight into
  air, it is started once the other way round (the face at the end of a band lies behind it).
* **Links** (Adaptive2d's ``keepToolDown`` linking through cleared area): the start of the next
  pass is found by a Dijkstra search over the cells whose tool disk is free of material (distance
  field of the stock on a coarse grid, capped just above r and recomputed only in the window the
  last change of the stock can reach) inside the tool-centre region, starting where the tool is;
  the cell route is shortened to straight chords that stay in that free set and written as rapids
  at depth tagged ``cleared`` (FreeCAD writes its keep-tool-down links as G0 too; the evaluator
  counts any rapid that removes material) or, with ``rapid_links=False``, as feed moves (``link``,
  link feed). Only when no free route exists (a disjoint region, material
  closing the way) does the tool retract, rapid at clearance and enter again.
* **Remnants**: where no border cell can be reached through cleared area but a free-standing remnant
  of material is left (a pillar the passes around it could not take), one straight feed move from a
  free point to where the tool disc holds the whole remnant takes it, if the remnant lies within
  r sin(theta/2) of its centre (the move then meets it over at most theta) and the move meets no
  other material; otherwise the tool enters there by helix. A place entered before is banned.
* **Entries**: a pre-drilled start hole is used as it is (plunge into the hole, air); otherwise a
  helix (G3 turns, 5 deg ramp like FreeCAD's default) at the point of the tool-centre region
  farthest from its boundary (the centre of the largest inscribed circle), radius
  ``min(0.75 r, 0.9 x inscribed radius - h)`` (FreeCAD's is 0.75 r too), then a floor circle;
  each entry's engagement is reported apart by the evaluator. A place that allows less than
  ``0.1 r`` (a helix of a few hundredths of a mm is a plunge) is banned unless its part of the
  tool-centre region is that narrow everywhere.
* **Finish**: one contour pass along every ring of the tool-centre region (outer rings
  counter-clockwise, islands clockwise: climb milling), started where the ring is already free of
  material, takes the thin rests the passes left against the walls (thinner than ``a_e`` where the
  passes reached the walls); it runs under the same engagement control with the target raised by
  ``finish_margin_deg`` (6 deg: the simulator measures up to ~3 deg more than the planning stock on
  the thin wall rests, and theta + 10 deg is the bound) so that the corner wedges are peeled instead
  of refused; the lap starts at the free ring point nearest the tool. Points planned within 2 h of
  the wall are snapped onto the nearest wall point (1 um inside
  the 64-segment tool-centre limit); the lap is replayed on the stock (chords the snap made longer
  than 1.5 ds sampled along their length) and a snapped point whose engagement would exceed theta +
  2 deg, at the 1/2 level or with slivers counted, keeps its planned place. Each part of the
  tool-centre region is finished before the tool leaves it (no extra lift). Up to ``clean_rounds``
  further rounds of passes and finishing take material the bans left (only while some lies deeper
  than 2 coarse cells inside the tool's reach).
* **Lifts** are G0 straight up (as FreeCAD's); links at depth are G0 only where no material pixel
  lies within r + h/sqrt(2) of the chord (``rapid_links``) on the *rapid stock*: the same discs cut
  with radius r - h/sqrt(2), so that the tool disc of such a chord is truly swept (sub-pixel cusps
  between passes, which the planning stock cannot show, never meet a rapid). A chord on the line of
  the wall-following pass that left the wall skin is tangent to it and never proven: an air run
  along it is moved 2 h to its left (away from the material on the pass's right) with feed legs
  off and back on the line, and a link from or to a wall point gets a feed leg of 2 h or 4 h, where
  that makes the rest provable (:func:`_bow_runs`, :func:`_rapid_legs`).
* **Refusal**: a pocket in which the tool does not fit (the tool-centre region is empty or thinner
  than the resolution) raises ValueError naming the job source and the reason.

>>> from shapely.geometry import box
>>> tp = adaptive_clearing(box(0, 0, 24, 18), tool_radius=3, theta_deg=60, a_p=1, feed_mm_min=255)
>>> sorted(set(tp.kinds()))
['cut', 'helix', 'link', 'plunge', 'rapid']
>>> bool(np.all(tp.xyz[tp.is_kind("plunge"), 2] >= 0.0))   # the only plunge ends on the stock top (air)
True
"""
from __future__ import annotations

import math
import time

import numpy as np
import shapely
from numba import njit
from shapely.geometry import LineString, MultiPolygon, Point, Polygon
from shapely.geometry.polygon import orient

from .path import Tool, ToolPath

__all__ = ["adaptive_clearing", "plan_job", "PlanningError"]


class PlanningError(ValueError):
    """The pocket cannot be machined safely with this tool (the message says why)."""


# ------------------------------------------------------------------------------------------------
# compiled kernels (pixel stock: M[j, i] = 1 material, pixel centre x0 + (i + 0.5) h, y0 + (j + 0.5) h)
# ------------------------------------------------------------------------------------------------
@njit(cache=True)
def _cut(M, x0, y0, h, cx, cy, r, pcx, pcy):
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
def _cut_both(M, Mr, x0, y0, h, cx, cy, r, rr, span, rows):
    """:func:`_cut` of the disc (cx, cy, r) into M and of (cx, cy, rr) into Mr (rr <= r) in one pass over
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
def _frac(M, x0, y0, h, x, y):
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


#: material level of the sliver guard (see _pass): a bilinear fraction of 0.1 counts crescents
#: down to ~ h/20 thick (the evaluator's dixel rows resolve them along the arc)
GUARD_LEVEL = 0.1

#: entry helix radius (fraction of the tool radius r; FreeCAD Adaptive's helix is 0.75 r too), and the
#: smallest accepted where the part of the tool-centre region is wider: a helix of a few hundredths of
#: a mm is a plunge (a place that narrow is banned; the passes reach it from elsewhere)
HELIX_RADIUS_FRAC = 0.75
HELIX_MIN_FRAC = 0.1

#: air allowance (in r) of the second try of a pass that met no material in a band narrower than r, and
#: the area it must remove per mm of its length (in a_e) to be kept (else the place is banned as before;
#: random pockets: 9 % fewer entries for 1 % more program time)
NARROW_AIR_STOP = 3.5
NARROW_MIN_YIELD = 0.2


@njit(cache=True)
def _arc_inside(fa, fb, da):
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
def _eng2(M, x0, y0, h, cx, cy, r, psi, n, level, level2):
    """Engagement (rad) of the front half circle (heading psi) with the material, at two material
    levels from the same arc samples: ``(engagement at level, engagement at level2)``.

    Where the whole arc lies in the grid, the bilinear stencil is read without bounds checks (pixel
    coordinates, the multiplication by 1/h: equal to :func:`_frac` up to rounding).

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
            f = _frac(M, x0, y0, h, cx + r * c, cy + r * s)
        fb = f - level
        gb = f - level2
        if k > 0:
            tot += _arc_inside(fa, fb, da)
            tot2 += _arc_inside(ga, gb, da)
        fa = fb
        ga = gb
    return tot, tot2


#: heading root finding (_root): stop once the engagement is within this (rad) below its bound
ROOT_TOL = math.radians(1.0)


@njit(cache=True)
def _root(M, x0, y0, h, r, px, py, ds, n_samp, guard_level, a, b, fa, fb, e_a, g_a, bound, which):
    """Heading between ``a`` (engagement <= bound: f(a) = fa <= 0, engagements e_a at the 1/2 level
    and g_a at the guard level) and ``b`` (f(b) = fb > 0) of the step of length ``ds`` from (px, py)
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
        e, g = _eng2(M, x0, y0, h, px + ds * math.cos(m), py + ds * math.sin(m), r, m, n_samp, 0.5, guard_level)
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


#: a slide along the wall (see _pass) may exceed the target engagement by this much (rad)
SLIDE_MARGIN = math.radians(1.0)

#: first bracketing step (rad) of :func:`_heading`; doubled until the root is bracketed
BRACKET_STEP = math.radians(2.0)


@njit(cache=True)
def _heading(M, x0, y0, h, r, px, py, ds, n_samp, guard_level, lo, hi, m0, bound, which, slope):
    """Heading of the step of length ``ds`` from (px, py) whose engagement (1/2 level: ``which`` 0;
    guard level: 1) is at most ``bound`` and within ROOT_TOL of it, searched in [hi, lo] (rad; ``lo``
    the hard left turn, least engagement; ``hi`` the hard right turn or the wall) from the guess
    ``m0``: a Newton step with ``slope`` (d engagement / d heading of the last step, < 0), then
    bracketing steps (doubling) and :func:`_root`. Returns (status, heading, engagement at 1/2, at
    the guard level, slope): status 0 found (or the right end ``hi`` already holds: taken), 1 even
    the hard left exceeds ``bound`` (stuck)."""
    m0 = min(max(m0, hi), lo)
    e0, g0 = _eng2(M, x0, y0, h, px + ds * math.cos(m0), py + ds * math.sin(m0), r, m0, n_samp, 0.5, guard_level)
    f0 = (e0 if which == 0 else g0) - bound
    if -ROOT_TOL <= f0 <= 0.0:
        return 0, m0, e0, g0, slope
    if f0 <= 0.0 and (m0 <= hi or g0 == 0.0):
        m1 = hi                          # holds at the right end, or nothing in front: hard right
    elif f0 > 0.0 and m0 >= lo:
        return 1, m0, e0, g0, slope
    else:
        stp = -f0 / slope if slope < 0.0 else (BRACKET_STEP if f0 > 0.0 else -BRACKET_STEP)
        stp = min(max(stp, -4.0 * BRACKET_STEP), 4.0 * BRACKET_STEP)
        m1 = min(max(m0 + stp, hi), lo)
    if m1 == m0:
        m1 = min(max(m0 + (BRACKET_STEP if f0 > 0.0 else -BRACKET_STEP), hi), lo)
        if m1 == m0:                     # a zero-width search interval
            return (0 if f0 <= 0.0 else 1), m0, e0, g0, slope
    e1, g1 = _eng2(M, x0, y0, h, px + ds * math.cos(m1), py + ds * math.sin(m1), r, m1, n_samp, 0.5, guard_level)
    f1 = (e1 if which == 0 else g1) - bound
    if (f1 - f0) / (m1 - m0) < 0.0:
        slope = (f1 - f0) / (m1 - m0)
    if -ROOT_TOL <= f1 <= 0.0:
        return 0, m1, e1, g1, slope
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
            e, g = _eng2(M, x0, y0, h, px + ds * math.cos(m), py + ds * math.sin(m), r, m, n_samp, 0.5, guard_level)
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
            e, g = _eng2(M, x0, y0, h, px + ds * math.cos(m), py + ds * math.sin(m), r, m, n_samp, 0.5, guard_level)
            f = (e if which == 0 else g) - bound
            if f <= 0.0:
                a, fa, ea, ga = m, f, e, g
                break
            b, fb = m, f
            st *= 2.0
    psi, e, g, sl = _root(M, x0, y0, h, r, px, py, ds, n_samp, guard_level, a, b, fa, fb, ea, ga, bound, which)
    if sl < 0.0:
        slope = sl
    return 0, psi, e, g, slope


@njit(cache=True)
def _inside(Amask, x0, y0, h, x, y):
    ny, nx = Amask.shape
    i = int(math.floor((x - x0) / h))
    j = int(math.floor((y - y0) / h))
    if i < 0 or j < 0 or i >= nx or j >= ny:
        return False
    return Amask[j, i] != 0


@njit(cache=True)
def _wall_heading(Amask, x0, y0, h, px, py, ds, lo, b):
    """The rightmost heading between ``lo`` (hard left; must stay in the mask) and ``b`` (leaves it)
    whose step of ``ds`` from (px, py) stays in the tool-centre mask (14 bisections: the pass slides
    along the wall); NaN when even ``lo`` leaves it."""
    if not _inside(Amask, x0, y0, h, px + ds * math.cos(lo), py + ds * math.sin(lo)):
        return np.nan
    a = lo
    for _ in range(14):
        m = 0.5 * (a + b)
        if _inside(Amask, x0, y0, h, px + ds * math.cos(m), py + ds * math.sin(m)):
            a = m
        else:
            b = m
    return a


@njit(cache=True)
def _mark_free(Mr, x0, y0, h, P, E, F, k0, k1, air_eng, r_capsule):
    """F[k] = the chord P[k-1] -> P[k] has no pixel of ``Mr`` within ``r_capsule``, for the air steps
    (E[k] < air_eng) k0 <= k < k1."""
    for k in range(max(k0, 1), k1):
        if E[k] < air_eng:
            F[k] = _capsule_free(Mr, x0, y0, h, P[k - 1, 0], P[k - 1, 1], P[k, 0], P[k, 1], r_capsule)


@njit(cache=True)
def _chain_clear(Mr, Amask, x0, y0, h, Q, r_capsule):
    """Every chord of the polyline Q (m, 2) has no pixel of ``Mr`` within ``r_capsule`` and every
    point of it, sampled every h/2, lies in the tool-centre mask (:func:`_segment_inside`)."""
    for k in range(1, Q.shape[0]):
        ax = Q[k - 1, 0]
        ay = Q[k - 1, 1]
        bx = Q[k, 0]
        by = Q[k, 1]
        if not _segment_inside(Amask, x0, y0, h, ax, ay, bx, by, 0.0):
            return False
        if not _capsule_free(Mr, x0, y0, h, ax, ay, bx, by, r_capsule):
            return False
    return True


@njit(cache=True)
def _bow_runs(Mr, Amask, x0, y0, h, P, E, F, k0, k1, air_eng, r_capsule, delta, min_steps):
    """For the air steps k0 <= k < k1 (engagement < ``air_eng``) not proven free one by one: a run of
    at least ``min_steps`` of them (steps a..b, from P[a-1] to P[b]) that slides along the last
    cut boundary (a wall-following pass left its skin there: the rapid stock keeps a band of it
    within r + h/sqrt(2) of the same line, so no chord on that line is ever proven) is moved
    ``delta`` mm to its left, away from the material on the pass's right: P[a..b-1] shifted. When
    every chord of the shifted points and the end points is proven as in :func:`_mark_free` and
    inside the mask, its inner steps become G0 (``F``) and the first and last steps stay feed links
    (the legs of ``delta`` off the line and back). Called before the run's discs are cut: the rapid
    stock holds what each step meets; the shifted discs remove nothing (proven), the discs at the
    shifted points that the pass cuts later remove nothing either."""
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
        if _chain_clear(Mr, Amask, x0, y0, h, Q[1:m + 1], r_capsule):
            for q in range(m):
                P[a + q, 0] = Q[q + 1, 0]
                P[a + q, 1] = Q[q + 1, 1]
            for q in range(a + 1, b):
                F[q] = True


@njit(cache=True)
def _pass(M, Amask, x0, y0, h, r, sx, sy, heading, target, ds, lag, max_steps, n_samp, air_stop, turn, turn_right, max_len,
          guard, guard_level, D, hc, Mr, r_rapid, r_capsule, air_eng):
    """One engagement-controlled pass from (sx, sy); cuts M (all disks flushed at the end) and the
    rapid stock ``Mr`` (the same discs, radius ``r_rapid``) in step with it.

    ``D``: the coarse distance field (cells of ``hc`` mm) of the stock as it was at the start or
    earlier (material only goes: a lower bound of the distance now); where it proves that no
    material lies within reach of any candidate step (r + ds + the cell and pixel margins), the
    step is air without sampling the arc: the hard right turn, engagement 0.

    Returns (points (n, 2), removed area mm^2, reason, engagement (n,) rad of each step, free (n,)):
    reason 0 left the region, 1 stuck (cannot lower the engagement), 2 air, 3 step limit; ``free[k]``:
    step k is an air step (engagement < ``air_eng`` rad) whose chord has no pixel of the rapid stock
    within ``r_capsule`` (0: not checked): a G0 through cleared area. The steps of an air run are
    checked when the run ends (dropped runs never): the discs held back since its start are not yet
    cut, so the rapid stock then holds at least the material each of its steps meets."""
    P = np.empty((max_steps + 1, 2))
    E = np.zeros(max_steps + 1)
    F = np.zeros(max_steps + 1, np.bool_)
    P[0, 0] = sx
    P[0, 1] = sy
    n = 1
    k_cut = 0
    s = np.zeros(max_steps + 1)
    removed = 0.0
    air = 0.0
    n_air_start = 1
    reason = 3
    phi = heading
    dpsi = 0.0       # the last heading change: the guess of the next one
    slope = -1.0     # d engagement / d heading (rad/rad) of the last root: the Newton step of the next
    slope_g = -1.0
    was_air = False  # the last step met no material at all: the next guess is the hard right turn
    # no material pixel centre within r + ds + h of any arc sample point: the coarse cell centre may be
    # hc/sqrt(2) from the point, the material pixel hc/sqrt(2) from its cell's centre
    air_reach = r + ds + h + math.sqrt(2.0) * hc
    span = np.empty((M.shape[0], 4), np.int64)   # the last disc's row spans (see _cut_both)
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
            removed += _cut_both(M, Mr, x0, y0, h, P[k_cut, 0], P[k_cut, 1], r, r_rapid, span, rows)
            k_cut += 1
        lo = phi + turn          # hard left: least engagement
        hi = phi - turn_right    # hard right (curvature limited): most engagement
        # the right end of the search: the hard right turn, or where it would leave the tool-centre
        # region, the rightmost heading that stays inside (the pass slides along the wall)
        if not _inside(Amask, x0, y0, h, px + ds * math.cos(hi), py + ds * math.sin(hi)):
            hi = _wall_heading(Amask, x0, y0, h, px, py, ds, lo, hi)
            if hi != hi:
                reason = 0
                break
        jc = int(math.floor((py - y0) / hc))
        ic = int(math.floor((px - x0) / hc))
        if 0 <= jc < D.shape[0] and 0 <= ic < D.shape[1] and D[jc, ic] > air_reach:
            psi = hi
            e = 0.0
            eg = 0.0
        else:
            m0 = hi if was_air else phi + dpsi
            st, psi, e, eg, slope = _heading(M, x0, y0, h, r, px, py, ds, n_samp, guard_level, lo, hi, m0, target, 0,
                                             slope)
            if st == 1:
                reason = 1
                break
        if eg > guard:
            # the guard: the engagement with every sliver of material counted (level GUARD_LEVEL) stays
            # within ``guard``; where the arc runs nearly tangent to a cut boundary (corner rests,
            # crescents between passes) the 1/2 level can miss a few degrees of thin slivers: turn left
            # until it holds
            st, psi, e, eg, slope_g = _heading(M, x0, y0, h, r, px, py, ds, n_samp, guard_level, lo, psi, psi, guard, 1,
                                               slope_g)
            if st == 1:
                reason = 1
                break
        qx = px + ds * math.cos(psi)
        qy = py + ds * math.sin(psi)
        if not _inside(Amask, x0, y0, h, qx, qy):
            # the headings that stay inside need not be contiguous (a corner of the region between the
            # wall-limited right end and the hard left): slide to the inside boundary between the hard
            # left and psi, where the engagement may exceed the target by at most 1 deg, else stop
            psi = _wall_heading(Amask, x0, y0, h, px, py, ds, lo, psi)
            if psi != psi:
                reason = 0
                break
            qx = px + ds * math.cos(psi)
            qy = py + ds * math.sin(psi)
            e, eg = _eng2(M, x0, y0, h, qx, qy, r, psi, n_samp, 0.5, guard_level)
            if e > target + SLIDE_MARGIN:
                reason = 1
                break
            if eg > guard:
                st, psi, e, eg, slope_g = _heading(M, x0, y0, h, r, px, py, ds, n_samp, guard_level, lo, psi, psi,
                                                   guard, 1, slope_g)
                qx = px + ds * math.cos(psi)
                qy = py + ds * math.sin(psi)
                if st == 1 or not _inside(Amask, x0, y0, h, qx, qy):
                    reason = 1
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
                _mark_free(Mr, x0, y0, h, P, E, F, n_air_start, n, air_eng, r_capsule)
                _bow_runs(Mr, Amask, x0, y0, h, P, E, F, n_air_start, n, air_eng, r_capsule, 2.0 * h, 4)
            air = 0.0
        P[n, 0] = qx
        P[n, 1] = qy
        E[n] = e
        s[n] = s[n - 1] + ds
        n += 1
        dpsi = psi - phi
        phi = psi
    if air > 0.0 and reason != 2 and r_capsule > 0.0:
        _mark_free(Mr, x0, y0, h, P, E, F, n_air_start, n, air_eng, r_capsule)
        _bow_runs(Mr, Amask, x0, y0, h, P, E, F, n_air_start, n, air_eng, r_capsule, 2.0 * h, 4)
    while k_cut < n:
        removed += _cut_both(M, Mr, x0, y0, h, P[k_cut, 0], P[k_cut, 1], r, r_rapid, span, rows)
        k_cut += 1
    return P[:n].copy(), removed, reason, E[:n].copy(), F[:n].copy()


@njit(cache=True)
def _replay(M, x0, y0, h, r, P, lag, n_samp, level2):
    """Cut the fixed points P (n, 2) into M in order, the disks of the last ``lag`` mm held back as
    in :func:`_pass`; the engagement (rad) measured at each point (heading: the chord from the point
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
            _cut(M, x0, y0, h, P[k_cut, 0], P[k_cut, 1], r, pcx, pcy)
            pcx = P[k_cut, 0]
            pcy = P[k_cut, 1]
            k_cut += 1
        if dx != 0.0 or dy != 0.0:
            E[i], G[i] = _eng2(M, x0, y0, h, P[i, 0], P[i, 1], r, math.atan2(dy, dx), n_samp, 0.5, level2)
    while k_cut < n:
        _cut(M, x0, y0, h, P[k_cut, 0], P[k_cut, 1], r, pcx, pcy)
        pcx = P[k_cut, 0]
        pcy = P[k_cut, 1]
        k_cut += 1
    return E, G


@njit(cache=True)
def _capsule_free(M, x0, y0, h, ax, ay, bx, by, rr):
    """True when no material pixel centre lies within ``rr`` of the segment (a, b): the tool disc
    (radius < rr - h/sqrt(2)) swept along it removes nothing."""
    ny, nx = M.shape
    i0 = max(int(math.floor((min(ax, bx) - rr - x0) / h)), 0)
    i1 = min(int(math.ceil((max(ax, bx) + rr - x0) / h)), nx - 1)
    j0 = max(int(math.floor((min(ay, by) - rr - y0) / h)), 0)
    j1 = min(int(math.ceil((max(ay, by) + rr - y0) / h)), ny - 1)
    dx = bx - ax
    dy = by - ay
    L2 = dx * dx + dy * dy
    for j in range(j0, j1 + 1):
        py = y0 + (j + 0.5) * h
        for i in range(i0, i1 + 1):
            if M[j, i]:
                px = x0 + (i + 0.5) * h
                t = 0.0 if L2 == 0.0 else ((px - ax) * dx + (py - ay) * dy) / L2
                t = min(max(t, 0.0), 1.0)
                ex = ax + t * dx - px
                ey = ay + t * dy - py
                if ex * ex + ey * ey < rr * rr:
                    return False
    return True


@njit(cache=True)
def _cut_path(M, x0, y0, h, P, r):
    rem = 0.0
    pcx = np.nan
    pcy = np.nan
    for k in range(P.shape[0]):
        rem += _cut(M, x0, y0, h, P[k, 0], P[k, 1], r, pcx, pcy)
        pcx = P[k, 0]
        pcy = P[k, 1]
    return rem


# ------------------------------------------------------------------------------------------------
# helpers
# ------------------------------------------------------------------------------------------------
def _resample(P, step):
    P = np.asarray(P, float)
    if len(P) < 2:
        return P
    d = np.hypot(*np.diff(P, axis=0).T)
    s = np.r_[0.0, np.cumsum(d)]
    if s[-1] == 0:
        return P[:1]
    n = max(int(math.ceil(s[-1] / step)), 1)
    t = np.linspace(0, s[-1], n + 1)
    return np.c_[np.interp(t, s, P[:, 0]), np.interp(t, s, P[:, 1])]


@njit(cache=True)
def _raster_edges(E, x0, y0, h, nx, ny):
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


def _raster(poly, x0, y0, h, nx, ny):
    """:func:`_raster_edges` of a shapely Polygon/MultiPolygon."""
    rings = []
    for part in shapely.get_parts(poly):
        rings += [part.exterior, *part.interiors]
    E = np.concatenate([np.c_[c[:-1], c[1:]] for c in (np.asarray(r.coords)[:, :2] for r in rings)]) if rings \
        else np.zeros((0, 4))
    return _raster_edges(np.ascontiguousarray(E, float), float(x0), float(y0), float(h), int(nx), int(ny))


@njit(cache=True)
def _coarse_any(M, k, mat, J0, J1, I0, I1):
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
def _dist_window(mat, ej0, ej1, ei0, ei1, wj0, wj1, wi0, wi1, hc, cap, D):
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
def _label8(M):
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
def _component_discs(lab, n, x0, y0, h):
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


def _max_filter(a, c):
    """The largest value of ``a`` (2-D) within c cells along each axis (a (2c+1)^2 window clipped at the
    edges; scipy.ndimage.maximum_filter's result, without importing scipy)."""
    from numpy.lib.stride_tricks import sliding_window_view

    w = 2 * c + 1
    a = np.pad(a, ((c, c), (0, 0)), mode="edge")
    a = sliding_window_view(a, w, axis=0).max(axis=-1)
    a = np.pad(a, ((0, 0), (c, c)), mode="edge")
    return sliding_window_view(a, w, axis=1).max(axis=-1)


def _densify(Q, step):
    """The polyline Q (n, 2) with points inserted so that no chord is longer than ``step`` mm, and for
    each of its points the index k of the chord Q[k-1] -> Q[k] it ends on (0 for Q[0])."""
    L = np.hypot(*np.diff(Q, axis=0).T)
    m = np.maximum(1, np.ceil(L / step).astype(int))
    seg = np.r_[0, np.repeat(np.arange(1, len(Q)), m)]
    t = np.concatenate([np.arange(1, k + 1) / k for k in m]) if len(m) else np.zeros(0)
    a = Q[seg[1:] - 1]
    return np.ascontiguousarray(np.vstack([Q[:1], a + t[:, None] * (Q[seg[1:]] - a)])), seg


def _rapid_legs(g, p, q):
    """A G0 for the chord p -> q at depth: ``(None, q)`` when the chord is proven clear on the rapid
    stock (:func:`_capsule_free`); else ``(p', q')`` with feed legs p -> p' and q' -> q of 2 h or 4 h
    along the chord at either end or both (``p'`` None: no leg at the start) when the shortened chord
    is proven; None when no G0 is proven."""
    h = g.h
    if _capsule_free(g.Mr, g.x0, g.y0, h, p[0], p[1], q[0], q[1], g.r_capsule):
        return None, q
    L = math.hypot(q[0] - p[0], q[1] - p[1])
    ux, uy = (q[0] - p[0]) / L, (q[1] - p[1]) / L
    for leg in (2.0 * h, 4.0 * h):
        if L < 4.0 * leg:
            break
        a = (p[0] + leg * ux, p[1] + leg * uy)
        b = (q[0] - leg * ux, q[1] - leg * uy)
        for s, e in ((a, q), (p, b), (a, b)):
            if _capsule_free(g.Mr, g.x0, g.y0, h, s[0], s[1], e[0], e[1], g.r_capsule):
                return (None if s is p else s), e
    return None


class _Grid:
    """The planning stock ``M`` (pixels of ``h`` mm), the tool-centre mask ``A`` and, on a coarse grid
    (cells of ``hc = k h``), the distance from each cell centre to the nearest material, kept up to date
    incrementally: every change of ``M`` goes through a method that marks the changed box, and
    :meth:`free_field` recomputes the coarse field only in the window the change can affect. The field
    is capped at ``cap`` (mm): the planner only compares it with thresholds below ``cap``."""

    def __init__(self, pocket, allowed, r, h, hole):
        self.r, self.h = r, h
        x0, y0, x1, y1 = pocket.bounds
        m = 2 * h
        self.x0, self.y0 = x0 - m, y0 - m
        self.nx = int(math.ceil((x1 - x0 + 2 * m) / h))
        self.ny = int(math.ceil((y1 - y0 + 2 * m) / h))
        self.M = _raster(pocket, self.x0, self.y0, h, self.nx, self.ny)
        # tool-centre region shrunk by h/sqrt(2): every point of a pixel whose centre it holds (what
        # _inside accepts) is inside the true region (a further 1e-6: centres exactly on the shrunk
        # boundary, e.g. of axis-parallel walls, are outside)
        self.A = _raster(allowed.buffer(-h / math.sqrt(2.0) * (1 + 1e-6)), self.x0, self.y0, h, self.nx, self.ny)
        # the rapid stock: the same discs cut with radius r - h/sqrt(2). A pixel centre it shows as
        # clear is within r - h/sqrt(2) of a disc centre, so every point within h/sqrt(2) of it (its
        # pixel) is truly swept: a chord with no material pixel of it within r + h/sqrt(2) is
        # clear in the exact geometry too, sub-pixel cusps between passes included
        self.r_rapid = r - h / math.sqrt(2.0)
        self.r_capsule = r + h / math.sqrt(2.0) * (1 + 1e-9)
        self.Mr = self.M.copy()
        if hole is not None:
            _cut(self.M, self.x0, self.y0, h, hole[0], hole[1], 0.5 * hole[2], np.nan, np.nan)
            _cut(self.Mr, self.x0, self.y0, h, hole[0], hole[1], 0.5 * hole[2] - h / math.sqrt(2.0), np.nan, np.nan)
        # coarse grid for the free-space search
        self.k = max(1, int(round(0.2 / h))) if r >= 2 else 1
        self.hc = self.k * h
        self.Ac = self.coarse(self.A).min(axis=(1, 3)) > 0
        # each cell's distance to the region's boundary (mm: to the nearest cell outside it)
        nJ, nI = self.Ac.shape
        self.dA = np.empty(self.Ac.shape)
        _dist_window(~self.Ac, 0, nJ, 0, nI, 0, nJ, 0, nI, self.hc, np.inf, self.dA)
        # half-width of the tool-centre region around each cell: the largest dA within r
        c = int(math.ceil(r / self.hc))
        self.half_width = _max_filter(self.dA, c)
        self.cap = r + 4.0 * self.hc + r / 30.0   # > the air test of _pass at the default step r/30
        self.mat = np.zeros(self.Ac.shape, bool)
        self.D = np.empty(self.Ac.shape)
        self._dirty = (-np.inf, -np.inf, np.inf, np.inf)
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
        d = self._dirty
        self._dirty = (lo[0], lo[1], hi[0], hi[1]) if d is None else \
            (min(d[0], lo[0]), min(d[1], lo[1]), max(d[2], hi[0]), max(d[3], hi[1]))

    def _cut_rapid(self, P):
        _cut_path(self.Mr, self.x0, self.y0, self.h, np.ascontiguousarray(P, float), self.r_rapid)

    def snapshot(self):
        """Copies of the stocks, for :meth:`restore`."""
        return self.M.copy(), self.Mr.copy()

    def run_pass(self, sx, sy, heading, target, ds, lag, max_steps, n_samp, air_stop, turn, turn_right, max_len,
                 guard, air_eng=0.0, check_rapids=False):
        """:func:`_pass` on these stocks (every argument given: numba's fast dispatch); ``check_rapids``:
        mark the air steps whose chord is clear on the rapid stock."""
        P, removed, reason, E, F = _pass(self.M, self.A, float(self.x0), float(self.y0), float(self.h), float(self.r),
                                         float(sx), float(sy), float(heading), float(target), float(ds), float(lag),
                                         int(max_steps), int(n_samp), float(air_stop), float(turn), float(turn_right),
                                         float(max_len), float(guard), float(GUARD_LEVEL), self.free_field()[0],
                                         float(self.hc), self.Mr, float(self.r_rapid),
                                         float(self.r_capsule) if check_rapids else 0.0, float(air_eng))
        self.touch(P, self.r + self.h)
        return P, removed, reason, E, F

    def cut_path(self, P):
        _cut_path(self.M, self.x0, self.y0, self.h, P, self.r)
        self._cut_rapid(P)
        self.touch(P, self.r + self.h)

    def replay(self, P, lag, n_samp):
        E = _replay(self.M, self.x0, self.y0, self.h, self.r, P, float(lag), int(n_samp), GUARD_LEVEL)[0]
        self._cut_rapid(P)
        self.touch(P, self.r + self.h)
        return E

    def restore(self, snap):
        """Set the stocks back to a :meth:`snapshot`."""
        self.M[:] = snap[0]
        self.Mr[:] = snap[1]
        self._dirty = (-np.inf, -np.inf, np.inf, np.inf)

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
                _coarse_any(self.M, self.k, self.mat, J0, J1, I0, I1)
                # the cells within cap of the change, from the material within cap of those cells
                wj0, wj1, wi0, wi1 = max(J0 - c, 0), min(J1 + c, nJ), max(I0 - c, 0), min(I1 + c, nI)
                ej0, ej1, ei0, ei1 = max(wj0 - c, 0), min(wj1 + c, nJ), max(wi0 - c, 0), min(wi1 + c, nI)
                _dist_window(self.mat, ej0, ej1, ei0, ei1, wj0, wj1, wi0, wi1, hc, cap, self.D)
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
        route = _dijkstra_nb(D, Ac, banned, float(r_free), float(band_hi), int(cell[0]), int(cell[1]), float(cur[0]),
                             float(cur[1]), float(self.x0), float(self.y0), float(self.hc), 2.0 * self.r, self._dist,
                             self._prev, self._hk, self._hv, self._touched, self.A, float(self.h))
        if len(route) == 1 and route[0, 0] < 0:
            return "off"        # no free cell within 2 r that a straight chord inside the region reaches
        return None if len(route) == 0 else route


@njit(cache=True)
def _segment_inside(A, x0, y0, h, ax, ay, bx, by, skip):
    """True when every point of the segment a-b sampled every h/2 lies in a pixel of the mask ``A``,
    but for the first ``skip`` mm (2 h where the start may lie on the true wall -- a finishing lap ends
    there -- outside the mask, which is the region shrunk by h/sqrt(2))."""
    L = math.hypot(bx - ax, by - ay)
    n = max(2, int(math.ceil(L / (0.5 * h))) + 1)
    for k in range(n):
        t = k / (n - 1)
        if t * L < skip:
            continue
        if not _inside(A, x0, y0, h, ax + t * (bx - ax), ay + t * (by - ay)):
            return False
    return True


@njit(cache=True)
def _dijkstra_nb(D, Ac, banned, r_free, band_hi, gj, gi, cx, cy, x0, y0, hc, reach, dist, prev, hk, hv, touched,
                 A, h):
    """8-neighbour Dijkstra (binary heap, lazy deletion) over the free cells (Ac and D >= r_free, or
    (gj, gi)) from the cell of (cx, cy) (off the free set: from the nearest free cell centre within
    ``reach`` mm that a straight chord from (cx, cy) inside the fine tool-centre mask ``A`` (pixels of
    ``h``, origin x0, y0) reaches; none: [[-1, -1]]) to the nearest goal cell (free, and D < band_hi and
    not banned, or (gj, gi));
    the route as (n, 2) cell indices (empty when none). ``dist``/``prev`` are all inf/-1 on entry
    and are left so (the cells touched are reset)."""
    ny, nx = D.shape
    nb = banned.shape[0] > 1
    j0 = min(max(int((cy - y0) // hc), 0), ny - 1)
    i0 = min(max(int((cx - x0) // hc), 0), nx - 1)
    if not ((Ac[j0, i0] and D[j0, i0] >= r_free) or (j0 == gj and i0 == gi)):
        # step off the material: the nearest free cell (first in row order among equals) within reach
        # whose centre a straight chord inside the tool-centre mask reaches
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
        bj = -1
        bi = -1
        for q in np.argsort(cand, kind="mergesort"):
            xcc = x0 + (ci[q] + 0.5) * hc
            ycc = y0 + (cj[q] + 0.5) * hc
            if _segment_inside(A, x0, y0, h, cx, cy, xcc, ycc, 2.0 * h):
                bj = cj[q]
                bi = ci[q]
                break
        if bj < 0:
            return np.full((1, 2), -1, np.int64)     # no free cell reachable by a straight chord
        j0 = bj
        i0 = bi
    s0 = j0 * nx + i0
    dist[s0] = 0.0
    touched[0] = s0
    nt = 1
    hk[0] = 0.0
    hv[0] = s0
    n = 1
    dj = (-1, -1, -1, 0, 0, 1, 1, 1)
    di = (-1, 0, 1, -1, 1, -1, 0, 1)
    ww = (1.4142, 1.0, 1.4142, 1.0, 1.0, 1.4142, 1.0, 1.4142)
    found = -1
    while n > 0:
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
        if d > dist[v]:
            continue
        j = v // nx
        i = v % nx
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
                    hk[n] = nd
                    hv[n] = u
                    c = n
                    n += 1
                    while c > 0:
                        p = (c - 1) // 2
                        if hk[c] < hk[p]:
                            hk[c], hk[p] = hk[p], hk[c]
                            hv[c], hv[p] = hv[p], hv[c]
                            c = p
                        else:
                            break
    if found < 0:
        out = np.empty((0, 2), np.int64)
    else:
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
    for t in range(nt):
        dist[touched[t]] = np.inf
        prev[touched[t]] = -1
    return out


@njit(cache=True)
def _chord_free(D, Ac, r_free, gj, gi, x0, y0, hc, ax, ay, bx, by):
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
def _shortcut(pts, D, Ac, r_free, gj, gi, x0, y0, hc):
    """Indices of the points of ``pts`` (m, 2) kept by greedy straight chords that stay free
    (:func:`_chord_free`): from each kept point the farthest reachable one (a binary search while
    the gap is over 8 points)."""
    m = pts.shape[0]
    out = np.empty(m, np.int64)
    out[0] = 0
    n = 1
    i = 0
    while i < m - 1:
        j = m - 1
        while j > i + 1 and not _chord_free(D, Ac, r_free, gj, gi, x0, y0, hc, pts[i, 0], pts[i, 1], pts[j, 0], pts[j, 1]):
            j = max(i + 1, (i + j) // 2) if j - i > 8 else j - 1
        out[n] = j
        n += 1
        i = j
    return out[:n]


# ------------------------------------------------------------------------------------------------
# the planner
# ------------------------------------------------------------------------------------------------
def adaptive_clearing(pocket, tool_radius: float, theta_deg: float, a_p: float, feed_mm_min: float,
                      depth: float | None = None, start_hole=None, link_feed_mm_min: float = 1500.0,
                      rapid_links: bool = True, guard_deg: float = 5.0, clean_rounds: int = 2,
                      clearance_z: float = 5.0, top_z: float = 0.0, spindle_rpm: float | None = None,
                      tool: Tool | None = None, resolution_mm: float | None = None, step_mm: float | None = None,
                      helix_angle_deg: float = 5.0, finish: bool = True, finish_margin_deg: float = 6.0, finish_laps: int = 3, source: str = "<pocket>",
                      max_passes: int = 5000) -> ToolPath:
    """Engagement-controlled clearing of ``pocket`` (see the module docstring); a :class:`ToolPath`.

    Parameters: ``tool_radius`` mm; ``theta_deg`` target engagement (deg); ``a_p`` axial depth per
    level (mm); ``depth`` total depth (mm, default ``a_p``; levels of at most ``a_p``);
    ``start_hole`` None or (x, y, diameter) mm of a pre-drilled hole; feeds mm/min; z in mm
    (stock top ``top_z``); ``resolution_mm`` planning pixel (default r/60); ``step_mm`` path step
    (default r/30); ``finish_margin_deg``: the wall-following finish is held at ``theta +
    finish_margin_deg`` (it takes the wedges the passes could not reach at ``theta``); ``source``
    names the job in error messages; ``finish_laps``: at most so many wall-following laps per ring,
    a further lap only while material deeper than max(0.3 mm, a_e/4) is left along the ring;
    ``rapid_links``: the links at depth between passes (chords proven free of material on the rapid
    stock: no pixel of it within r + h/sqrt(2) of the chord, see _Grid) are written as G0 tagged
    ``cleared`` (as FreeCAD Adaptive's keep-tool-down links), else as G1 at ``link_feed_mm_min``.
    G0 is a straight line on LinuxCNC (and on any controller with interpolated rapids); on a
    controller whose rapids dog-leg, set it False (job key ``"rapid_links": false``).
    """
    t_start = time.perf_counter()
    if not isinstance(pocket, (Polygon, MultiPolygon)) or pocket.is_empty or not pocket.is_valid:
        raise PlanningError(f"{source}: the pocket must be a valid, non-empty polygon")
    r = float(tool_radius)
    if not (math.isfinite(r) and r > 0):
        raise PlanningError(f"{source}: tool_radius must be > 0 mm, got {tool_radius!r}")
    if not 0 < theta_deg < 180:
        raise PlanningError(f"{source}: theta_deg must be in (0, 180) deg, got {theta_deg!r}")
    if not a_p > 0:
        raise PlanningError(f"{source}: a_p must be > 0 mm, got {a_p!r}")
    depth = float(a_p if depth is None else depth)
    h = float(resolution_mm or r / 60.0)
    if not (math.isfinite(h) and 0 < h <= r / 30.0 * (1 + 1e-9)):
        # measured: at h = r/20 the K&Y pocket plans with 169 mm^2 left uncut (r/30: 5 mm^2, as at r/60)
        raise PlanningError(f"{source}: resolution_mm must be in (0, r/30 = {r / 30.0:.4g}] mm (default r/60): a "
                            f"coarser planning stock cannot resolve the engagement; got {resolution_mm!r}")
    ds = float(step_mm or r / 30.0)
    allowed = pocket.buffer(-r, quad_segs=64)
    if allowed.is_empty or allowed.area < 4 * h * h:
        raise PlanningError(f"{source}: the tool (diameter {2 * r:g} mm) does not fit in the pocket "
                            "(no room for the tool centre)")
    parts = [p for p in shapely.get_parts(pocket)]
    for part in parts:
        if part.buffer(-r, quad_segs=32).is_empty:
            raise PlanningError(f"{source}: a region of the pocket (area {part.area:.1f} mm^2) is narrower "
                                f"than the tool (diameter {2 * r:g} mm)")
    target = math.radians(theta_deg)
    air_rad = math.radians(0.5)   # a step whose front half meets less than 0.5 deg of material is air
    a_e = r * (1 - math.cos(target))
    target_finish = math.radians(theta_deg + finish_margin_deg)
    # a point of a finishing lap snapped onto the wall keeps the snap only while the engagement there stays
    # within theta + 2 deg, slivers counted (level GUARD_LEVEL) as well as at level 1/2: the simulator
    # measures up to ~14 deg more than the planning stock where a snap pushes the tool into a corner
    # rest or into the crescent an earlier pass left beside it (measured on random pockets at theta =
    # 40 deg, r = 2 mm: 52.2 deg with the sliver level held to theta + 7, 46.8 with theta + 2)
    cap_finish = math.radians(theta_deg + 2.0)
    # the sliver guard (see _pass): theta + guard_deg for the clearing passes, theta + 7 deg for the finish
    guard_pass = math.radians(theta_deg + guard_deg)
    guard_finish = math.radians(theta_deg + max(guard_deg, 7.0))
    lag = 2.0 * math.sqrt(2.0 * r * h) + 2.0 * h
    n_samp = 90
    turn = math.radians(90.0)
    turn_radius = 0.25 * r        # the tightest right turn (the curvature limit of the passes), mm
    air_stop = 1.5 * r            # a pass ends after so much air (its air tail is dropped)
    spindle = np.nan if spindle_rpm is None else float(spindle_rpm)
    zlev = [top_z - min(depth, a_p * (k + 1)) for k in range(int(math.ceil(depth / a_p - 1e-9)))]

    # move list
    pts, kinds, tags, feeds, arcs, ctrs = [], [], [], [], [], []

    def add(p, kind, feed=np.nan, tag="", arc=0, ctr=(np.nan, np.nan)):
        pts.append(p); kinds.append(kind); feeds.append(feed); tags.append(tag); arcs.append(arc); ctrs.append(ctr)

    def add_line_moves(Q, z, kind, feed, tag):
        """Straight moves at height z to the points Q (m, 2); kind, feed, tag: arrays (m,) or scalars."""
        m = len(Q)
        pts.extend(zip(Q[:, 0].tolist(), Q[:, 1].tolist(), [z] * m))
        for lst, v in ((kinds, kind), (feeds, feed), (tags, tag)):
            lst.extend(v.tolist() if isinstance(v, np.ndarray) else [v] * m)
        arcs.extend([0] * m)
        ctrs.extend([(np.nan, np.nan)] * m)

    stats = {"passes": 0, "entries": 0, "retracts": 0, "links": 0, "clean_rounds": 0, "remnant_sweeps": 0}
    allowed_parts = list(shapely.get_parts(allowed))
    part_wide = {}        # part index -> inscribed radius of that part of the tool-centre region (mm)
    hole = None if start_hole is None else tuple(float(v) for v in start_hole)
    if hole is not None and not pocket.buffer(1e-9).contains(Point(hole[0], hole[1]).buffer(0.5 * hole[2] - 1e-6)):
        raise PlanningError(f"{source}: the start hole is not inside the pocket")
    for lev, z in enumerate(zlev):
        z_prev = top_z if lev == 0 else zlev[lev - 1]
        g = _Grid(pocket, allowed, r, h, hole)
        if not g.A.any():
            raise PlanningError(f"{source}: the tool-centre region is thinner than the planning resolution "
                                f"{h:g} mm: the pocket is too narrow for the tool")
        cur = None   # current xy at depth (None: at clearance)
        entered = set()   # coarse cells of the entries at this level

        def retract():
            nonlocal cur
            if cur is not None:
                # straight up out of the tool's own cut: G0 (as FreeCAD lifts); the writer and the
                # static check accept a rapid only so below the clearance plane
                add((cur[0], cur[1], clearance_z), "rapid")
                stats["retracts"] += 1
                cur = None

        def enter(banned=None):
            """Entry where the tool-centre region still has material within reach: True; False if
            none; None when the only place left is too narrow for a helix (it is then banned)."""
            nonlocal cur
            D, Ac = g.free_field()
            need = Ac & (D < r)       # tool disk touches material there
            if banned is not None:
                need &= ~banned
            if not need.any():
                return False
            # the farthest point from the tool-centre region's boundary among those cells
            dA = g.dA
            j, i = np.unravel_index(np.argmax(np.where(need, dA, -1)), need.shape)
            c = np.array(g.centre(j, i))
            k_part = next((k for k, p in enumerate(allowed_parts) if p.buffer(1e-6).contains(Point(*c))), None)
            comp = [] if k_part is None else [allowed_parts[k_part]]
            rho_max = comp[0].exterior.distance(Point(*c)) if comp else dA[j, i]
            if comp:
                rho_max = min([rho_max] + [Polygon(hh).exterior.distance(Point(*c)) for hh in comp[0].interiors])
            rho = max(min(HELIX_RADIUS_FRAC * r, 0.9 * rho_max - h), 0.0)
            # the smallest helix accepted here: HELIX_MIN_FRAC r, or half what the widest place of this
            # part of the tool-centre region allows (a part narrow everywhere is entered by a small
            # helix; the entry point is a coarse cell centre, up to hc/sqrt(2) off the widest place)
            rho_min = 0.02
            if comp and banned is not None:
                if k_part not in part_wide:
                    part_wide[k_part] = shapely.maximum_inscribed_circle(comp[0], 0.1 * h).length
                wide = part_wide[k_part]
                rho_min = max(0.02, min(HELIX_MIN_FRAC * r, 0.5 * (0.9 * wide - h)))
            # a place entered before (its passes made no room) or too narrow for a helix is banned: no
            # endless re-entry at one spot
            again = (int(j), int(i)) in entered
            entered.add((int(j), int(i)))
            if (rho < rho_min or again) and banned is not None and not (hole is not None and lev == 0 and stats["entries"] == 0):
                rad = int(math.ceil(2 * r / g.hc))
                banned[max(j - rad, 0):j + rad + 1, max(i - rad, 0):i + rad + 1] = True
                return None
            retract()
            if hole is not None and lev == 0 and stats["entries"] == 0:
                c = np.array(hole[:2])
                rho = 0.0
                add((c[0], c[1], clearance_z), "rapid")
                add((c[0], c[1], z), "plunge", feed_mm_min, "cleared: pre-drilled start hole")
            elif rho < rho_min:
                raise PlanningError(f"{source}: no room for a helical entry at ({c[0]:.2f}, {c[1]:.2f}): "
                                    "the region is too narrow for the tool")
            else:
                p0 = (c[0] + rho, c[1])
                add((p0[0], p0[1], clearance_z), "rapid")
                # down to 0.5 mm above the level's top: air above the stock top (level 0) or the floor
                # the previous level cleared (tagged: the program writer allows a rapid there only so)
                add((p0[0], p0[1], z_prev + 0.5), "rapid", np.nan, "cleared: above the level")
                add((p0[0], p0[1], z_prev), "plunge", feed_mm_min, "air")
                drop = 2 * math.pi * rho * math.tan(math.radians(helix_angle_deg))
                # the helix ends where it reaches z (the last turn partial); at least one full turn, so
                # that the floor circle after it cuts in the helix's own groove
                turns = max((z_prev - z) / drop, 1.0)
                drop = (z_prev - z) / turns
                zz = z_prev
                for _ in range(int(math.floor(turns + 1e-9))):
                    zz -= drop
                    add((p0[0], p0[1], max(zz, z)), "helix", feed_mm_min, "entry", 3, (c[0], c[1]))
                phi = 2 * math.pi * (turns - math.floor(turns + 1e-9))
                pe = (c[0] + rho * math.cos(phi), c[1] + rho * math.sin(phi)) if phi > 1e-6 else p0
                if phi > 1e-6:
                    add((pe[0], pe[1], z), "helix", feed_mm_min, "entry", 3, (c[0], c[1]))
                add((pe[0], pe[1], z), "cut", feed_mm_min, "entry-floor", 3, (c[0], c[1]))
                circ = c + rho * np.c_[np.cos(np.linspace(0, 2 * np.pi, 64)), np.sin(np.linspace(0, 2 * np.pi, 64))]
                g.cut_path(circ)
                stats["entries"] += 1
                cur = (float(pe[0]), float(pe[1]))
                return True
            stats["entries"] += 1
            cur = (c[0] + rho, c[1])
            return True

        def clearing_pass(heading, a_stop):
            """A clearing pass from the tool's point (:meth:`_Grid.run_pass`) with ``a_stop`` mm of air."""
            return g.run_pass(cur[0], cur[1], heading, target, ds, lag, 20000, n_samp, a_stop, turn,
                              min(turn, ds / turn_radius), 1e18, guard_pass, air_rad, rapid_links)

        def link_to(r_free, band_hi=-np.inf, banned=None, cell=(-1, -1), end_xy=None):
            """Link at depth through free cells to the nearest goal cell (:meth:`_Grid.route`); its
            cell or None. ``end_xy``: the exact end point (in ``cell``, which need not lie inside the
            tool-centre region: its centre is never a point of the link)."""
            nonlocal cur
            route = g.route(cur, r_free, band_hi, banned, cell)
            if isinstance(route, str):
                # no straight chord from here reaches a free cell inside the region (an island corner in
                # the way): retrace the tool's own path at this depth (inside the region, its material
                # removed) to the last point from which one does, as feed links
                n_back = 0
                while n_back < len(pts) - 1 and pts[-2 - n_back][2] == z and kinds[-1 - n_back] != "plunge" \
                        and n_back < 200:
                    n_back += 1
                for k in range(5, n_back + 1, 5):
                    p = pts[-1 - k]
                    route = g.route((p[0], p[1]), r_free, band_hi, banned, cell)
                    if not isinstance(route, str):
                        back = [pts[-1 - q] for q in range(1, k + 1)]
                        break
                if isinstance(route, str) or route is None:
                    return None
                for p in back:
                    add((p[0], p[1], z), "link", link_feed_mm_min)
                cur = (float(back[-1][0]), float(back[-1][1]))
            if route is None:
                return None
            D, Ac = g.free_field()
            R = np.asarray(route, float)
            cells = np.c_[g.x0 + (R[:, 1] + 0.5) * g.hc, g.y0 + (R[:, 0] + 0.5) * g.hc]
            pts_r = np.vstack([np.array([cur], float), cells[1:] if len(R) > 1 else cells[:1]])
            if end_xy is not None:
                pts_r[-1] = end_xy

            chords = pts_r[_shortcut(np.ascontiguousarray(pts_r, float), D, Ac, float(r_free), int(cell[0]), int(cell[1]),
                                     float(g.x0), float(g.y0), float(g.hc))]
            for q in chords[1:]:
                if math.hypot(q[0] - cur[0], q[1] - cur[1]) > 1e-9:
                    legs = _rapid_legs(g, cur, q) if rapid_links else None
                    if legs is None:
                        add((q[0], q[1], z), "link", link_feed_mm_min)
                    else:
                        # G0 at depth: no pixel of the rapid stock within r + h/sqrt(2) of the chord: the
                        # chord's tool disc is truly swept (see _Grid), sub-pixel slivers included; a
                        # chord starting or ending on a cut boundary (a pass ends at the wall: its skin
                        # is tangent there) gets a short feed leg off it
                        a, b = legs
                        if a is not None:
                            add((a[0], a[1], z), "link", link_feed_mm_min)
                        add((b[0], b[1], z), "rapid", np.nan, "cleared: link through cleared area")
                        if b[0] != q[0] or b[1] != q[1]:
                            add((q[0], q[1], z), "link", link_feed_mm_min)
                    cur = (float(q[0]), float(q[1]))
            stats["links"] += 1
            return route[-1]

        def finish_part(part):
            """The wall-following finish laps along every ring of one part of the tool-centre region."""
            nonlocal cur
            # the tool-centre limit (as the evaluator and Job.allowed() draw it: 64 segments a quarter circle),
            # 1 um inside it: the chords of its arcs never put the tool centre past the true limit
            wall = shapely.boundary(allowed.buffer(-1e-3))
            for ring in [part.exterior, *part.interiors]:
                R = np.asarray(ring.coords)[:-1]
                if len(R) < 3:
                    continue
                Rs = _resample(np.vstack([R, R[:1]]), ds)[:-1]
                for lap in range(finish_laps):   # repeated while the corner wedges are peeled
                    D, Ac = g.free_field()
                    jj = np.clip(((Rs[:, 1] - g.y0) // g.hc).astype(int), 0, D.shape[0] - 1)
                    ii = np.clip(((Rs[:, 0] - g.x0) // g.hc).astype(int), 0, D.shape[1] - 1)
                    dm = D[jj, ii]
                    if dm.min() > (r + g.hc if lap == 0 else r - max(0.3, 0.25 * a_e)):
                        break                # nothing (more) to take along this ring
                    # start where the ring is free of material (the farthest from it, the field being
                    # capped: any point at the cap), the nearest such point to the tool
                    free_k = np.flatnonzero(dm >= min(dm.max(), r_free + g.hc))
                    if cur is not None and len(free_k) > 1:
                        k0 = int(free_k[np.argmin(np.hypot(Rs[free_k, 0] - cur[0], Rs[free_k, 1] - cur[1]))])
                    else:
                        k0 = int(free_k[0])
                    Rl = np.vstack([Rs[k0:], Rs[:k0], Rs[k0:k0 + 1]])
                    if cur is not None:
                        e = link_to(r_free, cell=(int(jj[k0]), int(ii[k0])), end_xy=(Rl[0, 0], Rl[0, 1]))
                    else:
                        e = None
                    if e is None:
                        retract()
                        add((Rl[0, 0], Rl[0, 1], clearance_z), "rapid")
                        if dm[k0] >= r:          # free of material under the tool: feed down into cleared area
                            add((Rl[0, 0], Rl[0, 1], z), "plunge", feed_mm_min, "cleared")
                        else:
                            ins = shapely.maximum_inscribed_circle(part)
                            raise PlanningError(
                                f"{source}: a part of the tool-centre region (area {part.area:.2f} mm^2, inscribed "
                                f"radius {ins.length:.2f} mm near ({ins.coords[0][0]:.2f}, {ins.coords[0][1]:.2f})) "
                                "is too narrow to be cleared under engagement control: no cleared place to start "
                                "its finishing pass (the pocket is too narrow for the tool)")
                    elif math.hypot(Rl[0, 0] - cur[0], Rl[0, 1] - cur[1]) > 1e-9:
                        add((Rl[0, 0], Rl[0, 1], z), "link", link_feed_mm_min)
                        cur = (float(Rl[0, 0]), float(Rl[0, 1]))
                    # the wall-following pass: the same engagement control, sliding along the wall;
                    # it ends 2 r past the last ring point that still has material within reach
                    sl = np.r_[0.0, np.cumsum(np.hypot(*np.diff(Rl, axis=0).T))]
                    dml = np.r_[dm[k0:], dm[:k0], dm[k0:k0 + 1]]
                    mat = np.flatnonzero(dml < r + g.hc)
                    L_ring = float(sl[-1]) if len(mat) == 0 else min(float(sl[-1]), float(sl[mat[-1]]) + 2 * r)
                    hd = math.atan2(Rl[1, 1] - Rl[0, 1], Rl[1, 0] - Rl[0, 0])
                    snap = g.snapshot()
                    M_before = snap[0]
                    P, _, _, E, _ = g.run_pass(Rl[0, 0], Rl[0, 1], hd, target_finish, ds, lag,
                                               int(2 * L_ring / ds) + 100, n_samp, 1e18, turn,
                                               min(turn, ds / turn_radius), 1.02 * L_ring + ds, guard_finish)
                    # points the grid kept within 2 h of the wall go onto the exact wall
                    # (the grid mask is shrunk by h/sqrt(2) for safety: no skin is left on the walls)
                    pp = shapely.points(P)
                    near = shapely.distance(wall, pp) < 2.0 * h
                    if near.any():
                        # the nearest wall point (not locate + interpolate along the multi-ring wall: a
                        # point nearest to a ring's closing vertex would land on the next ring's start)
                        snapped = shapely.get_coordinates(shapely.shortest_line(pp[near], wall))[1::2]
                        Q = P.copy()
                        Q[near] = snapped
                        # the snap moves points up to 2 h outwards: near a concave corner that can
                        # raise the engagement steeply (an arc nearly tangent to the rest). Replayed
                        # on the stock as it was before this lap, a snapped point whose engagement
                        # exceeds the finish target keeps its planned place (a skin < 2 h remains there)
                        # (a chord the snap made longer than 1.5 ds measured along its length too: it can reach
                        # into a corner)
                        for _ in range(6):       # a reverted point changes the stock the later ones meet
                            Qd, seg = _densify(Q, 1.5 * ds)
                            Es, Eg = _replay(M_before.copy(), g.x0, g.y0, h, r, Qd, lag, n_samp, GUARD_LEVEL)
                            bad = np.zeros(len(Q), bool)
                            bad[seg[(Es > cap_finish) | (Eg > cap_finish)]] = True
                            bad[:-1] |= bad[1:]          # a chord over the bound: both its ends
                            over = near & bad & np.any(Q != P, axis=1)
                            if not over.any():
                                break
                            Q[over] = P[over]
                        g.restore(snap)
                        E = g.replay(Q, lag, n_samp)
                        P = Q
                    ai = E[1:] < air_rad
                    add_line_moves(P[1:], z, np.where(ai, "link", "cut").astype(object),
                                   np.where(ai, link_feed_mm_min, feed_mm_min), "finish")
                    cur = (float(P[-1, 0]), float(P[-1, 1]))

        todo_parts = [orient(q, 1.0) for q in shapely.get_parts(allowed.buffer(-1.5 * h))] if finish else []

        def sweep_remnant():
            """A free-standing remnant of material (a pillar the passes around it could not take: every
            border cell around it banned) small enough that a straight cut towards its centre meets it
            over at most theta -- within radius r sin(theta/2) of its centre -- is cut by one straight
            feed move from a free point, reached through cleared area, to where the tool disc holds all
            of it; True if one was cut."""
            nonlocal cur
            if cur is None:
                return False
            lbl, nlab = _label8(g.M)
            if nlab == 0:
                return False
            rho_max = r * math.sin(0.5 * target)
            CX, CY, RAD = _component_discs(lbl, nlab, g.x0, g.y0, h)
            for lab in np.flatnonzero(RAD + h / math.sqrt(2.0) <= rho_max):
                c = np.array([CX[lab], CY[lab]])
                rho_b = float(RAD[lab]) + h / math.sqrt(2.0)
                others = None
                D, Ac = g.free_field()
                for ang in np.arange(8) * (math.pi / 4):
                    u = np.array([math.cos(ang), math.sin(ang)])
                    # from a free point before the remnant to where the tool disc holds all of it
                    S, E = c - (r + rho_b + g.hc) * u, c - (r - rho_b - h) * u
                    jS, iS = g.cell(*S)
                    if not (0 <= jS < D.shape[0] and 0 <= iS < D.shape[1] and Ac[jS, iS] and D[jS, iS] >= r_free):
                        continue
                    if not _segment_inside(g.A, g.x0, g.y0, h, S[0], S[1], E[0], E[1], 2.0 * h):
                        continue
                    if others is None:
                        others = np.where(lbl == lab, 0, g.M).astype(np.uint8)
                    if not _capsule_free(others, g.x0, g.y0, h, S[0], S[1], E[0], E[1], r + h):
                        continue                       # the sweep would meet other material too
                    if link_to(r_free, cell=(jS, iS), end_xy=(S[0], S[1])) is None:
                        continue
                    Q = _resample(np.vstack([S, E]), ds)
                    add_line_moves(Q[1:], z, "cut", feed_mm_min, "remnant sweep")
                    g.cut_path(np.ascontiguousarray(Q))
                    cur = (float(E[0]), float(E[1]))
                    stats["remnant_sweeps"] += 1
                    return True
            return False

        def finish_if_done(D, Ac, banned):
            """Before the tool leaves its part of the tool-centre region (a retract and a new entry),
            finish that part if its clearing is done (no material within reach of its free cells)."""
            if cur is None or not todo_parts:
                return
            dd = [q.distance(Point(*cur)) for q in todo_parts]
            kk = int(np.argmin(dd))
            if dd[kk] > 2 * g.hc:
                return
            J, I = np.nonzero(Ac & (D < r) & ~banned)
            if len(J) and shapely.contains_xy(todo_parts[kk].buffer(2 * g.hc), g.x0 + (I + 0.5) * g.hc,
                                              g.y0 + (J + 0.5) * g.hc).any():
                return
            finish_part(todo_parts.pop(kk))

        if not enter():
            continue
        r_free = r + 0.75 * g.hc      # coarse cell centre to material, with the cell half-diagonal margin
        for rnd in range(clean_rounds + 1):
            # round 0 clears and finishes; a clean-up round takes what the sliver guard and the bans left
            # (a pass refused where its first steps would graze a crescent), then finishes again
            if rnd > 0:
                D, Ac = g.free_field()
                if not (Ac & (D < r - 2 * g.hc)).any():
                    break
                todo_parts[:] = [orient(q, 1.0) for q in shapely.get_parts(allowed.buffer(-1.5 * h))] if finish else []
                saved = (len(pts), g.snapshot(), cur, dict(stats))
            banned = np.zeros((g.ny // g.k, g.nx // g.k), bool)
            for _ in range(max_passes):
                D, Ac = g.free_field()
                end = link_to(r_free, r_free + 1.5 * g.hc, banned)
                if end is None:
                    D, Ac = g.free_field()
                    if not (Ac & (D < r) & ~banned).any():
                        break
                    if sweep_remnant():
                        continue
                    finish_if_done(D, Ac, banned)
                    if enter(banned) is False:
                        break
                    continue
                # heading: along the material boundary, material on the right
                j, i = end
                gy = D[min(j + 1, D.shape[0] - 1), i] - D[max(j - 1, 0), i]
                gx = D[j, min(i + 1, D.shape[1] - 1)] - D[j, max(i - 1, 0)]
                if not (np.isfinite(gx) and np.isfinite(gy)) or gx == gy == 0:
                    banned[j, i] = True
                    continue
                heading = math.atan2(gy, gx) - 0.5 * math.pi
                P, removed, reason, E, free = clearing_pass(heading, air_stop)
                stats["passes"] += 1
                if len(P) < 2 and g.half_width[j, i] < turn_radius:
                    # nothing emitted (the pass ran into air and was dropped: the stock is unchanged). In a band
                    # narrower than the turning circle, where the material lies behind the start heading (the
                    # face at the end of the band) the hard right turn through air slides away along the
                    # wall: start the other way round once
                    P, removed, reason, E, free = clearing_pass(heading + math.pi, air_stop)
                    stats["passes"] += 1
                if len(P) < 2 and reason == 2 and g.half_width[j, i] < r:
                    # nothing emitted (the stock is unchanged): the pass ran its whole air allowance
                    # without meeting material. In a band narrower than the tool (a neck between
                    # islands) the way to the face is a loop mostly through air (the turning circle is
                    # 1.57 r round): once more with 3.5 r of air before the place is banned -- else
                    # the face is taken by one helix entry after another (two_islands_neck: 5 lifts -> 2).
                    # Kept only where it removes NARROW_MIN_YIELD a_e per mm of its length
                    snap_try = g.snapshot()
                    P, removed, reason, E, free = clearing_pass(heading, NARROW_AIR_STOP * r)
                    stats["passes"] += 1
                    if len(P) >= 2 and removed < NARROW_MIN_YIELD * a_e * ds * (len(P) - 1):
                        g.restore(snap_try)        # not worth its air: the place is banned after all
                        P, removed, E, free = P[:1], 0.0, E[:1], free[:1]
                if removed < 0.2 * r * h or len(P) < 2:
                    rad = int(math.ceil(r / g.hc))
                    banned[max(j - rad, 0):j + rad + 1, max(i - rad, 0):i + rad + 1] = True
                air = E < air_rad                # nothing in front of the tool: a link at the link feed, or
                                                 # a G0 where the chord is proven clear (``free``, see _pass)
                fr, ai = free[1:], air[1:]
                add_line_moves(P[1:], z, np.where(fr, "rapid", np.where(ai, "link", "cut")).astype(object),
                               np.where(fr, np.nan, np.where(ai, link_feed_mm_min, feed_mm_min)),
                               np.where(fr, "cleared: air inside cleared area", "").astype(object))
                cur = (float(P[-1, 0]), float(P[-1, 1]))
            if finish:
                # every part of the tool-centre region is finished once, the nearest to the tool first (a part
                # is also finished as soon as its clearing is done, before the tool leaves it: no extra lift)
                while todo_parts:
                    kk = 0
                    if cur is not None:
                        dd = [q.distance(Point(*cur)) for q in todo_parts]
                        kk = int(np.argmin(dd))
                    finish_part(todo_parts.pop(kk))
            if rnd > 0:
                # keep the clean-up round only when it pays: the area it removed is at least 10 % of what
                # the nominal cut (a_e wide at the cutting feed) removes in the feed time the round adds
                # (its rapids not counted); else roll it back
                n0, snap0, cur0, st0 = saved
                took = float(snap0[0].sum() - g.M.sum()) * h * h
                P3 = np.asarray(pts[n0 - 1:], float)
                F3 = np.asarray(feeds[n0:], float)
                L3 = np.linalg.norm(np.diff(P3, axis=0), axis=1) if len(P3) > 1 else np.zeros(0)
                t_feed = float(np.sum(np.where(np.isfinite(F3) & (F3 > 0), L3 / np.where(F3 > 0, F3, 1.0), 0.0)))
                if took < 0.1 * a_e * feed_mm_min * t_feed or took <= 0.0:
                    for lst in (pts, kinds, tags, feeds, arcs, ctrs):
                        del lst[n0:]
                    g.restore(snap0)
                    cur = cur0
                    stats.clear(); stats.update(st0)
                    break
                stats["clean_rounds"] += 1
        retract()
    if not pts:
        raise PlanningError(f"{source}: nothing to machine")
    kinds[0] = "rapid"
    tp = ToolPath.build(np.array(pts, float), kind=kinds, tag=np.array(tags, dtype=object),
                        feed=np.array(feeds, float), spindle=spindle, arc=np.array(arcs),
                        arc_center=np.array(ctrs, float), tool=tool or Tool(2 * r),
                        info={"planner": "adaptive_clearing", "theta_deg": theta_deg, "resolution_mm": h,
                              "step_mm": ds, **stats, "plan_time_s": time.perf_counter() - t_start})
    return tp


def plan_job(job, **kw) -> ToolPath:
    """:func:`adaptive_clearing` with the tool, engagement, depths, feeds and start hole of a job
    (``cnclab.toolpath.job.Job`` or any object with its attribute names)."""
    sh = getattr(job, "start_hole", None)
    return adaptive_clearing(job.polygon, job.tool.radius, job.theta_deg, job.a_p, job.feed_mm_min,
                             depth=getattr(job, "depth", None), start_hole=sh,
                             link_feed_mm_min=getattr(job, "link_feed_mm_min", 1500.0),
                             rapid_links=bool(getattr(job, "rapid_links", True)),
                             clearance_z=getattr(job, "clearance_z", 5.0), top_z=getattr(job, "top_z", 0.0),
                             spindle_rpm=getattr(job, "spindle_rpm", None), tool=job.tool,
                             source=str(getattr(job, "source", "<job>")), **kw)
