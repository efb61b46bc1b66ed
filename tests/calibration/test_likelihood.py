"""The likelihood's Student-t surrogate error and the reported intervals: the highest-density
interval against known distributions, the scale mixture against the closed-form multivariate
t, and the Gaussian as its large-nu limit."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from calibration.fit import Calibration
from calibration.likelihood import hdi, mixture_log_likelihood, mvt_logpdf, precision_grid
from calibration.priors import Prior


def _corr(m: int, length: float = 3.0) -> np.ndarray:
    d = np.arange(m)
    return np.exp(-np.abs(d[:, None] - d[None, :]) / length)


def test_hdi_of_a_half_normal_piled_at_zero_starts_at_the_bound():
    x = np.abs(np.random.default_rng(0).standard_normal(200_000))
    lo, hi = hdi(x, 0.95)
    assert lo == x.min() and lo < 1e-4
    assert hi == pytest.approx(stats.halfnorm.ppf(0.95), abs=0.02)  # 1.96, not 2.24
    assert np.percentile(x, 2.5) > 0.03  # the equal-tailed interval leaves the bound out


def test_hdi_reaches_the_bound_only_when_the_draws_are_piled_against_it():
    x = np.abs(np.random.default_rng(6).standard_normal(20_000))
    assert hdi(x, 0.95, (0.0, 10.0))[0] == 0.0  # piled at 0: the bound itself
    assert hdi(x, 0.95, (0.0, 10.0))[1] < 2.1  # the upper end: the density's, not 10
    far = 5.0 + x  # piled at 5, the support's bound at 0: far from it
    assert far.min() <= hdi(far, 0.95, (0.0, 10.0))[0] < 5.01  # not moved to 0
    y = 20.0 - np.abs(np.random.default_rng(7).standard_normal(20_000))
    assert hdi(y, 0.95, (3.0, 20.0))[1] == 20.0


def test_hdi_of_a_symmetric_distribution_matches_the_equal_tailed_interval():
    x = np.random.default_rng(1).standard_normal(200_000)
    np.testing.assert_allclose(hdi(x, 0.95), np.percentile(x, [2.5, 97.5]), atol=0.03)


def test_hdi_is_the_shortest_interval_holding_the_mass():
    x = np.array([0.0, 0.1, 0.2, 5.0, 9.0])
    assert hdi(x, 0.6) == (0.0, 0.2)


def test_summary_reports_the_hdi_in_the_sampling_coordinate_and_decides_on_it():
    rng = np.random.default_rng(2)
    fat = 3.0 + np.abs(rng.normal(0.0, 1.0, 40_000))  # piled against the prior's bound
    skin = np.exp(rng.normal(math.log(50.0), 0.1, 40_000))  # log-normal: sampled in log
    priors = [Prior("fat_thickness_mm", "uniform", 3.0, 20.0, unit="mm"),
              Prior("skin_E_kPa", "loguniform", 20.0, 120.0, unit="kPa")]
    cal = Calibration(None, None, priors, np.column_stack([fat, skin]),  # type: ignore[arg-type]
                      np.zeros(fat.size), 1.0)
    s = cal.summary()
    f = s["fat_thickness_mm"]
    assert f["interval_kind"] == "hdi" and f["ci95"] == f["ci95_hdi"]
    assert f["ci95"][0] == 3.0  # holds a truth at the bound
    assert f["ci95_equal_tailed"][0] > 3.02
    assert f["ci95"][1] - f["ci95"][0] < f["ci95_equal_tailed"][1] - f["ci95_equal_tailed"][0]
    assert f["width_ratio"] == pytest.approx((f["ci95"][1] - 3.0) / (0.95 * 17.0), rel=0.02)
    k = s["skin_E_kPa"]  # HDI of ln x: the log-normal's equal-tailed interval
    np.testing.assert_allclose(k["ci95"], 50.0 * np.exp([-0.196, 0.196]), rtol=0.01)
    e = cal.summary(interval="equal_tailed")["fat_thickness_mm"]
    assert e["ci95"] == f["ci95_equal_tailed"] and e["width_ratio"] > f["width_ratio"]
    with pytest.raises(ValueError, match="interval 'median': allowed hdi, equal_tailed"):
        cal.summary(interval="median")


@pytest.mark.parametrize("nu", [0.8, 1.5, 4.0, 30.0])
def test_mvt_logpdf_matches_scipy(nu):
    rng = np.random.default_rng(3)
    s = rng.uniform(0.05, 0.2, 5)
    cov = s[:, None] * _corr(5) * s[None, :]
    r = rng.standard_normal((4, 5)) * 0.3
    want = stats.multivariate_t(np.zeros(5), cov, df=nu).logpdf(r)
    np.testing.assert_allclose(mvt_logpdf(r, cov, nu), want, rtol=1e-10)
    np.testing.assert_allclose(mvt_logpdf(r, cov, math.inf),
                               stats.multivariate_normal(np.zeros(5), cov).logpdf(r),
                               rtol=1e-10)


@pytest.mark.parametrize("nu", [0.8, 1.32, 2.0, 5.0, 30.0])
def test_scale_mixture_without_noise_is_the_multivariate_t(nu):
    rng = np.random.default_rng(4)
    m = 6
    s = rng.uniform(0.05, 0.15, m)
    cov = s[:, None] * _corr(m) * s[None, :]
    r = rng.standard_normal((5, m)) * 0.1
    r[0, 2] = 2.0  # one point far in the tail (a dip)
    r[1] *= 30.0
    got = mixture_log_likelihood(r, np.full(m, 1e-10), cov, [(np.arange(m), nu)])
    np.testing.assert_allclose(got, mvt_logpdf(r, cov, nu), atol=1e-5)
    u, logw = precision_grid(nu)  # the Gamma's mass above the grid's lowest precision
    above = stats.gamma(0.5 * nu, scale=2.0 / nu).sf(math.exp(u[0]))
    assert np.exp(logw).sum() == pytest.approx(above, abs=1e-4)


def test_scale_mixture_tends_to_the_gaussian_for_large_nu_and_blocks_are_independent():
    rng = np.random.default_rng(5)
    m = 5
    noise = rng.uniform(0.03, 0.1, m) ** 2
    s = rng.uniform(0.05, 0.15, m)
    cov = s[:, None] * _corr(m) * s[None, :]
    r = rng.standard_normal((6, m)) * 0.1
    gauss = stats.multivariate_normal(np.zeros(m), cov + np.diag(noise)).logpdf(r)
    np.testing.assert_allclose(mixture_log_likelihood(r, noise, cov, [(np.arange(m), math.inf)]),
                               gauss, rtol=1e-10)
    big = mixture_log_likelihood(r, noise, cov, [(np.arange(m), 1e5)])
    np.testing.assert_allclose(big, gauss, atol=2e-3)
    heavy = mixture_log_likelihood(r, noise, cov, [(np.arange(m), 1.5)])
    assert np.all(np.abs(heavy - gauss) > 1e-3)
    cov2 = cov.copy()
    cov2[:2, 2:] = cov2[2:, :2] = 0.0
    split = [(np.arange(2), 2.0), (np.arange(2, m), 3.0)]
    want = (mixture_log_likelihood(r[:, :2], noise[:2], cov2[:2, :2], [(np.arange(2), 2.0)])
            + mixture_log_likelihood(r[:, 2:], noise[2:], cov2[2:, 2:],
                                     [(np.arange(m - 2), 3.0)]))
    np.testing.assert_allclose(mixture_log_likelihood(r, noise, cov2, split), want, rtol=1e-12)


def test_precision_grid_rejects_a_bad_nu():
    for nu in (0.0, -1.0, math.inf):
        with pytest.raises(ValueError, match="nu"):
            precision_grid(nu)
