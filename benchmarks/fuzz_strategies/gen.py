"""The generator of the frozen fuzz corpus ``benchmarks/fuzz_strategies/jobs/`` (session 21, seed 29029,
40 jobs: rotated rectangles, L, T, U, filleted rectangles, circles, ellipses, rectangles with islands,
channels and slots; D 4-12 mm, a_p 1-4 mm, depth a_p / 2 a_p / 2.5 a_p, theta 30-90 deg, a start hole
in a third). Kept for provenance: the corpus is frozen, the planners are fixed, not the corpus.

    python benchmarks/fuzz_strategies/gen.py [SEED] [N] [OUT_DIR]
"""
import json, math, os, random, sys
from shapely.geometry import Polygon, Point, box
from shapely import affinity

SEED = int(sys.argv[1]) if len(sys.argv) > 1 else 29029
N = int(sys.argv[2]) if len(sys.argv) > 2 else 40
rng = random.Random(SEED)
HERE = os.path.dirname(os.path.abspath(__file__))
OUT = sys.argv[3] if len(sys.argv) > 3 else os.path.join(HERE, "jobs")
os.makedirs(OUT, exist_ok=True)


def ring(poly):
    return [[round(x, 4), round(y, 4)] for x, y in list(poly.exterior.coords)[:-1]]


def rot_trans(geoms, ang, dx, dy):
    return [affinity.translate(affinity.rotate(g, ang, origin=(0, 0)), dx, dy) for g in geoms]


def shape(kind, D):
    """return (outer Polygon, [island Polygons], descr)"""
    islands = []
    if kind == "rotrect":
        w, h = rng.uniform(30, 90), rng.uniform(30, 90)
        outer = box(0, 0, w, h)
        d = f"rect {w:.1f}x{h:.1f}"
    elif kind == "L":
        W, H = rng.uniform(40, 90), rng.uniform(40, 90)
        a = rng.uniform(max(2.5 * D, 12), 0.6 * W)
        b = rng.uniform(max(2.5 * D, 12), 0.6 * H)
        outer = Polygon([(0, 0), (W, 0), (W, b), (a, b), (a, H), (0, H)])
        d = f"L {W:.1f}x{H:.1f} arms {a:.1f},{b:.1f}"
    elif kind == "T":
        W, H = rng.uniform(45, 90), rng.uniform(40, 90)
        bar = rng.uniform(max(2.5 * D, 12), 0.5 * H)
        stem = rng.uniform(max(2.5 * D, 12), 0.5 * W)
        x0 = (W - stem) / 2
        outer = Polygon([(0, H - bar), (0, H), (W, H), (W, H - bar), (x0 + stem, H - bar), (x0 + stem, 0), (x0, 0), (x0, H - bar)])
        d = f"T {W:.1f}x{H:.1f} bar {bar:.1f} stem {stem:.1f}"
    elif kind == "U":
        W, H = rng.uniform(45, 90), rng.uniform(40, 90)
        arm = rng.uniform(max(2.5 * D, 12), 0.35 * W)
        base = rng.uniform(max(2.5 * D, 12), 0.5 * H)
        outer = Polygon([(0, 0), (W, 0), (W, H), (W - arm, H), (W - arm, base), (arm, base), (arm, H), (0, H)])
        d = f"U {W:.1f}x{H:.1f} arm {arm:.1f} base {base:.1f}"
    elif kind == "fillet":
        w, h = rng.uniform(30, 90), rng.uniform(30, 90)
        r = rng.uniform(0.4 * D, min(2.5 * D, min(w, h) / 3))
        outer = box(r, r, w - r, h - r).buffer(r, quad_segs=rng.choice([8, 16, 32]))
        d = f"filleted rect {w:.1f}x{h:.1f} r {r:.2f}"
    elif kind == "circle":
        R = rng.uniform(15, 45)
        n = rng.choice([64, 96, 128, 200])
        outer = Polygon([(R * math.cos(2 * math.pi * i / n), R * math.sin(2 * math.pi * i / n)) for i in range(n)])
        d = f"circle R {R:.1f} n {n}"
    elif kind == "ellipse":
        a, b = rng.uniform(15, 45), rng.uniform(15, 45)
        n = rng.choice([64, 96, 128])
        outer = Polygon([(a * math.cos(2 * math.pi * i / n), b * math.sin(2 * math.pi * i / n)) for i in range(n)])
        d = f"ellipse {a:.1f},{b:.1f} n {n}"
    elif kind in ("rect_islands",):
        w, h = rng.uniform(50, 90), rng.uniform(40, 90)
        outer = box(0, 0, w, h)
        k = rng.choice([1, 2])
        tries = 0
        while len(islands) < k and tries < 500:
            tries += 1
            sz = rng.uniform(5, 18)
            cx, cy = rng.uniform(0, w), rng.uniform(0, h)
            if rng.random() < 0.5:
                isl = Point(cx, cy).buffer(sz / 2, quad_segs=16)
            else:
                isl = affinity.rotate(box(cx - sz / 2, cy - sz / 2, cx + sz / 2, cy + sz / 2), rng.choice([0, 0, 15, 45]))
            gap = 1.5 * D
            if outer.exterior.distance(isl) < gap or not outer.contains(isl):
                continue
            if any(isl.distance(o) < gap for o in islands):
                continue
            islands.append(isl)
        d = f"rect {w:.1f}x{h:.1f} with {len(islands)} islands"
    elif kind == "channel":
        L = rng.uniform(40, 90)
        wd = rng.uniform(1.25 * D, 2.2 * D)
        if rng.random() < 0.5:
            outer = box(0, 0, L, wd)
            d = f"channel {L:.1f}x{wd:.2f} square ends"
        else:
            from shapely.geometry import LineString
            outer = LineString([(0, 0), (L, 0)]).buffer(wd / 2, quad_segs=16)
            d = f"slot {L:.1f} width {wd:.2f} round ends"
    else:
        raise ValueError(kind)
    return outer, islands, d


KINDS = ["rotrect", "L", "T", "U", "fillet", "circle", "ellipse", "rect_islands", "channel"]

manifest = []
for i in range(N):
    kind = KINDS[i % len(KINDS)] if i < 2 * len(KINDS) else rng.choice(KINDS)
    D = round(rng.uniform(4, 12), 2)
    if kind in ("channel",):
        D = round(rng.uniform(4, 10), 2)
    outer, islands, descr = shape(kind, D)
    ang = rng.uniform(0, 360) if kind in ("rotrect", "L", "T", "U", "fillet", "ellipse", "channel", "rect_islands") and rng.random() < 0.7 else 0.0
    dx, dy = rng.choice([(0, 0), (rng.uniform(-150, 150), rng.uniform(-150, 150))])
    geoms = rot_trans([outer] + islands, ang, dx, dy)
    outer, islands = geoms[0], geoms[1:]
    # sanity: tool must fit comfortably
    if outer.buffer(-D / 2 * 1.1).is_empty:
        print("skip (tool does not fit)", i, descr)
    a_p = round(rng.uniform(1, 4), 2)
    depth = round(a_p * rng.choice([1, 2, 2.5]), 3)
    theta = round(rng.uniform(30, 90), 1)
    ring_o = ring(outer)
    if rng.random() < 0.4:
        ring_o = ring_o[::-1]  # random orientation
    job = {
        "_generator": f"gen.py seed {SEED} index {i} kind {kind}: {descr}, rotated {ang:.1f} deg, shifted ({dx:.1f},{dy:.1f})",
        "polygon": ring_o,
        "tool_diameter": D,
        "a_p": a_p,
        "depth": depth,
        "theta_deg": theta,
        "v_c": round(rng.uniform(80, 200), 1),
        "f_z": round(rng.uniform(0.02, 0.08), 3),
        "teeth": rng.choice([2, 2, 3, 4]),
    }
    if islands:
        job["islands"] = [ring(p) if rng.random() < 0.6 else ring(p)[::-1] for p in islands]
    if rng.random() < 1 / 3:
        hd = round(D * rng.uniform(1.1, 1.6), 2)
        region = outer
        for isl in islands:
            region = region.difference(isl)
        inner = region.buffer(-(hd / 2 + D / 2))
        if not inner.is_empty:
            minx, miny, maxx, maxy = inner.bounds
            for _ in range(1000):
                p = Point(rng.uniform(minx, maxx), rng.uniform(miny, maxy))
                if inner.contains(p):
                    job["start_hole"] = {"center": [round(p.x, 3), round(p.y, 3)], "diameter": hd}
                    break
    name = f"job{i:02d}_{kind}"
    with open(os.path.join(OUT, name + ".json"), "w") as f:
        json.dump(job, f, indent=1)
    manifest.append({"name": name, "kind": kind, "descr": descr, "D": D, "a_p": a_p, "depth": depth, "theta": theta,
                     "area": round(outer.area - sum(p.area for p in islands), 1), "start_hole": "start_hole" in job})
with open(os.path.join(OUT, "..", "manifest.json") if len(sys.argv) <= 3 else os.path.join(OUT, "manifest.json"), "w") as f:
    json.dump({"seed": SEED, "jobs": manifest}, f, indent=1)
for m in manifest:
    print(m)
