"""The ledger follows its own rules (CONTRIBUTING "Claims ledger", issue 25 item 6).

* a MATCH (or DIFFERS) is never a restatement: two reproduced rows of one location with the same
  printed number must not compute the identical (or mirrored, −v) value unless the note states why
  the two computations are independent (``independent:``); the value 0 is exempt (p-values printed
  0.000, apex angles), since it is the common value of unrelated quantities;
* a paper value is a printed number, transcribed with its printed digits (not a statement encoded
  as 1, not a share of seeds);
* a DIFFERS row's alternative lands within half a unit of the printed last digit, unless the
  tolerance basis states an input-rounding reason (the propagated rounding of printed inputs) or the
  one figure-reading tolerance.
Rows marked slow are left out in fast mode (``CNCLAB_FAST=1``); ``make reproduce`` computes them.
"""
from __future__ import annotations

import collections
import csv
import functools
import math
import re
from pathlib import Path

import pytest

from cnclab import claims
from cnclab.paths import CLAIMS_CSV, REPO_ROOT
from cnclab.runtime import fast_mode

LEDGER = claims.load()
RAW = {r["claim_id"]: r for r in csv.DictReader(open(CLAIMS_CSV, encoding="utf-8"))}
REPRODUCED = ("MATCH", "DIFFERS")
#: a stated reason for a DIFFERS tolerance wider than half a printed unit
ROUNDING_REASON = re.compile(r"round|propagat|figure reading", re.I)


def half_unit(printed: str) -> float:
    """Half a unit of the last digit of a number as transcribed (``"12.50"`` → 0.005, ``"70"`` → 0.5).

    >>> half_unit("-4.363"), half_unit("3002"), half_unit("0.000")
    (0.0005, 0.5, 0.0005)
    """
    s = printed.strip().lstrip("+-")
    if not re.fullmatch(r"\d+(\.\d+)?", s):
        raise ValueError(f"not a plain decimal number: {printed!r}")
    decimals = len(s.split(".")[1]) if "." in s else 0
    return 0.5 * 10.0 ** -decimals


@functools.lru_cache(maxsize=None)
def value(claim_id: str):
    """(reproduced, alternative) of a row, computed once per test session."""
    c = next(c for c in LEDGER if c.claim_id == claim_id)
    res = claims.evaluate(c)
    assert not res.error, f"{claim_id}: {res.error}"
    return res.reproduced, res.alt


def _computable(c):
    return c.computed_by and not (c.slow and fast_mode())


def _scalar(v):
    return None if v is None or isinstance(v, claims.Interval) else float(v)


# ------------------------------------------------------------------------- statements are not rows
@pytest.mark.parametrize("c", LEDGER, ids=[c.claim_id for c in LEDGER])
def test_paper_value_is_a_printed_number(c):
    half_unit(RAW[c.claim_id]["paper_value"])           # a plain decimal, as printed
    assert c.unit.lower() not in ("statement", "share", "bool", "boolean"), (
        f"{c.claim_id}: unit {c.unit!r}: a statement is a qualitative row (data/qualitative_claims.csv)")
    text = f"{c.quantity} {c.tolerance_basis}".lower()
    assert "1 = holds" not in text and "a statement" not in text, (
        f"{c.claim_id}: a statement encoded as a number: make it a qualitative row")


def _seed_tokens():
    for d in (REPO_ROOT.parent / "shared" / "seeds", Path("/work/shared/seeds")):
        if d.is_dir():
            out = {}
            for w, f in claims.SEED_FILES.items():
                text = (d / f).read_text(encoding="utf-8")
                toks = set()
                for m in re.finditer(r"\d+(?:[.,]\d+)*|\d{1,3}(?:[ \u00a0\u2009\u202f]\d{3})+(?:[.,]\d+)?", text):
                    t = re.sub(r"[ \u00a0\u2009\u202f]", "", m.group(0))
                    toks.add(t.replace(",", "."))
                    if "," in t:
                        toks.add(t.replace(",", "") if "." in t or t.count(",") > 1 else t.replace(",", ""))
                out[w] = toks
            return out
    return None


SEED_TOKENS = _seed_tokens()


@pytest.mark.parametrize("c", LEDGER, ids=[c.claim_id for c in LEDGER])
def test_paper_value_has_its_printed_digits(c):
    """The transcription keeps the printed digits ("4.530", not "4.53"): half a unit depends on them."""
    if SEED_TOKENS is None:
        pytest.skip("seed texts not present")
    s = RAW[c.claim_id]["paper_value"].strip().lstrip("+-")
    assert s in SEED_TOKENS[c.work], f"{c.claim_id}: {s!r} is not printed with these digits in {c.seed_file}"


# ---------------------------------------------------------------- no MATCH by construction
def _groups():
    by = collections.defaultdict(list)
    for c in LEDGER:
        if c.status in REPRODUCED and _computable(c) and c.paper_value != 0:
            by[(c.work, c.location, abs(c.paper_value))].append(c)
    return [g for g in by.values() if len(g) > 1]


GROUPS = _groups()


@pytest.mark.parametrize("group", GROUPS, ids=[g[0].claim_id for g in GROUPS])
def test_no_reproduced_row_restates_another(group):
    """Two reproduced rows of one location with the same |printed number| whose computed values are
    equal (or opposite, a mirror) are one result counted twice, unless a note says why not."""
    vals = [(c, _scalar(value(c.claim_id)[0])) for c in group]
    for i, (a, va) in enumerate(vals):
        for b, vb in vals[i + 1:]:
            if va is None or vb is None or math.copysign(1, a.paper_value) * va == 0:
                continue
            same = math.isclose(va, vb, rel_tol=1e-9, abs_tol=1e-12)
            mirror = math.isclose(va, -vb, rel_tol=1e-9, abs_tol=1e-12) and a.paper_value == -b.paper_value
            if (same and a.paper_value == b.paper_value) or mirror:
                assert "independent:" in a.note or "independent:" in b.note, (
                    f"{a.claim_id} and {b.claim_id} compute the same value {va:g}: one restates the other "
                    f"(make it CONSISTENT, pointing to the other) or state in a note why they are independent")


# ------------------------------------------------------------- DIFFERS explains the printed digits
DIFFERS = [c for c in LEDGER if c.status == "DIFFERS"]


@pytest.mark.parametrize("c", DIFFERS, ids=[c.claim_id for c in DIFFERS])
def test_differs_alternative_within_half_a_printed_unit(c):
    if c.slow and fast_mode():
        pytest.skip("slow row")
    _, alt = value(c.claim_id)
    h = half_unit(RAW[c.claim_id]["paper_value"])
    if isinstance(alt, claims.Interval):
        inside = alt.lo - h <= c.paper_value <= alt.hi + h
    else:
        inside = abs(float(alt) - c.paper_value) <= h * (1 + 1e-9)
    assert inside or ROUNDING_REASON.search(c.tolerance_basis), (
        f"{c.claim_id}: the explanation gives {alt}, {abs(float(alt) - c.paper_value):.3g} from the printed "
        f"{RAW[c.claim_id]['paper_value']} (half a unit {h:g}) and the tolerance basis states no input-rounding reason")


# ------------------------------------------------------------------------- the rule tests can fail
def test_rules_catch_a_restatement_and_a_statement(tmp_path):
    base = dict(zip(claims.COLUMNS, [""] * len(claims.COLUMNS)))
    base.update(work="hoang2024", seed_file=claims.SEED_FILES["hoang2024"], location="T", quantity="q", unit="-",
                rtol="0", atol="0.5", tolerance_basis="half a unit", status="MATCH",
                computed_by="tests.test_claims_rules.five")
    p = tmp_path / "c.csv"
    with open(p, "w", newline="") as fh:
        w = csv.DictWriter(fh, claims.COLUMNS)
        w.writeheader()
        w.writerow({**base, "claim_id": "hoang2024.a", "paper_value": "5"})
        w.writerow({**base, "claim_id": "hoang2024.b", "paper_value": "5"})
    rows = claims.load(p)
    va, vb = (float(claims.evaluate(c).reproduced) for c in rows)
    assert va == vb and rows[0].location == rows[1].location        # the pair the group test rejects
    with pytest.raises(ValueError):
        half_unit("1 = holds")
    assert half_unit("4.530") == 0.0005 and half_unit("4.53") == 0.005


def five():
    return 5.0
