"""Driving a planned array: the device interface and its back ends (``serial``, ``sim``,
``log``), the frame protocol, the pattern file, and the host-side safety limits.

    from hardware import (build_schedule, load_pattern, load_plan, open_device, preflight,
                          resolve_limits)
    plan = load_plan("out/plan.json")              # plan.record: sealed / edited / unsealed
    schedule = build_schedule(load_pattern("examples/pattern-sweep.toml"), plan)
    limits = resolve_limits(plan.frequency_hz)     # the actuator's (then device, user: below)
    preflight(plan, schedule, limits)              # refuses what asks beyond them
    with open_device("sim", plan, Path("out/play"), limits.limits) as dev:
        dev.play(schedule)

The limits come from the device, the actuator's rated values and the user, never from the plan
(:mod:`hardware.limits`, docs/protocol.md).

The run-time path only: numpy, onnxruntime (through ``surrogate.runtime``), pyserial for the
serial port, matplotlib for the simulated array's figures; never the FE solver, torch or
scikit-learn (an import-linter contract).
"""

from hardware.backends import DEVICE_KINDS, open_device, parse_device
from hardware.device import Device, DeviceError, DeviceRefused, PlaybackInterrupted
from hardware.heartbeat import Heartbeat
from hardware.limits import ERM_RATING, ActuatorRating, DeviceLimits, preflight, resolve_limits
from hardware.pattern import Pattern, PatternError, Step, load_pattern, pattern_from_dict
from hardware.safety import ExposureMeter, SafetyError, SafetyLimits
from hardware.schedule import (
    TIMING_KEYS,
    PlanFile,
    PlanFileError,
    Schedule,
    build_schedule,
    load_plan,
    plan_from_dict,
)

__all__ = ["DEVICE_KINDS", "ERM_RATING", "TIMING_KEYS", "ActuatorRating", "Device",
           "DeviceError", "DeviceLimits", "DeviceRefused", "ExposureMeter", "Heartbeat",
           "Pattern", "PatternError", "PlanFile", "PlanFileError", "PlaybackInterrupted",
           "SafetyError", "SafetyLimits", "Schedule", "Step", "build_schedule", "load_pattern",
           "load_plan", "open_device", "parse_device", "pattern_from_dict", "plan_from_dict",
           "preflight", "resolve_limits"]
