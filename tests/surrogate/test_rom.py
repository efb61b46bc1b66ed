"""Transient envelope ROM: run-time integration, guards, the shipped model against held-out FE
runs, and identification on a known system."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from motorlaw import SpeedLaw
from surrogate.runtime.card import read_card
from surrogate.runtime.rom import (
    FORMAT,
    RomBlowUpError,
    RomInputError,
    _expm,
    load_envelope_model,
    model_from_dict,
    motor_speed,
)

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "models" / "rom-default"
DATASET = ROOT / "datasets" / "transient"
MOTOR = SpeedLaw()
DESIGN = {"skin_E_kPa": 49.0, "fat_thickness_mm": 10.0, "orientation": "reverse",
          "attachment": "pogo", "tau_spinup_ms": 20.0, "tau_spindown_ms": 35.0}


def one_mode(lam: complex, b: complex, *, bound_um: float = 1e6) -> dict:
    """Coefficients of a single-block model dz/dt + i omega z = lam z + b s^2, no design
    dependence."""
    spec = {"design": [{"name": "skin_E_kPa", "low": 20.0, "high": 120.0, "scale": "log"},
                       {"name": "orientation", "choices": ["forward", "reverse"]}],
            "interactions": [], "motor_ranges": {"tau_spinup_ms": [0.01, 100.0],
                                                 "tau_spindown_ms": [0.01, 100.0]}}
    block = {"point": "center", "component": "r",
             "A0": [[lam.real, -lam.imag], [lam.imag, lam.real]],
             "A_d": [[[0.0, 0.0], [0.0, 0.0]]] * 2, "b0": [b.real, b.imag],
             "b_d": [[0.0, 0.0]] * 2}
    edge = dict(block, point="edge")
    return {"format": FORMAT, "blocks": [block, edge], "spec": spec, "bound_um": bound_um,
            "motor": {"rated_voltage_V": 3.3, "rated_frequency_hz": 120.0,
                      "start_voltage_V": 0.4, "max_voltage_V": 4.5}}


ONE_DESIGN = {"skin_E_kPa": 49.0, "orientation": "reverse", "tau_spinup_ms": 20.0,
              "tau_spindown_ms": 35.0}


# --------------------------------------------------------------------------- motor + integrator


def test_motor_speed_matches_first_order_step_response():
    t = np.linspace(0.0, 0.2, 2001)
    omega = motor_speed(t, np.full(t.size, 3.3), 0.02, 0.035, MOTOR)
    exact = MOTOR.rated_omega * (1.0 - np.exp(-t / 0.02))
    np.testing.assert_allclose(omega, exact, rtol=1e-12, atol=1e-9)


def test_braking_stops_at_rest_and_sub_start_voltage_does_not_spin():
    t = np.linspace(0.0, 0.3, 3001)
    volts = np.where(t < 0.1, 3.3, -3.3)
    omega = motor_speed(t, volts, 0.02, 0.035, MOTOR)
    assert np.all(omega >= 0.0)
    assert omega[-1] == 0.0 and omega[t > 0.2].max() == 0.0
    assert np.all(motor_speed(t, np.full(t.size, 0.39), 0.02, 0.035, MOTOR) == 0.0)


def test_expm_matches_scipy():
    from scipy.linalg import expm

    rng = np.random.default_rng(1)
    m = rng.normal(size=(4, 3, 3)) * np.array([0.1, 1.0, 10.0, 100.0])[:, None, None]
    np.testing.assert_allclose(_expm(m), np.stack([expm(x) for x in m]), rtol=1e-10,
                               atol=1e-12)


def test_steady_envelope_is_the_harmonic_response_of_the_mode():
    lam, b = complex(-80.0, 2 * np.pi * 60.0), complex(1000.0, -500.0)
    model = model_from_dict(one_mode(lam, b))
    t = np.linspace(0.0, 0.5, 2501)
    design = dict(ONE_DESIGN, tau_spinup_ms=0.01)  # at speed almost at once
    out = model.simulate(t, np.full(t.size, 3.3), design)
    omega = MOTOR.rated_omega  # steady: 0 = (lam - i omega) z + b
    assert out["center_envelope_um"][-1] == pytest.approx(abs(b / (lam - 1j * omega)),
                                                          rel=1e-6)
    np.testing.assert_array_equal(out["center_envelope_um"], out["edge_envelope_um"])


def test_transient_matches_a_fine_ode_solution_and_converges_in_the_step():
    from scipy.integrate import solve_ivp

    lam, b = complex(-50.0, 2 * np.pi * 60.0), complex(800.0, 300.0)
    model = model_from_dict(one_mode(lam, b))
    t_end = 0.12

    def volts(t):
        return np.select([t < 0.01, t < 0.05, t < 0.08], [4.5, 2.5, -3.0], 0.0)

    def rom(n):
        t = np.linspace(0.0, t_end, n)
        return t, model.simulate(t, volts(t), ONE_DESIGN)["center_envelope_um"]

    # reference: the same ODE with the exact speed of the same schedule
    t_f = np.linspace(0.0, t_end, 120001)
    omega_f = motor_speed(t_f, volts(t_f), 0.02, 0.035, MOTOR)

    def rhs(t, y):
        w = np.interp(t, t_f, omega_f)
        z = (lam - 1j * w) * (y[0] + 1j * y[1]) + b * (w / MOTOR.rated_omega) ** 2
        return [z.real, z.imag]

    ref = solve_ivp(rhs, (0.0, t_end), [0.0, 0.0], t_eval=np.linspace(0.0, t_end, 121),
                    rtol=1e-10, atol=1e-12, max_step=1e-4)
    env_ref = np.hypot(*ref.y)
    errs = []
    for n in (121, 241, 481):
        _, env = rom(n)
        errs.append(np.max(np.abs(env[:: (n - 1) // 120] - env_ref)) / env_ref.max())
    assert errs[-1] < 2e-3
    assert errs[1] < errs[0] and errs[2] < errs[1]  # converges as the step shrinks


# --------------------------------------------------------------------------- guards


def test_unstable_model_is_refused_at_load():
    with pytest.raises(RomBlowUpError, match="unstable"):
        model_from_dict(one_mode(complex(5.0, 300.0), complex(1.0, 0.0)))


def test_divergence_beyond_the_bound_fails_cleanly():
    model = model_from_dict(one_mode(complex(-50.0, 300.0), complex(1e4, 0.0), bound_um=1.0))
    t = np.linspace(0.0, 0.1, 501)
    with pytest.raises(RomBlowUpError, match="diverged at t = "):
        model.simulate(t, np.full(t.size, 3.3), ONE_DESIGN)


def test_bad_inputs_name_the_field():
    model = model_from_dict(one_mode(complex(-50.0, 300.0), complex(1.0, 0.0)))
    t = np.linspace(0.0, 0.01, 11)
    cases = [
        (dict(ONE_DESIGN, skin_E_kPa=500.0), np.full(11, 3.3), t, "skin_E_kPa"),
        (dict(ONE_DESIGN, orientation="sideways"), np.full(11, 3.3), t, "orientation"),
        ({k: v for k, v in ONE_DESIGN.items() if k != "tau_spinup_ms"}, np.full(11, 3.3), t,
         "tau_spinup_ms"),
        (dict(ONE_DESIGN, colour=1), np.full(11, 3.3), t, "colour"),
        (ONE_DESIGN, np.full(11, 5.0), t, "volts"),
        (ONE_DESIGN, np.full(10, 3.3), t, "volts"),
        (ONE_DESIGN, np.full(11, 3.3), t[::-1], "t_s"),
    ]
    for design, volts, tt, field in cases:
        with pytest.raises(RomInputError) as err:
            model.simulate(tt, volts, design)
        assert err.value.field == field
    out = model.simulate(t, np.full(11, 3.3), dict(ONE_DESIGN, skin_E_kPa=500.0),
                         extrapolate=True)
    assert np.all(np.isfinite(out["center_envelope_um"]))


def test_runtime_imports_numpy_only():
    code = ("import sys; import surrogate.runtime.rom; "
            "bad = [m for m in ('scipy', 'pysindy', 'fem', 'sklearn', 'torch', 'pandas') "
            "if m in sys.modules]; print(bad); sys.exit(1 if bad else 0)")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT)
    assert res.returncode == 0, res.stdout + res.stderr


# --------------------------------------------------------------------------- the shipped model


def test_shipped_model_hashes_are_verified(tmp_path):
    model = load_envelope_model(SHIPPED)
    assert len(model.blocks) >= 4
    copy = tmp_path / "rom"
    shutil.copytree(SHIPPED, copy)
    coef = json.loads((copy / "coefficients.json").read_text())
    coef["bound_um"] *= 2
    (copy / "coefficients.json").write_text(json.dumps(coef))
    with pytest.raises(ValueError, match="sha256"):
        load_envelope_model(copy)


def test_shipped_model_is_stable_far_beyond_the_training_horizon():
    model = load_envelope_model(SHIPPED)
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 5.0, 2e-4)  # 40x the 120 ms training runs
    levels = rng.uniform(-4.5, 4.5, size=100)  # a new voltage every 50 ms
    volts = levels[(t / 0.05).astype(int)]
    out = model.simulate(t, volts, DESIGN)
    env = np.stack([out["center_envelope_um"], out["edge_envelope_um"]])
    assert np.all(np.isfinite(env)) and env.max() < model.bound_um
    # constant drive: the envelope settles to a constant; switched off: it dies away
    t2 = np.arange(0.0, 2.0, 2e-4)
    out2 = model.simulate(t2, np.where(t2 < 1.0, 3.3, 0.0), DESIGN)
    c = out2["center_envelope_um"]
    assert abs(c[t2 < 1.0][-1] / c[(t2 > 0.9) & (t2 < 1.0)].mean() - 1) < 1e-6
    assert c[-1] < 1e-6 * c.max()


def test_shipped_model_reproduces_held_out_fe_transients():
    from surrogate import rom

    runs, _, _ = rom.load_runs([DATASET])
    held = [r for r in runs if r.sample_index % rom.HOLDOUT_EVERY == rom.HOLDOUT_EVERY - 1]
    assert len(held) >= 4
    ev = rom.evaluate(load_envelope_model(SHIPPED), held)["summary"]
    card = json.loads((SHIPPED / "card.json").read_text())
    for key, value in ev.items():  # the card's metrics are what the model does
        assert card["metrics"]["held_out"]["summary"][key] == pytest.approx(value, rel=1e-9,
                                                                            abs=1e-12)
    assert ev["center_nrmse_median"] < 0.2 and ev["edge_nrmse_median"] < 0.2


# --------------------------------------------------------------------------- identification


def test_complex_envelope_of_a_rotating_signal():
    from surrogate.rom import complex_envelopes

    t = np.linspace(0.0, 0.12, 1201)
    phi = 2 * np.pi * 120.0 * t
    amp = 1.0 - np.exp(-t / 0.01)  # from rest, like an FE run
    u = np.stack([2.0 * amp * np.cos(phi + 0.3), np.zeros_like(t), 0.5 * amp * np.sin(phi)])
    z = complex_envelopes(u, phi)
    mid = slice(100, -100)
    np.testing.assert_allclose(np.abs(z[0, mid]), 2.0 * amp[mid], rtol=2.5e-2)
    np.testing.assert_allclose(np.angle(z[0, mid]), 0.3, atol=2.5e-2)
    np.testing.assert_allclose(z[2, mid], -0.5j * amp[mid], atol=2e-2)
    assert np.all(np.abs(z[1]) == 0.0)


def test_identification_recovers_a_known_mode():
    """Runs synthesised by the run-time integrator from a known mode; the fit must return
    its eigenvalue and forcing."""
    from surrogate import rom

    lam, b = complex(-70.0, 2 * np.pi * 60.0), complex(900.0, -400.0)
    model = model_from_dict(one_mode(lam, b))
    runs = []
    rng = np.random.default_rng(3)
    for i in range(6):
        t = np.arange(0.0, 0.12, 2e-4)
        volts = np.where(t < rng.uniform(0.03, 0.07), rng.uniform(1.5, 4.5), 0.0)
        design = {"skin_E_kPa": rng.uniform(20, 120), "fat_thickness_mm": rng.uniform(3, 20),
                  "orientation": ("forward", "reverse")[i % 2],
                  "attachment": ("glued", "pogo")[(i // 2) % 2],
                  "tau_spinup_ms": 20.0, "tau_spindown_ms": 35.0}
        omega = motor_speed(t, volts, 0.02, 0.035, MOTOR)
        z = model._integrate(t, omega, np.zeros(2))[:, 0]
        zc = z[:, 0] + 1j * z[:, 1]
        zz = np.stack([zc, np.zeros_like(zc), 1j * zc])
        runs.append(rom.Run(t, volts, omega, {"center": zz, "edge": zz}, design, i,
                            float(t[np.flatnonzero(volts <= 0)[0]])))
    coef, equations = rom.fit_envelope_model(runs, MOTOR, n_models=3)
    assert len(coef["blocks"]) == 4 and equations
    for blk in coef["blocks"]:
        eig = np.linalg.eigvals(np.asarray(blk["A0"]))
        assert np.max(eig.real) == pytest.approx(lam.real, rel=0.02)
        assert np.max(eig.imag) == pytest.approx(lam.imag, rel=0.02)
        scale = 1.0 if blk["component"] == "r" else 1j
        assert complex(*blk["b0"]) == pytest.approx(b * scale, rel=0.03)
        assert math.isfinite(blk["relative_spread"])


def test_train_kind_rom_registers_a_verified_model(tmp_path, capsys):
    from hapticrom.cli import main

    out = tmp_path / "rom"
    assert main(["train", "--data", str(DATASET), "--kind", "rom", "--out", str(out)]) == 0
    card = read_card(out)  # hashes verified like every model
    assert card["kind"] == "rom" and list(card["files"]) == ["coefficients.json"]
    model = load_envelope_model(out)
    assert model.spec == load_envelope_model(SHIPPED).spec
    from surrogate.registry import list_models

    [row] = list_models(tmp_path)
    assert row["status"] == "ok" and "center envelope median NRMSE" in row["headline"]
    assert main(["train", "--data", str(DATASET), "--kind", "rom", "--out", str(out)]) == 2
    assert "exists" in capsys.readouterr().err
    assert main(["train", "--data", str(DATASET), "--kind", "rom", "--out", str(tmp_path / "x"),
                 "--options", '{"threshold": 2}']) == 2
    assert "threshold = 2: allowed (0, 1)" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()
