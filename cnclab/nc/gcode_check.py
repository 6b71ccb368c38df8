"""``python -m cnclab.nc.gcode_check [build/gcode]`` — every written program through LinuxCNC's rs274.

For each program of ``build/gcode/manifest.json`` (written by ``python -m cnclab programs``):

1. ``rs274`` accepts it (:func:`cnclab.nc.rs274.run_rs274`);
2. feed length and feed time from rs274's canonical output agree with cnclab's reader and
   :func:`cnclab.nc.gcode.program_time` within 0.1 % (both start at the origin, as rs274 does);
3. the static safety check (:func:`cnclab.nc.program.check_program`) finds no rapid below the
   clearance plane outside marked cleared area, the spindle on before the first feed move, ``M5`` and
   ``M30``, and no vertical plunge below the stock top that is not marked cleared (the planners tag
   the plunges into area they cleared; for 2.5D pocket programs the manifest also carries the dixel
   simulator's counts of plunges and rapids into material, which must both be 0);
4. the planner's path time (:meth:`ToolPath.time_s`, in the manifest) and the written program's
   time agree within 0.5 % (the writer adds only the approach from and the retract to the
   clearance plane).

Prints one row per program and exits with 1 if any program fails 1–4 (``make gcode-check``).
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

from .gcode import parse_gcode, program_time
from .program import check_program
from .rs274 import Rs274Error, parse_canonical, run_rs274

FEED_TOL = 1e-3   # 0.1 %: the agreement target for rs274 vs cnclab's reader
TIME_TOL = 5e-3   # 0.5 %: the target for the planner's time vs the written program's


def check_all(root="build/gcode") -> tuple[list, bool]:
    """Rows (dicts) for every program under ``root`` and whether all passed."""
    root = Path(root)
    man = json.loads((root / "manifest.json").read_text(encoding="utf-8"))
    rapid = float(man["rapid_mm_min"])
    rows, ok_all = [], True
    for key, meta in man["programs"].items():
        row = {"program": key}
        if "error" in meta:
            row.update(ok=False, problem="not written: " + meta["error"])
            rows.append(row); ok_all = False
            continue
        f = root / meta["file"]
        text = f.read_text(encoding="utf-8")
        problems = []
        try:
            canon = parse_canonical(run_rs274(f), source=str(f))
        except Rs274Error as exc:
            row.update(ok=False, problem=str(exc))
            rows.append(row); ok_all = False
            continue
        t0 = program_time(parse_gcode(text, source=str(f), start=(0, 0, 0)), rapid, start=(0, 0, 0))
        t = program_time(parse_gcode(text, source=str(f)), rapid)
        d_len = t0["feed_mm"] / canon.feed_mm - 1 if canon.feed_mm else 0.0
        d_time = t0["feed_s"] / canon.feed_s - 1 if canon.feed_s else 0.0
        d_path = t["total_s"] / meta["path_time_s"] - 1 if meta["path_time_s"] else 0.0
        chk = check_program(text, clearance_z=meta["clearance_z"], top_z=meta["top_z"], source=str(f))
        if abs(d_len) > FEED_TOL:
            problems.append(f"feed length differs from rs274 by {100 * d_len:+.3f} %")
        if abs(d_time) > FEED_TOL:
            problems.append(f"feed time differs from rs274 by {100 * d_time:+.3f} %")
        if abs(d_path) > TIME_TOL:
            problems.append(f"path time differs from the program time by {100 * d_path:+.3f} %")
        problems += chk.errors[:3]
        if chk.plunges_into_material > 3:
            problems.append(f"{chk.plunges_into_material} plunges below the stock top not marked cleared")
        for k in ("sim_plunges_into_material", "sim_rapids_into_material"):
            if meta.get(k):
                problems.append(f"{k.replace('sim_', '').replace('_', ' ')}: {meta[k]} (dixel simulator)")
        if not canon.spindle_on_before_feed:
            problems.append("rs274: spindle not on before the first feed")
        row.update(ok=not problems, feed_mm=round(canon.feed_mm, 3), d_feed_pct=round(100 * d_len, 5) + 0.0,
                   feed_s=round(canon.feed_s, 3), d_time_pct=round(100 * d_time, 5) + 0.0,
                   path_vs_program_pct=round(100 * d_path, 4) + 0.0, rapids_below_clearance=chk.rapids_below_clearance,
                   plunges_below_top=chk.plunges_into_material, entries=chk.entries,
                   sim_plunges=meta.get("sim_plunges_into_material", ""), sim_rapids=meta.get("sim_rapids_into_material", ""),
                   problem="; ".join(problems))
        ok_all &= not problems
        rows.append(row)
    return rows, ok_all


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    root = argv[0] if argv else "build/gcode"
    rows, ok = check_all(root)
    cols = ["program", "ok", "feed_mm", "d_feed_pct", "feed_s", "d_time_pct", "path_vs_program_pct",
            "rapids_below_clearance", "plunges_below_top", "sim_plunges", "sim_rapids", "problem"]
    print(" | ".join(cols))
    for r in rows:
        print(" | ".join(str(r.get(c, "")) for c in cols))
    n_bad = sum(not r["ok"] for r in rows)
    print(f"\n{len(rows)} programs, {len(rows) - n_bad} pass, {n_bad} fail "
          f"(tolerances: rs274 feed length/time {100 * FEED_TOL:g} %, path time {100 * TIME_TOL:g} %)")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
