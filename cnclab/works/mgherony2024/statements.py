"""Verdicts on Mgherony (2024)'s thesis points, chapter conclusions and headline sentences.

Each function is a recipe of ``data/qualitative_claims.csv``: it returns a
:class:`cnclab.claims.Verdict` (``HOLDS`` / ``PARTIAL`` / ``FAILS``) computed from cnclab's
reproduction, with the numbers it rests on and the threshold stated in the text. The statements are
qualitative, so each threshold is a reading of the sentence, written down here once.

>>> v = thesis1_cutting_speed_varies()
>>> v.verdict
'HOLDS'
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from ...analysis import response_surface as rs
from ...claims import Verdict
from . import ch3, ch4_5, ch6, ch7_9


def _v(ok: bool, text: str, numbers: dict, partial: bool = False) -> Verdict:
    return Verdict("HOLDS" if ok else ("PARTIAL" if partial else "FAILS"), text, numbers)


# ------------------------------------------------------------------------------ chapter 3
def ch3_trends_feed_depth_radius() -> Verdict:
    """§3.4: larger feed (turning) / depth of cut (milling) -> rougher; larger corner radius -> smoother.

    Measured Table 3-4 Ra and Rz (transcribed inputs): every pair of parts differing in one factor is
    compared; HOLDS when every pair moves the stated way."""
    df = ch3.parts()
    agree, total = 0, 0
    for proc, g in df.groupby("process"):
        for a in g.index:
            for b in g.index:
                A, B = g.loc[a], g.loc[b]
                for resp in ("Ra_um", "Rz_um"):
                    if A.RE_mm == B.RE_mm and A.p_mm < B.p_mm:      # more feed / depth: rougher
                        total += 1
                        agree += B[resp] > A[resp]
                    if A.p_mm == B.p_mm and A.RE_mm < B.RE_mm:      # larger radius: smoother
                        total += 1
                        agree += B[resp] < A[resp]
    return _v(agree == total, f"{agree} of {total} one-factor pairs of Table 3-4 (Ra and Rz) move the stated way",
              {"pairs_agreeing": int(agree), "pairs": int(total)})


def ch3_cusp_height_same_trend() -> Verdict:
    """§3.4 "the calculated cusp height exhibits the same trend as the measured surface roughness":
    Spearman rank correlation of CH with measured Ra and Rz over the ten parts; HOLDS when both >= 0.8."""
    df = ch3.parts()
    r = {resp: float(df["CH_um"].rank().corr(df[resp].rank())) for resp in ("Ra_um", "Rz_um")}
    return _v(min(r.values()) >= 0.8, "Spearman rank correlation of CH with measured Ra / Rz (threshold 0.8)",
              {"spearman_Ra": r["Ra_um"], "spearman_Rz": r["Rz_um"]})


def ch3_rz_more_suitable() -> Verdict:
    """§3.4 "the hybrid model indicates that the Rz parameter is more suitable": the hybrid fit's
    adjusted R² (inverse form, the printed coefficients' form) is higher for Rz than for Ra."""
    s = ch3.statistics()
    ra, rz = s["hybrid.inverse.Ra.R2adj_pct"], s["hybrid.inverse.Rz.R2adj_pct"]
    return _v(rz > ra, "adjusted R² of the hybrid model C(RE, p), Rz vs Ra (%)", {"R2adj_Ra_pct": ra, "R2adj_Rz_pct": rz})


# ------------------------------------------------------------------------------ chapters 4-5
def ch4_speed_drops_at_normal_axis() -> Verdict:
    """§4.4 "the cutting speed diminishes significantly when the ball-end mill's normal axis is applied to
    the workpiece surface": v_c at the normal-0 point vs the largest v_c over the CV/CX measuring
    points; HOLDS when the drop is >= 25 % (a quarter: 'significantly')."""
    t = ch4_5.ch4_effective_diameters()
    lo = float(t.loc[t.normal_angle_deg.abs() < 1e-9, "v_c_m_min"].min())
    hi = float(t.v_c_m_min.max())
    return _v(lo <= 0.75 * hi, "v_c (m/min) at the normal-0 point vs the largest over the measuring points",
              {"v_c_normal0": lo, "v_c_max": hi, "drop_pct": 100 * (1 - lo / hi)})


def thesis1_cutting_speed_varies() -> Verdict:
    """Thesis 1 "the working diameter and therefore the cutting speed varies during the chip removal":
    the working-diameter change over one chip removal (a_e = 1, Fig 5-7 settings) exceeds 0.1 mm
    for every D and milling mode."""
    s = ch4_5.similar_vs_larger_summary()
    return _v(bool((s.variation_mm > 0.1).all()), "working-diameter change over one chip removal (mm), D = 6/8/10, up/down",
              {"min_variation_mm": float(s.variation_mm.min()), "max_variation_mm": float(s.variation_mm.max())})


def thesis1_larger_for_larger_D_and_down() -> Verdict:
    """Thesis 1 "This variation is larger for larger nominal tool diameters and down milling technology"."""
    s = ch4_5.similar_vs_larger_summary().set_index(["D_mm", "milling"]).variation_mm
    ok = bool(ch4_5.thesis1_larger_for_larger_D_and_down())
    return _v(ok, "variation grows with D (6 < 8 < 10) for up and down milling, and down > up at every D",
              {f"D{int(d)}_{m}_mm": float(v) for (d, m), v in s.items()})


def ch5_similar_ranges() -> Verdict:
    """§5.3 "the variations in working diameter exhibit similar ranges despite employing different tool
    diameters": D = 10 over D = 6 variation within ±20 % of 1 ('similar')."""
    down, up = ch4_5.variation_ratio_D10_to_D6("down"), ch4_5.variation_ratio_D10_to_D6("up")
    return _v(max(abs(down - 1), abs(up - 1)) <= 0.2, "variation ratio D = 10 / D = 6 (threshold ±20 %)",
              {"ratio_down": down, "ratio_up": up})


def thesis1_feed_direction_significant() -> Verdict:
    """Thesis 1 "the feed direction has a significant effect on the value of the working diameter":
    the spread of D_eff over A_f = 0…180° (Figs 5-8/5-9 settings) exceeds 10 % of D."""
    r = ch4_5.fig5_8_ranges()
    spread = {ap: r[f"true_ap{ap}_all_max"] - r[f"true_ap{ap}_all_min"] for ap in ("1", "0.3")}
    return _v(min(spread.values()) > 1.0, "D_eff spread (mm) over A_f = 0…180°, D = 10 (threshold 1 mm = 10 % of D)",
              {"spread_ap1_mm": spread["1"], "spread_ap0.3_mm": spread["0.3"]})


def ch6_relative_feed_direction() -> Verdict:
    """§6.4 "Introducing the relative feed direction allows us to reduce the number of input parameters
    due to the periodic nature of the geometric model": the D_eff map shifts by exactly the change of
    A_f (30° between A_f = 30 and 60), so A_N1 and A_f enter only as A_N1 − A_f."""
    s = ch4_5.map_shift_between_feed_directions_deg()
    return _v(abs(s - 30.0) < 1e-9, "shift of the D_eff map along A_N1 between A_f = 30° and 60° (deg)", {"shift_deg": s})


# ------------------------------------------------------------------------------ chapter 6
def thesis2_fifth_powers_essential() -> Verdict:
    """Thesis 2 "to create an accurate regression model, it is essential to include the first, third, and
    fifth powers of both the surface inclination and the relative feed direction": dropping the
    fifth-power terms from r1 must cost >= 1 point of adjusted R² (or raise S by >= 10 %)."""
    full = ch6.r1_fit()
    no5 = rs.fit_polynomial(ch6.dataset(), "D_eff1", tuple(t for t in rs.R1_TERMS if t.powers.get("A_N2", 0) < 5))
    no35 = rs.fit_polynomial(ch6.dataset(), "D_eff1", tuple(t for t in rs.R1_TERMS if t.powers.get("A_N2", 0) < 3))
    d_r2 = full.r_sq_adj - no5.r_sq_adj          # both in %
    ok = d_r2 >= 1.0 or no5.S >= 1.1 * full.S
    return _v(ok, "r1 with and without the AN2^5 terms (and without AN2^3, AN2^5): adjusted R² (%) and S (mm); "
              "threshold: dropping the fifth powers costs >= 1 point of R²adj or +10 % S",
              {"R2adj_full_pct": full.r_sq_adj, "R2adj_without_5th_pct": no5.r_sq_adj,
               "R2adj_without_3rd_5th_pct": no35.r_sq_adj, "S_full_mm": full.S, "S_without_5th_mm": no5.S})


def s6_3_1_r2adj_95() -> Verdict:
    """§6.3.1 "The accuracy of the regression is improved, the values of the R₂adj parameter are up to 95%
    in every case" (Table 6-2 prints 95.7 … 97.1): read as "at least 95 %", the adjusted R² of each of
    the four r2 fits is >= 95 % and above r1's."""
    v = ch6.r2_values()
    per_d = {k: float(x) for k, x in v.items() if k.startswith("rsq_adj.D")}
    r1 = float(ch6.r1_values()["rsq_adj"])
    return _v(min(per_d.values()) >= 95.0 and min(per_d.values()) > r1,
              "adjusted R² (%) of the four per-D r2 fits vs 95 % and vs r1's",
              {**{k.replace("rsq_adj.", "R2adj_"): x for k, x in per_d.items()}, "R2adj_r1": r1})


def thesis2_separate_model_more_accurate() -> Verdict:
    """Thesis 2 "a separated regression model based on tool diameter, which results in higher accuracy":
    RMSE of the unified r2 model (eq 6-5) below r1's over the 2704 rows."""
    t = ch6.regression_statistics()
    a, b = float(t.loc["rmse", "r1"]), float(t.loc["rmse", "r2 (unified, eq 6-5)"])
    return _v(b < a, "RMSE (mm) of r1 vs the unified r2 (eq 6-5) over the Table 6-1 plan", {"rmse_r1": a, "rmse_r2": b})


def ch6_ann_best() -> Verdict:
    """§6.4 "The ANN-based model performed the best, with the standard deviation, RMSE, and MAPE values all
    improving consistently": every LM seed of a1 and a2 beats r2 on st_dev, RMSE and MAPE."""
    reg = ch6.regression_statistics()["r2 (unified, eq 6-5)"]
    share, nums = [], {}
    for m in ("a1", "a2"):
        st = ch6.ann_statistics(m)
        better = (st[["st_dev", "rmse", "mape"]] < reg[["st_dev", "rmse", "mape"]].to_numpy()).all(axis=1)
        share.append(float(better.mean()))
        nums[f"{m}_share_of_seeds_better"] = share[-1]
        nums[f"{m}_median_rmse"] = float(st.rmse.median())
    nums["r2_rmse"] = float(reg["rmse"])
    return _v(min(share) == 1.0, "share of LM seeds whose network beats r2 on st_dev, RMSE and MAPE", nums,
              partial=max(share) > 0)


def ch6_a2_smallest_error() -> Verdict:
    """§6.3.3 "The a2 ANN model results in the smallest error in all cases": a2 beats a1 on every Table 6-3
    statistic for every seed pair."""
    s = ch6.ann_a2_beats_a1_share()
    return _v(s == 1.0, "share of seed pairs where a2 beats a1 on range, st_dev, RMSE, MAPE and R²", {"share": s},
              partial=s > 0)


# ------------------------------------------------------------------------------ chapters 7-9
def thesis3_constant_cutting_speed() -> Verdict:
    """Thesis 3 / §7.4: the spindle-speed control keeps v_c constant (63 m/min) along the A_f = 0 path of
    the STL + APT pipeline: within ±1 m/min (the facet normals of a discretised surface)."""
    iv = ch7_9.vc_controlled_range()
    return _v(iv.lo >= 62.0 and iv.hi <= 64.0, "actual v_c (m/min) after control over the A_f = 0 path",
              {"v_c_min": iv.lo, "v_c_max": iv.hi})


def thesis3_greater_dynamic_stress() -> Verdict:
    """Thesis 3 / §8.4 item 3: controlled spindle speed "introduces greater dynamic stress", and the integral
    of n along the path tells the milling directions apart: controlled/constant integral > 1 in every
    direction, and the directions' controlled integrals differ by >= 5 %."""
    t = ch7_9.direction_table()
    ratio = (t.integral_controlled / t.integral_constant)
    spread = float(t.integral_controlled.max() / t.integral_controlled.min() - 1)
    return _v(bool((ratio > 1).all()) and spread >= 0.05,
              "integral of n along the path, controlled / constant (per direction), and spread over directions",
              {"ratio_min": float(ratio.min()), "ratio_max": float(ratio.max()), "direction_spread_pct": 100 * spread})


def thesis5_reduces_spindle_speed_range() -> Verdict:
    """Thesis 5 "the optimized toolpath notably reduces the range of spindle speed values": the reordered
    path visits the same points, so the range of n is unchanged; the largest step |Δn| between
    consecutive points shrinks (case 1 vs original). PARTIAL when only the step shrinks (by >= 20 %)."""
    o, c = ch7_9.deltas("original"), ch7_9.deltas(1)
    frac = ch7_9.ch9_dn_max_reduction()
    return Verdict("PARTIAL" if frac <= 0.8 else "FAILS",
                   "the range of n is that of the same point set (unchanged); max |Δn| of case 1 / original",
                   {"max_dn_original_rpm": float(o["dn"].max()), "max_dn_case1_rpm": float(c["dn"].max()),
                    "ratio": frac, "printed_ratio": 128 / 622})


def ch9_reduces_deff_change() -> Verdict:
    """§9.4 "reducing the change in effective diameter ... was evidenced in the controlled working diameter
    variation observed in the improved tool path": median and max |ΔD_eff| between consecutive points,
    case 1 vs original; HOLDS when both shrink."""
    o, c = ch7_9.deltas("original"), ch7_9.deltas(1)
    nums = {"median_dD_original_mm": float(np.median(o["dD"])), "median_dD_case1_mm": float(np.median(c["dD"])),
            "max_dD_original_mm": float(o["dD"].max()), "max_dD_case1_mm": float(c["dD"].max())}
    ok = nums["median_dD_case1_mm"] < nums["median_dD_original_mm"] and nums["max_dD_case1_mm"] < nums["max_dD_original_mm"]
    return _v(ok, "|ΔD_eff| between consecutive points (jumps excluded), case 1 vs original", nums,
              partial=nums["max_dD_case1_mm"] < nums["max_dD_original_mm"])


def summary_table() -> pd.DataFrame:
    """Every verdict of this module (name, verdict, text)."""
    fns = [ch3_trends_feed_depth_radius, ch3_cusp_height_same_trend, ch3_rz_more_suitable,
           ch4_speed_drops_at_normal_axis, thesis1_cutting_speed_varies, thesis1_larger_for_larger_D_and_down,
           ch5_similar_ranges, thesis1_feed_direction_significant, ch6_relative_feed_direction,
           thesis2_fifth_powers_essential, thesis2_separate_model_more_accurate]
    return pd.DataFrame([{"recipe": f.__name__, **{"verdict": (v := f()).verdict, "text": v.text}} for f in fns])
