"""Figure recipes: re-render a figure of the collection for a paper without running its notebook.

:data:`FIGURES` maps a figure name (the stem ``savefig`` gives it in ``build/figures/<work>/``) to a
recipe: its work, a one-line description and a function that draws the figure from the package
alone. :func:`draw` runs a recipe under a style sheet (the collection's ``paper.mplstyle`` by
default: fonts and line widths are fixed when a figure is drawn); :func:`render` draws and exports
it with :func:`cnclab.plotting.export_figure` (width/height in mm, formats, dpi). The notebooks that
show these figures call the same recipes, so the notebook and the paper figure cannot differ.

``python -m cnclab figure NAME --width-mm 85 --format pdf -o DIR`` is the command line;
``python -m cnclab figure --list`` lists the covered figures. Covered so far: the figures whose
plotting lives in the package or was moved here from its notebook (Jacsó Fig 3-1; Hoang Table 2; Kim & Yang Fig 2;
Mgherony Fig 3-5, 3-6/3-7/3-8, the three other ch. 3 figures, 4-1, 4-2/4-3, 5-6, 5-7, 5-8/5-9, 6-2, 6-3,
6-10); the other notebook figures still draw in their notebook cell
(``--list`` shows the state).

>>> FIGURES["fig5-6_deff_vs_depth_of_cut"].work
'mgherony2024'
"""
from __future__ import annotations

import dataclasses
import sys
from pathlib import Path
from typing import Callable

import numpy as np

from . import clihelp
from .cutting import scallop_volume as sv
from .cutting.roughness import ideal_cusp_profile
from .geometry import ball_end as be
from .geometry import cusp
from .geometry import engagement as eng
from .geometry.cylinder_parts import MEASURING_POSITIONS_MM, CylinderPart
from .paths import build_dir
from .plotting import STYLE_PATH, WIDTH_PRESETS_MM, export_figure, figsize
from .works.hoang2024 import constant_volume as cv
from .works.kim_yang2006 import constant_mrr_pocket as ky
from .works.mgherony2024 import ch3, ch4_5, ch6

__all__ = ["FIGURES", "Recipe", "draw", "render", "main"]


@dataclasses.dataclass(frozen=True)
class Recipe:
    """A figure recipe: ``work`` (the reproduced work), ``description``, ``draw() -> Figure``."""

    work: str
    description: str
    draw: Callable


FIGURES: dict[str, Recipe] = {}


def _register(name: str, work: str, description: str):
    def deco(f):
        FIGURES[name] = Recipe(work, description, f)
        return f
    return deco


@_register("fig3-1_engagement_vs_stepover", "jacso2021",
           "Jacsó (2021) Fig 3-1: engagement angle against stepover, straight and on arcs (r = 3 mm)")
def fig3_1_engagement_vs_stepover(r: float = 3.0):
    import matplotlib.pyplot as plt

    s = np.linspace(0.01, 2 * r, 300)
    fig, ax = plt.subplots(figsize=figsize())
    ax.plot(s, eng.theta_straight(s, r), "k", label="straight")
    for rho in (4.0, 8.0, 20.0):
        ax.plot(s, eng.theta_concave(s, rho, r), label=f"concave ρ={rho:g}")
        ok = rho - s + r > 0
        ax.plot(s[ok], eng.theta_convex(s[ok], rho, r), "--", label=f"convex ρ={rho:g}")
    ax.set(xlabel="stepover s [mm]", ylabel="engagement θ [deg]")
    ax.legend(fontsize=7)
    return fig


@_register("fig6-2_main_effects", "mgherony2024", "Mgherony (2024) Fig 6-2: main effects on D_eff1")
def fig6_2_main_effects():
    return ch6.fig_main_effects()


@_register("fig6-3_interaction_plot", "mgherony2024", "Mgherony (2024) Fig 6-3: interaction plot of D_eff1")
def fig6_3_interaction_plot():
    return ch6.fig_interactions()


@_register("fig6-10_regression_estimates", "mgherony2024",
           "Mgherony (2024) Fig 6-10: regression estimates r1 (eq 6-4) and r2 (eq 6-5) against the data")
def fig6_10_regression_estimates():
    df = ch6.dataset()
    return ch6.fig_estimated_vs_calculated({"r1 (eq 6-4)": ch6.r1_fit().predict(df),
                                           "r2 (eq 6-5)": ch6.unified_model().predict(df)})


@_register("fig5-6_deff_vs_depth_of_cut", "mgherony2024",
           "Mgherony (2024) Fig 5-6: true working diameter against the depth of cut (D = 6, 8, 10 mm)")
def fig5_6_deff_vs_depth_of_cut():
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=figsize(1, 0.9))
    for Dm, g in ch4_5.fig5_6_curves().groupby("D_mm"):
        line, = ax.plot(g.a_p_mm, g.d1_lead_mm, label=f"D={Dm:g} up (1′)")
        ax.plot(g.a_p_mm, g.d1_trail_mm, "--", color=line.get_color(), label=f"D={Dm:g} down (1″)")
    ax.set(xlabel="a_p [mm]", ylabel="true working diameter [mm]", title="Fig 5-6")
    ax.legend(fontsize=7, ncol=3)
    return fig


@_register("fig5-7_deff_change_during_chip_removal", "mgherony2024",
           "Mgherony (2024) Fig 5-7: change of the true working diameter during chip removal against a_e")
def fig5_7_deff_change_during_chip_removal():
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=figsize(1, 0.9))
    for (Dm, mode), g in ch4_5.fig5_7_variation().groupby(["D_mm", "milling"]):
        ax.plot(g.a_e_mm, g.variation_mm, "-" if mode == "up" else "--", label=f"D={Dm:g} {mode}")
    ax.set(xlabel="a_e [mm]", ylabel="|Δ true working diameter| [mm]", title="Fig 5-7")
    ax.legend(fontsize=7, ncol=3)
    return fig


@_register("fig5-8_5-9_deff_vs_feed_direction", "mgherony2024",
           "Mgherony (2024) Fig 5-8, 5-9: the thesis' 'D_eff' (a radius) against the feed direction")
def fig5_8_5_9_deff_vs_feed_direction():
    import matplotlib.pyplot as plt

    Afs = np.linspace(0, 360, 721)
    fig, axs = plt.subplots(1, 2, figsize=figsize(1.5, 0.85), sharey=True)
    for ax, ap_ in zip(axs, (1.0, 0.3)):
        r1, r2 = be.paper_deff_radius_valued(10, ap_, 35, 25, Afs)
        ax.plot(Afs, r1, label="point 1")
        ax.plot(Afs, r2, label="point 2")
        ax.set(xlabel="A_f [deg]", title=f"a_p = {ap_:g} mm (Fig 5-{8 if ap_ == 1 else 9})")
    axs[0].set_ylabel("distance from axis ('D_eff' of the thesis) [mm]")
    axs[0].legend()
    return fig


@_register("ch3_cusp_approximation_error", "mgherony2024",
           "Mgherony (2024) ch. 3: underestimate of the cusp height by eq 3-2/3-4 against s/RE, Table 3-4 parts")
def ch3_cusp_approximation_error():
    import matplotlib.pyplot as plt

    parts = ch3.parts()
    ratio = np.linspace(0.01, 1.2, 300)
    fig, ax = plt.subplots(figsize=figsize(0.85, 0.85))
    ax.plot(ratio, -100 * cusp.approximation_relative_error(ratio, 1.0), label="eq 3-2 / 3-4 vs exact")
    for part, r in parts.iterrows():
        err = -100 * cusp.approximation_relative_error(r.spacing_mm, r.RE_mm)
        ax.plot(r.spacing_mm / r.RE_mm, err, "o", color="C1" if r.process == "milling" else "C0")
        ax.annotate(part, (r.spacing_mm / r.RE_mm, err), textcoords="offset points", xytext=(3, 3), fontsize=7)
    ax.set(xlabel="spacing / corner radius  s/RE", ylabel="underestimate of CH [%]",
           title="Error of the cusp-height approximation (Fig 3-1 geometry)")
    return fig


@_register("fig3-5_rz_ra_ratio", "mgherony2024", "Mgherony (2024) Fig 3-5: Rz/Ra of the turned and milled parts")
def fig3_5_rz_ra_ratio():
    import matplotlib.pyplot as plt

    parts, stats = ch3.parts(), ch3.statistics()
    fig, axes = plt.subplots(1, 2, figsize=figsize(1.15, 0.8), sharey=True)
    for ax, proc in zip(axes, ["turning", "milling"]):
        sub = parts[parts.process == proc]
        ax.bar(sub.index, sub.Rz_um / sub.Ra_um, color="C0" if proc == "turning" else "C1")
        ax.axhline(stats[f"ratio.{proc}"], color="k", lw=0.8, ls="--", label=f"mean {stats[f'ratio.{proc}']:.3f}")
        ax.set(title=f"{proc} (Fig 3-5 {'a' if proc == 'turning' else 'b'})", xlabel="part")
        ax.legend()
    axes[0].set_ylabel("Rz / Ra")
    return fig


@_register("fig3-6_3-7_3-8_roughness_vs_cusp_height", "mgherony2024",
           "Mgherony (2024) Fig 3-6, 3-7, 3-8: Ra and Rz against the cusp height with the linear fits")
def fig3_6_3_7_3_8_roughness_vs_cusp_height():
    import matplotlib.pyplot as plt

    parts, stats = ch3.parts(), ch3.statistics()
    fig, axes = plt.subplots(1, 3, figsize=figsize(1.5, 0.8), sharey=True)
    for ax, (group, fig_no) in zip(axes, [("turning", "3-6"), ("milling", "3-7"), ("both", "3-8")]):
        sub = parts if group == "both" else parts[parts.process == group]
        xs = np.linspace(0, sub.CH_um.max() * 1.05, 50)
        for resp, marker in [("Ra", "o"), ("Rz", "s")]:
            ax.plot(sub.CH_um, sub[f"{resp}_um"], marker, ls="", label=resp)
            b0, b1 = stats[f"linear.{group}.{resp}.intercept"], stats[f"linear.{group}.{resp}.slope"]
            ax.plot(xs, b0 + b1 * xs, lw=0.8, label=f"{resp} = {b1:.4f}·CH + {b0:.4f}")
        ax.set(title=f"{group} (Fig {fig_no})", xlabel="CH [µm]")
        ax.legend(fontsize=6)
    axes[0].set_ylabel("roughness [µm]")
    return fig


@_register("ch3_hybrid_model_erratum", "mgherony2024",
           "Mgherony (2024) eqs 3-10 ... 3-12: the hybrid roughness model as printed and inverted")
def ch3_hybrid_model_erratum():
    import matplotlib.pyplot as plt

    parts = ch3.parts()
    fig, ax = plt.subplots(figsize=figsize(0.7, 0.95))
    for resp, c, m in [("Ra", (1.94, -1.68, 11.6), "o"), ("Rz", (0.24, -0.37, 3.45), "s")]:
        C = c[0] + c[1] * parts.RE_mm + c[2] * parts.p_mm
        ax.plot(parts[f"{resp}_um"], parts.CH_um / C, m, label=f"{resp}: Rx = CH / C (printed coefficients)")
        ax.plot(parts[f"{resp}_um"], parts.CH_um * C, m, mfc="none", label=f"{resp}: Rx = C·CH (eq 3-10 as printed)")
    lim = [0, 22]
    ax.plot(lim, lim, "k", lw=0.6)
    ax.set(xlim=lim, ylim=[0, 40], xlabel="measured [µm]", ylabel="model [µm]", title="Hybrid model, eqs 3-10 … 3-12")
    ax.legend(fontsize=6)
    return fig


@_register("ch3_ideal_profile_share", "mgherony2024",
           "Mgherony (2024) ch. 3: the ideal profile of T3 and the share of Ra, Rz the geometry explains")
def ch3_ideal_profile_share():
    import matplotlib.pyplot as plt

    parts, ideal = ch3.parts(), ch3.ideal_vs_measured()
    fig, axes = plt.subplots(1, 2, figsize=figsize(1.35, 0.8))
    x, z = ideal_cusp_profile(parts.loc["T3", "spacing_mm"], parts.loc["T3", "RE_mm"], 1.0, n=4001)
    axes[0].plot(x, 1000 * z)
    axes[0].set(xlabel="x [mm]", ylabel="z [µm]", title="Ideal profile of T3 (f = 0.2 mm, RE = 0.4 mm)")
    w, idx = 0.38, np.arange(len(ideal))
    axes[1].bar(idx - w / 2, ideal.Rz_share * 100, w, label="Rz ideal / measured")
    axes[1].bar(idx + w / 2, ideal.Ra_share * 100, w, label="Ra ideal / measured")
    axes[1].set(xticks=idx, xticklabels=ideal.index, ylabel="explained by geometry [%]")
    axes[1].legend(fontsize=7)
    return fig


@_register("table2_fr_printed_vs_consistent", "hoang2024",
           "Hoang (2024) Table 2: forward step F_r as printed and unit-consistent; curvature volume V_RT")
def table2_fr_printed_vs_consistent():
    import matplotlib.pyplot as plt

    printed, re = cv.table2_printed(), cv.table2_recomputed()
    fig, axs = plt.subplots(1, 2, figsize=figsize(1.5, 0.9))
    x = np.arange(1, 9)
    axs[0].semilogy(x, printed.Fr_mm, "o-", label="printed F_r (slip)")
    axs[0].semilogy(x, re.Fr_consistent, "s-", label="unit-consistent F_r, eq. 7")
    axs[0].semilogy(x, re.Fr_v2, "^--", label="F_r from V2, eq. 4")
    axs[0].set(xlabel="Table 2 row", ylabel="forward step F_r [mm]")
    axs[0].legend(fontsize=7)
    th, R = re.theta_rad.to_numpy(), re.RT.to_numpy()
    axs[1].bar(x - 0.2, 0.5 * R**2 * (3.14 * th / 180 - np.sin(th)), 0.4, label="V_RT with slip")
    axs[1].bar(x + 0.2, sv.curvature_volume(th, R), 0.4, label="V_RT consistent")
    axs[1].set(xlabel="Table 2 row", ylabel="V_RT [mm²]")
    axs[1].legend(fontsize=7)
    return fig


@_register("fig4-1_cv_cx_sections", "mgherony2024",
           "Mgherony (2024) Fig 4-1: sections of the concave (CV) and convex (CX) test parts, ball centres")
def fig4_1_cv_cx_sections():
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=figsize(1.15, 0.8))
    for kind in ("CV", "CX"):
        part = CylinderPart(kind)
        y, z = part.section()
        ax.plot(y, z, label=f"{kind} surface")
        Rt = part.tool_path_radius(10.0)
        yc = part.contact_y(MEASURING_POSITIONS_MM)
        centre = np.c_[MEASURING_POSITIONS_MM, part.z(yc) + 5.0 * part.normal(yc)[:, 2]]
        ax.plot(*centre.T, "o", ms=3, label=f"{kind} ball centres (radius {Rt:g} mm)")
    ax.set(xlabel="y [mm]", ylabel="z [mm]", aspect="equal", title="CV/CX sections (Fig 4-1, Table 4-2)")
    ax.legend(fontsize=7, ncol=2)
    return fig


@_register("fig4-2_4-3_effective_diameter_cutting_speed", "mgherony2024",
           "Mgherony (2024) Fig 4-2, 4-3: effective diameter and actual cutting speed along the CV/CX parts")
def fig4_2_4_3_effective_diameter_cutting_speed():
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(1, 2, figsize=figsize(1.5, 0.85))
    for kind, g in ch4_5.ch4_effective_diameters().groupby("part"):
        axs[0].plot(g.y_mm, g.D_eff1_mm, "o-", label=kind)
        axs[1].plot(g.y_mm, g.v_c_m_min, "o-", label=kind)
    axs[0].set(xlabel="measuring position y [mm]", ylabel="effective diameter [mm]", title="Fig 4-2")
    axs[1].set(xlabel="measuring position y [mm]", ylabel="actual v_c [m/min]", title="Fig 4-3 (n = 5100 rpm)")
    for a in axs:
        a.legend()
    return fig


@_register("fig2_offsets_pocket_120x85", "kim_yang2006",
           "Kim & Yang (2006) Fig 2: the offset levels of the 120 x 85 mm pocket")
def fig2_offsets_pocket_120x85():
    import matplotlib.pyplot as plt

    levels, pocket = ky.offset_levels(), ky.pocket()
    fig, ax = plt.subplots(figsize=figsize(1.1, 1.2))
    ax.fill(*pocket.exterior.xy, color="0.9")
    for ring in pocket.interiors:
        ax.fill(*ring.xy, color="white")
    for k, loops in enumerate(levels):
        for lp in loops:
            ax.plot(lp[:, 0], lp[:, 1], color=plt.cm.viridis(k / len(levels)), lw=1)
    ax.set(aspect="equal", xlabel="x [mm]", ylabel="y [mm]",
           title=f"{len(levels)} offset levels, loops per level {[len(lv) for lv in levels]}")
    return fig


def draw(name: str, style=None):
    """Draw figure ``name`` under ``style`` (a style-sheet path or name; default the collection's)."""
    import matplotlib.pyplot as plt

    if name not in FIGURES:
        raise ValueError(f"unknown figure {name!r}: covered are {', '.join(sorted(FIGURES))}")
    with plt.style.context(str(style or STYLE_PATH)):
        return FIGURES[name].draw()


def render(name: str, outdir=None, *, width_mm=None, height_mm=None, formats=("pdf",), dpi: int = 300,
           style=None) -> list[Path]:
    """Draw figure ``name`` and export it (:func:`cnclab.plotting.export_figure`) into ``outdir``
    (default ``build/paper/<work>/``); returns the written paths."""
    import matplotlib.pyplot as plt

    fig = draw(name, style)
    try:
        outdir = Path(outdir) if outdir is not None else build_dir() / "paper" / FIGURES[name].work
        return export_figure(fig, name, outdir, width_mm=width_mm, height_mm=height_mm, formats=formats,
                             dpi=dpi, style=style)
    finally:
        plt.close(fig)


def _size(text: str):
    if text in WIDTH_PRESETS_MM:
        return text
    return clihelp.number("--width-mm/--height-mm", 0, hi=5000)(text)


def main(argv=None) -> int:
    ap = clihelp.parser(
        "python -m cnclab figure",
        "Re-render a figure of the collection from its recipe (no notebook is run) at a journal width,\n"
        "in the formats and resolution a paper needs, under the collection's style sheet or your own.\n"
        "Widths: a number of mm or 'column' (85 mm) / 'page' (175 mm); the height keeps the figure's\n"
        "aspect ratio unless given. --list shows the figures covered.",
        examples=["python -m cnclab figure fig3-1_engagement_vs_stepover --width-mm 85 --format pdf -o build/paper",
                  "python -m cnclab figure fig6-2_main_effects --width-mm page --height-mm 60 --format pdf,png "
                  "--dpi 600", "python -m cnclab figure --list"],
        writes=["DIR/NAME.FORMAT for every format (default DIR: build/paper/<work>)"])
    ap.add_argument("names", nargs="*", metavar="NAME", help="figure name(s), see --list")
    ap.add_argument("--list", action="store_true", help="list the figures that have a recipe")
    ap.add_argument("--width-mm", type=_size, default=None,
                    help="page width: mm, 'column' (85) or 'page' (175) (default: the figure's own size, cropped)")
    ap.add_argument("--height-mm", type=_size, default=None, help="page height in mm (default: keep the aspect ratio)")
    ap.add_argument("--format", default="pdf", help="comma-separated formats: pdf, svg, png, eps, ...")
    ap.add_argument("--dpi", type=clihelp.number("--dpi", 10, lo_open=False, hi=10000, kind=int), default=300,
                    help="resolution of raster formats (dots per inch)")
    ap.add_argument("--style", default=None,
                    help="matplotlib style sheet (path or name) (default: cnclab/paper.mplstyle)")
    ap.add_argument("-o", "--outdir", default=None, help="output folder (default: build/paper/<work>)")
    args = ap.parse_args(argv)
    if args.list or not args.names:
        for name, rec in sorted(FIGURES.items()):
            print(f"{name:<34} {rec.work:<13} {rec.description}")
        return 0 if args.list else 2
    formats = tuple(f.strip() for f in args.format.split(",") if f.strip())
    if args.height_mm is not None and args.width_mm is None:
        ap.error("--height-mm needs --width-mm")
    written = []
    try:
        for name in args.names:
            written += render(name, args.outdir, width_mm=args.width_mm, height_mm=args.height_mm, formats=formats,
                              dpi=args.dpi, style=args.style)
    except (ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print("wrote " + ", ".join(str(p) for p in written))
    return 0
