"""Helpers shared by the trochoidal pattern modules (package-private)."""
from __future__ import annotations

import math

import numpy as np

from ..path import ToolPath, ToolPathBuilder


def positive(name, v):
    v = float(v)
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"{name} must be a positive finite number, got {v!r}")
    return v


def pattern_builder(step, pattern: str) -> ToolPathBuilder:
    """A :class:`ToolPathBuilder` for a planar pattern, ``info`` with the step (mm) and the pattern name."""
    return ToolPathBuilder(info={"step": float(step), "pattern": pattern, "name": pattern})


def add_piece(b: ToolPathBuilder, points, kinds, period, feed_mm_min, link_feed_mm_min=None) -> None:
    """Append the planar points (m, 2) mm at z = 0: ``kinds`` (scalar or per point: cut / roll-in /
    roll-out / link, the move ending at the point), ``period`` (scalar or per point; tag
    ``"period k"`` or ``"period k:roll-in"``); links at ``link_feed_mm_min`` (default the feed)."""
    P = np.asarray(points, float).reshape(-1, 2)
    K = np.broadcast_to(np.asarray(kinds, dtype=object), (len(P),))
    per = np.broadcast_to(np.asarray(period), (len(P),))
    tags = np.array([f"period {int(k)}" + ("" if n in ("cut", "link") else f":{n}") for k, n in zip(per, K)],
                    dtype=object)
    lf = feed_mm_min if link_feed_mm_min is None else link_feed_mm_min
    b.add(P, np.where(K == "link", "link", "cut"), np.where(K == "link", lf, feed_mm_min), tags, z=0.0)


def pattern_path(points, kinds, period, step, pattern, feed_mm_min, link_feed_mm_min=None) -> ToolPath:
    """A planar pattern (z = 0) as a :class:`ToolPath` from whole arrays (:func:`add_piece`)."""
    b = pattern_builder(step, pattern)
    add_piece(b, points, kinds, period, feed_mm_min, link_feed_mm_min)
    return b.build()


def largest_step(emax, theta_max_deg, lo, hi, tol_mm, grow_limit=None):
    """Largest step s (mm, to ``tol_mm``) with ``emax(s) <= theta_max_deg``, emax growing with s:
    halve ``lo`` until it is admissible; with ``grow_limit`` (mm) also grow ``hi`` by 1.5x until it
    is not (returning the last admissible step if hi passes the limit); then bisect."""
    while emax(lo) > theta_max_deg:
        hi, lo = lo, 0.5 * lo
        if lo < tol_mm:
            raise ValueError(f"theta_max_deg={theta_max_deg} is below the engagement of the smallest step")
    if grow_limit is not None:
        while emax(hi) <= theta_max_deg:
            lo, hi = hi, 1.5 * hi
            if hi > grow_limit:
                return lo
    while hi - lo > tol_mm:
        mid = 0.5 * (lo + hi)
        if emax(mid) <= theta_max_deg:
            lo = mid
        else:
            hi = mid
    return lo


# ---------------------------------------------------------------------------------------------
# constant-engagement pattern (Thesis IV)
# ---------------------------------------------------------------------------------------------
