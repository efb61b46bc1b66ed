"""``hapticrom design``'s FE check: the band solve passed to :func:`planner.design.verify.
verify_search`.

Each unit's scene is built as ``hapticrom plan --verify`` builds it: the model's training
dataset's parameter space maps the design's model inputs and the site to a scene
(``Space.resolve``; inputs the model does not take keep the space's centre values); a unit of
catalogue silicones gets its rings by name (each ring its own silicone from the shared
catalogue, not the mean the model is given); the analysis becomes a sweep over the drive
frequencies, solved with the reduced-order sweep solver (``fem.sweep.sweep``): one reduced
model per unit for all its frequencies.
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from hapticrom.commands.plan_verify import _dataset_path

__all__ = ["band_solver", "unit_scene", "unit_space"]


def unit_space(model: str) -> Any:
    """The parameter space of the model's training dataset (it builds the scenes)."""
    # lazy: the command's FE solve loads only when it runs (`hapticrom --help`: 0.4 s)
    from surrogate.data.store import Store

    return Store.open(_dataset_path(model)).space


def unit_scene(space: Any, site: dict[str, Any], inputs: dict[str, Any],
               materials: tuple[str, ...] | None, analysis: dict[str, Any]) -> dict[str, Any]:
    """The scene dict of one unit on the site (``analysis``: the scene's analysis table)."""
    row = {**space.center(), **site, **inputs}
    row["frequency_hz"] = float(analysis.get("frequency_hz", row.get("frequency_hz", 120.0))
                                if not isinstance(analysis.get("frequency_hz"), list) else
                                analysis["frequency_hz"][0])
    scene = copy.deepcopy(space.resolve(row))
    scene.pop("band", None)
    if materials is not None:
        scene.setdefault("unit", {})["encapsulation"] = list(materials)
    scene["analysis"] = dict(analysis)
    return scene


def band_solver(model: str, site: dict[str, Any]) -> Any:
    """A :data:`planner.design.verify.BandSolve` on the model's training scenes; raises
    RuntimeError when a sweep fails."""
    # lazy: the command's FE solve loads only when it runs (`hapticrom --help`: 0.4 s)
    from fem.results import magnitude
    from fem.scene import scene_from_dict
    from fem.sweep import sweep
    from planner.crosstalk import UnitField
    from planner.verify import FeSolve

    space = unit_space(model)

    def solve(inputs: dict[str, Any], materials: tuple[str, ...] | None,
              frequencies_hz: tuple[float, ...]) -> list[FeSolve]:
        scene = unit_scene(space, site, inputs, materials,
                           {"kind": "sweep", "frequency_hz": [float(f) for f in frequencies_hz]})
        try:
            res = sweep(scene_from_dict(scene))
        except Exception as err:  # a failed solve is reported, not a traceback
            raise RuntimeError(f"the FE sweep of {inputs} failed: {err}") from err
        centre, edge = res.center_amplitude_um, res.edge_amplitude_um
        wall = float(res.meta["wall_s"]) / len(frequencies_hz)
        out = []
        for i in range(len(frequencies_hz)):
            profile = np.maximum(magnitude(res.profile[i]) * 1e6, 1e-12)
            out.append(FeSolve(UnitField(float(centre[i]), float(res.edge_mm),
                                         np.asarray(res.profile_mm, dtype=float), profile),
                               float(edge[i]), int(res.meta["dofs"]), wall,
                               {"materials": None if materials is None else list(materials),
                                **inputs}))
        return out

    return solve
