"""``python -m cnclab job-from-drawing DRAWING.dxf|DRAWING.svg --cutting CUTTING.json -o JOB.json [--layer NAME]``

Write a pocket job file from a drawing and cutting data: the closed outlines of the drawing (of
``--layer``, or of every layer) become the pocket outline(s) and islands, nested by containment and
flattened to ``--tolerance`` mm of chord error (:func:`cnclab.geometry.drawing.read_drawing`); CUTTING.json
gives every other job key (tool, engagement, depths, speeds; :mod:`cnclab.toolpath.from_drawing`). The
job is validated like any job file (:func:`cnclab.toolpath.job.Job.from_dict`) before it is written,
atomically; the inputs are never overwritten. Errors exit with code 2 naming the file and the entity
or key; the notes (units, what was skipped) and warnings go to stderr.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

from .. import clihelp
from ..fileio import atomic_write, check_outputs
from ..geometry.drawing import CHORD_TOL_MM, JOIN_TOL_MM
from ..toolpath.from_drawing import job_from_drawing

__all__ = ["job_json_text", "main", "write_job_from_drawing"]


def job_json_text(d: dict) -> str:
    """A job mapping as JSON text: one top-level key per line, each value compact (a ring on one line)."""
    return "{\n" + ",\n".join(f" {json.dumps(k)}: {json.dumps(v)}" for k, v in d.items()) + "\n}\n"


def write_job_from_drawing(drawing, cutting, out, layer: str | None = None, tolerance: float = CHORD_TOL_MM,
                           units: str | None = None, join_tol: float = JOIN_TOL_MM, quiet: bool = False) -> Path:
    """Read ``drawing`` and ``cutting`` into a job (validated) and write its JSON to ``out``; returns
    ``out``. Nothing is written on an error; ``out`` may not be one of the inputs."""
    drawing, cutting, out = Path(drawing), Path(cutting), Path(out)
    check_outputs([out], [drawing, cutting])
    job, d = job_from_drawing(drawing, cutting, layer=layer, tolerance=tolerance, units=units, join_tol=join_tol)
    atomic_write(out, job_json_text(d), inputs=[drawing, cutting])
    if not quiet:
        polys = list(getattr(job.polygon, "geoms", [job.polygon]))
        n_isl = sum(len(p.interiors) for p in polys)
        print(f"wrote {out}: {len(polys)} region(s), {n_isl} island(s), pocket area {job.polygon.area:.3f} mm^2")
        for n in d["_drawing"]["notes"]:
            print(f"note: {n}", file=sys.stderr)
        for w in job.warnings:
            print(f"warning: {w}", file=sys.stderr)
    return out


def main(argv=None) -> int:
    ap = clihelp.parser(
        "python -m cnclab job-from-drawing",
        "Write a pocket job file (JSON, mm) from a drawing (.dxf or .svg) and cutting data. The closed\n"
        "outlines of the drawing (of --layer, or of every layer) become the pocket outline(s) and islands,\n"
        "nested by containment, curves flattened to --tolerance mm of chord error; DXF units from\n"
        "$INSUNITS (a unitless drawing is read as mm and says so). CUTTING.json holds every other job key\n"
        "(tool, engagement, depths, speeds). Open outlines are refused naming the entity and the gap.\n"
        "The job is validated before it is written; the inputs are never overwritten. Job keys:\n"
        "docs/job-format.md.",
        examples=["python -m cnclab job-from-drawing part.dxf --layer POCKET --cutting cutting.json -o part.json",
                  "python -m cnclab job-from-drawing tests/fixtures/drawings/done_when.svg --layer POCKET "
                  "--cutting tests/fixtures/drawings/cutting.json -o done_when.json"],
        writes=["OUTPUT: the job file (only this file, atomically); notes and warnings on stderr"])
    ap.add_argument("drawing", help="the drawing (.dxf or .svg)")
    ap.add_argument("--cutting", required=True, metavar="CUTTING.json",
                    help="every job key except the geometry (JSON)")
    ap.add_argument("-o", "--output", required=True, help="job file to write (.json, must differ from the inputs)")
    ap.add_argument("--layer", default=None, metavar="NAME", help="read the outlines of this layer only (DXF layer, "
                    "SVG group id or inkscape:label; default: every layer)")
    ap.add_argument("--tolerance", type=float, default=CHORD_TOL_MM, metavar="MM",
                    help=f"chord error of the flattening of curves, mm (default {CHORD_TOL_MM})")
    ap.add_argument("--join-tol", type=float, default=JOIN_TOL_MM, metavar="MM",
                    help=f"largest gap between chained ends, mm (default {JOIN_TOL_MM})")
    ap.add_argument("--units", default=None, help="the drawing's unit (mm, inch, cm, m), overriding $INSUNITS / "
                    "the SVG size (default: from the drawing; a unitless DXF is read as mm)")
    args = ap.parse_args(argv)
    try:
        write_job_from_drawing(args.drawing, args.cutting, args.output, layer=args.layer, tolerance=args.tolerance,
                               units=args.units, join_tol=args.join_tol)
    except (ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0
