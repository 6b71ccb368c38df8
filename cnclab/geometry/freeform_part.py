"""Test parts of Mgherony (2024) as height fields and STL meshes (mm).

Chapter 8 test part (Fig 8-1): 50 x 50 mm, "a sphere (R = 106.25 mm), a toroid (R = 25 mm) section
and a horizontal plane", height 10 mm. The layout is not published; :class:`FreeformPart` is a
parameterised reconstruction that fits every statement of the text:

- a surface of revolution about a vertical axis through one corner (the ``apex``, default (50, 50)),
  so the diagonal plane is a symmetry plane (Sec. 8.2: "the diagonal plane is a symmetric plane too");
- a convex spherical cap (R_s = 106.25) at the top (zone 1.1 "at the top ... on a large radius
  section and nearly horizontal"), joined tangentially by a concave toroidal fillet (tube radius
  R_t = 25, the "small radius") to a horizontal plane at z = 0 (zone 4.4 "at the transition between
  the small radius and the horizontal surface");
- tangent continuity and total height h fix the blend slope: (R_s + R_t)(1 - cos a) = h, which gives
  a = 22.51 deg for h = 10 -- the steepest slope of the part.

In-text coordinates of chapters 7 and 9 (z = 9.994 at (4.9, 50.25) in the Sec. 7.2.2 excerpt, z = 10
at (28.5, 43.9) in Sec. 9.3) do not fit a single apex and suggest a different placement; the claims
that depend on the exact layout are therefore marked as such in the ledger.

Tessellation: :func:`tessellate_heightfield` samples any z(x, y) on a regular grid (two triangles
per cell, counter-clockwise seen from above, normals up), optionally closed with walls and bottom
(which the thesis's facet filter then removes).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from .cylinder_parts import CylinderPart
from .mesh import TriMesh

__all__ = ["FreeformPart", "tessellate_heightfield", "freeform_part_mesh", "cylinder_part_mesh"]


@dataclasses.dataclass(frozen=True)
class FreeformPart:
    """Chapter 8 test part: spherical cap + concave toroidal fillet + plane (all lengths mm).

    >>> p = FreeformPart()
    >>> round(p.blend_slope_deg, 2), float(p.height_at(50, 50)), float(p.height_at(0, 0))
    (22.51, 10.0, 0.0)
    """

    size_x: float = 50.0
    size_y: float = 50.0
    sphere_radius: float = 106.25
    torus_radius: float = 25.0
    height: float = 10.0
    apex: tuple = (50.0, 50.0)

    def __post_init__(self):
        for name in ("size_x", "size_y", "sphere_radius", "torus_radius", "height"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a positive finite length in mm, got {v}")
        if self.height >= self.sphere_radius + self.torus_radius:
            raise ValueError(f"height must be < sphere_radius + torus_radius, got {self.height}")

    @property
    def blend_slope_deg(self) -> float:
        """Slope (deg) at the sphere/toroid junction: acos(1 - h/(R_s + R_t))."""
        return float(np.degrees(np.arccos(1 - self.height / (self.sphere_radius + self.torus_radius))))

    @property
    def radii(self) -> tuple[float, float]:
        """Horizontal distances from the apex where the sphere ends and the plane begins (mm)."""
        a = np.radians(self.blend_slope_deg)
        r1 = self.sphere_radius * np.sin(a)
        return float(r1), float(r1 + self.torus_radius * np.sin(a))

    def _rho(self, x, y):
        dx = np.asarray(x, float) - self.apex[0]
        dy = np.asarray(y, float) - self.apex[1]
        return np.hypot(dx, dy), dx, dy

    def height_at(self, x, y) -> np.ndarray:
        """Surface height z(x, y) in mm (vectorised)."""
        rho, _, _ = self._rho(x, y)
        r1, r2 = self.radii
        Rs, Rt = self.sphere_radius, self.torus_radius
        z_s = self.height - Rs + np.sqrt(np.maximum(Rs ** 2 - np.minimum(rho, r1) ** 2, 0))
        d = np.clip(r2 - rho, 0, None)
        z_t = Rt - np.sqrt(np.maximum(Rt ** 2 - d ** 2, 0))
        return np.where(rho <= r1, z_s, np.where(rho <= r2, z_t, 0.0))

    def slope_deg(self, x, y) -> np.ndarray:
        """Surface slope A_N2 (deg from horizontal) at (x, y)."""
        rho, _, _ = self._rho(x, y)
        r1, r2 = self.radii
        s = np.where(rho <= r1, rho / self.sphere_radius,
                     np.where(rho <= r2, (r2 - rho) / self.torus_radius, 0.0))
        return np.degrees(np.arcsin(np.clip(s, 0, 1)))

    def normal_at(self, x, y) -> np.ndarray:
        """Unit surface normal (..., 3), pointing up and away from the apex."""
        rho, dx, dy = self._rho(x, y)
        th = np.radians(self.slope_deg(x, y))
        with np.errstate(invalid="ignore", divide="ignore"):
            ex = np.where(rho > 0, dx / rho, 0.0)
            ey = np.where(rho > 0, dy / rho, 0.0)
        return np.stack([np.sin(th) * ex, np.sin(th) * ey, np.cos(th)], axis=-1)

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        return (0.0, self.size_x, 0.0, self.size_y)


def tessellate_heightfield(height, x_range, y_range, nx: int, ny: int, closed: bool = False,
                           base_z: float | None = None, name: str = "heightfield") -> TriMesh:
    """Triangulate z = height(x, y) on an (nx+1) x (ny+1) grid of vertices (2 nx ny facets).

    ``closed=True`` adds four vertical walls and a bottom at ``base_z`` (default min z - 5 mm).

    >>> m = tessellate_heightfield(lambda x, y: 0 * x, (0, 1), (0, 1), 2, 3)
    >>> m.n_facets, bool((m.normals[:, 2] == 1).all())
    (12, True)
    """
    if int(nx) < 1 or int(ny) < 1:
        raise ValueError(f"nx and ny must be >= 1, got {nx}, {ny}")
    xs = np.linspace(*x_range, int(nx) + 1)
    ys = np.linspace(*y_range, int(ny) + 1)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    Z = np.asarray(height(X, Y), float)
    if not np.isfinite(Z).all():
        raise ValueError("height returned non-finite values")
    P = np.stack([X, Y, Z], axis=-1)
    a, b, c, d = P[:-1, :-1], P[1:, :-1], P[1:, 1:], P[:-1, 1:]
    tri = np.concatenate([np.stack([a, b, c], axis=-2).reshape(-1, 3, 3),
                          np.stack([a, c, d], axis=-2).reshape(-1, 3, 3)])
    if closed:
        zb = float(Z.min() - 5.0) if base_z is None else float(base_z)
        walls = []
        for edge in (P[:, 0], P[-1, :], P[::-1, -1], P[0, ::-1]):  # counter-clockwise boundary
            top0, top1 = edge[:-1], edge[1:]
            bot0, bot1 = top0.copy(), top1.copy()
            bot0[:, 2] = zb
            bot1[:, 2] = zb
            walls.append(np.stack([bot0, bot1, top1], axis=1))
            walls.append(np.stack([bot0, top1, top0], axis=1))
        x0, x1 = x_range
        y0, y1 = y_range
        q = np.array([[x0, y0, zb], [x1, y0, zb], [x1, y1, zb], [x0, y1, zb]])
        walls.append(np.array([[q[0], q[2], q[1]], [q[0], q[3], q[2]]]))
        tri = np.concatenate([tri] + walls)
    return TriMesh.from_triangles(tri, name=name, degenerate="drop")


def freeform_part_mesh(part: FreeformPart | None = None, cell_mm: float = 0.5, closed: bool = False) -> TriMesh:
    """STL-ready mesh of the chapter 8 test part with grid cell ``cell_mm`` (mm)."""
    part = part or FreeformPart()
    if not cell_mm > 0:
        raise ValueError(f"cell_mm must be > 0 mm, got {cell_mm}")
    x0, x1, y0, y1 = part.bounds
    nx = max(1, int(np.ceil((x1 - x0) / cell_mm)))
    ny = max(1, int(np.ceil((y1 - y0) / cell_mm)))
    return tessellate_heightfield(part.height_at, (x0, x1), (y0, y1), nx, ny, closed=closed,
                                  name="mgherony2024_ch8_test_part")


def cylinder_part_mesh(kind: str, cell_mm: float = 0.5, **kwargs) -> TriMesh:
    """Tessellate a chapter 4 CV/CX part (:class:`cnclab.geometry.cylinder_parts.CylinderPart`, mm).

    x in [0, length_x], y in [-y_extent, y_extent], z = the part's section z(y); extra keyword
    arguments go to ``CylinderPart``.

    >>> m = cylinder_part_mesh("CX", cell_mm=5.0)
    >>> bool((m.normals[:, 2] > 0).all())
    True
    """
    if not cell_mm > 0:
        raise ValueError(f"cell_mm must be > 0 mm, got {cell_mm}")
    part = CylinderPart(kind, **kwargs)
    ye = part.y_extent
    nx = max(1, int(np.ceil(part.length_x / cell_mm)))
    ny = max(1, int(np.ceil(2 * ye / cell_mm)))
    return tessellate_heightfield(lambda x, y: part.z(np.clip(y, -ye, ye)), (0.0, part.length_x), (-ye, ye),
                                  nx, ny, name=f"mgherony2024_ch4_{kind}")
