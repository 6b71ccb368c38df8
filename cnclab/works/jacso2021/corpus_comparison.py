"""The default planner against FreeCAD Path Adaptive on the issue-29 pocket corpus (``data/pockets/corpus``).

The corpus (71 jobs, 12 families incl. ``drawing``: outlines from public drawings) was generated once
by ``data/pockets/corpus/make_corpus.py`` and is frozen. For every job the default planner
(:func:`cnclab.toolpath.planners.plan`, strategy ``adaptive``) and FreeCAD Adaptive's committed program
(``tests/fixtures/freecad/corpus/<job>.ngc``, same tool, stepover a_e = r (1 - cos theta) and feed;
plan time from ``<job>.json``) are scored by the package's one evaluator on the job
(:func:`cnclab.toolpath.evaluate.evaluate`) with the columns of
:mod:`cnclab.works.jacso2021.freecad_comparison` (:func:`~.freecad_comparison.row`). Both are scored
as **written programs**: the planner's path goes through the one program writer
(:func:`cnclab.nc.program.write_program`: arcs fitted, approach and retract at the clearance plane)
and is read back by the same G-code reader as FreeCAD's (:func:`cnclab.nc.gcode.read_toolpath`), so
every column, the wall gouge included, is the program's a machine would run.

Evaluation dixel: h = r / 30 clipped to [0.05, 0.2] mm (the same relative resolution for every
tool; doubled in fast mode); the planner plans at the same h.

:func:`score_job` gives one row (planner columns, FreeCAD's with the suffix ``_fc``, the per-job
target flags; ``g0_unproven``: the planner's G0s at depth that :func:`cnclab.toolpath.adaptive.unproven_rapids`
cannot prove from the written path, 0 for a safe row); :func:`family_table` the per-family distribution (jobs, planned, worst value per axis);
:func:`targets` the issue-29 targets over the corpus (met or not, with the measured value).
Units: mm, mm^2, deg, min (program time: length / feed; machine time: the small-VMC model of
:mod:`cnclab.toolpath.motion`, ``Evaluation.time_machine_s``), s (plan time). Rows written before the
machine time was a column (a ``corpus_rows.csv`` without ``machine_time_min``) give NaN machine ratios.

>>> len(job_names()) >= 60 and family("gear10_island")
'gear'
"""
from __future__ import annotations

import json
import math
import time

import numpy as np
import pandas as pd

from ...nc.program import program_path
from ...paths import REPO_ROOT
from ...plotting import figsize
from ...runtime import pick
from ...toolpath import planners
from ...toolpath.adaptive import unproven_rapids
from ...toolpath.evaluate import evaluate
from ...toolpath.job import Job, load_job
from . import freecad_comparison as fx
from .freecad_comparison import meets_bounds

__all__ = ["CORPUS", "FIXTURES", "RESULTS", "ROW_COLUMNS", "job_names", "job", "family", "resolution_mm",
           "score_job", "family_table", "targets", "bounded_targets", "meets_bounds", "FIXTURES_BOUNDED", "warm", "load_rows", "ratio_columns", "distribution_figure",
           "worst_cases"]

CORPUS = REPO_ROOT / "data" / "pockets" / "corpus"
FIXTURES = REPO_ROOT / "tests" / "fixtures" / "freecad" / "corpus"
#: FreeCAD's programs held to the same engagement bounds (the largest stepover meeting them:
#: ``benchmarks/freecad_bounded.py``), for the program time at equal engagement
FIXTURES_BOUNDED = REPO_ROOT / "tests" / "fixtures" / "freecad" / "corpus_bounded"
#: the committed rows of the last full run of benchmarks/bench_corpus.py (with its run notes in the .json)
RESULTS = REPO_ROOT / "benchmarks" / "results" / "corpus_rows.csv"
#: the axes of the comparison: planner column -> FreeCAD column is the same name + "_fc"
AXES = ["engagement_p95_deg", "engagement_max_deg", "share_above_5_pct", "plunges_into_material", "rapids_into_material",
        "wall_gouge_mm", "lifts", "uncut_beyond_mm2", "program_time_min", "machine_time_min", "plan_time_s"]
ROW_COLUMNS = (["family", "D_mm", "theta_deg", "levels"] + AXES + [a + "_fc" for a in AXES]
               + ["uncut_over_limit", "g0_unproven", "ok_safe", "ok_engagement", "note"])


def job_names() -> list:
    """Names of the corpus jobs (file stems), sorted."""
    return sorted(p.stem for p in CORPUS.glob("*.json"))


def job(name: str) -> Job:
    """The corpus job ``name``, read by the package's one loader."""
    if name not in job_names():
        raise ValueError(f"{name!r} is not a job of {CORPUS}")
    return load_job(CORPUS / f"{name}.json")


def family(name: str) -> str:
    """The family the generator gave job ``name`` (its ``_family`` key)."""
    return json.loads((CORPUS / f"{name}.json").read_text(encoding="utf-8"))["_family"]


def resolution_mm(jb: Job, fast: bool | None = None) -> float:
    """Evaluation and planning dixel (mm): r / 30 clipped to [0.05, 0.2]; fast mode doubles it."""
    h = float(np.clip(jb.tool_radius / 30.0, 0.05, 0.2))
    return h * (pick(1.0, 2.0) if fast is None else (2.0 if fast else 1.0))


def _fixture_row(fixtures, name: str, jb: Job, h: float, missing_note: str, error_note) -> tuple:
    """FreeCAD's committed program of job ``name`` in ``fixtures`` scored by :func:`fx.row`:
    ``(row, provenance, "")``; ``(None, provenance or None, note)`` where there is no program to
    score: ``missing_note`` (no fixture), ``error_note(message)`` (its provenance records a failure)
    or that FreeCAD wrote no cutting motion (its plan time is then not a plan)."""
    prov_file = fixtures / f"{name}.json"
    if not prov_file.exists():
        return None, None, missing_note
    prov = json.loads(prov_file.read_text(encoding="utf-8"))
    if "error" in prov:
        return None, prov, error_note(prov["error"])
    try:
        fp = fx.freecad_path(name, jb.tool, fixtures)
    except ValueError:
        return None, prov, f"FreeCAD wrote no cutting motion ({prov['plan_time_s']:.2f} s)"
    return fx.row(evaluate(fp, jb, h), float(prov["plan_time_s"]), jb=jb), prov, ""


def _freecad(name: str, jb: Job, h: float) -> dict:
    r, _, note = _fixture_row(FIXTURES, name, jb, h, "no FreeCAD fixture", lambda e: f"FreeCAD failed: {e[-120:]}")
    return {a + "_fc": math.nan if r is None else r[a] for a in AXES} | {"note_fc": note}


#: the axes compared with FreeCAD held to the bounds (suffix ``_fcb``)
AXES_BOUNDED = ["engagement_p95_deg", "engagement_max_deg", "share_above_5_pct", "rapids_into_material", "lifts",
                "uncut_beyond_mm2", "program_time_min", "machine_time_min"]


def _freecad_bounded(name: str, jb: Job, h: float) -> dict:
    """FreeCAD's program held to the engagement bounds (:data:`FIXTURES_BOUNDED`), scored as
    :func:`_freecad` (suffix ``_fcb``) with its ``stepover_scale_fcb``; NaN and a note where there is none."""
    r, prov, note = _fixture_row(FIXTURES_BOUNDED, name, jb, h, "no bounded FreeCAD fixture", lambda e: e[:120])
    return ({a + "_fcb": math.nan if r is None else r[a] for a in AXES_BOUNDED}
            | {"stepover_scale_fcb": math.nan if r is None else float(prov["stepover_scale"]), "note_fcb": note})


def score_job(name: str, fast: bool | None = None) -> dict:
    """One row of the corpus table for job ``name`` (see the module docstring); a job the planner
    refuses or fails on gets NaN planner columns and the reason in ``note``."""
    jb = job(name)
    h = resolution_mm(jb, fast)
    out = {"job": name, "family": family(name), "D_mm": jb.tool_diameter, "theta_deg": jb.theta_deg,
           "levels": len(jb.levels()), "resolution_mm": h}
    t0 = time.perf_counter()
    try:
        # what it leaves and an engagement beyond the promise are columns here (the warnings: the note)
        tp = planners.plan(jb, "adaptive", h, allow_uncut=True, allow_engagement_breach=True, written=program_path)
        t_plan = time.perf_counter() - t0
        r = fx.row(evaluate(fx.as_written(tp, jb), jb, h), t_plan, jb=jb)    # scored as written, as FreeCAD's
        out.update({a: r[a] for a in AXES}, note="; ".join(tp.info.get("warnings", [])))
        out["uncut_over_limit"] = bool(tp.info["uncut"]["over"])
        # the G0s at depth the written path does not prove clear (adaptive.audit; a sound plan: none)
        out["g0_unproven"] = len(unproven_rapids(tp, jb))
    except Exception as exc:       # noqa: BLE001 -- a refusal or a crash is a result of this benchmark
        out.update({a: math.nan for a in AXES}, note=f"{type(exc).__name__}: {str(exc)[:200]}")
    out.setdefault("uncut_over_limit", math.nan)
    out.setdefault("g0_unproven", math.nan)
    out.update(_freecad(name, jb, h))
    th = jb.theta_deg
    out["ok_safe"] = bool(out["plunges_into_material"] == 0 and out["rapids_into_material"] == 0
                          and out["wall_gouge_mm"] <= 1e-3 and out["g0_unproven"] == 0) if out["note"][:5] != "Plann" else math.nan
    out["ok_engagement"] = meets_bounds(out["engagement_p95_deg"], out["engagement_max_deg"], out["share_above_5_pct"], th)
    out.update(_freecad_bounded(name, jb, h))
    return out


def _ratio(df, a, suffix="_fc"):
    """Column ``a`` over FreeCAD's (``a + suffix``; a zero there gives NaN)."""
    return df[a] / df[a + suffix].replace(0.0, np.nan)


def _bounded_ratio(df):
    """Program-time ratio to FreeCAD held to the bounds (NaN for rows without the ``_fcb`` columns)."""
    if "program_time_min_fcb" not in df:
        return pd.Series(np.nan, index=df.index)
    return _ratio(df, "program_time_min", "_fcb")


def _machine_ratio(df):
    """Machine-time ratio to FreeCAD (NaN for rows written before ``machine_time_min`` existed)."""
    if "machine_time_min" not in df or "machine_time_min_fc" not in df:
        return pd.Series(np.nan, index=df.index)
    return _ratio(df, "machine_time_min")


def family_table(df: pd.DataFrame) -> pd.DataFrame:
    """Per family: jobs, planned, unsafe jobs, worst (max) engagement excess over theta (p95, max),
    worst share above theta + 5, worst program-time and plan-time ratio to FreeCAD (and the median
    program-time ratio to FreeCAD held to the bounds, :data:`FIXTURES_BOUNDED`), worst lifts and
    uncut excess over FreeCAD's (lifts - lifts_fc, uncut - uncut_fc in mm^2)."""
    d = df.copy()
    d["p95-θ"] = d["engagement_p95_deg"] - d["theta_deg"]
    d["max-θ"] = d["engagement_max_deg"] - d["theta_deg"]
    d["program ratio"] = _ratio(d, "program_time_min")
    d["machine ratio"] = _machine_ratio(d)
    d["program ratio bounded"] = _bounded_ratio(d)
    d["plan ratio"] = _ratio(d, "plan_time_s")
    d["lifts - FC"] = d["lifts"] - d["lifts_fc"]
    d["uncut - FC"] = d["uncut_beyond_mm2"] - d["uncut_beyond_mm2_fc"]
    g = d.groupby("family")
    T = pd.DataFrame({"jobs": g.size(), "planned": g["engagement_max_deg"].count(),
                      "FC planned": g["engagement_max_deg_fc"].count(),
                      "unsafe": g["ok_safe"].apply(lambda s: int((s == False).sum())),  # noqa: E712 -- NaN: not planned
                      "worst p95-θ": g["p95-θ"].max(), "worst max-θ": g["max-θ"].max(),
                      "worst share>θ+5 %": g["share_above_5_pct"].max(), "worst program ratio": g["program ratio"].max(),
                      "median program ratio": g["program ratio"].median(),
                      "median program ratio bounded FC": g["program ratio bounded"].median(),
                      "worst machine ratio": g["machine ratio"].max(), "worst plan ratio": g["plan ratio"].max(),
                      "worst lifts - FC": g["lifts - FC"].max(), "worst uncut - FC mm2": g["uncut - FC"].max()})
    return T


def targets(df: pd.DataFrame) -> pd.DataFrame:
    """The issue-29 targets over the corpus: ``target``, ``measured``, ``met``. A job the planner did
    not plan counts against every target; the comparisons with FreeCAD are over the jobs FreeCAD
    planned (the count is stated): where FreeCAD wrote no program there is nothing to compare."""
    n = len(df)
    planned = df["engagement_max_deg"].notna()
    both = df[planned & df["engagement_max_deg_fc"].notna()]
    nb = f"of {len(both)} jobs both planned"
    prog = _ratio(both, "program_time_min")
    lifts_ok = both["lifts"] <= both["lifts_fc"]
    uncut_ok = both["uncut_beyond_mm2"] <= both["uncut_beyond_mm2_fc"] + 0.5
    safe = df["ok_safe"] == True  # noqa: E712 -- NaN (not planned) is not safe-and-planned
    rows = [
        ("every job planned", f"{int(planned.sum())}/{n}", bool(planned.all())),
        ("0 plunges, 0 rapids into material, 0 wall/island gouge on every job (and every G0 at depth proven "
         "by adaptive.audit)",
         f"{int(safe.sum())}/{n} planned and safe ({int(planned.sum())} planned)", bool(safe.all())),
        ("p95 <= θ+2, max <= θ+10, share>θ+5 <= 0.5 % on every job",
         f"{int(df['ok_engagement'].sum())}/{n}; "
         f"worst max-θ {float((df['engagement_max_deg'] - df['theta_deg']).max()):.1f} deg",
         bool(df["ok_engagement"].all())),
        ("program time <= FreeCAD's on >= 95 % of jobs", f"{float((prog <= 1.0).mean() * 100):.1f} % {nb}",
         bool((prog <= 1.0).mean() >= 0.95)),
        ("program time <= 1.05 x FreeCAD's on all jobs", f"worst {float(prog.max()):.3f} {nb}", bool((prog <= 1.05).all())),
        ("lifts <= FreeCAD's on >= 95 %", f"{float(lifts_ok.mean() * 100):.1f} % {nb}", bool(lifts_ok.mean() >= 0.95)),
        ("uncut <= FreeCAD's + 0.5 mm^2 on >= 95 %", f"{float(uncut_ok.mean() * 100):.1f} % {nb}",
         bool(uncut_ok.mean() >= 0.95)),
        ("plan time <= FreeCAD's on the median job", f"median ratio {float(_ratio(both, 'plan_time_s').median()):.2f} {nb}",
         bool(_ratio(both, "plan_time_s").median() <= 1.0)),
    ]
    for fam, label in (("channel_15d", "1.5 D channels"), ("tapered_channel", "tapered channels"),
                       ("slot_bulbs", "slots with bulbs"), ("gear", "gear outlines")):
        ch = df[df["family"] == fam]
        cb = ch[ch["engagement_max_deg"].notna() & ch["engagement_max_deg_fc"].notna()]
        ok = (cb["lifts"] <= cb["lifts_fc"] + 1) & (_ratio(cb, "program_time_min") <= 1.0)
        rows.append((f"{label}: lifts <= FreeCAD's + 1 and program time <= FreeCAD's",
                     f"{int(ok.sum())}/{len(cb)} (FreeCAD planned {len(cb)} of {len(ch)}; "
                     f"ours {int(ch['engagement_max_deg'].notna().sum())})",
                     bool(len(cb) and ok.all())))
    return pd.DataFrame(rows, columns=["target", "measured", "met"]).set_index("target")


def bounded_targets(df: pd.DataFrame) -> pd.DataFrame:
    """The program-time, lifts and uncut targets again against FreeCAD held to the same engagement
    bounds (columns ``_fcb``, :data:`FIXTURES_BOUNDED`): beyond the issue's own targets (which compare
    with FreeCAD at the job's stepover, where FreeCAD breaks the bounds), the comparison at equal
    engagement. Over the jobs both planned and for which a bounded FreeCAD program exists (counted)."""
    if "program_time_min_fcb" not in df:
        return pd.DataFrame(columns=["target", "measured", "met"]).set_index("target")
    both = df[df["engagement_max_deg"].notna() & df["program_time_min_fcb"].notna()]
    nb = f"of {len(both)} jobs with a bounded FreeCAD program"
    prog = _bounded_ratio(both)
    lifts_ok = both["lifts"] <= both["lifts_fcb"]
    uncut_ok = both["uncut_beyond_mm2"] <= both["uncut_beyond_mm2_fcb"] + 0.5
    held = [meets_bounds(*v) for v in both[["engagement_p95_deg_fcb", "engagement_max_deg_fcb",
                                            "share_above_5_pct_fcb", "theta_deg"]].to_numpy()]
    rows = [("bounded FreeCAD meets the bounds (checked again here)", f"{sum(held)}/{len(both)}", all(held)),
            ("program time <= bounded FreeCAD's on >= 95 %", f"{float((prog <= 1.0).mean() * 100):.1f} % {nb}; "
             f"median ratio {float(prog.median()):.3f}", bool((prog <= 1.0).mean() >= 0.95)),
            ("program time <= 1.05 x bounded FreeCAD's on all", f"worst {float(prog.max()):.3f} ({prog.idxmax() if len(prog) else '-'})",
             bool((prog <= 1.05).all())),
            ("lifts <= bounded FreeCAD's on >= 95 %", f"{float(lifts_ok.mean() * 100):.1f} % {nb}", bool(lifts_ok.mean() >= 0.95)),
            ("uncut <= bounded FreeCAD's + 0.5 mm^2 on >= 95 %", f"{float(uncut_ok.mean() * 100):.1f} % {nb}",
             bool(uncut_ok.mean() >= 0.95))]
    return pd.DataFrame(rows, columns=["target", "measured", "met"]).set_index("target")


def warm() -> None:
    """Load (or compile) the planner's and evaluator's kernels once before anything is timed."""
    fx.warm_planners(["adaptive"])


def load_rows(path=RESULTS) -> pd.DataFrame:
    """The per-job rows written by ``benchmarks/bench_corpus.py`` (``corpus_rows.csv``), indexed by job."""
    return pd.read_csv(path, index_col="job")


def ratio_columns(df: pd.DataFrame) -> pd.DataFrame:
    """Per job: program-time and plan-time ratios to FreeCAD, lifts and uncut area minus FreeCAD's,
    engagement max and p95 minus theta (ours and FreeCAD's), family."""
    return pd.DataFrame({"family": df["family"], "program time / FC": _ratio(df, "program_time_min"),
                         "machine time / FC": _machine_ratio(df),
                         "plan time / FC": _ratio(df, "plan_time_s"), "lifts - FC": df["lifts"] - df["lifts_fc"],
                         "uncut - FC (mm²)": df["uncut_beyond_mm2"] - df["uncut_beyond_mm2_fc"],
                         "max - θ (deg)": df["engagement_max_deg"] - df["theta_deg"],
                         "max - θ FC (deg)": df["engagement_max_deg_fc"] - df["theta_deg"],
                         "p95 - θ (deg)": df["engagement_p95_deg"] - df["theta_deg"],
                         "program time / bounded FC": _bounded_ratio(df)})


#: the panels of :func:`distribution_figure`: column of :func:`ratio_columns`, target line, y scale
PANELS = [("program time / FC", 1.0, "log"), ("program time / bounded FC", 1.0, "log"), ("lifts - FC", 0.0, "linear"),
          ("uncut - FC (mm²)", 0.5, "symlog"), ("max - θ (deg)", 10.0, "linear"), ("p95 - θ (deg)", 2.0, "linear"),
          ("plan time / FC", 1.0, "log")]


def distribution_figure(df: pd.DataFrame):
    """One panel per axis (:data:`PANELS`): every job as a dot in its family's column, the issue-29
    target as a dashed line; jobs FreeCAD did not plan have no ratio and are left out of those panels."""
    import matplotlib.pyplot as plt

    R = ratio_columns(df)
    fams = sorted(R["family"].unique())
    panels = [p for p in PANELS if R[p[0]].notna().any()]   # rows of a run without bounded FreeCAD: no such panel
    # rows of two, the families labelled once under the bottom row: legible at a column width of 85 mm
    nrow = (len(panels) + 1) // 2
    fig, axs = plt.subplots(nrow, 2, figsize=figsize(1.5, 0.95 * nrow), sharex=True, layout="constrained")
    for ax in axs.flat[len(panels):]:
        ax.set_visible(False)
    for ax, (col, target, yscale) in zip(axs.flat, panels):
        for i, f in enumerate(fams):
            v = R.loc[R["family"] == f, col].dropna()
            ax.plot(i + np.linspace(-0.2, 0.2, len(v)) if len(v) > 1 else [i] * len(v), v, "o", ms=3, alpha=0.8)
        ax.axhline(target, ls="--", color="k", lw=0.8)
        ax.set_title(col)
        ax.set_yscale(yscale, **({"linthresh": 1.0} if yscale == "symlog" else {}))
        if yscale == "symlog":          # decades beyond the linear part only: -1, 0, 1 would overlap
            lo, hi = ax.get_ylim()
            ax.set_yticks([t for t in (-1e4, -1e3, -1e2, -10, 0, 10, 1e2, 1e3, 1e4) if lo <= t <= hi])
    for ax in axs.flat[max(len(panels) - 2, 0):len(panels)]:      # the lowest panel of each column
        ax.set_xticks(range(len(fams)), fams, rotation=90, fontsize=6)
        ax.xaxis.set_tick_params(labelbottom=True)
    return fig


def worst_cases(df: pd.DataFrame, k: int = 3) -> pd.DataFrame:
    """The ``k`` worst jobs on each axis of :data:`PANELS` (largest value): axis, job, family, value."""
    R = ratio_columns(df)
    rows = [(col, j, R.at[j, "family"], float(R.at[j, col])) for col, _, _ in PANELS if R[col].notna().any()
            for j in R[col].dropna().sort_values(ascending=False).index[:k]]
    return pd.DataFrame(rows, columns=["axis", "job", "family", "value"])
