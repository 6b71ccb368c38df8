"""APT cutter-location (CL) files: parse, inspect, modify and write (dialect of Mgherony 2024, Sec. 7.2.2).

A program is a list of :class:`AptRecord`; each keeps its raw text (all its physical lines), so
writing an unmodified program reproduces the file byte for byte (lossless round trip), and records
cnclab does not interpret (``PARTNO``, ``MACHIN``, ``LOADTL``, ``CUTTER``, ``$$`` comments, ``CSYS`` ...)
are carried through unchanged.

Dialect
-------
- ``$$`` starts a comment (a whole line or the tail of a statement).
- A statement (or comment) whose text ends with a single ``$`` continues on the next line.
- ``UNITS/MM`` is **required** before the first motion (a file without it is refused, naming file
  and line: a CL file of unknown units is never guessed to be mm); ``UNITS/INCH`` is **refused** --
  convert in the CAM system; cnclab works in mm throughout. A UTF-8 byte-order mark at the start of
  the text is dropped (it is not part of the first record; outputs are written without it).
- Numbers follow a strict grammar: ASCII digits, optional sign, one decimal point, optional exponent
  (``[+-]?(digits[.digits]|.digits)([eE][+-]?digits)?``). ``2_0.000``, full-width digits, ``nan``,
  ``inf``, hex and anything else Python's ``float`` would also accept are refused. Record words are
  ASCII identifiers (``[A-Za-z][A-Za-z0-9_]*``).
- ``CIRCLE/xc,yc,zc,i,j,k,r`` (7 values; the 11-value form with tolerance and cutter values is
  accepted, the extra 4 ignored) announces that the **next statement**, which must be a feed
  ``GOTO``, is a circular arc about the centre (xc, yc, zc) and the axis (i, j, k), counter-clockwise
  by the right-hand rule: axis +Z -> G3, -Z -> G2 (arcs in the XY plane only; Z may change: helix).
  Start and end must lie on the circle: their XY distances from the centre may differ from each
  other by at most 0.8 um (so the G-code reader's 1 um arc check passes after 4-decimal output) and
  from r by at most 2 um + 1e-6 r. Anything between the CIRCLE and its GOTO other than comments is an error.
- Motion records cnclab does not interpret (``GODLTA``, ``GOFWD``, ``GOHOME``, ``INDIRV``, ``CYCLE``,
  ``COPY``, ``TRACUT`` ...) are **refused** (file and line) rather than carried through unmodelled.
- ``RAPID`` makes the *next* motion a rapid; ``GOTO/x,y,z[,i,j,k]`` is a linear motion (feed unless
  preceded by ``RAPID``); ``FROM/x,y,z`` sets the start position. ``FEDRAT/f[,MMPM]`` sets the feed in
  mm/min, ``SPINDL/[RPM,]n[,CLW|CCLW]`` the spindle speed in rpm. ``END`` / ``FINI`` end the program.
- Errors name file and line: GOTO/FROM with other than 3 or 6 values, non-numeric or non-finite
  values, a feed motion before any ``FEDRAT``, a program without motion, a motion before ``UNITS``.

Speed: runs of plain ``GOTO / x, y, z`` lines (the bulk of a CL file) are located with one regular
expression, then checked and converted in one compiled pass (``GOTO``, '/', three numbers of the strict
grammar separated by commas; values exactly as ``float`` gives them, see ``_bulk_goto``); they stay in
bulk (:class:`GotoRun`) until ``AptProgram.records`` is accessed. Any line that does not pass the
check goes through the careful per-line parser, so records, text and error messages are identical to
``parse_apt(..., fast=False)`` (tested). About 7-8x faster on 1e6 points (benchmarks/bench_spindle_postprocess.py).

>>> prog = parse_apt("UNITS / MM\\nRAPID\\nGOTO / 0, 0, 5\\nFEDRAT / 500, MMPM\\nGOTO / 10, 0, 0\\nFINI\\n")
>>> cl = prog.cl_points()
>>> cl.xyz.tolist(), cl.rapid.tolist(), cl.feed.tolist()
([[0.0, 0.0, 5.0], [10.0, 0.0, 0.0]], [True, False], [nan, 500.0])
>>> arc = parse_apt("UNITS/MM\\nFROM/10,0,0\\nFEDRAT/500\\nCIRCLE/0,0,0,0,0,1,10\\nGOTO/0,10,0\\n").cl_points()
>>> arc.arc.tolist(), round(float(arc.segment_lengths()[0]), 6)          # quarter circle, CCW (G3)
([3], 15.707963)
>>> prog.to_text() == "UNITS / MM\\nRAPID\\nGOTO / 0, 0, 5\\nFEDRAT / 500, MMPM\\nGOTO / 10, 0, 0\\nFINI\\n"
True
"""
from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
from numba import njit

from ..fileio import atomic_write
from ..toolpath.path import Tool, ToolPath, ToolPathBuilder, classify_moves

__all__ = ["AptError", "AptRecord", "AptProgram", "CLPoints", "parse_apt", "read_apt", "write_apt",
           "goto", "spindl", "fedrat", "circle", "apt_program", "cl_program"]


class AptError(ValueError):
    """A malformed APT file; the message names the file and line."""


#: the strict APT number grammar (ASCII only; no '_', no nan/inf, no hex)
NUMBER_RE = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?", re.ASCII)
_WORD_RE = re.compile(r"[A-Za-z][A-Za-z0-9_]*", re.ASCII)
#: motion records that move the tool in a way cnclab does not model: refused (file and line)
REFUSED_MOTION = frozenset({"GO", "GODLTA", "GOFWD", "GOBACK", "GOLFT", "GORGT", "GOUP", "GODOWN", "GOHOME",
                            "INDIRV", "INDIRP", "CYCLE", "COPY", "INDEX", "TRACUT", "ROTABL", "ROTHED",
                            "ROTATE", "TRANS", "ARC", "MOVARC", "MOVE", "PSIS", "DNTCUT", "AUTOPS"})
_CIRCLE_TOL_DIFF = 0.8e-3     # mm: start and end radius may differ by this much
_CIRCLE_TOL_R = 2e-3          # mm (+ 1e-6 r): start/end radius vs the CIRCLE's r


def parse_number(token: str) -> float:
    """A number of the strict APT grammar (:data:`NUMBER_RE`), else ValueError.

    >>> parse_number("-1.5e3"), parse_number(".5")
    (-1500.0, 0.5)
    """
    t = token.strip()
    if not NUMBER_RE.fullmatch(t):
        raise ValueError(f"{token!r} is not a number")
    return float(t)


@dataclasses.dataclass(slots=True)
class AptRecord:
    """One logical APT statement: ``word`` (upper case, '' for comments/blank), parsed ``values``.

    ``raw`` holds the exact physical text (with newlines) for lossless writing; ``line`` is the
    1-based first line in the source (0 for generated records).
    """

    word: str
    args: list
    raw: str
    line: int = 0
    comment: str = ""
    nums: list | None = None

    @property
    def values(self) -> list[float]:
        """The numeric arguments as floats (minor words such as MMPM/CLW skipped)."""
        if self.nums is not None:
            return self.nums
        out = []
        for a in self.args:
            try:
                out.append(parse_number(a))
            except ValueError:
                pass
        return out


def _format_num(v: float, decimals: int) -> str:
    s = f"{v:.{decimals}f}"
    return "0." + "0" * decimals if s.startswith("-") and float(s) == 0 else s


def goto(x: float, y: float, z: float, decimals: int = 3) -> AptRecord:
    """A generated ``GOTO / x, y, z`` record (mm)."""
    text = "GOTO / " + ", ".join(_format_num(v, decimals) for v in (x, y, z))
    return AptRecord("GOTO", [repr(float(x)), repr(float(y)), repr(float(z))], text + "\n",
                     nums=_finite_nums(x, y, z))


def _finite_nums(*vals) -> list | None:
    """The ``values`` of generated arguments ``repr(float(v))`` (None: let ``values`` parse them)."""
    out = [float(v) for v in vals]
    return out if all(math.isfinite(v) for v in out) else None


def spindl(rpm: float, direction: str = "CLW", decimals: int = 0) -> AptRecord:
    """A generated ``SPINDL / RPM, n, CLW`` record (rpm)."""
    text = f"SPINDL / RPM, {_format_num(rpm, decimals)}, {direction}"
    return AptRecord("SPINDL", ["RPM", repr(float(rpm)), direction], text + "\n", nums=_finite_nums(rpm))


def fedrat(feed_mm_min: float, decimals: int = 1) -> AptRecord:
    """A generated ``FEDRAT / f, MMPM`` record (mm/min)."""
    text = f"FEDRAT / {_format_num(feed_mm_min, decimals)}, MMPM"
    return AptRecord("FEDRAT", [repr(float(feed_mm_min)), "MMPM"], text + "\n", nums=_finite_nums(feed_mm_min))


def _word(text: str, word: str, args=()) -> AptRecord:
    return AptRecord(word, list(args), text + "\n")


@dataclasses.dataclass
class CLPoints:
    """Cutter locations of the motions of a program (arrays of equal length N).

    ``xyz`` (N, 3) mm end points; ``rapid`` (N,) bool; ``feed`` (N,) mm/min in force (NaN for rapids);
    ``spindle`` (N,) rpm in force (NaN before any SPINDL); ``record`` (N,) index into ``records``;
    ``line`` (N,) source line; ``start`` (3,) the FROM point (or the first point); ``arc`` (N,) int8:
    the :class:`~cnclab.toolpath.path.ToolPath` convention, 0 straight, 3 counter-clockwise (G3),
    2 clockwise (G2) arc from a ``CIRCLE`` record; ``centre`` (N, 3) arc centres (mm, NaN for
    straight moves). :meth:`to_toolpath` / :meth:`from_toolpath` convert to and from the one path
    type (the start becomes the path's point 0, a rapid).

    >>> cl = parse_apt("UNITS/MM\\nFROM/0,0,5\\nFEDRAT/300\\nGOTO/0,0,-1\\nGOTO/10,0,-1\\n").cl_points()
    >>> cl.to_toolpath().kinds().tolist()
    ['rapid', 'plunge', 'cut']
    """

    xyz: np.ndarray
    rapid: np.ndarray
    feed: np.ndarray
    spindle: np.ndarray
    record: np.ndarray
    line: np.ndarray
    start: np.ndarray
    arc: np.ndarray | None = None
    centre: np.ndarray | None = None

    def __post_init__(self):
        if self.arc is None:
            self.arc = np.zeros(len(self.xyz), np.int8)
        if self.centre is None:
            self.centre = np.full((len(self.xyz), 3), np.nan)

    def __len__(self):
        return len(self.xyz)

    def segment_lengths(self) -> np.ndarray:
        """Length (mm) of the motion ending at each point: chord for straight moves, arc (helix) length
        for CIRCLE moves (a move ending where it starts is a full circle):
        :meth:`ToolPath.segment_lengths <cnclab.toolpath.path.ToolPath.segment_lengths>`."""
        return self.to_toolpath().segment_lengths()[1:]

    def to_toolpath(self, tool: Tool | None = None, z_tol: float = 1e-6) -> ToolPath:
        """The motions as a :class:`~cnclab.toolpath.path.ToolPath`: point 0 the start (a rapid), then
        every CL point; kinds from the geometry (:func:`~cnclab.toolpath.path.classify_moves`), feed,
        spindle, arcs and their xy centres as they are (``cleared`` False: a CL file states no proof)."""
        P = np.vstack([np.asarray(self.start, float)[None], self.xyz])
        rapid = np.r_[True, self.rapid]
        arc = np.r_[0, self.arc].astype(np.int8)
        return ToolPath.build(P, kind=classify_moves(P, rapid, arc, z_tol), feed=np.r_[np.nan, self.feed],
                              spindle=np.r_[np.nan, self.spindle], arc=arc,
                              arc_center=np.vstack([[np.nan, np.nan], self.centre[:, :2]]), tool=tool, cleared=False)

    @classmethod
    def from_toolpath(cls, path: ToolPath) -> "CLPoints":
        """The CL points of ``path`` (the inverse of :meth:`to_toolpath` up to kinds, tags and flags,
        which a CL file does not carry): point 0 becomes the start; ``record``/``line`` are -1 (no
        file); an arc's centre z is the height of its start point."""
        if len(path) < 2:
            raise ValueError(f"path must have a start point and at least one move, got {len(path)} points")
        arc = path.arc[1:].astype(np.int8)
        cz = np.where(arc != 0, path.xyz[:-1, 2], np.nan)
        n = len(path) - 1
        return cls(path.xyz[1:].copy(), path.is_kind("rapid")[1:], path.feed[1:].copy(), path.spindle[1:].copy(),
                   np.full(n, -1, np.int64), np.full(n, -1, np.int64), path.xyz[0].copy(), arc,
                   np.column_stack([path.arc_center[1:], cz]))


class GotoRun:
    """A run of M consecutive plain ``GOTO / x, y, z`` lines parsed in bulk (internal).

    ``text`` is the exact physical text of the M lines, ``xyz`` (M, 3) their values (mm), ``line`` the
    1-based source line of the first one. Expanded to :class:`AptRecord` objects only on demand.
    """

    __slots__ = ("text", "xyz", "line", "_starts", "_off")

    def __init__(self, text: str, xyz: np.ndarray, line: int, starts: np.ndarray | None = None, off: int = 0):
        # starts - off: the line starts (a view of the parent run's offsets until first needed)
        self.text, self.xyz, self.line, self._starts, self._off = text, xyz, line, starts, off

    def __len__(self):
        return len(self.xyz)

    @property
    def raw(self) -> str:
        return self.text

    def starts(self) -> np.ndarray:
        """Offsets of the M line starts in ``text`` plus ``len(text)`` (M + 1 values)."""
        if self._starts is None:
            nl = np.flatnonzero(np.frombuffer(self.text.encode("ascii"), np.uint8) == 10)
            self._starts, self._off = np.concatenate([[0], nl + 1]), 0
        elif self._off:
            self._starts, self._off = self._starts - self._off, 0
        return self._starts

    def slice(self, a: int, b: int) -> "GotoRun":
        """Lines a..b-1 as a new run."""
        if self._starts is None:
            self.starts()
        st, off = self._starts, self._off
        s0, s1 = int(st[a]) - off, int(st[b]) - off
        return GotoRun(self.text[s0:s1], self.xyz[a:b], self.line + a, st[a:b + 1], s0 + off)

    def records(self) -> list:
        st = self.starts().tolist()
        out = []
        for k, v in enumerate(self.xyz.tolist()):
            raw = self.text[st[k]:st[k + 1]]
            args = [a.strip() for a in raw.rstrip("\r\n").partition("/")[2].split(",")]
            out.append(AptRecord("GOTO", args, raw, self.line + k, "", v))
        return out


class AptProgram:
    """A parsed APT CL program: ``records`` in file order and the ``source`` name for messages.

    Files read with :func:`parse_apt` keep runs of plain ``GOTO`` lines in bulk (numpy arrays);
    ``records`` expands them into :class:`AptRecord` objects on first access (after which the list is
    the program and may be edited). ``to_text``, ``cl_points`` and the spindle post-processor work on
    the bulk form directly.
    """

    def __init__(self, records=(), source: str = "<apt>"):
        self._items = list(records)
        self._bulk = any(isinstance(r, GotoRun) for r in self._items)
        self.source = source

    @property
    def records(self) -> list:
        """The list of :class:`AptRecord` (bulk GOTO runs expanded on first access)."""
        if self._bulk:
            flat = []
            for it in self._items:
                if isinstance(it, GotoRun):
                    flat.extend(it.records())
                else:
                    flat.append(it)
            self._items, self._bulk = flat, False
        return self._items

    @records.setter
    def records(self, value):
        self._items, self._bulk = list(value), False

    def items(self) -> list:
        """Records and bulk GOTO runs in file order (internal fast iteration)."""
        return self._items

    def __len__(self):
        return sum(len(it) if isinstance(it, GotoRun) else 1 for it in self._items)

    def __eq__(self, other):
        return isinstance(other, AptProgram) and self.source == other.source and self.records == other.records

    def to_text(self) -> str:
        """The program text; unchanged records are reproduced exactly."""
        return "".join(r.raw for r in self._items)

    def tool_diameter(self) -> float | None:
        """Cutter diameter (mm) from ``CUTTER/d`` (also inside a ``$$->`` comment), or None."""
        for r in self._items:
            if isinstance(r, GotoRun):
                continue
            if r.word == "CUTTER" and r.values:
                return r.values[0]
            c = r.comment.upper().replace(" ", "")
            if "CUTTER/" in c:
                try:
                    return parse_number(c.split("CUTTER/", 1)[1].split(",")[0].rstrip("$"))
                except ValueError:
                    pass
        return None

    def cl_points(self) -> CLPoints:
        """Motion end points with motion type, feed and spindle in force (validated).

        ``record`` indexes the (expanded) ``records`` list.
        """
        xyz, rapid, feed, spin, rec, line = [], [], [], [], [], []
        arcs = {}         # motion index -> (direction, centre)
        f = math.nan
        s = math.nan
        pending_rapid = False
        circle = None
        start = None
        k = 0
        n_mot = 0
        last = None       # current position (for arc checks)
        buf = []  # (xyz, rapid, feed, spindle, record, line) of single records, flushed into arrays

        def flush():
            if buf:
                cols = list(zip(*buf))
                xyz.append(np.asarray(cols[0], float).reshape(-1, 3))
                for dst, col, dt in zip((rapid, feed, spin, rec, line), cols[1:],
                                        (bool, float, float, np.int64, np.int64)):
                    dst.append(np.asarray(col, dt))
                buf.clear()

        for r in self._items:
            if isinstance(r, GotoRun):
                flush()
                m = len(r)
                if circle is not None:
                    raise AptError(f"{self.source}:{circle[3]}: CIRCLE must be followed by its end point GOTO")
                ra = np.zeros(m, bool)
                fe = np.full(m, f)
                if pending_rapid:
                    ra[0] = True
                    fe[0] = math.nan
                    pending_rapid = False
                if f != f and (~ra).any():
                    raise AptError(f"{self.source}:{r.line + int(np.argmax(~ra))}: feed motion (GOTO) before any FEDRAT")
                xyz.append(r.xyz)
                rapid.append(ra)
                feed.append(fe)
                spin.append(np.full(m, s))
                rec.append(np.arange(k, k + m, dtype=np.int64))
                line.append(np.arange(r.line, r.line + m, dtype=np.int64))
                k += m
                n_mot += m
                last = r.xyz[-1]
                continue
            w = r.word
            if w == "GOTO":
                if pending_rapid:
                    is_rapid, fv = True, math.nan
                    pending_rapid = False
                else:
                    if f != f:
                        raise AptError(f"{self.source}:{r.line}: feed motion (GOTO) before any FEDRAT")
                    is_rapid, fv = False, f
                end = r.values[:3]
                if circle is not None:
                    if last is None:
                        raise AptError(f"{self.source}:{circle[3]}: CIRCLE with an unknown start point "
                                       "(no FROM or GOTO before it)")
                    _check_arc(last, end, circle, self.source)
                    arcs[n_mot] = (circle[0], circle[1])
                    circle = None
                buf.append((end, is_rapid, fv, s, k, r.line))
                n_mot += 1
                last = end
            elif w == "CIRCLE":
                if pending_rapid:
                    raise AptError(f"{self.source}:{r.line}: CIRCLE after RAPID (an arc is a feed motion)")
                v = r.values
                circle = (3 if v[5] > 0 else 2, np.array(v[:3]), v[6], r.line)
            elif w == "RAPID":
                pending_rapid = True
            elif w == "FEDRAT":
                f = r.values[0]
            elif w == "SPINDL":
                s = r.values[0] if r.values else s
            elif w == "FROM":
                start = np.array(r.values[:3])
                last = start
            k += 1
        flush()
        if not xyz:
            raise AptError(f"{self.source}: empty program (no GOTO motion)")
        if circle is not None:
            raise AptError(f"{self.source}:{circle[3]}: CIRCLE without its end point GOTO")
        xyz = np.concatenate(xyz)
        arc = np.zeros(len(xyz), np.int8)
        centre = np.full((len(xyz), 3), np.nan)
        for j, (d, c) in arcs.items():
            arc[j], centre[j] = d, c
        return CLPoints(xyz, np.concatenate(rapid), np.concatenate(feed), np.concatenate(spin),
                        np.concatenate(rec), np.concatenate(line),
                        start if start is not None else xyz[0].copy(), arc, centre)


def _check_arc(p0, p1, circle, source) -> None:
    """Start and end of a CIRCLE move must lie on its circle (XY distances, see module docstring)."""
    _, c, r, line = circle
    d0 = math.hypot(p0[0] - c[0], p0[1] - c[1])
    d1 = math.hypot(p1[0] - c[0], p1[1] - c[1])
    tol = _CIRCLE_TOL_R + 1e-6 * r
    if abs(d0 - d1) > _CIRCLE_TOL_DIFF or abs(d0 - r) > tol or abs(d1 - r) > tol:
        raise AptError(f"{source}:{line}: CIRCLE radius {r:g} mm disagrees with its start and end points "
                       f"(distances {d0:.6g} and {d1:.6g} mm from the centre; tolerance "
                       f"{_CIRCLE_TOL_DIFF * 1000:g} um between them, {tol * 1000:.3g} um to r)")


def _split_comment(text: str) -> tuple[str, str]:
    k = text.find("$$")
    return (text, "") if k < 0 else (text[:k], text[k:])


def _continues(physical: str) -> bool:
    s = physical.rstrip()
    return s.endswith("$") and not s.endswith("$$")


class _State:
    """Parser state carried across careful segments and bulk runs."""

    __slots__ = ("fed", "pending_rapid", "n_goto", "units", "circle_line", "require_units")

    def __init__(self, require_units: bool = True):
        self.fed = False
        self.pending_rapid = False
        self.n_goto = 0
        self.units = False
        self.circle_line = 0
        self.require_units = require_units


_NONFINITE_RE = re.compile(r"[+-]?(?:nan|inf|infinity)", re.I)
_NUMERIC_WORDS = ("GOTO", "FROM", "CIRCLE", "FEDRAT", "SPINDL", "UNITS")


def _strict_values(word: str, args, where: str) -> list:
    """Numbers of a record with the strict grammar; every argument must be a number or a minor word."""
    vals = []
    for a in args:
        t = a.strip()
        if NUMBER_RE.fullmatch(t):
            vals.append(float(t))
        elif _NONFINITE_RE.fullmatch(t):
            raise AptError(f"{where}: {word} has a non-finite value {t!r}")
        elif word in ("GOTO", "FROM", "CIRCLE"):
            raise AptError(f"{where}: {word} value {a!r} is not a number")
        elif not _WORD_RE.fullmatch(t):
            raise AptError(f"{where}: {word} argument {a!r} is neither a number "
                           "([+-]digits[.digits][e[+-]digits]) nor a word")
    if not all(math.isfinite(v) for v in vals):
        raise AptError(f"{where}: {word} has a non-finite value")
    return vals


def _parse_careful(lines, first_line: int, records: list, st: _State, source: str) -> None:
    """The careful per-line parser: every statement, continuation, comment and check."""
    i = 0
    n_lines = len(lines)
    while i < n_lines:
        first = i
        phys = [lines[i]]
        while _continues(lines[i]) and i + 1 < n_lines:
            i += 1
            phys.append(lines[i])
        if _continues(lines[i]) and i + 1 >= n_lines:
            raise AptError(f"{source}:{first_line + i}: continuation '$' at the end of the file")
        i += 1
        raw = "".join(phys)
        # join continuation lines: drop the trailing '$' of each continued line
        joined = ""
        for ph in phys:
            t = ph.rstrip("\r\n")
            if _continues(t):
                t = t.rstrip()[:-1]
            joined += t + " "
        stmt, comment = _split_comment(joined)
        stmt = stmt.strip()
        lineno = first_line + first
        if not stmt:
            records.append(AptRecord("", [], raw, lineno, comment.strip()))
            continue
        if "/" in stmt:
            word, _, rest = stmt.partition("/")
            args = [a.strip() for a in rest.split(",")]
        else:
            word, args = stmt, []
        word = word.strip().upper()
        rec = AptRecord(word, args, raw, lineno, comment.strip())
        where = f"{source}:{lineno}"
        head = word.split()[0] if word.split() else ""     # '/ ...' with no word (e.g. after a form feed)
        if not _WORD_RE.fullmatch(head):
            raise AptError(f"{where}: {stmt[:40]!r} does not start with an APT word (ASCII letters, digits, '_')")
        if head in REFUSED_MOTION:
            raise AptError(f"{where}: motion record {head} is not supported (cnclab reads GOTO, FROM, RAPID "
                           "and CIRCLE); post the CL file with explicit GOTO points")
        if head in ("GOTO", "FROM", "CIRCLE", "FEDRAT", "SPINDL", "UNITS", "RAPID") and word != head:
            raise AptError(f"{where}: malformed {head} record {stmt[:40]!r} (expected '{head} / values')")
        if st.circle_line and word != "GOTO":
            raise AptError(f"{where}: CIRCLE of line {st.circle_line} must be followed directly by its end "
                           f"point GOTO, got {head}")
        if word in ("GOTO", "FROM", "CIRCLE") and st.require_units and not st.units:
            raise AptError(f"{where}: {word} before any UNITS record: UNITS/MM is required (cnclab does not "
                           "guess the units of a CL file)")
        if word in _NUMERIC_WORDS:
            rec.nums = _strict_values(word, args, where) if word != "UNITS" else None
        if word == "RAPID":
            st.pending_rapid = True
        elif word == "GOTO":
            if not st.pending_rapid and not st.fed:
                raise AptError(f"{where}: feed motion (GOTO) before any FEDRAT")
            st.pending_rapid = False
            st.n_goto += 1
        elif word == "FEDRAT":
            st.fed = True
        if word in ("GOTO", "FROM"):
            vals = rec.nums
            if len(vals) not in (3, 6):
                raise AptError(f"{where}: {word} needs 3 (x,y,z) or 6 (x,y,z,i,j,k) values, got {len(vals)}")
            if word == "GOTO":
                st.circle_line = 0
        elif word == "CIRCLE":
            v = rec.nums
            if len(v) not in (7, 11) or len(args) != len(v):
                raise AptError(f"{where}: CIRCLE needs 7 values (xc,yc,zc,i,j,k,r) or 11, got {args}")
            ax = np.array(v[3:6])
            na = float(np.linalg.norm(ax))
            if na == 0 or abs(ax[0]) > 1e-6 * na or abs(ax[1]) > 1e-6 * na:
                raise AptError(f"{where}: CIRCLE axis ({v[3]:g}, {v[4]:g}, {v[5]:g}) is not +-Z: only arcs in the "
                               "XY plane are supported")
            if not v[6] > 0:
                raise AptError(f"{where}: CIRCLE radius must be > 0 mm, got {v[6]:g}")
            if st.pending_rapid:
                raise AptError(f"{where}: CIRCLE after RAPID (an arc is a feed motion)")
            st.circle_line = lineno
        elif word == "FEDRAT":
            v = rec.values
            if not v or not math.isfinite(v[0]) or v[0] <= 0:
                raise AptError(f"{where}: FEDRAT needs a positive finite feed, got {args}")
            if any(a.strip().upper() == "IPM" for a in args):
                raise AptError(f"{where}: FEDRAT in IPM (inch/min) is not supported; use MMPM")
        elif word == "SPINDL":
            v = rec.values
            if v and (not math.isfinite(v[0]) or v[0] < 0):
                raise AptError(f"{where}: SPINDL needs a finite speed >= 0, got {args}")
        elif word == "UNITS":
            unit = (args[0].upper() if args else "")
            if unit == "INCH":
                raise AptError(f"{where}: UNITS/INCH is not supported: cnclab works in mm; "
                               "post the CL file in MM (UNITS/MM)")
            if unit != "MM" or len(args) != 1:
                raise AptError(f"{where}: unknown UNITS/{', '.join(args)} (UNITS/MM is required)")
            st.units = True
        records.append(rec)


# Candidate runs of plain GOTO lines: upper-case GOTO, '/', then only number characters, commas and
# blanks, each line ending in a newline. Candidates are then checked strictly (below); anything
# unusual (comments, '$' continuations, 6 values, lower case, nan, a malformed number ...) is left to
# the careful parser, which gives the same records and the same error messages.
_RUN_RE = re.compile(r"(?:^GOTO[ \t]*/[-+0-9.eE, \t]*\r?\n)+", re.M)
_MIN_RUN = 8


def _bulk_goto(text: str) -> np.ndarray | None:
    """(M, 3) values of a candidate run if every line is exactly ``GOTO / a, b, c`` (blanks and tabs
    around the fields, ``\\r\\n`` or ``\\n``) with three numbers of the strict grammar; else None.

    One compiled pass checks the lines and converts the numbers exactly (Clinger's fast path: at
    most 15 significant digits and a power of ten up to 22 are two exact doubles, so one
    multiplication or division gives the correctly rounded value ``float`` gives); the rare other
    numbers are converted by ``float``.
    """
    b = np.frombuffer(text.encode("ascii"), np.uint8)
    ok, vals, hard, t0, t1 = _goto_lines(b)
    if not ok:
        return None
    for i in np.flatnonzero(hard).tolist():
        vals[i] = float(text[t0[i]:t1[i]])
    if not np.isfinite(vals).all():
        return None
    return vals.reshape(-1, 3)


_POW10 = np.array([10.0 ** k for k in range(23)])


@njit(cache=True, nogil=True)
def _goto_lines(b):
    """Check and convert a candidate run (bytes): (ok, values (3M,), hard (3M,), token start/end)."""
    n = b.shape[0]
    m = 0
    for i in range(n):
        if b[i] == 10:
            m += 1
    vals = np.zeros(3 * m, np.float64)
    hard = np.zeros(3 * m, np.bool_)
    t0 = np.zeros(3 * m, np.int64)
    t1 = np.zeros(3 * m, np.int64)
    pos = 0
    k = 0
    for _ in range(m):
        if pos + 4 > n or b[pos] != 71 or b[pos + 1] != 79 or b[pos + 2] != 84 or b[pos + 3] != 79:  # GOTO
            return False, vals, hard, t0, t1
        pos += 4
        while pos < n and (b[pos] == 32 or b[pos] == 9):
            pos += 1
        if pos >= n or b[pos] != 47:  # '/'
            return False, vals, hard, t0, t1
        pos += 1
        for fld in range(3):
            while pos < n and (b[pos] == 32 or b[pos] == 9):
                pos += 1
            t0[k] = pos
            neg = False
            if pos < n and (b[pos] == 43 or b[pos] == 45):
                neg = b[pos] == 45
                pos += 1
            w = 0
            nd = 0        # significant digits kept in w
            scale = 0     # decimal exponent correction
            n_int = 0
            n_frac = 0
            while pos < n and 48 <= b[pos] <= 57:
                if w > 0 or b[pos] != 48:
                    if nd < 18:
                        w = w * 10 + (b[pos] - 48)
                        nd += 1
                    else:
                        scale += 1
                        hard[k] = True
                n_int += 1
                pos += 1
            if pos < n and b[pos] == 46:  # '.'
                pos += 1
                while pos < n and 48 <= b[pos] <= 57:
                    if w > 0 or b[pos] != 48:
                        if nd < 18:
                            w = w * 10 + (b[pos] - 48)
                            nd += 1
                            scale -= 1
                        else:
                            hard[k] = True
                    else:
                        scale -= 1
                    n_frac += 1
                    pos += 1
            if n_int + n_frac == 0:
                return False, vals, hard, t0, t1
            if pos < n and (b[pos] == 101 or b[pos] == 69):  # exponent
                pos += 1
                eneg = False
                if pos < n and (b[pos] == 43 or b[pos] == 45):
                    eneg = b[pos] == 45
                    pos += 1
                ne = 0
                ev = 0
                while pos < n and 48 <= b[pos] <= 57:
                    if ev < 100000:
                        ev = ev * 10 + (b[pos] - 48)
                    ne += 1
                    pos += 1
                if ne == 0:
                    return False, vals, hard, t0, t1
                scale += -ev if eneg else ev
            t1[k] = pos
            if nd > 15 or scale > 22 or scale < -22:
                hard[k] = True
            if not hard[k]:
                v = float(w)
                if scale >= 0:
                    v = v * _POW10[scale]
                else:
                    v = v / _POW10[-scale]
                vals[k] = -v if neg else v
            k += 1
            while pos < n and (b[pos] == 32 or b[pos] == 9):
                pos += 1
            if fld < 2:
                if pos >= n or b[pos] != 44:  # ','
                    return False, vals, hard, t0, t1
                pos += 1
        if pos < n and b[pos] == 13:
            pos += 1
        if pos >= n or b[pos] != 10:
            return False, vals, hard, t0, t1
        pos += 1
    return pos == n, vals, hard, t0, t1


def parse_apt(text: str, source: str = "<apt>", fast: bool = True, require_units: bool = True) -> AptProgram:
    """Parse APT CL text into an :class:`AptProgram` (see the module docstring for the dialect).

    ``fast=True`` reads runs of plain ``GOTO / x, y, z`` lines in bulk with numpy (same records, same
    errors, same text as the careful per-line parser used for everything else and with ``fast=False``).
    ``require_units=False`` accepts motions before ``UNITS/MM`` (taken as mm; for hand-written
    snippets only -- files read by :func:`read_apt` and the CLI always require UNITS).

    >>> p = parse_apt("UNITS / MM\\nFEDRAT / 500, MMPM\\n" + "GOTO / 1, 2, 3\\n" * 10)
    >>> len(p), p.cl_points().xyz.shape
    (12, (10, 3))
    """
    if text.startswith("\ufeff"):
        text = text[1:]           # a UTF-8 BOM is not part of the first record
    st = _State(require_units)
    items: list = []
    pos = 0
    line_no = 1
    if fast:
        for m in _RUN_RE.finditer(text):
            s, e = m.span()
            if s < pos:
                continue
            # a run line continuing the previous statement ('$') belongs to the careful parser
            prev = text[text.rfind("\n", 0, max(s - 1, 0)) + 1:s] if s > 0 else ""
            if prev and _continues(prev.rstrip("\r\n")):
                s = text.index("\n", s) + 1
            if text.count("\n", s, e) < _MIN_RUN:
                continue
            run_text = text[s:e]
            xyz = _bulk_goto(run_text)
            if xyz is None:
                continue
            before = text[pos:s].splitlines(keepends=True)
            _parse_careful(before, line_no, items, st, source)
            line_no += len(before)
            pos = s
            if st.circle_line or (st.require_units and not st.units):   # the careful parser reports it
                first_end = text.index("\n", s) + 1
                _parse_careful([text[s:first_end]], line_no, items, st, source)
                line_no += 1
                s = pos = first_end
                xyz = xyz[1:]
                run_text = text[s:e]
                if len(xyz) < _MIN_RUN:
                    continue
            if not st.pending_rapid and not st.fed:
                raise AptError(f"{source}:{line_no}: feed motion (GOTO) before any FEDRAT")
            if st.pending_rapid and not st.fed and len(xyz) > 1:
                raise AptError(f"{source}:{line_no + 1}: feed motion (GOTO) before any FEDRAT")
            st.pending_rapid = False
            st.n_goto += len(xyz)
            items.append(GotoRun(run_text, xyz, line_no))
            line_no += len(xyz)
            pos = e
    _parse_careful(text[pos:].splitlines(keepends=True), line_no, items, st, source)
    if st.n_goto == 0:
        raise AptError(f"{source}: empty program (no GOTO motion)")
    return AptProgram(items, source)


def read_apt(path) -> AptProgram:
    """Read and validate an APT CL file (UTF-8/ASCII); errors name file and line."""
    path = Path(path)
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].count(b"\n") + 1
        raise AptError(f"{path}:{line}: not a UTF-8/ASCII text APT file (byte 0x{raw[exc.start]:02x} at offset "
                       f"{exc.start})") from None
    return parse_apt(text, str(path))


def write_apt(path, program: AptProgram, inputs=()) -> Path:
    """Write a program atomically; ``inputs`` are never overwritten."""
    return atomic_write(path, program.to_text(), inputs=inputs)


def apt_program(path: ToolPath, *, tool_diameter: float | None = None, partno: str = "CNCLAB",
                decimals: int = 3) -> AptProgram:
    """The APT writer: an :class:`AptProgram` of ``path`` (tool-tip points, mm).

    Header as in Sec. 7.2.2 (``PARTNO``, ``MACHIN``, ``OUTPUT_ON_TIP``, ``UNITS / MM``, the ``CUTTER``
    diameter — ``tool_diameter`` or ``path.tool`` — and ``SPINDL`` at the first spindle speed set),
    ``FROM`` the path's point 0 (``RAPID FROM`` when move 1 is a rapid), then every move: ``RAPID`` + ``GOTO`` for rapids; for feed
    moves ``FEDRAT`` when the feed changes, ``CIRCLE / xc, yc, z0, 0, 0, +-1, r`` before an arc (z0
    the arc's start height; +1 counter-clockwise), ``GOTO``; ``SPINDL`` where the speed changes; ``FINI``.

    >>> from cnclab.toolpath.path import ToolPath
    >>> p = ToolPath.build([[0, 0, 30], [0, 0, 30], [0, 0, 0], [5, 0, 0]], kind=["rapid", "rapid", "plunge", "cut"],
    ...                    feed=500, spindle=2000)
    >>> print(apt_program(p, tool_diameter=10).to_text())   # doctest: +NORMALIZE_WHITESPACE
    PARTNO / CNCLAB
    MACHIN / MILL, 1
    $$-> CUTCOM_GEOMETRY_TYPE / OUTPUT_ON_TIP
    UNITS / MM
    $$-> CUTTER / 10.000000
    SPINDL / RPM, 2000, CLW
    RAPID
    FROM / 0.000, 0.000, 30.000
    RAPID
    GOTO / 0.000, 0.000, 30.000
    FEDRAT / 500.0, MMPM
    GOTO / 0.000, 0.000, 0.000
    GOTO / 5.000, 0.000, 0.000
    FINI
    """
    if len(path) < 2:
        raise ValueError(f"path must have a start point and at least one move, got {len(path)} points")
    if tool_diameter is None:
        if path.tool is None:
            raise ValueError("tool_diameter (mm) is required when the path has no tool")
        tool_diameter = path.tool.diameter
    spin = path.spindle[np.isfinite(path.spindle)]
    if not len(spin) or not spin[0] > 0:
        raise ValueError("the path sets no spindle speed > 0 rpm (ToolPath.spindle)")
    recs = [_word(f"PARTNO / {partno}", "PARTNO", [partno]), _word("MACHIN / MILL, 1", "MACHIN", ["MILL", "1"]),
            _word("$$-> CUTCOM_GEOMETRY_TYPE / OUTPUT_ON_TIP", ""), _word("UNITS / MM", "UNITS", ["MM"]),
            _word(f"$$-> CUTTER / {tool_diameter:.6f}", "")]
    recs[-1].comment = recs[-1].raw.strip()
    recs.append(spindl(spin[0]))
    p0 = path.xyz[0]
    rapid = path.is_kind("rapid")
    if rapid[1]:       # (the reader carries a RAPID over FROM to the next motion: only before a rapid)
        recs.append(_word("RAPID", "RAPID"))
    recs.append(_word("FROM / " + ", ".join(_format_num(v, decimals) for v in p0), "FROM", [str(v) for v in p0]))
    f_cur, s_cur = math.nan, float(spin[0])
    for k in range(1, len(path)):
        x, y, z = path.xyz[k]
        if np.isfinite(path.spindle[k]) and path.spindle[k] != s_cur:
            s_cur = float(path.spindle[k])
            recs.append(spindl(s_cur))
        if rapid[k]:
            recs += [_word("RAPID", "RAPID"), goto(x, y, z, decimals)]
            continue
        if path.feed[k] != f_cur:
            f_cur = float(path.feed[k])
            recs.append(fedrat(f_cur))
        if path.arc[k]:
            recs.append(circle(path.xyz[k - 1], path.arc_center[k], path.arc[k] == 3, decimals))
        recs.append(goto(x, y, z, decimals))
    recs.append(_word("FINI", "FINI"))
    for i, r in enumerate(recs, start=1):
        r.line = i
    return AptProgram(recs, partno)


def circle(start, center_xy, ccw: bool, decimals: int = 3) -> AptRecord:
    """A generated ``CIRCLE / xc, yc, z0, 0, 0, +-1, r`` record (mm) announcing an arc from ``start``
    (x, y, z0) about ``center_xy``; axis +Z counter-clockwise (``ccw``), -Z clockwise."""
    xc, yc = float(center_xy[0]), float(center_xy[1])
    r = math.hypot(start[0] - xc, start[1] - yc)
    vals = (xc, yc, float(start[2]), 0.0, 0.0, 1.0 if ccw else -1.0, r)
    text = "CIRCLE / " + ", ".join(_format_num(v, decimals) for v in vals)
    return AptRecord("CIRCLE", [repr(v) for v in vals], text + "\n", nums=_finite_nums(*vals))


def cl_program(passes, feed_mm_min: float, spindle_rpm: float, tool_diameter: float,
               clearance_z: float, partno: str = "CNCLAB", decimals: int = 3, link: str = "feed") -> AptProgram:
    """An APT program cutting each pass (list of (M, 3) arrays of tool-tip points, mm) in order.

    The tool rapids to ``clearance_z`` above the first point and *feeds* down onto it (never a rapid
    onto the part), then feeds through all passes in order, and retracts at the end. ``link="feed"``:
    consecutive passes are linked by a feed move (a zig-zag); ``"rapid"``: by a rapid retract straight
    up to ``clearance_z``, a rapid over the next pass start at ``clearance_z`` and a feed down onto it.
    Header as in Sec. 7.2.2 (``OUTPUT_ON_TIP``: the points are tool-tip positions); written by
    :func:`apt_program` from the :class:`~cnclab.toolpath.path.ToolPath` of the passes.
    """
    if feed_mm_min <= 0 or spindle_rpm <= 0:
        raise ValueError(f"feed_mm_min and spindle_rpm must be > 0, got {feed_mm_min}, {spindle_rpm}")
    if link not in ("feed", "rapid"):
        raise ValueError(f"link must be 'feed' or 'rapid', got {link!r}")
    passes = [np.asarray(p, float) for p in passes if len(p)]
    if not passes:
        raise ValueError("passes: no points")
    top = max(float(p[:, 2].max()) for p in passes)
    if not clearance_z > top:
        raise ValueError(f"clearance_z must be above every point of the passes ({top:g} mm), got {clearance_z}")
    b = ToolPathBuilder(tool=Tool(float(tool_diameter)), spindle=spindle_rpm)
    b.rapid(passes[0][:1, :2], z=clearance_z)                     # the FROM point
    for k, p in enumerate(passes):
        if k == 0 or link == "rapid":
            if k > 0:
                b.rapid(passes[k - 1][-1:, :2], z=clearance_z)
            b.rapid(p[:1, :2], z=clearance_z)
        b.add(p, classify_moves(np.vstack([b.position[None], p]), False, 0)[1:], feed_mm_min)
    b.rapid(passes[-1][-1:, :2], z=clearance_z)
    return apt_program(b.build(), tool_diameter=tool_diameter, partno=partno, decimals=decimals)


def reordered_program(points, result, *, feed_mm_min: float, spindle_rpm: float,
                      tool_diameter: float, clearance_z: float, partno: str = "CNCLAB_REORDERED",
                      decimals: int = 3):
    """An APT program visiting ``points`` (N, 3, mm) in ``result.order``: feed moves between
    neighbours, and at every jump a rapid retract to ``clearance_z`` (mm), a rapid over the next point
    and a feed down onto it (the tool lifts; no material is cut on a jump).

    >>> P = np.array([[0, 0, 0], [1, 0, 0], [5, 5, 0.0]])
    >>> from cnclab.toolpath.reorder import ReorderResult
    >>> r = ReorderResult(np.array([0, 1, 2]), np.array([False, False, True]), np.ones(3))
    >>> prog = reordered_program(P, r, feed_mm_min=500, spindle_rpm=2000, tool_diameter=10, clearance_z=30)
    >>> cl = prog.cl_points(); cl.rapid.tolist()
    [True, False, False, True, True, False, True]
    """
    P = np.asarray(points, float)
    order = np.asarray(result.order)
    if P.ndim != 2 or P.shape[1] != 3 or len(order) != len(P):
        raise ValueError(f"points must be (N, 3) with N = len(result.order), got {P.shape}, {len(order)}")
    cuts = np.flatnonzero(np.asarray(result.jump, bool))
    segs = np.split(P[order], cuts[cuts > 0])
    return cl_program(segs, feed_mm_min, spindle_rpm, tool_diameter, clearance_z, partno=partno,
                      decimals=decimals, link="rapid")
