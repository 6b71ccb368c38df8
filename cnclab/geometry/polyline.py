"""Polylines (mm): the one polyline resampler of the package and its vertex-keeping subdivision (used
by every planner through :mod:`cnclab.toolpath.path`, which re-exports them)."""
from __future__ import annotations

import math

import numpy as np

__all__ = ["resample_polyline", "subdivide"]


def subdivide(points, max_step: float) -> np.ndarray:
    """A polyline (N, 2) or (N, 3) mm with every segment split into equal pieces at most ``max_step``
    mm long (the vertices kept, repeated points dropped): :func:`resample_polyline`.

    >>> subdivide([[0, 0], [1, 0]], 0.4).tolist()
    [[0.0, 0.0], [0.3333333333333333, 0.0], [0.6666666666666666, 0.0], [1.0, 0.0]]
    """
    P = np.asarray(points, float)
    if P.ndim != 2 or P.shape[1] not in (2, 3) or len(P) < 1:
        raise ValueError(f"points must be (N, 2) or (N, 3) mm with N >= 1, got shape {P.shape}")
    Q = resample_polyline(P, max_step)
    return Q[np.r_[True, np.any(np.diff(Q, axis=0) != 0, axis=1)]]          # zero-length segments dropped


def resample_polyline(points, step_mm: float, *, uniform: bool = False, return_index: bool = False):
    """The one polyline resampler: points (N, d) mm -> points at most ``step_mm`` mm apart.

    ``uniform=False``: every segment split into ``ceil(L / step_mm)`` equal pieces, the vertices kept
    exactly (a zero-length segment gives its end point once more); ``uniform=True``: ``ceil(L_total /
    step_mm)`` equal pieces along the whole length (linear interpolation in the length travelled; the
    inner vertices are not kept; a zero-length polyline gives its first point). With ``return_index``
    also, per output point, the index k of the input segment ``P[k-1] -> P[k]`` it ends on (0 for
    the first point): ``(points, index)``.

    >>> resample_polyline([[0, 0], [1, 0], [1, 0.5]], 0.4).round(4).tolist()
    [[0.0, 0.0], [0.3333, 0.0], [0.6667, 0.0], [1.0, 0.0], [1.0, 0.25], [1.0, 0.5]]
    >>> resample_polyline([[0, 0], [1, 0], [1, 0.5]], 0.4, uniform=True)[:, 0].round(4).tolist()
    [0.0, 0.375, 0.75, 1.0, 1.0]
    """
    P = np.asarray(points, float)
    if P.ndim != 2 or len(P) < 1:
        raise ValueError(f"points must be (N, d) mm with N >= 1, got shape {P.shape}")
    if not (math.isfinite(step_mm) and step_mm > 0):
        raise ValueError(f"step_mm must be a finite number > 0 mm, got {step_mm!r}")
    D = np.diff(P, axis=0)
    L = np.hypot(D[:, 0], D[:, 1]) if P.shape[1] == 2 else np.linalg.norm(D, axis=1)
    if uniform:
        s = np.r_[0.0, np.cumsum(L)]
        if len(P) < 2 or s[-1] == 0:
            Q, idx = P[:1].copy(), np.zeros(1, int)
        else:
            u = np.linspace(0, s[-1], max(int(math.ceil(s[-1] / step_mm)), 1) + 1)
            Q = np.column_stack([np.interp(u, s, P[:, j]) for j in range(P.shape[1])])
            idx = np.r_[0, np.minimum(np.searchsorted(s, u[1:], side="left"), len(P) - 1)]
        return (Q, idx) if return_index else Q
    m = np.maximum(1, np.ceil(L / step_mm - 1e-9)).astype(np.int64)
    seg = np.repeat(np.arange(1, len(P)), m)                # segment (end index) of every new point
    t = (np.arange(seg.size) - np.repeat(np.cumsum(m) - m, m) + 1) / m[seg - 1]
    a = P[seg - 1]
    Q = np.vstack([P[:1], a + t[:, None] * (P[seg] - a)])
    Q[np.cumsum(m)] = P[1:]                                 # the vertices exactly
    idx = np.r_[0, seg]
    return (Q, idx) if return_index else Q
