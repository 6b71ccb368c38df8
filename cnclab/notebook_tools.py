"""Notebook housekeeping: list, strip outputs, build a notebook from a percent-format script.

Notebooks are stored as ``.ipynb`` *without outputs*; executed copies go to ``build/notebooks/``.

Authoring: write ``# %%`` / ``# %% [markdown]`` cells in a scratch ``.py`` file and run
``python -m cnclab nb from-py scratch.py notebooks/<work>/<name>.ipynb`` (the .py file is not kept:
the ``.ipynb`` is the single source). ``python -m cnclab nb strip`` strips every notebook in place.
"""
from __future__ import annotations

import json
import re
from pathlib import Path

from . import clihelp
from .fileio import atomic_write
from .paths import NOTEBOOKS_DIR
from .works import WORKS

INDEX_NOTEBOOK = NOTEBOOKS_DIR / "00_index.ipynb"


def list_notebooks(root: Path = NOTEBOOKS_DIR) -> list[Path]:
    """Every notebook under ``notebooks/`` in execution order: works (sorted), then the index last."""
    nbs = sorted(p for p in Path(root).rglob("*.ipynb") if ".ipynb_checkpoints" not in p.parts)
    return [p for p in nbs if p != INDEX_NOTEBOOK] + [p for p in nbs if p == INDEX_NOTEBOOK]


def is_stripped(path: Path) -> bool:
    nb = json.loads(Path(path).read_text(encoding="utf-8"))
    return not any(c.get("outputs") or c.get("execution_count")
                   for c in nb.get("cells", []) if c.get("cell_type") == "code")


def strip(path: Path) -> bool:
    """Remove outputs and execution counts in place; returns True if the file changed."""
    import nbformat

    path = Path(path)
    nb = nbformat.read(path, as_version=4)
    changed = False
    for cell in nb.cells:
        if cell.cell_type == "code":
            if cell.get("outputs") or cell.get("execution_count") is not None:
                changed = True
            cell.outputs = []
            cell.execution_count = None
        if "id" in cell and "metadata" in cell:
            cell.metadata.pop("execution", None)
    if changed:
        atomic_write(path, nbformat.writes(nb) + "\n")
    return changed


_CELL = re.compile(r"^# %%(.*)$")


def from_percent_script(text: str):
    """Parse ``# %%`` cells (``# %% [markdown]`` cells have their lines' leading ``# `` removed)."""
    import nbformat

    cells, kind, buf = [], None, []

    def flush():
        if kind is None:
            return
        src = "\n".join(buf).strip("\n")
        if kind == "markdown":
            src = "\n".join(l[2:] if l.startswith("# ") else l.lstrip("#") for l in src.splitlines())
            cells.append(nbformat.v4.new_markdown_cell(src))
        elif src.strip():
            cells.append(nbformat.v4.new_code_cell(src))

    for line in text.splitlines():
        m = _CELL.match(line)
        if m:
            flush()
            kind, buf = ("markdown" if "[markdown]" in m.group(1) else "code"), []
        elif kind is not None:
            buf.append(line)
    flush()
    nb = nbformat.v4.new_notebook(cells=cells)
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    nb.metadata["language_info"] = {"name": "python"}
    return nb


def from_py(src: Path, dst: Path) -> Path:
    import nbformat

    nb = from_percent_script(Path(src).read_text(encoding="utf-8"))
    for i, cell in enumerate(nb.cells):  # deterministic cell ids keep diffs small
        cell["id"] = f"c{i:03d}"
    nbformat.validate(nb)
    return atomic_write(dst, nbformat.writes(nb) + "\n")


def index_markdown() -> str:
    """Markdown links to every notebook, grouped by work (rendered by ``00_index.ipynb``)."""
    lines = []
    for work, info in WORKS.items():
        nbs = sorted((NOTEBOOKS_DIR / work).glob("*.ipynb"))
        lines.append(f"**{work}** — {info['citation']}")
        lines += [f"- [{p.stem}]({work}/{p.name})" for p in nbs] or ["- (no notebook yet)"]
        lines.append("")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = clihelp.parser(
        "python -m cnclab nb",
        "Notebook housekeeping: convert a percent-format script to a notebook, strip the outputs of\n"
        "every notebook (they are committed without outputs), list the notebooks in execution order.",
        examples=["python -m cnclab nb strip", "python -m cnclab nb from-py draft.py notebooks/hoang2024/new.ipynb"],
        writes=["from-py: DST; strip: the notebooks in notebooks/ that had outputs; list: nothing"])
    sub = ap.add_subparsers(dest="cmd", required=True, metavar="{from-py,strip,list}")
    f = sub.add_parser("from-py", help="percent-format script -> stripped .ipynb", formatter_class=clihelp.HelpFormatter,
                       description="Convert a percent-format (# %%) script into a notebook without outputs.",
                       epilog="Example:\n  python -m cnclab nb from-py draft.py notebooks/hoang2024/new.ipynb")
    f.add_argument("src", help="percent-format Python script")
    f.add_argument("dst", help="notebook to write (.ipynb)")
    sub.add_parser("strip", help="strip outputs of every notebook in notebooks/", formatter_class=clihelp.HelpFormatter,
                   description="Strip outputs and execution counts of every notebook in notebooks/.",
                   epilog="Example:\n  python -m cnclab nb strip")
    sub.add_parser("list", help="list notebooks in execution order", formatter_class=clihelp.HelpFormatter,
                   description="List the notebooks in execution order.", epilog="Example:\n  python -m cnclab nb list")
    a = ap.parse_args(argv)
    if a.cmd == "from-py":
        print(f"wrote {from_py(Path(a.src), Path(a.dst))}")
    elif a.cmd == "strip":
        for p in list_notebooks():
            if strip(p):
                print(f"stripped {p}")
    else:
        for p in list_notebooks():
            print(p.relative_to(NOTEBOOKS_DIR))
    return 0
