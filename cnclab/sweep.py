"""One helper for parameter sweeps: serial, joblib processes, or a Dask cluster.

:func:`sweep` evaluates ``fn(*args)`` for every argument tuple and returns the results **in input
order**, whatever ran them:

* serially (the default, ``n_jobs=1``; ``CNCLAB_SWEEP_JOBS`` changes the default), through
  :func:`cnclab.cache.map_cached` when ``fn`` is :func:`cnclab.cache.cached` (entries already
  computed are read, entries another process is computing are shared);
* on ``n_jobs`` local processes with joblib (``n_jobs=-1``: one per core);
* on a Dask cluster when a ``dask.distributed.Client`` is passed as ``client`` or the environment
  variable ``CNCLAB_DASK_SCHEDULER=tcp://host:port`` names a scheduler (start one with
  ``dask scheduler`` and workers with ``dask worker tcp://host:port`` on machines where cnclab is
  installed with the same environment.txt).

Every sweep routed through here is a pure function of its arguments (fixed seeds, no global state),
so the three ways give bit-identical results (``tests/test_sweep.py`` checks serial vs a local Dask
cluster vs joblib).

>>> sweep(pow, [(2, 3), (3, 2)])
[8, 9]
"""
from __future__ import annotations

import os
from typing import Callable, Sequence

from .cache import map_cached

__all__ = ["sweep", "default_jobs", "DASK_ENV", "JOBS_ENV"]

DASK_ENV = "CNCLAB_DASK_SCHEDULER"
JOBS_ENV = "CNCLAB_SWEEP_JOBS"


def default_jobs() -> int:
    """``$CNCLAB_SWEEP_JOBS`` (an int; -1 = one per core) or 1."""
    v = os.environ.get(JOBS_ENV, "").strip()
    if not v:
        return 1
    try:
        return int(v)
    except ValueError:
        raise ValueError(f"{JOBS_ENV} must be an integer, got {v!r}") from None


def _call(fn, args):
    return fn(*args)


def sweep(fn: Callable, arg_tuples: Sequence, *, n_jobs: int | None = None, client=None,
          scheduler: str | None = None) -> list:
    """``[fn(*a) for a in arg_tuples]``, serial, on joblib processes or on a Dask cluster.

    Parameters
    ----------
    fn : a picklable (module-level) function; deterministic in its arguments.
    arg_tuples : sequence of argument tuples (a non-tuple item is passed as the single argument).
    n_jobs : joblib processes (default :func:`default_jobs`); ignored when Dask is used.
    client : a ``dask.distributed.Client``; or ``scheduler`` / ``$CNCLAB_DASK_SCHEDULER`` — an address
        ``tcp://host:port`` to connect to (the connection is closed afterwards).
    """
    items = [a if isinstance(a, tuple) else (a,) for a in arg_tuples]
    address = scheduler or os.environ.get(DASK_ENV, "").strip() or None
    if client is not None or address:
        return _sweep_dask(fn, items, client, address)
    n = default_jobs() if n_jobs is None else int(n_jobs)
    if n == 0:
        raise ValueError("n_jobs must be non-zero")
    if n == 1 or len(items) <= 1:
        if hasattr(fn, "uncached"):
            return map_cached(fn, items)
        return [fn(*a) for a in items]
    from joblib import Parallel, delayed

    return list(Parallel(n_jobs=n)(delayed(fn)(*a) for a in items))


def _sweep_dask(fn, items, client, address):
    from distributed import Client

    own = client is None
    if own:
        client = Client(address, timeout="30s", set_as_default=False)
    try:
        futures = client.map(_call, [fn] * len(items), items, pure=False)
        return client.gather(futures)
    finally:
        if own:
            client.close()
