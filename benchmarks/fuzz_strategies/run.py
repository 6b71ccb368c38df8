"""Every strategy on every job of the frozen fuzz corpus (``jobs/``, see ``gen.py``) through the CLI as a
user runs it: ``python -m cnclab plan`` (240 s each), then LinuxCNC's ``rs274 -g`` on each written
program (when installed) and ``python -m cnclab analyze`` (all adaptive, contour-parallel and zig-zag
programs, 15 % of the others; resolution max(D / 45, 0.12) mm). One JSON line per run in
``OUT/results.jsonl`` (a rerun skips the runs already there). Session 21's run is summarised in the
README (issue 29 section) and its closing note. Not a test: about an hour on 2 cores.

    .venv/bin/python benchmarks/fuzz_strategies/run.py [--out DIR] [--strategies A,B] [JOB-NAME-FRAGMENT ...]
"""
import csv, glob, json, os, random, re, shutil, subprocess, sys, time
from concurrent.futures import ThreadPoolExecutor, as_completed

PY = sys.executable
HERE = os.path.dirname(os.path.abspath(__file__))
args = sys.argv[1:]
BASE = "build/fuzz_strategies"
if args[:1] == ["--out"]:
    BASE, args = args[1], args[2:]
only = None
if args[:1] == ["--strategies"]:
    only, args = args[1].split(","), args[2:]
BASE = os.path.abspath(BASE)
RS274 = shutil.which("rs274")
STRATS = ["adaptive", "constant-engagement", "contour-parallel", "hybrid", "kim-yang-modified", "kim-yang-original", "zig-zag"]
ALWAYS_ANALYZE = {"adaptive", "contour-parallel", "zig-zag"}
SAMPLE_RNG = random.Random(4242)
RES = os.path.join(BASE, "results.jsonl")
os.makedirs(os.path.join(BASE, "out"), exist_ok=True)
os.makedirs(os.path.join(BASE, "an"), exist_ok=True)

jobs = sorted(glob.glob(os.path.join(HERE, "jobs", "*.json")))
if args:
    jobs = [j for j in jobs if any(s in j for s in args)]
done = set()
if os.path.exists(RES):
    for line in open(RES):
        r = json.loads(line)
        done.add((r["job"], r["strategy"]))

tasks = []
for j in jobs:
    for s in (only or STRATS):
        name = os.path.basename(j)[:-5]
        if (name, s) in done:
            continue
        analyze = s in ALWAYS_ANALYZE or SAMPLE_RNG.random() < 0.15
        tasks.append((j, s, analyze))
PRIO = ['adaptive','contour-parallel','zig-zag','kim-yang-original','kim-yang-modified','hybrid','constant-engagement']
tasks.sort(key=lambda t: (PRIO.index(t[1]), t[0]))
import itertools  # noqa: E402
_by = {}
for t in tasks: _by.setdefault(t[1], []).append(t)
tasks = [t for grp in itertools.zip_longest(*_by.values()) for t in grp if t is not None]
def nice(cmd):
    return ["nice", "-n", "15"] + cmd


def run(cmd, timeout):
    t0 = time.time()
    try:
        p = subprocess.run(nice(cmd), capture_output=True, text=True, timeout=timeout, cwd=BASE)
        return p.returncode, p.stdout, p.stderr, time.time() - t0, False
    except subprocess.TimeoutExpired as e:
        return None, (e.stdout or b"").decode(errors="replace") if isinstance(e.stdout, bytes) else (e.stdout or ""), \
            (e.stderr or b"").decode(errors="replace") if isinstance(e.stderr, bytes) else (e.stderr or ""), time.time() - t0, True


def one(job, strat, analyze):
    name = os.path.basename(job)[:-5]
    jd = json.load(open(job))
    out = os.path.join(BASE, "out", f"{name}__{strat}.ngc")
    if os.path.exists(out):
        os.remove(out)
    rec = {"job": name, "strategy": strat, "job_path": job, "out": out}
    cmd = [PY, "-m", "cnclab", "plan", job, "-o", out, "--strategy", strat]
    rec["cmd"] = " ".join(cmd)
    rc, so, se, dt, to = run(cmd, 240)
    rec.update(plan_rc=rc, plan_stdout=so[-3000:], plan_stderr=se[-3000:], plan_s=round(dt, 1), timeout=to)
    rec["out_exists"] = os.path.exists(out)
    rec["traceback"] = "Traceback" in (so + se)
    m = re.search(r"by region: ([^;]*?) mm\^2", so)
    rec["plan_uncut_str"] = m.group(1) if m else None
    if m:
        nums = [float(x) for x in re.findall(r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?", m.group(1))]
        rec["plan_uncut"] = sum(nums)
    if rc == 0 and rec["out_exists"]:
        hdr = []
        with open(out) as f:
            for line in f:
                if line.startswith("(") or line.startswith("%"):
                    hdr.append(line.rstrip())
                elif hdr and not line.startswith("("):
                    break
        rec["header_warn"] = [h for h in hdr if re.search(r"warn|limit|exceed|breach|uncut|slot", h, re.I)]
        r2 = run([RS274, "-g", out], 120) if RS274 else (None, "", "", 0.0, False)
        rec["rs274_rc"] = r2[0]
        errs = [l for l in (r2[1] + r2[2]).splitlines() if re.search(r"error|unknown|bad |near line", l, re.I)]
        rec["rs274_err"] = errs[:5]
        rec["rs274_lines"] = len(r2[1].splitlines())
        if analyze:
            D = jd["tool_diameter"]
            res = round(max(D / 45, 0.12), 3)
            ad = os.path.join(BASE, "an", f"{name}__{strat}")
            acmd = [PY, "-m", "cnclab", "analyze", out, "--job", job, "--resolution", str(res), "-o", ad]
            rec["an_cmd"] = " ".join(acmd)
            r3 = run(acmd, 400)
            rec.update(an_rc=r3[0], an_s=round(r3[3], 1), an_timeout=r3[4], an_err=r3[2][-1500:] if r3[0] else "")
            sp = os.path.join(ad, "summary.csv")
            if r3[0] == 0 and os.path.exists(sp):
                rec["an"] = {row["metric"]: (float(row["value"]) if row["value"] not in ("", "nan", "NaN") else None)
                             for row in csv.DictReader(open(sp))}
    return rec


t_start = time.time()
with ThreadPoolExecutor(2) as ex, open(RES, "a") as fres:
    futs = {ex.submit(one, *t): t for t in tasks}
    for k, f in enumerate(as_completed(futs)):
        try:
            r = f.result()
        except Exception as e:
            t = futs[f]
            r = {"job": os.path.basename(t[0])[:-5], "strategy": t[1], "driver_error": repr(e)}
        fres.write(json.dumps(r) + "\n")
        fres.flush()
        print(f"[{time.time()-t_start:6.0f}s {k+1}/{len(tasks)}] {r['job']} {r['strategy']} rc={r.get('plan_rc')} "
              f"{r.get('plan_s')}s an={r.get('an_rc','-')}", flush=True)
