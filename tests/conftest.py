import os

import matplotlib

matplotlib.use("Agg")


def pytest_configure(config):
    # Tests never write into the user's build/: figures and reports go to a per-session temp folder.
    if "CNCLAB_BUILD_DIR" not in os.environ:
        import tempfile

        os.environ["CNCLAB_BUILD_DIR"] = tempfile.mkdtemp(prefix="cnclab-test-build-")


# Hypothesis: in CI (CI set) examples are derandomised (a fixed seed per test), so a CI run is
# reproducible; locally the search is random and keeps its example database (.hypothesis/), so
# new counterexamples are still found and then replayed.
from hypothesis import settings as _hyp_settings  # noqa: E402

_hyp_settings.register_profile("ci", derandomize=True, database=None)
if os.environ.get("CI"):
    _hyp_settings.load_profile("ci")
