"""2.5D pocket roughing: user pocket input, medial axis, the Jacsó (2021, §4) hybrid path and the
comparison strategies (contour-parallel offsets, zig-zag) on the same pocket.

A pocket is a shapely ``Polygon`` (mm) with a pre-drilled start hole (diameter, mm) and cutting data
(:class:`PocketJob`). Units: mm, mm/min, m/min, degrees. ``tool_diameter`` is a *diameter*;
``tool_radius`` = diameter / 2 everywhere else.

Hybrid path (:func:`hybrid_path`), after the medial axis transformation (:func:`medial_axis`):

1. **open centre** — spiral-like constant-engagement laps around the start hole
   (:func:`cnclab.toolpath.constant_engagement.multi_pass`, Thesis III with the stock recomputed
   after every lap) until a lap touches the final contour;
2. **arms** — for every medial-axis branch that ends in a tip, constant-engagement trochoidal
   periods (:func:`cnclab.toolpath.trochoidal.ce_period`) in the branch's frame, the front
   recomputed from a dixel stock after every period, linked by arcs through the cleared region;
3. **linking** — straight moves between arms through the cleared centre (fast linking feed).

Every strategy is a :class:`StrategyPath` (points + per-point link flags); :func:`evaluate_strategy`
cuts it through one dixel stock (pocket minus start hole) and reports engagement maxima, the share
of the path above theta + 5 deg, machining time and the uncut area; :func:`to_gcode_moves` exports
it as RS274/NGC moves.

>>> job = PocketJob.from_dict({"polygon": [[0, 0], [40, 0], [40, 30], [0, 30]],
...                            "start_hole": {"center": [20, 15], "diameter": 11}})
>>> round(job.volume_mm3(), 1)                # a_p (A_pocket - A_hole) = 3 (1200 - 95.03)
3314.9
>>> PocketJob.from_dict({"polygon": [[0, 0], [5, 0], [5, 30], [0, 30]],
...                      "start_hole": {"center": [2.5, 15], "diameter": 4}})
Traceback (most recent call last):
...
ValueError: <dict>: the tool (diameter 6 mm) cannot enter the pocket: it is narrower than the tool
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import shapely
from shapely import affinity
from shapely.geometry import LineString, Point, Polygon

__all__ = ["PocketJob", "load_pocket", "star_polygon", "design_star", "medial_axis", "arm_branches", "arm_regions",
           "StrategyPath", "centre_lap", "hybrid_path", "choose_candidate", "contour_parallel_path", "zigzag_path",
           "evaluate_strategy", "to_gcode_moves"]


# ---------------------------------------------------------------------------------------------
# input
# ---------------------------------------------------------------------------------------------
@dataclass
class PocketJob:
    """Pocket and cutting data. Lengths mm, v_c m/min, f_z mm/tooth, feeds mm/min, theta deg."""

    polygon: Polygon
    start_center: tuple
    start_hole_diameter: float
    tool_diameter: float = 6.0
    teeth: int = 1
    v_c: float = 120.0
    f_z: float = 0.04
    a_p: float = 3.0
    theta_deg: float = 60.0
    link_feed: float = 1500.0
    v_fmax: float = 1000.0
    roll_radius: float = 1.0
    source: str = "<dict>"
    feed_mm_min: float | None = None

    @property
    def tool_radius(self) -> float:
        return 0.5 * self.tool_diameter

    @property
    def spindle_rpm(self) -> float:
        """n = 1000 v_c / (pi D) (rpm)."""
        return 1000.0 * self.v_c / (math.pi * self.tool_diameter)

    @property
    def feed(self) -> float:
        """Nominal feed (mm/min): ``feed_mm_min`` if given (e.g. the rounded catalogue value), else
        v_f = f_z z n."""
        return self.feed_mm_min if self.feed_mm_min else self.f_z * self.teeth * self.spindle_rpm

    @property
    def a_e(self) -> float:
        """Radial depth of a straight cut at theta: r (1 - cos theta) (mm)."""
        return self.tool_radius * (1 - math.cos(math.radians(self.theta_deg)))

    def mrr_nominal(self, feed=None) -> float:
        """MRR_nom = a_p a_e v_f (mm^3/min)."""
        return self.a_p * self.a_e * (self.feed if feed is None else feed)

    def start_hole(self) -> Polygon:
        return Point(self.start_center).buffer(0.5 * self.start_hole_diameter, 256)

    def volume_mm3(self) -> float:
        """Material to remove: a_p (pocket area - start-hole area) (mm^3)."""
        return self.a_p * self.polygon.difference(self.start_hole()).area

    def allowed(self) -> Polygon:
        """Tool-centre region: the pocket shrunk by the tool radius."""
        return self.polygon.buffer(-self.tool_radius, 64)

    @classmethod
    def from_dict(cls, d: dict, source: str = "<dict>") -> "PocketJob":
        """Build and validate from a mapping (the JSON layout of :func:`load_pocket`)."""
        def num(key, default, sub=None):
            v = (d.get(sub, {}) if sub else d).get(key, default)
            try:
                v = float(v)
            except (TypeError, ValueError):
                raise ValueError(f"{source}: '{key}' must be a number, got {v!r}") from None
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{source}: '{key}' must be a positive number, got {v!r}")
            return v

        pts = d.get("polygon")
        if pts is None:
            raise ValueError(f"{source}: missing 'polygon' (a list of [x, y] points in mm)")
        try:
            P = np.asarray(pts, float)
        except (TypeError, ValueError):
            raise ValueError(f"{source}: 'polygon' must be a list of [x, y] points in mm") from None
        if P.ndim != 2 or P.shape[1] != 2 or len(P) < 3 or not np.all(np.isfinite(P)):
            raise ValueError(f"{source}: 'polygon' must hold >= 3 finite [x, y] points in mm")
        poly = Polygon(P)
        if not poly.is_valid or poly.area <= 0:
            raise ValueError(f"{source}: 'polygon' is not a simple polygon ({shapely.is_valid_reason(poly)})")
        tool = num("tool_diameter", 6.0)
        hole = d.get("start_hole", {})
        centre = hole.get("center")
        if centre is None:
            centre = shapely.get_coordinates(shapely.maximum_inscribed_circle(poly, 0.01))[0]
        centre = tuple(float(c) for c in centre)
        job = cls(poly, centre, num("diameter", 11.0, "start_hole"), tool, int(num("teeth", 1)),
                  num("v_c", 120.0), num("f_z", 0.04), num("a_p", 3.0), num("theta_deg", 60.0),
                  num("link_feed", 1500.0), num("v_fmax", 1000.0), num("roll_radius", 1.0), source,
                  num("feed_mm_min", 1.0) if "feed_mm_min" in d else None)
        job.validate()
        return job

    def validate(self) -> None:
        """Refuse jobs the tool cannot machine; ValueError naming the source and the reason."""
        if not 0 < self.theta_deg <= 180:
            raise ValueError(f"{self.source}: theta_deg must be in (0, 180], got {self.theta_deg}")
        allowed = self.allowed()
        if allowed.is_empty or allowed.area < 1e-6:
            raise ValueError(f"{self.source}: the tool (diameter {self.tool_diameter:g} mm) cannot enter "
                             "the pocket: it is narrower than the tool")
        if self.start_hole_diameter < self.tool_diameter:
            raise ValueError(f"{self.source}: start hole diameter {self.start_hole_diameter:g} mm is smaller "
                             f"than the tool diameter {self.tool_diameter:g} mm: the tool cannot enter it")
        if not self.polygon.buffer(1e-9).contains(self.start_hole()):
            raise ValueError(f"{self.source}: the start hole at {self.start_center} (diameter "
                             f"{self.start_hole_diameter:g} mm) is not inside the pocket")


def load_pocket(path) -> PocketJob:
    """Read a pocket job JSON (read-only): ``{"polygon": [[x, y], ...], "start_hole": {"center":
    [x, y], "diameter": d}, "tool_diameter": 6, "v_c": 120, "f_z": 0.04, "teeth": 1, "a_p": 3,
    "theta_deg": 60, "link_feed": 1500, "v_fmax": 1000}`` (mm, m/min, mm/min, deg).
    Errors name the file (and the line for JSON syntax errors)."""
    p = Path(path)
    try:
        d = json.loads(p.read_text(encoding="utf-8"))
    except json.JSONDecodeError as e:
        raise ValueError(f"{p}:{e.lineno}: invalid JSON ({e.msg})") from None
    if not isinstance(d, dict):
        raise ValueError(f"{p}: the top level must be a JSON object")
    if "star" in d and "polygon" not in d:
        d = dict(d, polygon=shapely.get_coordinates(star_polygon(**d["star"]).exterior).tolist())
    return PocketJob.from_dict(d, source=str(p))


# ---------------------------------------------------------------------------------------------
# the star pocket of §4 (contour not printed: a parameterised stand-in)
# ---------------------------------------------------------------------------------------------
def star_polygon(n_arms=5, outer_radius=23.0, inner_ratio=0.5, tip_radius=4.0, root_radius=2.0,
                 center=(0.0, 0.0), rotation_deg=90.0, quad_segs=32) -> Polygon:
    """Rounded star (mm): a regular star polygon with tips at ``outer_radius`` and roots at
    ``inner_ratio * outer_radius``, its convex tips rounded with ``tip_radius`` (the pocket's concave
    corners: must exceed the tool radius for the tool to follow) and its roots with ``root_radius``.

    Rounding is morphological: tips by an opening (buffer -rt, +rt), roots by a closing (+rr, -rr).
    """
    n = int(n_arms)
    if n < 3:
        raise ValueError(f"n_arms must be >= 3, got {n_arms!r}")
    if not 0 < inner_ratio < 1:
        raise ValueError(f"inner_ratio must be in (0, 1), got {inner_ratio!r}")
    k = np.arange(2 * n)
    rad = np.where(k % 2 == 0, outer_radius, inner_ratio * outer_radius)
    ang = np.radians(rotation_deg) + k * np.pi / n
    poly = Polygon(np.c_[center[0] + rad * np.cos(ang), center[1] + rad * np.sin(ang)])
    poly = poly.buffer(-tip_radius, quad_segs).buffer(tip_radius, quad_segs)
    poly = poly.buffer(root_radius, quad_segs).buffer(-root_radius, quad_segs)
    return shapely.set_precision(poly, 1e-9)


def design_star(volume_mm3, a_p, hole_diameter, **star_kw) -> float:
    """Outer radius (mm) of :func:`star_polygon` whose volume a_p (A - A_hole) equals ``volume_mm3``."""
    from scipy.optimize import brentq

    hole = math.pi * (0.5 * hole_diameter) ** 2
    star_kw = {k: v for k, v in star_kw.items() if k != "outer_radius"}

    def f(R):
        return a_p * (star_polygon(outer_radius=R, **star_kw).area - hole) - volume_mm3

    return float(brentq(f, 10.0, 100.0, xtol=1e-9))


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
    segs = np.asarray(shapely.get_parts(shapely.line_merge(edges) if False else edges))
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
@dataclass
class StrategyPath:
    """Tool-centre polyline (N, 2) mm with per-point labels of the segment ending at point i:
    ``kinds[i]`` in {"cut", "roll-in", "roll-out", "link", "rapid"}; ``link`` (link or rapid: no
    cutting intended) and ``rapid`` (retract-G0-plunge jump above the part) are derived from it;
    ``phase`` labels (e.g. 'centre', 'arm 2')."""

    points: np.ndarray
    kinds: np.ndarray
    phase: np.ndarray
    name: str = ""
    info: dict = field(default_factory=dict)

    @property
    def link(self) -> np.ndarray:
        return np.isin(self.kinds, ("link", "rapid"))

    @property
    def rapid(self) -> np.ndarray:
        return self.kinds == "rapid"

    @staticmethod
    def build(segments, name="", info=None):
        """From a list of (points (n,2), kind, phase) in path order; kind in
        {"cut", "roll-in", "roll-out", "link", "rapid"} or an (n,) array of kinds."""
        pts, kinds, phase = [], [], []
        for P, kind, ph in segments:
            P = np.asarray(P, float)
            K = np.asarray(kind, dtype=object) if not isinstance(kind, str) else np.full(len(P), kind, dtype=object)
            if len(K) != len(P):
                raise ValueError(f"segment kinds ({len(K)}) and points ({len(P)}) differ")
            bad = set(K) - KINDS
            if bad:
                raise ValueError(f"kind must be one of {sorted(KINDS)}, got {sorted(bad)}")
            if pts and np.hypot(*(P[0] - pts[-1][-1])) < 1e-9:
                P, K = P[1:], K[1:]
            if len(P) == 0:
                continue
            pts.append(P)
            kinds.append(K)
            phase.append(np.full(len(P), ph, dtype=object))
        kinds[0] = kinds[0].copy()
        kinds[0][0] = "cut" if kinds[0][0] == "rapid" else kinds[0][0]
        return StrategyPath(np.vstack(pts), np.concatenate(kinds), np.concatenate(phase), name, info or {})

    def lengths(self) -> dict:
        """Length (mm) per kind."""
        ds = np.r_[0.0, np.hypot(*np.diff(self.points, axis=0).T)]
        return {k: float(ds[self.kinds == k].sum()) for k in sorted(KINDS)}


KINDS = {"cut", "roll-in", "roll-out", "link", "rapid"}


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


def centre_lap(stock, domain, seed_xy, start_xy, tool_radius, theta_deg, allowed, dt=0.1, step_mm=0.05):
    """One spiral-like constant-engagement lap around the cleared region containing ``seed_xy``.

    The boundary of the cleared region is read from the dixel ``stock``
    (:func:`~cnclab.toolpath.constant_engagement.cleared_boundary_contour`), re-parametrised to start
    at the boundary point touched by the tool at ``start_xy`` (the previous lap's end, or a point
    touching the start hole), and Thesis III runs one full turn from ``start_xy``: the lap blends in
    from the previous one (engagement 0 -> theta, no radial plunge) and closes on its own start.
    Tool centres are clamped to ``allowed``. Returns the (n, 2) centre points (mm).
    """
    from .constant_engagement import (ShiftedContour, clamp_to_region, cleared_boundary_contour, lap_start,
                                      resample_path, thesis3_path)

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
    return clamp_to_region(resample_path(res.P, step_mm), allowed)


WALL_SHARE_CANDIDATES = (0.3, 0.5)


def hybrid_path(job: PocketJob, resolution_mm=0.05, dt=0.1, max_laps=20, max_periods=200,
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
    the dixel simulator (:func:`evaluate_strategy` at ``resolution_mm``, feed control on) and the
    winner is chosen by :func:`choose_candidate` (uncut area beyond the unreachable corners, then
    share above theta + 5 deg, then maximum engagement, then time, each with a tolerance). A
    candidate whose centre would stop at the same lap as the previous one gives the identical path
    and is not planned again (``"same as"`` in its record). ``stop_when_clean`` stops at the first
    candidate that is clean by :func:`choose_candidate`'s ``clean`` test (cheaper, but the later
    candidates are not seen). ``info`` then holds ``max_wall_share`` (the chosen value),
    ``wall_share_candidates`` (one metrics dict per candidate) and ``wall_share_choice`` (the
    reasons, stage by stage).
    """
    if isinstance(max_wall_share, str):
        if max_wall_share != "auto":
            raise ValueError(f"max_wall_share must be a number in (0, 1] or 'auto', got {max_wall_share!r}")
    else:
        v = float(max_wall_share)
        if not 0 < v <= 1:
            raise ValueError(f"max_wall_share must be a number in (0, 1] or 'auto', got {max_wall_share!r}")
        return _hybrid_path_one(job, resolution_mm, dt, max_laps, max_periods, spacing_mm, max_rounds,
                                arm_min_area_mm2, v)
    import time

    cands = sorted(float(c) for c in wall_share_candidates)
    if not cands or not all(0 < c <= 1 for c in cands):
        raise ValueError(f"wall_share_candidates must be numbers in (0, 1], got {wall_share_candidates!r}")
    paths, rows = [], []
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
        _, s = evaluate_strategy(hp, job, resolution_mm, feed_control=True)
        paths.append(hp)
        rows.append({"max_wall_share": w, "same_as": None, "laps": hp.info["laps"], "arms": len(hp.info["arms"]),
                     "uncut_beyond_unreachable_mm2": s["uncut_area_mm2"] - s["unreachable_area_mm2"],
                     "share_above_theta_plus5": s["share_above_theta_plus5"],
                     "max_engagement_deg": s["max_engagement_deg"], "time_s": s["time_s"],
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
    ``share_above_theta_plus5`` (fraction of the cutting length), ``max_engagement_deg`` and
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
    ...       "max_engagement_deg": 174.5, "time_s": 196.2},
    ...      {"uncut_beyond_unreachable_mm2": 2.0, "share_above_theta_plus5": 0.011,
    ...       "max_engagement_deg": 100.6, "time_s": 184.8}]
    >>> choose_candidate(m, 960.0)[0]
    1
    """
    if not metrics:
        raise ValueError("metrics must hold at least one candidate")
    keys = ("uncut_beyond_unreachable_mm2", "share_above_theta_plus5", "max_engagement_deg", "time_s")
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
                         and float(m["max_engagement_deg"]) < theta_deg + clean_max_eng_margin_deg)
                    for m in metrics]
    return i, why


def _hybrid_path_one(job, resolution_mm, dt, max_laps, max_periods, spacing_mm, max_rounds, arm_min_area_mm2,
                     max_wall_share):
    """:func:`hybrid_path` for one numeric ``max_wall_share``."""
    from cnclab.simulation.common import simulate
    from cnclab.simulation.dixel import Stock

    from .trochoidal import _link, ce_period

    r, th = job.tool_radius, job.theta_deg
    pocket, allowed = job.polygon, job.allowed()
    c = np.asarray(job.start_center, float)
    stock = Stock.from_polygon(pocket.difference(job.start_hole()), resolution_mm)
    # 1. open centre: chained constant-engagement laps
    E = c + np.array([0.5 * job.start_hole_diameter - r, 0.0])       # touches the hole wall
    segs = [(_link(c, E, None, resolution_mm), "link", "centre")]
    laps, stop_share = 0, None
    domain = pocket.buffer(-2 * resolution_mm)   # 2 rows: wall slivers must not join the cleared region
    for _ in range(int(max_laps)):
        try:
            P = centre_lap(stock, domain, tuple(c), E, r, th, allowed, dt, resolution_mm)
        except ValueError:
            break
        on_wall = shapely.distance(shapely.points(P), allowed.exterior) < 1e-6
        if on_wall.mean() > max_wall_share:
            stop_share = float(on_wall.mean())
            break               # this lap would run along the final contour: the arms take over
        df = simulate(stock, P, r, job.a_p, job.feed)
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
            ang = arm["angle_deg"]
            world_mat = _polygonal(stock.to_polygon())
            material = _polygonal(world_mat.intersection(arm["region"]).intersection(reach))
            if material.is_empty or material.area < 1e-3:
                periods.append(0)
                continue
            loc_mat = _polygonal(_rot(material, -ang, c))
            loc_all = _polygonal(_rot(world_mat, -ang, c))
            loc_allowed = _rot(allowed, -ang, c)
            loc = Stock.from_polygon(loc_mat, resolution_mm)          # this arm's front
            full = Stock.from_polygon(loc_all, resolution_mm)         # all material: engagement
            arm_segs, last = [], None
            for _ in range(int(max_periods)):
                per = ce_period(full, r, th, loc_allowed, dt=dt, step_mm=resolution_mm,
                                roll_radius=job.roll_radius, a_p=job.a_p, feed_mm_min=job.feed,
                                front_stock=loc, x_min=c[0])
                if per is None:
                    break
                Pl = per.points
                df = simulate(loc, Pl, r, job.a_p, job.feed)
                simulate(full, Pl, r, job.a_p, job.feed)
                if float(df.removed_mm2.sum()) < 1e-3:
                    break
                if last is not None:
                    arm_segs.append((_free_link(last, Pl[0], loc_allowed, full, r, resolution_mm)))
                arm_segs.append((Pl, per.kinds))
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
    return StrategyPath.build(segs, "hybrid (Jacsó §4)", info)


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


def _angular_lobes(part, center, tool_radius, bin_deg=5.0, valley=0.35, min_share=0.05):
    """Directions (deg) and areas (mm^2) of the lobes of ``part`` seen from ``center``.

    The area of ``part`` is histogrammed over the direction from ``center`` (grid samples every
    r/6, ``bin_deg`` bins, circular [1 2 1]/4 smoothing twice); neighbouring maxima separated by a
    minimum below ``valley`` times the lower maximum are separate lobes (e.g. the two legs of an L
    joined around its inner corner: one component, two arms). Lobes under ``min_share`` of the
    area join their neighbour. Returns [(direction deg, area mm^2)], one item for a single lobe.
    """
    c = np.asarray(center, float)
    x0, y0, x1, y1 = part.bounds
    h = tool_radius / 6.0
    X, Y = np.meshgrid(np.arange(x0 + 0.5 * h, x1, h), np.arange(y0 + 0.5 * h, y1, h))
    m = shapely.contains_xy(part, X, Y)
    a = np.degrees(np.arctan2(Y[m] - c[1], X[m] - c[0]))
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
    from .trochoidal import _disk_has_material, _link

    guard = allowed.buffer(1e-6)
    for Q in ([E, S],) + (([E, via, S],) if via is not None else ()):
        Q = np.asarray(Q, float)
        if not guard.contains(LineString(Q)):
            continue
        pts = np.vstack([_link(Q[i], Q[i + 1], None, ds)[(1 if i else 0):] for i in range(len(Q) - 1)])
        if not any(_disk_has_material(stock, p, r * 0.98) for p in pts[1:-1:2]):
            return pts, "link"
    return np.vstack([E, S]), "rapid"


def _polygonal(g):
    """Polygonal part of a geometry as a valid (Multi)Polygon (slivers under 1e-6 mm^2 dropped)."""
    from shapely.geometry import MultiPolygon

    parts = [p for p in shapely.get_parts(shapely.make_valid(g)) if isinstance(p, Polygon) and p.area > 1e-6]
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


def contour_parallel_path(job: PocketJob, stepover=None):
    """Contour-parallel offsets (inside-out, :mod:`cnclab.toolpath.offsets`) at ``stepover``
    (default the nominal a_e); passes joined by rapids (retract, G0, plunge)."""
    from .offsets import link_loops, offset_levels

    ae = job.a_e if stepover is None else stepover
    levels = offset_levels(job.polygon, job.tool_radius, ae)
    passes = link_loops(levels, job.allowed(), start=job.start_center)
    segs = [(np.vstack([job.start_center, passes[0][0]]), "link", "cp")]
    for i, P in enumerate(passes):
        if i > 0:
            segs.append((np.vstack([passes[i - 1][-1], P[0]]), "rapid", "cp"))
        segs.append((P, "cut", "cp"))
    return StrategyPath.build(segs, "contour-parallel", {"stepover": ae})


def zigzag_path(job: PocketJob, stepover=None, angle_deg=0.0):
    """Zig-zag (direction-parallel) raster over the tool-centre region at ``stepover`` (default a_e),
    alternate directions, straight feed links along the boundary side when inside the region
    (else retract-rapid), then one finishing lap of the region boundary (removes the scallops)."""
    ae = job.a_e if stepover is None else stepover
    allowed = job.allowed()
    c = job.start_center
    A = _rot(allowed, -angle_deg, c)
    x0, y0, x1, y1 = A.bounds
    lines = []
    ys = np.arange(y0 + 1e-6, y1, ae)
    for i, y in enumerate(ys):
        g = A.intersection(LineString([(x0 - 1, y), (x1 + 1, y)]))
        parts = [np.asarray(p.coords) for p in shapely.get_parts(g) if p.length > 1e-6]
        parts = sorted(parts, key=lambda q: q[:, 0].min())
        for q in parts:
            q = q[np.argsort(q[:, 0])]
            lines.append(q if i % 2 == 0 else q[::-1])
    guard = A.buffer(1e-6)
    segs = [(np.vstack([c, _rot(lines[0][:1], angle_deg, c)[0]]), "rapid", "zz")]
    prev = None
    for q in lines:
        qq = _rot(q, angle_deg, c)
        if prev is not None:
            kind = "cut" if guard.contains(LineString([q[0], prev])) else "rapid"
            segs.append((np.vstack([_rot(prev[None], angle_deg, c)[0], qq[0]]), kind, "zz"))
        segs.append((qq, "cut", "zz"))
        prev = q[-1]
    ring = np.asarray(allowed.exterior.coords)
    segs.append((np.vstack([segs[-1][0][-1], ring[0]]), "rapid", "zz"))
    segs.append((ring, "cut", "zz"))
    return StrategyPath.build(segs, "zig-zag", {"stepover": ae})


# ---------------------------------------------------------------------------------------------
# evaluation, feed control and G-code
# ---------------------------------------------------------------------------------------------
def _resample_strategy(path: StrategyPath, step_mm):
    """Insert points so no segment exceeds ``step_mm`` (labels carried by the segment end)."""
    P = path.points
    d = np.hypot(*np.diff(P, axis=0).T)
    n = np.maximum(np.ceil(d / step_mm).astype(int), 1)
    seg = np.repeat(np.arange(1, len(P)), n)                       # segment index of each new point
    t = (np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n) + 1) / np.repeat(n, n)
    Q = P[seg - 1] + t[:, None] * (P[seg] - P[seg - 1])
    return StrategyPath(np.vstack([P[:1], Q]), np.r_[path.kinds[:1], path.kinds[seg]],
                        np.r_[path.phase[:1], path.phase[seg]], path.name, path.info)


SEGMENT_KINDS = ("cut", "roll-in", "roll-out", "link")


def evaluate_strategy(path: StrategyPath, job: PocketJob, resolution_mm=0.05, feed_control=False,
                      block_mm=0.5, margin_deg=5.0, link_tol_mm2=1e-3, mrr_window_mm=1.0):
    """Cut ``path`` through the pocket stock (pocket minus start hole) with the dixel simulator.

    Rapid jumps are not simulated (the tool is above the part). Linking moves run at the linking
    feed only if they remove (almost) nothing: a link step removing more than ``link_tol_mm2`` is
    flagged ``link_cuts`` and runs at the cutting feed and counts as cutting. With
    ``feed_control`` the roll-in/roll-out steps get the MRR-holding feed
    (:func:`cnclab.cutting.feed_control.controlled_feed`, capped at ``job.v_fmax``).

    Returns ``(table, summary)``: the per-step DataFrame (columns of
    :func:`cnclab.simulation.common.simulate` plus ``kind``, ``phase``, ``link_cuts``,
    ``feed_mm_min``, ``mrr_ctrl_mm3_min``) and a dict: engagement maximum and share of length
    above theta + ``margin_deg`` overall and per segment kind (``max_eng_<kind>_deg``,
    ``share_above_<kind>``), lengths, machining time (s), uncut area (mm^2), the theoretical
    minimum V / MRR_nom and the MRR error over the "cut" segments
    (:func:`cnclab.cutting.feed_control.mrr_error_windowed`, windows of ``mrr_window_mm``).
    """
    from cnclab.cutting.feed_control import controlled_feed, mrr_error_windowed
    from cnclab.simulation import dixel

    p = _resample_strategy(path, resolution_mm)
    stock = dixel.Stock.from_polygon(job.polygon.difference(job.start_hole()), resolution_mm)
    T = dixel.simulate_runs(stock, p.points, p.rapid, job.tool_radius, job.a_p, job.feed, f_z=job.f_z,
                            teeth=job.teeth)
    idx = T.point.to_numpy()
    # the plunge after a rapid is a link
    T["kind"] = np.where(T.plunge.to_numpy() & (idx > 0), "link", np.asarray(p.kinds, dtype=object)[idx])
    T["phase"] = np.asarray(p.phase, dtype=object)[idx]
    kinds = T.kind.to_numpy()
    rem = T.removed_mm2.to_numpy()
    T["link_cuts"] = (kinds == "link") & (rem > link_tol_mm2)
    cut = (kinds != "link") | T.link_cuts.to_numpy()
    v = np.where(cut, job.feed, job.link_feed)
    if feed_control:
        adj = np.isin(kinds, ("roll-in", "roll-out"))
        vc = controlled_feed(rem, T.ds.to_numpy(), T.engagement_deg.to_numpy(), cut, job.a_e, job.feed,
                             job.v_fmax, job.theta_deg, block_mm, margin_deg, adjust=adj)
        v = np.where(cut, vc, job.link_feed)
    T["feed_mm_min"] = v
    ds = T.ds.to_numpy()
    with np.errstate(divide="ignore", invalid="ignore"):
        T["mrr_ctrl_mm3_min"] = np.where(ds > 0, job.a_p * rem / ds * v, np.nan)
    eng = T.engagement_deg.to_numpy()
    time_s = 60.0 * float(np.sum(ds / v))
    Lc = float(ds[cut].sum())
    lim = job.theta_deg + margin_deg
    summary = {"strategy": path.name, "max_engagement_deg": float(np.nanmax(eng[cut])),
               "share_above_theta_plus5": float(ds[cut & (eng > lim)].sum()) / Lc,
               "cut_length_mm": Lc, "link_length_mm": float(ds[~cut].sum()),
               "rapid_length_mm": p.lengths()["rapid"],
               "link_cutting_length_mm": float(ds[T.link_cuts.to_numpy()].sum()),
               "link_removed_mm3": job.a_p * float(rem[kinds == "link"].sum())}
    for k in SEGMENT_KINDS:
        m = kinds == k
        Lk = float(ds[m].sum())
        summary[f"length_{k}_mm"] = Lk
        summary[f"max_eng_{k}_deg"] = float(np.nanmax(eng[m])) if np.isfinite(eng[m]).any() else float("nan")
        summary[f"share_above_{k}"] = float(ds[m & (eng > lim)].sum()) / Lk if Lk > 0 else float("nan")
    reach = job.allowed().buffer(job.tool_radius, 64)
    summary.update({"time_s": time_s, "uncut_area_mm2": stock.area(),
                    "unreachable_area_mm2": float(job.polygon.difference(reach).area),
                    "removed_volume_mm3": job.a_p * float(rem.sum()),
                    "t_min_s": 60.0 * job.volume_mm3() / job.mrr_nominal()})
    summary["time_over_min"] = summary["time_s"] / summary["t_min_s"]
    err = mrr_error_windowed(rem, ds, v, job.a_p, job.mrr_nominal(), kinds == "cut", mrr_window_mm)
    summary["mrr_error_cut_pct"] = err["mean_abs_pct"]
    summary["mrr_error_cut_p95_pct"] = err["p95_abs_pct"]
    return T, summary


def to_gcode_moves(path: StrategyPath, job: PocketJob, feeds=None, z_cut=None, z_clear=5.0,
                   decimals=4):
    """RS274/NGC moves: G0 to the start above the part, plunge, then G1 per segment at the cutting
    feed (or ``feeds[i]`` mm/min per point, e.g. the controlled feed), links at the linking feed,
    rapid jumps as retract-G0-plunge. ``z_cut`` defaults to -a_p."""
    from .path import Move

    z = -job.a_p if z_cut is None else z_cut
    S = job.spindle_rpm
    P = path.points
    mv = [Move("G0", P[0, 0], P[0, 1], z_clear), Move("G1", P[0, 0], P[0, 1], z, feed=job.feed, spindle=S)]
    link = path.link
    for i in range(1, len(P)):
        if path.rapid[i]:
            mv += [Move("G0", P[i - 1, 0], P[i - 1, 1], z_clear), Move("G0", P[i, 0], P[i, 1], z_clear),
                   Move("G1", P[i, 0], P[i, 1], z, feed=job.feed, spindle=S)]
            continue
        f = job.link_feed if link[i] else (job.feed if feeds is None else float(feeds[i]))
        mv.append(Move("G1", P[i, 0], P[i, 1], z, feed=f, spindle=S))
    mv.append(Move("G0", P[-1, 0], P[-1, 1], z_clear, spindle=S))
    return mv
