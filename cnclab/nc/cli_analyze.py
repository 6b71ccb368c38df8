"""``python -m cnclab analyze PROGRAM.ngc --job POCKET.json [--resolution 0.05] [-o OUTDIR]``

Score any RS274/NGC program — cnclab's own or another CAM's (FreeCAD, a hand-written one) — on the
collection's dixel simulator: the program is read (:func:`cnclab.nc.gcode.read_toolpath`, the
subset real posts write), taken as a :class:`~cnclab.toolpath.path.ToolPath` with the job's tool,
and evaluated by :func:`cnclab.toolpath.evaluate.evaluate` against the pocket of the job file
(:func:`cnclab.toolpath.job.load_job`). Writes into OUTDIR (default ``build/analyze/<program>``):

* ``summary.csv`` — one row per metric (metric, value, unit), also printed;
* ``trace.csv`` — the evaluator's trace along the path (s, x, y, engagement, MRR, feed, kind);
* ``trace.png`` / ``trace.pdf`` — engagement, MRR and feed against path length;
* ``engagement_map.png`` — the engagement angle coloured over the pocket.

A program the reader refuses exits with code 2 and a message naming the file, line and word; the
inputs are never overwritten; every output is written atomically, and only after all of them were
computed (nothing partial on error).
"""
from __future__ import annotations

import argparse
import io
import sys
from pathlib import Path

import numpy as np

from .. import clihelp
from ..fileio import atomic_write
from ..paths import build_dir
from .gcode import GcodeError, read_toolpath

from ..toolpath.evaluate import evaluate
from ..toolpath.job import load_job

__all__ = ["main", "analyze", "trace_figure", "engagement_map"]


def _png_pdf(fig):
    out = {}
    for ext in ("png", "pdf"):
        buf = io.BytesIO()
        fig.savefig(buf, format=ext, dpi=150, bbox_inches="tight")
        out[ext] = buf.getvalue()
    return out


def trace_figure(trace: dict, title: str = ""):
    """Figure: engagement [deg], MRR [mm³/min] and feed [mm/min] against path length [mm]."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = np.asarray(trace["s_mm"], float)
    fig, ax = plt.subplots(3, 1, figsize=(8, 6.5), sharex=True)
    for a, key, lab in zip(ax, ("engagement_deg", "mrr_mm3_min", "feed_mm_min"),
                           ("engagement [deg]", "MRR [mm³/min]", "feed [mm/min]")):
        a.plot(s, np.asarray(trace[key], float), lw=0.7)
        a.set_ylabel(lab)
        a.grid(alpha=0.3)
    ax[-1].set_xlabel("path length s [mm]")
    if title:
        ax[0].set_title(title)
    fig.tight_layout()
    return fig


def engagement_map(trace: dict, polygon=None, title: str = ""):
    """Figure: engagement angle [deg] coloured along the tool-centre path over the pocket outline."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x, y = np.asarray(trace["x"], float), np.asarray(trace["y"], float)
    e = np.asarray(trace["engagement_deg"], float)
    fig, ax = plt.subplots(figsize=(7, 6))
    if polygon is not None:
        geoms = getattr(polygon, "geoms", [polygon])
        for g in geoms:
            for ring in [g.exterior, *g.interiors]:
                cx, cy = ring.xy
                ax.plot(cx, cy, color="k", lw=0.8)
    ok = np.isfinite(e)
    sc = ax.scatter(x[ok], y[ok], c=e[ok], s=2, cmap="viridis")
    fig.colorbar(sc, ax=ax, label="engagement [deg]")
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    if title:
        ax.set_title(title)
    fig.tight_layout()
    return fig


def analyze(program, job_file, resolution_mm: float = 0.05, outdir=None, quiet: bool = False) -> dict:
    """Evaluate ``program`` against ``job_file`` and write the outputs (see the module docstring);
    returns ``{"evaluation": Evaluation, "files": [paths]}``."""
    import matplotlib.pyplot as plt

    program, job_file = Path(program), Path(job_file)
    if not (resolution_mm > 0 and np.isfinite(resolution_mm)):
        raise ValueError(f"--resolution must be a finite number > 0 mm, got {resolution_mm}")
    if not program.is_file():
        raise OSError(f"{program}: no such program file")
    job = load_job(job_file)
    path = read_toolpath(program, tool=job.tool)
    ev = evaluate(path, job, resolution_mm)
    table = ev.summary_table()
    trace = {k: np.asarray(v) for k, v in ev.trace.items()}
    outdir = Path(outdir) if outdir is not None else build_dir() / "analyze" / program.stem
    # compute every output first; then write them (nothing partial on error)
    blobs = {"summary.csv": table.to_csv(index=False)}
    cols = list(trace)
    lines = [",".join(cols)]
    for row in zip(*(trace[c] for c in cols)):
        lines.append(",".join(f"{v:.6g}" if isinstance(v, (float, np.floating)) else str(v) for v in row))
    blobs["trace.csv"] = "\n".join(lines) + "\n"
    title = f"{program.name} on {job_file.name} (resolution {resolution_mm:g} mm)"
    fig = trace_figure(trace, title)
    figs = _png_pdf(fig)
    plt.close(fig)
    blobs["trace.png"], blobs["trace.pdf"] = figs["png"], figs["pdf"]
    fig = engagement_map(trace, getattr(job, "polygon", None), title)
    blobs["engagement_map.png"] = _png_pdf(fig)["png"]
    plt.close(fig)
    files = [atomic_write(outdir / name, data, inputs=[program, job_file]) for name, data in blobs.items()]
    if not quiet:
        print(f"{program}: {len(path)} moves, tool D{path.tool.diameter:g} mm" if path.tool else f"{program}")
        for w in path.info.get("warnings", []):
            print("note:", w)
        print(table.to_string(index=False))
        print("wrote", ", ".join(str(f) for f in files))
    return {"evaluation": ev, "files": files}


def main(argv=None) -> int:
    ap = clihelp.parser(
        "python -m cnclab analyze",
        "Score any RS274/NGC program (cnclab's own or another CAM's: FreeCAD, hand-written) on a pocket\n"
        "job with the collection's dixel simulator: engagement angle, MRR, feed, time, uncut area,\n"
        "plunges and rapids into material. A program the reader refuses exits with code 2 naming the\n"
        "file, line and word; inputs are never overwritten; all outputs are written together or none.",
        examples=["python -m cnclab analyze star.ngc --job data/jacso2021/star_pocket.json",
                  "python -m cnclab analyze tests/fixtures/freecad/two_regions.ngc --job data/pockets/two_regions.json "
                  "--resolution 0.25 -o build/freecad_two_regions"],
        writes=["OUTDIR/summary.csv        one row per metric (metric, value, unit), also printed",
                "OUTDIR/trace.csv          the trace along the path (s, x, y, engagement, MRR, feed, kind)",
                "OUTDIR/trace.png, .pdf    engagement, MRR and feed against path length",
                "OUTDIR/engagement_map.png the engagement angle coloured over the pocket"])
    ap.add_argument("program", help="RS274/NGC program (.ngc/.nc/.tap, mm)")
    ap.add_argument("--job", required=True, help="pocket job file (JSON, mm; keys in docs/job-format.md)")
    ap.add_argument("--resolution", type=float, default=0.05, help="dixel size of the simulation (mm)")
    ap.add_argument("-o", "--outdir", default=None, help="output folder (default: build/analyze/<program name>)")
    args = ap.parse_args(argv)
    try:
        analyze(args.program, args.job, args.resolution, args.outdir)
    except (GcodeError, ValueError, OSError, RuntimeError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0
