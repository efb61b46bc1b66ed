"""Planning a dataset: the first ``n`` distinct feasible design points of a space.

Points rejected by a constraint, or resolving to a scene already planned (e.g. a ring
material that a smaller ``n_rings`` truncates away), are skipped and counted; the sample id is
the hash of the resolved, validated scene, so the same space and seed give the same ids.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fem.scene import scene_hash, scene_to_dict
from surrogate.data.errors import SpaceError
from surrogate.data.space import Space

__all__ = ["PlanStats", "Planned", "plan_samples"]


@dataclass(frozen=True)
class Planned:
    """One design point to run: sequence ``index``, ``sample_id`` (scene hash), parameter
    ``values`` (column -> python scalar) and the resolved, canonical ``scene`` dict."""

    index: int
    sample_id: str
    values: dict[str, Any]
    scene: dict[str, Any]


@dataclass
class PlanStats:
    """How many sequence indices were scanned to find the planned points, and why the others
    were skipped."""

    scanned: int = 0
    rejected: int = 0
    duplicates: int = 0




#: Most samples one dataset plans: every planned scene is validated and held in memory
#: (about 2 KB each), and at the measured 170 samples/min on 2 cores this is ~20 h of solves.
MAX_SAMPLES = 200_000


def plan_samples(space: Space, n: int) -> tuple[list[Planned], PlanStats]:
    """The first ``n`` distinct feasible design points of ``space``, every scene validated.

    Raises :class:`SpaceError` naming the sample index and parameter if a scene is invalid,
    or if the space has fewer than ``n`` distinct feasible points in a long prefix."""
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise SpaceError("n", f"n = {n!r}: need an integer >= 1")
    if n > MAX_SAMPLES:
        raise SpaceError("n", f"n = {n} is out of range: allowed 1 <= n <= {MAX_SAMPLES} "
                         "samples per dataset (planning validates and keeps every scene); "
                         "split the work into several datasets and merge them")
    planned: list[Planned] = []
    seen: set[str] = set()
    stats = PlanStats()
    limit = max(16 * n, 4096)
    block = max(64, min(n, 8192))
    while len(planned) < n:
        if stats.scanned >= limit:
            raise SpaceError("n", f"space {space.name!r} gives only {len(planned)} distinct "
                             f"feasible points in its first {stats.scanned} design points "
                             f"({stats.rejected} rejected by constraints, {stats.duplicates} "
                             f"repeat a scene); n = {n} is too many for it")
        values = space.points(stats.scanned, block)
        feasible = space.feasible(values)
        for j in range(block):
            index = stats.scanned + j
            if not feasible[j]:
                stats.rejected += 1
                continue
            row = {k: _py(v[j]) for k, v in values.items()}
            try:
                scene = space.scene(row)
            except SpaceError as err:
                raise SpaceError(err.field, f"sample {index}: {err}") from None
            sid = scene_hash(scene)
            if sid in seen:
                stats.duplicates += 1
                continue
            seen.add(sid)
            planned.append(Planned(index, sid, row, scene_to_dict(scene)))
            if len(planned) == n:
                stats.scanned = index + 1
                return planned, stats
        stats.scanned += block
    return planned, stats  # pragma: no cover - the loop returns


def _py(value: Any) -> Any:
    return value.item() if isinstance(value, np.generic) else value


