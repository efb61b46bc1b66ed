"""Crosstalk of an array of identical units from one unit's predicted amplitude profile.

A unit's surface amplitude at distance ``r`` from its centre is read from the surrogate's
profile (amplitude against distance from the unit's edge, log-linear interpolation). Two
conservative choices, both stated in the plan:

* Envelope: the amplitude at ``r`` is taken as the largest predicted at any distance >= r,
  so leakage never falls with a shorter pitch (guided waves can make a profile ripple; a
  pitch in a trough would not survive a small change of the skin).
* Beyond the profile's last point the amplitude decays at the log-slope of its last quarter
  (and never grows). That is an extrapolation: :func:`beyond_profile_share` says how much of
  a site's leakage rests on it, and the plan flags it.
* A bound field (the surrogate's 95 % bounds) carries the nominal field as its ``floor``: its
  amplitude is never below the nominal one at any distance, also beyond the profile where the
  two tails' slopes differ, so a pitch at the bounds is never shorter than the nominal one.

Superposition: ERMs run independently (no common phase), so their contributions at a site add
in power: leakage = sqrt(sum of squares) ("incoherent"); "worst" takes the largest single
neighbour. Coherently driven actuators (a common phase) would add amplitudes; the surrogate
predicts magnitudes only, so that case is not offered.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["UnitField", "beyond_profile_share", "crosstalk_matrix", "leakage_ratio",
           "site_positions"]


@dataclass(frozen=True)
class UnitField:
    """One unit's amplitude [um] against distance from its centre [mm]."""

    center_um: float
    edge_radius_mm: float
    distance_mm: NDArray  # profile grid, distance from the edge [mm], increasing from 0
    profile_um: NDArray  # amplitude on that grid [um]
    floor: UnitField | None = None  # never below this field's amplitude (a bound's nominal)

    def __post_init__(self) -> None:
        if np.any(self.profile_um <= 0) or self.center_um <= 0:
            raise ValueError("amplitudes must be positive")
        # the log envelope and its tail slope, computed once (the pitch search calls
        # amplitude() many times)
        log_p = np.log(self.profile_um)
        envelope = np.maximum.accumulate(log_p[::-1])[::-1]  # max over all distances >= d
        grid = self.distance_mm
        tail = grid >= grid[-1] - 0.25 * (grid[-1] - grid[0])
        slope = min(np.polyfit(grid[tail], envelope[tail], 1)[0], 0.0) if tail.sum() > 1 else 0.0
        object.__setattr__(self, "_envelope", envelope)
        object.__setattr__(self, "_slope", float(slope))

    def amplitude(self, r_mm: NDArray) -> NDArray:
        """Envelope amplitude [um] at centre distances ``r_mm`` >= the edge radius."""
        d = np.asarray(r_mm, dtype=float) - self.edge_radius_mm
        envelope, slope = self._envelope, self._slope  # type: ignore[attr-defined]
        grid = self.distance_mm
        inside = np.interp(np.clip(d, grid[0], grid[-1]), grid, envelope)
        beyond = envelope[-1] + slope * np.maximum(d - grid[-1], 0.0)
        a = np.exp(np.where(d > grid[-1], beyond, inside))
        return a if self.floor is None else np.maximum(a, self.floor.amplitude(r_mm))

    @property
    def profile_end_mm(self) -> float:
        """Centre distance [mm] beyond which the amplitude is the log-slope extension."""
        return float(self.edge_radius_mm + self.distance_mm[-1])


def site_positions(rows: int, cols: int, pitch_mm: float, grid: str) -> NDArray:
    """(rows * cols, 2) site centres [mm]; "hex" offsets every other row by half a pitch and
    packs rows at sqrt(3)/2 pitch, so every neighbour is one pitch away."""
    i, j = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    x = j.astype(float)
    y = i.astype(float)
    if grid == "hex":
        x = x + 0.5 * (i % 2)
        y = y * np.sqrt(3.0) / 2.0
    return pitch_mm * np.column_stack([x.ravel(), y.ravel()])


def beyond_profile_share(field: UnitField, positions: NDArray, site: int) -> float:
    """Share (0..1) of the leakage power at ``site`` from neighbours farther than the
    profile's last point (amplitudes from the log-slope extension, not the model)."""
    r = np.linalg.norm(positions - positions[site], axis=1)
    r = np.delete(r, site)
    if not r.size:
        return 0.0
    a2 = field.amplitude(r) ** 2
    total = float(a2.sum())
    return 0.0 if total == 0 else float(a2[r > field.profile_end_mm].sum() / total)


def crosstalk_matrix(field: UnitField, positions: NDArray) -> NDArray:
    """C[i, j]: amplitude [um] at site i when unit j runs alone at its level (C[i, i] is the
    unit's own center amplitude)."""
    r = np.linalg.norm(positions[:, None, :] - positions[None, :, :], axis=2)
    C = np.zeros_like(r)
    off = ~np.eye(len(positions), dtype=bool)
    C[off] = field.amplitude(r[off])
    np.fill_diagonal(C, field.center_um)
    return C


def leakage_ratio(C: NDArray, superposition: str) -> NDArray:
    """Per site: leakage from all other units / the site's own amplitude."""
    off = C - np.diag(np.diag(C))
    leak = np.sqrt((off**2).sum(axis=1)) if superposition == "incoherent" else off.max(axis=1)
    return leak / np.diag(C)
