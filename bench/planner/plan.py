"""Planning time: the whole `hapticrom plan` command and the in-process optimiser, 4x4 and 8x8.

    .venv/bin/python bench/planner/plan.py [--repeat 5]

Uses examples/forearm-layout.toml (3 designs x 3 frequencies on its default harmonic model) with
the array size replaced, under the ratio criterion and the perceptual one (detection
threshold, planner.threshold); prints medians. The command (``python -m hapticrom.cli plan``,
this checkout's code) includes interpreter start-up, imports and the envelope timing of the
chosen unit on the transient ROM (when its frequency is within the motor's drive limit),
which is what a user waits for.
"""

from __future__ import annotations

import argparse
import itertools
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from planner import layout_from_dict, plan_layout

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "forearm-layout.toml"


def main() -> None:
    import tomllib

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    print(f"{'criterion':10s} {'array':6s} {'command s':>10s} {'plan_layout s':>14s} "
          f"{'pitch mm':>9s} {'timing':>7s}")
    for kind, n in itertools.product(("ratio", "perceptual"), (4, 8)):
        text = EXAMPLE.read_text().replace("rows = 4 ", f"rows = {n} ").replace(
            "cols = 4 ", f"cols = {n} ")
        if kind == "perceptual":
            text = text.replace('kind = "ratio"', 'kind = "perceptual"')
        with tempfile.TemporaryDirectory() as tmp:
            layout = Path(tmp) / "layout.toml"
            layout.write_text(text)
            runs = []
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                subprocess.run([sys.executable, "-m", "hapticrom.cli", "plan", str(layout)],
                               cwd=ROOT, check=True, capture_output=True)
                runs.append(time.perf_counter() - t0)
        req = layout_from_dict(tomllib.loads(text))
        inproc = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            plan = plan_layout(req)
            inproc.append(time.perf_counter() - t0)
        timed = "no" if plan.timing is None or plan.timing.get("unavailable") else "yes"
        print(f"{kind:10s} {n}x{n:<4d} {statistics.median(runs):10.2f} "
              f"{statistics.median(inproc):14.3f} {plan.best.pitch_mm:9.2f} {timed:>7s}")


if __name__ == "__main__":
    main()
