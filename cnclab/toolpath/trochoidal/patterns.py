"""Trochoidal slot patterns of Jacsó (2021) §3.4 and their evaluation: circular trochoid, cycloid,
the dixel slot evaluation and the admissible-step bisection (see :mod:`cnclab.toolpath.trochoidal`).

>>> p = circular_trochoid(step=1.0, width=12.0, tool_radius=3.0, n_periods=2, ds=0.1)
>>> round(length_per_period(p), 2)          # 2 pi R + step = 2 pi 3 + 1
19.85
"""
from __future__ import annotations

import math

import numpy as np
from shapely.geometry import box

from ...simulation import dixel
from ..evaluate import Evaluation, weighted_percentile
from ..path import ToolPath
from . import _common

__all__ = ["period_index", "pattern_kinds", "pattern_lengths", "length_per_period", "circular_trochoid", "cycloid", "slot_limit", "evaluate_pattern", "admissible_step", "max_engagement_circle_front", "circle_front_step"]


def slot_limit(width, tool_radius) -> float:
    """Largest |y| (mm) of the tool centre in a slot of width ``width`` (mm): W/2 - r.

    Raises ValueError naming ``width`` if the slot is not wider than the tool diameter 2r.

    >>> slot_limit(12.0, 3.0)
    3.0
    """
    W, r = _common.positive("width", width), _common.positive("tool_radius", tool_radius)
    if W <= 2 * r:
        raise ValueError(f"width must exceed the tool diameter 2*tool_radius = {2 * r} mm for a "
                         f"trochoidal slot, got {W}")
    return 0.5 * W - r


def period_index(path: ToolPath) -> np.ndarray:
    """Period index of every point of a pattern (from its ``"period k"`` tags)."""
    return np.array([int(str(t).split(":")[0].split(" ")[1]) for t in path.tag])


def pattern_kinds(path: ToolPath) -> np.ndarray:
    """cut / roll-in / roll-out / link per point of a pattern or period."""
    roll = np.array([str(t).split(":")[1] if ":" in str(t) else "" for t in path.tag], dtype=object)
    return np.where(path.is_kind("link"), "link", np.where(roll != "", roll, "cut")).astype(object)


def pattern_lengths(path: ToolPath, periods=None) -> dict:
    """Cutting and linking length (mm) of a pattern, over all periods or the given period indices."""
    ds = path.segment_lengths()
    m = np.ones(len(ds), bool) if periods is None else np.isin(period_index(path), list(periods))
    link = path.is_kind("link")
    return {"cut": float(ds[m & ~link].sum()), "link": float(ds[m & link].sum())}


def length_per_period(path: ToolPath, k: int | None = None) -> float:
    """Path length (mm) of one period (default: the middle period)."""
    k = int(np.median(np.unique(period_index(path)))) if k is None else k
    L = pattern_lengths(path, [k])
    return L["cut"] + L["link"]


def circular_trochoid(step, width, tool_radius, n_periods, x0=0.0, ds=0.05, feed_mm_min=255.0,
                      link_feed_mm_min=None) -> ToolPath:
    """Circle-and-line trochoid: ccw circles of radius W/2 - r, centres at x0 + k*step (mm).

    Each period starts at the circle's rear point (angle pi), runs one full circle and moves
    straight by ``step`` to the rear point of the next circle (that transfer is flagged as link).
    ``ds``: sampling distance along the path (mm).
    """
    s = _common.positive("step", step)
    R = slot_limit(width, tool_radius)
    n = int(n_periods)
    if n < 1:
        raise ValueError(f"n_periods must be >= 1, got {n_periods!r}")
    m = max(int(math.ceil(2 * math.pi * R / ds)), 16)
    phi = math.pi + np.linspace(0.0, 2 * math.pi, m + 1)
    b = _common.pattern_builder(s, "circular")
    for k in range(n):
        cx = x0 + k * s
        circ = np.c_[cx + R * np.cos(phi), R * np.sin(phi)]
        _common.add_piece(b, circ[1:] if k > 0 else circ, "cut", k, feed_mm_min, link_feed_mm_min)
        ml = max(int(math.ceil(s / ds)), 1)
        line = np.c_[cx - R + np.linspace(0, s, ml + 1)[1:], np.zeros(ml)]
        _common.add_piece(b, line, "link", k, feed_mm_min, link_feed_mm_min)
    return b.build()


def cycloid(step, width, tool_radius, n_periods, x0=0.0, ds=0.05, feed_mm_min=255.0) -> ToolPath:
    """Prolate-trochoid path x = x0 + s phi/(2 pi) + R cos(phi), y = R sin(phi), R = W/2 - r (mm).

    One period per 2 pi, starting at the rear point phi = pi (so the pattern is comparable with
    :func:`circular_trochoid`); no linking moves (the rear half is an air cut at feed).
    """
    s = _common.positive("step", step)
    R = slot_limit(width, tool_radius)
    n = int(n_periods)
    if n < 1:
        raise ValueError(f"n_periods must be >= 1, got {n_periods!r}")
    m = max(int(math.ceil((2 * math.pi * R + s) / ds)), 16)
    phi = math.pi + np.linspace(0.0, 2 * math.pi * n, n * m + 1)
    pts = np.c_[x0 + s * (phi - math.pi) / (2 * math.pi) + R * np.cos(phi), R * np.sin(phi)]
    per = np.minimum(((phi - math.pi) // (2 * math.pi)).astype(int), n - 1)
    return _common.pattern_path(pts, np.full(len(pts), "cut"), per, s, "cycloid", feed_mm_min)


def max_engagement_circle_front(step, width, tool_radius) -> float:
    """Exact engagement (deg) at the front point of a circular trochoid in steady state.

    The material ahead is bounded by the previous circle's envelope, a circle of radius R + r about
    the previous centre; the tool at the front point (distance d = R + step from it, feed along +y)
    engages psi in [0, alpha] with cos(alpha) = ((R + r)^2 - d^2 - r^2) / (2 d r).
    Used to check the simulator (the maximum over the period lies slightly after this point).

    >>> round(max_engagement_circle_front(circle_front_step(60.0, 12.0, 3.0), 12.0, 3.0), 6)
    60.0
    """
    R = slot_limit(width, tool_radius)
    r, s = float(tool_radius), _common.positive("step", step)
    d = R + s
    c = ((R + r) ** 2 - d * d - r * r) / (2 * d * r)
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


def circle_front_step(theta_deg, width, tool_radius) -> float:
    """Inverse of :func:`max_engagement_circle_front`: the step (mm) giving ``theta_deg`` at the front point.

    d = -r cos(theta) + sqrt((R + r)^2 - r^2 sin^2(theta)), step = d - R.

    >>> round(max_engagement_circle_front(circle_front_step(45.0, 15.0, 3.0), 15.0, 3.0), 9)
    45.0
    """
    R = slot_limit(width, tool_radius)
    r = float(tool_radius)
    th = math.radians(theta_deg)
    d = -r * math.cos(th) + math.sqrt((R + r) ** 2 - (r * math.sin(th)) ** 2)
    return d - R


# ---------------------------------------------------------------------------------------------
# simulation-based evaluation
# ---------------------------------------------------------------------------------------------
def _slot_stock(path: ToolPath, width, resolution_mm, x_start=0.0):
    x_end = float(path.xyz[:, 0].max()) + 4 * float(width)
    return dixel.Stock.from_polygon(box(x_start, -0.5 * width, x_end, 0.5 * width), resolution_mm)


def evaluate_pattern(path: ToolPath, width, tool_radius, resolution_mm=0.05, a_p=3.0,
                     feed_mm_min=255.0, link_feed_mm_min=None, steady_periods=None, stock=None):
    """Cut ``path`` through a slot stock (material x >= 0) with the dixel simulator; steady-state metrics.

    Returns ``(table, metrics)``: the per-step DataFrame of :func:`cnclab.simulation.dixel.simulate`
    with ``period`` and ``link`` columns, and an :class:`~cnclab.toolpath.evaluate.Evaluation` over
    the ``steady_periods`` (default: all but the first two and the last): the engagement p50 / p95 /
    max over the cutting moves (deg, length-weighted), cut and link lengths and times over those
    periods; the pattern's own metrics in ``metrics.extra`` (read as ``metrics["step_mm"]``):
    ``step_mm``, ``length_per_period_mm``,
    ``length_per_mm_slot`` (path mm per mm of slot), ``cut_mm``/``link_mm`` per period,
    ``time_per_period_s``, ``mrr_avg_mm3_min`` (= a_p W step / time per period, the geometric
    steady-state removal), ``mrr_avg_sim_mm3_min`` (simulated removed area over the same time),
    ``link_removed_mm2`` (material cut by linking moves) and ``engagement_max_<kind>_deg`` for the
    segment kinds roll-in, cut, roll-out and link (NaN for a kind the pattern lacks; the names of
    :class:`~cnclab.toolpath.evaluate.Evaluation`). On the link: for the constant-engagement pattern the link's final approach along the wall is the roll-in into the
    corner left by the previous period and does cut (see the notebook discussion).
    Linking moves run at ``link_feed_mm_min`` (default: the cutting feed).
    """
    r = _common.positive("tool_radius", tool_radius)
    W = _common.positive("width", width)
    st = _slot_stock(path, W, resolution_mm) if stock is None else stock
    period, link, kinds, step = period_index(path), path.is_kind("link"), pattern_kinds(path), path.info["step"]
    df = dixel.simulate(st, path.xyz[:, :2], r, a_p, feed_mm_min)
    df["period"] = period
    df["link"] = link
    df["kind"] = kinds
    periods = np.unique(period)
    if steady_periods is None:
        steady_periods = periods[2:-1] if len(periods) > 3 else periods[-1:]
    m = np.isin(period, list(steady_periods))
    vlink = feed_mm_min if link_feed_mm_min is None else link_feed_mm_min
    n_p = len(steady_periods)
    cut = float(df.ds[m & ~link].sum()) / n_p
    lnk = float(df.ds[m & link].sum()) / n_p
    t_min = cut / feed_mm_min + lnk / vlink
    removed = float(df.removed_mm2[m].sum()) / n_p
    eng = df.engagement_deg.to_numpy()
    cutting = m & ~link
    extra = {
        "step_mm": step,
        "cut_mm": cut, "link_mm": lnk,
        "length_per_period_mm": cut + lnk,
        "length_per_mm_slot": (cut + lnk) / step,
        "time_per_period_s": 60.0 * t_min,
        "mrr_avg_mm3_min": a_p * W * step / t_min,
        "mrr_avg_sim_mm3_min": a_p * removed / t_min,
        "link_removed_mm2": float(df.removed_mm2[m & link].sum()) / n_p,
        "engaged_share": float(np.mean(eng[m] > 1.0)),
    }
    for name in ("roll-in", "cut", "roll-out", "link"):
        e = eng[m & (kinds == name)]
        extra[f"engagement_max_{name}_deg"] = float(np.nanmax(e)) if np.isfinite(e).any() else math.nan
    w = df.ds.to_numpy()[cutting]
    metrics = Evaluation.partial(
        engagement_p50_deg=weighted_percentile(eng[cutting], w, 50), engagement_p95_deg=weighted_percentile(eng[cutting], w, 95),
        engagement_max_deg=float(np.nanmax(eng[cutting])), cut_length_mm=cut * n_p, link_length_mm=lnk * n_p,
        time_cut_s=60.0 * cut * n_p / feed_mm_min, time_link_s=60.0 * lnk * n_p / vlink,
        time_total_s=60.0 * t_min * n_p, resolution_mm=float(resolution_mm), extra=extra)
    return df, metrics


def admissible_step(pattern, theta_max_deg, width, tool_radius, resolution_mm=0.05, n_periods=5,
                    tol_mm=0.01, s_max=None):
    """Largest trochoidal step (mm) of ``pattern`` ("circular" or "cycloid") whose simulated
    steady-state maximum engagement does not exceed ``theta_max_deg`` (bisection on the step).

    The maximum engagement grows monotonically with the step (the material ahead grows).
    """
    gen = {"circular": circular_trochoid, "cycloid": cycloid}.get(pattern)
    if gen is None:
        raise ValueError(f"pattern must be 'circular' or 'cycloid', got {pattern!r}")
    if not 0 < theta_max_deg <= 180:
        raise ValueError(f"theta_max_deg must be in (0, 180], got {theta_max_deg!r}")
    r = _common.positive("tool_radius", tool_radius)
    slot_limit(width, r)
    ds = resolution_mm

    def emax(s):
        p = gen(s, width, r, n_periods, ds=ds)
        return evaluate_pattern(p, width, r, resolution_mm)[1]["engagement_max_deg"]

    # bracket: the exact front-point step of the circle (a lower bound of the maximum engagement)
    s_front = circle_front_step(theta_max_deg, width, r)
    return _common.largest_step(emax, theta_max_deg, 0.5 * s_front, 1.5 * s_front if s_max is None else s_max, tol_mm)
