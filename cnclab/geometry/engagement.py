"""Engagement angle vs stepover for constant-curvature cuts (Jacsó 2021 §3.1, Thesis I; Kim & Yang eq. 1).

Notation (Jacsó 2021, Fig. 3.1): r = tool radius (mm; the booklet's r_sz), s = stepover (mm; the
radial growth of the machined boundary), rho = curvature radius of the current contour (mm),
theta = engagement angle. Angles at the API are in **degrees**.

* straight line:  theta = arccos(1 - s/r)
* concave arc (tool inside the arc, e.g. a pocket wall): cosine theorem (booklet eq. 1) on the
  triangle O-P-C with |OC| = rho, |PO| = rho + s - r, |PC| = r, angle OPC = pi - theta
* convex arc (tool outside the arc, e.g. a boss): |OC| = rho, |PO| = rho - s + r, |PC| = r,
  angle OPC = theta
* Thesis I (inverse): s(theta, rho) = r (1 - cos theta) + k rho - k sqrt(rho^2 + r^2 (cos^2 theta - 1)),
  k = -1 concave, +1 convex.
* Kim & Yang (2006) eq. 1: theta_max = pi - acos((2r^2 + 2R(s - r) - s^2) / (2r(R - r))), with r the
  TOOL RADIUS (their nomenclature calls r "radial depth", which cannot be: the R -> infinity limit
  then gives 90 deg for every s) and R the radius of the machined corner (the boundary the tool
  periphery generates), i.e. R = rho + s in Jacsó's notation; then eq. 1 is Jacsó's concave case.

>>> round(float(theta_straight(1.5, 3.0)), 9)
60.0
>>> s = stepover_thesis1(60.0, 8.0, 3.0, "concave")
>>> round(float(theta_concave(s, 8.0, 3.0)), 9)
60.0
"""
from __future__ import annotations

import numpy as np

KIND_K = {"concave": -1, "convex": 1}


def _r(tool_radius):
    r = np.asarray(tool_radius, float)
    if np.any(~np.isfinite(r)) or np.any(r <= 0):
        raise ValueError(f"tool_radius must be > 0 mm, got {tool_radius!r}")
    return r


def _s(s, r):
    s = np.asarray(s, float)
    bad = ~np.isfinite(s) | (s < -1e-9) | (s > 2 * r + 1e-9)
    if np.any(bad):
        raise ValueError(f"s (stepover) must be in [0, 2r] = [0, {2 * float(np.max(r))}] mm, "
                         f"got {np.asarray(s)[bad].ravel()[:3]!r}")
    return np.clip(s, 0.0, 2 * r)


def _theta(theta_deg):
    t = np.asarray(theta_deg, float)
    if np.any(~np.isfinite(t)) or np.any(t <= 0) or np.any(t > 180):
        raise ValueError(f"theta_deg (engagement angle) must be in (0, 180] deg, got {theta_deg!r}")
    return np.radians(t)


def _rho(rho, name: str = "rho (contour curvature radius)"):
    """rho in (0, inf] mm; rho = inf is the straight-cut limit (handled in closed form, never NaN);
    ``name`` is the parameter the caller's user passed (e.g. Kim & Yang's corner radius R)."""
    try:
        p = np.asarray(rho, float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number or array in mm, got {rho!r}") from None
    if np.any(~(p > 0)):
        raise ValueError(f"{name} must be in (0, inf] mm (inf = straight cut), got {rho!r}")
    return p


def _shapes(**kw):
    """Check that the named array arguments broadcast; ValueError naming them otherwise."""
    try:
        return np.broadcast_shapes(*(np.shape(v) for v in kw.values()))
    except ValueError:
        got = ", ".join(f"{k} {np.shape(v)}" for k, v in kw.items())
        raise ValueError(f"{', '.join(kw)} must have broadcastable shapes, got {got}") from None


def _acos_checked(c, what):
    c = np.asarray(c, float)
    if np.any(np.abs(c) > 1 + 1e-12):
        raise ValueError(f"{what}: no engagement angle (|cos theta| = {np.max(np.abs(c)):.6g} > 1); "
                         "the stepover is outside the valid range for this rho")
    return np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))


def theta_straight(s, tool_radius):
    """Engagement angle (deg) of a straight cut: theta = arccos(1 - s/r) (Jacsó 2021 §3.1).

    >>> round(float(theta_straight(3.0, 3.0)), 9)
    90.0
    """
    r = _r(tool_radius)
    s = _s(s, r)
    return _acos_checked(1.0 - s / r, "theta_straight")


def theta_concave(s, rho, tool_radius):
    """Engagement angle (deg) on a concave arc: booklet eq. (1) with |PO| = rho + s - r, angle OPC = pi - theta.

    ``rho``: radius of the current (pre-cut) contour arc (mm); the tool centre runs on rho + s - r.

    >>> round(float(theta_concave(1.5, 1e9, 3.0)), 6)      # straight limit
    60.0
    """
    _shapes(s=s, rho=rho, tool_radius=tool_radius)
    r = _r(tool_radius)
    s = _s(s, r)
    p = _rho(rho)
    d = p + s - r
    if np.any(d <= 0):
        raise ValueError("rho + s - r must be > 0 (tool centre inside the arc), got "
                         f"rho={rho!r}, s={s!r}, r={tool_radius!r}")
    # rho^2 = d^2 + r^2 - 2 d r cos(pi - theta)  ->  cos(theta) = (rho^2 - d^2 - r^2) / (2 r d), with
    # rho^2 - d^2 = (r - s)(2 rho + s - r) (no cancellation, no overflow); rho = inf -> 1 - s/r
    with np.errstate(invalid="ignore"):
        c = ((r - s) * (2 * p + s - r) - r * r) / (2 * r * d)
    return _acos_checked(np.where(np.isinf(p), 1.0 - s / r, c), "theta_concave")


def theta_convex(s, rho, tool_radius):
    """Engagement angle (deg) on a convex arc: booklet eq. (1) with |PO| = rho - s + r, angle OPC = theta.

    >>> round(float(theta_convex(1.5, 1e9, 3.0)), 6)
    60.0
    """
    _shapes(s=s, rho=rho, tool_radius=tool_radius)
    r = _r(tool_radius)
    s = _s(s, r)
    p = _rho(rho)
    d = p - s + r
    if np.any(d <= 0):
        raise ValueError(f"rho - s + r must be > 0, got rho={rho!r}, s={s!r}, r={tool_radius!r}")
    # rho^2 = d^2 + r^2 - 2 d r cos(theta), with d^2 - rho^2 = (r - s)(2 rho - s + r); rho = inf -> 1 - s/r
    with np.errstate(invalid="ignore"):
        c = ((r - s) * (2 * p - s + r) + r * r) / (2 * r * d)
    return _acos_checked(np.where(np.isinf(p), 1.0 - s / r, c), "theta_convex")


def theta_arc(s, rho, tool_radius, kind: str):
    """Engagement (deg) for ``kind`` in {"concave", "convex", "straight"} (rho ignored for straight)."""
    if kind == "concave":
        return theta_concave(s, rho, tool_radius)
    if kind == "convex":
        return theta_convex(s, rho, tool_radius)
    if kind == "straight":
        return theta_straight(s, tool_radius)
    raise ValueError(f"kind must be 'concave', 'convex' or 'straight', got {kind!r}")


def rho_min(theta_deg, tool_radius):
    """Smallest contour radius (mm) for which Thesis I has a real root: rho >= r sin(theta)."""
    return _r(tool_radius) * np.abs(np.sin(_theta(theta_deg)))


def stepover_straight(theta_deg, tool_radius):
    """Radial depth (stepover, mm) of a straight cut at engagement ``theta_deg``: a_e = r (1 - cos theta);
    the inverse of :func:`theta_straight`.

    >>> round(float(stepover_straight(60.0, 3.0)), 12)
    1.5
    """
    return _r(tool_radius) * (1 - np.cos(_theta(theta_deg)))


def stepover_thesis1(theta_deg, rho, tool_radius, kind, k=None):
    """Thesis I: stepover s (mm) giving engagement ``theta_deg`` on an arc of radius ``rho`` (mm).

    s(theta, rho) = r (1 - cos theta) + k rho - k sqrt(rho^2 + r^2 (cos^2 theta - 1)),
    k = -1 for ``kind="concave"``, +1 for ``"convex"`` (``k`` may be given to override, e.g. to
    test the other sign); ``kind="straight"`` gives r (1 - cos theta).

    Raises ValueError when theta is outside (0, 180] deg, rho < r sin(theta) (complex root) or the
    result falls outside s in [0, 2r].

    >>> round(float(stepover_thesis1(90.0, 5.0, 3.0, "convex")), 9)     # 3 + 5 - 4
    4.0
    """
    r = _r(tool_radius)
    t = _theta(theta_deg)
    if kind == "straight":
        return stepover_straight(theta_deg, tool_radius)
    if k is None:
        if kind not in KIND_K:
            raise ValueError(f"kind must be 'concave', 'convex' or 'straight', got {kind!r}")
        k = KIND_K[kind]
    _shapes(theta_deg=theta_deg, rho=rho, tool_radius=tool_radius)
    p = _rho(rho)
    rs = r * np.sin(t)
    if np.any(p < np.abs(rs) * (1 - 1e-12)):
        raise ValueError(f"rho must be >= r sin(theta) for a real stepover, got rho={rho!r} "
                         f"(rho_min={np.max(rho_min(theta_deg, tool_radius)):.6g} mm)")
    # k rho - k sqrt(rho^2 - r^2 sin^2) = k r^2 sin^2 / (rho + sqrt(...)): stable, 0 for rho = inf
    with np.errstate(invalid="ignore", over="ignore"):
        root = np.where(np.isinf(p), np.inf, np.sqrt(np.maximum((p - np.abs(rs)) * (p + np.abs(rs)), 0.0)))
    s = r * (1 - np.cos(t)) + k * (rs * rs) / (p + root)
    if np.any(s < -1e-9) or np.any(s > 2 * r + 1e-9):
        raise ValueError(f"Thesis I gives s outside [0, 2r] for theta={theta_deg!r}, rho={rho!r}")
    return s


def theta_kim_yang(s, R, tool_radius):
    """Kim & Yang (2006) eq. 1: theta_max = pi - acos((2r^2 + 2R(s-r) - s^2) / (2r(R-r))) in degrees.

    r must be the tool radius (mm), R the machined corner radius (mm), s the path distance
    (stepover, mm). Identical to :func:`theta_concave` with rho = R - s.

    >>> abs(round(float(theta_kim_yang(1.5, 9.5, 3.0) - theta_concave(1.5, 8.0, 3.0)), 12))
    0.0
    """
    _shapes(s=s, R=R, tool_radius=tool_radius)
    r = _r(tool_radius)
    s = _s(s, r)
    R = _rho(R, "R (corner radius)")
    if np.any(R <= r):
        raise ValueError(f"R (corner radius) must be in (r, inf] mm (r = tool radius; inf = straight cut), got R={R!r}")
    # divide numerator and denominator by R: R = inf gives the straight limit (s - r)/r
    c = ((2 * r * r - s * s) / R + 2 * (s - r)) / (2 * r * (1 - r / R))
    return 180.0 - _acos_checked(c, "theta_kim_yang")


def kim_yang_to_jacso(s, R):
    """Change of variables eq. 1 -> Thesis I: (rho, s) = (R - s, s); tool-centre radius R - r = rho + s - r.

    ``s`` >= 0 mm (finite), ``R`` > s mm (R = inf, a straight cut, gives rho = inf); a result rho <= 0
    would be no contour at all, so R <= s is a ValueError.

    >>> [float(v) for v in kim_yang_to_jacso(1.5, 9.5)]
    [8.0, 1.5]
    """
    _shapes(s=s, R=R)
    try:
        s_ = np.asarray(s, float)
        R_ = np.asarray(R, float)
    except (TypeError, ValueError):
        raise ValueError(f"s and R must be numbers or arrays in mm, got s={s!r}, R={R!r}") from None
    if np.any(~np.isfinite(s_)) or np.any(s_ < 0):
        raise ValueError(f"s (stepover) must be finite and >= 0 mm, got {s!r}")
    if np.any(np.isnan(R_)) or np.any(R_ <= s_):
        raise ValueError(f"R (machined corner radius) must be in (s, inf] mm so that rho = R - s > 0, got R={R!r}, s={s!r}")
    return R_ - s_, s_
