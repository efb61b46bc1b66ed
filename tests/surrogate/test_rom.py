"""Grey-box transient envelope model: the rotating-frame mode against an ODE solver, the
continuation below the harmonic model's range, guards, the shipped model against its card and
held-out FE runs, and identification of a known mode."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys

import numpy as np
import pytest

from motorlaw import SpeedLaw
from surrogate.envelope.metrics import envelope_metrics, fall_time, first_crossing
from surrogate.runtime.card import read_card
from surrogate.runtime.rom import (
    RomInputError,
    continued_steady,
    gain_factor,
    load_envelope_model,
    mode_response,
    motor_speed,
)
from tests.surrogate.rom_cases import DESIGN, ROOT, SHIPPED, TRANSIENT, transient_subset

DATASET = TRANSIENT
MOTOR = SpeedLaw()


@pytest.fixture(scope="module")
def model():
    return load_envelope_model(SHIPPED)


# --------------------------------------------------------------------------- the mode


def test_mode_tracks_a_constant_steady_response_exactly():
    t = np.linspace(0.0, 0.4, 1601)
    omega = np.full(t.size, 2 * math.pi * 120.0)
    q = np.full((1, t.size), 7.0)
    env = mode_response(t, omega, q, np.array([60.0]), np.array([50.0]))[0]
    assert env[-1] == pytest.approx(7.0, rel=1e-9)
    # from rest the envelope beats at |f - f_n| = 70 Hz while the free part decays (sigma 60)
    assert env[: int(0.05 / 2.5e-4)].max() > 7.5


def test_mode_matches_a_fine_ode_solution_and_converges_in_the_step():
    from scipy.integrate import solve_ivp

    sigma, fn = 40.0, 55.0
    lam = complex(-sigma, 2 * math.pi * fn)
    t_end = 0.12

    def volts(t):
        return np.select([t < 0.01, t < 0.05, t < 0.08], [4.5, 2.5, -3.0], 0.0)

    def steady(w):
        return 3.0 * (w / MOTOR.rated_omega) ** 2

    t_f = np.linspace(0.0, t_end, 120001)
    w_f = motor_speed(t_f, volts(t_f), 0.02, 0.035, MOTOR)

    def rhs(t, y):
        w = np.interp(t, t_f, w_f)
        z = y[0] + 1j * y[1]
        dz = (lam - 1j * w) * z + (1j * w - lam) * steady(w)
        return [dz.real, dz.imag]

    ref = solve_ivp(rhs, (0.0, t_end), [0.0, 0.0], t_eval=np.linspace(0.0, t_end, 121),
                    rtol=1e-10, atol=1e-12, max_step=1e-4)
    env_ref = np.hypot(*ref.y)
    errs = []
    for n in (121, 241, 481, 961):
        t = np.linspace(0.0, t_end, n)
        w = motor_speed(t, volts(t), 0.02, 0.035, MOTOR)
        env = mode_response(t, w, steady(w)[None], np.array([sigma]), np.array([fn]))[0]
        errs.append(np.max(np.abs(env[:: (n - 1) // 120] - env_ref)) / env_ref.max())
    assert errs[-1] < 5e-3
    assert errs[0] > errs[1] > errs[2] > errs[3]  # converges as the step shrinks


@pytest.mark.parametrize("f_low", [100.0, 20.0])
def test_continuation_below_the_band_is_continuous_and_scales_with_the_force(f_low):
    """Below the harmonic model's band (its first grid frequency: 100 Hz for a model trained
    on 100-250 Hz, 20 Hz for one trained over the motor's whole range) the response is the
    band's first amplitude carried by m e omega^2 through the mode; inside, interpolated."""
    grid = np.arange(f_low, 250.1, 2.5)
    amp = (2.0 + 0.01 * (grid - f_low))[None]
    f = np.array([0.05 * f_low, 0.1 * f_low, f_low * (1 - 1e-6), f_low, f_low + 30.0])
    out = continued_steady(2 * math.pi * f, grid, amp, np.array([2000.0]), np.array([400.0]))[0]
    assert out[2] == pytest.approx(out[3], rel=1e-4)
    assert out[4] == pytest.approx(2.3)
    # below the band: the unbalance force m e omega^2 through the mode's frequency response
    lam = complex(-2000.0, 2 * math.pi * 400.0)
    w1, w2 = 2 * math.pi * f[0], 2 * math.pi * f[1]
    assert out[1] / out[0] == pytest.approx(4.0 * abs(1j * w1 - lam) / abs(1j * w2 - lam),
                                            rel=1e-9)


def test_the_learned_gain_varies_inside_the_band_only():
    """g exp(s (f - 130 Hz) / 50 Hz) with f clamped into the harmonic band."""
    grid = np.arange(20.0, 250.1, 2.5)
    f = np.array([5.0, 20.0, 130.0, 250.0, 400.0])
    g = gain_factor(2 * math.pi * f, np.array([1.5]), np.array([0.4]), grid)[0]
    expected = 1.5 * np.exp(0.4 * (np.clip(f, 20.0, 250.0) - 130.0) / 50.0)
    np.testing.assert_allclose(g, expected, rtol=1e-12)


# --------------------------------------------------------------------------- metrics


def test_metrics_of_a_first_order_envelope():
    t = np.arange(0.0, 0.2, 1e-4)
    tau_up, tau_down, on = 0.01, 0.02, 0.1
    env = np.where(t < on, 1 - np.exp(-t / tau_up),
                   (1 - math.exp(-on / tau_up)) * np.exp(-(t - on) / tau_down))
    volts = np.where(t < on, 3.3, 0.0)
    m = envelope_metrics(t, volts, on, env, env * 1.01)
    assert m["rise_ms_fe"] == pytest.approx(1e3 * tau_up * math.log(9), abs=0.05)
    assert m["decay_ms_fe"] == pytest.approx(1e3 * tau_down * math.log(9), abs=0.05)
    assert m["steady_um_model"] / m["steady_um_fe"] == pytest.approx(1.01)
    assert math.isnan(first_crossing(t, env, 2.0, rising=True))  # never reached
    assert math.isnan(fall_time(t, np.ones_like(t), 0.9, 0.1))


# --------------------------------------------------------------------------- guards


def test_demodulated_envelope_of_a_spin_up_from_rest_starts_at_zero():
    """A force rotating from rest seen in cosine (u_r) and sine (u_theta) phase: the FE
    demodulation recovers the envelope A from t = 0 (the odd-reflection extension made a
    spurious 9 % of the steady level at t = 0 and 9 % over the first 20 ms)."""
    from motorlaw import VoltageSchedule, speed_and_phase
    from surrogate.envelope import fit as rom

    t = np.arange(0.0, 0.3, 2.5e-4)
    law = SpeedLaw(tau_spinup_s=0.034, tau_spindown_s=0.03)
    steps = VoltageSchedule(((0.0, 3.5), (0.013, 1.75), (0.169, -1.76), (0.19, 0.0)))
    w, phi = speed_and_phase(law, steps, t)
    amp = (w / w[t < 0.169].max()) ** 2
    u = np.stack([amp * np.cos(phi), np.zeros_like(t), amp * np.sin(phi)])
    env = np.sqrt(np.sum(np.abs(rom.complex_envelopes(u, phi)) ** 2, axis=0)) / math.sqrt(2)
    level = float(np.mean(amp[(t >= 0.164) & (t < 0.169)]))
    assert env[0] < 1e-3 * level
    assert np.max(np.abs(env - amp)[t < 0.02]) < 0.05 * level


def test_runtime_imports_numpy_and_onnxruntime_only():
    code = ("import sys; import surrogate.runtime.rom; "
            "bad = [m for m in ('scipy', 'fem', 'sklearn', 'torch', 'pandas') "
            "if m in sys.modules]; print(bad); sys.exit(1 if bad else 0)")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT)
    assert res.returncode == 0, res.stdout + res.stderr


def test_bad_inputs_name_the_field(model):
    t = np.linspace(0.0, 0.01, 11)
    v = np.full(11, 3.3)
    cases = [
        (dict(DESIGN, skin_E_kPa=500.0), v, t, "skin_E_kPa"),
        (dict(DESIGN, orientation="sideways"), v, t, "orientation"),
        ({k: x for k, x in DESIGN.items() if k != "tau_spinup_ms"}, v, t, "tau_spinup_ms"),
        (dict(DESIGN, tau_spindown_ms=500.0), v, t, "tau_spindown_ms"),
        (dict(DESIGN, colour=1), v, t, "colour"),
        (dict(DESIGN, attachment="pogo", n_rings=0), v, t, "n_rings"),
        (DESIGN, np.full(11, 5.0), t, "volts"),
        (DESIGN, np.full(10, 3.3), t, "volts"),
        (DESIGN, v, t[::-1], "t_s"),
    ]
    for design, volts, tt, field in cases:
        with pytest.raises(RomInputError) as err:
            model.simulate(tt, volts, design)
        assert err.value.field == field
    out = model.simulate(t, v, dict(DESIGN, skin_E_kPa=500.0), extrapolate=True)
    assert np.all(np.isfinite(out["center_envelope_um"]))


# --------------------------------------------------------------------------- the shipped model


def test_shipped_model_hashes_are_verified(tmp_path):
    card = read_card(SHIPPED)
    assert card["kind"] == "rom"
    assert set(card["files"]) == {"coefficients.json", "harmonic_card.json", "harmonic.onnx"}
    copy = tmp_path / "rom"
    shutil.copytree(SHIPPED, copy)
    with open(copy / "harmonic.onnx", "ab") as f:
        f.write(b"\0")
    with pytest.raises(ValueError, match="sha256"):
        load_envelope_model(copy)


def test_steady_running_is_the_harmonic_model_times_the_learned_gain(model):
    """At constant speed the envelope settles on gain x the harmonic model's amplitude."""
    t = np.arange(0.0, 1.0, 5e-4)
    out = model.simulate(t, np.full(t.size, 3.3), DESIGN)
    f = out["speed_hz"][-1]
    assert f == pytest.approx(120.0, rel=1e-6)
    par = model.parameters(DESIGN)
    X = {k: [DESIGN[k]] for k in model.design_names}
    X["frequency_hz"] = [f]
    harm = model.harmonic.predict(X)
    for point in ("center", "edge"):
        p = par[point]
        gain = p["gain"] * math.exp(p["gain_slope"] * (f - 130.0) / 50.0)
        expected = gain * float(harm[f"{point}_amplitude_um"][0])
        assert out[f"{point}_envelope_um"][-1] == pytest.approx(expected, rel=2e-3)


def test_card_reports_every_target_and_the_held_out_runs_reproduce(model):
    from surrogate.envelope import fit as rom

    card = read_card(SHIPPED)
    summary = card["metrics"]["held_out"]["summary"]
    for point in ("center", "edge"):
        for key in ("steady_rel_err", "rise_abs_err_ms", "decay_abs_err_ms", "nrmse"):
            for stat in ("median", "max"):
                assert f"{point}_{key}_{stat}" in summary
    assert card["split"]["n_train"] + card["split"]["n_held_out"] >= 200
    rows = {r["sample_index"]: r for r in card["metrics"]["held_out"]["runs"]}
    assert all(i % rom.HOLDOUT_EVERY == rom.HOLDOUT_EVERY - 1 for i in rows)
    import pandas as pd

    df = pd.read_parquet(DATASET)
    df = df[(df["status"] == "ok") & df["sample_index"].isin(sorted(rows)[:4])]
    runs = [rom.run_from_row(r, model.design_names)[0] for r in df.to_dict("records")]
    from surrogate.envelope.metrics import evaluate

    for row in evaluate(model, runs)["runs"]:  # the card's per-run metrics are the model's
        ref = rows[row["sample_index"]]
        for k, v in row.items():
            if isinstance(v, float) and math.isfinite(v):
                assert ref[k] == pytest.approx(v, rel=1e-6, abs=1e-9), k


# --------------------------------------------------------------------------- identification


def test_identification_recovers_a_known_mode(model):
    """Synthetic runs made by the model's own equations with a known mode and gain are
    identified back (intercept-only features)."""
    from surrogate.envelope import fit as rom

    t = np.arange(0.0, 0.2, 2.5e-4)
    schedules = [np.where(t < 0.06, 3.3, 0.0), np.where(t < 0.01, 4.5, 2.5),
                 np.where(t < 0.05, 4.0, np.where(t < 0.07, -3.0, 0.0))]
    amp = model.steady_amplitudes(DESIGN)
    truth = np.array([math.log(70.0), 48.0, math.log(1.2), 0.3])
    runs, amps = [], []
    for volts in schedules:
        w = motor_speed(t, volts, 0.02, 0.035, MOTOR)
        env = np.stack([rom._predict(t, w[None], amp[p][None], model.grid_hz, truth[None])[0]
                        for p in ("center", "edge")])
        runs.append(rom.Run(t, volts, w, env, dict(DESIGN), len(runs), 0.06))
        amps.append(amp)
    feats = np.ones((len(runs), 1))
    weights, report = rom.fit_weights(runs, feats, {p: np.stack([a[p] for a in amps])
                                                    for p in ("center", "edge")}, model.grid_hz)
    for point in ("center", "edge"):
        w = weights[point][:, 0]
        assert math.exp(w[0]) == pytest.approx(70.0, rel=0.02)
        assert w[1] == pytest.approx(48.0, abs=0.5)
        assert math.exp(w[2]) == pytest.approx(1.2, rel=0.01)
        assert w[3] == pytest.approx(0.3, abs=0.02)
        assert report[point]["refined_rms"] < 1e-3


def test_train_kind_rom_registers_a_verified_model(tmp_path, capsys):
    from hapticrom.cli import main
    data = transient_subset(tmp_path / "data")  # three parts, its manifest listing only them
    out = tmp_path / "rom"
    opts = json.dumps({"max_nfev": 2})
    assert main(["train", "--data", str(data), "--kind", "rom", "--out", str(out),
                 "--options", opts]) == 0
    card = read_card(out)  # hashes verified like every model
    assert card["kind"] == "rom" and card["split"]["n_held_out"] >= 1
    m = load_envelope_model(out)
    assert m.input_names == load_envelope_model(SHIPPED).input_names
    assert main(["train", "--data", str(data), "--kind", "rom", "--out", str(out),
                 "--options", opts]) == 2
    assert "exists" in capsys.readouterr().err
    assert main(["train", "--data", str(data), "--kind", "rom", "--out", str(tmp_path / "x"),
                 "--options", '{"max_nfev": 0}']) == 2
    assert "max_nfev = 0: allowed integers 1..1000" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()
