"""A pole-residue form of the band response: a few complex poles shared by a design's centre
and edge components, their residues and a constant, fitted by vector fitting.

Per design, every component j of the centre and the edge (six complex responses over the band)
is written ``H_j(s) = sum_k r_jk / (s - p_k) + d_j`` with ``s = i f / f_ref`` (``f_ref`` =
100 Hz keeps the numbers of order one) and poles ``p_k`` common to all components: the
resonances that shape the band. The poles come from vector fitting (Gustavsen and Semlyen
1999: repeated linear least squares for a weighting function whose zeros are the next poles,
unstable poles reflected), the residues and constants from one final least-squares solve.
The response has a frequency-independent loss (a hysteretic, not a viscous, damping), so no
conjugate symmetry is imposed: poles and residues are free complex numbers.

:class:`PoleResidue` is the output choice: targets are ln of the band's RMS centre amplitude,
the poles sorted by frequency (real and imaginary parts), and the residues and constants
divided by the scale (real and imaginary parts); decoding evaluates the form on the band.
"""

from __future__ import annotations

import numpy as np

from .data import Sweeps
from .representations import Answers, Choice, ComplexBand, magnitude

__all__ = ["PoleResidue", "evaluate", "vector_fit"]

#: Reference frequency [Hz] of the normalised Laplace variable s = i f / F_REF.
F_REF = 100.0


def _basis(s: np.ndarray, poles: np.ndarray) -> np.ndarray:
    return 1.0 / (s[:, None] - poles[None, :])


def evaluate(s: np.ndarray, poles: np.ndarray, residues: np.ndarray, const: np.ndarray
             ) -> np.ndarray:
    """``sum_k r_jk / (s - p_k) + d_j`` (n_s, m) of poles (K,), residues (m, K), const (m,)."""
    return _basis(s, poles) @ residues.T + const[None, :]


def _residues(s: np.ndarray, h: np.ndarray, poles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a = np.column_stack([_basis(s, poles), np.ones_like(s)])
    sol = np.linalg.lstsq(a, h, rcond=None)[0]  # (K + 1, m)
    return sol[:-1].T, sol[-1]


def vector_fit(f_hz: np.ndarray, h: np.ndarray, n_poles: int, iterations: int = 10
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Poles (K,), residues (m, K) and constants (m,) of the responses ``h`` (n_f, m)
    sampled at ``f_hz`` [Hz], ``K = n_poles`` poles common to the m responses."""
    s = 1j * np.asarray(f_hz, float) / F_REF
    beta = np.linspace(f_hz[0], f_hz[-1], n_poles + 2)[1:-1] / F_REF
    poles = -beta / 50 + 1j * beta
    m = h.shape[1]
    # each response weighted by its own RMS level (pointwise 1 / |h| would let a component
    # that is zero to rounding, e.g. a tangential one, dominate the fit)
    rms = np.sqrt(np.mean(np.abs(h) ** 2, axis=0))
    wj = 1.0 / np.maximum(rms, 1e-9 * max(rms.max(), 1e-300))
    for _ in range(iterations):
        phi = _basis(s, poles)
        n_f, k = phi.shape
        # unknowns: residues and constant of each response (m (k + 1)), then sigma's c (k)
        rows = np.zeros((m * n_f, m * (k + 1) + k), complex)
        for j in range(m):
            rows[j * n_f:(j + 1) * n_f, j * (k + 1):j * (k + 1) + k] = phi
            rows[j * n_f:(j + 1) * n_f, j * (k + 1) + k] = 1.0
            rows[j * n_f:(j + 1) * n_f, m * (k + 1):] = -h[:, j:j + 1] * phi
        weight = np.repeat(wj, n_f)
        sol = np.linalg.lstsq(rows * weight[:, None], h.reshape(-1, order="F") * weight,
                              rcond=None)[0]
        c = sol[m * (k + 1):]
        new = np.linalg.eigvals(np.diag(poles) - np.outer(np.ones(k), c))
        poles = np.where(new.real > 0, -new.real + 1j * new.imag, new)
    poles = poles[np.argsort(poles.imag)]
    res, const = _residues(s, h, poles)
    return poles, res, const


class PoleResidue(Choice):
    """Poles, residues and constants of the centre and edge over the band (``n_poles`` poles
    per design, common to its six components). No profile."""

    def __init__(self, n_poles: int = 4) -> None:
        self.n_poles = n_poles
        self.name = f"pole-residue x{n_poles}"

    def targets(self, sw: Sweeps) -> np.ndarray:
        scale = ComplexBand.scale(sw.center)
        out = []
        for i in range(len(sw)):
            h = np.concatenate([sw.center[i], sw.edge[i]], axis=1) / scale[i]  # (n_f, 6)
            p, r, d = vector_fit(sw.band, h, self.n_poles)
            out.append(np.concatenate([[np.log(scale[i])], p.real, p.imag, r.real.ravel(),
                                       r.imag.ravel(), d.real, d.imag]))
        return np.array(out)

    def training(self, sw: Sweeps, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        return sw.x, self.targets(sw)

    def decode(self, pred: np.ndarray, sw: Sweeps) -> Answers:
        k, m, n_f = self.n_poles, 6, sw.band.size
        s = 1j * sw.band / F_REF
        c = np.empty((len(pred), n_f, 3), complex)
        e = np.empty_like(c)
        for i, t in enumerate(pred):
            at = 1
            p = t[at:at + k] + 1j * t[at + k:at + 2 * k]
            at += 2 * k
            r = (t[at:at + m * k] + 1j * t[at + m * k:at + 2 * m * k]).reshape(m, k)
            at += 2 * m * k
            d = t[at:at + m] + 1j * t[at + m:at + 2 * m]
            h = evaluate(s, p, r, d) * np.exp(t[0])
            c[i], e[i] = h[:, :3], h[:, 3:]
        return Answers(magnitude(c), magnitude(e), None)
