"""Drawing reader (cnclab.geometry.drawing): flattening within the stated chord tolerance, bulge arcs,
chaining and nesting, units, layers, SVG paths, and refusals that name the entity — on the generated
fixtures of tests/fixtures/drawings (make_drawings.py) and on drawings built here with ezdxf.

Area bounds: a flattening whose vertices lie on the curve with chord error <= tol changes the area
by at most (curve length) x tol, the strip between each arc and its chords."""
import math
from pathlib import Path

import ezdxf
import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import Point, Polygon

from cnclab.geometry.drawing import (CHORD_TOL_MM, arc_points, bulge_arc, circle_points, read_drawing)

FIX = Path(__file__).parent / "fixtures" / "drawings"
TOL = CHORD_TOL_MM


def _handles(path, **where):
    """Handles of the entities of ``path`` whose dxftype/layer match ``where``."""
    out = []
    for e in ezdxf.readfile(str(path)).modelspace():
        if all((e.dxftype() if k == "type" else getattr(e.dxf, k)) == v for k, v in where.items()):
            out.append(e.dxf.handle)
    return out


def _save(tmp_path, build, units=4, name="t.dxf"):
    doc = ezdxf.new("R2010", units=units)
    build(doc.modelspace())
    p = tmp_path / name
    doc.saveas(p)
    return p


# -- flattening ------------------------------------------------------------------------------------
@settings(max_examples=60, deadline=None)
@given(r=st.floats(0.5, 500), tol=st.floats(1e-4, 0.1))
def test_circle_flattening_meets_the_chord_tolerance(r, tol):
    """Vertices on the circle, every chord's sagitta <= tol, area = n/2 r^2 sin(2 pi/n) within
    2 pi r tol of pi r^2 (hand formulas)."""
    P = circle_points((3.0, -2.0), r, tol)
    n = len(P)
    assert np.allclose(np.hypot(P[:, 0] - 3.0, P[:, 1] + 2.0), r, rtol=0, atol=1e-9 * r)
    mid = 0.5 * (P + np.roll(P, -1, axis=0))
    sag = r - np.hypot(mid[:, 0] - 3.0, mid[:, 1] + 2.0)
    assert sag.max() <= tol * (1 + 1e-9)
    area = Polygon(P).area
    assert area == pytest.approx(0.5 * n * r * r * math.sin(2 * math.pi / n), rel=1e-9)
    assert 0 < math.pi * r * r - area <= 2 * math.pi * r * tol


def test_arc_points_ends_and_direction():
    P = arc_points((0, 0), 10.0, math.pi, -math.pi / 2, 0.001)           # clockwise quarter
    assert P[0] == pytest.approx([-10, 0]) and P[-1] == pytest.approx([0, 10], abs=1e-12)
    assert np.all(np.diff(np.arctan2(P[:, 1], P[:, 0])) < 0)             # angles decrease: clockwise


@pytest.mark.parametrize("bulge,center,radius,sweep", [
    (1.0, (5, 0), 5.0, math.pi),                                 # semicircle, below the chord
    (-1.0, (5, 0), 5.0, -math.pi),                               # semicircle, above the chord
    (math.tan(math.pi / 8), (5, 5), 5 * math.sqrt(2), math.pi / 2),     # quarter circle
    (math.tan(3 * math.pi / 8), (5, -5), 5 * math.sqrt(2), 3 * math.pi / 2),   # 270 deg
])
def test_bulge_arc_hand_cases(bulge, center, radius, sweep):
    """bulge = tan(angle/4), chord (0,0)-(10,0): centre, radius and sweep by hand; the arc runs from
    p0 to p1 and (positive bulge) lies right of the direction of travel for a minor arc."""
    c, r, a0, sw = bulge_arc((0, 0), (10, 0), bulge)
    assert c == pytest.approx(center, abs=1e-12) and r == pytest.approx(radius) and sw == pytest.approx(sweep)
    P = arc_points(c, r, a0, sw, 1e-3)
    assert P[0] == pytest.approx([0, 0], abs=1e-9) and P[-1] == pytest.approx([10, 0], abs=1e-9)
    mid = P[len(P) // 2]
    assert np.sign(mid[1]) == -np.sign(bulge)           # y < 0: right of +x travel for bulge > 0


@settings(max_examples=40, deadline=None)
@given(w=st.floats(20, 60), h=st.floats(20, 60), bulges=st.lists(st.floats(-0.15, 0.15), min_size=4, max_size=4),
       ccw=st.booleans())
def test_bulged_rectangle_area_by_hand(tmp_path_factory, w, h, bulges, ccw):
    """A W x H rectangle whose edges carry bulges b (either traversal direction): area = W H plus, per
    edge, the circular segment r^2/2 (theta - sin theta), theta = 4 atan|b|, r = c / (2 sin(theta/2)),
    added where the arc bulges outward (b > 0 on a counter-clockwise outline) and removed where inward;
    within (arc length) x tol."""
    pts = [(0, 0), (w, 0), (w, h), (0, h)]
    if not ccw:
        pts = pts[::-1]
    doc = ezdxf.new(units=4)
    doc.modelspace().add_lwpolyline([(x, y, b) for (x, y), b in zip(pts, bulges)], format="xyb", close=True)
    p = tmp_path_factory.mktemp("bulge") / "b.dxf"
    doc.saveas(p)
    area, arcs = w * h, 0.0
    for k, b in enumerate(bulges):
        (x0, y0), (x1, y1) = pts[k], pts[(k + 1) % 4]
        c = math.hypot(x1 - x0, y1 - y0)
        if abs(b) < 1e-12:
            continue
        th = 4 * math.atan(abs(b))
        r = c / (2 * math.sin(th / 2))
        outward = (b > 0) == ccw
        area += (1 if outward else -1) * 0.5 * r * r * (th - math.sin(th))
        arcs += r * th
    assert abs(read_drawing(p).polygon().area - area) <= arcs * TOL + 1e-9


# -- the done-when drawing ---------------------------------------------------------------------------
def _done_when_area():
    """Hand area of the done-when pocket (mm^2): 80 x 60 rectangle + semicircle r 30 + the circular
    segment of bulge 0.25 on a 60 mm chord - circle r 8 - obround (8 x 16 + circle r 8)."""
    theta = 4 * math.atan(0.25)
    rs = 30 / math.sin(theta / 2)
    seg = 0.5 * rs * rs * (theta - math.sin(theta))
    arcs = math.pi * 30 + rs * theta + 2 * math.pi * 8 + 2 * math.pi * 8       # curve lengths (mm)
    return 4800 + math.pi * 900 / 2 + seg - math.pi * 64 - (128 + math.pi * 64), arcs


def test_done_when_dxf_outline_islands_and_areas():
    path = FIX / "done_when.dxf"
    d = read_drawing(path, layer="POCKET")
    assert len(d.regions) == 1 and d.units == "mm" and d.mm_per_unit == 1.0
    reg = d.regions[0]
    circ = [i for i in reg.islands if i.circle is not None]
    chain = [i for i in reg.islands if i.circle is None]
    assert len(circ) == 1 and len(chain) == 1
    assert circ[0].circle == pytest.approx((25, 30, 8))
    assert circ[0].entities == (f"CIRCLE #{_handles(path, type='CIRCLE')[0]}",)
    lines, arcs = _handles(path, type="LINE"), _handles(path, type="ARC")
    assert sorted(chain[0].entities) == sorted([f"LINE #{h}" for h in lines] + [f"ARC #{h}" for h in arcs])
    area, curve_len = _done_when_area()
    assert abs(d.polygon().area - area) <= curve_len * TOL
    # the right-hand bulge: every flattened vertex with x > 80 lies on the circle (80, 30) r 30
    P = reg.shell.points
    right = P[P[:, 0] > 80 + 1e-9]
    assert len(right) > 10 and np.allclose(np.hypot(right[:, 0] - 80, right[:, 1] - 30), 30, atol=1e-9)


def test_done_when_dxf_hausdorff_to_a_fine_flattening():
    """The default flattening is within the chord tolerance of a 1e-5 mm one (Hausdorff distance)."""
    a = read_drawing(FIX / "done_when.dxf", layer="POCKET").polygon()
    b = read_drawing(FIX / "done_when.dxf", layer="POCKET", tolerance=1e-5).polygon()
    assert shapely.hausdorff_distance(a.boundary, b.boundary, densify=0.01) <= TOL + 1e-5


def test_layer_filtering_and_annotations_skipped():
    path = FIX / "done_when.dxf"
    every = read_drawing(path)                # the BORDER frame holds the pocket: 3 regions by nesting
    assert len(every.regions) == 3 and any("1 DIMENSION, 1 TEXT" in n for n in every.notes)
    assert read_drawing(path, layer="pocket").polygon().area == pytest.approx(
        read_drawing(path, layer="POCKET").polygon().area)                   # DXF layer names: any case
    border = read_drawing(path, layer="BORDER")
    assert border.polygon().area == pytest.approx(150 * 100)
    with pytest.raises(ValueError, match=r"no outline entity .* on layer 'ANNOTATION'; layers with outline "
                                         r"entities: 'BORDER' \(1\), 'POCKET' \(6\)"):
        read_drawing(path, layer="ANNOTATION")


# -- chains, gaps, nesting ---------------------------------------------------------------------------
def test_gap_is_refused_with_handle_and_size():
    path = FIX / "gap.dxf"
    moved = [e.dxf.handle for e in ezdxf.readfile(str(path)).modelspace()
             if e.dxftype() == "LINE" and e.dxf.start[0] == pytest.approx(62.05)][0]
    with pytest.raises(ValueError) as exc:
        read_drawing(path)
    msg = str(exc.value)
    assert msg.startswith(str(path)) and f"LINE #{moved} start at (62.0500, 22.0000)" in msg
    assert "is 0.05 mm away" in msg and "join tolerance 0.001 mm" in msg
    d = read_drawing(path, join_tol=0.06)                        # a join tolerance over the gap: closed
    assert d.polygon().area == pytest.approx(128 + math.pi * 64 - 0.05 * 16 / 2, abs=2 * math.pi * 16 * TOL)


def test_open_chain_single_line_refused(tmp_path):
    p = _save(tmp_path, lambda m: m.add_line((0, 0), (10, 0)))
    with pytest.raises(ValueError, match=r"open outline: LINE #\w+ (start|end) .* (is 10 mm away|there is)"):
        read_drawing(p)


def test_branch_and_duplicate_refused(tmp_path):
    def tee(m):
        for a, b in [((0, 0), (10, 0)), ((10, 0), (10, 10)), ((10, 10), (0, 0)), ((10, 0), (20, 0))]:
            m.add_line(a, b)
    with pytest.raises(ValueError, match=r"3 ends meet at \(10.0000, 0.0000\) \(LINE #\w+, LINE #\w+, LINE #\w+\)"):
        read_drawing(_save(tmp_path, tee))


def test_duplicated_outline_refused_and_zero_length_line_skipped(tmp_path):
    p = _save(tmp_path, lambda m: (m.add_circle((0, 0), 5), m.add_circle((0, 0), 5)))
    with pytest.raises(ValueError, match=r"outlines of CIRCLE #\w+ and CIRCLE #\w+ coincide \(a duplicated entity\?\)"):
        read_drawing(p)
    p = _save(tmp_path, lambda m: (m.add_lwpolyline([(0, 0), (10, 0), (10, 10), (0, 10), (0, 0)]),   # open, ends meet
                                   m.add_line((5, 5), (5, 5))), name="z.dxf")
    d = read_drawing(p)
    assert d.polygon().area == pytest.approx(100) and any("1 LINE of zero length" in n for n in d.notes)


def test_crossing_outlines_refused_naming_both(tmp_path):
    p = _save(tmp_path, lambda m: (m.add_circle((0, 0), 10), m.add_circle((15, 0), 10)))
    hs = _handles(p, type="CIRCLE")
    with pytest.raises(ValueError, match=rf"outlines of CIRCLE #({hs[0]}|{hs[1]}) and CIRCLE #({hs[0]}|{hs[1]}) cross"):
        read_drawing(p)


def test_self_intersecting_outline_refused(tmp_path):
    p = _save(tmp_path, lambda m: m.add_lwpolyline([(0, 0), (10, 10), (10, 0), (0, 10)], close=True))
    with pytest.raises(ValueError, match=r"outline of LWPOLYLINE #\w+ is not a simple polygon \(Self-intersection"):
        read_drawing(p)


def test_nesting_regions_islands_and_a_region_inside_an_island():
    d = read_drawing(FIX / "nested.dxf")
    areas = sorted(round(r.polygon().area, 3) for r in d.regions)
    inner = math.pi * 144
    assert len(d.regions) == 3
    assert areas == pytest.approx(sorted([3600 - 1600, 1200, inner]), abs=2 * math.pi * 12 * TOL)
    big = max(d.regions, key=lambda r: r.polygon().area)
    assert len(big.islands) == 1 and big.islands[0].polygon().area == pytest.approx(1600)


def test_block_reference_expanded_with_its_scale_and_layer(tmp_path):
    def build(m):
        blk = m.doc.blocks.new("PLATE")
        blk.add_lwpolyline([(0, 0), (10, 0), (10, 5), (0, 5)], close=True)      # layer 0: takes the INSERT's
        blk.add_circle((5, 2.5), 1, dxfattribs={"layer": "HOLES"})
        m.add_blockref("PLATE", (100, 100), dxfattribs={"layer": "POCKET", "xscale": 2, "yscale": 2})
    d = read_drawing(_save(tmp_path, build), layer="POCKET")
    assert d.polygon().area == pytest.approx(200) and d.polygon().bounds == pytest.approx((100, 100, 120, 110))
    assert "in INSERT" in d.regions[0].shell.entities[0]


def test_nested_block_references_expanded(tmp_path):
    """A block inserting another block (scale 2 inside scale 3): the square of side 1 becomes 6 x 6;
    the inner entities on layer 0 take the outer INSERT's layer."""
    def build(m):
        inner = m.doc.blocks.new("INNER")
        inner.add_lwpolyline([(0, 0), (1, 0), (1, 1), (0, 1)], close=True)
        outer = m.doc.blocks.new("OUTER")
        outer.add_blockref("INNER", (0, 0), dxfattribs={"xscale": 2, "yscale": 2})
        m.add_blockref("OUTER", (10, 0), dxfattribs={"layer": "POCKET", "xscale": 3, "yscale": 3})
    d = read_drawing(_save(tmp_path, build), layer="POCKET")
    assert d.polygon().area == pytest.approx(36) and d.polygon().bounds == pytest.approx((10, 0, 16, 6))
    assert d.regions[0].shell.entities[0].startswith("LWPOLYLINE in INSERT #")


def test_self_inserting_block_refused(tmp_path):
    def build(m):
        blk = m.doc.blocks.new("LOOP")
        blk.add_circle((0, 0), 1)
        blk.add_blockref("LOOP", (5, 0))
        m.add_blockref("LOOP", (0, 0))
    with pytest.raises(ValueError, match=r"INSERT .*(nested deeper than 16|cannot be expanded)"):
        read_drawing(_save(tmp_path, build))


def test_mirrored_extrusion_arcs_in_world_coordinates(tmp_path):
    """An ARC/CIRCLE with extrusion (0, 0, -1) (mirrored in CAD) is placed at its WCS position (x -> -x)."""
    def build(m):
        m.add_circle((10, 0), 2, dxfattribs={"extrusion": (0, 0, -1)})
    d = read_drawing(_save(tmp_path, build))
    assert d.regions[0].shell.circle == pytest.approx((-10, 0, 2))
    assert d.polygon().centroid.x == pytest.approx(-10)


def test_curve_outside_the_xy_plane_refused(tmp_path):
    p = _save(tmp_path, lambda m: m.add_circle((0, 0), 5, dxfattribs={"extrusion": (1, 0, 0)}))
    with pytest.raises(ValueError, match=r"CIRCLE #\w+ is not in the XY plane"):
        read_drawing(p)


# -- entity kinds ------------------------------------------------------------------------------------
def test_ellipse_spline_and_polyline2d():
    path = FIX / "ellipse_spline.dxf"
    d = read_drawing(path)
    (reg,) = d.regions
    ell = reg.shell.polygon()
    h = 40 + 25                                     # ellipse perimeter < pi (a + b) ... Ramanujan bound
    assert 0 <= math.pi * 40 * 25 - ell.area <= math.pi * h * TOL * 1.01
    by = {i.entities[0].split()[0]: i for i in reg.islands}
    assert by["POLYLINE"].polygon().area == pytest.approx(100 + math.pi * 25 / 2, abs=math.pi * 5 * TOL)
    # the spline island: every flattened vertex on the curve (ezdxf's exact evaluation), chords within tol
    spl = [e for e in ezdxf.readfile(str(path)).modelspace() if e.dxftype() == "SPLINE"][0].construction_tool()
    dense = np.array([(v.x, v.y) for v in spl.points(np.linspace(0, spl.max_t, 20001))])
    ring = by["SPLINE"].polygon().boundary
    assert max(ring.distance(Point(*q)) for q in dense[::10]) <= TOL * 1.05


def test_units_inch_unitless_and_override():
    d = read_drawing(FIX / "inch.dxf")
    assert d.mm_per_unit == pytest.approx(25.4) and any("x 25.4 to mm" in n for n in d.notes)
    assert d.polygon().bounds == pytest.approx((0, 0, 101.6, 50.8))
    assert d.regions[0].islands[0].circle == pytest.approx((50.8, 25.4, 12.7))
    assert d.polygon().area == pytest.approx(101.6 * 50.8 - math.pi * 12.7 ** 2, abs=2 * math.pi * 12.7 * TOL)
    u = read_drawing(FIX / "unitless.dxf")
    assert u.units == "unitless" and any("unitless ($INSUNITS 0): read as mm" in n for n in u.notes)
    assert u.polygon().area == pytest.approx(1200)
    assert read_drawing(FIX / "unitless.dxf", units="inch").polygon().area == pytest.approx(1200 * 25.4 ** 2)
    with pytest.raises(ValueError, match="units 'furlong' unknown"):
        read_drawing(FIX / "unitless.dxf", units="furlong")


def test_svg_paths_layers_and_units():
    path = FIX / "done_when.svg"
    d = read_drawing(path, layer="POCKET")
    assert d.mm_per_unit == pytest.approx(25.4 / 96)
    (reg,) = d.regions
    assert [i.entities[0] for i in reg.islands] == ["path id=obround", "circle id=round_island"]
    circ = reg.islands[1].polygon()
    assert 0 < math.pi * 64 - circ.area <= 2 * math.pi * 8 * TOL * 1.01
    assert circ.centroid.coords[0] == pytest.approx((35, 70 - 35), abs=1e-6)          # y flipped at the page height
    assert reg.islands[1].circle == pytest.approx((35, 35, 8))            # an SVG circle stays a circle ring
    assert reg.islands[0].polygon().area == pytest.approx(128 + math.pi * 64, abs=2 * math.pi * 8 * TOL * 1.01)
    # the outline's cubic (10,5) (2,20) (2,50) (10,65) in SVG coordinates, evaluated here (Bernstein form)
    t = np.linspace(0, 1, 4001)[:, None]
    B = np.array([[10, 5], [2, 20], [2, 50], [10, 65]], float)
    cub = ((1 - t) ** 3 * B[0] + 3 * (1 - t) ** 2 * t * B[1] + 3 * (1 - t) * t ** 2 * B[2] + t ** 3 * B[3])
    cub[:, 1] = 70 - cub[:, 1]
    ring = reg.shell.polygon().boundary
    assert max(ring.distance(Point(*q)) for q in cub[::20]) <= TOL * 1.05
    # the arc A 30 30 0 0 0 from (90, 65) to (90, 5): a semicircle bulging to x = 120
    assert reg.shell.polygon().bounds[2] == pytest.approx(120, abs=1e-6)
    assert read_drawing(path, layer="layer1").polygon().area == pytest.approx(d.polygon().area)   # group id
    as_mm = read_drawing(path, layer="POCKET", units="mm")          # one user unit = 1 mm, as the viewBox says
    assert as_mm.polygon().area == pytest.approx(d.polygon().area, rel=1e-9)
    cm = read_drawing(path, layer="POCKET", units="cm")                # x 10; flattened at 0.005 mm of the bigger part
    assert cm.polygon().area == pytest.approx(100 * d.polygon().area, rel=1e-4)
    notes = read_drawing(path, layer="NOTES")
    assert notes.polygon().area == pytest.approx(138 * 68)                           # the frame; text skipped
    assert any("skipped (not outlines): 1 Text" in n for n in notes.notes)


def test_unreadable_inputs_name_the_file(tmp_path):
    bad = tmp_path / "bad.dxf"
    bad.write_text("hello\n")
    with pytest.raises(ValueError, match=r"bad.dxf: not a readable DXF file"):
        read_drawing(bad)
    bsvg = tmp_path / "bad.svg"
    bsvg.write_text("<svg")
    with pytest.raises(ValueError, match=r"bad.svg: not a readable SVG file"):
        read_drawing(bsvg)
    with pytest.raises(OSError):
        read_drawing(tmp_path / "missing.dxf")
    with pytest.raises(ValueError, match=r"must be a .dxf or .svg file"):
        read_drawing(tmp_path / "x.dwg")
    for bad in (0, -1, float("nan"), 1e-9, 2.0):
        with pytest.raises(ValueError, match=r"inch.dxf: tolerance must be a number of mm in \(1e-05, 1\], got"):
            read_drawing(FIX / "inch.dxf", tolerance=bad)
    with pytest.raises(ValueError, match=r"join_tol must be a number of mm in \(0, 1\], got inf"):
        read_drawing(FIX / "inch.dxf", join_tol=float("inf"))


@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_corrupted_drawings_give_an_error_naming_the_file_or_valid_regions(tmp_path_factory, data):
    """Bytes of the done-when DXF/SVG replaced, deleted or inserted: a ValueError starting with the file
    name, or regions that are valid polygons (never another exception, never an invalid pocket)."""
    src = data.draw(st.sampled_from(["done_when.dxf", "done_when.svg"]))
    raw = bytearray((FIX / src).read_bytes())
    for _ in range(data.draw(st.integers(1, 6))):
        i = data.draw(st.integers(0, len(raw) - 1))
        op = data.draw(st.sampled_from(["replace", "delete", "insert", "digit"]))
        if op == "replace":
            raw[i] = data.draw(st.integers(0, 255))
        elif op == "delete":
            del raw[i]
        elif op == "insert":
            raw.insert(i, data.draw(st.integers(0, 255)))
        else:                                   # a digit changed: coordinates, handles, group codes
            raw[i] = ord(data.draw(st.sampled_from("0123456789-.")))
    f = tmp_path_factory.mktemp("corrupt") / src
    f.write_bytes(bytes(raw))
    try:
        d = read_drawing(f, layer="POCKET")
    except ValueError as e:
        assert str(e).startswith(str(f)), str(e)
        return
    poly = d.polygon()
    assert poly.is_valid and poly.area > 0
    assert all(r.polygon().is_valid for r in d.regions)
