"""Constant-MRR contour-parallel path by pixel simulation — Kim & Yang (2006), §3.2–3.3.

Pipeline (all lengths mm, feed mm/min, spindle rpm, MRR mm³/min):

1. a contour-parallel base path (:mod:`cnclab.toolpath.offsets`), optionally with a spiral entry
   (:func:`spiral_entry`) at the start of each pass;
2. :func:`modify_path` — the §3.2 pseudo-code on a pixel stock (:mod:`cnclab.simulation.pixel`):
   for every segment ``Linear_Motion`` counts the not-yet-visited pixels swept by the tool
   (:func:`linear_motion`); when the count exceeds the reference (eq. 4),
   ``Additional_Path_Insertion`` shifts the end point to the **left** of the moving direction
   (into the machined side) until the count is at or below the reference, inserts that segment,
   extends it by the same length while the extension is still excessive, and inserts a return path
   to the segment start; the original segment is then re-checked (and cut);
3. §3.3 post-step: :func:`fit_arcs` replaces runs of short segments by G2/G3 circular moves;
   :func:`passes_path` makes the :class:`~cnclab.toolpath.path.ToolPath` (:func:`kim_yang_passes` plans a job).

Eq. 4, the reference pixel count of one tool advance ``Δs`` (feed per tooth) at step length ``s``
(radial depth) on pixels of side ``p``: ``(Δs/p)·(s/p)``. The paper does **not** give the tooth count
needed for ``Δs = v_f/(n·z)``: we use :data:`DEFAULT_TEETH` = 2 (a two-flute Ø10 mm carbide end mill,
Δs = 500/(2000·2) = 0.125 mm). Since Δs is below the 0.3 mm pixel, a single tooth advance sweeps
only ~4 pixels and its count is quantisation noise; :func:`modify_path` therefore checks segments of
``step_mm`` (default 1 mm) against eq. 4 scaled by the number of tooth advances in the segment,
``(L/Δs)·(Δs/p)·(s/p) = (L/p)·(s/p)`` — the same reference per unit length — with a relative
tolerance ``tolerance`` for pixel noise (both stated in the results).

Spindle current (eqs 5–6) is only available with **assumed** constants (:data:`ASSUMED_CURRENT_MODEL`):
the paper gives no values of a, b, p1, p2 or H.

>>> round(reference_pixel_count(feed_per_tooth(500, 2000, 2), 3.0, 0.3), 4)   # eq. 4
4.1667
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
from shapely.geometry import Point, Polygon

from shapely.geometry import LinearRing

from ..simulation import pixel
from ..simulation.vector import point_segment_distances
from .job import Job
from .offsets import allowed_region, link_loops, offset_levels
from .path import ToolPath, ToolPathBuilder, helix_ring, subdivide

__all__ = ["DEFAULT_TEETH", "ASSUMED_CURRENT_MODEL", "feed_per_tooth", "reference_pixel_count",
           "linear_motion", "cut_linear", "modify_path", "ModifiedPath", "spiral_entry", "fit_arcs",
           "spindle_current", "resample_polyline", "kim_yang_passes", "passes_path"]

#: Tooth count used for eq. 4 — NOT given by Kim & Yang (2006); documented choice (2-flute Ø10 mm).
DEFAULT_TEETH = 2

#: Eq. 6 ``I_M = p1 + H·p2·Z_M`` with ASSUMED constants (not in the paper): idle current p1 [A],
#: hardness factor H [-] and slope p2 [A per mm³/min]; chosen only to draw an ampere axis.
ASSUMED_CURRENT_MODEL = {"p1_A": 2.0, "H": 1.0, "p2_A_per_mm3_min": 2.0e-3}


def feed_per_tooth(feed_mm_min: float, spindle_rpm: float, teeth: int = DEFAULT_TEETH) -> float:
    """Feed per tooth Δs = v_f / (n·z) [mm]."""
    if not (feed_mm_min > 0 and spindle_rpm > 0):
        raise ValueError(f"feed_mm_min and spindle_rpm must be > 0, got {feed_mm_min}, {spindle_rpm}")
    if int(teeth) != teeth or teeth < 1:
        raise ValueError(f"teeth must be an integer >= 1, got {teeth!r}")
    return feed_mm_min / (spindle_rpm * teeth)


def reference_pixel_count(feed_per_tooth_mm: float, step_length_mm: float, pixel_mm: float) -> float:
    """Eq. 4: ``(Δs/pixel)·(s/pixel)`` pixels removed per tooth advance at the nominal MRR."""
    for name, v in (("feed_per_tooth_mm", feed_per_tooth_mm), ("step_length_mm", step_length_mm),
                    ("pixel_mm", pixel_mm)):
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be > 0 mm, got {v!r}")
    return (feed_per_tooth_mm / pixel_mm) * (step_length_mm / pixel_mm)


def linear_motion(stock, p0, p1, tool_radius: float) -> int:
    """``Linear_Motion``: material pixels (centre within ``tool_radius`` of segment p0–p1) [count].

    ``stock`` is a :class:`cnclab.simulation.pixel.Stock` (read only here;
    :meth:`~cnclab.simulation.pixel.Stock.segment_pixels`).
    """
    return stock.segment_pixels(p0, p1, tool_radius)


def cut_linear(stock, p0, p1, tool_radius: float) -> int:
    """Remove the pixels swept by the tool along p0–p1; returns how many were material."""
    return stock.segment_pixels(p0, p1, tool_radius, cut=True)


def resample_polyline(points, step_mm: float) -> np.ndarray:
    """Split every segment of ``points`` [(n,2) mm] into equal parts of at most ``step_mm``
    (:func:`cnclab.toolpath.path.subdivide`)."""
    return subdivide(points, step_mm)


@dataclasses.dataclass
class ModifiedPath:
    """Result of :func:`modify_path`: passes (list of (n,2) mm), per-pass boolean ``inserted`` flags
    (True for points reached by an inserted or return segment), and counters."""

    passes: list
    inserted: list
    n_excessive: int
    n_insertions: int
    n_unresolved: int
    reference_per_mm: float


def modify_path(passes, stock, tool_radius: float, reference_per_mm: float, allowed: Polygon,
                step_mm: float = 1.0, shift_mm: float | None = None, tolerance: float = 0.15,
                max_insertions: int = 12, side: str = "left") -> ModifiedPath:
    """Kim & Yang §3.2 path modification on a pixel ``stock`` (cut in place as the tool moves).

    ``reference_per_mm``: reference pixel count per mm of path (eq. 4 / Δs); a segment of length L is
    excessive when its ``Linear_Motion`` count exceeds ``(1 + tolerance)·reference_per_mm·L``.
    ``shift_mm``: end-point shift per iteration to the left (default: one pixel); ``allowed``: where
    the tool centre may go (extensions leaving it stop the insertion). Each pass starts with a
    plunge at its first point (the disk there is cut, not checked). ``side``: the side of the moving
    direction the end point is shifted to (the paper says "to the left"; ``"right"`` is the other
    reading for clockwise passes).
    """
    if side not in ("left", "right"):
        raise ValueError(f"side must be 'left' or 'right', got {side!r}")
    r = float(tool_radius)
    shift = stock.resolution_mm if shift_mm is None else float(shift_mm)
    guard = allowed.buffer(1e-6)
    ref = lambda a, b: (1.0 + tolerance) * reference_per_mm * float(np.hypot(*(b - a)))  # noqa: E731
    out_passes, out_flags = [], []
    n_exc = n_ins = n_unres = 0
    for pas in passes:
        pts = resample_polyline(pas, step_mm)
        out, flags = [pts[0]], [False]
        stock.cut_disk_pixels(tuple(pts[0]), r)
        for a, b in zip(pts[:-1], pts[1:]):
            tries = 0
            while linear_motion(stock, a, b, r) > ref(a, b):
                if tries == 0:
                    n_exc += 1
                if tries >= max_insertions:
                    n_unres += 1
                    break
                tries += 1
                excursion = _additional_path(stock, a, b, r, shift if side == "left" else -shift, guard, ref)
                if not excursion:
                    n_unres += 1
                    break
                n_ins += 1
                prev = a
                for q in excursion + [a]:           # the excursion, then the return path to a
                    cut_linear(stock, prev, q, r)
                    out.append(q)
                    flags.append(True)
                    prev = q
            cut_linear(stock, a, b, r)
            out.append(b)
            flags.append(False)
        out_passes.append(np.array(out))
        out_flags.append(np.array(flags))
    return ModifiedPath(out_passes, out_flags, n_exc, n_ins, n_unres, reference_per_mm)


def _additional_path(stock, start, end, r, shift, guard, ref, max_extend: int = 200):
    """``Additional_Path_Insertion``: cuts and returns the inserted points (the caller adds the return)."""
    pts = []
    s, e = np.asarray(start, float), np.asarray(end, float)
    for _ in range(max_extend):
        d = e - s
        L = float(np.hypot(*d))
        left = np.array([-d[1], d[0]]) / L
        k, ok = 0, False
        while k * abs(shift) <= 2 * r:                # shift the end point to the left (shift < 0: right)
            k += 1
            e_k = e + k * shift * left
            if linear_motion(stock, s, e_k, r) <= ref(s, e_k):
                ok = True
                break
        if not ok or not guard.contains(Point(e_k)):
            break
        pts.append(e_k)                               # insert start -> shifted end
        cut_linear(stock, s, e_k, r)                  # the tool cuts it now
        ext = e_k + (e_k - s)                         # extend with the same length
        if not guard.contains(Point(ext)):
            break
        excessive = linear_motion(stock, e_k, ext, r) > ref(e_k, ext)
        if not excessive:
            break
        s, e = e_k, ext
    return pts


def spiral_entry(region: Polygon, target, pitch_mm: float, step_mm: float = 0.5) -> np.ndarray:
    """Archimedean spiral from the pole of inaccessibility of ``region`` out to its inscribed radius,
    then a straight run to ``target`` [mm]; pitch ``pitch_mm`` per turn. Returns (n, 2) points."""
    from shapely.ops import polylabel

    c = polylabel(region, tolerance=0.05)
    rho = region.exterior.distance(c) if not region.interiors else region.boundary.distance(c)
    cx, cy = c.x, c.y
    tx, ty = target
    phi_end = 2 * math.pi * rho / pitch_mm
    if phi_end <= 0:
        return np.array([[cx, cy], [tx, ty]])
    # end the spiral at the angle pointing to the target, so the run-out is radial
    a_t = math.atan2(ty - cy, tx - cx) % (2 * math.pi)
    phi_end = max(a_t, a_t + 2 * math.pi * math.floor((phi_end - a_t) / (2 * math.pi)))
    phi = [0.0]
    while phi[-1] < phi_end:                          # arc-length step ~ step_mm
        rad = max(pitch_mm * phi[-1] / (2 * math.pi), step_mm)
        phi.append(min(phi[-1] + step_mm / rad, phi_end))
    phi = np.array(phi)
    rad = pitch_mm * phi / (2 * math.pi)
    pts = np.column_stack([cx + rad * np.cos(phi), cy + rad * np.sin(phi)])
    return np.vstack([pts, [[tx, ty]]])


def _circle(p, q, s):
    ax, ay = p
    bx, by = q
    cx, cy = s
    d = 2 * (ax * (by - cy) + bx * (cy - ay) + cx * (ay - by))
    if abs(d) < 1e-12:
        return None
    ux = ((ax * ax + ay * ay) * (by - cy) + (bx * bx + by * by) * (cy - ay) + (cx * cx + cy * cy) * (ay - by)) / d
    uy = ((ax * ax + ay * ay) * (cx - bx) + (bx * bx + by * by) * (ax - cx) + (cx * cx + cy * cy) * (bx - ax)) / d
    return np.array([ux, uy]), math.hypot(ax - ux, ay - uy)


def fit_arcs(points, tol_mm: float = 0.02, short_mm: float = 2.0, min_points: int = 4,
             max_radius_mm: float = 500.0, chords: bool = False):
    """§3.3 circular interpolation: runs of short segments (≤ ``short_mm``) whose points lie within
    ``tol_mm`` of one circle (turning one way, sweep < 360°) become arcs.

    ``chords``: the segments too must lie within ``tol_mm`` of the arc (its radius minus a segment's
    distance from its centre: the sagitta by which an arc through a polygon's vertices bulges past
    its sides). The paper's criterion (points only, the default here, kept for the reproduction) fits
    one arc through the vertices of a polygonal circle: on a 200-gon of radius 42.3 mm its sides'
    5.1 um sagitta put a D5.8 tool that far into the wall (session 21's fuzz campaign); the
    strategies' programs use ``chords=True``.

    Returns a list of ``("line", end)`` and ``("arc", end, centre, ccw)`` items for the polyline
    after its first point.

    >>> a = np.linspace(0, np.pi / 2, 21)        # a quarter of an 80-gon of radius 10: sagitta 7.7 um
    >>> pts = 10 * np.column_stack([np.cos(a), np.sin(a)])
    >>> [it[0] for it in fit_arcs(pts, 5e-4)], len(fit_arcs(pts, 5e-4, chords=True))
    (['arc'], 20)
    >>> [it[0] for it in fit_arcs(pts, 1e-2, chords=True)]
    ['arc']
    """
    p = np.asarray(points, float)
    n = len(p)
    seg = np.hypot(*np.diff(p, axis=0).T)
    items, i = [], 0
    while i < n - 1:
        best = None
        j = i + min_points - 1
        while j < n and np.all(seg[i:j] <= short_mm) and np.all(seg[i:j] > 0):
            c = _circle(p[i], p[(i + j) // 2], p[j])
            if c is None or c[1] > max_radius_mm:
                break
            ctr, rad = c
            if np.max(np.abs(np.hypot(*(p[i:j + 1] - ctr).T) - rad)) > tol_mm:
                break
            if chords and np.max(rad - point_segment_distances(ctr, p[i:j], p[i + 1:j + 1])) > tol_mm:
                break
            v = p[i:j + 1] - ctr
            ang = np.unwrap(np.arctan2(v[:, 1], v[:, 0]))
            da = np.diff(ang)
            if not (np.all(da > 0) or np.all(da < 0)) or abs(ang[-1] - ang[0]) >= 2 * math.pi - 1e-6:
                break
            best = (j, ctr, bool(da[0] > 0))
            j += 1
        if best is None:
            items.append(("line", p[i + 1]))
            i += 1
        else:
            j, ctr, ccw = best
            items.append(("arc", p[j], ctr, ccw))
            i = j
    return items


def spindle_current(mrr_mm3_min, model: dict = ASSUMED_CURRENT_MODEL):
    """Eq. 6, ``I_M = p1 + H·p2·Z_M`` [A] with ``model`` constants (default: ASSUMED values)."""
    return model["p1_A"] + model["H"] * model["p2_A_per_mm3_min"] * np.asarray(mrr_mm3_min, float)


def _pass_segments(p, fit_kw):
    """Arc-fitted moves of one pass: list of (end xy, arc 0/2/3, centre xy)."""
    out = []
    for it in fit_arcs(p, **fit_kw):
        if it[0] == "line":
            out.append((it[1], 0, (np.nan, np.nan)))
        else:
            out.append((it[1], 3 if it[3] else 2, it[2]))
    return out


def kim_yang_passes(job: Job, spiral: bool = True, modified: bool = False, pixel_mm: float = 0.3,
                    teeth: int | None = None, tolerance: float = 0.15, step_mm: float = 1.0) -> list:
    """Kim & Yang (2006) contour-parallel passes on ``job`` (offsets at the radial depth ``job.a_e``,
    linked inside-out; each counter-clockwise pass preceded by a spiral entry from its centre), and
    with ``modified`` the §3.2 constant-MRR modification on a ``pixel_mm`` pixel stock (reference
    pixel count of eq. 4 with ``teeth`` teeth, default the job's). Returns a list of (n, 2) arrays, mm."""
    r, b = job.tool_radius, job.a_e
    allowed = allowed_region(job.polygon, r)
    passes = link_loops(offset_levels(job.polygon, r, b), allowed)
    if spiral:
        out = []
        for q in passes:
            d = np.hypot(q[1:, 0] - q[0, 0], q[1:, 1] - q[0, 1])
            k = np.flatnonzero(d < 1e-9)
            ring = LinearRing(q[:int(k[0]) + 2] if len(k) else q)
            if ring.is_ccw and Polygon(ring).area > 1.0:
                q = np.vstack([spiral_entry(Polygon(ring), q[0], pitch_mm=b)[:-1], q])
            out.append(q)
        passes = out
    if not modified:
        return passes
    z = job.teeth if teeth is None else int(teeth)
    fz = feed_per_tooth(job.feed_mm_min, job.spindle_rpm, z)
    ref = reference_pixel_count(fz, b, pixel_mm) / fz
    stock = pixel.Stock.from_polygon(job.polygon, pixel_mm)
    return list(modify_path(passes, stock, r, ref, allowed, step_mm=step_mm, tolerance=tolerance).passes)


def passes_path(passes, job: Job, arcs: bool = True, entry: str = "plunge", **fit_kw) -> ToolPath:
    """A :class:`ToolPath` of contour-parallel ``passes`` (mm) at the job's cutting level: rapid at
    the clearance plane above each pass start and down to :data:`~cnclab.toolpath.path.APPROACH_MM`
    above the stock top (:meth:`~cnclab.toolpath.path.ToolPathBuilder.approach`), the entry at feed,
    the pass as lines and fitted arcs (:func:`fit_arcs`, ``fit_kw``), a rapid straight up.
    ``entry="plunge"``: straight down onto the pass start (Kim & Yang's program: the pass starts at
    the centre of its region, its spiral entry); ``"helix"``: one helical turn of tool-centre radius
    r/4 about the pass start from the stock top to the cutting level, the circle once more flat, back
    to the start (a machine-safe entry)."""
    if entry not in ("plunge", "helix"):
        raise ValueError(f"entry must be 'plunge' or 'helix', got {entry!r}")
    z, zc = job.top_z - job.a_p, job.clearance_z
    f = job.feed_mm_min
    b = ToolPathBuilder(tool=job.tool, spindle=job.spindle_rpm, info={"name": "Kim & Yang contour-parallel"})
    e = 0.25 * job.tool_radius
    for pas in passes:
        p = np.asarray(pas, float)
        if entry == "helix":
            ring = helix_ring(p[0], e, 32)
            b.approach(ring[0], job.top_z, zc)
            b.plunge(ring[0], job.top_z, f, tag="approach")
            b.helix(ring, job.top_z, z, f, equal_steps=True)
            b.cut(ring[1:], f, z=z)
            b.cut(p[:1], f, z=z)
        else:
            b.approach(p[0], job.top_z, zc)
            b.plunge(p[0], z, f)
        items = _pass_segments(p, fit_kw) if arcs else [(q, 0, (np.nan, np.nan)) for q in p[1:]]
        for end, a, c in items:
            b.add(np.asarray(end, float)[None, :2], "cut", f, z=z, arc=a, center=np.asarray(c, float)[None])
        b.lift(zc)
    return b.build()
