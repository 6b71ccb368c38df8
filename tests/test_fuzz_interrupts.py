"""Interrupt fuzz (issue 28 item 5): SIGINT / SIGTERM sent to ``python -m cnclab plan | analyze |
spindle | finish-path`` at offsets from 0.05 s (while the interpreter is still importing: the
handlers at the top of ``cnclab/__main__.py``) to past the end of an uninterrupted run.

Every outcome is classified:

* ``complete`` -- exit 0, every output on disk and readable (finished, or interrupted after the
  outputs were committed: then stderr says "complete ... on disk");
* ``nothing written`` -- exit 128 + signal, one line "interrupted (SIG...): nothing written" on
  stderr, no traceback, no output and no temporary file;
* ``interpreter start-up`` -- the signal arrived before any cnclab code ran (Python's own start-up:
  ``site`` and its ``.pth`` files, runpy locating the package); Python's default action (killed,
  or "Fatal Python error: init_import_site" / a traceback with no frame in the cnclab package). Accepted only for offsets below twice the measured start-up time
  of the bare interpreter (``python -c pass``), and never with a cnclab frame in the traceback.

Anything else (a crash by SIGSEGV/SIGABRT..., a traceback through cnclab, a message that does not
match the disk, a leftover temporary file) fails. The offsets are fixed (early ones) plus fractions
of a measured uninterrupted run, so all phases are hit whatever the machine's speed.
"""
from __future__ import annotations

import collections
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from cnclab.nc import apt
from cnclab.runtime import pick

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "data" / "mgherony2024"
EARLY = (0.05, 0.1, 0.2, 0.3)
#: fractions of an uninterrupted run (after the early offsets; slow mode only)
FRACTIONS = (0.4, 0.7, 0.95, 1.1)
_CRASH = {-signal.SIGSEGV, -signal.SIGABRT, -signal.SIGBUS, -signal.SIGILL, -signal.SIGFPE}
OUTCOMES = collections.Counter()


def _commands(d: Path) -> dict:
    """command -> (argv after ``python -m cnclab``, output files)."""
    an = d / "an"
    return {
        "plan": (["plan", str(ROOT / "data/pockets/two_regions.json"), "-o", str(d / "p.ngc")], [d / "p.ngc"]),
        "analyze": (["analyze", str(ROOT / "tests/fixtures/freecad/two_regions.ngc"), "--job",
                     str(ROOT / "data/pockets/two_regions.json"), "--resolution", "0.25", "-o", str(an)],
                    [an / n for n in ("summary.csv", "trace.csv", "events.csv", "trace.png", "trace.pdf",
                                      "engagement_map.png")]),
        "spindle": (["spindle", str(SAMPLE / "sample_ch8_part.stl"), str(SAMPLE / "sample_ch8_zigzag_Af0.apt"),
                     "--vc", "63", "--fz", "0.125", "--teeth", "2", "--ap", "0.3", "-o", str(d / "s.apt"),
                     "--gcode", str(d / "s.ngc")], [d / "s.apt", d / "s.ngc"]),
        "finish-path": (["finish-path", str(SAMPLE / "sample_ch8_part.stl"), "-o", str(d / "f.apt"),
                         "--tool-diameter", "10", "--stepover", "5", "--step", "2", "--quiet"], [d / "f.apt"]),
    }


def _run(argv, sig=None, delay=None):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "cnclab", *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=env)
    if sig is not None:
        try:
            proc.wait(timeout=delay)
        except subprocess.TimeoutExpired:
            proc.send_signal(sig)
    out, err = proc.communicate(timeout=600)
    return proc.returncode, out, err, time.perf_counter() - t0


def _startup_s() -> float:
    """Wall time of the bare interpreter's start-up (``python -c pass``, worst of 3)."""
    best = 0.0
    for _ in range(3):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", "pass"], check=True)
        best = max(best, time.perf_counter() - t0)
    return best


def _check_complete(cmd, outs):
    if cmd in ("spindle", "finish-path"):
        apt.read_apt(outs[0]).cl_points()
    if cmd in ("plan", "spindle"):
        assert outs[-1].read_text().rstrip().endswith("%")
    if cmd == "analyze":
        assert "metric" in outs[0].read_text()


def classify(cmd, rc, out, err, outs, sig, delay, startup_s, d: Path) -> str:
    assert rc not in _CRASH, (cmd, delay, rc, err[-2000:])
    assert not [f for f in os.listdir(d) if f.endswith(".tmp") or ".tmp." in f]
    on_disk = [o.exists() for o in outs]
    assert all(on_disk) or not any(on_disk), (cmd, delay, on_disk, err[-1000:])
    if rc == 0:
        assert "Traceback" not in err, err[-2000:]
        _check_complete(cmd, outs)
        return "complete"
    if rc == 128 + sig:
        assert "Traceback" not in err, (cmd, delay, err[-2000:])
        assert not any(on_disk), (cmd, delay, err)
        lines = [ln for ln in err.splitlines() if ln.strip()]
        assert lines and re.fullmatch(r"interrupted \(SIG[A-Z]+\): nothing written.*", lines[-1]), (cmd, delay, err)
        return "nothing written"
    # Python's default action: only before cnclab's first line can run
    assert delay < 2.0 * startup_s, (cmd, delay, rc, startup_s, err[-2000:])
    assert not re.search(r'File "[^"]*/cnclab/', err) and rc in (-sig, 1, 128 + sig), (cmd, delay, rc, err[-2000:])
    return "interpreter start-up"


@pytest.mark.parametrize("cmd", ["plan", "analyze", "spindle", "finish-path"])
def test_interrupt_at_any_offset(tmp_path, cmd):
    argv, outs = _commands(tmp_path)[cmd]
    startup = _startup_s()
    offsets = list(EARLY)
    if pick(True, False):       # slow mode: fractions of an uninterrupted run (fast mode: 1 s, mid-import)
        rc, out, err, full = _run(argv)
        assert rc == 0, err[-2000:]
        assert classify(cmd, rc, out, err, outs, signal.SIGINT, 1e9, startup, tmp_path) == "complete"
        for o in outs:
            o.unlink()
        offsets += [f * full for f in FRACTIONS]
    else:
        offsets.append(1.0)
    kinds = collections.Counter()
    for k, delay in enumerate(offsets):
        sig = signal.SIGINT if k % 2 == 0 else signal.SIGTERM
        rc, out, err, _ = _run(argv, sig, delay)
        kind = classify(cmd, rc, out, err, outs, sig, delay, startup, tmp_path)
        kinds[kind] += 1
        OUTCOMES[(cmd, kind)] += 1
        for o in outs:
            if o.exists():
                o.unlink()
    print(cmd, "interrupt outcomes:", dict(kinds), "offsets", np.round(offsets, 2).tolist())
    assert kinds["nothing written"] >= 2, kinds      # the early offsets really interrupt


def test_handlers_installed_before_heavy_imports():
    """``import cnclab`` imports nothing heavy (the package is lazy), and ``cnclab/__main__.py``
    installs the handlers before its first import of anything else: the window left to Python's
    default action is the interpreter's own start-up."""
    code = "import sys, cnclab; print(sorted(m for m in sys.modules if m.startswith(('numpy', 'cnclab.'))))"
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert res.stdout.strip() == "[]", res.stdout
    src = (ROOT / "cnclab" / "__main__.py").read_text()
    body = src[src.index('"""', 3) + 3:]
    first_install = body.index("_signal.signal(")
    assert re.findall(r"^(?:import|from) \S+", body[:first_install], re.M) == ["import os", "import signal",
                                                                                 "import sys"]
