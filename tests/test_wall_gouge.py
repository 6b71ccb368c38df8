"""The plan's wall-gouge measure (:func:`cnclab.toolpath.coverage.wall_gouge`): its shortcut for short
segments deep inside the pocket (:func:`cnclab.toolpath.coverage._deep_inside`) changes no result."""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import Point, box

from cnclab.toolpath import coverage
from cnclab.toolpath.job import Job
from cnclab.toolpath.path import Tool, ToolPath

# a non-convex tool-centre region: a box with a round island and a notch (reflex corners, arcs)
POCKET = box(0, 0, 40, 30).difference(Point(20, 15).buffer(5, quad_segs=32)).difference(box(30, 0, 34, 8))
JOB = Job(POCKET, Tool(6.0), 60.0, 2.0, v_c=100, f_z=0.05)


def _path(pts, z=-2.0) -> ToolPath:
    P = np.c_[pts, np.full(len(pts), z)]
    return ToolPath.build(P, kind="cut", feed=300.0, tool=JOB.tool)


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([0.02, 0.1, 0.15, 0.6]), st.floats(2.9, 3.1), st.booleans())
def test_deep_segment_shortcut_changes_no_result(seed, step, ring, walk):
    """Chords of 0.02-0.6 mm (the shortcut only takes those <= 0.15 mm): a lap around the island
    ``ring`` mm from its edge (r = 3: its chords dip toward the island between their ends, so the
    worst depth is a segment's), or a random walk through the notch and along the walls: the worst
    depth and where it is are those of the measure without the shortcut (every segment built and
    measured exactly). It fails when the shortcut skips a segment the exact measure keeps (e.g. its
    ends tested against the pocket shrunk by 0.98 r instead of r + margin + half the chord)."""
    rng = np.random.default_rng(seed)
    if walk:
        pts = np.cumsum(rng.normal(0, step, (600, 2)), axis=0) + [rng.uniform(2.8, 37), rng.uniform(2.8, 27)]
        pts = np.clip(pts, 2.5, [37.5, 27.5])
    else:
        a = rng.uniform(0, 6.3) + np.cumsum(rng.uniform(0.5, 1.0, 600) * step / (5 + ring))
        pts = np.c_[20 + (5 + ring) * np.cos(a), 15 + (5 + ring) * np.sin(a)]
    p = _path(pts)
    fast = coverage.wall_gouge(p, JOB)
    orig = coverage._deep_inside
    try:
        coverage._deep_inside = lambda poly, P, seg, r: np.zeros(len(seg), bool)
        exact = coverage.wall_gouge(p, JOB)
    finally:
        coverage._deep_inside = orig
    assert fast == exact


def test_a_short_chord_into_the_island_is_found():
    """Hand case: chords of 0.1 mm from 2.5 mm off the island edge (r = 3) toward it: the deepest end
    is 2.5 mm away, so the disc reaches 0.5 mm into the island; the shortcut keeps those chords."""
    pts = np.c_[np.linspace(20 + 5 + 4.0, 20 + 5 + 2.5, 16), np.full(16, 15.0)]
    g, at = coverage.wall_gouge(_path(pts), JOB)
    assert abs(g - 0.5) < 1e-3 and abs(at[0] - 27.5) < 1e-2
