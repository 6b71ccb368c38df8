"""``python -m cnclab spindle PART.stl PATH.apt -o OUT.apt --vc 63 --fz 0.125 --teeth 2 --ap 0.3 --ae 0.25``

Constant-cutting-speed post-processing of an APT CL file against an STL surface (Mgherony 2024,
Sec. 7.2.3): inserts SPINDL/FEDRAT records; optional RS274/NGC export with ``--gcode OUT.ngc``.
Inputs are never overwritten; nothing is written on error (exit code 2 with a message naming the
file and line).
"""
from __future__ import annotations

import argparse
import sys

from ..cutting.spindle_model import POINT_RULES
from .spindle_control import postprocess_files


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m cnclab spindle", description=__doc__.split("\n\n")[1])
    ap.add_argument("stl", help="surface STL (ASCII or binary, mm)")
    ap.add_argument("apt", help="APT CL file (UNITS/MM)")
    ap.add_argument("-o", "--out", required=True, help="output APT file (must differ from the inputs)")
    ap.add_argument("--vc", type=float, required=True, help="nominal cutting speed v_c (m/min)")
    ap.add_argument("--fz", type=float, required=True, help="feed per tooth f_z (mm)")
    ap.add_argument("--teeth", type=int, required=True, help="number of teeth z")
    ap.add_argument("--ap", type=float, required=True, help="depth of cut a_p (mm)")
    ap.add_argument("--ae", type=float, default=None, help="width of cut a_e (mm; reported only)")
    ap.add_argument("--tool-diameter", type=float, default=None, help="D (mm); default from CUTTER in the APT")
    ap.add_argument("--feed-direction", type=float, default=None, help="constant A_f (deg); default eq 7-3")
    ap.add_argument("--point", choices=POINT_RULES, default="max", help="tangent point rule (default max)")
    ap.add_argument("--facet", choices=("centroid", "nearest"), default="centroid",
                    help="facet assignment: nearest centroid (thesis) or true nearest facet")
    ap.add_argument("--nmax", type=float, default=None, help="spindle limit (rpm)")
    ap.add_argument("--vfmax", type=float, default=None, help="feed limit (mm/min)")
    ap.add_argument("--accel", type=float, default=None, help="spindle acceleration limit (rpm/s)")
    ap.add_argument("--rpm-threshold", type=float, default=50.0, help="insert SPINDL when n changes more (rpm)")
    ap.add_argument("--vf-threshold", type=float, default=10.0, help="insert FEDRAT when v_f changes more (mm/min)")
    ap.add_argument("--gcode", default=None, help="also write RS274/NGC G-code here")
    args = ap.parse_args(argv)
    try:
        s = postprocess_files(args.stl, args.apt, args.out, v_c=args.vc, f_z=args.fz, teeth=args.teeth,
                              a_p=args.ap, tool_diameter=args.tool_diameter, gcode_path=args.gcode,
                              rpm_threshold=args.rpm_threshold, vf_threshold=args.vf_threshold,
                              progress=True, feed_direction_deg=args.feed_direction, point=args.point,
                              facet_rule=args.facet, n_max=args.nmax, vf_max=args.vfmax,
                              accel_rpm_s=args.accel)
    except (ValueError, FileNotFoundError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"{s['cl_points']} CL points ({s['feed_points']} feed) vs {s['facets']} facets, D = {s['tool_diameter']} mm"
          + (f", a_e = {args.ae} mm" if args.ae else ""))
    print(f"n   {s['n_min']:.0f} .. {s['n_max']:.0f} rpm   v_f {s['vf_min']:.0f} .. {s['vf_max']:.0f} mm/min   "
          f"D_eff {s['d_eff_min']:.3f} .. {s['d_eff_max']:.3f} mm")
    print(f"limited points: {s['limited_points']}   v_c within ±5 %: {100 * s['vc_within_5pct_share']:.1f} % of path")
    print(f"inserted SPINDL {s['spindl_inserted']}, FEDRAT {s['fedrat_inserted']}   -> {s['out']}   "
          f"({s['seconds']:.2f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
