"""Recipes for Hoang (2024): eqs 1–7, Table 2, Table 3 / Fig. 9 and the height-field check.

Table 2 explanation (found by reproducing it): θ is computed in **radians** (``asin(S_z/2R_T)``),
printed under the header "θ, °", and then put into eq. 3's ``π·θ/180`` as if it were in degrees
(with ``π = 3.14`` and θ rounded to the 5 printed decimals), while ``sin θ`` gets the radian value.
This reproduces every printed ``F_r`` to the last digit; the unit-consistent ``F_r`` is 12–32× larger.
"""
from __future__ import annotations

import functools
import json
import math

import numpy as np
import pandas as pd

from ...cutting import scallop_volume as sv
from ...paths import data_path
from ...simulation.heightfield import HeightField
from ...nc import gcode
from ...nc.program import write_program
from ...toolpath import zigzag
from ...toolpath.path import Tool, ToolPath

ROWS = tuple(f"r{i}" for i in range(1, 9))
#: spindle speed [rpm] of the written Table 3 program: a placeholder (the paper gives none, as for the
#: feed; no length depends on it) so that the program starts the spindle before cutting
TABLE3_SPINDLE_RPM = 8000.0


@functools.cache
def table2_printed() -> pd.DataFrame:
    """Table 2 as printed (``data/hoang2024/table2_toolpath_parameters.csv``), index r1..r8."""
    df = pd.read_csv(data_path("hoang2024", "table2_toolpath_parameters.csv"), comment="#")
    df.index = [f"r{i}" for i in df["row"]]
    return df


@functools.cache
def table2_recomputed() -> pd.DataFrame:
    """Every Table 2 row recomputed from its inputs (S_c, R_T, V): consistent and as-printed columns."""
    t = table2_printed()
    rows = {k: sv.table2_row(r.Sc_mm, r.RT_mm, r.V_mm3) for k, r in t.iterrows()}
    return pd.DataFrame(rows).T.astype(float)


def table2_sz() -> dict:
    """S_z [mm] from eq. 6 per row."""
    return table2_recomputed()["Sz"].to_dict()


def table2_theta_deg() -> dict:
    """θ [degrees] per row: the unit the header "θ, °" announces (eq. 5)."""
    return table2_recomputed()["theta_deg"].to_dict()


def table2_theta_rad() -> dict:
    """θ [radians] per row, unrounded (eq. 5)."""
    return table2_recomputed()["theta_rad"].to_dict()


def table2_theta_as_printed() -> dict:
    """θ as printed: radians, from the 5-decimal S_z, rounded to 5 decimals."""
    return table2_recomputed()["theta_printed_convention"].to_dict()


def table2_fr_consistent() -> dict:
    """F_r [mm] from eq. 7 with θ in consistent units (``π·θ_deg/180 = θ_rad``)."""
    return table2_recomputed()["Fr_consistent"].to_dict()


def table2_fr_as_printed() -> dict:
    """F_r [mm] under the slip: S_z and θ_rad at 5 decimals, θ_rad into ``π·θ/180``, π = 3.14."""
    return table2_recomputed()["Fr_printed_convention"].to_dict()


def table2_sc_from_printed_sz() -> dict:
    """S_c [mm] back from the *printed* S_z and R_T (Table 1 line 5 / inverse eq. 6)."""
    t = table2_printed()
    return {k: float(sv.scallop_height(r.Sz_mm, r.RT_mm)) for k, r in t.iterrows()}


def _v_from_printed(pi: float, slip: bool) -> dict:
    t = table2_printed()
    out = {}
    for k, r in t.iterrows():
        th = r.theta_printed
        term = pi * th / 180.0 - np.sin(th) if slip else th - np.sin(th)
        out[k] = 0.5 * (r.Sc_mm * r.Sz_mm - 0.5 * r.RT_mm ** 2 * term) * r.Fr_mm
    return out


def table2_v_consistent_from_printed() -> dict:
    """V1* [mm³] that the printed (S_z, F_r, θ_rad) actually leave, eq. 2 in consistent units."""
    return _v_from_printed(np.pi, slip=False)


def table2_v_as_printed_from_printed() -> dict:
    """V1* [mm³] from the printed row under the same slip (θ_rad into π·θ/180, π = 3.14)."""
    return _v_from_printed(3.14, slip=True)


# ---------------------------------------------------------------- Table 3 and Fig. 9
@functools.cache
def _table3_setup() -> dict:
    return json.loads(data_path("hoang2024", "table3_and_fig9.json").read_text(encoding="utf-8"))


def table3_program(covering: bool = True, decimals: int = 3, out=None) -> tuple[list, str]:
    """The Table 3 zig-zag for Table 2 row 2 as G-code text, parsed back: ``(moves, text)``.

    ``covering=True``: passes until the last one lies at y ≥ 50 mm (52 passes, Fig. 9's
    "N107 X100 Y50.744"); ``False``: the Table 1 loop as printed (``for i = 1:n/2``).
    Plunge (0,0,10)→(0,0,0) and retract at feed, rapid back to (0,0,10). Feed 500 mm/min and
    spindle :data:`TABLE3_SPINDLE_RPM` are placeholders (the paper gives none; lengths do not depend
    on them). Written by :func:`cnclab.nc.program.write_program` (start block, ``S.. M3`` before
    cutting, ``M5 M30``); clearance plane z = 10 mm (the printed approach height). ``out``: also
    write the program there (atomically).
    """
    s = _table3_setup()
    row = table2_recomputed().loc[f"r{s['table2_row_used']}"]
    w, L = s["workpiece_mm"]["width"], s["workpiece_mm"]["length"]
    if covering:
        pts = zigzag.zigzag_points((0.0, 0.0), w, L, row.Sz)
    else:
        pts = zigzag.hoang_table1_points(0.0, 0.0, w, L, row.Sz, row.Fr_printed_convention)
    rt = float(table2_printed().loc[f"r{s['table2_row_used']}", "RT_mm"])  # ball radius [mm]
    path = zigzag.zigzag_path(pts, z_cut=0.0, z_clear=10.0, feed=500.0)
    path.tool = Tool(2 * rt, corner_radius=rt)
    text = write_program(path, clearance_z=10.0, spindle_rpm=TABLE3_SPINDLE_RPM, top_z=0.0,
                         header=["Hoang 2024 Table 3 constant volume zig-zag, Table 2 row 2"], decimals=decimals,
                         out=out)
    return gcode.parse_gcode(text, source="table3.nc"), text


@functools.cache
def table3_lengths() -> dict:
    """Machining (feed moves incl. plunge and retract) and toolpath (+ rapid return) lengths [mm]
    of the covering program written with 3 decimals (as Fig. 9 prints Y50.744) and parsed back."""
    moves, _ = table3_program(covering=True, decimals=3)
    L = gcode.path_lengths(moves)
    return {"machining": L["feed"], "toolpath": L["total"]}


@functools.cache
def table1_loop_lengths() -> dict:
    """The same accounting for the Table 1 loop as printed (``for i = 1:n/2``)."""
    moves, _ = table3_program(covering=False, decimals=3)
    L = gcode.path_lengths(moves)
    pts = np.array([m.xyz for m in moves])
    return {"machining": L["feed"], "toolpath": L["total"], "last_y": float(pts[:, 1].max()),
            "passes": int(np.sum(np.abs(np.diff(pts[:, 0])) > 1.0))}


def fig9_last_pass_y() -> float:
    """Y [mm] of the last pass of the covering program (Fig. 9 'N107 X100, Y50.744')."""
    moves, _ = table3_program(covering=True, decimals=3)
    return max(m.y for m in moves)


def fig9_stop_y() -> float:
    """Y [mm] of the pass before the covering one (Fig. 9 prints 'N106 X100 Y49.7497'): 50 S_z."""
    moves, _ = table3_program(covering=True, decimals=4)
    ys = sorted({round(m.y, 6) for m in moves})
    return float(ys[-2])


def commercial_last_y() -> float:
    """Last pass Y [mm] of a zig-zag with the commercial run's printed 1 mm horizontal step over the
    printed 50 mm width (passes at 0, 1, ..., 50): restates Fig. 9 a's 'N107 Y50'."""
    s = _table3_setup()
    w, step = s["workpiece_mm"]["width"], s["commercial_cam"]["horizontal_step_mm"]
    return float(math.ceil(w / step - 1e-9) * step)


def table3_traditional_rapid() -> float:
    """Toolpath minus machining length [mm] of the printed Table 3 traditional column: the rapid
    return, which restates the last Y of the commercial program (Fig. 9 a 'it should be N107 Y49.995')
    if, as in the constant volume program, the only rapid is the return from the last pass."""
    t = _table3_setup()["table3"]
    return t["traditional_toolpath_length_mm"] - t["traditional_machining_length_mm"]


# ---------------------------------------------------------------- height-field check
def uncut_volume_per_cell(scallop_height: float, tool_radius: float, forward_step: float,
                          resolution: float = 0.005, discrete: bool = False) -> float:
    """Uncut volume [mm³] in one S_z × F_r cell from a ball-end height-field simulation.

    Two adjacent passes (y = 0 and y = S_z) and the forward steps around the cell are machined.
    ``discrete=False``: continuous straight G1 sweeps (what a zig-zag does); ``True``: the tool only
    plunges at the CC points (x = k·F_r), the point model of the paper's Fig. 2 "cone". Raises
    ValueError when the discrete imprints do not cover the cell (F_r too long for the ball).
    """
    r = float(tool_radius)
    sz = float(sv.stepover(scallop_height, r))
    fr = float(forward_step)
    top = 2 * r
    hf = HeightField.box((-r, 2 * fr + r), (-r, sz + r), resolution, z_top=top)
    for y in (0.0, sz):
        if discrete:
            for x in (0.0, fr, 2 * fr):
                hf.cut_ball_point((x, y, 0.0), r)
        else:
            hf.cut_ball_segment((-r, y, 0.0), (2 * fr + r, y, 0.0), r)
    cell_x, cell_y = (fr / 2, 3 * fr / 2), (0.0, sz)   # one cell, centred between the CC points
    if hf.max_above(0.0, cell_x, cell_y) >= top - 1e-9:
        raise ValueError(f"forward_step {fr:.4g} mm leaves stock untouched between imprints of a "
                         f"ball of radius {r} mm: the discrete uncut volume is not defined")
    return hf.volume_above(0.0, cell_x, cell_y)


@functools.cache
def uncut_volume_table(resolution: float = 0.005) -> pd.DataFrame:
    """Per Table 2 row: V1, V1*, V2 (eqs 1, 2, 4) and the height-field volumes, at the printed F_r."""
    t = table2_printed()
    out = []
    for k, r in t.iterrows():
        sz = float(sv.stepover(r.Sc_mm, r.RT_mm))
        fr = float(r.Fr_mm)
        row = {"row": k, "Sc": r.Sc_mm, "RT": r.RT_mm, "Fr_printed": fr,
               "V1": float(sv.block_volume_v1(r.Sc_mm, sz, fr)),
               "V1_star": float(sv.block_volume_v1_star(r.Sc_mm, r.RT_mm, fr)),
               "V2": float(sv.block_volume_v2(r.Sc_mm, sz, fr)),
               "exact_sweep": float(sv.scallop_area_exact(sz, r.RT_mm)) * fr,
               "heightfield_sweep": uncut_volume_per_cell(r.Sc_mm, r.RT_mm, fr, resolution),
               "heightfield_discrete": uncut_volume_per_cell(r.Sc_mm, r.RT_mm, fr, resolution, True)}
        out.append(row)
    return pd.DataFrame(out).set_index("row")


def table3_printed() -> dict:
    """Table 3 as printed (mm): ``traditional_machining``, ``traditional_toolpath``,
    ``constant_volume_machining``, ``constant_volume_toolpath``."""
    t = _table3_setup()["table3"]
    return {k.replace("_length_mm", ""): float(v) for k, v in t.items() if k.endswith("_length_mm")}
