"""A causal time-domain stand-in for the hysteretic loss factor over a band of frequencies.

Why: the harmonic solver damps every material hysteretically, E* = E (1 + i eta), a loss
independent of frequency. That modulus has no causal time-domain form, so the transient solver
needs another model. The old one (``"viscous_at_drive"``) is stiffness-proportional viscous
damping C = (eta / omega_ref) K: exact at one frequency, a loss eta f / f_ref elsewhere (too
low below the rated speed, too high above it). An ERM spins through its whole speed range on
every start, so the band model (``"hysteretic_band"``) replaces it with a generalised Maxwell
(standard linear solid, Prony) series whose complex modulus follows 1 + i eta on a band:

    E*(omega) / E = 1 - c eta + eta sum_k g_k (i omega tau_k) / (1 + i omega tau_k),

tau_k [s] log-spaced over the band, g_k >= 0 and c >= 0 [-] fitted once for unit eta by
non-negative least squares on Re = 1 and Im = eta (the shape scales with eta: both parts are
affine in it). In the FE, with K_eta = sum_m eta_m K_m (each material's stiffness times its
loss factor), the internal force is (K - c K_eta) u + sum_k q_k with

    tau_k dq_k/dt + q_k = g_k tau_k K_eta du/dt,

integrated exactly for u linear over a time step (:class:`Relaxation`, :class:`MemoryState`,
used by :func:`fem.transient.solve_transient`).

What it cannot do: a causal modulus obeys the Kramers-Kronig relations, so a loss near eta over
a band forces the real part to rise with frequency, by about (2 / pi) eta per unit of
ln(omega) (the dispersion of a constant-Q solid). Over 20-300 Hz that is about 1.7 eta, so
Im = eta and Re = 1 cannot both hold to within a few % of eta; the fit balances them (its
errors, :attr:`BandFit.im_error` and :attr:`BandFit.re_error`, are reported, and
docs/model.md quotes them with the steady amplitudes this gives against the hysteretic
harmonic solve).

The band: 20-300 Hz (:data:`BAND_HZ`) covers the motor's speed range (30-250 Hz; a spin-up
passes through all of it, and under 30 Hz the rotating force m e omega^2 is under
(30/120)^2, about 6 %, of the rated one) with a margin at both ends for the relaxation terms' tails.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import nnls

BAND_HZ = (20.0, 300.0)
"""Band [Hz] on which the default fit follows 1 + i eta (see the module docstring)."""

N_TERMS = 5
"""Candidate relaxation terms of the default fit, one per 0.29 decade of 20-300 Hz. The
non-negative fit keeps the two at the band's ends (g = c = 1.77); 4 or 6 candidates give the
same errors: what limits the fit is Kramers-Kronig, not the number of terms."""

RE_WEIGHT = 0.5
"""Weight of the real-part residual against the imaginary one in the default fit [-]. Chosen
by the steady centre and edge amplitudes of four designs of ``datasets/transient`` (samples
43, 53, 124, 213) at 40, 80, 130 and 200 Hz: harmonic solves on the transient's own matrices
with the fitted modulus against the hysteretic one (the steady state each transient settles
to), 32 values per fit (``python bench/fem/transient_damping.py --harmonic-only --samples
43 53 124 213 --re-weight 0.5 1 --anchored``). Median / max |relative error|: weight 0.5:
2.9 / 16 %; weight 1: 4.4 / 25 %; the viscous model at the rated speed: 3.9 / 51 %. Held
exact at the rated speed as well (``anchor_hz``), weight 0.5 gives 2.1 / 22 % (better from
80 Hz up, worse at 40 Hz) but c = 1.92, which caps the loss factor below the 0.5 that
``datasets/transient`` samples. Weighting the loss more keeps resonant peaks right, where the
amplitude is 1 / loss."""

_N_FIT = 200  # log-spaced fitting frequencies on the band


@dataclass(frozen=True)
class BandFit:
    """A Prony series fitted to 1 + i eta for unit eta on ``[f_lo_hz, f_hi_hz]``.

    Attributes:
        f_lo_hz, f_hi_hz: the band [Hz].
        tau_s: (n,) relaxation times [s], log-spaced: tau_k = 1 / (2 pi f_k).
        g: (n,) weights of the relaxation terms [-], >= 0.
        c: stiffness offset [-], >= 0: the relaxed (static) modulus is E (1 - c eta).
        im_error: largest |Im E*/E / eta - 1| on the band [-] (relative to eta).
        re_error: largest |(Re E*/E - 1) / eta| on the band [-] (relative to eta).
    """

    f_lo_hz: float
    f_hi_hz: float
    tau_s: NDArray
    g: NDArray
    c: float
    im_error: float
    re_error: float

    def modulus_factor(self, omega: NDArray | float, eta: NDArray | float) -> NDArray:
        """E*(omega) / E [-] at angular frequencies ``omega`` [rad/s] for loss factor ``eta``
        (broadcast together)."""
        w = np.asarray(omega, dtype=float)[..., None]
        iwt = 1j * w * self.tau_s
        shape = np.sum(self.g * iwt / (1.0 + iwt), axis=-1)
        return 1.0 - self.c * np.asarray(eta) + np.asarray(eta) * shape

    def max_loss_factor(self) -> float:
        """Largest eta whose relaxed (static) modulus E (1 - c eta) keeps a tenth of E [-]:
        above it the slow response is too soft to stand for the hysteretic material, and at
        1 / c the solid loses its static stiffness."""
        return math.inf if self.c <= 0 else 0.9 / self.c


def fit_band(f_lo_hz: float = BAND_HZ[0], f_hi_hz: float = BAND_HZ[1], n_terms: int = N_TERMS,
             re_weight: float = RE_WEIGHT, anchor_hz: float | None = None) -> BandFit:
    """Fit the Prony series to 1 + i eta (unit eta) on [f_lo_hz, f_hi_hz] [Hz].

    Non-negative least squares over ``g`` and ``c`` of the residuals Im - 1 and
    ``re_weight`` (Re - 1) at 200 log-spaced frequencies; tau_k = 1 / (2 pi f_k) with f_k
    log-spaced from f_lo_hz to f_hi_hz. With ``anchor_hz`` [Hz] the fit is also held to
    1 + i eta at that frequency (two rows weighted 1000: exact to about 1e-4).

    Raises:
        ValueError naming the argument when the band or the number of terms is out of range.
    """
    if not (math.isfinite(f_lo_hz) and math.isfinite(f_hi_hz) and 0 < f_lo_hz < f_hi_hz):
        raise ValueError(f"band must satisfy 0 < f_lo_hz < f_hi_hz (Hz), got "
                         f"f_lo_hz = {f_lo_hz!r}, f_hi_hz = {f_hi_hz!r}")
    if not 1 <= int(n_terms) <= 20:
        raise ValueError(f"n_terms must be in [1, 20], got {n_terms!r}")
    if not (math.isfinite(re_weight) and re_weight >= 0):
        raise ValueError(f"re_weight must be finite and >= 0, got {re_weight!r}")
    omega = 2 * np.pi * np.geomspace(f_lo_hz, f_hi_hz, _N_FIT)
    tau = 1.0 / (2 * np.pi * np.geomspace(f_lo_hz, f_hi_hz, int(n_terms)))
    x = omega[:, None] * tau[None, :]
    im, re = x / (1 + x * x), x * x / (1 + x * x)
    zeros, ones = np.zeros((_N_FIT, 1)), np.ones((_N_FIT, 1))
    A = np.vstack([np.hstack([im, zeros]), re_weight * np.hstack([re, -ones])])
    b = np.concatenate([np.ones(_N_FIT), np.zeros(_N_FIT)])
    if anchor_hz is not None:
        if not (math.isfinite(anchor_hz) and anchor_hz > 0):
            raise ValueError(f"anchor_hz must be finite and > 0 Hz, got {anchor_hz!r}")
        xa = 2 * np.pi * anchor_hz * tau
        A = np.vstack([A, 1e3 * np.append(xa / (1 + xa * xa), 0.0),
                       1e3 * np.append(xa * xa / (1 + xa * xa), -1.0)])
        b = np.concatenate([b, [1e3, 0.0]])
    sol, _ = nnls(A, b)
    g, c = sol[:-1], float(sol[-1])
    fit = BandFit(float(f_lo_hz), float(f_hi_hz), tau, g, c, 0.0, 0.0)
    z = fit.modulus_factor(omega, 1.0)
    return BandFit(fit.f_lo_hz, fit.f_hi_hz, tau, g, c,
                   float(np.abs(z.imag - 1).max()), float(np.abs(z.real - 1).max()))


@functools.cache
def default_fit() -> BandFit:
    """The fit every ``damping = "hysteretic_band"`` transient uses (computed once)."""
    return fit_band()


@dataclass(frozen=True, eq=False)
class Relaxation:
    """Relaxation (Maxwell) terms of a linear solid, for :func:`fem.transient.solve_transient`.

    The internal force is ``K u + sum_k q_k`` (K the stiffness given to the integrator, which
    holds the relaxed part: K - c K_eta for the band model) with

        tau_k dq_k/dt + q_k = g_k tau_k ``matrix`` du/dt,   q_k = 0 at the start.

    Attributes:
        matrix: (ndof, ndof) real sparse loss matrix K_eta [N/m].
        tau_s: (n,) relaxation times [s], > 0.
        g: (n,) weights [-], >= 0.
    """

    matrix: object
    tau_s: NDArray
    g: NDArray

    @classmethod
    def from_fit(cls, matrix: object, fit: BandFit) -> Relaxation:
        """The terms of ``fit`` acting through the loss matrix ``matrix`` [N/m]; terms of zero
        weight are left out (the default fit uses two of its five)."""
        keep = np.asarray(fit.g) > 0
        return cls(matrix, np.asarray(fit.tau_s, dtype=float)[keep],
                   np.asarray(fit.g, dtype=float)[keep])


class MemoryState:
    """The internal variables q_k of a :class:`Relaxation` stepped with the generalised-alpha
    scheme (``fem.transient``).

    Over a step q_{n+1} = e_k q_n + h_k K_eta (u_{n+1} - u_n) (exact for u linear over the
    step: e_k = exp(-dt / tau_k), h_k = g_k tau_k (1 - e_k) / dt). The scheme evaluates forces at
    t_{n+1-alpha_f}, q_{n+1-alpha_f} = (1-alpha_f) q_{n+1} + alpha_f q_n, so the part of
    sum_k q_{n+1-alpha_f} that depends on u_{n+1} is (1-alpha_f) H K_eta u_{n+1},
    H = sum_k h_k: a stiffness ``shift * K_eta`` (shift = H) added to K in the effective matrix
    and in the predictor product (same sparsity, one factorisation). What is left is known
    before the solve: :meth:`subtract_known` takes it from the right-hand side.
    """

    def __init__(self, relax: Relaxation, dt: float, alpha_f: float, u0: NDArray,
                 product: object) -> None:
        tau, g = np.asarray(relax.tau_s, dtype=float), np.asarray(relax.g, dtype=float)
        if tau.ndim != 1 or tau.shape != g.shape or tau.size == 0:
            raise ValueError(f"relaxation tau_s and g must be 1-D of one length >= 1, got "
                             f"shapes {tau.shape} and {g.shape}")
        if not (np.all(np.isfinite(tau)) and np.all(tau > 0)):
            raise ValueError(f"relaxation tau_s must be finite and > 0 s, got {tau!r}")
        if not (np.all(np.isfinite(g)) and np.all(g >= 0)):
            raise ValueError(f"relaxation g must be finite and >= 0, got {g!r}")
        decay = np.exp(-dt / tau)
        gain = g * tau * (-np.expm1(-dt / tau)) / dt
        self.shift = float(gain.sum())
        self._decay, self._gain = decay[:, None, None], gain[:, None, None]
        self._known = ((1.0 - alpha_f) * decay + alpha_f)[:, None, None]
        self._product = product  # K_eta through linalg.product: accumulate(X, out, alpha)
        self._s = np.zeros_like(u0)  # K_eta u_n
        product.accumulate(np.ascontiguousarray(u0), self._s)
        self._q = np.zeros((tau.size, *u0.shape))

    def subtract_known(self, rhs: NDArray) -> None:
        """rhs -= sum_k ((1-af) e_k + af) q_k - H K_eta u_n.

        With u_{n+1-af} = u_n + (1-af) du, the stiffness and memory forces at t_{n+1-af} are
        K u_{n+1-af} + sum_k q_{k,n+1-af} = (K + H K_eta) u_{n+1-af} - H K_eta u_n
        + sum_k ((1-af) e_k + af) q_k: the integrator treats the first term as it treats K
        alone; this method moves the other two to the right-hand side."""
        rhs -= np.sum(self._known * self._q, axis=0)
        rhs += self.shift * self._s

    def advance(self, du: NDArray) -> None:
        """Update q_k and K_eta u after a step with displacement increment ``du`` [m]."""
        d = np.zeros_like(du)
        self._product.accumulate(np.ascontiguousarray(du), d)
        self._q *= self._decay
        self._q += self._gain * d
        self._s += d
