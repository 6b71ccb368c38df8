"""Hostile and corrupted inputs for the STL and APT readers, the public API and ``python -m cnclab spindle``.

Every case must end in one of two outcomes:

* **error**: a ``ValueError``/``OSError`` whose message names the file (and the line for text files,
  the facet or byte count for binary STL) or the parameter / command-line option, or
* **correct result**: defined per reader --
  STL: every facet of the file is returned (count = facets announced / written in the file), as the
  same vertex triple an independent decoder reads (vertex order may be reversed by the documented
  orientation rule), all finite, non-degenerate, and a binary re-serialisation reads back equal;
  APT: the record text round-trips exactly, the careful and fast parsers agree, every number of a
  motion record obeys the strict grammar, UNITS/MM precedes the first motion, no refused motion
  word is present, and every CIRCLE is directly followed by its GOTO.

For every case the input files are unchanged (hash before/after) and no file is left in the output
folder except complete outputs of a successful run. Outcome counts are printed at the end of the
module (``pytest -s``) and written to ``$CNCLAB_BUILD_DIR/fuzz_outcomes.json`` (the session's
temporary build folder is removed at the end unless ``CNCLAB_KEEP_TEST_BUILD=1``).
"""
from __future__ import annotations

import collections
import hashlib
import json
import os
import re
import signal
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cnclab.__main__ import main as cli
from cnclab.geometry import ball_end, engagement
from cnclab.geometry.freeform_part import tessellate_heightfield
from cnclab.geometry.mesh import STLError, STLWarning, TriMesh, read_stl, write_stl
from cnclab.nc import apt
from cnclab.nc import spindle_control as sc
from tests._fuzz_support import SAMPLE, check_complete, classify_interrupt, communicate_or_dump, run_cli, startup_s

OUTCOMES: collections.Counter = collections.Counter()
FUZZ = settings(max_examples=120, deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


@pytest.fixture(scope="module", autouse=True)
def _report_outcomes():
    yield
    total = sum(OUTCOMES.values())
    lines = [f"{k[0]:<6} {k[1]:<8} {v:>5}" for k, v in sorted(OUTCOMES.items())]
    print(f"\nfuzz/hostile cases: {total}\n" + "\n".join(lines))
    by = collections.Counter()
    for (_, outcome), v in OUTCOMES.items():
        by[outcome] += v
    print("by outcome: " + ", ".join(f"{k} {v}" for k, v in sorted(by.items())))
    d = Path(os.environ.get("CNCLAB_BUILD_DIR", "build"))
    d.mkdir(parents=True, exist_ok=True)
    (d / "fuzz_outcomes.json").write_text(json.dumps({f"{k[0]}/{k[1]}": v for k, v in OUTCOMES.items()}))


def _sha(p: Path) -> str:
    return hashlib.sha256(p.read_bytes()).hexdigest()


# ============================================================================ STL
def _grid_mesh(n=3):
    return tessellate_heightfield(lambda x, y: 0.05 * x * y + 0.3 * x, (0, 10), (0, 10), n, n)


def _box():
    """A closed unit cube wound counter-clockwise seen from outside (outward normals)."""
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float)
    f = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4), (1, 2, 6), (1, 6, 5),
         (2, 3, 7), (2, 7, 6), (3, 0, 4), (3, 4, 7)]
    return TriMesh.from_triangles(v[np.array(f)])


def _ascii(tris, name="t", normals=None):
    out = [f"solid {name}"]
    for k, t in enumerate(tris):
        n = normals[k] if normals is not None else (0, 0, 0)
        out.append(f"  facet normal {n[0]:g} {n[1]:g} {n[2]:g}\n    outer loop")
        out += [f"      vertex {x!r} {y!r} {z!r}" for x, y, z in np.asarray(t, float).tolist()]
        out.append("    endloop\n  endfacet")
    out.append(f"endsolid {name}\n")
    return "\n".join(out)


def _binary(tris, header=b"cnclab", count=None):
    tris = np.asarray(tris, np.float32)
    rec = np.zeros(len(tris), np.dtype([("n", "<f4", (3,)), ("v", "<f4", (3, 3)), ("a", "<u2")]))
    rec["v"] = tris
    head = header.ljust(80, b" ")[:80]
    return head + np.uint32(len(tris) if count is None else count).tobytes() + rec.tobytes()


def _independent_stl(raw: bytes):
    """Facets (F, 3, 3) as an independent decoder reads them, or None if not decodable simply."""
    if len(raw) >= 84 and 84 + 50 * int.from_bytes(raw[80:84], "little") == len(raw):
        rec = np.frombuffer(raw, np.dtype([("n", "<f4", (3,)), ("v", "<f4", (3, 3)), ("a", "<u2")]), offset=84)
        return rec["v"].astype(float)
    text = raw.decode("ascii")
    v = [[float(t) for t in ln.split()[1:4]] for ln in text.splitlines() if ln.split()[:1] == ["vertex"]
         or (ln.split() and ln.split()[0].lower() == "vertex")]
    return np.asarray(v, float).reshape(-1, 3, 3)


def _same_facets(a, b, atol=0.0):
    """Equal facet by facet, up to reversal of the vertex order (the orientation rule)."""
    if a.shape != b.shape:
        return False
    fwd = np.abs(a - b).max(axis=(1, 2)) <= atol
    rev = np.abs(a[:, ::-1] - b).max(axis=(1, 2)) <= atol
    # reversal keeps the first vertex when done as t[:, ::-1]: compare as reversed triples
    return bool((fwd | rev).all())


def _check_stl(path: Path, raw: bytes, kind: str):
    """Read ``path`` and classify: an error naming the file, or a verified correct result."""
    h = _sha(path)
    listing = sorted(os.listdir(path.parent))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", STLWarning)
            m = read_stl(path)
    except (ValueError, OSError) as exc:
        msg = str(exc)
        assert isinstance(exc, STLError) or isinstance(exc, OSError), repr(exc)
        assert str(path) in msg, msg
        if m_ascii(raw) and "binary" not in msg:
            assert re.search(re.escape(str(path)) + r"(:\d+|: empty|: STL has no facets)", msg), msg
        outcome = "error"
    else:
        ref = _independent_stl(raw)
        assert m.n_facets == len(ref), (m.n_facets, len(ref))     # nothing dropped or invented
        assert _same_facets(m.triangles, ref)
        assert np.isfinite(m.triangles).all()
        assert (np.linalg.norm(m.normals, axis=1) > 0.999).all()
        back = read_stl(write_stl(path.parent / "out" / "re.stl", m))
        np.testing.assert_allclose(back.triangles, m.triangles.astype(np.float32), atol=0)
        assert back.info["reoriented_facets"] == 0                   # the result is already consistent
        (path.parent / "out" / "re.stl").unlink()
        (path.parent / "out").rmdir()
        outcome = "correct"
    assert _sha(path) == h
    assert sorted(os.listdir(path.parent)) == listing
    OUTCOMES[(kind, outcome)] += 1
    return outcome


def m_ascii(raw: bytes) -> bool:
    n = int.from_bytes(raw[80:84], "little") if len(raw) >= 84 else -1
    return raw.lstrip()[:5].lower() == b"solid" and 84 + 50 * n != len(raw)


GRID = _grid_mesh()
BOX = _box()


def _stl_cases():
    T = GRID.triangles
    asc = _ascii(T)
    binr = _binary(T)
    cases = {
        # the examples
        "binary count < facets held": (_binary(T, count=len(T) - 3), "error", "inconsistent binary STL"),
        "binary count > facets held": (_binary(T, count=len(T) + 3), "error", "truncated binary STL"),
        "ascii two solids -> all": (asc + _ascii(T + [0, 0, 5], "second"), "correct", None),
        "ascii missing endloop": (asc.replace("    endloop\n", "", 1), "error", r":7: expected 'vertex x y z' or 'endloop'"),
        "ascii trailing blank lines": (asc + "\n\n   \n\n", "correct", None),
        "binary header starts with solid": (_binary(T, header=b"solid exported by X"), "correct", None),
        "binary header 'solid' + short": (_binary(T, header=b"solid x")[:-7], "error", "non-ASCII|truncated|expected"),
        # non-finite, degenerate, empty
        "binary nan": (_binary(np.where(np.arange(T.size).reshape(T.shape) == 4, np.nan, T)), "error", r"\(facet 0\): non-finite"),
        "binary inf": (_binary(np.where(np.arange(T.size).reshape(T.shape) == 40, np.inf, T)), "error", r"\(facet 4\): non-finite"),
        "ascii nan": (asc.replace(f"vertex {float(T[1, 0, 0])!r}", "vertex nan", 1), "error", r":\d+: non-finite"),
        "ascii inf": (asc.replace(f"vertex {float(T[1, 0, 0])!r}", "vertex -inf", 1), "error", r":\d+: non-finite"),
        "ascii overflow 1e999": (asc.replace(f"vertex {float(T[1, 0, 0])!r}", "vertex 1e999", 1), "error", r":\d+: non-finite"),
        "degenerate facet": (_ascii(np.concatenate([T, [[[0, 0, 0], [1, 1, 1], [2, 2, 2]]]])), "error", r":\d+: facet \d+ has zero area"),
        "binary degenerate": (_binary(np.concatenate([T, [[[0, 0, 0], [0, 0, 0], [1, 0, 0]]]])), "error", r"\(facet \d+\): facet \d+ has zero area"),
        "binary duplicated facet": (_binary(np.concatenate([T, T[2:3]])), "error", r"\(facet \d+\): facet \d+ repeats facet 2"),
        "ascii duplicated facet reversed": (_ascii(np.concatenate([T, T[2:3, ::-1]])), "error", r":\d+: facet \d+ repeats facet 2"),
        "ascii vertex at 1e200": (_ascii(np.where(np.arange(T.size).reshape(T.shape) == 9, 1e200, T)), "error",
                                  r":\d+: facet 1 has a vertex coordinate 1e\+200 mm, beyond"),
        "ascii vertex at -1e10": (_ascii(np.where(np.arange(T.size).reshape(T.shape) == 30, -1e10, T)), "error",
                                  r":\d+: facet 3 has a vertex coordinate 1e\+10 mm, beyond"),
        "binary vertex at 1e30": (_binary(np.where(np.arange(T.size).reshape(T.shape) == 40, 1e30, T)), "error",
                                  r"\(facet 4\): facet 4 has a vertex coordinate 1e\+30 mm, beyond"),
        "empty file": (b"", "error", "empty STL"),
        "whitespace only": (b"  \n\n", "error", "empty STL"),
        "solid without facets": (b"solid x\nendsolid x\n", "error", "no facets"),
        "binary zero facets": (_binary(np.zeros((0, 3, 3))), "error", "no facets"),
        "83 bytes": (b"\0" * 83, "error", "truncated binary STL"),
        "binary + 1 byte": (binr + b"\0", "error", "inconsistent binary STL"),
        "binary - 1 byte": (binr[:-1], "error", "truncated binary STL"),
        # garbled ASCII
        "ascii no endsolid": (asc.rsplit("endsolid", 1)[0], "error", "no 'endsolid'"),
        "ascii 4 vertices": (asc.replace("    endloop\n", f"      vertex 1 2 3\n    endloop\n", 1), "error", "more than 3 vertices"),
        "ascii 2 vertices": (asc.replace(f"      vertex {float(T[0, 2, 0])!r} {float(T[0, 2, 1])!r} {float(T[0, 2, 2])!r}\n", "", 1), "error", "has 2 vertices"),
        "ascii 2_0 number": (asc.replace(f"vertex {float(T[1, 0, 0])!r}", "vertex 2_0", 1), "error", r":\d+: garbled vertex value"),
        "ascii full-width digit": (asc.replace(f"vertex {float(T[1, 0, 0])!r}", "vertex \uff11", 1), "error", r":\d+: non-ASCII"),
        "ascii hex": (asc.replace(f"vertex {float(T[1, 0, 0])!r}", "vertex 0x10", 1), "error", r":\d+: garbled vertex value"),
        "ascii comma decimal": (asc.replace(f"vertex {float(T[1, 0, 0])!r}", "vertex 1,5", 1), "error", r":\d+: garbled vertex value"),
        "ascii 2 coords": (asc.replace(f" {float(T[1, 0, 2])!r}\n", "\n", 1), "error", r":\d+: garbled vertex line"),
        "ascii text after endsolid": (asc + "garbage\n", "error", r":\d+: expected 'solid'"),
        "ascii missing endfacet": (asc.replace("  endfacet\n", "", 1), "error", r":\d+: expected 'endfacet'"),
        "ascii missing outer loop": (asc.replace("    outer loop\n", "", 1), "error", r":\d+: expected 'outer loop'"),
        "ascii facet without normal": (asc.replace("facet normal 0 0 0", "facet", 1), "error", r":\d+: garbled facet line"),
        "ascii latin-1 byte": (asc.replace("solid t", "solid t\xe9", 1).encode("latin-1"), "error", r":1: non-ASCII"),
        "ascii CRLF": (asc.replace("\n", "\r\n"), "correct", None),
        "ascii upper case keywords": (asc.upper().replace("SOLID T", "SOLID T"), "correct", None),
        "ascii tabs and blank lines inside": (asc.replace("    outer loop", "\n\t outer \t loop\n"), "correct", None),
        # winding / normals
        "closed box wound clockwise": (_ascii(BOX.triangles[:, ::-1], normals=BOX.normals), "correct", None),
        "open grid mixed winding": (_binary(np.where((np.arange(len(T)) % 3 == 0)[:, None, None], T[:, ::-1], T)), "correct", None),
        "open grid wound clockwise": (_binary(T[:, ::-1]), "correct", None),
    }
    return cases


STL_CASES = _stl_cases()


@pytest.mark.parametrize("name", list(STL_CASES))
def test_stl_hostile_table(tmp_path, name):
    data, expect, pattern = STL_CASES[name]
    raw = data.encode("ascii", errors="surrogateescape") if isinstance(data, str) and data.isascii() else \
        (data.encode("utf-8") if isinstance(data, str) else data)
    p = tmp_path / "case.stl"
    p.write_bytes(raw)
    if expect == "error":
        h = _sha(p)
        with pytest.raises(ValueError, match=pattern) as e:
            read_stl(p)
        assert str(p) in str(e.value)
        assert _sha(p) == h and os.listdir(tmp_path) == ["case.stl"]
        OUTCOMES[("stl", "error")] += 1
    else:
        assert _check_stl(p, raw, "stl") == "correct"


@pytest.mark.parametrize("binary", [True, False])
def test_stl_drop_removes_duplicates_and_degenerates(tmp_path, binary):
    """degenerate='drop' on repeated (and zero-area) facets: the original facets, each once, counted."""
    T = GRID.triangles
    bad = np.concatenate([T, T[2:3], T[5:6, ::-1], [[[0, 0, 0], [1, 1, 1], [2, 2, 2]]]])
    p = tmp_path / "dup.stl"
    p.write_bytes(_binary(bad) if binary else _ascii(bad).encode("ascii"))
    m = read_stl(p, degenerate="drop", orient="keep")
    assert m.info["dropped_duplicate"] == 2 and m.info["dropped_degenerate"] == 1
    np.testing.assert_allclose(m.triangles, T.astype(np.float32) if binary else T, rtol=0, atol=1e-12)
    OUTCOMES[("stl", "correct")] += 1


def test_stl_winding_is_reconciled_and_reported(tmp_path):
    """Clockwise facets: same mesh as the counter-clockwise file, outward/upward, count reported."""
    ccw = tmp_path / "ccw.stl"
    ccw.write_text(_ascii(BOX.triangles))
    cw = tmp_path / "cw.stl"
    cw.write_text(_ascii(BOX.triangles[:, ::-1]))
    a = read_stl(ccw)
    with pytest.warns(STLWarning, match=r"cw.stl: 12 of 12 facets re-oriented"):
        b = read_stl(cw)
    assert a.info["reoriented_facets"] == 0 and b.info["reoriented_facets"] == 12
    np.testing.assert_array_equal(a.normals, b.normals)
    centre = BOX.triangles.reshape(-1, 3).mean(axis=0)
    assert ((b.centroids - centre) * b.normals).sum(axis=1).min() > 0      # outward
    # an open surface wound clockwise is turned upward; 'keep' leaves the file's winding
    g = tmp_path / "g.stl"
    g.write_bytes(_binary(GRID.triangles[:, ::-1]))
    with pytest.warns(STLWarning):
        up = read_stl(g)
    assert (up.normals[:, 2] > 0).all()
    assert (read_stl(g, orient="keep").normals[:, 2] < 0).all()
    OUTCOMES[("stl", "correct")] += 3


def test_clockwise_part_does_not_shift_spindle_speed(tmp_path):
    """The issue's 372 rpm shift: a closed part wound clockwise must give the same schedule."""
    from cnclab.geometry.freeform_part import FreeformPart, freeform_part_mesh
    part = freeform_part_mesh(FreeformPart(), 5.0, closed=True)
    p1 = write_stl(tmp_path / "a.stl", part)
    p2 = tmp_path / "b.stl"
    p2.write_bytes(_binary(part.triangles[:, ::-1]))
    x = np.linspace(5, 95, 40)
    P = np.column_stack([x, np.full_like(x, 40.0), FreeformPart().height_at(x, np.full_like(x, 40.0))])
    cl = apt.cl_program([P], 500, 2000, 10, 60).cl_points()
    kw = dict(tool_diameter=10, a_p=0.3, v_c=63, f_z=0.125, teeth=2)
    with pytest.warns(STLWarning):
        m2 = read_stl(p2)
    s1 = sc.spindle_schedule(read_stl(p1), cl, **kw)
    s2 = sc.spindle_schedule(m2, cl, **kw)
    np.testing.assert_allclose(s1.n, s2.n, rtol=1e-12)
    OUTCOMES[("stl", "correct")] += 1


# ---------------------------------------------------------------- STL mutations (hypothesis)
_HOSTILE_NUMS = ["nan", "inf", "-inf", "1e999", "2_0", "\uff11", "0x1f", "1,5", "1.2.3", "--1", "", ".", "1e",
                 "1d3", "+", "١", "1 2", "0.0", "-0", "1e-320", "123456789012345678901234567890"]


@st.composite
def _binary_mutation(draw):
    raw = bytearray(_binary(GRID.triangles))
    op = draw(st.sampled_from(["flip", "truncate", "append", "count", "dup", "drop", "header"]))
    if op == "flip":
        for _ in range(draw(st.integers(1, 4))):
            i = draw(st.integers(0, len(raw) - 1))
            raw[i] ^= 1 << draw(st.integers(0, 7))
    elif op == "truncate":
        raw = raw[:draw(st.integers(0, len(raw) - 1))]
    elif op == "append":
        raw += draw(st.binary(min_size=1, max_size=120))
    elif op == "count":
        raw[80:84] = draw(st.integers(0, 2**32 - 1)).to_bytes(4, "little")
    elif op == "dup":
        k = draw(st.integers(0, len(GRID.triangles) - 1))
        raw += raw[84 + 50 * k:134 + 50 * k]
    elif op == "drop":
        k = draw(st.integers(0, len(GRID.triangles) - 1))
        del raw[84 + 50 * k:134 + 50 * k]
    else:
        raw[:80] = draw(st.sampled_from([b"solid", b"SOLID x", b"  solid\n", b"\0"])).ljust(80, b"\0")
    return bytes(raw)


@FUZZ
@given(raw=_binary_mutation())
def test_fuzz_binary_stl(tmp_path_factory, raw):
    d = tmp_path_factory.mktemp("bstl")
    p = d / "m.stl"
    p.write_bytes(raw)
    _check_stl(p, raw, "stl")


@st.composite
def _ascii_mutation(draw):
    lines = _ascii(GRID.triangles[:6]).split("\n")
    for _ in range(draw(st.integers(1, 3))):
        op = draw(st.sampled_from(["del", "dup", "num", "kw", "trunc", "blank", "case", "swap"]))
        i = draw(st.integers(0, len(lines) - 1))
        if op == "del":
            del lines[i]
        elif op == "dup":
            lines.insert(i, lines[i])
        elif op == "num":
            toks = lines[i].split()
            if len(toks) > 1:
                toks[draw(st.integers(1, len(toks) - 1))] = draw(st.sampled_from(_HOSTILE_NUMS))
                lines[i] = "  ".join(toks)
        elif op == "kw":
            lines[i] = draw(st.sampled_from(["endloop", "endfacet", "outer loop", "facet normal 0 0 1",
                                             "solid again", "endsolid", "vertex 1 2 3", "loop"]))
        elif op == "trunc":
            lines = lines[:i]
        elif op == "blank":
            lines.insert(i, draw(st.sampled_from(["", "   ", "\t"])))
        elif op == "case":
            lines[i] = lines[i].upper()
        else:
            j = draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
        if not lines:
            break
    return "\n".join(lines).encode("utf-8")


@FUZZ
@given(raw=_ascii_mutation())
def test_fuzz_ascii_stl(tmp_path_factory, raw):
    d = tmp_path_factory.mktemp("astl")
    p = d / "m.stl"
    p.write_bytes(raw)
    _check_stl(p, raw, "stl")


# ============================================================================ APT
VALID_APT = """PARTNO / FUZZ
UNITS / MM
$$-> CUTTER / 10.000000
SPINDL / RPM, 2000, CLW
RAPID
FROM / 10.000, 0.000, 30.000
RAPID
GOTO / 10.000, 0.000, 1.000
FEDRAT / 500.0, MMPM
GOTO / 10.000, 0.000, 0.000
CIRCLE / 0.000, 0.000, 0.000, 0.000, 0.000, 1.000, 10.000
GOTO / 0.000, 10.000, 0.000
""" + "".join(f"GOTO / {-0.5 * i:.3f}, 10.000, 0.000\n" for i in range(1, 11)) + """RAPID
GOTO / -5.000, 10.000, 30.000
FINI
"""


def _records_ok(prog: apt.AptProgram, text: str):
    """The 'correct result' oracle for APT (see module docstring)."""
    careful = apt.parse_apt(text, prog.source, fast=False)
    assert prog.to_text() == careful.to_text() == text.lstrip("\ufeff")
    recs = prog.records
    assert recs == careful.records
    seen_units = False
    for k, r in enumerate(recs):
        if r.word == "UNITS":
            assert [a.upper() for a in r.args] == ["MM"]
            seen_units = True
        if r.word in ("GOTO", "FROM", "CIRCLE"):
            assert seen_units
            assert all(apt.NUMBER_RE.fullmatch(a) for a in r.args), r.args
        if r.word == "CIRCLE":
            nxt = [q for q in recs[k + 1:] if q.word][0]
            assert nxt.word == "GOTO"
        assert r.word.split()[0] not in apt.REFUSED_MOTION if r.word else True
    cl = prog.cl_points()
    np.testing.assert_array_equal(cl.xyz, careful.cl_points().xyz)
    assert np.isfinite(cl.xyz).all()
    back = apt.parse_apt(prog.to_text(), "re.apt")
    np.testing.assert_array_equal(back.cl_points().xyz, cl.xyz)


def _check_apt_text(text: str, tmp: Path, kind="apt"):
    p = tmp / "in.apt"
    p.write_bytes(text.encode("utf-8", errors="surrogateescape"))
    h = _sha(p)
    try:
        prog = apt.read_apt(p)
        cl = prog.cl_points()
    except (ValueError, OSError) as exc:
        assert re.search(re.escape(str(p)) + r":\d+: ", str(exc)) or \
            re.search(re.escape(str(p)) + r": empty program", str(exc)), str(exc)
        outcome = "error"
    else:
        _records_ok(prog, p.read_bytes().decode("utf-8"))
        assert len(cl) > 0
        outcome = "correct"
    assert _sha(p) == h and os.listdir(tmp) == ["in.apt"]
    OUTCOMES[(kind, outcome)] += 1
    return outcome


APT_CASES = {
    # the examples
    "no UNITS": (VALID_APT.replace("UNITS / MM\n", ""), "error", r":5: FROM before any UNITS"),
    "BOM before UNITS/INCH": ("\ufeff" + VALID_APT.replace("UNITS / MM", "UNITS / INCH"), "error", r":2: UNITS/INCH"),
    "BOM first line UNITS/INCH": ("\ufeffUNITS / INCH\n" + VALID_APT, "error", r":1: UNITS/INCH"),
    "BOM valid": ("\ufeff" + VALID_APT, "correct", None),
    "2_0.000 in GOTO": (VALID_APT.replace("GOTO / 10.000, 0.000, 1.000", "GOTO / 2_0.000, 0.000, 1.000"), "error", r":8: GOTO value '2_0.000'"),
    "2_0.000 in FEDRAT": (VALID_APT.replace("FEDRAT / 500.0", "FEDRAT / 5_00.0"), "error", r":9: FEDRAT argument '5_00.0'"),
    "full-width digits": (VALID_APT.replace("GOTO / 10.000, 0.000, 0.000", "GOTO / \uff11\uff10, 0.000, 0.000"), "error", r":10: GOTO value"),
    "arabic-indic digits": (VALID_APT.replace("GOTO / 10.000, 0.000, 0.000", "GOTO / \u0661\u0660, 0, 0"), "error", r":10: GOTO value"),
    "nan": (VALID_APT.replace("GOTO / 10.000, 0.000, 0.000", "GOTO / nan, 0, 0"), "error", r":10: GOTO has a non-finite"),
    "inf": (VALID_APT.replace("GOTO / 10.000, 0.000, 0.000", "GOTO / 10, inf, 0"), "error", r":10: GOTO has a non-finite"),
    "1e999": (VALID_APT.replace("GOTO / 10.000, 0.000, 0.000", "GOTO / 10, 1e999, 0"), "error", r":10: GOTO has a non-finite"),
    "hex": (VALID_APT.replace("GOTO / 10.000, 0.000, 0.000", "GOTO / 0x0A, 0, 0"), "error", r":10: GOTO value '0x0A'"),
    "SPINDL nan": (VALID_APT.replace("RPM, 2000", "RPM, nan"), "error", r":4: SPINDL"),
    "FEDRAT infinity": (VALID_APT.replace("FEDRAT / 500.0", "FEDRAT / Infinity"), "error", r":9: FEDRAT"),
    "CIRCLE arc kept": (VALID_APT, "correct", None),
    "CIRCLE clockwise": (VALID_APT.replace("0.000, 0.000, 1.000, 10.000", "0.000, 0.000, -1.000, 10.000"), "correct", None),
    "CIRCLE 11 values": (VALID_APT.replace("1.000, 10.000\n", "1.000, 10.000, 0.01, 0, 10, 0\n"), "correct", None),
    "CIRCLE wrong radius": (VALID_APT.replace("1.000, 10.000\n", "1.000, 12.000\n"), "error", r":11: CIRCLE radius 12"),
    "CIRCLE end off the circle": (VALID_APT.replace("GOTO / 0.000, 10.000, 0.000", "GOTO / 0.000, 10.100, 0.000"), "error", r":11: CIRCLE radius"),
    "CIRCLE axis X": (VALID_APT.replace("0.000, 0.000, 1.000, 10.000", "1.000, 0.000, 0.000, 10.000"), "error", r":11: CIRCLE axis"),
    "CIRCLE radius 0": (VALID_APT.replace("1.000, 10.000\n", "1.000, 0\n"), "error", r":11: CIRCLE radius must be > 0"),
    "CIRCLE 6 values": (VALID_APT.replace("1.000, 10.000\n", "1.000\n"), "error", r":11: CIRCLE needs 7"),
    "CIRCLE then FEDRAT": (VALID_APT.replace("10.000\nGOTO / 0.000, 10", "10.000\nFEDRAT / 400\nGOTO / 0.000, 10"), "error", r":12: CIRCLE of line 11 must be followed"),
    "CIRCLE then RAPID": (VALID_APT.replace("10.000\nGOTO / 0.000, 10", "10.000\nRAPID\nGOTO / 0.000, 10"), "error", r":12: CIRCLE of line 11"),
    "CIRCLE at the end": (VALID_APT.replace("FINI\n", "CIRCLE / 0,0,0,0,0,1,5\n"), "error", r":\d+: CIRCLE"),
    "CIRCLE after RAPID": (VALID_APT.replace("GOTO / 10.000, 0.000, 0.000\nCIRCLE", "GOTO / 10.000, 0.000, 0.000\nRAPID\nCIRCLE"), "error", r":12: CIRCLE after RAPID"),
    "CIRCLE no start point": ("UNITS / MM\nFEDRAT / 500\nCIRCLE / 0,0,0,0,0,1,10\nGOTO / 0, 10, 0\n", "error", r":3: CIRCLE with an unknown start"),
    "GODLTA refused": (VALID_APT.replace("RAPID\nGOTO / -5", "GODLTA / 0, 0, 30\nRAPID\nGOTO / -5"), "error", r":\d+: motion record GODLTA"),
    "INDIRV refused": (VALID_APT.replace("FINI", "INDIRV / 1, 0, 0"), "error", r":\d+: motion record INDIRV"),
    "CYCLE refused": (VALID_APT.replace("FINI", "CYCLE / DRILL, 5, 100"), "error", r":\d+: motion record CYCLE"),
    "GOTO without slash": (VALID_APT.replace("GOTO / 10.000, 0.000, 0.000", "GOTO 10.000, 0.000, 0.000"), "error", r":10: malformed GOTO"),
    "full-width word": (VALID_APT.replace("GOTO / 10.000, 0.000, 0.000", "\uff27OTO / 10.000, 0.000, 0.000"), "error", r":10: .* does not start with an APT word"),
    "UNITS MM, INCH": (VALID_APT.replace("UNITS / MM", "UNITS / MM, INCH"), "error", r":2: unknown UNITS"),
    "UNITS CM": (VALID_APT.replace("UNITS / MM", "UNITS / CM"), "error", r":2: unknown UNITS"),
    "lower-case units": (VALID_APT.replace("UNITS / MM", "units/mm"), "correct", None),
    "FEDRAT IPM": (VALID_APT.replace("500.0, MMPM", "20, IPM"), "error", r":9: FEDRAT in IPM"),
    "FEDRAT 0": (VALID_APT.replace("500.0, MMPM", "0, MMPM"), "error", r":9: FEDRAT needs a positive"),
    "feed before FEDRAT": (VALID_APT.replace("FEDRAT / 500.0, MMPM\n", ""), "error", r":\d+: feed motion"),
    "GOTO 6 values": (VALID_APT.replace("GOTO / -5.000, 10.000, 30.000", "GOTO / -5.000, 10.000, 30.000, 0, 0, 1"), "correct", None),
    "GOTO 4 values": (VALID_APT.replace("GOTO / -5.000, 10.000, 30.000", "GOTO / -5.000, 10.000, 30.000, 1"), "error", r"GOTO needs 3"),
    "CRLF": (VALID_APT.replace("\n", "\r\n"), "correct", None),
    "continuation at EOF": (VALID_APT + "GOTO / 1, 2, $\n", "error", r"continuation"),
    "only comments": ("$$ nothing\n", "error", r"empty program"),
    "empty": ("", "error", r"empty program"),
    "non-UTF-8 byte": (VALID_APT.replace("PARTNO / FUZZ", "PARTNO / FUZZ\udce9"), "error", r":1: not a UTF-8"),
}


@pytest.mark.parametrize("name", list(APT_CASES))
def test_apt_hostile_table(tmp_path, name):
    text, expect, pattern = APT_CASES[name]
    p = tmp_path / "in.apt"
    p.write_bytes(text.encode("utf-8", errors="surrogateescape"))
    if expect == "error":
        with pytest.raises(ValueError, match=pattern) as e:
            apt.read_apt(p).cl_points()
        assert str(p) in str(e.value)
        OUTCOMES[("apt", "error")] += 1
    else:
        assert _check_apt_text(text, tmp_path) == "correct"


def test_bom_does_not_change_the_program():
    a = apt.parse_apt(VALID_APT, "a").cl_points()
    b = apt.parse_apt("\ufeff" + VALID_APT, "a").cl_points()
    np.testing.assert_array_equal(a.xyz, b.xyz)
    OUTCOMES[("apt", "correct")] += 1


def test_circle_is_an_arc_through_to_gcode():
    """CIRCLE: arc length in the schedule, G3/G2 in the G-code, SPINDL/FEDRAT never inside the pair."""
    from cnclab.nc.gcode import parse_gcode
    from cnclab.nc.program import write_moves
    prog = apt.parse_apt(VALID_APT, "c.apt")
    cl = prog.cl_points()
    k = int(np.flatnonzero(cl.arc)[0])
    assert cl.arc[k] == 3 and np.allclose(cl.centre[k], 0)          # G3 (the ToolPath convention)
    assert np.isclose(cl.segment_lengths()[k], np.pi / 2 * 10)
    mesh = tessellate_heightfield(lambda x, y: 0 * x, (-15, 15), (-5, 15), 6, 4)
    s = sc.spindle_schedule(mesh, cl, tool_diameter=10, a_p=0.3, v_c=63, f_z=0.125, teeth=2)
    s.n[:] = np.arange(len(s.n)) * 200 + 3000      # force an insertion before every feed point
    s.v_f[:] = s.n * 0.25
    new, counts = sc.insert_spindle_records(prog, cl, s, rpm_threshold=1, vf_threshold=1)
    words = [r.word for r in new.records]
    i = words.index("CIRCLE")
    assert words[i + 1] == "GOTO" and words[i - 1] in ("SPINDL", "FEDRAT")
    back = apt.parse_apt(new.to_text(), "n.apt").cl_points()           # still a valid program
    assert np.count_nonzero(back.arc) == 1
    moves = parse_gcode(write_moves(sc.to_gcode_moves(new)), "x.ngc")
    arcs = [m for m in moves if m.motion in ("G2", "G3")]
    assert len(arcs) == 1 and arcs[0].motion == "G3" and np.isclose(arcs[0].i, -10) and np.isclose(arcs[0].j, 0)
    cw = apt.parse_apt(VALID_APT.replace("0.000, 0.000, 1.000, 10.000", "0.000, 0.000, -1.000, 10.000"), "c")
    assert np.isclose(cw.cl_points().segment_lengths()[k], 1.5 * np.pi * 10)
    assert [m.motion for m in sc.to_gcode_moves(cw) if m.motion in ("G2", "G3")] == ["G2"]
    OUTCOMES[("apt", "correct")] += 2


_APT_INSERTS = ["CIRCLE / 0, 0, 0, 0, 0, 1, 10", "GODLTA / 0, 0, 1", "UNITS / INCH", "UNITS / MM", "RAPID",
                "FEDRAT / 300, MMPM", "FEDRAT / nan", "SPINDL / RPM, 1_000, CLW", "GOTO / 1, 2, 3",
                "GOTO / 1, 2", "GOTO / \uff11, 2, 3", "$$ comment", "", "GOTO / 1, 2, 3 $", "FROM / 0, 0, 0",
                "CIRCLE / 0, 0, 0, 1, 0, 0, 10", "PPRINT hello", "COOLNT / ON", "END", "goto/1,2,3", "\ufeffUNITS/MM"]


@st.composite
def _apt_mutation(draw):
    lines = VALID_APT.split("\n")
    for _ in range(draw(st.integers(1, 3))):
        op = draw(st.sampled_from(["del", "dup", "num", "ins", "trunc", "flip", "swap"]))
        i = draw(st.integers(0, len(lines) - 1))
        if op == "del":
            del lines[i]
        elif op == "dup":
            lines.insert(i, lines[i])
        elif op == "num":
            toks = re.split(r"(,|/)", lines[i])
            nums = [j for j, t in enumerate(toks) if re.fullmatch(r"\s*[-+0-9.]+\s*", t)]
            if nums:
                toks[draw(st.sampled_from(nums))] = " " + draw(st.sampled_from(_HOSTILE_NUMS))
                lines[i] = "".join(toks)
        elif op == "ins":
            lines.insert(i, draw(st.sampled_from(_APT_INSERTS)))
        elif op == "trunc":
            lines[i] = lines[i][:draw(st.integers(0, max(len(lines[i]) - 1, 0)))]
        elif op == "flip":
            if lines[i]:
                j = draw(st.integers(0, len(lines[i]) - 1))
                lines[i] = lines[i][:j] + chr(ord(lines[i][j]) ^ (1 << draw(st.integers(0, 6)))) + lines[i][j + 1:]
        else:
            j = draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
        if not lines:
            break
    return "\n".join(lines)


@settings(max_examples=250, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(text=_apt_mutation())
def test_fuzz_apt(tmp_path_factory, text):
    _check_apt_text(text, tmp_path_factory.mktemp("apt"))


# ============================================================================ public API
def _api_cases():
    inf = np.inf
    ok = {  # name -> (callable, expected value computed independently)
        "theta_concave rho=inf": (lambda: engagement.theta_concave(1.5, inf, 3.0), 60.0),
        "theta_convex rho=inf": (lambda: engagement.theta_convex(1.5, inf, 3.0), 60.0),
        "theta_concave rho=1e300": (lambda: engagement.theta_concave(1.5, 1e300, 3.0), 60.0),
        "theta_convex rho=1e200": (lambda: engagement.theta_convex(1.5, 1e200, 3.0), 60.0),
        "stepover concave rho=inf": (lambda: engagement.stepover_thesis1(60.0, inf, 3.0, "concave"), 1.5),
        "stepover convex rho=inf": (lambda: engagement.stepover_thesis1(60.0, inf, 3.0, "convex"), 1.5),
        "kim_yang R=inf": (lambda: engagement.theta_kim_yang(1.5, inf, 3.0), 60.0),
        "kim_yang_to_jacso R=inf": (lambda: engagement.kim_yang_to_jacso(1.5, inf)[0], inf),
        "theta_arc array with inf": (lambda: engagement.theta_concave(np.array([1.5, 3.0]), np.array([inf, inf]), 3.0)[1], 90.0),
    }
    bad = {  # name -> (callable, regex naming the parameter)
        "kim_yang_to_jacso R<s": (lambda: engagement.kim_yang_to_jacso(5.0, 3.0), r"R \(machined corner radius\)"),
        "kim_yang_to_jacso R=s": (lambda: engagement.kim_yang_to_jacso(3.0, 3.0), r"R \(machined"),
        "kim_yang_to_jacso s<0": (lambda: engagement.kim_yang_to_jacso(-1.0, 3.0), r"s \(stepover\)"),
        "kim_yang_to_jacso s nan": (lambda: engagement.kim_yang_to_jacso(np.nan, 3.0), r"s \(stepover\)"),
        "kim_yang_to_jacso R nan": (lambda: engagement.kim_yang_to_jacso(1.0, np.nan), r"R \(machined"),
        "kim_yang_to_jacso shapes": (lambda: engagement.kim_yang_to_jacso([1, 2], [5, 6, 7]), r"s, R must have broadcastable"),
        "theta_concave shapes": (lambda: engagement.theta_concave([1, 2], [5, 6, 7], 3), r"s, rho, tool_radius"),
        "theta_concave rho nan": (lambda: engagement.theta_concave(1, np.nan, 3), r"rho"),
        "theta_concave rho<0": (lambda: engagement.theta_concave(1, -5, 3), r"rho"),
        "theta_straight s>2r": (lambda: engagement.theta_straight(7, 3), r"s \(stepover\)"),
        "theta_straight r=0": (lambda: engagement.theta_straight(1, 0), r"tool_radius"),
        "theta_straight r=inf": (lambda: engagement.theta_straight(1, inf), r"tool_radius"),
        "stepover theta=0": (lambda: engagement.stepover_thesis1(0, 5, 3, "concave"), r"theta_deg"),
        "stepover theta nan": (lambda: engagement.stepover_thesis1(np.nan, 5, 3, "concave"), r"theta_deg"),
        "stepover rho<r sin": (lambda: engagement.stepover_thesis1(90, 1, 3, "concave"), r"rho must be >= r sin"),
        "stepover kind": (lambda: engagement.stepover_thesis1(60, 5, 3, "wavy"), r"kind"),
        "stepover shapes": (lambda: engagement.stepover_thesis1([60, 70], [5, 6, 7], 3, "concave"), r"theta_deg, rho"),
        "kim_yang R<=r": (lambda: engagement.theta_kim_yang(1, 2, 3), r"R \(corner radius\)"),
        "tangent_point_diameters shapes": (lambda: ball_end.tangent_point_diameters(10, 0.3, [1, 2], [1, 2, 3], 0),
                                           r"A_N1 \(2,\), A_N2 \(3,\)"),
        "tangent_point_diameters D nan": (lambda: ball_end.tangent_point_diameters(np.nan, 0.3, 0, 0, 0), r"\bD\b"),
        "tangent_point_diameters a_p>D/2": (lambda: ball_end.tangent_point_diameters(10, 6, 0, 0, 0), r"a_p must be in"),
        "tangent_point_diameters A_N2 100": (lambda: ball_end.tangent_point_diameters(10, 0.3, 0, 100, 0), r"A_N2"),
        "tangent_point_diameters A_f inf": (lambda: ball_end.tangent_point_diameters(10, 0.3, 0, 10, inf), r"A_f"),
        "tangent_point_diameters str": (lambda: ball_end.tangent_point_diameters("x", 0.3, 0, 10, 0), r"\bD\b"),
        "cut_point_diameters a_e<0": (lambda: ball_end.cut_point_diameters(10, 0.3, -1, 0, 10, 0), r"a_e"),
        "spindle_speed shapes": (lambda: __import__("cnclab.cutting.speeds", fromlist=["x"]).spindle_speed([1, 2], [3, 4, 5]),
                                 r"v_c_m_min, diameter_mm"),
        "spindle_speed d=0": (lambda: __import__("cnclab.cutting.speeds", fromlist=["x"]).spindle_speed(63, 0), r"diameter_mm"),
        "feed_speed teeth 2.7": (lambda: __import__("cnclab.cutting.speeds", fromlist=["x"]).feed_speed(0.1, 2.7, 1000), r"teeth"),
        "cusp_height_turning feed nan": (lambda: _cusp().cusp_height_turning(np.nan, 1.0), r"feed must be finite"),
        "cusp_height_turning shapes": (lambda: _cusp().cusp_height_turning([0.1, 0.2], [1, 2, 3]), r"spacing and corner_radius"),
        "cusp_height_zlevel A=180": (lambda: _cusp().cusp_height_zlevel(0.1, 1.0, 180), r"inclination A"),
        "cusp spacing > 2 RE": (lambda: _cusp().cusp_height_from_spacing(3.0, 1.0), r"spacing must be <= 2"),
        "schedule teeth 2.7": (lambda: _sched(teeth=2.7), r"teeth"),
        "schedule v_c nan": (lambda: _sched(v_c=np.nan), r"v_c"),
        "schedule a_p -1": (lambda: _sched(a_p=-1), r"a_p"),
        "schedule feed_direction nan": (lambda: _sched(feed_direction_deg=np.nan), r"feed_direction_deg"),
        "schedule n_min > n_max": (lambda: _sched(n_min=5000, n_max=4000), r"n_min"),
        "schedule accel nan": (lambda: _sched(accel_rpm_s=np.nan), r"accel_rpm_s"),
        "insert rpm_threshold nan": (lambda: _insert(rpm_threshold=np.nan), r"rpm_threshold"),
        "insert vf_threshold -1": (lambda: _insert(vf_threshold=-1), r"vf_threshold"),
        "acceleration 0": (lambda: sc.apply_acceleration_limit([1, 2], [1, 1], 0.1, 2, 0), r"accel_rpm_s"),
        "acceleration lengths": (lambda: sc.apply_acceleration_limit([1, 2], [1, 1, 1], 0.1, 2, 100), r"n_target and seg_len"),
        "acceleration nan target": (lambda: sc.apply_acceleration_limit([1, np.nan], [1, 1], 0.1, 2, 100), r"n_target"),
        "acceleration teeth 2.5": (lambda: sc.apply_acceleration_limit([1, 2], [1, 1], 0.1, 2.5, 100), r"teeth"),
        "feed_directions nan": (lambda: sc.feed_directions([[0, 0, 0], [np.nan, 1, 0]]), r"xyz must be finite"),
        "feed_directions shape": (lambda: sc.feed_directions([[0, 0], [1, 1]]), r"xyz must be finite points of shape"),
        "working_diameters A_f shape": (lambda: sc.working_diameters([[0, 0, 1.0]] * 3, [0.0, 1.0], 10, 0.3), r"A_f must be"),
        "working_diameters normals nan": (lambda: sc.working_diameters([[0, 0, np.nan]], 0.0, 10, 0.3), r"normals must be finite"),
        "deviation radius nan": (lambda: sc.path_surface_deviation(_FLAT[0], _FLAT[1].cl_points(), np.nan), r"tool_radius"),
        "TriMesh shape": (lambda: TriMesh.from_triangles(np.zeros((2, 3))), r"triangles must have shape"),
        "TriMesh nan": (lambda: TriMesh.from_triangles(np.full((1, 3, 3), np.nan)), r"non-finite"),
        "orient rule": (lambda: __import__("cnclab.geometry.mesh", fromlist=["x"]).orient_facets(GRID.triangles, "x"), r"orient"),
        # issue 28 item 6: the vague ones
        "kim_yang R nan": (lambda: engagement.theta_kim_yang(1, np.nan, 3), r"^R \(corner radius\) must be in"),
        "kim_yang R str": (lambda: engagement.theta_kim_yang(1, "x", 3), r"^R \(corner radius\) must be a number"),
        "plan resolution 0": (lambda: _plan(resolution_mm=0), r"^resolution_mm must be a finite number > 0 mm \(or None: each planner.s default\), got 0$"),
        "plan resolution nan": (lambda: _plan(resolution_mm=np.nan), r"^resolution_mm must be a finite number > 0 mm"),
        "plan resolution inf": (lambda: _plan(resolution_mm=inf), r"^resolution_mm must be a finite number > 0 mm"),
        "plan resolution str": (lambda: _plan(resolution_mm="0.1"), r"^resolution_mm must be a finite number > 0 mm"),
        "evaluate empty program": (lambda: _evaluate_text("(comment only)\n"), r"^empty.ngc: the path has 0 point"),
    }
    return ok, bad


def _plan(**kw):
    from shapely.geometry import box
    from cnclab.toolpath.job import Job
    from cnclab.toolpath.path import Tool
    from cnclab.toolpath.planners import plan
    return plan(Job(box(0, 0, 30, 20), Tool(6.0), 60.0, 1.0, feed_mm_min=300, spindle_rpm=5000), **kw)


def _evaluate_text(text):
    from shapely.geometry import box
    from cnclab.nc.gcode import read_toolpath
    from cnclab.toolpath.evaluate import evaluate
    from cnclab.toolpath.job import Job
    from cnclab.toolpath.path import Tool
    path = read_toolpath(text)
    path.info["source"] = "empty.ngc"
    return evaluate(path, Job(box(0, 0, 30, 20), Tool(6.0), 60.0, 1.0, feed_mm_min=300, spindle_rpm=5000))


_FLAT = (tessellate_heightfield(lambda x, y: 0 * x, (0, 20), (0, 20), 4, 4),
         apt.cl_program([np.array([[x, 10.0, 0.0] for x in np.linspace(2, 18, 9)])], 500, 2000, 10, 30))


def _cusp():
    from cnclab.geometry import cusp
    return cusp


def _sched(**kw):
    args = dict(tool_diameter=10, a_p=0.3, v_c=63, f_z=0.125, teeth=2)
    args.update(kw)
    return sc.spindle_schedule(_FLAT[0], _FLAT[1].cl_points(), **args)


def _insert(**kw):
    cl = _FLAT[1].cl_points()
    return sc.insert_spindle_records(_FLAT[1], cl, _sched(), **kw)


API_OK, API_BAD = _api_cases()


@pytest.mark.parametrize("name", list(API_OK))
def test_api_limits_give_correct_values(name):
    f, want = API_OK[name]
    with np.errstate(all="raise"):
        got = float(np.asarray(f()))
    assert got == pytest.approx(want, rel=1e-12) if np.isfinite(want) else got == want
    OUTCOMES[("api", "correct")] += 1


@pytest.mark.parametrize("name", list(API_BAD))
def test_api_bad_input_names_the_parameter(name):
    f, pattern = API_BAD[name]
    with pytest.raises(ValueError, match=pattern):
        f()
    OUTCOMES[("api", "error")] += 1


@settings(max_examples=80, deadline=None)
@given(s=st.floats(0, 6), rho=st.one_of(st.floats(1e-3, 1e12), st.just(np.inf)), kind=st.sampled_from(["concave", "convex"]))
def test_fuzz_engagement_never_nan(s, rho, kind):
    """Any (s, rho): an engagement angle in [0, 180] or a ValueError naming the domain; never NaN."""
    try:
        t = float(engagement.theta_arc(s, rho, 3.0, kind))
    except ValueError as exc:
        assert re.search(r"rho|s \(stepover\)|stepover", str(exc))
        OUTCOMES[("api", "error")] += 1
    else:
        assert 0.0 <= t <= 180.0
        if np.isinf(rho):
            assert t == pytest.approx(float(engagement.theta_straight(s, 3.0)), abs=1e-9)
        OUTCOMES[("api", "correct")] += 1


# ============================================================================ CLI
def _part_and_path(tmp_path, dz=0.0, dx=0.0, scale=1.0, arc=False):
    """A flat-ish surface STL and a ball-end zig-zag touching it (tip output), both written to tmp_path."""
    def f(x, y):
        return 0.02 * x + 0.01 * y
    mesh = tessellate_heightfield(f, (0, 40), (0, 40), 8, 8)
    n = np.array([-0.02, -0.01, 1.0]) / np.linalg.norm([-0.02, -0.01, 1.0])
    R = 5.0
    passes = []
    for k, y in enumerate(np.arange(8.0, 33.0, 4.0)):
        x = np.linspace(8, 32, 13)[::(1 if k % 2 == 0 else -1)]
        surf = np.column_stack([x, np.full_like(x, y), f(x, y)])
        centre = surf + R * n
        passes.append(centre - [0, 0, R])
    prog = apt.cl_program(passes, 500, 2000, 2 * R, 30)
    text = prog.to_text()
    tri = mesh.triangles * scale
    stl = write_stl(tmp_path / "part.stl", TriMesh.from_triangles(tri))
    if dz or dx:
        text = apt.cl_program([p + [dx, 0, dz] for p in passes], 500, 2000, 2 * R, 30 + max(dz, 0.0)).to_text()
    p = tmp_path / "path.apt"
    p.write_text(text)
    return stl, p


BASE = ["--vc", "63", "--fz", "0.125", "--teeth", "2", "--ap", "0.3"]


def _run_cli(args, tmp_path, capsys, inputs):
    hashes = {p: _sha(p) for p in inputs}
    before = set(os.listdir(tmp_path))
    rc = cli(["spindle", *map(str, args)])
    out = capsys.readouterr()
    for p, h in hashes.items():
        assert _sha(p) == h, f"input {p} modified"
    after = set(os.listdir(tmp_path))
    assert not [f for f in after if f.endswith(".tmp") or ".tmp." in f], after
    return rc, out, after - before


CLI_BAD = {
    "--gcode equals -o": (lambda d: ["-o", d / "o.apt", "--gcode", d / "o.apt"], r"name the same file"),
    "--gcode equals input": (lambda d: ["-o", d / "o.apt", "--gcode", d / "path.apt"], r"refusing to overwrite the input file .*path.apt"),
    "-o equals STL": (lambda d: ["-o", d / "part.stl"], r"refusing to overwrite the input file .*part.stl"),
    "-o equals input via ./": (lambda d: ["-o", d / "." / "path.apt"], r"refusing to overwrite"),
    "--ae -1": (lambda d: ["-o", d / "o.apt", "--ae", "-1"], r"--ae must be finite and in \(0, inf\)"),
    "--ae nan": (lambda d: ["-o", d / "o.apt", "--ae", "nan"], r"--ae must be finite"),
    "--rpm-threshold nan": (lambda d: ["-o", d / "o.apt", "--rpm-threshold", "nan"], r"--rpm-threshold must be finite"),
    "--rpm-threshold -1": (lambda d: ["-o", d / "o.apt", "--rpm-threshold", "-1"], r"--rpm-threshold"),
    "--vf-threshold inf": (lambda d: ["-o", d / "o.apt", "--vf-threshold", "inf"], r"--vf-threshold"),
    "--nmax -5": (lambda d: ["-o", d / "o.apt", "--nmax", "-5"], r"--nmax"),
    "--vfmax 0": (lambda d: ["-o", d / "o.apt", "--vfmax", "0"], r"--vfmax"),
    "--accel nan": (lambda d: ["-o", d / "o.apt", "--accel", "nan"], r"--accel"),
    "--feed-direction inf": (lambda d: ["-o", d / "o.apt", "--feed-direction", "inf"], r"--feed-direction"),
    "--tool-diameter 0": (lambda d: ["-o", d / "o.apt", "--tool-diameter", "0"], r"--tool-diameter"),
    "--max-off-share 2": (lambda d: ["-o", d / "o.apt", "--max-off-share", "2"], r"--max-off-share"),
    "--mismatch-tol -1": (lambda d: ["-o", d / "o.apt", "--mismatch-tol", "-1"], r"--mismatch-tol"),
}
CLI_BASE_BAD = {  # replace one of BASE's values
    "--vc 0": ("--vc", "0"), "--vc inf": ("--vc", "inf"), "--fz nan": ("--fz", "nan"), "--fz -0.1": ("--fz", "-0.1"),
    "--teeth 2.7": ("--teeth", "2.7"), "--teeth 0": ("--teeth", "0"), "--ap 6 (> D/2)": ("--ap", "6"),
    "--ap 1e999": ("--ap", "1e999"), "--teeth x": ("--teeth", "x"), "--vc 1_0": ("--vc", "1_0"),
}


@pytest.mark.parametrize("name", list(CLI_BAD) + list(CLI_BASE_BAD))
def test_cli_refuses_bad_options(tmp_path, capsys, name):
    stl, path = _part_and_path(tmp_path)
    if name in CLI_BAD:
        extra, pattern = CLI_BAD[name]
        args = [stl, path, *BASE, *extra(tmp_path)]
    else:
        opt, val = CLI_BASE_BAD[name]
        base = list(BASE)
        base[base.index(opt) + 1] = val
        args = [stl, path, *base, "-o", tmp_path / "o.apt"]
        pattern = re.escape(opt) if opt != "--ap" or val != "6" else r"a_p must be in \(0, D/2\]"
    try:
        rc, out, new = _run_cli(args, tmp_path, capsys, [stl, path])
    except SystemExit as e:            # argparse: exit 2 with "argument --x: ..." on stderr
        rc = e.code
        out = capsys.readouterr()
        new = set(os.listdir(tmp_path)) - {"part.stl", "path.apt"}
    assert rc == 2
    assert re.search(pattern, out.err), out.err
    assert any(ln.startswith(("error:", "python -m cnclab spindle: error:")) for ln in out.err.splitlines()), out.err
    assert not new, new
    OUTCOMES[("cli", "error")] += 1


@pytest.mark.parametrize("case, kw", [("1000 mm away", dict(dx=1000.0)), ("50 mm above", dict(dz=50.0)),
                                      ("part scaled x0.1", dict(scale=0.1)), ("1.5 mm into the part", dict(dz=-1.5))])
def test_cli_part_path_mismatch(tmp_path, capsys, case, kw):
    stl, path = _part_and_path(tmp_path, **kw)
    out_p = tmp_path / "o.apt"
    rc, out, new = _run_cli([stl, path, *BASE, "-o", out_p], tmp_path, capsys, [stl, path])
    assert rc == 2 and "does not match" in out.err and "path.apt" in out.err and not new
    rc, out, new = _run_cli([stl, path, *BASE, "-o", out_p, "--allow-mismatch"], tmp_path, capsys, [stl, path])
    assert rc == 0 and new == {"o.apt"} and "part/path check: 100.0 %" in out.out
    OUTCOMES[("cli", "error")] += 1
    OUTCOMES[("cli", "correct")] += 1


def test_cli_matching_path_passes_and_reports_share(tmp_path, capsys):
    stl, path = _part_and_path(tmp_path)
    rc, out, new = _run_cli([stl, path, *BASE, "-o", tmp_path / "o.apt", "--gcode", tmp_path / "o.ngc"],
                            tmp_path, capsys, [stl, path])
    assert rc == 0 and new == {"o.apt", "o.ngc"}, out.err
    assert "part/path check: 0.0 %" in out.out
    back = apt.read_apt(tmp_path / "o.apt").cl_points()
    np.testing.assert_allclose(back.xyz, apt.read_apt(path).cl_points().xyz)
    OUTCOMES[("cli", "correct")] += 1


def test_cli_failing_gcode_target_writes_nothing(tmp_path, capsys):
    stl, path = _part_and_path(tmp_path)
    (tmp_path / "adir").mkdir()
    for target in (tmp_path / "adir", tmp_path / "part.stl" / "x.ngc"):
        rc, out, new = _run_cli([stl, path, *BASE, "-o", tmp_path / "o.apt", "--gcode", target], tmp_path, capsys,
                                [stl, path])
        assert rc == 2 and not new and not (tmp_path / "o.apt").exists(), (out.err, new)
        assert str(target.name) in out.err or "adir" in out.err or "part.stl" in out.err
        assert not list((tmp_path / "adir").iterdir())
        OUTCOMES[("cli", "error")] += 1


def test_cli_bad_inputs_name_file_and_line(tmp_path, capsys):
    stl, path = _part_and_path(tmp_path)
    bad = tmp_path / "nounits.apt"
    bad.write_text(path.read_text().replace("UNITS / MM\n", ""))
    rc, out, new = _run_cli([stl, bad, *BASE, "-o", tmp_path / "o.apt"], tmp_path, capsys, [stl, bad])
    assert rc == 2 and re.search(r"nounits.apt:\d+: .*UNITS", out.err) and not new
    badstl = tmp_path / "short.stl"
    badstl.write_bytes(stl.read_bytes()[:-10])
    rc, out, new = _run_cli([badstl, path, *BASE, "-o", tmp_path / "o.apt"], tmp_path, capsys, [badstl, path])
    assert rc == 2 and "short.stl: truncated binary STL" in out.err and not new
    rc, out, new = _run_cli([tmp_path / "missing.stl", path, *BASE, "-o", tmp_path / "o.apt"], tmp_path, capsys, [path])
    assert rc == 2 and "missing.stl" in out.err and not new
    OUTCOMES[("cli", "error")] += 3


def test_cli_clockwise_stl_same_output_with_warning(tmp_path, capsys):
    stl, path = _part_and_path(tmp_path)
    m = read_stl(stl)
    cw = tmp_path / "cw.stl"
    cw.write_bytes(_binary(m.triangles[:, ::-1]))
    rc1, out1, _ = _run_cli([stl, path, *BASE, "-o", tmp_path / "a.apt"], tmp_path, capsys, [stl, path])
    rc2, out2, _ = _run_cli([cw, path, *BASE, "-o", tmp_path / "b.apt"], tmp_path, capsys, [cw, path])
    assert rc1 == rc2 == 0
    assert (tmp_path / "a.apt").read_text() == (tmp_path / "b.apt").read_text()
    assert "re-oriented" in out2.err and "warning:" in out2.err
    OUTCOMES[("cli", "correct")] += 1


@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_outputs_respect_umask(tmp_path, capsys, umask):
    stl, path = _part_and_path(tmp_path)
    old = os.umask(umask)
    try:
        rc, _, _ = _run_cli([stl, path, *BASE, "-o", tmp_path / "o.apt", "--gcode", tmp_path / "o.ngc"], tmp_path,
                            capsys, [stl, path])
    finally:
        os.umask(old)
    assert rc == 0
    for f in ("o.apt", "o.ngc"):
        assert (tmp_path / f).stat().st_mode & 0o777 == 0o666 & ~umask
    OUTCOMES[("cli", "correct")] += 1


@pytest.mark.parametrize("sig", ["SIGTERM", "SIGINT"])
def test_signal_during_atomic_write_leaves_no_tmp(tmp_path, sig):
    from cnclab.fileio import atomic_output, cleanup_on_signals
    exc = SystemExit if sig == "SIGTERM" else KeyboardInterrupt
    with pytest.raises(exc):
        with cleanup_on_signals():
            with atomic_output(tmp_path / "x.txt") as fh:
                fh.write("partial")
                assert len(os.listdir(tmp_path)) == 1          # the temporary file exists now
                os.kill(os.getpid(), getattr(signal, sig))
                for _ in range(1000):                           # the handler runs between bytecodes
                    pass
    assert os.listdir(tmp_path) == []
    OUTCOMES[("cli", "error")] += 1


def test_sigterm_to_cli_process_leaves_complete_outputs_or_none(tmp_path):
    """A real process killed with SIGTERM at a random moment: no .tmp file, and outputs all-or-none."""
    stl, path = _part_and_path(tmp_path)
    big = tmp_path / "big.apt"
    txt = path.read_text()
    body = "".join(ln + "\n" for ln in txt.splitlines() if ln.startswith("GOTO") and "30.000" not in ln)
    big.write_text(txt.replace("FINI\n", body * 60 + "FINI\n"))
    code = ("import sys; from cnclab.__main__ import main; sys.exit(main(sys.argv[1:]))")
    for delay in (0.3, 0.8, 1.6):
        out_p, ngc = tmp_path / f"o{delay}.apt", tmp_path / f"o{delay}.ngc"
        proc = subprocess.Popen([sys.executable, "-X", "faulthandler", "-c", code, "spindle", str(stl), str(big), *BASE, "-o", str(out_p),
                                 "--gcode", str(ngc), "--allow-mismatch"], stderr=subprocess.PIPE, stdout=subprocess.PIPE)
        try:
            proc.wait(timeout=delay)
        except subprocess.TimeoutExpired:
            proc.send_signal(signal.SIGTERM)
        communicate_or_dump(proc, 60)
        assert not [f for f in os.listdir(tmp_path) if f.endswith(".tmp") or ".tmp." in f]
        assert out_p.exists() == ngc.exists()
        if out_p.exists():
            apt.read_apt(out_p).cl_points()
        OUTCOMES[("cli", "correct" if out_p.exists() else "error")] += 1


def _spindle_process(tmp_path, tag, sig=None, delay=None):
    """``python -m cnclab spindle`` on the sample part and path (APT + G-code outputs), interrupted by
    ``sig`` after ``delay`` s (the shared runner, tests/_fuzz_support.py); (rc, stderr, outputs)."""
    outs = [tmp_path / f"{tag}.apt", tmp_path / f"{tag}.ngc"]
    rc, out, err, _ = run_cli(["spindle", SAMPLE / "sample_ch8_part.stl", SAMPLE / "sample_ch8_zigzag_Af0.apt", *BASE,
                               "-o", outs[0], "--gcode", outs[1]], sig, delay, timeout=300)
    return rc, out, err, outs


@pytest.mark.slow      # 8 whole runs of `spindle` (12 s); test_fuzz_interrupts.py interrupts spindle at fixed offsets in make test
def test_interrupt_at_any_moment_says_what_is_on_disk(tmp_path):
    """SIGINT and SIGTERM at offsets spread over a whole run of ``spindle`` on the sample files (the
    offsets are fractions of a measured uninterrupted run, so the reading, computing and writing
    phases are all hit whatever the machine's speed): never a crash (a SIGSEGV was seen 5 times in 20
    at ~1.2 s, while scipy was being imported), the message always matches the disk."""
    import time

    t0 = time.perf_counter()
    rc, out, err, outs = _spindle_process(tmp_path, "full")
    full = time.perf_counter() - t0
    assert rc == 0, err
    assert "wrote" in out
    start = startup_s()
    kinds = collections.Counter()
    for k, frac in enumerate(np.linspace(0.1, 1.05, 8)):
        sig = signal.SIGINT if k % 2 == 0 else signal.SIGTERM
        rc, _, err, outs = _spindle_process(tmp_path, f"i{k}", sig, frac * full)
        kind = classify_interrupt(rc, err, outs, sig, frac * full, start, tmp_path, check_complete("spindle"))
        kinds[kind] += 1
        OUTCOMES[("signal", "correct" if kind == "complete" else "error")] += 1
    print("interrupt outcomes:", dict(kinds))


@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
@pytest.mark.parametrize("when", ["after the outputs were committed", "between the two renames"])
def test_interrupt_after_commit_says_the_outputs_are_complete(tmp_path, capsys, monkeypatch, sig, when):
    """In process, deterministic: the signal arrives right after ``atomic_write_many`` returned, or
    between its two renames (deferred to after the second): both outputs are complete, the message says
    so and the exit code is 0."""
    from cnclab import fileio
    stl, path = _part_and_path(tmp_path)
    signum = getattr(signal, sig)
    if when == "between the two renames":
        real, calls = os.replace, []

        def replace(src, dst):
            real(src, dst)
            calls.append(dst)
            if len(calls) == 1:
                os.kill(os.getpid(), signum)
        monkeypatch.setattr(fileio.os, "replace", replace)
    else:
        real_many = sc.atomic_write_many

        def many(*a, **k):
            res = real_many(*a, **k)
            os.kill(os.getpid(), signum)
            return res
        monkeypatch.setattr(sc, "atomic_write_many", many)
    rc, out, new = _run_cli([stl, path, *BASE, "-o", tmp_path / "o.apt", "--gcode", tmp_path / "o.ngc"],
                            tmp_path, capsys, [stl, path])
    assert rc == 0 and new == {"o.apt", "o.ngc"}
    assert f"{sig} after the outputs were written: complete" in out.err, out.err
    apt.read_apt(tmp_path / "o.apt").cl_points()
    OUTCOMES[("signal", "correct")] += 1


@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_interrupt_before_commit_writes_nothing(tmp_path, capsys, monkeypatch, sig):
    """The signal arrives while the G-code text is being made (after the schedule, before any write):
    nothing written, exit 128 + signal, an old output file is left as it was."""
    stl, path = _part_and_path(tmp_path)
    old = tmp_path / "o.apt"
    old.write_text("previous run\n")
    signum = getattr(signal, sig)
    real = sc.gcode_text

    def gtext(*a, **k):
        os.kill(os.getpid(), signum)
        return real(*a, **k)
    monkeypatch.setattr(sc, "gcode_text", gtext)
    rc, out, new = _run_cli([stl, path, *BASE, "-o", old, "--gcode", tmp_path / "o.ngc"], tmp_path, capsys,
                            [stl, path])
    assert rc == 128 + signum and not new and old.read_text() == "previous run\n"
    assert f"interrupted ({sig}): nothing written" in out.err
    OUTCOMES[("signal", "error")] += 1


def test_error_is_printed_on_its_own_line(tmp_path, capsys):
    stl, path = _part_and_path(tmp_path, dz=50.0)
    rc, out, _ = _run_cli([stl, path, *BASE, "-o", tmp_path / "o.apt"], tmp_path, capsys, [stl, path])
    assert rc == 2
    err_lines = [ln for ln in out.err.replace("\r", "\n").splitlines() if "error:" in ln]
    assert err_lines and all(ln.startswith("error:") for ln in err_lines), out.err
    OUTCOMES[("cli", "error")] += 1


def test_path_surface_deviation_is_exact_on_a_closed_part():
    """The part/path check's distance equals brute force over all facets (walls and bottom included)."""
    from cnclab.geometry.freeform_part import FreeformPart, freeform_part_mesh
    from cnclab.geometry.mesh import closest_point_on_triangles
    m = freeform_part_mesh(FreeformPart(), 5.0, closed=True)
    rng = np.random.default_rng(4)
    P = rng.uniform([-20, -20, -10], [120, 120, 40], (60, 3))
    cl = apt.CLPoints(P, np.zeros(60, bool), np.full(60, 500.0), np.full(60, np.nan), np.arange(60),
                      np.arange(60), P[0])
    g = sc.path_surface_deviation(m, cl, 5.0)
    T = m.triangles
    C = P + [0, 0, 5.0]
    ref = np.array([np.linalg.norm(closest_point_on_triangles(c[None], T[:, 0], T[:, 1], T[:, 2]) - c, axis=1).min()
                    for c in C]) - 5.0
    np.testing.assert_allclose(g, ref, rtol=0, atol=1e-12)
    OUTCOMES[("api", "correct")] += 1


def test_atomic_write_many_rolls_back_on_a_failing_rename(tmp_path, monkeypatch):
    """All or none, also when the second rename fails after the first succeeded: old content restored."""
    from cnclab import fileio
    a, b = tmp_path / "a.txt", tmp_path / "b.txt"
    a.write_text("old a")
    real = os.replace
    calls = []

    def flaky(src, dst):
        calls.append(dst)
        if str(dst) == str(b):
            raise OSError(f"{dst}: simulated rename failure")
        return real(src, dst)

    monkeypatch.setattr(fileio.os, "replace", flaky)
    with pytest.raises(OSError, match="b.txt"):
        fileio.atomic_write_many([(a, "new a"), (b, "new b")])
    monkeypatch.setattr(fileio.os, "replace", real)
    assert a.read_text() == "old a" and not b.exists()
    assert sorted(os.listdir(tmp_path)) == ["a.txt"] and fileio.live_temporary_files() == []
    OUTCOMES[("cli", "error")] += 1


# --- finish-path: hostile STLs and hostile options (issue 28 item 7) ------------------------------
FP_BASE = ["--tool-diameter", "10", "--stepover", "5", "--step", "2", "--quiet"]


def _finish_path_run(tmp_path, capsys, stl, opts):
    out = tmp_path / "fp.apt"
    h = _sha(stl)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", STLWarning)
        rc = cli(["finish-path", str(stl), "-o", str(out), *opts])
    cap = capsys.readouterr()
    assert _sha(stl) == h, "input STL modified"
    assert not [f for f in os.listdir(tmp_path) if ".tmp" in f]
    return rc, cap, out


def _verify_finish_path(stl, out, D):
    """The APT reads back, every CL point is finite, and the ball never enters the part: its centre
    is at least D/2 from every facet at every feed point (exact distance; 1e-3 mm: GOTO records are
    written with 3 decimals, each coordinate rounded by up to 0.0005 mm)."""
    prog = apt.read_apt(out)
    cl = prog.cl_points()
    assert np.isfinite(cl.xyz).all() and len(cl.xyz) > 2
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", STLWarning)
        mesh = read_stl(stl)
    gap = sc.path_surface_deviation(mesh, cl, D / 2, output="tip", max_points=400)
    assert gap.min() >= -1e-3, gap.min()


@pytest.mark.parametrize("name", list(STL_CASES))
def test_finish_path_on_hostile_stl(tmp_path, capsys, name):
    data, expect, pattern = STL_CASES[name]
    raw = data.encode("utf-8") if isinstance(data, str) else data
    stl = tmp_path / "part.stl"
    stl.write_bytes(raw)
    rc, cap, out = _finish_path_run(tmp_path, capsys, stl, FP_BASE)
    if expect == "error":
        assert rc == 2 and cap.err.startswith("error: ") and str(stl) in cap.err, cap.err
        assert re.search(pattern, cap.err), cap.err
        assert not out.exists()
        OUTCOMES[("finish-path", "error")] += 1
    else:
        assert rc == 0, cap.err
        _verify_finish_path(stl, out, 10.0)
        OUTCOMES[("finish-path", "correct")] += 1


def _hostile_options(seed=28, n=24):
    """(option, value) pairs from a seeded generator over every numeric option of finish-path."""
    rnd = np.random.default_rng(seed)
    opts = ["--tool-diameter", "--stepover", "--step", "--feed-angle", "--feed", "--rpm", "--clearance"]
    values = ["0", "-1", "nan", "inf", "-inf", "1e-9", "1e300", "1_0", "", "0x10", "\uff11", "1e-4", "370", "12.5", "3"]
    return [(opts[int(rnd.integers(len(opts)))], values[int(rnd.integers(len(values)))]) for _ in range(n)]


@pytest.mark.parametrize("opt, value", _hostile_options())
def test_finish_path_hostile_options(tmp_path, capsys, opt, value):
    """Each case: exit 2 naming the option (or, for a huge path, --stepover/--step), nothing written;
    or a verified path."""
    stl = tmp_path / "part.stl"
    stl.write_bytes(_binary(GRID.triangles))
    opts = list(FP_BASE)
    if opt in opts:
        opts[opts.index(opt) + 1] = value
    else:
        opts += [opt, value]
    try:
        rc, cap, out = _finish_path_run(tmp_path, capsys, stl, opts)
    except SystemExit as exc:            # argparse: exit 2 and the message on stderr
        rc, cap, out = exc.code, capsys.readouterr(), tmp_path / "fp.apt"
    if rc == 2:
        assert opt in cap.err or "--stepover" in cap.err or "--step" in cap.err, cap.err
        assert not out.exists()
        OUTCOMES[("finish-path", "error")] += 1
    else:
        assert rc == 0, cap.err
        D = float(opts[opts.index("--tool-diameter") + 1])
        _verify_finish_path(stl, out, D)
        OUTCOMES[("finish-path", "correct")] += 1
