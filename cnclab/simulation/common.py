"""Shared part of the 2.5D material-removal simulators (:mod:`.dixel` and :mod:`.pixel`).

Both stock models derive from :class:`StockBase` and only implement material membership
(``_contains``), the disk cut and the area. Everything that is measured from the stock -- the
engagement angle, entry/exit angles, chip thickness and the per-step table of :func:`simulate` --
is written once here, so the two models are compared on exactly the same measurement.

Conventions
-----------
* Lengths in mm, the tool is a cylinder of radius ``tool_radius`` (mm, a radius, not a diameter);
  in the X-Y plane it is a disk.
* Angles at the API are in **degrees**. ``entry_deg``/``exit_deg`` are measured from the feed
  direction, counter-clockwise positive, so material on the right of the feed (as in Thesis II of
  Jacsó 2021, see :mod:`cnclab.toolpath.constant_engagement`) gives negative angles.
* The engagement angle is the central angle of the part of the tool circumference that lies in
  material (Jacsó 2021, §2.1). By default only the front half-circle (within +-90 deg of the feed
  direction) is examined: behind the tool the material has been removed by the tool itself, so this
  is the limit of a vanishing simulation step (``front_only=False`` examines the full circle).
"""
from __future__ import annotations

import dataclasses
import functools
import math
import os
from typing import NamedTuple

import numpy as np

#: implementations of the per-step work: "numpy" (the readable reference, vectorised per call) and
#: "numba" (compiled kernels in :mod:`._kernels`, line-by-line ports; a whole path is one call)
BACKENDS = ("numpy", "numba")


def _default_backend() -> str:
    name = os.environ.get("CNCLAB_SIM_BACKEND", "numba")
    if name not in BACKENDS:
        raise ValueError(f"CNCLAB_SIM_BACKEND must be one of {BACKENDS}, got {name!r}")
    if name == "numba":
        try:
            import numba  # noqa: F401
        except ImportError:  # pragma: no cover - numba is pinned in environment.txt
            return "numpy"
    return name


_BACKEND = [_default_backend()]


def set_backend(name: str) -> str:
    """Select the default simulator backend ("numpy" or "numba"); returns the previous one.

    Both give the same results (tests/test_simulation_kernels.py); "numba" is the fast default
    (environment variable ``CNCLAB_SIM_BACKEND`` overrides it at import).
    """
    if name not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {name!r}")
    old = _BACKEND[0]
    _BACKEND[0] = name
    return old


def get_backend() -> str:
    """The current default simulator backend ("numpy" or "numba")."""
    return _BACKEND[0]


def resolve_backend(backend) -> str:
    if backend is None:
        return _BACKEND[0]
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS} or None, got {backend!r}")
    return backend


class Engagement(NamedTuple):
    """Engagement of the tool circumference with material at one tool position.

    angle_deg: central angle in contact with material (deg); entry_deg/exit_deg: the first and
    last engaged angle measured from the feed direction (deg, ccw positive, NaN when not engaged);
    intervals: (k, 2) array of engaged angular intervals (rad, relative to the feed direction).
    """

    angle_deg: float
    entry_deg: float
    exit_deg: float
    intervals: np.ndarray


def check_radius(tool_radius) -> float:
    r = float(tool_radius)
    if not (math.isfinite(r) and r > 0):
        raise ValueError(f"tool_radius must be a positive finite length in mm, got {tool_radius!r}")
    return r


def check_xy(xy, name: str) -> np.ndarray:
    a = np.asarray(xy, dtype=float)
    if a.shape != (2,) or not (math.isfinite(a[0]) and math.isfinite(a[1])):
        raise ValueError(f"{name} must be a finite (x, y) pair in mm, got {xy!r}")
    return a


def strip_area(u1, u2, r):
    """Area (mm^2) of the disk of radius ``r`` centred at 0 lying in the strip ``u1 <= y <= u2``.

    Exact (integral of the chord length); ``u1``, ``u2`` may be arrays.

    >>> round(float(strip_area(-1.0, 1.0, 1.0)), 12) == round(math.pi, 12)
    True
    """
    u1 = np.clip(u1, -r, r)
    u2 = np.clip(u2, -r, r)

    def g(u):
        return 0.5 * (u * np.sqrt(np.maximum(r * r - u * u, 0.0)) + r * r * np.arcsin(u / r))

    return 2.0 * (g(u2) - g(u1))


def chip_thickness(intervals, f_z: float) -> tuple[float, float]:
    """Maximum and average uncut chip thickness (mm) over engaged angular intervals.

    Circular-tooth-path approximation (Martellotti, *Trans. ASME* 63, 1941; Altintas,
    *Manufacturing Automation*, 2nd ed. 2012, eq. 2.2): a tooth at angle psi from the feed
    direction cuts

        h(psi) = f_z cos(psi)                       (mm; |psi| <= 90 deg, the front half)

    so over the engaged set E (only its part in the front half-circle counts)

        h_max = f_z max_{psi in E} cos(psi)
        h_avg = (1/theta) integral_E h dpsi = f_z sum(sin psi_2 - sin psi_1) / theta,

    theta the engaged angle (rad). For a straight cut of radial depth a_e with a tool of radius r
    (theta = arccos(1 - a_e/r)): h_max = f_z sin(theta) for theta <= 90 deg (f_z beyond), and
    h_avg = f_z a_e / (r theta), Sandvik's mean chip thickness h_m = 360 f_z a_e / (pi D theta_deg)
    (Sandvik Coromant, *Metalcutting technical guide*, milling formulas; D = 2r, kappa_r = 90 deg).
    The booklet (Jacsó 2021, §2.2) names h_max and h_avg as
    outputs of the simulator but prints no formula; these are the standard ones.

    Parameters
    ----------
    intervals : (k, 2) engaged angular intervals, rad, relative to the feed direction (ccw +).
    f_z : feed per tooth (mm).

    Returns
    -------
    (h_max, h_avg) in mm; (0, 0) when nothing in the front half is engaged.

    Examples
    --------
    Straight cut, r = 3 mm, a_e = 1.5 mm (theta = 60 deg, material on the right of the feed):

    >>> th = math.acos(1 - 1.5 / 3)
    >>> h_max, h_avg = chip_thickness([[-math.pi / 2, -math.pi / 2 + th]], f_z=0.04)
    >>> round(h_max, 6), round(0.04 * math.sin(th), 6)
    (0.034641, 0.034641)
    >>> round(h_avg, 6), round(0.04 * 1.5 / (3 * th), 6)
    (0.019099, 0.019099)
    """
    iv = np.asarray(intervals, dtype=float).reshape(-1, 2)
    if iv.size == 0:
        return 0.0, 0.0
    lo = np.clip(iv[:, 0], -np.pi / 2, np.pi / 2)
    hi = np.clip(iv[:, 1], -np.pi / 2, np.pi / 2)
    keep = hi > lo
    lo, hi = lo[keep], hi[keep]
    theta = float(np.sum(hi - lo))
    if theta <= 0:
        return 0.0, 0.0
    contains0 = np.any((lo <= 0) & (hi >= 0))
    cmax = 1.0 if contains0 else float(np.max(np.cos(np.concatenate([lo, hi]))))
    h_avg = f_z * float(np.sum(np.sin(hi) - np.sin(lo))) / theta
    return f_z * cmax, h_avg


@functools.lru_cache(maxsize=8)
def _unit_grid(n: int) -> np.ndarray:
    u = np.linspace(0.0, 1.0, n + 1)
    u.flags.writeable = False
    return u


def refine_transitions(contains, c, r, psi0, a, b, ma, bisections=16, n_sub=256):
    """All material/air transitions on the tool circle inside angle brackets [a, b] (rad).

    ``ma`` is the state (in material?) at each ``a``; the state at ``b`` is its negation. Each
    bracket is sampled at ``n_sub`` sub-intervals (one vectorised membership call), so *every*
    transition inside it is found (not just one, as bisection would), then each transition is
    refined by further rounds of ``n_sub`` samples until its bracket has shrunk by
    >= 2**bisections. Returns the sorted transition angles (rad, bracket midpoints); their number
    per bracket is odd, so the material/air alternation of the caller is kept.
    """
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    ma = np.asarray(ma, bool)
    u = _unit_grid(n_sub)

    def sample(a, b):
        grid = a[:, None] + (b - a)[:, None] * u                 # (q, n_sub + 1)
        ang = psi0 + grid[:, 1:-1].ravel()
        mm = contains(c[0] + r * np.cos(ang), c[1] + r * np.sin(ang)).reshape(a.size, n_sub - 1)
        return grid, mm

    grid, mm = sample(a, b)
    state = np.concatenate([ma[:, None], mm, ~ma[:, None]], axis=1)
    qi, ii = np.nonzero(state[:, 1:] != state[:, :-1])          # every transition, row-major
    a, b, ma = grid[qi, ii], grid[qi, ii + 1], state[qi, ii]
    rows = np.arange(a.size)
    for _ in range(int(math.ceil(bisections / math.log2(n_sub))) - 1):
        grid, mm = sample(a, b)
        diff = mm != ma[:, None]
        first = np.where(diff.any(axis=1), diff.argmax(axis=1) + 1, n_sub)
        a, b = grid[rows, first - 1], grid[rows, first]
    return np.sort(0.5 * (a + b))


def material_removal_rate(removed_area_mm2, step_mm, a_p, feed_mm_min):
    """Material removal rate MRR (mm^3/min) of one simulation step.

    Jacsó (2021), §2.2: "the material removal rate ... can be calculated from the area of the
    sections determined step by step": the tool removes the area ``A`` (mm^2) while advancing
    ``ds`` (mm), i.e. a volume a_p A in ds / v_f minutes:

        MRR = a_p * A / ds * v_f          (mm^3/min; a_p axial depth mm, v_f feed mm/min)

    For a straight cut of radial depth a_e, A / ds = a_e and MRR = a_p a_e v_f (e.g. Table 4.1:
    3 mm x 1.5 mm x 255 mm/min = 1147.5 mm^3/min). Array inputs broadcast; ds = 0 gives NaN.

    >>> float(material_removal_rate(1.5 * 0.05, 0.05, a_p=3.0, feed_mm_min=255.0))
    1147.5
    """
    A = np.asarray(removed_area_mm2, dtype=float)
    ds = np.asarray(step_mm, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(ds > 0, float(a_p) * A / ds * float(feed_mm_min), np.nan)


class StockBase:
    """Interface shared by the dixel and pixel stocks (see the module docstrings)."""

    resolution_mm: float

    # -- to implement ---------------------------------------------------------------------------
    def _contains(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    def cut_disk(self, center_xy, tool_radius) -> float:  # pragma: no cover
        raise NotImplementedError

    def area(self) -> float:  # pragma: no cover
        raise NotImplementedError

    def copy(self):  # pragma: no cover
        raise NotImplementedError

    # -- shared ---------------------------------------------------------------------------------
    def contains(self, x, y) -> np.ndarray:
        """Boolean array: is the point (x, y) (mm, broadcastable arrays) in material?"""
        x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
        return self._contains(x.ravel(), y.ravel()).reshape(x.shape)

    def engagement(self, center_xy, tool_radius, feed_direction_xy, front_only: bool = True,
                   n_samples: int | None = None, bisections: int = 24) -> Engagement:
        """Engagement of the tool circumference with the material (before cutting at ``center_xy``).

        The circumference (front half by default) is sampled every ~resolution/2 of arc length, each
        material/air transition is refined on the membership test (:func:`refine_transitions`:
        the bracket shrunk by >= 2**bisections), and the engaged arcs are summed. Returns :class:`Engagement` (angles in degrees, intervals in radians).

        >>> from shapely.geometry import box
        >>> from cnclab.simulation.dixel import Stock
        >>> st = Stock.from_polygon(box(0, 0, 20, 10), 0.02)
        >>> round(st.engagement((5, 12), 3, (1, 0)).angle_deg)    # s = 1 mm: acos(1 - 1/3)
        48
        """
        c = check_xy(center_xy, "center_xy")
        r = check_radius(tool_radius)
        f = check_xy(feed_direction_xy, "feed_direction_xy")
        nf = math.hypot(*f)
        if nf == 0:
            raise ValueError("feed_direction_xy must be a non-zero vector")
        psi0 = math.atan2(f[1], f[0])
        lo, hi = (-np.pi / 2, np.pi / 2) if front_only else (-np.pi, np.pi)
        if n_samples is None:
            n_samples = int(max(181, math.ceil((hi - lo) * r / (0.5 * self.resolution_mm)) + 1))
        psi = np.linspace(lo, hi, n_samples)

        def inside(p):
            return self._contains(c[0] + r * np.cos(psi0 + p), c[1] + r * np.sin(psi0 + p))

        m = inside(psi)
        if not m.any():
            return Engagement(0.0, math.nan, math.nan, np.empty((0, 2)))
        if m.all():
            return Engagement(math.degrees(hi - lo), math.degrees(lo), math.degrees(hi),
                              np.array([[lo, hi]]))
        k = np.flatnonzero(m[1:] != m[:-1])          # transition between psi[k] and psi[k+1]
        # all transitions in each bracket, refined by >= 2**bisections (a few vectorised rounds)
        edges = refine_transitions(self._contains, c, r, psi0, psi[k], psi[k + 1], m[k], bisections)
        # build engaged intervals: start at lo if m[0], edges alternate rising/falling
        bounds = np.concatenate([[lo] if m[0] else [], edges, [hi] if m[-1] else []])
        return self._engagement_from_intervals(bounds.reshape(-1, 2))

    def _engagement_from_intervals(self, iv) -> Engagement:
        """:class:`Engagement` of engaged intervals (k, 2) (rad, from the feed direction, sorted)."""
        if iv.shape[0] == 0:
            return Engagement(0.0, math.nan, math.nan, np.empty((0, 2)))
        ang = float((iv[:, 1] - iv[:, 0]).sum())
        return Engagement(math.degrees(ang), math.degrees(iv[0, 0]), math.degrees(iv[-1, 1]), iv)

    def _simulate_compiled(self, P, d, ds, s, r, lag, central, front_only, f_z, out, hold_front=False):  # pragma: no cover
        """Run the whole path in one compiled call (see :func:`simulate`); False if not available."""
        return False

    def _removed_compiled(self, P, r, rem) -> bool:  # pragma: no cover
        """Cut the discs at ``P`` in order in one compiled call, their removed areas (mm^2) into ``rem``
        (see :func:`removal`); False if not available."""
        return False

    def _plain(self) -> bool:  # pragma: no cover
        """True when ``cut_disk``/``engagement`` are the model's own (accept ``backend=``, may be
        replaced by the compiled path); False for a subclass that overrides them."""
        return False

    def engagement_angle(self, center_xy, tool_radius, feed_direction_xy, **kw) -> float:
        """Engagement angle (deg) at ``center_xy`` for feed direction ``feed_direction_xy``.

        Central angle of the tool circumference in contact with material; see :meth:`engagement`.
        """
        return self.engagement(center_xy, tool_radius, feed_direction_xy, **kw).angle_deg


class PathSettings(NamedTuple):
    """The scalar settings of :func:`._kernels.simulate_path` (one tuple argument of the compiled kernel).

    ``model`` 0 dixel, 1 pixel; ``x0``, ``y0`` grid origin and ``h`` resolution (mm); ``r`` tool
    radius (mm); ``lag`` (mm) of :func:`.common.simulate`; ``central`` feed direction rule "central";
    ``front_only`` measure the front half-circle; ``polyline`` the dixel boundary rule; ``bisections``
    and ``n_samples`` of the engagement search (pixel: samples of the circle); ``f_z`` (mm; NaN: no
    chip thickness); ``hold_front`` the ``lag_rule="front"`` (held-back disks reaching the front
    half-circle are cut before the engagement is measured).
    """

    model: int
    x0: float
    y0: float
    h: float
    r: float
    lag: float
    central: bool
    front_only: bool
    polyline: bool
    bisections: int
    n_samples: int
    f_z: float
    hold_front: bool


def default_lag_mm(resolution_mm: float, tool_radius: float) -> float:
    """Distance (mm) behind the tool whose cuts are not yet applied when engagement is measured.

    Exactly, the tool's own recent positions never cover its front half-circle (for a smooth path
    whose curvature radius exceeds r). In a row/pixel model they do near psi = +-90 deg, because a
    row of height h at the top/bottom of a disk is up to ~sqrt(2 r h) wide: without a lag the
    engagement would lose ~sqrt(2h/r) rad at each end (8 deg at r = 3 mm, h = 0.01 mm). The lag
    2*sqrt(2 r h) + 2h removes this artefact.
    """
    return 2.0 * math.sqrt(2.0 * tool_radius * resolution_mm) + 2.0 * resolution_mm


@dataclasses.dataclass(frozen=True, kw_only=True)
class SimOptions:
    """Measurement settings of :func:`simulate` (see its parameters), keyword-only.

    ``front_only`` measure the front half-circle only; ``lag_mm`` (mm, None: :func:`default_lag_mm`);
    ``feed_direction`` ``"backward"`` | ``"central"``; ``backend`` ``"numba"`` | ``"numpy"`` | None;
    ``lag_rule`` ``"path"`` | ``"front"``.

    >>> SimOptions(lag_mm=0.0).feed_direction
    'backward'
    """

    front_only: bool = True
    lag_mm: float | None = None
    feed_direction: str = "backward"
    backend: str | None = None
    lag_rule: str = "path"


def _path_steps(centres, tool_radius, a_p, feed_mm_min):
    """The checked inputs of a path run (:func:`simulate`, :func:`removal`): centres ``P`` (N, 2) mm,
    the radius, the steps ``d`` (N-1, 2) and their lengths ``ds`` (N,, 0 first), mm."""
    P = np.asarray(centres, dtype=float)
    if P.ndim != 2 or P.shape[1] != 2 or len(P) < 2:
        raise ValueError(f"centres must be an (N, 2) array with N >= 2 (mm), got shape {P.shape}")
    if not np.all(np.isfinite(P)):
        raise ValueError("centres must be finite")
    r = check_radius(tool_radius)
    for name, v in (("a_p", a_p), ("feed_mm_min", feed_mm_min)):
        if not (math.isfinite(float(v)) and float(v) > 0):
            raise ValueError(f"{name} must be positive, got {v!r}")
    d = np.diff(P, axis=0)
    return P, r, d, np.r_[0.0, np.hypot(d[:, 0], d[:, 1])]


def simulate(stock: StockBase, centres, tool_radius, a_p, feed_mm_min, f_z=None, teeth=None, *,
             copy: bool = False, options: SimOptions | None = None, **fields):
    """Move the tool through ``centres`` cutting ``stock``; return a per-step pandas DataFrame.

    Works for both stock models (dixel and pixel). At step i the engagement is measured on the
    material left after step i-1 (feed direction = centres[i] - centres[i-1]), then the disk at
    centres[i] is cut.

    Parameters
    ----------
    stock : dixel or pixel ``Stock`` (updated in place unless ``copy=True``).
    centres : (N, 2) tool-centre positions (mm) sampled along the path (N >= 2).
    tool_radius : tool radius r (mm).
    a_p : axial depth of cut (mm).
    feed_mm_min : feed rate v_f (mm/min).
    f_z : feed per tooth (mm); gives chip-thickness columns (NaN without it).
    teeth : number of teeth z; with f_z gives the spindle speed n = v_f / (z f_z) column (rpm).
    copy : cut a copy of ``stock`` (the argument is left as it is).
    options : a :class:`SimOptions`; ``fields``, its fields as keywords (``front_only``, ``lag_mm``,
        ``feed_direction``, ``backend``, ``lag_rule``), replace those of ``options``:
    front_only : measure the front half-circle only (default True).
    lag_mm : engagement at step i is measured on the stock with the disks of the last ``lag_mm`` of
        path not yet cut (default :func:`default_lag_mm`; 0 = measure on the fully updated stock).
        The removed area of every step is still exact: disks are cut in path order.
    lag_rule : ``"path"`` (default): every disk of the last ``lag_mm`` is held back. ``"front"``: a
        held-back disk that truly covers part of the front half-circle (exact geometry,
        :func:`._kernels.reaches_front`; a disk behind the tool on a path whose curvature radius
        exceeds r never does, so smooth paths are measured as with ``"path"``) is cut before the
        engagement is measured, with the disks before it -- where the path turns back on itself (a pass starting beside the end of the
        previous one, a U-turn, a corner sharper than radius r) the lag would otherwise leave
        material the tool has already removed in front of it (phantom engagement).
    feed_direction : ``"backward"`` (default): centres[i] - centres[i-1], the chord just travelled;
        ``"central"``: centres[i+1] - centres[i-1], the tangent of a smoothly sampled path to
        O(ds^2) (the backward chord lags the tangent by half the step's turning angle, e.g. 0.09 deg
        for ds = 0.02 mm on a 6.5 mm radius, which shifts the measured front half-circle by as much).
    backend : ``"numba"`` (the whole loop in one compiled call), ``"numpy"`` (the reference: a Python
        loop over the steps calling ``stock.engagement`` / ``stock.cut_disk``) or None (the default
        of :func:`set_backend`). Same results; a stock subclass that overrides ``engagement`` or
        ``cut_disk`` always takes the numpy path (so the override is used).

    Returns
    -------
    DataFrame with columns x, y (mm), s (path length, mm), ds (mm), engagement_deg, entry_deg,
    exit_deg, removed_mm2 (area removed by this step), mrr_mm3_min = a_p * removed / ds * v_f
    (:func:`material_removal_rate`), h_max_mm, h_avg_mm (:func:`chip_thickness`; NaN without
    ``f_z``) (and spindle_rpm = v_f / (z f_z) when ``teeth`` is given). Row 0 (no feed direction from
    behind) uses centres[1] - centres[0] and has NaN MRR.

    >>> import numpy as np
    >>> from shapely.geometry import box
    >>> from cnclab.simulation.dixel import Stock
    >>> st = Stock.from_polygon(box(0, 0, 30, 10), 0.05)
    >>> xs = np.arange(-4, 34, 0.05)
    >>> df = simulate(st, np.c_[xs, np.full_like(xs, 11.5)], 3, a_p=3, feed_mm_min=255, f_z=0.04)
    >>> round(float(df.mrr_mm3_min[300:400].mean()), 0)       # a_p * a_e * v_f = 3*1.5*255
    1148.0
    """
    import pandas as pd

    o = SimOptions(**fields) if options is None else dataclasses.replace(options, **fields)
    lag_mm, feed_direction, lag_rule = o.lag_mm, o.feed_direction, o.lag_rule
    if copy:
        stock = stock.copy()
    P, r, d, ds = _path_steps(centres, tool_radius, a_p, feed_mm_min)
    if f_z is not None and not float(f_z) > 0:
        raise ValueError(f"f_z must be a positive feed per tooth in mm, got {f_z!r}")
    if teeth is not None and not (int(teeth) == teeth and teeth >= 1):
        raise ValueError(f"teeth must be a positive integer, got {teeth!r}")
    if feed_direction not in ("backward", "central"):
        raise ValueError(f"feed_direction must be 'backward' or 'central', got {feed_direction!r}")
    central = feed_direction == "central"
    if lag_rule not in ("path", "front"):
        raise ValueError(f"lag_rule must be 'path' or 'front', got {lag_rule!r}")
    hold_front = lag_rule == "front"
    n = len(P)
    eng = np.empty(n)
    ent = np.empty(n)
    ext = np.empty(n)
    rem = np.empty(n)
    hmax = np.full(n, np.nan)
    havg = np.full(n, np.nan)
    lag = default_lag_mm(stock.resolution_mm, r) if lag_mm is None else float(lag_mm)
    if not (lag >= 0):
        raise ValueError(f"lag_mm must be >= 0, got {lag_mm!r}")
    s_cum = np.cumsum(ds)
    fz = math.nan if f_z is None else float(f_z)
    be = resolve_backend(o.backend)
    plain = stock._plain()
    compiled = (be == "numba" and plain
                and stock._simulate_compiled(P, d, ds, s_cum, r, lag, central, o.front_only, fz,
                                             (eng, ent, ext, rem, hmax, havg), hold_front))
    if not compiled:
        _simulate_loop(stock, P, d, ds, s_cum, r, lag, f_z, (eng, ent, ext, rem, hmax, havg),
                       {"backend": be} if plain else {}, o)
    mrr = material_removal_rate(rem, ds, a_p, feed_mm_min)
    df = pd.DataFrame({"x": P[:, 0], "y": P[:, 1], "s": s_cum, "ds": ds,
                       "engagement_deg": eng, "entry_deg": ent, "exit_deg": ext,
                       "removed_mm2": rem, "mrr_mm3_min": mrr, "h_max_mm": hmax, "h_avg_mm": havg})
    if teeth is not None and f_z is not None:
        df["spindle_rpm"] = float(feed_mm_min) / (int(teeth) * float(f_z))
    return df


def removal(stock: StockBase, centres, tool_radius, a_p, feed_mm_min, *, backend: str | None = None):
    """The tool moved through ``centres`` cutting ``stock`` (in place), without measuring engagement:
    per step the columns ``s``, ``ds`` (mm), ``removed_mm2`` and ``mrr_mm3_min`` of :func:`simulate`,
    the same values (the discs are cut in path order there too, whatever its lag), in one compiled
    loop where the stock has one (the pixel stock, numba backend), else from :func:`simulate`.
    For MRR readings (Kim & Yang's pixel count): measuring the engagement is most of a simulation's
    time on a path that doubles back on itself.

    >>> import numpy as np
    >>> from shapely.geometry import box
    >>> from cnclab.simulation.pixel import Stock
    >>> xs = np.arange(-4, 34, 0.1)
    >>> df = removal(Stock.from_polygon(box(0, 0, 30, 10), 0.05), np.c_[xs, np.full_like(xs, 11.5)], 3, 3, 255)
    >>> round(float(df.mrr_mm3_min[100:300].mean()), -1)      # a_p * a_e * v_f = 3*1.5*255
    1150.0
    """
    import pandas as pd

    P, r, _, ds = _path_steps(centres, tool_radius, a_p, feed_mm_min)
    rem = np.empty(len(P))
    if not (resolve_backend(backend) == "numba" and stock._plain() and stock._removed_compiled(P, r, rem)):
        rem = simulate(stock, P, r, a_p, feed_mm_min, backend=backend)["removed_mm2"].to_numpy()
    return pd.DataFrame({"s": np.cumsum(ds), "ds": ds, "removed_mm2": rem,
                         "mrr_mm3_min": material_removal_rate(rem, ds, a_p, feed_mm_min)})


def simulate_runs(stock: StockBase, centres, rapid, tool_radius, a_p, feed_mm_min, **kwargs):
    """:func:`simulate` a path that contains rapid moves, on one stock, in path order.

    ``rapid[i]`` True means point i is reached by a rapid (the tool is lifted clear of the stock):
    each run of points from one rapid landing to the next is simulated on its own (runs of fewer
    than 2 points cut nothing and are skipped); keyword arguments go to :func:`simulate`.
    Returns one DataFrame: the columns of :func:`simulate` for every simulated point plus
    ``point`` (its index into ``centres``) and ``plunge`` (True at the first point of each run,
    where the tool comes down onto the path).

    >>> import numpy as np
    >>> from shapely.geometry import box
    >>> from cnclab.simulation.dixel import Stock
    >>> P = np.c_[np.r_[np.arange(0, 10, 0.5), np.arange(0, 10, 0.5)], np.r_[np.zeros(20), np.full(20, 6.0)]]
    >>> T = simulate_runs(Stock.from_polygon(box(0, -5, 10, 10), 0.1), P, np.arange(40) == 20, 2, 1, 100)
    >>> int(T.plunge.sum()), int(T.point.iloc[20])               # two runs; the second starts at point 20
    (2, 20)
    """
    import pandas as pd

    P = np.asarray(centres, dtype=float)
    rapid = np.asarray(rapid, dtype=bool)
    if rapid.shape != (len(P),):
        raise ValueError(f"rapid must have one flag per point ({len(P)}), got shape {rapid.shape}")
    starts = np.r_[0, np.flatnonzero(rapid[1:]) + 1]
    stops = np.r_[starts[1:], len(P)]
    tables = []
    for a, b in zip(starts, stops):
        if b - a < 2:
            continue
        df = simulate(stock, P[a:b], tool_radius, a_p, feed_mm_min, **kwargs)
        df["point"] = np.arange(a, b)
        df["plunge"] = np.arange(a, b) == a
        tables.append(df)
    if not tables:
        raise ValueError("the path has no run of >= 2 points between rapids: nothing to simulate")
    return pd.concat(tables, ignore_index=True)


def _simulate_loop(stock, P, d, ds, s_cum, r, lag, f_z, out, kw, opts: SimOptions):
    """The reference loop of :func:`simulate` (a Python loop over the steps calling
    ``stock.engagement(..., **kw)`` and ``stock.cut_disk(..., **kw)``): fills the arrays ``out``;
    ``opts`` gives front_only, the feed-direction rule and the lag rule."""
    eng, ent, ext, rem, hmax, havg = out
    central, front_only, hold_front = opts.feed_direction == "central", opts.front_only, opts.lag_rule == "front"
    n = len(P)
    s_l, ds_l = s_cum.tolist(), ds.tolist()          # Python floats: cheap scalar access per step
    fdir = d[0]
    k = 0                                  # next disk to cut
    for i in range(n):
        if i > 0 and ds_l[i] > 0:
            fdir = d[i - 1]
        fd = fdir
        if central and 0 < i < n - 1:
            v = P[i + 1] - P[i - 1]
            if v[0] != 0 or v[1] != 0:
                fd = v
        m = k
        if hold_front and (fd[0] != 0 or fd[1] != 0):
            for q in range(i - 1, k - 1, -1):
                if _reaches_front(P[q, 0], P[q, 1], P[i, 0], P[i, 1], fd[0], fd[1], r, 1e-9):
                    m = q + 1
                    break
        while k < i and (s_l[i] - s_l[k] > lag or k < m):
            rem[k] = stock.cut_disk(P[k], r, **kw)
            k += 1
        if fd[0] != 0 or fd[1] != 0:
            e = stock.engagement(P[i], r, fd, front_only=front_only, **kw)
            eng[i], ent[i], ext[i] = e.angle_deg, e.entry_deg, e.exit_deg
            if f_z is not None:
                hmax[i], havg[i] = chip_thickness(e.intervals, float(f_z))
        else:
            eng[i] = ent[i] = ext[i] = np.nan
    while k < n:
        rem[k] = stock.cut_disk(P[k], r, **kw)
        k += 1


def _reaches_front(qx, qy, px, py, g0, g1, r, margin) -> bool:
    """Python twin of :func:`._kernels.reaches_front` (the reference loop's rule ``lag_rule="front"``)."""
    vx, vy = qx - px, qy - py
    rho = math.hypot(vx, vy)
    if rho < 1e-12:
        return False
    gn = math.hypot(g0, g1)
    fx, fy = g0 / gn, g1 / gn
    if vx * fx + vy * fy > 0.0:
        return rho < 2.0 * r
    else:
        nx, ny = -fy * r, fx * r
        dist = min(math.hypot(vx - nx, vy - ny), math.hypot(vx + nx, vy + ny))
    return dist < r - margin
