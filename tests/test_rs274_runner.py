"""``cnclab.nc.rs274.run_rs274``: runs of LinuxCNC's interpreter that overlap (two xdist workers, or
``make gcode-check`` beside ``make test``) do not disturb each other.

rs274 keeps its tool data in ``$HOME/.tool.mmap``, opened with ``O_TRUNC`` and mapped shared; with one
HOME for all runs, 6 parallel loops of 40 runs each had 22 deaths by SIGBUS (exit -7) on this machine,
and a CI run of ``make test`` failed once that way. Skipped when rs274 is not installed.
"""
from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from cnclab.nc.rs274 import parse_canonical, rs274_available, run_rs274

FIX = Path(__file__).parent / "fixtures"
PROGRAM = FIX / "freecad" / "star_pocket_adaptive_linuxcnc.ngc"

pytestmark = pytest.mark.skipif(not rs274_available(), reason="LinuxCNC rs274 not installed")


def test_overlapping_runs_all_finish_with_the_same_output():
    with ThreadPoolExecutor(6) as pool:
        outs = list(pool.map(lambda _: run_rs274(PROGRAM), range(24)))
    assert len(set(outs)) == 1
    canon = parse_canonical(outs[0], source=str(PROGRAM))
    assert canon.feed_mm > 0 and canon.program_end


def test_the_users_home_is_left_alone(tmp_path, monkeypatch):
    monkeypatch.setenv("HOME", str(tmp_path))
    run_rs274(PROGRAM)
    assert list(tmp_path.iterdir()) == []
    assert os.environ["HOME"] == str(tmp_path)
