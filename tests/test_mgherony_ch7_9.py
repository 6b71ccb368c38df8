"""Mgherony (2024) chapters 7-9 recipes: pipeline on files, Table 9-2 qualitative claims, Rz cross-checks."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cnclab.runtime import fast_mode
from cnclab.works.mgherony2024 import ch7_9


@pytest.fixture(scope="module")
def cases():
    return ch7_9.reorder_cases()[0].set_index("case")


def test_table9_2_more_neighbours_longer_path(cases):
    assert cases.loc[3, "distance_mm"] > cases.loc[1, "distance_mm"]
    assert cases.loc[4, "distance_mm"] > cases.loc[2, "distance_mm"]
    for c in (1, 2, 3, 4):     # reordering with jumps always travels further than the original zig-zag
        assert cases.loc[c, "distance_mm"] > cases.loc["original", "distance_mm"]


def test_table9_2_more_neighbours_more_jumps(cases):
    # Sec. 9.3 / Fig 9-8b: 181, 180 jumps at k = 4 vs 426, 432 at k = 8 (ratio ~2.4) under the Sec. 9.2
    # reading (k-NN sets, D_eff of each neighbour for the direction of the move to it)
    for a, b in ((1, 3), (2, 4)):
        assert cases.loc[b, "jumps"] > 1.5 * cases.loc[a, "jumps"]
    # and the jumps are the text's: only when every neighbour is visited, so no feed move skips a point
    assert cases.loc[1, "jumps"] > 0


def test_table9_2_start_point_has_limited_influence_on_jumps(cases):
    # Table 9-2: 181 vs 180 and 426 vs 432 jumps (corner vs middle start). Full resolution (CL step
    # 2 mm): within 10 % (measured 166 vs 173, 557 vs 509). Fast mode (4 mm CL step, half the
    # points) is coarser: the greedy search reacts more to one point, so 20 % there (measured 186 vs
    # 161 since the path's first contact point is a fed CL point: issue 12, no rapid onto the part).
    tol = 0.2 if fast_mode() else 0.1
    for a, b in ((1, 2), (3, 4)):
        assert abs(cases.loc[a, "jumps"] - cases.loc[b, "jumps"]) <= tol * cases.loc[a, "jumps"]


def test_reordering_narrows_deff_and_n_changes(cases):
    # Figs 9-9 ... 9-12 compare the original with case 1; the k = 4 cases narrow both maxima
    for c in (1, 2):
        assert cases.loc[c, "dD_max"] < cases.loc["original", "dD_max"]
        assert cases.loc[c, "dn_max"] < cases.loc["original", "dn_max"]


def test_constant_direction_reading_reverses_the_jump_trend_and_why():
    """The finding: with D_eff evaluated at the constant A_f (a scalar field over the points) more
    neighbours give FEWER jumps; the printed trend needs the direction-dependent D_eff of Sec. 9.2,
    whose spread over the move directions dwarfs the change between neighbours, so the search keeps
    its heading (straight runs; with k = 8 also diagonal ones, which strand points -> jumps)."""
    const = ch7_9.reorder_cases("constant")[0].set_index("case")
    for a, b in ((1, 3), (2, 4)):
        assert const.loc[b, "jumps"] < const.loc[a, "jumps"]
        assert const.loc[b, "distance_mm"] > const.loc[a, "distance_mm"]     # longer path holds in both
    spread = ch7_9.deff_direction_spread()
    assert spread["direction_spread_median_mm"] > 10 * spread["adjacent_change_median_mm"]
    a_e = ch7_9.parameters()["table9_1"]["a_e"]
    _, dense, orders = ch7_9.reorder_cases()
    s4, s8 = (ch7_9.move_statistics(dense, orders[c], a_e) for c in (1, 3))
    _, _, const_orders = ch7_9.reorder_cases("constant")
    c4 = ch7_9.move_statistics(dense, const_orders[1], a_e)
    # heading persistence: the move reading goes straight on far more often than the scalar-field one
    assert s4["straight_share"] > 0.85 and s4["straight_share"] > c4["straight_share"] + 0.1
    assert s4["diagonal_share"] < 0.05 and s8["diagonal_share"] > 0.3
    assert s8["mean_feed_step_mm"] > s4["mean_feed_step_mm"]                 # diagonal steps: longer path


def test_ch8_pipeline_symmetry_and_ranges():
    s0, s90, s45 = ch7_9.schedule(0.0), ch7_9.schedule(90.0), ch7_9.schedule(45.0)
    # the diagonal symmetry of the part: 0 and 90 deg give the same spindle-speed range
    assert np.isclose(s0.n.min(), s90.n.min(), rtol=1e-6) and np.isclose(s0.n.max(), s90.n.max(), rtol=1e-6)
    assert np.isclose(s0.n.max(), ch7_9.horizontal_n_rpm(), rtol=1e-9)   # horizontal area on the path
    assert s45.n.max() > s0.n.max()                  # 'thesis' rule: 45 deg needs the highest speed
    assert s45.spindle_integral() > s0.spindle_integral()
    const = np.full_like(s0.n, 2000.0)
    assert s0.spindle_integral() > s0.spindle_integral(const)   # control loads the spindle more (Thesis 3)
    # without control (constant 2000 rpm) the actual v_c falls far below the nominal 63 m/min: lowest on the
    # horizontal area (eq 5-6 at D_eff = 2 sqrt(a_p (D - a_p)) = 3.41 mm -> 21.4), highest on the steepest slope
    from cnclab.cutting.speeds import cutting_speed
    v_const = cutting_speed(s0.d_eff, 2000.0)
    assert v_const.min() == pytest.approx(ch7_9.vc_min_at_2000(), rel=1e-9)
    assert 40.0 < v_const.max() < 63.0
    # the controlled spindle speed is ordered inversely to the working diameter (eq 7-4)
    order = np.argsort(s0.d_eff)
    assert np.all(np.diff(s0.n_ideal[order]) <= 1e-9)


def test_acceleration_limit_lowers_share_within_5pct():
    free = ch7_9.schedule(45.0, "max")
    lim = ch7_9.schedule(45.0, "max", accel_rpm_s=500.0)
    assert free.within_share() == 1.0
    assert lim.within_share() < 1.0 and lim.limited.any()


def test_files_are_written_and_read_back():
    from cnclab.nc import apt
    from cnclab.geometry.mesh import read_stl
    p = ch7_9.zigzag_apt(0.0)
    assert apt.read_apt(p).to_text() == open(p).read()
    assert read_stl(ch7_9.part_stl()).n_facets > 0


def test_reordered_apt_round_trip_visits_every_point_once():
    from cnclab.nc import apt
    cases, dense, orders = ch7_9.reorder_cases()
    path = ch7_9.reordered_apt(1)
    prog = apt.read_apt(path)
    assert prog.to_text() == open(path).read()
    cl = prog.cl_points()
    cut = cl.xyz[cl.xyz[:, 2] < 29.0]                     # below the 30 mm clearance plane
    np.testing.assert_allclose(cut, dense[orders[1].order], atol=5e-4)
    low = cl.xyz[:, 2] < 29.0
    assert not (cl.rapid & low).any()                     # never a rapid onto the part
    approach = low & np.r_[False, ~low[:-1]]              # fed down from the clearance plane
    assert approach.sum() == orders[1].n_jumps + 1        # first approach + one per jump
    # every feed move joins two neighbours: no feed move longer than the k-NN reach of a jump-free step
    on_part = ~cl.rapid[1:] & low[1:] & low[:-1]          # feed moves between points on the part
    feed_moves = np.linalg.norm(np.diff(cl.xyz, axis=0), axis=1)[on_part]
    assert feed_moves.max() < 3 * ch7_9.parameters()["table9_1"]["a_e"]


def test_deltas_match_path_metrics():
    cases = ch7_9.reorder_cases()[0].set_index("case")
    for case in ("original", 1, 4):
        d = ch7_9.deltas(case)
        assert np.isclose(d["dD"].max(), cases.loc[case, "dD_max"])
        assert np.isclose(d["dn"].max(), cases.loc[case, "dn_max"])


@settings(max_examples=60, deadline=None)
@given(st.floats(0.5, 40.0), st.floats(100.0, 30000.0), st.floats(0.01, 0.5), st.integers(1, 8))
def test_speed_relations_are_inverse(D, n, f_z, z):
    """eq 5-6 / eq 7-4 are inverses and eq 7-5 is linear in n (the relations behind the ch. 7 control law)."""
    from cnclab.cutting.speeds import cutting_speed, feed_speed, spindle_speed
    v = cutting_speed(D, n)
    assert spindle_speed(v, D) == pytest.approx(n, rel=1e-12)
    assert feed_speed(f_z, z, 2 * n) == pytest.approx(2 * feed_speed(f_z, z, n), rel=1e-12)
    assert float(feed_speed(f_z, z, n)) / (z * n) == pytest.approx(f_z, rel=1e-12)


def test_feed_direction_list_typo():
    assert ch7_9.feed_direction_step_deg() == 22.5 and ch7_9.feed_direction_typo_deg() == 22.0


def test_reconstructed_n_min_is_the_steepest_working_diameter():
    # n_min (eq 7-4) comes from the largest D_eff on the reconstructed part; the pipeline on the 0.5 mm
    # STL + CL files lands within 1 % of the exact-normal value (facet normals of a discretised surface)
    t = ch7_9.parameters()["table7_1"]
    d_max = ch7_9.analytic_deff_range(0.0)[1]
    assert ch7_9.n_min_reconstruction() == pytest.approx(1000 * t["v_c"] / (np.pi * d_max), rel=1e-12)
    assert abs(ch7_9.schedule(0.0).n.min() / ch7_9.n_min_reconstruction() - 1) < 0.01
    assert ch7_9.n_min_reconstruction() < ch7_9.horizontal_n_rpm()



def test_chapter10_counts_the_stated_thesis_points(monkeypatch):
    from cnclab.works.mgherony2024 import ch10
    t = ch10.theses()
    assert ch10.thesis_point_count() == len(t["theses"]) == 5 and t["announced_count"] == 7
    gap = {**t, "theses": [x for x in t["theses"] if x["number"] != 3]}
    monkeypatch.setattr(ch10, "theses", lambda: gap)
    with pytest.raises(ValueError, match="not 1..n"):
        ch10.thesis_point_count()
