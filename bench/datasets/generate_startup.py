"""Start-up of ``hapticrom generate``: seconds from the first line of Python to the first
sample handed to the execution backend (imports, space, planning, store), median of runs.

    .venv/bin/python bench/datasets/generate_startup.py [--runs 5] [--space FILE]

Each run is a fresh interpreter (so imports count) writing a new dataset in a temporary
directory; the run stops at the first submit. Target (issue 13): under 2 s.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

CHILD = r"""
import time
t0 = time.perf_counter()
import os, sys
import surrogate.data.backends as b
def first(self, *a, **k):
    print(f"{time.perf_counter() - t0:.4f}", flush=True)
    os._exit(0)
b.PoolBackend.submit = first
from hapticrom.cli import main
main(["generate", "--space", sys.argv[1], "--n", sys.argv[3], "--out", sys.argv[2],
      "--workers", "1", "--quiet"])
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--space", default=str(ROOT / "datasets" / "spaces" / "default.toml"))
    ap.add_argument("--n", type=int, default=4096, help="samples requested (default 4096, the "
                    "README's command)")
    args = ap.parse_args()
    times = []
    for i in range(args.runs):
        with tempfile.TemporaryDirectory() as tmp:
            out = subprocess.run([sys.executable, "-c", CHILD, args.space, f"{tmp}/d",
                                  str(args.n)],
                                 capture_output=True, text=True, cwd=ROOT, check=False)
            if out.returncode != 0 or not out.stdout.strip():
                sys.exit(f"run {i} failed: {out.stderr[-2000:]}")
            times.append(float(out.stdout.split()[-1]))
    med = statistics.median(times)
    print(f"generate start-up to the first dispatched sample: median {med:.2f} s "
          f"(min {min(times):.2f}, max {max(times):.2f}, {args.runs} runs, --n {args.n}; "
          "target < 2 s)")


if __name__ == "__main__":
    main()
