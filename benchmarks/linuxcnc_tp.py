"""``python benchmarks/linuxcnc_tp.py`` (``make tp-check``): LinuxCNC's own trajectory planner, run
headless in simulation, timing the programs of ``tests/fixtures/linuxcnc/``; writes the measured
times with their provenance to ``tests/fixtures/linuxcnc/tp_times.json`` (read by
``tests/test_machine_linuxcnc.py``, which compares :func:`cnclab.nc.machine.machine_time` with them
without LinuxCNC).

How it runs (LinuxCNC 2.9 ``linuxcnc-uspace``, no X, no real-time kernel):

* a generated configuration ``sim.ini`` (trivkins XYZ, ``LIB:basic_sim.tcl`` simulated joints, mm)
  whose ``[AXIS_*]`` and ``[JOINT_*]`` ``MAX_VELOCITY`` / ``MAX_ACCELERATION`` are the machine
  model's per-axis limits (:data:`cnclab.nc.machine.SMALL_VMC` by default), ``[TRAJ]`` limits that do
  not bind (the norm of the axis limits), ``NO_FORCE_HOMING = 1``, servo period 1 ms;
* ``DISPLAY = benchmarks/linuxcnc/driver.py`` (system ``/usr/bin/python3`` with LinuxCNC's
  ``linuxcnc`` module) instead of a GUI: it switches the machine on, runs each program in AUTO mode
  and records ``motion.current-vel`` once per servo cycle with HAL's ``sampler`` + ``halsampler``;
* ``linuxcnc`` is started with ``RUNTESTS=1`` (log to the terminal), ``RTAPI_UID=65534`` (uspace's
  ``rtapi_app`` refuses to run as root without a fallback uid) and a private ``RTAPI_FIFO_PATH``.

The time of a program is (servo cycles with ``current-vel > 0``) x (servo period): the planner
advances one cycle per servo-thread invocation whatever the wall clock does (POSIX non-real-time
threads may run late on a loaded machine; missed samples are detected by the sample counter and
refused). Each program is run as written plus one line ``G64 P<tol> Q0`` at its top: the blending
tolerance of the model (``junction_deviation_mm``), the naive-CAM collinear merge off (``Q0``) so
that LinuxCNC plans the same blocks as the model.
"""
from __future__ import annotations

import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cnclab.fileio import atomic_write  # noqa: E402
from cnclab.nc.machine import SMALL_VMC, Machine  # noqa: E402

FIX = ROOT / "tests" / "fixtures" / "linuxcnc"
DRIVER = Path(__file__).resolve().parent / "linuxcnc" / "driver.py"
#: servo period [ns] (1 ms; ``$CNCLAB_TP_SERVO_NS`` overrides it, recorded per case)
SERVO_PERIOD_NS = int(os.environ.get("CNCLAB_TP_SERVO_NS", "1000000"))

def _spiral(n: int = 4000) -> str:
    """``n`` blocks of an Archimedean spiral from r = 2 mm, 2 mm per turn, chords of ~0.1 mm, F3000."""
    out, t = [], 0.0
    for k in range(1, n + 1):          # angle step keeping the chord ~0.1 mm at the current radius
        t += 0.1 / (2.0 + t / math.pi)
        r = 2.0 + t / math.pi
        out.append(f"G1 X{r * math.cos(t):.4f} Y{r * math.sin(t):.4f}" + (" F3000" if k == 1 else "") + "\n")
    return "".join(out)


#: synthetic cases (closed-form shapes at feeds where acceleration matters): name -> program body
CASES = {
    "line": "G0 X0 Y0 Z0\nG1 X100 F6000\n",
    "corner": "G0 X0 Y0 Z0\nG1 X100 F6000\nG1 Y100\n",
    "circle": "G0 X2 Y0 Z0\nG2 X2 Y0 I-2 J0 F6000\n",            # r 2 mm: sqrt(a r) < F
    "polygon": "G0 X10 Y0 Z0\n" + "".join(
        f"G1 X{10 * math.cos(2 * math.pi * k / 360):.4f} Y{10 * math.sin(2 * math.pi * k / 360):.4f}"
        + (" F3000" if k == 1 else "") + "\n" for k in range(1, 361)),   # 360-gon r 10 mm, 0.17 mm chords
    "spiral": "G0 X2 Y0 Z0\n" + _spiral(),  # 4000 chords of ~0.1 mm
}
#: bench programs (copied into the fixtures once; the fixture files are what is timed)
BENCH = ("bench_rectangle_ours", "bench_rectangle_freecad")


def ini_text(m: Machine, tol_mm: float, driver: Path) -> str:
    """A LinuxCNC ``sim.ini`` whose axis limits are the machine model's."""
    v = [r / 60.0 for r in m.max_rate_mm_min]
    a = list(m.accel_mm_s2)
    vt, at = math.hypot(*v), math.hypot(*a)
    axes = "".join(f"[AXIS_{c}]\nMAX_VELOCITY = {v[k]:.6f}\nMAX_ACCELERATION = {a[k]:.6f}\n"
                   f"MIN_LIMIT = -10000\nMAX_LIMIT = 10000\n\n" for k, c in enumerate("XYZ"))
    joints = "".join(f"[JOINT_{k}]\nTYPE = LINEAR\nHOME_SEQUENCE = 0\nMAX_VELOCITY = {v[k]:.6f}\n"
                     f"MAX_ACCELERATION = {a[k]:.6f}\nMIN_LIMIT = -10000\nMAX_LIMIT = 10000\n\n" for k in range(3))
    extra_traj = os.environ.get("CNCLAB_TP_TRAJ", "").replace(";", "\n") + "\n" if os.environ.get("CNCLAB_TP_TRAJ") else ""
    return f"""[EMC]
VERSION = 1.1
MACHINE = cnclab-tp-check
[DISPLAY]
DISPLAY = {driver}
[TASK]
TASK = milltask
CYCLE_TIME = 0.001
[RS274NGC]
PARAMETER_FILE = sim.var
[EMCIO]
EMCIO = io
CYCLE_TIME = 0.100
TOOL_TABLE = sim.tbl
[EMCMOT]
EMCMOT = motmod
SERVO_PERIOD = {SERVO_PERIOD_NS}
COMM_TIMEOUT = 30.0
[HAL]
HALFILE = LIB:basic_sim.tcl -no_use_hal_manualtoolchange
HALFILE = cnclab.hal
[TRAJ]
COORDINATES = XYZ
LINEAR_UNITS = mm
ANGULAR_UNITS = degree
MAX_LINEAR_VELOCITY = {vt:.6f}
MAX_LINEAR_ACCELERATION = {at:.6f}
NO_FORCE_HOMING = 1
{extra_traj}[KINS]
JOINTS = 3
KINEMATICS = trivkins coordinates=XYZ
{axes}{joints}"""


HAL = """loadrt sampler depth=60000 cfg=fsb
addf sampler.0 servo-thread
net cl-vel motion.current-vel => sampler.0.pin.0
net cl-line motion.program-line => sampler.0.pin.1
net cl-inpos motion.in-position => sampler.0.pin.2
setp sampler.0.enable 0
"""


def with_g64(text: str, tol_mm: float) -> str:
    """``text`` with ``G64 P<tol> Q0`` as its first line (after a leading ``%``)."""
    lines = text.splitlines()
    k = 1 if lines and lines[0].strip() == "%" else 0
    return "\n".join(lines[:k] + [f"G64 P{tol_mm:g} Q0"] + lines[k:]) + "\n"


def last_motion_line(text: str) -> int:
    """1-based number of the last line with an X, Y or Z word (outside comments)."""
    last = 0
    for k, line in enumerate(text.splitlines(), 1):
        code = re.sub(r"\(.*?\)|;.*", "", line).upper()
        if re.search(r"[XYZ]\s*[-+.\d]", code):
            last = k
    return last


def timing(samples: Path, period_s: float, last_line: int) -> dict:
    """Motion time [s] from a ``halsampler -t`` file: cycles with current-vel > 0, the span from the
    first to the last moving cycle, and the peak speed; refuses a file with missing samples or one
    whose program stopped before ``last_line`` (an abort, e.g. a motion command timeout)."""
    n, vel, line = [], [], []
    for row in samples.read_text().split("\n"):
        f = row.split()
        if len(f) >= 3:
            n.append(int(f[0])); vel.append(float(f[1])); line.append(int(f[2]))
    if line and max(line) < last_line:
        raise RuntimeError(f"{samples}: the program stopped at line {max(line)}, before its last motion line "
                           f"{last_line} (aborted: see linuxcnc.log)")
    if not n:
        raise RuntimeError(f"{samples}: no samples")
    gaps = [b - a for a, b in zip(n, n[1:]) if b - a != 1]
    if gaps:
        raise RuntimeError(f"{samples}: {len(gaps)} gap(s) in the sample counter (sampler overrun)")
    moving = [k for k, x in enumerate(vel) if x > 0]
    if not moving:
        raise RuntimeError(f"{samples}: the machine never moved")
    return {"time_motion_s": len(moving) * period_s, "time_span_s": (moving[-1] - moving[0] + 1) * period_s,
            "peak_speed_mm_s": max(vel), "samples": len(n)}


def run(programs: dict, m: Machine = SMALL_VMC, workdir: Path | None = None) -> dict:
    """Run ``programs`` (name -> text, G64 already in it) through LinuxCNC; name -> timing."""
    if shutil.which("linuxcnc") is None:
        raise SystemExit("linuxcnc not found: apt-get install -y --no-install-recommends linuxcnc-uspace")
    tmp = Path(workdir or tempfile.mkdtemp(prefix="cnclab-tp-"))
    tmp.mkdir(parents=True, exist_ok=True)
    os.chmod(tmp, 0o777)                      # rtapi_app drops to the fallback uid (65534)
    (tmp / "sim.ini").write_text(ini_text(m, m.junction_deviation_mm, DRIVER))
    (tmp / "cnclab.hal").write_text(HAL)
    (tmp / "sim.tbl").write_text("T1 P1 D6 Z0 ;cnclab\n")
    paths = {}
    for name, text in programs.items():
        paths[name] = tmp / f"{name}.ngc"
        paths[name].write_text(text)
    env = dict(os.environ, RUNTESTS="1", RTAPI_UID="65534", RTAPI_FIFO_PATH=str(tmp / ".rtapi_fifo"),
               CNCLAB_TP_PROGRAMS=json.dumps([str(p) for p in paths.values()]),
               CNCLAB_TP_OUT=str(tmp / "driver.json"))
    env.pop("PYTHONPATH", None)
    t0 = time.time()
    log = subprocess.run(["linuxcnc", "sim.ini"], cwd=tmp, env=env, capture_output=True, text=True, timeout=3600)
    (tmp / "linuxcnc.log").write_text(log.stdout + log.stderr)
    if not (tmp / "driver.json").is_file():
        raise SystemExit(f"LinuxCNC run failed (log {tmp / 'linuxcnc.log'}):\n" + (log.stdout + log.stderr)[-3000:])
    drv = json.loads((tmp / "driver.json").read_text())
    out, failed = {}, {}
    for name, p in paths.items():
        errs = drv["programs"][str(p)]["errors"]
        try:
            if errs:
                raise RuntimeError(f"LinuxCNC reported {errs}")
            out[name] = timing(Path(str(p) + ".samples"), SERVO_PERIOD_NS * 1e-9, last_motion_line(programs[name]))
        except RuntimeError as exc:
            failed[name] = str(exc)
    print(f"LinuxCNC ran {len(programs)} programs in {time.time() - t0:.0f} s wall clock ({tmp})")
    for name, why in failed.items():
        print(f"FAILED {name}: {why} (not written to the fixture)", file=sys.stderr)
    return out, failed


def version() -> str:
    r = subprocess.run(["dpkg-query", "-W", "-f", "${Package} ${Version}", "linuxcnc-uspace"],
                       capture_output=True, text=True)
    return r.stdout.strip() or "unknown"


def main(argv) -> None:
    m = SMALL_VMC
    tol = m.junction_deviation_mm
    names = [a for a in argv if not a.startswith("-")]
    progs = {}
    for name, body in CASES.items():
        progs[name] = with_g64("G21 G90 G17 G94\n" + body + "M2\n", tol)
    for name in BENCH:
        progs[name] = (FIX / f"{name}.ngc").read_text()
    if names:
        progs = {k: v for k, v in progs.items() if k in names}
    for name, text in progs.items():
        if name in CASES:
            atomic_write(FIX / f"{name}.ngc", text)
    res, failed = run(progs, m)
    old = json.loads((FIX / "tp_times.json").read_text()) if (FIX / "tp_times.json").is_file() else {"cases": {}}
    cases = dict(old.get("cases", {}))
    stamp = time.strftime("%Y-%m-%dT%H:%MZ", time.gmtime())
    traj = os.environ.get("CNCLAB_TP_TRAJ", "")
    for name, v in res.items():
        cases[name] = dict(v, measured_utc=stamp, traj_extra=traj, servo_period_s=SERVO_PERIOD_NS * 1e-9)
    for name, why in failed.items():         # a failure never replaces a measurement; failures add up
        prev = cases.get(name, {})
        if "time_motion_s" not in prev:
            why = f"{prev['failed']}; {stamp}: {why}" if prev.get("failed") else why
            cases[name] = {"failed": why, "measured_utc": stamp, "traj_extra": traj,
                           "servo_period_s": SERVO_PERIOD_NS * 1e-9}
    doc = {"_provenance": {
        "linuxcnc": version(), "written_utc": stamp,
        "command": "python benchmarks/linuxcnc_tp.py (make tp-check): linuxcnc sim.ini with RUNTESTS=1 "
                   "RTAPI_UID=65534, DISPLAY = benchmarks/linuxcnc/driver.py, halsampler on motion.current-vel",
        "config": {"machine": m.name, "max_rate_mm_min": m.max_rate_mm_min, "accel_mm_s2": m.accel_mm_s2,
                   "g64": f"G64 P{tol:g} Q0", "servo_period_s": 1e-3, "kinematics": "trivkins XYZ",
                   "traj": "ARC_BLEND_* defaults (enabled, optimization depth 50), NO_FORCE_HOMING; per case "
                           "traj_extra: lines added to [TRAJ] from $CNCLAB_TP_TRAJ",
                   "start": "machine at X0 Y0 Z0"},
        "time_motion_s": "servo cycles with motion.current-vel > 0 times the servo period (pauses for "
                         "M-codes excluded); time_span_s: first to last moving cycle",
        "failed": "a case LinuxCNC did not run to its last motion line (see docs/linuxcnc-trajectory-check.md)"},
        "cases": cases}
    atomic_write(FIX / "tp_times.json", json.dumps(doc, indent=1) + "\n")
    for k, v in res.items():
        print(f"{k:28s} LinuxCNC {v['time_motion_s']:10.3f} s  span {v['time_span_s']:10.3f} s  peak {v['peak_speed_mm_s']:.2f} mm/s")
    if failed:
        raise SystemExit(1)


if __name__ == "__main__":
    main(sys.argv[1:])
