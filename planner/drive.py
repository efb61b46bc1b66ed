"""Drive levels that render a pattern of site amplitudes with the least leakage.

Each channel's level ``u_j`` in [0, ``max_level``] scales its unit's amplitude field (a linear
actuator at a fixed drive frequency; for an ERM the level stands for the steady amplitude it
is run at, which the transient model maps to a voltage). Independent units add in power, so
the squared amplitude at site i is sum_j C_ij^2 u_j^2: linear in v = u^2. The levels are the
bounded least-squares solution of C^2 v = target^2 with 0 <= v <= max_level^2
(``scipy.optimize.lsq_linear``); the rendered amplitudes and the per-site error are returned.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["DriveSolution", "drive_levels"]


@dataclass(frozen=True)
class DriveSolution:
    """Levels per channel (0..max_level), rendered and target amplitudes per site [um]."""

    levels: NDArray
    rendered_um: NDArray
    target_um: NDArray

    @property
    def max_error_um(self) -> float:
        return float(np.abs(self.rendered_um - self.target_um).max())


def rendered(C: NDArray, levels: NDArray) -> NDArray:
    """Site amplitudes [um] of channel ``levels`` (incoherent sum)."""
    return np.sqrt((C**2) @ (np.asarray(levels, dtype=float) ** 2))


def drive_levels(C: NDArray, target_um: NDArray, max_level: float = 1.0) -> DriveSolution:
    """Levels rendering ``target_um`` at the sites of crosstalk matrix ``C`` (C[i, j]: amplitude
    at site i of unit j at level 1) as closely as the bounds allow, in the power sense."""
    # lazy: planning imports no scipy (tests/planner/test_plan.py); only drive levels do
    from scipy.optimize import lsq_linear

    C = np.asarray(C, dtype=float)
    target = np.asarray(target_um, dtype=float)
    if C.ndim != 2 or C.shape[0] != C.shape[1] or target.shape != (C.shape[0],):
        raise ValueError(f"pattern: {target.shape[0] if target.ndim else 0} site amplitudes "
                         f"for a {C.shape} crosstalk matrix; give one amplitude per site")
    if not np.all(np.isfinite(target)) or np.any(target < 0):
        raise ValueError("pattern: site amplitudes must be finite and >= 0 um")
    if not 0 < max_level <= 1:
        raise ValueError(f"max_level = {max_level!r}: allowed 0 < max_level <= 1")
    # scale rows so every site counts alike whatever its own amplitude
    scale = 1.0 / np.diag(C) ** 2
    sol = lsq_linear((C**2) * scale[:, None], target**2 * scale, bounds=(0.0, max_level**2),
                     method="bvls")
    levels = np.sqrt(np.clip(sol.x, 0.0, max_level**2))
    return DriveSolution(levels, rendered(C, levels), target)
