"""Machine time (cnclab.nc.machine): closed-form cases of the look-ahead planner."""
import math

import pytest

from cnclab.nc.gcode import Move, parse_gcode
from cnclab.nc.machine import GRBL_ROUTER, SMALL_VMC, Machine, machine_time, trapezoid_time

M = Machine("test", (6000.0, 6000.0, 6000.0), (100.0, 100.0, 100.0), 0.05)   # 100 mm/s, 100 mm/s^2


def test_single_line_trapezoid_and_triangle():
    """One line from rest to rest: trapezoid t = L/v + v/a when L >= v^2/a, else triangle 2 sqrt(L/a)."""
    v, a = 100.0, 100.0
    for L in (50.0, 100.0, 250.0, 1000.0):
        t = machine_time([Move("G1", L, 0, 0, feed=60 * v)], M, start=(0, 0, 0))["time_machine_s"]
        expected = L / v + v / a if L >= v * v / a else 2 * math.sqrt(L / a)
        assert t == pytest.approx(expected, rel=1e-12)
    # a diagonal in x/y: both axes at their limits, the vector speed and acceleration sqrt(2) larger
    t = machine_time([Move("G1", 1000, 1000, 0, feed=1e6)], M, start=(0, 0, 0))["time_machine_s"]
    vd = ad = 100 * math.sqrt(2)
    assert t == pytest.approx(1000 * math.sqrt(2) / vd + vd / ad, rel=1e-12)


def test_right_angle_corner_junction_deviation():
    """Two 1000 mm legs at 90 deg: the corner speed is GRBL's v_j = sqrt(a delta sin45 / (1 - sin45)),
    each leg a trapezoid from/to it (closed form)."""
    a, v, delta = 100.0, 100.0, M.junction_deviation_mm
    moves = [Move("G1", 1000, 0, 0, feed=60 * v), Move("G1", 1000, 1000, 0, feed=60 * v)]
    t = machine_time(moves, M, start=(0, 0, 0))["time_machine_s"]
    s = math.sin(math.pi / 4)
    # the junction vector (exit - entry direction) is diagonal: its acceleration limit is a sqrt(2)
    vj = math.sqrt(a * math.sqrt(2) * delta * s / (1 - s))
    leg = trapezoid_time(1000, 0, v, vj, a)
    assert t == pytest.approx(2 * leg, rel=1e-12)
    assert t == pytest.approx(2 * (1000 / v + v / (2 * a) + (v - vj) ** 2 / (2 * a * v)), rel=1e-12)
    # straight on (180 deg): no slow-down; full reversal: a stop
    t_straight = machine_time([Move("G1", 500, 0, 0, feed=6000), Move("G1", 1000, 0, 0, feed=6000)], M,
                              start=(0, 0, 0))["time_machine_s"]
    assert t_straight == pytest.approx(1000 / v + v / a, rel=1e-12)
    t_back = machine_time([Move("G1", 500, 0, 0, feed=6000), Move("G1", 0, 0, 0, feed=6000)], M,
                          start=(0, 0, 0))["time_machine_s"]
    assert t_back == pytest.approx(2 * (500 / v + v / a), rel=1e-12)


def test_full_circle_at_the_centripetal_limit():
    """A full circle of radius r at a feed above sqrt(a r): cruise at v_c = sqrt(a r), from rest to
    rest: t = 2 pi r / v_c + v_c / a."""
    a, r = 100.0, 4.0
    vc = math.sqrt(a * r)                               # 20 mm/s < the 100 mm/s feed and axis limits
    t = machine_time([Move("G2", r, 0, 0, i=-r, j=0, feed=6000)], M, start=(r, 0, 0))["time_machine_s"]
    assert t == pytest.approx(2 * math.pi * r / vc + vc / a, rel=1e-12)
    # below the limit the feed governs
    f = 600.0                                           # 10 mm/s
    t2 = machine_time([Move("G2", r, 0, 0, i=-r, j=0, feed=f)], M, start=(r, 0, 0))["time_machine_s"]
    assert t2 == pytest.approx(2 * math.pi * r / 10 + 10 / a, rel=1e-12)


def test_block_rate_limit_and_canonical_bound():
    """Many tiny blocks: a block-rate limit makes each last >= 1/rate; the machine time is never below
    the canonical length / feed time."""
    moves = [Move("G1", 0.1 * k, 0, 0, feed=6000) for k in range(1, 1001)]       # 100 mm in 0.1 mm blocks
    slow = Machine("slow", (6000, 6000, 6000), (100, 100, 100), 0.05, block_rate_hz=200)
    t = machine_time(moves, slow, start=(0, 0, 0))["time_machine_s"]
    assert t >= 1000 / 200 - 1e-9
    t_free = machine_time(moves, M, start=(0, 0, 0))["time_machine_s"]
    assert t_free == pytest.approx(2.0, rel=1e-9)        # one 100 mm line: triangle 2 sqrt(100/100)
    for m in (SMALL_VMC, GRBL_ROUTER):
        text = "G21 G90\nG0 X0 Y0 Z5\nG1 Z0 F300\nG1 X30 F1200\nG2 X30 Y10 I0 J5\nG1 X0\nG0 Z5\n"
        mv = parse_gcode(text)
        from cnclab.nc.gcode import program_time
        canon = program_time(mv, rapid_mm_min=m.max_rate_mm_min[0])["total_s"]
        assert machine_time(mv, m)["time_machine_s"] >= canon - 1e-9


def test_analyze_reports_time_machine_s(tmp_path):
    """``analyze`` reports time_machine_s beside the length / feed time; a machine that accelerates
    never beats the canonical time."""
    import json

    from cnclab.nc.cli_analyze import analyze
    from cnclab.nc.program import write_program
    from cnclab.toolpath.job import load_job
    from cnclab.toolpath.planners import plan

    jf = tmp_path / "job.json"
    jf.write_text(json.dumps({"polygon": [[0, 0], [30, 0], [30, 20], [0, 20]], "tool_diameter": 6, "theta_deg": 60,
                              "a_p": 1, "v_c": 120, "f_z": 0.04, "teeth": 2}))
    job = load_job(jf)
    prog = tmp_path / "p.ngc"
    write_program(plan(job, "adaptive", 0.2), job, out=prog)
    res = analyze(prog, jf, 0.2, outdir=tmp_path / "out", quiet=True)
    rows = {r.split(",")[0]: r.split(",")[1] for r in (tmp_path / "out" / "summary.csv").read_text().splitlines()[1:]}
    assert float(rows["time_machine_s"]) >= res["evaluation"].time_total_s - 1e-6 > 0
