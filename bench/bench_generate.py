"""Dataset generation throughput: samples per minute on 1 and 2 worker processes.

    python bench/bench_generate.py                       # default space, default mesh
    python bench/bench_generate.py --n 64 --coarse       # coarse mesh: runner overhead regime
    python bench/bench_generate.py --workers 1 2 4 --space datasets/spaces/transient.toml

Each run generates ``--n`` samples of the space into a fresh temporary dataset through the
public ``surrogate.data.generate.generate`` (process pool, Parquet parts, manifest: the real path).
Reported per worker count: wall time of the run (worker start-up included), samples per
minute, the mean solver time per sample (``wall_s`` column) and the parallel efficiency
rate(w) / (w * rate(1)). No assertions: numbers go into the README.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

COARSE_MESH = {"near_size_mm": 1.0, "far_size_mm": 4.0, "order": 1}


def _space(path: Path, coarse: bool):
    from surrogate.data.space import load_space, space_from_dict

    space = load_space(path)
    if not coarse:
        return space
    d = space.to_dict()
    d["base"].setdefault("mesh", {}).update(COARSE_MESH)
    d["base"].setdefault("tissue", {})["radius_mm"] = 30.0
    return space_from_dict(d)


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print a table."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--space", type=Path, default=ROOT / "datasets" / "spaces" / "default.toml")
    p.add_argument("--n", type=int, default=16, help="samples per run (default 16)")
    p.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    p.add_argument("--coarse", action="store_true",
                   help="coarse mesh (1/4 mm, linear, 30 mm radius): measures the runner")
    args = p.parse_args(argv)

    import pandas as pd

    from surrogate.data.generate import generate, plan_samples

    space = _space(args.space, args.coarse)
    t0 = time.perf_counter()
    plan_samples(space, args.n)
    plan_s = time.perf_counter() - t0
    mesh = space.defaults.get("mesh", {})
    print(f"# hapticrom generate benchmark: space {space.name!r} ({args.space.name}), "
          f"{args.n} samples per run")
    print(f"# mesh near {mesh.get('near_size_mm')} mm / far {mesh.get('far_size_mm')} mm / "
          f"order {mesh.get('order')}{' (coarse)' if args.coarse else ''}; "
          f"{os.cpu_count()} cores, {platform.processor() or platform.machine()}, "
          f"python {platform.python_version()}")
    print(f"# planning (resolve + validate + hash {args.n} scenes): {plan_s * 1e3:.0f} ms")
    print(f"{'workers':>7} {'samples':>7} {'wall_s':>8} {'samples/min':>12} "
          f"{'solve_s/sample':>15} {'dofs':>7} {'failed':>6} {'efficiency':>10}")
    base_rate = None
    for w in args.workers:
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "ds"
            t0 = time.perf_counter()
            rep = generate(space, args.n, out, workers=w, progress=False)
            wall = time.perf_counter() - t0
            df = pd.read_parquet(out)
        rate = 60.0 * args.n / wall
        base_rate = base_rate or rate / w
        print(f"{w:>7} {args.n:>7} {wall:>8.2f} {rate:>12.1f} {df['wall_s'].mean():>15.3f} "
              f"{int(df['dofs'].median()) if df['dofs'].notna().any() else 0:>7} "
              f"{rep.new_failed:>6} {rate / (w * base_rate):>10.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
