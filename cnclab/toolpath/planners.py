"""Every 2.5D clearing strategy behind one call: :func:`plan` a :class:`~cnclab.toolpath.job.Job`.

:data:`STRATEGIES` maps a name to a planner ``f(job, resolution_mm, **options) -> ToolPath`` that
cuts one level (the job's ``top_z`` down to ``top_z - a_p``); :func:`plan` runs it level by level
for a pocket deeper than a_p (:meth:`Job.levels`) and joins the levels (each ends with a retract to
the clearance plane, the next starts with a rapid there). Units: mm, mm/min, deg.

=======================  ===================================================================
adaptive (default)       :func:`cnclab.toolpath.adaptive_clearing.plan_job` (engagement-controlled
                         clearing of the simulated stock, links at depth through cleared area;
                         issue 16: the planner ``python -m cnclab plan`` runs unless told otherwise)
constant-engagement      :func:`cnclab.toolpath.ce_clearing.clearing_path` (Jacsó Thesis III laps)
hybrid                   :func:`cnclab.toolpath.pocket.hybrid_path` (Jacsó §4: centre laps + CE trochoid arms)
contour-parallel         :func:`cnclab.toolpath.pocket.contour_parallel_path` (offsets at a_e)
zig-zag                  :func:`cnclab.toolpath.pocket.zigzag_path` (raster at a_e + a finishing lap)
kim-yang-original        :func:`cnclab.toolpath.constant_mrr.kim_yang_passes` (offsets at a_e, spiral entries;
                         each pass entered by a helix instead of the paper's plunge)
kim-yang-modified        the same with Kim & Yang's §3.2 constant-MRR modification
=======================  ===================================================================

>>> from shapely.geometry import box
>>> from cnclab.toolpath.path import Tool
>>> job = Job(box(0, 0, 30, 20), Tool(6.0), 60.0, 2.0, depth=4.0, start_hole=(15, 10, 8), v_c=100, f_z=0.05)
>>> p = plan(job, "contour-parallel")
>>> sorted(set(np.round(p.xyz[p.is_kind("cut"), 2], 6).tolist())), p.info["levels"]
([-4.0, -2.0], [-2.0, -4.0])
"""
from __future__ import annotations

import dataclasses

import numpy as np

from . import adaptive_clearing   # the default; the other planners' modules are imported when used
from .job import Job
from .path import ToolPath

__all__ = ["STRATEGIES", "DEFAULT_STRATEGY", "plan", "register"]

#: name -> (planner(job, resolution_mm, **options) -> ToolPath for one level, one-line description)
STRATEGIES: dict = {}


def register(name: str, description: str):
    """Decorator: add a one-level planner ``f(job, resolution_mm, **options) -> ToolPath`` under ``name``
    (an existing name is replaced: e.g. a new constant-engagement planner)."""
    def deco(f):
        STRATEGIES[name] = (f, description)
        return f
    return deco


@register("constant-engagement", "Jacsó Thesis III constant-engagement laps from helical entries (ce_clearing)")
def _constant_engagement(job: Job, resolution_mm: float, **options) -> ToolPath:
    from . import ce_clearing

    return ce_clearing.clearing_path(job, resolution_mm=resolution_mm, **options)


@register("hybrid", "Jacsó §4 hybrid: centre laps around the start hole, CE trochoid arms")
def _hybrid(job: Job, resolution_mm: float, **options) -> ToolPath:
    from . import pocket

    return pocket.hybrid_path(job, resolution_mm, **options)


@register("contour-parallel", "contour-parallel offsets at a_e, inside-out")
def _contour_parallel(job: Job, resolution_mm: float, **options) -> ToolPath:
    from . import pocket

    return pocket.contour_parallel_path(job, resolution_mm=resolution_mm, **options)


@register("zig-zag", "zig-zag raster at a_e and a finishing lap")
def _zigzag(job: Job, resolution_mm: float, **options) -> ToolPath:
    from . import pocket

    return pocket.zigzag_path(job, resolution_mm=resolution_mm, **options)


@register("kim-yang-original", "Kim & Yang 2006 contour-parallel path (offsets at a_e, spiral entries)")
def _kim_yang_original(job: Job, resolution_mm: float, **options) -> ToolPath:
    from . import constant_mrr

    return constant_mrr.passes_path(constant_mrr.kim_yang_passes(job, **options), job, entry="helix")


@register("kim-yang-modified", "Kim & Yang 2006 constant-MRR modified contour-parallel path")
def _kim_yang_modified(job: Job, resolution_mm: float, **options) -> ToolPath:
    from . import constant_mrr

    return constant_mrr.passes_path(constant_mrr.kim_yang_passes(job, modified=True, **options), job, entry="helix")


@register("adaptive", "engagement-controlled clearing of the simulated stock, links at depth (adaptive_clearing)")
def _adaptive(job: Job, resolution_mm: float, **options) -> ToolPath:
    return adaptive_clearing.plan_job(job, **options)


#: the strategy :func:`plan` (and ``python -m cnclab plan``) uses when none is named
DEFAULT_STRATEGY = "adaptive"


def plan(job: Job, strategy: str = DEFAULT_STRATEGY, resolution_mm: float = 0.1, **options) -> ToolPath:
    """Plan ``job`` with ``strategy`` (a key of :data:`STRATEGIES`) level by level.

    ``resolution_mm``: the planners' dixel row height / sampling step (mm); ``options`` go to the
    planner. Returns one :class:`ToolPath`; ``info["levels"]`` holds the cutting z of each level,
    ``info["strategy"]`` the name."""
    if strategy not in STRATEGIES:
        raise ValueError(f"unknown strategy {strategy!r}: must be one of {sorted(STRATEGIES)}")
    if not isinstance(job, Job):
        raise TypeError(f"job must be a cnclab.toolpath.job.Job, got {type(job).__name__}")
    f = STRATEGIES[strategy][0]
    levels = job.levels()
    tops = [job.top_z] + levels[:-1]
    paths = []
    for top, z in zip(tops, levels):
        lv = job if len(levels) == 1 else dataclasses.replace(job, top_z=top, a_p=top - z, depth=top - z)
        paths.append(f(lv, resolution_mm, **options))
    out = paths[0] if len(paths) == 1 else ToolPath.concat(paths)
    out.info.update(strategy=strategy, levels=levels)
    return out
