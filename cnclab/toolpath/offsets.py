"""Contour-parallel (offset) pocketing paths with shapely: islands, splitting loops, linking.

A pocket is a shapely ``Polygon`` (holes = islands) in mm. The tool centre may go where
``pocket.buffer(-tool_radius)`` is non-empty (the *allowed region*). Offset level ``k`` is the
boundary of ``pocket.buffer(-(tool_radius + k*stepover))``: level 0 is the finishing contour, each
further level lies ``stepover`` (the radial depth of cut, mm) inside the previous one. A level may
hold several loops (the offset splits in narrow regions) and island loops.

Loop orientation follows climb milling with a clockwise (M3) spindle when the pocket is cleared
from the inside out: the uncut material is on the **right** of the feed direction, the machined
side on the left (Kim & Yang 2006 shift their end points "to the left of moving direction" into the
machined side). So outer boundaries run counter-clockwise, island loops clockwise.

:func:`link_loops` orders the loops innermost level first (inside-out clearing) and nearest-neighbour
within a level, starts each loop at its vertex nearest the previous end, and returns *passes*:
continuous polylines at cutting depth. Consecutive loops are joined by a straight feed link when it
stays inside the allowed region, otherwise a new pass starts (retract, rapid, plunge).

>>> from shapely.geometry import box
>>> levels = offset_levels(box(0, 0, 40, 30), tool_radius=5, stepover=3)
>>> [len(l) for l in levels]      # one loop per level until the centre collapses
[1, 1, 1, 1]
>>> passes = link_loops(levels, box(0, 0, 40, 30).buffer(-5))
>>> len(passes), passes[0].shape[1]
(1, 2)
"""
from __future__ import annotations

import numpy as np
from shapely.geometry import LineString, MultiPolygon, Polygon
from shapely.geometry.polygon import orient

from ..geometry.planar import polygon_parts

__all__ = ["offset_levels", "link_loops", "passes_length", "allowed_region"]


def allowed_region(pocket: Polygon, tool_radius: float):
    """Where the tool centre may go [mm]: ``pocket.buffer(-tool_radius)``."""
    if not tool_radius > 0:
        raise ValueError(f"tool_radius must be > 0 mm, got {tool_radius}")
    return pocket.buffer(-tool_radius, join_style="round", quad_segs=64)


def offset_levels(pocket: Polygon, tool_radius: float, stepover: float, min_area: float = 1e-3,
                  max_levels: int = 10_000, quad_segs: int = 64) -> list[list[np.ndarray]]:
    """Offset loops per level, outermost level first; each loop an (n, 2) closed array [mm].

    ``tool_radius``: radius of the flat end mill [mm]; ``stepover``: radial depth between levels [mm].
    Loops are oriented for inside-out climb milling (outer CCW, islands CW; see module docstring).
    Polygons smaller than ``min_area`` mm² are dropped.
    """
    if not isinstance(pocket, (Polygon, MultiPolygon)) or pocket.is_empty or not pocket.is_valid:
        raise ValueError("pocket must be a valid, non-empty shapely Polygon (mm)")
    if not tool_radius > 0:
        raise ValueError(f"tool_radius must be > 0 mm, got {tool_radius}")
    if not stepover > 0:
        raise ValueError(f"stepover must be > 0 mm, got {stepover}")
    if stepover > 2 * tool_radius:
        raise ValueError(f"stepover must be <= tool diameter 2*tool_radius = {2 * tool_radius} mm, got {stepover}")
    levels = []
    for k in range(max_levels):
        g = pocket.buffer(-(tool_radius + k * stepover), join_style="round", quad_segs=quad_segs)
        polys = [orient(p, 1.0) for p in polygon_parts(g) if p.area > min_area]
        if not polys:
            break
        loops = []
        for p in polys:
            loops.append(np.asarray(p.exterior.coords, float))
            loops += [np.asarray(r.coords, float) for r in p.interiors]
        levels.append(loops)
    return levels


def _rotate_to(loop: np.ndarray, point) -> np.ndarray:
    ring = loop[:-1]
    k = int(np.argmin(np.hypot(ring[:, 0] - point[0], ring[:, 1] - point[1])))
    ring = np.roll(ring, -k, axis=0)
    return np.vstack([ring, ring[:1]])


def link_loops(levels: list[list[np.ndarray]], allowed, start=None) -> list[np.ndarray]:
    """Link offset loops into passes (inside-out); returns a list of (n, 2) polylines [mm].

    ``allowed``: the allowed region (:func:`allowed_region`); a straight link between loops is a
    feed move only when it lies inside it (tolerance 1e-6 mm). ``start``: where the first pass
    should begin (default: the first loop's first vertex).
    """
    passes: list[list[np.ndarray]] = []
    cur = None if start is None else np.asarray(start, float)
    guard = allowed.buffer(1e-6)
    for loops in reversed(levels):
        todo = list(loops)
        while todo:
            if cur is None:
                k = 0
            else:
                d = [np.min(np.hypot(lp[:, 0] - cur[0], lp[:, 1] - cur[1])) for lp in todo]
                k = int(np.argmin(d))
            lp = todo.pop(k)
            lp = lp if cur is None else _rotate_to(lp, cur)
            if cur is not None and passes and guard.contains(LineString([cur, lp[0]])):
                passes[-1].append(lp)
            else:
                passes.append([lp])
            cur = lp[-1]
    return [np.vstack(p) for p in passes]


def passes_length(passes) -> float:
    """Total feed length [mm] of the passes (links inside passes included, rapids excluded)."""
    return float(sum(np.hypot(*np.diff(p, axis=0).T).sum() for p in passes))
