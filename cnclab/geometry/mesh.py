"""Triangle meshes for CAM: STL read/write, facet normals, incentres, nearest-facet lookup.

STL files are read and written with numpy-stl (ASCII and binary, detected automatically). All
lengths are in mm. A :class:`TriMesh` holds the corner coordinates ``triangles`` (F, 3, 3) and unit
facet ``normals`` (F, 3).

Normals. The STL standard says the stored facet normal must agree with the counter-clockwise vertex
order (right-hand rule), but many exporters write zeros or stale normals. cnclab therefore **always
uses the normal recomputed from the vertex order**; the stored normals are only compared with it,
and the number of stored normals that were missing (zero) or inconsistent (angle > 1 deg, or
opposite) is reported in ``TriMesh.info``. ``read_stl(..., orient_up=True)`` additionally flips
facets whose recomputed normal points downwards (N_z < 0) -- useful for open height-field surfaces
written with mixed winding; closed solids should keep the default ``False``.

Nearest facet. Mgherony (2024, Sec. 7.2.3) assigns each cutter location the facet whose "incentre"
(which the thesis computes as the *average of the three corners*, i.e. the centroid) is nearest.
:class:`FacetLocator` does this with a KD-tree (``nearest_centroid``), and also offers the exact
nearest facet in Euclidean distance (``nearest_facet``) and the true incentre (``facet_incentres``).
"""
from __future__ import annotations

import dataclasses
import io
import re
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from ..fileio import atomic_output

__all__ = ["TriMesh", "read_stl", "write_stl", "facet_normals", "facet_centroids", "facet_incentres",
           "facet_areas", "machined_surface_mask", "FacetLocator", "closest_point_on_triangles",
           "inclination_angles"]


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
        areas = facet_areas(tri)
        scale = max(float(np.ptp(tri.reshape(-1, 3), axis=0).max()) if len(tri) else 1.0, 1e-300)
        zero = areas <= 1e-12 * scale * scale
        if zero.any():
            if degenerate == "error":
                raise STLError(f"{source}: facet {int(np.argmax(zero))} has zero area "
                               f"({int(zero.sum())} degenerate facet(s); pass degenerate='drop' to skip them)")
            if degenerate != "drop":
                raise ValueError(f"degenerate must be 'error' or 'drop', got {degenerate!r}")
            tri = tri[~zero]
        return cls(tri, facet_normals(tri), name=name, info={"dropped_degenerate": int(zero.sum())})

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
    axes = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, -1]], float)
    return ~((n @ axes.T) >= c).any(axis=1)


# ----------------------------------------------------------------------------- STL files
_FLOAT = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:nan|inf|infinity)"
_VERTEX_RE = re.compile(rf"^\s*vertex\s+({_FLOAT})\s+({_FLOAT})\s+({_FLOAT})\s*$", re.I)


def _is_ascii_stl(raw: bytes) -> bool:
    if not raw.lstrip()[:5].lower() == b"solid":
        return False
    if len(raw) >= 84:  # a binary file may start with "solid": trust the facet count if it fits
        count = int(np.frombuffer(raw[80:84], "<u4")[0])
        if 84 + 50 * count == len(raw):
            return False
    return b"facet" in raw[:4096].lower() or b"endsolid" in raw.lower()


def _check_ascii(text: str, path: Path) -> None:
    """Line-level validation of an ASCII STL so that errors name the line (parsing itself is numpy-stl's)."""
    state, n_vert, facet_line = "solid", 0, 0
    lines = text.splitlines()
    for i, line in enumerate(lines, start=1):
        s = line.strip()
        if not s:
            continue
        low = s.lower()
        kw = low.split()[0]
        if kw == "vertex":
            m = _VERTEX_RE.match(s)
            if not m:
                raise STLError(f"{path}:{i}: garbled vertex line {s[:60]!r} (need 'vertex x y z')")
            vals = np.array([float(v) for v in m.groups()])
            if not np.isfinite(vals).all():
                raise STLError(f"{path}:{i}: non-finite vertex coordinate {s[:60]!r}")
            n_vert += 1
        elif kw == "facet":
            facet_line, n_vert = i, 0
            parts = s.split()
            if len(parts) != 5 or parts[1].lower() != "normal":
                raise STLError(f"{path}:{i}: garbled facet line {s[:60]!r} (need 'facet normal nx ny nz')")
            try:
                [float(p) for p in parts[2:]]
            except ValueError:
                raise STLError(f"{path}:{i}: garbled facet normal {s[:60]!r}") from None
        elif kw == "endfacet":
            if n_vert != 3:
                raise STLError(f"{path}:{i}: facet starting on line {facet_line} has {n_vert} vertices, not 3")
        elif kw not in ("solid", "endsolid", "outer", "endloop"):
            raise STLError(f"{path}:{i}: unexpected text {s[:60]!r}")
    if not any(l.strip().lower().startswith("endsolid") for l in lines[-5:]):
        raise STLError(f"{path}:{len(lines)}: truncated ASCII STL (no 'endsolid' at the end)")


def _facet_line(text: str, k: int) -> int:
    """1-based line number of the k-th facet of an ASCII STL."""
    count = -1
    for i, line in enumerate(text.splitlines(), start=1):
        if line.lstrip().lower().startswith("facet"):
            count += 1
            if count == k:
                return i
    return 0


def read_stl(path, degenerate: str = "error", orient_up: bool = False) -> TriMesh:
    """Read an ASCII or binary STL (numpy-stl); normals recomputed from the vertex order.

    Parameters
    ----------
    path : STL file (mm).
    degenerate : 'error' (default: zero-area facet -> ValueError naming it) or 'drop'.
    orient_up : flip facets whose normal has N_z < 0 (open height-field surfaces only).

    Raises ``ValueError`` (:class:`STLError`) naming the file (and line for ASCII) on a truncated or
    garbled file, non-finite coordinates or zero-area facets.
    """
    from stl import mesh as stlmesh

    path = Path(path)
    raw = path.read_bytes()
    if not raw:
        raise STLError(f"{path}: empty STL file")
    ascii_ = _is_ascii_stl(raw)
    text = None
    if ascii_:
        text = raw.decode("ascii", errors="replace")
        _check_ascii(text, path)
    else:
        if len(raw) < 84:
            raise STLError(f"{path}: truncated binary STL ({len(raw)} bytes, header needs 84)")
        count = int(np.frombuffer(raw[80:84], "<u4")[0])
        if len(raw) < 84 + 50 * count:
            raise STLError(f"{path}: truncated binary STL: header announces {count} facets "
                           f"({84 + 50 * count} bytes), file has {len(raw)} bytes")
    try:
        m = stlmesh.Mesh.from_file(str(path), fh=io.BytesIO(raw), calculate_normals=False,
                                   speedups=False)
    except Exception as exc:  # numpy-stl raises assorted errors on bad files
        raise STLError(f"{path}: cannot read STL: {exc}") from None
    tri = np.asarray(m.vectors, dtype=float).reshape(-1, 3, 3)
    if tri.shape[0] == 0:
        raise STLError(f"{path}: STL has no facets")
    where = lambda k: f"{path}:{_facet_line(text, k)}" if ascii_ else f"{path} (facet {k})"  # noqa: E731
    bad = ~np.isfinite(tri).all(axis=(1, 2))
    if bad.any():
        raise STLError(f"{where(int(np.argmax(bad)))}: non-finite vertex coordinate")
    try:
        mesh = TriMesh.from_triangles(tri, name=(m.name.decode(errors="replace") if isinstance(m.name, bytes)
                                                 else str(m.name)) or path.stem,
                                      degenerate=degenerate, source=str(path))
    except STLError as exc:
        k = int(re.search(r"facet (\d+)", str(exc)).group(1))
        raise STLError(f"{where(k)}: {str(exc).split(': ', 1)[1]}") from None
    stored = np.asarray(m.normals, float).reshape(-1, 3)
    if degenerate == "drop" and mesh.info["dropped_degenerate"]:
        keep = facet_areas(tri) > 0
        stored = stored[keep][: mesh.n_facets]
    ln = np.linalg.norm(stored, axis=1)
    missing = ln == 0
    unit = np.divide(stored, ln[:, None], out=np.zeros_like(stored), where=ln[:, None] > 0)
    inconsistent = ~missing & ((unit * mesh.normals).sum(axis=1) < np.cos(np.radians(1.0)))
    if orient_up:
        down = mesh.normals[:, 2] < 0
        mesh.triangles[down] = mesh.triangles[down][:, ::-1]
        mesh.normals[down] *= -1
        mesh.info["flipped_down_facets"] = int(down.sum())
    mesh.info.update(format="ascii" if ascii_ else "binary", stored_normals_missing=int(missing.sum()),
                     stored_normals_inconsistent=int(inconsistent.sum()), normals="recomputed from vertex order",
                     source=str(path))
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
        self.circumradius = float(np.linalg.norm(mesh.triangles - self.centroids[:, None], axis=2).max())

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
