"""Opening a device by name: ``sim``, ``log`` or ``serial:PORT`` (the ``--device`` option)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from hardware.device import Device
from hardware.safety import ExposureMeter, SafetyLimits
from hardware.schedule import PlanFile

__all__ = ["DEVICE_KINDS", "open_device", "parse_device"]

DEVICE_KINDS = ("sim", "log", "serial:PORT")


def parse_device(text: str) -> tuple[str, str | None]:
    """``"sim"`` -> ("sim", None); ``"serial:/dev/ttyACM0"`` -> ("serial", "/dev/ttyACM0")."""
    kind, _, port = text.partition(":")
    if kind in ("sim", "log") and not port:
        return kind, None
    if kind == "serial" and port:
        return kind, port
    raise ValueError(f"--device {text!r}: choose one of {', '.join(DEVICE_KINDS)}")


def open_device(text: str, plan: PlanFile, out_dir: Path | None,
                limits: SafetyLimits | None = None,
                exposure: ExposureMeter | None = None, record: Any = None) -> Device:
    """The device ``text`` names, sized to the plan; ``sim`` and ``log`` write into
    ``out_dir`` (``field-peak.png`` and ``field.gif``; ``commands.jsonl``); ``serial`` keeps
    its session's events in ``record`` (a :class:`hardware.playback.JsonLines`) if given."""
    kind, port = parse_device(text)
    if kind == "serial":
        from hardware.serial_device import SerialDevice

        return SerialDevice(port, plan.n_sites, limits, exposure, record=record)
    if out_dir is None:
        raise ValueError(f"--device {kind} writes files: give --out DIR")
    if kind == "log":
        from hardware.log_device import LogDevice

        return LogDevice(out_dir / "commands.jsonl", plan.n_sites, limits, exposure)
    from hardware.sim import SimDevice, unit_field

    return SimDevice(out_dir, unit_field(plan), plan.positions_mm, limits, exposure,
                     plan.frequency_hz)
