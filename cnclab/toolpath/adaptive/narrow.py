"""Narrow regions by Thesis IV's constant-engagement trochoid (issue 29 item 5).

Where the tool-centre region is too narrow for an engagement-controlled pass at theta -- its
half-width ``c`` (distance from its medial axis to its boundary) at most ``NARROW_HALF_WIDTH_FRAC``
r, i.e. a pocket at most 2 D wide: channels and slots of 1-2 D, necks, the fingers of a comb -- the
controller of the level planner cannot turn inside it (its tightest turn is 0.8 r) and enters again
and again. Such a region is cut instead by Jacsó's constant-engagement trochoid (2021, Thesis IV:
:func:`cnclab.toolpath.trochoidal.ce_trochoid`, the converged period repeated at the step whose
simulated maximum engagement stays at theta) laid along the region's medial axis, at the same theta.

Steps (one role: the narrow regions, from detection to their moves):

* **detection** (:func:`narrow_regions`): the wide part of the tool-centre region is its
  morphological opening by ``c_max`` (every disc of radius ``c_max`` inside it: where a pass can
  turn); a connected rest whose medial axis is at least ``NARROW_MIN_LENGTH_FRAC`` r long is a
  narrow region (the other rests are the corners every pocket has);
* **medial axis** (:func:`medial_axis`): the Voronoi diagram of the densified boundary
  (``shapely.voronoi_polygons(only_edges=True)``, GEOS), its edges inside the region, the longest
  path of that tree (networkx, two Dijkstra sweeps), the spurs into corners trimmed (where the
  inscribed radius grows faster than ``SPUR_SLOPE`` per mm), resampled and smoothed;
* **trochoid along the axis** (:func:`axis_trochoid`): the straight-slot period for the pocket
  width ``2 (c_min + r)`` (the narrowest place of the axis, less one planning pixel), repeated at
  its admissible step in arc length along the axis, each local point (x, y) mapped to
  ``C(s0 + x) + y N(s0 + x)`` (C the axis, N its left normal: the pattern's climb side kept), the
  periods laid closer on bends (:func:`bend_step`: the outer side of a bend is spaced 1 + kappa c
  wider than the axis; at most ``BEND_STRETCH`` x the slot's step), points that a bend or an end
  pushes outside the tool-centre region projected back on it; towards a closed end the axis runs on
  to c - h of the tool-centre limit and the last period, shorter than the step, lands its front
  there (the face is reached, not left up to a step short);
* **order** (:mod:`.narrow_level`: ``LevelRegions``, ``next_region``): at the start of a level every region
  leaves the level planner's view (its tool-centre pixels leave the grid's mask, the material only
  centres inside it can reach leaves the planning stock, the finish parts holding it wait), so the
  passes clear the wide parts without crawling into it. When the planner has nothing left within
  reach through cleared area, a region whose open end (a mouth) the tool reaches through cleared
  area is put back and cut from there -- the tool linked to the free point nearest the mouth from
  which the first periods' returns, swinging c to either side across the axis, meet no material
  (a free capsule) and whose leg to the mouth holds the pattern's band inside the tool-centre
  region, the leg joined to the axis by a rounded bend (:func:`join_axis`) -- with no lift;
  the wide part behind it is then reached through the cleared slot. Only when no place is left to
  enter is a region entered by a helix at its axis start (a closed end first), opened to the slot's
  width by a spiral out (each turn gaining what keeps the engagement at theta: :func:`spiral_out`) and
  a circle;
* **moves** (:mod:`.narrow_level`: ``cut_region``, ``emit_trochoid``): the trochoid's cutting moves at the
  booklet's feed control (§4: roll-in, roll-out and the cutting part of the return hold the nominal
  MRR, up to ``v_fmax``), its returns through air as one G0 chord where the rapid stock proves it
  (with short feed legs off the cut boundary), else feed links; the planning stock is cut as it
  goes, so that the level planner continues from the cleared slot. Each region cut is named in the
  plan's ``info["narrow_regions"]`` and (``info["notes"]``) in the program header.

Units: mm, deg, mm/min; ``r`` the tool radius.

A 60 x 12 mm channel, D = 8 mm: the tool-centre region is 52 x 4 mm, its axis runs from 2 mm
inside one end to 2 mm inside the other (60 - 2 r - 2 c = 48 mm):

>>> from shapely.geometry import box
>>> regs = narrow_regions(box(0, 0, 60, 12).buffer(-4.0, join_style="mitre"), 4.0)
>>> len(regs), round(regs[0].c_min, 1), round(regs[0].length, 0), regs[0].dead
(1, 2.0, 48.0, (True, True))
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import networkx as nx
import numpy as np
import shapely
from shapely.geometry import LineString, MultiPoint, Point

from ..constant_engagement import clamp_to_region
from ..helix import helix_entry  # noqa: F401  (re-exported: the package's one entry helix)
from ...cutting.feed_control import controlled_feed
from ..trochoidal import ce_trochoid, evaluate_pattern, pattern_kinds, period_index

__all__ = ["NarrowRegion", "narrow_regions", "medial_graph", "medial_axis", "trochoid_period", "axis_trochoid",
           "width_classes", "along", "bend_step", "join_axis", "spiral_out", "helix_entry",
           "NARROW_HALF_WIDTH_FRAC", "NARROW_MIN_LENGTH_FRAC"]

# the narrow regions at one level (their order, their cut, the period check): narrow_level.py

#: a region is narrow where the tool-centre half-width c <= this x r (pocket width <= 2 D): the
#: controller's tightest turn is 0.8 r, so a pass cannot turn round inside a band of half-width r
NARROW_HALF_WIDTH_FRAC = 0.75
#: ... its axis ends where the half-width falls below this x r (the tip of a wedge is the finishing
#: lap's: a trochoid there would crawl at the step of a slot only a few hundredths of r wider than the tool)
NARROW_MIN_HALF_WIDTH_FRAC = 0.2
#: ... and its medial axis is at least this x r long (shorter rests are the corners of any pocket)
NARROW_MIN_LENGTH_FRAC = 3.0
#: the medial axis is cut off where the inscribed radius grows faster than this (mm per mm) towards
#: its end: a spur into a corner of the region (a 90 deg corner: sin 45 deg = 0.71; a taper: < 0.2)
SPUR_SLOPE = 0.4
#: a step of the straight-slot period removing at most this (mm^2 per mm of path) is a return
#: through air (a link at the link feed)
AIR_MM2_PER_MM = 1e-3
#: a width class whose admissible step is below this x a_e (= r (1 - cos theta)) ends the trochoid
#: (Thesis IV's pattern in a slot barely wider than the tool crawls: a 0.03 mm step = 0.01 a_e
#: measured at c = 0.2 r, theta 101.5 deg; 0.098 mm = 0.18 a_e at theta 30.7 deg still pays); the
#: rest of the axis is left to the level planner
MIN_STEP_FRAC = 0.1
#: on a bend the periods are laid closer (:func:`bend_step`) so that their spacing on the outer side
#: stays near the straight-slot step; never closer than this x that step (a kink of angle a then still
#: spaces the outer side by c a more: the axis is smoothed, see :func:`join_axis`)
MIN_BEND_STEP_FRAC = 0.1
#: ... and only as close as needed for the outer side's spacing to stay at most this x that step:
#: tight bends only (kappa c > 0.3: a mouth's joined leg, kappa c ~ 1). Measured on the corpus (one run
#: each): 1.0 costs 3-5 % program time on the curved/spiral 1.5 D channels; 1.15 none, but leaves more
#: uncut where the periods' spacing changes (slot_bulbs_0 1.37 -> 1.75 mm^2, FreeCAD 0.90; comb_3
#: 5.54 -> 6.48) for 1-3 deg less max; 1.3: slot_bulbs_0 1.37, comb_3 5.71 mm^2 (max 101.9, 103.0
#: without bend_step, theta 94.9), the spiral channel as without bend_step
BEND_STRETCH = 1.3
#: a mouth's free point is joined to the axis by a moving average over this x c a mm (c the
#: half-width, a the corner's turn; :func:`join_axis`): a bend of tightest radius ~0.6 x this x c
#: (0.89 mm at c = 1 mm, a 90 deg corner), so the pattern's inner side hardly folds over its centre
JOIN_RADIUS_C = 1.5
#: ... where the leg turns by more than this (deg): a gentler corner is left to :func:`bend_step`
#: (rounding every joint changed the passes after it: a neck test's max 68.6 -> 71.0 deg at theta 60)
JOIN_MIN_TURN_DEG = 30.0
#: free cells tried (nearest first) for the start of a trochoid at a mouth onto cleared area
MOUTH_CANDIDATES = 200
#: branches of one narrow part's medial tree given a trochoid of their own (narrow_regions(branches=True)):
#: a comb's fingers
MAX_BRANCHES = 8
#: boundary sampling of the Voronoi medial axis, x the planning pixel h (and at most r / 8)
AXIS_SPACING_H = 4.0


@dataclass
class NarrowRegion:
    """A narrow part of the tool-centre region: ``polygon`` (its tool-centre area, mm), ``axis``
    (n, 2) its medial axis from ``start`` to the other end, ``radius`` (n,) the inscribed radius c
    at each axis point (mm), ``dead`` which ends are closed (start, end: no wide area there)."""
    index: int
    polygon: object
    axis: np.ndarray
    radius: np.ndarray
    dead: tuple
    #: a branch of a narrow part's medial tree (narrow_regions(branches=True)): its open end lies at
    #: the trunk's slot, not at a wide area
    branch: bool = False

    @property
    def length(self) -> float:
        return float(np.hypot(*np.diff(self.axis, axis=0).T).sum())

    @property
    def c_min(self) -> float:
        return float(self.radius.min())

    def reversed(self) -> "NarrowRegion":
        return NarrowRegion(self.index, self.polygon, self.axis[::-1].copy(), self.radius[::-1].copy(),
                            self.dead[::-1], self.branch)

    def describe(self, r) -> str:
        """One line for the program header and the plan result (``r`` the tool radius, mm)."""
        a, b = self.axis[0], self.axis[-1]
        return (f"narrow region {self.index}: Thesis IV trochoid along its medial axis "
                f"({a[0]:.1f}, {a[1]:.1f}) -> ({b[0]:.1f}, {b[1]:.1f}), {self.length:.1f} mm, "
                f"narrowest {2 * (self.c_min + r):.2f} mm wide")


def _longest_path(G):
    """Longest shortest path of a tree-like graph (two Dijkstra sweeps): node list."""
    n0 = next(iter(G.nodes))
    d = nx.single_source_dijkstra_path_length(G, n0, weight="w")
    a = max(d, key=d.get)
    d, paths = nx.single_source_dijkstra(G, a, weight="w")
    b = max(d, key=d.get)
    return paths[b]


def _smooth(P, spacing):
    """Polyline P resampled every ``spacing`` mm and smoothed by a 5-point moving average (ends kept)."""
    line = LineString(P)
    n = max(int(math.ceil(line.length / spacing)), 2)
    Q = shapely.get_coordinates(shapely.line_interpolate_point(line, np.linspace(0, line.length, n + 1)))
    if len(Q) >= 5:
        S = Q.copy()
        S[2:-2] = (Q[:-4] + Q[1:-3] + Q[2:-2] + Q[3:-1] + Q[4:]) / 5.0
        Q = S
    return Q


def _trim_spurs(P, c):
    """Index range of the axis P (n, 2) without its end spurs: ends where c grows faster than
    SPUR_SLOPE (mm per mm) towards the middle (a spur into a corner) are dropped."""
    s = np.r_[0.0, np.cumsum(np.hypot(*np.diff(P, axis=0).T))]
    i0, i1 = 0, len(P) - 1
    while i0 < i1 - 1 and (c[i0 + 1] - c[i0]) > SPUR_SLOPE * (s[i0 + 1] - s[i0]):
        i0 += 1
    while i1 > i0 + 1 and (c[i1 - 1] - c[i1]) > SPUR_SLOPE * (s[i1] - s[i1 - 1]):
        i1 -= 1
    return i0, i1


def medial_graph(region, spacing):
    """Medial-axis graph of the polygon ``region`` (mm): the Voronoi edges of its boundary sampled
    every ``spacing`` mm (``shapely.voronoi_polygons(only_edges=True)``) that lie inside it, as a
    networkx Graph (nodes (x, y), edge weight ``w`` = length mm; node attribute ``c`` = distance to
    the boundary, mm): the approximation of the medial axis that converges as ``spacing`` -> 0."""
    dense = shapely.segmentize(region, spacing)
    pts = np.unique(np.round(shapely.get_coordinates(dense.boundary), 9), axis=0)
    G = nx.Graph()
    if len(pts) < 4:
        return G
    edges = shapely.get_parts(shapely.voronoi_polygons(MultiPoint(pts), only_edges=True))
    shapely.prepare(region)
    edges = edges[shapely.contains(region, edges)]
    for e in edges:
        q = np.round(shapely.get_coordinates(e), 7)
        for a, b in zip(q[:-1], q[1:]):
            w = float(np.hypot(*(b - a)))
            if w > 0:
                G.add_edge(tuple(a), tuple(b), w=w)
    if G.number_of_nodes():
        nodes = list(G.nodes)
        c = shapely.distance(region.boundary, shapely.points(np.array(nodes, float)))
        nx.set_node_attributes(G, dict(zip(nodes, c.tolist())), "c")
    return G


def medial_axis(region, spacing, G=None, keep=None):
    """Medial axis of ``region`` (mm) as one polyline: the longest path of its medial graph
    (:func:`medial_graph`, or the given ``G`` restricted to the nodes ``keep``), its corner spurs
    trimmed, resampled and smoothed. Returns (axis (n, 2), c (n,) distance to the boundary of
    ``region``), or None.

    >>> from shapely.geometry import box
    >>> P, c = medial_axis(box(0, 0, 40, 4), 0.5)
    >>> bool(abs(P[:, 1] - 2).max() < 0.05), round(float(np.median(c)), 2)
    (True, 2.0)
    """
    G = medial_graph(region, spacing) if G is None else G
    if keep is not None:
        G = G.subgraph(keep)
    if G.number_of_edges() == 0:
        return None
    G = G.subgraph(max(nx.connected_components(G), key=len))
    P = np.array(_longest_path(G), float)
    c = np.array([G.nodes[tuple(p)]["c"] for p in P]) if "c" in G.nodes[tuple(P[0])] else \
        shapely.distance(region.boundary, shapely.points(P))
    i0, i1 = _trim_spurs(P, c)
    P = P[i0:i1 + 1]
    if len(P) < 2:
        return None
    P = _smooth(P, max(spacing, 0.25 * float(np.median(c[i0:i1 + 1]))))
    return P, shapely.distance(region.boundary, shapely.points(P))


def narrow_regions(allowed, r, h=None, half_width_frac=NARROW_HALF_WIDTH_FRAC,
                   min_length_frac=NARROW_MIN_LENGTH_FRAC, branches=False) -> list:
    """The narrow regions of the tool-centre region ``allowed`` (pocket shrunk by the tool radius
    ``r``, mm): see the module docstring. ``h``: planning pixel (mm, default r/60). A list of
    :class:`NarrowRegion`, axes running from a closed (dead) end where there is one.

    The medial graph is built once on the whole region (so that the axis runs on through the mouth
    of a narrow part into the wide part with its true radius); each narrow part keeps the nodes of
    radius at most ``half_width_frac`` r inside it. ``branches``: each narrow part gives its trunk and
    its branches (:func:`_branch_axes`), else its longest medial path only."""
    h = r / 60.0 if h is None else float(h)
    c_max = half_width_frac * r
    wide = allowed.buffer(-c_max, quad_segs=16).buffer(c_max, quad_segs=16)
    rest = allowed.difference(wide.buffer(h))
    parts = [p for p in sorted(shapely.get_parts(rest), key=lambda p: -p.area)
             if p.area >= (min_length_frac * r) * (0.2 * r)]
    if not parts:
        return []
    spacing = min(AXIS_SPACING_H * h, r / 8.0)
    G = medial_graph(allowed, spacing)
    if G.number_of_nodes() == 0:
        return []
    nodes = np.array(list(G.nodes), float)
    cn = np.array([G.nodes[tuple(p)]["c"] for p in nodes])
    out = []
    for part in parts:
        near = part.buffer(2 * h)
        inside = shapely.contains_xy(near, nodes[:, 0], nodes[:, 1]) & (cn <= c_max * 1.02)
        axes = _branch_axes(allowed, spacing, G, nodes[inside], r, min_length_frac * r, c_max,
                            MAX_BRANCHES if branches else 0)
        polys = _branch_polygons(part, [a[0] for a, _ in axes], c_max, h)
        for ((P, c), junction), poly in zip(axes, polys):
            ok = np.flatnonzero(c >= NARROW_MIN_HALF_WIDTH_FRAC * r + 2 * h)
            if len(ok) < 2:
                continue
            P, c = P[ok[0]:ok[-1] + 1], c[ok[0]:ok[-1] + 1]
            if float(np.hypot(*np.diff(P, axis=0).T).sum()) < min_length_frac * r or c.min() < NARROW_MIN_HALF_WIDTH_FRAC * r:
                continue
            dead = tuple(bool(wide.is_empty or wide.distance(Point(*p)) > 2 * c_max) for p in (P[0], P[-1]))
            if junction is not None:      # a branch: its end at the trunk opens onto the trunk's slot
                at_start = np.hypot(*(P[0] - junction)) <= np.hypot(*(P[-1] - junction))
                dead = (False, dead[1]) if at_start else (dead[0], False)
            reg = NarrowRegion(len(out), poly, P, c, dead, junction is not None)
            out.append(reg.reversed() if (dead[1] and not dead[0]) else reg)
    return out


def _branch_axes(allowed, spacing, G, nodes, r, min_len, c_max, max_branches):
    """The medial axes of one narrow part: its longest path (the trunk, as :func:`medial_axis`), then
    each branch of its medial tree at least ``min_len`` mm long that the trunk's slot does not cover
    (the middle bar of an E, the far half of a T's bar): the longest path of each connected rest of
    the graph once the nodes within c_max + r/4 of an axis already taken are removed, at most
    ``max_branches`` (0: the trunk only). A list of ((axis, c), junction point (2,) or None for the
    trunk)."""
    keep = [tuple(p) for p in nodes]
    trunk = medial_axis(allowed, spacing, G, keep)
    if trunk is None:
        return []
    out, taken = [(trunk, None)], [trunk[0]]
    for _ in range(max_branches):
        cover = shapely.union_all([LineString(a).buffer(c_max + 0.25 * r) for a in taken])
        rest = nodes[~shapely.contains_xy(cover, nodes[:, 0], nodes[:, 1])]
        if len(rest) < 2:
            break
        H = G.subgraph([tuple(p) for p in rest])
        comps = sorted((cc for cc in nx.connected_components(H) if len(cc) > 1), key=len, reverse=True)
        best = None
        for cc in comps:
            ax = medial_axis(allowed, spacing, H.subgraph(cc))
            if ax is not None and float(np.hypot(*np.diff(ax[0], axis=0).T).sum()) >= min_len:
                best = ax
                break
        if best is None:
            break
        ends = np.array([best[0][0], best[0][-1]])
        dist = [min(float(LineString(a).distance(Point(*e))) for a in taken) for e in ends]
        out.append((best, ends[int(np.argmin(dist))]))
        taken.append(best[0])
    return out


def _branch_polygons(part, axes, c_max, h):
    """The tool-centre area of each axis of one narrow part: a branch keeps the part's area within
    c_max + 2 h of its axis (beyond the trunk's share); the trunk keeps the rest."""
    if len(axes) <= 1:
        return [part] * len(axes)
    polys = [None] * len(axes)
    rest = part
    for k in range(1, len(axes)):
        polys[k] = part.intersection(LineString(axes[k]).buffer(c_max + 2 * h)).difference(
            LineString(axes[0]).buffer(c_max + 2 * h))
        rest = rest.difference(polys[k])
    polys[0] = rest
    return polys


@lru_cache(maxsize=32)
def trochoid_period(width, r, theta_deg, h, vmax_ratio=1.0):
    """The converged Thesis IV period for a straight slot of ``width`` (mm) and tool radius ``r``
    at ``theta_deg``, planned on a dixel of ``h`` mm, with the booklet's feed control (§4: the
    roll-in, roll-out and the return's approach hold the nominal MRR, their feed raised up to
    ``vmax_ratio`` x the nominal; :func:`cnclab.cutting.feed_control.controlled_feed` on the simulated
    steady period of :func:`cnclab.toolpath.trochoidal.evaluate_pattern`).

    Returns (points (m, 2) with min x = 0, kinds (m,) ``cut`` or ``link`` (a step of the steady
    period that removes nothing), feed factors (m,) x the nominal feed (NaN on links), step mm), or
    None when Thesis IV has no pattern for this slot at ``theta_deg``: in a slot barely wider than
    the tool the converged period's engagement exceeds theta at every step down to the step search's
    tolerance (``ce_admissible_step``: "below the engagement of the smallest step"), or the
    iteration finds fewer than three complete periods -- :func:`ce_trochoid` raises ValueError for
    both (its arguments are valid here: a positive width, radius and pixel), and such a width is
    left to the level planner like a crawl (``MIN_STEP_FRAC``). Cached: a corpus of jobs repeats widths."""
    try:
        p = ce_trochoid(width, r, theta_deg, n_periods=5, resolution_mm=h)
    except ValueError:
        return None
    per = period_index(p)
    k0, k3 = per == 0, per == 3
    P = p.xyz[k0, :2]
    df, _ = evaluate_pattern(p, width, r, h)
    kinds = pattern_kinds(p)
    rem, ds, eng = (df[c].to_numpy() for c in ("removed_mm2", "ds", "engagement_deg"))
    air = rem <= AIR_MM2_PER_MM * ds
    a_e = r * (1.0 - math.cos(math.radians(theta_deg)))
    v = controlled_feed(rem, ds, eng, ~air, a_e, 1.0, max(float(vmax_ratio), 1.0), theta_deg,
                        adjust=np.isin(kinds, ["roll-in", "roll-out", "link"]))
    f3, a3 = v[k3], air[k3]
    n = int(k0.sum())
    if len(f3) != n - 1:        # the steady period lacks its first point (the previous return's end)
        raise RuntimeError(f"period 3 has {len(f3)} points, period 0 {n}")
    F = np.r_[f3[-1], f3]
    A = np.r_[a3[-1], a3]
    K = np.where(A, "link", "cut").astype(object)
    return P - np.array([P[:, 0].min(), 0.0]), K, np.where(A, np.nan, F), float(p.info["step"])


def _frame(axis):
    """Arc length s (n,) and unit tangents (n, 2) of the polyline ``axis``."""
    s = np.r_[0.0, np.cumsum(np.hypot(*np.diff(axis, axis=0).T))]
    T = np.gradient(axis, s, axis=0)
    return s, T / np.hypot(*T.T)[:, None]


def along(axis, s_q, y_q):
    """Map local pattern coordinates (arc length ``s_q`` mm along ``axis``, left offset ``y_q`` mm)
    to the plane: ``C(s) + y N(s)``, the axis extended straight beyond its ends.

    >>> along(np.array([[0.0, 0.0], [10.0, 0.0]]), np.array([2.0, 12.0]), np.array([1.0, -1.0])).tolist()
    [[2.0, 1.0], [12.0, -1.0]]
    """
    s, T = _frame(axis)
    ang = np.unwrap(np.arctan2(T[:, 1], T[:, 0]))
    sq = np.asarray(s_q, float)
    a = np.interp(sq, s, ang)
    C = np.c_[np.interp(sq, s, axis[:, 0]), np.interp(sq, s, axis[:, 1])]
    lo, hi = sq < 0, sq > s[-1]
    C[lo] = axis[0] + sq[lo, None] * T[0]
    C[hi] = axis[-1] + (sq[hi] - s[-1])[:, None] * T[-1]
    return C + np.asarray(y_q, float)[:, None] * np.c_[-np.sin(a), np.cos(a)]


def width_classes(region: NarrowRegion, q, span):
    """Runs of the axis cut with one pattern: [(s_from, s_to, c)] in arc length (mm), c the half-width
    of the tool-centre region the pattern is made for: the smallest c within ``span`` mm of each axis
    point (the pattern reaches that far along the axis), rounded down to a multiple of ``q`` mm (at
    most q of wall rest), runs shorter than ``span`` merged into their narrower neighbour."""
    s = np.r_[0.0, np.cumsum(np.hypot(*np.diff(region.axis, axis=0).T))]
    c = region.radius
    cw = np.array([c[(s >= si - span) & (s <= si + span)].min() for si in s])
    cls = np.maximum(np.floor(cw / q) * q, c.min())
    runs = []
    for i in range(len(s)):
        if runs and runs[-1][2] == cls[i]:
            runs[-1][1] = s[i]
        else:
            runs.append([s[i - 1] if i else 0.0, s[i], cls[i]])
    merged = True
    while merged and len(runs) > 1:
        merged = False
        for i, (a, b, cc) in enumerate(runs):
            if b - a < span:
                j = i - 1 if i == len(runs) - 1 or (i > 0 and runs[i - 1][2] < runs[i + 1][2]) else i + 1
                runs[j] = [min(runs[j][0], a), max(runs[j][1], b), min(runs[j][2], cc)]
                del runs[i]
                merged = True
                break
    return [tuple(r_) for r_ in runs]


def bend_step(s, ang, x0, x_ext, y_ext, step, h):
    """Arc-length step (mm) from the period at ``x0`` to the next along an axis of arc length ``s``
    (n,) mm and unwrapped tangent angle ``ang`` (n,) rad, for a pattern spanning local x in [0,
    ``x_ext``] and |y| <= ``y_ext`` (mm) whose straight-slot step is ``step`` (mm).

    :func:`along` moves the point (x, y) of the next period by ``|C(u + d) - C(u)| + |y| |ang(u + d)
    - ang(u)|`` at most (u = x0 + x, d the step): on a bend the outer side of the pattern is spaced
    wider than the axis (by 1 + kappa c on an arc of curvature kappa), and the engagement there
    exceeds theta (measured: 124.6-131.9 deg at theta 60 where a mouth's link joined the axis at 67
    deg). The largest d with ``d + y_ext max_u |ang(u + d) - ang(u)| <= step`` (u sampled every
    ``h`` mm) keeps every point of the pattern within the straight-slot step of the previous period
    (fixed-point iteration from d = step, decreasing), at least ``MIN_BEND_STEP_FRAC`` step.

    >>> s = np.linspace(0.0, 10.0, 101)
    >>> round(bend_step(s, np.zeros(101), 2.0, 2.0, 1.0, 0.2, 0.05), 9)     # straight: the step
    0.2
    >>> round(bend_step(s, 0.5 * s, 2.0, 2.0, 1.0, 0.2, 0.05), 3)          # kappa 0.5, c 1: 1.3 step / 1.5
    0.173
    """
    u = np.arange(x0, x0 + x_ext + h, h)
    a0 = np.interp(u, s, ang)
    d = step
    for _ in range(8):
        spread = float(np.abs(np.interp(u + d, s, ang) - a0).max())
        nd = max(min(BEND_STRETCH * step * d / (d + y_ext * spread), step), MIN_BEND_STEP_FRAC * step)
        if nd >= d - 1e-6:
            break
        d = nd
    return d


def axis_trochoid(region: NarrowRegion, allowed, r, theta_deg, h, s_start=None, s_end=None, q=None, hole_mm=0.0,
                  vmax_ratio=1.0, check=None):
    """The trochoid of ``region`` (module docstring): (points (m, 2) mm, kinds (m,) of cut / link
    (the pattern's return through the slot), feed factors (m,) x the nominal feed (NaN: link, see
    :func:`trochoid_period`), the steps used (mm), number of points projected back into ``allowed``).
    Periods start at arc length ``s_start`` (mm) and follow each other (:func:`bend_step` apart) while the
    period's front (its largest local x) stays at most ``s_end`` (default: the axis end); each run of
    :func:`width_classes` (``q`` mm, default r/10) with the period made for its width. ``s_start``
    None: the first period's front one step beyond a hole of radius ``hole_mm`` (the helix's, tool
    centre) about the axis start. ``check``: None, or a callable ``check(points (m, 2) mm, cutting (m,)
    bool, first) -> bool`` asked for every period (its points in the plane; after the first, from
    the previous period's last point): False refuses it -- it is laid again at half the arc-length
    step, down to ``MIN_BEND_STEP_FRAC`` x the step, and a period still refused there (or a refused
    first period) ends the trochoid (the rest of the axis is left to the level planner; see
    :class:`PeriodCheck`)."""
    s_end = region.length if s_end is None else s_end
    q = 0.1 * r if q is None else q
    X, Y, K, F, steps = [], [], [], [], []
    x0, stop_all, x_prev = s_start, False, None
    s_ax, T_ax = _frame(region.axis)
    ang_ax = np.unwrap(np.arctan2(T_ax[:, 1], T_ax[:, 0]))
    for (a, b, cc) in width_classes(region, q, 2.0 * r):
        period = trochoid_period(round(2.0 * (cc + r), 3), float(r), float(theta_deg), float(h),
                                 round(float(vmax_ratio), 3))
        if period is None or period[3] < MIN_STEP_FRAC * r * (1.0 - math.cos(math.radians(theta_deg))):
            break           # no step at theta, or too slow a crawl: the rest of the axis is left to the level planner
        P0, kinds0, F0, step = period
        x_ext = float(P0[:, 0].max())
        if x0 is None:
            x0 = hole_mm + step - x_ext
        stop = s_end if b >= region.length - 1e-9 else b
        closing_end = b >= region.length - 1e-9 and s_end > region.length
        steps.append(step)
        # period k runs from its roll-in start to the next period's (its return link included): the
        # periods join end to start, the first point of each after the first dropped
        last_front, d = -math.inf, step
        while x0 + x_ext <= stop + 1e-9 or not X or (closing_end and last_front < stop - 0.5 * h):
            if x0 + x_ext > stop + 1e-9 and X:
                # the axis end (a dead end, extended to c - h of the tool-centre limit by the caller): one
                # more period, shorter than the step, whose front lands on it -- the face is reached, not
                # left up to a step short of it (its engagement is below theta: less material ahead)
                x0 = stop - x_ext
            first = not X
            Xk, Yk, Kk, Fk = [], [], [], []
            if not first:        # a straight return to this pattern's start (a width change: a new shape)
                last = np.array([X[-1][-1], Y[-1][-1]])
                S = np.array([P0[0, 0] + x0, P0[0, 1]])
                m = max(int(math.ceil(np.hypot(*(S - last)) / (2 * h))), 1)
                t = np.linspace(0, 1, m + 1)[1:]
                Xk.append(last[0] + t * (S[0] - last[0])); Yk.append(last[1] + t * (S[1] - last[1]))
                Kk.append(np.full(m, "link", dtype=object)); Fk.append(np.full(m, np.nan))
            j = 0 if first else 1
            # the period's own return already ends at the next period's start: its last point dropped
            Xk.append(P0[j:-1, 0] + x0); Yk.append(P0[j:-1, 1]); Kk.append(kinds0[j:-1]); Fk.append(F0[j:-1])
            if check is not None:
                xs, ys = np.concatenate(Xk), np.concatenate(Yk)
                if not first:
                    xs, ys = np.r_[X[-1][-1], xs], np.r_[Y[-1][-1], ys]
                Qk = along(region.axis, np.maximum(xs, 0.0), ys)
                out = ~shapely.contains_xy(allowed, Qk[:, 0], Qk[:, 1])
                if out.any():
                    Qk = clamp_to_region(Qk, allowed.buffer(-1e-4))
                cutting = np.concatenate(Kk) == "cut"
                if not check(Qk, cutting if first else np.r_[False, cutting], first):
                    if x_prev is not None and d > MIN_BEND_STEP_FRAC * step * 1.5:
                        d = max(0.5 * d, MIN_BEND_STEP_FRAC * step)
                        x0 = x_prev + d          # the period laid again, closer to the previous one
                        continue
                    stop_all = True
                    break
            X += Xk; Y += Yk; K += Kk; F += Fk
            last_front, x_prev = x0 + x_ext, x0
            d = bend_step(s_ax, ang_ax, x0, x_ext, float(np.abs(P0[:, 1]).max()), step, h)
            x0 += d
        if stop_all:
            break
    if not X:
        return np.zeros((0, 2)), np.zeros(0, dtype=object), np.zeros(0), steps, 0
    X, Y, K, F = np.concatenate(X), np.concatenate(Y), np.concatenate(K), np.concatenate(F)
    # behind the axis start lies the entry's round hole (radius c + r about the start, see
    # :func:`cut_region`), then material (the dead end's corners, or the wide area at a mouth): the
    # first periods' returns are held at x >= 0, where the tool disc stays inside the hole
    X = np.maximum(X, 0.0)
    Q = along(region.axis, X, Y)
    inside = shapely.contains_xy(allowed, Q[:, 0], Q[:, 1])
    n_out = int((~inside).sum())
    if n_out:
        Q = clamp_to_region(Q, allowed.buffer(-1e-4))
    keep = np.r_[True, np.hypot(*np.diff(Q, axis=0).T) > 1e-6]
    return Q[keep], K[keep], F[keep], steps, n_out


def join_axis(reg: NarrowRegion, p) -> NarrowRegion:
    """``reg`` with its axis starting at the point ``p`` (2,) mm (a mouth's free point the tool
    stands at): the straight leg from ``p`` to the axis start and the axis resampled at the axis's
    own spacing, the corner between them rounded by a moving average over ``JOIN_RADIUS_C c a`` mm
    (a the corner's turn, c the half-width there; only where a > ``JOIN_MIN_TURN_DEG``, else the
    leg is prepended as it is: a bend of tightest radius about 0.6 ``JOIN_RADIUS_C`` c, so that the pattern's inner side hardly folds over the bend's centre and
    :func:`bend_step` has a finite curvature to space the periods by); the ends are kept. The start is open (the tool
    reached it through cleared area).

    >>> reg = NarrowRegion(0, None, np.c_[np.linspace(0, 5, 26), np.zeros(26)], np.full(26, 1.0), (True, True))
    >>> j = join_axis(reg, (0.0, -3.0))
    >>> j.axis[0].tolist(), j.axis[-1].tolist(), j.dead, bool(j.length < 8.0)
    ([0.0, -3.0], [5.0, 0.0], (False, True), True)
    """
    p = np.asarray(p, float)
    A, c = reg.axis, reg.radius
    P = np.vstack([p[None], A])
    s_old = np.r_[0.0, np.cumsum(np.hypot(*np.diff(P, axis=0).T))]
    turn = 0.0
    if len(A) > 1 and s_old[1] > 1e-9:
        t0, t1 = A[0] - p, A[min(2, len(A) - 1)] - A[0]
        turn = abs(math.atan2(t0[0] * t1[1] - t0[1] * t1[0], float(t0 @ t1)))
    if turn <= math.radians(JOIN_MIN_TURN_DEG):
        return NarrowRegion(reg.index, reg.polygon, P, np.r_[c[0], c], (False, reg.dead[1]))
    sp = float(np.median(np.hypot(*np.diff(A, axis=0).T)))
    n = max(int(math.ceil(s_old[-1] / sp)), 2)
    sq = np.linspace(0.0, s_old[-1], n + 1)
    Q = np.c_[np.interp(sq, s_old, P[:, 0]), np.interp(sq, s_old, P[:, 1])]
    cq = np.interp(sq, s_old, np.r_[c[0], c])
    k = int(math.ceil(0.5 * JOIN_RADIUS_C * float(c[0]) * turn / sp))
    S = Q.copy()
    for i in np.flatnonzero(np.abs(sq - s_old[1]) <= (k + 1) * sp):
        w = min(k, i, n - i)
        S[i] = Q[i - w:i + w + 1].mean(axis=0)
    Q = S
    return NarrowRegion(reg.index, reg.polygon, Q, cq, (False, reg.dead[1]))


def spiral_out(c_xy, rho0, rho1, pitch, ds, start_rad=0.0, tool_r=None):
    """Counter-clockwise spiral about ``c_xy`` from radius ``rho0`` at angle ``start_rad`` (rad) out to
    ``rho1`` (mm), then one full circle at ``rho1``; points about ``ds`` mm apart, (m, 2) mm.

    Without ``tool_r``: Archimedean, gaining at most ``pitch`` mm per turn. With ``tool_r`` (the tool
    radius r, mm): ``pitch`` is the radial depth a_e of a straight cut at the target engagement theta
    (cos theta = 1 - a_e / r), and a turn at radius rho gains g = rho + r - sqrt(rho^2 + r^2 +
    2 rho r cos theta): the tool circle at rho meets the wall the last turn left (radius rho - g + r)
    at the angle theta from the radial direction (law of cosines). It tends to a_e far out and to
    a_e rho / r near the centre, where a constant pitch of a_e / 2 cuts 45 deg at rho = 0.2 r for
    theta 25.6 deg.

    >>> S = spiral_out((0.0, 0.0), 1.0, 2.0, 0.5, 0.1)
    >>> S[0].round(9).tolist(), S[-1].round(9).tolist(), round(float(np.hypot(*S[-50].T)), 9)
    ([1.0, 0.0], [2.0, 0.0], 2.0)
    >>> S = spiral_out((0.0, 0.0), 0.5, 2.0, 0.3, 0.05, tool_r=3.0)
    >>> rad = np.hypot(*S.T); bool(np.all(np.diff(rad) >= -1e-12)), round(float(rad[-1]), 9)
    (True, 2.0)
    """
    c = np.asarray(c_xy, float)
    if tool_r is None or rho1 <= rho0:
        turns = max(int(math.ceil((rho1 - rho0) / pitch - 1e-9)), 1) if rho1 > rho0 else 0
        m = max(int(math.ceil(2 * math.pi * max(rho1, rho0) / ds)), 16)
        t = np.linspace(0.0, turns + 1.0, m * (turns + 1) + 1)
        rad = np.where(t < turns, rho0 + (rho1 - rho0) * t / max(turns, 1), max(rho1, rho0))
    else:
        rad, t = _engagement_spiral(rho0, rho1, pitch, ds, float(tool_r))
    a = start_rad + 2 * np.pi * t
    P = c + rad[:, None] * np.c_[np.cos(a), np.sin(a)]
    P[0] = c + rho0 * np.array([math.cos(start_rad), math.sin(start_rad)])
    P[-1] = c + max(rho1, rho0) * np.array([math.cos(start_rad), math.sin(start_rad)])
    return P


def _engagement_spiral(rho0, rho1, a_e, ds, r):
    """(radius (m,) mm, turn parameter t (m,)) of :func:`spiral_out`'s spiral with the radial gain per
    turn of its docstring, ending on a whole turn at ``rho1``, then one circle at ``rho1``: per turn the
    gain at its start radius (it grows with rho: the turn's end keeps within the bound), the radius
    linear in t within the turn, the last turn's gain shrunk to land on ``rho1``."""
    cos_t = 1.0 - a_e / r
    starts = [rho0]
    while starts[-1] < rho1 - 1e-9:
        rho = starts[-1]
        g = rho + r - math.sqrt(rho * rho + r * r + 2.0 * rho * r * cos_t)
        starts.append(min(rho + max(g, 1e-3 * a_e), rho1))
    starts.append(rho1)                           # the closing circle
    R = np.asarray(starts)
    turns = len(R) - 1
    m = max(int(math.ceil(2 * math.pi * rho1 / ds)), 16)
    t = np.linspace(0.0, float(turns), m * turns + 1)
    k = np.minimum(t.astype(int), turns - 1)
    return R[k] + (R[k + 1] - R[k]) * (t - k), t
