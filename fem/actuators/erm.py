"""The coin ERM unit (``load.kind = "unit"``): an eccentric rotating mass whose unbalance force
m e omega^2 [N] rotates parallel to the skin at the rotor plane (Fourier mode 1).

Its parameters are the scene's ``[unit.motor]`` table (``fem.scene.unit_model.Motor``, with
their sources there); its speed law, spin-up and spin-down come from ``motorlaw`` through
``fem.motor`` (the transient's load history)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from motorlaw import DEFAULTS as MOTOR_LAW

from .. import loads, motor
from ..domain import Domain
from .base import Actuator, History, ProblemView, SceneView, UnitPlacement, register


@register
class CoinERM(Actuator):
    """Coin ERM motor on the skin: force parallel to the skin, rocking, spin-up."""

    kind = "unit"
    enum_name = "UNIT"
    order = 2
    is_unit = True
    parallel_force = True
    spins_up = True
    transient_frequency_field = "unit.motor.rated_frequency_hz"

    def fourier_mode(self, direction: str) -> int:
        return 1  # the unbalance force is parallel to the skin whatever load.direction says

    def nodal_load(self, scene: SceneView, domain: Domain, mode: int,
                   lay: UnitPlacement | None) -> NDArray:
        """At the rotor plane: the unbalance force at ``analysis.frequency_hz`` in a steady
        solve, 1 N in a transient (scaled by the motor's force history)."""
        steady = scene.analysis.kind != "transient"
        force = scene.unit.motor.force_N_at(scene.analysis.frequency_hz) if steady else 1.0
        return loads.axis_point_force(domain, 1, force, z=lay.rotor_z)

    def load_scale(self, omega: NDArray, omega_ref: float,
                   scene: SceneView | None = None) -> NDArray:
        """The unbalance force m e omega^2 grows with the square of the speed."""
        return (np.asarray(omega, dtype=float) / omega_ref) ** 2

    def load_history(self, scene: SceneView, problem: ProblemView) -> tuple[History, int]:
        """The rotating force's two components [N] from the motor law's speed under the
        voltage schedule (spin-up and spin-down time constants when the effect is on)."""
        a = scene.analysis
        m = scene.unit.motor
        tau_up = m.tau_spinup_s if problem.effects["spin_up"] else 1e-9
        tau_down = m.tau_spindown_s if problem.effects["spin_up"] else 1e-9
        erm = motor.ERMMotor(m.rated_voltage_V, m.rated_frequency_hz, m.start_voltage_V,
                             tau_up, tau_down,
                             max(MOTOR_LAW["max_voltage_V"],
                                 float(np.max(np.abs([v for _, v in a.voltage_schedule])))),
                             unbalance_kg_m=m.unbalance_kg_m)
        schedule = motor.VoltageSchedule(a.voltage_schedule_s)
        return motor.erm_load_history(erm, schedule), 2
