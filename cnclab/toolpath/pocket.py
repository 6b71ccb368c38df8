"""2.5D pocket roughing: medial axis, the Jacsó (2021, §4) hybrid path and the comparison
strategies (contour-parallel offsets, zig-zag) on the same pocket.

A pocket is a :class:`cnclab.toolpath.job.Job` (polygon with islands, optional pre-drilled start
hole, cutting data). Units: mm, mm/min, m/min, degrees; ``tool_radius`` = diameter / 2.

Hybrid path (:func:`hybrid_path`), after the medial axis transformation (:func:`medial_axis`):

1. **open centre** — spiral-like constant-engagement laps around the start hole
   (:func:`cnclab.toolpath.constant_engagement.multi_pass`, Thesis III with the stock recomputed
   after every lap) until a lap touches the final contour (without a start hole the path first
   bores one by a helical entry);
2. **arms** — for every medial-axis branch that ends in a tip, constant-engagement trochoidal
   periods (:func:`cnclab.toolpath.trochoidal.ce_period`) in the branch's frame, the front
   recomputed from a dixel stock after every period, linked by arcs through the cleared region;
3. **linking** — straight moves between arms through the cleared centre (fast linking feed).

Every strategy returns a :class:`~cnclab.toolpath.path.ToolPath` at the cutting level (move tags:
``"<phase>"`` or ``"<phase>:roll-in"`` / ``"<phase>:roll-out"``, phase e.g. ``centre``, ``arm 2``,
``cp``, ``zz``); the one evaluator :func:`cnclab.toolpath.evaluate.evaluate` measures it, with
``feed_control=True`` also its cutting level through one dixel stock with the Thesis IV feed control.

>>> job = Job.from_dict({"polygon": [[0, 0], [40, 0], [40, 30], [0, 30]], "tool_diameter": 6, "teeth": 1,
...                      "v_c": 120, "f_z": 0.04, "a_p": 3, "theta_deg": 60,
...                      "start_hole": {"center": [20, 15], "diameter": 11}})
>>> p = contour_parallel_path(job)
>>> p.kinds()[:3].tolist(), p.xyz[:3, 2].tolist()          # G0 down to 0.5 mm, then into the start hole
(['rapid', 'rapid', 'plunge'], [5.0, 0.5, -3.0])
"""
from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
import shapely
from shapely import affinity
from shapely.geometry import LineString, MultiPolygon, Point, Polygon

from ..geometry.planar import polygon_parts
from ..simulation import dixel
from ..simulation.common import simulate
from .evaluate import SEGMENT_KINDS, entry_hole, evaluate, planar_view
from .constant_engagement import (ShiftedContour, clamp_chords, clamp_to_region, cleared_boundary_contour, lap_start,
                                  resample_path, thesis3_path)
from .job import Job, load_job, star_polygon
from .offsets import link_loops, offset_levels
from .path import ToolPath, subdivide
from .trochoidal import ce_period, disk_has_material, pattern_kinds
from .zigzag import cell_order, raster_lines, raster_link

__all__ = ["Job", "load_job", "star_polygon", "medial_axis", "arm_branches", "arm_regions",
           "centre_lap", "hybrid_path", "choose_candidate", "contour_parallel_path", "zigzag_path",
           "planar_view", "entry_hole", "SEGMENT_KINDS"]


def _entry_segments(job: Job, resolution_mm: float):
    """Planar segments that put the tool into the entry hole: none for a pre-drilled hole (the first
    point, its centre, is plunged into), else a helix circle (radius hole/2 - r) about the centre."""
    c, d, pre = entry_hole(job)
    if pre:
        return []
    e = 0.5 * d - job.tool_radius
    n = max(16, int(math.ceil(2 * math.pi * e / resolution_mm)))
    a = np.linspace(0.0, 2 * math.pi, n + 1)
    H = np.asarray(c) + e * np.c_[np.cos(a), np.sin(a)]
    H[-1] = H[0]
    return [(H, "helix", "entry"), (np.vstack([H[-1], c]), "link", "entry")]


def _to_toolpath(segs, job: Job, name: str, info: dict, resolution_mm: float = 0.1) -> ToolPath:
    """ToolPath at the job's (single) cutting level from planar (points, kind, phase) segments with
    kind cut / roll-in / roll-out / link / rapid (a rapid becomes a jump: retract, G0, plunge)."""
    out = _entry_segments(job, resolution_mm)
    for P, kind, ph in segs:
        P = np.asarray(P, float)
        K = np.full(len(P), kind, dtype=object) if isinstance(kind, str) else np.asarray(kind, dtype=object)
        if isinstance(kind, str) and kind == "rapid":
            out.append((P[[0, -1]], "jump", ph))
            continue
        bad = set(K) - set(SEGMENT_KINDS)
        if bad:
            raise ValueError(f"kind must be one of {SEGMENT_KINDS} or 'rapid', got {sorted(bad)}")
        tags = np.array([ph if k in ("cut", "link") else f"{ph}:{k}" for k in K], dtype=object)
        out.append((P, np.where(K == "link", "link", "cut"), tags))
    path = ToolPath.from_segments(out, z_cut=job.top_z - job.a_p, feed=job.feed_mm_min, clearance_z=job.clearance_z,
                                  top_z=job.top_z, link_feed=job.link_feed_mm_min, spindle=job.spindle_rpm,
                                  tool=job.tool, info=dict(info, name=name), reentry="ramp")
    return _tag_hole_plunges(path, job)


def _tag_hole_plunges(path: ToolPath, job: Job) -> ToolPath:
    """Flag (and tag) ``cleared`` every vertical plunge below the stock top whose tool disc lies inside the
    pre-drilled start hole (air: the path flags it ``cleared``, the program marks it
    ``(cnclab:cleared/1)``); in place, returned."""
    if job.start_hole is None:
        return path
    (cx, cy), d, _ = entry_hole(job)
    down = np.r_[False, np.diff(path.xyz[:, 2]) < 0]
    pl = path.is_kind("plunge") & down & (path.xyz[:, 2] < job.top_z - 1e-9)
    inside = np.hypot(path.xyz[:, 0] - cx, path.xyz[:, 1] - cy) <= 0.5 * d - job.tool_radius + 1e-9
    for k in np.flatnonzero(pl & inside):
        path.tag[k] = "cleared" if not path.tag[k] else f"{path.tag[k]} cleared"
        path.cleared[k] = True
    return path


# ---------------------------------------------------------------------------------------------
# medial axis
# ---------------------------------------------------------------------------------------------
def medial_axis(polygon, spacing_mm=0.25, min_clearance_mm=None):
    """Approximate medial axis (MultiLineString, mm) from the Voronoi diagram of boundary samples.

    The boundary is sampled every ``spacing_mm``; Voronoi edges (``shapely.voronoi_polygons``,
    GEOS) lying inside the polygon whose both ends are farther than ``min_clearance_mm`` (default
    2 spacings) from the boundary are kept and merged. Converges to the medial axis as the spacing
    shrinks (Brandt & Algazi 1992, CVGIP 55:329).
    """
    ring = polygon.exterior
    n = max(int(math.ceil(ring.length / spacing_mm)), 16)
    pts = shapely.line_interpolate_point(ring, np.linspace(0, ring.length, n, endpoint=False))
    edges = shapely.voronoi_polygons(shapely.multipoints(pts), only_edges=True)
    segs = shapely.get_parts(edges)
    segs = segs[shapely.within(segs, polygon)]
    clear = 2 * spacing_mm if min_clearance_mm is None else min_clearance_mm
    b = polygon.boundary
    c = shapely.get_coordinates(segs).reshape(-1, 2, 2)
    d0 = shapely.distance(shapely.points(c[:, 0]), b)
    d1 = shapely.distance(shapely.points(c[:, 1]), b)
    segs = segs[(d0 > clear) & (d1 > clear)]
    return shapely.line_merge(shapely.multilinestrings(segs))


def arm_branches(polygon, center, spacing_mm=0.25, min_length_mm=None):
    """Tips of the medial axis: end points of degree 1 (far from ``center``), with their clearance.

    Returns a list of dicts ``{"tip": (x, y), "angle_deg": direction from center, "clearance_mm":
    inscribed radius at the tip end, "length_mm": distance from center}``, sorted by angle.
    """
    ma = medial_axis(polygon, spacing_mm)
    parts = shapely.get_parts(ma)
    ends = np.vstack([shapely.get_coordinates(p)[[0, -1]] for p in parts])
    key = np.round(ends / (spacing_mm * 0.01)).astype(np.int64)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    deg1 = ends[cnt[inv.ravel()] == 1]
    c = np.asarray(center, float)
    dist = np.hypot(*(deg1 - c).T)
    minlen = 0.25 * dist.max() if min_length_mm is None else min_length_mm
    # a rounded tip (circular arc) degenerates into a fan of short Voronoi branches converging on
    # the arc centre: keep one tip (the farthest) per cluster of end points closer than the clearance
    order = np.argsort(-dist)
    kept = []
    for i in order:
        if dist[i] < minlen:
            continue
        clear = polygon.boundary.distance(Point(deg1[i]))
        if all(np.hypot(*(deg1[i] - deg1[j])) > clear for j in kept):
            kept.append(i)
    out = []
    for p, dd in zip(deg1[kept], dist[kept]):
        out.append({"tip": (float(p[0]), float(p[1])),
                    "angle_deg": float(np.degrees(np.arctan2(p[1] - c[1], p[0] - c[0]))),
                    "clearance_mm": float(polygon.boundary.distance(Point(p))), "length_mm": float(dd)})
    return sorted(out, key=lambda a: a["angle_deg"])


# ---------------------------------------------------------------------------------------------
# strategy paths
# ---------------------------------------------------------------------------------------------
def _rot(geom_or_pts, angle_deg, origin):
    if isinstance(geom_or_pts, np.ndarray):
        a = math.radians(angle_deg)
        c, s = math.cos(a), math.sin(a)
        p = geom_or_pts - np.asarray(origin)
        return np.c_[c * p[:, 0] - s * p[:, 1], s * p[:, 0] + c * p[:, 1]] + np.asarray(origin)
    return affinity.rotate(geom_or_pts, angle_deg, origin=tuple(origin))


def _label_lap(eng, theta_deg, margin_deg=5.0):
    """Kinds of a centre lap from its simulated engagement: the leading run below theta - margin
    is the lap's roll-in (Thesis III transition from the previous lap's end), the trailing run
    below it the roll-out (the lap closes on its own start); the rest is cut."""
    e = np.nan_to_num(np.asarray(eng, float))
    k = np.full(len(e), "cut", dtype=object)
    hi = np.flatnonzero(e >= theta_deg - margin_deg)
    if hi.size == 0:
        k[:] = "roll-in"
        return k
    k[:hi[0]] = "roll-in"
    k[hi[-1] + 1:] = "roll-out"
    return k


def centre_lap(stock, domain, seed_xy, start_xy, tool_radius, theta_deg, allowed, dt=0.1, step_mm=0.05,
               guard=None):
    """One spiral-like constant-engagement lap around the cleared region containing ``seed_xy``.

    The boundary of the cleared region is read from the dixel ``stock``
    (:func:`~cnclab.toolpath.constant_engagement.cleared_boundary_contour`), re-parametrised to start
    at the boundary point touched by the tool at ``start_xy`` (the previous lap's end, or a point
    touching the start hole), and Thesis III runs one full turn from ``start_xy``: the lap blends in
    from the previous one (engagement 0 -> theta, no radial plunge) and closes on its own start.
    Tool centres are clamped to ``allowed``, and with a ``guard`` (:func:`period_guard`) so are the
    chords between them (:func:`~cnclab.toolpath.constant_engagement.clamp_chords`). Returns the
    (n, 2) centre points (mm) and a boolean mask of the points inserted on the chords (the lap's
    spacing is ``step_mm`` without them).
    """
    r = tool_radius
    c = cleared_boundary_contour(stock, seed_xy, domain)
    shifted = ShiftedContour(c, lap_start(c, start_xy, r)[2])
    for h in (dt, dt / 2, dt / 4):
        try:
            res = thesis3_path(shifted, r, theta_deg, h, method="midpoint", P0=np.asarray(start_xy, float))
            break
        except ValueError:
            continue
    else:
        raise ValueError("Thesis III lap failed at every step size")
    P = resample_path(res.P, step_mm)
    if guard is None:
        return clamp_to_region(P, allowed), np.zeros(len(P), bool)
    return clamp_chords(P, allowed, guard, return_inserted=True)


WALL_SHARE_CANDIDATES = (0.3, 0.5)


def hybrid_path(job: Job, resolution_mm=0.05, dt=0.1, max_laps=20, max_periods=200,
                spacing_mm=0.25, max_rounds=3, arm_min_area_mm2=1.0, max_wall_share="auto",
                wall_share_candidates=WALL_SHARE_CANDIDATES, stop_when_clean=False):
    """Jacsó §4 hybrid path on ``job`` (see the module docstring). Returns a :class:`StrategyPath`
    with ``info`` holding the medial axis, the arms, the number of laps and periods per arm.

    Centre: the first lap starts touching the start hole (reached by a non-cutting link from its
    centre), every further lap starts where the previous one ended (:func:`centre_lap`), as long
    as at most ``max_wall_share`` of a lap runs along the final contour (clamped to the wall; a
    lap beyond it stops the centre and the arms take over). Arms: constant-engagement trochoidal
    periods with explicit roll-in / roll-out (:func:`cnclab.toolpath.trochoidal.ce_period`, radius
    ``job.roll_radius``) in each arm's frame (the front ignores material behind the start-hole
    centre, which belongs to another arm or a later round), joined by straight links through the
    cleared region.

    ``max_wall_share`` (fraction in (0, 1], or ``"auto"``, the default): with ``"auto"`` the path
    is planned for every value of ``wall_share_candidates`` (ascending), each plan is cut through
    the dixel simulator (the cutting-level model of :func:`cnclab.toolpath.evaluate.evaluate` at
    ``resolution_mm``, feed control on) and the
    winner is chosen by :func:`choose_candidate` (uncut area beyond the unreachable corners, then
    share above theta + 5 deg, then maximum engagement, then time, each with a tolerance). A
    candidate whose centre would stop at the same lap as the previous one gives the identical path
    and is not planned again (``"same as"`` in its record). ``stop_when_clean`` stops at the first
    candidate that is clean by :func:`choose_candidate`'s ``clean`` test (cheaper, but the later
    candidates are not seen). ``info`` then holds ``max_wall_share`` (the chosen value),
    ``wall_share_candidates`` (one metrics dict per candidate) and ``wall_share_choice`` (the
    reasons, stage by stage).
    """
    if not isinstance(job.polygon, Polygon) or job.polygon.interiors:
        raise ValueError(f"{job.source}: the hybrid strategy (Jacsó §4: centre laps around one start hole, arms "
                         "along the medial axis) plans a simple pocket without islands; use the "
                         "adaptive strategy for pockets with islands or several regions")
    if isinstance(max_wall_share, str):
        if max_wall_share != "auto":
            raise ValueError(f"max_wall_share must be a number in (0, 1] or 'auto', got {max_wall_share!r}")
    else:
        v = float(max_wall_share)
        if not 0 < v <= 1:
            raise ValueError(f"max_wall_share must be a number in (0, 1] or 'auto', got {max_wall_share!r}")
        return _hybrid_path_one(job, resolution_mm, dt, max_laps, max_periods, spacing_mm, max_rounds,
                                arm_min_area_mm2, v)
    cands = sorted(float(c) for c in wall_share_candidates)
    if not cands or not all(0 < c <= 1 for c in cands):
        raise ValueError(f"wall_share_candidates must be numbers in (0, 1], got {wall_share_candidates!r}")
    paths, rows = [], []
    # the feed control only scores the candidates (their time): a job whose cutting feed is above its
    # v_fmax (the default 1000 mm/min under a fast job's f_z x teeth x rpm) is scored with the cap at
    # that feed (the controller then only slows down); the program runs at the job's own feeds
    scored = job if job.v_fmax >= job.feed_mm_min else dataclasses.replace(job, v_fmax=job.feed_mm_min)
    for w in cands:
        prev = paths[-1] if paths else None
        stop = prev.info["stop_lap_wall_share"] if prev is not None else None
        if prev is not None and not (stop is not None and stop <= w):
            # the previous plan's centre stopped for a reason this value does not change (the
            # rejected lap ran along the wall on more than w, or no lap was rejected): same path
            paths.append(prev)
            rows.append(dict(rows[-1], max_wall_share=w, same_as=rows[-1]["max_wall_share"], plan_s=0.0))
            continue
        t0 = time.perf_counter()
        hp = _hybrid_path_one(job, resolution_mm, dt, max_laps, max_periods, spacing_mm, max_rounds,
                              arm_min_area_mm2, w)
        t1 = time.perf_counter()
        s = evaluate(hp, scored, resolution_mm, feed_control=True, level_only=True).trace["level_summary"]
        paths.append(hp)
        rows.append({"max_wall_share": w, "same_as": None, "laps": hp.info["laps"], "arms": len(hp.info["arms"]),
                     "uncut_beyond_unreachable_mm2": s["uncut_area_mm2"] - s["unreachable_area_mm2"],
                     "share_above_theta_plus5": s["share_above_theta_plus5"],
                     "engagement_max_deg": s["engagement_max_deg"], "time_s": s["time_s"],
                     "plan_s": t1 - t0, "evaluate_s": time.perf_counter() - t1})
        if stop_when_clean and choose_candidate(rows[-1:], job.polygon.area, job.theta_deg)[1]["clean"][0]:
            break
    i, why = choose_candidate(rows, job.polygon.area, job.theta_deg)
    hp = paths[i]
    hp.info.update(max_wall_share=cands[i], wall_share_candidates=rows, wall_share_choice=why)
    return hp


def choose_candidate(metrics, pocket_area_mm2, theta_deg=60.0, uncut_tol_frac=0.0025, share_tol=0.0025,
                     eng_tol_deg=2.0, clean_max_eng_margin_deg=50.0, clean_max_share=0.02):
    """Pick one of several planned paths from their simulated metrics (lexicographic, with tolerances).

    ``metrics``: list of dicts with ``uncut_beyond_unreachable_mm2`` (mm^2),
    ``share_above_theta_plus5`` (fraction of the cutting length), ``engagement_max_deg`` and
    ``time_s``. Successive filters, each keeping the candidates within a tolerance of the best:

    1. uncut area beyond the unreachable corners, within ``uncut_tol_frac`` x pocket area
       (0.25 %: 2.4 mm^2 on a 960 mm^2 pocket; this area moves by 0.3-0.4 mm^2 between 0.1 and
       0.05 mm dixels, a missed arm corner leaves several mm^2);
    2. share above theta + 5 deg, within ``share_tol`` (0.25 percentage points);
    3. maximum engagement, within ``eng_tol_deg`` (2 deg);
    4. the shortest machining time (first of equals: the smaller, earlier candidate).

    Returns ``(index, reasons)``; ``reasons`` holds the indices kept after each stage and
    ``clean`` (per candidate: uncut beyond unreachable within the stage-1 tolerance of zero, share
    above theta + 5 at most ``clean_max_share``, maximum engagement below theta +
    ``clean_max_eng_margin_deg``).

    >>> m = [{"uncut_beyond_unreachable_mm2": 10.1, "share_above_theta_plus5": 0.011,
    ...       "engagement_max_deg": 174.5, "time_s": 196.2},
    ...      {"uncut_beyond_unreachable_mm2": 2.0, "share_above_theta_plus5": 0.011,
    ...       "engagement_max_deg": 100.6, "time_s": 184.8}]
    >>> choose_candidate(m, 960.0)[0]
    1
    """
    if not metrics:
        raise ValueError("metrics must hold at least one candidate")
    keys = ("uncut_beyond_unreachable_mm2", "share_above_theta_plus5", "engagement_max_deg", "time_s")
    for j, m in enumerate(metrics):
        for k in keys:
            if k not in m or not np.isfinite(float(m[k])):
                raise ValueError(f"metrics[{j}]: '{k}' missing or not finite")
    tol_uncut = uncut_tol_frac * float(pocket_area_mm2)
    keep = list(range(len(metrics)))
    why = {}
    for key, tol in zip(keys[:3], (tol_uncut, share_tol, eng_tol_deg)):
        best = min(float(metrics[j][key]) for j in keep)
        keep = [j for j in keep if float(metrics[j][key]) <= best + tol]
        why[key] = {"best": best, "tolerance": tol, "kept": list(keep)}
    i = min(keep, key=lambda j: (float(metrics[j]["time_s"]), j))
    why["time_s"] = {"best": float(metrics[i]["time_s"]), "kept": [i]}
    why["clean"] = [bool(float(m["uncut_beyond_unreachable_mm2"]) <= tol_uncut
                         and float(m["share_above_theta_plus5"]) <= clean_max_share
                         and float(m["engagement_max_deg"]) < theta_deg + clean_max_eng_margin_deg)
                    for m in metrics]
    return i, why


#: mm: a period of an arm may leave the tool-centre region by this much (its chords along a curved wall:
#: up to 0.3 um on Jacsó's star and L); a period that leaves it by more (one chord across an inner
#: corner of a U: 4 mm into the wall) ends its arm. The wall-gouge tolerance of ``planners.plan``.
#: Measured from the exact tool-centre region (:func:`period_guard`), not from ``job.allowed()``, whose
#: 64-segment arcs round a reflex wall corner by chords already up to r (1 - cos(pi/256)) inside it
#: (0.3 um at r = 4 mm). The centre laps' chords are held to half of it: clamped to ``allowed`` point by
#: point, a lap on a 64 x 46 L (D8) reached 1.29 um into its reflex corner between two points
PERIOD_TOL_MM = 1e-3


def period_guard(pocket: Polygon, r: float, tol: float = PERIOD_TOL_MM) -> Polygon:
    """The tool centres (mm) whose disc of radius ``r`` reaches at most ``tol`` (+ ``5e-6 r``, the
    sagitta of its 256-segment arcs) past the walls of ``pocket``: the pocket shrunk by ``r - tol``.

    >>> from shapely.geometry import Point
    >>> g = period_guard(Polygon([(0, 0), (20, 0), (20, 10), (10, 10), (10, 20), (0, 20)]), 4.0)
    >>> d = g.boundary.distance(Point(10, 10))      # the reflex corner to the guard's nearest chord
    >>> bool(4.0 - 1e-3 - 2e-5 <= d <= 4.0 - 1e-3)
    True
    """
    return pocket.buffer(-(r - tol), 256)


def _hybrid_path_one(job, resolution_mm, dt, max_laps, max_periods, spacing_mm, max_rounds, arm_min_area_mm2,
                     max_wall_share):
    """:func:`hybrid_path` for one numeric ``max_wall_share``."""
    Stock = dixel.Stock
    r, th = job.tool_radius, job.theta_deg
    pocket, allowed = job.polygon, job.allowed()
    centre, hole_d, _ = entry_hole(job)
    c = np.asarray(centre, float)
    stock = Stock.from_polygon(pocket.difference(Point(c).buffer(0.5 * hole_d, 256)), resolution_mm)
    # 1. open centre: chained constant-engagement laps
    E = c + np.array([0.5 * hole_d - r, 0.0])       # touches the hole wall
    segs = [(subdivide(np.vstack([c, E]), resolution_mm), "link", "centre")]
    laps, stop_share = 0, None
    guard = period_guard(pocket, r)          # arms' periods (checked whole): within 1 um of the walls
    lap_guard = period_guard(pocket, r, 0.5 * PERIOD_TOL_MM).union(allowed)   # laps' chords (a margin)
    domain = pocket.buffer(-2 * resolution_mm)   # 2 rows: wall slivers must not join the cleared region
    for _ in range(int(max_laps)):
        try:
            P, inserted = centre_lap(stock, domain, tuple(c), E, r, th, allowed, dt, resolution_mm, lap_guard)
        except ValueError:
            break
        # the share of the lap's points (every step_mm; not the chords' inserted ones) on the wall
        on_wall = shapely.distance(shapely.points(P[~inserted]), allowed.exterior) < 1e-6
        if on_wall.mean() > max_wall_share:
            stop_share = float(on_wall.mean())
            break               # this lap would run along the final contour: the arms take over
        df = simulate(stock, P, r, job.a_p, job.feed_mm_min)
        if float(df.removed_mm2.sum()) < 1e-6:
            break
        segs.append((P, _label_lap(df.engagement_deg, th), "centre"))
        E = P[-1]
        laps += 1
    # 2. arms: the remaining material, split into arm regions (re-read after every arm)
    reach = allowed.buffer(r, 64)
    arms_done, periods, rounds = [], [], 0
    while rounds < int(max_rounds):
        regions = arm_regions(_polygonal(stock.to_polygon().intersection(reach)), c, r,
                              min_area_mm2=arm_min_area_mm2)
        if not regions:
            break
        rounds += 1
        for arm in regions:
            k = len(arms_done)
            arms_done.append(arm)
            world_mat = _polygonal(stock.to_polygon())
            material = _polygonal(world_mat.intersection(arm["region"]).intersection(reach))
            if material.is_empty or material.area < 1e-3:
                periods.append(0)
                continue
            ang = arm["axis_deg"] = arm_axis(material, c, arm["angle_deg"], r)     # the frame: x along it
            loc_mat = _polygonal(_rot(material, -ang, c))
            loc_all = _polygonal(_rot(world_mat, -ang, c))
            loc_allowed = _rot(allowed, -ang, c)
            loc_guard = _rot(guard, -ang, c)
            loc = Stock.from_polygon(loc_mat, resolution_mm)          # this arm's front
            full = Stock.from_polygon(loc_all, resolution_mm)         # all material: engagement
            arm_segs, last = [], None
            for _ in range(int(max_periods)):
                per = ce_period(full, r, th, loc_allowed, dt=dt, step_mm=resolution_mm,
                                roll_radius=job.roll_radius, a_p=job.a_p, feed_mm_min=job.feed_mm_min,
                                front_stock=loc, x_min=c[0])
                if per is None:
                    break
                Pl = per.xyz[:, :2]
                if not loc_guard.contains(LineString(Pl)):
                    break       # the period's chords leave the region (past an inner corner): the arm ends
                df = simulate(loc, Pl, r, job.a_p, job.feed_mm_min)
                simulate(full, Pl, r, job.a_p, job.feed_mm_min)
                if float(df.removed_mm2.sum()) < 1e-3:
                    break
                if last is not None:
                    arm_segs.append((_free_link(last, Pl[0], loc_allowed, full, r, resolution_mm)))
                arm_segs.append((Pl, pattern_kinds(per)))
                last = Pl[-1]
            periods.append(sum(1 for s in arm_segs if not isinstance(s[1], str)))
            if not arm_segs:
                continue
            S = _rot(arm_segs[0][0][:1], ang, c)[0]
            segs.append((*_free_link(segs[-1][0][-1], S, allowed, stock, r, resolution_mm, via=c), f"arm {k}"))
            world = []
            for Pl, kind in arm_segs:
                W = _rot(Pl, ang, c)
                segs.append((W, kind, f"arm {k}"))
                world.append(W)
            stock = _apply_world(stock, world, r)
    info = {"laps": laps, "arms": arms_done, "periods_per_arm": periods, "rounds": rounds,
            "medial_axis": medial_axis(pocket, spacing_mm), "max_wall_share": max_wall_share,
            "stop_lap_wall_share": stop_share}
    return _to_toolpath(segs, job, "hybrid (Jacsó §4)", info, resolution_mm)


#: an arm's periods advance along the long axis of its material (the principal axis of its area)
#: instead of the ray from the start centre when the material is at least this much longer than wide
#: (ratio of the standard deviations along the two axes): a leg of an L whose axis misses the start
#: centre (64 x 46 L, legs 20 and 30 wide, D8: along the ray at -10 deg the periods met the leg's wall
#: after 21 of them and 24 % of the level stayed uncut; along the leg's axis, 0.4 %)
ARM_AXIS_ELONGATION = 1.5
#: ... and when that axis is within this angle (deg) of the ray: material wider than long across the
#: ray (a star's arm after the centre laps: its long axis at 90 deg to the ray) keeps the ray
ARM_AXIS_MAX_TURN_DEG = 45.0


def arm_axis(material, center, ray_deg: float, tool_radius: float) -> float:
    """Direction (deg) along which an arm's constant-engagement periods advance: the principal axis of
    ``material`` (shapely, mm; the arm's share, sampled every r/6), pointing away from ``center``,
    when it is :data:`ARM_AXIS_ELONGATION` times longer than wide and within
    :data:`ARM_AXIS_MAX_TURN_DEG` of ``ray_deg`` (the direction of the arm seen from ``center``);
    otherwise ``ray_deg``.

    >>> from shapely.geometry import box
    >>> round(arm_axis(box(30, 0, 64, 20), (15.4, 15.4), -10.3, 4.0), 6)    # a leg below the centre
    0.0
    >>> arm_axis(box(-5, 10, 5, 14), (0, 0), 90.0, 3.0)      # wider than long across the ray: the ray
    90.0
    """
    P = _area_samples(material, tool_radius / 6.0)
    if len(P) < 20:
        return float(ray_deg)
    w, V = np.linalg.eigh(np.cov((P - P.mean(axis=0)).T))
    if not w[0] > 0 or math.sqrt(w[1] / w[0]) < ARM_AXIS_ELONGATION:
        return float(ray_deg)
    v = V[:, 1] if V[:, 1] @ (P.mean(axis=0) - np.asarray(center, float)) >= 0 else -V[:, 1]
    ax = math.degrees(math.atan2(v[1], v[0]))
    turn = (ax - ray_deg + 180.0) % 360.0 - 180.0
    return float(ax) if abs(turn) <= ARM_AXIS_MAX_TURN_DEG else float(ray_deg)


def arm_regions(material, center, tool_radius, min_area_mm2=1.0, open_mm=None):
    """Split the material left after the centre laps into arms (Jacsó §4: the narrowing arms).

    The material (shapely geometry, mm) is opened by ``open_mm`` (default r / 2: strips thinner
    than r along the walls do not make an arm); every remaining component larger than
    ``min_area_mm2`` is an arm, its axis the direction (deg) from ``center`` to its centroid — or
    several arms when the component has separate angular lobes seen from ``center`` (the two legs
    of an L joined around its inner corner: :func:`_angular_lobes`). The
    plane is split into angular sectors at the bisectors between neighbouring axes, so every bit
    of material (strips included) belongs to exactly one arm. Returns a list of dicts
    ``{"angle_deg", "region" (sector polygon), "area_mm2"}`` sorted by angle.

    >>> from shapely.geometry import box
    >>> m = box(0, 0, 4, 10).union(box(16, 0, 20, 10))          # two ends of a cleared slot
    >>> sorted(abs(round(a["angle_deg"])) for a in arm_regions(m, (10, 5), 3.0))
    [0, 180]
    """
    d = 0.5 * tool_radius if open_mm is None else open_mm
    if material.is_empty:
        return []
    core = material.buffer(-d, 16).buffer(d, 16)
    parts = [g for g in shapely.get_parts(core) if g.area > min_area_mm2]
    if not parts:
        parts = [g for g in shapely.get_parts(material) if g.area > min_area_mm2]
    if not parts:
        return []
    c = np.asarray(center, float)
    ang, area = [], []
    for p in parts:
        for a, ar in _angular_lobes(p, c, tool_radius):
            ang.append(a)
            area.append(ar)
    ang, area = np.array(ang), np.array(area)
    o = np.argsort(ang)
    ang, area = ang[o], area[o]
    b = shapely.bounds(material)
    reach = 2.0 * (np.hypot(b[2] - b[0], b[3] - b[1]) + np.hypot(*(c - b[:2])))
    out = []
    n = len(ang)
    for i in range(n):
        if n == 1:
            lo, hi = ang[i] - 180.0, ang[i] + 180.0
        else:
            prev, nxt = ang[i - 1] - (360.0 if i == 0 else 0.0), ang[(i + 1) % n] + (360.0 if i == n - 1 else 0.0)
            lo, hi = 0.5 * (prev + ang[i]), 0.5 * (ang[i] + nxt)
        out.append({"angle_deg": float((ang[i] + 180) % 360 - 180), "region": _sector(c, lo, hi, reach),
                    "area_mm2": float(area[i])})
    return out


def _area_samples(geom, h: float) -> np.ndarray:
    """(n, 2) mm: the centres of an ``h``-mm grid over ``geom``'s bounds that lie inside it (the area
    samples of :func:`_angular_lobes` and :func:`arm_axis`)."""
    x0, y0, x1, y1 = geom.bounds
    X, Y = np.meshgrid(np.arange(x0 + 0.5 * h, x1, h), np.arange(y0 + 0.5 * h, y1, h))
    m = shapely.contains_xy(geom, X, Y)
    return np.c_[X[m], Y[m]]


def _angular_lobes(part, center, tool_radius, bin_deg=5.0, valley=0.35, min_share=0.05):
    """Directions (deg) and areas (mm^2) of the lobes of ``part`` seen from ``center``.

    The area of ``part`` is histogrammed over the direction from ``center`` (grid samples every
    r/6, ``bin_deg`` bins, circular [1 2 1]/4 smoothing twice); neighbouring maxima separated by a
    minimum below ``valley`` times the lower maximum are separate lobes (e.g. the two legs of an L
    joined around its inner corner: one component, two arms). Lobes under ``min_share`` of the
    area join their neighbour. Returns [(direction deg, area mm^2)], one item for a single lobe.
    """
    c = np.asarray(center, float)
    S = _area_samples(part, tool_radius / 6.0)
    a = np.degrees(np.arctan2(S[:, 1] - c[1], S[:, 0] - c[0]))
    whole = [(math.degrees(math.atan2(part.centroid.y - c[1], part.centroid.x - c[0])), part.area)]
    if a.size < 20:
        return whole
    nb = int(round(360.0 / bin_deg))
    H = np.bincount(((a + 180.0) / bin_deg).astype(int) % nb, minlength=nb).astype(float)
    for _ in range(2):
        H = 0.25 * np.roll(H, 1) + 0.5 * H + 0.25 * np.roll(H, -1)
    peaks = np.flatnonzero((H > np.roll(H, 1)) & (H >= np.roll(H, -1)) & (H > 0))
    if peaks.size < 2:
        return whole
    # merge neighbouring peaks without a deep enough valley between them (circularly)
    peaks = list(peaks)
    changed = True
    while changed and len(peaks) > 1:
        changed = False
        for i in range(len(peaks)):
            p, q = peaks[i], peaks[(i + 1) % len(peaks)]
            idx = np.arange(p, p + ((q - p) % nb) + 1) % nb
            if H[idx].min() >= valley * min(H[p], H[q]):
                peaks.remove(p if H[p] < H[q] else q)
                changed = True
                break
    if len(peaks) < 2:
        return whole
    # lobe boundaries at the minima between consecutive peaks
    bounds = []
    for i in range(len(peaks)):
        p, q = peaks[i], peaks[(i + 1) % len(peaks)]
        idx = np.arange(p, p + ((q - p) % nb) + 1) % nb
        bounds.append(idx[int(np.argmin(H[idx]))])
    b = ((a + 180.0) / bin_deg).astype(int) % nb
    lobes = []
    for i in range(len(peaks)):
        lo, hi = bounds[i - 1], bounds[i]
        sel = ((b - lo) % nb) < ((hi - lo) % nb)
        if sel.any():
            z = np.exp(1j * np.radians(a[sel])).mean()
            lobes.append((math.degrees(np.angle(z)), part.area * sel.mean()))
    if min(ar for _, ar in lobes) < min_share * part.area:
        return whole
    return lobes


def _sector(center, a0_deg, a1_deg, radius):
    a = np.radians(np.linspace(a0_deg, a1_deg, max(int(abs(a1_deg - a0_deg) / 2), 8) + 1))
    c = np.asarray(center, float)
    return Polygon(np.vstack([c, c + radius * np.c_[np.cos(a), np.sin(a)]])).buffer(0)


def _free_link(E, S, allowed, stock, r, ds, via=None):
    """Linking move E -> S (mm): straight if the tool stays in ``allowed`` and clear of the
    ``stock`` material (sampled every ``ds``), else through ``via``, else a rapid jump
    (retract, G0, plunge into the cleared start). Returns (points, kind)."""
    guard = allowed.buffer(1e-6)
    for Q in ([E, S],) + (([E, via, S],) if via is not None else ()):
        Q = np.asarray(Q, float)
        if not guard.contains(LineString(Q)):
            continue
        pts = subdivide(Q, ds)
        if not any(disk_has_material(stock, p, r * 0.98) for p in pts[1:-1:2]):
            return pts, "link"
    return np.vstack([E, S]), "rapid"


def _polygonal(g):
    """Polygonal part of a geometry as a valid (Multi)Polygon (slivers under 1e-6 mm^2 dropped).

    >>> from shapely.geometry import box
    >>> bad = MultiPolygon([box(0, 0, 2, 2), box(1, 0, 3, 2), box(5, 5, 6, 6)])   # overlapping: invalid
    >>> round(_polygonal(bad).area, 6)        # make_valid nests a MultiPolygon in a collection: found
    7.0
    """
    parts = [p for p in polygon_parts(shapely.make_valid(g)) if p.area > 1e-6]
    if not parts:
        return Polygon()
    g = shapely.union_all(parts).buffer(0)
    if isinstance(g, MultiPolygon):
        g = MultiPolygon([p for p in g.geoms if p.area > 1e-6])
    return g


def _apply_world(stock, paths, r):
    for P in paths:
        for p in P:
            stock.cut_disk(p, r)
    return stock


def contour_parallel_path(job: Job, stepover=None, resolution_mm: float = 0.1) -> ToolPath:
    """Contour-parallel offsets (inside-out, :mod:`cnclab.toolpath.offsets`) at ``stepover`` (mm,
    default the nominal a_e); passes joined by jumps (retract, rapid, plunge)."""
    ae = job.a_e if stepover is None else stepover
    c = entry_hole(job)[0]
    allowed = job.allowed()
    levels = offset_levels(job.polygon, job.tool_radius, ae)
    passes = link_loops(levels, allowed, start=c)
    inside = raster_link(c, passes[0][0], allowed) is not None          # else a jump past an island
    segs = [(np.vstack([c, passes[0][0]]), "link" if inside else "rapid", "cp")]
    for i, P in enumerate(passes):
        if i > 0:
            segs.append((np.vstack([passes[i - 1][-1], P[0]]), "rapid", "cp"))
        segs.append((P, "cut", "cp"))
    return _to_toolpath(segs, job, "contour-parallel", {"stepover": ae}, resolution_mm)


#: a_e: the longest link between two raster rows along the wall (round a convex corner of the wall or
#: an island, where the straight chord leaves the tool-centre region); longer: a jump
ZIGZAG_ALONG_AE = 3.0


def zigzag_path(job: Job, stepover=None, angle_deg=0.0, resolution_mm: float = 0.1) -> ToolPath:
    """Zig-zag (direction-parallel) raster over the tool-centre region at ``stepover`` (mm, default
    a_e), alternate directions (:func:`cnclab.toolpath.zigzag.raster_lines`) cut cell by cell
    (:func:`cnclab.toolpath.zigzag.cell_order`: feed links between rows inside the region, along the
    wall round a corner; else a jump, re-entering by a ramp), then a finishing lap of every ring of the
    region (outlines and islands: removes the scallops)."""
    ae = job.a_e if stepover is None else stepover
    allowed = job.allowed()
    c = entry_hole(job)[0]
    A = _rot(allowed, -angle_deg, c)
    # tangency stubs are left to the finishing lap; an island or a neck splits the rows into cells,
    # each cut in one go (cell_order: one jump per cell, not one per row); a link between rows runs
    # along the wall (at most ZIGZAG_ALONG_AE a_e) where the chord would leave the region
    lines, links = cell_order(raster_lines(A, ae, min_length=0.5 * ae), A, ZIGZAG_ALONG_AE * ae)
    # the slot from the entry hole (the rotation's centre) to the first raster line, where it stays in the
    # tool-centre region; else (an island or a wall between them) a jump: retract, rapid, ramp down on it
    first = _rot(lines[0][:1], angle_deg, c)[0]
    segs = [(np.vstack([c, first]), "cut" if raster_link(c, lines[0][0], A) is not None else "rapid", "zz")]
    for q, link, prev in zip(lines, links, [None] + lines[:-1]):
        qq = _rot(q, angle_deg, c)
        if prev is not None:
            segs.append((_rot(link, angle_deg, c), "cut", "zz") if link is not None else
                        (np.vstack([_rot(prev[-1:], angle_deg, c)[0], qq[0]]), "rapid", "zz"))
        segs.append((qq, "cut", "zz"))
    for part in shapely.get_parts(allowed):                # finishing laps: every outline and island
        for ring in [np.asarray(part.exterior.coords)] + [np.asarray(i.coords) for i in part.interiors]:
            segs.append((np.vstack([segs[-1][0][-1], ring[0]]), "rapid", "zz"))
            segs.append((ring, "cut", "zz"))
    return _to_toolpath(segs, job, "zig-zag", {"stepover": ae}, resolution_mm)
