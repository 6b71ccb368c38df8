"""Matplotlib drawings of the explorer scenes (:mod:`cnclab.explore.scenes`): one function per scene,
each returning a new ``Figure`` (the caller closes it). Lengths in mm, angles in degrees."""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from ..plotting import figsize, plan_view

__all__ = ["thesis1", "ce_growth", "trochoid", "kim_yang", "hoang", "working_diameter", "cusp", "spindle"]


def _fig(w=1.5, h=1.0, ncols=2, **kw):
    """A figure of ``w`` x ``h`` times the style's ``figure.figsize`` (the paper style: 9 x 3.8 in)."""
    fig = Figure(figsize=figsize(w, h))
    fig.subplots_adjust(left=0.08, right=0.97, bottom=0.14, top=0.9, wspace=0.3)   # fixed: fast redraws
    return fig, fig.subplots(1, ncols, **kw) if ncols > 1 else fig.subplots()


def thesis1(sc, curves):
    fig, (a, b) = _fig()
    a.fill(*sc["tool_circle"].T, color="0.92", zorder=0)
    a.plot(*sc["tool_circle"].T, color="0.4", lw=1, label="tool")
    a.plot(*sc["previous_contour"].T, "k--", lw=1, label="previous contour")
    a.plot(*sc["new_contour"].T, "k", lw=1.2, label="new contour")
    a.plot(*sc["engaged_arc"].T, "C3", lw=3, label=f"engaged arc {sc['drawn_theta_deg']:.2f}°")
    P, C, Q = sc["tool_centre"], sc["contact_point"], sc["touch_point"]
    a.plot(*np.c_[C, P, Q], "C3:", lw=0.8)
    a.annotate("", P + [0, 1.6 * sc["tool_radius_mm"]], P, arrowprops={"arrowstyle": "->"})
    a.set_aspect("equal")
    r = sc["tool_radius_mm"]
    a.set(xlim=(P[0] - 2.5 * r, P[0] + 2.5 * r), ylim=(-2.5 * r, 2.5 * r), xlabel="x [mm]", ylabel="y [mm] (feed ↑)",
          title=f"{sc['kind']}: θ = {sc['theta_deg']:.2f}°")
    a.legend(fontsize=7, loc="lower left")
    for kind, st in (("straight", "k-"), ("concave", "C0-"), ("convex", "C1-")):
        b.plot(curves["s_mm"], curves[kind], st, lw=1, label=kind)
    b.plot(sc["stepover_mm"], sc["theta_deg"], "C3o")
    b.set(xlabel="stepover s [mm]", ylabel="engagement θ [deg]", title=f"ρ = {sc['rho_mm']:g} mm, r = {r:g} mm")
    b.legend(fontsize=7)
    return fig


def ce_growth(sc):
    fig, (a, b) = _fig()
    a.fill(*sc["contour"].T, color="0.92")
    a.plot(*sc["contour"].T, "k", lw=1, label="contour (cleared inside)")
    a.plot(*sc["P"].T, "C0", lw=1.2, label="Thesis III path")
    P, r = sc["P"][-1], sc["tool_radius_mm"]
    t = np.linspace(0, 2 * np.pi, 90)
    a.plot(P[0] + r * np.cos(t), P[1] + r * np.sin(t), "C3", lw=1, label="tool")
    plan_view(a); a.legend(fontsize=7, loc="lower left")
    b.plot(sc["s_mm"], sc["engagement_deg"], "C0", lw=1, label="simulated (dixel)")
    b.axhline(sc["theta_deg"], color="k", ls=":", label="θ target")
    b.set(xlabel="path length [mm]", ylabel="engagement [deg]", ylim=(0, max(100, sc["theta_deg"] + 20)))
    b.legend(fontsize=7)
    return fig


def trochoid(sc):
    fig, (a, b) = _fig(w=10 / 6)
    P, link = sc["points"], sc["link"]
    W = sc["width_mm"]
    a.axhspan(-W / 2, W / 2, color="0.92")
    a.plot(*P.T, "C0", lw=0.8, label="tool centre")
    if link.any():
        a.plot(*np.where(link[:, None], P, np.nan).T, "C1", lw=0.8, label="link")
    plan_view(a, title=f"{sc['pattern']}, step {sc['step_mm']:.3f} mm")
    a.legend(fontsize=7)
    b.plot(sc["s_mm"], sc["engagement_deg"], "C0", lw=0.8)
    if np.isfinite(sc["front_engagement_deg"]):
        b.axhline(sc["front_engagement_deg"], color="k", ls=":", label="circle front point (exact)")
    else:
        b.axhline(sc["theta_deg"], color="k", ls=":", label="θ")
    b.set(xlabel="path length [mm]", ylabel="engagement [deg]"); b.legend(fontsize=7)
    return fig


def kim_yang(sc):
    fig, (a, b) = _fig(w=10 / 6)
    a.plot(*sc["pocket"].T, "k", lw=1)
    for h in sc["islands"]:
        a.plot(*h.T, "k", lw=1)
    for p in sc["original"]:
        a.plot(*p.T, "0.6", lw=0.6)
    for p, f in zip(sc["modified"], sc["inserted"]):
        a.plot(*np.where(f[:, None], p, np.nan).T, "C3", lw=0.9)
    a.plot([], [], "0.6", label="contour-parallel"); a.plot([], [], "C3", label="inserted segments")
    plan_view(a); a.legend(fontsize=7, loc="upper right")
    k = np.ones(5) / 5.0                                  # 5-sample moving mean (pixel noise)
    for key, st, lab in (("mrr_modified", "C3", "modified"), ("mrr_original", "0.3", "original")):
        x, y = sc[key].T
        b.plot(x[2:-2], np.convolve(y, k, "valid"), st, lw=0.7, label=f"{lab} (5-sample mean)", alpha=0.8)
    b.axhline(sc["nominal_mrr_mm3_min"], color="k", ls=":", label="a_p·s·v_f")
    b.set(xlabel="path length [mm]", ylabel="MRR [mm³/min]", title=f"θ = {sc['theta_deg']:g}°, s = {sc['stepover_mm']:.2f} mm")
    b.legend(fontsize=7)
    return fig


def hoang(sc):
    fig, (a, b) = _fig(w=10 / 6)
    fig.subplots_adjust(wspace=0.65)                   # room for the bar labels
    for ball in sc["balls"]:
        a.plot(*ball.T, "0.5", lw=1)
    a.fill_between(sc["ridge_x"], 0, sc["ridge_z"], color="C1", alpha=0.6, label="scallop section")
    a.axhline(0, color="k", lw=0.8)
    h = sc["drawn_peak_mm"]
    a.set(xlabel="x [mm]", ylabel="z [mm] (vertical scale stretched)", ylim=(-0.3 * h, 2.5 * h),
          xlim=(-0.9 * sc["Sz"], 0.9 * sc["Sz"]), title=f"S_z = {sc['Sz']:.4f} mm, S_c = {h:.4f} mm")
    a.legend(fontsize=7)
    names = ("Fr_consistent", "Fr_v1", "Fr_v2", "Fr_printed_convention")
    b.barh(range(4), [sc[n] for n in names], color=["C0", "C2", "C4", "0.6"])
    b.set_yticks(range(4), ["eq 7 (consistent)", "eq 1 (no curvature)", "eq 4 (pyramid)", "as printed (Table 2)"])
    b.set(xlabel="forward step F_r [mm]")
    return fig


def working_diameter(sc):
    fig = Figure(figsize=figsize(1.5, 4.2 / 3.8))
    fig.subplots_adjust(left=0.02, right=0.97, bottom=0.14, top=0.9, wspace=0.2)
    a = fig.add_subplot(1, 2, 1, projection="3d")
    b = fig.add_subplot(1, 2, 2)
    R = sc["D"] / 2
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 25), np.linspace(np.pi / 2, np.pi, 9))
    a.plot_wireframe(R * np.cos(u) * np.sin(v), R * np.sin(u) * np.sin(v), R * np.cos(v), color="0.75", lw=0.4)
    a.plot(*sc["circle"].T, "C0", lw=1.5, label="contact circle")
    for k, c in (("p1", "C3"), ("p2", "C2")):
        p = sc[k]
        a.plot(*np.c_[[0, 0, p[2]], p], c + ":", lw=1)
        a.scatter(*p, color=c, s=30, label=f"point {k[1]}: D = {sc['d' + k[1] + '_mm']:.3f} mm")
    a.plot([0, 0], [0, 0], [-R, R * 0.5], "k", lw=1)
    f = sc["feed_dir"] * R
    a.quiver(0, 0, -R, *f, color="k", lw=1)
    a.set(xlabel="x", ylabel="y", zlabel="z [mm]"); a.set_box_aspect((1, 1, 0.6))
    a.legend(fontsize=7, loc="upper left")
    cd = sc["cut_diameters_mm"]
    names = ["p1_trail", "p1", "p1_lead", "p2_trail", "p2", "p2_lead"]
    b.bar(range(6), [cd[n] for n in names], color=["C3"] * 3 + ["C2"] * 3)
    b.set_xticks(range(6), ["1″", "1", "1′", "2″", "2", "2′"])
    ch = sc["chip_diameter_change_mm"]
    b.set(ylabel="working diameter [mm]",
          title=f"{sc['milling']} milling: ΔD side 1 = {ch[1]:+.3f}, side 2 = {ch[2]:+.3f} mm")
    return fig


def cusp(sc):
    fig, (a, b) = _fig()
    a.plot(sc["x"], 1000 * sc["z"], "C0", lw=1)
    a.axhline(1000 * sc["CH_mm"], color="C3", ls=":", label=f"CH = {1000 * sc['CH_mm']:.3f} µm")
    a.set(xlabel="x [mm]", ylabel="profile z [µm]", title=f"Ra = {1000 * sc['Ra_mm']:.3f} µm, Rz = {1000 * sc['Rz_mm']:.3f} µm")
    a.legend(fontsize=7)
    b.plot(sc["curve_feed_mm"], 1000 * sc["curve_CH_mm"], "C0", label="exact")
    b.plot(sc["curve_feed_mm"], 1000 * sc["curve_CH_approx_mm"], "C1--", label="f²/(8 RE) (eq 3-2)")
    b.plot(sc["feed_mm"], 1000 * sc["CH_mm"], "C3o")
    b.set(xlabel="feed f [mm/rev]", ylabel="cusp height [µm]", yscale="log", title=f"RE = {sc['corner_radius_mm']:g} mm")
    b.legend(fontsize=7)
    return fig


def spindle(sc):
    fig, (a, b) = _fig(w=10 / 6)
    xyz = sc["xyz"]
    m = a.scatter(xyz[:, 0], xyz[:, 1], c=sc["n_rpm"], s=3, cmap="viridis")
    fig.colorbar(m, ax=a, label="n [rpm]")
    plan_view(a, title=f"A_f = {sc['feed_angle_deg']:g}°")
    b.plot(sc["s_mm"], sc["n_rpm"], "C0", lw=0.6, label="controlled n")
    b.axhline(sc["n_nominal_rpm"], color="k", ls=":", label="constant n (Table 7-1)")
    b.set(xlabel="feed path length [mm]", ylabel="spindle speed n [rpm]"); b.legend(fontsize=7)
    return fig
