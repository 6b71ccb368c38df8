"""Working (effective) diameter of a ball-end mill on an inclined surface — the Mikó–Zentay model.

Closed-form, vectorised implementation of Mgherony (2024) §5.2 (eqs 5-1 … 5-6), after Mikó & Zentay.

Geometry (ball-centre coordinates, mm; tool axis = z axis)
-----------------------------------------------------------
The ball of radius ``R = D/2`` cuts a layer of depth ``a_p``. In the horizontal case the boundary of the
cut is the *intersection circle* at ``z = -(R - a_p)`` of radius ``r = sqrt(a_p (D - a_p))`` (eq 5-2).
For an inclined surface the circle is rotated by ``T_r`` of eq 5-3,
``T_r = Rz(A_N1) · Ry(-A_N2)``::

    [[cos A_N1 cos A_N2, -sin A_N1, -cos A_N1 sin A_N2],
     [sin A_N1 cos A_N2,  cos A_N1, -sin A_N1 sin A_N2],
     [sin A_N2,           0,         cos A_N2         ]]

so its centre moves to ``(R - a_p)·(cos A_N1 sin A_N2, sin A_N1 sin A_N2, -cos A_N2)``.

**Angle convention (degrees at the API, exactly eq 5-3).** ``A_N1`` is the azimuth (about z, from +x)
and ``A_N2`` the tilt (from +z) of the rotation. The outward surface normal implied by ``T_r`` is
``T_r·e_z = (-cos A_N1 sin A_N2, -sin A_N1 sin A_N2, cos A_N2)``: for ``A_N2 > 0`` the surface *rises*
towards azimuth ``A_N1`` with slope angle ``A_N2`` (the normal leans towards ``A_N1 + 180°``).
``(A_N1, A_N2)`` and ``(A_N1 + 180°, -A_N2)`` describe the same surface. To convert an outward unit
normal (e.g. an STL facet normal) use :func:`angles_from_normal`; the inverse is
:func:`normal_from_angles`.

``A_f`` is the absolute feed direction in the xy plane (degrees from +x, counter-clockwise), as in
§5.2 / Fig 5-4.

Tangent points 1 and 2 (Fig 5-3)
--------------------------------
The xy-projection of the rotated circle is an ellipse. Points 1 and 2 are the two points of the circle
whose projected tangent is parallel to the feed direction. **Point 1 is the one on the left of the feed
direction** (extreme in the direction ``m = (-sin A_f, cos A_f)``, the feed rotated +90°), **point 2
the one on the right** (extreme in ``-m``). This labelling reproduces every location the thesis prints
(Table 5-1 and §5.5: point 1 is minimal at ``A_N1 = A_f + 90°, A_N2 < 0`` and maximal at
``A_N2 = +45°``) and the §5.4 statement that point 1 at ``A_f + 180°`` equals point 2 at ``A_f``.

The *working radius* of a point is its distance from the tool axis; the *working diameter* is twice it.
The thesis's chapter 5 figures and Table 5-1 print the working **radius** labelled as a diameter (its
chapter 4 prints true diameters): :func:`paper_deff_radius_valued` reproduces that convention.

Cut points 1′, 1″, 2′, 2″ (Figs 5-4, 5-5)
-----------------------------------------
The line parallel to the tangent at point 1 (resp. 2), moved by the width of cut ``a_e`` towards the
inside of the ellipse, meets the ellipse at two points. We call **′ the one ahead of the tangent point
along the feed (leading)** and **″ the one behind (trailing)**. With the thesis's pairing, up-milling on
side 1 is the arc 1→1′, down-milling on side 1 is 1″→1, down-milling on side 2 is 2′→2 and up-milling on
side 2 is 2→2″ (side 1 up-milling is the mirror image of side 2 down-milling, so both use the leading
point). When ``a_e`` exceeds the ellipse's width across the feed the line misses the ellipse and the cut
points are NaN.

Horizontal limit: for ``A_N2 = 0`` both tangent points give the diameter ``2·sqrt(a_p (D - a_p))``
for every ``A_f`` (eq 5-1 *corrected*; as printed, eq 5-1 has ``+`` and gives 13.72 mm for D = 10,
a_p = 0.3 — see :func:`eq5_1_as_printed_diameter`).

>>> d1, d2 = tangent_point_diameters(10.0, 0.3, 0.0, 0.0, 30.0)
>>> round(float(d1), 4), round(float(d2), 4)
(3.4117, 3.4117)
>>> r1, r2 = tangent_point_radii(10.0, 1.0, 120.0, 45.0, 30.0)   # §5.5: "4.950" (a radius)
>>> round(float(r1), 3)
4.95
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = [
    "intersection_circle_radius", "horizontal_effective_diameter", "eq5_1_as_printed_diameter",
    "tangent_point_radii", "tangent_point_diameters", "paper_deff_radius_valued",
    "tangent_points_3d", "CutPointRadii", "cut_point_radii", "cut_point_diameters",
    "chip_removal_radius_variation", "rotation_matrix_Tr", "normal_from_angles",
    "angles_from_normal", "validate_model_inputs", "thesis_steps_numerical",
]


# --------------------------------------------------------------------------------------- validation
def _as_float_array(value, name: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number or an array of numbers, got {value!r}") from None
    return arr


def _check_finite(arr: np.ndarray, name: str, unit: str) -> None:
    if not np.all(np.isfinite(arr)):
        bad = arr[~np.isfinite(arr)].ravel()[0] if arr.ndim else arr
        raise ValueError(f"{name} must be finite ({unit}), got {bad}")


def validate_model_inputs(D, a_p, A_N1=0.0, A_N2=0.0, A_f=0.0, a_e=None):
    """Check the model's inputs; return them as float arrays (unchanged values).

    Raises ``ValueError`` naming the parameter: ``D > 0`` mm, ``0 < a_p <= D/2`` mm, ``a_e >= 0`` mm,
    finite angles in degrees with ``|A_N2| <= 90``.

    >>> validate_model_inputs(10, 0.3)[0]
    array(10.)
    >>> validate_model_inputs(10, 6)
    Traceback (most recent call last):
    ...
    ValueError: a_p must be in (0, D/2] mm, got 6.0 (D/2 = 5.0)
    """
    D = _as_float_array(D, "D")
    a_p = _as_float_array(a_p, "a_p")
    _check_finite(D, "D", "mm")
    if np.any(D <= 0):
        raise ValueError(f"D must be > 0 mm (tool diameter), got {D[D <= 0].ravel()[0] if D.ndim else D}")
    _check_finite(a_p, "a_p", "mm")
    Db, ab = np.broadcast_arrays(D, a_p)
    bad = (ab <= 0) | (ab > Db / 2 * (1 + 1e-12))
    if np.any(bad):
        i = np.argmax(bad.ravel())
        raise ValueError(f"a_p must be in (0, D/2] mm, got {ab.ravel()[i]} (D/2 = {Db.ravel()[i] / 2})")
    out = [D, a_p]
    for name, val in (("A_N1", A_N1), ("A_N2", A_N2), ("A_f", A_f)):
        arr = _as_float_array(val, name)
        _check_finite(arr, name, "degrees")
        out.append(arr)
    if np.any(np.abs(out[3]) > 90):
        raise ValueError(f"A_N2 must be in [-90, 90] degrees (tilt of the surface normal), "
                         f"got {out[3][np.abs(out[3]) > 90].ravel()[0] if out[3].ndim else out[3]}")
    if a_e is not None:
        ae = _as_float_array(a_e, "a_e")
        _check_finite(ae, "a_e", "mm")
        if np.any(ae < 0):
            raise ValueError(f"a_e must be >= 0 mm (width of cut), got {ae[ae < 0].ravel()[0] if ae.ndim else ae}")
        out.append(ae)
    names = ("D", "a_p", "A_N1", "A_N2", "A_f", "a_e")
    try:
        np.broadcast_shapes(*(o.shape for o in out))
    except ValueError:
        shapes = ", ".join(f"{n} {o.shape}" for n, o in zip(names, out))
        raise ValueError(f"D, a_p, A_N1, A_N2, A_f{', a_e' if a_e is not None else ''} must have broadcastable "
                         f"shapes (scalars or arrays of one shape), got {shapes}") from None
    return tuple(out)


# ------------------------------------------------------------------------------- horizontal case
def intersection_circle_radius(D, a_p):
    """Radius (mm) of the circle where a horizontal plane ``a_p`` above the ball's tip cuts the ball.

    ``sqrt(R² - (R - a_p)²) = sqrt(a_p·(D - a_p))``, with ``D`` the tool diameter (mm).

    >>> float(intersection_circle_radius(10, 1))
    3.0
    """
    D, a_p = validate_model_inputs(D, a_p)[:2]
    return np.sqrt(a_p * (D - a_p))


def horizontal_effective_diameter(D, a_p):
    """Effective **diameter** (mm) on a horizontal surface: ``2·sqrt(a_p·(D − a_p))`` (eq 5-1 corrected).

    >>> round(float(horizontal_effective_diameter(10, 0.3)), 4)
    3.4117
    """
    return 2.0 * intersection_circle_radius(D, a_p)


def eq5_1_as_printed_diameter(D, a_p):
    """Eq 5-1 *as printed*: ``2·sqrt((D/2)² + (D/2 − a_p)²)`` (mm) — an erratum ('+' for '−').

    It exceeds the tool diameter for every ``0 < a_p < D/2`` (13.72 mm for D = 10, a_p = 0.3).

    >>> round(float(eq5_1_as_printed_diameter(10, 0.3)), 2)
    13.72
    """
    D, a_p = validate_model_inputs(D, a_p)[:2]
    return 2.0 * np.sqrt((D / 2) ** 2 + (D / 2 - a_p) ** 2)


# ------------------------------------------------------------------------------ rotation, normals
def rotation_matrix_Tr(A_N1, A_N2):
    """The 3×3 rotation ``T_r`` of eq 5-3 (angles in degrees; broadcast, shape ``(..., 3, 3)``).

    >>> np.allclose(rotation_matrix_Tr(0, 0), np.eye(3))
    True
    """
    a = np.radians(np.asarray(A_N1, float))
    b = np.radians(np.asarray(A_N2, float))
    a, b = np.broadcast_arrays(a, b)
    ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
    z = np.zeros_like(a)
    return np.stack([np.stack([ca * cb, -sa, -ca * sb], -1),
                     np.stack([sa * cb, ca, -sa * sb], -1),
                     np.stack([sb, z, cb], -1)], -2)


def normal_from_angles(A_N1, A_N2):
    """Outward unit surface normal implied by eq 5-3's angles (degrees): ``T_r·e_z``.

    ``(-cos A_N1 sin A_N2, -sin A_N1 sin A_N2, cos A_N2)``, shape ``(..., 3)``.

    >>> np.round(normal_from_angles(0, 30), 4).tolist()
    [-0.5, -0.0, 0.866]
    """
    a = np.radians(np.asarray(A_N1, float))
    b = np.radians(np.asarray(A_N2, float))
    a, b = np.broadcast_arrays(a, b)
    return np.stack([-np.cos(a) * np.sin(b), -np.sin(a) * np.sin(b), np.cos(b)], -1)


def angles_from_normal(normal):
    """Eq 5-3 angles ``(A_N1, A_N2)`` in degrees of an outward surface normal (any length, ``n_z >= 0``).

    Returns ``A_N1 = atan2(-n_y, -n_x)`` in ``[0, 360)`` (the uphill azimuth) and ``A_N2 = arccos(n_z/|n|)``
    in ``[0, 90]``, so that ``normal_from_angles(*angles_from_normal(n))`` is ``n/|n|``. For a horizontal
    surface ``A_N1 = 0``. (Note: ch 7's eq 7-1 ``A_N1 = arctg(N_y/N_x)`` loses the quadrant.)

    >>> [round(float(v), 6) for v in angles_from_normal([-0.5, 0.0, 0.8660254])]
    [0.0, 30.0]
    """
    n = np.asarray(normal, dtype=float)
    if n.shape[-1:] != (3,):
        raise ValueError(f"normal must have shape (..., 3), got {n.shape}")
    _check_finite(n, "normal", "-")
    norm = np.linalg.norm(n, axis=-1)
    if np.any(norm == 0):
        raise ValueError("normal must be non-zero")
    if np.any(n[..., 2] < -1e-12 * norm):
        raise ValueError("normal must point upwards (n_z >= 0): a 3-axis ball-end mill cannot reach "
                         "a downward-facing surface")
    u = n / norm[..., None]
    tilt = np.degrees(np.arccos(np.clip(u[..., 2], -1.0, 1.0)))
    horiz = np.hypot(u[..., 0], u[..., 1]) < 1e-15
    az = np.where(horiz, 0.0, np.degrees(np.arctan2(-u[..., 1], -u[..., 0])) % 360.0)
    return az, tilt


# ------------------------------------------------------------------------------- tangent points
def _frame(D, a_p, A_N1, A_N2, A_f):
    """Shared closed-form pieces: h, r, cos/sin of tilt, delta = A_N1 - A_f, |g| and tangent params."""
    R = D / 2.0
    h = R - a_p
    r = np.sqrt(a_p * (D - a_p))
    b = np.radians(A_N2)
    d = np.radians(A_N1 - A_f)
    cb, sb = np.cos(b), np.sin(b)
    sd, cd = np.sin(d), np.cos(d)
    # support direction m = feed rotated +90°; in the circle's own (t) coordinates it is g = (cb sd, cd)
    gx, gy = cb * sd, cd
    g = np.hypot(gx, gy)
    safe = g > 1e-300
    gs = np.where(safe, g, 1.0)
    cos_t1 = np.where(safe, gx / gs, 1.0)   # degenerate (vertical wall, feed along tilt): any t; take 0
    sin_t1 = np.where(safe, gy / gs, 0.0)
    return h, r, cb, sb, cos_t1, sin_t1, g


def _radius_at(h, r, cb, sb, cos_t, sin_t):
    """Distance (mm) from the tool axis of the circle point with parameter t (local frame)."""
    u = h * sb + r * cb * cos_t      # along the tilt azimuth e_a = (cos A_N1, sin A_N1)
    v = r * sin_t                    # along e_perp = (-sin A_N1, cos A_N1)
    return np.hypot(u, v)


def tangent_point_radii(D, a_p, A_N1, A_N2, A_f):
    """Distances (mm) of tangent points 1 and 2 from the tool axis — the working **radii**.

    Parameters: ``D`` tool diameter (mm), ``a_p`` depth of cut (mm, ``0 < a_p <= D/2``), ``A_N1``,
    ``A_N2`` surface angles of eq 5-3 (degrees), ``A_f`` absolute feed direction (degrees). All
    broadcast. Point 1 lies left of the feed, point 2 right (see module docstring).

    Returns ``(r1, r2)`` float arrays in ``[0, D/2]``.

    >>> [round(float(v), 4) for v in tangent_point_radii(10, 0.3, 120, -20, 30)]
    [0.0045, 3.2105]
    """
    args = validate_model_inputs(D, a_p, A_N1, A_N2, A_f)
    shape = np.broadcast_shapes(*(a.shape for a in args))
    size = int(np.prod(shape))
    if size <= _CHUNK:
        return _tangent_radii_kernel(*args)
    # large inputs: evaluate in cache-sized blocks (a loop over blocks, not over points)
    flat = [np.broadcast_to(a, shape).reshape(-1) if a.ndim else a for a in args]
    r1, r2 = np.empty(size), np.empty(size)
    for s in range(0, size, _CHUNK):
        sl = slice(s, s + _CHUNK)
        r1[sl], r2[sl] = _tangent_radii_kernel(*(a[sl] if a.ndim else a for a in flat))
    return r1.reshape(shape), r2.reshape(shape)


_CHUNK = 4096


def _tangent_radii_kernel(D, a_p, A_N1, A_N2, A_f):
    """Hot path of :func:`tangent_point_radii` (validated inputs): few temporaries, in-place ops.

    In the tilt frame (e_a = (cos A_N1, sin A_N1), e_perp) point 1 is
    ``(h sin b + r cos b cos t1, r sin t1)`` with ``(cos t1, sin t1) = (cos b sin d, cos d)/g``,
    ``d = A_N1 − A_f``, ``g = |(cos b sin d, cos d)|``; point 2 is the opposite ``t1 + π``.
    """
    b = np.radians(A_N2)
    d = np.radians(A_N1 - A_f)
    cb, sb = np.cos(b), np.sin(b)
    sd, cd = np.sin(d), np.cos(d)
    r = np.sqrt(a_p * (D - a_p))
    u0 = D * 0.5
    u0 -= a_p
    u0 *= sb                                   # h sin b: centre offset along e_a
    gx = cb * sd
    g = np.hypot(gx, cd)
    k = np.divide(r, g, out=np.zeros(np.broadcast(r, g).shape), where=g > 0)  # degenerate: centre
    wu = k * cb
    wu *= gx                                   # r cos b cos t1
    k *= cd                                    # r sin t1
    return np.hypot(u0 + wu, k), np.hypot(u0 - wu, k)


def tangent_point_diameters(D, a_p, A_N1, A_N2, A_f):
    """True working **diameters** (mm) at tangent points 1 and 2: twice their distance from the tool axis.

    Contract used across cnclab: ``D`` tool diameter (mm), ``a_p`` depth of cut (mm), ``A_N1``/``A_N2``
    surface-normal azimuth/tilt in **degrees** exactly as in eq 5-3 (see :func:`angles_from_normal` to
    convert an outward normal), ``A_f`` absolute feed direction in the xy plane in **degrees**. Inputs
    broadcast (numpy). Returns ``(d1, d2)``: point 1 is the tangent point *left* of the feed direction,
    point 2 the one on the *right*. On a horizontal surface (``A_N2 = 0``) both equal
    ``2·sqrt(a_p·(D − a_p))`` for every ``A_f``.

    >>> d1, d2 = tangent_point_diameters(10, 1.0, 120, 45, 30)
    >>> round(float(d1), 3), round(float(d2), 3)
    (9.899, 1.414)
    """
    r1, r2 = tangent_point_radii(D, a_p, A_N1, A_N2, A_f)
    return 2.0 * r1, 2.0 * r2


def paper_deff_radius_valued(D, a_p, A_N1, A_N2, A_f):
    """The thesis's chapter-5 "D_eff" (mm): the tangent points' distance from the axis, i.e. a **radius**.

    Mgherony's Table 5-1, §5.3–5.5 and Figs 5-6 … 5-13 print this radius labelled as a diameter
    (``max = 4.530 < R = 5`` for D = 10, a_p = 0.3). Identical to :func:`tangent_point_radii`; kept
    under this name so that "paper convention" values are recognisable at the call site.

    >>> round(float(paper_deff_radius_valued(10, 0.3, 120, 45, 30)[0]), 3)
    4.53
    """
    return tangent_point_radii(D, a_p, A_N1, A_N2, A_f)


def _to_world(h, r, cb, sb, A_N1, cos_t, sin_t):
    a = np.radians(A_N1)
    ca, sa = np.cos(a), np.sin(a)
    u = h * sb + r * cb * cos_t
    v = r * sin_t
    z = -h * cb + r * sb * cos_t
    return np.stack(np.broadcast_arrays(u * ca - v * sa, u * sa + v * ca, z), -1)


def tangent_points_3d(D, a_p, A_N1, A_N2, A_f):
    """Tangent points 1 and 2 as xyz (mm) in ball-centre coordinates, arrays of shape ``(..., 3)``.

    >>> p1, p2 = tangent_points_3d(10, 1.0, 0, 0, 0)
    >>> np.round(p1, 6).tolist(), np.round(p2, 6).tolist()
    ([0.0, 3.0, -4.0], [0.0, -3.0, -4.0])
    """
    D, a_p, A_N1, A_N2, A_f = validate_model_inputs(D, a_p, A_N1, A_N2, A_f)
    h, r, cb, sb, c1, s1, _ = _frame(D, a_p, A_N1, A_N2, A_f)
    return _to_world(h, r, cb, sb, A_N1, c1, s1), _to_world(h, r, cb, sb, A_N1, -c1, -s1)


# ---------------------------------------------------------------------------------- cut points
class CutPointRadii(NamedTuple):
    """Distances (mm) from the tool axis of the tangent and cut points (NaN where the a_e line misses).

    ``p1``/``p2`` tangent points; ``p1_lead``/``p2_lead`` the thesis's 1′/2′ (ahead along the feed);
    ``p1_trail``/``p2_trail`` the thesis's 1″/2″ (behind).
    """

    p1: np.ndarray
    p1_lead: np.ndarray
    p1_trail: np.ndarray
    p2: np.ndarray
    p2_lead: np.ndarray
    p2_trail: np.ndarray

    def scaled(self, k: float) -> "CutPointRadii":
        return CutPointRadii(*(k * np.asarray(v) for v in self))


def cut_point_radii(D, a_p, a_e, A_N1, A_N2, A_f) -> CutPointRadii:
    """Working **radii** (mm) of points 1, 1′, 1″, 2, 2′, 2″ for width of cut ``a_e`` (mm).

    The line parallel to the feed through point 1 (2), moved ``a_e`` towards the ellipse's inside, meets
    the projected circle at 1′ (leading) and 1″ (trailing). Up-milling side 1: 1→1′; down-milling side 1:
    1″→1; down-milling side 2: 2′→2; up-milling side 2: 2→2″ (Fig 5-5). Angles in degrees.

    >>> c = cut_point_radii(10, 1.0, 0.0, 35, 25, 30)
    >>> bool(np.isclose(c.p1_lead, c.p1) and np.isclose(c.p1_trail, c.p1))
    True
    """
    D, a_p, A_N1, A_N2, A_f, a_e = validate_model_inputs(D, a_p, A_N1, A_N2, A_f, a_e)
    h, r, cb, sb, c1, s1, g = _frame(D, a_p, A_N1, A_N2, A_f)
    # m·p(t) = m·c + r g cos(t - t1): the a_e line is cos(t - t1) = 1 - a_e/(r g)
    rg = r * g
    with np.errstate(divide="ignore", invalid="ignore"):
        kappa = np.where(rg > 0, 1.0 - a_e / np.where(rg > 0, rg, 1.0), np.where(a_e == 0, 1.0, np.nan))
    kappa = np.where(kappa < -1.0, np.nan, kappa)     # line misses the ellipse
    phi = np.arccos(np.clip(kappa, -1.0, 1.0))
    phi = np.where(np.isnan(kappa), np.nan, phi)
    cp, sp = np.cos(phi), np.sin(phi)
    sgn = np.where(cb >= 0, 1.0, -1.0)                # leading side flips when the ellipse is mirrored
    # side 1 (t1): leading point is t1 - phi (cb > 0); side 2 (t1 + pi): leading point is t2 + phi
    def at(cos_base, sin_base, s):
        ct = cos_base * cp - s * sin_base * sp
        st = sin_base * cp + s * cos_base * sp
        return _radius_at(h, r, cb, sb, ct, st)
    return CutPointRadii(
        p1=_radius_at(h, r, cb, sb, c1, s1),
        p1_lead=at(c1, s1, -sgn), p1_trail=at(c1, s1, sgn),
        p2=_radius_at(h, r, cb, sb, -c1, -s1),
        p2_lead=at(-c1, -s1, sgn), p2_trail=at(-c1, -s1, -sgn),
    )


def cut_point_diameters(D, a_p, a_e, A_N1, A_N2, A_f) -> CutPointRadii:
    """True working **diameters** (mm) of points 1, 1′, 1″, 2, 2′, 2″: ``2 ×`` :func:`cut_point_radii`.

    >>> c = cut_point_diameters(10, 1.0, 1.0, 35, 25, 30)
    >>> round(float(c.p1), 3), round(float(c.p1_lead), 3), round(float(c.p1_trail), 3)
    (7.092, 8.522, 4.356)
    """
    return cut_point_radii(D, a_p, a_e, A_N1, A_N2, A_f).scaled(2.0)


def chip_removal_radius_variation(D, a_p, a_e, A_N1, A_N2, A_f, side: int = 1, milling: str = "up"):
    """Change (mm, signed end − start) of the working **radius** over one chip removal (Fig 5-5).

    ``side`` 1 or 2; ``milling`` "up" or "down". Up/side 1: 1→1′; down/side 1: 1″→1; down/side 2: 2′→2;
    up/side 2: 2→2″. Multiply by 2 for the diameter.

    >>> round(float(chip_removal_radius_variation(10, 1, 0.0, 35, 25, 30)), 9)
    0.0
    """
    if side not in (1, 2):
        raise ValueError(f"side must be 1 or 2, got {side!r}")
    if milling not in ("up", "down"):
        raise ValueError(f"milling must be 'up' or 'down', got {milling!r}")
    c = cut_point_radii(D, a_p, a_e, A_N1, A_N2, A_f)
    start, end = {(1, "up"): (c.p1, c.p1_lead), (1, "down"): (c.p1_trail, c.p1),
                  (2, "down"): (c.p2_lead, c.p2), (2, "up"): (c.p2, c.p2_trail)}[(side, milling)]
    return end - start


# ------------------------------------------------------------ numerical reference (thesis steps)
def thesis_steps_numerical(D: float, a_p: float, a_e: float, A_N1: float, A_N2: float, A_f: float,
                           n_rpm: float | None = None, n_scan: int = 24, xtol: float = 1e-13) -> dict:
    """One point of the thesis's pseudo-code (§5.2, steps 1–11), solved numerically (scalar, slow).

    Builds the transformed circle ``C(t) = T_r·[r cos t, r sin t, −R + a_p]`` (eq 5-4), finds the two
    tangent points where ``dC/dt`` (xy) is parallel to the feed by bracketing on ``n_scan`` samples and
    Brent's method (eq 5-5), intersects the circle with the lines at distance ``a_e`` (steps 7–8) the same
    way, and returns the working **radii** (mm) of points 1, 1′, 1″, 2, 2′, 2″ (keys ``"1"``, ``"1'"``,
    ``"1''"``, ``"2"``, ``"2'"``, ``"2''"``) and, when ``n_rpm`` is given, the true cutting speeds
    (m/min, key ``"v_c_1"``, ``"v_c_2"``) from the diameters. Reference for tests and the benchmark;
    use :func:`cut_point_radii` in practice.

    >>> res = thesis_steps_numerical(10, 1.0, 0.5, 35, 25, 30)
    >>> bool(abs(res["1"] - float(tangent_point_radii(10, 1.0, 35, 25, 30)[0])) < 1e-9)
    True
    """
    from scipy.optimize import brentq

    D, a_p, A_N1, A_N2, A_f, a_e = (float(v) for v in validate_model_inputs(D, a_p, A_N1, A_N2, A_f, a_e))
    R = D / 2.0                                                         # step 1
    r = math.sqrt(a_p * (D - a_p))                                      # step 4
    T = rotation_matrix_Tr(A_N1, A_N2)                                  # step 5
    af = math.radians(A_f)
    f = np.array([math.cos(af), math.sin(af)])
    m = np.array([-math.sin(af), math.cos(af)])

    def P(t):
        return T @ np.array([r * math.cos(t), r * math.sin(t), a_p - R])

    def dP(t):
        return T @ np.array([-r * math.sin(t), r * math.cos(t), 0.0])

    def cross(t):
        d = dP(t)
        return d[0] * f[1] - d[1] * f[0]

    ts = np.linspace(0.0, 2 * math.pi, n_scan + 1)                      # step 6
    vals = [cross(t) for t in ts]
    roots = []
    for i in range(n_scan):
        if vals[i] == 0.0:
            roots.append(ts[i])
        elif vals[i] * vals[i + 1] < 0:
            roots.append(brentq(cross, ts[i], ts[i + 1], xtol=xtol))
    if len(roots) < 2:       # degenerate (vertical wall with the feed along the tilt): fall back to extremes
        s = [m @ P(t)[:2] for t in ts]
        roots = [ts[int(np.argmax(s))], ts[int(np.argmin(s))]]
    roots.sort(key=lambda t: -(m @ P(t)[:2]))
    t1, t2 = roots[0], roots[-1]
    out = {}
    for name, t0, sgn in (("1", t1, 1.0), ("2", t2, -1.0)):
        p0 = P(t0)
        out[name] = math.hypot(p0[0], p0[1])                            # step 9
        level = sgn * (m @ p0[:2]) - a_e                                # step 7

        def g(t):
            return sgn * (m @ P(t)[:2]) - level

        pts = []
        for lo, hi in ((t0, t0 + math.pi), (t0 - math.pi, t0)):         # step 8
            if a_e == 0.0:
                pts.append(p0)
            elif g(lo) * g(hi) <= 0:
                pts.append(P(brentq(g, lo, hi, xtol=xtol)))
        if len(pts) == 2:
            pts.sort(key=lambda q: -(f @ q[:2]))
            out[name + "'"], out[name + "''"] = (math.hypot(q[0], q[1]) for q in pts)   # step 10
        else:
            out[name + "'"] = out[name + "''"] = float("nan")
    if n_rpm is not None:                                               # step 11
        out["v_c_1"] = 2 * out["1"] * float(n_rpm) * math.pi / 1000.0
        out["v_c_2"] = 2 * out["2"] * float(n_rpm) * math.pi / 1000.0
    return out
