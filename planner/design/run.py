"""``planner.design.design``: the search end to end, on the run-time predictor only.

    req = load_design_request("examples/design-forearm.toml")
    outcome = design(req, seed=0)               # the search; outcome.winner, .history
    block = verify_search(outcome.evaluator, outcome.finalists, req.references, solve)

Steps: the request's drive frequencies (or the model's band at ``band_step_hz``, the
unreachable ones dropped by the plan's own check); the space on the plan's validity domain;
the reference units evaluated as the searched ones are; the search; the ranking (the score,
then the larger own amplitude; the first few with their timing checked, so every finalist is
playable: ``planner.design.evaluate``); with a calibrated tissue (``--tissue``), the finalists
re-ranked on their pitch over the person's posterior draws (:func:`planner.tissue.
posterior_pitch`: the pitch that holds at the posterior's 95 % bound, judged at the
criterion's basis); and the winner planned with timing, as ``hapticrom plan`` would, so the
layout it writes is playable.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from planner.design.evaluate import Evaluation, Evaluator
from planner.design.request import DesignRequest
from planner.design.search import run_search
from planner.design.space import DesignSpace
from planner.domain import build_domain
from planner.layout import LayoutError, LayoutRequest, short_repr
from planner.optimise import Plan
from planner.tissue import apply_tissue, posterior_pitch
from surrogate.runtime import load_predictor

__all__ = ["DesignOutcome", "band_frequencies", "design", "distinct", "model_domain",
           "pareto_front"]

FINALISTS_WITH_TISSUE = 5  # designs re-ranked over the posterior draws
DISTINCT = 0.1  # finalists differ by more than this share in some number (or a choice)


@dataclass
class DesignOutcome:
    """What the search found."""

    request: DesignRequest
    layout: LayoutRequest  # the request's layout with the frequencies and tissue applied
    space: DesignSpace
    evaluator: Evaluator
    search: dict[str, Any]
    ranking: list[Evaluation]  # feasible, perceptible designs, best first
    references: list[Evaluation]
    plan: Plan | None  # the winner and the references planned with timing (the layout out)
    wall_s: float = 0.0
    tissue: dict[str, Any] | None = None
    posterior: list[dict[str, Any]] = field(default_factory=list)

    @property
    def winner(self) -> Evaluation | None:
        return self.ranking[0] if self.ranking else None

    @property
    def finalists(self) -> list[Evaluation]:
        """The best ``verify_top`` designs, each distinct from those before it
        (:func:`distinct`: continuous moduli make near-copies of the winner)."""
        out: list[Evaluation] = []
        for e in self.ranking:
            if len(out) == self.request.verify_top:
                break
            if all(distinct(e.inputs, f.inputs) for f in out):
                out.append(e)
        return out

    @property
    def history(self) -> list[Evaluation]:
        return self.evaluator.history


def distinct(a: dict[str, Any], b: dict[str, Any], rel: float = DISTINCT) -> bool:
    """Whether two designs differ: in a discrete input, or by more than ``rel`` in a number
    the units use (the catalogue's neighbouring silicones differ by 18 % or more in modulus)."""
    n = a["n_rings"]
    if any(a[k] != b[k] for k in ("orientation", "attachment", "n_rings")):
        return True
    used = [f"ring_{k}_E_kPa" for k in range(1, n + 1)]
    used += ["ring_density_kg_m3", "ring_nu", "ring_loss_factor"] if n else []
    return any(abs(a[k] / b[k] - 1.0) > rel for k in used)


def band_frequencies(layout: LayoutRequest, step_hz: float) -> tuple[float, ...]:
    """Every ``step_hz`` of the harmonic model's frequency range (the plan then drops those
    the motor cannot reach)."""
    spec = {s.name: s for s in load_predictor(layout.model).specs}["frequency_hz"]
    lo, hi = float(spec.low), float(spec.high)  # type: ignore[arg-type]
    n = int(np.floor((hi - lo) / step_hz + 1e-9)) + 1
    return tuple(float(round(lo + k * step_hz, 6)) for k in range(n))


def pareto_front(evaluations: list[Evaluation]) -> list[int]:
    """Indices (into ``evaluations``) of the feasible designs no other beats on both the
    pitch (smaller) and the own centre amplitude (larger), by increasing pitch."""
    pts = sorted((e.pitch_mm, -e.center_um, i) for i, e in enumerate(evaluations)
                 if e.pitch_mm is not None)
    front, best_center = [], -np.inf
    for _, neg_c, i in pts:
        if -neg_c > best_center:
            front.append(i)
            best_center = -neg_c
    return front


def model_domain(layout: LayoutRequest) -> Any:
    """The validity domain of the request's harmonic model (a bad ``model.path`` is a
    LayoutError naming it)."""
    try:
        predictor = load_predictor(layout.model)
    except (OSError, ValueError) as err:
        raise LayoutError("model.path", f"model.path = {short_repr(layout.model)}: {err}"
                          ) from None
    return build_domain(predictor, layout.model)


def design(request: DesignRequest, seed: int | None = None, tissue: Any = None) -> DesignOutcome:
    """Search the request's space (module docstring); ``tissue`` a
    :class:`calibration.document.Tissue` (``--tissue``) or None."""
    t0 = time.perf_counter()
    req = request.with_seed(seed)
    layout = req.layout
    if req.band_step_hz is not None:
        layout = replace(layout, frequencies_hz=band_frequencies(layout, req.band_step_hz))
    if tissue is not None:
        layout = apply_tissue(layout, tissue)
    space = DesignSpace(req.space, model_domain(layout))
    ev = Evaluator(layout, space.key, space.describe, space.materials, req.search.perceptible)
    refs = ev.judge([p.inputs for p in req.references], 0, [p.name for p in req.references],
                    [p.materials for p in req.references]) if req.references else []
    s = req.search
    stats = run_search(space, ev, s.optimiser, s.budget, s.batch, s.seed)
    outcome = DesignOutcome(req, layout, space, ev, stats, [], refs, None)
    head = FINALISTS_WITH_TISSUE if tissue is not None else 1
    _check_finalists(outcome, lambda o: o.ranking[:head] + o.finalists)
    stats.update(timing_checks=ev.timing_checks, timing_wall_s=round(ev.timing_wall_s, 3))
    if tissue is not None and outcome.ranking:
        _rerank_posterior(outcome, tissue)
    if outcome.winner is not None:
        designs = [{"name": outcome.winner.name, "inputs": outcome.winner.inputs}]
        designs += [{"name": p.name, "inputs": p.inputs} for p in req.references]
        outcome.plan = ev.plan(designs, timing=layout.timing)
    outcome.wall_s = time.perf_counter() - t0
    return outcome


def _check_finalists(outcome: DesignOutcome, chosen: Any) -> None:
    """``outcome.ranking``: the feasible, felt designs not known to be unplayable, best
    first, those ``chosen(outcome)`` picks (the finalists) with their timing checked
    (:meth:`Evaluator.recheck`; a design found unplayable leaves the ranking)."""
    ev, perceptible = outcome.evaluator, outcome.request.search.perceptible
    while True:
        outcome.ranking = sorted((e for e in ev.history if e.feasible and
                                  e.playable is not False and
                                  (e.perceptible or not perceptible)),
                                 key=lambda e: (e.score, -e.center_low_um, e.order))
        unchecked = [e for e in chosen(outcome) if e.playable is None]
        if not unchecked:
            return
        for e in unchecked:
            ev.recheck(e)


def _rerank_posterior(outcome: DesignOutcome, tissue: Any) -> None:
    """The first finalists ranked on their pitch over the posterior draws (None: infeasible
    for some draw beyond the 95 % bound, ranked last); the others keep their order."""
    head = outcome.ranking[:FINALISTS_WITH_TISSUE]
    rows = []
    for e in head:
        plan = outcome.evaluator.plan([{"name": e.name, "inputs": e.inputs}])
        plan.best = next(c for c in plan.candidates if c.frequency_hz == e.frequency_hz)
        p = posterior_pitch(plan, tissue)
        rows.append({"design": e.name, "pitch_mm_at_point_estimate": e.pitch_mm, **(p or {})})
    order = sorted(range(len(head)), key=lambda i: (
        rows[i].get("pitch_95_for_plan_mm") is None,
        rows[i].get("pitch_95_for_plan_mm") or 0.0, i))
    outcome.ranking = [head[i] for i in order] + outcome.ranking[len(head):]
    outcome.posterior = [rows[i] for i in order]
    outcome.tissue = {"calibration": tissue.path, "point": dict(tissue.point),
                      "ranked_on": "pitch_95_for_plan_mm", "finalists": len(head)}
