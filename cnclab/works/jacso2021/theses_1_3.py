"""Claim recipes for Jacsó (2021) §2.2 and Theses I–III, and Kim & Yang (2006) eq. 1.

The booklet (seed ``000_690a1ed8f09fd780.txt``) prints relations, not tables; each recipe evaluates
a relation as an identity (residual 0) or checks a numeric instance by simulation. The instance
parameters follow the booklet's experiments (Table 4.1): tool Ø6 mm (r = 3 mm), theta = 60 deg.
"""
from __future__ import annotations

import functools
import math

import numpy as np

from cnclab.geometry import engagement as eng
from cnclab.geometry.contours import Arc, Blob
from cnclab.toolpath import constant_engagement as ce
from cnclab.cache import cached
from cnclab.simulation import dixel, pixel

R_TOOL = 3.0          # mm, Ø6 mm tool of Table 4.1
THETA = 60.0          # deg, engagement angle of Table 4.1
THETA_GRID = np.linspace(1.0, 180.0, 359)
RHO_GRID = np.array([3.5, 4.0, 6.0, 8.0, 12.0, 25.0, 100.0])


# ---------------------------------------------------------------- Thesis I (identities) -----
def _inverse_residual(kind, k=None):
    res = 0.0
    for rho in RHO_GRID:
        th = THETA_GRID[eng.rho_min(THETA_GRID, R_TOOL) <= rho]
        s = eng.stepover_thesis1(th, rho, R_TOOL, kind, k=k)
        res = max(res, float(np.max(np.abs(eng.theta_arc(s, rho, R_TOOL, kind) - th))))
    return res


def thesis1_concave_inverse_residual() -> float:
    """max |theta_concave(s_I(theta, rho), rho) - theta| (deg) over theta in [1, 180], rho grid."""
    return _inverse_residual("concave")


def thesis1_convex_inverse_residual() -> float:
    """Same for convex arcs."""
    return _inverse_residual("convex")


def _k_that_inverts(kind):
    best = None
    for k in (-1, 1):
        try:
            r = _inverse_residual(kind, k=k)
        except ValueError:        # the other sign leaves [0, 2r] or the acos domain
            r = math.inf
        if best is None or r < best[1]:
            best = (k, r)
    return float(best[0])


def thesis1_inverse_residual_with_k(kind: str, k: float) -> float:
    """max |theta_kind(s_I(theta, rho; k), rho) - theta| (deg) of Thesis I with the sign ``k`` given
    (``inf`` when that sign leaves the stepover range [0, 2r] or the arccos domain)."""
    try:
        return _inverse_residual(kind, k=k)
    except ValueError:
        return math.inf


def thesis1_k_concave() -> float:
    """The sign k for which Thesis I inverts the concave cosine-theorem relation."""
    return _k_that_inverts("concave")


def thesis1_k_convex() -> float:
    """The sign k for which Thesis I inverts the convex cosine-theorem relation."""
    return _k_that_inverts("convex")


def thesis1_straight_limit_residual() -> float:
    """max |s_I(theta, rho=1e7) - r(1 - cos theta)| (mm), both k: Thesis I tends to the line formula."""
    out = 0.0
    for kind in ("concave", "convex"):
        s = eng.stepover_thesis1(THETA_GRID, 1e7, R_TOOL, kind)
        out = max(out, float(np.max(np.abs(s - R_TOOL * (1 - np.cos(np.radians(THETA_GRID)))))))
    return out


def thesis1_s_at_180_over_r() -> float:
    """s(180 deg, rho)/r for both arc types on the rho grid (max): the upper bound s = 2r."""
    return float(max(np.max(eng.stepover_thesis1(180.0, RHO_GRID, R_TOOL, kind)) for kind in
                     ("concave", "convex")) / R_TOOL)


# ---------------------------------------------------------------- Thesis I (simulation) ----
@functools.cache
def simulated_constant_curvature(kind: str, resolution_mm: float = 0.02, rho: float = 8.0) -> float:
    """Mean dixel-simulated engagement (deg) when cutting with the Thesis I stepover for theta = 60.

    ``kind``: "straight" (30 deg oblique cut of a half plane), "concave" (widening a circular hole
    of radius rho) or "convex" (turning down a disk of radius rho). Steady part of the pass only;
    feed direction = the path tangent (central difference; the backward chord would lag it by half a
    step's turning angle, ~0.09 deg on the concave arc at 0.02 mm steps).
    """
    from shapely import affinity
    from shapely.geometry import Point, box

    r, h = R_TOOL, resolution_mm
    s = float(eng.stepover_thesis1(THETA, rho, r, kind))
    if kind == "straight":
        ang = math.radians(30.0)
        poly = affinity.rotate(box(-30, -30, 30, 0), 30.0, origin=(0, 0))
        u, nrm = np.array([math.cos(ang), math.sin(ang)]), np.array([-math.sin(ang), math.cos(ang)])
        lam = np.arange(-12.0, 12.0, h)
        P = lam[:, None] * u + (r - s) * nrm            # material on the right of the feed
        lo, hi = len(P) // 3, 2 * len(P) // 3
    else:
        if kind == "concave":
            poly = box(-20, -20, 20, 20).difference(Point(0, 0).buffer(rho, quad_segs=512))
            d, sign = rho + s - r, 1.0
        else:
            poly = Point(0, 0).buffer(rho, quad_segs=512)
            d, sign = rho - s + r, -1.0
        n = int(math.radians(150) * d / h)
        phi = sign * np.linspace(0, math.radians(150), n)
        P = np.c_[d * np.cos(phi), d * np.sin(phi)]
        lo, hi = n // 3, n
    st = dixel.Stock.from_polygon(poly, h)
    df = dixel.simulate(st, P, r, 1.0, 1000.0, feed_direction="central")
    return float(df.engagement_deg.values[lo:hi - 1].mean())


def sim_straight_theta60() -> float:
    return simulated_constant_curvature("straight")


def sim_concave_theta60() -> float:
    return simulated_constant_curvature("concave")


def sim_convex_theta60() -> float:
    return simulated_constant_curvature("convex")


# ---------------------------------------------------------------- Thesis II / III -----------
def _ccw_angle(a, b) -> float:
    """Signed ccw angle (deg) from vector a to vector b, in (-180, 180]."""
    return math.degrees(math.atan2(a[0] * b[1] - a[1] * b[0], a @ b))


def thesis2_rotation_cp_to_feed() -> float:
    """Signed (ccw) angle from CP to the feed direction implied by the Thesis II equation (deg)."""
    C = np.array([0.0, 0.0])
    P = np.array([0.3, 2.9])
    P = C + R_TOOL * P / np.hypot(*P)
    v = ce.thesis2_feed_direction(P, C, THETA)
    return _ccw_angle(P - C, v)


def thesis2_rotation_prose_clockwise() -> float:
    """The prose's beta read as a clockwise rotation: the magnitude of the equation's angle."""
    return abs(thesis2_rotation_cp_to_feed())


def thesis3_alpha_from_thesis2() -> float:
    """ccw angle (deg) from P_iC_i to the Thesis II feed direction: must equal alpha = pi/2 - theta."""
    C = np.array([0.0, 0.0])
    P = np.array([-1.2, 2.0])
    P = C + R_TOOL * P / np.hypot(*P)
    return _ccw_angle(C - P, ce.thesis2_feed_direction(P, C, THETA))


def thesis2_ivp_arc_radius_residual() -> float:
    """max ||p(t) - O| - (rho + s_I - r)| (mm) for the Thesis II IVP on a concave arc (rho = 8 mm)."""
    arc = Arc((0, 0), 8.0, 0, 300)
    P0, d = ce.arc_start_point(arc, R_TOOL, THETA, "concave")
    sol = ce.thesis2_ivp(arc, R_TOOL, THETA, P0=P0)
    return float(np.max(np.abs(np.hypot(*sol.P.T) - d)))


@functools.cache
@cached()
def blob_engagement_stats(resolution_mm: float = 0.02, dt: float = 0.05, method: str = "midpoint"):
    """Engagement statistics (deg) along a Thesis III path on a smooth blob (R0 = 10 mm), dixel-simulated."""
    from shapely.geometry import Polygon, box

    blob = Blob((0, 0), 10.0)
    res = ce.thesis3_path(blob, R_TOOL, THETA, dt, method=method)
    P = ce.resample_path(res.P, resolution_mm)
    stock = box(-25, -25, 25, 25).difference(Polygon(blob.sample(4000)))
    df = ce.engagement_along_path(stock, P, R_TOOL, resolution_mm, feed_direction="central")
    return ce.deviation_stats(df.engagement_deg, THETA, skip_mm=3.0, s_mm=df.s, end_skip_mm=12.0)


def blob_mean_engagement_coarse() -> float:
    """Mean engagement (deg), 0.05 mm rows, midpoint dt = 0.05 (path error O(dt^2): -0.23 deg at dt = 0.1)."""
    return blob_engagement_stats(0.05, 0.05)["mean_deg"]


def blob_max_deviation_fine() -> float:
    return blob_engagement_stats(0.01, 0.05)["max_dev_deg"]


# ---------------------------------------------------------------- §2.2 dixel vs pixel ------
def disk_cost_counts(resolutions=(0.2, 0.1, 0.05, 0.02, 0.01), r=R_TOOL):
    """Data touched by one disk cut vs resolution: dixel rows and pixels (deterministic counts)."""
    rows = np.array([math.ceil(2 * r / h) for h in resolutions], float)
    pix = np.array([math.ceil(2 * r / h) ** 2 for h in resolutions], float)
    return np.asarray(resolutions, float), rows, pix


def _exponent(h, n):
    return float(-np.polyfit(np.log(h), np.log(n), 1)[0])


def dixel_data_exponent() -> float:
    """Fitted exponent k of (elements touched per disk cut) ~ resolution^-k, dixel model (rows of the stock)."""
    from shapely.geometry import box

    hs = np.array([0.2, 0.1, 0.05, 0.02, 0.01])
    n = []
    for h in hs:
        st = dixel.Stock.from_polygon(box(0, 0, 10, 10), h)
        j, _ = st.disk_halfwidths(5.0, R_TOOL)
        n.append(j.size)
    return _exponent(hs, np.array(n, float))


def pixel_data_exponent() -> float:
    """Same for the pixel model (pixels whose centres fall in the disk)."""
    from shapely.geometry import box

    hs = np.array([0.2, 0.1, 0.05, 0.02, 0.01])
    n = []
    for h in hs:
        st = pixel.Stock.from_polygon(box(0, 0, 10, 10), h)
        n.append(st.cut_disk_pixels((5.0, 5.0), R_TOOL))
    return _exponent(hs, np.array(n, float))


def dixel_disk_area_ratio() -> float:
    """Modelled dixel disk area / (pi r^2) at a coarse 0.25 mm resolution (exact by construction)."""
    from shapely.geometry import box

    st = dixel.Stock.from_polygon(box(0, 0, 10, 10), 0.25)
    return st.cut_disk((5.0, 5.13), R_TOOL) / (math.pi * R_TOOL ** 2)


def accuracy_cases(step_mm: float = 0.02, sweep_deg: float = 60.0, s: float = 1.5, rho: float = 8.0):
    """Cuts with a closed-form engagement, shared by the accuracy study and the dixel/pixel benchmark.

    Returns a list of ``(name, stock polygon, centres (N, 2) mm, theta_deg)``: a concave arc
    (widening a ``rho`` hole), a convex arc (turning a ``rho`` disk) -- both with stepover ``s``,
    theta from §3.1 -- and a straight cut oblique to the rows (25 deg), theta = arccos(1 - s/r).
    Tool r = 3 mm, tool step ``step_mm``; stocks cropped to the region the cut reaches.
    """
    from shapely import affinity
    from shapely.geometry import Point, box

    r = R_TOOL
    out = []
    hole = Point(0, 0).buffer(rho, quad_segs=512)
    d = rho + s - r
    phi = np.linspace(0, math.radians(sweep_deg), int(math.radians(sweep_deg) * d / step_mm) + 1)
    out.append(("concave", box(-1, -r - 1, rho + s + 1, rho + s + 1).difference(hole),
                np.c_[d * np.cos(phi), d * np.sin(phi)], float(eng.theta_concave(s, rho, r))))
    d = rho - s + r
    phi = -np.linspace(0, math.radians(sweep_deg), int(math.radians(sweep_deg) * d / step_mm) + 1)
    out.append(("convex", hole.intersection(box(-1, -rho - 1, rho + 1, r + 1)),
                np.c_[d * np.cos(phi), d * np.sin(phi)], float(eng.theta_convex(s, rho, r))))
    ang = math.radians(25.0)
    u, nrm = np.array([math.cos(ang), math.sin(ang)]), np.array([-math.sin(ang), math.cos(ang)])
    lam = np.arange(-3.0, 4.0 + 1e-9, step_mm)
    poly = affinity.rotate(box(-7, -4, 8, 0), 25.0, origin=(0, 0))
    out.append(("straight25", poly, lam[:, None] * u + (r - s) * nrm, float(eng.theta_straight(s, r))))
    return out


def engagement_error(model: str, case, resolution_mm: float, feed_direction: str = "central"):
    """Simulated minus closed-form engagement (deg) over the second half of an :func:`accuracy_cases` cut.

    ``model``: "dixel" or "pixel". The last step is excluded (no central difference there).
    Returns ``(errors array, per-step DataFrame)``.
    """
    mod = {"dixel": dixel, "pixel": pixel}[model]
    _, poly, P, th = case
    df = mod.simulate(mod.Stock.from_polygon(poly, resolution_mm), P, R_TOOL, 1.0, 1000.0,
                      feed_direction=feed_direction)
    return df.engagement_deg.values[len(P) // 2:-1] - th, df


def accuracy_table(resolutions=(0.1, 0.05, 0.02, 0.01), models=("dixel", "pixel"),
                   feed_directions=("central", "backward")):
    """Max |engagement error| (deg) per model, feed direction, resolution (mm) and case (DataFrame)."""
    import pandas as pd

    rows = []
    for case in accuracy_cases():
        for m in models:
            for fd in feed_directions:
                for h in resolutions:
                    e, _ = engagement_error(m, case, h, fd)
                    rows.append({"case": case[0], "model": m, "feed_direction": fd, "h_mm": h,
                                 "mean_err_deg": float(e.mean()), "max_abs_err_deg": float(np.abs(e).max())})
    return pd.DataFrame(rows)


# ---------------------------------------------------------------- Kim & Yang eq. 1 ---------
def kim_yang_eq1_equivalence_residual() -> float:
    """max |eq.1(R = rho + s, r, s) - theta_concave(s, rho, r)| (deg) on a grid of (s, rho)."""
    s = np.linspace(0.01, 2 * R_TOOL, 120)
    out = 0.0
    for rho in RHO_GRID:
        ok = (rho + s - R_TOOL > 0)
        c = (rho * rho - (rho + s - R_TOOL) ** 2 - R_TOOL ** 2) / (2 * R_TOOL * (rho + s - R_TOOL))
        ok &= np.abs(c) <= 1
        a = eng.theta_kim_yang(s[ok], rho + s[ok], R_TOOL)
        b = eng.theta_concave(s[ok], rho, R_TOOL)
        out = max(out, float(np.max(np.abs(a - b))))
    return out


def kim_yang_eq1_straight_limit_residual() -> float:
    """max |eq.1(R = 1e7) - arccos(1 - s/r)| (deg): eq. 1 tends to the line formula iff r = tool radius."""
    s = np.linspace(0.01, 2 * R_TOOL, 120)
    return float(np.max(np.abs(eng.theta_kim_yang(s, 1e7, R_TOOL) - eng.theta_straight(s, R_TOOL))))


def kim_yang_eq1_thesis1_roundtrip() -> float:
    """max |eq.1(R = rho + s_I, r, s_I) - theta| (deg): Thesis I stepovers fed to eq. 1 return theta."""
    out = 0.0
    for rho in RHO_GRID:
        th = THETA_GRID[(eng.rho_min(THETA_GRID, R_TOOL) <= rho) & (THETA_GRID < 180)]
        s = eng.stepover_thesis1(th, rho, R_TOOL, "concave")
        ok = rho + s > R_TOOL
        out = max(out, float(np.max(np.abs(eng.theta_kim_yang(s[ok], rho + s[ok], R_TOOL) - th[ok]))))
    return out
