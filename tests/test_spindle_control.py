"""Spindle-speed post-processor (cnclab.nc.spindle_control) and the `spindle` CLI."""
import numpy as np
import pytest

from cnclab.__main__ import main as cli
from cnclab.nc import spindle_control as sc
from cnclab.cutting.speeds import spindle_speed
from cnclab.geometry.freeform_part import tessellate_heightfield
from cnclab.geometry.mesh import write_stl
from cnclab.paths import data_path
from cnclab.nc import apt

STL = data_path("mgherony2024", "sample_ch8_part.stl")
APT = data_path("mgherony2024", "sample_ch8_zigzag_Af0.apt")


def _flat_case(slope_deg=0.0):
    t = np.tan(np.radians(slope_deg))
    mesh = tessellate_heightfield(lambda x, y: t * y, (0, 20), (0, 20), 4, 4)
    passes = [np.array([[x, 10.0, t * 10] for x in np.linspace(2, 18, 9)])]
    return mesh, apt.cl_program(passes, 500, 2000, 10, 30)


def test_horizontal_surface_gives_eq_7_4_everywhere():
    mesh, prog = _flat_case()
    s = sc.spindle_schedule(mesh, prog.cl_points(), tool_diameter=10, a_p=0.3, v_c=63, f_z=0.125, teeth=2)
    np.testing.assert_allclose(s.n, 1000 * 63 / (np.pi * 2 * np.sqrt(0.3 * 9.7)))
    np.testing.assert_allclose(s.v_f, 0.25 * s.n)
    np.testing.assert_allclose(s.v_c_actual, 63.0)
    assert s.within_share() == 1.0


def test_limits_and_counts():
    mesh, prog = _flat_case()
    s = sc.spindle_schedule(mesh, prog.cl_points(), tool_diameter=10, a_p=0.3, v_c=63, f_z=0.125, teeth=2,
                            n_max=4000)
    assert (s.n == 4000).all() and s.limited.all()
    s = sc.spindle_schedule(mesh, prog.cl_points(), tool_diameter=10, a_p=0.3, v_c=63, f_z=0.125, teeth=2,
                            vf_max=900)
    assert np.allclose(s.v_f, 900) and s.within_share() == 0.0
    with pytest.raises(ValueError, match="n_max"):
        sc.spindle_schedule(mesh, prog.cl_points(), tool_diameter=10, a_p=0.3, v_c=63, f_z=0.125, teeth=2, n_max=-1)
    with pytest.raises(ValueError, match="teeth"):
        sc.spindle_schedule(mesh, prog.cl_points(), tool_diameter=10, a_p=0.3, v_c=63, f_z=0.125, teeth=1.5)


def test_slope_across_feed_point_rules():
    mesh, prog = _flat_case(20.0)   # surface rises towards +y, feed along +x: uphill on the left (point 1)
    cl = prog.cl_points()
    kw = dict(tool_diameter=10, a_p=0.3, v_c=63, f_z=0.125, teeth=2)
    mx = sc.spindle_schedule(mesh, cl, point="max", **kw)
    p1 = sc.spindle_schedule(mesh, cl, point="1", **kw)
    p2 = sc.spindle_schedule(mesh, cl, point="2", **kw)
    assert np.allclose(mx.d_eff, np.maximum(p1.d_eff, p2.d_eff))
    assert (p1.d_eff > p2.d_eff).all()
    assert np.allclose(mx.A_N2, 20.0) and np.allclose(mx.A_N1, 90.0)


def test_acceleration_limit_is_respected():
    n_t = np.array([3000, 6000, 6000, 3000, 3000, 5000.0])
    L = np.full(6, 1.0)
    out = sc.apply_acceleration_limit(n_t, L, 0.125, 2, 2000.0)
    dt = L[1:] / (0.25 * out[:-1] / 60)
    assert (np.abs(np.diff(out)) <= 2000 * dt + 1e-9).all()
    assert np.isclose(out[0], 3000) and out.max() <= 6000


def test_threshold_insertion_keeps_every_original_record():
    prog = apt.read_apt(APT)
    cl = prog.cl_points()
    from cnclab.geometry.mesh import read_stl
    s = sc.spindle_schedule(read_stl(STL), cl, tool_diameter=10, a_p=0.3, v_c=63, f_z=0.125, teeth=2)
    new, counts = sc.insert_spindle_records(prog, cl, s, rpm_threshold=100, vf_threshold=25)
    orig = [r.raw for r in new.records if r.line]
    assert orig == [r.raw for r in prog.records]
    back = apt.parse_apt(new.to_text()).cl_points()
    fp = ~back.rapid
    assert np.all(np.abs(back.spindle[fp] - s.n) <= 100 + 0.5)
    assert np.all(np.abs(back.feed[fp] - s.v_f) <= 25 + 0.05)
    few, c2 = sc.insert_spindle_records(prog, cl, s, rpm_threshold=1000, vf_threshold=250)
    assert c2["spindl_inserted"] < counts["spindl_inserted"]


def test_cli_writes_apt_and_gcode_and_refuses_bad_input(tmp_path, capsys):
    out, ngc = tmp_path / "o.apt", tmp_path / "o.ngc"
    rc = cli(["spindle", str(STL), str(APT), "-o", str(out), "--vc", "63", "--fz", "0.125", "--teeth", "2",
              "--ap", "0.3", "--ae", "1", "--gcode", str(ngc)])
    assert rc == 0 and "inserted SPINDL" in capsys.readouterr().out
    from cnclab.nc.gcode import parse_gcode
    moves = parse_gcode(ngc.read_text(), str(ngc))
    feeds = [m for m in moves if m.motion == "G1"]
    assert max(m.spindle for m in feeds) == pytest.approx(spindle_speed(63, 2 * np.sqrt(0.3 * 9.7)), abs=0.5)
    before = APT.read_bytes()
    assert cli(["spindle", str(STL), str(APT), "-o", str(APT), "--vc", "63", "--fz", "0.125", "--teeth", "2",
                "--ap", "0.3"]) == 2
    assert APT.read_bytes() == before
    bad = tmp_path / "bad.apt"
    bad.write_text("UNITS / MM\nFEDRAT / 500, MMPM\nGOTO / 1, 2\n")
    out2 = tmp_path / "never.apt"
    assert cli(["spindle", str(STL), str(bad), "-o", str(out2), "--vc", "63", "--fz", "0.125", "--teeth", "2",
                "--ap", "0.3"]) == 2
    assert "bad.apt:3" in capsys.readouterr().err and not out2.exists()
    assert not list(tmp_path.glob(".never.apt*"))   # no partial output


@pytest.mark.parametrize("seed", range(4))
def test_insertions_match_a_python_walk(seed):
    """The compiled threshold walk of insert_spindle_records gives exactly the records of the plain
    Python walk (round(n), round(v_f, 1) as Python rounds, ties at .x5 included), also around an
    original SPINDL/FEDRAT of the file, which resets the value in force."""
    rng = np.random.default_rng(seed)
    P = np.column_stack([np.arange(300.0), np.zeros(300), np.zeros(300)])
    text = apt.cl_program([P], 500, 2000, 10, 30).to_text()
    lines = text.splitlines(keepends=True)
    k = next(i for i, ln in enumerate(lines) if ln.startswith("GOTO / 150.000"))
    text = "".join(lines[:k] + ["SPINDL / RPM, 3000, CLW\n", "FEDRAT / 700.0, MMPM\n"] + lines[k:])
    prog = apt.parse_apt(text, "p.apt")
    cl = prog.cl_points()
    idx = np.flatnonzero(~cl.rapid)
    thr_n, thr_f = rng.choice([0.0, 20.0, 300.0]), rng.choice([0.0, 5.0, 80.0])
    if seed % 2:
        n = np.round(rng.uniform(1000, 5000, idx.size) * 2) / 2         # many .5 ties for round()
        f = np.round(rng.uniform(100, 1500, idx.size) * 20) / 20        # many .x5 ties for round(., 1)
    else:                                                               # differences exactly at the thresholds
        thr_n, thr_f = 20.0, 5.0
        n = 3000.0 + thr_n * rng.integers(-2, 3, idx.size)
        f = 700.0 + thr_f * rng.integers(-2, 3, idx.size)
    s = sc.SpindleSchedule(idx, cl.xyz[idx], idx, *(np.zeros(idx.size),) * 4, n, n, f,
                           np.ones(idx.size), np.zeros(idx.size, bool), 63.0, {})
    new, counts = sc.insert_spindle_records(prog, cl, s, thr_n, thr_f)
    # reference: the walk over the expanded records, one Python step per feed point
    want, cur_n, cur_f, j = [], float("nan"), float("nan"), 0
    tgt = cl.record[idx].tolist()
    for r_i, r in enumerate(prog.records):
        if r.word == "SPINDL":
            cur_n = r.values[-1]
        elif r.word == "FEDRAT":
            cur_f = r.values[0]
        if j < len(tgt) and tgt[j] == r_i:
            if not abs(n[j] - cur_n) <= thr_n:
                cur_n = round(float(n[j]))
                want.append(apt.spindl(cur_n).raw)
            if not abs(f[j] - cur_f) <= thr_f:
                cur_f = round(float(f[j]), 1)
                want.append(apt.fedrat(cur_f).raw)
            j += 1
        want.append(r.raw)
    assert new.to_text() == "".join(want)
    assert counts["spindl_inserted"] == sum(w.startswith("SPINDL / RPM") for w in want) - 2
    assert counts["fedrat_inserted"] == sum(w.startswith("FEDRAT") for w in want) - 2


def test_schedule_of_the_toolpath_equals_the_schedule_of_its_cl_points():
    """The post-processor works on the one path type: the schedule of cl.to_toolpath() is the
    schedule of the CL points, value for value (same lengths, directions, facets)."""
    mesh, prog = _flat_case()
    cl = prog.cl_points()
    kw = dict(tool_diameter=10, a_p=0.3, v_c=63, f_z=0.125, teeth=2, n_max=9000)
    a = sc.spindle_schedule(mesh, cl, **kw)
    b = sc.spindle_schedule(mesh, cl.to_toolpath(), **kw)
    for name in ("n", "v_f", "d_eff", "index"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    np.testing.assert_array_equal(sc.path_surface_deviation(mesh, cl, 5.0),
                                  sc.path_surface_deviation(mesh, cl.to_toolpath(), 5.0))
    with pytest.raises(TypeError, match="CLPoints or a ToolPath"):
        sc.spindle_schedule(mesh, cl.xyz, **kw)
