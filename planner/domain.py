"""One validity domain per plan, and which drive frequencies the actuator can reach.

A plan uses up to two models: the harmonic surrogate (``[model] path``: amplitudes and
profiles) and the transient envelope ROM (``[timing] model``: rise, decay, overdrive, brake,
inter-stimulus interval). Each was trained on its own box of inputs; the plan's *domain* is
their intersection, input by input (:func:`build_domain`): a value inside the harmonic
model's range but outside the ROM's is outside the domain. Every value of the request is
checked against it before anything is predicted (:func:`check_value`), naming the field:

* the wrong type or choice (``orientation = "sideways"``, ``n_rings = 1.5``, a number written
  as text) is a :class:`planner.layout.LayoutError` saying what is allowed;
* a value outside the domain is refused with the range and the model(s) it exceeds, unless
  ``model.allow_extrapolation = true``; then it is an :class:`Extrapolation`, flagged on the
  candidates, the timing and in the plan's summary.

Drive reach (:func:`drive_reach`): the actuator's drive law (``motorlaw``) gives the nominal
voltage at a frequency and the voltage limit. An ERM's speed is set by its voltage: its
steady-speed law (``motorlaw.SpeedLaw``: ``V = V_start + f (V_rated - V_start) / f_rated``,
120 rev/s at 3.3 V, stiction below 0.4 V) and its voltage limit (4.5 V) give the highest
frequency it reaches (169.66 Hz for those numbers); an LRA reaches a band about its resonance
(``motorlaw.ResonantDrive``). A frequency outside the reach is not a candidate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

from planner.layout import LayoutError, short_repr
from surrogate.runtime.encoding import InputSpec

__all__ = ["Bound", "Domain", "Extrapolation", "build_domain", "check_value", "drive_reach"]


@dataclass(frozen=True)
class Bound:
    """The allowed values of one input: a numeric range or a set of choices, with each
    model's own range (``sources``: model -> [low, high] or its choices)."""

    name: str
    type: str  # "continuous" | "integer" | "categorical"
    low: float | None = None
    high: float | None = None
    choices: tuple[str, ...] = ()
    unit: str = ""
    sources: dict[str, Any] = field(default_factory=dict)

    def allowed(self) -> str:
        """Human-readable allowed values."""
        if self.type == "categorical":
            return "one of " + ", ".join(repr(c) for c in self.choices)
        unit = f" {self.unit}" if self.unit else ""
        what = "an integer" if self.type == "integer" else "a number"
        return f"{what} in [{self.low:.4g}, {self.high:.4g}]{unit}"

    def limited_by(self, value: float) -> list[str]:
        """The models whose own range excludes ``value``."""
        return [m for m, r in self.sources.items()
                if not isinstance(r[0], str) and not r[0] <= value <= r[1]]

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {"type": self.type}
        if self.type == "categorical":
            d["choices"] = list(self.choices)
        else:
            d.update(low=self.low, high=self.high, unit=self.unit)
        d["models"] = {m: list(r) for m, r in self.sources.items()}
        return d


@dataclass(frozen=True)
class Extrapolation:
    """A request value outside the plan's domain (allowed by ``allow_extrapolation``)."""

    field: str
    value: float
    low: float
    high: float
    models: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]:
        return {"field": self.field, "value": self.value, "domain": [self.low, self.high],
                "models": list(self.models)}

    def __str__(self) -> str:
        return (f"{self.field} = {self.value:g} outside [{self.low:.4g}, {self.high:.4g}] "
                f"({', '.join(self.models)})")


@dataclass(frozen=True)
class Domain:
    """The intersection of the ranges of every model a plan uses (``models``)."""

    bounds: dict[str, Bound]
    models: tuple[str, ...]

    def narrowed_specs(self, specs: list[InputSpec]) -> list[InputSpec]:
        """The harmonic model's input specs with their ranges cut to the domain (candidates
        of ``any = true`` are drawn from these)."""
        out = []
        for s in specs:
            b = self.bounds[s.name]
            out.append(replace(s, choices=b.choices) if s.type == "categorical" else
                       replace(s, low=b.low, high=b.high))
        return out

    def to_dict(self) -> dict[str, Any]:
        return {"models": list(self.models),
                "inputs": {n: b.to_dict() for n, b in self.bounds.items()}}


def build_domain(predictor: Any, model_path: str, rom: Any = None,
                 rom_path: str | None = None) -> Domain:
    """The domain of the harmonic ``predictor`` (a run-time :class:`Predictor`) intersected
    with the envelope ROM ``rom`` (an ``EnvelopeModel``, or None without timing)."""
    bounds: dict[str, Bound] = {}
    for s in predictor.specs:
        own: Any = tuple(s.choices) if s.type == "categorical" else (float(s.low),
                                                                     float(s.high))
        bounds[s.name] = Bound(s.name, s.type, None if s.type == "categorical" else own[0],
                               None if s.type == "categorical" else own[1],
                               tuple(s.choices), s.unit, {model_path: own})
    models = [model_path]
    if rom is not None:
        models.append(str(rom_path))
        for name, rng in rom.input_ranges.items():
            rng = tuple(rng)
            b = bounds.get(name)
            if b is None:  # the ROM's own inputs (motor time constants)
                bounds[name] = Bound(name, "continuous", float(rng[0]), float(rng[1]),
                                     unit="ms" if name.endswith("_ms") else "",
                                     sources={str(rom_path): rng})
            elif b.type == "categorical":
                keep = tuple(c for c in b.choices if c in rng)
                bounds[name] = Bound(name, b.type, choices=keep, unit=b.unit,
                                     sources={**b.sources, str(rom_path): rng})
            else:
                bounds[name] = Bound(name, b.type, max(b.low, float(rng[0])),
                                     min(b.high, float(rng[1])), (), b.unit,
                                     {**b.sources, str(rom_path): rng})
    return Domain(bounds, tuple(models))


def check_value(bound: Bound, value: Any, where: str,
                allow_extrapolation: bool) -> Extrapolation | None:
    """Check one request value against its domain bound; raises :class:`LayoutError` naming
    ``where`` for a wrong type or choice, and for a value outside the domain unless
    ``allow_extrapolation`` (then the :class:`Extrapolation` is returned)."""
    if bound.type == "categorical":
        if not isinstance(value, str) or value not in bound.choices:
            raise LayoutError(where, f"{where} = {short_repr(value)}: expected "
                              f"{bound.allowed()}")
        return None
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise LayoutError(where, f"{where} = {short_repr(value)}: expected {bound.allowed()}")
    x = float(value)
    if not math.isfinite(x):
        raise LayoutError(where, f"{where} = {value!r}: expected a finite number; allowed "
                          f"{bound.allowed()}")
    if bound.type == "integer" and x != round(x):
        raise LayoutError(where, f"{where} = {value!r}: expected {bound.allowed()}")
    if bound.low <= x <= bound.high:  # type: ignore[operator]
        return None
    models = bound.limited_by(x)
    if not allow_extrapolation or bound.type == "integer":
        advice = ("" if bound.type == "integer" else "; set model.allow_extrapolation = true "
                  "to plan outside it (flagged in the plan)")
        ranges = "; ".join(f"{m}: [{r[0]:.4g}, {r[1]:.4g}]" for m, r in bound.sources.items())
        unit = f" {bound.unit}" if bound.unit else ""
        raise LayoutError(where, f"{where} = {x:g} is outside the plan's validity domain "
                          f"[{bound.low:.4g}, {bound.high:.4g}]{unit} (the intersection of the "
                          f"models' trained ranges: {ranges}){advice}")
    return Extrapolation(where, x, float(bound.low), float(bound.high),  # type: ignore[arg-type]
                         tuple(models))


def drive_reach(law: Any, frequency_hz: float) -> dict[str, Any] | None:
    """None when the actuator's drive law ``law`` (``motorlaw.DriveLaw``: the ERM's
    ``SpeedLaw``, an LRA's ``ResonantDrive``) reaches ``frequency_hz`` within its voltage
    limit; else why not, with the law's numbers."""
    volts = law.nominal_voltage_V(frequency_hz)
    if volts <= law.max_voltage_V:
        return None
    top = law.band_hz()[1]
    return {"frequency_hz": frequency_hz, "needs_V": round(volts, 4),
            "limit_V": law.max_voltage_V,
            "max_frequency_hz": math.floor(top * 100) / 100 if math.isfinite(top) else None,
            "reason": f"{frequency_hz:g} Hz needs {volts:.3f} V, above the {law.noun}'s "
                      f"{law.max_voltage_V:g} V limit ({law.describe()}; "
                      f"{law.reach_text()})"}
