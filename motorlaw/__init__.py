"""The actuators' drive laws, defined once (numpy only; imports nothing of the project).

:mod:`motorlaw.erm` is the coin ERM's speed law: the solver (``fem.motor``: the unbalance
force m e omega^2 of the transient analysis) and the run-time envelope model
(``surrogate.runtime.rom``) both call its functions, so the speed the FE transients are driven
with and the speed the model predicts are the same law with the same defaults
(:data:`DEFAULTS`). :mod:`motorlaw.lra` is the LRA's resonant drive. Every law is registered
under its actuator's ``load.kind`` name in :data:`DRIVES` (:mod:`motorlaw.drive`); the run-time
side asks :func:`drive_law` instead of assuming the ERM. Adding an actuator's law is adding one
module here: every module of the package is imported below and registers itself.
"""

import importlib
import pkgutil

from motorlaw.drive import DRIVES, DriveLaw, drive_law, drive_law_class, register
from motorlaw.erm import (
    DEFAULTS,
    TWO_PI,
    LawLike,
    SpeedLaw,
    VoltageSchedule,
    check_law,
    held_speed_and_phase,
    max_frequency_hz,
    phase,
    rise_time_s,
    simulate_speed,
    speed_and_phase,
    speed_per_volt,
    speed_rate,
    steady_frequency_hz,
    target_speed_rad_s,
    voltage_for_frequency,
)
from motorlaw.lra import ResonantDrive

__all__ = ["DEFAULTS", "DRIVES", "TWO_PI", "DriveLaw", "LawLike", "ResonantDrive", "SpeedLaw",
           "VoltageSchedule", "check_law", "drive_law", "drive_law_class",
           "held_speed_and_phase", "max_frequency_hz", "phase", "register", "rise_time_s",
           "simulate_speed", "speed_and_phase", "speed_per_volt", "speed_rate",
           "steady_frequency_hz", "target_speed_rad_s", "voltage_for_frequency"]

for _module in pkgutil.iter_modules(__path__):
    importlib.import_module(f"{__name__}.{_module.name}")
