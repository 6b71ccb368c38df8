#!/usr/bin/python3
"""LinuxCNC DISPLAY program (runs under the system Python that has LinuxCNC's ``linuxcnc`` module):
switches the simulated machine on, runs every program of ``$CNCLAB_TP_PROGRAMS`` (JSON list of
paths) in AUTO mode and records, through ``halsampler``, one sample per servo cycle of
``motion.current-vel`` (the trajectory planner's speed), ``motion.program-line`` and
``motion.in-position`` while the program runs. Writes ``<program>.samples`` beside each program and
``$CNCLAB_TP_OUT`` (JSON: per program the interpreter errors seen, if any). Started by
``benchmarks/linuxcnc_tp.py`` through ``linuxcnc sim.ini``; not a module of the package.
"""
import json
import os
import subprocess
import sys
import time

import linuxcnc

STAT, CMD, ERR = linuxcnc.stat(), linuxcnc.command(), linuxcnc.error_channel()
#: status poll interval [s] (a GUI polls at ~10-20 Hz)
POLL_S = float(os.environ.get("CNCLAB_TP_POLL_S", "0.1"))


def wait(pred, timeout_s, what, stall_s=30.0):
    """Poll until ``pred()``; refuse a timeout and a stall (motion queued, the position unchanged
    for ``stall_s`` s of wall clock)."""
    t0 = t_moved = time.time()
    last = None
    while time.time() - t0 < timeout_s:
        STAT.poll()
        if pred():
            return
        pos = tuple(round(x, 6) for x in STAT.position[:3])
        if pos != last or STAT.queue == 0:
            t_moved, last = time.time(), pos
        elif time.time() - t_moved > stall_s:
            raise RuntimeError(f"motion stalled at line {STAT.motion_line} ({STAT.queue} segments queued, "
                               f"no motion for {stall_s} s) waiting for {what}")
        time.sleep(POLL_S)
    raise RuntimeError(f"timeout ({timeout_s} s) waiting for {what}")


def errors():
    out = []
    while True:
        e = ERR.poll()
        if not e:
            return out
        out.append(str(e[1]))


def to_origin():
    """Rapid to X0 Y0 Z0 in MDI (each program starts there, as the model assumes), back to AUTO."""
    CMD.mode(linuxcnc.MODE_MDI)
    CMD.wait_complete()
    CMD.mdi("G90 G0 X0 Y0 Z0")
    CMD.wait_complete()
    wait(lambda: STAT.interp_state == linuxcnc.INTERP_IDLE and STAT.queue == 0 and STAT.inpos, 60, "X0 Y0 Z0")
    CMD.mode(linuxcnc.MODE_AUTO)
    CMD.wait_complete()


def run(prog, timeout_s):
    to_origin()
    with open(prog + ".samples", "w") as f:
        hs = subprocess.Popen(["halsampler", "-t"], stdout=f)
        try:
            time.sleep(0.3)
            subprocess.run(["halcmd", "setp", "sampler.0.enable", "1"], check=True)
            CMD.program_open(prog)
            CMD.wait_complete()
            CMD.auto(linuxcnc.AUTO_RUN, 0)
            wait(lambda: STAT.interp_state != linuxcnc.INTERP_IDLE or STAT.current_vel > 0, 120,
                 "the program to start")
            wait(lambda: STAT.interp_state == linuxcnc.INTERP_IDLE and STAT.queue == 0 and STAT.inpos,
                 timeout_s, "the program to end")
            time.sleep(0.1)
        finally:
            subprocess.run(["halcmd", "setp", "sampler.0.enable", "0"], check=False)
            time.sleep(0.5)
            hs.terminate()
            hs.wait()
    return errors()


def main():
    progs = json.loads(os.environ["CNCLAB_TP_PROGRAMS"])
    timeout_s = float(os.environ.get("CNCLAB_TP_TIMEOUT_S", "900"))
    CMD.state(linuxcnc.STATE_ESTOP_RESET)
    CMD.wait_complete()
    CMD.state(linuxcnc.STATE_ON)
    CMD.wait_complete()
    out = {"startup_errors": errors(), "programs": {}}
    for prog in progs:
        try:
            out["programs"][prog] = {"errors": run(prog, timeout_s)}
        except RuntimeError as exc:        # a stall or a timeout: recorded, the other programs still run
            CMD.abort()
            CMD.wait_complete()
            out["programs"][prog] = {"errors": [f"driver: {exc}"]}
        print("cnclab-tp: ran", prog, out["programs"][prog], flush=True)
    with open(os.environ["CNCLAB_TP_OUT"], "w") as f:
        json.dump(out, f, indent=1)


if __name__ == "__main__":
    try:
        main()
    except Exception as exc:               # the DISPLAY must exit so that linuxcnc shuts down
        print("cnclab-tp driver failed:", exc, file=sys.stderr, flush=True)
        sys.exit(1)
