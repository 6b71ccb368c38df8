"""Constant-cutting-speed post-processor (Mgherony 2024, Sec. 7.2.3, Thesis 3).

For every feed point of an APT CL program:

1. the facet of the STL assigned to the cutter location: the facet whose centroid (the thesis's
   "incentre") is nearest (``facet_rule="centroid"``, thesis rule, KD-tree) or the facet at the
   smallest Euclidean distance (``"nearest"``);
2. the facet normal -> inclination angles. Eqs (7-1), (7-2) give A_N1 = atan2(N_y, N_x),
   A_N2 = acos(N_z) (the *downhill* azimuth); the working-diameter model of Sec. 5.2 (eq 5-3, see
   :mod:`cnclab.geometry.ball_end`) takes the *uphill* azimuth, so the normal is converted with
   :func:`cnclab.geometry.ball_end.angles_from_normal` (the same surface; feeding eq 7-1 straight
   into eq 5-3 would mirror it and swap tangent points 1 and 2);
3. the feed direction A_f from consecutive points (eq 7-3, with atan2) or a constant input; for a
   ``CIRCLE`` move the chord direction, which is the arc's tangent at its midpoint, and the arc length
   as the segment length;
4. the working diameter D_eff at tangent point 1 / 2 (``point`` = "max" uses the larger, i.e. the
   uphill-side tangent point, "1", "2", or "thesis": the one fixed point that reproduces the
   thesis's chapter 8 minima/maxima -- point 1 for nominal A_f <= 45 deg, point 2 above);
5. n = 1000 v_c / (pi D_eff) (eq 7-4), v_f = f_z z n (eq 7-5), clipped to ``n_max`` / ``vf_max``
   (and ``n_min``), optionally rate-limited by a spindle acceleration limit (rpm/s);
6. a new APT program with ``SPINDL`` / ``FEDRAT`` records inserted before a feed point only where
   the value in force differs by more than a threshold (rpm, mm/min).

Units: mm, m/min, rpm, mm/min, degrees.
"""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np
from numba import njit

from ..cutting.speeds import feed_speed, spindle_speed
from ..cutting.spindle_model import POINT_RULES, apply_acceleration_limit, feed_directions, working_diameters
from ..fileio import atomic_write_many, check_outputs
from ..geometry.mesh import FacetLocator, TriMesh, closest_point_on_triangles, machined_surface_mask, read_stl
from ..toolpath.path import Move, ToolPath
from .apt import AptProgram, AptRecord, CLPoints, GotoRun, fedrat, read_apt, spindl
from .numfmt import fixed, scaled_ints
from .program import write_linear_moves, write_moves

__all__ = ["SpindleOptions", "SpindleSchedule", "feed_directions", "working_diameters", "spindle_schedule",
           "apply_acceleration_limit", "insert_spindle_records", "to_gcode_moves", "postprocess_files", "read_inputs",
           "path_surface_deviation",
           "POINT_RULES"]



@dataclasses.dataclass
class SpindleSchedule:
    """Per feed point arrays (length M) and summary of a post-processing run.

    ``index`` positions in the CLPoints; ``xyz`` mm; ``facet`` assigned facet; ``A_N1``, ``A_N2``
    (deg, eq 5-3 convention), ``A_f`` (deg); ``d_eff`` working diameter (mm); ``n_ideal`` rpm from eq 7-4;
    ``n`` rpm after limits; ``v_f`` mm/min; ``seg_len`` mm of the motion ending at each point;
    ``limited`` bool (hit n_max/vf_max/n_min or the acceleration limit).
    """

    index: np.ndarray
    xyz: np.ndarray
    facet: np.ndarray
    A_N1: np.ndarray
    A_N2: np.ndarray
    A_f: np.ndarray
    d_eff: np.ndarray
    n_ideal: np.ndarray
    n: np.ndarray
    v_f: np.ndarray
    seg_len: np.ndarray
    limited: np.ndarray
    v_c: float
    params: dict

    @property
    def v_c_actual(self) -> np.ndarray:
        """Cutting speed (m/min) at the working diameter with the applied n."""
        return np.pi * self.d_eff * self.n / 1000.0

    def within_share(self, rel: float = 0.05) -> float:
        """Share of the feed path length whose actual v_c is within ±rel of the nominal v_c."""
        ok = np.abs(self.v_c_actual - self.v_c) <= rel * self.v_c
        L = self.seg_len.sum()
        return float(self.seg_len[ok].sum() / L) if L > 0 else float(ok.mean())

    def spindle_integral(self, n=None) -> float:
        """Integral of the spindle speed along the feed path, sum n_j * l_j (rpm*mm), Fig 8-4."""
        return float(np.sum((self.n if n is None else n) * self.seg_len))

    @property
    def path_length(self) -> float:
        """Feed path length (mm)."""
        return float(self.seg_len.sum())

    def summary(self) -> dict:
        return {"feed_points": int(len(self.n)), "n_min": float(self.n.min()), "n_max": float(self.n.max()),
                "vf_min": float(self.v_f.min()), "vf_max": float(self.v_f.max()),
                "d_eff_min": float(self.d_eff.min()), "d_eff_max": float(self.d_eff.max()),
                "limited_points": int(self.limited.sum()), "path_length_mm": self.path_length,
                "vc_within_5pct_share": self.within_share(0.05)}


def _cl_points(cl) -> CLPoints:
    """``cl`` as :class:`CLPoints` (a :class:`~cnclab.toolpath.path.ToolPath` converted)."""
    if isinstance(cl, ToolPath):
        return CLPoints.from_toolpath(cl)
    if not isinstance(cl, CLPoints):
        raise TypeError(f"cl must be CLPoints or a ToolPath, got {type(cl).__name__}")
    return cl


@dataclasses.dataclass(frozen=True, kw_only=True)
class SpindleOptions:
    """Settings of the constant-cutting-speed post-processor (the ``spindle`` CLI flags), keyword-only.

    Cutting data: ``v_c`` nominal cutting speed (m/min), ``f_z`` feed per tooth (mm), ``teeth`` (z,
    integer >= 1), ``a_p`` depth of cut (mm), ``tool_diameter`` ball diameter D (mm; None: from the
    CUTTER record in :func:`postprocess_files`, required by :func:`spindle_schedule`).
    Schedule: ``feed_direction_deg`` constant A_f (deg) or None for eq 7-3; ``facet_rule``
    'centroid' | 'nearest'; ``point`` 'max' | '1' | '2' | 'thesis'; limits ``n_max`` / ``n_min``
    (rpm), ``vf_max`` (mm/min), ``accel_rpm_s`` (rpm/s), None = no limit; ``filter_facets`` drop
    side/bottom facets first; ``workers`` threads of the KD-tree queries (-1: every core).
    Records and checks (:func:`postprocess_files` only): ``rpm_threshold`` (rpm) / ``vf_threshold``
    (mm/min) of :func:`insert_spindle_records`; part/path check ``mismatch_tol`` (mm),
    ``max_off_share`` (0..1), ``allow_mismatch``.

    Examples
    --------
    >>> o = SpindleOptions(v_c=63, f_z=0.125, teeth=2, a_p=0.3, tool_diameter=10, n_max=9000)
    >>> o.point, o.n_max
    ('max', 9000)
    """

    v_c: float
    f_z: float
    teeth: int
    a_p: float
    tool_diameter: float | None = None
    feed_direction_deg: float | None = None
    facet_rule: str = "centroid"
    point: str = "max"
    n_max: float | None = None
    n_min: float | None = None
    vf_max: float | None = None
    accel_rpm_s: float | None = None
    filter_facets: bool = True
    workers: int = -1
    rpm_threshold: float = 50.0
    vf_threshold: float = 10.0
    mismatch_tol: float = 1.0
    max_off_share: float = 0.2
    allow_mismatch: bool = False


def _options(options: SpindleOptions | None, fields: dict) -> SpindleOptions:
    """``options`` with the keyword ``fields`` replaced (a new :class:`SpindleOptions` if None)."""
    if options is None:
        return SpindleOptions(**fields)
    if not isinstance(options, SpindleOptions):
        raise TypeError(f"options must be SpindleOptions, got {type(options).__name__}")
    return dataclasses.replace(options, **fields) if fields else options


def spindle_schedule(mesh: TriMesh, cl: CLPoints | ToolPath, options: SpindleOptions | None = None, *,
                     locator: FacetLocator | None = None, **fields) -> SpindleSchedule:
    """Compute the point-by-point spindle speed and feed for the feed points of ``cl`` (the CL points
    of an APT program, or any :class:`~cnclab.toolpath.path.ToolPath`: the same schedule).

    The settings are a :class:`SpindleOptions` (``tool_diameter`` required) or its fields as keywords
    (``fields`` replace those of ``options``): tool_diameter (mm), a_p (mm), v_c nominal cutting speed
    (m/min), f_z (mm), teeth; feed_direction_deg constant A_f (deg) or None for eq 7-3; facet_rule
    'centroid' | 'nearest'; point 'max' | '1' | '2' | 'thesis'; limits n_max/n_min (rpm), vf_max
    (mm/min); accel_rpm_s (rpm/s); workers: threads of the KD-tree queries (-1: every core; the result
    does not depend on it). The record/check fields of the options are not used here. ``locator``: a
    prepared :class:`~cnclab.geometry.mesh.FacetLocator` of the mesh (built when None).
    """
    o = _options(options, fields)
    if o.tool_diameter is None:
        raise TypeError("spindle_schedule() needs tool_diameter (mm)")
    tool_diameter, a_p, v_c, f_z, teeth = o.tool_diameter, o.a_p, o.v_c, o.f_z, o.teeth
    feed_direction_deg, facet_rule, point, workers = o.feed_direction_deg, o.facet_rule, o.point, o.workers
    n_max, n_min, vf_max, accel_rpm_s = o.n_max, o.n_min, o.vf_max, o.accel_rpm_s

    for name, v in (("tool_diameter", tool_diameter), ("a_p", a_p), ("v_c", v_c), ("f_z", f_z)):
        if not (np.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be > 0, got {v}")
    if int(teeth) != teeth or teeth < 1:
        raise ValueError(f"teeth must be a positive integer, got {teeth}")
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers == 0 or workers < -1:
        raise ValueError(f"workers must be -1 (every core) or an integer >= 1, got {workers!r}")
    if facet_rule not in ("centroid", "nearest"):
        raise ValueError(f"facet_rule must be 'centroid' or 'nearest', got {facet_rule!r}")
    for name, v in (("n_max", n_max), ("n_min", n_min), ("vf_max", vf_max)):
        if v is not None and not (np.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be > 0, got {v}")
    for name, v in (("feed_direction_deg", feed_direction_deg), ("accel_rpm_s", accel_rpm_s)):
        if v is not None and not np.isfinite(v):
            raise ValueError(f"{name} must be finite, got {v}")
    if n_min is not None and n_max is not None and n_min > n_max:
        raise ValueError(f"n_min must be <= n_max, got n_min={n_min}, n_max={n_max}")
    cl = _cl_points(cl)
    if locator is None:
        m = mesh.subset(machined_surface_mask(mesh.normals)) if o.filter_facets else mesh
        if m.n_facets == 0:
            raise ValueError("mesh: no facet left after removing side/bottom facets")
        locator = FacetLocator(m)
    feed = ~cl.rapid
    idx = np.nonzero(feed)[0]
    if idx.size == 0:
        raise ValueError("program has no feed motion")
    xyz_all = cl.xyz
    seg = cl.segment_lengths()[idx]          # arc length for CIRCLE moves
    pts = xyz_all[idx]
    if feed_direction_deg is None:
        A_f = feed_directions(xyz_all, cl.start)[idx]
    else:
        A_f = np.full(idx.size, float(feed_direction_deg))
    facet = (locator.nearest_centroid(pts, workers=workers) if facet_rule == "centroid"
             else locator.nearest_facet(pts, workers=workers))
    normals = locator.mesh.normals[facet]
    d_eff, a1, a2 = working_diameters(normals, A_f, tool_diameter, a_p, point, feed_direction_deg)
    d_safe = np.maximum(d_eff, 1e-6)
    n_ideal = spindle_speed(v_c, d_safe)
    n = n_ideal.copy()
    hi = np.inf if n_max is None else n_max
    if vf_max is not None:
        hi = min(hi, vf_max / (f_z * teeth))
    lo = 0.0 if n_min is None else n_min
    n = np.clip(n, lo, hi)
    limited = n != n_ideal
    if accel_rpm_s is not None:
        n_acc = apply_acceleration_limit(n, seg, f_z, teeth, accel_rpm_s)
        limited |= np.abs(n_acc - n) > 1e-9
        n = n_acc
    v_f = feed_speed(f_z, teeth, n)
    params = dict(tool_diameter=tool_diameter, a_p=a_p, f_z=f_z, teeth=int(teeth),
                  feed_direction_deg=feed_direction_deg, facet_rule=facet_rule, point=point,
                  n_max=n_max, n_min=n_min, vf_max=vf_max, accel_rpm_s=accel_rpm_s)
    return SpindleSchedule(idx, pts, facet, a1, a2, A_f, d_eff, n_ideal, n, v_f, seg, limited, float(v_c), params)


def insert_spindle_records(program: AptProgram, cl: CLPoints, sched: SpindleSchedule,
                           rpm_threshold: float = 50.0, vf_threshold: float = 10.0) -> tuple[AptProgram, dict]:
    """New program with ``SPINDL`` / ``FEDRAT`` inserted before feed GOTOs where the value in force
    differs by more than ``rpm_threshold`` (rpm) / ``vf_threshold`` (mm/min). Original records are kept
    (an original SPINDL/FEDRAT resets the value in force). Returns (program, counts).

    Bulk GOTO runs of a parsed file are split only where a record is inserted (no per-point objects).
    """
    if not (rpm_threshold >= 0 and vf_threshold >= 0 and np.isfinite(rpm_threshold) and np.isfinite(vf_threshold)):
        raise ValueError(f"rpm_threshold and vf_threshold must be finite and >= 0, got {rpm_threshold}, {vf_threshold}")
    tgt = np.asarray(cl.record)[sched.index]
    if tgt.size > 1 and not (np.diff(tgt) > 0).all():
        raise ValueError("cl/sched: feed points must be in program order")
    n_a, f_a = np.asarray(sched.n, float), np.asarray(sched.v_f, float)
    if not (np.isfinite(n_a).all() and np.isfinite(f_a).all()):
        raise ValueError("sched: spindle speeds n (rpm) and feeds v_f (mm/min) must be finite")
    # the values written: round(n) and round(v_f, 1) as Python rounds them (correctly rounded,
    # ties to even): rint, and the digits of f"{v:.1f}" over 10 (a correctly rounded division)
    rn_a = np.rint(n_a)
    rf_a = np.copysign(scaled_ints(f_a, 1) / 10.0, f_a)
    tgt_l, n_l, f_l = tgt.tolist(), n_a.tolist(), f_a.tolist()
    n_t = len(tgt_l)
    out = []
    cur_n = cur_f = float("nan")
    n_sp = n_fr = 0

    def changes(n, f):
        """Records to insert before a feed point with values (n, f); updates the values in force."""
        nonlocal cur_n, cur_f, n_sp, n_fr
        ins = []
        if not abs(n - cur_n) <= rpm_threshold:
            cur_n = round(n)
            ins.append(spindl(cur_n))
            n_sp += 1
        if not abs(f - cur_f) <= vf_threshold:
            cur_f = round(f, 1)
            ins.append(fedrat(cur_f))
            n_fr += 1
        return ins

    k = 0   # index into the expanded record list
    j = 0   # next target
    for it in program.items():
        if isinstance(it, GotoRun):
            m = len(it)
            j1 = int(np.searchsorted(tgt, k + m, side="left"))
            a = 0
            # the threshold walk of changes() over the run's targets, compiled; records built after
            ins_s, ins_f, cur_n, cur_f = _insertions(n_a[j:j1], f_a[j:j1], rn_a[j:j1], rf_a[j:j1], float(cur_n), float(cur_f),
                                                     float(rpm_threshold), float(vf_threshold))
            hit = np.flatnonzero(ins_s | ins_f)
            n_sp += int(ins_s.sum())
            n_fr += int(ins_f.sum())
            sp_rec = _spindl_records(rn_a[j:j1][ins_s])
            fr_rec = _fedrat_records(rf_a[j:j1][ins_f])
            i_s = i_f = 0
            for t, s_, f_ in zip((hit + j).tolist(), ins_s[hit].tolist(), ins_f[hit].tolist()):
                li = tgt_l[t] - k
                if li > a:
                    out.append(it.slice(a, li))
                if s_:
                    out.append(sp_rec[i_s])
                    i_s += 1
                if f_:
                    out.append(fr_rec[i_f])
                    i_f += 1
                a = li
            if a == 0:
                out.append(it)
            elif a < m:
                out.append(it.slice(a, m))
            j = j1
            k += m
            continue
        r = it
        if r.word == "SPINDL" and r.values:
            cur_n = r.values[-1]
        elif r.word == "FEDRAT":
            cur_f = r.values[0]
        if j < n_t and (tgt_l[j] == k or (r.word == "CIRCLE" and tgt_l[j] == k + 1)):
            out.extend(changes(n_l[j], f_l[j]))   # before a CIRCLE, never between it and its GOTO
            j += 1
        out.append(r)
        k += 1
    return AptProgram(out, program.source), {"spindl_inserted": n_sp, "fedrat_inserted": n_fr}


@njit(cache=True, nogil=True)
def _insertions(n, f, rn, rf, cur_n, cur_f, rpm_threshold, vf_threshold):
    """Where SPINDL / FEDRAT records go (bool arrays) and the values in force after the run."""
    m = n.shape[0]
    ins_s = np.zeros(m, np.bool_)
    ins_f = np.zeros(m, np.bool_)
    for t in range(m):
        if not abs(n[t] - cur_n) <= rpm_threshold:
            cur_n = rn[t]
            ins_s[t] = True
        if not abs(f[t] - cur_f) <= vf_threshold:
            cur_f = rf[t]
            ins_f[t] = True
    return ins_s, ins_f, cur_n, cur_f


def _spindl_records(rpm) -> list:
    """``spindl(v)`` for each value of ``rpm`` (whole numbers >= 0, rpm), texts formatted in bulk."""
    if np.signbit(rpm).any():
        return [spindl(v) for v in rpm.tolist()]
    txt = fixed(rpm, 0).tolist()
    return [AptRecord("SPINDL", ["RPM", repr(v), "CLW"], f"SPINDL / RPM, {t}, CLW\n", nums=[v])
            for v, t in zip(rpm.tolist(), txt)]


def _fedrat_records(feed) -> list:
    """``fedrat(v)`` for each value of ``feed`` (mm/min), texts formatted in bulk."""
    if np.signbit(feed).any():
        return [fedrat(v) for v in feed.tolist()]
    txt = fixed(feed, 1).tolist()
    return [AptRecord("FEDRAT", [repr(v), "MMPM"], f"FEDRAT / {t}, MMPM\n", nums=[v]) for v, t in zip(feed.tolist(), txt)]


def to_gcode_moves(program: AptProgram):
    """RS274/NGC moves (:class:`cnclab.toolpath.path.Move`) of an APT program: G0 rapids, G1 feeds
    with the F and S in force, G2/G3 for a ``CIRCLE`` and its end-point GOTO (i, j = centre - start).

    >>> from cnclab.nc.apt import parse_apt
    >>> prog = parse_apt("UNITS/MM\\nFROM/10,0,0\\nFEDRAT/500\\nCIRCLE/0,0,0,0,0,-1,10\\nGOTO/0,-10,0\\n")
    >>> to_gcode_moves(prog)[0]
    Move(motion='G2', x=0.0, y=-10.0, z=0.0, i=-10.0, j=0.0, feed=500.0, spindle=None)
    """
    moves = []
    for xyz, rapid, f, sp, circle, pos, line in _motion_blocks(program):
        if circle is not None:
            if pos is None:
                raise ValueError(f"{program.source}:{line}: arc with an unknown start point")
            x, y, z = xyz[0].tolist()
            moves.append(Move("G3" if circle[5] > 0 else "G2", x, y, z, i=circle[0] - pos[0],
                              j=circle[1] - pos[1], feed=f, spindle=sp))
            continue
        for k, (x, y, z) in enumerate(xyz.tolist()):
            moves.append(Move("G0", x, y, z, spindle=sp) if rapid and k == 0
                         else Move("G1", x, y, z, feed=f, spindle=sp))
    return moves


def _motion_blocks(program: AptProgram):
    """The APT program's motion, once, with the modal state in force: yields ``(xyz (m, 3) mm,
    rapid (the first point is reached by RAPID), feed, spindle, circle (CIRCLE values ending at this
    single point, else None), start position (x, y, z) or None, line)`` per GOTO run or GOTO."""
    f = s = None
    rapid = False
    circle = None
    pos = None
    for r in program.items():
        if isinstance(r, GotoRun):
            yield r.xyz, rapid, f, s, None, pos, r.line
            rapid = False
            pos = r.xyz[-1].tolist()
        elif r.word == "RAPID":
            rapid = True
        elif r.word == "FEDRAT":
            f = r.values[0]
        elif r.word == "SPINDL" and r.values:
            s = r.values[-1]
        elif r.word == "FROM":
            pos = r.values[:3]
        elif r.word == "CIRCLE":
            circle = r.values
        elif r.word == "GOTO":
            yield np.asarray([r.values[:3]], float), rapid, f, s, circle, pos, r.line
            circle = None
            rapid = False
            pos = list(r.values[:3])


def path_surface_deviation(mesh: TriMesh, cl: CLPoints | ToolPath, tool_radius: float, *, output: str = "tip",
                           max_points: int = 2000) -> np.ndarray:
    """Gap (mm) between the ball of a ball-end mill at each feed CL point and the part surface.

    The ball centre is the CL point + (0, 0, ``tool_radius``) for ``output="tip"`` (APT
    ``OUTPUT_ON_TIP``) or the CL point itself for ``"centre"``; the gap is its exact distance to the
    nearest facet of ``mesh`` minus ``tool_radius``: 0 where the ball touches the surface, > 0 above
    it, < 0 where it would gouge. At most ``max_points`` feed points, evenly spaced along the program,
    are checked (2000 by default: a share estimated from them has a standard error <= 1.1 %, small
    against the 20 % limit of :func:`postprocess_files`).

    >>> from cnclab.geometry.freeform_part import tessellate_heightfield
    >>> from cnclab.nc.apt import cl_program
    >>> m = tessellate_heightfield(lambda x, y: 0 * x, (0, 10), (0, 10), 2, 2)
    >>> cl = cl_program([[[2, 5, 0.0], [8, 5, 0.0]]], 500, 2000, 10, 30).cl_points()
    >>> path_surface_deviation(m, cl, 5.0).round(9).tolist()   # both feed points (fed down onto the first)
    [0.0, 0.0]
    """
    if output not in ("tip", "centre"):
        raise ValueError(f"output must be 'tip' or 'centre', got {output!r}")
    if not (np.isfinite(tool_radius) and tool_radius > 0):
        raise ValueError(f"tool_radius must be a finite number > 0 mm, got {tool_radius!r}")
    cl = _cl_points(cl)
    pts = cl.xyz[~cl.rapid]
    if len(pts) > max_points:
        pts = pts[np.linspace(0, len(pts) - 1, max_points).round().astype(int)]
    c = pts + ([0.0, 0.0, tool_radius] if output == "tip" else 0.0)
    # exact distance to the mesh: facets much larger than the typical one (walls, bottom of a closed
    # part) would make the KD-tree bound of FacetLocator.nearest_facet cover the whole mesh, so they
    # are checked by brute force (in blocks) and the others through the locator
    T = mesh.triangles
    circ = np.linalg.norm(T - T.mean(axis=1)[:, None], axis=2).max(axis=1)
    big = circ > 4.0 * float(np.median(circ))
    best = np.full(len(c), np.inf)
    if (~big).any():
        small = mesh.subset(~big)
        f = FacetLocator(small).nearest_facet(c)
        S = small.triangles[f]
        best = np.linalg.norm(closest_point_on_triangles(c, S[:, 0], S[:, 1], S[:, 2]) - c, axis=1)
    B = T[big]
    cb, rb = B.mean(axis=1), circ[big]
    step = max(1, 2_000_000 // max(len(B), 1))
    for a in range(0, len(c) if len(B) else 0, step):
        q = c[a:a + step]
        lower = np.linalg.norm(q[:, None] - cb[None], axis=2) - rb[None]     # bounding-sphere bound
        i, j = np.nonzero(lower < best[a:a + step, None])
        if i.size:
            d = np.linalg.norm(closest_point_on_triangles(q[i], B[j, 0], B[j, 1], B[j, 2]) - q[i], axis=1)
            m = np.full(len(q), np.inf)
            np.minimum.at(m, i, d)
            best[a:a + step] = np.minimum(best[a:a + step], m)
    return best - tool_radius


def _finite(name, v, lo=None, lo_open=True, hi=None, optional=False):
    """ValueError naming the parameter unless v is a finite number in the range."""
    if v is None and optional:
        return
    ok = isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool) and np.isfinite(v)
    if ok and lo is not None:
        ok = v > lo if lo_open else v >= lo
    if ok and hi is not None:
        ok = v <= hi
    if not ok:
        rng = ("(" if lo_open else "[") + (f"{lo:g}" if lo is not None else "-inf") + ", " + \
              (f"{hi:g}]" if hi is not None else "inf)")
        raise ValueError(f"{name} must be a finite number in {rng}, got {v!r}")


def gcode_text(program: AptProgram, header: str = "") -> str:
    """``write_moves(to_gcode_moves(program), header)`` (:func:`cnclab.nc.program.write_moves`, the one
    writer) without building one Move per point: the program's points, rapid flags, F and S in force
    go to :func:`cnclab.nc.program.write_linear_moves` as arrays (same bytes)."""
    if any(getattr(r, "word", None) == "CIRCLE" for r in program.items()):
        return write_moves(to_gcode_moves(program), header=header)   # arcs: G2/G3 through the Move writer
    xyz, lens, rap0, fe, sp = [], [], [], [], []
    for pts, rapid, f, s, _, _, _ in _motion_blocks(program):
        xyz.append(pts)
        lens.append(len(pts))
        rap0.append(rapid)
        fe.append(np.nan if f is None else f)
        sp.append(np.nan if s is None else s)
    if not xyz:
        return write_moves([], header=header)
    lens_a = np.asarray(lens, np.int64)
    rap_a = np.zeros(int(lens_a.sum()), bool)
    rap_a[np.concatenate([[0], np.cumsum(lens_a)[:-1]])] = rap0       # only a block's first point is a rapid
    fe_a = np.repeat(np.asarray(fe, float), lens_a)
    sp = np.repeat(np.asarray(sp, float), lens_a)
    if np.isnan(fe_a[~rap_a]).any():   # a feed move without FEDRAT: let the Move writer report it
        return write_moves(to_gcode_moves(program), header=header)
    return write_linear_moves(np.vstack(xyz), rap_a, fe_a, sp, header=header)


def read_inputs(stl_path, apt_path):
    """``read_stl(stl_path)`` and ``read_apt(apt_path)`` with its ``cl_points()``, one after the other
    (the STL's errors first). Returns (mesh, program, cl).

    Read in the main thread only: an earlier version read the STL in a second thread, which gained
    ~3 ms on the sample files but made interrupts unsafe (a SIGINT while the thread ran compiled nogil
    kernels at interpreter shutdown crashed the process; a SIGTERM that arrived while the main thread
    held numba's compiler lock left the reader waiting for that lock forever and the CLI hung).
    """
    mesh = read_stl(stl_path)
    prog = read_apt(apt_path)
    return mesh, prog, prog.cl_points()


def postprocess_files(stl_path, apt_path, out_path, options: SpindleOptions | None = None, *, gcode_path=None,
                      progress: bool = False, **fields) -> dict:
    """Read STL + APT, compute the schedule, write the new APT (and G-code) together, atomically.

    Inputs are never overwritten (``out_path``/``gcode_path`` equal to an input or to each other is
    refused before anything is read); all outputs are written at the end, together, or none (a
    failing ``gcode_path`` leaves no APT output). Part/path check: the share of feed CL points whose
    ball (:func:`path_surface_deviation`, ``OUTPUT_ON_CENTER`` in the APT header means centre output)
    is more than ``mismatch_tol`` (mm) away from the surface -- above it or into it -- is reported
    (``off_surface_share``); above ``max_off_share`` it is an error unless ``allow_mismatch``.
    (Defaults: 1 mm covers finishing allowances and chordal error; 20 % leaves room for feed moves
    in the air such as lead-ins and links, while a path 50 mm above, 1000 mm away or on a part
    scaled x0.1 has nearly all points off.) The settings are a :class:`SpindleOptions` or its fields as
    keywords (``fields`` replace those of ``options``); ``tool_diameter`` None takes D from the CUTTER
    record. Returns a summary dict.
    """
    o = _options(options, fields)
    v_c, f_z, teeth, a_p, tool_diameter = o.v_c, o.f_z, o.teeth, o.a_p, o.tool_diameter
    rpm_threshold, vf_threshold = o.rpm_threshold, o.vf_threshold
    mismatch_tol, max_off_share, allow_mismatch = o.mismatch_tol, o.max_off_share, o.allow_mismatch

    t0 = time.perf_counter()
    check_outputs([out_path, gcode_path], inputs=[stl_path, apt_path],
                  names=["out_path (-o)", "gcode_path (--gcode)"][:2])
    _finite("v_c", v_c, 0)
    _finite("f_z", f_z, 0)
    _finite("a_p", a_p, 0)
    _finite("tool_diameter", tool_diameter, 0, optional=True)
    _finite("rpm_threshold", rpm_threshold, 0, lo_open=False)
    _finite("vf_threshold", vf_threshold, 0, lo_open=False)
    _finite("mismatch_tol", mismatch_tol, 0)
    _finite("max_off_share", max_off_share, 0, lo_open=False, hi=1)
    if isinstance(teeth, bool) or int(teeth) != teeth or teeth < 1:
        raise ValueError(f"teeth must be an integer >= 1, got {teeth!r}")
    steps = ["read STL", "read APT", "working diameter", "write"]
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(steps), desc="spindle", unit="step", disable=None)   # a bar only on a terminal

    def tick(msg):
        if bar is not None:
            bar.set_postfix_str(msg)
            bar.update(1)

    try:
        mesh, prog, cl = read_inputs(stl_path, apt_path)
        tick("STL")
        tick("APT")
        D = tool_diameter if tool_diameter is not None else prog.tool_diameter()
        if D is None:
            raise ValueError(f"{apt_path}: no CUTTER record; pass tool_diameter (--tool-diameter)")
        _finite(f"tool diameter (CUTTER of {apt_path})", D, 0)
        if a_p > D / 2:
            raise ValueError(f"a_p must be in (0, D/2] = (0, {D / 2:g}] mm for a ball-end mill, got {a_p!r}")
        header = " ".join(r.comment.upper() for r in prog.items()[:50] if hasattr(r, "comment"))
        output = "centre" if "OUTPUT_ON_CENTER" in header.replace(" ", "") else "tip"
        gap = path_surface_deviation(mesh, cl, D / 2, output=output)
        off = float(np.mean(np.abs(gap) > mismatch_tol)) if gap.size else 0.0
        if off > max_off_share and not allow_mismatch:
            raise ValueError(
                f"{apt_path} does not match {stl_path}: {100 * off:.1f} % of the feed CL points are more than "
                f"{mismatch_tol:g} mm from the surface (ball-end contact check, median gap {np.median(gap):.3g} mm; "
                f"limit {100 * max_off_share:g} %). Check units, origin and scale, or pass allow_mismatch "
                "(--allow-mismatch) to process anyway")
        sched = spindle_schedule(mesh, cl, dataclasses.replace(o, tool_diameter=D))
        tick("D_eff")
        new, counts = insert_spindle_records(prog, cl, sched, rpm_threshold, vf_threshold)
        outs = [(out_path, new.to_text())]
        if gcode_path is not None:
            outs.append((gcode_path, gcode_text(new, header=f"cnclab spindle control of {Path(apt_path).name}")))
        atomic_write_many(outs, inputs=[stl_path, apt_path])
        tick("written")
    finally:
        if bar is not None:
            bar.close()
    summ = sched.summary()
    summ.update(counts, facets=mesh.n_facets, cl_points=len(cl), seconds=time.perf_counter() - t0,
                tool_diameter=D, out=str(out_path), off_surface_share=off, median_gap_mm=float(np.median(gap)),
                reoriented_facets=mesh.info.get("reoriented_facets", 0), output_point=output)
    return summ
