"""Mgherony (2024) chapter 6: dataset, conventions, regression errata, Table 6-3 sources."""
import hashlib
import json

import numpy as np
import pandas as pd
import pytest

from cnclab.claims import Interval
from cnclab.paths import data_path
from cnclab.works.mgherony2024 import ch6


def test_dataset_hash_matches_committed_csv_and_metadata():
    text = ch6.dataset_csv_text()
    sha = hashlib.sha256(text.encode("utf-8")).hexdigest()
    csv_path = data_path("mgherony2024", "working_diameter_dataset.csv")
    meta = json.loads(data_path("mgherony2024", "working_diameter_dataset.json").read_text())
    assert hashlib.sha256(csv_path.read_bytes()).hexdigest() == sha == meta["sha256"]
    assert meta["rows"] == 2704 and meta["parameters"]["levels"] == ch6.LEVELS


def test_write_dataset_is_atomic_and_reproducible(tmp_path):
    p_csv, p_json = ch6.write_dataset(tmp_path / "wd.csv")
    assert p_csv.read_text() == ch6.dataset_csv_text()
    assert json.loads(p_json.read_text())["file"] == "wd.csv"


def test_dataset_physics():
    df = ch6.dataset()
    assert len(df) == 2704 and (df[["D_eff1", "D_eff2"]] > 0).all().all()
    assert (df["D_eff1"] <= df["D"]).all()
    # mirror symmetry: point 1 at A_f equals point 2 at -A_f
    d1, _ = ch6.working_diameters(df["D"], df["a_p"], df["A_N2"], df["A_f"])
    _, d2m = ch6.working_diameters(df["D"], df["a_p"], df["A_N2"], -df["A_f"])
    np.testing.assert_allclose(d1, d2m, atol=1e-12)
    np.testing.assert_allclose(d1, df["D_eff1"], atol=0)
    # scale invariance: D_eff(k·D, k·a_p) = k·D_eff(D, a_p)
    d6 = np.array(ch6.working_diameters(6.0, 0.15, 20.0, 31.0))
    d12 = np.array(ch6.working_diameters(12.0, 0.30, 20.0, 31.0))
    np.testing.assert_allclose(d12, 2 * d6)


def test_only_the_thesis_convention_reproduces_r1():
    ev = ch6.convention_evidence()
    z = ev["max |dCoef|/SE"]
    good = {"A_N1-A_f, point 1, diameter", "A_f-A_N1, point 2, diameter"}
    assert set(z[z < 0.01].index) == good          # within 1 % of an SE for every coefficient
    assert (z.drop(index=list(good)) > 1).all()    # every alternative misses by > 1 SE
    assert ev.loc["A_N1-A_f, point 1, radius", "coef D"] == pytest.approx(0.3416 / 2, rel=1e-3)


def test_eq6_4_last_term_typo():
    as_printed = ch6.r1_eq6_4_as_printed_values()["coef.AN2_5_Af5"]
    table = ch6.r1_values()["coef.AN2_5_Af3"]
    assert abs(table - (-4.363)) < 0.02 and abs(as_printed - (-4.363)) > 1.0


def test_table6_2_last_column_is_plain_r2():
    t = ch6.printed_table6_2().drop(index="R-Sq(adj)")
    lines = ch6.r2_lines()
    plain = np.abs(lines.loc[t.index, "r_sq"].to_numpy() - t["rsq_column"].to_numpy())
    adj = np.abs(lines.loc[t.index, "r_sq_adj"].to_numpy() - t["rsq_column"].to_numpy())
    assert plain.max() < 0.03
    assert (adj > 0.03).sum() == 9      # the two near-perfect lines agree either way


def test_table6_3_r2_column_is_the_unified_model():
    uni, sep = ch6.table6_3_regression_values(), ch6.table6_3_r2_separate_values()
    assert abs(uni["r2.range"] - 3.118) < 0.0005 and abs(sep["r2.range"] - 3.118) > 0.03
    assert abs(uni["r2.st_dev"] - 0.329) < 0.0005 and abs(sep["r2.st_dev"] - 0.329) > 0.0005
    # with the printed f_i(D) the unified model gives the same numbers
    stats = ch6.regression_statistics()
    assert stats.loc["range", "r2 (eq 6-5, printed f_i)"] == pytest.approx(3.118, abs=5e-4)


def test_unified_model_is_close_to_but_not_better_than_separate_fits():
    stats = ch6.regression_statistics()
    uni, sep = stats.loc["rmse", "r2 (unified, eq 6-5)"], stats.loc["rmse", "r2 (4 separate fits)"]
    assert sep <= uni < 1.01 * sep            # separate fits are the per-D least-squares optimum
    m = ch6.unified_model()
    np.testing.assert_allclose(m.coefficients(6.0), m.functions["slope"] * 6 + m.functions["intercept"])


def test_percentages_from_printed_table6_3():
    pc = ch6.percentages_from_table6_3()
    assert isinstance(pc["a1.rmse_pct"], Interval)
    assert not (pc["a1.rmse_pct"].lo - 0.5 <= 37 <= pc["a1.rmse_pct"].hi + 0.5)   # text's 37 % is not 0.194/0.562
    assert pc["a2.mape_pct"].lo - 0.5 <= 19 <= pc["a2.mape_pct"].hi + 0.5         # 0.038/0.194 with rounding


def test_printed_tables_are_complete():
    assert ch6.printed_r1_table().shape == (12, 4)
    assert ch6.printed_table6_2().shape == (12, 7)
    assert list(ch6.printed_table6_3().columns) == ["r1", "r2", "a1", "a2"]


def test_ann_runs_rejects_unknown_model():
    with pytest.raises(ValueError, match="model must be"):
        ch6.ann_runs("a3")


def test_r1_is_the_mean_of_the_r2_fits_on_the_balanced_plan():
    """Every D level has the same (a_p, A_N2, A_f) design, so the pooled r1 fit's shared coefficients are the mean
    of the four per-D fits, and its constant + coef_D·mean(D) is the mean of their constants (fitted, not printed)."""
    r1 = ch6.r1_fit().params
    fits = ch6.r2_fits()
    for term in r1.index:
        if term in ("Constant", "D"):
            continue
        assert r1[term] == pytest.approx(np.mean([f.params[term] for f in fits.values()]), rel=1e-9, abs=1e-12)
    mean_const = np.mean([f.params["Constant"] for f in fits.values()])
    assert r1["Constant"] + r1["D"] * np.mean(list(fits)) == pytest.approx(mean_const, rel=1e-9)
    # and the printed tables obey the same identity within their rounding (ledger rows ch6.r1_mean_of_r2.*)
    printed = ch6.printed_r1_coefficients()
    for term, v in ch6.r1_from_printed_r2_means().items():
        assert abs(v - printed[term]) < 6e-4


def test_percentile_among():
    assert ch6.percentile_among([1, 2, 3, 4], 0.5) == 0.0
    assert ch6.percentile_among([1, 2, 3, 4], 9) == 100.0
    assert ch6.percentile_among([1, 2, 3, 4], 2.5) == 50.0
    assert ch6.percentile_among([1, 2, 2, 4], 2) == 50.0          # ties count half


def test_ann_seed_table_judges_whole_rows():
    t = ch6.ann_seed_table("a1", n_seeds=2, max_epochs=3)      # tiny training: far from the printed row
    seeds = t.drop(index=["printed", "percentile"])
    assert list(seeds.index) == ["seed 0", "seed 1"]
    assert t.loc["printed", "range"] == 2.601 and t.loc["printed", "r_train"] == 0.99512
    assert not seeds["whole_row"].astype(bool).any()
    worst = ((seeds[list(ch6.ROW_STATS)].astype(float) - t.loc["printed", list(ch6.ROW_STATS)].astype(float)).abs()
             / pd.Series(ch6.ROW_TOLERANCE)).max(axis=1)
    np.testing.assert_allclose(seeds["worst_error_in_tol"].astype(float), worst)
    assert set(t.loc["percentile", list(ch6.ROW_STATS)]) <= {0.0, 25.0, 50.0, 75.0, 100.0}


def test_dataset_rows_and_r1_display():
    assert ch6.dataset_rows() == 4 * 4 * 13 * 13
    printed = ch6.printed_r1_coefficients()
    assert list(printed)[:3] == ["const", "D", "ap"] and printed["AN2_5_Af3"] == -4.363
