"""Command line: ``python -m cnclab <command> ...``.

Commands are imported lazily, so ``python -m cnclab claims`` does not import torch.

Interrupts: the first statements below (before any other import; ``_signal``, the built-in C module,
not ``signal``, whose enum set-up takes ~1 ms) make SIGINT, SIGTERM and SIGHUP end
the process at once with one line "interrupted (SIG...): nothing written ..." and exit code
128 + signal number (130, 143, 129), until the command's ``main`` starts; nothing is on disk then
(``cnclab/__init__.py`` imports nothing, so this is reached ~1 ms after the interpreter's own
start-up). While the command runs, SIGINT raises ``KeyboardInterrupt`` and SIGTERM/SIGHUP
``SystemExit(128 + signum)`` (temporary files of atomic writes are removed on the way out); the
commands that write files say what is on disk (:class:`cnclab.fileio.InterruptReport`), and an
interrupt no command handled (e.g. during its argument parsing) is reported here, naming the outputs
the atomic writers committed (:func:`cnclab.fileio.committed_outputs`; usually none: "nothing written").
"""
import _signal as _csignal      # the C module (built in: no import work), so the handlers are in first
import os as _os                # (os and sys are loaded by the interpreter's start-up already)
import sys

#: the signals an interrupt arrives by, and their names (the C module has no ``Signals`` enum)
_SIGNAL_NAMES = ("SIGINT", "SIGTERM", "SIGHUP")
_NAME_OF = {getattr(_csignal, n): n for n in _SIGNAL_NAMES if hasattr(_csignal, n)}


def _stop_before_start(signum, frame):
    """Signal handler until the command starts: one line on stderr, exit 128 + signum, no traceback and no
    interpreter finalization (an import cut in the middle cannot crash a finalizer)."""
    try:
        _os.write(2, f"\ninterrupted ({_NAME_OF.get(signum, signum)}): nothing written (the command had not "
                     "started)\n".encode())
    finally:
        _os._exit(128 + signum)


#: the signals this process was started with ignored (SIG_IGN survives exec: ``nohup`` ignores SIGHUP,
#: a non-interactive shell starts a background job with SIGINT ignored): left ignored throughout
_IGNORED_AT_START = set()
if __name__ == "__main__":
    for _sig in _NAME_OF:
        if _csignal.getsignal(_sig) == _csignal.SIG_IGN:
            _IGNORED_AT_START.add(_sig)
            continue
        _csignal.signal(_sig, _stop_before_start)
        # restart system calls the signal interrupts (SA_RESTART): Python retries its own calls
        # on EINTR (PEP 475), C libraries in other threads (numba/LLVM, BLAS) may not
        _csignal.siginterrupt(_sig, False)
    import faulthandler as _faulthandler

    # a crash (SIGSEGV, SIGBUS, SIGABRT, ...) prints every thread's Python stack on stderr: a test or a
    # user that sees one then has the place, not an empty stderr (one rare SIGSEGV after a SIGINT 1 s
    # into `plan` under a loaded CI machine is not yet explained)
    _faulthandler.enable()

import signal as _signal  # noqa: E402  (the Python module: its enum set-up takes ~1 ms, after the handlers)
import importlib  # noqa: E402  (after the handlers: everything below may be interrupted)

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
    from cnclab import fileio

    fileio.keep_ignored(_IGNORED_AT_START)       # InterruptReport & co. leave them ignored
    mod = importlib.import_module(COMMANDS[argv[0]][0])   # an interrupt here: _stop_before_start
    with _interrupts_raise():
        try:
            return int(mod.main(argv[1:]) or 0)
        except (KeyboardInterrupt, _Interrupted) as exc:
            _ignore_signals()     # a second interrupt cannot cut this message
            signum = exc.signum if isinstance(exc, _Interrupted) else _signal.SIGINT
            print("\n" + _unhandled_interrupt_message(argv[0], signum), file=sys.stderr)
            return 128 + signum


def _unhandled_interrupt_message(command: str, signum: int) -> str:
    """What an interrupt the command did not report (e.g. during its argument parsing, before its
    :class:`cnclab.fileio.InterruptReport`) leaves on disk: every output goes through the atomic
    writers, which record what they committed (:func:`cnclab.fileio.committed_outputs`)."""
    from cnclab.fileio import committed_outputs

    name = _signal.Signals(signum).name
    done = list(dict.fromkeys(str(p) for p in committed_outputs()))
    if not done:
        return f"interrupted ({name}): nothing written ({command} stopped before it wrote any output)"
    return (f"interrupted ({name}): {command} stopped after writing {', '.join(done)} (each complete, written "
            "atomically); no other output was written")


class _Interrupted(SystemExit):
    """SIGTERM / SIGHUP while a command runs: a ``SystemExit(128 + signum)`` (like
    :func:`cnclab.fileio.cleanup_on_signals`), so atomic writes clean up on the way out."""

    def __init__(self, signum):
        super().__init__(128 + signum)
        self.signum = signum


class _interrupts_raise:
    """While a command runs (main thread): SIGINT raises ``KeyboardInterrupt``, SIGTERM/SIGHUP
    :class:`_Interrupted`; the start-up handlers are restored afterwards (a late signal during the
    exit is then ignored by :func:`_exit`)."""

    def __enter__(self):
        import threading

        self.old = {}
        if threading.current_thread() is threading.main_thread():
            for name in _SIGNAL_NAMES:
                sig = getattr(_signal, name, None)
                if sig is not None and sig not in _IGNORED_AT_START:
                    self.old[sig] = _signal.signal(sig, self._raise)
                    _signal.siginterrupt(sig, False)     # as at start-up: no EINTR in C code
        return self

    @staticmethod
    def _raise(signum, frame):
        from cnclab.fileio import raise_outside_native_code

        raise_outside_native_code(signum, frame, KeyboardInterrupt() if signum == _signal.SIGINT
                                  else _Interrupted(signum))

    def __exit__(self, *exc):
        for sig, h in self.old.items():      # after the command, "nothing written" would be a lie: ignore
            _signal.signal(sig, _signal.SIG_IGN if h is _stop_before_start else h)
        return False


def _ignore_signals():
    for name in _SIGNAL_NAMES:
        if hasattr(_signal, name):
            _signal.signal(getattr(_signal, name), _signal.SIG_IGN)


def _exit(rc: int):
    """Exit with ``rc`` after the command returned: its outputs and exit code are final, so a late
    SIGINT/SIGTERM during interpreter shutdown (numba/LLVM teardown takes a moment) is ignored rather
    than turning a complete run into a "killed by signal" exit status.

    After an interrupt (exit codes 128 + SIGHUP/SIGINT/SIGTERM, the command has already said what is
    on disk) the interpreter is not finalized: the interrupt may have cut a C extension's import in
    the middle (scipy's, ~1.2 s into ``spindle``), and finalizing such a module can crash; CPython
    would also re-kill itself with SIGINT at exit when the KeyboardInterrupt passed through an
    extension's embedded Python code, although the command handled it."""
    _ignore_signals()
    if rc in {128 + int(getattr(_signal, n)) for n in _SIGNAL_NAMES if hasattr(_signal, n)}:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):
                pass
        _os._exit(rc)
    sys.exit(rc)


if __name__ == "__main__":
    _exit(main())
