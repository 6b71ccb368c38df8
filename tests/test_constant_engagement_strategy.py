"""The registered constant-engagement strategy plans the pockets on which it keeps its promise
(engagement <= theta + CE_PROMISE_DEG everywhere, <= theta + 5 deg on all but CE_SHARE_ABOVE_5_PCT % of
the cutting length, measured by the one evaluator at r / 20), as a safe program: issue 28 item 2.
Measured (cnclab/toolpath/planners.py): the free-form bench pocket data/pockets/spline_pocket.json,
refused before the link limit (one link into material at theta + 51.9 deg), plans at max theta + 6.1
deg, 0.03 % above theta + 5, its tool centres CE_WALL_MARGIN_MM (0.02 mm) inside the final contour
(without it, 0.006 mm past the wall near (29.8, 25.0)), so the walls keep a skin that thin.
Jacso's rectangle (data/jacso2021, 40 x 24 mm, D6, theta 60), refused before its cleanup rounded the
corners (the cleanup turning on the spot in a corner: theta + 30.8 deg), plans at theta + 11.3 deg,
0.29 % above theta + 5, the corner fillets of CE_CORNER_FRACTION x r leaving 8.15 mm^2 uncut."""
import math

import pytest

from cnclab.nc.program import check_program, write_program
from cnclab.paths import data_path
from cnclab.toolpath import planners
from cnclab.toolpath.evaluate import evaluate
from cnclab.toolpath.job import load_job


def _planned_within_the_promise(job):
    """The strategy's plan of ``job`` and its evaluation at the check's resolution, asserted within the
    promise and with nothing plunged or rapid into material."""
    path = planners.plan(job, "constant-engagement")
    ev = evaluate(path, job, planners.CE_CHECK_TOOL_FRACTION * job.tool_radius)
    assert ev.engagement_max_deg <= job.theta_deg + planners.CE_PROMISE_DEG
    assert ev.share_above_5_pct <= planners.CE_SHARE_ABOVE_5_PCT
    assert ev.plunges_into_material == 0 and ev.rapids_into_material == 0
    return path, ev


@pytest.mark.slow
def test_spline_pocket_is_planned_within_the_promise_and_safely():
    job = load_job(data_path("pockets", "spline_pocket.json"))
    path, ev = _planned_within_the_promise(job)
    # the corner cusps (0.28 mm^2 without the margin) and the wall skin of CE_WALL_MARGIN_MM (measured 3.60 mm^2)
    assert ev.uncut_beyond_unreachable_mm2 < 1.0 + job.polygon.length * planners.CE_WALL_MARGIN_MM
    assert ev.wall_gouge_max_mm == 0.0
    chk = check_program(write_program(path, job), job.clearance_z, job.top_z)
    assert chk.errors == [] and chk.plunges_into_material == 0 and chk.rapids_below_clearance == 0


def test_rectangle_is_planned_within_the_promise_its_corners_rounded():
    """The same properties on Jacso's rectangle (sharp corners, where the laps cannot follow), the
    uncut area bounded by what the rounded corners leave: 4 x (1 - pi/4) ((rho + r)^2 - r^2) beyond
    the unreachable cusps, plus the wall skin and 1 mm^2 as on the spline pocket."""
    job = load_job(data_path("jacso2021", "rectangle_pocket.json"))
    path, ev = _planned_within_the_promise(job)
    r, rho = job.tool_radius, planners.CE_CORNER_FRACTION * job.tool_radius
    corners = 4 * (1 - math.pi / 4) * ((rho + r) ** 2 - r ** 2)
    assert ev.uncut_beyond_unreachable_mm2 < corners + 1.0 + job.polygon.length * planners.CE_WALL_MARGIN_MM
    assert ev.wall_gouge_max_mm == 0.0
    chk = check_program(write_program(path, job), job.clearance_z, job.top_z)
    assert chk.errors == [] and chk.plunges_into_material == 0 and chk.rapids_below_clearance == 0
