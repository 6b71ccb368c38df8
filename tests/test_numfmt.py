"""Vectorised NC number formatting and the array G-code writer are byte-identical to the Python
formatting / the Move-by-Move writer (ties, negative zeros, huge/small values, modal rules)."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cnclab.nc import apt
from cnclab.nc.program import write_linear_moves, write_moves
from cnclab.nc.numfmt import fixed, python_fixed, scaled_ints
from cnclab.nc.spindle_control import gcode_text, insert_spindle_records, spindle_schedule, to_gcode_moves
from cnclab.geometry.mesh import read_stl
from cnclab.paths import data_path

HARD = np.array([0.0, -0.0, 0.5, 1.5, 2.5, -0.5, -2.5, 0.00005, 0.00015, -0.00005, 0.12345, 1e-300, -1e-300,
                 123456.78905, 2.675, 1.0005, -1.0005, 999.99995, 1e12 + 0.5])


@pytest.mark.parametrize("d", [0, 1, 3, 4, 8])
def test_fixed_matches_python_on_ties_and_random(d):
    rng = np.random.default_rng(d)
    v = np.concatenate([HARD, rng.normal(0, 100, 5000), np.round(rng.normal(0, 50, 2000), d + 1),
                        (np.arange(-500, 500) + 0.5) / 10 ** d, [np.nan, np.inf, -np.inf, 1e30]])
    assert fixed(v, d).tolist() == [python_fixed(x, d) for x in v.tolist()]
    fin = v[np.isfinite(v) & (np.abs(v) < 1e9)]
    k = scaled_ints(fin, d)
    # the scaled integers spell the same digits as Python
    assert [str(abs(x)).rjust(d + 1, "0") for x in k.tolist()] == \
        [python_fixed(x, d).lstrip("-").replace(".", "") for x in fin.tolist()]


@settings(max_examples=200, deadline=None)
@given(st.floats(allow_nan=False, allow_infinity=False, min_value=-1e9, max_value=1e9), st.integers(0, 6))
def test_fixed_property(v, d):
    assert fixed([v], d)[0] == python_fixed(v, d)


def _moves_program(rng, n):
    """A linear program with rapids, repeated points (after rounding), spindle on/off, feed changes."""
    xyz = np.round(rng.normal(0, 20, (n, 3)), int(rng.integers(3, 6)))
    xyz[rng.random(n) < 0.2] = xyz[rng.random(n) < 0.2][:1] if n else xyz[:0]
    xyz[5:9] = xyz[4]                                   # zero-length moves
    xyz[10, 0] = -0.00001                               # prints as 0.0000
    rapid = rng.random(n) < 0.1
    feed = np.round(rng.choice([500.0, 750.25, 1000.05, 333.333], n), 3)
    spindle = rng.choice([np.nan, 2000.0, 2500.5, 3002.0], n)
    return xyz, rapid, feed, spindle


@pytest.mark.parametrize("seed", range(5))
def test_gcode_linear_matches_move_writer(seed):
    from cnclab.nc.gcode import Move

    rng = np.random.default_rng(seed)
    xyz, rapid, feed, spindle = _moves_program(rng, 300)
    moves = [Move("G0", *p, spindle=None if np.isnan(s) else s) if r else
             Move("G1", *p, feed=f, spindle=None if np.isnan(s) else s)
             for p, r, f, s in zip(xyz.tolist(), rapid, feed.tolist(), spindle.tolist())]
    for dec in (3, 4):
        assert write_linear_moves(xyz, rapid, feed, spindle, header="t\nu", decimals=dec) == \
            write_moves(moves, header="t\nu", decimals=dec)
    with pytest.raises(ValueError, match="no feed"):
        write_linear_moves(xyz, np.zeros(len(xyz), bool), np.full(len(xyz), np.nan), spindle)


def test_postprocessed_program_gcode_identical():
    mesh = read_stl(data_path("mgherony2024", "sample_ch8_part.stl"))
    prog = apt.read_apt(data_path("mgherony2024", "sample_ch8_zigzag_Af0.apt"))
    cl = prog.cl_points()
    s = spindle_schedule(mesh, cl, tool_diameter=10, a_p=0.3, v_c=63, f_z=0.125, teeth=2, feed_direction_deg=0)
    new, _ = insert_spindle_records(prog, cl, s)
    for p in (prog, new):
        assert gcode_text(p, header="h") == write_moves(to_gcode_moves(p), header="h")
