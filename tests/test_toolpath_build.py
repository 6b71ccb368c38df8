"""ToolPath builders shared by the planners: from_segments (a machine-ready level), subdivide,
reordered_path, zigzag_path — kinds, z levels, lengths and times by hand."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cnclab.nc.program import check_program, write_program
from cnclab.toolpath.path import APPROACH_MM, ToolPath, ToolPathBuilder, helix_ring, resample_polyline, subdivide
from cnclab.toolpath.reorder import ReorderResult, reordered_path
from cnclab.toolpath.zigzag import zigzag_path


def test_lift_and_approach_by_hand():
    b = ToolPathBuilder()
    b.approach((3, 4), top_z=-1.0, clearance_z=5.0)                 # the floor a level above cleared at -1
    b.plunge((3, 4), -2.0, 300.0)
    b.cut([[8, 4]], 300.0, z=-2.0)
    b.lift(5.0)
    b.lift(5.0)                                                       # already there: nothing added
    b.approach((8, 4), top_z=4.8, clearance_z=5.0)                    # the clearance plane is nearer: stays there
    p = b.build()
    assert p.kinds().tolist() == ["rapid", "rapid", "plunge", "cut", "rapid"]
    assert p.xyz.tolist() == [[3, 4, 5], [3, 4, -1 + APPROACH_MM], [3, 4, -2], [8, 4, -2], [8, 4, 5]]
    assert p.cleared.tolist() == [False, True, False, False, False]
    with pytest.raises(ValueError, match="lift: no position"):
        ToolPathBuilder().lift(5.0)
    b.plunge((8, 4), -2.0, 300.0)
    b.approach((0, 0), top_z=0.0, clearance_z=5.0)                   # from depth: straight up first
    q = b.build()
    assert q.kinds()[-4:].tolist() == ["plunge", "rapid", "rapid", "rapid"]
    assert q.xyz[-3:].tolist() == [[8, 4, 5], [0, 0, 5], [0, 0, APPROACH_MM]]


def test_from_segments_jump_and_helix():
    circle = np.c_[1 + np.cos(np.linspace(0, 2 * np.pi, 33)), np.sin(np.linspace(0, 2 * np.pi, 33))]
    circle[-1] = circle[0]
    segs = [(circle, "helix", "entry"), (np.array([[2.0, 0], [10, 0]]), "cut", "a"),
            (np.array([[10.0, 0], [20, 0]]), "jump", ""), (np.array([[20.0, 0], [20, 5]]), "link", "")]
    p = ToolPath.from_segments(segs, z_cut=-2.0, feed=300.0, clearance_z=5.0, link_feed=1500.0)
    k = p.kinds()
    assert k[0] == "rapid" and p.xyz[0, 2] == 5.0 and k[-1] == "rapid" and p.xyz[-1, 2] == 5.0
    assert np.all(p.xyz[-1, :2] == p.xyz[-2, :2])                          # straight up at the end
    # every descent from the clearance plane: a rapid to APPROACH_MM above the level top, then feed
    down = np.flatnonzero((p.xyz[:-1, 2] == 5.0) & (p.xyz[1:, 2] < 5.0)) + 1
    assert len(down) == 2 and np.all(k[down] == "rapid") and np.all(p.xyz[down, 2] == APPROACH_MM)
    assert np.all(p.cleared[down]) and np.all(k[down + 1] != "rapid")
    hel = p.is_kind("helix")
    assert np.all(np.diff(p.xyz[hel, 2]) < 0) and p.xyz[hel, 2][-1] == pytest.approx(-2.0)
    assert (p.tag == "entry-floor").sum() == 32                          # the bored circle, flat at depth
    # the jump: rapid straight up at (10, 0), rapid at clearance to (20, 0), rapid down to 0.5, plunge
    j = int(np.flatnonzero((k == "rapid") & (p.xyz[:, 0] == 10.0))[0])
    assert k[j:j + 4].tolist() == ["rapid", "rapid", "rapid", "plunge"]
    assert p.xyz[j].tolist() == [10.0, 0.0, 5.0] and p.xyz[j + 1].tolist() == [20.0, 0.0, 5.0]
    assert p.xyz[j + 2].tolist() == [20.0, 0.0, APPROACH_MM] and p.xyz[j + 3].tolist() == [20.0, 0.0, -2.0]
    assert np.all((p.xyz[p.is_kind("rapid"), 2] == 5.0) | (p.xyz[p.is_kind("rapid"), 2] == APPROACH_MM))
    t = p.time_s(10000.0)
    assert t["link_s"] == pytest.approx(60 * 5 / 1500.0) and t["cut_s"] > 60 * 8 / 300.0
    with pytest.raises(ValueError, match="z_cut"):
        ToolPath.from_segments(segs, z_cut=1.0, feed=300.0)
    with pytest.raises(ValueError, match="cut/link"):
        ToolPath.from_segments([(np.zeros((2, 2)), "plunge", "")], z_cut=-1.0, feed=300.0)


def test_subdivide_keeps_vertices_and_bounds_steps():
    P = np.array([[0, 0], [3, 0], [3, 0], [3, 4.0]])
    Q = subdivide(P, 0.7)
    assert np.hypot(*np.diff(Q, axis=0).T).max() <= 0.7 + 1e-12
    assert all(any(np.allclose(v, q) for q in Q) for v in P) and len(Q) == 1 + 5 + 6


def test_reordered_path_jumps_at_clearance():
    P = np.array([[0, 0, 0], [1, 0, 0], [5, 5, 0.0], [6, 5, 0.0]])
    r = ReorderResult(np.array([0, 1, 2, 3]), np.array([False, False, True, False]), np.ones(4))
    p = reordered_path(P, r, feed_mm_min=500, clearance_z=30, spindle_rpm=2000)
    assert p.kinds().tolist() == ["rapid", "plunge", "cut", "retract", "rapid", "plunge", "cut", "retract"]
    assert p.lengths()["cut_mm"] == pytest.approx(2.0) and np.all(p.spindle == 2000)


def test_zigzag_path_is_the_old_program():
    p = zigzag_path([[0, 0], [10, 0], [10, 1], [0, 1]], z_cut=0.0, z_clear=10.0, feed=500.0)
    mv = p.to_moves()
    assert [m.motion for m in mv] == ["G0", "G1", "G1", "G1", "G1", "G1", "G0"]
    assert p.lengths()["feed_mm"] == pytest.approx(10 + 21 + 10)


def test_ramp_reentry_descends_at_the_ramp_angle_and_returns():
    """A jump re-entered by a ramp: from the stock top down to z_cut at ramp_deg along the next
    segment (back and forth over at most ramp_max_mm), then back to the segment start at depth."""
    segs = [(np.array([[0.0, 0], [10, 0]]), "cut", ""), (np.array([[10.0, 0], [0, 5]]), "jump", ""),
            (np.array([[0.0, 5], [4, 5], [12, 5]]), "cut", "")]
    p = ToolPath.from_segments(segs, z_cut=-3.0, feed=100.0, reentry="ramp", ramp_deg=3.0, ramp_max_mm=10.0)
    ramp = np.flatnonzero(p.is_kind("ramp"))
    assert ramp.size and p.xyz[ramp[-1], 2] == pytest.approx(-3.0)
    L = p.segment_lengths()[ramp].sum()
    H = 3.0 / np.tan(np.radians(3.0))                                           # horizontal = dz / tan
    assert L == pytest.approx(np.hypot(H, 3.0), rel=1e-9)
    assert np.all(np.abs(p.xyz[ramp, 0]) <= 10.0 + 1e-9) and np.all(p.xyz[ramp, 1] == 5.0)
    back = ramp[-1] + 1 + np.flatnonzero(p.tag[ramp[-1] + 1:] == "ramp-return")
    assert p.xyz[back[-1]].tolist() == [0.0, 5.0, -3.0]
    assert not np.any(p.is_kind("plunge") & (p.xyz[:, 2] < 0) & (np.arange(len(p)) > 2))


# --- ToolPathBuilder, the one helix/ramp generator, the one resampler, the cleared flag -----------
def test_builder_mark_rollback_restores_the_same_path():
    """A tentative stretch rolled back leaves exactly the path built without it (any mark inside a
    chunk, too); set_cleared/set_tag edit only the given moves."""
    def head(b):
        b.rapid([[0, 0]], z=5); b.plunge([0, 0], -1, 300); b.cut([[1, 0], [2, 0], [3, 0]], 300, z=-1)

    ref = ToolPathBuilder(); head(ref); ref.retract(5, 600)
    for m in range(2, 6):
        b = ToolPathBuilder(); head(b)
        b.link([[3, 3], [0, 3]], 1500, z=-1); b.rollback(m); b.rollback(b.mark())
        if m < 5:                                    # rolled back into the cut chunk: redo its end
            b.cut(np.c_[np.arange(m - 1, 4), np.zeros(5 - m)], 300, z=-1)
        b.retract(5, 600)
        p, q = b.build(), ref.build()
        assert np.array_equal(p.xyz, q.xyz) and np.array_equal(p.kind, q.kind), m
    b = ToolPathBuilder(); head(b); b.set_cleared(1, 2); b.set_tag(2, 4, "x")
    p = b.build()
    assert p.cleared.tolist() == [False, True, False, False, False]
    assert p.tag.tolist() == ["", "", "x", "x", ""]
    with pytest.raises(ValueError, match="mark"):
        b.rollback(99)


def test_builder_helix_descends_linearly_in_length_along_the_ring():
    """helix_ring is closed and regular; the helix loses z in proportion to the xy length travelled
    (hand value: a 4-segment ring of radius 2, depth 2 mm -> 0.5 mm a quarter turn)."""
    ring = helix_ring((1, 1), 2.0, 4)
    assert np.array_equal(ring[0], ring[-1]) and np.allclose(np.hypot(*(ring - 1).T), 2.0)
    b = ToolPathBuilder(); b.rapid(ring[:1], z=0.0); b.helix(ring, 0.0, -2.0, 200)
    p = b.build()
    assert p.kinds().tolist() == ["rapid"] + ["helix"] * 4
    assert np.allclose(p.xyz[1:, 2], [-0.5, -1.0, -1.5, -2.0])
    with pytest.raises(ValueError, match="n_segments"):
        helix_ring((0, 0), 1.0, 2)


@given(st.lists(st.tuples(st.floats(-50, 50), st.floats(-50, 50)), min_size=1, max_size=12),
       st.floats(0.05, 20))
@settings(max_examples=60, deadline=None)
def test_resample_polyline_properties(pts, step):
    """Subdivision keeps every vertex exactly, in order, with steps <= step (+1e-9 mm: the ceil
    tolerance of the piece count) and the same length; the uniform mode keeps both ends and the
    length (to 1e-9 relative) with equal steps; indices name the segment each point ends on."""
    P = np.array(pts, float)
    Q, idx = resample_polyline(P, step, return_index=True)
    L = np.hypot(*np.diff(P, axis=0).T).sum() if len(P) > 1 else 0.0
    d = np.hypot(*np.diff(Q, axis=0).T)
    assert np.all(d <= step * (1 + 1e-9) + 1e-12) and d.sum() == pytest.approx(L, rel=1e-9, abs=1e-9)
    assert np.all(np.diff(idx) >= 0) and idx[0] == 0 and idx[-1] == len(P) - 1
    last_of = {k: j for j, k in enumerate(idx)}            # the last point on each segment
    assert all(np.array_equal(Q[last_of[k]], P[k]) for k in range(len(P)))
    U = resample_polyline(P, step, uniform=True)
    assert np.array_equal(U[0], P[0])
    if L > 0:
        du = np.hypot(*np.diff(U, axis=0).T)
        assert np.allclose(U[-1], P[-1], atol=1e-9) and du.max() <= step * (1 + 1e-9)


def test_writer_reads_the_cleared_flag_not_the_tag():
    """A rapid at depth is written only when the move is flagged cleared; a tag saying 'cleared'
    on an unflagged move decides nothing (the flag given explicitly)."""
    pts = [[0, 0, 5], [0, 0, -1], [10, 0, -1], [10, 5, -1], [20, 5, -1], [20, 5, 5]]
    kind = ["rapid", "plunge", "cut", "rapid", "cut", "retract"]
    ok = ToolPath.build(pts, kind=kind, feed=300, cleared=[0, 1, 0, 1, 0, 0])
    text = write_program(ok, clearance_z=5, spindle_rpm=6000)
    assert text.count("(cnclab:cleared/1)") == 2 and check_program(text, clearance_z=5).ok
    lying = ToolPath.build(pts, kind=kind, feed=300, tag=["", "cleared", "", "cleared", "", ""], cleared=False)
    with pytest.raises(ValueError, match="move 3: rapid"):
        write_program(lying, clearance_z=5, spindle_rpm=6000)
    # the flag survives resampling and concatenation
    r = ok.resample(1.0)
    assert r.cleared[r.is_kind("rapid") & (r.xyz[:, 2] < 0)].all()
    assert ToolPath.concat([ok, ok]).cleared.sum() == 4
