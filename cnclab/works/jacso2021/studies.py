"""Studies of the Jacsó (2021) work on the toolpath layer's geometry: the Thesis IV sweeps over the
trochoidal patterns (§3.4) — the three patterns compared at one engagement limit
(:func:`compare_patterns`) and over a grid of W/r and theta_max (:func:`pattern_sweep`), on
:mod:`cnclab.toolpath.trochoidal` — and the §4 star pocket's design (:func:`design_star`: its
contour is not printed, a parameterised stand-in sized to the printed volume)."""
from __future__ import annotations

import math

import pandas as pd
from scipy.optimize import brentq

from ...toolpath.job import star_polygon
from ...toolpath.trochoidal import (admissible_step, ce_trochoid, ce_trochoid_iteration, circular_trochoid, cycloid,
                                    evaluate_pattern, slot_limit)

__all__ = ["compare_patterns", "pattern_sweep", "design_star"]


def design_star(volume_mm3, a_p, hole_diameter, **star_kw) -> float:
    """Outer radius (mm) of :func:`~cnclab.toolpath.job.star_polygon` whose volume a_p (A - A_hole)
    equals ``volume_mm3`` (mm^3; ``a_p`` and ``hole_diameter`` in mm; ``star_kw`` the other star
    parameters), solved by Brent's method on [10, 100] mm.

    >>> round(design_star(2098, 3, 11, n_arms=5, inner_ratio=0.5, tip_radius=4.0, root_radius=2.0), 3) > 10
    True
    """
    hole = math.pi * (0.5 * hole_diameter) ** 2
    star_kw = {k: v for k, v in star_kw.items() if k != "outer_radius"}

    def f(R):
        return a_p * (star_polygon(outer_radius=R, **star_kw).area - hole) - volume_mm3

    return float(brentq(f, 10.0, 100.0, xtol=1e-9))


def _row(ev) -> dict:
    """A table row of a pattern's Evaluation: its engagement percentiles and the pattern metrics."""
    return {"engagement_p50_deg": ev.engagement_p50_deg, "engagement_p95_deg": ev.engagement_p95_deg,
            "engagement_max_deg": ev.engagement_max_deg, **ev.extra}


def compare_patterns(width, tool_radius, theta_max_deg, resolution_mm=0.05, a_p=3.0,
                     feed_mm_min=255.0, link_feed_mm_min=None, n_periods=6, plan_offsets_deg=(0.0, 3.0),
                     fillet_fractions=(0.5, 1.0)):
    """The three patterns at the same engagement limit: admissible step, lengths, MRR (one row each).

    All three steps are bisected to the same limit: circular and cycloid by :func:`admissible_step`,
    the constant-engagement pattern by :func:`ce_admissible_step` — every pattern's simulated
    steady-state maximum engagement over all cutting moves (roll-in included) is <= theta_max
    (column ``theta_limit_deg``). The CE period is planned by :func:`ce_trochoid_iteration` with
    entry/exit fillets; as the cycloid's one parameter (its step) is optimised by the bisection,
    the CE pattern's two shape parameters are chosen from a small grid by the same simulation: the
    planning angle theta_plan in ``plan_offsets_deg`` + theta_max and the fillet radius in
    ``fillet_fractions`` x (W/2 - r); the candidate with the shortest path per mm of slot (at its
    admissible step) wins (columns ``theta_plan_deg``, ``fillet_radius_mm``, ``shift_mm``).
    Returns a pandas DataFrame.
    """
    R = slot_limit(width, tool_radius)
    best, errs = None, []
    for d_plan in plan_offsets_deg:
        for frac in fillet_fractions:
            th_plan = float(theta_max_deg) + float(d_plan)
            try:
                it = ce_trochoid_iteration(width, tool_radius, th_plan, 8, resolution_mm, a_p=a_p,
                                           feed_mm_min=feed_mm_min, fillet_radius_mm=frac * R)
                p = ce_trochoid(width, tool_radius, th_plan, n_periods, resolution_mm, iteration=it,
                                theta_max_deg=theta_max_deg, feed_mm_min=feed_mm_min,
                                link_feed_mm_min=link_feed_mm_min)
            except ValueError as e:
                errs.append(f"theta_plan={th_plan}, fillet={frac * R:.3g} mm: {e}")
                continue
            _, m = evaluate_pattern(p, width, tool_radius, resolution_mm, a_p, feed_mm_min, link_feed_mm_min)
            m = {**_row(m), "theta_plan_deg": th_plan, "fillet_radius_mm": frac * R, "shift_mm": p.info["shift"]}
            if best is None or m["length_per_mm_slot"] < best["length_per_mm_slot"]:
                best = m
    if best is None:
        raise ValueError(f"no constant-engagement period keeps theta_max_deg={theta_max_deg}: {'; '.join(errs)}")
    m_ce = best
    lim = float(theta_max_deg)
    rows = []
    for kind in ("circular", "cycloid"):
        s = admissible_step(kind, lim, width, tool_radius, resolution_mm)
        gen = circular_trochoid if kind == "circular" else cycloid
        p = gen(s, width, tool_radius, n_periods, ds=resolution_mm)
        _, m = evaluate_pattern(p, width, tool_radius, resolution_mm, a_p, feed_mm_min, link_feed_mm_min)
        rows.append({"pattern": kind, "theta_limit_deg": lim, **_row(m)})
    rows.append({"pattern": "constant-engagement", "theta_limit_deg": lim, **m_ce})
    df = pd.DataFrame(rows).set_index("pattern")
    # every move (links included) at the cutting feed: the "same feed" comparison of Thesis IV
    df["mrr_same_feed_mm3_min"] = a_p * float(width) * df.step_mm / ((df.cut_mm + df.link_mm) / feed_mm_min)
    for ref in ("circular", "cycloid"):
        df[f"mrr_gain_same_feed_vs_{ref}_pct"] = 100 * (df.mrr_same_feed_mm3_min / df.loc[ref, "mrr_same_feed_mm3_min"] - 1)
    df["mrr_gain_vs_circular_pct"] = 100 * (df.mrr_avg_mm3_min / df.loc["circular", "mrr_avg_mm3_min"] - 1)
    df["mrr_gain_vs_cycloid_pct"] = 100 * (df.mrr_avg_mm3_min / df.loc["cycloid", "mrr_avg_mm3_min"] - 1)
    return df


def pattern_sweep(width_over_r, theta_max_deg, tool_radius=3.0, resolution_mm=0.05, **kw):
    """:func:`compare_patterns` over a grid of W/r and theta_max; one row per (W/r, theta, pattern)."""
    out = []
    for wr in width_over_r:
        for th in theta_max_deg:
            df = compare_patterns(wr * tool_radius, tool_radius, th, resolution_mm, **kw).reset_index()
            df.insert(0, "theta_max_deg", th)
            df.insert(0, "W_over_r", wr)
            out.append(df)
    return pd.concat(out, ignore_index=True)
