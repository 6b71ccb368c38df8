"""Arc fitting for the program writer: runs of short line moves become G2/G3 arcs (helical where z
changes linearly with the angle) or longer G1 lines (runs of G0 moves: longer G0 lines, never arcs),
within a stated tolerance of the planned path.

:func:`fit_arcs` takes a :class:`~cnclab.toolpath.path.ToolPath` and returns the path the writer
writes. Only consecutive **line moves of the same kind, feed, spindle, tag** (and any other
per-move column the path carries, e.g. a ``cleared`` flag) are merged (G0 runs into G0 lines only:
a line between two points at or above a plane stays above it); existing arcs and the first move are
kept as they are, and a merged move keeps the attributes of the moves it replaces,
so a cleared rapid, a link and a cut are never joined and nothing the safety checks read changes.

Greedy fit, from each run start the longest next piece that passes (found by probing end points
at doubling distances, then bisection): a line through the two end points, or an arc through them whose centre
lies on their perpendicular bisector (one-parameter algebraic least squares, then snapped to the
written grid so that the start and end radii *as written* agree within 1.5 units of the last digit).
A piece is accepted only when, for every point and every chord of the replaced polyline,

* the distance to the fitted line/arc (radial and z deviation together, chords bounded exactly: the
  inward radial deviation of a chord is ``r`` minus the chord's distance to the centre) is at most
  ``tol_mm - 10**-decimals`` (the last unit is left for the written rounding of end points and
  centre), and
* the points advance monotonically along it (projection parameter for lines; angle, each step
  < 90 deg, total sweep <= 270 deg, for arcs): every point of the fitted piece is then within the
  tolerance of the polyline too (Hausdorff distance <= ``tol_mm`` both ways, tested by dense sampling
  in ``tests/test_arcfit.py``).

Arcs have radius <= ``max_radius_mm`` (1 m; flatter runs are lines) and a chord of at least
10 units of the last written digit.

**Walls** (``walls``, a :class:`Walls`: the pocket, the tool radius, the stock top): the tolerance is
two-sided, so a piece fitted to a pass that runs along a wall at exactly the tool radius could reach
up to ``tol_mm`` into it (written programs gouged walls by up to 4.9 um before this rule). Below the
stock top, every point and chord of the replaced polyline with clearance ``c`` from the walls and
islands (``distance - r``, >= 0 on a path that does not gouge) is therefore allowed a deviation of
at most ``max(c - tol_mm, 0) + Walls.slack_mm`` (0.5 um), capped by ``tol_mm``: a point within
``tol_mm`` of a wall (a finishing lap) keeps within 0.5 um of the plan both ways — toward the wall it
would gouge, away from it it would leave the sliver it was planned to take (spiral_0 of the corpus
left 0.037 mm^2 more at a rule of ``c + slack``) — and away from walls the fit is unchanged. The
written piece then reaches at most ``slack_mm`` past the wall (plus the rounding of the written
coordinates, half a unit of the last digit per axis).

>>> import numpy as np
>>> from cnclab.toolpath.path import ToolPath
>>> a = np.linspace(0, np.pi, 200)
>>> p = ToolPath.build(np.column_stack([10 * np.cos(a), 10 * np.sin(a), -a / np.pi]), feed=500)
>>> q = fit_arcs(p)
>>> len(p), len(q), q.arc.tolist()
(200, 2, [0, 3])
>>> [round(float(v), 4) + 0.0 for v in q.arc_center[1]]
[0.0, 0.0]
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..geometry.planar import wall_clearance
from . import _arcfit_kernels as _kernels
from ..toolpath.path import KINDS, ToolPath

__all__ = ["fit_arcs", "cleared_mask", "Walls", "engagement_tol_mm", "DEFAULT_TOL_MM", "MAX_RADIUS_MM",
           "WALL_SLACK_MM", "ENGAGEMENT_BUDGET_DEG", "MIN_TOL_MM"]

#: default fitting tolerance [mm] (stated in every program header)
DEFAULT_TOL_MM = 0.005
#: deviation [mm] a fitted piece may add toward a wall or island beyond the planned path's own
#: clearance (below the 1 um a corpus job counts as a gouge and the evaluator's 2 um event tolerance)
WALL_SLACK_MM = 0.0005
#: deg: the engagement change a fitted piece may cause on a pocket job. A lateral shift d of the path
#: changes the engagement angle of a tool of radius r at theta by d / (r sin theta) rad, so the 5 um
#: default is 0.45 deg for r = 1 mm at theta = 40 deg: measured on random pocket 76:5 of
#: bench_random_pockets (r 1, theta 40, dixel r/60), the written program's p95 rose from theta + 0.25
#: to + 0.78 and its share above theta + 5 from 0.001 to 0.045 %; fitted within 2 um it was + 0.09 / 0.001.
ENGAGEMENT_BUDGET_DEG = 0.2
#: mm: the smallest tolerance :func:`engagement_tol_mm` gives (ten units of a 4-decimal program)
MIN_TOL_MM = 0.001
#: largest fitted arc radius [mm]; flatter runs are written as lines
MAX_RADIUS_MM = 1000.0
_MAX_SWEEP = 1.5 * math.pi     # at most 270 deg per arc block (centre well conditioned)
_MAX_STEP = 0.5 * math.pi      # a point may advance at most 90 deg along the arc
_MAX_SPAN = 4096                # moves: the longest piece tried from one start
_RAPID = KINDS.index("rapid")
_LINK = KINDS.index("link")
_FIXED = ("xyz", "arc", "arc_center")


@dataclasses.dataclass(frozen=True)
class Walls:
    """The walls a fitted piece must not reach into: ``polygon`` (the pocket, islands as holes; mm),
    the tool radius ``radius_mm`` and the stock top ``top_z`` (points at or above it are free).

    >>> from shapely.geometry import box
    >>> w = Walls(box(0, 0, 40, 20), 3.0)
    >>> w.allowance(np.array([[20.0, 10, -1], [37.0, 10, -1], [37.0, 10, 1]]), 0.005).tolist()
    [0.005, 0.0005, 0.005]
    """
    polygon: object
    radius_mm: float
    top_z: float = 0.0
    slack_mm: float = WALL_SLACK_MM

    @classmethod
    def of_job(cls, job) -> "Walls | None":
        """The walls of a pocket job (None for a job without a pocket polygon or tool radius)."""
        poly, r = getattr(job, "polygon", None), getattr(job, "tool_radius", None)
        if poly is None or r is None or poly.is_empty:
            return None
        return cls(poly, float(r), float(getattr(job, "top_z", 0.0) or 0.0))

    def allowance(self, P: np.ndarray, tol: float) -> np.ndarray:
        """Per point of ``P`` (n, 3) mm: the deviation a fitted piece may have there [mm],
        ``min(tol, max(clearance - tol, 0) + slack_mm)`` below the stock top, ``tol`` above it
        (clearance: :func:`cnclab.geometry.planar.wall_clearance`; points inside the pocket shrunk by
        r + 3 tol, whose 64-segment arcs leave a margin of tol, have at least 2 tol and skip it)."""
        deep = self.polygon.buffer(-(self.radius_mm + 3 * tol), 64)
        c = wall_clearance(self.polygon, self.radius_mm, P, self.top_z, clear=deep)
        return np.minimum(tol, np.maximum(c - tol, 0.0) + self.slack_mm)

    def chord_allowance(self, P: np.ndarray, tol: float) -> np.ndarray:
        """Per chord of the polyline ``P`` [mm]: the least allowance of its two ends and its middle."""
        P = np.asarray(P, float)
        a = self.allowance(np.vstack([P, 0.5 * (P[1:] + P[:-1])]), tol)     # the points, then the middles
        n = len(P)
        return np.minimum(np.minimum(a[1:n], a[:n - 1]), a[n:])


def engagement_tol_mm(radius_mm: float, theta_deg: float, tol_mm: float = DEFAULT_TOL_MM,
                      budget_deg: float = ENGAGEMENT_BUDGET_DEG) -> float:
    """Fitting tolerance [mm] that changes the engagement of a tool of radius ``radius_mm`` [mm] at
    ``theta_deg`` [deg] by at most ``budget_deg`` [deg]: ``budget (rad) r sin(theta)`` (theta taken
    at most 90 deg) rounded down to 0.01 um, capped by ``tol_mm`` and at least :data:`MIN_TOL_MM`.

    >>> engagement_tol_mm(3.0, 60.0), engagement_tol_mm(1.0, 40.0), engagement_tol_mm(0.5, 5.0)
    (0.005, 0.00224, 0.001)
    """
    if not (math.isfinite(radius_mm) and radius_mm > 0 and math.isfinite(theta_deg) and 0 < theta_deg < 180):
        raise ValueError(f"engagement_tol_mm needs a tool radius > 0 mm and 0 < theta < 180 deg, "
                         f"got r = {radius_mm!r}, theta = {theta_deg!r}")
    d = math.radians(budget_deg) * radius_mm * math.sin(math.radians(min(theta_deg, 90.0)))
    return float(min(tol_mm, max(MIN_TOL_MM, math.floor(d * 1e5) / 1e5)))


def cleared_mask(path: ToolPath) -> np.ndarray:
    """Moves the planner marks as inside cleared area: the path's boolean ``cleared`` column (its
    proof of air; tags are never read)."""
    return np.asarray(path.cleared, bool).copy()


def _columns(path: ToolPath) -> dict:
    """Every per-move 1-D column of ``path`` (kind, tag, feed, spindle and any other), by field name."""
    n = len(path)
    out = {}
    for f in dataclasses.fields(path):
        v = getattr(path, f.name)
        if f.name not in _FIXED and isinstance(v, np.ndarray) and v.shape == (n,):
            out[f.name] = v
    return out


def _same_as_previous(cols: dict, n: int) -> np.ndarray:
    """``same[k]``: move k has the same value as move k-1 in every column (NaN equal to NaN)."""
    same = np.ones(n, bool)
    same[0] = False
    for v in cols.values():
        if v.dtype.kind == "f":
            a, b = v[1:], v[:-1]
            same[1:] &= (a == b) | (np.isnan(a) & np.isnan(b))
        else:
            same[1:] &= np.asarray(v[1:] == v[:-1], bool)      # elementwise == (object arrays: each pair's)
    return same


def _fit_run(P, tol, grid, max_radius, arcs=True):
    """Pieces ``[(end index in P, arc code 0/2/3, cx, cy), ...]`` covering the polyline ``P`` (lines
    only unless ``arcs``); ``tol`` [mm] per chord of ``P``. From each start the longest line and the
    longest arc are found (doublings, then bisection: a short piece may fail where a longer one fits,
    an arc centre being ill-determined over a short, noisy run); the arc is taken when it reaches
    further. The tests of one piece and the cover are compiled (:mod:`cnclab.nc._arcfit_kernels`)."""
    scale = 10.0 ** round(-math.log10(grid))
    ends, codes, cxs, cys = _kernels.fit_run(np.ascontiguousarray(P, float), np.ascontiguousarray(tol, float),
                                             grid, scale, max_radius, _MAX_STEP, _MAX_SWEEP, bool(arcs), _MAX_SPAN)
    return [(int(e), int(c), float(x), float(y)) for e, c, x, y in zip(ends, codes, cxs, cys)]


def fit_arcs(path: ToolPath, tol_mm: float = DEFAULT_TOL_MM, decimals: int = 4,
             max_radius_mm: float = MAX_RADIUS_MM, rapid_arc_feed_mm_min: float | None = None,
             walls: Walls | None = None) -> ToolPath:
    """``path`` with runs of line moves replaced by fewer lines and G2/G3 arcs (see the module
    docstring) within ``tol_mm`` [mm] of the planned path, for a program written with ``decimals``
    digits [mm]. ``rapid_arc_feed_mm_min`` (default None: off): a run of G0 moves inside cleared
    area (:func:`cleared_mask`) may be fitted with arcs too; such an arc becomes a ``link`` move (a
    feed move through cleared area) at this feed [mm/min] — the rapid rate keeps the program's time
    — because G0 cannot describe an arc; G0 pieces fitted as lines stay G0. ``walls`` (a
    :class:`Walls`, e.g. ``Walls.of_job(job)``; default None): below the stock top a point within
    ``tol_mm`` of a wall or island may move by ``walls.slack_mm`` only, farther ones by their clearance
    less ``tol_mm`` plus it (:meth:`Walls.allowance`, module docstring). ``info["arcfit"]`` records the tolerance and the move counts;
    ``info["arcfit_source"]`` the index of the original move each fitted move ends on.

    Raises ``ValueError`` for a tolerance not larger than two units of the last written digit.
    """
    if not isinstance(decimals, int) or not 1 <= decimals <= 8:
        raise ValueError(f"decimals must be an int in [1, 8], got {decimals!r}")
    grid = 10.0 ** -decimals
    if not (math.isfinite(tol_mm) and tol_mm > 2 * grid):
        raise ValueError(f"arc fitting tolerance tol_mm must be a finite number > {2 * grid:g} mm "
                         f"(two units of the last written digit), got {tol_mm!r}")
    if not (math.isfinite(max_radius_mm) and max_radius_mm > 0):
        raise ValueError(f"max_radius_mm must be a finite number > 0 mm, got {max_radius_mm!r}")
    tol_fit = tol_mm - grid
    N = len(path)
    tol_chord = (np.full(max(N - 1, 0), tol_fit) if walls is None or N < 2
                 else walls.chord_allowance(path.xyz, tol_fit))     # tol_chord[m]: xyz[m] -> xyz[m + 1]
    cols = _columns(path)
    elig = path.arc == 0
    if N:
        elig[0] = False
    same = _same_as_previous(cols, N)
    if rapid_arc_feed_mm_min is not None and not (math.isfinite(rapid_arc_feed_mm_min) and rapid_arc_feed_mm_min > 0):
        raise ValueError(f"rapid_arc_feed_mm_min must be a finite feed > 0 mm/min or None, got {rapid_arc_feed_mm_min!r}")
    cleared = cleared_mask(path)
    keep, arc, ctr, to_link = [], [], [], []
    k = 0
    while k < N:
        if not elig[k]:
            keep.append(k); arc.append(int(path.arc[k])); ctr.append(path.arc_center[k])
            k += 1
            continue
        k2 = k
        while k2 + 1 < N and elig[k2 + 1] and same[k2 + 1]:
            k2 += 1
        rapid = path.kind[k] == _RAPID     # G0 runs: G0 lines, arcs only as links in cleared area
        arcs_ok = not rapid or (rapid_arc_feed_mm_min is not None and cleared[k])
        for end, code, cx, cy in _fit_run(path.xyz[k - 1:k2 + 1], tol_chord[k - 1:k2], grid, max_radius_mm,
                                         arcs_ok):
            keep.append(k - 1 + end); arc.append(code); ctr.append((cx, cy))
            if rapid and code:
                to_link.append(len(keep) - 1)
        k = k2 + 1
    idx = np.asarray(keep, int)
    kw = {name: v[idx] for name, v in cols.items()}
    if to_link:
        kw["kind"][to_link] = _LINK
        kw["feed"][to_link] = float(rapid_arc_feed_mm_min)
    info = {key: v for key, v in path.info.items()
            if not (isinstance(v, np.ndarray) and v.shape[:1] == (N,))}  # per-move info no longer aligned
    info["arcfit"] = {"tol_mm": float(tol_mm), "wall_slack_mm": None if walls is None else float(walls.slack_mm), "moves_in": N, "moves_out": len(idx),
                      "arcs": int(np.count_nonzero(np.asarray(arc) != 0))}
    info["arcfit_source"] = idx
    return dataclasses.replace(path, xyz=path.xyz[idx], arc=np.asarray(arc, np.int8),
                               arc_center=np.asarray(ctr, float).reshape(-1, 2), info=info, **kw)
