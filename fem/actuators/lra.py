"""The linear resonant actuator (``load.kind = "lra"``): a coin LRA on the skin, a magnet mass
on a spring driven by a voice coil at its resonance, pushing the housing along the skin
normal (Fourier mode 0).

Its drive dynamics are its drive law, defined once in :mod:`motorlaw.lra`
(:class:`motorlaw.lra.ResonantDrive`, which the run-time side uses too): the force at a drive
frequency f is that of a damped mass-spring resonator,

    F(f) = force_N * |G(f)| / Q,   G = r^2 / (1 - r^2 + i r / Q),   r = f / resonance_hz

so F(resonance) = force_N, and far above resonance F -> force_N / Q (the mass is driven as a
free mass). Scene fields: a ``[unit]`` table as for any unit; ``unit.actuator.force_N`` [N] is
the force amplitude on the housing *at its resonance* (the rated force); the optional
``[unit.lra]`` table gives the resonator (``resonance_hz``, ``quality_factor``,
``moving_mass_g``, ``rated_voltage_V``, ``max_voltage_V``; absent: the law's defaults for a
common 10 mm coin LRA, with their sources in :mod:`motorlaw.lra`). Only the amplitude is
applied; the phase of the force against the drive voltage is not modelled (the solver's
displacements are relative to the force). A transient drives a sine at
``analysis.frequency_hz`` whose amplitude follows the voltage schedule (the resonator's own
ring-up and braking, which the run-time side takes from the drive law, are not in the FE
transient).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from motorlaw.lra import DEFAULTS as LAW
from motorlaw.lra import ResonantDrive

from .base import SceneView, register
from .normal import NormalActuator


@register
class LRA(NormalActuator):
    """Coin LRA: force along the normal on the unit's center, resonant in frequency."""

    kind = "lra"
    enum_name = "LRA"
    order = 4
    own_part = "lra"

    # the drive law's defaults (motorlaw.lra.DEFAULTS, sources there)
    RESONANCE_HZ: ClassVar[float] = LAW["resonance_hz"]
    RATED_FORCE_N: ClassVar[float] = LAW["force_N"]
    MOVING_MASS_KG: ClassVar[float] = LAW["moving_mass_kg"]
    QUALITY_FACTOR: ClassVar[float] = LAW["quality_factor"]

    def law(self, scene: SceneView | None = None) -> ResonantDrive:
        """The drive law of ``scene``'s LRA: its ``[unit.lra]`` table, else the defaults."""
        part = scene.unit.lra if scene is not None and scene.unit is not None else None
        if part is None:
            return ResonantDrive()
        return ResonantDrive(resonance_hz=part.resonance_hz,
                             quality_factor=part.quality_factor,
                             moving_mass_kg=part.moving_mass_kg,
                             rated_voltage_V=part.rated_voltage_V,
                             max_voltage_V=part.max_voltage_V)

    def response(self, frequency_hz: NDArray | float, scene: SceneView | None = None) -> NDArray:
        """Force at ``frequency_hz`` [Hz] relative to the force at resonance [-] (1 there)."""
        return self.law(scene).response(frequency_hz)

    def force_N(self, scene: SceneView) -> float:
        """Force amplitude [N] on the housing at ``analysis.frequency_hz``."""
        return float(scene.unit.actuator.force_N
                     * self.response(scene.analysis.frequency_hz, scene))

    def load_scale(self, omega: NDArray, omega_ref: float,
                   scene: SceneView | None = None) -> NDArray:
        """The resonator's force at ``omega`` over its force at ``omega_ref`` [rad/s]."""
        to_hz = 1 / (2 * np.pi)
        law = self.law(scene)
        return law.response(np.asarray(omega) * to_hz) / law.response(omega_ref * to_hz)
