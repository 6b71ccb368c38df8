"""Constant-engagement clearing of a 2.5D pocket with islands and narrow necks (Jacsó 2021, Thesis III).

Units: lengths in mm, areas in mm², feeds in mm/min, ``theta_deg`` in degrees; ``tool_radius`` is
the *radius* of the flat end mill. The pocket is a shapely ``Polygon`` whose holes are islands.

Algorithm (:func:`ce_clearing`):

1. **regions and entries** — the *allowed region* is the pocket shrunk by the tool radius (the final
   contour for the tool centre: walls offset inwards, islands grown). One seed per part of the
   pocket: the centres of the largest inscribed circles of the components of the allowed region
   eroded by ``seed_clearance_ratio`` x its largest inscribed radius (:func:`default_seeds`; a neck
   narrower than that separates two parts). At each seed a **helical entry** bores a hole of radius
   ``entry_radius_mm`` (XY trace: a circle of radius ``entry_radius_mm - r`` about the seed; in
   G-code a one-turn helical ramp to the cutting depth and one flat turn).
2. **constant-engagement laps** — seed after seed: the boundary of the cleared region around the
   seed is read from a dixel stock
   (:func:`~cnclab.toolpath.constant_engagement.cleared_boundary_contour`) and one full turn of the
   Thesis III path (engagement ``theta_deg``, midpoint direction) is traced from where the previous
   lap ended, so laps chain like a spiral. Tool centres are kept in the seed's *cell* (the part of
   the allowed region geodesically nearest to the seed, :func:`geodesic_cells`; islands included,
   :func:`~cnclab.toolpath.constant_engagement.clamp_to_region`): the pass is limited by the final contour and, across a neck, by the
   neighbouring cell. The limit acts *within* the lap (``wall="gate"``): a stretch pushed onto the
   final contour is kept only while a trial cut holds the engagement at or below
   ``theta_deg + gate_margin_deg``; otherwise the lap ends where it meets the final contour and
   resumes where it leaves it, so the tool is not dragged along the wall through the wedge between
   the previous lap and the wall (that wedge is cut by later laps or the final pass). Links are cut
   through the planning stock too: a link step that removes material is labelled ``"linkcut"``.
   With ``wall="roll-in"`` a run that resumes from the final contour (the wall) is entered by a
   **roll-in arc** (Jacsó §4; :func:`roll_in`): an arc of radius >= r tangent to the run, from a
   point where the tool misses the material, found by trial cuts so that the engagement ramps up
   from 0 (at most ``theta_deg + gate_margin_deg``, else the lowest found up to ``theta_deg +
   2 gate_margin_deg``) instead of the tool being linked head-on into the lap (up to 2 theta).
   The lap is cut into the stock; stretches that remove nothing become links:
   straight when the tool swept along the chord misses the material, else the shortest grid route
   through the cleared region (:func:`geodesic`, scipy Dijkstra), else the lap's own air stretch.
   A seed's laps stop when a lap removes less than ``min_removed_mm2``; a seed whose entry hole is
   already cleared is skipped.
3. **cleanup** — leftovers the laps do not reach (material enclosed between the cleared region and
   an island, slivers on the final contour, the corners) are cut by a final contour pass along every
   ring of the allowed region (outer ring counter-clockwise, islands clockwise: climb milling with
   an M3 spindle, material on the right), its air stretches again linked. This pass is *not*
   engagement-controlled: its spikes are reported by :func:`evaluate_path` (kind ``"cleanup"``).

The result is a :class:`~cnclab.toolpath.path.ToolPath` at the cutting level ``-a_p``: helical
entries (kind ``helix``, then the entry circle flat as a cut tagged ``entry-floor``), laps (``cut``),
cleanup (``cut`` tagged ``cleanup``), link steps that remove material (``cut`` tagged ``linkcut``),
links through the cleared region (``link``) and, where no route at depth exists, a retract, a rapid
at the clearance plane and a plunge into the *cleared* region nearest to the next run (the free
region of the planning stock), followed by a link at depth to the run. The one evaluator
:func:`cnclab.toolpath.evaluate.evaluate` measures it.

>>> from shapely.geometry import box
>>> from cnclab.toolpath.evaluate import evaluate
>>> from cnclab.toolpath.job import Job
>>> from cnclab.toolpath.path import Tool
>>> job = Job(box(0, 0, 40, 30), Tool(10.0), 66.42, 1.0, v_c=60, feed_mm_min=1000)
>>> ev = evaluate(ce_clearing(job, resolution_mm=0.25), job, 0.25)
>>> ev.uncut_beyond_unreachable_mm2 < 1.0                          # only the corner cusps remain
True
>>> abs(ev.engagement_p50_deg - 66.42) < 2.0                       # the laps hold theta
True
>>> (ev.plunges_into_material, ev.rapids_into_material)
(0, 0)
"""
from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
import shapely
from shapely.geometry import LineString, MultiPolygon, Point, Polygon
from shapely.geometry.polygon import orient
from shapely.ops import nearest_points

from ..geometry.planar import polygon_parts
from ..simulation import dixel
from ..simulation.common import simulate
from .constant_engagement import (ShiftedContour, clamp_to_region, cleared_boundary_contour, lap_start,
                                  resample_path, thesis3_path)
from .ce_routes import chord_clear, dilate, geodesic, geodesic_cells, roll_in, round_corners, split_runs
from .job import LINK_FEED_MM_MIN, MAX_LAPS, RAPID_MM_MIN, Job
from .path import ToolPath, helix_ring, resample_polyline

__all__ = ["PLAN_KINDS", "LINK_FEED_MM_MIN", "RAPID_MM_MIN", "default_seeds", "geodesic_cells", "helical_entry",
           "ClearingSettings", "ce_clearing", "round_corners"]

#: Planning labels of the clearing's points (written as ToolPath kinds/tags, see the module docstring).
PLAN_KINDS = ("entry", "cut", "cleanup", "linkcut", "link", "rapid")
#: tag (for people) of a move into area the planner cleared; the proof is the path's ``cleared`` flag
CLEARED = "cleared"
#: planning label of a jump's last point when it lies in the cleared region (the descent meets air)
CLEARED_LANDING = "rapid-cleared"


def _check_common(pocket, tool_radius, theta_deg=None):
    if not isinstance(pocket, (Polygon, MultiPolygon)) or pocket.is_empty or not pocket.is_valid:
        raise ValueError("pocket must be a valid, non-empty shapely Polygon (mm, holes = islands)")
    if not (isinstance(tool_radius, (int, float)) and math.isfinite(tool_radius) and tool_radius > 0):
        raise ValueError(f"tool_radius must be > 0 mm, got {tool_radius!r}")
    if theta_deg is not None and not (0 < theta_deg < 180):
        raise ValueError(f"theta_deg must be in (0, 180) deg, got {theta_deg!r}")
    allowed = pocket.buffer(-tool_radius, quad_segs=64)
    if allowed.is_empty or allowed.area < 1e-6:
        raise ValueError(f"tool_radius={tool_radius} mm: the tool does not fit in the pocket")
    return allowed


def default_seeds(allowed, seed_clearance_ratio: float = 0.6) -> list[tuple]:
    """One seed per part of the allowed region ``allowed`` (mm): the centres of the largest
    inscribed circles of the components of ``allowed`` eroded by ``seed_clearance_ratio`` times its
    largest inscribed radius, largest part first. Necks narrower than twice that erosion separate parts.

    >>> from shapely.geometry import box
    >>> two = box(0, 0, 30, 20).union(box(30, 8, 40, 12)).union(box(40, 0, 70, 20))
    >>> [tuple(round(v) for v in s) for s in default_seeds(two)]
    [(15, 10), (55, 10)]
    """
    if not 0 < seed_clearance_ratio < 1:
        raise ValueError(f"seed_clearance_ratio must be in (0, 1), got {seed_clearance_ratio!r}")
    parts = polygon_parts(allowed)
    if not parts:
        raise ValueError("allowed must be a non-empty polygon")
    rmax = max(shapely.maximum_inscribed_circle(p, 0.01).length for p in parts)   # centre -> nearest point
    core = allowed.buffer(-seed_clearance_ratio * rmax)
    seeds = []
    for p in sorted(polygon_parts(core), key=lambda q: (-round(q.area, 6), q.centroid.x, q.centroid.y)):
        c = shapely.get_coordinates(shapely.maximum_inscribed_circle(p, 0.01))[0]
        seeds.append((float(c[0]), float(c[1])))
    return seeds


def _true_runs(mask):
    """(start, stop) index pairs of the maximal runs of True in the boolean array ``mask``."""
    e = np.flatnonzero(np.diff(np.r_[0, np.asarray(mask).astype(int), 0]))
    return list(zip(e[0::2], e[1::2]))


def _resample(P, step):
    """Polyline samples every <= ``step`` mm (a zero-length path stays one point)."""
    return resample_polyline(P, step, uniform=True)


def helical_entry(seed_xy, entry_radius_mm: float, tool_radius: float, step_mm: float = 0.2):
    """XY trace of a helical entry boring a hole of radius ``entry_radius_mm`` about ``seed_xy``: one
    counter-clockwise circle of radius ``entry_radius_mm - tool_radius`` (mm), starting and ending at
    angle 0. Returns (n, 2) points, spaced <= ``step_mm``."""
    e = float(entry_radius_mm) - float(tool_radius)
    if not e > 0:
        raise ValueError(f"entry_radius_mm must exceed tool_radius={tool_radius} mm, got {entry_radius_mm!r}")
    return helix_ring(seed_xy, e, max(int(math.ceil(2 * math.pi * e / step_mm)), 16))


def _touch_start(contour, E, r):
    """Contour parameter t0 where a lap from ``E`` starts, and the start point P0 (|P0 - c(t0)| <= r):
    :func:`~cnclab.toolpath.constant_engagement.lap_start`, with ``E`` moved to within r of the
    contour when it is farther."""
    t_near, d_near, t_join = lap_start(contour, E, r)
    if d_near > r:
        C = contour.point(t_near)[0]
        return t_near, C + r * (np.asarray(E) - C) / d_near
    return t_join, np.asarray(E, float)


def _lap(stock, domain, seed, E, r, theta_deg, cell, dt, step, wall="trim"):
    """One Thesis III turn around the cleared region containing ``seed``, from ``E``.

    Returns a list of (n, 2) tool-centre runs (mm). ``wall="trim"``: the lap is limited by the final
    contour *within* the turn — it ends where it meets the boundary of ``cell`` and resumes where it
    re-enters (each run ends / starts on the boundary), so the tool is never dragged along the wall
    into material. ``wall="clamp"`` (previous behaviour, kept for comparison): every centre outside
    ``cell`` is pushed back onto its nearest boundary point, one run.
    """
    c = cleared_boundary_contour(stock, seed, domain)
    t0, P0 = _touch_start(c, E, r)
    shifted = ShiftedContour(c, t0)
    for h in (dt, dt / 2, dt / 4):
        try:
            res = thesis3_path(shifted, r, theta_deg, h, method="midpoint", P0=P0)
            break
        except ValueError:
            continue
    else:
        return None
    P = _resample(resample_path(res.P, step), step)
    if wall in ("clamp", "gate"):
        if wall == "clamp" and np.hypot(*(P0 - np.asarray(E))) > 1e-9:
            P = np.vstack([E, P])
        Q = clamp_to_region(P, cell)
        moved = np.hypot(*(Q - P).T) > 1e-9
        return [Q] if wall == "clamp" else (Q, moved)
    if wall != "trim":
        raise ValueError(f"wall must be 'trim', 'gate' or 'clamp', got {wall!r}")
    inside = shapely.contains_xy(cell, P[:, 0], P[:, 1])
    runs = []
    for a, b in _true_runs(inside):                       # P[a:b] inside
        run = P[a:b]
        ends = []
        for i_out, i_in, at_start in ((a - 1, a, True), (b, b - 1, False)):
            if 0 <= i_out < len(P):                          # the crossing of the cell boundary
                x = LineString([P[i_in], P[i_out]]).intersection(cell.boundary)
                q = shapely.get_coordinates(x)
                if len(q):
                    q = q[np.argmin(np.hypot(*(q - P[i_in]).T))]
                    ends.append((at_start, q))
        for at_start, q in ends:
            run = np.vstack([q, run]) if at_start else np.vstack([run, q])
        if len(run) >= 2:
            runs.append(run)
    return runs


def _gate(stock, Q, moved, r, limit_deg, a_p, feed_mm_min):
    """Split the clamped lap ``Q`` (mm) into runs, leaving out every wall stretch (maximal run of
    ``moved`` points) on which a trial cut of ``Q`` through a copy of ``stock`` exceeds ``limit_deg``."""
    eng = simulate(stock, Q, r, a_p, feed_mm_min, copy=True).engagement_deg.to_numpy()
    keep = np.ones(len(Q), bool)
    for a, b in _true_runs(moved):                        # Q[a:b] on the wall
        if np.nanmax(np.r_[eng[a:min(b + 1, len(Q))], 0.0]) > limit_deg:
            keep[a:b] = False
            if a > 0:
                keep[a] = True                                # the run ends on the wall ...
            if b < len(Q):
                keep[b - 1] = True                            # ... and resumes from it
                if b - 1 == a:
                    keep[a] = False
    runs = []
    for a, b in _true_runs(keep):
        if b - a >= 2:
            runs.append(Q[a:b])
    return runs


WALLS = ("gate", "trim", "clamp", "roll-in")


@dataclasses.dataclass(frozen=True)
class ClearingSettings:
    """Planning settings of :func:`ce_clearing` (every field has a default; lengths in mm).

    Attributes
    ----------
    seeds : start points ((x, y) mm), one per part; None: :func:`default_seeds`.
    entry_radius_mm : radius of the helical-entry hole (mm, > r); None: 1.6 r, reduced to fit.
    resolution_mm : dixel row height of the planning stock (mm).
    step_mm : spacing of the tool-centre samples (mm); None: ``2 * resolution_mm``.
    dt : Thesis III contour-parameter step (mm of boundary).
    max_laps : cap on the total number of laps.
    min_removed_mm2 : a seed's laps end when a lap removes less (mm²); None: ``r * step_mm``.
    seed_clearance_ratio : see :func:`default_seeds` (dimensionless, in (0, 1)).
    cleanup : add the final contour pass.
    link_grid_mm : grid spacing (mm) of the seed cells (:func:`geodesic_cells`) and of the shortest
        links through the cleared region.
    wall : how a lap is limited by the final contour (the boundary of the seed's cell):
        ``"gate"`` (default) — centres outside the cell are put on its boundary, but every such
        wall stretch whose simulated engagement exceeds ``theta_deg + gate_margin_deg`` is left out:
        the lap ends where it meets the final contour and resumes where it leaves it, the gap bridged
        by a link through the cleared region (the wedge it skips is cut by later laps / the final pass);
        ``"trim"`` — every outside stretch is left out (the lap never follows the wall);
        ``"clamp"`` — centres pushed onto the boundary, all kept (earlier behaviour: the tool is
        dragged along the wall and cuts full-width wedges, up to 180 deg); ``"roll-in"`` — ``"gate"``
        with the runs resuming from the wall entered by roll-in arcs (:func:`roll_in`).
    gate_margin_deg : engagement margin (deg) above ``theta_deg`` tolerated on a wall stretch.
    link_limit_deg : None (default), or an engagement (deg above ``theta_deg``) above which a link
        that cuts material (tried on a copy of the planning stock) is replaced by the jump to the
        cleared point nearest to its end when that jump's final link cuts less.
    cleanup_step_mm : None (default), or the radial step (mm) of contour-parallel passes outwards from
        the cleared region over what the laps left, before the final contour pass
        (``_Clearing.offset_rings``).
    clip_deg : None (default), or an engagement (deg above ``theta_deg``): a lap run is cut only up to
        its first step above it in a trial cut, and resumes after that stretch (``_Clearing.clip``),
        the material skipped left to later laps and the cleanup.
    corner_radius_mm : the cleanup (offset rings and the final contour pass) rounds every sharp
        convex corner of the allowed region (a concave corner of the pocket) by an arc of this radius
        (mm; 0: none), :func:`round_corners`: a tool centre path turning on the spot in a corner meets
        the corner's cusp along 90 deg of its edge (Jacso's rectangle: theta + 31 deg there); a fillet
        of radius rho leaves (1 - pi/4) ((rho + r)^2 - r^2) mm^2 more in a 90 deg corner.
    wall_margin_mm : the tool centres at depth (not the jumps, not the entries) are kept this far (mm)
        inside the allowed region, projected onto it when outside (data/pockets/spline_pocket.json:
        the tool 0.006 mm past the wall with 0 mm, 0.002 mm with 0.005 mm, none with 0.02 mm).

    >>> ClearingSettings(wall="roll-in").sample_step_mm()
    0.2
    """
    seeds: tuple | None = None
    entry_radius_mm: float | None = None
    resolution_mm: float = 0.1
    step_mm: float | None = None
    dt: float = 0.2
    max_laps: int = MAX_LAPS
    min_removed_mm2: float | None = None
    seed_clearance_ratio: float = 0.6
    cleanup: bool = True
    link_grid_mm: float = 1.0
    wall: str = "gate"
    gate_margin_deg: float = 5.0
    link_limit_deg: float | None = None
    cleanup_step_mm: float | None = None
    clip_deg: float | None = None
    wall_margin_mm: float = 0.0
    corner_radius_mm: float = 0.0

    def sample_step_mm(self) -> float:
        """Check the steps and wall options (ValueError naming the parameter); the sample step (mm)."""
        if not (isinstance(self.resolution_mm, (int, float)) and self.resolution_mm > 0):
            raise ValueError(f"resolution_mm must be > 0 mm, got {self.resolution_mm!r}")
        step = 2.0 * self.resolution_mm if self.step_mm is None else float(self.step_mm)
        if not step > 0:
            raise ValueError(f"step_mm must be > 0 mm, got {self.step_mm!r}")
        if not self.dt > 0:
            raise ValueError(f"dt must be > 0 mm, got {self.dt!r}")
        if self.wall not in WALLS:
            raise ValueError(f"wall must be 'gate', 'trim', 'clamp' or 'roll-in', got {self.wall!r}")
        if not self.gate_margin_deg >= 0:
            raise ValueError(f"gate_margin_deg must be >= 0 deg, got {self.gate_margin_deg!r}")
        return step


def ce_clearing(job: Job, settings: ClearingSettings | None = None, **options) -> ToolPath:
    """Constant-engagement clearing of ``job`` (see the module docstring).

    Parameters
    ----------
    job : the :class:`~cnclab.toolpath.job.Job`: its polygon (mm; holes are islands), tool (flat end
        mill, radius r), ``theta_deg``, ``a_p``, feeds, planes and spindle (one level, ``top_z - a_p``).
    settings : :class:`ClearingSettings` (planning: resolution, seeds, steps, wall handling ...);
        default all defaults.
    options : any field of :class:`ClearingSettings`, by name (e.g. ``resolution_mm=0.25,
        wall="trim"``), overriding ``settings``; another name is a TypeError.

    Returns a :class:`~cnclab.toolpath.path.ToolPath` whose ``info`` holds the seeds, laps per seed,
    the entry radius and the planning stock's uncut area.
    """
    settings = settings or ClearingSettings()
    names = {f.name for f in dataclasses.fields(ClearingSettings)}
    bad = sorted(set(options) - names)
    if bad:
        raise TypeError(f"ce_clearing() got an unexpected keyword argument {bad[0]!r} (not a ClearingSettings "
                        "field; the cutting data come from the job)")
    if not isinstance(job, Job):
        raise ValueError(f"ce_clearing: job must be a cnclab Job, got {type(job).__name__}")
    return _Clearing(job, dataclasses.replace(settings, **options)).run()


def _rings(region) -> list:
    """The rings ((n, 2) mm, closed) of the polygons of ``region``: outer rings counter-clockwise,
    holes clockwise (climb milling with an M3 spindle: the material on the right)."""
    rings = []
    for p in polygon_parts(region):
        p = orient(p, 1.0)
        rings += [np.asarray(p.exterior.coords)] + [np.asarray(i.coords) for i in p.interiors]
    return rings


#: the free region (``_Clearing.free_region``) grows only the material farther than this many rows from
#: the walls: the rest is farther than r - (this x res) > r - res from every centre of the allowed region,
#: so the region is the same in exact arithmetic (< 1: strictly), and growing it costs 3x less (the rows'
#: staircase along the walls and the wall slivers are left out: a D40 disc 5.2 -> 1.6 s). What differs is
#: the over-estimate of ``dilate`` near the walls, and the plans follow it: Jacso's rectangle at 0.25 /
#: 0.5 / 0.75 / 0.9 rows: max theta + 13.5 / 16.0 / 17.3 / 11.3 deg, the excess in a link onto a wall run
#: by a corner (the weak spot of this strategy: see planners.CE_PROMISE_DEG)
FREE_CORE_ROWS = 0.9


#: a cleanup ring's start candidates (``_Clearing.ring_start``): spacing (mm) and how many are tried
RING_START_SPACING_MM = 1.0
RING_START_TRIES = 12


class _Clearing:
    """The state of one :func:`ce_clearing` run: the planning stock, the emitted segments
    ``(points, labels, seed)``, and the steps (entries, laps, links, cleanup) that extend them."""

    def __init__(self, job: Job, settings: ClearingSettings):
        pocket, tool_radius, theta_deg = job.polygon, job.tool_radius, job.theta_deg
        self.allowed = _check_common(pocket, tool_radius, theta_deg)
        self.s, self.job, self.r, self.theta = settings, job, float(tool_radius), float(theta_deg)
        self.step = settings.sample_step_mm()
        self.roll_in = settings.wall == "roll-in"
        self.wall = "gate" if self.roll_in else settings.wall
        self.min_removed = self.r * self.step if settings.min_removed_mm2 is None else float(settings.min_removed_mm2)
        res = settings.resolution_mm
        self.air_tol = 0.5 * res * res                    # mm²: half a row² = air
        seeds = default_seeds(self.allowed, settings.seed_clearance_ratio) if settings.seeds is None else \
            [tuple(map(float, s)) for s in settings.seeds]
        if not seeds:
            raise ValueError("seeds must hold at least one (x, y) point in mm")
        for s in seeds:
            if len(s) != 2 or not self.allowed.contains(Point(s)):
                raise ValueError(f"seeds: {s!r} is not inside the allowed region (pocket shrunk by tool_radius)")
        self.seeds = seeds
        self.guard = self.allowed.buffer(1e-6)
        m = settings.wall_margin_mm
        self.inner = self.allowed.buffer(-m, quad_segs=64) if m > 0 else None
        self.stock = dixel.Stock.from_polygon(pocket, res)
        self.domain = pocket.buffer(-2 * res)              # wall slivers must not join the cleared region
        self.core = pocket.buffer(-FREE_CORE_ROWS * res, quad_segs=64)   # see free_region
        self.segs: list = []
        self.cells = geodesic_cells(self.allowed, seeds, settings.link_grid_mm)
        self.finish = round_corners(self.allowed, settings.corner_radius_mm)

    def emit(self, P, K, reg):
        """Append a planning segment; with ``wall_margin_mm`` its points at depth (not the jumps, not the
        entries) are kept that far inside the allowed region (projected onto it when outside)."""
        P, K = np.asarray(P, float), np.asarray(K, dtype=object)
        if self.inner is not None and not np.isin(K, ("rapid", CLEARED_LANDING, "entry")).any():
            P = clamp_to_region(P, self.inner)
        self.segs.append((P, K, reg))

    def sim(self, P, copy=False):
        """Cut the tool centres ``P`` (mm) through the planning stock (a copy with ``copy``): the table."""
        return simulate(self.stock, P, self.r, self.job.a_p, self.job.feed_mm_min, copy=copy)

    def free_region(self):
        """Material now, and (computed on demand) the region where the tool centre misses it."""
        mat = self.stock.to_polygon()
        r, res = self.r, self.s.resolution_mm
        # material within FREE_CORE_ROWS x res of the walls is farther than r - res from every centre of the
        # allowed region: left out of the growing (the rows' staircase along the walls and the wall slivers)
        return mat, functools.cache(lambda: self.allowed.difference(dilate(mat & self.core, r - res, res)))

    def link(self, R, k, kind="link"):
        """Emit the link ``R`` after cutting it through the stock: steps that remove material -> linkcut."""
        R = _resample(np.asarray(R, float), self.step)
        rem = self.sim(R).removed_mm2.to_numpy()
        self.emit(R, np.where(rem > self.air_tol, "linkcut", kind), k)

    def route(self, Q0, material, free) -> list:
        """How to get from the current tool position to Q0 (mm): ``[("link", points)]`` straight or along
        the shortest route through the cleared region, else :meth:`jump_route`; [] when already there."""
        a, r, res = self.segs[-1][0][-1], self.r, self.s.resolution_mm
        if np.hypot(*(Q0 - a)) < 1e-9:
            return []
        # material the tool already touches at either end (it cuts there anyway) is not an obstacle
        material = material.difference(Point(a).buffer(r, quad_segs=16))
        if chord_clear(a, Q0, material, self.guard, r, res):
            return [("link", np.vstack([a, Q0]))]
        route = geodesic(a, Q0, free, self.s.link_grid_mm, self.guard, material, r, res)
        if route is not None:
            return [("link", route)]
        return self.jump_route(Q0, free)

    def jump_route(self, Q0, free) -> list:
        """Jump (retract, rapid) to the cleared point nearest to Q0, plunge there (into air) and link at
        depth to Q0 (its steps that touch material become linkcut): ``[("jump", [a, F], landing), ("link", [F, Q0])]``."""
        a, res = self.segs[-1][0][-1], self.s.resolution_mm
        fr = free()
        safe = fr.buffer(-2.0 * res)
        F, landing = Q0, "rapid"
        for g in (safe, fr):
            if not g.is_empty:
                F = np.asarray(shapely.get_coordinates(nearest_points(g, Point(Q0))[0])[0])
                landing = CLEARED_LANDING           # F is in the cleared region: the plunge meets air
                break
        out = [("jump", np.vstack([a, F]), landing)]
        if np.hypot(*(F - Q0)) > 1e-9:
            L = _resample(np.vstack([F, Q0]), self.step)
            if not self.guard.contains(LineString(L)):        # across a bulge of the wall: kept 0.01 mm inside
                L = np.vstack([F, clamp_to_region(L[1:-1], self.allowed.buffer(-0.01)), Q0])
            out.append(("link", L))
        return out

    def emit_route(self, route, k):
        """Emit the moves of a :meth:`route` (links cut through the stock, :meth:`link`)."""
        for m in route:
            if m[0] == "jump":
                self.emit(m[1], ["rapid", m[2]], k)
            else:
                self.link(m[1], k)

    def go_to(self, Q0, k, material, free):
        """Link from the current tool position to Q0: straight, shortest through the cleared region, or rapid.
        With ``link_limit_deg``: the link is cut on a copy of the stock first, and when it exceeds
        ``theta + link_limit_deg`` the jump to the cleared point nearest to Q0 replaces it if that cuts less."""
        route = self.route(Q0, material, free)
        if self.s.link_limit_deg is not None and route and route[0][0] != "jump":
            e = self.trial_max(route)
            if e > self.theta + self.s.link_limit_deg:
                jump = self.jump_route(Q0, free)
                if self.trial_max(jump) < e:
                    route = jump
        self.emit_route(route, k)

    def trial_max(self, route) -> float:
        """Max engagement (deg) of cutting the links of ``route`` through a copy of the planning stock."""
        st, e_max = self.stock.copy(), 0.0
        for m in route:
            if m[0] == "link":
                e = simulate(st, _resample(np.asarray(m[1], float), self.step), self.r, self.job.a_p,
                             self.job.feed_mm_min).engagement_deg.to_numpy()
                e_max = max(e_max, float(np.nanmax(np.r_[e, 0.0])))
        return e_max

    def split(self, P, removed, material, free, kind):
        """:func:`split_runs` of a simulated stretch with this run's settings, emitted when not empty."""
        return split_runs(P, removed, material, self.guard, self.r, self.air_tol, kind, 3, self.s.resolution_mm,
                           free, self.s.link_grid_mm)

    def entry(self, k, s):
        """The helical entry at seed ``s``: its radius, and its first point (None when an earlier seed's
        laps already cleared this part)."""
        r = self.r
        clear = float(self.allowed.boundary.distance(Point(s)))
        er = min(1.6 * r if self.s.entry_radius_mm is None else float(self.s.entry_radius_mm), r + clear)
        if er <= r + 0.5 * self.step:
            raise ValueError(f"seeds: {s!r} is too close to the final contour for a helical entry")
        material = self.stock.to_polygon()
        if material.intersection(Point(s).buffer(er)).area < 0.05 * math.pi * er * er:
            return er, None
        H = helical_entry(s, er, r, self.step)
        if self.segs:
            self.emit(np.vstack([self.segs[-1][0][-1], H[0]]), ["rapid", "rapid"], k)
        self.sim(H)
        self.emit(H, ["entry"] * len(H), k)
        return er, H[0]

    def cut_runs(self, runs, k) -> float:
        """Link to each run of a lap (rolling in where :func:`roll_in` finds an arc), cut and emit it;
        returns the area removed (mm²)."""
        removed, lim = 0.0, (self.theta + self.s.gate_margin_deg, self.theta + 2 * self.s.gate_margin_deg)
        queue = list(runs)
        while queue:
            P = queue.pop(0)
            material, free = self.free_region()
            A, j = roll_in(self.stock, P, self.r, lim, self.guard, free, self.job.a_p, self.job.feed_mm_min,
                            self.step, self.segs[-1][0][-1], self.allowed) if self.roll_in else (None, 0)
            if A is not None:                        # link to the arc's start (in air), roll in
                self.go_to(A[0], k, material, free)
                removed += float(self.sim(A).removed_mm2.sum())
                self.emit(A, ["cut"] * len(A), k)
                P, (material, free) = P[j:], self.free_region()
            elif self.s.link_limit_deg is not None:
                P = self.reachable_tail(P, material, free)
                if P is None:
                    continue
            self.go_to(P[0], k, material, free)
            if self.s.clip_deg is not None:
                P, rest = self.clip(P)
                if rest is not None:
                    queue.insert(0, rest)
                if len(P) < 2:
                    continue
            rem = self.sim(P).removed_mm2.to_numpy()
            removed += float(rem.sum())
            run = self.split(P, rem, material, free, "cut")
            if run is not None:
                self.emit(*run, k)
        return removed

    def clip(self, P):
        """``(head, rest)``: the run ``P`` up to its first step above ``theta + clip_deg`` in a trial cut
        on a copy of the stock (its first two samples, the approach, excepted), and what follows the
        stretch above ``theta + gate_margin_deg`` there (None if nothing; P and None if no step is above)."""
        e = np.nan_to_num(self.sim(P, copy=True).engagement_deg.to_numpy(), nan=0.0)
        over = np.flatnonzero(e[2:] > self.theta + self.s.clip_deg)
        if not len(over):
            return P, None
        i0 = int(over[0]) + 2
        back = np.flatnonzero(e[i0:] <= self.theta + self.s.gate_margin_deg)
        rest = P[i0 + int(back[0]):] if len(back) else None
        return P[:i0], (rest if rest is not None and len(rest) >= 3 else None)

    def reachable_tail(self, P, material, free):
        """``P`` from its first sample (every 0.5 mm over its first 3 r) that the :meth:`route` or the
        jump reaches with the link and the run's first tool radius within ``theta + link_limit_deg``
        (a trial cut on a copy of the stock); the stretch before it is left to later laps or the
        cleanup (or the offset rings, ``cleanup_step_mm``). None when the run is shorter than that
        and none does (the run is left out); ``P`` itself when a longer run has none (linked head-on)."""
        lim = self.theta + self.s.link_limit_deg
        s_run = np.r_[0.0, np.cumsum(np.hypot(*np.diff(P, axis=0).T))]
        for d in np.arange(0.0, 3 * self.r + 1e-9, 0.5):
            j = int(np.searchsorted(s_run, d))
            if j >= len(P) - 2:
                return None if j > 0 else P
            head = P[j:max(j + 2, int(np.searchsorted(s_run, s_run[j] + self.r)))]
            route = self.route(P[j], material, free)
            for moves in ([route] if route and route[0][0] == "jump" else [route, self.jump_route(P[j], free)]):
                if self.trial_max(moves + [("link", head)]) <= lim:
                    return P[j:]
        return P

    def laps(self, k, s, E, n_laps) -> tuple[int, int]:
        """Constant-engagement laps about seed ``s`` from ``E``, limited by its cell; (laps cut, total)."""
        done = 0
        while n_laps < self.s.max_laps:
            runs = _lap(self.stock, self.domain, s, E, self.r, self.theta, self.cells[k], self.s.dt, self.step,
                        self.wall)
            if not runs:
                break
            if self.wall == "gate":
                runs = _gate(self.stock, *runs, self.r, self.theta + self.s.gate_margin_deg, self.job.a_p,
                             self.job.feed_mm_min)
                if not runs:
                    break
            pre, n_segs = self.stock.copy(), len(self.segs)
            removed = self.cut_runs(runs, k)
            if removed < self.min_removed or len(self.segs) == n_segs:
                self.stock = pre
                del self.segs[n_segs:]
                break
            E = self.segs[-1][0][-1]
            done += 1
            n_laps += 1
        return done, n_laps

    def cleanup(self):
        """The final contour pass on every ring of the allowed region (outer ring counter-clockwise,
        islands clockwise), its air stretches linked; rings it would not cut are left out. With
        ``cleanup_step_mm``, :meth:`offset_rings` first."""
        if self.s.cleanup_step_mm is not None:
            self.offset_rings(self.s.cleanup_step_mm)
        for ring in _rings(self.finish):
            self.ring_pass(ring)

    def offset_rings(self, step_mm):
        """Contour-parallel passes outwards from the cleared region over what the laps left: the
        boundary of the region where the tool misses the material grown by ``step_mm`` (mm, round
        joins) within the allowed region, recomputed after each round, until a round removes nothing
        (each pass cuts a layer about ``step_mm`` thick, the corners included)."""
        for _ in range(int(math.ceil(2 * self.r / step_mm)) + 2):
            material, free = self.free_region()
            if material.is_empty:
                return
            region = free().buffer(step_mm, quad_segs=16).intersection(self.finish)
            removed = sum(self.ring_pass(ring) for ring in _rings(region))
            if removed <= self.air_tol:
                return

    def ring_pass(self, ring) -> float:
        """Cut the closed ring (mm) from its point nearest to the tool where the tool misses the
        material (else its nearest point), linked to and split into cutting runs (kind cleanup); a
        ring that would cut nothing is left out. Returns the area removed (mm²)."""
        R0 = np.asarray(ring, float)[:-1]
        if len(R0) < 3:
            return 0.0
        cur = self.segs[-1][0][-1]
        d = np.hypot(*(R0 - cur).T)
        material, free = self.free_region()
        if self.s.cleanup_step_mm is not None:
            in_air = shapely.contains_xy(free(), R0[:, 0], R0[:, 1])
            if in_air.any():
                d = np.where(in_air, d, np.inf)
        i0 = int(np.argmin(d))
        if self.s.link_limit_deg is not None and self.s.cleanup_step_mm is not None:
            R0, i0 = self.ring_start(R0, i0, material, free)
        R = _resample(np.vstack([np.roll(R0, -i0, axis=0), R0[i0:i0 + 1]]), self.step)
        if not (self.sim(R, copy=True).removed_mm2.to_numpy() > self.air_tol).any():
            return 0.0
        self.go_to(R[0], -1, material, free)
        rem = self.sim(R).removed_mm2.to_numpy()
        run = self.split(R, rem, material, free, "cleanup")
        if run is not None:
            self.emit(*run, -1)
        return float(rem.sum())

    def ring_start(self, R0, i0, material, free):
        """``(ring, i)``: where a cleanup ring ``R0`` (mm, open, closed implicitly) starts: ``R0[i0]`` when
        the link to it (:meth:`route`) and the ring's first tool radius from it, cut on a copy of the
        stock, stay within ``theta + link_limit_deg``; else the first such point of the ring resampled
        every :data:`RING_START_SPACING_MM`, nearest to the tool first (at most :data:`RING_START_TRIES`);
        else the one that cuts least (the nearest start: theta + 18 deg on the issue-29 pocket)."""
        lim = self.theta + self.s.link_limit_deg

        def trial(ring, i):
            head = _resample(np.vstack([np.roll(ring, -i, axis=0), ring[i:i + 1]]), self.step)
            s = np.r_[0.0, np.cumsum(np.hypot(*np.diff(head, axis=0).T))]
            return self.trial_max(self.route(ring[i], material, free)
                                  + [("link", head[:max(2, int(np.searchsorted(s, self.r)))])])

        best = (trial(R0, i0), R0, i0)
        if best[0] <= lim:
            return R0, i0
        ring = _resample(np.vstack([R0, R0[:1]]), RING_START_SPACING_MM)[:-1]
        order = np.argsort(np.hypot(*(ring - self.segs[-1][0][-1]).T), kind="stable")
        for i in order[:RING_START_TRIES]:
            e = trial(ring, int(i))
            if e <= lim:
                return ring, int(i)
            if e < best[0]:
                best = (e, ring, int(i))
        return best[1], best[2]

    def run(self) -> ToolPath:
        """Entries and laps seed after seed, the cleanup, and the ToolPath of it all."""
        entry_r, laps, n_laps = [], [0] * len(self.seeds), 0
        for k, s in enumerate(self.seeds):
            er, E = self.entry(k, s)
            entry_r.append(er)
            if E is not None:
                laps[k], n_laps = self.laps(k, s, E, n_laps)
        if self.s.cleanup:
            self.cleanup()
        info = {"seeds": self.seeds, "laps_per_seed": laps, "entry_radius_mm": entry_r,
                "planning_uncut_area_mm2": self.stock.area(), "theta_deg": self.theta,
                "resolution_mm": float(self.s.resolution_mm), "step_mm": self.step,
                "name": "constant-engagement clearing"}
        j = self.job
        out, landed = _segments(self.segs)
        path = ToolPath.from_segments(out, z_cut=j.top_z - j.a_p, feed=j.feed_mm_min, clearance_z=j.clearance_z,
                                      top_z=j.top_z, link_feed=j.link_feed_mm_min, spindle=j.spindle_rpm,
                                      tool=j.tool, info=info)
        return _tag_cleared_plunges(path, out, landed, j.top_z)


def _tag_cleared_plunges(path: ToolPath, segments, landed, top_z: float) -> ToolPath:
    """Flag (and tag) ``cleared`` the vertical plunges below ``top_z`` that follow a jump landing in the cleared
    region (``landed[i]``, per segment, from :func:`_segments`: the planner's stock check, not the
    segment's tag, which only says so for people): the written program marks them
    ``(cnclab:cleared/1)`` and the static checker does not count them as plunges into material (the dixel
    evaluator proves them: ``plunges_into_material``). ``path`` is changed in place and returned."""
    landings = [landed[i] for i, (P, k, t) in enumerate(segments) if isinstance(k, str) and k == "jump"
                and not (i + 1 < len(segments) and isinstance(segments[i + 1][1], str) and segments[i + 1][1] == "helix")]
    down = np.r_[False, np.diff(path.xyz[:, 2]) < 0]
    plunges = np.flatnonzero(path.is_kind("plunge") & down & (path.xyz[:, 2] < top_z - 1e-9))
    first = 1 if len(segments) and not (isinstance(segments[0][1], str) and segments[0][1] == "helix") else 0
    if len(plunges) != first + len(landings):
        raise RuntimeError(f"ce_clearing: {len(plunges)} plunges for {len(landings)} jumps")   # planner invariant
    for k, ok in zip(plunges[first:], landings):
        if ok:
            path.tag[k] = CLEARED if not path.tag[k] else f"{path.tag[k]} {CLEARED}"
            path.cleared[k] = True
    return path


def _segments(segs):
    """Planning segments ``(points, labels, seed)`` -> (:meth:`ToolPath.from_segments` segments, per
    segment: a jump that lands in the cleared region (its last label ``CLEARED_LANDING``))."""
    out, landed = [], []
    for P, K, g in segs:
        K = np.asarray(K, dtype=object)
        jump = K[0] == "rapid" and np.isin(K, ("rapid", CLEARED_LANDING)).all()
        landed.append(bool(jump and K[-1] == CLEARED_LANDING))
        if (K == "entry").all():
            out.append((P, "helix", f"seed {g}"))
        elif jump:
            out.append((P[[0, -1]], "jump", CLEARED if landed[-1] else ""))
        else:
            kind = np.where(K == "link", "link", "cut")
            tag = np.where(np.isin(K, ("cleanup", "linkcut")), K,
                           np.where(K == "link", "", f"seed {g}" if g >= 0 else ""))
            out.append((P, kind, tag.astype(object)))
    return out, landed
