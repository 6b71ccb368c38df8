"""Machine-safe NC programs: the one writer every output uses, and a static safety checker.

:func:`write_program` turns a :class:`~cnclab.toolpath.path.ToolPath` into RS274/NGC text:

* start block ``G21 G90 G17 G94 G40 G49 G80`` (mm, absolute, XY plane, feed per minute, no cutter
  or length compensation, no canned cycle), ``T.. M6`` when a tool is given, ``S.. M3`` before the
  first motion (so before the first cutting move), ``G0 Z<clearance>`` and a rapid over the first
  point at the clearance plane;
* every path move written as it is (G0 for rapids, G1/G2/G3 at its feed), so the program's time is
  the path's :meth:`~cnclab.toolpath.path.ToolPath.time_s`;
* rapids only at or above ``clearance_z``, or straight up (a retract), or where the path marks the
  move as inside cleared area (its ``cleared`` flag, the planner's proof; written as a ``(cleared)``
  comment on the block, as on any other move the path flags ``cleared``, e.g. a plunge into cleared
  area — the evaluator proves it; tags are free text and decide nothing); any other rapid below the
  clearance plane is refused
  (``ValueError`` naming the move index). The first point is reached from the clearance plane by
  a feed move when it lies below it (never a rapid onto the part);
* the end: a rapid straight up to ``clearance_z``, ``M5``, ``M30``.

:func:`check_program` reads a program (any post's) and checks: the spindle is on before the first
feed move, no G0 below the clearance plane (except straight up, or a block commented
``cleared``), every Z-descending feed move classified (helix / ramp / plunge; a plunge below the stock
top ``top_z`` is a plunge into material unless commented ``cleared``), and the program stops the
spindle (``M5``) and ends (``M30`` or ``M2``).

>>> from cnclab.toolpath.path import Tool, ToolPath
>>> p = ToolPath.build([[0, 0, 1], [0, 0, -1], [10, 0, -1]], kind=["rapid", "plunge", "cut"], feed=300)
>>> text = write_program(p, clearance_z=5, tool=Tool(6), spindle_rpm=6000)
>>> print(text)   # doctest: +NORMALIZE_WHITESPACE
%
(cnclab program: mm, clearance plane Z5 mm, stock top Z0 mm)
G21 G90 G17 G94 G40 G49 G80
T1 M6
S6000 M3
G0 X0.0000 Y0.0000 Z5.0000
G1 Z1.0000 F300.0
Z-1.0000
X10.0000
G0 Z5.0000
M5
M30
%
>>> check_program(text, clearance_z=5).errors
['<string>:8: word G1: plunge into material below the stock top Z0 (not marked cleared)']
"""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from ..fileio import atomic_write
from ..toolpath.path import Move, Tool, ToolPath
from .gcode import GcodeProgram, read_gcode, read_program_text, write_gcode

__all__ = ["write_program", "save_program", "check_program", "ProgramCheck", "START_BLOCK"]

START_BLOCK = "G21 G90 G17 G94 G40 G49 G80"
CLEARED = "cleared"
_TOL = 1e-6


def _param(job, name, value):
    if value is not None:
        return value
    return getattr(job, name, None) if job is not None else None


def write_program(path: ToolPath, job=None, *, clearance_z: float | None = None, tool: Tool | None = None,
                  spindle_rpm: float | None = None, top_z: float | None = None, header=(),
                  decimals: int = 4) -> str:
    """RS274/NGC text of ``path`` as a machine-safe program (see the module docstring).

    ``job`` (optional, a :class:`cnclab.toolpath.job.Job` or any object with ``clearance_z``,
    ``tool``, ``spindle_rpm``, ``top_z``) supplies defaults for the keyword parameters;
    ``clearance_z`` [mm] the clearance plane; ``tool`` (``T.. M6``; default ``path.tool``);
    ``spindle_rpm`` [rpm] (default: the path's first set spindle speed; required);
    ``top_z`` [mm] stock top (default 0; stated in the header); ``header`` extra comment lines;
    ``decimals`` digits of X Y Z I J.
    Raises ``ValueError`` naming the move index for a rapid below the clearance plane that the path
    does not mark as cleared, and for non-finite or out-of-range numbers (:func:`write_gcode`).
    """
    clearance_z = _param(job, "clearance_z", clearance_z)
    tool = _param(job, "tool", tool) or path.tool
    spindle_rpm = _param(job, "spindle_rpm", spindle_rpm)
    top_z = _param(job, "top_z", top_z)
    top_z = 0.0 if top_z is None else float(top_z)
    if clearance_z is None or not math.isfinite(clearance_z):
        raise ValueError(f"clearance_z must be a finite height in mm, got {clearance_z!r}")
    clearance_z = float(clearance_z)
    if not clearance_z > top_z:
        raise ValueError(f"clearance_z ({clearance_z} mm) must be above the stock top top_z ({top_z} mm)")
    if len(path) == 0:
        raise ValueError("path has no moves")
    if spindle_rpm is None:
        finite = path.spindle[np.isfinite(path.spindle)]
        spindle_rpm = float(finite[0]) if len(finite) else None
    if spindle_rpm is None or not (math.isfinite(spindle_rpm) and spindle_rpm > 0):
        raise ValueError(f"spindle_rpm must be a finite speed > 0 rpm (the program starts the spindle "
                         f"before cutting), got {spindle_rpm!r}")
    rapid = path.is_kind("rapid")
    xyz = path.xyz
    for k in np.flatnonzero(rapid)[np.flatnonzero(rapid) > 0]:
        a, b = xyz[k - 1], xyz[k]
        above = min(a[2], b[2]) >= clearance_z - _TOL
        straight_up = b[2] >= a[2] and math.hypot(*(b[:2] - a[:2])) <= _TOL
        if not (above or straight_up or path.cleared[k]):
            raise ValueError(f"move {k}: rapid from z {a[2]:g} to z {b[2]:g} mm below the clearance plane "
                             f"z {clearance_z:g} mm, not marked as inside cleared area (ToolPath.cleared)")
    # the moves the writer adds go to the clearance plane rounded *up* to the written precision
    cz = math.ceil(clearance_z * 10 ** decimals - 1e-6) / 10 ** decimals
    x0, y0, z0 = xyz[0]
    moves = [Move("G0", x0, y0, max(cz, z0), spindle=spindle_rpm)]
    comments = [""]
    first_feed = next((float(f) for f in path.feed if np.isfinite(f)), None)
    if z0 < clearance_z - _TOL:
        if path.kind[0] == 0 and path.cleared[0]:
            moves.append(Move("G0", x0, y0, z0, spindle=spindle_rpm)); comments.append(CLEARED)
        else:
            if first_feed is None:
                raise ValueError("move 0: the path starts below the clearance plane and has no feed move "
                                 "whose feed could take the tool down")
            feed0 = float(path.feed[0]) if np.isfinite(path.feed[0]) else first_feed
            moves.append(Move("G1", x0, y0, z0, feed=feed0, spindle=spindle_rpm)); comments.append("")
    for k, mv in enumerate(path.to_moves()):
        if k == 0:
            continue
        moves.append(dataclasses.replace(mv, spindle=spindle_rpm))
        comments.append(CLEARED if path.cleared[k] else "")
    xe, ye, ze = xyz[-1]
    if ze < clearance_z:
        moves.append(Move("G0", xe, ye, cz, spindle=spindle_rpm)); comments.append("")
    hdr = [f"cnclab program: mm, clearance plane Z{clearance_z:g} mm, stock top Z{top_z:g} mm"]
    hdr += [header] if isinstance(header, str) and header else list(header or [])
    start = [START_BLOCK]
    if tool is not None:
        start.append(f"T{int(tool.number)} M6")
    return write_gcode(moves, header=hdr, decimals=decimals, comments=comments, start_block=start,
                       end_block=["M30"])


def save_program(path: ToolPath, out, job=None, inputs=(), **kw) -> Path:
    """Write :func:`write_program` ``(path, job, **kw)`` to ``out`` atomically (never over ``inputs``)."""
    return atomic_write(out, write_program(path, job, **kw), inputs=inputs)


@dataclasses.dataclass
class ProgramCheck:
    """Result of :func:`check_program`: ``errors`` (each naming ``source:line`` and the word),
    ``entries`` (counts of entries by kind: helix, ramp, plunge -- an entry is a run of consecutive
    Z-descending feed blocks of one kind, as :class:`~cnclab.toolpath.evaluate.Evaluation` counts them), ``plunges_into_material``,
    ``rapids_below_clearance`` (unsafe G0 count), ``spindle_on_before_cut``, ``end_word``."""

    errors: list
    entries: dict
    plunges_into_material: int
    rapids_below_clearance: int
    spindle_on_before_cut: bool
    end_word: str | None

    @property
    def ok(self) -> bool:
        return not self.errors


def check_program(program, clearance_z: float, top_z: float = 0.0, source: str | None = None) -> ProgramCheck:
    """Static safety check of a program (text, a file path, or a :class:`GcodeProgram`); see the
    module docstring for the rules. ``clearance_z``/``top_z`` in mm."""
    if isinstance(program, GcodeProgram):
        prog = program
    else:
        if isinstance(program, Path) or (isinstance(program, str) and "\n" not in program):
            p = Path(program)
            prog = read_gcode(read_program_text(p), source=source or str(p))
        else:
            prog = read_gcode(program, source=source or "<string>")
    src = prog.source
    errors = []
    entries = {"helix": 0, "ramp": 0, "plunge": 0}
    plunges = rapids_bad = 0
    spindle_ok = True
    seen_feed = False
    prev_entry = None
    moves, lines, cmts = prog.moves, prog.lines, prog.comments
    if moves and moves[0].z < clearance_z - _TOL:
        errors.append(f"{src}:{lines[0]}: word {moves[0].motion}: the first move ends below the clearance "
                      f"plane Z{clearance_z:g} (start position unknown)")
    for k, mv in enumerate(moves):
        where = f"{src}:{lines[k]}"
        cleared = CLEARED in cmts[k]
        if mv.motion != "G0" and not seen_feed:
            seen_feed = True
            if mv.spindle is None:
                spindle_ok = False
                errors.append(f"{where}: word {mv.motion}: feed move before the spindle is started (M3/M4)")
        if k == 0:
            continue
        a = moves[k - 1].xyz
        b = mv.xyz
        if mv.motion == "G0":
            prev_entry = None
            above = min(a[2], b[2]) >= clearance_z - _TOL
            straight_up = b[2] >= a[2] and math.hypot(*(b[:2] - a[:2])) <= _TOL
            if not (above or straight_up or cleared):
                rapids_bad += 1
                errors.append(f"{where}: word G0: rapid below the clearance plane Z{clearance_z:g} "
                              f"(z {a[2]:g} -> {b[2]:g} mm) not marked cleared")
            continue
        if b[2] < a[2] - _TOL:
            kind = "helix" if mv.motion in ("G2", "G3") else (
                "plunge" if math.hypot(*(b[:2] - a[:2])) <= _TOL else "ramp")
            if kind != prev_entry:          # an entry is a run of descending blocks (a helix of n arcs: 1)
                entries[kind] += 1
            if kind == "plunge" and b[2] < top_z - _TOL and not cleared:
                plunges += 1
                errors.append(f"{where}: word {mv.motion}: plunge into material below the stock top "
                              f"Z{top_z:g} (not marked cleared)")
            prev_entry = kind
            continue
        prev_entry = None
    if prog.end_word is None:
        errors.append(f"{src}: no program end (M30 or M2)")
    if prog.spindle_stop_line is None or (lines and prog.spindle_stop_line < lines[-1]):
        errors.append(f"{src}: the spindle is not stopped (M5) after the last move")
    return ProgramCheck(errors, entries, plunges, rapids_bad, spindle_ok, prog.end_word)
