"""What every actuator's drive law answers, and the registry the run-time side looks it up in.

A drive law is how an actuator's vibration follows its drive voltage: the coin ERM's speed law
(:class:`motorlaw.erm.SpeedLaw`: the voltage sets the spin speed, and with it the frequency
and the force), the LRA's resonator (:class:`motorlaw.lra.ResonantDrive`: an AC drive at a
frequency near the resonance, the force's envelope ringing up and down with the resonator's
time constant). The run-time envelope model, the planner's timing and the hardware schedule
ask the law (:func:`drive_law`) for the nominal voltage at a frequency, the frequencies it
reaches within its voltage limit, its drive state over a schedule, and whether an overdrive
kick or a reverse-drive brake exists, instead of assuming the ERM. The solver's actuator
classes (``fem.actuators``) take their drive dynamics and defaults from the same classes.

Each law is one module of this package, registered under its actuator's ``load.kind`` name
(``"unit"`` for the coin ERM, ``"lra"``) by :func:`register`; numpy only, nothing of the
project (errors are ValueError naming the field; callers turn them into their FieldError).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import fields, is_dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

__all__ = ["DRIVES", "DriveLaw", "drive_law", "drive_law_class", "register"]


class DriveLaw:
    """One actuator kind's drive dynamics (subclasses are frozen dataclasses of parameters).

    Attributes:
        kind: the actuator's ``load.kind`` name (the registry key).
        title: what it is, for messages.
        noun: what a message calls it ("the motor's 4.5 V limit").
        overdrive: a kick above the nominal voltage shortens its rise (and ends when the drive
            state reaches its nominal value).
        brake: a reverse drive (reversed polarity or phase) stops it, ending at rest.
        carrier: the device drives an AC carrier at the drive frequency (True) or a DC level
            whose size sets the frequency (False: the ERM).
        state_unit: unit of :meth:`drive_state` (for reports).
        max_voltage_V: the largest |voltage| a schedule may apply, V (a dataclass field).
    """

    kind: ClassVar[str]
    title: ClassVar[str]
    noun: ClassVar[str]
    overdrive: ClassVar[bool] = False
    brake: ClassVar[bool] = False
    carrier: ClassVar[bool] = False
    state_unit: ClassVar[str] = ""
    max_voltage_V: float

    def nominal_voltage_V(self, frequency_hz: float) -> float:
        """The steady drive voltage [V] that gives the nominal vibration at ``frequency_hz``
        (may exceed ``max_voltage_V``: compare with :meth:`band_hz`)."""
        raise NotImplementedError

    def band_hz(self) -> tuple[float, float]:
        """(low, high) [Hz]: the frequencies whose nominal voltage is within the limit."""
        raise NotImplementedError

    def reach_text(self) -> str:
        """The band in words, for a refusal."""
        lo, hi = self.band_hz()
        top = np.floor(hi * 100) / 100
        return f"at most {top:g} Hz" if lo <= 0 else f"{lo:.2f} to {top:g} Hz"

    def describe(self) -> str:
        """The law's numbers in words, for a refusal."""
        raise NotImplementedError

    def drive_state(self, t_s: NDArray, volts: NDArray, frequency_hz: float) -> NDArray:
        """The drive state at the times ``t_s`` (s, increasing, from rest at ``t_s[0]``) for
        ``volts[k]`` (V) held from ``t_s[k]`` to the next time, driven at ``frequency_hz``: the
        quantity an overdrive kick brings to its nominal value and a brake brings to 0 (the
        ERM's speed in rev/s, the LRA's force envelope relative to its rated force)."""
        raise NotImplementedError

    def force_ratio(self, state: NDArray, frequency_hz: float) -> NDArray:
        """The force relative to the nominal force at ``frequency_hz`` [-] at the drive state
        ``state`` (of :meth:`drive_state`)."""
        raise NotImplementedError

    @classmethod
    def from_params(cls, params: Mapping[str, Any]) -> DriveLaw:
        """The law with ``params`` (field name -> value; others default); ValueError naming an
        unknown parameter."""
        names = [f.name for f in fields(cls)] if is_dataclass(cls) else []
        unknown = sorted(set(params) - set(names))
        if unknown:
            raise ValueError(f"{cls.kind}.{unknown[0]}: unknown drive-law parameter (allowed: "
                             f"{names})")
        return cls(**params)

    def params(self) -> dict[str, float]:
        """The law's parameters (field name -> value)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}  # type: ignore[arg-type]


DRIVES: dict[str, type[DriveLaw]] = {}
"""Actuator ``load.kind`` name -> its drive law class (filled by :func:`register`)."""


def register(cls: type[DriveLaw]) -> type[DriveLaw]:
    """Class decorator: list ``cls`` in :data:`DRIVES` under ``cls.kind``."""
    if cls.kind in DRIVES:
        raise ValueError(f"drive law {cls.kind!r} registered twice")
    DRIVES[cls.kind] = cls
    return cls


def drive_law_class(kind: str) -> type[DriveLaw]:
    """The drive law class of actuator ``kind``; ValueError naming the kinds that have one."""
    try:
        return DRIVES[str(kind)]
    except KeyError:
        raise ValueError(f"actuator {kind!r} has no drive law (actuators with one: "
                         f"{sorted(DRIVES)})") from None


def drive_law(kind: str, params: Mapping[str, Any] | None = None) -> DriveLaw:
    """The drive law of actuator ``kind`` with ``params`` (defaults otherwise)."""
    return drive_law_class(kind).from_params(params or {})
