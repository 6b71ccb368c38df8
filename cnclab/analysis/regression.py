"""Ordinary least squares with a MiniTab-style report (statsmodels underneath).

>>> import numpy as np
>>> x = np.array([0., 1., 2., 3.]); y = 2 * x + 1
>>> fit = ols(y, {"x": x})
>>> [round(v, 6) for v in fit.params]            # Constant, x
[1.0, 2.0]
>>> round(fit_summary(fit)["R-Sq"], 3)
100.0
"""
from __future__ import annotations

import numpy as np
import pandas as pd


def ols(y, regressors: dict, constant: bool = True):
    """Fit ``y = b0 + Σ b_k·x_k`` by OLS; ``regressors`` maps term names to arrays.

    Returns a statsmodels ``RegressionResults`` whose ``params`` are labelled ``Constant`` and the
    term names.
    """
    import statsmodels.api as sm

    X = pd.DataFrame({k: np.asarray(v, dtype=float) for k, v in regressors.items()})
    if constant:
        X.insert(0, "Constant", 1.0)
    y = np.asarray(y, dtype=float)
    if len(y) != len(X):
        raise ValueError(f"y has {len(y)} rows but the regressors have {len(X)}")
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(X.to_numpy()))):
        raise ValueError("y and the regressors must be finite")
    return sm.OLS(y, X).fit()


def coefficient_table(fit) -> pd.DataFrame:
    """MiniTab-style coefficient table: Predictor, Coef, SE Coef, T, P."""
    return pd.DataFrame({"Coef": fit.params, "SE Coef": fit.bse, "T": fit.tvalues,
                         "P": fit.pvalues}).rename_axis("Predictor")


def fit_summary(fit) -> dict:
    """MiniTab-style fit statistics: S (residual standard error), R-Sq and R-Sq(adj) in percent."""
    return {"S": float(np.sqrt(fit.scale)), "R-Sq": 100.0 * float(fit.rsquared),
            "R-Sq(adj)": 100.0 * float(fit.rsquared_adj), "n": int(fit.nobs)}
