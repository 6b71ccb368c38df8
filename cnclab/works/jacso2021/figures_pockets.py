"""Jacsó (2021) Thesis IV and §4, and the planner comparisons built on them (star and user pockets,
FreeCAD Adaptive, the corpus): the figures of the thesis4, s4 and adaptive_vs_freecad notebooks.

Called without arguments a recipe computes its data through the work's cached functions (fast
settings under ``CNCLAB_FAST=1``); the notebooks pass what they have computed, by keyword.

>>> FIGURES["fig4-1_star_hybrid_path"].work
'jacso2021'
"""
from __future__ import annotations

import numpy as np

from ...plotting import FIGURES, draw_figure as draw, figsize, register_figure as _register
from ...runtime import fast_mode, pick
from ...toolpath import trochoidal as tr
from . import corpus_comparison as corpus
from . import freecad_comparison as fx
from . import thesis4_star_pocket as t4

__all__ = ["draw", "trochoid_iteration", "freecad_runs", "SHOWN_POCKETS"]

_KIND_COLOURS = (("cut", "C0"), ("roll-in", "g"), ("roll-out", "r"), ("link", "k"))


def _plt():
    import matplotlib.pyplot as plt
    return plt


# ------------------------------------------------------------------------------ Thesis IV
def trochoid_iteration(resolution_mm=None):
    """The Thesis IV period iteration of Fig. 3.5 (W = 12 mm, r = 3 mm, θ = 60°, 8 periods, dixel
    0.05 mm, fast mode 0.1)."""
    return tr.ce_trochoid_iteration(12.0, 3.0, 60.0, n_periods=8,
                                    resolution_mm=pick(0.05, 0.1) if resolution_mm is None else resolution_mm)


@_register("fig3-5_ce_trochoid_iteration", "jacso2021",
           "Jacsó (2021) Fig 3-5: the constant-engagement trochoid period iteration (W = 12 mm, r = 3 mm, θ = 60°)")
def fig3_5_ce_trochoid_iteration(it=None):
    it = trochoid_iteration() if it is None else it
    fig, ax = _plt().subplots(figsize=figsize(1.15, 0.9))
    for per in it.periods:
        K = tr.pattern_kinds(per)
        for kind, col in _KIND_COLOURS[:3]:
            ax.plot(np.where(K == kind, per.xyz[:, 0], np.nan), np.where(K == kind, per.xyz[:, 1], np.nan), c=col, lw=0.8)
    for lk in it.links:
        ax.plot(lk[:, 0], lk[:, 1], "k:", lw=0.5)
    ax.axhline(3, c="k", lw=0.5)
    ax.axhline(-3, c="k", lw=0.5)
    ax.set(aspect="equal", xlabel="x (mm)", ylabel="y (mm)", title="green roll-in, blue cut, red roll-out, dotted link")
    return fig


@_register("thesis4_patterns_engagement", "jacso2021",
           "Jacsó (2021) Thesis IV: circular, cycloid and constant-engagement trochoids and their engagement (θ_max 60°)")
def thesis4_patterns_engagement(cmp=None, resolution_mm=None):
    res = pick(0.05, 0.1) if resolution_mm is None else resolution_mm
    cmp = t4.trochoid_comparison(12.0, 60.0) if cmp is None else cmp
    c = cmp.loc["constant-engagement"]
    it_ce = tr.ce_trochoid_iteration(12, 3, c.theta_plan_deg, 8, res, fillet_radius_mm=c.fillet_radius_mm)
    pats = {"circular": tr.circular_trochoid(cmp.loc["circular", "step_mm"], 12, 3, 5, ds=res),
            "cycloid": tr.cycloid(cmp.loc["cycloid", "step_mm"], 12, 3, 5, ds=res),
            "constant-engagement": tr.ce_trochoid(12, 3, c.theta_plan_deg, 5, res, iteration=it_ce, theta_max_deg=60)}
    fig, axs = _plt().subplots(2, 3, figsize=figsize(1.65, 1.3), layout="constrained")
    for j, (name, p) in enumerate(pats.items()):
        df, _ = tr.evaluate_pattern(p, 12, 3, res)
        axs[0, j].plot(p.xyz[:, 0], p.xyz[:, 1], lw=0.7)
        axs[0, j].set(aspect="equal", title=name.replace("constant-engagement", "const. eng."))
        sel = df[df.period == 3]
        for kind, g in sel.groupby("kind"):
            axs[1, j].plot(g.s - sel.s.iloc[0], g.engagement_deg, ".", ms=1.5, label=kind)
        axs[1, j].axhline(60, c="r", lw=0.5)
    axs[1, 0].set_ylabel("engagement (deg)")
    fig.legend(*axs[1, -1].get_legend_handles_labels(), loc="outside right center", fontsize=7, markerscale=3)
    fig.supxlabel("path length in period 3 (mm)", fontsize=9)
    return fig


# ------------------------------------------------------------------------------ §4 star pocket
def _kinds(ax, T, kinds, ms, **kw):
    for kind, col in kinds:
        m = (T.kind == kind).to_numpy()
        ax.plot(T.x[m], T.y[m], ".", ms=ms, c=col, label=kind, **kw)


@_register("fig4-1_star_hybrid_path", "jacso2021",
           "Jacsó (2021) Fig 4-1: the star pocket, its medial axis and the hybrid path by segment kind")
def fig4_1_star_hybrid_path():
    import shapely

    hp, T = t4.star_strategies()[1]["hybrid"]
    fig, ax = _plt().subplots(figsize=figsize(1, 1.6))
    ax.plot(*t4.star_job().polygon.exterior.xy, "k", lw=1)
    for g in shapely.get_parts(hp.info["medial_axis"]):
        ax.plot(*np.asarray(g.coords).T, c="0.6", lw=0.6)
    _kinds(ax, T, _KIND_COLOURS, 0.6)
    ax.set_aspect("equal")
    ax.legend(markerscale=10, fontsize=7)
    ax.set_title(f"{hp.info['laps']} laps, periods per arm {hp.info['periods_per_arm']}")
    return fig


@_register("fig4-1_star_engagement_mrr", "jacso2021",
           "Jacsó (2021) Fig 4-1: engagement, MRR and feed along the star's hybrid path with feed control")
def fig4_1_star_engagement_mrr():
    T = t4.star_strategies()[1]["hybrid"][1]
    fig, axs = _plt().subplots(3, 1, figsize=figsize(1.5, 2.2), sharex=True, layout="constrained")
    for kind, col in _KIND_COLOURS[:3]:
        m = T.kind == kind
        axs[0].plot(T.s[m], T.engagement_deg[m], ".", ms=0.6, c=col, label=kind)
        axs[1].plot(T.s[m], T.mrr_ctrl_mm3_min[m], ".", ms=0.6, c=col)
        axs[2].plot(T.s[m], T.feed_mm_min[m], ".", ms=0.6, c=col)
    axs[0].axhline(60, c="k", lw=0.5)
    axs[0].set_ylabel("θ (deg)")
    fig.legend(*axs[0].get_legend_handles_labels(), loc="outside upper center", ncol=3, markerscale=10, fontsize=7)
    axs[1].axhline(t4.mrr_nominal(), c="k", lw=0.5)
    axs[1].set(ylim=(0, 3000), ylabel="MRR\n(mm³/min)")
    axs[2].set(ylabel="v_f\n(mm/min)", xlabel="path length (mm)")
    fig.align_ylabels(axs)
    return fig


@_register("s4_user_pockets_hybrid_path", "jacso2021",
           "Jacsó (2021) §4 method on user pockets (rectangle, L-shape): hybrid paths, samples above θ + 5°")
def s4_user_pockets_hybrid_path():
    from matplotlib.lines import Line2D

    summ, runs = t4.user_pockets()
    fig, axs = _plt().subplots(1, len(runs), figsize=figsize(1.5, 1.2), layout="constrained")
    for ax, (case, (uj, up, UT)) in zip(axs, runs.items()):
        ax.plot(*uj.polygon.exterior.xy, "k", lw=1)
        _kinds(ax, UT, _KIND_COLOURS, 0.5)
        hot = (UT.engagement_deg > uj.theta_deg + 5).to_numpy() & (UT.kind != "link").to_numpy()
        ax.plot(UT.x[hot], UT.y[hot], "x", ms=3, c="m", label=f"θ > {uj.theta_deg + 5:g}°")
        ax.set_title(f"{case}\nwall share {up.info['max_wall_share']}, "
                     f"max {summ.loc[case, 'engagement_max_deg']:.0f}°", fontsize=8)
        ax.set_aspect("equal")
    handles = [Line2D([], [], ls="", marker=ln.get_marker(), c=ln.get_color(), ms=4 if ln.get_marker() == "." else 3)
               for ln in axs[0].get_legend_handles_labels()[0]]
    fig.legend(handles, axs[0].get_legend_handles_labels()[1], loc="outside lower center", ncol=5, fontsize=7,
               columnspacing=0.8, handletextpad=0.1)
    return fig


# ------------------------------------------------------------------------------ against FreeCAD Adaptive
SHOWN_POCKETS = ("star", "two_islands_neck", "kim_yang_120x85", "spline")


def freecad_runs(names=None) -> dict:
    """``{pocket: {label: (path, evaluation)}}`` of the adaptive planner and FreeCAD Adaptive
    (:func:`cnclab.works.jacso2021.freecad_comparison.comparison`'s ``keep``) on ``names``
    (default :data:`SHOWN_POCKETS`, fast mode the star only)."""
    names = (("star",) if fast_mode() else SHOWN_POCKETS) if names is None else names
    keep = {}
    for name in names:
        keep[name] = {}
        fx.comparison(name, {"adaptive_clearing": "adaptive"}, feed_control=False, keep=keep[name])
    return keep


@_register("adaptive_vs_freecad_paths", "jacso2021",
           "Adaptive planner vs FreeCAD Adaptive: cutting samples coloured by simulated engagement, wall gouges")
def adaptive_vs_freecad_paths(keep=None):
    keep = freecad_runs() if keep is None else keep
    shown = [n for n in SHOWN_POCKETS if n in keep]
    fig, axs = _plt().subplots(len(shown), 2, figsize=figsize(2, 1.1 * len(shown)), squeeze=False,
                               layout="constrained")
    for k, (row, name) in enumerate(zip(axs, shown)):
        jb, sc = fx.job(name), None
        for ax, who, short in zip(row, ["adaptive_clearing", fx.FREECAD], ["ours (adaptive)", "FreeCAD Adaptive"]):
            for g in getattr(jb.polygon, "geoms", [jb.polygon]):
                ax.fill(*g.exterior.xy, color="0.92")
                for i in g.interiors:
                    ax.fill(*i.xy, color="white")
            ax.set(aspect="equal", title=short if k == 0 else "")
            if who not in keep[name]:
                ax.set_title(f"{short}: no program")
                continue
            t = keep[name][who][1].trace
            c = t["cutting"]
            sc = ax.scatter(t["x"][c], t["y"][c], c=t["engagement_deg"][c], s=0.3, cmap="turbo",
                            vmin=jb.theta_deg - 30, vmax=jb.theta_deg + 30, rasterized=True)  # pixels in PDF/SVG
            ax.plot(*fx.gouge_points(keep[name][who][1], jb, 0.05), "kx", ms=3)
        row[0].set_ylabel(f"{name}\ny [mm]")
        if sc is not None:
            fig.colorbar(sc, ax=row, label="engagement [°]")
    fig.supxlabel("x [mm]", fontsize=9)
    return fig


@_register("adaptive_vs_freecad_corpus", "jacso2021",
           "Adaptive planner vs FreeCAD Adaptive on the 71-pocket corpus: ratios per family against the targets")
def adaptive_vs_freecad_corpus(rows=None):
    return corpus.distribution_figure(corpus.load_rows() if rows is None else rows)
