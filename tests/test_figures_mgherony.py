"""Mgherony (2024) figures for papers: every figure a Mgherony notebook saves has a recipe, and every recipe
re-renders without its notebook to an 85 mm PDF (fast mode: 1 mm STL/CL resolution, 2 networks x 100
epochs, shared with the notebooks through the functools and on-disk caches)."""
import json
import re
import warnings

import matplotlib.pyplot as plt
import matplotlib.text as mtext
import pytest

from cnclab import figures, plotting
from cnclab.paths import NOTEBOOKS_DIR

WORK = "mgherony2024"
NB_DIR = NOTEBOOKS_DIR / WORK
MM_PER_INCH = 25.4
TOL_PT = 0.5        # the page size is written with 10+ significant digits; 0.5 pt = 0.18 mm is generous
NAMES = sorted(n for n, r in figures.FIGURES.items() if r.work == WORK)
SAVE_RE = re.compile(r"""savefig\(\s*(\w+)\s*,\s*["']([^"']+)["']""")
DRAW_RE = re.compile(r"""figures\.draw\(\s*["']([^"']+)["']\s*\)""")


def _code_cells():
    for nb in sorted(NB_DIR.glob("*.ipynb")):
        for i, cell in enumerate(json.loads(nb.read_text(encoding="utf-8"))["cells"]):
            if cell["cell_type"] == "code":
                yield nb.name, i, "".join(cell["source"])


def test_every_saved_figure_is_drawn_by_its_registered_recipe():
    saved = {}
    for nb, i, src in _code_cells():
        drawn = DRAW_RE.findall(src)
        for var, name in SAVE_RE.findall(src):
            saved[name] = nb
            assert name in NAMES, f"{nb} cell {i} saves {name!r}, which has no recipe in cnclab.figures"
            assert name in drawn, f"{nb} cell {i} saves {name!r} but does not draw it with figures.draw({name!r})"
        # plotting lives in the package: no notebook cell builds a matplotlib figure itself
        assert not re.search(r"\bplt\.|subplots\(|Figure\(", src), f"{nb} cell {i} draws a figure itself"
    assert len(saved) >= 30
    # and the other way round: no recipe without the notebook figure it re-renders
    assert sorted(saved) == NAMES


def test_notebooks_import_only_their_chapters_recipes():
    # make reproduce keys a notebook on the modules it imports: ch. 3-5 notebooks must not depend on
    # the networks (ch6) or the drop-cutter pipeline (ch7_9) through an all-chapters figures module
    for nb, _, src in _code_cells():
        assert "import figures\n" not in src and not src.rstrip().endswith("import figures"), nb


@pytest.mark.parametrize("name", NAMES)
def test_recipe_renders_an_85_mm_pdf(tmp_path, name):
    fig = figures.draw(name)
    try:
        # Fig 6-3's diagonal carries only the factor name (axis off); a 3D axes draws its own axes (axison False)
        shown = [ax for ax in fig.axes if ax.axison or ax.name == "3d"]
        assert shown and all(ax.has_data() for ax in shown), [ax.get_title() for ax in shown if not ax.has_data()]
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            [p] = plotting.export_figure(fig, name, tmp_path, width_mm=85, formats=("pdf",))
        assert not [w for w in caught if "constrained_layout not applied" in str(w.message)]
        # readable at column width: no title/label/tick label/legend off the page or on another one,
        # no text below 6 pt unless the recipe drew it so
        assert plotting.text_clashes(fig) == []
        sizes = [t.get_fontsize() for t in fig.findobj(mtext.Text) if t.get_text().strip()]
        assert min(sizes) >= plotting.MIN_FONT_PT - 1e-9
    finally:
        plt.close(fig)
    w, h = plotting.pdf_page_size_pt(p)
    assert abs(w - 85 / MM_PER_INCH * 72) < TOL_PT          # 240.94 pt
    assert h >= 0.25 * w                                    # no strip: at most 4:1


def _two_titles(title):
    fig, axs = plt.subplots(1, 2, figsize=(6.0, 3.0))
    for ax in axs:
        ax.plot([0, 1], [0, 1])
        ax.set_title(title)
    return fig


def test_fit_text_shrinks_clashing_texts_to_the_floor_only(tmp_path):
    fig = _two_titles("a title long enough to run into its neighbour")
    [p] = plotting.export_figure(fig, "t", tmp_path, width_mm=85, formats=("pdf",), fit=False)
    assert plotting.text_clashes(fig)                       # at 85 mm the two 9 pt titles collide
    left = plotting.fit_text(fig, min_pt=6.0)
    sizes = [t.get_fontsize() for t in fig.findobj(mtext.Text) if t.get_text().strip()]
    assert min(sizes) >= 6.0 - 1e-9
    if not left:                                            # fitted: nothing clashes any more
        assert plotting.text_clashes(fig) == []
    else:                                                   # not fittable: every text is at the floor
        assert max(sizes) <= 6.0 + 1e-9
    plt.close(fig)
    assert abs(plotting.pdf_page_size_pt(p)[0] - 85 / MM_PER_INCH * 72) < TOL_PT


def test_fit_text_leaves_a_fitting_figure_alone():
    fig = _two_titles("short")
    before = [t.get_fontsize() for t in fig.findobj(mtext.Text)]
    assert plotting.fit_text(fig) == []
    assert [t.get_fontsize() for t in fig.findobj(mtext.Text)] == before
    plt.close(fig)
    with pytest.raises(ValueError, match="step"):
        plotting.fit_text(fig, step=1.5)
