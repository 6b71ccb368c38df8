"""The offline site: ``build/site/index.html`` — works, reading order, notebooks, figures, claims.

Built by :func:`build_site` from whatever ``build/`` holds (``make reproduce`` calls it at its end;
``python -m cnclab site`` builds it alone): executed notebooks ``build/notebooks/**/*.ipynb`` are
exported to HTML with an **offline** nbconvert template (no require.js, MathJax, Mermaid or widget
manager from a CDN; formulas show as TeX source), figures ``build/figures/<work>/*.{pdf,svg,png,html}``
are copied with PNG thumbnails, and ``build/claims.csv`` becomes a table filterable by work and
status (inline JavaScript). Everything the pages load is inside ``build/site/``:
:func:`external_references` finds any script/style/font/image reference that would leave the machine.
The site is written to a temporary folder and swapped in whole (never a half-written site).
"""
from __future__ import annotations

import csv
import html
import os
import re
import shutil
import sys
import tempfile
from pathlib import Path

from . import claims as claims_mod
from . import clihelp
from .fileio import atomic_write
from .paths import WORK_IDS, build_dir

__all__ = ["WORKS", "READING_ORDER", "offline_notebook_html", "external_references", "build_site",
           "reading_order_markdown", "EXPLORER_NOTEBOOKS", "main"]

#: The four works: full citation and seed file (as in README.md).
WORKS = {
    "jacso2021": ("Jacsó, Á. (2021). <i>Tool path generation for pocket machining with uniform tool load.</i> "
                  "PhD dissertation booklet, Budapest University of Technology and Economics (supervisor "
                  "T. Szalay).", "000_690a1ed8f09fd780.txt",
                  "Constant-engagement 2.5D pocket paths (Theses I–IV), dixel simulation, star-pocket hybrid path."),
    "kim_yang2006": ("Kim, H.-C. &amp; Yang, M.-Y. (2006). An optimum 2.5D contour parallel tool path. "
                     "<i>International Journal of Precision Engineering and Manufacturing</i> 7(3).",
                     "002_d412f01ccb8e936f.txt",
                     "Constant-MRR contour-parallel path by pixel simulation and inserted path segments."),
    "hoang2024": ("Hoang, V.-Q. (2024). Toolpath generation on 3-axes milling using constant volume method. "
                  "<i>Journal of Mechanical Engineering – Problems of Machinery</i> 27(2). "
                  "doi:10.15407/pmach2024.02.060.", "003_216a87306e3bb9cf.txt",
                  "Constant-volume ball-end zig-zag."),
    "mgherony2024": ("Mgherony, A. W. (2024). <i>Optimization of ball end milling tool path in case of free form "
                     "milling.</i> PhD dissertation, Óbuda University (supervisor B. Mikó).",
                     "004_6087ee43271ee0e7.txt",
                     "Cusp height and roughness, ball-end working diameter, regression/MLP models, spindle-speed "
                     "control from STL + APT, tool-path reordering."),
}

#: A reading order for a course: (notebook relative to notebooks/, what to take from it).
READING_ORDER = [
    ("jacso2021/thesis1_engagement_formulas.ipynb", "engagement angle and stepover on arcs (Thesis I) — start here"),
    ("jacso2021/dixel_simulator_validation.ipynb", "how engagement is measured: the dixel and pixel simulators"),
    ("jacso2021/thesis2_3_constant_engagement_paths.ipynb", "paths that hold the engagement constant (Theses II–III)"),
    ("jacso2021/thesis4_trochoidal_slots.ipynb", "trochoidal slots: circle, cycloid, constant engagement (Thesis IV)"),
    ("jacso2021/s4_star_pocket_hybrid_path.ipynb", "a whole pocket: the star-pocket hybrid path"),
    ("jacso2021/adaptive_vs_freecad.ipynb", "the adaptive planner vs FreeCAD Adaptive: eight pockets and a 71-job corpus"),
    ("kim_yang2006/constant_mrr_contour_parallel.ipynb", "constant MRR by inserting path segments (Kim & Yang)"),
    ("kim_yang2006/ce_vs_constant_mrr.ipynb", "constant MRR vs constant engagement on one pocket"),
    ("hoang2024/eqs_and_table2_constant_volume.ipynb", "ball-end scallops and the constant-volume step (Hoang)"),
    ("hoang2024/table3_zigzag_toolpath.ipynb", "the constant-volume zig-zag program"),
    ("hoang2024/uncut_volume_heightfield.ipynb", "checking the uncut volume on a height field"),
    ("mgherony2024/ch3_cusp_height_roughness.ipynb", "cusp height and roughness (Mgherony ch. 3)"),
    ("mgherony2024/ch4_surface_inclination_cutting_speed.ipynb", "surface inclination and cutting speed (ch. 4)"),
    ("mgherony2024/ch5_working_diameter_simulation.ipynb", "the ball-end working diameter model (ch. 5)"),
    ("mgherony2024/ch6_dataset_regression.ipynb", "a data set and regression models of it (ch. 6)"),
    ("mgherony2024/ch6_neural_networks.ipynb", "neural networks on the same data (ch. 6)"),
    ("mgherony2024/ch7_spindle_speed_control.ipynb", "spindle-speed control from STL + APT files (ch. 7)"),
    ("mgherony2024/ch8_free_form_part_feed_directions.ipynb", "the free-form part and feed directions (ch. 8)"),
    ("mgherony2024/ch9_toolpath_reordering.ipynb", "reordering the tool path (ch. 9)"),
]

#: Notebooks holding an interactive explorer (marked ★ in the reading order).
EXPLORER_NOTEBOOKS = frozenset({
    "jacso2021/thesis1_engagement_formulas.ipynb", "jacso2021/thesis2_3_constant_engagement_paths.ipynb",
    "jacso2021/thesis4_trochoidal_slots.ipynb", "kim_yang2006/constant_mrr_contour_parallel.ipynb",
    "hoang2024/eqs_and_table2_constant_volume.ipynb", "mgherony2024/ch3_cusp_height_roughness.ipynb",
    "mgherony2024/ch5_working_diameter_simulation.ipynb", "mgherony2024/ch8_free_form_part_feed_directions.ipynb"})

_OFFLINE_TEMPLATE = """{%- extends 'lab/index.html.j2' -%}
{%- block html_head_js_requirejs -%}{%- endblock html_head_js_requirejs -%}
{%- block html_head_js_mathjax -%}{%- endblock html_head_js_mathjax -%}
{%- block html_head_js_mermaidjs -%}{%- endblock html_head_js_mermaidjs -%}
{%- block jupyter_widgets -%}{%- endblock jupyter_widgets -%}
"""

# references a browser would fetch: src/href of script, link, img, iframe, source, embed, object
# data, CSS url(...) and @import, and ES-module imports
_FETCHING = [
    re.compile(r"<(?:script|img|iframe|source|embed|audio|video|track|input)\b[^>]*\bsrc\s*=\s*[\"']?\s*(?:https?:)?//",
               re.I),
    re.compile(r"<link\b[^>]*\bhref\s*=\s*[\"']?\s*(?:https?:)?//", re.I),
    re.compile(r"<object\b[^>]*\bdata\s*=\s*[\"']?\s*(?:https?:)?//", re.I),
    re.compile(r"url\(\s*[\"']?\s*(?:https?:)?//", re.I),
    re.compile(r"@import\s+(?:url\()?\s*[\"']?\s*(?:https?:)?//", re.I),
    re.compile(r"\bimport\s*(?:[\w{}\s,*]+from\s*)?\(?\s*[\"'](?:https?:)?//", re.I),
]


def external_references(text: str) -> list[str]:
    """Snippets of ``text`` (HTML/CSS/JS) that make a browser fetch something from another host.

    Links a reader may follow (``<a href="https://doi.org/...">``) and URLs in comments or strings
    are not fetches and are not reported.

    >>> external_references('<script src="https://cdn.example/x.js"></script><a href="https://x">ok</a>')
    ['<script src="https://cdn.example/x.js">']
    >>> external_references('<link rel="stylesheet" href="site.css"><img src="thumbs/a.png">')
    []
    """
    out = []
    for rx in _FETCHING:
        for m in rx.finditer(text):
            end = text.find(">", m.end())
            end = m.end() + 80 if end < 0 or end > m.end() + 300 else end + 1
            out.append(text[m.start(): end])
    return out


def offline_notebook_html(nb) -> str:
    """HTML of an executed notebook (``nbformat`` node) with nothing loaded from a CDN.

    Saved widget state is dropped (the explorers leave a PNG snapshot in their ``text/html``), and the
    lab template's require.js, MathJax, Mermaid and widget-manager script tags are left out.
    """
    import copy

    from jinja2 import DictLoader
    from nbconvert import HTMLExporter

    nb = copy.deepcopy(nb)
    nb.metadata.pop("widgets", None)
    exp = HTMLExporter(template_name="lab", extra_loaders=[DictLoader({"cnclab_offline.html.j2": _OFFLINE_TEMPLATE})],
                       template_file="cnclab_offline.html.j2")
    text, _ = exp.from_notebook_node(nb)
    bad = external_references(text)
    if bad:
        raise ValueError(f"offline notebook HTML still references other hosts: {bad[:3]}")
    return text


def _notebooks(build: Path, site: Path) -> list[dict]:
    import nbformat

    src = build / "notebooks"
    rows = []
    for p in sorted(src.rglob("*.ipynb")) if src.is_dir() else []:
        rel = p.relative_to(src)
        dest = site / "notebooks" / rel.with_suffix(".html")
        dest.parent.mkdir(parents=True, exist_ok=True)
        nb = nbformat.read(p, as_version=4)
        # links between notebooks (the index) point at the exported pages of this site
        text = re.sub(r'href="(?!https?:)([^"#]+)\.ipynb(#[^"]*)?"', r'href="\1.html\2"', offline_notebook_html(nb))
        dest.write_text(text, encoding="utf-8")
        title = next((c.source.splitlines()[0].lstrip("# ").strip() for c in nb.cells
                      if c.cell_type == "markdown" and c.source.strip()), rel.stem)
        rows.append({"rel": rel.as_posix(), "href": f"notebooks/{rel.with_suffix('.html').as_posix()}",
                     "work": rel.parts[0] if len(rel.parts) > 1 else "", "title": title})
    return rows


def _figures(build: Path, site: Path) -> list[dict]:
    from PIL import Image

    src = build / "figures"
    groups: dict[tuple, dict] = {}
    for p in sorted(src.rglob("*")) if src.is_dir() else []:
        if p.suffix.lower() not in (".pdf", ".svg", ".png", ".html") or not p.is_file():
            continue
        rel = p.relative_to(src)
        dest = site / "figures" / rel
        dest.parent.mkdir(parents=True, exist_ok=True)
        if p.suffix.lower() == ".html":
            text = p.read_text(encoding="utf-8")
            if external_references(text):
                continue                              # never publish a page that would go online
            dest.write_text(text, encoding="utf-8")
        else:
            shutil.copyfile(p, dest)
        g = groups.setdefault((rel.parts[0], p.stem), {"work": rel.parts[0], "name": p.stem, "files": {}})
        g["files"][p.suffix.lower().lstrip(".")] = f"figures/{rel.as_posix()}"
        if p.suffix.lower() == ".png":
            thumb = site / "thumbs" / rel
            thumb.parent.mkdir(parents=True, exist_ok=True)
            with Image.open(p) as im:
                im.thumbnail((360, 270))
                im.save(thumb)
            g["thumb"] = f"thumbs/{rel.as_posix()}"
    return list(groups.values())


def _claims(build: Path) -> tuple[list[str], list[dict]]:
    p = build / "claims.csv"
    if not p.is_file():
        return [], []
    with open(p, newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    return (list(rows[0].keys()) if rows else []), rows


_CSS = """body{font-family:system-ui,-apple-system,"Segoe UI",sans-serif;margin:0 auto;max-width:72em;padding:1em 2em;
color:#222;line-height:1.45}h1{margin-bottom:.2em}nav a{margin-right:1.2em}table{border-collapse:collapse;width:100%;
font-size:.85em}th,td{border:1px solid #ccc;padding:.25em .4em;vertical-align:top}th{background:#f0f0f0;position:sticky;
top:0}.gallery{display:flex;flex-wrap:wrap;gap:1em}.fig{width:370px;border:1px solid #ddd;padding:.4em;font-size:.85em}
.fig img{max-width:360px;max-height:270px;display:block}.work{border-left:4px solid #4a7;padding-left:.8em;margin:.8em 0}
.ok-True{background:#effaf0}.ok-False{background:#fdeaea}label{margin-right:1em}code{font-size:.95em}"""

_JS = """function filt(){var w=document.getElementById('fw').value,s=document.getElementById('fs').value,n=0;
document.querySelectorAll('#claims tbody tr').forEach(function(r){var v=(!w||r.dataset.work===w)&&(!s||r.dataset.status===s);
r.style.display=v?'':'none';if(v)n++;});document.getElementById('nshown').textContent=n;}
document.getElementById('fw').addEventListener('change',filt);document.getElementById('fs').addEventListener('change',filt);filt();"""


def _page(notebooks, figures, claim_cols, claims) -> str:
    e = html.escape
    nb_by_rel = {n["rel"]: n for n in notebooks}
    out = ["<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
           "<meta name='viewport' content='width=device-width, initial-scale=1'>",
           "<title>cnclab — a reproducible study collection on CNC milling tool paths</title>",
           f"<style>{_CSS}</style></head><body>",
           "<h1>cnclab</h1><p>A reproducible study collection on CNC milling tool paths: four works, "
           "their notebooks (executed), figures and the claims ledger. Everything on this site is local.</p>",
           "<nav><a href='#works'>Works</a><a href='#reading'>Reading order</a><a href='#notebooks'>Notebooks</a>"
           "<a href='#figures'>Figures</a><a href='#claims-section'>Claims</a></nav>",
           "<h2 id='works'>The works</h2>"]
    for wid, (cite, seed, what) in WORKS.items():
        out.append(f"<div class='work' id='work-{wid}'><b><code>{wid}</code></b> — {cite}<br>{e(what)} "
                   f"<small>(seed text <code>{seed}</code>)</small></div>")
    out.append("<h2 id='reading'>Reading order for a course</h2><ol>")
    for rel, why in READING_ORDER:
        n = nb_by_rel.get(rel)
        link = f"<a href='{e(n['href'])}'>{e(rel)}</a>" if n else f"{e(rel)} <small>(not executed yet)</small>"
        star = " ★ <small>(explorer)</small>" if rel in EXPLORER_NOTEBOOKS else ""
        out.append(f"<li>{link}{star} — {e(why)}</li>")
    out.append("</ol><h2 id='notebooks'>Executed notebooks</h2><ul>")
    for n in notebooks:
        out.append(f"<li><a href='{e(n['href'])}'>{e(n['rel'])}</a> — {e(n['title'])}</li>")
    if not notebooks:
        out.append("<li>none yet: run <code>make reproduce</code></li>")
    out.append("</ul><h2 id='figures'>Figure gallery</h2><div class='gallery'>")
    for g in figures:
        links = " · ".join(f"<a href='{e(h)}'>{k.upper() if k != 'html' else '3D (HTML)'}</a>"
                           for k, h in sorted(g["files"].items()))
        img = (f"<a href='{e(g['files'].get('png', ''))}'><img loading='lazy' src='{e(g['thumb'])}' "
               f"alt='{e(g['name'])}'></a>" if "thumb" in g else "<div><i>interactive 3D view</i></div>")
        out.append(f"<div class='fig'>{img}<b>{e(g['name'])}</b> <small>({e(g['work'])})</small><br>{links}</div>")
    out.append("</div>")
    out.append("<h2 id='claims-section'>Claims</h2>")
    if claims:
        works = sorted({r.get("work", "") for r in claims})
        stats = sorted({r.get("status", "") for r in claims})
        opt = lambda vals: "".join(f"<option value='{e(v)}'>{e(v)}</option>" for v in vals)  # noqa: E731
        out.append(f"<p><label>work <select id='fw'><option value=''>all</option>{opt(works)}</select></label>"
                   f"<label>status <select id='fs'><option value=''>all</option>{opt(stats)}</select></label>"
                   f"<span id='nshown'>{len(claims)}</span> of {len(claims)} rows shown</p>")
        cols = [c for c in ("claim_id", "work", "location", "quantity", "unit", "paper_value", "reproduced_value",
                            "status", "ok", "note") if c in claim_cols] or claim_cols
        out.append("<table id='claims'><thead><tr>" + "".join(f"<th>{e(c)}</th>" for c in cols) + "</tr></thead><tbody>")
        for r in claims:
            out.append(f"<tr class='ok-{e(r.get('ok', ''))}' data-work='{e(r.get('work', ''))}' "
                       f"data-status='{e(r.get('status', ''))}'>" + "".join(f"<td>{e(r.get(c, ''))}</td>" for c in cols)
                       + "</tr>")
        out.append(f"</tbody></table><script>{_JS}</script>")
    else:
        out.append("<p>No claims report yet: run <code>make reproduce</code> (or <code>make claims</code>).</p>")
    out += _qualitative_section()
    out.append("</body></html>")
    return "\n".join(out)


def _qualitative_section() -> list[str]:
    """The qualitative rows (``data/qualitative_claims.csv``): quote, verdict and what was measured; the
    verdicts are the ones the tests assert (tests/test_claims_qualitative.py), the numbers are in
    ``build/claims.md``."""
    e = html.escape
    rows = claims_mod.load_qualitative()
    out = ["<h2 id='qualitative'>Qualitative claims (theses, conclusions, headline sentences)</h2>",
           "<table id='qualitative-claims'><thead><tr><th>claim</th><th>work</th><th>location</th><th>quote</th>"
           "<th>verdict</th><th>measure</th></tr></thead><tbody>"]
    for q in rows:
        out.append(f"<tr data-work='{e(q.work)}' data-verdict='{e(q.verdict)}'><td>{e(q.claim_id)}</td><td>{e(q.work)}</td>"
                   f"<td>{e(q.location)}</td><td>{e(q.quote)}</td><td><b>{e(q.verdict)}</b></td><td>{e(q.measure)}</td></tr>")
    return out + ["</tbody></table>"]


def build_site(build: Path | None = None, out: Path | None = None) -> Path:
    """Build the offline site from ``build`` (default :func:`cnclab.paths.build_dir`) into ``out``
    (default ``<build>/site``); returns the path of ``index.html``. Raises ValueError if any page would
    fetch from another host."""
    build = Path(build) if build is not None else build_dir()
    out = Path(out) if out is not None else build / "site"
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".site-", dir=out.parent))
    try:
        notebooks = _notebooks(build, tmp)
        figures = _figures(build, tmp)
        cols, claims = _claims(build)
        atomic_write(tmp / "index.html", _page(notebooks, figures, cols, claims))
        for p in tmp.rglob("*.htm*"):
            bad = external_references(p.read_text(encoding="utf-8"))
            if bad:
                raise ValueError(f"{p.relative_to(tmp)}: references another host: {bad[:3]}")
        old = out.with_name(out.name + ".old")
        if out.exists():
            shutil.rmtree(old, ignore_errors=True)
            os.replace(out, old)
        os.replace(tmp, out)
        shutil.rmtree(old, ignore_errors=True)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    print(f"site: {len(notebooks)} notebooks, {len(figures)} figures, {len(claims)} claims -> {out / 'index.html'}")
    return out / "index.html"


def reading_order_markdown() -> str:
    """The course reading order as a markdown list (the index notebook shows the same list)."""
    return "\n".join(f"{i}. [{rel}]({rel}){' ★' if rel in EXPLORER_NOTEBOOKS else ''} — {why}"
                     for i, (rel, why) in enumerate(READING_ORDER, 1))


def main(argv=None) -> int:
    ap = clihelp.parser(
        "python -m cnclab site",
        "Build the offline site (one HTML page linking the executed notebooks, a figure gallery and the\n"
        "claims table) from what the build folder holds; no notebook is executed.",
        examples=["python -m cnclab site"],
        writes=["BUILD/site/index.html and the pages it links"])
    ap.add_argument("--build", type=Path, default=None, help="build folder (default: build/ or $CNCLAB_BUILD_DIR)")
    a = ap.parse_args(argv)
    build_site(a.build)
    return 0


if __name__ == "__main__":
    sys.exit(main())
