"""STL I/O, normals, incentres, nearest facet, drop cutter, test part (cnclab.geometry.mesh & co)."""
import warnings

import numpy as np
import pytest

from cnclab.geometry.freeform_part import FreeformPart, freeform_part_mesh, tessellate_heightfield
from cnclab.geometry.mesh import (FacetLocator, STLWarning, TriMesh, closest_point_on_triangles,
                                  facet_incentres, machined_surface_mask, read_stl, write_stl)
from cnclab.toolpath.dropcutter import drop_cutter_z, split_passes, zigzag_finishing_path

RNG = np.random.default_rng(0)


def _mesh(n=40):
    return TriMesh.from_triangles(RNG.random((n, 3, 3)))


@pytest.mark.parametrize("ascii_", [True, False])
def test_stl_round_trip(tmp_path, ascii_):
    m = _mesh()
    p = write_stl(tmp_path / "a.stl", m, ascii=ascii_)
    r = read_stl(p, orient="keep")          # the file's vertex order, as written
    assert r.info["format"] == ("ascii" if ascii_ else "binary")
    np.testing.assert_allclose(r.triangles, m.triangles, atol=1e-6)  # float32 storage
    np.testing.assert_allclose(r.normals, m.normals, atol=1e-5)
    # default orientation rule: every facet it reverses is counted in info (and warned about)
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        auto = read_stl(p)
    changed = np.abs(auto.triangles - r.triangles).max(axis=(1, 2)) > 0
    assert auto.info["reoriented_facets"] == int(changed.sum()) == len(auto.triangles[changed])
    assert bool(w) == bool(changed.any())
    np.testing.assert_array_equal(auto.triangles[changed], r.triangles[changed][:, ::-1])


def test_normals_recomputed_when_stored_wrong(tmp_path):
    txt = ("solid t\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
           "facet normal 0 0 1\nouter loop\nvertex 5 0 1\nvertex 5 1 1\nvertex 6 0 1\nendloop\nendfacet\nendsolid t\n")
    (tmp_path / "t.stl").write_text(txt)
    m = read_stl(tmp_path / "t.stl", orient="keep")
    assert m.normals.tolist() == [[0, 0, 1], [0, 0, -1]]
    assert m.info["stored_normals_missing"] == 1 and m.info["stored_normals_inconsistent"] == 1
    up = read_stl(tmp_path / "t.stl", orient="keep", orient_up=True)
    assert (up.normals[:, 2] == 1).all()
    # default orientation rule: the second (clockwise, open) facet is turned upward and reported;
    # its stored normal (0 0 1) then agrees with the re-oriented facet
    with pytest.warns(STLWarning, match="1 of 2 facets re-oriented"):
        auto = read_stl(tmp_path / "t.stl")
    assert (auto.normals[:, 2] == 1).all() and auto.info["reoriented_facets"] == 1
    assert auto.info["stored_normals_inconsistent"] == 0


@pytest.mark.parametrize("bad, msg", [
    ("solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0\n", ":5: garbled vertex"),
    ("solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 nan\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n",
     ":4: non-finite"),
    ("solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 2 0 0\nendloop\nendfacet\nendsolid\n",
     ":2: facet 0 has zero area"),
    ("solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n",
     "truncated"),
])
def test_bad_ascii_stl_names_file_and_line(tmp_path, bad, msg):
    p = tmp_path / "bad.stl"
    p.write_text(bad)
    with pytest.raises(ValueError, match=msg) as e:
        read_stl(p)
    assert "bad.stl" in str(e.value)


def test_bad_binary_stl(tmp_path):
    p = write_stl(tmp_path / "b.stl", _mesh())
    raw = p.read_bytes()
    (tmp_path / "trunc.stl").write_bytes(raw[:-30])
    with pytest.raises(ValueError, match="trunc.stl: truncated binary STL"):
        read_stl(tmp_path / "trunc.stl")
    arr = bytearray(raw)
    arr[84 + 12:84 + 16] = np.array([np.inf], "<f4").tobytes()
    (tmp_path / "inf.stl").write_bytes(bytes(arr))
    with pytest.raises(ValueError, match=r"inf.stl \(facet 0\): non-finite"):
        read_stl(tmp_path / "inf.stl")
    (tmp_path / "empty.stl").write_bytes(b"")
    with pytest.raises(ValueError, match="empty"):
        read_stl(tmp_path / "empty.stl")


def test_write_never_overwrites_input(tmp_path):
    p = write_stl(tmp_path / "a.stl", _mesh())
    before = p.read_bytes()
    with pytest.raises(ValueError, match="refusing to overwrite"):
        write_stl(p, _mesh(5), inputs=[p])
    assert p.read_bytes() == before


def test_incentre_equidistant_from_sides():
    tri = RNG.random((20, 3, 3))
    I = facet_incentres(tri)
    d = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        u = tri[:, b] - tri[:, a]
        w = I - tri[:, a]
        d.append(np.linalg.norm(np.cross(u, w), axis=1) / np.linalg.norm(u, axis=1))
    np.testing.assert_allclose(d[0], d[1], rtol=1e-9)
    np.testing.assert_allclose(d[1], d[2], rtol=1e-9)


def test_nearest_facet_equals_brute_force_and_centroid_rule():
    m = _mesh(300)
    q = RNG.random((500, 3)) * 1.4 - 0.2
    loc = FacetLocator(m)
    T = m.triangles
    cp = closest_point_on_triangles(q[:, None], T[None, :, 0], T[None, :, 1], T[None, :, 2])
    brute = np.linalg.norm(cp - q[:, None], axis=2).argmin(axis=1)
    assert (loc.nearest_facet(q, k=4) == brute).all()
    allpairs = np.linalg.norm(q[:, None] - m.centroids[None], axis=2).argmin(axis=1)
    assert (loc.nearest_centroid(q) == allpairs).all()


def test_machined_surface_filter_and_closed_part():
    m = freeform_part_mesh(FreeformPart(), 5.0, closed=True)
    keep = machined_surface_mask(m.normals)
    assert keep.sum() == 2 * 10 * 10          # only the top surface survives the thesis rule
    assert (m.normals[keep][:, 2] > 0).all()


def test_freeform_part_geometry():
    p = FreeformPart()
    a = np.radians(p.blend_slope_deg)
    assert np.isclose((p.sphere_radius + p.torus_radius) * (1 - np.cos(a)), p.height)
    r1, r2 = p.radii
    for r in (r1, r2):  # C0 and C1 continuity at the junctions
        x = 50 - np.array([r - 1e-6, r + 1e-6]) / np.sqrt(2)
        z = p.height_at(x, x)
        assert abs(z[0] - z[1]) < 1e-5
        s = p.slope_deg(x, x)
        assert abs(s[0] - s[1]) < 1e-3
    n = p.normal_at(np.array([10.0, 30.0]), np.array([20.0, 40.0]))
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0)
    with pytest.raises(ValueError, match="sphere_radius"):
        FreeformPart(sphere_radius=-1)


def test_drop_cutter_flat_and_sphere_no_gouge():
    flat = tessellate_heightfield(lambda x, y: 0 * x + 3.0, (-20, 20), (-20, 20), 4, 4)
    assert np.allclose(drop_cutter_z(flat, RNG.random((50, 2)) * 20 - 10, 5.0), 3.0)
    m = freeform_part_mesh(FreeformPart(), 2.5)
    path = zigzag_finishing_path(m, 10.0, 2.0, 45.0, step=2.0)
    passes = split_passes(path)
    assert len(passes) > 1 and path.tool.corner_radius == 5.0 and np.all(path.kinds() == "cut")
    P = np.vstack(passes)
    assert np.array_equal(P, path.xyz)
    C = P + [0, 0, 5.0]
    f = FacetLocator(m).nearest_facet(C)
    T = m.triangles[f]
    d = np.linalg.norm(closest_point_on_triangles(C, T[:, 0], T[:, 1], T[:, 2]) - C, axis=1)
    assert d.min() >= 5.0 - 1e-9          # never gouges
    assert np.allclose(d, 5.0, atol=1e-9)  # and always touches
    with pytest.raises(ValueError, match="tool_radius"):
        drop_cutter_z(m, [[0, 0]], -1)


def test_cv_cx_parts_tessellate_to_stl(tmp_path):
    from cnclab.geometry.cylinder_parts import CylinderPart
    from cnclab.geometry.freeform_part import cylinder_part_mesh
    for kind in ("CV", "CX"):
        m = cylinder_part_mesh(kind, cell_mm=2.0)
        r = read_stl(write_stl(tmp_path / f"{kind}.stl", m))
        y = r.triangles[:, :, 1].ravel()
        np.testing.assert_allclose(r.triangles[:, :, 2].ravel(), CylinderPart(kind).z(y), atol=1e-4)


def _info0():
    return {"components": 0, "non_manifold_edges": 0, "winding_conflicts": 0, "boundary_edges": 0}


@pytest.mark.parametrize("seed", range(6))
def test_orient_fast_path_identical_to_graph_path(seed):
    """The compiled fast path (hash weld, edge hash, union-find parity) gives exactly what the
    scipy breadth-first graph path gives: triangles, flipped mask and every info count, on open and
    closed parts with random windings, shuffled facets and several components."""
    from cnclab.geometry.mesh import repair as M
    from cnclab.geometry.freeform_part import FreeformPart, freeform_part_mesh

    rng = np.random.default_rng(seed)
    t = freeform_part_mesh(FreeformPart(), rng.uniform(3, 8), closed=bool(seed % 2)).triangles.copy()
    f = rng.random(len(t)) < rng.random()
    t[f] = t[f][:, ::-1]
    if seed >= 2:
        t = np.concatenate([t, -t[: len(t) // 3] + [0, 0, -40]])     # a second (open) component
    t = t[rng.permutation(len(t))]
    fast = M.orient_facets(t)
    graph = M._orient_graph(np.array(t, copy=True), _info0())
    assert np.array_equal(fast[0], graph[0]) and np.array_equal(fast[1], graph[1]) and fast[2] == graph[2]
    assert fast[1].sum() > 0 and fast[2]["winding_conflicts"] == 0


def test_orient_non_orientable_strip_takes_the_graph_path():
    """A Moebius strip has no consistent winding: the union-find finds the conflict and the graph
    path decides (winding_conflicts > 0), as before."""
    from cnclab.geometry.mesh import repair as M

    n = 12
    ang = np.linspace(0, 2 * np.pi, n, endpoint=False)

    def P(a, s):
        return [np.cos(a) * (3 + s * np.cos(a / 2)), np.sin(a) * (3 + s * np.cos(a / 2)), s * np.sin(a / 2)]
    def col(i, s):             # the strip closes with a half twist: column n is column 0 upside down
        return P(ang[i], s) if i < n else P(ang[0], -s)
    tri = []
    for i in range(n):
        tri += [[col(i, -1), col(i + 1, -1), col(i + 1, 1)], [col(i, -1), col(i + 1, 1), col(i, 1)]]
    tri = np.array(tri)
    assert M._edge_parity(M.weld_ids(tri))[0]                       # conflict detected
    out, flipped, info = M.orient_facets(tri)
    ref = M._orient_graph(np.array(tri, copy=True), _info0())
    assert info["winding_conflicts"] > 0 and info == ref[2] and np.array_equal(flipped, ref[1])
