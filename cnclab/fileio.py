"""Safe output writing: atomic replace, never overwrite an input file.

Every file cnclab writes goes through :func:`atomic_write` (or :func:`atomic_output`): the content
is written to a temporary file in the destination folder and moved into place with
:func:`os.replace`, so a reader never sees a partial file and a failure leaves nothing behind.
"""
from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path
from typing import Iterator


def _check_not_input(dest: Path, inputs) -> None:
    for src in inputs or ():
        src = Path(src)
        if src.exists() and dest.exists() and os.path.samefile(src, dest):
            raise ValueError(f"refusing to overwrite the input file {src}: choose another output path")


@contextlib.contextmanager
def atomic_output(path, mode: str = "w", inputs=(), **open_kwargs) -> Iterator:
    """Open a temporary file next to ``path``; on success move it to ``path`` atomically.

    ``inputs``: paths that must not be overwritten (ValueError if ``path`` is one of them).
    On any exception the temporary file is removed and ``path`` is left untouched.

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> with atomic_output(d / "a.txt") as fh:
    ...     _ = fh.write("hello")
    >>> (d / "a.txt").read_text()
    'hello'
    """
    dest = Path(path)
    _check_not_input(dest, inputs)
    dest.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{dest.name}.", suffix=".tmp", dir=dest.parent)
    try:
        with os.fdopen(fd, mode, **open_kwargs) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, dest)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def atomic_write(path, data, inputs=()) -> Path:
    """Write ``data`` (str or bytes) to ``path`` atomically; returns the path."""
    mode = "wb" if isinstance(data, (bytes, bytearray)) else "w"
    kwargs = {} if mode == "wb" else {"encoding": "utf-8", "newline": ""}
    with atomic_output(path, mode, inputs=inputs, **kwargs) as fh:
        fh.write(data)
    return Path(path)
