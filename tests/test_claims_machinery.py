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


def test_cli_json_keys():
    out = subprocess.run([sys.executable, "-m", "cnclab", "claims", "--json", "--skip-slow"],
                         capture_output=True, text=True, check=False)
    rows = json.loads(out.stdout)
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

    monkeypatch.setenv("CNCLAB_BUILD_DIR", str(tmp_path))
    fig, ax = plt.subplots()
    ax.plot([0, 1], [1, 0])
    paths = savefig(fig, "t_fig", "hoang2024")
    assert {p.suffix for p in paths} == {".pdf", ".svg", ".png"}
    assert all(p.parent == tmp_path / "figures" / "hoang2024" and p.stat().st_size > 0 for p in paths)
    with pytest.raises(ValueError):
        savefig(fig, "../escape", "hoang2024")
    with pytest.raises(ValueError):
        savefig(fig, "ok", "nowork")
    plt.close(fig)
