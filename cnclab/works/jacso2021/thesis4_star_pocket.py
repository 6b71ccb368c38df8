"""Recipes for Jacsó (2021) §3.4 (Thesis IV, trochoidal slots) and §4 (star pocket, hybrid path).

Inputs: ``data/jacso2021/table4_1_cutting_parameters.json`` (Table 4.1 + §4 text) and
``data/jacso2021/star_pocket.json`` (the designed star: the booklet does not print the contour).
Every ledger value is computed here from those files; resolutions follow fast mode
(:func:`cnclab.runtime.pick`).

>>> round(feed_from_cutting_speed(), 2)        # f_z z 1000 v_c / (pi D)
254.65
>>> round(mrr_nominal(), 2)                    # a_p r (1 - cos 60) v_f = 3 * 1.5 * 255
1147.5
"""
from __future__ import annotations

import functools
import json

import numpy as np
import pandas as pd

from cnclab.cutting.feed_control import controlled_feed, mrr_error_windowed
from cnclab.cutting.speeds import spindle_speed
from cnclab.geometry.engagement import stepover_straight
from cnclab.cache import cached
from cnclab.paths import data_path
from cnclab.runtime import pick
from cnclab.sweep import sweep
from cnclab.toolpath import pocket as pk
from cnclab.toolpath.evaluate import evaluate
from cnclab.toolpath.job import load_job
from cnclab.toolpath.planners import plan
from .studies import compare_patterns, pattern_sweep


@functools.cache
def table41() -> dict:
    """Table 4.1 and the §4 text parameters (mm, m/min, mm/min, deg)."""
    return json.loads(data_path("jacso2021", "table4_1_cutting_parameters.json").read_text())


def feed_from_cutting_speed() -> float:
    """v_f = f_z z n, n = 1000 v_c / (pi D) (mm/min) — Table 4.1 prints 255."""
    t = table41()
    n = float(spindle_speed(t["v_c_m_min"], t["tool_diameter_mm"]))
    return t["f_z_mm"] * t["teeth"] * n


def mrr_nominal() -> float:
    """MRR_nom = a_p a_e v_f with a_e = r (1 - cos theta) and the printed v_f = 255 (mm^3/min)."""
    t = table41()
    a_e = float(stepover_straight(t["theta_deg"], 0.5 * t["tool_diameter_mm"]))
    return t["a_p_mm"] * a_e * t["v_f_printed_mm_min"]


@functools.cache
def star_job():
    """The designed star pocket job (:class:`cnclab.toolpath.job.Job`)."""
    return load_job(data_path("jacso2021", "star_pocket.json"))


def star_volume_mm3() -> float:
    """Volume to remove of the designed star at a_p = 3 mm with the 11 mm start hole (mm^3)."""
    return star_job().volume_mm3()


def t_min_s() -> float:
    """Theoretical minimum machining time V / MRR_nom (s), V of the designed star (= 2098 mm^3)."""
    return 60.0 * star_volume_mm3() / mrr_nominal()


@functools.cache
def printed_times_forces():
    """§4 machining times (s) and maximum forces (N) as printed, indexed by strategy name."""
    import pandas as pd

    return pd.read_csv(data_path("jacso2021", "s4_printed_times_forces.csv"), comment="#").set_index("strategy")


def _hybrid_row():
    df = printed_times_forces()
    return df.loc[[i for i in df.index if i.startswith("developed hybrid")][0]]


def printed_hybrid_time_s() -> float:
    """The booklet's measured machining time of its hybrid path (s, §4: 134)."""
    return float(_hybrid_row()["time_s"])


def excess_of_printed_time_pct() -> float:
    """(t_hybrid / t_min - 1) in % with the printed 134 s and t_min = V/MRR_nom from the printed
    V = 2098 mm³ and MRR_nom = 1147.5 mm³/min — consistency of the printed 22 %."""
    return 100.0 * (float(_hybrid_row()["time_s"]) / t_min_from_printed_s() - 1.0)


def t_min_from_printed_s() -> float:
    """t_min = V / MRR_nom (s) from the printed V = 2098 mm³ and MRR_nom = 1147.5 mm³/min."""
    t = table41()
    return 60.0 * t["volume_printed_mm3"] / t["mrr_nom_printed_mm3_min"]


def force_increase_of_printed_pct() -> float:
    """(F_hybrid / F_straight - 1) in % from the printed maximum forces 108 N and 99 N — the §4
    "9% higher compared to straight-line milling" restated (same arithmetic as the 22 % row)."""
    df = printed_times_forces()
    straight = float(df.loc[[i for i in df.index if i.startswith("straight")][0], "max_force_N"])
    return 100.0 * (float(_hybrid_row()["max_force_N"]) / straight - 1.0)


def level_evaluation(path, job, resolution_mm, feed_control=False):
    """The one evaluator with the cutting-level model (:func:`cnclab.toolpath.evaluate.evaluate`,
    ``feed_control`` on or off): ``(per-step table, summary dict)``; the summary adds the written
    program's time ``program_time_s`` (feed-controlled when ``feed_control``) and the evaluator's
    ``plunges_into_material`` / ``uncut_beyond_unreachable_mm2``."""
    ev = evaluate(path, job, resolution_mm, feed_control=feed_control)
    s = dict(ev.trace["level_summary"])
    s.update(program_time_s=ev.time_feed_controlled_s, plunges_into_material=ev.plunges_into_material,
             uncut_beyond_unreachable_mm2=ev.uncut_beyond_unreachable_mm2)
    return ev.trace["level"], s


def star_strategies(resolution_mm=None):
    """Hybrid (with and without feed control), contour-parallel and zig-zag on the star: summaries
    (:func:`level_evaluation`); ``resolution_mm`` None: 0.05 mm (0.1 in fast mode).

    Returns ``(summaries DataFrame, {name: (path, table)})``. Cached on disk (build/cache, keyed
    by the code and the resolution): the s4 notebook and the claims report share one computation.
    """
    return _star_strategies(pick(0.05, 0.1) if resolution_mm is None else float(resolution_mm))


@functools.cache
@cached()
def _star_strategies(res: float):
    job = star_job()
    hp = pk.hybrid_path(job, res)
    out, rows = {}, []
    T0, s0 = level_evaluation(hp, job, res, feed_control=False)
    s0["strategy"] = "hybrid, constant feed"
    T1, s1 = level_evaluation(hp, job, res, feed_control=True)
    s1["strategy"] = "hybrid, feed control"
    out["hybrid"] = (hp, T1)
    rows += [s0, s1]
    for name, f in (("contour-parallel", pk.contour_parallel_path), ("zig-zag", pk.zigzag_path)):
        p = f(job)
        T, s = level_evaluation(p, job, res)
        out[name] = (p, T)
        rows.append(s)
    return pd.DataFrame(rows).set_index("strategy"), out


@functools.cache
def star_adaptive(resolution_mm=None):
    """The star planned by the ``adaptive`` planner (:data:`cnclab.toolpath.planners.STRATEGIES`),
    evaluated like the others (constant feed): ``(path, table, summary)``."""
    res = pick(0.05, 0.1) if resolution_mm is None else resolution_mm
    job = star_job()
    p = plan(job, "adaptive", resolution_mm=res)
    T, s = level_evaluation(p, job, res)
    s["strategy"] = "adaptive"
    return p, T, s


def hybrid_time_s() -> float:
    """Machining time (s) of our hybrid path with roll-in/roll-out feed control on the designed star
    (the written program's time: entry, cutting level with the controlled feeds, links, rapids and
    retract): partial evidence beside the measured 134 s (the star is not printed)."""
    return float(star_strategies()[0].loc["hybrid, feed control", "program_time_s"])


def hybrid_mrr_error_pct() -> float:
    """Our MRR error (%) of the feed-controlled hybrid path on the designed star (length-weighted mean
    |MRR_w/MRR_nom - 1| over 1 mm windows of the cut segments): beside the booklet's 1.5 %."""
    return float(star_strategies()[0].loc["hybrid, feed control", "mrr_error_cut_pct"])


@functools.cache
def trochoid_comparison(width_mm=12.0, theta_max_deg=60.0, resolution_mm=None):
    """Thesis IV: the three patterns at one engagement limit (Ø6 tool, links at 1500 mm/min)."""
    t = table41()
    res = pick(0.05, 0.1) if resolution_mm is None else resolution_mm
    return compare_patterns(width_mm, 0.5 * t["tool_diameter_mm"], theta_max_deg, res, a_p=t["a_p_mm"],
                            feed_mm_min=t["v_f_printed_mm_min"], link_feed_mm_min=t["link_feed_mm_min"])


@functools.cache
def trochoid_sweep(resolution_mm=None):
    """MRR gain of the constant-engagement pattern over W/r and theta_max (slow in full mode).

    Every point compares the three patterns at the same simulated maximum engagement theta_max
    (:func:`cnclab.works.jacso2021.studies.compare_patterns`: all steps bisected to it).
    Fast mode: W/r = 4 at 0.1 mm dixels; full: W/r in {3, 4, 5, 6} at 0.05 mm; theta_max in
    {30, 45, 60, 75, 90} deg in both. Gains are reported with links at 1500 mm/min and with every
    move at the cutting feed (``mrr_gain_same_feed_vs_*``)."""
    t = table41()
    res = pick(0.05, 0.1) if resolution_mm is None else resolution_mm
    wr = pick((3.0, 4.0, 5.0, 6.0), (4.0,))
    th = (30.0, 45.0, 60.0, 75.0, 90.0)
    cells = sweep(trochoid_cell, [(w, a, 0.5 * t["tool_diameter_mm"], res, t["a_p_mm"], t["v_f_printed_mm_min"],
                                   t["link_feed_mm_min"]) for w in wr for a in th])
    return pd.concat(cells, ignore_index=True)


def trochoid_cell(wr, theta_max_deg, tool_radius, res, a_p, feed_mm_min, link_feed_mm_min):
    """One (W/r, theta_max) cell of :func:`trochoid_sweep` (the rows ``pattern_sweep`` gives for it)."""
    return pattern_sweep([wr], [theta_max_deg], tool_radius, res, a_p=a_p, feed_mm_min=feed_mm_min,
                         link_feed_mm_min=link_feed_mm_min)


USER_POCKETS = (("rectangle 40 x 24", "rectangle_pocket.json"), ("L-shape", "l_pocket.json"))


def user_pocket_job(fname: str, res: float):
    """One user pocket of :func:`user_pockets`: (job, hybrid path, feed-control table, summary)."""
    job = load_job(data_path("jacso2021", fname))
    hp = pk.hybrid_path(job, res)
    T, s = level_evaluation(hp, job, res, feed_control=True)
    return job, hp, T, s


def user_pockets(resolution_mm=None):
    """The hybrid path with default settings (``max_wall_share="auto"``) on the user-pocket
    examples of ``data/jacso2021`` (rectangle, L-shape), evaluated with feed control.

    Returns ``(summaries DataFrame indexed by case, {case: (job, path, table)})``; the summary adds
    ``uncut_beyond_unreachable_mm2`` = uncut area minus the corners the tool cannot reach and the
    chosen ``max_wall_share``. Cached on disk (build/cache, keyed by the code, the two job files and
    the resolution): the s4 notebook and its figure recipe share one computation.
    """
    return _user_pockets(pick(0.05, 0.1) if resolution_mm is None else float(resolution_mm))


@functools.cache
@cached(data=tuple(f"jacso2021/{fname}" for _, fname in USER_POCKETS))
def _user_pockets(res: float):
    import pandas as pd

    rows, out = [], {}
    runs = sweep(user_pocket_job, [(fname, res) for _, fname in USER_POCKETS])
    for (case, fname), (job, hp, T, s) in zip(USER_POCKETS, runs):
        s.update(case=case, laps=hp.info["laps"], arms=len(hp.info["arms"]),
                 max_wall_share=hp.info["max_wall_share"],
                 uncut_beyond_unreachable_mm2=s["uncut_area_mm2"] - s["unreachable_area_mm2"])
        rows.append(s)
        out[case] = (job, hp, T)
    return pd.DataFrame(rows).set_index("case"), out


def wall_share_candidates(resolution_mm=None):
    """The ``max_wall_share="auto"`` choice on the star and the user pockets: one row per shape and
    candidate (metrics from :func:`cnclab.toolpath.pocket.hybrid_path`'s ``info``), ``chosen``
    marks the winner of :func:`cnclab.toolpath.pocket.choose_candidate`."""
    import pandas as pd

    kw = {} if resolution_mm is None else {"resolution_mm": resolution_mm}     # same cache keys as the notebook
    paths = {"star": star_strategies(**kw)[1]["hybrid"][0]}
    paths.update({case: hp for case, (_, hp, _) in user_pockets(**kw)[1].items()})
    rows = []
    for case, hp in paths.items():
        for m in hp.info["wall_share_candidates"]:
            rows.append(dict(m, shape=case, chosen=m["max_wall_share"] == hp.info["max_wall_share"]))
    return pd.DataFrame(rows).set_index(["shape", "max_wall_share"])


# ------------------------------------------------------------------------------ issue 25: §4 "1.5 %"
#: readings of §4's feed control the text allows: block length (mm; unstated), which blocks get the
#: MRR-holding feed (the roll-in/roll-out sections only, as §4 says, or every block whose engagement
#: leaves theta by more than the margin), the margin (deg) and the MRR window (mm; Fig. 4.1's
#: resolution is unstated), and where the error is read (the constant-engagement cuts, or every cut)
MRR_READINGS_BLOCK_MM = (0.25, 0.5, 1.0, 2.0)
MRR_READINGS_WINDOW_MM = (1.0, 5.0)


@functools.cache
def mrr_error_readings(resolution_mm=None):
    """MRR error (%) of the hybrid path on the designed star under every reading of the §4 feed
    control (:data:`MRR_READINGS_BLOCK_MM`, adjusted blocks, margin 2 or 5 deg,
    :data:`MRR_READINGS_WINDOW_MM`, error read on the constant-engagement cuts or on every cut).

    One level simulation (:func:`level_evaluation`, constant feed) gives the removed area per step;
    each reading recomputes the feeds with :func:`cnclab.cutting.feed_control.controlled_feed` and the
    error with :func:`cnclab.cutting.feed_control.mrr_error_windowed`. Columns: the reading,
    ``mean_abs_pct``, ``p95_abs_pct``, ``v_fmax_share`` (share of cut length at the feed cap).
    """
    res = pick(0.05, 0.1) if resolution_mm is None else resolution_mm
    job = star_job()
    hp = star_strategies(resolution_mm)[1]["hybrid"][0]
    T, _ = level_evaluation(hp, job, res, feed_control=False)
    kinds = T.kind.to_numpy()
    rem, ds, eng = T.removed_mm2.to_numpy(), T.ds.to_numpy(), T.engagement_deg.to_numpy()
    cut = (kinds != "link") | T.link_cuts.to_numpy()
    roll = np.isin(kinds, ("roll-in", "roll-out"))
    rows = []
    for block in MRR_READINGS_BLOCK_MM:
        for adjusted, adj in (("roll-in/out", roll), ("any block off theta", None)):
            for margin in (2.0, 5.0):
                v = controlled_feed(rem, ds, eng, cut, job.a_e, job.feed_mm_min, job.v_fmax, job.theta_deg,
                                    block, margin, adjust=adj)
                capped = cut & np.isclose(v, job.v_fmax)
                for window in MRR_READINGS_WINDOW_MM:
                    for where, mask in (("constant-engagement cuts", kinds == "cut"), ("every cut", cut)):
                        e = mrr_error_windowed(rem, ds, v, job.a_p, job.mrr_nominal(), mask, window)
                        rows.append({"block_mm": block, "adjusted": adjusted, "margin_deg": margin,
                                     "window_mm": window, "error_on": where, "mean_abs_pct": e["mean_abs_pct"],
                                     "p95_abs_pct": e["p95_abs_pct"],
                                     "v_fmax_share": float(ds[capped].sum() / ds[cut].sum())})
    return pd.DataFrame(rows)


def mrr_error_best_reading_pct() -> float:
    """The smallest MRR error (%) on the constant-engagement cuts over every reading of
    :func:`mrr_error_readings` (partial evidence beside the booklet's 1.5 %)."""
    d = mrr_error_readings()
    return float(d[d.error_on == "constant-engagement cuts"].mean_abs_pct.min())


def discussion_numbers(resolution_mm=None) -> str:
    """The numbers the s4 notebook's discussion cites, computed (Markdown bullets): the designed star's
    hybrid path (engagement, uncut, program time with and without feed control against t_min and the
    booklet's 134 s, MRR error) and the two own pockets (the same summaries :func:`star_strategies` and
    :func:`user_pockets` give, at ``resolution_mm``, default the mode's: 0.05 mm full, 0.1 mm fast)."""
    res = pick(0.05, 0.1) if resolution_mm is None else float(resolution_mm)
    S, _ = star_strategies(res)
    U, _ = user_pockets(res)
    fc, cf, tm = S.loc["hybrid, feed control"], S.loc["hybrid, constant feed"], t_min_s()
    out = [f"* Star ({res:g} mm dixels): max engagement {fc.engagement_max_deg:.1f}°, "
           f"{100 * fc.share_above_theta_plus5:.1f} % of the cutting length above θ + 5°, uncut "
           f"{fc.uncut_area_mm2:.2f} mm² (unreachable {fc.unreachable_area_mm2:.2f} mm²). Program time with feed "
           f"control {fc.program_time_s:.1f} s = {fc.program_time_s / tm:.2f} × t_min (the booklet: 134 s, "
           f"{134 / tm:.2f} ×); without, {cf.program_time_s:.1f} s ({cf.program_time_s / tm:.2f} ×). MRR error "
           f"{fc.mrr_error_cut_pct:.1f} %."]
    for case, r in U.iterrows():
        out.append(f"* {case}: max engagement {r.engagement_max_deg:.1f}°, {100 * r.share_above_theta_plus5:.1f} % "
                   f"above θ + 5°, uncut {r.uncut_area_mm2:.2f} mm² of which {r.unreachable_area_mm2:.2f} mm² "
                   f"are the unreachable sharp corners ({r.uncut_beyond_unreachable_mm2:.2f} mm² beyond them), "
                   f"{r.program_time_s:.0f} s = {r.program_time_s / r.t_min_s:.2f} × t_min ({r.t_min_s:.1f} s).")
    return "\n".join(out)
