"""The FE check of a design search: the best few designs and the reference units re-solved
over their drive band, judged with the plan's own criterion, and whether the FE confirms the
winner.

The FE solve is not here (the planner never imports the solver): the caller passes a
:data:`BandSolve` that sweeps one unit over the drive frequencies and returns one
:class:`planner.verify.FeSolve` per frequency (the CLI sweeps with ``fem.sweep`` on the
model's training scene, ``hapticrom.commands.design_verify``). The decision is
:func:`planner.verify.rerank`'s, the one ``hapticrom plan --verify`` makes: the top designs
at every drive frequency form a plan whose candidates are ranked by the surrogate and
again on their FE fields; the winner is *confirmed* when the FE's best (design, frequency)
is the surrogate's, its pitch is within 2 % of the FE's, and the criterion holds on the FE
field at the planned pitch. Each unit is swept once (its frequencies share one reduced
model), whatever the number of its candidates.

The reference units (the paper's prototypes) are swept the same way; each one's *FE pitch*
is its smallest over the drive frequencies (the FE choosing the frequency), the same rule
as for the winner, so the two are compared under one criterion.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any

from planner.design.evaluate import Evaluation, Evaluator
from planner.optimise import DesignResult, Plan
from planner.verify import FeSolve, fe_judged, rerank

__all__ = ["BandSolve", "verify_search"]

#: (design inputs, ring silicones or None, drive frequencies [Hz]) -> one FE solve per frequency
BandSolve = Callable[[dict[str, Any], tuple[str, ...] | None, tuple[float, ...]],
                     list[FeSolve]]


class _Sweeps:
    """One FE sweep per unit (cached), read per frequency."""

    def __init__(self, solve: BandSolve, frequencies: tuple[float, ...]) -> None:
        self.solve, self.frequencies = solve, frequencies
        self.done: dict[str, list[FeSolve]] = {}
        self.wall_s: dict[str, float] = {}

    def of(self, name: str, inputs: dict[str, Any], materials: tuple[str, ...] | None
           ) -> list[FeSolve]:
        if name not in self.done:
            t0 = time.perf_counter()
            self.done[name] = self.solve(inputs, materials, self.frequencies)
            self.wall_s[name] = time.perf_counter() - t0
        return self.done[name]

    def at(self, name: str, inputs: dict[str, Any], materials: tuple[str, ...] | None,
           frequency_hz: float) -> FeSolve:
        return self.of(name, inputs, materials)[self.frequencies.index(frequency_hz)]


def _fe_best(plan: Plan, results: list[DesignResult], sweeps: _Sweeps, inputs: dict[str, Any],
             materials: tuple[str, ...] | None) -> dict[str, Any]:
    """A unit's FE pitch over its frequencies (the smallest; None when none holds)."""
    rows, best = [], None
    for r in results:
        fe = fe_judged(plan, r, sweeps.at(r.name, inputs, materials, r.frequency_hz))
        rows.append({"frequency_hz": r.frequency_hz,
                     "surrogate_pitch_mm": None if r.pitch_mm is None else round(r.pitch_mm, 3),
                     "fe_pitch_mm": None if fe.pitch_nominal_mm is None else
                     round(fe.pitch_nominal_mm, 3), "fe_center_um": round(fe.center_um, 4)})
        if fe.pitch_nominal_mm is not None and (best is None or fe.pitch_nominal_mm < best[0]):
            best = (fe.pitch_nominal_mm, r.frequency_hz)
    return {"fe_pitch_mm": None if best is None else round(best[0], 3),
            "fe_frequency_hz": None if best is None else best[1], "frequencies": rows}


def verify_search(evaluator: Evaluator, finalists: Sequence[Evaluation],
                  references: Sequence[Any], solve: BandSolve) -> dict[str, Any]:
    """The ``verify`` block: ``finalists`` (the winner first) and ``references``
    (:class:`planner.design.prototypes.Prototype`) solved by ``solve``."""
    if not finalists or not finalists[0].feasible:
        raise ValueError("verify: the search has no feasible winner to check")
    plan = evaluator.plan([{"name": e.name, "inputs": e.inputs} for e in finalists])
    winner = finalists[0]
    felt = {(e.name, row["frequency_hz"]) for e in finalists for row in e.per_frequency
            if row["perceptible"] or not evaluator.perceptible}
    plan.candidates = [c for c in plan.candidates if (c.name, c.frequency_hz) in felt]
    best = next(c for c in plan.candidates
                if c.name == winner.name and c.frequency_hz == winner.frequency_hz)
    plan = replace(plan, best=best)
    freqs = tuple(sorted({c.frequency_hz for c in plan.candidates}))
    sweeps = _Sweeps(solve, freqs)
    by_name = {e.name: e for e in finalists}

    def solve_one(r: DesignResult) -> FeSolve:
        e = by_name[r.name]
        return sweeps.at(r.name, e.inputs, e.materials, r.frequency_hz)

    feasible = [c for c in plan.candidates if c.pitch_mm is not None]
    block = rerank(plan, len(feasible), solve_one)
    designs = []
    for e in finalists:
        results = [c for c in plan.candidates if c.name == e.name]
        designs.append({"design": e.name, "surrogate_pitch_mm": round(e.pitch_mm or 0, 3),
                        "surrogate_frequency_hz": e.frequency_hz,
                        **_fe_best(plan, results, sweeps, e.inputs, e.materials)})
    refs = []
    if references:
        ref_plan = evaluator.plan([{"name": p.name, "inputs": p.inputs} for p in references])
        for p in references:
            results = [c for c in ref_plan.candidates if c.name == p.name]
            refs.append({"design": p.name, "scene": p.path,
                         **_fe_best(ref_plan, results, sweeps, p.inputs, p.materials)})
    block["designs"] = designs
    block["references"] = refs
    block["target"] = _target(designs[0], refs)
    block["sweep_wall_s"] = {k: round(v, 2) for k, v in sweeps.wall_s.items()}
    block["fe_check_wall_s"] = round(sum(sweeps.wall_s.values()), 2)
    return block


def _target(winner: dict[str, Any], refs: list[dict[str, Any]]) -> dict[str, Any]:
    """The winner's FE pitch against the best reference's, under the same criterion."""
    held = [r for r in refs if r["fe_pitch_mm"] is not None]
    best = min(held, key=lambda r: r["fe_pitch_mm"]) if held else None
    w = winner["fe_pitch_mm"]
    out: dict[str, Any] = {"winner_fe_pitch_mm": w,
                           "best_reference": None if best is None else best["design"],
                           "best_reference_fe_pitch_mm": None if best is None else
                           best["fe_pitch_mm"]}
    if w is None or best is None:
        out["met"] = best is None and w is not None
        out["rel_diff"] = None
    else:
        out["met"] = w < best["fe_pitch_mm"]
        out["rel_diff"] = round(w / best["fe_pitch_mm"] - 1.0, 4)
    return out
