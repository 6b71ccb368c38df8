"""The tool-path model shared by every planner: :class:`ToolPath`, :class:`Tool` and :class:`Move`.

A :class:`ToolPath` is a sequence of moves of the tool reference point (the tool tip on its axis;
for a flat end mill the centre of its end face), stored as arrays. Move ``k`` goes from point
``k-1`` to point ``k``; move 0 is the first positioning to ``xyz[0]`` (a rapid from the safe height
unless its kind says otherwise). Every planner returns a ToolPath; the G-code/APT writers and the
evaluator take one. One move vocabulary (:data:`KINDS`):

=========  ==================================================================================
rapid      G0 positioning (only at/above the clearance plane or inside proven-cleared area)
helix      helical entry (an arc move with decreasing z)
ramp       linear ramp entry (xy and decreasing z)
plunge     straight-down feed move (no xy); allowed only into air or cleared area
cut        cutting move at depth
link       feed move at depth through cleared area (no material expected)
retract    feed or rapid move with increasing z (to the clearance plane)
=========  ==================================================================================

Free ``tag`` strings (``"roll-in"``, ``"roll-out"``, ``"cleanup"``, ``"finish"``...) qualify a move.
Arcs: ``arc`` is 0 (line), 2 (G2, clockwise) or 3 (G3, counter-clockwise) with an absolute xy
``arc_center``; z varies linearly along an arc (helix).

:class:`Move` is one motion block of a program (G0/G1/G2/G3, absolute end point, arc centre offsets
from the start point, feed, spindle). Units everywhere: mm, mm/min, rpm.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from .helix import HELIX_CHORD_MM, helix_ring, helix_segments  # noqa: F401  (the path API re-exports them)
from ..geometry.polyline import resample_polyline, subdivide  # noqa: F401  (the path API re-exports them)

__all__ = ["MOTIONS", "Move", "KINDS", "ENTRY_KINDS", "Tool", "ToolPath", "ToolPathBuilder", "arc_geometry",
           "helix_ring", "helix_segments", "HELIX_CHORD_MM", "sample_arc", "subdivide", "resample_polyline", "classify_moves",
           "APPROACH_MM"]

MOTIONS = ("G0", "G1", "G2", "G3")


@dataclasses.dataclass(frozen=True)
class Move:
    """One motion block: absolute end point [mm], arc centre offsets [mm], feed [mm/min], spindle [rpm].

    ``motion`` is ``"G0"``, ``"G1"``, ``"G2"`` (CW) or ``"G3"`` (CCW). ``i, j`` are the arc-centre
    offsets from the *start* point (arcs only). ``feed`` is required for G1/G2/G3.
    """

    motion: str
    x: float
    y: float
    z: float
    i: float | None = None
    j: float | None = None
    feed: float | None = None
    spindle: float | None = None

    def __post_init__(self):
        if self.motion not in MOTIONS:
            raise ValueError(f"motion must be one of {MOTIONS}, got {self.motion!r}")
        for name in ("x", "y", "z"):
            v = getattr(self, name)
            if v is None or not math.isfinite(float(v)):
                raise ValueError(f"{name} must be a finite coordinate in mm, got {v!r}")
            object.__setattr__(self, name, float(v))
        if self.motion in ("G2", "G3"):
            if self.i is None or self.j is None:
                raise ValueError(f"{self.motion} needs both arc centre offsets i and j (mm)")
            object.__setattr__(self, "i", float(self.i))
            object.__setattr__(self, "j", float(self.j))
        elif self.i is not None or self.j is not None:
            raise ValueError(f"i/j only belong to arcs (G2/G3), got motion {self.motion}")
        if self.motion != "G0" and (self.feed is None or not (float(self.feed) > 0)):
            raise ValueError(f"{self.motion} needs a feed > 0 in mm/min, got {self.feed!r}")
        if self.feed is not None:
            object.__setattr__(self, "feed", float(self.feed))
        if self.spindle is not None:
            if not float(self.spindle) >= 0:
                raise ValueError(f"spindle must be >= 0 rpm, got {self.spindle!r}")
            object.__setattr__(self, "spindle", float(self.spindle))

    @property
    def xyz(self) -> np.ndarray:
        return np.array([self.x, self.y, self.z])


KINDS = ("rapid", "helix", "ramp", "plunge", "cut", "link", "retract")
#: mm: every planner's path comes down from the clearance plane by a rapid to this height above the
#: level top (air; :meth:`ToolPathBuilder.approach`; the adaptive planner's default
#: ``AdaptiveParams.approach_above_mm``), the rest at feed
APPROACH_MM = 0.5
ENTRY_KINDS = ("helix", "ramp", "plunge")
_KIND_INDEX = {k: i for i, k in enumerate(KINDS)}


def _kind_indices(names) -> np.ndarray:
    """Indices into :data:`KINDS` of the kind names (ValueError naming an unknown one)."""
    try:
        return np.array([_KIND_INDEX[x] for x in names], np.int8)
    except KeyError as exc:
        raise ValueError(f"kind must be one of {KINDS}, got {exc.args[0]!r}") from None


def arc_geometry(start, end, center_xy, ccw: bool):
    """Arc from ``start`` to ``end`` (x, y[, z], mm) about ``center_xy``: returns
    ``(cx, cy, radius, start_angle_rad, sweep_rad)``; sweep > 0 counter-clockwise. Equal start and
    end points give a full circle.

    >>> cx, cy, r, a0, sw = arc_geometry((1, 0), (0, 1), (0, 0), ccw=True)
    >>> round(r, 12), round(sw / math.pi, 12)
    (1.0, 0.5)
    """
    cx, cy = float(center_xy[0]), float(center_xy[1])
    r = math.hypot(start[0] - cx, start[1] - cy)
    a0 = math.atan2(start[1] - cy, start[0] - cx)
    a1 = math.atan2(end[1] - cy, end[0] - cx)
    sweep = (a1 - a0) % (2 * math.pi) if ccw else -((a0 - a1) % (2 * math.pi))
    if abs(sweep) < 1e-12:  # same start and end: full circle
        sweep = 2 * math.pi if ccw else -2 * math.pi
    return cx, cy, r, a0, sweep


def _arcs_geometry(P0, P1, C, ccw):
    """:func:`arc_geometry` of many arcs at once: arrays (n,) ``(radius, start_angle_rad, sweep_rad)``
    of the arcs from ``P0[k]`` to ``P1[k]`` (mm, (n, >=2)) about ``C[k]`` ((n, 2)), counter-clockwise where
    ``ccw[k]``."""
    r, a0 = np.hypot(P0[:, 0] - C[:, 0], P0[:, 1] - C[:, 1]), np.arctan2(P0[:, 1] - C[:, 1], P0[:, 0] - C[:, 0])
    a1 = np.arctan2(P1[:, 1] - C[:, 1], P1[:, 0] - C[:, 0])
    sweep = np.where(ccw, np.mod(a1 - a0, 2 * math.pi), -np.mod(a0 - a1, 2 * math.pi))
    full = np.abs(sweep) < 1e-12                   # same start and end: full circle
    sweep[full] = np.where(ccw[full], 2 * math.pi, -2 * math.pi)
    return r, a0, sweep


def sample_arc(start, end, center_xy, ccw: bool, max_segment: float = 0.5) -> np.ndarray:
    """Points (n, 3) mm along the arc or helix from ``start`` to ``end`` (both included), segments at
    most ``max_segment`` mm long along the arc.

    >>> p = sample_arc((1, 0, 0), (-1, 0, 0), (0, 0), ccw=True, max_segment=0.1)
    >>> bool(np.allclose(np.hypot(p[:, 0], p[:, 1]), 1)), bool(p[:, 1].min() >= -1e-12)
    (True, True)
    """
    if not max_segment > 0:
        raise ValueError(f"max_segment must be > 0 mm, got {max_segment}")
    start = np.asarray(start, float)
    end = np.asarray(end, float)
    cx, cy, r, a0, sweep = arc_geometry(start, end, center_xy, ccw)
    n = max(2, int(math.ceil(abs(sweep) * r / max_segment)) + 1)
    t = np.linspace(0.0, 1.0, n)
    ang = a0 + sweep * t
    pts = np.column_stack([cx + r * np.cos(ang), cy + r * np.sin(ang), start[2] + (end[2] - start[2]) * t])
    pts[-1] = end
    return pts


@dataclasses.dataclass(frozen=True)
class Tool:
    """A milling tool: ``diameter`` (mm), ``corner_radius`` (mm; 0 flat end, diameter/2 ball end),
    ``flutes`` (teeth), ``number`` (the T word of the program).

    >>> Tool(6.0).radius
    3.0
    """

    diameter: float
    corner_radius: float = 0.0
    flutes: int = 2
    number: int = 1

    def __post_init__(self):
        if not (math.isfinite(self.diameter) and self.diameter > 0):
            raise ValueError(f"tool diameter must be a finite number > 0 mm, got {self.diameter!r}")
        if not (0 <= self.corner_radius <= 0.5 * self.diameter):
            raise ValueError(f"tool corner_radius must be in [0, diameter/2] mm, got {self.corner_radius!r}")
        if int(self.flutes) != self.flutes or self.flutes < 1:
            raise ValueError(f"tool flutes must be a positive integer, got {self.flutes!r}")
        if int(self.number) != self.number or self.number < 0:
            raise ValueError(f"tool number must be a non-negative integer, got {self.number!r}")

    @property
    def radius(self) -> float:
        return 0.5 * self.diameter


def _col(v, n, fill, dtype, name):
    if v is None:
        return np.full(n, fill, dtype=dtype)
    a = np.asarray(v, dtype=dtype)
    if a.ndim == 0:
        a = np.full(n, a, dtype=dtype)
    if a.shape != (n,):
        raise ValueError(f"{name} must have one value per point ({n}), got shape {a.shape}")
    return a.copy()


@dataclasses.dataclass(eq=False)
class ToolPath:
    """Moves of the tool reference point (see the module docstring). Arrays, one entry per move:

    ``xyz`` (N, 3) end points (mm); ``kind`` (N,) indices into :data:`KINDS`; ``tag`` (N,) strings;
    ``feed`` (N,) mm/min (NaN for rapids); ``spindle`` (N,) rpm in force (NaN: not set);
    ``arc`` (N,) 0 line / 2 G2 / 3 G3; ``arc_center`` (N, 2) absolute xy centre (NaN for lines);
    ``tool`` a :class:`Tool` (or None); ``info`` free metadata (planner, parameters, timings);
    ``cleared`` (N,) bool: the planner's proof (from its stock simulation, a start hole, a drop-cut
    contact point) that the move runs only through air or cleared area. It is the one safety datum
    the program writer and the checks read (a rapid below the clearance plane or a plunge below the
    stock top is allowed only on a ``cleared`` move); tags are free text for people.

    Build with :meth:`build`:

    >>> p = ToolPath.build([[0, 0, 5], [0, 0, 0], [10, 0, 0]], kind=["rapid", "plunge", "cut"], feed=100)
    >>> p.lengths()["cut_mm"], p.kinds().tolist()
    (10.0, ['rapid', 'plunge', 'cut'])
    """

    xyz: np.ndarray
    kind: np.ndarray
    tag: np.ndarray
    feed: np.ndarray
    spindle: np.ndarray
    arc: np.ndarray
    arc_center: np.ndarray
    tool: Tool | None = None
    info: dict = dataclasses.field(default_factory=dict)
    cleared: np.ndarray | None = None

    def __post_init__(self):
        self.xyz = np.asarray(self.xyz, float).reshape(-1, 3)
        n = len(self.xyz)
        self.cleared = _col(self.cleared, n, False, bool, "cleared")
        self.kind = _col(self.kind, n, _KIND_INDEX["cut"], np.int8, "kind")
        self.tag = _col(self.tag, n, "", object, "tag")
        self.feed = _col(self.feed, n, np.nan, float, "feed")
        self.spindle = _col(self.spindle, n, np.nan, float, "spindle")
        self.arc = _col(self.arc, n, 0, np.int8, "arc")
        ac = np.full((n, 2), np.nan) if self.arc_center is None else np.asarray(self.arc_center, float)
        if ac.shape != (n, 2):
            raise ValueError(f"arc_center must be (N, 2) with N = {n}, got {ac.shape}")
        self.arc_center = ac.copy()
        if not np.all(np.isfinite(self.xyz)):
            raise ValueError("xyz: every coordinate must be finite (mm)")
        if np.any((self.kind < 0) | (self.kind >= len(KINDS))):
            raise ValueError(f"kind: indices must be in [0, {len(KINDS)})")
        if not np.all(np.isin(self.arc, (0, 2, 3))):
            raise ValueError("arc must be 0 (line), 2 (G2) or 3 (G3)")
        bad_arc = (self.arc != 0) & ~np.all(np.isfinite(self.arc_center), axis=1)
        if bad_arc.any():
            raise ValueError(f"arc_center missing for arc move {int(np.flatnonzero(bad_arc)[0])}")
        feedmove = self.kind != _KIND_INDEX["rapid"]
        badf = feedmove & ~(self.feed > 0)
        if badf.any():
            k = int(np.flatnonzero(badf)[0])
            raise ValueError(f"feed must be > 0 mm/min for feed move {k} ({KINDS[self.kind[k]]}), got {self.feed[k]}")
        if np.any(self.arc[~feedmove] != 0):
            raise ValueError("a rapid move cannot be an arc")

    # -- construction ------------------------------------------------------------------------
    @classmethod
    def build(cls, points, kind="cut", tag="", feed=None, spindle=None, arc=None, arc_center=None,
              tool: Tool | None = None, info: dict | None = None, cleared=None) -> "ToolPath":
        """A path from points (N, 3) or (N, 2) (z = 0) and per-point or scalar attributes; ``kind``
        is a name of :data:`KINDS` or a sequence of names. Rapids get NaN feed. ``cleared`` (bool,
        scalar or per point): the planner's proof of air (see the class docstring); None: False
        everywhere (no proof). Tags are free text for people: no decision reads them."""
        P = np.asarray(points, float)
        if P.ndim != 2 or P.shape[1] not in (2, 3):
            raise ValueError(f"points must be (N, 2) or (N, 3) mm, got shape {P.shape}")
        if P.shape[1] == 2:
            P = np.column_stack([P, np.zeros(len(P))])
        n = len(P)
        names = [kind] * n if isinstance(kind, str) else list(kind)
        if len(names) != n:
            raise ValueError(f"kind must have one entry per point ({n}), got {len(names)}")
        k = _kind_indices(names)
        f = _col(feed, n, np.nan, float, "feed")
        f[k == _KIND_INDEX["rapid"]] = np.nan
        return cls(P, k, tag, f, spindle, arc, arc_center, tool, dict(info or {}), cleared)

    def take(self, index) -> "ToolPath":
        """The moves ``index`` (a slice, indices or a boolean mask) with all their columns (same tool,
        a copy of ``info``)."""
        return ToolPath(self.xyz[index], self.kind[index], self.tag[index], self.feed[index], self.spindle[index],
                        self.arc[index], self.arc_center[index], self.tool, dict(self.info), self.cleared[index])

    @classmethod
    def concat(cls, paths, tool: Tool | None = None, info: dict | None = None) -> "ToolPath":
        """Join paths end to end (the first move of each path continues from the previous end)."""
        paths = list(paths)
        if not paths:
            raise ValueError("concat needs at least one path")
        tool = tool if tool is not None else paths[0].tool
        return cls(np.vstack([p.xyz for p in paths]), np.concatenate([p.kind for p in paths]),
                   np.concatenate([p.tag for p in paths]), np.concatenate([p.feed for p in paths]),
                   np.concatenate([p.spindle for p in paths]), np.concatenate([p.arc for p in paths]),
                   np.vstack([p.arc_center for p in paths]), tool,
                   dict(info if info is not None else paths[0].info), np.concatenate([p.cleared for p in paths]))

    @classmethod
    def from_segments(cls, segments, z_cut: float, feed: float, clearance_z: float = 5.0, top_z: float = 0.0,
                      link_feed: float | None = None, spindle: float | None = None, tool: Tool | None = None,
                      info: dict | None = None, reentry: str = "plunge", ramp_deg: float = 3.0,
                      ramp_max_mm: float = 10.0) -> "ToolPath":
        """A machine-ready path at one cutting level from planar segments (tool-centre xy, mm).

        ``segments``: list of ``(points (n, 2), kind, tag)`` in path order; ``kind`` is ``"cut"``,
        ``"link"`` (at depth through cleared area, at ``link_feed``), ``"jump"`` (leave at its first
        point, go to its last: retract to ``clearance_z``, rapid, and down again: a vertical plunge
        with ``reentry="plunge"``, or with ``"ramp"`` a ramp at ``ramp_deg`` from ``top_z`` along the
        next segment, back and forth over at most ``ramp_max_mm`` of it, then back to its start at
        depth) or ``"helix"`` (a
        closed xy circle: a helical entry from ``top_z`` down to ``z_cut`` along it, then the same
        circle flat at ``z_cut`` as a cut tagged ``"entry-floor"``); ``kind`` and ``tag`` may also be
        per-point arrays (cut/link). The path starts with a rapid at ``clearance_z`` above the first
        point and ends with a rapid straight up there. Every descent from the clearance plane is a rapid
        down to :data:`APPROACH_MM` above ``top_z`` (air), then the entry at feed; every lift a rapid
        straight up (as the adaptive planner and FreeCAD lift). Descents not into a helix are vertical
        ``plunge`` moves: the planner asserts their target is air (a start hole or cleared area; the
        evaluator checks).

        >>> p = ToolPath.from_segments([(np.array([[0, 0], [10, 0]]), "cut", "")], z_cut=-2, feed=100)
        >>> p.kinds().tolist(), p.xyz[:, 2].tolist()
        (['rapid', 'rapid', 'plunge', 'cut', 'rapid'], [5.0, 0.5, -2.0, -2.0, 5.0])
        """
        if not clearance_z > top_z >= z_cut:
            raise ValueError(f"need clearance_z > top_z >= z_cut (mm), got {clearance_z}, {top_z}, {z_cut}")
        if reentry not in ("plunge", "ramp"):
            raise ValueError(f"reentry must be 'plunge' or 'ramp', got {reentry!r}")
        lf = float(feed if link_feed is None else link_feed)
        b = ToolPathBuilder(tool=tool, spindle=spindle, info=info)

        def descend(P, k):
            """To P[0] at clearance, a rapid down to APPROACH_MM above the level top (air), then
            down at feed (helix along P, or plunge at P[0])."""
            b.approach(P[0], top_z, clearance_z)
            if k == "helix":
                b.add(P[:1], "plunge", feed, "approach", z=top_z)
                b.helix(P, top_z, z_cut, feed)
                b.add(P[1:], "cut", feed, "entry-floor", z=z_cut)
            else:
                b.add(P[:1], "plunge", feed, z=z_cut)

        segs = [(np.asarray(P, float).reshape(-1, 2), k, t) for P, k, t in segments if len(P)]
        if not segs:
            raise ValueError("segments: no points")
        first = segs[0]
        descend(first[0], first[1] if isinstance(first[1], str) else "cut")
        for i, (P, k, t) in enumerate(segs):
            if isinstance(k, str) and k == "jump":
                b.lift(clearance_z)                        # straight up out of the tool's own cut
                b.rapid(P[-1:], z=clearance_z)
                nxt = segs[i + 1] if i + 1 < len(segs) else None
                if nxt is not None and isinstance(nxt[1], str) and nxt[1] == "helix":
                    continue                           # the helix segment approaches its own start
                if reentry == "ramp" and nxt is not None and (not isinstance(nxt[1], str)
                                                                or nxt[1] in ("cut", "link")):
                    ahead = [P[-1:]]                   # the path ahead at depth, up to ramp_max_mm
                    for Pn, kn, _ in segs[i + 1:]:
                        if isinstance(kn, str) and kn not in ("cut", "link"):
                            break
                        ahead.append(Pn)
                        Q = np.vstack(ahead)
                        if np.hypot(*np.diff(Q, axis=0).T).sum() >= ramp_max_mm:
                            break
                    Q = np.vstack(ahead)
                    b.approach(P[-1], top_z, clearance_z)
                    b.ramp(Q[np.r_[True, np.any(np.diff(Q, axis=0) != 0, axis=1)]], top_z, z_cut, feed,
                           ramp_deg=ramp_deg, max_mm=ramp_max_mm)
                else:
                    descend(P[-1:], "plunge")
                continue
            if isinstance(k, str) and k == "helix":
                if i > 0:
                    descend(P, "helix")            # from depth, approach lifts first
                continue
            kk = np.broadcast_to(np.asarray(k, dtype=object), (len(P),))
            if np.any(~np.isin(kk, ("cut", "link"))):
                raise ValueError(f"segment kinds must be cut/link (or a whole jump/helix segment), got {set(kk)}")
            last = b.position
            skip = 1 if last is not None and np.hypot(*(P[0] - last[:2])) < 1e-9 and abs(last[2] - z_cut) < 1e-9 else 0
            tt = np.broadcast_to(np.asarray(t, dtype=object), (len(P),))
            b.add(P[skip:], kk[skip:], np.where(kk[skip:] == "link", lf, float(feed)), tt[skip:], z=z_cut)
        b.lift(clearance_z)
        return b.build()

    def __len__(self) -> int:
        return len(self.xyz)

    def kinds(self) -> np.ndarray:
        """Kind names per move (array of str)."""
        return np.array(KINDS, dtype=object)[self.kind]

    def is_kind(self, *names: str) -> np.ndarray:
        """Boolean mask of the moves whose kind is one of ``names``."""
        return np.isin(self.kind, [_KIND_INDEX[n] for n in names])

    # -- geometry ----------------------------------------------------------------------------
    def segment_lengths(self) -> np.ndarray:
        """Length (mm) of every move (move 0: 0); arcs and helices exact."""
        L = np.zeros(len(self))
        if len(self) < 2:
            return L
        d = np.diff(self.xyz, axis=0)
        L[1:] = np.linalg.norm(d, axis=1)
        k = np.flatnonzero(self.arc[1:] != 0) + 1
        if len(k):
            r, _, sweep = _arcs_geometry(self.xyz[k - 1], self.xyz[k], self.arc_center[k], self.arc[k] == 3)
            L[k] = np.hypot(np.abs(sweep) * r, self.xyz[k, 2] - self.xyz[k - 1, 2])
        return L

    def lengths(self) -> dict:
        """Length per kind, ``{"<kind>_mm": ..., "feed_mm": all but rapids, "total_mm": ...}``."""
        L = self.segment_lengths()
        out = {f"{k}_mm": float(L[self.kind == i].sum()) for i, k in enumerate(KINDS)}
        out["feed_mm"] = float(L[self.kind != _KIND_INDEX["rapid"]].sum())
        out["total_mm"] = float(L.sum())
        return out

    def time_s(self, rapid_mm_min: float) -> dict:
        """Motion time (s) of the path as a program describes it: every feed move at its feed, every
        rapid at ``rapid_mm_min`` (no acceleration, as RS274 canonical totals), per kind and total."""
        if not (math.isfinite(rapid_mm_min) and rapid_mm_min > 0):
            raise ValueError(f"rapid_mm_min must be a finite number > 0 mm/min, got {rapid_mm_min!r}")
        L = self.segment_lengths()
        rate = np.where(self.kind == _KIND_INDEX["rapid"], rapid_mm_min, self.feed)
        t = np.where(L > 0, 60.0 * L / rate, 0.0)
        out = {f"{k}_s": float(t[self.kind == i].sum()) for i, k in enumerate(KINDS)}
        out["total_s"] = float(t.sum())
        return out

    def polyline(self, max_segment: float = 0.5, max_sagitta: float | None = None):
        """Sampled points: ``(points (M, 3) mm, move (M,) index of the move each point belongs to)``;
        arcs are sampled with chords of at most ``max_segment`` mm (arc length) and, with
        ``max_sagitta``, of at most that sagitta (mm: how far a chord's middle lies inside its arc);
        lines are kept as they are (use :meth:`resample` to subdivide lines).

        >>> p = ToolPath.build([[5, 0, 0], [-5, 0, 0]], feed=100, arc=[0, 3], arc_center=[[0, 0], [0, 0]])
        >>> len(p.polyline(2.0)[0]), len(p.polyline(2.0, max_sagitta=1e-4)[0])   # r 5: chords 1.96 / 0.063 mm
        (9, 250)
        """
        if not max_segment > 0:
            raise ValueError(f"max_segment must be > 0 mm, got {max_segment}")
        if max_sagitta is not None and not max_sagitta > 0:
            raise ValueError(f"max_sagitta must be > 0 mm, got {max_sagitta}")
        arcs = np.flatnonzero(self.arc[1:] != 0) + 1
        if len(arcs) == 0:
            return self.xyz.copy(), np.arange(len(self))
        # every arc as sample_arc samples it (n points from its start, the start dropped), all at once
        P0, P1 = self.xyz[arcs - 1], self.xyz[arcs]
        r, a0, sweep = _arcs_geometry(P0, P1, self.arc_center[arcs], self.arc[arcs] == 3)
        n = np.maximum(2, np.ceil(np.abs(sweep) * r / max_segment).astype(int) + 1)   # points per arc
        if max_sagitta is not None:
            # a chord of angle a on radius r lies r (1 - cos(a / 2)) inside its arc at its middle
            step = 2.0 * np.arccos(np.clip(1.0 - max_sagitta / np.maximum(r, 1e-12), -1.0, 1.0))
            n = np.maximum(n, np.ceil(np.abs(sweep) / np.maximum(step, 1e-9)).astype(int) + 1)
        count = np.ones(len(self), int)                  # output points per move: 1 per line, n - 1 per arc
        count[arcs] = n - 1
        idx = np.repeat(np.arange(len(self)), count)
        first = np.cumsum(count) - count                  # where each move's points start
        out = self.xyz[idx].copy()
        which = np.repeat(np.arange(len(arcs)), n - 1)   # the arc of every arc sample
        j = np.arange(len(which)) - np.repeat(np.cumsum(n - 1) - (n - 1), n - 1) + 1   # 1 .. n - 1 along its arc
        t = j / (n[which] - 1.0)
        ang = a0[which] + sweep[which] * t
        C = self.arc_center[arcs][which]
        out[np.isin(idx, arcs)] = np.column_stack([C[:, 0] + r[which] * np.cos(ang), C[:, 1] + r[which] * np.sin(ang),
                                                   P0[which, 2] + (P1[which, 2] - P0[which, 2]) * t])
        out[first[arcs] + n - 2] = P1                     # the arc's end point exactly
        return out, idx

    def resample(self, max_step: float, return_index: bool = False):
        """The same path with every move split into pieces at most ``max_step`` mm long (arcs become
        line pieces on the arc); kind, tag, feed and spindle are inherited by the pieces. With
        ``return_index`` also the index of the original move of every piece: ``(path, index)``.

        >>> p = ToolPath.build([[0, 0, 0], [1, 0, 0]], feed=100).resample(0.25)
        >>> len(p), float(p.segment_lengths().max())
        (5, 0.25)
        """
        if not (math.isfinite(max_step) and max_step > 0):
            raise ValueError(f"max_step must be a finite number > 0 mm, got {max_step!r}")
        P, src = self.polyline(max_step)
        Q, seg = resample_polyline(P, max_step, return_index=True)
        I = src[seg]
        out = ToolPath(Q, self.kind[I], self.tag[I], self.feed[I], self.spindle[I], None, None,
                       self.tool, dict(self.info), self.cleared[I])
        return (out, I) if return_index else out

    # -- program moves -----------------------------------------------------------------------
    def to_moves(self) -> list[Move]:
        """The path as program blocks: rapids as G0, feed moves as G1 (G2/G3 for arcs, with I/J from
        the start point), with feed and spindle."""
        out = []
        for k in range(len(self)):
            x, y, z = self.xyz[k]
            sp = None if not np.isfinite(self.spindle[k]) else float(self.spindle[k])
            if self.kind[k] == _KIND_INDEX["rapid"]:
                out.append(Move("G0", x, y, z, spindle=sp))
            elif self.arc[k] and k > 0:
                cx, cy = self.arc_center[k]
                out.append(Move(f"G{int(self.arc[k])}", x, y, z, i=cx - self.xyz[k - 1, 0],
                                j=cy - self.xyz[k - 1, 1], feed=float(self.feed[k]), spindle=sp))
            else:
                out.append(Move("G1", x, y, z, feed=float(self.feed[k]), spindle=sp))
        return out

    @classmethod
    def from_moves(cls, moves, start=None, tool: Tool | None = None, info: dict | None = None,
                   z_tol: float = 1e-6) -> "ToolPath":
        """A path from program blocks, kinds classified from the geometry: G0 rapid; feed moves with
        rising z retract; falling z: helix (arc), plunge (no xy motion) or ramp; level: cut (the
        evaluator tells cuts from links by the material). ``start`` (x, y, z) is where the tool is
        before the first move (it then becomes point 0, a rapid)."""
        moves = list(moves)
        pts, rapid, feed, spin, arc, ctr = [], [], [], [], [], []
        cur = None
        if start is not None:
            cur = np.asarray(start, float)
            pts.append(cur); rapid.append(True); feed.append(np.nan); spin.append(np.nan)
            arc.append(0); ctr.append((np.nan, np.nan))
        for mv in moves:
            end = mv.xyz
            pts.append(end); rapid.append(mv.motion == "G0")
            spin.append(np.nan if mv.spindle is None else mv.spindle)
            feed.append(np.nan if mv.motion == "G0" else mv.feed)
            if mv.motion in ("G2", "G3") and cur is not None:
                arc.append(int(mv.motion[1])); ctr.append((cur[0] + mv.i, cur[1] + mv.j))
            else:
                arc.append(0); ctr.append((np.nan, np.nan))
            cur = end
        if not pts:
            return cls(np.zeros((0, 3)), None, None, None, None, None, None, tool, dict(info or {}))
        P, arc = np.array(pts), np.array(arc)
        return cls.build(P, kind=classify_moves(P, rapid, arc, z_tol), feed=np.array(feed, float),
                         spindle=np.array(spin, float), arc=arc, arc_center=np.array(ctr, float), tool=tool,
                         info=info, cleared=False)


def classify_moves(xyz, rapid, arc, z_tol: float = 1e-6) -> np.ndarray:
    """Kind names of the moves to the points ``xyz`` (N, 3) mm of a program, from the geometry: a
    rapid stays ``rapid``; a feed move with rising z is a ``retract``, with falling z a ``helix``
    (``arc`` != 0), ``plunge`` (no xy motion, within ``z_tol`` mm) or ``ramp``; a level move a ``cut``
    (the evaluator tells cuts from links by the material). Move 0 (no start known): rapid or cut.

    >>> classify_moves([[0, 0, 5], [0, 0, 0], [1, 0, -1], [2, 0, -1], [2, 0, 5]], [1, 0, 0, 0, 0], 0).tolist()
    ['rapid', 'plunge', 'ramp', 'cut', 'retract']
    """
    P = np.asarray(xyz, float).reshape(-1, 3)
    n = len(P)
    rapid = np.broadcast_to(np.asarray(rapid, bool), (n,))
    arc = np.broadcast_to(np.asarray(arc), (n,))
    dz = np.r_[0.0, np.diff(P[:, 2])]
    flat = np.r_[False, np.hypot(*np.diff(P[:, :2], axis=0).T) <= z_tol]
    down = np.where(arc != 0, "helix", np.where(flat, "plunge", "ramp"))
    k = np.where(dz > z_tol, "retract", np.where(dz < -z_tol, down, "cut")).astype(object)
    k[0] = "cut"
    k[rapid] = "rapid"
    return k

class ToolPathBuilder:
    """Moves appended one block at a time, then :meth:`build` one :class:`ToolPath`: the one way a
    planner assembles a path (no parallel lists of x, y, z, kind, feed, tag).

    Every method appends moves *to* points (mm; (m, 2) points take ``z``), with a kind of
    :data:`KINDS`, a feed [mm/min] (NaN for rapids), a free ``tag`` and the ``cleared`` flag (the
    planner's proof that the move runs through air or cleared area). :meth:`mark` /
    :meth:`rollback` undo a tentative stretch (an entry attempt that failed).

    >>> b = ToolPathBuilder(spindle=6000)
    >>> b.rapid([[0, 0]], z=5); b.plunge([0, 0], -1, 300, cleared=True); b.cut([[10, 0]], 300, z=-1)
    >>> m = b.mark(); b.cut([[10, 10]], 300, z=-1); b.rollback(m); b.retract(5, 300)
    >>> p = b.build(); p.kinds().tolist(), p.cleared.tolist()
    (['rapid', 'plunge', 'cut', 'retract'], [False, True, False, False])
    """

    def __init__(self, *, tool: Tool | None = None, spindle=None, info: dict | None = None):
        self.tool, self.spindle, self.info = tool, spindle, dict(info or {})
        self._chunks = []            # (xyz (m, 3), kind (m,), feed, tag, arc, center (m, 2), cleared)
        self._n = 0

    def __len__(self) -> int:
        return self._n

    @property
    def position(self) -> np.ndarray | None:
        """The end point (3,) mm of the last move (None before the first)."""
        return self._chunks[-1][0][-1] if self._chunks else None

    def add(self, points, kind, feed=np.nan, tag="", *, z=None, cleared=False, arc=0, center=None) -> None:
        """Moves to ``points`` ((m, 3), or (m, 2) at height ``z`` mm, scalar or (m,)); ``kind``,
        ``feed`` [mm/min], ``tag``, ``cleared``, ``arc`` (0/2/3) scalars or per point; ``center``
        (m, 2) absolute arc centres [mm]."""
        P = np.asarray(points, float)
        if P.ndim == 1:
            P = P[None]
        m = len(P)
        if m == 0:
            return
        if P.shape[1] == 2:
            if z is None:
                raise ValueError("z (mm) is required for (m, 2) points")
            P = np.column_stack([P, np.broadcast_to(np.asarray(z, float), (m,))])
        elif P.shape[1] != 3:
            raise ValueError(f"points must be (m, 2) or (m, 3) mm, got shape {P.shape}")
        if isinstance(kind, str):           # one kind for every point (the planners' call): one lookup
            k = _kind_indices((kind,)).repeat(m)
        else:
            k = _kind_indices(np.broadcast_to(np.asarray(kind, dtype=object), (m,)))
        ctr = np.full((m, 2), np.nan) if center is None else np.broadcast_to(np.asarray(center, float), (m, 2))
        self._chunks.append((P, k, np.broadcast_to(np.asarray(feed, float), (m,)),
                             np.broadcast_to(np.asarray(tag, dtype=object), (m,)),
                             np.broadcast_to(np.asarray(arc, np.int8), (m,)), ctr,
                             np.broadcast_to(np.asarray(cleared, bool), (m,))))
        self._n += m

    def rapid(self, points, *, z=None, tag="", cleared=False) -> None:
        """G0 moves (below the clearance plane only with ``cleared``: the writer refuses others)."""
        self.add(points, "rapid", np.nan, tag, z=z, cleared=cleared)

    def cut(self, points, feed, *, z=None, tag="", cleared=False) -> None:
        """Cutting feed moves at ``feed`` mm/min."""
        self.add(points, "cut", feed, tag, z=z, cleared=cleared)

    def link(self, points, feed, *, z=None, tag="", cleared=False) -> None:
        """Feed moves at depth through cleared area (no material expected)."""
        self.add(points, "link", feed, tag, z=z, cleared=cleared)

    def plunge(self, xy, z, feed, *, tag="", cleared=False) -> None:
        """A straight-down feed move to (xy, ``z``) — into air or cleared area only (``cleared``)."""
        self.add(np.asarray(xy, float).reshape(1, -1)[:, :2], "plunge", feed, tag, z=z, cleared=cleared)

    def lift(self, clearance_z, *, tag="") -> None:
        """A rapid straight up from the current position to ``clearance_z`` (mm): out of the tool's own
        cut, as FreeCAD and every cnclab planner lift (nothing to do when the tool is already there)."""
        if self.position is None:
            raise ValueError("lift: no position yet")
        if self.position[2] < clearance_z:
            self.add(self.position[None, :2], "rapid", np.nan, tag, z=clearance_z)

    def approach(self, xy, top_z, clearance_z, *, above_mm: float = APPROACH_MM) -> None:
        """From the clearance plane down towards the level whose material starts at ``top_z`` (mm; the
        stock top, or the floor a level above cleared): from below the clearance plane first a
        :meth:`lift`, then a rapid to ``xy`` at ``clearance_z`` (where the tool is not there yet) and a
        rapid down to ``above_mm`` (default :data:`APPROACH_MM`) above ``top_z`` (air), or to the
        clearance plane where that is lower. The entry at feed follows.

        >>> b = ToolPathBuilder()
        >>> b.approach((3, 4), top_z=0.0, clearance_z=5.0)
        >>> b.build().xyz.tolist(), b.build().kinds().tolist()
        ([[3.0, 4.0, 5.0], [3.0, 4.0, 0.5]], ['rapid', 'rapid'])
        """
        xy = np.asarray(xy, float).reshape(-1)[:2]
        if self.position is not None:
            self.lift(clearance_z)              # never a rapid across from below the clearance plane
        pos = self.position
        if pos is None or np.hypot(*(pos[:2] - xy)) > 1e-9 or abs(pos[2] - clearance_z) > 1e-9:
            self.add(xy[None], "rapid", np.nan, z=clearance_z)
        if top_z + above_mm < clearance_z:
            self.add(xy[None], "rapid", np.nan, "cleared: above the level top", z=top_z + above_mm, cleared=True)

    def retract(self, z, feed, *, tag="") -> None:
        """Straight up from the current position to ``z`` mm at ``feed`` mm/min."""
        if self.position is None:
            raise ValueError("retract: no position yet")
        self.add(self.position[None, :2], "retract", feed, tag, z=z)

    def arc(self, end, center_xy, ccw: bool, feed, *, kind="cut", tag="", cleared=False) -> None:
        """One circular (or, with a z change, helical) move to ``end`` (3,) mm about ``center_xy``
        (absolute, mm): G3 when ``ccw``, else G2."""
        self.add(np.asarray(end, float)[None], kind, feed, tag, cleared=cleared, arc=3 if ccw else 2,
                 center=np.asarray(center_xy, float)[None])

    def helix(self, ring_xy, z_from: float, z_to: float, feed, *, tag="", cleared=False,
              equal_steps: bool = False) -> None:
        """The one helical-entry generator: descend from ``z_from`` (at ``ring_xy[0]``, where the tool
        is) to ``z_to`` mm along the polyline ``ring_xy`` (e.g. :func:`helix_ring`), z linear in the
        xy length travelled; ``helix`` moves to ``ring_xy[1:]``. ``equal_steps``: the ring's chords
        are equal (a :func:`helix_ring`), so move k of n ends at exactly k/n of the depth (no
        rounding of the lengths' ratio)."""
        P = np.asarray(ring_xy, float).reshape(-1, 2)
        s = np.r_[0.0, np.cumsum(np.hypot(*np.diff(P, axis=0).T))]
        if len(P) < 2 or not s[-1] > 0:
            raise ValueError("helix: ring_xy must be a polyline of positive length (mm)")
        t = np.arange(1, len(P)) / (len(P) - 1) if equal_steps else s[1:] / s[-1]
        z = z_from + (z_to - z_from) * t
        z[-1] = z_to                                         # the depth exactly (no rounding)
        self.add(P[1:], "helix", feed, tag, z=z, cleared=cleared)

    def ramp(self, path_xy, z_from: float, z_to: float, feed, *, ramp_deg: float = 3.0,
             max_mm: float = 10.0) -> None:
        """The one ramp-entry generator: from above ``path_xy[0]`` (the tool at or above ``z_from``)
        down at ``ramp_deg`` degrees from ``z_from`` to ``z_to`` mm, back and forth along the first
        ``max_mm`` mm of the polyline ``path_xy``, then back to its start at depth (a ``cut`` tagged
        ``ramp-return``). A path shorter than 1e-3 mm gets a vertical plunge instead."""
        Q = np.asarray(path_xy, float).reshape(-1, 2)
        s_q = np.r_[0.0, np.cumsum(np.hypot(*np.diff(Q, axis=0).T))] if len(Q) > 1 else np.zeros(1)
        L = min(float(s_q[-1]), float(max_mm))
        H = (z_from - z_to) / math.tan(math.radians(ramp_deg))
        if L < 1e-3 or not H > 0:
            self.add(Q[:1], "plunge", feed, z=z_to)
            return
        self.add(Q[:1], "plunge", feed, "approach", z=z_from)

        def at(u):
            return np.column_stack([np.interp(u, s_q, Q[:, 0]), np.interp(u, s_q, Q[:, 1])])

        inner = s_q[(s_q > 0) & (s_q < L)]
        travelled, pos, fwd = 0.0, 0.0, True
        while travelled < H - 1e-12:
            end = L if fwd else 0.0
            leg = min(abs(end - pos), H - travelled)
            tgt = pos + leg if fwd else pos - leg
            mid = inner[(inner > min(pos, tgt)) & (inner < max(pos, tgt))]
            u = np.r_[np.sort(mid) if fwd else np.sort(mid)[::-1], tgt]
            dist = travelled + np.abs(u - pos)
            self.add(at(u), "ramp", feed, z=z_from + (z_to - z_from) * np.minimum(dist / H, 1.0))
            travelled, pos, fwd = travelled + leg, tgt, not fwd
        if pos > 1e-9:                                       # back to the segment start at depth
            mid = inner[inner < pos][::-1]
            self.add(at(np.r_[mid, 0.0]), "cut", feed, "ramp-return", z=z_to)

    def tail(self, start: int) -> tuple:
        """The moves ``start:`` appended so far, read back: ``(xyz (m, 3) mm, kind (m,) indices into
        :data:`KINDS`, feed (m,) mm/min)`` (e.g. a planner retracing its own last moves)."""
        if not 0 <= start <= self._n:
            raise ValueError(f"start must be in [0, {self._n}], got {start!r}")
        got, i = [(np.zeros((0, 3)), np.zeros(0, np.int8), np.zeros(0))], self._n
        for chunk in reversed(self._chunks[-(self._n - start):] if start < self._n else []):
            i -= len(chunk[0])
            got.insert(1, [c[max(start - i, 0):] for c in chunk[:3]])
            if i <= start:
                break
        return tuple(np.concatenate([g[j] for g in got]) for j in range(3))

    def mark(self) -> int:
        """The number of moves so far (a point to :meth:`rollback` to)."""
        return self._n

    def rollback(self, mark: int) -> None:
        """Drop every move appended after :meth:`mark` returned ``mark``."""
        if not 0 <= mark <= self._n:
            raise ValueError(f"mark must be in [0, {self._n}], got {mark!r}")
        while self._n > mark:
            chunk = self._chunks[-1]
            m = len(chunk[0])
            if self._n - m >= mark:
                self._chunks.pop()
                self._n -= m
            else:
                keep = mark - (self._n - m)
                self._chunks[-1] = tuple(c[:keep] for c in chunk)
                self._n = mark

    def set_tag(self, start: int, stop: int, tag) -> None:
        """Replace the tags of moves ``start:stop`` (indices as :meth:`mark` counts them)."""
        self._edit(start, stop, 3, tag)

    def set_cleared(self, start: int, stop: int, cleared=True) -> None:
        """Set the ``cleared`` flag of moves ``start:stop``."""
        self._edit(start, stop, 6, cleared)

    def _edit(self, start, stop, col, value):
        i = 0
        for c, chunk in enumerate(self._chunks):
            m = len(chunk[0])
            a, b = max(start - i, 0), min(stop - i, m)
            if a < b:
                arr = np.array(chunk[col])
                arr[a:b] = value
                self._chunks[c] = chunk[:col] + (arr,) + chunk[col + 1:]
            i += m

    def build(self, drop_repeats: bool = False, **info) -> ToolPath:
        """The :class:`ToolPath` of the moves (``info`` keys added to the builder's); with
        ``drop_repeats`` a move to the point the tool is already at is left out (the first kept)."""
        if not self._chunks:
            raise ValueError("ToolPathBuilder: no moves")
        col = [np.concatenate([c[j] for c in self._chunks]) for j in range(7)]
        col[5] = np.vstack([c[5] for c in self._chunks])
        if drop_repeats:
            keep = np.r_[True, np.any(np.diff(col[0], axis=0) != 0, axis=1)]
            col = [c[keep] for c in col]
        f = col[2].copy()
        f[col[1] == _KIND_INDEX["rapid"]] = np.nan
        return ToolPath(col[0], col[1], col[3].astype(object), f, self.spindle, col[4], col[5], self.tool,
                        {**self.info, **info}, col[6])
