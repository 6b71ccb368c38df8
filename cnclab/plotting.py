"""Figure style and export shared by every notebook.

>>> import matplotlib; matplotlib.use("Agg")
>>> import matplotlib.pyplot as plt
>>> use_style()
>>> fig, ax = plt.subplots(); _ = ax.plot([0, 1], [0, 1])
>>> paths = savefig(fig, "doctest_line", "mgherony2024")   # PDF, SVG, PNG under build/figures/
>>> sorted(p.suffix for p in paths)
['.pdf', '.png', '.svg']
"""
from __future__ import annotations

import io
import re
from pathlib import Path

from .fileio import atomic_write
from .paths import PACKAGE_DIR, figures_dir

STYLE_PATH = PACKAGE_DIR / "paper.mplstyle"
_NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.\-]*$")


def use_style() -> None:
    """Activate the packaged paper style (``cnclab/paper.mplstyle``)."""
    import matplotlib.pyplot as plt

    plt.style.use(str(STYLE_PATH))


def savefig(fig, name: str, work: str, formats=("pdf", "svg", "png"), dpi: int = 300) -> list[Path]:
    """Save ``fig`` as ``build/figures/<work>/<name>.{pdf,svg,png}`` (PNG at ``dpi``), atomically.

    ``name`` should say which seed figure it reproduces, e.g. ``"fig3-5_rz_ra_ratio"``.
    Returns the written paths.
    """
    if not _NAME_RE.match(name):
        raise ValueError(f"figure name {name!r}: use letters, digits, '_', '-', '.' only")
    out = []
    for fmt in formats:
        buf = io.BytesIO()
        meta = {"pdf": {"CreationDate": None}, "svg": {"Date": None}}.get(fmt)
        fig.savefig(buf, format=fmt, dpi=dpi if fmt == "png" else None, metadata=meta)
        out.append(atomic_write(figures_dir(work) / f"{name}.{fmt}", buf.getvalue()))
    return out
