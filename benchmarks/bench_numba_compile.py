"""Compile time of the numba kernels on an empty cache, per part of ``python -m cnclab warm`` and per
kernel, and the kernels compiled more than once (a second specialization: typically a literal
argument -- a constant 0, 2 or True passed from one kernel to another compiles the callee again for
``Literal[int](0)`` ... unless the call site passes ``np.int64(0)`` / ``np.bool_(True)``).

    .venv/bin/python benchmarks/bench_numba_compile.py [PART ...]

Each part runs in a fresh process with ``NUMBA_CACHE_DIR`` an empty temporary folder (the repository's
cache is not touched). Prints, per part: the wall seconds, the ten kernels with the longest compile
(inclusive of the callees they compile), and every cnclab kernel compiled more than once with the
argument positions whose types differ. Session 23 (2026-11-28): 82 -> 68 CPU-s for the three parts
in one process once the literal specializations were gone (16 such kernels before, 0 after).
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import collections, json, sys, time
from numba.core import event as ev
cm = ev.install_recorder("numba:compile")      # held: a collected context manager uninstalls it
rec = cm.__enter__()
from cnclab import warm
t0 = time.perf_counter()
warm.warm_part(sys.argv[1])
wall = time.perf_counter() - t0
start, times, sigs = {}, collections.Counter(), collections.defaultdict(list)
for ts, e in rec.buffer:
    d = e.data["dispatcher"]
    key = (id(d), str(e.data["args"]))
    if e.is_start:
        start[key] = ts
        continue
    name = f"{d.py_func.__module__}.{d.py_func.__qualname__}"
    times[name] = max(times[name], ts - start.pop(key, ts))
    if name.startswith("cnclab."):
        sigs[name].append([str(a) for a in e.data["args"]])
dups = {}
for name, ss in sigs.items():
    if len(ss) > 1:
        n = min(map(len, ss))
        dups[name] = {"compiled": len(ss), "differing args": [k for k in range(n) if len({s[k] for s in ss}) > 1]}
print(json.dumps({"wall_s": wall, "longest": times.most_common(10), "duplicates": dups}))
"""


def audit(part: str) -> dict:
    """The compile audit of one part of :data:`cnclab.warm.PARTS` in a fresh process, empty cache."""
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        out = subprocess.run([sys.executable, "-c", CHILD, part], cwd=ROOT, env=env, capture_output=True,
                             text=True, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main(argv=None) -> int:
    sys.path.insert(0, str(ROOT))
    from cnclab.warm import PARTS

    parts = (argv if argv is not None else sys.argv[1:]) or list(PARTS)
    total, n_dup = 0.0, 0
    for part in parts:
        a = audit(part)
        total += a["wall_s"]
        n_dup += len(a["duplicates"])
        print(f"== {part}: {a['wall_s']:.1f} s on an empty cache")
        for name, t in a["longest"]:
            print(f"   {t:6.2f} s  {name}")
        for name, d in sorted(a["duplicates"].items()):
            print(f"   compiled {d['compiled']} x: {name} (argument positions differing: {d['differing args']})")
    print(f"sum of the parts {total:.1f} s; kernels compiled more than once: {n_dup}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
