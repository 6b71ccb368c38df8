"""Execute every notebook headless in fast mode (CNCLAB_FAST=1)."""
import os

import pytest

from cnclab.notebook_tools import list_notebooks
from cnclab.paths import NOTEBOOKS_DIR
from cnclab.reproduce import execute_notebook

NOTEBOOKS = list_notebooks()


@pytest.mark.notebook
@pytest.mark.parametrize("nb", NOTEBOOKS, ids=[str(p.relative_to(NOTEBOOKS_DIR)) for p in NOTEBOOKS])
def test_notebook_executes(nb):
    env = {"CNCLAB_FAST": "1", "CNCLAB_BUILD_DIR": os.environ["CNCLAB_BUILD_DIR"], "MPLBACKEND": "Agg"}
    execute_notebook(nb, timeout=900, env=env)
