"""Figure recipes of mgherony2024: every figure its notebooks draw, re-drawn from the package alone.

Importing this module registers all of them in :data:`cnclab.plotting.FIGURES` (``python -m cnclab
figure --list``). They live per chapter, so that a notebook depends only on its chapter's recipes
(``make reproduce`` keys a notebook on the modules it imports):

* :mod:`.figures_ch3_5` -- chapters 3-5 (cusp height and roughness, CV/CX parts, working diameter);
* :mod:`.figures_ch6` -- chapter 6 (data set, regressions, neural networks);
* :mod:`.figures_ch7_9` -- chapters 7-9 (spindle-speed control, feed directions, reordering).

The notebooks call :func:`draw` (the same recipe), so a notebook figure and a paper figure cannot differ.

>>> sorted(n for n, r in FIGURES.items() if r.work == "mgherony2024")[:1]
['ch3_cusp_approximation_error']
"""
from __future__ import annotations

from ...plotting import FIGURES, draw_figure as draw
from . import figures_ch3_5, figures_ch6, figures_ch7_9  # noqa: F401  (each import registers its recipes)

__all__ = ["FIGURES", "draw"]
