"""Planar zig-zag (raster) tool paths — Hoang (2024) Table 1, and a general covering raster.

Passes run along +X / −X (``length`` [mm]) and step along +Y by the stepover ``S_z`` [mm] until the
``width`` [mm] is covered. Points are cutter-contact (CC) points in the XY plane; the programs built by
:func:`zigzag_path` put them at a cutting height ``z_cut`` [mm] with a plunge from and a retract to
``z_clear`` [mm], ending with a rapid back to the start above the part.

* :func:`hoang_table1_points` transcribes Table 1 literally (MATLAB ``for i = 1:n/2`` with
  ``n = Width/S_z + S_z/2``: ``floor(n/2)`` iterations of pass, stepover, pass, stepover).
* :func:`zigzag_points` covers the width: the last pass lies at ``y ≥ y0 + width`` (the paper's
  Fig. 9 "N107 X100 Y50.744" end-of-field fix), optionally with CC points every ``forward_step`` mm.

>>> p = zigzag_points((0, 0), width=2.0, length=10.0, stepover=1.0)
>>> p.tolist()
[[0.0, 0.0], [10.0, 0.0], [10.0, 1.0], [0.0, 1.0], [0.0, 2.0], [10.0, 2.0]]
"""
from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.geometry import LineString

from .path import ToolPath

__all__ = ["hoang_table1_points", "zigzag_points", "zigzag_path", "n_passes_covering", "raster_lines"]


def _positive(name, v):
    if not (isinstance(v, (int, float, np.floating, np.integer)) and math.isfinite(v) and v > 0):
        raise ValueError(f"{name} must be a finite number > 0 (mm), got {v!r}")
    return float(v)


def hoang_table1_points(x: float, y: float, width: float, length: float, stepover: float,
                        forward_step: float) -> np.ndarray:
    """Table 1 of Hoang (2024) executed as printed; returns the (k, 2) XY points [mm] of ``temp``.

    ``n = Width/S_z + S_z/2``, ``m = Long/F_r``; ``for i = 1:n/2`` runs ``floor(n/2)`` times (MATLAB
    colon semantics), each iteration appending a +X pass of ``F_r·m`` (= Long), a stepover, a −X pass
    and a stepover (so the path ends with a stepover after the last pass).
    """
    width, length = _positive("width", width), _positive("length", length)
    sz, fr = _positive("stepover", stepover), _positive("forward_step", forward_step)
    n = width / sz + sz / 2.0          # line 7, as printed
    m = length / fr                    # line 8
    temp = [(x, y)]
    for _ in range(int(math.floor(n / 2.0))):   # MATLAB 1:n/2 -> 1..floor(n/2)
        x = x + fr * m
        temp.append((x, y))
        y = y + sz
        temp.append((x, y))
        x = x - fr * m
        temp.append((x, y))
        y = y + sz
        temp.append((x, y))
    return np.array(temp, dtype=float)


def n_passes_covering(width: float, stepover: float) -> int:
    """Number of passes so that the last one lies at or beyond ``width`` mm: ``ceil(width/S_z) + 1``.

    >>> n_passes_covering(50.0, 0.994987)
    52
    """
    width, sz = _positive("width", width), _positive("stepover", stepover)
    return int(math.ceil(width / sz - 1e-12)) + 1


def zigzag_points(start, width: float, length: float, stepover: float, forward_step: float | None = None,
                  n_passes: int | None = None) -> np.ndarray:
    """Zig-zag CC points [mm], (k, 2): passes along X of ``length``, stepping ``stepover`` along +Y.

    ``n_passes`` defaults to :func:`n_passes_covering`; with ``forward_step`` [mm] each pass carries
    CC points every ``forward_step`` (the last interval may be shorter), else only its two ends.
    """
    x0, y0 = (float(v) for v in start)
    width, length = _positive("width", width), _positive("length", length)
    sz = _positive("stepover", stepover)
    if n_passes is None:
        n_passes = n_passes_covering(width, sz)
    if int(n_passes) != n_passes or n_passes < 1:
        raise ValueError(f"n_passes must be an int >= 1, got {n_passes!r}")
    if forward_step is None:
        xs = np.array([0.0, length])
    else:
        fr = _positive("forward_step", forward_step)
        xs = np.append(np.arange(0.0, length, fr), length)
        xs = xs[np.r_[True, np.diff(xs) > 1e-12]]
    pts = []
    for k in range(int(n_passes)):
        xk = xs if k % 2 == 0 else xs[::-1]
        pts.append(np.column_stack([x0 + xk, np.full(len(xk), y0 + k * sz)]))
    return np.vstack(pts)


def zigzag_path(points, z_cut: float, z_clear: float, feed: float, spindle: float | None = None,
                plunge_feed: float | None = None, return_home: bool = True, tool=None) -> ToolPath:
    """The tool path of XY ``points`` [mm]: rapid above the first point at ``z_clear``, plunge to
    ``z_cut`` (at ``plunge_feed``, default ``feed`` [mm/min]), cuts through the points, retract to
    ``z_clear`` at ``feed``, and (``return_home``) a rapid back above the first point.

    >>> zigzag_path([[0, 0], [10, 0]], z_cut=0, z_clear=10, feed=500).kinds().tolist()
    ['rapid', 'plunge', 'cut', 'retract', 'rapid']
    """
    p = np.asarray(points, float)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 2:
        raise ValueError(f"points must have shape (k >= 2, 2), got {p.shape}")
    if not z_clear > z_cut:
        raise ValueError(f"z_clear must be above z_cut (mm), got z_clear={z_clear}, z_cut={z_cut}")
    pf = feed if plunge_feed is None else plunge_feed
    xy = np.vstack([p[:1], p[:1], p, p[-1:]] + ([p[:1]] if return_home else []))
    z = np.r_[z_clear, z_cut, np.full(len(p), z_cut), z_clear] + 0.0
    kinds = ["rapid", "plunge"] + ["cut"] * len(p) + ["retract"]
    feeds = [np.nan, pf] + [feed] * len(p) + [feed]
    if return_home:
        z = np.r_[z, z_clear]
        kinds.append("rapid")
        feeds.append(np.nan)
    P = np.column_stack([xy, z])
    keep = np.r_[True, np.any(np.diff(P, axis=0) != 0, axis=1)]      # the plunge lands on points[0]
    return ToolPath.build(P[keep], kind=list(np.array(kinds, dtype=object)[keep]), feed=np.array(feeds)[keep],
                          spindle=spindle, tool=tool, info={"name": "zig-zag"})


def raster_lines(region, stepover: float, min_length: float = 1e-6) -> list[np.ndarray]:
    """Zig-zag raster over a shapely (Multi)Polygon ``region`` (mm): lines along x every ``stepover``
    mm in y from the bottom, clipped to the region (pieces shorter than ``min_length`` mm dropped),
    alternate lines reversed; list of (2, 2) arrays.

    >>> from shapely.geometry import box
    >>> [q.round(6).tolist() for q in raster_lines(box(0, 0, 10, 2), 1.0)]
    [[[0.0, 1e-06], [10.0, 1e-06]], [[10.0, 1.000001], [0.0, 1.000001]]]
    """
    sz = _positive("stepover", stepover)
    x0, y0, x1, y1 = region.bounds
    lines = []
    for i, y in enumerate(np.arange(y0 + 1e-6, y1, sz)):
        g = region.intersection(LineString([(x0 - 1, y), (x1 + 1, y)]))
        parts = sorted((np.asarray(p.coords) for p in shapely.get_parts(g) if p.length > min_length),
                       key=lambda q: q[:, 0].min())
        for q in parts:
            q = q[np.argsort(q[:, 0])]
            lines.append(q if i % 2 == 0 else q[::-1])
    return lines
