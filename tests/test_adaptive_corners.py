"""The corner check of the adaptive planner on the exact stock (cnclab.toolpath.adaptive.corners) and
the stepwise vector engagement it uses (cnclab.simulation.vector.engagement_along): hand-computed
cases and a consistency property against vector_engagement."""
from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.geometry import Point, Polygon, box

from cnclab.simulation.vector import SweptDiscs, engagement_along, engagement_swept, vector_engagement
from cnclab.toolpath.adaptive.corners import CornerCheck, sharp_points


def test_a_pass_along_a_wall_reads_the_radial_depth_angle():
    """r 3, a_e 1.5 into the material beside the pass: acos(1 - a_e / r) = 60 deg at every step inside
    the block (0.5 deg arc sampling, 361 points)."""
    xy = np.c_[np.linspace(-10, 40, 101), np.full(101, 20 + 3 - 1.5)]
    e = engagement_along(box(0, 0, 30, 20), xy, 3.0)
    inside = (xy[1:, 0] > 3.5) & (xy[1:, 0] < 26.5)
    assert np.allclose(e[inside], 60.0, atol=0.5)
    assert np.all(e[xy[1:, 0] < -3.01] == 0.0)


def test_stepwise_engagement_matches_the_sample_by_sample_measure():
    """engagement_along (the stock cut as the tool goes) and vector_engagement (the discs of the earlier
    samples re-swept for each sample) are two spellings of one quantity: equal within the arc sampling
    (361 against 3601 points: 0.5 deg) on a curved pass through a block with an earlier slot in it."""
    t = np.linspace(0, 1, 80)
    xy = np.c_[-4 + 30 * t, 6 + 5 * np.sin(3 * t)]
    slot = box(10, -1, 12, 30)                      # an earlier cut across the block
    stock = box(0, 0, 25, 12).difference(slot)
    e_step = engagement_along(stock, xy, 2.0)
    at = np.arange(1, len(xy))
    e_ref = vector_engagement(stock, xy, at, 2.0)
    assert np.max(np.abs(e_step - e_ref)) <= 0.6


def test_sharp_points_are_the_convex_corners_of_the_region():
    sq = Polygon([(0, 0), (10, 0), (10, 10), (0, 10)])
    assert sorted(map(tuple, sharp_points(sq, 20.0, 0.5).tolist())) == [(0, 0), (0, 10), (10, 0), (10, 10)]
    # the corners of an island (a hole of the region) turn the other way: not corners of the region
    holed = sq.difference(box(4, 4, 6, 6))
    assert len(sharp_points(holed, 20.0, 0.5)) == 4
    # a smooth boundary (a circle of 64 segments a quarter turns 1.4 deg a vertex) has none, a gentle
    # bend under the threshold neither; a fillet drawn with many small turns inside the window does
    assert len(sharp_points(Point(0, 0).buffer(5, quad_segs=64), 20.0, 0.5)) == 0
    fil = box(0, 0, 10, 10).buffer(-0.2).buffer(0.2, quad_segs=16)      # corners rounded to 0.2 mm
    assert len(sharp_points(fil, 20.0, 0.5)) >= 4 and len(sharp_points(fil, 20.0, 0.05)) == 0


def _corner_job():
    """A 20 x 20 pocket, r 2: the tool-centre region is [2, 18]^2, its corner (2, 2). The level (at
    z -1, after a rapid above it) has cleared the pocket except the corner rest beyond the disc at
    (2.1, 2.1): its moves in a ToolPathBuilder."""
    from cnclab.toolpath.path import ToolPathBuilder

    pocket = box(0, 0, 20, 20)
    moves = np.array([[10, 10, -1], [2.1, 10, -1], [2.1, 2.1, -1], [10, 2.1, -1], [10, 10, -1]], float)
    b = ToolPathBuilder()
    b.rapid([[10, 10]], z=5.0)
    b.cut(moves, 300.0)
    return pocket, moves, b


def test_a_jab_into_a_square_corner_is_stopped_before_the_rest():
    """From (3, 3) straight into the corner (2, 2): the last steps meet the corner rest (the rim over
    about the 90 deg the limit turns there, a chip of up to 0.14 mm) -- over a cap of theta + 8 with
    theta 50; the lap is cut before the first such point. With a cap of 100 deg, nothing is."""
    pocket, moves, b = _corner_job()
    P = np.c_[np.linspace(3.0, 2.0, 11), np.linspace(3.0, 2.0, 11)]
    E = np.full(len(P), math.radians(50.0))
    chk = CornerCheck(pocket, [[2.0, 2.0]], 2.0, 58.0, 1.0, 30.0)
    k = chk.first_over(b, 0, -1.0, P, E)
    assert k is not None and np.hypot(*(P[k] - 2.0)) < np.hypot(0.1, 0.1) + 1e-9     # past the earlier reach
    sw = SweptDiscs(2.0)
    sw.add(moves[:, :2])
    exact = engagement_swept(pocket, sw, P)
    assert exact[k - 1] > 58.0 and np.all(exact[:k - 1] <= 58.0)
    # (the polygon measure reads 90 deg at (2.1, 2.1), where the tool stands where it stood before: the
    # rim lies 0.15 um outside the 64-segment polygon of the old disc, on thick material beyond it)
    assert CornerCheck(pocket, [[2.0, 2.0]], 2.0, 100.0, 1.0, 30.0).first_over(b, 0, -1.0, P, E) is None
    # the moves rolled back (the level never went there): the corner is all rest, over the cap sooner
    m = b.mark()
    b.rollback(1)
    b.cut(moves[:2], 300.0)
    k2 = chk.first_over(b, 0, -1.0, P, E)
    assert k2 is not None and k2 <= k
    assert chk.sweep.tag.max() < len(b) < m     # the swept pieces of the rolled-back moves dropped


def test_only_points_near_a_corner_and_near_the_cap_are_measured():
    pocket, moves, b = _corner_job()
    P = np.c_[np.linspace(3.0, 2.0, 11), np.linspace(3.0, 2.0, 11)]
    far = CornerCheck(pocket, [[18.0, 18.0]], 2.0, 58.0, 1.0, 30.0)           # no corner within reach
    assert far.first_over(b, 0, -1.0, P, np.full(len(P), math.radians(50.0))) is None and far.measured == 0
    low = CornerCheck(pocket, [[2.0, 2.0]], 2.0, 58.0, 1.0, 30.0)             # planning engagement 20 < 58 - 30
    assert low.first_over(b, 0, -1.0, P, np.full(len(P), math.radians(20.0))) is None and low.measured == 0


def test_the_swept_discs_answer_as_the_polygons_do():
    """SweptDiscs (pieces in a k-d tree, a brute-forced tail, truncation by tag) against the exact
    point-segment distances, and engagement_swept against the polygon measure engagement_along on
    random passes (equal: both sample the same 361 rim points)."""
    from shapely.geometry import LineString

    from cnclab.simulation.vector import _seg_dist_min
    rng = np.random.default_rng(7)
    s = SweptDiscs(1.5, tail=40)
    runs = [np.cumsum(rng.normal(0, 0.4, (60, 2)), axis=0) + rng.uniform(2, 18, 2) for _ in range(5)]
    for i, run in enumerate(runs):
        s.add(run, tag=i)
    q = rng.uniform(0, 20, (400, 2))
    assert np.allclose(s.distance(q), _seg_dist_min(q, s.A, s.B))
    s.truncate(3)                                   # the last two runs rolled back
    ref = SweptDiscs(1.5)
    for run in runs[:3]:
        ref.add(run)
    assert np.allclose(s.distance(q), ref.distance(q))
    path = np.c_[np.linspace(0, 20, 120), 10 + 3 * np.sin(np.linspace(0, 6, 120))]
    stock = box(0, 0, 20, 20).difference(shapely.union_all([LineString(r).buffer(1.5, quad_segs=64) for r in runs[:3]]))
    a = engagement_along(stock, path, 1.5)
    b = engagement_swept(box(0, 0, 20, 20), s, path)
    assert np.max(np.abs(a - b)) <= 0.5 + 1e-9        # one rim sample (0.5 deg) at the most

