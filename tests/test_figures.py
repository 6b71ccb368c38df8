"""Figures for papers: export at a journal width in mm, sizes from the style, recipes re-rendered by
``python -m cnclab figure`` without a notebook."""
import re
from pathlib import Path

import matplotlib
import matplotlib.text
import matplotlib.pyplot as plt
import pytest

from cnclab import figures, plotting
from cnclab.paths import NOTEBOOKS_DIR

PT_PER_MM = 72 / 25.4
TOL_PT = 0.5        # the page size is written with 10+ significant digits; 0.5 pt = 0.18 mm is generous


def _line_figure():
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot([0, 1], [0, 1])
    ax.set(xlabel="x [mm]", ylabel="y [mm]")
    return fig


@pytest.mark.parametrize("width, height", [(85, None), ("column", None), ("page", 60), (120.5, 80)])
def test_pdf_page_is_the_requested_size(tmp_path, width, height):
    fig = _line_figure()
    [p] = plotting.export_figure(fig, "line", tmp_path, width_mm=width, height_mm=height, formats=("pdf",))
    plt.close(fig)
    w_mm = plotting.WIDTH_PRESETS_MM.get(width, width)
    w, h = plotting.pdf_page_size_pt(p)
    assert abs(w - w_mm * PT_PER_MM) < TOL_PT
    expected_h = (height if height is not None else w_mm * 4 / 6) * PT_PER_MM     # aspect kept without height
    assert abs(h - expected_h) < TOL_PT
    if width == 85:
        assert abs(w - 240.9) < TOL_PT


def test_formats_dpi_and_deterministic_output(tmp_path):
    # identical figures (each drawn afresh, as in two runs) give identical files; saving one figure
    # twice is not the property: its constrained layout may move a last bit between two draws
    figs = [_line_figure(), _line_figure()]
    a, b = (plotting.export_figure(f, "line", tmp_path / d, width_mm=85, formats=("pdf", "svg", "png"), dpi=150)
            for f, d in zip(figs, "ab"))
    for f in figs:
        plt.close(f)
    assert [p.suffix for p in a] == [".pdf", ".svg", ".png"]
    for p, q in zip(a, b):
        assert p.read_bytes() == q.read_bytes(), p.name
    from PIL import Image
    # 85 mm at 150 dpi = 501.97 px; matplotlib truncates the pixel count, so within 1 px
    assert abs(Image.open(a[2]).size[0] - 85 / 25.4 * 150) < 1


@pytest.mark.parametrize("kw, msg", [({"width_mm": "wide"}, "width_mm"), ({"width_mm": -1}, "width_mm"),
                                     ({"width_mm": 85, "height_mm": 0}, "height_mm"), ({"dpi": 0}, "dpi")])
def test_bad_sizes_are_refused_and_nothing_written(tmp_path, kw, msg):
    fig = _line_figure()
    with pytest.raises(ValueError, match=msg):
        plotting.export_figure(fig, "line", tmp_path, **kw)
    plt.close(fig)
    assert list(tmp_path.iterdir()) == []


def test_figsize_follows_the_style():
    with matplotlib.rc_context({"figure.figsize": (4.0, 3.0)}):
        assert plotting.figsize() == (4.0, 3.0)
        assert plotting.figsize(2, 0.5) == (8.0, 1.5)


def test_notebooks_do_not_hard_code_figure_sizes():
    hard = [str(p.relative_to(NOTEBOOKS_DIR)) for p in sorted(NOTEBOOKS_DIR.rglob("*.ipynb"))
            if re.search(r"figsize=\(", p.read_text(encoding="utf-8"))]
    assert hard == [], "use figsize=figsize(w, h) (units of the style's figure.figsize): " + ", ".join(hard)


# mgherony2024's recipes are rendered at 85 mm (with the text-clash checks) by tests/test_figures_mgherony.py
@pytest.mark.parametrize("name", sorted(n for n, r in figures.FIGURES.items() if r.work != "mgherony2024"))
def test_every_recipe_renders_an_85_mm_pdf(name, tmp_path):
    # what `python -m cnclab figure NAME --width-mm 85 --format pdf` does (cnclab.figures.render), with
    # the figure kept open to look at its axes; fast mode: the recipes compute with the notebooks'
    # fast settings and read the works' disk caches (build/cache) that the notebooks fill
    import warnings

    fig = figures.draw(name)
    try:
        drawn = [ax for ax in fig.axes if ax.has_data()]
        assert drawn, "no axes with data"
        assert all(ax.get_xlim()[0] < ax.get_xlim()[1] for ax in drawn)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            [pdf] = plotting.export_figure(fig, name, tmp_path, width_mm=85, formats=("pdf",))
        # readable in a column: no text off the page or on another one, none below the 6 pt floor
        assert plotting.text_clashes(fig) == []
        sizes = [t.get_fontsize() for t in fig.findobj(matplotlib.text.Text) if t.get_text().strip()]
        assert min(sizes) >= plotting.MIN_FONT_PT - 1e-9
    finally:
        plt.close(fig)
    # matplotlib's sign that a figure does not fit the page at all: its constrained layout gave up
    collapsed = [str(w.message) for w in caught if "constrained_layout not applied" in str(w.message)]
    assert not collapsed, f"{name} does not fit 85 mm: {collapsed[0]}"
    w, h = plotting.pdf_page_size_pt(pdf)
    assert abs(w - 85 * PT_PER_MM) < TOL_PT     # 240.94 pt
    assert h >= 0.25 * w                        # not a strip


# Works whose notebooks draw every figure through a registered recipe (issue 26 item 5): a figure a
# notebook saves can be re-rendered by `python -m cnclab figure NAME` without running the notebook.
RECIPE_WORKS = ("jacso2021", "kim_yang2006", "hoang2024")


def _saved_figures(nb_path):
    """(cell source, figure name, work) of every ``savefig(fig, "NAME", "WORK")`` call of a notebook."""
    import ast
    import json

    out = []
    for cell in json.loads(nb_path.read_text(encoding="utf-8"))["cells"]:
        src = "".join(cell["source"]) if cell["cell_type"] == "code" else ""
        lines = "\n".join(line for line in src.splitlines() if not line.lstrip().startswith(("%", "!")))
        for node in ast.walk(ast.parse(lines)):
            if isinstance(node, ast.Call) and getattr(node.func, "id", getattr(node.func, "attr", "")) == "savefig":
                name, work = (a.value if isinstance(a, ast.Constant) else None for a in node.args[1:3])
                out.append((src, name, work))
    return out


@pytest.mark.parametrize("work", RECIPE_WORKS)
def test_every_notebook_figure_is_drawn_by_its_recipe(work):
    notebooks = sorted((NOTEBOOKS_DIR / work).glob("*.ipynb"))
    assert notebooks
    saved = {}
    for nb in notebooks:
        code = nb.read_text(encoding="utf-8")
        # plotting lives in the recipes: no notebook makes a figure of its own
        assert not re.search(r"\b(subplots|plt\.figure|add_subplot)\(", code), f"{nb.name} draws a figure itself"
        for src, name, w in _saved_figures(nb):
            assert isinstance(name, str) and w == work, f"{nb.name}: savefig needs a literal name and work {work!r}"
            assert name in figures.FIGURES and figures.FIGURES[name].work == work, f"{nb.name}: {name} has no recipe"
            assert f'draw("{name}"' in src, f"{nb.name}: {name} is saved from a figure its recipe did not draw"
            saved[name] = nb.name
    registered = {n for n, r in figures.FIGURES.items() if r.work == work}
    assert registered == set(saved), f"recipes no notebook saves: {sorted(registered - set(saved))}"


def test_figure_cli_renders_an_85_mm_pdf(tmp_path, capsys):
    assert figures.main(["fig3-1_engagement_vs_stepover", "--width-mm", "85", "--format", "pdf",
                         "-o", str(tmp_path)]) == 0
    out = tmp_path / "fig3-1_engagement_vs_stepover.pdf"
    assert str(out) in capsys.readouterr().out
    assert abs(plotting.pdf_page_size_pt(out)[0] - 240.9) < TOL_PT
    assert figures.main(["--list"]) == 0
    assert "fig6-2_main_effects" in capsys.readouterr().out
    assert figures.main(["no_such_figure", "-o", str(tmp_path)]) == 2
    assert "unknown figure" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        figures.main(["fig3-1_engagement_vs_stepover", "--width-mm", "nan"])
    assert "--width-mm" in capsys.readouterr().err
    assert sorted(p.name for p in Path(tmp_path).iterdir()) == ["fig3-1_engagement_vs_stepover.pdf"]


def test_theses_notebooks_do_not_depend_on_the_planners_through_the_recipes():
    # make reproduce keys a notebook on the modules it imports: the Theses I-III and dixel notebooks
    # import the light recipes module, so a planner change does not re-run them
    from cnclab import reproduce
    from cnclab.paths import PACKAGE_DIR

    for nb in ("thesis1_engagement_formulas", "thesis2_3_constant_engagement_paths", "dixel_simulator_validation"):
        _, files = reproduce.notebook_inputs(NOTEBOOKS_DIR / "jacso2021" / f"{nb}.ipynb")
        assert PACKAGE_DIR / "works" / "jacso2021" / "figures.py" in files
        assert PACKAGE_DIR / "toolpath" / "planners.py" not in files, nb
    _, files = reproduce.notebook_inputs(NOTEBOOKS_DIR / "jacso2021" / "s4_star_pocket_hybrid_path.ipynb")
    assert PACKAGE_DIR / "works" / "jacso2021" / "figures_pockets.py" in files
