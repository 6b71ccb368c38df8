"""Build the pocket corpus of issue 29 (``data/pockets/corpus/*.json``): jobs the planners were not
developed on. Written once and FROZEN: the corpus is never changed to suit a planner's results (fix
the planner, not the corpus). Run from the repository root::

    .venv/bin/python data/pockets/corpus/make_corpus.py [--check]

(``--check`` rebuilds in memory and fails if a committed job differs: the corpus is reproducible.)

Two sources, one seeded generator (``numpy.random.default_rng(SEED)``, one child stream per job):

* **synthetic families** (:data:`FAMILIES`): star-shaped, rectilinear, islands, necks, slots with
  bulbs, long tapered curved channels, gear-like outlines, spirals, combs, channels about 1.5 D wide
  (straight, curved, spiral) and several regions; plus the named cases of issue 29 (a curved channel
  tapering from 30 to 10 mm for an 8 mm tool at theta 30.7 deg; an internal 10-tooth gear with a
  round island at theta 45.6 deg);
* **public drawings** (:data:`DRAWINGS`, files in ``drawings/``, copied byte for byte from public
  repositories; provenance, commit, blob hash and licence in ``provenance/<job>.json``): the closed
  outlines are extracted with ezdxf (LINE/ARC/CIRCLE/ELLIPSE/LWPOLYLINE/POLYLINE/SPLINE, flattened
  to 0.01 drawing units) or svgelements (paths, 0.01 units), polygonized with shapely, nested by the
  even-odd rule (a face inside an odd number of other faces is an island), then scaled uniformly so
  that the bounding box's larger side is the drawn size (mm) and moved to the origin.

Tool and engagement per job: diameter D from {3, 4, 5, 6, 8, 10, 12} mm, theta uniform in
[20, 120] deg, redrawn (same stream) until the stepover a_e = r (1 - cos theta) is at least 0.25 mm
(smaller stepovers are finishing work, not clearing) -- except in the named cases, whose D and theta
are fixed. Cutting data: 2 teeth, v_c 150 m/min, f_z = 0.008 D (mm/tooth, 0.03-0.08), a_p = 0.5 D
capped at 4 mm, one level (depth = a_p) except every 8th synthetic job (depth 2 a_p), link feed
1500 mm/min, v_fmax 1.5 x nominal feed. Sizes are drawn in units of D where the family is defined
by D (channels, slots, combs) and in mm otherwise; every pocket is checked by the package's job
loader (a job it refuses is redrawn from the same stream: the check is of validity, not of any
planner's result). Units: mm, deg, m/min, mm/min.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import math
import sys
from pathlib import Path

import numpy as np
import shapely
from shapely.affinity import rotate, scale, translate
from shapely.geometry import LineString, MultiPolygon, Point, Polygon, box
from shapely.geometry.polygon import orient
from shapely.ops import polygonize, unary_union

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
sys.path.insert(0, str(ROOT))
from cnclab.toolpath.job import Job  # noqa: E402

SEED = 20261125
TOOLS_MM = (3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 12.0)
MIN_AE_MM = 0.25
Q = 16          # quad_segs of round features


# ------------------------------------------------------------------------------------------------ shapes
def _blob(rng, radius, k=(2, 5), amp=0.12, n=160, center=(0.0, 0.0)):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    rr = radius * (1 + sum(rng.uniform(-amp, amp) * np.cos(m * t + rng.uniform(0, 6.28)) for m in range(k[0], k[1] + 1)))
    return Polygon(np.c_[center[0] + rr * np.cos(t), center[1] + rr * np.sin(t)])


def _tapered(center_xy, w0, w1):
    """A channel along the polyline ``center_xy`` whose width goes linearly from w0 to w1 (round ends)."""
    c = np.asarray(center_xy, float)
    d = np.gradient(c, axis=0)
    nrm = np.c_[-d[:, 1], d[:, 0]] / np.hypot(d[:, 0], d[:, 1])[:, None]
    s = np.r_[0, np.cumsum(np.hypot(*np.diff(c, axis=0).T))]
    w = w0 + (w1 - w0) * s / s[-1]
    body = Polygon(np.r_[c + nrm * w[:, None] / 2, (c - nrm * w[:, None] / 2)[::-1]]).buffer(0)
    return unary_union([body, Point(c[0]).buffer(w0 / 2, Q), Point(c[-1]).buffer(w1 / 2, Q)])


def _arc(radius, a0, a1, n=120):
    a = np.radians(np.linspace(a0, a1, n))
    return np.c_[radius * np.cos(a), radius * np.sin(a)]


def _spiral(r0, pitch, turns, n=400):
    t = np.linspace(0, 2 * np.pi * turns, n)
    r = r0 + pitch * t / (2 * np.pi)
    return np.c_[r * np.cos(t), r * np.sin(t)]


def star(rng, D):
    n = int(rng.integers(5, 15))
    ang = np.sort(rng.uniform(0, 2 * np.pi, n))
    R = rng.uniform(22, 40)
    rad = R * rng.uniform(0.45, 1.0, n)
    P = Polygon(np.c_[np.cos(ang) * rad, np.sin(ang) * rad]).buffer(0)
    return P.buffer(rng.uniform(0, 2), Q).buffer(-rng.uniform(0, 2), Q) if rng.random() < 0.5 else P


def rectilinear(rng, D):
    g = rng.uniform(8, 14)
    cells = [(0, 0)]
    for _ in range(int(rng.integers(4, 10))):
        x, y = cells[rng.integers(len(cells))]
        dx, dy = [(1, 0), (-1, 0), (0, 1), (0, -1)][rng.integers(4)]
        if (x + dx, y + dy) not in cells:
            cells.append((x + dx, y + dy))
    u = unary_union([box(x * g, y * g, (x + 1) * g, (y + 1) * g) for x, y in cells])
    return max(getattr(u, "geoms", [u]), key=lambda q: q.area)


def islands(rng, D):
    W, H = rng.uniform(45, 85), rng.uniform(35, 65)
    outer = box(0, 0, W, H) if rng.random() < 0.5 else _blob(rng, 0.5 * min(W, H) + 5, center=(W / 2, H / 2))
    P = outer
    for _ in range(int(rng.integers(1, 6))):
        c = (rng.uniform(0.2, 0.8) * W, rng.uniform(0.2, 0.8) * H)
        kind = rng.integers(3)
        isl = (Point(c).buffer(rng.uniform(2, 7), Q) if kind == 0 else
               rotate(box(c[0] - rng.uniform(2, 8), c[1] - rng.uniform(1.5, 5), c[0] + rng.uniform(2, 8),
                          c[1] + rng.uniform(1.5, 5)), rng.uniform(0, 90)) if kind == 1 else
               _blob(rng, rng.uniform(3, 7), amp=0.2, n=60, center=c))
        if P.buffer(-rng.uniform(0.3, 1.2) * D).contains(isl.buffer(rng.uniform(0.2, 1.0) * D)):
            P = P.difference(isl)
    return P


def neck(rng, D):
    r1, r2 = rng.uniform(10, 20), rng.uniform(10, 20)
    L = r1 + r2 + rng.uniform(8, 30)
    w = rng.uniform(1.15, 2.6) * D
    a = Point(0, 0).buffer(r1, Q) if rng.random() < 0.5 else box(-r1, -r1, r1, r1)
    b = Point(L, 0).buffer(r2, Q) if rng.random() < 0.5 else box(L - r2, -r2, L + r2, r2)
    return unary_union([a, b, box(0, -w / 2, L, w / 2)])


def slot_bulbs(rng, D):
    w = rng.uniform(1.1, 1.6) * D
    L = rng.uniform(8, 12) * D
    rb = rng.uniform(1.0, 1.6) * D
    parts = [box(0, -w / 2, L, w / 2), Point(L, 0).buffer(rb, Q)]
    if rng.random() < 0.6:
        parts.append(Point(0, 0).buffer(rb * rng.uniform(0.8, 1.2), Q))
    return unary_union(parts)


def tapered_channel(rng, D):
    R = rng.uniform(40, 80)
    sweep = rng.uniform(70, 150)
    w0 = rng.uniform(2.5, 4.0) * D
    w1 = rng.uniform(1.2, 1.6) * D
    return _tapered(_arc(R, 0, sweep), w0, w1)


def _internal_gear(n_teeth, r_tip, r_root, duty=0.5, n=720):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    s = np.clip(2.5 * np.cos(n_teeth * t) + 2.5 * (2 * duty - 1), -1, 1)      # trapezoidal teeth
    r = 0.5 * (r_tip + r_root) + 0.5 * (r_root - r_tip) * s
    return Polygon(np.c_[r * np.cos(t), r * np.sin(t)])


def gear(rng, D):
    z = int(rng.integers(8, 25))
    r_root = rng.uniform(25, 40)
    h = rng.uniform(0.8, 1.6) * D
    P = _internal_gear(z, r_root - h, r_root, rng.uniform(0.35, 0.65))
    if rng.random() < 0.6:
        P = P.difference(Point(0, 0).buffer(rng.uniform(0.2, 0.45) * (r_root - h - D), Q))
    return P


def spiral(rng, D):
    w = rng.uniform(1.6, 3.0) * D
    pitch = w + rng.uniform(0.8, 2.0) * D
    return LineString(_spiral(rng.uniform(0.5, 1.5) * w, pitch, rng.uniform(1.5, 3.0))).buffer(w / 2, Q)


def comb(rng, D):
    k = int(rng.integers(3, 7))
    wf = rng.uniform(1.2, 2.2) * D
    gap = rng.uniform(0.6, 1.5) * D
    Lf = rng.uniform(3, 6) * D
    spine_w = rng.uniform(1.6, 3.0) * D
    W = k * wf + (k - 1) * gap
    parts = [box(0, 0, W, spine_w)] + [box(i * (wf + gap), spine_w - 0.01, i * (wf + gap) + wf, spine_w + Lf)
                                       for i in range(k)]
    return unary_union(parts)


def channel_15d(rng, D):
    w = rng.uniform(1.35, 1.65) * D
    kind = rng.integers(3)
    if kind == 0:
        return box(0, 0, rng.uniform(8, 16) * D, w)
    if kind == 1:
        return LineString(_arc(rng.uniform(6, 12) * D, 0, rng.uniform(90, 240))).buffer(w / 2, Q)
    return LineString(_spiral(1.2 * w, w + rng.uniform(0.8, 1.5) * D, rng.uniform(1.2, 2.2))).buffer(w / 2, Q)


def regions(rng, D):
    out, x = [], 0.0
    for _ in range(int(rng.integers(2, 5))):
        g = [star, rectilinear, islands, neck][rng.integers(4)](rng, D)
        g = scale(g, 0.6, 0.6)
        g = translate(g, x - g.bounds[0], -g.bounds[1])
        out.append(g)
        x = g.bounds[2] + rng.uniform(2, 10)
    return MultiPolygon([p for g in out for p in getattr(g, "geoms", [g])])


#: family -> (generator(rng, D) -> shapely geometry in mm, number of jobs)
FAMILIES = {
    "star": (star, 6), "rectilinear": (rectilinear, 5), "islands": (islands, 6), "neck": (neck, 5),
    "slot_bulbs": (slot_bulbs, 4), "tapered_channel": (tapered_channel, 3), "gear": (gear, 3),
    "spiral": (spiral, 3), "comb": (comb, 4), "channel_15d": (channel_15d, 5), "regions": (regions, 4),
}


def named_cases():
    """The cases issue 29 names: (name, family, geometry, D, theta)."""
    ch = _tapered(_arc(60.0, -60.0, 60.0), 30.0, 10.0)                  # ~126 mm long, 30 -> 10 mm wide
    g = _internal_gear(10, 28.0, 34.0).difference(Point(0, 0).buffer(9.0, Q))
    return [("tapered_channel_30_10", "tapered_channel", ch, 8.0, 30.7),
            ("gear10_island", "gear", g, 6.0, 45.6),
            ("channel_15d_straight", "channel_15d", box(0, 0, 96.0, 12.0), 8.0, 60.0),
            ("channel_15d_curved", "channel_15d", LineString(_arc(45.0, 0, 180)).buffer(6.0, Q), 8.0, 60.0),
            ("channel_15d_spiral", "channel_15d", LineString(_spiral(12.0, 22.0, 2.0)).buffer(6.0, Q), 8.0, 60.0),
            ("slot_bulbs_named", "slot_bulbs", unary_union([box(0, -4.2, 60, 4.2), Point(0, 0).buffer(7.5, Q),
                                                            Point(60, 0).buffer(7.5, Q)]), 6.0, 60.0)]


# ------------------------------------------------------------------------------------------------ drawings
#: drawing file (in drawings/) -> provenance; the files are byte-identical copies (blob hash checked)
SOURCES = {
    "openscad_example007.dxf": ("openscad/openscad", "examples/Old/example007.dxf", "CC0-1.0 (examples/COPYING-CC0.txt)"),
    "openscad_example008.dxf": ("openscad/openscad", "examples/Old/example008.dxf", "CC0-1.0 (examples/COPYING-CC0.txt)"),
    "openscad_example009.dxf": ("openscad/openscad", "examples/Old/example009.dxf", "CC0-1.0 (examples/COPYING-CC0.txt)"),
    "openscad_polygon-concave-hole.dxf": ("openscad/openscad", "tests/data/dxf/polygon-concave-hole.dxf", "GPL-2.0-or-later (COPYING)"),
    "openscad_polygon-concave.dxf": ("openscad/openscad", "tests/data/dxf/polygon-concave.dxf", "GPL-2.0-or-later (COPYING)"),
    "openscad_polygon-many-holes.dxf": ("openscad/openscad", "tests/data/dxf/polygon-many-holes.dxf", "GPL-2.0-or-later (COPYING)"),
    "openscad_polygon8.dxf": ("openscad/openscad", "tests/data/dxf/polygon8.dxf", "GPL-2.0-or-later (COPYING)"),
    "openscad_polygons.dxf": ("openscad/openscad", "tests/data/dxf/polygons.dxf", "GPL-2.0-or-later (COPYING)"),
    "openscad_box-w-holes.svg": ("openscad/openscad", "tests/data/svg/box-w-holes.svg", "GPL-2.0-or-later (COPYING)"),
    "ezdxf_forms.dxf": ("mozman/ezdxf", "examples/addons/optimize/forms.dxf", "MIT (LICENSE)"),
    "ezdxf_1_polylines.dxf": ("mozman/ezdxf", "examples/edgeminer/1_polylines.dxf", "MIT (LICENSE)"),
}
#: the repositories' snapshot commits the files were copied from
COMMITS = {"openscad/openscad": "e4fdec49730103274a4e21c2390b9a12882f01aa",
           "mozman/ezdxf": "5ffc690746f1a993ff0c10f4dcd408b4ecedde59"}
#: drawing jobs: (job name, drawing file, which parts: "largest" | int k (k-th largest) | "all" | "inner":
#: the first hole of the largest part with the parts inside it as islands)
DRAWINGS = [
    ("dwg_example007", "openscad_example007.dxf", "all"),
    ("dwg_example008", "openscad_example008.dxf", "largest"),
    ("dwg_example008_all", "openscad_example008.dxf", "all"),
    ("dwg_example009", "openscad_example009.dxf", "largest"),
    ("dwg_concave_hole", "openscad_polygon-concave-hole.dxf", "largest"),
    ("dwg_concave", "openscad_polygon-concave.dxf", "largest"),
    ("dwg_many_holes_frame", "openscad_polygon-many-holes.dxf", "largest"),
    ("dwg_many_holes_inner", "openscad_polygon-many-holes.dxf", "inner"),
    ("dwg_polygon8", "openscad_polygon8.dxf", "largest"),
    ("dwg_polygons", "openscad_polygons.dxf", "all"),
    ("dwg_box_w_holes", "openscad_box-w-holes.svg", "largest"),
    ("dwg_forms_0", "ezdxf_forms.dxf", 0),
    ("dwg_forms_1", "ezdxf_forms.dxf", 1),
    ("dwg_forms_3", "ezdxf_forms.dxf", 3),
    ("dwg_forms_4", "ezdxf_forms.dxf", 4),
    ("dwg_forms_9", "ezdxf_forms.dxf", 9),
    ("dwg_polylines", "ezdxf_1_polylines.dxf", "largest"),
]
_DXF_TYPES = {"LINE", "ARC", "CIRCLE", "ELLIPSE", "LWPOLYLINE", "POLYLINE", "SPLINE"}


def _drawing_lines(path: Path) -> list:
    if path.suffix.lower() == ".svg":
        import svgelements

        lines = []
        for el in svgelements.SVG.parse(str(path)).elements():
            if isinstance(el, svgelements.Shape) and not isinstance(el, svgelements.Group):
                p = svgelements.Path(el)
                for sub in p.as_subpaths():
                    sp = svgelements.Path(sub)
                    n = max(2, int(sp.length(error=1e-3) / 0.01) + 1) if sp.length(error=1e-3) > 0 else 0
                    if n >= 2:
                        pts = [sp.point(t) for t in np.linspace(0, 1, min(n, 4000))]
                        lines.append(LineString([(q.x, -q.y) for q in pts]))      # SVG y points down
        return lines
    import ezdxf
    from ezdxf import path as ezpath

    lines = []
    for e in ezdxf.readfile(str(path)).modelspace():
        if e.dxftype() not in _DXF_TYPES:
            continue
        for sp in ezpath.make_path(e).sub_paths():
            v = [(q.x, q.y) for q in sp.flattening(0.01)]
            if len(v) >= 2:
                lines.append(LineString(v))
    return lines


def drawing_parts(path: Path) -> list:
    """The even-odd regions of a drawing's closed outlines, largest first (drawing units)."""
    faces = list(polygonize(unary_union(_drawing_lines(path))))
    shells = [Polygon(f.exterior) for f in faces]
    keep = []
    for i, f in enumerate(faces):
        p = f.representative_point()
        depth = sum(1 for j, s in enumerate(shells) if j != i and s.area > f.area and s.contains(p))
        if depth % 2 == 0:
            keep.append(f)
    u = unary_union(keep)
    return sorted(getattr(u, "geoms", [u]), key=lambda q: -q.area)


def _blob_sha(path: Path) -> str:
    data = path.read_bytes()
    return hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest()


# ------------------------------------------------------------------------------------------------ jobs
def _tool_theta(rng):
    while True:
        D = float(rng.choice(TOOLS_MM))
        th = float(rng.uniform(20.0, 120.0))
        if 0.5 * D * (1 - math.cos(math.radians(th))) >= MIN_AE_MM:
            return D, round(th, 1)


def _normalise(g):
    g = translate(g, -g.bounds[0], -g.bounds[1])
    g = shapely.set_precision(g, 1e-3)
    parts = [orient(p, 1.0) for p in getattr(g, "geoms", [g]) if p.area > 1e-6]
    return MultiPolygon(parts) if len(parts) > 1 else parts[0]


def _job_dict(name, family, g, D, theta, deep, provenance):
    a_p = min(4.0, 0.5 * D)
    d = {"description": f"corpus job {name} (family {family}): D {D:g} mm, theta {theta:g} deg",
         "_provenance": provenance, "_family": family,
         "tool_diameter": D, "teeth": 2, "v_c": 150.0, "f_z": round(min(0.08, max(0.03, 0.008 * D)), 3),
         "theta_deg": theta, "a_p": a_p, "depth": (2 if deep else 1) * a_p, "link_feed": 1500.0}
    job = Job(g, _tool(D), theta, a_p, v_c=150.0, f_z=d["f_z"])
    d["v_fmax"] = round(1.5 * job.feed_mm_min, 1)
    ring = lambda r: [[round(x, 3), round(y, 3)] for x, y in np.asarray(r.coords)[:-1]]  # noqa: E731
    polys = list(getattr(g, "geoms", [g]))
    if len(polys) == 1:
        d["polygon"] = ring(polys[0].exterior)
        if polys[0].interiors:
            d["islands"] = [ring(i) for i in polys[0].interiors]
    else:
        d["regions"] = [{"polygon": ring(p.exterior), "islands": [ring(i) for i in p.interiors]} for p in polys]
    Job.from_dict(d, source=name)           # raises if the loader refuses it
    return d


def _tool(D):
    from cnclab.toolpath.path import Tool

    return Tool(D, 0.0, 2)


def build() -> dict:
    """All jobs: name -> (job dict, provenance sidecar dict or None)."""
    root = np.random.default_rng(SEED)
    out = {}
    synthetic = "generated by data/pockets/corpus/make_corpus.py (seeded, frozen; issue 29 corpus)"
    k_all = 0
    for family, (gen, n) in FAMILIES.items():
        for i in range(n):
            rng = np.random.default_rng(root.integers(2**63))
            for _attempt in range(50):
                D, th = _tool_theta(rng)
                try:
                    g = _normalise(gen(rng, D))
                    d = _job_dict(f"{family}_{i}", family, g, D, th, k_all % 8 == 7, synthetic)
                    break
                except (ValueError, shapely.errors.GEOSException):
                    continue
            else:
                raise RuntimeError(f"{family}_{i}: no valid job in 50 draws")
            out[f"{family}_{i}"] = (d, None)
            k_all += 1
    for name, family, g, D, th in named_cases():
        out[name] = (_job_dict(name, family, _normalise(g), D, th, False, synthetic + "; a case named in issue 29"), None)
    for name, fname, which in DRAWINGS:
        rng = np.random.default_rng(root.integers(2**63))
        path = HERE / "drawings" / fname
        parts = drawing_parts(path)
        if which == "inner":
            g = Polygon(parts[0].interiors[0]).difference(unary_union(parts[1:]))
        else:
            g = unary_union(parts) if which == "all" else parts[0 if which == "largest" else which]
        for _attempt in range(50):
            D, th = _tool_theta(rng)
            size = float(rng.uniform(50, 110))
            f = size / max(g.bounds[2] - g.bounds[0], g.bounds[3] - g.bounds[1])
            try:
                gg = _normalise(scale(g, f, f, origin=(0, 0)))
                repo, rpath, lic = SOURCES[fname]
                prov = {"repo": repo, "path": rpath, "commit": COMMITS[repo], "blob_sha1": _blob_sha(path),
                        "licence": lic, "copy": f"data/pockets/corpus/drawings/{fname}", "parts": which,
                        "scale": f, "transform": "uniform scale about the origin, then moved to the positive quadrant",
                        "extraction": "data/pockets/corpus/make_corpus.py drawing_parts (ezdxf/svgelements, "
                                      "shapely polygonize, even-odd nesting)"}
                d = _job_dict(name, "drawing", gg, D, th, False, f"outline from {repo}:{rpath}@{COMMITS[repo][:10]} "
                              f"({lic}); see provenance/{name}.json")
                break
            except (ValueError, shapely.errors.GEOSException):
                continue
        else:
            raise RuntimeError(f"{name}: no valid job in 50 draws")
        out[name] = (d, prov)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true", help="compare with the committed jobs; write nothing")
    a = ap.parse_args(argv)
    jobs = build()
    bad = []
    for name, (d, prov) in jobs.items():
        text = json.dumps(d, indent=1) + "\n"
        f = HERE / f"{name}.json"
        if a.check:
            if not f.exists() or f.read_text(encoding="utf-8") != text:
                bad.append(name)
            continue
        f.write_text(text, encoding="utf-8")
        if prov is not None:
            (HERE / "provenance").mkdir(exist_ok=True)
            (HERE / "provenance" / f"{name}.json").write_text(json.dumps(prov, indent=1) + "\n", encoding="utf-8")
    fams = {}
    for d, _ in jobs.values():
        fams[d["_family"]] = fams.get(d["_family"], 0) + 1
    print(f"{len(jobs)} jobs: {fams}")
    if bad:
        raise SystemExit(f"corpus differs from the generator: {bad}")


if __name__ == "__main__":
    main()
