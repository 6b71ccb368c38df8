"""The dixel evaluator's engagement audited on an exact vector stock at chosen samples: its highest
peaks and a seeded random draw of cutting samples (:func:`vector_audit`).

The evaluator (:mod:`cnclab.toolpath.evaluate`) measures on dixels of side h; a wall skin or crescent
thinner than a dixel row can read as contact (over up to acos(1 - h / r) of the rim), and a
feature finer than a dixel can be missed. :func:`cnclab.simulation.vector.vector_engagement`
measures the same quantity on polygons, chips thinner than 2 um not counted. The audit says how far
apart the two are on a program: at the peaks (does the maximum stand on the vector stock?) and on
random samples (does the dixel read lower than the vector stock anywhere?).

The vector stock of a sample at height z is the slice of the pocket at z: the discs of every earlier
sample at or below z + 1 um cut it (a deeper tool cuts the slice too; one above it does not).

Units: mm, deg.
"""
from __future__ import annotations

import numpy as np

from ..simulation.vector import vector_engagement

__all__ = ["vector_audit", "vector_peaks"]


def _peaks(eng: np.ndarray, n: int, min_gap: int) -> list:
    """Indices of the ``n`` highest finite values of ``eng``, each ``min_gap`` samples from the others."""
    out = []
    for k in np.argsort(-np.nan_to_num(eng, nan=-np.inf)):
        if len(out) == n or not np.isfinite(eng[k]):
            break
        if all(abs(int(k) - q) > min_gap for q in out):
            out.append(int(k))
    return out


def _measurable(ev, counted) -> tuple:
    """(engagement (N,) deg, mask): the samples of ``ev`` that can be measured on the vector stock --
    ``counted`` (default the cutting samples) with a finite engagement and a step in the plane before
    them (the direction the front half faces)."""
    t = ev.trace
    eng = np.asarray(t["engagement_deg"], float)
    moved = np.r_[False, np.hypot(np.diff(t["x"]), np.diff(t["y"])) > 1e-9]
    base = np.asarray(t["cutting"], bool) if counted is None else np.asarray(counted, bool)
    return eng, base & moved & np.isfinite(eng)


def _measured(t, polygon, r, at, top_z) -> np.ndarray:
    """Vector engagement (deg) at the trace samples ``at``, each on the slice of its own height."""
    xy, z = np.c_[t["x"], t["y"]], np.asarray(t["z"], float)
    out = np.full(len(at), np.nan)
    for zk in np.unique(z[at]):
        sel = np.flatnonzero(z[at] == zk)
        cutting = (z <= zk + 1e-3) & (z < top_z)
        out[sel] = vector_engagement(polygon, xy, np.asarray(at)[sel], r, cutting=cutting)
    return out


def vector_audit(ev, job, n_peaks: int = 5, n_random: int = 300, seed: int = 0, min_gap: int = 200) -> dict:
    """The evaluation ``ev`` of a program on ``job`` audited on the vector stock: its ``n_peaks``
    highest cutting samples (``min_gap`` samples apart) and ``n_random`` cutting samples drawn with
    ``seed``. A dict (deg): ``dixel_max`` (the evaluator's maximum), ``peaks_dixel`` and
    ``peaks_vector`` (lists), ``vector_peak_max``, ``n_random``, ``random_vector_max`` (the vector
    stock's maximum over the random samples), ``random_diff_max`` (vector - dixel,
    the most the dixel under-reads), ``random_diff_min`` (the most it over-reads) and
    ``random_absdiff_p95``.

    >>> from shapely.geometry import box
    >>> from cnclab.toolpath.evaluate import evaluate
    >>> from cnclab.toolpath.job import Job
    >>> from cnclab.toolpath.path import Tool, ToolPath
    >>> job = Job(box(0, 0, 30, 12), Tool(4.0), 60.0, 1.0, feed_mm_min=300.0, spindle_rpm=8000.0)
    >>> p = ToolPath.build([[-5, 6, 5], [-5, 6, -1], [35, 6, -1], [35, 6, 5]],
    ...                    kind=["rapid", "plunge", "cut", "retract"], feed=300.0)
    >>> a = vector_audit(evaluate(p, job, 0.1), job, n_peaks=1, n_random=20)
    >>> round(a["vector_peak_max"]), abs(a["random_diff_max"]) < 1.0     # a slot: 180 on both stocks
    (180, True)
    """
    t = ev.trace
    eng, cut = _measurable(ev, None)
    pk = vector_peaks(ev, job, None, n_peaks, min_gap)
    vp = np.array([q[3] for q in pk])
    rng = np.random.default_rng(seed)
    idx = np.flatnonzero(cut)
    rand = np.sort(rng.choice(idx, size=min(n_random, idx.size), replace=False)) if idx.size else np.array([], int)
    vr = _measured(t, job.polygon, job.tool_radius, rand, job.top_z) if rand.size else np.array([])
    diff = vr - eng[rand]
    nan = float("nan")
    return {"dixel_max": float(eng[cut].max()) if cut.any() else nan,
            "peaks_dixel": [q[2] for q in pk], "peaks_vector": vp.tolist(),
            "vector_peak_max": float(vp.max()) if vp.size else nan, "n_random": int(rand.size),
            "random_vector_max": float(vr.max()) if vr.size else nan,
            "random_diff_max": float(diff.max()) if diff.size else nan,
            "random_diff_min": float(diff.min()) if diff.size else nan,
            "random_absdiff_p95": float(np.percentile(np.abs(diff), 95)) if diff.size else nan}


def vector_peaks(ev, job, counted=None, n_peaks: int = 5, min_gap: int = 200) -> list:
    """The ``n_peaks`` highest samples of the evaluation ``ev`` among ``counted`` ((N,) bool, default
    the cutting samples that moved), ``min_gap`` samples apart, measured on the vector stock:
    ``[(x mm, y mm, dixel deg, vector deg), ...]``, highest dixel first."""
    t = ev.trace
    eng, ok = _measurable(ev, counted)
    peaks = _peaks(np.where(ok, eng, np.nan), n_peaks, min_gap)
    if not peaks:
        return []
    v = _measured(t, job.polygon, job.tool_radius, peaks, job.top_z)
    return [(float(t["x"][k]), float(t["y"][k]), float(eng[k]), float(x)) for k, x in zip(peaks, v)]
