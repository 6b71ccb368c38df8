"""The mesh type: :class:`TriMesh` (corner coordinates and unit normals, mm) and per-facet geometry
(normals from the vertex order, areas, centroids, incentres, inclination, the machined-surface mask)."""
from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["TriMesh", "STLError", "COORD_LIMIT_MM", "facet_normals", "facet_areas", "facet_centroids",
           "facet_incentres", "inclination_angles", "machined_surface_mask"]


#: Largest accepted |coordinate| (mm): 1000 km, far beyond any machinable part; larger values are a unit
#: or export error, and near 1e154 the facet areas (squares of coordinates) overflow to inf.
COORD_LIMIT_MM = 1e9


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
        huge = (np.abs(tri) > COORD_LIMIT_MM).any(axis=(1, 2))
        if huge.any():                 # squares / cross products would overflow to inf (not "zero area")
            k = int(np.argmax(huge))
            raise STLError(f"{source}: facet {k} has a vertex coordinate {float(np.abs(tri[k]).max()):.6g} mm, "
                           f"beyond the +/-{COORD_LIMIT_MM:.0e} mm range (its area would overflow)")
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
