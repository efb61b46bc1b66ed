"""The SINDy study's integrator of an identified residual (numpy/scipy; pysindy not needed)."""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm

from studies.envelope_sindy import residual_response


def test_first_order_residual_is_exact_for_constant_coefficients() -> None:
    t = np.linspace(0.0, 50.0, 101)  # ms
    alpha, beta = -0.2, 0.05  # 1/ms, 1/ms
    x = residual_response(t, np.full((t.size, 1, 1), alpha), np.full((t.size, 1), beta))
    exact = -beta / alpha * (1.0 - np.exp(alpha * t))
    np.testing.assert_allclose(x[:, 0], exact, rtol=1e-12, atol=1e-14)


def test_second_order_residual_is_exact_for_a_damped_oscillation() -> None:
    t = np.linspace(0.0, 40.0, 161)
    a = np.array([[0.0, 1.0], [-0.5, -0.1]])  # r'' = -0.5 r - 0.1 r' + 0.02
    b = np.array([0.0, 0.02])
    x = residual_response(t, np.broadcast_to(a, (t.size, 2, 2)), np.broadcast_to(b, (t.size, 2)))
    x_inf = -np.linalg.solve(a, b)
    exact = np.stack([x_inf - expm(a * tk) @ x_inf for tk in t])
    np.testing.assert_allclose(x, exact, atol=1e-12)


def test_singular_and_unstable_residuals_stay_finite() -> None:
    t = np.linspace(0.0, 10.0, 41)
    ramp = residual_response(t, np.zeros((t.size, 1, 1)), np.full((t.size, 1), 0.1))
    np.testing.assert_allclose(ramp[:, 0], 0.1 * t, atol=1e-12)  # a = 0: dr/dt = b exactly
    grow = residual_response(t, np.full((t.size, 1, 1), 3.0), np.full((t.size, 1), 1.0))
    assert np.all(np.isfinite(grow)) and np.max(np.abs(grow)) <= 5.0  # clipped at STATE_MAX
