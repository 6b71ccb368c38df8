"""Drop-cutter finishing paths for a ball-end mill over a triangle mesh (all lengths mm).

For each cutter location (x, y) the ball (radius R) is lowered along -z until it first touches the
mesh; the touching height is the maximum over all facets of three contact tests (facet interior,
edge, vertex). The returned z is the **tool tip** (ball centre - R), as in the thesis's CL files
("the tool contact point is located at the nose point of the tool"). Because every facet within
reach is tested, the ball touches but never penetrates the mesh (no gouging).

Zig-zag path: parallel passes at feed angle A_f (deg from +x), spaced a_e, alternating direction,
linked by feed moves along the part boundary, sampled every ``step`` mm and drop-cut.

>>> from cnclab.geometry.mesh import TriMesh
>>> flat = TriMesh.from_triangles([[[-10, -10, 2], [10, -10, 2], [10, 10, 2]], [[-10, -10, 2], [10, 10, 2], [-10, 10, 2]]])
>>> drop_cutter_z(flat, [[0.0, 0.0]], tool_radius=5.0).round(9).tolist()
[2.0]
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange
from scipy.spatial import cKDTree

from ..geometry.mesh import TriMesh
from .path import Tool, ToolPath
from .zigzag import raster_passes

__all__ = ["drop_cutter_z", "zigzag_finishing_path", "split_passes"]


def _pair_heights(px, py, T, N, R):
    """Ball-centre height touching each facet T (P, 3, 3) for centres (px, py) (P,); -inf if none."""
    z = np.full(px.shape, -np.inf)
    # vertices
    for k in range(3):
        d2 = (px - T[:, k, 0]) ** 2 + (py - T[:, k, 1]) ** 2
        ok = d2 <= R * R
        z = np.where(ok, np.maximum(z, T[:, k, 2] + np.sqrt(np.clip(R * R - d2, 0, None))), z)
    # facet interiors (normal oriented up)
    n = N * np.where(N[:, 2:3] < 0, -1.0, 1.0)
    nz = n[:, 2]
    up = nz > 1e-12
    with np.errstate(divide="ignore", invalid="ignore"):
        zc = (R + (n * T[:, 0]).sum(1) - n[:, 0] * px - n[:, 1] * py) / nz
    cx, cy = px - R * n[:, 0], py - R * n[:, 1]
    # barycentric test of the contact point (cx, cy) in the xy projection
    a, b, c = T[:, 0, :2], T[:, 1, :2], T[:, 2, :2]
    v0, v1 = b - a, c - a
    v2 = np.stack([cx, cy], 1) - a
    den = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (v2[:, 0] * v1[:, 1] - v1[:, 0] * v2[:, 1]) / den
        t = (v0[:, 0] * v2[:, 1] - v2[:, 0] * v0[:, 1]) / den
    eps = 1e-12
    inside = up & (np.abs(den) > 0) & (s >= -eps) & (t >= -eps) & (s + t <= 1 + eps)
    z = np.where(inside, np.maximum(z, zc), z)
    # edges: ball touching the segment a->b in its interior
    for i, j in ((0, 1), (1, 2), (2, 0)):
        A, B = T[:, i], T[:, j]
        d = B - A
        L = np.linalg.norm(d, axis=1)
        u = d / np.where(L > 0, L, 1)[:, None]
        wx, wy = px - A[:, 0], py - A[:, 1]
        s0 = wx * u[:, 0] + wy * u[:, 1]
        qa = 1 - u[:, 2] ** 2
        qb = -2 * s0 * u[:, 2]
        qc = wx * wx + wy * wy - s0 * s0 - R * R
        disc = qb * qb - 4 * qa * qc
        ok = (qa > 1e-12) & (disc >= 0) & (L > 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            tt = (-qb + np.sqrt(np.clip(disc, 0, None))) / (2 * qa)
        along = s0 + tt * u[:, 2]
        ok &= (along >= 0) & (along <= L)
        z = np.where(ok, np.maximum(z, A[:, 2] + tt), z)
    return z


def drop_cutter_z(mesh: TriMesh, xy, tool_radius: float, chunk: int = 2_000_000,
                  default_z: float = np.nan, method: str = "grid") -> np.ndarray:
    """Tool-tip z (mm) of a ball-end mill of ``tool_radius`` (mm) dropped onto ``mesh`` at points xy (N, 2).

    Points where the ball touches nothing get ``default_z``.

    ``method="grid"`` (default): a uniform xy grid of cells indexes every facet under each cell its
    bounding box, grown by the radius, overlaps; a compiled kernel (numba, one thread per core) tests
    for each point only the facets listed in its cell, highest first, and stops as soon as no
    remaining facet can lift the ball higher (a facet's contact height is at most its top vertex
    z + R). ``method="kdtree"``: the reference numpy version, vectorised over (point, facet) pairs
    found with a KD-tree on facet centroids, processed in chunks of ``chunk`` pairs. Both evaluate
    the same contact formulas in the same floating-point order.
    """
    R = float(tool_radius)
    if not (np.isfinite(R) and R > 0):
        raise ValueError(f"tool_radius must be > 0 mm, got {tool_radius}")
    if method not in ("grid", "kdtree"):
        raise ValueError(f"method must be 'grid' or 'kdtree', got {method!r}")
    xy = np.asarray(xy, float).reshape(-1, 2)
    if not np.isfinite(xy).all():
        raise ValueError("xy: non-finite cutter location")
    if method == "grid":
        out = _drop_grid(mesh, xy, R)
    else:
        out = _drop_kdtree(mesh, xy, R, chunk)
    tip = out - R
    return np.where(np.isfinite(tip), tip, default_z)


def _drop_kdtree(mesh: TriMesh, xy: np.ndarray, R: float, chunk: int) -> np.ndarray:
    """Ball-centre heights (-inf where nothing is touched), numpy reference over KD-tree pairs."""
    T = mesh.triangles
    cen = T[:, :, :2].mean(axis=1)
    reach = R + float(np.linalg.norm(T[:, :, :2] - cen[:, None], axis=2).max()) + 1e-9
    tree = cKDTree(cen)
    out = np.full(len(xy), -np.inf)
    # choose point batches so that the number of pairs per batch stays near `chunk`
    density = mesh.n_facets / max(np.ptp(cen[:, 0]) * np.ptp(cen[:, 1]), 1e-9)
    per_point = max(1.0, density * np.pi * reach * reach)
    batch = int(max(1, chunk // per_point))
    for s in range(0, len(xy), batch):
        pts = xy[s:s + batch]
        lists = tree.query_ball_point(pts, reach)
        lens = np.fromiter((len(l) for l in lists), int, len(lists))
        if lens.sum() == 0:
            continue
        fac = np.concatenate([np.asarray(l, np.int64) for l in lists])
        own = np.repeat(np.arange(len(pts)), lens)
        zc = _pair_heights(pts[own, 0], pts[own, 1], T[fac], mesh.normals[fac], R)
        res = np.full(len(pts), -np.inf)
        np.maximum.at(res, own, zc)
        out[s:s + batch] = res
    return out


def _drop_grid(mesh: TriMesh, xy: np.ndarray, R: float) -> np.ndarray:
    """Ball-centre heights (-inf where nothing is touched) with the facet grid and compiled kernel."""
    T = np.ascontiguousarray(mesh.triangles, dtype=float)
    N = np.asarray(mesh.normals, dtype=float)
    n = np.ascontiguousarray(N * np.where(N[:, 2:3] < 0, -1.0, 1.0))
    if len(xy) == 0 or len(T) == 0:
        return np.full(len(xy), -np.inf)
    grow = R + 1e-9                            # facet bounding boxes grown by R (xy), + rounding
    lo = T[:, :, :2].min(axis=1) - grow
    hi = T[:, :, :2].max(axis=1) + grow
    zmax = T[:, :, 2].max(axis=1)
    order = np.argsort(-zmax, kind="stable")  # highest facets first in every cell
    x0, y0 = min(lo[:, 0].min(), xy[:, 0].min()), min(lo[:, 1].min(), xy[:, 1].min())
    x1, y1 = max(hi[:, 0].max(), xy[:, 0].max()), max(hi[:, 1].max(), xy[:, 1].max())
    # cell: about half the radius, but no more cells than ~4 per facet or per point
    h = max(R / 2.0, np.sqrt((x1 - x0) * (y1 - y0) / (4.0 * max(len(T), len(xy)))), 1e-9)
    nx = int(min((x1 - x0) / h, 4096)) + 1
    ny = int(min((y1 - y0) / h, 4096)) + 1
    hx, hy = max((x1 - x0) / nx, 1e-12), max((y1 - y0) / ny, 1e-12)
    start, items = _grid_build(lo, hi, order, x0, y0, hx, hy, nx, ny)
    return _grid_drop(xy, T, n, lo, hi, zmax, start, items, (x0, y0, hx, hy, nx, ny), R)


@njit(cache=True)
def _cell_range(a, b, o, h, n):
    i0 = int((a - o) / h)
    i1 = int((b - o) / h)
    return max(i0, 0), min(i1, n - 1)


@njit(cache=True)
def _grid_build(lo, hi, order, x0, y0, hx, hy, nx, ny):
    """CSR lists (start (nx*ny+1,), items) of the facets whose grown box overlaps each cell, each
    list in the order of ``order``."""
    count = np.zeros(nx * ny + 1, np.int64)
    for f in order:
        i0, i1 = _cell_range(lo[f, 0], hi[f, 0], x0, hx, nx)
        j0, j1 = _cell_range(lo[f, 1], hi[f, 1], y0, hy, ny)
        for j in range(j0, j1 + 1):
            for i in range(i0, i1 + 1):
                count[j * nx + i + 1] += 1
    start = np.cumsum(count)
    fill = start[:-1].copy()
    items = np.empty(start[-1], np.int64)
    for f in order:
        i0, i1 = _cell_range(lo[f, 0], hi[f, 0], x0, hx, nx)
        j0, j1 = _cell_range(lo[f, 1], hi[f, 1], y0, hy, ny)
        for j in range(j0, j1 + 1):
            for i in range(i0, i1 + 1):
                c = j * nx + i
                items[fill[c]] = f
                fill[c] += 1
    return start, items


@njit(cache=True)
def _facet_height(px, py, T, n, f, R):
    """Ball-centre height touching facet f (the formulas of :func:`_pair_heights`, same order)."""
    z = -np.inf
    RR = R * R
    for k in range(3):
        d2 = (px - T[f, k, 0]) ** 2 + (py - T[f, k, 1]) ** 2
        if d2 <= RR:
            z = max(z, T[f, k, 2] + math.sqrt(max(RR - d2, 0.0)))
    n0, n1, nz = n[f, 0], n[f, 1], n[f, 2]
    if nz > 1e-12:
        ax, ay = T[f, 0, 0], T[f, 0, 1]
        v0x, v0y = T[f, 1, 0] - ax, T[f, 1, 1] - ay
        v1x, v1y = T[f, 2, 0] - ax, T[f, 2, 1] - ay
        den = v0x * v1y - v1x * v0y
        if abs(den) > 0:
            cx, cy = px - R * n0, py - R * n1
            v2x, v2y = cx - ax, cy - ay
            s = (v2x * v1y - v1x * v2y) / den
            t = (v0x * v2y - v2x * v0y) / den
            eps = 1e-12
            if s >= -eps and t >= -eps and s + t <= 1 + eps:
                sd = n0 * T[f, 0, 0] + n1 * T[f, 0, 1] + nz * T[f, 0, 2]
                zc = (R + sd - n0 * px - n1 * py) / nz
                z = max(z, zc)
    for e in range(3):
        i, j = e, (e + 1) % 3
        Ax, Ay, Az = T[f, i, 0], T[f, i, 1], T[f, i, 2]
        dx, dy, dz = T[f, j, 0] - Ax, T[f, j, 1] - Ay, T[f, j, 2] - Az
        L = math.sqrt(dx * dx + dy * dy + dz * dz)
        if not L > 0:
            continue
        ux, uy, uz = dx / L, dy / L, dz / L
        wx, wy = px - Ax, py - Ay
        s0 = wx * ux + wy * uy
        qa = 1 - uz ** 2
        if not qa > 1e-12:
            continue
        qb = -2 * s0 * uz
        qc = wx * wx + wy * wy - s0 * s0 - RR
        disc = qb * qb - 4 * qa * qc
        if not disc >= 0:
            continue
        tt = (-qb + math.sqrt(max(disc, 0.0))) / (2 * qa)
        along = s0 + tt * uz
        if along >= 0 and along <= L:
            z = max(z, Az + tt)
    return z


@njit(cache=True, parallel=True)
def _grid_drop(xy, T, n, lo, hi, zmax, start, items, grid, R):
    """Ball-centre height (mm) at every point ``xy`` over the facets listed per cell (``start``,
    ``items``: :func:`_grid_build`); ``grid`` = (x0, y0, hx, hy, nx, ny): origin and cell size (mm),
    cell counts; R ball radius (mm)."""
    x0, y0, hx, hy, nx, ny = grid
    out = np.full(len(xy), -np.inf)
    grow = R + 1e-9
    RR = R * R * (1 + 1e-12) + 1e-12
    for p in prange(len(xy)):
        px, py = xy[p, 0], xy[p, 1]
        i = min(max(int((px - x0) / hx), 0), nx - 1)
        j = min(max(int((py - y0) / hy), 0), ny - 1)
        c = j * nx + i
        best = -np.inf
        for q in range(start[c], start[c + 1]):
            f = items[q]
            if zmax[f] + R + 1e-9 < best:
                break      # lists are sorted by top z: no later facet can lift the ball higher
            if px < lo[f, 0] or px > hi[f, 0] or py < lo[f, 1] or py > hi[f, 1]:
                continue
            # xy distance from the point to the facet's own box bounds every contact height
            ex = max(lo[f, 0] + grow - px, px - (hi[f, 0] - grow), 0.0)
            ey = max(lo[f, 1] + grow - py, py - (hi[f, 1] - grow), 0.0)
            e2 = ex * ex + ey * ey
            if e2 > RR or zmax[f] + math.sqrt(RR - e2) + 1e-9 < best:
                continue
            z = _facet_height(px, py, T, n, f, R)
            if z > best:
                best = z
        out[p] = best
    return out


def zigzag_finishing_path(mesh: TriMesh, tool_diameter: float, a_e: float, feed_angle_deg: float,
                          step: float = 0.5, bounds=None, feed_mm_min: float = 1000.0) -> ToolPath:
    """Drop-cut zig-zag finishing path over ``mesh``: a :class:`ToolPath` of tool-tip CL points (mm),
    every move a ``cut`` at ``feed_mm_min`` tagged ``"pass k"`` (the link to the next pass, along
    the boundary, belongs to pass k); :func:`split_passes` gives the passes back. The xy points are
    :func:`cnclab.toolpath.zigzag.raster_passes` on the rectangle (last pass on its edge, sampled
    evenly every ``step`` mm or less, links included).

    ``bounds`` (x0, x1, y0, y1) defaults to the mesh's xy extent (the tool centre line stays inside).
    """
    if not (np.isfinite(tool_diameter) and tool_diameter > 0):
        raise ValueError(f"tool_diameter must be > 0 mm, got {tool_diameter}")
    if bounds is None:
        lo, hi = mesh.triangles.reshape(-1, 3).min(0), mesh.triangles.reshape(-1, 3).max(0)
        bounds = (lo[0], hi[0], lo[1], hi[1])
    passes = raster_passes(tuple(bounds), a_e, feed_angle_deg, last="edge", step=step, links=True)
    xy = np.vstack(passes)
    z = drop_cutter_z(mesh, xy, tool_diameter / 2.0)
    if np.isnan(z).any():
        raise ValueError("zigzag_finishing_path: some cutter locations do not touch the mesh")
    tags = np.concatenate([np.full(len(q), f"pass {k}", dtype=object) for k, q in enumerate(passes)])
    return ToolPath.build(np.column_stack([xy, z]), kind="cut", tag=tags, feed=feed_mm_min,
                          tool=Tool(float(tool_diameter), 0.5 * float(tool_diameter)),
                          info={"name": "drop-cutter zig-zag finishing", "feed_angle_deg": float(feed_angle_deg),
                                "a_e": float(a_e)})


def split_passes(path: ToolPath) -> list[np.ndarray]:
    """The (M, 3) point arrays of the passes of a finishing path (consecutive runs of one tag)."""
    cuts = np.flatnonzero(path.tag[1:] != path.tag[:-1]) + 1
    return np.split(path.xyz, cuts)
