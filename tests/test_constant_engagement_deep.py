"""The constant-engagement strategy on the deep pocket of issue 29 (60 x 40 mm, D8, a_p 3, depth 7.5,
no start hole) through ``python -m cnclab plan``: it plans the job as a program that passes its own
check, or refuses it with the promise it cannot keep and the measured values -- never a crash of its
planner (it failed with scipy's "periodic" spline error before cnclab.toolpath.constant_engagement.thin_ring)."""
import json
import re

from cnclab.nc.program import check_program

JOB = {"polygon": [[0, 0], [60, 0], [60, 40], [0, 40]], "tool_diameter": 8, "teeth": 2, "theta_deg": 60,
       "a_p": 3, "depth": 7.5, "v_c": 120, "f_z": 0.04}


def test_deep_pocket_without_start_hole_plans_or_refuses_with_the_measured_promise(tmp_path, capsys):
    from cnclab.nc.cli_plan import main

    jf = tmp_path / "deep.json"
    jf.write_text(json.dumps(JOB))
    out = tmp_path / "deep.ngc"
    rc = main([str(jf), "-o", str(out), "--strategy", "constant-engagement"])
    err = capsys.readouterr().err
    if rc == 0:
        text = out.read_text()
        chk = check_program(text, 5.0, 0.0)
        assert chk.errors == [] and chk.plunges_into_material == 0 and chk.rapids_below_clearance == 0
        assert "Z-7.5000" in text
        return
    # refused: exit 2, nothing written, the message names the job, the promise and what was measured
    assert rc == 2 and not out.exists(), err
    assert "cannot plan this job" not in err, err                # not a crash of the planner
    assert re.search(r"deep\.json: the constant-engagement strategy promises an engagement <= theta \+ 15 deg.*"
                     r"measures max \d+\.\d deg \(theta 60 \+ \d+\.\d\) at \(-?\d+\.\d\d, -?\d+\.\d\d\) in its "
                     r"(laps|links cutting material|cleanup), \d+\.\d\d % of the cutting length above theta \+ 5 deg",
                     err), err
