"""The ERM motor's speed law, defined once (numpy only; imports nothing of the project).

The solver (``fem.motor``: the unbalance force m e omega^2 of the transient analysis) and the
run-time envelope model (``surrogate.runtime.rom``) both call these functions, so the speed the
FE transients are driven with and the speed the model predicts are the same law with the same
defaults (:data:`DEFAULTS`, sources in :mod:`motorlaw.erm`).
"""

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

__all__ = ["DEFAULTS", "TWO_PI", "LawLike", "SpeedLaw", "VoltageSchedule", "check_law",
           "held_speed_and_phase", "max_frequency_hz", "phase", "rise_time_s",
           "simulate_speed", "speed_and_phase", "speed_per_volt", "speed_rate",
           "steady_frequency_hz", "target_speed_rad_s", "voltage_for_frequency"]
