"""The device interface every back end implements, with the host-side safety rules applied
once, here, before a back end sees a command.

    with open_device("sim", n_channels=16, ...) as dev:   # stops every channel on exit,
        dev.play(schedule)                                 # on error and on Ctrl-C
        print(dev.status())

A back end implements the ``_set_levels``, ``_play``, ``_stop_all``, ``_heartbeat``,
``_status`` and ``_close`` primitives; the public methods clamp levels
(:func:`hardware.safety.clamp_levels`), check a schedule's on-time and duty cycle
(:func:`hardware.safety.check_schedule`) and its daily exposure
(:class:`hardware.safety.ExposureMeter`), and track the on-time of levels set directly.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from types import TracebackType
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from fieldspec import FieldError, WorkError
from hardware.protocol import Segment, Status
from hardware.safety import ExposureMeter, OnTimeGuard, SafetyLimits, check_schedule, clamp_levels

if TYPE_CHECKING:
    from hardware.limits import DeviceLimits
from hardware.schedule import Schedule

__all__ = ["Device", "DeviceError", "DeviceRefused", "PlaybackInterrupted"]


class DeviceError(WorkError):
    """The link to the device failed (no acknowledgement, disconnected, refused)."""


class DeviceRefused(FieldError):
    """The device refused a command before anything of it was played (a NAK naming why):
    bad input for this device, not a failure of the link (``field`` is ``device``)."""

    def __init__(self, message: str, code: str) -> None:
        super().__init__("device", message)
        self.code = code


class PlaybackInterrupted(DeviceError):
    """The schedule was cut short (watchdog or on-time stop reported by the device, lost
    link, NAK while playing); ``report`` says what was and was not played
    (:func:`hardware.playback.playback_report`)."""

    def __init__(self, report: dict[str, Any]) -> None:
        super().__init__(report["summary"])
        self.report = report


class Device(ABC):
    """An array of ``n_channels`` actuators behind the safety limits."""

    #: whether the device needs a host heartbeat (a real link with a watchdog)
    needs_heartbeat = False

    def __init__(self, n_channels: int, limits: SafetyLimits | None = None,
                 exposure: ExposureMeter | None = None) -> None:
        if not 1 <= n_channels <= 255:
            raise ValueError(f"n_channels = {n_channels}: allowed 1 <= n_channels <= 255")
        self.n_channels = n_channels
        self.limits = limits or SafetyLimits()
        self.exposure = exposure
        self.guard = OnTimeGuard(self.limits)
        self.closed = False
        self._accrued_ms = 0.0  # how much of the schedule playing now has been dosed

    def reported_limits(self) -> DeviceLimits | None:
        """The limits the device reports of itself (None: it reports none)."""
        return None

    def set_limits(self, limits: SafetyLimits) -> None:
        """Use ``limits`` from now on (:func:`hardware.limits.resolve_limits`)."""
        self.limits = limits
        self.guard = OnTimeGuard(limits)

    def note(self, event: str, **info: Any) -> None:
        """Record an event (a refusal, an interruption, the plan's integrity) where the back
        end keeps a record (the ``log`` device writes it as a line); others ignore it."""
        return None

    # ---- public API (safety first) ----------------------------------------------------------

    def set_levels(self, levels: NDArray) -> NDArray:
        """Set every channel's level now (clamped); returns the levels sent."""
        x = np.asarray(levels, dtype=float)
        if x.shape != (self.n_channels,):
            raise ValueError(f"levels: {x.size} values for {self.n_channels} channels")
        x = clamp_levels(x, self.limits)
        self._set_levels(x)
        self.guard.update(x, time.monotonic())
        return x

    def play(self, schedule: Schedule) -> list[Segment]:
        """Play ``schedule`` (refused if it breaks a limit); returns the segments sent."""
        if schedule.n_channels > self.n_channels:
            raise ValueError(f"schedule for {schedule.n_channels} channels: the device has "
                             f"{self.n_channels}")
        segs = check_schedule(list(schedule.segments), self.limits)
        amp_m = np.array([s.rendered_um for s in schedule.steps]) * 1e-6
        dur_s = np.array([s.duration_ms for s in schedule.steps]) * 1e-3
        if self.exposure is not None and len(amp_m):
            self.exposure.check(amp_m, schedule.frequency_hz, dur_s)
        self._accrued_ms = 0.0
        self._play(schedule, segs)
        self.accrue(schedule, schedule.total_ms)
        return segs

    def accrue(self, schedule: Schedule, t_ms: float) -> None:
        """Add the exposure of ``schedule`` from where the last call left off up to ``t_ms``
        after its start to the meter (written through to its file): a back end that plays in
        real time calls this as it plays, so a crash loses at most the last interval."""
        if self.exposure is None or t_ms <= self._accrued_ms or not schedule.steps:
            return
        self.exposure.accrue(schedule, self._accrued_ms, t_ms)
        self._accrued_ms = t_ms

    def stop_all(self) -> None:
        """Every channel to zero."""
        self.guard.clear()
        self._stop_all()

    def heartbeat(self) -> None:
        """Tell the device the host is alive; also stops channels set directly that have run
        past the on-time limit."""
        self._heartbeat()
        expired = self.guard.expired(time.monotonic())
        if expired:
            levels = np.array(self.status().levels[:self.n_channels], dtype=float)
            levels[expired] = 0.0
            self.set_levels(levels)

    def status(self) -> Status:
        return self._status()

    @property
    def watchdog_s(self) -> float:
        """The heartbeat deadline the host must keep [s]."""
        return self.limits.watchdog_s

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            self._close()

    def __enter__(self) -> Device:
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        """Stop everything on every way out (normal, error, KeyboardInterrupt), then close."""
        try:
            if not self.closed:
                self.stop_all()
        except Exception:  # the link is gone: the device's watchdog stops it
            if kind is None:
                raise
        finally:
            self.close()

    # ---- back-end primitives ------------------------------------------------------------------

    @abstractmethod
    def _set_levels(self, levels: NDArray) -> None: ...

    @abstractmethod
    def _play(self, schedule: Schedule, segments: list[Segment]) -> None: ...

    @abstractmethod
    def _stop_all(self) -> None: ...

    @abstractmethod
    def _heartbeat(self) -> None: ...

    @abstractmethod
    def _status(self) -> Status: ...

    @abstractmethod
    def _close(self) -> None: ...
