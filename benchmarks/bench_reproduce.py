"""Benchmark: ``make reproduce`` cold (empty build/ and cache) and warm (nothing changed), one run each.

Runs ``python -m cnclab reproduce`` twice into a fresh temporary build folder (``CNCLAB_BUILD_DIR``;
the cache goes to ``<build>/cache``) and prints the wall times against the targets (cold <= 480 s
on 2 cores, warm <= 60 s), and whether every executed notebook, figure and the claims report of the
warm run are byte-identical to the cold run's. The full run takes minutes: ``--only TEXT`` limits it
to the notebooks whose path contains TEXT (the claims report is always computed).
Usage: ``python benchmarks/bench_reproduce.py [--only TEXT] [--jobs N]``.
"""
import argparse
import hashlib
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def snapshot(build: Path) -> dict:
    return {str(p.relative_to(build)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(build.rglob("*")) if p.is_file() and "cache" not in p.relative_to(build).parts}


def main(argv):
    ap = argparse.ArgumentParser()
    ap.add_argument("--only")
    ap.add_argument("--jobs", type=int, default=os.cpu_count())
    a = ap.parse_args(argv)
    build = Path(tempfile.mkdtemp(prefix="cnclab-bench-reproduce-"))
    env = dict(os.environ, CNCLAB_BUILD_DIR=str(build))
    env.pop("CNCLAB_CACHE_DIR", None)
    cmd = [sys.executable, "-m", "cnclab", "reproduce", "--jobs", str(a.jobs)] + (["--only", a.only] if a.only else [])
    rows = []
    snaps = []
    for label, target in (("cold (empty build/ and cache)", 480.0), ("warm (nothing changed)", 60.0)):
        t0 = time.perf_counter()
        rc = subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL).returncode
        rows.append((label, time.perf_counter() - t0, target, rc))
        snaps.append(snapshot(build))
    same = snaps[0] == snaps[1]
    w = max(len(r[0]) for r in rows)
    print(f"{'make reproduce' + (' --only ' + a.only if a.only else ''):<{w}}  {'seconds':>8}  {'target':>7}  rc")
    for label, sec, target, rc in rows:
        print(f"{label:<{w}}  {sec:8.1f}  {target:7.0f}  {rc}")
    print(f"outputs of the warm run identical to the cold run's: {same} ({len(snaps[1])} files); "
          f"{a.jobs} jobs; machine possibly shared")


if __name__ == "__main__":
    main(sys.argv[1:])
