"""``python -m cnclab warm``: compile the package's shared numba kernels once, into their on-disk cache.

A fresh clone has no numba cache; every process that first simulates or plans compiles the same
kernels (about 30 CPU-s for the dixel simulation behind the evaluator, as much for the planner).
``make test`` and ``make reproduce`` start several such processes at once (test workers, notebook
kernels, the NC programs, the CLI runs of the README), and each would compile them in parallel.
Run first, this command compiles them once (``cache=True`` writes them next to their modules); the
processes started after it load them.

The kernels fall in three independent parts (:data:`PARTS`), compiled in three processes at once:
on 2 cores a fresh clone's warm-up takes about half the sum of the parts (measured: planner 35 s,
evaluator 35 s, free-form 18 s alone) instead of the sum. Seconds on a warm cache: about 3.
"""
from __future__ import annotations

import sys
import time
import warnings

import numpy as np
from shapely.geometry import Point, box

from . import clihelp
from .geometry.mesh import read_stl
from .nc import apt
from .nc import spindle_control as sc
from .nc.program import write_program
from .paths import data_path
from .simulation import pixel
from .toolpath.adaptive import adaptive_clearing
from .toolpath.coverage import uncut_report
from .toolpath.dropcutter import drop_cutter_z
from .toolpath.evaluate import evaluate
from .toolpath.helix import helix_ring
from .toolpath.job import Job
from .toolpath.path import Tool, ToolPathBuilder

__all__ = ["PARTS", "warm", "warm_part", "main"]

#: the parts, each compiled in its own process: the adaptive planner (its stocks, controller, links),
#: the evaluator (dixel and pixel stocks, with and without the cutting-level model, plan()'s uncut
#: count, the program writer's arc fit), the free-form side (STL reading and its facet repair,
#: drop-cutter, APT reading, the spindle post-processor and its G-code writer)
PARTS = ("planner", "evaluator", "freeform")


def _pocket_job(island: bool = False):
    """A 12 x 9 mm pocket for a 3 mm tool (with a 2 mm round island at (8.5, 4.5))."""
    poly = box(0, 0, 12, 9)
    if island:
        poly = poly.difference(Point(8.5, 4.5).buffer(1.0))
    return Job(poly, Tool(3.0), 60.0, 1.0, feed_mm_min=255.0, spindle_rpm=6000.0)


def _warm_planner() -> None:
    adaptive_clearing(_pocket_job(island=True), resolution_mm=0.05, step_mm=0.05)   # links round an island


def _warm_evaluator() -> None:
    job = _pocket_job()
    b = ToolPathBuilder(tool=job.tool)
    b.approach((7.0, 4.5), top_z=0.0, clearance_z=5.0)
    b.helix(helix_ring((6.0, 4.5), 1.0, 24, turns=1.0), 0.5, -1.0, 255.0, equal_steps=True)
    b.cut([[10.0, 4.5], [10.0, 7.0], [2.0, 7.0], [2.0, 2.0], [10.0, 2.0]], 255.0, z=-1.0)
    b.retract(5.0, 255.0)
    tp = b.build()
    evaluate(tp, job, 0.1)
    evaluate(tp, job, 0.1, feed_control=True)
    uncut_report(tp, job)                   # plan()'s count of what a path leaves
    write_program(tp, job)                  # the writer's arc fit
    xs = np.arange(-2.0, 14.0, 0.1)
    st = pixel.Stock.from_polygon(job.polygon, 0.1)
    pixel.simulate(st, np.c_[xs, np.full_like(xs, 4.5)], 1.5, 1.0, 255.0)
    st.segment_pixels((2.0, 2.0), (10.0, 7.0), 1.5, cut=True, backend="numba")    # Kim & Yang's Linear_Motion


def _warm_freeform() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")     # the sample's re-oriented facets: not news here
        mesh = read_stl(data_path("mgherony2024", "sample_ch8_part.stl"))
    prog = apt.read_apt(data_path("mgherony2024", "sample_ch8_zigzag_Af0.apt"))
    cl = prog.cl_points()
    drop_cutter_z(mesh, cl.xyz[:50, :2], 5.0)
    s = sc.spindle_schedule(mesh, cl, tool_diameter=10, a_p=0.3, v_c=63, f_z=0.125, teeth=2)
    new, _ = sc.insert_spindle_records(prog, cl, s, rpm_threshold=100, vf_threshold=25)
    sc.gcode_text(new)                      # the linear G-code writer's number formatting


_WARMERS = {"planner": _warm_planner, "evaluator": _warm_evaluator, "freeform": _warm_freeform}


def warm_part(name: str) -> float:
    """Compile (or load) the kernels of one part of :data:`PARTS`; the wall seconds it took."""
    if name not in _WARMERS:
        raise ValueError(f"warm: part must be one of {PARTS}, got {name!r}")
    t0 = time.perf_counter()
    _WARMERS[name]()
    return time.perf_counter() - t0


def warm(jobs: int | None = None) -> float:
    """Compile every part of :data:`PARTS`, ``jobs`` processes at once (default: one per part, on
    any number of cores -- compiling is CPU-bound, so the parts share the cores and end together
    instead of the shortest waiting for a free core; 1: all in this process). Returns the wall
    seconds it took."""
    t0 = time.perf_counter()
    jobs = max(1, min(len(PARTS), jobs if jobs is not None else len(PARTS)))
    if jobs == 1:
        for p in PARTS:
            warm_part(p)
    else:
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor

        # spawn: each part starts from a fresh interpreter (no fork of a process holding threads)
        with ProcessPoolExecutor(jobs, mp_context=mp.get_context("spawn")) as ex:
            list(ex.map(warm_part, PARTS))
    return time.perf_counter() - t0


def main(argv=None) -> int:
    ap = clihelp.parser("python -m cnclab warm",
                        "Compile the shared numba kernels once into their on-disk cache (make test and make\n"
                        "reproduce run it first, so that parallel workers do not compile them each).",
                        examples=["python -m cnclab warm", "python -m cnclab warm --jobs 1"],
                        writes=["the numba cache (__pycache__ next to the kernels)"])
    ap.add_argument("--jobs", type=int, default=None,
                    help=f"processes compiling at once (default {len(PARTS)}: one per part)")
    args = ap.parse_args(argv)
    if args.jobs is not None and args.jobs < 1:
        ap.error(f"--jobs must be >= 1, got {args.jobs}")
    print(f"numba kernels compiled and cached in {warm(args.jobs):.1f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
