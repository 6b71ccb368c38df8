"""Kim & Yang (2006) "constant MRR at all times" under the readings the text allows (issue 25 item 2).

The paper leaves open: the order of the passes, the side the end point is shifted to ("to the left of
moving direction"), the path step and the pixel size of the modification (§3.2, "the pixel size was
0.3 mm" for the experiment), how far a segment may exceed the reference (eq. 4 has no tolerance), how
often the "additional path" is repeated, whether the §3.3 arcs and spiral entries are used. Each
reading below is one choice of these; every reading is run on the 120 × 85 pocket and on the
pockets of ``data/pockets`` with Table 1's cutting data, and the MRR of the resulting program is
measured with the pixel model **outside the first full-width entry of each region** (the spiral entry
of each pass, or its first tool diameter when there is no spiral).

Band: MRR <= 1.2 × nominal (a_p·b·v_f) with at most 1 % of the sampled length above it
(:data:`cnclab.works.kim_yang2006.statements.BAND`).
"""
from __future__ import annotations

import functools
import json

import numpy as np
import pandas as pd
from shapely.geometry import LinearRing, Polygon

from ...cache import cached, map_cached
from ...paths import data_path
from ...runtime import pick
from ...simulation import pixel
from ...toolpath import constant_mrr as cm
from ...toolpath import offsets
from ...toolpath.job import Job, load_job
from . import constant_mrr_pocket as cmp

#: name -> keyword choices (defaults: the notebook's literal reading)
READINGS = {
    "literal (left, inside-out, 1 mm, tol 15 %, arcs, spiral)": {},
    "insert to the right": {"side": "right"},
    "outside-in pass order": {"order": "outside-in"},
    "0.3 mm path step": {"step_mm": 0.3},
    "tolerance 5 %": {"tolerance": 0.05},
    "no arcs, no spiral (Fig. 10 path)": {"arcs": False, "spiral": False},
    "additional path repeated up to 40 times": {"max_insertions": 40},
    "0.3 mm step, tol 5 %": {"step_mm": 0.3, "tolerance": 0.05},
    "0.3 mm step, 40 insertions": {"step_mm": 0.3, "max_insertions": 40},
}
#: the other pockets (cnclab's own, ``data/pockets``) machined with Table 1's tool and cutting data
#: (``long_slot`` is left out: the Ø10 tool of Table 1 cannot enter it)
OTHER_POCKETS = ("two_regions", "two_islands_neck", "spline_pocket")
BAND = 1.2


@functools.cache
def pocket_job(name: str) -> Job:
    """The 120 × 85 pocket (``"kim_yang_120x85"``) or a ``data/pockets`` pocket with Table 1's tool
    (Ø10 flat, 2 teeth assumed), a_p 0.5 mm, b 3 mm, 500 mm/min, 2000 rpm."""
    if name == "kim_yang_120x85":
        return cmp.job()
    base = json.loads(data_path("kim_yang2006", "pocket_120x85.json").read_text(encoding="utf-8"))
    d = json.loads(data_path("pockets", f"{name}.json").read_text(encoding="utf-8"))
    keep = {k: v for k, v in d.items() if k in ("polygon", "islands", "regions") or k.startswith("_")}
    cut = {k: base[k] for k in ("tool_diameter", "teeth", "theta_deg", "a_p", "feed_mm_min", "spindle_rpm",
                                "link_feed", "rapid_mm_min") if k in base}
    return Job.from_dict({**keep, **cut, "description": f"{name} with Kim & Yang Table 1 cutting data"},
                         source=f"data/pockets/{name}.json + Table 1")


def _passes(job: Job, spiral: bool, order: str):
    r, b = job.tool_radius, job.a_e
    allowed = offsets.allowed_region(job.polygon, r)
    passes = offsets.link_loops(offsets.offset_levels(job.polygon, r, b), allowed)
    if order == "outside-in":
        passes = [p[::-1] for p in passes[::-1]]
    out, entry_len = [], []
    for q in passes:
        n0 = _first_loop_len(q)
        ring = LinearRing(q[:n0])
        L = 2 * r
        if spiral and Polygon(ring).area > 1.0:
            sp = cm.spiral_entry(Polygon(ring), q[0], pitch_mm=b)
            q = np.vstack([sp[:-1], q])
            L = float(np.sum(np.hypot(*np.diff(sp, axis=0).T))) + r
        out.append(q)
        entry_len.append(L)
    return out, entry_len, allowed


def _first_loop_len(p: np.ndarray) -> int:
    d = np.hypot(p[1:, 0] - p[0, 0], p[1:, 1] - p[0, 1])
    k = np.flatnonzero(d < 1e-9)
    return int(k[0]) + 2 if len(k) else len(p)


def run_reading(pocket: str, reading: str, sample_mm: float | None = None) -> dict:
    """Modify, write (arcs per the reading) and measure one (pocket, reading): MRR over nominal
    outside the first full-width entry of each pass; counts of excessive / unresolved segments."""
    kw = dict(READINGS[reading])
    job = pocket_job(pocket)
    c = cmp.conditions()
    passes, entry_len, allowed = _passes(job, kw.pop("spiral", True), kw.pop("order", "inside-out"))
    arcs = kw.pop("arcs", True)
    ref = cm.reference_pixel_count(cm.feed_per_tooth(job.feed_mm_min, job.spindle_rpm, job.teeth), job.a_e,
                                   c["pixel_mm"]) / cm.feed_per_tooth(job.feed_mm_min, job.spindle_rpm, job.teeth)
    mod = cm.modify_path(passes, pixel.Stock.from_polygon(job.polygon, c["pixel_mm"]), job.tool_radius, ref,
                         allowed, **kw)
    path = cm.passes_path(mod.passes, job, arcs=arcs, entry="plunge", tol_mm=0.02, short_mm=1.5)
    sample = pick(0.3, 0.6) if sample_mm is None else sample_mm
    stock = pixel.Stock.from_polygon(job.polygon, c["pixel_mm"])
    nominal = job.a_p * job.a_e * job.feed_mm_min
    kept, all_m = [], []
    for poly, L_entry in zip(cmp.cut_polylines(path.to_moves(), sample), entry_len):
        pts = cm.resample_polyline(poly, sample)
        df = pixel.removal(stock, pts, job.tool_radius, job.a_p, job.feed_mm_min).iloc[1:]   # MRR only
        m = df.mrr_mm3_min.to_numpy() / nominal
        ok = np.isfinite(m)
        all_m.append(m[ok])
        kept.append(m[ok & (df.s.to_numpy() > L_entry)])
    k, a = np.concatenate(kept), np.concatenate(all_m)
    L = path.lengths()
    return {"pocket": pocket, "reading": reading, "max_outside_entry": float(k.max()),
            "p99_outside_entry": float(np.percentile(k, 99)), "share_above_band": float(np.mean(k > BAND)),
            "max_all": float(a.max()), "excessive_segments": mod.n_excessive, "unresolved": mod.n_unresolved,
            "cut_length_mm": L["cut_mm"], "within_band": bool(np.mean(k > BAND) <= 0.01 and np.percentile(k, 99) <= BAND)}


@cached()
def reading_row(pocket: str, reading: str) -> dict:
    """:func:`run_reading` of one (pocket, reading), cached on disk (build/cache, one entry each)."""
    return run_reading(pocket, reading)


def readings_table(pockets: tuple = ("kim_yang_120x85", *OTHER_POCKETS), readings: tuple | None = None) -> pd.DataFrame:
    """:func:`run_reading` for every pocket and reading, one row each (36 runs: 172 s in full mode on
    one core, 2026-11-28). Each row is cached on disk and shared (:func:`cnclab.cache.map_cached`):
    the notebook and the claims report of ``make reproduce`` compute different rows at once instead
    of one waiting for the other."""
    names = tuple(READINGS) if readings is None else readings
    return pd.DataFrame(map_cached(reading_row, [(p, r) for p in pockets for r in names]))
