import os

import matplotlib

matplotlib.use("Agg")


def pytest_configure(config):
    # Tests never write into the user's build/: figures and reports go to a per-session temp folder.
    if "CNCLAB_BUILD_DIR" not in os.environ:
        import tempfile

        os.environ["CNCLAB_BUILD_DIR"] = tempfile.mkdtemp(prefix="cnclab-test-build-")
