"""The surrogate's error model across frequency: the profile and frequency kernels, the
clusters of frequencies that share one mixing variable, the scale per frequency, the
likelihood over clusters against the closed-form t per cluster (and its normalisation), and
the estimator of a scale per frequency (bench/calibration/error_model.py) on synthetic errors."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from calibration.fit import (
    SCALE_HZ,
    SURROGATE_ERROR_T,
    SURROGATE_ERROR_T_BY_MODEL,
    calibrate,
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

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench" / "calibration"))
from error_model import fit_t_per_frequency

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


def test_a_model_measured_on_its_own_gets_its_own_t():
    """nn-sweep's t (measured on it, SURROGATE_ERROR_T_BY_MODEL) for nn-sweep; every other
    model, and an output it does not list, the t of SURROGATE_ERROR_T."""
    own = SURROGATE_ERROR_T_BY_MODEL["nn-sweep"]
    for o in ("center_amplitude_um", "profile_um"):
        assert surrogate_error_t(o, "nn-sweep") is own[o]
        assert surrogate_error_t(o, "nn-default") is SURROGATE_ERROR_T[o]
        assert surrogate_error_t(o) is SURROGATE_ERROR_T[o]
        assert len(own[o]["scale"]) == len(SCALE_HZ)
    assert surrogate_error_t("profile_normal_um", "nn-sweep") is SURROGATE_ERROR_T[
        "profile_normal_um"]
    e = error_settings("profile_um", True, 1.0, model="nn-sweep")
    assert e["nu"] == own["profile_um"]["nu"] and e["length_mm"] == own["profile_um"]["length_mm"]
    assert e["scale"] == tuple(own["profile_um"]["scale"])
    assert error_settings("profile_um", False, 1.5, model="nn-sweep")["nu"] is None


def test_calibrate_applies_the_t_of_the_model_by_its_name():
    """The fit picks the t by the card's name: the same predictor renamed nn-sweep gets
    nn-sweep's t (a short chain; the error model, not the posterior, is checked)."""
    p = load_predictor("models/nn-default")
    m = measurement_from_rows([_row("edge", 2, 150), _row("edge", 6, 150)], design=DESIGN)
    fit = ["skin_E_kPa"]
    fixed = {"fat_thickness_mm": 10.0, "tissue_loss_factor": 0.2}
    a = calibrate(p, m, fit, fixed=fixed, walkers=8, steps=20, burn=10, n_init=64)
    assert a.error_model["profile_um"]["nu"] == SURROGATE_ERROR_T["profile_um"]["nu"]
    p.card = {**p.card, "name": "nn-sweep"}
    b = calibrate(p, m, fit, fixed=fixed, walkers=8, steps=20, burn=10, n_init=64)
    want = SURROGATE_ERROR_T_BY_MODEL["nn-sweep"]["profile_um"]
    assert b.error_model["profile_um"]["nu"] == want["nu"]
    assert b.error_model["profile_um"]["length_mm"] == want["length_mm"]


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
