"""FreeCAD Path Adaptive held to the engagement bounds of issue 29, for a like-for-like program time.

At the job's own stepover (``a_e = r (1 - cos theta)``, the fixtures of ``bench_corpus.py``) FreeCAD's
program breaks the engagement bounds the planner is held to on every corpus job (its p95 is theta + 5.4
deg on the median job; its maximum theta + 22 deg): it removes more per mm of cut than a program that
holds theta can. This script finds, per corpus job, FreeCAD's program at the largest stepover that
meets the same bounds as the planner (evaluator p95 <= theta + 2, max <= theta + 10, share above
theta + 5 <= 0.5 %, at the corpus resolution ``corpus_comparison.resolution_mm``), so that its program
time can be compared at equal engagement.

The search (deterministic; the same FreeCAD settings as ``freecad_adaptive.py`` except the stepover):
FreeCAD's stepover scaled by s = 1, 0.95, 0.90, ... down to ``--min-scale`` (0.5) until a program
meets the bounds (s*); then s* + 0.025 is tried once (when below the last failing scale) and kept if
it also meets them. The program kept is FreeCAD's at the largest scale found on that grid: a finer
search could find a scale up to 0.025 larger, i.e. a FreeCAD program up to about 2.5 % shorter -- the
comparison errs in FreeCAD's favour by at most that (a program meeting the bounds at a larger scale
between the grid points would be shorter; one at a smaller scale is never chosen).

Writes ``tests/fixtures/freecad/corpus_bounded/<job>.ngc`` and ``<job>.json`` (provenance: FreeCAD
version, settings, the scale, every scale tried with its p95 - theta, max - theta and share; or
``error`` when FreeCAD plans nothing or no scale down to the minimum meets the bounds). Needs FreeCAD
(``apt-get install -y --no-install-recommends freecad``); ``bench_corpus.py`` reads the fixtures.

    .venv/bin/python benchmarks/freecad_bounded.py [JOB ...] [--min-scale 0.5]
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from freecad_adaptive import freecad_available, run_freecad  # noqa: E402

from cnclab.fileio import atomic_write  # noqa: E402
from cnclab.nc.gcode import read_toolpath  # noqa: E402
from cnclab.toolpath.evaluate import evaluate_engagement  # noqa: E402
from cnclab.works.jacso2021 import corpus_comparison as cc  # noqa: E402

#: the scan's coarse step and the one refinement step (fractions of the job's stepover)
COARSE, FINE = 0.05, 0.025


def measure(ngc: Path, jb, h: float) -> dict:
    """p95 - theta, max - theta (deg), share above theta + 5 (%) of a FreeCAD program, and whether
    they meet the bounds (:func:`cnclab.works.jacso2021.corpus_comparison.meets_bounds`)."""
    fp = read_toolpath(ngc, tool=jb.tool)
    ev = evaluate_engagement(fp, jb, h)
    th = jb.theta_deg
    m = {"p95_minus_theta_deg": round(ev.engagement_p95_deg - th, 3),
         "max_minus_theta_deg": round(ev.engagement_max_deg - th, 3), "share_above_5_pct": round(ev.share_above_5_pct, 4)}
    m["ok"] = cc.meets_bounds(ev.engagement_p95_deg, ev.engagement_max_deg, ev.share_above_5_pct, th)
    return m


def bounded(name: str, min_scale: float) -> None:
    """Search job ``name`` (module docstring) and write its fixture pair."""
    jb = cc.job(name)
    h = cc.resolution_mm(jb, False)
    cc.FIXTURES_BOUNDED.mkdir(parents=True, exist_ok=True)
    tried, kept = [], None
    with tempfile.TemporaryDirectory() as tmp:
        def attempt(s):
            out = Path(tmp) / f"{s:.3f}.ngc"
            try:
                res = run_freecad(jb, out, stepover_scale=s)
                m = measure(out, jb, h)
            except Exception as exc:          # noqa: BLE001 -- FreeCAD planning nothing is a result
                tried.append({"scale": s, "error": str(exc).replace(str(tmp), "<tmp>")[-300:]})
                return None
            tried.append({"scale": s} | m)
            return (s, out, res) if m["ok"] else None

        s = 1.0
        while s >= min_scale - 1e-9 and kept is None:
            kept = attempt(round(s, 3))
            if "error" in tried[0]:
                break            # nothing at the job's own stepover: no comparison (bench_corpus says why)
            s -= COARSE
        if kept is not None and kept[0] < 1.0:
            finer = attempt(round(kept[0] + FINE, 3))
            kept = finer or kept
        prov = {"job": f"data/pockets/corpus/{name}.json", "bounds": "evaluator p95 <= theta + 2, max <= theta + 10, "
                f"share above theta + 5 <= 0.5 % at h = {h:.4f} mm", "search": f"scales 1 - {COARSE} k down to "
                f"{min_scale}, then the first meeting scale + {FINE} (benchmarks/freecad_bounded.py)", "tried": tried}
        if kept is None:
            prov["error"] = (f"FreeCAD wrote no program at the job's stepover: {tried[0]['error'][-160:]}"
                             if "error" in tried[0] else
                             f"no stepover scale down to {min_scale} gives a FreeCAD program meeting the bounds")
            atomic_write(cc.FIXTURES_BOUNDED / f"{name}.json", json.dumps(prov, indent=1) + "\n")
            (cc.FIXTURES_BOUNDED / f"{name}.ngc").unlink(missing_ok=True)
            print(f"{name}: none", flush=True)
            return
        s, out, res = kept
        prov.update({"stepover_scale": s, "freecad_version": res["freecad_version"], "settings": res["settings"],
                     "command": res["command"] + f" (stepover_pct scaled by {s})", "plan_time_s": res["plan_time_s"]})
        atomic_write(cc.FIXTURES_BOUNDED / f"{name}.ngc", out.read_text(encoding="utf-8"))
        atomic_write(cc.FIXTURES_BOUNDED / f"{name}.json", json.dumps(prov, indent=1) + "\n")
        print(f"{name}: scale {s} after {len(tried)} runs", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("jobs", nargs="*", help="job names (default: every corpus job with a FreeCAD fixture)")
    ap.add_argument("--min-scale", type=float, default=0.5, help="smallest stepover scale tried")
    a = ap.parse_args(argv)
    if not 0.0 < a.min_scale <= 1.0:
        raise SystemExit(f"--min-scale must be in (0, 1] (a fraction of the job's stepover), got {a.min_scale!r}")
    names = a.jobs or cc.job_names()
    unknown = sorted(set(names) - set(cc.job_names()))
    if unknown:
        raise SystemExit(f"unknown job(s) {unknown} (the jobs are the stems of {cc.CORPUS})")
    if not freecad_available():
        raise SystemExit("needs FreeCAD (apt-get install -y --no-install-recommends freecad)")
    t0 = time.perf_counter()
    for n in names:
        bounded(n, a.min_scale)
    print(f"{len(names)} jobs in {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
