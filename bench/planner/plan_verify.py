"""Decisions against the FE's: `hapticrom plan --verify` on six layouts, one table.

    .venv/bin/python bench/planner/plan_verify.py [--top 5] [--model models/nn-default]

The layouts: examples/forearm-layout.toml, examples/thigh-layout.toml and
bench/planner/layouts/{square,hex,free,thick-fat}.toml.
For each, the plan (``planner.plan_layout``) and its FE re-plan of the surrogate's top K
candidates (``hapticrom.commands.plan_verify.verify_plan``: each candidate's scene built from
the model's training space and solved with the FE, judged and re-ranked with the plan's own
criterion), as library calls from the repository root. Columns: the surrogate's winner and the
FE's (design at frequency), whether they agree, the winner's compared value (grids: the
nominal pitch [mm]; free positions: the worst load at the sites) by the surrogate and by the
FE and their difference (surrogate / FE - 1), whether the criterion holds at the FE field at
the planned pitch, the verdict (confirmed: same winner, within 2 %, criterion holds), the share
of the winner's leakage read beyond the model's profile (the log-slope extension; the plan's
``validity.profile.leakage_share_beyond_profile``) and the time of plan + FE re-plan [s].
Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from hapticrom.commands.plan_verify import verify_plan  # noqa: E402
from planner import load_layout, plan_layout  # noqa: E402
from planner.verify import DEFAULT_TOP  # noqa: E402

LAYOUTS = ("examples/forearm-layout.toml", "examples/thigh-layout.toml",
           "bench/planner/layouts/square.toml",
           "bench/planner/layouts/hex.toml", "bench/planner/layouts/free.toml",
           "bench/planner/layouts/thick-fat.toml")


def _value(x: float | None, free: bool) -> str:
    return "none" if x is None else f"{x:.3f}" if free else f"{x:.2f} mm"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--top", type=int, default=DEFAULT_TOP, help="candidates re-solved (K)")
    ap.add_argument("--model", default=None, help="plan on this harmonic model instead of "
                    "each layout's [model] path")
    args = ap.parse_args()
    os.chdir(ROOT)  # the layouts' model paths are relative to the repository root
    print(f"`plan --verify`, top {args.top} candidates re-solved with the FE"
          + (f", model {args.model}" if args.model else ""))
    print()
    print("| layout | surrogate winner | FE winner | agree? | compared | surrogate / FE / "
          "difference | criterion at FE | verdict | leakage beyond profile | time s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for path in LAYOUTS:
        t0 = time.perf_counter()
        req = load_layout(path)
        if args.model:
            req = replace(req, model=args.model)
        plan = plan_layout(req)
        if plan.best is None:
            print(f"| {path} | none feasible | | | | | | | | {time.perf_counter() - t0:.1f} |")
            continue
        v = verify_plan(plan, args.top)
        dt = time.perf_counter() - t0
        free = v["compared"] == "worst_load"
        w = v["fe_winner"]
        fe_win = "none" if w is None else f"{w['design']}, {w['frequency_hz']:g} Hz"
        c = v["candidates"][0]
        diff = "n/a" if v["rel_diff"] is None else f"{v['rel_diff']:+.1%}"
        load = v["fe"]["criterion_load_at_plan_pitch"]
        print(f"| {path} | {v['design']}, {v['frequency_hz']:g} Hz | {fe_win} | "
              f"{'yes' if v['winner_agrees'] else 'NO'} | "
              f"{'worst load' if free else 'pitch'} (top {v['top_k']}) | "
              f"{_value(c['surrogate']['value'], free)} / {_value(c['fe']['value'], free)} / "
              f"{diff} | {'holds' if v['holds'] else 'FAILS'} (load {load:.3f}) | "
              f"{'confirmed' if v['confirmed'] else 'refuted'} | {plan.best.beyond_profile:.0%} | "
              f"{dt:.1f} |")


if __name__ == "__main__":
    main()
