"""Machine-safe programs (cnclab.nc.program): start block, spindle, clearance rapids, end, checker."""
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cnclab.nc.gcode import parse_gcode, program_time, read_gcode
from cnclab.nc.program import CLEARED_MARK, START_BLOCK, check_program, cleared_mark, write_program
from cnclab.toolpath.path import Tool, ToolPath

FREECAD = Path(__file__).parent / "fixtures" / "freecad"


def _pocket_path(tag_rapid=""):
    """Helix entry at (0,0), a cut, a rapid at depth (flagged cleared when ``tag_rapid`` is
    ``"cleared"``, the tag text as given), a cut, retract."""
    pts = [[3, 0, 1], [3, 0, -0.75], [3, 0, -1.5], [13, 0, -1.5], [13, 5, -1.5], [20, 5, -1.5], [20, 5, 2]]
    kind = ["rapid", "helix", "helix", "cut", "rapid", "cut", "retract"]
    arc = [0, 3, 3, 0, 0, 0, 0]
    ctr = [[np.nan] * 2, [0, 0], [0, 0], [np.nan] * 2, [np.nan] * 2, [np.nan] * 2, [np.nan] * 2]
    tag = ["", "", "", "", tag_rapid, "", ""]
    return ToolPath.build(pts, kind=kind, tag=tag, feed=400, arc=arc, arc_center=ctr, tool=Tool(6, number=3),
                          cleared=[t == "cleared" for t in tag])


def test_start_block_tool_spindle_and_end():
    text = write_program(_pocket_path("cleared"), clearance_z=5, spindle_rpm=6366)
    lines = text.splitlines()
    i = lines.index(START_BLOCK)
    assert all(h.startswith("(") for h in lines[1:i])           # header comments only before it
    assert lines[i + 1:i + 3] == ["T3 M6", "G43 H3"]
    assert lines[i + 3] == "S6366 M3"
    assert lines[i + 4].startswith("G0 X3.0000 Y0.0000 Z5.0000")   # over the first point at the clearance plane
    assert lines[i + 5].startswith("G1 Z1.0000")                    # fed down to the first point, never rapid
    assert lines[-3:] == ["M5", "M30", "%"]
    chk = check_program(text, clearance_z=5)
    assert chk.ok, chk.errors
    # the feed down to the first point (z 5 -> 1) is a plunge in air; the two helix turns are one entry
    assert chk.entries == {"helix": 1, "ramp": 0, "plunge": 1} and chk.plunges_into_material == 0


def test_rapid_below_clearance_needs_the_cleared_flag():
    with pytest.raises(ValueError, match="move 4: rapid from z -1.5 to z -1.5 mm below the clearance plane"):
        write_program(_pocket_path(""), clearance_z=5, spindle_rpm=6000)
    text = write_program(_pocket_path("cleared"), clearance_z=5, spindle_rpm=6000)
    assert "G0 Y5.0000 (cnclab:cleared/1)" in text
    # the checker refuses the same block without its mark
    bad = text.replace(" (cnclab:cleared/1)", "")
    chk = check_program(bad, clearance_z=5)
    assert chk.rapids_below_clearance == 1 and "word G0: rapid below the clearance plane" in chk.errors[0]


@pytest.mark.parametrize("comment", ["cleared", "not cleared", "cleared: link through cleared area",
                                     "cnclab:cleared/2", "cnclab:cleared/1 (no)", "CNCLAB:CLEARED/1", "x cnclab:cleared/1",
                                     "cnclab:cleared/10", ""])
def test_no_other_comment_text_grants_clearance(comment):
    """Only the writer's structured marker (exactly ``cnclab:cleared/1``) marks a block cleared: a free
    text comment that mentions 'cleared', a tag, another version or a longer text grants nothing (the
    rapid at depth and the plunge below the stock top are then errors)."""
    text = write_program(_pocket_path("cleared"), clearance_z=5, spindle_rpm=6000)
    assert check_program(text, clearance_z=5).ok and text.count(f"({CLEARED_MARK})") == 1
    other = text.replace(f"({CLEARED_MARK})", f"({comment})" if "(" not in comment else f"; {comment}")
    assert not cleared_mark(comment)
    chk = check_program(other, clearance_z=5)
    assert chk.rapids_below_clearance == 1 and not chk.ok


def test_check_program_on_a_path_reads_its_cleared_column():
    """A ToolPath is checked from its ``cleared`` column (data), its tags ignored: the same verdicts as
    its written program; a tag saying 'cleared' without the flag is refused."""
    good = _pocket_path("cleared")
    chk = check_program(good, clearance_z=5)
    assert chk.rapids_below_clearance == 0 and chk.entries["helix"] == 1
    tagged_only = ToolPath(good.xyz, good.kind, good.tag, good.feed, good.spindle, good.arc, good.arc_center,
                           good.tool, {}, np.zeros(len(good), bool))
    assert "cleared" in tagged_only.tag[4] and check_program(tagged_only, clearance_z=5).rapids_below_clearance == 1


def test_written_time_is_the_path_time():
    """The program's time (read back, feed moves at F, rapids at the stated rate) equals the path's
    ToolPath.time_s plus the approach/retract the writer adds (computed here by hand)."""
    path = _pocket_path("cleared")
    text = write_program(path, clearance_z=5, spindle_rpm=6000, decimals=6)
    t = program_time(parse_gcode(text), rapid_mm_min=10000)
    ts = path.time_s(10000)
    feed_down = 60 * (5 - 1) / 400          # G1 from the clearance plane to the first point
    retract_up = 60 * (5 - 2) / 10000       # final G0 from z 2 up to the clearance plane
    assert t["total_s"] == pytest.approx(ts["total_s"] + feed_down + retract_up, rel=1e-9)


@pytest.mark.parametrize("text, fragment", [
    ("G21\nG0 X0 Y0 Z5\nG1 Z-1 F100\nM5\nM30\n", "feed move before the spindle is started"),
    ("G21\nS1000 M3\nG0 X0 Y0 Z5\nG0 Z-1\nM5\nM30\n", "word G0: rapid below the clearance plane"),
    ("G21\nS1000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 Z5\nM5\n", "no program end"),
    ("G21\nS1000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 Z5\nM30\n", "the spindle is not stopped"),
    ("G21\nS1000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 Z5\nM5\nM30\n", "plunge into material"),
    ("G21\nS1000 M3\nG0 X0 Y0 Z1\nG1 X1 F100\nM5\nM30\n", "the first move ends below the clearance plane"),
])
def test_checker_finds_each_violation(text, fragment):
    chk = check_program(text, clearance_z=5, source="c.ngc")
    assert not chk.ok
    assert any(fragment in e for e in chk.errors), chk.errors


def test_checker_accepts_marked_plunge_and_counts_ramps():
    text = ("G21\nS1000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F100 (cnclab:cleared/1)\nG1 X5 Z-2\nG2 X5 Y0 Z-3 I1 J0\n"
            "G0 Z5\nM5\nM30\n")
    chk = check_program(text, clearance_z=5)
    assert chk.ok, chk.errors
    # a free-text comment that says so is no mark: the plunge counts as into material
    free = check_program(text.replace("(cnclab:cleared/1)", "(cleared: start hole)"), clearance_z=5)
    assert free.plunges_into_material == 1
    # the ramp (G1 X5 Z-2) and the helix (G2 ... Z-3) descend without a pause: one entry, counted as
    # the kind that descends the most in it (1 mm each: the first); the plunge before it is its own
    assert chk.entries == {"helix": 0, "ramp": 1, "plunge": 1} and chk.plunges_into_material == 0
    # a descent that alternates arcs and lines (a ramp along a curve the arc fit took in pieces) is one
    # entry; a pause at depth (a level move) ends it
    zz = ("G21\nS1000 M3\nG0 X0 Y0 Z5\nG0 Z0.5 (cnclab:cleared/1)\nG1 Z0 F100\nG3 X1 Y1 Z-0.2 I0 J1\n"
          "G1 X0 Y2 Z-0.3\nG3 X-1 Y1 Z-0.5 I0 J-1\nG1 X0 Y0 Z-0.6\nG1 X3\nG1 Z-0.8\nG0 Z5\nM5\nM30\n")
    got = check_program(zz, clearance_z=5)
    assert got.entries == {"helix": 1, "ramp": 0, "plunge": 2} and got.plunges_into_material == 1, got


def test_freecad_adaptive_rapids_at_depth_are_reported():
    """FreeCAD Adaptive links inside the cleared area with G0 at the cutting depth (keep-tool-down);
    the static checker cannot prove those are in cleared area and reports each of them (the
    simulator must judge them: cnclab analyze). Everything else in the program is safe."""
    text = (FREECAD / "star_pocket_adaptive_linuxcnc.ngc").read_text()
    chk = check_program(text, clearance_z=3.0, source="star")
    assert chk.spindle_on_before_cut and chk.end_word == "M2"
    assert chk.rapids_below_clearance > 0
    assert all("word G0: rapid below the clearance plane Z3 (z -3 -> -3 mm)" in e for e in chk.errors)
    assert chk.entries["helix"] == 1 and chk.plunges_into_material == 0       # one helix of 5 turns


@given(st.lists(st.tuples(st.floats(-40, 40), st.floats(-40, 40)), min_size=1, max_size=12),
       st.floats(0.2, 6), st.integers(4, 80).map(lambda q: q / 4), st.sampled_from([2, 3, 4]))
@settings(max_examples=40, deadline=None)
def test_written_programs_always_pass_the_checker(xy, depth, clear, decimals):
    """Any path of ramp entry + cuts + retract is written as a program that passes the checker and
    reads back to the same feed length (within the written precision). Clearance planes on a 0.25 mm
    grid: written exactly at every precision."""
    x0, y0 = xy[0]
    pts = [[x0, y0, clear + 1], [x0 + 1, y0, -depth]] + [[x, y, -depth] for x, y in xy] + [[xy[-1][0], xy[-1][1], clear]]
    kind = ["rapid", "ramp"] + ["cut"] * len(xy) + ["retract"]
    path = ToolPath.build(pts, kind=kind, feed=500)
    text = write_program(path, clearance_z=clear, spindle_rpm=10000, decimals=decimals)
    chk = check_program(text, clearance_z=clear)
    assert chk.ok, chk.errors
    back = program_time(parse_gcode(text), rapid_mm_min=5000)
    tol = len(pts) * 2 * math.sqrt(3) * 0.5 * 10.0 ** -decimals
    assert back["feed_mm"] == pytest.approx(path.lengths()["feed_mm"], abs=tol)


def test_written_program_file_is_atomic_and_never_overwrites_inputs(tmp_path):
    job = tmp_path / "job.json"
    job.write_text("{}")
    with pytest.raises(ValueError, match="refusing to overwrite"):
        write_program(_pocket_path("cleared"), out=job, clearance_z=5, spindle_rpm=6000, inputs=[job])
    assert job.read_text() == "{}"
    text = write_program(_pocket_path("cleared"), out=tmp_path / "p.ngc", clearance_z=5, spindle_rpm=6000)
    assert (tmp_path / "p.ngc").read_text() == text and read_gcode(text).end_word == "M30"


def test_bad_parameters():
    with pytest.raises(ValueError, match="spindle_rpm"):
        write_program(_pocket_path("cleared"), clearance_z=5)
    with pytest.raises(ValueError, match="clearance_z"):
        write_program(_pocket_path("cleared"), clearance_z=-1, spindle_rpm=100)


def test_plunge_flagged_cleared_is_written_as_such():
    pts = [[0, 0, 5], [0, 0, -2], [10, 0, -2], [10, 0, 5]]
    p = ToolPath.build(pts, kind=["rapid", "plunge", "cut", "retract"], cleared=[0, 1, 0, 0], feed=300)
    text = write_program(p, clearance_z=5, spindle_rpm=5000)
    assert "G1 Z-2.0000 F300.0 (cnclab:cleared/1)" in text
    assert check_program(text, clearance_z=5).ok
    untagged = write_program(ToolPath.build(pts, kind=["rapid", "plunge", "cut", "retract"], feed=300),
                             clearance_z=5, spindle_rpm=5000)
    assert check_program(untagged, clearance_z=5).plunges_into_material == 1


def test_programs_cover_the_default_plan_of_every_job_file():
    """``python -m cnclab programs`` writes the default planner's program of every pocket job file
    of data/ (jacso2021, kim_yang2006 pocket, pockets) next to the works' programs."""
    import json

    from cnclab.paths import DATA_DIR
    from cnclab.works.programs import PROGRAM_RECIPES

    expected = set()
    for folder, pattern in (("jacso2021", "*.json"), ("kim_yang2006", "pocket_*.json"), ("pockets", "*.json")):
        for f in (DATA_DIR / folder).glob(pattern):
            d = json.loads(f.read_text(encoding="utf-8"))
            if "tool_diameter" in d:
                expected.add(f"{folder}/{f.stem}_plan_default")
    got = {f"{w}/{n}" for w, r in PROGRAM_RECIPES.items() for n in r if n.endswith("_plan_default")}
    assert got == expected and {"kim_yang2006/pocket_120x85_plan_default", "jacso2021/star_pocket_plan_default",
                                "pockets/two_regions_plan_default"} <= got
    assert "jacso2021/table4_1_cutting_parameters_plan_default" not in got


def test_drop_cut_descent_tagged_cleared_only_when_vertical():
    """ch. 8 programs: the vertical feed down onto a drop-cut CL point is tagged cleared (the ball
    above the contact height touches no facet); a sloped descent (a ramp) is not."""
    from cnclab.works.programs import _tag_drop_cut_descents

    p = ToolPath.build([[0, 0, 30], [0, 0, 2], [1, 0, 2], [2, 0, 1.5], [2, 0, 1.0]],
                       kind=["rapid", "plunge", "cut", "cut", "plunge"], feed=500)
    _tag_drop_cut_descents(p)
    assert p.cleared.tolist() == [False, True, False, False, True]
    chk = check_program(write_program(p, clearance_z=30, spindle_rpm=2000, top_z=10), clearance_z=30, top_z=10)
    assert chk.plunges_into_material == 0 and chk.entries == {"helix": 0, "ramp": 1, "plunge": 2}


def test_write_moves_writes_its_text_atomically_and_never_over_an_input(tmp_path):
    """The move-by-move entry of the one writer (the spindle post-processor's): ``out`` gets exactly
    the returned text; an ``out`` that is one of the ``inputs`` is refused and the input unchanged."""
    from cnclab.nc.gcode import Move
    from cnclab.nc.program import write_linear_moves, write_moves

    moves = [Move("G0", 0, 0, 5), Move("G1", 1.25, 0, -1, feed=200, spindle=3000), Move("G0", 1.25, 0, 5)]
    out = tmp_path / "m.ngc"
    text = write_moves(moves, header="t", out=out)
    assert out.read_text() == text and parse_gcode(text) == [
        Move("G0", 0, 0, 5), Move("G1", 1.25, 0, -1, feed=200.0, spindle=3000.0), Move("G0", 1.25, 0, 5)]   # M5 before it
    src = tmp_path / "in.apt"
    src.write_text("input\n")
    with pytest.raises(ValueError):
        write_linear_moves([[0, 0, 5], [1, 0, -1]], [True, False], [np.nan, 200], [np.nan, 3000], out=src,
                           inputs=[src])
    assert src.read_text() == "input\n"
