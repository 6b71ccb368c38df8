"""Uncut (scallop) volume of ball-end zig-zag finishing — Hoang (2024), eqs 1–7.

Geometry (Hoang 2024, Figs 1–4): a ball-end mill of radius ``R_T`` [mm] machines a plane with
parallel passes ``S_z`` [mm] apart (stepover); along a pass the cutter-contact points are ``F_r`` [mm]
apart (forward step). Between two passes a ridge of height ``S_c`` [mm] (scallop height) is left.

Equations (all lengths mm, volumes mm³):

* eq. 1  ``V1  = 1/2 · S_c · S_z · F_r``                     (triangular prism, no tool curvature)
* eq. 3  ``V_RT = R_T²/2 · (π·θ/180 − sin θ)``               (θ in **degrees**, as the π/180 says)
* eq. 2  ``V1* = 1/2 · {S_c·S_z − V_RT} · F_r``
* eq. 4  ``V2  = 1/3 · S_c · S_z · F_r``                      (pyramid over two half-steps)
* eq. 5  ``sin θ = S_z / (2 R_T)``
* eq. 6  ``S_z = 2·sqrt(R_T² − (R_T − S_c)²)``;  inverse (Table 1 line 5) ``S_c = R_T·(1 − cos θ)``
* eq. 7  ``F_r = 2·V1* / {S_c·S_z − V_RT}``

Every function here is **unit consistent**: angles are passed in radians (``theta_rad``) or degrees
(``theta_deg``) as the name says, and eq. 3 is evaluated as ``R_T²/2·(θ_rad − sin θ_rad)``.
:func:`forward_step_as_printed` reproduces Table 2's printed ``F_r`` column: it feeds θ **in
radians** (rounded to the 5 printed decimals) into the ``π·θ/180`` term and uses ``π = 3.14``
(see ``notebooks/hoang2024/eqs_and_table2_constant_volume.ipynb``).

>>> round(float(stepover(scallop_height=0.05, tool_radius=2.0)), 5)
0.88882
>>> round(float(theta_from_stepover(0.888819, 2.0)), 5)   # radians
0.22408
"""
from __future__ import annotations

import numpy as np

__all__ = ["stepover", "scallop_height", "theta_from_stepover", "curvature_volume",
           "block_volume_v1", "block_volume_v1_star", "block_volume_v2", "forward_step",
           "forward_step_as_printed", "theta_as_printed", "scallop_area_exact", "table2_row"]


def _pos(name: str, value, allow_zero: bool = False):
    a = np.asarray(value, dtype=float)
    bad = ~np.isfinite(a) | ((a < 0) if allow_zero else (a <= 0))
    if np.any(bad):
        raise ValueError(f"{name} must be {'>= 0' if allow_zero else '> 0'} and finite (mm), got {value!r}")
    return a


def _check_sc(sc, r):
    if np.any(sc > r):
        raise ValueError(f"scallop_height must be <= tool_radius (mm), got S_c={sc!r}, R_T={r!r}")


def stepover(scallop_height, tool_radius):
    """Stepover S_z [mm] leaving scallop height S_c [mm] with a ball of radius R_T [mm] (eq. 6).

    >>> round(float(stepover(0.05, 2.5)), 5)
    0.99499
    """
    sc, r = _pos("scallop_height", scallop_height), _pos("tool_radius", tool_radius)
    _check_sc(sc, r)
    return 2.0 * np.sqrt(r ** 2 - (r - sc) ** 2)


def scallop_height(stepover_mm, tool_radius):
    """Scallop height S_c [mm] of stepover S_z [mm], ball radius R_T [mm] (inverse of eq. 6).

    Same as Table 1 line 5, ``S_c = R_T (1 − cos θ)`` with ``sin θ = S_z/(2R_T)``.

    >>> round(float(scallop_height(0.994987, 2.5)), 6)
    0.05
    """
    th = theta_from_stepover(stepover_mm, tool_radius)
    return _pos("tool_radius", tool_radius) * (1.0 - np.cos(th))


def theta_from_stepover(stepover_mm, tool_radius):
    """Angle θ [**radians**] of eq. 5, ``sin θ = S_z / (2 R_T)`` (S_z, R_T in mm).

    >>> round(float(np.degrees(theta_from_stepover(1.0, 2.5))), 4)   # in degrees
    11.537
    """
    sz, r = _pos("stepover_mm", stepover_mm), _pos("tool_radius", tool_radius)
    if np.any(sz > 2 * r):
        raise ValueError(f"stepover_mm must be <= 2*tool_radius (mm), got S_z={stepover_mm!r}, R_T={tool_radius!r}")
    return np.arcsin(sz / (2.0 * r))


def curvature_volume(theta_rad, tool_radius):
    """Curvature term V_RT of eq. 3 [mm²; ×F_r gives mm³], unit consistent: ``R²/2 (θ − sin θ)``.

    ``theta_rad`` in radians (eq. 3's ``π·θ/180`` with θ in degrees is the same number).

    >>> round(float(curvature_volume(np.pi / 2, 1.0)), 6)   # (π/2 − 1)/2
    0.285398
    """
    th = _pos("theta_rad", theta_rad, allow_zero=True)
    r = _pos("tool_radius", tool_radius)
    return 0.5 * r ** 2 * (th - np.sin(th))


def block_volume_v1(scallop_height, stepover_mm, forward_step_mm):
    """V1 = ½·S_c·S_z·F_r [mm³] (eq. 1)."""
    return 0.5 * _pos("scallop_height", scallop_height) * _pos("stepover_mm", stepover_mm) \
        * _pos("forward_step_mm", forward_step_mm)


def block_volume_v2(scallop_height, stepover_mm, forward_step_mm):
    """V2 = ⅓·S_c·S_z·F_r [mm³] (eq. 4)."""
    return _pos("scallop_height", scallop_height) * _pos("stepover_mm", stepover_mm) \
        * _pos("forward_step_mm", forward_step_mm) / 3.0


def block_volume_v1_star(scallop_height, tool_radius, forward_step_mm):
    """V1* = ½·{S_c·S_z − R²/2(θ − sin θ)}·F_r [mm³] (eq. 2, unit consistent; S_z, θ from eqs 5–6)."""
    sz = stepover(scallop_height, tool_radius)
    th = theta_from_stepover(sz, tool_radius)
    return 0.5 * (scallop_height * sz - curvature_volume(th, tool_radius)) * _pos("forward_step_mm", forward_step_mm)


def forward_step(volume, scallop_height, tool_radius):
    """Forward step F_r [mm] keeping V1* = ``volume`` [mm³] constant (eq. 7, unit consistent).

    >>> v = float(block_volume_v1_star(0.05, 2.0, 3.0))
    >>> round(float(forward_step(v, 0.05, 2.0)), 12)
    3.0
    """
    v = _pos("volume", volume)
    sz = stepover(scallop_height, tool_radius)
    th = theta_from_stepover(sz, tool_radius)
    return 2.0 * v / (scallop_height * sz - curvature_volume(th, tool_radius))


def theta_as_printed(scallop_height, tool_radius, decimals: int | None = 5):
    """θ as Table 2 prints it: **radians**, from S_z rounded to ``decimals``, rounded to ``decimals``.

    >>> float(theta_as_printed(0.05, 2.5))   # printed 0.20034 under the header "θ, °"
    0.20034
    """
    sz = stepover(scallop_height, tool_radius)
    if decimals is not None:
        sz = np.round(sz, decimals)
    th = theta_from_stepover(sz, tool_radius)
    return th if decimals is None else np.round(th, decimals)


def forward_step_as_printed(volume, scallop_height, tool_radius, pi: float = 3.14, decimals: int | None = 5):
    """F_r [mm] as Table 2 prints it: eq. 7 with θ in *radians* put where eq. 3 expects degrees.

    The chain of the printed table: S_z rounded to ``decimals``, θ = asin(S_z/2R_T) in radians rounded
    to ``decimals`` (:func:`theta_as_printed`), then ``π·θ/180`` receives that radian value while
    ``sin θ`` takes it as radians, with ``pi = 3.14``. This slip reproduces the printed column to all
    5 decimals; it is *not* the unit-consistent value (:func:`forward_step`).
    """
    v = _pos("volume", volume)
    sz = stepover(scallop_height, tool_radius)
    if decimals is not None:
        sz = np.round(sz, decimals)
    th = theta_as_printed(scallop_height, tool_radius, decimals)
    r = np.asarray(tool_radius, float)
    return 2.0 * v / (scallop_height * sz - 0.5 * r ** 2 * (pi * th / 180.0 - np.sin(th)))


def scallop_area_exact(stepover_mm, tool_radius):
    """Exact cross-section area [mm²] of the ridge left between two straight ball-end passes.

    Area between the design plane and the envelope of two circles of radius R_T whose centres are
    S_z apart: ``R²(2 sin θ − sin θ cos θ − θ)`` with ``sin θ = S_z/(2R)``. Times a length of pass
    it is the true uncut volume of a continuous sweep (≈ ⅓·S_c·S_z for small S_z/R, i.e. eq. 4 / F_r).

    >>> a = float(scallop_area_exact(0.994987, 2.5)); round(a, 5)
    0.01652
    """
    th = theta_from_stepover(stepover_mm, tool_radius)
    r = np.asarray(tool_radius, float)
    return r ** 2 * (2 * np.sin(th) - np.sin(th) * np.cos(th) - th)


def table2_row(scallop_height, tool_radius, volume) -> dict:
    """All Table 2 quantities of one row, printed convention and consistent one side by side.

    Returns a dict: ``Sz`` [mm], ``theta_rad``, ``theta_deg``, ``Fr_printed_convention`` [mm] (the
    slip), ``Fr_consistent`` [mm] (eq. 7 unit consistent), ``Fr_v1`` (eq. 1, no curvature),
    ``Fr_v2`` (eq. 4).
    """
    sz = float(stepover(scallop_height, tool_radius))
    th = float(theta_from_stepover(sz, tool_radius))
    return {
        "Sc": scallop_height, "RT": tool_radius, "V": volume, "Sz": sz,
        "theta_rad": th, "theta_deg": float(np.degrees(th)),
        "theta_printed_convention": float(theta_as_printed(scallop_height, tool_radius)),
        "Fr_printed_convention": float(forward_step_as_printed(volume, scallop_height, tool_radius)),
        "Fr_consistent": float(forward_step(volume, scallop_height, tool_radius)),
        "Fr_v1": 2.0 * volume / (scallop_height * sz),
        "Fr_v2": 3.0 * volume / (scallop_height * sz),
    }
