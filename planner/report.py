"""A plan as JSON (``plan_to_dict``) and as a figure (``write_plan_plot``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from planner.figure import write_plan_plot
from planner.optimise import PITCH_TOL_MM, Z95, Plan
from planner.plan_record import KIND, SCHEMA_VERSION, PlanRecord
from planner.summary import validity

__all__ = ["plan_as_record", "plan_to_dict", "write_plan_plot"]


def _r(x: float | None, digits: int = 4) -> float | None:
    return None if x is None else float(round(x, digits))


def plan_to_dict(plan: Plan) -> dict[str, Any]:
    """The plan's JSON content with its header, not yet sealed (:func:`plan_as_record`'s
    ``to_json`` adds the digest when it is written)."""
    return {"schema_version": SCHEMA_VERSION, "kind": KIND, **plan_as_record(plan).to_dict()}


def plan_as_record(plan: Plan) -> PlanRecord:
    """Everything a user or the play step needs: request, candidates, the chosen array, as
    the typed record of ``plan.json``."""
    req = plan.request
    cands = [{"name": c.name, "frequency_hz": c.frequency_hz, "inputs": c.inputs,
              "center_um": _r(c.center_um), "edge_radius_mm": _r(c.edge_radius_mm),
              "pitch_mm": _r(c.pitch_mm, 3), "pitch_nominal_mm": _r(c.pitch_nominal_mm, 3),
              "pitch_95_mm": _r(c.pitch_95_mm, 3),
              "leakage_share_beyond_profile": _r(c.beyond_profile),
              "extrapolated_inputs": [str(x) for x in c.extrapolations],
              "edge_to_edge_mm": _r(c.edge_to_edge_mm, 3),
              "worst_load": _r(c.load), "shape": c.shape, "log_std_center": _r(c.log_std_center),
              "log_std_profile_max":
              _r(c.log_std_profile_max), "extrapolated": c.extrapolated}
             for c in plan.candidates]
    best = plan.best
    crit = req.criterion
    criterion: dict[str, Any] = {
        "kind": crit.kind, "max_ratio": crit.max_ratio, "superposition": crit.superposition,
        "profile": "envelope (largest amplitude at any larger distance)",
        "pitch_tolerance_mm": PITCH_TOL_MM, "drive_level": crit.drive_level,
        "holds_at": crit.holds_at}
    if crit.threshold is not None:
        t = crit.threshold
        criterion["body_site"] = crit.body_site
        criterion["threshold"] = {
            "source": t.source, "site": t.site, "contactor_area_cm2": t.contactor_area_cm2,
            "frequency_hz": list(t.frequency_hz),
            "threshold_um": [round(x, 6) for x in t.threshold_um],
            "at_best_frequency_um": None if best is None else
            _r(float(t(best.frequency_hz)), 6)}
    return PlanRecord(
        model=req.model,
        array={"rows": req.rows, "cols": req.cols, "grid": req.grid,
               "objective": req.objective, "region_mm": req.region_mm},
        criterion=criterion,
        site=req.site, candidates=cands,
        best=None if best is None else best.name,
        best_inputs=None if best is None else best.inputs,
        best_frequency_hz=None if best is None else best.frequency_hz,
        pitch_mm=None if best is None else _r(best.pitch_mm, 3),
        margin=_r(plan.margin),
        positions_mm=np.round(plan.positions_mm, 4).tolist(),
        crosstalk_um=np.round(plan.crosstalk_um, 6).tolist(),
        leakage_ratio=np.round(plan.ratios, 6).tolist(),
        leakage_um=np.round(plan.leakage_um, 6).tolist(),
        criterion_load=np.round(plan.loads, 6).tolist(),
        uncertainty=None if best is None else uncertainty(plan),
        timing=plan.timing,
        validity=validity(plan),
        dropped_frequencies=plan.dropped,
        not_playable=plan.unplayable,
        warnings=crit.warnings(),
    )


def uncertainty(plan: Plan) -> dict[str, Any]:
    """The surrogate's uncertainty at the chosen design: its predictive log-std (the ensemble
    spread or GP std the run-time model exports), the 95 % interval of the own amplitude, the
    margin left when neighbours sit at their upper and the site at its lower 95 % bound, and
    whether the design lies outside the model's trained range."""
    b = plan.best
    lo, hi = b.center_um * np.exp(-Z95 * b.log_std_center), b.center_um * np.exp(
        Z95 * b.log_std_center)
    load95 = plan.load_95
    return {"center_log_std": _r(b.log_std_center), "profile_log_std_max":
            _r(b.log_std_profile_max), "center_95_um": [_r(lo), _r(hi)],
            "margin_95": None if load95 is None else (None if load95 == 0 else
                                                      _r(1.0 / load95)),
            "criterion_holds_at_95": load95 is not None and load95 <= 1.0,
            "pitch_95_mm": _r(b.pitch_95_mm, 3), "pitch_nominal_mm": _r(b.pitch_nominal_mm, 3),
            "holds_at": b.holds_at, "extrapolated": b.extrapolated}
