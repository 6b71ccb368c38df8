"""The narrow regions at one level (the second half of issue 29 item 5; the regions, their axis and
the pattern: :mod:`.narrow`): the order in which the level planner meets them
(:class:`LevelRegions`, :func:`next_region`, :func:`close`), the cut of one (:func:`cut_region`:
entry, the trochoid's moves by :func:`emit_trochoid`) and the closed loop of its periods
(:class:`PeriodCheck`). See :mod:`.narrow`'s docstring for the method. Units: mm, deg, mm/min.
"""
from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.geometry import LineString, Point

from ..helix import helix_entry, helix_ring
from .control import GUARD_LEVEL, replay
from .links import rapid_legs
from .narrow import MOUTH_CANDIDATES, NarrowRegion, axis_trochoid, join_axis, spiral_out
from .stock import capsule_free, cut_disc, raster

__all__ = ["PeriodCheck", "emit_trochoid", "cut_region", "LevelRegions", "next_region", "close"]


class PeriodCheck:
    """The closed loop of a region's trochoid (``axis_trochoid(check=...)``): each period is replayed
    (:func:`cnclab.toolpath.adaptive.control.replay`, the level planner's engagement model) on a
    working copy of the planning stock about the region -- with the material hidden for the other
    narrow regions still pending put back (the evaluator sees it) -- and refused where the engagement
    of any of its points (the cuts and the returns through the slot) exceeds ``limit_rad``; an
    accepted period is cut into the copy. The open-loop pattern is made for a straight slot of the
    narrowest width nearby: at a corner of a channel, a
    junction with another channel or the mouth of a wider area the material beside or ahead of it
    is more (fresh letter-shaped pockets, D 3-12 mm, channels 1.1-1.8 D: up to theta + 132 deg
    before this check). ``refused``: how many periods were laid again or ended the trochoid."""

    def __init__(self, lv, reg: NarrowRegion, limit_rad: float, start, hole=None):
        """``start`` (2,) mm: where the tool stands when the first period begins (None: at the first
        period's first point -- after an entry's spiral out, whose end the pattern's start joins);
        ``hole``: None, or (centre (2,), radius mm) of the entry's hole about the axis start, cut
        before the periods."""
        g = lv.g
        self.g, self.r, self.lag, self.n_samp, self.limit = g, lv.r, lv.lag, lv.n_samp, float(limit_rad)
        win = g.window(reg.polygon.buffer(lv.r + 3.0 * g.h).bounds)
        self.j0, self.i0 = win[0].start, win[1].start
        st = getattr(lv, "narrow_state", None)
        M = g.M if st is None else st.stock_with_hidden(range(len(st.masks)))
        self.M = M[win].copy()
        if hole is not None:
            cut_disc(self.M, g.x0 + self.i0 * g.h, g.y0 + self.j0 * g.h, g.h, float(hole[0][0]), float(hole[0][1]),
                     float(hole[1]), np.nan, np.nan)
        self.start = None if start is None else np.asarray(start, float)
        # the first period after an entry's spiral out (``hole``) is the transition from the round hole
        # to the pattern: held to the limit plus the margin again (measured: theta + 5.2 deg in the
        # model at the closed end of an E's bar, D 8 mm; refused, the region is left whole to the passes)
        self.first_slack = (self.limit - math.radians(lv.theta_deg)) if hole is not None else 0.0
        self.refused = 0

    def __call__(self, Q, cutting, first=False) -> bool:
        """``axis_trochoid``'s check of one period (``cutting``, its cut flags, is part of that protocol:
        every point is held to the limit here, the returns through the slot too)."""
        if first and self.start is not None:
            Q = np.vstack([self.start[None], Q])
        g, pad = self.g, self.r + 2.0 * self.g.h
        lo, hi = Q.min(axis=0) - pad, Q.max(axis=0) + pad
        wj, wi = g.window((lo[0], lo[1], hi[0], hi[1]))      # grid pixels, then within the copy
        b0, b1 = max(wj.start - self.j0, 0), min(wj.stop - self.j0, self.M.shape[0])
        a0, a1 = max(wi.start - self.i0, 0), min(wi.stop - self.i0, self.M.shape[1])
        if a1 <= a0 or b1 <= b0:
            return True
        sub = np.ascontiguousarray(self.M[b0:b1, a0:a1])
        E, _ = replay(sub, g.x0 + (self.i0 + a0) * g.h, g.y0 + (self.j0 + b0) * g.h, g.h, self.r,
                      np.ascontiguousarray(Q, float), self.lag, self.n_samp, GUARD_LEVEL)
        # every point after the first (the tool's place before the period, measured already): a cut, or a
        # return through the slot that meets material where the slot is not straight (at a junction the
        # return of letter E 34:11, D 5 mm, theta 24, ended in the other bar: theta + 26.9 on a G1 at
        # the link feed; session 18)
        if len(E) > 1 and float(E[1:].max()) > self.limit + (self.first_slack if first else 0.0):
            self.refused += 1
            return False
        self.M[b0:b1, a0:a1] = sub
        return True



def emit_trochoid(b, g, start, Q, K, feed, z, link_feed, tag):
    """Append the trochoid ``Q`` (m, 2) mm at height ``z`` to the builder ``b`` from ``start`` (2,),
    cutting the planning stocks of the grid ``g`` as it goes: every run of cutting moves is cut into
    ``g``; every run of returns (``K == "link"``) then becomes one G0 chord marked cleared where the
    rapid stock proves it (:func:`~.links.rapid_legs`: no material within r + h/sqrt(2) of it, with
    short feed legs off the cut boundary at its ends: how the level planner's links are proven),
    else feed links at ``link_feed`` (mm/min).
    ``feed``: per point, mm/min (NaN on links)."""
    link = np.asarray(K) == "link"
    edges = np.flatnonzero(np.diff(link.astype(int))) + 1
    bounds = np.r_[0, edges, len(Q)]
    prev = np.asarray(start, float)
    for a, e in zip(bounds[:-1], bounds[1:]):
        run = Q[a:e]
        if not link[a]:
            b.cut(run, np.round(feed[a:e], 1), z=z, tag=tag)
            g.cut_path(np.vstack([prev[None], run]))
        else:
            legs = rapid_legs(g, prev, run[-1]) if len(run) > 1 else None
            if legs is None:
                b.link(run, link_feed, z=z, tag=tag)
                g.cut_path(np.vstack([prev[None], run]))
            else:
                p1, q1 = legs
                if p1 is not None:
                    b.link([p1], link_feed, z=z, tag=tag)
                b.rapid([q1], z=z, tag="cleared: trochoid return through the cleared slot", cleared=True)
                if q1[0] != run[-1, 0] or q1[1] != run[-1, 1]:
                    b.link(run[-1:], link_feed, z=z, tag=tag)
        prev = run[-1]


def _builder(lv):
    """The level planner's :class:`ToolPathBuilder` (``lv.b``)."""
    return lv.b


def cut_region(lv, reg: NarrowRegion, from_cleared: bool = False) -> bool:
    """Cut the narrow region ``reg`` at the level of the planner ``lv``
    (:class:`cnclab.toolpath.adaptive.planner._Level`): the trochoid along the axis from its start,
    the planning stock cut along it; the tool stays down at the trochoid's end (``lv.cur``).
    ``from_cleared``: the tool stands at the axis start, reached through cleared area (the level
    planner's link), and the trochoid starts there; else it retracts, enters by a helix at the axis
    start (into material) and spirals out to the slot's width. False (nothing emitted) when the axis
    start has no room for a helix of ``prm.helix_min_mm`` or the pattern of its first width class
    would crawl (step below ``MIN_STEP_FRAC`` a_e): the region is left to the level planner."""
    prm, r, h = lv.prm, lv.r, lv.h
    c_start = float(reg.radius[0])      # the hole opened to the half-width c: the pattern swings to c
    rho = min(prm.helix_radius_frac * r, prm.helix_room_frac * float(reg.radius[0]) - h)
    if not from_cleared and rho < prm.helix_min_mm:
        return False
    s_end = reg.length + (float(reg.radius[-1]) - h if reg.dead[1] else 0.0)
    vmax = float(getattr(getattr(lv, "job", None), "v_fmax", lv.feed_mm_min))
    chk = None
    if prm.narrow_check_margin_deg is not None:
        c0 = reg.axis[0]
        chk = PeriodCheck(lv, reg, math.radians(lv.theta_deg + prm.narrow_check_margin_deg),
                          lv.cur if from_cleared else None, None if from_cleared else (c0, c_start + r))
    Q, K, F, steps, n_out = axis_trochoid(reg, lv.allowed, r, lv.theta_deg, h, s_end=s_end,
                                          hole_mm=0.0 if from_cleared else c_start, vmax_ratio=vmax / lv.feed_mm_min,
                                          check=chk)
    if len(Q) == 0:
        return False
    b = _builder(lv)
    c0 = reg.axis[0]
    if from_cleared:
        p0 = np.array(lv.cur, float)
    else:
        lv.retract()
        p0 = (c0[0] + rho, c0[1])
        lv.approach(p0)
        b.plunge(p0, lv.z_prev, lv.feed_mm_min, tag="air")
        m_helix = b.mark()
        pe = helix_entry(b, c0, rho, lv.z_prev, lv.z, lv.feed_mm_min, lv.helix_angle_deg, tag="entry: narrow region")
        # the rapid stock along the written floor circle's chords (as entries.enter)
        lv.g.cut_path(helix_ring(c0, rho, 64), lv.written_floor(m_helix))
        # the hole opened to the slot's width: a spiral out to radius c at the engagement theta (each
        # turn gains what the wall of the last one leaves at theta: narrow.spiral_out), then a circle
        S = spiral_out(c0, rho, c_start, r * (1 - math.cos(math.radians(lv.theta_deg))), 2 * h,
                       start_rad=math.atan2(pe[1] - c0[1], pe[0] - c0[0]), tool_r=r)
        S[0] = pe
        b.cut(S[1:], lv.feed_mm_min, z=lv.z, tag="entry: narrow region, spiral out to the slot width")
        lv.g.cut_path(S)
        p0 = S[-1]
        lv.stats["entries"] += 1
    emit_trochoid(b, lv.g, np.asarray(p0, float), Q, K, F * lv.feed_mm_min, lv.z, lv.link_feed_mm_min,
                  f"narrow region {reg.index}: Thesis IV trochoid")
    lv.cur = (float(Q[-1, 0]), float(Q[-1, 1]))
    lv.stats["narrow_trochoids"] = lv.stats.get("narrow_trochoids", 0) + 1
    ended = ""
    if chk is not None and chk.refused:
        ended = (f", {chk.refused} period(s) laid closer or refused where the engagement would exceed theta + "
                 f"{prm.narrow_check_margin_deg:g} deg")
        d_end = float(np.hypot(*(Q[-1] - reg.axis[-1])))
        if d_end > 2.0 * r:
            ended += f"; ended at ({Q[-1, 0]:.1f}, {Q[-1, 1]:.1f}), the rest left to the passes"
    lv.narrow_done.append(reg.describe(r) + (" from cleared area" if from_cleared else " from a helix")
                          + f", steps {', '.join(f'{s_:.3f}' for s_ in steps)} mm" + ended)
    return True


def _leg_fits(allowed, p, q, c) -> bool:
    """The straight leg from ``p`` to ``q`` (mm) with a band of half-width ``c`` (mm) about it lies
    inside the tool-centre region ``allowed`` (the trochoid's periods along it fit unclamped)."""
    leg = LineString([p, q]) if float(np.hypot(*(np.asarray(p) - np.asarray(q)))) > 1e-9 else Point(*p)
    return bool(allowed.contains(leg.buffer(max(c, 0.0), quad_segs=8)))


class LevelRegions:
    """The narrow regions of one level while the level planner runs (see :func:`next_region`).

    On creation every region is taken out of the planner's view: its tool-centre pixels leave the
    grid's tool-centre mask (the passes cannot enter it) and the material that only tool centres
    inside it can reach (farther than r from the rest of the region) leaves the planning stock
    (no pass, entry or link is drawn to it); the finish parts that hold it wait. A region is put
    back just before its trochoid cuts it."""

    def __init__(self, lv, regions):
        g = lv.g
        self.lv, self.pending, self.parked = lv, list(regions), []
        self.masks, self.saved = [], []
        if not self.pending:
            return
        self.A0 = g.A.copy()
        narrow_all = shapely.union_all([q.polygon.buffer(g.h) for q in self.pending])
        rest = lv.allowed.difference(narrow_all)
        # hidden: material farther than r + hide_margin_h h from the rest (a pass's tool centre lies up to
        # a pixel's half-diagonal inside the raster ``am`` of a region, and a thin crescent of hidden
        # material at its circle spans a wide arc: dwg_concave_hole theta + 14.8 deg at r)
        reach = rest.buffer(lv.r + lv.prm.narrow_hide_margin_h * g.h) if not rest.is_empty else shapely.Polygon()
        for reg in self.pending:
            am = raster(reg.polygon.buffer(g.h), g.x0, g.y0, g.h, g.nx, g.ny) > 0
            mm = raster(reg.polygon.buffer(lv.r + 2 * g.h).difference(reach), g.x0, g.y0, g.h, g.nx, g.ny) > 0
            self.masks.append((am, mm))
            self.saved.append(g.M[mm].copy())
        for am, mm in self.masks:
            g.A[am] = False
            g.M[mm] = 0
        self._refresh()
        self.park()

    def _refresh(self):
        g = self.lv.g
        g.Ac = g.coarse(g.A).min(axis=(1, 3)) > 0
        g.touch(np.array([[g.x0, g.y0], [g.x0 + g.nx * g.h, g.y0 + g.ny * g.h]]), 0.0)

    def park(self):
        """Hold back the finish parts that meet a pending region (their laps would cut its hidden
        material); give back the others."""
        lv = self.lv
        parts = list(lv.todo_parts) + self.parked
        polys = [q.polygon for q in self.pending]
        self.parked = [p for p in parts if any(p.intersects(q) for q in polys)]
        lv.todo_parts[:] = [p for p in parts if not any(p.intersects(q) for q in polys)]

    def restore(self, k):
        """Put region ``k`` (index into ``pending``) back into the planner's view and drop it."""
        g = self.lv.g
        am, mm = self.masks.pop(k)
        g.A[am] = self.A0[am]
        g.M[mm] = np.maximum(g.M[mm], self.saved.pop(k))
        self._refresh()
        return self.pending.pop(k)

    def open_mouth_pending(self) -> bool:
        """Whether a pending region has an open end (a mouth the planner must clear completely,
        slivers too, for :meth:`reachable_mouth` to find its swing free)."""
        return any(not all(reg.dead) for reg in self.pending)

    def stock_with_hidden(self, ks):
        """A copy of the planning stock with the material hidden for the pending regions ``ks``
        (indices into ``pending``) put back: what the evaluator sees there. A branch's mouth lies at
        the trunk's slot, next to its own hidden material (:meth:`reachable_mouth`); a trochoid's
        periods meet the other pending regions' (:class:`PeriodCheck`)."""
        M = self.lv.g.M.copy()
        for k in ks:
            mm = self.masks[k][1]
            M[mm] = np.maximum(M[mm], self.saved[k])
        return M

    def reachable_mouth(self):
        """(k, reversed?, cell, point) of a pending region whose open end the tool reaches through
        cleared area: ``point`` the centre of the free coarse cell (its tool disc free of material)
        nearest to that end of the axis within 2 r, reached by :meth:`Grid.route`; the shortest
        route first. None when no open end is reachable."""
        lv, g = self.lv, self.lv.g
        if lv.cur is None:
            return None
        D, Ac = g.free_field()
        free = Ac & (D >= lv.r_free)
        best = None
        for k, reg in enumerate(self.pending):
            for rev, (end, dead) in enumerate(((reg.axis[0], reg.dead[0]), (reg.axis[-1], reg.dead[1]))):
                if dead:
                    continue
                j0, i0 = g.cell(*end)
                w = int(math.ceil(3 * lv.r / g.hc))
                J, I = np.nonzero(free[max(j0 - w, 0):j0 + w + 1, max(i0 - w, 0):i0 + w + 1])
                if len(J) == 0:
                    continue
                J, I = J + max(j0 - w, 0), I + max(i0 - w, 0)
                C = np.c_[g.x0 + (I + 0.5) * g.hc, g.y0 + (J + 0.5) * g.hc]
                # the nearest from which the first periods' returns, swinging c to either side across
                # the axis, meet no material (the capsule of radius r + mouth_capsule_margin_h h about that swing is free)
                ax = reg.axis if rev == 0 else reg.axis[::-1]
                t = ax[min(3, len(ax) - 1)] - ax[0]
                n = np.array([-t[1], t[0]]) / max(float(np.hypot(*t)), 1e-12)
                sw = float(reg.radius[0 if rev == 0 else -1]) * n
                # ... and the leg from it to the axis end, where the pattern swings c to either side
                # too, lies inside the tool-centre region (else the pattern is clamped onto its boundary
                # along the leg and cuts as a slot: 124-152 deg at theta 60 where a leg ran 4 mm along an
                # island's edge through uncleared material)
                c_end = float(reg.radius[0 if rev == 0 else -1])
                near = np.argsort(np.hypot(*(C - end).T))[:MOUTH_CANDIDATES]
                Mk = self.stock_with_hidden([k]) if reg.branch else g.M
                m = next((int(q) for q in near
                          if capsule_free(Mk, g.x0, g.y0, g.h, C[q, 0] - sw[0], C[q, 1] - sw[1], C[q, 0] + sw[0],
                                          C[q, 1] + sw[1], lv.r + lv.prm.mouth_capsule_margin_h * g.h)
                          and _leg_fits(lv.allowed, C[q], end, c_end - 2 * g.h)), None)
                if m is None:
                    continue
                route = g.route(lv.cur, lv.r_free, -np.inf, None, (int(J[m]), int(I[m])))
                if route is None or isinstance(route, str):
                    continue
                if best is None or len(route) < best[4]:
                    best = (k, bool(rev), (int(J[m]), int(I[m])), C[m], len(route))
        return None if best is None else best[:4]


def next_region(lv, banned=None) -> bool:
    """The level planner has nothing left within reach through cleared area: cut the next narrow
    region (True), or leave it to the planner (False). A region whose open end (a mouth onto the
    cleared area) the tool reaches through cleared area is entered there by the planner's link;
    else, once the planner has no place left to enter (no material within reach of a free cell of
    its tool-centre region, ``banned`` cells aside), a region is entered by a helix at its axis start
    (a closed end first); a region without room for that helix is handed back to the planner."""
    st = getattr(lv, "narrow_state", None)
    if st is None or not st.pending:
        return False
    hit = st.reachable_mouth()
    if hit is not None:
        k, rev, cell, pt = hit
        reg = st.pending[k].reversed() if rev else st.pending[k]
        if lv.link_to(lv.r_free, -np.inf, None, cell, end_xy=tuple(pt)) is not None:
            st.restore(k)
            # the axis starts at the free point the link reached (its tool disc is free of material)
            reg = join_axis(reg, lv.cur)
            cut_region(lv, reg, from_cleared=True)
            st.park()
            return True
    D, Ac = lv.g.free_field()
    need = Ac & (D < lv.r)
    if banned is not None:
        need &= ~banned
    if need.any():
        return False
    while st.pending:
        k = next((i for i, q in enumerate(st.pending) if q.dead[0]), 0)
        done = cut_region(lv, st.restore(k))
        st.park()
        if done:
            return True
        # no room for its helix, or its pattern would crawl: the region is back in the planner's
        # view, and the planner enters it its own way (None: that place is banned, try again)
        if lv.enter(banned) is not False:
            return True
    return False


def close(lv) -> None:
    """End of the level's passes: any region still pending goes back into the planner's view, and
    every parked finish part back to the planner's list."""
    st = getattr(lv, "narrow_state", None)
    if st is None:
        return
    while st.pending:
        st.restore(0)
    st.park()
