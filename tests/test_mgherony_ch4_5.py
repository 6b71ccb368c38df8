"""Mgherony (2024) chapters 4–5: CV/CX part geometry, recipes and the consistency of transcriptions."""
import math

import numpy as np
import pytest

from cnclab import claims
from cnclab.geometry.ball_end import tangent_point_radii
from cnclab.geometry.cylinder_parts import MEASURING_POSITIONS_MM, CylinderPart
from cnclab.works.mgherony2024 import ch4_5


# ------------------------------------------------------------------------------- CV/CX part geometry
@pytest.mark.parametrize("kind", ["CV", "CX"])
def test_part_section_is_continuous_and_normal_matches_slope(kind):
    p = CylinderPart(kind)
    y, z = p.section(40001)
    assert np.max(np.abs(np.diff(z))) < 0.01                       # no jump at cylinder/fillet/plane joints
    slope = np.gradient(z, y)
    n = p.normal(y)
    assert np.allclose(np.linalg.norm(n, axis=-1), 1.0)
    interior = np.ones_like(y, bool)
    for yj in (p.y_cylinder, p.y_plane):                            # kinks of the sampled gradient
        interior &= np.abs(np.abs(y) - yj) > 0.01
    assert np.allclose(-n[interior, 1] / n[interior, 2], slope[interior], atol=2e-3)
    assert np.allclose(z, p.z(-y))                                  # symmetric section
    assert abs(float(p.z(p.y_extent)) - p.plane_z) < 1e-12


def test_part_orientation():
    cv, cx = CylinderPart("CV"), CylinderPart("CX")
    assert cv.plane_z > 0 > cx.plane_z                               # trough vs crest
    assert cv.z(10.0) > 0 > cx.z(10.0)
    assert cx.tool_path_radius(10) == 50 and cv.tool_path_radius(10) == 40


@pytest.mark.parametrize("kind", ["CV", "CX"])
def test_normal_at_tool_position_equals_surface_normal_at_contact(kind):
    p = CylinderPart(kind)
    y = MEASURING_POSITIONS_MM
    assert np.allclose(p.normal_at_tool_y(y, 10.0), p.normal(p.contact_y(y, 10.0)))
    # the ball centre is the contact point plus R along the normal
    yc = p.contact_y(y, 10.0)
    centre_y = yc + 5.0 * p.normal(yc)[:, 1]
    assert np.allclose(centre_y, y)


def test_table4_2_transcription_matches_geometry():
    t = ch4_5.table4_2()
    got = ch4_5.table4_2_normal_angles_deg()
    for row in t.itertuples():
        assert got[f"CX_{int(row.y_mm)}"] == pytest.approx(row.CX_deg, abs=0.05)
        assert got[f"CV_{int(row.y_mm)}"] == pytest.approx(row.CV_deg, abs=0.05)
    surf = ch4_5.table4_2_angles_on_part_surface_deg()
    assert abs(surf["CX_-25"] - 30.0) > 3                           # surface-y reading does not give the table


def test_bad_part_parameters():
    with pytest.raises(ValueError, match="kind"):
        CylinderPart("XX")
    with pytest.raises(ValueError, match="radius"):
        CylinderPart("CV", radius=-1)
    with pytest.raises(ValueError, match="y_tool"):
        CylinderPart("CV").normal_at_tool_y(100.0)
    with pytest.raises(ValueError, match=r"^y "):
        CylinderPart("CX").z(1e3)


# ------------------------------------------------------------------------------------ chapter 4 model
def test_ch4_diameters_symmetric_and_min_in_middle():
    df = ch4_5.ch4_effective_diameters()
    for kind, g in df.groupby("part"):
        d = g.D_eff1_mm.to_numpy()
        assert np.allclose(d, d[::-1]) and np.allclose(d, g.D_eff2_mm)
        assert int(np.argmin(d)) == 5 and np.all(np.diff(d[5:]) > 0)
        assert d[5] == pytest.approx(2 * math.sqrt(0.3 * 9.7))
    cv, cx = (df[df.part == k].v_c_m_min.to_numpy() for k in ("CV", "CX"))
    assert np.all(cv[np.arange(11) != 5] > cx[np.arange(11) != 5])   # CV faster than CX off-centre (§4.2)


def test_table4_3_transcription():
    t = ch4_5.table4_3()
    assert set(t.v_c_m_min) == {1600} and set(t.n_rpm) == {5100}
    vf = ch4_5.table4_3_feed_speeds()
    assert all(abs(vf[r.test_cv] - r.v_f_mm_min) <= 5 for r in t.itertuples())


# ------------------------------------------------------------------------------------ chapter 5
def test_thesis_display_double_rounding():
    assert ch4_5.thesis_display(0.0044994) == 0.005
    assert ch4_5.thesis_display(0.0044449) == 0.004          # 0.0044 -> 0.004
    assert round(0.0044994, 3) == 0.004                       # a single rounding would print 0.004
    assert ch4_5.thesis_display(4.5304158) == 4.530


def test_table5_1_csv_and_ledger_agree_and_are_reproduced():
    printed = ch4_5.table5_1_printed()
    model = ch4_5.table5_1_model()
    ledger = {c.claim_id: c for c in claims.load()}
    for r in printed.itertuples():
        k = f"Af{r.A_f_deg}_p{r.point}_"
        base = f"mgherony2024.ch5.table5-1.af{r.A_f_deg}_p{r.point}"
        assert ledger[base + ".deff_min"].paper_value == r.deff_min_mm
        assert ledger[base + ".vc_max"].paper_value == r.vc_max_m_min
        assert model[k + "paper_deff_min"] == r.deff_min_mm and model[k + "paper_deff_max"] == r.deff_max_mm
        assert (model[k + "AN1_min"], model[k + "AN2_min"]) == (r.AN1_min_deg, r.AN2_min_deg)
        assert model[k + "deff_max"] == pytest.approx(2 * model[k + "paper_deff_max"], abs=1e-3)


def test_only_a_2_5_degree_tilt_grid_hits_the_printed_extremes():
    g = ch4_5.grid_steps_reproducing_extremes(steps_AN2=(1.0, 1.25, 2.5, 5.0), steps_AN1=(2.5, 45.0))
    ok = g[g.reproduces_all]
    assert set(ok.step_AN2_deg) == {2.5} and set(ok.step_AN1_deg) == {2.5}


def test_extremes_sit_at_tilt_across_feed_and_have_twins_beyond_180():
    AN1, AN2 = ch4_5.angle_grid(AN1_range=(0.0, 357.5))
    r1 = tangent_point_radii(10, 0.3, AN1, AN2, 30)[0]
    lo = np.isclose(r1, r1.min())
    assert {(float(a), float(b)) for a, b in zip(AN1[lo], AN2[lo])} == {(120.0, -20.0), (300.0, 20.0)}


def test_half_of_nominal_is_the_radius_slip():
    f = ch4_5.highest_speed_fraction_of_nominal()
    assert f["true"] == pytest.approx(2 * f["paper_convention"])
    assert 0.9 < f["true"] < 0.91


def test_fig5_7_supports_thesis_1_not_similar_ranges():
    s = ch4_5.similar_vs_larger_summary()
    for mode in ("up", "down"):
        v = s[s.milling == mode].variation_mm.to_numpy()
        assert np.all(np.diff(v) > 0) and v[-1] / v[0] > 1.5        # grows with D (6 -> 10 mm)
    up = s[s.milling == "up"].variation_mm.to_numpy()
    down = s[s.milling == "down"].variation_mm.to_numpy()
    assert np.all(down > up)                                          # "larger for down milling"


def test_fig5_6_bottom_to_top_larger():
    df = ch4_5.fig5_6_curves()
    assert np.all(df.d1_lead_mm > df.d1_trail_mm)
    for _, g in df.groupby("D_mm"):
        assert np.all(np.diff(g.d1_mm) > 0)                           # grows with a_p


def test_surface_map_symmetry_between_points():
    AN1, AN2, r1, r2 = ch4_5.surface_map(1.0, 30)
    assert np.allclose(r1, r2[:, ::-1])                               # "the two diagrams are symmetrical"


def test_points_1_and_2_share_extremes_and_switch():
    """§5.5 "The minimum and maximum values of the D_eff1 and D_eff2 are the same" and §5.4 "the working
    diameter at point 1 with A_f = 180° matches the working diameter at point 2 with A_f = 0°" (statements,
    formerly ledger rows with an unprinted paper value 0): point 1 at A_f + 180° is point 2 at A_f."""
    from cnclab.geometry.ball_end import tangent_point_diameters

    e = ch4_5.ap1_extremes()
    assert abs(e["p1_deff_min"] - e["p2_deff_min"]) < 1e-9 and abs(e["p1_deff_max"] - e["p2_deff_max"]) < 1e-9
    assert ch4_5.fig5_8_ranges()["switch_identity"] < 1e-9
    rng = np.random.default_rng(5)
    a1, a2, af = rng.uniform(0, 360, 50), rng.uniform(-60, 60, 50), rng.uniform(0, 360, 50)
    for ap in (0.3, 1.0):
        d1_shift = tangent_point_diameters(10.0, ap, a1, a2, af + 180.0)[0]
        d2 = tangent_point_diameters(10.0, ap, a1, a2, af)[1]
        np.testing.assert_allclose(d1_shift, d2, atol=1e-9)
    # the two points are not the same point: they differ away from the symmetric cases
    d1, d2 = tangent_point_diameters(10.0, 1.0, a1, a2, af)
    assert np.max(np.abs(d1 - d2)) > 0.5


def test_eq5_1_as_printed_exceeds_the_tool_and_corrected_is_the_chord():
    from cnclab.geometry.ball_end import eq5_1_as_printed_diameter, horizontal_effective_diameter

    ap = np.linspace(0.01, 4.99, 50)
    # as printed (with '+') the "diameter" exceeds the 10 mm tool for every 0 < a_p < D/2
    assert np.all(eq5_1_as_printed_diameter(10.0, ap) > 10.0)
    assert ch4_5.eq5_1_as_printed_ch4() == pytest.approx(2 * math.sqrt(25 + 4.7 ** 2))
    # corrected: the chord of the ball at depth a_p, 2 sqrt(a_p (D - a_p)), equal to D at a_p = D/2
    np.testing.assert_allclose(horizontal_effective_diameter(10.0, ap), 2 * np.sqrt(ap * (10.0 - ap)))
    assert horizontal_effective_diameter(10.0, 5.0) == pytest.approx(10.0)
