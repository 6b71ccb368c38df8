"""Engagement formulas: Thesis I as exact inverse, limits, Kim & Yang eq. 1 equivalence, bad input."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cnclab.geometry import engagement as eng

R = 3.0


def test_straight_hand_values():
    assert float(eng.theta_straight(1.5, R)) == pytest.approx(60.0, abs=1e-12)
    assert float(eng.theta_straight(3.0, R)) == pytest.approx(90.0, abs=1e-12)
    assert float(eng.theta_straight(6.0, R)) == pytest.approx(180.0, abs=1e-12)


def test_convex_hand_value():
    # theta = 90 deg, rho = 5, r = 3: d = sqrt(rho^2 - r^2) = 4 -> s = rho + r - d = 4
    assert float(eng.stepover_thesis1(90.0, 5.0, R, "convex")) == pytest.approx(4.0, abs=1e-12)
    assert float(eng.theta_convex(4.0, 5.0, R)) == pytest.approx(90.0, abs=1e-9)


@settings(max_examples=200, deadline=None)
@given(theta=st.floats(1.0, 179.0), rho=st.floats(3.2, 200.0), kind=st.sampled_from(["concave", "convex"]))
def test_thesis1_is_exact_inverse(theta, rho, kind):
    if rho < float(eng.rho_min(theta, R)):
        return
    s = eng.stepover_thesis1(theta, rho, R, kind)
    assert 0 <= float(s) <= 2 * R
    assert float(eng.theta_arc(s, rho, R, kind)) == pytest.approx(theta, abs=1e-7)


@settings(max_examples=100, deadline=None)
@given(s=st.floats(0.05, 5.9), rho=st.floats(4.0, 100.0))
def test_concave_more_than_straight_more_than_convex(s, rho):
    """Booklet §2.1: at equal stepover theta grows on concave and shrinks on convex arcs."""
    t_cc, t_line, t_cv = (float(eng.theta_arc(s, rho, R, k)) for k in ("concave", "straight", "convex"))
    assert t_cc >= t_line - 1e-9 and t_line >= t_cv - 1e-9


def test_large_radius_tends_to_line():
    th = np.linspace(5, 175, 35)
    for kind in ("concave", "convex"):
        s = eng.stepover_thesis1(th, 1e6, R, kind)
        assert np.allclose(s, R * (1 - np.cos(np.radians(th))), atol=1e-4)


def test_kim_yang_equivalence_and_straight_limit():
    s = np.linspace(0.1, 5.5, 50)
    rho = 10.0
    assert np.allclose(eng.theta_kim_yang(s, rho + s, R), eng.theta_concave(s, rho, R), atol=1e-9)
    assert np.allclose(eng.theta_kim_yang(s, 1e8, R), eng.theta_straight(s, R), atol=1e-4)
    # with r read as the radial depth (= s on a line) eq. 1 would give 90 deg for any s
    assert np.allclose(180 - np.degrees(np.arccos((s - s) / s)), 90.0)


@pytest.mark.parametrize("call, name", [
    (lambda: eng.theta_straight(-0.1, R), "s (stepover)"),
    (lambda: eng.theta_straight(7.0, R), "s (stepover)"),
    (lambda: eng.theta_straight(1.0, 0.0), "tool_radius"),
    (lambda: eng.stepover_thesis1(0.0, 5.0, R, "concave"), "theta_deg"),
    (lambda: eng.stepover_thesis1(181.0, 5.0, R, "concave"), "theta_deg"),
    (lambda: eng.stepover_thesis1(90.0, 2.0, R, "convex"), "rho must be >= r sin"),
    (lambda: eng.stepover_thesis1(60.0, 5.0, R, "wavy"), "kind"),
    (lambda: eng.theta_kim_yang(1.0, 2.0, R), "R (corner radius)"),
])
def test_bad_input_names_parameter(call, name):
    with pytest.raises(ValueError, match=name.split()[0]):
        call()
