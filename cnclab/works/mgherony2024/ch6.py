"""Mgherony (2024) chapter 6 / Thesis 2: working-diameter dataset, regression (r1, r2, eq 6-5) and MLPs.

Recipes behind the ``mgherony2024.ch6.*`` ledger rows. Everything is computed from the geometric model
of chapter 5 (:func:`cnclab.geometry.ball_end.tangent_point_diameters`); nothing reads the thesis.

Conventions (found by fitting the alternatives, see :func:`convention_evidence`)
-------------------------------------------------------------------------------
* The dataset's inputs are ``D`` (mm), ``a_p`` (mm), ``A_N2`` (degrees) and the *relative feed
  direction* ``A_f`` (degrees). The printed r1 coefficients come out (to < 1 % of each standard error)
  only when the relative feed direction is ``A_f = A_N1 − A_f,abs`` — the eq 5-3 azimuth of the surface
  normal measured from the feed direction — and ``D_eff1`` is tangent point 1 (left of the feed),
  ``D_eff2`` point 2. (Equivalently ``A_f,abs − A_N1`` with the points swapped: the model is symmetric.)
* Outputs are **true working diameters** (mm), twice the distance of the tangent point from the axis
  (the radius reading of chapter 5 halves every coefficient and is rejected by the fit).
* Regression terms use the angles in **radians** (the thesis's ``AN2_rad``, ``Af_rad``).

>>> df = dataset()
>>> len(df), list(df.columns)
(2704, ['D', 'a_p', 'A_N2', 'A_f', 'D_eff1', 'D_eff2'])
"""
from __future__ import annotations

import functools
import hashlib
import io
import json
from pathlib import Path

import numpy as np
import pandas as pd

from ... import __version__
from ...cache import cached
from ...analysis import response_surface as rs
from ...analysis.doe import full_factorial
from ...analysis.error_stats import STAT_NAMES, difference_stats
from ...claims import Interval
from ...fileio import atomic_write
from ...paths import DATA_DIR, data_path
from ...runtime import pick
from ...geometry.ball_end import tangent_point_diameters
from ...analysis.mlp import train_mlp
from ...sweep import sweep

# ----------------------------------------------------------------------------------- Table 6-1
#: Table 6-1 levels, in the printed order (the plan's first factor varies slowest).
LEVELS = {
    "D": [6, 8, 10, 12],
    "a_p": [0.15, 0.25, 0.35, 0.45],
    "A_N2": [40, 30, 20, 15, 10, 5, 1, -5, -10, -15, -20, -30, -40],
    "A_f": [89, 74, 61, 44, 31, 14, 1, -14, -31, -44, -61, -74, -89],
}
DATASET_CSV = DATA_DIR / "mgherony2024" / "working_diameter_dataset.csv"
INPUTS = ("D", "a_p", "A_N2", "A_f")
OUTPUTS = ("D_eff1", "D_eff2")
TERM_IDS = {"Constant": "const", "D": "D", "ap": "ap", "AN2^2": "AN2_2", "AN2^4": "AN2_4", "Af^2": "Af_2",
            "(AN2 x Af)": "AN2_Af", "(AN2 x Af^3)": "AN2_Af3", "(AN2^3 x Af)": "AN2_3_Af",
            "(AN2^3 x Af^3)": "AN2_3_Af3", "(AN2^5 x Af)": "AN2_5_Af", "(AN2^5 x Af^3)": "AN2_5_Af3",
            "(AN2^5 x Af^5)": "AN2_5_Af5"}


def working_diameters(D, a_p, A_N2, A_f_rel, sign: float = 1.0, offset_deg: float = 0.0):
    """``(D_eff1, D_eff2)`` true working diameters (mm) for the chapter-6 relative feed direction.

    Parameters: ``D``, ``a_p`` in mm; ``A_N2`` and ``A_f_rel`` in degrees. The thesis's convention is
    ``sign=+1, offset_deg=0``: the relative feed direction is ``A_N1 − A_f,abs`` (so the model is called
    with ``A_N1 = A_f_rel`` and an absolute feed along +x); ``sign``/``offset_deg`` give the alternatives
    tried in :func:`convention_evidence` (``A_N1 = sign·A_f_rel + offset_deg``).

    >>> d1, d2 = working_diameters(10, 0.3, 0, 30)           # horizontal: 2·sqrt(a_p (D − a_p))
    >>> round(float(d1), 4), round(float(d2), 4)
    (3.4117, 3.4117)
    """
    return tangent_point_diameters(D, a_p, sign * np.asarray(A_f_rel, dtype=float) + offset_deg, A_N2, 0.0)


def dataset_block(D) -> pd.DataFrame:
    """The rows of the §6.2 plan with tool diameter ``D`` (mm): one sweep item of :func:`dataset`."""
    plan = full_factorial({**LEVELS, "D": [D]})
    d1, d2 = working_diameters(plan["D"].to_numpy(), plan["a_p"].to_numpy(), plan["A_N2"].to_numpy(),
                               plan["A_f"].to_numpy())
    return plan.assign(D_eff1=d1, D_eff2=d2)


@functools.cache
def _dataset_cached() -> pd.DataFrame:
    # D varies slowest in the plan: the blocks concatenated in LEVELS order are the full plan's rows
    return pd.concat(sweep(dataset_block, [(D,) for D in LEVELS["D"]]), ignore_index=True)


def dataset() -> pd.DataFrame:
    """The 2704-row full-factorial dataset of §6.2 (Table 6-1): inputs and D_eff1, D_eff2 (mm)."""
    return _dataset_cached().copy()


def dataset_csv_text() -> str:
    """The dataset as CSV text (9 decimals, '\\n' line ends): the bytes written to ``data/`` and hashed."""
    buf = io.StringIO()
    dataset().to_csv(buf, index=False, float_format="%.9f", lineterminator="\n")
    return buf.getvalue()


def dataset_metadata() -> dict:
    """Generator, parameters, package version and sha256 of :func:`dataset_csv_text`."""
    text = dataset_csv_text()
    return {
        "file": DATASET_CSV.name,
        "description": "Mgherony (2024) §6.2 full-factorial working-diameter dataset (Table 6-1), 2704 rows",
        "source": "seed 004_6087ee43271ee0e7.txt, chapter 6, §6.2 and Table 6-1; model of §5.2",
        "generator": "cnclab.works.mgherony2024.ch6.dataset",
        "model": "cnclab.geometry.ball_end.tangent_point_diameters(D, a_p, A_N1=A_f, A_N2, A_f=0)",
        "parameters": {"levels": LEVELS, "order": "D slowest, then a_p, A_N2, A_f (as printed)"},
        "columns": {"D": "tool diameter, mm", "a_p": "depth of cut, mm", "A_N2": "surface inclination, degrees",
                    "A_f": "relative feed direction A_N1 - A_f,abs, degrees",
                    "D_eff1": "true working diameter at tangent point 1 (left of feed), mm",
                    "D_eff2": "true working diameter at tangent point 2 (right of feed), mm"},
        "float_format": "%.9f",
        "rows": len(dataset()),
        "cnclab_version": __version__,
        "sha256": hashlib.sha256(text.encode("utf-8")).hexdigest(),
    }


def write_dataset(path=DATASET_CSV) -> tuple[Path, Path]:
    """Write the dataset CSV and its ``.json`` metadata sidecar atomically; returns both paths."""
    path = Path(path)
    meta = dataset_metadata()
    meta["file"] = path.name
    p1 = atomic_write(path, dataset_csv_text())
    p2 = atomic_write(path.with_suffix(".json"), json.dumps(meta, indent=1) + "\n")
    return p1, p2


# ------------------------------------------------------------------------- printed tables (data/)
def _read(name: str) -> pd.DataFrame:
    return pd.read_csv(data_path("mgherony2024", name), comment="#")


def printed_r1_table() -> pd.DataFrame:
    """The MiniTab table under eq 6-4 as printed (index: predictor)."""
    return _read("ch6_eq6-4_r1_coefficients.csv").set_index("predictor")


def printed_table6_2() -> pd.DataFrame:
    """Table 6-2 as printed (index: term; last row ``R-Sq(adj)`` of the four fits)."""
    return _read("ch6_table6-2_r2_coefficients.csv").set_index("term")


def printed_table6_3() -> pd.DataFrame:
    """Table 6-3 as printed (index: statistic; columns r1, r2, a1, a2)."""
    return _read("ch6_table6-3_statistics.csv").set_index("statistic")


def printed_percentages() -> pd.DataFrame:
    """§6.3.3 text percentages (index: model; st_dev_pct, rmse_pct, mape_pct)."""
    return _read("ch6_s6.3.3_percentages.csv").set_index("model")


def printed_ann_figures() -> pd.DataFrame:
    """§6.3.2 text numbers of Figs 6-4…6-7 (index: a1, a2)."""
    return _read("ch6_s6.3.2_ann_figures.csv").set_index("model")


# ------------------------------------------------------------------------------- conventions
#: (relative feed reading, A_N1 = sign·A_f + offset, tangent point, output scale)
CONVENTIONS = {
    "A_N1-A_f, point 1, diameter": (1, 0, 0, 1.0),
    "A_N1-A_f, point 2, diameter": (1, 0, 1, 1.0),
    "A_f-A_N1, point 1, diameter": (-1, 0, 0, 1.0),
    "A_f-A_N1, point 2, diameter": (-1, 0, 1, 1.0),
    "from contour (A_N1+90-A_f), point 1": (1, 90, 0, 1.0),
    "from contour (A_N1+90-A_f), point 2": (1, 90, 1, 1.0),
    "A_N1-A_f, point 1, radius": (1, 0, 0, 0.5),
}


@functools.cache
def convention_evidence() -> pd.DataFrame:
    """Fit r1 under each convention of :data:`CONVENTIONS`; compare with the printed table.

    Columns: ``R-Sq`` (%), ``S`` (mm), ``max |ΔCoef|/SE`` (printed SE) and the worst term.
    Only the thesis's convention reproduces every coefficient.
    """
    plan = full_factorial(LEVELS)
    printed = printed_r1_table()
    rows = []
    for name, (sign, off, point, scale) in CONVENTIONS.items():
        d = working_diameters(plan["D"].to_numpy(), plan["a_p"].to_numpy(), plan["A_N2"].to_numpy(),
                              plan["A_f"].to_numpy(), sign, off)[point] * scale
        fit = rs.fit_polynomial(plan.assign(y=d), "y", rs.R1_TERMS)
        z = ((fit.params - printed["coef"]) / printed["se_coef"]).abs()
        rows.append({"convention": name, "R-Sq": fit.r_sq, "S": fit.S, "coef D": fit.params["D"],
                     "max |dCoef|/SE": z.max(), "worst term": z.idxmax()})
    return pd.DataFrame(rows).set_index("convention")


# ---------------------------------------------------------------------------------- regression
@functools.cache
def r1_fit(response: str = "D_eff1", eq6_4_as_printed: bool = False) -> rs.OLSFit:
    """The r1 model (eq 6-4) fitted to the dataset; ``eq6_4_as_printed`` uses AN2^5·Af^5 as last term."""
    terms = rs.R1_TERMS_EQ6_4_AS_PRINTED if eq6_4_as_printed else rs.R1_TERMS
    return rs.fit_polynomial(dataset(), response, terms)


def _table_values(fit: rs.OLSFit) -> dict:
    tab = fit.coefficient_table()
    out = {}
    for term, row in tab.iterrows():
        tid = TERM_IDS[term]
        out.update({f"coef.{tid}": row["Coef"], f"se.{tid}": row["SE Coef"], f"t.{tid}": row["T"],
                    f"p.{tid}": row["P"]})
    out.update({"S": fit.S, "rsq": fit.r_sq, "rsq_adj": fit.r_sq_adj})
    return out


@functools.cache
def r1_values() -> dict:
    """r1 MiniTab table flattened: ``coef.<term>``, ``se.<term>``, ``t.<term>``, ``p.<term>``, S, rsq, rsq_adj."""
    return _table_values(r1_fit())


@functools.cache
def r1_eq6_4_as_printed_values() -> dict:
    """Same as :func:`r1_values` but with eq 6-4's printed last term AN2^5·Af^5."""
    return _table_values(r1_fit(eq6_4_as_printed=True))


@functools.cache
def r2_fits(response: str = "D_eff1") -> dict:
    """Table 6-2: one r2 fit per tool diameter ``{6.0: OLSFit, ...}``."""
    return rs.fit_per_level(dataset(), response, rs.R2_TERMS, by="D")


@functools.cache
def r2_lines(response: str = "D_eff1") -> pd.DataFrame:
    """Table 6-2's last columns: slope, intercept, plain and adjusted R² (%) of each coefficient vs D."""
    return rs.linear_coefficient_functions(r2_fits(response))


@functools.cache
def r2_values() -> dict:
    """Table 6-2 flattened: ``D6.<term>`` coefficients, ``rsq_adj.D6`` …, ``slope.<term>``,
    ``intercept.<term>``, ``line_rsq.<term>`` (plain R², %), ``line_rsq_adj.<term>`` (adjusted, %)."""
    out = {}
    for D, fit in r2_fits().items():
        for term, c in fit.params.items():
            out[f"D{int(D)}.{TERM_IDS[term]}"] = c
        out[f"rsq_adj.D{int(D)}"] = fit.r_sq_adj
    for term, row in r2_lines().iterrows():
        tid = TERM_IDS[term]
        out.update({f"slope.{tid}": row["slope"], f"intercept.{tid}": row["intercept"],
                    f"line_rsq.{tid}": row["r_sq"], f"line_rsq_adj.{tid}": row["r_sq_adj"]})
    return out


@functools.cache
def unified_model(response: str = "D_eff1") -> rs.UnifiedModel:
    """eq 6-5 / Thesis 2: ``D_eff = Σ f_i(D)·C_i`` with the fitted straight lines of Table 6-2."""
    return rs.UnifiedModel(r2_lines(response)[["slope", "intercept"]])


def printed_unified_model() -> rs.UnifiedModel:
    """eq 6-5 with the f_i(D) exactly as printed in Table 6-2 (4 decimals)."""
    t = printed_table6_2().drop(index="R-Sq(adj)")
    return rs.UnifiedModel(t[["slope", "intercept"]].astype(float))


def _r2_separate_predictions(response="D_eff1") -> np.ndarray:
    df = dataset()
    pred = np.empty(len(df))
    for D, fit in r2_fits(response).items():
        m = (df["D"] == D).to_numpy()
        pred[m] = fit.predict(df[m])
    return pred


@functools.cache
def regression_statistics() -> pd.DataFrame:
    """Table 6-3 statistics of ``D_eff1 − estimate`` for r1, r2 via eq 6-5 (unified) and r2 as 4 fits."""
    df = dataset()
    y = df["D_eff1"].to_numpy()
    preds = {"r1": r1_fit().predict(df), "r2 (unified, eq 6-5)": unified_model().predict(df),
             "r2 (4 separate fits)": _r2_separate_predictions(),
             "r2 (eq 6-5, printed f_i)": printed_unified_model().predict(df)}
    return pd.DataFrame({k: difference_stats(y, p) for k, p in preds.items()}).loc[list(STAT_NAMES)]


@functools.cache
def table6_3_regression_values() -> dict:
    """``r1.<stat>`` and ``r2.<stat>`` (r2 = unified eq 6-5 model, as Table 6-3 uses)."""
    t = regression_statistics()
    out = {f"r1.{s}": t.loc[s, "r1"] for s in STAT_NAMES}
    out.update({f"r2.{s}": t.loc[s, "r2 (unified, eq 6-5)"] for s in STAT_NAMES})
    return out


@functools.cache
def table6_3_r2_separate_values() -> dict:
    """``r2.<stat>`` from the four separate fits (the alternative reading of Table 6-3's r2 column)."""
    t = regression_statistics()
    return {f"r2.{s}": t.loc[s, "r2 (4 separate fits)"] for s in STAT_NAMES}


# ------------------------------------------------------------------------------ neural networks
#: Mgherony's two networks (§6.3.2): hidden layer widths.
ARCHITECTURES = {"a1": (10,), "a2": (10, 5)}
N_SEEDS = 10
MAX_EPOCHS = 1000


@cached()
def _ann_net(model: str, seed: int, trainer: str, max_epochs: int):
    """One network of :func:`ann_runs` (cached under build/cache/, keyed by the code and the args)."""

    df = dataset()
    X, Y = df[list(INPUTS)].to_numpy(), df[list(OUTPUTS)].to_numpy()
    return train_mlp(X, Y, hidden=ARCHITECTURES[model], activation="logsig", trainer=trainer,
                     seed=seed, max_epochs=max_epochs)


@functools.cache
def ann_runs(model: str, n_seeds: int = N_SEEDS, trainer: str = "lm", max_epochs: int = MAX_EPOCHS) -> tuple:
    """Train ``model`` ('a1' or 'a2') for seeds ``0..n_seeds-1``: 4 inputs (D, a_p, A_N2, A_f) →
    logistic hidden layer(s) → 2 linear outputs (D_eff1, D_eff2), MATLAB-like LM recipe.

    Returns a tuple of :class:`cnclab.analysis.mlp.TrainedMLP`. The seeds run through
    :func:`cnclab.sweep.sweep` (serial, joblib or Dask) and each network is cached on disk.
    """
    if model not in ARCHITECTURES:
        raise ValueError(f"model must be one of {list(ARCHITECTURES)}, got {model!r}")
    return tuple(sweep(_ann_net, [(model, s, trainer, max_epochs) for s in range(n_seeds)]))


def ann_statistics(model: str, n_seeds: int = N_SEEDS, trainer: str = "lm",
                   max_epochs: int = MAX_EPOCHS) -> pd.DataFrame:
    """Table 6-3 statistics of D_eff1 over all 2704 rows, one row per seed, plus the pooled R of the
    train/validation/test subsets (both outputs, MATLAB plotregression) and the tallest-bin error of
    the 20-bin error histogram (ploterrhist, both outputs pooled), in mm."""
    df = dataset()
    X, Y = df[list(INPUTS)].to_numpy(), df[list(OUTPUTS)].to_numpy()
    rows = []
    for net in ann_runs(model, n_seeds, trainer, max_epochs):
        P = net.predict(X)
        row = difference_stats(Y[:, 0], P[:, 0])
        for name, idx in zip(("r_train", "r_validation", "r_test"), net.split):
            row[name] = float(np.corrcoef(Y[idx].ravel(), P[idx].ravel())[0, 1])
        err = (Y - P).ravel()
        counts, edges = np.histogram(err, bins=20)
        k = int(np.argmax(counts))
        row["hist_peak_error"] = 0.5 * (edges[k] + edges[k + 1])
        row.update(seed=net.seed, best_epoch=net.best_epoch, stop=net.stop_reason)
        rows.append(row)
    return pd.DataFrame(rows).set_index("seed")


def _interval(s: pd.Series) -> Interval:
    return Interval(float(s.min()), float(s.max()), center=float(s.mean()))


#: the statistics that make up one network's printed "row": its Table 6-3 column and its §6.3.2 R values
ROW_STATS = (*STAT_NAMES, "r_train", "r_validation", "r_test")
#: half a unit of the printed last digit of each statistic (Table 6-3: 3 decimals; §6.3.2 R: 5, 5, 4 decimals)
ROW_TOLERANCE = {**{s: 0.0005 for s in STAT_NAMES}, "r_train": 5e-6, "r_validation": 5e-6, "r_test": 5e-5}


def printed_network_row(model: str) -> pd.Series:
    """The printed numbers of one network (``ROW_STATS``): its Table 6-3 column and its §6.3.2 R values."""
    t, f = printed_table6_3(), printed_ann_figures()
    return pd.Series({**{s: float(t.loc[s, model]) for s in STAT_NAMES},
                      **{s: float(f.loc[model, s]) for s in ("r_train", "r_validation", "r_test")}})


def percentile_among(values, printed: float) -> float:
    """Percentile (0…100) of ``printed`` among ``values``: the share of values below it, ties counted half.

    >>> percentile_among([1.0, 2.0, 3.0, 4.0], 2.0)
    37.5
    """
    v = np.asarray(values, dtype=float)
    return float(100.0 * (np.sum(v < printed) + 0.5 * np.sum(v == printed)) / len(v))


def ann_seed_table(model: str, n_seeds: int = N_SEEDS, trainer: str = "lm",
                   max_epochs: int = MAX_EPOCHS) -> pd.DataFrame:
    """Rule-4 view of one network: the value of every ``ROW_STATS`` statistic for each seed, then rows
    ``printed`` and ``percentile`` (the printed value's percentile among the seeds). Column
    ``whole_row`` says whether that seed reproduces *every* statistic of the printed row within
    ``ROW_TOLERANCE``; ``worst_error_in_tol`` is its largest |seed − printed| / tolerance."""
    stats = ann_statistics(model, n_seeds, trainer, max_epochs)[list(ROW_STATS)]
    printed = printed_network_row(model)
    tol = pd.Series(ROW_TOLERANCE)[list(ROW_STATS)]
    scaled = (stats - printed).abs() / tol
    out = stats.astype(float).copy()
    out["worst_error_in_tol"] = scaled.max(axis=1)
    out["whole_row"] = (scaled.max(axis=1) <= 1.0).astype(object)   # object: the two summary rows hold NaN
    out.index = [f"seed {i}" for i in stats.index]
    out.loc["printed", list(ROW_STATS)] = printed
    out.loc["percentile", list(ROW_STATS)] = [percentile_among(stats[c], printed[c]) for c in ROW_STATS]
    return out


def ann_row_verdict(model: str, n_seeds: int = N_SEEDS) -> dict:
    """Whether one seed reproduces the whole printed row of ``model``; the seeds that do; the closest seed
    (smallest worst error in tolerances) and the printed value's percentile per statistic."""
    t = ann_seed_table(model, n_seeds)
    seeds = t.drop(index=["printed", "percentile"])
    ok = [i for i in seeds.index if bool(seeds.loc[i, "whole_row"])]
    best = seeds["worst_error_in_tol"].astype(float).idxmin()
    return {"reproduced": bool(ok), "seeds": ok, "closest_seed": best,
            "closest_worst_error_in_tol": float(seeds.loc[best, "worst_error_in_tol"]),
            "percentile": t.loc["percentile", list(ROW_STATS)].astype(float).to_dict()}


@functools.cache
def ann_values() -> dict:
    """``a1.<stat>``, ``a2.<stat>`` for ``ROW_STATS`` judged per rule 4 (one seed must reproduce the
    whole printed row of its network): the value of the first seed that reproduces the whole row when
    one does, otherwise the **median over the** :data:`N_SEEDS` **LM seeds** (the typical run; the
    printed value's percentile among the seeds is in :func:`ann_seed_table`)."""
    out = {}
    for model in ARCHITECTURES:
        t = ann_seed_table(model).drop(index=["printed", "percentile"])
        whole = t[t["whole_row"].astype(bool)]
        for col in ROW_STATS:
            v = t[col].astype(float)
            out[f"{model}.{col}"] = float(whole[col].iloc[0]) if len(whole) else float(v.median())
    return out


def ann_a2_beats_a1_share() -> float:
    """§6.3.3 "The a2 ANN model results in the smallest error in all cases": share of seeds s for which
    a2 (seed s) beats a1 (seed s) on every Table 6-3 statistic (smaller range, st_dev, rmse, mape; larger
    R²). 1.0 = the statement holds run by run."""
    a1, a2 = ann_statistics("a1"), ann_statistics("a2")
    lower = [c for c in STAT_NAMES if c != "r2"]
    better = (a2[lower] < a1[lower]).all(axis=1) & (a2["r2"] > a1["r2"])
    return float(better.mean())


# ------------------------------------------------------------------------------ §6.3.3 percentages
def _ratio_interval(num: float, den: float, half_unit: float) -> Interval:
    lo = (num - half_unit) / (den + half_unit)
    hi = (num + half_unit) / (den - half_unit)
    return Interval(100 * lo, 100 * hi, center=100 * num / den)


_PCT_STATS = {"st_dev_pct": "st_dev", "rmse_pct": "rmse", "mape_pct": "mape"}


def percentages_from_table6_3() -> dict:
    """§6.3.3 percentages recomputed from the *printed* Table 6-3 (``<model>.<stat>_pct``), as Intervals
    that carry the table's rounding (each value ± half a unit of its 3rd decimal)."""
    t = printed_table6_3()
    return {f"{m}.{k}": _ratio_interval(t.loc[s, m], t.loc[s, "r1"], 0.0005)
            for m in ("r2", "a1", "a2") for k, s in _PCT_STATS.items()}


@functools.cache
def percentages_from_reproduction() -> dict:
    """§6.3.3 percentages from our reproduction: r2 (eq 6-5) / r1 as numbers; a1, a2 / r1 as min–max
    Intervals over the LM seeds."""
    reg = table6_3_regression_values()
    out = {f"r2.{k}": 100 * reg[f"r2.{s}"] / reg[f"r1.{s}"] for k, s in _PCT_STATS.items()}
    for m in ("a1", "a2"):
        t = ann_statistics(m)
        for k, s in _PCT_STATS.items():
            out[f"{m}.{k}"] = _interval(100 * t[s] / reg[f"r1.{s}"])
    return out


# ------------------------------------------------------------------------------ beyond the paper
def surrogate_features(df: pd.DataFrame) -> np.ndarray:
    """Physics-informed inputs: ``a_p/D`` and sin/cos of A_N2 and A_f (the model is scale-invariant:
    ``D_eff = D·g(a_p/D, A_N2, A_f)``, and periodic in the angles)."""
    a2, af = np.radians(df["A_N2"].to_numpy()), np.radians(df["A_f"].to_numpy())
    return np.column_stack([df["a_p"].to_numpy() / df["D"].to_numpy(), np.sin(a2), np.cos(a2),
                            np.sin(af), np.cos(af)])


@cached()
def _surrogate_net(seed: int, hidden: tuple, max_epochs: int):
    """One network of :func:`surrogate_runs` (cached under build/cache/)."""
    df = dataset()
    X, Y = surrogate_features(df), df[list(OUTPUTS)].to_numpy() / df[["D"]].to_numpy()
    return train_mlp(X, Y, hidden=hidden, activation="tansig", trainer="lm", seed=seed,
                     max_epochs=max_epochs)


@functools.cache
def surrogate_runs(n_seeds: int = 3, hidden: tuple = (20, 20), max_epochs: int = 400) -> tuple:
    """Train the surrogate: features of :func:`surrogate_features` → tanh (20, 20) → ``D_eff/D``; LM."""
    return tuple(sweep(_surrogate_net, [(s, tuple(hidden), max_epochs) for s in range(n_seeds)]))


def surrogate_predict(net, df: pd.DataFrame) -> np.ndarray:
    """``(n, 2)`` working diameters (mm) predicted by a surrogate network."""
    return net.predict(surrogate_features(df)) * df[["D"]].to_numpy()


def held_out_rmse(model: str, n_seeds: int = N_SEEDS, max_epochs: int = MAX_EPOCHS, **surrogate_kw) -> pd.DataFrame:
    """Test-split RMSE (mm) of D_eff1 and D_eff2 per seed for 'a1', 'a2' or 'surrogate'."""
    df = dataset()
    Y = df[list(OUTPUTS)].to_numpy()
    if model == "surrogate":
        nets = surrogate_runs(n_seeds, **surrogate_kw)
        preds = [surrogate_predict(n, df) for n in nets]
    else:
        nets = ann_runs(model, n_seeds, "lm", max_epochs)
        preds = [n.predict(df[list(INPUTS)].to_numpy()) for n in nets]
    rows = []
    for net, P in zip(nets, preds):
        te = net.split[2]
        r = np.sqrt(np.mean((P[te] - Y[te]) ** 2, axis=0))
        rows.append({"seed": net.seed, "rmse_D_eff1": r[0], "rmse_D_eff2": r[1]})
    return pd.DataFrame(rows).set_index("seed")


# ------------------------------------------------------------------------------ comparison tables
def r1_comparison() -> pd.DataFrame:
    """The r1 MiniTab table: printed next to reproduced, with the coefficient gap in SE units."""
    p = printed_r1_table()
    t = r1_fit().coefficient_table()
    t.index = p.index
    out = pd.concat({"printed": p, "reproduced": t}, axis=1)
    out[("gap", "|dCoef|/SE")] = (t["Coef"] - p["coef"]).abs() / p["se_coef"]
    return out


def table6_2_comparison() -> pd.DataFrame:
    """Table 6-2 printed vs reproduced: coefficients per D, f_i(D) and the R² column (plain and adjusted)."""
    p = printed_table6_2().drop(index="R-Sq(adj)")
    fits, lines = r2_fits(), r2_lines()
    rows = {}
    for term in p.index:
        r = {f"D={int(D)} printed": p.loc[term, f"D{int(D)}"] for D in fits}
        r.update({f"D={int(D)} ours": fits[D].params[term] for D in fits})
        r.update({"slope printed": p.loc[term, "slope"], "slope ours": lines.loc[term, "slope"],
                  "intercept printed": p.loc[term, "intercept"], "intercept ours": lines.loc[term, "intercept"],
                  "'R-Sq(adj)' printed": p.loc[term, "rsq_column"], "R² ours": lines.loc[term, "r_sq"],
                  "R²adj ours": lines.loc[term, "r_sq_adj"]})
        rows[term] = r
    return pd.DataFrame(rows).T


def seed_summary(stats: pd.DataFrame, columns=STAT_NAMES) -> pd.DataFrame:
    """mean ± sd and min–max over seeds of the given columns of :func:`ann_statistics`."""
    s = stats[list(columns)]
    return pd.DataFrame({"mean": s.mean(), "sd": s.std(ddof=1), "min": s.min(), "max": s.max()})


def run_settings() -> tuple[int, int]:
    """``(n_seeds, max_epochs)`` of the notebook and figure runs of the networks: (:data:`N_SEEDS`,
    :data:`MAX_EPOCHS`), or (2, 100) in fast mode (``CNCLAB_FAST=1``)."""
    return pick(N_SEEDS, 2), pick(MAX_EPOCHS, 100)


def table6_3_reproduced(n_seeds: int = N_SEEDS, max_epochs: int = MAX_EPOCHS) -> pd.DataFrame:
    """Table 6-3 reproduced (statistics of D_eff1 differences × models, mm or fraction): r1, r2 (eq 6-5)
    and the means over ``n_seeds`` LM-trained networks a1, a2 (``max_epochs`` each)."""
    t = regression_statistics()[["r1", "r2 (unified, eq 6-5)"]].set_axis(["r1", "r2"], axis=1)
    for m in ARCHITECTURES:
        t[m] = seed_summary(ann_statistics(m, n_seeds, "lm", max_epochs))["mean"]
    return t


def surrogate_statistics(n_seeds: int = 3, max_epochs: int = 400) -> pd.DataFrame:
    """Table 6-3 statistics of D_eff1 over all 2704 rows for each surrogate seed (as :func:`ann_statistics`)."""
    df = dataset()
    y = df["D_eff1"].to_numpy()
    rows = [dict(difference_stats(y, surrogate_predict(net, df)[:, 0]), seed=net.seed)
            for net in surrogate_runs(n_seeds, max_epochs=max_epochs)]
    return pd.DataFrame(rows).set_index("seed")


# ------------------------------------------------------------------------------ ledger audit (issue 13)
def table6_3_printed_values() -> dict:
    """Table 6-3 as printed, ``<model>.<stat>``; the §6.3.3 text restates several of its cells
    (``<model>.r2_pct`` = R² in % as the text prints it)."""
    t = printed_table6_3()
    out = {f"{m}.{s}": float(t.loc[s, m]) for m in t.columns for s in t.index}
    out.update({f"{m}.r2_pct": 100 * float(t.loc["r2", m]) for m in t.columns})
    return out


def dataset_rows() -> int:
    """§6.4 "2704 variations of input parameters": rows of the Table 6-1 full factorial (4·4·13·13)."""
    return len(dataset())


def r1_from_printed_r2_means() -> dict:
    """r1 = mean of r2 (printed tables only): on the balanced Table 6-1 plan, each r1 coefficient of a
    shared term equals the mean of the four per-D Table 6-2 coefficients, and r1's constant + coef_D·9
    (the mean D) equals the mean of the per-D constants. Keys: term ids (``ap``, ``AN2_2``, …; ``const``
    = mean of the per-D constants − 9 · r1's printed coef_D)."""
    t = printed_table6_2().drop(index="R-Sq(adj)")
    cols = [c for c in t.columns if c.startswith("D")]
    out = {}
    for term in t.index:
        key = TERM_IDS.get(term, term)
        out[key] = float(t.loc[term, cols].astype(float).mean())
    coef_D = float(printed_r1_table()["coef"].iloc[1])
    out["const"] = out.pop("const") - 9.0 * coef_D     # mean of per-D constants = C + c_D · mean(D)
    return out


def printed_r1_coefficients() -> dict:
    """The MiniTab coefficient column under eq 6-4 as printed, keyed by term id (``const``, ``D``, ``ap`` …);
    eq 6-4's displayed equation restates it rounded to 3 significant digits."""
    p = printed_r1_table()
    ids = list(TERM_IDS.values())
    return {ids[i]: float(v) for i, v in enumerate(p["coef"].to_numpy())}


# ------------------------------------------------------------------------------ ledger rules (issue 25)
@functools.cache
def line_rsq_from_printed_coefficients() -> dict:
    """Table 6-2's last column recomputed from the table's own printed per-D coefficients: the plain
    R² (%) of the straight line through the four printed values of each term, keyed by term id.

    This is arithmetic on printed numbers (no data set involved), so the column is checked at half a
    printed unit (0.005 %) without any allowance for the numerical data.
    """
    t = printed_table6_2().drop(index="R-Sq(adj)")
    cols = [c for c in t.columns if c.startswith("D")]
    D = np.array([float(c[1:]) for c in cols])
    out = {}
    for term in t.index:
        y = t.loc[term, cols].astype(float).to_numpy()
        slope, intercept = np.polyfit(D, y, 1)
        resid = y - (slope * D + intercept)
        out[TERM_IDS[term]] = 100.0 * (1.0 - resid @ resid / np.sum((y - y.mean()) ** 2))
    return out


def r2_from_printed_training_R() -> dict:
    """Table 6-3's R² restated from §6.3.2's printed training R of each network: ``{model: R²}``
    (0.99512² = 0.9903 for a1, 0.99892² = 0.9978 for a2)."""
    f = printed_ann_figures()
    return {m: float(f.loc[m, "r_train"]) ** 2 for m in f.index}


@functools.cache
def ann_seed_intervals() -> dict:
    """``<model>.<stat>`` -> :class:`Interval` (min … max over the :data:`N_SEEDS` LM seeds, centre = the
    median) for every ``ROW_STATS`` statistic: what MATLAB-default training (``initnw``, ``dividerand``,
    ``trainlm``) gives run to run. A printed value inside it is one possible run; which one the thesis
    drew depends on MATLAB's random stream, which is not printed."""
    out = {}
    for model in ARCHITECTURES:
        t = ann_seed_table(model).drop(index=["printed", "percentile"])
        for col in ROW_STATS:
            v = t[col].astype(float)
            out[f"{model}.{col}"] = Interval(float(v.min()), float(v.max()), center=float(v.median()))
    return out


@functools.cache
def tangent_search_emulation(steps_deg=(5.0, 2.0, 1.0, 0.5, 0.25, 0.1, 0.05)) -> pd.DataFrame:
    """What a numerical tangent search (§5.2 step 6) of finite resolution does to the r1 table: the
    tangent point taken at the circle sample nearest to the exact one (``round``) or the last sample
    before it (``floor``), samples every ``step`` degrees of the circle parameter; the r1 model refitted.
    Columns: ``mode``, ``step_deg``, ``within_half_unit`` (how many of the 12 printed coefficients the
    fit reproduces within half a printed unit), ``median_error_half_units``. Step 0 = the exact point."""
    plan = full_factorial(LEVELS)
    D, ap, AN2, Af = (plan[c].to_numpy(float) for c in INPUTS)
    b, d = np.radians(AN2), np.radians(Af)
    r, u0 = np.sqrt(ap * (D - ap)), (D / 2 - ap) * np.sin(b)
    t_exact = np.arctan2(np.cos(d), np.cos(b) * np.sin(d))
    printed = printed_r1_table()
    text = pd.read_csv(data_path("mgherony2024", "ch6_eq6-4_r1_coefficients.csv"), comment="#", dtype=str)
    half = pd.Series([0.5 * 10.0 ** -len(c.split(".")[1]) for c in text["coef"]], index=printed.index)
    rows = []
    for mode, fn in (("round", np.round), ("floor", np.floor)):
        for step in (0.0, *steps_deg):
            t = t_exact if step == 0 else fn(t_exact / np.radians(step)) * np.radians(step)
            y = 2 * np.hypot(u0 + r * np.cos(b) * np.cos(t), r * np.sin(t))
            fit = rs.fit_polynomial(plan.assign(y=y), "y", rs.R1_TERMS)
            err = ((fit.params - printed["coef"]) / half).abs()
            rows.append({"mode": mode, "step_deg": step, "within_half_unit": int((err <= 1 + 1e-9).sum()),
                         "median_error_half_units": float(err.median())})
    return pd.DataFrame(rows)
