"""The in-graph decode of a sweep model: ensemble heads -> complex band -> the requested
frequency -> ln magnitudes, exported as the one graph contract of :mod:`surrogate.export`.

    x (batch, d + 1): encoded design features, then the encoded frequency (its last column)
      -> each member's targets y = [ln s, POD coefficients]       (members, batch, 1 + k)
      -> t = (f - f_0) / step from the frequency's feature, clamped to [0, n_f - 1];
         i = min(floor(t), n_f - 2), w = t - i
      -> normalised components z = mean_t + y[1:] @ modes_t at the band's grid points i and
         i + 1, linearly interpolated with the weight w            (members, batch, P, 6)
      -> ln |u| = ln s + 0.5 ln(sum of squares of the six parts)   (members, batch, P)
      -> log outputs [centre, edge, edge / centre, profile, (normal profile)]
      -> log_mean, log_std: their mean and (population) std over the members.

Rebuilding two grid points per row rather than the whole band costs 2 / n_f of it. The modes
and the means carry the per-location weights of :class:`surrogate.sweep_targets.BandTargets`,
so the graph needs nothing outside it. :func:`reference_log_outputs` is the graph-free numpy version
(training checks the exported graph against it).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import torch

from surrogate.export import export_module
from surrogate.nn import MLPEnsembleRegressor
from surrogate.sweep_targets import (
    TINY,
    BandTargets,
    Z,
    log_magnitudes,
    log_normal,
    log_output_columns,
)

__all__ = ["BandDecoder", "SweepEnsembleModule", "export_sweep_nn", "magnitude_error",
           "member_targets",
           "reference_log_outputs"]


class BandDecoder(torch.nn.Module):
    """Member targets (M, b, 1 + k) and a fractional band index t (b,) -> log outputs
    (M, b, 3 + m [+ m]) (``normal``: with the ln |u_z| profile block)."""

    def __init__(self, targets: BandTargets, normal: bool = False) -> None:
        super().__init__()
        modes, mean = targets.band_basis()
        f32 = torch.float32
        self.register_buffer("modes", torch.as_tensor(modes, dtype=f32))   # (n_f, k, L)
        self.register_buffer("mean", torch.as_tensor(mean, dtype=f32))     # (n_f, L)
        self.n_f, self.P = targets.shape_
        self.normal = normal

    def components(self, y: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
        """Normalised components (M, b, P, 6) at fractional band indices ``t`` (b,)."""
        t = t.clamp(0.0, float(self.n_f - 1))
        i0 = t.floor().clamp(max=float(self.n_f - 2))
        w = (t - i0).unsqueeze(-1)
        i0 = i0.long()
        c = y[..., 1:].transpose(0, 1)                                 # (b, M, k)
        # one (M x k) @ (k x L) product per row and grid point, then the weights: the same
        # arithmetic as interpolating the basis, without a (b, k, L) interpolated copy
        z0 = torch.matmul(c, self.modes.index_select(0, i0)) \
            + self.mean.index_select(0, i0).unsqueeze(1)               # (b, M, L)
        z1 = torch.matmul(c, self.modes.index_select(0, i0 + 1)) \
            + self.mean.index_select(0, i0 + 1).unsqueeze(1)
        z = z0 + w.unsqueeze(-1) * (z1 - z0)
        return z.transpose(0, 1).unflatten(-1, (self.P, 6))

    def at_grid(self, y: torch.Tensor, index: torch.Tensor) -> torch.Tensor:
        """Normalised components (M, b, F, P, 6) at the band grid points ``index`` (F,)."""
        z = self.mean[index] + torch.einsum("mbk,fkl->mbfl", y[..., 1:], self.modes[index])
        return z.unflatten(-1, (self.P, 6))

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
        self.ensemble = estimator.to_module()
        self.decoder = decoder
        self.d = int(estimator.n_features_in_)
        step = float(band_hz[1] - band_hz[0])
        # encoded frequency e = (f - low) / (high - low)  ->  t = (f - f_0) / step
        self.t_scale = float((frequency_high - frequency_low) / step)
        self.t_offset = float((frequency_low - band_hz[0]) / step)

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        y = torch.matmul(self.ensemble.members(x[:, :self.d]), self.ensemble.B) \
            + self.ensemble.b
        out = self.decoder(y, x[:, self.d] * self.t_scale + self.t_offset)
        mean = out.mean(dim=0)
        std = ((out - mean) ** 2).mean(dim=0).sqrt()
        return mean, std


def member_targets(estimator: MLPEnsembleRegressor, X: np.ndarray) -> np.ndarray:
    """Every member's targets (members, n, 1 + k) for design features ``X`` (float64)."""
    module = estimator.to_module()
    with torch.no_grad():
        x = torch.as_tensor(X, dtype=torch.float32)
        y = torch.matmul(module.members(x), module.B) + module.b
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
    """The ``error`` of :meth:`surrogate.nn.MLPEnsembleRegressor.refit` that trains the members
    through the decode on what users meet: squared errors of ln |u| at band frequencies (a
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
