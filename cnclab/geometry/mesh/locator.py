"""Nearest facet: :func:`closest_point_on_triangles` (Ericson 2005) and :class:`FacetLocator` (KD-tree
over centroids; the thesis rule ``nearest_centroid`` and the exact ``nearest_facet``)."""
from __future__ import annotations

import functools

import numpy as np
from scipy.spatial import cKDTree

from .core import TriMesh

__all__ = ["closest_point_on_triangles", "FacetLocator"]


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
