"""Score a ToolPath on the dixel simulator for the issue-16 comparison (the same rules for every
planner and for FreeCAD's programs). A stand-in until ``cnclab.toolpath.evaluate.evaluate`` lands
(the integrator switches the benchmark to it).

Rules: the path is resampled to steps <= the resolution; every point below the stock top cuts its
disk (2.5D, one level); consecutive such points form runs (:func:`cnclab.simulation.common.simulate_runs`,
engagement with the simulator's default lag). Cutting samples: in stock, removing more than 0.5 h^2,
not of an entry kind (helix/ramp/plunge), not the first point of a run. ``plunges_into_material``:
runs entered by a vertical feed or a rapid whose first disk removes more than ``tol_mm2`` (0.05 mm^2,
20 pixels at 0.05 mm: the dixel quantisation of a disk that only grazes material is below it);
``rapids_into_material``: rapid samples in stock removing more than ``tol_mm2``; ``retracts``: moves
from below the stock top to above it. Uncut beyond unreachable: stock left minus the area the tool
cannot reach (pocket minus its opening by the tool disk).
"""
from __future__ import annotations

import math

import numpy as np

from cnclab.simulation import dixel
from cnclab.simulation.common import simulate_runs
from cnclab.toolpath.path import KINDS

ENTRY = [KINDS.index(k) for k in ("helix", "ramp", "plunge")]
RAPID = KINDS.index("rapid")


def wpercentile(x, w, q):
    o = np.argsort(x)
    c = np.cumsum(w[o])
    return float(x[o][np.searchsorted(c, q / 100.0 * c[-1])])


def score(tp, job, resolution_mm=None, tol_mm2=0.05):
    h = float(resolution_mm or job.resolution_mm)
    r = job.tool_radius
    theta = job.theta_deg
    top = job.top_z
    R = tp.resample(h)
    z = R.xyz[:, 2]
    instock = z < top - 1e-6
    kind = R.kind
    # retracts: from below the top to above it (in the original moves)
    zo = tp.xyz[:, 2]
    retracts = int(np.sum((zo[:-1] < top - 1e-6) & (zo[1:] > top + 1e-6)))
    stock = dixel.Stock.from_polygon(job.polygon, h)
    if job.start_hole is not None:  # the pre-drilled hole is not stock
        stock.cut_disk(job.start_hole[:2], 0.5 * job.start_hole[2])
    T = simulate_runs(stock, R.xyz[:, :2], ~instock, r, job.a_p, job.feed_mm_min)
    idx = T.point.to_numpy()
    T = T[instock[idx]]
    idx = T.point.to_numpy()
    rem, ds, eng = T.removed_mm2.to_numpy(), T.ds.to_numpy(), T.engagement_deg.to_numpy()
    first = T.plunge.to_numpy()
    k = kind[idx]
    entry = np.isin(k, ENTRY)
    cut = (rem > 0.5 * h * h) & ~first & ~entry & np.isfinite(eng)
    # plunges: run starts reached vertically or by a rapid
    prev_kind = kind[np.maximum(idx - 1, 0)]
    vertical = first & ((k == KINDS.index("plunge")) | (k == RAPID) | (prev_kind == RAPID))
    plunges = int(np.sum(vertical & (rem > tol_mm2)))
    rapid_mat = int(np.sum((k == RAPID) & (rem > tol_mm2)))
    w = ds[cut]
    e = eng[cut]
    L = w.sum()
    unreach = float(job.polygon.difference(job.polygon.buffer(-r, quad_segs=64).buffer(r, quad_segs=64)).area)
    t = tp.time_s(job.rapid_mm_min)
    return {"p50": wpercentile(e, w, 50), "p95": wpercentile(e, w, 95), "max": float(e.max()),
            "share>5%": 100 * float(w[e > theta + 5].sum() / L), "share>15%": 100 * float(w[e > theta + 15].sum() / L),
            "entry_max": float(np.nanmax(eng[entry & (rem > 0.5 * h * h)])) if (entry & (rem > 0.5 * h * h)).any() else float("nan"),
            "retracts": retracts, "plunges": plunges, "rapids_in_mat": rapid_mat,
            "uncut_beyond_mm2": stock.area() - unreach, "time_min": t["total_s"] / 60.0,
            "cut_mm": float(L), "_trace": {"xy": R.xyz[idx[cut], :2], "eng": e, "ds": w, "tag": R.tag[idx[cut]]}}
