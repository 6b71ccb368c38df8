"""Qualitative claims (data/qualitative_claims.csv): every thesis statement, conclusion and headline
sentence of the four works has a row; each verdict is computed by its recipe, and this test fails when
the computed verdict differs from the stated one (so a verdict cannot change silently)."""
import csv
from pathlib import Path

import pytest

from cnclab import claims
from cnclab.paths import REPO_ROOT
from cnclab.runtime import fast_mode

QUAL = claims.load_qualitative()
COMPUTED = [q for q in QUAL if q.computed_by]


@pytest.mark.parametrize("q", COMPUTED, ids=[q.claim_id for q in COMPUTED])
def test_verdict_is_computed(q):
    if q.slow and fast_mode():
        pytest.skip("slow recipe: computed by make reproduce (and by a run without CNCLAB_FAST)")
    res = claims.evaluate_qualitative(q)
    assert not res.error, f"{q.claim_id} ({q.computed_by}) raised: {res.error}"
    assert res.verdict.verdict == q.verdict, (
        f"{q.claim_id}: the recipe now says {res.verdict.verdict} ({res.verdict.text}: {res.verdict.numbers}), "
        f"the ledger says {q.verdict}: revisit the row")
    assert res.verdict.numbers, f"{q.claim_id}: a verdict must carry the numbers it rests on"


def test_every_row_names_this_test_and_an_existing_notebook():
    for q in QUAL:
        path, _, name = q.test.partition("::")
        assert (REPO_ROOT / path).is_file() and name, f"{q.claim_id}: test {q.test!r} not found"
        assert name in (REPO_ROOT / path).read_text(), f"{q.claim_id}: {name} not in {path}"
        assert (REPO_ROOT / "notebooks" / q.notebook).is_file(), f"{q.claim_id}: notebook {q.notebook} missing"


#: every thesis point and every conclusion section of each work must have at least one row
REQUIRED = {
    "jacso2021": ("Thesis I ", "Thesis II ", "Thesis III ", "Thesis IV", "§4"),
    "kim_yang2006": ("Abstract", "§5 Conclusions", "§4"),
    "hoang2024": ("Abstract", "Conclusion"),
    "mgherony2024": ("§3.4", "§4.4", "Thesis 1", "Thesis 2", "Thesis 3", "Thesis 4", "Thesis 5", "§6.4",
                     "§7.4", "§8.4", "§9.4"),
}


@pytest.mark.parametrize("work", list(REQUIRED))
def test_every_thesis_and_conclusion_has_a_row(work):
    locs = [q.location + " " for q in QUAL if q.work == work]
    for marker in REQUIRED[work]:
        assert any(marker in loc for loc in locs), f"{work}: no qualitative row for {marker.strip()}"


def _seed_text(work):
    for d in (REPO_ROOT.parent / "shared" / "seeds", Path("/work/shared/seeds")):
        p = d / claims.SEED_FILES[work]
        if p.is_file():
            return claims.normalize_text(p.read_text(encoding="utf-8"))
    pytest.skip("seed texts not present (../shared/seeds)")


@pytest.mark.parametrize("q", QUAL, ids=[q.claim_id for q in QUAL])
def test_quote_is_in_the_seed(q):
    text = _seed_text(q.work)
    assert claims.normalize_text(q.quote) in text, f"{q.claim_id}: quote not in the seed: {q.quote!r}"
    for part in claims.quotes(q.note):
        assert claims.normalize_text(part) in text, f"{q.claim_id}: note quote not in the seed: {part!r}"


HEADER = list(claims.QUAL_COLUMNS)
BASE = dict(claim_id="hoang2024.q.x", work="hoang2024", seed_file=claims.SEED_FILES["hoang2024"],
            location="Conclusion", quote="q", verdict="HOLDS", measure="m",
            computed_by="tests.test_claims_qualitative.holds", test="t::x", notebook="", note="")


def holds():
    return claims.Verdict("HOLDS", "always", {"x": 1.0})


def _write(tmp_path, **over):
    p = tmp_path / "q.csv"
    with open(p, "w", newline="") as fh:
        w = csv.DictWriter(fh, HEADER)
        w.writeheader()
        w.writerow({**BASE, **over})
    return p


@pytest.mark.parametrize("over, msg", [
    (dict(verdict="TRUE"), "verdict"),
    (dict(computed_by=""), "computed_by"),
    (dict(verdict="NOT_TESTABLE", computed_by=""), "quote"),
    (dict(work="x"), "work"),
    (dict(quote=""), "quote"),
])
def test_bad_rows_name_file_and_line(tmp_path, over, msg):
    p = _write(tmp_path, **over)
    with pytest.raises(claims.LedgerError) as ei:
        claims.load_qualitative(p)
    assert f"{p}:2" in str(ei.value) and msg in str(ei.value)


def test_evaluate_flags_a_changed_verdict(tmp_path):
    ok = claims.evaluate_qualitative(claims.load_qualitative(_write(tmp_path))[0])
    assert ok.ok and ok.verdict.numbers == {"x": 1.0}
    changed = claims.evaluate_qualitative(claims.load_qualitative(_write(tmp_path, verdict="FAILS"))[0])
    assert not changed.ok and changed.verdict.verdict == "HOLDS"


def test_verdict_rejects_unknown_labels():
    with pytest.raises(ValueError, match="verdict"):
        claims.Verdict("MAYBE", "x")


def test_report_lists_qualitative_rows(tmp_path):
    q = claims.load_qualitative(_write(tmp_path))
    res = [claims.evaluate_qualitative(c) for c in q]
    _, md = claims.write_report([], tmp_path / "out", qualitative=res)
    text = Path(md).read_text()
    assert "Qualitative claims" in text and "hoang2024.q.x" in text and "| HOLDS |" in text
