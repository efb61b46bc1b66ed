"""Read-only SI views of scene fields kept in the file's units, defined once for every table."""

from __future__ import annotations

from typing import Any

from ..materials import Material

__all__ = ["Elastic", "si_view"]


def si_view(name: str, factor: float, doc: str = "") -> property:
    """A read-only SI view of a field kept in the units of the file (``thickness_mm`` ->
    ``thickness_m``): the field's value times ``factor``."""

    def value(self: Any) -> float:
        return getattr(self, name) * factor

    return property(value, doc=doc or f"``{name}`` in SI units (x {factor:g}).")


class Elastic:
    """SI material view shared by the tables that describe a solid (layers, rings, board)."""

    name: str
    E_kPa: float
    density_kg_m3: float
    nu: float
    loss_factor: float

    E_Pa = si_view("E_kPa", 1e3)

    def solid(self, hysteretic: bool = True) -> Material:
        """This solid as the solver's SI :class:`~fem.materials.Material`; ``hysteretic=False``
        drops the loss factor (the effect switched off)."""
        loss = self.loss_factor if hysteretic else 0.0
        return Material(self.name, self.E_Pa, self.density_kg_m3, self.nu, loss)
