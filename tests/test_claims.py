"""Every ledger row is a test: MATCH within tolerance, DIFFERS pinned by its explanation,
NOT_DERIVABLE names the missing input."""
import pytest

from cnclab import claims

LEDGER = claims.load()


@pytest.mark.parametrize("claim", LEDGER, ids=[c.claim_id for c in LEDGER])
def test_claim_holds(claim):
    res = claims.evaluate(claim)
    assert not res.error, f"{claim.claim_id} ({claim.computed_by}) raised: {res.error}"
    if claim.status == "MATCH":
        assert res.ok, (f"{claim.claim_id}: reproduced {res.reproduced} vs paper {claim.paper_value}"
                        f" (atol {claim.atol}, rtol {claim.rtol})")
    elif claim.status == "DIFFERS":
        assert not claim.holds_within(res.reproduced), (
            f"{claim.claim_id} is marked DIFFERS but the consistent value {res.reproduced} matches the "
            f"paper's {claim.paper_value}: make it MATCH")
        assert claim.holds_within(res.alt), (
            f"{claim.claim_id}: the explanation {claim.alt_computed_by} gives {res.alt}, not the printed "
            f"{claim.paper_value}")
    else:
        assert claim.missing_input.strip(), f"{claim.claim_id}: NOT_DERIVABLE must name the missing input"
        assert not claim.computed_by
