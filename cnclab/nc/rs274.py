"""LinuxCNC's ``rs274`` interpreter as a reference: run it, and read its canonical output.

``rs274 -g PROGRAM`` (Debian package ``linuxcnc-uspace``) interprets an RS274/NGC program the way the
LinuxCNC controller does and prints one *canonical machining command* per line::

    33 N..... STRAIGHT_TRAVERSE(0.0000, 0.0000, 5.0000, 0.0000, 0.0000, 0.0000)
    36 N..... SET_FEED_RATE(254.6000)
    39 N..... ARC_FEED(17.9970, 11.9940, 20.2370, 11.9940, -1, -0.6180, 0.0000, 0.0000, 0.0000)

:func:`parse_canonical` turns that text into totals — feed length and feed time (every
``STRAIGHT_FEED``/``ARC_FEED`` at the ``SET_FEED_RATE`` in force), rapid length
(``STRAIGHT_TRAVERSE``), counts, spindle and end events — independently of cnclab's own reader, so
the two can be compared (``make gcode-check``, and ``tests/test_rs274_fixtures.py`` on committed
canonical outputs without LinuxCNC installed). ``ARC_FEED(first_end, second_end, first_axis,
second_axis, rotation, axis_end_point, a, b, c[, u, v, w])`` in the XY plane: end (x, y), centre
(x, y), ``rotation`` > 0 counter-clockwise, ``|rotation| - 1`` extra full turns, end z. Lengths are
in the program's units (``USE_LENGTH_UNITS``); they are converted to mm. The interpreter starts at
the origin (0, 0, 0).

:func:`run_rs274` runs the interpreter (a tool table with tools 0..99 is passed with ``-t`` so that
``T.. M6`` blocks are accepted) and raises :class:`Rs274Error` with rs274's own message when it
refuses the program.
"""
from __future__ import annotations

import dataclasses
import math
import os
import re
import shutil
import signal
import subprocess
import tempfile
from pathlib import Path

from ..toolpath.path import arc_geometry

__all__ = ["Canonical", "Rs274Error", "parse_canonical", "run_rs274", "rs274_available", "tool_table"]

_LINE = re.compile(r"^\s*\d+\s+N\S*\s+([A-Z_0-9]+)\((.*)\)\s*$")
_MM_PER_INCH = 25.4


class Rs274Error(RuntimeError):
    """rs274 refused a program (its message included) or its output could not be read."""


@dataclasses.dataclass
class Canonical:
    """Totals of an rs274 canonical output (mm, s).

    ``feed_mm``/``feed_s``: straight and arc feeds (arcs and helices exact, at the feed rate in
    force); ``rapid_mm``: traverses; ``n_feed``, ``n_arc``, ``n_traverse``: command counts;
    ``spindle_on_before_feed``: a ``START_SPINDLE_*`` came before the first feed command;
    ``program_end``: ``PROGRAM_END`` seen; ``tool_changes``: tool numbers of ``CHANGE_TOOL``.
    """

    feed_mm: float = 0.0
    feed_s: float = 0.0
    rapid_mm: float = 0.0
    n_feed: int = 0
    n_arc: int = 0
    n_traverse: int = 0
    spindle_on_before_feed: bool = False
    program_end: bool = False
    tool_changes: list = dataclasses.field(default_factory=list)

    def rapid_s(self, rapid_mm_min: float) -> float:
        """Rapid time (s) at ``rapid_mm_min`` (mm/min)."""
        return 60.0 * self.rapid_mm / rapid_mm_min


def _floats(args: str, where: str, n_min: int) -> list[float]:
    try:
        vals = [float(a) for a in args.replace(" ", ",").split(",") if a.strip()]
    except ValueError:
        raise Rs274Error(f"{where}: cannot read the numbers of ({args})") from None
    if len(vals) < n_min:
        raise Rs274Error(f"{where}: expected at least {n_min} numbers, got ({args})")
    return vals


def parse_canonical(text: str, source: str = "<rs274>") -> Canonical:
    """Totals of ``rs274 -g`` canonical output ``text`` (see the module docstring).

    >>> out = '''1 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)
    ... 2 N..... STRAIGHT_TRAVERSE(0.0000, 0.0000, 5.0000, 0, 0, 0)
    ... 3 N..... SET_FEED_RATE(600.0000)
    ... 4 N..... STRAIGHT_FEED(10.0000, 0.0000, 5.0000, 0, 0, 0)
    ... 5 N..... ARC_FEED(0.0000, 0.0000, 5.0000, 0.0000, 1, 5.0000, 0, 0, 0)'''
    >>> c = parse_canonical(out)
    >>> c.rapid_mm, round(c.feed_mm, 6), round(c.feed_s, 6)
    (5.0, 25.707963, 2.570796)
    """
    out = Canonical()
    scale = 1.0
    x = y = z = 0.0
    feed = None
    spindle_on = False
    feed_seen = False
    for ln, raw in enumerate(text.splitlines(), start=1):
        m = _LINE.match(raw)
        if not m:
            continue
        cmd, args = m.group(1), m.group(2)
        where = f"{source}:{ln}"
        if cmd == "USE_LENGTH_UNITS":
            scale = _MM_PER_INCH if "INCH" in args else 1.0
        elif cmd == "SET_FEED_RATE":
            feed = _floats(args, where, 1)[0] * scale
        elif cmd.startswith("START_SPINDLE"):
            spindle_on = True
        elif cmd == "STOP_SPINDLE_TURNING":
            spindle_on = False
        elif cmd == "CHANGE_TOOL":
            out.tool_changes.append(int(_floats(args, where, 1)[0]))
        elif cmd == "PROGRAM_END":
            out.program_end = True
        elif cmd in ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED", "ARC_FEED"):
            v = [a * scale for a in _floats(args, where, 6)]
            if cmd == "ARC_FEED":
                ex, ey, cx, cy, rot, ez = v[0], v[1], v[2], v[3], v[4] / scale, v[5]
                turns = int(round(abs(rot)))
                if turns < 1:
                    raise Rs274Error(f"{where}: ARC_FEED rotation must be a non-zero integer, got {rot:g}")
                _, _, r, _, sweep = arc_geometry((x, y), (ex, ey), (cx, cy), rot > 0)
                if math.hypot(ex - x, ey - y) < 1e-9:
                    sweep = math.copysign(2 * math.pi, rot)  # full circle
                sweep = abs(sweep) + 2 * math.pi * (turns - 1)
                length = math.hypot(sweep * r, ez - z)
                x, y, z = ex, ey, ez
                out.n_arc += 1
            else:
                length = math.dist((x, y, z), v[:3])
                x, y, z = v[:3]
            if cmd == "STRAIGHT_TRAVERSE":
                out.rapid_mm += length
                out.n_traverse += 1
                continue
            if not feed_seen:
                out.spindle_on_before_feed, feed_seen = spindle_on, True
            if cmd == "STRAIGHT_FEED":
                out.n_feed += 1
            if length > 0:
                if not feed:
                    raise Rs274Error(f"{where}: {cmd} with no feed rate set")
                out.feed_mm += length
                out.feed_s += 60.0 * length / feed
    return out


def rs274_available() -> bool:
    """True when LinuxCNC's ``rs274`` is on the PATH."""
    return shutil.which("rs274") is not None


def tool_table(diameter_mm: float = 6.0, n_tools: int = 100) -> str:
    """A LinuxCNC tool table (``T P D Z`` lines) with tools 0..n_tools-1 of ``diameter_mm``, zero
    length offset, so that any ``T.. M6`` / ``G43 H..`` block is accepted."""
    return "".join(f"T{k} P{k} D{diameter_mm:g} Z0 ;cnclab\n" for k in range(n_tools))


def run_rs274(program, timeout_s: float = 120.0) -> str:
    """Canonical output of ``rs274 -t TABLE -g PROGRAM`` (text). Raises :class:`Rs274Error` with
    rs274's message when it refuses the program, ``OSError`` when rs274 is not installed."""
    exe = shutil.which("rs274")
    if exe is None:
        raise OSError("rs274 (LinuxCNC, Debian package linuxcnc-uspace) is not installed")
    program = Path(program)
    if not program.is_file():
        raise OSError(f"{program}: no such program file")
    with tempfile.TemporaryDirectory() as tmp:
        tbl = Path(tmp) / "tools.tbl"
        tbl.write_text(tool_table())
        # rs274 keeps its tool data in $HOME/.tool.mmap, opened with O_TRUNC and mapped shared: two
        # runs with one HOME truncate each other's map and one dies of SIGBUS (seen with 2 xdist
        # workers). Each run gets its own HOME, the temporary directory it runs in.
        env = {**os.environ, "HOME": tmp}
        proc = subprocess.run([exe, "-t", str(tbl), "-g", str(program.resolve())], capture_output=True,
                              text=True, timeout=timeout_s, cwd=tmp, env=env)
    if proc.returncode < 0:
        try:
            name = signal.Signals(-proc.returncode).name
        except ValueError:                       # a real-time signal has no name in the enum
            name = "no name"
        raise OSError(f"{program}: rs274 was killed by signal {-proc.returncode} ({name}); that is a crash, "
                      "not a verdict on the program")
    if proc.returncode != 0:
        msg = " | ".join(s.strip() for s in proc.stderr.splitlines() if s.strip() and s.strip() != "executing")
        raise Rs274Error(f"{program}: rs274 refused the program (exit {proc.returncode}): {msg}")
    return proc.stdout
