"""``make reproduce``: execute every notebook headless, export HTML, write the claims report.

Notebooks run in parallel (``--jobs N``, default one per core; ``make reproduce JOBS=N``), each in
its own process with a fresh ``python3`` kernel talking over IPC sockets (no TCP, so no transport
warning). Progress is printed per notebook.

Incremental: a notebook whose inputs are unchanged — its own ``.ipynb``, the source of every cnclab
module it imports (transitively, :func:`cnclab.cache.module_closure`), the data files those name,
``environment.txt`` and the fast-mode flag — is not executed again; its executed copy and HTML in
``build/notebooks/`` are kept (their hashes are checked). The claims report is likewise reused when
no cnclab source or data file changed. Expensive recipes inside are cached by :mod:`cnclab.cache`.
``--force`` (``make reproduce FORCE=1``, which also sets ``CNCLAB_NO_CACHE=1``) re-runs everything.
"""
from __future__ import annotations

import ast
import concurrent.futures as cf
import functools
import hashlib
import json
import logging
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

from . import claims, clihelp, site
from .cache import module_closure
from .fileio import atomic_write
from .notebook_tools import INDEX_NOTEBOOK, list_notebooks
from .paths import DATA_DIR, NOTEBOOKS_DIR, PACKAGE_DIR, REPO_ROOT, build_dir
from .runtime import fast_mode
from .works import programs as nc_programs
from .warm import warm


class _KernelPollNoise(logging.Filter):
    """Drop asyncio's "Task exception was never retrieved" for nbclient's kernel-alive poll, which
    fails harmlessly (an AssertionError on the already closed client) once a notebook has finished."""

    def filter(self, record):
        return "_async_poll_kernel_alive" not in str(getattr(record, "msg", "")) + str(record.args or "")


logging.getLogger("asyncio").addFilter(_KernelPollNoise())


def execute_notebook(path: Path, timeout: int = 3600, env: dict | None = None):
    """Execute a notebook in its own folder with a fresh ``python3`` kernel; returns the executed nb.

    The kernel talks over IPC (Unix sockets in a private temporary folder), not TCP; cell timing
    metadata is not recorded, so an executed notebook depends only on what its cells print.
    """
    import nbformat
    from nbclient import NotebookClient
    from traitlets.config import Config

    nb = nbformat.read(path, as_version=4)
    old = {k: os.environ.get(k) for k in (env or {})}
    os.environ.update(env or {})
    sockdir = tempfile.mkdtemp(prefix="cnclab-kernel-")
    try:
        cfg = Config()
        cfg.KernelManager.transport = "ipc"
        cfg.KernelManager.ip = os.path.join(sockdir, "k")
        NotebookClient(nb, config=cfg, timeout=timeout, kernel_name="python3", record_timing=False,
                       resources={"metadata": {"path": str(Path(path).parent)}}).execute()
    finally:
        shutil.rmtree(sockdir, ignore_errors=True)
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    return nb


# ------------------------------------------------------------------------------ input hashes
def _sha(*parts: bytes) -> str:
    h = hashlib.sha256()
    for p in parts:
        h.update(p)
        h.update(b"\0")
    return h.hexdigest()


def _code_cells(nb_path: Path) -> str:
    nb = json.loads(nb_path.read_text(encoding="utf-8"))
    return "\n".join("".join(c.get("source", "")) for c in nb.get("cells", []) if c.get("cell_type") == "code")


def _cnclab_imports(source: str) -> set[str]:
    """cnclab modules named by ``import``/``from`` statements in ``source`` (IPython magics dropped)."""
    lines = [ln for ln in source.splitlines() if not ln.lstrip().startswith(("%", "!"))]
    try:
        tree = ast.parse("\n".join(lines))
    except SyntaxError:
        return {"cnclab"}
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name.split(".")[0] == "cnclab")
        elif isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "cnclab":
            out.add(node.module)
            out.update(f"{node.module}.{a.name}" for a in node.names)
    return out or {"cnclab"}


@functools.lru_cache(maxsize=None)
def _data_names_in(source: str) -> frozenset:
    found: set[Path] = set()
    try:
        tree = ast.parse(source)
    except SyntaxError:
        return frozenset()
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and 0 < len(node.value) < 200 \
                and "\n" not in node.value and not node.value.startswith(("/", ".")):
            p = DATA_DIR / node.value
            try:
                if p.is_file():
                    found.add(p)
                elif p.is_dir():
                    found.update(q for q in p.rglob("*") if q.is_file())
            except OSError:
                continue
    return frozenset(found)


def _data_files_named(sources: list[str]) -> list[Path]:
    """Files under ``data/`` named by a string constant in ``sources`` (a folder name: all its files),
    plus ``data/claims.csv`` (every notebook's closing table shows ledger rows)."""
    found: set[Path] = {DATA_DIR / "claims.csv"} if (DATA_DIR / "claims.csv").is_file() else set()
    for src in sources:
        found.update(_data_names_in(src))
    return sorted(found)


#: modules whose string constants name work folders as identifiers, not as files they read
_NOT_DATA_READERS = ("paths.py", "claims.py", "plotting.py", "works/__init__.py")


@functools.lru_cache(maxsize=None)
def _read_bytes(path: Path, mtime_ns: int) -> bytes:
    return path.read_bytes()


def _bytes(path: Path) -> bytes:
    return _read_bytes(path, path.stat().st_mtime_ns)


def _environment_key() -> bytes:

    env = (REPO_ROOT / "environment.txt")
    return (env.read_bytes() if env.exists() else b"") + f"|py{sys.version_info[:3]}|fast={fast_mode()}".encode()


def notebook_inputs(nb_path: Path) -> tuple[str, list[Path]]:
    """(hash, files): the key of everything a notebook's outputs depend on, and the files in it."""

    code = _code_cells(nb_path)
    mods: set[Path] = set()
    for m in sorted(_cnclab_imports(code)):
        mods.update(module_closure(m))
    mods.add(PACKAGE_DIR / "paper.mplstyle")
    skip = {PACKAGE_DIR / m for m in _NOT_DATA_READERS}
    sources = [code] + [_bytes(p).decode("utf-8") for p in sorted(mods) if p.suffix == ".py" and p not in skip]
    files = [Path(nb_path)] + sorted(mods) + _data_files_named(sources)
    parts = [_environment_key()]
    for f in files:
        parts += [str(f.relative_to(REPO_ROOT)).encode(), _bytes(f)]
    return _sha(*parts), files


def report_inputs() -> str:
    """Key of the claims report: every cnclab source, every data file and the environment."""
    files = sorted(PACKAGE_DIR.rglob("*.py")) + sorted(p for p in DATA_DIR.rglob("*") if p.is_file())
    parts = [_environment_key()]
    for f in files:
        parts += [str(f.relative_to(REPO_ROOT)).encode(), _bytes(f)]
    return _sha(*parts)


def _stamp_path(name: str) -> Path:
    return build_dir() / "cache" / "reproduce" / (name.replace("/", "__") + ".json")


def _outputs_ok(stamp: dict) -> bool:
    for rel, digest in stamp.get("outputs", {}).items():
        p = build_dir() / rel
        if not p.is_file() or hashlib.sha256(p.read_bytes()).hexdigest() != digest:
            return False
    return bool(stamp.get("outputs"))


def _read_stamp(name: str, key: str, force: bool) -> dict | None:
    p = _stamp_path(name)
    if force or not p.is_file():
        return None
    try:
        stamp = json.loads(p.read_text())
    except (OSError, ValueError):
        return None
    return stamp if stamp.get("key") == key and _outputs_ok(stamp) else None


def _write_stamp(name: str, key: str, outputs: list[Path], seconds: float) -> None:
    out = {str(p.relative_to(build_dir())): hashlib.sha256(p.read_bytes()).hexdigest() for p in outputs}
    atomic_write(_stamp_path(name), json.dumps({"key": key, "seconds": round(seconds, 1), "outputs": out},
                                               indent=1, sort_keys=True) + "\n")


# ------------------------------------------------------------------------------ jobs
def _run_notebook_job(path_str: str, key: str) -> tuple[str, float, str | None]:
    """Execute one notebook and export it (in a worker process); (rel, seconds, error)."""
    import nbformat
    from nbconvert import HTMLExporter

    p = Path(path_str)
    rel = p.relative_to(NOTEBOOKS_DIR)
    t0 = time.perf_counter()
    try:
        nb = execute_notebook(p)
    except Exception as exc:  # report and go on: the summary fails the run
        return str(rel), time.perf_counter() - t0, f"{type(exc).__name__}: {str(exc)[-2000:]}"
    dest = build_dir() / "notebooks" / rel
    atomic_write(dest, nbformat.writes(nb) + "\n")
    html, _ = HTMLExporter().from_notebook_node(nb)
    atomic_write(dest.with_suffix(".html"), html)
    sec = time.perf_counter() - t0
    _write_stamp(str(rel), key, [dest, dest.with_suffix(".html")], sec)
    return str(rel), sec, None


def _run_claims_job(key: str) -> tuple[str, float, str | None]:
    """Evaluate the ledger and write build/claims.{csv,md} (in a worker process)."""
    t0 = time.perf_counter()
    results = claims.evaluate_all(claims.load())
    # the qualitative rows too, every one computed (slow ones included: this is where they are checked)
    qres = [claims.evaluate_qualitative(q) for q in claims.load_qualitative()]
    p_csv, p_md = claims.write_report(results, build_dir(), qualitative=qres)
    summary = claims.headline(claims.summary_frame(results)).to_string()
    bad = [r.claim.claim_id for r in [*results, *qres] if not r.ok and not r.skipped]
    atomic_write(build_dir() / "cache" / "reproduce" / "claims_summary.json",
                 json.dumps({"summary": summary, "bad": bad, "files": [str(p_csv), str(p_md)]}, indent=1) + "\n")
    sec = time.perf_counter() - t0
    if not bad:
        _write_stamp("claims-report", key, [Path(p_csv), Path(p_md)], sec)
    return "claims report", sec, None


def _run_programs_job(key: str) -> tuple[str, float, str | None]:
    """Write every NC program (``python -m cnclab programs``) in a worker process; stamped like a
    notebook (key: every cnclab source, data file and the environment) when all were written."""
    t0 = time.perf_counter()
    try:
        rc = nc_programs.main([])
    except Exception as exc:  # reported in the summary
        return "NC programs", time.perf_counter() - t0, f"{type(exc).__name__}: {str(exc)[-2000:]}"
    sec = time.perf_counter() - t0
    if rc != 0:
        return "NC programs", sec, "some programs failed (build/gcode/manifest.json)"
    gdir = build_dir() / "gcode"
    _write_stamp("nc-programs", key, sorted(p for p in gdir.rglob("*") if p.is_file()), sec)
    return "NC programs", sec, None


def _previous_seconds(rel: str) -> float:
    try:
        return float(json.loads(_stamp_path(rel).read_text()).get("seconds", 0))
    except (OSError, ValueError):
        return 0.0


#: notebooks that use none of the kernels ``cnclab warm`` compiles (they start while it runs)
_NO_SHARED_KERNELS = ("mgherony2024/ch6_neural_networks.ipynb",)
#: notebooks that take minutes (measured on the 2-core reference machine): on a fresh clone, with no
#: previous times in build/cache/reproduce, they start first so the parallel run ends sooner
#: (2026-11-28, fresh clone: the K&Y contour-parallel notebook, not in this list, started last and
#: ran alone for its last 130 s: 546 s in all)
_KNOWN_LONG = ("kim_yang2006/constant_mrr_contour_parallel.ipynb",     # its slow qualitative rows: 3-4 min
               "kim_yang2006/ce_vs_constant_mrr.ipynb", "mgherony2024/ch6_neural_networks.ipynb",
               "jacso2021/adaptive_vs_freecad.ipynb", "jacso2021/s4_star_pocket_hybrid_path.ipynb",
               "jacso2021/thesis4_trochoidal_slots.ipynb", "mgherony2024/ch7_spindle_speed_control.ipynb",
               "mgherony2024/ch9_toolpath_reordering.ipynb")


#: the notebook that computes the ce_clearing path the NC programs also write (see run_all)
_CE_PATH_NOTEBOOK = "kim_yang2006/ce_vs_constant_mrr.ipynb"


def run_all(only: str | None = None, jobs: int | None = None, force: bool = False) -> int:
    out = build_dir()
    nbs = [p for p in list_notebooks() if not only or only in str(p)]
    work_nbs = [p for p in nbs if p != INDEX_NOTEBOOK]
    jobs = max(1, jobs or os.cpu_count() or 1)
    t_start = time.perf_counter()
    failures, n_total, done = [], len(nbs), [0]

    def log(rel, msg):
        done[0] += 1
        print(f"[{done[0]}/{n_total}] {rel}: {msg} (total {time.perf_counter() - t_start:.0f} s)", flush=True)

    # what must run; the rest is reused
    todo = []
    for p in work_nbs:
        rel = str(p.relative_to(NOTEBOOKS_DIR))
        key, _ = notebook_inputs(p)
        if _read_stamp(rel, key, force):
            log(rel, "unchanged, executed copy reused")
        else:
            todo.append((p, rel, key))
    # longest first: by the last run's times, else the notebooks known to be long start first
    todo.sort(key=lambda t: (-_previous_seconds(t[1]),
                             _KNOWN_LONG.index(t[1]) if t[1] in _KNOWN_LONG else len(_KNOWN_LONG)))
    rkey = report_inputs()
    report_cached = _read_stamp("claims-report", rkey, force) is not None
    pkey = _sha(rkey.encode(), str(fast_mode()).encode())
    programs_cached = bool(only) or _read_stamp("nc-programs", pkey, force) is not None
    if programs_cached and not only:
        print("NC programs: unchanged, build/gcode reused", flush=True)
    print(f"running {len(todo)} notebook(s) on {jobs} process(es)"
          f"{'' if report_cached else ' + the claims report'} ...", flush=True)
    summ_path = out / "cache" / "reproduce" / "claims_summary.json"
    if not report_cached:
        summ_path.unlink(missing_ok=True)   # never print a previous run's summary for this one
    # the NC programs start early (long, independent); the claims report is queued last, so the
    # expensive recipes it shares with the notebooks (disk-cached by cnclab.cache) are mostly done
    with cf.ProcessPoolExecutor(max_workers=jobs) as pool:
        futs = {}
        # a notebook that needs none of the shared numba kernels starts while they compile
        early = [t for t in todo if t[1] in _NO_SHARED_KERNELS]
        for p, rel, key in early:
            futs[pool.submit(_run_notebook_job, str(p), key)] = rel
            print(f"      queued {rel}", flush=True)
        if todo or not programs_cached or not report_cached:
            # compile the shared numba kernels once before the processes that all need them start
            print(f"numba kernels ready in {warm():.1f} s", flush=True)
        rest = [t for t in todo if t not in early]
        # the longest notebooks first; the programs right after the K&Y comparison (it computes the
        # ce_clearing path the NC programs also write, cached on disk; the programs write that one
        # last and find it there), else after the first notebook
        after = _CE_PATH_NOTEBOOK if any(t[1] == _CE_PATH_NOTEBOOK for t in rest) else (rest[0][1] if rest else None)
        for p, rel, key in rest:
            futs[pool.submit(_run_notebook_job, str(p), key)] = rel
            print(f"      queued {rel}", flush=True)
            if rel == after and not programs_cached:
                futs[pool.submit(_run_programs_job, pkey)] = "NC programs"
        if after is None and not programs_cached:
            futs[pool.submit(_run_programs_job, pkey)] = "NC programs"
        if not report_cached:
            futs[pool.submit(_run_claims_job, rkey)] = "claims report"
        for fut in cf.as_completed(futs):
            try:
                name, sec, err = fut.result()
            except Exception as exc:  # a worker crashed
                name, sec, err = futs[fut], 0.0, f"{type(exc).__name__}: {exc}"
            if name in ("claims report", "NC programs"):
                print(f"      {name} done in {sec:.1f} s" if not err else f"{name} FAILED: {err}", flush=True)
                if err:
                    failures.append(name)
                continue
            if err:
                failures.append(name)
                log(name, f"FAILED after {sec:.1f} s: {err}")
            else:
                log(name, f"done in {sec:.1f} s -> {out / 'notebooks' / name}")
    bad = []
    if summ_path.is_file():
        summ = json.loads(summ_path.read_text())
        print(summ["summary"])
        print(f"wrote {' and '.join(summ['files'])}{' (unchanged inputs: reused)' if report_cached else ''}")
        bad = summ["bad"]
    if INDEX_NOTEBOOK in nbs:  # last: it shows the report just written
        rel = str(INDEX_NOTEBOOK.relative_to(NOTEBOOKS_DIR))
        key, _ = notebook_inputs(INDEX_NOTEBOOK)
        key = _sha(key.encode(), (out / "claims.md").read_bytes() if (out / "claims.md").is_file() else b"")
        if _read_stamp(rel, key, force):
            log(rel, "unchanged, executed copy reused")
        else:
            name, sec, err = _run_notebook_job(str(INDEX_NOTEBOOK), key)
            if err:
                failures.append(name)
                log(name, f"FAILED after {sec:.1f} s: {err}")
            else:
                log(name, f"done in {sec:.1f} s")
    if failures:
        print(f"{len(failures)} notebook(s) failed: {', '.join(failures)}")
    if bad:
        print(f"{len(bad)} claim(s) do not hold: {', '.join(bad[:30])}")
    site.build_site(out)
    print(f"reproduce finished in {time.perf_counter() - t_start:.0f} s")
    return 1 if (failures or bad) else 0


def main(argv=None) -> int:
    ap = clihelp.parser(
        "python -m cnclab reproduce",
        "Execute every notebook headless (in parallel), export HTML and figures, write every NC program\n"
        "and the claims report, then build the offline site. What did not change is reused from the\n"
        "previous run. Exits non-zero if a notebook fails or a claim no longer holds (make reproduce).",
        examples=["python -m cnclab reproduce --jobs 2", "python -m cnclab reproduce --only mgherony2024/ch3"],
        writes=["build/notebooks/<work>/<name>.ipynb, .html   the executed notebooks",
                "build/figures/<work>/<figure>.pdf, .svg, .png every figure (CNCLAB_FAST=1: a 100 dpi .png)",
                "build/gcode/<work>/*.ngc, manifest.json       every NC program",
                "build/claims.csv, build/claims.md             the claims report",
                "build/site/index.html                         the offline site"])
    ap.add_argument("--only", help="run only notebooks whose path contains this text (default: all)")
    ap.add_argument("--jobs", type=int, default=None, help="notebooks run at once (default: one per core)")
    ap.add_argument("--force", action="store_true", help="re-run everything: ignore executed copies and caches")
    a = ap.parse_args(argv)
    if a.force:
        os.environ["CNCLAB_NO_CACHE"] = "1"
    return run_all(a.only, a.jobs, a.force)


if __name__ == "__main__":
    sys.exit(main())
