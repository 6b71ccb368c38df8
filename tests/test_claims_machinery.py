"""The ledger machinery itself: validation errors, status semantics, CLI, atomic writes, savefig."""
import csv
import json
import subprocess
import sys

import pytest

from cnclab import claims
from cnclab.fileio import atomic_output, atomic_write

HEADER = list(claims.COLUMNS)
BASE = dict(claim_id="mgherony2024.test.x", work="mgherony2024", seed_file="004_6087ee43271ee0e7.txt",
            location="Table 0", quantity="q", unit="mm", paper_value="1.0", rtol="0", atol="0.01",
            tolerance_basis="printed to 2 decimals", status="MATCH", computed_by="math.sqrt",
            alt_computed_by="", missing_input="", slow="", notebook="", note="")


def one(value):
    return value


def ledger(tmp_path, **over):
    p = tmp_path / "claims.csv"
    with open(p, "w", newline="") as fh:
        w = csv.DictWriter(fh, HEADER)
        w.writeheader()
        w.writerow({**BASE, **over})
    return p


def test_interval_semantics():
    assert claims.within(claims.Interval(0.9, 1.1), 1.0, 0, 0)
    assert not claims.within(claims.Interval(1.2, 1.3), 1.0, 0, 0.1)
    assert claims.within(claims.Interval(1.05, 1.3), 1.0, 0, 0.05)
    with pytest.raises(ValueError):
        claims.Interval(2, 1)


def test_tolerance_is_atol_plus_rtol():
    assert claims.within(1.015, 1.0, 0.01, 0.005)
    assert not claims.within(1.016, 1.0, 0.01, 0.005)
    assert not claims.within(float("nan"), 1.0, 1, 1)


@pytest.mark.parametrize("over, msg", [
    (dict(status="FINE"), "status"),
    (dict(work="nobody"), "work"),
    (dict(paper_value="abc"), "paper_value"),
    (dict(status="DIFFERS"), "alt_computed_by"),
    (dict(status="NOT_DERIVABLE"), "missing_input"),
    (dict(computed_by="not dotted"), "dotted"),
    (dict(seed_file="000_690a1ed8f09fd780.txt"), "seed"),
    (dict(rtol="-1"), "tolerances"),
])
def test_bad_rows_name_file_line_and_column(tmp_path, over, msg):
    p = ledger(tmp_path, **over)
    with pytest.raises(claims.LedgerError) as ei:
        claims.load(p)
    assert f"{p}:2" in str(ei.value) and msg in str(ei.value)


def test_duplicate_ids_rejected(tmp_path):
    p = ledger(tmp_path)
    with open(p, "a", newline="") as fh:
        csv.DictWriter(fh, HEADER).writerow(BASE)
    with pytest.raises(claims.LedgerError, match="duplicate"):
        claims.load(p)


def test_evaluate_match_and_differs(tmp_path):
    ok = claims.evaluate(claims.load(ledger(tmp_path, computed_by="math.pi", paper_value="3.14"))[0])
    assert ok.error  # math.pi is not callable -> reported as an error, never a silent pass
    c = claims.load(ledger(tmp_path, computed_by="tests.test_claims_machinery.val_one"))[0]
    assert claims.evaluate(c).ok
    d = claims.load(ledger(tmp_path, status="DIFFERS", paper_value="2.0", note="typo",
                           computed_by="tests.test_claims_machinery.val_one",
                           alt_computed_by="tests.test_claims_machinery.val_two"))[0]
    r = claims.evaluate(d)
    assert r.ok and r.alt == 2.0 and r.reproduced == 1.0
    # a DIFFERS row whose consistent value matches after all does not hold
    d2 = claims.load(ledger(tmp_path, status="DIFFERS", paper_value="1.0", note="x",
                            computed_by="tests.test_claims_machinery.val_one",
                            alt_computed_by="tests.test_claims_machinery.val_one"))[0]
    assert not claims.evaluate(d2).ok


def test_status_semantics_discrepant_consistent_input(tmp_path):
    def ev(**over):
        return claims.evaluate(claims.load(ledger(tmp_path, **over))[0])

    one = "tests.test_claims_machinery.val_one"
    # DISCREPANT holds only while the value stays outside the tolerance
    assert ev(status="DISCREPANT", paper_value="2.0", computed_by=one, note="tried x").ok
    assert not ev(status="DISCREPANT", paper_value="1.0", computed_by=one, note="tried x").ok
    # CONSISTENT and INPUT (with a function) hold only within tolerance
    for st in ("CONSISTENT", "INPUT"):
        assert ev(status=st, paper_value="1.0", computed_by=one).ok
        assert not ev(status=st, paper_value="1.5", computed_by=one).ok
    # NOT_DERIVABLE: the reconstruction is computed and reported, an error is not hidden
    r = ev(status="NOT_DERIVABLE", computed_by="", missing_input="measured: “the forces were measured on the machine”",
           reconstructed_by="tests.test_claims_machinery.val_two")
    assert r.ok and r.reconstructed == 2.0 and r.reproduced is None
    assert r.to_json()["reconstructed_value"] == 2.0
    assert claims.results_frame([r]).loc[0, "reconstructed"] == "2"
    bad = ev(status="NOT_DERIVABLE", computed_by="", missing_input="measured: “the forces were measured on the machine”",
             reconstructed_by="tests.test_claims_machinery.raises")
    assert not bad.ok and "boom" in bad.error


@pytest.mark.parametrize("over, msg", [
    (dict(status="DISCREPANT", computed_by="tests.test_claims_machinery.val_one"), "what was tried"),
    (dict(status="CONSISTENT", computed_by=""), "computed_by"),
    (dict(reconstructed_by="tests.test_claims_machinery.val_two"), "reconstructed_by"),
    (dict(status="MATCH", alt_computed_by="tests.test_claims_machinery.val_two"), "alt_computed_by"),
])
def test_status_rules_enforced_by_load(tmp_path, over, msg):
    with pytest.raises(claims.LedgerError, match=msg):
        claims.load(ledger(tmp_path, **over))


def test_not_derivable_must_quote_the_seed_in_quoted_works(tmp_path):
    row = dict(claim_id="hoang2024.test.x", work="hoang2024", seed_file=claims.SEED_FILES["hoang2024"],
               status="NOT_DERIVABLE", computed_by="")
    assert "hoang2024" in claims.QUOTED_WORKS
    with pytest.raises(claims.LedgerError, match="quote"):
        claims.load(ledger(tmp_path, missing_input="the commercial program", **row))
    with pytest.raises(claims.LedgerError, match="quote"):  # too short to be a sentence
        claims.load(ledger(tmp_path, missing_input='the program: "CAD/CAM"', **row))
    c = claims.load(ledger(tmp_path, missing_input="the program: “using commercial CAD/CAM software”", **row))[0]
    assert claims.quotes(c.missing_input) == ["using commercial CAD/CAM software"]


def test_printed_number_forms():
    text = "V = 2 098 mm3; MRR 1147,5; lengths | 5270,744 | and 1,234 and Y49.7497"
    for v in (2098, 1147.5, 5270.744, 1234, 1.234, 49.7497, -49.7497):
        assert claims.is_printed(v, text), v
    for v in (2099, 1147.0, 49.7494, 0.5):
        assert not claims.is_printed(v, text), v


def test_headline_keeps_reproduced_apart(tmp_path):
    rows = [dict(BASE, claim_id=f"mgherony2024.t.{i}", status=st, computed_by=cb, note="n",
                 alt_computed_by=alt, missing_input=mi)
            for i, (st, cb, alt, mi) in enumerate([
                ("MATCH", "tests.test_claims_machinery.val_one", "", ""),
                ("DIFFERS", "tests.test_claims_machinery.val_two", "tests.test_claims_machinery.val_one", ""),
                ("CONSISTENT", "tests.test_claims_machinery.val_one", "", ""),
                ("INPUT", "", "", ""),
                ("NOT_DERIVABLE", "", "", "measured: “the forces were measured on the machine”"),
                ("DISCREPANT", "tests.test_claims_machinery.val_two", "", "")])]
    p = tmp_path / "h.csv"
    with open(p, "w", newline="") as fh:
        w = csv.DictWriter(fh, HEADER)
        w.writeheader()
        w.writerows(rows)
    res = claims.evaluate_all(claims.load(p))
    assert all(r.ok for r in res)
    h = claims.headline(claims.summary_frame(res))
    row = h.loc["mgherony2024"]
    assert row["reproduced"] == 2 and row["MATCH"] == 1 and row["DIFFERS"] == 1
    assert row["CONSISTENT"] == row["INPUT"] == row["NOT_DERIVABLE"] == row["DISCREPANT"] == 1
    assert row["rows"] == 6 and row["hold"] == 6 and h.loc["all", "rows"] == 6
    _, md = claims.write_report(res, tmp_path / "out")
    text = md.read_text()
    assert text.index("| work | reproduced |") < text.index("## mgherony2024")
    assert "reconstructed" in text


def test_indexed_computed_by(tmp_path):
    c = claims.load(ledger(tmp_path, computed_by="tests.test_claims_machinery.mapping[b]",
                           paper_value="2"))[0]
    assert claims.evaluate(c).reproduced == 2.0
    c = claims.load(ledger(tmp_path, computed_by="tests.test_claims_machinery.mapping[zz]"))[0]
    assert "no key" in claims.evaluate(c).error


def val_one():
    return 1.0


def val_two():
    return 2.0


def mapping():
    return {"a": 1.0, "b": 2.0}


def raises():
    raise RuntimeError("boom")


# The CLI's JSON and exit status on three slices that hold every kind of row the full ledger has
# (every row's value is checked in-process by tests/test_claims.py; the full ledger through the CLI
# would evaluate it all a second time): hoang2024 = the qualitative rows (HOLDS, PARTIAL,
# NOT_TESTABLE) and DIFFERS; mgherony2024.ch9 = slow rows skipped and a reconstructed value;
# mgherony2024.ch5 = an interval-valued reproduced value (a JSON object).
@pytest.mark.parametrize("scope", [["--work", "hoang2024"], ["--prefix", "mgherony2024.ch9"],
                                   ["--prefix", "mgherony2024.ch5"]], ids=lambda s: s[1])
def test_cli_json_keys(scope):
    out = subprocess.run([sys.executable, "-m", "cnclab", "claims", "--json", "--skip-slow", *scope],
                         capture_output=True, text=True, check=False)
    rows = json.loads(out.stdout)
    assert rows and all(r["claim_id"].startswith(scope[1]) for r in rows)
    for r in rows:
        assert {"claim_id", "work", "seed_file", "location", "paper_value", "reproduced_value",
                "status", "ok"} <= set(r)
    assert out.returncode == (0 if all(r["ok"] or r["skipped"] for r in rows) else 1)


def test_report_written(tmp_path):
    c = claims.load(ledger(tmp_path, computed_by="tests.test_claims_machinery.val_one"))
    p_csv, p_md = claims.write_report(claims.evaluate_all(c), tmp_path / "out")
    assert "mgherony2024.test.x" in p_md.read_text() and p_csv.read_text().count("\n") == 2


def test_atomic_write_leaves_nothing_on_failure(tmp_path):
    dest = tmp_path / "x.txt"
    atomic_write(dest, "old")
    with pytest.raises(RuntimeError):
        with atomic_output(dest) as fh:
            fh.write("partial")
            raise RuntimeError("boom")
    assert dest.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["x.txt"]


def test_atomic_write_refuses_to_overwrite_input(tmp_path):
    src = tmp_path / "in.txt"
    src.write_text("input")
    with pytest.raises(ValueError, match="input"):
        atomic_write(src, "new", inputs=[src])
    assert src.read_text() == "input"


def test_savefig_writes_three_formats(tmp_path, monkeypatch):
    import matplotlib.pyplot as plt

    from cnclab import savefig

    from PIL import Image

    monkeypatch.setenv("CNCLAB_BUILD_DIR", str(tmp_path))
    monkeypatch.setenv("CNCLAB_FAST", "0")                  # what make reproduce writes
    fig, ax = plt.subplots()
    ax.plot([0, 1], [1, 0])
    paths = savefig(fig, "t_fig", "hoang2024")
    assert {p.suffix for p in paths} == {".pdf", ".svg", ".png"}
    assert all(p.parent == tmp_path / "figures" / "hoang2024" and p.stat().st_size > 0 for p in paths)
    w_in = fig.get_size_inches()[0]
    with Image.open(paths[-1]) as im:                       # 300 dpi, up to the tight crop of the style
        full_px = im.size[0]
    assert 0.8 * 300 * w_in < full_px <= 300 * w_in + 1
    monkeypatch.setenv("CNCLAB_FAST", "1")                  # fast mode (make test's notebooks): a 100 dpi PNG
    [png] = savefig(fig, "t_fig_fast", "hoang2024")
    assert png.suffix == ".png" and not png.with_suffix(".pdf").exists()
    with Image.open(png) as im:
        assert im.size[0] == pytest.approx(full_px / 3, abs=2)
    with pytest.raises(ValueError):
        savefig(fig, "../escape", "hoang2024")
    with pytest.raises(ValueError):
        savefig(fig, "ok", "nowork")
    plt.close(fig)
