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
from numba import njit

__all__ = ["fixed", "python_fixed", "scaled_ints", "gcode_linear_body"]


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


def scaled_ints(values, decimals: int) -> np.ndarray:
    """int64 ``k`` with ``fixed(values, decimals) == format(k / 10**decimals)``: the digits Python
    prints, as an integer (negative zero → 0). Non-finite or huge values raise ValueError."""
    v = np.asarray(values, dtype=float).ravel()
    if not np.isfinite(v).all():
        raise ValueError("scaled_ints: non-finite value")
    p = v * 10.0 ** decimals
    ap = np.abs(p)
    if (ap >= 2.0 ** 52).any():
        raise ValueError("scaled_ints: value too large for exact fixed-point formatting")
    frac = ap - np.floor(ap)
    risky = np.abs(frac - 0.5) <= ap * 2.0 ** -50 + 1e-300
    k = np.rint(p).astype(np.int64)
    for i in np.flatnonzero(risky):
        k[i] = int(python_fixed(float(v[i]), int(decimals)).replace(".", ""))
    return k


@njit(cache=True)
def _put_fixed(buf, pos, k, decimals):
    """Write the scaled integer ``k`` as fixed-point text with ``decimals`` digits; new position."""
    if k < 0:
        buf[pos] = 45  # '-'
        pos += 1
        k = -k
    m = 1
    for _ in range(decimals):
        m *= 10
    ip, fp = k // m, k % m
    # integer part
    tmp = np.empty(20, np.uint8)
    n = 0
    while True:
        tmp[n] = 48 + ip % 10
        n += 1
        ip //= 10
        if ip == 0:
            break
    for i in range(n - 1, -1, -1):
        buf[pos] = tmp[i]
        pos += 1
    if decimals > 0:
        buf[pos] = 46  # '.'
        pos += 1
        for i in range(decimals - 1, -1, -1):
            buf[pos + i] = 48 + fp % 10
            fp //= 10
        pos += decimals
    return pos


@njit(cache=True)
def gcode_linear_body(kx, ky, kz, rapid, kf, ks, has_s, decimals, feed_decimals):
    """RS274 lines (bytes) of linear moves, modal rules of :func:`cnclab.nc.program.write_moves`.

    ``kx, ky, kz``: scaled coordinates (:func:`scaled_ints`, ``decimals``); ``rapid``: G0 vs G1;
    ``kf``: scaled feeds (``feed_decimals``, ignored for G0); ``ks``/``has_s``: spindle (0 decimals,
    False = off). Returns (bytes array, spindle still on, last spindle value).
    """
    n = kx.shape[0]
    buf = np.empty(n * 96 + 64, np.uint8)
    pos = 0
    first = True
    cx = cy = cz = 0
    motion = -1
    have_f = False
    cur_f = 0
    have_s = False
    cur_s = 0
    for i in range(n):
        chx = first or kx[i] != cx
        chy = first or ky[i] != cy
        chz = first or kz[i] != cz
        if not (chx or chy or chz):
            continue
        first = False
        if has_s[i] != have_s or (has_s[i] and ks[i] != cur_s):
            if has_s[i]:
                buf[pos] = 83  # 'S'
                pos = _put_fixed(buf, pos + 1, ks[i], np.int64(0))
                buf[pos:pos + 4] = np.array([32, 77, 51, 10], np.uint8)  # ' M3\n'
                pos += 4
            else:
                buf[pos:pos + 3] = np.array([77, 53, 10], np.uint8)  # 'M5\n'
                pos += 3
            have_s = has_s[i]
            cur_s = ks[i]
        sep = False
        mo = 0 if rapid[i] else 1
        if mo != motion:
            buf[pos] = 71  # 'G'
            buf[pos + 1] = 48 + mo
            pos += 2
            motion = mo
            sep = True
        for ax in range(3):
            if ax == 0:
                ch, v, letter = chx, kx[i], 88
            elif ax == 1:
                ch, v, letter = chy, ky[i], 89
            else:
                ch, v, letter = chz, kz[i], 90
            if ch:
                if sep:
                    buf[pos] = 32
                    pos += 1
                buf[pos] = letter
                pos = _put_fixed(buf, pos + 1, v, decimals)
                sep = True
        if mo == 1 and (not have_f or kf[i] != cur_f):
            buf[pos] = 32
            buf[pos + 1] = 70  # 'F'
            pos = _put_fixed(buf, pos + 2, kf[i], feed_decimals)
            have_f = True
            cur_f = kf[i]
        cx, cy, cz = kx[i], ky[i], kz[i]
        buf[pos] = 10
        pos += 1
    return buf[:pos], have_s
