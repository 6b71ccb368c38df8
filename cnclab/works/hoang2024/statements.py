"""Verdicts on Hoang (2024)'s abstract and conclusion sentences (recipes of
``data/qualitative_claims.csv``; each returns a :class:`cnclab.claims.Verdict` with its numbers and
states its threshold).

>>> shorter_toolpath().verdict
'HOLDS'
"""
from __future__ import annotations

from ...claims import Verdict
from ...cutting import scallop_volume as sv
from . import constant_volume as cv


def constant_volume_per_step() -> Verdict:
    """Abstract: "adjust the toolpath in such a way that the volume of this portion remains constant in
    each step of the tool". Measured per Table 2 row: the exact uncut volume of one S_z × F_r cell
    (swept ball, :func:`cnclab.cutting.scallop_volume.scallop_area_exact` × F_r) over the design V,
    with the unit-consistent F_r of eq. 7 and with the printed F_r. HOLDS when the consistent ratio is
    1 within 5 % on every row; PARTIAL when it is at least constant over the rows (spread <= 1 %) —
    the volume per step is then constant but not the V asked for."""
    t = cv.table2_printed()
    fc = cv.table2_fr_consistent()
    cons, prin = [], []
    for k, r in t.iterrows():
        area = float(sv.scallop_area_exact(float(sv.stepover(r.Sc_mm, r.RT_mm)), r.RT_mm))
        cons.append(area * fc[k] / r.V_mm3)
        prin.append(area * r.Fr_mm / r.V_mm3)
    if max(abs(c - 1) for c in cons) <= 0.05:
        v = "HOLDS"
    else:
        v = "PARTIAL" if max(cons) / min(cons) - 1 <= 0.01 else "FAILS"
    return Verdict(v, "exact uncut volume per cell / V over the 8 Table 2 rows, consistent F_r (eq. 7) and printed F_r",
                   {"consistent_ratio_min": min(cons), "consistent_ratio_max": max(cons),
                    "printed_ratio_min": min(prin), "printed_ratio_max": max(prin)})


def shorter_toolpath() -> Verdict:
    """Conclusion: "the proposed method yields a shorter toolpath compared to the traditional method" (and
    "the total length is less than one in the traditional method"): our Constant Volume program (Table 2
    row 2 on 100 × 50 mm, written and parsed back) vs the printed traditional (commercial CAM) lengths."""
    ours = cv.table3_lengths()
    p = cv.table3_printed()
    d_tot = p["traditional_toolpath"] - ours["toolpath"]
    d_mach = p["traditional_machining"] - ours["machining"]
    return Verdict("HOLDS" if d_tot > 0 and d_mach > 0 else "FAILS",
                   "traditional (printed) minus our constant-volume program length (mm)",
                   {"toolpath_shorter_by_mm": d_tot, "machining_shorter_by_mm": d_mach,
                    "toolpath_shorter_by_pct": 100 * d_tot / p["traditional_toolpath"]})


def edge_region_covered() -> Verdict:
    """Conclusion: "the Constant Volume method also has an advantage in the corresponding edge regions ...
    the accuracy remains the same for the entire surface": the covering pass (Fig. 9 N107 Y50.744)
    reaches past the 50 mm edge, and the last two passes are no farther apart than S_z (so the edge
    scallop is no higher than S_c)."""
    last, before = cv.fig9_last_pass_y(), cv.fig9_stop_y()
    sz = float(cv.table2_sz()["r2"])
    ok = last >= 50.0 and last - before <= sz + 1e-3
    return Verdict("HOLDS" if ok else "FAILS", "last pass y, pass before it, and their gap vs S_z (mm)",
                   {"last_pass_y": last, "previous_pass_y": before, "gap_mm": last - before, "S_z_mm": sz})
