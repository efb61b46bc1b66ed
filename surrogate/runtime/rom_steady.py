"""The envelope model's steady response A(omega) (numpy only; used by
:mod:`surrogate.runtime.rom` and its fit, :mod:`surrogate.envelope.fit`): the harmonic model's
amplitudes on its trained band, interpolated at the instantaneous speed, continued below the band
with the unbalance force m e omega^2 through mode 1, times the gain g exp(s (f - 130 Hz) / 50 Hz)
with f clamped into the band (g = 1, s = 0 unless the fit learned them: ``learn_gain``).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from surrogate.runtime.predictor import Predictor

__all__ = ["F_REF_HZ", "F_SPAN_HZ", "GRID_STEP_HZ", "continued_steady", "gain_factor",
           "harmonic_grid", "steady_from_params", "steady_response"]

F_REF_HZ, F_SPAN_HZ = 130.0, 50.0  # the gain slope is per 50 Hz about 130 Hz
GRID_STEP_HZ = 2.5  # the harmonic model is evaluated this finely and interpolated linearly


def continued_steady(omega: NDArray, grid_hz: NDArray, amplitude: NDArray, sigma: NDArray,
                     fn_hz: NDArray) -> NDArray:
    """Steady response (nb, nt) at the speeds ``omega`` ((nt,) or (nb, nt), rad/s) from the
    harmonic amplitudes ``amplitude`` (nb, n_grid) on ``grid_hz`` (increasing, from the
    harmonic model's lowest trained frequency f_low), continued below f_low by
    m e omega^2 through the mode (see the module docstring)."""
    f = np.broadcast_to(omega, (amplitude.shape[0], np.shape(omega)[-1])) / (2 * math.pi)
    above = np.stack([np.interp(fi, grid_hz, a) for fi, a in zip(f, amplitude, strict=True)])
    lam = -np.asarray(sigma)[:, None] + 2j * math.pi * np.asarray(fn_hz)[:, None]
    f_low = float(grid_hz[0])
    w_low, w = 2 * math.pi * f_low, 2 * math.pi * f
    below = (amplitude[:, :1] * (f / f_low) ** 2 * np.abs(1j * w_low - lam)
             / np.abs(1j * w - lam))
    return np.where(f >= f_low, above, below)


def harmonic_grid(harmonic: Predictor) -> NDArray:
    """Frequencies (Hz) at which the envelope model evaluates its harmonic model: its trained
    ``frequency_hz`` range every ``GRID_STEP_HZ``."""
    spec = next(s for s in harmonic.specs if s.name == "frequency_hz")
    return np.arange(float(spec.low), float(spec.high) + 1e-9, GRID_STEP_HZ)


def steady_response(omega: NDArray, grid_hz: NDArray, amplitude: NDArray, sigma: NDArray,
                    fn_hz: NDArray, gain: NDArray, slope: NDArray) -> NDArray:
    """The model's steady response (nb, nt) at the speeds ``omega``: the gain times
    the harmonic amplitudes continued below the band (:func:`gain_factor`,
    :func:`continued_steady`; per-batch parameters ``sigma`` 1/s, ``fn_hz`` Hz, ``gain``,
    ``slope``, each (nb,))."""
    return (gain_factor(omega, gain, slope, grid_hz)
            * continued_steady(omega, grid_hz, amplitude, sigma, fn_hz))


def steady_from_params(omega: NDArray, grid_hz: NDArray, amplitude: NDArray, p: NDArray
                       ) -> NDArray:
    """:func:`steady_response` for parameter rows ``p`` (nb, >= 4: log sigma, f_n, log g,
    slope first, as :data:`surrogate.runtime.rom_modes.PARAMS`)."""
    p = np.asarray(p, dtype=float)
    return steady_response(omega, grid_hz, amplitude, np.exp(p[:, 0]), p[:, 1],
                           np.exp(p[:, 2]), p[:, 3])


def gain_factor(omega: NDArray, gain: NDArray, slope: NDArray, grid_hz: NDArray) -> NDArray:
    """Learned steady gain (nb, nt): g exp(slope (f - 130 Hz) / 50 Hz), f clamped into the
    harmonic model's band ``grid_hz`` (below it, the continuation through the mode carries
    the frequency dependence)."""
    f = np.clip(np.asarray(omega) / (2 * math.pi), grid_hz[0], grid_hz[-1])
    return np.asarray(gain)[:, None] * np.exp(np.asarray(slope)[:, None]
                                              * (f - F_REF_HZ) / F_SPAN_HZ)
