"""``python -m cnclab finish-path PART.stl -o PATH.apt --tool-diameter 10 --stepover 0.25 --feed-angle 0``

The drop-cutter zig-zag finishing path of Mgherony (2024), ch. 7-9, as a command: a ball end mill
(diameter D) is dropped onto the STL part along parallel passes at the feed direction ``A_f`` (deg
from +x), ``a_e`` apart, sampled every ``--step`` mm
(:func:`cnclab.toolpath.dropcutter.zigzag_finishing_path`), and written as an APT CL file of tool-tip
points (:func:`cnclab.nc.apt.cl_program`: UNITS/MM, CUTTER record, SPINDL, rapid to the clearance
plane, feed down onto the first point, zig-zag links by feed, retract, FINI). The file is the input
of ``python -m cnclab spindle PART.stl PATH.apt ...``.

Input checks as in ``spindle``: the output must differ from the STL (the input is never
overwritten), every numeric option must be finite and in its range (the message names the option),
the output is written atomically (nothing partial on error or Ctrl-C), errors exit with code 2.

>>> import tempfile, pathlib
>>> from cnclab.paths import data_path
>>> out = pathlib.Path(tempfile.mkdtemp()) / "af0.apt"
>>> main([str(data_path("mgherony2024", "sample_ch8_part.stl")), "-o", str(out), "--tool-diameter", "10",
...       "--stepover", "4", "--step", "4", "--quiet"])
0
>>> out.read_text().splitlines()[3:5]
['UNITS / MM', '$$-> CUTTER / 10.000000']
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from .. import clihelp
from ..fileio import InterruptReport
from ..geometry.mesh import read_stl
from ..toolpath.dropcutter import split_passes, zigzag_finishing_path
from .apt import cl_program, write_apt
from .gcode import MAX_COORD_MM, MAX_FEED_MM_MIN, MAX_SPINDLE_RPM

__all__ = ["finish_path", "main"]


def finish_path(stl, out, tool_diameter: float, stepover: float, feed_angle_deg: float = 0.0, step: float = 0.5,
                feed_mm_min: float = 500.0, spindle_rpm: float = 2000.0, clearance: float = 10.0,
                link: str = "feed", partno: str | None = None) -> dict:
    """Plan the drop-cutter zig-zag over the STL ``stl`` and write it to ``out`` (APT, mm).

    Parameters
    ----------
    stl : part surface STL (mm). out : the APT file to write (must differ from ``stl``).
    tool_diameter : ball diameter D (mm). stepover : distance a_e between passes (mm).
    feed_angle_deg : feed direction A_f (deg from +x). step : largest distance between CL points (mm).
    feed_mm_min, spindle_rpm : the constant feed (mm/min) and spindle speed (rpm) of the program.
    clearance : height of the clearance plane above the highest CL point (mm).
    link : 'feed' (zig-zag: passes linked at depth) or 'rapid' (lift between passes).
    partno : the PARTNO record (default: the output's stem in upper case).

    Returns a summary dict: passes, cl_points, path_mm, z_min, z_max, clearance_z, out, seconds.
    """
    t0 = time.perf_counter()
    stl, out = Path(stl), Path(out)
    if out.resolve() == stl.resolve():
        raise ValueError(f"-o {out}: the output must differ from the input STL")
    mesh = read_stl(stl)
    _check_size(mesh, stepover, step)
    path = zigzag_finishing_path(mesh, tool_diameter, stepover, feed_angle_deg, step=step, feed_mm_min=feed_mm_min)
    passes = split_passes(path)
    z = path.xyz[:, 2]
    clearance_z = float(z.max()) + clearance
    prog = cl_program(passes, feed_mm_min, spindle_rpm, tool_diameter, clearance_z=clearance_z,
                      partno=partno or out.stem.upper(), link=link)
    write_apt(out, prog, inputs=[stl])
    return {"passes": len(passes), "cl_points": len(path.xyz),
            "path_mm": float(np.linalg.norm(np.diff(path.xyz, axis=0), axis=1).sum()),
            "z_min": float(z.min()), "z_max": float(z.max()), "clearance_z": clearance_z, "out": str(out),
            "seconds": time.perf_counter() - t0}


#: largest path the command plans (CL points): beyond it a stepover or step far below the part's size
#: (a unit error, 0.0001 for 0.25) would run for hours and fill the memory
MAX_CL_POINTS = 5_000_000


def _check_size(mesh, stepover: float, step: float) -> None:
    """ValueError naming --stepover / --step when the path would exceed :data:`MAX_CL_POINTS`."""
    lo, hi = mesh.triangles.reshape(-1, 3).min(axis=0), mesh.triangles.reshape(-1, 3).max(axis=0)
    span = float(np.hypot(*(hi - lo)[:2]))            # longest pass and widest spread of passes (mm)
    need = (span / stepover + 1.0) * (span / step + 1.0)
    if need > MAX_CL_POINTS:
        raise ValueError(f"--stepover {stepover:g} mm and --step {step:g} mm would need about {need:.3g} CL points on "
                         f"this part ({span:.4g} mm across; limit {MAX_CL_POINTS:.0e}): use a larger stepover or step")


def main(argv=None) -> int:
    num = clihelp.number
    ap = clihelp.parser(
        "python -m cnclab finish-path",
        "Drop-cutter zig-zag finishing path over an STL part (Mgherony 2024, ch. 7-9): a ball end mill\n"
        "of diameter D dropped onto the part along parallel passes at the feed direction A_f, a_e apart,\n"
        "written as an APT CL file of tool-tip points (UNITS/MM, CUTTER, SPINDL, FEDRAT, feed down onto\n"
        "the part from the clearance plane). Feed it to `python -m cnclab spindle` for constant-v_c\n"
        "spindle control. The output must differ from the input; it is written atomically or not at all;\n"
        "every numeric option must be finite and in its range; errors exit with code 2.",
        examples=["python -m cnclab finish-path data/mgherony2024/sample_ch8_part.stl -o af0.apt "
                  "--tool-diameter 10 --stepover 0.25 --feed-angle 0",
                  "python -m cnclab spindle data/mgherony2024/sample_ch8_part.stl af0.apt -o af0_vc63.apt "
                  "--vc 63 --fz 0.125 --teeth 2 --ap 0.3"],
        writes=["OUT: the APT CL file (only this file)"])
    ap.add_argument("stl", help="part surface STL (ASCII or binary, mm)")
    ap.add_argument("-o", "--out", required=True, help="APT file to write (must differ from the STL)")
    ap.add_argument("--tool-diameter", type=num("--tool-diameter", 0, hi=MAX_COORD_MM), required=True, help="ball diameter D (mm)")
    ap.add_argument("--stepover", type=num("--stepover", 0), required=True, help="distance a_e between passes (mm)")
    ap.add_argument("--feed-angle", type=num("--feed-angle", -360, lo_open=False, hi=360), default=0.0,
                    help="feed direction A_f of the passes (deg from +x, -360..360)")
    ap.add_argument("--step", type=num("--step", 0), default=0.5, help="largest distance between CL points along a pass (mm)")
    ap.add_argument("--feed", type=num("--feed", 0.1, lo_open=False, hi=MAX_FEED_MM_MIN), default=500.0, help="feed v_f of the program (mm/min, 0.1 .. 1e6: FEDRAT is written with 1 decimal; Table 7-1)")
    ap.add_argument("--rpm", type=num("--rpm", 1, lo_open=False, hi=MAX_SPINDLE_RPM), default=2000.0, help="spindle speed n of the program (rpm, 1 .. 1e6: SPINDL is written in whole rpm; Table 7-1)")
    ap.add_argument("--clearance", type=num("--clearance", 0, hi=MAX_COORD_MM), default=10.0,
                    help="clearance plane height above the highest CL point (mm)")
    ap.add_argument("--link", choices=("feed", "rapid"), default="feed",
                    help="between passes: feed along the boundary (zig-zag) or lift and rapid")
    ap.add_argument("--partno", default=None, help="PARTNO record (default: the output file name in upper case)")
    ap.add_argument("--quiet", action="store_true", help="print nothing on success")
    args = ap.parse_args(argv)
    def body():
        s = finish_path(args.stl, args.out, args.tool_diameter, args.stepover, args.feed_angle, args.step,
                        args.feed, args.rpm, args.clearance, args.link, args.partno)
        if not args.quiet:
            print(f"{s['passes']} passes, {s['cl_points']} CL points, path {s['path_mm']:.0f} mm, z "
                  f"{s['z_min']:.3f} .. {s['z_max']:.3f} mm, clearance plane z {s['clearance_z']:.3f} mm; "
                  f"wrote {s['out']} ({s['seconds']:.2f} s)")

    return InterruptReport([args.out]).call(body)

if __name__ == "__main__":
    sys.exit(main())
