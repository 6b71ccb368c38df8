"""Designed experiments: the general full-factorial plan and its main-effect / interaction means.

A *plan* is a tidy :class:`pandas.DataFrame`: one column per factor, one row per run. The factor
levels keep the order they are given in, and the first factor varies slowest (as in MiniTab's
"Create Factorial Design" with no randomisation).

>>> plan = full_factorial({"D": [6, 8], "a_p": [0.15, 0.25, 0.35]})
>>> len(plan), list(plan.columns)
(6, ['D', 'a_p'])
>>> plan.iloc[1].tolist()
[6.0, 0.25]
"""
from __future__ import annotations

import itertools
from typing import Mapping, Sequence

import numpy as np
import pandas as pd

__all__ = ["full_factorial", "main_effects", "interaction_means"]


def full_factorial(levels: Mapping[str, Sequence[float]]) -> pd.DataFrame:
    """Every combination of the factor levels, first factor slowest.

    Parameters
    ----------
    levels : mapping factor name -> sequence of levels (numbers, any units; the order is kept).

    Returns
    -------
    DataFrame with ``prod(len(levels[f]))`` rows and one float column per factor.

    Raises ``ValueError`` naming the factor if it has no levels, repeated levels or non-finite levels.

    >>> full_factorial({"x": [1, 2], "y": [10, 20]})["y"].tolist()
    [10.0, 20.0, 10.0, 20.0]
    """
    if not isinstance(levels, Mapping) or not levels:
        raise ValueError("levels must be a non-empty mapping factor -> levels")
    cols = {}
    for name, lv in levels.items():
        if not isinstance(name, str) or not name:
            raise ValueError(f"factor names must be non-empty strings, got {name!r}")
        arr = np.asarray(list(lv), dtype=float)
        if arr.ndim != 1 or arr.size == 0:
            raise ValueError(f"factor {name!r} needs a non-empty 1-D sequence of levels")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"factor {name!r} has non-finite levels: {arr.tolist()}")
        if np.unique(arr).size != arr.size:
            raise ValueError(f"factor {name!r} has repeated levels: {arr.tolist()}")
        cols[name] = arr
    rows = np.array(list(itertools.product(*cols.values())), dtype=float)
    return pd.DataFrame(rows, columns=list(cols))


def main_effects(data: pd.DataFrame, factors: Sequence[str], response: str) -> dict[str, pd.Series]:
    """Mean response at each level of each factor (MiniTab "Main Effects Plot" data).

    Returns ``{factor: Series(mean response, index = level in sorted order)}``.

    >>> df = pd.DataFrame({"x": [1, 1, 2, 2], "y": [1.0, 3.0, 5.0, 7.0]})
    >>> main_effects(df, ["x"], "y")["x"].tolist()
    [2.0, 6.0]
    """
    _check_columns(data, [*factors, response])
    return {f: data.groupby(f)[response].mean() for f in factors}


def interaction_means(data: pd.DataFrame, row_factor: str, line_factor: str, response: str) -> pd.DataFrame:
    """Mean response for each (row level, line level) pair: one line per ``line_factor`` level.

    The table behind one panel of a MiniTab "Interaction Plot": index = levels of ``row_factor``
    (x axis), columns = levels of ``line_factor``. Parallel lines mean no interaction.
    """
    _check_columns(data, [row_factor, line_factor, response])
    return data.pivot_table(index=row_factor, columns=line_factor, values=response, aggfunc="mean")


def _check_columns(data: pd.DataFrame, names) -> None:
    missing = [n for n in names if n not in data.columns]
    if missing:
        raise ValueError(f"data has no column(s) {missing}; columns are {list(data.columns)}")
