"""Figure recipes of Mgherony (2024) chapter 6: the data set (Figs 6-2, 6-3), the regressions (6-10) and
the neural networks (6-4 ... 6-9, 6-11, 6-12), each drawn from the package alone.

The plotting functions take their data (:func:`main_effects_figure`, :func:`ann_diagnostics_figure`, ...);
the registered recipes (``python -m cnclab figure --list``) call them with the chapter's data: the
networks are those of the notebooks, seed 0 of :func:`cnclab.works.mgherony2024.ch6.ann_runs` at
:func:`~cnclab.works.mgherony2024.ch6.run_settings` (10 seeds x 1000 epochs, or 2 x 100 in fast mode;
cached on disk). Sizes are in units of the style's ``figure.figsize`` (:func:`cnclab.plotting.figsize`).

>>> import matplotlib; matplotlib.use("Agg")
>>> fig = draw("fig6-2_main_effects")
>>> len(fig.axes)                                  # one panel per factor D, a_p, A_N2, A_f
4
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from ...analysis.doe import interaction_means, main_effects
from ...plotting import FIGURES, draw_figure as draw, figsize, register_figure as _register
from . import ch6

__all__ = ["FIGURES", "draw", "main_effects_figure", "interactions_figure", "estimated_vs_calculated_figure",
           "statistics_bars_figure", "ann_diagnostics_figure"]


# ---------------------------------------------------------------------------------- plotting functions
def main_effects_figure(df: pd.DataFrame | None = None, response: str = "D_eff1"):
    """Figure 6-2: mean working diameter (mm) at each level of each factor (MiniTab main-effects plot)."""
    import matplotlib.pyplot as plt

    df = ch6.dataset() if df is None else df
    me = main_effects(df, ch6.INPUTS, response)
    fig, axes = plt.subplots(1, 4, figsize=figsize(1.85, 0.8), sharey=True, layout="constrained")
    for ax, f in zip(axes, ch6.INPUTS):
        ax.plot(me[f].index, me[f].to_numpy(), "o-")
        ax.axhline(df[response].mean(), color="grey", lw=0.8, ls="--")
        ax.set_xlabel(f + (" (deg)" if f.startswith("A_") else " (mm)"))
    axes[0].set_ylabel(f"mean {response} (mm)")
    fig.suptitle("Main effects plot (Fig 6-2)")
    return fig


def interactions_figure(df: pd.DataFrame | None = None, response: str = "D_eff1"):
    """Figure 6-3: interaction plot matrix (row factor on x, one line per level of the column factor)."""
    import matplotlib.pyplot as plt

    df = ch6.dataset() if df is None else df
    n = len(ch6.INPUTS)
    fig, axes = plt.subplots(n, n, figsize=figsize(1.85, 2.35), layout="constrained")
    for i, fx in enumerate(ch6.INPUTS):
        for j, fl in enumerate(ch6.INPUTS):
            ax = axes[i, j]
            if i == j:
                ax.text(0.5, 0.5, fx, ha="center", va="center", fontsize="large", transform=ax.transAxes)
                ax.set_axis_off()
                continue
            tab = interaction_means(df, fx, fl, response)
            cols = tab.columns if len(tab.columns) <= 4 else tab.columns[::3]
            for c in cols:
                ax.plot(tab.index, tab[c], lw=1, label=f"{fl}={c:g}")
            ax.tick_params(labelsize="small")
            if i == 0:
                ax.legend(fontsize="x-small", handlelength=1, borderaxespad=0.2, labelspacing=0.2)
    fig.suptitle(f"Interaction plot for {response} (Fig 6-3)")
    return fig


def estimated_vs_calculated_figure(predictions: dict, y=None, bins: int = 40):
    """Figures 6-10 / 6-11: estimated vs calculated D_eff1 (mm) and the histogram of the differences,
    one row per entry of ``predictions`` (name -> estimates of the 2704 rows)."""
    import matplotlib.pyplot as plt

    y = ch6.dataset()["D_eff1"].to_numpy() if y is None else y
    fig, axes = plt.subplots(len(predictions), 2, figsize=figsize(1.5, 0.85 * len(predictions)), squeeze=False,
                             layout="constrained")
    for (name, pred), (a, b) in zip(predictions.items(), axes):
        a.plot(y, pred, ".", ms=2)
        a.plot([0, y.max()], [0, y.max()], "k-", lw=0.8)
        a.set(xlabel="calculated D_eff1 (mm)", ylabel="estimated (mm)", title=name)
        b.hist(y - pred, bins=bins)
        b.set(xlabel="difference (mm)", ylabel="count", title=f"{name}: differences")
    return fig


def statistics_bars_figure(table: pd.DataFrame):
    """Figure 6-12: the statistics of Table 6-3 per model as grouped bars (``table``: stats × models)."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=figsize(1.35, 0.92))
    table.T.plot.bar(ax=ax, rot=0)
    ax.set(ylabel="value (mm or fraction)", title="Statistics of the differences (Fig 6-12)")
    ax.legend(fontsize="small", ncol=2)
    return fig


def ann_diagnostics_figure(net, title: str):
    """Figs 6-4…6-9 for one network: 20-bin error histogram (both outputs, all samples, by subset),
    outputs vs targets per subset with R (plotregression), and the MSE curves with the best epoch."""
    import matplotlib.pyplot as plt
    from matplotlib.ticker import LogLocator, MaxNLocator

    df = ch6.dataset()
    X, Y = df[list(ch6.INPUTS)].to_numpy(), df[list(ch6.OUTPUTS)].to_numpy()
    P = net.predict(X)
    names = ("training", "validation", "test")
    fig, grid = plt.subplots(2, 3, figsize=figsize(1.85, 1.7), layout="constrained")
    axes = grid.flat[:5]                                   # histogram, three regressions, MSE curves
    err = Y - P
    edges = np.histogram_bin_edges(err.ravel(), bins=20)
    axes[0].hist([err[idx].ravel() for idx in net.split], bins=edges, stacked=True, label=names)
    axes[0].axvline(0, color="orange")
    axes[0].xaxis.set_major_locator(MaxNLocator(2))        # a narrow panel at column width
    axes[0].set(xlabel="target − output (mm)", ylabel="instances", title=f"{title}: error histogram")
    for ax, name, idx in zip(axes[1:4], names, net.split):
        t, o = Y[idx].ravel(), P[idx].ravel()
        ax.plot(t, o, ".", ms=2)
        ax.plot([0, t.max()], [0, t.max()], "k--", lw=0.8)
        ax.set(xlabel="target (mm)", ylabel="output (mm)", title=f"{name}\nR = {np.corrcoef(t, o)[0, 1]:.5f}")
    h = net.history
    for col in ("train_mse", "val_mse", "test_mse"):
        axes[4].semilogy(h["epoch"], h[col], label=col.split("_")[0])
    axes[4].yaxis.set_major_locator(LogLocator(base=100.0))     # every second decade: 4+ decades in a short panel
    axes[4].axvline(net.best_epoch, color="grey", ls=":")
    axes[4].set(xlabel="epoch", ylabel="MSE (scaled)", title=f"best validation\nat epoch {net.best_epoch}")
    grid[1, 2].set_axis_off()                              # one legend for both: same subsets, same colours
    grid[1, 2].legend(*axes[0].get_legend_handles_labels(), title="subset", loc="center")
    return fig


def _network(model: str):
    """Seed 0 of the notebooks' LM runs of ``model`` (the same cached network as ``ann_runs(...)[0]``)."""
    _, max_epochs = ch6.run_settings()
    return ch6.ann_runs(model, 1, "lm", max_epochs)[0]


# ------------------------------------------------------------------------------------------ recipes
@_register("fig6-2_main_effects", "mgherony2024", "Mgherony (2024) Fig 6-2: main effects on D_eff1")
def fig6_2_main_effects():
    return main_effects_figure()


@_register("fig6-3_interaction_plot", "mgherony2024", "Mgherony (2024) Fig 6-3: interaction plot of D_eff1")
def fig6_3_interaction_plot():
    return interactions_figure()


@_register("fig6-10_regression_estimates", "mgherony2024",
           "Mgherony (2024) Fig 6-10: regression estimates r1 (eq 6-4) and r2 (eq 6-5) against the data")
def fig6_10_regression_estimates():
    df = ch6.dataset()
    return estimated_vs_calculated_figure({"r1 (eq 6-4)": ch6.r1_fit().predict(df),
                                           "r2 (eq 6-5)": ch6.unified_model().predict(df)})


@_register("fig6-4_6-6_6-8_a1_diagnostics", "mgherony2024",
           "Mgherony (2024) Figs 6-4, 6-6, 6-8: network a1 (seed 0): error histogram, regressions, MSE curves")
def fig6_4_6_6_6_8_a1_diagnostics():
    return ann_diagnostics_figure(_network("a1"), "a1")


@_register("fig6-5_6-7_6-9_a2_diagnostics", "mgherony2024",
           "Mgherony (2024) Figs 6-5, 6-7, 6-9: network a2 (seed 0): error histogram, regressions, MSE curves")
def fig6_5_6_7_6_9_a2_diagnostics():
    return ann_diagnostics_figure(_network("a2"), "a2")


@_register("fig6-11_ann_estimates", "mgherony2024",
           "Mgherony (2024) Fig 6-11: network estimates a1, a2 (seed 0) of D_eff1 against the data")
def fig6_11_ann_estimates():
    X = ch6.dataset()[list(ch6.INPUTS)].to_numpy()
    return estimated_vs_calculated_figure({m: _network(m).predict(X)[:, 0] for m in ("a1", "a2")})


@_register("fig6-12_statistics_bars", "mgherony2024",
           "Mgherony (2024) Fig 6-12: Table 6-3 statistics of r1, r2, a1, a2 (network columns: seed means)")
def fig6_12_statistics_bars():
    return statistics_bars_figure(ch6.table6_3_reproduced(*ch6.run_settings()))
