"""``python -m cnclab warm``: compile the package's shared numba kernels once, into their on-disk cache.

A fresh clone has no numba cache; every process that first simulates or plans compiles the same
kernels (about 30 CPU-s for the dixel simulation behind the evaluator). ``make test`` and
``make reproduce`` start several such processes at once (test workers, notebook kernels, the NC
programs), and each would compile them in parallel. Run first, this command compiles them once
(``cache=True`` writes them next to their modules); the processes started after it load them.
Seconds on a warm cache: about 2.
"""
from __future__ import annotations

import sys
import time

import numpy as np
from shapely.geometry import box

from . import clihelp
from .nc.arcfit import fit_arcs
from .simulation import pixel
from .toolpath.adaptive import adaptive_clearing
from .toolpath.evaluate import evaluate
from .toolpath.job import Job
from .toolpath.path import Tool

__all__ = ["warm", "main"]


def warm() -> float:
    """Plan and evaluate a small pocket (dixel and pixel stocks, with and without the cutting-level
    model) and fit its arcs as the writer does: every shared kernel is compiled and cached. Returns the wall seconds it took."""
    t0 = time.perf_counter()
    poly = box(0, 0, 12, 9)
    job = Job(poly, Tool(3.0), 60.0, 1.0, feed_mm_min=255.0, spindle_rpm=6000.0)
    tp = adaptive_clearing(job, resolution_mm=0.05, step_mm=0.05)
    evaluate(tp, job, 0.1)
    evaluate(tp, job, 0.1, feed_control=True)
    fit_arcs(tp)                                   # the writer's arc fit
    xs = np.arange(-2.0, 14.0, 0.1)
    pixel.simulate(pixel.Stock.from_polygon(poly, 0.1), np.c_[xs, np.full_like(xs, 4.5)], 1.5, 1.0, 255.0)
    return time.perf_counter() - t0


def main(argv=None) -> int:
    clihelp.parser("python -m cnclab warm",
                   "Compile the shared numba kernels once into their on-disk cache (make test and make\n"
                   "reproduce run it first, so that parallel workers do not compile them each).",
                   examples=["python -m cnclab warm"], writes=["the numba cache (__pycache__ next to the kernels)"]
                   ).parse_args(argv)
    print(f"numba kernels compiled and cached in {warm():.1f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
