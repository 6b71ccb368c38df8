"""Tool-path reordering (cnclab.toolpath.reorder): densification and the tabu search."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cnclab.toolpath.reorder import densify, path_metrics, reorder_path


@given(st.integers(2, 30), st.floats(0.05, 3.0), st.integers(0, 10_000))
@settings(max_examples=30, deadline=None)
def test_densify_properties(n, d_lim, seed):
    P = np.random.default_rng(seed).random((n, 3)) * 10
    D, src = densify(P, d_lim)
    assert np.all(np.linalg.norm(np.diff(D, axis=0), axis=1) <= d_lim + 1e-9)
    # the polyline is unchanged (same length) and every original point is kept
    L0 = np.linalg.norm(np.diff(P, axis=0), axis=1).sum()
    L1 = np.linalg.norm(np.diff(D, axis=0), axis=1).sum()
    assert np.isclose(L0, L1)
    for p in P:
        assert np.min(np.linalg.norm(D - p, axis=1)) < 1e-9


def test_reorder_visits_every_point_once_and_flat_follows_feed():
    x, y = np.meshgrid(np.arange(10.0), np.arange(4.0))
    P = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    nrm = np.tile([0, 0, 1.0], (len(P), 1))
    r = reorder_path(P, nrm, tool_diameter=10, a_p=0.3, k=4, start=0, feed_direction_deg=0)
    assert sorted(r.order.tolist()) == list(range(len(P)))
    assert r.order[:10].tolist() == list(range(10))        # flat: continue in the feed direction
    m = path_metrics(P[r.order], r.d_eff, jump=r.jump)
    assert m["dD_max"] == 0.0 and m["jumps"] == r.n_jumps


def test_reorder_prefers_smallest_deff_change():
    # a line of points; the neighbour on the right has the same slope, the one above a different slope
    P = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0], [0, 2, 0.0]])
    n_flat = [0, 0, 1.0]
    s = np.sin(np.radians(15))
    n_slope = [0, -s, np.cos(np.radians(15))]
    nrm = np.array([n_flat, n_flat, n_slope, n_flat, n_slope])
    r = reorder_path(P, nrm, tool_diameter=10, a_p=0.3, k=2, start=0, feed_direction_deg=90, direction="constant")
    assert r.order[1] == 1


def test_reorder_bad_input():
    P = np.zeros((3, 3))
    with pytest.raises(ValueError, match="start"):
        reorder_path(P, np.tile([0, 0, 1.0], (3, 1)), tool_diameter=10, a_p=0.3, start=5)
    with pytest.raises(ValueError, match="d_lim"):
        densify(P, 0)
    with pytest.raises(ValueError, match="direction"):
        reorder_path(P, np.tile([0, 0, 1.0], (3, 1)), tool_diameter=10, a_p=0.3, direction="x")


def test_reordered_program_links_segments_by_rapids():
    from cnclab.toolpath import apt
    from cnclab.toolpath.reorder import ReorderResult, reordered_program

    P = np.array([[0, 0, 1.0], [1, 0, 1], [2, 0, 1], [10, 10, 2], [11, 10, 2]])
    r = ReorderResult(np.array([0, 1, 2, 3, 4]), np.array([False, False, False, True, False]), np.ones(5))
    prog = reordered_program(P, r, feed_mm_min=500, spindle_rpm=2000, tool_diameter=10, clearance_z=30)
    cl = apt.parse_apt(prog.to_text()).cl_points()
    low = cl.xyz[:, 2] < 29
    np.testing.assert_allclose(cl.xyz[low], P)
    assert cl.rapid[low].tolist() == [True, False, False, True, False]
    with pytest.raises(ValueError, match="points must be"):
        reordered_program(P[:3], r, feed_mm_min=500, spindle_rpm=2000, tool_diameter=10, clearance_z=30)
