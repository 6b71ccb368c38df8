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
