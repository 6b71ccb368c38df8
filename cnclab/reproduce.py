"""``make reproduce``: execute every notebook headless, export HTML, write the claims report."""
from __future__ import annotations

import os
import sys
import time
from pathlib import Path

from . import site
from .fileio import atomic_write
from .notebook_tools import INDEX_NOTEBOOK, list_notebooks
from .paths import NOTEBOOKS_DIR, build_dir
from .works import programs as nc_programs


def execute_notebook(path: Path, timeout: int = 3600, env: dict | None = None):
    """Execute a notebook in its own folder with a fresh ``python3`` kernel; returns the executed nb."""
    import nbformat
    from nbclient import NotebookClient

    nb = nbformat.read(path, as_version=4)
    old = {k: os.environ.get(k) for k in (env or {})}
    os.environ.update(env or {})
    try:
        NotebookClient(nb, timeout=timeout, kernel_name="python3",
                       resources={"metadata": {"path": str(Path(path).parent)}}).execute()
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    return nb


def run_all(only: str | None = None) -> int:
    import nbformat
    from nbconvert import HTMLExporter

    from . import claims

    out = build_dir()
    nbs = [p for p in list_notebooks() if not only or only in str(p)]
    work_nbs = [p for p in nbs if p != INDEX_NOTEBOOK]
    t_start = time.perf_counter()
    failures = []

    def run(i, p):
        rel = p.relative_to(NOTEBOOKS_DIR)
        print(f"[{i}/{len(nbs)}] {rel} ...", flush=True)
        t0 = time.perf_counter()
        try:
            nb = execute_notebook(p)
        except Exception as exc:  # report and go on: the summary fails the run
            failures.append(str(rel))
            print(f"      FAILED after {time.perf_counter() - t0:.1f} s: {type(exc).__name__}: "
                  f"{str(exc)[-2000:]}", flush=True)
            return
        dest = out / "notebooks" / rel
        atomic_write(dest, nbformat.writes(nb) + "\n")
        html, _ = HTMLExporter().from_notebook_node(nb)
        atomic_write(dest.with_suffix(".html"), html)
        print(f"      done in {time.perf_counter() - t0:.1f} s (total {time.perf_counter() - t_start:.0f} s)"
              f" -> {dest}", flush=True)

    for i, p in enumerate(work_nbs, 1):
        run(i, p)
    print("computing the claims ledger ...", flush=True)
    results = claims.evaluate_all(claims.load(), progress=True)
    p_csv, p_md = claims.write_report(results, out)
    print(claims.headline(claims.summary_frame(results)).to_string())
    print(f"wrote {p_csv} and {p_md}")
    if INDEX_NOTEBOOK in nbs:  # last: it shows the report just written
        run(len(nbs), INDEX_NOTEBOOK)
    bad = [r.claim.claim_id for r in results if not r.ok and not r.skipped]
    if failures:
        print(f"{len(failures)} notebook(s) failed: {', '.join(failures)}")
    if bad:
        print(f"{len(bad)} claim(s) do not hold: {', '.join(bad[:30])}")
    prog_rc = 0 if only else nc_programs.main([])  # every NC program -> build/gcode/<work>/ (issue 12)
    site.build_site(out)
    print(f"reproduce finished in {time.perf_counter() - t_start:.0f} s")
    return 1 if (failures or bad or prog_rc) else 0


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(prog="python -m cnclab reproduce")
    ap.add_argument("--only", help="run only notebooks whose path contains this text")
    a = ap.parse_args(argv)
    return run_all(a.only)


if __name__ == "__main__":
    sys.exit(main())
