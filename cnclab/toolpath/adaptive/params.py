"""The adaptive planner's tuning constants as one documented object (:class:`AdaptiveParams`).

Every field states its unit and why it has its value; the defaults are the values the planner was
measured with (``benchmarks/bench_vs_freecad.py``, ``benchmarks/bench_random_pockets.py``): changing one
changes the programs.

>>> AdaptiveParams().helix_radius_frac, AdaptiveParams(clean_rounds=0).clean_rounds
(0.75, 0)
"""
from __future__ import annotations

import dataclasses

from ..path import APPROACH_MM

__all__ = ["AdaptiveParams"]


@dataclasses.dataclass(frozen=True)
class AdaptiveParams:
    """Tuning constants of :func:`cnclab.toolpath.adaptive.adaptive_clearing` (units in each comment)."""

    #: deg: the sliver guard of the clearing passes holds the engagement with any material counted
    #: within theta + guard_deg (a crescent the 1/2-level contour misses; the bound promised is +10)
    guard_deg: float = 5.0
    #: deg: the finishing laps' guard, at least this over theta (the laps peel corner wedges)
    finish_guard_deg: float = 7.0
    #: rounds: further rounds of passes and finishing for what the guard and the bans left
    #: (each kept only when it pays, see ``clean_round_min_yield``)
    clean_rounds: int = 2
    #: fraction: a clean-up round is kept when it removes at least this share of what the nominal
    #: cut (a_e wide at the cutting feed) removes in the feed time it adds
    clean_round_min_yield: float = 0.1
    #: deg: helix ramp angle of an entry (FreeCAD Adaptive's default 5 deg)
    helix_angle_deg: float = 5.0
    #: fraction of r: entry helix radius (FreeCAD Adaptive's 0.75 r)
    helix_radius_frac: float = 0.75
    #: fraction of r: the smallest helix accepted where the part of the tool-centre region is wider (a
    #: helix of a few hundredths of a mm is a plunge: such a place is banned, reached from elsewhere)
    helix_min_frac: float = 0.1
    #: whether the wall-following finish laps run (off: roughing only)
    finish: bool = True
    #: whether narrow regions (tool-centre half-width <= narrow.NARROW_HALF_WIDTH_FRAC r) are cut by
    #: Thesis IV's trochoid along their medial axis before the passes (issue 29 item 5, narrow.py)
    narrow_trochoid: bool = True
    #: whether the strips of the tool-centre region thinner than 2 x narrow.NARROW_MIN_HALF_WIDTH_FRAC r
    #: (a slot less than 0.4 r wider than the tool: no step under the engagement bound enters it) are cut
    #: by slotting along their medial axis, their engagement (up to 180 deg) stated in the notes
    #: (finish.slot_strips; off: they are left, and ``plan`` reports them as uncut)
    slot_narrow: bool = False
    #: mm^2: without slot_narrow, a strip that slot_narrow would slot and that keeps more material than
    #: this within the tool's reach after the finish is stated with the remedies (finish.note_thin_strips;
    #: the floor of the plan's uncut limit, coverage.uncut_limit_mm2)
    thin_strip_note_mm2: float = 1.0
    #: fraction of r: a part of the tool-centre region whose inscribed radius is below this and whose
    #: rings have no place free of material when its finish starts (it was entered, if at all, by a helix
    #: smaller than its ring) gets no finishing lap: the link to the ring and the lap would cut its rest
    #: at the link feed (dwg_many_holes_inner, D 4: theta + 71.7 deg on a link after a 0.06 mm helix,
    #: + 49.4 after a 0.1 mm one; fuzz_random_pockets --seed 1, 100 pockets: 2 above the bound, theta +
    #: 24.1 on a link, now 0; "free" as for every link end: D >= r_free). Left uncut and stated
    #: (finish._leave_part); ``plan`` measures it. Unless the tool stands in the part and the step onto
    #: its ring stays within the finish target (a skin along the walls: finish._skin_step)
    lap_skip_inscribed_frac: float = 1.0
    #: whether such a part gets its lap from where the tool stands when the step onto its ring stays
    #: within the finish target (finish._skin_step; ``info["skin_steps"]`` counts them). ``plan`` plans
    #: a level beyond the engagement bounds again without them first (dwg_many_holes_inner: with them a
    #: link later in the level read theta + 43.5 deg, without them theta + 8.0)
    finish_skin_step: bool = True
    #: deg: the finish is held at theta + finish_margin_deg (the simulator measures up to ~3 deg more
    #: than the planning stock on thin wall rests; theta + 10 is the bound). Was 6: above theta + 5 by
    #: design, the laps alone put 2.0 % (spiral_0) and 1.27 % (rectilinear_0) of the cutting length
    #: above theta + 5 (the promise: <= 0.5 %); at 4: 0.015 and 0.23 %, uncut +0.0 / +0.5 mm^2
    finish_margin_deg: float = 4.0
    #: deg: a finishing point snapped onto the wall keeps the snap only while its engagement stays
    #: within theta + this (random pockets, theta 40, r 2 mm: max 52.2 deg at +7, 46.8 at +2)
    finish_snap_deg: float = 2.0
    #: laps: at most so many wall-following laps per ring (a further lap only while material deeper
    #: than max(0.3 mm, a_e/4) is left along the ring)
    finish_laps: int = 3
    #: laps: a lap that stops short of its run (the control finds no way on at the finish target, at
    #: a corner) is resumed at the first free ring point at least r past where it stopped, at most
    #: this many times per ring (0: not resumed: the ring's rest was left, skins thinner than
    #: ``finish_rest_min_mm`` too -- star_1 with the upstream starts: a lap of 8 of its 129 mm)
    finish_resume_laps: int = 6
    #: passes: the most clearing passes per round (a bound against endless re-entry)
    max_passes: int = 5000
    #: deg: a step whose front half meets less material than this is air
    air_deg: float = 0.5
    #: samples: arc samples of the front half-circle per engagement evaluation
    n_samples: int = 90
    #: deg: the hardest turn of the heading search per step (left away from the material, right into it)
    max_turn_deg: float = 90.0
    #: fraction of r: the tightest right-turn radius (the curvature limit of the passes)
    turn_radius_frac: float = 0.25
    #: fraction of r: a pass ends after so much air (its air tail is dropped)
    air_stop_frac: float = 1.5
    #: fraction of r: the air allowance of the second try of a pass that met no material in a band
    #: narrower than r (the way to the face of a neck is a loop mostly through air)
    narrow_air_stop_frac: float = 3.5
    #: fraction of a_e: that second try is kept only where it removes this much per mm of its length
    #: (random pockets: 9 % fewer entries for 1 % more program time)
    narrow_min_yield: float = 0.2
    #: fraction: the entry helix radius is at most this share of the room at the entry point, less h
    #: (the helix disc stays clear of the walls by a tenth of the room)
    helix_room_frac: float = 0.9
    #: mm: the smallest helix radius ever accepted (below it the helix is a plunge)
    helix_min_mm: float = 0.02
    #: fraction of r: a place too narrow for a helix, or entered before, bans the cells within this
    #: radius (no endless re-entry at one spot)
    entry_ban_frac: float = 2.0
    #: mm: an entry rapids down to this height above the level's top before its feed descent (the
    #: package's one approach height, :data:`cnclab.toolpath.path.APPROACH_MM`, as ToolPath.from_segments)
    approach_above_mm: float = APPROACH_MM
    #: mm and fraction of a_e: a further finishing lap runs only while material deeper than
    #: max(finish_rest_min_mm, finish_rest_frac_ae a_e) is left along the ring
    finish_rest_min_mm: float = 0.3
    finish_rest_frac_ae: float = 0.25
    #: deg (None: off, the default): each period of a narrow region's trochoid is replayed on the
    #: planning stock and laid closer (down to a tenth of its step), or ends the trochoid, where its
    #: engagement exceeds theta + this (narrow_level.PeriodCheck). The open-loop pattern is made for a
    #: straight slot; at a channel's sharp corner or junction it met up to theta + 29 deg (letter
    #: pockets, benchmarks/bench_letters.py). Not the default: on the corpus's 1.5 D channels, which the
    #: open loop holds, it lays periods closer at width changes and bends (+9 to +22 % program time on
    #: 4 of 8, measured at 4 deg); ``plan``'s re-plan of a level beyond the bounds turns it on last
    #: (``retry_narrow_check_deg``)
    narrow_check_margin_deg: float | None = None
    #: whether a narrow part's medial tree gives its branches their own trochoid (narrow._branch_axes:
    #: the middle bar of an E, the far half of a T's bar; each entered from the trunk's slot), else
    #: only its longest path is, and the passes take the branches. Not the default (as the check);
    #: ``plan``'s last re-plan of a level beyond the bounds turns it on with the check
    narrow_branches: bool = False
    #: whether a ring's first finishing lap runs the whole ring (else it ends finish_run_on_frac r past
    #: the last ring point the planning stock shows material in reach of): it is the only move on the
    #: true tool-centre limit (passes stay h/sqrt(2) inside it), so it alone takes the sub-pixel skin
    #: along walls the planning stock does not show (islands_5: 2.5 mm^2 of pixel skins in the
    #: evaluator along a 42 mm wall the lap had skipped)
    finish_full_first_lap: bool = True
    #: rounds: after the full laps, local laps over each run of the ring where material is left deeper
    #: than finish_peel_rest_h h inside the tool disc (corner wedges: the control peels one layer a
    #: lap), from the last free point before the run to finish_peel_run_on_frac r past it (0: none)
    finish_peel_rounds: int = 4
    finish_peel_rest_h: float = 1.5
    finish_peel_run_on_frac: float = 0.5
    #: mm^2: a run is peeled only while this much material is left within the tool's reach of it
    #: (a tenth of the 0.5 mm^2 a job may leave beyond FreeCAD's in issue 29's uncut target)
    finish_peel_min_mm2: float = 0.05
    #: fraction of r: a finishing lap runs on this far past the last ring point with material in reach
    finish_run_on_frac: float = 2.0
    #: whether a ring's laps after the first (and a first lap that is not a full one) cover only the
    #: shortest arc of the ring holding every point with a rest deeper than max(finish_rest_min_mm,
    #: finish_rest_frac_ae a_e) within reach (the ring minus its longest gap): they start at the free
    #: ring point nearest upstream of it and end finish_run_on_frac r past its last point. Else they
    #: start at the free point nearest to the tool and end past the last point with any material in
    #: reach, and a rest just behind the tool was reached the long way round (dwg_polylines: laps 2
    #: and 3 ran 226 and 240 mm of a 241 mm ring for a rest in one corner). Corpus: 8 of 62 jobs
    #: change, program time 0.96-0.99 x (dwg_forms_3 1.060 -> 0.990 x FreeCAD's); the long laps also
    #: shaved micrometres off wall skins no pixel shows: uncut +0.3 and +0.5 mm^2 on two jobs
    finish_arc_laps: bool = True
    #: pixels (h): finishing points planned within this distance of the wall are snapped onto it
    finish_snap_band_h: float = 2.0
    #: rounds: replays of the snapped lap (a point kept at its planned place changes what the later
    #: points meet)
    finish_replay_rounds: int = 6
    #: steps: the most steps of one clearing pass
    pass_max_steps: int = 20000
    #: moves and stride: a link with no straight chord out retraces at most so many of the tool's own
    #: moves, trying every ``retrace_stride``-th point
    retrace_max_moves: int = 200
    retrace_stride: int = 5
    #: r h (mm^2): a pass removing less than this bans its start cell
    pass_min_removed_rh: float = 0.2
    #: coarse cells: a cell is free when its distance to material is at least r + this many cells
    #: (the cell half-diagonal margin of the coarse grid)
    free_margin_hc: float = 0.75
    #: mm: the coarse cell of the free-space search is about ``min(coarse_cell_mm, coarse_cell_max_r r)``,
    #: a whole number of pixels, at least one. Small tools (r < 2 mm) had cells of one pixel (r/60, the
    #: pixel ``plan`` plans at: 36x the cells of r/10), and the Dijkstra searches and the distance field
    #: took 60-80 % of the plan (star_1, islands_0: 4.5 and 17 s); at r/10 they plan 3-9x faster, with
    #: fewer passes and shorter programs. r/20 (D4-D6 tools changed too) was worse on the corpus: uncut
    #: <= FreeCAD's + 0.5 mm^2 on 91.9 % of the jobs, plan time 3.18 x FreeCAD's on the median job
    #: (closing note of 2026-11-26, session 10)
    coarse_cell_mm: float = 0.2
    #: fraction of r: the most the coarse cell may be (see ``coarse_cell_mm``)
    coarse_cell_max_r: float = 0.1

    # -- pass loop and narrow regions (helper "passes", issues 29/24: program time) ---------------
    #: fraction of r: a pass that left the tool-centre region at its first step
    #: bans the coarse cells within this (Chebyshev) distance of its start cell; any other pass that
    #: removes (almost) nothing bans those within r. Was r for both: at the fillet where the arm of an
    #: L (a band about a tool radius wide) leaves the wide part, one such start banned the arm's face,
    #: and its end was taken by a lift and a helix entry (rectilinear_0: 0.665 -> 0.588 min); in the
    #: second chance (second_chance_min_yield) every failed start bans this much
    pass_ban_frac: float = 0.5
    #: pixels (h): a narrow region's mouth is entered from cleared area (narrow.py) at a free point
    #: from which the first periods' swing across the axis meets no material pixel centre within
    #: r + this (a capsule). Was +1: the pixel centres along the walls that no pass clears (a tool
    #: centre on the tool-centre boundary, itself shrunk by h/sqrt(2), leaves them within about h)
    #: were always within reach, so every open region was entered by a lift and a helix at its closed
    #: end (tapered_channel_2: 2.415 -> 2.29 min at +0.5). +0.5 is measured, not derived: at -1
    #: (r - h) slot_bulbs_2 reaches theta + 22 deg (the mouth point then chosen has its first return
    #: meet material), at 0 the islands-neck case of test_adaptive_clearing theta + 11 in a later pass
    mouth_capsule_margin_h: float = 0.5
    #: pixels (h): while a narrow region waits for its trochoid (narrow_level.LevelRegions), the material
    #: only its tool centres reach is hidden from the passes; "only" means farther than r + this from
    #: the rest of the tool-centre region. Was r (0): a pass's tool centre may stand up to a pixel's
    #: half-diagonal inside the region's raster, and the hidden crescent its circle then meets, thin
    #: but wide in angle, was engagement the planner did not see (dwg_concave_hole, D 8: theta + 14.8 deg
    #: measured where the planner saw theta - 1.2; program stock 52.0 deg at that step)
    narrow_hide_margin_h: float = 2.0
    #: fraction of a_e: before the tool lifts for another helix entry (at the entry feed, a slot's
    #: chip), the pass bans are lifted once (a second chance: the places a failed start closed with
    #: its r-wide ban are tried again through cleared area, a failed start then banning only
    #: pass_ban_frac r); a pass of that second chance is kept only where it removes this much area
    #: per mm of its length (a_e wide: the nominal cut), else it and its link are undone. Measured:
    #: dwg_example008 3.26 -> 2.16 min (12 -> 3 entries), regions_1 3.21 -> 2.82; without the
    #: yield rule the slivers it takes cost more than they save (dwg_polygons +5.6 %)
    second_chance_min_yield: float = 0.3
    #: fraction of a_e: a clearing pass that removes less than this area per mm of its length (a_e
    #: wide: the nominal cut) only cuts slivers (a crescent left between passes, a corner rest): it
    #: is undone with its link and its start banned, the slivers left to the finish laps and the
    #: clean-up rounds -- except while a narrow region with an open end waits (narrow.py): its mouth
    #: is entered from cleared area only where the first periods' swing meets no material, slivers
    #: and the wall skins such passes leave included (tapered_channel_2: else a lift, a helix at the
    #: closed end and 0.71 % of the samples above theta + 5). Measured (program time, min): star_3
    #: 0.847 -> 0.809 (uncut 3.40 both; FreeCAD 8.99 mm^2), islands_3 1.874 -> 1.840, rectilinear_2
    #: 0.571 -> 0.561 at 0.2. OFF by default (0): on the whole corpus it left spiral_0 11.4 mm^2 uncut
    #: (1.4 without; FreeCAD 1.0) and dwg_example008_all 11.2 (1.5; FreeCAD 4.9): slivers of long
    #: channels that neither the finish laps nor the clean-up rounds take. A budget on the area the
    #: undone passes leave (0.3 or 1 mm^2 a level) kept spiral_0 covered but also removed the gain
    sliver_pass_min_yield: float = 0.0
    #: r a_e (mm^2): a clearing pass that removes less than this area, all of it within reach of a
    #: finishing lap still to come (every removed pixel within r - 3 h of the tool-centre limit, the
    #: ring the laps follow 1.5 h inside it), is undone with its link and its start banned: the lap
    #: takes that wall cusp in its one continuous run, where the pass cost a link at depth (two stops
    #: of the machine) for a sliver. Measured on the bench pockets (machine time, small VMC, issue 24):
    #: see the closing note of the session; 0 turns the rule off
    wall_sliver_max_area_rae: float = 0.25
    #: mm: a link chord that no single G0 is proven for (links.rapid_legs) is split: each stretch of at
    #: least this length with no material pixel within r + h/sqrt(2) becomes a G0, the rest stays at the
    #: link feed (links.rapid_pieces). 2 mm: on the small VMC (2.5 m/s^2) a G0 of 2 mm from stop to
    #: stop takes 0.057 s, the same length at 1500 mm/min 0.080 s; shorter pieces would not pay their
    #: stops (1 mm: 0.040 against 0.040 s). 0: off (star_2, D 3 mm: 126 mm of such chords at feed)
    rapid_piece_min_mm: float = 2.0
    #: a link to a pass start whose pass emitted nothing (it ran into air and was dropped) is rolled
    #: back with it; the next start is sought from that start, as before, and linked to from the tool's
    #: point (the same passes, shorter links). False: kept (a comb, D 4 mm: a chain of such links ran
    #: 750 mm of G0 through every finger)
    drop_idle_links: bool = True
    #: fraction of r: the next pass starts at the upstream end of the band of starts through the
    #: nearest one (:func:`.links.upstream_end`), at most this far up it (0: the nearest)
    upstream_start_frac: float = 2.5
    #: fraction of r: ... and not for a pass that runs where the tool-centre region is less than this
    #: half-wide (Grid.half_width): in a band narrower than the tool every pass cuts little and they are
    #: the way in (a 7 mm channel, D 6, of test_adaptive_links: 4 entries instead of 2 and 0.71 min
    #: instead of 0.57 when its passes were undone)
    sliver_min_half_width_frac: float = 1.0

    # -- links and entries (helper "links", issue 29: lifts) --------------------------------------
    #: fraction of r: before an entry (a lift), once the second chance has found no start either, the
    #: starts within the pass bans that lie farther than this from every failed start (banned_fine)
    #: are tried (:meth:`_Level.rescue_start`): at the end of a slot opening into a wider part the
    #: passes from its upper corner head out of the region, and the bans cover the slot end
    failed_start_ban_frac: float = 0.25
    #: passes: that rescue gives up after so many failed passes in a row (each a Dijkstra search over
    #: the free cells; a ring of seams the engagement does not see can hold hundreds of such starts)
    rescue_max_fails: int = 16
    #: fraction of r: ... and tries only starts with solid material (:func:`.links.solid_within`, at least
    #: a pass's minimum removal) within this reach (the wall skins a slot's trochoid leaves are none)
    rescue_reach_frac: float = 1.5
    #: deg: a rescued start (tangent to the solid material, on the right) whose pass removes nothing is
    #: tried again turned so far towards the material (a mouth narrower than the turning circle: the
    #: tangent heading leaves the region before the pass can turn into the face)
    rescue_turns_deg: tuple = (30.0, 60.0)
    #: fraction of r: ... where the tool-centre region is at least this half-wide (Grid.half_width;
    #: narrower, no pass can turn: the crawl limit of the narrow regions' trochoid,
    #: narrow.NARROW_MIN_HALF_WIDTH_FRAC; a channel that narrow is left to the entries)
    rescue_min_half_width_frac: float = 0.2
    #: fraction of r: an entry place in a band of tool-centre half-width below this (no pass can turn
    #: there, and the narrow regions' trochoid would crawl: narrow.NARROW_MIN_HALF_WIDTH_FRAC) is entered
    #: by a ramp along the band (entries.ramp_entry: one entry for the band where helix after helix was
    #: entered about 2 r apart); level 0 only (a deeper level's ramp start would need the level above's
    #: proof)
    ramp_half_width_frac: float = 0.2
    #: fraction of r: ... when the straight segment through the place inside the band, with material
    #: within reach all along, is at least this long (else the helix)
    ramp_min_frac: float = 2.0
    #: ... each way at most this x the 5 deg ramp length of the level (a longer band: one shallower leg)
    ramp_max_frac: float = 4.0
    #: deg: the directions tried for that segment
    ramp_direction_step_deg: float = 5.0
    #: fraction of the helix's disc (radius r + helix radius): a helix entry that removes less than
    #: this and from which no pass start outside the bans is reachable is undone and its place banned
    #: (dwg_forms_4: three entries in a row, each followed by no pass, on slivers the passes had failed on)
    idle_entry_frac: float = 0.1

    # -- the promise, checked per job (issue 28 item 2) -------------------------------------------
    #: deg over theta: the engagement maximum the planner promises (the issue-29 target), measured on
    #: every planned level by the package's one evaluator (cnclab.toolpath.evaluate, the dixel
    #: stock the corpus benchmark scores) in ``plan``'s adaptive registration: a level beyond it is
    #: planned once more (``retry_guard_deg``), then stated in the result and the program header, and
    #: refused unless ``allow_engagement_breach``
    promise_max_deg: float = 10.0
    #: fraction of r: the check's evaluation dixel (the corpus benchmark's r / 30, so that the check
    #: and the benchmark agree; a coarser one misses peaks: neck_3 reads theta + 2.8 at r / 20 where
    #: r / 30 reads + 11.2), at least ``check_min_resolution_mm``; 0: no check
    check_resolution_frac: float = 1.0 / 30.0
    #: mm: ... and never finer than this (a check stays affordable for the smallest tools). 0.02: the
    #: check measures at r / 30 down to r = 0.6 mm, as the benchmarks do (min(0.05, r / 30) since
    #: session 11); at 0.05 a 1 mm tool was checked at r / 20, where random pocket 76:15 read under
    #: theta + 9 and the benchmark's r / 30 read theta + 10.35
    check_min_resolution_mm: float = 0.02
    #: deg: the retry of a level beyond the promise plans with the clearing passes' sliver guard at
    #: theta + this (tighter than ``guard_deg``: the passes turn away from wall skins and crescents
    #: thinner than a pixel, which the planning stock under-counts); the retry is kept when its maximum
    #: is lower. Measured: spiral_0 theta + 11.1 -> + 5.5, neck_3 + 11.2 -> + 4.4, regions_3 + 10.0 ->
    #: + 8.6; as the default it cost up to 1 % program time and 1.2 mm^2 uncut (dwg_concave_hole)
    retry_guard_deg: float = 3.0
    #: deg over theta: the narrow-region period check (``narrow_check_margin_deg``) of the last re-plan
    #: of a level beyond the bounds (after the tighter guard, the nearest starts and both). 4 deg: the
    #: check's replay is the planning stock's model, which measures up to ~3 deg less than the evaluator
    #: (as the finish's ``finish_margin_deg``); at 6 a letter T (D 3 mm, theta 22.9) kept 0.55 % above
    #: theta + 5 deg
    retry_narrow_check_deg: float = 4.0
    #: deg: the finish margin (``finish_margin_deg``) of the very last re-plan of a level still beyond
    #: the bounds after every other retry, with the tighter guard (``retry_guard_deg``): a breach on a
    #: finishing lap. Random pocket 86:11 (theta 75, r 5 mm, tests/fixtures/adaptive): theta + 13.4 on
    #: a clearing pass, + 10.1 on a lap with the tighter guard, + 7.4 with the laps at 2 (or 3) deg.
    #: Not the default margin: the corpus was measured at 4; a retry changes only levels beyond the bounds
    retry_finish_margin_deg: float = 2.0
    #: deg over theta and % of the cutting length: with the maximum, the rest of the issue-29 bounds
    #: (p95 <= theta + 2, share above theta + 5 <= 0.5 %); a level beyond any of them is planned again
    #: (``retry_guard_deg``, then with the nearest pass starts, ``upstream_start_frac`` = 0, then
    #: both) and the first plan within all three kept, else the one with the lowest maximum. Only
    #: the maximum is refused (``promise_max_deg``); the others are stated in ``engagement_check``.
    #: The upstream starts hold them on 67 of 71 corpus jobs; on dwg_concave_hole (theta + 12.2),
    #: neck_3 (+ 10.03) and tapered_channel_2 (0.71 % above theta + 5) the nearest starts do
    promise_p95_deg: float = 2.0
    promise_share_pct: float = 0.5
    #: deg: the margin the check keeps below ``promise_max_deg`` for the written program: a level whose
    #: planned maximum lies within it of the promise is planned again (``_retries``) as one beyond the
    #: bounds, and refused only beyond the promise itself. The arc fit moves every point by up to its
    #: tolerance (5 um) and the r / 30 dixel re-draws the peak: over the corpus the written programs'
    #: maximum lies 0.8 deg above the planned paths' on average, and dwg_forms_3 read theta + 9.24
    #: planned, + 10.06 written (session 11)
    written_margin_deg: float = 1.0
    #: a level still beyond the bounds after every retry is measured again at half the check's dixel,
    #: and again at half that while it stays beyond them, at most this many times (``planners._refined_check``;
    #: the finest measure is the verdict). The evaluator converges as its dixel shrinks, and a wall skin
    #: or crescent thinner than a dixel row reads as contact over up to acos(1 - h / r) on each side:
    #: letter E 32:8 (r 5 mm, theta 26.7, a pass ending at the wall of a 1.77 D bar) reads theta + 13.5,
    #: + 10.9, + 11.1 and + 7.1 at r / 30, 60, 120 and 240 (session 18)
    refine_halvings: int = 3
    #: mm and pixels: ... never finer than ``refine_min_resolution_mm`` (half the check's floor: a
    #: 3 mm tool is measured at r / 30, 60 and 120) nor over ``refine_max_pixels`` dixels over the
    #: pocket's bounding box grown by r (the evaluator's grid: about 8 bytes each per array)
    refine_min_resolution_mm: float = 0.01
    refine_max_pixels: int = 20_000_000
    #: the highest samples (at least 200 samples apart) of each measure of the refinement -- the
    #: coarse one and every finer one -- measured again on the exact vector stock
    #: (:func:`cnclab.toolpath.vector_check.vector_peaks`: the pocket less the swept discs as polygons,
    #: chips thinner than 2 um not counted); where one reads more than the finest dixel, it is the
    #: verdict. A dixel can read low too: letter U 33:2 (D 4, theta 25) reads theta + 9.4 at r / 120,
    #: + 10.5 on the vector stock at the peak r / 30 found (session 18). 0: no vector measure
    refine_vector_peaks: int = 5
    #: deg over theta: a clearing pass ends before its first point near a sharp corner of the
    #: tool-centre region whose engagement on the exact stock (the pocket less the level's swept discs,
    #: chips of 2 um and more: :class:`.corners.CornerCheck`) exceeds theta + this; a finishing lap
    #: goes past that corner on the chord across it (``corner_skips``). The planning stock reads a
    #: corner rest thinner than a pixel as a fraction of material: short passes of rectilinear_1 (D 4,
    #: theta 50.1) and comb_1 (D 6, theta 65.3) took square corners micrometres at a time at theta + 13
    #: on the exact stock, + 6 to + 4 on the r / 30 dixel (session 19). 2 deg under
    #: the bound of + 10 (``written_margin_deg`` and the arc fit). None: no check
    corner_exact_cap_deg: float | None = 8.0
    #: deg and fraction of r: a sharp corner is where the tool-centre limit turns convexly by at least
    #: ``corner_min_turn_deg`` within ``corner_window_frac`` r of its length (a square pocket corner
    #: turns 90 at one vertex; a fillet a little wider than the tool, many small turns)
    corner_min_turn_deg: float = 20.0
    corner_window_frac: float = 0.25
    #: pixels (h): pass and lap points within this of a sharp corner are checked. The rests the
    #: planning stock can under-read there are the sub-pixel wall skins (the passes keep h/sqrt(2)
    #: inside the limit, the laps snap within 2 h of it): a tool d from the corner along one wall meets
    #: the other wall's skin only where d is under the skin's thickness. The two found stood 1.2 h and
    #: 0.4 h from the corner
    corner_reach_h: float = 4.0
    #: corners: a finishing lap over the cap at a corner goes on past it along the chord across the
    #: corner (checked the same way) at most this many times, then ends (a lap cut short there left
    #: the rest of its ring: neck_3 4.3 mm^2 more uncut, session 19)
    corner_skips: int = 8
    #: deg: ... those whose planning engagement is at least the cap less this (the pixel stock read
    #: 4 to 9 deg under the exact one at the two corners above)
    corner_screen_deg: float = 30.0
