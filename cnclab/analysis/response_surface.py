"""Polynomial response-surface models fitted by OLS (statsmodels), reported the MiniTab way.

Mgherony (2024) §6.3.1 models the working diameter of a ball-end mill with the polynomial of
eq 6-4 in the tool diameter ``D`` (mm), the depth of cut ``a_p`` (mm), the surface inclination
``A_N2`` and the relative feed direction ``A_f`` (the data hold degrees; the terms use **radians**,
as the thesis's ``AN2_rad``, ``Af_rad``):

* **r1** — one fit over all tool diameters (:data:`R1_TERMS`);
* **r2** — one fit per tool diameter without the ``D`` term (:data:`R2_TERMS`, Table 6-2);
* **unified r2** (eq 6-5, Thesis 2) — each r2 coefficient replaced by a straight line in ``D``:
  ``D_eff = Σ f_i(D)·C_i`` with ``f_i(D) = slope_i·D + intercept_i`` (:class:`UnifiedModel`).

>>> import pandas as pd
>>> df = pd.DataFrame({"x": [0.0, 1, 2, 3], "y": [1.0, 3.1, 4.9, 7.0]})
>>> fit = fit_polynomial(df, "y", (Term("Constant"), Term("x", {"x": 1})), angle_columns=())
>>> fit.coefficient_table().loc["x", "Coef"].round(2)
np.float64(1.98)
"""
from __future__ import annotations

import dataclasses
from typing import Mapping, Sequence

import numpy as np
import pandas as pd

__all__ = ["Term", "R1_TERMS", "R1_TERMS_EQ6_4_AS_PRINTED", "R2_TERMS", "ANGLE_COLUMNS",
           "design_matrix", "fit_polynomial", "OLSFit", "fit_per_level", "linear_coefficient_functions",
           "UnifiedModel"]

#: Columns holding angles in degrees; their powers are taken in radians.
ANGLE_COLUMNS = ("A_N2", "A_f")


@dataclasses.dataclass(frozen=True)
class Term:
    """One regressor: the product of column powers, e.g. ``Term("AN2^3 x Af", {"A_N2": 3, "A_f": 1})``.

    An empty ``powers`` mapping is the constant term.
    """

    name: str
    powers: Mapping[str, int] = dataclasses.field(default_factory=dict)

    def __hash__(self):
        return hash((self.name, tuple(sorted(self.powers.items()))))

    def evaluate(self, data: pd.DataFrame, angle_columns=ANGLE_COLUMNS) -> np.ndarray:
        """The regressor column for ``data`` (angle columns in degrees, converted to radians)."""
        return self._from_columns(_columns(data, [self], angle_columns), len(data))

    def _from_columns(self, cols: dict, n: int) -> np.ndarray:
        out = np.ones(n)
        for col, p in self.powers.items():
            out = out * cols[col] ** p
        return out


def _columns(data: pd.DataFrame, terms, angle_columns) -> dict:
    """Each column the terms use, as a float array (angles converted to radians once)."""
    cols = {}
    for t in terms:
        for col in t.powers:
            if col in cols:
                continue
            if col not in data.columns:
                raise ValueError(f"term {t.name!r} needs column {col!r}; data has {list(data.columns)}")
            v = data[col].to_numpy(dtype=float)
            cols[col] = np.radians(v) if col in angle_columns else v
    return cols


def _t(name, **powers):
    return Term(name, powers)


_ANGLE_TERMS = (
    _t("AN2^2", A_N2=2), _t("AN2^4", A_N2=4), _t("Af^2", A_f=2),
    _t("(AN2 x Af)", A_N2=1, A_f=1), _t("(AN2 x Af^3)", A_N2=1, A_f=3),
    _t("(AN2^3 x Af)", A_N2=3, A_f=1), _t("(AN2^3 x Af^3)", A_N2=3, A_f=3),
    _t("(AN2^5 x Af)", A_N2=5, A_f=1),
)
#: r1 model as in the MiniTab coefficient table under eq 6-4 (last term AN2^5·Af^3).
R1_TERMS = (_t("Constant"), _t("D", D=1), _t("ap", a_p=1), *_ANGLE_TERMS, _t("(AN2^5 x Af^3)", A_N2=5, A_f=3))
#: eq 6-4 exactly as printed: its last term reads AN2^5·Af^5 (a typo, see the ch6 notebook).
R1_TERMS_EQ6_4_AS_PRINTED = (*R1_TERMS[:-1], _t("(AN2^5 x Af^5)", A_N2=5, A_f=5))
#: r2 model (Table 6-2): r1 without the D term, fitted once per tool diameter.
R2_TERMS = tuple(t for t in R1_TERMS if t.name != "D")


def design_matrix(data: pd.DataFrame, terms: Sequence[Term], angle_columns=ANGLE_COLUMNS) -> pd.DataFrame:
    """The regressor matrix (one column per term, named by the term); angles are converted to radians."""
    if len(data) == 0:
        raise ValueError("data has no rows")
    cols = _columns(data, terms, angle_columns)
    return pd.DataFrame({t.name: t._from_columns(cols, len(data)) for t in terms}, index=data.index)


@dataclasses.dataclass
class OLSFit:
    """An OLS fit of a polynomial model; ``result`` is the statsmodels RegressionResults."""

    terms: tuple
    response: str
    result: object
    angle_columns: tuple = ANGLE_COLUMNS

    @property
    def params(self) -> pd.Series:
        """Coefficients by term name."""
        return self.result.params

    def coefficient_table(self) -> pd.DataFrame:
        """MiniTab's table: ``Coef``, ``SE Coef``, ``T``, ``P`` indexed by predictor."""
        r = self.result
        return pd.DataFrame({"Coef": r.params, "SE Coef": r.bse, "T": r.tvalues, "P": r.pvalues})

    @property
    def S(self) -> float:
        """Standard error of the regression, sqrt(SSE / (n - p)) (units of the response)."""
        return float(np.sqrt(self.result.mse_resid))

    @property
    def r_sq(self) -> float:
        """R-Sq in percent."""
        return 100.0 * float(self.result.rsquared)

    @property
    def r_sq_adj(self) -> float:
        """R-Sq(adj) in percent."""
        return 100.0 * float(self.result.rsquared_adj)

    def predict(self, data: pd.DataFrame) -> np.ndarray:
        X = design_matrix(data, self.terms, self.angle_columns)
        return X.to_numpy() @ self.params.to_numpy()

    def summary_line(self) -> str:
        return f"S = {self.S:.6f}   R-Sq = {self.r_sq:.1f}%   R-Sq(adj) = {self.r_sq_adj:.1f}%"


def fit_polynomial(data: pd.DataFrame, response: str, terms: Sequence[Term],
                   angle_columns=ANGLE_COLUMNS) -> OLSFit:
    """Ordinary least squares of ``data[response]`` on the ``terms`` (include ``Term("Constant")``).

    Angle columns (degrees in ``data``) enter the terms in radians.
    """
    import statsmodels.api as sm

    if response not in data.columns:
        raise ValueError(f"response {response!r} is not a column of data ({list(data.columns)})")
    X = design_matrix(data, terms, angle_columns)
    if len(data) <= X.shape[1]:
        raise ValueError(f"need more rows than terms: {len(data)} rows, {X.shape[1]} terms")
    y = data[response].to_numpy(dtype=float)
    res = sm.OLS(y, X).fit()
    return OLSFit(tuple(terms), response, res, tuple(angle_columns))


def fit_per_level(data: pd.DataFrame, response: str, terms: Sequence[Term], by: str = "D",
                  angle_columns=ANGLE_COLUMNS) -> dict[float, OLSFit]:
    """One OLS fit per level of the column ``by`` (the r2 model: one fit per tool diameter)."""
    if by not in data.columns:
        raise ValueError(f"by={by!r} is not a column of data")
    return {float(k): fit_polynomial(g, response, terms, angle_columns) for k, g in data.groupby(by)}


def linear_coefficient_functions(fits: Mapping[float, OLSFit]) -> pd.DataFrame:
    """Fit each coefficient as a straight line of the level (Table 6-2's last two columns).

    Returns a DataFrame indexed by term with ``slope``, ``intercept``, ``r_sq`` (plain R², percent)
    and ``r_sq_adj`` (adjusted R², percent; n = number of levels, one regressor).
    """
    if len(fits) < 3:
        raise ValueError(f"need at least 3 levels to judge a straight line, got {len(fits)}")
    levels = np.array(sorted(fits), dtype=float)
    coefs = pd.DataFrame({lv: fits[lv].params for lv in levels}).T  # rows: levels
    rows = {}
    n = len(levels)
    for term in coefs.columns:
        y = coefs[term].to_numpy()
        slope, intercept = np.polyfit(levels, y, 1)
        resid = y - (slope * levels + intercept)
        sst = np.sum((y - y.mean()) ** 2)
        r2 = 1.0 - resid @ resid / sst if sst > 0 else np.nan  # a constant coefficient has no R²
        rows[term] = {"slope": slope, "intercept": intercept, "r_sq": 100 * r2,
                      "r_sq_adj": 100 * (1 - (1 - r2) * (n - 1) / (n - 2))}
    return pd.DataFrame(rows).T


@dataclasses.dataclass
class UnifiedModel:
    """eq 6-5: ``D_eff = Σ_i (slope_i·D + intercept_i)·C_i(a_p, A_N2, A_f)``.

    ``functions``: DataFrame indexed by term name with ``slope`` and ``intercept`` columns (e.g. from
    :func:`linear_coefficient_functions` or the printed Table 6-2); ``terms``: the r2 terms.
    """

    functions: pd.DataFrame
    terms: tuple = R2_TERMS
    level_column: str = "D"
    angle_columns: tuple = ANGLE_COLUMNS

    def __post_init__(self):
        missing = [t.name for t in self.terms if t.name not in self.functions.index]
        if missing:
            raise ValueError(f"functions lacks rows for terms {missing}")

    def coefficients(self, level) -> pd.Series:
        """The coefficients C_i at tool diameter ``level`` (mm)."""
        f = self.functions.loc[[t.name for t in self.terms]]
        return f["slope"] * float(level) + f["intercept"]

    def predict(self, data: pd.DataFrame) -> np.ndarray:
        X = design_matrix(data, self.terms, self.angle_columns).to_numpy()
        f = self.functions.loc[[t.name for t in self.terms]]
        lv = data[self.level_column].to_numpy(dtype=float)[:, None]
        return np.sum(X * (lv * f["slope"].to_numpy() + f["intercept"].to_numpy()), axis=1)
