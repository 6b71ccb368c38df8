"""Jobs from drawings and the job format's circle rings and plausibility checks: cnclab.toolpath.job
(circle rings, misspelt keys, a_p / spindle / feed limits, inch-looking numbers),
cnclab.toolpath.from_drawing and the CLIs ``job-from-drawing`` and ``plan DRAWING``."""
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from cnclab.nc import cli_drawing, cli_plan
from cnclab.nc.arcfit import DEFAULT_TOL_MM as ARC_TOL_MM
from cnclab.nc.gcode import read_gcode, read_toolpath
from cnclab.nc.program import check_program
from cnclab.paths import data_path
from cnclab.toolpath.evaluate import evaluate
from cnclab.toolpath.from_drawing import job_from_drawing, load_cutting, load_job_input
from cnclab.toolpath.job import SPINDLE_RPM_MAX, Job, load_job, ring_points

FIX = Path(__file__).parent / "fixtures" / "drawings"
CUT = FIX / "cutting.json"
BASE = {"tool_diameter": 8.0, "teeth": 2, "theta_deg": 60.0, "a_p": 3.0, "v_c": 120.0, "f_z": 0.04}
SQUARE = [[0, 0], [60, 0], [60, 40], [0, 40]]


def _job(**kw):
    d = dict(BASE, polygon=SQUARE)
    for k, v in kw.items():
        if v is None:
            d.pop(k, None)
        else:
            d[k] = v
    return Job.from_dict(d, source="j.json")


# -- circle rings ----------------------------------------------------------------------------------
@pytest.mark.parametrize("tol", [None, 0.001, 0.05])
def test_circle_ring_flattened_within_its_tolerance(tol):
    c = {"center": [10, -4], "radius": 25}
    if tol is not None:
        c["tolerance"] = tol
    t = 0.005 if tol is None else tol
    P = ring_points({"circle": c})
    job = _job(polygon={"circle": c})
    assert 0 < math.pi * 625 - job.polygon.area <= 2 * math.pi * 25 * t
    mids = 0.5 * (P + np.roll(P, -1, axis=0))                    # chord middles: sagitta <= tolerance
    sag = 25 - np.hypot(mids[:, 0] - 10, mids[:, 1] + 4)
    assert sag.max() <= t * (1 + 1e-9)


def test_circle_rings_wherever_a_ring_is_allowed():
    isl = {"circle": {"center": [20, 20], "radius": 5}}
    j = _job(islands=[isl, [[40, 10], [50, 10], [50, 20]]])
    assert len(j.polygon.interiors) == 2
    assert j.polygon.area == pytest.approx(2400 - math.pi * 25 - 50, abs=2 * math.pi * 5 * 0.005)
    d = dict(BASE, regions=[{"polygon": {"circle": {"center": [0, 0], "radius": 20}}, "islands": [isl]},
                            {"polygon": [[100, 0], [140, 0], [140, 30], [100, 30]]}])
    with pytest.raises(ValueError, match=r"\$\.regions\[0\]\.islands\[0\]: the island is not inside"):
        Job.from_dict(d, "r.json")
    d["regions"][0]["islands"] = [{"circle": {"center": [0, 0], "radius": 5}}]
    j = Job.from_dict(d, "r.json")
    assert j.polygon.geom_type == "MultiPolygon"
    assert j.polygon.area == pytest.approx(math.pi * 375 + 1200, abs=2 * math.pi * 25 * 0.005)
    back = Job.from_dict(j.to_dict(), "back")                  # written back as points: the same pocket
    assert back.polygon.symmetric_difference(j.polygon).area < 1e-9


@pytest.mark.parametrize("ring,msg", [
    ({"circle": {"center": [0, 0]}}, "$.polygon.circle: 'radius' is a required property"),
    ({"circle": {"center": [0, 0], "radius": -1}}, "$.polygon.circle.radius: -1 is less than or equal to the minimum"),
    ({"circle": {"center": [0, 0], "radius": 30, "tol": 1}}, "$.polygon.circle: unknown key(s) ['tol'] ('tol': did you "
                                                            "mean 'tolerance'? (it is not given))"),
    ({"circle": {"center": [0, 0], "radius": 30, "tolerance": 1e-9}},
     "$.polygon.circle.tolerance: 1e-09 is less than the minimum of 1e-05"),
    ({"circle": {"center": [0, 0], "radius": 1e7}}, "$.polygon.circle.radius: 10000000.0 is greater than the maximum"),
    ({"circ": {}}, "$.polygon: unknown key(s) ['circ'] ('circ': did you mean 'circle'? (it is not given)); missing "
                   "required key(s): circle"),
    ({"circle": {"center": [0, 0], "radius": 2}}, "$.polygon: the tool (diameter 8 mm) cannot enter the pocket"),
    ("abc", "$.polygon: 'abc' is not of type 'array'"),
])
def test_bad_circle_rings_named(ring, msg):
    with pytest.raises(ValueError) as exc:
        _job(polygon=ring)
    assert str(exc.value).startswith("j.json: ") and msg in str(exc.value), str(exc.value)


# -- plausibility ----------------------------------------------------------------------------------
def test_misspelt_key_reported_with_the_missing_one():
    with pytest.raises(ValueError) as exc:
        _job(tool_diameter=None, tool_dia=8)
    msg = str(exc.value)
    assert ("$: unknown key(s) ['tool_dia'] ('tool_dia': did you mean 'tool_diameter'? (it is not given)); "
            "missing required key(s): tool_diameter") in msg
    with pytest.raises(ValueError, match=r"'vc': did you mean 'v_c'\? \(it is not given\)"):
        _job(v_c=None, vc=120)
    with pytest.raises(ValueError, match=r"'polygn': did you mean 'polygon'\?.*missing required key\(s\): "
                                         r"polygon / star / regions"):
        _job(polygon=None, polygn=SQUARE)


def test_a_p_beyond_the_cutting_length():
    with pytest.raises(ValueError, match=r"^j.json: \$\.a_p: a_p = 30 mm is beyond the tool's cutting length 24 mm "
                                         r"\(3 x tool_diameter 8 mm; give 'cutting_length'"):
        _job(a_p=30)
    assert _job(a_p=30, cutting_length=35).a_p == 30
    with pytest.raises(ValueError, match=r"\$\.a_p: a_p = 30 mm is beyond the tool's cutting length 20 mm"):
        _job(a_p=30, cutting_length=20)
    j = _job(depth=40)                                           # deep pocket: levels fine, shank warned
    assert any("$.depth: depth 40 mm is beyond the tool's cutting length" in w for w in j.warnings)


def test_inch_numbers_in_a_mm_job():
    """The issue's case: a pocket typed in inches (tool 0.25, pocket 2 x 1.5) with v_c in m/min."""
    inch = {"polygon": [[0, 0], [2, 0], [2, 1.5], [0, 1.5]], "tool_diameter": 0.25, "a_p": 0.1}
    with pytest.raises(ValueError) as exc:
        _job(**inch)
    msg = str(exc.value)
    assert msg.startswith("j.json: $.v_c: v_c = 120 m/min on a 0.25 mm tool needs 152789 rpm, above the machine's "
                          f"spindle_rpm_max {SPINDLE_RPM_MAX:g} rpm")
    assert "the lengths look like inches (tool_diameter 0.25, pocket 2 across: 6.35 and 50.8 mm" in msg
    j = _job(**inch, v_c=None, spindle_rpm=12000, f_z=None, feed_mm_min=20)   # speeds fine: a warning
    assert j.warnings and j.warnings[0].startswith("j.json: $.tool_diameter: the lengths look like inches")
    assert not _job().warnings                                   # a mm job: nothing


def test_spindle_and_feed_beyond_machine_limits():
    with pytest.raises(ValueError, match=r"\$\.spindle_rpm: spindle_rpm = 30000, above the machine's "
                                         r"spindle_rpm_max 24000 rpm"):
        _job(v_c=None, spindle_rpm=30000)
    assert _job(v_c=None, spindle_rpm=30000, spindle_rpm_max=40000).spindle_rpm == 30000
    with pytest.raises(ValueError, match=r"\$\.f_z: f_z = 2 mm/tooth x 2 teeth x 4775 rpm = 19099 mm/min is above "
                                         r"the machine's rapid rate rapid_mm_min 10000 mm/min"):
        _job(f_z=2)
    with pytest.raises(ValueError, match=r"\$\.feed_mm_min: feed_mm_min = 3000 mm/min is above the machine's "
                                         r"feed_max_mm_min 2000 mm/min"):
        _job(feed_mm_min=3000, feed_max_mm_min=2000)
    with pytest.raises(ValueError, match=r"\$\.link_feed: link_feed = 20000 mm/min"):
        _job(link_feed=20000)


@pytest.mark.parametrize("f", sorted(str(p) for p in Path(data_path()).rglob("*.json")
                                     if '"tool_diameter"' in p.read_text(encoding="utf-8")))
def test_every_data_job_is_plausible(f):
    """Every job the collection ships passes the plausibility checks (a check that refused them would
    be wrong) — with no warning."""
    job = load_job(f)
    assert job.warnings == ()


# -- jobs from drawings ----------------------------------------------------------------------------
def test_job_from_the_done_when_drawing():
    job, d = job_from_drawing(FIX / "done_when.dxf", CUT, layer="POCKET")
    assert d["_drawing"]["layer"] == "POCKET" and d["_drawing"]["tolerance_mm"] == 0.005
    assert {"circle": {"center": [25.0, 30.0], "radius": 8.0}} in d["islands"]
    assert len(job.polygon.interiors) == 2 and job.tool_diameter == 6.0
    assert not job.warnings


def test_cutting_file_must_not_hold_geometry(tmp_path):
    c = tmp_path / "c.json"
    c.write_text(json.dumps(dict(BASE, polygon=SQUARE)))
    with pytest.raises(ValueError, match=r"c.json: \$\.polygon: cutting data must not hold geometry"):
        load_cutting(c)
    c.write_text("[1, 2]")
    with pytest.raises(ValueError, match=r"c.json: \$: cutting data must be a JSON object"):
        load_cutting(c)


def test_cutting_key_errors_name_both_files(tmp_path):
    c = tmp_path / "c.json"
    c.write_text(json.dumps(dict(BASE, a_p=40)))
    with pytest.raises(ValueError, match=r"done_when.dxf \+ .*c.json: \$\.a_p: a_p = 40 mm"):
        job_from_drawing(FIX / "done_when.dxf", c, layer="POCKET")


def test_inch_drawing_with_mm_numbers_warned(tmp_path):
    import ezdxf

    def save(w, h):
        doc = ezdxf.new(units=1)
        doc.modelspace().add_lwpolyline([(0, 0), (w, 0), (w, h), (0, h)], close=True)
        p = tmp_path / f"mm_as_inch_{w}.dxf"
        doc.saveas(p)
        return p

    slot = save(60, 10)                                  # a 60 x 10 mm plate drawn with $INSUNITS inch
    job, _ = job_from_drawing(slot, CUT)
    assert any("the drawing is in in (x 25.4) but its pocket is 1524 mm across (60 in)" in w for w in job.warnings)
    job, _ = job_from_drawing(slot, CUT, units="mm")
    assert not job.warnings and job.polygon.area == pytest.approx(600)
    with pytest.raises(ValueError, match=r"\$\.theta_deg: .* \(note: .*numbers that look like mm"):
        job_from_drawing(save(120, 80), CUT)             # the job fails (too many laps): the note says why


def test_load_job_input_dispatch(tmp_path):
    with pytest.raises(ValueError, match=r"done_when.dxf: a drawing gives only the geometry: give the cutting data"):
        load_job_input(FIX / "done_when.dxf")
    with pytest.raises(ValueError, match=r"--cutting, --layer and --units apply to a drawing"):
        load_job_input(data_path("jacso2021", "rectangle_pocket.json"), layer="POCKET")


def test_cli_job_from_drawing_round_trip_and_safety(tmp_path, capsys):
    out = tmp_path / "job.json"
    rc = cli_drawing.main([str(FIX / "done_when.svg"), "--layer", "POCKET", "--cutting", str(CUT), "-o", str(out)])
    assert rc == 0 and "1 region(s), 2 island(s)" in capsys.readouterr().out
    job = load_job(out)
    ref = load_job_input(FIX / "done_when.svg", cutting=CUT, layer="POCKET")
    assert job.polygon.symmetric_difference(ref.polygon).area < 1e-3       # coordinates rounded to 1e-6 mm
    before = CUT.read_bytes()
    assert cli_drawing.main([str(FIX / "done_when.svg"), "--cutting", str(CUT), "-o", str(CUT)]) == 2
    assert "refusing to overwrite the input file" in capsys.readouterr().err and CUT.read_bytes() == before
    bad = tmp_path / "bad.json"
    assert cli_drawing.main([str(FIX / "gap.dxf"), "--cutting", str(CUT), "-o", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "gap.dxf: open outline: LINE #" in err and "0.05 mm away" in err and not bad.exists()


def test_cli_registered():
    from cnclab.__main__ import COMMANDS

    assert COMMANDS["job-from-drawing"][0] == "cnclab.nc.cli_drawing"


def test_plan_names_implausible_keys_and_writes_warnings_in_the_header(tmp_path, capsys):
    """`plan DRAWING`: a_p beyond the stated cutting length is refused naming $.a_p (nothing written);
    a pocket that looks typed in inches (an 8 x 6 'mm' plate, a 0.8 mm tool) is planned with the
    warning naming $.tool_diameter on stderr and in the program header."""
    cut, out = tmp_path / "cut.json", tmp_path / "w.ngc"
    cut.write_text(json.dumps(dict(json.loads(CUT.read_text()), a_p=3.0, cutting_length=2.5)))
    assert cli_plan.main([str(FIX / "inch.dxf"), "--cutting", str(cut), "-o", str(out)]) == 2
    assert "$.a_p: a_p = 3 mm is beyond the tool's cutting length 2.5 mm" in capsys.readouterr().err
    assert not out.exists()
    small = tmp_path / "small.svg"
    small.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="10mm" height="10mm" viewBox="0 0 10 10">'
                     '<rect x="1" y="1" width="8" height="6"/></svg>')
    cut.write_text(json.dumps({"tool_diameter": 0.8, "teeth": 2, "theta_deg": 60, "a_p": 0.5,
                               "spindle_rpm": 20000, "feed_mm_min": 100}))
    assert cli_plan.main([str(small), "--cutting", str(cut), "-o", str(out), "--strategy", "zig-zag"]) == 0
    assert "warning: " in capsys.readouterr().err
    # the header's comment text (a long line is wrapped into several comments: program.LINUXCNC_LINE_MAX)
    head = " ".join(ln[1:-1] for ln in out.read_text().splitlines() if ln.startswith("("))
    assert head.count("WARNING job:") == 1
    assert "$.tool_diameter: the lengths look like inches [tool_diameter 0.8, pocket 8 across" in head


def _grbl_problems(text: str) -> list:
    """Blocks of ``text`` outside GRBL 1.1's documented grammar (data/nc/grbl11_grammar.json: G/M words
    of the default build, value letters, no %, O-words or parameters, lines <= 80 characters)."""
    g = json.loads(data_path("nc", "grbl11_grammar.json").read_text(encoding="utf-8"))
    words = ({w for grp in g["modal_groups"].values() for w in grp} | set(g["non_modal"])) - set(g["not_default_build"])
    bad = []
    for n, line in enumerate(text.splitlines(), 1):
        body = re.sub(r"\([^)]*\)", "", line).split(";")[0].strip()
        if len(line) > g["line_max_chars"] or re.search(r"[%#\[\]Oo]", body):
            bad.append((n, line))
        for letter, num in re.findall(r"([A-Za-z])\s*([-+]?\d*\.?\d+)", body):
            v = float(num)
            code = f"{letter.upper()}{int(v) if v.is_integer() else format(v, 'g')}"
            if (letter.upper() in "GM" and code not in words) or letter.upper() not in "GM" + "".join(g["value_words"]):
                bad.append((n, line))
    return bad


# one xdist group: the second dialect's `plan` answers its (identical) job from memo_levels
@pytest.mark.parametrize("dialect", [pytest.param(d, marks=pytest.mark.xdist_group("done-when-dxf"))
                                     for d in ("linuxcnc", "grbl")])
def test_plan_from_the_done_when_dxf_writes_a_safe_program(tmp_path, capsys, dialect, memo_levels):
    """Issue 24's done-when drawing: bulged outline, CIRCLE island, LINE/ARC island, on layer POCKET
    among annotation layers -> `plan` writes, in both dialects, a program that passes the static safety
    check; GRBL's uses only GRBL 1.1 words. Read back and cut through a simulated stock of the
    drawing's pocket (0.1 mm dixels): nothing rapid or plunged into material, the engagement held near
    theta, and no wall or island gouge beyond the writer's arc-fitting tolerance (the fitted G2/G3
    stay within DEFAULT_TOL_MM = 0.005 mm of the planned path, which touches the walls)."""
    out = tmp_path / f"dw_{dialect}.ngc"
    rc = cli_plan.main([str(FIX / "done_when.dxf"), "--layer", "POCKET", "--cutting", str(CUT), "-o", str(out),
                        "--dialect", dialect])
    assert rc == 0, capsys.readouterr().err
    text = out.read_text()
    chk = check_program(text, clearance_z=5.0)
    assert chk.ok and chk.plunges_into_material == 0, chk.errors[:3]
    comments = " ".join(re.findall(r"^\((.*)\)$", text, re.M))          # GRBL wraps header lines at 78 chars
    assert "geometry from done_when.dxf layer POCKET, chord tolerance 0.005 mm; cutting data from cutting.json" in comments
    if dialect == "grbl":
        assert not _grbl_problems(text), _grbl_problems(text)[:5]
    else:
        assert read_gcode(text).tool_number == 1 and re.search(r"^T1 M6", text, re.M)
    job = load_job_input(FIX / "done_when.dxf", cutting=CUT, layer="POCKET")
    ev = evaluate(read_toolpath(out, tool=job.tool), job, resolution_mm=0.1, sampling="arc_length")
    assert ev.plunges_into_material == 0 and ev.rapids_into_material == 0
    assert ev.wall_gouge_max_mm <= ARC_TOL_MM
    assert ev.engagement_p95_deg <= job.theta_deg + 2
    if dialect == "linuxcnc":
        assert cli_plan.main([str(FIX / "done_when.dxf"), "-o", str(tmp_path / "x.ngc")]) == 2
        assert "give the cutting data" in capsys.readouterr().err


def test_cli_job_from_drawing_hostile_arguments(tmp_path, capsys):
    """Each bad argument: exit 2, a message naming the file or option, nothing written."""
    out = tmp_path / "j.json"
    dw = str(FIX / "done_when.dxf")
    cases = [
        ([str(tmp_path / "none.dxf"), "--cutting", str(CUT)], "none.dxf: no such drawing file"),
        ([dw, "--cutting", str(tmp_path / "none.json")], "none.json"),
        ([str(CUT), "--cutting", str(CUT)], "a drawing must be a .dxf or .svg file"),
        ([dw, "--cutting", str(CUT), "--layer", "NOPE"], "no outline entity (LINE, ARC"),
        ([dw, "--cutting", str(CUT), "--tolerance", "nan"], "tolerance must be a number of mm"),
        ([dw, "--cutting", str(CUT), "--units", "parsec"], "units 'parsec' unknown"),
        ([dw, "--cutting", str(CUT), "--layer", "POCKET", "--join-tol", "0"], "join_tol must be a number of mm"),
    ]
    for args, msg in cases:
        assert cli_drawing.main([*args, "-o", str(out)]) == 2, args
        err = capsys.readouterr().err
        assert err.startswith("error: ") and msg in err, (args, err)
        assert not out.exists()
    (tmp_path / "adir").mkdir()
    assert cli_drawing.main([dw, "--cutting", str(CUT), "--layer", "POCKET", "-o", str(tmp_path / "adir")]) == 2
    assert "adir" in capsys.readouterr().err


def test_feeds_beyond_the_dialect_machine_model_warned(tmp_path, capsys):
    """A link feed of 6000 mm/min is within the job's limit (rapid 10000) and the small VMC's 15 m/min,
    but above the 5 m/min X/Y rate of the GRBL router model: planned for grbl, the warning names
    $.link_feed on stderr and in the header; for linuxcnc, none."""
    job = _job(link_feed=6000)
    assert cli_plan.with_machine_warnings(job, "linuxcnc") is job
    (w,) = cli_plan.with_machine_warnings(job, "grbl").warnings
    assert w == ("j.json: $.link_feed: 6000 mm/min is above the X/Y rate 5000 mm/min of the GRBL router machine "
                 "model of --dialect grbl: the controller will cap it")
    svg, cut, out = tmp_path / "r.svg", tmp_path / "c.json", tmp_path / "r.nc"
    svg.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="40mm" height="30mm" viewBox="0 0 40 30">'
                   '<rect x="0" y="0" width="30" height="20"/></svg>')
    cut.write_text(json.dumps(dict(BASE, tool_diameter=6.0, link_feed=6000)))
    assert cli_plan.main([str(svg), "--cutting", str(cut), "-o", str(out), "--dialect", "grbl",
                          "--strategy", "zig-zag"]) == 0
    assert "warning: " in capsys.readouterr().err
    comments = " ".join(re.findall(r"^\((.*)\)$", out.read_text(), re.M))
    assert "$.link_feed: 6000 mm/min is above the X/Y rate 5000 mm/min" in comments
