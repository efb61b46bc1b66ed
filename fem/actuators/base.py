"""What every actuator answers, and the registry the scene and the solver look kinds up in.

An actuator is what excites the tissue: a pressure patch, a point force, or a haptic unit on
the skin (a coin ERM, a normal actuator, an LRA). Each kind is one class in one module of
``fem.actuators``; the class holds its scene string (``load.kind``), the Fourier mode it
excites, the nodal load it applies, which scene fields it reads, and its drive dynamics (how
its force follows the frequency, its transient load history). The solver asks the class
(:func:`actuator`) instead of branching on the kind's name.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, ClassVar, Protocol

import numpy as np
from numpy.typing import NDArray

from ..domain import Domain

__all__ = ["ACTUATORS", "Actuator", "ProblemView", "SceneView", "UnitPlacement", "actuator",
           "register"]

History = Callable[[NDArray], NDArray]


# What an actuator is handed, as the interfaces it reads: the scene, the built problem and the
# unit layout sit above the actuators (the scene's schema is made from this registry), so the
# actuators name what they read instead of importing them (no circle in fem).
class SceneView(Protocol):
    """What an actuator reads of a scene (:class:`fem.scene.Scene` is one): its ``[analysis]``,
    ``[load]`` and ``[unit]`` tables."""

    @property
    def analysis(self) -> Any: ...

    @property
    def load(self) -> Any: ...

    @property
    def unit(self) -> Any: ...


class UnitPlacement(Protocol):
    """Where a unit sits (:class:`fem.haptic_unit.UnitLayout` is one): heights [m] of its
    centre and rotor plane, and the radius [m] of its outer edge."""

    @property
    def center_z(self) -> float: ...

    @property
    def rotor_z(self) -> float: ...

    @property
    def edge(self) -> float: ...


class ProblemView(Protocol):
    """What an actuator reads of a built problem (:class:`fem.problem.Problem` is one): which
    physical effects are on."""

    @property
    def effects(self) -> Mapping[str, bool]: ...


class Actuator:
    """One kind of load. Subclasses set the class attributes and :meth:`nodal_load`.

    Attributes:
        kind: the scene string (``load.kind``).
        enum_name: the member name in ``fem.scene.LoadKind``.
        order: position among the kinds (scene schema choices are listed in this order).
        is_unit: a haptic unit sitting on the skin (needs a ``[unit]`` table).
        unit_part: the ``[unit.<part>]`` table it reads beyond motor, board and pogo, or None.
        own_part: an optional ``[unit.<part>]`` table of its own (its drive law's parameters),
            or None; absent from a scene, the drive law's defaults apply.
        load_fields: the ``[load]`` fields it reads (beyond ``kind`` and ``direction``).
        parallel_force: its force on a unit is parallel to the skin (the unit may rock).
        spins_up: a transient drives it through a spin-up (the ``spin_up`` effect).
        transient_frequency_field: the scene field whose frequency a transient runs at.
    """

    kind: ClassVar[str]
    enum_name: ClassVar[str]
    order: ClassVar[int] = 100
    is_unit: ClassVar[bool] = False
    unit_part: ClassVar[str | None] = None
    own_part: ClassVar[str | None] = None
    load_fields: ClassVar[tuple[str, ...]] = ()
    parallel_force: ClassVar[bool] = False
    spins_up: ClassVar[bool] = False
    transient_frequency_field: ClassVar[str] = "analysis.frequency_hz"

    def fourier_mode(self, direction: str) -> int:
        """The Fourier mode excited: 0 / 1 for a "normal" / "tangential" ``load.direction``."""
        return 0 if direction == "normal" else 1

    def nodal_load(self, scene: SceneView, domain: Domain, mode: int,
                   lay: UnitPlacement | None) -> NDArray:
        """Full nodal load vector [N] at the drive amplitude of a steady solve (a transient
        multiplies it by :meth:`load_history`)."""
        raise NotImplementedError

    def r_breaks(self, scene: SceneView) -> list[float]:
        """Radii [m] the mesh must have a grid line at (besides a unit's own)."""
        return []

    def edge(self, scene: SceneView, lay: UnitPlacement | None) -> float | None:
        """Radius [m] of the load footprint's edge: the unit's, else None (a point)."""
        return lay.edge if lay is not None else None

    def transient_frequency_hz(self, scene: SceneView) -> float:
        """The frequency [Hz] a transient runs at (mesh and absorbers are sized for it)."""
        return float(_get(scene, self.transient_frequency_field))

    def load_scale(self, omega: NDArray, omega_ref: float,
                   scene: SceneView | None = None) -> NDArray:
        """Force at angular frequencies ``omega`` [rad/s] relative to the force of
        :meth:`nodal_load` at ``omega_ref`` [rad/s] (a sweep scales its one load by it) for
        ``scene``'s actuator. Default: a force that does not depend on frequency."""
        return np.ones_like(np.asarray(omega, dtype=float))

    def load_history(self, scene: SceneView, problem: ProblemView) -> tuple[History, int]:
        """(history(t) -> (n_t, k) amplitudes, k) of a transient: the nodal load is repeated in
        k columns, each weighted by one column of the history. Default: a sine at
        ``analysis.frequency_hz`` whose amplitude follows the voltage schedule relative to the
        unit's rated voltage."""
        a = scene.analysis
        starts = np.array([t for t, _ in a.voltage_schedule_s])
        level = np.array([v for _, v in a.voltage_schedule]) / scene.unit.motor.rated_voltage_V
        w = 2 * np.pi * a.frequency_hz

        def history(t: NDArray) -> NDArray:
            env = level[np.searchsorted(starts, t, side="right") - 1]
            return (env * np.sin(w * t))[:, None]

        return history, 1


def _get(scene: Any, dotted: str) -> Any:
    value = scene
    for name in dotted.split("."):
        value = getattr(value, name)
    return value


ACTUATORS: dict[str, Actuator] = {}
"""``load.kind`` string -> the actuator (filled by :func:`register`, kept in ``order``)."""


def register(cls: type[Actuator]) -> type[Actuator]:
    """Class decorator: add one instance of ``cls`` to :data:`ACTUATORS` under ``cls.kind``."""
    if cls.kind in ACTUATORS:
        raise ValueError(f"actuator kind {cls.kind!r} registered twice")
    ACTUATORS[cls.kind] = cls()
    ordered = sorted(ACTUATORS.values(), key=lambda a: (a.order, a.kind))
    ACTUATORS.clear()
    ACTUATORS.update((a.kind, a) for a in ordered)
    return cls


def actuator(kind: str) -> Actuator:
    """The actuator of ``load.kind`` string ``kind`` (KeyError when unknown: the scene
    validation reports unknown kinds before any solver asks)."""
    return ACTUATORS[str(kind)]
