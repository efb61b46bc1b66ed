"""A Gaussian process on sweep datasets (``hapticrom train --data SWEEP --kind gp``).

Per design the GP learns the targets of :class:`surrogate.sweep.targets.BandTargets` (ln s and
the POD coefficients of the weighted complex band), centred and scaled (``y_mean_``,
``y_std_``), with ONE kernel shared by every output:

    k(x, x') = amp * Matern_5/2(|(x - x') / ls|) + noise * [x == x']

(ARD: one length scale per design feature, features in [0, 1];
:func:`surrogate.estimators.gp.ard_kernel`).
Because the outputs share the kernel they share the posterior variance too, in scaled units:
the coefficient j's variance is ``v(x) * y_std_[j]^2``. The scale (``scale`` option): "block"
(default) divides ln s by its std and each POD block's coefficients by one common scale (the
RMS of their stds), so they keep their relative energies and the likelihood is driven by the
modes that carry the band; "output" standardises every output, and the hundred low-energy,
noise-like modes then pull the shared kernel to a large noise and short length scales (on 178
designs of default-sweep, held-out centre median 9.0 % against 2.8 % with "block";
docs/sweep-models.md).

* Hyperparameters (amp, ls, noise) maximise the marginal likelihood summed over the outputs
  on a seeded subset of at most ``max_hyper`` designs (scikit-learn's
  :class:`~sklearn.gaussian_process.GaussianProcessRegressor`, with a log marginal likelihood
  that holds one n x n matrix rather than n x n x outputs).
* The posterior mean is exact on ALL fitted designs: alpha = (K + noise I)^-1 Y (one Cholesky
  of the N x N kernel matrix), mean(x) = y_mean + y_std * (k(x, X) @ alpha).
* The posterior variance is the deterministic-training-conditional (DTC, "projected process")
  approximation on an inducing set of ``inducing`` designs (the first of the same seeded
  permutation): v(x) = amp - |a|^2 + |L_B^-1 a|^2 + noise, a = L_m^-1 k_m(x), L_m the Cholesky
  of K_mm, L_B that of I + L_m^-1 K_mn K_nm L_m^-T / noise. It uses every fitted design, is
  exact when every design is inducing, and grows to amp + noise far from the data. Its level is
  a shape, not a calibrated width: the training pipeline scales the exported log-std
  conformally (:mod:`surrogate.intervals`).

:func:`linearised_log_std` propagates v(x) through the decode to ln |u| (a first-order
expansion of ln |u| in the targets); :mod:`surrogate.sweep.gp_export` does the same in the graph.
"""

from __future__ import annotations

import time
import warnings
from typing import Any

import numpy as np
from scipy.linalg import LinAlgError, cho_solve, cholesky, solve_triangular
from sklearn.exceptions import ConvergenceWarning
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import Kernel

from surrogate.estimators.gp import ard_kernel
from surrogate.estimators.params import check_choice, check_number
from surrogate.runtime.encoding import encode
from surrogate.sweep.targets import TINY, BandTargets, SweepData, Z

__all__ = ["GP_OPTIONS", "JITTER", "SCALES", "SweepGP", "fit_sweep_gp", "linearised_log_std",
           "split_gp_options"]

#: ``--options`` of ``--kind gp`` on sweep data and their defaults (``centre_modes`` and
#: ``--modes`` size the two POD blocks as for the NN).
GP_OPTIONS: dict[str, Any] = {"max_hyper": 1500, "inducing": 512, "noise": 1e-2,
                              "noise_bounds": (1e-6, 1.0), "n_restarts_optimizer": 0,
                              "scale": "block", "centre_modes": 48}
#: ``scale``: "output" standardises every output; "block" keeps the POD coefficients' relative
#: energies (ln s by its std, each POD block by the RMS of its coefficients' std).
SCALES = ("output", "block")
#: Relative jitter on the diagonal of the inducing kernel matrix (its Cholesky); it raises the
#: variance at the inducing designs by about this times amp.
JITTER = 1e-8


def split_gp_options(options: dict[str, Any] | None) -> dict[str, Any]:
    """The checked GP options with defaults; a ValueError naming an unknown one."""
    options = dict(options or {})
    unknown = sorted(set(options) - set(GP_OPTIONS))
    if unknown:
        raise ValueError(f"{unknown[0]} = {options[unknown[0]]!r}: not an option of the sweep "
                         f"gp (allowed: {', '.join(GP_OPTIONS)})")
    out = {**GP_OPTIONS, **options}
    check_number("max_hyper", out["max_hyper"], 2, 20000, integer=True)
    check_number("inducing", out["inducing"], 1, 20000, integer=True)
    check_number("noise", out["noise"], 0, 1e3, low_open=True)
    check_number("n_restarts_optimizer", out["n_restarts_optimizer"], 0, 100, integer=True)
    check_number("centre_modes", out["centre_modes"], 1, 10**4, integer=True)
    check_choice("scale", out["scale"], SCALES)
    low, high = out["noise_bounds"]
    if not 0 < low <= out["noise"] <= high:
        raise ValueError(f"noise_bounds = {tuple(out['noise_bounds'])!r}: allowed 0 < low <= "
                         f"noise ({out['noise']:g}) <= high")
    out["noise_bounds"] = (float(low), float(high))
    return out


class _SummedGPR(GaussianProcessRegressor):
    """scikit-learn's GP regressor whose multi-output log marginal likelihood (the sum over
    the outputs, as scikit-learn's) and its gradient hold one n x n matrix instead of
    scikit-learn's n x n x outputs (3 GB at 1,500 designs and 178 outputs)."""

    def log_marginal_likelihood(self, theta: Any = None, eval_gradient: bool = False,
                                clone_kernel: bool = True) -> Any:
        if theta is None:
            return super().log_marginal_likelihood(theta, eval_gradient, clone_kernel)
        kernel = self.kernel_.clone_with_theta(theta) if clone_kernel else self.kernel_
        kernel.theta = theta
        K, K_grad = kernel(self.X_train_, eval_gradient=True) if eval_gradient \
            else (kernel(self.X_train_), None)
        K[np.diag_indices_from(K)] += self.alpha
        try:
            L = cholesky(K, lower=True, check_finite=False)
        except LinAlgError:
            return (-np.inf, np.zeros_like(theta)) if eval_gradient else -np.inf
        Y = self.y_train_.reshape(len(K), -1)
        n, T = Y.shape
        A = cho_solve((L, True), Y, check_finite=False)
        lml = -0.5 * np.sum(Y * A) - T * np.log(np.diag(L)).sum() - 0.5 * n * T * np.log(2 * np.pi)
        if not eval_gradient:
            return lml
        inner = A @ A.T - T * cho_solve((L, True), np.eye(n), check_finite=False)
        return lml, 0.5 * np.einsum("ij,jik->k", inner, K_grad)


class SweepGP:
    """The fitted sweep GP (see the module docstring). After :meth:`fit`: ``kernel_``
    (scikit-learn's fitted kernel), ``amp_``, ``length_scale_`` (d,), ``noise_`` (variances in
    the scaled units), ``X_train_`` (N, d), ``alpha_`` (N, T, with ``y_std_`` folded in),
    ``y_mean_``/``y_std_`` (T,), ``inducing_`` (m,) row indices, ``Lm_inv_T_``,
    ``LB_inv_T_`` (m, m), ``hyper_rows_``, ``fit_seconds_``."""

    def __init__(self, *, max_hyper: int = 1500, inducing: int = 512, noise: float = 1e-2,
                 noise_bounds: tuple[float, float] = (1e-6, 1.0), n_restarts_optimizer: int = 0,
                 scale: str = "block", random_state: int = 0) -> None:
        self.max_hyper = max_hyper
        self.inducing = inducing
        self.noise = noise
        self.noise_bounds = noise_bounds
        self.n_restarts_optimizer = n_restarts_optimizer
        self.scale = scale
        self.random_state = random_state

    def get_params(self) -> dict[str, Any]:
        """The constructor's parameters (for the card)."""
        return {k: getattr(self, k) for k in ("max_hyper", "inducing", "noise", "noise_bounds",
                                              "n_restarts_optimizer", "scale", "random_state")}

    def fit(self, X: np.ndarray, Y: np.ndarray,
            blocks: list[np.ndarray] | None = None) -> SweepGP:
        """Fit on design features ``X`` (N, d) in [0, 1] and targets ``Y`` (N, T) (``blocks``:
        the output columns sharing one scale with ``scale = "block"``; default: all)."""
        t0 = time.perf_counter()
        X, Y = np.asarray(X, dtype=float), np.asarray(Y, dtype=float)
        if X.ndim != 2 or Y.ndim != 2 or len(X) != len(Y) or len(X) < 2:
            raise ValueError(f"X {X.shape} and Y {Y.shape}: need (N, d) and (N, T), N >= 2")
        self.y_mean_ = Y.mean(axis=0)
        std = Y.std(axis=0)
        if self.scale == "block":
            for cols in blocks or [np.arange(Y.shape[1])]:
                std[cols] = np.sqrt(np.mean(std[cols] ** 2))
        self.y_std_ = np.where(std > 0, std, 1.0)
        Ys = (Y - self.y_mean_) / self.y_std_
        perm = np.random.default_rng(self.random_state).permutation(len(X))
        hyper = np.sort(perm[:self.max_hyper])
        gpr = _SummedGPR(ard_kernel("matern52", X.shape[1], self.noise, self.noise_bounds),
                         normalize_y=False, n_restarts_optimizer=self.n_restarts_optimizer,
                         random_state=self.random_state)
        with warnings.catch_warnings():  # a length scale at its bound means "irrelevant"
            warnings.simplefilter("ignore", ConvergenceWarning)
            gpr.fit(X[hyper], Ys[hyper])
        self.kernel_: Kernel = gpr.kernel_
        self.hyper_rows_ = int(hyper.size)
        self.amp_ = float(self.kernel_.k1.k1.constant_value)
        self.length_scale_ = np.broadcast_to(np.asarray(self.kernel_.k1.k2.length_scale, float),
                                             (X.shape[1],)).copy()
        self.noise_ = float(self.kernel_.k2.noise_level)
        self.X_train_ = X
        K = self._k(X, X)
        K[np.diag_indices_from(K)] += self.noise_
        try:
            L = cholesky(K, lower=True, check_finite=False)
        except LinAlgError:  # a noise at its floor on thousands of designs: add the jitter
            K[np.diag_indices_from(K)] += JITTER * self.amp_
            L = cholesky(K, lower=True, check_finite=False)
        self.alpha_ = cho_solve((L, True), Ys, check_finite=False) * self.y_std_
        del K, L
        self.inducing_ = np.sort(perm[:self.inducing])
        Kmm = self._k(X[self.inducing_], X[self.inducing_])
        Kmm[np.diag_indices_from(Kmm)] += JITTER * self.amp_
        Lm = cholesky(Kmm, lower=True, check_finite=False)
        P = solve_triangular(Lm, self._k(X[self.inducing_], X), lower=True, check_finite=False)
        B = P @ P.T / self.noise_
        B[np.diag_indices_from(B)] += 1.0
        LB = cholesky(B, lower=True, check_finite=False)
        eye = np.eye(len(Lm))
        self.Lm_inv_T_ = solve_triangular(Lm, eye, lower=True, check_finite=False).T
        self.LB_inv_T_ = solve_triangular(LB, eye, lower=True, check_finite=False).T
        self.fit_seconds_ = time.perf_counter() - t0
        return self

    def variance_factor(self) -> np.ndarray:
        """G (m, m) with |a|^2 - |a L_B^-T|^2 = |k_m G|^2 for a = k_m L_m^-T: the DTC variance
        as one product, v = amp - |k_m G|^2 + noise. G = L_m^-T R, R R' = I - L_B^-T L_B^-1
        (positive semidefinite: L_B L_B' = I + A with A >= 0, so its eigenvalues lie in
        [0, 1)), R from its eigendecomposition with rounding's negative eigenvalues at 0.
        One m x m product per design instead of two (the graph's: half the bytes read)."""
        W = np.eye(len(self.LB_inv_T_)) - self.LB_inv_T_ @ self.LB_inv_T_.T
        eigenvalues, vectors = np.linalg.eigh(W)
        return self.Lm_inv_T_ @ (vectors * np.sqrt(np.clip(eigenvalues, 0.0, None)))

    def _k(self, A: np.ndarray, B: np.ndarray) -> np.ndarray:
        """amp * Matern 5/2 between rows of ``A`` and ``B`` (no noise)."""
        return self.kernel_.k1(A, B)

    def predict(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(mean targets (n, T), standardised predictive variance v (n,)) at features ``X``."""
        X = np.asarray(X, dtype=float)
        k = self._k(X, self.X_train_)
        a = k[:, self.inducing_] @ self.Lm_inv_T_
        c = a @ self.LB_inv_T_
        v = np.maximum(self.amp_ - np.sum(a * a, axis=1) + np.sum(c * c, axis=1), 0.0)
        return self.y_mean_ + k @ self.alpha_, v + self.noise_

    def card(self) -> dict[str, Any]:
        """What the card records of the fit."""
        return {"kernel": str(self.kernel_), "hyperparameter_designs": self.hyper_rows_,
                "mean_designs": len(self.X_train_), "inducing_designs": int(
                    self.inducing_.size), "fit_seconds": round(self.fit_seconds_, 1),
                "variance": "DTC (projected process) on the inducing designs, linearised "
                "through the decode; scaled conformally"}


def fit_sweep_gp(data: SweepData, designs: np.ndarray, *, seed: int = 0,
                 n_modes: int | None = None, options: dict[str, Any] | None = None
                 ) -> tuple[SweepGP, BandTargets]:
    """(fitted :class:`SweepGP`, fitted :class:`BandTargets`) of the rows ``designs`` of
    ``data`` (``options``: :data:`GP_OPTIONS`; ``n_modes``: the profile's POD modes)."""
    opts = split_gp_options(options)
    targets = BandTargets(centre_modes=opts.pop("centre_modes"), profile_modes=n_modes or 128)
    T = targets.fit_transform(data.response[designs])
    k0 = int(targets.pods[0].modes_.shape[0])
    blocks = [np.arange(1), np.arange(1, 1 + k0), np.arange(1 + k0, T.shape[1])]
    est = SweepGP(random_state=seed, **opts).fit(encode(data.codes[designs], data.specs), T,
                                                 blocks)
    return est, targets


def linearised_log_std(targets: BandTargets, y: np.ndarray, v: np.ndarray, t: np.ndarray,
                       y_std: np.ndarray, normal: bool = False,
                       components: np.ndarray | None = None) -> np.ndarray:
    """First-order std of the log outputs (n, 3 + m [+ m]) at fractional band indices ``t``
    (n,) for mean targets ``y`` (n, T) whose standardised variance is ``v`` (n,) (coefficient
    j's variance v * ``y_std``[j]^2, independent): sqrt(v sum_j (y_std_j d out / d y_j)^2),
    the derivatives taken explicitly from the interpolated basis (numpy; the reference of the
    graph's table-based form). ``components`` (n, P, 6): the normalised components at ``t``
    if given (else rebuilt from ``y``)."""
    modes, mean = targets.band_basis()                   # (n_f, k, L), (n_f, L)
    rows = range(0, len(y), 256)
    return np.concatenate([_linearised(modes, mean, targets.shape_, y[i:i + 256],
                                       v[i:i + 256], t[i:i + 256], y_std, normal,
                                       None if components is None else components[i:i + 256])
                           for i in rows])


def _linearised(modes: np.ndarray, mean: np.ndarray, shape: tuple[int, int], y: np.ndarray,
                v: np.ndarray, t: np.ndarray, y_std: np.ndarray, normal: bool,
                components: np.ndarray | None) -> np.ndarray:
    """:func:`linearised_log_std` of one block of rows."""
    n_f, P = shape
    t = np.clip(t, 0.0, n_f - 1.0)
    i0 = np.minimum(np.floor(t), n_f - 2).astype(int)
    w = (t - i0)[:, None, None]
    Mt = (1 - w) * modes[i0] + w * modes[i0 + 1]        # (n, k, L)
    z = (1 - w[..., 0]) * mean[i0] + w[..., 0] * mean[i0 + 1] + np.einsum("nk,nkl->nl",
                                                                         y[:, 1:], Mt)
    Mt = Mt.reshape(len(y), -1, P, 6) * y_std[None, 1:, None, None]
    z = z.reshape(len(y), P, 6) if components is None else components

    def grad(part: slice) -> np.ndarray:                # d ln|u_p| / d y_j * y_std_j: (n, k, P)
        zp = z[..., part]
        return np.einsum("nkpc,npc->nkp", Mt[..., part], zp) \
            / np.maximum(np.sum(zp * zp, axis=-1), TINY)[:, None, :]

    g = grad(slice(0, 6))
    s0 = y_std[0] ** 2
    var = [s0 + np.sum(g[:, :, :1] ** 2, axis=1), s0 + np.sum(g[:, :, 1:2] ** 2, axis=1),
           np.sum((g[:, :, 1:2] - g[:, :, :1]) ** 2, axis=1), s0 + np.sum(g[:, :, 1:] ** 2,
                                                                           axis=1)]
    if normal:
        var.append(s0 + np.sum(grad(slice(2 * Z, 2 * Z + 2))[:, :, 1:] ** 2, axis=1))
    return np.sqrt(v[:, None] * np.concatenate(var, axis=1))
