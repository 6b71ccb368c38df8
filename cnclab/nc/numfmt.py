"""Vectorised fixed-point number formatting for the NC writers (APT, G-code).

:func:`fixed` turns an array of floats into the strings ``f"{v:.{decimals}f}"`` would give, with a
negative zero written without its sign (``-0.00001`` → ``"0.0000"``, as the G-code writer's
``_fmt``). It is byte-identical to Python's formatting (correctly rounded, ties to even on the
exact binary value): the integer ``k = rint(v·10^d)`` is used only where the float product cannot
sit on the wrong side of a rounding tie (``|frac(v·10^d) − ½|`` larger than the product's rounding
error bound); the few other values, and non-finite or huge ones, are formatted by Python.

>>> fixed([1.23456, -0.00001, 2.5, 3.5, -7.0], 0).tolist()
['1', '0', '2', '4', '-7']
>>> fixed([1.23456, -0.00001, 0.00005, -12.5], 4).tolist()
['1.2346', '0.0000', '0.0001', '-12.5000']
"""
from __future__ import annotations

import numpy as np

__all__ = ["fixed", "python_fixed"]


def python_fixed(v: float, decimals: int) -> str:
    """One value as ``f"{v:.{decimals}f}"`` with the sign of a negative zero dropped (reference)."""
    s = f"{v:.{decimals}f}"
    if s.startswith("-") and float(s) == 0.0:
        s = s[1:]
    return s


def fixed(values, decimals: int) -> np.ndarray:
    """Array of ``str`` (numpy unicode) of ``values`` with ``decimals`` digits after the point.

    Parameters
    ----------
    values : array-like of float (any shape; the result has the same shape).
    decimals : int in [0, 15], digits after the decimal point.
    """
    if not isinstance(decimals, (int, np.integer)) or not 0 <= decimals <= 15:
        raise ValueError(f"decimals must be an int in [0, 15], got {decimals!r}")
    v = np.asarray(values, dtype=float)
    shape = v.shape
    v = v.ravel()
    scale = 10.0 ** decimals
    p = v * scale
    # exactness guard: the product carries a relative error <= 2^-53; a value whose scaled fraction
    # lies within 4 ulp of a tie (or is not finite / too large for int64) goes to Python's formatter
    with np.errstate(invalid="ignore", over="ignore"):
        ap = np.abs(p)
        frac = ap - np.floor(ap)
        risky = ~np.isfinite(p) | (ap >= 2.0 ** 52) | (np.abs(frac - 0.5) <= ap * 2.0 ** -50 + 1e-300)
    safe = np.where(risky, 0.0, p)
    k = np.rint(safe).astype(np.int64)
    neg = k < 0
    a = np.abs(k)
    if decimals == 0:
        body = a.astype(str)
    else:
        m = 10 ** decimals
        ip = (a // m).astype(str)
        fp = np.strings.zfill((a % m).astype(str), decimals)
        body = np.strings.add(np.strings.add(ip, "."), fp)
    out = np.where(neg, np.strings.add("-", body), body)
    if risky.any():
        out = out.astype(object)
        for i in np.flatnonzero(risky):
            out[i] = python_fixed(float(v[i]), int(decimals))
        out = out.astype(str)
    return out.reshape(shape)
