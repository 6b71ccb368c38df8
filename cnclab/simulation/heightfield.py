"""Ball-end height-field (z-map) simulation for 3-axis finishing of a plane.

The stock is a regular XY grid of cell-centre heights ``z`` [mm]. A ball-end mill of radius ``R`` [mm]
is positioned by its **tip** (lowest point of the ball, the cutter-contact point on a horizontal
plane); its lower hemisphere at horizontal distance ``d`` from the axis reaches
``z_tip + R − sqrt(R² − d²)``. A straight sweep at constant height lowers the field to the swept
envelope exactly (``d`` = distance to the segment); sloped segments are sampled.

>>> hf = HeightField.box((0, 10), (0, 10), resolution=0.05, z_top=1.0)
>>> hf.cut_ball_segment((-5, 5.025, 0), (15, 5.025, 0), radius=2.0)   # y = centre of row 100
>>> round(float(hf.z[100, 100]), 6)   # on the pass centre line the surface is at the tip height
0.0
"""
from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["HeightField"]


@dataclasses.dataclass
class HeightField:
    """Heights ``z`` [mm], shape (ny, nx), at cell centres ``x0 + (i+½)h``, ``y0 + (j+½)h``."""

    x0: float
    y0: float
    resolution: float
    z: np.ndarray

    @classmethod
    def box(cls, x_range, y_range, resolution: float, z_top: float) -> "HeightField":
        """Flat stock over ``x_range × y_range`` [mm] at height ``z_top`` [mm], cells ``resolution`` mm."""
        if not resolution > 0:
            raise ValueError(f"resolution must be > 0 mm, got {resolution}")
        (xa, xb), (ya, yb) = x_range, y_range
        if not (xb > xa and yb > ya):
            raise ValueError(f"x_range and y_range must be increasing, got {x_range}, {y_range}")
        nx = int(round((xb - xa) / resolution))
        ny = int(round((yb - ya) / resolution))
        return cls(float(xa), float(ya), float(resolution), np.full((ny, nx), float(z_top)))

    @property
    def xc(self) -> np.ndarray:
        return self.x0 + (np.arange(self.z.shape[1]) + 0.5) * self.resolution

    @property
    def yc(self) -> np.ndarray:
        return self.y0 + (np.arange(self.z.shape[0]) + 0.5) * self.resolution

    def _ball(self, d2: np.ndarray, z_tip, radius: float) -> np.ndarray:
        out = np.full(d2.shape, np.inf)
        inside = d2 <= radius ** 2
        zt = np.broadcast_to(z_tip, d2.shape)
        out[inside] = zt[inside] + radius - np.sqrt(radius ** 2 - d2[inside])
        return out

    def cut_ball_point(self, tip, radius: float) -> None:
        """Plunge the ball with its tip at ``tip`` (x, y, z) [mm]."""
        if not radius > 0:
            raise ValueError(f"radius must be > 0 mm, got {radius}")
        X, Y = np.meshgrid(self.xc, self.yc)
        d2 = (X - tip[0]) ** 2 + (Y - tip[1]) ** 2
        np.minimum(self.z, self._ball(d2, float(tip[2]), radius), out=self.z)

    def cut_ball_segment(self, tip0, tip1, radius: float, sample: float | None = None) -> None:
        """Sweep the ball tip from ``tip0`` to ``tip1`` [mm]; exact for constant z, else sampled
        every ``sample`` mm (default ``resolution/2``)."""
        if not radius > 0:
            raise ValueError(f"radius must be > 0 mm, got {radius}")
        p0, p1 = np.asarray(tip0, float), np.asarray(tip1, float)
        if abs(p1[2] - p0[2]) > 1e-12:
            step = sample or self.resolution / 2
            n = max(2, int(np.ceil(np.linalg.norm(p1 - p0) / step)) + 1)
            for t in np.linspace(0, 1, n):
                self.cut_ball_point(p0 + t * (p1 - p0), radius)
            return
        X, Y = np.meshgrid(self.xc, self.yc)
        d = p1[:2] - p0[:2]
        L2 = float(d @ d)
        t = np.zeros_like(X) if L2 == 0 else np.clip(((X - p0[0]) * d[0] + (Y - p0[1]) * d[1]) / L2, 0, 1)
        d2 = (X - p0[0] - t * d[0]) ** 2 + (Y - p0[1] - t * d[1]) ** 2
        np.minimum(self.z, self._ball(d2, p0[2], radius), out=self.z)

    def volume_above(self, z_ref: float, x_range=None, y_range=None) -> float:
        """Material volume [mm³] above ``z_ref`` inside the given window (cell centres inside)."""
        mask_x = np.ones(self.z.shape[1], bool) if x_range is None else \
            (self.xc >= x_range[0]) & (self.xc < x_range[1])
        mask_y = np.ones(self.z.shape[0], bool) if y_range is None else \
            (self.yc >= y_range[0]) & (self.yc < y_range[1])
        sub = self.z[np.ix_(mask_y, mask_x)]
        return float(np.clip(sub - z_ref, 0, None).sum() * self.resolution ** 2)

    def max_above(self, z_ref: float, x_range=None, y_range=None) -> float:
        """Largest residual height [mm] above ``z_ref`` inside the window."""
        mx = (self.xc >= x_range[0]) & (self.xc < x_range[1]) if x_range is not None else slice(None)
        my = (self.yc >= y_range[0]) & (self.yc < y_range[1]) if y_range is not None else slice(None)
        return float((self.z[my][:, mx] - z_ref).max())
