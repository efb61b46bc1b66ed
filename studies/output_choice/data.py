"""Sweep datasets as arrays: encoded design features and the complex band response.

A sweep dataset (:mod:`surrogate.data.columns`) holds one row per design with its complex
response over the band; this module turns its ``ok`` rows into a :class:`Sweeps` (features
encoded by the training dataset's input specs, so that a second dataset of the same space is
encoded identically), splits one dataset into training and test designs, and caps rows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyarrow as pa

from surrogate.data.columns import COMPONENTS
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


def _lists(table: pa.Table, column: str) -> np.ndarray:
    """A list column of equal-length lists as an array (rows, length)."""
    arr = table.column(column).combine_chunks()
    values = np.asarray(arr.flatten().to_numpy(zero_copy_only=False), dtype=float)
    return values.reshape(len(arr), -1)


def _complex(table: pa.Table, where: str) -> np.ndarray:
    """The complex sweep of every row at ``where`` as (rows, n_values, 3) [um], components
    (r, z, t) last (:func:`surrogate.data.columns.sweep_arrays`, for all rows at once)."""
    return np.stack([_lists(table, f"sweep_{where}_u{c}_re_um")
                     + 1j * _lists(table, f"sweep_{where}_u{c}_im_um")
                     for c in COMPONENTS], axis=-1)


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
    table = store.read_table()
    if "sweep_frequency_hz" not in table.column_names:
        raise ValueError(f"{path}: not a sweep dataset (no sweep_frequency_hz column)")
    meta = table.select(["status", "sample_index"]).to_pandas()
    ok = np.flatnonzero((meta["status"] == "ok").to_numpy())
    rows = ok[np.argsort(meta["sample_index"].to_numpy()[ok], kind="stable")][:limit]
    if len(rows) < 2:
        raise ValueError(f"{path}: {len(rows)} usable designs (need at least 2)")
    table = table.take(pa.array(rows))
    lists = [n for n in table.column_names if n.startswith("sweep_") or n.startswith("profile_")]
    codes = codes_from_frame(table.drop_columns(lists).to_pandas(), specs)
    x = SpaceEncoder([s.to_dict() for s in specs]).fit_transform(codes)
    band = _lists(table, "sweep_frequency_hz")[0]
    dist = _lists(table, "profile_distance_mm")[0]
    center, edge = _complex(table, "center"), _complex(table, "edge")
    prof = _complex(table, "profile").reshape(len(rows), band.size, dist.size, 3) \
        if profile else None
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
