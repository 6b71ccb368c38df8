"""Recipes for Kim & Yang (2006): constant-MRR contour-parallel path on a 120 × 85 mm pocket.

The pocket (``data/kim_yang2006/pocket_120x85.json``) is cnclab's own: the paper gives only the
model size. Conditions are Table 1's (``data/kim_yang2006/table1_conditions.json``). Everything is
computed from the G-code actually written and parsed back.
"""
from __future__ import annotations

import functools
import json

import numpy as np
import pandas as pd
from shapely.geometry import LinearRing, Polygon

from ...paths import data_path
from ...runtime import pick
from ...simulation import dixel, pixel
from ...toolpath import constant_mrr as cm
from ...nc import gcode
from ...nc.program import write_program
from ...toolpath import offsets
from ...toolpath.job import Job, load_job
from ...toolpath.path import ToolPath

Z_CUT_BELOW_TOP = True   # cutting height z = -a_p below the stock top z = 0


@functools.cache
def conditions() -> dict:
    """Table 1 conditions (mm, rpm, mm/min)."""
    return json.loads(data_path("kim_yang2006", "table1_conditions.json").read_text(encoding="utf-8"))


@functools.cache
def pocket() -> Polygon:
    """The 120 × 85 mm test pocket (our design; see the data file's description)."""
    return job().polygon


@functools.cache
def job() -> Job:
    """The pocket as a job (:func:`cnclab.toolpath.job.load_job`): Table 1 cutting data."""
    return load_job(data_path("kim_yang2006", "pocket_120x85.json"))


def tool_radius() -> float:
    return conditions()["tool_diameter_mm"] / 2.0


def reference_per_mm(teeth: int = cm.DEFAULT_TEETH) -> float:
    """Eq. 4 reference pixel count per tooth advance, divided by Δs: pixels per mm of path."""
    c = conditions()
    fz = cm.feed_per_tooth(c["feed_mm_min"], c["spindle_rpm"], teeth)
    return cm.reference_pixel_count(fz, c["radial_depth_mm"], c["pixel_mm"]) / fz


@functools.cache
def offset_levels():
    return offsets.offset_levels(pocket(), tool_radius(), conditions()["radial_depth_mm"])


@functools.cache
def base_passes(spiral: bool = True) -> tuple:
    """Contour-parallel passes (inside-out), each preceded by a spiral entry when ``spiral``."""
    allowed = offsets.allowed_region(pocket(), tool_radius())
    passes = offsets.link_loops(offset_levels(), allowed)
    if not spiral:
        return tuple(passes)
    out = []
    for p in passes:
        n0 = _first_loop_len(p)
        ring = LinearRing(p[:n0])
        if ring.is_ccw and Polygon(ring).area > 1.0:
            sp = cm.spiral_entry(Polygon(ring), p[0], pitch_mm=conditions()["radial_depth_mm"])
            p = np.vstack([sp[:-1], p])
        out.append(p)
    return tuple(out)


def _first_loop_len(p: np.ndarray) -> int:
    d = np.hypot(p[1:, 0] - p[0, 0], p[1:, 1] - p[0, 1])
    k = np.flatnonzero(d < 1e-9)
    return int(k[0]) + 2 if len(k) else len(p)


@functools.cache
def modified(tolerance: float = 0.15, step_mm: float = 1.0) -> cm.ModifiedPath:
    """§3.2 modification of :func:`base_passes` on a 0.3 mm pixel stock."""
    c = conditions()
    stock = pixel.Stock.from_polygon(pocket(), c["pixel_mm"])
    return cm.modify_path(list(base_passes()), stock, tool_radius(), reference_per_mm(),
                          offsets.allowed_region(pocket(), tool_radius()), step_mm=step_mm,
                          tolerance=tolerance)


@functools.cache
def program_path(which: str, entry: str = "plunge") -> ToolPath:
    """The ``"original"`` or ``"modified"`` contour-parallel path (§3.3 arcs). ``entry="plunge"``:
    the paper's program (straight down onto each pass start); ``"helix"``: the machine-safe program
    (:func:`cnclab.toolpath.constant_mrr.passes_path`)."""
    passes = {"original": base_passes(), "modified": tuple(modified().passes)}[which]
    return cm.passes_path(passes, job(), arcs=True, entry=entry, tol_mm=0.02, short_mm=1.5)


def program(which: str) -> tuple:
    """``(moves parsed back, G-code text)`` of the ``"original"`` or ``"modified"`` path."""
    text = written_program(program_path(which), [f"Kim and Yang 2006 {which} contour-parallel path",
                                                 "pocket 120 x 85 mm, cnclab design, tool D10 flat"])
    return tuple(gcode.parse_gcode(text, source=f"kim_yang2006_{which}.nc")), text


def written_program(path: ToolPath, header) -> str:
    """``path`` through the one program writer (:func:`cnclab.nc.program.write_program`) with the
    job's clearance plane, stock top, tool and spindle speed, every move as planned (no arc fitting,
    the planned feeds): the paper's moves, with the writer's start block, tool change and end."""
    j = job()
    return write_program(path, clearance_z=j.clearance_z, top_z=j.top_z, tool=j.tool, spindle_rpm=j.spindle_rpm,
                         arc_tol_mm=None, header=header)


def cut_polylines(moves, max_segment):
    """Split a parsed program (or :meth:`ToolPath.to_moves`) into cutting polylines (z below 0), arcs
    sampled every ``max_segment`` mm; one polyline per pass."""
    polys, cur, prev = [], [], None
    for mv in moves:
        if prev is not None and mv.z < 0 and prev[2] < 0:
            seg = gcode.sample_move(prev, mv, max_segment)[1:]
            cur.extend(seg[:, :2])
        elif mv.z < 0:
            cur = [mv.xyz[:2]]
            polys.append(cur)
        prev = mv.xyz
    return [np.array(p) for p in polys if len(p) > 1]


@functools.cache
def mrr_trace(which: str, model: str = "pixel", sample_mm: float | None = None) -> pd.DataFrame:
    """MRR along the program (``model`` = ``"pixel"`` at 0.3 mm or ``"dixel"`` at 0.1 mm)."""
    c = conditions()
    sample = pick(0.3, 0.6) if sample_mm is None else sample_mm
    moves, _ = program(which)
    mod = {"pixel": (pixel, c["pixel_mm"]), "dixel": (dixel, pick(0.1, 0.2))}[model]
    stock = mod[0].Stock.from_polygon(pocket(), mod[1])
    frames, s0 = [], 0.0
    for poly in cut_polylines(moves, sample):
        pts = cm.resample_polyline(poly, sample)
        df = mod[0].simulate(stock, pts, tool_radius(), a_p=c["axial_depth_mm"], feed_mm_min=c["feed_mm_min"])
        df["s"] += s0
        s0 = float(df["s"].iloc[-1])
        frames.append(df.iloc[1:])
    return pd.concat(frames, ignore_index=True)


def nominal_mrr() -> float:
    """a_p · b · v_f [mm³/min] = 0.5 · 3 · 500."""
    c = conditions()
    return c["axial_depth_mm"] * c["radial_depth_mm"] * c["feed_mm_min"]


@functools.cache
def summary(model: str = "pixel") -> pd.DataFrame:
    """Max / 99th-percentile MRR over nominal, path lengths and times, before and after."""
    rows = {}
    for which in ("original", "modified"):
        df = mrr_trace(which, model)
        moves, _ = program(which)
        L = gcode.path_lengths(moves)
        m = df.mrr_mm3_min.to_numpy()
        m = m[np.isfinite(m)]
        rows[which] = {"max_over_nominal": m.max() / nominal_mrr(),
                       "p99_over_nominal": np.percentile(m, 99) / nominal_mrr(),
                       "share_above_1.2_nominal": float(np.mean(m > 1.2 * nominal_mrr())),
                       "feed_length_mm": L["feed"], "rapid_length_mm": L["rapid"],
                       "feed_time_min": L["feed"] / conditions()["feed_mm_min"],
                       "n_arcs": sum(mv.motion in ("G2", "G3") for mv in moves)}
    out = pd.DataFrame(rows)
    out["added"] = out["modified"] - out["original"]
    return out


# ---------------------------------------------------------------- claim recipes (Table 1)
def pocket_size() -> dict:
    """Bounding box [mm] of the pocket the programs machine (Table 1 'model size')."""
    x0, y0, x1, y1 = pocket().bounds
    return {"x": x1 - x0, "y": y1 - y0}


def measured_radial_depth() -> float:
    """Distance [mm] between the first two offset levels of the program (Table 1 radial depth)."""
    lv = offset_levels()
    a = LinearRing(lv[0][0])
    return float(min(a.distance(LinearRing(lp)) for lp in lv[1]))


def measured_tool_diameter() -> float:
    """2 × distance [mm] from the finishing contour to the pocket wall (Table 1 tool φ10)."""
    return 2.0 * float(LinearRing(offset_levels()[0][0]).distance(pocket().exterior))


def gcode_words() -> dict:
    """Feed F [mm/min], spindle S [rpm] and cutting depth −Z [mm] read back from the written program."""
    moves, _ = program("modified")
    cut = [m for m in moves if m.motion != "G0"]
    return {"feed": float(np.median([m.feed for m in cut])),
            "spindle": float(np.median([m.spindle for m in cut])),
            "axial_depth": -float(min(m.z for m in moves))}
