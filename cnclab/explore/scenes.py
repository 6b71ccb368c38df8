"""Pure functions behind the explorers: each returns the data one explorer draws (no widgets here).

Every function takes the explorer's control values (units in the parameter names), calls the
package's own models (never a copy of them) and returns a plain ``dict`` of numbers and arrays.
Out-of-range values raise the package's own ``ValueError`` unchanged, so an explorer shows exactly
the message the package gives. Angles in **degrees**, lengths in **mm**.

>>> sc = thesis1_scene(1.5, 8.0, 3.0, "concave")
>>> round(sc["theta_deg"], 6) == round(sc["drawn_theta_deg"], 6)
True
"""
from __future__ import annotations

import functools
import math

import numpy as np
from shapely import affinity
from shapely.geometry import Polygon, box

from ..cutting import scallop_volume as sv
from ..cutting.roughness import ideal_cusp_profile, profile_parameters
from ..geometry import ball_end, cusp, engagement
from ..geometry.contours import Blob, Ellipse, SplineContour
from ..simulation import pixel
from ..toolpath import constant_engagement as ce
from ..toolpath import constant_mrr as cm
from ..toolpath import offsets, trochoidal
from ..works.kim_yang2006 import constant_mrr_pocket as ky_pocket
from ..works.mgherony2024 import ch7_9

__all__ = ["thesis1_scene", "thesis1_curves", "CE_CONTOURS", "ce_contour", "ce_growth_scene",
           "TROCHOID_PATTERNS", "trochoid_scene", "kim_yang_scene", "hoang_scene",
           "working_diameter_scene", "cusp_scene", "spindle_scene"]


# ------------------------------------------------------------------------------------ Thesis I
def _angle_deg(u, v) -> float:
    """Unsigned angle (deg) between 2D vectors u and v."""
    return math.degrees(math.atan2(abs(u[0] * v[1] - u[1] * v[0]), u[0] * v[0] + u[1] * v[1]))


def _circle_intersection_upper(r0, P, r):
    """Intersection with y >= 0 of the circle |x| = r0 (centre O = 0) and the circle |x - P| = r, P on +x."""
    d = float(P[0])
    a = (d * d + r0 * r0 - r * r) / (2 * d)          # x of the radical line
    h2 = r0 * r0 - a * a
    if h2 < -1e-12:
        raise ValueError("the tool circle does not meet the previous contour")
    return np.array([a, math.sqrt(max(h2, 0.0))])


def thesis1_scene(stepover_mm, rho_mm, tool_radius_mm, kind, n=121):
    """Drawing data of Thesis I: tool, previous/new contour, engaged arc, all to scale (mm, deg).

    The engagement angle ``theta_deg`` comes from :func:`cnclab.geometry.engagement.theta_arc`; the
    drawn engaged arc is built independently (circle-circle or circle-line intersection of the tool
    with the previous contour) and ``drawn_theta_deg`` is the angle it subtends at the tool centre,
    so the two agree exactly when the formula is right. The feed runs along +y; the tool centre
    ``P`` lies on the +x axis (``O`` = arc centre at the origin; straight: the walls are x = const).
    ``s_thesis1_mm`` is Thesis I's stepover for that angle (None where Thesis I has no root).

    >>> sc = thesis1_scene(3.0, 1e3, 3.0, "straight")
    >>> round(sc["theta_deg"], 9), round(sc["drawn_theta_deg"], 9)
    (90.0, 90.0)
    """
    s, rho, r = float(stepover_mm), float(rho_mm), float(tool_radius_mm)
    theta = float(engagement.theta_arc(s, rho, r, kind))
    L = 3.0 * r
    if kind == "straight":
        P = np.array([0.0, 0.0])
        Q = P + [r, 0.0]                                   # touch point on the new wall x = r
        c = r - s
        C = np.array([c, math.sqrt(max(r * r - c * c, 0.0))])
        y = np.linspace(-L, L, 2)
        previous, new = np.c_[np.full(2, c), y], np.c_[np.full(2, r), y]
    else:
        sign = 1.0 if kind == "concave" else -1.0
        P = np.array([rho + sign * (s - r), 0.0])
        Q = P + [sign * r, 0.0]
        C = _circle_intersection_upper(rho, P, r)
        span = min(math.pi, L / max(rho, 1e-9) + 0.3)
        phi = np.linspace(-span, span, n)
        previous = rho * np.c_[np.cos(phi), np.sin(phi)]
        new = (rho + sign * s) * np.c_[np.cos(phi), np.sin(phi)]
    a0 = math.atan2(*(Q - P)[::-1])
    a1 = math.atan2(*(C - P)[::-1])
    sweep = (a1 - a0 + math.pi) % (2 * math.pi) - math.pi       # shortest signed sweep
    psi = a0 + np.linspace(0.0, sweep, n)
    arc = P + r * np.c_[np.cos(psi), np.sin(psi)]
    t = np.linspace(0, 2 * math.pi, 181)
    try:
        s1 = float(engagement.stepover_thesis1(theta, rho, r, kind))
    except ValueError:
        s1 = None
    return {"kind": kind, "stepover_mm": s, "rho_mm": rho, "tool_radius_mm": r, "theta_deg": theta,
            "drawn_theta_deg": _angle_deg(Q - P, C - P), "tool_centre": P, "touch_point": Q,
            "contact_point": C, "engaged_arc": arc, "tool_circle": P + r * np.c_[np.cos(t), np.sin(t)],
            "previous_contour": previous, "new_contour": new, "s_thesis1_mm": s1}


def thesis1_curves(rho_mm, tool_radius_mm, n=121):
    """Engagement (deg) vs stepover s in [0, 2r] (mm) for the three kinds; NaN where undefined."""
    r = float(tool_radius_mm)
    s = np.linspace(0.0, 2 * r, n)
    out = {"s_mm": s}
    for kind in ("straight", "concave", "convex"):
        th = np.full(n, np.nan)
        for i, si in enumerate(s):
            try:
                th[i] = float(engagement.theta_arc(si, rho_mm, r, kind))
            except ValueError:
                pass
        out[kind] = th
    return out


# ------------------------------------------------------------------------- Thesis III / IV
#: Contours the reader can pick for the constant-engagement path (material on the right = outside).
CE_CONTOURS = ("ellipse", "spline", "star")


@functools.cache
def ce_contour(name: str):
    """``(contour, dt)``: the ellipse 12 x 8 mm, a closed spline, or a 5-lobed star (Blob), and a
    Thesis III step ``dt`` in the contour's parameter (rad for ellipse/star, mm for the spline)."""
    if name == "ellipse":
        return Ellipse((0, 0), 12, 8), 0.04
    if name == "spline":
        tk = np.linspace(0, 2 * np.pi, 9)[:-1]
        return SplineContour(np.c_[10 * np.cos(tk), 8 * np.sin(tk) + np.sin(2 * tk)], closed=True), 0.4
    if name == "star":
        return Blob((0, 0), 11.0, amplitudes=(0, 0, 0, 0, 0.18), phases=(0, 0, 0, 0, 0)), 0.03
    raise ValueError(f"contour must be one of {CE_CONTOURS}, got {name!r}")


def ce_growth_scene(contour, theta_deg, tool_radius_mm, progress, resolution_mm=0.1):
    """Thesis III path growing along ``contour`` up to ``progress`` in (0, 1] of its parameter, and
    its engagement simulated in the dixel model (``resolution_mm`` rows, central feed direction).

    Returns the contour polyline, the path points ``P`` and contact points ``C`` (mm), the simulated
    ``engagement_deg`` per path point and the path length ``s_mm``.
    """
    if not 0 < progress <= 1:
        raise ValueError(f"progress must be in (0, 1], got {progress!r}")
    c, dt = ce_contour(contour)
    t_end = c.t_min + progress * (c.t_max - c.t_min)
    path = ce.thesis3_path(c, tool_radius_mm, theta_deg, dt, "midpoint", t_end=t_end)
    cc = c.sample(800)
    x0, y0, x1, y1 = Polygon(cc).bounds
    m = 4 * float(tool_radius_mm)
    stock = box(x0 - m, y0 - m, x1 + m, y1 + m).difference(Polygon(cc))
    if len(path.P) < 3:
        eng, s = np.full(len(path.P), np.nan), np.zeros(len(path.P))
    else:
        tab = ce.engagement_along_path(stock, path.P, tool_radius_mm, resolution_mm, feed_direction="central")
        eng, s = tab.engagement_deg.to_numpy(), tab.s.to_numpy()
    return {"contour": cc, "P": path.P, "C": path.C, "engagement_deg": eng, "s_mm": s,
            "theta_deg": float(theta_deg), "tool_radius_mm": float(tool_radius_mm)}


#: Trochoid patterns of Thesis IV.
TROCHOID_PATTERNS = ("circle", "cycloid", "constant-engagement")


def trochoid_scene(pattern, step_mm, width_mm, tool_radius_mm, theta_deg=60.0, n_periods=5,
                   resolution_mm=0.1):
    """One trochoid pattern cut through a straight slot (``width_mm``) in the dixel model.

    ``pattern``: "circle" / "cycloid" at trochoidal ``step_mm`` (``theta_deg`` only sets the
    reference line: the exact front-point engagement of the circle pattern), or
    "constant-engagement" (Thesis IV; its step comes from ``theta_deg``). Returns the path, the
    per-point engagement (deg), segment kinds, and the steady-state metrics of
    :func:`cnclab.toolpath.trochoidal.evaluate_pattern`.
    """
    r, W = float(tool_radius_mm), float(width_mm)
    if pattern == "circle":
        path = trochoidal.circular_trochoid(step_mm, W, r, n_periods, ds=resolution_mm)
    elif pattern == "cycloid":
        path = trochoidal.cycloid(step_mm, W, r, n_periods, ds=resolution_mm)
    elif pattern == "constant-engagement":
        path = trochoidal.ce_trochoid(W, r, theta_deg, n_periods=n_periods, resolution_mm=resolution_mm,
                                      dt=0.2, n_iter=4)
    else:
        raise ValueError(f"pattern must be one of {TROCHOID_PATTERNS}, got {pattern!r}")
    df, metrics = trochoidal.evaluate_pattern(path, W, r, resolution_mm)
    step = float(path.info["step"])
    front = (trochoidal.max_engagement_circle_front(step, W, r) if pattern == "circle" else math.nan)
    return {"pattern": pattern, "points": path.xyz[:, :2], "link": path.is_kind("link"),
            "kinds": np.asarray(trochoidal.pattern_kinds(path)),
            "engagement_deg": df.engagement_deg.to_numpy(), "s_mm": df.s.to_numpy(),
            "metrics": metrics.to_dict(), "step_mm": step, "width_mm": W, "tool_radius_mm": r,
            "theta_deg": float(theta_deg), "front_engagement_deg": front}


# ---------------------------------------------------------------------------------- Kim & Yang
def kim_yang_pocket(scale=0.5) -> Polygon:
    """Kim & Yang's 120 x 85 mm test pocket (cnclab's design) scaled by ``scale`` about its origin."""
    return affinity.scale(ky_pocket.pocket(), scale, scale, origin=(0, 0))


def _with_spiral_entry(p, pitch_mm):
    """Prefix a pass with Kim & Yang's §3.3 spiral entry inside its first (closed, ccw) loop."""
    d = np.hypot(p[1:, 0] - p[0, 0], p[1:, 1] - p[0, 1])
    k = np.flatnonzero(d < 1e-9)
    ring = p[: int(k[0]) + 2] if len(k) else p
    poly = Polygon(ring)
    if len(ring) < 4 or not poly.is_valid or poly.area <= 1.0 or not poly.exterior.is_ccw:
        return p
    sp = cm.spiral_entry(poly, p[0], pitch_mm=pitch_mm)
    return np.vstack([sp[:-1], p])


def kim_yang_scene(theta_deg, tool_radius_mm=5.0, pixel_mm=0.5, tolerance=0.15, feed_mm_min=500.0,
                   a_p_mm=0.5, pocket_scale=0.5, sample_mm=1.0):
    """Kim & Yang §3.2 on the (scaled) test pocket for a reference engagement ``theta_deg``.

    The radial depth is the straight-cut stepover of that engagement, s = r (1 - cos theta) (Thesis I,
    straight); eq. 4's reference per mm of path is s / p^2 pixels. Returns the original and modified
    passes (mm), the inserted-point flags, and the simulated MRR (mm^3/min) along both paths on a
    pixel stock of ``pixel_mm``, with the nominal MRR a_p s v_f.
    """
    r = float(tool_radius_mm)
    s = float(engagement.stepover_thesis1(theta_deg, None, r, "straight"))
    poly = kim_yang_pocket(pocket_scale)
    allowed = offsets.allowed_region(poly, r)
    passes = [_with_spiral_entry(p, s) for p in offsets.link_loops(offsets.offset_levels(poly, r, s), allowed)]
    fz = cm.feed_per_tooth(feed_mm_min, 2000.0)
    ref = cm.reference_pixel_count(fz, s, pixel_mm) / fz
    mod = cm.modify_path([p.copy() for p in passes], pixel.Stock.from_polygon(poly, pixel_mm), r, ref, allowed,
                         tolerance=tolerance)

    def trace(pp):
        st = pixel.Stock.from_polygon(poly, pixel_mm)
        out, s0 = [], 0.0
        for p in pp:
            pts = cm.resample_polyline(p, sample_mm)
            if len(pts) < 2:
                continue
            df = pixel.removal(st, pts, r, a_p_mm, feed_mm_min)        # the MRR only: no engagement measured
            out.append(np.c_[df.s.to_numpy()[1:] + s0, df.mrr_mm3_min.to_numpy()[1:]])
            s0 += float(df.s.iloc[-1])
        return np.vstack(out)

    return {"theta_deg": float(theta_deg), "stepover_mm": s, "pocket": np.asarray(poly.exterior.coords),
            "islands": [np.asarray(h.coords) for h in poly.interiors], "original": passes,
            "modified": mod.passes, "inserted": mod.inserted, "n_insertions": mod.n_insertions,
            "n_excessive": mod.n_excessive, "mrr_original": trace(passes), "mrr_modified": trace(mod.passes),
            "nominal_mrr_mm3_min": a_p_mm * s * feed_mm_min, "tolerance": float(tolerance),
            "reference_per_mm": ref}


# --------------------------------------------------------------------------------------- Hoang
def hoang_scene(scallop_height_mm, tool_radius_mm, volume_mm3, n=401):
    """Constant-volume step (Hoang eqs 1-7) and the scallop cross-section drawn to scale (mm).

    Two ball sections of radius R_T touch the design plane z = 0 at x = -S_z/2 and +S_z/2; the ridge
    between them is the envelope ``ridge_z`` over ``ridge_x``. Returns Table 2's quantities
    (:func:`cnclab.cutting.scallop_volume.table2_row`), the drawn ridge's peak height and area
    (numerical, trapezoid) and the exact area.
    """
    row = sv.table2_row(scallop_height_mm, tool_radius_mm, volume_mm3)
    R, Sz = float(tool_radius_mm), row["Sz"]
    x = np.linspace(-Sz / 2, Sz / 2, n)
    z = R - np.sqrt(np.maximum(R * R - np.minimum((x + Sz / 2) ** 2, (x - Sz / 2) ** 2), 0.0))
    t = np.linspace(-math.pi / 2 - 0.9, -math.pi / 2 + 0.9, 181)
    balls = [np.c_[cx + R * np.cos(t), R + R * np.sin(t)] for cx in (-Sz / 2, Sz / 2)]
    area = float(np.sum(0.5 * (z[1:] + z[:-1]) * np.diff(x)))
    return {**row, "ridge_x": x, "ridge_z": z, "balls": balls, "drawn_peak_mm": float(z.max()),
            "drawn_area_mm2": area, "exact_area_mm2": float(sv.scallop_area_exact(Sz, R))}


# ----------------------------------------------------------------------------------- Mgherony
def working_diameter_scene(D, a_p, A_N1, A_N2, A_f, a_e, milling="up", n=181):
    """Ball-end contact geometry in 3D (ball-centre coordinates, mm; angles deg, eq 5-3 convention).

    The contact circle is the ball (radius D/2) cut by the surface plane ``a_p`` below the tool tip
    along the outward normal; tangent points 1/2 come from
    :func:`cnclab.geometry.ball_end.tangent_points_3d`, their working diameters from
    :func:`tangent_point_diameters`, the cut points (width ``a_e``) from :func:`cut_point_diameters`
    and the working-radius change over one chip from :func:`chip_removal_radius_variation`.
    """
    if milling not in ("up", "down"):
        raise ValueError(f"milling must be 'up' or 'down', got {milling!r}")
    ball_end.validate_model_inputs(D, a_p, A_N1, A_N2, A_f, a_e)
    R = D / 2.0
    nrm = np.asarray(ball_end.normal_from_angles(A_N1, A_N2), float)
    centre = -(R - a_p) * nrm
    rc = float(ball_end.intersection_circle_radius(D, a_p))
    u = np.cross(nrm, [0.0, 0.0, 1.0]) if abs(nrm[2]) < 1 - 1e-12 else np.array([1.0, 0.0, 0.0])
    u = u / np.linalg.norm(u)
    v = np.cross(nrm, u)
    t = np.linspace(0, 2 * math.pi, n)
    circle = centre + rc * (np.cos(t)[:, None] * u + np.sin(t)[:, None] * v)
    p1, p2 = (np.asarray(p, float) for p in ball_end.tangent_points_3d(D, a_p, A_N1, A_N2, A_f))
    d1, d2 = (float(d) for d in ball_end.tangent_point_diameters(D, a_p, A_N1, A_N2, A_f))
    cut = ball_end.cut_point_diameters(D, a_p, a_e, A_N1, A_N2, A_f)
    var = {side: 2 * float(ball_end.chip_removal_radius_variation(D, a_p, a_e, A_N1, A_N2, A_f, side, milling))
           for side in (1, 2)}
    return {"D": float(D), "a_p": float(a_p), "normal": nrm, "circle_centre": centre, "circle_radius": rc,
            "circle": circle, "p1": p1, "p2": p2, "d1_mm": d1, "d2_mm": d2,
            "cut_diameters_mm": {k: float(v) for k, v in cut._asdict().items()},
            "chip_diameter_change_mm": var, "milling": milling,
            "feed_dir": np.array([math.cos(math.radians(A_f)), math.sin(math.radians(A_f)), 0.0])}


def cusp_scene(feed_mm, corner_radius_mm, n_periods=10, n=10001):
    """Cusp height (exact eq. and eq 3-2 approximation) and the ideal profile's Ra, Rz (mm) for a feed
    (mm/rev) and corner radius (mm); curves of CH vs feed for this radius."""
    ch = float(cusp.cusp_height_turning(feed_mm, corner_radius_mm, exact=True))
    ch_approx = float(cusp.cusp_height_turning(feed_mm, corner_radius_mm, exact=False))
    x, z = ideal_cusp_profile(feed_mm, corner_radius_mm, n_periods * feed_mm, n)
    par = profile_parameters(z - z.mean())
    f = np.linspace(0.02, 2 * corner_radius_mm, 120)
    return {"feed_mm": float(feed_mm), "corner_radius_mm": float(corner_radius_mm), "CH_mm": ch,
            "CH_approx_mm": ch_approx, "x": x, "z": z, "Ra_mm": float(par["Ra"]), "Rz_mm": float(par["Rz"]),
            "curve_feed_mm": f, "curve_CH_mm": cusp.cusp_height_turning(f, corner_radius_mm),
            "curve_CH_approx_mm": cusp.cusp_height_turning(f, corner_radius_mm, exact=False)}


def spindle_scene(feed_angle_deg, point="thesis"):
    """Chapter 8 spindle schedule along the zig-zag at feed direction ``feed_angle_deg`` (one of
    :data:`cnclab.works.mgherony2024.ch7_9.DIRECTIONS`), computed by the ch. 7-9 pipeline from the
    STL and APT files it writes (fast-mode resolution under ``CNCLAB_FAST=1``)."""
    if float(feed_angle_deg) not in ch7_9.DIRECTIONS:
        raise ValueError(f"feed_angle_deg must be one of {ch7_9.DIRECTIONS} deg, got {feed_angle_deg!r}")
    sc = ch7_9.schedule(float(feed_angle_deg), point)
    return {"feed_angle_deg": float(feed_angle_deg), "xyz": sc.xyz, "n_rpm": sc.n, "d_eff_mm": sc.d_eff,
            "s_mm": np.cumsum(sc.seg_len), "limited": sc.limited, "v_c_actual": sc.v_c_actual,
            "v_c": float(sc.v_c), "summary": sc.summary(), "n_nominal_rpm": float(ch7_9.parameters()["table7_1"]["n"])}
