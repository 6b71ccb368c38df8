"""Verdicts on Jacsó (2021)'s theses and §3-§4 headline sentences (recipes of
``data/qualitative_claims.csv``; each returns a :class:`cnclab.claims.Verdict` with its numbers and
states its threshold).

>>> thesis1_formula().verdict
'HOLDS'
"""
from __future__ import annotations

from ...claims import Verdict
from . import theses_1_3 as t13
from . import thesis4_star_pocket as s4

#: engagement tolerance (deg) for "constant engagement": half a degree, above the 0.02 mm dixel
#: model's angular resolution at r = 3 mm (0.02/3 rad = 0.38 deg)
ENGAGEMENT_TOL_DEG = 0.5


def thesis1_formula() -> Verdict:
    """Thesis I: s(θ, ρ) with the printed k (−1 concave, +1 convex) inverts the cosine-theorem relation
    (1) (residual < 1e-6 deg over θ ∈ [1, 180]°, ρ ∈ {3.5 … 100} mm) and the opposite sign does not
    (residual > 1 deg) — so the printed signs are not a free choice."""
    ok_c = t13.thesis1_inverse_residual_with_k("concave", -1)
    ok_v = t13.thesis1_inverse_residual_with_k("convex", 1)
    bad_c = t13.thesis1_inverse_residual_with_k("concave", 1)
    bad_v = t13.thesis1_inverse_residual_with_k("convex", -1)
    ok = max(ok_c, ok_v) < 1e-6 and min(bad_c, bad_v) > 1.0
    return Verdict("HOLDS" if ok else "FAILS", "inversion residual (deg) with the printed k and with the other sign",
                   {"residual_concave_k-1": ok_c, "residual_convex_k+1": ok_v,
                    "residual_concave_k+1": bad_c, "residual_convex_k-1": bad_v})


def thesis2_ivp() -> Verdict:
    """Thesis II: the IVP's path keeps θ constant — on arcs it is the offset arc (radius residual) and a
    dixel simulation (0.02 mm) of the path on concave/convex arcs gives θ = 60° within 0.5°."""
    res = t13.thesis2_ivp_arc_radius_residual()
    sims = {"concave": t13.sim_concave_theta60(), "convex": t13.sim_convex_theta60(), "straight": t13.sim_straight_theta60()}
    ok = res < 1e-6 and all(abs(v - 60.0) <= ENGAGEMENT_TOL_DEG for v in sims.values())
    return Verdict("HOLDS" if ok else "FAILS", "IVP arc-radius residual (mm) and simulated engagement (deg) for θ = 60°",
                   {"ivp_radius_residual_mm": res, **{f"theta_sim_{k}_deg": v for k, v in sims.items()}})


def thesis3_algorithm() -> Verdict:
    """Thesis III: the numerical algorithm (Steps 0-5) on an arbitrary contour (the blob) keeps the
    simulated engagement within 0.5° of θ = 60°."""
    dev = t13.blob_max_deviation_fine()
    mean = t13.blob_mean_engagement_coarse()
    return Verdict("HOLDS" if dev <= ENGAGEMENT_TOL_DEG else "FAILS",
                   "max |θ_sim − 60°| on the blob (0.02 mm dixels) and the mean at the coarse resolution",
                   {"max_deviation_deg": dev, "mean_engagement_coarse_deg": mean})


def thesis4_constant_engagement() -> Verdict:
    """Thesis IV, first half: the repetitive pattern "provides a constant engagement angle between the
    roll-in and roll-out segments". Measured: the maximum simulated engagement on the cut segment
    equals θ (within 0.5°); the minimum along the segment is not measured by the pattern comparison,
    so the verdict is PARTIAL at best."""
    t = s4.trochoid_comparison().loc["constant-engagement"]
    dev = abs(float(t["engagement_max_cut_deg"]) - float(t["theta_limit_deg"]))
    return Verdict("PARTIAL" if dev <= ENGAGEMENT_TOL_DEG else "FAILS",
                   "max engagement on the cut segment vs θ (the minimum is not measured)",
                   {"theta_deg": float(t["theta_limit_deg"]), "engagement_max_cut_deg": float(t["engagement_max_cut_deg"]),
                    "engagement_max_roll_in_deg": float(t["engagement_max_roll-in_deg"])})


def thesis4_shorter_path() -> Verdict:
    """Thesis IV, second half: the limit on the maximal engagement "can be met with a significantly shorter
    tool path than the conventional circular and cycloid-type trochoidal strategies": path length per
    mm of slot at the same simulated θ_max = 60° (W = 12 mm, Ø6): >= 10 % shorter than both."""
    t = s4.trochoid_comparison()["length_per_mm_slot"]
    ce, circ, cyc = float(t["constant-engagement"]), float(t["circular"]), float(t["cycloid"])
    short = {"shorter_than_circular_pct": 100 * (1 - ce / circ), "shorter_than_cycloid_pct": 100 * (1 - ce / cyc)}
    ok = min(short.values()) >= 10.0
    return Verdict("HOLDS" if ok else ("PARTIAL" if min(short.values()) > 0 else "FAILS"),
                   "path length per mm of slot, constant-engagement vs circular / cycloid (threshold 10 %)",
                   {"ce_mm_per_mm": ce, "circular_mm_per_mm": circ, "cycloid_mm_per_mm": cyc, **short})


def s3_4_mrr_gain_up_to_40() -> Verdict:
    """§3.4 "the value of the material removal rate could increase by up to 40%": the simulated MRR gain of
    the constant-engagement pattern over circular / cycloid at the same θ_max = 60° (W = 12 mm, Ø6),
    every move at the cutting feed (the like-for-like reading) and with links at 1500 mm/min.
    HOLDS when the like-for-like gains reach 40 % within ±5 points (35…45 %)."""
    t = s4.trochoid_comparison().loc["constant-engagement"]
    same = [float(t["mrr_gain_same_feed_vs_circular_pct"]), float(t["mrr_gain_same_feed_vs_cycloid_pct"])]
    ok = 35.0 <= max(same) and min(same) <= 45.0
    return Verdict("HOLDS" if ok else ("PARTIAL" if max(same) > 0 else "FAILS"),
                   "MRR gain (%) of the constant-engagement pattern, same feed / with fast links",
                   {"gain_same_feed_vs_circular_pct": same[0], "gain_same_feed_vs_cycloid_pct": same[1],
                    "gain_fast_links_vs_circular_pct": float(t["mrr_gain_vs_circular_pct"]),
                    "gain_fast_links_vs_cycloid_pct": float(t["mrr_gain_vs_cycloid_pct"])})


def s4_mrr_control_error() -> Verdict:
    """§4 "both the engagement angle and the material removal rate control work appropriately in the
    developed algorithm (the 1.5% error seen at MRR can be considered negligible)": MRR error of the
    hybrid path on the designed star under every reading of the feed-control block structure
    (:func:`cnclab.works.jacso2021.thesis4_star_pocket.mrr_error_readings`: block length, which blocks
    are adjusted, margin, MRR window), read on the constant-engagement cuts.
    HOLDS when some reading gives <= 1.55 % (the printed 1.5 within half a unit), PARTIAL when the
    best reading stays <= 5 % (the control works, the error is larger than printed), FAILS above."""
    d = s4.mrr_error_readings()
    d = d[d.error_on == "constant-engagement cuts"]
    best = d.loc[d.mean_abs_pct.idxmin()]
    rule = d[(d.adjusted == "roll-in/out") & (d.window_mm == 1.0)].mean_abs_pct.min()
    e = float(best.mean_abs_pct)
    v = "HOLDS" if e <= 1.55 else ("PARTIAL" if e <= 5.0 else "FAILS")
    return Verdict(v, "MRR error (%) on the constant-engagement cuts of the designed star, best over the "
                   f"{len(d)} readings (best: block {best.block_mm:g} mm, {best.adjusted}, margin "
                   f"{best.margin_deg:g} deg, window {best.window_mm:g} mm); printed 1.5 %",
                   {"best_error_pct": e, "best_p95_pct": float(best.p95_abs_pct),
                    "booklet_rule_1mm_window_pct": float(rule), "readings": int(len(d)), "printed_pct": 1.5})


def s4_feed_control_shortens() -> Verdict:
    """§4 "optimizing the feed rate at the entry and exit stages of trochoidal sections can significantly
    improve the machining efficiency": program time of the hybrid path without vs with the roll-in /
    roll-out feed control on the designed star; HOLDS at >= 10 % shorter."""
    t = s4.star_strategies()[0]["program_time_s"]
    a, b = float(t["hybrid, constant feed"]), float(t["hybrid, feed control"])
    gain = 100 * (1 - b / a)
    return Verdict("HOLDS" if gain >= 10 else ("PARTIAL" if gain > 0 else "FAILS"),
                   "program time (s) of the hybrid path, constant feed vs feed control (threshold 10 %)",
                   {"time_constant_feed_s": a, "time_feed_control_s": b, "shorter_pct": gain})


def s4_time_near_minimum() -> Verdict:
    """§4 "The machining time was 134 s, which is only 22% higher than the theoretical minimum": our
    feed-controlled hybrid program on the designed star (same V, MRR_nom) vs V/MRR_nom; HOLDS when
    within 22 % + 5 points."""
    t, tmin = s4.hybrid_time_s(), s4.t_min_s()
    ex = 100 * (t / tmin - 1)
    return Verdict("HOLDS" if ex <= 27.0 else "PARTIAL", "program time over V/MRR_nom (%), printed 22 %",
                   {"program_time_s": t, "t_min_s": tmin, "excess_pct": ex})
