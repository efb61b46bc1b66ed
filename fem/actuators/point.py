"""A point force ``load.force_N`` [N] on the axis at the surface, normal (Fourier mode 0) or
tangential (mode 1) by ``load.direction``."""

from __future__ import annotations

from numpy.typing import NDArray

from .. import loads
from ..domain import Domain
from .base import Actuator, SceneView, UnitPlacement, register


@register
class PointForce(Actuator):
    """Point force at the axis (no unit, no footprint edge)."""

    kind = "point_force"
    enum_name = "POINT_FORCE"
    order = 1
    load_fields = ("force_N",)

    def nodal_load(self, scene: SceneView, domain: Domain, mode: int,
                   lay: UnitPlacement | None) -> NDArray:
        return loads.axis_point_force(domain, mode, scene.load.force_N)
