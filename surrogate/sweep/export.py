"""The in-graph decode of a sweep model: ensemble heads -> complex band -> the requested
frequency -> ln magnitudes, exported as the one graph contract of
:mod:`surrogate.estimators.export`.

    x (batch, d + 1): encoded design features, then the encoded frequency (its last column)
      -> each member's targets y = [ln s, POD coefficients]       (members, batch, 1 + k)
      -> t = (f - f_0) / step from the frequency's feature, clamped to [0, n_f - 1];
         i = min(floor(t), n_f - 2), w = t - i
      -> per POD block j (centre + edge; the profile beyond the edge), with the block's
         factored basis (:mod:`surrogate.sweep.basis`: per group g of its modes
         modes[f][g] = A_g[f] @ Psi[:S_g], mean[f] = a[f] @ Psi):
         v = sum_g [(1 - w) y_g, w y_g] @ [A_g[i]; A_g[i + 1]] (one gather of both grid
         points, 2 k_g x S_g per row, and the interpolation inside the product, padded to S)
         + the interpolated mean's coordinates, then z_j = v @ Psi (one dense product shared
         by every row)                                              (members, batch, P, 6)
      -> ln |u| = ln s + 0.5 ln(sum of squares of the six parts)   (members, batch, P)
      -> log outputs [centre, edge, edge / centre, profile, (normal profile)]
      -> log_mean, log_std: their mean and (population) std over the members.

Per row the decode gathers sum_g 2 k_g S_g numbers of each block (not the band's k x P * 6
modes at two grid points, with the zeros off the blocks) and does 2 M (sum_g 2 k_g S_g + S L_j)
FLOPs; ``bench/surrogate/sweep_predict.py`` counts and times them. The
members' target scaling is folded into their last layer. Psi carries the per-location
weights of :class:`surrogate.sweep.targets.BandTargets`, so the graph needs nothing outside
it. :func:`reference_log_outputs` is the graph-free numpy version (through the same factored
basis; training checks the exported graph against it).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import torch

from surrogate.estimators.export import export_module
from surrogate.estimators.nn import EnsembleModule, MLPEnsembleRegressor
from surrogate.sweep.targets import (
    TINY,
    BandTargets,
    Z,
    log_magnitudes,
    log_normal,
    log_output_columns,
)

__all__ = ["BandDecoder", "SweepEnsembleModule", "export_sweep_nn", "magnitude_error",
           "member_targets", "reference_log_outputs", "target_module"]


class BandDecoder(torch.nn.Module):
    """Member targets (M, b, 1 + k) and a fractional band index t (b,) -> log outputs
    (M, b, 3 + m [+ m]) (``normal``: with the ln |u_z| profile block), through the factored
    basis of each block (:attr:`surrogate.sweep.targets.BandTargets.factors`)."""

    def __init__(self, targets: BandTargets, normal: bool = False) -> None:
        super().__init__()
        f32 = torch.float32
        self.n_f, self.P = targets.shape_
        self.normal = normal
        self.rows = targets.block_modes()
        self.groups: list[list[slice]] = []
        for j, fac in enumerate(targets.factors):
            self.groups.append(list(fac.groups))
            for g, coef in enumerate(fac.coefs):
                # grid points i and i + 1 stacked along the modes, so that one product by the
                # coefficients weighted [(1 - w) c, w c] interpolates: (n_f - 1, 2 k_g, S_g)
                pair = np.concatenate([coef[:-1], coef[1:]], axis=1)
                self.register_buffer(f"coef{j}_{g}", torch.as_tensor(coef, dtype=f32))
                self.register_buffer(f"pair{j}_{g}", torch.as_tensor(pair, dtype=f32))
            pair_mean = np.stack([fac.mean[:-1], fac.mean[1:]], axis=1)  # (n_f - 1, 2, S)
            self.register_buffer(f"mean{j}", torch.as_tensor(fac.mean, dtype=f32))
            self.register_buffer(f"pair_mean{j}", torch.as_tensor(pair_mean, dtype=f32))
            self.register_buffer(f"psi{j}", torch.as_tensor(fac.psi, dtype=f32))  # (S, L_j)

    def _buffer(self, name: str, *index: int) -> torch.Tensor:
        return getattr(self, name + "_".join(str(i) for i in index))

    def components(self, y: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
        """Normalised components (M, b, P, 6) at fractional band indices ``t`` (b,)."""
        t = t.clamp(0.0, float(self.n_f - 1))
        i0 = t.floor().clamp(max=float(self.n_f - 2))
        w = (t - i0).unsqueeze(-1)
        weights = torch.cat([1.0 - w, w], dim=-1).unsqueeze(-1)       # (b, 2, 1)
        i0 = i0.long()
        # the coefficients weighted for grid points i and i + 1: (b, M, 2, k)
        cw = y[..., 1:].transpose(0, 1).unsqueeze(2) * weights.unsqueeze(1)
        parts = []
        for j, rows in enumerate(self.rows):
            v = (self._buffer("pair_mean", j).index_select(0, i0) * weights).sum(1)
            v = v.unsqueeze(1)                                         # (b, 1, S)
            S = v.shape[-1]
            for g, modes in enumerate(self.groups[j]):
                # one (M x 2 k_g) @ (2 k_g x S_g) product per row: both grid points and the
                # interpolation; padded to S (the groups' spatial vectors are nested)
                m = slice(rows.start + modes.start, rows.start + modes.stop)
                u = torch.matmul(cw[..., m].flatten(-2),
                                 self._buffer("pair", j, g).index_select(0, i0))
                v = v + (torch.nn.functional.pad(u, (0, S - u.shape[-1]))
                         if u.shape[-1] < S else u)
            # then one dense product by the spatial basis, shared by every row
            parts.append(torch.matmul(v.transpose(0, 1), self._buffer("psi", j)))
        return torch.cat(parts, dim=-1).unflatten(-1, (self.P, 6))

    def at_grid(self, y: torch.Tensor, index: torch.Tensor) -> torch.Tensor:
        """Normalised components (M, b, F, P, 6) at the band grid points ``index`` (F,)."""
        parts = []
        for j, rows in enumerate(self.rows):
            cj = y[..., 1:][..., rows]
            z = torch.matmul(self._buffer("mean", j)[index], self._buffer("psi", j))
            for g, modes in enumerate(self.groups[j]):
                coef = self._buffer("coef", j, g)
                v = torch.einsum("mbk,fks->mbfs", cj[..., modes], coef[index])
                z = z + torch.matmul(v, self._buffer("psi", j)[:coef.shape[2]])
            parts.append(z)
        return torch.cat(parts, dim=-1).unflatten(-1, (self.P, 6))

    def log_outputs(self, y: torch.Tensor, z: torch.Tensor) -> torch.Tensor:
        """Log outputs of components ``z`` (M, b, [F,] P, 6) and targets ``y`` (M, b, 1 + k)."""
        ln_s = y[..., :1] if z.dim() == 4 else y[..., :1].unsqueeze(-1)
        ln = ln_s + 0.5 * torch.log((z * z).sum(-1).clamp(min=TINY))
        c, e = ln[..., :1], ln[..., 1:2]
        cols = [c, e, e - c, ln[..., 1:]]
        if self.normal:
            uz = z[..., 2 * Z:2 * Z + 2]
            cols.append((ln_s + 0.5 * torch.log((uz * uz).sum(-1).clamp(min=TINY)))[..., 1:])
        return torch.cat(cols, dim=-1)

    def forward(self, y: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
        return self.log_outputs(y, self.components(y, t))


class SweepEnsembleModule(torch.nn.Module):
    """x (n, d + 1) -> (log_mean, log_std) (n, 3 + m [+ m]): the exported sweep model."""

    def __init__(self, estimator: MLPEnsembleRegressor, decoder: BandDecoder,
                 frequency_low: float, frequency_high: float, band_hz: np.ndarray) -> None:
        super().__init__()
        self.ensemble = target_module(estimator)
        self.decoder = decoder
        self.d = int(estimator.n_features_in_)
        step = float(band_hz[1] - band_hz[0])
        # encoded frequency e = (f - low) / (high - low)  ->  t = (f - f_0) / step
        self.t_scale = float((frequency_high - frequency_low) / step)
        self.t_offset = float((frequency_low - band_hz[0]) / step)

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        y = self.ensemble.members(x[:, :self.d])
        out = self.decoder(y, x[:, self.d] * self.t_scale + self.t_offset)
        mean = out.mean(dim=0)
        std = ((out - mean) ** 2).mean(dim=0).sqrt()
        return mean, std


def target_module(estimator: MLPEnsembleRegressor) -> EnsembleModule:
    """The members as a torch module whose ``members(x)`` are the targets themselves: the
    estimator's target scaling (a diagonal map) folded into the last layer, so the graph
    does no (k x k) product by it."""
    module = estimator.to_module()
    scale = torch.as_tensor(estimator.y_scale_, dtype=torch.float32)
    with torch.no_grad():
        module.weights[-1].mul_(scale)
        module.biases[-1].mul_(scale).add_(torch.as_tensor(estimator.y_mean_,
                                                           dtype=torch.float32))
    return module


def member_targets(estimator: MLPEnsembleRegressor, X: np.ndarray) -> np.ndarray:
    """Every member's targets (members, n, 1 + k) for design features ``X`` (float64)."""
    with torch.no_grad():
        y = target_module(estimator).members(torch.as_tensor(X, dtype=torch.float32))
    return y.double().numpy()


def reference_log_outputs(targets: BandTargets, y: np.ndarray, index: np.ndarray,
                          normal: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Graph-free (log_mean, log_std) (n, K) of member targets ``y`` (M, n, 1 + k) at band grid
    indices ``index`` (n,): the numpy rebuild of :class:`SweepEnsembleModule`'s outputs."""
    ln_s, z = targets.components(y)                 # (M, n), (M, n, n_f, P, 6)
    rows = np.arange(y.shape[1])
    zi = z[:, rows, index]                          # (M, n, P, 6)
    ln_mag = log_magnitudes(zi, ln_s)
    out = log_output_columns(ln_mag, log_normal(zi, ln_s) if normal else None)
    mean = out.mean(axis=0)
    return mean, np.sqrt(((out - mean) ** 2).mean(axis=0))


def export_sweep_nn(estimator: MLPEnsembleRegressor, targets: BandTargets, normal: bool,
                    frequency_low: float, frequency_high: float, band_hz: np.ndarray,
                    metadata: Mapping[str, Any]) -> bytes:
    """ONNX bytes of a sweep model (float32 input ``x``: design features, then frequency)."""
    module = SweepEnsembleModule(estimator, BandDecoder(targets, normal), frequency_low,
                                 frequency_high, band_hz).eval()
    return export_module(module, module.d + 1, metadata)


def magnitude_error(decoder: BandDecoder, response: np.ndarray, *, per_step: int = 8,
                    val_every: int = 8, centre_weight: float = 1.0) -> Any:
    """The ``error`` of :meth:`surrogate.estimators.nn.MLPEnsembleRegressor.refit` that trains the
    members through the decode on what users meet: squared errors of ln |u| at band frequencies (a
    random ``per_step`` of them per step, every ``val_every``-th one for validation) of the
    centre, the edge and the profile (each a third of the weight; with the normal profile a
    quarter each; ``centre_weight`` multiplies the centre's), against ``response``
    (n, n_f, P, 6) [um] of the fitted rows."""
    truth_mag = log_magnitudes(response)                                   # (n, n_f, P)
    parts = [truth_mag[..., :2], truth_mag[..., 1:]]
    if decoder.normal:
        parts.append(log_normal(response)[..., 1:])
    truth = torch.as_tensor(np.concatenate(parts, axis=-1), dtype=torch.float32)
    m = decoder.P - 1
    shares = [centre_weight, 1.0, *([1.0 / m] * m), *([1.0 / m] * (m if decoder.normal else 0))]
    w = torch.as_tensor(shares, dtype=torch.float32)
    w = w * (w.numel() / w.sum())
    keep = [0, 1, *range(3, 3 + m * (2 if decoder.normal else 1))]  # all but edge / centre
    val_index = torch.arange(0, decoder.n_f, val_every)

    def error(y: torch.Tensor, rows: Any, training: bool) -> torch.Tensor:
        index = torch.randperm(decoder.n_f)[:per_step] if training else val_index
        out = decoder.log_outputs(y, decoder.at_grid(y, index))[..., keep]  # (M, b, F, Q)
        sq = (out - truth[rows][:, index].unsqueeze(0)) ** 2 * w
        return sq.flatten(2)

    return error
