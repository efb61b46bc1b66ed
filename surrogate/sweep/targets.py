"""Sweep datasets as training data, and the complex-band representation a sweep model learns.

A sweep dataset (:mod:`surrogate.data.band`) holds one row per design with its complex
response over a band. Near an antiresonance the magnitude at one frequency changes sharply
with the design while the complex components and the resonance frequencies move smoothly
(issue 20; ``bench/surrogate/output_choice.py`` measured it). A sweep model therefore learns, per
design, a few numbers from which the whole complex band is rebuilt linearly:

* ``ln s``: the log of the band's RMS centre amplitude [um] (the level of the design);
* the POD coefficients of the complex components (r, z, t; real and imaginary parts) at the
  centre and at every profile point over every band frequency, divided by ``s`` and by a
  fixed weight per location (its RMS over the training designs, so the profile far from the
  edge, three decades below the centre, counts as much as the centre in the POD).

The response at a frequency between grid points is the linear interpolation of the complex
components (index floor + weight, clamped to the band); a magnitude is
sqrt(sum over components of |u_c|^2). The run-time graph does the same
(:mod:`surrogate.sweep.export`), so a sweep model meets the one graph contract of
:mod:`surrogate.estimators.export`: ``x`` with ``frequency_hz`` as its last input in,
ln [centre, edge, normalized edge, profile...] out.

Arrays: ``response`` (n, n_f, P, 6) float32 [um], P = 1 + n_p locations (0 the centre,
1 + j the profile point j; the edge is profile point 0, at distance 0 from the unit's edge),
last axis (r re, r im, z re, z im, t re, t im) -- :data:`surrogate.data.columns.COMPONENTS`.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fieldspec import FieldError
from surrogate.data.columns import COMPONENTS
from surrogate.data.store import Store
from surrogate.features import codes_from_frame, edge_radii_mm, input_specs, merge_specs
from surrogate.pod import POD
from surrogate.registry import manifest_sha256
from surrogate.runtime.encoding import InputSpec
from surrogate.sweep.basis import factor_block

__all__ = ["FREQUENCY_INPUT", "BandTargets", "SweepData", "check_not_mixed", "frequency_spec",
           "is_sweep", "load_sweep_datasets", "log_magnitudes", "log_normal",
           "log_output_columns", "pair_rows"]

#: The input a sweep model adds to the space's design inputs (last, so its feature is last).
FREQUENCY_INPUT = "frequency_hz"
#: Index of the normal component u_z on the last axis (re, im at 2 * Z, 2 * Z + 1).
Z = COMPONENTS.index("z")
#: Floor of a squared normalised magnitude before its log (keeps ln finite where a predicted
#: magnitude crosses zero; far below any stored value, about 1e-7 of the centre's square).
TINY = 1e-20


def is_sweep(path: str | Path) -> bool:
    """Whether the dataset at ``path`` holds sweeps (its manifest has a ``band``)."""
    return bool(Store.open(path, check=False).manifest.get("band"))


def check_not_mixed(paths: Sequence[str | Path]) -> bool:
    """True when every dataset of ``paths`` is a sweep dataset, False when none is; a
    :class:`fieldspec.FieldError` naming ``--data`` when they are mixed."""
    sweeps = [is_sweep(p) for p in paths]
    if any(sweeps) and not all(sweeps):
        which = ", ".join(f"{p} ({'sweep' if s else 'single-frequency'})"
                          for p, s in zip(paths, sweeps, strict=True))
        raise FieldError("--data", f"--data mixes sweep and single-frequency datasets ({which}): "
                         "a model learns from one kind (sweep datasets: the complex band of "
                         "each design; single-frequency: one row per design and frequency)")
    return bool(sweeps) and all(sweeps)


def frequency_spec(band_hz: np.ndarray) -> InputSpec:
    """The ``frequency_hz`` input of a model over ``band_hz`` (the band's uniform grid)."""
    step = float(band_hz[1] - band_hz[0])
    return InputSpec(name=FREQUENCY_INPUT, type="continuous", low=float(band_hz[0]),
                     high=float(band_hz[-1]), unit="Hz",
                     description=f"vibration frequency (ERM spin frequency), Hz; the complex "
                     f"response is interpolated linearly between the band's grid (every "
                     f"{step:g} Hz)")


@dataclass
class SweepData:
    """The ok rows of sweep datasets. ``specs``: the design inputs (no frequency)."""

    specs: list[InputSpec]
    codes: np.ndarray          # (n, d) design codes
    band_hz: np.ndarray        # (n_f,)
    grid_mm: np.ndarray        # (n_p,) distance from the unit's edge [mm]
    response: np.ndarray       # (n, n_f, 1 + n_p, 6) float32 [um]
    edge_radius_mm: np.ndarray  # (n,)
    sources: list[dict[str, Any]]

    @property
    def all_specs(self) -> list[InputSpec]:
        """The model's inputs: the design inputs, then ``frequency_hz``."""
        return [*self.specs, frequency_spec(self.band_hz)]

    def take(self, designs: Sequence[int] | np.ndarray) -> SweepData:
        """The designs (row positions, in this data's design-sequence order) ``designs``
        only, in that order; a :class:`fieldspec.FieldError` naming ``designs`` when one is
        out of range or repeated."""
        idx = np.asarray(designs)
        n = len(self.codes)
        if idx.ndim != 1 or idx.size == 0 or not np.issubdtype(idx.dtype, np.integer) \
                or idx.min() < 0 or idx.max() >= n or np.unique(idx).size != idx.size:
            raise FieldError("designs", f"designs: need distinct integer row positions in "
                             f"[0, {n - 1}] (the ok designs of the training datasets), "
                             f"got {idx.size} values")
        return SweepData(self.specs, self.codes[idx], self.band_hz, self.grid_mm,
                         self.response[idx], self.edge_radius_mm[idx], self.sources)


def _response(df: Any, n_f: int, n_p: int) -> np.ndarray:
    """(n, n_f, 1 + n_p, 6) float32 [um] of a frame's sweep columns."""
    out = np.empty((len(df), n_f, 1 + n_p, 6), dtype=np.float32)
    for k, c in enumerate(COMPONENTS):
        for part, off in (("re", 0), ("im", 1)):
            out[:, :, 0, 2 * k + off] = np.stack(df[f"sweep_center_u{c}_{part}_um"].to_numpy())
            prof = np.stack(df[f"sweep_profile_u{c}_{part}_um"].to_numpy())
            out[:, :, 1:, 2 * k + off] = prof.reshape(len(df), n_f, n_p)
    return out


def load_sweep_datasets(paths: Sequence[str | Path], *, categorical: str = "onehot"
                        ) -> SweepData:
    """Read the ok rows of sweep datasets (the same space inputs, band and profile grid),
    each in its design-sequence order (``sample_index``), as :class:`SweepData`."""
    if not paths:
        raise ValueError("--data: give at least one dataset")
    specs: list[InputSpec] | None = None
    band = grid = None
    codes, responses, radii, sources = [], [], [], []
    for path in paths:
        store = Store.open(path)
        manifest = store.manifest
        if not manifest.get("band"):
            raise FieldError("--data", f"--data {path}: not a sweep dataset (no band)")
        these = input_specs(manifest["space"]["parameter"], categorical=categorical)
        specs = these if specs is None else merge_specs(specs, these, str(path))
        f = np.asarray(manifest["band"]["frequency_hz"], dtype=float)
        g = np.asarray(manifest.get("profile_grid_mm") or [], dtype=float)
        if band is None:
            band, grid = f, g
        elif f.shape != band.shape or not np.allclose(f, band) or g.shape != grid.shape \
                or not np.allclose(g, grid):
            raise FieldError("--data", f"--data {path}: its band or profile grid differs from "
                             "the first dataset's")
        df = store.read()
        df = df[df["status"] == "ok"].sort_values("sample_index", kind="stable")
        df = df.reset_index(drop=True)
        if len(df) == 0:
            raise ValueError(f"{path}: no rows with status 'ok'")
        for col, want in (("sweep_frequency_hz", f), ("profile_distance_mm", g)):
            if any(len(v) != want.size or not np.allclose(v, want) for v in df[col]):
                raise ValueError(f"{path}: some rows' {col} differ from the manifest's")
        codes.append(codes_from_frame(df, these))
        responses.append(_response(df, f.size, g.size))
        radii.append(edge_radii_mm(df))
        sources.append({"path": str(path), "manifest_sha256": manifest_sha256(path),
                        "space_hash": manifest.get("space_hash"), "rows": len(df),
                        "band_hz": [float(f[0]), float(f[-1]), float(f[1] - f[0])]})
    assert specs is not None and band is not None and grid is not None
    if band.size < 2 or not np.allclose(np.diff(band), band[1] - band[0]):
        raise ValueError("the band must be a uniform grid of at least 2 frequencies")
    if grid.size < 2:
        raise ValueError("the datasets have no profile grid (profile_grid_mm)")
    response = np.concatenate(responses)
    if not np.isfinite(response).all():
        raise ValueError("some rows' sweeps are not finite")
    return SweepData(specs, np.concatenate(codes), band, grid, response,
                     np.concatenate(radii), sources)


def log_magnitudes(z: np.ndarray, ln_scale: np.ndarray | float = 0.0) -> np.ndarray:
    """ln |u| [ln um] of components ``z`` (..., P, 6) (times exp(``ln_scale``), broadcast
    over the leading axes): shape (..., P)."""
    ss = np.maximum(np.sum(np.square(z, dtype=float), axis=-1), TINY)
    return np.asarray(ln_scale)[..., None] + 0.5 * np.log(ss)


def log_normal(z: np.ndarray, ln_scale: np.ndarray | float = 0.0) -> np.ndarray:
    """ln |u_z| [ln um] of components ``z`` (..., P, 6), as :func:`log_magnitudes`."""
    ss = np.maximum(np.sum(np.square(z[..., 2 * Z:2 * Z + 2], dtype=float), axis=-1), TINY)
    return np.asarray(ln_scale)[..., None] + 0.5 * np.log(ss)


def log_output_columns(ln_mag: np.ndarray, ln_normal: np.ndarray | None = None) -> np.ndarray:
    """The graph's log outputs from ln magnitudes (..., P) (and ln |u_z| when the model has
    ``profile_normal_um``): [centre, edge, edge / centre, profile (P - 1), normal (P - 1)]."""
    c, e = ln_mag[..., :1], ln_mag[..., 1:2]
    cols = [c, e, e - c, ln_mag[..., 1:]]
    if ln_normal is not None:
        cols.append(ln_normal[..., 1:])
    return np.concatenate(cols, axis=-1)


class BandTargets:
    """Targets [ln s, POD coefficients of the weighted normalised complex band] of sweeps.

    Two blocks, each with its own POD of the flattened (n_f * locations * 6) band: the centre
    and the edge (``centre_modes``: they are few numbers and need few modes), and the profile
    beyond the edge (``profile_modes``: the wave pattern over 40 mm needs many more). Each
    block's basis is then factored through a spatial basis shared by the band's frequencies
    (:mod:`surrogate.sweep.basis`, relative error of the weighted components on the fitting
    designs at most ``spatial_tol``; 0 keeps every spatial vector: exact), and the factored
    basis is the model's: :meth:`components` and the graph rebuild through it.
    Fitted: ``weights_`` (P,) per-location weights, ``pods`` (two
    :class:`surrogate.pod.POD`), ``factors`` (two :class:`surrogate.sweep.basis.SpatialFactor`),
    ``shape_`` (n_f, P)."""

    def __init__(self, centre_modes: int = 48, profile_modes: int = 128,
                 spatial_tol: float = 1e-3) -> None:
        self.centre_modes = centre_modes
        self.profile_modes = profile_modes
        self.spatial_tol = spatial_tol

    def fit_transform(self, response: np.ndarray) -> np.ndarray:
        """Fit on (n, n_f, P, 6) responses [um]; return the (n, 1 + k) targets."""
        n, n_f, P, _ = response.shape
        ln_s, z = self._normalise(response)
        self.weights_ = np.sqrt(np.mean(np.sum(np.square(z, dtype=float), axis=-1),
                                        axis=(0, 1)))
        if not np.all(self.weights_ > 0):
            raise ValueError("a location's response is zero on every training design")
        self.shape_ = (n_f, P)
        limit = n - 1
        self.pods = [POD(n_modes=max(1, min(k, limit, n_f * len(loc) * 6)))
                     for k, loc in zip((self.centre_modes, self.profile_modes), self._blocks(),
                                       strict=True)]
        coefficients = [pod.fit_transform(b) for pod, b in zip(self.pods, self._flat(z),
                                                                   strict=True)]
        self.factors = [factor_block(*self._block_basis(j), c, self._block_weights(j),
                                     tol=self.spatial_tol)
                        for j, c in enumerate(coefficients)]
        return np.column_stack([ln_s, *coefficients])

    def transform(self, response: np.ndarray) -> np.ndarray:
        """The targets of (n, n_f, P, 6) responses with the fitted basis."""
        ln_s, z = self._normalise(response)
        return np.column_stack([ln_s, *(pod.transform(b) for pod, b in
                                        zip(self.pods, self._flat(z), strict=True))])

    def _blocks(self) -> tuple[list[int], list[int]]:
        P = self.shape_[1]
        return [0, 1], list(range(2, P))

    def _flat(self, z: np.ndarray) -> list[np.ndarray]:
        zw = z / self.weights_[None, None, :, None]
        return [zw[:, :, loc].reshape(len(z), -1) for loc in self._blocks()]

    @staticmethod
    def _normalise(response: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(ln s (n,), response / s) with s the band's RMS centre amplitude [um]."""
        centre_sq = np.sum(np.square(response[:, :, 0, :], dtype=float), axis=-1)
        s = np.sqrt(np.mean(centre_sq, axis=1))
        if not np.all(s > 0):
            raise ValueError("a design's centre response is zero over the whole band")
        return np.log(s), response / s[:, None, None, None]

    @property
    def n_modes(self) -> int:
        """Coefficients of both blocks."""
        return sum(int(pod.modes_.shape[0]) for pod in self.pods)

    def block_values(self) -> list[slice]:
        """Per block, its values in a location-major flattened (P * 6) row."""
        return [slice(6 * loc[0], 6 * (loc[-1] + 1)) for loc in self._blocks()]

    def block_modes(self) -> list[slice]:
        """Per block, its coefficients in a (k,) coefficient row (the targets without ln s)."""
        sizes = np.cumsum([0, *(int(pod.modes_.shape[0]) for pod in self.pods)])
        return [slice(int(a), int(b)) for a, b in itertools.pairwise(sizes)]

    def _block_basis(self, j: int) -> tuple[np.ndarray, np.ndarray]:
        """Block ``j``'s POD as (modes (n_f, k_j, L_j), mean (n_f, L_j)), weighted space."""
        n_f, pod = self.shape_[0], self.pods[j]
        k = pod.modes_.shape[0]
        return (pod.modes_.reshape(k, n_f, -1).transpose(1, 0, 2),
                pod.mean_.reshape(n_f, -1))

    def _block_weights(self, j: int) -> np.ndarray:
        """Block ``j``'s location weights, one per value (L_j,)."""
        return np.repeat(self.weights_[self._blocks()[j]], 6)

    def band_basis(self, exact: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """(modes (n_f, k, P * 6), mean (n_f, P * 6)): normalised components at band
        frequency i = mean[i] + coefficients @ modes[i] (block-diagonal; the location weights
        folded in). The factored basis (the model's) unless ``exact``: then the PODs'."""
        n_f, P = self.shape_
        modes = np.zeros((n_f, self.n_modes, P * 6))
        mean = np.zeros((n_f, P * 6))
        for j, (rows, cols) in enumerate(zip(self.block_modes(), self.block_values(),
                                             strict=True)):
            if exact:
                m, a = self._block_basis(j)
                w = self._block_weights(j)
                m, a = m * w, a * w
            else:
                m, a = self.factors[j].modes(), self.factors[j].means()
            modes[:, rows, cols], mean[:, cols] = m, a
        return modes, mean

    def components(self, targets: np.ndarray, exact: bool = False
                   ) -> tuple[np.ndarray, np.ndarray]:
        """(ln s (...,), normalised components (..., n_f, P, 6)) of targets (..., 1 + k),
        through the factored basis unless ``exact`` (:meth:`band_basis`)."""
        n_f, P = self.shape_
        modes, mean = self.band_basis(exact)
        z = mean + np.einsum("...k,fkl->...fl", targets[..., 1:], modes)
        return targets[..., 0], z.reshape(*targets.shape[:-1], n_f, P, 6)

    def to_dict(self) -> dict[str, Any]:
        """What the card records of the representation."""
        return {"name": "complex-band-pod",
                "targets": "ln of the band's RMS centre amplitude [um], then POD coefficients "
                "of the complex components (r, z, t; re, im) over the band, divided by that "
                "RMS and by a weight per location: one POD of the centre and the edge, one of "
                "the profile beyond the edge",
                "interpolation": "linear in frequency on the band's grid, of the complex "
                "components (index floor + weight, clamped to the band)",
                "pod_modes": {"centre_edge": int(self.pods[0].modes_.shape[0]),
                              "profile": int(self.pods[1].modes_.shape[0])},
                "pod_energy": {"centre_edge": float(self.pods[0].energy_[-1]),
                               "profile": float(self.pods[1].energy_[-1])},
                "spatial_tol": self.spatial_tol,
                "spatial_rank": dict(zip(("centre_edge", "profile"),
                                         (f.rank for f in self.factors), strict=True)),
                "spatial_groups": dict(zip(("centre_edge", "profile"), (
                    [{"modes": [g.start, g.stop], "rank": r}
                     for g, r in zip(f.groups, f.ranks, strict=True)]
                    for f in self.factors), strict=True)),
                "spatial_rel_error": dict(zip(("centre_edge", "profile"),
                                              (f.rel_error for f in self.factors), strict=True)),
                "location_weights": [float(v) for v in self.weights_]}


def pair_rows(data: SweepData, designs: np.ndarray, normal: bool = False
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """The (design, band frequency) pairs of ``designs``, design-major: (codes with the
    frequency last (n * n_f, d + 1), centre [um] (n * n_f,), profile [um] (n * n_f, n_p),
    extra profiles by output name: ``profile_normal_um`` when ``normal``)."""
    n_f = data.band_hz.size
    codes = np.column_stack([np.repeat(data.codes[designs], n_f, axis=0),
                             np.tile(data.band_hz, designs.size)])
    z = data.response[designs].reshape(designs.size * n_f, -1, 6)
    mag = np.sqrt(np.sum(np.square(z, dtype=float), axis=-1))
    extra = {}
    if normal:
        extra["profile_normal_um"] = np.sqrt(np.sum(np.square(z[:, 1:, 2 * Z:2 * Z + 2],
                                                              dtype=float), axis=-1))
    return codes, mag[:, 0], mag[:, 1:], extra
