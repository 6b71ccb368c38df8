"""Kim & Yang (2006) pocket: constant-MRR path vs a constant-engagement clearing (beyond the paper).

The same 120 × 85 mm pocket (cnclab's design, ``data/kim_yang2006/pocket_120x85.json``) and Table 1
conditions (tool Ø10 → r = 5 mm, radial depth b = 3 mm, a_p = 0.5 mm, 500 mm/min, 2000 rpm) are
cleared three ways and every path is cut through the *same* dixel simulator
(:func:`cnclab.toolpath.ce_clearing.evaluate_path`):

* ``original`` — the contour-parallel path (offsets at b = 3 mm, spiral entries), from its G-code;
* ``modified`` — Kim & Yang's §3.2–3.3 constant-MRR modification, from its G-code;
* ``constant engagement`` — :func:`cnclab.toolpath.ce_clearing.ce_clearing` at the engagement of a
  straight cut at b: theta = arccos(1 - b/r) = 66.42 deg (Jacsó Thesis III laps from a helical
  entry in each part of the pocket, limited by the final contour within each lap, then a final
  contour pass).

Times: cutting steps (those that remove material) at 500 mm/min, non-cutting feed steps at Jacsó's
linking feed 1500 mm/min (§4), rapids at an assumed 10 m/min — one rule for all three paths.

The paper prints no number for such a comparison: nothing here is a ledger claim.
"""
from __future__ import annotations

import functools
import math

import numpy as np
import pandas as pd

from ...runtime import pick
from ...toolpath import ce_clearing as cc
from ...nc import gcode
from . import constant_mrr_pocket as ky

PATHS = ("original", "modified", "constant engagement")


def theta_deg() -> float:
    """Engagement of a straight cut at Table 1's radial depth: arccos(1 - b/r) (deg) = 66.42."""
    return math.degrees(math.acos(1.0 - ky.conditions()["radial_depth_mm"] / ky.tool_radius()))


def resolution_mm() -> float:
    """Dixel row height (mm) of the planning and evaluation stocks: 0.1 (fast mode 0.25)."""
    return pick(0.1, 0.25)


@functools.cache
def ce_path() -> cc.ClearingPath:
    """The constant-engagement clearing of the pocket (default seeds: one per side of the neck)."""
    c = ky.conditions()
    return cc.ce_clearing(ky.pocket(), ky.tool_radius(), theta_deg(), resolution_mm=resolution_mm(),
                          a_p=c["axial_depth_mm"], feed_mm_min=c["feed_mm_min"])


@functools.cache
def ce_program() -> tuple:
    """``(moves parsed back, G-code text)`` of the constant-engagement path."""
    c = ky.conditions()
    moves = cc.to_moves(ce_path(), z_cut=-c["axial_depth_mm"], z_clear=5.0, feed=c["feed_mm_min"],
                        spindle=c["spindle_rpm"], link_feed=cc.LINK_FEED_MM_MIN)
    text = gcode.write_gcode(moves, header=["Kim and Yang 2006 pocket: constant-engagement clearing",
                                            "cnclab ce_clearing, Jacso Thesis III laps, tool D10 flat"], decimals=4)
    return tuple(gcode.parse_gcode(text, source="kim_yang2006_ce.nc")), text


def ce_roundtrip() -> dict:
    """G-code round trip of the CE path: max distance (mm) of the parsed cutting-depth points from
    the path points, and parsed vs path XY length at cutting depth (mm)."""
    from scipy.spatial import cKDTree

    moves, _ = ce_program()
    z = -ky.conditions()["axial_depth_mm"]
    P = np.array([[m.x, m.y] for m in moves if abs(m.z - z) < 1e-9])
    d, _ = cKDTree(ce_path().points).query(P)
    return {"max_point_error_mm": float(d.max()), "n_cutting_points": len(P),
            "n_path_points": len(ce_path().points)}


def programme_path(which: str) -> cc.ClearingPath:
    """The ``original`` / ``modified`` program read back, as a :class:`ClearingPath` at cutting
    depth (arcs sampled every 0.5 mm; a jump over non-cutting moves is a ``rapid``)."""
    moves, _ = ky.program(which)
    pts, _ = gcode.to_polyline(moves, max_segment=0.5)
    z = -ky.conditions()["axial_depth_mm"]
    keep = np.flatnonzero(np.abs(pts[:, 2] - z) < 1e-9)
    jump = np.r_[False, np.diff(keep) > 1]
    return cc.path_from_programme(pts[keep], jump)


@functools.cache
def evaluation(which: str) -> tuple:
    """``(per-step table, summary)`` of one path cut through a fresh dixel stock of the pocket."""
    c = ky.conditions()
    path = ce_path() if which == "constant engagement" else programme_path(which)
    return cc.evaluate_path(path, ky.pocket(), ky.tool_radius(), theta_deg(), resolution_mm(),
                            a_p=c["axial_depth_mm"], feed_mm_min=c["feed_mm_min"],
                            radial_depth_mm=c["radial_depth_mm"])


ROWS = {"max_mrr_over_nominal": "max MRR / nominal (1 mm windows, entry ramps excluded)",
        "p99_mrr_over_nominal": "99th pct MRR / nominal",
        "max_engagement_deg": "max engagement [deg] (entry ramps excluded)",
        "median_engagement_cut_deg": "median engagement [deg]",
        "share_above_theta_plus5": "share of cutting length above theta+5 deg",
        "cutting_length_mm": "cutting length [mm]",
        "linking_length_mm": "linking (air) feed length [mm]",
        "rapid_length_mm": "rapid XY length [mm]",
        "n_rapids": "retracts (rapid + plunge)",
        "cutting_time_min": "cutting time at 500 mm/min [min]",
        "linking_time_min": "linking time at 1500 mm/min [min]",
        "rapid_time_min": "rapid time at 10 m/min, assumed [min]",
        "entry_time_min": "helical entry time, 2 turns at 500 mm/min [min]",
        "total_time_min": "total time [min]",
        "time_one_feed_min": "time, every feed move at 500 mm/min [min]",
        "entry_mean_mrr_over_nominal": "helical entry: mean MRR / nominal",
        "plunge_area_mm2": "area plunged axially [mm2]",
        "uncut_area_mm2": "uncut area [mm2]",
        "unreachable_area_mm2": "of which unreachable by a r=5 tool [mm2]"}


@functools.cache
def comparison_table() -> pd.DataFrame:
    """The three paths side by side (rows: :data:`ROWS`)."""
    out = pd.DataFrame({w: {ROWS[k]: evaluation(w)[1][k] for k in ROWS} for w in PATHS})
    return out


def ce_breakdown() -> pd.DataFrame:
    """Constant-engagement path per segment kind (entry = helical ramp simulated at full depth, shown
    here only): cutting length, max engagement, share above theta+5."""
    s = evaluation("constant engagement")[1]
    return pd.DataFrame({k: {"cutting length [mm]": s[f"cutting_length_{k}_mm"],
                             "max engagement [deg]": s[f"max_engagement_{k}_deg"],
                             "share above theta+5": s[f"share_above_{k}"]} for k in cc.CUTTING_KINDS})


@functools.cache
def wall_modes(modes: tuple = ("clamp", "gate")) -> pd.DataFrame:
    """Lap statistics of the CE clearing under each final-contour handling ``wall`` (see
    :func:`cnclab.toolpath.ce_clearing.ce_clearing`): max engagement and share above theta+5 of the
    laps, of the whole path (entry excluded), retracts, total time. Each mode plans and evaluates anew."""
    c = ky.conditions()
    rows = {}
    for w in modes:
        path = cc.ce_clearing(ky.pocket(), ky.tool_radius(), theta_deg(), resolution_mm=resolution_mm(),
                              a_p=c["axial_depth_mm"], feed_mm_min=c["feed_mm_min"], wall=w)
        s = cc.evaluate_path(path, ky.pocket(), ky.tool_radius(), theta_deg(), resolution_mm(),
                             a_p=c["axial_depth_mm"], feed_mm_min=c["feed_mm_min"],
                             radial_depth_mm=c["radial_depth_mm"])[1]
        rows[w] = {"laps: max engagement [deg]": s["max_engagement_cut_deg"],
                   "laps: share above theta+5": s["share_above_cut"],
                   "path: max engagement [deg]": s["max_engagement_deg"],
                   "path: share above theta+5": s["share_above_theta_plus5"],
                   "retracts": s["n_rapids"], "total time [min]": s["total_time_min"]}
    return pd.DataFrame(rows)
