"""The APT CL reader (:func:`parse_apt`, :func:`read_apt`): the careful per-line parser and the bulk
reader of plain ``GOTO`` runs (see :mod:`cnclab.nc.apt` for the dialect; import from there).
"""
from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
from numba import njit

from .apt_records import NUMBER_RE, REFUSED_MOTION, WORD_RE, AptError, AptProgram, AptRecord, GotoRun

__all__ = ["parse_apt", "read_apt"]


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
        elif not WORD_RE.fullmatch(t):
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
        if not WORD_RE.fullmatch(head):
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
