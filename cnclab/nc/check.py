"""The static safety check of NC programs (:func:`check_program`; :mod:`cnclab.nc.program` re-exports
it): the spindle is on before the first feed move, no G0 below the clearance plane (except straight up or
a move the writer marked cleared), no plunge below the stock top unless marked cleared, a program end
and a spindle stop after the last move; and the entries counted by kind. Lengths mm."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

from ..toolpath.path import ToolPath
from .gcode import GcodeProgram, read_gcode, read_program_text

__all__ = ["check_program", "ProgramCheck", "CLEARED_MARK", "cleared_mark"]

#: the structured marker (versioned) the writer puts on a block whose move the path flags ``cleared``
#: (:attr:`ToolPath.cleared`, the planner's proof); read back only by :func:`cleared_mark`
CLEARED_MARK = "cnclab:cleared/1"
_TOL = 1e-6


@dataclasses.dataclass
class ProgramCheck:
    """Result of :func:`check_program`: ``errors`` (each naming ``source:line`` and the word),
    ``entries`` (counts of entries by kind: helix, ramp, plunge -- an entry is a run of consecutive
    Z-descending feed blocks: vertical ones (plunges) a run of their own, arcs and lines with xy motion
    one run counted as the kind that descends most in it, :class:`_EntryRun`), ``plunges_into_material``,
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


def cleared_mark(comment: str) -> bool:
    """Whether a block's comment (as :attr:`GcodeProgram.comments` holds it) is the writer's marker
    :data:`CLEARED_MARK` — exactly (surrounding blanks aside), the one parser of it: any other text,
    ``(cleared)`` or a marker of another version included, grants nothing.

    >>> cleared_mark("cnclab:cleared/1"), cleared_mark("cleared"), cleared_mark("not cnclab:cleared/1")
    (True, False, False)
    """
    return comment.strip() == CLEARED_MARK


def check_program(program, clearance_z: float, top_z: float = 0.0, source: str | None = None) -> ProgramCheck:
    """Static safety check of a program (text, a file path, or a :class:`GcodeProgram`) or of a
    :class:`ToolPath` (its moves and its ``cleared`` column; no program end to check); see the module
    docstring for the rules. ``clearance_z``/``top_z`` in mm."""
    if isinstance(program, ToolPath):
        moves = program.to_moves()
        return _check_moves(moves, list(range(len(moves))), program.cleared, source or "<path>", clearance_z,
                            top_z, None)
    if isinstance(program, GcodeProgram):
        prog = program
    else:
        if isinstance(program, Path) or (isinstance(program, str) and "\n" not in program):
            p = Path(program)
            prog = read_gcode(read_program_text(p), source=source or str(p))
        else:
            prog = read_gcode(program, source=source or "<string>")
    return _check_moves(prog.moves, prog.lines, [cleared_mark(c) for c in prog.comments], prog.source,
                        clearance_z, top_z, prog)


class _EntryRun:
    """One run of descending feed blocks (an entry) of :func:`_check_moves`: the z it descends by kind
    (helix: G2/G3, ramp: G1 with xy motion, plunge: vertical G1); counted once, as its deepest kind."""

    def __init__(self):
        self.drop = {}

    @property
    def kind(self):
        return max(self.drop, key=self.drop.get)

    def add(self, kind, dz):
        self.drop[kind] = self.drop.get(kind, 0.0) + dz


def _check_moves(moves, lines, cleared, src, clearance_z, top_z, prog) -> ProgramCheck:
    """The rules of :func:`check_program` over ``moves`` (``cleared``: per move, the data that marks
    it cleared); ``prog``: the program whose end and spindle stop are checked too (None: a path)."""
    errors = []
    entries = {"helix": 0, "ramp": 0, "plunge": 0}
    plunges = rapids_bad = 0
    spindle_ok = True
    seen_feed = False
    runs, prev_entry = [], None      # the entries, and the one the last move belongs to (None: none)
    if moves and moves[0].z < clearance_z - _TOL:
        errors.append(f"{src}:{lines[0]}: word {moves[0].motion}: the first move ends below the clearance "
                      f"plane Z{clearance_z:g} (start position unknown)")
    for k, mv in enumerate(moves):
        where = f"{src}:{lines[k]}"
        ok_cleared = bool(cleared[k])
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
            if not (above or straight_up or ok_cleared):
                rapids_bad += 1
                errors.append(f"{where}: word G0: rapid below the clearance plane Z{clearance_z:g} "
                              f"(z {a[2]:g} -> {b[2]:g} mm) not marked cleared")
            continue
        if b[2] < a[2] - _TOL:
            kind = "helix" if mv.motion in ("G2", "G3") else (
                "plunge" if math.hypot(*(b[:2] - a[:2])) <= _TOL else "ramp")
            # an entry is a run of descending blocks (a helix of n arcs: 1); a descent whose blocks
            # alternate between arcs and lines (a ramp along a curve the arc fit took in pieces) is
            # one entry too, of the kind that descends the most in it (_EntryRun)
            if prev_entry is None or (kind == "plunge") != (prev_entry.kind == "plunge"):
                prev_entry = _EntryRun()
                runs.append(prev_entry)
            prev_entry.add(kind, a[2] - b[2])
            if kind == "plunge" and b[2] < top_z - _TOL and not ok_cleared:
                plunges += 1
                errors.append(f"{where}: word {mv.motion}: plunge into material below the stock top "
                              f"Z{top_z:g} (not marked cleared)")
            continue
        prev_entry = None
    for run in runs:
        entries[run.kind] += 1
    if prog is None:
        return ProgramCheck(errors, entries, plunges, rapids_bad, spindle_ok, None)
    if prog.end_word is None:
        errors.append(f"{src}: no program end (M30 or M2)")
    if prog.spindle_stop_line is None or (lines and prog.spindle_stop_line < lines[-1]):
        errors.append(f"{src}: the spindle is not stopped (M5) after the last move")
    return ProgramCheck(errors, entries, plunges, rapids_bad, spindle_ok, prog.end_word)


