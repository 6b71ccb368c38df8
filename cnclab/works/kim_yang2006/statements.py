"""Verdicts on Kim & Yang (2006)'s headline claim and results sentences (recipes of
``data/qualitative_claims.csv``; each returns a :class:`cnclab.claims.Verdict` with its numbers).

The band: "constant MRR" is read as MRR <= 1.2 × nominal (a_p · b · v_f) with at most 1 % of the
sampled path above it (pixel model at Table 1's 0.3 mm, the written program parsed back).
"""
from __future__ import annotations

from ...claims import Verdict
from . import constant_mrr_pocket as cmp
from . import readings

#: MRR band over nominal and the share of samples allowed above it
BAND = 1.2
SHARE_ALLOWED = 0.01


def constant_mrr_at_all_times() -> Verdict:
    """Abstract / §5: "an optimized contour parallel path that maintains a constant material removal rate
    at all times": the modified path's MRR on the 120 × 85 pocket stays within :data:`BAND` × nominal
    (<= 1 % of samples above). FAILS otherwise, with the numbers."""
    s = cmp.summary("pixel")["modified"]
    ok = s["share_above_1.2_nominal"] <= SHARE_ALLOWED and s["p99_over_nominal"] <= BAND
    return Verdict("HOLDS" if ok else "FAILS",
                   "modified path, pixel model 0.3 mm: peak and 99th-percentile MRR over nominal, share of "
                   "samples above 1.2 × nominal, feed length over the original's",
                   {"max_over_nominal": float(s["max_over_nominal"]), "p99_over_nominal": float(s["p99_over_nominal"]),
                    "share_above_1.2": float(s["share_above_1.2_nominal"]),
                    "feed_length_ratio": float(s["feed_length_mm"] / cmp.summary("pixel")["original"]["feed_length_mm"])})


def original_large_changes() -> Verdict:
    """§4 "Without additional paths, there were large changes in the spindle current": the original
    contour-parallel path's MRR (proportional to the current, eq. 5) peaks at >= 1.5 × nominal."""
    s = cmp.summary("pixel")["original"]
    ok = s["max_over_nominal"] >= 1.5
    return Verdict("HOLDS" if ok else "FAILS", "original path: peak MRR over nominal and share above 1.2 × nominal",
                   {"max_over_nominal": float(s["max_over_nominal"]), "share_above_1.2": float(s["share_above_1.2_nominal"])})


def constant_mrr_under_any_reading() -> Verdict:
    """Issue 25 item 2: is there a reading of §3.2-§3.3 (:data:`cnclab.works.kim_yang2006.readings.READINGS`)
    under which the MRR stays within the band outside the first full-width entry of each region on
    the 120 × 85 pocket and the three other pockets? HOLDS when one reading is within the band on all
    four; FAILS otherwise, with the best reading per pocket, the smallest peak over all runs and the
    unresolved excessive segments (the places the shift-left insertion cannot fix inside the
    allowed region, where the peaks stay)."""
    t = readings.readings_table()
    per = t.groupby("reading").within_band.sum()
    n_pockets = t.pocket.nunique()
    best = t.loc[t.groupby("pocket").p99_outside_entry.idxmin()]
    nums = {f"best_p99_{r.pocket}": float(r.p99_outside_entry) for r in best.itertuples()}
    nums.update({f"best_reading_{r.pocket}": r.reading for r in best.itertuples()})
    nums.update(min_peak_outside_entry=float(t.max_outside_entry.min()),
                min_unresolved_segments=int(t.unresolved.min()), readings=int(t.reading.nunique()),
                pockets=int(n_pockets), most_pockets_within_band=int(per.max()))
    return Verdict("HOLDS" if per.max() == n_pockets else "FAILS",
                   "MRR / nominal outside the first full-width entry of each pass (pixel 0.3 mm): p99 and peak per "
                   "(pocket, reading); band 1.2 with <= 1 % of the length above", nums)
