"""Pocket jobs of the issue-16 comparison, read into a small Job-like object (the attribute names of
``cnclab.toolpath.job.Job`` in CONTRACT_12) until the package's ``load_job`` replaces this reader.

Formats read: the Jacsó §4 job files (``polygon`` or ``star``, ``start_hole``, Table 4.1 cutting
data), the issue-16 pockets in data/pockets/ (same format plus ``islands`` and ``regions``: a list
of ``{"polygon", "islands"}`` for disjoint regions) and the Kim & Yang pocket
(``outer`` + ``islands``) with the Table 1 conditions of data/kim_yang2006/table1_conditions.json
(D = 10 mm, a_e = 3 mm -> theta = acos(1 - 3/5) = 66.42 deg, a_p = 0.5 mm, feed 500 mm/min,
2000 rpm; link feed 1500 mm/min as in Jacsó §4).
"""
from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import shapely
from shapely.geometry import MultiPolygon, Polygon

from cnclab.paths import data_path
from cnclab.toolpath.path import Tool
from cnclab.toolpath.pocket import star_polygon

ROOT = Path(__file__).resolve().parents[1]
#: the pockets of the comparison: name -> job file (relative to the repository)
POCKETS = {
    "star": "data/jacso2021/star_pocket.json",
    "rectangle": "data/jacso2021/rectangle_pocket.json",
    "L": "data/jacso2021/l_pocket.json",
    "kim_yang_120x85": "data/kim_yang2006/pocket_120x85.json",
    "two_islands_neck": "data/pockets/two_islands_neck.json",
    "spline": "data/pockets/spline_pocket.json",
    "slot": "data/pockets/long_slot.json",
    "two_regions": "data/pockets/two_regions.json",
}


@dataclasses.dataclass
class BenchJob:
    polygon: Polygon | MultiPolygon
    tool: Tool
    theta_deg: float
    a_p: float
    depth: float
    start_hole: tuple | None
    feed_mm_min: float
    spindle_rpm: float
    link_feed_mm_min: float = 1500.0
    rapid_mm_min: float = 10000.0
    clearance_z: float = 5.0
    top_z: float = 0.0
    f_z: float = 0.04
    source: str = "<job>"
    resolution_mm: float = 0.05

    @property
    def tool_radius(self) -> float:
        return 0.5 * self.tool.diameter

    @property
    def a_e(self) -> float:
        return self.tool_radius * (1 - math.cos(math.radians(self.theta_deg)))


def _poly(outer, islands=()):
    return Polygon(outer, [list(h) for h in islands])


def load_job(path) -> BenchJob:
    p = Path(path)
    if not p.is_absolute():
        p = ROOT / p
    d = json.loads(p.read_text(encoding="utf-8"))
    src = str(p.relative_to(ROOT)) if p.is_relative_to(ROOT) else str(p)
    if "outer" in d:  # Kim & Yang pocket + Table 1
        t = json.loads(data_path("kim_yang2006", "table1_conditions.json").read_text(encoding="utf-8"))
        r = 0.5 * t["tool_diameter_mm"]
        theta = math.degrees(math.acos(1 - t["radial_depth_mm"] / r))
        return BenchJob(_poly(d["outer"], d.get("islands", [])), Tool(2 * r, flutes=2), theta,
                        t["axial_depth_mm"], t["axial_depth_mm"], None, t["feed_mm_min"], t["spindle_rpm"],
                        source=src, resolution_mm=0.1, f_z=t["feed_mm_min"] / (2 * t["spindle_rpm"]))
    if "regions" in d:
        poly = MultiPolygon([_poly(g["polygon"], g.get("islands", [])) for g in d["regions"]])
    elif "star" in d and "polygon" not in d:
        poly = star_polygon(**d["star"])
    else:
        poly = _poly(d["polygon"], d.get("islands", []))
    if not poly.is_valid:
        raise ValueError(f"{src}: the pocket polygon is not valid ({shapely.is_valid_reason(poly)})")
    sh = d.get("start_hole")
    hole = None if sh is None else (float(sh["center"][0]), float(sh["center"][1]), float(sh["diameter"]))
    teeth = int(d.get("teeth", 1))
    rpm = 1000 * d["v_c"] / (math.pi * d["tool_diameter"])
    feed = float(d.get("feed_mm_min", teeth * d["f_z"] * rpm))
    return BenchJob(poly, Tool(float(d["tool_diameter"]), flutes=teeth), float(d["theta_deg"]), float(d["a_p"]),
                    float(d.get("depth", d["a_p"])), hole, feed, rpm, float(d.get("link_feed", 1500.0)),
                    f_z=float(d["f_z"]), source=src)
