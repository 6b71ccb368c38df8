"""The wall-following finish (see the package docstring, "Finish"): laps along every ring of one part
of the tool-centre region under the engagement control at theta + finish_margin_deg, started where
the ring is free of material (a lap that stops short resumed r past its stop), points near the wall snapped onto it and replayed on the stock (a snap
that would raise the engagement beyond theta + finish_snap_deg keeps its planned place). A function
of the level planner ``lv`` (:class:`cnclab.toolpath.adaptive.planner._Level`). Units: mm, rad.
"""
from __future__ import annotations

import math

import numpy as np
import shapely

from .control import GUARD_LEVEL, replay
from .narrow import NARROW_MIN_HALF_WIDTH_FRAC, medial_axis, medial_graph
from ..path import resample_polyline
from .stock import material_within

__all__ = ["finish_part", "note_thin_strips", "note_unvisited", "slot_strips"]


def finish_part(lv, part):
    """The wall-following finish laps along every ring of one part of the tool-centre region (then,
    with ``AdaptiveParams.slot_narrow``, :func:`slot_strips`)."""
    _laps(lv, part)
    if lv.prm.slot_narrow:
        slot_strips(lv, part)


def _laps(lv, part):
    # the tool-centre limit (as the evaluator and Job.allowed() draw it: 64 segments a quarter circle),
    # 1 um inside it: the chords of its arcs never put the tool centre past the true limit
    wall = shapely.boundary(lv.allowed.buffer(-1e-3))
    sliver = None       # whether the part is narrower than lap_skip_inscribed_frac r (asked once, when needed)
    for ring in [part.exterior, *part.interiors]:
        R = np.asarray(ring.coords)[:-1]
        if len(R) < 3:
            continue
        Rs = resample_polyline(np.vstack([R, R[:1]]), lv.ds, uniform=True)[:-1]
        lap, segs, resume = 0, 0, None
        while lap < lv.finish_laps and segs <= lv.prm.finish_resume_laps:   # laps while the corner wedges are peeled
            dm, jj, ii = _field_at(lv, Rs)
            # a lap's material: any within reach on the first lap, a rest deeper than
            # max(finish_rest_min_mm, finish_rest_frac_ae a_e) on the further ones
            reach = lv.r + lv.g.hc if lap == 0 else lv.r - max(lv.prm.finish_rest_min_mm, lv.prm.finish_rest_frac_ae * lv.a_e)
            want = dm < reach
            if resume is None and not want.any():
                break                # nothing (more) to take along this ring
            # start where the ring is free of material (the farthest from it, the field being
            # capped: any point at the cap), the nearest such point to the tool (after a lap that
            # stopped short, the first one at least r past where it stopped)
            free_k = np.flatnonzero(dm >= min(dm.max(), lv.r_free + lv.g.hc))
            if resume is not None:
                past = (free_k - resume) % len(Rs)
                free_k = free_k[past * lv.ds >= lv.r]
                if len(free_k) == 0:
                    break
                k0 = int(free_k[np.argmin((free_k - resume) % len(Rs))])
            elif lv.prm.finish_arc_laps and (lap > 0 or not lv.prm.finish_full_first_lap) and len(free_k) > 1:
                k0 = _arc_start(want, free_k)
            elif lv.cur is not None and len(free_k) > 1:
                k0 = int(free_k[np.argmin(np.hypot(Rs[free_k, 0] - lv.cur[0], Rs[free_k, 1] - lv.cur[1]))])
            else:
                k0 = int(free_k[0])
            Rl = np.vstack([Rs[k0:], Rs[:k0], Rs[k0:k0 + 1]])
            origin = k0 if resume is None else origin    # a resumed lap runs on only to where its lap began
            # free: as for every link end, a coarse cell at least r_free (r + the cell half-diagonal
            # margin) from material; D at the cell of a point is not the point's own distance
            undo = None          # a skin step's (builder mark, stock snapshot, tool point): _skin_step
            if dm[k0] < lv.r_free and lap == 0:
                if sliver is None:
                    sliver = shapely.maximum_inscribed_circle(part).length < lv.prm.lap_skip_inscribed_frac * lv.r
                if sliver:
                    # no free place on the ring of a part narrower than the tool (entered, if at all, by a
                    # helix smaller than its ring): the link to the ring and the lap would cut its rest at
                    # the link feed, far beyond the bound (AdaptiveParams.lap_skip_inscribed_frac); unless
                    # the tool stands in the part and its rest there is a skin (_skin_step)
                    undo = _skin_step(lv, part, Rl[0]) if lv.prm.finish_skin_step else None
                    if undo is None:
                        _leave_part(lv, part)
                        return
            stepped = undo is not None
            if stepped:
                e = lv.g.cell(*lv.cur)
            elif lv.cur is not None:
                e = lv.link_to(lv.r_free, cell=(int(jj[k0]), int(ii[k0])), end_xy=(Rl[0, 0], Rl[0, 1]))
            else:
                e = None
            if e is None and resume is not None:
                break                # a resumed lap only through cleared area: no lift for it
            if e is None and dm[k0] < lv.r:
                # no cleared place to start the lap from and none reachable at depth: a part no entry
                # could open (a sliver of the tool-centre region thinner than the smallest helix). Left
                # uncut and stated (:func:`_leave_part`); ``plan`` measures what it leaves and refuses it
                # above the uncut limit unless allow_uncut (issue 28 item 1)
                _leave_part(lv, part)
                return
            if e is None:
                lv.retract()
                lv.approach(Rl[0])
                # free of material under the tool: feed down into cleared area
                lv.b.plunge(Rl[0], lv.z, lv.feed_mm_min, tag="cleared", cleared=True)
            else:
                _step_onto(lv, Rl[0])
            # the wall-following pass: the same engagement control, sliding along the wall;
            # it ends 2 r past the last ring point with the lap's material (see ``want``)
            sl = np.r_[0.0, np.cumsum(np.hypot(*np.diff(Rl, axis=0).T))]
            if lv.prm.finish_arc_laps:
                mat = np.flatnonzero(np.r_[want[k0:], want[:k0], want[k0:k0 + 1]])
            else:
                mat = np.flatnonzero(np.r_[dm[k0:], dm[:k0], dm[k0:k0 + 1]] < lv.r + lv.g.hc)
            L_ring = float(sl[-1]) if len(mat) == 0 else min(float(sl[-1]), float(sl[mat[-1]]) + lv.prm.finish_run_on_frac * lv.r)
            if lap == 0 and resume is None and lv.prm.finish_full_first_lap:
                L_ring = float(sl[-1])       # the whole ring: see AdaptiveParams.finish_full_first_lap
            if resume is not None:
                L_ring = min(L_ring, float(sl[(origin - k0) % len(Rs)]) + lv.prm.finish_run_on_frac * lv.r)
            P = _run_lap(lv, wall, Rl, L_ring)
            short = float(np.hypot(*np.diff(P, axis=0).T).sum()) < L_ring - lv.prm.finish_run_on_frac * lv.r
            if stepped and short:
                # a skin lap that stopped short (a thicker rest on the ring): step and lap taken back,
                # the part left as without the step (its resumed laps would link past that rest)
                lv.b.rollback(undo[0])
                lv.g.restore(undo[1])
                lv.cur = undo[2]
                _leave_part(lv, part)
                return
            if stepped:
                lv.stats["skin_steps"] = lv.stats.get("skin_steps", 0) + 1
            if short:
                # the lap stopped short (the control found no way on at the finish target): the next
                # one starts past where it stopped, the ring's rest not left for want of a thick rest
                resume, segs = int(np.argmin(np.hypot(Rs[:, 0] - P[-1, 0], Rs[:, 1] - P[-1, 1]))), segs + 1
            else:
                resume, lap = None, lap + 1
        if lap and lv.prm.finish_peel_rounds:
            _peel(lv, wall, Rs)


def _skin_step(lv, part, xy):
    """The start of the lap of a part narrower than the tool whose ring has no place free of material:
    when the tool stands at depth inside the part (the passes that cleared it ended there) and the
    straight move from it to the ring point ``xy`` (mm) stays in the tool-centre region, that move at
    the cutting feed, if its engagement replayed on the planning stock stays within the finish target
    (the rest there is a skin the passes left along the walls: a 7.2 mm slot, D6, kept 30-150 um on
    both walls, 9.3 mm^2, for want of this step). Emitted and cut into the stock: its undo (builder
    mark, stock snapshot and tool point before it), with which the caller takes the step and the lap
    back if the lap stops short (:func:`_laps`); else nothing: None."""
    if lv.cur is None or not shapely.contains_xy(part.buffer(2.0 * lv.h), *lv.cur):
        return None
    undo = (lv.b.mark(), lv.g.snapshot(), lv.cur)
    if math.hypot(xy[0] - lv.cur[0], xy[1] - lv.cur[1]) <= 1e-9:
        return undo
    if not lv.allowed.buffer(1e-6).contains(shapely.LineString([lv.cur, xy])):
        return None
    P = resample_polyline(np.array([lv.cur, xy], float), lv.ds)
    E = lv.g.replay(np.ascontiguousarray(P), lv.lag, lv.n_samp)
    if len(E) and float(np.max(E)) > lv.target_finish:
        lv.g.restore(undo[1])
        return None
    lv.b.cut(P[1:], lv.feed_mm_min, z=lv.z, tag="finish: onto a skin")
    lv.cur = (float(xy[0]), float(xy[1]))
    return undo


def _step_onto(lv, xy):
    """After a link to a ring point's cell: a feed step at the link feed onto the point ``xy`` (mm)
    itself, where the tool is not there yet."""
    if math.hypot(xy[0] - lv.cur[0], xy[1] - lv.cur[1]) > 1e-9:
        lv.b.link([xy], lv.link_feed_mm_min, z=lv.z)
        lv.cur = (float(xy[0]), float(xy[1]))


def _field_at(lv, P):
    """(dm, jj, ii): the free field's distance (mm) from the coarse cell of each point of P (n, 2) to
    material, and the cell indices (clipped to the grid)."""
    D, _ = lv.g.free_field()
    jj = np.clip(((P[:, 1] - lv.g.y0) // lv.g.hc).astype(int), 0, D.shape[0] - 1)
    ii = np.clip(((P[:, 0] - lv.g.x0) // lv.g.hc).astype(int), 0, D.shape[1] - 1)
    return D[jj, ii], jj, ii


def _arc_start(mat, free_k) -> int:
    """The free ring point (of the indices ``free_k``) nearest upstream of the shortest arc of the
    cyclic ring holding every True of ``mat`` (the ring minus its longest run of False): a lap
    started there and run on past the arc's last material point covers the least ring.

    >>> _arc_start(np.array([0, 0, 1, 0, 0, 0, 0, 0, 1, 0], bool), np.array([0, 4, 5, 9]))
    5

    (the longest free run is 3..7: the arc is 8, 9, 0, 1, 2; of the free points, 5 is the nearest
    before 8)
    """
    gaps = [(m, a) for a, m in _cyclic_runs(~mat)]
    if not gaps:
        return int(free_k[0])
    m, a = max(gaps)
    first = (a + m) % len(mat)                  # the arc's first material point
    return int(free_k[np.argmin((first - free_k) % len(mat))])


def _cyclic_runs(mask):
    """(start, length) of the maximal runs of True in the cyclic boolean array ``mask`` (a run across
    the end continues at the start); [(0, n)] when all True."""
    n = len(mask)
    if mask.all():
        return [(0, n)]
    k = int(np.flatnonzero(~mask)[0])           # rotate so that the array starts on a False
    m = np.roll(mask, -k)
    e = np.flatnonzero(np.diff(np.r_[0, m.astype(int), 0]))
    return [((int(a) + k) % n, int(b - a)) for a, b in zip(e[0::2], e[1::2])]


def _rest_mm2(lv, P) -> float:
    """Area (mm^2) of the planning stock's material within the tool's reach (r) of the points P (n, 2)."""
    g = lv.g
    return float(material_within(g.M, float(g.x0), float(g.y0), float(g.h), np.ascontiguousarray(P, float), float(lv.r)))


def _peel(lv, wall, Rs):
    """Local laps over the rests the full laps left along the ring ``Rs`` (corner wedges, which the
    engagement control at the finish target peels a layer per lap): each run of ring points with
    material deeper than ``finish_peel_rest_h`` h inside the tool disc gets laps from the last free
    point before it (at most r upstream) to ``finish_peel_run_on_frac`` r past it, linked at depth
    through cleared area (never by a lift), at most ``finish_peel_rounds``, while a lap takes
    material and at least ``finish_peel_min_mm2`` is left within reach of the run."""
    if lv.cur is None:
        return
    n = len(Rs)
    up = max(1, int(math.ceil(lv.r / lv.ds)))
    on = int(math.ceil(lv.prm.finish_peel_run_on_frac * lv.r / lv.ds))
    dm, _, _ = _field_at(lv, Rs)
    runs = _cyclic_runs(dm < lv.r - lv.prm.finish_peel_rest_h * lv.h)
    if not runs or runs[0][1] == n:
        return                       # nothing left along the ring (or no free place on it)
    for a, m in runs:
        span = (a + np.arange(m)) % n
        for _ in range(lv.prm.finish_peel_rounds):
            dm, jj, ii = _field_at(lv, Rs)
            if not (dm[span] < lv.r - lv.prm.finish_peel_rest_h * lv.h).any() or \
                    _rest_mm2(lv, Rs[span]) < lv.prm.finish_peel_min_mm2:
                break
            free = [k for k in ((a - q) % n for q in range(1, up + 1)) if dm[k] >= lv.r_free]
            if not free:
                break
            k0 = free[0]
            idx = (k0 + np.arange(min((a + m - k0) % n + on + 1, n + 1))) % n
            Rl = Rs[idx]
            if lv.link_to(lv.r_free, cell=(int(jj[k0]), int(ii[k0])), end_xy=(Rl[0, 0], Rl[0, 1])) is None:
                break
            _step_onto(lv, Rl[0])
            before = int(np.count_nonzero(lv.g.M))
            _run_lap(lv, wall, Rl, float(np.hypot(*np.diff(Rl, axis=0).T).sum()))
            lv.stats["peels"] = lv.stats.get("peels", 0) + 1
            if int(np.count_nonzero(lv.g.M)) == before:
                break


def _run_lap(lv, wall, Rl, L_ring):
    """One wall-following pass along the ring points ``Rl`` (from the tool's point, its start) for at
    most ``L_ring`` mm, under the engagement control at the finish target, points near the wall
    snapped onto it (see the module docstring); emitted, the stock cut. Returns its points (n, 2)."""
    hd = math.atan2(Rl[1, 1] - Rl[0, 1], Rl[1, 0] - Rl[0, 0])
    snap = lv.g.snapshot()
    M_before = snap[0]
    P, _, _, E, _ = lv.g.run_pass(Rl[0], hd, lv.target_finish, lv.pass_step, int(2 * L_ring / lv.ds) + 100, 1e18,
                                  min(lv.turn, lv.ds / lv.turn_radius), 1.02 * L_ring + lv.ds, lv.guard_finish)
    # points the grid kept within 2 h of the wall go onto the exact wall
    # (the grid mask is shrunk by h/sqrt(2) for safety: no skin is left on the walls)
    pp = shapely.points(P)
    near = shapely.distance(wall, pp) < lv.prm.finish_snap_band_h * lv.h
    # not the first point: it is where the tool is (the lap's moves go to P[1:]); a snapped P[0] would
    # cut the stocks where the tool never goes (up to 2 h off), and a G0 proven on them could graze
    near[0] = False
    if near.any():
        # the nearest wall point (not locate + interpolate along the multi-ring wall: a
        # point nearest to a ring's closing vertex would land on the next ring's start)
        snapped = shapely.get_coordinates(shapely.shortest_line(pp[near], wall))[1::2]
        Q = P.copy()
        Q[near] = snapped
        # the snap moves points up to 2 h outwards: near a concave corner that can
        # raise the engagement steeply (an arc nearly tangent to the rest). Replayed
        # on the stock as it was before this lap, a snapped point whose engagement
        # exceeds the finish target keeps its planned place (a skin < 2 h remains there)
        # (a chord the snap made longer than 1.5 ds measured along its length too: it can reach
        # into a corner)
        for _ in range(lv.prm.finish_replay_rounds):       # a reverted point changes the stock the later ones meet
            Qd, seg = resample_polyline(Q, 1.5 * lv.ds, return_index=True)
            Qd = np.ascontiguousarray(Qd)
            Es, Eg = replay(M_before.copy(), lv.g.x0, lv.g.y0, lv.h, lv.r, Qd, lv.lag, lv.n_samp, GUARD_LEVEL)
            bad = np.zeros(len(Q), bool)
            bad[seg[(Es > lv.cap_finish) | (Eg > lv.cap_finish)]] = True
            bad[:-1] |= bad[1:]          # a chord over the bound: both its ends
            over = near & bad & np.any(Q != P, axis=1)
            if not over.any():
                break
            Q[over] = P[over]
        lv.g.restore(snap)
        E = lv.g.replay(Q, lv.lag, lv.n_samp)
        P = Q
    P, E = _corner_cut(lv, P, E, snap)
    ai = E[1:] < lv.air_rad
    lv.b.add(P[1:], np.where(ai, "link", "cut").astype(object), np.where(ai, lv.link_feed_mm_min, lv.feed_mm_min),
             "finish", z=lv.z)
    lv.cur = (float(P[-1, 0]), float(P[-1, 1]))
    return P


def _corner_cut(lv, P, E, snap):
    """The lap ``P`` (planning engagement ``E``) past the sharp corners where the exact stock reads it
    over the cap (:class:`.corners.CornerCheck`): the stretch from the first such point to the first
    point beyond the corner's reach replaced by the chord across (inside the region: the corner is
    convex), the chord's points ``ds`` apart; where the chord too is over the cap (exact stock, or
    the planning stock over the finish target), the lap ends before it. The stock is replayed from
    ``snap``; (P, E) unchanged when no point is over (or the check is off:
    ``corner_exact_cap_deg`` None)."""
    chk = lv.corner_check()
    if chk is None:
        return P, E
    for skip in range(lv.prm.corner_skips + 1):
        k = chk.first_over(lv.b, lv.mark0, lv.z, P, E)
        if k is None:
            return P, E
        lv.stats["corner_cuts"] = lv.stats.get("corner_cuts", 0) + 1
        m = chk.past_corner(P, k)
        lv.g.restore(snap)
        if m is None or skip == lv.prm.corner_skips:
            return _end_before(lv, P, k, snap)          # no way past this corner
        chord = resample_polyline(P[[k - 1, m]], lv.ds, uniform=True)
        Q = np.vstack([P[:k - 1], chord, P[m + 1:]])
        E2 = lv.g.replay(Q, lv.lag, lv.n_samp)
        if np.any(E2[k - 1:k - 1 + len(chord)] > lv.target_finish):
            return _end_before(lv, P, k, snap)
        P, E = Q, E2
    return P, E


def _end_before(lv, P, k, snap):
    """(P[:k], its planning engagement): the lap ended before point ``k``, the stock replayed from
    ``snap`` along what is left of it."""
    lv.g.restore(snap)
    P = P[:k]
    return P, (lv.g.replay(P, lv.lag, lv.n_samp) if len(P) > 1 else np.zeros(len(P)))


def _leave_part(lv, part) -> None:
    """State a part of the tool-centre region whose finishing lap has no cleared place to start and
    none reachable at depth (a sliver thinner than the tool can move in under the engagement bound:
    an entry's tiny helix at most): the lap is skipped, one line in ``lv.left_parts`` (the result's
    ``info["left_parts"]`` and notes, the program header); ``plan`` measures what is left."""
    _state_left(lv, part, "cleared under engagement control (no cleared place to start its finishing lap): its "
                          "rest is left uncut")


def _state_left(lv, part, why: str, rest: float | None = None) -> None:
    """One line in ``lv.left_parts`` for a part of the tool-centre region left: where (its largest
    inscribed circle, mm), its area and the material within the tool's reach of it (mm^2: ``rest``,
    else :func:`_part_rest_mm2`; a sliver of a tool-centre part can hold a whole corner's material)
    and ``why`` (after "is too narrow to be ")."""
    ins = shapely.maximum_inscribed_circle(part)
    x, y = ins.coords[0]
    rest = _part_rest_mm2(lv, part) if rest is None else rest
    lv.left_parts.append(f"level z {lv.z:g}: a part of the tool-centre region near ({x:.2f}, {y:.2f}) (area "
                         f"{part.area:.2f} mm^2, inscribed radius {ins.length:.2f} mm, {rest:.1f} mm^2 of material "
                         f"within the tool's reach of it) is too narrow to be {why}")
    lv.stats["parts_left"] = lv.stats.get("parts_left", 0) + 1


def _part_rest_mm2(lv, part) -> float:
    """The planning stock's material (mm^2) within r of the part ``part`` of the tool-centre region: of
    its vertices and of a grid of points inside it every r/10 mm (the discs of radius r about a grid of
    r/10 miss at most cusps r/800 deep of what the part's every point reaches)."""
    step = 0.1 * lv.r
    x0, y0, x1, y1 = part.bounds
    X, Y = np.meshgrid(np.arange(x0, x1 + step, step), np.arange(y0, y1 + step, step))
    pts = np.c_[X.ravel(), Y.ravel()]
    pts = np.vstack([pts[shapely.contains_xy(part, pts[:, 0], pts[:, 1])], shapely.get_coordinates(part)])
    return _rest_mm2(lv, pts)


def note_unvisited(lv, mark) -> None:
    """After the level: every part of the tool-centre region (``lv.allowed_parts``) that no move at
    the level's depth since the builder ``mark`` visits (no entry fits it: thinner than the smallest
    helix, ``helix_min_frac`` r, and no ramp; no way in at depth) is stated in ``lv.left_parts``."""
    pts, _, _ = lv.b.tail(mark)
    pts = pts[pts[:, 2] <= lv.z + 1e-9] if len(pts) else pts
    for part in lv.allowed_parts:
        near = part.buffer(2.0 * lv.h)
        if len(pts) and shapely.contains_xy(near, pts[:, 0], pts[:, 1]).any():
            continue
        _state_left(lv, part, "entered under engagement control (no helix or ramp fits, no way in at depth): "
                              "left uncut")


def slot_strips(lv, part) -> None:
    """Opt-in (``AdaptiveParams.slot_narrow``): the strips of the part of the tool-centre region
    thinner than 2 c (c = ``narrow.NARROW_MIN_HALF_WIDTH_FRAC`` r: a slot less than 0.4 r wider than
    the tool, a channel tapering to the tool's diameter) that still hold material within the tool's
    reach are cut by slotting: one feed move along the strip's medial axis from its cleared end to
    its tip and back through the slot it cut. No pass, lap or trochoid enters such a strip under the
    engagement bound (each step ahead meets nearly the whole front half of the tool), so what it
    holds is left otherwise (``plan`` refuses that as uncut). The slot is cut at the feed that keeps
    the nominal removal rate (``feed_mm_min`` x a_e / 2 r: the full tool width is engaged); its
    engagement (up to 180 deg) is stated in the result's notes (the program header)."""
    c_lim = NARROW_MIN_HALF_WIDTH_FRAC * lv.r
    strips = _thin_strips(lv, part)
    if not strips:
        return
    spacing = min(2.0 * lv.h, lv.r / 8.0)
    G = medial_graph(part, spacing)
    if G.number_of_nodes() == 0:
        return
    nodes = np.array(list(G.nodes), float)
    cn = np.array([G.nodes[tuple(p)]["c"] for p in nodes])
    inside = lv.allowed.buffer(-1e-3)
    for q in strips:
        keep = shapely.contains_xy(q.buffer(2.0 * lv.h), nodes[:, 0], nodes[:, 1]) & (cn <= 1.5 * c_lim)
        ax = medial_axis(part, spacing, G, [tuple(p) for p in nodes[keep]])
        if ax is not None:
            P, c = ax
            _slot_along(lv, P if c[0] >= c[-1] else P[::-1], inside)


def _thin_strips(lv, part) -> list:
    """The strips of ``part`` thinner than 2 c (c = ``narrow.NARROW_MIN_HALF_WIDTH_FRAC`` r), of at
    least c r mm^2: what a slot less than 0.4 r wider than the tool leaves of the tool-centre region."""
    c_lim = NARROW_MIN_HALF_WIDTH_FRAC * lv.r
    wide = part.buffer(-c_lim, quad_segs=16).buffer(c_lim, quad_segs=16)
    return [q for q in shapely.get_parts(part.difference(wide)) if q.area >= c_lim * lv.r]


def note_thin_strips(lv) -> None:
    """After the level, without ``AdaptiveParams.slot_narrow``: every strip of the tool-centre region
    that :func:`slot_strips` would slot and that keeps more than ``thin_strip_note_mm2`` of material
    within the tool's reach of it (:func:`_part_rest_mm2`) is stated in ``lv.left_parts`` with that
    area and the two ways to cut it (``plan`` then refuses the uncut area with that reason, or warns
    under ``allow_uncut``)."""
    for q in (q for part in lv.finish_parts() for q in _thin_strips(lv, part)):
        rest = _part_rest_mm2(lv, q)
        if rest > lv.prm.thin_strip_note_mm2:
            _state_left(lv, q, f"cleared by this plan's passes (tool-centre half-width under "
                               f"{NARROW_MIN_HALF_WIDTH_FRAC:g} r, a step there meets nearly half the tool): its "
                               "material is left; slot it (AdaptiveParams.slot_narrow, python -m cnclab plan "
                               "--slot-narrow) or use a smaller tool", rest)


def _slot_along(lv, P, inside) -> None:
    """One slot along the axis ``P`` (from its wide end): from the last point before the first one
    with material within reach whose tool disc is free, to the last axis point inside the region."""
    P = resample_polyline(P[shapely.contains_xy(inside, P[:, 0], P[:, 1])], lv.ds, uniform=True)
    if len(P) < 2:
        return
    dm, jj, ii = _field_at(lv, P)
    mat = np.flatnonzero(dm < lv.r)
    if len(mat) == 0:
        return                                   # nothing left along this strip
    free = np.flatnonzero(dm[:mat[0] + 1] >= lv.r_free)
    if len(free) == 0:
        return                                   # no cleared place to start from
    k0 = int(free[-1])
    Q = P[k0:]
    if lv.cur is not None:
        e = lv.link_to(lv.r_free, cell=(int(jj[k0]), int(ii[k0])), end_xy=(Q[0, 0], Q[0, 1]))
        if e is not None and math.hypot(Q[0, 0] - lv.cur[0], Q[0, 1] - lv.cur[1]) > 1e-9:
            lv.b.link([Q[0]], lv.link_feed_mm_min, z=lv.z)
    else:
        e = None
    if e is None:
        lv.retract()
        lv.approach(Q[0])
        lv.b.plunge(Q[0], lv.z, lv.feed_mm_min, tag="cleared", cleared=True)   # dm[k0] >= r_free: free
    lv.cur = (float(Q[0, 0]), float(Q[0, 1]))
    slot_feed = lv.feed_mm_min * min(1.0, lv.a_e / (2.0 * lv.r))
    E = lv.g.replay(Q, lv.lag, lv.n_samp)
    back = np.ascontiguousarray(Q[::-1])
    Eb = lv.g.replay(back, lv.lag, lv.n_samp)
    for pts, eng in ((Q, E), (back, Eb)):
        ai = eng[1:] < lv.air_rad
        lv.b.add(pts[1:], np.where(ai, "link", "cut").astype(object), np.where(ai, lv.link_feed_mm_min, slot_feed),
                 "slot", z=lv.z)
    lv.cur = (float(back[-1, 0]), float(back[-1, 1]))
    lv.stats["slots"] = lv.stats.get("slots", 0) + 1
    L = float(np.hypot(*np.diff(Q, axis=0).T).sum())
    lv.narrow_done.append(f"slot along ({Q[0, 0]:.1f}, {Q[0, 1]:.1f}) -> ({Q[-1, 0]:.1f}, {Q[-1, 1]:.1f}), {L:.1f} mm: "
                          f"a strip narrower than the engagement bound admits, cut by slotting at up to "
                          f"{math.degrees(float(np.nanmax(E))):.0f} deg engagement, feed {slot_feed:.0f} mm/min "
                          "(slot_narrow)")
