"""Completeness and conventions of the collection: ledger, notebooks, environment, README."""
import json
import re
from pathlib import Path

import pytest

from cnclab import claims
from cnclab.notebook_tools import INDEX_NOTEBOOK, is_stripped, list_notebooks
from cnclab.paths import NOTEBOOKS_DIR, REPO_ROOT, WORK_IDS

LEDGER = claims.load()
NOTEBOOKS = list_notebooks()


def test_every_computed_by_resolves():
    for c in LEDGER:
        for name in (c.computed_by, c.alt_computed_by):
            if name:
                claims.resolve(name)  # raises LedgerError naming the problem


def test_every_claim_names_an_existing_notebook():
    for c in LEDGER:
        assert c.notebook, f"{c.claim_id}: no notebook shows this claim"
        assert (NOTEBOOKS_DIR / c.notebook).is_file(), f"{c.claim_id}: notebook {c.notebook} not found"


def test_notebook_folders_are_the_work_ids():
    for p in NOTEBOOKS:
        rel = p.relative_to(NOTEBOOKS_DIR)
        assert p == INDEX_NOTEBOOK or rel.parts[0] in WORK_IDS, f"{rel}: not under a work folder"
        assert not p.name.lower().startswith("untitled"), f"{rel}: Untitled notebook"


@pytest.mark.parametrize("nb", NOTEBOOKS, ids=[str(p.relative_to(NOTEBOOKS_DIR)) for p in NOTEBOOKS])
def test_notebook_is_stripped_and_follows_template(nb):
    assert is_stripped(nb), f"{nb} is committed with outputs: run `python -m cnclab nb strip`"
    cells = json.loads(nb.read_text())["cells"]
    # nbformat 4.5: every cell has a unique id (without, nbformat warns now and will refuse the file)
    ids = [c.get("id") for c in cells]
    assert None not in ids and len(set(ids)) == len(ids), f"{nb.name}: a cell without an id, or a repeated one"
    assert cells[0]["cell_type"] == "markdown" and "".join(cells[0]["source"]).startswith("# ")
    code = ["".join(c["source"]) for c in cells if c["cell_type"] == "code"]
    assert "notebook_setup(" in code[0], "first code cell must call cnclab.notebook_setup()"
    if nb != INDEX_NOTEBOOK:
        head = "".join(cells[0]["source"])
        assert "Claims covered" in head and "Run time" in head, "title cell lacks claims/run time"
        md = "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "markdown")
        assert "## Discussion" in md, "notebook lacks a Discussion section"
        assert "claims.table(" in code[-1], "last code cell must render the notebook's claims table"
        for block in code:
            assert len([l for l in block.splitlines() if l.strip()]) <= 25, (
                f"a code cell of {nb.name} is long: move algorithm code into the package")


def test_index_notebook_exists():
    assert INDEX_NOTEBOOK.is_file()


def test_environment_pins_are_exact():
    lines = [l.strip() for l in (REPO_ROOT / "environment.txt").read_text().splitlines()
             if l.strip() and not l.startswith("#")]
    for l in lines:
        assert re.match(r"^[A-Za-z0-9_.\-\[\]]+==[^=<>~!*]+$", l), f"environment.txt: not an exact pin: {l}"
    assert "torch==2.13.0" in lines


def test_readme_shows_the_two_commands():
    text = (REPO_ROOT / "README.md").read_text()
    assert "make reproduce" in text and "make test" in text


def test_ci_runs_make_test():
    assert "make test" in (REPO_ROOT / ".ci" / "run").read_text()
