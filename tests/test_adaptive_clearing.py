"""Property tests of the engagement-controlled clearing planner (cnclab.toolpath.adaptive_clearing)
over random small pockets, scored on the dixel simulator at 0.05 mm by the package's one evaluator
(cnclab.toolpath.evaluate.evaluate).

Tolerances: the planner controls the engagement on its own pixel stock (0.05 mm here) and the
scorer measures it on the dixel stock at 0.05 mm; one pixel of radial depth at r = 1.5 mm changes
the engagement by up to ~ h / (r sin theta) = 2.2 deg at theta = 60 deg, so the engagement bound is
asserted as theta + 10 deg + 2 pixels' worth (4.4 deg). Coverage (:func:`_uncut_allowance_mm2`):
the area left beyond the unreachable corners must be below 1 % of the pocket area + 1 mm^2 (dixel
rows of 0.05 mm along the walls contribute ~ perimeter x h / 2) + about one more unreachable-corner
area per corner below 180 deg (the engagement bound keeps the tool centre short of such corners of
the tool-centre region: ``_corner_allowance_mm2``, at most the pocket's unreachable area) + the
material only a slot barely wider than the tool reaches (``_slot_only_mm2``: no pass enters a strip
of the tool-centre region thinner than 0.4 r under the engagement bound; ``plan`` refuses such a
plan by its uncut report, :func:`test_tapered_slot_is_left_and_plan_says_so`).
"""
import math
from pathlib import Path

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, Phase, example, given, settings
from hypothesis import strategies as st
from shapely.geometry import Polygon, box
from shapely.ops import unary_union

from cnclab.toolpath.adaptive import PlanningError, adaptive_clearing
from cnclab.nc.gcode import read_gcode
from cnclab.toolpath.evaluate import evaluate, unreachable_region
from cnclab.toolpath.job import Job
from cnclab.toolpath.path import Tool

R = 1.5
H = 0.05


def _job(poly, theta, r=R, source="<dict>", **kw):
    return Job(poly, Tool(2 * r), theta, 1.0, feed_mm_min=255.0, spindle_rpm=6366.0, rapid_mm_min=10000.0,
               source=source, **kw)


def _plan(poly, theta):
    return adaptive_clearing(_job(poly, theta, source="hypothesis"), resolution_mm=H, step_mm=0.05)


@st.composite
def star_pockets(draw):
    n = draw(st.integers(5, 8))
    ang = np.sort(draw(st.lists(st.floats(0, 2 * math.pi), min_size=n, max_size=n, unique=True)))
    rad = draw(st.lists(st.floats(4.5, 8.0), min_size=n, max_size=n))
    return Polygon(np.c_[np.cos(ang) * rad, np.sin(ang) * rad]).buffer(0)


@st.composite
def rectilinear_pockets(draw):
    boxes = []
    for _ in range(draw(st.integers(1, 3))):
        x, y = draw(st.integers(0, 6)), draw(st.integers(0, 6))
        boxes.append(box(x, y, x + draw(st.integers(5, 10)), y + draw(st.integers(5, 10))))
    u = unary_union(boxes)
    return max(getattr(u, "geoms", [u]), key=lambda g: g.area)


@st.composite
def pockets(draw):
    poly = draw(st.one_of(star_pockets(), rectilinear_pockets()))
    if draw(st.booleans()):            # an island: a small square around a point well inside
        c = poly.buffer(-3 * R).representative_point() if not poly.buffer(-3 * R).is_empty else None
        if c is not None:
            s = draw(st.floats(0.5, 1.2))
            isl = box(c.x - s, c.y - s, c.x + s, c.y + s)
            if poly.buffer(-0.1).contains(isl):
                poly = poly.difference(isl)
    return poly


_SETTINGS = dict(max_examples=6, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck),
                 phases=[Phase.explicit, Phase.generate])   # no shrinking: each example plans a pocket


def _corner_allowance_mm2(poly) -> float:
    """Sum over the corners of the pocket with an interior angle a < 180 deg (outline corners below
    180 deg, island corners above 180 deg) of the unreachable corner area R^2 (cot(a/2) - (pi - a)/2). The planner may leave about as much again at each such
    corner: the tool centre cannot reach the corner of the tool-centre region without its front
    half-circle touching the unreachable corner over ~(pi - a) -- more than theta + 10 deg -- so
    under the engagement bound it stops short (the bench compares what is left with FreeCAD's).
    A corner where the ring doubles back (a = 0: a spike of no width) has no area to leave: 0.
    (Until 2026-11 the outline was recognised by ``ring is poly.exterior``, never true -- shapely
    makes a new ring object on each access --, so outline corners counted as island corners: the
    allowance was 0 on every pocket without islands, and the test stricter than it said.)"""
    tot = 0.0
    for k_ring, ring in enumerate([poly.exterior, *poly.interiors]):
        P = np.asarray(ring.coords)[:-1]
        # orientation by the signed area (GEOS's is_ccw looks at the highest vertex: wrong on a spike)
        ccw = float(np.sum(P[:, 0] * np.roll(P[:, 1], -1) - np.roll(P[:, 0], -1) * P[:, 1])) > 0
        for k in range(len(P)):
            a, b, c = P[k - 1], P[k], P[(k + 1) % len(P)]
            u, v = b - a, c - b
            cross = u[0] * v[1] - u[1] * v[0]
            turn = math.atan2(abs(cross), float(u @ v))          # exterior turning angle (rad)
            left = cross > 0
            # the pocket lies left of an outline walked counter-clockwise and right of an island
            # walked counter-clockwise: a convex corner of the free region turns towards it
            convex = (left == ccw) if k_ring == 0 else (left != ccw)
            alpha = math.pi - turn
            if convex and turn > 1e-6 and alpha > 1e-9:
                tot += R * R * (1.0 / math.tan(alpha / 2) - (math.pi - alpha) / 2)
    return tot


def _scored(poly, theta):
    if not poly.is_valid or poly.buffer(-R).is_empty:
        with pytest.raises(PlanningError, match="hypothesis"):
            _plan(poly, theta)
        return None, None
    try:
        tp = _plan(poly, theta)
    except PlanningError as exc:
        # a refusal is right only for a pocket too narrow for the tool: some part of its tool-centre
        # region has an inscribed radius below R / 2 (no room to clear it under engagement control)
        narrow = min(shapely.maximum_inscribed_circle(q).length for q in shapely.get_parts(poly.buffer(-R, 64)))
        assert "too narrow" in str(exc) and narrow < 0.5 * R, (str(exc), narrow)
        return None, None
    return tp, evaluate(tp, _job(poly, theta), H)


def _slot_only_mm2(poly, frac=0.2) -> float:
    """Pocket area (mm^2) that only tool centres in strips of the tool-centre region thinner than
    2 frac R reach (the region less its morphological opening by a disc of radius frac R): a slot
    less than 2 frac R wider than the tool, a channel tapering to the tool's diameter. Moving along
    such a strip the front half of the tool meets material over nearly 180 deg; under the engagement
    bound a pass, a finishing lap or a trochoid advances there only by steps far below the planning
    pixel (a loop of radius c advances c (1/cos(theta/2) - 1): 0.02 mm at c = 0.2 R, theta 45 deg), so
    the planner stops where the strip's half-width falls to ~0.15 R (measured on random pockets:
    frac 0.2 bounds what is left on each of them; narrow.NARROW_MIN_HALF_WIDTH_FRAC is the same 0.2)."""
    allowed = poly.buffer(-R, quad_segs=64)
    c = frac * R
    wide = allowed.buffer(-c, quad_segs=32).buffer(c, quad_segs=32)
    # strips, not the rounded-off corners of the tool-centre region: a rest of at least c R mm^2 (a
    # corner of angle a leaves c^2 (cot(a/2) - (pi - a)/2): 0.02 mm^2 at 90 deg; c R below ~22 deg)
    strips = [q for q in shapely.get_parts(allowed.difference(wide)) if q.area >= c * R]
    if not strips:
        return 0.0
    only = shapely.union_all(strips).buffer(R, quad_segs=64).difference(wide.buffer(R, quad_segs=64))
    return only.intersection(poly).area


def _uncut_allowance_mm2(poly) -> float:
    """What the planner may leave beyond the unreachable corners (mm^2): see the module docstring."""
    corners = min(_corner_allowance_mm2(poly), unreachable_region(poly, R).area)
    return 0.01 * poly.area + 1.0 + corners + _slot_only_mm2(poly)


#: a channel tapering from 4 mm to the tool's 3 mm over 10 mm (the minimal pocket of the class that
#: random stars drew, e.g. the 102 mm^2 star of two fresh-clone CI runs, 10.8 mm^2 uncut): its
#: tool-centre region is a 10 mm wedge at most 1 mm wide
TAPERED = Polygon([(0, 0), (10, 0), (10, 4), (0, 3)])
#: a star the fuzz drew (benchmarks/fuzz_random_pockets.py, seed 1): 11.7 mm^2 left at theta 45 deg,
#: 13.2 mm^2 reachable only through a strip thinner than 0.4 r
STAR_TAPER = Polygon([(7.845249487397951, 0), (7.097828378873946, -3.3568791045564064),
                      (6.388173760961252, -4.564979848621672), (-6.326017799425355, -4.639982577647401),
                      (-7.659842916314508, -1.6955075985982098)])
#: each property run must plan at least this many of its pockets (the drawn ones and the explicit
#: examples, 7 in all, all planned now: a refusal is checked for its reason in _scored, but a run
#: cannot pass by refusing)
MIN_PLANNED = 6


def test_random_pockets_are_safe_covered_and_bounded():
    """On every pocket drawn (and the explicit examples): zero plunges into material, zero rapids
    through material (rapids below the top only as links marked cleared), no wall gouge, full
    coverage beyond the unreachable corners up to :func:`_uncut_allowance_mm2`, and the engagement
    within theta + 10 deg + 2 pixels' worth. At least MIN_PLANNED pockets are planned."""
    planned = []

    @settings(**_SETTINGS)
    @example(STAR_TAPER, 45.0)
    @given(pockets(), st.sampled_from([45.0, 60.0]))
    def check(poly, theta):
        tp, s = _scored(poly, theta)
        if tp is None:
            return
        assert s.plunges_into_material == 0
        assert s.rapids_into_material == 0
        assert s.uncut_beyond_unreachable_mm2 <= _uncut_allowance_mm2(poly)
        K = tp.kinds()
        assert np.all((K != "rapid") | (tp.xyz[:, 2] >= 0.0) | tp.cleared)   # below the top: proven links only
        assert _wall_gouge(tp, poly) <= 1e-3
        assert s.engagement_max_deg <= theta + 10 + 2 * math.degrees(H / (R * math.sin(math.radians(theta))))
        planned.append(poly.area)

    check()
    assert len(planned) >= MIN_PLANNED, planned


#: a star with an island the fuzz drew (benchmarks/fuzz_random_pockets.py --seed 2, 1 of 207 planned):
#: the channel round the island is a narrow region cut by narrow.py's trochoid, which reached 124.6 deg
#: at theta 60 (bound 74.4; 131.9 with the drawn 6e-237 written as 0) near (3.4-3.8, 1.3-1.5), where a
#: mouth's leg along the island's edge joined the channel's axis (64.4 deg since the leg check)
STAR_ISLAND_TROCHOID = Polygon(
    [(5.011582845372573, -4.594407262504043), (0.2819898780318265, -6.79301276448603),
     (-6.694578638050897, -2.36790653453732), (-5.926326582395415, 0.9072695465015134),
     (1.9701040575136066, 4.95637310975307), (4.829415512699131, 5.5936450688357064),
     (6.255449397869905, 0.210069288773419), (6.724134726375773, 0.0)],
    [[(1.8393711718172212, -0.0751371842491606), (0.3839191913015273, -0.0751371842491606),
      (0.3839191913015273, -1.5305891647648544), (1.8393711718172212, -1.5305891647648544)]])


def test_star_island_trochoid_engagement_bounded():
    """Was 124.6-131.9 deg at theta 60: the trochoid started at a mouth's free point 4 mm from the axis
    end, its straight leg along the island's edge (the pattern clamped onto the region's boundary, a
    slot cut through uncleared material) and joined to the axis at a 67 deg kink. Now a mouth's leg
    must hold the pattern's band inside the tool-centre region, a leg is joined by a rounded bend
    (narrow.join_axis) and periods are laid closer on bends (narrow.bend_step)."""
    tp, s = _scored(STAR_ISLAND_TROCHOID, 60.0)
    assert s.plunges_into_material == 0 and s.rapids_into_material == 0      # safe all the same
    assert s.engagement_max_deg <= 60.0 + 10 + 2 * math.degrees(H / (R * math.sin(math.radians(60.0))))


#: a star with an island the fuzz drew (benchmarks/fuzz_random_pockets.py --seed 1 --slot-narrow, 1 of
#: 300; the crash is before any slot): at theta 45 the narrow-region trochoid's step search raised a raw
#: "ValueError: theta_max_deg=45.0 is below the engagement of the smallest step" (trochoidal/_common.py)
STAR_ISLAND_CRASH = Polygon([(-1.0415809886170826, -7.673962306434592), (-5.97551053239977, -3.09584666070707), (-6.646544963740736, 4.452352192377941), (-5.788687427558027, 4.396379407837443), (2.373716118102958, 7.6397298244544105), (4.300155489872455, 6.697095377144545), (6.778087006374358, 2.353566066092042)],
                            [[(-0.0378956346211456, 1.2602165869199564), (-2.406397089857617, 1.2602165869199564), (-2.406397089857617, -1.108284868316515), (-0.0378956346211456, -1.108284868316515)]])


def test_star_island_trochoid_plans_or_refuses_clearly():
    """Was a raw ``ValueError`` from Thesis IV's step search (no step of the straight-slot period
    keeps theta 45 in the island's channel, barely wider than the tool): such a width is now left
    to the level planner (narrow.trochoid_period returns None), and the job plans safely."""
    tp, s = _scored(STAR_ISLAND_CRASH, 45.0)        # planned, or refused as too narrow (checked in _scored)
    if tp is not None:
        assert s.plunges_into_material == 0 and s.rapids_into_material == 0


def test_corner_allowance_hand_cases():
    """A 9 x 7 box: four right-angle corners, 4 R^2 (1 - pi/4); a square island adds nothing (its
    corners are reflex for the free region); a spike of no width (the ring doubles back) adds 0."""
    four = 4 * R * R * (1 - math.pi / 4)
    assert _corner_allowance_mm2(box(0, 0, 9, 7)) == pytest.approx(four, rel=1e-12)
    assert _corner_allowance_mm2(box(0, 0, 30, 30).difference(box(10, 10, 12, 12))) == pytest.approx(four, rel=1e-12)
    spike = Polygon([(0, 0), (9, 0), (9, 7), (5, 7), (5, 12), (5, 7), (0, 7)])
    assert _corner_allowance_mm2(spike) == pytest.approx(four, rel=1e-12)
    assert _slot_only_mm2(box(0, 0, 9, 7)) == pytest.approx(0.0, abs=1e-9)


@pytest.mark.slow      # a whole random-bench pocket: make test-slow (CI); in make test the refusal of a
# part no tool can enter is test_plan_limits' thin annulus
def test_tapered_slot_is_left_and_plan_says_so():
    """The class of the random pockets the planner leaves most of (a channel narrowing to the tool's
    diameter, :data:`TAPERED`): the planner plans it safely within the engagement bound and leaves
    the strip it cannot enter -- more than the corner allowance, at most the slot-only area --, and
    :func:`cnclab.toolpath.planners.plan` does not pass it silently: it refuses it (UncutError naming
    the job and the region), and with ``allow_uncut`` it plans with the same words as a warning."""
    from cnclab.toolpath.planners import UncutError, plan

    tp, s = _scored(TAPERED, 45.0)
    assert s.plunges_into_material == 0 and s.rapids_into_material == 0 and _wall_gouge(tp, TAPERED) <= 1e-3
    assert s.engagement_max_deg <= 45.0 + 10 + 2 * math.degrees(H / (R * math.sin(math.radians(45.0))))
    slot = _slot_only_mm2(TAPERED)
    assert slot > 10.0                                       # 14.7 mm^2: most of the 35 mm^2 pocket
    assert 0.01 * TAPERED.area + 1.0 + _corner_allowance_mm2(TAPERED) < s.uncut_beyond_unreachable_mm2 \
        <= _uncut_allowance_mm2(TAPERED)
    job = _job(TAPERED, 45.0, source="tapered.json")
    with pytest.raises(UncutError, match=r"tapered.json: strategy adaptive leaves material uncut .*region 0"):
        plan(job, resolution_mm=H)
    ok = plan(job, resolution_mm=H, allow_uncut=True)
    assert ok.info["warnings"] and "region 0" in ok.info["warnings"][0]
    # with slot_narrow the strip is cut by slotting (stated in the notes: engagement up to 180 deg) and
    # the pocket is covered up to the corner allowance; plan() then accepts it
    from cnclab.toolpath.adaptive import AdaptiveParams

    slotted = adaptive_clearing(_job(TAPERED, 45.0), AdaptiveParams(slot_narrow=True), resolution_mm=H, step_mm=0.05)
    s2 = evaluate(slotted, _job(TAPERED, 45.0), H)
    assert s2.plunges_into_material == 0 and s2.rapids_into_material == 0 and _wall_gouge(slotted, TAPERED) <= 1e-3
    assert s2.uncut_beyond_unreachable_mm2 <= 0.01 * TAPERED.area + 1.0 + _corner_allowance_mm2(TAPERED)   # 1.0 of 3.3
    assert slotted.info["slots"] >= 1 and any("slotting at up to" in n for n in slotted.info["notes"])
    # plan() with the slots leaves a fraction of what it leaves without them (1.5 against 4.8 mm^2 by
    # its count, whose limit here is 1.3: since 2026-11-28 it counts the thin rest the slots leave
    # along the walls, which a pixel opening used to drop)
    sl = plan(job, resolution_mm=H, params=AdaptiveParams(slot_narrow=True), allow_uncut=True)
    assert sl.info["uncut"]["uncut_mm2"][0] < 0.5 * ok.info["uncut"]["uncut_mm2"][0]
    # the report says what the evaluator measures on that plan (plan() plans at r/60 = 0.025 mm, a
    # finer pixel than the 0.05 mm above: it gets further into the strip, 7.3 against 11.6 mm^2);
    # 0.5 mm^2: the report's r/25 pixels against the 0.05 mm dixels
    left = evaluate(ok, job, H).uncut_beyond_unreachable_mm2
    assert ok.info["uncut"]["uncut_mm2"][0] == pytest.approx(left, abs=0.5)
    assert ok.info["uncut"]["uncut_mm2"][0] > ok.info["uncut"]["limit_mm2"][0]


#: seeded pockets of the two families (the property tests' shapes) that must all be planned and safe:
#: the hypothesis tests above may meet a pocket the planner refuses (its reason checked in _scored);
#: this one cannot pass by refusing (issue 29 item 6)
SEEDED = 5


def _seeded_pockets(n=SEEDED, seed=29):
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        if k % 2 == 0:                                   # a star of 5-8 rays, radii 5.5..8 mm
            m = int(rng.integers(5, 9))
            ang = np.sort(rng.uniform(0, 2 * math.pi, m))
            rad = rng.uniform(5.5, 8.0, m)
            out.append(Polygon(np.c_[np.cos(ang) * rad, np.sin(ang) * rad]).buffer(0))
        else:                                            # two overlapping rectangles, an island
            a = box(0, 0, rng.uniform(10, 14), rng.uniform(7, 10))
            b = box(4, 3, 4 + rng.uniform(8, 12), 3 + rng.uniform(7, 10))
            u = unary_union([a, b])
            c = u.buffer(-3 * R).representative_point()
            out.append(u.difference(box(c.x - 0.8, c.y - 0.8, c.x + 0.8, c.y + 0.8)))
    return out


def test_seeded_pockets_are_all_planned_and_safe():
    planned = 0
    for poly in _seeded_pockets():
        # the planner must plan these (a refusal fails here: they are wide enough for the tool)
        assert min(shapely.maximum_inscribed_circle(q).length
                   for q in shapely.get_parts(poly.buffer(-R, 64))) > R
        tp = _plan(poly, 60.0)
        s = evaluate(tp, _job(poly, 60.0), H)
        assert s.plunges_into_material == 0 and s.rapids_into_material == 0
        assert _wall_gouge(tp, poly) <= 1e-3
        planned += 1
    assert planned == SEEDED


def _wall_gouge(tp, poly) -> float:
    """Deepest reach (mm) of the tool disc past the pocket's walls and islands along every move below
    the stock top (lines sampled every 0.05 mm; arcs, if any, are entry helices about an interior centre). The
    planner keeps the centre in the 64-segment tool-centre region: < 1e-3 mm at R = 1.5 mm."""
    P, low = tp.xyz, tp.xyz[:, 2] < 0.0
    worst = 0.0
    for k in np.flatnonzero(low[1:] & low[:-1]) + 1:
        a, b = P[k - 1, :2], P[k, :2]
        t = np.linspace(0.0, 1.0, max(2, int(np.hypot(*(b - a)) / 0.05) + 2))
        q = a + t[:, None] * (b - a)
        d = shapely.distance(poly.boundary, shapely.points(q))
        d = np.where(shapely.contains_xy(poly, q[:, 0], q[:, 1]), d, -d)
        worst = max(worst, R - float(d.min()))
    return worst


def test_finish_snap_stays_on_its_ring():
    """Regression: the finishing lap snaps points within 2 h of the wall onto the nearest wall point; a
    point nearest to an island ring's closing vertex was once sent to the next ring's start, 22 mm
    away, through an island. Two islands side by side, a lap around each."""
    poly = box(0, 0, 30, 14).difference(box(8, 5, 11, 9)).difference(box(19, 5, 22, 9))
    tp = adaptive_clearing(_job(poly, 60.0, source="islands"), resolution_mm=H)
    assert _wall_gouge(tp, poly) <= 1e-3


def test_refuses_pocket_narrower_than_the_tool():
    with pytest.raises(PlanningError, match="narrow-job.*does not fit|narrow-job.*narrower"):
        adaptive_clearing(_job(box(0, 0, 20, 2.5), 60.0, source="narrow-job"))


GOLDEN = Path(__file__).parent / "fixtures" / "adaptive" / "box_9x7_theta60.ngc"


def test_deterministic_golden_program():
    """The path of a 9 x 7 mm pocket (R 1.5 mm, theta 60 deg) equals, move by move, the committed
    program (tests/fixtures/adaptive/box_9x7_theta60.ngc, one block per path move: written by this
    planner before the package split, rewritten by ``write_program(..., arc_tol_mm=None)`` when the
    entry became the package's one helix generator, issue 27: 63 line moves in place of 3 G3, every
    other move the same within 0.5e-4 mm; rewritten so again when the passes began to start at the
    upstream end of their band and wall slivers were left to the finishing lap, issue 24; and when the
    join of a link's last G0 to its pass kept the link's feed leg off the cut boundary, which it had
    dropped, writing a G0 from the boundary that no proof covered: 12 feed legs more; and when the
    free-space search's coarse cell of a small tool became r/10 (AdaptiveParams.coarse_cell_max_r; here
    0.15 mm, it was one 0.05 mm pixel): the same 27 passes, 174 G0 link corners fewer; and when a link to a
    start whose pass cut nothing was no longer run (AdaptiveParams.drop_idle_links): the same 27 passes and
    cut moves, 3 links fewer, G0 length at depth 69.5 -> 61.9 mm): read back, every end point within its 4 written decimals
    (0.5e-4 mm), every motion word and feed the same. Any change of the planner's moves fails here
    (the writer's own changes, e.g. arc fitting, do not: the path's moves are compared); regenerate the
    file only for a change that is meant, and say so in the commit."""
    tp = _plan(box(0, 0, 9, 7), 60.0)
    want = read_gcode(GOLDEN.read_text(), source=str(GOLDEN)).moves
    got = tp.to_moves()
    assert len(want) == len(got) > 100
    assert [m.motion for m in want] == [m.motion for m in got]
    assert np.allclose([m.xyz for m in want], [m.xyz for m in got], atol=0.5e-4, rtol=0)
    assert [m.feed or 0.0 for m in want] == pytest.approx([m.feed or 0.0 for m in got])
    again = _plan(box(0, 0, 9, 7), 60.0)
    assert np.array_equal(again.xyz, tp.xyz)


def test_capsule_free_hand_case():
    # one material pixel centred at (1.025, 0.025) on a 0.05 mm grid; the segment (0,0)-(0,5)
    # passes 1.025 mm from it: free for a radius below that, not free above
    from cnclab.toolpath.adaptive.stock import capsule_free

    M = np.zeros((200, 200), np.uint8)
    M[100, 120] = 1          # centre x = -5 + 120.5 * 0.05 = 1.025, y = -5 + 100.5 * 0.05 = 0.025
    args = (M, -5.0, -5.0, 0.05, 0.0, 0.0, 0.0, 5.0)
    assert capsule_free(*args, 1.0)
    assert not capsule_free(*args, 1.05)
    assert capsule_free(M, -5.0, -5.0, 0.05, 0.0, 0.1, 0.0, 5.0, 1.025)    # the pixel is past the segment's end


def test_rapid_links_switch():
    # the default writes the links at depth (and air steps whose chord is clear of the stock the pass
    # started on) as G0 tagged cleared, rapid_links=False as G1 at the link feed. The geometry differs
    # only where a G0 needs a detour to be proven (an air run along a wall moved 2 h off it, a feed leg
    # off a wall at a link's ends): the same number of passes, and no rapid removes material (evaluator)
    poly = box(0, 0, 16, 11)
    a = adaptive_clearing(_job(poly, 60.0), resolution_mm=H, step_mm=0.05)
    b = adaptive_clearing(_job(poly, 60.0, rapid_links=False), resolution_mm=H, step_mm=0.05)
    assert a.info["passes"] == b.info["passes"] and a.info["entries"] == b.info["entries"]
    low_a = a.is_kind("rapid") & (a.xyz[:, 2] < 0)
    assert low_a.any() and set(a.tag[low_a]) <= {"cleared: link through cleared area", "cleared: air inside cleared area"}
    assert not (b.is_kind("rapid") & (b.xyz[:, 2] < 0)).any()
    assert evaluate(a, _job(poly, 60.0), H).rapids_into_material == 0
    assert a.time_s(10000.0)["total_s"] < b.time_s(10000.0)["total_s"]
    job = Job.from_dict({"polygon": [[0, 0], [16, 0], [16, 11], [0, 11]], "tool_diameter": 3.0, "theta_deg": 60,
                         "a_p": 1.0, "feed_mm_min": 255, "spindle_rpm": 6000, "rapid_links": False})
    assert job.rapid_links is False and Job.from_dict(job.to_dict()).rapid_links is False


# a random star pocket (hypothesis found it) whose tool-centre region is a 0.5 mm^2 sliver, inscribed radius 0.2 mm
_SLIVER_WKT = ('POLYGON ((-4.916339044839923 0.576290201359072, 4.881874450970326 -6.2127850347776015, -2.66839'
    '7659143814 -4.7438233887726104, -4.723983831250046 -6.240018494358061, -3.6669612046935347 -4.1'
    '14643005055887, -5.675759822888521 -5.307154383198031, -4.916339044839923 0.576290201359072))')


def test_sliver_pocket_left_stated_and_refused_as_uncut():
    # the planner enters the sliver (a helix of its room) but no finishing lap can start in it: the
    # rest is left and stated (was: PlanningError for the whole job, issue 28 item 1); plan measures
    # it (3.6 of 15 mm^2 reachable) and refuses it above the uncut limit unless allow_uncut
    from shapely import wkt

    from cnclab.toolpath import planners

    job = _job(wkt.loads(_SLIVER_WKT), 60.0, source="sliver-test")
    tp = adaptive_clearing(job, resolution_mm=H, step_mm=0.05)
    assert any("too narrow" in q and "left uncut" in q for q in tp.info["left_parts"])
    assert evaluate(tp, job, H).plunges_into_material == 0
    with pytest.raises(planners.UncutError, match="sliver-test: .*leaves material uncut"):
        planners.plan(job, "adaptive", H)


def test_coarse_planning_stock_refused():
    # coarser than r/30 the pixel stock cannot resolve the engagement (measured: r/20 left 169 mm^2 of
    # the Kim & Yang pocket uncut): a clear error naming the parameter, not a poor path
    with pytest.raises(PlanningError, match="coarse-test: resolution_mm must be in"):
        adaptive_clearing(_job(box(0, 0, 16, 11), 60.0, source="coarse-test"), resolution_mm=R / 20)


def test_neck_between_islands_is_taken_from_its_ends_not_by_helix_after_helix():
    # two 14 x 20 mm islands 7.8 mm apart (1.3 D for D = 6 mm): the tool-centre band in the neck is
    # 1.8 mm wide, narrower than the tool. A pass that meets no material within 1.5 r of air there is
    # tried once more with 3.5 r (the way round to the face is a loop mostly through air); without it
    # the neck was taken by four helix entries one after another (5 entries in all, FreeCAD 4 or 5).
    # Also: no entry helix is smaller than 0.1 r where its part of the region is wider.
    islands = [box(14, 10, 28, 30), box(35.8, 10, 49.8, 30)]
    poly = box(0, 0, 63.8, 40).difference(unary_union(islands))
    tp = adaptive_clearing(_job(poly, 60.0, r=3.0, source="neck"))
    assert tp.info["entries"] <= 3
    ev = evaluate(tp, _job(poly, 60.0, 3.0), 0.1)
    assert ev.plunges_into_material == 0 and ev.rapids_into_material == 0
    assert ev.engagement_max_deg <= 70.0
    # every helix is a run of line moves on a ring (ToolPathBuilder.helix): its radius is the
    # circumradius of its first three points (the move before the run and its first two)
    hel = np.flatnonzero(tp.is_kind("helix"))
    starts = hel[np.r_[True, np.diff(hel) > 1]]
    assert len(starts) == tp.info["entries"]
    for k in starts:
        a, b, c = tp.xyz[k - 1:k + 2, :2]
        ab, bc, ca = np.hypot(*(b - a)), np.hypot(*(c - b)), np.hypot(*(a - c))
        area2 = abs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
        assert ab * bc * ca / (2 * area2) >= 0.1 * 3.0 - 1e-6
