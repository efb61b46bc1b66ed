"""Count the outcomes of a scene fuzz run (the property test of tests/fem/test_fuzz.py).

    .venv/bin/python bench/fem/fuzz_scenes.py [--n 1000] [--max-unknowns 50000] [--seed 0]

Prints how many mutated scenes were rejected by validation, refused by the cost check, and
solved to finite values. Any other outcome (another exception, a non-finite result, a solve
above the limit) stops the run with the failing scene, as the test does.
"""

from __future__ import annotations

import argparse
import collections
import copy
import sys
import time
from pathlib import Path

from hypothesis import HealthCheck, given, seed, settings

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests" / "fem"))
from test_fuzz import BASES, _set, cases, outcome


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--max-unknowns", type=float, default=50_000)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    counts: collections.Counter[str] = collections.Counter()

    @seed(args.seed)
    @settings(max_examples=args.n, deadline=None, database=None,
              suppress_health_check=list(HealthCheck))
    @given(cases(list(BASES)))
    def run(case):
        base, changes = case
        d = copy.deepcopy(BASES[base])
        for path, value in changes:
            _set(d, path, value)
        counts[outcome(d, args.max_unknowns)] += 1
        counts[f"base {base}"] += 1

    t0 = time.perf_counter()
    run()
    total = sum(v for k, v in counts.items() if not k.startswith("base"))
    print(f"{total} scenes in {time.perf_counter() - t0:.0f} s (hypothesis may run a few more "
          "than --n while it shrinks nothing)")
    for key in ("invalid", "refused", "solved"):
        print(f"  {key:8s} {counts[key]}")
    print("  other    0 (any other outcome stops the run)")
    print("  bases: " + ", ".join(f"{k[5:]} {v}" for k, v in sorted(counts.items())
                                   if k.startswith("base")))


if __name__ == "__main__":
    main()
