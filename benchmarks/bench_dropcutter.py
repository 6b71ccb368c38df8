"""Benchmark: ball-end drop-cutter, cnclab vs OpenCAMLib's BatchDropCutter (same CL points, same mesh).

Rows (one run, printed as a table): for the 1452-facet sample STL and a finer tessellation of the
ch. 8 part (about 20.8k facets on its machined surface), the time of cnclab's grid + compiled kernel
(``method="grid"``, the default), of the numpy KD-tree reference (``method="kdtree"``, on a subset
when the full set would take minutes), and of OpenCAMLib's ``BatchDropCutter`` with as many threads
as cores, plus the largest |z difference| between them (mm). Target: cnclab <= OpenCAMLib.
The OpenCAMLib column is skipped when ``opencamlib`` is not installed (``pip install opencamlib``).
Usage: ``python benchmarks/bench_dropcutter.py [N_POINTS]`` (default 20000).
"""
import os
import sys
import time

import numpy as np

from cnclab.geometry.mesh import read_stl
from cnclab.paths import data_path
from cnclab.toolpath.dropcutter import drop_cutter_z
from cnclab.toolpath.zigzag import raster_passes
from cnclab.works.mgherony2024 import ch7_9

try:
    from opencamlib import ocl
except ImportError:  # optional peer
    ocl = None

R = 5.0  # D = 10 mm ball (Table 7-1)


def ocl_drop(mesh, xy, radius, zmin):
    """Tool-tip z by OpenCAMLib BatchDropCutter (threads = cores); seconds excluding the STL build."""
    surf = ocl.STLSurf()
    for t in mesh.triangles:
        surf.addTriangle(ocl.Triangle(*(ocl.Point(*map(float, p)) for p in t)))
    bdc = ocl.BatchDropCutter()
    bdc.setSTL(surf)
    bdc.setCutter(ocl.BallCutter(2 * radius, 50.0))
    bdc.setThreads(os.cpu_count() or 1)
    for x, y in xy.tolist():
        bdc.appendPoint(ocl.CLPoint(x, y, zmin))
    t0 = time.perf_counter()
    bdc.run()
    sec = time.perf_counter() - t0
    z = np.array([p.z for p in bdc.getCLPoints()])
    return z, sec


def cases(n_points):
    sample = read_stl(data_path("mgherony2024", "sample_ch8_part.stl"))
    sample = sample.subset(ch7_9.machined_surface_mask(sample.normals))
    fine = ch7_9.surface_mesh(0.5)
    for name, m in (("sample STL", sample), ("ch. 8 part, cell 0.5 mm", fine)):
        lo, hi = m.triangles.reshape(-1, 3).min(0), m.triangles.reshape(-1, 3).max(0)
        xy = np.vstack(raster_passes((lo[0], hi[0], lo[1], hi[1]), 0.25, 0.0, last="edge", step=0.5, links=True))
        yield name, m, xy[np.linspace(0, len(xy) - 1, min(n_points, len(xy))).astype(int)]


def main(argv):
    n_points = int(float(argv[0])) if argv else 20000
    drop_cutter_z(next(cases(10))[1], [[0.0, 0.0]], R)  # compile (or load the cached kernels)
    rows = []
    for name, m, xy in cases(n_points):
        t0 = time.perf_counter()
        z = drop_cutter_z(m, xy, R)
        t_grid = time.perf_counter() - t0
        sub = xy[:: max(1, len(xy) // 2000)]
        t0 = time.perf_counter()
        z_ref = drop_cutter_z(m, sub, R, method="kdtree")
        t_ref = (time.perf_counter() - t0) * len(xy) / len(sub)
        d_ref = float(np.nanmax(np.abs(z_ref - z[:: max(1, len(xy) // 2000)])))
        if ocl is not None:
            zmin = float(m.triangles[:, :, 2].min()) - 2 * R
            z_ocl, t_ocl = ocl_drop(m, xy, R, zmin)
            d_ocl = float(np.nanmax(np.abs(z_ocl - z)))
            ocl_cols = (f"{t_ocl:8.2f}", f"{t_ocl / t_grid:7.1f}x", f"{d_ocl:9.1e}")
        else:
            ocl_cols = ("     n/a", "     n/a", "      n/a")
        rows.append((f"{name}: {m.n_facets} facets, {len(xy)} pts", f"{t_grid:8.2f}", f"{t_ref:8.1f}",
                     f"{d_ref:9.1e}", *ocl_cols))
    head = ("case", "cnclab s", "numpy s*", "|dz| np", "OCL s", "OCL/cnc", "|dz| OCL")
    w = max(len(r[0]) for r in rows + [head])
    print(f"{head[0]:<{w}}  " + "  ".join(f"{h:>9}" for h in head[1:]))
    for r in rows:
        print(f"{r[0]:<{w}}  " + "  ".join(f"{c:>9}" for c in r[1:]))
    print("* numpy KD-tree reference timed on <= 2000 of the points and scaled to all; OCL with "
          f"{os.cpu_count()} threads; target OCL/cnc >= 1. Machine possibly shared: ratios from one run.")


if __name__ == "__main__":
    main(sys.argv[1:])
