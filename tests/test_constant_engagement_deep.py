"""The constant-engagement strategy on the deep pocket of issue 29 (60 x 40 mm, D8, a_p 3, depth 7.5,
no start hole) through ``python -m cnclab plan``: it plans the job (three levels) as a program that
passes its own check. Before its cleanup rounded the corners and chose where its rings start
(cnclab.toolpath.ce_clearing: corner_radius_mm, ``_Clearing.ring_start``) it refused the job by its
promise (theta + 35.1 deg in a corner, then theta + 18.3 on a link onto the wall by a corner); measured
now at r / 20: max theta + 9.6 deg, 0.30 % of the cutting length above theta + 5 (it failed with
scipy's "periodic" spline error before cnclab.toolpath.constant_engagement.thin_ring)."""
import json

import pytest

from cnclab.nc.program import check_program

JOB = {"polygon": [[0, 0], [60, 0], [60, 40], [0, 40]], "tool_diameter": 8, "teeth": 2, "theta_deg": 60,
       "a_p": 3, "depth": 7.5, "v_c": 120, "f_z": 0.04}


@pytest.mark.slow      # a three-level plan through the CLI (16 s): make test-slow (CI)
def test_deep_pocket_without_start_hole_is_planned_as_a_safe_program(tmp_path, capsys):
    from cnclab.nc.cli_plan import main

    jf = tmp_path / "deep.json"
    jf.write_text(json.dumps(JOB))
    out = tmp_path / "deep.ngc"
    rc = main([str(jf), "-o", str(out), "--strategy", "constant-engagement"])
    err = capsys.readouterr().err
    assert rc == 0, err
    text = out.read_text()
    chk = check_program(text, 5.0, 0.0)
    assert chk.errors == [] and chk.plunges_into_material == 0 and chk.rapids_below_clearance == 0
    assert "Z-7.5000" in text
