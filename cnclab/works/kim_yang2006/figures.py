"""Figure recipes of kim_yang2006: each draws one figure of the collection from the package alone.

Registered in :data:`cnclab.plotting.FIGURES` (``python -m cnclab figure --list``); the notebooks
call :func:`draw` (the same recipe), so a notebook figure and a paper figure cannot differ.
Kept per work so that a notebook depends only on its own work's recipes (``make reproduce`` keys).

>>> sorted(n for n, r in FIGURES.items() if r.work == "kim_yang2006")[:1]
['fig2_offsets_pocket_120x85']
"""
from __future__ import annotations

import numpy as np

from . import constant_mrr_pocket as ky
from ...plotting import FIGURES, draw_figure as draw, figsize, register_figure as _register

__all__ = ["draw"]

@_register("fig2_offsets_pocket_120x85", "kim_yang2006",
           "Kim & Yang (2006) Fig 2: the offset levels of the 120 x 85 mm pocket")
def fig2_offsets_pocket_120x85():
    import matplotlib.pyplot as plt

    levels, pocket = ky.offset_levels(), ky.pocket()
    fig, ax = plt.subplots(figsize=figsize(1.1, 1.2))
    ax.fill(*pocket.exterior.xy, color="0.9")
    for ring in pocket.interiors:
        ax.fill(*ring.xy, color="white")
    for k, loops in enumerate(levels):
        for lp in loops:
            ax.plot(lp[:, 0], lp[:, 1], color=plt.cm.viridis(k / len(levels)), lw=1)
    ax.set(aspect="equal", xlabel="x [mm]", ylabel="y [mm]",
           title=f"{len(levels)} offset levels, loops per level {[len(lv) for lv in levels]}")
    return fig
