"""Recipes for Mgherony (2024) chapters 7-9 and Theses 3-5: spindle-speed control on STL + APT files,
the chapter 8 free-form test part, and tool-path reordering.

Every pipeline recipe writes its files (STL, APT) into ``build/mgherony2024/`` and reads them back,
so the numbers come from real files. Resolution: STL grid cell and CL point step are 0.5 mm (full)
or 1.0 mm (``CNCLAB_FAST=1``); the claims use the full resolution (ledger rows marked slow).
Transcribed inputs: ``data/mgherony2024/ch7_9_parameters.json``.
"""
from __future__ import annotations

import functools
import json

import numpy as np
import pandas as pd

from ...cache import cached
from ...claims import Interval
from ...cutting.speeds import cutting_speed, feed_speed, spindle_speed
from ...cutting.spindle_model import feed_directions, working_diameters
from ...geometry.ball_end import horizontal_effective_diameter, tangent_point_diameters
from ...geometry.freeform_part import FreeformPart, freeform_part_mesh
from ...geometry.mesh import FacetLocator, machined_surface_mask, read_stl, write_stl
from ...nc import apt
from ...nc.apt import reordered_program
from ...nc.spindle_control import postprocess_files, spindle_schedule
from ...paths import build_dir, data_path
from ...runtime import pick
from ...sweep import sweep
from ...toolpath.dropcutter import split_passes, zigzag_finishing_path
from ...toolpath.reorder import ReorderResult, densify, path_metrics, reorder_path

DIRECTIONS = (0.0, 22.5, 45.0, 67.5, 90.0)


@functools.cache
def parameters() -> dict:
    """The transcribed chapter 7-9 inputs and printed values (JSON with provenance)."""
    return json.loads(data_path("mgherony2024", "ch7_9_parameters.json").read_text())


def part() -> FreeformPart:
    """The reconstructed chapter 8 test part (see :mod:`cnclab.geometry.freeform_part`)."""
    p = parameters()["ch8_part"]
    return FreeformPart(p["size"], p["size"], p["sphere_radius"], p["torus_radius"], p["height"])


def _out(name):
    d = build_dir() / "mgherony2024"
    d.mkdir(parents=True, exist_ok=True)
    return d / name


@functools.cache
def part_stl(cell_mm: float | None = None) -> str:
    """Write the closed test part as a binary STL into build/ (grid cell mm) and return its path."""
    cell = pick(0.5, 1.0) if cell_mm is None else cell_mm
    path = _out(f"ch8_test_part_cell{cell:g}.stl")
    write_stl(path, freeform_part_mesh(part(), cell, closed=True))
    return str(path)


@functools.cache
def surface_mesh(cell_mm: float | None = None):
    """The machined surface of the STL read back from disk (side/bottom facets removed, Sec. 7.2.3)."""
    m = read_stl(part_stl(cell_mm))
    return m.subset(machined_surface_mask(m.normals))


@functools.cache
def zigzag_apt(feed_angle_deg: float, a_e: float = 0.25, step_mm: float | None = None,
               cell_mm: float | None = None) -> str:
    """Drop-cut zig-zag finishing CL file (D = 10 ball) at A_f, written to build/; returns its path."""
    step = pick(0.5, 1.0) if step_mm is None else step_mm
    tp = parameters()["table7_1"]
    passes = split_passes(zigzag_finishing_path(surface_mesh(cell_mm), tp["D"], a_e, feed_angle_deg, step=step,
                                                feed_mm_min=tp["v_f"]))
    prog = apt.cl_program(passes, tp["v_f"], tp["n"], tp["D"], clearance_z=30.0,
                          partno=f"CH8_AF{feed_angle_deg:g}")
    path = _out(f"ch8_zigzag_Af{feed_angle_deg:g}_ae{a_e:g}_step{step:g}.apt")
    apt.write_apt(path, prog)
    return str(path)


def sample_ch8_apt() -> apt.AptProgram:
    """The committed sample CL file ``data/mgherony2024/sample_ch8_zigzag_Af0.apt`` (its recipe): the
    test part on a 2 mm grid, drop-cut zig-zag (D = 10 ball, a_e = 1 mm, A_f = 0, 2 mm step), Table 7-1
    n and v_f, approach at Z30 and feed down (:func:`cnclab.nc.apt.cl_program`)."""
    tp = parameters()["table7_1"]
    passes = split_passes(zigzag_finishing_path(surface_mesh(2.0), tp["D"], 1.0, 0.0, step=2.0))
    return apt.cl_program(passes, tp["v_f"], tp["n"], tp["D"], clearance_z=30.0, partno="SAMPLE_CH8_AF0")


def write_sample_ch8_apt(path=None):
    """Regenerate the sample CL file (default: its place in data/mgherony2024/) atomically."""
    return apt.write_apt(path or data_path("mgherony2024", "sample_ch8_zigzag_Af0.apt"), sample_ch8_apt())


@functools.cache
def schedule(feed_angle_deg: float, point: str = "thesis", a_e: float = 0.25, accel_rpm_s: float | None = None):
    """Post-process the A_f zig-zag (read from disk) against the STL (read from disk), Table 7-1 data."""
    tp = parameters()["table7_1"]
    cl = apt.read_apt(zigzag_apt(feed_angle_deg, a_e)).cl_points()
    return spindle_schedule(read_stl(part_stl()), cl, tool_diameter=tp["D"], a_p=tp["a_p"], v_c=tp["v_c"],
                            f_z=tp["f_z"], teeth=tp["teeth"], feed_direction_deg=feed_angle_deg, point=point,
                            accel_rpm_s=accel_rpm_s)


@functools.cache
def controlled_apt(feed_angle_deg: float = 0.0, point: str = "thesis") -> str:
    """Post-process the A_f zig-zag APT (read from disk) against the STL with Table 7-1 data, as
    ``python -m cnclab spindle STL APT -o OUT --vc 63 --fz 0.125 --teeth 2 --ap 0.3 --feed-direction A_f
    --point thesis`` does (:func:`cnclab.nc.spindle_control.postprocess_files`); write the controlled APT
    into build/ and return its path (Figs 7-16 ... 7-18 read it back)."""
    tp = parameters()["table7_1"]
    out = _out(f"ch7_Af{feed_angle_deg:g}_{point}_controlled_recipe.apt")
    postprocess_files(part_stl(), zigzag_apt(feed_angle_deg), out, v_c=tp["v_c"], f_z=tp["f_z"], teeth=tp["teeth"],
                      a_p=tp["a_p"], feed_direction_deg=feed_angle_deg, point=point)
    return str(out)


def direction_table(point: str = "thesis") -> pd.DataFrame:
    """Chapter 8 per-direction results on the reconstruction vs the printed minima/maxima."""
    p = parameters()
    rows = []
    for k, a in enumerate(DIRECTIONS):
        s = schedule(a, point)
        const = np.full_like(s.n, p["table7_1"]["n"])
        rows.append({"A_f": a, "n_min": s.n.min(), "n_min_paper": p["ch8_n_min"][k], "n_max": s.n.max(),
                     "n_max_paper": p["ch8_n_max"][k], "path_mm": s.path_length,
                     "integral_controlled": s.spindle_integral(), "integral_constant": s.spindle_integral(const),
                     "points": len(s.n)})
    df = pd.DataFrame(rows)
    df["D_eff_implied_by_paper_n_min"] = 1000 * p["table7_1"]["v_c"] / (np.pi * df.n_min_paper)
    df["D_eff_implied_by_paper_n_max"] = 1000 * p["table7_1"]["v_c"] / (np.pi * df.n_max_paper)
    return df


# ------------------------------------------------------------------------------ claims: chapter 7
def nominal_feed_mm_min() -> float:
    """Table 7-1: v_f = f_z z n (eq 7-5) at n = 2000 rpm."""
    t = parameters()["table7_1"]
    return float(feed_speed(t["f_z"], t["teeth"], t["n"]))


def nominal_vc_m_min() -> float:
    """Table 7-1: v_c at the nominal diameter D = 10 mm and n = 2000 rpm (eq 5-6)."""
    t = parameters()["table7_1"]
    return float(cutting_speed(t["D"], t["n"]))


def horizontal_n_rpm() -> float:
    """n on the horizontal area: eq 7-4 at D_eff = 2 sqrt(a_p (D - a_p)) (the maximum spindle speed)."""
    t = parameters()["table7_1"]
    return float(spindle_speed(t["v_c"], horizontal_effective_diameter(t["D"], t["a_p"])))


def horizontal_vf_mm_min() -> float:
    """Maximum feed: eq 7-5 at the horizontal-area spindle speed."""
    t = parameters()["table7_1"]
    return float(feed_speed(t["f_z"], t["teeth"], horizontal_n_rpm()))


def vc_min_at_2000() -> float:
    """Lowest actual cutting speed at constant n = 2000 rpm (horizontal area), m/min."""
    t = parameters()["table7_1"]
    return float(cutting_speed(horizontal_effective_diameter(t["D"], t["a_p"]), t["n"]))


@functools.cache
def analytic_deff_range(feed_angle_deg: float = 0.0, point: str = "max") -> tuple[float, float]:
    """(min, max) working diameter (mm) over the reconstructed part's exact normals (fine grid)."""
    P = part()
    x, y = np.meshgrid(np.linspace(0, 50, 401), np.linspace(0, 50, 401))
    nrm = P.normal_at(x.ravel(), y.ravel())
    t = parameters()["table7_1"]
    d, _, _ = working_diameters(nrm, np.full(len(nrm), feed_angle_deg), t["D"], t["a_p"], point, feed_angle_deg)
    return float(d.min()), float(d.max())


def vc_max_at_2000() -> float:
    """Highest actual cutting speed at n = 2000 rpm, A_f = 0, on the reconstructed part (m/min)."""
    return float(cutting_speed(analytic_deff_range(0.0)[1], parameters()["table7_1"]["n"]))


def vf_min_reconstruction() -> float:
    """Lowest controlled feed (eq 7-5) on the reconstructed part, A_f = 0 (mm/min)."""
    t = parameters()["table7_1"]
    n_min = spindle_speed(t["v_c"], analytic_deff_range(0.0)[1])
    return float(feed_speed(t["f_z"], t["teeth"], n_min))


def vf_min_from_printed_n_min() -> float:
    """Explanation: the printed 750 mm/min is eq 7-5 applied to the thesis's printed n_min = 3002 rpm."""
    t = parameters()["table7_1"]
    return float(feed_speed(t["f_z"], t["teeth"], parameters()["ch7_text"]["n_min"]))


def horizontal_deff_mm() -> float:
    """Working diameter on the horizontal area (mm): 3.41 for D = 10, a_p = 0.3."""
    t = parameters()["table7_1"]
    return float(horizontal_effective_diameter(t["D"], t["a_p"]))


def horizontal_working_radius_mm() -> float:
    """Explanation of "about 1.5 mm" (Sec. 7.3): the working *radius* (Fig 7-12 plots radii, as ch. 5)."""
    return horizontal_deff_mm() / 2.0


# ------------------------------------------------------------------------------ claims: chapter 8
def ch8_n_max_pipeline() -> dict:
    """Maximum controlled spindle speed per feed direction from the STL + APT pipeline (rpm)."""
    return {f"{a:g}": float(schedule(a).n.max()) for a in (0.0, 90.0)}


def rz_cross_checks() -> dict:
    """Ratios (%) computable from in-text Rz values (Sec. 8.3) to check Thesis 4's ranges."""
    rz = parameters()["ch8_rz"]
    return {"mean_overall": 100 * rz["ctrl_mean"] / rz["const_mean"],
            "sd_overall": 100 * rz["ctrl_sd"] / rz["const_sd"],
            "mean_0deg": 100 * rz["ctrl_mean_0deg"] / rz["const_mean_0deg"]}


# ------------------------------------------------------------------------------ chapter 9
def ch9_original_apt(step_mm: float | None = None) -> str:
    """The chapter 9 original path (Table 9-1: a_e = 0.5, A_f = 90; CL step 2 mm, 4 mm fast) as an APT file in build/."""
    t = parameters()["table9_1"]
    return zigzag_apt(t["A_f"], t["a_e"], pick(2.0, 4.0) if step_mm is None else step_mm)


@functools.cache
def ch9_points(step_mm: float | None = None):
    """The chapter 9 point cloud: the original path (read from its APT file) densified to d_lim = a_e
    (eqs 9-1 ... 9-3), each point's nearest-centroid STL normal, and the corner / middle start indices.

    Returns ``(dense (N, 3) mm, normals (N, 3), {"corner": i, "middle": j})``.
    """
    t = parameters()["table9_1"]
    cl = apt.read_apt(ch9_original_apt(step_mm)).cl_points()
    dense, _ = densify(cl.xyz[~cl.rapid], t["a_e"])
    mesh = surface_mesh()
    nrm = mesh.normals[FacetLocator(mesh).nearest_centroid(dense)]
    starts = {"corner": int(np.argmin(np.linalg.norm(dense[:, :2] - [50.0, 50.0], axis=1))),
              "middle": int(np.argmin(np.linalg.norm(dense[:, :2] - [25.0, 25.0], axis=1)))}
    return dense, nrm, starts


def original_deff(direction: str = "move", step_mm: float | None = None) -> np.ndarray:
    """D_eff (mm) along the original path: A_f = direction of each move ("move") or 90 deg ("constant")."""
    t = parameters()["table9_1"]
    dense, nrm, _ = ch9_points(step_mm)
    af = np.full(len(dense), float(t["A_f"])) if direction == "constant" else feed_directions(dense)
    return working_diameters(nrm, af, t["D"], t["a_p"], "max")[0]


@cached()
def reorder_path_job(dense, nrm, D, a_p, k, start, A_f, direction, neighbours, a_e):
    """One reordering of :func:`reorder_cases` (a module-level function: a sweep item), cached on disk
    (build/cache, keyed by the code and the arguments): the notebook, the figure recipes and the
    claims report each need the same 24 reorderings of the six readings, in different processes."""
    return reorder_path(dense, nrm, tool_diameter=D, a_p=a_p, k=k, start=start, feed_direction_deg=A_f,
                        direction=direction, neighbours=neighbours, radius_step=a_e,
                        adjacent_mm=1.5 * a_e if neighbours == "unvisited" else None)


@functools.cache
def reorder_cases(direction: str = "move", step_mm: float | None = None, neighbours: str = "knn"):
    """Original vs reordered metrics for the four Table 9-2 cases on the reconstruction (a_e = 0.5, A_f = 90).

    Default = the Sec. 9.2 reading: k nearest neighbours (visited ones tabu), D_eff of a neighbour for
    the direction of the move to it. Returns ``(table, dense points, {case: ReorderResult})``.
    """
    t = parameters()["table9_1"]
    dense, nrm, starts = ch9_points(step_mm)
    d0 = original_deff(direction, step_mm)
    rows = [{"case": "original", "start": "-", "k": "-", **path_metrics(dense, d0, t["v_c"])}]
    orders = {"original": ReorderResult(np.arange(len(dense)), np.zeros(len(dense), bool), d0)}
    cases = [("corner", 4), ("middle", 4), ("corner", 8), ("middle", 8)]
    runs = sweep(reorder_path_job, [(dense, nrm, t["D"], t["a_p"], k, starts[where], t["A_f"], direction,
                                     neighbours, t["a_e"]) for where, k in cases])
    for case, ((where, k), r) in enumerate(zip(cases, runs), start=1):
        orders[case] = r
        rows.append({"case": case, "start": starts[where], "k": k,
                     **path_metrics(dense[r.order], r.d_eff, t["v_c"], jump=r.jump)})
    return pd.DataFrame(rows), dense, orders


def move_statistics(dense, result, a_e: float) -> dict:
    """Shape of a reordered path: jumps, non-adjacent feed moves (> 1.5 a_e, 3D), share of diagonal
    feed moves (direction nearer 45 deg than an axis), share of straight continuations (two
    consecutive feed moves turning < 10 deg), mean feed step (mm), and the share of jumps that land
    on a dead end (the next move is a jump again: an isolated point left behind)."""
    Q = dense[result.order]
    v = np.diff(Q, axis=0)
    L = np.linalg.norm(v, axis=1)
    feed = ~result.jump[1:]
    h = np.arctan2(v[:, 1], v[:, 0])
    diag = np.abs(np.degrees(h) % 90.0 - 45.0) < 22.5
    j = result.jump
    turn = np.abs(np.angle(np.exp(1j * np.diff(h))))
    both = feed[1:] & feed[:-1]
    return {"jumps": int(j.sum()), "long_feed_moves": int(np.sum(feed & (L > 1.5 * a_e))),
            "diagonal_share": float(diag[feed].mean()),
            "straight_share": float(np.mean(turn[both] < np.radians(10.0))),
            "mean_feed_step_mm": float(L[feed].mean()),
            "dead_end_share": float(np.sum(j[1:-1] & j[2:]) / max(1, j.sum())),
            "distance_mm": float(L.sum())}


READINGS = {  # name: (neighbour rule, D_eff direction rule)
    "thesis: k-NN, D_eff per move": ("knn", "move"),
    "k-NN, D_eff at constant A_f": ("knn", "constant"),
    "radius steps of a_e, per move": ("radius", "move"),
    "radius steps of a_e, constant A_f": ("radius", "constant"),
    "k unvisited, per move": ("unvisited", "move"),
    "k unvisited, constant A_f": ("unvisited", "constant"),
}


@functools.cache
def reorder_readings(step_mm: float | None = None) -> pd.DataFrame:
    """The Table 9-2 experiment under six readings of Sec. 9.2 (``READINGS``): one row per
    (reading, case) with :func:`move_statistics`, the |Delta D_eff| / |Delta n| maxima (jumps excluded)
    and the same maxima of the original path under that reading's D_eff rule. For "k unvisited" the
    neighbour set is never empty, so a jump is a move to a point farther than 1.5 a_e."""
    t = parameters()["table9_1"]
    rows = []
    for name, (nb, direction) in READINGS.items():
        table, dense, orders = reorder_cases(direction, step_mm, nb)
        tab = table.set_index("case")
        for case in (1, 2, 3, 4):
            rows.append({"reading": name, "case": case, "k": tab.loc[case, "k"],
                         **move_statistics(dense, orders[case], t["a_e"]),
                         "dD_max": tab.loc[case, "dD_max"], "dn_max": tab.loc[case, "dn_max"],
                         "dD_max_original": tab.loc["original", "dD_max"],
                         "dn_max_original": tab.loc["original", "dn_max"]})
    return pd.DataFrame(rows)


def reading_verdicts(step_mm: float | None = None) -> pd.DataFrame:
    """Per reading, which Table 9-2 / Sec. 9.3 qualitative claims hold on the reconstruction:
    more neighbours -> longer path (case 3 > 1 and 4 > 2), -> more jumps (same pairs), start point
    changes jumps by <= 10 % at equal k (1 vs 2, 3 vs 4), case 1 narrows max |Delta D_eff| and |Delta n|."""
    df = reorder_readings(step_mm).set_index(["reading", "case"])
    out = []
    for name in READINGS:
        r = df.loc[name]
        J, L = r["jumps"], r["distance_mm"]
        out.append({"reading": name, "jumps_k4": f"{J[1]}/{J[2]}", "jumps_k8": f"{J[3]}/{J[4]}",
                    "dist_k4": f"{L[1]:.0f}/{L[2]:.0f}", "dist_k8": f"{L[3]:.0f}/{L[4]:.0f}",
                    "longer_path": bool(L[3] > L[1] and L[4] > L[2]),
                    "more_jumps": bool(J[3] > J[1] and J[4] > J[2]),
                    "start_limited": bool(abs(J[1] - J[2]) <= 0.1 * J[1] and abs(J[3] - J[4]) <= 0.1 * J[3]),
                    "case1_narrows": bool(r.loc[1, "dD_max"] < r.loc[1, "dD_max_original"]
                                          and r.loc[1, "dn_max"] < r.loc[1, "dn_max_original"]),
                    "diag_share_k4": r.loc[[1, 2], "diagonal_share"].mean(),
                    "diag_share_k8": r.loc[[3, 4], "diagonal_share"].mean(),
                    "straight_share_k4": r.loc[[1, 2], "straight_share"].mean(),
                    "straight_share_k8": r.loc[[3, 4], "straight_share"].mean()})
    return pd.DataFrame(out).set_index("reading")


def deff_direction_spread(step_mm: float | None = None) -> dict:
    """Why the move reading keeps its heading: over the sloped points of the chapter 9 cloud, the median
    spread (max - min, mm) of D_eff over the 8 grid directions 0, 45, ..., 315 deg, against the median
    non-zero |Delta D_eff| between consecutive points of the original path at the constant A_f = 90."""
    t = parameters()["table9_1"]
    dense, nrm, _ = ch9_points(step_mm)
    slope = np.abs(nrm[:, 2]) < np.cos(np.radians(1.0))
    D = np.stack([working_diameters(nrm[slope], np.full(int(slope.sum()), a), t["D"], t["a_p"], "max")[0]
                  for a in np.arange(0.0, 360.0, 45.0)])
    adj = np.abs(np.diff(original_deff("constant", step_mm)))
    return {"sloped_share": float(slope.mean()), "direction_spread_median_mm": float(np.median(np.ptp(D, axis=0))),
            "adjacent_change_median_mm": float(np.median(adj[adj > 0]))}


def reordered_apt(case: int = 1, direction: str = "move") -> str:
    """Write the Table 9-2 ``case`` reordered path as an APT file into build/ (jumps: retract, rapid,
    plunge) and return its path; Table 9-1 feed and n = 2000 rpm."""
    t = parameters()["table9_1"]
    _, dense, orders = reorder_cases(direction)
    prog = reordered_program(dense, orders[case], feed_mm_min=t["v_f"], spindle_rpm=parameters()["table7_1"]["n"],
                             tool_diameter=t["D"], clearance_z=30.0, partno=f"CH9_CASE{case}")
    path = _out(f"ch9_reordered_case{case}_{direction}.apt")
    apt.write_apt(path, prog)
    return str(path)


def deltas(case="original", direction: str = "move") -> dict:
    """|Delta D_eff| (mm) and |Delta n| (rpm, eq 7-4 at v_c = 63) between consecutive points of the
    original or a reordered path (moves into jump points excluded, the tool lifts): Figs 9-9 ... 9-12."""
    t = parameters()["table9_1"]
    r = reorder_cases(direction)[2][case]
    n = spindle_speed(t["v_c"], np.maximum(r.d_eff, 1e-6))
    keep = ~r.jump[1:]
    return {"dD": np.abs(np.diff(r.d_eff))[keep], "dn": np.abs(np.diff(n))[keep]}


# ------------------------------------------------------------------------------ ledger completeness
def nominal_n_rpm() -> float:
    """Table 7-1 / Sec. 8.2: n from eq 7-4 at the nominal diameter D = 10 mm and v_c = 63 m/min (2005.3)."""
    t = parameters()["table7_1"]
    return float(spindle_speed(t["v_c"], t["D"]))


def feed_per_tooth_mm() -> float:
    """Table 7-1: f_z = v_f / (z n) (eq 7-5 inverted) from v_f = 500, z = 2, n = 2000."""
    t = parameters()["table7_1"]
    return float(t["v_f"] / (t["teeth"] * t["n"]))


def vf_peak_ratio() -> float:
    """Sec. 7.3 'three times greater than the nominal feed rate': max controlled v_f / 500."""
    return horizontal_vf_mm_min() / parameters()["table7_1"]["v_f"]


@functools.cache
def vc_controlled_range():
    """Fig 7-18: actual cutting speed (m/min) after control over the A_f = 0 pipeline, as an Interval."""
    v = schedule(0.0).v_c_actual
    return Interval(float(v.min()), float(v.max()))


def feed_direction_step_deg() -> float:
    """Sec. 8.2: the second of five equally spaced feed directions 0 ... 90 deg (90/4 = 22.5)."""
    d = parameters()["ch8_feed_directions"]
    return float(np.linspace(d[0], d[-1], len(d))[1])


def feed_direction_typo_deg() -> float:
    """Explanation of the printed '22 deg' (Sec. 8.2 list): 22.5 with the '.5' dropped."""
    return float(np.floor(feed_direction_step_deg()))


def path_length_difference_mm() -> float:
    """Sec. 8.2 'maximum difference in tool path length is 100 mm': 10383 - 10286 from the printed lengths."""
    L = parameters()["ch8_path_length"]
    return float(L["45"] - L["0"])


def thesis4_mean_ratio_hi_interval():
    """Thesis 4 highest per-direction mean-Rz ratio (%): the in-text extremes (controlled max 2.0 um and
    constant min 3.7 um, both at 0 deg) make the 0-deg ratio the highest; Interval over the rounding of
    the printed values to 0.1 um: [1.95/3.75, 2.05/3.65]."""
    rz = parameters()["ch8_rz"]
    c, k = rz["ctrl_mean_0deg"], rz["const_mean_0deg"]
    return Interval(100 * (c - 0.05) / (k + 0.05), 100 * (c + 0.05) / (k - 0.05))


def thesis4_mean_ratio_mixed_directions() -> float:
    """1.6 / 4.5 (%): controlled minimum (45 deg) over constant maximum (67.5 deg) -- different directions."""
    rz = parameters()["ch8_rz"]
    return 100 * rz["ctrl_mean_45deg"] / rz["const_mean_67_5deg"]


def table9_1_feed_mm_min() -> float:
    """Table 9-1 v_f = 500: eq 7-5 with f_z = 0.125, z = 2 (Table 7-1; Table 9-1 gives neither) at n = 2000."""
    t = parameters()["table7_1"]
    return float(feed_speed(t["f_z"], t["teeth"], t["n"]))


def start_point_height_mm(which: str = "corner") -> float:
    """z (mm) of the reconstructed part at the Sec. 9.3 start coordinates: 'corner' (50, 50), 'text' (28.5, 43.919)."""
    xy = (50.0, 50.0) if which == "corner" else tuple(parameters()["ch9_text"]["start_xyz_text"][:2])
    return float(part().height_at(*xy))


def ch9_delta_minima() -> dict:
    """min |Delta D_eff| (mm) and min |Delta n| (rpm) of the original path and of case 1 (Figs 9-9 ... 9-12)."""
    o, c = deltas("original"), deltas(1)
    return {"dD_original": float(o["dD"].min()), "dD_case1": float(c["dD"].min()),
            "dn_original": float(o["dn"].min()), "dn_case1": float(c["dn"].min())}


# ------------------------------------------------------------------------------ ledger audit (issue 13)
def n_min_reconstruction() -> float:
    """Lowest controlled spindle speed (rpm, eq 7-4) on the reconstructed part, A_f = 0: v_c = 63 at the
    largest working diameter over the exact normals (the printed 3002 needs the thesis's unpublished part)."""
    t = parameters()["table7_1"]
    return float(spindle_speed(t["v_c"], analytic_deff_range(0.0)[1]))


def vf_max_printed_mm_min() -> float:
    """Sec. 7.3's printed highest feed (1469 mm/min), restated as 'reaching 1500' in the same paragraph."""
    return float(parameters()["ch7_text"]["vf_max"])


def vf_ratio_from_printed() -> float:
    """Sec. 7.3 'three times greater than the nominal feed rate' from the printed numbers: 1469 / 500."""
    return float(parameters()["ch7_text"]["vf_max"] / parameters()["table7_1"]["v_f"])


def vc_nominal_from_printed_n() -> float:
    """v_c (m/min, eq 5-6) from Table 7-1's printed D = 10 mm and n = 2000 rpm: 62.83 (printed 63)."""
    t = parameters()["table7_1"]
    return float(cutting_speed(t["D"], t["n"]))


@functools.cache
def ch9_delta_maxima() -> dict:
    """max |Delta D_eff| (mm) and max |Delta n| (rpm) of the original path and of case 1 (Figs 9-9 ... 9-12),
    reconstruction, Sec. 9.2 reading, jump moves excluded."""
    o, c = deltas("original"), deltas(1)
    return {"dD_original": float(o["dD"].max()), "dD_case1": float(c["dD"].max()),
            "dn_original": float(o["dn"].max()), "dn_case1": float(c["dn"].max())}


def ch9_dn_max_reduction() -> float:
    """Thesis 5 / Sec. 9.3: case 1 max |Delta n| as a fraction of the original's, reconstruction (printed: 128/622)."""
    m = ch9_delta_maxima()
    return m["dn_case1"] / m["dn_original"]


def ch8_direction_reconstruction() -> dict:
    """Chapter 8 per-direction n_min, n_max (rpm) and path lengths (mm) of the STL + APT pipeline, keys
    ``n_min_<A_f>``, ``n_max_<A_f>``, ``path_<A_f>``, plus ``integral_diff_pct`` (max/min controlled
    spindle integral over the five directions, minus 1, in %)."""
    df = direction_table()
    out = {}
    for r in df.itertuples():
        out[f"n_min_{r.A_f:g}"] = float(r.n_min)
        out[f"n_max_{r.A_f:g}"] = float(r.n_max)
        out[f"path_{r.A_f:g}"] = float(r.path_mm)
    ig = df.integral_controlled
    out["integral_diff_pct"] = float(100 * (ig.max() / ig.min() - 1))
    return out


def ch9_reorder_reconstruction() -> dict:
    """Table 9-2 on the reconstruction (Sec. 9.2 reading): ``case<k>.distance`` (mm) and ``case<k>.jumps``."""
    tab = reorder_cases()[0].set_index("case")
    out = {}
    for c in (1, 2, 3, 4):
        out[f"case{c}.distance"] = float(tab.loc[c, "distance_mm"])
        out[f"case{c}.jumps"] = float(tab.loc[c, "jumps"])
    return out


def start_point_height_text_mm() -> float:
    """z (mm) of the reconstructed part at the Sec. 9.3 text's start coordinates (28.5, 43.919)."""
    return start_point_height_mm("text")


def printed_values() -> dict:
    """Printed chapter 7-8 numbers that other printed numbers restate (Thesis 4 restates ch. 8):
    ``ch8_n_min_min``, ``ch8_n_max_max`` (rpm)."""
    p = parameters()
    return {"ch8_n_min_min": float(min(p["ch8_n_min"])), "ch8_n_max_max": float(max(p["ch8_n_max"]))}
