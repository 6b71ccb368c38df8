"""Deep pockets: the levels of a job joined safely (:func:`join_levels`), for every planner.

A planner of :data:`cnclab.toolpath.planners.STRATEGIES` cuts one level: it sees the level's top
(the floor of the level above) as the stock top, so it may descend through the region above that
top as through air — a rapid down to just above it tagged ``cleared``, a plunge onto it before its
helix, a rapid over it. In the pocket these moves run through the levels above, which is safe only
where those levels cleared the tool disc. :func:`join_levels` proves it with the exact swept area
of the levels above and tags the moves accordingly, or re-enters by helix from the stock top where
the proof fails.

Model (units mm): the region a level cleared is the union of the tool discs (radius r) along its
moves whose tip lies below the level's top (:func:`swept_region`, shapely buffers of the move
polylines, arcs sampled by chords of at most ``r/8``: the inscribed buffer polygon underestimates
the swept area, so the proof is conservative). Material left in the slabs above level k is
``material - cleared_j`` for each j < k (``material`` = the pocket minus the pre-drilled hole).
A move of level k whose tip is below the stock top and at or above the level's top is *proven* when
its swept area meets at most ``tol_mm2`` of that material; it is then marked ``cleared`` (the
:attr:`ToolPath.cleared` flag the writer and the evaluator read; its tag gains ``cleared: levels
above`` for people). A move straight up needs no proof (the
tool leaves along the column its body swept on the way down). A descent to the level top that
cannot be proven is replaced by a plunge to the stock top (air) and a helix about the centre of the
level's own following helix, at its pitch, down to the level top (an entry into material the level
may cut). Any other unproven move is an error naming the level and the point.

``info["levels_extra_mm2"]``: per level, the area where the level's tool body, below the stock top,
meets material left in the levels above (it would cut more than ``a_p`` there; 0 when every level
follows the same plan in x, y).

>>> from shapely.geometry import box
>>> from cnclab.toolpath.path import ToolPath
>>> a = ToolPath.build([[5, 5, 5], [5, 5, -1], [15, 5, -1], [15, 5, 5]], kind=["rapid", "helix", "cut", "retract"], feed=100)
>>> round(swept_region(a, 0.0, 2.0).area, 1)        # a 10 mm stroke of a 4 mm disc: 40 + pi 2^2
52.6
"""
from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.geometry import LineString, Point

from .helix import HELIX_CHORD_MM, helix_ring, helix_segments
from .path import KINDS, ToolPath, ToolPathBuilder

__all__ = ["swept_region", "join_levels", "with_entry_feed", "ENTRY_MOVE_KINDS", "LevelError", "PROOF_TOL_MM2",
           "CLEARED_ABOVE", "sliver_mm"]

#: material area (mm^2) a proven move may meet: a sliver 0.01 mm wide over 0.1 mm (the buffer
#: polygons' chord error at r = 4 mm with 32 segments a quarter is 0.005 mm)
PROOF_TOL_MM2 = 1e-3
#: tag text added (for people) to a move proven to run inside the levels above
CLEARED_ABOVE = "cleared: levels above"
_K = {k: i for i, k in enumerate(KINDS)}
_CHUNK = 200
_EPS = 1e-9
#: segments a quarter circle of the tool-disc buffers (:func:`swept_region`)
_QUAD_SEGS = 32


def sliver_mm(r: float) -> float:
    """Half the thickness (mm) of the thinnest rest :func:`join_levels` counts when it proves a move
    through the levels above: the chord error of the tool-disc buffers (radius ``r`` mm, 32 segments
    a quarter: r (1 - cos(pi / 128)), 1.2 um at r = 4). Both the move's disc and the levels' swept
    region are such polygons, so a rest up to twice that thick may be their chords alone: along a
    round wall a D8 level left 32 such scallops 1.19 um thick (0.0019 mm^2 in all) that a descent
    touched, and the zig-zag refused 7 of 30 deep fuzz pockets as a move through material.

    >>> round(sliver_mm(4.0) * 1000, 3)
    1.205
    """
    return r * (1.0 - math.cos(math.pi / (4 * _QUAD_SEGS)))


#: the move kinds that run at the job's entry feed (:func:`with_entry_feed`); a plunge keeps its feed
#: (into a start hole or cleared area, or through air down to the stock top before a helix)
ENTRY_MOVE_KINDS = ("helix", "ramp")


def with_entry_feed(path: ToolPath, job) -> ToolPath:
    """``path`` with its helix and ramp moves (:data:`ENTRY_MOVE_KINDS`) at the job's entry feed
    :attr:`Job.entry_feed <cnclab.toolpath.job.Job.entry_feed>` (mm/min: the job key
    ``entry_feed_mm_min``, else :data:`~cnclab.toolpath.job.ENTRY_FEED_FRACTION` x ``feed_mm_min``)
    and ``info["entry_feed_mm_min"]`` set to it; every other move as given. The one place a planned
    path gets its entry feed: :func:`cnclab.toolpath.planners.plan` applies it to every strategy's
    joined levels, so the evaluator times the feeds the program writer writes (it writes a path's
    feeds as they are). A new path; ``path`` is not changed.

    >>> from types import SimpleNamespace
    >>> p = ToolPath.build([[0, 0, 1], [0, 0, 0], [5, 0, 0]], kind=["rapid", "helix", "cut"], feed=200)
    >>> with_entry_feed(p, SimpleNamespace(entry_feed=100.0)).feed.tolist()     # a rapid has no feed
    [nan, 100.0, 200.0]
    """
    ef = float(job.entry_feed)
    entry = path.is_kind(*ENTRY_MOVE_KINDS)
    out = ToolPath(path.xyz.copy(), path.kind.copy(), path.tag.copy(), np.where(entry, ef, path.feed),
                   path.spindle.copy(), path.arc.copy(), path.arc_center.copy(), path.tool, dict(path.info),
                   path.cleared.copy())
    out.info["entry_feed_mm_min"] = ef
    return out


class LevelError(ValueError):
    """A level cannot be joined safely to the levels above (the message names level and point)."""


def swept_region(path: ToolPath, below_z: float, r: float, moves=None):
    """Union of the tool discs (radius ``r`` mm) along the moves of ``path`` whose tip lies below
    ``below_z`` (mm) at both ends (``moves``: restrict to these move indices); a shapely geometry."""
    pts, src = path.polyline(max(r / 8.0, 1e-3))
    low = pts[:, 2] < below_z - _EPS
    keep = low & (np.ones(len(pts), bool) if moves is None else np.isin(src, moves))
    geoms = []
    idx = np.flatnonzero(keep)
    if idx.size:
        brk = np.flatnonzero(np.diff(idx) > 1) + 1
        for run in np.split(idx, brk):
            for xy in _first_passes(pts[run, :2]):
                # pieces of at most _CHUNK points buffered apart, then united (GEOS buffers a long
                # self-overlapping polyline several times slower than its pieces)
                for k in range(0, max(len(xy) - 1, 1), _CHUNK):
                    q = xy[k:k + _CHUNK + 1]
                    g = Point(q[0]) if len(q) == 1 or np.ptp(q, axis=0).max() == 0 else LineString(q)
                    geoms.append(g.buffer(r, quad_segs=_QUAD_SEGS))
    return shapely.union_all(geoms) if geoms else shapely.Polygon()


def _first_passes(xy: np.ndarray) -> list:
    """The polyline ``xy`` (n, 2) mm without the segments it runs again (the same two end points, either
    way; exact): the runs of first passes, as polylines. They sweep what ``xy`` sweeps; GEOS buffers a
    line over coincident segments slowly (Kim & Yang's §3.2 modification goes back and forth over one
    segment to take extra material: 27 k moves of a level took 100 s to buffer, 7 s without them).

    >>> _first_passes(np.array([[0, 0], [1, 0], [0, 0], [1, 0], [1, 1.0]]))
    [array([[0., 0.],
           [1., 0.]]), array([[1., 0.],
           [1., 1.]])]
    """
    if len(xy) < 3:
        return [xy]
    a, b = xy[:-1], xy[1:]
    swap = (a[:, 0] > b[:, 0]) | ((a[:, 0] == b[:, 0]) & (a[:, 1] > b[:, 1]))
    key = np.column_stack([np.where(swap[:, None], b, a), np.where(swap[:, None], a, b)])
    first = np.zeros(len(a), bool)
    first[np.unique(key, axis=0, return_index=True)[1]] = True
    if first.all():
        return [xy]
    seg = np.flatnonzero(first)
    cut = np.flatnonzero(np.diff(seg) > 1) + 1
    return [xy[s[0]:s[-1] + 2] for s in np.split(seg, cut)]


def _move_sweep(path, k, r):
    a, b = path.xyz[k - 1], path.xyz[k]
    if path.arc[k]:
        return swept_region(path.take(slice(k - 1, k + 1)), math.inf, r)
    if math.hypot(b[0] - a[0], b[1] - a[1]) <= _EPS:
        return Point(b[:2]).buffer(r, quad_segs=_QUAD_SEGS)
    return LineString([a[:2], b[:2]]).buffer(r, quad_segs=_QUAD_SEGS)


def _following_helix(path, k):
    """``(centre xy, ccw, sweep rad, drop mm, feed)`` of the helix that follows move ``k`` of ``path``:
    one G2/G3 move, or a run of ``helix`` line moves on a ring (:meth:`ToolPathBuilder.helix`, its
    centre the circumcentre of its first three points); None if no helix follows."""
    nxt = k + 1
    if nxt >= len(path) or (path.arc[nxt] == 0 and path.kind[nxt] != _K["helix"]):
        return None
    p0 = path.xyz[k]
    if path.arc[nxt] != 0:
        c, p1 = path.arc_center[nxt], path.xyz[nxt]
        a0, a1 = math.atan2(p0[1] - c[1], p0[0] - c[0]), math.atan2(p1[1] - c[1], p1[0] - c[0])
        ccw = path.arc[nxt] == 3
        sweep = (a1 - a0) % (2 * math.pi) if ccw else (a0 - a1) % (2 * math.pi)
        return c, ccw, (sweep if sweep > 1e-9 else 2 * math.pi), p0[2] - p1[2], float(path.feed[nxt])
    e = nxt
    while e + 1 < len(path) and path.kind[e + 1] == _K["helix"] and path.arc[e + 1] == 0:
        e += 1
    if e < nxt + 1:
        return None
    (ax, ay), (bx, by), (cx, cy) = path.xyz[k:k + 3, :2]
    d = 2.0 * (ax * (by - cy) + bx * (cy - ay) + cx * (ay - by))
    if abs(d) <= 1e-12:
        return None
    ux = ((ax * ax + ay * ay) * (by - cy) + (bx * bx + by * by) * (cy - ay) + (cx * cx + cy * cy) * (ay - by)) / d
    uy = ((ax * ax + ay * ay) * (cx - bx) + (bx * bx + by * by) * (ax - cx) + (cx * cx + cy * cy) * (bx - ax)) / d
    ang = np.unwrap(np.arctan2(path.xyz[k:e + 1, 1] - uy, path.xyz[k:e + 1, 0] - ux))
    return np.array([ux, uy]), bool(ang[-1] > ang[0]), float(abs(ang[-1] - ang[0])), p0[2] - path.xyz[e, 2], \
        float(path.feed[nxt])


def _helix_from_top(path, k, top_z, r):
    """The moves (a :class:`ToolPath`, spindle as move ``k``'s) replacing the unproven vertical descent
    ``k`` of ``path`` (ending on the level top above a helix): a plunge to ``top_z`` (air) and a helix
    about the following helix's centre (:func:`_following_helix`), in its sense and at no more than
    its pitch, down to the descent's end, by the package's one helix generator
    (:meth:`ToolPathBuilder.helix` on a :func:`helix_ring` of chord error <= ``HELIX_CHORD_MM``)."""
    hx = _following_helix(path, k)
    if hx is None:
        return None
    c, ccw, sweep, drop, feed = hx
    end = path.xyz[k]
    rad = math.hypot(end[0] - c[0], end[1] - c[1])
    if rad <= 1e-6 or not drop > 1e-9 or not sweep > 1e-9:
        return None
    a0 = math.atan2(end[1] - c[1], end[0] - c[0])
    turns = max(1, math.ceil((top_z - end[2]) / (drop * 2 * math.pi / sweep) - 1e-9))
    n = helix_segments(rad, HELIX_CHORD_MM)
    ring = helix_ring((0.0, 0.0), rad, n)                       # counter-clockwise from angle 0
    if not ccw:
        ring[:, 1] = -ring[:, 1]
    rot = np.array([[math.cos(a0), -math.sin(a0)], [math.sin(a0), math.cos(a0)]])
    ring = ring @ rot.T + c
    ring[0] = ring[-1] = end[:2]                                # exactly where the tool is
    b = ToolPathBuilder(tool=path.tool, spindle=path.spindle[k])
    b.plunge(end[:2], top_z, feed, tag="entry: down to the stock top (air)")
    b.helix(np.vstack([ring] + [ring[1:]] * (turns - 1)), top_z, float(end[2]), feed,
            tag="entry: helix through the levels above", equal_steps=True)
    return b.build()


def _rebuild(path, replace):
    """``path`` with moves ``k`` replaced by the paths ``replace[k]`` (None: dropped; see
    :func:`_helix_from_top`)."""
    pieces, last = [], 0
    for k in sorted(replace):
        pieces += [path.take(slice(last, k))] + ([replace[k]] if replace[k] is not None else [])
        last = k + 1
    pieces.append(path.take(slice(last, None)))
    return ToolPath.concat([q for q in pieces if len(q)], tool=path.tool, info=dict(path.info))


def _with_tag(tag, extra):
    t = str(tag or "")
    return extra if not t else (t if extra in t else f"{t}; {extra}")


def join_levels(paths, tops, job, tol_mm2: float = PROOF_TOL_MM2) -> ToolPath:
    """Join the one-level ``paths`` (level k cuts from ``tops[k]`` down; ``tops[0]`` is the stock top
    ``job.top_z``) into one safe path (see the module docstring). Raises :class:`LevelError` when a
    move through the levels above is neither proven cleared nor re-entered by a helix."""
    r = job.tool_radius
    material = job.polygon.difference(job.start_hole_polygon())
    top0 = job.top_z
    left_above = shapely.Polygon()      # material left in the slabs above the current level
    out, extra = [], []
    for k, (p, top) in enumerate(zip(paths, tops)):
        if k > 0:
            p = _prove_level(p, k, top, top0, left_above, r, tol_mm2)
            body = swept_region(p, top0, r)
            extra.append(float(body.intersection(left_above).area))
        else:
            extra.append(0.0)
        if k < len(paths) - 1:          # what the levels below need (the last level's is never read)
            left_above = left_above.union(material.difference(swept_region(p, top, r)))
        out.append(p)
    joined = out[0] if len(out) == 1 else ToolPath.concat(out)
    joined.info["levels_extra_mm2"] = extra
    return joined


def _prove_level(p, k, top, top0, left_above, r, tol_mm2):
    """Tag (or re-enter) the moves of level ``k`` (path ``p``, top ``top``) that run through the levels
    above (tip below ``top0``, at or above ``top``)."""
    z = p.xyz[:, 2]
    zprev = np.r_[np.inf, z[:-1]]
    lo = np.minimum(z, zprev)
    through = np.flatnonzero((lo < top0 - _EPS) & (np.maximum(z, zprev) > top + _EPS))
    through = through[through > 0]
    # straight up: the tool leaves along its own column, which its body swept on the way down
    up = (z[through] > zprev[through]) & (np.hypot(*(p.xyz[through, :2] - p.xyz[through - 1, :2]).T) <= _EPS)
    through = through[~up]
    tags = p.tag.copy()
    cleared = p.cleared.copy()
    replace = {}
    for i in through:
        if i in replace:
            continue
        sweep = _move_sweep(p, i, r)
        met = shapely.Polygon() if left_above.is_empty else sweep.intersection(left_above)
        # a rest no thicker than the polygons' chords (:func:`sliver_mm`) is not material
        ok = met.area <= tol_mm2 or met.buffer(-sliver_mm(r), quad_segs=_QUAD_SEGS).is_empty
        if ok:
            tags[i] = _with_tag(tags[i], CLEARED_ABOVE)
            cleared[i] = True
            continue
        vertical = math.hypot(*(p.xyz[i, :2] - p.xyz[i - 1, :2])) <= _EPS and z[i] < zprev[i]
        # the descent ending on the level top (a rapid tagged cleared by the level's planner, or its
        # plunge onto the top): re-entered by a helix from the stock top when a helix follows
        j = i
        while vertical and j + 1 < len(p) and p.arc[j + 1] == 0 and abs(z[j] - top) > 1e-6 \
                and math.hypot(*(p.xyz[j + 1, :2] - p.xyz[j, :2])) <= _EPS and z[j + 1] < z[j]:
            j += 1
        new = _helix_from_top(p, j, top0, r) if vertical and abs(z[j] - top) <= 1e-6 else None
        if new is None:
            x, y = p.xyz[i, :2]
            raise LevelError(f"level {k + 1} (top z {top:g} mm): move {i} at x {x:.3f} y {y:.3f} mm runs "
                             f"through material the levels above left ({met.area:.3g} "
                             "mm^2) and is no descent onto a helix that could enter from the stock top")
        for m in range(i, j):
            replace[m] = None                     # the vertical pieces before the descent's end
        replace[j] = new
    p = ToolPath(p.xyz, p.kind, tags, p.feed, p.spindle, p.arc, p.arc_center, p.tool, dict(p.info), cleared)
    return _rebuild(p, replace) if replace else p
