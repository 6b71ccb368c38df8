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

import numpy as np
from scipy.spatial import cKDTree

from ..geometry.mesh import TriMesh
from .path import Tool, ToolPath

__all__ = ["drop_cutter_z", "zigzag_xy", "zigzag_finishing_path", "split_passes"]


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
                  default_z: float = np.nan) -> np.ndarray:
    """Tool-tip z (mm) of a ball-end mill of ``tool_radius`` (mm) dropped onto ``mesh`` at points xy (N, 2).

    Points where the ball touches nothing get ``default_z``. Vectorised over (point, facet) pairs
    found with a KD-tree on facet centroids (x, y), processed in chunks of ``chunk`` pairs.
    """
    R = float(tool_radius)
    if not (np.isfinite(R) and R > 0):
        raise ValueError(f"tool_radius must be > 0 mm, got {tool_radius}")
    xy = np.asarray(xy, float).reshape(-1, 2)
    if not np.isfinite(xy).all():
        raise ValueError("xy: non-finite cutter location")
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
    tip = out - R
    return np.where(np.isfinite(tip), tip, default_z)


def zigzag_xy(bounds, a_e: float, feed_angle_deg: float, step: float) -> list[np.ndarray]:
    """Zig-zag passes (list of (M, 2) arrays, mm) covering the rectangle ``bounds`` = (x0, x1, y0, y1).

    Passes run along (cos A_f, sin A_f), spaced ``a_e`` apart, alternating direction; each is
    sampled every ``step`` mm or less (end points included). The link to the next pass is appended
    to the end of each pass (along the boundary), so concatenating the passes gives the full path.
    """
    x0, x1, y0, y1 = map(float, bounds)
    if not (a_e > 0 and step > 0):
        raise ValueError(f"a_e and step must be > 0 mm, got {a_e}, {step}")
    A = np.radians(feed_angle_deg)
    u = np.array([np.cos(A), np.sin(A)])
    v = np.array([-np.sin(A), np.cos(A)])
    corners = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    cv = corners @ v
    offs = np.arange(cv.min(), cv.max() + 1e-9, a_e)
    if offs.size == 0 or cv.max() - offs[-1] > 1e-9:
        offs = np.append(offs, cv.max())
    lines = []
    for k, o in enumerate(offs):
        p0 = o * v
        # clip the line p0 + t u to the rectangle
        tmin, tmax = -np.inf, np.inf
        for ax, lo, hi in ((0, x0, x1), (1, y0, y1)):
            if abs(u[ax]) < 1e-12:
                if not (lo - 1e-9 <= p0[ax] <= hi + 1e-9):
                    tmin, tmax = 1.0, 0.0
                continue
            ta, tb = (lo - p0[ax]) / u[ax], (hi - p0[ax]) / u[ax]
            tmin, tmax = max(tmin, min(ta, tb)), min(tmax, max(ta, tb))
        if tmax - tmin < 1e-9:
            continue
        n = int(np.ceil((tmax - tmin) / step))
        t = np.linspace(tmin, tmax, n + 1)
        seg = p0 + t[:, None] * u
        lines.append(seg if len(lines) % 2 == 0 else seg[::-1])
    passes = []
    for k, seg in enumerate(lines):
        if k + 1 < len(lines):
            nxt = lines[k + 1][0]
            d = np.linalg.norm(nxt - seg[-1])
            m = int(np.ceil(d / step))
            link = seg[-1] + np.linspace(0, 1, m + 1)[1:-1, None] * (nxt - seg[-1]) if m > 1 else np.zeros((0, 2))
            seg = np.vstack([seg, link])
        passes.append(np.clip(seg, [x0, y0], [x1, y1]))
    return passes


def zigzag_finishing_path(mesh: TriMesh, tool_diameter: float, a_e: float, feed_angle_deg: float,
                          step: float = 0.5, bounds=None, feed_mm_min: float = 1000.0) -> ToolPath:
    """Drop-cut zig-zag finishing path over ``mesh``: a :class:`ToolPath` of tool-tip CL points (mm),
    every move a ``cut`` at ``feed_mm_min`` tagged ``"pass k"`` (the link to the next pass, along
    the boundary, belongs to pass k); :func:`split_passes` gives the passes back.

    ``bounds`` (x0, x1, y0, y1) defaults to the mesh's xy extent (the tool centre line stays inside).
    """
    if not (np.isfinite(tool_diameter) and tool_diameter > 0):
        raise ValueError(f"tool_diameter must be > 0 mm, got {tool_diameter}")
    if bounds is None:
        lo, hi = mesh.triangles.reshape(-1, 3).min(0), mesh.triangles.reshape(-1, 3).max(0)
        bounds = (lo[0], hi[0], lo[1], hi[1])
    passes = zigzag_xy(bounds, a_e, feed_angle_deg, step)
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
