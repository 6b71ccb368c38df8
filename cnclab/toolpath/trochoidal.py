"""Trochoidal slot-milling patterns: circular trochoid, cycloid and the constant-engagement pattern.

Jacsó (2021) §3.4, Thesis IV. A straight slot of width ``width`` (mm) runs along +X with its
centre line on y = 0; the tool (radius ``tool_radius`` r, mm — a *radius*) advances by the
trochoidal step ``step`` (mm) per period. The tool centre must stay in |y| <= W/2 - r (the
final-contour limit). All patterns are climb milling with a clockwise (M3) spindle: the uncut
material lies on the right of the feed direction, so circles run counter-clockwise.

Patterns (each returned as a :class:`TrochoidPath`: centre points, a per-point link flag, a period
index):

* **circular trochoid** — full circles of radius R = W/2 - r whose centres advance by ``step``; the
  transfer from one circle to the next is a straight move of length ``step`` at the rear point of
  the circle (circle-and-line trochoid; Otkur & Lazoglu, "Trochoidal milling", *Int. J. Mach. Tools
  Manuf.* 47 (2007) 1324-1332, Fig. 1; Rauch, Duc & Hascoët, *Int. J. Mach. Tools Manuf.* 49 (2009)
  375-383, "circular" pattern).
* **cycloid** — the prolate trochoid x = s phi / (2 pi) + R cos phi, y = R sin phi (the classical
  trochoid x = a phi - b sin phi, y = a - b cos phi of Weisstein, MathWorld "Trochoid", with
  a = s / 2pi, b = R, rotated a quarter turn), one period per 2 pi.
* **constant engagement** (Thesis IV) — per period the current front of the material is read from
  a dixel stock, the Thesis III algorithm (:func:`cnclab.toolpath.constant_engagement.thesis3_path`)
  generates the cut holding ``theta_deg`` along it from one wall to the other, the cut is clipped
  to the final-contour limit (roll-in/roll-out), the stock is cut, and a linking arc through the
  cleared region leads back to the next period. The period shape converges (booklet Fig. 3.5);
  :func:`ce_trochoid_iteration` returns every period and its change, :func:`ce_trochoid` repeats the
  converged period with the converged step.

Evaluation (:func:`evaluate_pattern`) cuts the pattern through a dixel slot stock and reports the
steady-state engagement trace, path length per period and per mm of slot, cutting vs linking
length and the average MRR; :func:`admissible_step` finds the largest step whose simulated maximum
engagement stays at ``theta_max_deg``.

Units: mm, mm/min, mm^3/min; angles in degrees at the API.

>>> p = circular_trochoid(step=1.0, width=12.0, tool_radius=3.0, n_periods=2, ds=0.1)
>>> round(p.length_per_period(), 2)          # 2 pi R + step = 2 pi 3 + 1
19.85
>>> c = cycloid(step=1.0, width=12.0, tool_radius=3.0, n_periods=1, ds=0.05)
>>> bool(abs(c.points[:, 1]).max() <= 3.0 + 1e-9)
True
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["TrochoidPath", "circular_trochoid", "cycloid", "slot_limit", "evaluate_pattern",
           "admissible_step", "front_contour", "linking_arc", "ce_period", "ce_trochoid_iteration",
           "ce_trochoid", "compare_patterns", "pattern_sweep", "max_engagement_circle_front", "circle_front_step"]


def _pos(name, v):
    v = float(v)
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"{name} must be a positive finite number, got {v!r}")
    return v


def slot_limit(width, tool_radius) -> float:
    """Largest |y| (mm) of the tool centre in a slot of width ``width`` (mm): W/2 - r.

    Raises ValueError naming ``width`` if the slot is not wider than the tool diameter 2r.

    >>> slot_limit(12.0, 3.0)
    3.0
    """
    W, r = _pos("width", width), _pos("tool_radius", tool_radius)
    if W <= 2 * r:
        raise ValueError(f"width must exceed the tool diameter 2*tool_radius = {2 * r} mm for a "
                         f"trochoidal slot, got {W}")
    return 0.5 * W - r


@dataclass
class TrochoidPath:
    """Tool-centre polyline (N, 2) mm; ``link[i]`` True when the segment ending at point i is a
    linking (non-cutting by design) move; ``period[i]`` the period index; ``step`` mm per period.

    ``arcs`` optionally lists linking arcs as (start_index, end_index, centre_xy, ccw) for G-code.
    """

    points: np.ndarray
    link: np.ndarray
    period: np.ndarray
    step: float
    kind: str = ""
    arcs: list = field(default_factory=list)

    def seg_lengths(self) -> np.ndarray:
        return np.r_[0.0, np.hypot(*np.diff(self.points, axis=0).T)]

    def lengths(self, periods=None) -> dict:
        """Cutting and linking length (mm), over all periods or the given period indices."""
        ds = self.seg_lengths()
        m = np.ones(len(ds), bool) if periods is None else np.isin(self.period, list(periods))
        return {"cut": float(ds[m & ~self.link].sum()), "link": float(ds[m & self.link].sum())}

    def length_per_period(self, k: int | None = None) -> float:
        """Path length (mm) of one period (default: the middle period)."""
        k = int(np.median(np.unique(self.period))) if k is None else k
        L = self.lengths([k])
        return L["cut"] + L["link"]


def circular_trochoid(step, width, tool_radius, n_periods, x0=0.0, ds=0.05) -> TrochoidPath:
    """Circle-and-line trochoid: ccw circles of radius W/2 - r, centres at x0 + k*step (mm).

    Each period starts at the circle's rear point (angle pi), runs one full circle and moves
    straight by ``step`` to the rear point of the next circle (that transfer is flagged as link).
    ``ds``: sampling distance along the path (mm).
    """
    s = _pos("step", step)
    R = slot_limit(width, tool_radius)
    n = int(n_periods)
    if n < 1:
        raise ValueError(f"n_periods must be >= 1, got {n_periods!r}")
    m = max(int(math.ceil(2 * math.pi * R / ds)), 16)
    phi = math.pi + np.linspace(0.0, 2 * math.pi, m + 1)
    pts, link, per = [], [], []
    for k in range(n):
        cx = x0 + k * s
        circ = np.c_[cx + R * np.cos(phi), R * np.sin(phi)]
        if k > 0:
            circ = circ[1:]
        pts.append(circ)
        link.append(np.zeros(len(circ), bool))
        per.append(np.full(len(circ), k))
        ml = max(int(math.ceil(s / ds)), 1)
        line = np.c_[cx - R + np.linspace(0, s, ml + 1)[1:], np.zeros(ml)]
        pts.append(line)
        link.append(np.ones(ml, bool))
        per.append(np.full(ml, k))
    return TrochoidPath(np.vstack(pts), np.concatenate(link), np.concatenate(per), s, "circular")


def cycloid(step, width, tool_radius, n_periods, x0=0.0, ds=0.05) -> TrochoidPath:
    """Prolate-trochoid path x = x0 + s phi/(2 pi) + R cos(phi), y = R sin(phi), R = W/2 - r (mm).

    One period per 2 pi, starting at the rear point phi = pi (so the pattern is comparable with
    :func:`circular_trochoid`); no linking moves (the rear half is an air cut at feed).
    """
    s = _pos("step", step)
    R = slot_limit(width, tool_radius)
    n = int(n_periods)
    if n < 1:
        raise ValueError(f"n_periods must be >= 1, got {n_periods!r}")
    m = max(int(math.ceil((2 * math.pi * R + s) / ds)), 16)
    phi = math.pi + np.linspace(0.0, 2 * math.pi * n, n * m + 1)
    pts = np.c_[x0 + s * (phi - math.pi) / (2 * math.pi) + R * np.cos(phi), R * np.sin(phi)]
    per = np.minimum(((phi - math.pi) // (2 * math.pi)).astype(int), n - 1)
    return TrochoidPath(pts, np.zeros(len(pts), bool), per, s, "cycloid")


def max_engagement_circle_front(step, width, tool_radius) -> float:
    """Exact engagement (deg) at the front point of a circular trochoid in steady state.

    The material ahead is bounded by the previous circle's envelope, a circle of radius R + r about
    the previous centre; the tool at the front point (distance d = R + step from it, feed along +y)
    engages psi in [0, alpha] with cos(alpha) = ((R + r)^2 - d^2 - r^2) / (2 d r).
    Used to check the simulator (the maximum over the period lies slightly after this point).

    >>> round(max_engagement_circle_front(circle_front_step(60.0, 12.0, 3.0), 12.0, 3.0), 6)
    60.0
    """
    R = slot_limit(width, tool_radius)
    r, s = float(tool_radius), _pos("step", step)
    d = R + s
    c = ((R + r) ** 2 - d * d - r * r) / (2 * d * r)
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


def circle_front_step(theta_deg, width, tool_radius) -> float:
    """Inverse of :func:`max_engagement_circle_front`: the step (mm) giving ``theta_deg`` at the front point.

    d = -r cos(theta) + sqrt((R + r)^2 - r^2 sin^2(theta)), step = d - R.

    >>> round(max_engagement_circle_front(circle_front_step(45.0, 15.0, 3.0), 15.0, 3.0), 9)
    45.0
    """
    R = slot_limit(width, tool_radius)
    r = float(tool_radius)
    th = math.radians(theta_deg)
    d = -r * math.cos(th) + math.sqrt((R + r) ** 2 - (r * math.sin(th)) ** 2)
    return d - R


# ---------------------------------------------------------------------------------------------
# simulation-based evaluation
# ---------------------------------------------------------------------------------------------
def _slot_stock(path: TrochoidPath, width, resolution_mm, x_start=0.0):
    from shapely.geometry import box

    from cnclab.simulation import dixel

    x_end = float(path.points[:, 0].max()) + 4 * float(width)
    return dixel.Stock.from_polygon(box(x_start, -0.5 * width, x_end, 0.5 * width), resolution_mm)


def evaluate_pattern(path: TrochoidPath, width, tool_radius, resolution_mm=0.05, a_p=3.0,
                     feed_mm_min=255.0, link_feed_mm_min=None, steady_periods=None, stock=None):
    """Cut ``path`` through a slot stock (material x >= 0) with the dixel simulator; steady-state metrics.

    Returns ``(table, metrics)``: the per-step DataFrame of :func:`cnclab.simulation.dixel.simulate`
    with ``period`` and ``link`` columns, and a dict over the ``steady_periods`` (default: all but
    the first two and the last) with ``max_engagement_deg``, ``step_mm``, ``length_per_period_mm``,
    ``length_per_mm_slot`` (path mm per mm of slot), ``cut_mm``/``link_mm`` per period,
    ``time_per_period_s``, ``mrr_avg_mm3_min`` (= a_p W step / time per period, the geometric
    steady-state removal), ``mrr_avg_sim_mm3_min`` (simulated removed area over the same time),
    ``link_removed_mm2`` (material cut by linking moves) and ``max_engagement_link_deg``: for the
    constant-engagement pattern the link's final approach along the wall is the roll-in into the
    corner left by the previous period and does cut (see the notebook discussion).
    Linking moves run at ``link_feed_mm_min`` (default: the cutting feed).
    """
    from cnclab.simulation import dixel

    r = _pos("tool_radius", tool_radius)
    W = _pos("width", width)
    st = _slot_stock(path, W, resolution_mm) if stock is None else stock
    df = dixel.simulate(st, path.points, r, a_p, feed_mm_min)
    df["period"] = path.period
    df["link"] = path.link
    periods = np.unique(path.period)
    if steady_periods is None:
        steady_periods = periods[2:-1] if len(periods) > 3 else periods[-1:]
    m = np.isin(path.period, list(steady_periods))
    vlink = feed_mm_min if link_feed_mm_min is None else link_feed_mm_min
    n_p = len(steady_periods)
    cut = float(df.ds[m & ~path.link].sum()) / n_p
    lnk = float(df.ds[m & path.link].sum()) / n_p
    t_min = cut / feed_mm_min + lnk / vlink
    removed = float(df.removed_mm2[m].sum()) / n_p
    eng = df.engagement_deg.to_numpy()
    metrics = {
        "max_engagement_deg": float(np.nanmax(eng[m & ~path.link])),
        "max_engagement_link_deg": float(np.nanmax(np.r_[0.0, eng[m & path.link]])),
        "step_mm": path.step,
        "cut_mm": cut, "link_mm": lnk,
        "length_per_period_mm": cut + lnk,
        "length_per_mm_slot": (cut + lnk) / path.step,
        "time_per_period_s": 60.0 * t_min,
        "mrr_avg_mm3_min": a_p * W * path.step / t_min,
        "mrr_avg_sim_mm3_min": a_p * removed / t_min,
        "link_removed_mm2": float(df.removed_mm2[m & path.link].sum()) / n_p,
        "engaged_share": float(np.mean(eng[m] > 1.0)),
    }
    return df, metrics


def admissible_step(pattern, theta_max_deg, width, tool_radius, resolution_mm=0.05, n_periods=5,
                    tol_mm=0.01, s_max=None):
    """Largest trochoidal step (mm) of ``pattern`` ("circular" or "cycloid") whose simulated
    steady-state maximum engagement does not exceed ``theta_max_deg`` (bisection on the step).

    The maximum engagement grows monotonically with the step (the material ahead grows).
    """
    gen = {"circular": circular_trochoid, "cycloid": cycloid}.get(pattern)
    if gen is None:
        raise ValueError(f"pattern must be 'circular' or 'cycloid', got {pattern!r}")
    if not 0 < theta_max_deg <= 180:
        raise ValueError(f"theta_max_deg must be in (0, 180], got {theta_max_deg!r}")
    r = _pos("tool_radius", tool_radius)
    slot_limit(width, r)
    ds = resolution_mm

    def emax(s):
        p = gen(s, width, r, n_periods, ds=ds)
        return evaluate_pattern(p, width, r, resolution_mm)[1]["max_engagement_deg"]

    # bracket: the exact front-point step of the circle (a lower bound of the maximum engagement)
    s_front = circle_front_step(theta_max_deg, width, r)
    hi = 1.5 * s_front if s_max is None else s_max
    lo = 0.5 * s_front
    while emax(lo) > theta_max_deg:
        hi, lo = lo, 0.5 * lo
        if lo < tol_mm:
            raise ValueError(f"theta_max_deg={theta_max_deg} is below the engagement of the smallest step")
    while hi - lo > tol_mm:
        mid = 0.5 * (lo + hi)
        if emax(mid) <= theta_max_deg:
            lo = mid
        else:
            hi = mid
    return lo


# ---------------------------------------------------------------------------------------------
# constant-engagement pattern (Thesis IV)
# ---------------------------------------------------------------------------------------------
def front_contour(stock, x_min=-math.inf, every_rows=3, min_points=6):
    """Front of the material (smallest x of material per row, x >= ``x_min``) as an open spline
    contour traversed from the lowest to the highest row: material on the right (Thesis II).

    Returns a :class:`~cnclab.geometry.contours.SplineContour`, or None when fewer than
    ``min_points`` rows hold material.
    """
    from cnclab.geometry.contours import SplineContour

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


def ce_period(stock, tool_radius, theta_deg, allowed, dt=0.1, step_mm=0.05, x_min=-math.inf):
    """One constant-engagement cut (Thesis III along the current front), clipped to ``allowed``.

    ``allowed``: shapely polygon of admissible tool-centre positions (final contour shrunk by r).
    The raw Thesis III path starts where the tool touches the lowest front point; the part of it
    outside ``allowed`` is cut off and both ends are moved onto the boundary of ``allowed`` (the
    roll-in and roll-out). Returns the (n, 2) centre points resampled every ``step_mm``, or None
    when the front is gone or the path never enters ``allowed``.
    """
    import shapely

    from .constant_engagement import resample_path, thesis3_path

    c = front_contour(stock, x_min=x_min)
    if c is None or c.t_max < 2 * stock.resolution_mm:
        return None
    try:
        res = thesis3_path(c, tool_radius, theta_deg, dt, method="midpoint")
    except ValueError:
        res = thesis3_path(c, tool_radius, theta_deg, dt, method="midpoint", adaptive=True)
    P = res.P
    inside = shapely.contains_xy(allowed, P[:, 0], P[:, 1])
    run = _clip_run(P, inside)
    if run is None:
        return None
    i0, i1 = run
    Q = P[i0:i1 + 1]
    ring = allowed.exterior
    ends = []
    for k_out, k_in in ((i0 - 1, i0), (i1 + 1, i1)):
        if 0 <= k_out < len(P):
            seg = shapely.LineString([P[k_in], P[k_out]])
            x = seg.intersection(ring)
            pts = shapely.get_coordinates(x)
            if len(pts):
                j = int(np.argmin(np.hypot(*(pts - P[k_in]).T)))
                ends.append(pts[j])
                continue
        ends.append(None)
    if ends[0] is not None:
        Q = np.vstack([ends[0], Q])
    if ends[1] is not None:
        Q = np.vstack([Q, ends[1]])
    if len(Q) < 2:
        return None
    return resample_path(Q, step_mm, spline=len(Q) >= 4)


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
        from .constant_engagement import clamp_to_region

        q = clamp_to_region(pts, allowed)
        if not np.allclose(q, pts):
            return q, None, ccw
    return pts, C, ccw


@dataclass
class CEIteration:
    """Periods of the constant-engagement iteration (Fig. 3.5) and their convergence."""

    cuts: list
    table: object          # pandas DataFrame: period, shift_mm, shape_change_mm, cut_mm, removed_mm2
    stock: object


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


def ce_trochoid_iteration(width, tool_radius, theta_deg, n_periods=8, resolution_mm=0.05,
                          dt=0.1, a_p=3.0, feed_mm_min=255.0, x_front0=0.0):
    """Thesis IV iteration: cut period after period into a straight slot (front at ``x_front0``).

    Per period the front is recomputed from the dixel stock, the Thesis III cut is generated and
    simulated (stock updated). Returns :class:`CEIteration` with the cut polylines and a table of
    shift (the trochoidal step between consecutive periods, mm) and shape change (max residual
    after removing the shift, mm): the iteration converges when the shape change stops changing.
    """
    import pandas as pd
    from shapely.geometry import box

    from cnclab.simulation import dixel

    r = _pos("tool_radius", tool_radius)
    yl = slot_limit(width, r)
    W = float(width)
    length = x_front0 + (n_periods + 2) * 2 * r + 4 * r
    st = dixel.Stock.from_polygon(box(x_front0, -W / 2, length, W / 2), resolution_mm)
    allowed = box(x_front0 - 10 * W, -yl, length + 10 * W, yl)
    cuts, rows = [], []
    for k in range(int(n_periods)):
        P = ce_period(st, r, theta_deg, allowed, dt=dt, step_mm=resolution_mm)
        if P is None:
            break
        df = dixel.simulate(st, P, r, a_p, feed_mm_min)
        shift, change = (math.nan, math.nan) if not cuts else _shape_change(cuts[-1], P)
        cuts.append(P)
        rows.append({"period": k, "shift_mm": shift, "shape_change_mm": change,
                     "cut_mm": float(df.ds.sum()), "removed_mm2": float(df.removed_mm2.sum()),
                     "max_engagement_deg": float(np.nanmax(df.engagement_deg))})
    return CEIteration(cuts, pd.DataFrame(rows), st)


def ce_trochoid(width, tool_radius, theta_deg, n_periods=6, resolution_mm=0.05, dt=0.1,
                n_iter=8, link_bulge=0.5, iteration: CEIteration | None = None) -> TrochoidPath:
    """Repetitive constant-engagement pattern: the last (converged) period of
    :func:`ce_trochoid_iteration` repeated ``n_periods`` times with the converged step, each cut
    followed by a linking arc (:func:`linking_arc`, flagged link) to the next cut's start.
    """
    it = iteration or ce_trochoid_iteration(width, tool_radius, theta_deg, n_iter, resolution_mm, dt)
    if len(it.cuts) < 3:
        raise ValueError("the constant-engagement iteration produced fewer than 3 periods")
    cut = it.cuts[-1]
    step = float(it.table.shift_mm.iloc[-1])
    if not step > 0:
        raise ValueError(f"non-positive converged step {step}")
    cut = cut - np.array([cut[:, 0].min(), 0.0])
    pts, link, per, arcs = [], [], [], []
    n = 0
    for k in range(int(n_periods)):
        C = cut + np.array([k * step, 0.0])
        if k > 0:
            C = C[1:]
        pts.append(C)
        link.append(np.zeros(len(C), bool))
        per.append(np.full(len(C), k))
        n += len(C)
        E, S = C[-1], cut[0] + np.array([(k + 1) * step, 0.0])
        A, centre, ccw = linking_arc(E, S, bulge=link_bulge, ds=resolution_mm)
        if centre is not None:
            arcs.append((n - 1, n - 1 + len(A) - 1, centre, ccw))
        pts.append(A[1:])
        link.append(np.ones(len(A) - 1, bool))
        per.append(np.full(len(A) - 1, k))
        n += len(A) - 1
    return TrochoidPath(np.vstack(pts), np.concatenate(link), np.concatenate(per), step,
                        "constant-engagement", arcs)


def compare_patterns(width, tool_radius, theta_max_deg, resolution_mm=0.05, a_p=3.0,
                     feed_mm_min=255.0, link_feed_mm_min=None, n_periods=6):
    """The three patterns at the same engagement limit: admissible step, lengths, MRR (one row each).

    Circular and cycloid steps come from :func:`admissible_step`; the constant-engagement pattern
    uses ``theta_deg = theta_max_deg`` and its converged step. Returns a pandas DataFrame.
    """
    import pandas as pd

    rows = []
    for kind in ("circular", "cycloid"):
        s = admissible_step(kind, theta_max_deg, width, tool_radius, resolution_mm)
        gen = circular_trochoid if kind == "circular" else cycloid
        p = gen(s, width, tool_radius, n_periods, ds=resolution_mm)
        _, m = evaluate_pattern(p, width, tool_radius, resolution_mm, a_p, feed_mm_min, link_feed_mm_min)
        rows.append({"pattern": kind, **m})
    p = ce_trochoid(width, tool_radius, theta_max_deg, n_periods, resolution_mm)
    _, m = evaluate_pattern(p, width, tool_radius, resolution_mm, a_p, feed_mm_min, link_feed_mm_min)
    rows.append({"pattern": "constant-engagement", **m})
    df = pd.DataFrame(rows).set_index("pattern")
    df["mrr_gain_vs_circular_pct"] = 100 * (df.mrr_avg_mm3_min / df.loc["circular", "mrr_avg_mm3_min"] - 1)
    df["mrr_gain_vs_cycloid_pct"] = 100 * (df.mrr_avg_mm3_min / df.loc["cycloid", "mrr_avg_mm3_min"] - 1)
    return df


def pattern_sweep(width_over_r, theta_max_deg, tool_radius=3.0, resolution_mm=0.05, **kw):
    """:func:`compare_patterns` over a grid of W/r and theta_max; one row per (W/r, theta, pattern)."""
    import pandas as pd

    out = []
    for wr in width_over_r:
        for th in theta_max_deg:
            df = compare_patterns(wr * tool_radius, tool_radius, th, resolution_mm, **kw).reset_index()
            df.insert(0, "theta_max_deg", th)
            df.insert(0, "W_over_r", wr)
            out.append(df)
    return pd.concat(out, ignore_index=True)
