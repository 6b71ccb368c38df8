"""APT CL parser/writer (cnclab.nc.apt): round trip, dialect, bad input naming file and line."""
import numpy as np
import pytest

from cnclab.paths import data_path
from cnclab.nc import apt

EXCERPT = """$$-> MFGNO / MFG0002
PARTNO / MFG0002
MACHIN / MILL, 1
UNITS / MM
LOADTL / 37 $$-> D10 R5 FRISA
$$-> CUTTER / 10.000000
$$-> CSYS / 1.000000000, 0.000000000, 0.000000000, -25.000000000, $
    0.000000000, 1.000000000, 0.000000000, -25.000000000, $
    0.000000000, 0.000000000, 1.000000000, 0.000000000
SPINDL / RPM, 2000.000000, CLW
RAPID
FROM / -20.100, 25.249, 30.000
RAPID
GOTO / -20.100, 25.249, 9.994
FEDRAT / 500.000000, MMPM
GOTO / -19.975, 25.249, 9.994
GOTO / -18.996, $
   25.249, 9.990
GOTO / -18.871, 25.249, 9.994
FINI
"""


def test_thesis_excerpt_round_trip_and_points(tmp_path):
    prog = apt.parse_apt(EXCERPT, "excerpt.apt")
    assert prog.to_text() == EXCERPT
    assert prog.tool_diameter() == 10.0
    cl = prog.cl_points()
    np.testing.assert_allclose(cl.xyz[2], [-18.996, 25.249, 9.990])
    assert cl.rapid.tolist() == [True, False, False, False]
    assert cl.line.tolist() == [14, 16, 17, 19]
    assert np.isnan(cl.feed[0]) and (cl.feed[1:] == 500).all() and (cl.spindle == 2000).all()
    np.testing.assert_allclose(cl.start, [-20.1, 25.249, 30.0])
    p = apt.write_apt(tmp_path / "o.apt", prog)
    assert p.read_text() == EXCERPT


def test_sample_file_round_trip():
    path = data_path("mgherony2024", "sample_ch8_zigzag_Af0.apt")
    prog = apt.read_apt(path)
    assert prog.to_text() == path.read_text()
    assert len(prog.cl_points()) > 1000


def test_sample_file_is_its_recipe():
    """The committed sample CL file is exactly what its recipe writes (approach at Z30, feed down)."""
    from cnclab.works.mgherony2024.ch7_9 import sample_ch8_apt

    text = data_path("mgherony2024", "sample_ch8_zigzag_Af0.apt").read_text()
    assert sample_ch8_apt().to_text() == text
    cl = apt.parse_apt(text).cl_points()
    assert cl.xyz[cl.rapid, 2].min() == 30   # no rapid below the clearance plane


def test_generated_program_parses_back():
    passes = [np.array([[0, 0, 1.0], [5, 0, 1.5]]), np.array([[5, 1, 1.5], [0, 1, 1.0]])]
    prog = apt.cl_program(passes, 500, 2000, 10, 30)
    back = apt.parse_apt(prog.to_text())
    cl = back.cl_points()
    feed = cl.xyz[~cl.rapid]
    np.testing.assert_allclose(feed, np.vstack(passes))   # the first point too: fed down onto, never rapid
    assert cl.xyz[cl.rapid, 2].min() == 30


@pytest.mark.parametrize("text, msg", [
    ("UNITS / INCH\nFEDRAT / 5, IPM\nGOTO / 1, 2, 3\n", r"x.apt:1: UNITS/INCH"),
    ("UNITS / MM\nFEDRAT / 500, MMPM\nGOTO / 1, 2\n", r"x.apt:3: GOTO needs 3 .* got 2"),
    ("UNITS / MM\nFEDRAT / 500, MMPM\nGOTO / 1, 2, 3, 4\n", r"x.apt:3: GOTO needs 3 .* got 4"),
    ("UNITS / MM\nFEDRAT / 500, MMPM\nGOTO / 1, abc, 3\n", r"x.apt:3: GOTO value 'abc'"),
    ("UNITS / MM\nFEDRAT / 500, MMPM\nGOTO / 1, nan, 3\n", r"x.apt:3: GOTO has a non-finite"),
    ("UNITS / MM\nRAPID\nGOTO / 0, 0, 5\nGOTO / 1, 2, 3\n", r"x.apt:4: feed motion \(GOTO\) before any FEDRAT"),
    ("PARTNO / X\nUNITS / MM\nFINI\n", r"x.apt: empty program"),
    ("", r"x.apt: empty program"),
    ("UNITS / MM\nGOTO / 1, 2, $\n", r"x.apt:2: continuation"),
])
def test_bad_apt_names_file_and_line(text, msg):
    with pytest.raises(ValueError, match=msg):
        apt.parse_apt(text, "x.apt")


def test_write_never_overwrites_input(tmp_path):
    src = tmp_path / "in.apt"
    src.write_text(EXCERPT)
    prog = apt.read_apt(src)
    with pytest.raises(ValueError, match="refusing to overwrite"):
        apt.write_apt(src, apt.AptProgram(prog.records[:3]), inputs=[src])
    assert src.read_text() == EXCERPT


# ------------------------------------------------------------------ bulk (fast) vs careful parser
def _run(n, x0=0.0, fmt="GOTO / {:.3f}, {:.3f}, {:.3f}\n"):
    return "".join(fmt.format(x0 + 0.5 * i, 1.25 - 0.001 * i, -2.0 + i * 1e-3) for i in range(n))


HEAD = "PARTNO / T\nUNITS / MM\nSPINDL / RPM, 2000, CLW\nRAPID\nGOTO / 0, 0, 30\nRAPID\n"


def _both(text):
    fast = apt.parse_apt(text, "x.apt", fast=True)
    careful = apt.parse_apt(text, "x.apt", fast=False)
    return fast, careful


@pytest.mark.parametrize("text", [
    HEAD + "GOTO / 0, 0, 1\nFEDRAT / 500, MMPM\n" + _run(50) + "RAPID\nGOTO / 1, 1, 30\nFINI\n",
    (HEAD + "GOTO / 0, 0, 1\nFEDRAT / 500, MMPM\n" + _run(30)).replace("\n", "\r\n") + "FINI",
    HEAD + "GOTO / 0, 0, 1\nFEDRAT / 500, MMPM\n" + _run(20) + "FEDRAT / 400, MMPM\n" + _run(20, fmt="GOTO/{:.6e},{:+.4f} ,\t{:.2f}\n") + "END\n",
    HEAD + "FEDRAT / 500, MMPM\nCOOLNT / ON $\n" + _run(20) + _run(3, fmt="GOTO / {},{},{}  $$ c\n") + _run(12),
    HEAD + "FEDRAT / 500, MMPM\n" + _run(12) + "goto / 1, 2, 3\n" + _run(12, fmt="GOTO / {}, {}, {}, 0, 0, 1\n")
    + _run(12, fmt="GOTO / .{:.0f}, {:.1f}, {:.0f}.\n") + _run(9),
])
def test_fast_and_careful_parsers_give_identical_records(text):
    fast, careful = _both(text)
    assert any(isinstance(it, apt.GotoRun) for it in fast.items())  # the bulk path was taken
    assert fast.to_text() == careful.to_text() == text
    cf, cc = fast.cl_points(), careful.cl_points()
    for name in ("xyz", "rapid", "feed", "spindle", "record", "line", "start"):
        np.testing.assert_array_equal(getattr(cf, name), getattr(cc, name), err_msg=name)
    assert fast.records == careful.records                     # expands the runs; dataclass equality
    assert fast.to_text() == text


def test_fast_parser_values_equal_python_float():
    rng = np.random.default_rng(3)
    v = rng.normal(0, 300, (400, 3))
    text = "UNITS / MM\nFEDRAT / 500, MMPM\n" + "".join(f"GOTO / {a!r}, {b:.17g}, {c:.9f}\n" for a, b, c in v.tolist())
    fast, careful = _both(text)
    np.testing.assert_array_equal(fast.cl_points().xyz, careful.cl_points().xyz)
    np.testing.assert_array_equal(fast.cl_points().xyz[:, 0], v[:, 0])


@pytest.mark.parametrize("bad, msg", [
    ("GOTO / 1, abc, 3\n", r"x.apt:{}: GOTO value 'abc'"),
    ("GOTO / 1, 2\n", r"x.apt:{}: GOTO needs 3 .* got 2"),
    ("GOTO / 1, 1e999, 3\n", r"x.apt:{}: GOTO has a non-finite"),
    ("GOTO / 1, nan, 3\n", r"x.apt:{}: GOTO has a non-finite"),
    ("GOTO / 1.2.3, 2, 3\n", r"x.apt:{}: GOTO value '1.2.3'"),
    ("GOTO / 1-2, 2, 3\n", r"x.apt:{}: GOTO value '1-2'"),
    ("GOTO / 1 2, 2, 3\n", r"x.apt:{}: GOTO value '1 2'"),
    ("GOTO / 1e, 2, 3\n", r"x.apt:{}: GOTO value '1e'"),
    ("GOTO / --1, 2, 3\n", r"x.apt:{}: GOTO value '--1'"),
    ("GOTO / 1,, 3\n", r"x.apt:{}: GOTO value ''"),
    ("GOTO / ., 2, 3\n", r"x.apt:{}: GOTO value '.'"),
    ("GOTO / 1, 2, 3, 4\n", r"x.apt:{}: GOTO needs 3 .* got 4"),
])
def test_fast_and_careful_parsers_give_identical_errors(bad, msg):
    pre = "UNITS / MM\nFEDRAT / 500, MMPM\n" + _run(40)
    text = pre + bad + _run(40)
    line = pre.count("\n") + 1
    for fast in (True, False):
        with pytest.raises(apt.AptError, match=msg.format(line)):
            apt.parse_apt(text, "x.apt", fast=fast)


@pytest.mark.parametrize("text, line", [
    ("UNITS / MM\n" + _run(20), 2),                                  # feed before FEDRAT, run's first line
    ("UNITS / MM\nRAPID\n" + _run(20), 4),                           # rapid consumed, second line is a feed
    ("UNITS / MM\nFEDRAT / 5, MMPM\nLOADTL / 1, $\n" + _run(20) + "GOTO / 1, 2, $\n", 24),
])
def test_fast_and_careful_parsers_agree_on_state_errors(text, line):
    msgs = []
    for fast in (True, False):
        with pytest.raises(apt.AptError, match=rf"x.apt:{line}:") as e:
            apt.parse_apt(text, "x.apt", fast=fast)
        msgs.append(str(e.value))
    assert msgs[0] == msgs[1]


def test_bulk_insertion_equals_record_insertion():
    from cnclab.nc import spindle_control as sc
    from cnclab.geometry.freeform_part import FreeformPart, freeform_part_mesh

    part = FreeformPart()
    mesh = freeform_part_mesh(part, 2.0)
    x = np.linspace(0, 50, 60)
    P = np.column_stack([x, np.full_like(x, 20.0), part.height_at(x, np.full_like(x, 20.0))])
    text = apt.cl_program([P, P[::-1] + [0, 1, 0]], 500, 2000, 10, 30).to_text()
    outs = []
    for fast in (True, False):
        prog = apt.parse_apt(text, "p.apt", fast=fast)
        cl = prog.cl_points()
        s = sc.spindle_schedule(mesh, cl, tool_diameter=10, a_p=0.3, v_c=63, f_z=0.125, teeth=2,
                                feed_direction_deg=0)
        new, counts = sc.insert_spindle_records(prog, cl, s, rpm_threshold=20, vf_threshold=5)
        outs.append((new.to_text(), counts, [(m.x, m.y, m.z, m.feed, m.spindle) for m in sc.to_gcode_moves(new)]))
    assert outs[0] == outs[1]
    assert outs[0][1]["spindl_inserted"] > 3


def test_bulk_goto_values_bit_identical_to_float_on_hard_numbers():
    """The compiled GOTO-run reader converts exactly as ``float``: Clinger's fast path (<= 15 digits,
    |10-power| <= 22) and ``float`` for the rest; every line of these runs is read in bulk."""
    import random

    rng = random.Random(17)
    fixed_cases = ["0", "-0", "+0.", ".5", "-.25e-3", "1e22", "1E23", "123456789012345678901234",
                   "0.000000000000000000012345", "1e300", "1e-400", "5.", "+7", "9007199254740993",
                   "0.1", "2.2250738585072014e-308", "4.9e-324", "999999999999999.9", "1.7976931348623157e308"]

    def num():
        c = rng.random()
        if c < 0.3:
            return f"{rng.uniform(-1e3, 1e3):.{rng.randint(0, 6)}f}"
        if c < 0.6:
            return repr(rng.uniform(-1e5, 1e5) * 10.0 ** rng.randint(-30, 30))
        if c < 0.75:
            return rng.choice(fixed_cases)
        return str(rng.randint(-10 ** 6, 10 ** 6))

    for _ in range(60):
        toks = [[num() for _ in range(3)] for _ in range(20)]
        text = "UNITS / MM\nFEDRAT / 500, MMPM\n" + "".join(
            "GOTO" + rng.choice([" / ", "/", "\t/ "]) + rng.choice([", ", ",", " ,\t"]).join(t)
            + rng.choice(["", " ", "\r"]) + "\n" for t in toks)
        fast = apt.parse_apt(text, "x.apt")
        assert sum(len(it) for it in fast.items() if isinstance(it, apt.GotoRun)) == 20
        want = np.array([[float(v) for v in t] for t in toks])
        got = fast.cl_points().xyz
        assert got.tobytes() == want.tobytes()          # bit for bit, signs of zeros included
        careful = apt.parse_apt(text, "x.apt", fast=False)
        assert fast.records == careful.records and fast.to_text() == text


def test_statement_without_word_is_an_error_naming_the_line():
    """A form feed is a line break for the careful parser: '/ RPM, ...' left without a word is an
    AptError naming file and line (was an IndexError, found by tests/test_fuzz_inputs.py)."""
    text = "UNITS / MM\nSPIND\x0c / RPM, 2000, CLW\nFEDRAT / 500\nGOTO / 1, 2, 3\n"
    for fast in (True, False):
        with pytest.raises(apt.AptError, match=r"x\.apt:3: '/ RPM, 2000, CLW' does not start with an APT word"):
            apt.parse_apt(text, "x.apt", fast=fast)


# --- CLPoints <-> ToolPath: one path type, one arc convention (0 / 2 G2 / 3 G3) ---------------------
from hypothesis import given, settings, strategies as st  # noqa: E402

from cnclab.toolpath.path import ToolPath  # noqa: E402


@st.composite
def _paths(draw):
    """Random programs as ToolPaths: a start above the part, then rapids, lines and CCW/CW arcs (the
    arc end on the circle through its start; z may change: helices), feeds > 0, a spindle speed."""
    n = draw(st.integers(2, 12))
    coord = st.floats(-100, 100, allow_nan=False).map(lambda v: round(v, 3))
    pts, kind, feed, arc, ctr = [[0.0, 0.0, 50.0]], ["rapid"], [np.nan], [0], [[np.nan, np.nan]]
    for _ in range(n):
        x, y, z = draw(coord), draw(coord), draw(st.floats(-20, 40).map(lambda v: round(v, 3)))
        what = draw(st.sampled_from(["rapid", "line", "arc"]))
        if what == "arc":
            c = np.array(pts[-1][:2]) + [draw(st.floats(1, 20)), draw(st.floats(-20, 20))]
            r = float(np.hypot(*(np.array(pts[-1][:2]) - c)))
            a = draw(st.floats(0, 2 * np.pi))
            x, y = c[0] + r * np.cos(a), c[1] + r * np.sin(a)
            arc.append(draw(st.sampled_from([2, 3]))); ctr.append(list(c))
        else:
            arc.append(0); ctr.append([np.nan, np.nan])
        pts.append([x, y, z]); kind.append("rapid" if what == "rapid" else "cut")
        feed.append(np.nan if what == "rapid" else draw(st.sampled_from([300.0, 500.0, 1200.0])))
    return ToolPath.build(pts, kind=kind, feed=feed, arc=arc, arc_center=ctr, spindle=2000.0, cleared=False)


@given(_paths())
@settings(max_examples=80, deadline=None)
def test_clpoints_toolpath_round_trip(path):
    """ToolPath -> CLPoints -> ToolPath keeps every point, rapid flag, feed, spindle, arc (2/3) and
    centre exactly, and the kinds become the geometric ones (classify_moves); CLPoints -> ToolPath ->
    CLPoints is the identity on the CL arrays; both give the same move lengths."""
    cl = apt.CLPoints.from_toolpath(path)
    back = cl.to_toolpath()
    for a in ("xyz", "feed", "spindle", "arc", "arc_center"):
        np.testing.assert_array_equal(getattr(back, a)[1:], getattr(path, a)[1:], err_msg=a)
    np.testing.assert_array_equal(back.xyz[0], path.xyz[0])
    assert np.array_equal(back.is_kind("rapid"), path.is_kind("rapid"))
    again = apt.CLPoints.from_toolpath(back)
    for a in ("xyz", "rapid", "feed", "spindle", "arc", "start"):
        np.testing.assert_array_equal(getattr(again, a), getattr(cl, a), err_msg=a)
    np.testing.assert_array_equal(again.centre[:, :2], cl.centre[:, :2])
    np.testing.assert_allclose(cl.segment_lengths(), path.segment_lengths()[1:], rtol=1e-12, atol=1e-12)


@given(_paths())
@settings(max_examples=60, deadline=None)
def test_apt_writer_takes_a_toolpath_and_reads_back(path):
    """apt_program(path) (6 decimals) parses back (CIRCLE checks included) to the same motions: points
    within 5e-7 mm (half a unit of the 6th decimal), arcs with the same sense, same feeds."""
    cl = apt.parse_apt(apt.apt_program(path, tool_diameter=10, decimals=6).to_text(), "w.apt").cl_points()
    np.testing.assert_allclose(cl.xyz, path.xyz[1:], atol=5e-7)
    np.testing.assert_array_equal(cl.arc, path.arc[1:])
    np.testing.assert_array_equal(cl.rapid, path.is_kind("rapid")[1:])
    np.testing.assert_array_equal(cl.feed[~cl.rapid], path.feed[1:][~cl.rapid])


def test_cl_program_is_apt_program_of_its_toolpath():
    """The sample ch. 8 APT (a committed file) is still written byte for byte by cl_program, which
    now goes through the ToolPath writer."""
    passes = [np.array([[0, 0, 1.0], [5, 0, 1.0]]), np.array([[5, 2, 1.0], [0, 2, 1.5]])]
    for link in ("feed", "rapid"):
        prog = apt.cl_program(passes, 500, 2000, 10, 30, link=link)
        cl = prog.cl_points()
        assert cl.rapid.tolist() == ([True, False, False, False, False, True] if link == "feed" else
                                     [True, False, False, True, True, False, False, True])
        assert np.array_equal(apt.CLPoints.from_toolpath(cl.to_toolpath()).xyz, cl.xyz)
