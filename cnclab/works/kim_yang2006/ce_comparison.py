"""Kim & Yang (2006) pocket: constant-MRR paths vs constant-engagement clearings (beyond the paper).

The same 120 × 85 mm pocket (cnclab's design, ``data/kim_yang2006/pocket_120x85.json``) and Table 1
conditions (tool Ø10 → r = 5 mm, radial depth b = 3 mm, a_p = 0.5 mm, 500 mm/min, 2000 rpm) are
cleared four ways and every path is cut through the *same* dixel simulator
(:func:`cnclab.toolpath.evaluate.evaluate` on the pocket job ``data/kim_yang2006/pocket_120x85.json``):

* ``original`` — the contour-parallel path (offsets at b = 3 mm, spiral entries), from its G-code;
* ``modified`` — Kim & Yang's §3.2–3.3 constant-MRR modification, from its G-code;
* ``constant engagement`` — :func:`cnclab.toolpath.ce_clearing.ce_clearing` at the engagement of a
  straight cut at b: theta = arccos(1 - b/r) = 66.42 deg (Jacsó Thesis III laps from a helical
  entry in each part of the pocket, limited by the final contour within each lap, then a final
  contour pass) -- the collection's older clearing planner;
* ``adaptive clearing`` -- the engagement-controlled clearing of issue 16,
  ``cnclab.toolpath.planners.STRATEGIES["adaptive"]`` (:mod:`cnclab.toolpath.adaptive`: each step
  steered to theta on the simulated stock, links at depth through the cleared region, a wall-following
  finish); fast mode plans it on a coarser pixel stock (``resolution_mm()``) to keep the notebook short.

Times: the programs' own motion model (every feed move at its written feed, rapids at an assumed
10 m/min) — one rule for all four paths.

The paper prints no number for such a comparison: nothing here is a ledger claim.
"""
from __future__ import annotations

import functools
import math
import time

import numpy as np
import pandas as pd

from ...cache import cached
from ...nc import gcode
from ...runtime import fast_mode, pick
from ...toolpath import adaptive
from ...toolpath import ce_clearing as cc
from ...toolpath import planners
from ...toolpath.evaluate import Evaluation, evaluate
from ...toolpath.path import ToolPath
from ..jacso2021.freecad_comparison import lifts
from . import constant_mrr_pocket as ky

PATHS = ("original", "modified", "constant engagement", "adaptive clearing")


def theta_deg() -> float:
    """Engagement of a straight cut at Table 1's radial depth: arccos(1 - b/r) (deg) = 66.42."""
    return math.degrees(math.acos(1.0 - ky.conditions()["radial_depth_mm"] / ky.tool_radius()))


def resolution_mm() -> float:
    """Dixel row height (mm) of the planning and evaluation stocks: 0.1 (fast mode 0.25)."""
    return pick(0.1, 0.25)


def ce_path() -> ToolPath:
    """The constant-engagement clearing of the pocket job (default seeds: one per side of the neck);
    cached on disk (build/cache, keyed by the code and the resolution: minutes at full resolution,
    shared by the notebook, the claims report and ``python -m cnclab programs``)."""
    return _ce_path(resolution_mm())


@functools.cache
@cached()
def _ce_path(res: float) -> ToolPath:
    return cc.ce_clearing(ky.job(), resolution_mm=res)


@functools.cache
def adaptive_path() -> ToolPath:
    """The engagement-controlled clearing (``planners.STRATEGIES["adaptive"]``) of the pocket job; full mode
    plans with the planner's own defaults (as ``python -m cnclab plan`` does), fast mode on a pixel stock
    of r/30 (the planner's coarsest, instead of r/60). ``info["plan_time_s"]``: wall-clock plan time."""
    t0 = time.perf_counter()
    if fast_mode():     # the strategy's own function with a coarser planning stock (planners.plan has no such knob)
        path = adaptive.plan_job(ky.job(), resolution_mm=min(resolution_mm(), ky.job().tool_radius / 30))
    else:
        path = planners.plan(ky.job(), "adaptive", resolution_mm())
    path.info["plan_time_s"] = time.perf_counter() - t0
    return path


@functools.cache
def ce_program() -> tuple:
    """``(moves parsed back, G-code text)`` of the constant-engagement path."""
    text = ky.written_program(ce_path(), ["Kim and Yang 2006 pocket: constant-engagement clearing",
                                          "cnclab ce_clearing, Jacso Thesis III laps, tool D10 flat"])
    return tuple(gcode.parse_gcode(text, source="kim_yang2006_ce.nc")), text


def ce_roundtrip() -> dict:
    """G-code round trip of the CE path: max distance (mm) of the parsed end points from the path
    points, and the number of points."""
    from scipy.spatial import cKDTree

    moves, _ = ce_program()
    P = np.array([m.xyz for m in moves])
    d, _ = cKDTree(ce_path().xyz).query(P)
    return {"max_point_error_mm": float(d.max()), "n_program_points": len(P), "n_path_points": len(ce_path())}


@functools.cache
def programme_path(which: str) -> ToolPath:
    """The ``original`` / ``modified`` program read back as a :class:`ToolPath` (kinds classified
    from the geometry by :meth:`ToolPath.from_moves`)."""
    moves, _ = ky.program(which)
    return ToolPath.from_moves(moves, tool=ky.job().tool, info={"name": which})


def path(which: str) -> ToolPath:
    """The tool path of ``which`` (a name of :data:`PATHS`)."""
    if which not in PATHS:
        raise ValueError(f"which must be one of {PATHS}, got {which!r}")
    return {"constant engagement": ce_path, "adaptive clearing": adaptive_path}.get(which, lambda: programme_path(which))()


def key_figures() -> pd.DataFrame:
    """The figures the notebook's discussion talks about, per path: share above theta+5 (%), max
    engagement (deg), max MRR / nominal, retracts (feed moves), lifts (every rise out of the stock, G0
    or G1: :func:`cnclab.works.jacso2021.freecad_comparison.lifts`), plunges into material, links at
    depth (mm), total time (min), uncut beyond the unreachable corners (mm^2)."""
    cols = {"share_above_5_pct": "share > θ+5 [%]", "engagement_max_deg": "max eng. [deg]",
            "mrr_max_over_nominal": "max MRR / nom", "retracts": "retracts",
            "plunges_into_material": "plunges into mat.", "link_length_mm": "links at depth [mm]",
            "uncut_beyond_unreachable_mm2": "uncut beyond [mm2]"}
    out = {w: {v: getattr(evaluation(w), k) for k, v in cols.items()}
           | {"lifts (G0 or G1)": lifts(evaluation(w), ky.job().top_z), "time [min]": evaluation(w).time_total_s / 60}
           for w in PATHS}
    return pd.DataFrame(out).T


@functools.cache
def evaluation(which: str) -> Evaluation:
    """The one evaluator (:func:`cnclab.toolpath.evaluate.evaluate`) on the pocket job (computed once
    per process: the tables and traces of the notebook share it)."""
    return evaluate(path(which), ky.job(), resolution_mm())


def trace_table(which: str) -> pd.DataFrame:
    """The evaluation's trace along the sampled path as a DataFrame (``ds`` = xy step, mm)."""
    t = evaluation(which).trace
    return pd.DataFrame({k: v for k, v in t.items()}).rename(columns={"ds_mm": "ds"})


ROWS = {"mrr_max_over_nominal": "max MRR / nominal (1 mm windows, entries excluded)",
        "engagement_max_deg": "max engagement [deg] (entries excluded)",
        "engagement_p50_deg": "median engagement [deg]",
        "engagement_p95_deg": "95th pct engagement [deg]",
        "share_above_5_pct": "share of cutting length above theta+5 deg [%]",
        "cut_length_mm": "cut length [mm]",
        "air_cut_length_mm": "of which air cut [mm]",
        "link_length_mm": "link length at depth [mm]",
        "rapid_length_mm": "rapid length [mm]",
        "retracts": "retracts",
        "entries_helix": "helical entries", "entries_plunge": "plunge entries",
        "plunges_into_material": "plunges into material",
        "plunge_swept_area_mm2": "area plunged into [mm2]",
        "rapids_into_material": "rapids into material",
        "time_cut_s": "cut time [s]", "time_link_s": "link time [s]",
        "time_rapid_s": "rapid time at 10 m/min, assumed [s]",
        "time_entry_s": "entry time [s]", "time_retract_s": "retract time [s]",
        "time_total_s": "total time = the program's [s]",
        "uncut_area_mm2": "uncut area [mm2]",
        "uncut_beyond_unreachable_mm2": "uncut beyond the unreachable corners [mm2]"}


@functools.cache
def comparison_table() -> pd.DataFrame:
    """The four paths side by side (rows: :data:`ROWS`)."""
    return pd.DataFrame({w: {ROWS[k]: getattr(evaluation(w), k) for k in ROWS} for w in PATHS})


def _by_tag(ev: Evaluation) -> pd.DataFrame:
    t = ev.trace
    tags = np.array([str(x).split(" ")[0] for x in t["tag"]], dtype=object)
    groups = {"laps": (t["kind"] == "cut") & (tags == "seed"), "cleanup": tags == "cleanup",
              "linkcut": tags == "linkcut", "entry (helix)": t["kind"] == "helix"}
    lim = ev.theta_deg + 5.0
    out = {}
    for name, m in groups.items():
        m = m & (t["removed_mm2"] > 0.5 * ev.resolution_mm ** 2)
        L = float(t["ds_mm"][m].sum())
        e = t["engagement_deg"][m]
        out[name] = {"cutting length [mm]": L,
                     "max engagement [deg]": float(np.nanmax(e)) if np.isfinite(e).any() else float("nan"),
                     "share above theta+5": float(t["ds_mm"][m & (t["engagement_deg"] > lim)].sum()) / L if L else float("nan")}
    return pd.DataFrame(out)


def ce_breakdown() -> pd.DataFrame:
    """Constant-engagement path per part (laps, cleanup, link steps that cut, helical entries):
    cutting length, max engagement, share above theta+5."""
    return _by_tag(evaluation("constant engagement"))


@functools.cache
def wall_modes(modes: tuple = ("clamp", "gate")) -> pd.DataFrame:
    """Lap statistics of the CE clearing under each final-contour handling ``wall`` (see
    :func:`cnclab.toolpath.ce_clearing.ce_clearing`): max engagement and share above theta+5 of the
    laps, of the whole path (entries excluded), retracts, total time. Each mode plans and evaluates anew,
    except the planner's default ("gate"), which is :func:`ce_path` and its evaluation."""
    rows = {}
    default_wall = cc.ClearingSettings().wall
    for w in modes:
        if w == default_wall:
            ev = evaluation("constant engagement")
        else:
            path = cc.ce_clearing(ky.job(), resolution_mm=resolution_mm(), wall=w)
            ev = evaluate(path, ky.job(), resolution_mm())
        laps = _by_tag(ev)["laps"]
        rows[w] = {"laps: max engagement [deg]": laps["max engagement [deg]"],
                   "laps: share above theta+5": laps["share above theta+5"],
                   "path: max engagement [deg]": ev.engagement_max_deg,
                   "path: share above theta+5 [%]": ev.share_above_5_pct,
                   "retracts": ev.retracts, "total time [s]": ev.time_total_s}
    return pd.DataFrame(rows)
