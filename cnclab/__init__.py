"""cnclab: helper package of a study collection reproducing four works on CNC milling tool paths.

Pipeline modules (geometry -> tool path -> cutting physics / simulation -> analysis and models):

- :mod:`cnclab.geometry`   surfaces, contours, tool-surface contact geometry (cusp height, ...)
- :mod:`cnclab.toolpath`   tool-path generators and file formats
- :mod:`cnclab.cutting`    cutting physics: speeds, feeds, roughness of profiles
- :mod:`cnclab.simulation` material-removal simulators
- :mod:`cnclab.analysis`   regression, statistics, learned models
- :mod:`cnclab.works`      one sub-package per reproduced work, holding its claim recipes

Support: :mod:`cnclab.claims` (ledger), :mod:`cnclab.plotting` (style, ``figsize``, ``savefig``, ``export_figure``),
:mod:`cnclab.runtime` (fast mode, seeding, environment report), :mod:`cnclab.fileio`
(atomic writes), :mod:`cnclab.paths`.
"""
import importlib as _importlib

__version__ = "0.1.0"
__all__ = ["export_figure", "figsize", "savefig", "use_style", "environment_report", "fast_mode", "notebook_setup",
           "seed_everything", "__version__"]

#: the names above, imported from their module on first use (PEP 562): ``import cnclab`` imports
#: nothing else, so ``python -m cnclab`` reaches its interrupt handlers (cnclab/__main__.py) ~1 ms
#: after the interpreter starts instead of after numpy (~0.15 s)
_LAZY = {"export_figure": "plotting", "figsize": "plotting", "savefig": "plotting", "use_style": "plotting",
         "environment_report": "runtime", "fast_mode": "runtime", "notebook_setup": "runtime",
         "seed_everything": "runtime"}


def __getattr__(name):
    if name in _LAZY:
        return getattr(_importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
