"""Mgherony (2024) chapters 7-9 recipes: pipeline on files, Table 9-2 qualitative claims, Rz cross-checks."""
import numpy as np
import pytest

from cnclab.works.mgherony2024 import ch7_9


@pytest.fixture(scope="module")
def cases():
    return ch7_9.reorder_cases()[0].set_index("case")


def test_table9_2_more_neighbours_longer_path(cases):
    assert cases.loc[3, "distance_mm"] > cases.loc[1, "distance_mm"]
    assert cases.loc[4, "distance_mm"] > cases.loc[2, "distance_mm"]
    for c in (1, 2, 3, 4):     # reordering with jumps always travels further than the original zig-zag
        assert cases.loc[c, "distance_mm"] > cases.loc["original", "distance_mm"]


def test_table9_2_start_point_has_limited_influence_on_jumps(cases):
    for a, b in ((1, 2), (3, 4)):
        assert abs(cases.loc[a, "jumps"] - cases.loc[b, "jumps"]) <= 0.1 * cases.loc[a, "jumps"]


def test_reordering_narrows_deff_and_n_changes(cases):
    for c in (1, 2, 3, 4):
        assert cases.loc[c, "dD_max"] < cases.loc["original", "dD_max"]
        assert cases.loc[c, "dn_max"] < cases.loc["original", "dn_max"]


def test_ch8_pipeline_symmetry_and_ranges():
    s0, s90, s45 = ch7_9.schedule(0.0), ch7_9.schedule(90.0), ch7_9.schedule(45.0)
    # the diagonal symmetry of the part: 0 and 90 deg give the same spindle-speed range
    assert np.isclose(s0.n.min(), s90.n.min(), rtol=1e-6) and np.isclose(s0.n.max(), s90.n.max(), rtol=1e-6)
    assert np.isclose(s0.n.max(), ch7_9.horizontal_n_rpm(), rtol=1e-9)   # horizontal area on the path
    assert s45.n.max() > s0.n.max()                  # 'thesis' rule: 45 deg needs the highest speed
    assert s45.spindle_integral() > s0.spindle_integral()
    const = np.full_like(s0.n, 2000.0)
    assert s0.spindle_integral() > s0.spindle_integral(const)   # control loads the spindle more (Thesis 3)
    assert np.allclose(s0.v_c_actual, 63.0)


def test_acceleration_limit_lowers_share_within_5pct():
    free = ch7_9.schedule(45.0, "max")
    lim = ch7_9.schedule(45.0, "max", accel_rpm_s=500.0)
    assert free.within_share() == 1.0
    assert lim.within_share() < 1.0 and lim.limited.any()


def test_rz_in_text_values_fall_inside_thesis4_ranges():
    r = ch7_9.rz_cross_checks()
    t4 = ch7_9.parameters()["thesis4"]
    assert t4["mean_ratio_pct"][0] <= r["mean_overall"] <= t4["mean_ratio_pct"][1]
    assert t4["mean_ratio_pct"][0] <= r["mean_0deg"] <= t4["mean_ratio_pct"][1]
    assert t4["sd_ratio_pct"][0] <= r["sd_overall"] <= t4["sd_ratio_pct"][1]


def test_files_are_written_and_read_back():
    from cnclab.toolpath import apt
    from cnclab.geometry.mesh import read_stl
    p = ch7_9.zigzag_apt(0.0)
    assert apt.read_apt(p).to_text() == open(p).read()
    assert read_stl(ch7_9.part_stl()).n_facets > 0
