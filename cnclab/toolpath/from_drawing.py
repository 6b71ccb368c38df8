"""Pocket jobs from drawings: the geometry of a DXF/SVG drawing (:func:`cnclab.geometry.drawing.read_drawing`)
plus a cutting-data file (every job key except the geometry) -> a job (:mod:`cnclab.toolpath.job`).

A CUTTING.json holds what a job file holds except ``polygon``, ``star``, ``islands`` and ``regions``,
e.g. ``{"tool_diameter": 6, "teeth": 2, "theta_deg": 60, "a_p": 3, "depth": 6, "v_c": 120, "f_z": 0.04}``
(a ``start_hole`` may be given too, in the drawing's coordinates converted to mm).
The drawing's regions become ``polygon`` + ``islands`` (one region) or ``regions`` (several); a ring
that is one circle of the drawing is written ``{"circle": {"center": [x, y], "radius": r}}``. The job
records where its geometry came from under ``_drawing`` (file, layer, units, tolerances, entities).

>>> import ezdxf, tempfile, os
>>> doc = ezdxf.new(units=1)                                     # $INSUNITS 1: inch
>>> _ = doc.modelspace().add_lwpolyline([(0, 0), (2, 0), (2, 1), (0, 1)], close=True)
>>> path = os.path.join(tempfile.mkdtemp(), "plate.dxf"); doc.saveas(path)
>>> cutting = {"tool_diameter": 6, "teeth": 2, "theta_deg": 60, "a_p": 3, "v_c": 120, "f_z": 0.04}
>>> d = job_dict_from_drawing(read_drawing(path), cutting)
>>> d["polygon"], d["_drawing"]["units"]
([[0.0, 0.0], [50.8, 0.0], [50.8, 25.4], [0.0, 25.4]], 'in')
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from ..geometry.drawing import CHORD_TOL_MM, JOIN_TOL_MM, Drawing, Ring, read_drawing
from .job import Job, load_job, read_job_json

__all__ = ["DRAWING_SUFFIXES", "GEOMETRY_KEYS", "INCH_DRAWING_EXTENT_MM", "job_dict_from_drawing",
           "job_from_drawing", "load_cutting", "load_job_input"]

#: job keys that hold geometry: they come from the drawing, never from the cutting-data file
GEOMETRY_KEYS = ("polygon", "star", "islands", "regions")
#: file suffixes read as drawings by :func:`load_job_input`
DRAWING_SUFFIXES = (".dxf", ".svg")
#: a drawing in inches whose pocket is wider than this (mm, i.e. 1 m) looks drawn in mm: warned
INCH_DRAWING_EXTENT_MM = 1000.0
#: coordinates written to a job are rounded to this many decimals of a mm (1e-6 mm: far below the
#: flattening tolerance)
DECIMALS = 6


def load_cutting(path) -> dict:
    """The cutting data of a job (a JSON object of job keys without geometry); ``ValueError`` naming
    the file and the key if it holds geometry or is not a JSON object."""
    d = read_job_json(path)
    if not isinstance(d, dict):
        raise ValueError(f"{path}: $: cutting data must be a JSON object {{...}}, got a {type(d).__name__}")
    for k in GEOMETRY_KEYS:
        if k in d:
            raise ValueError(f"{path}: $.{k}: cutting data must not hold geometry ('{k}'): the pocket comes "
                             "from the drawing")
    return d


def _ring_json(ring: Ring, tolerance: float):
    if ring.circle is not None:
        cx, cy, r = (round(float(v), DECIMALS) for v in ring.circle)
        c = {"center": [cx, cy], "radius": r}
        if abs(tolerance - CHORD_TOL_MM) > 1e-12:
            c["tolerance"] = float(tolerance)
        return {"circle": c}
    return np.round(np.asarray(ring.points, float), DECIMALS).tolist()


def job_dict_from_drawing(drawing: Drawing, cutting: dict) -> dict:
    """The job mapping (:meth:`cnclab.toolpath.job.Job.from_dict` format) of ``drawing``'s geometry and
    the ``cutting`` keys; provenance under ``_drawing``."""
    tol = drawing.tolerance
    regions = [{"polygon": _ring_json(r.shell, tol), "islands": [_ring_json(i, tol) for i in r.islands]}
               for r in drawing.regions]
    d = {k: v for k, v in cutting.items() if k not in GEOMETRY_KEYS}
    if len(regions) == 1:
        d["polygon"] = regions[0]["polygon"]
        if regions[0]["islands"]:
            d["islands"] = regions[0]["islands"]
    else:
        d["regions"] = [r if r["islands"] else {"polygon": r["polygon"]} for r in regions]
    d["_drawing"] = {
        "file": Path(drawing.source).name, "layer": drawing.layer, "units": drawing.units,
        "mm_per_unit": drawing.mm_per_unit, "tolerance_mm": tol, "join_tol_mm": drawing.join_tol,
        "notes": list(drawing.notes),
        "entities": [{"outline": list(r.shell.entities), "islands": [list(i.entities) for i in r.islands]}
                     for r in drawing.regions]}
    return d


def _drawing_warnings(drawing: Drawing) -> list:
    """The reverse of the job's inch check: a drawing in inches whose numbers look like mm."""
    if drawing.mm_per_unit < 25.4 - 1e-9:
        return []
    x0, y0, x1, y1 = drawing.polygon().bounds
    extent = max(x1 - x0, y1 - y0)
    if extent > INCH_DRAWING_EXTENT_MM:
        return [f"{drawing.source}: the drawing is in {drawing.units} (x {drawing.mm_per_unit:g}) but its pocket is "
                f"{extent:g} mm across ({extent / drawing.mm_per_unit:g} {drawing.units}): numbers that look like mm "
                "(give units='mm' / --units mm)"]
    return []


def job_from_drawing(drawing_path, cutting, layer: str | None = None, tolerance: float = CHORD_TOL_MM,
                     units: str | None = None, join_tol: float = JOIN_TOL_MM) -> tuple[Job, dict]:
    """Read ``drawing_path`` (.dxf/.svg) and the cutting data (a file path or a mapping) into a job:
    ``(job, job_mapping)``. Errors name the drawing (its entities) or the cutting file and the key."""
    drawing = read_drawing(drawing_path, layer=layer, tolerance=tolerance, units=units, join_tol=join_tol)
    cut = load_cutting(cutting) if not isinstance(cutting, dict) else dict(cutting)
    name = cutting if not isinstance(cutting, dict) else "<cutting>"
    d = job_dict_from_drawing(drawing, cut)
    warns = _drawing_warnings(drawing)
    try:
        # 'DRAWING + CUTTING' names both inputs in messages (and its last path part is the cutting file)
        job = Job.from_dict(d, source=f"{drawing_path} + {name}")
    except ValueError as exc:
        if not warns:
            raise
        raise ValueError(f"{exc} (note: {warns[0]})") from None
    if warns:
        job = dataclasses.replace(job, warnings=tuple(warns) + tuple(job.warnings))
    return job, d


def load_job_input(path, cutting=None, layer: str | None = None, tolerance: float = CHORD_TOL_MM,
                   units: str | None = None) -> Job:
    """A job from a job file (.json) or from a drawing (.dxf/.svg) with its ``cutting`` data (required
    then); ``layer``, ``tolerance`` and ``units`` apply to drawings only."""
    if Path(path).suffix.lower() in DRAWING_SUFFIXES:
        if cutting is None:
            raise ValueError(f"{path}: a drawing gives only the geometry: give the cutting data (every job key "
                             "except the geometry) with --cutting CUTTING.json")
        return job_from_drawing(path, cutting, layer=layer, tolerance=tolerance, units=units)[0]
    if cutting is not None or layer is not None or units is not None:
        raise ValueError(f"{path}: --cutting, --layer and --units apply to a drawing (.dxf/.svg), not to a job file")
    return load_job(path)
