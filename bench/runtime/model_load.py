"""Time to load each shipped model with the run-time loaders (the whole integrity check
included): median of 15 loads after one warm-up.

    .venv/bin/python bench/runtime/model_load.py
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from surrogate.runtime import load_envelope_model, load_predictor  # noqa: E402


def main() -> None:
    for name in ("gp-default", "nn-default", "rom-default"):
        path = ROOT / "models" / name
        load = load_envelope_model if name.startswith("rom") else load_predictor
        load(path)
        times = []
        for _ in range(15):
            t0 = time.perf_counter()
            load(path)
            times.append(time.perf_counter() - t0)
        print(f"{name:12s} load median {1e3 * statistics.median(times):.1f} ms")


if __name__ == "__main__":
    main()
