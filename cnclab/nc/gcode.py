"""RS274/NGC (G-code) reader for 3-axis milling programs, and the program model the writer uses.

A program is a list of :class:`Move` records. Conventions (fixed, stated in every written file):

* ``G21`` millimetres, ``G90`` absolute coordinates, ``G17`` XY arc plane, ``G94`` feed per minute.
* Each :class:`Move` holds the **absolute end point** ``x, y, z`` [mm] of the motion, the motion word
  ``"G0"`` (rapid), ``"G1"`` (linear feed), ``"G2"`` (clockwise arc) or ``"G3"`` (counter-clockwise
  arc, seen from +Z), arc-centre offsets ``i, j`` [mm] *relative to the start point* (the RS274
  default incremental IJ) for arcs, the feed ``feed`` [mm/min] (``None`` for ``G0``) and the spindle
  speed ``spindle`` [rpm] (``None`` = spindle off / not set). A ``G2``/``G3`` move with a Z change is
  a helix.

Writer — none here: every program text is written by :mod:`cnclab.nc.program`
(:func:`~cnclab.nc.program.write_program` for a planned :class:`ToolPath`,
:func:`~cnclab.nc.program.write_moves` / :func:`~cnclab.nc.program.write_linear_moves` for a motion
program given move by move, e.g. the spindle post-processor's); :data:`MAX_COORD_MM`,
:data:`MAX_FEED_MM_MIN` and :data:`MAX_SPINDLE_RPM` bound the numbers it writes.

Reader — :func:`read_gcode` (:class:`GcodeProgram`), :func:`parse_gcode` (its moves),
:func:`load_gcode` (a file), :func:`read_toolpath` (a :class:`ToolPath`). It reads the RS274/NGC
subset real post-processors (FreeCAD's LinuxCNC and GRBL posts) and hand-written programs use:

* ``N`` words, ``( )`` and ``;`` comments, ``%`` lines, upper/lower case, ``G00``/``G01`` forms;
* ``G0 G1 G2 G3`` (motion modal; ``G80`` cancels it), F and S modal, helical arcs (an arc with a Z
  change), arc centres ``I J`` (incremental, ``G91.1``, the default; absolute with ``G90.1``) or a
  signed radius ``R`` (R > 0 the arc of at most 180°, R < 0 the larger one);
* ``G90``/``G91`` absolute/incremental X Y Z; ``G20`` inches, **converted to mm** (every length and
  F × 25.4; :attr:`GcodeProgram.converted_from_inch` and a warning say so), ``G21`` mm;
* accepted with no effect on the tool-centre path: ``G17 G40 G43 (H) G49 G54–G59(.3) G61 G61.1 G64
  (P Q) G80 G94``, ``T``, ``M6`` (tool number recorded), ``M0 M1 M7 M8 M9``; ``M3/M4`` spindle on,
  ``M5`` off, ``M2/M30`` end (lines after them are not executed, as in LinuxCNC);
* refused with a :class:`GcodeError` (a ``ValueError``) naming ``source:line`` and the word: G18/G19
  (other arc planes, and K), canned cycles (G73 G76 G81–G89) and G98/G99, G4 dwell, G28/G30/G53/G92,
  cutter compensation G41/G42 (and D), G93/G95 feed modes, parameters/expressions/O-words, an unknown
  word, an arc without I/J/R, an arc whose start and end radius disagree, a feed move with no feed
  set, or a feed move from a position not fully known.

:func:`program_time` is the motion time of a program (feed moves at F, rapids at a stated rate, arcs
and helices exact) — the same model as :meth:`ToolPath.time_s` and rs274's canonical totals
(:mod:`cnclab.nc.rs274`).

Round trip: ``write_moves(parse_gcode(write_moves(m)))`` equals ``write_moves(m)`` exactly.

Helpers: :func:`sample_move` (a move → points; arcs by :func:`cnclab.toolpath.path.sample_arc`),
:func:`to_polyline` (a whole program → points with a rapid/feed flag), :func:`path_lengths` (feed vs
rapid length, arcs exact), :func:`linear_moves` (polyline → ``G1`` moves).

>>> moves = [Move("G0", 0, 0, 10), Move("G1", 0, 0, 0, feed=500, spindle=2000),
...          Move("G1", 10, 0, 0, feed=500, spindle=2000),
...          Move("G3", 10, 10, 0, i=0, j=5, feed=500, spindle=2000)]
>>> from cnclab.nc.program import write_moves
>>> text = write_moves(moves, header="demo", decimals=3)
>>> print(text)   # doctest: +NORMALIZE_WHITESPACE
%
(demo)
G21 G90 G17 G94
G0 X0.000 Y0.000 Z10.000
S2000 M3
G1 Z0.000 F500.0
X10.000
G3 Y10.000 I0.000 J5.000
M5
M30
%
>>> parse_gcode(text)[3]
Move(motion='G3', x=10.0, y=10.0, z=0.0, i=0.0, j=5.0, feed=500.0, spindle=2000.0)
>>> write_moves(parse_gcode(text), header="demo", decimals=3) == text
True
"""
from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path
from typing import Sequence

import numpy as np

from ..toolpath.path import Move, Tool, ToolPath, arc_geometry, sample_arc

__all__ = ["Move", "GcodeError", "GcodeProgram", "read_gcode", "parse_gcode",
           "load_gcode", "read_program_text", "read_toolpath", "program_time", "sample_move", "to_polyline", "path_lengths",
           "linear_moves", "MM_PER_INCH",
           "MAX_COORD_MM", "MAX_FEED_MM_MIN", "MAX_SPINDLE_RPM"]

class GcodeError(ValueError):
    """Malformed G-code; the message starts with ``source:line``."""


#: bounds of written numbers: coordinates [mm], feeds [mm/min], spindle speeds [rpm]. A value beyond
#: them is a unit or planning error (no 3-axis mill travels 10 m or feeds at 1 km/min).
MAX_COORD_MM = 1.0e4
MAX_FEED_MM_MIN = 1.0e6
MAX_SPINDLE_RPM = 1.0e6


# --------------------------------------------------------------------------------------------
# reader
# --------------------------------------------------------------------------------------------
_WORD = re.compile(r"([A-Za-z])\s*([+-]?\s*(?:\d+\.?\d*|\.\d+))", re.ASCII)  # ASCII digits only (RS274)
MM_PER_INCH = 25.4
#: G words accepted with no effect on the tool-centre path (cutter compensation off, tool length
#: offset on/off — coordinates are the controlled point either way —, work offsets G54..G59.3 taken
#: as identity, canned cycle cancel, absolute/incremental arc centres handled, feed per minute, path
#: blending modes)
_NOOP_G = {"17", "21", "40", "43", "49", "54", "55", "56", "57", "58", "59", "59.1", "59.2", "59.3",
           "80", "94", "61", "61.1", "64"}
_REFUSED_G = {
    "4": "dwell G4 is not supported (program time would miss the pause)",
    "18": "arc plane G18 (XZ) is not supported; only G17 (XY)",
    "19": "arc plane G19 (YZ) is not supported; only G17 (XY)",
    "28": "G28 (go to reference point) is not supported: the position after it is machine-specific",
    "30": "G30 (go to reference point) is not supported: the position after it is machine-specific",
    "53": "G53 (machine coordinates) is not supported",
    "92": "G92 (coordinate system offset) is not supported",
    "41": "cutter radius compensation G41 is not supported (the path would not be the tool centre)",
    "42": "cutter radius compensation G42 is not supported (the path would not be the tool centre)",
    "93": "inverse-time feed G93 is not supported; use G94 (mm/min)",
    "95": "feed per revolution G95 is not supported; use G94 (mm/min)",
    "98": "canned-cycle return mode G98 is not supported (canned cycles are not read)",
    "99": "canned-cycle return mode G99 is not supported (canned cycles are not read)",
}
_CANNED = {"73", "76", "81", "82", "83", "84", "85", "86", "87", "88", "89"}
_NOOP_M = {"0", "1", "6", "7", "8", "9"}


@dataclasses.dataclass
class GcodeProgram:
    """A program read by :func:`read_gcode`.

    ``moves`` (absolute mm, :class:`Move`); ``lines`` the source line of each move (1-based);
    ``comments`` the comment text on each move's line ('' if none); ``converted_from_inch``: the file
    used ``G20`` and every length (X Y Z I J R, F) was multiplied by 25.4; ``warnings`` human-readable
    notes (unit conversion, skipped partial positioning...); ``tool_number`` the T word of the last
    ``M6`` (None if no tool change); ``tool_diameter`` [mm] from a comment such as ``(T1 D=6.0)`` or
    ``(tool diameter 6 mm)`` when one is present; ``spindle_on_line`` line of the first M3/M4;
    ``spindle_stop_line`` line of the last M5; ``end_word`` ``"M30"``/``"M2"`` or None; ``end_line``;
    ``source`` the name used in messages; ``tool_diameter_line`` the line of the diameter comment;
    ``first_line`` the first non-blank line; ``opening_percent`` / ``closing_percent_line`` the ``%``
    demarcation; ``program_number`` of a bare O-word line (``O1001``).
    """

    moves: list
    lines: list
    comments: list
    source: str = "<string>"
    converted_from_inch: bool = False
    warnings: list = dataclasses.field(default_factory=list)
    tool_number: int | None = None
    tool_diameter: float | None = None
    spindle_on_line: int | None = None
    spindle_stop_line: int | None = None
    end_word: str | None = None
    end_line: int | None = None
    tool_diameter_line: int | None = None
    first_line: int | None = None
    opening_percent: bool = False
    closing_percent_line: int | None = None
    program_number: str | None = None


def _split_comments(line: str, where: str):
    if "(" not in line and ";" not in line:
        return line, []                   # most blocks: no comment (a stray ')' is a word error later)
    out, comments, buf, depth = [], [], [], 0
    for k, ch in enumerate(line):
        if ch == "(":
            if depth:
                raise GcodeError(f"{where}: nested comment '(' (RS274 comments do not nest)")
            depth, buf = 1, []
        elif ch == ")" and depth:
            depth = 0
            comments.append("".join(buf).strip())
        elif depth:
            buf.append(ch)
        elif ch == ";":
            comments.append(line[k + 1:].strip())
            break
        else:
            out.append(ch)
    if depth:
        raise GcodeError(f"{where}: comment '(' is not closed on this line")
    return "".join(out), comments


_TOOL_DIA = re.compile(r"(?:\bD\s*=?\s*|diam(?:eter)?\s*[=:]?\s*)([0-9]*\.?[0-9]+)\s*(mm|in\b|inch|\")?", re.I)


def _gnum(num: str) -> str:
    """Canonical form of a G/M number: '01' -> '1', '90.10' -> '90.1'."""
    v = float(num)
    return str(int(v)) if v == int(v) else f"{v:g}"


def read_gcode(text: str, source: str = "<string>", arc_tolerance: float = 0.002,
               start=None) -> GcodeProgram:
    """Read RS274/NGC text (the subset real posts write, see the module docstring) into a
    :class:`GcodeProgram` of absolute-mm :class:`Move` records.

    ``source`` names the text in errors (``source:line: word ...``); ``arc_tolerance`` [mm] is the
    largest accepted difference between an arc's start and end radius (default 0.002 mm: a program
    written with 3 decimals rounds each of I, J, X, Y by up to 0.0005 mm, so the two radii can differ
    by up to 2·√2·0.0005 ≈ 0.0014 mm; arcs are also accepted within 0.1 % of their radius).
    ``start`` (x, y, z) mm: the position before the program (rs274 starts at the origin); without it,
    G0 moves before every axis is known only set the known axes (a ``G0 Z5`` first line), and a feed
    move before that is an error.

    >>> p = read_gcode("G20 G90\\nG0 X0 Y0 Z1\\nG1 Z0 F10\\nM30\\n", source="t.ngc")
    >>> p.moves[-1].z, p.moves[-1].feed, p.converted_from_inch
    (0.0, 254.0, True)
    """
    moves, lines, comments = [], [], []
    prog = GcodeProgram(moves, lines, comments, source=source)
    st = _ReaderState({"X": None, "Y": None, "Z": None} if start is None else dict(zip("XYZ", map(float, start))))
    raw_lines = _LINE_END.split(text)
    for ln, raw in enumerate(raw_lines, start=1):
        if prog.end_word is not None or prog.closing_percent_line is not None:
            break  # M2/M30 or the closing % ends the program; later lines are not executed (as in LinuxCNC)
        where = f"{source}:{ln}"
        body, cmts = _block_body(raw, where, ln, prog, st.scale)
        if body is None:
            continue
        if prog.moves and _M6.search(body.upper().replace(" ", "")):
            prog.warnings.append(f"{where}: tool change {body.strip()!r} after the program has moved: "
                                 "the moves after it are taken with the same tool as before")
        words = [(a.upper(), b.replace(" ", "")) for a, b in _WORD.findall(body)]
        coords, new_motion = _block_words(words, st, prog, where, ln)
        if prog.end_word is not None and prog.end_line == ln and any(a in coords for a in "XYZ"):
            raise GcodeError(f"{where}: word {prog.end_word}: motion in the program-end block")
        if new_motion is not None:
            st.motion = new_motion
        motion, pos = st.motion, st.pos
        has_xyz = any(a in coords for a in "XYZ")
        if not has_xyz and not any(a in coords for a in "IJR"):
            if new_motion in ("G2", "G3"):
                raise GcodeError(f"{where}: word {new_motion}: arc without an end point")
            continue
        if motion is None:
            w = next(a for a in "XYZIJR" if a in coords)
            raise GcodeError(f"{where}: word {w}: coordinates given with no motion mode (G0/G1/G2/G3) "
                             "in force")
        startp = _move_end(coords, st, where)
        unknown = [a for a in "XYZ" if pos[a] is None]
        if unknown:
            if motion == "G0" and not any(a in coords for a in "IJR"):
                st.skipped_partial += 1
                continue
            raise GcodeError(f"{where}: word {motion}: position of {'/'.join(unknown)} is unknown "
                             "(state every axis on the first move)")
        if any(startp[a] is None for a in "XYZ"):
            startp = None  # the first fully known position: the start of the path
        i, j = _arc_offsets(motion, coords, startp, st, arc_tolerance, where)
        if motion != "G0" and st.feed is None:
            raise GcodeError(f"{where}: word {motion}: {motion} feed move with no feed F set")
        moves.append(Move(motion, pos["X"], pos["Y"], pos["Z"], i=i, j=j,
                          feed=st.feed if motion != "G0" else None,
                          spindle=st.spindle if st.spindle_on else None))
        lines.append(ln)
        comments.append(" ".join(cmts))
    if st.skipped_partial:
        prog.warnings.append(f"{source}: {st.skipped_partial} rapid(s) before X, Y and Z were all known "
                             "(start position unknown) were not turned into moves")
    _check_end(prog, raw_lines, text)
    return prog


@dataclasses.dataclass
class _ReaderState:
    """The modal state of :func:`read_gcode` between blocks: ``pos`` (mm, None = unknown axis),
    motion mode, feed (mm/min), spindle (rpm) and on/off, length scale (1 or 25.4), G90/G91,
    G90.1/G91.1, the selected T, and the count of skipped partial rapids."""

    pos: dict
    motion: str | None = None
    feed: float | None = None
    spindle: float | None = None
    spindle_on: bool = False
    scale: float = 1.0
    absolute: bool = True
    arc_absolute: bool = False
    selected_tool: int | None = None
    skipped_partial: int = 0


def _block_words(words, st: _ReaderState, prog: GcodeProgram, where: str, ln: int):
    """Apply the words of one block to ``st`` / ``prog``; return ``(coords, new_motion)``: the
    X Y Z I J R values (mm, scaled, as written) and the block's motion word (or None)."""
    coords: dict[str, float] = {}
    new_motion = None
    gset = set()
    for letter, num in words:  # T is selected before M6 acts, wherever it stands in the block
        if letter == "T":
            st.selected_tool = int(float(num))
    for letter, num in words:
        if letter == "G":
            code = _gnum(num)
            gset.add(code)
            if code in ("0", "1", "2", "3"):
                if new_motion is not None:
                    raise GcodeError(f"{where}: word G{num}: two motion words in one block")
                new_motion = "G" + code
            else:
                _g_word(code, num, st, prog, where)
        elif letter == "M":
            _m_word(_gnum(num), num, st, prog, where, ln)
        elif letter in "XYZIJR":
            if letter in coords:
                raise GcodeError(f"{where}: word {letter}{num} given twice")
            coords[letter] = float(num) * st.scale
        elif letter == "K":
            raise GcodeError(f"{where}: word K{num}: K belongs to arcs in G18/G19 planes; only G17 (XY) is read")
        elif letter == "F":
            if not float(num) > 0:
                raise GcodeError(f"{where}: word F{num}: feed must be > 0 mm/min")
            st.feed = float(num) * st.scale
        elif letter == "S":
            if float(num) < 0:
                raise GcodeError(f"{where}: word S{num}: spindle speed must be >= 0 rpm")
            st.spindle = float(num)
        elif letter == "T":
            pass
        elif letter in "NHPDQ":
            if letter in "PQ" and "64" not in gset:
                raise GcodeError(f"{where}: word {letter}{num} only accepted with G64")
            if letter == "D":
                raise GcodeError(f"{where}: word D{num}: cutter compensation is not supported")
        else:
            raise GcodeError(f"{where}: unknown word {letter}{num}")
    return coords, new_motion


def _g_word(code: str, num: str, st: _ReaderState, prog: GcodeProgram, where: str) -> None:
    """A non-motion G word (canonical ``code``, as written ``num``): modal state or a refusal."""
    if code == "20":
        st.scale = MM_PER_INCH
        if not prog.converted_from_inch:
            prog.converted_from_inch = True
            prog.warnings.append(f"{where}: G20 (inches): every length and feed converted "
                                 "to mm (x 25.4)")
    elif code == "21":
        st.scale = 1.0
    elif code == "90":
        st.absolute = True
    elif code == "91":
        st.absolute = False
    elif code == "90.1":
        st.arc_absolute = True
    elif code == "91.1":
        st.arc_absolute = False
    elif code == "80":
        st.motion = None
    elif code in _CANNED:
        raise GcodeError(f"{where}: word G{num}: canned cycles (G73, G76, G81-G89) are not "
                         "supported")
    elif code in _REFUSED_G:
        raise GcodeError(f"{where}: word G{num}: {_REFUSED_G[code]}")
    elif code not in _NOOP_G:
        raise GcodeError(f"{where}: unknown or unsupported word G{num}")


def _m_word(code: str, num: str, st: _ReaderState, prog: GcodeProgram, where: str, ln: int) -> None:
    """An M word (canonical ``code``, as written ``num``) on line ``ln``: spindle, end, tool change."""
    if code in ("3", "4"):
        st.spindle_on = True
        if prog.spindle_on_line is None:
            prog.spindle_on_line = ln
    elif code == "5":
        st.spindle_on = False
        prog.spindle_stop_line = ln
    elif code in ("2", "30"):
        prog.end_word, prog.end_line = "M" + code, ln
    elif code == "6":
        prog.tool_number = st.selected_tool
    elif code not in _NOOP_M:
        raise GcodeError(f"{where}: unknown or unsupported word M{num}")


def _move_end(coords: dict, st: _ReaderState, where: str) -> dict:
    """Update ``st.pos`` to the block's end point (G90/G91); return the start position (a copy)."""
    pos = st.pos
    startp = dict(pos)
    for a in "XYZ":
        if a in coords:
            if st.absolute:
                pos[a] = coords[a]
            elif pos[a] is None:
                raise GcodeError(f"{where}: word {a}: incremental (G91) move from an unknown {a} position")
            else:
                pos[a] = pos[a] + coords[a]
    return startp


def _arc_offsets(motion: str, coords: dict, startp, st: _ReaderState, arc_tolerance: float, where: str):
    """``(i, j)`` centre offsets (mm, from the start) of a G2/G3 block, checked (start and end radius
    within ``arc_tolerance`` mm or 0.1 %); ``(None, None)`` for G0/G1 (which must not carry I/J/R)."""
    pos = st.pos
    i = j = None
    if motion in ("G2", "G3"):
        if startp is None:
            raise GcodeError(f"{where}: word {motion}: arc start point unknown")
        sx, sy = startp["X"], startp["Y"]
        if "R" in coords:
            if "I" in coords or "J" in coords:
                raise GcodeError(f"{where}: word R: give either R or I/J, not both")
            cx, cy = _center_from_radius((sx, sy), (pos["X"], pos["Y"]), coords["R"], motion == "G3",
                                         where)
        else:
            if "I" not in coords and "J" not in coords:
                raise GcodeError(f"{where}: word {motion}: arc needs centre offsets I and J (or R)")
            if st.arc_absolute:
                cx, cy = coords.get("I", sx), coords.get("J", sy)
            else:
                cx, cy = sx + coords.get("I", 0.0), sy + coords.get("J", 0.0)
        i, j = cx - sx, cy - sy
        r0 = math.hypot(i, j)
        r1 = math.hypot(pos["X"] - cx, pos["Y"] - cy)
        if r0 == 0 or abs(r0 - r1) > max(arc_tolerance, 1e-3 * r0):
            w = "R" if "R" in coords else ("I" if "I" in coords else "J")
            raise GcodeError(f"{where}: word {w}: arc start radius {r0:.6g} and end radius {r1:.6g} mm "
                             f"differ by more than {max(arc_tolerance, 1e-3 * r0):.3g} mm")
    elif any(a in coords for a in "IJR"):
        w = next(a for a in "IJR" if a in coords)
        raise GcodeError(f"{where}: word {w}: I/J/R given with {motion} (only arcs G2/G3 take them)")
    return i, j


_LINE_END = re.compile(r"\r\n|\n|\r")
_M6 = re.compile(r"M0*6(?![0-9.])")
_O_LINE = re.compile(r"^(?:N\s*\d+\s*)?O\s*(\d+(?:\.\d*)?|<[^>]*>)\s*(.*)$", re.I)
_O_KEYWORDS = ("sub", "endsub", "call", "do", "while", "endwhile", "if", "elseif", "else", "endif", "repeat",
               "endrepeat", "return", "break", "continue")


def _block_body(raw: str, where: str, ln: int, prog, scale: float):
    """``(words, comments)`` of one line (tool diameter comments recorded); words None for a
    line with nothing to execute: blank, comment, the opening ``%``, a bare O-word (program number).
    The closing ``%`` sets ``prog.closing_percent_line``. Refuses what LinuxCNC refuses (a ``%``
    that is not the first non-blank line, an O-word with other words or with a non-integer number)
    and what is not read here (block delete, parameters, expressions, subroutines, control flow)."""
    body, cmts = _split_comments(raw, where)
    for c in cmts:
        m = _TOOL_DIA.search(c)
        if m and prog.tool_diameter is None and ("tool" in c.lower() or re.match(r"\s*T\d", c, re.I)
                                                 or "diam" in c.lower()):
            unit = (m.group(2) or "").lower()
            inch = unit.startswith("in") or unit == '"' or (not unit and scale != 1.0)
            prog.tool_diameter = float(m.group(1)) * (MM_PER_INCH if inch else 1.0)
            prog.tool_diameter_line = ln
    body = body.strip()
    blank = not body and not cmts
    if prog.first_line is None and not blank:
        prog.first_line = ln
        if body == "%":
            prog.opening_percent = True
            return None, cmts
    if "%" in body:
        if body == "%" and prog.opening_percent:
            prog.closing_percent_line = ln
            return None, cmts
        raise GcodeError(f"{where}: '%' here: a '%' line may only open the program (first non-blank line) "
                         "and close it (LinuxCNC: \"Bad character '%' used\")")
    if not body:
        return None, cmts
    if body.startswith("/"):
        raise GcodeError(f"{where}: block delete '/' is not supported")
    m = _O_LINE.match(body)
    if m:
        number, rest = m.group(1), m.group(2).strip()
        key = rest.split()[0].lower() if rest else ""
        if key in _O_KEYWORDS:
            raise GcodeError(f"{where}: O-word '{key}': subroutines and control flow are not supported")
        if rest:
            raise GcodeError(f"{where}: cannot read {rest!r} after the O-word O{number}: an O-word line holds "
                             "nothing else (LinuxCNC: \"Unknown control command in o word\")")
        if "." in number:
            raise GcodeError(f"{where}: O-word O{number}: the program number must be an integer")
        prog.program_number = number
        return None, cmts
    rest = _WORD.sub(" ", body).strip()
    if rest:
        raise GcodeError(f"{where}: cannot read {rest!r} in {raw.strip()!r} "
                         "(parameters #, expressions [ ] and O-words inside blocks are not supported)")
    return body, cmts


def _check_end(prog, raw_lines, text: str) -> None:
    """Warnings (LinuxCNC runs such files but ends them with an error, or they look cut off): no
    M2/M30 and no closing ``%``, a last block without its line end, blocks after the end.
    A file opened by ``%`` that ends without M2/M30 or the closing ``%`` is refused, as LinuxCNC does."""
    src = prog.source
    last = next((k for k in range(len(raw_lines), 0, -1) if raw_lines[k - 1].strip()), 0)
    stop = prog.end_line or prog.closing_percent_line
    if stop is None:
        if prog.opening_percent:
            raise GcodeError(f"{src}:{last}: the file opens with '%' (line {prog.first_line}) but ends without "
                             "the closing '%' or M2/M30: truncated? (LinuxCNC: \"File ended with no percent sign\")")
        prog.warnings.append(f"{src}: no program end (M2/M30) and no closing '%': LinuxCNC runs the moves and "
                             "then stops with \"File ended with no percent sign or program end\"; truncated?")
        if text and not text.endswith(("\n", "\r")):
            prog.warnings.append(f"{src}:{last}: the last block has no line end: the file may be cut off "
                                 "in the middle of a block")
    else:
        after = sum(1 for k in range(stop, len(raw_lines)) if raw_lines[k].strip()
                    and not (prog.end_line and prog.opening_percent and raw_lines[k].strip() == "%"))
        if after:
            what = f"{prog.end_word} (line {stop})" if prog.end_line else f"the closing '%' (line {stop})"
            prog.warnings.append(f"{src}:{stop + 1}: {after} non-blank line(s) after {what} not executed "
                                 "(as in LinuxCNC)")


def _center_from_radius(s, e, R, ccw, where):
    """Arc centre (mm) from start ``s``, end ``e`` and the RS274 signed radius ``R`` (R > 0: the arc
    of at most 180°, R < 0: the larger one)."""
    dx, dy = e[0] - s[0], e[1] - s[1]
    d = math.hypot(dx, dy)
    if d == 0:
        raise GcodeError(f"{where}: word R: an R-format arc cannot be a full circle (start = end); use I/J")
    r = abs(R)
    if r < 0.5 * d:
        if 0.5 * d - r > 1e-3 * max(r, 1.0):
            raise GcodeError(f"{where}: word R{R:g}: radius smaller than half the chord ({0.5 * d:.6g} mm)")
        r = 0.5 * d
    h = math.sqrt(max(r * r - 0.25 * d * d, 0.0))
    nx, ny = -dy / d, dx / d  # left normal of the chord
    side = 1.0 if ccw else -1.0
    if R < 0:
        side = -side
    return 0.5 * (s[0] + e[0]) + side * h * nx, 0.5 * (s[1] + e[1]) + side * h * ny


def parse_gcode(text: str, source: str = "<string>", arc_tolerance: float = 0.002, start=None) -> list[Move]:
    """Parse RS274/NGC text into :class:`Move` records (absolute mm); :func:`read_gcode` with only
    the moves. Errors are :class:`GcodeError` naming ``source:line`` and the word."""
    return read_gcode(text, source=source, arc_tolerance=arc_tolerance, start=start).moves


def _read_text(path_or_text):
    if isinstance(path_or_text, Path) or (isinstance(path_or_text, str) and "\n" not in path_or_text
                                          and len(path_or_text) < 4096 and Path(path_or_text).is_file()):
        p = Path(path_or_text)
        return read_program_text(p), str(p)
    if isinstance(path_or_text, str) and "\n" not in path_or_text:
        raise OSError(f"{path_or_text}: no such G-code file")
    return str(path_or_text), "<string>"


def read_program_text(path) -> str:
    """The text of a program file, refused with a :class:`GcodeError` naming the file and line when
    it is not text: a NUL byte (a binary file) or bytes that are not UTF-8 (e.g. a Latin-1 ``é`` in a
    comment; RS274 programs are ASCII, UTF-8 comments are accepted).

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "l1.ngc"
    >>> _ = p.write_bytes(b"G21\\n(caf\\xe9)\\nM2\\n")
    >>> read_program_text(p)
    Traceback (most recent call last):
    ...
    cnclab.nc.gcode.GcodeError: ...l1.ngc:2: byte 0xe9 at column 5 is not UTF-8 text (a Latin-1 or binary file?); G-code programs are ASCII text
    """
    p = Path(path)
    if p.is_dir():
        raise IsADirectoryError(f"{p}: is a directory, not a G-code program")
    raw = p.read_bytes()
    nul = raw.find(b"\0")
    if nul >= 0:
        line, col = raw.count(b"\n", 0, nul) + 1, nul - raw.rfind(b"\n", 0, nul)
        raise GcodeError(f"{p}:{line}: NUL byte at column {col}: a binary file, not a G-code program")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        col = exc.start - raw.rfind(b"\n", 0, exc.start)
        raise GcodeError(f"{p}:{line}: byte 0x{raw[exc.start]:02x} at column {col} is not UTF-8 text (a Latin-1 "
                         "or binary file?); G-code programs are ASCII text") from None


def load_gcode(path) -> list[Move]:
    """Parse a G-code file (read-only); errors name the file, line and word."""
    p = Path(path)
    return parse_gcode(read_program_text(p), source=str(p))


def read_toolpath(path_or_text, tool: Tool | None = None, start=None, arc_tolerance: float = 0.002) -> ToolPath:
    """A :class:`ToolPath` from a program file (path) or program text (a string with newlines).

    Move kinds come from :meth:`ToolPath.from_moves` (rapid, retract, helix/ramp/plunge, cut). The
    tool: ``tool`` if given, else a :class:`Tool` with the diameter found in a comment and the M6
    tool number (None when the program states no diameter). ``info`` records the source, the unit
    conversion flag, warnings, source line per move and comments.
    """
    text, source = _read_text(path_or_text)
    prog = read_gcode(text, source=source, arc_tolerance=arc_tolerance, start=start)
    if tool is None and prog.tool_diameter is not None:
        tool = Tool(prog.tool_diameter, number=prog.tool_number or 1)
    elif tool is not None and prog.tool_diameter is not None and abs(prog.tool_diameter - tool.diameter) > 1e-3:
        prog.warnings.append(f"{source}:{prog.tool_diameter_line}: the program's tool comment says D "
                             f"{prog.tool_diameter:g} mm, the given tool is D {tool.diameter:g} mm: "
                             "analyzed with the given tool")
    info = {"source": source, "converted_from_inch": prog.converted_from_inch,
            "warnings": list(prog.warnings), "tool_number": prog.tool_number, "end_word": prog.end_word,
            "spindle_on_line": prog.spindle_on_line}
    path = ToolPath.from_moves(prog.moves, start=start, tool=tool, info=info)
    lines = ([0] if start is not None else []) + list(prog.lines)
    path.info["line"] = np.asarray(lines, int)
    return path


def program_time(moves: Sequence[Move], rapid_mm_min: float, start=None) -> dict:
    """Motion time and length of a program: feed moves at their F, rapids at ``rapid_mm_min``,
    arcs and helices exact, no acceleration (the RS274 canonical model; equals
    :meth:`ToolPath.time_s` of ``ToolPath.from_moves(moves, start)``).

    Returns ``{"feed_mm", "rapid_mm", "feed_s", "rapid_s", "total_s"}``. ``start`` (x, y, z) mm is
    the position before the first move (rs274 starts at the origin); without it the first move only
    positions.

    >>> program_time([Move("G0", 0, 0, 5), Move("G1", 0, 0, 0, feed=300),
    ...               Move("G1", 10, 0, 0, feed=600)], rapid_mm_min=6000)["feed_s"]
    2.0
    """
    path = ToolPath.from_moves(moves, start=start)
    L = path.segment_lengths()
    t = path.time_s(rapid_mm_min)
    rapid = path.is_kind("rapid")
    feed_s = t["total_s"] - t["rapid_s"]
    return {"feed_mm": float(L[~rapid].sum()), "rapid_mm": float(L[rapid].sum()),
            "feed_s": float(feed_s), "rapid_s": float(t["rapid_s"]), "total_s": float(t["total_s"])}


def sample_move(start, mv: Move, max_segment: float = 0.5) -> np.ndarray:
    """Points (n, 3) mm along the move ``mv`` from ``start`` (x, y, z), both ends included; arcs and
    helices sampled by :func:`cnclab.toolpath.path.sample_arc` (chords at most ``max_segment`` mm).

    >>> p = sample_move((1, 0, 0), Move("G3", -1, 0, 0, i=-1, j=0, feed=100), max_segment=0.1)
    >>> bool(np.allclose(np.hypot(p[:, 0], p[:, 1]), 1)), bool(p[:, 1].min() >= -1e-12)
    (True, True)
    """
    if not max_segment > 0:
        raise ValueError(f"max_segment must be > 0 mm, got {max_segment}")
    start = np.asarray(start, float)
    if mv.motion not in ("G2", "G3"):
        return np.vstack([start, mv.xyz])
    return sample_arc(start, mv.xyz, (start[0] + mv.i, start[1] + mv.j), mv.motion == "G3", max_segment)


def to_polyline(moves: Sequence[Move], start=None, max_segment: float = 0.5):
    """A program as points: returns ``(points (n,3) mm, rapid (n,) bool)``; ``rapid[k]`` is True
    when the segment *ending* at point k is a G0 move (``rapid[0]`` is False).

    ``start`` defaults to the end point of the first move.
    """
    if not moves:
        return np.zeros((0, 3)), np.zeros(0, bool)
    cur = moves[0].xyz if start is None else np.asarray(start, float)
    pts, flags = [cur[None, :]], [np.array([False])]
    for mv in moves if start is not None else moves[1:]:
        seg = sample_move(cur, mv, max_segment)[1:]
        pts.append(seg)
        flags.append(np.full(len(seg), mv.motion == "G0"))
        cur = mv.xyz
    return np.vstack(pts), np.concatenate(flags)


def path_lengths(moves: Sequence[Move], start=None) -> dict:
    """Lengths [mm]: ``{"feed": G1+G2+G3, "rapid": G0, "total": both}``; arcs and helices exact.

    ``start`` (x, y, z) is where the tool is before the first move (default: the first move's end).
    """
    feed = rapid = 0.0
    cur = None if start is None else np.asarray(start, float)
    for mv in moves:
        if cur is None:
            cur = mv.xyz
            continue
        if mv.motion in ("G2", "G3"):
            _, _, r, _, sweep = arc_geometry(cur, mv.xyz, (cur[0] + mv.i, cur[1] + mv.j), mv.motion == "G3")
            length = math.hypot(abs(sweep) * r, mv.z - cur[2])
        else:
            length = float(np.linalg.norm(mv.xyz - cur))
        if mv.motion == "G0":
            rapid += length
        else:
            feed += length
        cur = mv.xyz
    return {"feed": feed, "rapid": rapid, "total": feed + rapid}


def linear_moves(points, feed: float, spindle: float | None = None, z: float | None = None) -> list[Move]:
    """``G1`` moves through ``points`` [(n,2) or (n,3) mm] at ``feed`` mm/min (``z`` for 2-D points)."""
    p = np.asarray(points, float)
    if p.ndim != 2 or p.shape[1] not in (2, 3):
        raise ValueError(f"points must have shape (n, 2) or (n, 3), got {p.shape}")
    if p.shape[1] == 2:
        if z is None:
            raise ValueError("z (mm) is required for 2-D points")
        p = np.column_stack([p, np.full(len(p), float(z))])
    return [Move("G1", *row, feed=feed, spindle=spindle) for row in p]
