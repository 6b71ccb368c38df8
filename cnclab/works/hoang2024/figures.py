"""Hoang (2024), constant-volume zig-zag: Table 2's forward step, the Table 3 programs and the uncut
volume against a height-field simulation, drawn from :mod:`.constant_volume` alone.

>>> FIGURES["fig7_zigzag_table3"].work
'hoang2024'
"""
from __future__ import annotations

import numpy as np

from . import constant_volume as cv
from ...cutting import scallop_volume as sv
from ...nc import gcode
from ...plotting import FIGURES, draw_figure as draw, figsize, register_figure as _register
from ...runtime import pick

__all__ = ["draw", "uncut_resolution_mm"]


@_register("table2_fr_printed_vs_consistent", "hoang2024",
           "Hoang (2024) Table 2: forward step F_r as printed and unit-consistent; curvature volume V_RT")
def table2_fr_printed_vs_consistent():
    import matplotlib.pyplot as plt

    printed, re = cv.table2_printed(), cv.table2_recomputed()
    fig, axs = plt.subplots(1, 2, figsize=figsize(1.5, 1.2), layout="constrained")
    x = np.arange(1, 9)
    axs[0].semilogy(x, printed.Fr_mm, "o-", label="printed F_r (slip)")
    axs[0].semilogy(x, re.Fr_consistent, "s-", label="unit-consistent F_r, eq. 7")
    axs[0].semilogy(x, re.Fr_v2, "^--", label="F_r from V2, eq. 4")
    axs[0].set(xlabel="Table 2 row", ylabel="F_r [mm]", title="forward step")
    th, R = re.theta_rad.to_numpy(), re.RT.to_numpy()
    axs[1].bar(x - 0.2, 0.5 * R**2 * (3.14 * th / 180 - np.sin(th)), 0.4, label="V_RT with slip")
    axs[1].bar(x + 0.2, sv.curvature_volume(th, R), 0.4, label="V_RT consistent")
    axs[1].set(xlabel="Table 2 row", ylabel="V_RT [mm²]", title="curvature volume")
    handles, labels = (sum(x, []) for x in zip(*(ax.get_legend_handles_labels() for ax in axs)))
    fig.legend(handles, labels, loc="outside lower center", ncol=2, fontsize=7, columnspacing=0.8)
    return fig


@_register("fig7_zigzag_table3", "hoang2024",
           "Hoang (2024) Fig 7 / Table 3: the covering zig-zag (52 passes) and the Table 1 loop as printed (50)")
def fig7_zigzag_table3():
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(1, 2, figsize=figsize(1.5, 0.85), sharey=True)
    for ax, covering, title in ((axs[0], True, "covering: 52 passes"), (axs[1], False, "Table 1 loop: 50 passes")):
        pts, rapid = gcode.to_polyline(cv.table3_program(covering=covering, decimals=3)[0])
        ax.plot(pts[:, 0], pts[:, 1], lw=0.4)
        ax.plot(pts[rapid, 0], pts[rapid, 1], "r--", lw=0.8)
        ax.axhline(50, color="k", lw=0.6, ls=":")
        ax.set(title=title, xlabel="x [mm]", xlim=(-5, 105))
    axs[0].set_ylabel("y [mm]")
    return fig


def uncut_resolution_mm() -> float:
    """z-map cell (mm) of the uncut-volume study: 0.004 (fast mode 0.01)."""
    return pick(0.004, 0.01)


@_register("uncut_volume_formulas_vs_heightfield", "hoang2024",
           "Hoang (2024) eqs 1, 2, 4 against the uncut volume of a ball-end height-field simulation, per Table 2 row")
def uncut_volume_formulas_vs_heightfield():
    import matplotlib.pyplot as plt

    tab = cv.uncut_volume_table(uncut_resolution_mm())
    fig, ax = plt.subplots(figsize=figsize(1, 0.9))
    ax.set_title("cell: S_z × F_r", fontsize=8)
    x = np.arange(1, 9)
    for col, m in (("V1", "o"), ("V1_star", "s"), ("V2", "^"), ("heightfield_sweep", "x"), ("heightfield_discrete", "d")):
        ax.semilogy(x, tab[col], m + "-", label=col)
    ax.set(xlabel="Table 2 row (printed F_r)", ylabel="uncut volume per cell [mm³]")
    ax.legend(fontsize=7)
    return fig
