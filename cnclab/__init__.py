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
from .plotting import export_figure, figsize, savefig, use_style
from .runtime import environment_report, fast_mode, notebook_setup, seed_everything

__version__ = "0.1.0"
__all__ = ["export_figure", "figsize", "savefig", "use_style", "environment_report", "fast_mode", "notebook_setup",
           "seed_everything", "__version__"]
