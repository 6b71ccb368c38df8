"""Spindle-speed model of Mgherony (2024) Sec. 7.2.3 along a ball-end path: feed direction per
move (eq 7-3), working diameter per facet normal and feed direction (Sec. 5.2 model), and a spindle
acceleration limit. The APT post-processor that uses it is :mod:`cnclab.nc.spindle_control`.

Units: mm, degrees (A_f, normal angles), rpm, rpm/s.
"""
from __future__ import annotations

import numpy as np

from ..geometry.ball_end import angles_from_normal, tangent_point_diameters

__all__ = ["POINT_RULES", "feed_directions", "working_diameters", "apply_acceleration_limit"]

#: which tangent point's working diameter is used: the larger ("max"), point "1", point "2", or
#: "thesis" (point 1 for nominal A_f <= 45 deg, point 2 above; see cnclab.nc.spindle_control)
POINT_RULES = ("max", "1", "2", "thesis")


def feed_directions(xyz, start=None) -> np.ndarray:
    """Feed direction (deg, atan2 of eq 7-3) of the motion ending at each point; zero-xy moves inherit
    the next (or previous) non-zero direction. ``start`` is the position before the first point."""
    p = np.asarray(xyz, float)
    if p.ndim != 2 or p.shape[1] != 3 or not np.isfinite(p).all():
        raise ValueError(f"xyz must be finite points of shape (N, 3) in mm, got shape {p.shape}")
    if start is not None and (np.shape(start) != (3,) or not np.isfinite(np.asarray(start, float)).all()):
        raise ValueError(f"start must be a finite point (3,) in mm, got {start!r}")
    if len(p) == 0:
        return np.zeros(0)
    prev = np.vstack([p[:1] if start is None else np.asarray(start, float)[None], p[:-1]])
    d = p[:, :2] - prev[:, :2]
    ok = np.hypot(d[:, 0], d[:, 1]) > 1e-9
    ang = np.degrees(np.arctan2(d[:, 1], d[:, 0]))
    if not ok.any():
        return np.zeros(len(p))
    idx = np.where(ok, np.arange(len(p)), len(p))
    nxt = np.minimum.accumulate(idx[::-1])[::-1]          # next valid index
    idx2 = np.where(ok, np.arange(len(p)), -1)
    prv = np.maximum.accumulate(idx2)                     # previous valid index
    src = np.where(nxt < len(p), nxt, prv)
    return ang[src]


def working_diameters(normals, A_f, tool_diameter: float, a_p: float, point: str = "max",
                      nominal_feed_deg: float | None = None):
    """Working diameter (mm) for facet normals (M, 3) and feed directions A_f (deg, (M,)).

    Returns ``(d_eff, A_N1, A_N2)`` with the eq 5-3 angles (deg). ``point``: see module docstring.
    """
    if point not in POINT_RULES:
        raise ValueError(f"point must be one of {POINT_RULES}, got {point!r}")
    n = np.asarray(normals, float)
    if n.ndim != 2 or n.shape[1] != 3 or not np.isfinite(n).all():
        raise ValueError(f"normals must be finite unit vectors of shape (M, 3), got shape {n.shape}")
    if np.ndim(A_f) > 0 and np.shape(A_f) != (len(n),):
        raise ValueError(f"A_f must be a scalar or have shape (M,) = ({len(n)},) like normals, got {np.shape(A_f)}")
    n = n * np.where(n[:, 2:3] < 0, -1.0, 1.0)  # a 3-axis tool sees the upward side
    a1, a2 = angles_from_normal(n)
    d1, d2 = tangent_point_diameters(tool_diameter, a_p, a1, a2, A_f)
    if point == "max":
        d = np.maximum(d1, d2)
    elif point == "1":
        d = d1
    elif point == "2":
        d = d2
    else:
        nom = float(np.median(A_f) if nominal_feed_deg is None else nominal_feed_deg) % 180.0
        d = d1 if nom <= 45.0 + 1e-9 or nom > 135.0 else d2
    return np.asarray(d, float), a1, a2


def apply_acceleration_limit(n_target, seg_len, f_z: float, teeth: int, accel_rpm_s: float,
                             n0: float | None = None) -> np.ndarray:
    """Causal spindle-speed sequence following ``n_target`` (rpm) with |dn/dt| <= accel (rpm/s).

    The time of the motion ending at point j is seg_len_j / v_f with v_f = f_z z n_{j-1} (mm/min),
    i.e. the feed stays synchronised with the spindle (constant f_z).
    """
    if not (accel_rpm_s > 0 and np.isfinite(accel_rpm_s)):
        raise ValueError(f"accel_rpm_s must be finite and > 0 rpm/s, got {accel_rpm_s}")
    if not (f_z > 0 and np.isfinite(f_z)):
        raise ValueError(f"f_z must be finite and > 0 mm, got {f_z}")
    if isinstance(teeth, bool) or int(teeth) != teeth or teeth < 1:
        raise ValueError(f"teeth must be an integer >= 1, got {teeth!r}")
    nt = np.asarray(n_target, float)
    L = np.asarray(seg_len, float)
    if nt.ndim != 1 or L.shape != nt.shape:
        raise ValueError(f"n_target and seg_len must be 1-D arrays of one length, got shapes {nt.shape}, {L.shape}")
    if not (np.isfinite(nt).all() and (nt >= 0).all() and np.isfinite(L).all() and (L >= 0).all()):
        raise ValueError("n_target (rpm) and seg_len (mm) must be finite and >= 0")
    if nt.size == 0:
        return nt.copy()
    out = np.empty_like(nt)
    cur = float(nt[0] if n0 is None else n0)
    k = f_z * teeth / 60.0  # mm/s per rpm
    for j in range(len(nt)):
        dt = L[j] / (k * cur) if cur > 0 else 0.0
        step = accel_rpm_s * dt
        cur = min(max(nt[j], cur - step), cur + step)
        out[j] = cur
    return out
