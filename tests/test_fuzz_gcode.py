"""Corrupted G-code (issue 15): mutations of real programs (a FreeCAD Adaptive post output, a
hand-written inch/helix program, one of ours) must give a GcodeError/ValueError naming the source and
line, or a program whose every move is finite and whose motion time is finite and non-negative.

Mutations: byte flips, truncation, a line duplicated, removed or swapped, a number replaced by a
hostile token (nan, inf, 1e999, full-width digits, 2_0, hex, empty). Hypothesis settings follow the
conftest profile (derandomised in CI).
"""
import math
import re
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cnclab.nc.gcode import GcodeError, parse_gcode, program_time

FIX = Path(__file__).parent / "fixtures"
SOURCES = [FIX / "freecad" / "star_pocket_adaptive_linuxcnc.ngc", FIX / "nc" / "handwritten_inch_helix.ngc",
           FIX / "nc" / "hoang2024_table3.ngc"]
TEXTS = {p.name: p.read_text(encoding="utf-8") for p in SOURCES}
HOSTILE = ["nan", "inf", "-inf", "1e999", "１２", "2_0", "0x1A", "", "--1", "1.2.3", "1e-400"]
_NUM = re.compile(r"(?<=[XYZIJKRFS])[-+]?\d*\.?\d+")


def _check(text: str, name: str):
    try:
        moves = parse_gcode(text, source=name)
    except (GcodeError, ValueError) as exc:
        assert re.search(re.escape(name) + r":\d+", str(exc)), f"error does not name {name}:line: {exc}"
        return "error"
    for m in moves:
        assert all(math.isfinite(v) for v in (m.x, m.y, m.z)), m
        assert m.feed is None or (math.isfinite(m.feed) and m.feed > 0), m
    if moves:
        t = program_time(moves, 10000.0)
        assert math.isfinite(t["total_s"]) and t["total_s"] >= 0
    return "ok"


def test_the_sources_read_cleanly():
    assert all(_check(t, n) == "ok" for n, t in TEXTS.items())


@settings(max_examples=150, deadline=None)
@given(src=st.sampled_from(sorted(TEXTS)), data=st.data())
def test_mutated_programs_error_with_line_or_read_correctly(src, data):
    text = TEXTS[src]
    lines = text.splitlines(True)
    kind = data.draw(st.sampled_from(["flip", "truncate", "dup", "drop", "swap", "number"]))
    if kind == "flip":
        b = bytearray(text.encode("utf-8"))
        i = data.draw(st.integers(0, len(b) - 1))
        b[i] = data.draw(st.integers(0, 255))
        text = b.decode("utf-8", errors="replace")
    elif kind == "truncate":
        text = text[:data.draw(st.integers(0, len(text)))]
    elif kind in ("dup", "drop", "swap"):
        i = data.draw(st.integers(0, len(lines) - 1))
        j = data.draw(st.integers(0, len(lines) - 1))
        if kind == "dup":
            lines.insert(j, lines[i])
        elif kind == "drop":
            del lines[i]
        else:
            lines[i], lines[j] = lines[j], lines[i]
        text = "".join(lines)
    else:
        nums = list(_NUM.finditer(text))
        if nums:
            m = nums[data.draw(st.integers(0, len(nums) - 1))]
            text = text[:m.start()] + data.draw(st.sampled_from(HOSTILE)) + text[m.end():]
    _check(text, "fuzz.ngc")


@pytest.mark.parametrize("token", HOSTILE)
def test_hostile_number_in_a_feed_move_is_refused_with_its_line(token):
    text = "G21 G90 G17\nS1000 M3\nG0 X0 Y0 Z5\nG1 Z0 F100\nG1 X" + token + " Y1\nM5 M30\n"
    assert _check(text, "hostile.ngc") == "error"


# --- hostile programs for ``cnclab analyze`` (issue 28 item 7) ------------------------------------
# Families generated from one clean program by a seeded generator (not a copied list): truncation,
# binary bytes, text encodings, huge coordinates, blocks after the closing %, tool changes, lines
# duplicated/dropped. Every case runs ``python -m cnclab analyze`` in process and must end in
#   error    exit 2, a message naming the program (file:line where a line is at fault), the job or the
#            option; no output folder created;
#   verified exit 0 with all six outputs whose figures are checked against independent computations
#            (wall gouge by brute force over the program's segments, lengths by gcode.path_lengths,
#            every line number of trace.csv/events.csv a motion line of the program),
# and the program and job files unchanged. Counts by family and outcome are printed (pytest -s).
import collections
import hashlib
import json
import os
import math as _math
import random

import numpy as np
import pandas as pd
import shapely

from cnclab.nc import cli_analyze
from cnclab.nc.gcode import path_lengths, read_gcode

ANALYZE_OUTCOMES: collections.Counter = collections.Counter()
_POCKET = {"polygon": [[0, 0], [30, 0], [30, 20], [0, 20]], "islands": [[[20, 8], [24, 8], [24, 12], [20, 12]]],
           "tool_diameter": 6.0, "teeth": 2, "v_c": 120.0, "f_z": 0.04, "feed_mm_min": 500.0, "a_p": 1.0,
           "theta_deg": 60.0, "start_hole": {"center": [10, 10], "diameter": 11.0}}
H = 0.25        # analyze resolution of the fuzz runs (mm): D/24, coarse and quick


def _clean_program() -> str:
    """Helix in the start hole, loops (G3 half arcs), a lap that passes 1 mm from the island, a
    retract: a small but complete program (mm)."""
    out = ["%", "(T1 D=6 flat end mill)", "G21 G90 G17 G94", "T1 M6", "G0 X12.0000 Y10.0000 Z5.0000", "S6000 M3",
           "G1 Z0.5000 F500.0", "G3 X8.0000 Y10.0000 Z0.0000 I-2.0000 J0.0000 F250.0",
           "G3 X12.0000 Y10.0000 Z-1.0000 I2.0000 J0.0000", "G3 X8.0000 Y10.0000 I-2.0000 J0.0000 F500.0",
           "G3 X12.0000 Y10.0000 I2.0000 J0.0000"]
    for rad in (3.0, 4.0, 5.0, 6.0):
        out += [f"G1 X{10 + rad:.4f} Y10.0000", f"G3 X{10 - rad:.4f} Y10.0000 I{-rad:.4f} J0.0000",
                f"G3 X{10 + rad:.4f} Y10.0000 I{rad:.4f} J0.0000"]
    out += ["G1 X16.0000 Y3.0000", "G1 X27.0000 Y3.0000", "G1 X27.0000 Y17.0000", "G1 X3.0000 Y17.0000",
            "G1 X3.0000 Y3.0000", "G1 X16.0000 Y3.0000", "G0 Z5.0000", "M5", "M30", "%"]
    return "\n".join(out) + "\n"


CLEAN = _clean_program()


def _hostile_programs(seed: int = 2028, per_family: int = 4):
    """(family, name, bytes) cases, ``per_family`` per family, from a seeded generator."""
    rnd = random.Random(seed)
    lines = CLEAN.splitlines(True)
    motion = [k for k, ln in enumerate(lines) if ln[:2] in ("G0", "G1", "G3")]
    raw = CLEAN.encode()
    for i in range(per_family):
        cut = rnd.randrange(1, len(raw))
        yield "truncation", f"cut at byte {cut}", raw[:cut]
        pos = rnd.randrange(len(raw))
        byte = rnd.choice([0, 0x80, 0xC3, 0xE9, 0xFF, 0x1B])
        yield "binary", f"byte {byte:#x} at {pos}", raw[:pos] + bytes([byte]) + raw[pos:]
        enc = ["latin-1 comment", "utf-16", "utf-8 bom", "utf-8 comment"][i % 4]
        text = CLEAN.replace("(T1 D=6 flat end mill)", "(T1 D=6 fraise \u00e0 bout plat)")
        data = {"latin-1 comment": lambda: text.encode("latin-1"), "utf-16": lambda: CLEAN.encode("utf-16"),
                "utf-8 bom": lambda: b"\xef\xbb\xbf" + raw, "utf-8 comment": lambda: text.encode("utf-8")}[enc]()
        yield "encoding", enc, data
        k = rnd.choice(motion)
        big = rnd.choice(["1e6", "-1e30", "1e300", "1000", "-250.5"])
        ln = lines[k]
        mutated = ln.replace("X", "X" + big + " (", 1).replace(" Y", ") Y", 1) if "X" in ln else ln.replace("Z", "Z" + big + " (", 1).rstrip("\n") + ")\n"
        yield "huge coordinate", f"line {k + 1} -> {big}", "".join(lines[:k] + [mutated] + lines[k + 1:]).encode()
        junk = rnd.choice(["G0 X1000 Y1000 Z-50\n", "#<x> = [1/0]\n", "\x00\x01garbage\n", "O100 sub\n", "%\n%\n"])
        yield "after closing %", f"{junk!r}", (CLEAN + junk).encode("utf-8", "surrogateescape")
        k = rnd.choice(motion[2:])
        tc = rnd.choice(["T2 M6\n", "T2 M6 (D=10 mm)\n", "M6 T3\n", "T99999999999 M6\n"])
        yield "tool change", f"{tc.strip()} before line {k + 1}", "".join(lines[:k] + [tc] + lines[k:]).encode()
        a, b = rnd.randrange(len(lines)), rnd.randrange(len(lines))
        op = rnd.choice(["dup", "drop", "swap"])
        ls = list(lines)
        if op == "dup":
            ls.insert(b, ls[a])
        elif op == "drop":
            del ls[a]
        else:
            ls[a], ls[b] = ls[b], ls[a]
        yield "lines", f"{op} {a + 1} {b + 1}", "".join(ls).encode()


HOSTILE_PROGRAMS = list(_hostile_programs())


def _sha(p):
    return hashlib.sha256(p.read_bytes()).hexdigest()


def _brute_gouge(moves, r, poly, top=0.0, step=0.02):
    """max(0, r - signed distance of the tool centre to the pocket boundary) over every move below the
    stock top, lines sampled every ``step`` mm (arcs by their chords <= step): independent of the
    evaluator's sampling."""
    from cnclab.nc.gcode import sample_move
    worst, cur = 0.0, None
    for mv in moves:
        if cur is not None:
            p = sample_move(cur, mv, step)
            seg = np.vstack([p[k - 1] + t[:, None] * (p[k] - p[k - 1]) for k in range(1, len(p))
                             for t in [np.linspace(0, 1, max(2, int(np.linalg.norm(p[k] - p[k - 1]) / step) + 2))]])
            low = seg[seg[:, 2] < top - 1e-9]
            if len(low):
                d = shapely.distance(poly.boundary, shapely.points(low[:, :2]))
                d = np.where(shapely.contains_xy(poly, low[:, 0], low[:, 1]), d, -d)
                worst = max(worst, r - float(d.min()))
        cur = mv.xyz
    return max(worst, 0.0)


def _verify_result(prog, job, out):
    from cnclab.toolpath.job import load_job
    summ = pd.read_csv(out / "summary.csv")
    ev = dict(zip(summ.metric, summ.value.astype(float)))
    assert sorted(p.name for p in out.iterdir()) == sorted(cli_analyze.OUTPUT_NAMES)
    text = prog.read_bytes().decode("utf-8")
    g = read_gcode(text, source=str(prog))
    motion_lines = set(g.lines)
    tr = pd.read_csv(out / "trace.csv")
    assert set(tr["line"]) <= motion_lines
    ec = pd.read_csv(out / "events.csv")
    assert set(ec["line"]) <= motion_lines
    L = path_lengths(g.moves)
    got = ev["cut_length_mm"] + ev["link_length_mm"] + ev["entry_length_mm"] + ev["retract_length_mm"]
    assert got == pytest.approx(L["feed"], rel=1e-9, abs=1e-9)
    assert ev["rapid_length_mm"] == pytest.approx(L["rapid"], rel=1e-9, abs=1e-9)
    jb = load_job(job)
    brute = _brute_gouge(g.moves, jb.tool_radius, jb.polygon, jb.top_z)
    # the evaluator samples every <= H mm along the path: it may miss the worst point by H/2 along a
    # move (gouge changes by at most 1 mm per mm of travel); the brute force by 0.01 mm
    assert abs(ev["wall_gouge_max_mm"] - brute) <= 0.5 * H + 0.011, (ev["wall_gouge_max_mm"], brute)
    assert set(summ.metric) >= {"wall_gouge_max_mm", "wall_gouge_area_mm2", "gouges", "engagement_p50_deg"}


@pytest.mark.parametrize("case", range(len(HOSTILE_PROGRAMS)),
                         ids=[f"{f}: {n}"[:60] for f, n, _ in HOSTILE_PROGRAMS])
def test_analyze_hostile_programs(tmp_path, capsys, case):
    family, name, data = HOSTILE_PROGRAMS[case]
    prog, job, out = tmp_path / "prog.ngc", tmp_path / "job.json", tmp_path / "out"
    prog.write_bytes(data)
    job.write_text(json.dumps(_POCKET))
    before = {p: _sha(p) for p in (prog, job)}
    rc = cli_analyze.main([str(prog), "--job", str(job), "--resolution", str(H), "-o", str(out)])
    cap = capsys.readouterr()
    assert {p: _sha(p) for p in (prog, job)} == before, "an input was modified"
    assert not [f for f in os.listdir(tmp_path) if ".tmp" in f]
    if rc == 2:
        msg = cap.err.strip()
        assert msg.startswith("error: ") and (f"{prog}" in msg or "--resolution" in msg), msg
        assert "codec" not in msg and "Traceback" not in msg and "Errno" not in msg, msg
        assert not out.exists(), "outputs written on error"
        outcome = "error"
    else:
        assert rc == 0, cap.err
        _verify_result(prog, job, out)
        outcome = "verified" + (" with warnings" if "warning:" in cap.out else "")
    ANALYZE_OUTCOMES[(family, outcome)] += 1


def test_zz_report_analyze_fuzz_counts():
    """Counts by family and outcome of the hostile-program cases (printed with pytest -s)."""
    by = collections.Counter()
    for (fam, outcome), v in sorted(ANALYZE_OUTCOMES.items()):
        print(f"analyze fuzz  {fam:<16} {outcome:<22} {v}")
        by[outcome] += v
    print("analyze fuzz by outcome:", dict(by))
    if ANALYZE_OUTCOMES:
        assert sum(by.values()) <= len(HOSTILE_PROGRAMS)
