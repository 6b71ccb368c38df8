"""The one helix generator's ring: :func:`helix_ring`, the xy trace a helical entry descends along
(:meth:`cnclab.toolpath.path.ToolPathBuilder.helix` turns it into moves), :func:`helix_segments`,
the chords per turn for a stated chord error, and :func:`helix_entry`, the planners' entry (a helix
at a ramp angle, then a floor circle) on a builder. Units: mm, rad, deg.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["HELIX_CHORD_MM", "helix_segments", "helix_ring", "helix_entry"]


def _check_radius(radius):
    if not (math.isfinite(radius) and radius > 0):
        raise ValueError(f"radius must be a finite number > 0 mm, got {radius!r}")


#: mm: chord error of a helix's polyline (:func:`helix_segments`; the program's 4th decimal x 100)
HELIX_CHORD_MM = 0.01


def helix_segments(radius: float, chord_mm: float = HELIX_CHORD_MM) -> int:
    """Chords per turn (at least 16) for a ring of ``radius`` mm whose chords stay within ``chord_mm``
    mm of the circle (sagitta r (1 - cos(pi / n)) <= chord_mm).

    >>> helix_segments(1.5), helix_segments(0.1)
    (28, 16)
    """
    _check_radius(radius)
    return max(16, math.ceil(math.pi / math.acos(max(1.0 - chord_mm / radius, -1.0))))


def helix_ring(center_xy, radius: float, n_segments: int, *, turns: float = 1.0, start_rad: float = 0.0) -> np.ndarray:
    """The xy trace (n_segments + 1, 2) mm of ``turns`` counter-clockwise turns (default one) of
    radius ``radius`` mm about ``center_xy`` in ``n_segments`` equal chords, from angle ``start_rad``
    (rad) to ``start_rad + 2 pi turns``; a point at a whole number of turns equals the first exactly:
    the ring a helical entry descends along (:meth:`ToolPathBuilder.helix`).

    >>> helix_ring((0, 0), 2.0, 4).round(12).tolist()
    [[2.0, 0.0], [0.0, 2.0], [-2.0, 0.0], [-0.0, -2.0], [2.0, 0.0]]
    >>> helix_ring((0, 0), 2.0, 3, turns=0.75).round(12).tolist()
    [[2.0, 0.0], [0.0, 2.0], [-2.0, 0.0], [-0.0, -2.0]]
    """
    _check_radius(radius)
    if int(n_segments) != n_segments or n_segments < 3:
        raise ValueError(f"n_segments must be an integer >= 3, got {n_segments!r}")
    if not (math.isfinite(turns) and turns > 0):
        raise ValueError(f"turns must be a finite number > 0, got {turns!r}")
    u = np.linspace(0.0, turns, int(n_segments) + 1)                     # turns travelled
    a = np.linspace(start_rad, start_rad + 2 * math.pi * turns, int(n_segments) + 1)
    pts = np.asarray(center_xy, float) + radius * np.c_[np.cos(a), np.sin(a)]
    pts[u == np.round(u)] = pts[0]
    return pts


def helix_entry(b, c_xy, rho: float, z_from: float, z_to: float, feed: float, angle_deg: float, *,
                tag: str = "entry") -> np.ndarray:
    """A helical entry through the builder ``b`` (a :class:`~cnclab.toolpath.path.ToolPathBuilder`,
    the tool at ``z_from`` over the ring's start, ``c_xy + (rho, 0)``): counter-clockwise turns of
    radius ``rho`` mm about ``c_xy`` from ``z_from`` down to ``z_to`` mm at ``angle_deg`` deg (at
    least one turn, the last partial: z linear in the angle, :meth:`ToolPathBuilder.helix`), chords
    within :data:`HELIX_CHORD_MM` of the circle; then a floor circle at ``z_to`` (``cut`` moves tagged
    ``entry-floor``). ``feed`` mm/min; ``tag`` of the helix moves. Returns the end point (2,) mm.

    >>> from cnclab.toolpath.path import ToolPathBuilder
    >>> b = ToolPathBuilder(); b.rapid([[1.0, 0.0]], z=0.0)
    >>> end = helix_entry(b, (0, 0), 1.0, 0.0, -1.0, 300, 5.0)        # 1 mm at 5 deg: 1.82 turns, ends at 295 deg
    >>> p = b.build(); int(p.is_kind("helix").sum()), round(float(p.xyz[:, 2].min()), 6), end.round(3).tolist()
    (42, -1.0, [0.421, -0.907])
    """
    drop = 2 * math.pi * rho * math.tan(math.radians(angle_deg))
    turns = max((z_from - z_to) / drop, 1.0)
    n = helix_segments(rho)
    ring = helix_ring(c_xy, rho, max(int(math.ceil(n * turns - 1e-9)), n), turns=turns)
    b.helix(ring, z_from, z_to, feed, tag=tag, equal_steps=True)
    floor = helix_ring(c_xy, rho, n, start_rad=2 * math.pi * turns)
    floor[0] = floor[-1] = ring[-1]
    b.cut(floor[1:], feed, z=z_to, tag="entry-floor")
    return floor[-1]
