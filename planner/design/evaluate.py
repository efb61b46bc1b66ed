"""The objective: a unit's smallest pitch by the planner's own criterion, evaluated in batches.

A batch of designs becomes one layout request (the request's array, site, drive and criterion;
the designs as ``[[design]]`` tables; timing off) planned by :func:`planner.optimise.plan_layout`:
one batched prediction of every design at every drive frequency, then the plan's own checks
(validity domain, the motor's reach), its bisection and its criterion at the model's 95 %
bounds (``criterion.holds_at``). Of each design the best frequency is kept: the smallest
pitch among the frequencies at which it is *perceptible* (``planner.design.request``) and
*playable*; ties go to the larger own amplitude, as the plan ranks.

Playable, as the plan's winner must be: its envelope timing can be computed
(:func:`planner.timing.plan_timing` on the request's ``[timing]``; a unit on frictionless
pogo pins with no ring is refused there: nothing holds it sideways). The timing costs about
0.2 s, so it is computed only for a candidate that would beat the best playable score so far
(the incumbent); a design that cannot beat it is not the winner whatever its timing
(``playable`` None: not checked). :meth:`Evaluator.recheck` checks a design fully (the
finalists, before the FE check).

The optimisers minimise the *score*: the pitch [mm] of a feasible, perceptible, playable
design; else a penalty above any pitch, ``2 max_pitch_mm`` (+1 when only the timing failed)
plus, for a design felt at no frequency, its shortfall below the threshold [dB], so a search
is led towards felt designs.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from planner.layout import LayoutRequest, TimingSpec
from planner.optimise import DesignResult, Plan, plan_layout
from planner.prepare import load_rom
from planner.threshold import VERRILLO_1966_FOREARM, ThresholdCurve
from planner.timing import plan_timing

__all__ = ["Evaluation", "Evaluator", "contact_threshold_um"]

KEY = Callable[[dict[str, Any]], tuple]


@dataclass
class Evaluation:
    """One design, judged at its best drive frequency (lengths in mm, amplitudes in um)."""

    order: int  # its place in the search history (0-based; references: -1)
    name: str
    inputs: dict[str, Any]
    materials: tuple[str, ...] | None
    score: float
    frequency_hz: float | None = None  # the best frequency (None: no feasible, felt one)
    pitch_mm: float | None = None  # at the criterion's basis (holds_at)
    pitch_nominal_mm: float | None = None
    pitch_95_mm: float | None = None
    center_um: float = 0.0  # nominal own amplitude at that frequency
    center_low_um: float = 0.0  # at the lower 95 % bound (what must be felt)
    threshold_um: float = 0.0  # detection threshold at the unit's contact area
    edge_radius_mm: float = 0.0
    perceptible: bool = False
    beyond_profile: float = 0.0  # share of the worst site's leakage power from beyond the
    # model's profile (the log-slope extension) at the pitch
    extrapolated: bool = False
    batch: int = 0  # the batch it was evaluated in
    per_frequency: list[dict[str, Any]] = field(default_factory=list)
    playable: bool | None = None  # its timing computed (None: not checked, see module doc)
    unplayable: list[dict[str, Any]] = field(default_factory=list)  # skipped, with why

    @property
    def feasible(self) -> bool:
        return self.pitch_mm is not None

    def to_dict(self) -> dict[str, Any]:
        def r(x: float | None, n: int = 4) -> float | None:
            return None if x is None else round(float(x), n)
        return {"order": self.order, "name": self.name, "inputs": self.inputs,
                "materials": None if self.materials is None else list(self.materials),
                "score": r(self.score), "frequency_hz": self.frequency_hz,
                "pitch_mm": r(self.pitch_mm), "pitch_nominal_mm": r(self.pitch_nominal_mm),
                "pitch_95_mm": r(self.pitch_95_mm), "center_um": r(self.center_um),
                "center_low_um": r(self.center_low_um), "threshold_um": r(self.threshold_um),
                "edge_radius_mm": r(self.edge_radius_mm), "perceptible": self.perceptible,
                "beyond_profile_share": r(self.beyond_profile), "extrapolated": self.extrapolated,
                "playable": self.playable, "unplayable": self.unplayable, "batch": self.batch}


def contact_threshold_um(curve: ThresholdCurve, frequency_hz: float,
                         edge_radius_mm: float) -> float:
    """Detection threshold [um] at ``frequency_hz`` for a contact of the unit's own footprint
    (radius ``edge_radius_mm``): the curve rescaled by Verrillo's area law when it has a
    reference area."""
    if curve.contactor_area_cm2 is not None:
        curve = curve.at_area(math.pi * (edge_radius_mm / 10.0) ** 2)
    return float(curve(frequency_hz))


class Evaluator:
    """Scores designs in batches, each distinct design once; keeps the history in order."""

    def __init__(self, layout: LayoutRequest, key: KEY, describe: Callable[[dict], str],
                 materials: Callable[[dict], tuple[str, ...] | None],
                 perceptible: bool = True) -> None:
        self.layout = replace(layout, timing=TimingSpec(enabled=False))
        self.key, self.describe, self.materials = key, describe, materials
        self.perceptible = perceptible
        crit = layout.criterion
        self.curve = crit.threshold if crit.threshold is not None else VERRILLO_1966_FOREARM
        self.cache: dict[tuple, Evaluation] = {}
        self.history: list[Evaluation] = []
        self.batches = 0
        self.wall_s = 0.0
        self.dropped: list[dict[str, Any]] = []
        self.profile_end_mm = 0.0
        self.timed = layout  # the request with its [timing] (the playability check)
        self.rom = load_rom(layout) if layout.timing.enabled else None
        self.incumbent = math.inf  # the best playable score so far
        self.names: set[str] = set()  # the designs' names so far (each unique)
        self.timing_checks = 0
        self.timing_wall_s = 0.0

    @property
    def unique(self) -> int:
        return len(self.history)

    def plan(self, designs: Sequence[dict[str, Any]], timing: TimingSpec | None = None) -> Plan:
        """The planner's plan of ``designs`` (``{"name", "inputs"}``) under the request."""
        req = replace(self.layout, designs=tuple({"name": d["name"], "inputs": d["inputs"],
                                                  "any": False} for d in designs),
                      timing=timing or self.layout.timing)
        return plan_layout(req)

    def __call__(self, batch: Sequence[dict[str, Any]]) -> list[Evaluation]:
        """The evaluations of ``batch`` (model inputs of the design part), in its order."""
        new: dict[tuple, dict[str, Any]] = {}
        for inputs in batch:
            k = self.key(inputs)
            if k not in self.cache:
                new.setdefault(k, inputs)
        if new:
            t0 = time.perf_counter()
            self.batches += 1
            for ev in self.judge(list(new.values()), len(self.history)):
                self.cache[self.key(ev.inputs)] = ev
                self.history.append(ev)
            self.wall_s += time.perf_counter() - t0
        return [self.cache[self.key(x)] for x in batch]

    def recheck(self, ev: Evaluation) -> Evaluation:
        """``ev`` judged with every candidate's timing checked (same place in the history)."""
        if ev.playable is not None or not self.layout_timed:
            return ev
        new = self.judge([ev.inputs], ev.order, [ev.name], [ev.materials], check_all=True)[0]
        new.order, new.batch = ev.order, ev.batch
        self.cache[self.key(ev.inputs)] = new
        if 0 <= ev.order < len(self.history):
            self.history[ev.order] = new
        return new

    @property
    def layout_timed(self) -> bool:
        return self.timed.timing.enabled

    def _timing_problem(self, r: DesignResult) -> str | None:
        """Why ``r`` (a design at a frequency) is not playable, or None."""
        t0 = time.perf_counter()
        timing = plan_timing(self.timed, r, model=self.rom)
        self.timing_checks += 1
        self.timing_wall_s += time.perf_counter() - t0
        return timing.get("unavailable")

    def judge(self, designs: Sequence[dict[str, Any]], first: int,
              names: Sequence[str] | None = None,
              materials: Sequence[tuple[str, ...] | None] | None = None,
              check_all: bool = False) -> list[Evaluation]:
        """Evaluations of ``designs`` (history orders from ``first``), not cached; every
        candidate's timing checked with ``check_all`` (else as the module docstring says)."""
        plan = self.plan([{"name": f"#{first + i}", "inputs": x} for i, x in enumerate(designs)])
        self.dropped, self.profile_end_mm = plan.dropped, plan.profile_end_mm
        by_name: dict[str, list[DesignResult]] = {}
        for c in plan.candidates:
            by_name.setdefault(c.name, []).append(c)
        out = []
        for i, x in enumerate(designs):
            name = names[i] if names is not None else self._unique(self.describe(x), first + i)
            mats = materials[i] if materials is not None else self.materials(x)
            ev = self.best(by_name.get(f"#{first + i}", []), x, name, mats,
                           check_all or names is not None)
            ev.order, ev.batch = (first + i if names is None else -1), self.batches
            out.append(ev)
        return out

    def _unique(self, name: str, order: int) -> str:
        """``name``, or with ``#order`` when another design already has it (continuous
        moduli are shown rounded)."""
        unique = name if name not in self.names else f"{name} #{order}"
        self.names.add(unique)
        return unique

    def best(self, results: list[DesignResult], inputs: dict[str, Any], name: str,
             materials: tuple[str, ...] | None, check_all: bool = False) -> Evaluation:
        """One design's evaluation from its candidates at every kept frequency."""
        rows, ok, shortfall_db = [], [], math.inf
        for r in results:
            low = r.decision.center_um if r.decision is not None else r.center_um
            level = low * self.layout.criterion.drive_level
            threshold = contact_threshold_um(self.curve, r.frequency_hz, r.edge_radius_mm)
            heard = level >= threshold
            shortfall_db = min(shortfall_db, max(0.0, 20 * math.log10(threshold / level)))
            rows.append({"frequency_hz": r.frequency_hz, "pitch_mm": r.pitch_mm,
                         "center_um": round(r.center_um, 4), "perceptible": heard})
            if r.pitch_mm is not None and (heard or not self.perceptible):
                ok.append(((r.pitch_mm, -low), r, low, threshold, heard))
        best, playable, skipped = None, None, []
        for _, r, low, threshold, heard in sorted(ok, key=lambda x: x[0]):
            if not self.layout_timed or not (check_all or r.pitch_mm < self.incumbent):
                best = (r, low, threshold, heard)
                break
            why = self._timing_problem(r)
            if why is None:
                best, playable = (r, low, threshold, heard), True
                self.incumbent = min(self.incumbent, r.pitch_mm)
                break
            skipped.append({"frequency_hz": r.frequency_hz, "reason": why})
        top = 2.0 * self.layout.max_pitch_mm
        if best is None:
            score = top + (1.0 if skipped else 0.0) + (
                0.0 if not results or not math.isfinite(shortfall_db) or ok else shortfall_db)
            return Evaluation(-1, name, dict(inputs), materials, score, per_frequency=rows,
                              edge_radius_mm=results[0].edge_radius_mm if results else 0.0,
                              playable=False if skipped else None, unplayable=skipped)
        r, low, threshold, heard = best
        return Evaluation(-1, name, dict(inputs), materials, float(r.pitch_mm), r.frequency_hz,
                          r.pitch_mm, r.pitch_nominal_mm, r.pitch_95_mm, r.center_um, low,
                          threshold, r.edge_radius_mm, heard, r.beyond_profile,
                          bool(r.extrapolated or r.extrapolations), per_frequency=rows,
                          playable=playable if self.layout_timed else True,
                          unplayable=skipped)
