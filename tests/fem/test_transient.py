"""Generalised-alpha integrator (fem.transient) against analytic solutions."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sl
import scipy.sparse as sp

from fem.transient import GeneralizedAlphaParameters, TransientResult, solve_transient


def _sdof(m: float, k: float, c: float | None = None):
    mat = lambda x: sp.csr_matrix([[x]])  # noqa: E731
    return mat(m), mat(k), None if c is None else mat(c)


def _zero_load(t: np.ndarray) -> np.ndarray:
    return np.zeros_like(t)


def _free_sdof(omega: float, dt: float, n_steps: int, rho_inf: float) -> np.ndarray:
    """Displacement history of u'' + omega^2 u = 0 from u0 = 1, v0 = 0."""
    m, k, _ = _sdof(1.0, omega**2)
    res = solve_transient(m, k, np.zeros(1), _zero_load, dt, n_steps, rho_inf=rho_inf,
                          u0=np.ones(1), record_dofs=[0])
    return res.u[:, 0, 0]


# ---------------------------------------------------------------- parameters


def test_parameters_match_chung_hulbert() -> None:
    p = GeneralizedAlphaParameters.from_rho_inf(1.0)
    assert (p.alpha_m, p.alpha_f, p.gamma, p.beta) == (0.5, 0.5, 0.5, 0.25)
    p = GeneralizedAlphaParameters.from_rho_inf(0.0)
    assert (p.alpha_m, p.alpha_f, p.gamma, p.beta) == (-1.0, 0.0, 1.5, 1.0)


# ---------------------------------------------------------------- SDOF, free vibration


def test_trapezoidal_free_vibration_is_exact_discrete_rotation() -> None:
    """rho_inf = 1 is the trapezoidal rule: (omega u, v) rotates by 2 atan(omega dt / 2) per
    step, so u_n = cos(n Omega_bar) exactly, T_num / T = (Omega/2) / atan(Omega/2), and the
    energy is conserved to round-off."""
    m, omega = 2.0, 2.0 * np.pi * 3.0
    dt = (2.0 * np.pi / omega) / 20.0
    states: list[tuple[float, float]] = []
    res = solve_transient(
        *_sdof(m, m * omega**2)[:2], np.zeros(1), _zero_load, dt, 400, rho_inf=1.0,
        u0=np.ones(1), record_dofs=[0],
        on_snapshot=lambda step, t, u, v, a: states.append((u[0, 0], v[0, 0])),
    )
    big_omega = omega * dt
    omega_bar = 2.0 * np.arctan(big_omega / 2.0)
    np.testing.assert_allclose(res.u[:, 0, 0], np.cos(np.arange(401) * omega_bar),
                               rtol=0, atol=1e-11)

    u, v = np.array(states).T
    energy = 0.5 * m * v**2 + 0.5 * m * omega**2 * u**2
    np.testing.assert_allclose(energy, energy[0], rtol=1e-12, atol=0)

    # Period elongation measured from the unwrapped phase of the numerical state.
    angle = np.unwrap(np.arctan2(-v / omega, u))
    step_angle = np.polyfit(np.arange(angle.size), angle, 1)[0]
    period_ratio = (2.0 * np.pi / step_angle) * dt / (2.0 * np.pi / omega)
    assert period_ratio == pytest.approx((big_omega / 2.0) / np.arctan(big_omega / 2.0),
                                         rel=1e-12)
    assert period_ratio > 1.0  # the trapezoidal rule lengthens the period


# ---------------------------------------------------------------- SDOF, damped and forced

_M, _WN, _ZETA, _F = 1.0, 2.0 * np.pi, 0.05, 1.0
_K, _C = _M * _WN**2, 2.0 * _ZETA * _M * _WN
_W = 0.5 * _WN  # forcing frequency, rad/s
_TF = 2.0 * np.pi / _W


def _receptance(w: complex) -> complex:
    """u / F for u'' + ... under F e^{i w t} (w may be complex for the discrete check)."""
    return 1.0 / (_K - _M * w**2 + 1j * _C * w)


def _forced_exact(t: np.ndarray) -> np.ndarray:
    """Full response (transient + steady) of the damped SDOF to F cos(W t) from rest."""
    h = _F * _receptance(_W)
    wd = _WN * np.sqrt(1.0 - _ZETA**2)
    a = -h.real
    b = (_ZETA * _WN * a - (1j * _W * h).real) / wd
    decay = np.exp(-_ZETA * _WN * t)
    return (h * np.exp(1j * _W * t)).real + decay * (a * np.cos(wd * t) + b * np.sin(wd * t))


def _run_forced(rho_inf: float, steps_per_period: int, n_periods: int,
                record_every: int = 1) -> TransientResult:
    m, k, c = _sdof(_M, _K, _C)
    return solve_transient(m, k, np.full(1, _F), lambda t: np.cos(_W * t),
                           _TF / steps_per_period, steps_per_period * n_periods, C=c,
                           rho_inf=rho_inf, record_dofs=[0], record_every=record_every)


def _fit_complex_amplitude(t: np.ndarray, u: np.ndarray) -> complex:
    """Z with u = Re(Z e^{i W t}), by least squares."""
    basis = np.column_stack([np.cos(_W * t), np.sin(_W * t)])
    a, b = np.linalg.lstsq(basis, u, rcond=None)[0]
    return complex(a, -b)


@pytest.mark.parametrize("rho_inf", [1.0, 0.8])
def test_forced_steady_state_amplitude_and_phase(rho_inf: float) -> None:
    res = _run_forced(rho_inf, 40, 60)  # zeta omega t_end = 19: transient below 1e-8
    z = _fit_complex_amplitude(res.t[-80:], res.u[-80:, 0, 0])
    exact = _F * _receptance(_W)
    assert abs(z) / abs(exact) == pytest.approx(1.0, abs=5e-3)
    assert abs(np.angle(z / exact)) < 5e-3  # rad
    if rho_inf == 1.0:
        # Trapezoidal rule = bilinear map: the sampled steady state is the exact receptance at
        # the warped frequency (2/dt) tan(W dt / 2).
        dt = _TF / 40
        warped = (2.0 / dt) * np.tan(_W * dt / 2.0)
        assert abs(z - _F * _receptance(warped)) < 1e-9 * abs(exact)


@pytest.mark.parametrize("rho_inf", [1.0, 0.8])
def test_second_order_convergence(rho_inf: float) -> None:
    steps = np.array([20, 40, 80, 160])
    errors = []
    for n in steps:
        res = _run_forced(rho_inf, int(n), 5, record_every=int(n) // 20)  # same 101 times
        errors.append(np.max(np.abs(res.u[:, 0, 0] - _forced_exact(res.t))))
    order = -np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert order == pytest.approx(2.0, abs=0.2)


# ---------------------------------------------------------------- numerical dissipation


@pytest.mark.parametrize("rho_inf", [0.3, 0.6, 0.9, 1.0])
def test_spectral_radius_at_high_frequency_is_rho_inf(rho_inf: float) -> None:
    """omega dt = 1e4: the free response obeys a 3-term linear recurrence whose roots are the
    eigenvalues of the amplification matrix; their largest modulus must be rho_inf."""
    omega = 2.0 * np.pi
    u = _free_sdof(omega, 1e4 / omega, 60, rho_inf)
    lhs = np.column_stack([u[2:-1], u[1:-2], u[:-3]])
    coeff = np.linalg.lstsq(lhs, u[3:], rcond=None)[0]
    roots = np.roots([1.0, -coeff[0], -coeff[1], -coeff[2]])
    assert np.max(np.abs(roots)) == pytest.approx(rho_inf, abs=5e-3)
    # Decay over many steps: |u_n|^(1/n) -> rho_inf (polynomial prefactor allowed for).
    long = np.abs(_free_sdof(omega, 1e4 / omega, 200, rho_inf))
    assert (long[200] / long[100]) ** (1 / 100) == pytest.approx(rho_inf, rel=0.02)


def test_asymptotic_annihilation_at_rho_zero() -> None:
    omega = 2.0 * np.pi
    u = _free_sdof(omega, 1e4 / omega, 20, 0.0)
    assert np.max(np.abs(u[6:])) < 1e-10


# ---------------------------------------------------------------- MDOF chain


def _chain(n: int = 50, ks: float = 1e4, ms: float = 0.01):
    """Fixed-free spring-mass chain: ground - m - m - ... - m (tip)."""
    diag = np.full(n, 2.0 * ks)
    diag[-1] = ks
    off = np.full(n - 1, -ks)
    stiff = sp.diags([diag, off, off], [0, 1, -1], format="csr")
    mass = sp.diags(np.full(n, ms), format="csr")
    return mass, stiff


def test_mdof_step_response_matches_modal_solution() -> None:
    mass, stiff = _chain()
    a_ray, b_ray = 0.5, 2e-4  # Rayleigh damping: classical modes, zeta_i < 0.25
    damp = a_ray * mass + b_ray * stiff
    force = np.zeros(50)
    force[-1] = 1.0
    w2, phi = sl.eigh(stiff.toarray(), mass.toarray())  # M-orthonormal modes
    w = np.sqrt(w2)
    zeta = a_ray / (2 * w) + b_ray * w / 2
    assert zeta.max() < 1.0
    wd = w * np.sqrt(1 - zeta**2)
    dofs = np.array([0, 24, 49])
    period = 2 * np.pi / w[0]

    res = solve_transient(mass, stiff, force, np.ones_like, period / 800, 1600, C=damp,
                          rho_inf=1.0, record_dofs=dofs)

    t = res.t[:, None]
    static = (phi.T @ force) / w2
    unit_step = 1 - np.exp(-zeta * w * t) * (
        np.cos(wd * t) + zeta / np.sqrt(1 - zeta**2) * np.sin(wd * t))
    exact = (unit_step * static) @ phi[dofs].T
    assert np.max(np.abs(res.u[:, :, 0] - exact)) < 5e-3 * np.max(np.abs(exact))
    assert res.n_factorizations == 2  # f(0) != 0: M once for a0, effective matrix once


def test_factorization_count() -> None:
    mass, stiff = _chain(10)
    force = np.zeros(10)
    force[-1] = 1.0
    rest = solve_transient(mass, stiff, force, lambda t: np.sin(t), 1e-3, 50)
    assert rest.n_factorizations == 1  # f(0) = 0, u0 = v0 = 0: a0 = 0 exactly
    loaded = solve_transient(mass, stiff, force, np.ones_like, 1e-3, 50)
    assert loaded.n_factorizations == 2  # M factorised once for a0, effective matrix once


def test_batched_columns_equal_separate_runs_exactly() -> None:
    mass, stiff = _chain()
    damp = 1e-3 * stiff
    f1, f2 = np.zeros(50), np.zeros(50)
    f1[-1], f2[10] = 1.0, 0.5
    phase = lambda t: 30.0 * t + 5.0 * t**2  # noqa: E731
    history = lambda t: np.column_stack([np.cos(phase(t)), np.sin(phase(t))])  # noqa: E731
    kw = dict(C=damp, rho_inf=0.9, record_dofs=[0, 10, 49])
    both = solve_transient(mass, sp.csr_matrix(stiff), sp.csr_matrix(np.column_stack([f1, f2])),
                           history, 1e-3, 300, **kw)
    first = solve_transient(mass, stiff, f1, lambda t: history(t)[:, 0], 1e-3, 300, **kw)
    second = solve_transient(mass, stiff, f2[:, None], lambda t: history(t)[:, 1:], 1e-3, 300,
                             **kw)
    assert both.u.shape == (301, 3, 2)
    # SuperLU solves the columns one by one: bit for bit; PARDISO's block solve of several
    # right-hand sides orders the sums differently (measured 4e-16 relative on the transient
    # example), so the runs agree to round-off
    scale = np.abs(both.u).max()
    np.testing.assert_allclose(both.u[:, :, 0], first.u[:, :, 0], rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(both.u[:, :, 1], second.u[:, :, 0], rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(both.u_final[:, 1], second.u_final[:, 0], rtol=0,
                               atol=1e-12 * np.abs(both.u_final).max())
    np.testing.assert_allclose(both.v_final[:, 0], first.v_final[:, 0], rtol=0,
                               atol=1e-12 * np.abs(both.v_final).max())


# ---------------------------------------------------------------- extreme step sizes


@pytest.mark.parametrize("rho_inf", [0.9, 0.5, 0.0])
def test_huge_step_converges_to_quasi_static(rho_inf: float) -> None:
    m, omega, force = 2.0, 2.0 * np.pi * 3.0, 5.0
    mass, stiff, _ = _sdof(m, m * omega**2)
    period = 2.0 * np.pi / omega
    res = solve_transient(mass, stiff, np.full(1, force), np.ones_like, 1e3 * period, 300,
                          rho_inf=rho_inf, record_dofs=[0])
    assert np.all(np.isfinite(res.u))
    static = force / (m * omega**2)
    assert res.u[-1, 0, 0] == pytest.approx(static, rel=1e-9)
    assert abs(res.v_final[0, 0]) < 1e-9 * static / period


def test_tiny_step_matches_analytic() -> None:
    m, omega, force = 2.0, 2.0 * np.pi * 3.0, 5.0
    mass, stiff, _ = _sdof(m, m * omega**2)
    dt = 1e-6 * (2.0 * np.pi / omega)
    res = solve_transient(mass, stiff, np.full(1, force), np.ones_like, dt, 2000,
                          rho_inf=0.9, record_dofs=[0])
    # u = F/k (1 - cos omega t), written without cancellation.
    exact = force / (m * omega**2) * 2.0 * np.sin(omega * res.t / 2.0) ** 2
    np.testing.assert_allclose(res.u[:, 0, 0], exact, rtol=1e-8, atol=0)


# ---------------------------------------------------------------- records and initial state


def test_record_stride_and_times() -> None:
    mass, stiff = _chain(5)
    res = solve_transient(mass, stiff, np.ones(5), np.ones_like, 0.01, 10, t0=1.0,
                          record_dofs=[1, 3], record_every=3)
    np.testing.assert_allclose(res.t, [1.0, 1.03, 1.06, 1.09])
    assert res.u.shape == (4, 2, 1)
    assert res.u_final.shape == res.v_final.shape == res.a_final.shape == (5, 1)
    full = solve_transient(mass, stiff, np.ones(5), np.ones_like, 0.01, 10, t0=1.0,
                           record_dofs=[1, 3])
    np.testing.assert_array_equal(res.u, full.u[::3])


def test_initial_conditions_and_initial_acceleration() -> None:
    """Free vibration from u0, v0 with damping: exact SDOF solution, second-order close."""
    omega, zeta = 2.0 * np.pi, 0.1
    mass, stiff, damp = _sdof(1.0, omega**2, 2 * zeta * omega)
    u0, v0 = 0.3, -1.2
    snaps: list[np.ndarray] = []
    res = solve_transient(mass, stiff, np.zeros(1), _zero_load, 1e-3, 2000, C=damp,
                          u0=np.array([u0]), v0=np.array([v0]), record_dofs=[0],
                          on_snapshot=lambda s, t, u, v, a: snaps.append(a.copy()),
                          snapshot_every=1000)
    assert res.n_factorizations == 2
    # a0 from equilibrium.
    assert snaps[0][0, 0] == pytest.approx(-2 * zeta * omega * v0 - omega**2 * u0, rel=1e-14)
    wd = omega * np.sqrt(1 - zeta**2)
    t = res.t
    exact = np.exp(-zeta * omega * t) * (
        u0 * np.cos(wd * t) + (v0 + zeta * omega * u0) / wd * np.sin(wd * t))
    np.testing.assert_allclose(res.u[:, 0, 0], exact, rtol=0, atol=1e-5)
    assert len(snaps) == 3


# ---------------------------------------------------------------- validation


@pytest.fixture
def small():
    mass, stiff = _chain(4)
    return mass, stiff, np.ones(4)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"dt": 0.0}, "dt"),
        ({"dt": -1.0}, "dt"),
        ({"dt": float("nan")}, "dt"),
        ({"dt": float("inf")}, "dt"),
        ({"n_steps": 0}, r"n_steps.*\[1, 100000000\]"),
        ({"n_steps": 10**8 + 1}, "n_steps"),
        ({"rho_inf": 1.5}, r"rho_inf.*\[0, 1\]"),
        ({"rho_inf": -0.1}, "rho_inf"),
        ({"u0": np.zeros(3)}, r"u0.*\(4, 1\)"),
        ({"v0": np.zeros((4, 2))}, r"v0.*\(4, 1\)"),
        ({"C": sp.eye(3)}, r"C.*\(4, 4\)"),
        ({"record_dofs": [0, 4]}, r"record_dofs.*\[0, 3\]"),
        ({"record_every": 0}, "record_every"),
        ({"snapshot_every": 2}, "on_snapshot"),
    ],
)
def test_validation_errors_name_the_argument(small, kwargs, match) -> None:
    mass, stiff, load = small
    args = {"dt": 1e-3, "n_steps": 5}
    args.update(kwargs)
    dt, n = args.pop("dt"), args.pop("n_steps")
    with pytest.raises(ValueError, match=match):
        solve_transient(mass, stiff, load, np.ones_like, dt, n, **args)


def test_validation_of_matrices_and_loads(small) -> None:
    mass, stiff, load = small
    with pytest.raises(ValueError, match=r"K.*\(4, 4\)"):
        solve_transient(mass, sp.eye(5), load, np.ones_like, 1e-3, 5)
    with pytest.raises(ValueError, match="M must be a square"):
        solve_transient(sp.csr_matrix(np.ones((4, 3))), stiff, load, np.ones_like, 1e-3, 5)
    with pytest.raises(ValueError, match=r"load_vectors.*\(4, k"):
        solve_transient(mass, stiff, np.ones(3), np.ones_like, 1e-3, 5)
    with pytest.raises(ValueError, match=r"load_history.*\(6, 2\)"):
        solve_transient(mass, stiff, np.ones((4, 2)), np.ones_like, 1e-3, 5)
    with pytest.raises(ValueError, match="non-finite"):
        solve_transient(mass, stiff, load, lambda t: np.full_like(t, np.nan), 1e-3, 5)
    with pytest.raises(TypeError, match="n_steps"):
        solve_transient(mass, stiff, load, np.ones_like, 1e-3, 2.5)
    with pytest.raises(ValueError, match="singular"):
        solve_transient(sp.csr_matrix((4, 4)), stiff, load, np.ones_like, 1e-3, 5)
