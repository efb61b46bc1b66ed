"""Where a solve is sampled: the probe radii, the centre (on the unit's skin-side face), the
edge and the profile from the edge, as one interpolation stencil over the nodal solution."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from . import results
from .problem import Problem
from .scene import Scene


@dataclass(frozen=True)
class OutputPoints:
    """The sampled points of a scene: probes (m), profile distances from the edge (mm) and a
    warning when the profile was cut to the model; ``radii`` (m) lists probes, centre, edge,
    profile in that order and ``stencil`` interpolates them."""

    r_probe: NDArray
    profile_mm: NDArray
    cut: str | None
    radii: NDArray
    stencil: tuple[NDArray, NDArray]

    @property
    def n_probe(self) -> int:
        return self.r_probe.size


def output_points(scene: Scene, problem: Problem) -> OutputPoints:
    """The probes, centre, edge and profile of ``scene`` on ``problem``'s mesh."""
    edge = problem.edge or 0.0
    r_probe = np.asarray(scene.output.radii_m)
    prof_mm, cut = profile_distances_mm(scene, edge)
    radii = np.concatenate([r_probe, [0.0, edge], edge + prof_mm * 1e-3])
    return OutputPoints(r_probe, prof_mm, cut, radii, stencil(problem, radii, r_probe.size))


def stencil(problem: Problem, radii: NDArray, center_index: int) -> tuple[NDArray, NDArray]:
    """Interpolation stencil of the skin surface at ``radii``, except the center point
    (index ``center_index``), which sits on the unit's skin-side face (see
    ``fem.haptic_unit``)."""
    nodes, weights = results.surface_stencil(problem.domain, radii)
    lay = problem.layout
    if lay is not None and lay.contact_z != 0.0:
        c_nodes, c_weights = results.surface_stencil(problem.domain, [0.0], lay.contact_z,
                                                     side="above")
        nodes, weights = nodes.copy(), weights.copy()
        nodes[center_index], weights[center_index] = c_nodes[0], c_weights[0]
    return nodes, weights


def profile_distances_mm(scene: Scene, edge: float) -> tuple[NDArray, str | None]:
    """Distances from the edge (mm) of the profile, within the meshed radius, and a warning
    naming the keys when the requested length had to be cut to the model."""
    out = scene.output
    n = int(np.floor(out.profile_length_mm / out.profile_step_mm + 1e-9))
    d = out.profile_step_mm * np.arange(n + 1)
    kept = d[edge + d * 1e-3 <= scene.tissue.radius_m * (1 + 1e-12)]
    if kept.size == d.size:
        return kept, None
    room = (scene.tissue.radius_m - edge) * 1e3
    return kept, (f"output.profile_length_mm = {out.profile_length_mm:g} reaches beyond the "
                  f"model: cut to {kept[-1] if kept.size else 0.0:g} mm (tissue.radius_mm = "
                  f"{scene.tissue.radius_m * 1e3:g} less the edge radius "
                  f"{edge * 1e3:g} mm leaves {room:g} mm); raise tissue.radius_mm or lower "
                  "output.profile_length_mm")
