"""``python -m cnclab programs [-o build/gcode] [--work W]``: every NC program the collection produces.

Writes one RS274/NGC file per program to ``build/gcode/<work>/<name>.ngc``, each written to disk by
the one safe writer :func:`cnclab.nc.program.write_program` (``out=``: the static check passes first;
arcs fitted within 0.005 mm, entries at the entry feed; start block, tool change, ``S.. M3`` before the
first cut, rapids only at the clearance plane or straight up, ``M5 M30``), and a
``build/gcode/manifest.json`` with, per program, the clearance plane, stock top, rapid rate and the
path's own time (:meth:`ToolPath.time_s`) that ``make gcode-check`` compares with LinuxCNC's
``rs274``. Programs of every work and strategy:

* hoang2024 — Table 3 constant-volume zig-zag (covering) and the Table 1 loop as printed;
* kim_yang2006 — original and modified constant-MRR contour-parallel paths, constant-engagement
  clearing of the same pocket;
* jacso2021 — hybrid, contour-parallel and zig-zag on the star, rectangle and L pockets;
* mgherony2024 — the ch. 8 drop-cut zig-zag finishing path at the five feed directions (the feed
  down onto the first CL point is tagged ``cleared``: its z is the drop cutter's contact height);
* every pocket job file of ``data/`` (``data/jacso2021/*.json``, ``data/kim_yang2006/pocket_*.json``,
  ``data/pockets/*.json``): the default planner's program, ``<job>_plan_default.ngc`` in the folder
  of its work (or ``pockets``), written by the code path of ``python -m cnclab plan JOB.json``
  (:func:`cnclab.nc.cli_plan.planned_program`; the planner's own resolution in either mode).

A program whose path the writer refuses (a rapid below the clearance plane that the path does not
mark as cleared, a non-finite number) is not written; its error goes into the manifest and the
command exits with 1. Fast mode (``CNCLAB_FAST=1``) uses the coarse settings of the notebooks.
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

from .. import clihelp
from ..fileio import atomic_write
from ..nc.apt import read_apt
from ..nc.cli_plan import planned_program
from ..nc.program import program_path, write_program
from ..nc.spindle_control import to_gcode_moves as apt_to_moves
from ..paths import build_dir, data_path
from ..runtime import fast_mode, pick
from ..toolpath.job import load_job
from ..toolpath.levels import with_entry_feed
from ..toolpath.path import Tool, ToolPath
from ..toolpath.evaluate import evaluate
from ..toolpath.planners import plan
from .hoang2024 import constant_volume as cv
from .jacso2021 import thesis4_star_pocket as t4
from .kim_yang2006 import ce_comparison as kyce
from .kim_yang2006 import constant_mrr_pocket as ky
from .mgherony2024 import ch7_9

__all__ = ["PROGRAM_RECIPES", "write_programs", "main"]

#: rapid traverse rate [mm/min] stated for every written program's time (the issue's 10 m/min)
RAPID_MM_MIN = 10000.0
#: programs written last (their path is cached on disk and also computed by a notebook)
LAST = ("kim_yang2006/constant_engagement",)


def _hoang(covering):
    def make(out):
        moves, text = cv.table3_program(covering=covering, decimals=3, out=out)
        return text, {"clearance_z": 10.0, "top_z": 0.0, "path": ToolPath.from_moves(moves)}
    return make


def _ky(which):
    def make(out):
        job = ky.job()
        # the paper's passes, entered by a helix (the paper plunges; the reproduction keeps that in
        # ky.program, the program for a machine does not)
        path = ky.program_path(which, entry="helix") if which != "ce" else kyce.ce_path()
        # planned from the job outside plan(): its helix entries get the job's entry feed as plan's do
        path = with_entry_feed(path, job)
        hdr = [f"Kim and Yang 2006 pocket 120 x 85 mm: {which} path, tool D{job.tool.diameter:g} flat"]
        text = write_program(path, job, header=hdr, out=out)
        return text, {"clearance_z": job.clearance_z, "top_z": job.top_z, "path": program_path(path, job), "job": job}
    return make


def _jacso(job_file, strategy):
    def make(out):
        job = load_job(data_path("jacso2021", job_file))
        path = plan(job, strategy, resolution_mm=pick(0.05, 0.1))
        hdr = [f"Jacso 2021 section 4: {strategy} on {job_file}, tool D{job.tool.diameter:g} flat"]
        text = write_program(path, job, header=hdr, out=out)
        return text, {"clearance_z": job.clearance_z, "top_z": job.top_z, "path": program_path(path, job), "job": job}
    return make


def _planned(job_file):
    def make(out):
        text, job, path, _ = planned_program(job_file, out=out)
        return text, {"clearance_z": job.clearance_z, "top_z": job.top_z, "path": program_path(path, job), "job": job,
                      "strategy": path.info.get("strategy", "")}
    return make


def _job_files() -> dict:
    """Every pocket job file of ``data/``: ``{folder: [file, ...]}`` (folder = work id or ``pockets``)."""
    out = {}
    for folder, pattern in (("jacso2021", "*.json"), ("kim_yang2006", "pocket_*.json"), ("pockets", "*.json")):
        files = sorted(p for p in data_path(folder).glob(pattern) if _is_job_file(p))
        if files:
            out[folder] = files
    return out


def _is_job_file(p) -> bool:
    """A pocket job file (the job format's ``tool_diameter`` and a ``polygon``, ``regions`` or
    ``star``), not a parameter table (those name their fields with units: ``tool_diameter_mm``)."""
    try:
        d = json.loads(Path(p).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return isinstance(d, dict) and "tool_diameter" in d and any(k in d for k in ("polygon", "regions", "star"))


def _tag_drop_cut_descents(path: ToolPath) -> ToolPath:
    """Flag (and tag) ``cleared`` the vertical feed moves that come down onto a drop-cut CL point of a finishing
    path (the ch. 8 approach from the clearance plane). The point's z is the ball's first contact
    height over the part mesh (:func:`cnclab.toolpath.dropcutter.drop_cutter_z`, the maximum over
    every facet in reach), so the ball above it touches no facet: the descent meets no part
    material (the model has no finishing allowance above the surface). In place, returned."""
    down = np.r_[False, np.diff(path.xyz[:, 2]) < 0]
    xy_same = np.r_[False, np.all(np.abs(np.diff(path.xyz[:, :2], axis=0)) <= 1e-9, axis=1)]
    for k in np.flatnonzero(path.is_kind("plunge") & down & xy_same):
        path.tag[k] = "cleared (drop-cut contact point)" if not path.tag[k] else f"{path.tag[k]} cleared"
        path.cleared[k] = True
    return path


def _mgherony(angle):
    def make(out):
        tp = ch7_9.parameters()["table7_1"]
        moves = apt_to_moves(read_apt(ch7_9.zigzag_apt(angle)))
        path = ToolPath.from_moves(moves, tool=Tool(tp["D"], corner_radius=0.5 * tp["D"], flutes=tp["teeth"]))
        _tag_drop_cut_descents(path)
        hdr = [f"Mgherony 2024 ch. 8 drop-cut zig-zag finishing, A_f = {angle:g} deg, D{tp['D']:g} ball"]
        on_part = path.xyz[(~path.is_kind("rapid")) & (path.xyz[:, 2] < 30.0), 2]
        top = float(on_part.max())   # the part's highest CL point: the stock top of a finishing path
        text = write_program(path, clearance_z=30.0, spindle_rpm=tp["n"], top_z=top, header=hdr, out=out)
        return text, {"clearance_z": 30.0, "top_z": top, "path": program_path(path, clearance_z=30.0, spindle_rpm=tp["n"])}
    return make


PROGRAM_RECIPES = {
    "hoang2024": {"table3_constant_volume_zigzag": _hoang(True), "table1_loop_as_printed": _hoang(False)},
    "kim_yang2006": {"constant_mrr_original": _ky("original"), "constant_mrr_modified": _ky("modified"),
                     "constant_engagement": _ky("ce")},
    "jacso2021": {f"{job[:-5]}_{s}": _jacso(job, s) for job in ("star_pocket.json", "rectangle_pocket.json",
                                                                "l_pocket.json")
                  for s in ("hybrid", "contour-parallel", "zig-zag")},
    "mgherony2024": {f"ch8_zigzag_Af{a:g}": _mgherony(a) for a in ch7_9.DIRECTIONS},
    "pockets": {},
}
# the default planner's program (``python -m cnclab plan JOB.json``) of every job file of data/
for _folder, _files in _job_files().items():
    PROGRAM_RECIPES[_folder].update({f"{f.stem}_plan_default": _planned(f) for f in _files})


def write_programs(outdir=None, works=None, quiet=False) -> dict:
    """Write every program (or those of ``works``) under ``outdir`` (default ``build/gcode``);
    returns the manifest ``{work/name: {...}}`` (also written as ``manifest.json``)."""
    outdir = Path(outdir) if outdir is not None else build_dir() / "gcode"
    manifest = {"rapid_mm_min": RAPID_MM_MIN, "fast_mode": fast_mode(), "programs": {}}
    todo = [(w, n, m) for w, recipes in PROGRAM_RECIPES.items() if not (works and w not in works)
            for n, m in recipes.items()]
    # the programs whose path a notebook also computes (cached on disk) go last: `make reproduce` runs
    # that notebook beside this command, and the cache lock would otherwise hold this process idle
    todo.sort(key=lambda t: f"{t[0]}/{t[1]}" in LAST)
    for work, name, make in todo:
        key = f"{work}/{name}"
        t0 = time.perf_counter()
        f = outdir / work / f"{name}.ngc"
        try:
            text, meta = make(f)       # written by the one writer (write_program(out=...)), checked first
        except ValueError as exc:
            manifest["programs"][key] = {"error": str(exc)}
            if not quiet:
                print(f"{key}: NOT WRITTEN: {exc}", file=sys.stderr)
            continue
        path = meta.pop("path")   # the path as written (program_path: fitted arcs; entry feeds as planned)
        job = meta.pop("job", None)
        if job is not None:   # 2.5D pocket: the simulator proves entries and rapids (issue 12)
            # 0.1 mm in both modes: at 0.25 mm rows the dixel chord of a disc boundary leaves slivers of
            # up to 0.034 mm^2 (> the 0.5 h^2 air tolerance) that a G0 proven clear in exact geometry is
            # charged with (two_islands_neck; 0 at 0.2, 0.1 and 0.05 mm)
            ev = evaluate(path, job, resolution_mm=0.1)
            meta.update(sim_resolution_mm=ev.resolution_mm, sim_plunges_into_material=ev.plunges_into_material,
                        sim_rapids_into_material=ev.rapids_into_material)
        t = path.time_s(RAPID_MM_MIN)
        L = path.lengths()
        manifest["programs"][key] = {"file": str(f.relative_to(outdir)), **meta,
                                     "path_feed_mm": L["feed_mm"], "path_time_s": t["total_s"],
                                     "moves": len(path)}
        if not quiet:
            print(f"{key}: {len(path)} moves, feed {L['feed_mm']:.1f} mm, path time {t['total_s']:.1f} s "
                  f"({time.perf_counter() - t0:.1f} s to plan)")
    atomic_write(outdir / "manifest.json", json.dumps(manifest, indent=1) + "\n")
    return manifest


def main(argv=None) -> int:
    ap = clihelp.parser(
        "python -m cnclab programs",
        "Write every NC program the collection produces (every work and strategy, and the default\n"
        "planner's program of every pocket job file in data/) through the one safe program writer.\n"
        "A program the writer refuses is not written; its error goes into the manifest and the\n"
        "command exits with 1. CNCLAB_FAST=1 uses the coarse settings of the notebooks.",
        examples=["python -m cnclab programs", "python -m cnclab programs --work jacso2021 -o build/gcode"],
        writes=["OUTDIR/<work>/<name>.ngc  one RS274/NGC program each",
                "OUTDIR/manifest.json      per program: clearance plane, stock top, rapid rate, path time"])
    ap.add_argument("-o", "--outdir", default=None, help="output folder (default: build/gcode)")
    ap.add_argument("--work", action="append", default=None,
                    help="only this work, repeatable (default: every work)")
    args = ap.parse_args(argv)
    man = write_programs(args.outdir, args.work)
    bad = [k for k, v in man["programs"].items() if "error" in v]
    outdir = Path(args.outdir) if args.outdir is not None else build_dir() / "gcode"
    print(f"wrote {len(man['programs']) - len(bad)} programs under {outdir}/<work>/ and {outdir / 'manifest.json'}"
          + (f"; {len(bad)} not written (errors in the manifest)" if bad else ""))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
