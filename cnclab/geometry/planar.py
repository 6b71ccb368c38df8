"""Planar pocket geometry shared by the evaluator, the planners and the program writer (mm).

:func:`wall_clearance`: how far a tool disc centred at each point stays off the walls and islands of
a pocket -- the one place the signed distance to a pocket boundary is computed for the wall-gouge
measure (:func:`cnclab.toolpath.evaluate.wall_gouge`) and for the arc fit's wall rule
(:class:`cnclab.nc.arcfit.Walls`). :func:`polygon_parts`: the polygons of any shapely result.
"""
from __future__ import annotations

import numpy as np
import shapely

__all__ = ["wall_clearance", "polygon_parts"]


def wall_clearance(polygon, radius_mm: float, P, top_z: float = 0.0, clear=None) -> np.ndarray:
    """Per tool-tip centre of ``P`` (n, 3) mm: ``d - r`` [mm], the clearance of a disc of radius
    ``radius_mm`` from the walls and islands of ``polygon`` (islands as holes), with ``d`` the signed
    distance of the centre to the polygon's boundary (positive inside); negative where the disc
    reaches into a wall (a gouge of that depth). ``+inf`` at or above ``top_z`` and inside ``clear``
    (optional: a polygon whose points are known to keep the disc off the walls, e.g. the pocket shrunk
    by r; they skip the distance computation).

    >>> from shapely.geometry import box
    >>> wall_clearance(box(0, 0, 40, 20), 3.0, np.array([[38.0, 10, -1], [20.0, 1, -1], [38.0, 10, 1]])).tolist()
    [-1.0, -2.0, inf]
    """
    P = np.asarray(P, float)
    out = np.full(len(P), np.inf)
    idx = np.flatnonzero(P[:, 2] < top_z - 1e-9)
    if idx.size and clear is not None:
        idx = idx[~shapely.contains_xy(clear, P[idx, 0], P[idx, 1])]
    if idx.size:
        x, y = P[idx, 0], P[idx, 1]
        d = shapely.distance(polygon.boundary, shapely.points(x, y))
        out[idx] = np.where(shapely.contains_xy(polygon, x, y), d, -d) - radius_mm
    return out


def polygon_parts(g) -> list:
    """The non-empty polygons of the shapely geometry ``g``, in order, with nested collections
    flattened (``make_valid`` of an invalid MultiPolygon is a collection holding a MultiPolygon and
    lines; a buffer gives a Polygon or a MultiPolygon); points and lines are dropped.

    >>> from shapely.geometry import GeometryCollection, LineString, MultiPolygon, box
    >>> g = GeometryCollection([MultiPolygon([box(0, 0, 1, 1), box(2, 0, 3, 1)]), LineString([(0, 0), (5, 5)])])
    >>> [p.bounds for p in polygon_parts(g)]
    [(0.0, 0.0, 1.0, 1.0), (2.0, 0.0, 3.0, 1.0)]
    >>> polygon_parts(box(0, 0, 1, 1).buffer(-1))
    []
    """
    out = []
    for p in shapely.get_parts(g):
        if p.geom_type == "Polygon":
            if not p.is_empty:
                out.append(p)
        elif p.geom_type in ("MultiPolygon", "GeometryCollection"):
            out += polygon_parts(p)
    return out
