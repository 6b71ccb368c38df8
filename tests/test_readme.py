"""The README's "Getting started" section runs as written.

Every ```bash block of the section is executed, in order, by one bash (``set -euo pipefail``) in a
temporary folder that links the repository's ``data/``, ``tests/``, ``notebooks/`` and the running
virtual environment (as ``.venv``), with ``CNCLAB_BUILD_DIR`` pointed at the folder's ``build/``: the
README's outputs never touch the checkout. Lines carrying the visible marker
``# (not run by tests/test_readme.py)`` (``make reproduce``, ``make test``, ``make lab``) are left
out; the test checks that the skipped lines are only these and that ``make lab`` is a real target.
"""
from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"
SKIP_MARK = "# (not run by tests/test_readme.py)"


def getting_started() -> str:
    """The text of the README section '## Getting started' (up to the next '## ' heading)."""
    text = README.read_text(encoding="utf-8")
    m = re.search(r"^## Getting started\n(.*?)(?=^## )", text, re.S | re.M)
    assert m, "README.md has no '## Getting started' section"
    return m.group(1)


def shell_blocks(section: str) -> list[str]:
    """The ```bash blocks of ``section``, in order."""
    return re.findall(r"^```bash\n(.*?)^```", section, re.S | re.M)


def runnable(block: str) -> tuple[str, list[str]]:
    """(script without the marked lines, the marked lines)."""
    keep, skipped = [], []
    for line in block.splitlines():
        (skipped if SKIP_MARK in line else keep).append(line)
    return "\n".join(keep) + "\n", skipped


def test_getting_started_is_first_and_skips_only_make_targets():
    text = README.read_text(encoding="utf-8")
    headings = re.findall(r"^## (.+)$", text, re.M)
    assert headings[0] == "Getting started"
    blocks = shell_blocks(getting_started())
    assert len(blocks) >= 6
    skipped = [s for b in blocks for s in runnable(b)[1]]
    assert sorted(s.split()[1] for s in skipped) == ["lab", "reproduce", "test"]
    assert all(s.startswith("make ") for s in skipped)
    text = getting_started()
    for cmd in ("plan", "analyze", "spindle"):      # three examples each
        assert len(re.findall(rf"^python -m cnclab {cmd} ", text, re.M)) >= 3, cmd


def test_reading_order_is_the_collections():
    """The README's reading order is the index notebook's and the site's (cnclab.site.READING_ORDER)."""
    from cnclab import site

    m = re.search(r"^Reading order .*?\n((?:\d+\. .*\n)+)", getting_started(), re.M)
    assert m, "no numbered reading order in Getting started"
    listed = re.findall(r"\]\(notebooks/([^)]+\.ipynb)\)", m.group(1))
    assert listed == [rel for rel, _ in site.READING_ORDER]
    assert all((REPO / "notebooks" / rel).is_file() for rel in listed)


def test_make_lab_opens_the_index():
    if shutil.which("make") is None:
        pytest.skip("make is not installed")
    out = subprocess.run(["make", "-n", "lab", "STAMP="], cwd=REPO, capture_output=True, text=True, check=True).stdout
    assert "jupyter lab notebooks/00_index.ipynb" in out
    assert (REPO / "notebooks" / "00_index.ipynb").is_file()


def test_getting_started_blocks_run(tmp_path):
    for name in ("data", "tests", "notebooks"):
        (tmp_path / name).symlink_to(REPO / name)
    (tmp_path / ".venv").symlink_to(Path(sys.prefix))
    (tmp_path / "build").mkdir()
    env = dict(os.environ, CNCLAB_BUILD_DIR=str(tmp_path / "build"), CNCLAB_FAST="1",
               PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""),
               PATH=str(Path(sys.executable).parent) + os.pathsep + os.environ.get("PATH", ""))
    env.pop("CNCLAB_DASK_SCHEDULER", None)
    env.pop("CNCLAB_SWEEP_JOBS", None)
    script = "set -euo pipefail\n" + "".join(runnable(b)[0] for b in shell_blocks(getting_started()))
    # its own process group: the Dask scheduler and worker the README starts in the background are
    # ended with the group even when a line fails before the README's own `kill`
    # output to files, not pipes: a background process left running (a Dask worker) keeps a pipe open
    # and would hold communicate() until the timeout; with files the test waits for bash only
    with open(tmp_path / "readme.out", "w+") as fo, open(tmp_path / "readme.err", "w+") as fe:
        proc = subprocess.Popen(["bash", "-c", script], cwd=tmp_path, env=env, stdout=fo, stderr=fe,
                                text=True, start_new_session=True)
        try:
            proc.wait(timeout=1800)
        finally:
            for sig in (signal.SIGTERM, signal.SIGKILL):
                try:
                    os.killpg(proc.pid, sig)
                except ProcessLookupError:
                    break
        fo.seek(0)
        fe.seek(0)
        out, err = fo.read(), fe.read()
    res = subprocess.CompletedProcess(proc.args, proc.returncode, out, err)
    assert res.returncode == 0, f"README Getting started failed:\n{res.stdout[-3000:]}\n{res.stderr[-3000:]}"
    start = tmp_path / "build" / "start"
    for f in ("my_pocket.ngc", "my_pocket_cp.ngc", "from_drawing.ngc", "two_regions.ngc", "ch8_vc63.apt", "ch8_limited.apt",
              "ch8_limited.ngc", "ch8_af0.apt", "part_af45.apt", "part_af45_vc63.ngc", "freecad_two_regions/summary.csv"):
        assert (start / f).stat().st_size > 0, f
    assert (tmp_path / "build" / "analyze" / "my_pocket" / "engagement_map.png").is_file()
    from cnclab.plotting import pdf_page_size_pt
    w_pt = pdf_page_size_pt(start / "paper" / "fig3-1_engagement_vs_stepover.pdf")[0]
    assert abs(w_pt - 85 * 72 / 25.4) < 0.5                      # the 85 mm-wide PDF figure
    # the sweep printed the same table locally and on the Dask cluster
    rows = [ln for ln in res.stdout.splitlines() if ln.startswith("a_e = ")]
    assert len(rows) == 10 and rows[:5] == rows[5:]
