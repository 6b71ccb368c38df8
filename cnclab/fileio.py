"""Safe output writing: atomic replace, never overwrite an input file.

Every file cnclab writes goes through :func:`atomic_write` (or :func:`atomic_output`,
:func:`atomic_write_many`): the content is written to a temporary file in the destination folder and
moved into place with :func:`os.replace`, so a reader never sees a partial file and a failure leaves
nothing behind.

* Permissions: the result gets the mode a plain ``open(path, "w")`` would give, ``0o666 & ~umask``
  (``tempfile.mkstemp`` creates 0600, which would otherwise survive the rename).
* Signals: :func:`cleanup_on_signals` (used by the command-line tools) turns SIGTERM (and SIGHUP)
  into ``SystemExit`` so the same cleanup runs as for SIGINT (``KeyboardInterrupt``) and for errors.
  Temporary files in progress are registered (:func:`live_temporary_files`).
* Several outputs of one run: :func:`atomic_write_many` writes all temporary files first and renames
  them only when every one is complete, so a failure on one target leaves no output at all.
"""
from __future__ import annotations

import contextlib
import os
import signal
import tempfile
import threading
from pathlib import Path
from typing import Iterator

__all__ = ["atomic_output", "atomic_write", "atomic_write_many", "cleanup_on_signals", "deferred_signals",
           "same_file", "check_outputs", "live_temporary_files", "InterruptReport", "in_native_callback",
           "redeliver_later", "raise_outside_native_code", "committed_outputs", "keep_ignored"]

_LIVE_TMP: set = set()
_COMMITTED: list = []      # every output this process moved into place (committed_outputs)
#: signal numbers the process was started with ignored (:func:`keep_ignored`)
_INHERITED_IGNORED: set = set()
_LOCK = threading.Lock()


def keep_ignored(signals) -> None:
    """Record the signal numbers this process was started with ignored (SIG_IGN survives exec:
    ``nohup`` ignores SIGHUP, a non-interactive shell starts its background jobs with SIGINT
    ignored); :class:`InterruptReport` and :func:`cleanup_on_signals` then leave them ignored, as
    Python itself does for SIGINT. Called once by ``python -m cnclab`` before it installs anything.

    >>> keep_ignored([])
    """
    _INHERITED_IGNORED.update(int(s) for s in signals)


def _umask() -> int:
    with _LOCK:
        old = os.umask(0)
        os.umask(old)
    return old


def same_file(a, b) -> bool:
    """True if the paths name the same file (existing: same inode; else same absolute resolved path)."""
    a, b = Path(a), Path(b)
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
    except OSError:
        pass
    return a.resolve() == b.resolve()


def _check_not_input(dest: Path, inputs) -> None:
    for src in inputs or ():
        if same_file(src, dest):
            raise ValueError(f"refusing to overwrite the input file {src}: choose another output path")


def check_outputs(outputs, inputs=(), names=None) -> None:
    """ValueError if an output is an input or two outputs are the same file (names: option names)."""
    outs = [Path(p) for p in outputs if p is not None]
    names = names or [str(p) for p in outs]
    for k, p in enumerate(outs):
        _check_not_input(p, inputs)
        for q, nq in zip(outs[:k], names[:k]):
            if same_file(p, q):
                raise ValueError(f"{names[k]} ({p}) and {nq} ({q}) name the same file: choose different outputs")


def _make_parent(dest: Path) -> None:
    """Create the folder of ``dest``; a clear error (naming the output) when a parent is a file."""
    for q in [dest.parent, *dest.parent.parents]:
        if q.exists():
            if not q.is_dir():
                raise NotADirectoryError(f"cannot write {dest}: {q} is a file, not a folder")
            break
    dest.parent.mkdir(parents=True, exist_ok=True)


def _mkstemp(dest: Path):
    _make_parent(dest)
    fd, tmp = tempfile.mkstemp(prefix=f".{dest.name}.", suffix=".tmp", dir=dest.parent)
    with _LOCK:
        _LIVE_TMP.add(tmp)
    try:
        os.fchmod(fd, 0o666 & ~_umask())
    except BaseException:
        os.close(fd)
        _discard(tmp)
        raise
    return fd, tmp


def _discard(tmp) -> None:
    with contextlib.suppress(FileNotFoundError):
        os.unlink(tmp)
    with _LOCK:
        _LIVE_TMP.discard(tmp)


@contextlib.contextmanager
def atomic_output(path, mode: str = "w", inputs=(), **open_kwargs) -> Iterator:
    """Open a temporary file next to ``path``; on success move it to ``path`` atomically.

    ``inputs``: paths that must not be overwritten (ValueError if ``path`` is one of them).
    On any exception (also KeyboardInterrupt / SystemExit) the temporary file is removed and
    ``path`` is left untouched. The result has mode ``0o666 & ~umask``.

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> with atomic_output(d / "a.txt") as fh:
    ...     _ = fh.write("hello")
    >>> (d / "a.txt").read_text()
    'hello'
    """
    dest = Path(path)
    _check_not_input(dest, inputs)
    fd, tmp = _mkstemp(dest)
    try:
        with os.fdopen(fd, mode, **open_kwargs) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, dest)
        with _LOCK:
            _LIVE_TMP.discard(tmp)
            _COMMITTED.append(dest)
    except BaseException:
        _discard(tmp)
        raise


def atomic_write(path, data, inputs=()) -> Path:
    """Write ``data`` (str or bytes) to ``path`` atomically; returns the path."""
    mode = "wb" if isinstance(data, (bytes, bytearray)) else "w"
    kwargs = {} if mode == "wb" else {"encoding": "utf-8", "newline": ""}
    with atomic_output(path, mode, inputs=inputs, **kwargs) as fh:
        fh.write(data)
    return Path(path)


def atomic_write_many(items, inputs=()) -> list:
    """Write several files together: all or none.

    ``items``: (path, data) pairs (data str or bytes). Every output is checked against ``inputs``
    and the others (no two outputs may be the same file), every temporary file is written and
    synced, and only then are they renamed into place. Any failure before the renames removes
    every temporary file and leaves all destinations untouched.

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> [p.name for p in atomic_write_many([(d / "a.txt", "A"), (d / "b.bin", b"B")])]
    ['a.txt', 'b.bin']
    """
    items = [(Path(p), data) for p, data in items]
    check_outputs([p for p, _ in items], inputs)
    for dest, _ in items:
        if dest.is_dir():
            raise IsADirectoryError(f"{dest}: is a directory, not a file name for an output")
    tmps, backups, done = [], [], []
    try:
        for dest, data in items:
            fd, tmp = _mkstemp(dest)
            tmps.append(tmp)
            binary = isinstance(data, (bytes, bytearray))
            with os.fdopen(fd, "wb" if binary else "w", **({} if binary else {"encoding": "utf-8",
                                                                              "newline": ""})) as fh:
                fh.write(data)
                fh.flush()
                os.fsync(fh.fileno())
    except BaseException:
        for tmp in tmps:
            _discard(tmp)
        raise
    with deferred_signals():      # the renames (or their rollback) run to the end: all or none
        _commit(items, tmps, backups, done)
    return [p for p, _ in items]


def _commit(items, tmps, backups, done) -> None:
    """Rename the complete temporary files into place; on any failure undo the renames made."""
    try:
        for (dest, _), tmp in zip(items, tmps):
            bak = None
            if dest.exists():      # keep the old content until every rename succeeded (rollback)
                bak = f"{tmp}.bak"
                with _LOCK:
                    _LIVE_TMP.add(bak)
                os.link(dest, bak)
            backups.append(bak)
            os.replace(tmp, dest)
            done.append(dest)
            with _LOCK:
                _LIVE_TMP.discard(tmp)
    except BaseException:
        for dest, bak in zip(done, backups):       # undo the renames already made
            with contextlib.suppress(OSError):
                if bak is not None:
                    os.replace(bak, dest)
                else:
                    os.unlink(dest)
        for tmp in tmps + [b for b in backups if b]:
            _discard(tmp)
        raise
    for b in backups:
        if b:
            _discard(b)
    with _LOCK:
        _COMMITTED.extend(done)


@contextlib.contextmanager
def deferred_signals(signals=("SIGINT", "SIGTERM", "SIGHUP")):
    """While active, the given signals are only recorded; on exit the handlers are restored and the
    first recorded signal is delivered to the handler that was in force (``KeyboardInterrupt`` for
    SIGINT, ``SystemExit`` under :func:`cleanup_on_signals`, the default action otherwise). For
    steps that must not be cut in the middle (the renames of :func:`atomic_write_many`): an
    interrupt then lands before or after them, never between. Main thread only; elsewhere a no-op.

    >>> import signal, os
    >>> try:
    ...     with deferred_signals():
    ...         os.kill(os.getpid(), signal.SIGINT); done = "the block ran to its end"
    ... except KeyboardInterrupt:
    ...     print(done, "- then KeyboardInterrupt")
    the block ran to its end - then KeyboardInterrupt
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    got, old = [], {}

    def record(signum, frame):
        got.append(signum)

    for name in signals:
        sig = getattr(signal, name, None)
        if sig is not None:
            old[sig] = signal.signal(sig, record)
    try:
        yield
    finally:
        for sig, h in old.items():
            signal.signal(sig, h)
        if got:
            h = old[got[0]]
            if callable(h):
                h(got[0], None)
            elif h == signal.SIG_DFL:
                signal.raise_signal(got[0])


def _raise_exit(signum, frame):
    # the exception unwinds through atomic_output / atomic_write_many, which remove their temporary
    # files and roll back renames already made (deleting files here could break that rollback)
    raise_outside_native_code(signum, frame, SystemExit(128 + signum))


def committed_outputs() -> list:
    """The outputs (paths) this process has written completely so far, in the order they were moved
    into place by :func:`atomic_output`, :func:`atomic_write` or :func:`atomic_write_many`: what an
    interrupt leaves on disk (``python -m cnclab`` names them when a command did not say it).

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "a.txt"
    >>> _ = atomic_write(p, "A")
    >>> committed_outputs()[-1] == p
    True
    """
    with _LOCK:
        return list(_COMMITTED)


def live_temporary_files() -> list:
    """Temporary files of atomic writes in progress (for diagnostics and tests)."""
    with _LOCK:
        return sorted(_LIVE_TMP)


@contextlib.contextmanager
def cleanup_on_signals(signals=("SIGTERM", "SIGHUP")):
    """While active, the given signals raise ``SystemExit(128 + signum)``, so ``atomic_output`` and
    ``atomic_write_many`` clean up as for an error. Main thread only; elsewhere a no-op. SIGINT
    already raises ``KeyboardInterrupt``."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = {}
    for name in signals:
        sig = getattr(signal, name, None)
        if sig is not None and sig not in _INHERITED_IGNORED:
            old[sig] = signal.signal(sig, _raise_exit)
    try:
        yield
    finally:
        for sig, h in old.items():
            signal.signal(sig, h)


def _identity(path):
    """What names the file now (inode, mtime, size), or None: an atomic write replaces all three."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_ino, st.st_mtime_ns, st.st_size


#: Python functions that native code calls back into, as (file name ending, function name): llvmlite's
#: object-cache hooks (``llvmlite/binding/executionengine.py``, wrapped by ``ctypes.CFUNCTYPE`` and
#: called by LLVM while numba compiles). An exception raised in them (or in anything they call) is
#: printed and dropped by ctypes ("Exception ignored on calling ctypes callback function"), and the
#: native code goes on in a state it did not expect (a rare SIGSEGV was seen after one).
_NATIVE_CALLBACKS = tuple((os.path.join("llvmlite", "binding", "executionengine.py"), name)
                          for name in ("_raw_object_cache_notify", "_raw_object_cache_getbuffer"))

#: Packages whose Python code runs under native machinery: numba's dispatcher (C) calls into numba's
#: Python code to type arguments and to compile or load a kernel from its cache, and numba's compiler
#: holds a global lock taken in Python. A KeyboardInterrupt raised there was seen to surface as
#: "SystemError: CPUDispatcher(pass_kernel) returned a result with an exception set" (a CI fuzz run,
#: SIGINT 1.5 s into `plan`), and one raised between a lock's acquire and its ``with`` block leaves the
#: lock held for good. A signal arriving there is delivered again once the call is back in other code.
_DEFER_PACKAGES = ("numba", "llvmlite")


def _package_dirs() -> tuple:
    """The folders (with a trailing separator) of the :data:`_DEFER_PACKAGES` imported so far."""
    import sys

    dirs = []
    for name in _DEFER_PACKAGES:
        f = getattr(sys.modules.get(name), "__file__", None)
        if f:
            dirs.append(os.path.dirname(os.path.abspath(f)) + os.sep)
    return tuple(dirs)


def in_native_callback(frame) -> bool:
    """True when ``frame`` (a signal handler's frame argument) or a caller of it runs inside a callback
    from native code (one of ``_NATIVE_CALLBACKS``), in numba/llvmlite's own Python code
    (:data:`_DEFER_PACKAGES`) or in a ``__del__`` finalizer, where an exception must not be raised.

    >>> import sys
    >>> in_native_callback(sys._getframe())
    False
    """
    dirs = _package_dirs()
    while frame is not None:
        code = frame.f_code
        if any(code.co_name == name and code.co_filename.endswith(os.sep + tail) for tail, name in _NATIVE_CALLBACKS):
            return True
        if code.co_name == "__del__":
            # a finalizer (tqdm's, at exit): Python prints and drops an exception raised in it
            # ("Exception ignored in ... __del__"): deliver the signal once it has returned
            return True
        if dirs and code.co_filename.startswith(dirs):
            return True
        frame = frame.f_back
    return False


def redeliver_later(signum: int, delay_s: float = 0.05) -> None:
    """Send ``signum`` to this process again after ``delay_s`` seconds (s), from a daemon timer
    thread: a handler that must not raise now (:func:`in_native_callback`) gets the signal again once
    the native code has returned."""
    t = threading.Timer(delay_s, os.kill, (os.getpid(), signum))
    t.daemon = True
    t.start()


def raise_outside_native_code(signum: int, frame, exc: BaseException) -> None:
    """What every signal handler here does: raise ``exc`` now, or -- when ``frame`` runs inside a
    callback from native code (:func:`in_native_callback`) -- send ``signum`` again shortly
    (:func:`redeliver_later`) so the handler raises once the native code has returned."""
    if in_native_callback(frame):
        redeliver_later(signum)
        return
    raise exc


class InterruptReport:
    """For a command-line run writing ``outputs``: SIGINT / SIGTERM / SIGHUP at any moment end it with a
    message that says what is on disk, and an exit code that follows it.

    While active (main thread), a signal is recorded and raised (``KeyboardInterrupt`` for SIGINT,
    ``SystemExit(128 + signum)`` for the others), so temporary files are removed and renames rolled
    back on the way out (:func:`atomic_write_many` defers signals during its renames: outputs are all
    new or all old). :meth:`check` raises a recorded signal again (a library may have swallowed the
    exception, e.g. in a ``__del__``). :meth:`exit_code` (in the ``except`` clause) compares the
    outputs with their state at the start: all replaced -> "complete ... on disk", exit 0; none ->
    "nothing written", exit 128 + signum.

    >>> import os, signal, tempfile, pathlib
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "a.txt"
    >>> with InterruptReport([out]) as run:
    ...     try:
    ...         os.kill(os.getpid(), signal.SIGINT)
    ...         for _ in range(100): pass
    ...     except KeyboardInterrupt as exc:
    ...         code = run.exit_code(exc, quiet=True)
    >>> code, out.exists()
    (130, False)
    """

    NAMES = ("SIGINT", "SIGTERM", "SIGHUP")

    def __init__(self, outputs):
        self.outputs = [Path(p) for p in outputs if p is not None]
        self.before = {p: _identity(p) for p in self.outputs}
        self.signum = None
        self.old = {}

    def _handler(self, signum, frame):
        self.signum = self.signum or signum
        raise_outside_native_code(signum, frame, KeyboardInterrupt() if signum == signal.SIGINT
                                  else SystemExit(128 + signum))

    @staticmethod
    def _raise(signum):
        if signum == signal.SIGINT:
            raise KeyboardInterrupt
        raise SystemExit(128 + signum)

    def check(self) -> None:
        """Raise the recorded signal again (no-op without one)."""
        if self.signum is not None:
            self._raise(self.signum)

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for name in self.NAMES:
                sig = getattr(signal, name, None)
                if sig is not None and sig not in _INHERITED_IGNORED:
                    self.old[sig] = signal.signal(sig, self._handler)
        return self

    def __exit__(self, *exc):
        for sig, h in self.old.items():
            signal.signal(sig, h)
        self.old = {}
        return False

    def call(self, body, errors=(ValueError, OSError), message=None) -> int:
        """A command's tail, the one copy: run ``body()`` with the report active and return the exit
        code — 0 when it returns; after an interrupt :meth:`exit_code`'s (a signal a library turned
        into one of ``errors`` included); after another exception of ``errors`` the line
        ``message(exc)`` (default ``"error: <exc>"``) on stderr and 2. Anything else propagates.

        >>> InterruptReport([]).call(lambda: None)
        0
        >>> import contextlib, io
        >>> with contextlib.redirect_stderr(io.StringIO()) as err:
        ...     code = InterruptReport([]).call(lambda: int("x"))
        >>> code, err.getvalue().startswith("error: invalid literal")
        (2, True)
        """
        import sys

        try:
            with self:
                body()
                self.check()
        except (KeyboardInterrupt, SystemExit) as exc:
            code = self.exit_code(exc)
            if code is None:
                raise
            return code
        except errors as exc:
            if self.signum is not None:            # a library turned the interrupt into an error
                return self.exit_code(KeyboardInterrupt())
            sys.stdout.flush(), sys.stderr.flush()
            print(message(exc) if message else f"error: {exc}", file=sys.stderr)
            return 2
        return 0

    def exit_code(self, exc: BaseException, quiet: bool = False):
        """The exit code after ``exc`` (None: ``exc`` is not an interrupt, re-raise it); the message is
        printed on stderr unless ``quiet``."""
        import sys

        if self.signum is None and not isinstance(exc, KeyboardInterrupt):
            return None
        signum = self.signum or signal.SIGINT
        name = signal.Signals(signum).name
        new = [p for p in self.outputs if _identity(p) is not None and _identity(p) != self.before[p]]
        if new and len(new) == len(self.outputs):
            msg, code = (f"{name} after the outputs were written: complete {' and '.join(map(str, new))} on disk "
                         "(the summary was not printed)"), 0
        elif not new:
            msg, code = f"interrupted ({name}): nothing written (no output created or changed, no temporary file left)", \
                128 + signum
        else:                           # not expected: the renames run with signals deferred
            msg, code = f"interrupted ({name}) while writing: {', '.join(map(str, new))} written, the others not", \
                128 + signum
        if not quiet:
            print("\n" + msg, file=sys.stderr)
        return code
