"""Checks that used to be ledger rows although the seeds print no such number (issue 13): inverse
residuals of 0, simulated θ = 60° for an input θ = 60°, rotation senses, dixel cost exponents.
They are code checks of the reproduction, kept here with the tolerances the rows had."""
import pytest

from cnclab.runtime import fast_mode
from cnclab.works.jacso2021 import theses_1_3 as t13


# ---------------------------------------------------------------- Thesis I and eq. (1)
def test_thesis1_inverts_the_cosine_theorem_concave_and_convex():
    # θ 1..180°, ρ 3.5..100 mm, r = 3 mm: floating-point round-off only (observed ~1e-11 deg)
    assert t13.thesis1_concave_inverse_residual() <= 1e-9
    assert t13.thesis1_convex_inverse_residual() <= 1e-9


def test_thesis1_reduces_to_the_straight_line_formula():
    # ρ = 1e7 mm: O(r²/ρ) plus cancellation round-off (~5e-7 mm)
    assert t13.thesis1_straight_limit_residual() <= 1e-5


def test_thesis1_reaches_the_upper_bound_2r_at_slotting():
    # the booklet's boundary condition s ∈ [0, 2 r_sz]: s(180°, ρ) = 2r for every ρ, both k
    assert t13.thesis1_s_at_180_over_r() == pytest.approx(2.0, abs=1e-12)


def test_kim_yang_eq1_is_jacso_concave_case():
    # eq. 1 with R = ρ + s and r = tool radius is the concave cosine theorem; Thesis I inverts it
    assert t13.kim_yang_eq1_equivalence_residual() <= 1e-9
    assert t13.kim_yang_eq1_thesis1_roundtrip() <= 1e-9
    assert t13.kim_yang_eq1_straight_limit_residual() <= 1e-4  # R = 1e7 mm: O(r/R)


# ---------------------------------------------------------------- simulated engagement
@pytest.mark.parametrize("fn", [t13.sim_straight_theta60, t13.sim_concave_theta60, t13.sim_convex_theta60],
                         ids=["straight", "concave", "convex"])
def test_dixel_simulation_holds_the_design_engagement(fn):
    # a Thesis I (or θ(s)) stepover for 60° cut in the dixel simulator at 0.02 mm rows:
    # simulator accuracy target 0.2° (dixel error O(h²), ~0.01° here)
    assert fn() == pytest.approx(60.0, abs=0.2)


# ---------------------------------------------------------------- Theses II and III
def test_thesis2_equation_rotates_cp_clockwise_to_the_feed():
    # p = c + R(π/2 + θ) p' r/|p'| makes CP the feed rotated ccw by β: feed = CP rotated cw by β
    assert t13.thesis2_rotation_cp_to_feed() == pytest.approx(-150.0, abs=1e-9)
    assert t13.thesis2_rotation_prose_clockwise() == pytest.approx(150.0, abs=1e-9)


def test_thesis3_step1_alpha_agrees_with_thesis2():
    assert t13.thesis3_alpha_from_thesis2() == pytest.approx(30.0, abs=1e-9)  # α = π/2 − θ


def test_thesis2_ivp_on_an_arc_is_the_thesis1_offset():
    assert t13.thesis2_ivp_arc_radius_residual() <= 1e-6  # ODE solver rtol = atol = 1e-10


def test_thesis3_path_holds_the_engagement_on_a_blob():
    # midpoint, dt = 0.05, 0.05 mm rows: path error O(dt²) (mean -0.05° here)
    assert t13.blob_mean_engagement_coarse() == pytest.approx(60.0, abs=0.2)


@pytest.mark.skipif(fast_mode(), reason="slow (0.01 mm rows); run in full mode")
def test_thesis3_path_max_deviation_after_entry():
    assert t13.blob_max_deviation_fine() <= 1.0


# ---------------------------------------------------------------- §2.2 dixel representation
def test_dixel_disk_area_is_exact():
    assert t13.dixel_disk_area_ratio() == pytest.approx(1.0, abs=1e-12)


def test_dixel_data_grows_linearly_pixel_data_quadratically():
    # log-log fit over 5 resolutions 0.2..0.01 mm; ceil() rounding gives ~1 % scatter
    assert t13.dixel_data_exponent() == pytest.approx(1.0, abs=0.05)
    assert t13.pixel_data_exponent() == pytest.approx(2.0, abs=0.05)


def test_thesis3_explicit_algorithm_as_printed_on_a_convex_arc():
    """Steps 0-5 exactly as printed (explicit Euler, constant Δt, polyline) turning a ρ = 8 mm disk at
    θ = 60° (r = 3 mm): the path stays at the Thesis I offset ρ − s + r up to a first-order error."""
    import numpy as np

    from cnclab.geometry.contours import Arc
    from cnclab.toolpath import constant_engagement as ce

    errs = []
    for dt in (0.2, 0.1, 0.05):
        arc = Arc((0, 0), 8.0, 0, -300)          # cw: the material (the disk) on the right
        P0, d = ce.arc_start_point(arc, 3.0, 60.0, "convex")
        res = ce.thesis3_path(arc, 3.0, 60.0, dt, method="euler", P0=P0)
        errs.append(float(np.max(np.abs(np.hypot(*res.P.T) - d))))
    assert errs[0] / errs[1] == pytest.approx(2.0, rel=0.05)   # first order in Δt
    assert errs[1] / errs[2] == pytest.approx(2.0, rel=0.05)
    assert errs[2] < 0.011                                       # 0.0097 mm at Δt = 0.05 mm
