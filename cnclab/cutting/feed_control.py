"""Feed control in roll-in / roll-out segments holding the simulated MRR at its nominal value
(Jacsó 2021, §4: "feed rate control in the roll-in and roll-out sections", capped at v_fmax).

The MRR of a step is a_p * w * v_f with w = removed area / path length (mm) the *removal width*;
on a straight cut at engagement theta, w = a_e = r (1 - cos theta). Where the engagement drops
(roll-in, roll-out, air) the feed is raised to v_nom * a_e / w so that MRR = MRR_nom, at most
``v_fmax``; where it rises above theta it is lowered the same way. The feed is set per G-code block
of about ``block_mm`` (the removal width averaged over the block), so it changes in steps the
controller can follow.

Units: mm, mm^2, mm/min, degrees.

>>> import numpy as np
>>> w = np.r_[np.full(10, 1.5), np.full(10, 0.5), np.zeros(10)] * 0.05    # removed mm^2 per 0.05 mm
>>> v = controlled_feed(w, np.full(30, 0.05), np.r_[np.full(10, 60.), np.full(20, 20.)],
...                     np.ones(30, bool), 1.5, 255.0, 1000.0, 60.0, block_mm=0.5)
>>> v[[0, 15, 25]].tolist()              # nominal, 3x (MRR held), capped in air
[255.0, 765.0, 1000.0]
"""
from __future__ import annotations

import numpy as np

__all__ = ["controlled_feed", "machining_time_s", "mrr_error", "mrr_error_windowed"]


def controlled_feed(removed_mm2, ds_mm, engagement_deg, cutting, a_e_nominal, v_nominal,
                    v_fmax, theta_deg, block_mm=0.5, margin_deg=5.0, adjust=None):
    """Per-step feed (mm/min) along a simulated path (arrays of equal length).

    ``removed_mm2``: area removed by each step; ``ds_mm``: step lengths; ``engagement_deg``: step
    engagement; ``cutting``: True on cutting moves (others get NaN). A block of consecutive cutting
    steps (about ``block_mm`` long) whose mean engagement deviates from ``theta_deg`` by more than
    ``margin_deg`` gets v = min(v_fmax, v_nominal a_e / w_block); otherwise v_nominal.
    With ``adjust`` (bool array, e.g. the roll-in/roll-out steps) exactly the blocks inside it get
    the MRR-holding feed (the booklet's rule) and every other cutting step runs at v_nominal.
    """
    rem = np.asarray(removed_mm2, float)
    ds = np.asarray(ds_mm, float)
    eng = np.nan_to_num(np.asarray(engagement_deg, float))
    cut = np.asarray(cutting, bool)
    if not (rem.shape == ds.shape == eng.shape == cut.shape):
        raise ValueError("removed_mm2, ds_mm, engagement_deg and cutting must have the same shape")
    for name, v in (("a_e_nominal", a_e_nominal), ("v_nominal", v_nominal), ("v_fmax", v_fmax),
                    ("block_mm", block_mm)):
        if not v > 0:
            raise ValueError(f"{name} must be > 0, got {v!r}")
    if v_fmax < v_nominal:
        raise ValueError(f"v_fmax ({v_fmax}) must be >= v_nominal ({v_nominal}) mm/min")
    v = np.full(rem.shape, np.nan)
    # block ids: a new block at every cutting-run start and every block_mm of path
    adj = None if adjust is None else np.asarray(adjust, bool)
    if adj is not None and adj.shape != cut.shape:
        raise ValueError("adjust must have the same shape as cutting")
    s = np.cumsum(np.where(cut, ds, 0.0))
    state = cut.astype(int) + (0 if adj is None else 2 * adj.astype(int))
    run = np.cumsum(np.r_[1, np.diff(state) != 0])
    blk = run * 10_000_000 + np.floor(s / block_mm).astype(np.int64)
    idx = np.flatnonzero(cut)
    if idx.size == 0:
        return v
    ub, inv = np.unique(blk[idx], return_inverse=True)
    A = np.bincount(inv, rem[idx])
    L = np.bincount(inv, ds[idx])
    E = np.bincount(inv, eng[idx] * ds[idx]) / np.maximum(L, 1e-12)
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.where(L > 0, A / L, 0.0)
        vb = np.where(w > 0, v_nominal * a_e_nominal / w, np.inf)
    vb = np.minimum(vb, v_fmax)
    if adj is None:
        off = np.abs(E - theta_deg) > margin_deg
    else:
        off = np.bincount(inv, adj[idx].astype(float)) > 0
    vb = np.where(off, vb, float(v_nominal))
    v[idx] = vb[inv]
    return v


def machining_time_s(ds_mm, feed_mm_min) -> float:
    """Sum of ds / v_f over the steps (s); steps with NaN feed are skipped.

    >>> machining_time_s([255.0, 1500.0], [255.0, 1500.0])
    120.0
    """
    ds = np.asarray(ds_mm, float)
    f = np.asarray(feed_mm_min, float)
    m = np.isfinite(f)
    if np.any(f[m] <= 0):
        raise ValueError("feed_mm_min must be > 0 where given")
    return 60.0 * float(np.sum(ds[m] / f[m]))


def mrr_error(mrr_mm3_min, mrr_nominal, mask=None) -> dict:
    """Relative MRR deviation from nominal (%, over ``mask``): mean |.|, p95 |.|, mean (signed).

    >>> round(mrr_error([1000.0, 1100.0], 1000.0)["mean_abs_pct"], 9)
    5.0
    """
    m = np.asarray(mrr_mm3_min, float)
    sel = np.isfinite(m) if mask is None else (np.asarray(mask, bool) & np.isfinite(m))
    e = 100.0 * (m[sel] / mrr_nominal - 1.0)
    return {"mean_abs_pct": float(np.mean(np.abs(e))), "p95_abs_pct": float(np.percentile(np.abs(e), 95)),
            "mean_pct": float(np.mean(e)), "n": int(sel.sum())}


def mrr_error_windowed(removed_mm2, ds_mm, feed_mm_min, a_p, mrr_nominal, mask=None, window_mm=1.0) -> dict:
    """MRR deviation from nominal over windows of ``window_mm`` path length (%).

    Definition used for the booklet's "1.5 % MRR error" (§4, Fig. 4.1): the steps in ``mask``
    (e.g. the constant-engagement cuts, outside roll-in/roll-out) are grouped into consecutive
    windows of about ``window_mm`` (within contiguous runs of the mask); each window's MRR is
    its removed volume over its time, a_p sum(A) / sum(ds / v_f) (mm^3/min); returned are the
    mean and p95 of |MRR_w / MRR_nom - 1| and the signed mean (in %), weighted by window length.

    >>> r = mrr_error_windowed([1.5, 1.5, 1.6, 1.4], [1.0] * 4, [255.0] * 4, 3.0, 1147.5)
    >>> round(r["mean_abs_pct"], 6), round(r["mean_pct"], 6)
    (3.333333, 0.0)
    """
    rem = np.asarray(removed_mm2, float)
    ds = np.asarray(ds_mm, float)
    v = np.asarray(feed_mm_min, float)
    m = np.ones(rem.shape, bool) if mask is None else np.asarray(mask, bool)
    m = m & (ds > 0) & np.isfinite(v)
    if not m.any():
        return {"mean_abs_pct": float("nan"), "p95_abs_pct": float("nan"), "mean_pct": float("nan"), "n": 0}
    run = np.cumsum(np.r_[1, np.diff(m.astype(int)) != 0])
    s = np.cumsum(np.where(m, ds, 0.0)) - np.where(m, ds, 0.0)
    blk = run * 10_000_000 + np.floor(s / window_mm + 1e-9).astype(np.int64)
    ub, inv = np.unique(blk[m], return_inverse=True)
    A = np.bincount(inv, rem[m])
    L = np.bincount(inv, ds[m])
    t = np.bincount(inv, ds[m] / v[m])
    e = 100.0 * (a_p * A / t / mrr_nominal - 1.0)
    w = L / L.sum()
    order = np.argsort(np.abs(e))
    cw = np.cumsum(w[order])
    p95 = float(np.abs(e)[order][min(int(np.searchsorted(cw, 0.95)), len(e) - 1)])
    return {"mean_abs_pct": float(np.sum(w * np.abs(e))), "p95_abs_pct": p95,
            "mean_pct": float(np.sum(w * e)), "n": int(len(e))}
