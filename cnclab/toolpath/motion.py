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
``benchmarks/linuxcnc_tp.py``; fixture ``tests/fixtures/linuxcnc/tp_times.json``): within 3 % on a
line, a corner, a small full circle, a 360-gon and two bench pocket programs
(``tests/test_machine_linuxcnc.py``); LinuxCNC's blend arcs (a ``G64 P`` tolerance) are modelled by
the junction-deviation corner speed, the main source of the difference.

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
    u = np.abs(np.asarray(u, float))
    m = u > 1e-12
    return float(np.min(np.asarray(limits)[m] / u[m])) if m.any() else math.inf


def _block_table(moves, machine: Machine, start):
    """Per block (zero-length moves dropped): length L [mm], speed cap [mm/s], acceleration
    [mm/s^2], entry and exit unit tangents."""
    cur = None if start is None else np.asarray(start, float)
    rate = np.asarray(machine.max_rate_mm_min) / 60.0
    acc = np.asarray(machine.accel_mm_s2)
    L, vmax, amax, t_in, t_out = [], [], [], [], []
    for mv in moves:
        end = mv.xyz
        if cur is None:
            cur = end
            continue
        d = end - cur
        if mv.motion in ("G2", "G3"):
            cx, cy, r, a0, sweep = arc_geometry(cur, end, (cur[0] + mv.i, cur[1] + mv.j), mv.motion == "G3")
            arc_len = abs(sweep) * r
            length = math.hypot(arc_len, d[2])
            s = 1.0 if sweep > 0 else -1.0
            tz = d[2] / length if length > 0 else 0.0
            k = arc_len / length if length > 0 else 0.0
            a1 = a0 + sweep
            tin = np.array([-s * math.sin(a0) * k, s * math.cos(a0) * k, tz])
            tout = np.array([-s * math.sin(a1) * k, s * math.cos(a1) * k, tz])
            plan_rate, plan_acc = min(rate[0], rate[1]), min(acc[0], acc[1])
            v = min(plan_rate / max(k, 1e-12), rate[2] / abs(tz) if abs(tz) > 1e-12 else math.inf)
            a = min(plan_acc / max(k, 1e-12), acc[2] / abs(tz) if abs(tz) > 1e-12 else math.inf)
            a *= machine.arc_tangential_accel_fraction
            # centripetal limit (on the xy projection)
            v = min(v, math.sqrt(machine.arc_normal_accel_fraction * plan_acc * r) / max(k, 1e-12))
        else:
            length = float(np.linalg.norm(d))
            if length <= 1e-9:
                cur = end
                continue
            u = d / length
            tin = tout = u
            v, a = _axis_limit(rate, u), _axis_limit(acc, u) * machine.line_accel_fraction
        if mv.motion != "G0":
            v = min(v, float(mv.feed) / 60.0)
        if machine.block_rate_hz is not None:
            v = min(v, length * machine.block_rate_hz)
        L.append(length); vmax.append(v); amax.append(a); t_in.append(tin); t_out.append(tout)
        cur = end
    return (np.asarray(L), np.asarray(vmax), np.asarray(amax), np.asarray(t_in).reshape(-1, 3),
            np.asarray(t_out).reshape(-1, 3))


def _junction_speeds(t_out_prev, t_in_next, machine: Machine) -> np.ndarray:
    """GRBL junction-deviation speed limit [mm/s] at each junction (arrays of unit vectors)."""
    acc = np.asarray(machine.accel_mm_s2)
    cos_theta = -np.einsum("ij,ij->i", t_out_prev, t_in_next)       # theta: reversed entry vs exit
    cos_theta = np.clip(cos_theta, -1.0, 1.0)
    out = np.empty(len(cos_theta))
    for k, c in enumerate(cos_theta):
        if c > 0.999999:                     # full reversal: stop
            out[k] = 0.0
            continue
        if c < -0.999999:                    # straight on: no junction limit
            out[k] = math.inf
            continue
        jv = t_in_next[k] - t_out_prev[k]
        n = np.linalg.norm(jv)
        a = _axis_limit(acc, jv / n) if n > 0 else float(acc.min())
        s = math.sqrt(0.5 * (1.0 - c))        # sin(theta / 2)
        out[k] = math.sqrt(a * machine.junction_deviation_mm * s / (1.0 - s))
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
    for i in range(n - 1, 0, -1):             # backward: able to slow down to what follows
        e[i] = min(cap[i], math.sqrt(e[i + 1] ** 2 + 2 * amax[i] * L[i]))
    for i in range(1, n):                     # forward: reachable from what precedes
        e[i] = min(e[i], math.sqrt(e[i - 1] ** 2 + 2 * amax[i - 1] * L[i - 1]))
    t = sum(trapezoid_time(L[i], e[i], vmax[i], e[i + 1], amax[i]) for i in range(n))
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
