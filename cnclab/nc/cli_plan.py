"""``python -m cnclab plan JOB.json|DRAWING.dxf|DRAWING.svg [--cutting CUTTING.json] [--layer NAME] -o PROGRAM.ngc [--strategy NAME]``

Plan a pocket job with one of the collection's 2.5D strategies
(:func:`cnclab.toolpath.planners.plan`; default the engagement-controlled clearing ``adaptive``,
:data:`cnclab.toolpath.planners.DEFAULT_STRATEGY`) and write it as a machine-safe
program (:func:`cnclab.nc.program.write_program`: start block, ``T.. M6``, ``S.. M3`` before cutting,
rapids only at the clearance plane or in cleared area, ``M5 M30``). The program is checked
(:func:`cnclab.nc.program.check_program`) before it is written; the job file is never overwritten;
the output is written atomically. Errors exit with code 2 and a message naming the file.

A drawing (.dxf/.svg) gives the pocket (:func:`cnclab.geometry.drawing.read_drawing`: closed outlines
of ``--layer`` or of every layer, islands by containment) and ``--cutting CUTTING.json`` every other
job key (:mod:`cnclab.toolpath.from_drawing`).
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

from .. import clihelp
from ..fileio import InterruptReport, check_outputs
from .gcode import program_time, read_gcode
from .machine import machine_for_dialect, machine_time
from .program import COOLANT, DIALECTS, check_program, program_path, write_program

from ..geometry.drawing import CHORD_TOL_MM
from ..toolpath.from_drawing import load_job_input
from ..toolpath.adaptive import AdaptiveParams
from ..toolpath.job import load_job
from ..toolpath.planners import (CE_PROMISE_DEG, CE_SHARE_ABOVE_5_PCT, DEFAULT_STRATEGY, HYBRID_JACSO_MAX_DEG,
                                 HYBRID_JACSO_SHARE_ABOVE_5_PCT, MIN_RESOLUTION_MM,
                                 STRATEGIES, plan)

__all__ = ["main", "plan_program", "planned_program", "with_machine_warnings"]


def with_machine_warnings(job, dialect: str):
    """``job`` with a warning (naming the key) for each feed above the X/Y rate of the dialect's machine
    model (:func:`cnclab.nc.machine.machine_for_dialect`: an assumed machine, so a warning -- the
    controller caps the feed -- where the job's own ``feed_max_mm_min`` is an error)."""
    m = machine_for_dialect(dialect)
    vmax = min(m.max_rate_mm_min[:2])
    feeds = (("feed_mm_min", job.feed_mm_min), ("link_feed", job.link_feed_mm_min), ("v_fmax", job.v_fmax))
    warns = [f"{job.source}: $.{key}: {v:g} mm/min is above the X/Y rate {vmax:g} mm/min of the {m.name} machine "
             f"model of --dialect {dialect}: the controller will cap it" for key, v in feeds if v > vmax * (1 + 1e-9)]
    return dataclasses.replace(job, warnings=tuple(job.warnings) + tuple(warns)) if warns else job


def planned_program(job_file, strategy: str | None = None, source: str | None = None, *, cutting=None,
                    layer: str | None = None, tolerance: float = CHORD_TOL_MM, units: str | None = None,
                    dialect: str = "linuxcnc", coolant: str | None = None, out=None, inputs=(),
                    plan_options: dict | None = None):
    """Plan ``job_file`` with ``strategy`` (None: the planner's default) and write its program text:
    ``(text, job, path, check)`` — what ``python -m cnclab plan`` writes (also used by
    ``python -m cnclab programs``). Raises ``ValueError`` when the program fails the static safety
    check or leaves more uncut area than :func:`cnclab.toolpath.coverage.uncut_limit_mm2` allows in a
    region (with ``plan_options={"allow_uncut": True}``: a WARNING line in the program header instead, and in
    ``path.info["warnings"]``); ``source`` names the program in the messages. ``job_file`` may be a
    drawing (.dxf/.svg): then ``cutting`` (CUTTING.json) gives every other job key,
    ``layer``/``tolerance`` (mm)/``units`` how the drawing is read
    (:func:`cnclab.toolpath.from_drawing.load_job_input`); ``plan_options`` are keywords of
    :func:`cnclab.toolpath.planners.plan`: ``allow_uncut`` (bool), ``resolution_mm`` (mm, None: each
    planner's default; bounded to [0.005, D/10])."""
    if load_job is None or plan is None:
        raise RuntimeError("cnclab plan needs cnclab.toolpath.job and cnclab.toolpath.planners "
                           f"(issue 12, toolpath-core), not available: {_MISSING}")
    job_file = Path(job_file)
    job = load_job_input(job_file, cutting=cutting, layer=layer, tolerance=tolerance, units=units)
    job = with_machine_warnings(job, dialect)
    # the adaptive promise is checked on the path as this program writes it (the arc fit)
    path = plan(job, strategy or DEFAULT_STRATEGY, written=program_path, **(plan_options or {}))
    name = strategy or path.info.get("strategy", "default")
    rep = path.info["uncut"]
    header = [f"cnclab plan {job_file.name} strategy {name}",
              "uncut beyond unreachable corners by region, mm^2: "
              + ", ".join(f"{u:.1f} of limit {lim:.1f}" for u, lim in zip(rep["uncut_mm2"], rep["limit_mm2"]))]
    if cutting is not None:
        header.insert(1, f"geometry from {job_file.name} layer {layer if layer is not None else 'all'}, chord "
                         f"tolerance {tolerance:g} mm; cutting data from {Path(cutting).name}")
    # a header line is a G-code comment: no parentheses inside
    # the planner's warnings: what --allow-uncut / --allow-engagement-breach let through
    header += ["WARNING: " + w.replace("(", "[").replace(")", "]") for w in path.info.get("warnings", [])]
    header += ["WARNING job: " + w.replace("(", "[").replace(")", "]") for w in getattr(job, "warnings", ())]
    # with ``out`` the one writer checks the text and writes it atomically (nothing written on error)
    text = write_program(path, job, header=header, dialect=dialect, coolant=coolant, out=out, inputs=inputs)
    src = str(source or job_file.with_suffix(".ngc").name)
    # the lines named are those of the planned text (nothing is written when it fails): never of a file
    chk = check_program(text, clearance_z=job.clearance_z, top_z=getattr(job, "top_z", 0.0),
                        source="<planned program>")
    if chk.errors:      # every planner tags its plunges into a start hole or cleared area 'cleared'
        raise ValueError(f"{src}: the planned program fails the safety check (nothing written): "
                         + "; ".join(chk.errors[:5]))
    return text, job, path, chk


def plan_program(job_file, out, strategy: str | None = None, quiet: bool = False, *, cutting=None,
                 layer: str | None = None, tolerance: float = CHORD_TOL_MM, units: str | None = None,
                 dialect: str = "linuxcnc", coolant: str | None = None, **plan_options) -> Path:
    """Plan ``job_file`` (a job file, or a drawing with ``cutting`` data, see :func:`planned_program`)
    with ``strategy`` (None: the planner's default) and write the program to ``out``; returns the
    output path. Raises ``ValueError`` when the written program fails the static safety check or
    leaves too much uncut or breaks the planner's engagement promise (nothing is written then);
    ``plan_options`` go to :func:`cnclab.toolpath.planners.plan` (``allow_uncut``,
    ``allow_engagement_breach``: the warning is then printed to stderr and written in the header;
    ``resolution_mm``). The job's plausibility warnings go to stderr
    unless ``quiet``."""
    job_file, out = Path(job_file), Path(out)
    inputs = [job_file] + ([Path(cutting)] if cutting is not None else [])
    check_outputs([out], inputs)
    text, job, path, chk = planned_program(job_file, strategy, source=str(out), cutting=cutting, layer=layer,
                                           tolerance=tolerance, units=units, dialect=dialect, coolant=coolant, out=out,
                                           inputs=inputs,
                                           plan_options=plan_options)
    for w in path.info.get("warnings", []):
        print(f"warning: {w}", file=sys.stderr)
    name = strategy or path.info.get("strategy", "default")
    if not quiet:
        for w in getattr(job, "warnings", ()):
            print(f"warning: {w}", file=sys.stderr)
        uncut = ", ".join(f"{u:.1f}" for u in path.info["uncut"]["uncut_mm2"])
        moves = read_gcode(text).moves
        t = program_time(moves, job.rapid_mm_min)["total_s"]        # the written program's time
        m = machine_for_dialect(dialect)
        print(f"wrote {out} ({dialect}): {len(path)} planned moves, {len(moves)} motion blocks, strategy {name}, "
              f"entries {chk.entries}, plunges below the stock top marked cleared or none: "
              f"{chk.plunges_into_material == 0}, uncut beyond the unreachable corners by region: {uncut} mm^2; "
              f"program time {t / 60:.2f} min (length / feed), time_machine_s "
              f"{machine_time(moves, m)['time_machine_s']:.1f} s ({m.name} model)")
    return out


def main(argv=None) -> int:
    ap = clihelp.parser(
        "python -m cnclab plan",
        "Plan a 2.5D pocket job (JSON, mm) and write a machine-safe RS274/NGC program: start block,\n"
        "tool change, spindle on before cutting, entries by helix/ramp or into cleared area, rapids only\n"
        "at the clearance plane or through cleared area, M5 M30. The program is checked before it is\n"
        "written; the job file is never overwritten; errors exit with code 2 naming the file and key.\n"
        "The job may be a drawing (.dxf/.svg: its closed outlines, islands by containment) with\n"
        "--cutting CUTTING.json holding every other job key. Job keys: docs/job-format.md.",
        examples=["python -m cnclab plan data/jacso2021/star_pocket.json -o star.ngc",
                  "python -m cnclab plan my_pocket.json -o my_pocket.ngc --strategy zig-zag",
                  "python -m cnclab plan part.dxf --layer POCKET --cutting cutting.json -o part.ngc"],
        writes=["OUTPUT: the program (only this file, atomically)"])
    ap.add_argument("job", help="pocket job file (JSON, mm; keys in docs/job-format.md), or a drawing "
                    "(.dxf/.svg) with --cutting")
    ap.add_argument("-o", "--output", required=True, help="program to write (.ngc, must differ from the inputs)")
    ap.add_argument("--strategy", default=None, metavar="NAME",
                    help=f"planner: {', '.join(sorted(STRATEGIES))} (default: {DEFAULT_STRATEGY}). "
                         f"constant-engagement plans only a pocket on which it keeps the engagement <= theta + "
                         f"{CE_PROMISE_DEG:g} deg and <= theta + 5 deg on all but {CE_SHARE_ABOVE_5_PCT:g} %% of its "
                         "cutting length, measured on each job (planned so far: discs, ellipses, rectangles also "
                         "filleted or rotated, a U; refused with the measured values: L, star, islands); "
                         "hybrid promises no engagement bound (measured on Jacso's star, rectangle and L: <= theta "
                         f"+ {HYBRID_JACSO_MAX_DEG:g} deg, {HYBRID_JACSO_SHARE_ABOVE_5_PCT:g} %% above theta + 5; "
                         "159.5 deg on a keyhole)")
    ap.add_argument("--cutting", default=None, metavar="CUTTING.json",
                    help="with a drawing: every job key except the geometry (JSON)")
    ap.add_argument("--layer", default=None, metavar="NAME", help="with a drawing: read the outlines of this "
                    "layer only (DXF layer, SVG group id or inkscape:label; default: every layer)")
    ap.add_argument("--tolerance", type=float, default=CHORD_TOL_MM, metavar="MM",
                    help=f"with a drawing: chord error of the flattening of curves, mm (default {CHORD_TOL_MM})")
    ap.add_argument("--units", default=None, help="with a drawing: its unit (mm, inch, cm, m), overriding "
                    "$INSUNITS / the SVG size (default: from the drawing; a unitless DXF is read as mm)")
    ap.add_argument("--allow-uncut", action="store_true",
                    help="write the program even when it leaves more uncut area in a region than the limit "
                         "(1 mm^2 + 1 %% of the region's reachable area), with a WARNING in the output and the header")
    ap.add_argument("--allow-engagement-breach", action="store_true",
                    help="write the program even when a level breaks the planner's engagement promise (adaptive: "
                         "theta + 10 deg, measured at r/30 after one re-plan), with a WARNING in the output and the header")
    ap.add_argument("--slot-narrow", action="store_true",
                    help="adaptive strategy: cut the strips too narrow for any step under the engagement bound (a "
                         "slot less than 0.4 r wider than the tool) by slotting along their axis, their engagement "
                         "[up to 180 deg] and feed stated in the header (default: left, and refused as uncut with "
                         "that reason)")
    ap.add_argument("--dialect", default="linuxcnc", choices=DIALECTS,
                    help="controller dialect: linuxcnc (T M6, G43 H; default) or grbl (GRBL 1.1 words, lines <= 80 "
                         "characters, tool named in a comment)")
    ap.add_argument("--coolant", default=None, choices=sorted(COOLANT),
                    help="coolant on after the spindle (flood M8, mist M7; grbl: flood only), off before M5")
    ap.add_argument("--resolution", type=clihelp.number("--resolution", 0), default=None, metavar="MM",
                    help=f"planning dixel / sampling step, mm, in [{MIN_RESOLUTION_MM:g}, D/10] (default: the "
                         "planner's own, 0.1 mm; adaptive r/60)")
    args = ap.parse_args(argv)
    extra = {}
    if args.slot_narrow:
        if (args.strategy or DEFAULT_STRATEGY) != "adaptive":
            print(f"error: --slot-narrow applies to the adaptive strategy only, not {args.strategy!r}", file=sys.stderr)
            return 2
        extra["params"] = AdaptiveParams(slot_narrow=True)

    def message(exc):
        msg = str(exc)
        if args.resolution is not None and msg.startswith("resolution_mm "):
            msg = "--resolution" + msg[len("resolution_mm"):]
        return f"error: {msg}"

    # an interrupt says whether the program is on disk
    return InterruptReport([args.output]).call(
        lambda: plan_program(args.job, args.output, args.strategy, cutting=args.cutting, layer=args.layer,
                             tolerance=args.tolerance, units=args.units, allow_uncut=args.allow_uncut,
                             dialect=args.dialect, coolant=args.coolant, resolution_mm=args.resolution,
                             allow_engagement_breach=args.allow_engagement_breach, **extra),
        (ValueError, OSError, RuntimeError, KeyError), message)
