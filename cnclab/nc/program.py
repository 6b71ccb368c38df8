"""Machine-safe NC programs: the one writer every output uses, and a static safety checker.

:func:`write_program` turns a :class:`~cnclab.toolpath.path.ToolPath` into a program for a
``dialect`` — ``linuxcnc`` (RS274/NGC, the default) or ``grbl`` (GRBL 1.1) — returns its text and,
given ``out``, writes it atomically (the one way a program reaches disk):

* a header of comments: clearance plane and stock top, dialect and cnclab version, the tool, the
  stock (pocket bounds, depth, levels, job file), the strategy, the estimated run time (length /
  feed), the entry feed and the arc-fitting tolerance;
* start block ``G21 G90 G17 G94 G40 G49 G80`` (mm, absolute, XY plane, feed per minute, no cutter
  or length compensation, no canned cycle); linuxcnc: ``T.. M6`` then ``G43 H..`` when a tool is
  given; grbl: the tool in a comment (GRBL 1.1 has no ``M6`` and only ``G43.1``), no ``%`` lines,
  every line at most 80 characters; ``S.. M3`` before the first motion (so before the first
  cutting move), the coolant word after it when asked, ``G0 Z<clearance>`` and a rapid over the first
  point at the clearance plane;
* the path's moves at the path's feeds (the planner's: :func:`cnclab.toolpath.planners.plan` gives
  helix and ramp entries the job's entry feed, :attr:`Job.entry_feed <cnclab.toolpath.job.Job.entry_feed>`:
  job key ``entry_feed_mm_min``, default :data:`ENTRY_FEED_FRACTION` x ``feed_mm_min``; the writer
  changes no feed, so the evaluator's times are the program's) and runs of short moves fitted as G2/G3
  arcs and longer lines within 0.005 mm (:mod:`cnclab.nc.arcfit`); :func:`program_path` is that
  path, its :meth:`~cnclab.toolpath.path.ToolPath.time_s` the program's time;
* rapids only at or above ``clearance_z``, or straight up (a retract), or where the path marks the
  move as inside cleared area (its ``cleared`` flag, the planner's proof from its stock simulation;
  written as the structured, versioned marker :data:`CLEARED_MARK` ``(cnclab:cleared/1)`` on the
  block, as on any other move the path flags ``cleared``, e.g. a plunge into cleared area — the
  evaluator proves it again by simulation; tags are free text and decide nothing); any other rapid
  below the clearance plane is refused
  (``ValueError`` naming the move index). The first point is reached from the clearance plane by
  a feed move when it lies below it (never a rapid onto the part);
* the end: a rapid straight up to ``clearance_z``, (``M9``), ``M5``, ``M30``.

A number the program cannot carry (a feed that would be written ``F0.0``, a spindle speed written
``S0``, a tool number beyond the controller's T range, a depth that rounds to the stock top...) is
refused with the job key that produced it.

:func:`write_moves` / :func:`write_linear_moves` write a motion program given move by move (a
post-processor's: :mod:`cnclab.nc.spindle_control` turns an APT CL file with its SPINDL/FEDRAT
records into G-code through them) as it is, with the same text rules; the G-code text of every
program cnclab writes comes from this module.

:func:`check_program` (:mod:`cnclab.nc.check`, re-exported here) reads a program (any post's) or a ToolPath and
checks: the spindle is on before the first feed move, no G0 below the clearance plane (except
straight up, or a move marked cleared), every Z-descending feed move classified (helix / ramp /
plunge; a plunge below the stock top ``top_z`` is a plunge into material unless marked cleared),
and the program stops the spindle (``M5``) and ends (``M30`` or ``M2``). "Marked cleared" is data:
on a ToolPath its ``cleared`` column; in a program text only a block whose comment is exactly
:data:`CLEARED_MARK` (:func:`cleared_mark`, the one parser, next to the writer): no other comment
text (``(cleared)``, ``(not cleared)``, a tag) grants anything.

>>> from cnclab.toolpath.path import Tool, ToolPath
>>> p = ToolPath.build([[0, 0, 1], [0, 0, -1], [10, 0, -1]], kind=["rapid", "plunge", "cut"], feed=300)
>>> text = write_program(p, clearance_z=5, tool=Tool(6), spindle_rpm=6000)
>>> print(text)   # doctest: +NORMALIZE_WHITESPACE, +ELLIPSIS
%
(cnclab program: mm, clearance plane Z5 mm, stock top Z0 mm)
(dialect linuxcnc, written by cnclab ...)
(tool T1: D6 mm flat end mill, 2 teeth)
(estimated run time 0.05 min: feed moves 0.05 min at their F, rapids 0.00 min at 10000 mm/min; ...)
(estimated machine time 0.06 min on the small VMC, LinuxCNC model: ...)
(arcs fitted within 0.005 mm of the planned path)
G21 G90 G17 G94 G40 G49 G80
T1 M6
G43 H1
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
['<string>:14: word G1: plunge into material below the stock top Z0 (not marked cleared)']
>>> check_program(p, clearance_z=5).plunges_into_material          # the path itself: its cleared column
1
>>> print(write_program(p, clearance_z=5, tool=Tool(6), spindle_rpm=6000, dialect="grbl",
...                     coolant="flood"))   # doctest: +NORMALIZE_WHITESPACE, +ELLIPSIS
(cnclab program: mm, clearance plane Z5 mm, stock top Z0 mm)
...
(load tool T1 before running: GRBL has no tool change M6 and no G43)
G21 G90 G17 G94 G40 G49 G80
S6000 M3
M8
G0 X0.0000 Y0.0000 Z5.0000
...
G0 Z5.0000
M9
M5
M30
"""
from __future__ import annotations

import dataclasses
import math
import textwrap
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

from .. import __version__
from ..fileio import atomic_write
from ..toolpath.job import ENTRY_FEED_FRACTION
from ..toolpath.path import Move, ToolPath
from .check import CLEARED_MARK, ProgramCheck, check_program, cleared_mark  # noqa: F401  (re-exported)
from .arcfit import DEFAULT_TOL_MM, ENGAGEMENT_BUDGET_DEG, Walls, engagement_tol_mm, fit_arcs
from .machine import machine_for_dialect, machine_time
from .gcode import MAX_COORD_MM, MAX_FEED_MM_MIN, MAX_SPINDLE_RPM, parse_gcode, path_lengths, program_time

__all__ = ["write_program", "write_moves", "write_linear_moves", "gcode_roundtrip_error", "program_path",
           "check_program", "ProgramCheck", "CLEARED_MARK", "cleared_mark", "START_BLOCK", "DIALECTS",
           "TOOL_NUMBER_RANGE", "ENTRY_FEED_FRACTION", "GRBL_LINE_MAX", "LINUXCNC_LINE_MAX", "COOLANT"]

START_BLOCK = "G21 G90 G17 G94 G40 G49 G80"
_TOL = 1e-6


#: the T word range each controller reads. LinuxCNC: ``read_t`` (src/emc/rs274ngc/interp_read.cc)
#: reads the T number as a C ``int`` (larger values overflow to "Negative tool id used") and
#: ``T0 M6`` unloads the spindle, so 1 .. 2**31 - 1 (the tool must also be in the machine's tool
#: table); GRBL 1.1: ``MAX_TOOL_NUMBER 255`` (grbl/gcode.c, "limited by max unsigned 8-bit value").
TOOL_NUMBER_RANGE = {"linuxcnc": (1, 2 ** 31 - 1), "grbl": (0, 255)}
DIALECTS = tuple(TOOL_NUMBER_RANGE)
#: GRBL 1.1 line buffer: at most 80 characters per line (``LINE_BUFFER_SIZE``, data/nc/grbl11_grammar.json)
GRBL_LINE_MAX = 80
#: LinuxCNC's interpreter reads at most 252 characters per line: ``rs274`` refuses a line of 253 or more
#: with "Command too long" (its line buffer of 256 with the newline and the terminator; measured on the
#: rs274 of linuxcnc-uspace: 252 passes, 253 fails; tests/test_dialects.py runs it when installed)
LINUXCNC_LINE_MAX = 252
#: coolant words: flood M8, mist M7 (M7 is off in GRBL's default build: refused for grbl)
COOLANT = {"flood": "M8", "mist": "M7"}
_FEED_DEC = 1
_ENTRY_KINDS = ("helix", "ramp")   # cnclab.toolpath.levels.ENTRY_MOVE_KINDS: the moves plan gives the entry feed

#: where a feed move's F comes from, by move kind: (job key, how it is derived) — for the messages
_FEED_SOURCE = {
    "cut": ("feed_mm_min", "or f_z x teeth x spindle_rpm"),
    "plunge": ("feed_mm_min", "or f_z x teeth x spindle_rpm"),
    "retract": ("feed_mm_min", "or f_z x teeth x spindle_rpm"),
    "link": ("link_feed", "the linking feed"),
    "helix": ("entry_feed_mm_min", f"default {ENTRY_FEED_FRACTION:g} x feed_mm_min, given the entries by plan"),
    "ramp": ("entry_feed_mm_min", f"default {ENTRY_FEED_FRACTION:g} x feed_mm_min, given the entries by plan"),
}


@dataclasses.dataclass
class _Setup:
    """The numbers a program is written with, each with where it came from (for error messages)."""

    values: dict
    origin: dict

    def __getitem__(self, key):
        return self.values.get(key)

    def blame(self, key: str) -> str:
        return self.origin.get(key, f"write_program parameter {key!r}")


_JOB_ATTR = {"clearance_z": "clearance_z", "top_z": "top_z", "spindle_rpm": "spindle_rpm", "tool": "tool",
             "rapid_mm_min": "rapid_mm_min", "entry_feed_mm_min": "entry_feed_mm_min",
             "feed_mm_min": "feed_mm_min", "link_feed": "link_feed_mm_min"}
_OVERRIDES = {"clearance_z", "top_z", "spindle_rpm", "tool", "rapid_mm_min"}


def _setup(path: ToolPath, job, overrides: dict) -> _Setup:
    unknown = set(overrides) - _OVERRIDES
    if unknown:
        raise TypeError(f"write_program got unknown keyword(s) {sorted(unknown)}; allowed: {sorted(_OVERRIDES)}")
    src = getattr(job, "source", None) or "the job"
    values, origin = {}, {}
    for key, attr in _JOB_ATTR.items():
        if overrides.get(key) is not None:
            values[key], origin[key] = overrides[key], f"write_program parameter {key!r}"
        elif job is not None and getattr(job, attr, None) is not None:
            values[key], origin[key] = getattr(job, attr), f"job key {key!r} of {src}"
    if values.get("tool") is None and path.tool is not None:
        values["tool"], origin["tool"] = path.tool, "the path's tool"
    if job is not None and overrides.get("spindle_rpm") is None and getattr(job, "v_c", None) is not None:
        origin["spindle_rpm"] = (f"job key 'spindle_rpm' of {src}, or v_c x 1000 / (pi x tool_diameter) with "
                                 f"v_c = {job.v_c!r} m/min, tool_diameter = {job.tool.diameter!r} mm")
    if values.get("spindle_rpm") is None:
        finite = path.spindle[np.isfinite(path.spindle)]
        if len(finite):
            values["spindle_rpm"], origin["spindle_rpm"] = float(finite[0]), "the path's spindle speed"
    origin["geometry"] = f"the polygon coordinates ($.polygon), depth and a_p of {src}"
    if values.get("entry_feed_mm_min") is None and values.get("feed_mm_min") is not None:
        values["entry_feed_mm_min"] = ENTRY_FEED_FRACTION * float(values["feed_mm_min"])   # as Job.entry_feed
        origin["entry_feed_mm_min"] = (f"default entry feed {ENTRY_FEED_FRACTION:g} x job key 'feed_mm_min' "
                                       f"of {src}")
    return _Setup(values, origin)


def _limit(setup: _Setup, key: str, v, lo: float, hi: float, unit: str, rule: str = "") -> float:
    """``v`` as a float within [lo, hi], else ValueError naming ``key`` and where it came from."""
    ok = v is not None and not isinstance(v, bool) and isinstance(v, (int, float, np.floating, np.integer))
    ok = ok and math.isfinite(float(v)) and lo <= float(v) <= hi
    if not ok:
        raise ValueError(f"{key} = {v!r} {unit} ({setup.blame(key)}) is outside what the program writer "
                         f"can write: [{lo:g}, {hi:g}] {unit}{'; ' + rule if rule else ''}")
    return float(v)


def _check_setup(setup: _Setup, dialect: str, decimals: int) -> None:
    """Range checks of the job's numbers, each error naming the job key (issue 28 item 3)."""
    cz = _limit(setup, "clearance_z", setup["clearance_z"], -MAX_COORD_MM, MAX_COORD_MM, "mm")
    tz = _limit(setup, "top_z", 0.0 if setup["top_z"] is None else setup["top_z"], -MAX_COORD_MM, MAX_COORD_MM, "mm")
    if not cz > tz:
        raise ValueError(f"clearance_z ({cz:g} mm, {setup.blame('clearance_z')}) must be above the stock top "
                         f"top_z ({tz:g} mm, {setup.blame('top_z')})")
    smin = 0.5    # S is written as an integer rpm: below 0.5 it would read S0 (spindle stopped)
    _limit(setup, "spindle_rpm", setup["spindle_rpm"], smin, MAX_SPINDLE_RPM, "rpm",
           "the program starts the spindle before cutting, with S written as a whole rpm")
    fmin = 0.5 * 10.0 ** -_FEED_DEC   # F is written with one decimal: below 0.05 it would read F0.0
    for key in ("feed_mm_min", "link_feed", "entry_feed_mm_min", "rapid_mm_min"):
        if setup[key] is not None:
            _limit(setup, key, setup[key], fmin, MAX_FEED_MM_MIN, "mm/min", f"F is written with {_FEED_DEC} decimal")
    tool = setup["tool"]
    if tool is not None:
        lo, hi = TOOL_NUMBER_RANGE[dialect]
        n = getattr(tool, "number", None)
        if not (isinstance(n, (int, float, np.integer)) and math.isfinite(n) and float(n).is_integer()
                and lo <= n <= hi):
            raise ValueError(f"tool_number = {n!r} ({setup.blame('tool')}) is outside the {dialect} T word range "
                             f"[{lo}, {hi}]" + (" (T0 M6 unloads the spindle)" if dialect == "linuxcnc" else ""))


def _check_path_numbers(path: ToolPath, setup: _Setup, decimals: int) -> None:
    """Every feed and coordinate of the path writable; a bad one is traced to the job key that
    gives moves of its kind their feed (or to the job's geometry for a coordinate)."""
    kinds = path.kinds()
    fmin = 0.5 * 10.0 ** -_FEED_DEC
    feedmove = ~path.is_kind("rapid")
    bad = feedmove & ~((path.feed >= fmin) & (path.feed <= MAX_FEED_MM_MIN))
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        key, how = _FEED_SOURCE.get(kinds[k], ("feed_mm_min", "the planner's feed"))
        val = setup[key]
        raise ValueError(f"move {k} ({kinds[k]}): feed {path.feed[k]!r} mm/min cannot be written as F > 0 with "
                         f"{_FEED_DEC} decimal (range [{fmin:g}, {MAX_FEED_MM_MIN:g}] mm/min); moves of this kind take "
                         f"their feed from {key} = {val!r} ({how}; {setup.blame(key)})")
    big = np.abs(path.xyz) > MAX_COORD_MM
    if big.any():
        k, ax = (int(v) for v in np.argwhere(big)[0])
        raise ValueError(f"move {k} ({kinds[k]}): {'XYZ'[ax]} = {path.xyz[k, ax]:g} mm beyond the writer's "
                         f"+-{MAX_COORD_MM:g} mm: check {setup.origin.get('geometry', 'the job')} (mm)")


def _check_depth(path: ToolPath, job, setup: _Setup, decimals: int) -> None:
    """A pocket job must cut below its stock top as written (a_p/depth rounding to nothing)."""
    if job is None or getattr(job, "a_p", None) is None:
        return
    feed = ~path.is_kind("rapid")
    tz = float(setup["top_z"] or 0.0)
    if feed.any() and round(float(path.xyz[feed, 2].min()), decimals) >= round(tz, decimals):
        raise ValueError(f"a_p = {job.a_p!r} mm, depth = {job.depth!r} mm (job keys 'a_p'/'depth' of "
                         f"{getattr(job, 'source', 'the job')}): no feed move goes below the stock top Z{tz:g} "
                         f"once written with {decimals} decimals")


def program_path(path: ToolPath, job=None, *, arc_tol_mm: float | None = DEFAULT_TOL_MM, decimals: int = 4,
                 **values) -> ToolPath:
    """The path as :func:`write_program` writes it (before its approach from and retract to the
    clearance plane): every feed as the path has it (a path of :func:`cnclab.toolpath.planners.plan`
    has its helix and ramp entries at the job's entry feed already) and arcs fitted within ``arc_tol_mm`` (:func:`cnclab.nc.arcfit.fit_arcs`; curved G0 runs in
    cleared area as G2/G3 links at ``rapid_mm_min``). Its :meth:`~ToolPath.time_s` is the written
    program's time. ``values``: overrides of the job's numbers (see :func:`write_program`)."""
    setup = _setup(path, job, values)
    return _program_path(path, setup, arc_tol_mm, decimals, job)[0]


def _walls(job, setup: _Setup) -> Walls | None:
    """The walls the arc fit keeps off (:class:`cnclab.nc.arcfit.Walls`): the job's pocket with the
    tool and stock top the program is written with; None without a pocket."""
    walls = Walls.of_job(job)
    if walls is None:
        return None
    r = float(getattr(setup["tool"], "radius", walls.radius_mm))     # the tool as written (None: the job's)
    return dataclasses.replace(walls, radius_mm=r, top_z=float(setup["top_z"] or 0.0))


def _fit_tolerance(arc_tol_mm: float, walls: Walls | None, job, decimals: int) -> tuple:
    """The arc-fitting tolerance [mm] of a program and the note saying why it is below ``arc_tol_mm``:
    on a pocket job (walls and a target engagement) at most :func:`cnclab.nc.arcfit.engagement_tol_mm`
    of the tool radius as written and the job's theta, so that fitting moves the engagement by at most
    ``ENGAGEMENT_BUDGET_DEG``; never below three units of the last written digit."""
    theta = getattr(job, "theta_deg", None)
    if walls is None or theta is None:
        return float(arc_tol_mm), ""
    tol = max(engagement_tol_mm(walls.radius_mm, float(theta), arc_tol_mm), 3 * 10.0 ** -decimals)
    if tol >= arc_tol_mm:
        return float(arc_tol_mm), ""
    return tol, (f", {arc_tol_mm:g} mm capped so that the engagement of r {walls.radius_mm:g} mm at "
                 f"theta {float(theta):g} deg moves <= {ENGAGEMENT_BUDGET_DEG:g} deg")


def _program_path(path: ToolPath, setup: _Setup, arc_tol_mm, decimals, job=None) -> tuple:
    notes = []
    entry = path.is_kind(*_ENTRY_KINDS)
    if entry.any():
        ef = setup["entry_feed_mm_min"]
        feeds = np.unique(path.feed[entry])
        said = ", ".join(f"F{float(f):g}" for f in feeds[:4]) + (" ..." if len(feeds) > 4 else "")
        why = (setup.blame("entry_feed_mm_min") if ef is not None and np.allclose(feeds, float(ef), rtol=1e-12, atol=0)
               else "the planned feed")
        notes.append(f"helix and ramp entries at {said} mm/min as planned ({why})")
    if arc_tol_mm is not None and arc_tol_mm <= 2 * 10.0 ** -decimals:
        notes.append(f"no arc fitting: tolerance {arc_tol_mm:g} mm not above 2 units of the {decimals}-decimal output")
    elif arc_tol_mm is not None:
        rapid = setup["rapid_mm_min"]
        walls = _walls(job, setup)
        tol, why = _fit_tolerance(arc_tol_mm, walls, job, decimals)
        path = fit_arcs(path, tol, decimals=decimals, rapid_arc_feed_mm_min=rapid, walls=walls)
        notes.append(f"arcs fitted within {tol:g} mm of the planned path{why}"
                     + (f" ({walls.slack_mm:g} mm beyond its clearance toward walls and islands)" if walls else "")
                     + (f", curved G0 runs in cleared area as G2/G3 at F{rapid:g}" if rapid else ""))
    return path, notes


def _program_moves(path: ToolPath, clearance_z: float, spindle_rpm: float, decimals: int) -> tuple:
    """Moves and comments: approach over the first point at the clearance plane, the path, retract."""
    xyz = path.xyz
    cz = math.ceil(clearance_z * 10 ** decimals - 1e-6) / 10 ** decimals   # rounded *up* to the written grid
    x0, y0, z0 = xyz[0]
    moves = [Move("G0", x0, y0, max(cz, z0), spindle=spindle_rpm)]
    comments = [""]
    first_feed = next((float(f) for f in path.feed if np.isfinite(f)), None)
    if z0 < clearance_z - _TOL:
        if path.kind[0] == 0 and path.cleared[0]:
            moves.append(Move("G0", x0, y0, z0, spindle=spindle_rpm)); comments.append(CLEARED_MARK)
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
        comments.append(CLEARED_MARK if path.cleared[k] else "")
    xe, ye, ze = xyz[-1]
    if ze < clearance_z:
        moves.append(Move("G0", xe, ye, cz, spindle=spindle_rpm)); comments.append("")
    return moves, comments


def _header(path: ToolPath, job, setup: _Setup, dialect: str, moves, notes, extra) -> list:
    cz, tz = float(setup["clearance_z"]), float(setup["top_z"] or 0.0)
    hdr = [f"cnclab program: mm, clearance plane Z{cz:g} mm, stock top Z{tz:g} mm",
           f"dialect {dialect}, written by cnclab {__version__}"]
    tool = setup["tool"]
    if tool is not None:
        shape = "ball end" if tool.corner_radius >= 0.5 * tool.diameter else (
            f"corner radius {tool.corner_radius:g} mm" if tool.corner_radius else "flat end")
        teeth = "tooth" if tool.flutes == 1 else "teeth"
        hdr.append(f"tool T{tool.number}: D{tool.diameter:g} mm {shape} mill, {tool.flutes} {teeth}")
    if job is not None and getattr(job, "polygon", None) is not None:
        x0, y0, x1, y1 = job.polygon.bounds
        hdr.append(f"stock: pocket X{x0:.3f}..{x1:.3f} Y{y0:.3f}..{y1:.3f} mm, depth {job.depth:g} mm below "
                   f"Z{tz:g} in levels of a_p {job.a_p:g} mm, job {Path(str(job.source)).name}")
    strategy = path.info.get("strategy") or path.info.get("planner")
    if strategy:
        hdr.append(f"strategy {strategy}")
    hdr += [str(n) for n in path.info.get("notes", ())]     # the planner's own notes (e.g. its narrow regions)
    rapid = setup["rapid_mm_min"] or RAPID_DEFAULT_MM_MIN
    t = program_time(moves, rapid)
    hdr.append(f"estimated run time {t['total_s'] / 60:.2f} min: feed moves {t['feed_s'] / 60:.2f} min at their F, "
               f"rapids {t['rapid_s'] / 60:.2f} min at {rapid:g} mm/min; length / feed, no acceleration")
    m = machine_for_dialect(dialect)
    hdr.append(f"estimated machine time {machine_time(moves, m)['time_machine_s'] / 60:.2f} min on the {m.name} "
               f"model: acceleration, junction deviation, G0 at its axis rates, cnclab.nc.machine")
    hdr = [h.replace("(", "[").replace(")", "]") for h in hdr + notes]   # RS274 comments cannot nest
    return hdr + ([extra] if isinstance(extra, str) and extra else list(extra or []))


#: rapid rate [mm/min] stated in the run-time estimate when neither the job nor the caller gives one
RAPID_DEFAULT_MM_MIN = 10000.0


def write_program(path: ToolPath, job=None, *, out=None, inputs=(), dialect: str = "linuxcnc", header=(),
                  decimals: int = 4, arc_tol_mm: float | None = DEFAULT_TOL_MM, coolant: str | None = None,
                  **values) -> str:
    """Program text of ``path`` (see the module docstring); with ``out`` also written to that file
    atomically (never over a file of ``inputs``) after :func:`check_program` passed it (nothing is
    written otherwise) — the one way a program reaches disk.

    ``job`` (a :class:`cnclab.toolpath.job.Job` or any object with the attributes) supplies the
    numbers; ``values`` override them: ``clearance_z`` [mm], ``top_z`` [mm] (default 0), ``tool``
    (default ``path.tool``), ``spindle_rpm`` [rpm] (default the path's first spindle speed),
    ``rapid_mm_min`` [mm/min] (curved G0 runs in cleared area become G2/G3 at this rate; run-time
    estimate). Every feed is written as the path has it (helix and ramp entries: the entry feed
    :func:`cnclab.toolpath.planners.plan` gave them, job key ``entry_feed_mm_min``). ``dialect``: ``"linuxcnc"`` (``%``
    lines, ``T.. M6`` then ``G43 H..``) or ``"grbl"`` (GRBL 1.1 words only: no ``%``, no ``M6``/``G43``,
    lines <= 80 characters, the tool named in a comment); ``coolant``: None, ``"flood"`` (M8) or
    ``"mist"`` (M7, linuxcnc only), on after the spindle, off (M9) before ``M5``; ``header`` extra
    comment lines; ``decimals`` digits of X Y Z I J [mm]; ``arc_tol_mm`` [mm] arc fitting tolerance
    (None: every move as planned). The header names the tool, stock, strategy, cnclab version,
    estimated run time, entry feed and arc tolerance.

    Raises ``ValueError`` for a rapid below the clearance plane that the path does not mark as
    cleared (naming the move), and for a number the program cannot carry, naming the job key (or
    parameter) that produced it: ``clearance_z``, ``top_z``, ``spindle_rpm`` (and ``v_c``),
    ``feed_mm_min`` (``f_z``, ``teeth``), ``link_feed``, ``entry_feed_mm_min``, ``rapid_mm_min``,
    ``a_p``/``depth``, ``tool_number`` (:data:`TOOL_NUMBER_RANGE`).
    """
    if dialect not in DIALECTS:
        raise ValueError(f"dialect must be one of {DIALECTS}, got {dialect!r}")
    if coolant is not None and (coolant not in COOLANT or (dialect == "grbl" and coolant == "mist")):
        ok = ["flood"] if dialect == "grbl" else sorted(COOLANT)
        raise ValueError(f"coolant must be None or one of {ok} for dialect {dialect}, got {coolant!r}")
    if len(path) == 0:
        raise ValueError("path has no moves")
    setup = _setup(path, job, values)
    if setup["clearance_z"] is None:
        raise ValueError("clearance_z must be a finite height in mm, got None (no job, no clearance_z)")
    if setup["spindle_rpm"] is None:
        raise ValueError("spindle_rpm must be a finite speed > 0 rpm (the program starts the spindle "
                         "before cutting), got None")
    _check_setup(setup, dialect, decimals)
    clearance_z, spindle = float(setup["clearance_z"]), float(setup["spindle_rpm"])
    _check_rapids(path, clearance_z)
    path, notes = _program_path(path, setup, arc_tol_mm, decimals, job)
    _check_path_numbers(path, setup, decimals)
    _check_depth(path, job, setup, decimals)
    moves, comments = _program_moves(path, clearance_z, spindle, decimals)
    hdr = _header(path, job, setup, dialect, moves, notes, header)
    text = _render(moves, comments, hdr, setup["tool"], dialect, decimals, coolant)
    if out is not None:
        chk = check_program(text, clearance_z, float(setup["top_z"] or 0.0), source=str(out))
        if chk.errors:
            raise ValueError(f"{out}: not written, the program fails the safety check: " + "; ".join(chk.errors[:5]))
        atomic_write(out, text, inputs=inputs)
    return text


def _render(moves, comments, hdr, tool, dialect, decimals, coolant) -> str:
    cool_on = [COOLANT[coolant]] if coolant else []
    cool_off = ["M9"] if coolant else []
    start = [START_BLOCK]
    if dialect == "linuxcnc":
        if tool is not None:
            start += [f"T{int(tool.number)} M6", f"G43 H{int(tool.number)}"]
        hdr = [piece for h in hdr for piece in textwrap.wrap(h, LINUXCNC_LINE_MAX - 2)]
        text = _write_gcode(moves, header=hdr, decimals=decimals, comments=comments, start_block=start,
                            end_block=["M30"], after_spindle_on=cool_on, before_spindle_off=cool_off)
        return _lines_within(text, LINUXCNC_LINE_MAX, "linuxcnc", "LinuxCNC's interpreter")
    if tool is not None:
        hdr = hdr + [f"load tool T{int(tool.number)} before running: GRBL has no tool change M6 and no G43"]
    hdr = [piece for h in hdr for piece in textwrap.wrap(h, GRBL_LINE_MAX - 2)]
    text = _write_gcode(moves, header=hdr, decimals=decimals, comments=comments, start_block=start,
                       end_block=["M30"], after_spindle_on=cool_on, before_spindle_off=cool_off, percent=False)
    return _lines_within(text, GRBL_LINE_MAX, "grbl", "GRBL 1.1")


def _lines_within(text: str, limit: int, dialect: str, reader: str) -> str:
    """``text`` when every line has at most ``limit`` characters, else ValueError naming the line (a
    controller refuses such a program: the header comments are wrapped to fit, so only a move or
    comment the writer cannot split gets here)."""
    for n, line in enumerate(text.splitlines(), 1):
        if len(line) > limit:
            raise ValueError(f"{dialect} line {n} has {len(line)} characters ({reader} reads at most "
                             f"{limit}): {line[:40]}...")
    return text


def _check_rapids(path: ToolPath, clearance_z: float) -> None:
    """Refuse a rapid below the clearance plane that is not straight up nor marked cleared."""
    rapid = path.is_kind("rapid")
    xyz = path.xyz
    for k in np.flatnonzero(rapid)[np.flatnonzero(rapid) > 0]:
        a, b = xyz[k - 1], xyz[k]
        above = min(a[2], b[2]) >= clearance_z - _TOL
        straight_up = b[2] >= a[2] and math.hypot(*(b[:2] - a[:2])) <= _TOL
        if not (above or straight_up or path.cleared[k]):
            raise ValueError(f"move {k}: rapid from z {a[2]:g} to z {b[2]:g} mm below the clearance plane "
                             f"z {clearance_z:g} mm, not marked as inside cleared area (ToolPath.cleared)")


# --------------------------------------------------------------------------------------------
# text: the one G-code text writer (private) and its entries for programs given move by move
# --------------------------------------------------------------------------------------------
def _fmt(v: float, decimals: int) -> str:
    s = f"{v:.{decimals}f}"
    if s.startswith("-") and float(s) == 0.0:
        s = s[1:]
    return s




def _check_value(k: int, word: str, v, bound: float, positive: bool = False) -> float:
    if v is None or not math.isfinite(float(v)):
        raise ValueError(f"move {k}: word {word} must be a finite number, got {word}{v!r}")
    v = float(v)
    if abs(v) > bound or (positive and v <= 0):
        rng = f"(0, {bound:g}]" if positive else f"[-{bound:g}, {bound:g}]"
        raise ValueError(f"move {k}: word {word}{v:g} out of range {rng}")
    return v


def _write_gcode(moves: Iterable[Move], header: str | Sequence[str] = "", decimals: int = 4,
                 feed_decimals: int = 1, comments: Sequence[str] | None = None,
                 start_block: Sequence[str] = ("G21 G90 G17 G94",), end_block: Sequence[str] = ("M30",),
                 after_spindle_on: Sequence[str] = (), before_spindle_off: Sequence[str] = (),
                 percent: bool = True) -> str:
    """RS274/NGC text of ``moves`` (the conventions of :mod:`cnclab.nc.gcode`): the one text writer,
    used by :func:`write_program` and :func:`write_moves`.

    ``header``: comment text (a string with newlines or a list of lines), written as ``( ... )``;
    ``decimals``: digits after the point for X Y Z I J [mm]; ``feed_decimals`` for F [mm/min] and S
    [rpm]; ``comments``: optional text per move, appended to its block as ``( ... )``;
    ``start_block``/``end_block``: lines written before the first/after the last move (``M5`` is
    written before the end block whenever the spindle is on); ``after_spindle_on`` lines follow every
    ``S.. M3`` that starts the spindle, ``before_spindle_off`` lines precede every ``M5`` (coolant
    M8/M9); ``percent``: the ``%`` first and last lines (False for controllers that do not read them).

    Refuses (``ValueError`` naming the move index and word) a non-finite or out-of-range number
    (:data:`MAX_COORD_MM`, :data:`MAX_FEED_MM_MIN`, :data:`MAX_SPINDLE_RPM`) and an arc whose start and
    end radii, computed from the *written* numbers, differ by more than 2·10^-decimals mm (then the
    file would not describe the arc the path means; a reader would refuse or distort it).
    """
    if not isinstance(decimals, int) or not 0 <= decimals <= 8:
        raise ValueError(f"decimals must be an int in [0, 8], got {decimals!r}")
    lines = ["%"] if percent else []
    hdr = header.splitlines() if isinstance(header, str) else list(header)
    for h in hdr:
        if "(" in h or ")" in h:
            raise ValueError(f"header lines cannot contain parentheses, got {h!r}")
        lines.append(f"({h})")
    lines += list(start_block)
    cur = {"X": None, "Y": None, "Z": None}
    motion = feed = spindle = None
    arc_tol = 2.0 * 10.0 ** -decimals
    for k, mv in enumerate(moves):
        if not isinstance(mv, Move):
            raise ValueError(f"moves[{k}] must be a Move, got {type(mv).__name__}")
        for ax, v in (("X", mv.x), ("Y", mv.y), ("Z", mv.z)):
            _check_value(k, ax, v, MAX_COORD_MM)
        if mv.motion != "G0":
            _check_value(k, "F", mv.feed, MAX_FEED_MM_MIN, positive=True)
        if mv.spindle is not None:
            _check_value(k, "S", mv.spindle, MAX_SPINDLE_RPM)
        start_w = dict(cur)
        axes = [(ax, _fmt(v, decimals)) for ax, v in (("X", mv.x), ("Y", mv.y), ("Z", mv.z))]
        axes = [(ax, s) for ax, s in axes if s != cur[ax]]
        if not axes and mv.motion in ("G0", "G1"):
            continue  # zero-length move after rounding: nothing to say, modal state untouched
        sp = None if mv.spindle is None else _fmt(mv.spindle, 0)
        if sp != spindle:   # spindle off (coolant off first), on (coolant after) or a new speed
            lines += list(before_spindle_off) + ["M5"] if sp is None else [f"S{sp} M3"] + (
                list(after_spindle_on) if spindle is None else [])
            spindle = sp
        words = []
        if mv.motion != motion or mv.motion in ("G2", "G3"):
            words.append(mv.motion)
            motion = mv.motion
        for ax, s in axes:
            words.append(ax + s)
            cur[ax] = s
        if mv.motion in ("G2", "G3"):
            iw, jw = _fmt(_check_value(k, "I", mv.i, MAX_COORD_MM), decimals), \
                _fmt(_check_value(k, "J", mv.j, MAX_COORD_MM), decimals)
            if start_w["X"] is None or start_w["Y"] is None:
                raise ValueError(f"move {k}: word {mv.motion}: an arc cannot be the first move (start unknown)")
            sx, sy = float(start_w["X"]), float(start_w["Y"])
            r0 = math.hypot(float(iw), float(jw))
            r1 = math.hypot(float(cur["X"]) - sx - float(iw), float(cur["Y"]) - sy - float(jw))
            if r0 == 0 or abs(r0 - r1) > arc_tol:
                raise ValueError(f"move {k}: word {mv.motion}: written arc start radius {r0:.6g} and end radius "
                                 f"{r1:.6g} mm differ by more than {arc_tol:g} mm (2 units of the last "
                                 "written digit)")
            words += ["I" + iw, "J" + jw]
        if mv.motion != "G0":
            f = _fmt(mv.feed, feed_decimals)
            if f != feed:
                words.append("F" + f)
                feed = f
        line = " ".join(words)
        if comments is not None and comments[k]:
            c = str(comments[k])
            if "(" in c or ")" in c:
                raise ValueError(f"move {k}: comment cannot contain parentheses, got {c!r}")
            line += f" ({c})"
        lines.append(line)
    if spindle is not None:
        lines += list(before_spindle_off) + ["M5"]
    lines += list(end_block) + (["%"] if percent else [])
    return "\n".join(lines) + "\n"


def _write_gcode_linear(xyz, rapid, feed, spindle, header: str | Sequence[str] = "", decimals: int = 4,
                        feed_decimals: int = 1) -> str:
    """:func:`_write_gcode` of linear moves given as arrays, byte-identical and ~50x faster.

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
        raise ValueError("write_linear_moves: a G1 move has no feed")
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

def write_moves(moves: Iterable[Move], header: str | Sequence[str] = "", decimals: int = 4, feed_decimals: int = 1,
                comments: Sequence[str] | None = None, *, out=None, inputs=()) -> str:
    """Text of a motion program given move by move, written as it is (no approach, clearance plane
    or tool block): ``%``, the ``header`` comments, ``G21 G90 G17 G94``, the moves with modal words
    (``S.. M3`` where the spindle speed ``Move.spindle`` [rpm] first appears or changes, F [mm/min]
    where the feed changes), ``M5``, ``M30``, ``%``; with ``out`` also written atomically (never
    over a file of ``inputs``). For converters and post-processors whose input already is a whole
    program (an APT CL file with its SPINDL/FEDRAT records, :mod:`cnclab.nc.spindle_control`); a
    planned :class:`~cnclab.toolpath.path.ToolPath` goes through :func:`write_program`.

    ``decimals`` digits of X Y Z I J [mm], ``feed_decimals`` of F; ``comments`` optional text per
    move. Refuses (``ValueError`` naming the move index and word) a non-finite or out-of-range number
    and an arc whose written start and end radii differ by more than 2 units of the last digit.

    >>> text = write_moves([Move("G0", 0, 0, 5), Move("G1", 0, 0, -1, feed=200, spindle=3000)], header="demo")
    >>> print(text)   # doctest: +NORMALIZE_WHITESPACE
    %
    (demo)
    G21 G90 G17 G94
    G0 X0.0000 Y0.0000 Z5.0000
    S3000 M3
    G1 Z-1.0000 F200.0
    M5
    M30
    %
    >>> write_moves(parse_gcode(text), header="demo") == text    # the reader reads back what is written
    True
    """
    text = _write_gcode(moves, header=header, decimals=decimals, feed_decimals=feed_decimals, comments=comments)
    if out is not None:
        atomic_write(out, text, inputs=inputs)
    return text


def write_linear_moves(xyz, rapid, feed, spindle, header: str | Sequence[str] = "", decimals: int = 4,
                       feed_decimals: int = 1, *, out=None, inputs=()) -> str:
    """:func:`write_moves` of linear moves given as arrays (same bytes, ~50x faster): ``xyz`` (n, 3)
    end points [mm], ``rapid`` (n,) bool (G0 vs G1), ``feed`` (n,) [mm/min] (NaN for G0 only),
    ``spindle`` (n,) [rpm] (NaN = off); with ``out`` also written atomically.

    >>> lin = write_linear_moves([[0, 0, 5], [0, 0, -1]], [True, False], [np.nan, 200], [np.nan, 3000])
    >>> lin == write_moves([Move("G0", 0, 0, 5), Move("G1", 0, 0, -1, feed=200, spindle=3000)])
    True
    """
    text = _write_gcode_linear(xyz, rapid, feed, spindle, header=header, decimals=decimals,
                               feed_decimals=feed_decimals)
    if out is not None:
        atomic_write(out, text, inputs=inputs)
    return text


def gcode_roundtrip_error(path, job=None, feeds=None, decimals=4):
    """Write a :class:`~cnclab.toolpath.path.ToolPath` as G-code (:meth:`ToolPath.to_moves`), parse it
    back and compare: (max distance mm of the parsed end points from the path points, feed-length
    difference mm, text) — the parsed program must reproduce the path within the written decimals.
    ``job`` and ``feeds`` are not used (kept for the call signature)."""
    name = str(path.info.get("name", "path"))
    moves = path.to_moves()
    text = write_moves(moves, header="cnclab " + name.replace("(", "").replace(")", ""), decimals=decimals)
    back = parse_gcode(text, source=name)
    P = np.array([m.xyz for m in back])
    from scipy.spatial import cKDTree      # imported here: the writers and readers do not need scipy

    d, _ = cKDTree(path.xyz).query(P)
    dl = abs(path_lengths(back)["feed"] - path_lengths(moves)["feed"])
    return float(d.max()), float(dl), text
