"""Figure recipes of hoang2024: each draws one figure of the collection from the package alone.

Registered in :data:`cnclab.plotting.FIGURES` (``python -m cnclab figure --list``); the notebooks
call :func:`draw` (the same recipe), so a notebook figure and a paper figure cannot differ.
Kept per work so that a notebook depends only on its own work's recipes (``make reproduce`` keys).

>>> sorted(n for n, r in FIGURES.items() if r.work == "hoang2024")[:1]
['table2_fr_printed_vs_consistent']
"""
from __future__ import annotations

import numpy as np

from ...cutting import scallop_volume as sv
from . import constant_volume as cv
from ...plotting import FIGURES, draw_figure as draw, figsize, register_figure as _register

__all__ = ["draw"]

@_register("table2_fr_printed_vs_consistent", "hoang2024",
           "Hoang (2024) Table 2: forward step F_r as printed and unit-consistent; curvature volume V_RT")
def table2_fr_printed_vs_consistent():
    import matplotlib.pyplot as plt

    printed, re = cv.table2_printed(), cv.table2_recomputed()
    fig, axs = plt.subplots(1, 2, figsize=figsize(1.5, 0.9))
    x = np.arange(1, 9)
    axs[0].semilogy(x, printed.Fr_mm, "o-", label="printed F_r (slip)")
    axs[0].semilogy(x, re.Fr_consistent, "s-", label="unit-consistent F_r, eq. 7")
    axs[0].semilogy(x, re.Fr_v2, "^--", label="F_r from V2, eq. 4")
    axs[0].set(xlabel="Table 2 row", ylabel="forward step F_r [mm]")
    axs[0].legend(fontsize=7)
    th, R = re.theta_rad.to_numpy(), re.RT.to_numpy()
    axs[1].bar(x - 0.2, 0.5 * R**2 * (3.14 * th / 180 - np.sin(th)), 0.4, label="V_RT with slip")
    axs[1].bar(x + 0.2, sv.curvature_volume(th, R), 0.4, label="V_RT consistent")
    axs[1].set(xlabel="Table 2 row", ylabel="V_RT [mm²]")
    axs[1].legend(fontsize=7)
    return fig
