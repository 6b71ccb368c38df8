"""The constant-engagement trochoidal pattern (Jacsó 2021, Thesis IV): the material front read from a
dixel stock, Thesis III cuts along it, fillets at the walls, linking arcs, the converged period
repeated at the admissible step (see :mod:`cnclab.toolpath.trochoidal`)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import shapely
from shapely.geometry import box

from ...geometry.contours import SplineContour
from ...simulation import dixel
from ...simulation.common import simulate
from ..constant_engagement import clamp_to_region, resample_path, thesis3_path
from ..path import ToolPath, subdivide
from . import _common
from .patterns import circle_front_step, evaluate_pattern, pattern_kinds, slot_limit

__all__ = ["disk_has_material", "front_contour", "roll_arc", "linking_arc", "CEPeriodOptions", "ce_period", "ce_trochoid_iteration", "CEPatternOptions", "ce_trochoid", "ce_admissible_step", "fillet_entry", "fillet_exit", "tangent_arc", "CEIteration"]


def front_contour(stock, x_min=-math.inf, every_rows=3, min_points=6):
    """Front of the material (smallest x of material per row, x >= ``x_min``) as an open spline
    contour traversed from the lowest to the highest row: material on the right (Thesis II).

    Returns a :class:`~cnclab.geometry.contours.SplineContour`, or None when fewer than
    ``min_points`` rows hold material.
    """
    rows, a, b = stock.intervals()
    keep = b > x_min
    rows, a = rows[keep], np.maximum(a[keep], x_min)
    if rows.size == 0:
        return None
    ur, first = np.unique(rows, return_index=True)      # intervals sorted by row then a
    xf = a[first]
    y = stock.row_y(ur)
    sel = np.r_[np.arange(0, len(ur) - 1, every_rows), len(ur) - 1]
    pts = np.c_[xf[sel], y[sel]]
    if len(pts) < min_points:
        return None
    pts = pts[np.r_[True, np.hypot(*np.diff(pts, axis=0).T) > 1e-9]]
    return SplineContour(pts)


def _clip_run(P, inside):
    """Longest run of consecutive True in ``inside``; returns (i0, i1) inclusive or None."""
    if not inside.any():
        return None
    d = np.diff(np.r_[0, inside.astype(int), 0])
    starts, ends = np.flatnonzero(d == 1), np.flatnonzero(d == -1) - 1
    k = int(np.argmax(ends - starts))
    return int(starts[k]), int(ends[k])


class _SubContour:
    """Open contour ``base`` restricted to parameters [t0, base.t_max] (for Thesis III restarts)."""

    def __init__(self, base, t0):
        self.base, self.t_min, self.t_max, self.closed = base, float(t0), float(base.t_max), False

    def point(self, t):
        return self.base.point(t)

    def deriv(self, t):
        return self.base.deriv(t)


def roll_arc(end_xy, tangent_xy, radius_mm, sweep_deg, ds=0.05, into=True):
    """Counter-clockwise circular arc of radius ``radius_mm`` tangent to ``tangent_xy`` at ``end_xy``.

    ``into=True``: the roll-in arc that *ends* at ``end_xy`` moving along ``tangent_xy`` (it comes
    from the left of the tangent, the cleared side when the material is on the right);
    ``into=False``: the roll-out arc that *starts* there and turns left, away from the material.
    Returns ``(points (m, 2), centre (2,))``; ``sweep_deg`` is the swept angle in degrees.

    >>> P, C = roll_arc((0.0, 0.0), (1.0, 0.0), 1.0, 90.0, ds=0.1)
    >>> np.round(P[[0, -1]], 9).tolist(), C.tolist()
    ([[-1.0, 1.0], [0.0, 0.0]], [0.0, 1.0])
    """
    E = np.asarray(end_xy, float)
    T = np.asarray(tangent_xy, float)
    T = T / np.hypot(*T)
    rho = _common.positive("radius_mm", radius_mm)
    C = E + rho * np.array([-T[1], T[0]])
    a_end = math.atan2(E[1] - C[1], E[0] - C[0])
    sw = math.radians(_common.positive("sweep_deg", sweep_deg))
    m = max(int(math.ceil(sw * rho / ds)), 2)
    ang = a_end - sw + sw * np.linspace(0, 1, m + 1) if into else a_end + sw * np.linspace(0, 1, m + 1)
    P = np.c_[C[0] + rho * np.cos(ang), C[1] + rho * np.sin(ang)]
    P[-1 if into else 0] = E
    return P, C


def disk_has_material(stock, p, r, n_r=6, n_a=48):
    """True when material lies under the tool disk at ``p`` (polar sample grid, plus the circle)."""
    rr = r * np.linspace(0.0, 1.0, n_r + 1)[1:, None] * 0.999
    a = np.linspace(0, 2 * np.pi, n_a, endpoint=False)[None, :]
    x = p[0] + rr * np.cos(a)
    y = p[1] + rr * np.sin(a)
    return bool(stock.contains(np.r_[x.ravel(), p[0]], np.r_[y.ravel(), p[1]]).any())


def _period(segments, reached_theta: bool, feed_mm_min: float) -> ToolPath:
    """One planned period as a :class:`ToolPath` (z = 0): ``segments`` = [(kind, points (n, 2))] with
    kind roll-in / cut / roll-out (tags ``"roll-in"``, ``""``, ``"roll-out"``); ``info["reached_theta"]``
    False when the roll-in march never reached theta (little material left)."""
    P = np.vstack([Q if i == 0 else Q[1:] for i, (_, Q) in enumerate(segments)])
    tags = np.concatenate([np.full(len(Q) if i == 0 else len(Q) - 1, "" if k == "cut" else f"period 0:{k}", dtype=object)
                           for i, (k, Q) in enumerate(segments)])
    tags = np.where(tags == "", "period 0", tags)
    return ToolPath.build(P, kind="cut", tag=tags, feed=feed_mm_min, info={"reached_theta": bool(reached_theta)})


def _roll_out_period(roll_in, rho, sweep_deg, step_mm, allowed, feed_mm_min) -> ToolPath:
    """A period that never reached theta (little material left): the roll-in, then a roll-out arc."""
    E, T = roll_in[-1], roll_in[-1] - roll_in[-2]
    out, _ = roll_arc(E, T, rho, sweep_deg, ds=step_mm, into=False)
    return _period([("roll-in", roll_in), ("roll-out", clamp_to_region(out, allowed))], False, feed_mm_min)


@dataclass(frozen=True, kw_only=True)
class CEPeriodOptions:
    """Settings of one period of :func:`ce_period`, keyword-only.

    ``dt`` Thesis III integration step (mm of contour parameter); ``step_mm`` sampling of the
    march/arcs/cut (mm); ``x_min`` (mm) the front is read right of it; ``roll_radius`` (mm) and
    ``roll_sweep_deg`` (deg) of the roll-in/roll-out arcs; ``a_p`` (mm) and ``feed_mm_min`` (mm/min)
    of the simulated cut; ``fillet_radius_mm`` (mm; None = sharp corners).

    >>> CEPeriodOptions(step_mm=0.1).roll_radius
    1.0
    """

    dt: float = 0.1
    step_mm: float = 0.05
    x_min: float = -math.inf
    roll_radius: float = 1.0
    roll_sweep_deg: float = 90.0
    a_p: float = 1.0
    feed_mm_min: float = 1000.0
    fillet_radius_mm: float | None = None


def ce_period(stock, tool_radius, theta_deg, allowed, options=None, *, front_stock=None, **fields) -> ToolPath | None:
    """Plan one constant-engagement trochoidal period with explicit roll-in and roll-out.

    Local frame: the period advances along +x, the material front is cut from the lower wall to the
    upper wall (material on the right of the feed, Thesis II). ``allowed`` is the shapely polygon of
    admissible tool centres (final contour shrunk by r). Planning runs the dixel simulator on a copy
    of ``stock`` (never modified):

    1. **roll-in** — a ccw arc of radius ``roll_radius`` (mm, booklet §4: 1 mm) lands tangentially
       on the lower wall limit behind the material, then the tool moves along the wall limit into
       the material corner until the simulated engagement reaches ``theta_deg`` (it grows
       monotonically from 0 while the tool enters the convex corner);
    2. **cut** — Thesis III (:func:`~cnclab.toolpath.constant_engagement.thesis3_path`) along the
       current front, started at the roll-in end with the contact at the material entry point, so
       the engagement stays at theta (it cannot exceed theta: the entry point is held at theta - 90
       deg from the feed, the front-half measure is <= theta);
    3. **roll-out** — where the cut reaches the upper wall limit the tool leaves on a ccw arc of
       radius ``roll_radius`` tangent to the wall limit (the feed turns away from the material);
    4. with ``fillet_radius_mm`` (mm; default None = sharp corners) the corner between the wall
       march and the cut and the one between the cut and the far wall are rounded
       (:func:`fillet_entry`, :func:`fillet_exit`; the entry fillet is tagged roll-in).

    Settings: ``options`` a :class:`CEPeriodOptions` or its fields as keywords (replacing its fields).
    ``front_stock`` (default ``stock``): the stock whose front is followed (e.g. one pocket arm's
    material) while the engagement is simulated on ``stock`` (all the material).

    Returns a :class:`ToolPath` of the period (:func:`pattern_kinds` gives roll-in / cut / roll-out),
    or None when no material is left in reach.
    """
    o = CEPeriodOptions(**fields) if options is None else replace(options, **fields)
    dt, step_mm, x_min, roll_sweep_deg, a_p, feed_mm_min = o.dt, o.step_mm, o.x_min, o.roll_sweep_deg, o.a_p, o.feed_mm_min
    r, rho = _common.positive("tool_radius", tool_radius), _common.positive("roll_radius", o.roll_radius)
    fs = stock if front_stock is None else front_stock
    c = front_contour(fs, x_min=x_min)
    if c is None or c.t_max < 2 * stock.resolution_mm:
        return None
    ring = shapely.LineString(np.asarray(shapely.orient_polygons(allowed).exterior.coords))  # ccw
    L = ring.length
    F0 = c.point(c.t_min)[0]
    s_near = float(ring.project(shapely.Point(F0)))
    back = 0.25                    # start the march just behind the material (the disk clear of it)
    while back < 4 * r and disk_has_material(stock, np.asarray(ring.interpolate(s_near - back).coords[0]), r):
        back += 0.25
    s_A = s_near - back
    if s_A < 0:
        s_A += L
    # march along the wall limit (ring direction = +x on the lower wall of a ccw ring)
    s_m = s_A + np.arange(0.0, back + 3 * r, step_mm)
    M = shapely.get_coordinates(shapely.line_interpolate_point(ring, np.mod(s_m, L)))
    T_A = M[1] - M[0]
    arc, _ = roll_arc(M[0], T_A, rho, roll_sweep_deg, ds=step_mm, into=True)
    arc = clamp_to_region(arc, allowed)
    pre = np.vstack([arc, M[1:]])
    st = stock.copy()
    df = simulate(st, pre, r, a_p, feed_mm_min)
    eng = np.nan_to_num(df.engagement_deg.to_numpy())
    hit = np.flatnonzero(eng[len(arc):] >= theta_deg)
    if hit.size == 0:            # little material: the whole march is roll-in, then roll out
        k = int(np.argmax(eng))
        return _roll_out_period(pre[:max(k + 1, len(arc) + 1)], rho, roll_sweep_deg, step_mm, allowed, feed_mm_min)
    i_s = len(arc) + int(hit[0])
    roll_in = pre[:i_s + 1].copy()
    e0, e1 = eng[i_s - 1], eng[i_s]
    if e1 > e0 and i_s > len(arc):     # end exactly where the engagement reaches theta (linear)
        roll_in[-1] = pre[i_s - 1] + (theta_deg - e0) / (e1 - e0) * (pre[i_s] - pre[i_s - 1])
    st = fs.copy()
    simulate(st, roll_in, r, a_p, feed_mm_min, lag_mm=0.0)
    c = front_contour(st, x_min=x_min)
    if c is None:
        return _period([("roll-in", roll_in)], True, feed_mm_min)
    Ps = roll_in[-1]
    tt = np.linspace(c.t_min, c.t_max, max(int(c.t_max / (0.25 * step_mm)), 50))
    dist = np.hypot(*(c.point(tt) - Ps).T)
    inside = np.flatnonzero(dist <= r)
    t0 = tt[inside[-1]] if inside.size else tt[int(np.argmin(np.abs(dist - r)))]
    sub = _SubContour(c, t0)
    res = None
    for h in (dt, dt / 4):
        try:
            res = thesis3_path(sub, r, theta_deg, h, method="midpoint", P0=Ps)
            break
        except ValueError:
            continue
    if res is None:          # the followed front is out of the tool's reach here: roll out
        out, _ = roll_arc(Ps, Ps - roll_in[-2], rho, roll_sweep_deg, ds=step_mm, into=False)
        return _period([("roll-in", roll_in), ("roll-out", clamp_to_region(out, allowed))], False, feed_mm_min)
    Q = resample_path(res.P, step_mm)
    ins = shapely.contains_xy(allowed.buffer(1e-9), Q[:, 0], Q[:, 1])
    # the cut ends where it first leaves the region through the *upper* wall: the wall limit there
    # runs backwards (-x in this frame, ccw ring); along an end wall (tangent ~ +y) the clamped cut
    # follows the wall and keeps clearing the corner material
    ymid = 0.5 * (Q[:, 1].min() + Q[:, 1].max())
    out = np.flatnonzero(~ins & (Q[:, 1] > ymid))
    if out.size:
        sq = shapely.line_locate_point(ring, shapely.points(Q[out]))
        tq = (shapely.get_coordinates(shapely.line_interpolate_point(ring, np.mod(sq + step_mm, L)))
              - shapely.get_coordinates(shapely.line_interpolate_point(ring, np.mod(sq - step_mm, L))))
        back_wall = tq[:, 0] < -0.5 * np.hypot(*tq.T)
        out = out[back_wall] if back_wall.any() else out[-1:]
    i_e = int(out[0]) if out.size else len(Q)
    cut = clamp_to_region(Q[:max(i_e, 2)], allowed)
    # roll-out: leave on an arc tangent to the wall limit at the cut's end (the feed turns away from
    # the material: the ring runs -x along the upper wall of a ccw ring)
    E = cut[-1]
    sE = float(ring.project(shapely.Point(E)))
    TE = np.asarray(ring.interpolate(min(sE + step_mm, L)).coords[0]) - np.asarray(ring.interpolate(max(sE - step_mm, 0)).coords[0])
    near_wall = ring.distance(shapely.Point(E)) < 2 * step_mm
    if not near_wall or float(np.dot(TE, cut[-1] - cut[-2])) <= 0:
        TE = cut[-1] - cut[-2]          # the cut ended inside the region: leave along its direction
    if not np.hypot(*TE) > 1e-9:
        d = np.hypot(*np.diff(cut, axis=0).T) > 1e-9
        TE = np.diff(cut, axis=0)[d][-1] if d.any() else np.array([1.0, 0.0])
    cut = np.vstack([Ps, cut[1:]])
    if o.fillet_radius_mm is not None:
        roll_in, cut = fillet_entry(roll_in, cut, o.fillet_radius_mm, rho, roll_sweep_deg, step_mm, allowed)
        if near_wall and float(np.dot(TE, cut[-1] - cut[-2])) > 0:
            cut, E, TE = fillet_exit(cut, TE, o.fillet_radius_mm, step_mm, allowed)
    roll_out, _ = roll_arc(E, TE, rho, roll_sweep_deg, ds=step_mm, into=False)
    roll_out = clamp_to_region(roll_out, allowed)
    return _period([("roll-in", roll_in), ("cut", cut), ("roll-out", roll_out)], True, feed_mm_min)


def _arclength(P):
    return np.r_[0.0, np.cumsum(np.hypot(*np.diff(P, axis=0).T))]


def _unit2(v):
    v = np.asarray(v, float)
    n = float(np.hypot(*v))
    if not n > 1e-12:
        raise ValueError("zero-length direction")
    return v / n


def tangent_arc(A, T, B, ds=0.05):
    """Circular arc from ``A`` (mm) leaving along direction ``T`` and ending at ``B`` (mm).

    The circle tangent to T at A through B (centre on the side of T that B lies on); a straight
    segment when B lies on the line. Returns points (m, 2) with the exact end points.

    >>> P = tangent_arc((0.0, 0.0), (1.0, 0.0), (1.0, 1.0), ds=0.1)
    >>> bool(np.allclose(np.hypot(P[:, 0], P[:, 1] - 1.0), 1.0))       # centre (0, 1), radius 1
    True
    """
    A, B, T = np.asarray(A, float), np.asarray(B, float), _unit2(T)
    d = B - A
    n = np.array([-T[1], T[0]])
    dn = float(d @ n)
    if abs(dn) < 1e-12 * max(float(d @ d), 1e-300):
        return subdivide(np.vstack([A, B]), ds)
    rho = float(d @ d) / (2.0 * dn)                # signed: > 0 turns left (ccw)
    C = A + rho * n
    a0, a1 = math.atan2(*(A - C)[::-1]), math.atan2(*(B - C)[::-1])
    sweep = (a1 - a0) % (2 * math.pi) if rho > 0 else -((a0 - a1) % (2 * math.pi))
    m = max(int(math.ceil(abs(sweep * rho) / ds)), 2)
    ang = a0 + sweep * np.linspace(0.0, 1.0, m + 1)
    P = np.c_[C[0] + abs(rho) * np.cos(ang), C[1] + abs(rho) * np.sin(ang)]
    P[0], P[-1] = A, B
    return P


def _turn(T0, T1) -> float:
    """Signed turning angle (rad, ccw positive) from direction T0 to T1."""
    return math.atan2(T0[0] * T1[1] - T0[1] * T1[0], T0 @ T1)


def fillet_entry(roll_in, cut, radius_mm, roll_radius_mm=1.0, roll_sweep_deg=90.0, ds=0.05, allowed=None,
                 min_turn_deg=2.0):
    """Round the corner where the roll-in (along the wall limit) turns into the Thesis III cut.

    The cut leaves the wall at the roll-in end Ps turning by alpha (ccw); a tool arriving along the
    wall engages the corner left by the previous period's turn at once (the engagement jumps to
    ~alpha however short the step). The corner is replaced by a G1 arc tangent to the roll-in line
    (direction T_in) at A and to the cut at the cut point whose tangent circle has the radius
    closest to ``radius_mm`` (mm; on a straight cut: A = Ps - u T_in and the cut point at arc length
    u, u = radius tan(alpha / 2)). It runs on the cleared side, so each period rounds the corner
    and the next one, shifted by the step s, cuts it like a circular trochoid of radius
    ``radius_mm`` at step s. The roll-in becomes a ``roll_radius_mm`` arc landing on the wall
    0.5 mm before A, the wall to A, and the fillet; ``ds`` (mm) samples them.

    Returns ``(roll_in, cut)`` (points (n, 2), mm); unchanged when the turn is below ``min_turn_deg``.

    >>> wall = np.c_[np.linspace(-5.0, 0.0, 51), np.zeros(51)]
    >>> cut = np.c_[np.zeros(51), np.linspace(0.0, 5.0, 51)]          # a 90 deg turn at (0, 0)
    >>> r_in, c = fillet_entry(wall, cut, 1.0, ds=0.1)
    >>> c[0].tolist(), np.round(r_in[-1], 9).tolist()               # u = 1 tan 45 deg = 1 mm
    ([0.0, 1.0], [0.0, 1.0])
    """
    roll_in, cut = np.asarray(roll_in, float), np.asarray(cut, float)
    rf = _common.positive("radius_mm", radius_mm)
    Ps = cut[0]
    d_in = np.diff(roll_in, axis=0)
    d_in = d_in[np.hypot(*d_in.T) > 1e-9]
    T_in = _unit2(d_in[-1])
    sc = _arclength(cut)
    if sc[-1] < 4 * ds:
        return roll_in, cut
    T_out = _unit2(cut[int(np.searchsorted(sc, min(0.5, 0.5 * sc[-1])))] - Ps)
    alpha = _turn(T_in, T_out)
    if not math.degrees(alpha) > min_turn_deg:
        return roll_in, cut
    # G1 fillet: for each cut point j (tangent T_j) the circle tangent to the roll-in line and to the
    # cut at j has its corner X_j (the two tangent lines' intersection) equidistant from both
    # tangent points; take the j whose radius is closest to ``radius_mm``
    J = np.arange(1, len(cut) - 1)
    T = cut[J + 1] - cut[J - 1]
    T = T / np.hypot(*T.T)[:, None]
    den = T_in[0] * T[:, 1] - T_in[1] * T[:, 0]           # sin of the turn at j
    w = cut[J] - Ps
    lam = (w[:, 0] * T[:, 1] - w[:, 1] * T[:, 0]) / np.where(np.abs(den) > 1e-9, den, np.nan)
    X = Ps + lam[:, None] * T_in
    dist = np.hypot(*(cut[J] - X).T)
    turn = np.arctan2(den, T @ T_in)
    rad = dist / np.tan(0.5 * np.where(turn > 1e-3, turn, np.nan))
    ok = np.isfinite(rad) & (dist <= 0.6 * sc[-1] + 10 * rf) & (sc[J] <= 0.6 * sc[-1])
    if ok.any():
        k = int(np.nanargmin(np.where(ok, np.abs(rad - rf), np.nan)))
        j = int(J[k])
        A = X[k] - dist[k] * T_in
    else:
        u = min(rf * math.tan(0.5 * alpha), 0.6 * sc[-1])
        A = Ps - u * T_in
        j = min(int(np.searchsorted(sc, u)), len(cut) - 2)
    fil = tangent_arc(A, T_in, cut[j], ds)
    A0 = A - 0.5 * T_in
    arc, _ = roll_arc(A0, T_in, roll_radius_mm, roll_sweep_deg, ds=ds, into=True)
    new_in = np.vstack([arc, subdivide(np.vstack([A0, A]), ds)[1:], fil[1:]])
    if allowed is not None:
        new_in = clamp_to_region(new_in, allowed)
    return new_in, cut[j:]


def fillet_exit(cut, wall_direction, radius_mm, ds=0.05, allowed=None, min_turn_deg=2.0):
    """Round the corner where the cut reaches the far wall limit and turns along it (``wall_direction``).

    Mirror of :func:`fillet_entry`: the cut's last ``u = radius tan(alpha / 2)`` (alpha = turn from
    the cut's arrival direction to the wall direction) is replaced by the arc tangent to the wall at
    D = E + u T_wall (E the cut's end on the wall) through the cut point at arc length u before E.
    Returns ``(cut, D, T_wall)``: the new cut ending at D, where the roll-out starts along T_wall.
    """
    cut = np.asarray(cut, float)
    rf = _common.positive("radius_mm", radius_mm)
    TE = _unit2(wall_direction)
    sc = _arclength(cut)
    E = cut[-1]
    if sc[-1] < 4 * ds:
        return cut, E, TE
    T_c = _unit2(E - cut[int(np.searchsorted(sc, sc[-1] - min(0.5, 0.5 * sc[-1])))])
    alpha = _turn(T_c, TE)
    if not math.degrees(alpha) > min_turn_deg:
        return cut, E, TE
    u = min(rf * math.tan(0.5 * alpha), 0.6 * sc[-1])
    D = E + u * TE
    if allowed is not None:
        D = clamp_to_region(D[None, :], allowed)[0]
    j = max(int(np.searchsorted(sc, sc[-1] - u)), 1)
    fil = tangent_arc(D, -TE, cut[j], ds)[::-1]
    new = np.vstack([cut[:j], fil])
    if allowed is not None:
        new = clamp_to_region(new, allowed)
    return new, D, TE


def linking_arc(E, S, allowed=None, bulge=0.5, ds=0.05, side=None):
    """Arc from E to S (mm) through the cleared side: passes B = midpoint - bulge*|ES| * n, n the
    unit normal of ES toward ``side`` (default: the -x side of the chord direction's left normal).

    Returns ``(points (m, 2), centre (2,), ccw)``. Points outside ``allowed`` (if given) are
    projected onto its boundary (the arc is then not exact; the G-code writer uses G1 for it).
    """
    E, S = np.asarray(E, float), np.asarray(S, float)
    ch = S - E
    L = float(np.hypot(*ch))
    if L < 1e-9:
        return np.vstack([E, S]), None, True
    n = np.array([-ch[1], ch[0]]) / L                  # left normal of E->S
    if side is None:
        side = np.array([-1.0, 0.0])
    if n @ side < 0:
        n = -n
    B = 0.5 * (E + S) + bulge * L * n
    # circumcentre of E, B, S
    ax, ay, bx, by, cx, cy = *E, *B, *S
    d = 2 * (ax * (by - cy) + bx * (cy - ay) + cx * (ay - by))
    ux = ((ax * ax + ay * ay) * (by - cy) + (bx * bx + by * by) * (cy - ay) + (cx * cx + cy * cy) * (ay - by)) / d
    uy = ((ax * ax + ay * ay) * (cx - bx) + (bx * bx + by * by) * (ax - cx) + (cx * cx + cy * cy) * (bx - ax)) / d
    C = np.array([ux, uy])
    a0 = math.atan2(E[1] - uy, E[0] - ux)
    aB = math.atan2(B[1] - uy, B[0] - ux)
    a1 = math.atan2(S[1] - uy, S[0] - ux)
    ccw_sweep = (a1 - a0) % (2 * math.pi)
    ccw = ((aB - a0) % (2 * math.pi)) < ccw_sweep
    sweep = ccw_sweep if ccw else ccw_sweep - 2 * math.pi
    R = float(np.hypot(*(E - C)))
    m = max(int(math.ceil(abs(sweep) * R / ds)), 2)
    ang = a0 + sweep * np.linspace(0, 1, m + 1)
    pts = np.c_[ux + R * np.cos(ang), uy + R * np.sin(ang)]
    pts[0], pts[-1] = E, S
    if allowed is not None:
        q = clamp_to_region(pts, allowed)
        if not np.allclose(q, pts):
            return q, None, ccw
    return pts, C, ccw


@dataclass
class CEIteration:
    """Periods of the constant-engagement iteration (Fig. 3.5) and their convergence."""

    cuts: list
    table: object          # pandas DataFrame: period, shift_mm, shape_change_mm, lengths, max engagements
    stock: object
    periods: list = field(default_factory=list)
    links: list = field(default_factory=list)


def _shape_change(A, B, n=200):
    """Mean x-shift (mm) of cut B relative to A and the max residual |x_B - x_A - shift| over
    common arc-length fractions."""
    def resamp(P):
        s = np.r_[0.0, np.cumsum(np.hypot(*np.diff(P, axis=0).T))]
        u = np.linspace(0, s[-1], n)
        return np.c_[np.interp(u, s, P[:, 0]), np.interp(u, s, P[:, 1])]

    a, b = resamp(A), resamp(B)
    shift = float(np.mean(b[:, 0] - a[:, 0]))
    res = np.hypot(b[:, 0] - a[:, 0] - shift, b[:, 1] - a[:, 1])
    return shift, float(res.max())


def _straight_link(E, S, allowed, ds):
    """Straight linking move E -> S (mm) sampled every ``ds`` (:func:`subdivide`), clamped to ``allowed``."""
    P = subdivide(np.vstack([E, S]), ds)
    return P if allowed is None else clamp_to_region(P, allowed)


def ce_trochoid_iteration(width, tool_radius, theta_deg, n_periods=8, resolution_mm=0.05,
                          dt=0.1, a_p=3.0, feed_mm_min=255.0, x_front0=0.0, roll_radius=1.0,
                          fillet_radius_mm="auto"):
    """Thesis IV iteration: plan and cut period after period into a straight slot (front at ``x_front0``).

    Per period the front is recomputed from the dixel stock and :func:`ce_period` plans roll-in,
    constant-engagement cut and roll-out; a straight link joins the previous roll-out to it.
    ``fillet_radius_mm``: corner fillets of :func:`ce_period` ("auto" = the slot's centre-line
    half-width W/2 - r, the circle trochoid's radius; None = sharp corners, the pre-fillet roll-in).
    Returns :class:`CEIteration`: ``cuts`` (the whole period polylines), ``periods``
    (period :class:`ToolPath` s), ``links`` and a table per period of shift (the trochoidal step, mm),
    shape change (max residual after removing the shift, mm), lengths, removed area, the maximum
    engagement per segment type (deg) and the material cut by the link (mm^2).
    """
    r = _common.positive("tool_radius", tool_radius)
    yl = slot_limit(width, r)
    W = float(width)
    length = x_front0 + (n_periods + 2) * 2 * r + 4 * r
    st = dixel.Stock.from_polygon(box(x_front0, -W / 2, length, W / 2), resolution_mm)
    allowed = box(x_front0 - 10 * W, -yl, length + 10 * W, yl)
    cuts, periods, links, rows = [], [], [], []
    fr = yl if isinstance(fillet_radius_mm, str) and fillet_radius_mm == "auto" else fillet_radius_mm
    for k in range(int(n_periods)):
        per = ce_period(st, r, theta_deg, allowed, dt=dt, step_mm=resolution_mm, roll_radius=roll_radius,
                        a_p=a_p, feed_mm_min=feed_mm_min, fillet_radius_mm=fr)
        if per is None:
            break
        P, kinds = per.xyz[:, :2], pattern_kinds(per)
        lk = _straight_link(cuts[-1][-1], P[0], allowed, resolution_mm) if cuts else P[:1]
        df = dixel.simulate(st, np.vstack([lk, P[1:]]), r, a_p, feed_mm_min)
        kk = np.r_[np.full(len(lk), "link", dtype=object), kinds[1:]]
        if not cuts:
            kk[0] = kinds[0]
        eng = df.engagement_deg.to_numpy()
        shift, change = (math.nan, math.nan) if not cuts else _shape_change(cuts[-1], P)
        row = {"period": k, "shift_mm": shift, "shape_change_mm": change,
               "cut_mm": float(df.ds[kk != "link"].sum()), "link_mm": float(df.ds[kk == "link"].sum()),
               "removed_mm2": float(df.removed_mm2.sum()),
               "link_removed_mm2": float(df.removed_mm2[kk == "link"].sum())}
        for name in ("roll-in", "cut", "roll-out", "link"):
            e = eng[kk == name]
            row[f"engagement_max_{name}_deg"] = float(np.nanmax(e)) if np.isfinite(e).any() else math.nan
        rows.append(row)
        cuts.append(P)
        periods.append(per)
        links.append(lk)
    import pandas as pd      # here: the planners import this module, most never build a table (0.3 s)

    return CEIteration(cuts, pd.DataFrame(rows), st, periods, links)


def _repeat_period(per: ToolPath, step, n_periods, resolution_mm, feed_mm_min=255.0,
                   link_feed_mm_min=None) -> ToolPath:
    """One planned period (roll-in, cut, roll-out) repeated ``n_periods`` times ``step`` mm apart
    along +x, joined by straight links (flagged link) through the cleared slot."""
    P0, K0 = per.xyz[:, :2], pattern_kinds(per)
    P0 = P0 - np.array([P0[:, 0].min(), 0.0])
    b = _common.pattern_builder(step, "constant-engagement")
    for k in range(int(n_periods)):
        C = P0 + np.array([k * step, 0.0])
        if k > 0:
            lk = _straight_link(b.position[:2], C[0], None, resolution_mm)
            _common.add_piece(b, lk[1:], "link", k - 1, feed_mm_min, link_feed_mm_min)
            C, KC = C[1:], K0[1:]
        else:
            KC = K0
        _common.add_piece(b, C, KC, k, feed_mm_min, link_feed_mm_min)
    return b.build()


def ce_admissible_step(per: ToolPath, theta_max_deg, width, tool_radius, resolution_mm=0.05, n_periods=5,
                       s_guess=None, tol_mm=0.005):
    """Largest step (mm) at which the repeated period ``per`` keeps the simulated steady-state
    maximum engagement (every cutting move: roll-in, cut, roll-out) at most ``theta_max_deg``.

    The same bisection as :func:`admissible_step` applies to the circle and the cycloid, so the three
    patterns are compared at equal simulated maximum engagement. ``s_guess`` (mm, e.g. the
    iteration's shift) seeds the bracket.
    """
    r = _common.positive("tool_radius", tool_radius)
    s0 = _common.positive("s_guess", s_guess) if s_guess is not None else 0.5 * r

    def emax(s):
        p = _repeat_period(per, s, n_periods, resolution_mm)
        return evaluate_pattern(p, width, r, resolution_mm)[1]["engagement_max_deg"]

    return _common.largest_step(emax, theta_max_deg, 0.5 * s0, 1.5 * s0, tol_mm, grow_limit=4 * r)


@dataclass(frozen=True, kw_only=True)
class CEPatternOptions:
    """Settings of the repeated pattern of :func:`ce_trochoid`, keyword-only.

    ``dt`` (mm of contour parameter), ``n_iter`` (periods) and ``roll_radius`` (mm): the
    :func:`ce_trochoid_iteration` run when no ``iteration`` is given; ``feed_mm_min`` (mm/min) of the
    periods and ``link_feed_mm_min`` (mm/min; None = the feed) of the links; ``step`` ``"admissible"``
    | ``"shift"`` | a number (mm); ``theta_max_deg`` (deg; None = ``theta_deg``) of the admissible step.

    >>> CEPatternOptions(step="shift").n_iter
    8
    """

    dt: float = 0.1
    n_iter: int = 8
    roll_radius: float = 1.0
    feed_mm_min: float = 255.0
    link_feed_mm_min: float | None = None
    step: str | float = "admissible"
    theta_max_deg: float | None = None


def ce_trochoid(width, tool_radius, theta_deg, n_periods=6, resolution_mm=0.05, *,
                iteration: CEIteration | None = None, options: CEPatternOptions | None = None,
                **fields) -> ToolPath:
    """Repetitive constant-engagement pattern: the last (converged) period of
    :func:`ce_trochoid_iteration` (roll-in, cut, roll-out) repeated ``n_periods`` times, joined by
    straight linking moves (flagged link) through the cleared slot.

    ``step``: ``"admissible"`` (default) — the largest step whose simulated maximum engagement stays
    at ``theta_max_deg`` (default ``theta_deg``; :func:`ce_admissible_step`); ``"shift"`` — the
    iteration's last shift (a dixel-noisy estimate: the roll-in end sits where the engagement climbs
    steeply, so a step a few hundredths of a mm too long shows as an overshoot); or a number (mm).
    ``info["shift"]`` keeps the iteration's last shift. Settings: a :class:`CEPatternOptions` or its
    fields as keywords (``fields`` replace those of ``options``).
    """
    o = CEPatternOptions(**fields) if options is None else replace(options, **fields)
    step, theta_max_deg = o.step, o.theta_max_deg
    it = iteration or ce_trochoid_iteration(width, tool_radius, theta_deg, o.n_iter, resolution_mm, o.dt,
                                            roll_radius=o.roll_radius)
    # the last complete period (roll-in, cut at theta, roll-out); a final period that found no
    # front in reach (Thesis III failed, rolled straight out) is not a pattern period
    good = [k for k, q in enumerate(it.periods)
            if q.info.get("reached_theta", True) and bool((pattern_kinds(q) == "cut").any())]
    if len(it.cuts) < 3 or not good or good[-1] < 2:
        raise ValueError("the constant-engagement iteration produced fewer than 3 complete periods")
    k_last = good[-1]
    per = it.periods[k_last]
    shifts = it.table.shift_mm.to_numpy()[:k_last + 1]
    shift = float(shifts[-1])
    if isinstance(step, str):
        if step == "shift":
            if not shift > 0:
                raise ValueError(f"non-positive converged step {shift}")
            s = shift
        elif step == "admissible":
            th = theta_deg if theta_max_deg is None else theta_max_deg
            last = shifts[-3:]
            last = last[np.isfinite(last) & (last > 0)]     # the bracket's seed only
            guess = float(np.median(last)) if last.size else circle_front_step(th, width, tool_radius)
            s = ce_admissible_step(per, th, width, tool_radius, resolution_mm, s_guess=guess)
        else:
            raise ValueError(f"step must be 'admissible', 'shift' or a number (mm), got {step!r}")
    else:
        s = _common.positive("step", step)
    p = _repeat_period(per, s, n_periods, resolution_mm, o.feed_mm_min, o.link_feed_mm_min)
    p.info["shift"] = shift
    return p
