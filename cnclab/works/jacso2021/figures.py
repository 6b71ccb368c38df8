"""Figure recipes of jacso2021: each draws one figure of the collection from the package alone.

Registered in :data:`cnclab.plotting.FIGURES` (``python -m cnclab figure --list``); the notebooks
call :func:`draw` (the same recipe), so a notebook figure and a paper figure cannot differ.
Kept per work so that a notebook depends only on its own work's recipes (``make reproduce`` keys).

>>> sorted(n for n, r in FIGURES.items() if r.work == "jacso2021")[:1]
['fig3-1_engagement_vs_stepover']
"""
from __future__ import annotations

import numpy as np

from ...geometry import engagement as eng
from ...plotting import FIGURES, draw_figure as draw, figsize, register_figure as _register

__all__ = ["draw"]

@_register("fig3-1_engagement_vs_stepover", "jacso2021",
           "Jacsó (2021) Fig 3-1: engagement angle against stepover, straight and on arcs (r = 3 mm)")
def fig3_1_engagement_vs_stepover(r: float = 3.0):
    import matplotlib.pyplot as plt

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
