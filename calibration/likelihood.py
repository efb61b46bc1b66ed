"""The likelihood of a calibration and the intervals it reports (numpy only).

The surrogate's error on the log amplitudes is heavy-tailed where an amplitude dips (the normal
component |u_z| of ``nn-normal``, docs/calibration.md): a Gaussian with one widening factor
fits either its body or its tail. Here it is a Gaussian scale mixture, a multivariate Student-t
with ``nu`` degrees of freedom per output block (the points read from one model output, whose
errors are correlated along the profile and across frequencies):

    r = ln y - ln mu(theta) = e + n,   n ~ N(0, D),   e | lam ~ N(0, lam S),
    lam ~ InverseGamma(nu / 2, nu / 2),

with D = diag((sigma_i / y_i)^2) the stated measurement noise (Gaussian, independent), S =
c^2 diag(s) C diag(s) the surrogate's error covariance (s its predictive log-std, c the fitted
scale, C the error correlation). Without noise, e alone is multivariate t (:func:`mvt_logpdf`);
with it the mixture has no closed form and the one-dimensional integral over the precision
w = 1 / lam ~ Gamma(nu / 2, rate nu / 2) is a sum over a grid of ln w
(:func:`precision_grid`), each term O(m) once D^-1/2 S D^-1/2 is diagonalised. ``nu = inf``
is the Gaussian (lam = 1).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

__all__ = ["PROFILE_KERNELS", "frequency_clusters", "hdi", "mixture_log_likelihood",
           "mvt_logpdf", "precision_grid", "profile_kernel"]

#: grid of u = ln w for the precision integral: lowest u, and the step's cap
U_LOW = -16.0
U_STEP = 0.1
ROW_CHUNK = 128
#: shapes of the correlation of the surrogate's errors along a profile (:func:`profile_kernel`)
PROFILE_KERNELS = ("matern32", "exponential")


def profile_kernel(lag_mm: np.ndarray, length_mm: float, kind: str = "matern32") -> np.ndarray:
    """Correlation of the surrogate's errors at points ``lag_mm`` apart along a profile:
    Matern 3/2, (1 + a) exp(-a) with a = sqrt(3) |lag| / length (errors smooth along the
    profile: once differentiable), or the exponential exp(-|lag| / length) (rough)."""
    a = np.abs(np.asarray(lag_mm, dtype=float)) / length_mm
    if kind == "exponential":
        return np.exp(-a)
    if kind != "matern32":
        raise ValueError(f"kernel {kind!r}: allowed {', '.join(PROFILE_KERNELS)}")
    a = math.sqrt(3.0) * a
    return (1.0 + a) * np.exp(-a)


def frequency_clusters(frequency_hz: np.ndarray, within_hz: float) -> np.ndarray:
    """Label per point: the cluster of its frequency, frequencies chained while neighbours
    (sorted) are at most ``within_hz`` apart. The surrogate's error shares one mixing
    variable within a cluster; clusters are independent (docs/calibration.md)."""
    f = np.asarray(frequency_hz, dtype=float)
    u = np.unique(f)
    labels = np.concatenate([[0], np.cumsum(np.diff(u) > within_hz + 1e-9)])
    return labels[np.searchsorted(u, f)]


def precision_grid(nu: float) -> tuple[np.ndarray, np.ndarray]:
    """Grid u = ln w and the log of (Gamma(nu/2, rate nu/2) density of w) * w * du on it (the
    trapezoid weights of the integral over u; they sum to about one): fine enough for the
    density's width 1 / sqrt(nu/2) in u, wide enough for residuals far in the tail (a small
    precision w)."""
    if not nu > 0 or math.isinf(nu):
        raise ValueError(f"nu = {nu}: must be finite and > 0")
    a = 0.5 * nu
    h = min(U_STEP, 0.25 / math.sqrt(a))
    u = np.arange(U_LOW, min(5.0, 1.0 + 12.0 / math.sqrt(a)) + h, h)
    logw = a * math.log(a) - math.lgamma(a) + a * u - a * np.exp(u) + math.log(h)
    return u, logw


def mvt_logpdf(r: np.ndarray, cov: np.ndarray, nu: float) -> np.ndarray:
    """Log density of the zero-mean multivariate t (scale matrix ``cov`` (m, m), ``nu``
    degrees of freedom; the Gaussian for nu = inf) at each row of ``r`` (n, m)."""
    r = np.atleast_2d(r)
    m = r.shape[1]
    chol = np.linalg.cholesky(cov)
    w = np.linalg.solve(chol, r.T)
    delta = np.sum(w ** 2, axis=0)
    logdet = 2.0 * np.sum(np.log(np.diagonal(chol)))
    if math.isinf(nu):
        return -0.5 * (delta + logdet + m * math.log(2 * math.pi))
    return (math.lgamma(0.5 * (nu + m)) - math.lgamma(0.5 * nu)
            - 0.5 * m * math.log(nu * math.pi) - 0.5 * logdet
            - 0.5 * (nu + m) * np.log1p(delta / nu))


def _whitened(noise_var: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigen-decomposition of D^-1/2 S D^-1/2 (S (m, m) or (n, m, m)): eigenvalues and
    vectors, so that D + S / w = D^1/2 U (I + L / w) U^T D^1/2 for every w at O(m) cost."""
    g = 1.0 / np.sqrt(noise_var)
    return np.linalg.eigh(g[:, None] * s * g[None, :] if s.ndim == 2 else
                          g[None, :, None] * s * g[None, None, :])


def mixture_log_likelihood(r: np.ndarray, noise_var: np.ndarray, surrogate_cov: np.ndarray,
                           blocks: Sequence[tuple[np.ndarray, float]]) -> np.ndarray:
    """Log-likelihood of each row of the residual ``r`` (n, m): the sum over ``blocks``
    (index array of the points of one output, its nu) of the scale mixture of the module
    docstring; ``noise_var`` (m,) the measurement variances D (> 0), ``surrogate_cov`` S,
    either (m, m) (one for every row) or (n, m, m). Points of different blocks are
    independent. The integral over u = ln w is a sum on :func:`precision_grid`."""
    r = np.atleast_2d(r)
    total = np.zeros(r.shape[0])
    for idx, nu in blocks:
        s = (surrogate_cov[np.ix_(idx, idx)] if surrogate_cov.ndim == 2
             else surrogate_cov[:, idx][:, :, idx])
        dv = noise_var[idx]
        lam, vec = _whitened(dv, s)
        x = r[:, idx] / np.sqrt(dv)
        rho2 = (x @ vec if s.ndim == 2 else np.einsum("nm,nmk->nk", x, vec)) ** 2
        lam = np.broadcast_to(lam, rho2.shape)
        base = -0.5 * (np.sum(np.log(dv)) + len(idx) * math.log(2 * math.pi))
        if math.isinf(nu):
            total += base - 0.5 * np.sum(np.log1p(lam) + rho2 / (1.0 + lam), axis=1)
            continue
        u, logw = precision_grid(nu)
        inv_w = np.exp(-u)
        for c in range(0, r.shape[0], ROW_CHUNK):
            q = 1.0 + lam[c:c + ROW_CHUNK, None, :] * inv_w[None, :, None]  # (n, G, m)
            f = logw - 0.5 * np.sum(np.log(q) + rho2[c:c + ROW_CHUNK, None, :] / q, axis=2)
            top = f.max(axis=1)
            total[c:c + ROW_CHUNK] += base + top + np.log(np.sum(np.exp(f - top[:, None]),
                                                                 axis=1))
    return total


def hdi(draws: np.ndarray, mass: float = 0.95,
        bounds: tuple[float, float] = (-math.inf, math.inf)) -> tuple[float, float]:
    """The highest-density interval of ``draws`` (1-d): the shortest interval holding
    ``mass`` of them (for a unimodal density, the interval whose ends have equal density).
    ``bounds``: the support's (the prior's) bounds: an end of the interval among the 1 % of
    draws nearest a bound is moved to the bound when the draws are piled against it, i.e.
    when the gap from the outermost draw to the bound is smaller than the span of those 1 %
    (the density does not fall off before the bound, so the interval holds the bound)."""
    x = np.sort(np.asarray(draws, dtype=float))
    n = x.size
    k = min(n, max(1, math.ceil(mass * n)))
    widths = x[k - 1:] - x[: n - k + 1]
    i = int(np.argmin(widths))
    lo, hi = float(x[i]), float(x[i + k - 1])
    edge = max(1, n // 100)
    if i <= edge and x[0] - bounds[0] <= x[min(edge, n - 1)] - x[0]:
        lo = float(bounds[0])
    if n - (i + k) <= edge and bounds[1] - x[-1] <= x[-1] - x[max(n - 1 - edge, 0)]:
        hi = float(bounds[1])
    return lo, hi
