"""Random-pocket fuzz, the long run: the generator of the property test
``tests/test_adaptive_clearing.py::test_random_pockets_are_safe_covered_and_bounded`` (Hypothesis
``pockets()``: stars of 5-8 rays and unions of 1-3 boxes, an island in half of them; theta 45 or
60 deg; R 1.5 mm, planning pixel 0.05 mm) with many more examples and any seed, every pocket planned by
the default planner and scored by the evaluator, with the test's bounds.

    python benchmarks/fuzz_random_pockets.py --examples 300 --seed 1 --out /tmp/fuzz/pockets.jsonl

One JSON line per pocket (WKT, theta, status, uncut beyond the unreachable corners, the test's
allowance and its parts, plunges, rapids into material, engagement max, wall gouge); at the end the
counts: planned, refused, and failing each bound -- ``base`` (1 % + 1 mm^2, no corners), ``corners``
(+ the corner allowance, capped at the unreachable area), ``full`` (+ the slot-only area: what the
test asserts). ``--slot-narrow``: plan with ``AdaptiveParams(slot_narrow=True)`` (the thin strips cut
by slotting: then ``corners`` is the bound that matters and the engagement bound does not hold).
Not a test (about 1 s a pocket).
"""
from __future__ import annotations

import argparse
import collections
import json
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hypothesis import HealthCheck, Phase, given, seed, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import tests.test_adaptive_clearing as T  # noqa: E402
from cnclab.toolpath.adaptive import AdaptiveParams, PlanningError, adaptive_clearing  # noqa: E402
from cnclab.toolpath.evaluate import evaluate, unreachable_region  # noqa: E402


def score(poly, theta, slot_narrow=False) -> dict:
    rec = {"wkt": poly.wkt, "theta": theta, "area": poly.area}
    if not poly.is_valid or poly.buffer(-T.R).is_empty:
        return rec | {"status": "invalid or no room for the tool"}
    try:
        tp = adaptive_clearing(T._job(poly, theta, source="hypothesis"), AdaptiveParams(slot_narrow=slot_narrow),
                               resolution_mm=T.H, step_mm=0.05)
    except PlanningError as exc:
        return rec | {"status": "refused", "msg": str(exc)[:300]}
    except Exception as exc:                      # a crash: counted, the run goes on
        return rec | {"status": "error", "msg": f"{type(exc).__name__}: {exc}"[:300]}
    s = evaluate(tp, T._job(poly, theta), T.H)
    corners = min(T._corner_allowance_mm2(poly), unreachable_region(poly, T.R).area)
    eng_bound = theta + 10 + 2 * math.degrees(T.H / (T.R * math.sin(math.radians(theta))))
    return rec | {"status": "planned", "uncut": s.uncut_beyond_unreachable_mm2, "base": 0.01 * poly.area + 1.0,
                  "corners": corners, "slot_only": T._slot_only_mm2(poly), "plunges": s.plunges_into_material,
                  "rapids": s.rapids_into_material, "engagement_max": s.engagement_max_deg,
                  "engagement_bound": eng_bound, "gouge": T._wall_gouge(tp, poly)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--examples", type=int, default=300)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--family", choices=("pockets", "stars"), default="pockets")
    ap.add_argument("--slot-narrow", action="store_true", help="AdaptiveParams(slot_narrow=True)")
    ap.add_argument("--out", type=Path, required=True)
    a = ap.parse_args(argv)
    gen = T.pockets() if a.family == "pockets" else T.star_pockets()
    counts = collections.Counter()

    with open(a.out, "a") as log:
        @settings(max_examples=a.examples, deadline=None, database=None, suppress_health_check=list(HealthCheck),
                  phases=[Phase.generate])
        @seed(a.seed)
        @given(gen, st.sampled_from([45.0, 60.0]))
        def run(poly, theta):
            t0 = time.perf_counter()
            rec = score(poly, theta, a.slot_narrow)
            rec["t_s"] = round(time.perf_counter() - t0, 3)
            counts[rec["status"]] += 1
            if rec["status"] == "planned":
                u = rec["uncut"]
                counts["fail base"] += u > rec["base"]
                counts["fail corners"] += u > rec["base"] + rec["corners"]
                counts["fail full"] += u > rec["base"] + rec["corners"] + rec["slot_only"]
                counts["unsafe"] += bool(rec["plunges"] or rec["rapids"] or rec["gouge"] > 1e-3)
                counts["engagement over"] += rec["engagement_max"] > rec["engagement_bound"]
                counts["has slot-only area"] += rec["slot_only"] > 0
            log.write(json.dumps(rec) + "\n")
            log.flush()

        run()
    print(dict(counts))
    return 0


if __name__ == "__main__":
    sys.exit(main())
