"""Triangle meshes for CAM: STL read/write, facet normals, incentres, nearest-facet lookup.

STL files are read by a strict reader of cnclab's own (binary recognised by its size, ASCII with
every solid, errors naming file and line or facet; see :func:`read_stl`) and written with numpy-stl.
All lengths are in mm. A :class:`TriMesh` holds the corner coordinates ``triangles`` (F, 3, 3) and unit
facet ``normals`` (F, 3).

Normals. The STL standard says the stored facet normal must agree with the counter-clockwise vertex
order (right-hand rule), but many exporters write zeros or stale normals. cnclab therefore **always
uses the normal recomputed from the vertex order**; the stored normals are only compared with it,
and the number of stored normals that were missing (zero) or inconsistent (angle > 1 deg, or
opposite) is reported in ``TriMesh.info``. Winding: :func:`read_stl` re-orients facets consistently
(closed parts outward, open surfaces upward, :func:`orient_facets`) and reports the number flipped
(``info["reoriented_facets"]`` and an :class:`STLWarning`), so a file wound clockwise does not change
which facets count as the machined surface. ``read_stl(..., orient_up=True)`` additionally flips
facets whose recomputed normal points downwards (N_z < 0) -- useful for open height-field surfaces
written with mixed winding; closed solids should keep the default ``False``.

Nearest facet. Mgherony (2024, Sec. 7.2.3) assigns each cutter location the facet whose "incentre"
(which the thesis computes as the *average of the three corners*, i.e. the centroid) is nearest.
:class:`FacetLocator` does this with a KD-tree (``nearest_centroid``), and also offers the exact
nearest facet in Euclidean distance (``nearest_facet``) and the true incentre (``facet_incentres``).
"""
from __future__ import annotations

import dataclasses
import functools
import re
import warnings
from pathlib import Path

import numpy as np
from numba import njit
from scipy.spatial import cKDTree

from ..fileio import atomic_output

__all__ = ["TriMesh", "read_stl", "write_stl", "facet_normals", "facet_centroids", "facet_incentres",
           "facet_areas", "machined_surface_mask", "FacetLocator", "closest_point_on_triangles",
           "inclination_angles", "orient_facets", "STLError", "STLWarning"]


#: Largest accepted |coordinate| (mm): 1000 km, far beyond any machinable part; larger values are a unit
#: or export error, and near 1e154 the facet areas (squares of coordinates) overflow to inf.
_COORD_LIMIT_MM = 1e9


class STLError(ValueError):
    """A malformed STL file; the message names the file (and the line for ASCII files)."""


@dataclasses.dataclass
class TriMesh:
    """A triangle soup: ``triangles`` (F, 3, 3) corner coordinates in mm, unit ``normals`` (F, 3).

    >>> tri = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], float)
    >>> m = TriMesh.from_triangles(tri)
    >>> m.normals.tolist(), m.n_facets
    ([[0.0, 0.0, 1.0]], 1)
    """

    triangles: np.ndarray
    normals: np.ndarray
    name: str = "cnclab"
    info: dict = dataclasses.field(default_factory=dict)

    @classmethod
    def from_triangles(cls, triangles, name: str = "cnclab", degenerate: str = "error",
                       source: str = "triangles") -> "TriMesh":
        """Build a mesh, normals from the vertex order; ``degenerate`` = 'error' | 'drop'."""
        tri = np.asarray(triangles, dtype=float)
        if tri.ndim != 3 or tri.shape[1:] != (3, 3):
            raise ValueError(f"triangles must have shape (F, 3, 3), got {tri.shape}")
        bad = ~np.isfinite(tri).all(axis=(1, 2))
        if bad.any():
            raise STLError(f"{source}: facet {int(np.argmax(bad))} has a non-finite coordinate")
        huge = (np.abs(tri) > _COORD_LIMIT_MM).any(axis=(1, 2))
        if huge.any():                 # squares / cross products would overflow to inf (not "zero area")
            k = int(np.argmax(huge))
            raise STLError(f"{source}: facet {k} has a vertex coordinate {float(np.abs(tri[k]).max()):.6g} mm, "
                           f"beyond the +/-{_COORD_LIMIT_MM:.0e} mm range (its area would overflow)")
        cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        ln = np.linalg.norm(cross, axis=1)
        areas = 0.5 * ln                       # = facet_areas(tri), facet_normals(tri) below
        scale = max(float(np.ptp(tri.reshape(-1, 3), axis=0).max()) if len(tri) else 1.0, 1e-300)
        zero = areas <= 1e-12 * scale * scale
        if zero.any():
            if degenerate == "error":
                k = int(np.argmax(zero))
                raise STLError(f"{source}: facet {k} has zero area ({areas[k]:.3g} mm^2 <= 1e-12 x the part size "
                               f"{scale:.6g} mm squared; {int(zero.sum())} degenerate facet(s); "
                               "pass degenerate='drop' to skip them)")
            if degenerate != "drop":
                raise ValueError(f"degenerate must be 'error' or 'drop', got {degenerate!r}")
            tri, cross, ln = tri[~zero], cross[~zero], ln[~zero]
        normals = np.divide(cross, ln[:, None], out=np.zeros_like(cross), where=ln[:, None] > 0)
        return cls(tri, normals, name=name, info={"dropped_degenerate": int(zero.sum())})

    @property
    def n_facets(self) -> int:
        return int(self.triangles.shape[0])

    @property
    def centroids(self) -> np.ndarray:
        """The thesis's "incentres": the average of the three corners (the centroid), (F, 3) mm."""
        return facet_centroids(self.triangles)

    def subset(self, mask) -> "TriMesh":
        """The facets selected by a boolean mask or index array."""
        return TriMesh(self.triangles[mask], self.normals[mask], self.name, dict(self.info))


def facet_normals(triangles) -> np.ndarray:
    """Unit normals (F, 3) from the vertex order (right-hand rule); zero rows for zero-area facets."""
    t = np.asarray(triangles, float)
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    ln = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, ln, out=np.zeros_like(n), where=ln > 0)


def facet_areas(triangles) -> np.ndarray:
    """Facet areas (F,) in mm^2."""
    t = np.asarray(triangles, float)
    return 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)


def facet_centroids(triangles) -> np.ndarray:
    """Average of the three corners (F, 3) -- what the thesis (Sec. 7.2.3) calls the incentre."""
    return np.asarray(triangles, float).mean(axis=1)


def facet_incentres(triangles) -> np.ndarray:
    """True incentres (F, 3): corners weighted by the length of the opposite side.

    >>> facet_incentres(np.array([[[0, 0, 0], [4, 0, 0], [0, 3, 0]]], float)).round(6).tolist()
    [[1.0, 1.0, 0.0]]
    """
    t = np.asarray(triangles, float)
    a = np.linalg.norm(t[:, 2] - t[:, 1], axis=1)
    b = np.linalg.norm(t[:, 0] - t[:, 2], axis=1)
    c = np.linalg.norm(t[:, 1] - t[:, 0], axis=1)
    w = np.stack([a, b, c], axis=1)
    return (w[:, :, None] * t).sum(axis=1) / w.sum(axis=1)[:, None]


def inclination_angles(normals):
    """Surface inclination (A_N1, A_N2) in **degrees** from unit normals, eqs (7-1), (7-2).

    A_N1 = atan2(N_y, N_x) (the thesis writes arctg(N_y/N_x), which loses the quadrant),
    A_N2 = acos(N_z).

    >>> inclination_angles(np.array([[0.0, 0.0, 1.0]]))
    (array([0.]), array([0.]))
    """
    n = np.asarray(normals, float)
    a1 = np.degrees(np.arctan2(n[..., 1], n[..., 0]))
    a2 = np.degrees(np.arccos(np.clip(n[..., 2], -1.0, 1.0)))
    return a1, a2


def machined_surface_mask(normals, tol_deg: float = 1e-3) -> np.ndarray:
    """Thesis rule (Sec. 7.2.3): drop facets whose normal is parallel to a coordinate axis other than +Z.

    Returns a boolean mask of the facets kept (sides and bottom of a closed part are removed).
    """
    n = np.asarray(normals, float)
    c = np.cos(np.radians(tol_deg))
    # n . axis for the axes +-X, +-Y, -Z is +-one component (what n @ axes.T gives, without the product)
    nx, ny, nz = n[..., 0], n[..., 1], n[..., 2]
    return ~((nx >= c) | (-nx >= c) | (ny >= c) | (-ny >= c) | (-nz >= c))


# ----------------------------------------------------------------------------- STL files
# Strict number grammar for ASCII STL: ASCII digits only, optional sign, decimal point, exponent;
# 'nan'/'inf' are recognised only to be refused with a "non-finite" message.
_NUM = r"[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?"
_NUM_RE = re.compile(rf"^{_NUM}$", re.ASCII)
_NONFINITE_RE = re.compile(r"^[-+]?(?:nan|inf|infinity)$", re.I)


class STLWarning(UserWarning):
    """An STL file was read but repaired (facets re-oriented); the message names the file and count."""


def _stl_numbers(parts, path, lineno, what):
    vals = []
    for p in parts:
        if _NUM_RE.match(p):
            vals.append(float(p))
        elif _NONFINITE_RE.match(p):
            raise STLError(f"{path}:{lineno}: non-finite {what} coordinate {p!r}")
        else:
            raise STLError(f"{path}:{lineno}: garbled {what} value {p!r} (need a decimal number)")
    if len(vals) != 3:
        raise STLError(f"{path}:{lineno}: garbled {what} line (need 3 numbers, got {len(vals)})")
    vals = [float(v) for v in vals]
    if not all(np.isfinite(vals)):
        raise STLError(f"{path}:{lineno}: non-finite {what} coordinate (overflow)")
    return vals


def _parse_ascii_stl(text: str, path):
    """Strict ASCII STL parser: every solid of the file; errors name file and line.

    Returns (triangles (F, 3, 3), stored normals (F, 3), facet line numbers (F,), solid names).
    """
    tris, norms, flines, names = [], [], [], []
    # states: 'top' (between solids), 'solid', 'facet' (after 'facet normal'), 'loop', 'endloop'
    state = "top"
    verts: list = []
    facet_line = solid_line = 0
    lineno = 0
    for lineno, line in enumerate(text.splitlines(), start=1):
        parts = line.split()
        if not parts:
            continue
        kw = parts[0].lower()
        if state == "top":
            if kw != "solid":
                raise STLError(f"{path}:{lineno}: expected 'solid', got {line.strip()[:60]!r}")
            names.append(" ".join(parts[1:]))
            state, solid_line = "solid", lineno
        elif state == "solid":
            if kw == "facet":
                if len(parts) < 2 or parts[1].lower() != "normal":
                    raise STLError(f"{path}:{lineno}: garbled facet line {line.strip()[:60]!r} "
                                   "(need 'facet normal nx ny nz')")
                norms.append(_stl_numbers(parts[2:], path, lineno, "facet normal"))
                state, facet_line, verts = "facet", lineno, []
            elif kw == "endsolid":
                state = "top"
            else:
                raise STLError(f"{path}:{lineno}: expected 'facet' or 'endsolid', got {line.strip()[:60]!r}")
        elif state == "facet":
            if kw != "outer" or len(parts) != 2 or parts[1].lower() != "loop":
                raise STLError(f"{path}:{lineno}: expected 'outer loop', got {line.strip()[:60]!r}")
            state = "loop"
        elif state == "loop":
            if kw == "vertex":
                if len(verts) == 3:
                    raise STLError(f"{path}:{lineno}: facet starting on line {facet_line} has more than 3 vertices")
                verts.append(_stl_numbers(parts[1:], path, lineno, "vertex"))
            elif kw == "endloop" and len(parts) == 1:
                if len(verts) != 3:
                    raise STLError(f"{path}:{lineno}: facet starting on line {facet_line} has {len(verts)} "
                                   "vertices, not 3")
                state = "endloop"
            else:
                raise STLError(f"{path}:{lineno}: expected 'vertex x y z' or 'endloop' (facet of line "
                               f"{facet_line}), got {line.strip()[:60]!r}")
        elif state == "endloop":
            if kw != "endfacet" or len(parts) != 1:
                raise STLError(f"{path}:{lineno}: expected 'endfacet' (facet of line {facet_line}), "
                               f"got {line.strip()[:60]!r}")
            tris.append(verts)
            flines.append(facet_line)
            state = "solid"
    if state != "top":
        raise STLError(f"{path}:{lineno}: truncated ASCII STL: solid of line {solid_line} has no 'endsolid'")
    if not names:
        raise STLError(f"{path}: empty STL file (no 'solid')")
    return (np.asarray(tris, float).reshape(-1, 3, 3), np.asarray(norms, float).reshape(-1, 3),
            np.asarray(flines, np.int64), names)


_BIN_DTYPE = np.dtype([("normals", "<f4", (3,)), ("vectors", "<f4", (3, 3)), ("attr", "<u2")])


def _stl_kind(raw: bytes) -> str:
    """'binary' when the size matches the facet count of the header (even if the header starts with
    'solid'), else 'ascii' for text starting with 'solid', else 'binary' (size checked later)."""
    if len(raw) >= 84 and 84 + 50 * int(np.frombuffer(raw[80:84], "<u4")[0]) == len(raw):
        return "binary"
    if raw.lstrip()[:5].lower() == b"solid":
        return "ascii"
    return "binary"


def _parse_binary_stl(raw: bytes, path):
    if len(raw) < 84:
        raise STLError(f"{path}: truncated binary STL ({len(raw)} bytes, the header needs 84)")
    count = int(np.frombuffer(raw[80:84], "<u4")[0])
    need = 84 + 50 * count
    if len(raw) != need:
        body = len(raw) - 84
        what = "truncated" if len(raw) < need else "inconsistent"
        raise STLError(f"{path}: {what} binary STL: the header announces {count} facets ({need} bytes) but the "
                       f"file has {len(raw)} bytes ({body // 50} whole facets + {body % 50} bytes)")
    if count == 0:
        raise STLError(f"{path}: STL has no facets")
    data = np.frombuffer(raw, _BIN_DTYPE, count=count, offset=84)
    name = raw[:80].split(b"\0", 1)[0].decode("ascii", errors="replace").strip()
    return data["vectors"].astype(float), data["normals"].astype(float), name


def orient_facets(triangles, rule: str = "auto"):
    """Re-orient facets consistently; returns (triangles, flipped bool mask (F,), info dict).

    Rule (``rule="auto"``): vertices are welded (exact coordinate equality, as written in the STL);
    across every edge shared by exactly two facets the winding must run in opposite directions, so
    each edge-connected component gets one consistent winding (breadth-first propagation); then each
    component is turned **outward** if it is closed (no boundary edge; signed volume > 0). An open
    component (boundary edges) is decided by ray parity when the mesh has several components (a solid
    closed only geometrically: walls meeting a surface at T-junctions, a separate bottom): a ray from
    its largest facet along the normal crossing the mesh an odd number of times, and the opposite
    ray an even number, means the normal points into material (flip); otherwise -- a truly open
    surface -- it is turned **upward** (area-weighted mean normal N_z >= 0; a component with zero N_z
    sum keeps the majority winding of the file). (Ray tests: the 64 largest open components.) Edges shared by more than two facets are ignored and counted
    (``non_manifold_edges``); a non-orientable component keeps the propagated winding and its
    conflicting edges are counted (``winding_conflicts``). ``rule="keep"`` changes nothing.

    >>> tri = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[1, 0, 0], [0, 1, 0], [1, 1, 0]]], float)
    >>> t, flipped, info = orient_facets(tri)        # second facet wound clockwise (normal -Z)
    >>> flipped.tolist(), facet_normals(t)[:, 2].tolist()
    ([False, True], [1.0, 1.0])
    """
    tri = np.array(triangles, dtype=float, copy=True)
    F = len(tri)
    info = {"components": 0, "non_manifold_edges": 0, "winding_conflicts": 0, "boundary_edges": 0}
    if rule == "keep":
        return tri, np.zeros(F, bool), info
    if rule != "auto":
        raise ValueError(f"orient must be 'auto' or 'keep', got {rule!r}")
    if F == 0:
        return tri, np.zeros(0, bool), info
    return _orient(tri, info)


def _orient(tri, info, vid=None):
    """orient_facets on a float copy ``tri`` (F > 0); ``vid`` (F, 3) welded vertex ids if known.

    Fast path (compiled): weld, group the half-edges by edge, and propagate the winding parity by a
    union-find. When no edge disagrees with the propagated winding (every orientable mesh), the
    parity relative to the lowest-index facet of each component is the one the breadth-first
    propagation gives, and the components are labelled in order of their lowest facet as
    ``scipy.sparse.csgraph.connected_components`` does, so the result is identical. A mesh with
    winding conflicts takes the graph path (:func:`_orient_graph`) unchanged.
    """
    F = len(tri)
    if vid is None:
        vid = _weld_ids(tri)
    res = _edge_parity(np.ascontiguousarray(vid, np.int64).reshape(F, 3))
    conflict, n_bnd, n_nm, ncomp, comp, flip, open_fac = res
    if conflict:
        return _orient_graph(tri, info)
    info["boundary_edges"] = int(n_bnd)
    info["non_manifold_edges"] = int(n_nm)
    info["components"] = int(ncomp)
    open_comp = np.zeros(ncomp, bool)
    open_comp[comp[open_fac]] = True
    return _orient_turn(tri, info, comp, ncomp, flip, open_comp)


def _weld_ids(tri) -> np.ndarray:
    """Vertex ids (F, 3) welding exactly equal coordinates (-0.0 == 0.0), numbered by first use."""
    flat = np.ascontiguousarray(tri.reshape(-1, 3)) + 0.0
    return _weld(flat.view(np.uint64)).reshape(-1, 3)


@njit(cache=True, nogil=True)
def _mix(x, y, z):
    h = x * np.uint64(0x9E3779B97F4A7C15) ^ y * np.uint64(0xC2B2AE3D27D4EB4F) ^ z * np.uint64(0x165667B19E3779F9)
    h ^= h >> np.uint64(31)
    h *= np.uint64(0xBF58476D1CE4E5B9)
    h ^= h >> np.uint64(29)
    return h


@njit(cache=True, nogil=True)
def _hash_table(n):
    """Empty open-addressing table (-1 = free) of a power-of-two size >= 2 n, and its index mask."""
    size = 16
    while size < 2 * n:
        size *= 2
    return np.full(size, -1, np.int64), np.uint64(size - 1)


@njit(cache=True, nogil=True)
def _weld(bits):
    """Id per row of ``bits`` (N, 3) uint64: rows equal bit for bit share an id (open addressing)."""
    n = bits.shape[0]
    table, mask = _hash_table(n)
    vid = np.empty(n, np.int64)
    nv = 0
    for i in range(n):
        slot = _mix(bits[i, 0], bits[i, 1], bits[i, 2]) & mask
        while True:
            j = table[slot]
            if j < 0:
                table[slot] = i
                vid[i] = nv
                nv += 1
                break
            if bits[j, 0] == bits[i, 0] and bits[j, 1] == bits[i, 1] and bits[j, 2] == bits[i, 2]:
                vid[i] = vid[j]
                break
            slot = (slot + np.uint64(1)) & mask
    return vid


@njit(cache=True, nogil=True)
def _first_equal_triple(vid):
    """For each row of ``vid`` (F, 3) the first row with the same three ids in any order."""
    F = vid.shape[0]
    table, mask = _hash_table(F)
    key = np.empty((F, 3), np.int64)
    first = np.empty(F, np.int64)
    for i in range(F):
        a, b, c = vid[i, 0], vid[i, 1], vid[i, 2]
        if a > b:
            a, b = b, a
        if b > c:
            b, c = c, b
        if a > b:
            a, b = b, a
        key[i, 0], key[i, 1], key[i, 2] = a, b, c
        slot = _mix(np.uint64(a), np.uint64(b), np.uint64(c)) & mask
        while True:
            j = table[slot]
            if j < 0:
                table[slot] = i
                first[i] = i
                break
            if key[j, 0] == a and key[j, 1] == b and key[j, 2] == c:
                first[i] = j
                break
            slot = (slot + np.uint64(1)) & mask
    return first


@njit(cache=True)
def _find(parent, par, x):
    """Root of x and the parity of x relative to it (path compression keeps the parities)."""
    p = 0
    r = x
    while parent[r] != r:
        p ^= par[r]
        r = parent[r]
    # compress: point every node of the path at the root with its own parity
    q = p
    y = x
    while parent[y] != y:
        nxt = parent[y]
        py = par[y]
        parent[y] = r
        par[y] = q
        q ^= py
        y = nxt
    return r, p


@njit(cache=True, nogil=True)
def _edge_parity(V):
    """Edges of the facets ``V`` (F, 3) by bucketing half-edges, winding parity by union-find.

    Returns (conflict, boundary edges, non-manifold edges, components, component label per facet
    (in order of the lowest facet), flip parity to that facet, facets of boundary/non-manifold edges).
    """
    F = V.shape[0]
    H = 3 * F
    nv = V.max() + 1
    # half-edges bucketed by their lower vertex (counting sort: h order kept inside a bucket), then
    # grouped by the upper vertex inside each bucket: one group per undirected edge
    start = np.zeros(nv + 1, np.int64)
    for h in range(H):
        f = h // 3
        a = V[f, h % 3]
        b = V[f, (h % 3 + 1) % 3]
        start[min(a, b) + 1] += 1
    for v in range(nv):
        start[v + 1] += start[v]
    fill = start[:-1].copy()
    bucket = np.empty(H, np.int64)
    upper = np.empty(H, np.int64)
    for h in range(H):
        f = h // 3
        a = V[f, h % 3]
        b = V[f, (h % 3 + 1) % 3]
        lo = min(a, b)
        bucket[fill[lo]] = h
        upper[fill[lo]] = max(a, b)
        fill[lo] += 1
    n_edges = 0
    e_first = np.empty(H, np.int64)       # per edge: first and second half-edge, count
    e_second = np.empty(H, np.int64)
    e_cnt = np.zeros(H, np.int64)
    scratch = np.empty(64, np.int64)
    for v in range(nv):
        s0, s1 = start[v], start[v + 1]
        k = s1 - s0
        if k > 64:
            o = np.argsort(upper[s0:s1], kind="mergesort") + s0     # stable: h order among equals
        else:                                                       # stable insertion sort
            o = scratch[:k]
            for i in range(k):
                x = s0 + i
                j = i
                while j > 0 and upper[o[j - 1]] > upper[x]:
                    o[j] = o[j - 1]
                    j -= 1
                o[j] = x
        i = 0
        while i < k:
            j = i + 1
            while j < k and upper[o[j]] == upper[o[i]]:
                j += 1
            e_first[n_edges] = bucket[o[i]]
            e_second[n_edges] = bucket[o[i + 1]] if j - i > 1 else -1
            e_cnt[n_edges] = j - i
            n_edges += 1
            i = j
    parent = np.arange(F)
    par = np.zeros(F, np.uint8)
    rank = np.ones(F, np.int64)
    open_mark = np.zeros(F, np.bool_)
    n_bnd = 0
    n_nm = 0
    conflict = False
    for e in range(n_edges):
        c = e_cnt[e]
        ha = e_first[e]
        fa = ha // 3
        if c == 1:
            n_bnd += 1
            open_mark[fa] = True
        elif c > 2:
            n_nm += 1
            open_mark[fa] = True
        elif fa != e_second[e] // 3:
            hb = e_second[e]
            fb = hb // 3
            da = V[fa, ha % 3] < V[fa, (ha % 3 + 1) % 3]
            db = V[fb, hb % 3] < V[fb, (hb % 3 + 1) % 3]
            same = np.uint8(1) if da == db else np.uint8(0)
            ra, pa = _find(parent, par, fa)
            rb, pb = _find(parent, par, fb)
            if ra == rb:
                if (pa ^ pb) != same:
                    conflict = True
            elif rank[ra] < rank[rb]:       # union by size keeps the trees shallow
                parent[ra] = rb
                par[ra] = pa ^ pb ^ same
                rank[rb] += rank[ra]
            else:
                parent[rb] = ra
                par[rb] = pa ^ pb ^ same
                rank[ra] += rank[rb]
    comp = np.empty(F, np.int64)
    flip = np.zeros(F, np.bool_)
    label = np.full(F, -1, np.int64)
    rootpar = np.zeros(F, np.uint8)
    ncomp = 0
    for f in range(F):
        r, p = _find(parent, par, f)
        if label[r] < 0:
            label[r] = ncomp
            rootpar[ncomp] = p
            ncomp += 1
        comp[f] = label[r]
        flip[f] = (p ^ rootpar[label[r]]) != 0
    return conflict, n_bnd, n_nm, ncomp, comp, flip, np.flatnonzero(open_mark)


def _orient_graph(tri, info):
    """The graph path of orient_facets (scipy breadth-first propagation; any mesh)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import breadth_first_order, connected_components

    F = len(tri)
    flat = np.ascontiguousarray(tri.reshape(-1, 3)) + 0.0          # + 0.0: -0.0 welds with 0.0
    _, vid = np.unique(flat.view(np.dtype((np.void, 24))).ravel(), return_inverse=True)
    V = vid.reshape(F, 3)
    a = V.ravel()
    b = V[:, [1, 2, 0]].ravel()
    fac = np.repeat(np.arange(F), 3)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    fwd = a < b
    order = np.lexsort((hi, lo))
    lo_s, hi_s = lo[order], hi[order]
    new = np.ones(order.size, bool)
    new[1:] = (lo_s[1:] != lo_s[:-1]) | (hi_s[1:] != hi_s[:-1])
    gid = np.cumsum(new) - 1
    cnt = np.bincount(gid)
    info["boundary_edges"] = int((cnt == 1).sum())
    info["non_manifold_edges"] = int((cnt > 2).sum())
    first = np.flatnonzero(new)
    pair = first[cnt[gid[first]] == 2]
    f1, f2 = fac[order[pair]], fac[order[pair + 1]]
    same = fwd[order[pair]] == fwd[order[pair + 1]]          # same direction -> relative flip
    keep = f1 != f2
    f1, f2, same = f1[keep], f2[keep], same[keep]
    _, u = np.unique(np.minimum(f1, f2) * F + np.maximum(f1, f2), return_index=True)
    f1, f2, same = f1[u], f2[u], same[u]                        # one link per facet pair
    # graph with a virtual root F linked to every facet (weight 1 = no flip) so one BFS covers all
    w = np.concatenate([same + 1, same + 1]).astype(np.int8)   # 1 = consistent, 2 = flip
    rows = np.concatenate([f1, f2])
    cols = np.concatenate([f2, f1])
    G = coo_matrix((w, (rows, cols)), shape=(F, F)).tocsr()
    ncomp, comp = connected_components(G, directed=False)
    info["components"] = int(ncomp)
    root_of = np.full(ncomp, -1)
    root_of[comp[::-1]] = np.arange(F)[::-1]                  # first facet of each component
    R = coo_matrix((np.ones(ncomp, np.int8), (np.full(ncomp, F), root_of)), shape=(F + 1, F + 1))
    Gx = coo_matrix((G.data, (np.repeat(np.arange(F), np.diff(G.indptr)), G.indices)), shape=(F + 1, F + 1))
    H = (Gx + R).tocsr()
    _, pred = breadth_first_order(H, F, directed=True, return_predecessors=True)
    pred = pred[:F]
    par = np.zeros(F, np.int8)
    tree = pred != F
    if tree.any():
        keys = np.concatenate([f1 * F + f2, f2 * F + f1])
        vals = np.concatenate([same, same])
        o = np.argsort(keys)
        pos = np.searchsorted(keys[o], pred[tree].astype(np.int64) * F + np.flatnonzero(tree))
        par[tree] = vals[o][pos].astype(np.int8)
    anc = np.where(tree, pred, np.arange(F))
    while True:       # pointer jumping: parity to the component root = XOR along the tree path
        moving = anc[anc] != anc
        if not moving.any():
            break
        par = np.where(moving, par ^ par[anc], par)
        anc = np.where(moving, anc[anc], anc)
    flip = par.astype(bool)
    info["winding_conflicts"] = int(((flip[f1] ^ flip[f2]) != same).sum())
    bnd_fac = fac[order[first[cnt[gid[first]] == 1]]]
    open_comp = np.zeros(ncomp, bool)
    open_comp[comp[bnd_fac]] = True
    nm_fac = fac[order[first[cnt[gid[first]] > 2]]]
    open_comp[comp[nm_fac]] = True
    return _orient_turn(tri, info, comp, ncomp, flip, open_comp)


def _orient_turn(tri, info, comp, ncomp, flip, open_comp):
    """One sign per component: closed -> outward (signed volume), open -> upward (sum of N_z * area)
    or by ray parity (see :func:`orient_facets`); returns (triangles, flipped, info)."""
    F = len(tri)
    t2 = np.where(flip[:, None, None], tri[:, ::-1], tri) if flip.any() else tri
    cross = np.cross(t2[:, 1] - t2[:, 0], t2[:, 2] - t2[:, 0])
    vol = np.bincount(comp, (t2[:, 0] * cross).sum(axis=1), ncomp)
    upz = np.bincount(comp, cross[:, 2], ncomp)
    agree = np.bincount(comp, (~flip).astype(float), ncomp) - np.bincount(comp, flip.astype(float), ncomp)
    turn = np.where(open_comp, np.where(upz != 0, upz < 0, agree < 0), vol < 0)
    # open components of a solid that is closed only geometrically (walls meeting a surface at
    # T-junctions, separate bottom ...): ray parity from the largest facet of the component decides
    # (odd crossings along the normal -> the normal points into material -> flip). Rays in both
    # directions must disagree in parity, else (a truly open surface) the upward rule above stands.
    areas = np.linalg.norm(cross, axis=1)
    cand = np.flatnonzero(open_comp)
    if cand.size and ncomp > 1:
        cand = cand[np.argsort(-np.bincount(comp, areas, ncomp)[cand])][:64]
        big = np.full(ncomp, -1)
        order_a = np.lexsort((-areas, comp))
        firsts = np.ones(F, bool)
        firsts[1:] = comp[order_a][1:] != comp[order_a][:-1]
        big[comp[order_a][firsts]] = order_a[firsts]
        for c in cand:
            f = big[c]
            n = cross[f] / areas[f]
            o = t2[f].mean(axis=0)                       # independent of the vertex order
            sgn = 1.0 if n @ _RAY_W >= 0 else -1.0       # canonical direction: same rays either winding
            d = sgn * n + 1e-4 * _RAY_W
            along = _ray_hits(o, d, t2, exclude=f)
            against = _ray_hits(o, -d, t2, exclude=f)
            if along % 2 != against % 2:                 # material on exactly one side
                inside = along % 2 == 1 if sgn > 0 else against % 2 == 1
                turn[c] = inside
    flip = flip ^ turn[comp]
    out = np.where(flip[:, None, None], tri[:, ::-1], tri) if flip.any() else tri
    return out, flip, info


_RAY_W = np.array([0.37, 0.59, 0.23]) / np.linalg.norm([0.37, 0.59, 0.23])


def _ray_hits(o, d, tri, exclude=-1) -> int:
    """Number of facets crossed by the ray o + t d, t > 0 (Moller-Trumbore, vectorised)."""
    e1 = tri[:, 1] - tri[:, 0]
    e2 = tri[:, 2] - tri[:, 0]
    p = np.cross(d, e2)
    det = (e1 * p).sum(axis=1)
    ok = np.abs(det) > 1e-300
    inv = np.divide(1.0, det, out=np.zeros_like(det), where=ok)
    s = o - tri[:, 0]
    u = (s * p).sum(axis=1) * inv
    q = np.cross(s, e1)
    v = (q * d).sum(axis=1) * inv
    t = (q * e2).sum(axis=1) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    if exclude >= 0:
        hit[exclude] = False
    return int(hit.sum())


def read_stl(path, degenerate: str = "error", orient: str = "auto", orient_up: bool = False) -> TriMesh:
    """Read an ASCII or binary STL strictly; facets re-oriented consistently (see :func:`orient_facets`).

    Parameters
    ----------
    path : STL file (mm). Binary is recognised by its size (84 + 50 x the facet count of the header,
        also when the 80-byte header starts with "solid"); any other size is refused, both shorter
        and longer. ASCII files may hold several ``solid ... endsolid`` blocks: **all** solids are
        read (their facets concatenated; ``info["solids"]`` lists the names). Blank lines anywhere
        are accepted.
    degenerate : 'error' (default: zero-area facet -> ValueError naming it) or 'drop'.
    orient : 'auto' (default: consistent winding, closed parts outward, open surfaces upward; the
        number of flipped facets is ``info["reoriented_facets"]`` and an :class:`STLWarning` is
        issued when it is not zero) or 'keep' (the file's vertex order as written).
    orient_up : additionally flip every facet whose normal has N_z < 0 (open height fields with folds).

    Raises ``ValueError`` (:class:`STLError`) naming the file (and the line for ASCII, the facet for
    binary) on an empty, truncated, oversized or garbled file, non-finite coordinates, zero-area
    facets or repeated facets (same three corners; ``degenerate="drop"`` drops both kinds, counted in
    ``info["dropped_degenerate"]`` / ``info["dropped_duplicate"]``).

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "t.stl"
    >>> _ = p.write_text("solid a\\nfacet normal 0 0 1\\nouter loop\\nvertex 0 0 0\\nvertex 1 0 0\\n"
    ...                  "vertex 0 1 0\\nendloop\\nendfacet\\nendsolid a\\n\\n\\n")
    >>> m = read_stl(p); m.n_facets, m.info["format"], m.info["reoriented_facets"]
    (1, 'ascii', 0)
    """
    path = Path(path)
    raw = path.read_bytes()
    if not raw.strip():
        raise STLError(f"{path}: empty STL file")
    kind = _stl_kind(raw)
    flines = None
    if kind == "ascii":
        try:
            text = raw.decode("ascii")
        except UnicodeDecodeError as exc:
            line = raw[:exc.start].count(b"\n") + 1
            raise STLError(f"{path}:{line}: non-ASCII byte in an ASCII STL (or a binary STL whose size "
                           f"does not match its facet count)") from None
        tri, stored, flines, names = _parse_ascii_stl(text, path)
        name = names[0] or path.stem
        if len(tri) == 0:
            raise STLError(f"{path}: STL has no facets")
    else:
        tri, stored, name = _parse_binary_stl(raw, path)
        names = [name]
        name = name or path.stem
    where = (lambda k: f"{path}:{flines[k]}") if flines is not None else (lambda k: f"{path} (facet {k})")
    bad = ~np.isfinite(tri).all(axis=(1, 2))
    if bad.any():
        raise STLError(f"{where(int(np.argmax(bad)))}: non-finite vertex coordinate")
    try:
        mesh = TriMesh.from_triangles(tri, name=name, degenerate=degenerate, source=str(path))
    except STLError as exc:
        k = int(re.search(r"facet (\d+)", str(exc)).group(1))
        raise STLError(f"{where(k)}: {str(exc).split(': ', 1)[1]}") from None
    if mesh.info["dropped_degenerate"]:
        stored = stored[facet_areas(tri) > 1e-12 * max(float(np.ptp(tri.reshape(-1, 3), axis=0).max()), 1e-300) ** 2]
    # repeated facets: the same three welded corners (exact coordinates, -0.0 == 0.0) in any order
    vid = _weld_ids(mesh.triangles)
    first = _first_equal_triple(vid)
    dup = np.flatnonzero(first != np.arange(len(first)))
    if dup.size and degenerate == "error":
        k, j = int(dup[0]), int(first[dup[0]])
        raise STLError(f"{where(k)}: facet {k} repeats facet {j} (same three corners; {dup.size} duplicate "
                       "facet(s); pass degenerate='drop' to skip them)")
    if dup.size:
        keep = np.ones(len(first), bool)
        keep[dup] = False
        mesh.triangles, mesh.normals, stored = mesh.triangles[keep], mesh.normals[keep], stored[keep]
        vid = vid[keep]
    mesh.info["dropped_duplicate"] = int(dup.size)
    if orient == "auto":          # = orient_facets(mesh.triangles), reusing the welded vertex ids
        oinfo = {"components": 0, "non_manifold_edges": 0, "winding_conflicts": 0, "boundary_edges": 0}
        t2, flipped, oinfo = _orient(np.array(mesh.triangles, dtype=float, copy=True), oinfo, vid)
    else:
        t2, flipped, oinfo = orient_facets(mesh.triangles, orient)
    if flipped.any():
        mesh.triangles = t2
        mesh.normals = facet_normals(t2)
    ln = np.linalg.norm(stored, axis=1)
    missing = ln == 0
    unit = np.divide(stored, ln[:, None], out=np.zeros_like(stored), where=ln[:, None] > 0)
    inconsistent = ~missing & ((unit * mesh.normals).sum(axis=1) < np.cos(np.radians(1.0)))
    if orient_up:
        down = mesh.normals[:, 2] < 0
        mesh.triangles[down] = mesh.triangles[down][:, ::-1]
        mesh.normals[down] *= -1
        mesh.info["flipped_down_facets"] = int(down.sum())
    mesh.info.update(format=kind, solids=names, stored_normals_missing=int(missing.sum()),
                     stored_normals_inconsistent=int(inconsistent.sum()),
                     normals="recomputed from the (re-oriented) vertex order",
                     reoriented_facets=int(flipped.sum()), orientation=orient, source=str(path), **oinfo)
    if flipped.any():
        warnings.warn(f"{path}: {int(flipped.sum())} of {mesh.n_facets} facets re-oriented (consistent winding; "
                      "closed parts outward, open surfaces upward)", STLWarning, stacklevel=2)
    return mesh


def write_stl(path, mesh: TriMesh, ascii: bool = False, inputs=()) -> Path:
    """Write ``mesh`` as an ASCII or binary STL atomically (numpy-stl); normals from vertex order.

    ``inputs``: files that must not be overwritten (ValueError if ``path`` is one of them).
    """
    from stl import mesh as stlmesh
    from stl.stl import Mode

    data = np.zeros(mesh.n_facets, dtype=stlmesh.Mesh.dtype)
    data["vectors"] = mesh.triangles
    data["normals"] = facet_normals(mesh.triangles)
    m = stlmesh.Mesh(data, calculate_normals=False, name=mesh.name or "cnclab", speedups=False)
    with atomic_output(path, "wb", inputs=inputs) as fh:
        m.save(mesh.name or "cnclab", fh=fh, mode=Mode.ASCII if ascii else Mode.BINARY, update_normals=False)
    return Path(path)


# ----------------------------------------------------------------------------- nearest facet
def closest_point_on_triangles(p, a, b, c) -> np.ndarray:
    """Closest points on triangles (a, b, c) to points p, all (..., 3); vectorised (Ericson 2005, 5.1.5)."""
    p, a, b, c = (np.asarray(v, float) for v in (p, a, b, c))
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = (ab * ap).sum(-1), (ac * ap).sum(-1)
    bp = p - b
    d3, d4 = (ab * bp).sum(-1), (ac * bp).sum(-1)
    cp = p - c
    d5, d6 = (ab * cp).sum(-1), (ac * cp).sum(-1)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        v = vb / denom
        w = vc / denom
        out = a + ab * v[..., None] + ac * w[..., None]  # interior
        t_ab = d1 / (d1 - d3)
        t_ac = d2 / (d2 - d6)
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
    e_bc = (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0)
    out = np.where(e_bc[..., None], b + (c - b) * t_bc[..., None], out)
    e_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    out = np.where(e_ac[..., None], a + ac * t_ac[..., None], out)
    e_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    out = np.where(e_ab[..., None], a + ab * t_ab[..., None], out)
    out = np.where(((d6 >= 0) & (d5 <= d6))[..., None], c, out)
    out = np.where(((d3 >= 0) & (d4 <= d3))[..., None], b, out)
    out = np.where(((d1 <= 0) & (d2 <= 0))[..., None], a, out)
    return out


class FacetLocator:
    """Find the facet belonging to each cutter location (KD-tree over facet centroids).

    >>> tri = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0], [0, 1, 0]]], float)
    >>> loc = FacetLocator(TriMesh.from_triangles(tri))
    >>> loc.nearest_centroid([[0.9, 0.9, 0.0]]).tolist(), loc.nearest_facet([[0.1, 0.1, 5.0]]).tolist()
    ([1], [0])
    """

    def __init__(self, mesh: TriMesh, leafsize: int = 16):
        self.mesh = mesh
        self.centroids = mesh.centroids
        self.tree = cKDTree(self.centroids, leafsize=leafsize, balanced_tree=False, compact_nodes=False)

    @functools.cached_property
    def circumradius(self) -> float:
        """Largest distance (mm) from a facet centroid to one of its corners (computed on first use)."""
        return float(np.linalg.norm(self.mesh.triangles - self.centroids[:, None], axis=2).max())

    def nearest_centroid(self, points, workers: int = 1) -> np.ndarray:
        """Index of the facet whose centroid ("incentre", thesis rule) is nearest each point (N,)."""
        pts = np.asarray(points, float).reshape(-1, 3)
        return self.tree.query(pts, k=1, workers=workers)[1].astype(np.int64)

    def nearest_facet(self, points, k: int = 8, workers: int = 1) -> np.ndarray:
        """Index of the facet at the smallest Euclidean distance from each point (exact).

        Candidates: the ``k`` nearest centroids give an upper bound ``u`` on the distance; every facet
        whose centroid is within ``u + circumradius_max`` is then checked exactly.
        """
        pts = np.asarray(points, float).reshape(-1, 3)
        k = min(k, self.mesh.n_facets)
        _, idx = self.tree.query(pts, k=k, workers=workers)
        idx = idx.reshape(len(pts), k)
        T = self.mesh.triangles
        cp = closest_point_on_triangles(pts[:, None], T[idx, 0], T[idx, 1], T[idx, 2])
        dist = np.linalg.norm(cp - pts[:, None], axis=2)
        best = idx[np.arange(len(pts)), dist.argmin(axis=1)]
        upper = dist.min(axis=1)
        radius = upper + self.circumradius + 1e-9
        # points whose k candidates may miss the nearest facet: check every facet in the bound
        kth = np.linalg.norm(self.centroids[idx[:, -1]] - pts, axis=1)
        unsure = np.nonzero(kth < radius)[0]
        if unsure.size:
            lists = self.tree.query_ball_point(pts[unsure], radius[unsure], workers=workers)
            lens = np.fromiter((len(l) for l in lists), int, len(lists))
            cand = np.concatenate([np.asarray(l, np.int64) for l in lists]) if lens.sum() else np.zeros(0, int)
            owner = np.repeat(np.arange(unsure.size), lens)
            cpu = closest_point_on_triangles(pts[unsure][owner], T[cand, 0], T[cand, 1], T[cand, 2])
            d = np.linalg.norm(cpu - pts[unsure][owner], axis=1)
            order = np.lexsort((d, owner))
            first = np.ones(order.size, bool)
            first[1:] = owner[order][1:] != owner[order][:-1]
            best[unsure[owner[order][first]]] = cand[order][first]
        return best
