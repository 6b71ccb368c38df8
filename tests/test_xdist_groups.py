"""``make test`` runs ``pytest -n N --dist loadgroup``: tests marked ``xdist_group(name)`` share one
worker, so a section's claims compute their recipe once (functools.cache) and the deep-pocket matrix
plans each strategy's first level once (``memo_levels``). pytest 9.2.0 with pytest-xdist 3.8.0
silently drops the groups (pytest-dev/pytest-xdist#1386: the worker's nodeid suffix no longer takes
effect) and every group is spread over the workers: about a minute more of ``make test``. This test
fails when the pinned pair stops grouping."""
import os

import pytest


@pytest.mark.xdist_group("xdist-group-check")
def test_a_grouped_test_carries_its_group_under_loadgroup(request):
    # on a worker, xdist sets option ``loadgroup`` from the controller's --dist (and ``dist`` to "no")
    if os.environ.get("PYTEST_XDIST_WORKER") is None or not getattr(request.config.option, "loadgroup", False):
        pytest.skip("not run by xdist with --dist loadgroup")
    assert request.node.nodeid.endswith("@xdist-group-check"), request.node.nodeid
