"""``python -m cnclab plan JOB.json -o PROGRAM.ngc [--strategy NAME]``

Plan a pocket job with one of the collection's 2.5D strategies
(:func:`cnclab.toolpath.planners.plan`; default the engagement-controlled clearing ``adaptive``,
:data:`cnclab.toolpath.planners.DEFAULT_STRATEGY`) and write it as a machine-safe
program (:func:`cnclab.nc.program.write_program`: start block, ``T.. M6``, ``S.. M3`` before cutting,
rapids only at the clearance plane or in cleared area, ``M5 M30``). The program is checked
(:func:`cnclab.nc.program.check_program`) before it is written; the job file is never overwritten;
the output is written atomically. Errors exit with code 2 and a message naming the file.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .. import clihelp
from ..fileio import atomic_write
from .program import check_program, write_program

from ..toolpath.job import load_job
from ..toolpath.planners import DEFAULT_STRATEGY, STRATEGIES, plan

__all__ = ["main", "plan_program", "planned_program"]


def planned_program(job_file, strategy: str | None = None, source: str | None = None):
    """Plan ``job_file`` with ``strategy`` (None: the planner's default) and write its program text:
    ``(text, job, path, check)`` — what ``python -m cnclab plan`` writes (also used by
    ``python -m cnclab programs``). Raises ``ValueError`` when the program fails the static safety
    check; ``source`` names the program in the messages."""
    if load_job is None or plan is None:
        raise RuntimeError("cnclab plan needs cnclab.toolpath.job and cnclab.toolpath.planners "
                           f"(issue 12, toolpath-core), not available: {_MISSING}")
    job_file = Path(job_file)
    job = load_job(job_file)
    path = plan(job) if strategy is None else plan(job, strategy)
    name = strategy or path.info.get("strategy", "default")
    text = write_program(path, job, header=[f"cnclab plan {job_file.name} strategy {name}"])
    src = str(source or job_file.with_suffix(".ngc").name)
    chk = check_program(text, clearance_z=job.clearance_z, top_z=getattr(job, "top_z", 0.0), source=src)
    if chk.errors:      # every planner tags its plunges into a start hole or cleared area 'cleared'
        raise ValueError(f"{src}: the planned program fails the safety check: " + "; ".join(chk.errors[:5]))
    return text, job, path, chk


def plan_program(job_file, out, strategy: str | None = None, quiet: bool = False) -> Path:
    """Plan ``job_file`` with ``strategy`` (None: the planner's default) and write the program to
    ``out``; returns the output path. Raises ``ValueError`` when the written program fails the
    static safety check (nothing is written then)."""
    job_file, out = Path(job_file), Path(out)
    text, job, path, chk = planned_program(job_file, strategy, source=str(out))
    name = strategy or path.info.get("strategy", "default")
    atomic_write(out, text, inputs=[job_file])
    if not quiet:
        print(f"wrote {out}: {len(path)} moves, strategy {name}, entries {chk.entries}, "
              f"plunges below the stock top marked cleared or none: {chk.plunges_into_material == 0}")
    return out


def main(argv=None) -> int:
    ap = clihelp.parser(
        "python -m cnclab plan",
        "Plan a 2.5D pocket job (JSON, mm) and write a machine-safe RS274/NGC program: start block,\n"
        "tool change, spindle on before cutting, entries by helix/ramp or into cleared area, rapids only\n"
        "at the clearance plane or through cleared area, M5 M30. The program is checked before it is\n"
        "written; the job file is never overwritten; errors exit with code 2 naming the file and key.\n"
        "Job keys: docs/job-format.md.",
        examples=["python -m cnclab plan data/jacso2021/star_pocket.json -o star.ngc",
                  "python -m cnclab plan my_pocket.json -o my_pocket.ngc --strategy zig-zag"],
        writes=["OUTPUT: the program (only this file, atomically)"])
    ap.add_argument("job", help="pocket job file (JSON, mm; keys in docs/job-format.md)")
    ap.add_argument("-o", "--output", required=True, help="program to write (.ngc, must differ from the job file)")
    ap.add_argument("--strategy", default=None, metavar="NAME",
                    help=f"planner: {', '.join(sorted(STRATEGIES))} (default: {DEFAULT_STRATEGY})")
    args = ap.parse_args(argv)
    try:
        plan_program(args.job, args.output, args.strategy)
    except (ValueError, OSError, RuntimeError, KeyError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0
