"""Benchmark: spindle post-processing (STL + APT files) and tool-path reordering (Mgherony ch. 7-9).

Rows (one run, printed as a table):
1. post-process N_CL CL points against an N_FACET-facet STL: write both files, read back, KD-tree
   nearest centroid, working diameter, n/v_f, SPINDL/FEDRAT insertion, write the new APT and the
   G-code (target <= 5 s for 1e6 / 1e6, issue 17). Concurrency: the STL is read in a second thread
   while the main thread reads the APT (``read_inputs``); the KD-tree queries run on both cores.
   Wall and CPU seconds are printed; on a machine shared with other jobs wall time is an upper bound;
2. nearest-centroid lookup: KD-tree vs the thesis's all-pairs search, on a size the naive one finishes
   (ratio measured in this run; target >= 100x);
3. reordering of N_RE points (target <= 30 s for 1e5).
Sizes: ``python benchmarks/bench_spindle_postprocess.py [N_CL N_FACET N_RE]`` (defaults 1e6 1e6 1e5).
"""
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from cnclab.fileio import atomic_write
from cnclab.nc.program import write_moves
from cnclab.nc.spindle_control import (gcode_text, insert_spindle_records, read_inputs, spindle_schedule,
                                      to_gcode_moves)
from cnclab.geometry.freeform_part import FreeformPart, freeform_part_mesh
from cnclab.geometry.mesh import FacetLocator, read_stl, write_stl
from cnclab.nc import apt
from cnclab.toolpath.reorder import reorder_path


def main(argv):
    n_cl, n_fac, n_re = (int(float(a)) for a in (argv + ["1e6", "1e6", "1e5"][len(argv):]))
    rows = []
    part = FreeformPart()
    tmp = Path(tempfile.mkdtemp(prefix="cnclab-bench-"))
    cell = 50.0 / np.sqrt(n_fac / 2)
    mesh = freeform_part_mesh(part, cell)
    write_stl(tmp / "part.stl", mesh)
    # CL points: zig-zag rows at the surface height (tip on the surface, as a fine CAM output)
    rows_n = int(np.sqrt(n_cl))
    x = np.linspace(0, 50, rows_n)
    X, Y = np.meshgrid(x, np.linspace(0, 50, int(np.ceil(n_cl / rows_n))))
    X[1::2] = X[1::2, ::-1]
    P = np.column_stack([X.ravel(), Y.ravel(), part.height_at(X.ravel(), Y.ravel())])[:n_cl]
    prog = apt.cl_program([P], 500, 2000, 10, 30)
    apt.write_apt(tmp / "path.apt", prog)
    # load the compiled kernels (numba cache) on small files first: STL weld/edges, APT runs, writers
    write_stl(tmp / "warm.stl", freeform_part_mesh(part, 5.0))
    apt.write_apt(tmp / "warm.apt", apt.cl_program([P[:20]], 500, 2000, 10, 30))
    mw, pw, cw = read_inputs(tmp / "warm.stl", tmp / "warm.apt")
    sw = spindle_schedule(mw, cw, tool_diameter=10, a_p=0.3, v_c=63, f_z=0.125, teeth=2, feed_direction_deg=0)
    gcode_text(insert_spindle_records(pw, cw, sw)[0])
    # the timed pipeline: STL and APT read concurrently (read_inputs: the STL in a second thread),
    # then facets + D_eff + n/v_f (KD-tree queries on both cores), insertion, APT and G-code writing
    cpu = [time.process_time()]
    t0 = time.perf_counter()
    m, pr, cl = read_inputs(tmp / "part.stl", tmp / "path.apt")
    t2 = time.perf_counter()
    t_read = t2 - t0
    cpu.append(time.process_time())
    n_bulk = sum(len(it) for it in pr.items() if isinstance(it, apt.GotoRun))
    s = spindle_schedule(m, cl, tool_diameter=10, a_p=0.3, v_c=63, f_z=0.125, teeth=2, feed_direction_deg=0)
    t3 = time.perf_counter()
    cpu.append(time.process_time())
    new, _ = insert_spindle_records(pr, cl, s)
    apt.write_apt(tmp / "out.apt", new)
    t4 = time.perf_counter()
    cpu.append(time.process_time())
    atomic_write(tmp / "out.ngc", gcode_text(new, header="bench"))
    t5 = time.perf_counter()
    cpu.append(time.process_time())
    dc = [f"CPU {b - a:.2f} s" for a, b in zip(cpu[:-1], cpu[1:])]
    rows.append((f"post-process {len(cl):.0e} CL pts vs {m.n_facets:.0e} facets incl. G-code (total)", t5 - t0,
                 f"target <= 5 s; CPU {cpu[-1] - cpu[0]:.2f} s (2 threads; machine shared with other jobs)"))
    rows.append(("  read STL || read + validate APT (2 threads)", t_read,
                 f"{dc[0]} (both threads); {n_bulk / len(cl):.0%} of the GOTOs read in bulk"))
    rows.append(("  facets + D_eff + n, v_f (KD-tree on 2 cores)", t3 - t2, dc[1]))
    rows.append(("  insert records + write APT", t4 - t3, dc[2]))
    rows.append(("  write G-code (array writer, nc.numfmt)", t5 - t4, dc[3]))
    # the two reads one after the other, for the split
    c0 = time.process_time()
    t0 = time.perf_counter()
    read_stl(tmp / "part.stl")
    t1 = time.perf_counter()
    apt.read_apt(tmp / "path.apt").cl_points()
    t2b = time.perf_counter()
    rows.append(("    read STL alone (serial)", t1 - t0, ""))
    rows.append(("    read + validate APT alone (serial)", t2b - t1,
                 f"serial STL + APT {t2b - t0:.2f} s, CPU {time.process_time() - c0:.2f} s; "
                 f"concurrent {t_read:.2f} s"))
    t0 = time.perf_counter()
    c0 = time.process_time()
    old_text = write_moves(to_gcode_moves(new), header="bench")
    t_old = time.perf_counter() - t0
    c_old = time.process_time() - c0
    assert old_text == (tmp / "out.ngc").read_text()
    rows.append(("  write G-code, Move-by-Move writer (same bytes)", t_old,
                 f"CPU {c_old:.2f} s; array writer {c_old / max(cpu[4] - cpu[3], 1e-9):.1f}x less CPU"))
    t0 = time.perf_counter()
    apt.parse_apt((tmp / "path.apt").read_text(), "path.apt", fast=False).cl_points()
    t_careful = time.perf_counter() - t0
    rows.append(("  read + validate APT, careful per-line parser", t_careful,
                 f"bulk parser {t_careful / (t2b - t1):.1f}x faster"))
    # nearest centroid: KD-tree vs all pairs on a size the naive search finishes
    small = freeform_part_mesh(part, 50.0 / np.sqrt(20000 / 2))
    q = np.random.default_rng(0).random((20000, 3)) * [50, 50, 10]
    t0 = time.perf_counter()
    loc = FacetLocator(small)
    a = loc.nearest_centroid(q)
    t_kd = time.perf_counter() - t0
    t0 = time.perf_counter()
    c = small.centroids
    b = np.concatenate([np.argmin(((q[i:i + 500, None] - c[None]) ** 2).sum(-1), axis=1)
                        for i in range(0, len(q), 500)])
    t_naive = time.perf_counter() - t0
    assert (a == b).all()
    rows.append((f"nearest centroid 2e4 pts x {small.n_facets:.0e} facets: KD-tree", t_kd, ""))
    rows.append(("  all-pairs (thesis)", t_naive, f"ratio {t_naive / t_kd:.0f}x (target >= 100x)"))
    # reordering
    side = int(np.sqrt(n_re))
    xx, yy = np.meshgrid(np.linspace(0, 50, side), np.linspace(0, 50, side))
    R = np.column_stack([xx.ravel(), yy.ravel(), part.height_at(xx.ravel(), yy.ravel())])
    nr = part.normal_at(R[:, 0], R[:, 1])
    t0 = time.perf_counter()
    r = reorder_path(R, nr, tool_diameter=10, a_p=0.3, k=8, start=0, feed_direction_deg=90, direction="constant")
    rows.append((f"reorder {len(R):.0e} points (k = 8), {r.n_jumps} jumps", time.perf_counter() - t0, "target <= 30 s"))
    w = max(len(r_[0]) for r_ in rows)
    print(f"{'step':<{w}}  {'seconds':>8}  note")
    for name, sec, note in rows:
        print(f"{name:<{w}}  {sec:8.2f}  {note}")


if __name__ == "__main__":
    main(sys.argv[1:])
