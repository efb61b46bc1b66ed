"""Options of the envelope model's identification (docs/transient-model.md, "what was tried"):
the gain held at 1 (steady level = the harmonic model), one mode map per attachment, the
transient's equivalent loss factor, the settled-run steady metric and two modes per point."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from motorlaw import SpeedLaw
from surrogate.envelope.metrics import envelope_metrics, summarise
from surrogate.runtime.rom import load_envelope_model, model_from_parts, motor_speed
from surrogate.runtime.rom_modes import mode_response, modes_response, params_for
from tests.surrogate.rom_cases import DESIGN, SHIPPED

MOTOR = SpeedLaw()


@pytest.fixture(scope="module")
def model():
    return load_envelope_model(SHIPPED)


def _synthetic_runs(model, truths):
    """Runs made by the model's own equations, one per (schedule, truth) pair."""
    from surrogate.envelope import fit as rom

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
    from surrogate.envelope import fit as rom

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
    from surrogate.envelope import fit as rom

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


# --------------------------------------------------------------------------- two modes

#: fast mode 1 (sigma 150 1/s, 60 Hz), slow mode 2 (25 1/s, 40 Hz), mode 1's share w
TWO_MODES = [math.log(150.0), 60.0, 0.0, 0.0, math.log(25.0), 40.0, 0.7]


def _intercept_model(row):
    """The shipped model with every design's parameters ``row`` (intercept-only weights; two
    modes for a row of 7)."""
    coef = json.loads((SHIPPED / "coefficients.json").read_text())
    hcard = json.loads((SHIPPED / "harmonic_card.json").read_text())
    n = np.asarray(coef["weights"]["center"]).shape[1]
    weights = np.zeros((len(row), n))
    for j in range(len(coef["group_by"]["choices"])):  # each group's intercept column
        weights[:, (j + 1) * n // len(coef["group_by"]["choices"]) - 1] = row
    modes = 2 if len(row) == len(params_for(2)) else 1
    coef.update(modes=modes, weights={p: weights.tolist() for p in ("center", "edge")},
                clip={k: [-1e6, 1e6] for k in params_for(modes)})
    return model_from_parts(coef, hcard, SHIPPED / "harmonic.onnx")


def test_two_modes_are_identified_back(model):
    """Runs made by the two-mode equations: the per-run starts about the one-mode fit and
    the refinements recover both modes and the share."""
    from surrogate.envelope import fit as rom

    runs, amps = _synthetic_runs(model, [TWO_MODES])
    weights, report = rom.fit_weights(runs, np.ones((len(runs), 1)), amps, model.grid_hz,
                                      learn_gain=False, modes=2)
    for point in ("center", "edge"):
        w = weights[point][:, 0]
        assert w.shape == (7,)
        assert np.exp(w[[0, 4]]) == pytest.approx([150.0, 25.0], rel=0.02)
        assert w[[1, 5]] == pytest.approx([60.0, 40.0], abs=0.5)
        assert w[6] == pytest.approx(0.7, abs=0.01)
        assert w[2] == 0.0 and w[3] == 0.0  # the gain held
        assert report[point]["refined_rms"] < 1e-3


def test_a_quasi_static_share_and_one_mode_are_identified_back(model):
    """Runs made by a quasi-static share w of the steady response (mode 1 held at QS_SIGMA)
    beside one mode: the fit holds mode 1 and recovers the mode and the share."""
    from surrogate.envelope import fit as rom

    truth = [math.log(rom.QS_SIGMA), rom.QS_FN, 0.0, 0.0, math.log(40.0), 45.0, 0.3]
    runs, amps = _synthetic_runs(model, [truth])
    weights, report = rom.fit_weights(runs, np.ones((len(runs), 1)), amps, model.grid_hz,
                                      learn_gain=False, modes=2, share=True)
    for point in ("center", "edge"):
        w = weights[point][:, 0]
        assert w[:4] == pytest.approx([math.log(rom.QS_SIGMA), rom.QS_FN, 0.0, 0.0])  # held
        assert math.exp(w[4]) == pytest.approx(40.0, rel=0.02)
        assert w[5] == pytest.approx(45.0, abs=0.5)
        assert w[6] == pytest.approx(0.3, abs=0.01)
        assert report[point]["refined_rms"] < 1e-3


def test_the_quasi_static_share_option_is_checked(tmp_path):
    from surrogate.envelope import fit as rom

    for bad in ({"quasi_static_share": 1}, {"quasi_static_share": True, "modes": 2}):
        with pytest.raises(ValueError, match="quasi_static_share"):
            rom.train(["unused"], tmp_path / "out", **bad)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("share", [0.7, 1.6, -0.5])
def test_two_modes_settle_on_the_steady_response_exactly(share):
    """c_1 = w, c_2 = 1 - w: at constant speed z_1 + z_2 = A, whatever the (real) share."""
    t = np.linspace(0.0, 1.0, 4001)
    omega = np.full(t.size, 2 * math.pi * 120.0)
    q = np.full((1, t.size), 7.0)
    env = modes_response(t, omega, q, np.array([[150.0, 25.0]]), np.array([[60.0, 40.0]]),
                         np.array([[share, 1.0 - share]]))[0]
    assert env[-1] == pytest.approx(7.0, rel=1e-9)


def test_a_two_mode_model_runs_from_its_coefficients_and_settles_on_the_harmonic_level():
    two = _intercept_model(TWO_MODES)
    assert two.modes == 2 and two.params == params_for(2)
    par = two.parameters(DESIGN)["edge"]
    assert (par["sigma2_1_s"], par["fn2_hz"], par["weight"]) == pytest.approx((25.0, 40.0, 0.7))
    t = np.arange(0.0, 1.0, 5e-4)
    out = two.simulate(t, np.full(t.size, 3.3), DESIGN)
    level = two.steady_levels(out["speed_hz"][-1:] * 2 * math.pi, DESIGN)
    for point in ("center", "edge"):
        assert out[f"{point}_envelope_um"][-1] == pytest.approx(level[point][0], rel=1e-9)
    # w = 1: the second mode is not forced, the model is the one-mode model of mode 1
    unforced = _intercept_model([*TWO_MODES[:6], 1.0])
    volts = np.where(t < 0.06, 3.3, np.where(t < 0.08, -3.0, 0.0))
    a, b = (m.simulate(t, volts, DESIGN) for m in (_intercept_model(TWO_MODES[:4]), unforced))
    for point in ("center", "edge"):
        np.testing.assert_allclose(a[f"{point}_envelope_um"], b[f"{point}_envelope_um"],
                                   rtol=1e-12, atol=1e-12)


def test_one_mode_output_is_unchanged():
    """The one-mode recurrence of the model before two modes, step by step: the shared
    integration gives the same numbers bit for bit, and a model recording ``modes: 1`` is the
    model that records nothing."""
    t = np.arange(0.0, 0.2, 2.5e-4)
    volts = np.where(t < 0.05, 4.0, np.where(t < 0.07, -3.0, 0.0))
    omega = motor_speed(t, volts, 0.02, 0.035, MOTOR)
    q = np.stack([3.0 * (omega / MOTOR.rated_omega) ** 2, (omega / MOTOR.rated_omega) ** 2])
    sigma, fn = np.array([60.0, 210.0]), np.array([45.0, 90.0])
    lam = -sigma + 2j * math.pi * fn
    h = np.diff(t)
    wm, qm = 0.5 * (omega[1:] + omega[:-1]), 0.5 * (q[:, 1:] + q[:, :-1])
    decay = np.exp((lam[:, None] - 1j * wm) * h[None, :])
    ref = np.zeros(q.shape, dtype=complex)
    for k in range(h.size):
        ref[:, k + 1] = qm[:, k] + (ref[:, k] - qm[:, k]) * decay[:, k]
    assert np.array_equal(mode_response(t, omega, q, sigma, fn), np.abs(ref))
    # a one-mode model made of the shipped coefficients' one-mode rows (the shipped model has
    # two: the quasi-static share), recorded as modes 1 and as a model written before the field
    coef = json.loads((SHIPPED / "coefficients.json").read_text())
    one = {**{k: v for k, v in coef.items() if k != "quasi_static_share"}, "modes": 1,
           "weights": {p: w[:len(params_for(1))] for p, w in coef["weights"].items()},
           "clip": {k: coef["clip"][k] for k in params_for(1)}}
    hcard = json.loads((SHIPPED / "harmonic_card.json").read_text())
    recorded, unrecorded = (model_from_parts(c, hcard, SHIPPED / "harmonic.onnx") for c in
                            (one, {k: v for k, v in one.items() if k != "modes"}))
    assert recorded.modes == unrecorded.modes == 1
    a, b = (m.simulate(t, volts, DESIGN) for m in (recorded, unrecorded))
    for k in a:
        assert np.array_equal(a[k], b[k])


@pytest.mark.parametrize("bad", [3, 0, True, 2.0, "2"])
def test_bad_modes_are_refused_by_name(model, tmp_path, bad):
    from surrogate.envelope import fit as rom

    with pytest.raises(ValueError, match=r"^modes = .*allowed 1 or 2"):
        rom.train([tmp_path], tmp_path / "out", modes=bad)
    coef = json.loads((SHIPPED / "coefficients.json").read_text())
    hcard = json.loads((SHIPPED / "harmonic_card.json").read_text())
    with pytest.raises(ValueError, match=r"^modes: "):
        model_from_parts({**coef, "modes": bad}, hcard, SHIPPED / "harmonic.onnx")


def test_cli_refuses_bad_modes_naming_the_field(tmp_path, capsys):
    from hapticrom.cli import main

    out = tmp_path / "rom"
    assert main(["train", "--data", str(SHIPPED.parents[1] / "datasets" / "transient"),
                 "--kind", "rom", "--out", str(out), "--options", '{"modes": 3}']) == 2
    assert "modes = 3: allowed 1 or 2" in capsys.readouterr().err
    assert not out.exists()
