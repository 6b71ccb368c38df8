"""APT CL parser/writer (cnclab.toolpath.apt): round trip, dialect, bad input naming file and line."""
import numpy as np
import pytest

from cnclab.paths import data_path
from cnclab.toolpath import apt

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


def test_generated_program_parses_back():
    passes = [np.array([[0, 0, 1.0], [5, 0, 1.5]]), np.array([[5, 1, 1.5], [0, 1, 1.0]])]
    prog = apt.cl_program(passes, 500, 2000, 10, 30)
    back = apt.parse_apt(prog.to_text())
    cl = back.cl_points()
    feed = cl.xyz[~cl.rapid]
    np.testing.assert_allclose(feed, np.vstack(passes)[1:])


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
