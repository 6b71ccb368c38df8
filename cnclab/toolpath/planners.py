"""Every 2.5D clearing strategy behind one call: :func:`plan` a :class:`~cnclab.toolpath.job.Job`.

:data:`STRATEGIES` maps a name to a planner ``f(job, resolution_mm, **options) -> ToolPath`` that
cuts one level (the job's ``top_z`` down to ``top_z - a_p``); :func:`plan` runs it level by level
for a pocket deeper than a_p (:meth:`Job.levels`) and joins the levels (each ends with a retract to
the clearance plane, the next starts with a rapid there). Units: mm, mm/min, deg.

=======================  ===================================================================
adaptive (default)       :func:`cnclab.toolpath.adaptive.plan_job` (engagement-controlled
                         clearing of the simulated stock, links at depth through cleared area;
                         issue 16: the planner ``python -m cnclab plan`` runs unless told otherwise)
constant-engagement      :func:`cnclab.toolpath.ce_clearing.ce_clearing` (Jacsó Thesis III laps); plans
                         only jobs on which it keeps its promise (:data:`CE_PROMISE_DEG`), refuses the others
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

import copy
import dataclasses
import inspect
import math

import numpy as np
import shapely

from . import adaptive   # the default; the other planners' modules are imported when used
from . import coverage
from .evaluate import evaluate, evaluate_engagement
from .job import Job
from .levels import join_levels, with_entry_feed
from .path import ToolPath
from .vector_check import vector_peaks

__all__ = ["STRATEGIES", "DEFAULT_STRATEGY", "MAX_LEVELS", "MIN_LEVEL_STEP_MM", "GOUGE_TOL_MM", "CE_PROMISE_DEG",
           "CE_SHARE_ABOVE_5_PCT", "CE_CORNER_FRACTION",
           "MIN_RESOLUTION_MM", "MAX_RESOLUTION_TOOL_FRACTION", "UncutError", "check_limits", "check_resolution",
           "adaptive_engagement_check", "plan", "register"]

#: name -> (planner(job, resolution_mm, **options) -> ToolPath for one level, one-line description);
#: ``resolution_mm`` None: the planner's own default
STRATEGIES: dict = {}
#: the planners' dixel / sampling step (mm) when :func:`plan` is given none (the adaptive planner: r/60)
DEFAULT_RESOLUTION_MM = 0.1


#: bounds of a planning / evaluation resolution (mm), shared by :func:`plan` and ``python -m cnclab analyze
#: --resolution``: below 0.005 mm the dixel rows and path samples grow without use (the engagement of a
#: 1 mm tool is resolved to < 1 deg at 0.005 mm); above D/10 the tool disc spans fewer than 10 dixel
#: rows, and the planners' stock, the engagement and the uncut area are meaningless (100 mm on a 6 mm
#: tool gave NaN and uncut 0)
MIN_RESOLUTION_MM = 0.005
MAX_RESOLUTION_TOOL_FRACTION = 0.1


def check_resolution(resolution_mm, job: Job, name: str = "resolution_mm") -> None:
    """Refuse (ValueError naming ``name`` and the job) a ``resolution_mm`` (mm) outside
    [:data:`MIN_RESOLUTION_MM`, :data:`MAX_RESOLUTION_TOOL_FRACTION` x the tool diameter]; None passes
    (each planner's own default).

    >>> from shapely.geometry import box
    >>> from cnclab.toolpath.path import Tool
    >>> check_resolution(1.0, Job(box(0, 0, 30, 20), Tool(6.0), 60.0, 1.0, v_c=100, f_z=0.05, source="j.json"))
    Traceback (most recent call last):
    ...
    ValueError: resolution_mm 1 mm is outside [0.005, 0.6] mm for j.json (tool D 6 mm): above D/10 the tool disc spans fewer than 10 dixel rows and the planning stock, engagement and uncut area are meaningless
    """
    if resolution_mm is None:
        return
    if (isinstance(resolution_mm, bool) or not isinstance(resolution_mm, (int, float, np.integer, np.floating))
            or not (math.isfinite(resolution_mm) and resolution_mm > 0)):
        raise ValueError(f"{name} must be a finite number > 0 mm (or None: each planner's default), "
                         f"got {resolution_mm!r}")
    hi = MAX_RESOLUTION_TOOL_FRACTION * job.tool_diameter
    why = None
    if resolution_mm > hi:
        why = ("above D/10 the tool disc spans fewer than 10 dixel rows and the planning stock, engagement and "
               "uncut area are meaningless")
    elif resolution_mm < MIN_RESOLUTION_MM:
        why = f"below {MIN_RESOLUTION_MM:g} mm the dixel rows and samples grow without gain in accuracy"
    if why:
        raise ValueError(f"{name} {float(resolution_mm):g} mm is outside [{MIN_RESOLUTION_MM:g}, {hi:g}] mm for "
                         f"{job.source} (tool D {job.tool_diameter:g} mm): {why}")


def _res(resolution_mm):
    return DEFAULT_RESOLUTION_MM if resolution_mm is None else resolution_mm


def register(name: str, description: str):
    """Decorator: add a one-level planner ``f(job, resolution_mm, **options) -> ToolPath`` under ``name``
    (an existing name is replaced: e.g. a new constant-engagement planner)."""
    def deco(f):
        STRATEGIES[name] = (f, description)
        return f
    return deco


#: the constant-engagement strategy's promise, checked on every level it plans (the one evaluator at
#: :data:`CE_CHECK_TOOL_FRACTION` x r): the engagement never above theta + CE_PROMISE_DEG, and at most
#: CE_SHARE_ABOVE_5_PCT % of the cutting length above theta + 5 deg; a path that breaks it is refused
#: (message: the measured values, where, and in which part: laps, links cutting material, cleanup).
#: Measured at r / 20 (issue 28), max - theta and share above theta + 5, before -> with the strategy's
#: link limit, lap clip and offset-ring cleanup (:data:`CE_LINK_LIMIT_DEG`, :data:`CE_CLIP_DEG`,
#: :data:`CE_CLEANUP_STEP_FRACTION`; the clip measured on the rectangle only):
#: discs hold it (D 6 in a 40 mm disc: max theta + 6, 0.08 %);
#: data/pockets/spline_pocket: 51.9 deg, 0.09 % (one link into material) -> 6.1 deg, 0.03 %: PLANNED
#: (tests/test_constant_engagement_strategy.py; see CE_WALL_MARGIN_MM);
#: Jacso's rectangle: 67.7, 2.76 % (laps 1.50, links 0.97, cleanup 0.29) -> 34.6, 0.90 % (laps 0.15,
#: links 0.21, cleanup 0.53) -> with the rounded corners (:data:`CE_CORNER_FRACTION`) 11.3, 0.28 % -> with
#: the cleanup rings' start chosen by a trial cut (ce_clearing ``_Clearing.ring_start``) 7.8, 0.17 %: PLANNED
#: (tests/test_constant_engagement_strategy.py); the issue-29 pocket (60 x 40, D8, depth 7.5, no start
#: hole) 35.1 (cleanup in a corner) -> 18.3 (a ring's link onto the wall by a corner) -> 9.6, 0.30 %: PLANNED
#: (tests/test_constant_engagement_deep.py); the 30 x 22 mm pocket of tests/test_deep_pockets.py 29.1 ->
#: 18.0 -> 8.6, 0.04 %: PLANNED; star 39.9 (links) -> 23.1, 1.09 % (cleanup by a tip); a 28 x 18 mm
#: rectangle 59.5, L 65.6 (links of the laps onto a wall run, head-on): still refused (2026-11-26);
#: Jacso's L: 68.4, 2.15 % -> 68.2, 1.38 % (before the clip); star: 69.6, 6.13 % -> 46.8, 3.37 % (cleanup
#: 2.39 % in the star's inner corners; before the clip); the 60 x 40 mm D8 deep pocket of issue 29
#: (first level, tests/test_constant_engagement_deep.py): 61.9, 1.24 % -> 32.7, 0.62 % (before the clip);
#: two_regions 102.3, 2.42 %; long_slot (a slot 1.2 D wide) 87.4, 36.2 %: refused. What remains above
#: theta + 15 is in the pocket's corners: the last contour-parallel passes turning there (theta + 15-29)
#: and links onto runs that start in a corner (theta + 30-35).
CE_PROMISE_DEG = 15.0
CE_SHARE_ABOVE_5_PCT = 1.0
#: the evaluation dixel of that check, as a fraction of the tool radius (r / 20: 0.15 mm for D 6;
#: the engagement it reports is within ~2 deg of the exact one away from the first contact)
CE_CHECK_TOOL_FRACTION = 0.05
#: the strategy's links: a run the link or jump reaches only above theta + this (deg) is started
#: further on (ce_clearing ``link_limit_deg``: twice the roll-in's gate margin)
CE_LINK_LIMIT_DEG = 10.0
#: the radial step of its contour-parallel passes over what the laps leave, as a fraction of the radial
#: depth of a straight cut at theta (ce_clearing ``cleanup_step_mm``; 28 x 18 mm rectangle, D6, theta 60:
#: 0.75 -> 3.56 %, 0.4 -> 1.40 %, 0.25 -> 0.72 % of the cutting length above theta + 5 in the cleanup)
CE_CLEANUP_STEP_FRACTION = 0.25
#: a lap run is cut up to its first step above theta + this (deg) in a trial cut and resumes after
#: that stretch (ce_clearing ``clip_deg``; Jacso's rectangle: a lap stretch at theta + 68 left out)
CE_CLIP_DEG = 12.0
#: its tool centres at depth stay this far (mm) inside the final contour (ce_clearing ``wall_margin_mm``):
#: the wall check (GOUGE_TOL_MM) found the tool 0.006 mm past the wall near (29.8, 25.0) on
#: data/pockets/spline_pocket with none, 0.002 mm with 0.005 mm, none with 0.02 (the cause of the
#: excursion not yet found); the walls keep a skin that thin (3.6 mm^2 uncut on that pocket)
CE_WALL_MARGIN_MM = 0.02
#: its cleanup (offset rings, final contour) rounds the pocket's concave corners (sharp convex corners
#: of the tool-centre region) by arcs of this fraction of the tool radius (ce_clearing
#: ``corner_radius_mm``): a tool centre turning on the spot in a corner meets the corner's cusp along
#: 90 deg of its edge, whatever the laps before. Jacso's rectangle (40 x 24, D6, theta 60), max - theta
#: and share above theta + 5 at r / 20 (uncut beyond the unreachable corners): none 30.8, 0.63 % (1.27
#: mm^2); r/3 15.6, 0.39 % (6.78); 0.4 r 11.3, 0.29 % (8.15): PLANNED; r/2 9.9, 0.25 % (10.37). The
#: price: (1 - pi/4) ((rho + r)^2 - r^2) mm^2 more left in each 90 deg corner (1.85 mm^2 for D6)
CE_CORNER_FRACTION = 0.4


def _has_islands(job: Job) -> bool:
    return any(len(g.interiors) for g in getattr(job.polygon, "geoms", [job.polygon]))


def _engagement_peak(trace, counted) -> tuple:
    """(engagement (deg) per trace sample with NaN and the samples not ``counted`` at -1, index of
    the largest): where a strategy's promise is measured."""
    eng = np.where(counted, np.nan_to_num(np.asarray(trace["engagement_deg"], float), nan=-1.0), -1.0)
    return eng, int(np.argmax(eng))


def _ce_breach(path: ToolPath, job: Job) -> str | None:
    """None when ``path`` keeps the constant-engagement promise on ``job``; else what it breaks: the
    measured maximum and share, where the maximum is, and the share per part of the path."""
    ev = evaluate(path, job, CE_CHECK_TOOL_FRACTION * job.tool_radius)
    th = job.theta_deg
    if ev.engagement_max_deg <= th + CE_PROMISE_DEG and ev.share_above_5_pct <= CE_SHARE_ABOVE_5_PCT:
        return None
    t = ev.trace
    cut = np.asarray(t["cutting"], bool)
    eng, k = _engagement_peak(t, cut)
    ds = np.asarray(t["ds_mm"], float)
    part = np.array(["cleanup" if "cleanup" in g else "links cutting material" if "linkcut" in g else "laps"
                     for g in t["tag"]], dtype=object)
    L = float(ds[cut].sum())
    shares = ", ".join(f"{name} {100.0 * ds[cut & (part == name) & (eng > th + 5)].sum() / L:.2f} %"
                       for name in ("laps", "links cutting material", "cleanup"))
    return (f"max {ev.engagement_max_deg:.1f} deg (theta {th:g} + {ev.engagement_max_deg - th:.1f}) at "
            f"({t['x'][k]:.2f}, {t['y'][k]:.2f}) in its {part[k]}, {ev.share_above_5_pct:.2f} % of the cutting length "
            f"above theta + 5 deg ({shares})")


@register("constant-engagement", "Jacsó Thesis III constant-engagement laps from helical entries (ce_clearing); "
          f"plans only jobs on which it keeps the engagement <= theta + {CE_PROMISE_DEG:g} deg and <= theta + 5 deg "
          f"on all but {CE_SHARE_ABOVE_5_PCT:g} % of its cutting length (else refuses: e.g. discs, the spline "
          "bench pocket, Jacsó's rectangle, the 60 x 40 mm deep pocket yes; L, star, islands no)")
def _constant_engagement(job: Job, resolution_mm: float, **options) -> ToolPath:
    """The Thesis III laps (:func:`cnclab.toolpath.ce_clearing.ce_clearing`), refused when the planned
    level breaks the promise (:data:`CE_PROMISE_DEG`, :data:`CE_SHARE_ABOVE_5_PCT`, measured by the
    evaluator at r / 20; islands included: no island pocket measured so far keeps it)."""
    from . import ce_clearing

    # runs resuming from the wall entered by roll-in arcs; around islands (where the arcs leave material,
    # see ce_routes.roll_in) the wall stretches are gated instead. Islands are planned and checked like
    # any pocket: measured at r / 20 (D6, theta 60), the 30 x 22 mm pocket with a 4 x 4 island of
    # tests/test_deep_pockets.py theta + 81.8, 4.9 % above theta + 5, the island pockets of
    # tests/test_strategy_safety.py theta + 120 (180 deg), 6.6-12.5 %: the laps stop at the island and
    # the cleanup slots round it, so they are refused with those numbers (issue 28)
    wall = "gate" if _has_islands(job) else "roll-in"
    a_e = job.tool_radius * (1.0 - math.cos(math.radians(job.theta_deg)))     # radial depth at theta, mm
    path = ce_clearing.ce_clearing(job, resolution_mm=_res(resolution_mm),
                                     **{"wall": wall, "link_limit_deg": CE_LINK_LIMIT_DEG,
                                        "clip_deg": CE_CLIP_DEG, "cleanup_step_mm": CE_CLEANUP_STEP_FRACTION * a_e,
                                        "wall_margin_mm": CE_WALL_MARGIN_MM,
                                        "corner_radius_mm": CE_CORNER_FRACTION * job.tool_radius, **options})
    breach = _ce_breach(path, job)
    if breach:
        raise ValueError(f"{job.source}: the constant-engagement strategy promises an engagement <= theta + "
                         f"{CE_PROMISE_DEG:g} deg, and <= theta + 5 deg on all but {CE_SHARE_ABOVE_5_PCT:g} % of its "
                         f"cutting length; on this pocket its path measures {breach}: refused, use the adaptive "
                         "strategy (theta + 10 deg)")
    return path


#: the hybrid strategy promises NO engagement bound in general and checks none per job (its centre
#: laps clamp to the wall, its arms follow the medial axis: 159.5 deg measured on a keyhole, issue 28);
#: on Jacsó's own pockets (data/jacso2021: star, rectangle, L; default options) it stays within
#: theta + HYBRID_JACSO_MAX_DEG and HYBRID_JACSO_SHARE_ABOVE_5_PCT % of the cutting length above
#: theta + 5 deg, measured by the evaluator at r / 20: max theta + 30.6 / 41.3 / 38 deg,
#: 0.88 / 1.49 / 1.5 % above theta + 5 (tests/test_pocket.py asserts it on the three pockets)
HYBRID_JACSO_MAX_DEG = 45.0
HYBRID_JACSO_SHARE_ABOVE_5_PCT = 2.0


@register("hybrid", "Jacsó §4 hybrid: centre laps around the start hole, CE trochoid arms; promises no "
          "engagement bound (none checked per job: 159.5 deg on a keyhole); on Jacsó's star, rectangle and L "
          f"within theta + {HYBRID_JACSO_MAX_DEG:g} deg and {HYBRID_JACSO_SHARE_ABOVE_5_PCT:g} % above theta + 5 deg")
def _hybrid(job: Job, resolution_mm: float, **options) -> ToolPath:
    """Jacsó §4 hybrid path (:func:`cnclab.toolpath.pocket.hybrid_path`) of a one-outline pocket. It
    states no engagement bound in general (:data:`HYBRID_JACSO_MAX_DEG`: only Jacsó's pockets are
    measured within theta + 45 deg, 2 % above theta + 5); use constant-engagement or adaptive for a
    bound checked on every job."""
    from . import pocket

    if not hasattr(job.polygon, "exterior"):
        raise ValueError(f"{job.source}: the hybrid strategy plans one pocket outline around one start hole; "
                         "this job has several regions (use the adaptive strategy)")
    try:
        return pocket.hybrid_path(job, _res(resolution_mm), **options)
    except (IndexError, AttributeError, TypeError) as exc:   # its medial-axis arms need a pocket wide enough
        raise ValueError(f"{job.source}: the hybrid strategy cannot build its arms in this pocket "
                         f"({type(exc).__name__}: {exc}); use the adaptive strategy") from None


@register("contour-parallel", "contour-parallel offsets at a_e, inside-out")
def _contour_parallel(job: Job, resolution_mm: float, **options) -> ToolPath:
    from . import pocket

    return pocket.contour_parallel_path(job, resolution_mm=_res(resolution_mm), **options)


@register("zig-zag", "zig-zag raster at a_e and a finishing lap")
def _zigzag(job: Job, resolution_mm: float, **options) -> ToolPath:
    from . import pocket

    return pocket.zigzag_path(job, resolution_mm=_res(resolution_mm), **options)


#: arc-fit tolerance (mm) of the Kim & Yang strategies' programs: the paper's 0.02 mm lets an arc
#: bulge up to ~0.035 mm past the tool-centre region (into the wall); 0.5 um, on the points and the
#: chords alike (``chords=True``: an arc through a polygon's vertices bulges past its sides by their
#: sagitta), keeps it inside :data:`GOUGE_TOL_MM`
ARC_FIT_TOL_MM = 5e-4


def _no_islands(job: Job, name: str) -> None:
    if _has_islands(job):
        raise ValueError(f"{job.source}: the {name} strategy has no island support (Kim & Yang 2006 offset "
                         "one outline: its passes and links would cut through the islands); use the adaptive "
                         "or contour-parallel strategy")


@register("kim-yang-original", "Kim & Yang 2006 contour-parallel path (offsets at a_e, spiral entries)")
def _kim_yang_original(job: Job, resolution_mm: float, **options) -> ToolPath:
    from . import constant_mrr

    _no_islands(job, "kim-yang-original")
    return constant_mrr.passes_path(constant_mrr.kim_yang_passes(job, **options), job, entry="helix",
                                    tol_mm=ARC_FIT_TOL_MM, chords=True)


@register("kim-yang-modified", "Kim & Yang 2006 constant-MRR modified contour-parallel path")
def _kim_yang_modified(job: Job, resolution_mm: float, **options) -> ToolPath:
    from . import constant_mrr

    _no_islands(job, "kim-yang-modified")
    passes = _snap_inside(constant_mrr.kim_yang_passes(job, modified=True, **options), job)
    return constant_mrr.passes_path(passes, job, entry="helix", tol_mm=ARC_FIT_TOL_MM, chords=True)


def _snap_inside(passes, job: Job) -> list:
    """The §3.2 modification moves pass points on a 0.3 mm pixel stock, up to ~0.04 mm past the
    tool-centre region (into the wall): such points are moved to the nearest point of the region."""
    allowed = job.allowed()
    edge = allowed.boundary
    out = []
    for q in passes:
        q = np.array(q, float)
        bad = np.flatnonzero(~shapely.contains_xy(allowed, q[:, 0], q[:, 1]))
        for k in bad:
            p = edge.interpolate(edge.project(shapely.Point(q[k])))
            q[k] = (p.x, p.y)
        out.append(q)
    return out


@register("adaptive", "engagement-controlled clearing of the simulated stock, links at depth (adaptive_clearing); "
          "promises an engagement <= theta + 10 deg, measured on every job (refuses a job beyond it unless "
          "allow_engagement_breach)")
def _adaptive(job: Job, resolution_mm: float, written=None, **options) -> ToolPath:
    """One level of :func:`cnclab.toolpath.adaptive.plan_job`, its promise checked
    (:func:`adaptive_engagement_check`): a level beyond the bounds (max theta +
    ``AdaptiveParams.promise_max_deg`` less the written program's margin ``written_margin_deg``, p95 theta + ``promise_p95_deg``, share above theta + 5 deg
    ``promise_share_pct``) is planned again (:func:`_retries`: the tighter sliver guard
    ``retry_guard_deg``, the nearest pass starts, both, the narrow regions' trochoids checked period
    by period) and the first plan within all three kept, else
    the lowest maximum; a level still beyond the bounds is measured again at finer dixels and its
    peaks on the exact vector stock, the verdict (:func:`_refined_check`); a maximum still beyond the promise: ``info["engagement_breach"]`` says
    where and how far (:func:`plan` refuses it unless ``allow_engagement_breach``, then states it in
    ``info["warnings"]`` and the program header); ``info["engagement_check"]`` holds the measure.
    ``written`` (default None: the planned path is measured): ``written(path, job)`` is the path as the
    program writes it (``cnclab.nc.program.program_path``: the arc fit), measured instead, so that the
    promise holds for the program a machine runs (``python -m cnclab plan`` passes it)."""
    # the planning pixel is at most r/60, the resolution the planner was designed and measured at
    # (at r/20 the K&Y pocket keeps 169 mm^2 uncut, at r/30 5 mm^2): a finer resolution_mm is used as
    # given, a coarser one (a caller's evaluation dixel) plans at r/60 (info["resolution_mm"] says so)
    h = None if resolution_mm is None else min(float(resolution_mm), job.tool_radius / 60.0)
    prm = options.pop("params", None) or adaptive.AdaptiveParams()
    form = (lambda p, j: p) if written is None else written
    path = adaptive.plan_job(job, resolution_mm=h, params=prm, **options)
    if not prm.check_resolution_frac > 0:       # the check is off
        return path
    shown = form(path, job)                        # what the check measures: the path as written
    chk, *seen = _engagement_eval(shown, job, prm, None)     # seen: its evaluation, kept for _refined_check
    for again_prm in _retries(prm, path.info.get("skin_steps", 0)):
        if _within_bounds(chk, job, prm):
            break
        again = adaptive.plan_job(job, resolution_mm=h, params=again_prm, **options)
        shown2 = form(again, job)
        chk2, *seen2 = _engagement_eval(shown2, job, prm, None)
        if _within_bounds(chk2, job, prm) or (not _within_bounds(chk, job, prm) and chk2["max_deg"] < chk["max_deg"]):
            path, shown, chk, seen = again, shown2, dict(chk2, retried=True), seen2
    if not _within_bounds(chk, job, prm):
        chk = _refined_check(shown, job, prm, chk, tuple(seen))
    path.info["engagement_check"] = chk
    if not chk["ok"]:
        path.info["engagement_breach"] = (
            f"{job.source}: the adaptive strategy promises an engagement <= theta + {prm.promise_max_deg:g} deg; the "
            f"level at z {min(job.levels()):g} mm measures {chk['where']} (evaluator at {chk['resolution_mm']:.4g} mm)")
    return path


def _refined_check(path: ToolPath, job: Job, prm, chk: dict, coarse_eval: tuple) -> dict:
    """The verdict on a level still beyond the bounds after every retry: ``path`` measured again at
    half the check's dixel (:func:`adaptive_engagement_check`), and at half that while it stays beyond
    the bounds (:func:`_within_bounds`), at most ``prm.refine_halvings`` times, never finer than
    ``prm.refine_min_resolution_mm`` nor over ``prm.refine_max_pixels`` dixels; the finest measure is
    the verdict, the coarse one kept under ``"coarse"`` and every dixel's maximum under
    ``"refined"`` (``[(resolution_mm, max_deg), ...]``). The evaluator converges as its dixel shrinks,
    and at r / 30 a sliver thinner than a dixel row can read high where the tool takes it at the end
    of a pass: random pocket 97:7 (r 5 mm, theta 40, a pass ending in the pinched tip of the
    tool-centre region) reads theta + 12.6 at r / 30 and theta + 4.4 at r / 60 (the evaluator on its
    written program: + 4.7, + 3.4, + 2.4, + 3.4 at r / 60, r / 100, r / 200, r / 400). The highest
    samples of every measure are also measured on the exact vector stock (``prm.refine_vector_peaks``,
    :func:`_vector_verdict`): where that reads more, it decides. A level beyond the promise stays
    refused. With no finer dixel allowed, ``chk`` is the verdict. ``coarse_eval``: ``(Evaluation,
    counted)`` of ``chk`` (:func:`_engagement_eval`), whose peaks are measured on the vector stock too."""
    x0, y0, x1, y1 = job.polygon.bounds
    r = job.tool_radius
    area = (x1 - x0 + 2 * r) * (y1 - y0 + 2 * r)
    fine, steps, evs = chk, [], []
    for _ in range(prm.refine_halvings):
        hf = 0.5 * fine["resolution_mm"]
        if hf < prm.refine_min_resolution_mm or area / (hf * hf) > prm.refine_max_pixels:
            break
        fine, ev, counted = _engagement_eval(path, job, prm, hf)
        steps.append((hf, fine["max_deg"]))
        evs.append((ev, counted))
        if _within_bounds(fine, job, prm):
            break
    if not steps:
        return chk
    coarse = {k: v for k, v in chk.items() if k != "retried"}
    out = dict(fine, coarse=coarse, refined=steps, **({"retried": chk["retried"]} if "retried" in chk else {}))
    if prm.refine_vector_peaks > 0:
        out = _vector_verdict(out, [coarse_eval] + evs, job, prm)
    return out


def _vector_verdict(out: dict, evs: list, job: Job, prm) -> dict:
    """``out`` (the refined verdict) with the ``prm.refine_vector_peaks`` highest samples of each
    evaluation in ``evs`` (``[(Evaluation, counted), ...]``) measured on the vector stock
    (:func:`cnclab.toolpath.vector_check.vector_peaks`), listed under ``"vector_peaks"`` (x, y mm,
    dixel deg, vector deg); where the vector stock reads more than ``out["max_deg"]`` it is the maximum."""
    pk = [q for ev, counted in evs for q in vector_peaks(ev, job, counted, prm.refine_vector_peaks)]
    out = dict(out, vector_peaks=[tuple(round(v, 3) for v in q) for q in pk])
    if not pk:
        return out
    x, y, dix, vmax = max(pk, key=lambda q: q[3])
    if vmax > out["max_deg"]:
        th = job.theta_deg
        out.update(max_deg=vmax, ok=bool(vmax <= th + prm.promise_max_deg),
                   where=f"max {vmax:.1f} deg (theta {th:g} + {vmax - th:.1f}) at ({x:.2f}, {y:.2f}) on the exact vector "
                         f"stock (chips of 2 um and more; the dixel there reads {dix:.1f}); " + out["where"])
    return out


def _retries(prm, skin_steps: int = 0):
    """The re-plans of a level beyond the engagement bounds, in order: (when the level lapped
    ``skin_steps`` sliver parts from a skin step) the level without them, the tighter sliver guard, the
    nearest pass starts, both, then the narrow regions' trochoids checked period by period
    (``retry_narrow_check_deg``), last the tighter guard with the finishing laps held closer to theta
    (``retry_finish_margin_deg``; :class:`cnclab.toolpath.adaptive.AdaptiveParams`)."""
    if prm.finish_skin_step and skin_steps:
        # first the level without skin laps, then every retry of that one (the plans made before them)
        plain = dataclasses.replace(prm, finish_skin_step=False)
        return [plain] + _retries(plain)
    guard = dataclasses.replace(prm, guard_deg=prm.retry_guard_deg)
    out = [guard, dataclasses.replace(prm, upstream_start_frac=0.0), dataclasses.replace(guard, upstream_start_frac=0.0)]
    if prm.narrow_check_margin_deg is None:
        checked = dataclasses.replace(prm, narrow_check_margin_deg=prm.retry_narrow_check_deg)
        out.append(checked)
        if not prm.narrow_branches:
            out.append(dataclasses.replace(checked, narrow_branches=True))
    if prm.finish_margin_deg > prm.retry_finish_margin_deg:      # last: a breach on a finishing lap
        out.append(dataclasses.replace(guard, finish_margin_deg=prm.retry_finish_margin_deg))
    return out


def _within_bounds(chk: dict, job: Job, prm) -> bool:
    """Whether a level's :func:`adaptive_engagement_check` holds all three bounds: max (with the
    written program's margin, ``prm.written_margin_deg`` below the promise), p95 and share."""
    aim = job.theta_deg + prm.promise_max_deg - prm.written_margin_deg
    return bool(chk["ok"] and chk["max_deg"] <= aim and chk["p95_deg"] <= job.theta_deg + prm.promise_p95_deg
                and chk["share_above_5_pct"] <= prm.promise_share_pct)


def adaptive_engagement_check(path: ToolPath, job: Job, prm, resolution_mm: float | None = None) -> dict | None:
    """The adaptive planner's promise measured on its own ``path`` of one level: the evaluator
    (:func:`cnclab.toolpath.evaluate.evaluate_engagement`, its dixel stock) at ``prm.check_resolution_frac`` r
    (at least ``prm.check_min_resolution_mm``; ``resolution_mm``, mm: that dixel instead); None when
    the check is off (frac 0). A dict:
    ``resolution_mm``, ``max_deg`` (over the cutting samples; with ``prm.slot_narrow`` its slots, whose
    engagement the notes state, aside), ``p95_deg``, ``share_above_5_pct`` (the evaluator's), ``ok``
    (max <= theta + ``prm.promise_max_deg``), ``where`` (the maximum, where it is, the tag of its move).

    >>> from shapely.geometry import box
    >>> from cnclab.toolpath.path import Tool
    >>> job = Job(box(0, 0, 16, 11), Tool(3.0), 60.0, 1.0, v_c=100, f_z=0.05)
    >>> prm = adaptive.AdaptiveParams()
    >>> chk = adaptive_engagement_check(adaptive.plan_job(job, params=prm), job, prm)
    >>> chk["ok"], chk["max_deg"] <= 70.0, round(chk["resolution_mm"], 3)
    (True, True, 0.05)
    """
    if not prm.check_resolution_frac > 0:
        return None
    return _engagement_eval(path, job, prm, resolution_mm)[0]


def _engagement_eval(path: ToolPath, job: Job, prm, resolution_mm: float | None) -> tuple:
    """``(check dict, Evaluation, counted (N,) bool)`` of :func:`adaptive_engagement_check`: the
    measure, the evaluation it was read from and the samples it counts."""
    hc = max(prm.check_resolution_frac * job.tool_radius, prm.check_min_resolution_mm) if resolution_mm is None \
        else float(resolution_mm)
    ev = evaluate_engagement(path, job, hc)     # gouge and uncut area: plan measures them itself
    th = job.theta_deg
    t = ev.trace
    tags = np.array([str(g) for g in t["tag"]], dtype=object)
    # the slots of the opt-in slot_narrow are no breach: their engagement (up to 180 deg) is its stated point
    counted = np.asarray(t["cutting"], bool) & ~((tags == "slot") if prm.slot_narrow else np.zeros(len(tags), bool))
    if not counted.any():
        return {"resolution_mm": hc, "max_deg": float("nan"), "p95_deg": float("nan"), "share_above_5_pct": float("nan"),
                "ok": True, "where": "no cutting"}, ev, counted
    eng, k = _engagement_peak(t, counted)
    mx = float(eng[k])
    where = (f"max {mx:.1f} deg (theta {th:g} + {mx - th:.1f}) at ({t['x'][k]:.2f}, {t['y'][k]:.2f}) in a move "
             f"'{tags[k] or 'clearing pass'}', p95 {ev.engagement_p95_deg:.1f} deg, {ev.share_above_5_pct:.2f} % of "
             "the cutting length above theta + 5 deg")
    return {"resolution_mm": hc, "max_deg": mx, "p95_deg": float(ev.engagement_p95_deg),
            "share_above_5_pct": float(ev.share_above_5_pct), "ok": bool(mx <= th + prm.promise_max_deg), "where": where}, ev, counted


#: the strategy :func:`plan` (and ``python -m cnclab plan``) uses when none is named
DEFAULT_STRATEGY = "adaptive"


#: the most levels :func:`plan` accepts (depth / a_p): a deeper job is refused up front
MAX_LEVELS = 1000
#: the smallest level step (mm) :func:`plan` accepts: 10 units of the program's 4th decimal, so every
#: level is written below the one above it (a_p = 1e-6 would be written at Z0)
MIN_LEVEL_STEP_MM = 0.001
#: how far (mm) a tool disc may reach past a wall or island (exact geometry, every r / 10 along the
#: path) before plan refuses the strategy's path: the planners' finishing-snap tolerance
GOUGE_TOL_MM = 1e-3


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


def lowered_level(path: ToolPath, z_from: float, z_to: float, clearance_z: float) -> ToolPath:
    """The one-level plan ``path`` of the level cutting at ``z_from`` (mm) as the plan of an equally deep
    level cutting at ``z_to``: every point below the clearance plane ``clearance_z`` lowered by
    ``z_from - z_to``, the rest (the clearance-plane moves) kept; the z in its info (``levels``, the
    parts it states it left, the engagement-breach text) said of ``z_to``. What a strategy plans for
    the deeper level itself, to float rounding (the helix's z steps)."""
    dz = z_to - z_from
    xyz = path.xyz.copy()
    low = xyz[:, 2] < clearance_z - 1e-9
    xyz[low, 2] += dz
    xyz[low & (np.abs(path.xyz[:, 2] - z_from) < 1e-9), 2] = z_to     # the cutting moves at exactly z_to

    def said(v):
        if isinstance(v, str):
            return v.replace(f"level z {z_from:g}:", f"level z {z_to:g}:").replace(f"level at z {z_from:g} mm",
                                                                                   f"level at z {z_to:g} mm")
        if isinstance(v, list):
            return [said(q) for q in v]
        return v

    info = {k: said(copy.deepcopy(v)) for k, v in path.info.items()}
    if "levels" in info:
        info["levels"] = [z_to]
    cols = {f.name: getattr(path, f.name).copy() for f in dataclasses.fields(path)
            if isinstance(getattr(path, f.name), np.ndarray) and f.name != "xyz"}
    return dataclasses.replace(path, xyz=xyz, info=info, **cols)


def _uncut_message(job: Job, strategy: str, rep: dict, left=()) -> str:
    """The uncut-area refusal (or warning): the regions over their limit, then how many parts the
    planner stated it left (``info["left_parts"]``: each with where, its size and why) and the first."""
    n = len(rep.get("levels", ())) or 1
    # the uncut area and its limit are sums over the levels, the reachable area is one level's (a
    # deep pocket read "7628.1 mm^2 left of 5350 mm^2 reachable per level, summed over its 3 levels")
    over = "" if n == 1 else f" over its {n} levels"
    each = "" if n == 1 else " on each level"
    summed = "" if n == 1 else ", summed over the levels"
    parts = "; ".join(f"region {k}: {rep['uncut_mm2'][k]:.1f} mm^2 left{over} of {rep['reach_mm2'][k]:.0f} mm^2 "
                      f"reachable{each} (limit {rep['limit_mm2'][k]:.1f}{summed})" for k in rep["over"])
    why = "" if not left else (f"; the plan states {len(left)} part(s) left" + (", the first" if len(left) > 1 else "")
                               + f": {left[0]}")
    return (f"{job.source}: strategy {strategy} leaves material uncut beyond the corners no tool disc reaches: "
            f"{parts}{why}")


def _run_strategy(f, strategy: str, job: Job, resolution_mm: float, options: dict) -> ToolPath:
    """``f(job, resolution_mm, **options)``; a planner's internal failure on a job it cannot handle
    (an empty medial axis, a region too thin for its seeds...) becomes a refusal naming the job."""
    try:
        return f(job, resolution_mm, **options)
    except (ValueError, IndexError, AttributeError, ZeroDivisionError, shapely.errors.GEOSException) as exc:
        if isinstance(exc, ValueError) and str(job.source) in str(exc):
            raise
        raise ValueError(f"{job.source}: strategy {strategy} cannot plan this job "
                         f"({type(exc).__name__}: {exc}); try the adaptive strategy") from exc


def plan(job: Job, strategy: str = DEFAULT_STRATEGY, resolution_mm: float | None = None, allow_uncut: bool = False,
         **options) -> ToolPath:
    """Plan ``job`` with ``strategy`` (a key of :data:`STRATEGIES`) level by level.

    ``resolution_mm``: the planners' dixel row height / planning pixel / sampling step (mm), passed
    to every strategy (None: each planner's own default, 0.1 mm, the adaptive planner's r/60; the
    adaptive planner plans at r/60 or finer, see ``info["resolution_mm"]``); ``options`` go to the
    planner. The levels (:meth:`Job.levels`, at most ``a_p`` each) are planned here, each as a
    one-level job whose top is the floor above (a level as deep as the first -- with equal levels,
    every one -- is the first's plan lowered, :func:`lowered_level`: each strategy plans the same 2D
    problem one step down the same way, so it is planned and checked once), and joined by
    :func:`cnclab.toolpath.levels.join_levels`: a move through the levels above is marked cleared
    only where their swept area proves it, else the level enters by a helix from the stock top.
    Every helix and ramp entry then runs at the job's entry feed (:attr:`Job.entry_feed`, mm/min;
    :func:`cnclab.toolpath.levels.with_entry_feed`, ``info["entry_feed_mm_min"]``): the path carries
    the feeds the program writer writes, so :func:`cnclab.toolpath.evaluate.evaluate` times the
    written program.
    Returns one :class:`ToolPath`; ``info["levels"]`` holds the cutting z of each level,
    ``info["strategy"]`` the name, ``info["levels_extra_mm2"]`` the area each level's tool body meets
    material the levels above left, ``info["uncut"]`` what the plan leaves by region
    (:func:`cnclab.toolpath.coverage.uncut_report`). A plan leaving more than the stated limit in a
    region raises :class:`UncutError`, unless ``allow_uncut`` (then ``info["warnings"]`` says it).
    A level beyond the strategy's engagement promise (the adaptive one, measured per level:
    ``info["engagement_check"]``, the worst level's) raises ValueError naming the job, where and how
    far, unless the option ``allow_engagement_breach=True`` (then the warnings and the program header
    say it). The option ``written`` (a function ``(path, job) -> path``, e.g.
    ``cnclab.nc.program.program_path``: the path as the program writes it) makes that check measure
    the written form; ``python -m cnclab plan`` and the benchmarks pass it; strategies without such a
    check ignore it. Every level's ``notes``, ``warnings`` and ``left_parts`` reach the result.
    A job beyond :data:`MAX_LEVELS` / :data:`MIN_LEVEL_STEP_MM`, or a ``resolution_mm`` outside
    [:data:`MIN_RESOLUTION_MM`, D / 10] (:func:`check_resolution`), is refused before planning."""
    if strategy not in STRATEGIES:
        raise ValueError(f"unknown strategy {strategy!r}: must be one of {sorted(STRATEGIES)}")
    if not isinstance(job, Job):
        raise TypeError(f"job must be a cnclab.toolpath.job.Job, got {type(job).__name__}")
    check_resolution(resolution_mm, job)
    check_limits(job)
    f = STRATEGIES[strategy][0]
    allow_breach = bool(options.pop("allow_engagement_breach", False))
    written = options.pop("written", None)     # the writer's form of a path: the adaptive promise's check
    if written is not None and "written" in inspect.signature(f).parameters:
        options["written"] = written
    levels = job.levels()
    tops = [job.top_z] + levels[:-1]
    paths = []
    for top, z in zip(tops, levels):
        if paths and math.isclose(top - z, tops[0] - levels[0], rel_tol=0.0, abs_tol=1e-12):
            # a level as deep as the first is the first level's 2D problem one step down: its plan,
            # lowered (every strategy plans it so; tests/test_deep_pockets.py), as FreeCAD plans once
            paths.append(lowered_level(paths[0], levels[0], z, job.clearance_z))
            continue
        lv = job if len(levels) == 1 else dataclasses.replace(job, top_z=top, a_p=top - z, depth=top - z)
        paths.append(_run_strategy(f, strategy, lv, resolution_mm, options))
    out = with_entry_feed(join_levels(paths, tops, job), job)
    out.info.update(strategy=strategy, levels=levels)
    for key in ("notes", "warnings", "left_parts"):      # every level's, not only the first's
        got = list(dict.fromkeys(q for p in paths for q in p.info.get(key, ())))
        if got:
            out.info[key] = got
    checks = [p.info["engagement_check"] for p in paths if "engagement_check" in p.info]
    if checks:                         # the adaptive promise per level (_adaptive): the worst level's
        out.info["engagement_check"] = max(checks, key=lambda c: c["max_deg"])
    gouge, at = coverage.wall_gouge(out, job)
    if gouge > GOUGE_TOL_MM:
        raise ValueError(f"{job.source}: strategy {strategy} cannot honour this job: its tool reaches {gouge:.3f} mm "
                         f"into a wall or island near ({at[0]:.2f}, {at[1]:.2f}) (tolerance {GOUGE_TOL_MM:g} mm); "
                         "use the adaptive strategy")
    rep = coverage.uncut_report(out, job)
    out.info["uncut"] = rep
    if rep["over"]:
        msg = _uncut_message(job, strategy, rep, out.info.get("left_parts", ()))
        if not allow_uncut:
            raise UncutError(msg + " (accept it with allow_uncut=True, CLI --allow-uncut)", rep)
        out.info.setdefault("warnings", []).append(msg)
    breach = [p.info["engagement_breach"] for p in paths if "engagement_breach" in p.info]
    if breach:          # a strategy's promise broken on this job (the adaptive one: _adaptive)
        if not allow_breach:
            raise ValueError(breach[0] + ": refused (accept it with allow_engagement_breach=True, CLI --allow-engagement-breach)")
        out.info.setdefault("warnings", []).extend(breach)
        out.info["notes"] = list(out.info.get("notes", ())) + [f"engagement beyond the promise: {b}" for b in breach]
    return out
