"""Job files: every data/ job loads; hostile inputs get a ValueError naming the file and the JSON path;
corrupted JSON gives such an error or a correct Job (hypothesis); to_dict/from_dict round trip."""
import json
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cnclab.paths import data_path
from cnclab.toolpath.job import JOB_SCHEMA, Job, load_job, theta_min_deg

RECT = {"polygon": [[0, 0], [40, 0], [40, 24], [0, 24]], "start_hole": {"center": [20, 12], "diameter": 11},
        "tool_diameter": 6.0, "teeth": 1, "v_c": 120.0, "f_z": 0.04, "feed_mm_min": 255, "a_p": 3.0,
        "theta_deg": 60.0}
JOB_FILES = [("jacso2021", "rectangle_pocket.json"), ("jacso2021", "l_pocket.json"),
             ("jacso2021", "star_pocket.json"), ("kim_yang2006", "pocket_120x85.json")]


@pytest.mark.parametrize("work,name", JOB_FILES)
def test_every_job_file_loads(work, name):
    job = load_job(data_path(work, name))
    assert job.polygon.is_valid and job.allowed().area > 0
    assert job.feed_mm_min > 0 and job.spindle_rpm > 0 and job.levels()[-1] == pytest.approx(-job.depth)
    again = Job.from_dict(job.to_dict(), "roundtrip")
    assert again.polygon.symmetric_difference(job.polygon).area < 1e-9
    assert (again.feed_mm_min, again.spindle_rpm, again.start_hole) == (job.feed_mm_min, job.spindle_rpm, job.start_hole)


def test_kim_yang_job_carries_table1_data():
    job = load_job(data_path("kim_yang2006", "pocket_120x85.json"))
    assert len(job.polygon.interiors) == 1                          # the island
    assert job.a_e == pytest.approx(3.0, abs=1e-9)                   # theta = arccos(1 - b/r), b = 3 mm
    assert (job.tool_diameter, job.a_p, job.feed_mm_min, job.spindle_rpm) == (10.0, 0.5, 500.0, 2000.0)
    assert job.start_hole is None


def _poly(**kw):
    return dict(RECT, **kw)


HOSTILE = [  # (mapping or raw text, fragment of the message)
    (_poly(polygon=[[0, 0], [5, 0], [5, 30], [0, 30]], start_hole={"center": [2.5, 15], "diameter": 6}),
     "$.polygon: the tool (diameter 6 mm) cannot enter"),
    (_poly(start_hole={"center": [20, 12], "diameter": 4}), "$.start_hole.diameter: start hole diameter 4"),
    (_poly(start_hole={"center": [1, 1], "diameter": 11}), "$.start_hole: the start hole at (1, 1)"),
    (_poly(teeth=2.7), "$.teeth: 2.7 is not of type 'integer'"),
    (_poly(teeth=0.5), "$.teeth: 0.5 is not of type 'integer'"),
    (_poly(teeth=0), "$.teeth: 0 is less than the minimum of 1"),
    (_poly(theta_deg=0), "$.theta_deg: 0 is less than or equal to the minimum of 0"),
    (_poly(theta_deg=180), "$.theta_deg: 180 is greater than or equal to the maximum of 180"),
    (_poly(theta_deg=5.0), "$.theta_deg: theta_deg = 5 deg is below 11.5 deg"),
    (_poly(islands=[[[50, 5], [55, 5], [55, 10]]]), "$.islands[0]: the island is not inside"),
    (_poly(islands=[[[5, 5], [15, 5], [15, 15], [5, 15]], [[10, 10], [18, 10], [18, 18]]]),
     "$.islands[1]: the island overlaps"),
    (_poly(polygon=[[0, 0], [40, 24], [40, 0], [0, 24]]), "$.polygon: not a simple polygon (Self-intersection"),
    (_poly(start_hole={"center": [20], "diameter": 11}), "$.start_hole.center: [20] is too short"),
    (_poly(tool_diameter="6"), "$.tool_diameter: '6' is not of type 'number'"),
    (_poly(tool_diameter=True), "$.tool_diameter: True is not of type 'number'"),
    (_poly(teth=2), "$: unknown key(s) ['teth']"),
    (_poly(start_hole={"center": [1, 2], "diameter": 11, "d": 3}), "$.start_hole: unknown key(s) ['d']"),
    ({k: v for k, v in RECT.items() if k != "polygon"}, "give exactly one of 'polygon'"),
    ({k: v for k, v in RECT.items() if k != "f_z"}, None),                     # feed given: fine
    ({k: v for k, v in RECT.items() if k != "v_c"} | {"spindle_rpm": 6000}, None),
    ({k: v for k, v in RECT.items() if k != "v_c"}, "give the spindle speed: 'v_c'"),
    ({k: v for k, v in RECT.items() if k not in ("feed_mm_min", "f_z")}, "give the feed: 'f_z'"),
    ([RECT], "$: a job must be a JSON object"),
    (b'{"polygon": \xff\xfe}', "not UTF-8 text: byte 0xff at offset 12"),
    ('{"polygon": [[0, 0],\n [1, 2]\n', ":3:1: invalid JSON"),
    ('{"tool_diameter": NaN}', "NaN is not a number"),
    ('{"tool_diameter": 1e999}', "out of range"),
]


@pytest.mark.parametrize("case,msg", HOSTILE)
def test_hostile_jobs(tmp_path, case, msg):
    f = tmp_path / "hostile.json"
    if isinstance(case, bytes):
        f.write_bytes(case)
    elif isinstance(case, str):
        f.write_text(case, encoding="utf-8")
    else:
        f.write_text(json.dumps(case), encoding="utf-8")
    before = f.read_bytes()
    if msg is None:
        assert isinstance(load_job(f), Job)
        return
    with pytest.raises(ValueError) as exc:
        load_job(f)
    assert str(exc.value).startswith(str(f)) and msg in str(exc.value), str(exc.value)
    assert f.read_bytes() == before                               # input never touched


def test_missing_file_is_oserror(tmp_path):
    with pytest.raises(OSError):
        load_job(tmp_path / "nope.json")


def test_theta_lower_bound_is_the_lap_cap():
    """theta_min: R_in / a_e(theta_min) = MAX_LAPS laps (R_in = 12 mm in the 40 x 24 rectangle)."""
    t = theta_min_deg(Job.from_dict(RECT).polygon, 3.0, max_laps=200)
    assert 12.0 / (3.0 * (1 - math.cos(math.radians(t)))) == pytest.approx(200, rel=1e-3)
    Job.from_dict(_poly(theta_deg=t + 0.1))                       # just above: accepted


def test_islands_are_holes_and_levels():
    job = Job.from_dict(_poly(islands=[[[2, 2], [8, 2], [8, 8], [2, 8]]], depth=7.0, a_p=3.0,
                              start_hole={"center": [30, 12], "diameter": 8}))
    assert len(job.polygon.interiors) == 1 and job.polygon.area == pytest.approx(960 - 36)
    assert job.levels() == pytest.approx([-7 / 3, -14 / 3, -7.0])     # equal levels of <= a_p
    assert job.volume_mm3() == pytest.approx(7.0 * (924 - math.pi * 16), rel=1e-4)


def test_schema_is_a_valid_json_schema():
    import jsonschema

    jsonschema.Draft202012Validator.check_schema(JOB_SCHEMA)


_TEXT = json.dumps(RECT)


@settings(max_examples=150, deadline=None)
@given(st.data())
def test_corrupted_json_gives_error_naming_the_file_or_a_job(tmp_path_factory, data):
    """Any corruption of a valid file (bytes replaced, deleted or inserted): a ValueError starting
    with the file name, or a Job that passes the same checks as a clean one."""
    raw = bytearray(_TEXT.encode())
    for _ in range(data.draw(st.integers(1, 4))):
        op = data.draw(st.sampled_from(["replace", "delete", "insert"]))
        i = data.draw(st.integers(0, len(raw) - 1))
        b = data.draw(st.integers(0, 255))
        if op == "replace":
            raw[i] = b
        elif op == "delete":
            del raw[i]
        else:
            raw.insert(i, b)
    f = tmp_path_factory.mktemp("corrupt") / "job.json"
    f.write_bytes(bytes(raw))
    try:
        job = load_job(f)
    except ValueError as e:
        assert str(e).startswith(str(f)), str(e)
        return
    assert job.polygon.is_valid and job.allowed().area > 0 and 0 < job.theta_deg < 180
    assert job.tool.flutes == int(job.tool.flutes) >= 1 and job.feed_mm_min > 0


def test_regions_give_a_multipolygon_and_round_trip(tmp_path):
    """A job of disjoint regions (data/pockets/two_regions.json) is one MultiPolygon; to_dict/from_dict
    keep it; overlapping regions are refused naming the region."""
    from cnclab.paths import data_path
    from cnclab.toolpath.job import Job, load_job

    job = load_job(data_path("pockets", "two_regions.json"))
    assert job.polygon.geom_type == "MultiPolygon" and len(job.polygon.geoms) == 2
    back = Job.from_dict(job.to_dict())
    assert back.polygon.symmetric_difference(job.polygon).area < 1e-9
    sq = [[0, 0], [20, 0], [20, 20], [0, 20]]
    d = {"regions": [{"polygon": sq}, {"polygon": [[10, 10], [30, 10], [30, 30], [10, 30]]}],
         "tool_diameter": 6, "theta_deg": 60, "a_p": 1}
    with pytest.raises(ValueError, match=r"regions\[1\].*overlaps"):
        Job.from_dict(d, source="j.json")
