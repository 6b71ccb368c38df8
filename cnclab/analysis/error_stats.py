"""Statistics of the differences between calculated and estimated values (Mgherony 2024, eq 6-1…6-3).

>>> s = difference_stats([1.0, 2.0, 3.0, 4.0], [1.1, 1.9, 3.0, 4.0])
>>> round(s["range"], 3), round(s["rmse"], 4)
(0.2, 0.0707)
"""
from __future__ import annotations

import numpy as np

__all__ = ["difference_stats", "STAT_NAMES"]

#: Row order of Table 6-3.
STAT_NAMES = ("range", "st_dev", "r2", "rmse", "mape")


def difference_stats(calculated, estimated) -> dict[str, float]:
    """Range, standard deviation, R², RMSE and MAPE of ``e = calculated - estimated``.

    Parameters
    ----------
    calculated : array of the true (model) values x_i, e.g. working diameters in mm; must be non-zero
        for MAPE.
    estimated : array of the same shape, the estimates x̂_i.

    Returns
    -------
    dict with ``range`` = max(e) - min(e) (units of x), ``st_dev`` = sample standard deviation of e
    (ddof=1, as Excel's STDEV / MiniTab), ``r2`` = eq 6-1 (NaN if all x are equal), ``rmse`` = eq 6-2 (units of x),
    ``mape`` = eq 6-3 as a fraction (not percent), ``mean`` = mean of e, ``n``.
    """
    x = np.asarray(calculated, dtype=float).ravel()
    xh = np.asarray(estimated, dtype=float).ravel()
    if x.shape != xh.shape:
        raise ValueError(f"calculated and estimated must have the same size, got {x.size} and {xh.size}")
    if x.size < 2:
        raise ValueError(f"calculated needs at least 2 values, got {x.size}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(xh))):
        raise ValueError("calculated and estimated must be finite")
    if np.any(x == 0):
        raise ValueError("calculated contains zeros: MAPE (eq 6-3) is undefined")
    e = x - xh
    sst = np.sum((x - x.mean()) ** 2)
    return {
        "range": float(e.max() - e.min()),
        "st_dev": float(e.std(ddof=1)),
        "r2": float(1.0 - np.sum(e ** 2) / sst) if sst > 0 else float("nan"),  # undefined for constant x
        "rmse": float(np.sqrt(np.mean(e ** 2))),
        "mape": float(np.mean(np.abs(e / x))),
        "mean": float(e.mean()),
        "n": int(x.size),
    }
