"""The offline site (cnclab.site) and the offline 3D views (cnclab.explore.views3d), built from synthetic inputs."""
import csv
import re

import matplotlib
import nbformat
import numpy as np
import pytest
from nbconvert import HTMLExporter

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from cnclab import site  # noqa: E402
from cnclab.explore import views3d  # noqa: E402
from cnclab.geometry.mesh import read_stl  # noqa: E402
from cnclab.notebook_tools import INDEX_NOTEBOOK  # noqa: E402
from cnclab.paths import DATA_DIR, NOTEBOOKS_DIR  # noqa: E402


def _executed_notebook():
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_markdown_cell("# Thesis I — a synthetic notebook\nWith $\\theta$ in TeX. "
                                              "[next](../hoang2024/next.ipynb), [doi](https://doi.org/10.1/x.ipynb)"),
                nbformat.v4.new_code_cell("1 + 1")]
    nb.cells[1].outputs = [nbformat.v4.new_output("execute_result", {"text/plain": "2"}, execution_count=1)]
    nb.metadata["widgets"] = {"application/vnd.jupyter.widget-state+json": {"version_major": 2, "version_minor": 0,
                                                                            "state": {}}}
    return nb


@pytest.fixture(scope="module")
def small_build(tmp_path_factory):
    b = tmp_path_factory.mktemp("build")
    (b / "notebooks" / "jacso2021").mkdir(parents=True)
    nbformat.write(_executed_notebook(), b / "notebooks" / "jacso2021" / "thesis1_engagement_formulas.ipynb")
    fd = b / "figures" / "jacso2021"
    fd.mkdir(parents=True)
    fig, ax = plt.subplots(figsize=(3, 2))
    ax.plot([0, 1], [0, 1])
    for ext in ("png", "svg", "pdf"):
        fig.savefig(fd / f"fig_line.{ext}")
    plt.close(fig)
    mesh = read_stl(DATA_DIR / "mgherony2024" / "sample_ch8_part.stl")
    md = b / "figures" / "mgherony2024"
    md.mkdir(parents=True)
    (md / "part3d.html").write_text(views3d.offline_html(views3d.part_figure(mesh), full_html=True))
    with open(b / "claims.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["claim_id", "work", "location", "paper_value", "reproduced_value", "status", "ok"])
        w.writerow(["jacso2021.t1.a", "jacso2021", "eq 1", "1.0", "1.0", "MATCH", "True"])
        w.writerow(["hoang2024.t2.b", "hoang2024", "Table 2", "2.0", "3.0", "DIFFERS", "True"])
    index = site.build_site(b)
    return b, index


def test_site_has_works_reading_order_notebooks_figures_and_claims(small_build):
    b, index = small_build
    text = index.read_text()
    for wid, (cite, seed, _) in site.WORKS.items():
        assert cite in text and seed in text
    assert "Reading order" in text and "thesis1_engagement_formulas.ipynb" in text
    hrefs = re.findall(r"(?:href|src)='([^']+)'", text)
    local = [h for h in hrefs if not h.startswith("#")]
    assert "notebooks/jacso2021/thesis1_engagement_formulas.html" in local
    for ext in ("png", "svg", "pdf", "html"):
        assert any(h.endswith("." + ext) and h.startswith("figures/") for h in local)
    assert any(h.startswith("thumbs/") for h in local)
    for h in local:                                              # every link resolves inside the site
        assert (index.parent / h).is_file(), h
    assert text.count("data-status='MATCH'") == 1 and text.count("data-status='DIFFERS'") == 1
    assert "id='fw'" in text and "id='fs'" in text               # the filters
    page = (index.parent / "notebooks/jacso2021/thesis1_engagement_formulas.html").read_text()
    assert 'href="../hoang2024/next.html"' in page and 'href="https://doi.org/10.1/x.ipynb"' in page


def test_site_has_no_external_reference_anywhere(small_build):
    b, index = small_build
    files = [p for p in index.parent.rglob("*") if p.is_file()]
    assert len(files) >= 7            # index, notebook, png/svg/pdf, thumbnail, 3D page
    for p in files:
        if p.suffix in (".html", ".css", ".js", ".svg"):
            t = p.read_text(encoding="utf-8", errors="replace")
            assert site.external_references(t) == [], p
            # no tag at all whose src/href attribute starts with http(s) (stricter than the fetch list)
            assert not re.search(r"<(script|link|img|iframe)\b[^>]*(src|href)\s*=\s*[\"']?https?://", t, re.I), p


def test_default_nbconvert_html_would_go_online_but_ours_does_not():
    nb = _executed_notebook()
    default, _ = HTMLExporter().from_notebook_node(nb)
    assert site.external_references(default)                   # the detector sees require.js/MathJax/widgets
    ours = site.offline_notebook_html(nb)
    assert site.external_references(ours) == []
    assert "Thesis I — a synthetic notebook" in ours


def test_build_site_is_repeatable_and_replaces_the_old_site(small_build, tmp_path):
    b, index = small_build
    (index.parent / "stale.txt").write_text("old")
    again = site.build_site(b)
    assert again == index and not (index.parent / "stale.txt").exists()
    assert not list(b.glob(".site-*"))                          # no temporary folder left behind


def test_build_site_from_an_empty_build(tmp_path):
    index = site.build_site(tmp_path)
    assert "make reproduce" in index.read_text()


def test_reading_order_lists_existing_notebooks_and_matches_the_index():
    for rel, _ in site.READING_ORDER:
        assert (NOTEBOOKS_DIR / rel).is_file(), rel
    cells = nbformat.read(INDEX_NOTEBOOK, as_version=4).cells
    md = next(c.source for c in cells if c.cell_type == "markdown" and "Reading order" in c.source)
    listed = re.findall(r"\]\(([^)]+\.ipynb)\)", md)
    assert listed == [rel for rel, _ in site.READING_ORDER]


# ------------------------------------------------------------------------------ 3D views
def test_mesh_arrays_rebuild_the_triangles():
    mesh = read_stl(DATA_DIR / "mgherony2024" / "sample_ch8_part.stl")
    V, F = views3d.mesh_arrays(mesh)
    assert np.allclose(V[F], mesh.triangles)
    assert len(V) < 3 * mesh.n_facets / 2                       # corners are shared


def test_views_render_offline_with_plotly_inlined(tmp_path, monkeypatch):
    monkeypatch.setenv("CNCLAB_BUILD_DIR", str(tmp_path))
    mesh = read_stl(DATA_DIR / "mgherony2024" / "sample_ch8_part.stl")
    P = mesh.centroids[:50]
    fig = views3d.path_figure(mesh, P, P[:, 2], "z", "mm", "test")
    path = views3d.save_html(fig, "t3d", "mgherony2024")
    text = path.read_text()
    assert path.parent == tmp_path / "figures" / "mgherony2024"
    assert site.external_references(text) == [] and "plotly" in text.lower() and len(text) > 1_000_000
    views3d.reset_plotlyjs()
    b1 = views3d.show(fig)._repr_mimebundle_()
    b2 = views3d.show(fig)._repr_mimebundle_()
    assert "application/vnd.plotly.v1+json" in b1 and len(b1["text/html"]) > 1_000_000   # plotly.js once
    assert len(b2["text/html"]) < 200_000
    order = np.arange(50)[::-1]
    jump = np.zeros(50, bool)
    jump[[10, 30]] = True
    rf = views3d.reorder_figure(mesh, P, order, jump)
    assert rf.data[2].name == "jumps (2)"
    with pytest.raises(ValueError, match="xyz"):
        views3d.path_figure(mesh, P[:, :2], P[:, 0], "z", "mm")


def test_site_lists_the_qualitative_rows(small_build):
    from cnclab import claims

    _, index = small_build
    page = index.read_text(encoding="utf-8")
    assert "id='qualitative-claims'" in page
    for q in claims.load_qualitative():
        assert q.claim_id in page
