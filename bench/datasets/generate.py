"""Dataset generation throughput: samples per minute on 1 and 2 worker processes.

    python bench/datasets/generate.py                       # default space, default mesh
    python bench/datasets/generate.py --n 64 --coarse       # coarse mesh: runner overhead regime
    python bench/datasets/generate.py --workers 1 2 4 --space datasets/spaces/transient.toml
    python bench/datasets/generate.py --n 256 --compare --repeats 2   # topology grouping on/off
    python bench/datasets/generate.py --n 256 --mesh-topology per_design   # one mesh per design
    python bench/datasets/generate.py --sweep-space --workers 2             # sweeps side by side

Each run generates ``--n`` samples of the space into a fresh temporary dataset through the
public ``surrogate.data.generate.generate`` (process pool, Parquet parts, manifest: the real path).
Reported per worker count: wall time of the run (worker start-up included), samples per
minute, the mean solver time per sample (``wall_s`` column) and the parallel efficiency
rate(w) / (w * rate(1)). No assertions: numbers go into the README.

``--sweep-space [TOML]`` (default ``datasets/spaces/default-sweep.toml``) runs, per worker
count, the single-frequency space and the sweep space (``--sweep-n`` designs, default
``--n``) one after the other and reports both in design-frequency answers per minute: a
single-frequency sample is one answer, a sweep design is one answer per frequency of its band.
The sweep rows also give the mean full solves per design and the largest error estimate.

``--compare`` runs every worker count with the dispatch grouped by mesh topology
(``surrogate.data.generate.GROUP_BY_TOPOLOGY``) and in plan order, alternately, ``--repeats``
times, and counts in the workers how many scatter maps each sample built (0: every map came
from the per-process cache): the medians and the grouped/plan-order speed-up are printed.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

COARSE_MESH = {"near_size_mm": 1.0, "far_size_mm": 4.0, "order": 1}
#: Directory the workers of a --compare run append their per-sample map build counts to.
COUNTS_ENV = "HAPTICROM_BENCH_MAP_COUNTS"
_builds = [0]


def _count_builds() -> None:
    """In a worker: count fem.assembly.ScatterMap builds (once per process)."""
    import fem.assembly as fa

    if getattr(fa.ScatterMap.build, "_bench_counting", False):
        return
    real = fa.ScatterMap.build

    def build(cls, *args, **kwargs):
        _builds[0] += 1
        return real(*args, **kwargs)

    build._bench_counting = True
    fa.ScatterMap.build = classmethod(build)


def counting_run_chunk(payload: str) -> str:
    """``surrogate.data.worker.run_chunk`` one sample at a time, appending the number of scatter
    maps each sample built to a file of this worker process (spawned workers import this
    script as their ``__main__``)."""
    from surrogate.data.worker import run_chunk

    _count_builds()
    rows, solver = [], None
    with open(Path(os.environ[COUNTS_ENV]) / f"{os.getpid()}.txt", "a") as log:
        for scene in json.loads(payload):
            before = _builds[0]
            reply = json.loads(run_chunk(json.dumps([scene])))
            solver = reply["solver"]
            rows += reply["rows"]
            log.write(f"{_builds[0] - before}\n")
    return json.dumps({"solver": solver, "rows": rows})


def _run(space, n: int, workers: int, grouped: bool) -> dict:
    """One generate run into a fresh dataset: wall [s], rate, mean solve time, map counts."""
    import surrogate.data.backends as backends
    import surrogate.data.generate as gen
    from surrogate.data.store import Store

    with tempfile.TemporaryDirectory() as tmp:
        counts = Path(tmp) / "counts"
        counts.mkdir()
        os.environ[COUNTS_ENV] = str(counts)
        saved = gen.GROUP_BY_TOPOLOGY, backends.run_chunk
        gen.GROUP_BY_TOPOLOGY, backends.run_chunk = grouped, counting_run_chunk
        try:
            t0 = time.perf_counter()
            rep = gen.generate(space, n, Path(tmp) / "ds", workers=workers, progress=False)
            wall = time.perf_counter() - t0
        finally:
            gen.GROUP_BY_TOPOLOGY, backends.run_chunk = saved
        df = Store.open(Path(tmp) / "ds").read()
        built = [int(x) for f in counts.iterdir() for x in f.read_text().split()]
    return {"wall": wall, "rate": 60.0 * n / wall, "solve": float(df["wall_s"].mean()),
            "failed": rep.new_failed, "maps": sum(built),
            "reused": sum(b == 0 for b in built), "counted": len(built)}


def compare(space, n: int, workers: list[int], repeats: int) -> None:
    """Grouped vs plan-order dispatch, alternating, medians per worker count."""
    import numpy as np

    print(f"{'workers':>7} {'dispatch':>10} {'wall_s':>8} {'samples/min':>12} "
          f"{'solve_s/sample':>15} {'maps built':>10} {'all reused':>10}")
    runs: dict[tuple[int, bool], list[dict]] = {}
    for r in range(repeats):
        for w in workers:
            for grouped in ((True, False) if r % 2 else (False, True)):
                res = _run(space, n, w, grouped)
                runs.setdefault((w, grouped), []).append(res)
                print(f"{w:>7} {'topology' if grouped else 'plan':>10} {res['wall']:>8.2f} "
                      f"{res['rate']:>12.1f} {res['solve']:>15.3f} {res['maps']:>10} "
                      f"{res['reused']:>7}/{res['counted']:<3}", flush=True)
    print("# medians")
    for w in workers:
        med = {g: {k: float(np.median([x[k] for x in runs[(w, g)]])) for k in runs[(w, g)][0]}
               for g in (False, True)}
        for g in (False, True):
            m = med[g]
            print(f"{w:>7} {'topology' if g else 'plan':>10} {m['wall']:>8.2f} "
                  f"{m['rate']:>12.1f} {m['solve']:>15.3f} {m['maps']:>10.0f} "
                  f"{m['reused']:>7.0f}/{n:<3}")
        print(f"# {w} worker(s): grouped/plan-order wall ratio "
              f"{med[True]['wall'] / med[False]['wall']:.3f}, mean solve time ratio "
              f"{med[True]['solve'] / med[False]['solve']:.3f}")


def _space(path: Path, coarse: bool, mesh_topology: str | None):
    from surrogate.data.space import load_space, space_from_dict

    space = load_space(path)
    if not coarse and mesh_topology is None:
        return space
    d = space.to_dict()
    if coarse:
        d["base"].setdefault("mesh", {}).update(COARSE_MESH)
        d["base"].setdefault("tissue", {})["radius_mm"] = 30.0
    if mesh_topology is not None:
        d["space"]["mesh_topology"] = mesh_topology
    return space_from_dict(d)


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print a table."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--space", type=Path, default=ROOT / "datasets" / "spaces" / "default.toml")
    p.add_argument("--n", type=int, default=16, help="samples per run (default 16)")
    p.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    p.add_argument("--coarse", action="store_true",
                   help="coarse mesh (1/4 mm, linear, 30 mm radius): measures the runner")
    p.add_argument("--compare", action="store_true",
                   help="topology-grouped vs plan-order dispatch, alternating, with map counts")
    p.add_argument("--repeats", type=int, default=2, help="runs per variant with --compare")
    p.add_argument("--mesh-topology", choices=("per_sample", "per_design"), default=None,
                   help="override the space's mesh_topology (surrogate.data.mesh_plan)")
    p.add_argument("--sweep-space", type=Path, nargs="?", default=None,
                   const=ROOT / "datasets" / "spaces" / "default-sweep.toml",
                   help="also generate this sweep space and compare answers per minute")
    p.add_argument("--sweep-n", type=int, default=None,
                   help="designs per sweep run (default --n)")
    args = p.parse_args(argv)

    from surrogate.data.generate import plan_samples

    space = _space(args.space, args.coarse, args.mesh_topology)
    t0 = time.perf_counter()
    plan_samples(space, args.n)
    plan_s = time.perf_counter() - t0
    mesh = space.defaults.get("mesh", {})
    print(f"# hapticrom generate benchmark: space {space.name!r} ({args.space.name}), "
          f"{args.n} samples per run, mesh_topology {space.mesh_topology}")
    print(f"# mesh near {mesh.get('near_size_mm')} mm / far {mesh.get('far_size_mm')} mm / "
          f"order {mesh.get('order')}{' (coarse)' if args.coarse else ''}; "
          f"{os.cpu_count()} cores, {platform.processor() or platform.machine()}, "
          f"python {platform.python_version()}")
    print(f"# planning (resolve + validate + hash {args.n} scenes): {plan_s * 1e3:.0f} ms")
    if args.compare:
        compare(space, args.n, args.workers, args.repeats)
        return 0
    if args.sweep_space is not None:
        sweeps(space, _space(args.sweep_space, args.coarse, args.mesh_topology), args.n,
               args.sweep_n or args.n, args.workers)
        return 0
    print(f"{'workers':>7} {'samples':>7} {'wall_s':>8} {'samples/min':>12} "
          f"{'solve_s/sample':>15} {'dofs':>7} {'failed':>6} {'efficiency':>10}")
    base_rate = None
    for w in args.workers:
        run = _generate(space, args.n, w)
        df, rate = run["df"], run["rate"]
        base_rate = base_rate or rate / w
        print(f"{w:>7} {args.n:>7} {run['wall']:>8.2f} {rate:>12.1f} "
              f"{df['wall_s'].mean():>15.3f} "
              f"{int(df['dofs'].median()) if df['dofs'].notna().any() else 0:>7} "
              f"{run['failed']:>6} {rate / (w * base_rate):>10.2f}")
    return 0


def _generate(space, n: int, workers: int) -> dict:
    """One generate run into a fresh temporary dataset: wall [s], rows, samples/min."""
    from surrogate.data.generate import generate
    from surrogate.data.store import Store

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "ds"
        t0 = time.perf_counter()
        rep = generate(space, n, out, workers=workers, progress=False)
        wall = time.perf_counter() - t0
        df = Store.open(out).read()
        size = sum(p.stat().st_size for p in Store.open(out).parts())
    return {"wall": wall, "rate": 60.0 * n / wall, "df": df, "failed": rep.new_failed,
            "bytes_per_row": size / max(len(df), 1)}


def sweeps(single, sweep, n: int, n_sweep: int, workers: list[int]) -> None:
    """Single-frequency and sweep generation side by side, in answers per minute."""

    n_f = len(sweep.band.frequencies_hz)
    print(f"# sweep space {sweep.name!r}: {n_f} frequencies "
          f"{sweep.band.start:g}-{sweep.band.stop:g} Hz every {sweep.band.step:g} Hz")
    print(f"{'workers':>7} {'kind':>7} {'rows':>5} {'wall_s':>8} {'rows/min':>9} "
          f"{'answers/min':>12} {'solve_s/row':>12} {'full solves':>11} {'max est.':>9} "
          f"{'kB/row':>7} {'failed':>6}")
    for w in workers:
        for kind, space, count in (("single", single, n), ("sweep", sweep, n_sweep)):
            run = _generate(space, count, w)
            df = run["df"]
            ok = df[df["status"] == "ok"]
            per = n_f if kind == "sweep" else 1
            solves = (f"{ok['sweep_full_solves'].mean():>11.2f}" if kind == "sweep"
                      else f"{'1':>11}")
            est = (f"{ok['sweep_error_estimate'].max():>9.1e}" if kind == "sweep"
                   else f"{'-':>9}")
            print(f"{w:>7} {kind:>7} {count:>5} {run['wall']:>8.2f} {run['rate']:>9.1f} "
                  f"{run['rate'] * per:>12.0f} {df['wall_s'].mean():>12.3f} {solves} {est} "
                  f"{run['bytes_per_row'] / 1e3:>7.1f} {run['failed']:>6}", flush=True)


if __name__ == "__main__":
    sys.exit(main())
