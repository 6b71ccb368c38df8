"""``python -m cnclab analyze PROGRAM.ngc --job POCKET.json [--resolution 0.05] [-o OUTDIR]``

Score any RS274/NGC program — cnclab's own or another CAM's (FreeCAD, a hand-written one) — on the
collection's dixel simulator: the program is read (:func:`cnclab.nc.gcode.read_toolpath`, the
subset real posts write), taken as a :class:`~cnclab.toolpath.path.ToolPath` with the job's tool,
and evaluated by :func:`cnclab.toolpath.evaluate.evaluate` against the pocket of the job file
(:func:`cnclab.toolpath.job.load_job`). Writes into OUTDIR (default ``build/analyze/<program>``):

* ``summary.csv`` — one row per metric (metric, value, unit), also printed; ``time_machine_s`` is
  the program's time on the small-VMC machine model (:mod:`cnclab.nc.machine`: acceleration,
  junction deviation) beside the evaluator's length / feed ``time_total_s``;
  ``uncut_exact_mm2`` is the uncut area beyond the unreachable corners independent of the
  resolution (:func:`cnclab.toolpath.coverage.uncut_report` with ``at_or_below``: a point of a
  level's floor is uncut when no move at or below that level passes within r + 2 um of it, summed
  over the levels) -- the dixel count ``uncut_beyond_unreachable_mm2`` also holds the rows' slivers
  along the walls, about proportional to the resolution (on a 67 x 87 mm T with D10, three levels:
  6.3, 2.7 and 1.3 mm^2 at 0.225, 0.1 and 0.05 mm where the exact count reads 0.0);
* ``trace.csv`` — the evaluator's trace along the path (s, x, y, engagement, MRR, feed, kind, wall
  gouge, move index and program line of every sample);
* ``events.csv`` — rapids and plunges into material and wall gouges, one row per block, with its
  program line (also printed);
* ``trace.png`` / ``trace.pdf`` — engagement, MRR and feed against path length;
* ``engagement_map.png`` — the engagement angle coloured over the pocket.

A program the reader refuses exits with code 2 and a message naming the file, line and word; the
inputs are never overwritten; the outputs are written together (all or none, after all of them were
computed; an output folder that is a file or an output that is an input is refused before anything
is computed). Warnings (printed as ``warning:``) flag what LinuxCNC would run but a machinist should
question: see :func:`analyze`.
"""
from __future__ import annotations

import argparse
import io
import math
from pathlib import Path

import numpy as np

from .. import clihelp
from ..fileio import InterruptReport, atomic_write_many, check_outputs
from ..paths import build_dir
from ..plotting import figsize, with_style
from .gcode import GcodeError, read_toolpath

from ..toolpath.coverage import uncut_report
from ..toolpath.evaluate import POSITION_TOL_MM, evaluate
from ..toolpath.job import load_job
from ..toolpath.planners import MAX_RESOLUTION_TOOL_FRACTION, MIN_RESOLUTION_MM

__all__ = ["main", "analyze", "trace_figure", "engagement_map"]


def _png_pdf(fig):
    out = {}
    for ext in ("png", "pdf"):
        buf = io.BytesIO()
        # no creation date in the PDF: the same program and job give the same bytes (as plotting.savefig)
        fig.savefig(buf, format=ext, dpi=150, bbox_inches="tight",
                    metadata={"CreationDate": None} if ext == "pdf" else None)
        out[ext] = buf.getvalue()
    return out


@with_style
def trace_figure(trace: dict, title: str = ""):
    """Figure: engagement [deg], MRR [mm³/min] and feed [mm/min] against path length [mm]."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = np.asarray(trace["s_mm"], float)
    fig, ax = plt.subplots(3, 1, figsize=figsize(1.35, 1.7), sharex=True)
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


@with_style
def engagement_map(trace: dict, polygon=None, title: str = ""):
    """Figure: engagement angle [deg] coloured along the tool-centre path over the pocket outline."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x, y = np.asarray(trace["x"], float), np.asarray(trace["y"], float)
    e = np.asarray(trace["engagement_deg"], float)
    fig, ax = plt.subplots(figsize=figsize(1.15, 1.6))
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


#: bounds of ``--resolution`` (mm): those of ``plan``'s ``resolution_mm``
#: (:data:`cnclab.toolpath.planners.MIN_RESOLUTION_MM`, D x :data:`~cnclab.toolpath.planners.MAX_RESOLUTION_TOOL_FRACTION`,
#: the reasons there). Samples and rows are also bounded (memory, run time).
MAX_SAMPLES = 5_000_000
MAX_ROWS = 100_000
OUTPUT_NAMES = ("summary.csv", "trace.csv", "events.csv", "trace.png", "trace.pdf", "engagement_map.png")


def _check_resolution(h: float, job, path) -> None:
    """ValueError naming ``--resolution`` when ``h`` (mm) is outside the bounds for this job/program."""
    if not (isinstance(h, (int, float)) and math.isfinite(h) and h > 0):
        raise ValueError(f"--resolution must be a finite number > 0 mm, got {h}")
    hi = MAX_RESOLUTION_TOOL_FRACTION * job.tool_diameter
    if h < MIN_RESOLUTION_MM or h > hi:
        raise ValueError(f"--resolution must be in [{MIN_RESOLUTION_MM:g}, {hi:g}] mm for a D {job.tool_diameter:g} mm "
                         f"tool (at most D/10: the tool disc must span 10 dixel rows), got {h:g}")
    minx, miny, maxx, maxy = job.polygon.bounds
    rows = (maxy - miny) / h
    samples = float(path.segment_lengths().sum()) / h
    if rows > MAX_ROWS or samples > MAX_SAMPLES:
        need = max((maxy - miny) / MAX_ROWS, float(path.segment_lengths().sum()) / MAX_SAMPLES)
        raise ValueError(f"--resolution {h:g} mm needs {samples:.3g} path samples and {rows:.3g} dixel rows (limits "
                         f"{MAX_SAMPLES:.0e} and {MAX_ROWS:.0e}): use --resolution {need:.3g} or more")


def _check_outdir(outdir: Path, inputs) -> list:
    """The output paths; refused (before anything is computed or written) when the folder or one of
    its parents is a file, or an output would overwrite an input."""
    for q in [outdir, *outdir.parents]:
        if q.exists():
            if not q.is_dir():
                what = "the output folder" if q == outdir else f"a parent of the output folder {outdir}"
                raise ValueError(f"-o/--outdir: {q} is a file, not a folder ({what}): choose another output folder")
            break
    outs = [outdir / name for name in OUTPUT_NAMES]
    check_outputs(outs, inputs)
    return outs


def _bbox_warnings(path, job, ev, program: Path, job_file: Path) -> list:
    """Warnings about where the program goes relative to the pocket (see :func:`analyze`); raises
    ValueError when no feed move comes near the pocket at all."""
    out = []
    t = ev.trace
    r = job.tool_radius
    feed = np.asarray(t["kind"]) != "rapid"
    X, Y = np.asarray(t["x"]), np.asarray(t["y"])
    lines = np.asarray(t.get("line", t["move"]))
    minx, miny, maxx, maxy = job.polygon.bounds
    ex = np.maximum.reduce([minx - X, X - maxx, miny - Y, Y - maxy, np.zeros_like(X)])   # outside the bbox (mm)
    inch = bool(path.info.get("converted_from_inch"))
    if feed.any():
        fx, fy = X[feed], Y[feed]
        pb = (fx.min(), fy.min(), fx.max(), fy.max())
        overlap = not (pb[2] < minx - r or pb[0] > maxx + r or pb[3] < miny - r or pb[1] > maxy + r)
        scale = 1 / 25.4 if inch else 25.4
        alt = _iou((pb[0] * scale, pb[1] * scale, pb[2] * scale, pb[3] * scale), job.polygon.bounds)
        hint = (" The program states G20 (inches): its numbers look like mm." if inch and alt > 0.3 else
                " Its numbers look like inches without G20." if not inch and alt > 0.3 else "")
        if not overlap:
            raise ValueError(f"{program}: no feed move comes near the pocket of {job_file}: the feed moves span "
                             f"X {pb[0]:.4g}..{pb[2]:.4g}, Y {pb[1]:.4g}..{pb[3]:.4g} mm, the pocket X {minx:.4g}..{maxx:.4g}, "
                             f"Y {miny:.4g}..{maxy:.4g} mm (work offset or units?).{hint}")
        if hint and alt > 2.0 * _iou(pb, job.polygon.bounds):
            out.append(f"{program}: units look wrong:{hint} (bounding box of the feed moves X {pb[0]:.4g}..{pb[2]:.4g}, "
                       f"Y {pb[1]:.4g}..{pb[3]:.4g} mm vs the pocket's X {minx:.4g}..{maxx:.4g}, Y {miny:.4g}..{maxy:.4g} mm)")
        far = feed & (ex > r + POSITION_TOL_MM)
        if far.any():
            k = int(np.argmax(np.where(far, ex, -1.0)))
            out.append(f"{program}:{int(lines[np.flatnonzero(far)[0]])}: feed moves leave the pocket's bounding box by more "
                       f"than the tool radius ({int(len(np.unique(lines[far])))} block(s); farthest {ex[k] - r:.4g} mm beyond "
                       f"the reach of the tool at line {int(lines[k])}, X {X[k]:.4g} Y {Y[k]:.4g})")
    else:
        out.append(f"{program}: no feed move (G1/G2/G3): the program cuts nothing")
    margin = max(math.hypot(maxx - minx, maxy - miny), 50.0)
    far = ~feed & (ex > margin)
    if far.any():
        k = int(np.argmax(np.where(far, ex, -1.0)))
        out.append(f"{program}:{int(lines[k])}: a rapid goes {ex[k]:.4g} mm outside the pocket's bounding box "
                   f"(more than {margin:.4g} mm; X {X[k]:.4g} Y {Y[k]:.4g})")
    return out


def _iou(a, b) -> float:
    """Intersection over union of two boxes (minx, miny, maxx, maxy); degenerate boxes grown by 1e-9."""
    iw = min(a[2], b[2]) - max(a[0], b[0])
    ih = min(a[3], b[3]) - max(a[1], b[1])
    inter = max(iw, 0.0) * max(ih, 0.0)
    area = lambda q: max(q[2] - q[0], 1e-9) * max(q[3] - q[1], 1e-9)
    return inter / (area(a) + area(b) - inter)


def _trace_csv(trace: dict) -> str:
    import pandas as pd

    n = len(trace["s_mm"])
    cols = {k: np.asarray(v) for k, v in trace.items() if np.ndim(v) == 1 and len(v) == n}
    return pd.DataFrame(cols).to_csv(index=False, float_format="%.6g", lineterminator="\n")


def analyze(program, job_file, resolution_mm: float = 0.05, outdir=None, quiet: bool = False) -> dict:
    """Evaluate ``program`` against ``job_file`` and write the outputs (see the module docstring);
    returns ``{"evaluation": Evaluation, "files": [paths], "warnings": [str]}``.

    The path is sampled by arc length (:func:`cnclab.toolpath.evaluate.resample_by_length`), so the
    figures do not depend on how finely the program is split into blocks. Warnings (printed, and
    returned): the reader's (G20 conversion, no M2/M30 or closing ``%``, a last block without line
    end, blocks after the end, a tool change after the first move, a tool comment contradicting the
    job's tool), feed moves farther outside the pocket's bounding box than the tool radius, rapids
    farther out than its diagonal (at least 50 mm), units that look wrong (the feed moves' bounding box
    matches the pocket's better after x 25.4 or / 25.4). A program whose feed moves all lie outside
    the pocket (and cut nothing) is an error. Events (rapids and plunges into material, wall gouges)
    are listed with their program lines in ``events.csv``; ``trace.csv`` has the ``line`` of every
    sample. Errors (``ValueError``/``OSError``) name the file, line, option; nothing is written then.
    """
    import matplotlib.pyplot as plt

    program, job_file = Path(program), Path(job_file)
    if not (isinstance(resolution_mm, (int, float)) and math.isfinite(resolution_mm) and resolution_mm > 0):
        raise ValueError(f"--resolution must be a finite number > 0 mm, got {resolution_mm}")
    if not program.is_file():
        raise OSError(f"{program}: no such program file")
    outdir = Path(outdir) if outdir is not None else build_dir() / "analyze" / program.stem
    outs = _check_outdir(outdir, [program, job_file])
    job = load_job(job_file)
    path = read_toolpath(program, tool=job.tool)
    if len(path) < 2:
        raise ValueError(f"{program}: {len(path)} move(s) with a known position: nothing to analyze (an empty or "
                         "comment-only program?)")
    _check_resolution(resolution_mm, job, path)
    ev = evaluate(path, job, resolution_mm, sampling="arc_length")
    notes = list(path.info.get("warnings", [])) + _bbox_warnings(path, job, ev, program, job_file)
    table = ev.summary_table()      # with time_machine_s: the program on the small-VMC model (cnclab.nc.machine)
    import pandas as pd

    exact = float(sum(uncut_report(path, job, at_or_below=True)["uncut_mm2"]))
    table = pd.concat([table, pd.DataFrame([{"metric": "uncut_exact_mm2", "value": exact, "unit": "mm^2"}])],
                      ignore_index=True)
    trace = ev.trace
    blobs = {"summary.csv": table.to_csv(index=False, lineterminator="\n"), "trace.csv": _trace_csv(trace),
             "events.csv": ev.events.to_csv(index=False, float_format="%.6g", lineterminator="\n")}
    title = f"{program.name} on {job_file.name} (resolution {resolution_mm:g} mm)"
    fig = trace_figure(trace, title)
    figs = _png_pdf(fig)
    plt.close(fig)
    blobs["trace.png"], blobs["trace.pdf"] = figs["png"], figs["pdf"]
    fig = engagement_map(trace, getattr(job, "polygon", None), title)
    blobs["engagement_map.png"] = _png_pdf(fig)["png"]
    plt.close(fig)
    files = atomic_write_many([(o, blobs[o.name]) for o in outs], inputs=[program, job_file])
    if not quiet:
        print(f"{program}: {len(path)} moves, tool D{path.tool.diameter:g} mm" if path.tool else f"{program}")
        for w in notes:
            print("warning:", w)
        print(table.to_string(index=False))
        _print_events(ev.events, program)
        print("wrote", ", ".join(str(f) for f in files))
    return {"evaluation": ev, "files": files, "warnings": notes}


def _print_events(events, program: Path) -> None:
    """One line per event kind: blocks, the worst one with its program line, the first lines."""
    for name, grp in events.groupby("event", sort=False):
        w = grp.loc[grp["value"].idxmax()]
        first = ", ".join(str(v) for v in grp["line"].head(8))
        print(f"event: {name}: {len(grp)} block(s), worst {w['value']:.4g} {w['unit']} at {program}:{w['line']} "
              f"(X{w['x']:.4f} Y{w['y']:.4f} Z{w['z']:.4f}); lines {first}{' ...' if len(grp) > 8 else ''} "
              "(all in events.csv)")


def main(argv=None) -> int:
    ap = clihelp.parser(
        "python -m cnclab analyze",
        "Score any RS274/NGC program (cnclab's own or another CAM's: FreeCAD, hand-written) on a pocket\n"
        "job with the collection's dixel simulator: engagement angle, MRR, feed, time, uncut area,\n"
        "plunges and rapids into material, wall gouge (with program lines). A program the reader refuses exits with code 2 naming the\n"
        "file, line and word; inputs are never overwritten; all outputs are written together or none.",
        examples=["python -m cnclab analyze star.ngc --job data/jacso2021/star_pocket.json",
                  "python -m cnclab analyze tests/fixtures/freecad/two_regions.ngc --job data/pockets/two_regions.json "
                  "--resolution 0.25 -o build/freecad_two_regions"],
        writes=["OUTDIR/summary.csv        one row per metric (metric, value, unit), also printed",
                "OUTDIR/trace.csv          the trace along the path (s, x, y, engagement, MRR, feed, kind,\n"
                "                          wall gouge, move and program line of every sample)",
                "OUTDIR/events.csv         rapids/plunges into material and wall gouges with their program lines",
                "OUTDIR/trace.png, .pdf    engagement, MRR and feed against path length",
                "OUTDIR/engagement_map.png the engagement angle coloured over the pocket"])
    ap.add_argument("program", help="RS274/NGC program (.ngc/.nc/.tap, mm)")
    ap.add_argument("--job", required=True, help="pocket job file (JSON, mm; keys in docs/job-format.md)")
    ap.add_argument("--resolution", type=float, default=0.05, help="dixel size of the simulation (mm)")
    ap.add_argument("-o", "--outdir", default=None, help="output folder (default: build/analyze/<program name>)")
    args = ap.parse_args(argv)
    outdir = Path(args.outdir) if args.outdir is not None else build_dir() / "analyze" / Path(args.program).stem
    # an interrupt says what is on disk
    return InterruptReport([outdir / name for name in OUTPUT_NAMES]).call(
        lambda: analyze(args.program, args.job, args.resolution, outdir), (GcodeError, ValueError, OSError, RuntimeError))
