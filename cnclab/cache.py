"""Content-addressed cache of expensive results under ``build/cache/``.

A result is stored under a key made of the function's qualified name, the **fast-mode flag**
(``CNCLAB_FAST``: a value computed with fast mode's settings is never served to a full run), a hash of the **source files
of the cnclab modules it depends on** (its own module and every cnclab module it imports,
transitively, found by reading the ``import`` statements), a hash of the **data files it reads**
(given to the decorator) and its **arguments**. Change any of these and the key changes, so a stale
value can never be returned; change something the function does not depend on and it is reused.

* :func:`cached` — decorator: ``@cached(data=("mgherony2024/x.csv",))``.
* :func:`map_cached` — evaluate a cached function over many argument tuples, sharing the work
  with other processes (xdist workers, parallel notebooks): a process computes an entry only when it
  holds that entry's lock, skips entries another process is computing and picks them up at the end.
* ``CNCLAB_NO_CACHE=1`` ignores the cache (computes, does not read or write); ``CNCLAB_CACHE_DIR``
  moves it (default ``<build>/cache``).

Values are pickled and written atomically (:func:`cnclab.fileio.atomic_write`).

>>> import tempfile, os
>>> old = os.environ.get("CNCLAB_CACHE_DIR")
>>> os.environ["CNCLAB_CACHE_DIR"] = tempfile.mkdtemp()
>>> @cached()
... def square(x):
...     return x * x
>>> square(3), square(3), square.last_hit
(9, 9, True)
>>> _ = os.environ.pop("CNCLAB_CACHE_DIR") if old is None else os.environ.update(CNCLAB_CACHE_DIR=old)
"""
from __future__ import annotations

import ast
import functools
import hashlib
import importlib.util
import os
import pickle
import sys
from pathlib import Path
from typing import Callable, Iterable, Sequence

from .fileio import atomic_write
from .paths import DATA_DIR, PACKAGE_DIR, build_dir
from .runtime import fast_mode

__all__ = ["cache_dir", "enabled", "module_closure", "code_hash", "data_hash", "cache_key", "cached",
           "map_cached"]

NO_CACHE_ENV = "CNCLAB_NO_CACHE"
CACHE_DIR_ENV = "CNCLAB_CACHE_DIR"


def cache_dir() -> Path:
    """``$CNCLAB_CACHE_DIR`` or ``<build>/cache``, created on demand."""
    p = Path(os.environ.get(CACHE_DIR_ENV) or (build_dir() / "cache"))
    p.mkdir(parents=True, exist_ok=True)
    return p


def enabled() -> bool:
    """False when ``CNCLAB_NO_CACHE`` is set to a true value (1/true/yes/on)."""
    return os.environ.get(NO_CACHE_ENV, "").strip().lower() not in {"1", "true", "yes", "on"}


def _module_file(name: str) -> Path | None:
    if not (name == "cnclab" or name.startswith("cnclab.")):
        return None
    rel = Path(*name.split(".")[1:])
    for cand in (PACKAGE_DIR / rel / "__init__.py", (PACKAGE_DIR / rel).with_suffix(".py")):
        if cand.is_file():
            return cand
    return None


def _imports(path: Path, modname: str) -> frozenset:
    """Absolute names of the modules ``path`` (module ``modname``) imports, anywhere in the file."""
    return _imports_cached(path, modname, path.stat().st_mtime_ns, path.stat().st_size)


@functools.lru_cache(maxsize=None)
def _imports_cached(path: Path, modname: str, mtime_ns: int, size: int) -> frozenset:
    pkg = modname if path.name == "__init__.py" else modname.rpartition(".")[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = importlib.util.resolve_name("." * node.level + (node.module or ""), pkg) \
                if node.level else (node.module or "")
            out.add(base)
            out.update(f"{base}.{a.name}" for a in node.names)   # `from . import x` imports modules
    return frozenset(out)


@functools.lru_cache(maxsize=None)
def _closure_cached(modname: str, stamp: tuple) -> tuple:
    seen: dict[str, Path] = {}
    todo = [modname]
    while todo:
        name = todo.pop()
        f = _module_file(name)
        if f is None or name in seen:
            continue
        seen[name] = f
        todo.extend(_imports(f, name))
        parts = name.split(".")            # a module's parent packages run their __init__ too
        todo.extend(".".join(parts[:i]) for i in range(1, len(parts)))
    return tuple(sorted(str(p) for p in set(seen.values())))


def module_closure(modname: str) -> list[Path]:
    """Source files of the cnclab module ``modname`` and of every cnclab module it imports,
    transitively (sorted paths)."""
    stamp = tuple(sorted((str(p), p.stat().st_mtime_ns) for p in PACKAGE_DIR.rglob("*.py")))
    return [Path(p) for p in _closure_cached(modname, stamp)]


def _hash_files(paths: Iterable[Path], root: Path) -> str:
    h = hashlib.sha256()
    for p in sorted(Path(p) for p in paths):
        try:
            rel = p.resolve().relative_to(root.resolve())
        except ValueError:
            rel = p
        h.update(str(rel).encode() + b"\0" + p.read_bytes() + b"\0")
    return h.hexdigest()


def code_hash(modname: str) -> str:
    """sha256 of the source files of :func:`module_closure` (paths relative to the package)."""
    return _hash_files(module_closure(modname), PACKAGE_DIR)


def data_hash(files: Sequence) -> str:
    """sha256 of the bytes of data files (paths relative to ``data/`` or absolute)."""
    paths = [Path(f) if Path(f).is_absolute() else DATA_DIR / f for f in files]
    missing = [str(p) for p in paths if not p.is_file()]
    if missing:
        raise FileNotFoundError(f"cache: data file(s) not found: {', '.join(missing)}")
    return _hash_files(paths, DATA_DIR)


def cache_key(func: Callable, args: tuple = (), kwargs: dict | None = None, data: Sequence = ()) -> str:
    """Hex key of ``func(*args, **kwargs)``: qualname, the fast-mode flag, code hash, data hash and
    pickled arguments. The flag is in the key because a function may read it anywhere below
    (:func:`cnclab.runtime.pick`): ``make test`` (``CNCLAB_FAST=1``) and ``make reproduce`` share
    ``build/cache``, and a value computed with fast mode's coarser settings must never be served to
    a full run (nor the other way round)."""
    h = hashlib.sha256()
    h.update(f"{func.__module__}.{func.__qualname__}".encode() + b"\0")
    h.update(f"fast={fast_mode()}".encode() + b"\0")
    h.update(code_hash(func.__module__).encode())
    h.update(data_hash(data).encode() if data else b"-")
    h.update(pickle.dumps((tuple(args), sorted((kwargs or {}).items())), protocol=4))
    return h.hexdigest()[:32]


def _entry(func: Callable, key: str) -> Path:
    return cache_dir() / f"{func.__module__}.{func.__qualname__}" / f"{key}.pkl"


def _load(path: Path):
    with open(path, "rb") as fh:
        return pickle.load(fh)


def _store(path: Path, value) -> None:
    atomic_write(path, pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL))


def _lock(path: Path):
    from filelock import FileLock

    return FileLock(str(path) + ".lock")


def cached(data: Sequence = ()) -> Callable:
    """Decorator: cache the function's results on disk (see the module docstring).

    ``data``: data files the function reads (relative to ``data/``), hashed into the key.
    The wrapped function gets ``last_hit`` (True when the last call was served from the cache) and
    ``key(*args, **kwargs)``.
    """
    def deco(func):
        @functools.wraps(func)
        def wrapper(*args, **kwargs):
            if not enabled():
                wrapper.last_hit = False
                return func(*args, **kwargs)
            path = _entry(func, cache_key(func, args, kwargs, data))
            if path.is_file():
                wrapper.last_hit = True
                return _load(path)
            with _lock(path):
                if path.is_file():          # another process finished it while we waited
                    wrapper.last_hit = True
                    return _load(path)
                value = func(*args, **kwargs)
                _store(path, value)
            wrapper.last_hit = False
            return value

        wrapper.last_hit = None
        wrapper.key = lambda *a, **kw: cache_key(func, a, kw, data)
        wrapper.uncached = func
        wrapper.data = tuple(data)
        return wrapper

    return deco


def map_cached(fn: Callable, arg_tuples: Sequence[tuple]) -> list:
    """``[fn(*a) for a in arg_tuples]`` for a :func:`cached` ``fn``, sharing work between processes.

    Entries another process is computing (its lock is held) are deferred, and read (or computed, if
    that process died) after the others. Results are in the order of ``arg_tuples``.
    """
    if not hasattr(fn, "uncached"):
        raise ValueError("map_cached needs a function decorated with @cached")
    if not enabled():
        return [fn.uncached(*a) for a in arg_tuples]
    from filelock import Timeout

    out: dict[int, object] = {}
    deferred = []
    for i, a in enumerate(arg_tuples):
        path = _entry(fn.uncached, fn.key(*a))
        if path.is_file():
            out[i] = _load(path)
            continue
        lock = _lock(path)
        try:
            lock.acquire(timeout=0)
        except Timeout:
            deferred.append(i)
            continue
        try:
            if path.is_file():
                out[i] = _load(path)
            else:
                out[i] = fn.uncached(*a)
                _store(path, out[i])
        finally:
            lock.release()
    for i in deferred:
        out[i] = fn(*arg_tuples[i])
    return [out[i] for i in range(len(arg_tuples))]
