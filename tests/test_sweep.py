"""cnclab.sweep: serial, joblib and a local Dask cluster give bit-identical results, in input order."""
import numpy as np
import pytest

from cnclab.sweep import sweep


def noisy_stat(seed: int, n: int):
    """A deterministic, floating-point-heavy function of its arguments (module level: picklable)."""
    x = np.random.default_rng(seed).normal(size=n)
    return float(np.sum(np.sin(x) * np.exp(-x * x))), np.cumsum(x)[-3:]


ARGS = [(s, 1000 + 17 * s) for s in range(8)]


def _same(a, b):
    assert len(a) == len(b)
    for (fa, va), (fb, vb) in zip(a, b):
        assert fa == fb and np.array_equal(va, vb)


def test_joblib_matches_serial():
    _same(sweep(noisy_stat, ARGS, n_jobs=1), sweep(noisy_stat, ARGS, n_jobs=2))


def test_local_dask_cluster_matches_serial(monkeypatch):
    distributed = pytest.importorskip("distributed")
    serial = sweep(noisy_stat, ARGS)
    cluster = distributed.LocalCluster(host="127.0.0.1", n_workers=2, threads_per_worker=1,
                                       processes=True, dashboard_address=None, silence_logs=50)
    try:
        with distributed.Client(cluster, timeout="60s") as client:
            _same(sweep(noisy_stat, ARGS, client=client), serial)
        monkeypatch.setenv("CNCLAB_DASK_SCHEDULER", cluster.scheduler_address)
        _same(sweep(noisy_stat, ARGS), serial)                 # address from the environment
    finally:
        cluster.close(timeout=30)


def test_bad_jobs(monkeypatch):
    with pytest.raises(ValueError, match="n_jobs"):
        sweep(noisy_stat, ARGS, n_jobs=0)
    monkeypatch.setenv("CNCLAB_SWEEP_JOBS", "many")
    with pytest.raises(ValueError, match="CNCLAB_SWEEP_JOBS"):
        sweep(noisy_stat, ARGS)
