"""``hapticrom plan --verify``: the surrogate's top candidates judged again on FE fields,
re-ranked, and whether the FE makes the same decision.

The FE solve itself is not here (the planner never imports the solver): the caller passes a
``solve`` function that gives each candidate's FE field (:class:`FeSolve`; the CLI builds the
scene from the model's training space, ``hapticrom.commands.plan_verify``). Everything else is
the plan's own code: each FE field is judged by :func:`planner.optimise.judge` (the field as
both the nominal and the bound field: the FE has no interval), and ranked by
:func:`planner.optimise.ranked`, the key the plan ranks its candidates with.

Definitions (``verify`` in plan.json):

* the *top K*: the first K of the surrogate's ranking of playable feasible candidates (design
  at a frequency), the plan's winner first; fewer when fewer are feasible;
* the *compared value* of a candidate: on a grid its pitch, the surrogate's nominal pitch
  (its prediction of the same quantity the FE gives; the planned pitch at the 95 % bounds is
  reported beside it) against the pitch the FE field needs under the same criterion; with
  free positions the pitch is the sites' and the ranking is on the worst load, so the worst
  load at the sites (nominal field against FE field) is compared. ``rel_diff`` = surrogate /
  FE - 1;
* the plan is *confirmed* when (1) the FE's winner (design and frequency) among the top K is
  the plan's winner, (2) the winner's compared value is within ``PITCH_TOLERANCE`` (2 %) of
  the FE's, and (3) the criterion holds at the FE field at the planned pitch (FE load <= 1,
  and, perceptual, the FE's own amplitude felt). Otherwise it is *refuted* and
  ``refuted_because`` lists each failed condition (the CLI exits 3).

The FE ranking uses the criterion alone: candidates below the plan's winner were never checked
for timing (playability), as the surrogate's ranking did not need them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

from planner.crosstalk import UnitField
from planner.optimise import DesignResult, Plan, judge, ranked, shaped_request, worst_load
from planner.plan_record import MAX_VERIFY_TOP

__all__ = ["DEFAULT_TOP", "MAX_TOP", "PITCH_TOLERANCE", "FeSolve", "fe_judged", "rerank",
           "surrogate_ranking"]

DEFAULT_TOP = 5  # candidates re-solved by default
MAX_TOP = MAX_VERIFY_TOP  # at most 32 (one FE solve each, about 1 s)
PITCH_TOLERANCE = 0.02  # |surrogate / FE - 1| of the winner's compared value, at most


@dataclass(frozen=True)
class FeSolve:
    """One candidate's FE solve: its amplitude field and what the solve reports."""

    field: UnitField  # centre amplitude [um], edge radius [mm], profile [mm] -> [um]
    edge_um: float  # the FE's edge amplitude [um]
    dofs: int = 0
    wall_s: float = 0.0  # solve time [s]
    scene_inputs: dict[str, Any] | None = None  # the row of the space that made the scene


Solver = Callable[[DesignResult], FeSolve]


def _r(x: float | None, digits: int = 4) -> float | None:
    return None if x is None else float(round(x, digits))


def _same(a: DesignResult | None, b: DesignResult | None) -> bool:
    return a is not None and b is not None and (a.name, a.frequency_hz) == (b.name,
                                                                            b.frequency_hz)


def surrogate_ranking(plan: Plan) -> list[DesignResult]:
    """The plan's feasible candidates in its own order, without those skipped as not playable
    (the winner first)."""
    skipped = {(u["name"], u["frequency_hz"]) for u in plan.unplayable}
    free = plan.request.positions_mm is not None
    return [r for r in ranked(plan.candidates, free) if (r.name, r.frequency_hz) not in skipped]


def fe_judged(plan: Plan, r: DesignResult, fe: FeSolve) -> DesignResult:
    """Candidate ``r`` judged on its FE field with the plan's criterion (field = bound)."""
    f = fe.field
    return judge(plan.request, replace(r, center_um=f.center_um, edge_radius_mm=f.edge_radius_mm,
                                       log_std_center=0.0, log_std_profile_max=0.0, unit=f,
                                       bound=f, edge_um=fe.edge_um))


def _load_at_plan(plan: Plan, r: DesignResult, f: UnitField) -> float:
    """Worst site load of field ``f`` at candidate ``r``'s planned pitch (free: the sites)."""
    return worst_load(f, shaped_request(plan.request, r), r.pitch_mm, r.frequency_hz)


def _compared(plan: Plan, s: DesignResult, fe: DesignResult) -> tuple[float | None, ...]:
    """(surrogate value, FE value, rel_diff) of the compared quantity (module docstring)."""
    if plan.request.positions_mm is not None:
        a, b = _load_at_plan(plan, s, s.unit), _load_at_plan(plan, s, fe.unit)
    else:
        a, b = s.pitch_nominal_mm, fe.pitch_nominal_mm
    rel = None if a is None or b is None or b == 0 else a / b - 1.0
    return a, b, rel


def rerank(plan: Plan, top_k: int, solve: Solver) -> dict[str, Any]:
    """The ``verify`` block: the top ``top_k`` candidates solved by ``solve``, judged and
    ranked on their FE fields, compared with the surrogate's, and the verdict (module
    docstring). ``plan.best`` must be set."""
    best = plan.best
    if best is None:
        raise ValueError("rerank: the plan has no winner to verify")
    top = surrogate_ranking(plan)[:top_k]
    if not _same(top[0], best):  # the plan's own order: cannot differ
        raise ValueError(f"rerank: the plan's winner {best.name!r} is not first in its ranking")
    solves = [solve(r) for r in top]
    fe = [fe_judged(plan, r, s) for r, s in zip(top, solves, strict=True)]
    free = plan.request.positions_mm is not None
    fe_order = ranked(fe, free)
    fe_rank = {id(r): i + 1 for i, r in enumerate(fe_order)}
    fe_winner = fe_order[0] if fe_order else None
    rows = []
    for i, (s, f, sol) in enumerate(zip(top, fe, solves, strict=True)):
        a, b, rel = _compared(plan, s, f)
        rows.append({
            "design": s.name, "frequency_hz": s.frequency_hz, "surrogate_rank": i + 1,
            "fe_rank": fe_rank.get(id(f)), "rel_diff": _r(rel, 5),
            "surrogate": {"value": _r(a), "pitch_mm": _r(s.pitch_mm, 3),
                          "pitch_nominal_mm": _r(s.pitch_nominal_mm, 3),
                          "center_um": _r(s.center_um), "edge_um": _r(s.edge_um),
                          "load_at_plan_pitch": _r(_load_at_plan(plan, s, s.unit)),
                          "shape": None if s.shape is None else list(s.shape)},
            "fe": {"value": _r(b), "pitch_mm": _r(f.pitch_nominal_mm, 3),
                   "center_um": _r(f.center_um), "edge_um": _r(f.edge_um), "felt": f.felt,
                   "load_at_plan_pitch": _r(_load_at_plan(plan, s, f.unit)),
                   "dofs": sol.dofs, "wall_s": round(sol.wall_s, 2),
                   "shape": None if f.shape is None else list(f.shape)}})
    win_fe, win_solve = fe[0], solves[0]
    load = _load_at_plan(plan, best, win_fe.unit)
    holds = win_fe.felt and load <= 1.0
    rel = _compared(plan, best, win_fe)[2]
    agrees = _same(fe_winner, best)
    within = rel is not None and abs(rel) <= PITCH_TOLERANCE
    what = "worst load at the sites" if free else "pitch"
    reasons = []
    if not agrees:
        reasons.append("no re-solved candidate meets the criterion on the FE" if fe_winner is None
                       else f"the FE's winner is {fe_winner.name} at {fe_winner.frequency_hz:g}"
                       " Hz")
    if rel is None:
        reasons.append("the FE field meets the criterion at no pitch within the bounds")
    elif not within:
        reasons.append(f"the surrogate's {what} is {rel:+.1%} off the FE's (more than "
                       f"{PITCH_TOLERANCE:.0%})")
    if not win_fe.felt:
        reasons.append("the unit's own FE amplitude is below the detection threshold")
    elif load > 1.0:
        reasons.append(f"the criterion fails at the FE field: load {round(load, 4):.3f} > 1 at the "
                       f"planned pitch {best.pitch_mm:.2f} mm")
    f = win_fe.unit
    return {
        "design": best.name, "frequency_hz": best.frequency_hz,
        "edge_radius_mm": round(best.edge_radius_mm, 4), "holds": holds,
        "criterion": plan.request.criterion.kind,
        "surrogate": {"center_um": round(best.center_um, 4),
                      "edge_um": None if best.edge_um is None else round(best.edge_um, 4),
                      "pitch_mm": round(best.pitch_mm, 3),
                      "pitch_nominal_mm": _r(best.pitch_nominal_mm, 3),
                      "holds_at": best.holds_at},
        "fe": {"center_um": round(f.center_um, 4), "edge_um": round(win_solve.edge_um, 4),
               "pitch_mm": _r(win_fe.pitch_nominal_mm, 3),
               "criterion_load_at_plan_pitch": round(load, 4), "felt": win_fe.felt,
               "profile_end_from_edge_mm": float(f.distance_mm[-1]),
               "dofs": win_solve.dofs, "wall_s": round(win_solve.wall_s, 2)},
        "scene_inputs": win_solve.scene_inputs,
        "top_k": len(top), "top_k_requested": top_k,
        "compared": "worst_load" if free else "pitch_mm", "tolerance": PITCH_TOLERANCE,
        "candidates": rows,
        "fe_winner": None if fe_winner is None else {"design": fe_winner.name,
                                                     "frequency_hz": fe_winner.frequency_hz},
        "winner_agrees": agrees, "rel_diff": _r(rel, 5), "within_tolerance": within,
        "confirmed": not reasons, "refuted_because": reasons,
        "fe_wall_s": round(sum(s.wall_s for s in solves), 2),
    }
