"""The compiled piece tests of the arc fit (:mod:`cnclab.nc._arcfit_kernels`) against a plain NumPy
statement of the same tests (the fit's code before it was compiled, kept here as the reference): on
noisy arcs, helices and lines drawn from a fixed seed, both accept the same pieces and give the same
written centre. The tolerance is drawn well away from the points' deviations' floating-point noise, so
a disagreement is a real one."""
import math

import numpy as np
import pytest

from cnclab.nc import _arcfit_kernels as K
from cnclab.nc.arcfit import _MAX_STEP, _MAX_SWEEP

GRID = 1e-4
SCALE = 1e4


def ref_line_ok(P, i, j, tol):
    """The line P[i] -> P[j] fits P[i..j]: every point within its tolerance (``tol`` per chord of
    ``P``: a point gets the smaller of its two chords'; the line's distance to a chord is largest at
    the chord's ends) and advancing along the line."""
    A, B = P[i], P[j]
    d = B - A
    dd = float(d @ d)
    if dd <= 1e-18:
        return False
    Q = P[i:j + 1] - A
    t = Q @ d / dd
    if np.any(np.diff(t) < -1e-12):
        return False
    perp = Q - t[:, None] * d
    c = tol[i:j]
    tp = np.minimum(np.r_[c[0], c], np.r_[c, c[-1]])
    return bool(np.all(np.einsum("ij,ij->i", perp, perp) <= tp * tp))


def ref_arc_fit(P, i, j, tol, grid, max_radius):
    """``(code, cx, cy)`` of the arc through P[i] and P[j] that fits P[i..j] (``tol`` [mm] per chord
    of ``P``), or None."""
    Q = P[i:j + 1]
    A, B = Q[0], Q[-1]
    scale = 10.0 ** round(-math.log10(grid))
    Aw, Bw = np.round(A[:2] * scale) / scale, np.round(B[:2] * scale) / scale
    ch = Bw - Aw
    d = math.hypot(*ch)
    if d < 10 * grid:
        return None
    n = np.array([-ch[1], ch[0]]) / d
    Pr = Q[:, :2] - Aw
    half = 0.5 * ch
    a = np.einsum("ij,ij->i", Pr, Pr) - 2 * Pr @ half
    b = 2 * Pr @ n
    bb = float(b @ b)
    if bb <= 1e-18:
        return None                                       # collinear: a line, if anything
    t = float(a @ b) / bb
    if math.hypot(0.5 * d, t) > max_radius:
        return None
    c = np.round((Aw + half + t * n) * scale) / scale    # the centre as written
    r0, r1 = math.hypot(*(Aw - c)), math.hypot(*(Bw - c))
    if abs(r0 - r1) > 1.5 * grid:
        return None
    r = 0.5 * (r0 + r1)
    V = Q[:, :2] - c
    ang = np.arctan2(V[:, 1], V[:, 0])
    dth = (np.diff(ang) + math.pi) % (2 * math.pi) - math.pi
    sweep = float(dth.sum())
    s = 1.0 if sweep > 0 else -1.0
    if np.any(dth * s < -1e-12) or np.any(np.abs(dth) > _MAX_STEP) or not 1e-9 < abs(sweep) <= _MAX_SWEEP:
        return None
    cum = np.concatenate([[0.0], np.cumsum(dth)]) / sweep
    dz = Q[:, 2] - (A[2] + (B[2] - A[2]) * cum)
    dr = np.hypot(V[:, 0], V[:, 1]) - r
    # chords: outward deviation is largest at an end point (|p - c| is convex along a chord), inward
    # deviation is r minus the chord's distance to the centre; z at the chord's middle checked too
    E = np.diff(V, axis=0)
    ee = np.einsum("ij,ij->i", E, E)
    u = np.clip(-np.einsum("ij,ij->i", V[:-1], E) / np.where(ee > 0, ee, 1.0), 0.0, 1.0)
    near = V[:-1] + u[:, None] * E
    inward = r - np.hypot(near[:, 0], near[:, 1])
    rad = np.maximum(np.maximum(np.abs(dr[:-1]), np.abs(dr[1:])), inward)
    zmid = 0.5 * (Q[:-1, 2] + Q[1:, 2]) - (A[2] + (B[2] - A[2]) * 0.5 * (cum[:-1] + cum[1:]))
    zdev = np.maximum(np.maximum(np.abs(dz[:-1]), np.abs(dz[1:])), np.abs(zmid))
    tc = tol[i:j]                                    # per chord
    if np.any(rad * rad + zdev * zdev > tc * tc):
        return None
    return (3 if s > 0 else 2), float(c[0]), float(c[1])


def _polyline(rng):
    """A run of 8-80 points: an arc (radius 0.5-40 mm, sweep up to 300 deg, maybe descending in z), a
    line, or a zig of both, with noise of 0-8 um on every point."""
    n = int(rng.integers(8, 80))
    kind = rng.integers(0, 3)
    if kind == 0:
        r = rng.uniform(0.5, 40.0)
        sw = rng.uniform(0.05, 5.2) * rng.choice([-1, 1])
        a = rng.uniform(0, 2 * np.pi) + sw * np.linspace(0, 1, n)
        c = rng.uniform(-50, 50, 2)
        P = np.c_[c[0] + r * np.cos(a), c[1] + r * np.sin(a), np.linspace(0, rng.choice([0.0, -1.0]), n)]
    elif kind == 1:
        A, B = rng.uniform(-50, 50, 3), rng.uniform(-50, 50, 3)
        P = A + np.linspace(0, 1, n)[:, None] * (B - A)
    else:
        t = np.linspace(0, 1, n)
        P = np.c_[20 * t, 2 * np.sin(6 * t), np.zeros(n)]
    return P + rng.normal(0, rng.choice([0.0, 0.001, 0.003, 0.008]), (n, 3)) * np.r_[1, 1, 0.2]


@pytest.mark.parametrize("seed", range(4))
def test_compiled_piece_tests_agree_with_the_numpy_statement(seed):
    rng = np.random.default_rng(seed)
    n_arcs = n_lines = 0
    for _ in range(150):
        P = np.ascontiguousarray(_polyline(rng))
        tol = np.full(len(P) - 1, rng.choice([0.002, 0.004, 0.005, 0.02]))
        if rng.random() < 0.3:                  # per-chord allowances, as along a wall
            tol = tol * rng.uniform(0.1, 1.0, len(tol))
        i = int(rng.integers(0, len(P) // 3))
        for j in (i + 2, (i + len(P) - 1) // 2, len(P) - 1):
            if j <= i + 1:
                continue
            want = ref_line_ok(P, i, j, tol)
            assert K.line_ok(P, i, j, tol) == want
            n_lines += want
            got = K.arc_fit(P, i, j, tol, GRID, SCALE, 100.0, _MAX_STEP, _MAX_SWEEP)
            ref = ref_arc_fit(P, i, j, tol, GRID, 100.0)
            if ref is None:
                assert got[0] == 0
            else:
                n_arcs += 1
                assert got[0] == ref[0] and got[1:] == pytest.approx(ref[1:], abs=0.5 * GRID)
    assert n_arcs >= 20 and n_lines >= 20          # both kinds of piece are accepted, not only refused
