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
import math

import numpy as np

from . import adaptive_clearing   # the default; the other planners' modules are imported when used
from . import coverage
from .job import Job
from .path import ToolPath

__all__ = ["STRATEGIES", "DEFAULT_STRATEGY", "MAX_LEVELS", "MIN_LEVEL_STEP_MM", "UncutError", "check_limits", "plan",
           "register"]

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


#: the most levels :func:`plan` accepts (depth / a_p): a deeper job is refused up front
MAX_LEVELS = 1000
#: the smallest level step (mm) :func:`plan` accepts: 10 units of the program's 4th decimal, so every
#: level is written below the one above it (a_p = 1e-6 would be written at Z0)
MIN_LEVEL_STEP_MM = 0.001


class UncutError(ValueError):
    """A plan leaves more uncut area than :func:`cnclab.toolpath.coverage.uncut_limit_mm2` allows in a
    region (``report``: :func:`cnclab.toolpath.coverage.uncut_report`)."""

    def __init__(self, msg, report):
        super().__init__(msg)
        self.report = report


def check_limits(job: Job) -> None:
    """Refuse, before any planning, a job whose levels exceed :data:`MAX_LEVELS` or are thinner than
    :data:`MIN_LEVEL_STEP_MM` (ValueError naming the job key and the number the job would need)."""
    n = int(math.ceil(job.depth / job.a_p - 1e-9)) if job.a_p > 0 else math.inf
    if n > MAX_LEVELS:
        raise ValueError(f"{job.source}: $.depth / $.a_p: depth {job.depth:g} mm at a_p {job.a_p:g} mm needs {n} "
                         f"levels; at most {MAX_LEVELS} are planned (raise a_p to >= {job.depth / MAX_LEVELS:g} mm)")
    if job.depth / n < MIN_LEVEL_STEP_MM:
        raise ValueError(f"{job.source}: $.a_p: levels {job.depth / n:g} mm apart are below {MIN_LEVEL_STEP_MM:g} mm "
                         "(the program's z resolution x 10): the cut would be written at or near the stock top")


def _uncut_message(job: Job, strategy: str, rep: dict) -> str:
    parts = "; ".join(f"region {k}: {rep['uncut_mm2'][k]:.1f} of {rep['reach_mm2'][k]:.0f} mm^2 reachable "
                      f"(limit {rep['limit_mm2'][k]:.1f})" for k in rep["over"])
    return (f"{job.source}: strategy {strategy} leaves material uncut beyond the corners no tool disc reaches: "
            f"{parts}")


def plan(job: Job, strategy: str = DEFAULT_STRATEGY, resolution_mm: float = 0.1, allow_uncut: bool = False,
         **options) -> ToolPath:
    """Plan ``job`` with ``strategy`` (a key of :data:`STRATEGIES`) level by level.

    ``resolution_mm``: the planners' dixel row height / sampling step (mm); ``options`` go to the
    planner. Returns one :class:`ToolPath`; ``info["levels"]`` holds the cutting z of each level,
    ``info["strategy"]`` the name, ``info["uncut"]`` what the plan leaves by region
    (:func:`cnclab.toolpath.coverage.uncut_report`). A plan leaving more than the stated limit in a
    region raises :class:`UncutError`, unless ``allow_uncut`` (then ``info["warnings"]`` says it).
    A job beyond :data:`MAX_LEVELS` / :data:`MIN_LEVEL_STEP_MM` is refused before planning."""
    if strategy not in STRATEGIES:
        raise ValueError(f"unknown strategy {strategy!r}: must be one of {sorted(STRATEGIES)}")
    if not isinstance(job, Job):
        raise TypeError(f"job must be a cnclab.toolpath.job.Job, got {type(job).__name__}")
    if isinstance(resolution_mm, bool) or not isinstance(resolution_mm, (int, float, np.integer, np.floating)) \
            or not (math.isfinite(resolution_mm) and resolution_mm > 0):
        raise ValueError(f"resolution_mm must be a finite number > 0 mm, got {resolution_mm!r}")
    check_limits(job)
    f = STRATEGIES[strategy][0]
    levels = job.levels()
    tops = [job.top_z] + levels[:-1]
    paths = []
    for top, z in zip(tops, levels):
        lv = job if len(levels) == 1 else dataclasses.replace(job, top_z=top, a_p=top - z, depth=top - z)
        paths.append(f(lv, resolution_mm, **options))
    out = paths[0] if len(paths) == 1 else ToolPath.concat(paths)
    out.info.update(strategy=strategy, levels=levels)
    rep = coverage.uncut_report(out, job)
    out.info["uncut"] = rep
    if rep["over"]:
        msg = _uncut_message(job, strategy, rep)
        if not allow_uncut:
            raise UncutError(msg + " (accept it with allow_uncut=True, CLI --allow-uncut)", rep)
        out.info.setdefault("warnings", []).append(msg)
    return out
