"""APT records and programs: the data model shared by the reader (:mod:`cnclab.nc.apt_read`)
and the writer (:mod:`cnclab.nc.apt`): :class:`AptRecord`, :class:`GotoRun` (bulk GOTO runs),
:class:`AptProgram`, :class:`CLPoints` and the generated records. Import them from
:mod:`cnclab.nc.apt` (the dialect is described there). Units: mm, mm/min, rpm.
"""
from __future__ import annotations

import dataclasses
import math
import re

import numpy as np

from ..toolpath.path import Tool, ToolPath, classify_moves

__all__ = ["AptError", "AptRecord", "AptProgram", "CLPoints", "GotoRun", "NUMBER_RE", "WORD_RE",
           "REFUSED_MOTION", "parse_number", "format_num", "finite_nums", "goto", "spindl", "fedrat"]


class AptError(ValueError):
    """A malformed APT file; the message names the file and line."""


#: the strict APT number grammar (ASCII only; no '_', no nan/inf, no hex)
NUMBER_RE = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?", re.ASCII)
WORD_RE = re.compile(r"[A-Za-z][A-Za-z0-9_]*", re.ASCII)
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


def format_num(v: float, decimals: int) -> str:
    """``v`` with ``decimals`` decimals, never ``-0.000``."""
    s = f"{v:.{decimals}f}"
    return "0." + "0" * decimals if s.startswith("-") and float(s) == 0 else s


def goto(x: float, y: float, z: float, decimals: int = 3) -> AptRecord:
    """A generated ``GOTO / x, y, z`` record (mm)."""
    text = "GOTO / " + ", ".join(format_num(v, decimals) for v in (x, y, z))
    return AptRecord("GOTO", [repr(float(x)), repr(float(y)), repr(float(z))], text + "\n",
                     nums=finite_nums(x, y, z))


def finite_nums(*vals) -> list | None:
    """The ``values`` of generated arguments ``repr(float(v))`` (None: let ``values`` parse them)."""
    out = [float(v) for v in vals]
    return out if all(math.isfinite(v) for v in out) else None


def spindl(rpm: float, direction: str = "CLW", decimals: int = 0) -> AptRecord:
    """A generated ``SPINDL / RPM, n, CLW`` record (rpm)."""
    text = f"SPINDL / RPM, {format_num(rpm, decimals)}, {direction}"
    return AptRecord("SPINDL", ["RPM", repr(float(rpm)), direction], text + "\n", nums=finite_nums(rpm))


def fedrat(feed_mm_min: float, decimals: int = 1) -> AptRecord:
    """A generated ``FEDRAT / f, MMPM`` record (mm/min)."""
    text = f"FEDRAT / {format_num(feed_mm_min, decimals)}, MMPM"
    return AptRecord("FEDRAT", [repr(float(feed_mm_min)), "MMPM"], text + "\n", nums=finite_nums(feed_mm_min))


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

    >>> from cnclab.nc.apt import parse_apt
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
