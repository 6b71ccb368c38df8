"""``python -m cnclab finish-path``: the ch. 7-9 drop-cutter zig-zag from an STL, then ``spindle``."""
import hashlib

import pytest

from cnclab.nc import apt, cli_finish_path, cli_spindle
from cnclab.paths import data_path

STL = data_path("mgherony2024", "sample_ch8_part.stl")
SAMPLE = data_path("mgherony2024", "sample_ch8_zigzag_Af0.apt")


def _digest(p):
    return hashlib.sha256(p.read_bytes()).hexdigest()


def test_reproduces_the_committed_sample_byte_for_byte(tmp_path):
    # the sample's recipe (ch7_9.sample_ch8_apt): D 10, a_e 1, A_f 0, 2 mm step, Table 7-1 n and v_f, Z30
    # (= part top 10 + clearance 20); the CLI reads the STL instead of tessellating the part itself
    out = tmp_path / "af0.apt"
    assert cli_finish_path.main([str(STL), "-o", str(out), "--tool-diameter", "10", "--stepover", "1",
                                 "--feed-angle", "0", "--step", "2", "--clearance", "20",
                                 "--partno", "SAMPLE_CH8_AF0", "--quiet"]) == 0
    assert out.read_text() == SAMPLE.read_text()


def test_then_spindle_end_to_end(tmp_path, capsys):
    path, ctl, ngc = tmp_path / "af90.apt", tmp_path / "af90_vc63.apt", tmp_path / "af90_vc63.ngc"
    assert cli_finish_path.main([str(STL), "-o", str(path), "--tool-diameter", "10", "--stepover", "2",
                                 "--feed-angle", "90", "--step", "2"]) == 0
    out = capsys.readouterr().out
    assert f"wrote {path}" in out
    prog = apt.read_apt(path)
    cl = prog.cl_points()
    # passes run along y (A_f = 90 deg): consecutive feed points of a pass share x
    assert len(cl) > 100
    assert cli_spindle.main([str(STL), str(path), "-o", str(ctl), "--gcode", str(ngc), "--vc", "63", "--fz", "0.125",
                             "--teeth", "2", "--ap", "0.3"]) == 0
    out = capsys.readouterr().out
    assert "part/path check: 0.0 % of feed points" in out      # the path lies on the part
    assert str(ctl) in out and str(ngc) in out                  # the summary names both outputs
    assert "SPINDL" in ctl.read_text() and "M3" in ngc.read_text()


@pytest.mark.parametrize("opt, value", [("--stepover", "-1"), ("--stepover", "nan"), ("--tool-diameter", "0"),
                                        ("--step", "1_0"), ("--feed", "inf"), ("--feed-angle", "400"),
                                        ("--rpm", "0x10")])
def test_bad_numbers_name_the_option(tmp_path, capsys, opt, value):
    out = tmp_path / "p.apt"
    args = {"--tool-diameter": "10", "--stepover": "1"}
    args[opt] = value
    argv = [str(STL), "-o", str(out)] + [x for kv in args.items() for x in kv]
    with pytest.raises(SystemExit) as exc:
        cli_finish_path.main(argv)
    assert exc.value.code == 2
    assert opt in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_refuses_to_overwrite_the_input_and_leaves_nothing_on_error(tmp_path, capsys):
    stl = tmp_path / "part.stl"
    stl.write_bytes(STL.read_bytes())
    before = _digest(stl)
    assert cli_finish_path.main([str(stl), "-o", str(stl), "--tool-diameter", "10", "--stepover", "1"]) == 2
    assert "must differ" in capsys.readouterr().err and _digest(stl) == before
    bad = tmp_path / "bad.stl"
    bad.write_bytes(STL.read_bytes()[:200])                    # truncated binary STL
    assert cli_finish_path.main([str(bad), "-o", str(tmp_path / "x.apt"), "--tool-diameter", "10",
                                 "--stepover", "1"]) == 2
    assert "bad.stl" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.stl", "part.stl"]
