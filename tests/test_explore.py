"""The explorers' pure scene functions (real geometric properties) and their widget layer (headless)."""
import math
import re

import numpy as np
import pytest

from cnclab.cutting import scallop_volume as sv
from cnclab.explore import scenes as S
from cnclab.explore import widgets as X
from cnclab.geometry import ball_end, engagement


# ------------------------------------------------------------------------------------ Thesis I
@pytest.mark.parametrize("kind", ["concave", "convex", "straight"])
@pytest.mark.parametrize("s", [0.3, 1.5, 3.0, 4.5, 5.7])
@pytest.mark.parametrize("rho", [2.0, 8.0, 40.0])
def test_drawn_engaged_arc_subtends_the_formula_angle(kind, s, rho):
    try:
        engagement.theta_arc(s, rho, 3.0, kind)
    except ValueError as exc:                       # invalid combination: the scene refuses it too
        with pytest.raises(ValueError, match="^" + re.escape(str(exc)) + "$"):
            S.thesis1_scene(s, rho, 3.0, kind)
        return
    sc = S.thesis1_scene(s, rho, 3.0, kind)
    # independent geometry (intersection of the tool with the previous contour) vs the closed form;
    # 1e-7 deg: double-precision round-off of acos near 0/180 deg
    assert sc["drawn_theta_deg"] == pytest.approx(sc["theta_deg"], abs=1e-7)
    P, r = sc["tool_centre"], 3.0
    arc = sc["engaged_arc"]
    assert np.allclose(np.hypot(*(arc - P).T), r)                  # on the tool periphery
    ends = arc[[0, -1]]
    assert np.allclose(ends[0], sc["touch_point"]) and np.allclose(ends[1], sc["contact_point"])
    if kind != "straight":                                          # the arc lies in the removed ring
        d = np.hypot(*arc.T)
        lo, hi = sorted([rho, rho + (s if kind == "concave" else -s)])
        assert d.min() >= lo - 1e-9 and d.max() <= hi + 1e-9
        assert np.hypot(*sc["contact_point"]) == pytest.approx(rho)  # C is on the previous contour


def test_thesis1_inverse_round_trip_in_scene():
    sc = S.thesis1_scene(1.5, 8.0, 3.0, "concave")
    assert sc["s_thesis1_mm"] == pytest.approx(1.5, abs=1e-12)


def test_thesis1_refuses_like_the_package():
    with pytest.raises(ValueError) as pkg:
        engagement.theta_arc(7.0, 8.0, 3.0, "concave")
    ex = X.thesis1_explorer()
    ex.controls["stepover"].value = 7.0
    assert ex.error == str(pkg.value) and ex.scene is None
    assert "refused" in ex.message.value


def test_thesis1_curves_match_formulas():
    c = S.thesis1_curves(8.0, 3.0, n=31)
    assert np.allclose(c["straight"], engagement.theta_straight(c["s_mm"], 3.0))
    assert np.nanmax(np.abs(c["concave"] - engagement.theta_concave(c["s_mm"], 8.0, 3.0))) < 1e-12


# --------------------------------------------------------------------------------- Thesis III
@pytest.mark.parametrize("contour", S.CE_CONTOURS)
def test_ce_growth_holds_theta_after_entry(contour):
    sc = S.ce_growth_scene(contour, 60.0, 3.0, 0.6, resolution_mm=0.1)
    e, s = sc["engagement_deg"], sc["s_mm"]
    m = (s > 6.0) & (s < s[-1] - 1.0)
    # dixel rows of 0.1 mm and Δt of the explorer: median within 1 deg, 90 % of points within 3 deg
    assert abs(np.nanmedian(e[m]) - 60.0) < 1.0
    assert np.mean(np.abs(e[m] - 60.0) < 3.0) > 0.9
    # contact points are the contour points, at distance r... only at the exact solution; the path
    # keeps the tool within r of its contact point (the contact is on the tool periphery)
    assert np.allclose(np.hypot(*(sc["P"] - sc["C"]).T), 3.0, atol=1e-6)


def test_ce_growth_progress_grows_the_path():
    a = S.ce_growth_scene("ellipse", 60.0, 3.0, 0.3, resolution_mm=0.2)
    b = S.ce_growth_scene("ellipse", 60.0, 3.0, 0.6, resolution_mm=0.2)
    n = len(a["P"]) - 1                      # the last step of the shorter path is truncated
    assert len(b["P"]) > len(a["P"]) and np.allclose(b["P"][:n], a["P"][:n])
    with pytest.raises(ValueError, match="progress"):
        S.ce_growth_scene("ellipse", 60.0, 3.0, 0.0)
    with pytest.raises(ValueError, match="contour"):
        S.ce_contour("square")


def test_trochoid_circle_simulated_max_is_near_the_exact_front_engagement():
    sc = S.trochoid_scene("circle", 1.0, 12.0, 3.0, resolution_mm=0.1)
    m = sc["metrics"]["engagement_max_deg"]
    # the exact front-point engagement is a lower bound of the period's maximum (docstring of
    # max_engagement_circle_front); the maximum lies slightly after it: within 8 deg here
    assert sc["front_engagement_deg"] - 1.0 <= m <= sc["front_engagement_deg"] + 8.0


def test_trochoid_ce_pattern_cuts_at_theta():
    sc = S.trochoid_scene("constant-engagement", 1.0, 12.0, 3.0, theta_deg=60.0, resolution_mm=0.1)
    cut = sc["metrics"]["engagement_max_cut_deg"]
    assert abs(cut - 60.0) < 6.0     # coarse 0.1 mm dixels and 4 iterations (explorer speed)
    with pytest.raises(ValueError, match="pattern"):
        S.trochoid_scene("square", 1.0, 12.0, 3.0)


# --------------------------------------------------------------------------------- Kim & Yang
def test_kim_yang_modification_reduces_excess_mrr():
    sc = S.kim_yang_scene(60.0, pixel_mm=0.6, tolerance=0.25)
    assert sc["stepover_mm"] == pytest.approx(2.5)                         # r (1 - cos 60)
    assert sc["nominal_mrr_mm3_min"] == pytest.approx(0.5 * 2.5 * 500.0)
    assert sc["n_insertions"] > 0
    lim = 1.5 * sc["nominal_mrr_mm3_min"]
    over = lambda tr: float(np.sum(np.clip(tr[:, 1] - lim, 0, None)))      # noqa: E731
    assert over(sc["mrr_modified"]) < over(sc["mrr_original"])
    # removed volume is the same pocket either way (both clear it): within 5 % pixel noise
    vol = lambda tr: float(np.sum(tr[1:, 1] * np.diff(tr[:, 0])))          # noqa: E731
    assert vol(sc["mrr_modified"]) == pytest.approx(vol(sc["mrr_original"]), rel=0.05)


# -------------------------------------------------------------------------------------- Hoang
@pytest.mark.parametrize("sc_mm,r", [(0.05, 2.5), (0.01, 1.0), (0.5, 4.0)])
def test_hoang_section_has_the_scallop_height_and_area(sc_mm, r):
    sc = S.hoang_scene(sc_mm, r, 0.1, n=4001)
    assert sc["drawn_peak_mm"] == pytest.approx(sc_mm, rel=1e-9)
    assert sc["drawn_area_mm2"] == pytest.approx(sc["exact_area_mm2"], rel=1e-4)   # trapezoid, 4001 pts
    assert sc["Fr_consistent"] == pytest.approx(float(sv.forward_step(0.1, sc_mm, r)))


def test_hoang_refuses_like_the_package():
    with pytest.raises(ValueError) as pkg:
        sv.stepover(3.0, 2.5)
    ex = X.hoang_explorer()
    ex.controls["scallop_height_mm"].value = 3.0
    assert ex.error == str(pkg.value)


# ----------------------------------------------------------------------------------- Mgherony
@pytest.mark.parametrize("A_N1,A_N2,A_f", [(30, 20, 0), (120, 45, 30), (-60, -35, 200), (0, 0, 45)])
def test_tangent_points_lie_on_the_contact_circle(A_N1, A_N2, A_f):
    sc = S.working_diameter_scene(10.0, 1.0, A_N1, A_N2, A_f, 0.5)
    n, c = sc["normal"], sc["circle_centre"]
    for k in ("p1", "p2"):
        p = sc[k]
        assert np.linalg.norm(p) == pytest.approx(5.0)                        # on the ball
        assert np.dot(p - c, n) == pytest.approx(0.0, abs=1e-12)             # in the surface plane
        assert np.linalg.norm(p - c) == pytest.approx(sc["circle_radius"])   # on the circle
        assert sc["d" + k[1] + "_mm"] == pytest.approx(2 * math.hypot(p[0], p[1]))
    # the drawn circle: its xy projection is tangent to the feed at the tangent points
    C = sc["circle"][:-1]
    f = sc["feed_dir"][:2]
    m = np.array([-f[1], f[0]])
    i1, i2 = np.argmax(C[:, :2] @ m), np.argmin(C[:, :2] @ m)
    assert np.dot(C[i1, :2] - sc["p1"][:2], m) == pytest.approx(0.0, abs=1e-3)   # point 1: left of feed
    assert np.dot(C[i2, :2] - sc["p2"][:2], m) == pytest.approx(0.0, abs=1e-3)


def test_working_diameter_refusal_matches_package():
    with pytest.raises(ValueError) as pkg:
        ball_end.validate_model_inputs(10.0, 0.3, 30.0, 100.0, 0.0, 0.25)
    ex = X.working_diameter_explorer()
    ex.controls["A_N2"].value = 100.0
    assert ex.error == str(pkg.value)


def test_cusp_profile_height_and_rz_equal_the_cusp_height():
    sc = S.cusp_scene(0.2, 0.8, n_periods=10, n=20001)
    assert sc["z"].max() == pytest.approx(sc["CH_mm"], rel=1e-4)   # sampled peak: 1e-4 at 20001 pts
    assert sc["Rz_mm"] == pytest.approx(sc["CH_mm"], rel=1e-3)     # each section holds a whole cusp
    assert sc["CH_approx_mm"] == pytest.approx(0.2 ** 2 / (8 * 0.8))


def test_spindle_scene_keeps_cutting_speed_where_not_limited(tmp_path, monkeypatch):
    sc = S.spindle_scene(45.0)
    free = ~sc["limited"]
    assert free.any()
    assert np.allclose(sc["v_c_actual"][free], sc["v_c"], rtol=1e-9)
    with pytest.raises(ValueError, match="feed_angle_deg"):
        S.spindle_scene(10.0)


# ------------------------------------------------------------------------- widget layer
@pytest.mark.parametrize("factory,control,value", [
    (X.thesis1_explorer, "rho", 20.0), (X.hoang_explorer, "tool_radius_mm", 4.0),
    (X.working_diameter_explorer, "A_f", 90.0), (X.cusp_explorer, "feed_mm", 0.3),
    (X.trochoid_explorer, "pattern", "cycloid"), (X.ce_growth_explorer, "progress", 0.3),
    (X.kim_yang_explorer, "theta", 40.0), (X.spindle_explorer, "feed_angle_deg", 45.0)])
def test_explorer_builds_and_redraws_on_change(factory, control, value):
    ex = factory()
    assert ex.error is None and ex.image.value and ex.readout.value
    before = (bytes(ex.image.value), ex.readout.value)
    ex.controls[control].value = value
    assert ex.error is None
    assert bytes(ex.image.value) != before[0] and ex.readout.value != before[1]
    for w in ex.controls.values():              # units on every control label (or a unitless choice)
        assert "[" in w.description or w.__class__.__name__ == "Dropdown"
    bundle = ex._repr_mimebundle_()
    assert "application/vnd.jupyter.widget-view+json" in bundle and "data:image/png;base64," in bundle["text/html"]
