"""scikit-learn conventions of the estimators, POD, and ONNX parity per kernel."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.utils.estimator_checks import parametrize_with_checks

from surrogate.estimators.gp import GPSurrogateRegressor
from surrogate.estimators.nn import MLPEnsembleRegressor
from surrogate.features import SpaceEncoder
from surrogate.pod import POD, ProfileTargets

# Checks excluded, and why:
_EXPECTED = {
    # an MLP trained for a few epochs in a check is not expected to reach the check's score
    "check_regressors_train": "few epochs in checks; accuracy is tested on known data",
}


@parametrize_with_checks(
    [MLPEnsembleRegressor(max_epochs=5, n_members=2, hidden=(8,)),
     GPSurrogateRegressor(max_train=200), POD(n_modes=1), SpaceEncoder()],
    expected_failed_checks=lambda est: _EXPECTED if isinstance(est, MLPEnsembleRegressor)
    else {})
def test_sklearn_conventions(estimator, check):
    check(estimator)


def test_pod_round_trip_and_energy():
    rng = np.random.default_rng(1)
    modes = np.linalg.qr(rng.normal(size=(12, 3)))[0].T
    X = rng.normal(size=(40, 3)) @ modes + 5.0
    pod = POD().fit(X)
    assert pod.modes_.shape[0] == 3  # rank 3 data: 3 modes hold all the energy
    np.testing.assert_allclose(pod.inverse_transform(pod.transform(X)), X, atol=1e-10)


def test_output_map_defines_edge_and_normalized_once():
    rng = np.random.default_rng(2)
    center = rng.uniform(1, 10, 30)
    rate = rng.uniform(0.5, 1, 30)[:, None]
    profile = 0.8 * center[:, None] * np.exp(-np.linspace(0, 3, 7)[None, :] * rate)
    t = ProfileTargets(n_modes=7)
    T = t.fit_transform(center, profile)
    B, b = t.output_map()
    out = T @ B + b
    tol = {"rtol": 0, "atol": 1e-12}
    np.testing.assert_allclose(out[:, 0], np.log(center), **tol)
    np.testing.assert_allclose(out[:, 1], np.log(profile[:, 0]), **tol)
    np.testing.assert_allclose(out[:, 2], np.log(profile[:, 0] / center), **tol)
    np.testing.assert_allclose(out[:, 3:], np.log(profile), **tol)


def _data(n=80, d=3):
    rng = np.random.default_rng(3)
    X = rng.random((n, d))
    Y = np.column_stack([np.sin(3 * X[:, 0]) + X[:, 1], np.cos(2 * X[:, 2]) + 0.1 * X[:, 0]])
    Y += 0.01 * rng.normal(size=Y.shape)  # measured data is never exact: noise above the floor
    return X, Y, rng.random((17, d)), rng.normal(size=(2, 5)), rng.normal(size=5)


@pytest.mark.parametrize("kernel", ["rbf", "matern52"])
def test_gp_onnx_parity_mean_and_std(kernel):
    """The exported graph reproduces sklearn's mean AND std, per kernel shipped."""
    import onnxruntime as ort

    from surrogate.estimators.gp import export_gp

    X, Y, Xt, B, b = _data()
    gp = GPSurrogateRegressor(kernel=kernel).fit(X, Y)
    sess = ort.InferenceSession(export_gp(gp, B, b, {}), providers=["CPUExecutionProvider"])
    mean, std = sess.run(["log_mean", "log_std"], {"x": Xt})
    ref_mean, ref_std = gp.predict(Xt, return_std=True)
    np.testing.assert_allclose(mean, ref_mean @ B + b, rtol=0, atol=1e-6)
    # the variance is a difference of nearly equal numbers near the data, and onnxruntime's
    # float64 Exp differs from numpy's in the last ~8 digits: agreement to 1e-4 in log std is
    # what float64 allows here; the traps guarded against (wrong kernel or distance) give O(1)
    np.testing.assert_allclose(std, np.sqrt(ref_std**2 @ B**2), rtol=0, atol=1e-4)
    # far from the data the std tends to the prior: the kernel really is in the graph
    far = sess.run(["log_std"], {"x": Xt + 50.0})[0]
    assert np.all(far > 5 * std.max())


def test_nn_onnx_parity():
    import onnxruntime as ort
    import torch

    from surrogate.estimators.nn import export_nn

    X, Y, Xt, B, b = _data()
    nn = MLPEnsembleRegressor(max_epochs=30, n_members=3, hidden=(16, 16)).fit(X, Y)
    sess = ort.InferenceSession(export_nn(nn, B, b, {"note": "x"}),
                                providers=["CPUExecutionProvider"])
    for batch in (1, 17):  # dynamic batch axis
        mean, std = sess.run(["log_mean", "log_std"], {"x": Xt[:batch].astype(np.float32)})
        with torch.no_grad():
            rm, rs = nn.to_module(B, b)(torch.as_tensor(Xt[:batch], dtype=torch.float32))
        np.testing.assert_allclose(mean, rm.numpy(), atol=1e-5)
        np.testing.assert_allclose(std, rs.numpy(), atol=1e-5)
        assert mean.shape == (batch, 5)
    ref_mean, _ = nn.predict(Xt, return_std=True)
    np.testing.assert_allclose(sess.run(["log_mean"], {"x": Xt.astype(np.float32)})[0],
                               ref_mean @ B + b, atol=1e-4)


def test_nn_is_seeded():
    X, Y, Xt, _, _ = _data()
    a = MLPEnsembleRegressor(max_epochs=10, n_members=2, hidden=(8,), random_state=4).fit(X, Y)
    b = MLPEnsembleRegressor(max_epochs=10, n_members=2, hidden=(8,), random_state=4).fit(X, Y)
    np.testing.assert_array_equal(a.predict(Xt), b.predict(Xt))


@pytest.mark.parametrize("estimator, param, value, message", [
    (MLPEnsembleRegressor, "hidden", (0, 4), "hidden = (0, 4): allowed one or more"),
    (MLPEnsembleRegressor, "n_members", 0, "n_members = 0: allowed [1, 256]"),
    (MLPEnsembleRegressor, "learning_rate", 0.0, "learning_rate = 0.0: allowed (0, 1]"),
    (MLPEnsembleRegressor, "val_fraction", 0.95, "val_fraction = 0.95: allowed [0, 0.9]"),
    (MLPEnsembleRegressor, "batch_size", 2.5, "batch_size = 2.5: must be an integer"),
    (GPSurrogateRegressor, "kernel", "cubic", "kernel = 'cubic': allowed 'rbf', 'matern52'"),
    (GPSurrogateRegressor, "max_train", 1, "max_train = 1: allowed [2, 20000]"),
    (GPSurrogateRegressor, "noise", float("nan"), "noise = nan: must be a number"),
    (GPSurrogateRegressor, "noise_bounds", (1e-1, 1.0), "noise_bounds = (0.1, 1.0): allowed"),
])
def test_bad_parameters_name_the_parameter_and_its_range(estimator, param, value, message):
    X = np.random.default_rng(0).random((30, 2))
    with pytest.raises(ValueError) as info:
        estimator(**{param: value}).fit(X, X.sum(axis=1))
    assert message in str(info.value)
