"""Hoang (2024) eqs 1-7 (cnclab.cutting.scallop_volume) and the ball-end height field."""
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cnclab.cutting import scallop_volume as sv
from cnclab.simulation.heightfield import HeightField
from cnclab.works.hoang2024 import constant_volume as cv

radii = st.floats(0.5, 10.0)


@settings(max_examples=60, deadline=None)
@given(radii, st.floats(0.001, 0.99))
def test_stepover_and_scallop_height_are_inverse(r, frac):
    sc = frac * r
    assert sv.scallop_height(sv.stepover(sc, r), r) == pytest.approx(sc, rel=1e-9, abs=1e-12)


@settings(max_examples=60, deadline=None)
@given(radii, st.floats(0.001, 0.2), st.floats(0.1, 50))
def test_forward_step_inverts_eq2(r, frac, fr):
    sc = frac * r
    v = sv.block_volume_v1_star(sc, r, fr)
    assert sv.forward_step(v, sc, r) == pytest.approx(fr, rel=1e-9)


def test_hand_computed_case():
    # R=2.5, Sc=0.05: Sz = 2 sqrt(6.25 - 2.45^2) = 2 sqrt(0.2475)
    assert sv.stepover(0.05, 2.5) == pytest.approx(2 * math.sqrt(0.2475))
    th = sv.theta_from_stepover(2 * math.sqrt(0.2475), 2.5)
    assert math.sin(th) == pytest.approx(math.sqrt(0.2475) / 2.5)
    assert sv.curvature_volume(th, 2.5) == pytest.approx(3.125 * (th - math.sin(th)))
    assert sv.block_volume_v1(0.05, 1.0, 3.0) == pytest.approx(0.075)
    assert sv.block_volume_v2(0.05, 1.0, 3.0) == pytest.approx(0.05)


def test_exact_area_tends_to_v2_for_small_stepover():
    # parabolic limit: ridge area -> Sc*Sz/3, i.e. eq. 4 per unit F_r
    r, sc = 5.0, 1e-4
    sz = sv.stepover(sc, r)
    assert sv.scallop_area_exact(sz, r) == pytest.approx(sc * sz / 3, rel=1e-3)


def test_printed_convention_reproduces_table2_and_differs_from_consistent():
    t, p = cv.table2_recomputed(), cv.table2_printed()
    assert np.all(np.abs(t.Fr_printed_convention - p.Fr_mm) <= 5e-6)
    assert np.all(t.Fr_consistent / p.Fr_mm > 10)
    # with the true pi instead of 3.14 the printed digits are NOT all reproduced
    alt = [sv.forward_step_as_printed(r.V_mm3, r.Sc_mm, r.RT_mm, pi=math.pi) for _, r in p.iterrows()]
    assert np.max(np.abs(np.array(alt) - p.Fr_mm.to_numpy())) > 5e-6


@pytest.mark.parametrize("call, name", [
    (lambda: sv.stepover(-0.1, 2.0), "scallop_height"),
    (lambda: sv.stepover(0.05, 0.0), "tool_radius"),
    (lambda: sv.stepover(3.0, 2.0), "scallop_height must be <= tool_radius"),
    (lambda: sv.theta_from_stepover(5.0, 2.0), "stepover_mm must be <= 2"),
    (lambda: sv.forward_step(-1, 0.05, 2.0), "volume"),
    (lambda: HeightField.box((0, 1), (0, 1), 0.0, 1.0), "resolution"),
])
def test_bad_input_names_parameter(call, name):
    with pytest.raises(ValueError, match=name):
        call()


def test_heightfield_sweep_matches_exact_ridge_area():
    sc, r, fr = 0.05, 2.5, 3.0
    v = cv.uncut_volume_per_cell(sc, r, fr, resolution=0.01)
    exact = sv.scallop_area_exact(sv.stepover(sc, r), r) * fr
    assert v == pytest.approx(exact, rel=0.01)


def test_heightfield_discrete_is_larger_and_uncovered_raises():
    sc, r = 0.05, 2.5
    fr = 3.0
    assert cv.uncut_volume_per_cell(sc, r, fr, 0.02, discrete=True) > \
        cv.uncut_volume_per_cell(sc, r, fr, 0.02)
    with pytest.raises(ValueError, match="forward_step"):
        cv.uncut_volume_per_cell(sc, r, 44.0, 0.05, discrete=True)


def test_heightfield_point_is_a_sphere():
    hf = HeightField.box((-3, 3), (-3, 3), 0.05, z_top=5.0)
    hf.cut_ball_point((0, 0, 0), 2.0)
    X, Y = np.meshgrid(hf.xc, hf.yc)
    d2 = X ** 2 + Y ** 2
    inside = d2 < 4
    assert np.allclose(hf.z[inside], 2 - np.sqrt(4 - d2[inside]))
    assert np.all(hf.z[~inside] == 5.0)
