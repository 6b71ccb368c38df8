"""Figure recipes of Mgherony (2024) chapters 7-9: spindle-speed control on the STL + APT files (ch. 7), the
feed directions of the free-form part (ch. 8) and the tool-path reordering (ch. 9).

Each recipe runs the chapter's pipeline of :mod:`cnclab.works.mgherony2024.ch7_9` (files written into
``build/mgherony2024/`` and read back; 0.5 mm STL cell and CL step, or 1 mm in fast mode) and draws
one figure; the ch. 7-9 notebooks call the same recipes (``python -m cnclab figure --list``). Sizes are
in units of the style's ``figure.figsize`` (:func:`cnclab.plotting.figsize`).

>>> sorted(n for n in FIGURES if n.startswith("fig8-"))
['fig8-1_test_part_reconstruction', 'fig8-3_controlled_n_five_directions', 'fig8-4_spindle_integral']
"""
from __future__ import annotations

import numpy as np

from ...geometry.mesh import read_stl
from ...nc import apt
from ...paths import data_path
from ...plotting import FIGURES, draw_figure as draw, figsize, plan_view, register_figure as _register
from . import ch7_9

__all__ = ["FIGURES", "draw"]


# --------------------------------------------------------------------------------------- chapter 7
@_register("fig7-10_7-11_stl_apt", "mgherony2024",
           "Mgherony (2024) Figs 7-10, 7-11: the test part STL (facet centroids) and the A_f = 0 APT feed points")
def fig7_10_7_11_stl_apt():
    import matplotlib.pyplot as plt

    mesh = read_stl(ch7_9.part_stl())
    cl = apt.read_apt(ch7_9.zigzag_apt(0.0)).cl_points()
    fig, axs = plt.subplots(1, 2, figsize=figsize(1.65, 1.05))
    c = mesh.centroids
    axs[0].tripcolor(c[:, 0], c[:, 1], c[:, 2], shading="gouraud")
    axs[0].set(title="STL facet centroids, z (Fig 7-10)")
    f = ~cl.rapid
    axs[1].scatter(cl.xyz[f, 0], cl.xyz[f, 1], c=cl.xyz[f, 2], s=0.5)
    axs[1].set(title="APT feed points (Fig 7-11)")
    plan_view(axs)
    return fig


@_register("fig7-12_7-15_deff_vc_constant_n", "mgherony2024",
           "Mgherony (2024) Figs 7-12 ... 7-15: working diameter and v_c at constant n = 2000 rpm (A_f = 0)")
def fig7_12_7_15_deff_vc_constant_n():
    import matplotlib.pyplot as plt

    s0 = ch7_9.schedule(0.0)
    vc_2000 = np.pi * s0.d_eff * ch7_9.parameters()["table7_1"]["n"] / 1000      # m/min
    fig, axs = plt.subplots(2, 2, figsize=figsize(1.65, 1.6), layout="constrained")
    axs[0, 0].plot(s0.d_eff, lw=0.4)
    axs[0, 0].set(title="Fig 7-12: working diameter", ylabel="D_eff [mm]", xlabel="feed point")
    axs[0, 1].plot(vc_2000, lw=0.4)
    axs[0, 1].set(title="Fig 7-13: v_c at n = 2000", ylabel="v_c [m/min]", xlabel="feed point")
    axs[1, 0].scatter(s0.A_N2, s0.d_eff, s=1)
    axs[1, 0].set(title="Fig 7-14", xlabel="A_N2 [deg]", ylabel="D_eff [mm]")
    axs[1, 1].scatter(s0.A_N2, vc_2000, s=1)
    axs[1, 1].set(title="Fig 7-15", xlabel="A_N2 [deg]", ylabel="v_c [m/min]")
    return fig


@_register("fig7-16_7-18_controlled", "mgherony2024",
           "Mgherony (2024) Figs 7-16 ... 7-18: v_f and n written into the controlled APT, the resulting v_c")
def fig7_16_7_18_controlled():
    import matplotlib.pyplot as plt

    s0 = ch7_9.schedule(0.0)
    back = apt.read_apt(ch7_9.controlled_apt(0.0)).cl_points()       # the written program read back
    fb = ~back.rapid
    vc_file = np.pi * s0.d_eff * back.spindle[fb] / 1000                # m/min
    fig, axs = plt.subplots(1, 3, figsize=figsize(2, 0.85), layout="constrained")
    axs[0].plot(back.feed[fb], lw=0.5)
    axs[0].set(title="Fig 7-16\nv_f in the file", ylabel="mm/min")
    axs[1].plot(back.spindle[fb], lw=0.5)
    axs[1].set(title="Fig 7-17\nn in the file", ylabel="rpm")
    axs[2].scatter(s0.A_N2, vc_file, s=1)
    axs[2].set(title="Fig 7-18\nresulting v_c", xlabel="A_N2 [deg]", ylabel="m/min", ylim=(55, 70))
    return fig


# --------------------------------------------------------------------------------------- chapter 8
@_register("fig8-1_test_part_reconstruction", "mgherony2024",
           "Mgherony (2024) Fig 8-1: height map of the reconstructed free-form test part")
def fig8_1_test_part_reconstruction():
    import matplotlib.pyplot as plt

    part = ch7_9.part()
    x, y = np.meshgrid(np.linspace(0, 50, 201), np.linspace(0, 50, 201))     # mm, the 50 x 50 mm part
    fig, ax = plt.subplots(figsize=figsize(0.75, 1), layout="constrained")
    cs = ax.contourf(x, y, part.height_at(x, y), 20)
    fig.colorbar(cs, label="z [mm]")
    plan_view(ax, title="Reconstructed test part (Fig 8-1)")
    return fig


@_register("fig8-3_controlled_n_five_directions", "mgherony2024",
           "Mgherony (2024) Fig 8-3: controlled spindle speed along the path for the five feed directions")
def fig8_3_controlled_n_five_directions():
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(2, 3, figsize=figsize(1.6, 1.3), sharey=True, layout="constrained")
    fig.delaxes(axs[1, 2])                                 # five directions on a 2 x 3 grid
    for ax, a in zip(axs.flat, ch7_9.DIRECTIONS):
        s = ch7_9.schedule(a)
        ax.plot(np.cumsum(s.seg_len), s.n, lw=0.4)
        ax.set(title=f"A_f = {a:g}°", xlabel="path [mm]")
    for ax in axs[:, 0]:
        ax.set_ylabel("n [rpm]")
    return fig


@_register("fig8-4_spindle_integral", "mgherony2024",
           "Mgherony (2024) Fig 8-4: integral of the spindle speed along the path, controlled vs constant n")
def fig8_4_spindle_integral():
    import matplotlib.pyplot as plt

    tab = ch7_9.direction_table("thesis")
    fig, ax = plt.subplots(figsize=figsize(0.85, 0.8))
    ax.bar(tab.A_f.astype(str), tab.integral_controlled / 1e6, label="controlled")
    ax.bar(tab.A_f.astype(str), tab.integral_constant / 1e6, alpha=0.6, label="constant n = 2000")
    ax.set(xlabel="A_f [deg]", ylabel="∫ n ds [10^6 rpm·mm]", title="Fig 8-4 (reconstruction)")
    ax.legend()
    return fig


# --------------------------------------------------------------------------------------- chapter 9
@_register("fig9-5_9-6_points_original_path", "mgherony2024",
           "Mgherony (2024) Figs 9-5, 9-6: original CL points, the densified point cloud and the original path")
def fig9_5_9_6_points_original_path():
    import matplotlib.pyplot as plt

    orig = apt.read_apt(ch7_9.ch9_original_apt()).cl_points()
    P0 = orig.xyz[~orig.rapid]
    _, dense, _ = ch7_9.reorder_cases()
    fig, axs = plt.subplots(1, 3, figsize=figsize(2.15, 1.1))
    axs[0].scatter(P0[:, 0], P0[:, 1], s=0.5)
    axs[0].set(title="Fig 9-5a\noriginal points")
    axs[1].scatter(dense[:, 0], dense[:, 1], s=0.2)
    axs[1].set(title="Fig 9-5b\nextended point cloud")
    axs[2].plot(dense[:, 0], dense[:, 1], lw=0.3)
    axs[2].set(title="Fig 9-6\noriginal path")
    plan_view(axs)
    return fig


@_register("fig9-7_reordered_paths", "mgherony2024",
           "Mgherony (2024) Fig 9-7: the reordered paths of the four Table 9-2 cases, jumps in red")
def fig9_7_reordered_paths():
    import matplotlib.pyplot as plt

    cases, dense, orders = ch7_9.reorder_cases()
    fig, axs = plt.subplots(2, 2, figsize=figsize(1.3, 1.9), sharex=True, sharey=True, layout="constrained")
    for ax, case in zip(axs.flat, (1, 3, 2, 4)):
        r = orders[case]
        Q = dense[r.order]
        ax.plot(Q[:, 0], Q[:, 1], lw=0.3)
        J = np.flatnonzero(r.jump)
        ax.plot(np.c_[Q[J - 1, 0], Q[J, 0]].T, np.c_[Q[J - 1, 1], Q[J, 1]].T, "r-", lw=0.4)
        row = cases.set_index("case").loc[case]
        ax.set(title=f"case {case}: start {row.start}, k = {row.k}", aspect="equal")
    return fig


@_register("fig9-8_distance_jumps", "mgherony2024",
           "Mgherony (2024) Fig 9-8: travelling distance and jump points of the original path and the four cases")
def fig9_8_distance_jumps():
    import matplotlib.pyplot as plt

    cases, _, _ = ch7_9.reorder_cases()
    fig, axs = plt.subplots(1, 2, figsize=figsize(1.5, 0.8))
    axs[0].bar(cases.case.astype(str), cases.distance_mm)
    axs[0].set(title="Fig 9-8a: travelling distance", ylabel="mm")
    axs[1].bar(cases.case.astype(str)[1:], cases.jumps[1:])
    axs[1].set(title="Fig 9-8b: jump points")
    return fig


@_register("fig9-8b_jumps_per_reading", "mgherony2024",
           "Mgherony (2024) Fig 9-8b: jump points under each reading of the §9 neighbour and D_eff rules")
def fig9_8b_jumps_per_reading():
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    readings = ch7_9.reorder_readings()
    fig, ax = plt.subplots(figsize=figsize(1.65, 0.85))
    piv = readings.pivot_table(index="reading", columns="k", values="jumps", sort=False)
    piv.plot.barh(ax=ax, logx=True)
    ax.xaxis.set_minor_formatter(NullFormatter())          # decade labels only: minor ones crowd a column
    ax.set(xlabel="jumps (mean of the two start points)", ylabel="")
    return fig


@_register("fig9-9_9-12_delta_deff_n", "mgherony2024",
           "Mgherony (2024) Figs 9-9 ... 9-12: |ΔD_eff| and |Δn| between consecutive points, original vs case 1")
def fig9_9_9_12_delta_deff_n():
    import matplotlib.pyplot as plt

    d_orig, d_opt = ch7_9.deltas("original"), ch7_9.deltas(1)
    fig, axs = plt.subplots(2, 2, figsize=figsize(1.85, 1.45), sharey="row", layout="constrained")
    axs[0, 0].plot(d_orig["dD"], lw=0.4)
    axs[0, 0].set(title="Fig 9-9: original", ylabel="|ΔD_eff| [mm]")
    axs[0, 1].plot(d_opt["dD"], lw=0.4)
    axs[0, 1].set(title="Fig 9-10: reordered (case 1)")
    axs[1, 0].plot(d_orig["dn"], lw=0.4)
    axs[1, 0].set(title="Fig 9-11: original", ylabel="|Δn| [rpm]", xlabel="step")
    axs[1, 1].plot(d_opt["dn"], lw=0.4)
    axs[1, 1].set(title="Fig 9-12: reordered (case 1)", xlabel="step")
    return fig


# ------------------------------------------------------------------ 3D views (static versions for papers)
def _part_3d(ax, mesh):
    """The sample part (STL triangles, mm) as a light grey surface in a 3D axes."""
    from matplotlib.ticker import MaxNLocator
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    ax.add_collection3d(Poly3DCollection(np.asarray(mesh.triangles, float), facecolor="0.85", edgecolor="none",
                                         alpha=0.6))
    lo, hi = mesh.triangles.reshape(-1, 3).min(axis=0), mesh.triangles.reshape(-1, 3).max(axis=0)
    ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]), xlabel="x [mm]", ylabel="y [mm]",
           zlabel="z [mm]")
    ax.set_box_aspect(hi - lo)
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(MaxNLocator(3))


def _path_3d(xyz, values, label: str, title: str):
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=figsize(1.0, 1.2), layout="constrained")
    ax = fig.add_subplot(projection="3d")
    _part_3d(ax, read_stl(data_path("mgherony2024", "sample_ch8_part.stl")))   # the light 2 mm sample STL
    sc = ax.scatter(xyz[:, 0], xyz[:, 1], xyz[:, 2] + 0.5, c=values, s=0.3, depthshade=False)   # 0.5 mm lift
    fig.colorbar(sc, ax=ax, label=label, shrink=0.6)
    ax.set_title(title)
    return fig


@_register("ch7_3d_cl_path_deff", "mgherony2024",
           "Mgherony (2024) ch. 7: the A_f = 0 CL path on the part, coloured by the working diameter (3D)")
def ch7_3d_cl_path_deff():
    s0 = ch7_9.schedule(0.0)
    return _path_3d(s0.xyz, s0.d_eff, "D_eff [mm]", "A_f = 0: CL path coloured by D_eff")


@_register("ch8_3d_spindle_speed_Af45", "mgherony2024",
           "Mgherony (2024) ch. 8: the A_f = 45° CL path on the part, coloured by the controlled spindle speed (3D)")
def ch8_3d_spindle_speed_af45():
    s45 = ch7_9.schedule(45.0)
    return _path_3d(s45.xyz, s45.n, "n [rpm]", "A_f = 45°: controlled spindle speed")


@_register("ch9_3d_reordered_case1", "mgherony2024",
           "Mgherony (2024) ch. 9: the case 1 reordered path on the part, feed moves and jumps (3D)")
def ch9_3d_reordered_case1():
    import matplotlib.pyplot as plt

    _, dense, orders = ch7_9.reorder_cases()
    r = orders[1]
    Q = dense[r.order] + [0.0, 0.0, 0.3]                    # 0.3 mm lift above the surface
    feed = Q.copy()
    feed[r.jump] = np.nan                                   # break the line at each jump
    fig = plt.figure(figsize=figsize(1.0, 1.2), layout="constrained")
    ax = fig.add_subplot(projection="3d")
    _part_3d(ax, read_stl(data_path("mgherony2024", "sample_ch8_part.stl")))
    ax.plot(*feed.T, lw=0.4, label="feed moves")
    J = [i for i in np.flatnonzero(r.jump) if i > 0]
    for k, i in enumerate(J):
        ax.plot(*Q[[i - 1, i]].T, "--", color="C3", lw=0.6, label=f"jumps ({len(J)})" if k == 0 else None)
    ax.set_title("Case 1 (corner, k = 4): reordered path")
    ax.legend(loc="upper left", fontsize="small")
    return fig
