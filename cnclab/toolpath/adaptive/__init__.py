"""Engagement-controlled clearing of any 2.5D pocket (islands, necks, several regions): the tool
follows the boundary of the cleared region, each step steered so that its engagement angle equals
the target, and links at depth through the cleared region (issue 16).

Units: lengths mm, angles deg at the API (rad inside the kernels), feeds mm/min; ``tool_radius`` is
the radius of the flat end mill. The pocket is a shapely Polygon/MultiPolygon whose holes are islands.

Design (the ideas and where they come from; the code is cnclab's own)
--------------------------------------------------------------------
* **The cleared region is the state** (Jacsó 2021, Thesis III: the constant-engagement path is the
  offset of the *cleared boundary*, not of the pocket contour). It is kept as a pixel stock
  (``h = r/60``, the tool-radius resolution of the evaluator) that the planner cuts as it goes.
* **Step control by the engagement angle** (Thesis III's constant engagement, Adaptive2d's per-step
  direction search): from the current point the next point is ``ds`` (default r/30) away; its
  heading is searched between a hard left turn (away from the material, material on the right:
  climb milling with an M3 spindle) and a hard right turn (or, where that would leave the
  tool-centre region, the rightmost heading that stays in it: the pass slides along the wall) so
  that the engagement measured
  on the stock -- the material fraction of the front half of the tool circle, the quantity the
  evaluator scores, on the 1/2 contour of the bilinear pixel stock with the crossings between the
  arc samples interpolated -- equals ``theta``. Libarea's ``Adaptive2d`` does the same with the *area cut
  per unit length* (its ``stepOverFactor``); at a constant step the two are equivalent to first
  order, and the angle is what is promised, so the angle is controlled directly. The search starts
  from the last step's turn rate, takes a Newton step with the last step's slope d(engagement)/
  d(heading) and closes the bracket by false position (Illinois), stopping within ROOT_TOL (1 deg)
  below the target: 2-3 arc evaluations a step. Air steps turn hard right at once. Disks are cut
  into the planning stock with the evaluator's lag (the last ``2 sqrt(2 r h) + 2 h`` mm not yet
  cut) so the planner measures what the evaluator will measure.
* **Sliver guard**: where the tool circle runs nearly tangent to a cut boundary -- re-entering a
  corner another pass left, a pass start beside a crescent -- the engagement angle jumps although
  the chip is thin, and the 1/2 contour can miss a sub-pixel crescent. Every step is therefore also
  measured with any material counted (bilinear fraction >= ``GUARD_LEVEL``); where that exceeds
  ``theta + guard_deg`` (5 deg) the heading turns left until it holds, or the pass ends.
  Consequence: the tool centre stops short of a concave corner of the tool-centre region (reaching
  it means touching the unreachable corner over ~180 deg minus the corner angle): a wedge about as
  large as the unreachable corner itself stays (less than FreeCAD Adaptive leaves, see
  ``benchmarks/bench_vs_freecad.py``).
* **A pass ends** when the next point would leave the tool-centre region (pocket shrunk by r), when
  even the hardest left turn cannot bring the engagement down to the target, or when the tool has
  run ``1.5 r`` through air (that air tail is dropped; a pass that met no material at all in a band
  narrower than the tool is tried once more with ``3.5 r``, kept if it removes 0.2 a_e per mm: the
  way to the face of a neck is a loop mostly through air). Kim & Yang's insertion idea -- insert a path only where the regular
  pass would leave material -- becomes the start rule: the next pass starts on the band of
  cleared-region points whose disk just touches material (distance to the nearest material = r)
  that is *nearest through cleared area* to where the tool is, at that band's **upstream end**
  (:func:`.links.upstream_end`: walked against the climb direction, up to ``upstream_start_frac`` r
  coarse cells, to a wall, a ban or a bend), heading along the material boundary; the controller
  then turns into the material and settles at ``theta`` (no perpendicular approach: no slotting).
  A pass so started runs the whole boundary, as FreeCAD Adaptive's long arcs do, where a start at
  the nearest point beside a wall hooked off it after a few mm (one link at depth each: two
  machine stops). A pass that would cut less than ``wall_sliver_max_area_rae`` r a_e, all of it
  within reach of a finishing lap still to come, is undone with its link (the lap takes that cusp).
  Where the tool-centre region is narrower than the turning circle and a pass runs straight into
  air, it is started once the other way round (the face at the end of a band lies behind it).
* **Links** (Adaptive2d's ``keepToolDown`` linking through cleared area): the start of the next
  pass is found by a Dijkstra search over the cells whose tool disk is free of material (distance
  field of the stock on a coarse grid of min(0.2 mm, r/10) cells, capped just above r and
  recomputed only in the window the last change of the stock can reach) inside the tool-centre
  region, starting where the tool is;
  the cell route is shortened to straight chords that stay in that free set and written as rapids
  at depth marked ``cleared`` (the ToolPath's proof column; FreeCAD writes its keep-tool-down links as G0 too; the evaluator
  counts any rapid that removes material) or, with ``rapid_links=False``, as feed moves (``link``,
  link feed). A start whose pass meets no material at all (dropped) keeps no link either
  (``drop_idle_links``): the next start is sought from it, as if the tool had gone there, and linked
  to from where the tool is (the same passes, shorter links: a comb's fingers were wandered by G0).
  When the search finds nothing from there the link to it is made after all, so that what follows
  is chosen from the same point. A pass that cuts too little bans the cells within r of its start (r/2 where it left the
  region at once, or in the second chance: before a lift the bans are lifted once). Before the tool
  lifts for a new entry, the *rescue* (``_Level.rescue_start``) tries the starts inside those bans
  that lie farther than ``failed_start_ban_frac`` r from every failed start, where solid material lies
  within reach (the stock eroded by one pixel: no wall skins or seams) and the band is at least
  0.2 r half-wide, heading along that material (turned 30 and 60 deg towards it when that pass
  removes nothing): the end of a slot opening into a bulb is cut from the slot, not by a second
  helix. Only when no free route exists (a disjoint region, material closing the way) does the tool
  retract, rapid at clearance and enter again.
* **Remnants**: where no border cell can be reached through cleared area but a free-standing remnant
  of material is left (a pillar the passes around it could not take), one straight feed move from a
  free point to where the tool disc holds the whole remnant takes it, if the remnant lies within
  r sin(theta/2) of its centre (the move then meets it over at most theta) and the move meets no
  other material; otherwise the tool enters there by helix. A place entered before is banned.
* **Entries**: a pre-drilled start hole is used as it is (plunge into the hole, air); otherwise a
  helix (the package's one helix generator, ToolPathBuilder.helix on a helix_ring: counter-clockwise
  chords within 0.01 mm of the circle, 5 deg ramp like FreeCAD's default) at the point of the tool-centre region
  farthest from its boundary (the centre of the largest inscribed circle), radius
  ``min(0.75 r, 0.9 x inscribed radius - h)`` (FreeCAD's is 0.75 r too), then a floor circle;
  each entry's engagement is reported apart by the evaluator. A place that allows less than
  ``0.1 r`` (a helix of a few hundredths of a mm is a plunge) is banned unless its part of the
  tool-centre region is that narrow everywhere. In a band of tool-centre half-width below 0.2 r
  (no pass turns there, the narrow regions' trochoid would crawl) the entry is a **ramp** along the
  longest straight segment of the band through the place (``entries.ramp_entry``: the package's one
  ramp generator, ToolPathBuilder.ramp, in an even number of legs at the helix angle or shallower,
  so that it ends at depth where it began -- a return at depth through the wedge under the first leg
  would slot at 180 deg; its ends at the exact tool-centre limit): one entry for the band where helix after helix was
  entered about r apart; its band counts as entered (the wall skins are the finishing laps').
* **Finish**: one contour pass along every ring of the tool-centre region (outer rings
  counter-clockwise, islands clockwise: climb milling), started where the ring is already free of
  material, takes the thin rests the passes left against the walls (thinner than ``a_e`` where the
  passes reached the walls); it runs under the same engagement control with the target raised by
  ``finish_margin_deg`` (4 deg: the simulator measures up to ~3 deg more than the planning stock on
  the thin wall rests, and theta + 10 deg is the bound) so that the corner wedges are peeled instead
  of refused; the lap starts at the free ring point nearest the tool. A lap that stops short (the
  control finds no way on at the finish target, at a corner) is resumed at the first free ring point
  r past the stop, linked through cleared area, up to ``finish_resume_laps`` times a ring. A ring's
  first lap runs the whole ring (``finish_full_first_lap``): it is the only move on the true
  tool-centre limit, and the sub-pixel skin the passes leave there is not on the planning stock.
  The further laps (while a rest deeper than max(0.3 mm, a_e/4) is left) cover only the shortest arc
  of the ring holding those rests, from the free ring point upstream of it (``finish_arc_laps``).
  After the laps, each run of the ring where material deeper than 1.5 h is left in reach (the corner
  wedges the control rounds) gets local laps from the last free point before it to r/2 past it,
  linked at depth, while at least ``finish_peel_min_mm2`` is left there (``finish_peel_rounds``).
  Points planned within 2 h of
  the wall are snapped onto the nearest wall point (1 um inside
  the 64-segment tool-centre limit); the lap is replayed on the stock (chords the snap made longer
  than 1.5 ds sampled along their length) and a snapped point whose engagement would exceed theta +
  2 deg, at the 1/2 level or with slivers counted, keeps its planned place. Each part of the
  tool-centre region is finished before the tool leaves it (no extra lift). Up to ``clean_rounds``
  further rounds of passes and finishing take material the bans left (only while some lies deeper
  than 2 coarse cells inside the tool's reach).
* **Lifts** are G0 straight up (as FreeCAD's); links at depth are G0 only where no material pixel
  lies within r + h/sqrt(2) of the chord (``rapid_links``) on the *rapid stock*: the same discs cut
  with radius r - h/sqrt(2), so that the tool disc of such a chord is truly swept (sub-pixel cusps
  between passes, which the planning stock cannot show, never meet a rapid). A chord on the line of
  the wall-following pass that left the wall skin is tangent to it and never proven: an air run
  along it is moved 2 h to its left (away from the material on the pass's right) with feed legs
  off and back on the line, and a link from or to a wall point gets a feed leg of 2 h or 4 h, where
  that makes the rest provable (:func:`bow_runs`, :func:`rapid_legs`); a chord still not proven is
  split, every stretch of at least ``rapid_piece_min_mm`` with no such pixel a G0 and the rest at the
  link feed (:func:`rapid_pieces`: the exact chord intervals each pixel blocks).
  :func:`unproven_rapids` (``audit.py``) proves every G0 at depth again from the written path alone
  (a rapid stock rebuilt from its moves in their order); on a sound plan it finds none, and the tests
  hold the planner to it (it found the join of a link's last G0 to its pass writing that G0 from the
  cut boundary, the feed leg the proof assumed dropped).
* **Narrow regions** (``narrow``; issue 29 item 5): where the tool-centre region is at most 0.75 r
  half-wide (a pocket <= 1.75 D: channels, slots, necks, comb fingers) along at least 3 r of its
  medial axis, the passes cannot turn; such a region is hidden from them and cut instead by Jacsó's
  constant-engagement trochoid (Thesis IV) laid along its Voronoi medial axis at the same theta,
  entered from cleared area at a mouth (no lift) or by a helix and a spiral out at a closed end; the
  regions cut so are listed in ``info["narrow_regions"]`` and in the program header. The pattern is
  laid open loop, made for a straight slot of the narrowest width nearby; at a channel's sharp corner
  or a junction (letter pockets, ``benchmarks/bench_letters.py``) it can exceed the bound, and
  ``plan``'s last re-plan of such a level replays each period on the planning stock, laying it closer
  or ending the trochoid where its engagement would exceed theta + 4 deg (``narrow_level.PeriodCheck``,
  ``retry_narrow_check_deg``; the notes say where).
* **Sharp corners on the exact stock** (``corners``; session 19): at a convex vertex of the
  tool-centre region (a pocket corner sharper than the tool) the rim of a tool moving into the corner
  meets the rest there over up to the angle the limit turns (90 deg in a square corner) however thin
  the rest is, and the pixel stock reads a rest thinner than a pixel as a fraction of material: short
  passes that took a square corner micrometres at a time read theta + 4 to 6 on the r/30 dixel and
  theta + 13 on the exact stock (corpus rectilinear_1, comb_1). Every pass and lap point within
  ``corner_reach_h`` h of such a vertex whose planning engagement comes within
  ``corner_screen_deg`` of the cap is measured on polygons (the pocket less the discs of every move
  the level made at depth, chips of 2 um and more: :func:`cnclab.simulation.vector.engagement_along`),
  and the pass or lap ends before the first point above theta + ``corner_exact_cap_deg`` (8): the
  corner rest stays, counted as uncut (``info["corner_cuts"]``: how many were so ended).
* **Refusal**: a pocket in which the tool does not fit (the tool-centre region is empty or thinner
  than the resolution) raises ValueError naming the job source and the reason.

Package layout (one role per module)
-----------------------------------
``corners`` the sharp-corner check on the exact stock; ``stock`` pixel-stock kernels; ``control`` the engagement controller (heading search, guard, a
pass); ``links`` links at depth and the rapid proofs; ``grid`` the per-level state (stocks, masks,
free field); ``entries`` the entry choice, helix and bans; ``finish`` the wall-following laps;
``params`` :class:`AdaptiveParams` (every tuning constant with its unit and reason); ``narrow`` the
narrow regions (detection, medial axis, the trochoid along it); ``narrow_level`` those regions at
one level (their order, their cut, the period check); ``planner`` the
level planner object (``_Level``) whose ``run`` is the loop below, and :func:`adaptive_clearing`.

The loop of one level (``_Level.run``)::

    hide the narrow regions (narrow_level.LevelRegions)
    enter() or a narrow region by helix       # helix at the widest place with material in reach
    for each round (0, then up to clean_rounds clean-up rounds, each kept only if it pays):
        repeat:
            link_to(next border cell)         # Dijkstra through free cells, chords as G0 where proven
                                              # (not run when the pass from there meets no material)
            if no border cell is reachable:
                narrow_level.next_region()          # a trochoid from a reachable mouth, or (nothing left) by helix
                sweep_remnant() or finish_if_done() and enter() again, or stop
            else:
                clearing_pass()               # steps at theta until the wall, air or the guard ends it
        finish_part(each part)                # wall-following laps at theta + finish margin
    retract()
    note_unvisited()                          # parts no entry could open: left, stated
    note_thin_strips()                        # strips only slotting clears (slot_narrow off): stated

A part of the tool-centre region no entry opens, or one narrower than the tool whose rings hold no
free place when its finish starts, is left and stated (``info["left_parts"]``, the notes, the program
header); :func:`cnclab.toolpath.planners.plan` measures what it leaves (uncut report, issue 28 item 1).

Levels (a pocket deeper than ``a_p``) are planned one by one by
:func:`cnclab.toolpath.planners.plan` and joined by :func:`cnclab.toolpath.levels.join_levels`.
``plan`` also checks the promise on every level (engagement max <= theta +
``AdaptiveParams.promise_max_deg``, measured by the evaluator at r / 30,
:func:`cnclab.toolpath.planners.adaptive_engagement_check`): a level beyond it, or within
``written_margin_deg`` (1 deg, what the arc fit of the written program may add) below it, is planned
again (the tighter sliver guard, the nearest pass starts, ...); a level still beyond the bounds is
measured again at r / 60, r / 120, r / 240 while it stays beyond them (a sliver thinner than a dixel
row can read high at r / 30), and the highest samples of every measure on the exact vector stock
(:mod:`cnclab.simulation.vector`; a dixel can read low too): a maximum beyond the promise on the
finest dixel or on the vector stock is refused unless ``allow_engagement_breach``
(``AdaptiveParams.refine_*``).

>>> import numpy as np
>>> from shapely.geometry import box
>>> from cnclab.toolpath.job import Job
>>> from cnclab.toolpath.path import Tool
>>> job = Job(box(0, 0, 24, 18), Tool(6.0), theta_deg=60, a_p=1, feed_mm_min=255, spindle_rpm=6000)
>>> tp = adaptive_clearing(job)
>>> sorted(set(tp.kinds()))
['cut', 'helix', 'link', 'plunge', 'rapid']
>>> bool(np.all(tp.xyz[tp.is_kind("plunge"), 2] >= 0.0))   # the only plunge ends on the stock top (air)
True
"""
from __future__ import annotations

from .audit import unproven_rapids
from .params import AdaptiveParams
from .planner import PlanningError, adaptive_clearing, plan_job

__all__ = ["adaptive_clearing", "plan_job", "PlanningError", "AdaptiveParams", "unproven_rapids"]
