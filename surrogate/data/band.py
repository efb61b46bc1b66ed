"""Data made of sweeps: a parameter space's ``[band]`` instead of a frequency input.

::

    [band]
    start = 100.0     # Hz
    stop = 250.0      # Hz (included when it lies on the grid)
    step = 2.0        # Hz
    tolerance = 0.01  # optional: the sweep's error tolerance (default: the scene's, 1e-3)

Every design point of such a space becomes one sweep scene (``analysis.kind = "sweep"``,
``analysis.frequency_hz = {start, stop, step}``) and one dataset row holding the complex
response over the whole band (columns in :mod:`surrogate.data.columns`). No parameter may
write ``analysis.frequency_hz`` or ``analysis.kind`` (the band sets them).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from fieldspec import REQUIRED, Context, Spec, read_table
from surrogate.data.errors import SpaceError

__all__ = ["MAX_BAND_FREQUENCIES", "Band", "read_band"]

#: Most frequencies per row (each row stores every one of them).
MAX_BAND_FREQUENCIES = 2000
_BAND = {
    "start": Spec(float, REQUIRED, "(0, 1e5]"),
    "stop": Spec(float, REQUIRED, "(0, 1e5]"),
    "step": Spec(float, REQUIRED, "(0, 1e5]"),
    "tolerance": Spec(float, None, "[1e-6, 0.1]"),
}
#: Scene fields the band owns.
BAND_PATHS = ("analysis.frequency_hz", "analysis.kind", "analysis.tolerance")


@dataclass(frozen=True)
class Band:
    """A frequency band [Hz]: ``start, start + step, ...`` up to ``stop``."""

    start: float
    stop: float
    step: float
    tolerance: float | None = None  # the sweep's relative error tolerance; None: the scene's

    @property
    def frequencies_hz(self) -> tuple[float, ...]:
        """The grid, each value rounded to 1e-9 Hz (the same band gives the same floats)."""
        n = math.floor((self.stop - self.start) / self.step + 1e-9) + 1
        return tuple(round(self.start + self.step * i, 9) for i in range(n))

    def to_dict(self) -> dict[str, float]:
        """The ``[band]`` table (``tolerance`` only when set: older space hashes hold)."""
        out = {"start": self.start, "stop": self.stop, "step": self.step}
        return out if self.tolerance is None else out | {"tolerance": self.tolerance}

    def apply(self, scene: dict[str, Any]) -> None:
        """Make ``scene`` (a TOML-shaped dict) a sweep over this band, in place."""
        analysis = scene.setdefault("analysis", {})
        analysis["kind"] = "sweep"
        analysis["frequency_hz"] = {"start": self.start, "stop": self.stop, "step": self.step}
        if self.tolerance is not None:
            analysis["tolerance"] = self.tolerance


def read_band(raw: Any) -> Band:
    """Validate a ``[band]`` table (:class:`SpaceError` naming the field and the range)."""
    ctx = Context(SpaceError)
    if not isinstance(raw, Mapping):
        raise SpaceError("band", f"band must be a table {{start, stop, step}} in Hz, got "
                         f"{type(raw).__name__}")
    got = read_table(raw, _BAND, "band", ctx)
    if not got["stop"] > got["start"]:
        raise SpaceError("band.stop", f"band.stop = {got['stop']!r} is out of range: allowed "
                         f"stop > start (= {got['start']:g} Hz)")
    count = (got["stop"] - got["start"]) / got["step"] + 1
    if count > MAX_BAND_FREQUENCIES:
        raise SpaceError("band.step", f"band.step = {got['step']!r} gives {count:.4g} "
                         f"frequencies per row: allowed step >= "
                         f"{(got['stop'] - got['start']) / (MAX_BAND_FREQUENCIES - 1):.4g} Hz "
                         f"(at most {MAX_BAND_FREQUENCIES})")
    return Band(start=got["start"], stop=got["stop"], step=got["step"],
                tolerance=got.get("tolerance"))


def check_band_parameters(parameters: Any) -> None:
    """No parameter may write a field the band owns."""
    for p in parameters:
        for path in p.paths:
            if path in BAND_PATHS:
                raise SpaceError(f"parameter {p.name}.path",
                                 f"parameter {p.name!r} writes {path}, which the space's "
                                 "[band] sets (every row is a sweep over the band): remove "
                                 "the parameter or the [band]")
