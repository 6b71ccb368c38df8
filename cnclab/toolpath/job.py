"""One 2.5D pocket job for every planner and the evaluator: :class:`Job`, :func:`load_job`, :data:`JOB_SCHEMA`.

A job is a pocket (shapely ``Polygon`` or ``MultiPolygon``, mm; islands are its holes), a flat end
mill (:class:`~cnclab.toolpath.path.Tool`), the target engagement ``theta_deg`` (deg), the axial
depth per level ``a_p`` and the pocket ``depth`` (mm; deeper than a_p: cut in levels of at most
a_p), an optional pre-drilled start hole and the cutting data (v_c m/min, f_z mm/tooth, feeds
mm/min, spindle rpm). The stock top is ``top_z`` (0), the clearance plane ``clearance_z`` (5 mm).

The JSON job format (``data/jacso2021/*.json``, ``data/kim_yang2006/pocket_120x85.json``)::

    {"polygon": [[x, y], ...]            (or "star": {star_polygon keywords}),
     "islands": [[[x, y], ...], ...],    optional
     (every ring, outline or island, may also be {"circle": {"center": [x, y], "radius": r}}: flattened
      to an inscribed polygon of chord error "tolerance", default 0.005 mm, see ring_points)
     "start_hole": {"center": [x, y], "diameter": d},   optional (else the planner makes its entry)
     "tool_diameter": 6, "teeth": 1, "corner_radius": 0,
     "theta_deg": 60, "a_p": 3, "depth": 3,              depth optional (default a_p)
     "v_c": 120 or "spindle_rpm": 6366, "f_z": 0.04 and/or "feed_mm_min": 255,
     "link_feed": 1500, "entry_feed_mm_min": 127.5, "v_fmax": 1000, "roll_radius": 1, "rapid_mm_min": 10000,
     "clearance_z": 5, "top_z": 0, "description": "...", "_provenance": "..."}

:func:`load_job` validates the file against :data:`JOB_SCHEMA` (jsonschema) and then the geometry;
every error is a ``ValueError`` naming the file and the JSON path (``$.start_hole.diameter``).

>>> job = Job.from_dict({"polygon": [[0, 0], [40, 0], [40, 30], [0, 30]], "tool_diameter": 6,
...                      "theta_deg": 60, "a_p": 3, "v_c": 120, "f_z": 0.04, "teeth": 1,
...                      "start_hole": {"center": [20, 15], "diameter": 11}})
>>> round(job.a_e, 6), round(job.volume_mm3(), 1)      # r (1 - cos 60), a_p (1200 - pi 5.5^2)
(1.5, 3314.9)
>>> Job.from_dict({"polygon": [[0, 0], [5, 0], [5, 30], [0, 30]], "tool_diameter": 6, "theta_deg": 60,
...                "a_p": 3, "v_c": 120, "f_z": 0.04, "teeth": 1})
Traceback (most recent call last):
...
ValueError: <dict>: $.polygon: the tool (diameter 6 mm) cannot enter the pocket: it is narrower than the tool
"""
from __future__ import annotations

import dataclasses
import difflib
import json
import math
import sys
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Point, Polygon

from ..cutting.speeds import cutting_speed, feed_speed, spindle_speed
from ..geometry.drawing import CHORD_TOL_MM, circle_points
from ..geometry.engagement import stepover_straight
from .path import Tool

__all__ = ["CUTTING_LENGTH_PER_D", "ENTRY_FEED_FRACTION", "JOB_SCHEMA", "MAX_LAPS", "LINK_FEED_MM_MIN", "RAPID_MM_MIN",
           "SPINDLE_RPM_MAX",
           "Job", "load_job", "plausibility", "read_job_json", "ring_points", "star_polygon", "theta_min_deg"]

#: Linking feed (mm/min): Jacsó (2021) §4, "on the straight sections of the connecting movements, an
#: equally increased feed rate (v_f = 1500 mm/min) was used" (text under Table 4.1).
LINK_FEED_MM_MIN = 1500.0
#: Default helix/ramp entry feed as a fraction of the cutting feed ``feed_mm_min`` (:attr:`Job.entry_feed`,
#: when the job gives no ``entry_feed_mm_min``): a helix or ramp cuts a full slot while it descends, so it
#: runs slower than the cut; 0.5 is cnclab's choice (issue 24), not a value from a source
ENTRY_FEED_FRACTION = 0.5
#: Rapid traverse (mm/min): an ASSUMED machine value (no seed gives one).
RAPID_MM_MIN = 10000.0
#: Default top spindle speed (rpm) when a job states none (``spindle_rpm_max``): an ASSUMED machine value,
#: the top speed of the common 24 000 rpm spindles of small VMCs and routers.
SPINDLE_RPM_MAX = 24000.0
#: Default cutting (flute) length of the tool as a multiple of its diameter (``cutting_length`` not given):
#: flute lengths of 4-12 mm end mills are up to about 3 D (long-flute types 3-5 D), so an ``a_p`` above
#: 3 D needs a stated ``cutting_length``.
CUTTING_LENGTH_PER_D = 3.0
#: A job whose tool is under 1 mm and whose pocket fits in 50 mm looks typed in inches (0.25 for a
#: 6.35 mm tool): warned, not refused (micro-milling exists).
INCH_LOOK_TOOL_MM, INCH_LOOK_EXTENT_MM = 1.0, 50.0
#: Cap on the number of clearing laps of a planner (ce_clearing's ``max_laps``): a theta so small
#: that the pocket needs more laps than this is refused by :func:`theta_min_deg`.
MAX_LAPS = 200

#: coordinates are limited to +-1 km (mm): beyond it the geometry tolerances (0.01 mm) make no sense
_COORD = {"type": "number", "minimum": -1e6, "maximum": 1e6}
_POINT = {"type": "array", "items": _COORD, "minItems": 2, "maxItems": 2,
          "description": "an [x, y] point in mm (|x|, |y| <= 1e6)"}
_POS = {"type": "number", "exclusiveMinimum": 0, "maximum": 1e9}
_POINTS = {"type": "array", "items": _POINT, "minItems": 3, "description": "a list of >= 3 [x, y] points in mm"}
_CIRCLE = {"type": "object", "required": ["circle"], "additionalProperties": False,
           "properties": {"circle": {
               "type": "object", "required": ["center", "radius"], "additionalProperties": False,
               "description": "a circle {center: [x, y], radius: r, tolerance: chord error} (mm)",
               "properties": {"center": _POINT, "radius": dict(_POS, maximum=1e6, description="circle radius, mm"),
                              "tolerance": {"type": "number", "minimum": 1e-5, "maximum": 1,
                                            "description": "chord error of the circle's flattening, mm "
                                            f"(default {CHORD_TOL_MM})"}}}}}
#: a ring: a list of >= 3 [x, y] points, or {"circle": {"center": [x, y], "radius": r}} (mm)
_RING = {"if": {"type": "object"}, "then": _CIRCLE, "else": _POINTS,
         "description": "a list of >= 3 [x, y] points or {circle: {center: [x, y], radius: r}} (mm)"}


def _pos(desc):
    return dict(_POS, description=desc)


#: JSON schema (draft 2020-12) of a job file; geometry checks follow in :meth:`Job.from_dict`.
JOB_SCHEMA = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "cnclab 2.5D pocket job",
    "type": "object",
    "properties": {
        "polygon": dict(_RING, description="the pocket outline: a list of >= 3 [x, y] points or a "
                        "{circle: {center: [x, y], radius: r}} (mm)"),
        "star": {"type": "object", "description": "keywords of cnclab.toolpath.job.star_polygon",
                 "properties": {"n_arms": {"type": "integer", "minimum": 3},
                                "outer_radius": _pos("mm"), "inner_ratio": {"type": "number", "exclusiveMinimum": 0,
                                                                            "exclusiveMaximum": 1},
                                "tip_radius": _pos("mm"), "root_radius": _pos("mm"), "center": _POINT,
                                "rotation_deg": {"type": "number"}, "quad_segs": {"type": "integer", "minimum": 1}},
                 "additionalProperties": False},
        "islands": {"type": "array", "items": _RING, "description": "a list of island outlines (each >= 3 [x, y] points)"},
        "regions": {"type": "array", "minItems": 1,
                    "items": {"type": "object", "properties": {"polygon": _RING, "islands": {"type": "array", "items": _RING}},
                              "required": ["polygon"], "additionalProperties": False},
                    "description": "disjoint pocket regions of one job: a list of {polygon, islands}"},
        "start_hole": {"type": "object", "properties": {"center": _POINT, "diameter": _pos("start hole diameter, mm")},
                       "required": ["center", "diameter"], "additionalProperties": False,
                       "description": "a pre-drilled hole {center: [x, y], diameter: d} (mm)"},
        "tool_diameter": _pos("tool diameter, mm"),
        "corner_radius": {"type": "number", "minimum": 0, "description": "tool corner radius, mm"},
        "teeth": {"type": "integer", "minimum": 1, "description": "number of teeth (a positive integer)"},
        "tool_number": {"type": "integer", "minimum": 0, "description": "T word of the program"},
        "theta_deg": {"type": "number", "exclusiveMinimum": 0, "exclusiveMaximum": 180,
                      "description": "target engagement angle, deg in (0, 180)"},
        "a_p": _pos("axial depth of cut per level, mm"),
        "depth": _pos("pocket depth, mm (default a_p)"),
        "v_c": _pos("cutting speed, m/min"),
        "spindle_rpm": _pos("spindle speed, rpm"),
        "f_z": _pos("feed per tooth, mm"),
        "feed_mm_min": _pos("nominal cutting feed, mm/min"),
        "link_feed": _pos("linking feed, mm/min"),
        "entry_feed_mm_min": _pos("helix/ramp entry feed, mm/min (default 0.5 x the cutting feed, "
                                  "cnclab.toolpath.job.ENTRY_FEED_FRACTION)"),
        "rapid_links": {"type": "boolean", "description": "links at depth through cleared area as G0 "
                        "(default true; false on a controller whose rapids dog-leg: G1 at link_feed)"},
        "v_fmax": _pos("maximum feed of the feed control, mm/min"),
        "roll_radius": _pos("roll-in/roll-out radius, mm"),
        "rapid_mm_min": _pos("rapid traverse rate, mm/min"),
        "cutting_length": _pos(f"cutting (flute) length of the tool, mm (default {CUTTING_LENGTH_PER_D:g} x tool_diameter)"),
        "spindle_rpm_max": _pos(f"top spindle speed of the machine, rpm (default {SPINDLE_RPM_MAX:g})"),
        "feed_max_mm_min": _pos("top feed of the machine, mm/min (default rapid_mm_min)"),
        "clearance_z": {"type": "number", "description": "clearance plane z, mm"},
        "top_z": {"type": "number", "description": "stock top z, mm"},
        "description": {"type": "string"}, "source": {"type": "string"}, "units": {"const": "mm"},
    },
    "patternProperties": {"^_": {}},
    "required": ["tool_diameter", "theta_deg", "a_p"],
    "oneOf": [{"required": ["polygon"]}, {"required": ["star"]}, {"required": ["regions"]}],
    "additionalProperties": False,
}

_VALIDATOR = []


def _validator():
    """The JSON-schema validator of :data:`JOB_SCHEMA`, built on first use. jsonschema is imported
    with its optional ``iri`` format checker (package ``rfc3987_syntax``, installed by Jupyter)
    hidden: its import compiles a grammar, ~2 s of CPU in every process that loads a job, for a
    format this schema never uses (no ``format`` keyword: format checks are off anyway)."""
    if not _VALIDATOR:
        hide = "rfc3987_syntax" not in sys.modules
        if hide:
            sys.modules["rfc3987_syntax"] = None        # makes `import rfc3987_syntax` raise ImportError
        try:
            import jsonschema
        finally:
            if hide and sys.modules.get("rfc3987_syntax", 0) is None:
                del sys.modules["rfc3987_syntax"]
        _VALIDATOR.append(jsonschema.Draft202012Validator(JOB_SCHEMA))
    return _VALIDATOR[0]


def star_polygon(n_arms=5, outer_radius=23.0, inner_ratio=0.5, tip_radius=4.0, root_radius=2.0,
                 center=(0.0, 0.0), rotation_deg=90.0, quad_segs=32) -> Polygon:
    """Rounded star (mm): a regular star polygon with tips at ``outer_radius`` and roots at
    ``inner_ratio * outer_radius``, its convex tips rounded with ``tip_radius`` (the pocket's concave
    corners: must exceed the tool radius for the tool to follow) and its roots with ``root_radius``.

    Rounding is morphological: tips by an opening (buffer -rt, +rt), roots by a closing (+rr, -rr).

    >>> round(star_polygon(outer_radius=24.2856).area, 1)
    794.4
    """
    n = int(n_arms)
    if n < 3:
        raise ValueError(f"n_arms must be >= 3, got {n_arms!r}")
    if not 0 < inner_ratio < 1:
        raise ValueError(f"inner_ratio must be in (0, 1), got {inner_ratio!r}")
    k = np.arange(2 * n)
    rad = np.where(k % 2 == 0, outer_radius, inner_ratio * outer_radius)
    ang = np.radians(rotation_deg) + k * np.pi / n
    poly = Polygon(np.c_[center[0] + rad * np.cos(ang), center[1] + rad * np.sin(ang)])
    poly = poly.buffer(-tip_radius, quad_segs).buffer(tip_radius, quad_segs)
    poly = poly.buffer(root_radius, quad_segs).buffer(-root_radius, quad_segs)
    return shapely.set_precision(poly, 1e-9)


def theta_min_deg(polygon, tool_radius: float, max_laps: int = MAX_LAPS) -> float:
    """Smallest engagement (deg) a clearing planner can use on ``polygon`` within ``max_laps`` laps.

    A lap at engagement theta advances the cleared region by at most a_e = r (1 - cos theta) (a
    straight cut; less on concave stretches), and clearing reaches every point of the pocket only
    after ``R_in / a_e`` laps, R_in the largest inscribed radius of the pocket. So theta must satisfy
    ``R_in / (r (1 - cos theta)) <= max_laps``: ``theta_min = arccos(1 - R_in / (max_laps r))``.

    >>> from shapely.geometry import box
    >>> round(theta_min_deg(box(0, 0, 40, 24), 3.0), 2)          # R_in = 12 mm
    11.48
    """
    r_in = float(shapely.maximum_inscribed_circle(polygon, 0.01).length)
    c = 1.0 - r_in / (int(max_laps) * float(tool_radius))
    return 180.0 if c <= -1 else math.degrees(math.acos(c))


def _finite_float(s: str) -> float:
    v = float(s)
    if not math.isfinite(v):
        raise ValueError(f"number {s} is out of range (not a finite float)")
    return v


def _bounded_int(s: str) -> int:
    if len(s.lstrip("-")) > 18:
        raise ValueError(f"integer {s[:20]}... is out of range")
    return int(s)


def _reject_constant(s: str):
    raise ValueError(f"{s} is not a number (JSON has no NaN/Infinity)")


def ring_points(ring) -> np.ndarray:
    """A job ring as an (N, 2) array (mm): a list of [x, y] points as given, a ``{"circle": {"center":
    [x, y], "radius": r, "tolerance": t}}`` flattened by :func:`cnclab.geometry.drawing.circle_points`
    (inscribed polygon, chord error <= t, default :data:`~cnclab.geometry.drawing.CHORD_TOL_MM` mm).

    >>> len(ring_points({"circle": {"center": [0, 0], "radius": 5}}))      # 2 arccos(1 - 0.005/5) per chord
    71
    """
    if isinstance(ring, dict):
        c = ring["circle"]
        return circle_points(c["center"], float(c["radius"]), float(c.get("tolerance", CHORD_TOL_MM)))
    return np.asarray(ring, float)


def _unknown_keys_message(obj: dict, schema: dict) -> str:
    """The unknown keys of ``obj`` (a JSON object of ``schema``), each with the key it probably meant
    (difflib) when that one is not given, and the required keys that are missing."""
    known = set(schema.get("properties", {}))
    bad = sorted(k for k in obj if k not in known and not str(k).startswith("_"))
    absent = sorted(known - set(obj))
    missing = [k for k in schema.get("required", []) if k not in obj]
    alts = [" or ".join(sorted(a.get("required", []))) for a in schema.get("oneOf", [])]
    if alts and not any(k in obj for a in schema.get("oneOf", []) for k in a.get("required", [])):
        missing.append(" / ".join(alts))
    hints = []
    for k in bad:
        close = difflib.get_close_matches(str(k), sorted(known), n=1, cutoff=0.6)
        if not close and len(str(k)) >= 3:         # an abbreviation: 'tool_dia' for 'tool_diameter'
            close = [a for a in absent if a.startswith(str(k))][:1]
        if close:
            state = "it is not given" if close[0] in absent else "it is given too"
            hints.append(f"{k!r}: did you mean {close[0]!r}? ({state})")
    msg = f"unknown key(s) {bad}" + (f" ({'; '.join(hints)})" if hints else "")
    if missing:
        msg += f"; missing required key(s): {', '.join(missing)}"
    msg += f"; allowed are {sorted(known)} and comments '_...'"
    return msg


def _ring_problem(P: np.ndarray):
    """Reason why the ring P is not a simple polygon (None if it is)."""
    if not np.all(np.isfinite(P)):
        return "coordinates must be finite"
    poly = Polygon(P)
    if not poly.is_valid:
        return f"not a simple polygon ({shapely.is_valid_reason(poly)})"
    if poly.area <= 0:
        return "the polygon has zero area"
    return None


@dataclasses.dataclass(frozen=True, eq=False)
class Job:
    """A 2.5D pocket job. Lengths mm, angles deg, feeds mm/min, v_c m/min, f_z mm/tooth, speed rpm.

    ``polygon`` (islands = holes), ``tool``, ``theta_deg``, ``a_p`` (axial depth per level),
    ``depth`` (None: a_p), ``start_hole`` (None or (x, y, diameter)), ``v_c``, ``f_z``,
    ``feed_mm_min`` (nominal cutting feed), ``spindle_rpm``, ``link_feed_mm_min``, ``rapid_mm_min``,
    ``clearance_z``, ``top_z``, ``v_fmax`` (feed-control cap), ``roll_radius`` (roll-in radius of the
    hybrid path), ``rapid_links`` (links at depth through cleared area written as G0; False: G1 at
    ``link_feed_mm_min``), ``entry_feed_mm_min`` (helix/ramp entry feed; None:
    :data:`ENTRY_FEED_FRACTION` x ``feed_mm_min``; :attr:`entry_feed` is the value, which
    :func:`cnclab.toolpath.planners.plan` gives the path's entries), ``source`` (file name for messages), ``description``, the machine and tool
    limits ``cutting_length`` (None: 3 D), ``spindle_rpm_max`` (rpm) and ``feed_max_mm_min`` (None: the
    rapid rate) that :meth:`from_dict` checks (:func:`plausibility`), and the ``warnings`` it gave.
    Build with :meth:`from_dict` / :func:`load_job` (validated).
    """

    polygon: Polygon | MultiPolygon
    tool: Tool
    theta_deg: float
    a_p: float
    depth: float | None = None
    start_hole: tuple | None = None
    v_c: float | None = None
    f_z: float | None = None
    feed_mm_min: float | None = None
    spindle_rpm: float | None = None
    link_feed_mm_min: float = LINK_FEED_MM_MIN
    rapid_mm_min: float = RAPID_MM_MIN
    clearance_z: float = 5.0
    top_z: float = 0.0
    v_fmax: float = 1000.0
    roll_radius: float = 1.0
    rapid_links: bool = True
    entry_feed_mm_min: float | None = None
    source: str = "<dict>"
    description: str = ""
    cutting_length: float | None = None
    spindle_rpm_max: float = SPINDLE_RPM_MAX
    feed_max_mm_min: float | None = None
    warnings: tuple = ()

    def __post_init__(self):
        d = self.tool.diameter
        n = self.spindle_rpm if self.spindle_rpm is not None else (
            float(spindle_speed(self.v_c, d)) if self.v_c is not None else None)
        if n is None:
            raise ValueError(f"{self.source}: $: give the spindle speed: 'v_c' (m/min) or 'spindle_rpm'")
        f = self.feed_mm_min if self.feed_mm_min is not None else (
            float(feed_speed(self.f_z, self.tool.flutes, n)) if self.f_z is not None else None)
        if f is None:
            raise ValueError(f"{self.source}: $: give the feed: 'f_z' (mm/tooth) or 'feed_mm_min'")
        object.__setattr__(self, "spindle_rpm", float(n))
        object.__setattr__(self, "feed_mm_min", float(f))
        if self.v_c is None:
            object.__setattr__(self, "v_c", float(cutting_speed(d, n)))
        if self.f_z is None:
            object.__setattr__(self, "f_z", f / (self.tool.flutes * n))
        object.__setattr__(self, "depth", float(self.a_p if self.depth is None else self.depth))
        if not self.clearance_z > self.top_z:
            raise ValueError(f"{self.source}: $.clearance_z: the clearance plane ({self.clearance_z} mm) must "
                             f"be above the stock top ({self.top_z} mm)")

    # -- derived quantities ------------------------------------------------------------------
    @property
    def tool_radius(self) -> float:
        return self.tool.radius

    @property
    def tool_diameter(self) -> float:
        return self.tool.diameter

    @property
    def teeth(self) -> int:
        return int(self.tool.flutes)

    @property
    def entry_feed(self) -> float:
        """Feed (mm/min) of the helix and ramp entries: ``entry_feed_mm_min``, else
        :data:`ENTRY_FEED_FRACTION` x ``feed_mm_min``. :func:`cnclab.toolpath.planners.plan` sets it on
        the planned path's entries (:func:`cnclab.toolpath.levels.with_entry_feed`), so the evaluator
        and the program writer see the same feeds.

        >>> j = Job(Polygon([(0, 0), (20, 0), (20, 20), (0, 20)]), Tool(6), 60, 3, feed_mm_min=300, v_c=100)
        >>> j.entry_feed, dataclasses.replace(j, entry_feed_mm_min=111.0).entry_feed
        (150.0, 111.0)
        """
        if self.entry_feed_mm_min is not None:
            return float(self.entry_feed_mm_min)
        return ENTRY_FEED_FRACTION * float(self.feed_mm_min)

    @property
    def a_e(self) -> float:
        """Radial depth of a straight cut at theta: r (1 - cos theta) (mm)."""
        return float(stepover_straight(self.theta_deg, self.tool_radius))

    def mrr_nominal(self, feed=None) -> float:
        """MRR_nom = a_p a_e v_f (mm^3/min), v_f = ``feed`` or the nominal feed."""
        return self.a_p * self.a_e * (self.feed_mm_min if feed is None else float(feed))

    def allowed(self):
        """Tool-centre region: the pocket shrunk by the tool radius (islands grown)."""
        return self.polygon.buffer(-self.tool_radius, 64)

    def start_hole_polygon(self) -> Polygon:
        """The pre-drilled hole as a polygon (empty without a start hole)."""
        if self.start_hole is None:
            return Polygon()
        x, y, dia = self.start_hole
        return Point(x, y).buffer(0.5 * dia, 256)

    @property
    def start_center(self) -> tuple:
        """Start-hole centre, else the centre of the largest inscribed circle of the pocket (mm)."""
        if self.start_hole is not None:
            return (float(self.start_hole[0]), float(self.start_hole[1]))
        c = shapely.get_coordinates(shapely.maximum_inscribed_circle(self.polygon, 0.01))[0]
        return (float(c[0]), float(c[1]))

    def levels(self) -> list[float]:
        """Cutting z of each level (mm), top down: equal steps of at most a_p down to top_z - depth.

        >>> j = Job(Polygon([(0, 0), (20, 0), (20, 20), (0, 20)]), Tool(6), 60, 3, depth=7, v_c=100, f_z=0.05)
        >>> j.levels()
        [-2.3333333333333335, -4.666666666666667, -7.0]
        """
        n = max(1, int(math.ceil(self.depth / self.a_p - 1e-9)))
        return [self.top_z - self.depth * (k + 1) / n for k in range(n)]

    def volume_mm3(self) -> float:
        """Material to remove: depth (pocket area - start-hole area) (mm^3)."""
        return self.depth * self.polygon.difference(self.start_hole_polygon()).area

    # -- construction ------------------------------------------------------------------------
    @classmethod
    def from_dict(cls, d, source: str = "<dict>") -> "Job":
        """Build and validate a job from a mapping of the JSON format (see the module docstring)."""
        if not isinstance(d, dict):
            raise ValueError(f"{source}: $: a job must be a JSON object {{...}}, got a {type(d).__name__}")
        errors = sorted(_validator().iter_errors(d), key=lambda e: (len(list(e.absolute_path)), e.json_path))
        if errors:
            e = errors[0]
            same = [x for x in errors if x.json_path == e.json_path]
            e = next((x for x in same if x.validator == "additionalProperties"), e)
            desc = e.schema.get("description") if isinstance(e.schema, dict) else None
            extra = f" (expected {desc})" if desc else ""
            if e.validator == "additionalProperties":
                msg = _unknown_keys_message(e.instance, e.schema)
            elif e.validator == "oneOf" and not e.absolute_path:
                msg = ("give exactly one of 'polygon' (a list of [x, y] points), 'star' (star_polygon keywords) "
                       "or 'regions' (a list of {polygon, islands})")
            else:
                msg = e.message
            raise ValueError(f"{source}: {e.json_path}: {msg}{extra}")

        def err(path, msg):
            return ValueError(f"{source}: {path}: {msg}")

        def region(shell_pts, rings, at):
            islands = []
            for k, ring in enumerate(rings):
                P = ring_points(ring)
                why = _ring_problem(P)
                if why:
                    raise err(f"{at}islands[{k}]", why)
                islands.append(Polygon(P))
            outer = Polygon(shell_pts)
            for k, isl in enumerate(islands):
                if not outer.contains(isl):
                    raise err(f"{at}islands[{k}]", "the island is not inside the pocket outline")
                for j in range(k):
                    if isl.intersects(islands[j]):
                        raise err(f"{at}islands[{k}]", f"the island overlaps or touches island {j}")
            poly = Polygon(shell_pts, [np.asarray(i.exterior.coords) for i in islands])
            if not poly.is_valid:
                raise err(f"{at}islands", f"pocket with islands is not valid ({shapely.is_valid_reason(poly)})")
            return poly

        if "star" in d:
            try:
                shell = star_polygon(**d["star"])
            except ValueError as exc:
                raise err("$.star", str(exc)) from None
            if shell.is_empty or not isinstance(shell, Polygon):
                raise err("$.star", "the star parameters give no single polygon")
            poly = region(shapely.get_coordinates(shell.exterior), d.get("islands", []), "$.")
        elif "regions" in d:
            if "islands" in d:
                raise err("$.islands", "with 'regions', give the islands inside each region")
            parts = []
            for k, g in enumerate(d["regions"]):
                P = ring_points(g["polygon"])
                why = _ring_problem(P)
                if why:
                    raise err(f"$.regions[{k}].polygon", why)
                parts.append(region(P, g.get("islands", []), f"$.regions[{k}]."))
                for j in range(k):
                    if parts[k].intersects(parts[j]):
                        raise err(f"$.regions[{k}]", f"the region overlaps or touches region {j}")
            poly = MultiPolygon(parts) if len(parts) > 1 else parts[0]
        else:
            shell_pts = ring_points(d["polygon"])
            why = _ring_problem(shell_pts)
            if why:
                raise err("$.polygon", why)
            poly = region(shell_pts, d.get("islands", []), "$.")
        D = float(d["tool_diameter"])
        teeth = int(d.get("teeth", 2))
        try:
            tool = Tool(D, float(d.get("corner_radius", 0.0)), teeth, int(d.get("tool_number", 1)))
        except ValueError as exc:
            raise err("$.corner_radius" if "corner" in str(exc) else "$.tool_diameter", str(exc)) from None
        r = 0.5 * D
        allowed = poly.buffer(-r, 64)
        if allowed.is_empty or allowed.area < 1e-6:
            raise err("$.polygon", f"the tool (diameter {D:g} mm) cannot enter the pocket: it is narrower than the tool")
        hole = None
        if "start_hole" in d:
            (cx, cy), hd = d["start_hole"]["center"], float(d["start_hole"]["diameter"])
            if hd < D:
                raise err("$.start_hole.diameter", f"start hole diameter {hd:g} mm is smaller than the tool "
                          f"diameter {D:g} mm: the tool cannot enter it")
            if not poly.buffer(1e-9).contains(Point(cx, cy).buffer(0.5 * hd, 256)):
                raise err("$.start_hole", f"the start hole at ({cx:g}, {cy:g}) (diameter {hd:g} mm) is not inside "
                          "the pocket (outline minus islands)")
            hole = (float(cx), float(cy), hd)
        theta = float(d["theta_deg"])
        tmin = theta_min_deg(poly, r)
        if theta < tmin:
            raise err("$.theta_deg", f"theta_deg = {theta:g} deg is below {tmin:.3g} deg: at a_e = r (1 - cos theta) "
                      f"= {float(stepover_straight(theta, r)):.3g} mm per lap, clearing the largest inscribed "
                      f"radius of this pocket needs more than {MAX_LAPS} laps (the planners' cap)")
        a_p = float(d["a_p"])
        kw = {k: float(d[k]) for k in ("v_c", "f_z", "feed_mm_min", "spindle_rpm", "rapid_mm_min", "clearance_z",
                                        "top_z", "v_fmax", "roll_radius", "depth", "cutting_length",
                                        "spindle_rpm_max", "feed_max_mm_min", "entry_feed_mm_min") if k in d}
        if "link_feed" in d:
            kw["link_feed_mm_min"] = float(d["link_feed"])
        if "rapid_links" in d:
            kw["rapid_links"] = bool(d["rapid_links"])
        try:
            job = cls(poly, tool, theta, a_p, start_hole=hole, source=str(source),
                      description=str(d.get("description", "")), **kw)
        except ValueError as exc:
            msg = str(exc)
            raise (exc if msg.startswith(str(source)) else err("$", msg)) from None
        warns = plausibility(job, given=set(d))
        return dataclasses.replace(job, warnings=tuple(warns)) if warns else job

    def to_dict(self) -> dict:
        """The JSON mapping of this job (``Job.from_dict(job.to_dict())`` gives an equal job)."""
        polys = list(self.polygon.geoms) if isinstance(self.polygon, MultiPolygon) else [self.polygon]
        ring = lambda g: shapely.get_coordinates(g)[:-1].tolist()  # noqa: E731
        p = polys[0]
        d = {"polygon": ring(p.exterior),
             "tool_diameter": self.tool.diameter, "corner_radius": self.tool.corner_radius,
             "teeth": int(self.tool.flutes), "tool_number": int(self.tool.number),
             "theta_deg": self.theta_deg, "a_p": self.a_p, "depth": self.depth, "v_c": self.v_c,
             "f_z": self.f_z, "feed_mm_min": self.feed_mm_min, "spindle_rpm": self.spindle_rpm,
             "link_feed": self.link_feed_mm_min, "rapid_mm_min": self.rapid_mm_min,
             "clearance_z": self.clearance_z, "top_z": self.top_z, "v_fmax": self.v_fmax,
             "roll_radius": self.roll_radius, "rapid_links": self.rapid_links,
             "spindle_rpm_max": self.spindle_rpm_max}
        for key in ("cutting_length", "feed_max_mm_min", "entry_feed_mm_min"):
            if getattr(self, key) is not None:
                d[key] = getattr(self, key)
        if p.interiors:
            d["islands"] = [ring(i) for i in p.interiors]
        if len(polys) > 1:
            d.pop("polygon"), d.pop("islands", None)
            d["regions"] = [{"polygon": ring(q.exterior), "islands": [ring(i) for i in q.interiors]} for q in polys]
        if self.start_hole is not None:
            d["start_hole"] = {"center": [self.start_hole[0], self.start_hole[1]], "diameter": self.start_hole[2]}
        if self.description:
            d["description"] = self.description
        return d


def _looks_like_inches(job: Job) -> str:
    """Why ``job``'s lengths look typed in inches ('' if they do not)."""
    x0, y0, x1, y1 = job.polygon.bounds
    extent = max(x1 - x0, y1 - y0)
    if job.tool_diameter < INCH_LOOK_TOOL_MM and extent < INCH_LOOK_EXTENT_MM:
        return (f"the lengths look like inches (tool_diameter {job.tool_diameter:g}, pocket {extent:g} across: "
                f"{25.4 * job.tool_diameter:g} and {25.4 * extent:g} mm if they were inches); job lengths are mm")
    return ""


def plausibility(job: Job, given=None) -> list:
    """Check that ``job``'s numbers are ones a machine can run; returns the warnings (str), raises
    ``ValueError`` naming the job key (``$.a_p``) for what cannot be run.

    Errors: the spindle speed (``spindle_rpm``, or from ``v_c``) above ``spindle_rpm_max`` (default
    :data:`SPINDLE_RPM_MAX`); the cutting feed (``feed_mm_min`` or from ``f_z``), or a given
    ``link_feed`` / ``v_fmax``, above ``feed_max_mm_min`` (default the rapid rate ``rapid_mm_min``);
    ``a_p`` above the tool's ``cutting_length`` (default :data:`CUTTING_LENGTH_PER_D` x diameter).
    Warnings: lengths that look typed in inches (tool under 1 mm, pocket within 50 mm); a pocket
    ``depth`` beyond the cutting length (the shank enters the cut). ``given``: keys of the job file
    (the default-valued keys are not checked against the limits).

    >>> job = Job(Polygon([(0, 0), (40, 0), (40, 30), (0, 30)]), Tool(8), 60, 30, v_c=120, f_z=0.04)
    >>> plausibility(job)
    Traceback (most recent call last):
    ...
    ValueError: <dict>: $.a_p: a_p = 30 mm is beyond the tool's cutting length 24 mm (3 x tool_diameter 8 mm; give 'cutting_length' for a longer flute)
    """
    given = set(given) if given is not None else {"link_feed", "v_fmax"}
    src, warns = job.source, []
    inch = _looks_like_inches(job)
    hint = f" ({inch})" if inch else ""
    flute = job.cutting_length if job.cutting_length is not None else CUTTING_LENGTH_PER_D * job.tool_diameter
    flute_txt = (f"{flute:g} mm" if job.cutting_length is not None else
                 f"{flute:g} mm ({CUTTING_LENGTH_PER_D:g} x tool_diameter {job.tool_diameter:g} mm; give "
                 "'cutting_length' for a longer flute)")
    if job.a_p > flute * (1 + 1e-9):
        raise ValueError(f"{src}: $.a_p: a_p = {job.a_p:g} mm is beyond the tool's cutting length {flute_txt}{hint}")
    if job.spindle_rpm > job.spindle_rpm_max * (1 + 1e-9):
        key = "spindle_rpm" if "spindle_rpm" in given or "v_c" not in given else "v_c"
        how = (f"v_c = {job.v_c:g} m/min on a {job.tool_diameter:g} mm tool needs {job.spindle_rpm:.0f} rpm"
               if key == "v_c" else f"spindle_rpm = {job.spindle_rpm:g}")
        raise ValueError(f"{src}: $.{key}: {how}, above the machine's spindle_rpm_max {job.spindle_rpm_max:g} rpm{hint}")
    fmax = job.feed_max_mm_min if job.feed_max_mm_min is not None else job.rapid_mm_min
    what = "feed_max_mm_min" if job.feed_max_mm_min is not None else "rapid rate rapid_mm_min"
    key = "feed_mm_min" if "feed_mm_min" in given or "f_z" not in given else "f_z"
    feeds = [(key, job.feed_mm_min)] + [(k, v) for k, v in (("link_feed", job.link_feed_mm_min),
                                                              ("v_fmax", job.v_fmax)) if k in given]
    for k, v in feeds:
        if v > fmax * (1 + 1e-9):
            how = (f"f_z = {job.f_z:g} mm/tooth x {job.teeth} teeth x {job.spindle_rpm:.0f} rpm = {v:.0f} mm/min"
                   if k == "f_z" else f"{k} = {v:g} mm/min")
            raise ValueError(f"{src}: $.{k}: {how} is above the machine's {what} {fmax:g} mm/min{hint}")
    if inch:
        warns.append(f"{src}: $.tool_diameter: {inch}")
    if job.depth > flute * (1 + 1e-9):
        warns.append(f"{src}: $.depth: depth {job.depth:g} mm is beyond the tool's cutting length {flute_txt}: "
                     "the shank would rub the pocket wall")
    return warns


def read_job_json(path) -> dict:
    """The JSON object of a job (or cutting-data) file, read strictly: UTF-8, no NaN/Infinity, finite
    numbers, bounded integers. ``ValueError`` names the file and the line and column of a syntax
    error or the byte offset of a non-UTF-8 byte; a missing file raises ``OSError``."""
    p = Path(path)
    raw = p.read_bytes()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise ValueError(f"{p}: not UTF-8 text: byte 0x{raw[e.start]:02x} at offset {e.start}") from None
    try:
        return json.loads(text, parse_float=_finite_float, parse_int=_bounded_int, parse_constant=_reject_constant)
    except json.JSONDecodeError as e:
        raise ValueError(f"{p}:{e.lineno}:{e.colno}: invalid JSON ({e.msg})") from None
    except (ValueError, RecursionError) as e:
        raise ValueError(f"{p}: invalid JSON ({e})") from None


def load_job(path) -> Job:
    """Read and validate a job JSON file (read-only; see the module docstring for the format).

    Errors (``ValueError``) name the file and the JSON path, or the line and column of a JSON
    syntax error, or the byte offset of a non-UTF-8 byte; a missing file raises ``OSError``.
    """
    return Job.from_dict(read_job_json(path), source=str(Path(path)))
