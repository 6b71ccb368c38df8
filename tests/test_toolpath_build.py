"""ToolPath builders shared by the planners: from_segments (a machine-ready level), subdivide,
reordered_path, zigzag_path — kinds, z levels, lengths and times by hand."""
import numpy as np
import pytest

from cnclab.toolpath.path import ToolPath, subdivide
from cnclab.toolpath.reorder import ReorderResult, reordered_path
from cnclab.toolpath.zigzag import zigzag_path


def test_from_segments_jump_and_helix():
    circle = np.c_[1 + np.cos(np.linspace(0, 2 * np.pi, 33)), np.sin(np.linspace(0, 2 * np.pi, 33))]
    circle[-1] = circle[0]
    segs = [(circle, "helix", "entry"), (np.array([[2.0, 0], [10, 0]]), "cut", "a"),
            (np.array([[10.0, 0], [20, 0]]), "jump", ""), (np.array([[20.0, 0], [20, 5]]), "link", "")]
    p = ToolPath.from_segments(segs, z_cut=-2.0, feed=300.0, clearance_z=5.0, link_feed=1500.0)
    k = p.kinds()
    assert k[0] == "rapid" and p.xyz[0, 2] == 5.0 and k[-1] == "retract" and p.xyz[-1, 2] == 5.0
    hel = p.is_kind("helix")
    assert np.all(np.diff(p.xyz[hel, 2]) < 0) and p.xyz[hel, 2][-1] == pytest.approx(-2.0)
    assert (p.tag == "entry-floor").sum() == 32                          # the bored circle, flat at depth
    # the jump: retract at (10, 0), rapid at clearance to (20, 0), plunge
    j = int(np.flatnonzero(k == "retract")[0])
    assert k[j:j + 3].tolist() == ["retract", "rapid", "plunge"]
    assert p.xyz[j + 1].tolist() == [20.0, 0.0, 5.0] and p.xyz[j + 2].tolist() == [20.0, 0.0, -2.0]
    assert np.all(p.xyz[p.is_kind("rapid"), 2] == 5.0)
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
