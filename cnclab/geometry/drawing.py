"""Pocket outlines from drawings: DXF (on ``ezdxf``) and SVG (on ``svgelements``) -> regions of an outline
with islands, in mm, flattened to a stated chord tolerance.

:func:`read_drawing` reads the closed shapes of one layer (or of every layer) of a drawing:

* DXF (model space): closed LWPOLYLINE (bulges as exact arcs), closed 2D/3D POLYLINE, CIRCLE, full
  ELLIPSE, closed SPLINE, and chains of LINE, ARC, open LWPOLYLINE/POLYLINE, elliptic arcs and open
  SPLINEs whose ends meet within ``join_tol``; block references (INSERT) are expanded (an entity on
  layer ``0`` inside a block takes the layer of its INSERT). Everything else (TEXT, MTEXT, DIMENSION,
  HATCH, POINT, ...) is skipped and counted in :attr:`Drawing.notes`. ``$INSUNITS`` gives the unit
  (inch -> x 25.4, ...); a unitless drawing (``$INSUNITS`` 0) is read as mm and says so in the notes
  (``units=`` overrides the drawing's unit).
* SVG: every path and basic shape (path, rect, circle, ellipse, polygon, polyline, line), transforms
  applied; a "layer" is an ancestor group's ``inkscape:label`` or ``id``. Lengths follow the document's
  ``width``/``height`` and ``viewBox`` (user units without a physical size are CSS px, 96 per inch);
  the y axis is flipped (SVG's y points down) so the part is read as drawn. Text and images are
  skipped and counted in the notes; every path counts as an outline whatever its fill or fill rule
  (nesting is by containment).

Open chains (an end that meets no other end within ``join_tol``) are refused naming the entity (DXF
handle ``#2F`` or SVG id) and the gap to the nearest other end; ends where three or more pieces meet,
self-intersecting rings and crossing rings are refused naming their entities. Rings nest by
containment (shapely): a ring inside an outline is an island, a ring inside an island the outline of
another region, and so on; several regions are allowed.

Tolerances (mm; both stated in :attr:`Drawing.notes`):

* ``tolerance`` (default :data:`CHORD_TOL_MM` = 0.005 mm): chord error of the flattening. Arcs and
  circles are flattened exactly (sagitta ``r (1 - cos(dphi/2)) <= tolerance``, vertices on the curve),
  ellipses and splines by ezdxf's adaptive flattening, SVG curves by bisection until the curve point at
  each chord's middle (and quarter points) is within ``tolerance`` of the chord. Chords lie on the
  inner side of each arc: the pocket shrinks by up to ``tolerance`` at its convex walls and grows by up
  to ``tolerance`` into round islands and inward-bulging walls. 0.005 mm is a tenth of a usual
  +-0.05 mm pocket tolerance.
* ``join_tol`` (default :data:`JOIN_TOL_MM` = 0.001 mm): the largest gap two chained ends may have; far
  below any machining tolerance and far above the rounding of DXF coordinates (16 digits).

>>> import ezdxf, tempfile, os
>>> doc = ezdxf.new(units=4)                                    # $INSUNITS 4: mm
>>> msp = doc.modelspace()
>>> _ = msp.add_lwpolyline([(0, 0, 0), (40, 0, 1), (40, 20, 0), (0, 20, 0)], format="xyb",
...                        close=True, dxfattribs={"layer": "POCKET"})   # bulge 1: a semicircle
>>> _ = msp.add_circle((15, 10), 4, dxfattribs={"layer": "POCKET"})
>>> path = os.path.join(tempfile.mkdtemp(), "part.dxf"); doc.saveas(path)
>>> d = read_drawing(path, layer="POCKET")
>>> len(d.regions), len(d.regions[0].islands), d.regions[0].islands[0].circle
(1, 1, (15.0, 10.0, 4.0))
>>> round(d.polygon().area, 2), round(800 + math.pi * 10 ** 2 / 2 - math.pi * 4 ** 2, 2)
(906.79, 906.81)
"""
from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon

__all__ = ["CHORD_TOL_MM", "JOIN_TOL_MM", "Drawing", "Region", "Ring", "arc_points", "bulge_arc",
           "circle_points", "read_drawing", "read_dxf", "read_svg"]

#: default chord error of the flattening (mm): a tenth of a usual +-0.05 mm pocket tolerance
CHORD_TOL_MM = 0.005
#: default largest gap between two chained ends (mm)
JOIN_TOL_MM = 0.001
#: accepted range of ``tolerance`` (mm): below 1e-5 mm flattening makes millions of vertices with no
#: machining meaning; above 1 mm a curve is no longer the drawn one (``join_tol`` shares the upper bound)
TOL_RANGE_MM = (1e-5, 1.0)
#: unit name -> mm per unit (the ``units=`` override of :func:`read_drawing`)
UNITS_MM = {"mm": 1.0, "inch": 25.4, "in": 25.4, "cm": 10.0, "m": 1000.0, "ft": 304.8, "um": 1e-3}
#: SVG user units (CSS px) per inch
SVG_PX_PER_INCH = 96.0


@dataclasses.dataclass(frozen=True, eq=False)
class Ring:
    """A closed outline: ``points`` (N, 2) in mm, not repeating the first point; ``entities`` names the
    drawing entities it was made of (``'LINE #2F'``, ``'path id=p1'``); ``circle`` is ``(cx, cy, r)``
    (mm) when the ring is one circle of the drawing, else None."""

    points: np.ndarray
    entities: tuple
    circle: tuple | None = None

    def polygon(self) -> Polygon:
        return Polygon(self.points)

    def describe(self) -> str:
        names = ", ".join(self.entities[:4]) + (f" and {len(self.entities) - 4} more" if len(self.entities) > 4 else "")
        return names


@dataclasses.dataclass(frozen=True, eq=False)
class Region:
    """One pocket region: an outline ``shell`` and the ``islands`` inside it (rings, mm)."""

    shell: Ring
    islands: tuple

    def polygon(self) -> Polygon:
        return Polygon(self.shell.points, [i.points for i in self.islands])


@dataclasses.dataclass(frozen=True, eq=False)
class Drawing:
    """What :func:`read_drawing` read: ``regions`` (outline + islands each, mm), the ``source`` file, the
    ``layer`` (None: all), ``units`` (the drawing's unit name), ``mm_per_unit``, ``tolerance`` and
    ``join_tol`` (mm) and ``notes`` (what was assumed or skipped)."""

    regions: tuple
    source: str
    layer: str | None
    units: str
    mm_per_unit: float
    tolerance: float
    join_tol: float
    notes: tuple = ()

    def polygon(self) -> Polygon | MultiPolygon:
        """The pocket as one shapely geometry (islands are holes; several regions: a MultiPolygon)."""
        polys = [r.polygon() for r in self.regions]
        return polys[0] if len(polys) == 1 else MultiPolygon(polys)


# -- flattening -------------------------------------------------------------------------------------
def _arc_steps(radius: float, sweep: float, tol: float) -> int:
    """Number of chords for an arc of ``radius`` and ``|sweep|`` (rad) with sagitta <= ``tol``
    (at most a quarter turn per chord)."""
    c = 1.0 - tol / radius
    dphi = 2.0 * math.acos(c) if c > -1.0 else math.pi
    return max(1, int(math.ceil(abs(sweep) / min(dphi, 0.5 * math.pi) - 1e-12)))


def arc_points(center, radius: float, start: float, sweep: float, tol: float = CHORD_TOL_MM) -> np.ndarray:
    """Points of a circular arc (mm), both ends included, chord error (sagitta) <= ``tol``.

    ``start`` and ``sweep`` in rad, ``sweep`` > 0 counter-clockwise. Vertices lie on the arc, equally
    spaced: ``n = ceil(|sweep| / (2 arccos(1 - tol / r)))`` chords.

    >>> P = arc_points((0, 0), 10.0, 0.0, math.pi / 2, tol=0.01)
    >>> len(P), P[0].tolist(), np.round(P[-1], 12).tolist()       # 2 arccos(0.999) = 0.0894 rad
    (19, [10.0, 0.0], [0.0, 10.0])
    """
    n = _arc_steps(float(radius), float(sweep), float(tol))
    a = start + sweep * np.linspace(0.0, 1.0, n + 1)
    return np.c_[center[0] + radius * np.cos(a), center[1] + radius * np.sin(a)]


def circle_points(center, radius: float, tol: float = CHORD_TOL_MM) -> np.ndarray:
    """A circle as a closed ring of points (first point not repeated), chord error <= ``tol`` (mm);
    the polygon is inscribed: its area ``n/2 r^2 sin(2 pi/n)`` is below ``pi r^2`` by less than
    ``2 pi r tol``.

    >>> P = circle_points((0, 0), 5.0, 0.005)
    >>> n = len(P); n, round(Polygon(P).area, 4), round(n / 2 * 25 * math.sin(2 * math.pi / n), 4)
    (71, 78.4373, 78.4373)
    """
    return arc_points(center, radius, 0.0, 2.0 * math.pi, tol)[:-1]


def bulge_arc(p0, p1, bulge: float):
    """The arc of a polyline bulge from ``p0`` to ``p1``: ``(center, radius, start_angle, sweep)`` (rad).

    DXF: ``bulge = tan(included angle / 4)``, positive counter-clockwise.

    >>> c, r, a0, sw = bulge_arc((0, 0), (10, 0), 1.0)              # a semicircle below the chord
    >>> np.round(c, 12).tolist(), r, round(abs(a0), 6), round(sw, 6)
    ([5.0, 0.0], 5.0, 3.141593, 3.141593)
    """
    p0, p1 = np.asarray(p0, float)[:2], np.asarray(p1, float)[:2]
    theta = 4.0 * math.atan(bulge)
    d = p1 - p0
    c = float(np.hypot(*d))
    left = np.array([-d[1], d[0]]) / c
    center = 0.5 * (p0 + p1) + left * (0.5 * c / math.tan(0.5 * theta))
    r = 0.5 * c / abs(math.sin(0.5 * theta))
    a0 = math.atan2(p0[1] - center[1], p0[0] - center[0])
    return center, r, a0, theta


def _bulge_points(pts, closed: bool, tol: float) -> np.ndarray:
    """Vertices (x, y, bulge) of a polyline -> flattened points (closed: the closing segment included,
    the start point repeated at the end)."""
    pts = [tuple(p) for p in pts]
    if closed:
        pts = pts + [pts[0]]
    out = [np.asarray(pts[0][:2], float)[None]]
    for (x0, y0, b), (x1, y1, _) in zip(pts[:-1], pts[1:]):
        if abs(b) > 1e-12 and (x0, y0) != (x1, y1):
            c, r, a0, sw = bulge_arc((x0, y0), (x1, y1), b)
            arc = arc_points(c, r, a0, sw, tol)
            arc[-1] = (x1, y1)
            out.append(arc[1:])
        else:
            out.append(np.array([[x1, y1]], float))
    return np.concatenate(out)


def _flatten_curve(point, tol: float, t0: float = 0.0, t1: float = 1.0, min_pieces: int = 8) -> np.ndarray:
    """Adaptive flattening of a parametric curve ``point(t) -> (x, y)``: ``min_pieces`` equal pieces, each
    bisected until the curve at its 1/4, 1/2 and 3/4 parameters is within ``tol`` of the chord (both
    ends included)."""
    def dist(a, b, q):
        d = b - a
        L = math.hypot(*d)
        return math.hypot(*(q - a)) if L == 0 else abs(d[0] * (q - a)[1] - d[1] * (q - a)[0]) / L

    out = [np.asarray(point(t0), float)]
    edges = np.linspace(t0, t1, min_pieces + 1)
    todo = [(a, b) for a, b in zip(edges[:-1], edges[1:])][::-1]       # a stack: the first piece on top
    while todo:
        a, b = todo.pop()
        pa, pb = out[-1], np.asarray(point(b), float)
        qs = [np.asarray(point(a + (b - a) * f), float) for f in (0.25, 0.5, 0.75)]
        if (b - a) > 1e-9 * (t1 - t0) and max(dist(pa, pb, q) for q in qs) > tol:
            m = 0.5 * (a + b)
            todo.extend([(m, b), (a, m)])
        else:
            out.append(pb)
    return np.asarray(out)


# -- chaining and nesting ---------------------------------------------------------------------------
@dataclasses.dataclass
class _Piece:
    points: np.ndarray      # (N, 2) mm, N >= 2
    name: str               # 'LINE #2F'


def _fmt(p) -> str:
    return f"({p[0]:.4f}, {p[1]:.4f})"


def _chain(pieces: list, join_tol: float, source: str) -> list:
    """Join open pieces whose ends meet within ``join_tol`` into closed rings (lists of Ring)."""
    if not pieces:
        return []
    from scipy.spatial import cKDTree     # here: every Job imports this module, few read a drawing (0.3 s)

    ends = np.array([p.points[k] for p in pieces for k in (0, -1)], float)     # end 2i: start, 2i+1: end
    tree = cKDTree(ends)
    partners = [[j for j in tree.query_ball_point(e, join_tol) if j != i] for i, e in enumerate(ends)]
    for i, ps in enumerate(partners):
        if not ps:
            d, j = tree.query(ends[i], k=2)
            which = "start" if i % 2 == 0 else "end"
            if len(ends) > 1 and np.isfinite(d[1]):
                k = int(j[1])
                near = f"the nearest end ({pieces[k // 2].name} {'start' if k % 2 == 0 else 'end'}) is {d[1]:.6g} mm away"
            else:
                near = "there is no other end"
            raise ValueError(f"{source}: open outline: {pieces[i // 2].name} {which} at {_fmt(ends[i])} meets no "
                             f"other end within the join tolerance {join_tol:g} mm: {near}")
        if len(ps) > 1:
            names = sorted({pieces[i // 2].name} | {pieces[j // 2].name for j in ps})
            raise ValueError(f"{source}: {len(ps) + 1} ends meet at {_fmt(ends[i])} ({', '.join(names)}): an "
                             "outline must be a simple closed chain (a branch or a duplicated entity)")
    used = [False] * len(pieces)
    rings = []
    for s in range(len(pieces)):
        if used[s]:
            continue
        pts, names, end = [pieces[s].points], [pieces[s].name], 2 * s + 1
        used[s] = True
        while True:
            nxt = partners[end][0]
            k = nxt // 2
            if k == s and nxt == 2 * s:
                break
            if used[k]:         # cannot happen with one partner per end; guards against a loop bug
                raise ValueError(f"{source}: the chain through {pieces[k].name} does not close")
            used[k] = True
            P = pieces[k].points if nxt % 2 == 0 else pieces[k].points[::-1]
            pts.append(P[1:])
            names.append(pieces[k].name)
            end = nxt + 1 if nxt % 2 == 0 else nxt - 1
        P = np.concatenate(pts)[:-1]          # the last point is the first one (within join_tol)
        rings.append(Ring(P, tuple(names)))
    return rings


def _closed_ring(points, name: str, circle=None) -> Ring:
    P = np.asarray(points, float)[:, :2]
    if len(P) > 1 and np.allclose(P[0], P[-1], rtol=0, atol=1e-12):
        P = P[:-1]
    return Ring(P, (name,), circle)


def _nest(rings: list, source: str) -> tuple:
    """Regions from rings by containment depth: even depth -> outline, odd -> island of its parent."""
    if not rings:
        raise ValueError(f"{source}: no closed outline found")
    polys = []
    for r in rings:
        if len(r.points) < 3:
            raise ValueError(f"{source}: the outline of {r.describe()} is not a simple polygon (fewer than 3 points)")
        poly = Polygon(r.points)
        if not poly.is_valid or poly.area <= 0:
            why = shapely.is_valid_reason(poly) if not poly.is_valid else "zero area"
            raise ValueError(f"{source}: the outline of {r.describe()} is not a simple polygon ({why})")
        polys.append(poly)
    order = sorted(range(len(rings)), key=lambda i: -polys[i].area)
    tree = shapely.STRtree(polys)
    parent, depth = {}, {}
    for i in order:
        best = None
        for j in tree.query(polys[i]):
            j = int(j)
            if j == i:
                continue
            same_area = abs(polys[j].area - polys[i].area) <= 1e-9 * polys[i].area
            if same_area and polys[i].symmetric_difference(polys[j]).area <= 1e-9 * polys[i].area:
                raise ValueError(f"{source}: the outlines of {rings[i].describe()} and {rings[j].describe()} "
                                 "coincide (a duplicated entity?)")
            if polys[j].area > polys[i].area and polys[j].contains(polys[i]):
                if best is None or polys[j].area < polys[best].area:
                    best = j
            elif polys[i].intersects(polys[j]) and not polys[i].contains(polys[j]):
                pt = shapely.get_coordinates(polys[i].boundary.intersection(polys[j].boundary))
                where = f" near {_fmt(pt[0])}" if len(pt) else ""
                raise ValueError(f"{source}: the outlines of {rings[i].describe()} and {rings[j].describe()} cross "
                                 f"or touch{where}: outlines and islands must be disjoint or nested")
        parent[i], depth[i] = best, (0 if best is None else depth[best] + 1)
    regions = []
    for i in order:
        if depth[i] % 2 == 0:
            isl = tuple(rings[k] for k in order if parent[k] == i)
            regions.append(Region(rings[i], isl))
    return tuple(regions)


# -- DXF ----------------------------------------------------------------------------------------------
_CURVES = {"LINE", "ARC", "CIRCLE", "ELLIPSE", "SPLINE", "LWPOLYLINE", "POLYLINE"}


def _planar(e, name: str, source: str):
    ext = getattr(e.dxf, "extrusion", None)
    if ext is not None and (abs(ext[0]) > 1e-9 or abs(ext[1]) > 1e-9):
        raise ValueError(f"{source}: {name} is not in the XY plane (extrusion {tuple(round(v, 6) for v in ext)}): "
                         "only 2D drawings are read")


def _to_wcs(e, pts2, z: float = 0.0) -> np.ndarray:
    """OCS (x, y) points of an entity -> WCS (x, y) (handles the mirrored extrusion (0, 0, -1))."""
    ocs = e.ocs()
    return np.array([(v.x, v.y) for v in ocs.points_to_wcs([(x, y, z) for x, y in pts2])], float)


def _dxf_entity(e, name: str, tol: float, source: str):
    """One curve entity (drawing units) -> ('closed', points, circle) or ('open', points, None)."""
    t = e.dxftype()
    _planar(e, name, source)
    if t == "LINE":
        P = np.array([tuple(e.dxf.start)[:2], tuple(e.dxf.end)[:2]], float)
        return ("open", P, None)
    if t in ("ARC", "CIRCLE"):
        c, r = tuple(e.dxf.center)[:2], float(e.dxf.radius)
        if r <= 0:
            raise ValueError(f"{source}: {name} has radius {r:g}")
        if t == "CIRCLE":
            P = _to_wcs(e, circle_points(c, r, tol), e.dxf.center[2])
            cw = _to_wcs(e, [c], e.dxf.center[2])[0]
            return ("closed", P, (float(cw[0]), float(cw[1]), r))
        a0, a1 = math.radians(e.dxf.start_angle), math.radians(e.dxf.end_angle)
        sweep = (a1 - a0) % (2 * math.pi) or 2 * math.pi
        return ("open", _to_wcs(e, arc_points(c, r, a0, sweep, tol), e.dxf.center[2]), None)
    if t == "LWPOLYLINE":
        P = _bulge_points(e.get_points("xyb"), e.closed, tol)
        P = _to_wcs(e, P, e.dxf.elevation)
        return ("closed" if e.closed else "open", P, None)
    if t == "POLYLINE":
        if not (e.is_2d_polyline or e.is_3d_polyline):
            raise ValueError(f"{source}: {name} is a polygon mesh or polyface, not an outline")
        if e.is_2d_polyline:
            verts = [(v.dxf.location[0], v.dxf.location[1], v.dxf.bulge) for v in e.vertices]
            P = _to_wcs(e, _bulge_points(verts, e.is_closed, tol), e.dxf.elevation[2])
        else:
            P = np.array([tuple(v)[:2] for v in e.points()], float)
            P = np.vstack([P, P[:1]]) if e.is_closed else P
        return ("closed" if e.is_closed else "open", P, None)
    if t == "ELLIPSE":
        full = abs(abs(e.dxf.end_param - e.dxf.start_param) - 2 * math.pi) < 1e-9
        P = np.array([(v.x, v.y) for v in e.construction_tool().flattening(tol, segments=16)], float)
        return ("closed" if full else "open", P, None)
    if t == "SPLINE":
        P = np.array([(v.x, v.y) for v in e.construction_tool().flattening(tol, segments=8)], float)
        closed = e.closed or (len(P) > 2 and np.allclose(P[0], P[-1], rtol=0, atol=1e-9))
        return ("closed" if closed else "open", P, None)
    raise AssertionError(t)


#: block references nested deeper than this are refused (a block that inserts itself loops forever)
MAX_BLOCK_DEPTH = 16


def _dxf_entities(entities, parent: str = "", parent_layer: str | None = None, depth: int = 0):
    """(entity, name, layer) of ``entities`` (the model space), block references expanded recursively
    (an entity on layer ``0`` inside a block takes the layer of its INSERT)."""
    for k, e in enumerate(entities):
        lay = e.dxf.layer if parent_layer is None or e.dxf.layer != "0" else parent_layer
        name = f"{e.dxftype()} #{e.dxf.handle}" if not parent else f"{e.dxftype()} in {parent} item {k}"
        if e.dxftype() != "INSERT":
            yield (e, name, lay)
            continue
        if depth >= MAX_BLOCK_DEPTH:
            yield (None, f"{name} (block references nested deeper than {MAX_BLOCK_DEPTH})", lay)
            continue
        try:
            subs = list(e.virtual_entities())
        except Exception as exc:          # ezdxf raises various errors on broken blocks
            yield (None, f"{name} ({exc})", lay)
            continue
        here = f"INSERT #{e.dxf.handle} ({e.dxf.name})" if not parent else f"{parent} item {k} ({e.dxf.name})"
        yield from _dxf_entities(subs, here, lay, depth + 1)


def _recover_dxf(src: str, first: Exception):
    """(document, number of fixes) of ezdxf's recover mode; ValueError naming the file if it fails too."""
    from ezdxf import recover

    try:
        doc, auditor = recover.readfile(src)
    except Exception as exc:
        raise ValueError(f"{src}: not a readable DXF file ({type(first).__name__}: {first}; recover mode: "
                         f"{type(exc).__name__}: {exc})") from None
    if auditor.has_errors:
        raise ValueError(f"{src}: not a readable DXF file (recover mode left {len(auditor.errors)} errors, "
                         f"first: {auditor.errors[0].message})")
    return doc, len(auditor.fixes)


def read_dxf(path, layer: str | None = None, tolerance: float = CHORD_TOL_MM, units: str | None = None,
             join_tol: float = JOIN_TOL_MM) -> Drawing:
    """Read the pocket outline(s) of a DXF file; see the module docstring. Lengths in mm."""
    import ezdxf
    from ezdxf import units as dxfunits

    src = str(path)
    if not Path(src).is_file():
        raise FileNotFoundError(f"{src}: no such drawing file")
    notes = []
    try:
        doc = ezdxf.readfile(src)
    except ezdxf.DXFStructureError as exc:
        # sloppy writers (e.g. header variables after ENDSEC): ezdxf's recover mode repairs the structure
        doc, fixes = _recover_dxf(src, exc)
        notes.append(f"the DXF structure was repaired by ezdxf.recover ({fixes} fixes; strict read: {exc})")
    except Exception as exc:       # ezdxf: IOError 'not a DXF file', UnicodeDecodeError, ...
        raise ValueError(f"{src}: not a readable DXF file ({type(exc).__name__}: {exc})") from None
    code = int(doc.header.get("$INSUNITS", 0) or 0)
    if units is not None:
        unit, scale = units, _units_scale(units, src)
        notes.append(f"units given as {unit} (the drawing says $INSUNITS {code})")
    elif code == 0:
        unit, scale = "unitless", 1.0
        meas = doc.header.get("$MEASUREMENT", None)
        hint = " ($MEASUREMENT 0: an imperial drawing? give units='inch')" if meas == 0 else ""
        notes.append(f"the drawing is unitless ($INSUNITS 0): read as mm{hint}")
    else:
        try:
            scale = float(dxfunits.conversion_factor(code, dxfunits.InsertUnits.Millimeters))
            unit = dxfunits.decode(code) or str(code)
        except (ValueError, KeyError):
            raise ValueError(f"{src}: $INSUNITS {code} is not a length unit ezdxf knows; give units=") from None
        if scale != 1.0:
            notes.append(f"$INSUNITS {code} ({unit}): coordinates x {scale:g} to mm")
    tol_du = tolerance / scale
    closed, pieces, skipped, layers = [], [], {}, {}
    want = None if layer is None else layer.casefold()
    for e, name, lay in _dxf_entities(doc.modelspace()):
        t = "INSERT" if e is None else e.dxftype()
        if t in _CURVES:
            layers[lay] = layers.get(lay, 0) + 1
        if want is not None and lay.casefold() != want:
            continue
        if e is None:
            raise ValueError(f"{src}: {name}: the block reference cannot be expanded")
        if t not in _CURVES:
            skipped[t] = skipped.get(t, 0) + 1
            continue
        try:
            kind, P, circ = _dxf_entity(e, name, tol_du, src)
        except ValueError as exc:
            if str(exc).startswith(src):
                raise
            raise ValueError(f"{src}: {name} cannot be read ({type(exc).__name__}: {exc})") from None
        except (ArithmeticError, LookupError, TypeError, AttributeError, ezdxf.DXFError) as exc:
            raise ValueError(f"{src}: {name} cannot be read ({type(exc).__name__}: {exc})") from None
        if not np.all(np.isfinite(P)):
            raise ValueError(f"{src}: {name} has coordinates that are not finite numbers")
        P = P * scale
        if circ is not None:
            circ = (circ[0] * scale, circ[1] * scale, circ[2] * scale)
        if kind == "closed":
            closed.append(_closed_ring(P, name, circ))
        elif float(np.hypot(*np.diff(P, axis=0).T).sum()) <= join_tol:
            skipped[f"{t} of zero length"] = skipped.get(f"{t} of zero length", 0) + 1
        else:
            pieces.append(_Piece(P, name))
    if not closed and not pieces:
        where = "in the drawing" if layer is None else f"on layer {layer!r}"
        have = ", ".join(f"{k!r} ({v})" for k, v in sorted(layers.items())) or "none"
        raise ValueError(f"{src}: no outline entity (LINE, ARC, CIRCLE, ELLIPSE, SPLINE, LWPOLYLINE, POLYLINE) "
                         f"{where}; layers with outline entities: {have}")
    if skipped:
        notes.append("skipped (not outlines): " + ", ".join(f"{v} {k}" for k, v in sorted(skipped.items())))
    rings = closed + _chain(pieces, join_tol, src)
    notes.append(f"flattened to a chord error of {tolerance:g} mm; ends joined within {join_tol:g} mm")
    return Drawing(_nest(rings, src), src, layer, unit, scale, float(tolerance), float(join_tol), tuple(notes))


def _units_scale(units: str, src: str) -> float:
    try:
        return UNITS_MM[units]
    except KeyError:
        raise ValueError(f"{src}: units {units!r} unknown: one of {sorted(UNITS_MM)}") from None


# -- SVG ----------------------------------------------------------------------------------------------
_INK_LABEL = "{http://www.inkscape.org/namespaces/inkscape}label"


def _svg_walk(node, groups):
    """(shape, names of the enclosing groups) for every shape under ``node``."""
    import svgelements as se

    for child in node:
        if isinstance(child, se.Group):
            names = [v for v in (child.values.get("id"), child.values.get(_INK_LABEL)) if v]
            yield from _svg_walk(child, groups + names)
        elif isinstance(child, se.Shape):
            yield child, groups
        elif isinstance(child, (se.Text, se.SVGImage)):
            yield type(child).__name__, groups            # not an outline: counted in the notes


def _svg_circle(shape, scale: float, height: float):
    """``(cx, cy, r)`` (mm, y flipped) of a circle or equal-radius ellipse left untransformed by reify
    (its transform folded into cx, cy, r), else None."""
    import svgelements as se

    if not isinstance(shape, (se.Circle, se.Ellipse)):
        return None
    m = shape.transform
    rx, ry = float(shape.rx), float(shape.ry)
    if not (m.is_identity() and rx > 0 and abs(rx - ry) <= 1e-12 * rx):
        return None
    return (float(shape.cx) * scale, (height - float(shape.cy)) * scale, rx * scale)


def _svg_subpaths(shape, tol_px: float):
    """Flattened subpaths of one shape: list of (points (N, 2) user units, closed)."""
    import svgelements as se

    out, cur, closed = [], None, False
    for seg in se.Path(shape):
        if isinstance(seg, se.Move):
            if cur is not None and len(cur) > 1:
                out.append((np.concatenate(cur), closed))
            cur, closed = [np.array([[seg.end.x, seg.end.y]], float)], False
            continue
        if cur is None:
            cur = [np.array([[seg.start.x, seg.start.y]], float)]
        if isinstance(seg, (se.Line, se.Close)):
            if seg.end is not None and (seg.start is None or seg.end != seg.start):
                cur.append(np.array([[seg.end.x, seg.end.y]], float))
            if isinstance(seg, se.Close):
                closed = True
                out.append((np.concatenate(cur), True))
                cur, closed = None, False
        else:
            P = _flatten_curve(lambda t, s=seg: (s.point(t).x, s.point(t).y), tol_px)
            cur.append(P[1:])
    if cur is not None and len(cur) > 1:
        out.append((np.concatenate(cur), closed))
    return out


#: mm per unit of an SVG length (CSS: 96 px = 1 in = 72 pt = 6 pc)
_SVG_LENGTH_MM = {"mm": 1.0, "cm": 10.0, "in": 25.4, "pt": 25.4 / 72, "pc": 25.4 / 6, "px": 25.4 / 96, "": 25.4 / 96}


def _svg_mm_per_px(svg) -> float:
    """mm per px of the parsed document, exact from its ``width`` attribute (svgelements rounds mm to
    3.7795296 px); 25.4/96 without a physical width."""
    m = re.fullmatch(r"\s*([0-9.eE+-]+)\s*(mm|cm|in|pt|pc|px|)\s*", str(svg.values.get("width") or ""))
    try:
        w_mm = float(m.group(1)) * _SVG_LENGTH_MM[m.group(2)] if m else None
    except ValueError:
        w_mm = None
    if w_mm and svg.width and math.isfinite(w_mm) and w_mm > 0:
        return w_mm / float(svg.width)
    return 25.4 / SVG_PX_PER_INCH


def read_svg(path, layer: str | None = None, tolerance: float = CHORD_TOL_MM, units: str | None = None,
             join_tol: float = JOIN_TOL_MM) -> Drawing:
    """Read the pocket outline(s) of an SVG file; see the module docstring. Lengths in mm.

    ``units`` (e.g. ``'mm'``) overrides the physical size: one user unit is then one such unit."""
    import svgelements as se

    src = str(path)
    if not Path(src).is_file():
        raise FileNotFoundError(f"{src}: no such drawing file")
    try:
        svg = se.SVG.parse(src, reify=True, ppi=SVG_PX_PER_INCH)
    except Exception as exc:           # xml.etree.ElementTree.ParseError and svgelements' own errors
        raise ValueError(f"{src}: not a readable SVG file ({type(exc).__name__}: {exc})") from None
    if not isinstance(svg, se.SVG):
        raise ValueError(f"{src}: not a readable SVG file (no <svg> root element)")
    notes = []
    if units is not None:
        # svgelements already mapped the viewBox to px: undo the physical size, keep user units
        scale = _units_scale(units, src)
        vb = getattr(svg, "viewbox", None)
        k = (vb.width / svg.width) if (vb is not None and svg.width) else 1.0
        scale *= k
        unit = f"{units} per user unit"
    else:
        scale, unit = _svg_mm_per_px(svg), "px (96 per inch) after the document's size and viewBox"
    notes.append(f"SVG lengths: {unit}; y flipped (SVG's y points down)")
    tol_px = tolerance / scale
    height = float(svg.height) if getattr(svg, "height", None) else 0.0
    closed, pieces, n_shapes, names, skipped = [], [], 0, set(), {}
    for k, (shape, groups) in enumerate(_svg_walk(svg, [])):
        names.update(groups)
        if layer is not None and layer not in groups:
            continue
        if isinstance(shape, str):
            skipped[shape] = skipped.get(shape, 0) + 1
            continue
        sid = shape.values.get("id") or f"#{k}"
        kind = type(shape).__name__.lower()
        try:
            subpaths = _svg_subpaths(shape, tol_px)
        except (ArithmeticError, LookupError, TypeError, AttributeError, ValueError) as exc:
            raise ValueError(f"{src}: {kind} id={sid} cannot be read ({type(exc).__name__}: {exc})") from None
        for m, (P, is_closed) in enumerate(subpaths):
            if not np.all(np.isfinite(P)):
                raise ValueError(f"{src}: {kind} id={sid} has coordinates that are not finite numbers")
            n_shapes += 1
            P = np.c_[P[:, 0] * scale, (height - P[:, 1]) * scale]
            name = f"{kind} id={sid}" + (f" subpath {m}" if m else "")
            if is_closed or (len(P) > 2 and np.hypot(*(P[0] - P[-1])) <= join_tol):
                closed.append(_closed_ring(P, name, _svg_circle(shape, scale, height)))
            else:
                pieces.append(_Piece(P, name))
    if n_shapes == 0:
        where = "in the drawing" if layer is None else f"in a group with id or inkscape:label {layer!r}"
        raise ValueError(f"{src}: no path or shape {where}; groups: {', '.join(sorted(names)) or 'none'}")
    if skipped:
        notes.append("skipped (not outlines): " + ", ".join(f"{v} {k}" for k, v in sorted(skipped.items())))
    rings = closed + _chain(pieces, join_tol, src)
    notes.append(f"flattened to a chord error of {tolerance:g} mm; ends joined within {join_tol:g} mm")
    return Drawing(_nest(rings, src), src, layer, unit, scale, float(tolerance), float(join_tol), tuple(notes))


def read_drawing(path, layer: str | None = None, tolerance: float = CHORD_TOL_MM, units: str | None = None,
                 join_tol: float = JOIN_TOL_MM) -> Drawing:
    """Read a DXF (``.dxf``) or SVG (``.svg``) drawing: the closed outlines on ``layer`` (None: every
    layer) as regions of an outline with islands, in mm, flattened to ``tolerance`` (mm chord error).
    Errors: ``ValueError`` naming the file and the entity; a missing file ``OSError``."""
    for name, v, lo in (("tolerance", tolerance, TOL_RANGE_MM[0]), ("join_tol", join_tol, 0.0)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and lo <= v <= TOL_RANGE_MM[1] and v > 0):
            raise ValueError(f"{path}: {name} must be a number of mm in ({lo:g}, {TOL_RANGE_MM[1]:g}], got {v!r}")
    suffix = Path(path).suffix.lower()
    if suffix == ".dxf":
        return read_dxf(path, layer, tolerance, units, join_tol)
    if suffix == ".svg":
        return read_svg(path, layer, tolerance, units, join_tol)
    raise ValueError(f"{path}: a drawing must be a .dxf or .svg file (got {suffix or 'no suffix'!r})")
