"""The normal actuator (``load.kind = "normal_actuator"``): a voice coil or any actuator that
pushes the unit's housing along the skin normal (Fourier mode 0) with the amplitude
``unit.actuator.force_N`` [N] (``fem.scene.unit_model.Actuator``) at every frequency.

No drive dynamics of its own: in a transient its force is a sine at ``analysis.frequency_hz``
whose amplitude follows the voltage schedule relative to the unit's rated voltage."""

from __future__ import annotations

from numpy.typing import NDArray

from .. import loads
from ..domain import Domain
from .base import Actuator, SceneView, UnitPlacement, register


@register
class NormalActuator(Actuator):
    """Force along the normal on the unit's center, flat in frequency."""

    kind = "normal_actuator"
    enum_name = "NORMAL_ACTUATOR"
    order = 3
    is_unit = True
    unit_part = "actuator"

    def fourier_mode(self, direction: str) -> int:
        return 0

    def force_N(self, scene: SceneView) -> float:
        """Force amplitude [N] on the housing at ``analysis.frequency_hz``."""
        return scene.unit.actuator.force_N

    def nodal_load(self, scene: SceneView, domain: Domain, mode: int,
                   lay: UnitPlacement | None) -> NDArray:
        return loads.axis_point_force(domain, 0, self.force_N(scene), z=lay.center_z)
