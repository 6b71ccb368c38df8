"""The compiled grid drop-cutter against the numpy KD-tree reference (same formulas, same floating-
point order) on random meshes, and against OpenCAMLib's BatchDropCutter where it is installed."""
import numpy as np
import pytest

from cnclab.geometry.mesh import TriMesh, read_stl
from cnclab.paths import data_path
from cnclab.toolpath.dropcutter import drop_cutter_z

# tolerance: both implementations evaluate the same expressions in the same order, so they agree
# to rounding of the final max (observed: bit-identical); 1e-12 mm leaves room for libm differences.
TOL = 1e-12


def _random_mesh(rng, n_tri, spread=20.0, size=4.0):
    """A triangle soup: random centres, random vertices around them (steep, flat, slivers, vertical)."""
    c = rng.random((n_tri, 1, 3)) * [spread, spread, 3.0]
    v = c + rng.normal(0, size / 2, (n_tri, 3, 3)) * [1, 1, rng.choice([0.0, 0.3, 3.0])]
    vertical = rng.random(n_tri) < 0.1            # some facets standing vertically
    v[vertical, 1, :2] = v[vertical, 0, :2]
    return TriMesh.from_triangles(v, degenerate="drop")


@pytest.mark.parametrize("seed", range(6))
def test_grid_matches_reference_on_random_meshes(seed):
    rng = np.random.default_rng(seed)
    m = _random_mesh(rng, int(rng.integers(1, 300)))
    xy = rng.random((400, 2)) * 30 - 5            # includes points beyond the mesh (touch nothing)
    R = float(rng.choice([0.5, 2.0, 5.0]))
    a = drop_cutter_z(m, xy, R, default_z=-99.0)
    b = drop_cutter_z(m, xy, R, method="kdtree", default_z=-99.0)
    assert (a == -99.0).sum() == (b == -99.0).sum()
    np.testing.assert_allclose(a, b, rtol=0, atol=TOL)


def test_grid_matches_reference_on_sample_part():
    m = read_stl(data_path("mgherony2024", "sample_ch8_part.stl"))
    rng = np.random.default_rng(7)
    lo, hi = m.triangles.reshape(-1, 3).min(0), m.triangles.reshape(-1, 3).max(0)
    xy = lo[:2] + rng.random((1500, 2)) * (hi - lo)[:2]
    np.testing.assert_allclose(drop_cutter_z(m, xy, 5.0), drop_cutter_z(m, xy, 5.0, method="kdtree"),
                               rtol=0, atol=TOL)


def test_method_validation():
    m = _random_mesh(np.random.default_rng(0), 5)
    with pytest.raises(ValueError, match="method"):
        drop_cutter_z(m, [[0, 0]], 1.0, method="brute")


def test_agrees_with_opencamlib():
    ocl = pytest.importorskip("opencamlib").ocl
    m = read_stl(data_path("mgherony2024", "sample_ch8_part.stl"))
    rng = np.random.default_rng(3)
    lo, hi = m.triangles.reshape(-1, 3).min(0), m.triangles.reshape(-1, 3).max(0)
    xy = lo[:2] + rng.random((600, 2)) * (hi - lo)[:2]
    surf = ocl.STLSurf()
    for t in m.triangles:
        surf.addTriangle(ocl.Triangle(*(ocl.Point(*map(float, p)) for p in t)))
    bdc = ocl.BatchDropCutter()
    bdc.setSTL(surf)
    bdc.setCutter(ocl.BallCutter(10.0, 50.0))
    bdc.setThreads(1)
    zmin = float(lo[2]) - 20.0
    for x, y in xy.tolist():
        bdc.appendPoint(ocl.CLPoint(x, y, zmin))
    bdc.run()
    z_ocl = np.array([p.z for p in bdc.getCLPoints()])
    z = drop_cutter_z(m, xy, 5.0, default_z=zmin)
    # OpenCAMLib solves the same contacts with its own formulas: agreement to 1e-9 mm (observed ~1e-14)
    np.testing.assert_allclose(z, z_ocl, rtol=0, atol=1e-9)
