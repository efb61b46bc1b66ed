"""The haptic unit in the time domain: spin-up to steady running matches the harmonic solve,
and the step size stays stable and accurate from very small to very large."""

import numpy as np
import pytest

from fem import results, simulate
from fem.problem import build_problem
from fem.scene import load_scene, scene_from_dict, scene_to_dict
from fem.solve import solve_mode

EXAMPLE = "examples/unit-transient.toml"


def _coarse(duration_ms=300.0, **analysis):
    d = scene_to_dict(load_scene(EXAMPLE))
    d["mesh"].update(order=1, near_size_mm=1.0, far_size_mm=3.0)
    for layer in d["tissue"]["layer"]:
        layer["loss_factor"] = 0.1  # hysteresis: complex modulus vs its Rayleigh equivalent
    d["analysis"].update({"duration_ms": duration_ms, "voltage_schedule": [[0.0, 3.3]],
                          **analysis})
    return scene_from_dict(d)


def _harmonic_on_same_domain(scene):
    """Steady solve at rated speed on the transient's own domain (damping-layer absorber)."""
    p = build_problem(scene)
    w = 2 * np.pi * scene.unit.motor.rated_frequency_hz
    sol = solve_mode(p.domain, 1, p.load * scene.unit.motor.unbalance_kg_m * w**2, w,
                     extra=p.extra)
    stencil = results.surface_stencil(p.domain, np.asarray(scene.output.radii_m))
    return np.abs(results.interpolate(stencil, sol.nodal()))


ON_MS, OFF_MS = 280.0, 350.0


@pytest.fixture(scope="module")
def long_run():
    scene = _coarse(OFF_MS, voltage_schedule=[[0.0, 3.3], [ON_MS, 0.0]])
    return scene, simulate(scene)


def _window(h, t0, t1):
    return (h.t >= t0 * 1e-3) & (h.t < t1 * 1e-3)


def test_steady_amplitude_of_a_long_transient_matches_the_harmonic_solve(long_run):
    scene, res = long_run
    h = res.histories
    n = len(scene.output.radii_mm)
    steady = np.abs(h.u[_window(h, ON_MS - 50, ON_MS)]).max(axis=0)[:n]
    harmonic = _harmonic_on_same_domain(scene)
    assert np.allclose(steady[:, 0], harmonic[:, 0], rtol=0.02)  # u_r
    assert np.allclose(steady[1:, 1], harmonic[1:, 1], rtol=0.02)  # u_z (zero on the axis)
    assert np.allclose(steady[:, 2], harmonic[:, 2], rtol=0.02)  # u_theta


def test_spin_up_runs_at_rated_speed_and_spin_down_rings_out(long_run):
    scene, res = long_run
    h = res.histories
    ux = h.u[:, len(scene.output.radii_mm), 0]  # center, u_r of the theta = 0 meridian
    steady = _window(h, ON_MS - 50, ON_MS)
    def frequency_hz(window):
        return np.count_nonzero(np.diff(np.sign(ux[window])) != 0) / 2 / (
            h.t[window][-1] - h.t[window][0])

    rated = scene.unit.motor.rated_frequency_hz
    assert frequency_hz(steady) == pytest.approx(rated, rel=0.03)
    peak = np.abs(ux[steady]).max()
    assert np.abs(ux[h.t < 2e-3]).max() < 0.01 * peak  # the motor starts from rest
    # after switch-off the speed falls through the unit's suspension resonance (the response
    # first grows), then 40-70 ms later (1.1-2 spin-down time constants) it is slower and dying
    assert frequency_hz(_window(h, OFF_MS - 30, OFF_MS)) < 0.5 * rated
    spin_down = np.abs(ux[h.t > ON_MS * 1e-3]).max()
    assert np.abs(ux[_window(h, OFF_MS - 10, OFF_MS)]).max() < 0.5 * spin_down
    assert "spin up" in res.meta["effects"] and res.meta["modes"] == [1]


@pytest.mark.parametrize("dt_ms", [0.01, 5.0])
def test_step_size_extremes_stay_finite_and_consistent(dt_ms):
    """dt = 0.01 ms resolves the same run as 0.05 ms; dt = 5 ms (less than two steps per
    period) must stay finite and bounded: generalised-alpha damps what it cannot resolve."""
    ref = simulate(_coarse(30.0, time_step_ms=0.05)).histories
    run = simulate(_coarse(30.0, time_step_ms=dt_ms)).histories
    assert np.all(np.isfinite(run.u))
    peak_ref = np.abs(ref.u).max()
    if dt_ms < 0.05:
        at = np.searchsorted(run.t, ref.t)
        assert np.abs(run.u[at] - ref.u).max() < 0.01 * peak_ref
    else:
        assert np.abs(run.u).max() < 2 * peak_ref
