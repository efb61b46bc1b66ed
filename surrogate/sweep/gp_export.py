"""The sweep GP (:class:`surrogate.sweep.gp.SweepGP`) as one float64 ONNX graph of the one
graph contract of :mod:`surrogate.estimators.export` (input ``x``: design features, then the encoded
frequency; outputs ``log_mean``, ``log_std``).

    x -> K* = amp * Matern_5/2(x / ls, X / ls)                        (batch, N)
      -> mean targets y = y_mean + (alpha' @ K*')'                     (batch, T)
      -> v = amp - |K*[:, inducing] @ G|^2 + noise                       (batch,)
      -> the decode of :class:`surrogate.sweep.export.BandDecoder` (cast to float64): the
         complex band at the requested frequency, ln |u| -> log_mean
      -> log_std: v propagated to first order, log_std_p^2 = v (s_0^2 + g_p' C_p(t) g_p) with
         g_p = z_p / |z_p|^2 (the gradient of ln |u_p| in the six component parts z_p) and
         C_p(t) = sum_j s_j^2 M_jp(t) M_jp(t)' the 6 x 6 covariance the coefficients' unit
         variance puts on z_p (s_j: their ``y_std_``, M_jp(t) the basis interpolated to t).

C_p(t) is quadratic in the interpolation weight w: (1 - w)^2 D[i] + w^2 D[i + 1]
+ w (1 - w) H[i], with D (the band's grid) and H (neighbouring grid points) tabulated once
from :meth:`surrogate.sweep.targets.BandTargets.band_basis` (one extra pair: the centre-edge
covariance for the edge / centre column). So the std costs a few hundred flops per row beside
the decode. G (:meth:`SweepGP.variance_factor`) folds the DTC variance's two triangular
products (amp - |a|^2 + |a L_B^-T|^2, a = K*[:, inducing] L_m^-T) into one; alpha is the
left operand of the mean's product. Both because at one design onnxruntime's float64
products read their constant operand at a fraction of the memory rate numpy's reach, so the
bytes read are the time (docs/sweep-models.md, "The shipped models' cost"). This module uses
only the decoder's public behaviour (``components``,
``log_outputs``). :func:`gp_parity` checks the graph against the numpy rebuild
(:meth:`SweepGP.predict`, :func:`surrogate.sweep.export.reference_log_outputs`,
:func:`surrogate.sweep.gp.linearised_log_std`, all float64).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import torch

from surrogate.estimators.export import export_module
from surrogate.kind import SweepKind, estimator_params
from surrogate.runtime.encoding import encode
from surrogate.runtime.predictor import Predictor
from surrogate.sweep.export import BandDecoder, reference_log_outputs
from surrogate.sweep.gp import SweepGP, fit_sweep_gp, linearised_log_std, split_gp_options
from surrogate.sweep.targets import TINY, BandTargets, SweepData, Z, pair_rows

__all__ = ["GP_PARITY_TOL", "SWEEP", "SweepGPModule", "covariance_tables", "export_sweep_gp",
           "gp_parity", "std_difference"]

#: Largest |d ln| of log_mean, and relative difference of log_std (of :data:`STD_FLOOR`),
#: between the float64 graph and the float64 rebuild at every band frequency of held-out
#: designs.
GP_PARITY_TOL = 1e-6
#: Below this log-std (an interval narrower than 0.1 %) its difference is relative to this.
#: The difference is taken of the variances, |s_g^2 - s_r^2| / (2 max(s_r, floor)^2) (|d s| / s
#: to first order above the floor): the edge / centre column's variance is a difference
#: (q_0 + q_1 - 2 q_01) that is rounding alone where centre and edge move together, and its
#: square root turns a rounding of 1e-16 into a std of 1e-8, 1e-5 of the floor.
STD_FLOOR = 1e-3
#: Held-out designs checked for export parity (every band frequency of each).
_PARITY_DESIGNS = 32


def covariance_tables(targets: BandTargets, y_std: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(D (n_f, P + 1, 6, 6), H (n_f - 1, P + 1, 6, 6)): at grid point i,
    D[i, p] = sum_j s_j^2 M_ijp M_ijp' for every location p, and D[i, P] the centre-edge
    covariance sum_j s_j^2 M_ij0 M_ij1'; H[i, .] the same with M_i on the left, M_(i+1) on the
    right, plus its transpose pair (s_j = ``y_std``[1 + j], M the basis of ``band_basis``)."""
    modes, _ = targets.band_basis()
    n_f, P = targets.shape_
    M = modes.reshape(n_f, -1, P, 6) * y_std[None, 1:, None, None]
    D = np.concatenate([np.einsum("fjpc,fjpd->fpcd", M, M),
                        np.einsum("fjc,fjd->fcd", M[:, :, 0], M[:, :, 1])[:, None]], axis=1)
    a, b = M[:-1], M[1:]
    G = np.einsum("fjpc,fjpd->fpcd", a, b)
    G01 = np.einsum("fjc,fjd->fcd", a[:, :, 0], b[:, :, 1])
    G10 = np.einsum("fjc,fjd->fcd", a[:, :, 1], b[:, :, 0])
    H = np.concatenate([G + G.transpose(0, 1, 3, 2), (G01 + G10.transpose(0, 2, 1))[:, None]],
                       axis=1)
    return D, H


class SweepGPModule(torch.nn.Module):
    """x (n, d + 1) float64 -> (log_mean, log_std) (n, 3 + m [+ m]): the exported sweep GP."""

    def __init__(self, est: SweepGP, targets: BandTargets, normal: bool, frequency_low: float,
                 frequency_high: float, band_hz: np.ndarray) -> None:
        super().__init__()
        f64 = torch.float64

        def buf(name: str, value: Any, dtype: torch.dtype = f64) -> None:
            self.register_buffer(name, torch.as_tensor(np.asarray(value), dtype=dtype))

        # centred on the unit cube: |x|^2 of the distance expansion 4x smaller (its rounding,
        # through L_m^-1, is what limits the variance's precision near the data)
        Xs = (est.X_train_ - 0.5) / est.length_scale_
        buf("inv_ls", 1.0 / est.length_scale_)
        buf("Xs_T", Xs.T.copy())
        buf("Xs_sq", np.sum(Xs * Xs, axis=1))
        buf("alpha_T", est.alpha_.T.copy())
        buf("y_mean", est.y_mean_)
        buf("inducing", est.inducing_, torch.long)
        buf("G", est.variance_factor())
        D, H = covariance_tables(targets, est.y_std_)
        buf("D", D)
        buf("H", H)
        buf("zmask", np.eye(6)[[2 * Z, 2 * Z + 1]].sum(axis=0))
        buf("t_max", float(targets.shape_[0] - 1))
        # scalars as float64 tensors: the exporter writes a Python float as a float32 constant
        buf("amp", est.amp_)
        buf("noise", est.noise_)
        buf("s0", est.y_std_[0] ** 2)
        buf("five_thirds", 5.0 / 3.0)
        self.d = int(Xs.shape[1])
        self.decoder = BandDecoder(targets, normal).double()
        self.n_f, self.P = targets.shape_
        self.normal = normal
        step = float(band_hz[1] - band_hz[0])
        # encoded frequency e = (f - low) / (high - low)  ->  t = (f - f_0) / step
        buf("t_scale", (frequency_high - frequency_low) / step)
        buf("t_offset", (frequency_low - band_hz[0]) / step)

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        xs = (x[:, :self.d] - 0.5) * self.inv_ls
        d2 = torch.relu((xs * xs).sum(dim=1, keepdim=True) - 2.0 * torch.matmul(xs, self.Xs_T)
                        + self.Xs_sq)
        r = torch.sqrt(5.0 * d2)
        k = self.amp * (1.0 + r + self.five_thirds * d2) * torch.exp(-r)       # (n, N)
        y = torch.matmul(self.alpha_T, k.T).T + self.y_mean                # (n, T)
        a = torch.matmul(k.index_select(1, self.inducing), self.G)
        v = torch.relu(self.amp - (a * a).sum(dim=1)) + self.noise
        t = x[:, self.d] * self.t_scale + self.t_offset
        z = self.decoder.components(y.unsqueeze(0), t)                      # (1, n, P, 6)
        log_mean = self.decoder.log_outputs(y.unsqueeze(0), z)[0]
        return log_mean, torch.sqrt(v.unsqueeze(1) * self._linear_var(z[0], t))

    def _linear_var(self, z: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
        """sum_j (s_j d out / d y_j)^2 of every log output column (n, 3 + m [+ m]) for the
        components ``z`` (n, P, 6) at fractional band indices ``t`` (n,)."""
        # the decoder's clamp to the band (torch.clamp twice on one tensor breaks the export)
        t = torch.minimum(torch.relu(t), self.t_max)
        i0 = torch.minimum(t.floor(), self.t_max - 1.0)
        w = (t - i0)[:, None, None, None]
        i0 = i0.long()
        C = ((1.0 - w) ** 2 * self.D.index_select(0, i0) + w * w * self.D.index_select(0, i0 + 1)
             + w * (1.0 - w) * self.H.index_select(0, i0))                 # (n, P + 1, 6, 6)
        g = z / (z * z).sum(dim=-1, keepdim=True).clamp(min=TINY)          # (n, P, 6)
        left = torch.cat([g, g[:, :1]], dim=1)
        right = torch.cat([g, g[:, 1:2]], dim=1)
        q = (left * torch.matmul(C, right.unsqueeze(-1)).squeeze(-1)).sum(dim=-1)  # (n, P + 1)
        qp = q[:, :self.P]
        cols = [self.s0 + qp[:, :2], torch.relu(qp[:, :1] + qp[:, 1:2] - 2.0 * q[:, self.P:]),
                self.s0 + qp[:, 1:]]
        if self.normal:
            uz = z * self.zmask
            gz = uz / (uz * uz).sum(dim=-1, keepdim=True).clamp(min=TINY)
            qz = (gz * torch.matmul(C[:, :self.P], gz.unsqueeze(-1)).squeeze(-1)).sum(dim=-1)
            cols.append(self.s0 + qz[:, 1:])
        return torch.cat(cols, dim=1)


def export_sweep_gp(est: SweepGP, targets: BandTargets, normal: bool, frequency_low: float,
                    frequency_high: float, band_hz: np.ndarray,
                    metadata: Mapping[str, Any]) -> bytes:
    """ONNX bytes of a sweep GP (float64 input ``x``: design features, then frequency)."""
    module = SweepGPModule(est, targets, normal, frequency_low, frequency_high, band_hz).eval()
    return export_module(module, module.d + 1, metadata, dtype="float64")


def reference_gp_outputs(est: SweepGP, targets: BandTargets, X: np.ndarray, index: np.ndarray,
                         normal: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Graph-free outputs at design features ``X`` (n, d) and band grid indices ``index`` (n,):
    (log_mean through the decoder itself run eagerly in float64, log_mean through the numpy
    decode of :func:`surrogate.sweep.export.reference_log_outputs`, log_std of
    :func:`surrogate.sweep.gp.linearised_log_std` at the decoder's components), each (n, K),
    from the numpy GP."""
    y, v = est.predict(X)
    decoder = BandDecoder(targets, normal).double()
    with torch.no_grad():
        yt, tt = torch.as_tensor(y)[None], torch.as_tensor(index, dtype=torch.float64)
        z = decoder.components(yt, tt)
        eager = decoder.log_outputs(yt, z)[0].numpy()
    numpy_mean, _ = reference_log_outputs(targets, y[None], index, normal)
    return eager, numpy_mean, linearised_log_std(targets, y, v, index.astype(float),
                                                 est.y_std_, normal, z[0].numpy())


def std_difference(got: np.ndarray, ref: np.ndarray) -> float:
    """The largest relative difference of log-stds ``got`` from ``ref``, taken of the
    variances: |got^2 - ref^2| / (2 max(ref, :data:`STD_FLOOR`)^2)."""
    return float(np.max(np.abs(got**2 - ref**2) / (2.0 * np.maximum(ref, STD_FLOOR) ** 2)))


def gp_parity(est: SweepGP, targets: BandTargets, session: Any, data: SweepData,
              specs: list[Any], designs: np.ndarray, normal: bool) -> dict[str, float]:
    """Largest |d ln| between the graph ``session`` and the rebuild of
    :func:`reference_gp_outputs` at every band frequency of up to :data:`_PARITY_DESIGNS`
    ``designs``: ``log_mean`` against the decoder run eagerly on the numpy GP's targets,
    (raises above :data:`GP_PARITY_TOL`), ``log_std_rel`` against the numpy linearisation
    (the variances' difference of :data:`STD_FLOOR`; raises above :data:`GP_PARITY_TOL`), and,
    recorded only, ``log_mean`` against the all-numpy decode (the decoder stores its basis in
    float32: about 1e-7 relative in each component, amplified where |u| nearly vanishes)."""
    designs = designs[:_PARITY_DESIGNS]
    n_f = data.band_hz.size
    codes, *_ = pair_rows(data, designs)
    X = encode(data.codes[designs], data.specs)
    eager, numpy_mean, ref_std = reference_gp_outputs(
        est, targets, np.repeat(X, n_f, axis=0), np.tile(np.arange(n_f), designs.size), normal)
    got_mean, got_std = session.run(["log_mean", "log_std"],
                                    {"x": encode(codes, specs).astype(np.float64)})
    out = {"log_mean": float(np.abs(got_mean - eager).max()),
           "log_std_rel": std_difference(got_std, ref_std),
           "log_mean_vs_float64_basis": float(np.abs(got_mean - numpy_mean).max())}
    if not out["log_mean"] <= GP_PARITY_TOL:
        raise RuntimeError(f"exported sweep GP's log_mean differs from its numpy rebuild by "
                           f"{out['log_mean']:.3g} (tolerance {GP_PARITY_TOL})")
    if not out["log_std_rel"] <= GP_PARITY_TOL:
        raise RuntimeError(f"exported sweep GP's log_std differs from its numpy rebuild by "
                           f"{out['log_std_rel']:.3g} relative (tolerance {GP_PARITY_TOL})")
    return out


def _fit(checked: dict[str, Any], data: SweepData, designs: np.ndarray, seed: int,
         n_modes: int | None, normal: bool) -> tuple[SweepGP, BandTargets, dict[str, Any]]:
    """(estimator, targets, the card's training entries) of the GP on ``designs``."""
    est, targets = fit_sweep_gp(data, designs, seed=seed, n_modes=n_modes, options=checked)
    return est, targets, {"gp": est.card(), "estimator": estimator_params(est)}


def _parity(est: SweepGP, targets: BandTargets, predictor: Predictor, data: SweepData,
            designs: np.ndarray, normal: bool) -> dict[str, Any]:
    parity = gp_parity(est, targets, predictor.session, data, data.all_specs, designs, normal)
    return {"export_parity_max_abs_dln": parity["log_mean"],
            "export_parity": parity}  # with log_std's relative difference


#: The GP's part of the sweep pipeline (:class:`surrogate.kind.SweepKind`, joined to its kind in
#: :mod:`surrogate.kinds`).
SWEEP = SweepKind(check_options=split_gp_options, fit=_fit, export=export_sweep_gp,
                  parity=_parity)
