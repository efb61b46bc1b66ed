"""Options of the envelope model's identification (docs/transient-model.md, "what was tried"):
the gain held at 1 (steady level = the harmonic model), one mode map per attachment, the
transient's equivalent loss factor, and the settled-run steady metric."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from motorlaw import SpeedLaw
from surrogate.rom_metrics import envelope_metrics, summarise
from surrogate.runtime.rom import load_envelope_model, motor_speed
from tests.surrogate.rom_cases import DESIGN, SHIPPED

MOTOR = SpeedLaw()


@pytest.fixture(scope="module")
def model():
    return load_envelope_model(SHIPPED)


def _synthetic_runs(model, truths):
    """Runs made by the model's own equations, one per (schedule, truth) pair."""
    from surrogate import rom

    t = np.arange(0.0, 0.2, 2.5e-4)
    schedules = [np.where(t < 0.06, 3.3, 0.0), np.where(t < 0.01, 4.5, 2.5),
                 np.where(t < 0.05, 4.0, np.where(t < 0.07, -3.0, 0.0))]
    amp = model.steady_amplitudes(DESIGN)
    runs, amps = [], []
    for truth in truths:
        for volts in schedules:
            w = motor_speed(t, volts, 0.02, 0.035, MOTOR)
            env = np.stack([rom._predict(t, w[None], amp[p][None], model.grid_hz,
                                         np.asarray(truth)[None])[0]
                            for p in ("center", "edge")])
            runs.append(rom.Run(t, volts, w, env, dict(DESIGN), len(runs), 0.06))
            amps.append(amp)
    return runs, {p: np.stack([a[p] for a in amps]) for p in ("center", "edge")}


def test_without_a_learned_gain_the_mode_is_identified_and_the_gain_stays_one(model):
    from surrogate import rom

    truth = [math.log(70.0), 48.0, 0.0, 0.0]
    runs, amps = _synthetic_runs(model, [truth])
    weights, report = rom.fit_weights(runs, np.ones((len(runs), 1)), amps, model.grid_hz,
                                      learn_gain=False)
    for point in ("center", "edge"):
        w = weights[point][:, 0]
        assert math.exp(w[0]) == pytest.approx(70.0, rel=0.02)
        assert w[1] == pytest.approx(48.0, abs=0.5)
        assert w[2] == 0.0 and w[3] == 0.0  # held, not fitted
        assert report[point]["refined_rms"] < 1e-3


def test_one_mode_map_per_group_identifies_two_different_modes(model):
    """Runs of two groups (block one-hot intercepts, as ``group_by`` builds them) with
    different modes: each group's block recovers its own mode."""
    from surrogate import rom

    truths = [[math.log(60.0), 45.0, 0.0, 0.0], [math.log(150.0), 80.0, 0.0, 0.0]]
    runs, amps = _synthetic_runs(model, truths)
    feats = np.kron(np.repeat(np.eye(2), 3, axis=0), np.ones((1, 1)))  # (6 runs, 2 blocks)
    weights, _ = rom.fit_weights(runs, feats, amps, model.grid_hz, intercepts=[0, 1],
                                 learn_gain=False)
    for point in ("center", "edge"):
        for j, truth in enumerate(truths):
            assert math.exp(weights[point][0, j]) == pytest.approx(math.exp(truth[0]),
                                                                    rel=0.03)
            assert weights[point][1, j] == pytest.approx(truth[1], abs=1.0)


def test_group_by_features_are_one_block_per_choice(model):
    group = {"input": "attachment", "choices": ["glued", "pogo"]}
    grouped = replace(model, meta={**model.meta, "group_by": group})
    model = replace(model, meta={k: v for k, v in model.meta.items() if k != "group_by"})
    x = model.features(DESIGN)
    assert np.array_equal(grouped.features(DESIGN), np.concatenate([x, np.zeros_like(x)]))
    pogo = {**DESIGN, "attachment": "pogo"}
    assert np.array_equal(grouped.features(pogo)[x.size:], model.features(pogo))
    assert not np.any(grouped.features(pogo)[:x.size])


def test_equivalent_loss_evaluates_the_harmonic_model_at_eta_f_over_f_ref(model):
    eq = replace(model, meta={**model.meta, "loss_reference_hz": 120.0})
    amp = eq.steady_amplitudes(DESIGN)
    grid = model.grid_hz
    X = {k: [DESIGN[k]] * grid.size for k in model.design_names}
    X["frequency_hz"] = grid
    X["tissue_loss_factor"] = DESIGN["tissue_loss_factor"] * grid / 120.0
    X["ring_loss_factor"] = DESIGN["ring_loss_factor"] * grid / 120.0
    ref = model.harmonic.predict(X, extrapolate=True)
    np.testing.assert_allclose(amp["center"], ref["center_amplitude_um"], rtol=1e-12)
    at_120 = int(np.argmin(abs(grid - 120.0)))  # equal to the plain model at f_ref
    assert amp["edge"][at_120] == pytest.approx(
        model.steady_amplitudes(DESIGN)["edge"][at_120], rel=1e-6)


def test_settled_flag_and_the_settled_steady_summary():
    t = np.arange(0.0, 0.2, 1e-4)
    on = 0.1
    volts = np.where(t < on, 3.3, 0.0)
    settled = np.where(t < on, 1 - np.exp(-t / 0.005), np.exp(-(t - on) / 0.01))
    beating = settled * (1 + 0.3 * np.sin(2 * math.pi * 60 * t))
    a = envelope_metrics(t, volts, on, settled, settled * 1.02)
    b = envelope_metrics(t, volts, on, beating, settled)
    assert a["settled"] == 1.0 and b["settled"] == 0.0
    rows = [{**{f"{p}_{k}": v for p in ("center", "edge") for k, v in m.items()}}
            for m in (a, b)]
    s = summarise(rows)
    assert s["center_settled_runs"] == 1
    assert s["center_steady_rel_err_settled_median"] == pytest.approx(0.02, rel=1e-6)
