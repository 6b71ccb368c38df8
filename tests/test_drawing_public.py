"""The drawing reader on public drawings written by real CAD tools (tests/fixtures/drawings/public,
provenance and licences in provenance.json): layers with odd names, block references with mirror,
rotation and scale, a plate with holes checked against an independent polygonization, an Inkscape
file's layers by id and label, a sloppy DXF repaired by ezdxf's recover mode, open outlines refused.

Area bounds as in test_drawing.py: flattening with vertices on the curve and chord error <= tol
changes an area by at most (curve length) x tol."""
import hashlib
import json
import math
from pathlib import Path

import ezdxf
import pytest
import shapely
from shapely.geometry import LineString

from cnclab.geometry.drawing import CHORD_TOL_MM, read_drawing
from cnclab.toolpath.from_drawing import job_from_drawing

PUB = Path(__file__).parent / "fixtures" / "drawings" / "public"
TOL = CHORD_TOL_MM


def test_provenance_sidecar_matches_the_files():
    meta = json.loads((PUB / "provenance.json").read_text(encoding="utf-8"))["files"]
    on_disk = sorted(p.name for p in PUB.iterdir() if p.suffix in (".dxf", ".svg"))
    assert sorted(meta) == on_disk
    for name, m in meta.items():
        assert {"repo", "path", "commit", "licence", "blob_sha1", "sha256"} <= set(m), name
        data = (PUB / name).read_bytes()
        assert hashlib.sha256(data).hexdigest() == m["sha256"], name
        assert hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest() == m["blob_sha1"], name   # unchanged copy


def test_multiple_layers_each_layer_alone():
    """Square 80 x 80 on '0', circle r = 50 sqrt 2 on 'noname', regular hexagon r = 100 on a layer whose
    name holds quotes and backslashes (hand areas)."""
    p = PUB / "openscad_multiple-layers.dxf"
    odd = [lay.dxf.name for lay in ezdxf.readfile(str(p)).layers if "pretty long" in lay.dxf.name][0]
    assert read_drawing(p, layer="0").polygon().area == pytest.approx(6400)
    r = 50 * math.sqrt(2)
    circ = read_drawing(p, layer="noname")
    assert circ.regions[0].shell.circle == pytest.approx((0, 0, r), abs=1e-4)
    assert 0 < math.pi * r * r - circ.polygon().area <= 2 * math.pi * r * TOL
    assert read_drawing(p, layer=odd).polygon().area == pytest.approx(1.5 * math.sqrt(3) * 100 ** 2)
    every = read_drawing(p)                               # hexagon > circle > square: nested by containment
    assert len(every.regions) == 2 and every.polygon().area == pytest.approx(
        1.5 * math.sqrt(3) * 1e4 - circ.polygon().area + 6400)


def test_block_references_mirrored_rotated_scaled():
    """transform-insert.dxf: squares of LINEs with T-shaped tabs from blocks inserted mirrored
    (yscale -1), rotated 45/-135 deg and at half scale: 400 + 2 x 16, and 100 + 2 x 16/4 (hand)."""
    d = read_drawing(PUB / "openscad_transform-insert.dxf")
    areas = sorted(r.polygon().area for r in d.regions)
    assert areas == pytest.approx([108, 432, 432])
    assert all(any("in INSERT #" in n for n in r.shell.entities) for r in d.regions)


def test_riser_plate_against_an_independent_polygonization():
    """polygon-riser.dxf: the outline of 26 LINEs with 8 CIRCLE holes. Its outline has one gap of 0.00041 mm
    (closed by the 0.001 mm join tolerance, refused below it). Reference: shapely.polygonize of the raw
    LINE coordinates read with ezdxf, snapped to a 0.002 mm grid (which closes that gap; each vertex
    moves <= 0.0015 mm, so the area by <= perimeter x 0.0015), minus pi r^2 of each CIRCLE."""
    p = PUB / "openscad_polygon-riser.dxf"
    msp = ezdxf.readfile(str(p)).modelspace()
    lines = [LineString([tuple(e.dxf.start)[:2], tuple(e.dxf.end)[:2]]) for e in msp if e.dxftype() == "LINE"]
    radii = [e.dxf.radius for e in msp if e.dxftype() == "CIRCLE"]
    assert not shapely.get_parts(shapely.polygonize(lines)).size          # the raw lines do not close
    outline = shapely.get_parts(shapely.polygonize(shapely.set_precision(lines, 2e-3)))
    assert len(outline) == 1
    ref = outline[0].area - sum(math.pi * r * r for r in radii)
    d = read_drawing(p)
    (reg,) = d.regions
    assert len(reg.islands) == len(radii) == 8 and all(i.circle is not None for i in reg.islands)
    bound = sum(2 * math.pi * r * TOL for r in radii) + outline[0].length * 1.5e-3
    assert abs(reg.polygon().area - ref) <= bound
    with pytest.raises(ValueError, match=r"meets no other end within the join tolerance 0.0001 mm: the nearest end "
                                         r"\(LINE #\w+ (start|end)\) is 0.00041\d* mm away"):
        read_drawing(p, join_tol=1e-4)


def test_line_arc_chain_quarter_disc():
    d = read_drawing(PUB / "openscad_arc.dxf")
    assert d.polygon().bounds == pytest.approx((0, 0, 100, 100))
    assert 0 < math.pi * 100 ** 2 / 4 - d.polygon().area <= 0.5 * math.pi * 100 * TOL


def test_open_polyline_refused_naming_the_entity():
    p = PUB / "openscad_open-polyline.dxf"
    with pytest.raises(ValueError, match=r"openscad_open-polyline.dxf: open outline: LINE #\w+ (start|end) at "
                                         r"\(.*\) meets no other end .* is 100 mm away"):
        read_drawing(p)


def test_inkscape_layers_by_id_and_label():
    """id-layer-selection-test.svg (Inkscape, 100 x 50 mm, viewBox in mm): layer 'layer-2' holds one
    path of elliptic arcs, the unnamed layer 'id-layer-3' an ellipse rx 12.207458, ry 2.5403628 (mm);
    every layer together overlaps (the drawing's boxes cross): refused naming two shapes."""
    p = PUB / "openscad_id-layer-selection-test.svg"
    by_label, by_id = read_drawing(p, layer="layer-2"), read_drawing(p, layer="id-layer-2")
    assert by_label.polygon().area == pytest.approx(by_id.polygon().area)
    assert by_label.regions[0].shell.entities == ("path id=id-circle",)
    ell = read_drawing(p, layer="id-layer-3").polygon()
    a, b = 12.207458, 2.5403628
    per = math.pi * (3 * (a + b) - math.sqrt((3 * a + b) * (a + 3 * b)))       # Ramanujan's perimeter
    assert 0 < math.pi * a * b - ell.area <= per * TOL
    with pytest.raises(ValueError, match=r"the outlines of rect id=id-rect-\d and rect id=id-rect-\d cross"):
        read_drawing(p)
    with pytest.raises(ValueError, match=r"no path or shape in a group with id or inkscape:label 'layer-9'; "
                                         r"groups: boxes, .*layer-2"):
        read_drawing(p, layer="layer-9")


def test_svg_square_with_hole():
    d = read_drawing(PUB / "openscad_simple.svg")
    (reg,) = d.regions
    assert len(reg.islands) == 1 and reg.polygon().area == pytest.approx(300)


def test_sloppy_dxf_recovered_then_refused_as_open():
    """librecad_t-part.dxf has header variables after ENDSEC (dxflib): the strict reader fails, ezdxf's
    recover mode repairs it; the T profile is drawn open (centre lines, a contour with gaps), so it is
    refused naming an ARC/LINE handle and the gap."""
    p = PUB / "librecad_t-part.dxf"
    with pytest.raises(ezdxf.DXFStructureError):
        ezdxf.readfile(str(p))
    with pytest.raises(ValueError, match=r"librecad_t-part.dxf: open outline: (ARC|LINE) #\w+ (start|end) at .* "
                                         r"is [0-9.]+ mm away"):
        read_drawing(p, layer="0")


def test_public_plate_becomes_a_job():
    job, d = job_from_drawing(PUB / "openscad_polygon-riser.dxf", Path(__file__).parent / "fixtures" / "drawings"
                              / "cutting.json")
    assert len(d["islands"]) == 8 and all("circle" in i for i in d["islands"])
    assert job.polygon.area == pytest.approx(read_drawing(PUB / "openscad_polygon-riser.dxf").polygon().area)
