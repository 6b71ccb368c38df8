"""Run the docstring examples of every cnclab module (they are part of the documentation)."""
import doctest
import importlib
import pkgutil

import pytest

import cnclab

MODULES = sorted(m.name for m in pkgutil.walk_packages(cnclab.__path__, "cnclab.")
                 if not m.name.endswith("__main__"))


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    mod = importlib.import_module(name)
    res = doctest.testmod(mod, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE, verbose=False)
    assert res.failed == 0, f"{res.failed} docstring example(s) of {name} failed"
