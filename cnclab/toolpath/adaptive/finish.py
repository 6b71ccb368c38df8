"""The wall-following finish (see the package docstring, "Finish"): laps along every ring of one part
of the tool-centre region under the engagement control at theta + finish_margin_deg, started where
the ring is free of material, points near the wall snapped onto it and replayed on the stock (a snap
that would raise the engagement beyond theta + finish_snap_deg keeps its planned place). A function
of the level planner ``lv`` (:class:`cnclab.toolpath.adaptive.planner._Level`). Units: mm, rad.
"""
from __future__ import annotations

import math

import numpy as np
import shapely
from scipy.spatial import cKDTree

from .control import GUARD_LEVEL, replay
from .entries import PlanningError
from ..path import resample_polyline

__all__ = ["finish_part"]


def finish_part(lv, part):
    """The wall-following finish laps along every ring of one part of the tool-centre region."""
    # the tool-centre limit (as the evaluator and Job.allowed() draw it: 64 segments a quarter circle),
    # 1 um inside it: the chords of its arcs never put the tool centre past the true limit
    wall = shapely.boundary(lv.allowed.buffer(-1e-3))
    # the region farther than the snap band from the wall (1e-4 of its offset + 1e-6 mm more: the
    # sagitta of buffer's 64-segment arcs): its points need no exact distance to the wall
    off = 1e-3 + lv.prm.finish_snap_band_h * lv.h
    inner = lv.allowed.buffer(-(off * (1.0 + 1e-4) + 1e-6), quad_segs=64)
    shapely.prepare(inner)
    for ring in [part.exterior, *part.interiors]:
        R = np.asarray(ring.coords)[:-1]
        if len(R) < 3:
            continue
        Rs = resample_polyline(np.vstack([R, R[:1]]), lv.ds, uniform=True)[:-1]
        # a ring whose skin lap ran (in round 0) gets only rest laps in the clean-up rounds
        ring_key = (round(float(R[0, 0]), 6), round(float(R[0, 1]), 6), len(R))
        skinned = lv.skinned_rings
        for lap in range(lv.finish_laps):   # repeated while the corner wedges are peeled
            D, Ac = lv.g.free_field()
            jj = np.clip(((Rs[:, 1] - lv.g.y0) // lv.g.hc).astype(int), 0, D.shape[0] - 1)
            ii = np.clip(((Rs[:, 0] - lv.g.x0) // lv.g.hc).astype(int), 0, D.shape[1] - 1)
            dm = D[jj, ii]
            # the ring points with material in reach: any (the first lap takes the wall skin), or a rest
            # deeper than max(finish_rest_min_mm, finish_rest_frac_ae a_e) (further laps: the corner
            # wedges; in a clean-up round also the skin along the stretches where its passes cut)
            skin = lap == 0 and ring_key not in skinned
            mat = dm < (lv.r + lv.g.hc if skin else lv.r - max(lv.prm.finish_rest_min_mm, lv.prm.finish_rest_frac_ae * lv.a_e))
            if lap == 0 and not skin:
                mat |= _cut_near(lv, Rs)
            if not mat.any():
                break                # nothing (more) to take along this ring
            # start where the ring is free of material (the farthest from it, the field being
            # capped: any point at the cap): at the end of the longest stretch without material in
            # reach (the lap skips it), or where there is none, the nearest such point to the tool
            free = dm >= min(dm.max(), lv.r_free + lv.g.hc)
            free_k = np.flatnonzero(free)
            k0 = None if skin else _gap_start(mat, free, lv.ds, lv.prm.finish_skip_gap_frac * lv.r)
            if k0 is None:
                if lv.cur is not None and len(free_k) > 1:
                    k0 = int(free_k[np.argmin(np.hypot(Rs[free_k, 0] - lv.cur[0], Rs[free_k, 1] - lv.cur[1]))])
                else:
                    k0 = int(free_k[0])
            Rl = np.vstack([Rs[k0:], Rs[:k0], Rs[k0:k0 + 1]])
            if lv.cur is not None:
                e = lv.link_to(lv.r_free, cell=(int(jj[k0]), int(ii[k0])), end_xy=(Rl[0, 0], Rl[0, 1]))
            else:
                e = None
            if e is None:
                lv.retract()
                lv.b.rapid([Rl[0]], z=lv.clearance_z)
                if dm[k0] >= lv.r:          # free of material under the tool: feed down into cleared area
                    lv.b.plunge(Rl[0], lv.z, lv.feed_mm_min, tag="cleared", cleared=True)
                else:
                    ins = shapely.maximum_inscribed_circle(part)
                    raise PlanningError(
                        f"{lv.source}: a part of the tool-centre region (area {part.area:.2f} mm^2, inscribed "
                        f"radius {ins.length:.2f} mm near ({ins.coords[0][0]:.2f}, {ins.coords[0][1]:.2f})) "
                        "is too narrow to be cleared under engagement control: no cleared place to start "
                        "its finishing pass (the pocket is too narrow for the tool)")
            elif math.hypot(Rl[0, 0] - lv.cur[0], Rl[0, 1] - lv.cur[1]) > 1e-9:
                lv.b.link([Rl[0]], lv.link_feed_mm_min, z=lv.z)
                lv.cur = (float(Rl[0, 0]), float(Rl[0, 1]))
            # the wall-following pass: the same engagement control, sliding along the wall;
            # it ends 2 r past the last ring point that still has material within reach
            sl = np.r_[0.0, np.cumsum(np.hypot(*np.diff(Rl, axis=0).T))]
            mat_l = np.flatnonzero(np.r_[mat[k0:], mat[:k0], mat[k0:k0 + 1]])
            L_ring = float(sl[-1]) if len(mat_l) == 0 else min(float(sl[-1]), float(sl[mat_l[-1]]) + lv.prm.finish_run_on_frac * lv.r)
            hd = math.atan2(Rl[1, 1] - Rl[0, 1], Rl[1, 0] - Rl[0, 0])
            snap = lv.g.snapshot()
            M_before = snap[0]
            n_before = int(np.count_nonzero(M_before))
            P, _, _, E, _ = lv.g.run_pass(Rl[0], hd, lv.target_finish, lv.pass_step, int(2 * L_ring / lv.ds) + 100, 1e18,
                                          min(lv.turn, lv.ds / lv.turn_radius), 1.02 * L_ring + lv.ds, lv.guard_finish)
            # points the grid kept within 2 h of the wall go onto the exact wall
            # (the grid mask is shrunk by h/sqrt(2) for safety: no skin is left on the walls)
            band = lv.prm.finish_snap_band_h * lv.h
            near = ~shapely.contains_xy(inner, P[:, 0], P[:, 1])       # the others are farther than band
            near[near] = shapely.distance(wall, shapely.points(P[near])) < band
            if near.any():
                # the nearest wall point (not locate + interpolate along the multi-ring wall: a
                # point nearest to a ring's closing vertex would land on the next ring's start)
                snapped = shapely.get_coordinates(shapely.shortest_line(shapely.points(P[near]), wall))[1::2]
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
            ai = E[1:] < lv.air_rad
            lv.b.add(P[1:], np.where(ai, "link", "cut").astype(object), np.where(ai, lv.link_feed_mm_min, lv.feed_mm_min),
                     "finish", z=lv.z)
            lv.cur = (float(P[-1, 0]), float(P[-1, 1]))
            skinned.add(ring_key)
            if lap > 0 and (n_before - int(np.count_nonzero(lv.g.M))) * lv.h * lv.h < lv.prm.pass_min_removed_rh * lv.r * lv.h:
                break                # a further lap took (almost) nothing: the rests left are out of its reach


def _gap_start(mat, free, ds, min_gap):
    """Start index of a finishing lap along a ring of points ``ds`` mm apart: the free point (``free``)
    nearest before the end of the longest circular run of points without material in reach (``~mat``)
    when that run is at least ``min_gap`` mm long (the lap then skips it: it ends ``finish_run_on``
    past the last material before the gap); None when there is no such gap (every point has material
    in reach, or the gaps are short)."""
    n = len(mat)
    if mat.all() or not mat.any():
        return None
    k = int(np.flatnonzero(mat)[-1])
    order = (np.arange(n) + k + 1) % n          # from just after the last material point, circularly
    m = mat[order]
    best, best_end, run = 0, -1, 0
    for q in range(n):
        run = 0 if m[q] else run + 1
        if run > best:
            best, best_end = run, q
    if best * ds < min_gap:
        return None
    for q in range(best_end, best_end - best, -1):   # the free point nearest the gap's end
        if free[order[q]]:
            return int(order[q])
    return None


def _cut_near(lv, Rs):
    """Ring points (Rs, (n, 2) mm) within r + 2 coarse cells of a pixel the current clean-up round cut
    (the planning stock against its copy at the round's start): where its passes may have left a
    new wall skin; all False in round 0."""
    if lv.round_start_M is None:
        return np.zeros(len(Rs), bool)
    J, I = np.nonzero(lv.round_start_M != lv.g.M)
    if len(J) == 0:
        return np.zeros(len(Rs), bool)
    xy = np.c_[lv.g.x0 + (I + 0.5) * lv.h, lv.g.y0 + (J + 0.5) * lv.h]
    reach = lv.r + 2.0 * lv.g.hc
    d, _ = cKDTree(xy).query(Rs, distance_upper_bound=reach)
    return d <= reach
