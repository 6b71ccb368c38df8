"""The job file reference (``docs/job-format.md``), generated from :data:`cnclab.toolpath.job.JOB_SCHEMA`.

:func:`job_format_markdown` walks the JSON schema (every key, nested keys as ``start_hole.center``,
``regions[].polygon``), writing for each its type and limits (from ``minimum``/``maximum``/...),
its unit (from the schema description), its default and its meaning. Defaults come from the schema
(``"default"``, or ``(default X)`` in the description), otherwise from the job the loader builds
from a minimal file (so the table shows what :func:`~cnclab.toolpath.job.load_job` really uses).
Each feature has an example (a whole job file), validated by :meth:`Job.from_dict` while the text
is generated: an example the loader refuses is an error, so the reference cannot show a broken job.
``tests/test_job_format.py`` checks that ``docs/job-format.md`` equals the generated text.

``python -m cnclab job --schema`` prints the reference; ``--json-schema`` the JSON schema itself;
``--check JOB.json`` validates a job file and prints what the loader understood.

>>> text = job_format_markdown()
>>> "| `tool_diameter` |" in text and "## Examples" in text
True
"""
from __future__ import annotations

import inspect
import json
import re
import sys

from .. import clihelp
from .job import JOB_SCHEMA, Job, load_job, star_polygon

__all__ = ["EXAMPLES", "job_format_markdown", "main"]

#: feature -> (explanation, job file). Every one must load (checked when the text is generated).
EXAMPLES = {
    "A rectangle (the minimum)": (
        "Outline, tool, engagement, depth per level and the cutting data; everything else has its default.",
        {"polygon": [[0, 0], [40, 0], [40, 30], [0, 30]], "tool_diameter": 6, "theta_deg": 60, "a_p": 3,
         "v_c": 120, "f_z": 0.04}),
    "Islands": (
        "Material to leave standing inside the pocket: each island is a ring inside the outline; islands "
        "must not touch each other.",
        {"polygon": [[0, 0], [60, 0], [60, 40], [0, 40]],
         "islands": [[[15, 15], [25, 15], [25, 25], [15, 25]], [[38, 12], [48, 12], [43, 28]]],
         "tool_diameter": 6, "teeth": 2, "theta_deg": 60, "a_p": 3, "v_c": 120, "f_z": 0.04}),
    "Circle rings": (
        "Any ring (outline or island) may be a circle: `{\"circle\": {\"center\": [x, y], \"radius\": r}}` "
        "(mm), flattened to chords within `tolerance`.",
        {"polygon": {"circle": {"center": [0, 0], "radius": 30}},
         "islands": [{"circle": {"center": [0, 0], "radius": 8}}],
         "tool_diameter": 8, "teeth": 3, "theta_deg": 50, "a_p": 4, "v_c": 150, "f_z": 0.05}),
    "Depth levels": (
        "A pocket deeper than `a_p` is cut in equal levels of at most `a_p`, top down from `top_z`.",
        {"polygon": [[0, 0], [40, 0], [40, 30], [0, 30]], "tool_diameter": 6, "theta_deg": 60, "a_p": 3,
         "depth": 7, "top_z": 0, "clearance_z": 5, "v_c": 120, "f_z": 0.04}),
    "Start hole": (
        "A pre-drilled hole the tool can plunge into (at least the tool diameter, inside the pocket).",
        {"polygon": [[0, 0], [40, 0], [40, 24], [0, 24]], "start_hole": {"center": [20, 12], "diameter": 11},
         "tool_diameter": 6, "teeth": 1, "theta_deg": 60, "a_p": 3, "v_c": 120, "f_z": 0.04,
         "feed_mm_min": 255}),
    "Several regions": (
        "Disjoint pockets machined by one job with one tool: `regions`, each with its own outline and "
        "islands (then no top-level `polygon` or `islands`).",
        {"regions": [{"polygon": [[0, 0], [30, 0], [30, 20], [0, 20]]},
                     {"polygon": [[40, 0], [70, 0], [70, 20], [40, 20]],
                      "islands": [[[52, 7], [58, 7], [58, 13], [52, 13]]]}],
         "tool_diameter": 6, "theta_deg": 60, "a_p": 3, "v_c": 120, "f_z": 0.04}),
    "Star pocket and spindle speed / feed given directly": (
        "The rounded star of Jacsó (2021) by its keywords; `spindle_rpm` and `feed_mm_min` instead of "
        "`v_c` and `f_z`; comments in keys starting with `_`.",
        {"star": {"n_arms": 5, "outer_radius": 24.2856, "inner_ratio": 0.5, "tip_radius": 4, "root_radius": 4},
         "tool_diameter": 6, "teeth": 1, "theta_deg": 60, "a_p": 3, "spindle_rpm": 6366, "feed_mm_min": 255,
         "_comment": "keys starting with _ are ignored"}),
}

#: keys whose default is computed from other keys (the loader's rule, in words)
_DERIVED = {"depth": "a_p (one level)", "v_c": "from spindle_rpm", "spindle_rpm": "from v_c",
            "f_z": "from feed_mm_min", "feed_mm_min": "f_z x teeth x spindle_rpm"}
#: meaning of keys the schema leaves without a description
_NOTES = {"description": "free text about the job", "source": "where the job comes from (free text)",
          "units": "the only unit accepted (optional)", "star.n_arms": "number of arms",
          "star.outer_radius": "centre-to-tip radius", "star.inner_ratio": "root radius / outer radius",
          "star.tip_radius": "rounding radius of the tips (the pocket's concave corners)",
          "star.root_radius": "rounding radius of the roots", "star.center": "centre of the star",
          "star.rotation_deg": "direction of the first tip from +x", "star.quad_segs":
          "segments per quarter circle of the roundings"}
_MINIMAL = EXAMPLES["A rectangle (the minimum)"][1]
_UNIT_RE = re.compile(r"\b(m/min|mm/min|rpm/s|rpm|deg|mm)\b")
_DEFAULT_RE = re.compile(r"\(default:? ([^;)]+(?:\([^)]*\))?[^;)]*)[;)]")


def _limits(s: dict) -> list[str]:
    out = []
    for key, op in (("minimum", ">="), ("exclusiveMinimum", ">"), ("maximum", "<="), ("exclusiveMaximum", "<")):
        if key in s:
            out.append(f"{op} {s[key]:g}")
    if "minItems" in s and s.get("minItems") == s.get("maxItems"):
        out.append(f"exactly {s['minItems']} items")
    else:
        if "minItems" in s:
            out.append(f">= {s['minItems']} items")
        if "maxItems" in s:
            out.append(f"<= {s['maxItems']} items")
    return out


def _alternatives(s: dict) -> list[dict]:
    for key in ("oneOf", "anyOf"):
        if key in s:
            return list(s[key])
    if "then" in s or "else" in s:
        return [x for x in (s.get("else"), s.get("then")) if x is not None]
    return []


def _type(s: dict) -> str:
    """Short type text with limits, e.g. 'number > 0, <= 1e+09', 'list of [x, y] points'."""
    if "const" in s:
        return f"`{json.dumps(s['const'])}`"
    if "enum" in s:
        return "one of " + ", ".join(f"`{json.dumps(v)}`" for v in s["enum"])
    alts = _alternatives(s)
    if alts:
        return " or ".join(_type(a) for a in alts)
    t = s.get("type", "any")
    if t == "array":
        items = s.get("items", {})
        if _is_point(s):
            return "[x, y]"
        base = "list of " + ("[x, y] points" if _is_point(items) else (f"({_type(items)})" if items.get("type") == "array" or _alternatives(items) else _type(items)))
    elif t == "object" and s.get("properties"):
        base = "{" + ", ".join(s["properties"]) + "}"
    else:
        base = {"number": "number", "integer": "integer", "boolean": "true/false", "string": "text",
                "object": "object"}.get(t, str(t))
    lim = _limits(s)
    return base + (" (" + ", ".join(lim) + ")" if lim else "")


def _is_point(s: dict) -> bool:
    return s.get("type") == "array" and s.get("items", {}).get("type") == "number" and s.get("maxItems") == 2


def _unit(s: dict) -> str:
    m = _UNIT_RE.search(s.get("description", ""))
    return m.group(1) if m else ""


def _loader_defaults() -> dict:
    """Key -> value the loader uses when the key is absent (from the minimal job's to_dict)."""
    d = Job.from_dict(_MINIMAL).to_dict()
    return {k: v for k, v in d.items() if k not in _MINIMAL and k not in _DERIVED}


def _default(key: str, s: dict, loaded: dict) -> str:
    if key.startswith("star."):
        v = inspect.signature(star_polygon).parameters[key[5:]].default
        return f"`{json.dumps(list(v) if isinstance(v, tuple) else v)}`"
    if "default" in s:
        return f"`{json.dumps(s['default'])}`"
    m = _DEFAULT_RE.search(s.get("description", ""))
    if m:
        return m.group(1).strip()
    if key in _DERIVED:
        return _DERIVED[key]
    if "." in key or "[" in key:
        return ""
    if key in loaded:
        return f"`{json.dumps(loaded[key])}`"
    return ""


def _rows(props: dict, required, prefix: str, loaded: dict, seen: set) -> list[str]:
    rows = []
    for key, s in props.items():
        name = prefix + key
        req = "yes" if key in required else ""
        desc = s.get("description", "")
        meaning = _NOTES.get(name, desc if _unit(s) != desc else "")
        cells = [f"`{name}`", _type(s), _unit(s), req, _default(name, s, loaded), meaning]
        rows.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
        for sub, sub_prefix in _nested(s, name):
            if id(sub) in seen:
                continue
            seen.add(id(sub))
            rows += _rows(sub["properties"], sub.get("required", []), sub_prefix, loaded, seen)
    return rows


def _nested(s: dict, name: str):
    """(object schema with properties, key prefix) found under ``s``."""
    if s.get("type") == "object" and s.get("properties"):
        yield s, name + "."
    items = s.get("items")
    if isinstance(items, dict):
        for sub, pre in _nested(items, name + "[]"):
            yield sub, pre
    for alt in _alternatives(s):
        for sub, pre in _nested(alt, name):
            yield sub, pre


def _example(title: str, why: str, job: dict) -> list[str]:
    parsed = Job.from_dict(json.loads(json.dumps(job)), source=f"example {title!r}")
    text = "{" + ",\n ".join(f"{json.dumps(k)}: {json.dumps(v)}" for k, v in job.items()) + "}"
    lines = [f"### {title}", "", why, "", "```json", text, "```", ""]
    levels = ", ".join(f"{z:g}" for z in parsed.levels())
    lines += [f"Loaded: {len(getattr(parsed.polygon, 'geoms', [parsed.polygon]))} region(s), area "
              f"{parsed.polygon.area:.1f} mm², levels z = {levels} mm, spindle {parsed.spindle_rpm:.0f} rpm, "
              f"feed {parsed.feed_mm_min:.0f} mm/min.", ""]
    return lines


def job_format_markdown() -> str:
    """The job file reference as markdown (the text of ``docs/job-format.md``)."""
    loaded = _loader_defaults()
    one_of = [sorted(a.get("required", [])) for a in JOB_SCHEMA.get("oneOf", [])]
    lines = [
        "# Job file reference",
        "",
        "<!-- generated by `python -m cnclab job --schema > docs/job-format.md` from JOB_SCHEMA in "
        "cnclab/toolpath/job.py; tests/test_job_format.py checks that this file is up to date -->",
        "",
        "A job file is a JSON object describing one 2.5D pocket, the flat end mill and the cutting data; "
        "`python -m cnclab plan JOB.json -o PROGRAM.ngc` plans it and `python -m cnclab analyze` scores "
        "a program on it. Lengths are mm, angles deg, cutting speed m/min, feeds mm/min, spindle speed rpm. "
        "`python -m cnclab job --check JOB.json` validates a file and prints what was understood; every "
        "error names the file and the JSON path (`$.start_hole.diameter`).",
        "",
        "Required: " + ", ".join(f"`{k}`" for k in JOB_SCHEMA.get("required", []))
        + ("; and exactly one of " + ", ".join("`" + "`+`".join(r) + "`" for r in one_of) if one_of else "")
        + ". The spindle speed needs `v_c` or `spindle_rpm`, the feed `f_z` or `feed_mm_min`. "
        "Keys starting with `_` are comments; any other unknown key is an error.",
        "",
        "## Keys",
        "",
        "| key | type and limits | unit | required | default | meaning |",
        "|---|---|---|---|---|---|",
    ]
    lines += _rows(JOB_SCHEMA["properties"], JOB_SCHEMA.get("required", []), "", loaded, set())
    lines += ["", "## Examples", ""]
    circles = '"circle"' in json.dumps(JOB_SCHEMA)      # circle rings arrive with the drawing input
    for title, (why, job) in EXAMPLES.items():
        if circles or "circle" not in json.dumps(job):
            lines += _example(title, why, job)
    return "\n".join(lines).rstrip("\n") + "\n"


def main(argv=None) -> int:
    ap = clihelp.parser(
        "python -m cnclab job",
        "The job file format: print its reference (every key, unit, default, limits and an example\n"
        "per feature), print the JSON schema, or check a job file and print what the loader understood.",
        examples=["python -m cnclab job --schema > docs/job-format.md",
                  "python -m cnclab job --check data/jacso2021/star_pocket.json"],
        writes=["nothing (prints to standard output)"])
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--schema", action="store_true", help="print the job file reference (markdown)")
    g.add_argument("--json-schema", action="store_true", help="print the JSON schema of a job file")
    g.add_argument("--check", metavar="JOB", help="validate this job file (JSON, mm)")
    args = ap.parse_args(argv)
    if args.schema:
        sys.stdout.write(job_format_markdown())
    elif args.json_schema:
        print(json.dumps(JOB_SCHEMA, indent=1))
    else:
        try:
            job = load_job(args.check)
        except (ValueError, OSError) as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        levels = ", ".join(f"{z:g}" for z in job.levels())
        print(f"{args.check}: ok: area {job.polygon.area:.1f} mm², tool D{job.tool_diameter:g} mm "
              f"({job.teeth} teeth), theta {job.theta_deg:g} deg (a_e {job.a_e:.3f} mm), levels z = {levels} mm, "
              f"spindle {job.spindle_rpm:.0f} rpm, feed {job.feed_mm_min:.0f} mm/min")
    return 0
