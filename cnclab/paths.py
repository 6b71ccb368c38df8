"""Where cnclab's files live.

Every path is resolved from the package location, never from the working directory, so the
notebooks, the tests and the CLI find ``data/`` wherever they are started from.

``build/`` (executed notebooks, figures, the claims report) defaults to ``<repo>/build`` and can be
redirected with the environment variable ``CNCLAB_BUILD_DIR`` (the tests point it at a temporary
folder so that they never touch a user's build outputs).
"""
from __future__ import annotations

import os
from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parent
REPO_ROOT = PACKAGE_DIR.parent
DATA_DIR = REPO_ROOT / "data"
NOTEBOOKS_DIR = REPO_ROOT / "notebooks"
CLAIMS_CSV = DATA_DIR / "claims.csv"

#: Work ids used everywhere: notebook folders, the ledger's ``work`` column, the CLI.
WORK_IDS = ("jacso2021", "kim_yang2006", "hoang2024", "mgherony2024")


def data_path(*parts: str) -> Path:
    """Absolute path of a file under ``data/``; raises FileNotFoundError naming it if absent."""
    p = DATA_DIR.joinpath(*parts)
    if not p.exists():
        raise FileNotFoundError(f"cnclab data file not found: {p}")
    return p


def build_dir() -> Path:
    """The build output folder (``$CNCLAB_BUILD_DIR`` or ``<repo>/build``), created on demand."""
    p = Path(os.environ.get("CNCLAB_BUILD_DIR") or (REPO_ROOT / "build")).resolve()
    p.mkdir(parents=True, exist_ok=True)
    return p


def figures_dir(work: str) -> Path:
    """``build/figures/<work>/``, created on demand; ``work`` must be one of :data:`WORK_IDS`."""
    if work not in WORK_IDS:
        raise ValueError(f"work must be one of {WORK_IDS}, got {work!r}")
    p = build_dir() / "figures" / work
    p.mkdir(parents=True, exist_ok=True)
    return p
