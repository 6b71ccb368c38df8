"""STL exchange: the strict reader (:func:`read_stl`: binary by size, ASCII with every solid, errors
naming file and line or facet; facets re-oriented by :func:`~cnclab.geometry.mesh.repair.orient_facets`)
and the writer (:func:`write_stl`, numpy-stl, atomic)."""
from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np

from ...fileio import atomic_output
from .core import STLError, TriMesh, facet_areas, facet_normals
from .repair import first_equal_triple, orient_facets, orient_with_info, weld_ids

__all__ = ["read_stl", "write_stl", "STLWarning"]


_NUM = r"[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?"
_NUM_RE = re.compile(rf"^{_NUM}$", re.ASCII)
_NONFINITE_RE = re.compile(r"^[-+]?(?:nan|inf|infinity)$", re.I)


class STLWarning(UserWarning):
    """An STL file was read but repaired (facets re-oriented); the message names the file and count."""


def _stl_numbers(parts, path, lineno, what):
    vals = []
    for p in parts:
        if _NUM_RE.match(p):
            vals.append(float(p))
        elif _NONFINITE_RE.match(p):
            raise STLError(f"{path}:{lineno}: non-finite {what} coordinate {p!r}")
        else:
            raise STLError(f"{path}:{lineno}: garbled {what} value {p!r} (need a decimal number)")
    if len(vals) != 3:
        raise STLError(f"{path}:{lineno}: garbled {what} line (need 3 numbers, got {len(vals)})")
    vals = [float(v) for v in vals]
    if not all(np.isfinite(vals)):
        raise STLError(f"{path}:{lineno}: non-finite {what} coordinate (overflow)")
    return vals


def _parse_ascii_stl(text: str, path):
    """Strict ASCII STL parser: every solid of the file; errors name file and line.

    Returns (triangles (F, 3, 3), stored normals (F, 3), facet line numbers (F,), solid names).
    """
    tris, norms, flines, names = [], [], [], []
    # states: 'top' (between solids), 'solid', 'facet' (after 'facet normal'), 'loop', 'endloop'
    state = "top"
    verts: list = []
    facet_line = solid_line = 0
    lineno = 0
    for lineno, line in enumerate(text.splitlines(), start=1):
        parts = line.split()
        if not parts:
            continue
        kw = parts[0].lower()
        if state == "top":
            if kw != "solid":
                raise STLError(f"{path}:{lineno}: expected 'solid', got {line.strip()[:60]!r}")
            names.append(" ".join(parts[1:]))
            state, solid_line = "solid", lineno
        elif state == "solid":
            if kw == "facet":
                if len(parts) < 2 or parts[1].lower() != "normal":
                    raise STLError(f"{path}:{lineno}: garbled facet line {line.strip()[:60]!r} "
                                   "(need 'facet normal nx ny nz')")
                norms.append(_stl_numbers(parts[2:], path, lineno, "facet normal"))
                state, facet_line, verts = "facet", lineno, []
            elif kw == "endsolid":
                state = "top"
            else:
                raise STLError(f"{path}:{lineno}: expected 'facet' or 'endsolid', got {line.strip()[:60]!r}")
        elif state == "facet":
            if kw != "outer" or len(parts) != 2 or parts[1].lower() != "loop":
                raise STLError(f"{path}:{lineno}: expected 'outer loop', got {line.strip()[:60]!r}")
            state = "loop"
        elif state == "loop":
            if kw == "vertex":
                if len(verts) == 3:
                    raise STLError(f"{path}:{lineno}: facet starting on line {facet_line} has more than 3 vertices")
                verts.append(_stl_numbers(parts[1:], path, lineno, "vertex"))
            elif kw == "endloop" and len(parts) == 1:
                if len(verts) != 3:
                    raise STLError(f"{path}:{lineno}: facet starting on line {facet_line} has {len(verts)} "
                                   "vertices, not 3")
                state = "endloop"
            else:
                raise STLError(f"{path}:{lineno}: expected 'vertex x y z' or 'endloop' (facet of line "
                               f"{facet_line}), got {line.strip()[:60]!r}")
        elif state == "endloop":
            if kw != "endfacet" or len(parts) != 1:
                raise STLError(f"{path}:{lineno}: expected 'endfacet' (facet of line {facet_line}), "
                               f"got {line.strip()[:60]!r}")
            tris.append(verts)
            flines.append(facet_line)
            state = "solid"
    if state != "top":
        raise STLError(f"{path}:{lineno}: truncated ASCII STL: solid of line {solid_line} has no 'endsolid'")
    if not names:
        raise STLError(f"{path}: empty STL file (no 'solid')")
    return (np.asarray(tris, float).reshape(-1, 3, 3), np.asarray(norms, float).reshape(-1, 3),
            np.asarray(flines, np.int64), names)


_BIN_DTYPE = np.dtype([("normals", "<f4", (3,)), ("vectors", "<f4", (3, 3)), ("attr", "<u2")])


def _stl_kind(raw: bytes) -> str:
    """'binary' when the size matches the facet count of the header (even if the header starts with
    'solid'), else 'ascii' for text starting with 'solid', else 'binary' (size checked later)."""
    if len(raw) >= 84 and 84 + 50 * int(np.frombuffer(raw[80:84], "<u4")[0]) == len(raw):
        return "binary"
    if raw.lstrip()[:5].lower() == b"solid":
        return "ascii"
    return "binary"


def _parse_binary_stl(raw: bytes, path):
    if len(raw) < 84:
        raise STLError(f"{path}: truncated binary STL ({len(raw)} bytes, the header needs 84)")
    count = int(np.frombuffer(raw[80:84], "<u4")[0])
    need = 84 + 50 * count
    if len(raw) != need:
        body = len(raw) - 84
        what = "truncated" if len(raw) < need else "inconsistent"
        raise STLError(f"{path}: {what} binary STL: the header announces {count} facets ({need} bytes) but the "
                       f"file has {len(raw)} bytes ({body // 50} whole facets + {body % 50} bytes)")
    if count == 0:
        raise STLError(f"{path}: STL has no facets")
    data = np.frombuffer(raw, _BIN_DTYPE, count=count, offset=84)
    name = raw[:80].split(b"\0", 1)[0].decode("ascii", errors="replace").strip()
    return data["vectors"].astype(float), data["normals"].astype(float), name


def read_stl(path, degenerate: str = "error", orient: str = "auto", orient_up: bool = False) -> TriMesh:
    """Read an ASCII or binary STL strictly; facets re-oriented consistently (see :func:`orient_facets`).

    Parameters
    ----------
    path : STL file (mm). Binary is recognised by its size (84 + 50 x the facet count of the header,
        also when the 80-byte header starts with "solid"); any other size is refused, both shorter
        and longer. ASCII files may hold several ``solid ... endsolid`` blocks: **all** solids are
        read (their facets concatenated; ``info["solids"]`` lists the names). Blank lines anywhere
        are accepted.
    degenerate : 'error' (default: zero-area facet -> ValueError naming it) or 'drop'.
    orient : 'auto' (default: consistent winding, closed parts outward, open surfaces upward; the
        number of flipped facets is ``info["reoriented_facets"]`` and an :class:`STLWarning` is
        issued when it is not zero) or 'keep' (the file's vertex order as written).
    orient_up : additionally flip every facet whose normal has N_z < 0 (open height fields with folds).

    Raises ``ValueError`` (:class:`STLError`) naming the file (and the line for ASCII, the facet for
    binary) on an empty, truncated, oversized or garbled file, non-finite coordinates, zero-area
    facets or repeated facets (same three corners; ``degenerate="drop"`` drops both kinds, counted in
    ``info["dropped_degenerate"]`` / ``info["dropped_duplicate"]``).

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "t.stl"
    >>> _ = p.write_text("solid a\\nfacet normal 0 0 1\\nouter loop\\nvertex 0 0 0\\nvertex 1 0 0\\n"
    ...                  "vertex 0 1 0\\nendloop\\nendfacet\\nendsolid a\\n\\n\\n")
    >>> m = read_stl(p); m.n_facets, m.info["format"], m.info["reoriented_facets"]
    (1, 'ascii', 0)
    """
    path = Path(path)
    raw = path.read_bytes()
    if not raw.strip():
        raise STLError(f"{path}: empty STL file")
    kind = _stl_kind(raw)
    flines = None
    if kind == "ascii":
        try:
            text = raw.decode("ascii")
        except UnicodeDecodeError as exc:
            line = raw[:exc.start].count(b"\n") + 1
            raise STLError(f"{path}:{line}: non-ASCII byte in an ASCII STL (or a binary STL whose size "
                           f"does not match its facet count)") from None
        tri, stored, flines, names = _parse_ascii_stl(text, path)
        name = names[0] or path.stem
        if len(tri) == 0:
            raise STLError(f"{path}: STL has no facets")
    else:
        tri, stored, name = _parse_binary_stl(raw, path)
        names = [name]
        name = name or path.stem
    where = (lambda k: f"{path}:{flines[k]}") if flines is not None else (lambda k: f"{path} (facet {k})")
    bad = ~np.isfinite(tri).all(axis=(1, 2))
    if bad.any():
        raise STLError(f"{where(int(np.argmax(bad)))}: non-finite vertex coordinate")
    try:
        mesh = TriMesh.from_triangles(tri, name=name, degenerate=degenerate, source=str(path))
    except STLError as exc:
        k = int(re.search(r"facet (\d+)", str(exc)).group(1))
        raise STLError(f"{where(k)}: {str(exc).split(': ', 1)[1]}") from None
    if mesh.info["dropped_degenerate"]:
        stored = stored[facet_areas(tri) > 1e-12 * max(float(np.ptp(tri.reshape(-1, 3), axis=0).max()), 1e-300) ** 2]
    # repeated facets: the same three welded corners (exact coordinates, -0.0 == 0.0) in any order
    vid = weld_ids(mesh.triangles)
    first = first_equal_triple(vid)
    dup = np.flatnonzero(first != np.arange(len(first)))
    if dup.size and degenerate == "error":
        k, j = int(dup[0]), int(first[dup[0]])
        raise STLError(f"{where(k)}: facet {k} repeats facet {j} (same three corners; {dup.size} duplicate "
                       "facet(s); pass degenerate='drop' to skip them)")
    if dup.size:
        keep = np.ones(len(first), bool)
        keep[dup] = False
        mesh.triangles, mesh.normals, stored = mesh.triangles[keep], mesh.normals[keep], stored[keep]
        vid = vid[keep]
    mesh.info["dropped_duplicate"] = int(dup.size)
    if orient == "auto":          # = orient_facets(mesh.triangles), reusing the welded vertex ids
        oinfo = {"components": 0, "non_manifold_edges": 0, "winding_conflicts": 0, "boundary_edges": 0}
        t2, flipped, oinfo = orient_with_info(np.array(mesh.triangles, dtype=float, copy=True), oinfo, vid)
    else:
        t2, flipped, oinfo = orient_facets(mesh.triangles, orient)
    if flipped.any():
        mesh.triangles = t2
        mesh.normals = facet_normals(t2)
    ln = np.linalg.norm(stored, axis=1)
    missing = ln == 0
    unit = np.divide(stored, ln[:, None], out=np.zeros_like(stored), where=ln[:, None] > 0)
    inconsistent = ~missing & ((unit * mesh.normals).sum(axis=1) < np.cos(np.radians(1.0)))
    if orient_up:
        down = mesh.normals[:, 2] < 0
        mesh.triangles[down] = mesh.triangles[down][:, ::-1]
        mesh.normals[down] *= -1
        mesh.info["flipped_down_facets"] = int(down.sum())
    mesh.info.update(format=kind, solids=names, stored_normals_missing=int(missing.sum()),
                     stored_normals_inconsistent=int(inconsistent.sum()),
                     normals="recomputed from the (re-oriented) vertex order",
                     reoriented_facets=int(flipped.sum()), orientation=orient, source=str(path), **oinfo)
    if flipped.any():
        warnings.warn(f"{path}: {int(flipped.sum())} of {mesh.n_facets} facets re-oriented (consistent winding; "
                      "closed parts outward, open surfaces upward)", STLWarning, stacklevel=2)
    return mesh


def write_stl(path, mesh: TriMesh, ascii: bool = False, inputs=()) -> Path:
    """Write ``mesh`` as an ASCII or binary STL atomically (numpy-stl); normals from vertex order.

    ``inputs``: files that must not be overwritten (ValueError if ``path`` is one of them).
    """
    from stl import mesh as stlmesh
    from stl.stl import Mode

    data = np.zeros(mesh.n_facets, dtype=stlmesh.Mesh.dtype)
    data["vectors"] = mesh.triangles
    data["normals"] = facet_normals(mesh.triangles)
    m = stlmesh.Mesh(data, calculate_normals=False, name=mesh.name or "cnclab", speedups=False)
    with atomic_output(path, "wb", inputs=inputs) as fh:
        m.save(mesh.name or "cnclab", fh=fh, mode=Mode.ASCII if ascii else Mode.BINARY, update_normals=False)
    return Path(path)
