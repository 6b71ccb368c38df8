"""Figure style, size and export shared by every notebook and by ``python -m cnclab figure``.

* :func:`use_style` activates the collection's style sheet ``cnclab/paper.mplstyle`` (fonts, line
  widths, the default figure size ``figure.figsize``);
* :func:`figsize` gives a figure size in units of the style's default size, so notebooks never
  hard-code inches and a new style sheet resizes every figure;
* :func:`export_figure` writes a figure for a paper: into any folder, at a journal width in mm
  (:data:`WIDTH_PRESETS_MM`: ``"column"`` 85 mm, ``"page"`` 175 mm) and height, in any formats, dpi,
  under a style sheet (the collection's by default); :func:`savefig` is the notebooks' shortcut to
  ``build/figures/<work>/``.

>>> import matplotlib; matplotlib.use("Agg")
>>> import matplotlib.pyplot as plt
>>> use_style()
>>> figsize(2, 1) == (12.0, 3.8)                  # two panels of the style's 6.0 x 3.8 in
True
>>> fig, ax = plt.subplots(figsize=figsize()); _ = ax.plot([0, 1], [0, 1])
>>> paths = savefig(fig, "doctest_line", "mgherony2024", formats=SAVE_FORMATS)   # under build/figures/
>>> sorted(p.suffix for p in paths)                 # the default, except in fast mode (a PNG alone)
['.pdf', '.png', '.svg']
>>> import tempfile
>>> [p] = export_figure(fig, "doctest_line", tempfile.mkdtemp(), width_mm="column", formats=("pdf",))
>>> round(pdf_page_size_pt(p)[0], 1)               # 85 mm = 240.9 pt
240.9
"""
from __future__ import annotations

import dataclasses
import io
import re
from pathlib import Path
from typing import Callable

from .fileio import atomic_write
from .paths import PACKAGE_DIR, figures_dir
from .runtime import fast_mode

STYLE_PATH = PACKAGE_DIR / "paper.mplstyle"
#: journal figure widths (mm): one column and the full page width
WIDTH_PRESETS_MM = {"column": 85.0, "page": 175.0}


@dataclasses.dataclass(frozen=True)
class FigureRecipe:
    """A figure recipe: ``work`` (the reproduced work), ``description``, ``draw() -> Figure``."""

    work: str
    description: str
    draw: Callable


#: figure name (its stem in ``build/figures/<work>/``) -> :class:`FigureRecipe`; filled by the works'
#: ``figures`` modules when they are imported (``cnclab.figures`` imports them all).
FIGURES: dict[str, FigureRecipe] = {}


def register_figure(name: str, work: str, description: str):
    """Decorator: register a function drawing figure ``name`` of ``work`` and returning the figure.

    Called without arguments it computes what it draws (fast settings under ``CNCLAB_FAST=1``);
    a notebook that has computed the data already passes it by keyword (:func:`draw_figure`)."""
    def deco(f):
        FIGURES[name] = FigureRecipe(work, description, f)
        return f
    return deco


def draw_figure(name: str, style=None, **data):
    """Draw registered figure ``name`` under ``style`` (a style-sheet path or name; default the
    collection's ``paper.mplstyle``) and return the matplotlib figure; ``data``: keyword arguments
    of the recipe (results a notebook has computed already, so they are not computed twice)."""
    import matplotlib.pyplot as plt

    if name not in FIGURES:
        raise ValueError(f"unknown figure {name!r}: covered are {', '.join(sorted(FIGURES))}")
    with plt.style.context(str(style or STYLE_PATH)):
        return FIGURES[name].draw(**data)


MM_PER_INCH = 25.4
_NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.\-]*$")
_MEDIABOX_RE = re.compile(rb"/MediaBox\s*\[\s*([-\d.]+)\s+([-\d.]+)\s+([-\d.]+)\s+([-\d.]+)\s*\]")


def use_style(style=None) -> None:
    """Activate a style sheet: ``style`` (a path or matplotlib style name), by default the packaged
    paper style ``cnclab/paper.mplstyle``."""
    import matplotlib.pyplot as plt

    plt.style.use(str(style or STYLE_PATH))


def figsize(width: float = 1.0, height: float = 1.0) -> tuple[float, float]:
    """Figure size (inches) ``width`` x ``height`` times the active style's ``figure.figsize``.

    ``plt.subplots(1, 2, figsize=figsize(2, 1))``: two panels side by side, each of the style's
    default size; change the style sheet and every figure follows.
    """
    import matplotlib as mpl

    w, h = mpl.rcParams["figure.figsize"]
    return (round(float(width) * w, 6), round(float(height) * h, 6))


def plan_view(*axes, **props):
    """Set each axis up as a plan view of the xy plane: equal aspect, ``x [mm]`` / ``y [mm]`` labels,
    then any further ``Axes.set`` properties (``title=...``). Accepts axes or arrays of axes.

    >>> import matplotlib; matplotlib.use("Agg"); import matplotlib.pyplot as plt
    >>> fig, axs = plt.subplots(1, 2)
    >>> plan_view(axs, title="pocket")
    >>> axs[1].get_xlabel(), axs[1].get_aspect(), axs[0].get_title()
    ('x [mm]', 1.0, 'pocket')
    >>> plt.close(fig)
    """
    import numpy as np

    for ax in np.ravel(np.array(axes, dtype=object)):
        ax.set(aspect="equal", xlabel="x [mm]", ylabel="y [mm]", **props)


def with_style(func=None, *, style=None):
    """Decorator: draw a figure function under a style sheet (``style``, default the collection's
    ``paper.mplstyle``), so fonts and :func:`figsize` follow the style outside a notebook too (the
    ``analyze`` command's figures). Does not import pyplot.

    >>> @with_style
    ... def size():
    ...     return figsize(2, 1)
    >>> size()
    (12.0, 3.8)
    """
    import functools

    def deco(f):
        @functools.wraps(f)
        def wrapper(*args, **kwargs):
            import matplotlib.style

            with matplotlib.style.context(str(style or STYLE_PATH)):
                return f(*args, **kwargs)
        return wrapper

    return deco(func) if func is not None else deco


#: smallest text size (pt) :func:`fit_text` shrinks to: legible in print (journals ask for 6-8 pt)
MIN_FONT_PT = 6.0


def _ticklabels_in_view(ax):
    out = []
    for axis, lim in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
        lo, hi = sorted(lim)
        eps = 1e-9 * max(1.0, abs(lo), abs(hi))
        # the ticks drawn are the first len(locs) ones (an axis keeps spare ticks from earlier draws)
        drawn = [*axis.get_major_ticks(len(axis.get_majorticklocs())),
                 *axis.get_minor_ticks(len(axis.get_minorticklocs()))]
        for tick in drawn:
            if lo - eps <= tick.get_loc() <= hi + eps:
                out += [t for t in (tick.label1, tick.label2) if t.get_visible() and t.get_text().strip()]
    return out


def _layout_texts(fig):
    """(axes index, text) of every title, axis label and tick label in view of the shown axes."""
    out = []
    for i, ax in enumerate(fig.axes):
        if ax.get_visible() and ax.axison:
            texts = [ax.title, ax.xaxis.label, ax.yaxis.label, *_ticklabels_in_view(ax)]
            out += [(i, t) for t in texts if t.get_visible() and t.get_text().strip()]
    return out


def text_clashes(fig, tol_pt: float = 0.5) -> list[str]:
    """Texts of ``fig``'s 2D axes (titles, axis labels, tick labels in view, legends) that leave the page or overlap
    another title/label/tick label by more than ``tol_pt`` (points) both ways, after laying the figure
    out at its current size. Empty: every text is readable.

    >>> import matplotlib; matplotlib.use("Agg")
    >>> import matplotlib.pyplot as plt
    >>> fig, ax = plt.subplots(layout="constrained"); fig.set_size_inches(2.0, 2.0)   # a 2-inch test page
    >>> _ = ax.set_title("a title much wider than the two inches of this page")
    >>> text_clashes(fig)
    ["axes 0: 'a title much wider than the two inches of this page' leaves the page"]
    >>> _ = ax.set_title("short"); text_clashes(fig)
    []
    >>> plt.close(fig)
    """
    fig.draw_without_rendering()
    px = fig.dpi / 72.0 * tol_pt
    page = fig.bbox
    texts = [(i, t, t.get_window_extent()) for i, t in _layout_texts(fig)]
    texts += [(i, ax.get_legend(), ax.get_legend().get_window_extent()) for i, ax in enumerate(fig.axes)
              if ax.get_visible() and ax.get_legend() is not None]
    out = []
    for i, t, b in texts:
        if b.x0 < page.x0 - px or b.x1 > page.x1 + px or b.y0 < page.y0 - px or b.y1 > page.y1 + px:
            out.append(f"axes {i}: {getattr(t, 'get_text', lambda: 'legend')()!r} leaves the page")
    texts = [x for x in texts if hasattr(x[1], "get_text")]
    for k, (i, t, b) in enumerate(texts):
        for j, u, c in texts[k + 1:]:
            if min(b.x1, c.x1) - max(b.x0, c.x0) > px and min(b.y1, c.y1) - max(b.y0, c.y0) > px:
                out.append(f"axes {i}: {t.get_text()!r} overlaps axes {j}: {u.get_text()!r}")
    return out


def fit_text(fig, min_pt: float = MIN_FONT_PT, step: float = 0.9, max_rounds: int = 15) -> list[str]:
    """Shrink the texts of ``fig`` by ``step`` per round (none below ``min_pt`` points; smaller ones
    are kept) until :func:`text_clashes` finds nothing or every text is at ``min_pt``; returns the
    clashes left (empty: fitted). Used by :func:`export_figure` at a journal width, where a figure
    drawn for a 6-inch notebook page must fit 85 mm with its fonts in points unchanged elsewhere."""
    import matplotlib.text as mtext

    if not (0 < step < 1 and min_pt > 0):
        raise ValueError(f"step must be in (0, 1) and min_pt > 0, got {step!r}, {min_pt!r}")
    clashes = text_clashes(fig)
    for _ in range(max_rounds):
        if not clashes:
            break
        changed = False
        ticks = set()          # tick labels shrink through the axis (new ticks take its size), the rest one by one
        for ax in fig.axes:
            for axis in (ax.xaxis, ax.yaxis):
                labels = [t for tk in [*axis.get_major_ticks(), *axis.get_minor_ticks()]
                          for t in (tk.label1, tk.label2)]
                ticks.update(map(id, labels))
                size = labels[0].get_fontsize() if labels else None
                if size is not None and size > min_pt:
                    axis.set_tick_params(which="both", labelsize=max(min_pt, size * step))
                    changed = True
        for t in fig.findobj(mtext.Text):
            if id(t) not in ticks and t.get_fontsize() > min_pt:
                t.set_fontsize(max(min_pt, t.get_fontsize() * step))
                changed = True
        if not changed:
            break
        clashes = text_clashes(fig)
    return clashes


def _mm(value, name: str):
    if value is None:
        return None
    if isinstance(value, str):
        if value not in WIDTH_PRESETS_MM:
            raise ValueError(f"{name} must be a number (mm) or one of {sorted(WIDTH_PRESETS_MM)}, got {value!r}")
        return WIDTH_PRESETS_MM[value]
    v = float(value)
    if not (v > 0 and v < 5000):
        raise ValueError(f"{name} must be in (0, 5000) mm, got {value!r}")
    return v


def export_figure(fig, name: str, outdir, *, width_mm=None, height_mm=None, formats=("pdf", "svg", "png"),
                  dpi: int = 300, style=None, fit: bool = True) -> list[Path]:
    """Write ``fig`` as ``outdir/<name>.<format>`` for each format, atomically; returns the paths.

    Parameters
    ----------
    fig : a matplotlib figure.
    name : file stem (letters, digits, '_', '-', '.'), e.g. ``"fig3-5_rz_ra_ratio"``.
    outdir : output folder (created if missing).
    width_mm : page width of the figure in mm, or a preset of :data:`WIDTH_PRESETS_MM` (``"column"``
        85 mm, ``"page"`` 175 mm). None: the figure's own size, cropped to its content (the style's
        ``savefig.bbox: tight``). With a width, the page is exactly ``width_mm`` x ``height_mm``
        (constrained layout inside it; the figure is resized).
    height_mm : page height in mm; None keeps the figure's aspect ratio.
    formats : any of matplotlib's formats ('pdf', 'svg', 'png', 'eps', ...).
    dpi : resolution of raster formats (dots per inch).
    style : style sheet (path or name) active while saving (its ``savefig.*``, ``pdf.fonttype``, ...);
        None: the collection's ``paper.mplstyle``. Text sizes are set when a figure is drawn, so a
        figure drawn under another style is best re-drawn: ``python -m cnclab figure NAME --style S``.
    fit : with a width: shrink texts that leave the page or overlap at that size (:func:`fit_text`,
        down to :data:`MIN_FONT_PT`); the figure's texts keep their size where they fit.

    PDF and SVG carry no date, so identical figures give identical files.
    """
    import matplotlib as mpl
    import matplotlib.pyplot as plt

    if not _NAME_RE.match(name):
        raise ValueError(f"figure name {name!r}: use letters, digits, '_', '-', '.' only")
    w, h = _mm(width_mm, "width_mm"), _mm(height_mm, "height_mm")
    if not (isinstance(dpi, (int, float)) and 10 <= dpi <= 10000):
        raise ValueError(f"dpi must be in [10, 10000], got {dpi!r}")
    outdir = Path(outdir)
    blobs = []
    with plt.style.context(str(style or STYLE_PATH)):
        if w is not None:
            old_w, old_h = fig.get_size_inches()
            h_in = h / MM_PER_INCH if h is not None else w / MM_PER_INCH * old_h / old_w
            fig.set_size_inches(w / MM_PER_INCH, h_in)
            if fig.get_layout_engine() is None or type(fig.get_layout_engine()).__name__ == "PlaceHolderLayoutEngine":
                fig.set_layout_engine("constrained")
            for ax in fig.axes:       # a legend inside an axes at column width must not collapse the layout
                if ax.get_legend() is not None and ax.axison:       # (an axis-off legend panel keeps its room)
                    ax.get_legend().set_in_layout(False)
            mpl.rcParams["savefig.bbox"] = "standard"   # no cropping: the page is exactly the requested size
            if fit:
                fit_text(fig)
        for fmt in formats:
            buf = io.BytesIO()
            meta = {"pdf": {"CreationDate": None}, "svg": {"Date": None}}.get(fmt)
            fig.savefig(buf, format=fmt, dpi=dpi, metadata=meta)
            blobs.append((outdir / f"{name}.{fmt}", buf.getvalue()))
    outdir.mkdir(parents=True, exist_ok=True)
    return [atomic_write(path, data) for path, data in blobs]


#: what :func:`savefig` writes by default: PDF, SVG and PNG at 300 dpi (``make reproduce``)
SAVE_FORMATS, SAVE_DPI = ("pdf", "svg", "png"), 300
#: ... and in fast mode (``CNCLAB_FAST=1``: ``make test`` runs every notebook so): the PNG alone at
#: 100 dpi. The figure is still drawn and rasterised whole; the PDF and SVG writers and the 300 dpi
#: PNG are tested on their own (tests/test_figures.py, tests/test_claims_machinery.py). Writing
#: the three formats took 95 of the notebooks' 280 CPU s in fast mode (56 figures, 2026-11-28).
FAST_SAVE_FORMATS, FAST_SAVE_DPI = ("png",), 100


def savefig(fig, name: str, work: str, formats=None, dpi: int | None = None) -> list[Path]:
    """Save ``fig`` as ``build/figures/<work>/<name>.<format>``, atomically: :func:`export_figure`
    into the collection's figure folder at the figure's own size.

    ``formats`` / ``dpi`` (raster formats, dots per inch): None gives :data:`SAVE_FORMATS` at
    :data:`SAVE_DPI` (PDF, SVG and PNG at 300 dpi), in fast mode (``CNCLAB_FAST=1``)
    :data:`FAST_SAVE_FORMATS` at :data:`FAST_SAVE_DPI` (a 100 dpi PNG).
    ``name`` should say which seed figure it reproduces, e.g. ``"fig3-5_rz_ra_ratio"``.
    Returns the written paths.
    """
    fast = fast_mode()
    if formats is None:
        formats = FAST_SAVE_FORMATS if fast else SAVE_FORMATS
    if dpi is None:
        dpi = FAST_SAVE_DPI if fast else SAVE_DPI
    return export_figure(fig, name, figures_dir(work), formats=formats, dpi=dpi)


def pdf_page_size_pt(path) -> tuple[float, float]:
    """(width, height) of the first page of a PDF in points (1/72 in), from its ``/MediaBox``."""
    m = _MEDIABOX_RE.search(Path(path).read_bytes())
    if not m:
        raise ValueError(f"{path}: no /MediaBox found (not a PDF written by matplotlib?)")
    x0, y0, x1, y1 = (float(v) for v in m.groups())
    return (x1 - x0, y1 - y0)
