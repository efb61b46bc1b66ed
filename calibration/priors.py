"""Priors of the fitted model inputs.

Default: uniform over the model's trained range on the input's own scale, i.e. log-uniform for
a log-scale input (``scale = "log"`` in the model card: a positive scale parameter such as a
modulus) and uniform for a linear one. Given ones (``--prior NAME=KIND:A,B``)::

    uniform:LOW,HIGH        uniform on [LOW, HIGH]
    loguniform:LOW,HIGH     uniform in log on [LOW, HIGH] (LOW > 0)
    normal:MEAN,SD          Gaussian, truncated to the model's range

Every prior is truncated to the model's range: the surrogate is not evaluated outside it. The
sampler works in the coordinate ``z`` (log x for log-uniform, x otherwise), in which uniform
priors are flat.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fieldspec import FieldError

__all__ = ["KINDS", "Prior", "PriorError", "default_prior", "parse_prior", "priors_for"]

KINDS = ("uniform", "loguniform", "normal")


class PriorError(FieldError):
    """A bad prior or fitted-input choice (``.field`` names the input)."""


@dataclass(frozen=True)
class Prior:
    """The prior of one input, in the model's units; ``low``/``high`` bound its support
    (within the model's range)."""

    name: str
    kind: str
    low: float
    high: float
    mean: float | None = None  # normal only
    sd: float | None = None  # normal only
    unit: str = ""

    @property
    def log(self) -> bool:
        """Whether the sampling coordinate is log x."""
        return self.kind == "loguniform"

    def to_z(self, x: np.ndarray) -> np.ndarray:
        """Model units -> sampling coordinate."""
        return np.log(x) if self.log else np.asarray(x, dtype=float)

    def from_z(self, z: np.ndarray) -> np.ndarray:
        """Sampling coordinate -> model units."""
        return np.exp(z) if self.log else np.asarray(z, dtype=float)

    @property
    def z_bounds(self) -> tuple[float, float]:
        return float(self.to_z(np.array(self.low))), float(self.to_z(np.array(self.high)))

    def log_density_z(self, z: np.ndarray) -> np.ndarray:
        """Unnormalised log prior density in z (-inf outside the support)."""
        lo, hi = self.z_bounds
        inside = (z >= lo) & (z <= hi)
        val = np.zeros_like(z, dtype=float)
        if self.kind == "normal":
            val = -0.5 * ((z - self.mean) / self.sd) ** 2
        return np.where(inside, val, -np.inf)

    def sample_z(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """``n`` draws in z (a truncated normal by rejection)."""
        lo, hi = self.z_bounds
        if self.kind != "normal":
            return rng.uniform(lo, hi, n)
        out = np.empty(0)
        while out.size < n:
            z = rng.normal(self.mean, self.sd, 4 * n + 16)
            out = np.concatenate([out, z[(z >= lo) & (z <= hi)]])
        return out[:n]

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {"kind": self.kind, "low": self.low, "high": self.high,
                             "unit": self.unit}
        if self.kind == "normal":
            d.update(mean=self.mean, sd=self.sd)
        return d


def default_prior(spec: Any) -> Prior:
    """Uniform (log-uniform for a log-scale input) over the model's range of ``spec``
    (a :class:`surrogate.runtime.encoding.InputSpec`)."""
    kind = "loguniform" if spec.scale == "log" else "uniform"
    return Prior(spec.name, kind, float(spec.low), float(spec.high), unit=spec.unit)


def parse_prior(text: str, specs: Mapping[str, Any]) -> Prior:
    """``NAME=KIND:A,B`` (see the module docstring) against the model's inputs ``specs``."""
    name, sep, rest = text.partition("=")
    name = name.strip()
    if not sep or name not in specs:
        raise PriorError("--prior", f"--prior {text!r}: expected NAME=KIND:A,B with NAME a "
                         f"continuous input of the model ({', '.join(specs)})")
    spec = specs[name]
    kind, _, args = rest.partition(":")
    kind = kind.strip()
    try:
        a, b = (float(x) for x in args.split(","))
    except ValueError:
        a = b = math.nan
    if kind not in KINDS or not (math.isfinite(a) and math.isfinite(b)):
        raise PriorError(f"--prior {name}", f"--prior {text!r}: expected KIND:A,B with KIND "
                         f"one of {', '.join(KINDS)} and two numbers")
    lo, hi = float(spec.low), float(spec.high)
    where = f"--prior {name}"
    if kind == "normal":
        if b <= 0:
            raise PriorError(where, f"{where}: the standard deviation {b:g} must be > 0")
        return Prior(name, kind, lo, hi, a, b, spec.unit)
    if not lo <= a < b <= hi:
        raise PriorError(where, f"{where}: [{a:g}, {b:g}] must be an interval inside the "
                         f"model's range [{lo:g}, {hi:g}] {spec.unit}".rstrip())
    return Prior(name, kind, a, b, unit=spec.unit)


def priors_for(fit: Sequence[str], specs: Sequence[Any], given: Sequence[str] = ()
               ) -> list[Prior]:
    """The prior of every fitted input: given ones (``NAME=KIND:A,B``) or the default. Each
    fitted name must be a continuous input of the model."""
    by_name = {s.name: s for s in specs}
    cont = {s.name: s for s in specs if s.type == "continuous" and s.name != "frequency_hz"}
    if not fit:
        raise PriorError("--fit", "--fit: name at least one input to fit")
    for name in fit:
        if name not in cont:
            what = "not an input of the model" if name not in by_name else (
                "not a continuous input")
            raise PriorError("--fit", f"--fit {name}: {what} (continuous inputs: "
                             f"{', '.join(cont)})")
    if len(set(fit)) != len(fit):
        raise PriorError("--fit", f"--fit {','.join(fit)}: a name is given twice")
    chosen = {n: default_prior(cont[n]) for n in fit}
    for text in given:
        p = parse_prior(text, cont)
        if p.name not in chosen:
            raise PriorError(f"--prior {p.name}", f"--prior {p.name}: not a fitted input "
                             f"(--fit {','.join(fit)})")
        chosen[p.name] = p
    return [chosen[n] for n in fit]
