"""The planner (:func:`adaptive_clearing`, :func:`plan_job`): entries, clearing passes, links,
remnant sweeps and the wall-following finish on one level at a time (see the package docstring
for the loop). Units: mm, deg, mm/min.
"""
from __future__ import annotations

import math
import time

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Point, Polygon
from shapely.geometry.polygon import orient

from ..path import KINDS, ToolPath, ToolPathBuilder, resample_polyline
from . import corners, entries, finish, narrow, narrow_level
from .entries import PlanningError
from .grid import Grid, PassStep
from .params import AdaptiveParams
from .links import boundary_gradient, rapid_legs, rapid_pieces, shortcut, solid_within, upstream_end
from .stock import capsule_free_of, component_discs, label8, segment_inside

_RAPID, _PLUNGE = KINDS.index("rapid"), KINDS.index("plunge")
_UNTRIED = object()    # a chord whose rapid_legs were not computed yet (merge_rapid_chords)


class _Level:
    """One level of the plan: the state the loop shares (the grid, the tool position ``cur``, the
    entries made, the parts still to finish) and the steps of the loop as methods (see the package
    docstring). ``cfg``: the planner's settings and its :class:`ToolPathBuilder` ``b``
    (:func:`adaptive_clearing`): every move goes to ``b``, with its ``cleared`` flag (the planner's
    proof that the move runs through air or cleared area: the writer's licence for a G0 below the
    clearance plane); tags are free text for people."""

    def __init__(self, cfg, lev, z, z_prev, g):
        self.__dict__.update(cfg)
        self.lev, self.z, self.z_prev, self.g = lev, z, z_prev, g
        self.cur = None   # current xy at depth (None: at clearance)
        self.entered = set()   # coarse cells of the entries at this level
        self.todo_parts = []
        self.r_free = np.nan
        self._wall = None      # the tool-centre limit's boundary (wall_sliver), made when first needed
        self._remnant_cache = None     # (stock, its components) of the last sweep_remnant (_remnants)
        self._link_tail = None  # the last link's final G0 (join_link_to_pass)
        self._virtual = None    # (start of a pass that emitted nothing, its link rolled back; the tool's point then)
        self.mark0 = self.b.mark()     # the builder before the level's first move
        self._corners = None    # the level's CornerCheck (corner_check), made when first needed

    def corner_check(self):
        """The exact-stock check of the laps near the sharp corners (:class:`.corners.CornerCheck`),
        made when first asked; None when ``AdaptiveParams.corner_exact_cap_deg`` is None."""
        p = self.prm
        if p.corner_exact_cap_deg is None:
            return None
        if self._corners is None:
            pts = corners.sharp_points(self.allowed, p.corner_min_turn_deg, p.corner_window_frac * self.r)
            self._corners = corners.CornerCheck(self.pocket, pts, self.r, self.theta_deg + p.corner_exact_cap_deg,
                                                p.corner_reach_h * self.h, p.corner_screen_deg)
        return self._corners

    def corner_trim(self, P, removed, E, free):
        """The pass just run (``P``, ``removed`` mm^2, ``E``, ``free``) ended before its first point near a
        sharp corner over the exact-stock cap (:meth:`corner_check`), the stock rolled back and replayed
        without the rest; unchanged when none is."""
        chk = self.corner_check()
        k = None if chk is None else chk.first_over(self.b, self.mark0, self.z, P, E)
        if k is None:
            return P, removed, E, free
        self.stats["corner_cuts"] = self.stats.get("corner_cuts", 0) + 1
        self.g.rollback()
        m0 = float(self.g.M.sum())
        P = P[:k]
        E = self.g.replay(P, self.lag, self.n_samp) if len(P) > 1 else E[:1]
        return P, (m0 - float(self.g.M.sum())) * self.h * self.h, E, free[:k]

    def retract(self):
        if self.cur is not None:
            # straight up out of the tool's own cut: G0 (as FreeCAD lifts); the writer and the
            # static check accept a rapid only so below the clearance plane
            self.b.lift(self.clearance_z)
            self.stats["retracts"] += 1
            self.cur = self._virtual = None

    def approach(self, xy):
        """From the clearance plane to ``approach_above_mm`` above the level's top (the stock top or the
        floor the level above cleared) at ``xy`` (mm; :meth:`ToolPathBuilder.approach`): air; the entry
        at feed follows."""
        self.b.approach(xy, self.z_prev, self.clearance_z, above_mm=self.prm.approach_above_mm)

    def enter(self, banned=None):
        """An entry (:func:`.entries.enter`): True; False if none is left; None when banned."""
        return entries.enter(self, banned)

    def written_floor(self, mark):
        """The moves written since the builder ``mark`` at this level's z, as points every h/2 (n, 2) mm:
        where the tool truly ran at depth. An entry cuts the rapid stock along them (its floor
        circle's chords): discs on the exact circle would clear the sagitta outside the chords the
        tool runs, and prove G0s that graze it."""
        xyz = self.b.tail(mark)[0]
        return np.ascontiguousarray(resample_polyline(xyz[np.abs(xyz[:, 2] - self.z) < 1e-9, :2], 0.5 * self.h))

    def clearing_pass(self, heading, a_stop):
        """A clearing pass from the tool's point (:meth:`Grid.run_pass`) with ``a_stop`` mm of air, ended
        before a sharp corner where the exact stock reads it over the cap (:meth:`corner_trim`)."""
        P, removed, reason, E, free = self.g.run_pass(self.cur, heading, self.target, self.pass_step,
                                                      self.prm.pass_max_steps, a_stop, min(self.turn, self.ds / self.turn_radius),
                                                      1e18, self.guard_pass, self.air_rad, self.rapid_links)
        P, removed, E, free = self.corner_trim(P, removed, E, free)
        return P, removed, reason, E, free

    def link_to(self, r_free, band_hi=-np.inf, banned=None, cell=(-1, -1), end_xy=None, route=None):
        """Link at depth through free cells to the nearest goal cell (:meth:`Grid.route`); its
        cell or None. ``end_xy``: the exact end point (in ``cell``, which need not lie inside the
        tool-centre region: its centre is never a point of the link). ``route``: that search's result
        from the tool's point, when the caller has it already (not searched again)."""
        if route is None:
            route = self.g.route(self.cur, r_free, band_hi, banned, cell)
        if isinstance(route, str):
            # no straight chord from here reaches a free cell inside the region (an island corner in
            # the way): retrace the tool's own path at this depth (inside the region, its material
            # removed) to the last point from which one does, as feed links
            pts, kinds, _ = self.b.tail(max(len(self.b) - self.prm.retrace_max_moves - 1, 0))
            n_back = 0
            while n_back < len(pts) - 1 and pts[-2 - n_back][2] == self.z and kinds[-1 - n_back] != _PLUNGE\
                    and n_back < self.prm.retrace_max_moves:
                n_back += 1
            for k in range(self.prm.retrace_stride, n_back + 1, self.prm.retrace_stride):
                p = pts[-1 - k]
                route = self.g.route((p[0], p[1]), r_free, band_hi, banned, cell)
                if not isinstance(route, str):
                    back = [pts[-1 - q] for q in range(1, k + 1)]
                    break
            if isinstance(route, str) or route is None:
                return None
            self.b.link(np.asarray(back)[:, :2], self.link_feed_mm_min, z=self.z)
            self.cur = (float(back[-1][0]), float(back[-1][1]))
        if route is None:
            return None
        D, Ac = self.g.free_field()
        R = np.asarray(route, float)
        cells = np.c_[self.g.x0 + (R[:, 1] + 0.5) * self.g.hc, self.g.y0 + (R[:, 0] + 0.5) * self.g.hc]
        # the route's first cell is the tool's own cell, or (the tool off the free set) the free cell a
        # straight chord inside the fine mask reaches (links._start_cell): that one is kept, a chord
        # past it to the next cell was never checked against the walls
        own = tuple(int(v) for v in R[0]) == self.g.cell(*self.cur)
        pts_r = np.vstack([np.array([self.cur], float), cells[1:] if (own and len(R) > 1) else cells])
        if end_xy is not None:
            pts_r[-1] = end_xy

        chords = pts_r[shortcut(np.ascontiguousarray(pts_r, float), D, Ac, float(r_free), int(cell[0]), int(cell[1]),
                                 float(self.g.x0), float(self.g.y0), float(self.g.hc), self.g.A, float(self.h))]
        known = [_UNTRIED] * len(chords)      # the rapid_legs of each chord, where merge_rapid_chords has them
        if self.rapid_links and len(chords) > 2:
            chords, known = self.merge_rapid_chords(chords)
        self._link_tail = None
        for n_q, q in enumerate(chords[1:], start=1):
            if math.hypot(q[0] - self.cur[0], q[1] - self.cur[1]) > 1e-9:
                legs = None if not self.rapid_links else \
                    (rapid_legs(self.g, self.cur, q) if known[n_q] is _UNTRIED else known[n_q])
                pieces = None
                # the link ends with one G0 into the pass start: join_link_to_pass may run it on to the
                # end of the pass's own first G0 run (its start, its first chord or not)
                tail = legs is not None and n_q == len(chords) - 1 and legs[1][0] == q[0] and legs[1][1] == q[1]
                # G0 at depth: no pixel of the rapid stock within r + h/sqrt(2) of the chord: the
                # chord's tool disc is truly swept (see Grid), sub-pixel slivers included; a chord
                # starting or ending on a cut boundary (a pass ends at the wall: its skin is tangent
                # there) gets a short feed leg off it (rapid_legs); a chord still not proven is G0
                # only where a stretch of it is (rapid_pieces), the rest at the link feed
                if legs is not None:
                    a, b = legs
                    pieces = ([] if a is None else [(a, False)]) + [(b, True)] + \
                        ([] if (b[0] == q[0] and b[1] == q[1]) else [(q, False)])
                elif self.rapid_links and self.prm.rapid_piece_min_mm > 0:
                    pieces = rapid_pieces(self.g, self.cur, q, self.prm.rapid_piece_min_mm)
                at = self.cur
                for e, fast in pieces or [(q, False)]:
                    if fast:
                        if tail:
                            # the builder mark and start point of this G0 itself: a feed leg before it
                            # stays (the join's proof is for the chord from the leg's end)
                            self._link_tail = (self.b.mark(), (float(at[0]), float(at[1])), n_q == 1 and legs[0] is None)
                        self.b.rapid([e[:2]], z=self.z, tag="cleared: link through cleared area", cleared=True)
                    else:
                        self.b.link([e[:2]], self.link_feed_mm_min, z=self.z)
                    at = e
                self.cur = (float(q[0]), float(q[1]))
        self.stats["links"] += 1
        self._virtual = None
        return route[-1]

    def join_link_to_pass(self, P, free):
        """Run the link's last G0 (``_link_tail``: builder mark, its start, whether the tool's own point)
        on to the end of the pass's first G0 run (the steps ``free`` from its start, proven while the
        pass ran) where that one chord is a proven G0 on the rapid stock before the pass (the grid's
        checkpoint) and stays in the fine mask: the corner at the pass start, a machine stop, goes.
        Returns the index k of the pass point the link now ends at (0: no join)."""
        tail, self._link_tail = self._link_tail, None
        if tail is None or not self.rapid_links or len(P) < 3 or not free[1]:
            return 0
        k = 1
        while k + 1 < len(P) - 1 and free[k + 1]:
            k += 1
        mark, s, own = tail
        g = self.g
        if not (segment_inside(g.A, g.x0, g.y0, self.h, s[0], s[1], P[k, 0], P[k, 1], 2.0 * self.h if own else 0.0)
                and g.rapid_free_at_checkpoint(s, P[k])):
            return 0
        self.b.rollback(mark)
        self.b.rapid([P[k]], z=self.z, tag="cleared: link through cleared area", cleared=True)
        return k

    def merge_rapid_chords(self, chords):
        """The chords of a link (m, 2) joined where one G0 is proven for the join (:func:`rapid_legs` on
        the rapid stock, feed legs off a cut boundary included) and stays in the fine tool-centre mask:
        from each kept point the farthest such; (the kept points (k, 2), per kept point the
        :func:`rapid_legs` of the chord ending there, ``_UNTRIED`` where not computed). The coarse free cells keep a chord r + 0.75 cells from
        material; proven on the pixels it runs straighter, and every corner it removes is a stop of the
        machine (a G0 chain's vertices are junctions of two rapids)."""
        g, h = self.g, self.h
        out, legs, i, n = [0], [None], 0, len(chords)
        while i < n - 1:
            j, lg = n - 1, _UNTRIED
            while j > i + 1:
                if segment_inside(g.A, g.x0, g.y0, h, chords[i][0], chords[i][1], chords[j][0], chords[j][1],
                                  2.0 * h if i == 0 else 0.0):
                    lg = rapid_legs(g, chords[i], chords[j])
                    if lg is not None:
                        break
                j -= 1
            out.append(j)
            legs.append(lg if j > i + 1 else _UNTRIED)
            i = j
        return chords[out], legs

    def next_start(self, banned):
        """Link at depth to the start of the next clearing pass (:meth:`link_to`): the nearest cell
        through cleared area whose tool disc touches material, outside ``banned``; (its cell, the
        pass's start heading (rad) or None: along the material boundary), or (None, None) when none
        is left (the loop then cuts a narrow region, sweeps a remnant, tries :meth:`rescue_start`
        and enters anew). During a rescue (``rescue_fails`` >= 0): :meth:`rescue_start`'s next start."""
        if self.rescue_fails >= 0:
            return self.rescue_start()
        band_hi = self.r_free + 1.5 * self.g.hc
        max_cells = int(self.prm.upstream_start_frac * self.r / self.g.hc)
        virtual = self.virtual
        if (max_cells > 0 or virtual is not None) and self.cur is not None:
            # after a pass that emitted nothing (its link rolled back): the start is sought from that
            # pass's start, as if the tool had gone there, and linked to from the tool's point
            route = self.g.route(self.cur if virtual is None else virtual, self.r_free, band_hi, banned)
            if route is None and virtual is not None:
                self.go_to_virtual(banned)
                return None, None
            if virtual is None and (route is None or isinstance(route, str)):
                # the search of the last line from the same point on the same stock: this answer
                self._virtual = None
                return (None if route is None else self.link_to(self.r_free, band_hi, banned, route=route)), None
            if route is not None and not isinstance(route, str):
                goal = tuple(int(v) for v in route[-1])
                if max_cells > 0:
                    D, Ac = self.g.free_field()
                    up = upstream_end(D, Ac, banned, float(self.r_free), float(band_hi), goal[0], goal[1], max_cells)
                    if up != goal:
                        end = self.link_to(self.r_free, -np.inf, banned, cell=up)
                        if end is not None:
                            return end, None
                if virtual is None:
                    return self.link_to(self.r_free, band_hi, banned, route=route), None
                end = self.link_to(self.r_free, -np.inf, banned, cell=goal)
                if end is not None:
                    return end, None
            self._virtual = None
        end = self.link_to(self.r_free, band_hi, banned)
        return end, None

    @property
    def virtual(self):
        """The start (x, y) mm of the last pass that emitted nothing, its link rolled back, while the tool
        is still where it was then (:meth:`next_start` seeks the next start from there); else None."""
        v = self._virtual
        return v[0] if v is not None and v[1] == self.cur else None

    def go_to_virtual(self, banned):
        """Link to ``virtual`` after all, when no start is left from there: what comes next (a remnant
        sweep, a narrow region, the second chance, a rescue, a finish before a lift) is chosen from the
        tool's point, and the plan stays the one the links through the idle starts gave."""
        v = self.virtual
        if v is not None:
            self._virtual = None
            self.link_to(self.r_free, -np.inf, banned, cell=self.g.cell(*v), end_xy=v)

    def rescue_start(self):
        """Before an entry (a lift): a pass start within the r-bans of failed passes, farther than
        ``failed_start_ban_frac`` r from every failed start (``banned_fine``), with solid material within
        ``rescue_reach_frac`` r (:func:`.links.solid_within`, at least a pass's minimum removal: not the
        wall skins along a cleared slot), where the tool-centre region is at least
        ``rescue_min_half_width_frac`` r half-wide, linked to at depth; its heading along that material, on the
        right. The end of a slot opening into a wider part: the passes from its upper corner head out
        of the region, the bans of r cover the slot end, and the far part took a helix and a lift. Up
        to ``rescue_max_fails`` failed passes in a row (``rescue_fails``: -1 outside a rescue), once
        between two passes that cut (``rescue_spent``); (cell, heading rad) or (None, None)."""
        if self.rescue_spent:
            self.go_to_virtual(self.banned_fine)
            return None, None
        band_hi = self.r_free + 1.5 * self.g.hc
        self.rescue_fails = max(self.rescue_fails, 0)
        min_solid = self.prm.pass_min_removed_rh * self.r * self.h
        rad = int(math.ceil(self.prm.failed_start_ban_frac * self.r / self.g.hc))
        while self.rescue_fails < self.prm.rescue_max_fails and self.cur is not None:
            route = self.g.route(self.cur if self.virtual is None else self.virtual, self.r_free, band_hi,
                                 self.banned_fine)
            if route is None or isinstance(route, str):
                break
            j, i = (int(v) for v in route[-1])
            x, y = self.g.centre(j, i)
            area, sx, sy = solid_within(self.g.M, self.g.x0, self.g.y0, self.h, x, y, self.prm.rescue_reach_frac * self.r)
            if area < min_solid or self.g.half_width[j, i] < self.prm.rescue_min_half_width_frac * self.r:
                # only skins and seams within reach, or a band too narrow for any pass to turn: no pass tried
                self.banned_fine[max(j - rad, 0):j + rad + 1, max(i - rad, 0):i + rad + 1] = True
                continue
            # the search above ended at (j, i), its nearest goal: the same route leads there (from the
            # tool's point, not from the start of an idle pass rolled back)
            if self.link_to(self.r_free, -np.inf, self.banned_fine, cell=(j, i),
                            route=route if self.virtual is None else None) is None:
                break
            self.stats["rescued_starts"] += 1
            # along that solid material, on the right (the distance field's gradient there may point
            # away from a skin instead)
            return (j, i), math.atan2(sy - y, sx - x) + 0.5 * math.pi
        self.rescue_fails, self.rescue_spent = -1, True
        self.go_to_virtual(self.banned_fine)
        return None, None

    def rescue_turns(self, heading, P, removed, reason, E, free):
        """A rescued start (:meth:`rescue_start`) whose pass removed nothing from the planning stock
        (nothing kept): once more per ``rescue_turns_deg``, turned so far towards the material (a
        narrow mouth: along it the pass leaves the region); the last pass's (P, removed, reason, E, free).
        Each pass not kept is rolled back first: removing nothing from the planning stock, it may
        still have cut pixels of the rapid stock (its discs are r - h/sqrt(2): pixels whose centre an
        earlier disc swept but not all of the pixel), and a rapid stock cut where the tool never went
        proves G0 links that meet material."""
        for turn in self.prm.rescue_turns_deg:
            if removed > 0.0:
                break
            self.g.rollback()
            P, removed, reason, E, free = self.clearing_pass(heading - math.radians(turn), self.air_stop)
            self.stats["passes"] += 1
        return P, removed, reason, E, free

    def note_pass(self, failed, j, i):
        """After a pass from the start cell (j, i): a failed one bans ``failed_start_ban_frac`` r of
        ``banned_fine`` and counts against a rescue; one that cut ends a rescue and renews it."""
        if failed:
            self.ban_start(self.banned_fine, j, i, self.prm.failed_start_ban_frac)
        self.rescue_fails = self.rescue_fails + 1 if failed and self.rescue_fails >= 0 else -1
        self.rescue_spent = self.rescue_spent and failed

    def finish_parts(self):
        """The parts of the tool-centre region the finishing laps follow: the region 1.5 h inside its
        limit (:meth:`finish_part` is given them oriented; :func:`.finish.note_thin_strips` reads them)."""
        return list(shapely.get_parts(self.allowed.buffer(-1.5 * self.h)))

    def finish_part(self, part):
        """The wall-following finish laps of one part (:func:`.finish.finish_part`)."""
        return finish.finish_part(self, part)

    def sweep_remnant(self):
        """A free-standing remnant of material (a pillar the passes around it could not take: every
        border cell around it banned) small enough that a straight cut towards its centre meets it
        over at most theta -- within radius r sin(theta/2) of its centre -- is cut by one straight
        feed move from a free point, reached through cleared area, to where the tool disc holds all
        of it; True if one was cut."""
        if self.cur is None:
            return False
        lbl, nlab, discs = self._remnants()
        if nlab == 0:
            return False
        rho_max = self.r * math.sin(0.5 * self.target)
        CX, CY, RAD = discs
        labs = np.flatnonzero(RAD + self.h / math.sqrt(2.0) <= rho_max)
        if len(labs) == 0:
            return False
        D, Ac = self.g.free_field()
        # the 8 sweep directions of every candidate at once: start S (a free cell) and end E
        U = np.array([[math.cos(a), math.sin(a)] for a in np.arange(8) * (math.pi / 4)])
        C = np.stack([CX[labs], CY[labs]], axis=1)[:, None, :]
        rho_b = (RAD[labs] + self.h / math.sqrt(2.0))[:, None, None]
        S_all, E_all = C - (self.r + rho_b + self.g.hc) * U, C - (self.r - rho_b - self.h) * U
        J, I = (S_all[..., 1] - self.g.y0) // self.g.hc, (S_all[..., 0] - self.g.x0) // self.g.hc     # Grid.cell
        ok = (J >= 0) & (J < D.shape[0]) & (I >= 0) & (I < D.shape[1])
        Jc, Ic = np.where(ok, J, 0).astype(int), np.where(ok, I, 0).astype(int)
        ok &= Ac[Jc, Ic] & (D[Jc, Ic] >= self.r_free)
        for n, m in zip(*np.nonzero(ok)):          # candidate-major, direction-minor: the order of the search
            lab, S, E, jS, iS = labs[n], S_all[n, m], E_all[n, m], int(Jc[n, m]), int(Ic[n, m])
            if not segment_inside(self.g.A, self.g.x0, self.g.y0, self.h, S[0], S[1], E[0], E[1], 2.0 * self.h):
                continue
            if not capsule_free_of(self.g.M, lbl, lab, self.g.x0, self.g.y0, self.h, S[0], S[1], E[0], E[1],
                                   self.r + self.h):
                continue                       # the sweep would meet other material too
            if self.link_to(self.r_free, cell=(jS, iS), end_xy=(S[0], S[1])) is None:
                continue
            Q = resample_polyline(np.vstack([S, E]), self.ds, uniform=True)
            self.b.cut(Q[1:], self.feed_mm_min, z=self.z, tag="remnant sweep")
            self.g.cut_path(np.ascontiguousarray(Q))
            self.cur = (float(E[0]), float(E[1]))
            self.stats["remnant_sweeps"] += 1
            return True
        return False

    def _remnants(self):
        """(labels, count, (centre x, centre y, radius) mm) of the planning stock's 8-connected material
        components (:func:`label8`, :func:`component_discs`), computed again only when the stock differs
        pixel for pixel from the one of the last call (a remnant sweep is often tried again before any
        pass has cut)."""
        c = self._remnant_cache
        if c is not None and np.array_equal(c[0], self.g.M):
            return c[1]
        lbl, nlab = label8(self.g.M)
        discs = component_discs(lbl, nlab, self.g.x0, self.g.y0, self.h) if nlab else None
        self._remnant_cache = (self.g.M.copy(), (lbl, nlab, discs))
        return self._remnant_cache[1]

    def min_yield(self, fine, P):
        """The least area (fraction of a_e per mm of the pass) the pass through the points P (n, 2)
        must remove to be kept: ``second_chance_min_yield`` in the second chance, else
        ``sliver_pass_min_yield``; none while a narrow region with an open end waits (its mouth must
        be cleared, slivers too) or where the pass runs where the tool-centre region is narrower than
        ``sliver_min_half_width_frac`` r (a band where the passes are the way in)."""
        if self.narrow_state.open_mouth_pending():
            return 0.0
        if self.in_band(P):
            return 0.0
        return self.prm.second_chance_min_yield if fine else self.prm.sliver_pass_min_yield

    def wall_sliver(self, removed, start, P):
        """True when the pass just cut (from ``start``, (x, y) mm, through the points P (n, 2)), not in
        a band (:meth:`in_band`), removed less than
        ``wall_sliver_max_area_rae`` r a_e mm^2, all of it within reach of a finishing lap still to come
        in its part: every removed pixel centre within r - 3 h of the tool-centre limit (the lap's
        ring lies 1.5 h inside it; 1.5 h more for the pixel's half-diagonal and the ring's chords)."""
        if (self.prm.wall_sliver_max_area_rae <= 0 or not self.finish or start is None
                or removed >= self.prm.wall_sliver_max_area_rae * self.r * self.a_e
                or self.narrow_state.open_mouth_pending() or self.in_band(P)):
            return False
        if not any(q.distance(Point(*start)) <= 2 * self.g.hc for q in self.todo_parts):
            return False
        taken = self.g.taken_since_checkpoint()
        if len(taken) == 0:
            return False
        if self._wall is None:
            self._wall = shapely.boundary(self.allowed)
            shapely.prepare(self._wall)
        return bool(shapely.dwithin(self._wall, shapely.points(taken), self.r - 3 * self.h).all())   # prepared: indexed

    def in_band(self, P):
        """Whether the pass through the points P (n, 2) runs where the tool-centre region is narrower
        than ``sliver_min_half_width_frac`` r (a band where the passes are the way in)."""
        J = np.clip(((P[:, 1] - self.g.y0) // self.g.hc).astype(int), 0, self.g.half_width.shape[0] - 1)
        I = np.clip(((P[:, 0] - self.g.x0) // self.g.hc).astype(int), 0, self.g.half_width.shape[1] - 1)
        return bool(self.g.half_width[J, I].min() < self.prm.sliver_min_half_width_frac * self.r)

    def undo_pass(self, undo, E, free):
        """A pass that only cuts slivers is not worth its link and its feed time: the link and the
        pass are undone (``undo``: the builder mark, tool point, link count and ``virtual`` state before the link; the
        stocks go back to the grid's checkpoint); the (P, removed, E, free) of an empty pass."""
        self.b.rollback(undo[0])
        self.g.rollback()
        self.cur, self.stats["links"], self._virtual = undo[1], undo[2], undo[3]
        return np.array([self.cur], float), 0.0, E[:1], free[:1]

    def ban_start(self, banned, j, i, frac):
        """Ban the coarse cells within ``frac`` r (Chebyshev) of the failed start cell (j, i). A pass
        that left the tool-centre region at its first step failed on the local shape of the region's
        boundary (a fillet, the mouth of a band), not for want of material: it bans only
        ``pass_ban_frac`` r, so that the passes still reach a band beside it (as every failed start
        of the second chance)."""
        rad = int(math.ceil(frac * self.r / self.g.hc))
        banned[max(j - rad, 0):j + rad + 1, max(i - rad, 0):i + rad + 1] = True

    def finish_if_done(self, D, Ac, banned):
        """Before the tool leaves its part of the tool-centre region (a retract and a new entry),
        finish that part if its clearing is done (no material within reach of its free cells)."""
        if self.cur is None or not self.todo_parts:
            return
        dd = [q.distance(Point(*self.cur)) for q in self.todo_parts]
        kk = int(np.argmin(dd))
        if dd[kk] > 2 * self.g.hc:
            return
        J, I = np.nonzero(Ac & (D < self.r) & ~banned)
        if len(J) and shapely.contains_xy(self.todo_parts[kk].buffer(2 * self.g.hc), self.g.x0 + (I + 0.5) * self.g.hc,
                                          self.g.y0 + (J + 0.5) * self.g.hc).any():
            return
        self.finish_part(self.todo_parts.pop(kk))

    def keep_clean_round(self, saved):
        """Keep the clean-up round since ``saved`` (builder mark, stock snapshot, tool point, stats)
        only when it pays: the area it removed is at least ``clean_round_min_yield`` of what the
        nominal cut (a_e wide at the cutting feed) removes in the feed time the round adds (its
        rapids not counted); else roll it back. True if kept."""
        n0, snap0, cur0, st0 = saved
        took = float(snap0[0].sum() - self.g.M.sum()) * self.h * self.h
        P3, _, F3 = self.b.tail(n0 - 1)
        F3 = F3[1:]
        L3 = np.linalg.norm(np.diff(P3, axis=0), axis=1) if len(P3) > 1 else np.zeros(0)
        t_feed = float(np.sum(np.where(np.isfinite(F3) & (F3 > 0), L3 / np.where(F3 > 0, F3, 1.0), 0.0)))
        if took < self.prm.clean_round_min_yield * self.a_e * self.feed_mm_min * t_feed or took <= 0.0:
            self.b.rollback(n0)
            self.g.restore(snap0)
            self.cur = cur0
            self.stats.clear(); self.stats.update(st0)
            return False
        self.stats["clean_rounds"] += 1
        return True

    def run(self):
        """Plan the level: enter, clear (passes, links, remnants), finish; up to clean_rounds more rounds."""
        self.todo_parts = [orient(q, 1.0) for q in self.finish_parts()] if self.finish else []
        self.r_free = self.r + self.prm.free_margin_hc * self.g.hc      # coarse cell centre to material, with the cell half-diagonal margin
        # narrow regions (narrow.py): out of the passes' view, each cut by Thesis IV's trochoid when reached
        self.narrow_state = narrow_level.LevelRegions(self, self.narrow_regs)
        mark = self.b.mark()
        if not self.enter() and not narrow_level.next_region(self):
            finish.note_unvisited(self, mark)
            return
        for rnd in range(self.clean_rounds + 1):
            # round 0 clears and finishes; a clean-up round takes what the sliver guard and the bans left
            # (a pass refused where its first steps would graze a crescent), then finishes again
            if rnd > 0:
                D, Ac = self.g.free_field()
                if not (Ac & (D < self.r - 2 * self.g.hc)).any():
                    break
                self.todo_parts[:] = [orient(q, 1.0) for q in self.finish_parts()] if self.finish else []
                saved = (self.b.mark(), self.g.snapshot(), self.cur, dict(self.stats))
            banned = np.zeros((self.g.ny // self.g.k, self.g.nx // self.g.k), bool)
            fine = False     # second chance (see below): failed passes ban only pass_ban_frac r
            self.banned_fine = banned.copy()     # the bans, a failed start's only failed_start_ban_frac r
            self.rescue_fails, self.rescue_spent = -1, False
            for _ in range(self.max_passes):
                D, Ac = self.g.free_field()
                self.g.checkpoint()          # for undo_pass (only the window changed since is copied)
                self._link_tail = None
                undo = (self.b.mark(), self.cur, self.stats["links"], self._virtual)
                end, heading = self.next_start(banned)
                if end is None and narrow_level.next_region(self, banned):
                    continue
                if end is None:
                    D, Ac = self.g.free_field()
                    if not (Ac & (D < self.r) & ~banned).any():
                        break
                    if self.sweep_remnant():
                        continue
                    if not fine:
                        # before a lift and a helix entry (at the entry feed), the places the coarse
                        # bans (r about a failed start) closed get a second chance through cleared area
                        fine = True
                        banned[:] = False
                        continue
                    end, heading = self.rescue_start()
                if end is None:
                    self.finish_if_done(D, Ac, banned)
                    if self.enter(banned) is False:
                        break
                    continue
                # heading: along the material boundary, material on the right
                j, i = end
                gx, gy = boundary_gradient(D, int(j), int(i))
                if heading is None and (not (np.isfinite(gx) and np.isfinite(gy)) or gx == gy == 0):
                    banned[j, i] = self.banned_fine[j, i] = True
                    continue
                rescued, heading = heading is not None, math.atan2(gy, gx) - 0.5 * math.pi if heading is None else heading
                P, removed, reason, E, free = self.clearing_pass(heading, self.air_stop)
                self.stats["passes"] += 1
                if rescued:
                    P, removed, reason, E, free = self.rescue_turns(heading, P, removed, reason, E, free)
                if len(P) < 2 and self.g.half_width[j, i] < self.turn_radius:
                    # nothing emitted (the pass ran into air and was dropped: the stock is unchanged). In a band
                    # narrower than the turning circle, where the material lies behind the start heading (the
                    # face at the end of the band) the hard right turn through air slides away along the
                    # wall: start the other way round once
                    P, removed, reason, E, free = self.clearing_pass(heading + math.pi, self.air_stop)
                    self.stats["passes"] += 1
                if len(P) < 2 and reason == 2 and self.g.half_width[j, i] < self.r:
                    # nothing emitted (the stock is unchanged): the pass ran its whole air allowance
                    # without meeting material. In a band narrower than the tool (a neck between
                    # islands) the way to the face is a loop mostly through air (the turning circle is
                    # 1.57 r round): once more with 3.5 r of air before the place is banned -- else
                    # the face is taken by one helix entry after another (two_islands_neck: 5 lifts -> 2).
                    # Kept only where it removes narrow_min_yield a_e per mm of its length
                    snap_try = self.g.snapshot()
                    P, removed, reason, E, free = self.clearing_pass(heading, self.prm.narrow_air_stop_frac * self.r)
                    self.stats["passes"] += 1
                    if len(P) >= 2 and removed < self.prm.narrow_min_yield * self.a_e * self.ds * (len(P) - 1):
                        self.g.restore(snap_try)        # not worth its air: the place is banned after all
                        P, removed, E, free = P[:1], 0.0, E[:1], free[:1]
                if len(P) >= 2 and removed < self.min_yield(fine, P) * self.a_e * self.ds * (len(P) - 1):
                    P, removed, E, free = self.undo_pass(undo, E, free)
                elif len(P) >= 2 and self.wall_sliver(removed, undo[1], P):
                    P, removed, E, free = self.undo_pass(undo, E, free)
                    self.stats["wall_slivers"] += 1
                if len(P) < 2 and self.prm.drop_idle_links and len(self.b) > undo[0]:
                    # nothing emitted: the link to this start is not run either (a chain of such links
                    # wandered a comb's fingers by G0, hundreds of mm); the next start is sought from
                    # this one (``virtual``) and linked to from the tool's point
                    at = (float(P[0, 0]), float(P[0, 1]))
                    P, removed, E, free = self.undo_pass(undo, E, free)
                    self._virtual = (at, self.cur)
                failed = removed < self.prm.pass_min_removed_rh * self.r * self.h or len(P) < 2
                if failed:
                    self.ban_start(banned, j, i, self.prm.pass_ban_frac if (len(P) < 2 and reason == 0) or fine else 1.0)
                self.note_pass(failed, j, i)
                air = E < self.air_rad                # nothing in front of the tool: a link at the link feed, or
                                                 # a G0 where the chord is proven clear (``free``, see pass_kernel)
                k0 = self.join_link_to_pass(P, free) + 1
                fr, ai = free[k0:], air[k0:]
                self.b.add(P[k0:], np.where(fr, "rapid", np.where(ai, "link", "cut")).astype(object),
                           np.where(fr, np.nan, np.where(ai, self.link_feed_mm_min, self.feed_mm_min)),
                           np.where(fr, "cleared: air inside cleared area", "").astype(object), z=self.z, cleared=fr)
                self.cur = (float(P[-1, 0]), float(P[-1, 1]))
            narrow_level.close(self)
            if self.finish:
                # every part of the tool-centre region is finished once, the nearest to the tool first (a part
                # is also finished as soon as its clearing is done, before the tool leaves it: no extra lift)
                while self.todo_parts:
                    kk = 0
                    if self.cur is not None:
                        dd = [q.distance(Point(*self.cur)) for q in self.todo_parts]
                        kk = int(np.argmin(dd))
                    self.finish_part(self.todo_parts.pop(kk))
            if rnd > 0 and not self.keep_clean_round(saved):
                break
        self.retract()
        finish.note_unvisited(self, mark)
        if self.finish and not self.prm.slot_narrow:
            finish.note_thin_strips(self)         # strips only slotting would clear: stated with the remedies


# ------------------------------------------------------------------------------------------------
# the planner
# ------------------------------------------------------------------------------------------------
def adaptive_clearing(job, params: AdaptiveParams = AdaptiveParams(), *, resolution_mm: float | None = None,
                      step_mm: float | None = None) -> ToolPath:
    """Engagement-controlled clearing of ``job.polygon`` (see the module docstring); a :class:`ToolPath`.

    ``job``: a :class:`cnclab.toolpath.job.Job` (or any object with its attribute names); the planner
    reads ``polygon``, ``tool`` (its radius, mm), ``theta_deg`` target engagement (deg), ``a_p`` axial
    depth per level (mm), ``depth`` total depth (mm, None: ``a_p``; levels of at most ``a_p``),
    ``start_hole`` (None or (x, y, diameter) mm of a pre-drilled hole), ``feed_mm_min`` and
    ``link_feed_mm_min`` (mm/min), ``rapid_links``, ``clearance_z`` and ``top_z`` (mm),
    ``spindle_rpm`` and ``source`` (names the job in error messages). ``params``: the tuning
    constants (:class:`AdaptiveParams`, each field with its unit and reason); ``resolution_mm``
    planning pixel (mm, None: r/60); ``step_mm`` path step (mm, None: r/30). The result's ``info``
    holds ``resolution_mm`` and ``levels`` (the cutting z of each level, mm), what
    :func:`.audit.unproven_rapids` reads.
    ``rapid_links``: the links at depth between passes (chords proven free of material on the rapid
    stock: no pixel of it within r + h/sqrt(2) of the chord, see Grid) are written as G0 marked
    ``cleared`` (the ToolPath column; as FreeCAD Adaptive's keep-tool-down links), else as G1 at ``link_feed_mm_min``.
    G0 is a straight line on LinuxCNC (and on any controller with interpolated rapids); on a
    controller whose rapids dog-leg, set it False (job key ``"rapid_links": false``).
    """
    t_start = time.perf_counter()
    prm = params
    pocket, tool, theta_deg, a_p, feed_mm_min = job.polygon, job.tool, job.theta_deg, job.a_p, job.feed_mm_min
    tool_radius, depth, start_hole = tool.radius, getattr(job, "depth", None), getattr(job, "start_hole", None)
    link_feed_mm_min, rapid_links = getattr(job, "link_feed_mm_min", 1500.0), bool(getattr(job, "rapid_links", True))
    clearance_z, top_z = getattr(job, "clearance_z", 5.0), getattr(job, "top_z", 0.0)
    spindle_rpm, source = getattr(job, "spindle_rpm", None), str(getattr(job, "source", "<job>"))
    guard_deg, clean_rounds, helix_angle_deg = prm.guard_deg, prm.clean_rounds, prm.helix_angle_deg
    finish, finish_margin_deg, finish_laps, max_passes = prm.finish, prm.finish_margin_deg, prm.finish_laps, prm.max_passes
    if not isinstance(pocket, (Polygon, MultiPolygon)) or pocket.is_empty or not pocket.is_valid:
        raise PlanningError(f"{source}: the pocket must be a valid, non-empty polygon")
    r = float(tool_radius)
    if not (math.isfinite(r) and r > 0):
        raise PlanningError(f"{source}: tool_radius must be > 0 mm, got {tool_radius!r}")
    if not 0 < theta_deg < 180:
        raise PlanningError(f"{source}: theta_deg must be in (0, 180) deg, got {theta_deg!r}")
    if not a_p > 0:
        raise PlanningError(f"{source}: a_p must be > 0 mm, got {a_p!r}")
    depth = float(a_p if depth is None else depth)
    h = float(resolution_mm or r / 60.0)
    if not (math.isfinite(h) and 0 < h <= r / 30.0 * (1 + 1e-9)):
        # measured: at h = r/20 the K&Y pocket plans with 169 mm^2 left uncut (r/30: 5 mm^2, as at r/60)
        raise PlanningError(f"{source}: resolution_mm must be in (0, r/30 = {r / 30.0:.4g}] mm (default r/60): a "
                            f"coarser planning stock cannot resolve the engagement; got {resolution_mm!r}")
    ds = float(step_mm or r / 30.0)
    allowed = pocket.buffer(-r, quad_segs=64)
    if allowed.is_empty or allowed.area < 4 * h * h:
        raise PlanningError(f"{source}: the tool (diameter {2 * r:g} mm) does not fit in the pocket "
                            "(no room for the tool centre)")
    parts = [p for p in shapely.get_parts(pocket)]
    for part in parts:
        if part.buffer(-r, quad_segs=32).is_empty:
            raise PlanningError(f"{source}: a region of the pocket (area {part.area:.1f} mm^2) is narrower "
                                f"than the tool (diameter {2 * r:g} mm)")
    target = math.radians(theta_deg)
    air_rad = math.radians(prm.air_deg)   # a step whose front half meets less material is air
    a_e = r * (1 - math.cos(target))
    target_finish = math.radians(theta_deg + finish_margin_deg)
    # a point of a finishing lap snapped onto the wall keeps the snap only while the engagement there stays
    # within theta + 2 deg, slivers counted (level GUARD_LEVEL) as well as at level 1/2: the simulator
    # measures up to ~14 deg more than the planning stock where a snap pushes the tool into a corner
    # rest or into the crescent an earlier pass left beside it (measured on random pockets at theta =
    # 40 deg, r = 2 mm: 52.2 deg with the sliver level held to theta + 7, 46.8 with theta + 2)
    cap_finish = math.radians(theta_deg + prm.finish_snap_deg)
    # the sliver guard (see pass_kernel): theta + guard_deg for the clearing passes, theta + 7 deg for the finish
    guard_pass = math.radians(theta_deg + guard_deg)
    guard_finish = math.radians(theta_deg + max(guard_deg, prm.finish_guard_deg))
    lag = 2.0 * math.sqrt(2.0 * r * h) + 2.0 * h
    n_samp = prm.n_samples
    turn = math.radians(prm.max_turn_deg)
    pass_step = PassStep(ds, lag, n_samp, turn)
    turn_radius = prm.turn_radius_frac * r    # the tightest right turn (the curvature limit of the passes), mm
    air_stop = prm.air_stop_frac * r          # a pass ends after so much air (its air tail is dropped)
    spindle = np.nan if spindle_rpm is None else float(spindle_rpm)
    zlev = [top_z - min(depth, a_p * (k + 1)) for k in range(int(math.ceil(depth / a_p - 1e-9)))]

    # the moves (shared with the level planners: _Level.b)
    b = ToolPathBuilder(tool=tool, spindle=spindle, info={"planner": "adaptive_clearing", "theta_deg": theta_deg,
                                                          "resolution_mm": h, "step_mm": ds})
    stats = {"passes": 0, "entries": 0, "retracts": 0, "links": 0, "clean_rounds": 0, "remnant_sweeps": 0, "wall_slivers": 0,
             "rescued_starts": 0}
    allowed_parts = list(shapely.get_parts(allowed))
    part_wide = {}        # part index -> inscribed radius of that part of the tool-centre region (mm)
    hole = None if start_hole is None else tuple(float(v) for v in start_hole)
    if hole is not None and not pocket.buffer(1e-9).contains(Point(hole[0], hole[1]).buffer(0.5 * hole[2] - 1e-6)):
        raise PlanningError(f"{source}: the start hole is not inside the pocket")
    narrow_regs = narrow.narrow_regions(allowed, r, h, branches=prm.narrow_branches) if prm.narrow_trochoid else []
    narrow_done = []      # one line per narrow region cut by the trochoid (info, program header)
    left_parts = []       # one line per part of the tool-centre region left uncut (finish._leave_part)
    cfg = {k: v for k, v in locals().items() if k not in ("lev", "z", "z_prev", "g")}
    for lev, z in enumerate(zlev):
        z_prev = top_z if lev == 0 else zlev[lev - 1]
        g = Grid(pocket, allowed, r, h, hole, prm.coarse_cell_mm, prm.coarse_cell_max_r)
        if not g.A.any():
            raise PlanningError(f"{source}: the tool-centre region is thinner than the planning resolution "
                                f"{h:g} mm: the pocket is too narrow for the tool")

        _Level(cfg, lev, z, z_prev, g).run()
    if len(b) == 0:
        raise PlanningError(f"{source}: nothing to machine" + "".join(f"; {q}" for q in dict.fromkeys(left_parts)))
    done = list(dict.fromkeys(narrow_done))        # the narrow regions cut by the trochoid (narrow.py)
    left = list(dict.fromkeys(left_parts))         # the parts left uncut (finish._leave_part; a clean-up round repeats them)
    tp = b.build(**stats, plan_time_s=time.perf_counter() - t_start, narrow_regions=done, left_parts=left, levels=zlev,
                 notes=done + left)
    if tp.kind[0] != _RAPID:                     # the first move (from an unknown place) is a rapid
        tp.kind[0], tp.feed[0], tp.arc[0], tp.arc_center[0] = _RAPID, np.nan, 0, np.nan
    return tp


def plan_job(job, **kw) -> ToolPath:
    """:func:`adaptive_clearing` of ``job`` (the registry's name for it); ``kw``: its ``params``,
    ``resolution_mm``, ``step_mm``."""
    return adaptive_clearing(job, **kw)
