"""Benchmark: what writing a figure costs, in the two modes of :func:`cnclab.plotting.savefig` --
PDF + SVG + PNG at 300 dpi (``make reproduce``) against one PNG at 100 dpi (fast mode, the
notebooks of ``make test``) -- on every registered figure recipe (:data:`cnclab.figures.FIGURES`),
each drawn once and written both ways in one run (the order alternates per figure); seconds per
figure and the ratio, one table. Drawing (the recipe's computation and its artists) is not timed.

Run: ``CNCLAB_FAST=1 .venv/bin/python benchmarks/bench_figure_export.py [NAME ...]`` (fast mode: the
recipes compute as the notebooks do in ``make test``; their disk caches make a second run quick).
"""
import sys
import tempfile
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

from cnclab import figures, plotting  # noqa: E402

MODES = {"full": (plotting.SAVE_FORMATS, plotting.SAVE_DPI), "fast": (plotting.FAST_SAVE_FORMATS, plotting.FAST_SAVE_DPI)}


def _write(fig, name, mode, outdir) -> float:
    formats, dpi = MODES[mode]
    t0 = time.perf_counter()
    plotting.export_figure(fig, name, outdir, formats=formats, dpi=dpi)
    return time.perf_counter() - t0


def main(names=None):
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for i, name in enumerate(sorted(names or figures.FIGURES)):
            fig = figures.draw(name)
            try:
                order = ("full", "fast") if i % 2 == 0 else ("fast", "full")
                t = {mode: _write(fig, name, mode, tmp) for mode in order}
            finally:
                plt.close(fig)
            rows.append({"figure": name, "full_s": t["full"], "fast_s": t["fast"]})
    df = pd.DataFrame(rows)
    total = {"figure": f"all {len(df)}", "full_s": df.full_s.sum(), "fast_s": df.fast_s.sum()}
    df = pd.concat([df, pd.DataFrame([total])], ignore_index=True)
    df["ratio"] = df.full_s / df.fast_s
    with pd.option_context("display.width", 200, "display.max_rows", 500):
        print(df.round(3).to_string(index=False))
    return df


if __name__ == "__main__":
    main(sys.argv[1:] or None)
