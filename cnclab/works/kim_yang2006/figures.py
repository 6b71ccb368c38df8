"""Kim & Yang (2006) pocket: the drawing of every figure its two notebooks save (Fig 2, 10/11, 13, and the
constant-MRR against constant-engagement comparison). Each recipe computes what it draws (fast
settings under ``CNCLAB_FAST=1``) through the work's cached functions, so the notebook and
``python -m cnclab figure`` share one computation per process.

>>> FIGURES["fig13_spindle_current_assumed"].description.startswith("Kim & Yang")
True
"""
from __future__ import annotations

import numpy as np

from . import ce_comparison as cx
from . import constant_mrr_pocket as ky
from ...nc import gcode
from ...plotting import FIGURES, draw_figure as draw, figsize, plan_view, register_figure as _register
from ...toolpath import constant_mrr as cm

__all__ = ["draw"]


def _pocket(ax):
    ax.fill(*ky.pocket().exterior.xy, color="0.93")
    for ring in ky.pocket().interiors:
        ax.fill(*ring.xy, color="white")


@_register("fig2_offsets_pocket_120x85", "kim_yang2006",
           "Kim & Yang (2006) Fig 2: the offset levels of the 120 x 85 mm pocket")
def fig2_offsets_pocket_120x85():
    import matplotlib.pyplot as plt

    levels = ky.offset_levels()
    fig, ax = plt.subplots(figsize=figsize(1.1, 1.2))
    _pocket(ax)
    for k, loops in enumerate(levels):
        for lp in loops:
            ax.plot(lp[:, 0], lp[:, 1], color=plt.cm.viridis(k / len(levels)), lw=1)
    plan_view(ax, title=f"{len(levels)} offset levels, loops per level {[len(lv) for lv in levels]}")
    return fig


@_register("fig10_11_original_vs_modified", "kim_yang2006",
           "Kim & Yang (2006) Figs 10-11: original and §3.2-modified contour-parallel paths, inserted segments red")
def fig10_11_original_vs_modified():
    import matplotlib.pyplot as plt

    mod = ky.modified()
    fig, axs = plt.subplots(1, 2, figsize=figsize(1.85, 1.1))
    for ax, which in zip(axs, ("original", "modified")):
        pts, _ = gcode.to_polyline(ky.program(which)[0], max_segment=0.5)
        cut = pts[:, 2] < 0
        ax.plot(np.where(cut, pts[:, 0], np.nan), np.where(cut, pts[:, 1], np.nan), lw=0.5)
        ax.set(aspect="equal", title=f"{which} path", xlabel="x [mm]")
    for p, f in zip(mod.passes, mod.inserted):
        axs[1].plot(np.where(f, p[:, 0], np.nan), np.where(f, p[:, 1], np.nan), "r.", ms=1)
    return fig


@_register("fig13_spindle_current_assumed", "kim_yang2006",
           "Kim & Yang (2006) Fig 13 analogue: spindle current from the simulated MRR (pixel 0.3 mm), assumed eq. 6")
def fig13_spindle_current_assumed():
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(2, 1, figsize=figsize(1.65, 1.45), sharey=True, layout="constrained")
    for ax, which in zip(axs, ("original", "modified")):
        d = ky.mrr_trace(which, "pixel")
        ax.plot(d.s, cm.spindle_current(d.mrr_mm3_min.rolling(3, center=True).mean()), lw=0.5)
        ax.set(title=which)
        ax.axhline(float(cm.spindle_current(ky.nominal_mrr())), color="k", ls=":", lw=0.8)
    axs[1].set_xlabel("cutting path length s [mm]")
    fig.supylabel("I_M [A] (assumed eq. 6)", fontsize=9)
    return fig


@_register("ce_vs_cmrr_paths", "kim_yang2006",
           "Kim & Yang pocket: the constant-MRR paths and two constant-engagement clearings, samples above θ + 5° red")
def ce_vs_cmrr_paths():
    import matplotlib.pyplot as plt

    theta = cx.theta_deg()
    fig, axs = plt.subplots(2, 2, figsize=figsize(2.15, 2.2), sharex=True, sharey=True, layout="constrained")
    for ax, w in zip(axs.flat, cx.PATHS):
        _pocket(ax)
        path = cx.path(w)
        for kind, col in {"helix": "g", "cut": "C0", "link": "0.75"}.items():
            m = path.is_kind(kind) & (path.xyz[:, 2] < 0)
            ax.plot(np.where(m, path.xyz[:, 0], np.nan), np.where(m, path.xyz[:, 1], np.nan), color=col, lw=0.5)
        T = cx.trace_table(w)
        hi = T[T.cutting & (T.engagement_deg > theta + 5)]
        ax.plot(hi.x, hi.y, "r.", ms=0.8)
        ax.set(aspect="equal", title=w)
    fig.suptitle("red: engagement > θ + 5°", fontsize=9)
    fig.supxlabel("x [mm]", fontsize=9)
    return fig


@_register("ce_vs_cmrr_traces", "kim_yang2006",
           "Kim & Yang pocket: engagement and MRR / nominal along the four paths (one dixel evaluator)")
def ce_vs_cmrr_traces():
    import matplotlib.pyplot as plt

    theta = cx.theta_deg()
    fig, axs = plt.subplots(len(cx.PATHS), 2, figsize=figsize(2.15, 2.65), sharex="row", sharey="col",
                            layout="constrained")
    for row, w in zip(axs, cx.PATHS):
        T = cx.trace_table(w)
        C = T[T.cutting]
        s = np.cumsum(C.ds)
        row[0].plot(s, C.engagement_deg, lw=0.4)
        row[0].axhline(theta + 5, color="r", ls=":", lw=0.8)
        row[1].plot(s, C.mrr_mm3_min.rolling(10, center=True).mean() / ky.nominal_mrr(), lw=0.4)
        row[1].axhline(1.0, color="k", ls=":", lw=0.8)
        row[0].text(0.01, 0.97, w, transform=row[0].transAxes, va="top", fontsize=7,
                    bbox=dict(fc="white", ec="none", pad=0.5, alpha=0.8))
    axs[0, 0].set_title("engagement [deg]")
    axs[0, 1].set_title("MRR / nominal")
    fig.supxlabel("cutting length [mm]", fontsize=9)
    return fig
