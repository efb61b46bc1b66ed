"""The layout optimiser: the smallest pitch at which every site meets the crosstalk criterion,
for each candidate design and drive frequency, on the shipped surrogate (run time only).

For identical units on a regular grid the worst-site leakage ratio is a function of the pitch
alone and, with the envelope profile (:mod:`planner.crosstalk`), never grows with it; the
smallest feasible pitch is found by bisection to ``PITCH_TOL_MM``. Units may not overlap: the
pitch is at least two edge radii. The surrogate's uncertainty is carried through as a second,
conservative pitch: the leakage of the upper 95 % bound of the neighbours' amplitudes against
the lower bound of the site's own (log-normal, 1.96 sigma), never below the nominal amplitude
(so never a shorter pitch). By default (``criterion.holds_at = "bounds_95"``) candidates are
ranked, and the array laid out, on that pitch; ``"nominal"`` uses the prediction alone.

Before ranking (:mod:`planner.prepare`): every value is checked against the plan's validity
domain (:mod:`planner.domain`), and drive frequencies the motor cannot reach within its
voltage limit are dropped and listed. After ranking, the winner's timing is computed; a
candidate whose timing cannot be computed is not playable and the next one wins (listed in
``Plan.unplayable``), so a plan's winner is always playable.

Criteria (:class:`planner.layout.CriterionSpec`): the *load* of a site is its leakage over
what the criterion allows, so a pitch is feasible when every load is <= 1 and the margin is
1 / the largest load. ``ratio``: leakage / own amplitude / max_ratio. ``perceptual``:
drive_level x leakage [um] / the detection threshold at the drive frequency
(:mod:`planner.threshold`); a unit whose own amplitude is below the threshold is infeasible
(it would not be felt). The surrogate's amplitudes are absolute: the nominal coin ERM of the
training scenes (fem defaults, unbalance 0.006 g mm) spinning at the drive frequency, so the
force grows with the frequency squared; drive_level scales them linearly (another unbalance,
or a linear actuator at that frequency).

Free positions (``grid = "free"``): no pitch is chosen; every design and frequency is
evaluated at the given sites and the feasible one with the smallest worst load (the largest
margin) wins; its ``pitch_mm`` is the sites' nearest-neighbour distance. Mixed designs in one
array are not planned (the search would be over assignments). ``[[design]] any = true``
tables are expanded into candidates from the model's trained range
(:mod:`planner.candidates`) and searched like named designs; ``objective = "max_sites"``
chooses rows x cols per candidate to fill ``region_mm`` (:mod:`planner.region`) and the most
sites win.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from planner.crosstalk import (
    UnitField,
    beyond_profile_share,
    crosstalk_matrix,
    leakage_ratio,
    site_positions,
)
from planner.domain import Domain, Extrapolation
from planner.layout import MAX_SITES_PER_SIDE, LayoutError, LayoutRequest
from planner.prepare import prepare
from planner.region import largest_array, largest_pitch
from planner.timing import plan_timing

__all__ = ["PITCH_TOL_MM", "DesignResult", "Plan", "array_positions", "judge", "loads",
           "plan_layout", "ranked", "shaped_request", "smallest_pitch", "worst_load"]

PITCH_TOL_MM = 0.01
Z95 = 1.959964


@dataclass
class DesignResult:
    """One (design, frequency): its unit field, smallest feasible pitches and uncertainty."""

    name: str
    frequency_hz: float
    inputs: dict[str, Any]
    center_um: float
    edge_radius_mm: float
    log_std_center: float
    log_std_profile_max: float
    extrapolated: bool  # an input outside the plan's domain (allow_extrapolation)
    pitch_nominal_mm: float | None  # None: infeasible within the pitch bounds
    pitch_95_mm: float | None  # with the surrogate's 95 % bounds (>= the nominal pitch)
    unit: UnitField | None = None  # the nominal amplitude field
    bound: UnitField | None = None  # the 95 % bound field (neighbours high, own low)
    felt: bool = True  # perceptual: own amplitude above the detection threshold
    edge_um: float | None = None  # the surrogate's edge amplitude [um]
    load: float | None = None  # worst site load at pitch_mm (free positions: at the sites)
    family: str = ""  # the request's design table (an any = true table: its name)
    shape: tuple[int, int] | None = None  # max_sites: the (rows, cols) that fit the region
    holds_at: str = "bounds_95"  # which pitch is the candidate's: "bounds_95" | "nominal"
    extrapolations: list[Extrapolation] = field(default_factory=list)
    beyond_profile: float = 0.0  # share of the worst site's leakage power from beyond the
    # profile's last point (the log-slope extension), at the candidate's pitch

    @property
    def pitch_mm(self) -> float | None:
        """The candidate's pitch [mm]: at the 95 % bounds or nominal (``holds_at``)."""
        return self.pitch_95_mm if self.holds_at == "bounds_95" else self.pitch_nominal_mm

    @property
    def decision(self) -> UnitField | None:
        """The field the criterion is judged on (the bound or the nominal one)."""
        return self.bound if self.holds_at == "bounds_95" else self.unit

    @property
    def edge_to_edge_mm(self) -> float | None:
        """Clear skin between neighbouring units at the chosen pitch [mm]."""
        return None if self.pitch_mm is None else self.pitch_mm - 2 * self.edge_radius_mm


@dataclass
class Plan:
    """The optimiser's answer: every candidate, the chosen one and its array."""

    request: LayoutRequest
    candidates: list[DesignResult]
    best: DesignResult | None
    positions_mm: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    crosstalk_um: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    ratios: np.ndarray = field(default_factory=lambda: np.zeros(0))

    loads: np.ndarray = field(default_factory=lambda: np.zeros(0))
    load_95: float | None = None  # worst load at the chosen pitch with the 95 % bound field
    timing: dict[str, Any] | None = None  # planner.timing.plan_timing of the chosen unit
    domain: Domain | None = None  # the intersection of the models' ranges
    dropped: list[dict[str, Any]] = field(default_factory=list)  # unreachable frequencies
    unplayable: list[dict[str, Any]] = field(default_factory=list)  # better, but no timing
    profile_end_mm: float = 0.0  # the model profile's last distance from the unit's edge

    def shown(self) -> list[DesignResult]:
        """The candidates worth listing: every named design, and of each ``any = true`` table
        only its best (the chosen one's key) or, with none feasible, its first."""
        named = [c for c in self.candidates if c.family == c.name]
        best: dict[str, DesignResult] = {}
        for c in self.candidates:
            if c.family != c.name and (c.family not in best or _better(
                    c, best[c.family], self.request.positions_mm is not None)):
                best[c.family] = c
        return named + list(best.values())

    @property
    def margin(self) -> float | None:
        """1 / the worst load at the chosen pitch (>= 1: the criterion holds)."""
        if self.best is None or not self.loads.size:
            return None
        worst = float(self.loads.max())
        return float("inf") if worst == 0 else 1.0 / worst

    @property
    def leakage_um(self) -> np.ndarray:
        """Leakage amplitude at every site [um] at the criterion's drive level."""
        if not self.crosstalk_um.size:
            return np.zeros(0)
        C = self.crosstalk_um
        return self.ratios * np.diag(C) * self.request.criterion.drive_level


def array_positions(req: LayoutRequest, pitch_mm: float) -> np.ndarray:
    """(n, 2) site centres [mm]: the grid at ``pitch_mm``, or the given free positions (the
    pitch then plays no part)."""
    if req.positions_mm is not None:
        return np.array(req.positions_mm, dtype=float)
    return site_positions(req.rows, req.cols, pitch_mm, req.grid)


def nearest_distance_mm(positions: np.ndarray) -> float:
    """Smallest centre-to-centre distance of the sites [mm] (inf for one site)."""
    r = np.linalg.norm(positions[:, None, :] - positions[None, :, :], axis=2)
    np.fill_diagonal(r, np.inf)
    return float(r.min())


def worst_ratio(f: UnitField, req: LayoutRequest, pitch_mm: float) -> float:
    """Largest leakage / own amplitude over the sites at ``pitch_mm``."""
    pos = array_positions(req, pitch_mm)
    if len(pos) < 2:
        return 0.0
    return float(leakage_ratio(crosstalk_matrix(f, pos), req.criterion.superposition).max())


def loads(C: np.ndarray, req: LayoutRequest, frequency_hz: float) -> np.ndarray:
    """Per site: leakage over what the criterion allows (<= 1: the site meets it)."""
    crit = req.criterion
    ratios = leakage_ratio(C, crit.superposition)
    if crit.kind == "ratio":
        return ratios / crit.max_ratio
    threshold = float(crit.threshold(frequency_hz))
    return ratios * np.diag(C) * crit.drive_level / threshold


def worst_load(f: UnitField, req: LayoutRequest, pitch_mm: float, frequency_hz: float) -> float:
    """Largest site load of the array at ``pitch_mm`` (0 for a single site)."""
    pos = array_positions(req, pitch_mm)
    if len(pos) < 2:
        return 0.0
    return float(loads(crosstalk_matrix(f, pos), req, frequency_hz).max())


def smallest_pitch(f: UnitField, req: LayoutRequest, frequency_hz: float = 0.0) -> float | None:
    """Smallest pitch in the request's bounds (and >= 2 edge radii) meeting the criterion
    (``frequency_hz`` sets the threshold of the perceptual one). Free positions: their
    nearest-neighbour distance when the units do not overlap there and every load is <= 1,
    else None."""
    if req.positions_mm is not None:
        near = nearest_distance_mm(array_positions(req, 0.0))
        fits = near >= 2 * f.edge_radius_mm and worst_load(f, req, near, frequency_hz) <= 1.0
        return near if fits else None
    lo = max(req.min_pitch_mm, 2 * f.edge_radius_mm)
    hi = req.max_pitch_mm
    if lo > hi or worst_load(f, req, hi, frequency_hz) > 1.0:
        return None
    if worst_load(f, req, lo, frequency_hz) <= 1.0:
        return lo
    while hi - lo > PITCH_TOL_MM:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if worst_load(f, req, mid, frequency_hz) <= 1.0 else (mid, hi)
    return hi


def is_felt(center_um: float, req: LayoutRequest, frequency_hz: float) -> bool:
    """Perceptual criterion: whether the unit's own amplitude reaches the threshold."""
    crit = req.criterion
    return crit.kind != "perceptual" or \
        center_um * crit.drive_level >= float(crit.threshold(frequency_hz))


def _key(r: DesignResult, free: bool) -> tuple[float, ...]:
    """Sort key of a feasible candidate: the most sites (max_sites), then the smallest
    pitch (free positions: smallest worst load), then the larger own amplitude."""
    sites = -r.shape[0] * r.shape[1] if r.shape is not None else 0
    own = r.decision.center_um if r.decision is not None else r.center_um
    return (sites, (r.load if free else r.pitch_mm), -own)  # type: ignore[return-value]


def shaped_request(req: LayoutRequest, r: DesignResult) -> LayoutRequest:
    """The request with the candidate's grid shape (max_sites), else as it is."""
    return req if r.shape is None else replace(req, rows=r.shape[0], cols=r.shape[1])


def _fill_region(f: UnitField, req: LayoutRequest, frequency_hz: float) -> LayoutRequest | None:
    """max_sites: the request with the most rows x cols that meet the criterion inside
    ``region_mm`` (None: not even one unit fits); other objectives: the request."""
    if req.objective != "max_sites":
        return req

    def top(rows: int, cols: int) -> float:
        return min(largest_pitch(rows, cols, req.grid, req.region_mm, f.edge_radius_mm),
                   req.max_pitch_mm)

    def fits(rows: int, cols: int) -> bool:
        p = top(rows, cols)
        if p < max(req.min_pitch_mm, 2 * f.edge_radius_mm):
            return rows * cols == 1 and p > -math.inf
        shaped = replace(req, rows=rows, cols=cols)
        return worst_load(f, shaped, p, frequency_hz) <= 1.0

    shape = largest_array(fits, MAX_SITES_PER_SIDE)
    return None if shape is None else replace(req, rows=shape[0], cols=shape[1])


def _better(a: DesignResult, b: DesignResult, free: bool) -> bool:
    """Whether ``a`` beats ``b`` (a feasible candidate beats an infeasible one)."""
    if a.pitch_mm is None or b.pitch_mm is None:
        return a.pitch_mm is not None and b.pitch_mm is None
    return _key(a, free) < _key(b, free)


def _check_overlap(req: LayoutRequest, results: list[DesignResult]) -> None:
    """Free positions: refuse sites closer than every candidate unit's diameter (naming the
    later site of the closest pair); a candidate that overlaps while another fits is only
    infeasible."""
    pos = array_positions(req, 0.0)
    smallest = min(2 * r.edge_radius_mm for r in results)
    r = np.linalg.norm(pos[:, None, :] - pos[None, :, :], axis=2)
    np.fill_diagonal(r, np.inf)
    if r.min() >= smallest:
        return
    i, j = sorted(np.unravel_index(int(np.argmin(r)), r.shape))
    raise LayoutError(f"array.positions_mm[{j}]", f"array.positions_mm[{j}] is {r[i, j]:.3g} "
                      f"mm from array.positions_mm[{i}]: units overlap (the smallest candidate "
                      f"unit is {smallest:.3g} mm across); sites must be at least that apart")


def _evaluate(req: LayoutRequest, design: dict[str, Any], freq: float, k: int,
              prep: Any) -> DesignResult:
    """One candidate: its nominal and bound fields from the prediction, then :func:`judge`."""
    out, grid = prep.out, prep.predictor.profile_distance_mm
    center, profile = out["center_amplitude_um"][k], out["profile_um"][k]
    s_c, s_p = out["center_amplitude_um_log_std"][k], out["profile_um_log_std"][k]
    edge = float(out["edge_radius_mm"][k])
    nominal = UnitField(float(center), edge, grid, profile)
    bound = UnitField(float(center * np.exp(-Z95 * s_c)), edge, grid,
                      profile * np.exp(Z95 * s_p), floor=nominal)
    ex = prep.extrapolations[k]
    flagged = bool(ex) or ("extrapolated" in out and bool(out["extrapolated"][k]))
    r = DesignResult(
        design["name"], freq, dict(design["inputs"]), float(center), edge, float(s_c),
        float(s_p.max()), flagged, None, None, nominal, bound,
        edge_um=float(out["edge_amplitude_um"][k]),
        family=design.get("family", design["name"]), extrapolations=list(ex))
    return judge(req, r)


def judge(req: LayoutRequest, r: DesignResult) -> DesignResult:
    """``r`` judged on its fields (``unit``, ``bound``) under the request's criterion: whether
    it is felt, its shape (max_sites), nominal and 95 % pitches, worst load and the leakage
    share beyond the profile (the one criterion code of the plan; ``plan --verify`` judges
    an FE field with it, the field as both nominal and bound)."""
    freq, nominal, bound = r.frequency_hz, r.unit, r.bound
    holds_at = req.criterion.holds_at
    decide = bound if holds_at == "bounds_95" else nominal
    felt = is_felt(decide.center_um, req, freq)
    shaped = _fill_region(decide, req, freq) if felt else None
    p_nom = smallest_pitch(nominal, shaped, freq) if shaped else None
    p_95 = smallest_pitch(bound, shaped, freq) if shaped else None
    if p_95 is not None and p_nom is not None:
        p_95 = max(p_95, p_nom)  # the bounds never ask for less room than the prediction
    r = replace(r, felt=felt, pitch_nominal_mm=p_nom, pitch_95_mm=p_95, holds_at=holds_at,
                shape=None if shaped is None or req.objective != "max_sites" else
                (shaped.rows, shaped.cols), load=None, beyond_profile=0.0)
    if r.pitch_mm is not None:
        shaped_req = shaped_request(req, r)
        pos = array_positions(shaped_req, r.pitch_mm)
        r.load = worst_load(decide, shaped_req, r.pitch_mm, freq)
        if len(pos) > 1:
            worst = int(np.argmax(loads(crosstalk_matrix(decide, pos), shaped_req, freq)))
            r.beyond_profile = beyond_profile_share(decide, pos, worst)
    return r


def ranked(results: list[DesignResult], free: bool) -> list[DesignResult]:
    """The feasible candidates, best first (:func:`_key`: most sites, then the smallest
    pitch, or with free positions the smallest worst load, then the larger own amplitude)."""
    return sorted((r for r in results if r.pitch_mm is not None), key=lambda r: _key(r, free))


def _playable(req: LayoutRequest, ranked: list[DesignResult], rom: Any
              ) -> tuple[DesignResult | None, dict[str, Any] | None, list[dict[str, Any]]]:
    """The best candidate whose timing can be computed (timing disabled: the best), its
    timing, and the better ones skipped with the reason."""
    skipped: list[dict[str, Any]] = []
    for r in ranked:
        if not req.timing.enabled:
            return r, None, skipped
        timing = plan_timing(shaped_request(req, r), r, model=rom)
        if not timing.get("unavailable"):
            return r, timing, skipped
        skipped.append({"name": r.name, "frequency_hz": r.frequency_hz,
                        "reason": timing["unavailable"]})
    return None, None, skipped


def plan_layout(req: LayoutRequest) -> Plan:
    """Evaluate every design at every reachable drive frequency, pick the smallest feasible
    pitch (ties: the larger own amplitude) whose timing can be computed; with free
    positions, the feasible design with the smallest worst load (the largest margin) at the
    given sites."""
    prep = prepare(req)
    results = [_evaluate(req, d, float(f), k, prep) for k, (d, f) in enumerate(prep.combos)]
    free = req.positions_mm is not None
    if free:
        _check_overlap(req, results)
    best, timing, skipped = _playable(req, ranked(results, free), prep.rom)
    if best is not None:
        req = shaped_request(req, best)
    result = Plan(req, results, best, timing=timing, domain=prep.domain,
                  dropped=prep.dropped, unplayable=skipped,
                  profile_end_mm=float(prep.predictor.profile_distance_mm[-1]))
    if best is not None:
        result.positions_mm = array_positions(req, best.pitch_mm)
        result.crosstalk_um = crosstalk_matrix(best.unit, result.positions_mm)
        result.ratios = leakage_ratio(result.crosstalk_um, req.criterion.superposition)
        result.loads = loads(result.crosstalk_um, req, best.frequency_hz)
        result.load_95 = worst_load(best.bound, req, best.pitch_mm, best.frequency_hz)
    return result
