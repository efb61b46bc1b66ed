"""The GP on sweep datasets: exact mean on all designs, DTC variance, linearised decode, graph."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.gaussian_process import GaussianProcessRegressor
from synthetic_sweep import BAND_HZ, GRID_MM, make_sweep_dataset

from fieldspec import FieldError
from surrogate.runtime.encoding import encode
from surrogate.runtime.predictor import load_predictor, make_session
from surrogate.sweep.export import reference_log_outputs
from surrogate.sweep.gp import JITTER, SweepGP, fit_sweep_gp, linearised_log_std, split_gp_options
from surrogate.sweep.gp_export import GP_PARITY_TOL, export_sweep_gp, gp_parity, std_difference
from surrogate.sweep.targets import load_sweep_datasets, log_magnitudes, log_output_columns
from surrogate.sweep.train import train_sweep
from surrogate.train import split

OPTIONS = {"centre_modes": 6, "scale": "block"}
OUTPUTS = ("profile_um", "profile_normal_um")


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    return load_sweep_datasets([make_sweep_dataset(tmp_path_factory.mktemp("sweep") / "d", 48)])


@pytest.fixture(scope="module")
def fitted(data):
    """(estimator, targets, training designs, held-out designs, ONNX session with the normal
    profile)."""
    tr, te = split(len(data.codes), 0.2, 0)
    est, targets = fit_sweep_gp(data, tr, n_modes=8, options={**OPTIONS, "inducing": 20})
    onnx = export_sweep_gp(est, targets, True, BAND_HZ[0], BAND_HZ[-1], data.band_hz, {})
    return est, targets, tr, te, make_session(onnx)


def test_a_sweep_gp_trains_exports_and_loads(data, tmp_path):
    out = tmp_path / "gp-sweep"
    card = train_sweep([data.sources[0]["path"]], "gp", out, n_modes=8, options=dict(OPTIONS),
                       outputs=OUTPUTS)
    assert card["graph"]["dtype"] == "float64"
    gp = card["training"]["gp"]
    assert gp["mean_designs"] == card["training"]["rows"] == gp["hyperparameter_designs"]
    assert "Matern" in gp["kernel"] and "WhiteKernel" in gp["kernel"]
    assert card["export_parity"]["log_mean"] <= 1e-6
    assert card["export_parity"]["log_std_rel"] <= 1e-6
    m = card["metrics"]["center_amplitude_um"]
    assert {"median_rel_err", "p95_rel_err", "p99_rel_err", "max_rel_err",
            "max_abs_err_over_field", "coverage95"} <= set(m)
    assert m["median_rel_err"] < 1e-2  # the synthetic response is smooth in the design
    p = load_predictor(out)
    res = p.predict({"orientation": ["forward", "reverse"], "skin_E_kPa": [40.0, 90.0],
                     "fat_thickness_mm": [5.0, 12.0], "frequency_hz": [123.4, 200.0]})
    assert res["profile_normal_um"].shape == (2, GRID_MM.size)
    assert np.all(res["center_amplitude_um_log_std"] > 0)


def test_between_grid_points_the_graph_equals_the_numpy_rebuild(data, fitted):
    est, targets, _, te, session = fitted
    X = encode(data.codes[te], data.specs)
    y, v = est.predict(X)
    ln_s, z = targets.components(y)                            # (n, n_f, P, 6)
    for f in (100.0, 137.3, 201.0, 250.0):
        t = np.full(te.size, (f - BAND_HZ[0]) / (BAND_HZ[1] - BAND_HZ[0]))
        i = min(int(t[0]), BAND_HZ.size - 2)
        zf = z[:, i] + (t[0] - i) * (z[:, i + 1] - z[:, i])
        want = log_output_columns(log_magnitudes(zf, ln_s),
                                  log_magnitudes(zf[..., 2:4], ln_s))
        x = np.column_stack([X, np.full(te.size, (f - BAND_HZ[0]) / (BAND_HZ[-1] - BAND_HZ[0]))])
        got_mean, got_std = session.run(["log_mean", "log_std"], {"x": x})
        np.testing.assert_allclose(got_mean, want, atol=1e-6)
        # atol: the edge / centre column's std is zero up to rounding (the synthetic centre
        # and edge move together): 1e-14 to 1e-11 by the path, against 3e-3 elsewhere
        np.testing.assert_allclose(got_std, linearised_log_std(targets, y, v, t, est.y_std_,
                                                               True), rtol=1e-6, atol=1e-9)


def test_the_parity_check_passes_and_catches_a_wrong_graph(data, fitted):
    est, targets, _, te, session = fitted
    out = gp_parity(est, targets, session, data, data.all_specs, te, True)
    assert out["log_mean"] <= 1e-9 and out["log_std_rel"] <= 1e-6
    assert out["log_mean_vs_float64_basis"] <= 1e-5   # the decoder's float32 basis
    wrong = export_sweep_gp(est, targets, False, BAND_HZ[0], BAND_HZ[-1] + 10.0, data.band_hz, {})
    with pytest.raises(RuntimeError, match="log_mean differs from its numpy rebuild"):
        gp_parity(est, targets, make_session(wrong), data, data.all_specs, te, False)


def test_the_std_parity_ignores_the_square_root_of_rounding_and_sees_a_real_difference():
    # the edge / centre column where centre and edge move together: a variance of rounding
    # (6e-17) on one side, exactly 0 on the other, is a std of 7.8e-9 against 0
    assert std_difference(np.array([0.0]), np.array([7.8e-9])) < 1e-10
    # above the floor the measure is |d std| / std to first order
    assert std_difference(np.array([0.2 * (1 + 2e-6)]), np.array([0.2])) == pytest.approx(
        2e-6, rel=1e-3)
    assert std_difference(np.array([1.01e-3]), np.array([1e-3])) > GP_PARITY_TOL


def test_the_linearised_std_is_the_first_order_propagation(data, fitted):
    est, targets, _, te, _ = fitted
    y, v = est.predict(encode(data.codes[te[:3]], data.specs))
    index = np.array([0, 7, 15])
    got = linearised_log_std(targets, y, v, index.astype(float), est.y_std_, True)
    h = 1e-6
    var = np.zeros_like(got)
    for j in range(y.shape[1]):                       # central differences in each target
        step = np.zeros(y.shape[1])
        step[j] = h * est.y_std_[j]
        plus, _ = reference_log_outputs(targets, (y + step)[None], index, True)
        minus, _ = reference_log_outputs(targets, (y - step)[None], index, True)
        var += ((plus - minus) / (2 * h)) ** 2
    np.testing.assert_allclose(got, np.sqrt(v[:, None] * var), rtol=1e-4, atol=1e-9)  # as above


def test_the_variance_is_the_exact_gp_when_every_design_is_inducing(data, fitted):
    _, targets, tr, _, _ = fitted
    X = encode(data.codes, data.specs)
    T = targets.transform(data.response[tr])
    gp = SweepGP(inducing=10**4, noise=1e-4, noise_bounds=(1e-4, 1.0), scale="block")
    gp.fit(X[tr], T)
    exact = GaussianProcessRegressor(gp.kernel_, optimizer=None, normalize_y=False)
    exact.fit(X[tr], (T - gp.y_mean_) / gp.y_std_)
    mean, std = exact.predict(X, return_std=True)
    y, v = gp.predict(X)
    np.testing.assert_allclose(y, gp.y_mean_ + gp.y_std_ * mean, rtol=1e-6,
                               atol=1e-6 * np.abs(T).max())
    # (sklearn's std is per output, all equal here; the inducing matrix's jitter adds ~1e-8 amp)
    np.testing.assert_allclose(v, std[:, 0] ** 2, rtol=1e-4, atol=10 * JITTER * gp.amp_)
    # the noise only at the fitted designs, growing away from them to the prior's amp + noise
    assert np.all(np.abs(v[tr] - gp.noise_) < 1e-5 * gp.amp_)
    ray = X[tr[0]] + np.array([0.0, 1.0, 3.0, 10.0, 30.0, 300.0])[:, None] * np.ones(X.shape[1])
    along = gp.predict(ray)[1]
    assert np.all(np.diff(along) > 0) and along[-1] == pytest.approx(gp.amp_ + gp.noise_)


@pytest.mark.parametrize("inducing", [8, 20, 10**4])
def test_the_variance_factor_is_the_two_triangular_products_in_one(data, fitted, inducing):
    _, targets, tr, _, _ = fitted
    X = encode(data.codes, data.specs)
    gp = SweepGP(inducing=inducing, scale="block").fit(X[tr], targets.transform(data.response[tr]))
    k_m = gp._k(X, X[tr][gp.inducing_])
    a = k_m @ gp.Lm_inv_T_
    c = a @ gp.LB_inv_T_
    G = gp.variance_factor()
    assert G.shape == (gp.inducing_.size, gp.inducing_.size)
    np.testing.assert_allclose(np.sum((k_m @ G) ** 2, axis=1),
                               np.sum(a * a, axis=1) - np.sum(c * c, axis=1),
                               rtol=1e-9, atol=1e-12 * gp.amp_)


def test_the_mean_is_exact_whatever_the_inducing_set(data, fitted):
    _, targets, tr, _, _ = fitted
    X = encode(data.codes, data.specs)
    T = targets.transform(data.response[tr])
    full = SweepGP(inducing=10**4, scale="block").fit(X[tr], T)
    few = SweepGP(inducing=8, scale="block").fit(X[tr], T)
    np.testing.assert_allclose(few.predict(X)[0], full.predict(X)[0])
    # 8 inducing designs leave the others' Nystrom residual k** - Q** in the variance
    assert np.median(few.predict(X)[1]) > 10 * np.median(full.predict(X)[1])


def test_bad_options_and_other_kinds_are_refused_naming_them(data, tmp_path):
    path = data.sources[0]["path"]
    with pytest.raises(ValueError, match=r"hidden = \[16\]: not an option of the sweep gp"):
        split_gp_options({"hidden": [16]})
    with pytest.raises(ValueError, match="scale = 'each': allowed 'output', 'block'"):
        train_sweep([path], "gp", tmp_path / "g", options={"scale": "each"})
    with pytest.raises(ValueError, match="noise_bounds"):
        split_gp_options({"noise": 1e-9})
    with pytest.raises(FieldError, match="sweep datasets train the gp and nn kinds") as err:
        train_sweep([path], "lgbm", tmp_path / "l")
    assert err.value.field == "--kind"
    from hapticrom.cli import main
    assert main(["train", "--data", path, "--kind", "gp", "--out", str(tmp_path / "c"),
                 "--options", '{"inducing": 0}']) == 2
    assert not any((tmp_path / n).exists() for n in ("g", "l", "c"))
