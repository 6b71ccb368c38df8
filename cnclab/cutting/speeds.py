"""Cutting speed, spindle speed and feed speed (Mgherony 2024, eqs 4-1 / 5-6, 7-4, 7-5).

Units: diameters in mm, cutting speed ``v_c`` in m/min, spindle speed ``n`` in rpm (1/min), feed per
tooth ``f_z`` in mm, feed speed ``v_f`` in mm/min. All functions broadcast over numpy arrays and raise
``ValueError`` naming the offending parameter.

>>> round(float(cutting_speed(10, 3820)), 2)
120.01
>>> round(float(spindle_speed(cutting_speed(10, 3820), 10)), 6)
3820.0
>>> float(feed_speed(0.08, 4, 5100))
1632.0
"""
from __future__ import annotations

import numpy as np

__all__ = ["cutting_speed", "spindle_speed", "feed_speed"]


def _arr(value, name: str, unit: str, *, positive: bool = False, nonneg: bool = False) -> np.ndarray:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number or an array of numbers ({unit}), got {value!r}") from None
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite ({unit}), got {value!r}")
    if positive and np.any(a <= 0):
        raise ValueError(f"{name} must be > 0 {unit}, got {a[a <= 0].ravel()[0] if a.ndim else a}")
    if nonneg and np.any(a < 0):
        raise ValueError(f"{name} must be >= 0 {unit}, got {a[a < 0].ravel()[0] if a.ndim else a}")
    return a


def _same_shape(**kw) -> None:
    """ValueError naming the parameters when their shapes do not broadcast."""
    try:
        np.broadcast_shapes(*(np.shape(v) for v in kw.values()))
    except ValueError:
        got = ", ".join(f"{k} {np.shape(v)}" for k, v in kw.items())
        raise ValueError(f"{', '.join(kw)} must have broadcastable shapes, got {got}") from None


def cutting_speed(diameter_mm, n_rpm):
    """Cutting speed ``v_c = D·n·π/1000`` (m/min) at a (working) diameter (mm) and spindle speed (rpm).

    Eq 4-1 / 5-6. A working diameter of 0 (the tool tip) gives 0. Pass a *diameter*, not a radius.

    >>> round(float(cutting_speed(3.4117, 5100)), 2)
    54.66
    """
    d = _arr(diameter_mm, "diameter_mm", "mm", nonneg=True)
    n = _arr(n_rpm, "n_rpm", "rpm", nonneg=True)
    _same_shape(diameter_mm=d, n_rpm=n)
    return d * n * np.pi / 1000.0


def spindle_speed(v_c_m_min, diameter_mm):
    """Spindle speed ``n = 1000·v_c/(π·D)`` (rpm) giving cutting speed ``v_c`` (m/min) at diameter ``D`` (mm).

    Eq 7-4; the inverse of :func:`cutting_speed`. ``diameter_mm`` must be > 0.

    >>> round(float(spindle_speed(120, 10)), 1)
    3819.7
    """
    v = _arr(v_c_m_min, "v_c_m_min", "m/min", nonneg=True)
    d = _arr(diameter_mm, "diameter_mm", "mm", positive=True)
    _same_shape(v_c_m_min=v, diameter_mm=d)
    return 1000.0 * v / (np.pi * d)


def feed_speed(f_z_mm, teeth, n_rpm):
    """Feed speed ``v_f = f_z·z·n`` (mm/min) from feed per tooth (mm), number of teeth and spindle speed (rpm).

    Eq 7-5. ``teeth`` must be a positive integer.

    >>> float(feed_speed(0.16, 4, 5100))
    3264.0
    """
    fz = _arr(f_z_mm, "f_z_mm", "mm", nonneg=True)
    z = _arr(teeth, "teeth", "-", positive=True)
    if np.any(z != np.round(z)):
        raise ValueError(f"teeth must be a positive integer, got {teeth!r}")
    n = _arr(n_rpm, "n_rpm", "rpm", nonneg=True)
    _same_shape(f_z_mm=fz, teeth=z, n_rpm=n)
    return fz * z * n
