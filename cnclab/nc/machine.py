"""Machine time of a program: the G-code-facing face of :mod:`cnclab.toolpath.motion`.

The machine model (per-axis maximum rate and acceleration, junction deviation / ``G64 P``
blending tolerance, LinuxCNC's acceleration fractions, an optional block-rate limit) and the
forward/backward look-ahead live in :mod:`cnclab.toolpath.motion` (the toolpath layer, so that the
evaluator reports ``time_machine_s`` for any tool path); this module re-exports them for programs
and adds the default machine of a program dialect.

>>> from cnclab.nc.gcode import parse_gcode
>>> moves = parse_gcode("G21 G90\\nG1 X100 F6000\\n", start=(0, 0, 0))
>>> m = Machine("demo", (6000, 6000, 6000), (100, 100, 100), 0.01)
>>> round(machine_time(moves, m, start=(0, 0, 0))["time_machine_s"], 6)
2.0
"""
from __future__ import annotations

from ..toolpath.motion import (GRBL_ROUTER, LINUXCNC_29_FRACTIONS, MACHINES, SMALL_VMC, Machine, machine_time,
                               path_machine_time, trapezoid_time)

__all__ = ["Machine", "LINUXCNC_29_FRACTIONS", "SMALL_VMC", "GRBL_ROUTER", "MACHINES", "machine_for_dialect",
           "machine_time", "path_machine_time", "trapezoid_time"]


def machine_for_dialect(dialect: str) -> Machine:
    """The default machine of a program dialect: linuxcnc -> :data:`SMALL_VMC`, grbl -> :data:`GRBL_ROUTER`.

    >>> machine_for_dialect("grbl").name
    'GRBL router'
    """
    return {"linuxcnc": SMALL_VMC, "grbl": GRBL_ROUTER}[dialect]
