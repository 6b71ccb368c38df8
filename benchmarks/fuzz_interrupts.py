"""Interrupt fuzz, the long run (issue 28 item 5): SIGINT / SIGTERM sent to ``python -m cnclab plan |
analyze | spindle`` at seeded random offsets from 0.02 to 3 s, a share of the runs with an EMPTY numba
cache (``NUMBA_CACHE_DIR`` a fresh folder: the kernels compile in the run, llvmlite calls back into
Python), every outcome classified by ``tests/_fuzz_support.classify_interrupt`` (complete / stopped after writing / nothing
written / interpreter start-up; anything else is counted by class: crash, traceback, exception
ignored, lying message, partial outputs, temporary file left, early default action).

    python benchmarks/fuzz_interrupts.py --runs 300 --seed 28 --out /tmp/fuzz/interrupts.jsonl

One JSON line per run (command, signal, offset, cache, rc, class, stderr tail of a bad run); the
counts by class at the end. Not a test (minutes of wall time): the suite runs a few fixed offsets
(tests/test_fuzz_interrupts.py).
"""
from __future__ import annotations

import argparse
import collections
import json
import signal
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests._fuzz_support import BadOutcome, check_complete, classify_interrupt, commands, run_cli, startup_s  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=300)
    ap.add_argument("--seed", type=int, default=28)
    ap.add_argument("--cold-share", type=float, default=0.3, help="share of runs with an empty numba cache")
    ap.add_argument("--commands", default="plan,analyze,spindle")
    ap.add_argument("--lo", type=float, default=0.02, help="smallest offset (s)")
    ap.add_argument("--hi", type=float, default=3.0, help="largest offset (s)")
    ap.add_argument("--out", type=Path, required=True)
    a = ap.parse_args(argv)
    import numpy as np

    rng = np.random.default_rng(a.seed)
    cmds = a.commands.split(",")
    counts = collections.Counter()
    start = startup_s()
    with open(a.out, "a") as log:
        for k in range(a.runs):
            cmd = cmds[k % len(cmds)]
            sig = signal.SIGINT if rng.random() < 0.5 else signal.SIGTERM
            delay = float(np.exp(rng.uniform(np.log(a.lo), np.log(a.hi))))
            cold = bool(rng.random() < a.cold_share)
            with tempfile.TemporaryDirectory(prefix="cnclab-intr-") as td:
                d = Path(td) / "out"
                d.mkdir()
                argv_c, outs = commands(d)[cmd]
                env = {"NUMBA_CACHE_DIR": str(Path(td) / "numba")} if cold else {}
                rc, out, err, wall = run_cli(argv_c, sig, delay, env=env)
                # the start-up window moves with the machine's load: measured again next to each run
                start_now = max(start, startup_s(1))
                rec = {"cmd": cmd, "sig": signal.Signals(sig).name, "delay": round(delay, 4), "cold": cold, "rc": rc,
                       "wall": round(wall, 3), "startup": round(start_now, 3)}
                try:
                    rec["class"] = classify_interrupt(rc, err, outs, sig, delay, start_now, d, check_complete(cmd))
                except BadOutcome as exc:
                    rec["class"], rec["err"] = "BAD " + exc.kind, err[-3000:]
                except Exception as exc:               # a complete output that does not read back
                    rec["class"], rec["err"] = "BAD unreadable output", repr(exc) + err[-2000:]
            counts[(cmd, rec["class"])] += 1
            log.write(json.dumps(rec) + "\n")
            log.flush()
            print(k, rec["cmd"], rec["sig"], rec["delay"], "cold" if cold else "warm", rc, rec["class"], flush=True)
    print("start-up (python -c pass, worst of 3):", round(start, 3), "s")
    for key, n in sorted(counts.items()):
        print(*key, n)
    return 0


if __name__ == "__main__":
    sys.exit(main())
