"""Command line: ``python -m cnclab <command> ...``.

Commands are imported lazily, so ``python -m cnclab claims`` does not import torch.
"""
from __future__ import annotations

import importlib
import sys

#: command -> (module, one-line help). Each module has ``main(argv) -> int``.
COMMANDS = {
    "claims": ("cnclab.claims", "compute every ledger row; --work W, --json, --report DIR"),
    "reproduce": ("cnclab.reproduce", "execute every notebook, export HTML/figures, write the claims report"),
    "finish-path": ("cnclab.nc.cli_finish_path", "drop-cutter zig-zag finishing path (APT) over an STL part, the input of spindle"),
    "spindle": ("cnclab.nc.cli_spindle", "constant-v_c spindle/feed post-processing of an APT file against an STL"),
    "nb": ("cnclab.notebook_tools", "notebook housekeeping: from-py, strip, list"),
    "site": ("cnclab.site", "build the offline site build/site/index.html from what build/ holds"),
    "analyze": ("cnclab.nc.cli_analyze", "score any G-code program on a pocket job (summary, traces, engagement map)"),
    "plan": ("cnclab.nc.cli_plan", "plan a pocket job and write a machine-safe program"),
    "job": ("cnclab.toolpath.job_format", "the job file format: reference (--schema), JSON schema, check a file"),
    "job-from-drawing": ("cnclab.nc.cli_drawing", "write a pocket job from a DXF/SVG drawing and cutting data"),
    "figure": ("cnclab.figures", "re-render a figure of the collection for a paper (width in mm, formats, dpi, style)"),
    "programs": ("cnclab.works.programs", "write every program the collection produces to build/gcode/<work>/"),
    "warm": ("cnclab.warm", "compile the shared numba kernels once into their cache (make test/reproduce run it first)"),
}


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help") or argv[0] not in COMMANDS:
        print("usage: python -m cnclab <command> [options]\n\ncommands:")
        for name, (_, hlp) in COMMANDS.items():
            print(f"  {name:<{max(map(len, COMMANDS))}} {hlp}")
        print("\n`python -m cnclab COMMAND --help` explains a command: every option with its unit and default,\n"
              "an example and the files it writes. Getting started: README.md; job files: docs/job-format.md.")
        if argv and argv[0] not in ("-h", "--help"):
            print(f"\nerror: unknown command {argv[0]!r}")
            return 2
        return 0
    try:
        with _terminate_raises():
            mod = importlib.import_module(COMMANDS[argv[0]][0])
    except (KeyboardInterrupt, _Terminated) as exc:          # the command has not started: nothing written
        print("\ninterrupted: nothing written", file=sys.stderr)
        return exc.code if isinstance(exc, _Terminated) else 130
    return int(mod.main(argv[1:]) or 0)


class _Terminated(Exception):
    def __init__(self, code):
        super().__init__(code)
        self.code = code


class _terminate_raises:
    """SIGTERM/SIGHUP raise :class:`_Terminated` (like SIGINT raises KeyboardInterrupt) while the
    command's module is imported (main thread; restored afterwards)."""

    def __enter__(self):
        import signal
        import threading

        self.old = {}
        if threading.current_thread() is threading.main_thread():
            for name in ("SIGTERM", "SIGHUP"):
                sig = getattr(signal, name, None)
                if sig is not None:
                    self.old[sig] = signal.signal(sig, self._raise)
        return self

    @staticmethod
    def _raise(signum, frame):
        raise _Terminated(128 + signum)

    def __exit__(self, *exc):
        import signal

        for sig, h in self.old.items():
            signal.signal(sig, h)
        return False


def _exit(rc: int):
    """Exit with ``rc`` after the command returned: its outputs and exit code are final, so a late
    SIGINT/SIGTERM during interpreter shutdown (numba/LLVM teardown takes a moment) is ignored rather
    than turning a complete run into a "killed by signal" exit status.

    After an interrupt (exit codes 128 + SIGHUP/SIGINT/SIGTERM, the command has already said what is
    on disk) the interpreter is not finalized: the interrupt may have cut a C extension's import in
    the middle (scipy's, ~1.2 s into ``spindle``), and finalizing such a module can crash; CPython
    would also re-kill itself with SIGINT at exit when the KeyboardInterrupt passed through an
    extension's embedded Python code, although the command handled it."""
    import os
    import signal

    for name in ("SIGINT", "SIGTERM", "SIGHUP"):
        sig = getattr(signal, name, None)
        if sig is not None:
            signal.signal(sig, signal.SIG_IGN)
    if rc in {128 + int(getattr(signal, n)) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n)}:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):
                pass
        os._exit(rc)
    sys.exit(rc)


if __name__ == "__main__":
    _exit(main())
