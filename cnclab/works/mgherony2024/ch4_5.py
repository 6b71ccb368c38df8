"""Recipes for Mgherony (2024) chapters 4 and 5: surface inclination, working diameter, cutting speed.

Model: :mod:`cnclab.geometry.ball_end` (closed form of the Mikó–Zentay intersection-circle model, eq 5-3
angle convention). Inputs: ``data/mgherony2024/ch4_5_parameters.json`` and Tables 4-2, 4-3, 5-1.

What the recipes establish
--------------------------
- **Chapter 4 prints true diameters** (3.4 mm on the horizontal middle = ``2·sqrt(a_p (D − a_p))``).
  Table 4-2's angles are those of the *ball-centre* position on radius 45 ± 5 mm. The CV/CX effective
  diameters (3.4–6.8 / 3.4–5.8 mm) follow with the feed across the cylinder (A_f = 90°).
- **Chapter 5 prints radii labelled as diameters**: Table 5-1, §5.4–5.5 and Figs 5-8 … 5-13 give the
  tangent point's distance from the tool axis (max 4.530 < R = 5 mm for a_p = 0.3), and the v_c values
  are computed from that radius (and, in Table 5-1, from the radius rounded as printed). The true
  diameter and cutting speed are twice as large, so the §5.5 conclusion "the highest actual cutting
  speed reaches half of the nominal" is an artefact: the true fraction is 0.906.
- Table 5-1's D_eff min "0.005" is the radius 0.0044994 mm displayed with four decimals (0.0045) and then
  rounded again to three (double rounding); its v_c min "0.06" and max "54.36" are ``π·n·d/1000`` of the
  rounded radii 0.005 and 4.530 (the unrounded radii give 0.054 and 54.37; §5.5's text says 0.05).
- The printed extremes and locations are hit on an ``A_N2`` grid of step 2.5° (−45 … 45) and any ``A_N1``
  grid through 120° and 150° restricted to 0 … 180° (on 0 … 360° each extreme has an exact twin at
  ``(A_N1 + 180°, −A_N2)``).
- Eq 5-1 as printed ('+') gives 13.72 mm for D = 10, a_p = 0.3 (larger than the tool): erratum.
- Table 4-3's v_c = 1600 m/min is ten times ``π·D·n/1000`` = 160.2 m/min.
"""
from __future__ import annotations

import functools
import json
from decimal import ROUND_HALF_UP, Decimal

import numpy as np
import pandas as pd

from ...claims import Interval
from ...cutting.speeds import cutting_speed, feed_speed
from ...geometry.ball_end import (angles_from_normal, cut_point_radii, eq5_1_as_printed_diameter,
                                  horizontal_effective_diameter, paper_deff_radius_valued,
                                  tangent_point_diameters, tangent_point_radii)
from ...geometry.cylinder_parts import MEASURING_POSITIONS_MM, CylinderPart
from ...paths import data_path


# ------------------------------------------------------------------------------------------ inputs
@functools.cache
def parameters() -> dict:
    """The transcribed model/simulation inputs of chapters 4–5 (``ch4_5_parameters.json``)."""
    with open(data_path("mgherony2024", "ch4_5_parameters.json"), encoding="utf-8") as fh:
        return json.load(fh)


@functools.cache
def table4_2() -> pd.DataFrame:
    """Table 4-2 as printed (normal angles, degrees, by signed measuring position y in mm)."""
    return pd.read_csv(data_path("mgherony2024", "ch4_table4-2_normal_angles.csv"), comment="#")


@functools.cache
def table4_3() -> pd.DataFrame:
    """Table 4-3 as printed (cutting parameters of the five CV/CX test surfaces)."""
    return pd.read_csv(data_path("mgherony2024", "ch4_table4-3_cutting_parameters.csv"), comment="#")


@functools.cache
def table5_1_printed() -> pd.DataFrame:
    """Table 5-1 as printed (for side-by-side display; claims compute their own values)."""
    return pd.read_csv(data_path("mgherony2024", "ch5_table5-1_simulation.csv"), comment="#")


def thesis_display(value_mm: float) -> float:
    """A value as the thesis prints it: shown with 4 decimals (Matlab ``format short``), then rounded
    half-up to the 3 decimals of Table 5-1 (0.0044994 → 0.0045 → 0.005)."""
    four = Decimal(repr(round(float(value_mm), 4)))
    return float(four.quantize(Decimal("0.001"), rounding=ROUND_HALF_UP))


# --------------------------------------------------------------------------------------- chapter 4
def _ch4_part(kind: str) -> CylinderPart:
    p = parameters()["ch4"]
    return CylinderPart(kind, radius=p["cylinder_radius_mm"], fillet_radius=p["fillet_radius_mm"])


def table4_2_normal_angles_deg() -> dict:
    """Table 4-2 recomputed: normal angle (deg) at each ball-centre position, keys ``"CX_-25"`` … ``"CV_25"``."""
    D = parameters()["ch4"]["tool_diameter_mm"]
    out = {}
    for kind in ("CX", "CV"):
        ang = _ch4_part(kind).normal_angle_at_tool_y_deg(MEASURING_POSITIONS_MM, D)
        out.update({f"{kind}_{int(y)}": float(a) for y, a in zip(MEASURING_POSITIONS_MM, ang)})
    return out


def table4_2_angles_on_part_surface_deg() -> dict:
    """The same positions read as *surface* y (sin = y/45): 33.7° at ±25 — not what Table 4-2 prints."""
    out = {}
    for kind in ("CX", "CV"):
        ang = _ch4_part(kind).normal_angle_at_surface_y_deg(MEASURING_POSITIONS_MM)
        out.update({f"{kind}_{int(y)}": float(a) for y, a in zip(MEASURING_POSITIONS_MM, ang)})
    return out


@functools.cache
def ch4_effective_diameters() -> pd.DataFrame:
    """Figs 4-2/4-3: true effective diameter (mm) and actual v_c (m/min) at each measuring point.

    Feed across the cylinder (A_f = 90°), D = 10, a_p = 0.3, n = 5100; tangent points 1 and 2 coincide by
    symmetry (the tilt is parallel to the feed).
    """
    p = parameters()["ch4"]
    D, a_p, n = p["tool_diameter_mm"], p["a_p_mm"], p["n_rpm"]
    rows = []
    for kind in ("CV", "CX"):
        part = _ch4_part(kind)
        A1, A2 = angles_from_normal(part.normal_at_tool_y(MEASURING_POSITIONS_MM, D))
        d1, d2 = tangent_point_diameters(D, a_p, A1, A2, 90.0)
        for y, ang, a, b in zip(MEASURING_POSITIONS_MM, part.normal_angle_at_tool_y_deg(MEASURING_POSITIONS_MM, D),
                                d1, d2):
            rows.append({"part": kind, "y_mm": y, "normal_angle_deg": float(ang), "D_eff1_mm": float(a),
                         "D_eff2_mm": float(b), "v_c_m_min": float(cutting_speed(a, n))})
    return pd.DataFrame(rows)


def ch4_deff_range_mm() -> dict:
    """§4.2: min/max effective diameter (mm) over the measuring points, keys ``CV_min`` … ``CX_max``."""
    df = ch4_effective_diameters()
    out = {}
    for kind, g in df.groupby("part"):
        out[f"{kind}_min"] = float(g.D_eff1_mm.min())
        out[f"{kind}_max"] = float(g.D_eff1_mm.max())
    return out


def ch4_normal_angle_at_min_deff_deg() -> float:
    """§4.2: the normal angle (deg) where D_eff and v_c are smallest (largest |angle| over CV and CX)."""
    df = ch4_effective_diameters()
    return float(max(abs(g.normal_angle_deg.iloc[int(np.argmin(g.D_eff1_mm.to_numpy()))])
                     for _, g in df.groupby("part")))


def ch4_cx_cutting_speed_at_15mm() -> float:
    """v_c (m/min) of the CX measuring points y = ±15 mm — the "70 m/min" of §4.3 (neighbours 62.5, 81.4)."""
    df = ch4_effective_diameters()
    g = df[(df.part == "CX") & (df.y_mm.abs() == 15)]
    return float(g.v_c_m_min.mean())


def ch4_cx_cutting_speeds_m_min() -> list:
    """All distinct CX measuring-point cutting speeds (m/min), ascending."""
    df = ch4_effective_diameters()
    return sorted(set(np.round(df[df.part == "CX"].v_c_m_min, 6)))


def table4_3_nominal_cutting_speed() -> float:
    """Nominal cutting speed (m/min) of Table 4-3: ``π·D·n/1000`` with D = 10 mm, n = 5100 rpm (160.2)."""
    p = parameters()["ch4"]
    return float(cutting_speed(p["tool_diameter_mm"], p["n_rpm"]))


def table4_3_cutting_speed_extra_zero() -> float:
    """The printed 1600 m/min explained: ten times the nominal value (one zero too many)."""
    return 10.0 * table4_3_nominal_cutting_speed()


def table4_3_feed_speeds() -> dict:
    """Table 4-3's v_f (mm/min) = f_z·z·n per test id (``CV-01`` …), eq 7-5."""
    t = table4_3()
    z = parameters()["ch4"]["teeth"]
    return {row.test_cv: float(feed_speed(row.f_z_mm, z, row.n_rpm)) for row in t.itertuples()}


def eq5_1_horizontal_diameter_ch4() -> float:
    """Corrected eq 5-1 (mm) for chapter 4's D = 10, a_p = 0.3: the 3.41 mm of the horizontal middle point."""
    p = parameters()["ch4"]
    return float(horizontal_effective_diameter(p["tool_diameter_mm"], p["a_p_mm"]))


def eq5_1_as_printed_ch4() -> float:
    """Eq 5-1 as printed for D = 10, a_p = 0.3: 13.72 mm (larger than the 10 mm tool)."""
    p = parameters()["ch4"]
    return float(eq5_1_as_printed_diameter(p["tool_diameter_mm"], p["a_p_mm"]))


# --------------------------------------------------------------------------------------- chapter 5
def angle_grid(step_AN1: float = 2.5, step_AN2: float = 2.5, AN1_range=(0.0, 180.0), AN2_range=(-45.0, 45.0)):
    """``(A_N1, A_N2)`` meshgrid (degrees, ``indexing="ij"``) with the given steps and inclusive ranges."""
    a1 = np.arange(AN1_range[0], AN1_range[1] + 1e-9, step_AN1)
    a2 = np.arange(AN2_range[0], AN2_range[1] + 1e-9, step_AN2)
    return np.meshgrid(a1, a2, indexing="ij")


def grid_extremes(D: float, a_p: float, A_f: float, AN1, AN2, point: int) -> dict:
    """Min/max of the working **radius** (mm) of tangent point ``point`` over the angle grid, with locations."""
    r = tangent_point_radii(D, a_p, AN1, AN2, A_f)[point - 1]
    i, j = int(np.argmin(r)), int(np.argmax(r))
    return {"min": float(r.flat[i]), "AN1_min": float(AN1.flat[i]), "AN2_min": float(AN2.flat[i]),
            "max": float(r.flat[j]), "AN1_max": float(AN1.flat[j]), "AN2_max": float(AN2.flat[j])}


def _sim():
    p = parameters()["ch5_fig5_10"]
    return p["tool_diameter_mm"], p["n_rpm"]


@functools.cache
def table5_1_model() -> dict:
    """Table 5-1 from the model: true diameters/speeds, paper-convention values and locations.

    Keys ``Af{30|60}_p{1|2}_<q>`` with ``<q>`` in: ``deff_min``/``deff_max`` (true diameter, mm),
    ``vc_min``/``vc_max`` (true v_c, m/min), ``paper_deff_min``/``paper_deff_max`` (radius as the thesis
    prints it, :func:`thesis_display`), ``paper_vc_min``/``paper_vc_max`` (v_c from the printed radius),
    ``AN1_min``, ``AN2_min``, ``AN1_max``, ``AN2_max`` (degrees).
    """
    D, n = _sim()
    AN1, AN2 = angle_grid()
    out = {}
    for A_f in (30, 60):
        for pt in (1, 2):
            e = grid_extremes(D, 0.3, A_f, AN1, AN2, pt)
            k = f"Af{A_f}_p{pt}_"
            for q in ("min", "max"):
                out[k + f"deff_{q}"] = 2 * e[q]
                out[k + f"vc_{q}"] = float(cutting_speed(2 * e[q], n))
                out[k + f"paper_deff_{q}"] = thesis_display(e[q])
                out[k + f"paper_vc_{q}"] = float(cutting_speed(thesis_display(e[q]), n))
                out[k + f"paper_vc_{q}_unrounded"] = float(cutting_speed(e[q], n))
                out[k + f"AN1_{q}"] = e[f"AN1_{q}"]
                out[k + f"AN2_{q}"] = e[f"AN2_{q}"]
    return out


@functools.cache
def ap1_extremes() -> dict:
    """§5.5 in-text values for a_p = 1 mm, A_f = 30° (Figs 5-10, 5-11): same keys as :func:`table5_1_model`
    with prefix ``p{1|2}_``; ``paper_vc_*`` use the unrounded radius (59.40, 0.660)."""
    D, n = _sim()
    AN1, AN2 = angle_grid()
    out = {}
    for pt in (1, 2):
        e = grid_extremes(D, 1.0, 30, AN1, AN2, pt)
        vc = cutting_speed(2 * tangent_point_radii(D, 1.0, AN1, AN2, 30)[pt - 1], n)
        i, j = int(np.argmin(vc)), int(np.argmax(vc))
        k = f"p{pt}_"
        for q in ("min", "max"):
            out[k + f"deff_{q}"] = 2 * e[q]
            out[k + f"paper_deff_{q}"] = e[q]
            out[k + f"vc_{q}"] = float(cutting_speed(2 * e[q], n))
            out[k + f"paper_vc_{q}"] = float(cutting_speed(e[q], n))
            out[k + f"AN1_{q}"] = e[f"AN1_{q}"]
            out[k + f"AN2_{q}"] = e[f"AN2_{q}"]
        out[k + "vc_AN1_min"], out[k + "vc_AN2_min"] = float(AN1.flat[i]), float(AN2.flat[i])
        out[k + "vc_AN1_max"], out[k + "vc_AN2_max"] = float(AN1.flat[j]), float(AN2.flat[j])
    out["minmax_p1_vs_p2_abs_diff"] = max(abs(out["p1_deff_min"] - out["p2_deff_min"]),
                                          abs(out["p1_deff_max"] - out["p2_deff_max"]))
    return out


def ch5_text_vc_range() -> dict:
    """§5.5 "ranging from 0.05 to 54.5 m/min" (a_p = 0.3): true v_c and radius-based v_c (unrounded)."""
    t = table5_1_model()
    return {"true_min": t["Af30_p1_vc_min"], "true_max": t["Af30_p1_vc_max"],
            "paper_min": t["Af30_p1_paper_vc_min_unrounded"], "paper_max": t["Af30_p1_paper_vc_max_unrounded"]}


def nominal_cutting_speed_ch5() -> float:
    """§5.5: v_c (m/min) of the 10 mm nominal diameter at n = 3820 rpm (printed as 120 m/min)."""
    D, n = _sim()
    return float(cutting_speed(D, n))


def highest_speed_fraction_of_nominal() -> dict:
    """§5.5 "the highest actual cutting speed reaches half of the nominal": true (0.906) vs radius-based (0.453)."""
    t = table5_1_model()
    nominal = parameters()["ch5_fig5_10"]["nominal_v_c_m_min"]
    return {"true": t["Af30_p1_vc_max"] / nominal,
            "paper_convention": t["Af30_p1_paper_vc_max_unrounded"] / nominal}


def map_shift_between_feed_directions_deg() -> float:
    """§5.5: shift (deg along A_N1) that maps the A_f = 30° radius map onto the A_f = 60° one (step 2.5°)."""
    D, _ = _sim()
    AN1, AN2 = angle_grid(AN1_range=(0.0, 357.5))
    r30 = tangent_point_radii(D, 0.3, AN1, AN2, 30)[0]
    r60 = tangent_point_radii(D, 0.3, AN1, AN2, 60)[0]
    step = AN1[1, 0] - AN1[0, 0]
    errs = [np.abs(np.roll(r30, k, axis=0) - r60).max() for k in range(AN1.shape[0])]
    return float(int(np.argmin(errs)) * step)


def grid_steps_reproducing_extremes(steps_AN2=(0.5, 1.0, 1.25, 2.5, 5.0, 7.5, 15.0),
                                    steps_AN1=(1.0, 2.5, 5.0, 7.5, 10.0, 15.0, 30.0, 45.0)) -> pd.DataFrame:
    """Which ``A_N1``/``A_N2`` grid steps (deg; ranges 0…180 and −45…45) reproduce every printed extreme.

    Checked: Table 5-1 (a_p = 0.3, A_f = 30°/60°, radius displayed as printed and locations) and the §5.5
    a_p = 1 values (0.055 at ±37.5°, 4.950 at ±45°, A_N1 = 120°).
    """
    D, _ = _sim()
    printed = table5_1_printed()
    rows = []
    for s1 in steps_AN1:
        for s2 in steps_AN2:
            AN1, AN2 = angle_grid(s1, s2)
            ok = True
            for r in printed.itertuples():
                e = grid_extremes(D, 0.3, r.A_f_deg, AN1, AN2, r.point)
                ok &= (thesis_display(e["min"]) == r.deff_min_mm and thesis_display(e["max"]) == r.deff_max_mm
                       and (e["AN1_min"], e["AN2_min"], e["AN1_max"], e["AN2_max"])
                       == (r.AN1_min_deg, r.AN2_min_deg, r.AN1_max_deg, r.AN2_max_deg))
            for pt, sgn in ((1, 1.0), (2, -1.0)):
                e = grid_extremes(D, 1.0, 30, AN1, AN2, pt)
                ok &= (round(e["min"], 3) == 0.055 and round(e["max"], 3) == 4.950
                       and (e["AN1_min"], e["AN2_min"], e["AN1_max"], e["AN2_max"]) == (120, -37.5 * sgn, 120, 45 * sgn))
            rows.append({"step_AN1_deg": s1, "step_AN2_deg": s2, "reproduces_all": bool(ok)})
    return pd.DataFrame(rows)


@functools.cache
def fig5_8_ranges() -> dict:
    """Figs 5-8/5-9 (D = 10, A_N1 = 35°, A_N2 = 25°, A_f = 0…180°): ranges of points 1 and 2.

    Keys ``ap{1|0.3}_p{1|2|all}_{min|max}`` — radius (paper convention) — and ``true_`` + the same key
    (diameter, mm). Also ``switch_identity``: |D_eff1(A_f = 180°) − D_eff2(A_f = 0°)| (mm).
    """
    p = parameters()["ch5_fig5_8"]
    D, a1, a2 = p["tool_diameter_mm"], p["A_N1_deg"], p["A_N2_deg"]
    A_f = np.linspace(p["A_f_range_deg"][0], p["A_f_range_deg"][1], 7201)
    out = {}
    for ap in p["a_p_mm"]:
        r1, r2 = tangent_point_radii(D, ap, a1, a2, A_f)
        tag = f"ap{ap:g}"
        for name, arr in (("p1", r1), ("p2", r2), ("all", np.concatenate([r1, r2]))):
            for q, fn in (("min", np.min), ("max", np.max)):
                out[f"{tag}_{name}_{q}"] = float(fn(arr))
                out[f"true_{tag}_{name}_{q}"] = 2 * float(fn(arr))
    d1_180 = tangent_point_diameters(D, 1.0, a1, a2, 180.0)[0]
    d2_0 = tangent_point_diameters(D, 1.0, a1, a2, 0.0)[1]
    out["switch_identity"] = float(abs(d1_180 - d2_0))
    return out


def fig5_6_curves(a_p=None, a_e: float = 1.0) -> pd.DataFrame:
    """Fig 5-6: true working diameters (mm) at points 1, 1′ (up-milling end), 1″ (down-milling start) vs a_p."""
    p = parameters()["ch5_fig5_6"]
    a_p = np.linspace(*p["a_p_range_mm"], 91) if a_p is None else np.asarray(a_p, float)
    rows = []
    for D in p["tool_diameters_mm"]:
        c = cut_point_radii(D, a_p, a_e, p["A_N1_deg"], p["A_N2_deg"], p["A_f_deg"]).scaled(2.0)
        rows.append(pd.DataFrame({"D_mm": D, "a_p_mm": a_p, "d1_mm": c.p1, "d1_lead_mm": c.p1_lead,
                                  "d1_trail_mm": c.p1_trail, "d2_mm": c.p2}))
    return pd.concat(rows, ignore_index=True)


def fig5_6_half_diameter_ratio() -> Interval:
    """§5.3 "At a_p = 0.1 mm the tool operates with half its diameter": true D_eff/D at points 1, 2 over D = 6, 8, 10."""
    p = parameters()["ch5_fig5_6"]
    ratios = []
    for D in p["tool_diameters_mm"]:
        d1, d2 = tangent_point_diameters(D, 0.1, p["A_N1_deg"], p["A_N2_deg"], p["A_f_deg"])
        ratios += [float(d1) / D, float(d2) / D]
    return Interval(min(ratios), max(ratios))


def fig5_6_half_diameter_ratio_radius_convention() -> Interval:
    """The same ratio with the chapter-5 radius convention (what Fig 5-6 plots): about a quarter."""
    iv = fig5_6_half_diameter_ratio()
    return Interval(iv.lo / 2, iv.hi / 2)


def fig5_7_variation(a_e=None) -> pd.DataFrame:
    """Fig 5-7: change of the true working diameter (mm) over one chip removal vs a_e, up/down, D = 6, 8, 10.

    Side 1 (Fig 5-5 a/b): up-milling 1→1′, down-milling 1″→1; ``variation_mm`` = |end − start| × 2.
    """
    p = parameters()["ch5_fig5_7"]
    a_e = np.linspace(*p["a_e_range_mm"], 51) if a_e is None else np.asarray(a_e, float)
    rows = []
    for D in p["tool_diameters_mm"]:
        c = cut_point_radii(D, p["a_p_mm"], a_e, p["A_N1_deg"], p["A_N2_deg"], p["A_f_deg"]).scaled(2.0)
        for mode, start, end in (("up", c.p1, c.p1_lead), ("down", c.p1_trail, c.p1)):
            rows.append(pd.DataFrame({"D_mm": D, "milling": mode, "a_e_mm": a_e, "start_mm": start,
                                      "end_mm": end, "variation_mm": np.abs(end - start)}))
    return pd.concat(rows, ignore_index=True)


def similar_vs_larger_summary() -> pd.DataFrame:
    """§5.3 ("similar ranges for D = 6/8/10") vs Thesis 1 ("larger for larger D and down milling"), a_e = 1.

    Variation of the true working diameter (mm) and its ratio to the D = 6 mm value.
    """
    df = fig5_7_variation(a_e=[1.0])
    df = df[["D_mm", "milling", "variation_mm"]].copy()
    df["ratio_to_D6"] = df.variation_mm / df.groupby("milling").variation_mm.transform("first")
    return df.reset_index(drop=True)


def surface_map(a_p: float, A_f: float, step: float = 2.5):
    """Figs 5-10 … 5-13: ``(AN1, AN2, r1, r2)`` grids — working radii (mm, paper convention) of points 1, 2."""
    D, _ = _sim()
    AN1, AN2 = angle_grid(step, step)
    r1, r2 = paper_deff_radius_valued(D, a_p, AN1, AN2, A_f)
    return AN1, AN2, r1, r2


# ------------------------------------------------------------------------------ ledger audit (issue 13)
def ch4_cx_cutting_speed_at_15mm_truncated() -> float:
    """Explanation of §4.3's "70 m/min": the CX measuring point y = ±15 mm runs at 70.9 m/min, printed
    truncated to whole m/min as the thesis prints 5877.8 rpm as 5877 (Sec. 7.3)."""
    return float(np.floor(ch4_cx_cutting_speed_at_15mm()))


def table5_1_printed_values() -> dict:
    """Table 5-1 as printed for A_f = 30°, point 1 (the §5.5 text restates it): ``deff_min``, ``deff_max``
    (mm), ``vc_min``, ``vc_max`` (m/min)."""
    r = table5_1_printed()
    r = r[(r.A_f_deg == 30) & (r.point == 1)].iloc[0]
    return {"deff_min": float(r.deff_min_mm), "deff_max": float(r.deff_max_mm),
            "vc_min": float(r.vc_min_m_min), "vc_max": float(r.vc_max_m_min)}


def nominal_cutting_speed_from_printed() -> float:
    """§5.5: v_c = π·D·n/1000 (m/min) from the printed D = 10 mm and n = 3820 1/min."""
    return nominal_cutting_speed_ch5()


def variation_ratio_D10_to_D6(milling: str = "down") -> float:
    """§5.3 "similar ranges" vs Thesis 1 "larger for larger D": the true working-diameter variation over
    one chip removal (a_e = 1, Fig 5-7 settings) for D = 10 over D = 6 (down milling)."""
    s = similar_vs_larger_summary()
    s = s[s.milling == milling].set_index("D_mm")
    return float(s.loc[10.0, "variation_mm"] / s.loc[6.0, "variation_mm"])


def thesis1_larger_for_larger_D_and_down() -> float:
    """Thesis 1 "This variation is larger for larger nominal tool diameters and down milling technology":
    1.0 when the variation (a_e = 1) grows with D for both up and down milling and down > up at every D."""
    s = similar_vs_larger_summary()
    up = s[s.milling == "up"].sort_values("D_mm").variation_mm.to_numpy()
    down = s[s.milling == "down"].sort_values("D_mm").variation_mm.to_numpy()
    return float(bool(np.all(np.diff(up) > 0) and np.all(np.diff(down) > 0) and np.all(down > up)))
