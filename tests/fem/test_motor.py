"""Coin ERM motor model (fem.motor) against independent solutions of its stated ODE."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid, solve_ivp
from scipy.optimize import brentq

from fem.motor import (
    ERMMotor,
    VoltageSchedule,
    erm_load_history,
    phase,
    rise_time_s,
    simulate_speed,
    speed_rate,
    steady_force_N,
    steady_frequency_hz,
    unbalance_force,
)

MOTOR = ERMMotor(unbalance_kg_m=2.0e-7)
W_RATED = 2 * math.pi * 120.0  # rad/s at 3.3 V (defaults)
TAU_UP, TAU_DOWN = 0.020, 0.035


def _target(volts: float) -> float:
    """Signed target speed written from the specification, independently of fem.motor."""
    slope = W_RATED / (3.3 - 0.4)
    return math.copysign(slope * max(abs(volts) - 0.4, 0.0), volts)


def _rhs(volts: float):
    target = _target(volts)

    def f(_t: float, y: np.ndarray) -> list[float]:
        w = y[0]
        if w <= 0.0 and target <= 0.0:
            return [0.0]
        tau = TAU_UP if abs(target) > w else TAU_DOWN
        return [(target - w) / tau]

    return f


def _reference_speed(schedule: list[tuple[float, float]], t_end: float,
                     t_eval: np.ndarray) -> np.ndarray:
    """solve_ivp interval by interval (the right-hand side jumps at every voltage step)."""
    out = np.empty_like(t_eval)
    w0 = 0.0
    bounds = [t for t, _ in schedule[1:]] + [t_end]
    for (start, volts), end in zip(schedule, bounds, strict=True):
        mask = (t_eval >= start) & (t_eval <= end)
        sol = solve_ivp(_rhs(volts), (start, end), [w0], method="DOP853", rtol=1e-12,
                        atol=1e-9, max_step=1e-3, dense_output=True)
        out[mask] = sol.sol(t_eval[mask])[0]
        w0 = float(sol.y[0, -1])
    return out


def test_speed_matches_ode_solver() -> None:
    """Spin-up, spin-down to a lower speed, over-rated drive and sub-start coasting."""
    steps = [(0.0, 3.3), (0.12, 1.5), (0.25, 4.2), (0.33, 0.3)]
    t = np.linspace(0.0, 0.5, 2001)
    ref = _reference_speed(steps, 0.5, t)
    got = simulate_speed(MOTOR, VoltageSchedule(tuple(steps)), t)
    np.testing.assert_allclose(got, ref, rtol=1e-6, atol=1e-6 * W_RATED)
    assert got.max() > 1.2 * W_RATED  # the 4.2 V step drives above rated speed


def test_braking_with_tau_switch_matches_ode_solver() -> None:
    """Weak reverse drive: tau_spindown until omega = |target|, then tau_spinup, then rest."""
    steps = [(0.0, 3.3), (0.2, -1.0)]
    t = np.linspace(0.0, 0.24, 1201)  # stop occurs near 0.246 s: compare before it
    ref = _reference_speed(steps, 0.24, t)
    got = simulate_speed(MOTOR, VoltageSchedule(tuple(steps)), t)
    np.testing.assert_allclose(got, ref, rtol=1e-6, atol=1e-6 * W_RATED)


def test_exponential_approach_closed_form() -> None:
    t = np.linspace(0.0, 0.2, 101)
    got = simulate_speed(MOTOR, VoltageSchedule.constant(3.3), t)
    np.testing.assert_allclose(got, W_RATED * -np.expm1(-t / TAU_UP), rtol=1e-12, atol=1e-9)


def test_phase_is_integral_of_speed() -> None:
    schedule = VoltageSchedule(((0.0, 3.3), (0.1, 1.2), (0.2, -2.0), (0.3, 2.5)))
    t = np.linspace(0.0, 0.4, 80001)
    omega = simulate_speed(MOTOR, schedule, t)
    phi = phase(MOTOR, schedule, t)
    integral = cumulative_trapezoid(omega, t, initial=0.0)
    np.testing.assert_allclose(phi, integral, rtol=1e-6, atol=1e-6)
    assert phi[0] == 0.0


@pytest.mark.parametrize("brake_volts", [-3.3, -1.0])
def test_braking_reaches_zero_at_analytic_time_and_stays(brake_volts: float) -> None:
    t_brake = 0.2
    schedule = VoltageSchedule(((0.0, 3.3), (t_brake, brake_volts)))
    w0 = W_RATED * -math.expm1(-t_brake / TAU_UP)
    target = _target(brake_volts)
    if w0 >= -target:  # slow constant until omega = |target|, then the fast one
        t1 = TAU_DOWN * math.log((w0 - target) / (-2 * target))
        w1 = -target
    else:
        t1, w1 = 0.0, w0
    t_stop = t_brake + t1 + TAU_UP * math.log((w1 - target) / (-target))
    if brake_volts == -3.3:
        assert t_stop == pytest.approx(t_brake + TAU_UP * math.log(2.0), rel=1e-5)

    before = simulate_speed(MOTOR, schedule, np.array([t_stop - 1e-4, t_stop - 1e-7]))
    assert before[0] > 0.0
    assert before[1] == pytest.approx(-target * 1e-7 / TAU_UP, rel=1e-3)  # linear arrival
    after = np.linspace(t_stop, 1.0, 50)
    assert np.all(simulate_speed(MOTOR, schedule, after) == 0.0)
    phi = phase(MOTOR, schedule, after)
    assert np.all(phi == phi[0])


def test_stiction_below_start_voltage() -> None:
    t = np.linspace(0.0, 0.3, 31)
    assert np.all(simulate_speed(MOTOR, VoltageSchedule.constant(0.35), t) == 0.0)
    assert np.all(simulate_speed(MOTOR, VoltageSchedule.constant(-2.0), t) == 0.0)
    assert np.all(phase(MOTOR, VoltageSchedule.constant(0.4), t) == 0.0)


def test_rise_time_is_tau_ln9() -> None:
    schedule = VoltageSchedule.constant(2.0)
    final = 2 * math.pi * steady_frequency_hz(MOTOR, 2.0)

    def crossing(fraction: float) -> float:
        return brentq(lambda s: simulate_speed(MOTOR, schedule, s) - fraction * final,
                      0.0, 1.0, xtol=1e-14)

    measured = crossing(0.9) - crossing(0.1)
    assert measured == pytest.approx(TAU_UP * math.log(9.0), rel=1e-9)
    assert rise_time_s(MOTOR) == pytest.approx(TAU_UP * math.log(9.0), rel=1e-15)


def test_steady_speed_map_and_force_scales_with_omega_squared() -> None:
    assert steady_frequency_hz(MOTOR, 3.3) == pytest.approx(120.0)
    assert steady_frequency_hz(MOTOR, 0.4) == 0.0
    assert steady_frequency_hz(MOTOR, 1.85) == pytest.approx(60.0)
    assert steady_frequency_hz(MOTOR, 4.5) == pytest.approx(120.0 * 4.1 / 2.9)  # extrapolated
    np.testing.assert_array_equal(steady_frequency_hz(MOTOR, np.array([-3.0, 0.1])), 0.0)
    assert steady_force_N(MOTOR, 3.3) == pytest.approx(2.0e-7 * W_RATED**2)
    assert steady_force_N(MOTOR, 3.3) / steady_force_N(MOTOR, 1.85) == pytest.approx(4.0)


def test_unbalance_force_rotates_with_amplitude_me_omega2() -> None:
    schedule = VoltageSchedule(((0.0, 3.3), (0.1, 2.0)))
    t = np.linspace(0.0, 0.2, 501)
    fx, fy = unbalance_force(MOTOR, schedule, t)
    omega = simulate_speed(MOTOR, schedule, t)
    phi = phase(MOTOR, schedule, t)
    np.testing.assert_allclose(np.hypot(fx, fy), 2.0e-7 * omega**2, rtol=1e-12, atol=0)
    np.testing.assert_allclose(np.arctan2(fy, fx)[1:], np.angle(np.exp(1j * phi[1:])),
                               atol=1e-9)
    doubled = ERMMotor(unbalance_kg_m=4.0e-7)
    np.testing.assert_allclose(unbalance_force(doubled, schedule, t)[0], 2 * fx)
    history = erm_load_history(MOTOR, schedule)(t)
    assert history.shape == (t.size, 2)
    np.testing.assert_array_equal(history, np.column_stack([fx, fy]))


def test_scalar_time_and_speed_rate() -> None:
    schedule = VoltageSchedule.constant(3.3)
    assert np.ndim(simulate_speed(MOTOR, schedule, 0.05)) == 0
    assert speed_rate(MOTOR, 3.3, 0.0) == pytest.approx(W_RATED / TAU_UP)
    assert speed_rate(MOTOR, 0.0, 100.0) == pytest.approx(-100.0 / TAU_DOWN)
    assert speed_rate(MOTOR, -3.3, 0.0) == 0.0


# ---------------------------------------------------------------- validation


@pytest.mark.parametrize(
    ("steps", "match"),
    [
        ((), "at least one"),
        (((0.1, 3.3),), r"steps\[0\] t_start_s must be 0"),
        (((0.0, 3.3), (0.2, 1.0), (0.2, 2.0)), r"increase strictly.*steps\[2\]"),
        (((0.0, 3.3), (0.2, 1.0), (0.1, 2.0)), "increase strictly"),
        (((0.0, float("nan")),), "volts must be finite"),
        (((0.0, 3.3), (float("inf"), 1.0)), "t_start_s must be finite"),
        (((0.0, 3.3, 1.0),), r"steps\[0\] must be \(t_start_s, volts\)"),
    ],
)
def test_schedule_validation(steps, match) -> None:
    with pytest.raises(ValueError, match=match):
        VoltageSchedule(steps)


def test_voltage_limits_name_field_and_range() -> None:
    schedule = VoltageSchedule(((0.0, 3.3), (0.1, -4.6)))
    with pytest.raises(ValueError, match=r"steps\[1\] volts = -4.6 V.*\[-4.5, 4.5\].*max_volt"):
        simulate_speed(MOTOR, schedule, np.array([0.0]))
    with pytest.raises(ValueError, match=r"\[-4.5, 4.5\] V"):
        steady_force_N(MOTOR, 5.0)
    with pytest.raises(ValueError, match=r"t must be finite and >= 0"):
        phase(MOTOR, VoltageSchedule.constant(1.0), np.array([-0.1]))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"unbalance_kg_m": 0.0}, r"unbalance_kg_m must be in \(0, inf\)"),
        ({"tau_spinup_s": -1.0}, "tau_spinup_s"),
        ({"tau_spindown_s": float("nan")}, "tau_spindown_s"),
        ({"rated_frequency_hz": 0.0}, "rated_frequency_hz"),
        ({"start_voltage_V": -0.1}, "start_voltage_V"),
        ({"rated_voltage_V": 0.3}, r"rated_voltage_V must be in \(start_voltage_V = 0.4"),
        ({"max_voltage_V": 3.0}, r"max_voltage_V must be in \[rated_voltage_V = 3.3"),
    ],
)
def test_motor_validation(kwargs, match) -> None:
    args = {"unbalance_kg_m": 1e-7} | kwargs
    with pytest.raises(ValueError, match=match):
        ERMMotor(**args)
