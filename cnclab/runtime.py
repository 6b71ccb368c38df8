"""Run-time conventions: fast mode, seeding, and the environment report of each notebook."""
from __future__ import annotations

import os
import platform
import random
import sys
from importlib import metadata

import numpy as np

FAST_ENV = "CNCLAB_FAST"

_REPORTED = ("cnclab", "numpy", "scipy", "pandas", "statsmodels", "scikit-learn", "matplotlib",
             "shapely", "numpy-stl", "trimesh", "torch")


def fast_mode() -> bool:
    """True when ``CNCLAB_FAST`` is set to a true value (1/true/yes): shrink sweeps and epochs.

    Claims are still computed in full in fast mode unless the ledger marks them slow.
    """
    return os.environ.get(FAST_ENV, "").strip().lower() in {"1", "true", "yes", "on"}


def pick(full, fast):
    """``fast`` in fast mode, otherwise ``full`` (for sweep sizes, epochs, seeds)."""
    return fast if fast_mode() else full


def seed_everything(seed: int = 0) -> np.random.Generator:
    """Seed Python's, NumPy's legacy and (if already imported) torch's RNGs; return a Generator.

    cnclab code itself never uses global RNG state: functions take a ``seed`` or a
    ``numpy.random.Generator``; this is for user code in notebooks.
    """
    random.seed(seed)
    np.random.seed(seed)
    torch = sys.modules.get("torch")
    if torch is not None:
        torch.manual_seed(seed)
    return np.random.default_rng(seed)


def _version(dist: str) -> str:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return "not installed"


def environment_report() -> str:
    """A short text: Python, platform, CPU count, fast mode and the versions of the key packages."""
    lines = [
        f"python {platform.python_version()} on {platform.platform()} ({os.cpu_count()} CPUs)",
        f"fast mode: {'ON' if fast_mode() else 'off'} ({FAST_ENV}={os.environ.get(FAST_ENV, '')!r})",
    ]
    lines.append(", ".join(f"{d} {_version(d)}" for d in _REPORTED))
    return "\n".join(lines)


def notebook_setup(seed: int = 0) -> np.random.Generator:
    """First cell of every notebook: paper plot style, seeds, and the environment report printed."""
    from .plotting import use_style

    use_style()
    rng = seed_everything(seed)
    print(environment_report())
    return rng
