"""The space of units searched, as a box of numbers every optimiser can walk.

A point ``x`` holds, in this order: the orientation's index, the attachment's index, the
index of the ring count, one entry per ring slot (the silicone's index in the catalogue, or
log10 of the ring's Young's modulus [kPa] when materials are continuous) and, continuous
only, the rings' density [kg/m^3], Poisson's ratio and log10 of their loss factor where the
catalogue's range is not a single value. Integer entries are rounded, every entry clipped to
its bounds (:meth:`DesignSpace.decode`). A ring slot beyond the unit's ring count is unused
(the model ignores it): decoding sets it to a fixed value, so every point maps to one
canonical design (:meth:`DesignSpace.key`) and repeated points are evaluated once.

Continuous ranges are the catalogue's (its softest to its stiffest silicone, its lowest to its
highest density ...), cut to the plan's validity domain.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.design.catalogue import RING_SLOTS, ring_inputs
from planner.design.request import SpaceSpec
from planner.domain import Domain

__all__ = ["DesignSpace", "Dimension"]

SHARED = ("ring_density_kg_m3", "ring_nu", "ring_loss_factor")
_ATTR = {"ring_density_kg_m3": "density_kg_m3", "ring_nu": "nu",
         "ring_loss_factor": "loss_factor"}
_LOG = ("ring_loss_factor",)


@dataclass(frozen=True)
class Dimension:
    """One entry of a point: integer (an index into ``choices``) or continuous in
    [low, high]; ``min_rings``: used only by units with at least that many rings."""

    name: str
    low: float
    high: float
    integer: bool
    choices: tuple[Any, ...] = ()
    min_rings: int = 0


class DesignSpace:
    """The request's space (:class:`planner.design.request.SpaceSpec`) on the plan's domain."""

    def __init__(self, spec: SpaceSpec, domain: Domain) -> None:
        cat = spec.catalogue
        if cat is None:
            raise ValueError("space: no catalogue")
        self.spec, self.catalogue = spec, cat
        self.continuous = spec.materials == "continuous"
        silicones = cat.chosen
        e = self._cut(domain, "ring_1_E_kPa", min(s.E_kPa for s in silicones),
                      max(s.E_kPa for s in silicones))
        self.E_range_kPa = e
        self.fill_E_kPa = silicones[0].E_kPa if not self.continuous else math.sqrt(e[0] * e[1])
        self.shared = {n: self._cut(domain, n, min(getattr(s, _ATTR[n]) for s in silicones),
                                    max(getattr(s, _ATTR[n]) for s in silicones))
                       for n in SHARED}
        dims = [Dimension("orientation", 0, len(spec.orientations) - 1, True,
                          spec.orientations),
                Dimension("attachment", 0, len(spec.attachments) - 1, True, spec.attachments),
                Dimension("n_rings", 0, len(spec.n_rings) - 1, True, spec.n_rings)]
        for k in range(1, RING_SLOTS + 1):
            if max(spec.n_rings) < k:
                continue
            dims.append(Dimension(f"ring_{k}", math.log10(e[0]), math.log10(e[1]), False,
                                  min_rings=k) if self.continuous else
                        Dimension(f"ring_{k}", 0, len(silicones) - 1, True,
                                  tuple(s.name for s in silicones), k))
        if self.continuous and max(spec.n_rings) > 0:
            for n, (lo, hi) in self.shared.items():
                if hi > lo:
                    log = n in _LOG
                    dims.append(Dimension(n, math.log10(lo) if log else lo,
                                          math.log10(hi) if log else hi, False, min_rings=1))
        self.dimensions = tuple(dims)

    @staticmethod
    def _cut(domain: Domain, name: str, lo: float, hi: float) -> tuple[float, float]:
        b = domain.bounds[name]
        lo, hi = max(lo, float(b.low)), min(hi, float(b.high))  # type: ignore[arg-type]
        if lo > hi:
            raise ValueError(f"space.catalogue: the silicones' {name} range lies outside the "
                             f"model's [{b.low:g}, {b.high:g}]")
        return lo, hi

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(low, high, integer mask) of a point's entries."""
        d = self.dimensions
        return (np.array([x.low for x in d], float), np.array([x.high for x in d], float),
                np.array([x.integer for x in d]))

    def decode(self, x: Sequence[float]) -> dict[str, Any]:
        """The model inputs (design part) of point ``x`` (rounded, clipped, canonical)."""
        lo, hi, integer = self.bounds
        v = np.clip(np.asarray(x, dtype=float), lo, hi)
        v = np.where(integer, np.round(v), v)
        at = {d.name: float(v[i]) for i, d in enumerate(self.dimensions)}
        n = self.spec.n_rings[int(at["n_rings"])]
        inputs: dict[str, Any] = {"orientation": self.spec.orientations[int(at["orientation"])],
                                  "attachment": self.spec.attachments[int(at["attachment"])],
                                  "n_rings": n}
        if not self.continuous:
            rings = [self.catalogue.chosen[int(at[f"ring_{k}"])] for k in range(1, n + 1)]
            return inputs | ring_inputs(rings, self.fill_E_kPa)
        for k in range(1, RING_SLOTS + 1):
            used = k <= n
            inputs[f"ring_{k}_E_kPa"] = (float(round(10 ** at[f"ring_{k}"], 6)) if used else
                                         self.fill_E_kPa)
        for name, (lo_, hi_) in self.shared.items():
            value = at.get(name)
            if value is None or n == 0:
                inputs[name] = 0.5 * (lo_ + hi_)
            else:
                inputs[name] = float(round(10 ** value if name in _LOG else value, 6))
        return inputs

    def materials(self, inputs: dict[str, Any]) -> tuple[str, ...] | None:
        """The catalogue names of a catalogue design's rings (None: continuous materials)."""
        if self.continuous:
            return None
        by_e = {round(s.E_kPa, 6): s.name for s in self.catalogue.chosen}
        return tuple(by_e[round(inputs[f"ring_{k}_E_kPa"], 6)]
                     for k in range(1, inputs["n_rings"] + 1))

    @staticmethod
    def key(inputs: dict[str, Any]) -> tuple:
        """A hashable identity of a design (its inputs, rounded)."""
        return tuple((k, round(v, 6) if isinstance(v, float) else v)
                     for k, v in sorted(inputs.items()))

    def grid(self) -> list[dict[str, Any]]:
        """Every design of an exhaustive grid: every discrete choice, and ``grid_levels``
        levels per continuous entry (distinct designs only, in a fixed order)."""
        axes = [np.arange(d.low, d.high + 0.5) if d.integer else
                np.linspace(d.low, d.high, self.spec.grid_levels) for d in self.dimensions]
        seen: dict[tuple, dict[str, Any]] = {}
        for x in itertools.product(*axes):
            inputs = self.decode(x)
            seen.setdefault(self.key(inputs), inputs)
        return list(seen.values())

    def describe(self, inputs: dict[str, Any]) -> str:
        """A short name: ``reverse pogo, ecoflex-00-10 / dragon-skin-30`` (or the moduli)."""
        n = inputs["n_rings"]
        head = f"{inputs['orientation']} {inputs['attachment']}"
        if n == 0:
            return f"{head}, bare"
        names = self.materials(inputs)
        rings = (" / ".join(names) if names is not None else
                 " / ".join(f"{inputs[f'ring_{k}_E_kPa']:.0f}" for k in range(1, n + 1))
                 + " kPa")
        return f"{head}, {rings}"
