"""Figure recipes: re-render a figure of the collection for a paper without running its notebook.

:data:`FIGURES` maps a figure name (the stem ``savefig`` gives it in ``build/figures/<work>/``) to a
recipe: its work, a one-line description and a function that draws the figure from the package
alone. :func:`draw` runs a recipe under a style sheet (the collection's ``paper.mplstyle`` by
default: fonts and line widths are fixed when a figure is drawn); :func:`render` draws and exports
it with :func:`cnclab.plotting.export_figure` (width/height in mm, formats, dpi). The notebooks that
show these figures call the same recipes, so the notebook and the paper figure cannot differ.

``python -m cnclab figure NAME --width-mm 85 --format pdf -o DIR`` is the command line;
``python -m cnclab figure --list`` lists the covered figures: every figure the notebooks save
(tests/test_figures.py checks each jacso2021, kim_yang2006 and hoang2024 notebook's ``savefig`` against
its recipe, tests/test_figures_mgherony.py the mgherony2024 ones). At a given width the texts that
would leave the page or run into each other are shrunk (:func:`cnclab.plotting.fit_text`, >= 6 pt).

>>> FIGURES["fig5-6_deff_vs_depth_of_cut"].work
'mgherony2024'
"""
from __future__ import annotations

import sys
from pathlib import Path

from . import clihelp
from .paths import build_dir
from .plotting import FIGURES, WIDTH_PRESETS_MM, FigureRecipe as Recipe, draw_figure as draw, export_figure
from .works.hoang2024 import figures as _hoang2024  # noqa: F401  (each import registers its recipes)
from .works.jacso2021 import figures as _jacso2021  # noqa: F401
from .works.jacso2021 import figures_pockets as _jacso2021_pockets  # noqa: F401
from .works.kim_yang2006 import figures as _kim_yang2006  # noqa: F401
from .works.mgherony2024 import figures as _mgherony2024  # noqa: F401

__all__ = ["FIGURES", "Recipe", "draw", "render", "main"]


def render(name: str, outdir=None, *, width_mm=None, height_mm=None, formats=("pdf",), dpi: int = 300,
           style=None) -> list[Path]:
    """Draw figure ``name`` and export it (:func:`cnclab.plotting.export_figure`) into ``outdir``
    (default ``build/paper/<work>/``); returns the written paths."""
    import matplotlib.pyplot as plt

    fig = draw(name, style)
    try:
        outdir = Path(outdir) if outdir is not None else build_dir() / "paper" / FIGURES[name].work
        return export_figure(fig, name, outdir, width_mm=width_mm, height_mm=height_mm, formats=formats,
                             dpi=dpi, style=style)
    finally:
        plt.close(fig)


def _size(text: str):
    if text in WIDTH_PRESETS_MM:
        return text
    return clihelp.number("--width-mm/--height-mm", 0, hi=5000)(text)


def main(argv=None) -> int:
    ap = clihelp.parser(
        "python -m cnclab figure",
        "Re-render a figure of the collection from its recipe (no notebook is run) at a journal width,\n"
        "in the formats and resolution a paper needs, under the collection's style sheet or your own.\n"
        "Widths: a number of mm or 'column' (85 mm) / 'page' (175 mm); the height keeps the figure's\n"
        "aspect ratio unless given. --list shows the figures covered.",
        examples=["python -m cnclab figure fig3-1_engagement_vs_stepover --width-mm 85 --format pdf -o build/paper",
                  "python -m cnclab figure fig6-2_main_effects --width-mm page --height-mm 60 --format pdf,png "
                  "--dpi 600", "python -m cnclab figure --list"],
        writes=["DIR/NAME.FORMAT for every format (default DIR: build/paper/<work>)"])
    ap.add_argument("names", nargs="*", metavar="NAME", help="figure name(s), see --list")
    ap.add_argument("--list", action="store_true", help="list the figures that have a recipe")
    ap.add_argument("--width-mm", type=_size, default=None,
                    help="page width: mm, 'column' (85) or 'page' (175) (default: the figure's own size, cropped)")
    ap.add_argument("--height-mm", type=_size, default=None, help="page height in mm (default: keep the aspect ratio)")
    ap.add_argument("--format", default="pdf", help="comma-separated formats: pdf, svg, png, eps, ...")
    ap.add_argument("--dpi", type=clihelp.number("--dpi", 10, lo_open=False, hi=10000, kind=int), default=300,
                    help="resolution of raster formats (dots per inch)")
    ap.add_argument("--style", default=None,
                    help="matplotlib style sheet (path or name) (default: cnclab/paper.mplstyle)")
    ap.add_argument("-o", "--outdir", default=None, help="output folder (default: build/paper/<work>)")
    args = ap.parse_args(argv)
    if args.list or not args.names:
        for name, rec in sorted(FIGURES.items()):
            print(f"{name:<34} {rec.work:<13} {rec.description}")
        return 0 if args.list else 2
    formats = tuple(f.strip() for f in args.format.split(",") if f.strip())
    if args.height_mm is not None and args.width_mm is None:
        ap.error("--height-mm needs --width-mm")
    written = []
    try:
        for name in args.names:
            written += render(name, args.outdir, width_mm=args.width_mm, height_mm=args.height_mm, formats=formats,
                              dpi=args.dpi, style=args.style)
    except (ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print("wrote " + ", ".join(str(p) for p in written))
    return 0
