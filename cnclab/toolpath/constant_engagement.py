"""Constant-engagement tool paths along arbitrary contours (Jacsó 2021, Theses II and III).

Conventions: lengths in mm, ``theta_deg`` in degrees, ``tool_radius`` is the radius r (the
booklet's r_sz). The contour c(t) (:mod:`cnclab.geometry.contours`) is the current boundary of the
material, traversed with the material on its **right**.

Rotation sense (checked here, see :func:`thesis2_feed_direction`): Thesis II's equation
p = c + R(pi/2 + theta) p' r/|p'| says CP is the feed direction rotated *counter-clockwise* by
beta = pi/2 + theta, i.e. the feed direction is CP rotated *clockwise* by beta. The prose of §3.2
("rotating CP by beta = pi/2 + theta") therefore holds only in the clockwise sense. Thesis III's
Step 1 (rotate P_iC_i by alpha = pi/2 - theta, counter-clockwise) gives the same direction, since
PC = -CP and pi + pi/2 - theta = -(pi/2 + theta) mod 2 pi.

Thesis II (IVP) is solved with :func:`scipy.integrate.solve_ivp`: differentiating |p - c| = r gives
p' = lambda u, u = R(-(pi/2 + theta)) (p - c)/r, lambda = -(p - c).c'(t) / (r sin theta).
Thesis III (Steps 0-5) is :func:`thesis3_path` with explicit Euler or midpoint direction, fixed or
adaptive step, and :func:`spline_path` connects the points with a cubic spline.

>>> from cnclab.geometry.contours import Line
>>> res = thesis3_path(Line((0, 0), (10, 0)), 3.0, 60.0, 0.5)
>>> round(float(res.P[-1, 1]), 9)          # straight contour: offset r cos(theta) = 1.5 mm
1.5
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..geometry.contours import SplineContour
from ..geometry.engagement import stepover_thesis1
from ..simulation import dixel, pixel
from ..simulation.common import simulate
from .path import resample_polyline


def rot(v, angle_rad):
    """Rotate 2-vectors ``v`` (..., 2) counter-clockwise by ``angle_rad``."""
    v = np.asarray(v, float)
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1]], axis=-1)


def _unit(v):
    v = np.asarray(v, float)
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / n


def _check(tool_radius, theta_deg):
    if not (tool_radius > 0):
        raise ValueError(f"tool_radius must be > 0 mm, got {tool_radius!r}")
    if not (0 < theta_deg <= 180):
        raise ValueError(f"theta_deg must be in (0, 180] deg, got {theta_deg!r}")
    return float(tool_radius), math.radians(theta_deg)


def thesis3_feed_direction(P, C, theta_deg):
    """Thesis III Step 1: unit feed direction = P->C rotated ccw by alpha = pi/2 - theta."""
    return rot(_unit(np.asarray(C, float) - np.asarray(P, float)), math.pi / 2 - math.radians(theta_deg))


def thesis2_feed_direction(P, C, theta_deg):
    """Feed direction implied by Thesis II's equation: u = R(pi/2 + theta)^-1 (P - C)/|P - C|."""
    return rot(_unit(np.asarray(P, float) - np.asarray(C, float)), -(math.pi / 2 + math.radians(theta_deg)))


def start_point(contour, tool_radius, theta_deg, t0=None):
    """P0 = C0 + r R(pi/2 + theta) T0 (T0 the contour's unit tangent): exact on straight contours."""
    r, th = _check(tool_radius, theta_deg)
    t0 = contour.t_min if t0 is None else t0
    C0 = contour.point(t0)[0]
    T0 = _unit(contour.deriv(t0)[0])
    return C0 + r * rot(T0, math.pi / 2 + th)


def arc_start_point(arc, tool_radius, theta_deg, kind):
    """Exact P0 on an :class:`~cnclab.geometry.contours.Arc` contour (path concentric from the start).

    The path radius is d = rho + s - r (concave, arc traversed ccw) or rho - s + r (convex, cw),
    s from Thesis I; P0 lags C0 by the angle POC of the triangle (d, rho, r).
    """
    r, _ = _check(tool_radius, theta_deg)
    rho = arc.radius
    s = float(stepover_thesis1(theta_deg, rho, r, kind))
    d = rho + s - r if kind == "concave" else rho - s + r
    delta = math.acos(np.clip((d * d + rho * rho - r * r) / (2 * d * rho), -1, 1))
    a = arc.a0 - arc.sign * delta
    return arc.c + d * np.array([math.cos(a), math.sin(a)]), d


def ray_circle(P, v, C, r):
    """Smallest lambda >= 0 with |P + lambda v - C| = r (v unit); NaN if the half-line misses
    (:func:`_ray_circle` on the 2-vectors)."""
    (px, py), (vx, vy), (cx, cy) = (np.asarray(a, float).tolist() for a in (P, v, C))
    return _ray_circle(px, py, vx, vy, cx, cy, r)


@dataclass
class PathResult:
    """Tool-path points P (N, 2) with contour parameters t (N,) and contact points C = c(t) (N, 2)."""

    t: np.ndarray
    P: np.ndarray
    C: np.ndarray
    method: str = ""
    n_rejected: int = 0

    @property
    def length(self) -> float:
        return float(np.sum(np.hypot(*np.diff(self.P, axis=0).T)))


def _step(contour, P, t, dt, r, theta_deg, method):
    """One Thesis III step from (P, t) to t + dt; returns the new P or None if the ray misses."""
    C = contour.point(t)[0]
    v = thesis3_feed_direction(P, C, theta_deg)
    if method == "midpoint":
        Ch = contour.point(t + 0.5 * dt)[0]
        lam = ray_circle(P, v, Ch, r)
        if not math.isfinite(lam):
            return None
        Ph = P + lam * v
        v = thesis3_feed_direction(Ph, Ch, theta_deg)
    elif method != "euler":
        raise ValueError(f"method must be 'euler' or 'midpoint', got {method!r}")
    C1 = contour.point(t + dt)[0]
    lam = ray_circle(P, v, C1, r)
    if not math.isfinite(lam):
        return None
    return P + lam * v


def _fixed_step_path(contour, P, t, t_end, dt, r, theta_deg, method, max_steps):
    """:func:`thesis3_path` with a fixed step: the contour parameters of every step are known before
    the march, so the contact points are evaluated in one call and the steps (:func:`_step`'s
    arithmetic, on floats) run without array overhead."""
    if method not in ("euler", "midpoint"):
        raise ValueError(f"method must be 'euler' or 'midpoint', got {method!r}")
    ts, hs, h = [t], [], dt
    while ts[-1] < t_end - 1e-12 and len(ts) < max_steps:
        h = min(h, t_end - ts[-1])
        hs.append(h)
        ts.append(ts[-1] + h)
    tt = np.asarray(ts)
    C = contour.point(tt)
    Cx, Cy = C[:, 0].tolist(), C[:, 1].tolist()
    if method == "midpoint":
        M = contour.point(tt[:-1] + 0.5 * np.asarray(hs))
        Mx, My = M[:, 0].tolist(), M[:, 1].tolist()
    alpha = math.pi / 2 - math.radians(theta_deg)
    ca, sa = math.cos(alpha), math.sin(alpha)
    px, py = float(P[0]), float(P[1])
    out = [(px, py)]
    for i in range(len(hs)):
        vx, vy = _feed_dir(px, py, Cx[i], Cy[i], ca, sa)
        if method == "midpoint":
            lam = _ray_circle(px, py, vx, vy, Mx[i], My[i], r)
            if not math.isfinite(lam):
                raise ValueError(f"dt={dt} too large: the feed half-line misses the circle at t={ts[i]:.6g}")
            vx, vy = _feed_dir(px + lam * vx, py + lam * vy, Mx[i], My[i], ca, sa)
        lam = _ray_circle(px, py, vx, vy, Cx[i + 1], Cy[i + 1], r)
        if not math.isfinite(lam):
            raise ValueError(f"dt={dt} too large: the feed half-line misses the circle at t={ts[i]:.6g}")
        px, py = px + lam * vx, py + lam * vy
        out.append((px, py))
    return PathResult(tt, np.asarray(out), C, method, 0)


def _feed_dir(px, py, cx, cy, ca, sa):
    """Thesis III Step 1 on floats: the unit vector P -> C rotated ccw by alpha (cos ``ca``, sin ``sa``)."""
    ux, uy = cx - px, cy - py
    n = math.sqrt(ux * ux + uy * uy)
    ux, uy = ux / n, uy / n
    return ca * ux - sa * uy, sa * ux + ca * uy


def _ray_circle(px, py, vx, vy, cx, cy, r):
    """:func:`ray_circle` on floats: the nearer intersection of the half-line P + lambda v with the
    circle (C, r) first."""
    wx, wy = px - cx, py - cy
    b = vx * wx + vy * wy
    disc = b * b - (wx * wx + wy * wy - r * r)
    if disc < 0:
        return math.nan
    sq = math.sqrt(disc)
    for lam in (-b - sq, -b + sq):
        if lam >= -1e-12:
            return max(lam, 0.0)
    return math.nan


def thesis3_path(contour, tool_radius, theta_deg, dt, method="euler", P0=None, t_end=None,
                 adaptive=False, tol_mm=1e-4, dt_min=None, dt_max=None, max_steps=2_000_000):
    """Thesis III: tool-path points holding engagement ``theta_deg`` along ``contour``.

    Steps 0-5 of the booklet with ``method="euler"`` (Step 1 direction at P_i) or ``"midpoint"``
    (direction re-evaluated at the half step). ``dt`` is the contour-parameter step (mm for
    arc-length contours). With ``adaptive=True`` the step is chosen by step doubling so the local
    error stays below ``tol_mm`` (mm). ``P0`` defaults to :func:`start_point`.

    Returns :class:`PathResult`. Raises ValueError if the half-line misses the circle (step too
    large for the contour's curvature) in fixed-step mode.
    """
    r, _ = _check(tool_radius, theta_deg)
    if not dt > 0:
        raise ValueError(f"dt must be > 0, got {dt!r}")
    t = float(contour.t_min)
    t_end = float(contour.t_max if t_end is None else t_end)
    P = start_point(contour, r, theta_deg) if P0 is None else np.asarray(P0, float)
    if not adaptive:
        return _fixed_step_path(contour, P, t, t_end, dt, r, theta_deg, method, max_steps)
    ts, Ps = [t], [P]
    dt_min = dt * 1e-3 if dt_min is None else dt_min
    dt_max = dt * 50 if dt_max is None else dt_max
    order = 2 if method == "midpoint" else 1
    rejected = 0
    h = dt
    while t < t_end - 1e-12 and len(ts) < max_steps:
        h = min(h, t_end - t)
        P1 = _step(contour, P, t, h, r, theta_deg, method)
        Pm = _step(contour, P, t, 0.5 * h, r, theta_deg, method)
        P2 = None if Pm is None else _step(contour, Pm, t + 0.5 * h, 0.5 * h, r, theta_deg, method)
        if P1 is None or P2 is None:
            rejected += 1
            h *= 0.5
            if h < dt_min:
                raise ValueError(f"adaptive step fell below dt_min at t={t:.6g}")
            continue
        err = float(np.hypot(*(P2 - P1))) / (2 ** order - 1)
        if err > tol_mm and h > dt_min:
            rejected += 1
            h = max(h * max(0.2, 0.9 * (tol_mm / err) ** (1 / (order + 1))), dt_min)
            continue
        Pn = P2 + (P2 - P1) / (2 ** order - 1)   # Richardson-extrapolated
        fac = 2.0 if err == 0 else min(2.0, 0.9 * (tol_mm / err) ** (1 / (order + 1)))
        t = t + h
        P = Pn
        ts.append(t)
        Ps.append(P)
        h = min(max(h * fac, dt_min), dt_max)
    tt = np.asarray(ts)
    return PathResult(tt, np.asarray(Ps), contour.point(tt), method + "-adaptive", rejected)


def thesis2_ivp(contour, tool_radius, theta_deg, P0=None, t_eval=None, rtol=1e-10, atol=1e-10,
                t_end=None):
    """Thesis II: solve the IVP p = c + R(pi/2 + theta) p' r/|p'|, p(t_min) = P0 with scipy.

    Uses the equivalent ODE p' = lambda u (see the module docstring), RK45 (``DOP853``) with dense
    output. Returns :class:`PathResult` at ``t_eval`` (default 2001 points).
    """
    from scipy.integrate import solve_ivp

    r, th = _check(tool_radius, theta_deg)
    P0 = start_point(contour, r, theta_deg) if P0 is None else np.asarray(P0, float)
    t_end = contour.t_max if t_end is None else t_end
    sin_t = math.sin(th)
    if sin_t < 1e-12:
        raise ValueError("theta_deg = 180 (slotting): the feed speed lambda is undefined")

    def f(t, p):
        c = contour.point(t)[0]
        dc = contour.deriv(t)[0]
        w = p - c
        u = rot(w / np.hypot(*w), -(math.pi / 2 + th))
        lam = -(w @ dc) / (r * sin_t)
        return lam * u

    if t_eval is None:
        t_eval = np.linspace(contour.t_min, t_end, 2001)
    sol = solve_ivp(f, (contour.t_min, t_end), P0, method="DOP853", t_eval=t_eval, rtol=rtol,
                    atol=atol, dense_output=True)
    if not sol.success:
        raise RuntimeError(f"solve_ivp failed: {sol.message}")
    res = PathResult(sol.t, sol.y.T, contour.point(sol.t), "thesis2-ivp")
    res.sol = sol
    return res


def spline_path(P, closed: bool = False):
    """Cubic spline (C2) through path points P (N, 2) with chord-length parameter (mm).

    Returns (spline, total length); ``spline(u)`` gives points, ``spline(u, 1)`` tangents.
    """
    from scipy.interpolate import CubicSpline

    P = np.asarray(P, float)
    keep = np.r_[True, np.hypot(*np.diff(P, axis=0).T) > 1e-12]
    P = P[keep]
    u = np.r_[0.0, np.cumsum(np.hypot(*np.diff(P, axis=0).T))]
    return CubicSpline(u, P, bc_type="periodic" if closed else "not-a-knot"), float(u[-1])


def resample_path(P, step_mm, spline: bool = True):
    """Tool-centre samples every ``step_mm`` along the path (cubic spline or polyline through P)."""
    if not step_mm > 0:
        raise ValueError(f"step_mm must be > 0, got {step_mm!r}")
    P = np.asarray(P, float)
    if spline and len(P) >= 4:
        sp, L = spline_path(P)
        return sp(np.linspace(0, L, max(int(math.ceil(L / step_mm)), 1) + 1))
    return resample_polyline(P, step_mm, uniform=True)


def engagement_along_path(stock_polygon, centres, tool_radius, resolution_mm, a_p=1.0,
                          feed_mm_min=1000.0, model="dixel", feed_direction="backward"):
    """Cut ``stock_polygon`` with the path ``centres`` in the dixel (or pixel) simulator; per-step table.

    ``feed_direction`` is passed to :func:`cnclab.simulation.common.simulate` (``"central"``: the
    tangent of the sampled path, without the half-step lag of the backward chord).
    """
    mod = {"dixel": dixel, "pixel": pixel}.get(model)
    if mod is None:
        raise ValueError(f"model must be 'dixel' or 'pixel', got {model!r}")
    st = mod.Stock.from_polygon(stock_polygon, resolution_mm)
    return mod.simulate(st, centres, tool_radius, a_p, feed_mm_min, feed_direction=feed_direction)


def convergence_study(contour, tool_radius, theta_deg, dts, methods=("euler", "midpoint"), t_end=None,
                      P0=None):
    """Thesis III error vs step: max |P_i - p(t_i)| (mm) against the Thesis II IVP (scipy, tol 1e-10).

    Returns ``(table, orders)``: a DataFrame with columns method, dt, max_err_mm, and a dict of the
    observed orders (least-squares slope of log error vs log dt) per method. Expected: 1 (Euler),
    2 (midpoint).

    >>> from cnclab.geometry.contours import Ellipse
    >>> _, k = convergence_study(Ellipse((0, 0), 12, 8), 3.0, 60.0, [0.04, 0.02, 0.01], t_end=3.0)
    >>> round(k["euler"], 1), round(k["midpoint"], 1)
    (1.0, 2.0)
    """
    import pandas as pd

    dts = np.asarray(dts, float)
    if dts.ndim != 1 or dts.size < 2 or not np.all(dts > 0):
        raise ValueError(f"dts must hold at least two positive steps, got {dts!r}")
    ref = thesis2_ivp(contour, tool_radius, theta_deg, P0=P0, t_end=t_end)
    rows = []
    for m in methods:
        for dt in dts:
            p = thesis3_path(contour, tool_radius, theta_deg, float(dt), m, P0=P0, t_end=t_end)
            rows.append((m, float(dt), float(np.max(np.hypot(*(p.P - ref.sol.sol(p.t).T).T)))))
    table = pd.DataFrame(rows, columns=["method", "dt", "max_err_mm"])
    orders = {m: float(np.polyfit(np.log(g.dt), np.log(g.max_err_mm), 1)[0])
              for m, g in table.groupby("method", sort=False)}
    return table, orders


def simulated_deviation_vs_dt(contour, stock_polygon, tool_radius, theta_deg, dts, method="euler",
                              resolution_mm=0.05, t_end=None, skip_mm=3.0, end_skip_mm=1.0):
    """Engagement deviation measured by the dixel simulator along Thesis III paths, per step ``dt``.

    For every dt the path along ``contour`` (up to ``t_end``) is generated, resampled every
    ``resolution_mm`` with a cubic spline, and cut into ``stock_polygon`` (feed direction: central
    difference). Returns a DataFrame (dt, mean_deg, mean_abs_dev_deg, p95_dev_deg, max_dev_deg, n)
    over the path length [skip_mm, L - end_skip_mm] (deg).
    """
    import pandas as pd

    rows = []
    for dt in np.asarray(dts, float):
        res = thesis3_path(contour, tool_radius, theta_deg, float(dt), method, t_end=t_end)
        P = resample_path(res.P, resolution_mm)
        df = engagement_along_path(stock_polygon, P, tool_radius, resolution_mm, feed_direction="central")
        st = deviation_stats(df.engagement_deg, theta_deg, skip_mm=skip_mm, s_mm=df.s, end_skip_mm=end_skip_mm)
        rows.append({"dt": float(dt), **st})
    return pd.DataFrame(rows)


def deviation_stats(engagement_deg, theta_deg, skip_mm, s_mm, end_skip_mm=0.0):
    """Mean, p95 and max |engagement - theta| (deg) for path length in [skip_mm, L - end_skip_mm]."""
    e = np.asarray(engagement_deg, float)
    s = np.asarray(s_mm, float)
    m = (s >= skip_mm) & (s <= s[-1] - end_skip_mm) & np.isfinite(e)
    dev = np.abs(e[m] - theta_deg)
    return {"mean_deg": float(np.mean(e[m])), "mean_abs_dev_deg": float(np.mean(dev)),
            "p95_dev_deg": float(np.percentile(dev, 95)), "max_dev_deg": float(np.max(dev)),
            "n": int(m.sum())}


# ---------------------------------------------------------------------------------------------
# multiple passes (building block for trochoids and pockets)
# ---------------------------------------------------------------------------------------------
def cleared_boundary_contour(stock, seed_xy, domain_polygon, min_spacing_mm=None):
    """Boundary of the cleared region around ``seed_xy`` from a dixel stock, as a closed ccw contour.

    The material is rebuilt from the dixels (row rectangles), the cleared region = domain minus
    material, and its exterior ring is sampled at the row centre lines (vertical staircase edges,
    exact in x) plus the midpoints of horizontal edges, thinned to ``min_spacing_mm`` (default 10 row
    heights, at least 0.3 mm) and closed with a periodic cubic spline (:class:`~cnclab.geometry.contours.SplineContour`).
    """
    from shapely.geometry import Point

    h = stock.resolution_mm
    min_spacing_mm = max(10 * h, 0.3) if min_spacing_mm is None else min_spacing_mm
    cleared = domain_polygon.difference(stock.to_polygon())
    geoms = getattr(cleared, "geoms", [cleared])
    seed = Point(*seed_xy)
    comp = [g for g in geoms if g.buffer(1e-9).contains(seed)]
    if not comp:
        raise ValueError(f"seed_xy={tuple(seed_xy)} is not in a cleared region of the stock")
    ring = np.asarray(comp[0].exterior.coords)[:-1]
    a, b = ring, np.roll(ring, -1, axis=0)
    mid = 0.5 * (a + b)
    # keep the midpoints of all staircase edges (vertical: row centre samples; horizontal: chords)
    pts = thin_ring(mid, min_spacing_mm)
    area2 = np.sum(pts[:, 0] * np.roll(pts[:, 1], -1) - np.roll(pts[:, 0], -1) * pts[:, 1])
    if area2 < 0:
        pts = pts[::-1]
    return SplineContour(pts, closed=True)


def thin_ring(points, min_spacing_mm: float):
    """The points of a closed ring (n, 2) (mm; not repeating the first), thinned to at least
    ``min_spacing_mm`` apart along the ring, for a periodic spline through them. The last point kept
    is dropped while it lies within half that spacing of the first: the ring closes there, and a
    near-duplicate (1.3e-4 mm apart at y = 39.75 mm on the 60 x 40 mm deep pocket of issue 29, "equal"
    to np.allclose but not identical) made the periodic spline refuse the ring.

    >>> ring = np.c_[np.cos(np.linspace(0, 2 * np.pi, 400)), np.sin(np.linspace(0, 2 * np.pi, 400))][:-1] * 40
    >>> ring = np.vstack([ring, ring[0] + [1.3e-4, 0.0]])          # a near-duplicate of the first point
    >>> p = thin_ring(ring, 1.0)
    >>> bool(np.hypot(*(p[-1] - p[0])) >= 0.5)
    True
    """
    pts = np.asarray(points, float)
    seg = np.hypot(*np.diff(np.vstack([pts, pts[:1]]), axis=0).T)
    keep = [0]
    acc = 0.0
    for i in range(1, len(pts)):
        acc += seg[i - 1]
        if acc >= min_spacing_mm:
            keep.append(i)
            acc = 0.0
    pts = pts[keep]
    while len(pts) > 4 and np.hypot(*(pts[-1] - pts[0])) < 0.5 * min_spacing_mm:
        pts = pts[:-1]
    return pts


def lap_start(contour, start_xy, tool_radius, spacing: float = 0.02):
    """Where a lap around ``contour`` begun with the tool centre at ``start_xy`` (mm) joins it.

    The contour is sampled every ``spacing`` of its parameter (at least 200 samples). Returns
    ``(t_nearest, d_nearest, t_join)``: the parameter of the sample nearest to ``start_xy``, its
    distance (mm), and the parameter of the last sample, going forward from the nearest one, that
    is still under the tool (within max(r, d_nearest) of ``start_xy``) — the lap continues from
    there, so it blends in from the previous one without a radial plunge.
    """
    T = contour.t_max - contour.t_min
    tt = np.linspace(contour.t_min, contour.t_max, max(int(T / spacing), 200), endpoint=False)
    d = np.hypot(*(contour.point(tt) - np.asarray(start_xy)).T)
    i = int(np.argmin(d))
    fwd = np.r_[i:len(tt), 0:i]
    run = d[fwd] <= max(tool_radius, d[i] + 1e-6)
    j = fwd[int(np.argmin(run)) - 1] if not run.all() else i
    return float(tt[i]), float(d[i]), float(tt[j])


def clamp_to_region(P, allowed_polygon):
    """Project path points (N, 2, mm) outside ``allowed_polygon`` onto its nearest boundary point
    (the final-contour limit): outer ring or island ring; a MultiPolygon works too. Points inside
    are unchanged; returns a new array.

    >>> from shapely.geometry import box
    >>> ring = box(0, 0, 10, 10).difference(box(4, 4, 6, 6))     # an island in the middle
    >>> clamp_to_region([[5.0, 4.5], [12.0, 5.0]], ring).round(6).tolist()
    [[5.0, 4.0], [10.0, 5.0]]
    """
    import shapely

    P = np.array(P, float)
    inside = shapely.contains_xy(allowed_polygon, P[:, 0], P[:, 1])
    if not inside.all():
        pts = shapely.points(P[~inside])
        best, dist = None, None
        for part in shapely.get_parts(allowed_polygon):
            for ring in (part.exterior, *part.interiors):
                proj = shapely.line_interpolate_point(ring, shapely.line_locate_point(ring, pts))
                d = shapely.distance(proj, pts)
                if best is None:
                    best, dist = proj, d
                else:
                    closer = d < dist
                    best, dist = np.where(closer, proj, best), np.where(closer, d, dist)
        P[~inside] = shapely.get_coordinates(best)
    return P


def clamp_chords(P, allowed_polygon, guard, max_rounds=6, return_inserted=False):
    """:func:`clamp_to_region`, then the chords: every segment that does not lie inside ``guard``
    (the centres allowed within a tolerance of the exact tool-centre region, e.g.
    :func:`cnclab.toolpath.pocket.period_guard`) gets its midpoint, clamped, inserted, up to
    ``max_rounds`` halvings. Two clamped points on the concave arc that the tool-centre region has
    around a reflex wall corner (radius rho) are joined by a chord ``s^2 / (8 rho)`` inside it: 0.9 um
    at s = 0.17 mm, r = 4 mm (the hybrid's centre lap in a 64 x 46 L, D8); a halving divides it by 4.
    Points (N, 2), mm; returns a new array (and, with ``return_inserted``, a boolean mask of the
    inserted points).

    >>> from shapely.geometry import Point, box
    >>> ring = box(-10, -10, 10, 10).difference(Point(0, 0).buffer(4.0, 64))   # around a round island
    >>> guard = box(-10, -10, 10, 10).difference(Point(0, 0).buffer(3.999, 64))
    >>> P = clamp_chords([[4.5, 0.0], [0.0, 4.5]], ring, guard)
    >>> bool(len(P) > 2 and np.hypot(*(0.5 * (P[1:] + P[:-1])).T).min() > 3.999)
    True
    """
    import shapely

    P = clamp_to_region(P, allowed_polygon)
    added = np.zeros(len(P), bool)
    shapely.prepare(guard)
    for _ in range(int(max_rounds)):
        moved = np.any(P[1:] != P[:-1], axis=1)           # a repeated point is no chord
        bad = moved & ~shapely.contains(guard, shapely.linestrings(np.stack([P[:-1], P[1:]], axis=1)))
        if not bad.any():
            break
        at = np.flatnonzero(bad) + 1
        P = np.insert(P, at, clamp_to_region(0.5 * (P[1:] + P[:-1])[bad], allowed_polygon), axis=0)
        added = np.insert(added, at, True)
    return (P, added) if return_inserted else P


@dataclasses.dataclass(frozen=True)
class LapSettings:
    """Settings of :func:`multi_pass` (lengths in mm, angles in deg, feed in mm/min).

    Attributes
    ----------
    dt : Thesis III contour-parameter step (mm of boundary).
    step_mm : spacing of the tool-centre samples (mm); None: twice the stock's dixel row height.
    method : the Thesis III direction rule of :func:`thesis3_path` (``"midpoint"`` ...).
    a_p : axial depth of the planning simulation (mm).
    feed_mm_min : feed of the planning simulation (mm/min).
    start_angle_deg : each lap starts at the contour point nearest the ray from the seed at this
        angle (deg, counter-clockwise from +x).

    >>> LapSettings(dt=0.1).method
    'midpoint'
    """
    dt: float = 0.2
    step_mm: float | None = None
    method: str = "midpoint"
    a_p: float = 1.0
    feed_mm_min: float = 1000.0
    start_angle_deg: float = 0.0


def multi_pass(stock, domain_polygon, final_polygon, seed_xy, tool_radius, theta_deg, n_passes,
               settings: LapSettings | None = None, **options):
    """Successive constant-engagement laps around a growing cleared region, limited by ``final_polygon``.

    After each lap the boundary is recomputed from the (dixel) ``stock`` (updated in place), the
    next lap is generated by :func:`thesis3_path` on it, and tool centres are kept inside
    ``final_polygon`` shrunk by r (so the tool never cuts beyond the final contour).
    ``settings`` (:class:`LapSettings`, default all defaults) holds the steps, the method, the planning
    cut and the start angle; ``options`` override any of its fields by name (e.g. ``dt=0.1``).
    Returns a list of dicts (path, table, removed area) per lap; stops early when nothing is removed.
    """
    o = dataclasses.replace(settings or LapSettings(), **options)
    dt, method, a_p, feed_mm_min, start_angle_deg = o.dt, o.method, o.a_p, o.feed_mm_min, o.start_angle_deg
    step_mm = o.step_mm
    r, _ = _check(tool_radius, theta_deg)
    step_mm = stock.resolution_mm * 2 if step_mm is None else step_mm
    allowed = final_polygon.buffer(-r)
    laps = []
    for k in range(int(n_passes)):
        contour = cleared_boundary_contour(stock, seed_xy, domain_polygon)
        # start the lap at the contour point nearest the ray from the seed at start_angle_deg
        tt = np.linspace(contour.t_min, contour.t_max, 721)[:-1]
        pts = contour.point(tt)
        ang = np.degrees(np.arctan2(pts[:, 1] - seed_xy[1], pts[:, 0] - seed_xy[0]))
        t0 = tt[np.argmin(np.abs((ang - start_angle_deg + 180) % 360 - 180))]
        shifted = ShiftedContour(contour, t0)
        path = thesis3_path(shifted, r, theta_deg, dt, method=method)
        P = clamp_to_region(resample_path(path.P, step_mm), allowed)
        df = simulate(stock, P, r, a_p, feed_mm_min)
        removed = float(df.removed_mm2.sum())
        laps.append({"path": P, "table": df, "removed_mm2": removed, "contour": shifted})
        if removed < 1e-9:
            break
    return laps


class ShiftedContour:
    """A closed contour re-parametrised to start at parameter ``t0`` (one full turn, t in [0, period))."""

    def __init__(self, base, t0):
        self.base, self.t0 = base, float(t0)
        self.t_min, self.t_max, self.closed = 0.0, base.t_max - base.t_min, True

    def _map(self, t):
        t = np.atleast_1d(np.asarray(t, float))
        return self.base.t_min + np.mod(t + self.t0 - self.base.t_min, self.t_max)

    def point(self, t):
        return self.base.point(self._map(t))

    def deriv(self, t):
        return self.base.deriv(self._map(t))
