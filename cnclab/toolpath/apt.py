"""APT cutter-location (CL) files: parse, inspect, modify and write (dialect of Mgherony 2024, Sec. 7.2.2).

A program is a list of :class:`AptRecord`; each keeps its raw text (all its physical lines), so
writing an unmodified program reproduces the file byte for byte (lossless round trip), and records
cnclab does not interpret (``PARTNO``, ``MACHIN``, ``LOADTL``, ``CUTTER``, ``$$`` comments, ``CSYS`` ...)
are carried through unchanged.

Dialect
-------
- ``$$`` starts a comment (a whole line or the tail of a statement).
- A statement (or comment) whose text ends with a single ``$`` continues on the next line.
- ``UNITS/MM`` is required for coordinates in mm; ``UNITS/INCH`` is **refused** (ValueError naming
  file and line) -- convert in the CAM system; cnclab works in mm throughout.
- ``RAPID`` makes the *next* motion a rapid; ``GOTO/x,y,z[,i,j,k]`` is a linear motion (feed unless
  preceded by ``RAPID``); ``FROM/x,y,z`` sets the start position. ``FEDRAT/f[,MMPM]`` sets the feed in
  mm/min, ``SPINDL/[RPM,]n[,CLW|CCLW]`` the spindle speed in rpm. ``END`` / ``FINI`` end the program.
- Errors name file and line: GOTO/FROM with other than 3 or 6 values, non-numeric or non-finite
  values, a feed motion before any ``FEDRAT``, a program without motion.

>>> prog = parse_apt("UNITS / MM\\nRAPID\\nGOTO / 0, 0, 5\\nFEDRAT / 500, MMPM\\nGOTO / 10, 0, 0\\nFINI\\n")
>>> cl = prog.cl_points()
>>> cl.xyz.tolist(), cl.rapid.tolist(), cl.feed.tolist()
([[0.0, 0.0, 5.0], [10.0, 0.0, 0.0]], [True, False], [nan, 500.0])
>>> prog.to_text() == "UNITS / MM\\nRAPID\\nGOTO / 0, 0, 5\\nFEDRAT / 500, MMPM\\nGOTO / 10, 0, 0\\nFINI\\n"
True
"""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

__all__ = ["AptError", "AptRecord", "AptProgram", "CLPoints", "parse_apt", "read_apt", "write_apt",
           "goto", "spindl", "fedrat", "cl_program"]


class AptError(ValueError):
    """A malformed APT file; the message names the file and line."""


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
                out.append(float(a))
            except ValueError:
                pass
        return out


def _format_num(v: float, decimals: int) -> str:
    s = f"{v:.{decimals}f}"
    return "0." + "0" * decimals if s.startswith("-") and float(s) == 0 else s


def goto(x: float, y: float, z: float, decimals: int = 3) -> AptRecord:
    """A generated ``GOTO / x, y, z`` record (mm)."""
    text = "GOTO / " + ", ".join(_format_num(v, decimals) for v in (x, y, z))
    return AptRecord("GOTO", [repr(float(x)), repr(float(y)), repr(float(z))], text + "\n")


def spindl(rpm: float, direction: str = "CLW", decimals: int = 0) -> AptRecord:
    """A generated ``SPINDL / RPM, n, CLW`` record (rpm)."""
    text = f"SPINDL / RPM, {_format_num(rpm, decimals)}, {direction}"
    return AptRecord("SPINDL", ["RPM", repr(float(rpm)), direction], text + "\n")


def fedrat(feed_mm_min: float, decimals: int = 1) -> AptRecord:
    """A generated ``FEDRAT / f, MMPM`` record (mm/min)."""
    text = f"FEDRAT / {_format_num(feed_mm_min, decimals)}, MMPM"
    return AptRecord("FEDRAT", [repr(float(feed_mm_min)), "MMPM"], text + "\n")


def _word(text: str, word: str, args=()) -> AptRecord:
    return AptRecord(word, list(args), text + "\n")


@dataclasses.dataclass
class CLPoints:
    """Cutter locations of the motions of a program (arrays of equal length N).

    ``xyz`` (N, 3) mm end points; ``rapid`` (N,) bool; ``feed`` (N,) mm/min in force (NaN for rapids);
    ``spindle`` (N,) rpm in force (NaN before any SPINDL); ``record`` (N,) index into ``records``;
    ``line`` (N,) source line; ``start`` (3,) the FROM point (or the first point).
    """

    xyz: np.ndarray
    rapid: np.ndarray
    feed: np.ndarray
    spindle: np.ndarray
    record: np.ndarray
    line: np.ndarray
    start: np.ndarray

    def __len__(self):
        return len(self.xyz)


@dataclasses.dataclass
class AptProgram:
    """A parsed APT CL program: ``records`` in file order and the ``source`` name for messages."""

    records: list
    source: str = "<apt>"

    def to_text(self) -> str:
        """The program text; unchanged records are reproduced exactly."""
        return "".join(r.raw for r in self.records)

    def tool_diameter(self) -> float | None:
        """Cutter diameter (mm) from ``CUTTER/d`` (also inside a ``$$->`` comment), or None."""
        for r in self.records:
            if r.word == "CUTTER" and r.values:
                return r.values[0]
            c = r.comment.upper().replace(" ", "")
            if "CUTTER/" in c:
                try:
                    return float(c.split("CUTTER/", 1)[1].split(",")[0].rstrip("$"))
                except ValueError:
                    pass
        return None

    def cl_points(self) -> CLPoints:
        """Motion end points with motion type, feed and spindle in force (validated)."""
        xyz, rapid, feed, spin, rec, line = [], [], [], [], [], []
        ax, ar, af, asp, arec, al = xyz.append, rapid.append, feed.append, spin.append, rec.append, line.append
        f = math.nan
        s = math.nan
        pending_rapid = False
        start = None
        for i, r in enumerate(self.records):
            w = r.word
            if w == "GOTO":
                if pending_rapid:
                    ar(True)
                    af(math.nan)
                    pending_rapid = False
                else:
                    if f != f:
                        raise AptError(f"{self.source}:{r.line}: feed motion (GOTO) before any FEDRAT")
                    ar(False)
                    af(f)
                ax(r.values[:3])
                asp(s)
                arec(i)
                al(r.line)
            elif w == "RAPID":
                pending_rapid = True
            elif w == "FEDRAT":
                f = r.values[0]
            elif w == "SPINDL":
                s = r.values[0] if r.values else s
            elif w == "FROM":
                start = np.array(r.values[:3])
        if not xyz:
            raise AptError(f"{self.source}: empty program (no GOTO motion)")
        xyz = np.asarray(xyz, float)
        return CLPoints(xyz, np.asarray(rapid, bool), np.asarray(feed, float), np.asarray(spin, float),
                        np.asarray(rec, np.int64), np.asarray(line, np.int64),
                        start if start is not None else xyz[0].copy())


def _split_comment(text: str) -> tuple[str, str]:
    k = text.find("$$")
    return (text, "") if k < 0 else (text[:k], text[k:])


def _continues(physical: str) -> bool:
    s = physical.rstrip()
    return s.endswith("$") and not s.endswith("$$")


def parse_apt(text: str, source: str = "<apt>") -> AptProgram:
    """Parse APT CL text into an :class:`AptProgram` (see the module docstring for the dialect)."""
    lines = text.splitlines(keepends=True)
    records = []
    i = 0
    n_lines = len(lines)
    fed = False
    pending_rapid = False
    n_goto = 0
    while i < n_lines:
        first = i
        line = lines[i]
        if line.startswith("GOTO") and "$" not in line:  # fast path for the bulk of a CL file
            args = line.partition("/")[2].split(",")
            try:
                vals = [float(a) for a in args]
            except ValueError:
                vals = None
            if vals is not None and len(vals) in (3, 6) and math.isfinite(sum(vals)):
                if not pending_rapid and not fed:
                    raise AptError(f"{source}:{i + 1}: feed motion (GOTO) before any FEDRAT")
                pending_rapid = False
                n_goto += 1
                records.append(AptRecord("GOTO", args, line, i + 1, "", vals))
                i += 1
                continue
        phys = [lines[i]]
        while _continues(lines[i]) and i + 1 < n_lines:
            i += 1
            phys.append(lines[i])
        if _continues(lines[i]) and i + 1 >= n_lines:
            raise AptError(f"{source}:{i + 1}: continuation '$' at the end of the file")
        i += 1
        raw = "".join(phys)
        # join continuation lines: drop the trailing '$' of each continued line
        joined = ""
        for p in phys:
            s = p.rstrip("\r\n")
            if _continues(s):
                s = s.rstrip()[:-1]
            joined += s + " "
        stmt, comment = _split_comment(joined)
        stmt = stmt.strip()
        if not stmt:
            records.append(AptRecord("", [], raw, first + 1, comment.strip()))
            continue
        if "/" in stmt:
            word, _, rest = stmt.partition("/")
            args = [a.strip() for a in rest.split(",")]
        else:
            word, args = stmt, []
        word = word.strip().upper()
        rec = AptRecord(word, args, raw, first + 1, comment.strip())
        where = f"{source}:{first + 1}"
        if word == "RAPID":
            pending_rapid = True
        elif word == "GOTO":
            if not pending_rapid and not fed:
                raise AptError(f"{where}: feed motion (GOTO) before any FEDRAT")
            pending_rapid = False
            n_goto += 1
        elif word == "FEDRAT":
            fed = True
        if word in ("GOTO", "FROM"):
            vals = []
            for a in args:
                try:
                    vals.append(float(a))
                except ValueError:
                    raise AptError(f"{where}: {word} value {a!r} is not a number") from None
            if len(vals) not in (3, 6):
                raise AptError(f"{where}: {word} needs 3 (x,y,z) or 6 (x,y,z,i,j,k) values, got {len(vals)}")
            if not all(math.isfinite(v) for v in vals):
                raise AptError(f"{where}: {word} has a non-finite value")
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
            if unit != "MM":
                raise AptError(f"{where}: unknown UNITS/{unit}")
        records.append(rec)
    if n_goto == 0:
        raise AptError(f"{source}: empty program (no GOTO motion)")
    return AptProgram(records, source)


def read_apt(path) -> AptProgram:
    """Read and validate an APT CL file (UTF-8/ASCII); errors name file and line."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise AptError(f"{path}: not a text APT file ({exc})") from None
    return parse_apt(text, str(path))


def write_apt(path, program: AptProgram, inputs=()) -> Path:
    """Write a program atomically; ``inputs`` are never overwritten."""
    from ..fileio import atomic_write

    return atomic_write(path, program.to_text(), inputs=inputs)


def cl_program(passes, feed_mm_min: float, spindle_rpm: float, tool_diameter: float,
               clearance_z: float, partno: str = "CNCLAB", decimals: int = 3) -> AptProgram:
    """An APT program cutting each pass (list of (M, 3) arrays of tool-tip points, mm) in order.

    The tool rapids above the first point at ``clearance_z`` and down to it, then feeds through all
    passes in order (a zig-zag: consecutive passes are linked by a feed move), and retracts at the
    end. Header as in Sec. 7.2.2 (``OUTPUT_ON_TIP``: the points are tool-tip positions).
    """
    if feed_mm_min <= 0 or spindle_rpm <= 0:
        raise ValueError(f"feed_mm_min and spindle_rpm must be > 0, got {feed_mm_min}, {spindle_rpm}")
    recs = [_word(f"PARTNO / {partno}", "PARTNO", [partno]), _word("MACHIN / MILL, 1", "MACHIN", ["MILL", "1"]),
            _word("$$-> CUTCOM_GEOMETRY_TYPE / OUTPUT_ON_TIP", ""), _word("UNITS / MM", "UNITS", ["MM"]),
            _word(f"$$-> CUTTER / {tool_diameter:.6f}", "")]
    recs[-1].comment = recs[-1].raw.strip()
    recs.append(spindl(spindle_rpm))
    passes = [np.asarray(p, float) for p in passes if len(p)]
    if not passes:
        raise ValueError("passes: no points")
    p0 = passes[0][0]
    recs += [_word("RAPID", "RAPID"), _word("FROM / " + ", ".join(_format_num(v, decimals) for v in
                                                                    (p0[0], p0[1], clearance_z)),
                                             "FROM", [str(p0[0]), str(p0[1]), str(clearance_z)])]
    feed_set = False
    for k, p in enumerate(passes):
        if k == 0:
            recs += [_word("RAPID", "RAPID"), goto(p[0, 0], p[0, 1], clearance_z, decimals)]
            recs += [_word("RAPID", "RAPID"), goto(*p[0], decimals=decimals)]
        if not feed_set:
            recs.append(fedrat(feed_mm_min))
            feed_set = True
        recs += [goto(*q, decimals=decimals) for q in p[(1 if k == 0 else 0):]]
    last = passes[-1][-1]
    recs += [_word("RAPID", "RAPID"), goto(last[0], last[1], clearance_z, decimals), _word("FINI", "FINI")]
    for i, r in enumerate(recs, start=1):
        r.line = i
    return AptProgram(recs, partno)
