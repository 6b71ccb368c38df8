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
from shapely.geometry import Point, Polygon

from ..helix import helix_entry

__all__ = ["PlanningError", "enter"]


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
    lv.retract()
    if lv.hole is not None and lv.lev == 0 and lv.stats["entries"] == 0:
        c = np.array(lv.hole[:2])
        rho = 0.0
        lv.b.rapid([c], z=lv.clearance_z)
        lv.b.plunge(c, lv.z, lv.feed_mm_min, tag="cleared: pre-drilled start hole", cleared=True)
    elif rho < rho_min:
        raise PlanningError(f"{lv.source}: no room for a helical entry at ({c[0]:.2f}, {c[1]:.2f}): "
                            "the region is too narrow for the tool")
    else:
        p0 = (c[0] + rho, c[1])
        lv.b.rapid([p0], z=lv.clearance_z)
        # down to 0.5 mm above the level's top: air above the stock top (level 0) or the floor
        # the previous level cleared (marked cleared: the program writer allows a rapid there only so)
        lv.b.rapid([p0], z=lv.z_prev + lv.prm.approach_above_mm, tag="cleared: above the level", cleared=True)
        lv.b.plunge(p0, lv.z_prev, lv.feed_mm_min, tag="air")
        # the helix ends where it reaches z (the last turn partial); at least one full turn, so
        # that the floor circle after it cuts in the helix's own groove (the package's one entry helix)
        pe = helix_entry(lv.b, c, rho, lv.z_prev, lv.z, lv.feed_mm_min, lv.helix_angle_deg)
        circ = c + rho * np.c_[np.cos(np.linspace(0, 2 * np.pi, 64)), np.sin(np.linspace(0, 2 * np.pi, 64))]
        lv.g.cut_path(circ)
        lv.stats["entries"] += 1
        lv.cur = (float(pe[0]), float(pe[1]))
        return True
    lv.stats["entries"] += 1
    lv.cur = (c[0] + rho, c[1])
    return True
