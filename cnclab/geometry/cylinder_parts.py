"""The CV (concave) and CX (convex) test parts of Mgherony (2024) chapter 4, as a parametric surface.

§4.2: "a cylindrical surface with a 45 mm radius connected to a horizontal plane with a 10 mm radius"
(read: a 10 mm fillet joins the cylinder to the horizontal plane). The cylinder axis is parallel to x;
the part is a prism along x whose cross-section ``z(y)`` (mm) is:

- CX (convex): cylinder crest ``z = sqrt(R² − y²) − R`` (top at ``z = 0``), a concave fillet of radius
  ``fillet_radius`` turning it back to a horizontal plane below;
- CV (concave): trough ``z = R − sqrt(R² − y²)`` (bottom at ``z = 0``), a convex fillet up to a
  horizontal plane above.

``cylinder_half_angle_deg`` (where the cylinder hands over to the fillet) and the part's extents are not
printed (Fig 4-1 is a photograph); the defaults (45°, 100 mm long in x) contain every measuring position.

Table 4-2's normal angles are those of the **ball-centre** (tool) position ``y``: the ball centre of a
``D = 10`` mm tool runs on a circle of radius ``45 + 5 = 50`` mm (CX) or ``45 − 5 = 40`` mm (CV), so
``sin(angle) = y/50`` (CX: 5.7, 11.5, 17.5, 23.6, 30°) and ``y/40`` (CV: 7.2, 14.5, 22, 30, 38.7°).
Measured on the part surface (``y/45``) the angles would be 6.4 … 33.7° — not what the table prints.

Sign of the printed angle: the tilt of the outward normal in the yz plane, positive when it leans
towards −y (Table 4-2 lists the positions from y = −25 to +25: CX starts at +30°, CV at −38.7°).

>>> cx = CylinderPart("CX")
>>> round(float(cx.normal_angle_at_tool_y_deg(-25.0)), 1)
30.0
>>> cv = CylinderPart("CV")
>>> round(float(cv.normal_angle_at_tool_y_deg(-25.0)), 1)
-38.7
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

__all__ = ["CylinderPart", "MEASURING_POSITIONS_MM"]

#: Table 4-2's measuring positions (tool y, mm), in the table's order (printed as 25 … 0 … 25).
MEASURING_POSITIONS_MM = np.array([-25.0, -20.0, -15.0, -10.0, -5.0, 0.0, 5.0, 10.0, 15.0, 20.0, 25.0])


@dataclasses.dataclass(frozen=True)
class CylinderPart:
    """Cross-section ``z(y)`` and outward normal of a CV/CX part (mm; angles in degrees where named ``_deg``).

    Parameters
    ----------
    kind : "CV" (concave) or "CX" (convex)
    radius : cylinder radius (mm), 45 in the thesis
    fillet_radius : fillet joining the cylinder to the horizontal plane (mm), 10 in the thesis
    cylinder_half_angle_deg : angular half-extent of the cylindrical part (degrees; not printed)
    length_x : extent of the prism along x (mm; not printed)

    >>> p = CylinderPart("CV")
    >>> float(p.z(0.0)), round(float(p.z(p.y_plane)), 3) == round(p.plane_z, 3)
    (0.0, True)
    """

    kind: str
    radius: float = 45.0
    fillet_radius: float = 10.0
    cylinder_half_angle_deg: float = 45.0
    length_x: float = 100.0

    def __post_init__(self):
        if self.kind not in ("CV", "CX"):
            raise ValueError(f"kind must be 'CV' or 'CX', got {self.kind!r}")
        for name in ("radius", "fillet_radius", "length_x"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a finite number > 0 mm, got {v!r}")
        if not (0 < self.cylinder_half_angle_deg < 90):
            raise ValueError(f"cylinder_half_angle_deg must be in (0, 90), got {self.cylinder_half_angle_deg!r}")

    # ---- section geometry -------------------------------------------------------------------------
    @property
    def _sign(self) -> float:
        return 1.0 if self.kind == "CV" else -1.0   # CV: axis above (z = +R); CX: axis below (z = -R)

    @property
    def y_cylinder(self) -> float:
        """|y| (mm) where the cylinder ends and the fillet starts."""
        return self.radius * math.sin(math.radians(self.cylinder_half_angle_deg))

    @property
    def _fillet_centre(self) -> tuple[float, float]:
        th = math.radians(self.cylinder_half_angle_deg)
        s = self._sign
        dist = self.radius + self.fillet_radius       # the fillet bends the other way than the cylinder
        return dist * math.sin(th), s * self.radius - s * dist * math.cos(th)

    @property
    def y_plane(self) -> float:
        """|y| (mm) where the fillet ends and the horizontal plane starts."""
        return self._fillet_centre[0]

    @property
    def plane_z(self) -> float:
        """Height (mm) of the horizontal plane (above the trough for CV, below the crest for CX)."""
        return self._fillet_centre[1] + self._sign * self.fillet_radius

    @property
    def y_extent(self) -> float:
        """Half width (mm) of the modelled section: the plane continues 10 mm past the fillet."""
        return self.y_plane + 10.0

    def z(self, y):
        """Surface height (mm) at ``y`` (mm), broadcast; ``|y| <= y_extent``."""
        y = np.asarray(y, dtype=float)
        if np.any(~np.isfinite(y)) or np.any(np.abs(y) > self.y_extent + 1e-9):
            raise ValueError(f"y must be finite with |y| <= {self.y_extent:.3f} mm")
        a = np.abs(y)
        R, rho, s = self.radius, self.fillet_radius, self._sign
        fy, fz = self._fillet_centre
        cyl = s * (R - np.sqrt(np.maximum(R * R - a * a, 0.0)))
        fil = fz + s * np.sqrt(np.maximum(rho * rho - (a - fy) ** 2, 0.0))
        return np.where(a <= self.y_cylinder, cyl, np.where(a <= fy, fil, self.plane_z))

    def normal(self, y):
        """Outward unit normal ``(0, n_y, n_z)`` of the surface at ``y`` (mm), shape ``(..., 3)``."""
        y = np.asarray(y, dtype=float)
        self.z(y)   # validates
        a = np.abs(y)
        sy = np.where(y < 0, -1.0, 1.0)
        R, rho, s = self.radius, self.fillet_radius, self._sign
        fy, _ = self._fillet_centre
        # slope angle of the section (positive = rising with |y|)
        ang_cyl = np.arcsin(np.clip(a / R, -1, 1)) * s
        ang_fil = np.arcsin(np.clip((fy - a) / rho, -1, 1)) * s
        ang = np.where(a <= self.y_cylinder, ang_cyl, np.where(a <= fy, ang_fil, 0.0))
        ny = -np.sin(ang) * sy
        nz = np.cos(ang)
        return np.stack([np.zeros_like(ny), ny, nz], -1)

    def normal_angle_at_surface_y_deg(self, y):
        """Table-4-2-style normal angle (degrees, + when leaning to −y) at surface position ``y`` (mm)."""
        n = self.normal(y)
        return np.degrees(np.arctan2(-n[..., 1], n[..., 2]))

    # ---- ball-centre (tool) positions ---------------------------------------------------------------
    def tool_path_radius(self, tool_diameter: float = 10.0) -> float:
        """Radius (mm) of the ball-centre circle over the cylindrical part: ``R ± D/2`` (CX +, CV −)."""
        if not (math.isfinite(tool_diameter) and tool_diameter > 0):
            raise ValueError(f"tool_diameter must be > 0 mm, got {tool_diameter!r}")
        return self.radius + (tool_diameter / 2 if self.kind == "CX" else -tool_diameter / 2)

    def normal_at_tool_y(self, y_tool, tool_diameter: float = 10.0):
        """Outward normal (shape ``(..., 3)``) at the contact point of a ball centred at ``y_tool`` (mm).

        Valid on the cylindrical part: ``sin(tilt) = y_tool / (R ± D/2)``.
        """
        y = np.asarray(y_tool, dtype=float)
        Rt = self.tool_path_radius(tool_diameter)
        lim = Rt * math.sin(math.radians(self.cylinder_half_angle_deg))
        if np.any(~np.isfinite(y)) or np.any(np.abs(y) > lim + 1e-9):
            raise ValueError(f"y_tool must be finite with |y_tool| <= {lim:.3f} mm (cylindrical part)")
        s = np.clip(y / Rt, -1, 1)
        ny = s if self.kind == "CX" else -s
        return np.stack([np.zeros_like(ny), ny, np.sqrt(1 - s * s)], -1)

    def contact_y(self, y_tool, tool_diameter: float = 10.0):
        """Surface ``y`` (mm) of the contact point for a ball centred at ``y_tool`` (mm)."""
        return np.asarray(y_tool, dtype=float) * self.radius / self.tool_path_radius(tool_diameter)

    def normal_angle_at_tool_y_deg(self, y_tool, tool_diameter: float = 10.0):
        """Table 4-2's normal angle (degrees, + when leaning to −y) for a ball centred at ``y_tool`` (mm)."""
        n = self.normal_at_tool_y(y_tool, tool_diameter)
        return np.degrees(np.arctan2(-n[..., 1], n[..., 2]))

    def section(self, n: int = 401):
        """``(y, z)`` arrays (mm) sampling the cross-section over ``[-y_extent, y_extent]`` (for plots/meshing)."""
        if n < 3:
            raise ValueError(f"n must be >= 3, got {n}")
        y = np.linspace(-self.y_extent, self.y_extent, n)
        return y, self.z(y)
