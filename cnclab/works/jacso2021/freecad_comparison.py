"""Constant-engagement clearing against FreeCAD Path Adaptive on every pocket of issue 16 (beyond the booklet).

Every path -- the planners of :data:`cnclab.toolpath.planners.STRATEGIES` and FreeCAD Adaptive's
programs read back from their G-code (:func:`cnclab.nc.gcode.read_toolpath`) -- is scored by the one
evaluator (:func:`cnclab.toolpath.evaluate.evaluate`) on the pocket's job file
(:func:`cnclab.toolpath.job.load_job`): same polygon, tool, engagement theta and feeds.
FreeCAD's programs are the committed ``tests/fixtures/freecad/<pocket>.ngc`` (written by
``benchmarks/freecad_adaptive.py``: libarea ``Adaptive2d`` + FreeCAD's G-code generation and
``linuxcnc`` post, StepOver = a_e / D with a_e = r (1 - cos theta)); their plan time is the one
recorded in ``<pocket>.json`` when they were made (``benchmarks/bench_vs_freecad.py`` re-runs FreeCAD
live when it is installed, for ratios measured in one run).

Columns of a table row (:data:`COLUMNS`; units in the names): engagement p95 / max over cutting moves
(deg), shares of the cutting length above theta + 5 / + 15 deg (%), entry engagement max (deg,
helices/ramps/plunges, reported apart), retracts (the evaluator's: feed moves of kind ``retract``),
lifts (:func:`lifts`: every rise from below the stock top to above it, G0 or G1 -- FreeCAD lifts by
G0, which the evaluator's count does not see), plunges and rapids into material (counts),
uncut area beyond the unreachable corners (mm^2), program time (min: the written program's
motion model, rapids at the job's rapid rate), machine time (min: the same path on the small-VMC
model of :mod:`cnclab.toolpath.motion`, acceleration and corners, ``Evaluation.time_machine_s``;
both programs timed as paths, FreeCAD's as written, ours unfitted: see :mod:`cnclab.toolpath.evaluate`),
plan time (s, wall clock: noisy on a shared CPU) and
the wall gouge (mm, :func:`wall_gouge_mm`: how far the tool disc reaches into a wall or island
below the stock top -- the evaluator's stock is the pocket only, so it cannot see such a cut).

Jacsó §4 feed control for any tool path (:func:`feed_controlled`): the evaluator's trace gives the
removal width per sample; :func:`cnclab.cutting.feed_control.controlled_feed` sets the feed per
0.5 mm block so that MRR = nominal (capped at the job's ``v_fmax``, nominal where the block's mean
engagement is within 5 deg of theta); the result is the same geometry with those feeds, a
ToolPath whose own program time is reported.

Units: mm, deg, mm/min, s (min in the table's time column). Nothing here is a ledger claim.

>>> sorted(POCKETS)[:3]
['L', 'kim_yang_120x85', 'rectangle']
"""
from __future__ import annotations

import json
import math
import time
from pathlib import Path

import numpy as np
import pandas as pd
from shapely.geometry import box

from ...cutting.feed_control import controlled_feed
from ...nc.gcode import read_toolpath
from ...nc.program import program_path, write_program
from ...paths import REPO_ROOT
from ...runtime import pick
from ...toolpath import planners
from ...toolpath.evaluate import Evaluation, evaluate, wall_gouge
from ...toolpath.job import Job, load_job
from ...toolpath.motion import path_machine_time
from ...toolpath.path import KINDS, Tool, ToolPath

__all__ = ["POCKETS", "FIXTURES", "COLUMNS", "PLANNER_ROWS", "FREECAD", "job", "resolution_mm",
           "freecad_path", "freecad_plan_time_s", "plan_timed", "feed_controlled", "wall_gouge_mm", "lifts", "row",
           "comparison", "ratios", "warm_planners", "summary", "engagement_targets", "meets_bounds", "as_written"]

#: the pockets of the comparison: name -> job file (relative to the repository)
POCKETS = {
    "star": "data/jacso2021/star_pocket.json",
    "rectangle": "data/jacso2021/rectangle_pocket.json",
    "L": "data/jacso2021/l_pocket.json",
    "kim_yang_120x85": "data/kim_yang2006/pocket_120x85.json",
    "two_islands_neck": "data/pockets/two_islands_neck.json",
    "spline": "data/pockets/spline_pocket.json",
    "slot": "data/pockets/long_slot.json",
    "two_regions": "data/pockets/two_regions.json",
}
#: the committed FreeCAD Adaptive programs (<pocket>.ngc) and their provenance (<pocket>.json)
FIXTURES = REPO_ROOT / "tests" / "fixtures" / "freecad"
FREECAD = "FreeCAD Adaptive"
#: planner rows: label -> strategy of cnclab.toolpath.planners.STRATEGIES
PLANNER_ROWS = {"adaptive_clearing": "adaptive", "ce_clearing (old)": "constant-engagement"}
FEED_CONTROL_SUFFIX = " + §4 feed control"
#: the table's columns: the :class:`~cnclab.toolpath.evaluate.Evaluation` names where the value is one
COLUMNS = ["engagement_p95_deg", "engagement_max_deg", "share_above_5_pct", "share_above_15_pct",
           "entry_engagement_max_deg", "retracts", "lifts",
           "plunges_into_material", "rapids_into_material", "uncut_beyond_mm2", "program_time_min",
           "machine_time_min", "plan_time_s", "wall_gouge_mm"]
_CUT = KINDS.index("cut")


def job(name: str) -> Job:
    """The job of pocket ``name`` (a key of :data:`POCKETS`), read by the package's one loader."""
    if name not in POCKETS:
        raise ValueError(f"pocket must be one of {sorted(POCKETS)}, got {name!r}")
    return load_job(REPO_ROOT / POCKETS[name])


def resolution_mm(name: str, fast: bool | None = None) -> float:
    """Evaluation dixel (mm): 0.05 (0.1 for the 120 x 85 pocket, 4x the area of the others); fast mode
    (or ``fast=True``) doubles it. The planners that take a resolution plan at the same value."""
    full = 0.1 if name == "kim_yang_120x85" else 0.05
    if fast is None:
        return pick(full, 2 * full)
    return 2 * full if fast else full


def as_written(path: ToolPath, jb: Job) -> ToolPath:
    """``path`` as the program a machine runs: written by :func:`cnclab.nc.program.write_program`
    (arcs fitted off the walls, approach and retract at the clearance plane, 4 decimals) and read
    back by the reader of FreeCAD's programs (:func:`cnclab.nc.gcode.read_toolpath`), so that a
    planner's path and a FreeCAD program are scored the same way. ``info["program"]`` holds the
    program text."""
    text = write_program(path, jb)
    out = read_toolpath(text, tool=jb.tool)
    out.info["program"] = text
    return out


def freecad_path(name: str, tool=None, fixtures: Path = FIXTURES) -> ToolPath:
    """FreeCAD Adaptive's committed program of pocket ``name`` as a ToolPath (the package's G-code
    reader); ValueError if the program has no motion (FreeCAD planned nothing for the pocket)."""
    p = read_toolpath(Path(fixtures) / f"{name}.ngc", tool=tool)
    if len(p) < 2 or not np.any(p.xyz[:, 2] < 0.0):
        raise ValueError(f"{Path(fixtures) / (name + '.ngc')}: FreeCAD wrote no cutting motion for this pocket")
    return p


def freecad_plan_time_s(name: str, fixtures: Path = FIXTURES) -> float:
    """Plan time (s) FreeCAD needed when the fixture was made (from ``<pocket>.json``)."""
    prov = json.loads((Path(fixtures) / f"{name}.json").read_text(encoding="utf-8"))
    return float(prov["plan_time_s"])


def plan_timed(jb: Job, strategy: str, res_mm: float) -> tuple:
    """``(ToolPath, wall seconds)`` of :func:`cnclab.toolpath.planners.plan` (``res_mm``: the
    planner's dixel where it takes one)."""
    t0 = time.perf_counter()
    tp = planners.plan(jb, strategy, res_mm, written=program_path)
    return tp, time.perf_counter() - t0


def warm_planners(strategies) -> None:
    """Plan a small pocket once with each strategy (untimed): the compiled kernels are loaded from the
    numba cache, or compiled, before :func:`plan_timed` measures anything."""
    # an island and a pre-drilled hole: every entry, link and finishing path is taken once
    jb = Job(box(0, 0, 30, 20).difference(box(14, 8, 18, 12)), Tool(6.0), 60.0, 1.0, feed_mm_min=255.0,
             spindle_rpm=6366.0, start_hole=(5.0, 10.0, 4.0))
    for strategy in strategies:
        try:
            planners.plan(jb, strategy, 0.1)
        except ValueError:
            pass


def summary(tables: dict) -> pd.DataFrame:
    """One row per pocket: the first planner row against FreeCAD's (plan and program time and their
    ratios, max engagement, share above theta + 5 deg, uncut area, lifts, plunges and rapids into
    material)."""
    out = {}
    for name, T in tables.items():
        a, f = T.iloc[0], T.loc[FREECAD]
        out[name] = {"plan_s": a["plan_time_s"], "plan_s FC": f["plan_time_s"],
                     "plan ratio": a["plan_time_s"] / f["plan_time_s"],
                     "program_min": a["program_time_min"], "program_min FC": f["program_time_min"],
                     "program ratio": a["program_time_min"] / f["program_time_min"],
                     "machine_min": a["machine_time_min"], "machine_min FC": f["machine_time_min"],
                     "machine ratio": a["machine_time_min"] / f["machine_time_min"],
                     "engagement_max_deg": a["engagement_max_deg"], "engagement_max_deg FC": f["engagement_max_deg"],
                     "share>θ+5": a["share_above_5_pct"],
                     "uncut_mm2": a["uncut_beyond_mm2"], "uncut_mm2 FC": f["uncut_beyond_mm2"],
                     "lifts": a["lifts"], "lifts FC": f["lifts"],
                     "plunges+rapids into material": a["plunges_into_material"] + a["rapids_into_material"]}
    return pd.DataFrame(out).T


def feed_controlled(path: ToolPath, jb: Job, ev: Evaluation, block_mm: float = 0.5) -> ToolPath:
    """``path`` resampled as ``ev`` was (``ev.resolution_mm``) with Jacsó §4 engagement-based feeds
    on its cut moves (:func:`cnclab.cutting.feed_control.controlled_feed`: MRR held at a_p a_e v_nom
    per ``block_mm`` block, at most ``jb.v_fmax``; air cuts at ``v_fmax``); other moves keep their
    feed. ``ev`` must be ``evaluate(path, jb, h)``.

    >>> from shapely.geometry import box
    >>> from cnclab.toolpath.path import Tool
    >>> jb = Job(box(0, 0, 40, 20), Tool(6.0), 180.0, 2.0, feed_mm_min=300, spindle_rpm=5000, v_fmax=1000)
    >>> p = ToolPath.build([[-20, 10, -2], [45, 10, -2]], kind=["rapid", "cut"], feed=300)
    >>> q = feed_controlled(p, jb, evaluate(p, jb, 0.1))
    >>> float(np.nanmax(q.feed)), float(np.nanmin(q.feed))     # air at v_fmax, the slot (theta) at nominal
    (1000.0, 300.0)
    """
    rp = path.resample(ev.resolution_mm)
    t = ev.trace
    if len(t["x"]) != len(rp) or not np.allclose(t["x"], rp.xyz[:, 0]):
        raise ValueError("ev is not the evaluation of this path at ev.resolution_mm")
    cut = (rp.kind == _CUT) & (t["ds_mm"] > 0)
    v = controlled_feed(t["removed_mm2"], t["ds_mm"], t["engagement_deg"], cut, jb.a_e, jb.feed_mm_min,
                        jb.v_fmax, jb.theta_deg, block_mm=block_mm)
    feed = np.where(cut, v, rp.feed)
    return ToolPath(rp.xyz, rp.kind, rp.tag, feed, rp.spindle, None, None, rp.tool,
                    dict(rp.info, feed_control="Jacso 2021 §4, cnclab.cutting.feed_control.controlled_feed"))


def wall_gouge_mm(ev: Evaluation, jb: Job) -> float:
    """Deepest reach (mm) of the tool disc into the walls or islands (outside ``jb.polygon``) over the
    evaluated samples below the stock top: the evaluator's ``wall_gouge_max_mm``
    (:func:`cnclab.toolpath.evaluate.wall_gouge`: max(0, r - d), d the signed distance (mm) of the tool
    centre to the pocket boundary, negative outside; 0 for a path that keeps the centre in
    ``jb.allowed()``). ``ev`` must have been evaluated on ``jb``.

    >>> from shapely.geometry import box
    >>> from cnclab.toolpath.path import Tool
    >>> jb = Job(box(0, 0, 40, 20), Tool(6.0), 60.0, 2.0, feed_mm_min=300, spindle_rpm=5000)
    >>> p = ToolPath.build([[5, 10, 5], [5, 10, -2], [38, 10, -2]], kind=["rapid", "plunge", "cut"], feed=300)
    >>> round(wall_gouge_mm(evaluate(p, jb, 0.1), jb), 6)          # centre 2 mm from the x = 40 wall, r = 3
    1.0
    """
    if math.isfinite(ev.wall_gouge_max_mm):
        return float(ev.wall_gouge_max_mm)
    t = ev.trace          # an Evaluation made without the slab simulation: measure its samples
    return float(wall_gouge(np.column_stack([t["x"], t["y"], t["z"]]), jb)[0].max(initial=0.0))


def gouge_points(ev: Evaluation, jb: Job, tol_mm: float = 0.05):
    """x, y (mm) of the evaluated samples whose tool disc reaches more than ``tol_mm`` into a wall or
    island (the mask of :func:`cnclab.toolpath.evaluate.wall_gouge`), e.g. to mark them on a plot.

    >>> from cnclab.toolpath.path import Tool
    >>> jb = Job(box(0, 0, 40, 20), Tool(6.0), 60.0, 2.0, feed_mm_min=300, spindle_rpm=5000)
    >>> p = ToolPath.build([[5, 10, 5], [5, 10, -2], [38, 10, -2]], kind=["rapid", "plunge", "cut"], feed=300)
    >>> x, y = gouge_points(evaluate(p, jb, 0.1), jb)
    >>> float(x.min()) > 37 - 0.05, bool((y == 10).all())    # the samples beyond x = 37 (r = 3)
    (True, True)
    """
    t = ev.trace
    mask = wall_gouge(np.column_stack([t["x"], t["y"], t["z"]]), jb, tol_mm=tol_mm)[2]
    return t["x"][mask], t["y"][mask]


def engagement_targets(engagement_p95_deg, engagement_max_deg, share_above_5_pct, share_above_15_pct, plunges, rapids,
                       gouge_mm, theta_deg, gouge_tol_mm: float = 1e-3) -> dict:
    """The issue-16 targets of one program (deg, %, counts, mm): p95 <= theta + 2, share above
    theta + 5 <= 0.5 %, above theta + 15 <= 0.05 %, max <= theta + 10, no plunge or rapid into
    material, no wall gouge beyond ``gouge_tol_mm`` (1e-3 mm: the finishing snap's tolerance).
    Shared by the comparison notebook (:func:`targets`) and ``benchmarks/bench_random_pockets.py``.

    >>> all(engagement_targets(41, 49, 0.2, 0.0, 0, 0, 0.0, theta_deg=40).values())
    True
    """
    b = _bounds(engagement_p95_deg, engagement_max_deg, share_above_5_pct, theta_deg)
    return {"p95<=θ+2": b["p95"], "share>θ+5<=0.5%": b["share5"],
            "share>θ+15<=0.05%": bool(share_above_15_pct <= 0.05), "max<=θ+10": b["max"],
            "no plunges": bool(plunges == 0), "no rapids in mat.": bool(rapids == 0),
            f"no gouge (<={gouge_tol_mm:g} mm)": bool(gouge_mm <= gouge_tol_mm)}


def _bounds(p95_deg: float, max_deg: float, share_above_5_pct: float, theta_deg: float) -> dict:
    """The three engagement bounds, written once: p95 <= theta + 2, max <= theta + 10 (deg), share
    above theta + 5 <= 0.5 (%)."""
    th = float(theta_deg)
    return {"p95": bool(p95_deg <= th + 2.0), "max": bool(max_deg <= th + 10.0), "share5": bool(share_above_5_pct <= 0.5)}


def meets_bounds(p95_deg: float, max_deg: float, share_above_5_pct: float, theta_deg: float) -> bool:
    """Issue 29's engagement bounds (deg, %): p95 <= theta + 2, max <= theta + 10, share above
    theta + 5 <= 0.5 % (three of :func:`engagement_targets`, without the theta + 15 share and the
    safety counts); the corpus, letter and bounded-FreeCAD tables judge a program by it.

    >>> meets_bounds(61.9, 69.0, 0.4, 60.0), meets_bounds(62.1, 69.0, 0.4, 60.0)
    (True, False)
    """
    return all(_bounds(p95_deg, max_deg, share_above_5_pct, theta_deg).values())


def targets(t: pd.DataFrame, theta_deg: float, ours: str = "adaptive_clearing", gouge_tol_mm: float = 0.05) -> dict:
    """The targets of one pocket's :func:`comparison` table ``t`` for the row ``ours``: the
    :func:`engagement_targets` and, against FreeCAD's row, lifts, uncut area and program time no
    larger, the §4 feed control lowering the time, plan time at most twice FreeCAD's (None where
    FreeCAD wrote no program)."""
    a, f = t.loc[ours], t.loc[FREECAD]
    fc_time = t.loc[ours + FEED_CONTROL_SUFFIX, "program_time_min"]

    def le(x, y):
        return bool(x <= y) if np.isfinite(y) else None

    out = engagement_targets(a.engagement_p95_deg, a.engagement_max_deg, a.share_above_5_pct, a.share_above_15_pct,
                             a.plunges_into_material, a.rapids_into_material, a.wall_gouge_mm, theta_deg, gouge_tol_mm)
    out.update({"lifts<=FC": le(a.lifts, f.lifts), "uncut<=FC": le(a.uncut_beyond_mm2, f.uncut_beyond_mm2),
                "time<=FC": le(a.program_time_min, f.program_time_min),
                "feed ctrl lower": bool(fc_time < a.program_time_min),
                "plan<=2xFC": le(a.plan_time_s, 2 * f.plan_time_s)})
    return out


def lifts(ev: Evaluation, top_z: float = 0.0) -> int:
    """Number of times the tool rises from below ``top_z`` (mm) to above it along the evaluated samples
    (any move kind: a G0 lift counts like a G1 retract).

    >>> from shapely.geometry import box
    >>> from cnclab.toolpath.path import Tool
    >>> jb = Job(box(0, 0, 40, 20), Tool(6.0), 60.0, 2.0, feed_mm_min=300, spindle_rpm=5000)
    >>> p = ToolPath.build([[5, 10, 5], [5, 10, -2], [9, 10, -2], [9, 10, 5], [20, 10, -2], [20, 10, 5]],
    ...                    kind=["rapid", "plunge", "cut", "rapid", "plunge", "retract"], feed=300)
    >>> lifts(evaluate(p, jb, 0.5))
    2
    """
    z = ev.trace["z"]
    below = z < top_z - 1e-9
    return int(np.count_nonzero(below[:-1] & (z[1:] > top_z + 1e-9)) + np.count_nonzero(
        below[:-1] & (np.abs(z[1:] - top_z) <= 1e-9) & np.r_[z[2:] > top_z + 1e-9, False]))


def row(ev: Evaluation, plan_s: float, time_s: float | None = None, jb: Job | None = None,
        machine_s: float | None = None) -> dict:
    """One table row (:data:`COLUMNS`) of an evaluation; ``time_s`` overrides the program time (s)
    and ``machine_s`` the machine time (s: ``ev.time_machine_s``, the small-VMC model of
    :mod:`cnclab.toolpath.motion`); with ``jb`` the wall gouge is measured (else NaN)."""
    return {"wall_gouge_mm": math.nan if jb is None else wall_gouge_mm(ev, jb),
            "engagement_p95_deg": ev.engagement_p95_deg, "engagement_max_deg": ev.engagement_max_deg,
            "share_above_5_pct": ev.share_above_5_pct, "share_above_15_pct": ev.share_above_15_pct,
            "entry_engagement_max_deg": ev.entry_engagement_max_deg, "retracts": ev.retracts,
            "lifts": lifts(ev, jb.top_z if jb is not None else 0.0),
            "plunges_into_material": ev.plunges_into_material, "rapids_into_material": ev.rapids_into_material,
            "uncut_beyond_mm2": ev.uncut_beyond_unreachable_mm2,
            "program_time_min": (ev.time_total_s if time_s is None else time_s) / 60.0,
            "machine_time_min": (ev.time_machine_s if machine_s is None else machine_s) / 60.0, "plan_time_s": plan_s}


def _nan_row(note: str) -> dict:
    return {c: math.nan for c in COLUMNS} | {"note": note}


def comparison(name: str, planner_rows: dict | None = None, fast: bool | None = None, freecad=None,
               feed_control: bool = True, keep: dict | None = None) -> pd.DataFrame:
    """The table of pocket ``name``: one row per planner (``planner_rows``: label -> strategy,
    default :data:`PLANNER_ROWS`; a planner that refuses the pocket gets a NaN row with its reason in
    ``note``), the first one again with §4 feed control, and FreeCAD Adaptive. Every planner's path
    is scored as written (:func:`as_written`), as FreeCAD's program is; the feed-control row sets its
    feeds on the planned moves (its engagement columns are the planned path's). ``freecad``:
    ``(ToolPath or None, plan seconds, note)`` (default: the committed fixture). ``keep``: a dict
    that receives the paths and evaluations (label -> (path as written, evaluation)) for plots."""
    jb = job(name)
    h = resolution_mm(name, fast)
    rows = {}
    for k, (label, strategy) in enumerate((planner_rows or PLANNER_ROWS).items()):
        try:
            tp, t_plan = plan_timed(jb, strategy, h)
        except ValueError as exc:
            rows[label] = _nan_row(f"refused: {exc}")
            continue
        tw = as_written(tp, jb)                          # scored as written, as FreeCAD's program
        ev = evaluate(tw, jb, h)
        rows[label] = row(ev, t_plan, jb=jb) | {"note": ""}
        if keep is not None:
            keep[label] = (tw, ev)
        if feed_control and k == 0:
            evp = evaluate(tp, jb, h)                    # the feeds are set on the planned moves
            fc = feed_controlled(tp, jb, evp)
            rows[label + FEED_CONTROL_SUFFIX] = row(evp, t_plan, fc.time_s(jb.rapid_mm_min)["total_s"], jb,
                                                    path_machine_time(fc)) | {
                "note": "the planned path, feeds per 0.5 mm block (MRR held, <= v_fmax)"}
    if freecad is None:
        try:
            freecad = (freecad_path(name, jb.tool), freecad_plan_time_s(name), "committed program, plan time from its JSON")
        except ValueError as exc:
            freecad = (None, freecad_plan_time_s(name), str(exc))
    fp, t_fc, note = freecad
    if fp is None:
        rows[FREECAD] = _nan_row(note) | {"plan_time_s": t_fc}
    else:
        ev = evaluate(fp, jb, h)
        rows[FREECAD] = row(ev, t_fc, jb=jb) | {"note": note}
        if keep is not None:
            keep[FREECAD] = (fp, ev)
    T = pd.DataFrame(rows).T
    T[COLUMNS] = T[COLUMNS].astype(float)
    T.attrs.update(pocket=name, job=POCKETS[name], theta_deg=jb.theta_deg, resolution_mm=h)
    return T


def ratios(T: pd.DataFrame) -> pd.DataFrame:
    """Every row of a :func:`comparison` table divided by the FreeCAD row (NaN where FreeCAD has no
    program or a zero value)."""
    fc = T.loc[FREECAD, COLUMNS].astype(float).replace(0.0, np.nan)
    return T.loc[[i for i in T.index if i != FREECAD], COLUMNS].astype(float).div(fc, axis=1)
