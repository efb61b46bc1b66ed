"""A uniform pressure patch at the axis: ``load.radius_mm`` [mm], ``load.amplitude_Pa`` [Pa],
normal (Fourier mode 0) or tangential (mode 1) by ``load.direction``."""

from __future__ import annotations

from numpy.typing import NDArray

from .. import loads
from ..domain import Domain
from .base import Actuator, SceneView, UnitPlacement, register


@register
class PressurePatch(Actuator):
    """Pressure patch (no unit): the default load of a scene."""

    kind = "pressure_patch"
    enum_name = "PRESSURE_PATCH"
    order = 0
    load_fields = ("radius_mm", "amplitude_Pa")

    def nodal_load(self, scene: SceneView, domain: Domain, mode: int,
                   lay: UnitPlacement | None) -> NDArray:
        t = scene.load.amplitude_Pa
        return loads.surface_traction(domain, mode, scene.load.radius_m,
                                      (0.0, t, 0.0) if mode == 0 else (t, 0.0, -t))

    def r_breaks(self, scene: SceneView) -> list[float]:
        return [scene.load.radius_m]

    def edge(self, scene: SceneView, lay: UnitPlacement | None) -> float | None:
        return scene.load.radius_m
