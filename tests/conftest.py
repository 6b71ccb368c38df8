import copy
import functools
import os
import pickle

import matplotlib
import pytest

matplotlib.use("Agg")


def pytest_configure(config):
    # Tests never write into the user's build/: figures and reports go to a per-session temp folder.
    if "CNCLAB_BUILD_DIR" not in os.environ:
        import tempfile

        os.environ["CNCLAB_BUILD_DIR"] = tempfile.mkdtemp(prefix="cnclab-test-build-")
        config._cnclab_made_build_dir = os.environ["CNCLAB_BUILD_DIR"]
    # Expensive results (trained MLP weights, ...) are content-addressed (cnclab.cache: keyed by the
    # code, data and arguments that produce them), so the tests share the repository's build/cache/
    # with `make reproduce`; CNCLAB_NO_CACHE=1 recomputes everything.
    if "CNCLAB_CACHE_DIR" not in os.environ:
        from pathlib import Path

        os.environ["CNCLAB_CACHE_DIR"] = str(Path(__file__).resolve().parents[1] / "build" / "cache")


def pytest_unconfigure(config):
    # The per-session build folder is removed when the session that made it ends (about 80 MB of
    # figures and executed notebooks a run: left behind, every `make test` added one to /tmp).
    # CNCLAB_KEEP_TEST_BUILD=1 keeps it (its path is printed) to look at what the tests wrote.
    made = getattr(config, "_cnclab_made_build_dir", None)
    if made is None or hasattr(config, "workerinput"):
        return
    if os.environ.get("CNCLAB_KEEP_TEST_BUILD"):
        print(f"\ntest build folder kept: {made}")
        return
    import shutil

    shutil.rmtree(made, ignore_errors=True)


# Hypothesis: examples are derandomised (a fixed seed per test), so every run of `make test` -- CI or
# local -- draws the same examples and a failure is reproducible (two fresh-clone CI runs had drawn
# different examples: the search was random unless CI was set). For exploring, CNCLAB_HYPOTHESIS_RANDOM=1
# gives a random search with the example database (.hypothesis/); a counterexample found so goes
# into the test as an @example.
from hypothesis import settings as _hyp_settings  # noqa: E402

_hyp_settings.register_profile("ci", derandomize=True, database=None)
if not os.environ.get("CNCLAB_HYPOTHESIS_RANDOM"):
    _hyp_settings.load_profile("ci")

# Hypothesis (>= 6.131) mixes "local constants" of every module loaded in the process into 5 % of its
# draws, so the examples a derandomized test gets depended on what earlier tests in the same xdist
# worker had imported: two fresh-clone runs of one commit drew a star pocket that a third run and
# every single-file run did not. With no local constants the examples depend only on the test.
from hypothesis.internal.conjecture import providers as _hyp_providers  # noqa: E402

if hasattr(_hyp_providers, "_get_local_constants"):
    _NO_LOCAL_CONSTANTS = _hyp_providers._local_constants      # still the empty set built at import
    _hyp_providers._get_local_constants = lambda: _NO_LOCAL_CONSTANTS


# Longest tests first: pytest-xdist hands tests out in collection order, so a long test collected
# last runs alone at the end while the other worker idles (about a minute of the `make test` wall
# time on 2 cores). Order only; nothing is skipped. The list names the tests that take > ~5 CPU-s.
# With `--dist loadgroup` (make test) the xdist groups (several tests each) are handed out first,
# then the rest in this order.
_SLOW_FIRST = ("adaptive_vs_freecad", "ce_vs_constant_mrr", "ch6_neural", "s4_star", "test_notebooks.py::",
               "test_plan_real_every_job_file", "test_claim_status_holds[mgherony2024.ch6",
               "test_random_pockets", "test_getting_started_blocks_run", "test_every_strategy_safe_or_refusing",
               "test_random_polylines_fit_within_tolerance", "test_claim_status_holds[jacso2021.s4",
               "test_auto_wall_share", "test_interrupt_at_any_moment",
               "test_claim_status_holds[mgherony2024.ch8", "test_every_strategy_plans",
               "test_results_do_not_depend_on_block_length", "test_planned_pocket_figures_unchanged_by_fitting")


def pytest_collection_modifyitems(session, config, items):
    def rank(item):
        return next((i for i, s in enumerate(_SLOW_FIRST) if s in item.nodeid), len(_SLOW_FIRST))

    items.sort(key=rank)   # stable: the rest keeps its order
    # `slow` tests (a whole bench pocket where a smaller case shows the same property) are skipped in
    # fast mode (`make test`) unless CNCLAB_SLOW=1; `make test-slow` runs exactly them and CI runs it
    # after `make test` (README, "The two commands"), so nothing goes untested.
    from cnclab.runtime import fast_mode

    if fast_mode() and os.environ.get("CNCLAB_SLOW", "").strip().lower() not in {"1", "true", "yes", "on"}:
        skip = pytest.mark.skip(reason="slow: run by `make test-slow` (CI runs it) or without CNCLAB_FAST")
        for item in items:
            if "slow" in item.keywords:
                item.add_marker(skip)


#: one-level plans by (strategy, one-level job, resolution, options), pickled, for the whole session
_LEVEL_PLANS: dict = {}


def _memo_planner(name, f):
    @functools.wraps(f)          # its signature is f's (plan() passes ``written`` only to planners taking it)
    def planner(job, resolution_mm, **options):
        key = pickle.dumps((name, job, resolution_mm, sorted(options.items())))
        if key not in _LEVEL_PLANS:
            try:
                _LEVEL_PLANS[key] = f(job, resolution_mm, **options)
            except ValueError as exc:        # a refusal is as deterministic as a plan: kept, raised anew
                _LEVEL_PLANS[key] = exc
        got = _LEVEL_PLANS[key]
        if isinstance(got, ValueError):
            raise copy.copy(got).with_traceback(None)
        return copy.deepcopy(got)
    return planner


@pytest.fixture
def memo_levels(monkeypatch):
    """During the test, every registered one-level planner (what :func:`cnclab.toolpath.planners.plan`
    runs per level) answers a job it has planned before in this session with a deep copy of that
    plan. The key is the pickled (strategy, job, resolution, options): a job differing in any field is
    planned anew. The planners are deterministic (golden-digest tests), so a test sees the path it
    would have planned; plan() still joins the levels, checks gouges and uncut area, and the test
    still writes and checks its own program. A refusal (ValueError) is memoised too and raised anew."""
    from cnclab.toolpath.planners import STRATEGIES

    for name, (f, desc) in list(STRATEGIES.items()):
        monkeypatch.setitem(STRATEGIES, name, (_memo_planner(name, f), desc))
