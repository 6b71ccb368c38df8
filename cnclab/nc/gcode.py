"""RS274/NGC (G-code) writer and parser for 3-axis milling programs.

A program is a list of :class:`Move` records. Conventions (fixed, stated in every written file):

* ``G21`` millimetres, ``G90`` absolute coordinates, ``G17`` XY arc plane, ``G94`` feed per minute.
* Each :class:`Move` holds the **absolute end point** ``x, y, z`` [mm] of the motion, the motion word
  ``"G0"`` (rapid), ``"G1"`` (linear feed), ``"G2"`` (clockwise arc) or ``"G3"`` (counter-clockwise
  arc, seen from +Z), arc-centre offsets ``i, j`` [mm] *relative to the start point* (the RS274
  default incremental IJ) for arcs, the feed ``feed`` [mm/min] (``None`` for ``G0``) and the spindle
  speed ``spindle`` [rpm] (``None`` = spindle off / not set). A ``G2``/``G3`` move with a Z change is
  a helix.

Writer — :func:`write_gcode` / :func:`save_gcode`: modal words (motion, F, S, unchanged axes) are
emitted only when they change; coordinates use fixed decimals (``decimals=4`` by default); the first
motion always states X, Y and Z; ``S.. M3`` is written when a spindle speed first appears or changes,
``M5`` when it goes to ``None``; the program ends with ``M5 M30``. ``save_gcode`` writes atomically
(:func:`cnclab.fileio.atomic_write`) and never overwrites a file given in ``inputs``.

Parser — :func:`parse_gcode`: reads what the writer writes and common hand-written variants (``G00``/
``G01``, line numbers ``N..``, ``( )`` and ``;`` comments, ``%`` lines, ``T``/``M6`` tool change,
``M3/M4/M5/M8/M9/M2/M30``, ``G40 G49 G54 G80 G17 G21 G90 G94`` accepted as no-ops). It raises
:class:`GcodeError` (a ``ValueError``) naming ``source:line`` for an unknown word, inches (``G20``),
incremental mode (``G91``), R-format or non-XY arcs, an arc without ``I``/``J``, an arc whose start and end
radii disagree, a feed move with no feed set, or a move whose position is not fully known yet.

Round trip: ``write_gcode(parse_gcode(write_gcode(m)))`` equals ``write_gcode(m)`` exactly.

Helpers: :func:`sample_arc` (arc → polyline points), :func:`to_polyline` (a whole program → points
with a rapid/feed flag), :func:`path_lengths` (feed vs rapid length, arcs exact), :func:`linear_moves`
(polyline → ``G1`` moves).

>>> moves = [Move("G0", 0, 0, 10), Move("G1", 0, 0, 0, feed=500, spindle=2000),
...          Move("G1", 10, 0, 0, feed=500, spindle=2000),
...          Move("G3", 10, 10, 0, i=0, j=5, feed=500, spindle=2000)]
>>> text = write_gcode(moves, header="demo", decimals=3)
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
>>> write_gcode(parse_gcode(text), header="demo", decimals=3) == text
True
"""
from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

from ..fileio import atomic_write
from ..toolpath.path import MOTIONS, Move

__all__ = ["Move", "GcodeError", "write_gcode", "write_gcode_linear", "save_gcode", "parse_gcode", "load_gcode",
           "sample_arc", "to_polyline", "path_lengths", "linear_moves", "gcode_roundtrip_error"]

class GcodeError(ValueError):
    """Malformed G-code; the message starts with ``source:line``."""


def _fmt(v: float, decimals: int) -> str:
    s = f"{v:.{decimals}f}"
    if s.startswith("-") and float(s) == 0.0:
        s = s[1:]
    return s


def write_gcode(moves: Iterable[Move], header: str | Sequence[str] = "", decimals: int = 4,
                feed_decimals: int = 1) -> str:
    """RS274/NGC text of ``moves`` (see module docstring for the conventions).

    ``header``: comment text (a string with newlines or a list of lines), written as ``( ... )``;
    ``decimals``: digits after the point for X Y Z I J [mm]; ``feed_decimals`` for F [mm/min] and S [rpm].
    """
    if not isinstance(decimals, int) or not 0 <= decimals <= 8:
        raise ValueError(f"decimals must be an int in [0, 8], got {decimals!r}")
    lines = ["%"]
    hdr = header.splitlines() if isinstance(header, str) else list(header)
    for h in hdr:
        if "(" in h or ")" in h:
            raise ValueError(f"header lines cannot contain parentheses, got {h!r}")
        lines.append(f"({h})")
    lines.append("G21 G90 G17 G94")
    cur = {"X": None, "Y": None, "Z": None}
    motion = feed = spindle = None
    for k, mv in enumerate(moves):
        if not isinstance(mv, Move):
            raise ValueError(f"moves[{k}] must be a Move, got {type(mv).__name__}")
        axes = [(ax, _fmt(v, decimals)) for ax, v in (("X", mv.x), ("Y", mv.y), ("Z", mv.z))]
        axes = [(ax, s) for ax, s in axes if s != cur[ax]]
        if not axes and mv.motion in ("G0", "G1"):
            continue  # zero-length move after rounding: nothing to say, modal state untouched
        sp = None if mv.spindle is None else _fmt(mv.spindle, 0)
        if sp != spindle:
            lines.append("M5" if sp is None else f"S{sp} M3")
            spindle = sp
        words = []
        if mv.motion != motion or mv.motion in ("G2", "G3"):
            words.append(mv.motion)
            motion = mv.motion
        for ax, s in axes:
            words.append(ax + s)
            cur[ax] = s
        if mv.motion in ("G2", "G3"):
            words += ["I" + _fmt(mv.i, decimals), "J" + _fmt(mv.j, decimals)]
        if mv.motion != "G0":
            f = _fmt(mv.feed, feed_decimals)
            if f != feed:
                words.append("F" + f)
                feed = f
        lines.append(" ".join(words))
    if spindle is not None:
        lines.append("M5")
    lines += ["M30", "%"]
    return "\n".join(lines) + "\n"


def write_gcode_linear(xyz, rapid, feed, spindle, header: str | Sequence[str] = "", decimals: int = 4,
                       feed_decimals: int = 1) -> str:
    """:func:`write_gcode` of linear moves given as arrays, byte-identical and ~50x faster.

    ``xyz`` (n, 3) end points [mm]; ``rapid`` (n,) bool (G0 vs G1); ``feed`` (n,) [mm/min] (NaN
    allowed for G0 only); ``spindle`` (n,) [rpm], NaN = off. Numbers are formatted exactly as
    ``f"{v:.{d}f}"`` by :mod:`cnclab.nc.numfmt`.
    """
    from .numfmt import gcode_linear_body, scaled_ints

    if not isinstance(decimals, int) or not 0 <= decimals <= 8:
        raise ValueError(f"decimals must be an int in [0, 8], got {decimals!r}")
    xyz = np.asarray(xyz, float).reshape(-1, 3)
    rapid = np.asarray(rapid, bool).reshape(-1)
    feed = np.asarray(feed, float).reshape(-1)
    spindle = np.asarray(spindle, float).reshape(-1)
    if not (len(rapid) == len(feed) == len(spindle) == len(xyz)):
        raise ValueError("xyz, rapid, feed and spindle must have the same length")
    if np.isnan(feed[~rapid]).any():
        raise ValueError("write_gcode_linear: a G1 move has no feed")
    has_s = ~np.isnan(spindle)
    body, on = gcode_linear_body(scaled_ints(xyz[:, 0], decimals), scaled_ints(xyz[:, 1], decimals),
                                 scaled_ints(xyz[:, 2], decimals), rapid,
                                 scaled_ints(np.where(rapid, 0.0, feed), feed_decimals),
                                 scaled_ints(np.where(has_s, spindle, 0.0), 0), has_s, decimals, feed_decimals)
    hdr = header.splitlines() if isinstance(header, str) else list(header)
    for h in hdr:
        if "(" in h or ")" in h:
            raise ValueError(f"header lines cannot contain parentheses, got {h!r}")
    head = "\n".join(["%", *(f"({h})" for h in hdr), "G21 G90 G17 G94"]) + "\n"
    return head + body.tobytes().decode("ascii") + ("M5\n" if on else "") + "M30\n%\n"


def save_gcode(moves: Iterable[Move], path, header: str | Sequence[str] = "", decimals: int = 4,
               inputs=()) -> Path:
    """Write ``write_gcode(moves, ...)`` to ``path`` atomically; returns the path."""
    return atomic_write(path, write_gcode(moves, header=header, decimals=decimals), inputs=inputs)


_WORD = re.compile(r"([A-Za-z])\s*([+-]?(?:\d+\.?\d*|\.\d+))")
_NOOP_G = {"17", "21", "40", "49", "54", "80", "90", "94", "90.1", "91.1"}
_NOOP_M = {"0", "1", "2", "6", "8", "9", "30"}


def _strip_comments(line: str) -> str:
    out, depth = [], 0
    for ch in line:
        if ch == "(":
            depth += 1
        elif ch == ")":
            depth = max(depth - 1, 0)
        elif ch == ";" and depth == 0:
            break
        elif depth == 0:
            out.append(ch)
    return "".join(out)


def parse_gcode(text: str, source: str = "<string>", arc_tolerance: float = 1e-3) -> list[Move]:
    """Parse RS274/NGC text into :class:`Move` records (absolute mm; see module docstring).

    ``source`` names the text in error messages (``source:line: ...``); ``arc_tolerance`` [mm] is the
    largest accepted difference between an arc's start and end radius.
    """
    moves: list[Move] = []
    pos: dict[str, float | None] = {"X": None, "Y": None, "Z": None}
    motion, feed, spindle, spindle_on = None, None, None, False
    for ln, raw in enumerate(text.splitlines(), start=1):
        where = f"{source}:{ln}"
        body = _strip_comments(raw).strip()
        if not body or body == "%":
            continue
        rest = _WORD.sub(" ", body).strip()
        if rest:
            raise GcodeError(f"{where}: cannot read {rest!r} in {raw.strip()!r}")
        words = [(m.group(1).upper(), m.group(2)) for m in _WORD.finditer(body)]
        coords: dict[str, float] = {}
        new_motion = None
        for letter, num in words:
            if letter == "G":
                code = num.lstrip("0") or "0"
                code = code if "." not in code else code.rstrip("0").rstrip(".")
                code = code if code else "0"
                if code in ("0", "1", "2", "3"):
                    if new_motion is not None:
                        raise GcodeError(f"{where}: two motion words in one block")
                    new_motion = "G" + code
                elif code == "20":
                    raise GcodeError(f"{where}: G20 (inches) is not supported; cnclab programs are in mm (G21)")
                elif code == "91":
                    raise GcodeError(f"{where}: G91 (incremental) is not supported; use G90 absolute")
                elif code in ("18", "19"):
                    raise GcodeError(f"{where}: G{code} arc plane is not supported; only G17 (XY)")
                elif code not in _NOOP_G:
                    raise GcodeError(f"{where}: unknown or unsupported word G{num}")
            elif letter == "M":
                code = num.lstrip("0") or "0"
                if code in ("3", "4"):
                    spindle_on = True
                elif code in ("5", "2", "30"):
                    spindle_on = False if code == "5" else spindle_on
                elif code not in _NOOP_M:
                    raise GcodeError(f"{where}: unknown or unsupported word M{num}")
            elif letter in "XYZIJ":
                if letter in coords:
                    raise GcodeError(f"{where}: word {letter} given twice")
                coords[letter] = float(num)
            elif letter == "F":
                if float(num) <= 0:
                    raise GcodeError(f"{where}: feed F must be > 0 mm/min, got {num}")
                feed = float(num)
            elif letter == "S":
                spindle = float(num)
            elif letter in "NT":
                pass
            elif letter == "R":
                raise GcodeError(f"{where}: R-format arcs are not supported; give I and J")
            else:
                raise GcodeError(f"{where}: unknown word {letter}{num}")
        if new_motion is not None:
            motion = new_motion
        has_xyz = any(a in coords for a in "XYZ")
        if not has_xyz and not ("I" in coords or "J" in coords):
            if new_motion in ("G2", "G3"):
                raise GcodeError(f"{where}: {new_motion} without an end point")
            continue
        if motion is None:
            raise GcodeError(f"{where}: coordinates given before any motion word (G0/G1/G2/G3)")
        start = dict(pos)
        for a in "XYZ":
            if a in coords:
                pos[a] = coords[a]
        unknown = [a for a in "XYZ" if pos[a] is None]
        if unknown:
            raise GcodeError(f"{where}: position of {'/'.join(unknown)} is unknown (state every axis on the first move)")
        i = j = None
        if motion in ("G2", "G3"):
            if "I" not in coords and "J" not in coords:
                raise GcodeError(f"{where}: {motion} arc needs centre offsets I and J")
            if any(start[a] is None for a in "XY"):
                raise GcodeError(f"{where}: arc start point unknown")
            i, j = coords.get("I", 0.0), coords.get("J", 0.0)
            r0 = math.hypot(i, j)
            cx, cy = start["X"] + i, start["Y"] + j
            r1 = math.hypot(pos["X"] - cx, pos["Y"] - cy)
            if r0 == 0 or abs(r0 - r1) > arc_tolerance:
                raise GcodeError(f"{where}: arc start radius {r0:.6g} and end radius {r1:.6g} mm differ "
                                 f"by more than {arc_tolerance} mm")
        elif "I" in coords or "J" in coords:
            raise GcodeError(f"{where}: I/J given with {motion} (only arcs G2/G3 take them)")
        if motion != "G0" and feed is None:
            raise GcodeError(f"{where}: {motion} feed move with no feed F set")
        moves.append(Move(motion, pos["X"], pos["Y"], pos["Z"], i=i, j=j,
                          feed=feed if motion != "G0" else None,
                          spindle=spindle if spindle_on else None))
    return moves


def load_gcode(path) -> list[Move]:
    """Parse a G-code file (read-only); errors name the file and line."""
    p = Path(path)
    return parse_gcode(p.read_text(encoding="utf-8"), source=str(p))


def _arc_geometry(start: np.ndarray, mv: Move):
    cx, cy = start[0] + mv.i, start[1] + mv.j
    r = math.hypot(mv.i, mv.j)
    a0 = math.atan2(start[1] - cy, start[0] - cx)
    a1 = math.atan2(mv.y - cy, mv.x - cx)
    if mv.motion == "G3":
        sweep = (a1 - a0) % (2 * math.pi)
    else:
        sweep = -((a0 - a1) % (2 * math.pi))
    if abs(sweep) < 1e-12:  # same start and end: full circle
        sweep = 2 * math.pi if mv.motion == "G3" else -2 * math.pi
    return cx, cy, r, a0, sweep


def sample_arc(start, mv: Move, max_segment: float = 0.5) -> np.ndarray:
    """Points [mm] along the arc (or helix) ``mv`` from ``start`` (x, y, z), including both ends.

    Segments are at most ``max_segment`` mm long along the arc. Returns an (n, 3) array.

    >>> p = sample_arc((1, 0, 0), Move("G3", -1, 0, 0, i=-1, j=0, feed=100), max_segment=0.1)
    >>> bool(np.allclose(np.hypot(p[:, 0], p[:, 1]), 1)), bool(p[:, 1].min() >= -1e-12)
    (True, True)
    """
    if max_segment <= 0:
        raise ValueError(f"max_segment must be > 0 mm, got {max_segment}")
    start = np.asarray(start, float)
    if mv.motion not in ("G2", "G3"):
        return np.vstack([start, mv.xyz])
    cx, cy, r, a0, sweep = _arc_geometry(start, mv)
    n = max(2, int(math.ceil(abs(sweep) * r / max_segment)) + 1)
    t = np.linspace(0.0, 1.0, n)
    ang = a0 + sweep * t
    pts = np.column_stack([cx + r * np.cos(ang), cy + r * np.sin(ang), start[2] + (mv.z - start[2]) * t])
    pts[-1] = mv.xyz
    return pts


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
        seg = sample_arc(cur, mv, max_segment)[1:]
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
            _, _, r, _, sweep = _arc_geometry(cur, mv)
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


def gcode_roundtrip_error(path, job, feeds=None, decimals=4):
    """Write the G-code, parse it back and compare: (max point distance mm, feed-length difference
    mm, text) — the parsed program must reproduce the path within the written decimals."""
    from ..toolpath.pocket import to_gcode_moves

    moves = to_gcode_moves(path, job, feeds, decimals=decimals)
    text = write_gcode(moves, header="cnclab " + path.name.replace("(", "").replace(")", ""), decimals=decimals)
    back = parse_gcode(text, source=path.name)
    cut_back = np.array([[m.x, m.y] for m in back if m.motion == "G1" and abs(m.z + job.a_p) < 1e-9])
    keep = np.r_[True, np.hypot(*np.diff(path.points, axis=0).T) > 10 ** -decimals]
    ref = path.points[keep]
    # every written cutting-depth point must lie on the path within rounding
    from scipy.spatial import cKDTree

    d, _ = cKDTree(ref).query(cut_back)
    dl = abs(path_lengths(back)["feed"] - path_lengths(moves)["feed"])
    return float(d.max()), float(dl), text
