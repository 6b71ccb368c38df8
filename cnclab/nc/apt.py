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
grammar separated by commas; values exactly as ``float`` gives them, see ``apt_read._bulk_goto``); they stay in
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

import math
from pathlib import Path

import numpy as np

from ..fileio import atomic_write
from ..toolpath.path import Tool, ToolPath, ToolPathBuilder, classify_moves
# the reader and the data model live in their own modules; everything is re-exported here, so
# ``from cnclab.nc.apt import ...`` keeps working (NUMBER_RE, REFUSED_MOTION, GotoRun, parse_number too)
from .apt_read import parse_apt, read_apt
from .apt_records import (NUMBER_RE, REFUSED_MOTION, AptError, AptProgram, AptRecord, CLPoints, GotoRun,  # noqa: F401
                          fedrat, finite_nums, format_num, goto, parse_number, spindl)

__all__ = ["AptError", "AptRecord", "AptProgram", "CLPoints", "parse_apt", "read_apt", "write_apt",
           "goto", "spindl", "fedrat", "circle", "apt_program", "cl_program"]


def _word(text: str, word: str, args=()) -> AptRecord:
    return AptRecord(word, list(args), text + "\n")


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
    recs.append(_word("FROM / " + ", ".join(format_num(v, decimals) for v in p0), "FROM", [str(v) for v in p0]))
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
    text = "CIRCLE / " + ", ".join(format_num(v, decimals) for v in vals)
    return AptRecord("CIRCLE", [repr(v) for v in vals], text + "\n", nums=finite_nums(*vals))


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
