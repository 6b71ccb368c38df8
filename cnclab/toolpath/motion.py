"""Machine time of a tool path or program: a documented machine model and a look-ahead velocity planner.

The RS274 canonical time (length / feed, :func:`cnclab.nc.gcode.program_time`) ignores that a
machine must accelerate, slow down at corners and on small arcs, and may not digest blocks faster
than its controller (or its serial line) can take them. :func:`machine_time` plans the feed along
the program as a GRBL-style (and, for the look-ahead, LinuxCNC-like) trajectory planner does:

* **Machine** (:class:`Machine`): per-axis maximum rate ``max_rate_mm_min`` (G0 runs at it; a
  G1/G2/G3 at ``min(F, axis limits)``) and acceleration ``accel_mm_s2``; along a move of unit
  direction ``u`` the limits are ``min_i(limit_i / |u_i|)`` (GRBL ``limit_value_by_axis_maximum``);
  arcs use the smaller of the X/Y limits (the direction turns through the plane);
* **junctions** (corners between blocks): GRBL's junction deviation ``junction_deviation_mm``
  (``$11``): ``v_j^2 = a * delta * sin(theta/2) / (1 - sin(theta/2))``, ``theta`` the angle between
  the reversed entry direction and the exit direction (180 deg = straight on: no limit; 0 deg = full
  reversal: stop), ``a`` the acceleration limit along the junction vector; arcs contribute their end
  tangents;
* **arcs**: the centripetal limit ``v <= sqrt(f a r)`` (``a`` the planar acceleration, ``f`` the
  machine's ``arc_normal_accel_fraction``), as LinuxCNC's planner applies to circular segments; the
  tangential acceleration on an arc is ``arc_tangential_accel_fraction`` of ``a``;
* **acceleration budget**: a planner may keep part of the acceleration for blending: lines plan
  with ``line_accel_fraction`` of it (LinuxCNC 2.9 under ``G64``: 1/2, :data:`LINUXCNC_29_FRACTIONS`;
  GRBL: all of it);
* **block rate** ``block_rate_hz`` (optional): every block lasts at least ``1 / block_rate_hz``
  (a streamed GRBL at 115200 baud, a controller's block processing time), applied as a cap
  ``v <= L * block_rate_hz`` on the block's speed;
* the look-ahead: a backward pass (every block can stop by the end of the program), a forward pass
  (accelerate from rest), then each block is a trapezoid or triangle of speed in time. The program
  starts and ends at rest; M-codes between moves do not stop the motion (the programs written by
  :func:`cnclab.nc.program.write_program` change spindle and coolant only before the first and
  after the last move).

Validated against LinuxCNC 2.9's own planner run headless in simulation (``make tp-check``,
``benchmarks/linuxcnc_tp.py``; fixture ``tests/fixtures/linuxcnc/tp_times.json``): within 2.6 % on
a line, a corner, a small full circle, a 360-gon, a 4000-chord spiral and our rectangle bench
program (``tests/test_machine_linuxcnc.py``, ``docs/linuxcnc-trajectory-check.md``); LinuxCNC's
blend arcs (a ``G64 P`` tolerance, tangent segments at full acceleration) are modelled by the
junction-deviation corner speed, the main source of the difference.

Layering: this module (toolpath layer) is the core, usable by the evaluator
(:mod:`cnclab.toolpath.evaluate`) on any :class:`~cnclab.toolpath.path.ToolPath`
(:func:`path_machine_time`); :mod:`cnclab.nc.machine` is its G-code-facing face (re-exports, the
machine of a program dialect).

Models: :data:`SMALL_VMC` (a small vertical machining centre under LinuxCNC) and
:data:`GRBL_ROUTER` (a hobby router under GRBL 1.1 with its default ``$11`` and ``$12``); both are
stated assumptions, not measurements of a particular machine.

>>> from cnclab.toolpath.path import Move
>>> m = Machine("demo", (6000, 6000, 6000), (100, 100, 100), 0.01)
>>> t = machine_time([Move("G1", 100, 0, 0, feed=6000)], m, start=(0, 0, 0))
>>> round(t["time_machine_s"], 6)       # 100 mm at 100 mm/s: 1 s ramp up, 0 s cruise, 1 s down
2.0
"""
from __future__ import annotations

import dataclasses
import math
from typing import Sequence

import numpy as np

from .path import Move, ToolPath, arc_geometry

__all__ = ["Machine", "LINUXCNC_29_FRACTIONS", "SMALL_VMC", "GRBL_ROUTER", "MACHINES", "machine_time",
           "path_machine_time", "trapezoid_time"]


@dataclasses.dataclass(frozen=True)
class Machine:
    """A 3-axis machine for :func:`machine_time`.

    ``max_rate_mm_min`` (x, y, z) per-axis maximum rate [mm/min] (the G0 rate); ``accel_mm_s2``
    (x, y, z) per-axis acceleration [mm/s^2]; ``junction_deviation_mm`` [mm] (GRBL ``$11``; a
    LinuxCNC ``G64 P`` blending tolerance plays the same role); ``block_rate_hz`` [blocks/s] or None.
    The fractions (default 1: GRBL) scale the acceleration a planner allows along a line
    (``line_accel_fraction``), along an arc (``arc_tangential_accel_fraction``) and across an arc
    (``arc_normal_accel_fraction``, the centripetal limit ``v <= sqrt(f a r)``); LinuxCNC 2.9 keeps
    part of the budget for blending: :data:`LINUXCNC_29_FRACTIONS`.
    """

    name: str
    max_rate_mm_min: tuple
    accel_mm_s2: tuple
    junction_deviation_mm: float
    block_rate_hz: float | None = None
    line_accel_fraction: float = 1.0
    arc_tangential_accel_fraction: float = 1.0
    arc_normal_accel_fraction: float = 1.0

    def __post_init__(self):
        for field in ("max_rate_mm_min", "accel_mm_s2"):
            v = tuple(float(x) for x in getattr(self, field))
            if len(v) != 3 or not all(math.isfinite(x) and x > 0 for x in v):
                raise ValueError(f"{field} must be three finite values > 0 (x, y, z), got {getattr(self, field)!r}")
            object.__setattr__(self, field, v)
        if not (math.isfinite(self.junction_deviation_mm) and self.junction_deviation_mm >= 0):
            raise ValueError(f"junction_deviation_mm must be finite and >= 0 mm, got {self.junction_deviation_mm!r}")
        for field in ("line_accel_fraction", "arc_tangential_accel_fraction", "arc_normal_accel_fraction"):
            f = getattr(self, field)
            if not (math.isfinite(f) and 0 < f <= 1):
                raise ValueError(f"{field} must be in (0, 1], got {f!r}")
        if self.block_rate_hz is not None and not (math.isfinite(self.block_rate_hz) and self.block_rate_hz > 0):
            raise ValueError(f"block_rate_hz must be None or a finite rate > 0 blocks/s, got {self.block_rate_hz!r}")


#: LinuxCNC 2.9's trajectory planner (``src/emc/tp/tp.c``, ``tpGetScaledAccel``) under ``G64``: a
#: segment that blends parabolically with its neighbour, or follows one, plans with half the
#: acceleration (so that two overlapping blends never exceed it): lines 1/2; a circular segment
#: further keeps ``BLEND_ACC_RATIO_TANGENTIAL`` = 1/2 of that for its tangential acceleration (1/4)
#: and limits its speed to ``sqrt(BLEND_ACC_RATIO_NORMAL a r)``, ``BLEND_ACC_RATIO_NORMAL`` =
#: ``sqrt(1 - 1/2^2)`` (``pmCircleActualMaxVel``). Measured with LinuxCNC 2.9 in simulation:
#: ``tests/fixtures/linuxcnc/tp_times.json`` (``benchmarks/linuxcnc_tp.py``).
LINUXCNC_29_FRACTIONS = {"line_accel_fraction": 0.5, "arc_tangential_accel_fraction": 0.25,
                         "arc_normal_accel_fraction": math.sqrt(0.75)}
#: a small VMC under LinuxCNC 2.9: 15 m/min X/Y, 10 m/min Z, 2.5 m/s^2 (X/Y), 1.5 m/s^2 (Z) per
#: axis, blending tolerance 0.01 mm (``G64 P0.01``), LinuxCNC's acceleration fractions
#: (:data:`LINUXCNC_29_FRACTIONS`), no block-rate limit (LinuxCNC plans from a file at its servo
#: rate). Axis limits assumed, the planner's rules LinuxCNC's.
SMALL_VMC = Machine("small VMC, LinuxCNC", (15000.0, 15000.0, 10000.0), (2500.0, 2500.0, 1500.0), 0.01,
                    **LINUXCNC_29_FRACTIONS)
#: a hobby router under GRBL 1.1: 5 m/min X/Y, 1.5 m/min Z, 0.5 m/s^2 (X/Y), 0.2 m/s^2 (Z),
#: junction deviation 0.01 mm (GRBL's default $11), 300 blocks/s (streaming ~25-character lines at
#: 115200 baud leaves room for ~400 blocks/s; 300 with the ok-handshake). Assumed.
GRBL_ROUTER = Machine("GRBL router", (5000.0, 5000.0, 1500.0), (500.0, 500.0, 200.0), 0.01, 300.0)
MACHINES = {"small-vmc": SMALL_VMC, "grbl-router": GRBL_ROUTER}


def _axis_limit(limits, u) -> float:
    """``min_i(limit_i / |u_i|)`` over the axes the unit vector ``u`` moves (GRBL)."""
    return float(_axis_limits(limits, np.asarray(u, float).reshape(1, 3))[0])


def _axis_limits(limits, U) -> np.ndarray:
    """:func:`_axis_limit` for each row of ``U`` (n, 3); inf for a zero row."""
    A = np.abs(U)
    with np.errstate(divide="ignore"):
        q = np.where(A > 1e-12, np.asarray(limits, float) / np.where(A > 1e-12, A, 1.0), math.inf)
    return q.min(axis=1)


def _arc_row(p0, mv, rate, acc, machine: Machine):
    """(length, speed cap, acceleration, entry tangent, exit tangent) of one G2/G3 block."""
    cx, cy, r, a0, sweep = arc_geometry(p0, mv.xyz, (p0[0] + mv.i, p0[1] + mv.j), mv.motion == "G3")
    dz = float(mv.xyz[2] - p0[2])
    arc_len = abs(sweep) * r
    length = math.hypot(arc_len, dz)
    s = 1.0 if sweep > 0 else -1.0
    tz = dz / length if length > 0 else 0.0
    k = arc_len / length if length > 0 else 0.0
    a1 = a0 + sweep
    tin = (-s * math.sin(a0) * k, s * math.cos(a0) * k, tz)
    tout = (-s * math.sin(a1) * k, s * math.cos(a1) * k, tz)
    plan_rate, plan_acc = min(rate[0], rate[1]), min(acc[0], acc[1])
    v = min(plan_rate / max(k, 1e-12), rate[2] / abs(tz) if abs(tz) > 1e-12 else math.inf)
    a = min(plan_acc / max(k, 1e-12), acc[2] / abs(tz) if abs(tz) > 1e-12 else math.inf)
    a *= machine.arc_tangential_accel_fraction
    # centripetal limit (on the xy projection)
    v = min(v, math.sqrt(machine.arc_normal_accel_fraction * plan_acc * r) / max(k, 1e-12))
    return length, v, a, tin, tout


def _block_table(moves, machine: Machine, start):
    """Per block (zero-length lines dropped): length L [mm], speed cap [mm/s], acceleration
    [mm/s^2], entry and exit unit tangents (arrays; lines vectorised, arcs one by one)."""
    moves = list(moves)
    if start is None:
        if not moves:
            return np.zeros(0), np.zeros(0), np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3))
        start, moves = moves[0].xyz, moves[1:]
    n = len(moves)
    P = np.empty((n + 1, 3))
    P[0] = np.asarray(start, float)
    if n:
        P[1:] = [mv.xyz for mv in moves]
    rate = np.asarray(machine.max_rate_mm_min) / 60.0
    acc = np.asarray(machine.accel_mm_s2)
    is_arc = np.array([mv.motion in ("G2", "G3") for mv in moves], bool)
    feed = np.array([math.inf if mv.motion == "G0" else float(mv.feed) / 60.0 for mv in moves], float)
    D = P[1:] - P[:-1]
    L = np.linalg.norm(D, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        U = D / np.where(L > 0, L, 1.0)[:, None]
    vmax = _axis_limits(rate, U)
    amax = _axis_limits(acc, U) * machine.line_accel_fraction
    t_in, t_out = U.copy(), U.copy()
    for k in np.flatnonzero(is_arc):
        L[k], vmax[k], amax[k], t_in[k], t_out[k] = _arc_row(P[k], moves[k], rate, acc, machine)
    vmax = np.minimum(vmax, feed)
    if machine.block_rate_hz is not None:
        vmax = np.minimum(vmax, L * machine.block_rate_hz)
    keep = is_arc | (L > 1e-9)
    return L[keep], vmax[keep], amax[keep], t_in[keep], t_out[keep]


def _junction_speeds(t_out_prev, t_in_next, machine: Machine) -> np.ndarray:
    """GRBL junction-deviation speed limit [mm/s] at each junction (arrays of unit vectors)."""
    acc = np.asarray(machine.accel_mm_s2)
    cos_theta = np.clip(-np.einsum("ij,ij->i", t_out_prev, t_in_next), -1.0, 1.0)  # reversed entry vs exit
    jv = t_in_next - t_out_prev
    nrm = np.linalg.norm(jv, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        a = np.where(nrm > 0, _axis_limits(acc, jv / np.where(nrm > 0, nrm, 1.0)[:, None]), acc.min())
        s = np.sqrt(0.5 * (1.0 - cos_theta))          # sin(theta / 2)
        out = np.sqrt(a * machine.junction_deviation_mm * s / (1.0 - s))
    out[cos_theta > 0.999999] = 0.0                   # full reversal: stop
    out[cos_theta < -0.999999] = math.inf             # straight on: no junction limit
    return out


def trapezoid_time(L: float, u: float, v: float, w: float, a: float) -> float:
    """Time [s] to travel ``L`` mm entering at ``u``, cruising at most at ``v`` and leaving at ``w``
    [mm/s] with acceleration ``a`` [mm/s^2] (trapezoid, or triangle when ``v`` is not reached).

    >>> trapezoid_time(100, 0, 100, 0, 100)       # triangle: peak 100 mm/s exactly at mid-length
    2.0
    >>> trapezoid_time(300, 0, 100, 0, 100)       # 1 s up (50 mm), 2 s at 100 mm/s, 1 s down
    4.0
    """
    if L <= 0:
        return 0.0
    d_acc = max(v * v - u * u, 0.0) / (2 * a)
    d_dec = max(v * v - w * w, 0.0) / (2 * a)
    if d_acc + d_dec <= L:
        return (v - u) / a + (v - w) / a + (L - d_acc - d_dec) / v
    vp = math.sqrt(max((2 * a * L + u * u + w * w) / 2.0, 0.0))
    return (vp - u) / a + (vp - w) / a


def machine_time(moves: Sequence[Move], machine: Machine = SMALL_VMC, start=None) -> dict:
    """Time [s] a machine needs for ``moves`` (see the module docstring), from rest to rest.

    ``start`` (x, y, z) mm is the position before the first move (without it the first move only
    positions, as :func:`cnclab.nc.gcode.program_time`). Returns ``{"time_machine_s", "blocks",
    "mean_speed_mm_s", "length_mm", "machine"}``.
    """
    L, vmax, amax, t_in, t_out = _block_table(list(moves), machine, start)
    n = len(L)
    if n == 0:
        return {"time_machine_s": 0.0, "blocks": 0, "mean_speed_mm_s": 0.0, "length_mm": 0.0, "machine": machine.name}
    e = np.zeros(n + 1)                       # e[i]: speed entering block i; e[n] = exit of the last
    cap = np.zeros(n + 1)
    if n > 1:
        vj = _junction_speeds(t_out[:-1], t_in[1:], machine)
        cap[1:n] = np.minimum(vj, np.minimum(vmax[:-1], vmax[1:]))
    e, cap, Ls, vs, As = e.tolist(), cap.tolist(), L.tolist(), vmax.tolist(), amax.tolist()
    for i in range(n - 1, 0, -1):             # backward: able to slow down to what follows
        e[i] = min(cap[i], math.sqrt(e[i + 1] ** 2 + 2 * As[i] * Ls[i]))
    for i in range(1, n):                     # forward: reachable from what precedes
        e[i] = min(e[i], math.sqrt(e[i - 1] ** 2 + 2 * As[i - 1] * Ls[i - 1]))
    t = math.fsum(trapezoid_time(Ls[i], e[i], vs[i], e[i + 1], As[i]) for i in range(n))
    return {"time_machine_s": float(t), "blocks": int(n), "mean_speed_mm_s": float(L.sum() / t) if t > 0 else 0.0,
            "length_mm": float(L.sum()), "machine": machine.name}


def path_machine_time(path: ToolPath, machine: Machine = SMALL_VMC) -> float:
    """Machine time [s] of a tool path as its blocks (:meth:`ToolPath.to_moves`: rapids G0 at the
    machine's axis rates, feed moves at their feed, arcs where the path has them), from its first
    point, rest to rest. A planner's polyline is timed as it is (not arc-fitted as the program
    writer would; see :mod:`cnclab.toolpath.evaluate`).

    >>> from cnclab.toolpath.path import ToolPath
    >>> p = ToolPath.build([[0, 0, 0], [100, 0, 0]], kind=["rapid", "cut"], feed=6000)
    >>> demo = Machine("demo", (6000, 6000, 6000), (100, 100, 100), 0.01)
    >>> round(path_machine_time(p, demo), 6)            # 1 s up to 100 mm/s, 1 s down
    2.0
    """
    return float(machine_time(path.to_moves(), machine)["time_machine_s"])
