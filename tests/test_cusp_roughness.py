"""Cusp-height geometry (Mgherony ch. 3), profile roughness parameters, and the chapter-3 recipes."""
import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cnclab import claims
from cnclab.cutting.roughness import (RA_OVER_CH_PARABOLIC, RQ_OVER_CH_PARABOLIC, ideal_cusp_profile,
                                      profile_parameters)
from cnclab.geometry.cusp import (approximation_relative_error, cusp_height_eq3_1_as_printed,
                                  cusp_height_from_spacing, cusp_height_turning, cusp_height_zlevel,
                                  zlevel_spacing)
from cnclab.works.mgherony2024 import ch3

radius = st.floats(0.05, 5.0)
frac = st.floats(0.01, 1.0)


def test_hand_computed_cases():
    # T1: f = 0.1 mm, RE = 0.4 mm -> f²/(8 RE) = 0.01/3.2 mm = 3.125 µm; exact 0.4 - sqrt(0.1575)
    assert cusp_height_turning(0.1, 0.4, exact=False) == pytest.approx(3.125e-3, rel=1e-12)
    assert cusp_height_turning(0.1, 0.4) == pytest.approx(0.4 - math.sqrt(0.1575), rel=1e-12)
    # spacing equal to the diameter: the cusp is the full radius
    assert cusp_height_from_spacing(2.0, 1.0) == pytest.approx(1.0)
    # M1: a_p = 0.15, RE = 0.5, A = 80° -> 0.0225 / (4 sin²80°)
    assert cusp_height_zlevel(0.15, 0.5, 80, exact=False) == pytest.approx(
        0.0225 / (4 * math.sin(math.radians(80)) ** 2), rel=1e-12)


@given(s=frac, re_=radius)
def test_exact_relation_inverse_and_bounds(s, re_):
    s = s * 2 * re_  # 0 < s <= 2 RE
    ch = cusp_height_from_spacing(s, re_)
    # the Pythagorean relation RE² = (s/2)² + (RE - CH)² holds
    assert re_**2 == pytest.approx((s / 2) ** 2 + (re_ - ch) ** 2, rel=1e-9)
    # inverse: s = 2 sqrt(2 RE CH - CH²)
    assert 2 * math.sqrt(max(2 * re_ * ch - ch**2, 0)) == pytest.approx(s, rel=1e-6)
    # the approximation never exceeds the exact value and is within 0 <= CH <= RE
    assert 0 <= cusp_height_from_spacing(s, re_, exact=False) <= ch * (1 + 1e-12) or s == 2 * re_
    assert 0 < ch <= re_ * (1 + 1e-12)


@given(s=st.floats(0.001, 0.2), re_=st.floats(0.2, 5.0), k=st.floats(0.1, 10))
def test_scaling_and_leading_order_error(s, re_, k):
    # geometric similarity: scaling every length by k scales the cusp by k
    assert cusp_height_from_spacing(k * s, k * re_) == pytest.approx(k * cusp_height_from_spacing(s, re_), rel=1e-9)
    # relative error of the approximation: exactly (sqrt(1 - x) - 1)/2 with x = s²/(4 RE²),
    # i.e. -CH/(2 RE) to leading order
    x = s**2 / (4 * re_**2)
    err = approximation_relative_error(s, re_)
    assert err == pytest.approx((math.sqrt(1 - x) - 1) / 2, rel=1e-9, abs=1e-15)
    ch = cusp_height_from_spacing(s, re_)
    assert err == pytest.approx(-ch / (2 * re_), abs=4 * (ch / re_) ** 2 + 1e-15)


@given(ap=st.floats(0.01, 0.2), re_=st.floats(0.6, 3.0), a=st.floats(10, 170))  # spacing <= 2 RE
def test_zlevel_symmetry_and_vertical_wall(ap, re_, a):
    assert cusp_height_zlevel(ap, re_, a) == pytest.approx(cusp_height_zlevel(ap, re_, 180 - a), rel=1e-9)
    assert cusp_height_zlevel(ap, re_, 90.0) == pytest.approx(cusp_height_turning(ap, re_), rel=1e-12)
    assert zlevel_spacing(ap, a) >= ap


def test_eq3_1_as_printed_is_the_erratum():
    # the printed eq 3-1 (missing (RE - CH)²) gives a "cusp" of almost the whole corner radius
    assert cusp_height_eq3_1_as_printed(0.1, 0.4) == pytest.approx(0.39375)
    assert cusp_height_eq3_1_as_printed(0.1, 0.4) > 100 * cusp_height_turning(0.1, 0.4)


@pytest.mark.parametrize("call, name", [
    (lambda: cusp_height_turning(-0.1, 0.4), "feed"),
    (lambda: cusp_height_turning(0.1, 0.0), "corner_radius"),
    (lambda: cusp_height_turning(0.1, -1.0), "corner_radius"),
    (lambda: cusp_height_zlevel(0.1, 0.5, 0.0), "inclination"),
    (lambda: cusp_height_zlevel(0.1, 0.5, 180.0), "inclination"),
    (lambda: cusp_height_zlevel(0.1, 0.5, float("nan")), "inclination"),
    (lambda: cusp_height_zlevel(-0.1, 0.5, 80.0), "a_p"),
    (lambda: cusp_height_from_spacing(3.0, 1.0), "spacing"),
])
def test_bad_input_names_the_parameter(call, name):
    with pytest.raises(ValueError, match=name):
        call()


def test_profile_parameters_of_known_profiles():
    x = np.linspace(0, 1, 200001)
    # a cosine of whole periods is orthogonal to the least-squares line, so the tilt is removed exactly
    p = profile_parameters(3.0 * np.cos(2 * np.pi * 50 * x) + 0.7 * x + 2)
    assert p["Ra"] == pytest.approx(3 * 2 / np.pi, rel=1e-3)
    assert p["Rq"] == pytest.approx(3 / np.sqrt(2), rel=1e-3)
    assert p["Rz"] == pytest.approx(6.0, rel=1e-3) and p["Rt"] == pytest.approx(6.0, rel=1e-3)
    with pytest.raises(ValueError):
        profile_parameters([1.0, np.nan] * 10)


@pytest.mark.parametrize("s, re_", [(0.1, 0.8), (0.02, 0.5)])
def test_ideal_cusp_profile_matches_parabolic_limit(s, re_):
    x, z = ideal_cusp_profile(s, re_, 20 * s, n=20 * 2000 + 1)
    p = profile_parameters(z)
    ch = cusp_height_from_spacing(s, re_)
    assert p["Rz"] == pytest.approx(ch, rel=1e-3) and p["Rt"] == pytest.approx(ch, rel=1e-3)
    assert p["Ra"] / ch == pytest.approx(RA_OVER_CH_PARABOLIC, rel=2e-2)
    assert p["Rq"] / ch == pytest.approx(RQ_OVER_CH_PARABOLIC, rel=2e-2)


def test_batched_statistics_agree_with_statsmodels():
    s = ch3.statistics()
    for g, resp in [("turning", "Ra"), ("milling", "Rz"), ("both", "Ra")]:
        fit = ch3.linear_fit(g, resp)
        assert s[f"linear.{g}.{resp}.slope"] == pytest.approx(fit.params["CH"], rel=1e-10)
        assert s[f"linear.{g}.{resp}.R2_pct"] == pytest.approx(100 * fit.rsquared, rel=1e-10)
    for form in ("as_printed", "inverse"):
        fit = ch3.hybrid_model("Rz", form)
        assert s[f"hybrid.{form}.Rz.c_p"] == pytest.approx(fit.params["p"], rel=1e-10)
        assert s[f"hybrid.{form}.Rz.R2adj_pct"] == pytest.approx(100 * fit.rsquared_adj, rel=1e-10)


def test_ch3_tolerances_are_the_stated_rounding_band():
    """Pins each regression claim's tolerance to its basis: half a printed unit + the rounding band."""
    band = ch3.rounding_band()
    rows = [c for c in claims.load() if c.claim_id.startswith("mgherony2024.ch3.") and "statistics[" in c.computed_by]
    assert len(rows) >= 20
    for c in rows:
        key = re.search(r"\[(.*)\]", c.alt_computed_by or c.computed_by).group(1)
        digits = f"{c.paper_value:.10g}".split(".")
        # paper values are printed with 2 to 4 decimals; half a unit of the last one
        hu = 0.5 * 10 ** -max(len(digits[1]) if len(digits) > 1 else 0, 1 if c.paper_value % 1 else 0)
        assert band[key] <= c.atol <= 1.5 * (0.005 + band[key]) + hu, c.claim_id


def test_hybrid_inverse_form_describes_the_data_better():
    # the printed coefficients belong to CH/Rx = C(RE, p): used that way the model predicts Rz
    df = ch3.parts()
    s = ch3.statistics()
    c = [s[f"hybrid.inverse.Rz.{k}"] for k in ("c0", "c_RE", "c_p")]
    pred = df.CH_um / (c[0] + c[1] * df.RE_mm + c[2] * df.p_mm)
    assert np.max(np.abs(pred / df.Rz_um - 1)) < 0.25
    # while Rx = C·CH with the printed coefficients is typically off by more than a factor of 2
    wrong = (0.24 - 0.37 * df.RE_mm + 3.45 * df.p_mm) * df.CH_um
    assert np.median(np.abs(np.log(wrong / df.Rz_um))) > np.log(2)


def test_ideal_profile_explains_part_of_measured_roughness():
    t = ch3.ideal_vs_measured()
    assert (t.Rz_ideal_um <= t.Rz_um).all()          # geometry alone never exceeds the measurement
    assert np.allclose(t.Rz_ideal_um, t.CH_um, rtol=2e-3)
    assert (t.Rz_share > 0.2).all() and (t.Rz_share < 1).all()
