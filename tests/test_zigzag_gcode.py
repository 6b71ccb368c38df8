"""G-code writer/parser (cnclab.nc.gcode) and the Hoang zig-zag generator."""
import math

import numpy as np
import pytest
from hypothesis import example, given, settings, strategies as st

from cnclab.nc import gcode
from cnclab.nc.gcode import GcodeError, Move, parse_gcode, path_lengths
from cnclab.nc.program import write_moves
from cnclab.nc.program import check_program


def _program():
    return [Move("G0", 0, 0, 10), Move("G1", 0, 0, 0, feed=300, spindle=2000),
            Move("G1", 20, 0, 0, feed=500, spindle=2000),
            Move("G2", 30, -10, 0, i=0, j=-10, feed=500, spindle=2000),
            Move("G3", 30, -10, -1, i=5, j=0, feed=500, spindle=2000),   # full helical circle
            Move("G0", 30, -10, 10, spindle=2000)]


def test_round_trip_exact_and_modal():
    text = write_moves(_program(), header=["cnclab test", "second line"])
    moves = parse_gcode(text)
    assert len(moves) == 6
    assert write_moves(moves, header=["cnclab test", "second line"]) == text
    # modal: F500 written once, S2000 once, motion word G1 once for the two linear moves
    assert text.count("F500.0") == 1 and text.count("S2000") == 1
    assert moves[3].i == 0 and moves[3].j == -10 and moves[3].feed == 500
    assert moves[5].feed is None and moves[5].spindle == 2000


def test_lengths_of_arcs_and_helix():
    L = path_lengths(_program())
    quarter = 0.5 * math.pi * 10
    helix = math.hypot(2 * math.pi * 5, 1.0)
    assert L["feed"] == pytest.approx(10 + 20 + quarter + helix)
    assert L["rapid"] == pytest.approx(11)   # from z=-1 back to z=10


def test_sample_arc_on_circle_and_direction():
    start = (10.0, 0.0, 0.0)
    cw = gcode.sample_move(start, Move("G2", 0, -10, 0, i=-10, j=0, feed=1), max_segment=0.2)
    ccw = gcode.sample_move(start, Move("G3", 0, -10, 0, i=-10, j=0, feed=1), max_segment=0.2)
    assert np.allclose(np.hypot(cw[:, 0], cw[:, 1]), 10)
    assert cw[:, 1].max() <= 1e-9            # CW from +X to -Y stays in the lower half (quarter)
    assert ccw[:, 1].max() == pytest.approx(10, abs=0.01)   # CCW goes the long way (3/4 circle)
    seg = np.linalg.norm(np.diff(cw, axis=0), axis=1)
    assert seg.max() <= 0.2 + 1e-9


@pytest.mark.parametrize("text, fragment", [
    ("G0 X0 Y0 Z0\nG1 X1 Q5 F100\n", "t.nc:2: word Q5 only accepted with G64"),
    ("G18\n", "t.nc:1: word G18"),
    ("G91 G0 X1\n", "t.nc:1: word X: incremental .G91. move from an unknown X"),
    ("G1 X0 Y0 F100\n", "t.nc:1: word G1: position of Z is unknown"),
    ("G0 X0 Y0 Z0\nG1 X5\n", "t.nc:2: word G1: G1 feed move with no feed F"),
    ("G0 X0 Y0 Z0\nG2 X2 Y0 F100\n", "t.nc:2: word G2: arc needs centre offsets I and J"),
    ("G0 X0 Y0 Z0\nG2 X3 Y0 I1 J0 F100\n", "t.nc:2: word I: arc start radius"),
    ("G0 X0 Y0 Z0\nG2 X2 Y0 R0.5 F100\n", "t.nc:2: word R0.5: radius smaller than half the chord"),
    ("G0 X0 Y0 Z0\nM98\n", "t.nc:2: unknown or unsupported word M98"),
    ("G0 X0 Y0 Z0\nG81 X1 Y1 Z-1 R1 F100\n", "t.nc:2: word G81: canned cycles"),
    ("G0 X0 Y0 Z0 @\n", "t.nc:1: cannot read"),
    ("G0 X0 Y0 Z0\nG1 X1 E5 F100\n", "t.nc:2: unknown word E5"),
])
def test_bad_input_names_source_and_line(text, fragment):
    with pytest.raises(GcodeError, match=fragment.replace("(", r"\(")):
        parse_gcode(text, source="t.nc")


def test_hand_written_variants_parse():
    text = "%\nN10 G00 X0 Y0 Z5 (rapid)\nN20 G01 Z-1 F250 ; plunge\nN30 X10\nM30\n%\n"
    moves = parse_gcode(text)
    assert [m.motion for m in moves] == ["G0", "G1", "G1"]
    assert moves[-1].x == 10 and moves[-1].z == -1 and moves[-1].feed == 250


def test_move_validation():
    with pytest.raises(ValueError, match="needs a feed"):
        Move("G1", 0, 0, 0)
    with pytest.raises(ValueError, match="i and j"):
        Move("G2", 0, 0, 0, feed=1)
    with pytest.raises(ValueError, match="motion must be"):
        Move("G5", 0, 0, 0)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.floats(-500, 500), st.floats(-500, 500), st.floats(-50, 50),
                          st.sampled_from(["G0", "G1"]), st.floats(1, 5000)), min_size=1, max_size=30))
@example([(0.0, 0.0, 0.0005, "G0", 1.0)])     # a rounding tie: written as 0.001, np.round gives 0.0
def test_round_trip_property(pts):
    moves = [Move(m, x, y, z, feed=None if m == "G0" else f) for x, y, z, m, f in pts]
    text = write_moves(moves, decimals=3)
    again = parse_gcode(text)
    assert write_moves(again, decimals=3) == text
    # every parsed point is within half a unit of the last digit of an original point (the writer's
    # decimal formatting and np.round may break ties like 0.0005 differently, so compare distances)
    orig = np.array([mv.xyz for mv in moves], dtype=float)
    for mv in again:
        assert np.min(np.max(np.abs(orig - np.asarray(mv.xyz, float)), axis=1)) <= 0.5e-3 + 1e-9


# ---------------------------------------------------------------- zig-zag (Hoang Table 1)
from cnclab.toolpath import zigzag  # noqa: E402
from cnclab.works.hoang2024 import constant_volume as cv  # noqa: E402


def test_table1_loop_as_printed_counts():
    sz, fr = 0.994987, 3.02718
    p = zigzag.hoang_table1_points(0, 0, 50, 100, sz, fr)
    n = 50 / sz + sz / 2
    iters = math.floor(n / 2)
    assert len(p) == 1 + 4 * iters
    assert p[-1, 1] == pytest.approx(2 * iters * sz)        # ends on a trailing stepover
    assert np.allclose(np.abs(np.diff(p[:, 0]))[::2], 100)   # each pass is F_r*m = Long


@settings(max_examples=40, deadline=None)
@given(st.floats(1, 200), st.floats(1, 200), st.floats(0.05, 5))
def test_covering_zigzag_properties(width, length, sz):
    p = zigzag.zigzag_points((1.0, 2.0), width, length, sz)
    ys = np.unique(np.round(p[:, 1], 9))
    assert ys[-1] >= 2.0 + width - 1e-9 and ys[-2] < 2.0 + width - 1e-9   # covers, no spare pass
    assert np.allclose(np.diff(ys), sz)
    assert np.all((p[:, 0] >= 1.0 - 1e-9) & (p[:, 0] <= 1.0 + length + 1e-9))


def test_forward_step_points_are_on_the_pass():
    p = zigzag.zigzag_points((0, 0), 1.0, 10.0, 1.0, forward_step=3.0)
    assert p[:5, 0].tolist() == [0, 3, 6, 9, 10]
    assert p[5:10, 0].tolist() == [10, 9, 6, 3, 0]


def test_table3_accounting_and_gcode_round_trip():
    moves, text = cv.table3_program(covering=True, decimals=3)
    sz = cv.table2_recomputed().loc["r2", "Sz"]
    L = path_lengths(moves)
    y_last = round(51 * sz, 3)
    assert L["feed"] == pytest.approx(52 * 100 + y_last + 20, abs=1e-9)
    assert L["rapid"] == pytest.approx(y_last, abs=1e-9)   # rapid return; the tool starts at (0,0,10)
    # the written program is machine-safe: spindle on before the plunge, no rapid below Z10, M5 M30
    chk = check_program(text, clearance_z=10.0)
    assert chk.ok, chk.errors
    assert text.index("S8000 M3") < text.index("\nG1 ")
    assert text.rstrip().endswith("M5\nM30\n%")


# ---------------------------------------------------------------- the one raster generator
@settings(max_examples=40, deadline=None)
@given(st.floats(-90, 180), st.floats(0.3, 5.0), st.floats(0.2, 3.0))
def test_raster_passes_rectangle_properties(angle, ae, step):
    """Rectangle at any feed angle: passes along +-u alternating, on lines ae apart (the last on the
    far edge, closer; lines that only touch a corner dropped), sampled at most ``step`` apart, inside the rectangle, links at most ``step``."""
    rect = (-3.0, 17.0, 2.0, 13.0)
    passes = zigzag.raster_passes(rect, ae, angle, last="edge", step=step)
    u = np.array([math.cos(math.radians(angle)), math.sin(math.radians(angle))])
    v = np.array([-u[1], u[0]])
    corners = np.array([[-3, 2], [17, 2], [17, 13], [-3, 13]], float)
    offs = np.array([q[0] @ v for q in passes])
    assert np.all(np.diff(offs) > 0) and np.all(np.diff(offs)[:-1] == pytest.approx(ae, abs=1e-9))
    # covered: a line on or within one stepover of each extreme (a line touching only a corner is dropped)
    assert np.diff(offs)[-1] <= ae + 1e-9 and -1e-9 <= (corners @ v).max() - offs[-1] <= ae + 1e-9
    assert -1e-9 <= offs[0] - (corners @ v).min() <= ae + 1e-9
    for k, q in enumerate(passes):
        d = np.diff(q, axis=0)
        assert np.allclose(q @ v, q[0] @ v, atol=1e-9)                         # a straight pass
        assert np.all(d @ u * (1 if k % 2 == 0 else -1) > 0)                  # alternating direction
        assert np.hypot(*d.T).max() <= step + 1e-9
        assert np.all((q >= [-3 - 1e-9, 2 - 1e-9]) & (q <= [17 + 1e-9, 13 + 1e-9]))
    linked = zigzag.raster_passes(rect, ae, angle, last="edge", step=step, links=True)
    P = np.vstack(linked)
    assert np.hypot(*np.diff(P, axis=0).T).max() <= step + 1e-9                 # one continuous path
    assert [len(q) for q in passes] == [len(q) - len(q) + len(p) for q, p in zip(linked, passes)]


def test_raster_passes_region_matches_hand_computed_lines():
    """A region with a hole: each line splits in two pieces, pieces ordered along +x, reversed on odd
    lines; the first line sits start_offset above the bottom; lines strictly below the top."""
    from shapely.geometry import box

    region = box(0, 0, 10, 3).difference(box(4, -1, 6, 2.2))
    lines = zigzag.raster_passes(region, 1.0, start_offset_mm=0.5)
    ys = [q[0, 1] for q in lines]
    assert ys == [0.5, 0.5, 1.5, 1.5, 2.5]
    assert lines[0].tolist() == [[0.0, 0.5], [4.0, 0.5]] and lines[1].tolist() == [[6.0, 0.5], [10.0, 0.5]]
    assert lines[2].tolist() == [[4.0, 1.5], [0.0, 1.5]] and lines[3].tolist() == [[10.0, 1.5], [6.0, 1.5]]
    assert lines[4].tolist() == [[0.0, 2.5], [10.0, 2.5]]


def test_the_three_users_share_the_generator():
    """Hoang's points, the pocket raster and the drop-cutter raster are raster_passes outputs."""
    from shapely.geometry import box

    p = zigzag.zigzag_points((0, 0), 2.0, 10.0, 1.0)
    assert np.array_equal(p, np.vstack(zigzag.raster_passes((0, 10, 0, 2), 1.0, last="edge")))
    r = zigzag.raster_lines(box(0, 0, 10, 2), 1.0)
    assert all(np.array_equal(a, b) for a, b in zip(r, zigzag.raster_passes(box(0, 0, 10, 2), 1.0, start_offset_mm=1e-6, min_length=1e-6)))
    with pytest.raises(ValueError, match="last"):
        zigzag.raster_passes((0, 1, 0, 1), 1.0, last="beyond")
    with pytest.raises(ValueError, match="stepover"):
        zigzag.raster_passes((0, 1, 0, 1), 0.0)
