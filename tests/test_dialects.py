"""Program dialects (linuxcnc, grbl), header, entry feed and writer limits named by job keys
(cnclab.nc.program.write_program)."""
import json
import re

import numpy as np
import pytest

from cnclab.nc.gcode import read_gcode
from cnclab.nc.program import (ENTRY_FEED_FRACTION, GRBL_LINE_MAX, LINUXCNC_LINE_MAX, check_program, program_path,
                               write_program)
from cnclab.paths import data_path
from cnclab.toolpath.job import Job
from cnclab.toolpath.levels import with_entry_feed
from cnclab.toolpath.path import Tool, ToolPath

GRAMMAR = json.loads(data_path("nc", "grbl11_grammar.json").read_text(encoding="utf-8"))


def _job(**kw):
    d = {"polygon": [[0, 0], [40, 0], [40, 30], [0, 30]], "tool_diameter": 6, "theta_deg": 60, "a_p": 2,
         "v_c": 120, "f_z": 0.04, "teeth": 2, "tool_number": 7, "start_hole": {"center": [20, 15], "diameter": 8}}
    d.update(kw)
    return Job.from_dict(d, source="job.json")


def _path(job=None):
    """Helix entry at the start hole (lines, as planners sample it), a cut, a cleared rapid, a link."""
    a = np.linspace(0, 4 * np.pi, 161)
    helix = np.column_stack([20 + 2 * np.cos(a), 15 + 2 * np.sin(a), np.linspace(0, -2, 161)])
    pts = np.vstack([[22, 15, 1], helix, [[30, 15, -2], [30, 20, -2], [25, 20, -2], [25, 20, 5]]])
    kind = ["rapid"] + ["helix"] * 161 + ["cut", "cut", "rapid", "retract"]
    tag = [""] * 164 + ["cleared"] + [""]
    return ToolPath.build(pts, kind=kind, tag=tag, feed=500.0, tool=Tool(6, flutes=2, number=7),
                          info={"strategy": "test"}, cleared=[t == "cleared" for t in tag])


def _grbl_words():
    g = {w for grp in GRAMMAR["modal_groups"].values() for w in grp} | set(GRAMMAR["non_modal"])
    return g - set(GRAMMAR["not_default_build"])


def _code(letter, num):
    v = float(num)
    return f"{letter}{int(v)}" if v.is_integer() else f"{letter}{v:g}"


def test_grbl_output_only_uses_grbl11_words():
    """Every block of a GRBL program uses only G/M words of GRBL 1.1's documented grammar (modal
    groups of gnea/grbl doc/markdown/commands.md, default build), value words it reads, no %,
    O-words or parameters, lines <= 80 characters, T <= 255; it reads back and passes the checker."""
    job = _job()
    text = write_program(_path(job), job, dialect="grbl", coolant="flood")
    allowed, values = _grbl_words(), set(GRAMMAR["value_words"])
    for n, line in enumerate(text.splitlines(), 1):
        assert len(line) <= GRAMMAR["line_max_chars"] == GRBL_LINE_MAX, (n, line)
        body = re.sub(r"\([^)]*\)", "", line).split(";")[0].strip()
        assert not re.search(r"[%#\[\]Oo]", body), (n, line)
        for letter, num in re.findall(r"([A-Za-z])\s*([-+]?\d*\.?\d+)", body):
            letter = letter.upper()
            if letter in "GM":
                assert _code(letter, num) in allowed, (n, line)
            else:
                assert letter in values, (n, line)
                if letter == "T":
                    assert 0 <= float(num) <= GRAMMAR["max_tool_number"]
    blocks = "\n".join(re.sub(r"\([^)]*\)", "", ln) for ln in text.splitlines())
    assert "M6" not in blocks and "G43" not in blocks and "%" not in blocks
    assert "(load tool T7 before running" in text
    assert check_program(text, clearance_z=job.clearance_z).ok


def test_linuxcnc_tool_change_length_offset_and_coolant():
    job = _job()
    lines = write_program(_path(job), job, coolant="mist").splitlines()
    i = lines.index("T7 M6")
    assert lines[i + 1] == "G43 H7"
    s = next(k for k, ln in enumerate(lines) if ln.startswith("S") and ln.endswith("M3"))
    assert s > i + 1 and lines[s + 1] == "M7"
    assert lines[-5:] == ["G1 Z5.0000", "M9", "M5", "M30", "%"]   # the path's own retract, then coolant off
    with pytest.raises(ValueError, match="coolant"):
        write_program(_path(job), job, dialect="grbl", coolant="mist")     # M7 off in GRBL's default build


def test_header_names_tool_stock_strategy_version_time_tolerance():
    from cnclab import __version__

    job = _job()
    text = write_program(_path(job), job)
    head = "\n".join(ln for ln in text.splitlines() if ln.startswith("("))
    for piece in ("tool T7: D6 mm flat end mill, 2 teeth", "stock: pocket X0.000..40.000 Y0.000..30.000 mm, depth 2 mm",
                  "job job.json", "strategy test", f"cnclab {__version__}", "estimated run time",
                  "arcs fitted within 0.005 mm", "entries at F"):
        assert piece in head, piece
    # the stated run time is the written program's (length / feed)
    m = re.search(r"estimated run time ([0-9.]+) min", head)
    t = program_path(_path(job), job).time_s(job.rapid_mm_min)["total_s"] / 60
    assert float(m.group(1)) == pytest.approx(t, abs=0.02)


def test_entry_feed_default_fraction_and_job_key():
    """plan gives helix/ramp entries the job's entry feed (ENTRY_FEED_FRACTION x feed_mm_min, or the
    job key entry_feed_mm_min); the writer writes them as planned, and a path not from plan keeps its feeds."""
    from cnclab.toolpath.planners import plan

    import dataclasses

    job = _job()
    p = plan(dataclasses.replace(job, start_hole=None), "adaptive", resolution_mm=0.1)   # enters by helix
    entry = p.is_kind("helix", "ramp")
    assert entry.any() and set(p.feed[entry]) == {ENTRY_FEED_FRACTION * job.feed_mm_min} == {job.entry_feed}
    assert p.info["entry_feed_mm_min"] == job.entry_feed
    helix_feeds = {m.feed for m in read_gcode(write_program(with_entry_feed(_path(job), job), job)).moves
                   if m.motion in ("G2", "G3")}
    assert helix_feeds == {round(ENTRY_FEED_FRACTION * job.feed_mm_min, 1)}
    job2 = _job(entry_feed_mm_min=111.0)
    assert Job.from_dict(job2.to_dict()).entry_feed_mm_min == 111.0 == job2.entry_feed
    text = write_program(with_entry_feed(_path(job2), job2), job2)
    assert {m.feed for m in read_gcode(text).moves if m.motion in ("G2", "G3")} == {111.0}
    assert "entry_feed_mm_min" in text
    # the writer changes no feed: the helix of a path built at F500 is written at F500
    assert {m.feed for m in read_gcode(write_program(_path(job2), job2)).moves if m.motion in ("G2", "G3")} == {500.0}


@pytest.mark.parametrize("change, key", [
    ({"tool_number": 10 ** 20}, "tool_number"),
    ({"tool_number": 0}, "tool_number"),
    ({"feed_mm_min": 0.01}, "feed_mm_min"),
    ({"f_z": 1e-9}, "feed_mm_min"),
    ({"link_feed": 0.001}, "link_feed"),
    ({"entry_feed_mm_min": 0.02}, "entry_feed_mm_min"),
    ({"v_c": 1e-7}, "spindle_rpm"),
    ({"spindle_rpm": 2e6}, "spindle_rpm"),
    ({"clearance_z": 1e5}, "clearance_z"),
    ({"rapid_mm_min": 1e9}, "rapid_mm_min"),
])
def test_writer_limits_name_the_job_key(change, key):
    """A number the program cannot carry is refused with the job key that produced it (not the
    reader's 'prog.ngc:N: word F0.0'), by the writer or already by the job loader."""
    with pytest.raises(ValueError, match=re.escape(key)) as err:
        job = _job(**change)          # the job loader's plausibility checks may refuse it first
        write_program(with_entry_feed(_path(job), job), job)
    assert "job.json" in str(err.value) or key == "tool_number"


def test_tool_number_range_per_dialect():
    job = _job(tool_number=300)
    path = _path(job)
    path.tool = job.tool
    assert "T300 M6" in write_program(path, job)
    with pytest.raises(ValueError, match=r"tool_number = 300 .* grbl T word range \[0, 255\]"):
        write_program(path, job, dialect="grbl")


def test_depth_rounding_to_the_stock_top_names_a_p():
    job = _job(a_p=1e-6)
    p = ToolPath.build([[5, 5, 5], [5, 5, -1e-6], [30, 5, -1e-6], [30, 5, 5]],
                       kind=["rapid", "plunge", "cut", "retract"], tag=["", "cleared", "", ""], feed=300.0,
                       cleared=[False, True, False, False])
    with pytest.raises(ValueError, match="a_p = 1e-06 mm"):
        write_program(p, job)


def test_link_feed_of_a_path_traced_to_link_feed():
    job = _job()
    p = _path(job)
    p.kind[-3] = 5      # the cut becomes a link with a feed that cannot be written
    p.feed[-3] = 0.01
    with pytest.raises(ValueError, match="move .* \\(link\\).*link_feed = 1500"):
        write_program(p, job)


@pytest.mark.parametrize("dialect, limit", [("linuxcnc", LINUXCNC_LINE_MAX), ("grbl", GRBL_LINE_MAX)])
def test_long_header_lines_are_wrapped_within_the_controller_line_limit(dialect, limit, tmp_path):
    """A header line longer than the controller reads (a planner's note about a part it left runs to
    ~300 characters) is wrapped into comment lines of at most ``limit`` characters, every word kept;
    LinuxCNC's ``rs274`` reads the result (it refuses a line of 253 characters: "Command too long"),
    when installed."""
    from cnclab.nc.rs274 import rs274_available, run_rs274

    job = _job()
    note = "level z -2: a part of the tool-centre region near [3.60, 3.60] " + "word " * 60 + "END"
    text = write_program(_path(job), job, header=[note], dialect=dialect)
    assert max(len(line) for line in text.splitlines()) <= limit
    words = " ".join(re.findall(r"\(([^)]*)\)", text)).split()
    assert words.count("word") == 60 and "END" in words
    if dialect == "linuxcnc" and rs274_available():
        p = tmp_path / "long.ngc"
        p.write_text(text)
        run_rs274(p)
