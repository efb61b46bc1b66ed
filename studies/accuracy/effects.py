"""Effects audit: what each optional physical effect costs and how much it moves the answer.

For every design the scene is solved as the dataset solved it ("all effects": every effect the
scene contains on, the solver's default) and then with one effect forced off at a time, plus
two model choices that are not effects (a fixed outer side instead of the absorbing layer,
linear elements). An effect the design does not contain (no rings, no loss) is not varied; a
combination the solver refuses (e.g. no inertia for a unit on frictionless pins, which would
be a mechanism) is counted as refused. The change is :mod:`.metric`'s error of the variant
against the all-effects answer on the same mesh, so it isolates the effect.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from typing import Any

import numpy as np

from fem import SceneError, scene_from_dict
from fem.problem import resolve_effects

from .designs import Design
from .fe_ladder import solve
from .metric import errors, summary

__all__ = ["EFFECTS", "audit", "variants"]

#: The optional effects audited (fem.scene.model.EFFECT_NAMES less those that are a design
#: choice rather than an approximation: pogo pins, and the transient/pin-check-only spin_up
#: and preload).
EFFECTS = ("hysteretic_damping", "inertia", "encapsulation", "unit_mass", "rocking")


def variants(base: dict[str, Any]) -> dict[str, dict[str, Any] | None]:
    """Scene dicts by variant name: "all effects" (``base``), "no EFFECT" for each effect the
    scene contains (None when it has none to switch off), "fixed side (no absorber)" and
    "order 1 elements"."""
    on = resolve_effects(scene_from_dict(base))
    out: dict[str, dict[str, Any] | None] = {"all effects": base}
    for effect in EFFECTS:
        if not on[effect]:
            out[f"no {effect}"] = None
            continue
        d = copy.deepcopy(base)
        d.setdefault("effects", {})[effect] = False
        out[f"no {effect}"] = d
    side = copy.deepcopy(base)
    side["tissue"]["side"] = "fixed"
    out["fixed side (no absorber)"] = side
    order1 = copy.deepcopy(base)
    order1.setdefault("mesh", {})["order"] = 1
    out["order 1 elements"] = order1
    return out


def audit(designs: Sequence[Design], grid_mm: np.ndarray, repeat: int) -> list[dict[str, Any]]:
    """One row per variant: designs where it applies / was refused, median time ratio to all
    effects, and the summary of its change of the answer over the designs it applies to."""
    per: dict[str, dict[str, Any]] = {}
    for des in designs:
        vs = variants(des.scene)
        full, t_full, _ = solve(vs["all effects"], grid_mm, repeat)
        for name, d in vs.items():
            rec = per.setdefault(name, {"errs": [], "ratios": [], "n_a": 0, "refused": 0})
            if d is None:
                rec["n_a"] += 1
                continue
            try:
                a, t, _ = solve(d, grid_mm, repeat) if name != "all effects" else (full, t_full,
                                                                                   0)
            except (SceneError, ValueError):
                rec["refused"] += 1
                continue
            rec["errs"].append(errors(a, full))
            rec["ratios"].append(t / t_full)
    rows = []
    for name, rec in per.items():
        row = {"variant": name, "applies": len(rec["errs"]), "not_present": rec["n_a"],
               "refused": rec["refused"]}
        if rec["errs"]:
            row.update(time_ratio=float(np.median(rec["ratios"])), **summary(rec["errs"]))
        rows.append(row)
    return rows
