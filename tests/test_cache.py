"""cnclab.cache: keys follow the code, data and arguments; a change recomputes only what depends on it."""
import textwrap

import numpy as np
import pytest

from cnclab import cache


@pytest.fixture
def fake_pkg(tmp_path, monkeypatch):
    """A throw-away copy of a tiny 'cnclab' package (a -> b; c alone) and a data folder."""
    pkg = tmp_path / "cnclab"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "sub" / "a.py").write_text("from . import b\nimport numpy\n")
    (pkg / "sub" / "b.py").write_text("from ..paths import X\n")
    (pkg / "paths.py").write_text("X = 1\n")
    (pkg / "sub" / "c.py").write_text("Y = 2\n")
    data = tmp_path / "data"
    data.mkdir()
    (data / "in_a.csv").write_text("1,2\n")
    (data / "in_c.csv").write_text("3,4\n")
    monkeypatch.setattr(cache, "PACKAGE_DIR", pkg)
    monkeypatch.setattr(cache, "DATA_DIR", data)
    monkeypatch.setenv("CNCLAB_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv("CNCLAB_NO_CACHE", raising=False)
    return pkg, data


def _recipe(module: str, name: str, data: tuple, calls: list):
    """A cached function that claims to live in ``module`` and reads ``data``; counts its calls."""
    def f(x):
        calls.append((name, x))
        return np.arange(x) * sum(len((cache.DATA_DIR / d).read_text()) for d in data)
    f.__module__, f.__qualname__ = module, name
    return cache.cached(data=data)(f)


def test_closure_follows_imports(fake_pkg):
    pkg, _ = fake_pkg
    names = {p.relative_to(pkg).as_posix() for p in cache.module_closure("cnclab.sub.a")}
    assert names == {"__init__.py", "sub/__init__.py", "sub/a.py", "sub/b.py", "paths.py"}
    names_c = {p.relative_to(pkg).as_posix() for p in cache.module_closure("cnclab.sub.c")}
    assert names_c == {"__init__.py", "sub/__init__.py", "sub/c.py"}


def test_change_recomputes_only_dependents(fake_pkg):
    pkg, data = fake_pkg
    calls = []
    fa = _recipe("cnclab.sub.a", "fa", ("in_a.csv",), calls)
    fc = _recipe("cnclab.sub.c", "fc", ("in_c.csv",), calls)
    first = fa(3), fc(3)
    assert calls == [("fa", 3), ("fc", 3)]
    again = fa(3), fc(3)                                  # nothing changed: both from the cache
    assert calls == [("fa", 3), ("fc", 3)] and fa.last_hit and fc.last_hit
    np.testing.assert_array_equal(first[0], again[0])
    (data / "in_a.csv").write_text("1,2,3\n")             # data of fa only
    fa(3), fc(3)
    assert calls[2:] == [("fa", 3)]
    (pkg / "sub" / "b.py").write_text("from ..paths import X\nZ = 3\n")   # code fa imports
    fa(3), fc(3)
    assert calls[3:] == [("fa", 3)]
    (pkg / "sub" / "c.py").write_text("Y = 5\n")          # fc's own module
    fa(3), fc(3)
    assert calls[4:] == [("fc", 3)]
    fa(4)                                                  # new arguments
    assert calls[5:] == [("fa", 4)]


def test_no_cache_env_and_map_cached(fake_pkg, monkeypatch):
    calls = []
    fa = _recipe("cnclab.sub.a", "fa", ("in_a.csv",), calls)
    assert [len(r) for r in cache.map_cached(fa, [(1,), (2,), (1,)])] == [1, 2, 1]
    assert calls == [("fa", 1), ("fa", 2)]
    monkeypatch.setenv("CNCLAB_NO_CACHE", "1")
    fa(1)
    cache.map_cached(fa, [(2,)])
    assert calls[2:] == [("fa", 1), ("fa", 2)]


def test_a_fast_mode_value_is_never_served_to_a_full_run(fake_pkg, monkeypatch):
    """make test (CNCLAB_FAST=1) and make reproduce share build/cache: a function that reads the mode
    (runtime.pick) below its arguments gets a key per mode."""
    from cnclab.runtime import pick

    calls = []

    def f(x):
        calls.append(x)
        return x * pick(10, 1)                    # full mode 10, fast mode 1
    f.__module__, f.__qualname__ = "cnclab.sub.c", "f_mode"
    f = cache.cached()(f)
    monkeypatch.setenv("CNCLAB_FAST", "1")
    assert f(3) == 3
    monkeypatch.setenv("CNCLAB_FAST", "0")
    assert f(3) == 30 and not f.last_hit          # computed again, not the fast value
    assert f(3) == 30 and f.last_hit
    monkeypatch.setenv("CNCLAB_FAST", "1")
    assert f(3) == 3 and f.last_hit and calls == [3, 3]


def test_missing_data_file_is_named(fake_pkg):
    f = _recipe("cnclab.sub.c", "fm", ("absent.csv",), [])
    with pytest.raises(FileNotFoundError, match="absent.csv"):
        f(1)


def test_real_closure_of_ch6_includes_the_trainer_not_the_planners():
    names = {p.name for p in cache.module_closure("cnclab.works.mgherony2024.ch6")}
    assert {"ch6.py", "mlp.py", "cache.py"} <= names
    assert "dropcutter.py" not in names and "ce_clearing.py" not in names
