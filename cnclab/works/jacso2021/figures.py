"""Jacsó (2021) Theses I-III and the §2.2 dixel simulator: the figures of their three notebooks.

A recipe called without arguments computes its data (fast settings under ``CNCLAB_FAST=1``, the
notebooks' own); a notebook passes what it has computed already, by keyword. Thesis IV, §4 and the
planner comparisons, which need the planners, are in :mod:`.figures_pockets` (a notebook's
``make reproduce`` key follows the modules it imports).

>>> FIGURES["thesis3_convergence_arc"].work
'jacso2021'
"""
from __future__ import annotations

import numpy as np

from ...geometry import engagement as eng
from ...geometry.contours import Arc, Ellipse, SplineContour
from ...plotting import FIGURES, draw_figure as draw, figsize, register_figure as _register
from ...runtime import pick
from ...simulation import dixel, pixel
from ...toolpath import constant_engagement as ce
from . import theses_1_3 as rec

__all__ = ["draw", "thesis3_spline", "simulated_deviation", "multi_pass_laps", "closed_path_trace", "accuracy"]

R_TOOL, THETA = 3.0, 60.0          # tool radius (mm) and engagement (deg) of the Theses II-III figures


def _plt():
    import matplotlib.pyplot as plt
    return plt


def _log_x_ticks(ax, values):
    """Log x axis labelled at the study's own values (the minor labels of a one-decade range overlap
    at a column width of 85 mm); y: decades only."""
    from matplotlib.ticker import NullFormatter

    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_xticks(list(values), [f"{v:g}" for v in values])


# ------------------------------------------------------------------------------ Thesis I
@_register("fig3-1_engagement_vs_stepover", "jacso2021",
           "Jacsó (2021) Fig 3-1: engagement angle against stepover, straight and on arcs (r = 3 mm)")
def fig3_1_engagement_vs_stepover(r: float = 3.0):
    plt = _plt()
    s = np.linspace(0.01, 2 * r, 300)
    fig, ax = plt.subplots(figsize=figsize())
    ax.plot(s, eng.theta_straight(s, r), "k", label="straight")
    for rho in (4.0, 8.0, 20.0):
        ax.plot(s, eng.theta_concave(s, rho, r), label=f"concave ρ={rho:g}")
        ok = rho - s + r > 0
        ax.plot(s[ok], eng.theta_convex(s[ok], rho, r), "--", label=f"convex ρ={rho:g}")
    ax.set(xlabel="stepover s [mm]", ylabel="engagement θ [deg]")
    ax.legend(fontsize=7)
    return fig


# ------------------------------------------------------------------------------ Theses II and III
def thesis3_spline() -> SplineContour:
    """The closed spline contour of the Thesis III studies (8 knots on a 10 x 8 mm oval, wavy)."""
    tk = np.linspace(0, 2 * np.pi, 9)[:-1]
    return SplineContour(np.c_[10 * np.cos(tk), 8 * np.sin(tk) + np.sin(2 * tk)], closed=True)


@_register("fig3-3_3-4_feed_field_and_step", "jacso2021",
           "Jacsó (2021) Fig 3-3/3-4: Thesis III feed directions and steps along an ellipse (r = 3 mm, θ = 60°)")
def fig3_3_3_4_feed_field_and_step(theta_deg: float = THETA, t_end: float = 2.0, dt: float = 0.4):
    """``theta_deg``: engagement (deg); ``t_end``: how far along the ellipse and ``dt``: the Euler
    step (contour parameter, mm)."""
    plt = _plt()
    ell = Ellipse((0, 0), 12, 8)
    res = ce.thesis3_path(ell, R_TOOL, theta_deg, dt, "euler", t_end=t_end)
    fig, ax = plt.subplots(figsize=figsize(1, 1.3))
    ax.plot(*ell.sample(400).T, "k", lw=1, label="contour c(t)")
    v = ce.thesis3_feed_direction(res.P, res.C, theta_deg)
    ax.quiver(*res.P.T, *v.T, color="C0", scale=12, label="feed direction")
    ax.plot(*res.P.T, "C1.-", label="Thesis III points P_i")
    for P, C in zip(res.P[::2], res.C[::2]):
        ax.plot(*np.c_[P, C], "C2", lw=0.6)
        ax.add_patch(plt.Circle(P, R_TOOL, fill=False, lw=0.4, color="0.5"))
    ax.set_aspect("equal")
    ax.legend(fontsize=7)
    return fig


@_register("thesis3_convergence_arc", "jacso2021",
           "Jacsó (2021) Thesis III: Euler vs midpoint error on a concave arc (ρ = 8 mm) against Δt")
def thesis3_convergence_arc():
    plt = _plt()
    arc = Arc((0, 0), 8.0, 0, 200)
    P0, d = ce.arc_start_point(arc, R_TOOL, THETA, "concave")
    dts = np.array([0.4, 0.2, 0.1, 0.05, 0.025])
    fig, ax = plt.subplots(figsize=figsize(0.85, 1.05))
    for m in ("euler", "midpoint"):
        e = [np.max(np.abs(np.hypot(*ce.thesis3_path(arc, R_TOOL, THETA, dt, m, P0=P0).P.T) - d)) for dt in dts]
        k = np.polyfit(np.log(dts), np.log(e), 1)[0]
        ax.loglog(dts, e, "o-", label=f"{m}: slope {k:.2f}")
    ax.set(xlabel="Δt [mm]", ylabel="max radial error [mm]")
    _log_x_ticks(ax, dts[::2])
    ax.legend()
    return fig


@_register("thesis3_convergence_ellipse_spline", "jacso2021",
           "Jacsó (2021) Thesis III: observed order on an ellipse and a closed spline (reference: Thesis II IVP)")
def thesis3_convergence_ellipse_spline():
    plt = _plt()
    contours = {"ellipse 12×8": (Ellipse((0, 0), 12, 8), 3.0), "spline": (thesis3_spline(), 20.0)}
    dts = np.array([0.08, 0.04, 0.02, 0.01])
    fig, axs = plt.subplots(1, 2, figsize=figsize(1.65, 1.05), layout="constrained")
    for ax, (name, (c, t_end)) in zip(axs, contours.items()):
        table, orders = ce.convergence_study(c, R_TOOL, THETA, dts, t_end=t_end)
        for m, g in table.groupby("method", sort=False):
            ax.loglog(g.dt, g.max_err_mm, "o-", label=m)
        ax.set_title(f"{name}\norders {orders['euler']:.2f} / {orders['midpoint']:.2f}", fontsize=8)
        ax.set_xlabel("Δt [mm]")
        _log_x_ticks(ax, dts[::2])
    axs[0].set_ylabel("max |P_i − p(t_i)| [mm]", fontsize=8)
    axs[0].legend(fontsize=7, loc="lower right")
    return fig


def simulated_deviation(dts=None) -> dict:
    """Engagement deviation from θ measured by the dixel simulator (0.05 mm) along the Thesis III
    paths on :func:`thesis3_spline` (first 25 mm), per method: ``{method: DataFrame}``
    (:func:`cnclab.toolpath.constant_engagement.simulated_deviation_vs_dt`); ``dts`` (mm) default
    0.8 ... 0.05 (fast mode 0.8 ... 0.1)."""
    from shapely.geometry import Polygon, box

    spline = thesis3_spline()
    stock = box(-25, -25, 25, 25).difference(Polygon(spline.sample(4000)))
    dts = pick([0.8, 0.4, 0.2, 0.1, 0.05], [0.8, 0.4, 0.2, 0.1]) if dts is None else dts
    return {m: ce.simulated_deviation_vs_dt(spline, stock, R_TOOL, THETA, dts, method=m, resolution_mm=0.05,
                                            t_end=25.0) for m in ("euler", "midpoint")}


@_register("thesis3_simulated_deviation_vs_dt", "jacso2021",
           "Jacsó (2021) Thesis III: simulated |engagement − θ| (max, p95) on the spline against Δt")
def thesis3_simulated_deviation_vs_dt(dev=None):
    dev = simulated_deviation() if dev is None else dev
    fig, ax = _plt().subplots(figsize=figsize(0.85, 1.05))
    for m, df in dev.items():
        ax.loglog(df.dt, df.max_dev_deg, "o-", label=f"{m}: max")
        ax.loglog(df.dt, df.p95_dev_deg, "x:", label=f"{m}: p95")
    ax.set(xlabel="Δt [mm]", ylabel="|engagement − θ| [deg]")
    _log_x_ticks(ax, next(iter(dev.values())).dt)
    ax.legend(fontsize=7)
    return fig


def multi_pass_laps(n_passes=None):
    """Constant-engagement laps around a Ø12 mm hole limited by a Ø28 mm final contour (dixel
    0.05 mm, Δt 0.1 mm; ``n_passes`` default 4, fast mode 2): ``(laps, final polygon)``."""
    from shapely.geometry import Point, box

    domain, final = box(-20, -20, 20, 20), Point(0, 0).buffer(14.0, quad_segs=128)
    stock = dixel.Stock.from_polygon(domain.difference(Point(0, 0).buffer(6.0, quad_segs=128)), 0.05)
    n = pick(4, 2) if n_passes is None else n_passes
    return ce.multi_pass(stock, domain, final, (0, 0), R_TOOL, THETA, n_passes=n, dt=0.1), final


@_register("multi_pass_engagement", "jacso2021",
           "Jacsó (2021) Theses II-III: successive laps limited by a final contour and their simulated engagement")
def multi_pass_engagement(laps=None, final=None):
    if laps is None or final is None:
        laps, final = multi_pass_laps()
    fig, (a1, a2) = _plt().subplots(1, 2, figsize=figsize(1.65, 1.3), layout="constrained")
    for i, lap in enumerate(laps):
        a1.plot(*lap["path"].T, lw=0.8, label=f"lap {i + 1}")
        a2.plot(lap["table"].s, lap["table"].engagement_deg, lw=0.6, label=f"lap {i + 1}")
    a1.plot(*np.asarray(final.exterior.coords).T, "k")
    a1.set_aspect("equal")
    a1.legend(fontsize=7)
    a2.axhline(THETA, color="k", ls=":")
    a2.set(xlabel="path length [mm]", ylabel="engagement [deg]")
    return fig


# ------------------------------------------------------------------------------ §2.2 dixel simulator
def accuracy(resolutions=None):
    """:func:`cnclab.works.jacso2021.theses_1_3.accuracy_table` at ``resolutions`` (mm), default the
    notebook's 0.1 ... 0.01 mm (fast mode down to 0.02)."""
    return rec.accuracy_table(resolutions=pick((0.1, 0.05, 0.02, 0.01), (0.1, 0.05, 0.02))
                              if resolutions is None else resolutions)


@_register("dixel_pixel_engagement_error_vs_h", "jacso2021",
           "Jacsó (2021) §2.2: dixel and pixel engagement error against the resolution (closed forms of §3.1)")
def dixel_pixel_engagement_error_vs_h(acc=None):
    acc = accuracy() if acc is None else acc
    worst = acc.groupby(["model", "feed_direction", "h_mm"]).max_abs_err_deg.max().unstack("h_mm")
    fig, ax = _plt().subplots(figsize=figsize(0.9, 1.05))
    for (m, fd), row in worst.iterrows():
        ax.loglog(row.index, row.values, "o-" if fd == "central" else "x:", label=f"{m}, {fd}")
    ax.set(xlabel="resolution h [mm]", ylabel="max |error| over the 3 cases [deg]")
    _log_x_ticks(ax, worst.columns)
    ax.legend(fontsize=7)
    return fig


def closed_path_trace(model: str = "pixel", resolution_mm: float = 0.02):
    """A closed trochoid-like path (r = 3 mm, 3 mm deep, 255 mm/min, f_z 0.04 mm) cut into a 30 mm
    square by the ``"dixel"`` or ``"pixel"`` simulator: ``(per-step DataFrame, swept area mm²)``,
    the swept area from shapely (the tool disc along the path, clipped to the square)."""
    from shapely.geometry import LineString, box

    t = np.linspace(0, 2 * np.pi, 3000)
    path = np.c_[6 * np.cos(t) + 1.5 * np.cos(3 * t), 5 * np.sin(t)]
    square = box(-15, -15, 15, 15)
    swept = square.intersection(LineString(path).buffer(R_TOOL, quad_segs=256)).area
    mod = {"dixel": dixel, "pixel": pixel}[model]
    df = mod.simulate(mod.Stock.from_polygon(square, resolution_mm), path, R_TOOL, 3, 255, f_z=0.04)
    return df, swept


@_register("dixel_closed_path_trace", "jacso2021",
           "Jacsó (2021) §2.2: engagement and MRR along a closed path (pixel stock, 0.02 mm)")
def dixel_closed_path_trace(df=None):
    df = closed_path_trace("pixel")[0] if df is None else df
    fig, ax = _plt().subplots(2, 1, figsize=figsize(1.15, 1.3), sharex=True)
    ax[0].plot(df.s, df.engagement_deg)
    ax[0].set_ylabel("engagement [deg]")
    ax[1].plot(df.s, df.mrr_mm3_min)
    ax[1].set(ylabel="MRR [mm³/min]", xlabel="path length [mm]")
    return fig
