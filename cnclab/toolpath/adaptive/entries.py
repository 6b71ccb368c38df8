"""Entries (see the package docstring, "Entries"): where the next entry goes (the point of the
tool-centre region farthest from its boundary among the cells whose tool disc still meets material),
the helix radius allowed there and the bans of places too narrow or entered before, the pre-drilled
start hole, and the helix itself. Functions of the level planner ``lv``
(:class:`cnclab.toolpath.adaptive.planner._Level`). Units: mm.
"""
from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.geometry import LineString, Point, Polygon

from ..helix import helix_entry
from ..path import resample_polyline
from .stock import segment_inside

__all__ = ["PlanningError", "enter", "ramp_segment", "ramp_entry"]


class PlanningError(ValueError):
    """The pocket cannot be machined safely with this tool (the message says why)."""


def enter(lv, banned=None):
    """Entry where the tool-centre region still has material within reach: True; False if
    none; None when the only place left is too narrow for a helix (it is then banned)."""
    D, Ac = lv.g.free_field()
    need = Ac & (D < lv.r)       # tool disk touches material there
    if banned is not None:
        need &= ~banned
    if not need.any():
        return False
    # the farthest point from the tool-centre region's boundary among those cells
    dA = lv.g.dA
    j, i = np.unravel_index(np.argmax(np.where(need, dA, -1)), need.shape)
    c = np.array(lv.g.centre(j, i))
    k_part = next((k for k, p in enumerate(lv.allowed_parts) if p.buffer(1e-6).contains(Point(*c))), None)
    comp = [] if k_part is None else [lv.allowed_parts[k_part]]
    rho_max = comp[0].exterior.distance(Point(*c)) if comp else dA[j, i]
    if comp:
        rho_max = min([rho_max] + [Polygon(hh).exterior.distance(Point(*c)) for hh in comp[0].interiors])
    rho = max(min(lv.prm.helix_radius_frac * lv.r, lv.prm.helix_room_frac * rho_max - lv.h), 0.0)
    # the smallest helix accepted here: helix_min_frac r, or half what the widest place of this
    # part of the tool-centre region allows (a part narrow everywhere is entered by a small
    # helix; the entry point is a coarse cell centre, up to hc/sqrt(2) off the widest place)
    rho_min = lv.prm.helix_min_mm
    if comp and banned is not None:
        if k_part not in lv.part_wide:
            lv.part_wide[k_part] = shapely.maximum_inscribed_circle(comp[0], 0.1 * lv.h).length
        wide = lv.part_wide[k_part]
        rho_min = max(lv.prm.helix_min_mm, min(lv.prm.helix_min_frac * lv.r, 0.5 * (lv.prm.helix_room_frac * wide - lv.h)))
    # a place entered before (its passes made no room) or too narrow for a helix is banned: no
    # endless re-entry at one spot
    again = (int(j), int(i)) in lv.entered
    lv.entered.add((int(j), int(i)))
    if (rho < rho_min or again) and banned is not None and not (lv.hole is not None and lv.lev == 0 and lv.stats["entries"] == 0):
        rad = int(math.ceil(lv.prm.entry_ban_frac * lv.r / lv.g.hc))
        banned[max(j - rad, 0):j + rad + 1, max(i - rad, 0):i + rad + 1] = True
        fine = getattr(lv, "banned_fine", None)
        if fine is not None and fine.shape == banned.shape:
            fine[max(j - rad, 0):j + rad + 1, max(i - rad, 0):i + rad + 1] = True
        return None
    if lv.lev == 0 and banned is not None and lv.g.half_width[j, i] < lv.prm.ramp_half_width_frac * lv.r \
            and not (lv.hole is not None and lv.stats["entries"] == 0):
        seg = ramp_segment(lv, c, D)
        if seg is not None:
            ramp_entry(lv, *seg)
            return True
    # (before the retract: an idle entry is undone with it, the tool still down)
    undo = (lv.b.mark(), lv.g.snapshot(), lv.cur, dict(lv.stats)) if banned is not None and lv.cur is not None else None
    lv.retract()
    if lv.hole is not None and lv.lev == 0 and lv.stats["entries"] == 0:
        c = np.array(lv.hole[:2])
        rho = 0.0
        lv.approach(c)
        lv.b.plunge(c, lv.z, lv.feed_mm_min, tag="cleared: pre-drilled start hole", cleared=True)
    elif rho < rho_min:
        raise PlanningError(f"{lv.source}: no room for a helical entry at ({c[0]:.2f}, {c[1]:.2f}): "
                            "the region is too narrow for the tool")
    else:
        p0 = (c[0] + rho, c[1])
        # down to 0.5 mm above the level's top: air above the stock top (level 0) or the floor
        # the previous level cleared (marked cleared: the program writer allows a rapid there only so)
        lv.approach(p0)
        lv.b.plunge(p0, lv.z_prev, lv.feed_mm_min, tag="air")
        # the helix ends where it reaches z (the last turn partial); at least one full turn, so
        # that the floor circle after it cuts in the helix's own groove (the package's one entry helix)
        m_helix = lv.b.mark()
        pe = helix_entry(lv.b, c, rho, lv.z_prev, lv.z, lv.feed_mm_min, lv.helix_angle_deg)
        circ = c + rho * np.c_[np.cos(np.linspace(0, 2 * np.pi, 64)), np.sin(np.linspace(0, 2 * np.pi, 64))]
        # the rapid stock cut along the written moves at the level's z (the floor circle's chords)
        lv.g.cut_path(circ, lv.written_floor(m_helix))
        lv.stats["entries"] += 1
        lv.cur = (float(pe[0]), float(pe[1]))
        if undo is not None and _idle_entry(lv, undo, rho, banned):
            # an entry that took hardly anything and from which no pass start is reachable (every
            # start about it banned: slivers the passes already failed on) is a lift for nothing:
            # undone, its place banned (the finishing laps take what is left there)
            lv.b.rollback(undo[0])
            lv.g.restore(undo[1])
            lv.cur = undo[2]
            lv.stats.clear(); lv.stats.update(undo[3])
            lv.stats["idle_entries_undone"] = lv.stats.get("idle_entries_undone", 0) + 1
            rad = int(math.ceil(lv.prm.entry_ban_frac * lv.r / lv.g.hc))
            banned[max(j - rad, 0):j + rad + 1, max(i - rad, 0):i + rad + 1] = True
            return None
        return True
    lv.stats["entries"] += 1
    lv.cur = (c[0] + rho, c[1])
    return True


def _extents(lv, c, u, D, reach):
    """How far (mm) the band runs from ``c`` along +u and -u: inside the tool-centre mask with
    material within reach (coarse distance ``D`` < r), at most ``reach`` each way; where the mask
    ends, on to the exact tool-centre limit (1 um inside it, as the finishing laps), so that the end
    face is cut, not left as a skin."""
    g = lv.g
    ext = []
    for sgn in (1.0, -1.0):
        t = 0.0
        while t < reach:
            p = c + sgn * (t + g.hc) * u
            jj, ii = g.cell(*p)
            if not (0 <= jj < D.shape[0] and 0 <= ii < D.shape[1]) or not D[jj, ii] < lv.r:
                break
            if not segment_inside(g.A, g.x0, g.y0, g.h, c[0], c[1], p[0], p[1], 0.0):
                piece = _piece(lv, c, c + sgn * (t + 2.0 * g.hc) * u)
                t = t if piece is None else max(t, piece.length)
                break
            t += g.hc
        ext.append(t)
    return ext


def _piece(lv, a, b):
    """The part of the segment a-b inside the tool-centre region (1 um in) that holds ``a``, or None."""
    if getattr(lv, "wall_in", None) is None:
        lv.wall_in = lv.allowed.buffer(-1e-3)
    cut = LineString([a, b]).intersection(lv.wall_in)
    return next((q for q in shapely.get_parts(cut) if q.distance(Point(*a)) < 1e-9), None)


def ramp_segment(lv, c, D):
    """The longest straight segment through ``c`` (mm) inside the tool-centre region whose points all
    have material within reach (coarse distance ``D`` < r), among directions every
    ``ramp_direction_step_deg``, each way at most ``ramp_max_frac`` x the 5 deg ramp length of the
    level, moved across the band onto the middle of its chord through ``c`` (the skins either side
    equal): (a, b) mm, or None when it is shorter than ``ramp_min_frac`` r."""
    prm = lv.prm
    dz = lv.z_prev - lv.z
    reach = prm.ramp_max_frac * dz / math.tan(math.radians(lv.helix_angle_deg))
    best, best_len = None, prm.ramp_min_frac * lv.r
    for ang in np.radians(np.arange(0.0, 180.0, prm.ramp_direction_step_deg)):
        u = np.array([math.cos(ang), math.sin(ang)])
        ext = _extents(lv, c, u, D, reach)
        if ext[0] + ext[1] > best_len:
            best, best_len = u, ext[0] + ext[1]
    if best is None:
        return None
    u, n = best, np.array([-best[1], best[0]])
    w = prm.ramp_half_width_frac * lv.r + lv.g.hc
    lo, hi = _piece(lv, c, c - 2 * w * n), _piece(lv, c, c + 2 * w * n)
    if lo is not None and hi is not None:
        c = c + 0.5 * (hi.length - lo.length) * n
    ext = _extents(lv, c, u, D, reach)
    if ext[0] + ext[1] < prm.ramp_min_frac * lv.r:
        return None
    return c - ext[1] * u, c + ext[0] * u


def ramp_entry(lv, a, b):
    """A ramp entry along the segment a-b (mm) of a band too narrow for a pass to turn (tool-centre
    half-width below ``ramp_half_width_frac`` r, where helix after helix was entered a few r apart):
    down from the level's top to its floor back and forth along a-b (the package's one ramp,
    :meth:`ToolPathBuilder.ramp`) in an even number of legs at the helix angle or shallower, so that
    it ends at depth back at ``a`` (no ``ramp-return`` through the wedge under its first leg), then one
    floor pass at depth a -> b through the wedge under its last leg (dz / legs high at b, at most half
    the level) and back to ``a`` at the link feed. The tool disc swept along a-b is cut from the stock;
    the tool stays down at ``a``. The legs are ``ramp`` moves (the job's entry feed; the evaluator
    reports their engagement apart, as a helix's), the floor pass a ``cut`` and a ``link``."""
    L = float(math.hypot(b[0] - a[0], b[1] - a[1]))
    dz = lv.z_prev - lv.z
    # an even number of legs, at most at the helix angle: the ramp ends at depth back at ``a``. A
    # ramp ending at b needs a return at depth to a through the wedge under its first leg: a slot
    # (180 deg) for its last r, up to the full a_p high (a plus-shaped pocket, D 12 mm: theta + 132 deg)
    legs = 2 * max(1, math.ceil(dz / math.tan(math.radians(lv.helix_angle_deg)) / (2.0 * L)))
    deg = math.degrees(math.atan2(dz, legs * L))
    lv.retract()
    lv.approach(a)
    lv.b.ramp(np.array([a, b]), lv.z_prev, lv.z, lv.feed_mm_min, ramp_deg=deg, max_mm=L)
    # the floor pass: the last leg (b -> a) leaves the wedge under it, dz / legs high at b, which no
    # move at depth has swept (as the helix's floor circle takes the wedge under its last turn); the
    # stocks below say a-b is clear at depth, so the tool runs it once at depth, and back to a along
    # its own cut at the link feed (from b, the dead end of a band this narrow, no link is proven)
    lv.b.cut([b], lv.feed_mm_min, z=lv.z, tag="entry-floor")
    lv.b.link([a], lv.link_feed_mm_min, z=lv.z, tag="entry-floor")
    Q = np.ascontiguousarray(resample_polyline(np.array([a, b]), lv.ds, uniform=True))
    lv.g.cut_path(Q)
    lv.cur = (float(a[0]), float(a[1]))
    # the band along it counts as entered (its wall skins are the finishing laps', not new entries)
    w = lv.prm.ramp_half_width_frac * lv.r + 2.0 * lv.g.hc
    for q in Q[::max(1, int(lv.g.hc / lv.ds))]:
        j0, i0 = lv.g.cell(q[0] - w, q[1] - w)
        j1, i1 = lv.g.cell(q[0] + w, q[1] + w)
        lv.entered.update((jj, ii) for jj in range(j0, j1 + 1) for ii in range(i0, i1 + 1))
    lv.stats["entries"] += 1
    lv.stats["ramp_entries"] = lv.stats.get("ramp_entries", 0) + 1


def _idle_entry(lv, undo, rho, banned):
    """Whether the helix just made (``undo[1]``: the stock before it) removed less than
    ``idle_entry_frac`` of its disc (radius r + rho) and no pass start outside ``banned`` is
    reachable from it through cleared area (:meth:`Grid.route`)."""
    took = float(undo[1][0].sum() - lv.g.M.sum()) * lv.h * lv.h
    if took >= lv.prm.idle_entry_frac * math.pi * (lv.r + rho) ** 2:
        return False
    route = lv.g.route(lv.cur, lv.r_free, lv.r_free + 1.5 * lv.g.hc, banned)
    return route is None
