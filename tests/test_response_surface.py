"""OLS response surfaces, MiniTab-style tables, per-level fits, eq 6-5 unified model, error statistics."""
import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cnclab.analysis import response_surface as rs
from cnclab.analysis.doe import full_factorial
from cnclab.analysis.error_stats import difference_stats


@pytest.fixture(scope="module")
def plan():
    return full_factorial({"D": [6, 8, 10, 12], "a_p": [0.15, 0.3, 0.45], "A_N2": [-40, -20, -5, 0, 10, 30],
                           "A_f": [-80, -45, -10, 0, 20, 60, 89]})


def test_exact_polynomial_is_recovered(plan):
    rng = np.random.default_rng(3)
    true = pd.Series(rng.normal(size=len(rs.R1_TERMS)), index=[t.name for t in rs.R1_TERMS])
    y = rs.design_matrix(plan, rs.R1_TERMS).to_numpy() @ true.to_numpy()
    fit = rs.fit_polynomial(plan.assign(y=y), "y", rs.R1_TERMS)
    np.testing.assert_allclose(fit.params.to_numpy(), true.to_numpy(), atol=1e-8)
    assert fit.r_sq == pytest.approx(100.0) and fit.S < 1e-8


def test_terms_use_radians(plan):
    X = rs.design_matrix(plan, rs.R1_TERMS)
    a, f = np.radians(plan["A_N2"]), np.radians(plan["A_f"])
    np.testing.assert_allclose(X["(AN2^5 x Af^3)"], a ** 5 * f ** 3)
    np.testing.assert_allclose(rs.design_matrix(plan, rs.R1_TERMS_EQ6_4_AS_PRINTED)["(AN2^5 x Af^5)"], a ** 5 * f ** 5)
    assert "D" not in [t.name for t in rs.R2_TERMS] and len(rs.R2_TERMS) == 11


def test_minitab_table_identities(plan):
    rng = np.random.default_rng(0)
    y = 0.3 * plan["D"] + 2 * plan["a_p"] + np.radians(plan["A_N2"]) ** 2 + rng.normal(0, 0.1, len(plan))
    fit = rs.fit_polynomial(plan.assign(y=y), "y", rs.R1_TERMS)
    tab = fit.coefficient_table()
    np.testing.assert_allclose(tab["T"], tab["Coef"] / tab["SE Coef"])
    n, p = len(plan), len(rs.R1_TERMS)
    resid = y - fit.predict(plan)
    assert fit.S == pytest.approx(np.sqrt(resid @ resid / (n - p)))
    r2 = 1 - resid @ resid / np.sum((y - y.mean()) ** 2)
    assert fit.r_sq == pytest.approx(100 * r2)
    assert fit.r_sq_adj == pytest.approx(100 * (1 - (1 - r2) * (n - 1) / (n - p)))
    assert 0 <= tab["P"].min() and tab["P"].max() <= 1


def test_per_level_lines_and_unified_model(plan):
    """Coefficients exactly linear in D: the lines have R² = 100 % and eq 6-5 equals the separate fits."""
    names = [t.name for t in rs.R2_TERMS]
    slope = pd.Series(np.linspace(-1, 1.2, len(names)), index=names)
    icpt = pd.Series(np.linspace(2, -2, len(names)), index=names)
    X = rs.design_matrix(plan, rs.R2_TERMS).to_numpy()
    y = np.sum(X * (plan[["D"]].to_numpy() * slope.to_numpy() + icpt.to_numpy()), axis=1)
    data = plan.assign(y=y)
    fits = rs.fit_per_level(data, "y", rs.R2_TERMS, by="D")
    assert sorted(fits) == [6.0, 8.0, 10.0, 12.0]
    lines = rs.linear_coefficient_functions(fits)
    np.testing.assert_allclose(lines["slope"], slope[lines.index], atol=1e-8)
    np.testing.assert_allclose(lines["intercept"], icpt[lines.index], atol=1e-7)
    np.testing.assert_allclose(lines["r_sq"], 100, atol=1e-6)
    model = rs.UnifiedModel(lines[["slope", "intercept"]])
    np.testing.assert_allclose(model.predict(data), y, atol=1e-7)
    np.testing.assert_allclose(model.coefficients(8.0), 8 * slope + icpt, atol=1e-7)


def test_adjusted_line_r2_is_lower_for_imperfect_lines():
    fits = {}
    for D, c in zip([6, 8, 10, 12], [1.0, 2.5, 2.9, 4.2]):
        class F:  # minimal stand-in with .params
            params = pd.Series({"x": c})
        fits[D] = F()
    lines = rs.linear_coefficient_functions(fits)
    r2 = lines.loc["x", "r_sq"] / 100
    assert lines.loc["x", "r_sq_adj"] == pytest.approx(100 * (1 - (1 - r2) * 3 / 2))
    assert lines.loc["x", "r_sq_adj"] < lines.loc["x", "r_sq"] < 100


def test_bad_inputs(plan):
    with pytest.raises(ValueError, match="response 'nope'"):
        rs.fit_polynomial(plan, "nope", rs.R1_TERMS)
    with pytest.raises(ValueError, match="column 'D'"):
        rs.design_matrix(plan.drop(columns="D"), rs.R1_TERMS)
    with pytest.raises(ValueError, match="more rows than terms"):
        rs.fit_polynomial(plan.head(5).assign(y=1.0), "y", rs.R1_TERMS)
    with pytest.raises(ValueError, match="lacks rows"):
        rs.UnifiedModel(pd.DataFrame({"slope": [1.0], "intercept": [0.0]}, index=["Constant"]))


# ----------------------------------------------------------------------------- error statistics
def test_difference_stats_hand_computed():
    s = difference_stats([2.0, 4.0, 6.0, 8.0], [1.0, 4.0, 7.0, 8.0])   # e = 1, 0, -1, 0
    assert s["range"] == 2.0 and s["mean"] == 0.0
    assert s["rmse"] == pytest.approx(np.sqrt(0.5))
    assert s["st_dev"] == pytest.approx(np.sqrt(2 / 3))
    assert s["mape"] == pytest.approx((1 / 2 + 1 / 6) / 4)
    assert s["r2"] == pytest.approx(1 - 2 / 20)


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(0.1, 20), min_size=3, max_size=30), st.floats(-1, 1))
def test_constant_shift_properties(x, c):
    x = np.array(x)
    s = difference_stats(x, x + c)
    assert s["range"] == pytest.approx(0, abs=1e-9) and s["st_dev"] == pytest.approx(0, abs=1e-9)
    assert s["rmse"] == pytest.approx(abs(c), abs=1e-9)


def test_difference_stats_bad_input():
    with pytest.raises(ValueError, match="same size"):
        difference_stats([1, 2, 3], [1, 2])
    with pytest.raises(ValueError, match="zeros"):
        difference_stats([0, 1, 2], [0, 1, 2])
