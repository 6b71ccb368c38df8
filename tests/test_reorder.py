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
    from cnclab.nc import apt
    from cnclab.nc.apt import reordered_program
    from cnclab.toolpath.reorder import ReorderResult

    P = np.array([[0, 0, 1.0], [1, 0, 1], [2, 0, 1], [10, 10, 2], [11, 10, 2]])
    r = ReorderResult(np.array([0, 1, 2, 3, 4]), np.array([False, False, False, True, False]), np.ones(5))
    prog = reordered_program(P, r, feed_mm_min=500, spindle_rpm=2000, tool_diameter=10, clearance_z=30)
    cl = apt.parse_apt(prog.to_text()).cl_points()
    low = cl.xyz[:, 2] < 29
    np.testing.assert_allclose(cl.xyz[low], P)
    # every point on the part is reached by a feed move; each segment start from straight above at Z30
    assert cl.rapid[low].tolist() == [False] * 5
    starts = np.flatnonzero(low & np.r_[True, ~low[:-1]])
    for k in starts:
        assert cl.rapid[k - 1] and cl.xyz[k - 1, 2] == 30 and np.allclose(cl.xyz[k - 1, :2], cl.xyz[k, :2])
    with pytest.raises(ValueError, match="points must be"):
        reordered_program(P[:3], r, feed_mm_min=500, spindle_rpm=2000, tool_diameter=10, clearance_z=30)


@given(st.integers(5, 60), st.sampled_from([1, 2, 4, 8]), st.integers(0, 10_000))
@settings(max_examples=25, deadline=None)
def test_neighbour_sets_knn_and_radius(n, k, seed):
    from cnclab.toolpath.reorder import neighbour_sets

    P = np.random.default_rng(seed).random((n, 3)) * 5
    ip, ix = neighbour_sets(P, k)
    kk = min(k, n - 1)
    D = np.linalg.norm(P[:, None] - P[None], axis=2)
    np.fill_diagonal(D, np.inf)
    brute = np.argsort(D, axis=1)[:, :kk]
    for i in range(n):
        got = ix[ip[i]:ip[i + 1]]
        assert i not in got and sorted(got.tolist()) == sorted(brute[i].tolist())
    step = 0.7
    ip2, ix2 = neighbour_sets(P, k, "radius", step)
    for i in range(n):
        got = ix2[ip2[i]:ip2[i + 1]]
        R = np.ceil(np.sort(D[i])[kk - 1] / step - 1e-9) * step     # smallest multiple of step with >= k inside
        assert sorted(got.tolist()) == sorted(np.flatnonzero(D[i] <= R + 1e-9).tolist())
        assert len(got) >= kk


def test_neighbour_sets_with_duplicate_points_exclude_self():
    from cnclab.toolpath.reorder import neighbour_sets

    P = np.array([[0, 0, 0], [0, 0, 0], [1, 0, 0], [2, 0, 0.0]])
    ip, ix = neighbour_sets(P, 2)
    for i in range(4):
        assert i not in ix[ip[i]:ip[i + 1]]


def test_move_reading_keeps_heading_on_a_slope():
    # an inclined plane (10 deg about x): D_eff depends strongly on the move direction, hardly on the
    # point, so the Sec. 9.2 search (direction="move") runs straight along the feed rows
    x, y = np.meshgrid(np.arange(0, 10, 0.5), np.arange(0, 10, 0.5))
    a = np.radians(10)
    P = np.column_stack([x.ravel(), y.ravel(), y.ravel() * np.tan(a)])
    nrm = np.tile([0, -np.sin(a), np.cos(a)], (len(P), 1))
    r = reorder_path(P, nrm, tool_diameter=10, a_p=0.3, k=4, start=0, feed_direction_deg=90)
    assert sorted(r.order.tolist()) == list(range(len(P)))
    Q = P[r.order]
    assert np.allclose(Q[:20, 0], 0.0) and np.all(np.diff(Q[:20, 1]) > 0)   # the whole first row, uphill
    assert r.n_jumps >= 1                          # the uphill heading cannot be kept after the row end


def test_unvisited_rule_and_adjacent_jumps():
    x, y = np.meshgrid(np.arange(6.0), np.arange(3.0))
    P = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    nrm = np.tile([0, 0, 1.0], (len(P), 1))
    r = reorder_path(P, nrm, tool_diameter=10, a_p=0.3, k=2, neighbours="unvisited")
    assert sorted(r.order.tolist()) == list(range(len(P))) and r.n_jumps == 0   # never an empty set
    far = np.vstack([P, [[40.0, 40.0, 0.0]]])
    r2 = reorder_path(far, np.vstack([nrm, [[0, 0, 1.0]]]), tool_diameter=10, a_p=0.3, k=2,
                      neighbours="unvisited", adjacent_mm=1.5)
    assert r2.n_jumps == 1 and r2.jump[np.flatnonzero(r2.order == len(P))[0]]
    with pytest.raises(ValueError, match="neighbours"):
        reorder_path(P, nrm, tool_diameter=10, a_p=0.3, neighbours="ring")
    with pytest.raises(ValueError, match="radius_step"):
        reorder_path(P, nrm, tool_diameter=10, a_p=0.3, neighbours="radius")
    with pytest.raises(ValueError, match="adjacent_mm"):
        reorder_path(P, nrm, tool_diameter=10, a_p=0.3, adjacent_mm=0)
