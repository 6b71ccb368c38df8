"""Cusp (scallop) height left by a round tool edge: longitudinal turning and Z-level milling.

Mgherony (2024), chapter 3, eqs 3-1 … 3-4. A tool edge of corner radius ``RE`` leaves circular arcs
spaced ``s`` apart; the cusp between two arcs has height ``CH``.

Exact relation (Pythagoras in Fig 3-1/3-2)::

    RE² = (s/2)² + (RE − CH)²      →   CH = RE − √(RE² − s²/4)

Approximation (drop CH², eq 3-2/3-4)::

    CH ≈ s² / (8·RE)

Turning: ``s = f`` (feed per revolution). Z-level milling of a wall inclined at ``A`` to the
horizontal with step-down ``a_p``: the arcs are ``s = a_p / sin A`` apart along the surface.

Erratum: eq 3-1 is printed as ``RE² = (f/2)² + RE·CH``: the term ``(RE − CH)²`` is missing (the
printed form gives CH = RE − f²/(4·RE), i.e. almost the corner radius itself). See
:func:`cusp_height_eq3_1_as_printed`.

All lengths in mm; angles in degrees.

>>> round(float(cusp_height_turning(0.1, 0.4, exact=False)) * 1000, 3)     # µm, Table 3-4 T1
3.125
>>> round(float(cusp_height_zlevel(0.15, 0.5, 80.0, exact=False)) * 1000, 2)  # µm, Table 3-4 M1
5.8
"""
from __future__ import annotations

import numpy as np


def _positive(name, value):
    v = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(v)) or np.any(v <= 0):
        raise ValueError(f"{name} must be finite and > 0 mm, got {value!r}")
    return v


def cusp_height_from_spacing(spacing, corner_radius, exact: bool = True):
    """Cusp height (mm) between circular arcs of radius ``corner_radius`` (mm) spaced ``spacing`` (mm).

    ``exact=True``: ``RE − √(RE² − s²/4)`` (needs ``s ≤ 2·RE``); ``exact=False``: ``s²/(8·RE)``.

    >>> float(cusp_height_from_spacing(2.0, 1.0))   # half-circle: the cusp is the full radius
    1.0
    """
    s = _positive("spacing", spacing)
    re = _positive("corner_radius", corner_radius)
    try:
        np.broadcast_shapes(s.shape, re.shape)
    except ValueError:
        raise ValueError(f"spacing and corner_radius must have broadcastable shapes, got spacing {s.shape}, "
                         f"corner_radius {re.shape}") from None
    if not exact:
        return s**2 / (8.0 * re)
    if np.any(s > 2.0 * re):
        raise ValueError(f"spacing must be <= 2*corner_radius for the exact relation, got {spacing!r}")
    # RE − √(RE² − s²/4) written without cancellation for s ≪ RE
    return 0.25 * s**2 / (re + np.sqrt(re**2 - 0.25 * s**2))


def cusp_height_turning(feed, corner_radius, exact: bool = True):
    """Cusp height (mm) of longitudinal turning: feed ``f`` (mm/rev), insert corner radius ``RE`` (mm).

    ``exact=False`` is eq 3-2, ``CH = f²/(8·RE)``.
    """
    f = np.asarray(feed, dtype=float)
    if not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise ValueError(f"feed must be finite and > 0 mm/rev, got {feed!r}")
    return cusp_height_from_spacing(feed, corner_radius, exact)


def zlevel_spacing(a_p, inclination_deg):
    """Distance (mm) along a wall inclined ``A`` degrees between Z-level passes ``a_p`` (mm) apart."""
    a = np.asarray(inclination_deg, dtype=float)
    if not np.all(np.isfinite(a)) or np.any((a <= 0) | (a >= 180)):
        raise ValueError(f"inclination A must be in (0, 180) degrees, got {inclination_deg!r}")
    ap = _positive("a_p", a_p)
    return ap / np.sin(np.radians(a))


def cusp_height_zlevel(a_p, corner_radius, inclination_deg, exact: bool = True):
    """Cusp height (mm) of Z-level milling: step-down ``a_p`` (mm), corner radius ``RE`` (mm), wall
    inclination ``A`` (degrees from horizontal, 0 < A < 180). ``exact=False`` is eq 3-4,
    ``CH = a_p² / (8·RE·sin²A)``."""
    return cusp_height_from_spacing(zlevel_spacing(a_p, inclination_deg), corner_radius, exact)


def cusp_height_eq3_1_as_printed(feed, corner_radius):
    """CH (mm) solved from eq 3-1 *as printed*, ``RE² = (f/2)² + RE·CH`` — the erratum.

    Gives ``RE − f²/(4·RE)``, nearly the corner radius: the printed relation lacks ``(RE − CH)²``.
    """
    f = _positive("feed", feed)
    re = _positive("corner_radius", corner_radius)
    return (re**2 - 0.25 * f**2) / re


def approximation_relative_error(spacing, corner_radius):
    """Relative error ``(approx − exact)/exact`` of eq 3-2/3-4 (negative: the approximation is low).

    To leading order it is ``−CH/(2·RE)`` ≈ ``−s²/(16·RE²)``.
    """
    ex = cusp_height_from_spacing(spacing, corner_radius, exact=True)
    ap = cusp_height_from_spacing(spacing, corner_radius, exact=False)
    return (ap - ex) / ex
