"""Shared by the process-level fuzz tests (``test_fuzz_interrupts.py``, ``test_fuzz_inputs.py``) and the
long interrupt fuzz (``benchmarks/fuzz_interrupts.py``): run ``python -m cnclab ...`` in a child
process, interrupt it after a delay, and classify what it did.

Outcomes of an interrupted run (:func:`classify_interrupt`):

* ``complete`` -- exit 0, every output on disk and readable (finished, or interrupted after the
  outputs were committed: then stderr says "complete ... on disk");
* ``stopped after writing`` -- exit 128 + signal, every output on disk and readable, the last line
  "interrupted (SIG...): COMMAND stopped after writing <exactly those outputs> (each complete ...)": the
  signal came after the command's last write, before it returned (``cnclab/__main__.py`` reports it);
* ``nothing written`` -- exit 128 + signal, the last line "interrupted (SIG...): nothing written ...",
  no traceback, no output and no temporary file;
* ``interpreter start-up`` -- the signal arrived before any cnclab code ran (Python's own start-up:
  ``site`` and its ``.pth`` files, runpy locating the package): Python's default action (killed by the
  signal, or a ``KeyboardInterrupt`` traceback with no frame in the cnclab package). Accepted only for
  delays below twice the measured start-up time of the bare interpreter (``python -c pass``) or 0.75 s.

Anything else raises :class:`BadOutcome` (a crash by SIGSEGV/SIGABRT..., a traceback through cnclab,
"Exception ignored" -- an exception a callback or finalizer dropped --, a message that does not match
the disk, a leftover temporary file).
"""
from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: exit codes of a process killed by a crash signal
CRASH = {-signal.SIGSEGV, -signal.SIGABRT, -signal.SIGBUS, -signal.SIGILL, -signal.SIGFPE}


class BadOutcome(AssertionError):
    """An interrupted run that crashed, lied about the disk or printed a traceback; ``kind`` names the
    class (``crash``, ``temporary file left``, ``partial outputs``, ``traceback``, ``exception ignored``,
    ``lying message``, ``early default action``)."""

    def __init__(self, kind: str, detail):
        super().__init__(f"{kind}: {detail}")
        self.kind = kind


def _dispositions(ignored):
    """In the child before exec: SIGINT/SIGTERM/SIGHUP at their default action (a handler is reset by
    exec anyway, but SIG_IGN survives it: a test run as a background job of a non-interactive shell
    has SIGINT ignored), except ``ignored``, which the child is started with ignored."""
    def reset():
        for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            signal.signal(s, signal.SIG_IGN if s in ignored else signal.SIG_DFL)
    return reset


def run_cli(argv, sig=None, delay=None, env=None, timeout=600.0, ignored=()):
    """``python -m cnclab *argv`` in a child process (this checkout first on ``PYTHONPATH``; ``env``:
    extra variables; ``ignored``: signals it starts with ignored, as under ``nohup``), sent ``sig`` after
    ``delay`` s unless it has ended; (rc, stdout, stderr, wall s)."""
    full_env = dict(os.environ, PYTHONPATH=str(ROOT), **(env or {}))
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "cnclab", *map(str, argv)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=full_env, preexec_fn=_dispositions(set(ignored)))
    if sig is not None:
        try:
            proc.wait(timeout=delay)
        except subprocess.TimeoutExpired:
            proc.send_signal(sig)
    out, err = communicate_or_dump(proc, timeout)
    return proc.returncode, out, err, time.perf_counter() - t0


def communicate_or_dump(proc, timeout: float):
    """``proc.communicate(timeout)`` (the pipes are read, so a chatty child cannot block on a full
    pipe); a child still running after ``timeout`` s is sent SIGABRT -- a child started with
    ``python -X faulthandler`` (or ``-m cnclab``, which enables it) then prints every thread's stack --
    and the test fails with that stderr: a hang is reported with its place, not as a bare timeout."""
    try:
        return proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGABRT)
        try:
            out, err = proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            out, err = proc.communicate()
        err = err.decode(errors="replace") if isinstance(err, bytes) else err
        raise AssertionError(f"child {proc.args!r} still running {timeout} s after it was started or "
                             f"signalled; its stacks (SIGABRT):\n{err[-6000:]}") from None


def startup_s(n: int = 3) -> float:
    """Wall time (s) of the bare interpreter's start-up (``python -c pass``, worst of ``n``). On a
    loaded machine it varies several-fold (0.03 to 0.7 s seen on 2 shared cores): measure it next to
    the runs it judges (before and after them)."""
    worst = 0.0
    for _ in range(n):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", "pass"], check=True)
        worst = max(worst, time.perf_counter() - t0)
    return worst


def temporary_files(d: Path) -> list:
    return [f for f in os.listdir(d) if f.endswith(".tmp") or ".tmp." in f]


def classify_interrupt(rc, err, outs, sig, delay, startup, d: Path, check_complete=None) -> str:
    """The outcome class of a run of a command writing ``outs`` (in folder ``d``) sent ``sig`` after
    ``delay`` s (see the module docstring); ``check_complete(outs)`` reads complete outputs back.
    Raises :class:`BadOutcome` for anything else."""
    def bad(kind, ok):
        if not ok:
            raise BadOutcome(kind, (delay, rc, err[-2000:]))

    bad("crash", rc not in CRASH and "Fatal Python error: Segmentation" not in err)
    bad("temporary file left", not temporary_files(d))
    on_disk = [Path(o).exists() for o in outs]
    bad("partial outputs", all(on_disk) or not any(on_disk))
    bad("exception ignored", "Exception ignored" not in err)
    if rc == 0:
        bad("traceback", "Traceback" not in err)
        bad("lying message", all(on_disk) and "nothing written" not in err)
        if check_complete is not None:
            check_complete(outs)
        return "complete"
    if rc == 128 + sig:
        bad("traceback", "Traceback" not in err)
        lines = [ln for ln in err.splitlines() if ln.strip()]
        if any(on_disk):
            # the signal came after the command's last output was committed (after its
            # InterruptReport window, before it returned): __main__ names exactly what is on disk
            m = re.fullmatch(r"interrupted \(SIG[A-Z]+\): \S+ stopped after writing (.*) \(each complete, "
                             r"written atomically\); no other output was written", lines[-1] if lines else "")
            bad("lying message", m is not None and set(m.group(1).split(", ")) == {str(o) for o in outs})
            if check_complete is not None:
                check_complete(outs)
            return "stopped after writing"
        bad("lying message", bool(lines)
            and re.fullmatch(r"interrupted \(SIG[A-Z]+\): nothing written.*", lines[-1]) is not None)
        return "nothing written"
    # Python's default action: only before cnclab's first line can run
    # (the evidence decides: no cnclab frame, nothing on disk, Python's exit codes; the delay bound only
    # guards against a cnclab that installs its handlers late, generous because the start-up of
    # `python -m cnclab` under load is longer than the bare interpreter's measured next to it)
    bad("early default action", delay < max(2.0 * startup, 0.75) and not any(on_disk)
        and not re.search(r'File "[^"]*/cnclab/', err) and rc in (-sig, 1, 128 + sig))
    return "interpreter start-up"


SAMPLE = ROOT / "data" / "mgherony2024"


def commands(d: Path) -> dict:
    """command -> (argv after ``python -m cnclab``, its output files in ``d``): a run of each command
    on the repository's sample inputs (a few seconds each)."""
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


def check_complete(cmd: str):
    """A function reading back the complete outputs of ``cmd`` (see :func:`commands`)."""
    def check(outs):
        from cnclab.nc import apt

        if cmd in ("spindle", "finish-path"):
            apt.read_apt(outs[0]).cl_points()
        if cmd in ("plan", "spindle"):
            assert Path(outs[-1]).read_text().rstrip().endswith("%")
        if cmd == "analyze":
            assert "metric" in Path(outs[0]).read_text()
    return check
