"""Factorisations and error estimates of the reduced-order sweep on the verification cases of
tests/fem/test_sweep_slow.py (the example scenes and 40 designs of the default space, 10 of
them lightly damped pogo units), 100-250 Hz at 1 Hz steps; no direct solves (the slow test
compares those).

    python bench/fem/sweep_solve_counts.py
"""

from __future__ import annotations

import statistics
import sys
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "tests" / "fem")]

from sweep_cases import EXAMPLES, example, space_designs  # noqa: E402

from fem.sweep import sweep  # noqa: E402


def main() -> int:
    cases = [(name, example(name)) for name in EXAMPLES]
    cases += [(f"design {i}", s) for i, (_, s) in enumerate(space_designs(40, 10))]
    solves, estimates, walls = [], [], []
    for name, scene in cases:
        t = time.perf_counter()
        res = sweep(scene)
        walls.append(time.perf_counter() - t)
        solves.append(res.full_solves)
        estimates.append(res.error_estimate)
        print(f"{name:34s} factorisations {res.full_solves}  back-solves "
              f"{res.meta['back_solves']:3d}  estimate {res.error_estimate:.2g}  "
              f"{walls[-1]:.2f} s", flush=True)
    print(f"{len(cases)} cases: factorisations {min(solves)}-{max(solves)} (median "
          f"{statistics.median(solves):g}; counts {dict(sorted(Counter(solves).items()))}), "
          f"largest estimate {max(estimates):.2g}, median wall {statistics.median(walls):.2f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
