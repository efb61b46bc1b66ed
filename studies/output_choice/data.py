"""Sweep datasets as arrays: encoded design features and the complex band response.

A sweep dataset (:mod:`surrogate.data.columns`) holds one row per design with its complex
response over the band; this module turns its ``ok`` rows into a :class:`Sweeps` (features
encoded by the training dataset's input specs, so that a second dataset of the same space is
encoded identically), splits one dataset into training and test designs, and caps rows.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from surrogate.data.columns import sweep_arrays
from surrogate.data.store import Store
from surrogate.features import SpaceEncoder, codes_from_frame, input_specs
from surrogate.runtime.encoding import InputSpec

__all__ = ["Sweeps", "load", "split"]


@dataclass(frozen=True)
class Sweeps:
    """Designs with their band response.

    Attributes:
        x: encoded design features (n, d).
        band: the band's frequencies (n_f,) [Hz].
        center, edge: complex displacement (n, n_f, 3) [um], components (r, z, t).
        profile: complex surface displacement (n, n_f, n_p, 3) [um], or None (not loaded).
        distance_mm: the profile's distances from the unit's edge (n_p,) [mm].
        source: where the designs come from (a dataset path, with the split if any).
    """

    x: np.ndarray
    band: np.ndarray
    center: np.ndarray
    edge: np.ndarray
    profile: np.ndarray | None
    distance_mm: np.ndarray
    source: str

    def __len__(self) -> int:
        return len(self.x)

    def take(self, rows: np.ndarray, source: str | None = None) -> Sweeps:
        """The designs ``rows`` (an index array), in that order."""
        return Sweeps(self.x[rows], self.band, self.center[rows], self.edge[rows],
                      None if self.profile is None else self.profile[rows], self.distance_mm,
                      source or self.source)


def _specs(store: Store) -> list[InputSpec]:
    return input_specs(store.manifest["space"]["parameter"])


def load(path: str, *, profile: bool = True, limit: int | None = None,
         specs: list[InputSpec] | None = None) -> tuple[Sweeps, list[InputSpec]]:
    """The ``ok`` rows of the sweep dataset at ``path`` in its design order (the first
    ``limit`` of them if given), encoded by ``specs`` (default: the dataset's own), and the
    specs used. Raises ValueError when the dataset has no sweep columns or its inputs differ
    from ``specs``."""
    store = Store.open(path)
    own = _specs(store)
    if specs is not None and [s.name for s in own] != [s.name for s in specs]:
        raise ValueError(f"{path}: inputs {[s.name for s in own]} differ from the training "
                         f"dataset's {[s.name for s in specs]}")
    specs = specs or own
    df = store.read()
    if "sweep_frequency_hz" not in df.columns:
        raise ValueError(f"{path}: not a sweep dataset (no sweep_frequency_hz column)")
    df = df[df["status"] == "ok"]
    if "sample_index" in df.columns:
        df = df.sort_values("sample_index", kind="stable")
    df = df.reset_index(drop=True)
    if limit is not None:
        df = df.iloc[:limit]
    if len(df) < 2:
        raise ValueError(f"{path}: {len(df)} usable designs (need at least 2)")
    codes = codes_from_frame(df, specs)
    x = SpaceEncoder([s.to_dict() for s in specs]).fit_transform(codes)
    rows: list[dict[str, Any]] = df.to_dict("records")
    band = np.asarray(rows[0]["sweep_frequency_hz"], dtype=float)
    center = np.stack([sweep_arrays(r, "center") for r in rows])
    edge = np.stack([sweep_arrays(r, "edge") for r in rows])
    prof = np.stack([sweep_arrays(r, "profile") for r in rows]) if profile else None
    dist = np.asarray(rows[0]["profile_distance_mm"], dtype=float)
    return Sweeps(x, band, center, edge, prof, dist, str(path)), specs


def split(sw: Sweeps, test: float, seed: int) -> tuple[Sweeps, Sweeps]:
    """(training, test) designs: a random ``test`` fraction (0, 1) of the designs held out."""
    if not 0 < test < 1:
        raise ValueError(f"test fraction {test}: allowed (0, 1)")
    order = np.random.default_rng(seed).permutation(len(sw))
    n_test = min(len(sw) - 1, max(1, round(test * len(sw))))
    te, tr = np.sort(order[:n_test]), np.sort(order[n_test:])
    return (sw.take(tr, f"{sw.source} (split seed {seed}, train)"),
            sw.take(te, f"{sw.source} (split seed {seed}, held out)"))
