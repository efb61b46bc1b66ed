"""What one solve of a case gives the report (:class:`Solved`): plain numbers, amplitudes in m
inside, um in the derived properties. Its own module so that the cases (which rank solved
results) and the runner (which makes them) both stand on it without importing each other."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["Solved", "magnitude"]


@dataclass(frozen=True)
class Solved:
    """What the report needs from one solve. Complex (U_r, U_z, U_t) amplitudes in m.

    Attributes:
        edge_mm: the unit's outer radius (mm).
        centre: the unit's skin-side face on the axis (the solver's haptic unit); edge: skin at
            edge_mm.
        skin_axis: the skin surface on the axis; top_axis: the motor's top face on the axis
            (NaN for a transient).
        profile_mm: distance from the edge (mm); profile: (n, 3) skin amplitudes there.
        surface_r_mm, surface: every skin-surface node (mm; (n, 3)).
        wall_s: solve time (s); dofs; warnings; contact: pogo preload check or None.
        transient: for a time-domain case, peak amplitudes (um) and sampled histories.
    """

    edge_mm: float
    centre: NDArray
    edge: NDArray
    skin_axis: NDArray
    top_axis: NDArray
    profile_mm: NDArray
    profile: NDArray
    surface_r_mm: NDArray
    surface: NDArray
    wall_s: float
    dofs: int
    warnings: tuple[str, ...] = ()
    contact: dict | None = None
    transient: dict | None = field(default=None, repr=False)

    @property
    def centre_um(self) -> float:
        return magnitude(self.centre) * 1e6

    @property
    def edge_um(self) -> float:
        return magnitude(self.edge) * 1e6

    @property
    def edge_z_um(self) -> float:
        return abs(self.edge[1]) * 1e6

    @property
    def norm(self) -> float:
        """Normalized edge: displacement magnitude at the edge over the centre's."""
        return self.edge_um / self.centre_um

    @property
    def norm_z(self) -> float:
        """|U_z| at the edge over the centre magnitude (U_z vanishes on the axis in mode 1)."""
        return self.edge_z_um / self.centre_um

    def centre_variants_um(self) -> dict[str, float]:
        """Four readings of "centre" (um): ours (the unit's skin-side face on the axis), the
        skin surface on the axis, the largest skin amplitude under the unit, and the motor's
        top face on the axis (where a vibrometer looking down at the unit would aim)."""
        under = self.surface_r_mm <= self.edge_mm * (1 + 1e-9)
        return {"unit face": self.centre_um, "skin on axis": magnitude(self.skin_axis) * 1e6,
                "skin peak under unit": float(magnitude(self.surface[under]).max() * 1e6),
                "motor top": float(magnitude(self.top_axis) * 1e6)}

    def normalized_profile(self, vertical: bool = False) -> NDArray:
        """Profile amplitude over the centre magnitude (magnitude, or |U_z| if vertical)."""
        amp = np.abs(self.profile[:, 1]) if vertical else magnitude(self.profile)
        return amp * 1e6 / self.centre_um


def magnitude(U: NDArray) -> Any:
    return np.sqrt(np.sum(np.abs(U) ** 2, axis=-1))
