"""Parametric planar contours c(t) with derivative c'(t) (mm), for constant-engagement paths.

Every contour has ``t_min``, ``t_max``, ``point(t)`` and ``deriv(t)`` (vectorised: t of shape (n,)
gives (n, 2)), ``closed`` and ``length``. Orientation convention (Jacsó 2021, Thesis II as printed):
the material to be cut lies on the **right** of the direction of travel c'(t). So a pocket wall
grown outward (concave contour, material outside) is traversed counter-clockwise, a boss (convex,
material inside) clockwise. ``Reversed(c)`` flips a contour.

>>> import numpy as np
>>> a = Arc((0, 0), 5.0, start_deg=0, sweep_deg=90)
>>> np.round(a.point(np.array([a.t_max])), 12).tolist()
[[0.0, 5.0]]
"""
from __future__ import annotations

import math

import numpy as np


class Contour:
    """Base class: subclasses set t_min, t_max, closed and implement point/deriv."""

    t_min: float = 0.0
    t_max: float = 1.0
    closed: bool = False

    def point(self, t):  # pragma: no cover
        raise NotImplementedError

    def deriv(self, t):  # pragma: no cover
        raise NotImplementedError

    def sample(self, n: int = 400) -> np.ndarray:
        """(n, 2) points at uniform parameter values."""
        return self.point(np.linspace(self.t_min, self.t_max, int(n)))

    @property
    def length(self) -> float:
        """Arc length (mm), by Gauss-Legendre quadrature on 64 panels."""
        x, w = np.polynomial.legendre.leggauss(8)
        edges = np.linspace(self.t_min, self.t_max, 65)
        a, b = edges[:-1, None], edges[1:, None]
        t = (0.5 * (b - a) * x + 0.5 * (a + b)).ravel()
        d = self.deriv(t)
        sp = np.hypot(d[:, 0], d[:, 1]).reshape(64, 8)
        return float(np.sum(sp * w * 0.5 * (b - a)))

    def curvature(self, t):
        """Signed curvature (1/mm), positive when turning left (counter-clockwise)."""
        t = np.atleast_1d(np.asarray(t, float))
        h = 1e-5 * max(self.t_max - self.t_min, 1.0)
        d = self.deriv(t)
        dd = (self.deriv(t + h) - self.deriv(t - h)) / (2 * h)
        return (d[:, 0] * dd[:, 1] - d[:, 1] * dd[:, 0]) / np.hypot(d[:, 0], d[:, 1]) ** 3

    def polygon_coords(self, n: int = 2000) -> np.ndarray:
        return self.sample(n)


def _t(t):
    return np.atleast_1d(np.asarray(t, float))


class Line(Contour):
    """Segment from p0 to p1, parametrised by arc length t in [0, L] (mm)."""

    def __init__(self, p0, p1):
        self.p0 = np.asarray(p0, float)
        self.p1 = np.asarray(p1, float)
        L = float(np.hypot(*(self.p1 - self.p0)))
        if L <= 0:
            raise ValueError("Line: p0 and p1 must differ")
        self.u = (self.p1 - self.p0) / L
        self.t_max = L

    def point(self, t):
        return self.p0 + _t(t)[:, None] * self.u

    def deriv(self, t):
        return np.broadcast_to(self.u, (_t(t).size, 2)).copy()


class Arc(Contour):
    """Circular arc, centre, radius (mm), start angle and signed sweep (deg, + = ccw); t = arc length."""

    def __init__(self, center, radius, start_deg=0.0, sweep_deg=360.0):
        if not radius > 0:
            raise ValueError(f"radius must be > 0 mm, got {radius!r}")
        if sweep_deg == 0:
            raise ValueError("sweep_deg must be non-zero")
        self.c = np.asarray(center, float)
        self.radius = float(radius)
        self.a0 = math.radians(start_deg)
        self.sign = 1.0 if sweep_deg > 0 else -1.0
        self.t_max = abs(math.radians(sweep_deg)) * self.radius
        self.closed = abs(abs(sweep_deg) - 360.0) < 1e-12

    def angle(self, t):
        return self.a0 + self.sign * _t(t) / self.radius

    def point(self, t):
        a = self.angle(t)
        return self.c + self.radius * np.c_[np.cos(a), np.sin(a)]

    def deriv(self, t):
        a = self.angle(t)
        return self.sign * np.c_[-np.sin(a), np.cos(a)]


class Ellipse(Contour):
    """Ellipse with semi-axes a (x) and b (y), mm; t = polar parameter in [0, 2 pi] (ccw, or cw if ``cw``)."""

    def __init__(self, center, a, b, cw: bool = False, turns: float = 1.0):
        if not (a > 0 and b > 0):
            raise ValueError(f"semi-axes a, b must be > 0 mm, got {a!r}, {b!r}")
        self.c = np.asarray(center, float)
        self.a, self.b = float(a), float(b)
        self.sign = -1.0 if cw else 1.0
        self.t_max = 2 * math.pi * turns
        self.closed = turns == 1.0

    def point(self, t):
        t = self.sign * _t(t)
        return self.c + np.c_[self.a * np.cos(t), self.b * np.sin(t)]

    def deriv(self, t):
        t = self.sign * _t(t)
        return self.sign * np.c_[-self.a * np.sin(t), self.b * np.cos(t)]


class Blob(Contour):
    """Smooth star-shaped closed curve r(phi) = R0 (1 + sum a_k cos(k phi + phi_k)), phi = t in [0, 2 pi] (ccw)."""

    def __init__(self, center, R0, amplitudes=(0.0, 0.12, 0.06), phases=(0.0, 0.5, 1.3), cw=False):
        self.c = np.asarray(center, float)
        self.R0 = float(R0)
        self.amp = np.asarray(amplitudes, float)
        self.ph = np.asarray(phases, float)
        self.k = np.arange(1, self.amp.size + 1)
        if np.sum(np.abs(self.amp)) >= 1:
            raise ValueError("sum of |amplitudes| must be < 1 for a star-shaped curve")
        self.sign = -1.0 if cw else 1.0
        self.t_max = 2 * math.pi
        self.closed = True

    def _r(self, phi):
        arg = self.k[None, :] * phi[:, None] + self.ph[None, :]
        r = self.R0 * (1 + np.sum(self.amp * np.cos(arg), axis=1))
        dr = -self.R0 * np.sum(self.amp * self.k * np.sin(arg), axis=1)
        return r, dr

    def point(self, t):
        phi = self.sign * _t(t)
        r, _ = self._r(phi)
        return self.c + np.c_[r * np.cos(phi), r * np.sin(phi)]

    def deriv(self, t):
        phi = self.sign * _t(t)
        r, dr = self._r(phi)
        return self.sign * np.c_[dr * np.cos(phi) - r * np.sin(phi), dr * np.sin(phi) + r * np.cos(phi)]


class SplineContour(Contour):
    """Cubic spline through points (mm), chord-length parameter t (mm); periodic if ``closed``."""

    def __init__(self, points, closed: bool = False):
        from scipy.interpolate import CubicSpline

        P = np.asarray(points, float)
        if P.ndim != 2 or P.shape[1] != 2 or len(P) < 4:
            raise ValueError(f"points must be (n >= 4, 2), got shape {P.shape}")
        if closed and not np.allclose(P[0], P[-1]):
            P = np.vstack([P, P[:1]])
        seg = np.hypot(*np.diff(P, axis=0).T)
        if np.any(seg <= 0):
            raise ValueError("points must not repeat consecutively")
        u = np.r_[0.0, np.cumsum(seg)]
        self.spline = CubicSpline(u, P, bc_type="periodic" if closed else "not-a-knot")
        self.closed = closed
        self.t_max = float(u[-1])

    def point(self, t):
        return self.spline(_t(t))

    def deriv(self, t):
        return self.spline(_t(t), 1)


class RoundedPolygon(Contour):
    """Closed polygon (vertices ccw, mm) with every corner rounded by ``corner_radius``; t = arc length.

    Traversed counter-clockwise (``cw=True`` reverses). Corners must fit (radius small enough).
    """

    def __init__(self, vertices, corner_radius: float, cw: bool = False):
        V = np.asarray(vertices, float)
        n = len(V)
        if n < 3 or not corner_radius > 0:
            raise ValueError("need >= 3 vertices and corner_radius > 0 mm")
        area2 = np.sum(V[:, 0] * np.roll(V[:, 1], -1) - np.roll(V[:, 0], -1) * V[:, 1])
        if area2 < 0:
            V = V[::-1]
        segs = []  # ("L", p0, p1) or ("A", center, radius, a0, sweep)
        pts = []
        for i in range(n):
            a, b, c = V[i - 1], V[i], V[(i + 1) % n]
            u1 = (b - a) / np.hypot(*(b - a))
            u2 = (c - b) / np.hypot(*(c - b))
            turn = math.atan2(u1[0] * u2[1] - u1[1] * u2[0], u1 @ u2)
            if turn <= 0:
                raise ValueError("RoundedPolygon needs a convex polygon (all left turns)")
            dcut = corner_radius * math.tan(turn / 2)
            if dcut > 0.5 * min(np.hypot(*(b - a)), np.hypot(*(c - b))):
                raise ValueError(f"corner_radius {corner_radius} mm too large for vertex {i}")
            q1 = b - u1 * dcut
            q2 = b + u2 * dcut
            centre = q1 + corner_radius * np.array([-u1[1], u1[0]])
            pts.append((q1, q2, centre, turn))
        for i in range(n):
            q1, q2, centre, turn = pts[i]
            a0 = math.atan2(q1[1] - centre[1], q1[0] - centre[0])
            segs.append(Arc(centre, corner_radius, math.degrees(a0), math.degrees(turn)))
            nq1 = pts[(i + 1) % n][0]
            segs.append(Line(q2, nq1))
        self.segs = segs
        lens = np.array([s.t_max for s in segs])
        self.cum = np.r_[0.0, np.cumsum(lens)]
        self.t_max = float(self.cum[-1])
        self.closed = True
        self.cw = cw

    def _eval(self, t, what):
        t = _t(t)
        if self.cw:
            t = self.t_max - t
        t = np.mod(t, self.t_max) if self.closed else t
        k = np.clip(np.searchsorted(self.cum, t, side="right") - 1, 0, len(self.segs) - 1)
        out = np.empty((t.size, 2))
        for j in np.unique(k):
            m = k == j
            s = self.segs[j]
            out[m] = getattr(s, what)(t[m] - self.cum[j])
        if what == "deriv" and self.cw:
            out = -out
        return out

    def point(self, t):
        return self._eval(t, "point")

    def deriv(self, t):
        return self._eval(t, "deriv")


class Reversed(Contour):
    """The contour traversed backwards (flips the material side)."""

    def __init__(self, contour: Contour):
        self.base = contour
        self.t_min, self.t_max, self.closed = contour.t_min, contour.t_max, contour.closed

    def point(self, t):
        return self.base.point(self.t_min + self.t_max - _t(t))

    def deriv(self, t):
        return -self.base.deriv(self.t_min + self.t_max - _t(t))
