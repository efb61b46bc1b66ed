"""Factorisations and error estimates of the reduced-order sweep on the verification cases of
tests/fem/test_sweep_slow.py (the example scenes and 40 designs of the default space, 10 of
them lightly damped pogo units), 100-250 Hz at 1 Hz steps.

    python bench/fem/sweep_solve_counts.py                   # counts and estimates only
    python bench/fem/sweep_solve_counts.py --true-every 3    # + the true error, a table

With ``--true-every N`` every case is also solved directly (``fem.sweep.direct_sweep``, the
slow test's reference) at every N-th frequency of the band and at the frequency of the largest
estimate, and the table gives the largest true error (``fem.sweep.sweep_errors``: magnitudes
relative, phases in rad above 1 % of the quantity's largest) and its ratio to the estimate:
below 1 the estimate was conservative, above 1 it was not.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "tests" / "fem")]

import numpy as np  # noqa: E402
from sweep_cases import EXAMPLES, example, space_designs  # noqa: E402

from fem.sweep import direct_sweep, sweep, sweep_errors  # noqa: E402


def _true_error(res, scene, every: int) -> float:
    """Largest error of ``res`` against direct solves at every ``every``-th frequency and at
    the frequency of the largest estimate."""
    freqs = res.frequency_hz
    picks = set(range(0, freqs.size, every)) | {int(res.meta.get("worst_index", 0))}
    ref = direct_sweep(scene, freqs[sorted(picks)])
    return max(sweep_errors(res, ref).values())


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--true-every", type=int, default=0,
                    help="also the true error against direct solves at every N-th frequency")
    args = ap.parse_args()
    cases = [(name, example(name)) for name in EXAMPLES]
    cases += [(f"design {i}", s) for i, (_, s) in enumerate(space_designs(40, 10))]
    solves, estimates, walls, ratios = [], [], [], []
    for name, scene in cases:
        t = time.perf_counter()
        res = sweep(scene)
        walls.append(time.perf_counter() - t)
        solves.append(res.full_solves)
        estimates.append(res.error_estimate)
        line = (f"{name:34s} factorisations {res.full_solves}  back-solves "
                f"{res.meta['back_solves']:3d}  estimate {res.error_estimate:.2g}  "
                f"{walls[-1]:.2f} s")
        if args.true_every:
            true = _true_error(res, scene, args.true_every)
            ratios.append(true / res.error_estimate)
            line += f"  true {true:.2g}  true/estimate {ratios[-1]:.2f}"
        print(line, flush=True)
    print(f"{len(cases)} cases: factorisations {min(solves)}-{max(solves)} (median "
          f"{statistics.median(solves):g}; counts {dict(sorted(Counter(solves).items()))}), "
          f"largest estimate {max(estimates):.2g}, median wall {statistics.median(walls):.2f} s")
    if ratios:
        print(f"true/estimate: min {min(ratios):.2f}, median {statistics.median(ratios):.2f}, "
              f"max {max(ratios):.2f}; within [0.3, 1] on "
              f"{sum(0.3 <= r <= 1.0 for r in ratios)} of {len(ratios)} cases "
              f"({np.mean(np.asarray(ratios) > 1.0):.0%} not conservative)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
