"""Planning for one person: a calibration document (``hapticrom calibrate``) as the tissue of a
layout, and its posterior uncertainty carried into the pitch.

    tissue = load_tissue("out/cal.json")
    plan = plan_layout(apply_tissue(load_layout("examples/forearm-layout.toml"), tissue))
    spread = posterior_pitch(plan, tissue)    # pitch over the posterior draws

:func:`apply_tissue` puts the calibration's point estimate (posterior means of the fitted
inputs, and the tissue inputs the fit held fixed) into the layout's ``[site]``, so the plan
chooses its design and frequency for that person. :func:`posterior_pitch` then re-evaluates the
chosen design at the chosen frequency for every posterior draw of the tissue and finds each
draw's smallest feasible pitch (the same criterion and bisection as the plan); the pitch at the
posterior's 95 % bound is the 95th percentile of those (a draw with no feasible pitch counts as
larger than any). The same with the surrogate's own 95 % bound field gives the conservative
figure that holds for both uncertainties; ``pitch_95_for_plan_mm`` is the one of the two that
matches the plan's own rule (``criterion.holds_at``: the bounds or the prediction).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from calibration.document import Tissue, read_calibration
from planner.crosstalk import UnitField
from planner.layout import LayoutError, LayoutRequest
from planner.optimise import Z95, Plan, smallest_pitch
from surrogate.runtime import load_predictor

__all__ = ["apply_tissue", "load_tissue", "posterior_pitch"]

MAX_DRAWS = 400


def load_tissue(path: str | Path) -> Tissue:
    """Read a calibration document (errors name the key: :class:`CalibrationFileError`)."""
    return read_calibration(path)


def apply_tissue(req: LayoutRequest, tissue: Tissue) -> LayoutRequest:
    """The request with its ``[site]`` values replaced by the calibration's tissue. The
    calibration must come from the model the layout plans on (a surrogate's calibrated inputs
    absorb that surrogate's own bias)."""
    card_name = load_predictor(req.model).card.get("name")
    if tissue.model_name is not None and tissue.model_name != card_name:
        raise LayoutError("--tissue", f"--tissue {tissue.path}: calibrated on model "
                          f"{tissue.model_name!r}, but the layout plans on {card_name!r} "
                          f"({req.model}); calibrate with --model {req.model} or set [model] "
                          "path")
    clash = [k for d in req.designs for k in d["inputs"] if k in tissue.point]
    if clash:
        raise LayoutError(f"design.{clash[0]}", f"design.{clash[0]}: also set by --tissue "
                          f"{tissue.path}; a tissue input goes in [site] or the calibration")
    return replace(req, site={**req.site, **tissue.point})


def posterior_pitch(plan: Plan, tissue: Tissue, max_draws: int = MAX_DRAWS
                    ) -> dict[str, Any] | None:
    """The chosen design's pitch over the posterior draws (None without a chosen design):
    percentiles of the nominal pitch, the pitch at the posterior's 95 % bound, and the same
    with the surrogate's 95 % bound field; lengths in mm."""
    best = plan.best
    if best is None:
        return None
    req = plan.request
    n = min(tissue.n_samples, max_draws)
    predictor = load_predictor(req.model)
    rows = {**req.site, **best.inputs, "frequency_hz": best.frequency_hz}
    X = {k: np.array([v] * n) for k, v in rows.items()}
    for name, draws in tissue.samples.items():
        X[name] = draws[:n]
    out = predictor.predict(X, extrapolate=True)
    grid = predictor.profile_distance_mm
    nominal, bound = [], []
    for k in range(n):
        c, p = float(out["center_amplitude_um"][k]), out["profile_um"][k]
        s_c, s_p = float(out["center_amplitude_um_log_std"][k]), out["profile_um_log_std"][k]
        edge = float(out["edge_radius_mm"][k])
        f_nom = UnitField(c, edge, grid, p)
        f_95 = UnitField(c * np.exp(-Z95 * s_c), edge, grid, p * np.exp(Z95 * s_p), floor=f_nom)
        p_nom = smallest_pitch(f_nom, req, best.frequency_hz)
        p_95 = smallest_pitch(f_95, req, best.frequency_hz)
        nominal.append(p_nom)
        # as the plan does: the bounds never ask for less room than the prediction
        bound.append(None if p_95 is None or p_nom is None else max(p_95, p_nom))

    def pct(values: list[float | None], q: float) -> float | None:
        arr = np.array([np.inf if v is None else v for v in values])
        x = float(np.percentile(arr, q, method="higher"))
        return None if not np.isfinite(x) else round(x, 3)

    holds_at = getattr(req.criterion, "holds_at", "nominal")
    rule = bound if holds_at == "bounds_95" else nominal
    return {"draws": n, "design": best.name, "frequency_hz": best.frequency_hz,
            "holds_at": holds_at,
            "pitch_mm_at_point_estimate": round(best.pitch_mm, 3),
            "pitch_95_for_plan_mm": pct(rule, 95.0),
            "pitch_mm_median": pct(nominal, 50.0), "pitch_mm_2_5": pct(nominal, 2.5),
            "pitch_mm_97_5": pct(nominal, 97.5), "pitch_95_mm": pct(nominal, 95.0),
            "pitch_95_with_surrogate_mm": pct(bound, 95.0),
            "infeasible_fraction": round(sum(v is None for v in nominal) / n, 4),
            "extrapolated_fraction": round(float(np.mean(out["extrapolated"])), 4),
            "calibration": tissue.path, "statement": tissue.statement}
