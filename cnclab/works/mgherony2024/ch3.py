"""Recipes for Mgherony (2024) chapter 3: cusp height and surface roughness, turning vs Z-level milling.

Inputs are the transcribed Tables 3-2, 3-3 (cutting parameters) and the measured Ra/Rz of Table 3-4
(``data/mgherony2024/ch3_*.csv``). Every printed number of the chapter is recomputed here:

- Table 3-4 CH column: eq 3-2 (turning, spacing = f) and eq 3-4 (Z-level milling, spacing
  a_p/sin A, A = 80°) — the *approximate* relations. The exact relation gives 0.1 … 1.7 % more
  (M2: 16.38 vs 16.11 µm); the printed column follows the approximation.
- Rz/Ra means (5.52 turning, 4.18 milling).
- Linear fits eqs 3-5 … 3-9 and their R² (turning, milling, both).
- The hybrid model eqs 3-10 … 3-12. As printed, ``Rx = C(RE, p)·CH``; the printed coefficients are in
  fact those of ``CH / Rx = C(RE, p)`` (so ``Rx = CH / C``), and the printed coefficients of
  determination (70.0 %, 88.8 %) are the *adjusted* R² of that fit.

Every quantity is returned in the unit the thesis prints (µm, %, mm/mm).
"""
from __future__ import annotations

import functools

import numpy as np
import pandas as pd

from ...analysis.regression import fit_summary, ols
from ...cutting.roughness import ideal_cusp_profile, profile_parameters
from ...geometry.cusp import cusp_height_from_spacing, zlevel_spacing
from ...paths import data_path

#: Half a unit of the last printed digit of Table 3-4's Ra and Rz (µm).
MEASUREMENT_ROUNDING_UM = 0.005


@functools.cache
def parts() -> pd.DataFrame:
    """The ten test parts (T1…T6 turning, M1…M4 Z-level milling) with parameters and measurements.

    Columns: process, RE_mm, p_mm (feed f for turning, step-down a_p for milling — the ``p`` of
    eq 3-10), spacing_mm (distance between tool-edge arcs), CH_um (eqs 3-2/3-4), CH_exact_um,
    Ra_um, Rz_um.
    """
    t = pd.read_csv(data_path("mgherony2024", "ch3_table3-2_turning_parameters.csv"), comment="#")
    m = pd.read_csv(data_path("mgherony2024", "ch3_table3-3_milling_parameters.csv"), comment="#")
    meas = pd.read_csv(data_path("mgherony2024", "ch3_table3-4_measured_roughness.csv"), comment="#")
    t = pd.DataFrame({"part": t.part, "process": "turning", "RE_mm": t.RE_mm, "p_mm": t.f_mm_rev,
                      "spacing_mm": t.f_mm_rev})
    m = pd.DataFrame({"part": m.part, "process": "milling", "RE_mm": m.RE_mm, "p_mm": m.a_p_mm,
                      "spacing_mm": zlevel_spacing(m.a_p_mm.to_numpy(), m.inclination_deg.to_numpy())})
    df = pd.concat([t, m], ignore_index=True).merge(meas, on="part", validate="one_to_one")
    df["CH_um"] = 1000 * cusp_height_from_spacing(df.spacing_mm.to_numpy(), df.RE_mm.to_numpy(), exact=False)
    df["CH_exact_um"] = 1000 * cusp_height_from_spacing(df.spacing_mm.to_numpy(), df.RE_mm.to_numpy())
    return df.set_index("part")


def cusp_height_table_um() -> pd.Series:
    """Table 3-4 CH column (µm) by the thesis's eqs 3-2/3-4."""
    return parts()["CH_um"]


def cusp_height_exact_um() -> pd.Series:
    """CH (µm) from the exact relation RE² = (s/2)² + (RE − CH)²."""
    return parts()["CH_exact_um"]


_GROUPS = {"turning": ("turning",), "milling": ("milling",), "both": ("turning", "milling")}


def _lstsq_stats(X: np.ndarray, Y: np.ndarray):
    """Batched OLS: X (n, k) shared design with constant column, Y (m, n) responses.

    Returns coefficients (m, k), R² and adjusted R² (m,) as fractions.
    """
    coef = np.linalg.lstsq(X, Y.T, rcond=None)[0].T
    resid = Y - coef @ X.T
    ss_res = (resid**2).sum(axis=1)
    ss_tot = ((Y - Y.mean(axis=1, keepdims=True)) ** 2).sum(axis=1)
    n, k = X.shape
    r2 = 1.0 - ss_res / ss_tot
    return coef, r2, 1.0 - (1.0 - r2) * (n - 1) / (n - k)


def _quantities(df: pd.DataFrame, Ra: np.ndarray | None = None, Rz: np.ndarray | None = None) -> dict:
    """Every printed chapter-3 statistic, for one or many (rows of ``Ra``/``Rz``) sets of measurements.

    Values are arrays of length m (number of measurement sets).
    """
    Ra = np.atleast_2d(df.Ra_um.to_numpy() if Ra is None else Ra)
    Rz = np.atleast_2d(df.Rz_um.to_numpy() if Rz is None else Rz)
    meas = {"Ra": Ra, "Rz": Rz}
    ch, proc = df.CH_um.to_numpy(), df.process.to_numpy()
    out = {}
    for g in ("turning", "milling"):
        out[f"ratio.{g}"] = (Rz / Ra)[:, proc == g].mean(axis=1)
    for g, procs in _GROUPS.items():
        sel = np.isin(proc, procs)
        X = np.column_stack([np.ones(sel.sum()), ch[sel]])
        for resp, Y in meas.items():
            coef, r2, _ = _lstsq_stats(X, Y[:, sel])
            out[f"linear.{g}.{resp}.slope"] = coef[:, 1]
            out[f"linear.{g}.{resp}.intercept"] = coef[:, 0]
            out[f"linear.{g}.{resp}.R2_pct"] = 100 * r2
    X = np.column_stack([np.ones(len(df)), df.RE_mm.to_numpy(), df.p_mm.to_numpy()])
    for form in ("as_printed", "inverse"):
        for resp, Y in meas.items():
            target = Y / ch if form == "as_printed" else ch / Y
            coef, r2, r2a = _lstsq_stats(X, target)
            key = f"hybrid.{form}.{resp}"
            for j, name in enumerate(("c0", "c_RE", "c_p")):
                out[f"{key}.{name}"] = coef[:, j]
            out[f"{key}.R2_pct"], out[f"{key}.R2adj_pct"] = 100 * r2, 100 * r2a
    return out


def linear_fit(group: str, resp: str):
    """statsmodels fit of ``resp = b0 + b1·CH`` for group in {"turning", "milling", "both"} (eqs 3-5 … 3-9)."""
    df = parts()[parts().process.isin(_GROUPS[group])]
    return ols(df[f"{resp}_um"], {"CH": df.CH_um})


def _hybrid_fit(df: pd.DataFrame, resp: str, form: str):
    """statsmodels fit of C(RE, p) = c0 + c_RE·RE + c_p·p on all ten parts.

    ``as_printed``: C = Rx/CH (eq 3-10, Rx = C·CH); ``inverse``: C = CH/Rx (Rx = CH/C).
    """
    rx, ch = df[f"{resp}_um"].to_numpy(), df.CH_um.to_numpy()
    target = rx / ch if form == "as_printed" else ch / rx
    return ols(target, {"RE": df.RE_mm, "p": df.p_mm})


@functools.cache
def statistics() -> dict:
    """Every printed chapter-3 statistic, keyed e.g. ``linear.turning.Ra.slope``, ``ratio.milling``,
    ``hybrid.inverse.Rz.R2adj_pct`` (R² in %)."""
    return {k: float(v[0]) for k, v in _quantities(parts()).items()}


def hybrid_model(resp: str, form: str = "inverse"):
    """The statsmodels fit of the hybrid model for ``resp`` in {"Ra", "Rz"} (see :func:`_hybrid_fit`)."""
    return _hybrid_fit(parts(), resp, form)


@functools.cache
def rounding_band(n: int = 20000, seed: int = 3, q: float = 99.5) -> dict:
    """How much each statistic moves when Ra, Rz are perturbed within their printed rounding.

    Monte Carlo: Ra and Rz of every part get independent uniform offsets in ±0.005 µm (the
    measurements are printed to 2 decimals); returns the ``q``-th percentile of |Δ| for every key
    of :func:`statistics`. With half a unit of the paper's last printed digit this is the tolerance
    basis of the chapter-3 claims.
    """
    rng = np.random.default_rng(seed)
    df = parts()
    h = MEASUREMENT_ROUNDING_UM
    Ra = df.Ra_um.to_numpy() + rng.uniform(-h, h, (n, len(df)))
    Rz = df.Rz_um.to_numpy() + rng.uniform(-h, h, (n, len(df)))
    ref = statistics()
    return {k: float(np.percentile(np.abs(v - ref[k]), q)) for k, v in _quantities(df, Ra, Rz).items()}


def ideal_vs_measured(profile_periods: int = 25) -> pd.DataFrame:
    """Roughness of the ideal cusp profile of every part next to the measured values (µm).

    The ideal profile is the periodic sequence of tool-edge arcs (spacing and radius of each part),
    evaluated over ``profile_periods`` periods in 5 sections (see :mod:`cnclab.cutting.roughness`).
    ``Ra_share``/``Rz_share``: ideal / measured — the part of the measured roughness that the
    geometry alone explains.
    """
    rows = []
    for part, r in parts().iterrows():
        x, z = ideal_cusp_profile(r.spacing_mm, r.RE_mm, profile_periods * r.spacing_mm,
                                  n=profile_periods * 800 + 1)
        p = profile_parameters(z * 1000.0)
        rows.append({"part": part, "process": r.process, "CH_um": r.CH_exact_um,
                     "Ra_ideal_um": p["Ra"], "Rq_ideal_um": p["Rq"], "Rz_ideal_um": p["Rz"],
                     "Rt_ideal_um": p["Rt"], "Ra_um": r.Ra_um, "Rz_um": r.Rz_um,
                     "Ra_share": p["Ra"] / r.Ra_um, "Rz_share": p["Rz"] / r.Rz_um})
    return pd.DataFrame(rows).set_index("part")


# ------------------------------------------------------------------------------ ledger audit (issue 13)
#: eqs 3-11 / 3-12 as printed: C(RE, p) = c0 + c_RE·RE + c_p·p
PRINTED_HYBRID = {"Ra": (1.94, -1.68, 11.6), "Rz": (0.24, -0.37, 3.45)}


def eq3_1_as_printed_ch_um() -> pd.Series:
    """Eq 3-1 *as printed*, RE² = (f/2)² + RE·CH, solved for CH (µm) for the turned parts T1…T6:
    CH = (RE² − f²/4)/RE ≈ RE (hundreds of µm). The geometry of Fig 3-1 is RE² = (f/2)² + (RE − CH)²,
    whose small-CH form is eq 3-2 (the Table 3-4 column)."""
    t = parts()[parts().process == "turning"]
    return 1000 * (t.RE_mm ** 2 - t.spacing_mm ** 2 / 4) / t.RE_mm


def hybrid_printed_r2_pct() -> dict:
    """Eqs 3-11/3-12 evaluated with the *printed* coefficients: the coefficient of determination (%) of
    C(RE, p) against the measured C of the ten parts, ``<Rx>.as_printed`` (C = Rx/CH, eq 3-10 as printed)
    and ``<Rx>.inverse`` (C = CH/Rx, the reading the coefficients come from)."""
    df = parts()
    ch = df.CH_um.to_numpy()
    out = {}
    for resp, (c0, c_re, c_p) in PRINTED_HYBRID.items():
        C = c0 + c_re * df.RE_mm.to_numpy() + c_p * df.p_mm.to_numpy()
        rx = df[f"{resp}_um"].to_numpy()
        for form, target in (("as_printed", rx / ch), ("inverse", ch / rx)):
            ss_res = np.sum((target - C) ** 2)
            ss_tot = np.sum((target - target.mean()) ** 2)
            out[f"{resp}.{form}"] = float(100 * (1 - ss_res / ss_tot))
    return out
