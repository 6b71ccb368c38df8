"""``python -m cnclab spindle PART.stl PATH.apt -o OUT.apt --vc 63 --fz 0.125 --teeth 2 --ap 0.3 --ae 0.25``

Constant-cutting-speed post-processing of an APT CL file against an STL surface (Mgherony 2024,
Sec. 7.2.3): inserts SPINDL/FEDRAT records; optional RS274/NGC export with ``--gcode OUT.ngc``.
Inputs are never overwritten and outputs must differ from the inputs and from each other; all
outputs are written together at the end or none (also on Ctrl-C / SIGTERM: no temporary file is
left). An interrupt at any moment says what is on disk: "nothing written" (exit 130 for SIGINT,
143 for SIGTERM) or, when it comes after the outputs were committed, that they are complete (exit
0); the renames of the outputs are never cut in the middle
(:func:`cnclab.fileio.deferred_signals`). Every numeric option must be finite and in its range. Errors: exit code 2 with a message on
its own line naming the option or the file and line.
"""
from __future__ import annotations

import sys
import warnings

from .. import clihelp
from ..fileio import InterruptReport
from ..cutting.spindle_model import POINT_RULES
from .spindle_control import SpindleOptions, postprocess_files


def main(argv=None) -> int:
    ap = clihelp.parser(
        "python -m cnclab spindle",
        "Constant-cutting-speed control of a ball-end finishing path (Mgherony 2024, Sec. 7.2.3): for\n"
        "every CL point of an APT file the working diameter on the STL part gives the spindle speed\n"
        "that holds v_c, and the feed that holds f_z; SPINDL/FEDRAT records are inserted where they\n"
        "change by more than the thresholds. Inputs are never overwritten; outputs must differ from\n"
        "the inputs and from each other and are written together at the end or not at all (also on\n"
        "Ctrl-C). Every numeric option must be finite and in its range. Errors: exit code 2 with a\n"
        "message naming the option, or the file and line.",
        examples=["python -m cnclab spindle data/mgherony2024/sample_ch8_part.stl "
                  "data/mgherony2024/sample_ch8_zigzag_Af0.apt -o out.apt --vc 63 --fz 0.125 --teeth 2 --ap 0.3",
                  "python -m cnclab spindle part.stl path.apt -o out.apt --gcode out.ngc --vc 63 --fz 0.125 "
                  "--teeth 2 --ap 0.3 --nmax 6000 --vfmax 1200"],
        writes=["OUT: the APT file with SPINDL/FEDRAT records",
                "GCODE: the same program as RS274/NGC G-code (only with --gcode)"])
    ap.add_argument("stl", help="part surface STL (ASCII or binary, mm)")
    ap.add_argument("apt", help="APT CL file of a ball-end path (UNITS/MM)")
    ap.add_argument("-o", "--out", required=True, help="output APT file (must differ from the inputs)")
    ap.add_argument("--vc", type=clihelp.number("--vc", 0), required=True, help="cutting speed v_c to hold (m/min)")
    ap.add_argument("--fz", type=clihelp.number("--fz", 0), required=True, help="feed per tooth f_z (mm)")
    ap.add_argument("--teeth", type=clihelp.number("--teeth", 1, lo_open=False, kind=int), required=True,
                    help="number of teeth z (integer >= 1)")
    ap.add_argument("--ap", type=clihelp.number("--ap", 0), required=True, help="depth of cut a_p (mm, <= D/2)")
    ap.add_argument("--ae", type=clihelp.number("--ae", 0), default=None, help="width of cut a_e (mm; reported only; default: not reported)")
    ap.add_argument("--tool-diameter", type=clihelp.number("--tool-diameter", 0), default=None,
                    help="ball diameter D (mm; default: from the CUTTER record of the APT)")
    ap.add_argument("--feed-direction", type=clihelp.number("--feed-direction"), default=None,
                    help="constant feed direction A_f (deg; default: from the path, eq. 7-3)")
    ap.add_argument("--point", choices=POINT_RULES, default="max", help="contact point rule")
    ap.add_argument("--facet", choices=("centroid", "nearest"), default="centroid",
                    help="facet of a CL point: nearest centroid (the thesis) or the true nearest facet")
    ap.add_argument("--nmax", type=clihelp.number("--nmax", 0), default=None, help="spindle speed limit (rpm; default: no limit)")
    ap.add_argument("--vfmax", type=clihelp.number("--vfmax", 0), default=None, help="feed limit (mm/min; default: no limit)")
    ap.add_argument("--accel", type=clihelp.number("--accel", 0), default=None, help="spindle acceleration limit (rpm/s; default: no limit)")
    ap.add_argument("--rpm-threshold", type=clihelp.number("--rpm-threshold", 0, lo_open=False), default=50.0,
                    help="insert SPINDL when the speed changes by more than this (rpm, >= 0)")
    ap.add_argument("--vf-threshold", type=clihelp.number("--vf-threshold", 0, lo_open=False), default=10.0,
                    help="insert FEDRAT when the feed changes by more than this (mm/min, >= 0)")
    ap.add_argument("--gcode", default=None, help="also write RS274/NGC G-code to this file (differs from -o and the inputs; default: none)")
    ap.add_argument("--mismatch-tol", type=clihelp.number("--mismatch-tol", 0), default=1.0,
                    help="part/path check: a feed CL point is off the part if its ball is farther than this "
                         "from the surface (mm)")
    ap.add_argument("--max-off-share", type=clihelp.number("--max-off-share", 0, lo_open=False, hi=1), default=0.2,
                    help="part/path check: largest accepted share of off-part feed points (0..1)")
    ap.add_argument("--allow-mismatch", action="store_true",
                    help="process even when the part/path check fails (the share is still reported)")
    args = ap.parse_args(argv)
    if args.ae is not None and args.tool_diameter is not None and args.ae > args.tool_diameter:
        ap.error(f"--ae must be <= the tool diameter ({args.tool_diameter:g} mm), got {args.ae:g}")
    run = InterruptReport([args.out, args.gcode])

    def body():
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            run.check()
            opts = SpindleOptions(v_c=args.vc, f_z=args.fz, teeth=args.teeth, a_p=args.ap,
                                  tool_diameter=args.tool_diameter, feed_direction_deg=args.feed_direction,
                                  point=args.point, facet_rule=args.facet, n_max=args.nmax, vf_max=args.vfmax,
                                  accel_rpm_s=args.accel, rpm_threshold=args.rpm_threshold,
                                  vf_threshold=args.vf_threshold, mismatch_tol=args.mismatch_tol,
                                  max_off_share=args.max_off_share, allow_mismatch=args.allow_mismatch)
            s = postprocess_files(args.stl, args.apt, args.out, opts, gcode_path=args.gcode, progress=True)
            run.check()
            for w in caught:
                print(f"warning: {w.message}", file=sys.stderr)
            _print_summary(s, args)

    return run.call(body, message=lambda exc: f"\nerror: {exc}")     # after the progress line


def _print_summary(s: dict, args) -> None:
    print(f"{s['cl_points']} CL points ({s['feed_points']} feed) vs {s['facets']} facets, D = {s['tool_diameter']} mm"
          + (f", a_e = {args.ae} mm" if args.ae else ""))
    print(f"part/path check: {100 * s['off_surface_share']:.1f} % of feed points more than {args.mismatch_tol:g} mm "
          f"from the surface (median gap {s['median_gap_mm']:.3g} mm)"
          + (f"; {s['reoriented_facets']} STL facets re-oriented" if s["reoriented_facets"] else ""))
    print(f"n   {s['n_min']:.0f} .. {s['n_max']:.0f} rpm   v_f {s['vf_min']:.0f} .. {s['vf_max']:.0f} mm/min   "
          f"D_eff {s['d_eff_min']:.3f} .. {s['d_eff_max']:.3f} mm")
    print(f"limited points: {s['limited_points']}   v_c within ±5 %: {100 * s['vc_within_5pct_share']:.1f} % of path")
    wrote = f"{s['out']}" + (f" and {args.gcode}" if args.gcode else "")
    print(f"inserted SPINDL {s['spindl_inserted']}, FEDRAT {s['fedrat_inserted']}; wrote {wrote} "
          f"({s['seconds']:.2f} s)")

if __name__ == "__main__":
    sys.exit(main())
