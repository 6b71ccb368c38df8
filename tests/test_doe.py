"""Full-factorial plans and main-effect / interaction means (cnclab.analysis.doe)."""
import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cnclab.analysis.doe import full_factorial, interaction_means, main_effects


def test_table6_1_plan_size_and_order():
    levels = {"D": [6, 8, 10, 12], "a_p": [0.15, 0.25, 0.35, 0.45],
              "A_N2": [40, 30, 20, 15, 10, 5, 1, -5, -10, -15, -20, -30, -40],
              "A_f": [89, 74, 61, 44, 31, 14, 1, -14, -31, -44, -61, -74, -89]}
    plan = full_factorial(levels)
    assert len(plan) == 4 * 4 * 13 * 13 == 2704
    assert plan.iloc[0].tolist() == [6, 0.15, 40, 89]          # printed order kept
    assert plan.iloc[1].tolist() == [6, 0.15, 40, 74]          # last factor fastest
    assert plan.iloc[-1].tolist() == [12, 0.45, -40, -89]
    assert not plan.duplicated().any()


@settings(max_examples=40, deadline=None)
@given(st.lists(st.lists(st.integers(-50, 50), min_size=1, max_size=4, unique=True), min_size=1, max_size=4))
def test_every_combination_exactly_once(level_lists):
    levels = {f"f{i}": lv for i, lv in enumerate(level_lists)}
    plan = full_factorial(levels)
    assert len(plan) == int(np.prod([len(lv) for lv in level_lists]))
    assert not plan.duplicated().any()
    for name, lv in levels.items():  # balanced: each level appears equally often
        counts = plan[name].value_counts()
        assert set(counts.index) == set(float(v) for v in lv)
        assert counts.nunique() == 1


@pytest.mark.parametrize("levels, word", [
    ({}, "non-empty"), ({"x": []}, "'x'"), ({"x": [1, 1]}, "repeated"), ({"x": [1, np.nan]}, "non-finite"),
    ({"": [1]}, "factor names")])
def test_bad_levels_name_the_factor(levels, word):
    with pytest.raises(ValueError, match=word):
        full_factorial(levels)


def test_main_effects_and_interactions_hand_computed():
    plan = full_factorial({"x": [0, 1], "z": [0, 1, 2]})
    df = plan.assign(y=plan["x"] * 10 + plan["z"] + plan["x"] * plan["z"])
    me = main_effects(df, ["x", "z"], "y")
    assert me["x"].tolist() == [1.0, 12.0]          # x=0: mean(0,1,2); x=1: mean(10,12,14)
    assert me["z"].tolist() == [5.0, 6.5, 8.0]
    im = interaction_means(df, "z", "x", "y")
    assert im.loc[2.0, 1.0] == 14.0 and im.loc[2.0, 0.0] == 2.0
    # the interaction term makes the lines non-parallel
    assert not np.allclose(np.diff(im[0.0]), np.diff(im[1.0]))
    with pytest.raises(ValueError, match="no column"):
        main_effects(df, ["nope"], "y")
