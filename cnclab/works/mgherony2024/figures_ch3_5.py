"""Figure recipes of Mgherony (2024) chapters 3-5: each draws one figure from the package alone.

Registered in :data:`cnclab.plotting.FIGURES` on import (``python -m cnclab figure --list``); the ch. 3-5
notebooks call :func:`draw` (the same recipe), so a notebook figure and a paper figure cannot differ.
Sizes are in units of the style's ``figure.figsize`` (:func:`cnclab.plotting.figsize`).

>>> import matplotlib; matplotlib.use("Agg")
>>> fig = draw("fig5-3_transformed_circle_tangent_points")
>>> [ax.get_title()[:14] for ax in fig.axes]
['tangent points']
"""
from __future__ import annotations

import numpy as np

from ...cutting.roughness import ideal_cusp_profile
from ...geometry import ball_end as be
from ...geometry import cusp
from ...geometry.cylinder_parts import MEASURING_POSITIONS_MM, CylinderPart
from ...plotting import FIGURES, draw_figure as draw, figsize, plan_view, register_figure as _register
from . import ch3, ch4_5

__all__ = ["FIGURES", "draw"]


@_register("fig5-6_deff_vs_depth_of_cut", "mgherony2024",
           "Mgherony (2024) Fig 5-6: true working diameter against the depth of cut (D = 6, 8, 10 mm)")
def fig5_6_deff_vs_depth_of_cut():
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=figsize(1, 0.9))
    for Dm, g in ch4_5.fig5_6_curves().groupby("D_mm"):
        line, = ax.plot(g.a_p_mm, g.d1_lead_mm, label=f"D={Dm:g} up (1′)")
        ax.plot(g.a_p_mm, g.d1_trail_mm, "--", color=line.get_color(), label=f"D={Dm:g} down (1″)")
    ax.set(xlabel="a_p [mm]", ylabel="true working diameter [mm]", title="Fig 5-6")
    ax.legend(fontsize=7, ncol=3)
    return fig


@_register("fig5-7_deff_change_during_chip_removal", "mgherony2024",
           "Mgherony (2024) Fig 5-7: change of the true working diameter during chip removal against a_e")
def fig5_7_deff_change_during_chip_removal():
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=figsize(1, 0.9))
    for (Dm, mode), g in ch4_5.fig5_7_variation().groupby(["D_mm", "milling"]):
        ax.plot(g.a_e_mm, g.variation_mm, "-" if mode == "up" else "--", label=f"D={Dm:g} {mode}")
    ax.set(xlabel="a_e [mm]", ylabel="|Δ true working diameter| [mm]", title="Fig 5-7")
    ax.legend(fontsize=7, ncol=3)
    return fig


@_register("fig5-8_5-9_deff_vs_feed_direction", "mgherony2024",
           "Mgherony (2024) Fig 5-8, 5-9: the thesis' 'D_eff' (a radius) against the feed direction")
def fig5_8_5_9_deff_vs_feed_direction():
    import matplotlib.pyplot as plt

    Afs = np.linspace(0, 360, 721)
    fig, axs = plt.subplots(1, 2, figsize=figsize(1.5, 1.0), sharey=True)
    for ax, ap_ in zip(axs, (1.0, 0.3)):
        r1, r2 = be.paper_deff_radius_valued(10, ap_, 35, 25, Afs)
        ax.plot(Afs, r1, label="point 1")
        ax.plot(Afs, r2, label="point 2")
        ax.set(xlabel="A_f [deg]", title=f"a_p = {ap_:g} mm (Fig 5-{8 if ap_ == 1 else 9})")
    axs[0].set_ylabel("thesis' 'D_eff' [mm]")
    axs[0].legend()
    return fig


@_register("ch3_cusp_approximation_error", "mgherony2024",
           "Mgherony (2024) ch. 3: underestimate of the cusp height by eq 3-2/3-4 against s/RE, Table 3-4 parts")
def ch3_cusp_approximation_error():
    import matplotlib.pyplot as plt

    parts = ch3.parts()
    ratio = np.linspace(0.01, 1.2, 300)
    fig, ax = plt.subplots(figsize=figsize(0.85, 0.85))
    ax.plot(ratio, -100 * cusp.approximation_relative_error(ratio, 1.0), label="eq 3-2 / 3-4 vs exact")
    for part, r in parts.iterrows():
        err = -100 * cusp.approximation_relative_error(r.spacing_mm, r.RE_mm)
        ax.plot(r.spacing_mm / r.RE_mm, err, "o", color="C1" if r.process == "milling" else "C0")
        ax.annotate(part, (r.spacing_mm / r.RE_mm, err), textcoords="offset points", xytext=(3, 3), fontsize=7)
    ax.set(xlabel="spacing / corner radius  s/RE", ylabel="underestimate of CH [%]",
           title="Error of the cusp-height approximation (Fig 3-1 geometry)")
    return fig


@_register("fig3-5_rz_ra_ratio", "mgherony2024", "Mgherony (2024) Fig 3-5: Rz/Ra of the turned and milled parts")
def fig3_5_rz_ra_ratio():
    import matplotlib.pyplot as plt

    parts, stats = ch3.parts(), ch3.statistics()
    fig, axes = plt.subplots(1, 2, figsize=figsize(1.15, 0.8), sharey=True)
    for ax, proc in zip(axes, ["turning", "milling"]):
        sub = parts[parts.process == proc]
        ax.bar(sub.index, sub.Rz_um / sub.Ra_um, color="C0" if proc == "turning" else "C1")
        ax.axhline(stats[f"ratio.{proc}"], color="k", lw=0.8, ls="--", label=f"mean {stats[f'ratio.{proc}']:.3f}")
        ax.set(title=f"{proc} (Fig 3-5 {'a' if proc == 'turning' else 'b'})", xlabel="part")
        ax.legend()
    axes[0].set_ylabel("Rz / Ra")
    return fig


@_register("fig3-6_3-7_3-8_roughness_vs_cusp_height", "mgherony2024",
           "Mgherony (2024) Fig 3-6, 3-7, 3-8: Ra and Rz against the cusp height with the linear fits")
def fig3_6_3_7_3_8_roughness_vs_cusp_height():
    import matplotlib.pyplot as plt

    parts, stats = ch3.parts(), ch3.statistics()
    fig, axes = plt.subplots(3, 1, figsize=figsize(1.0, 1.9), sharey=True, layout="constrained")
    for ax, (group, fig_no) in zip(axes, [("turning", "3-6"), ("milling", "3-7"), ("both", "3-8")]):
        sub = parts if group == "both" else parts[parts.process == group]
        xs = np.linspace(0, sub.CH_um.max() * 1.05, 50)
        for resp, marker in [("Ra", "o"), ("Rz", "s")]:
            ax.plot(sub.CH_um, sub[f"{resp}_um"], marker, ls="", label=resp)
            b0, b1 = stats[f"linear.{group}.{resp}.intercept"], stats[f"linear.{group}.{resp}.slope"]
            ax.plot(xs, b0 + b1 * xs, lw=0.8, label=f"{resp} = {b1:.4f}·CH {b0:+.4f}")
        ax.set(title=f"{group} (Fig {fig_no})", ylabel="roughness [µm]")
        ax.legend(fontsize=6, loc="upper left", ncol=2)
    axes[-1].set_xlabel("CH [µm]")
    return fig


@_register("ch3_hybrid_model_erratum", "mgherony2024",
           "Mgherony (2024) eqs 3-10 ... 3-12: the hybrid roughness model as printed and inverted")
def ch3_hybrid_model_erratum():
    import matplotlib.pyplot as plt

    parts = ch3.parts()
    fig, ax = plt.subplots(figsize=figsize(0.7, 0.95))
    for resp, c, m in [("Ra", (1.94, -1.68, 11.6), "o"), ("Rz", (0.24, -0.37, 3.45), "s")]:
        C = c[0] + c[1] * parts.RE_mm + c[2] * parts.p_mm
        ax.plot(parts[f"{resp}_um"], parts.CH_um / C, m, label=f"{resp}: Rx = CH / C (printed coefficients)")
        ax.plot(parts[f"{resp}_um"], parts.CH_um * C, m, mfc="none", label=f"{resp}: Rx = C·CH (eq 3-10 as printed)")
    lim = [0, 22]
    ax.plot(lim, lim, "k", lw=0.6)
    ax.set(xlim=lim, ylim=[0, 40], xlabel="measured [µm]", ylabel="model [µm]", title="Hybrid model, eqs 3-10 … 3-12")
    ax.legend(fontsize=6)
    return fig


@_register("ch3_ideal_profile_share", "mgherony2024",
           "Mgherony (2024) ch. 3: the ideal profile of T3 and the share of Ra, Rz the geometry explains")
def ch3_ideal_profile_share():
    import matplotlib.pyplot as plt

    parts, ideal = ch3.parts(), ch3.ideal_vs_measured()
    fig, axes = plt.subplots(1, 2, figsize=figsize(1.35, 0.8))
    x, z = ideal_cusp_profile(parts.loc["T3", "spacing_mm"], parts.loc["T3", "RE_mm"], 1.0, n=4001)
    axes[0].plot(x, 1000 * z)
    axes[0].set(xlabel="x [mm]", ylabel="z [µm]", title="Ideal profile of T3\n(f = 0.2 mm, RE = 0.4 mm)")
    w, idx = 0.38, np.arange(len(ideal))
    axes[1].bar(idx - w / 2, ideal.Rz_share * 100, w, label="Rz ideal / measured")
    axes[1].bar(idx + w / 2, ideal.Ra_share * 100, w, label="Ra ideal / measured")
    axes[1].set(xticks=idx, ylabel="explained by geometry [%]")
    axes[1].set_xticklabels(ideal.index, rotation=90)
    axes[1].legend(fontsize=7)
    return fig


@_register("fig4-1_cv_cx_sections", "mgherony2024",
           "Mgherony (2024) Fig 4-1: sections of the concave (CV) and convex (CX) test parts, ball centres")
def fig4_1_cv_cx_sections():
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=figsize(1.15, 0.95), layout="constrained")
    for kind in ("CV", "CX"):
        part = CylinderPart(kind)
        y, z = part.section()
        ax.plot(y, z, label=f"{kind} surface")
        Rt = part.tool_path_radius(10.0)
        yc = part.contact_y(MEASURING_POSITIONS_MM)
        centre = np.c_[MEASURING_POSITIONS_MM, part.z(yc) + 5.0 * part.normal(yc)[:, 2]]
        ax.plot(*centre.T, "o", ms=3, label=f"{kind} ball centres (radius {Rt:g} mm)")
    ax.set(xlabel="y [mm]", ylabel="z [mm]", aspect="equal", title="CV/CX sections (Fig 4-1, Table 4-2)")
    fig.legend(loc="outside lower center", fontsize=7, ncol=2)
    return fig


@_register("fig4-2_4-3_effective_diameter_cutting_speed", "mgherony2024",
           "Mgherony (2024) Fig 4-2, 4-3: effective diameter and actual cutting speed along the CV/CX parts")
def fig4_2_4_3_effective_diameter_cutting_speed():
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(1, 2, figsize=figsize(1.5, 0.85))
    for kind, g in ch4_5.ch4_effective_diameters().groupby("part"):
        axs[0].plot(g.y_mm, g.D_eff1_mm, "o-", label=kind)
        axs[1].plot(g.y_mm, g.v_c_m_min, "o-", label=kind)
    axs[0].set(xlabel="measuring position y [mm]", ylabel="effective diameter [mm]", title="Fig 4-2")
    axs[1].set(xlabel="measuring position y [mm]", ylabel="actual v_c [m/min]", title="Fig 4-3 (n = 5100 rpm)")
    for a in axs:
        a.legend()
    return fig


@_register("fig5-3_transformed_circle_tangent_points", "mgherony2024",
           "Mgherony (2024) Fig 5-3: the intersection circle transformed by the surface inclination, tangent points")
def fig5_3_transformed_circle_tangent_points():
    import matplotlib.pyplot as plt

    D, a_p, A1, A2, Af = 10.0, 1.0, 35.0, 25.0, 30.0        # mm, mm, deg, deg, deg (the Fig 5-3 example)
    t = np.linspace(0, 2 * np.pi, 361)
    r = float(be.intersection_circle_radius(D, a_p))
    C = be.rotation_matrix_Tr(A1, A2) @ np.stack([r * np.cos(t), r * np.sin(t), np.full_like(t, a_p - D / 2)])
    P1, P2 = be.tangent_points_3d(D, a_p, A1, A2, Af)
    fig, ax = plt.subplots(figsize=figsize(0.75, 1.2))
    ax.plot(C[0], C[1], label="transformed circle (xy)")
    ax.plot(r * np.cos(t), r * np.sin(t), ":", label="horizontal circle")
    for P, name in ((P1, "1"), (P2, "2")):
        ax.plot(*P[:2], "o")
        ax.annotate(name, P[:2], xytext=(4, 4), textcoords="offset points")
    ax.arrow(0, 0, 2 * np.cos(np.radians(Af)), 2 * np.sin(np.radians(Af)), width=0.03, color="k")
    plan_view(ax, title="tangent points (Fig 5-3), feed arrow A_f")
    ax.legend(fontsize=7)
    return fig


@_register("fig5-10_5-13_deff_vc_maps", "mgherony2024",
           "Mgherony (2024) Figs 5-10 ... 5-13: working radii of points 1, 2 and v_c over the surface normal angles")
def fig5_10_5_13_deff_vc_maps():
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    n_rpm = ch4_5.parameters()["ch5_fig5_10"]["n_rpm"]          # §5.5: 3820 1/min
    fig, axs = plt.subplots(3, 2, figsize=figsize(1.3, 2.0), layout="constrained", sharex=True, sharey=True)
    for col, (ap_, Af_) in enumerate(((1.0, 30), (0.3, 60))):
        AN1, AN2, r1, r2 = ch4_5.surface_map(ap_, Af_)
        for row, (z, lab) in enumerate(((r1, "point 1 radius [mm]"), (r2, "point 2 radius [mm]"),
                                        (np.pi * n_rpm * r1 / 1000, "point 1 v_c [m/min]\n(radius-based)"))):
            ax = axs[row, col]
            fig.colorbar(ax.contourf(AN1, AN2, z, 20), ax=ax, label=lab, ticks=MaxNLocator(4))
            ax.set(ylabel="A_N2 [deg]" if col == 0 else "", xlabel="A_N1 [deg]" if row == 2 else "")
        axs[0, col].set_title(f"a_p = {ap_:g} mm, A_f = {Af_}°")
    return fig
