"""The envelope model's dynamic correction: damped modes seen from the frame rotating with the
force (numpy only; used by :mod:`surrogate.runtime.rom` and its fit, :mod:`surrogate.envelope.fit`).

Each point has one or two modes lambda_k = -sigma_k + i 2 pi f_k (sigma_k > 0, 1/s) sharing
the steady response A(omega):

    dz_k/dt = (lambda_k - i omega) z_k + c_k (i omega - lambda_k) A(omega),   z_k(0) = 0,

with envelope |z_1 + z_2|. One mode: c_1 = 1. Two modes: c_1 = w, c_2 = 1 - w (w real), so in
steady running z_1 + z_2 = A exactly and the model is stable for every schedule. Each step is
integrated exactly with omega and A held at their step averages.

The parameter rows (``PARAMS`` of one mode, then ``MODE2_PARAMS`` for the second) are what the
coefficients map affinely from the design features.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["MODE2_PARAMS", "PARAMS", "envelope_from_params", "mode_response", "modes_response",
           "params_for"]

PARAMS = ("log_sigma", "fn_hz", "log_gain", "gain_slope")
MODE2_PARAMS = ("log_sigma2", "fn2_hz", "weight")  # the second mode and mode 1's share w


def params_for(modes: int) -> tuple[str, ...]:
    """The parameter rows of a model with ``modes`` (1 or 2) modes per point; ValueError
    naming ``modes`` otherwise."""
    if type(modes) is not int or modes not in (1, 2):
        raise ValueError(f"modes: {modes!r}: allowed 1 or 2")
    return PARAMS if modes == 1 else (*PARAMS, *MODE2_PARAMS)


def modes_response(t: NDArray, omega: NDArray, steady: NDArray, sigma: NDArray, fn_hz: NDArray,
                   share: NDArray) -> NDArray:
    """Envelope |sum_k z_k| (same unit as ``steady``) of rotating-frame modes for a batch.

    ``t`` (nt,) s; ``omega`` (nt,) or (nb, nt) rad/s; ``steady`` (nb, nt) the steady response
    at the instantaneous speed; ``sigma`` (nb, m) 1/s, ``fn_hz`` (nb, m) Hz and ``share``
    (nb, m) the modes and their shares c_k of the forcing (summing to 1 for a steady state
    equal to ``steady``). Exact for omega and the steady response held at their step
    averages."""
    lam = -np.asarray(sigma, dtype=float) + 2j * math.pi * np.asarray(fn_hz, dtype=float)
    c = np.asarray(share, dtype=float)
    h = np.diff(t)
    w = np.broadcast_to(omega, steady.shape)
    wm = 0.5 * (w[:, 1:] + w[:, :-1])
    qm = 0.5 * (steady[:, 1:] + steady[:, :-1])
    decay = np.exp((lam[:, :, None] - 1j * wm[:, None, :]) * h)  # (nb, m, nt - 1)
    forced = c[:, :, None] * qm[:, None, :]
    z = np.zeros(steady.shape, dtype=complex)
    zk = np.zeros(lam.shape, dtype=complex)
    for k in range(h.size):  # z_k -> c_k q + (z_k - c_k q) e^{(lambda_k - i omega) h}
        zk = forced[:, :, k] + (zk - forced[:, :, k]) * decay[:, :, k]
        z[:, k + 1] = zk.sum(axis=1)
    return np.abs(z)


def mode_response(t: NDArray, omega: NDArray, steady: NDArray, sigma: NDArray,
                  fn_hz: NDArray) -> NDArray:
    """Envelope |z| of one rotating-frame mode for a batch (:func:`modes_response` with
    c = 1; ``sigma`` (nb,) 1/s and ``fn_hz`` (nb,) Hz)."""
    sigma = np.asarray(sigma, dtype=float)[:, None]
    return modes_response(t, omega, steady, sigma, np.asarray(fn_hz, dtype=float)[:, None],
                          np.ones_like(sigma))


def envelope_from_params(t: NDArray, omega: NDArray, steady: NDArray, p: NDArray) -> NDArray:
    """Envelopes (nb, nt) for parameter rows ``p`` (nb, 4) in ``PARAMS`` order (one mode) or
    (nb, 7) with ``MODE2_PARAMS`` appended (two modes) and the steady response ``steady``
    (nb, nt) they give (the gain rows are already in it)."""
    p = np.asarray(p, dtype=float)
    if p.shape[1] == len(PARAMS):
        return mode_response(t, omega, steady, np.exp(p[:, 0]), p[:, 1])
    sigma = np.exp(np.stack([p[:, 0], p[:, 4]], axis=1))
    fn = np.stack([p[:, 1], p[:, 5]], axis=1)
    share = np.stack([p[:, 6], 1.0 - p[:, 6]], axis=1)
    return modes_response(t, omega, steady, sigma, fn, share)
