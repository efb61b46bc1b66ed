"""The registry of devices: ``--device`` name -> :class:`DeviceKind` (``sim``, ``log``,
``serial:PORT``).

This is the one place that lists the devices; ``hapticrom play`` asks a kind what it is
(whether it writes files, keeps a refused session, drives a live array) and never its name.
Every kind opens with one signature, ``open(DeviceRequest) -> Device``. Adding a device is one
module with its :class:`hardware.device.Device` subclass plus its line in :data:`DEVICES`
(docs/architecture.md).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fieldspec import FieldError
from hardware.device import Device
from hardware.log_device import LogDevice
from hardware.playback import JsonLines
from hardware.safety import ExposureMeter, SafetyLimits
from hardware.schedule import PlanFile
from hardware.serial_device import SerialDevice
from hardware.sim import SimDevice, unit_field

__all__ = ["DEVICES", "DEVICE_KINDS", "DeviceKind", "DeviceRequest", "device_kind",
           "open_device", "parse_device"]


@dataclass(frozen=True)
class DeviceRequest:
    """Everything a device may be opened with: the ``port`` (``serial:PORT``; None for a
    device without one), the plan it plays (channels, positions, frequency), the directory it
    writes into (devices that write files), the limits, the exposure meter, and the session
    record (a :class:`hardware.playback.JsonLines`, live devices)."""

    port: str | None
    plan: PlanFile
    out_dir: Path | None = None
    limits: SafetyLimits | None = None
    exposure: ExposureMeter | None = None
    record: JsonLines | None = None


@dataclass(frozen=True)
class DeviceKind:
    """One kind of device, registered once in :data:`DEVICES`.

    Attributes:
        name: the ``--device`` name (``serial`` is written ``serial:PORT``).
        summary: one line for ``--help`` and docs.
        open: ``open(DeviceRequest) -> Device``.
        needs_port: the name takes ``:PORT``.
        writes_files: it writes its output into ``--out`` (required; written atomically).
        keeps_refusal: its files are kept when the session is refused (a record of it).
        live: it drives an array: a heartbeat while playing, the day's exposure persisted
            (``--exposure-file``), a ``session-*.jsonl`` record in ``--out`` if given, a lost
            link reported as a cut-short playback.
    """

    name: str
    summary: str
    open: Callable[[DeviceRequest], Device]
    needs_port: bool = False
    writes_files: bool = False
    keeps_refusal: bool = False
    live: bool = False

    @property
    def usage(self) -> str:
        """How ``--device`` spells it."""
        return f"{self.name}:PORT" if self.needs_port else self.name


def _out(req: DeviceRequest, name: str) -> Path:
    if req.out_dir is None:
        raise FieldError("--out", f"--device {name} writes files: give --out DIR")
    return req.out_dir


def _open_sim(req: DeviceRequest) -> Device:
    return SimDevice(_out(req, "sim"), unit_field(req.plan), req.plan.positions_mm, req.limits,
                     req.exposure, req.plan.frequency_hz)


def _open_log(req: DeviceRequest) -> Device:
    return LogDevice(_out(req, "log") / "commands.jsonl", req.plan.n_sites, req.limits,
                     req.exposure)


def _open_serial(req: DeviceRequest) -> Device:
    return SerialDevice(req.port, req.plan.n_sites, req.limits, req.exposure,
                        record=req.record)


#: Every device, by name, in the order ``--help`` lists them.
DEVICES: dict[str, DeviceKind] = {k.name: k for k in (
    DeviceKind("sim", "render the skin field (field-peak.png, field.gif)", _open_sim,
               writes_files=True),
    DeviceKind("log", "write the commands (commands.jsonl), a refusal included", _open_log,
               writes_files=True, keeps_refusal=True),
    DeviceKind("serial", "drive the array over a serial port (docs/protocol.md)", _open_serial,
               needs_port=True, live=True),
)}
#: How ``--device`` spells each kind.
DEVICE_KINDS = tuple(k.usage for k in DEVICES.values())


def device_kind(text: str) -> tuple[DeviceKind, str | None]:
    """``"sim"`` -> (the sim kind, None); ``"serial:/dev/ttyACM0"`` -> (serial, the port).
    A :class:`fieldspec.FieldError` on ``--device`` naming the choices otherwise."""
    name, _, port = text.partition(":")
    kind = DEVICES.get(name)
    if kind is None or kind.needs_port != bool(port):
        raise FieldError("--device", f"--device {text!r}: choose one of "
                         f"{', '.join(DEVICE_KINDS)}")
    return kind, port or None


def parse_device(text: str) -> tuple[str, str | None]:
    """``"sim"`` -> ("sim", None); ``"serial:/dev/ttyACM0"`` -> ("serial", "/dev/ttyACM0")."""
    kind, port = device_kind(text)
    return kind.name, port


def open_device(text: str, plan: PlanFile, out_dir: Path | None,
                limits: SafetyLimits | None = None,
                exposure: ExposureMeter | None = None, record: Any = None) -> Device:
    """The device ``text`` names, sized to the plan (:class:`DeviceRequest` says what each
    argument is for)."""
    kind, port = device_kind(text)
    return kind.open(DeviceRequest(port, plan, out_dir, limits, exposure, record))
