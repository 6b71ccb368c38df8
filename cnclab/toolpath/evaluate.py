"""One evaluator for every tool path: :func:`evaluate` a :class:`~cnclab.toolpath.path.ToolPath` on
a :class:`~cnclab.toolpath.job.Job` with the dixel simulator, one metric schema (:class:`Evaluation`).

Model (units: mm, deg, mm/min, s):

* The stock is the pocket (outline minus islands minus the pre-drilled start hole) from ``top_z``
  down to ``top_z - depth``, cut in the levels of :meth:`Job.levels`. Each level is a slab with its
  own 2D dixel stock (:class:`cnclab.simulation.dixel.Stock`); the path is sampled every
  ``resolution_mm`` (:meth:`ToolPath.resample`) and every sample whose tool tip is below a slab's
  top (by more than :data:`POSITION_TOL_MM`: a written program's rounding of a level's z does not
  enter the slab below) cuts the tool disc out of that slab, in path order (:func:`cnclab.simulation.common.simulate`
  on each run of consecutive samples inside the slab). The slab is 2D: a tool that has entered it
  removes its full thickness under the disc, so ramps and helices are approximated by the level
  they cross (they are entries: excluded from the engagement statistics anyway). The engagement is
  measured with the simulator's lag (the disks of the last ``2 sqrt(2 r h) + 2 h`` mm are cut after
  the measurement, against the row-discretisation artefact at the ends of the front half-circle)
  under ``lag_rule="front"``: a held-back disk that truly covers the front half-circle -- the path
  came back beside itself within the lag, e.g. a pass starting where the previous one ended -- is
  cut first, so material the tool has already removed is never counted as engaged.
* **Cutting samples**: cut or link moves (at depth) that remove more than ``air_tol_mm2`` (default
  half a dixel row squared); engagement (max over the slabs the tool is in) and MRR statistics are
  length-weighted over them. A *cut* move removing nothing is **air cut**.
* **Plunges into material**: a descending move that is not a helix or ramp (a plunge, or a cut,
  link or rapid losing z) and whose tool disc removes material where it enters a slab; the swept
  area is the material area under the disc. **Rapids into material**: rapid moves that remove
  material, or run below ``top_z`` with the tool centre outside the allowed region (into a wall or
  island) by more than :data:`POSITION_TOL_MM`. Both are counted as runs of consecutive moves (one
  plunge written as n blocks counts once); :attr:`Evaluation.events` lists every block.
* **Wall gouge** (:func:`wall_gouge`): how far the tool disc reaches past the walls and islands below
  the stock top (``wall_gouge_max_mm``), the plan-view wall area it sweeps (``wall_gouge_area_mm2``)
  and the number of gouging stretches (``gouges``: runs of samples gouging more than
  :data:`POSITION_TOL_MM`).
* **Uncut area**: material left, summed over the levels; *beyond unreachable*: the part outside the
  region no tool disc can reach (the pocket minus the morphological opening: the union of the tool
  discs over the allowed tool-centre region).
* **Times**: :meth:`ToolPath.time_s` at ``job.rapid_mm_min`` — the motion model of the written program
  (feed moves at their feed, rapids at the rapid rate, no acceleration) — and beside it
  ``time_machine_s``: the same blocks on a machine that accelerates (:mod:`cnclab.toolpath.motion`,
  default :data:`~cnclab.toolpath.motion.SMALL_VMC`: per-axis rate and acceleration, corner and
  centripetal limits, look-ahead; validated against LinuxCNC's planner). It times the path as given:
  a planner's polyline as polyline, a path read from a program with its arcs. The program writer
  writes every feed as the path has it (:func:`cnclab.toolpath.planners.plan` gives helix and ramp
  entries the job's entry feed, :attr:`Job.entry_feed <cnclab.toolpath.job.Job.entry_feed>`) and fits
  arcs (:mod:`cnclab.nc.arcfit`), so a planned path's ``time_s`` is the written program's length /
  feed time (within the written rounding; with fitted arcs within 0.04 %, measured) and its
  ``time_machine_s`` differs by the arc fitting only: measured on the eight bench pockets (adaptive,
  small VMC, planned at 0.1 mm, 2026-11-25), the written program's machine time is 0.29-0.72 % longer
  (before the entry feed was
  planned: 0.6-0.9 % on the star, rectangle, L and 120 x 85 pockets, 2.4 / 4.0 / 7.8 / 55 % on spline,
  two_islands_neck, two_regions and slot). Tested: tests/test_entry_feed_times.py.
* **Feed control** (``feed_control=True``, Jacsó Thesis IV / §4): the cutting level (the lowest z
  of the path, :func:`planar_view`) is cut through one dixel stock of the pocket minus the entry hole
  (:func:`entry_hole`) with segment kinds from the tags (cut / roll-in / roll-out / link); the
  roll-in/roll-out steps get the MRR-holding feed (:func:`cnclab.cutting.feed_control.controlled_feed`,
  capped at ``job.v_fmax``); link steps that remove more than ``link_tol_mm2`` run at the cutting
  feed. ``time_feed_controlled_s`` is the written program's time with those feeds (the path time
  plus, per level sample, ``ds (1/v_controlled - 1/v_path)``), ``mrr_error_cut_pct`` the windowed
  MRR error of the "cut" steps; the per-step table and the level summary (per segment kind) are
  ``trace["level"]`` and ``trace["level_summary"]``. With ``feed_control=False`` the same level
  model runs at constant feed (the comparison baseline); ``None`` (default) skips it.

>>> from cnclab.toolpath.job import Job
>>> from cnclab.toolpath.path import Tool, ToolPath
>>> from shapely.geometry import box
>>> job = Job(box(0, 0, 40, 20), Tool(6.0, flutes=2), 180.0, 2.0, v_c=100, feed_mm_min=300)
>>> p = ToolPath.build([[-5, 10, 5], [-5, 10, -2], [45, 10, -2], [45, 10, 5]],
...                    kind=["rapid", "plunge", "cut", "retract"], feed=300)
>>> ev = evaluate(p, job, 0.05)                   # a full slot across the pocket, entered from outside
>>> round(ev.engagement_p50_deg), ev.plunges_into_material, ev.retracts
(180, 0, 1)
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd
import shapely
from shapely.geometry import Point

from ..cutting.feed_control import controlled_feed, mrr_error_windowed
from ..geometry.planar import wall_clearance
from ..simulation import dixel
from ..simulation.common import simulate, simulate_runs
from .job import Job
from .motion import SMALL_VMC, Machine, path_machine_time
from .path import KINDS, ToolPath

__all__ = ["Evaluation", "evaluate", "evaluate_engagement", "UNITS", "weighted_percentile", "unreachable_region", "planar_view",
           "entry_hole", "SEGMENT_KINDS", "POSITION_TOL_MM", "EVENT_COLUMNS", "resample_by_length", "wall_gouge"]

#: segment kinds of the cutting level (from the move kind and the tag's ``phase:kind``)
SEGMENT_KINDS = ("cut", "roll-in", "roll-out", "link")

_K = {k: i for i, k in enumerate(KINDS)}

#: unit of every scalar field of :class:`Evaluation` (for :meth:`Evaluation.summary_table`)
UNITS = {"deg": "deg", "pct": "%", "mm2": "mm^2", "mm": "mm", "_s": "s", "nominal": "-"}

#: position tolerance (mm) of the safety checks (rapids outside the tool-centre region, wall gouge
#: events): the reading tolerance of programs written with 3 decimals (0.0005 mm per coordinate, up to
#: 2 sqrt(2) x that on an arc's radius) and larger than the rounding of an inch program written with 4
#: or more decimals (0.00127 mm); a G20 copy of a mm program then reports the same events.
POSITION_TOL_MM = 0.002

#: largest sagitta (mm) of the chords an arc is sampled on (:func:`resample_by_length`): the samples
#: lie within 0.1 um of the arc, so a wall gouge read on them is the program's, not the chords' (chords
#: as long as the step lie step^2 / (8 r) inside an arc of radius r: 1.3 um at r / 22 on r = 5 mm,
#: read as a gouge round every convex wall corner an arc goes round)
ARC_SAGITTA_MM = 1e-4

#: columns of :attr:`Evaluation.events` (one row per event; ``move`` indexes the path's points,
#: ``line`` the program line when the path came from a program (``path.info["line"]``), else -1)
EVENT_COLUMNS = ("event", "move", "line", "x", "y", "z", "value", "unit")


def _events_frame(rows) -> pd.DataFrame:
    return pd.DataFrame(rows, columns=list(EVENT_COLUMNS))


@dataclasses.dataclass(frozen=True)
class Evaluation:
    """Metrics of a tool path on a job (units in the names; see the module docstring)."""

    engagement_p50_deg: float
    engagement_p95_deg: float
    engagement_max_deg: float
    share_above_5_pct: float
    share_above_15_pct: float
    entry_engagement_max_deg: float
    mrr_max_over_nominal: float
    entries_helix: int
    entries_ramp: int
    entries_plunge: int
    plunges_into_material: int
    plunge_swept_area_mm2: float
    rapids_into_material: int
    retracts: int
    cut_length_mm: float
    link_length_mm: float
    rapid_length_mm: float
    entry_length_mm: float
    retract_length_mm: float
    air_cut_length_mm: float
    uncut_area_mm2: float
    uncut_beyond_unreachable_mm2: float
    time_cut_s: float
    time_link_s: float
    time_rapid_s: float
    time_entry_s: float
    time_retract_s: float
    time_total_s: float
    theta_deg: float
    resolution_mm: float
    time_feed_controlled_s: float = float("nan")
    time_machine_s: float = float("nan")
    mrr_error_cut_pct: float = float("nan")
    mrr_error_cut_p95_pct: float = float("nan")
    wall_gouge_max_mm: float = float("nan")
    wall_gouge_area_mm2: float = float("nan")
    gouges: int = -1
    trace: dict = dataclasses.field(repr=False, compare=False, default_factory=dict)
    events: pd.DataFrame = dataclasses.field(repr=False, compare=False, default_factory=lambda: _events_frame([]))
    #: further scalar metrics of a special evaluation (e.g. a trochoidal pattern's ``step_mm``), units in
    #: the names; part of :meth:`to_dict` and of the mapping access ``ev["name"]``
    extra: dict = dataclasses.field(compare=False, default_factory=dict)

    @classmethod
    def partial(cls, **known) -> "Evaluation":
        """An Evaluation of the ``known`` fields only: every other metric NaN (a count -1: "not
        measured"), e.g. for a path evaluated without the job's stock (a slot pattern).

        >>> ev = Evaluation.partial(engagement_max_deg=42.0, extra={"step_mm": 0.5})
        >>> ev["engagement_max_deg"], ev["step_mm"], ev.plunges_into_material
        (42.0, 0.5, -1)
        """
        out = {}
        for f in dataclasses.fields(cls):
            if f.name in known or f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING:
                continue
            out[f.name] = -1 if f.type in ("int", int) else float("nan")
        return cls(**out, **known)

    def to_dict(self) -> dict:
        """The scalar fields and :attr:`extra` (``trace`` and ``events`` left out)."""
        out = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
               if f.name not in ("trace", "events", "extra")}
        return {**out, **self.extra}

    def keys(self):
        """The metric names (mapping access: ``ev["engagement_max_deg"]``, ``{**ev}``)."""
        return self.to_dict().keys()

    def __getitem__(self, name: str):
        d = self.to_dict()
        if name not in d:
            raise KeyError(f"no metric {name!r} in this Evaluation")
        return d[name]

    def summary_table(self) -> pd.DataFrame:
        """Scalars as a table: columns ``metric``, ``value``, ``unit``."""
        rows = []
        for k, v in self.to_dict().items():
            unit = next((u for suf, u in UNITS.items() if k.endswith(suf)), "count")
            rows.append({"metric": k, "value": v, "unit": unit})
        return pd.DataFrame(rows)


def weighted_percentile(values, weights, q: float) -> float:
    """Length-weighted percentile: the smallest value whose cumulative weight reaches ``q`` % of the
    total (NaN for no weight).

    >>> weighted_percentile([1, 2, 3], [1, 1, 2], 50)
    2.0
    """
    v, w = np.asarray(values, float), np.asarray(weights, float)
    ok = np.isfinite(v) & (w > 0)
    if not ok.any():
        return float("nan")
    o = np.argsort(v[ok])
    c = np.cumsum(w[ok][o])
    return float(v[ok][o][np.searchsorted(c, q / 100.0 * c[-1] - 1e-12 * c[-1])])


def unreachable_region(polygon, tool_radius: float):
    """Part of the pocket no tool disc reaches: pocket minus the union of the discs over the allowed
    tool-centre region (the morphological opening by the tool disc).

    >>> from shapely.geometry import box
    >>> round(unreachable_region(box(0, 0, 20, 10), 3.0).area, 2)      # 4 r^2 (1 - pi/4) = 7.726 (64-gon arcs)
    7.73
    """
    reach = polygon.buffer(-tool_radius, quad_segs=64).buffer(tool_radius, quad_segs=64)
    return polygon.difference(reach)


def _runs(mask):
    """(start, stop) pairs of the maximal runs of True."""
    e = np.flatnonzero(np.diff(np.r_[0, np.asarray(mask, int), 0]))
    return list(zip(e[0::2], e[1::2]))


def _move_runs(moves) -> int:
    """Number of runs of consecutive move indices (a plunge or rapid written as n blocks counts once)."""
    m = np.unique(moves)
    return int(m.size and 1 + np.count_nonzero(np.diff(m) > 1))


def _count_runs(kind, k):
    m = kind == _K[k]
    return int(np.count_nonzero(m & ~np.r_[False, m[:-1]]))


def entry_hole(job: Job):
    """``(centre (x, y), diameter mm, predrilled)``: the job's start hole, or a hole to bore by a
    helical entry at :attr:`Job.start_center` (diameter 1.8 D, reduced to fit the pocket)."""
    if job.start_hole is not None:
        return (job.start_hole[0], job.start_hole[1]), job.start_hole[2], True
    c = job.start_center
    clear = float(job.polygon.boundary.distance(Point(c)))
    return c, min(1.8 * job.tool_diameter, 2.0 * clear - 0.2), False


def planar_view(path: ToolPath, step_mm: float, z_tol: float = 1e-6):
    """The cutting level of ``path`` as planar samples: ``(points (n, 2), kinds, phase, jump)``.

    The path is resampled every ``step_mm`` (:meth:`ToolPath.resample`); samples at the lowest z
    (cut, link or the end of a descent) are kept; ``kinds`` is cut / roll-in / roll-out / link (from
    the move kind and its tag), ``phase`` the tag's phase, ``jump[i]`` True when sample i is reached
    after leaving the level (a retract-rapid-descent)."""
    P, kinds, phase, jump, _ = _level_samples(path, step_mm, z_tol)
    return P, kinds, phase, jump


def _level_samples(path: ToolPath, step_mm: float, z_tol: float = 1e-6):
    """:func:`planar_view` plus the path's feed (mm/min) at each kept sample."""
    rp, _ = path.resample(step_mm, return_index=True)
    z0 = float(rp.xyz[:, 2].min())
    at = np.flatnonzero(np.abs(rp.xyz[:, 2] - z0) <= z_tol)
    if at.size < 2:
        raise ValueError("the path has fewer than 2 points at its cutting level")
    names = rp.kinds()[at]
    tags = rp.tag[at]
    phase = np.array([str(t).split(":")[0] for t in tags], dtype=object)
    roll = np.array([str(t).split(":")[1] if ":" in str(t) else "" for t in tags], dtype=object)
    kinds = np.where(names == "link", "link", np.where(roll != "", roll, "cut")).astype(object)
    kinds[names == "plunge"] = "link"
    jump = np.r_[False, np.diff(at) > 1]
    return rp.xyz[at, :2], kinds, phase, jump, rp.feed[at]


def _cutting_level(path: ToolPath, job: Job, resolution_mm, feed_control, block_mm, margin_deg,
                   link_tol_mm2, mrr_window_mm):
    """The Thesis IV cutting-level model (module docstring): ``(table, summary, extra_time_s)``."""
    P, kinds_p, phase_p, jump, feed_p = _level_samples(path, resolution_mm)
    centre, hole_d, _ = entry_hole(job)
    stock = dixel.Stock.from_polygon(job.polygon.difference(Point(centre).buffer(0.5 * hole_d, 256)), resolution_mm)
    T = simulate_runs(stock, P, jump, job.tool_radius, job.a_p, job.feed_mm_min, f_z=job.f_z, teeth=job.teeth)
    idx = T.point.to_numpy()
    # the descent after a jump is a link
    T["kind"] = np.where(T.plunge.to_numpy() & (idx > 0), "link", kinds_p[idx])
    T["phase"] = phase_p[idx]
    kinds = T.kind.to_numpy()
    rem = T.removed_mm2.to_numpy()
    T["link_cuts"] = (kinds == "link") & (rem > link_tol_mm2)
    cut = (kinds != "link") | T.link_cuts.to_numpy()
    feed, link_feed = job.feed_mm_min, job.link_feed_mm_min
    v = np.where(cut, feed, link_feed)
    if feed_control:
        adj = np.isin(kinds, ("roll-in", "roll-out"))
        vc = controlled_feed(rem, T.ds.to_numpy(), T.engagement_deg.to_numpy(), cut, job.a_e, feed,
                             job.v_fmax, job.theta_deg, block_mm, margin_deg, adjust=adj)
        v = np.where(cut, vc, link_feed)
    T["feed_mm_min"] = v
    ds = T.ds.to_numpy()
    with np.errstate(divide="ignore", invalid="ignore"):
        T["mrr_ctrl_mm3_min"] = np.where(ds > 0, job.a_p * rem / ds * v, np.nan)
    eng = T.engagement_deg.to_numpy()
    time_s = 60.0 * float(np.sum(ds / v))
    # the written program runs these steps at the path's feed: the difference is the program's change
    fp = feed_p[idx]
    ok = np.isfinite(fp) & (fp > 0) & (ds > 0)
    extra_s = 60.0 * float(np.sum(ds[ok] / v[ok] - ds[ok] / fp[ok]))
    Lc = float(ds[cut].sum())
    lim = job.theta_deg + margin_deg
    summary = {"strategy": path.info.get("name", ""), "engagement_max_deg": float(np.nanmax(eng[cut])),
               "share_above_theta_plus5": float(ds[cut & (eng > lim)].sum()) / Lc,
               "cut_length_mm": Lc, "link_length_mm": float(ds[~cut].sum()),
               "rapid_length_mm": path.lengths()["rapid_mm"],
               "link_cutting_length_mm": float(ds[T.link_cuts.to_numpy()].sum()),
               "link_removed_mm3": job.a_p * float(rem[kinds == "link"].sum())}
    for k in SEGMENT_KINDS:
        m = kinds == k
        Lk = float(ds[m].sum())
        summary[f"length_{k}_mm"] = Lk
        summary[f"engagement_max_{k}_deg"] = float(np.nanmax(eng[m])) if np.isfinite(eng[m]).any() else float("nan")
        summary[f"share_above_{k}"] = float(ds[m & (eng > lim)].sum()) / Lk if Lk > 0 else float("nan")
    reach = job.allowed().buffer(job.tool_radius, 64)
    summary.update({"time_s": time_s, "uncut_area_mm2": stock.area(),
                    "unreachable_area_mm2": float(job.polygon.difference(reach).area),
                    "removed_volume_mm3": job.a_p * float(rem.sum()),
                    "t_min_s": 60.0 * job.volume_mm3() / job.mrr_nominal()})
    summary["time_over_min"] = summary["time_s"] / summary["t_min_s"]
    err = mrr_error_windowed(rem, ds, v, job.a_p, job.mrr_nominal(), kinds == "cut", mrr_window_mm)
    summary["mrr_error_cut_pct"] = err["mean_abs_pct"]
    summary["mrr_error_cut_p95_pct"] = err["p95_abs_pct"]
    return T, summary, extra_s


def evaluate(path: ToolPath, job: Job, resolution_mm: float = 0.05, air_tol_mm2: float | None = None,
             mrr_window_mm: float = 1.0, feed_control: bool | None = None, block_mm: float = 0.5,
             margin_deg: float = 5.0, link_tol_mm2: float = 1e-3, level_only: bool = False,
             sampling: str = "vertices", machine: Machine | None = SMALL_VMC) -> Evaluation:
    """Cut ``path`` through a fresh stock of ``job`` (level by level) and measure it.

    Parameters
    ----------
    path : the tool path (tool reference point = the flat end mill's tip centre, mm).
    job : the pocket and cutting data (``job.tool_radius``, levels, ``rapid_mm_min``, theta).
    resolution_mm : dixel row height and path sampling step (mm).
    air_tol_mm2 : a sample removing at most this area (mm^2) removes nothing (default 0.5 h^2).
    mrr_window_mm : MRR is averaged over windows of this cutting length (mm) before its maximum is
        taken (single dixel steps are noisy by +-h / ds).
    feed_control : None: no cutting-level model; True / False: the Thesis IV cutting-level model
        with / without the roll-in/roll-out feed control (module docstring): fills
        ``time_feed_controlled_s``, ``mrr_error_cut_pct``, ``mrr_error_cut_p95_pct`` and
        ``trace["level"]`` (per-step table), ``trace["level_summary"]`` (dict).
    block_mm, margin_deg : feed-control block length (mm) and engagement margin over theta (deg).
    link_tol_mm2 : a link step removing more than this (mm^2) cuts (runs at the cutting feed).
    level_only : with ``feed_control`` set, skip the level-by-level slab simulation (its float
        fields are NaN and its counts of plunges/rapids into material -1, "not simulated"; lengths,
        times and the cutting-level figures are filled): for planners that only need the latter.
    sampling : 'vertices' (default: every move end is a sample, moves split into steps <= h,
        :meth:`ToolPath.resample`) or 'arc_length' (:func:`resample_by_length`: equal steps of at
        most h between corners, whatever the block length -- what ``cnclab analyze`` uses for
        programs of unknown block length).
    machine : the machine model of ``time_machine_s`` (:mod:`cnclab.toolpath.motion`); None: NaN.

    Returns an :class:`Evaluation`; besides the metrics it holds the wall gouge
    (:func:`wall_gouge`: ``wall_gouge_max_mm``, ``wall_gouge_area_mm2``, ``gouges`` = gouging
    moves) and :attr:`Evaluation.events` (rapids and plunges into material, wall gouges: one row per
    move with its program line when ``path.info["line"]`` is set). ``trace`` holds per sample
    ``move`` (the path point index), ``line`` (with ``path.info["line"]``) and ``gouge_mm``.
    """
    h = _checked(path, resolution_mm, mrr_window_mm)
    level = None
    if feed_control is not None:
        level = _cutting_level(path, job, h, bool(feed_control), block_mm, margin_deg, link_tol_mm2, mrr_window_mm)
    elif level_only:
        raise ValueError("level_only needs feed_control=True or False")
    if level_only:
        return _level_evaluation(path, job, h, level, machine)
    return _measured(path, job, h, air_tol_mm2, mrr_window_mm, sampling, machine, level, True)


def evaluate_engagement(path: ToolPath, job: Job, resolution_mm: float = 0.05) -> Evaluation:
    """:func:`evaluate` (default options, no machine model) without the wall gouge and the uncut area
    beyond the unreachable corners: ``wall_gouge_max_mm``, ``wall_gouge_area_mm2`` and
    ``uncut_beyond_unreachable_mm2`` are NaN, ``gouges`` -1, no gouge events (rapids outside the
    allowed region still count). For a caller that reads only the engagement: the adaptive planner's
    check of its promise (``plan`` measures gouge and uncut area on its own). Units as
    :func:`evaluate`'s."""
    h = _checked(path, resolution_mm, 1.0)
    return _measured(path, job, h, None, 1.0, "vertices", None, None, False)


def _checked(path, resolution_mm, mrr_window_mm) -> float:
    """The evaluator's argument checks; returns the resolution (mm) as float."""
    if not isinstance(path, ToolPath):
        raise TypeError(f"path must be a ToolPath, got {type(path).__name__}")
    h = float(resolution_mm)
    if not (math.isfinite(h) and h > 0):
        raise ValueError(f"resolution_mm must be a finite number > 0 mm, got {resolution_mm!r}")
    if not mrr_window_mm > 0:
        raise ValueError(f"mrr_window_mm must be > 0 mm, got {mrr_window_mm!r}")
    if len(path) < 2:
        raise ValueError(f"{path.info.get('source', 'path')}: the path has {len(path)} point(s), at least 2 are "
                         "needed (an empty or comment-only program?)")
    return h


def _measured(path, job, h, air_tol_mm2, mrr_window_mm, sampling, machine, level, uncut_and_gouge) -> Evaluation:
    """The slab simulation and every measure of :func:`evaluate` (``level``: its cutting-level model
    or None); without ``uncut_and_gouge`` as :func:`evaluate_engagement`."""
    air = 0.5 * h * h if air_tol_mm2 is None else float(air_tol_mm2)
    r = job.tool_radius
    rp, src = _samples(path, h, sampling)
    P, K = rp.xyz, rp.kind
    L3 = rp.segment_lengths()
    dxy = np.r_[0.0, np.hypot(*np.diff(P[:, :2], axis=0).T)]
    feed = rp.feed
    # descending moves that are not helix/ramp entries (plunge-like), per sample
    dz_move = np.r_[0.0, np.diff(path.xyz[:, 2])]
    plunge_like_move = (dz_move < -1e-9) & ~path.is_kind("helix", "ramp")
    plunge_like = plunge_like_move[src]
    eng, removed, vol, stocks = _simulate_slabs(P, dxy, job, h)

    cutting = np.isin(K, [_K["cut"], _K["link"]]) & (removed > air) & (dxy > 0)
    entry = np.isin(K, [_K["helix"], _K["ramp"], _K["plunge"]])
    rapid = K == _K["rapid"]
    mrr_max = _mrr_max(cutting, dxy, feed, vol, mrr_window_mm, job.mrr_nominal())
    lines = np.asarray(path.info["line"], int) if len(path.info.get("line", ())) == len(path) else None
    # plunges / rapids into material, per original move
    pl = plunge_like & (K != _K["rapid"]) & (removed > air)
    rp_bad, gouge, g_area, g_mask, events = _material_events(P, src, lines, job, rapid, pl, removed, air,
                                                             uncut_and_gouge)
    air_cut = (K == _K["cut"]) & (removed <= air)
    lengths = path.lengths()
    times = path.time_s(job.rapid_mm_min)
    unreach = unreachable_region(job.polygon, r) if uncut_and_gouge else None
    uncut = float(sum(st.area() for st in stocks))
    beyond = float("nan")
    if uncut_and_gouge:
        beyond = float(sum(st.to_polygon().difference(unreach).area for st in stocks)) if uncut > 0 else 0.0
    trace = {"s_mm": np.cumsum(L3), "x": P[:, 0].copy(), "y": P[:, 1].copy(), "z": P[:, 2].copy(),
             "engagement_deg": eng, "removed_mm2": removed,
             "mrr_mm3_min": np.where((dxy > 0) & ~rapid, vol / np.where(dxy > 0, dxy, 1.0) * np.nan_to_num(feed), np.nan),
             "feed_mm_min": feed.copy(), "kind": rp.kinds(), "tag": rp.tag.copy(), "ds_mm": dxy, "cutting": cutting,
             "gouge_mm": gouge, "move": src.copy()}
    if lines is not None:
        trace["line"] = lines[src]
    return Evaluation(
        **_engagement_fields(eng, dxy, cutting, entry, job.theta_deg),
        mrr_max_over_nominal=mrr_max,
        entries_helix=_count_runs(path.kind, "helix"), entries_ramp=_count_runs(path.kind, "ramp"),
        entries_plunge=_count_runs(path.kind, "plunge"),
        plunges_into_material=_move_runs(src[pl]), plunge_swept_area_mm2=float(removed[pl].sum()),
        rapids_into_material=_move_runs(src[rp_bad]), retracts=_count_runs(path.kind, "retract"),
        cut_length_mm=lengths["cut_mm"], link_length_mm=lengths["link_mm"], rapid_length_mm=lengths["rapid_mm"],
        entry_length_mm=lengths["helix_mm"] + lengths["ramp_mm"] + lengths["plunge_mm"],
        retract_length_mm=lengths["retract_mm"], air_cut_length_mm=float(L3[air_cut].sum()),
        uncut_area_mm2=uncut, uncut_beyond_unreachable_mm2=beyond,
        time_cut_s=times["cut_s"], time_link_s=times["link_s"], time_rapid_s=times["rapid_s"],
        time_entry_s=times["helix_s"] + times["ramp_s"] + times["plunge_s"], time_retract_s=times["retract_s"],
        time_total_s=times["total_s"], theta_deg=float(job.theta_deg), resolution_mm=h,
        time_machine_s=_machine_s(path, machine),
        wall_gouge_max_mm=float(gouge.max(initial=0.0)) if uncut_and_gouge else float("nan"), wall_gouge_area_mm2=g_area,
        gouges=len(_runs(g_mask)) if uncut_and_gouge else -1, events=events,
        **_level_fields(times, level, trace))


def _engagement_fields(eng, dxy, cutting, entry, theta_deg) -> dict:
    """The engagement fields of :func:`evaluate` (deg; shares in % of the cutting length ``dxy`` (mm)
    of the ``cutting`` samples above theta + 5 / + 15 deg; the maximum over the ``entry`` samples)."""
    Lc = float(dxy[cutting].sum())
    e_c = eng[cutting]
    lim5, lim15 = theta_deg + 5.0, theta_deg + 15.0
    share5 = 100.0 * float(dxy[cutting & (eng > lim5)].sum()) / Lc if Lc > 0 else float("nan")
    share15 = 100.0 * float(dxy[cutting & (eng > lim15)].sum()) / Lc if Lc > 0 else float("nan")
    e_entry = eng[entry]
    return dict(
        engagement_p50_deg=weighted_percentile(e_c, dxy[cutting], 50),
        engagement_p95_deg=weighted_percentile(e_c, dxy[cutting], 95),
        engagement_max_deg=float(np.nanmax(e_c)) if np.isfinite(e_c).any() else float("nan"),
        share_above_5_pct=share5, share_above_15_pct=share15,
        entry_engagement_max_deg=float(np.nanmax(e_entry)) if np.isfinite(e_entry).any() else float("nan"))


def _mrr_max(cutting, dxy, feed, vol, mrr_window_mm: float, mrr_nominal: float) -> float:
    """Windowed MRR over the cutting samples (volume / time in windows of ``mrr_window_mm`` of cutting
    length, windows at least half full) over ``mrr_nominal`` (mm^3/min): its maximum (NaN if none)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        dt_min = np.where(cutting, dxy / feed, 0.0)
    s_cut = np.cumsum(np.where(cutting, dxy, 0.0))
    win = np.floor(s_cut / mrr_window_mm).astype(int)
    V = np.bincount(win[cutting], weights=vol[cutting])
    T = np.bincount(win[cutting], weights=dt_min[cutting])
    Lw = np.bincount(win[cutting], weights=dxy[cutting])
    full = (Lw >= 0.5 * mrr_window_mm) & (T > 0)
    return float((V[full] / T[full]).max() / mrr_nominal) if full.any() else float("nan")


def _material_events(P, src, lines, job: Job, rapid, pl, removed, air: float, gouge_too: bool = True):
    """Rapids into material or below the top outside the allowed region (``rp_bad`` per sample), the
    wall gouge (:func:`wall_gouge`; NaN, no gouging sample, when not ``gouge_too``) and the events table of
    the plunges ``pl`` / rapids / gouges: ``(rp_bad, gouge, g_area, g_mask, events)``."""
    guard = job.allowed().buffer(POSITION_TOL_MM)
    low = rapid & (P[:, 2] < job.top_z - 1e-9)
    outside = np.zeros(len(P), bool)
    if low.any():
        outside[low] = ~shapely.contains_xy(guard, P[low, 0], P[low, 1])
    rp_bad = rapid & ((removed > air) | outside)
    if gouge_too:
        gouge, g_area, g_mask = wall_gouge(P, job, rapid=rapid)
    else:
        gouge, g_area, g_mask = np.full(len(P), np.nan), float("nan"), np.zeros(len(P), bool)
    events = _events(P, src, lines, [("rapid into material", rp_bad, removed, "mm^2"),
                                     ("plunge into material", pl, removed, "mm^2"),
                                     ("wall gouge", g_mask, gouge, "mm")])
    return rp_bad, gouge, g_area, g_mask, events


def _samples(path: ToolPath, h: float, sampling: str):
    """The evaluator's samples ``(path, move index)``: see ``sampling`` in :func:`evaluate`."""
    if sampling == "arc_length":
        return resample_by_length(path, h)
    if sampling == "vertices":
        return path.resample(h, return_index=True)
    raise ValueError(f"sampling must be 'vertices' or 'arc_length', got {sampling!r}")


def _simulate_slabs(P, dxy, job: Job, h: float):
    """Cut the samples ``P`` (n, 3) through the job's slabs (module docstring): per sample the
    engagement (deg, max over slabs), removed area (mm^2, summed) and volume (mm^3), and the stocks."""
    n, r = len(P), job.tool_radius
    levels = job.levels()
    tops = [job.top_z] + levels[:-1]
    material = job.polygon.difference(job.start_hole_polygon())
    eng = np.full(n, np.nan)
    removed = np.zeros(n)          # area summed over slabs (mm^2)
    vol = np.zeros(n)              # volume (mm^3)
    stocks = []
    for top, bot in zip(tops, levels):
        stock = dixel.Stock.from_polygon(material, h)
        # a tip less than POSITION_TOL_MM below the slab's top has not entered it: a level's z as a
        # program writes it (-2.4917 for -2.491667) is up to half a last digit below the level, and
        # the slab under it would otherwise be cut 33 nm deep at full width (read as 180 deg)
        inside = np.flatnonzero(P[:, 2] < top - POSITION_TOL_MM)
        thick = top - np.maximum(P[:, 2], bot)
        if inside.size:
            brk = np.r_[True, np.diff(inside) > 1]
            starts = np.flatnonzero(brk)
            stops = np.r_[starts[1:], inside.size]
            for a, b in zip(starts, stops):
                idx = inside[a:b]
                keep = np.r_[True, dxy[idx[1:]] > 1e-12]
                idx = idx[keep]
                if len(idx) == 1:
                    rem = np.array([stock.cut_disk(P[idx[0], :2], r)])
                    e = np.array([np.nan])
                else:
                    df = simulate(stock, P[idx, :2], r, 1.0, 1.0, lag_rule="front")
                    rem = df.removed_mm2.to_numpy()
                    e = df.engagement_deg.to_numpy().copy()
                    e[0] = np.nan                     # no feed direction from behind at the run start
                removed[idx] += rem
                vol[idx] += rem * thick[idx]
                eng[idx] = np.fmax(eng[idx], np.where(rem > 0, e, np.nan))
        stocks.append(stock)
    return eng, removed, vol, stocks


def wall_gouge(P, job: Job, rapid=None, tol_mm: float = POSITION_TOL_MM):
    """How far the tool disc reaches into the walls and islands (outside ``job.polygon``).

    ``P`` (n, 3) mm: tool-tip centre samples (e.g. the evaluator's, every ``resolution_mm``); only
    samples below the stock top ``job.top_z`` count. Returns ``(gouge (n,) mm, area mm^2, mask (n,))``:
    ``gouge = max(0, r - d)`` with ``d`` the signed distance of the centre to the pocket boundary
    (negative outside); ``area`` the plan-view wall/island area swept by the tool disc along the runs
    of samples gouging more than ``tol_mm`` (union over levels; the tool disc as a 64-segment
    quarter-circle polygon); ``mask`` those samples. ``rapid`` (n,) bool: samples of rapid moves,
    counted as "rapid into material" instead (their gouge is still reported). Samples inside the
    tool-centre region :meth:`Job.allowed` gouge 0 (up to its 64-segment approximation, < 1e-3 mm
    for r <= 10 mm) and skip the distance computation.

    >>> from shapely.geometry import box
    >>> from cnclab.toolpath.path import Tool
    >>> jb = Job(box(0, 0, 40, 20), Tool(6.0), 60.0, 2.0, feed_mm_min=300, spindle_rpm=5000)
    >>> g, area, m = wall_gouge(np.array([[20, 10, -1.0], [38, 10, -1], [38, 10, 5]]), jb)
    >>> g.tolist(), round(area, 2)     # centre 2 mm from the x = 40 wall, r = 3: 1 mm deep; above: 0
    ([0.0, 1.0, 0.0], 3.1)

    (the area: the circular segment of depth 1 of the r = 3 disc, 9 acos(2/3) - 2 sqrt(5) = 3.098 mm^2)
    """
    P = np.asarray(P, float)
    r = job.tool_radius
    gouge = np.maximum(0.0, -wall_clearance(job.polygon, r, P, job.top_z, clear=job.allowed()))
    mask = gouge > tol_mm
    if rapid is not None:
        mask &= ~np.asarray(rapid, bool)
    area = 0.0
    if mask.any():
        discs = [shapely.LineString(P[a:b, :2]).buffer(r, 64) if b - a > 1 else shapely.Point(P[a, :2]).buffer(r, 64)
                 for a, b in _runs(mask)]
        area = float(shapely.union_all(discs).difference(job.polygon).area)
    return gouge, area, mask


def _events(P, src, lines, kinds) -> pd.DataFrame:
    """One row per (event kind, run of consecutive samples of one move): the sample with the largest
    value (area mm^2 or depth mm), its move and program line."""
    rows = []
    for name, mask, value, unit in kinds:
        for a, b in _runs(mask):
            for m in np.unique(src[a:b]):
                seg = a + np.flatnonzero(src[a:b] == m)
                k = seg[np.argmax(value[seg])]
                rows.append((name, int(m), int(lines[m]) if lines is not None else -1, float(P[k, 0]),
                             float(P[k, 1]), float(P[k, 2]), float(value[k]), unit))
    rows.sort(key=lambda row: (row[1], row[0]))
    return _events_frame(rows)


def resample_by_length(path: ToolPath, step_mm: float, corner_tol: float | None = None):
    """The path sampled by arc length: ``(path, index)`` like :meth:`ToolPath.resample` with
    ``return_index``, but independent of how the program splits it into blocks.

    The path is cut into runs of one move kind; each run is split at its corners and sampled with
    equal steps of at most ``step_mm`` mm between them. A corner is a vertex farther than
    ``corner_tol`` (default ``step_mm / 10``) from the chord between the path points ``step_mm / 2``
    before and after it (arc length), so a line written as 1 or as 100 collinear blocks, or an arc as
    one G2 or as many chords, gives the same samples (up to the chords' sagitta) — while
    :meth:`ToolPath.resample` keeps every block end, so blocks shorter than the step would give
    steps shorter than the dixel resolution. Arcs are first tessellated with chords <= ``step_mm``
    and of sagitta <= :data:`ARC_SAGITTA_MM`.
    ``index`` is the move of each sample (the move whose span holds its arc length).

    >>> p = ToolPath.build([[0, 0, 0], [0.3, 0, 0], [0.31, 0, 0], [1, 0, 0]], feed=100)
    >>> q, i = resample_by_length(p, 0.25)
    >>> q.xyz[:, 0].round(3).tolist(), i.tolist()
    ([0.0, 0.25, 0.5, 0.75, 1.0], [0, 1, 3, 3, 3])
    """
    h = float(step_mm)
    if not (math.isfinite(h) and h > 0):
        raise ValueError(f"step_mm must be a finite number > 0 mm, got {step_mm!r}")
    tol = 0.1 * h if corner_tol is None else float(corner_tol)
    Q, qsrc = path.polyline(h, max_sagitta=ARC_SAGITTA_MM)
    keep = np.r_[True, np.any(np.diff(Q, axis=0) != 0, axis=1)]
    kind = path.kind[qsrc]
    keep |= np.r_[True, kind[1:] != kind[:-1]]          # a kind change is kept even without length
    Q, qsrc, kind = Q[keep], qsrc[keep], kind[keep]
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(Q, axis=0), axis=1))]
    # runs of one kind: vertex j starts a new run when the segment ending at j has another kind than
    # the one before; run boundaries and corners are breakpoints
    seg_kind = kind[1:]
    brk = np.zeros(len(Q), bool)
    brk[0] = brk[-1] = True
    brk[1:-1] = seg_kind[1:] != seg_kind[:-1]
    bidx = np.flatnonzero(brk)
    lo_s = s[bidx[np.searchsorted(bidx, np.arange(len(Q)), side="right") - 1]]
    hi_s = s[bidx[np.minimum(np.searchsorted(bidx, np.arange(len(Q)), side="left"), len(bidx) - 1)]]
    inner = ~brk
    if inner.any():
        a_s = np.maximum(s - 0.5 * h, lo_s)[inner]
        b_s = np.minimum(s + 0.5 * h, hi_s)[inner]
        A = np.column_stack([np.interp(a_s, s, Q[:, c]) for c in range(3)])
        B = np.column_stack([np.interp(b_s, s, Q[:, c]) for c in range(3)])
        V = Q[inner]
        AB = B - A
        L2 = np.einsum("ij,ij->i", AB, AB)
        t = np.clip(np.einsum("ij,ij->i", V - A, AB) / np.where(L2 > 0, L2, 1.0), 0.0, 1.0)
        dev = np.linalg.norm(A + t[:, None] * AB - V, axis=1)
        brk[np.flatnonzero(inner)[dev > tol]] = True
    bidx = np.flatnonzero(brk)
    out_s, out_src = [s[:1]], [qsrc[:1]]
    for a, b in zip(bidx[:-1], bidx[1:]):
        L = s[b] - s[a]
        if L <= 0:
            if qsrc[b] != qsrc[a]:              # zero-length kind change: keep the vertex
                out_s.append(s[b:b + 1]); out_src.append(qsrc[b:b + 1])
            continue
        m = max(1, int(math.ceil(L / h - 1e-9)))
        ss = s[a] + L * np.arange(1, m + 1) / m
        ss[-1] = s[b]
        j = np.clip(np.searchsorted(s, ss, side="left"), a + 1, b)
        out_s.append(ss); out_src.append(qsrc[j])
    S, I = np.concatenate(out_s), np.concatenate(out_src)
    X = np.column_stack([np.interp(S, s, Q[:, c]) for c in range(3)])
    out = ToolPath(X, path.kind[I], path.tag[I], path.feed[I], path.spindle[I], None, None, path.tool,
                   dict(path.info), path.cleared[I])
    return out, I


def _level_fields(times, level, trace) -> dict:
    """The feed-control fields of :class:`Evaluation` (NaN without the level model) and the trace."""
    if level is None:
        return {"trace": trace}
    T, summary, extra_s = level
    trace = dict(trace, level=T, level_summary=summary)
    return {"time_feed_controlled_s": times["total_s"] + extra_s, "mrr_error_cut_pct": summary["mrr_error_cut_pct"],
            "mrr_error_cut_p95_pct": summary["mrr_error_cut_p95_pct"], "trace": trace}


def _machine_s(path: ToolPath, machine: Machine | None) -> float:
    """``time_machine_s`` of the path on ``machine`` (NaN without one)."""
    return float("nan") if machine is None else path_machine_time(path, machine)


def _level_evaluation(path: ToolPath, job: Job, h: float, level, machine: Machine | None = SMALL_VMC) -> Evaluation:
    """An :class:`Evaluation` with only the path's lengths/times and the cutting-level figures."""
    nan = float("nan")
    lengths, times = path.lengths(), path.time_s(job.rapid_mm_min)
    T, summary, _ = level
    return Evaluation(
        engagement_p50_deg=nan, engagement_p95_deg=nan, engagement_max_deg=summary["engagement_max_deg"],
        share_above_5_pct=100.0 * summary["share_above_theta_plus5"], share_above_15_pct=nan,
        entry_engagement_max_deg=nan, mrr_max_over_nominal=nan,
        entries_helix=_count_runs(path.kind, "helix"), entries_ramp=_count_runs(path.kind, "ramp"),
        entries_plunge=_count_runs(path.kind, "plunge"), plunges_into_material=-1, plunge_swept_area_mm2=nan,
        rapids_into_material=-1, retracts=_count_runs(path.kind, "retract"),
        cut_length_mm=lengths["cut_mm"], link_length_mm=lengths["link_mm"], rapid_length_mm=lengths["rapid_mm"],
        entry_length_mm=lengths["helix_mm"] + lengths["ramp_mm"] + lengths["plunge_mm"],
        retract_length_mm=lengths["retract_mm"], air_cut_length_mm=nan,
        uncut_area_mm2=summary["uncut_area_mm2"],
        uncut_beyond_unreachable_mm2=summary["uncut_area_mm2"] - summary["unreachable_area_mm2"],
        time_cut_s=times["cut_s"], time_link_s=times["link_s"], time_rapid_s=times["rapid_s"],
        time_entry_s=times["helix_s"] + times["ramp_s"] + times["plunge_s"], time_retract_s=times["retract_s"],
        time_total_s=times["total_s"], theta_deg=float(job.theta_deg), resolution_mm=h,
        time_machine_s=_machine_s(path, machine), **_level_fields(times, level, {}))
