"""Run FreeCAD Path Adaptive (libarea ``Adaptive2d`` + FreeCAD's own G-code generation and the
``linuxcnc`` post) on a cnclab pocket job, for the comparison of issue 16.

Two halves, one file:

* imported from the project venv (:func:`job_spec`, :func:`run_freecad`): the job
  (:class:`cnclab.toolpath.job.Job`) is turned into plain polygon rings, the tool, the stepover (FreeCAD's ``StepOver`` is a % of the
  tool diameter: ``100 a_e / D`` with ``a_e = r (1 - cos theta)``), the depth ``a_p`` and the feeds;
  then FreeCAD's own Python (``/usr/bin/python3``, Debian package ``freecad``) is run on this file;
* run by FreeCAD's Python (``--worker SPEC.json OUT.ngc``): ``area.Adaptive2d`` is executed with the
  settings of a default Adaptive operation (``PathAdaptive.opSetDefaultValues``: tolerance 0.1,
  helix angle 5 deg, keep-tool-down ratio 3, finishing profile on, lift distance 0) except the
  stepover, and ``PathScripts.PathAdaptive.GenerateGCode`` -- FreeCAD's own helix entry, linking and
  depth handling -- writes the commands, which ``PathScripts.post.linuxcnc_post`` posts (headless:
  ``--no-show-editor``), preceded by the tool change and spindle start a tool controller emits.
  The plan time (``Adaptive2d.Execute`` + G-code generation) is printed as JSON.

Install FreeCAD: ``apt-get install -y --no-install-recommends freecad``.

The programs are read back by the package's G-code reader (``cnclab.nc.gcode.read_toolpath``).
"""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time

FREECAD_PYTHON = "/usr/bin/python3"
FREECAD_LIB = "/usr/lib/freecad/lib"
FREECAD_PATH_MOD = "/usr/share/freecad/Mod/Path"
CLEARANCE_Z = 5.0
SAFE_Z = 3.0


# ------------------------------------------------------------------------------------------------
# FreeCAD side (FreeCAD's Python: no numpy/shapely assumed)
# ------------------------------------------------------------------------------------------------
class _Q:
    """A FreeCAD quantity stand-in (``.Value``)."""

    def __init__(self, v):
        self.Value = float(v)


class _Op:
    def __init__(self, feed, vert_feed):
        self.commandlist = []
        # FreeCAD's Path feeds are mm/s; the post writes mm/min. GenerateGCode runs its helix and its
        # descents at vertFeed: the job's helix/ramp entry feed, as our programs run theirs
        self.vertFeed = float(vert_feed) / 60.0
        self.horizFeed = float(feed) / 60.0


class _Obj:
    """The properties of a default Adaptive operation that ``GenerateGCode`` reads."""

    def __init__(self, spec):
        self.StepDown = _Q(spec["a_p"])
        self.StartDepth = _Q(0.0)
        self.FinalDepth = _Q(-spec["depth"])
        self.ClearanceHeight = _Q(CLEARANCE_Z)
        self.SafeHeight = _Q(SAFE_Z)
        self.HelixAngle = 5.0
        self.HelixConeAngle = 0.0
        self.LiftDistance = _Q(0.0)
        self.FinishDepth = _Q(0.0)
        self.UseHelixArcs = False


class _PathObj:
    def __init__(self, label, path):
        self.Label = label
        self.Name = label
        self.Path = path


def _stub_pyside():
    """FreeCAD's Path scripts import ``PySide`` (Qt) at module level for translations and GUI cursors;
    the headless Debian install has no PySide2, so a do-nothing stand-in is registered (translation
    functions return their text; nothing of Qt is used by the computation)."""
    import types

    class _Any:
        def __init__(self, *a, **k):
            pass

        def __call__(self, *a, **k):
            return a[1] if len(a) == 2 and isinstance(a[1], str) else _Any()

        def __getattr__(self, name):
            return _Any()

    pyside = types.ModuleType("PySide")
    for sub in ("QtCore", "QtGui", "QtWidgets"):
        m = types.ModuleType("PySide." + sub)
        m.__getattr__ = lambda name: _Any()
        m.QT_TRANSLATE_NOOP = lambda ctx, txt: txt
        setattr(pyside, sub, m)
        sys.modules["PySide." + sub] = m
    sys.modules["PySide"] = pyside


def _worker(spec_path, out_path):
    try:
        sys.path.append("/usr/share/freecad/Ext")
        import PySide  # noqa: F401
    except ImportError:
        _stub_pyside()
    sys.path.append(FREECAD_LIB)
    sys.path.append(FREECAD_PATH_MOD)
    sys.path.append("/usr/share/freecad/Ext")
    import FreeCAD  # noqa: F401
    import Path
    import area
    from PathScripts import PathAdaptive
    from PathScripts.post import linuxcnc_post

    with open(spec_path, encoding="utf-8") as fh:
        spec = json.load(fh)
    geometry = [[(float(x), float(y)) for x, y in ring] for ring in spec["rings"]]
    xs = [p[0] for ring in geometry for p in ring]
    ys = [p[1] for ring in geometry for p in ring]
    m = 1.0
    stock = [[(min(xs) - m, min(ys) - m), (max(xs) + m, min(ys) - m), (max(xs) + m, max(ys) + m),
              (min(xs) - m, max(ys) + m)]]
    t0 = time.perf_counter()
    a2d = area.Adaptive2d()
    a2d.stepOverFactor = 0.01 * spec["stepover_pct"]
    a2d.toolDiameter = float(spec["tool_diameter"])
    a2d.helixRampDiameter = 0.0
    a2d.keepToolDownDistRatio = 3.0
    a2d.stockToLeave = 0.0
    a2d.tolerance = 0.1
    a2d.forceInsideOut = False
    a2d.finishingProfile = True
    a2d.opType = area.AdaptiveOperationType.ClearingInside
    results = a2d.Execute(stock, geometry, lambda paths: False)
    adaptive = [{"HelixCenterPoint": r.HelixCenterPoint, "StartPoint": r.StartPoint,
                 "AdaptivePaths": r.AdaptivePaths, "ReturnMotionType": r.ReturnMotionType} for r in results]
    op, obj = _Op(spec["feed_mm_min"], spec.get("entry_feed_mm_min", spec["feed_mm_min"])), _Obj(spec)
    op.commandlist.append(Path.Command("(Adaptive)"))
    op.commandlist.append(Path.Command("G0", {"Z": CLEARANCE_Z}))
    PathAdaptive.GenerateGCode(op, obj, adaptive, 0.0)
    t_plan = time.perf_counter() - t0
    tc = Path.Path([Path.Command("(TC: cnclab tool)"), Path.Command("M6", {"T": 1}),
                    Path.Command("M3", {"S": float(spec["spindle_rpm"])})])
    prog = linuxcnc_post.export([_PathObj("TC", tc), _PathObj("Adaptive", Path.Path(op.commandlist))], "-",
                                "--no-show-editor --no-header")
    tmp = out_path + ".tmp"
    with open(tmp, "w", encoding="utf-8") as fh:
        fh.write(prog)
    os.replace(tmp, out_path)
    print("CNCLAB_RESULT " + json.dumps({"plan_time_s": t_plan, "regions": len(results),
                                          "freecad_version": ".".join(FreeCAD.Version()[:3])}))


# ------------------------------------------------------------------------------------------------
# venv side
# ------------------------------------------------------------------------------------------------
def freecad_available() -> bool:
    """True when FreeCAD's Python can import ``FreeCAD`` and ``area``."""
    if not os.path.exists(FREECAD_PYTHON):
        return False
    code = f"import sys; sys.path.append({FREECAD_LIB!r}); import FreeCAD, area, Path"
    try:
        return subprocess.run([FREECAD_PYTHON, "-c", code], capture_output=True, timeout=120).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        return False


def job_spec(job, stepover_scale: float = 1.0) -> dict:
    """Plain settings for the worker from a :class:`cnclab.toolpath.job.Job`; ``stepover_scale``
    multiplies FreeCAD's stepover (1: the job's a_e = r (1 - cos theta); below 1: FreeCAD held to the
    engagement bounds, ``benchmarks/freecad_bounded.py``)."""
    if not 0.0 < stepover_scale <= 1.0:
        raise ValueError(f"stepover_scale must be in (0, 1], got {stepover_scale!r}")
    import shapely
    from shapely.geometry.polygon import orient

    rings = []
    for poly in shapely.get_parts(job.polygon):
        poly = orient(poly, 1.0)
        rings.append(shapely.get_coordinates(poly.exterior).tolist())
        rings.extend(shapely.get_coordinates(h).tolist() for h in poly.interiors)
    D = 2 * job.tool_radius
    a_e = job.tool_radius * (1 - math.cos(math.radians(job.theta_deg)))
    return {"rings": rings, "tool_diameter": D, "stepover_pct": 100.0 * a_e / D * stepover_scale, "stepover_scale": stepover_scale, "a_p": job.a_p,
            "depth": job.depth, "feed_mm_min": job.feed_mm_min, "entry_feed_mm_min": job.entry_feed, "spindle_rpm": job.spindle_rpm,
            "theta_deg": job.theta_deg, "source": _repo_relative(job.source)}


def _repo_relative(source: str) -> str:
    """A job file's path relative to the repository (as the provenance names it), else as given."""
    try:
        return os.path.relpath(os.path.abspath(source), os.path.dirname(os.path.dirname(os.path.abspath(__file__))))\
            if os.path.exists(source) else str(source)
    except ValueError:
        return str(source)


def run_freecad(job, out_ngc, timeout_s: float = 600.0, stepover_scale: float = 1.0) -> dict:
    """Run FreeCAD Adaptive on ``job``; write ``out_ngc``; return the worker's result (plan time s,
    FreeCAD version) plus the settings and the command. ``stepover_scale``: see :func:`job_spec`."""
    import tempfile

    spec = job_spec(job, stepover_scale)
    with tempfile.TemporaryDirectory() as tmp:
        sp = os.path.join(tmp, "spec.json")
        with open(sp, "w", encoding="utf-8") as fh:
            json.dump(spec, fh)
        cmd = [FREECAD_PYTHON, os.path.abspath(__file__), "--worker", sp, os.path.abspath(str(out_ngc))]
        t0 = time.perf_counter()
        res = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout_s)
        wall = time.perf_counter() - t0
    if res.returncode != 0:
        raise RuntimeError(f"FreeCAD worker failed on {job.source}:\n{res.stderr[-2000:]}")
    line = [ln for ln in res.stdout.splitlines() if ln.startswith("CNCLAB_RESULT ")]
    if not line:
        raise RuntimeError(f"FreeCAD worker printed no result for {job.source}:\n{res.stdout[-2000:]}")
    out = json.loads(line[-1].split(" ", 1)[1])
    out["wall_time_s"] = wall
    out["settings"] = {k: v for k, v in spec.items() if k != "rings"} | {
        "tolerance": 0.1, "helix_angle_deg": 5.0, "helix_diameter_limit": 0.0, "keep_tool_down_ratio": 3.0,
        "finishing_profile": True, "lift_distance": 0.0, "use_helix_arcs": False, "clearance_z": CLEARANCE_Z,
        "safe_z": SAFE_Z, "post": "linuxcnc_post --no-show-editor --no-header"}
    out["command"] = f"{FREECAD_PYTHON} benchmarks/freecad_adaptive.py --worker SPEC.json OUT.ngc"
    return out


if __name__ == "__main__" and len(sys.argv) == 4 and sys.argv[1] == "--worker":
    _worker(sys.argv[2], sys.argv[3])
