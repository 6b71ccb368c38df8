"""The claims ledger: every number the four works print, next to the value cnclab computes.

``data/claims.csv`` holds one row per printed number. Paper values are transcribed (with seed file
and table/equation/section); reproduced values are *never* stored: they are computed by calling the
function named in ``computed_by``.

Columns
-------
claim_id        unique id, ``<work>.<chapter-or-section>.<what>`` (e.g. ``mgherony2024.ch3.eq3-5.slope``)
work            one of ``cnclab.paths.WORK_IDS``
seed_file       the seed text the number is printed in
location        table / equation / section / figure where it is printed
quantity        what the number is, in words
unit            unit of ``paper_value`` (``-`` for dimensionless, ``%`` for percent)
paper_value     the number as printed (float)
rtol, atol      tolerance: holds when ``|reproduced - paper| <= atol + rtol*|paper|``
tolerance_basis why that tolerance (e.g. "printed to 2 decimals")
status          MATCH | DIFFERS | DISCREPANT | CONSISTENT | INPUT | NOT_DERIVABLE (see below)
computed_by     dotted name of a zero-argument function returning the value; ``name[key]`` indexes
                the function's result (a mapping, Series or sequence) with ``key``
alt_computed_by DIFFERS only: function reproducing the *printed* number under the explanation
                (the typo, the slipped unit or convention); it must match ``paper_value``
missing_input   NOT_DERIVABLE only: which input the seed does not give, quoting (in “…” or "…") the
                seed sentence that shows it is measured or not given (enforced for ``QUOTED_WORKS``)
slow            1 if computing the claim takes long (skipped by the tests in fast mode)
notebook        the notebook (relative to ``notebooks/``) that shows the claim
note            free text: for DIFFERS the explanation, otherwise context
reconstructed_by NOT_DERIVABLE only (optional): dotted function giving what the reconstruction yields
                (partial evidence), reported as ``reconstructed_value`` beside the paper value

Status semantics (what "holds" means)
-------------------------------------
MATCH           a result the seed prints, computed from the seed's inputs by an independent route, lies
                within tolerance of the paper value (for an :class:`Interval`, the paper value lies
                inside the interval widened by the tolerance)
DIFFERS         the reproduced (consistent) value is *outside* tolerance, and the alternative that
                explains the printed number is *inside* it
DISCREPANT      outside tolerance and no explanation found; the note says what was tried. Holds only
                while the discrepancy persists (value still outside tolerance)
CONSISTENT      a printed number that restates other printed numbers (arithmetic check); holds when
                within tolerance; counted apart from reproduced results
INPUT           a printed value the reproduction takes as input or builds in (design target, program
                condition); never counted as reproduced; with computed_by it must be within tolerance
NOT_DERIVABLE   no function; ``missing_input`` names what the seed does not give and quotes the seed
                sentence; a ``reconstructed_by`` value (partial evidence) is computed and reported
                beside the paper value but decides nothing

Only MATCH and DIFFERS rows are reproduced results (``REPRODUCED``); :func:`headline` counts the
other statuses apart. A number the seed does not print (an inverse residual of 0, a simulated
θ = 60° for an input θ = 60°) is no row at all: such checks are unit tests.
"""
from __future__ import annotations

import csv
import dataclasses
import importlib
import io
import json
import math
import re
import time
from pathlib import Path
from typing import Any, Iterable

from . import clihelp
from .fileio import atomic_write
from .paths import CLAIMS_CSV, WORK_IDS, build_dir
from .runtime import fast_mode

COLUMNS = ("claim_id", "work", "seed_file", "location", "quantity", "unit", "paper_value", "rtol",
           "atol", "tolerance_basis", "status", "computed_by", "alt_computed_by", "missing_input",
           "slow", "notebook", "note", "reconstructed_by")
STATUSES = ("MATCH", "DIFFERS", "DISCREPANT", "CONSISTENT", "INPUT", "NOT_DERIVABLE")
#: statuses whose rows are reproduced results (the headline); the others are counted apart
REPRODUCED = ("MATCH", "DIFFERS")
SEED_FILES = {
    "jacso2021": "000_690a1ed8f09fd780.txt",
    "kim_yang2006": "002_d412f01ccb8e936f.txt",
    "hoang2024": "003_216a87306e3bb9cf.txt",
    "mgherony2024": "004_6087ee43271ee0e7.txt",
}
#: works whose NOT_DERIVABLE rows must quote the seed in ``missing_input`` (all works once every
#: work's rows carry their quotes)
QUOTED_WORKS = frozenset(WORK_IDS)
_QUOTE = re.compile(r'[“"]([^“”"]{12,})[”"]')
_DOTTED = re.compile(r"^[A-Za-z_][\w]*(\.[A-Za-z_]\w*)+(\[[^\[\]]+\])?$")


def quotes(text: str) -> list[str]:
    """The quoted seed excerpts (“…” or "…", at least 12 characters) in a ``missing_input`` text.

    >>> quotes('the time was measured: “The machining time was 134 s”')
    ['The machining time was 134 s']
    """
    return [m.group(1).strip() for m in _QUOTE.finditer(text)]


_NUM_PLAIN = re.compile(r"\d+(?:[.,]\d+)*")
_NUM_GROUPED = re.compile(r"\d{1,3}(?:[ \u00a0\u2009\u202f]\d{3})+(?:[.,]\d+)?")


def printed_numbers(text: str) -> set[float]:
    """Every number a text prints, in each reading of its separators (unsigned).

    ``2098``, ``2 098`` and ``2,098`` read as 2098; a single comma also as a decimal comma
    (``1147,5`` → 1147.5, ``5270,744`` → 5270.744 and 5270744).

    >>> sorted(printed_numbers("V = 2 098 mm, MRR = 1147,5"))
    [2.0, 98.0, 1147.5, 2098.0, 11475.0]
    """
    out: set[float] = set()
    tokens = [m.group(0) for m in _NUM_PLAIN.finditer(text)]
    tokens += [m.group(0) for m in _NUM_GROUPED.finditer(text)]
    for tok in tokens:
        t = re.sub(r"[ \u00a0\u2009\u202f]", "", tok)
        readings = {t.replace(",", "")}
        if t.count(",") == 1 and "." not in t:
            readings.add(t.replace(",", "."))
        for r in readings:
            if r.count(".") <= 1:
                out.add(float(r))
    return out


def is_printed(value: float, text: str) -> bool:
    """True when ``|value|`` is among :func:`printed_numbers` of ``text`` (to 1e-9 relative).

    >>> is_printed(5270.744, "| 5275,540 | 5325,535 | 5270,744 |"), is_printed(0.5, "θ = 60°")
    (True, False)
    """
    v = abs(float(value))
    return any(abs(n - v) <= 1e-9 * max(1.0, v) for n in printed_numbers(text))


def normalize_text(text: str) -> str:
    """Collapse whitespace and drop markdown emphasis (``*``) for comparing quotes with a seed."""
    return re.sub(r"\s+", " ", text.replace("*", "")).strip()


class LedgerError(ValueError):
    """A malformed ledger row; the message names file, line and column."""


@dataclasses.dataclass(frozen=True)
class Interval:
    """A reproduced quantity known as a range (e.g. min..max over training seeds).

    A claim with an Interval value MATCHes when the paper value lies in ``[lo - tol, hi + tol]``.
    """

    lo: float
    hi: float
    center: float | None = None

    def __post_init__(self):
        if not (self.lo <= self.hi):
            raise ValueError(f"Interval needs lo <= hi, got {self.lo}, {self.hi}")

    def __float__(self) -> float:
        return float(self.center if self.center is not None else 0.5 * (self.lo + self.hi))

    def to_json(self):
        return {"lo": float(self.lo), "hi": float(self.hi),
                "center": None if self.center is None else float(self.center)}


@dataclasses.dataclass(frozen=True)
class Claim:
    claim_id: str
    work: str
    seed_file: str
    location: str
    quantity: str
    unit: str
    paper_value: float
    rtol: float
    atol: float
    tolerance_basis: str
    status: str
    computed_by: str
    alt_computed_by: str
    missing_input: str
    slow: bool
    notebook: str
    note: str
    reconstructed_by: str = ""
    line: int = 0  # line in the CSV file (1-based, header is line 1)

    def holds_within(self, value) -> bool:
        """True when ``value`` is within this claim's tolerance of the paper value."""
        return within(value, self.paper_value, self.rtol, self.atol)


def within(value, paper: float, rtol: float, atol: float) -> bool:
    tol = atol + rtol * abs(paper)
    if isinstance(value, Interval):
        return bool(value.lo - tol <= paper <= value.hi + tol)
    v = float(value)
    return bool(math.isfinite(v) and abs(v - paper) <= tol)


def _float(text: str, where: str, name: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise LedgerError(f"{where}: column {name!r} must be a number, got {text!r}") from None
    if not math.isfinite(v):
        raise LedgerError(f"{where}: column {name!r} must be finite, got {text!r}")
    return v


def load(path: Path | str = CLAIMS_CSV) -> list[Claim]:
    """Read and validate the ledger; raises :class:`LedgerError` naming file, line and column."""
    path = Path(path)
    with open(path, newline="", encoding="utf-8") as fh:
        reader = csv.DictReader(fh)
        missing = [c for c in COLUMNS if c not in (reader.fieldnames or [])]
        if missing:
            raise LedgerError(f"{path}: header lacks columns {missing}")
        rows, seen = [], {}
        for i, raw in enumerate(reader, start=2):
            where = f"{path}:{i}"
            r = {k: (raw.get(k) or "").strip() for k in COLUMNS}
            cid = r["claim_id"]
            if not cid:
                raise LedgerError(f"{where}: empty claim_id")
            if cid in seen:
                raise LedgerError(f"{where}: duplicate claim_id {cid!r} (first on line {seen[cid]})")
            seen[cid] = i
            if r["work"] not in WORK_IDS:
                raise LedgerError(f"{where}: column 'work' must be one of {WORK_IDS}, got {r['work']!r}")
            if r["seed_file"] != SEED_FILES[r["work"]]:
                raise LedgerError(f"{where}: seed_file {r['seed_file']!r} is not the seed of {r['work']}"
                                  f" ({SEED_FILES[r['work']]})")
            if r["status"] not in STATUSES:
                raise LedgerError(f"{where}: column 'status' must be one of {STATUSES}, got {r['status']!r}")
            for col in ("location", "quantity", "unit", "tolerance_basis"):
                if not r[col] and not (col == "tolerance_basis" and (
                        r["status"] == "NOT_DERIVABLE" or (r["status"] == "INPUT" and not r["computed_by"]))):
                    raise LedgerError(f"{where}: column {col!r} is empty")
            for col in ("computed_by", "alt_computed_by"):
                if r[col] and not _DOTTED.match(r[col]):
                    raise LedgerError(f"{where}: column {col!r} is not a dotted name: {r[col]!r}")
            st = r["status"]
            if st in ("MATCH", "DIFFERS", "DISCREPANT", "CONSISTENT") and not r["computed_by"]:
                raise LedgerError(f"{where}: {st} row needs computed_by")
            if st == "DIFFERS" and not (r["alt_computed_by"] and r["note"]):
                raise LedgerError(f"{where}: DIFFERS row needs alt_computed_by (the explanation) and a note")
            if st == "NOT_DERIVABLE" and (r["computed_by"] or not r["missing_input"]):
                raise LedgerError(f"{where}: NOT_DERIVABLE row needs missing_input and no computed_by")
            if st == "NOT_DERIVABLE" and r["work"] in QUOTED_WORKS and not quotes(r["missing_input"]):
                raise LedgerError(f"{where}: NOT_DERIVABLE row must quote in missing_input (in “…”) the "
                                  f"seed sentence showing the input is measured or not given")
            if st != "DIFFERS" and r["alt_computed_by"]:
                raise LedgerError(f"{where}: alt_computed_by only belongs to DIFFERS rows")
            if st == "DISCREPANT" and not r["note"]:
                raise LedgerError(f"{where}: DISCREPANT row needs a note saying what was tried")
            if r["reconstructed_by"] and st != "NOT_DERIVABLE":
                raise LedgerError(f"{where}: reconstructed_by only belongs to NOT_DERIVABLE rows")
            if r["reconstructed_by"] and not _DOTTED.match(r["reconstructed_by"]):
                raise LedgerError(f"{where}: column 'reconstructed_by' is not a dotted name")
            rows.append(Claim(
                claim_id=cid, work=r["work"], seed_file=r["seed_file"], location=r["location"],
                quantity=r["quantity"], unit=r["unit"],
                paper_value=_float(r["paper_value"], where, "paper_value"),
                rtol=_float(r["rtol"] or "0", where, "rtol"), atol=_float(r["atol"] or "0", where, "atol"),
                tolerance_basis=r["tolerance_basis"], status=st, computed_by=r["computed_by"],
                alt_computed_by=r["alt_computed_by"], missing_input=r["missing_input"],
                slow=r["slow"] in ("1", "true", "True", "yes"), notebook=r["notebook"], note=r["note"],
                reconstructed_by=r["reconstructed_by"], line=i))
            if rows[-1].rtol < 0 or rows[-1].atol < 0:
                raise LedgerError(f"{where}: tolerances must be >= 0")
    return rows


def resolve(dotted: str):
    """Return a zero-argument callable for ``pkg.mod.func`` or ``pkg.mod.func[key]``."""
    key = None
    m = re.match(r"^(.*)\[([^\[\]]+)\]$", dotted)
    if m:
        dotted, key = m.group(1), m.group(2)
    modname, _, attr = dotted.rpartition(".")
    try:
        mod = importlib.import_module(modname)
    except ImportError as exc:
        raise LedgerError(f"cannot import module {modname!r} of {dotted!r}: {exc}") from exc
    try:
        fn = getattr(mod, attr)
    except AttributeError:
        raise LedgerError(f"module {modname!r} has no function {attr!r}") from None
    if not callable(fn):
        raise LedgerError(f"{dotted!r} is not callable")
    if key is None:
        return fn

    def indexed():
        res = fn()
        try:
            return res[key]
        except (KeyError, IndexError, TypeError):
            try:
                return res[int(key)]
            except (ValueError, KeyError, IndexError, TypeError):
                raise LedgerError(f"{dotted}: result has no key {key!r}") from None

    return indexed


def _scalar(value):
    if isinstance(value, Interval):
        return value
    try:
        return float(value)
    except (TypeError, ValueError):
        raise LedgerError(f"claim function returned {type(value).__name__}, not a number") from None


@dataclasses.dataclass
class Result:
    claim: Claim
    reproduced: Any = None      # float, Interval or None
    alt: Any = None             # DIFFERS: value under the explanation
    reconstructed: Any = None   # NOT_DERIVABLE: what the reconstruction gives (reconstructed_by)
    ok: bool = False
    skipped: bool = False
    error: str = ""
    seconds: float = 0.0

    @property
    def abs_error(self):
        if self.reproduced is None:
            return None
        return abs(float(self.reproduced) - self.claim.paper_value)

    @property
    def rel_error(self):
        e = self.abs_error
        if e is None or self.claim.paper_value == 0:
            return None
        return e / abs(self.claim.paper_value)

    def to_json(self) -> dict:
        c = self.claim
        enc = lambda v: v.to_json() if isinstance(v, Interval) else v  # noqa: E731
        return {"claim_id": c.claim_id, "work": c.work, "seed_file": c.seed_file,
                "location": c.location, "quantity": c.quantity, "unit": c.unit,
                "paper_value": c.paper_value, "reproduced_value": enc(self.reproduced),
                "alt_value": enc(self.alt), "reconstructed_value": enc(self.reconstructed),
                "abs_error": self.abs_error, "rel_error": self.rel_error,
                "rtol": c.rtol, "atol": c.atol, "status": c.status, "ok": self.ok,
                "skipped": self.skipped, "error": self.error, "computed_by": c.computed_by,
                "note": c.note}


def _json_default(o):
    """numpy scalars (np.bool_, np.float64 ...) in results become plain Python values."""
    if hasattr(o, "item"):
        return o.item()
    raise TypeError(f"Object of type {type(o).__name__} is not JSON serializable")


def evaluate(claim: Claim, skip_slow: bool = False) -> Result:
    """Compute one claim and decide whether its status holds."""
    res = Result(claim)
    if claim.status == "NOT_DERIVABLE":
        res.ok = bool(claim.missing_input) and not claim.computed_by
        if claim.reconstructed_by and not (skip_slow and claim.slow):
            try:
                res.reconstructed = _scalar(resolve(claim.reconstructed_by)())
            except Exception as exc:  # reported, never hidden
                res.error = f"{type(exc).__name__}: {exc}"
                res.ok = False
        return res
    if claim.status == "INPUT" and not claim.computed_by:
        res.ok = True
        return res
    if skip_slow and claim.slow:
        res.skipped = True
        return res
    t0 = time.perf_counter()
    try:
        res.reproduced = _scalar(resolve(claim.computed_by)())
        inside = claim.holds_within(res.reproduced)
        if claim.status in ("MATCH", "CONSISTENT", "INPUT"):
            res.ok = bool(inside)
        elif claim.status == "DISCREPANT":
            res.ok = not inside
        else:  # DIFFERS
            res.alt = _scalar(resolve(claim.alt_computed_by)())
            res.ok = bool((not inside) and claim.holds_within(res.alt))
    except Exception as exc:  # reported, never hidden
        res.error = f"{type(exc).__name__}: {exc}"
        res.ok = False
    res.seconds = time.perf_counter() - t0
    return res


def select(claims: Iterable[Claim], work: str | None = None, notebook: str | None = None,
           prefix: str | None = None) -> list[Claim]:
    out = list(claims)
    if work:
        if work not in WORK_IDS:
            raise ValueError(f"--work must be one of {WORK_IDS}, got {work!r}")
        out = [c for c in out if c.work == work]
    if notebook:
        out = [c for c in out if c.notebook == notebook]
    if prefix:
        out = [c for c in out if c.claim_id.startswith(prefix)]
    return out


def evaluate_all(claims: Iterable[Claim], skip_slow: bool = False, progress: bool = False) -> list[Result]:
    claims = list(claims)
    it = claims
    if progress:
        from tqdm.auto import tqdm

        it = tqdm(claims, desc="claims", unit="claim", disable=None)   # a bar only on a terminal
    return [evaluate(c, skip_slow=skip_slow) for c in it]


def _fmt(v) -> str:
    if v is None:
        return ""
    if isinstance(v, Interval):
        return f"[{v.lo:.6g}, {v.hi:.6g}]"
    return f"{float(v):.6g}"


def results_frame(results: list[Result]):
    """A pandas DataFrame of results: paper vs reproduced vs tolerance vs status."""
    import pandas as pd

    rows = []
    for r in results:
        c = r.claim
        rows.append({
            "claim": c.claim_id, "location": c.location, "quantity": c.quantity, "unit": c.unit,
            "paper": c.paper_value, "reproduced": _fmt(r.reproduced),
            "reconstructed": _fmt(r.reconstructed), "alternative": _fmt(r.alt), "tolerance": f"±({c.atol:g} + {c.rtol:g}·|paper|)",
            "status": c.status,
            "holds": "skipped" if r.skipped else ("yes" if r.ok else ("ERROR" if r.error else "NO")),
            "note": (r.error or c.note),
        })
    return pd.DataFrame(rows)


def table(notebook: str | None = None, work: str | None = None, prefix: str | None = None):
    """Compute and tabulate the claims shown by a notebook (its last cell calls this): the numeric
    rows, then the notebook's qualitative rows (``status`` = the stated verdict, ``reproduced`` = the
    recipe's measurements)."""
    import pandas as pd

    res = evaluate_all(select(load(), work=work, notebook=notebook, prefix=prefix),
                       skip_slow=fast_mode())
    out = results_frame(res)
    if prefix is None and (notebook or work):
        q = qualitative_table(notebook=notebook, work=work)
        if len(q):
            q = pd.DataFrame({"claim": q.claim, "location": q.location, "quantity": q.quote,
                              "unit": "statement", "reproduced": q.numbers, "status": q.verdict,
                              "holds": q.holds, "note": q.measured})
            out = pd.concat([out, q], ignore_index=True).fillna("")
    return out


def summary_frame(results: list[Result]):
    """Counts per work and status, with how many hold."""
    import pandas as pd

    df = pd.DataFrame([{"work": r.claim.work, "status": r.claim.status, "holds": r.ok,
                        "skipped": r.skipped} for r in results])
    if df.empty:
        return df
    g = df.groupby(["work", "status"]).agg(rows=("holds", "size"), hold=("holds", "sum"),
                                            skipped=("skipped", "sum"))
    return g.reset_index()


def latest_summary():
    """Summary per work and status: from ``build/claims.csv`` if it is newer than the ledger (and its
    notebooks' recipes were just computed by ``make reproduce``), otherwise computed now."""
    import pandas as pd

    report = build_dir() / "claims.csv"
    if report.exists() and report.stat().st_mtime >= CLAIMS_CSV.stat().st_mtime:
        df = pd.read_csv(report)
        df["hold"] = df.holds.astype(str) == "True"
        df["skipped"] = df.holds.astype(str) == "skipped"
        out = df.groupby(["work", "status"]).agg(rows=("hold", "size"), hold=("hold", "sum"),
                                                 skipped=("skipped", "sum")).reset_index()
        out.attrs["source"] = str(report)
        return out
    out = summary_frame(evaluate_all(load(), skip_slow=fast_mode()))
    out.attrs["source"] = "computed now"
    return out


def headline(summary=None):
    """The headline: one row per work, reproduced results (MATCH + DIFFERS) apart from the rest.

    ``summary`` is a :func:`summary_frame` (or :func:`latest_summary`) frame; by default
    :func:`latest_summary`. Columns: ``reproduced`` (MATCH + DIFFERS), one column per status with
    its row count, ``rows``, ``hold`` and ``skipped``; a last row ``all`` sums the works.

    >>> import pandas as pd
    >>> s = pd.DataFrame({"work": ["w", "w"], "status": ["MATCH", "INPUT"], "rows": [3, 2],
    ...                   "hold": [3, 2], "skipped": [0, 0]})
    >>> h = headline(s)
    >>> int(h.loc["w", "reproduced"]), int(h.loc["w", "INPUT"]), int(h.loc["all", "rows"])
    (3, 2, 5)
    """
    import pandas as pd

    if summary is None:
        summary = latest_summary()
    cols = ["reproduced", *STATUSES, "rows", "hold", "skipped"]
    if summary.empty:
        return pd.DataFrame(columns=cols, index=pd.Index([], name="work"))
    counts = summary.pivot_table(index="work", columns="status", values="rows", aggfunc="sum",
                                 fill_value=0).reindex(columns=list(STATUSES), fill_value=0)
    out = pd.DataFrame(index=counts.index)
    out["reproduced"] = counts[list(REPRODUCED)].sum(axis=1)
    for st in STATUSES:
        out[st] = counts[st]
    tot = summary.groupby("work")[["rows", "hold", "skipped"]].sum()
    out = out.join(tot)
    order = [w for w in WORK_IDS if w in out.index] + [w for w in out.index if w not in WORK_IDS]
    out = out.loc[order]
    out.loc["all"] = out.sum()
    out = out.astype(int)
    out.index.name = "work"
    out.attrs.update(getattr(summary, "attrs", {}))
    return out


# ------------------------------------------------------------------ qualitative claims (statements)
#: data/qualitative_claims.csv: one row per thesis statement, conclusion or headline sentence
QUALITATIVE_CSV = CLAIMS_CSV.parent / "qualitative_claims.csv"
QUAL_COLUMNS = ("claim_id", "work", "seed_file", "location", "quote", "verdict", "measure",
                "computed_by", "test", "notebook", "note")
VERDICTS = ("HOLDS", "PARTIAL", "FAILS", "NOT_TESTABLE")


@dataclasses.dataclass(frozen=True)
class Verdict:
    """What a qualitative recipe returns: the verdict, one sentence saying what was measured against
    which threshold (``text``) and the measured quantities (``numbers``, name with unit -> value).

    >>> Verdict("HOLDS", "max |s - s_Thesis| = 0 mm", {"residual_mm": 0.0}).verdict
    'HOLDS'
    """

    verdict: str
    text: str
    numbers: dict = dataclasses.field(default_factory=dict)

    def __post_init__(self):
        if self.verdict not in VERDICTS:
            raise ValueError(f"verdict must be one of {VERDICTS}, got {self.verdict!r}")


#: one row of ``data/qualitative_claims.csv`` (the columns, plus ``slow`` and the CSV ``line``)
QualitativeClaim = dataclasses.make_dataclass(
    "QualitativeClaim", [(c, str) for c in QUAL_COLUMNS] + [("slow", bool, False), ("line", int, 0)], frozen=True)


def load_qualitative(path: Path | str = QUALITATIVE_CSV) -> list[QualitativeClaim]:
    """Read and validate ``data/qualitative_claims.csv`` (errors name file, line and column).

    Every row quotes the seed (``quote``), names its expected ``verdict`` and, unless NOT_TESTABLE,
    the zero-argument recipe (``computed_by``) returning a :class:`Verdict`; ``test`` names the test
    asserting it. A ``slow`` column (optional) marks recipes that take more than a few seconds.
    """
    path = Path(path)
    with open(path, newline="", encoding="utf-8") as fh:
        reader = csv.DictReader(fh)
        missing = [c for c in QUAL_COLUMNS if c not in (reader.fieldnames or [])]
        if missing:
            raise LedgerError(f"{path}: header lacks columns {missing}")
        out, seen = [], {}
        for i, raw in enumerate(reader, start=2):
            where = f"{path}:{i}"
            r = {k: (raw.get(k) or "").strip() for k in (*QUAL_COLUMNS, "slow")}
            cid = r["claim_id"]
            if not cid or cid in seen:
                raise LedgerError(f"{where}: empty or duplicate claim_id {cid!r}")
            seen[cid] = i
            if r["work"] not in WORK_IDS:
                raise LedgerError(f"{where}: column 'work' must be one of {WORK_IDS}, got {r['work']!r}")
            if r["seed_file"] != SEED_FILES[r["work"]]:
                raise LedgerError(f"{where}: seed_file {r['seed_file']!r} is not the seed of {r['work']}")
            if r["verdict"] not in VERDICTS:
                raise LedgerError(f"{where}: column 'verdict' must be one of {VERDICTS}, got {r['verdict']!r}")
            if any(not r[col] for col in ("location", "quote", "measure", "test")):
                raise LedgerError(f"{where}: a column of location, quote, measure, test is empty")
            if r["computed_by"] and not _DOTTED.match(r["computed_by"]):
                raise LedgerError(f"{where}: column 'computed_by' is not a dotted name: {r['computed_by']!r}")
            if not r["computed_by"] and r["verdict"] != "NOT_TESTABLE":
                raise LedgerError(f"{where}: a {r['verdict']} verdict needs computed_by (only NOT_TESTABLE has none)")
            if r["verdict"] == "NOT_TESTABLE" and not r["computed_by"] and not quotes(r["note"]):
                raise LedgerError(f"{where}: a NOT_TESTABLE row without a recipe must quote in its note "
                                  f"(in “…”) the seed sentence showing the evidence is measured or not given")
            out.append(QualitativeClaim(**{k: r[k] for k in QUAL_COLUMNS},
                                        slow=r["slow"] in ("1", "true", "True", "yes"), line=i))
    return out


@dataclasses.dataclass
class QualitativeResult:
    claim: QualitativeClaim
    verdict: Verdict | None = None
    ok: bool = False
    skipped: bool = False
    error: str = ""


def evaluate_qualitative(claim: QualitativeClaim, skip_slow: bool = False) -> QualitativeResult:
    """Run the row's recipe; ``ok`` when it returns the verdict the row states."""
    res = QualitativeResult(claim)
    if not claim.computed_by or (skip_slow and claim.slow):
        res.ok, res.skipped = claim.verdict == "NOT_TESTABLE", bool(claim.computed_by)
        return res
    try:
        v = resolve(claim.computed_by)()
        if not isinstance(v, Verdict):
            raise LedgerError(f"{claim.computed_by} returned {type(v).__name__}, not a claims.Verdict")
        res.verdict = v
        res.ok = v.verdict == claim.verdict
    except Exception as exc:  # reported, never hidden
        res.error = f"{type(exc).__name__}: {exc}"
    return res


def _numbers(v: Verdict | None) -> str:
    return "" if v is None else "; ".join(f"{k} = {_fmt(x) if isinstance(x, (int, float)) else x}"
                                          for k, x in v.numbers.items())


def qualitative_frame(results: list[QualitativeResult]):
    """A pandas DataFrame of qualitative results: quote, stated verdict, computed verdict, numbers."""
    import pandas as pd

    rows = []
    for r in results:
        c = r.claim
        rows.append({"claim": c.claim_id, "location": c.location, "quote": c.quote, "verdict": c.verdict,
                     "computed": "skipped" if r.skipped else (r.verdict.verdict if r.verdict else
                                                              ("" if r.ok else "ERROR")),
                     "holds": "skipped" if r.skipped else ("yes" if r.ok else "NO"),
                     "measured": r.error or (r.verdict.text if r.verdict else c.note),
                     "numbers": _numbers(r.verdict)})
    return pd.DataFrame(rows)


def qualitative_table(notebook: str | None = None, work: str | None = None):
    """Compute and tabulate the qualitative rows (of one notebook or work)."""
    qs = [q for q in load_qualitative() if (notebook is None or q.notebook == notebook)
          and (work is None or q.work == work)]
    return qualitative_frame([evaluate_qualitative(q, skip_slow=fast_mode()) for q in qs])


def qualitative_counts(results: list[QualitativeResult]):
    """Rows per work and verdict (the closing note's qualitative counts)."""
    import pandas as pd

    df = pd.DataFrame([{"work": r.claim.work, "verdict": r.claim.verdict} for r in results])
    if df.empty:
        return df
    return df.pivot_table(index="work", columns="verdict", aggfunc="size", fill_value=0).reindex(
        columns=list(VERDICTS), fill_value=0)


def write_report(results: list[Result], outdir: Path,
                 qualitative: list[QualitativeResult] | None = None) -> tuple[Path, Path]:
    """Write ``claims.csv`` and ``claims.md`` into ``outdir`` (atomically); ``claims.md`` ends with
    the qualitative rows (computed now, slow ones skipped in fast mode, unless given)."""
    outdir = Path(outdir)
    if qualitative is None:
        qualitative = [evaluate_qualitative(q, skip_slow=fast_mode()) for q in load_qualitative()]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["claim_id", "work", "seed_file", "location", "quantity", "unit", "paper_value",
                "reproduced_value", "reconstructed_value", "alt_value", "rtol", "atol", "status",
                "holds", "note"])
    for r in results:
        c = r.claim
        w.writerow([c.claim_id, c.work, c.seed_file, c.location, c.quantity, c.unit, c.paper_value,
                    _fmt(r.reproduced), _fmt(r.reconstructed), _fmt(r.alt), c.rtol, c.atol, c.status,
                    "skipped" if r.skipped else r.ok, r.error or c.note])
    p_csv = atomic_write(outdir / "claims.csv", buf.getvalue())
    md = ["# cnclab claims report", "",
          "Rows per work and status. Reproduced results are the MATCH and DIFFERS rows only; "
          "CONSISTENT (arithmetic on printed numbers), INPUT (taken as input or built in), "
          "NOT_DERIVABLE (an input is absent) and DISCREPANT (no explanation found) are counted apart.",
          ""]
    head = headline(summary_frame(results))
    cols = list(head.columns)
    md += ["| work | " + " | ".join(cols) + " |", "|---" * (len(cols) + 1) + "|"]
    for work, s in head.iterrows():
        md.append(f"| {work} | " + " | ".join(str(s[c]) for c in cols) + " |")
    md.append("")
    for work in WORK_IDS:
        rs = [r for r in results if r.claim.work == work]
        if not rs:
            continue
        md += [f"## {work}", "", "| claim | location | paper | reproduced | reconstructed | alternative | "
               "tolerance | status | holds |", "|---|---|---|---|---|---|---|---|---|"]
        for r in rs:
            c = r.claim
            holds = "skipped" if r.skipped else ("yes" if r.ok else "**NO**")
            md.append(f"| {c.claim_id} | {c.location} | {c.paper_value:g} {c.unit} | {_fmt(r.reproduced)} | "
                      f"{_fmt(r.reconstructed)} | {_fmt(r.alt)} | ±({c.atol:g}+{c.rtol:g}·p) | {c.status} | "
                      f"{holds} |")
        md.append("")
    md += _qualitative_markdown(qualitative)
    p_md = atomic_write(outdir / "claims.md", "\n".join(md) + "\n")
    return p_csv, p_md


def _qualitative_markdown(results: list[QualitativeResult]) -> list[str]:
    if not results:
        return []
    md = ["## Qualitative claims (thesis statements, conclusions, headline sentences)", "",
          "Each verdict is computed by the recipe named in `data/qualitative_claims.csv`; a test fails "
          "if the computed verdict changes.", "", "| work | " + " | ".join(VERDICTS) + " |",
          "|---" * (len(VERDICTS) + 1) + "|"]
    for work, s in qualitative_counts(results).iterrows():
        md.append(f"| {work} | " + " | ".join(str(s[v]) for v in VERDICTS) + " |")
    md += ["", "| claim | location | quote | verdict | holds | measured |", "|---|---|---|---|---|---|"]
    cell = lambda t: str(t).replace("|", "\\|").replace("\n", " ")  # noqa: E731
    for r in results:
        c = r.claim
        holds = "skipped" if r.skipped else ("yes" if r.ok else "**NO**")
        meas = r.error or ((r.verdict.text + (" (" + _numbers(r.verdict) + ")" if r.verdict.numbers else ""))
                           if r.verdict else c.note)
        md.append(f"| {c.claim_id} | {cell(c.location)} | {cell(c.quote)} | {c.verdict} | {holds} | "
                  f"{cell(meas)} |")
    return md + [""]


def main(argv: list[str] | None = None) -> int:
    """``python -m cnclab claims [--work W] [--json] [--report DIR] [--skip-slow]``."""
    ap = clihelp.parser(
        "python -m cnclab claims",
        "Compute every row of the claims ledger (every number the four works print, with the value\n"
        "the code computes now) and say whether its status (MATCH, DIFFERS, ...) still holds. Prints\n"
        "one line per row and a headline per work; exits with 1 if a row no longer holds.",
        examples=["python -m cnclab claims --work hoang2024",
                  "python -m cnclab claims --skip-slow --report build"],
        writes=["nothing, unless --report DIR: DIR/claims.csv and DIR/claims.md"])
    ap.add_argument("--work", choices=WORK_IDS, help="only this work (default: all four)")
    ap.add_argument("--prefix", help="only claims whose id starts with this (default: all)")
    ap.add_argument("--json", action="store_true", help="print a JSON list of result objects instead of tables")
    ap.add_argument("--report", metavar="DIR", help="also write DIR/claims.csv and DIR/claims.md (default: none)")
    ap.add_argument("--skip-slow", action="store_true", help="do not compute rows marked slow")
    ap.add_argument("--ledger", default=str(CLAIMS_CSV), help="ledger CSV (default: data/claims.csv)")
    args = ap.parse_args(argv)
    try:
        claims = select(load(args.ledger), work=args.work, prefix=args.prefix)
    except (LedgerError, FileNotFoundError) as exc:
        print(f"error: {exc}")
        return 2
    results = evaluate_all(claims, skip_slow=args.skip_slow, progress=not args.json)
    try:
        quals = [q for q in load_qualitative() if (not args.work or q.work == args.work)
                 and (not args.prefix or q.claim_id.startswith(args.prefix))]
    except (LedgerError, FileNotFoundError) as exc:
        print(f"error: {exc}")
        return 2
    qres = [evaluate_qualitative(q, skip_slow=args.skip_slow) for q in quals]
    if args.json:
        print(json.dumps([r.to_json() for r in results] + [
            {"claim_id": r.claim.claim_id, "work": r.claim.work, "seed_file": r.claim.seed_file,
             "location": r.claim.location, "paper_value": None, "reproduced_value": None,
             "status": r.claim.verdict, "kind": "qualitative", "quote": r.claim.quote,
             "verdict": r.claim.verdict, "computed_verdict": r.verdict.verdict if r.verdict else None,
             "measured": r.verdict.text if r.verdict else "", "numbers": r.verdict.numbers if r.verdict else {},
             "ok": r.ok, "skipped": r.skipped, "error": r.error} for r in qres],
            indent=1, default=_json_default))
    else:
        import pandas as pd

        with pd.option_context("display.max_rows", None, "display.width", 200,
                               "display.max_colwidth", 60):
            print(results_frame(results).drop(columns=["note"]).to_string(index=False))
        print()
        print(headline(summary_frame(results)).to_string())
        if qres:
            with pd.option_context("display.max_rows", None, "display.width", 200, "display.max_colwidth", 70):
                q = qualitative_frame(qres)[["claim", "verdict", "computed", "holds", "numbers"]]
                print(f"\n{q.to_string(index=False)}\n\n{qualitative_counts(qres).to_string()}")
    if args.report:
        for p in write_report(results, Path(args.report), qualitative=qres):
            print(f"wrote {p}")
    failed = [r for r in results if not r.ok and not r.skipped]
    failed += [r for r in qres if not r.ok and not r.skipped]
    if failed and not args.json:
        print(f"\n{len(failed)} claim(s) do not hold: " + ", ".join(r.claim.claim_id for r in failed[:20]))
    return 1 if failed else 0
