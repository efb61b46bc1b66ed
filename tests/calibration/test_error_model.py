"""The surrogate's error model across frequency: the profile and frequency kernels, the
clusters of frequencies that share one mixing variable, the scale per frequency, the
likelihood over clusters against the closed-form t per cluster (and its normalisation), the
estimator of a scale per frequency (bench/calibration/error_model.py) on synthetic errors, and
the model card's own t (``calibration_error_t``): what the fit applies, the fallback without
it, and the bench's writer (round trip, refusals)."""

from __future__ import annotations

import json
import math
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

from calibration.fit import (
    CARD_ERROR_KEY,
    SCALE_HZ,
    SURROGATE_ERROR_T,
    calibrate,
    check_error_t,
    error_settings,
    point_scales,
    surrogate_error_t,
)
from calibration.forward import ForwardModel
from calibration.likelihood import (
    frequency_clusters,
    mixture_log_likelihood,
    mvt_logpdf,
    profile_kernel,
)
from calibration.measurement import measurement_from_rows
from calibration.synthetic import REFERENCE_DESIGNS
from surrogate.runtime import load_predictor
from surrogate.runtime.card import ModelFileError, card_digest, replace_card, verify_model_dir

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench" / "calibration"))
from error_model import error_t_entry, fit_t_per_frequency, select_outputs, write_error_t

DESIGN = REFERENCE_DESIGNS["bare motor"]


def _row(ref, d, f):
    return {"reference": ref, "distance_mm": d, "frequency_hz": f, "quantity": "displacement",
            "unit": "um", "statistic": "peak", "component": "magnitude", "value": 1.0,
            "uncertainty": "5%"}


def test_profile_kernel_matern32_and_exponential():
    lag = np.array([0.0, 1.0, 10.0])
    a = math.sqrt(3.0) * lag / 10.0
    np.testing.assert_allclose(profile_kernel(lag, 10.0), (1 + a) * np.exp(-a))
    np.testing.assert_allclose(profile_kernel(lag, 10.0, "exponential"), np.exp(-lag / 10.0))
    d = np.arange(21.0)
    assert np.linalg.eigvalsh(profile_kernel(d[:, None] - d[None, :], 10.2)).min() > 0
    with pytest.raises(ValueError, match="kernel 'gauss'"):
        profile_kernel(lag, 1.0, "gauss")


def test_frequency_clusters_chain_neighbours():
    f = np.array([150.0, 100.0, 110.0, 150.0, 200.0, 220.0, 210.0])
    assert frequency_clusters(f, 20.0).tolist() == [1, 0, 0, 1, 2, 2, 2]
    assert frequency_clusters(f, 10.0).tolist() == [1, 0, 0, 1, 2, 2, 2]  # chained by 210
    assert frequency_clusters(f, 9.0).tolist() == [2, 0, 1, 2, 3, 5, 4]
    assert frequency_clusters(f, math.inf).tolist() == [0] * 7


def test_error_correlation_and_blocks_follow_the_clusters():
    p = load_predictor("models/nn-default")
    rows = [_row("edge", 2, 150), _row("edge", 5, 160), _row("edge", 5, 200),
            _row("centre", 0, 150), _row("centre", 0, 200)]
    fwd = ForwardModel(p, measurement_from_rows(rows, design=DESIGN),
                       ["skin_E_kPa", "fat_thickness_mm", "tissue_loss_factor"], DESIGN)
    e = {o: error_settings(o, True, 1.5) for o in ("profile_um", "center_amplitude_um")}
    shared = {o: v["shared_within_hz"] for o, v in e.items()}
    C = fwd.error_correlation({"profile_um": e["profile_um"]["length_mm"]},
                              {o: v["frequency_hz"] for o, v in e.items()},
                              shared_within_hz=shared,
                              profile_kernel={o: v["profile_kernel"] for o, v in e.items()},
                              frequency_kernel={o: v["frequency_kernel"] for o, v in e.items()})
    t = SURROGATE_ERROR_T["profile_um"]
    want = (profile_kernel(np.array(3.0), t["length_mm"])
            * math.exp(-0.5 * (10.0 / t["frequency_hz"]) ** 2))
    assert C[0, 1] == pytest.approx(float(want))
    assert C[0, 2] == C[1, 2] == 0.0  # 200 Hz is 40 Hz from 160: its own mixing variable
    assert C[3, 4] == 0.0 and C[0, 3] == 0.0  # the face: 50 Hz apart; face and profile
    blocks = sorted(idx.tolist() for idx, _ in fwd.error_blocks(shared))
    assert blocks == [[0, 1], [2], [3], [4]]
    assert sorted(idx.tolist() for idx, _ in fwd.error_blocks(None)) == [[0, 1, 2], [3, 4]]
    c = point_scales(fwd, e, 1.5)
    j = SCALE_HZ.index(150.0)
    assert c[0] == pytest.approx(t["scale"][j]) and c[1] == pytest.approx(t["scale"][j + 1])
    g = error_settings("profile_um", False, 1.5)  # the Gaussian: one factor, one block
    assert g["nu"] is None and g["shared_within_hz"] is None
    assert np.all(point_scales(fwd, {"profile_um": g}, 1.5) == 1.5)


#: a measured t unlike SURROGATE_ERROR_T's in every value (a coarser scale grid, too)
OWN_PROFILE = {"nu": 3.33, "scale": [2.0, 3.0, 4.0], "frequency_hz": 11.1,
               "shared_within_hz": 0.0, "length_mm": 5.5}


def _entry(card, **outputs):
    """A card entry for the model of ``card`` holding ``outputs`` (output: t)."""
    return {"outputs": outputs or {"profile_um": OWN_PROFILE}, "scale_hz": [100.0, 150.0, 250.0],
            "graph_sha256": card["files"][card["graph"]["file"]],
            "measured_on": {"dataset": "datasets/default-sweep-test",
                            "manifest_sha256": "0" * 64, "designs": "all", "n_designs": 512},
            "command": "python bench/calibration/calibrate.py --sweep-error ... --write-card",
            "measured": "2026-11-28T10:00:00Z"}


def test_the_card_s_own_t_is_what_the_fit_uses():
    """A card with its own t (calibration_error_t): calibrate applies it to the outputs it
    lists (nu, lengths, clusters, the scale on its own frequency grid) and SURROGATE_ERROR_T
    to the others; the t follows the card, not the card's name (a short chain; the error
    model, not the posterior, is checked)."""
    p = load_predictor("models/nn-default")
    m = measurement_from_rows([_row("edge", 2, 125), _row("edge", 6, 125),
                               _row("centre", 0, 125)], design=DESIGN)
    fit = ["skin_E_kPa"]
    fixed = {"fat_thickness_mm": 10.0, "tissue_loss_factor": 0.2}
    p.card = {**p.card, CARD_ERROR_KEY: _entry(p.card)}
    b = calibrate(p, m, fit, fixed=fixed, walkers=8, steps=20, burn=10, n_init=64)
    e = b.error_model["profile_um"]
    assert (e["nu"], e["length_mm"], e["frequency_hz"], e["shared_within_hz"]) == (
        3.33, 5.5, 11.1, 0.0)
    assert e["source"] == "model card" and e["scale_hz"] == (100.0, 150.0, 250.0)
    # 125 Hz: half way between the entry's 2.0 at 100 Hz and 3.0 at 150 Hz
    np.testing.assert_allclose(b.point_scale[:2], 2.5)
    face = b.error_model["center_amplitude_um"]
    assert face["source"] == "SURROGATE_ERROR_T"
    assert face["nu"] == SURROGATE_ERROR_T["center_amplitude_um"]["nu"]
    # the name no longer picks a t: nn-sweep's name on a card without the entry is generic
    p.card = {k: v for k, v in p.card.items() if k != CARD_ERROR_KEY} | {"name": "nn-sweep"}
    a = calibrate(p, m, fit, fixed=fixed, walkers=8, steps=20, burn=10, n_init=64)
    assert a.error_model["profile_um"]["nu"] == SURROGATE_ERROR_T["profile_um"]["nu"]
    assert a.error_model["profile_um"]["source"] == "SURROGATE_ERROR_T"


def test_a_card_without_its_own_t_falls_back_to_the_generic_one():
    card = load_predictor("models/nn-default").card
    assert CARD_ERROR_KEY not in card
    for o in ("center_amplitude_um", "profile_um", "profile_normal_um"):
        for c in (card, None):
            t = surrogate_error_t(o, c)
            assert t["source"] == "SURROGATE_ERROR_T" and t["nu"] == SURROGATE_ERROR_T[o]["nu"]
            assert t["scale"] == tuple(SURROGATE_ERROR_T[o]["scale"]) and t["scale_hz"] == SCALE_HZ
    # an output the card's t does not list: the generic one; an output in neither: None
    own = {**card, CARD_ERROR_KEY: _entry(card)}
    assert surrogate_error_t("profile_um", own)["nu"] == OWN_PROFILE["nu"]
    assert surrogate_error_t("center_amplitude_um", own)["source"] == "SURROGATE_ERROR_T"
    assert surrogate_error_t("edge_amplitude_um", own) is None
    assert error_settings("profile_um", False, 1.5, card=own)["nu"] is None  # the Gaussian


def test_a_card_s_t_measured_on_another_graph_is_refused():
    """An entry whose graph digest is not this card's graph (the model retrained, the entry
    carried over): refused with the key and the reason, never applied."""
    card = load_predictor("models/nn-default").card
    stale = {**card, CARD_ERROR_KEY: {**_entry(card), "graph_sha256": "f" * 64}}
    with pytest.raises(ModelFileError, match=r"graph_sha256.*measured on another model") as err:
        surrogate_error_t("profile_um", stale)
    assert err.value.field == f"{CARD_ERROR_KEY}.graph_sha256"


@pytest.fixture
def model_copy(tmp_path):
    dest = tmp_path / "nn-default"
    shutil.copytree("models/nn-default", dest)
    return dest


def test_the_bench_writer_round_trips_through_the_card(model_copy):
    """bench/calibration/error_model.py's writer: the entry lands in the card under
    calibration_error_t, every other key unchanged, the card re-sealed (the directory
    verifies), and the calibration reads back what was measured."""
    before = verify_model_dir(model_copy)
    p = load_predictor(model_copy)
    fitted = {"outputs": {"profile_um": OWN_PROFILE,
                          "center_amplitude_um": {"nu": 2.5, "scale": [1.0, 1.1, 1.2],
                                                  "frequency_hz": 20.0,
                                                  "shared_within_hz": 40.0}},
              "scale_hz": [100.0, 150.0, 250.0], "n_designs": 512,
              "frequencies_hz": [100.0, 150.0, 250.0], "profile_mm": [0.0, 2.0]}
    entry = error_t_entry(p, fitted, Path("datasets/default-sweep-test"), None, "the command")
    assert entry["measured_on"]["dataset"] == "datasets/default-sweep-test"
    assert entry["measured_on"]["n_designs"] == 512 and entry["command"] == "the command"
    write_error_t(model_copy, entry)
    after = verify_model_dir(model_copy)  # sealed: card_sha256 matches the new content
    assert after[CARD_ERROR_KEY] == json.loads(json.dumps(entry))
    assert {k: v for k, v in after.items() if k not in (CARD_ERROR_KEY, "card_sha256")} \
        == {k: v for k, v in before.items() if k != "card_sha256"}
    assert after["card_sha256"] == card_digest(after) != before["card_sha256"]
    t = surrogate_error_t("profile_um", load_predictor(model_copy).card)
    assert t["source"] == "model card" and t["nu"] == 3.33 and t["scale"] == (2.0, 3.0, 4.0)
    assert not list(model_copy.parent.glob(".*tmp"))  # no temporary file left behind


def test_only_the_outputs_asked_for_are_written():
    """--write-outputs: a measured output left out keeps SURROGATE_ERROR_T; one not measured,
    or none, is refused naming what was measured."""
    measured = {"outputs": {"center_amplitude_um": {"nu": 2.5}, "profile_um": OWN_PROFILE},
                "n_designs": 512}
    assert select_outputs(measured, None) is measured
    got = select_outputs(measured, "profile_um")
    assert list(got["outputs"]) == ["profile_um"] and got["n_designs"] == 512
    assert list(measured["outputs"]) == ["center_amplitude_um", "profile_um"]  # not changed
    for names in ("profile_normal_um", " , "):
        with pytest.raises(ValueError, match="measured: center_amplitude_um, profile_um"):
            select_outputs(measured, names)


BAD = {
    "scale of the wrong length": (lambda e: e["outputs"]["profile_um"].update(scale=[1.0]),
                                  "outputs.profile_um.scale: must be 3 numbers > 0"),
    "negative nu": (lambda e: e["outputs"]["profile_um"].update(nu=-1.0),
                    "outputs.profile_um.nu: -1.0: must be a finite number > 0"),
    "no length along the profile": (lambda e: e["outputs"]["profile_um"].pop("length_mm"),
                                    "outputs.profile_um.length_mm: None"),
    "not an output of the model": (
        lambda e: e["outputs"].update(profile_normal_um=dict(OWN_PROFILE)),
        "outputs.profile_normal_um: not an output of the model"),
    "frequencies not increasing": (lambda e: e.update(scale_hz=[100.0, 100.0, 250.0]),
                                   "scale_hz: [100.0, 100.0, 250.0]: must be frequencies"),
    "no provenance": (lambda e: e.pop("measured_on"), "measured_on: must name the dataset"),
    "no frequency length (NaN)": (
        lambda e: e["outputs"]["profile_um"].update(frequency_hz=float("nan")),
        "outputs.profile_um.frequency_hz: nan"),
    "another model's graph": (lambda e: e.update(graph_sha256="0" * 64),
                              "measured on another model"),
}


@pytest.mark.parametrize("damage", BAD)
def test_the_bench_writer_refuses_a_bad_entry_and_writes_nothing(model_copy, damage):
    card = verify_model_dir(model_copy)
    raw = (model_copy / "card.json").read_bytes()
    entry = json.loads(json.dumps(_entry(card)))
    how, message = BAD[damage]
    how(entry)
    with pytest.raises(ModelFileError) as err:
        write_error_t(model_copy, entry)
    assert message in str(err.value) and CARD_ERROR_KEY in str(err.value)
    assert "--write-card" in str(err.value)  # says how to make a good one
    assert (model_copy / "card.json").read_bytes() == raw
    with pytest.raises(ModelFileError):
        check_error_t(entry, card)


def test_replace_card_keeps_the_model_files_and_refuses_a_damaged_directory(model_copy):
    card = verify_model_dir(model_copy)
    with pytest.raises(ModelFileError, match="other files"):
        replace_card(model_copy, {**card, "files": {**card["files"], "x.onnx": "0" * 64}})
    (model_copy / "model.onnx").write_bytes(b"changed")
    with pytest.raises(ModelFileError, match="file digest"):
        replace_card(model_copy, {**card, CARD_ERROR_KEY: _entry(card)})
    assert CARD_ERROR_KEY not in json.loads((model_copy / "card.json").read_text())


def test_scale_between_grid_frequencies_is_interpolated():
    p = load_predictor("models/nn-default")
    fwd = ForwardModel(p, measurement_from_rows([_row("edge", 2, 155)], design=DESIGN),
                       ["skin_E_kPa"], {**DESIGN, "fat_thickness_mm": 10.0,
                                        "tissue_loss_factor": 0.2})
    t = SURROGATE_ERROR_T["profile_um"]["scale"]
    j = SCALE_HZ.index(150.0)
    got = point_scales(fwd, {"profile_um": error_settings("profile_um", True, 1.0)}, 1.0)
    assert got[0] == pytest.approx(0.5 * (t[j] + t[j + 1]))


def test_likelihood_over_clusters_is_the_closed_form_t_per_cluster():
    """Two frequencies in separate clusters, each with its own scale: without noise, the sum
    of the two closed-form multivariate t densities; with one cluster it is the closed-form
    t of the whole (the one-frequency limit is the previous likelihood)."""
    rng = np.random.default_rng(11)
    d = np.array([0.0, 3.0, 7.0])
    K = profile_kernel(d[:, None] - d[None, :], 10.2)
    s = rng.uniform(0.05, 0.15, 6) * np.repeat([0.9, 1.3], 3)  # scale per frequency
    cov = np.zeros((6, 6))
    cov[:3, :3] = s[:3, None] * K * s[None, :3]
    cov[3:, 3:] = s[3:, None] * K * s[None, 3:]
    r = rng.standard_normal((4, 6)) * 0.1
    r[0, 4] = 1.5  # one frequency far in the tail
    nu = 1.92
    got = mixture_log_likelihood(r, np.full(6, 1e-10), cov,
                                 [(np.arange(3), nu), (np.arange(3, 6), nu)])
    want = mvt_logpdf(r[:, :3], cov[:3, :3], nu) + mvt_logpdf(r[:, 3:], cov[3:, 3:], nu)
    np.testing.assert_allclose(got, want, atol=1e-5)
    one = mixture_log_likelihood(r, np.full(6, 1e-10), cov, [(np.arange(6), nu)])
    np.testing.assert_allclose(one, mvt_logpdf(r, cov, nu), atol=1e-5)
    assert np.all(np.abs(one - got) > 1e-3)  # sharing the mixing variable is another model


def test_likelihood_with_noise_integrates_to_one():
    """One point per cluster, two clusters, noise and a heavy tail: the density of the
    residual pair integrates to one (a product of two normalised one-dimensional ones)."""
    x = np.linspace(-60.0, 60.0, 120_001)
    noise = np.array([0.05, 0.08]) ** 2
    cov = np.diag([0.1, 0.2]) ** 2
    blocks = [(np.array([0]), 1.5), (np.array([1]), 1.5)]
    for i in range(2):
        r = np.zeros((x.size, 2))
        r[:, i] = x
        lp = mixture_log_likelihood(r, noise, cov, blocks)
        # the free coordinate integrated out leaves the other's density at 0
        assert np.trapezoid(np.exp(lp), x) == pytest.approx(
            math.exp(_one(0.0, noise[1 - i], cov[1 - i, 1 - i])), rel=2e-3)


def _one(r: float, noise: float, var: float) -> float:
    return float(mixture_log_likelihood(np.array([[r]]), np.array([noise]),
                                        np.array([[var]]), [(np.array([0]), 1.5)])[0])


def test_scale_per_frequency_is_recovered_from_synthetic_t_errors():
    rng = np.random.default_rng(12)
    d = np.arange(0.0, 21.0, 4.0)
    K = profile_kernel(d[:, None] - d[None, :], 10.0)
    c, nu, n = np.array([0.8, 1.3]), 2.0, 1500
    g = rng.standard_normal((n, 2, d.size)) @ np.linalg.cholesky(K).T
    lam = nu / rng.chisquare(nu, size=(n, 2, 1))  # one mixing variable per frequency
    x = c[None, :, None] * np.sqrt(lam) * g
    nu_hat, c_hat = fit_t_per_frequency(x, K)
    np.testing.assert_allclose(c_hat, c, rtol=0.08)
    assert nu_hat == pytest.approx(nu, rel=0.2)
