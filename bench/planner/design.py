"""The unit search: each optimiser against the exhaustive grid of the same evaluations.

    .venv/bin/python bench/planner/design.py [--request examples/design-forearm.toml]
        [--seeds 0 1 2] [--methods de cmaes tpe] [--budget 200] [--materials catalogue]

The request's space (default: the forearm example's, 6 catalogue silicones, 1036 designs) is
first evaluated whole (``grid``: every design, the known optimum); then each optimiser runs
with the budget for every seed, on a fresh evaluator (no cache shared). Per run: distinct
designs evaluated, points the optimiser asked for (repeats included), wall time (search and
the evaluations in it), the best pitch found, its rank in the grid (1 = the grid's optimum),
and how many evaluations it took to reach the grid's optimum (``-`` if it never did). The
summary gives each method's median and worst (max) over the seeds. The FE check is not part
of this bench (``hapticrom design`` times it: ``fe_check_wall_s`` in design.json).
"""

from __future__ import annotations

import argparse
import statistics
import time
from dataclasses import replace
from pathlib import Path

from planner.design.evaluate import Evaluator
from planner.design.request import load_design_request
from planner.design.run import model_domain
from planner.design.search import run_search
from planner.design.space import DesignSpace

ROOT = Path(__file__).resolve().parents[2]


def _run(req, space, method: str, budget: int, seed: int) -> dict:
    ev = Evaluator(req.layout, space.key, space.describe, space.materials,
                   req.search.perceptible)
    t0 = time.perf_counter()
    stats = run_search(space, ev, method, budget, req.search.batch, seed)
    wall = time.perf_counter() - t0
    scores = [e.score for e in ev.history]
    return {"method": method, "seed": seed, "unique": ev.unique, "wall_s": wall,
            "asked": stats["points_asked"],
            "eval_s": stats["evaluation_wall_s"], "best": min(scores), "scores": scores}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--request", default=str(ROOT / "examples" / "design-forearm.toml"))
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--methods", nargs="+", default=["de", "cmaes", "tpe"])
    ap.add_argument("--budget", type=int, default=200)
    ap.add_argument("--materials", choices=("catalogue", "continuous"), default=None)
    args = ap.parse_args()
    req = load_design_request(args.request)
    if args.materials:
        req = replace(req, space=replace(req.space, materials=args.materials))
    space = DesignSpace(req.space, model_domain(req.layout))
    grid = _run(req, space, "grid", 0, 0)
    ranked = sorted(grid["scores"])
    optimum = ranked[0]
    print(f"space: {req.space.materials}, {grid['unique']} designs; grid: {grid['wall_s']:.1f} s "
          f"({grid['eval_s']:.1f} s evaluating), optimum {optimum:.3f} mm")
    print(f"{'method':7s} {'seed':>4s} {'designs':>7s} {'asked':>6s} {'wall s':>7s} {'eval s':>7s} "
          f"{'best mm':>8s} {'rank':>5s} {'to optimum':>10s}")
    rows: dict[str, list[dict]] = {}
    for method in args.methods:
        for seed in args.seeds:
            r = _run(req, space, method, args.budget, seed)
            r["rank"] = 1 + sum(s < r["best"] - 1e-9 for s in ranked)
            hit = [i for i, s in enumerate(r["scores"]) if s <= optimum + 1e-9]
            r["to_optimum"] = hit[0] + 1 if hit else None
            rows.setdefault(method, []).append(r)
            print(f"{method:7s} {seed:4d} {r['unique']:7d} {r['asked']:6d} {r['wall_s']:7.1f} "
                  f"{r['eval_s']:7.1f} "
                  f"{r['best']:8.3f} {r['rank']:5d} "
                  f"{'-' if r['to_optimum'] is None else r['to_optimum']:>10}")
    print("summary (median / worst over seeds): wall s, rank, evaluations to the optimum")
    for method, rs in rows.items():
        walls = [r["wall_s"] for r in rs]
        ranks = [r["rank"] for r in rs]
        hits = [r["to_optimum"] for r in rs]
        found = [h for h in hits if h is not None]
        print(f"  {method:7s} wall {statistics.median(walls):6.1f} / {max(walls):6.1f}; rank "
              f"{statistics.median(ranks):g} / {max(ranks)}; optimum found in {len(found)} of "
              f"{len(rs)} runs" + (f", after {statistics.median(found):g} / {max(found)} "
                                   "evaluations" if found else ""))
    print(f"  grid    wall {grid['wall_s']:6.1f}; {grid['unique']} evaluations")


if __name__ == "__main__":
    main()
