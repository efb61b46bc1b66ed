"""The linear resonant actuator (``load.kind = "lra"``): a coin LRA on the skin, a magnet mass
on a spring driven by a voice coil at its resonance, pushing the housing along the skin
normal (Fourier mode 0).

Scene fields: a ``[unit]`` table as for any unit; ``unit.actuator.force_N`` [N] is the LRA's
force amplitude on the housing *at its resonance* (the rated force). At another drive
frequency f the same coil drive gives the force of a damped mass-spring resonator, the
reaction of the moving mass on the housing:

    F(f) = force_N * |G(f)| / Q,   G = r^2 / (1 - r^2 + i r / Q),   r = f / RESONANCE_HZ

so F(RESONANCE_HZ) = force_N, and far above resonance F -> force_N / Q (the mass is driven
as a free mass). Only the amplitude is applied; the phase of the force against the drive
voltage is not modelled (the solver's displacements are relative to the force). A transient
drives a sine at ``analysis.frequency_hz`` whose amplitude follows the voltage schedule (the
resonator's own ring-up and braking are not modelled).

Defaults for a common 10 mm coin LRA, from the headline figures of the datasheet families
Precision Microdrives C10-100 (10 mm, 175 Hz rated frequency, about 1.4 g normalised
amplitude on a 100 g test mass) and Vybronics VG1040003D (10 mm coin, resonance in the
170-175 Hz band). These figures were not re-read from the datasheets in this tree: check them
against the current datasheet before relying on them.

- ``RESONANCE_HZ`` = 175 Hz: the families' rated frequency.
- ``RATED_FORCE_N`` = 1.4 N: 1.4 g x 9.81 m/s2 on a 0.1 kg test mass (about 1.37 N), the
  force-class of the family (the scene's ``unit.actuator.force_N`` is what the solver uses).
- ``MOVING_MASS_KG`` = 1.5e-3 kg: an estimate (1-2 g for a 10 mm coin LRA's magnet mass).
- ``QUALITY_FACTOR`` = 10: an estimate from the narrow (about +-10 Hz) band around resonance
  in which these LRAs are specified to be driven.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numpy.typing import NDArray

from .base import register
from .normal import NormalActuator

if TYPE_CHECKING:
    from ..scene import Scene


@register
class LRA(NormalActuator):
    """Coin LRA: force along the normal on the unit's center, resonant in frequency."""

    kind = "lra"
    enum_name = "LRA"
    order = 4

    RESONANCE_HZ: ClassVar[float] = 175.0
    RATED_FORCE_N: ClassVar[float] = 1.4
    MOVING_MASS_KG: ClassVar[float] = 1.5e-3
    QUALITY_FACTOR: ClassVar[float] = 10.0

    def response(self, frequency_hz: NDArray | float) -> NDArray:
        """Force at ``frequency_hz`` [Hz] relative to the force at resonance [-] (1 there)."""
        r = np.asarray(frequency_hz, dtype=float) / self.RESONANCE_HZ
        q = self.QUALITY_FACTOR
        return np.abs(r**2 / (1 - r**2 + 1j * r / q)) / q

    def force_N(self, scene: Scene) -> float:
        """Force amplitude [N] on the housing at ``analysis.frequency_hz``."""
        return float(scene.unit.actuator.force_N * self.response(scene.analysis.frequency_hz))

    def load_scale(self, omega: NDArray, omega_ref: float) -> NDArray:
        """The resonator's force at ``omega`` over its force at ``omega_ref`` [rad/s]."""
        to_hz = 1 / (2 * np.pi)
        return self.response(np.asarray(omega) * to_hz) / self.response(omega_ref * to_hz)
